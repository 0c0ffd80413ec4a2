//! A hostile host: inputs that once aborted, hung or panicked the library, each run in a child
//! process of this test binary (so an abort is caught, not suffered) under a 4 GiB
//! address-space limit and a watchdog. Every case must end in a clear `Err` or a correct
//! result, on every backend.

mod common;

use std::io::Write;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::{camera, material, Builder};
use glam::Vec3;
use meshlight::lux::{enclosed, illuminance, LuxOptions};
use meshlight::progress::Control;
use meshlight::reference::{patch_radiosity, path_trace, PatchOptions, PathOptions};
use meshlight::scene::{Grid, Mesh, SceneParts, SolverDefaults};
use meshlight::visibility::{Hit, Ray, Segment};
use meshlight::{Backend, Error, Options, RenderOptions, Scene, Visibility};

/// The environment variable that tells a child which case it runs.
const CASE: &str = "MESHLIGHT_HOSTILE_CASE";
/// Address space a case may take: a case asking for more fails its allocation (an abort the
/// parent sees) instead of swapping the machine.
const ADDRESS_SPACE: u64 = 4 << 30;
/// Seconds a case may take before it counts as a hang.
const WATCHDOG: u64 = 60;

/// Runs `body` in a child process (the parent) or runs it (the child).
fn isolated(name: &str, body: impl FnOnce()) {
    if std::env::var(CASE).as_deref() == Ok(name) {
        body();
        return;
    }
    let exe = std::env::current_exe().unwrap();
    let limit = format!("--as={ADDRESS_SPACE}");
    let args = [name, "--exact", "--nocapture", "--test-threads=1"];
    let mut command = if Command::new("prlimit").arg("--version").output().is_ok() {
        let mut c = Command::new("prlimit");
        c.arg(limit).arg("--").arg(&exe).args(args);
        c
    } else {
        let mut c = Command::new(&exe);
        c.args(args);
        c
    };
    let mut child = command
        .env(CASE, name)
        .env("RUST_BACKTRACE", "0")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > Duration::from_secs(WATCHDOG) {
            child.kill().ok();
            panic!("{name}: still running after {WATCHDOG} s: a hang");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let output = child.wait_with_output().unwrap();
    let text = String::from_utf8_lossy(&output.stdout).to_string()
        + &String::from_utf8_lossy(&output.stderr);
    let text: String = text.lines().take(30).collect::<Vec<_>>().join("\n");
    assert!(
        status.success(),
        "{name}: the child ended with {status} after {:.1} s:\n{text}",
        start.elapsed().as_secs_f64()
    );
}

/// A lit room, 2 × 2 × 2, with a point light: small enough to solve in a moment.
fn room() -> Scene {
    let mut b = Builder::default();
    let white = b.material(material("white", 0.7, 0.0));
    b.room(Vec3::ZERO, Vec3::splat(2.0), white, &[]);
    b.point_lights.push(meshlight::scene::PointLight {
        position: Vec3::splat(1.0),
        intensity: Vec3::splat(2.0),
    });
    b.scene(camera(Vec3::new(1.0, 1.0, 1.9), Vec3::splat(1.0), 16))
}

fn quick() -> Options {
    Options {
        rounds: 1,
        epsilon: Some(0.2),
        ..Options::default()
    }
}

fn go(_: &meshlight::Progress) -> Control {
    Control::Continue
}

/// A scene of `triangles` with one material, a point light and a camera.
fn scene_of(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> meshlight::Result<Scene> {
    scene_sided(positions, triangles, false)
}

/// [`scene_of`], its faces reflecting on both sides if `two_sided`.
fn scene_sided(
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    two_sided: bool,
) -> meshlight::Result<Scene> {
    let n = triangles.len();
    let parts = SceneParts {
        mesh: Mesh {
            positions,
            triangles,
            triangle_materials: vec![0; n],
            materials: vec![material("white", 0.5, 0.0)],
            texcoords: Vec::new(),
        },
        point_lights: vec![meshlight::scene::PointLight {
            position: Vec3::new(0.5, 2.0, 0.5),
            intensity: Vec3::ONE,
        }],
        camera: camera(Vec3::new(0.5, 0.5, 3.0), Vec3::splat(0.5), 8),
        two_sided,
        solver: SolverDefaults::default(),
    };
    Scene::from_parts("hostile", parts)
}

/// Asserts an error and that its message mentions every word of `words`.
fn refused<T: std::fmt::Debug>(case: &str, result: meshlight::Result<T>, words: &[&str]) {
    match result {
        Ok(value) => panic!("{case}: accepted: {value:?}"),
        Err(e) => {
            let text = e.to_string();
            for w in words {
                assert!(text.contains(w), "{case}: '{text}' does not mention '{w}'");
            }
            println!("{case}: {text}");
        }
    }
}

// --- Surface grouping: linear in the triangles whatever the mesh. ---

/// `n` triangles sharing the edge (0,0,0)-(0,0,1), each turned by 2π / n about it, their third
/// corners `radius` from it.
fn fan(n: u32, radius: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut positions = vec![Vec3::ZERO, Vec3::Z];
    let mut triangles = Vec::new();
    for i in 0..n {
        let a = std::f32::consts::TAU * i as f32 / n as f32;
        positions.push(Vec3::new(radius * a.cos(), radius * a.sin(), 0.5));
        triangles.push([0, 1, i + 2]);
    }
    (positions, triangles)
}

#[test]
fn ten_thousand_identical_triangles_group_in_bounded_time() {
    isolated(
        "ten_thousand_identical_triangles_group_in_bounded_time",
        || {
            let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Z];
            let scene = scene_of(positions, vec![[0, 2, 1]; 10_000]).unwrap();
            // Identical faces: one surface (they share edges, plane, facing and material).
            assert_eq!(scene.surfaces().len(), 1);
            assert_eq!(scene.triangles().len(), 10_000);
        },
    );
}

#[test]
fn a_hundred_thousand_triangles_fanned_around_one_edge_group_in_bounded_time() {
    isolated(
        "a_hundred_thousand_triangles_fanned_around_one_edge_group_in_bounded_time",
        || {
            // Every triangle shares the edge (0,0,0)-(0,0,1) and turns by 2π / n about it:
            // each in its own plane, so each its own surface.
            let n = 100_000u32;
            let (positions, triangles) = fan(n, 1.0);
            let t = Instant::now();
            let scene = scene_of(positions, triangles).unwrap();
            println!("fan of {n}: {:.2} s", t.elapsed().as_secs_f64());
            assert_eq!(scene.surfaces().len(), n as usize);
        },
    );
}

#[test]
fn a_hundred_thousand_identical_triangles_build_on_every_backend() {
    isolated(
        "a_hundred_thousand_identical_triangles_build_on_every_backend",
        || {
            // The pure-Rust BVH's builder once took time quadratic in copies of one triangle
            // (10k copies 48 s); copies are now built once and answer as the first.
            let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Z];
            let scene = scene_of(positions, vec![[0, 2, 1]; 100_000]).unwrap();
            for backend in Backend::available() {
                let t = Instant::now();
                let caster = backend.build(&scene).unwrap();
                println!("{backend}: {:.2} s", t.elapsed().as_secs_f64());
                // A ray down onto the triangle from y = 1 hits it at t = 1, a ray beside it
                // misses; and a segment through it is blocked.
                let down = Vec3::new(0.0, -1.0, 0.0);
                let rays = [
                    Ray {
                        origin: Vec3::new(0.2, 1.0, 0.2),
                        dir: down,
                        t_min: 0.0,
                        t_max: 10.0,
                    },
                    Ray {
                        origin: Vec3::new(0.8, 1.0, 0.8),
                        dir: down,
                        t_min: 0.0,
                        t_max: 10.0,
                    },
                ];
                let mut hits = [None; 2];
                caster.intersect(&rays, &mut hits).unwrap();
                let hit = hits[0].unwrap_or_else(|| panic!("{backend}: missed"));
                assert!((hit.t - 1.0).abs() < 1e-5, "{backend}: t {}", hit.t);
                assert!((hit.triangle as usize) < 100_000);
                assert!(hits[1].is_none(), "{backend}: hit beside the triangle");
                let through = Segment {
                    a: Vec3::new(0.2, 1.0, 0.2),
                    b: Vec3::new(0.2, -1.0, 0.2),
                };
                let mut blocked = [false];
                caster.occluded(&[through], &mut blocked).unwrap();
                assert!(blocked[0], "{backend}: the segment passed through");
            }
        },
    );
}

