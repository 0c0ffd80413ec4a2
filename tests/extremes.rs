//! The solver at the ends of its knobs and inputs: albedo near 1, tiny and huge scales, dim and
//! blinding lights, one sample per surface, and degenerate geometry. Results stay right, or the
//! solver says why not; never a NaN.

mod common;

use common::{camera, material, shipped, Builder};
use glam::{DVec3, Vec3};
use meshlight::scene::PointLight;
use meshlight::solver::{Options, StopReason};
use meshlight::{Backend, Image, Scene, Solution};

fn solve(scene: &Scene, options: &Options) -> (Solution, Image) {
    let (solution, image) =
        common::solve_and_render(scene, Backend::default_backend(), options.clone(), true);
    assert!(
        solution.radiosity().iter().all(|b| b.is_finite()),
        "radiosity is finite"
    );
    assert!(
        image.pixels.iter().all(|p| p.is_finite()),
        "pixels are finite"
    );
    (solution, image)
}

fn relative_difference(a: &Image, b: &Image, factor: f64) -> f64 {
    let (mut diff, mut sum) = (0.0f64, 0.0f64);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        diff += (p.as_dvec3() - q.as_dvec3() * factor).abs().element_sum();
        sum += (q.as_dvec3() * factor).abs().element_sum();
    }
    diff / sum
}

#[test]
fn albedo_099_converges_to_ke_over_one_minus_rho() {
    let mut scene = Scene::load(shipped("box")).unwrap();
    {
        let mut m = scene.materials()[0].clone();
        m.kd = Vec3::splat(0.99);
        scene.set_material(0, m).unwrap();
    }
    let options = Options {
        tolerance: 1e-4,
        max_shots: Some(2_000_000),
        ..Options::default()
    };
    let (s, image) = solve(&scene, &options);
    assert_eq!(s.stop(), StopReason::Converged);
    let expected = 0.1 / (1.0 - 0.99f64);
    for b in s.radiosity() {
        let l = b.x / std::f64::consts::PI;
        assert!(
            (l - expected).abs() < 0.01 * expected,
            "sample L = {l}, expected {expected}"
        );
    }
    for p in &image.pixels {
        assert!(
            (f64::from(p.x) - expected).abs() < 0.01 * expected,
            "pixel {p}"
        );
    }
}

#[test]
fn albedo_099_with_few_shots_stops_and_says_how_much_is_left() {
    let mut scene = Scene::load(shipped("box")).unwrap();
    {
        let mut m = scene.materials()[0].clone();
        m.kd = Vec3::splat(0.99);
        scene.set_material(0, m).unwrap();
    }
    // The flat solver's shots are single samples; the hierarchy's, sweeps of all of them.
    for (threshold, shots) in [(0.0, 5_000), (Options::default().cluster_threshold, 50)] {
        let options = Options {
            max_shots: Some(shots),
            rounds: 0,
            cluster_threshold: threshold,
            ..Options::default()
        };
        let (s, _) = solve(&scene, &options);
        assert_eq!(s.stop(), StopReason::ShotLimit);
        let left = s.rounds()[0].shooting.unshot_fraction;
        assert!(
            left > options.tolerance && left.is_finite(),
            "unshot fraction {left}"
        );
        // What was shot is a lower bound: below the converged answer, above the direct light.
        let l = s.radiosity()[0].x / std::f64::consts::PI;
        assert!(l > 0.1 * 1.99 && l < 10.0, "{l}");
        // And what is left is told right: unshot radiosity U still brings ρU + ρ²U + … =
        // U·ρ/(1 − ρ), so B + 99·U (area-weighted means) is the converged π·Ke/(1 − ρ) = 10π.
        let area: f64 = s.samples().area().iter().sum();
        let mean = |v: &[glam::DVec3]| {
            v.iter()
                .zip(s.samples().area())
                .map(|(b, a)| b.x * a)
                .sum::<f64>()
                / area
        };
        let predicted = (mean(s.radiosity()) + 99.0 * mean(s.unshot())) / std::f64::consts::PI;
        assert!(
            (predicted - 10.0).abs() < 0.02 * 10.0,
            "threshold {threshold}: shot {:.3} + left {:.3} = {predicted:.3}, not 10",
            mean(s.radiosity()) / std::f64::consts::PI,
            99.0 * mean(s.unshot()) / std::f64::consts::PI
        );
    }
}

