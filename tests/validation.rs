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

/// Loads the files and returns the error message, which must exist.
fn error(files: Files) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), &files);
    match Scene::load(&path) {
        Ok(_) => panic!("the scene loaded, but an error was expected"),
        Err(e) => e
            .to_string()
            .replace(&format!("{}/", dir.path().display()), ""),
    }
}

fn assert_names(message: &str, location: &str, problem: &str) {
    assert!(
        message.starts_with(location),
        "message should start with '{location}': {message}"
    );
    assert!(
        message.contains(problem),
        "message should say '{problem}': {message}"
    );
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

    // A missing MTL file is a warning (scene-format.md); tests/quirks.rs checks it.
    write(dir.path(), &Files::default());
    std::fs::write(dir.path().join("s.mtl"), [0xff, 0xfe]).unwrap();
    let e = Scene::load(&path).unwrap_err().to_string();
    assert!(e.contains("s.mtl:1: not valid UTF-8"), "{e}");
}

#[test]
fn toml_that_does_not_parse() {
    let e = error(Files {
        toml: "obj = \"s.obj\"\n[camera\n",
        ..Files::default()
    });
    assert_names(&e, "scene.toml:2:", "unclosed table");
    let e = error(Files {
        toml: "obj = \"s.obj\"\n",
        ..Files::default()
    });
    assert_names(&e, "scene.toml", "missing field `camera`");
}

#[test]
fn unknown_toml_keys_are_errors() {
    let toml = TOML.replace("fov_y = 40.0", "fov_y = 40.0\nfocal = 3");
    assert_names(
        &error(Files {
            toml: &toml,
            ..Files::default()
        }),
        "scene.toml:",
        "unknown field `focal`",
    );
    let toml = format!("{TOML}\n[solver]\nepsilon = 0.1\nzeta_typo = 1\n");
    assert_names(
        &error(Files {
            toml: &toml,
            ..Files::default()
        }),
        "scene.toml:",
        "unknown field `zeta_typo`",
    );
}

#[test]
fn obj_that_does_not_parse() {
    let obj = OBJ.replace("v 1 1 0", "v 1 one 0");
    assert_names(
        &error(Files {
            obj: &obj,
            ..Files::default()
        }),
        "s.obj:4:",
        "vertex needs three numbers",
    );
    let obj = OBJ.replace("f 1 2 3 4", "f 1 2 x 4");
    assert_names(
        &error(Files {
            obj: &obj,
            ..Files::default()
        }),
        "s.obj:7:",
        "face vertex 'x'",
    );
    let obj = OBJ.replace("f 1 2 3 4", "f 1 2 3 9");
    assert_names(
        &error(Files {
            obj: &obj,
            ..Files::default()
        }),
        "s.obj:7:",
        "vertex index 9 is out of range",
    );
    let obj = OBJ.replace("usemtl white", "usemtl chalk");
    assert_names(
        &error(Files {
            obj: &obj,
            ..Files::default()
        }),
        "s.obj:6:",
        "usemtl 'chalk'",
    );
}

#[test]
fn mtl_that_does_not_parse() {
    let mtl = MTL.replace("Kd 0.5 0.5 0.5", "Kd 0.5 0.5");
    assert_names(
        &error(Files {
            mtl: &mtl,
            ..Files::default()
        }),
        "s.mtl:2:",
        "Kd needs three numbers",
    );
    let mtl = "Kd 0.5 0.5 0.5\nnewmtl white\n";
    assert_names(
        &error(Files {
            mtl,
            ..Files::default()
        }),
        "s.mtl:1:",
        "Kd before any newmtl",
    );
    let mtl = format!("{MTL}newmtl white\nKd 0.1 0.1 0.1\n");
    assert_names(
        &error(Files {
            mtl: &mtl,
            ..Files::default()
        }),
        "s.mtl:3:",
        "defined twice",
    );
}

#[test]
fn nan_and_infinite_numbers() {
    let obj = OBJ.replace("v 1 1 0", "v 1 NaN 0");
    assert_names(
        &error(Files {
            obj: &obj,
            ..Files::default()
        }),
        "s.obj:4:",
        "NaN or infinite",
    );
    let obj = OBJ.replace("v 1 1 0", "v 1 inf 0");
    assert_names(
        &error(Files {
            obj: &obj,
            ..Files::default()
        }),
        "s.obj:4:",
        "NaN or infinite",
    );
    let mtl = MTL.replace("Kd 0.5 0.5 0.5", "Kd 0.5 nan 0.5");
    assert_names(
        &error(Files {
            mtl: &mtl,
            ..Files::default()
        }),
        "s.mtl:2:",
        "not a finite number",
    );
    let toml = TOML.replace("position = [0.5, 0.5, 3.0]", "position = [0.5, nan, 3.0]");
    assert_names(
        &error(Files {
            toml: &toml,
            ..Files::default()
        }),
        "scene.toml:3:",
        "finite",
    );
    let toml = format!(
        "{TOML}\n[[point_light]]\nposition = [0.5, 0.5, 1.0]\nintensity = [1.0, inf, 1.0]\n"
    );
    assert_names(
        &error(Files {
            toml: &toml,
            ..Files::default()
        }),
        "scene.toml:10:",
        "not a finite number",
    );
    let toml = format!("{TOML}\n[solver]\nepsilon = nan\n");
    assert_names(
        &error(Files {
            toml: &toml,
            ..Files::default()
        }),
        "scene.toml:10:",
        "epsilon",
    );
}

