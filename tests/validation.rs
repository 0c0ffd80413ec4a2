//! Every way a scene can be wrong gives an error that names the file (and the line where it is
//! known) and the problem. Each case writes a small scene into a temporary folder.

use std::path::{Path, PathBuf};

use meshlight::Scene;

const TOML: &str = r#"obj = "s.obj"

[camera]
position = [0.5, 0.5, 3.0]
look_at = [0.5, 0.5, 0.0]
fov_y = 40.0
width = 32
height = 24
"#;

const OBJ: &str = "mtllib s.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
usemtl white
f 1 2 3 4
";

const MTL: &str = "newmtl white
Kd 0.5 0.5 0.5
";

/// A scene folder with the three files, any of them replaced.
struct Files<'a> {
    toml: &'a str,
    obj: &'a str,
    mtl: &'a str,
}

impl Default for Files<'_> {
    fn default() -> Self {
        Files {
            toml: TOML,
            obj: OBJ,
            mtl: MTL,
        }
    }
}

fn write(dir: &Path, files: &Files) -> PathBuf {
    std::fs::write(dir.join("scene.toml"), files.toml).unwrap();
    std::fs::write(dir.join("s.obj"), files.obj).unwrap();
    std::fs::write(dir.join("s.mtl"), files.mtl).unwrap();
    dir.join("scene.toml")
}

/// Which file of the scene a case edits.
#[derive(Clone, Copy)]
enum In {
    Toml,
    Obj,
    Mtl,
}

/// A malformed scene: the valid one with `from` replaced by `to` in one file (`from` empty: `to`
/// appended; `from` "*": the whole file is `to`), and the location and words the error must
/// give.
struct Case {
    file: In,
    from: &'static str,
    to: &'static str,
    location: &'static str,
    problem: &'static str,
}

const fn case(
    file: In,
    from: &'static str,
    to: &'static str,
    location: &'static str,
    problem: &'static str,
) -> Case {
    Case {
        file,
        from,
        to,
        location,
        problem,
    }
}