#[test]
fn an_obj_of_a_hundred_thousand_repeated_faces_loads() {
    isolated("an_obj_of_a_hundred_thousand_repeated_faces_loads", || {
        let dir = std::env::temp_dir().join(format!("meshlight-hostile-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut obj = std::fs::File::create(dir.join("f.obj")).unwrap();
        writeln!(obj, "v 0 0 0\nv 1 0 0\nv 0 1 0").unwrap();
        for _ in 0..100_000 {
            writeln!(obj, "f 1 2 3").unwrap();
        }
        drop(obj);
        std::fs::write(
            dir.join("scene.toml"),
            "obj = \"f.obj\"\n[[point_light]]\nposition = [0.2, 0.2, 1]\nintensity = [1, 1, 1]\n\
             [camera]\nposition = [0.3, 0.3, 2]\nlook_at = [0.3, 0.3, 0]\nfov_y = 60\nwidth = 8\n\
             height = 8\n",
        )
        .unwrap();
        let scene = Scene::load(dir.join("scene.toml"));
        std::fs::remove_dir_all(&dir).ok();
        let scene = scene.unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.surfaces().len(), 1);
    });
}

// --- Allocations under the budget, refused before they are made. ---

#[test]
fn a_huge_camera_is_refused_before_its_image_is_allocated() {
    isolated(
        "a_huge_camera_is_refused_before_its_image_is_allocated",
        || {
            let mut scene = room();
            let big = meshlight::scene::Camera {
                width: 32_768,
                height: 32_768,
                ..*scene.camera()
            };
            // Either the camera or the render is refused; nothing is allocated for 10⁹ pixels.
            if scene.set_camera(big).is_ok() {
                let vis = Backend::Bvh.build(&scene).unwrap();
                let s = meshlight::solve(&scene, vis.as_ref(), &quick(), &mut go).unwrap();
                let r =
                    meshlight::render(&scene, &s, vis.as_ref(), &RenderOptions::default(), &mut go);
                refused("camera 32768²", r.map(|_| ()), &["budget"]);
            }
        },
    );
}

#[test]
fn a_huge_supersample_or_gather_is_refused() {
    isolated("a_huge_supersample_or_gather_is_refused", || {
        let scene = room();
        let vis = Backend::Bvh.build(&scene).unwrap();
        let s = meshlight::solve(&scene, vis.as_ref(), &quick(), &mut go).unwrap();
        let options = RenderOptions {
            supersample: 4096,
            ..RenderOptions::default()
        };
        let r = meshlight::render(&scene, &s, vis.as_ref(), &options, &mut go);
        refused("supersample 4096", r.map(|_| ()), &["supersample"]);
        let options = RenderOptions {
            gather_rays: u32::MAX,
            ..RenderOptions::default()
        };
        let r = meshlight::render(&scene, &s, vis.as_ref(), &options, &mut go);
        refused("gather rays u32::MAX", r.map(|_| ()), &["gather_rays"]);
        // The most gather rays allowed, in a room whose every pixel is near a corner, end
        // within the child's address space and watchdog.
        let options = RenderOptions {
            gather_rays: meshlight::render::MAX_GATHER_RAYS,
            ..RenderOptions::default()
        };
        let (image, _) = meshlight::render(&scene, &s, vis.as_ref(), &options, &mut go).unwrap();
        assert!(image.mean() > 0.0 && image.mean().is_finite());
    });
}

#[test]
fn a_huge_pipeline_is_refused_or_bounded() {
    isolated("a_huge_pipeline_is_refused_or_bounded", || {
        let scene = room();
        let vis = Backend::Bvh.build(&scene).unwrap();
        let options = Options {
            pipeline_capacity: 1 << 30,
            ..quick()
        };
        let r = meshlight::solve(&scene, vis.as_ref(), &options, &mut go);
        refused("pipeline 2³⁰", r.map(|_| ()), &["pipeline"]);
    });
}

#[test]
fn a_huge_grid_is_refused() {
    isolated("a_huge_grid_is_refused", || {
        let huge = Grid::new(
            "huge",
            Vec3::ZERO,
            Vec3::X * 1e5,
            Vec3::Z * 1e5,
            None,
            Some(1.0),
        );
        assert!(huge.is_err(), "a 10⁵ × 10⁵ grid was accepted");
    });
}

// --- Loops a host waits on end, or hear Stop. ---

#[test]
fn a_tiny_zeta_ends_or_is_stopped() {
    isolated("a_tiny_zeta_ends_or_is_stopped", || {
        let scene = room();
        let vis = Backend::Bvh.build(&scene).unwrap();
        let options = Options {
            zeta: 1e-5,
            rounds: 2,
            ..quick()
        };
        let start = Instant::now();
        let mut last = Instant::now();
        let mut longest_silence = Duration::ZERO;
        let r = meshlight::solve(&scene, vis.as_ref(), &options, &mut |_| {
            longest_silence = longest_silence.max(last.elapsed());
            last = Instant::now();
            if start.elapsed() > Duration::from_secs(5) {
                Control::Stop
            } else {
                Control::Continue
            }
        });
        let took = start.elapsed();
        println!(
            "zeta 1e-5: {:.1} s, longest silence {longest_silence:?}",
            took.as_secs_f64()
        );
        // Either it ends on its own (the darts are capped) or the Stop is heard promptly.
        if let Ok(s) = &r {
            assert_eq!(s.validate(), Ok(()));
        }
        assert!(took < Duration::from_secs(8), "{took:?}");
        assert!(
            longest_silence < Duration::from_secs(5),
            "{longest_silence:?}"
        );
    });
}

// --- A backend that answers nonsense. ---

/// A backend that answers every ray with a hit on a triangle the scene does not have.
struct Liar(Box<dyn Visibility>);

impl Visibility for Liar {
    fn name(&self) -> &'static str {
        "liar"
    }
    fn occluded(&self, segments: &[Segment], out: &mut [bool]) -> meshlight::Result<()> {
        self.0.occluded(segments, out)
    }
    fn intersect(&self, rays: &[Ray], out: &mut [Option<Hit>]) -> meshlight::Result<()> {
        for (o, r) in out.iter_mut().zip(rays) {
            *o = Some(Hit {
                t: 0.5 * (r.t_min + r.t_max.min(1.0)),
                triangle: u32::MAX,
            });
        }
        Ok(())
    }
}

