//! glTF 2.0 input: the Cornell room written as glTF by `scripts/obj2gltf.py` (Python's standard
//! library, no code shared with either reader) lights the same as the OBJ, moved or not; a
//! hand-written file checks node transforms, lights, cameras and the material mapping.

mod common;

use common::{shipped, solve_and_render};
use glam::Vec3;
use meshlight::metrics::compare;
use meshlight::scene::{Kind, Units};
use meshlight::{Backend, Options, Scene};

fn cornell(file: &str) -> std::path::PathBuf {
    shipped("cornell").with_file_name(file)
}

fn data(file: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(file)
}

/// Solves and renders at 64 × 64 with ε a fixed fraction of the scene's diagonal.
fn image(scene: &mut Scene, backend: Backend) -> meshlight::Image {
    let camera = meshlight::scene::Camera {
        width: 64,
        height: 64,
        ..*scene.camera()
    };
    scene.set_camera(camera).unwrap();
    let options = Options {
        epsilon: Some(0.04 * scene.bounds().diagonal()),
        rounds: 1,
        ..Options::default()
    };
    solve_and_render(scene, backend, options, true).1
}

#[test]
fn the_cornell_room_in_gltf_is_the_room_in_obj_moved_or_not() {
    let obj = Scene::load(shipped("cornell")).unwrap();
    let gltf = Scene::load(cornell("cornell.gltf")).unwrap();
    let moved = Scene::load(cornell("cornell-moved.gltf")).unwrap();
    // The same geometry: triangles, surfaces and area (the moved one doubled in size).
    assert_eq!(gltf.triangles().len(), obj.triangles().len());
    assert_eq!(gltf.surfaces().len(), obj.surfaces().len());
    assert_eq!(moved.surfaces().len(), obj.surfaces().len());
    assert!((gltf.total_area() / obj.total_area() - 1.0).abs() < 1e-9);
    assert!((moved.total_area() / obj.total_area() - 4.0).abs() < 1e-5);
    // The camera from the glTF's node: the scene file's, to float precision.
    let (a, b) = (obj.camera(), gltf.camera());
    assert!((a.position - b.position).length() < 1e-5, "{a:?} {b:?}");
    let (fa, fb) = (
        (a.look_at - a.position).normalize(),
        (b.look_at - b.position).normalize(),
    );
    assert!((fa - fb).length() < 1e-5, "{fa} {fb}");
    assert!((a.fov_y - b.fov_y).abs() < 1e-4);
    // The light: Ke 10 as emissive 1 × strength 10.
    assert_eq!(gltf.emitted_power(), obj.emitted_power());
    for backend in Backend::available() {
        let [a, b, c] =
            [obj.clone(), gltf.clone(), moved.clone()].map(|mut s| image(&mut s, backend));
        // The surfaces come in another order (one primitive per material), so the samples
        // differ: the images agree to the method's noise.
        let same = compare(&b, &a).unwrap();
        assert!(same.mae_over_mean < 0.01, "{backend} gltf: {same:?}");
        assert!((b.mean() / a.mean() - 1.0).abs() < 0.003, "{backend} gltf");
        let moved = compare(&c, &a).unwrap();
        assert!(moved.mae_over_mean < 0.01, "{backend} moved: {moved:?}");
        assert!((c.mean() / a.mean() - 1.0).abs() < 0.003, "{backend} moved");
    }
}

#[test]
fn nodes_lights_cameras_and_materials_come_across() {
    let scene = Scene::load(data("lamp.gltf")).unwrap();
    // The floor under the node moved by (1, 0, 1): x and z in [1, 3].
    let b = scene.bounds();
    assert!((b.min - Vec3::new(1.0, 0.0, 1.0)).length() < 1e-6, "{b:?}");
    assert!((b.max - Vec3::new(3.0, 1.0, 3.0)).length() < 1e-6, "{b:?}");
    // The point light: 683 cd × colour (1, 0.5, 0.25) is 1 W/sr × colour in radiometric units,
    // at its node (1, 1, 1) under (1, 0, 1). The spot is left out with a warning.
    assert_eq!(scene.units(), Units::Radiometric);
    let lights = scene.point_lights();
    assert_eq!(lights.len(), 1);
    assert!((lights[0].position - Vec3::new(2.0, 1.0, 2.0)).length() < 1e-6);
    assert!((lights[0].intensity - Vec3::new(1.0, 0.5, 0.25)).length() < 1e-6);
    assert!(
        scene.warnings().iter().any(|w| w.contains("spot")),
        "{:?}",
        scene.warnings()
    );
    // The camera: at (3, 1, 5), looking down −z, 0.8 rad tall, twice as wide as tall.
    let c = scene.camera();
    assert!((c.position - Vec3::new(3.0, 1.0, 5.0)).length() < 1e-6);
    assert!(((c.look_at - c.position).normalize() - Vec3::NEG_Z).length() < 1e-6);
    assert!((c.fov_y - 0.8f32.to_degrees()).abs() < 1e-4);
    assert_eq!(c.width, 2 * c.height);
    // Metallic 0.25 over base (0.8, 0.6, 0.4): Kd = base × 0.75, Ks = base × 0.25, roughness
    // 0.3, both sides. The pane: glass of index 1.45 passing the base colour, thin (no volume).
    let metal = scene
        .materials()
        .iter()
        .find(|m| m.name == "brushed metal")
        .unwrap();
    assert!(
        (metal.kd - Vec3::new(0.6, 0.45, 0.3)).length() < 1e-6,
        "{metal:?}"
    );
    assert!(metal.two_sided);
    let Kind::Specular { ks, roughness } = metal.kind else {
        panic!("{metal:?}")
    };
    assert!((ks - Vec3::new(0.2, 0.15, 0.1)).length() < 1e-6);
    assert!((roughness - 0.3).abs() < 1e-6);
    let pane = scene.materials().iter().find(|m| m.name == "pane").unwrap();
    assert_eq!(
        pane.kind,
        Kind::Glass {
            ior: 1.45,
            transmit: Vec3::splat(0.9),
            thin: true
        }
    );
}