/// Every malformed scene this file checks, by kind of mistake.
#[rustfmt::skip]
const CASES: &[Case] = &[
    // TOML that does not parse, and unknown keys.
    case(In::Toml, "*", "obj = \"s.obj\"\n[camera\n", "scene.toml:2:", "unclosed table"),
    case(In::Toml, "*", "obj = \"s.obj\"\n", "scene.toml:1", "no [camera]"),
    case(In::Toml, "*", "two_sided = true\n", "scene.toml:1", "names no geometry"),
    case(In::Toml, "fov_y = 40.0", "fov_y = 40.0\nfocal = 3", "scene.toml:", "unknown field `focal`"),
    case(In::Toml, "", "\n[solver]\nepsilon = 0.1\nzeta_typo = 1\n", "scene.toml:", "unknown field `zeta_typo`"),
    // OBJ and MTL that do not parse.
    case(In::Obj, "v 1 1 0", "v 1 one 0", "s.obj:4:", "vertex needs three numbers"),
    case(In::Obj, "f 1 2 3 4", "f 1 2 x 4", "s.obj:7:", "face vertex 'x'"),
    case(In::Obj, "f 1 2 3 4", "f 1 2 3 9", "s.obj:7:", "vertex index 9 is out of range"),
    case(In::Mtl, "Kd 0.5 0.5 0.5", "Kd 0.5 0.5", "s.mtl:2:", "Kd needs three numbers"),
    case(In::Mtl, "*", "Kd 0.5 0.5 0.5\nnewmtl white\n", "s.mtl:1:", "Kd before any newmtl"),
    case(In::Mtl, "", "newmtl white\nKd 0.1 0.1 0.1\n", "s.mtl:3:", "defined twice"),
    // NaN and infinite numbers.
    case(In::Obj, "v 1 1 0", "v 1 NaN 0", "s.obj:4:", "NaN or infinite"),
    case(In::Obj, "v 1 1 0", "v 1 inf 0", "s.obj:4:", "NaN or infinite"),
    case(In::Mtl, "Kd 0.5 0.5 0.5", "Kd 0.5 nan 0.5", "s.mtl:2:", "not a finite number"),
    case(In::Toml, "position = [0.5, 0.5, 3.0]", "position = [0.5, nan, 3.0]", "scene.toml:3:", "finite"),
    case(In::Toml, "", "\n[[point_light]]\nposition = [0.5, 0.5, 1.0]\nintensity = [1.0, inf, 1.0]\n", "scene.toml:10:", "not a finite number"),
    case(In::Toml, "", "\n[solver]\nepsilon = nan\n", "scene.toml:10:", "epsilon"),
    // Reflectance outside [0, 1) (exactly 1 is lowered with a warning: tests/quirks.rs),
    // negative emission and intensity.
    case(In::Mtl, "Kd 0.5 0.5 0.5", "Kd 1.0001 0.5 0.5", "s.mtl:2:", "material 'white': Kd 1.0001 0.5 0.5 is outside [0, 1)"),
    case(In::Mtl, "Kd 0.5 0.5 0.5", "Kd 0.5 1.2 0.5", "s.mtl:2:", "is outside [0, 1)"),
    case(In::Mtl, "Kd 0.5 0.5 0.5", "Kd -0.1 0.5 0.5", "s.mtl:2:", "is outside [0, 1)"),
    case(In::Mtl, "", "Ke 1 -1 1\n", "s.mtl:3:", "Ke 1 -1 1 is negative"),
    case(In::Toml, "", "\n[[point_light]]\nposition = [0.5, 0.5, 1.0]\nintensity = [1.0, -2.0, 1.0]\n", "scene.toml:10:", "intensity 1 -2 1 is negative"),
    // Cameras of no size or no direction.
    case(In::Toml, "width = 32", "width = 0", "scene.toml:3:", "empty"),
    case(In::Toml, "fov_y = 40.0", "fov_y = 0.0", "scene.toml:3:", "fov_y"),
    case(In::Toml, "fov_y = 40.0", "fov_y = 180.0", "scene.toml:3:", "fov_y"),
    case(In::Toml, "look_at = [0.5, 0.5, 0.0]", "look_at = [0.5, 0.5, 3.0]", "scene.toml:3:", "look_at equals its position"),
    case(In::Toml, "fov_y = 40.0", "up = [0.0, 0.0, 1.0]\nfov_y = 40.0", "scene.toml:3:", "parallel"),
    case(In::Toml, "width = 32", "width = -4", "scene.toml:7:", "invalid value"),
    // No geometry, or only zero-area triangles.
    case(In::Obj, "*", "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 2 0 0\n", "s.obj", "no geometry"),
    case(In::Obj, "*", "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 2 0 0\nusemtl white\nf 1 2 3\n", "s.obj", "no geometry"),
    // Hostile numbers.
    case(In::Obj, "v 1 1 0", "v 1 1e38 0", "s.obj:4:", "too large"),
    case(In::Obj, "v 1 1 0", "v 1 1e39 0", "s.obj:4:", "NaN or infinite"),
    case(In::Obj, "f 1 2 3 4", "f 1 2 3 2147483648", "s.obj:7:", "vertex index 2147483648 is out of range"),
    case(In::Obj, "f 1 2 3 4", "f 1 2 3 99999999999999999999999", "s.obj:7:", "does not start with a vertex index"),
    case(In::Toml, "width = 32", "width = 100000000000", "scene.toml:7:", "invalid value"),
    case(In::Toml, "width = 32", "width = 40000", "scene.toml:3:", "too large"),
    case(In::Toml, "fov_y = 40.0", "fov_y = 1e300", "scene.toml:3:", "fov_y = inf"),
    case(In::Mtl, "Kd 0.5 0.5 0.5", "Kd 0.5 0.5 0.5\nKe 1e39 0 0", "s.mtl:3:", "not a finite number"),
    // Truncated files.
    case(In::Toml, "fov_y = 40.0\nwidth = 32\nheight = 24\n", "fov", "scene.toml:6:", "key with no value"),
    case(In::Toml, "*", "obj = \"s.o", "scene.toml:1:", "invalid basic string"),
    case(In::Obj, "1 0\nv 0 1 0\nusemtl white\nf 1 2 3 4\n", "", "s.obj:4:", "vertex needs three numbers"),
    case(In::Mtl, "0.5 0.5 0.5\n", "0.5 0.5 ", "s.mtl:2:", "Kd needs three numbers"),
];