#[test]
fn hits_on_triangles_the_scene_lacks_are_refused_everywhere() {
    isolated(
        "hits_on_triangles_the_scene_lacks_are_refused_everywhere",
        || {
            let mut scene = room();
            let grid =
                Grid::new("g", Vec3::new(0.1, 0.5, 0.1), Vec3::X, Vec3::Z, None, None).unwrap();
            scene.add_grid(grid.clone()).unwrap();
            for backend in Backend::available() {
                let honest = backend.build(&scene).unwrap();
                let liar = Liar(backend.build(&scene).unwrap());
                let words = ["liar", "triangle 4294967295"];
                refused("enclosed", enclosed(&scene, &liar, &grid), &words);
                refused(
                    "solve",
                    meshlight::solve(&scene, &liar, &quick(), &mut go).map(|_| ()),
                    &words,
                );
                let s = meshlight::solve(&scene, honest.as_ref(), &quick(), &mut go).unwrap();
                let r = meshlight::render(&scene, &s, &liar, &RenderOptions::default(), &mut go);
                refused("render", r.map(|_| ()), &words);
                let lux = illuminance(&scene, &s, &liar, &grid, &LuxOptions::default(), &mut go);
                // The direct light and gather trace segments only: the liar's rays are not
                // asked, and the honest answer is fine.
                if let Err(e) = lux {
                    assert!(e.to_string().contains("liar"), "{e}");
                }
                let paths = PathOptions {
                    spp: 2,
                    ..PathOptions::default()
                };
                refused(
                    "path_trace",
                    path_trace(&scene, &liar, &paths, &mut go).map(|_| ()),
                    &words,
                );
                let patches = PatchOptions {
                    patch_size: 0.5,
                    ..PatchOptions::default()
                };
                refused(
                    "patch_radiosity",
                    patch_radiosity(&scene, &liar, &patches, &mut go).map(|_| ()),
                    &words,
                );
            }
        },
    );
}

/// A backend whose hits are the true ones at a distance no ray can have: −1 or ∞.
struct FarOff(Box<dyn Visibility>, f32);

impl Visibility for FarOff {
    fn name(&self) -> &'static str {
        "far-off"
    }
    fn occluded(&self, segments: &[Segment], out: &mut [bool]) -> meshlight::Result<()> {
        self.0.occluded(segments, out)
    }
    fn intersect(&self, rays: &[Ray], out: &mut [Option<Hit>]) -> meshlight::Result<()> {
        self.0.intersect(rays, out)?;
        for hit in out.iter_mut().flatten() {
            hit.t = self.1;
        }
        Ok(())
    }
}

#[test]
fn hits_at_a_negative_or_infinite_distance_are_the_casters_error() {
    isolated(
        "hits_at_a_negative_or_infinite_distance_are_the_casters_error",
        || {
            // Once: t = −1 gave a black image without a word, t = ∞ was blamed on the
            // library's own segments.
            let scene = room();
            for backend in Backend::available() {
                let honest = backend.build(&scene).unwrap();
                let s = meshlight::solve(&scene, honest.as_ref(), &quick(), &mut go).unwrap();
                for t in [-1.0, f32::INFINITY] {
                    let caster = FarOff(backend.build(&scene).unwrap(), t);
                    let t_is = format!("at t = {t}");
                    let words = ["far-off", "intersect answered", t_is.as_str()];
                    let solved = meshlight::solve(&scene, &caster, &quick(), &mut go);
                    refused("solve", solved.map(|_| ()), &words);
                    let r =
                        meshlight::render(&scene, &s, &caster, &RenderOptions::default(), &mut go);
                    refused("render", r.map(|_| ()), &words);
                    let paths = PathOptions {
                        spp: 2,
                        ..PathOptions::default()
                    };
                    let traced = path_trace(&scene, &caster, &paths, &mut go);
                    refused("path_trace", traced.map(|_| ()), &words);
                }
            }
        },
    );
}

