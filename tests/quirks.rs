//! Real-world OBJ/MTL quirks load as `docs/scene-format.md` says: white written as Kd 1 (lowered,
//! or refused with `strict`), several files on one `mtllib` line, a missing MTL file, a UTF-8
//! byte-order mark, `v` with a w component, negative indices, `vt`/`vn` face forms, tabs and
//! CRLF line ends, texture options in the MTL. Each file is written here; the expected
//! positions, areas and reflectances are worked out by hand from it.

use std::path::{Path, PathBuf};

use glam::Vec3;
use meshlight::scene::{LoadOptions, Memory, DEFAULT_MAX_REFLECTANCE};
use meshlight::Scene;

const TOML: &str = r#"obj = "s.obj"

[camera]
position = [0.5, 0.5, 3.0]
look_at = [0.5, 0.5, 0.0]
fov_y = 40.0
width = 32
height = 24
"#;

/// A unit square at z = 0 in material `white`, its front towards +z.
const OBJ: &str = "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl white\nf 1 2 3 4\n";

fn load_with(
    obj: &str,
    mtls: &[(&str, &str)],
    toml: &str,
    options: &LoadOptions,
) -> meshlight::Result<Scene> {
    let mut files = Memory::default()
        .with("scene.toml", toml)
        .with("s.obj", obj);
    for (name, text) in mtls {
        files = files.with(*name, *text);
    }
    Scene::load_with(&files, "scene.toml", options)
}

fn load(obj: &str, mtl: &str) -> Scene {
    load_with(obj, &[("s.mtl", mtl)], TOML, &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Every surface's (area, reflectance), sorted by area.
fn surfaces(scene: &Scene) -> Vec<(f64, Vec3)> {
    let mut v: Vec<(f64, Vec3)> = scene
        .surfaces()
        .iter()
        .map(|s| (s.area, scene.materials()[s.material as usize].kd))
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-6
}

#[test]
fn white_written_as_one_is_lowered_with_one_warning() {
    let scene = load(OBJ, "newmtl white\nKd 1 1 1\n");
    let kd = scene.materials()[0].kd;
    // The default `docs/scene-format.md` documents and justifies.
    assert_eq!(kd, Vec3::splat(0.9));
    assert_eq!(DEFAULT_MAX_REFLECTANCE, 0.9);
    assert_eq!(scene.warnings().len(), 1, "{:?}", scene.warnings());
    let w = &scene.warnings()[0];
    assert!(
        w.starts_with("s.mtl:2: material 'white'") && w.contains("lowered to 0.9"),
        "{w}"
    );

    // Only the channels at 1 move.
    let scene = load(OBJ, "newmtl white\nKd 1 0.5 0.25\n");
    assert_eq!(scene.materials()[0].kd, Vec3::new(0.9, 0.5, 0.25));

    // The scene file's [solver] max_reflectance, and the caller's over it.
    let toml = format!("{TOML}\n[solver]\nmax_reflectance = 0.8\n");
    let mtl = [("s.mtl", "newmtl white\nKd 1 1 1\n")];
    let scene = load_with(OBJ, &mtl, &toml, &LoadOptions::default()).unwrap();
    assert_eq!(scene.materials()[0].kd, Vec3::splat(0.8));
    let options = LoadOptions {
        max_reflectance: Some(0.7),
        ..LoadOptions::default()
    };
    let scene = load_with(OBJ, &mtl, &toml, &options).unwrap();
    assert_eq!(scene.materials()[0].kd, Vec3::splat(0.7));
}

#[test]
fn strict_refuses_white_written_as_one_and_bad_limits_are_named() {
    let mtl = [("s.mtl", "newmtl white\nKd 1 1 1\n")];
    let strict = LoadOptions {
        strict: true,
        ..LoadOptions::default()
    };
    let e = load_with(OBJ, &mtl, TOML, &strict).unwrap_err().to_string();
    assert!(e.starts_with("s.mtl:2: material 'white': Kd 1 1 1"), "{e}");
    for bad in ["1.0", "0.0", "-0.5", "nan"] {
        let toml = format!("{TOML}\n[solver]\nmax_reflectance = {bad}\n");
        let e = load_with(OBJ, &mtl, &toml, &LoadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("scene.toml:10:") && e.contains("max_reflectance"),
            "{bad}: {e}"
        );
    }
    let options = LoadOptions {
        max_reflectance: Some(1.0),
        ..LoadOptions::default()
    };
    let e = load_with(OBJ, &mtl, TOML, &options)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("max_reflectance 1 must lie strictly between 0 and 1"),
        "{e}"
    );
}

#[test]
fn several_mtl_files_on_one_line_are_each_read() {
    // Two squares: the unit one in white (from a.mtl), a 2 × 1 one in red (from b.mtl).
    let obj = "mtllib a.mtl  b.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 2 0 1\nv 2 1 1\nv 0 1 1\n\
               usemtl white\nf 1 2 3 4\nusemtl red\nf 5 6 7 8\n";
    let mtls = [
        ("a.mtl", "newmtl white\nKd 0.7 0.7 0.7\n"),
        ("b.mtl", "newmtl red\nKd 0.6 0.1 0.1\n"),
    ];
    let scene = load_with(obj, &mtls, TOML, &LoadOptions::default()).unwrap();
    let s = surfaces(&scene);
    assert_eq!(s.len(), 2);
    assert!(close(s[0].0, 1.0) && s[0].1 == Vec3::splat(0.7), "{s:?}");
    assert!(
        close(s[1].0, 2.0) && s[1].1 == Vec3::new(0.6, 0.1, 0.1),
        "{s:?}"
    );
    assert!(scene.warnings().is_empty(), "{:?}", scene.warnings());
}

#[test]
fn a_missing_mtl_file_is_one_warning_and_grey_faces() {
    let obj = OBJ.replace("mtllib s.mtl", "mtllib gone.mtl");
    let scene = load_with(&obj, &[], TOML, &LoadOptions::default()).unwrap();
    assert_eq!(surfaces(&scene), vec![(1.0, Vec3::splat(0.5))]);
    let missing: Vec<&String> = scene
        .warnings()
        .iter()
        .filter(|w| w.contains("gone.mtl"))
        .collect();
    assert_eq!(missing.len(), 1, "{:?}", scene.warnings());
    assert!(
        missing[0].starts_with("s.obj:1: MTL file gone.mtl not found"),
        "{}",
        missing[0]
    );
}

#[test]
fn byte_order_marks_w_components_negative_indices_and_face_forms() {
    // A BOM before each file; `v` with w; a quad by negative indices; a triangle each in the
    // v/vt, v//vn and v/vt/vn forms, all in the plane z = 0: areas 1 + 3 × 0.5 = 2.5.
    let obj = "\u{feff}mtllib s.mtl\nv 0 0 0 1\nv 1 0 0 1\nv 1 1 0 1\nv 0 1 0 1\nvt 0 0\nvn 0 0 1\n\
               usemtl white\nf -4 -3 -2 -1\nv 2 0 0\nv 3 0 0\nv 3 1 0\nf 5/1 6/1 7/1\nf 5//1 6//1 7//1\nf 5/1/1 6/1/1 7/1/1\n";
    let scene = load(obj, "\u{feff}newmtl white\nKd 0.5 0.5 0.5\n");
    assert!(close(scene.total_area(), 2.5), "{}", scene.total_area());
    let top = scene.bounds();
    assert_eq!((top.min, top.max), (Vec3::ZERO, Vec3::new(3.0, 1.0, 0.0)));
    assert!(scene.warnings().is_empty(), "{:?}", scene.warnings());
}

#[test]
fn tabs_crlf_and_texture_options_are_read_through() {
    let obj = OBJ
        .replace('\n', "\r\n")
        .replace("v ", "v\t")
        .replace("usemtl white", "usemtl\twhite ");
    let mtl =
        "newmtl white\r\nKa 0.1 0.1 0.1\r\nKd\t0.25 0.5 0.75\r\nKs 0 0 0\r\nNs 10\r\nillum 2\r\n\
               map_Kd -s 1 1 1 -o 0 0 0 -blendu on wood.png\r\nd 1\r\n";
    let scene = load(&obj, mtl);
    assert_eq!(surfaces(&scene), vec![(1.0, Vec3::new(0.25, 0.5, 0.75))]);
    // `-s` and `-o` are read; `-blendu` is said to be ignored; the texture is missing (one
    // warning naming it) and the material keeps its Kd.
    assert_eq!(
        scene.warnings(),
        [
            "s.mtl:7: material 'white': map_Kd option -blendu is ignored",
            "s.mtl:7: material 'white': texture wood.png cannot be read (no such file): the \
             material keeps its Kd"
        ],
    );
}

#[test]
fn a_generated_obj_not_made_yet_says_how_to_make_it() {
    let toml = format!(
        "# big.obj is generated: `make-big --out here`\n{}",
        TOML.replace("s.obj", "big.obj")
    );
    let files = Memory::default().with("scene.toml", toml.as_str());
    let e = Scene::load_from(&files, "scene.toml")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("scene.toml:2: big.obj not found"), "{e}");
    assert!(e.contains("make-big --out here"), "{e}");
}