#[test]
fn a_scene_file_may_name_a_gltf_and_add_to_it() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(data("lamp.gltf"), dir.path().join("lamp.gltf")).unwrap();
    let write = |text: &str| {
        let path = dir.path().join("scene.toml");
        std::fs::write(&path, text).unwrap();
        path
    };
    // Photometric: the candela stay candela; a camera given here wins over the file's.
    let scene = Scene::load(write(
        "gltf = \"lamp.gltf\"\nunits = \"photometric\"\n[camera]\nposition = [2, 3, 2]\n\
         look_at = [2, 0, 2.01]\nfov_y = 50\nwidth = 32\nheight = 32\n",
    ))
    .unwrap();
    assert!((scene.point_lights()[0].intensity - Vec3::new(683.0, 341.5, 170.75)).length() < 1e-3);
    assert_eq!(scene.camera().width, 32);
    // Both an OBJ and a glTF: an error naming the file and line.
    let e = Scene::load(write("obj = \"x.obj\"\ngltf = \"lamp.gltf\"\n"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("scene.toml:2") && e.contains("both"), "{e}");
    // Not glTF at all, and a glTF without a camera: errors naming the file.
    std::fs::write(dir.path().join("bad.glb"), b"not a glTF").unwrap();
    let e = Scene::load(dir.path().join("bad.glb"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("bad.glb") && e.contains("glTF"), "{e}");
    let text = std::fs::read_to_string(data("lamp.gltf")).unwrap();
    let cameraless = text.replace("\"camera\": 0,", "");
    assert_ne!(cameraless, text);
    std::fs::write(dir.path().join("dark.gltf"), cameraless).unwrap();
    let e = Scene::load(dir.path().join("dark.gltf"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("dark.gltf") && e.contains("camera"), "{e}");
}

#[test]
fn a_room_exported_from_blender_lights_as_cycles_renders_it() {
    // tests/data/blender-room.glb: a cube room with a red box, a 100 W point light and a camera,
    // made and exported by Blender 5.0.1 (`scripts/blender_room.py`). Cycles rendered the same
    // file's view at 256 × 192, 256 spp without clamping or denoising: mean radiance 0.61280
    // (`scripts/compare_with_cycles.py`). Blender writes the light as 100·683/4π cd: in a
    // radiometric scene, 100/4π W/sr.
    let scene = Scene::load(data("blender-room.glb")).unwrap();
    let lights = scene.point_lights();
    assert_eq!(lights.len(), 1);
    let expected = 100.0 / (4.0 * std::f32::consts::PI);
    assert!(
        (lights[0].intensity / expected - Vec3::ONE)
            .abs()
            .max_element()
            < 1e-4
    );
    // Blender exports every material double-sided: the cube's faces point out, and still
    // reflect inside.
    assert!(scene.surfaces().iter().all(|s| s.two_sided));
    const CYCLES_MEAN: f64 = 0.61280;
    for backend in Backend::available() {
        let mut scene = scene.clone();
        let camera = meshlight::scene::Camera {
            width: 128,
            height: 96,
            ..*scene.camera()
        };
        scene.set_camera(camera).unwrap();
        let (_, image) = solve_and_render(&scene, backend, Options::default(), true);
        let ratio = image.mean() / CYCLES_MEAN;
        assert!((ratio - 1.0).abs() < 0.01, "{backend}: {ratio}");
    }
}

#[test]
fn a_camera_is_chosen_by_name() {
    use meshlight::scene::{Disk, LoadOptions};
    let load = |path: std::path::PathBuf, camera: &str| {
        let options = LoadOptions {
            camera: Some(camera.into()),
            ..LoadOptions::default()
        };
        Scene::load_with(&Disk, path, &options)
    };
    // The Blender export's camera is its object's name.
    let scene = load(data("blender-room.glb"), "Camera").unwrap();
    assert!((scene.camera().position - Vec3::new(-1.8, 1.6, 1.8)).length() < 1e-5);
    let e = load(data("blender-room.glb"), "Kamera")
        .unwrap_err()
        .to_string();
    assert!(e.contains("'Kamera'") && e.contains("Camera"), "{e}");
    let e = load(shipped("cornell"), "Camera").unwrap_err().to_string();
    assert!(e.contains("only glTF"), "{e}");
}