#[test]
fn an_epsilon_beyond_the_scene_is_refused_by_name() {
    isolated("an_epsilon_beyond_the_scene_is_refused_by_name", || {
        // Once: "invalid argument segments … 8.5e37", the library blaming its own segment.
        let scene = room();
        let diagonal = 12f32.sqrt(); // the 2 × 2 × 2 room
        let vis = Backend::Bvh.build(&scene).unwrap();
        for epsilon in [f32::MAX, 1e30, 101.0 * diagonal] {
            let options = Options {
                epsilon: Some(epsilon),
                ..quick()
            };
            let solved = meshlight::solve(&scene, vis.as_ref(), &options, &mut go);
            refused("huge ε", solved.map(|_| ()), &["epsilon", "diagonal"]);
        }
        // Within the bound: one sample a side, a lit answer.
        let options = Options {
            epsilon: Some(99.0 * diagonal),
            ..quick()
        };
        let s = meshlight::solve(&scene, vis.as_ref(), &options, &mut go).unwrap();
        assert!(s.samples().len() <= 12, "{} samples", s.samples().len());
        assert!(s.radiosity().iter().any(|b| b.x > 0.0));
    });
}

#[test]
fn a_hosts_sky_out_of_range_is_refused_by_name() {
    isolated("a_hosts_sky_out_of_range_is_refused_by_name", || {
        use meshlight::daylight::{Daylight, Sky, SkyModel};
        for e in [f64::NAN, -1.0, f64::INFINITY, 1e300] {
            refused(
                "sky",
                Sky::new(SkyModel::CieOvercast, 0.0, 0.0, e),
                &["diffuse_horizontal"],
            );
        }
        refused(
            "type 0",
            Sky::new(SkyModel::Cie(0), 30.0, 180.0, 1e4),
            &["type 0"],
        );
        refused(
            "perez NaN",
            Sky::new(
                SkyModel::Perez {
                    clearness: f64::NAN,
                    brightness: 0.2,
                },
                30.0,
                180.0,
                1e4,
            ),
            &["Perez"],
        );
        let sky = || Sky::new(SkyModel::Uniform, 0.0, 0.0, 1e4).unwrap();
        let site = |up: Vec3, north: Vec3, rho: f64, sun: Option<(f64, f64)>, en: f64| {
            Daylight::new(sky(), up, north, rho, 1e4, sun, en)
        };
        refused("up 0", site(Vec3::ZERO, -Vec3::Z, 0.2, None, 0.0), &["up"]);
        refused("up NaN", site(Vec3::NAN, -Vec3::Z, 0.2, None, 0.0), &["up"]);
        refused(
            "north up",
            site(Vec3::Y, Vec3::Y, 0.2, None, 0.0),
            &["north"],
        );
        refused(
            "rho 2",
            site(Vec3::Y, -Vec3::Z, 2.0, None, 0.0),
            &["ground_reflectance"],
        );
        refused(
            "sun NaN",
            site(Vec3::Y, -Vec3::Z, 0.2, Some((f64::NAN, 0.0)), 1.0),
            &["sun"],
        );
        refused(
            "no sun",
            site(Vec3::Y, -Vec3::Z, 0.2, None, 5e4),
            &["sun's position"],
        );
        refused(
            "huge sun",
            site(Vec3::Y, -Vec3::Z, 0.2, Some((30.0, 0.0)), 1e300),
            &["illuminance"],
        );
        // Within range: a scene with it solves to finite light.
        let mut scene = room();
        scene.set_daylight(Some(
            site(Vec3::Y, -Vec3::Z, 1.0, Some((10.0, 0.0)), 1e6).unwrap(),
        ));
        let vis = Backend::Bvh.build(&scene).unwrap();
        let s = meshlight::solve(&scene, vis.as_ref(), &quick(), &mut go).unwrap();
        assert!(s.radiosity().iter().all(|b| b.is_finite()));
    });
}

/// A backend that panics on its first call.
struct Panicky;

impl Visibility for Panicky {
    fn name(&self) -> &'static str {
        "panicky"
    }
    fn occluded(&self, _: &[Segment], _: &mut [bool]) -> meshlight::Result<()> {
        panic!("occluded exploded")
    }
    fn intersect(&self, _: &[Ray], _: &mut [Option<Hit>]) -> meshlight::Result<()> {
        panic!("intersect exploded")
    }
}

#[test]
fn a_panicking_backend_is_named_in_the_error() {
    isolated("a_panicking_backend_is_named_in_the_error", || {
        let scene = room();
        let r = meshlight::solve(&scene, &Panicky, &quick(), &mut go);
        refused("solve", r.map(|_| ()), &["panicky", "exploded"]);
        let honest = Backend::Bvh.build(&scene).unwrap();
        let s = meshlight::solve(&scene, honest.as_ref(), &quick(), &mut go).unwrap();
        let r = meshlight::render(&scene, &s, &Panicky, &RenderOptions::default(), &mut go);
        let text = r.map(|_| ()).unwrap_err().to_string();
        assert!(
            text.contains("panicky") && text.contains("exploded"),
            "{text}"
        );
        assert!(
            !text.contains("solver"),
            "a render failure worded as the solver's: {text}"
        );
    });
}

// --- Scale and solutions that do not fit. ---

#[test]
fn a_solution_of_another_size_does_not_render() {
    isolated("a_solution_of_another_size_does_not_render", || {
        let scene = room();
        let bigger = scene.scaled(2.0).unwrap();
        let vis = Backend::Bvh.build(&scene).unwrap();
        let s = meshlight::solve(&scene, vis.as_ref(), &quick(), &mut go).unwrap();
        let vis2 = Backend::Bvh.build(&bigger).unwrap();
        let r = meshlight::render(
            &bigger,
            &s,
            vis2.as_ref(),
            &RenderOptions::default(),
            &mut go,
        );
        refused("render ×2", r.map(|_| ()), &["solution"]);
    });
}

