//! What a host passes through the public API never panics: bad arguments, a solution of
//! another scene, and a host's own `Visibility` that panics all come back as typed errors.

mod common;

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use common::shipped;
use glam::{DVec3, Vec3};
use meshlight::solver::{transfer, Control, Options};
use meshlight::visibility::{Hit, Ray, Segment};
use meshlight::{Backend, Error, Image, RenderOptions, Scene, Visibility};

fn box_scene() -> Scene {
    Scene::load(shipped("box")).unwrap()
}

fn solve(scene: &Scene) -> meshlight::Solution {
    let vis = Backend::Bvh.build(scene).unwrap();
    meshlight::solve(scene, vis.as_ref(), &Options::default(), &mut |_| {
        Control::Continue
    })
    .unwrap()
}

#[test]
fn an_image_whose_pixels_do_not_fill_it_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let image = Image {
        width: 4,
        height: 4,
        pixels: vec![Vec3::ONE; 15],
    };
    for result in [
        image.write_exr(&dir.path().join("a.exr")),
        image.write_png(&dir.path().join("a.png"), 1.0),
    ] {
        let e = result.unwrap_err();
        assert!(matches!(e, Error::Argument { .. }), "{e}");
        assert!(e.to_string().contains("15 pixels for a 4 × 4 image"), "{e}");
    }
    let empty = Image {
        width: 0,
        height: 3,
        pixels: vec![],
    };
    assert!(empty.write_exr(&dir.path().join("b.exr")).is_err());
}

#[test]
fn a_solution_of_another_scene_is_refused() {
    let (cube, room) = (box_scene(), Scene::load(shipped("room")).unwrap());
    let solution = solve(&cube);
    let vis = Backend::Bvh.build(&room).unwrap();
    let e = meshlight::render(
        &room,
        &solution,
        vis.as_ref(),
        &RenderOptions::default(),
        &mut |_| meshlight::Control::Continue,
    )
    .unwrap_err();
    assert!(
        e.to_string()
            .contains("solved for 6 surfaces, the scene has 17"),
        "{e}"
    );
    let e = transfer(&room, &solution, vis.as_ref(), &[0], DVec3::ONE).unwrap_err();
    assert!(matches!(e, Error::Argument { .. }), "{e}");

    // A solution of the same scene at another scale is refused too: every count agrees, the
    // samples do not lie on the surfaces.
    let bigger = cube.scaled(2.0).unwrap();
    let vis = Backend::Bvh.build(&bigger).unwrap();
    let e = meshlight::render(
        &bigger,
        &solution,
        vis.as_ref(),
        &RenderOptions::default(),
        &mut |_| meshlight::Control::Continue,
    )
    .unwrap_err();
    assert!(e.to_string().contains("does not lie on surface"), "{e}");
}

#[test]
fn indexes_out_of_range_are_errors() {
    let cube = box_scene();
    let solution = solve(&cube);
    let vis = Backend::Bvh.build(&cube).unwrap();
    let n = solution.samples().len() as u32;
    let e = transfer(&cube, &solution, vis.as_ref(), &[0, n], DVec3::ONE).unwrap_err();
    assert!(
        e.to_string()
            .contains(&format!("sample {n} does not exist")),
        "{e}"
    );
    let e = solution.samples().area_per_side(3).unwrap_err();
    assert!(matches!(e, Error::Argument { .. }), "{e}");
    // Enough sides: the areas add up to the cube's 6 m² (each face's area is conserved).
    let total: f64 = solution.samples().area_per_side(12).unwrap().iter().sum();
    assert!((total - 6.0).abs() < 1e-3, "{total}");
}

#[test]
fn scaling_by_nonsense_is_an_error() {
    let cube = box_scene();
    for s in [0.0, -1.0, f32::NAN, f32::INFINITY, 1e30, 1e-30] {
        let e = cube.scaled(s).unwrap_err();
        assert!(matches!(e, Error::Argument { .. }), "scale {s}: {e}");
    }
    assert!(cube.scaled(2.0).is_ok());
    for f in [-1.0, f32::NAN, f32::INFINITY] {
        let e = cube.with_lights_scaled(f).unwrap_err();
        assert!(matches!(e, Error::Argument { .. }), "light scale {f}: {e}");
    }
    let dark = cube.with_lights_scaled(0.0).unwrap();
    assert_eq!(dark.emitted_power(), DVec3::ZERO);
}