#[test]
fn every_malformed_scene_names_its_file_line_and_problem() {
    assert!(CASES.len() >= 40);
    for c in CASES {
        let edit = |valid: &str| match c.from {
            "*" => c.to.to_string(),
            "" => format!("{valid}{}", c.to),
            from => {
                assert!(valid.contains(from), "'{from}' is not in the valid file");
                valid.replacen(from, c.to, 1)
            }
        };
        let (mut toml, mut obj, mut mtl) = (TOML.to_string(), OBJ.to_string(), MTL.to_string());
        match c.file {
            In::Toml => toml = edit(TOML),
            In::Obj => obj = edit(OBJ),
            In::Mtl => mtl = edit(MTL),
        }
        let dir = tempfile::tempdir().unwrap();
        let files = Files {
            toml: &toml,
            obj: &obj,
            mtl: &mtl,
        };
        let path = write(dir.path(), &files);
        let e = match Scene::load(&path) {
            Ok(_) => panic!("{} -> {}: the scene loaded", c.from, c.to),
            Err(e) => e
                .to_string()
                .replace(&format!("{}/", dir.path().display()), ""),
        };
        assert!(
            e.starts_with(c.location) && e.contains(c.problem),
            "{} -> {}: the message should start with '{}' and say '{}': {e}",
            c.from,
            c.to,
            c.location,
            c.problem
        );
    }
}

#[test]
fn the_valid_scene_loads() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Scene::load(write(dir.path(), &Files::default())).unwrap();
    assert_eq!((scene.triangles().len(), scene.surfaces().len()), (2, 1));
    assert!(scene.warnings().is_empty());
}

#[test]
fn missing_files_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nothing.toml");
    let e = Scene::load(&missing).unwrap_err().to_string();
    assert!(
        e.contains("nothing.toml") && e.contains("cannot read"),
        "{e}"
    );

    let path = write(dir.path(), &Files::default());
    std::fs::remove_file(dir.path().join("s.obj")).unwrap();
    let e = Scene::load(&path).unwrap_err().to_string();
    assert!(e.contains("s.obj: cannot read"), "{e}");

    // A missing MTL file is a warning (`docs/scene-format.md`); tests/quirks.rs checks it.
    write(dir.path(), &Files::default());
    std::fs::write(dir.path().join("s.mtl"), [0xff, 0xfe]).unwrap();
    let e = Scene::load(&path).unwrap_err().to_string();
    assert!(e.contains("s.mtl:1: not valid UTF-8"), "{e}");
}

#[test]
fn zero_area_triangles_are_dropped_with_one_warning() {
    let obj = format!("{OBJ}v 5 5 5\nf 1 1 2\nf 5 5 5\nf 1 2 2\n");
    let dir = tempfile::tempdir().unwrap();
    let scene = Scene::load(write(
        dir.path(),
        &Files {
            obj: &obj,
            ..Files::default()
        },
    ))
    .unwrap();
    assert_eq!(scene.triangles().len(), 2);
    let warnings: Vec<&String> = scene
        .warnings()
        .iter()
        .filter(|w| w.contains("zero-area"))
        .collect();
    assert_eq!(warnings.len(), 1, "{:?}", scene.warnings());
    assert!(
        warnings[0].contains("s.obj: dropped 3 zero-area triangles"),
        "{}",
        warnings[0]
    );
}