#[test]
fn scenes_beyond_the_valid_scale_are_refused_and_those_within_it_agree() {
    isolated(
        "scenes_beyond_the_valid_scale_are_refused_and_those_within_it_agree",
        || {
            let scene = room();
            let diagonal = scene.bounds().diagonal();
            for s in [2.4e14f32, 1e-18, 1e-4] {
                refused(&format!("× {s}"), scene.scaled(s).map(|_| ()), &["across"]);
            }
            // Far from the origin: 1e6 diagonals out.
            let mut b = Builder::default();
            let white = b.material(material("white", 0.7, 0.0));
            let o = Vec3::new(1e6 * 3.5, 0.0, 0.0);
            b.room(o, o + Vec3::splat(2.0), white, &[]);
            let parts = SceneParts {
                mesh: b.mesh,
                point_lights: Vec::new(),
                camera: camera(o + Vec3::ONE, o + Vec3::new(1.0, 1.0, -1e3), 8),
                two_sided: false,
                solver: SolverDefaults::default(),
            };
            refused(
                "far out",
                Scene::from_parts("far", parts).map(|_| ()),
                &["from the origin"],
            );
            // Near the ends of the range the image is the same as at 1 (the same ε in
            // diagonals): the range is one the results hold over.
            let mean = |s: f32, backend: Backend| {
                let scaled = scene.scaled(s).unwrap();
                let vis = backend.build(&scaled).unwrap();
                let options = Options {
                    epsilon: Some(0.2 * s),
                    ..quick()
                };
                let solved = meshlight::solve(&scaled, vis.as_ref(), &options, &mut go).unwrap();
                let (image, _) = meshlight::render(
                    &scaled,
                    &solved,
                    vis.as_ref(),
                    &RenderOptions::default(),
                    &mut go,
                )
                .unwrap();
                image.mean()
            };
            let (lo, hi) = (
                *meshlight::scene::SCENE_SIZE.start() / diagonal,
                *meshlight::scene::SCENE_SIZE.end() / diagonal,
            );
            for backend in Backend::available() {
                let at_one = mean(1.0, backend);
                for s in [lo * 1.01, hi * 0.99] {
                    let m = mean(s, backend);
                    assert!(
                        (m / at_one - 1.0).abs() < 1e-3,
                        "{backend} × {s}: mean {m} against {at_one} at × 1"
                    );
                }
            }
        },
    );
}

#[test]
fn numbers_in_messages_have_sensible_digits() {
    isolated("numbers_in_messages_have_sensible_digits", || {
        let scene = room();
        let vis = Backend::Bvh.build(&scene).unwrap();
        let options = Options {
            epsilon: Some(1e-12),
            ..quick()
        };
        let e = meshlight::solve(&scene, vis.as_ref(), &options, &mut go).unwrap_err();
        let text = e.to_string();
        let longest = text
            .split(|c: char| !c.is_ascii_digit())
            .map(str::len)
            .max()
            .unwrap_or(0);
        assert!(longest <= 8, "a number of {longest} digits: {text}");
        assert!(
            matches!(e, Error::Budget { .. } | Error::Option { .. }),
            "{e:?}"
        );
    });
}

// --- Options drawn at random from the extremes. ---

/// splitmix64: a reproducible stream of choices without a dependency.
struct Draw(u64);

impl Draw {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn pick<T: Copy>(&mut self, values: &[T]) -> T {
        values[(self.next() % values.len() as u64) as usize]
    }
}

fn draw_f32(draw: &mut Draw) -> f32 {
    draw.pick(&[f32::NAN, f32::INFINITY, -1.0, 0.0, 1e-30, 0.2, 8.0, 1e30])
}

#[test]
fn options_drawn_from_the_extremes_end_in_a_result_or_an_error_and_hear_a_stop() {
    isolated(
        "options_drawn_from_the_extremes_end_in_a_result_or_an_error_and_hear_a_stop",
        || {
            let scene = room();
            let vis = Backend::Bvh.build(&scene).unwrap();
            let f32s = [f32::NAN, f32::INFINITY, -1.0, 0.0, 1e-30, 0.2, 8.0, 1e30];
            let f64s = [
                f64::NAN,
                f64::INFINITY,
                -1.0,
                0.0,
                1e-300,
                1e-3,
                0.05,
                1.0,
                1e300,
            ];
            let sizes = [0usize, 1, 2, 16, 1 << 20, usize::MAX];
            let counts = [0u32, 1, 2, 16, 1000, u32::MAX];
            let mut draw = Draw(2026);
            let (mut ok, mut refused) = (0, 0);
            for case in 0..120 {
                // One to three fields at an extreme (or an ordinary value), the rest default:
                // most cases then reach the solver rather than all being refused at once.
                let mut options = Options {
                    seed: draw.next(),
                    ..Options::default()
                };
                for _ in 0..1 + draw.next() % 3 {
                    match draw.next() % 15 {
                        0 => {
                            let e = draw_f32(&mut draw);
                            options.epsilon = draw.pick(&[None, Some(e)]);
                        }
                        1 => options.alpha = draw.pick(&f32s),
                        2 => options.zeta = draw.pick(&f32s),
                        3 => options.rounds = draw.pick(&[0, 1, 2, 1000]),
                        4 => options.light_samples = draw.pick(&counts),
                        5 => options.tolerance = draw.pick(&f64s),
                        6 => {
                            options.max_shots = draw.pick(&[None, Some(0), Some(1), Some(u64::MAX)])
                        }
                        7 => options.max_samples = draw.pick(&sizes),
                        8 => options.cluster_threshold = draw.pick(&f64s),
                        9 => options.memory_budget = draw.pick(&sizes),
                        10 => options.specular_depth = draw.pick(&counts),
                        11 => options.specular_rays = draw.pick(&counts),
                        12 => options.threads = draw.pick(&[0, 1, 2, usize::MAX]),
                        13 => options.pipeline_capacity = draw.pick(&sizes),
                        _ => options.exact_visibility = !options.exact_visibility,
                    }
                }
                // Stop after 1 s: whatever the options, the call must then end promptly.
                let start = Instant::now();
                let r = meshlight::solve(&scene, vis.as_ref(), &options, &mut |_| {
                    if start.elapsed() > Duration::from_secs(1) {
                        Control::Stop
                    } else {
                        Control::Continue
                    }
                });
                let took = start.elapsed();
                assert!(
                    took < Duration::from_secs(3),
                    "case {case}: {took:?}: {options:?}"
                );
                match r {
                    Ok(s) => {
                        assert_eq!(s.validate(), Ok(()), "case {case}: {options:?}");
                        ok += 1;
                    }
                    Err(_) => refused += 1,
                }
            }
            println!("{ok} solved, {refused} refused");
            assert!(ok > 0 && refused > 0);
        },
    );
}