#[test]
fn brighter_walls_give_a_brighter_room() {
    let base = Scene::load(shipped("room")).unwrap();
    let white = base
        .materials()
        .iter()
        .position(|m| m.name == "white")
        .unwrap();
    let mut means = Vec::new();
    for kd in [0.725, 0.85, 0.95] {
        let mut scene = base.clone();
        {
            let mut m = scene.materials()[white].clone();
            m.kd = Vec3::splat(kd);
            scene.set_material(white, m).unwrap();
        }
        let (s, image) = solve(
            &scene,
            &Options {
                rounds: 0,
                ..Options::default()
            },
        );
        assert_eq!(s.stop(), StopReason::Converged, "kd {kd}");
        means.push(image.mean());
    }
    assert!(means[0] < means[1] && means[1] < means[2], "{means:?}");
}

#[test]
#[ignore = "full tier: a large or repeated solve (cargo test -- --include-ignored)"]
fn scaling_the_scene_leaves_the_image_alone() {
    let room = Scene::load(shipped("room")).unwrap();
    let options = Options {
        rounds: 1,
        ..Options::default()
    };
    let (_, reference) = solve(&room, &options);
    for s in [1e-3f32, 1e3] {
        let (_, image) = solve(&room.scaled(s).unwrap(), &options);
        let d = relative_difference(&image, &reference, 1.0);
        assert!(d < 1e-3, "scale {s}: MAE/mean {d}");
    }
}

#[test]
#[ignore = "full tier: a large or repeated solve (cargo test -- --include-ignored)"]
fn scaling_the_lights_scales_the_image() {
    let room = Scene::load(shipped("room")).unwrap();
    let options = Options::default();
    let (_, reference) = solve(&room, &options);
    for f in [1e-6f32, 1e6] {
        let (_, image) = solve(&room.with_lights_scaled(f).unwrap(), &options);
        let d = relative_difference(&image, &reference, f64::from(f));
        assert!(d < 1e-5, "lights × {f}: relative difference {d}");
    }
}

#[test]
#[ignore = "full tier: a large or repeated solve (cargo test -- --include-ignored)"]
fn one_sample_per_surface_still_gives_a_plausible_image() {
    let room = Scene::load(shipped("room")).unwrap();
    let (_, fine) = solve(&room, &Options::default());
    let (s, coarse) = solve(
        &room,
        &Options {
            epsilon: Some(100.0),
            rounds: 0,
            ..Options::default()
        },
    );
    // One sample per reflecting side (the light reflects nothing: no sample).
    assert_eq!(s.samples().len(), 16);
    let ratio = coarse.mean() / fine.mean();
    assert!(
        ratio > 0.5 && ratio < 2.0,
        "mean radiance {ratio} of the fine solve"
    );
}

#[test]
fn nearly_coincident_facing_samples_transfer_finitely() {
    // Two squares facing each other 1e-6 apart, a light above shining through neither: the
    // samples almost coincide across the gap.
    let mut b = Builder::default();
    let grey = b.material(material("grey", 0.7, 0.0));
    let light = b.material(material("light", 0.0, 5.0));
    b.quad(
        [
            Vec3::new(0., 0., 0.),
            Vec3::new(1., 0., 0.),
            Vec3::new(1., 1., 0.),
            Vec3::new(0., 1., 0.),
        ],
        grey,
    );
    b.quad(
        [
            Vec3::new(0., 0., 1e-6),
            Vec3::new(0., 1., 1e-6),
            Vec3::new(1., 1., 1e-6),
            Vec3::new(1., 0., 1e-6),
        ],
        grey,
    );
    b.quad(
        [
            Vec3::new(-1., -1., 2.),
            Vec3::new(-1., 2., 2.),
            Vec3::new(2., 2., 2.),
            Vec3::new(2., -1., 2.),
        ],
        light,
    );
    let scene = b.scene(camera(
        Vec3::new(0.5, 0.5, 1.5),
        Vec3::new(0.5, 0.5, 0.0),
        16,
    ));
    let (s, _) = solve(&scene, &Options::default());
    assert!(s.radiosity().iter().all(|b| b.is_finite()));
    assert!(
        s.radiosity().iter().any(|b| b.x > 0.0),
        "the upper face is lit"
    );
}

