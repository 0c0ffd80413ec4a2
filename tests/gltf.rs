//! glTF 2.0 input: the Cornell room written as glTF by `scripts/obj2gltf.py` (Python's standard
//! library, no code shared with either reader) lights the same as the OBJ, moved or not; a
//! hand-written file checks node transforms, lights, cameras and the material mapping.

mod common;

use common::{shipped, solve_and_render};
use glam::Vec3;
use meshlight::metrics::compare;
use meshlight::scene::{Kind, Units};
use meshlight::{Backend, Image, Options, Scene};

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
    // at its node (1, 1, 1) under (1, 0, 1).
    assert_eq!(scene.units(), Units::Radiometric);
    let lights = scene.point_lights();
    assert_eq!(lights.len(), 1);
    assert!((lights[0].position - Vec3::new(2.0, 1.0, 2.0)).length() < 1e-6);
    assert!((lights[0].intensity - Vec3::new(1.0, 0.5, 0.25)).length() < 1e-6);
    // The spot: 10 cd (10/683 W/sr) at (2, 1.5, 2), turned −90° about x to point down, cones
    // 0.2 and 0.5 rad. Inside 0.2 rad the full intensity; at γ = 0.35 rad glTF's falloff,
    // t = (cos 0.35 − cos 0.5) / (cos 0.2 − cos 0.5) = 0.60292, t² = 0.36352 (by hand); none
    // beyond 0.5 rad.
    let spot = &scene.luminaires()[0];
    assert!((spot.position - Vec3::new(2.0, 1.5, 2.0)).length() < 1e-6);
    assert!((spot.aim - Vec3::NEG_Y).length() < 1e-6, "{:?}", spot.aim);
    let peak = 10.0 / 683.0;
    let at = |gamma: f32| {
        let dir = Vec3::new(gamma.sin(), -gamma.cos(), 0.0);
        spot.tint.x * spot.candela_towards(dir) as f32
    };
    assert!((at(0.0) - peak).abs() < 1e-6 * peak);
    assert!((at(0.15) - peak).abs() < 1e-6 * peak);
    assert!(
        (at(0.35) / peak - 0.36352).abs() < 2e-3,
        "{}",
        at(0.35) / peak
    );
    assert_eq!(at(0.55), 0.0);
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
fn blender_mesh_lights_and_spots_light_as_cycles_renders_them() {
    // tests/data/blender-lamps.glb (`scripts/blender_lamps.py`): the same room lit by a 0.6 m
    // emissive panel hanging in it (emission strength 10, which Blender's mesh lights give off
    // from both faces) and a 200 W spot of 60° with blend 0.3 pointing down. Cycles, 512 spp at
    // 256 × 192: mean radiance 0.36488 (228 s). The panel emits 2 × 0.36 m² × π × 10 =
    // 22.62 W; the spot is 200/4π W/sr on its axis, as Blender writes it (10,870 cd).
    let scene = Scene::load(data("blender-lamps.glb")).unwrap();
    let area = scene.emitted_power().x - scene.luminaires()[0].flux().x;
    assert!(
        (area - 2.0 * 0.36 * std::f64::consts::PI * 10.0).abs() < 0.01,
        "{area}"
    );
    let spot = &scene.luminaires()[0];
    let axis = spot.tint.x * spot.candela_towards(spot.aim) as f32;
    assert!((axis / (200.0 / (4.0 * std::f32::consts::PI)) - 1.0).abs() < 1e-4);
    const CYCLES_MEAN: f64 = 0.36488;
    for backend in Backend::available() {
        let mut scene = scene.clone();
        let camera = meshlight::scene::Camera {
            width: 256,
            height: 192,
            ..*scene.camera()
        };
        scene.set_camera(camera).unwrap();
        let (_, image) = solve_and_render(&scene, backend, Options::default(), true);
        let ratio = image.mean() / CYCLES_MEAN;
        eprintln!("{backend}: ours / Cycles {ratio:.4}");
        assert!((ratio - 1.0).abs() < 0.01, "{backend}: {ratio}");
    }
}