#[test]
fn shadow_ray_counts_out_of_range_are_errors() {
    let cube = box_scene();
    let vis = Backend::Bvh.build(&cube).unwrap();
    let max = meshlight::MAX_LIGHT_SAMPLES;
    for light_samples in [0, max + 1, u32::MAX] {
        let options = Options {
            light_samples,
            ..Options::default()
        };
        let e = meshlight::solve(&cube, vis.as_ref(), &options, &mut |_| Control::Continue)
            .unwrap_err();
        assert!(matches!(e, Error::Option { .. }), "{light_samples}: {e}");
    }
    let solution = solve(&cube);
    for light_samples in [0, max + 1, u32::MAX] {
        let options = RenderOptions {
            direct: meshlight::Direct::Traced { light_samples },
            ..RenderOptions::default()
        };
        let e = meshlight::render(&cube, &solution, vis.as_ref(), &options, &mut |_| {
            meshlight::Control::Continue
        })
        .unwrap_err();
        assert!(matches!(e, Error::Argument { .. }), "{light_samples}: {e}");
        let grid = meshlight::scene::Grid::new(
            "g",
            Vec3::splat(0.4),
            Vec3::X * 0.2,
            Vec3::Z * 0.2,
            Some(Vec3::Y),
            Some(0.1),
        )
        .unwrap();
        let options = meshlight::lux::LuxOptions {
            light_samples,
            ..Default::default()
        };
        let e = meshlight::lux::illuminance(
            &cube,
            &solution,
            vis.as_ref(),
            &grid,
            &options,
            &mut |_| meshlight::Control::Continue,
        )
        .unwrap_err();
        assert!(matches!(e, Error::Argument { .. }), "{light_samples}: {e}");
    }
}

/// A host's backend that panics on its `fail_at`-th call.
struct Faulty {
    inner: Box<dyn Visibility>,
    calls: AtomicU64,
    fail_at: u64,
}

impl Faulty {
    fn tick(&self) {
        if self.calls.fetch_add(1, Ordering::Relaxed) + 1 == self.fail_at {
            panic!("the host's ray caster broke on call {}", self.fail_at);
        }
    }
}

impl Visibility for Faulty {
    fn name(&self) -> &'static str {
        "faulty"
    }
    fn occluded(&self, segments: &[Segment], out: &mut [bool]) -> meshlight::Result<()> {
        self.tick();
        self.inner.occluded(segments, out)
    }
    fn intersect(&self, rays: &[Ray], out: &mut [Option<Hit>]) -> meshlight::Result<()> {
        self.tick();
        self.inner.intersect(rays, out)
    }
}

#[test]
fn a_backend_that_panics_ends_the_solve_with_an_error_not_a_hang() {
    let room = Scene::load(shipped("room")).unwrap();
    for threads in [1, 2] {
        for threshold in [0.05, 0.0] {
            let vis = Faulty {
                inner: Backend::Bvh.build(&room).unwrap(),
                calls: AtomicU64::new(0),
                fail_at: 1000,
            };
            let options = Options {
                threads,
                cluster_threshold: threshold,
                ..Options::default()
            };
            let start = Instant::now();
            let e =
                meshlight::solve(&room, &vis, &options, &mut |_| Control::Continue).unwrap_err();
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "{:?}",
                start.elapsed()
            );
            assert!(vis.calls.load(Ordering::Relaxed) >= 1000);
            // The panic is caught at the call, and the error names the backend and the call.
            let Error::Backend { backend, problem } = &e else {
                panic!("{threads} threads: {e}")
            };
            assert_eq!(*backend, vis.name());
            assert!(
                problem.contains("broke on call 1000") && problem.contains("panicked"),
                "{threads} threads: {problem}"
            );
        }
    }
    // Rendering with a backend that breaks.
    let cube = box_scene();
    let solution = solve(&cube);
    for threads in [1, 2] {
        let vis = Faulty {
            inner: Backend::Bvh.build(&cube).unwrap(),
            calls: AtomicU64::new(0),
            fail_at: 5,
        };
        let options = RenderOptions {
            threads,
            ..RenderOptions::default()
        };
        let e = meshlight::render(&cube, &solution, &vis, &options, &mut |_| {
            meshlight::Control::Continue
        })
        .unwrap_err();
        assert!(e.to_string().contains("broke on call 5"), "{e}");
    }
}