// --- Rooms of mirrors and glass that once listed chains of images without end. ---

/// A 2 m cube of `walls` with a 0.4 m panel light under its ceiling, and `inside` added.
fn mirrored(walls: meshlight::scene::Material, inside: impl FnOnce(&mut Builder)) -> Scene {
    let mut b = Builder::default();
    let walls = b.material(walls);
    let light = b.material(material("light", 0.0, 10.0));
    b.room(Vec3::ZERO, Vec3::splat(2.0), walls, &[]);
    b.quad(
        [
            Vec3::new(0.8, 1.99, 0.8),
            Vec3::new(1.2, 1.99, 0.8),
            Vec3::new(1.2, 1.99, 1.2),
            Vec3::new(0.8, 1.99, 1.2),
        ],
        light,
    );
    inside(&mut b);
    b.scene(camera(
        Vec3::new(1.0, 1.0, 0.1),
        Vec3::new(1.0, 0.8, 2.0),
        12,
    ))
}

#[test]
fn rooms_of_mirrors_and_a_lamp_in_dense_glass_end_with_an_answer() {
    // Every wall a lossless mirror (a diffuse box the only thing that keeps light), and a lamp
    // inside a closed glass box of index 10 (R = 0.67 at normal incidence, nearly all of it
    // caught by total internal reflection): both listed chains of images without end.
    isolated(
        "rooms_of_mirrors_and_a_lamp_in_dense_glass_end_with_an_answer",
        || {
            let all_mirrors = mirrored(common::specular("mirror", 0.0, 1.0, 0.0), |b| {
                let grey = b.material(material("grey", 0.5, 0.0));
                b.solid(Vec3::new(0.7, 0.0, 0.7), Vec3::new(1.3, 0.6, 1.3), grey);
            });
            let glass_box = mirrored(material("white", 0.7, 0.0), |b| {
                let dense = b.material(common::glass("dense", 10.0, false));
                b.solid(Vec3::splat(0.6), Vec3::new(1.4, 1.995, 1.4), dense);
            });
            for (name, scene) in [("mirrors", all_mirrors), ("dense glass", glass_box)] {
                for backend in Backend::available() {
                    let vis = backend.build(&scene).unwrap();
                    let s = meshlight::solve(&scene, vis.as_ref(), &quick(), &mut go).unwrap();
                    let (image, _) = meshlight::render(
                        &scene,
                        &s,
                        vis.as_ref(),
                        &RenderOptions::default(),
                        &mut go,
                    )
                    .unwrap();
                    let mean = image.mean();
                    assert!(mean.is_finite() && mean > 0.0, "{name}, {backend}: {mean}");
                    println!("{name}, {backend}: mean {mean:.4}");
                }
            }
        },
    );
}

#[test]
fn photons_beyond_the_budget_are_refused_before_they_are_traced() {
    isolated(
        "photons_beyond_the_budget_are_refused_before_they_are_traced",
        || {
            let scene = Scene::load(common::shipped("glass-block")).unwrap();
            let vis = Backend::Bvh.build(&scene).unwrap();
            let options = Options {
                photons: meshlight::solver::MAX_PHOTONS,
                memory_budget: 1 << 30,
                ..quick()
            };
            let solved = meshlight::solve(&scene, vis.as_ref(), &options, &mut go);
            refused("photons", solved, &["photons", "budget"]);
        },
    );
}

// --- glTF files: node graphs, and what their lights and cameras bring. ---

/// A glTF of one triangle (mesh 0) with `nodes` (JSON), `roots` in its scene, and extra
/// top-level JSON members `more` (lights, cameras).
fn gltf_with(nodes: &str, roots: &str, more: &str) -> Vec<u8> {
    format!(
        r#"{{"asset": {{"version": "2.0"}},
  "buffers": [{{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                  "min": [0, 0, 0], "max": [1, 1, 0]}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
  "nodes": {nodes},
  "scenes": [{{"nodes": {roots}}}],
  "scene": 0{more}}}"#
    )
    .into_bytes()
}

/// A perspective camera, as `gltf_with`'s `more`.
const CAMERA: &str =
    r#", "cameras": [{"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.1}}]"#;

fn load_gltf(bytes: Vec<u8>) -> meshlight::Result<Scene> {
    let files = meshlight::scene::Memory::default().with("x.gltf", bytes);
    Scene::load_from(&files, "x.gltf")
}