#[test]
fn the_shipped_gallery_names_its_generator_when_its_obj_is_missing() {
    // The shipped scene file, with its OBJ looked for where it is not.
    let shipped = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/gallery/scene.toml");
    let text = std::fs::read_to_string(&shipped).unwrap();
    let files = Memory::default().with(Path::new("g/scene.toml"), text);
    let e = Scene::load_from(&files, "g/scene.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cargo run --release -p meshlight-gallery"),
        "{e}"
    );
}

#[test]
fn a_usemtl_no_mtl_defines_is_a_warning_and_grey() {
    // tinyobjloader's corpus has OBJs whose usemtl names a material the MTL lacks, or that
    // have no mtllib at all: they load, their faces grey (Kd 0.5), with one warning each.
    let scene = load(
        &OBJ.replace("usemtl white", "usemtl chalk"),
        "newmtl white\nKd 0.8 0.8 0.8\n",
    );
    assert_eq!(surfaces(&scene), vec![(1.0, Vec3::splat(0.5))]);
    let said: Vec<&String> = scene
        .warnings()
        .iter()
        .filter(|w| w.contains("usemtl 'chalk'"))
        .collect();
    // One warning in all: not a second one counting the same faces as having no material.
    assert_eq!(scene.warnings().len(), 1, "{:?}", scene.warnings());
    assert!(said[0].contains("s.obj:6:") && said[0].contains("not defined in"));
    let bare = load_with(
        &OBJ.replace("mtllib s.mtl\n", ""),
        &[],
        TOML,
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(surfaces(&bare), vec![(1.0, Vec3::splat(0.5))]);
    assert!(
        bare.warnings().len() == 1 && bare.warnings()[0].contains("names no mtllib"),
        "{:?}",
        bare.warnings()
    );
}