#[test]
fn reflectance_outside_zero_to_one() {
    // Exactly 1 is lowered with a warning instead (tests/quirks.rs).
    for kd in ["Kd 1.0001 0.5 0.5", "Kd 0.5 1.2 0.5", "Kd -0.1 0.5 0.5"] {
        let mtl = MTL.replace("Kd 0.5 0.5 0.5", kd);
        let e = error(Files {
            mtl: &mtl,
            ..Files::default()
        });
        assert_names(&e, "s.mtl:2:", "material 'white'");
        assert!(e.contains("outside [0, 1)"), "{e}");
    }
}

#[test]
fn negative_emission_and_intensity() {
    let mtl = format!("{MTL}Ke 1 -1 1\n");
    assert_names(
        &error(Files {
            mtl: &mtl,
            ..Files::default()
        }),
        "s.mtl:3:",
        "Ke 1 -1 1 is negative",
    );
    let toml = format!(
        "{TOML}\n[[point_light]]\nposition = [0.5, 0.5, 1.0]\nintensity = [1.0, -2.0, 1.0]\n"
    );
    assert_names(
        &error(Files {
            toml: &toml,
            ..Files::default()
        }),
        "scene.toml:10:",
        "intensity 1 -2 1 is negative",
    );
}

#[test]
fn zero_size_and_degenerate_cameras() {
    let cases = [
        ("width = 32", "width = 0", "empty"),
        ("fov_y = 40.0", "fov_y = 0.0", "fov_y"),
        ("fov_y = 40.0", "fov_y = 180.0", "fov_y"),
        (
            "look_at = [0.5, 0.5, 0.0]",
            "look_at = [0.5, 0.5, 3.0]",
            "look_at equals its position",
        ),
        (
            "fov_y = 40.0",
            "up = [0.0, 0.0, 1.0]\nfov_y = 40.0",
            "parallel",
        ),
    ];
    for (from, to, problem) in cases {
        let toml = TOML.replace(from, to);
        assert_names(
            &error(Files {
                toml: &toml,
                ..Files::default()
            }),
            "scene.toml:3:",
            problem,
        );
    }
    let toml = TOML.replace("width = 32", "width = -4");
    assert_names(
        &error(Files {
            toml: &toml,
            ..Files::default()
        }),
        "scene.toml:7:",
        "invalid value",
    );
}

#[test]
fn a_scene_with_no_geometry() {
    let obj = "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 2 0 0\n";
    assert_names(
        &error(Files {
            obj,
            ..Files::default()
        }),
        "s.obj",
        "no geometry",
    );
    // Only zero-area triangles: nothing is left either.
    let obj = "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 2 0 0\nusemtl white\nf 1 2 3\n";
    assert_names(
        &error(Files {
            obj,
            ..Files::default()
        }),
        "s.obj",
        "no geometry",
    );
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
            materials: vec![Material {
                name: "m".into(),
                kd: Vec3::splat(kd),
                ke: Vec3::ZERO,
            }],
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
fn hostile_numbers_are_refused() {
    let obj = OBJ.replace("v 1 1 0", "v 1 1e38 0");
    assert_names(
        &error(Files {
            obj: &obj,
            ..Files::default()
        }),
        "s.obj:4:",
        "too large",
    );
    let obj = OBJ.replace("v 1 1 0", "v 1 1e39 0");
    assert_names(
        &error(Files {
            obj: &obj,
            ..Files::default()
        }),
        "s.obj:4:",
        "NaN or infinite",
    );
    let obj = OBJ.replace("f 1 2 3 4", "f 1 2 3 2147483648");
    assert_names(
        &error(Files {
            obj: &obj,
            ..Files::default()
        }),
        "s.obj:7:",
        "vertex index 2147483648 is out of range",
    );
    let obj = OBJ.replace("f 1 2 3 4", "f 1 2 3 99999999999999999999999");
    assert_names(
        &error(Files {
            obj: &obj,
            ..Files::default()
        }),
        "s.obj:7:",
        "does not start with a vertex index",
    );
    let toml = TOML.replace("width = 32", "width = 100000000000");
    assert_names(
        &error(Files {
            toml: &toml,
            ..Files::default()
        }),
        "scene.toml:7:",
        "invalid value",
    );
    let toml = TOML.replace("width = 32", "width = 40000");
    assert_names(
        &error(Files {
            toml: &toml,
            ..Files::default()
        }),
        "scene.toml:3:",
        "too large",
    );
    let toml = TOML.replace("fov_y = 40.0", "fov_y = 1e300");
    assert_names(
        &error(Files {
            toml: &toml,
            ..Files::default()
        }),
        "scene.toml:3:",
        "fov_y = inf",
    );
    let mtl = MTL.replace("Kd 0.5 0.5 0.5", "Kd 0.5 0.5 0.5\nKe 1e39 0 0");
    assert_names(
        &error(Files {
            mtl: &mtl,
            ..Files::default()
        }),
        "s.mtl:3:",
        "not a finite number",
    );
}

#[test]
fn truncated_files_are_errors_not_panics() {
    let toml = &TOML[..TOML.find("fov_y").unwrap() + 3];
    assert_names(
        &error(Files {
            toml,
            ..Files::default()
        }),
        "scene.toml:6:",
        "key with no value",
    );
    let toml = "obj = \"s.o";
    assert_names(
        &error(Files {
            toml,
            ..Files::default()
        }),
        "scene.toml:1:",
        "invalid basic string",
    );
    let obj = &OBJ[..OBJ.find("v 1 1 0").unwrap() + 5];
    assert_names(
        &error(Files {
            obj,
            ..Files::default()
        }),
        "s.obj:4:",
        "vertex needs three numbers",
    );
    let mtl = &MTL[..MTL.len() - 4];
    assert_names(
        &error(Files {
            mtl,
            ..Files::default()
        }),
        "s.mtl:2:",
        "Kd needs three numbers",
    );
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