#[test]
fn a_blender_panel_light_a_centimetre_under_the_ceiling_lights_as_cycles_renders_it() {
    // tests/data/blender-halo.glb (`scripts/blender_halo.py`): Blender's default mesh light, a
    // 0.6 m plane facing up, emitting from both faces, 1 cm under the ceiling of a cube room
    // whose faces point out; every material two-sided, as Blender exports them. Against
    // Cycles' image of the same view (tests/data/blender-halo-cycles.exr, 1,024 spp, a
    // renderer that shares nothing with us): light emitted into the gap must stay there (a
    // bright ring round the panel read +4.8% once), and the room's outsides, which no light
    // reaches, must not take half the samples (with them, MAE/mean over 4 × 4 blocks 0.64%,
    // bias −0.62%; without, 0.33% and −0.23%).
    let scene = Scene::load(data("blender-halo.glb")).unwrap();
    let cycles = Image::read_exr(&data("blender-halo-cycles.exr")).unwrap();
    for backend in Backend::available() {
        let mut scene = scene.clone();
        let camera = meshlight::scene::Camera {
            width: cycles.width,
            height: cycles.height,
            ..*scene.camera()
        };
        scene.set_camera(camera).unwrap();
        let (_, image) = solve_and_render(&scene, backend, Options::default(), true);
        let e = meshlight::metrics::compare_blocks(&image, &cycles, 4).unwrap();
        assert!(
            e.bias.abs() < 0.01 && e.mae_over_mean < 0.005 && e.p99_over_mean < 0.025,
            "{backend}: {e:?}"
        );
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

#[test]
fn mutated_blender_glb_files_load_or_fail_cleanly_never_panic() {
    // 4,000 mutants of the two Blender exports: bytes flipped, runs overwritten with 0 or 0xFF,
    // the file cut short, and numbers in the JSON chunk replaced by 0, -1, 9e99 or 4294967295
    // (padded, so the chunk's length holds and the mutant gets past the GLB header). Each
    // loads or is an error; a panic fails the test and names the mutant.
    use rand::{RngExt, SeedableRng};
    let seeds = [
        std::fs::read(shipped("blender-stripes").with_file_name("room.glb")).unwrap(),
        std::fs::read(data("blender-room.glb")).unwrap(),
    ];
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(20);
    let (mut loaded, mut refused) = (0, 0);
    for i in 0..4000 {
        let mut bytes = seeds[i % 2].clone();
        let json_end = 20 + u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        match i % 4 {
            0 => {
                for _ in 0..rng.random_range(1..8) {
                    let at = rng.random_range(0..bytes.len());
                    bytes[at] ^= 1 << rng.random_range(0..8);
                }
            }
            1 => {
                let at = rng.random_range(0..bytes.len());
                let end = (at + rng.random_range(1..64)).min(bytes.len());
                let fill = if rng.random_bool(0.5) { 0 } else { 0xFF };
                bytes[at..end].fill(fill);
            }
            2 => bytes.truncate(rng.random_range(0..bytes.len())),
            _ => {
                let digits: Vec<usize> = (20..json_end)
                    .filter(|&j| bytes[j].is_ascii_digit() && !bytes[j - 1].is_ascii_digit())
                    .collect();
                let at = digits[rng.random_range(0..digits.len())];
                let end = (at..json_end)
                    .find(|&j| !(bytes[j].is_ascii_digit() || bytes[j] == b'.'))
                    .unwrap();
                let choices: [&[u8]; 4] = [b"0", b"-1", b"9e99", b"4294967295"];
                let with = choices[rng.random_range(0..4)];
                if with.len() <= end - at {
                    bytes[at..at + with.len()].copy_from_slice(with);
                    bytes[at + with.len()..end].fill(b' ');
                }
            }
        }
        let files = meshlight::scene::Memory::default().with("x.glb", bytes);
        let result = std::panic::catch_unwind(|| Scene::load_from(&files, "x.glb"));
        match result {
            Ok(Ok(scene)) => {
                assert!(scene.bounds().diagonal().is_finite(), "mutant {i}");
                loaded += 1;
            }
            Ok(Err(e)) => {
                // Named, and found by our checks, not by a panic inside the gltf crate.
                let e = e.to_string();
                assert!(e.contains("x.glb"), "mutant {i}: {e}");
                assert!(!e.contains("glTF reader failed"), "mutant {i}: {e}");
                refused += 1;
            }
            Err(_) => panic!("mutant {i} panicked"),
        }
    }
    // Both outcomes happen: the mutations reach the reader and not only its first check.
    assert!(
        loaded > 100 && refused > 100,
        "{loaded} loaded, {refused} refused"
    );
}

#[test]
fn a_double_sided_emitter_lights_both_halves_of_a_room() {
    // A 0.5 m square lamp (Ke 1) level in the middle of a closed 2 m cube of Kd 0.5, two-sided
    // (glTF's doubleSided, as Blender writes it; here the library's `two_sided`): it emits
    // 2 × 0.25 m² × π W, twice a one-sided lamp's, and by symmetry the floor and the ceiling
    // get the same light. Both backends, meshless against the path tracer.
    let build = |two_sided: bool| {
        let mut b = common::Builder::default();
        let wall = b.material(common::material("wall", 0.5, 0.0));
        let mut lamp = common::material("lamp", 0.0, 1.0);
        lamp.two_sided = two_sided;
        let lamp = b.material(lamp);
        b.room(Vec3::ZERO, Vec3::splat(2.0), wall, &[]);
        let (lo, hi) = (0.75, 1.25);
        b.quad(
            [
                Vec3::new(lo, 1.0, lo),
                Vec3::new(hi, 1.0, lo),
                Vec3::new(hi, 1.0, hi),
                Vec3::new(lo, 1.0, hi),
            ],
            lamp,
        );
        b.scene(common::camera(
            Vec3::new(1.0, 1.0, 0.05),
            Vec3::new(1.0, 1.0, 2.0),
            24,
        ))
    };
    let (one, two) = (build(false), build(true));
    let quarter_pi = 0.25 * std::f64::consts::PI;
    assert!((one.emitted_power().x - quarter_pi).abs() < 1e-6);
    assert!((two.emitted_power().x - 2.0 * quarter_pi).abs() < 1e-5);
    for backend in common::backends() {
        let (solution, image) = solve_and_render(&two, backend, Options::default(), true);
        let s = solution.samples();
        let mean_on = |y: f32, ny: f32| {
            let ks: Vec<usize> = (0..s.len())
                .filter(|&k| (s.position()[k].y - y).abs() < 1e-3 && s.normal()[k].y == ny)
                .collect();
            ks.iter().map(|&k| solution.irradiance()[k].x).sum::<f64>() / ks.len() as f64
        };
        let (floor, ceiling) = (mean_on(0.0, 1.0), mean_on(2.0, -1.0));
        assert!(
            floor > 0.0 && (floor / ceiling - 1.0).abs() < 0.02,
            "{backend:?}: floor {floor}, ceiling {ceiling}"
        );
        let vis = backend.build(&two).unwrap();
        let traced = meshlight::reference::path_trace(
            &two,
            vis.as_ref(),
            &meshlight::reference::PathOptions {
                spp: 512,
                ..Default::default()
            },
            &mut |_| meshlight::Control::Continue,
        )
        .unwrap();
        let error = compare(&image, &traced.image).unwrap();
        assert!(error.bias.abs() < 0.02, "{backend:?}: {error:?}");
    }
}