#[test]
fn faces_without_material_get_grey_and_one_warning() {
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";
    let dir = tempfile::tempdir().unwrap();
    let scene = Scene::load(write(
        dir.path(),
        &Files {
            obj,
            ..Files::default()
        },
    ))
    .unwrap();
    assert_eq!(scene.warnings().len(), 1, "{:?}", scene.warnings());
    assert!(
        scene.warnings()[0].contains("2 triangles have no material"),
        "{}",
        scene.warnings()[0]
    );
    assert_eq!(
        scene.materials()[scene.surfaces()[0].material as usize].kd,
        glam::Vec3::splat(0.5)
    );
}

#[test]
fn binary_garbage_is_not_text() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), &Files::default());
    std::fs::write(dir.path().join("s.obj"), b"v 0 0 0\n\xff\xfe\x00garbage").unwrap();
    let e = Scene::load(&path).unwrap_err().to_string();
    assert!(e.contains("s.obj:2: not valid UTF-8"), "{e}");
}

#[test]
fn host_built_scenes_are_checked_too() {
    use glam::Vec3;
    use meshlight::scene::{Camera, Material, Mesh, SceneParts, SolverDefaults};
    let parts = |kd: f32| SceneParts {
        mesh: Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            triangles: vec![[0, 1, 2]],
            triangle_materials: vec![0],
            materials: vec![Material::diffuse("m", Vec3::splat(kd), Vec3::ZERO)],
            texcoords: Vec::new(),
        },
        point_lights: vec![],
        camera: Camera {
            position: Vec3::Z,
            look_at: Vec3::ZERO,
            up: Vec3::Y,
            fov_y: 45.0,
            width: 8,
            height: 8,
        },
        two_sided: false,
        solver: SolverDefaults::default(),
    };
    assert!(Scene::from_parts("host", parts(0.5)).is_ok());
    let e = Scene::from_parts("host", parts(1.0))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("host: material 'm': Kd"), "{e}");
}

#[test]
fn a_face_cut_to_two_vertices_is_ignored_with_a_warning() {
    // A face cut to two vertices is a line, not a face: ignored, and said.
    let obj = OBJ.replace("f 1 2 3 4", "f 1 2 3 4\nf 1 2");
    let dir = tempfile::tempdir().unwrap();
    let scene = Scene::load(write(
        dir.path(),
        &Files {
            obj: &obj,
            ..Files::default()
        },
    ))
    .unwrap();
    assert!(
        scene
            .warnings()
            .iter()
            .any(|w| w.contains("ignored 1 face with fewer than 3 vertices")),
        "{:?}",
        scene.warnings()
    );
}

#[test]
fn utf8_errors_name_their_line_in_every_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), &Files::default());
    std::fs::write(
        dir.path().join("s.mtl"),
        b"newmtl white\nKd 0.5 0.5 0.5\n# caf\xe9\n",
    )
    .unwrap();
    let e = Scene::load(&path).unwrap_err().to_string();
    assert!(e.contains("s.mtl:3: not valid UTF-8"), "{e}");
    std::fs::write(
        dir.path().join("scene.toml"),
        b"obj = \"s.obj\"\n\xc3\x28\n",
    )
    .unwrap();
    let e = Scene::load(&path).unwrap_err().to_string();
    assert!(e.contains("scene.toml:2: not valid UTF-8"), "{e}");
}

#[test]
fn scenes_load_from_memory_too() {
    use meshlight::scene::Memory;
    let files = Memory::default()
        .with("scene.toml", TOML)
        .with("s.obj", OBJ)
        .with("s.mtl", MTL);
    let scene = Scene::load_from(&files, "scene.toml").unwrap();
    assert_eq!(scene.triangles().len(), 2);
    let e = Scene::load_from(&Memory::default().with("scene.toml", TOML), "scene.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("s.obj: cannot read"), "{e}");
}