#[test]
fn gltf_node_cycles_are_refused_by_name_and_deep_instancing_is_bounded() {
    isolated(
        "gltf_node_cycles_are_refused_by_name_and_deep_instancing_is_bounded",
        || {
            // A node that is its own child; two nodes that are each other's.
            let own = gltf_with(r#"[{"mesh": 0, "children": [0]}]"#, "[0]", "");
            refused("own child", load_gltf(own), &["node 0", "cycle"]);
            let two = gltf_with(r#"[{"children": [1]}, {"children": [0]}]"#, "[0]", "");
            refused("2-cycle", load_gltf(two), &["cycle"]);
            // 40 levels, each node the child of the one above twice: 2^40 instances.
            let nodes: Vec<String> = (0..40)
                .map(|i| {
                    if i < 39 {
                        format!(r#"{{"mesh": 0, "children": [{}, {}]}}"#, i + 1, i + 1)
                    } else {
                        r#"{"mesh": 0}"#.to_string()
                    }
                })
                .collect();
            let doubled = gltf_with(&format!("[{}]", nodes.join(",")), "[0]", "");
            refused("doubled", load_gltf(doubled), &["nodes", "refused"]);
            // Instancing within bounds is fine: one triangle in three places.
            let shared = gltf_with(
                r#"[{"children": [1, 2, 3]}, {"mesh": 0}, {"mesh": 0, "translation": [2, 0, 0]},
                   {"mesh": 0, "translation": [4, 0, 0]}, {"camera": 0, "translation": [2, 0, 5]}]"#,
                "[0, 4]",
                CAMERA,
            );
            // (No light: loading is what is tested.)
            let scene = load_gltf(shared).unwrap();
            assert_eq!(scene.triangles().len(), 3);
        },
    );
}

#[test]
fn a_fifo_named_as_a_buffer_is_refused_not_waited_on() {
    isolated("a_fifo_named_as_a_buffer_is_refused_not_waited_on", || {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("buffer.bin");
        let made = Command::new("mkfifo").arg(&fifo).status();
        if !made.is_ok_and(|s| s.success()) {
            println!("no mkfifo here: skipped");
            return;
        }
        let gltf = String::from_utf8(gltf_with(r#"[{"mesh": 0}]"#, "[0]", ""))
            .unwrap()
            .replace(
                "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA",
                "buffer.bin",
            );
        let path = dir.path().join("x.gltf");
        std::fs::write(&path, gltf).unwrap();
        refused("fifo", Scene::load(&path), &["buffer.bin", "regular file"]);
    });
}

#[test]
fn gltf_lights_and_cameras_get_the_checks_a_hosts_do() {
    isolated("gltf_lights_and_cameras_get_the_checks_a_hosts_do", || {
        let light = |intensity: &str, colour: &str| {
            gltf_with(
                r#"[{"mesh": 0}, {"camera": 0, "translation": [0, 0, 5]},
                    {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 0, 1]}]"#,
                "[0, 1, 2]",
                &format!(
                    r#"{CAMERA}, "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [{{"type": "point", "intensity": {intensity}, "color": {colour}}}]}}}}"#
                ),
            )
        };
        refused(
            "negative",
            load_gltf(light("-1e6", "[1, 1, 1]")),
            &["light 0", "negative"],
        );
        refused(
            "huge",
            load_gltf(light("1e39", "[1, 1, 1]")),
            &["light 0", "finite"],
        );
        refused(
            "colour",
            load_gltf(light("10", "[1, -0.5, 1]")),
            &["light 0", "negative"],
        );
        assert!(load_gltf(light("10", "[1, 0.5, 1]")).is_ok());
        let camera = |perspective: &str| {
            gltf_with(
                r#"[{"mesh": 0}, {"camera": 0, "translation": [0, 0, 5]}]"#,
                "[0, 1]",
                &format!(
                    r#", "cameras": [{{"type": "perspective", "perspective": {perspective}}}]"#
                ),
            )
        };
        refused(
            "fov 0",
            load_gltf(camera(r#"{"yfov": 0.0, "znear": 0.1}"#)),
            &["camera", "fov"],
        );
        refused(
            "tall",
            load_gltf(camera(
                r#"{"yfov": 1.0, "znear": 0.1, "aspectRatio": 1e-7}"#,
            )),
            &["camera", "image size", "too large"],
        );
    });
}

#[test]
fn textures_refuse_a_reflectance_bound_outside_zero_to_one() {
    // −1 made every texel's reflectance negative (an image mean of −0.18), 2 let white reflect
    // all light and more (1.45).
    isolated(
        "textures_refuse_a_reflectance_bound_outside_zero_to_one",
        || {
            use meshlight::scene::Texture;
            let png = {
                let mut bytes = Vec::new();
                image::RgbImage::from_raw(1, 1, vec![255, 255, 255])
                    .unwrap()
                    .write_to(
                        &mut std::io::Cursor::new(&mut bytes),
                        image::ImageFormat::Png,
                    )
                    .unwrap();
                bytes
            };
            for bound in [-1.0, 2.0] {
                let made = Texture::from_srgb8("white", 1, 1, 3, &[255, 255, 255], bound);
                assert!(
                    made.is_err_and(|e| e.contains("max_reflectance")),
                    "{bound}"
                );
                let decoded = Texture::decode("white.png", &png, bound);
                assert!(
                    decoded.is_err_and(|e| e.contains("max_reflectance")),
                    "{bound}"
                );
            }
            assert!(Texture::decode("white.png", &png, 0.9).is_ok());
        },
    );
}

// --- A host's transport between ranks. ---

/// A transport that says it is rank 0 of `size` and answers every collective with `fill`
/// (everywhere, its own part too, when `own` is false), its rank flipping after `flip` calls.
struct Faulty {
    size: usize,
    fill: f64,
    own: bool,
    flip: Option<usize>,
    calls: std::sync::atomic::AtomicUsize,
}

impl Faulty {
    fn new(size: usize, fill: f64, own: bool, flip: Option<usize>) -> Faulty {
        Faulty {
            size,
            fill,
            own,
            flip,
            calls: std::sync::atomic::AtomicUsize::new(0),
        }
    }
}

impl meshlight::distributed::Ranks for Faulty {
    fn rank(&self) -> usize {
        let calls = self
            .calls
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        usize::from(self.flip.is_some_and(|f| calls >= f))
    }

    fn size(&self) -> usize {
        self.size
    }

    fn all_gather(&self, mine: &[f64], _: &[usize], out: &mut [f64]) -> meshlight::Result<()> {
        out.fill(self.fill);
        if self.own {
            out[..mine.len()].copy_from_slice(mine);
        }
        Ok(())
    }
}

#[test]
fn a_faulty_transport_is_an_error_that_names_it() {
    isolated("a_faulty_transport_is_an_error_that_names_it", || {
        let scene = room();
        let vis = Backend::Bvh.build(&scene).unwrap();
        let solve = |ranks: &dyn meshlight::distributed::Ranks| {
            meshlight::solver::solve_distributed(&scene, vis.as_ref(), &quick(), ranks, &mut go)
        };
        // Sizes no job has: 2⁴⁰ once allocated that many numbers, usize::MAX overflowed.
        for size in [1usize << 40, usize::MAX, 0] {
            refused(
                "size",
                solve(&Faulty::new(size, 0.0, true, None)),
                &["ranks", "size"],
            );
        }
        // NaN, or −1 where this rank's own values should come back, or a rank that changes.
        refused(
            "NaN",
            solve(&Faulty::new(2, f64::NAN, true, None)),
            &["transport", "NaN"],
        );
        refused(
            "-1",
            solve(&Faulty::new(2, -1.0, false, None)),
            &["transport", "own"],
        );
        refused(
            "flip",
            solve(&Faulty::new(2, 0.0, true, Some(5))),
            &["transport", "rank 1"],
        );
    });
}

// --- Sizes a host raises past the machine. ---

#[test]
fn a_budget_raised_past_the_machine_still_refuses_what_cannot_fit() {
    // At usize::MAX a 32768² render, path trace or patch image once aborted on allocation.
    isolated(
        "a_budget_raised_past_the_machine_still_refuses_what_cannot_fit",
        || {
            let mut scene = room();
            let big = meshlight::scene::Camera {
                width: 32_768,
                height: 32_768,
                ..*scene.camera()
            };
            scene.set_camera(big).unwrap();
            let vis = Backend::Bvh.build(&scene).unwrap();
            let s = meshlight::solve(&scene, vis.as_ref(), &quick(), &mut go).unwrap();
            let render = RenderOptions {
                memory_budget: usize::MAX,
                ..RenderOptions::default()
            };
            let r = meshlight::render(&scene, &s, vis.as_ref(), &render, &mut go);
            refused("render", r.map(|_| ()), &["image", "machine"]);
            let path = PathOptions {
                memory_budget: usize::MAX,
                ..PathOptions::default()
            };
            let p = path_trace(&scene, vis.as_ref(), &path, &mut go);
            refused("path trace", p.map(|_| ()), &["image", "machine"]);
            let patches = PatchOptions {
                memory_budget: usize::MAX,
                ..PatchOptions::default()
            };
            let q = patch_radiosity(&scene, vis.as_ref(), &patches, &mut go);
            refused("patches", q.map(|_| ()), &["image", "machine"]);
        },
    );
}

#[test]
fn a_path_trace_of_ten_million_samples_takes_passes_sized_by_time() {
    // spp/32 samples a pass once held 64 × 312,500 paths per worker in flight: an abort. Now
    // passes last about a quarter of a second, so the time limit and a Stop are heard.
    isolated(
        "a_path_trace_of_ten_million_samples_takes_passes_sized_by_time",
        || {
            let scene = room();
            let vis = Backend::Bvh.build(&scene).unwrap();
            let started = Instant::now();
            let timed = PathOptions {
                spp: 10_000_000,
                seconds: Some(2.0),
                ..PathOptions::default()
            };
            let image = path_trace(&scene, vis.as_ref(), &timed, &mut go).unwrap();
            assert!(image.spp >= 2 && image.spp < 10_000_000, "{}", image.spp);
            assert!(started.elapsed().as_secs_f64() < 10.0);
            let mut reports = 0;
            let asked = PathOptions {
                spp: u32::MAX,
                ..PathOptions::default()
            };
            let stopped = path_trace(&scene, vis.as_ref(), &asked, &mut |_| {
                reports += 1;
                Control::Stop
            })
            .unwrap();
            assert!(stopped.stopped && stopped.spp == 2, "{} spp", stopped.spp);
        },
    );
}

// --- Facets many sides share: the solve's first steps stay short and hear a stop. ---

/// Solves `scene` at `epsilon` (facets joined or apart), answering Stop once `stop` has passed;
/// returns the result and how long the call took.
fn stopped_solve(
    scene: &Scene,
    epsilon: f32,
    join_facets: bool,
    stop: Duration,
) -> (meshlight::Result<meshlight::Solution>, Duration) {
    let vis = Backend::Bvh.build(scene).unwrap();
    let options = Options {
        epsilon: Some(epsilon),
        join_facets,
        ..Options::default()
    };
    let start = Instant::now();
    let r = meshlight::solve(scene, vis.as_ref(), &options, &mut |_| {
        if start.elapsed() >= stop {
            Control::Stop
        } else {
            Control::Continue
        }
    });
    (r, start.elapsed())
}

#[test]
fn twenty_thousand_facets_fanned_around_one_edge_hear_a_stop_promptly() {
    isolated(
        "twenty_thousand_facets_fanned_around_one_edge_hear_a_stop_promptly",
        || {
            // Slivers 5 cm wide sharing one edge, each turned by 2π / n: every one lies in every
            // other's box, and each crosses the band over half of the others. Looking through
            // all of them for each side took 16 s before the first progress report (so before
            // a stop could be heard); now a side stops looking after a bounded number of misses.
            // Two-sided, the probes for the sides light reaches (every ray passes through every
            // sliver's box) took 165 s before the first report; now the probing reports between
            // batches of 16,384 rays (under a second each here; with batches 4 times larger a
            // stop went unheard for 9 s).
            let (positions, triangles) = fan(20_000, 0.05);
            for two_sided in [false, true] {
                let scene = scene_sided(positions.clone(), triangles.clone(), two_sided).unwrap();
                for join in [false, true] {
                    // Stopped a moment in: the two-sided probes are then under way.
                    let (r, took) = stopped_solve(&scene, 0.1, join, Duration::from_millis(300));
                    println!("fan, two-sided {two_sided}, joined {join}: stopped after {took:?}");
                    assert!(
                        took < Duration::from_secs(8),
                        "two-sided {two_sided}, joined {join}: {took:?}"
                    );
                    assert_eq!(r.unwrap().validate(), Ok(()));
                }
            }
        },
    );
}

#[test]
fn a_corrugated_sheet_of_narrow_facets_joins_in_bounded_time() {
    isolated(
        "a_corrugated_sheet_of_narrow_facets_joins_in_bounded_time",
        || {
            // 4,000 strips 1 cm wide and 4 m long, tilted ±5° in turn: one run of facets within
            // the joining cone, far beyond a piece's cap of 256 ε².
            let n = 4_000u32;
            let mut positions = Vec::new();
            let mut triangles = Vec::new();
            let mut y = 0.0f32;
            for i in 0..=n {
                let x = 0.01 * i as f32;
                positions.push(Vec3::new(x, y, 0.0));
                positions.push(Vec3::new(x, y, 4.0));
                y += if i % 2 == 0 { 0.000_87 } else { -0.000_87 };
                if i < n {
                    let k = 2 * i;
                    triangles.push([k, k + 1, k + 2]);
                    triangles.push([k + 2, k + 1, k + 3]);
                }
            }
            let scene = scene_of(positions, triangles).unwrap();
            let (r, took) = stopped_solve(&scene, 0.05, true, Duration::from_secs(2));
            println!("sheet: stopped after {took:?}");
            assert!(took < Duration::from_secs(8), "{took:?}");
            assert_eq!(r.unwrap().validate(), Ok(()));
        },
    );
}