#[test]
fn degenerate_geometry_is_survived() {
    let mut b = Builder::default();
    let grey = b.material(material("grey", 0.6, 0.0));
    let red = b.material(material("red", 0.6, 0.0));
    // A room, a needle triangle, a zero-area triangle, a duplicated face, a z-fighting face of
    // another material, a fin sharing an edge with two other faces (non-manifold).
    b.room(Vec3::ZERO, Vec3::splat(2.0), grey, &[]);
    let m = &mut b.mesh;
    let base = m.positions.len() as u32;
    m.positions.extend([
        Vec3::new(0.2, 0.5, 0.2),
        Vec3::new(1.8, 0.5, 0.2),
        Vec3::new(1.0, 0.5, 0.200_01), // needle
        Vec3::new(0.5, 1.0, 0.5),
        Vec3::new(0.6, 1.0, 0.5),
        Vec3::new(0.7, 1.0, 0.5), // zero area
    ]);
    m.triangles
        .extend([[base, base + 1, base + 2], [base + 3, base + 4, base + 5]]);
    m.triangle_materials.extend([grey, grey]);
    let floor = [
        Vec3::new(0.5, 0.0, 0.5),
        Vec3::new(0.5, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 0.5),
    ];
    b.quad(floor, grey); // duplicates part of the floor's plane, same facing
    b.quad(floor, red); // coincident with it, another material
    b.quad(
        [
            Vec3::new(1.0, 0.0, 0.5),
            Vec3::new(1.0, 0.5, 0.5),
            Vec3::new(1.0, 0.5, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
        ],
        grey,
    );
    b.point_lights.push(PointLight {
        position: Vec3::new(1.0, 1.8, 1.0),
        intensity: Vec3::splat(2.0),
    });
    let scene = b.scene(camera(
        Vec3::new(1.0, 1.5, 0.1),
        Vec3::new(1.0, 0.5, 1.5),
        32,
    ));
    assert!(
        scene
            .warnings()
            .iter()
            .any(|w| w.contains("dropped 1 zero-area triangle")),
        "{:?}",
        scene.warnings()
    );
    let (s, image) = solve(&scene, &Options::default());
    assert_eq!(s.stop(), StopReason::Converged);
    assert!(image.mean() > 0.0);
}

#[test]
fn a_lone_triangle_and_a_light_with_nothing_to_light() {
    let mut b = Builder::default();
    let grey = b.material(material("grey", 0.5, 0.0));
    let m = &mut b.mesh;
    m.positions.extend([Vec3::ZERO, Vec3::X, Vec3::Y]);
    m.triangles.push([0, 1, 2]);
    m.triangle_materials.push(grey);
    // Behind the triangle (it faces +z): lights nothing.
    b.point_lights.push(PointLight {
        position: Vec3::new(0.2, 0.2, -1.0),
        intensity: Vec3::splat(3.0),
    });
    let scene = b.scene(camera(
        Vec3::new(0.3, 0.3, 2.0),
        Vec3::new(0.3, 0.3, 0.0),
        16,
    ));
    let (s, image) = solve(&scene, &Options::default());
    assert!(s.radiosity().iter().all(|b| *b == DVec3::ZERO));
    assert_eq!(image.mean(), 0.0);
    // The light's power all escapes.
    assert!((s.ledger().escaped.x - s.ledger().emitted.x).abs() < 1e-9 * s.ledger().emitted.x);
}

#[test]
fn a_scene_without_light_renders_black() {
    let room = Scene::load(shipped("room"))
        .unwrap()
        .with_lights_scaled(0.0)
        .unwrap();
    let (s, image) = solve(&room, &Options::default());
    assert_eq!(s.stop(), StopReason::NoLight);
    assert!(image.pixels.iter().all(|p| *p == Vec3::ZERO));
}
