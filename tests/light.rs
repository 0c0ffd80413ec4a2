//! The direct-light estimator in a penumbra: unbiased, and steadier than independent rays.

mod common;

use common::{backends, material, Builder};
use glam::Vec3;
use meshlight::lux::{illuminance, LuxOptions};
use meshlight::scene::Grid;
use meshlight::solver::{Control, Options};
use meshlight::Scene;

#[test]
fn half_a_light_hidden_gives_half_its_light_with_little_spread() {
    // A 2 × 2 m panel at height 2 facing down; a black sheet at height 1 over x > 0. From any
    // receiver on the line x = 0 of the floor, the sheet's edge projects onto x = 0 of the
    // panel: exactly the half x < 0 is in sight, and by symmetry it sends half the light.
    let mut b = Builder::default();
    let lamp = b.material(material("lamp", 0.0, 1.0));
    let black = b.material(material("black", 0.0, 0.0));
    let floor = b.material(material("floor", 0.5, 0.0));
    b.quad(
        [
            Vec3::new(-1.0, 2.0, -1.0),
            Vec3::new(1.0, 2.0, -1.0),
            Vec3::new(1.0, 2.0, 1.0),
            Vec3::new(-1.0, 2.0, 1.0),
        ],
        lamp,
    );
    b.quad(
        [
            Vec3::new(0.0, 1.0, -5.0),
            Vec3::new(5.0, 1.0, -5.0),
            Vec3::new(5.0, 1.0, 5.0),
            Vec3::new(0.0, 1.0, 5.0),
        ],
        black,
    );
    b.quad(
        [
            Vec3::new(-3.0, 0.0, -3.0),
            Vec3::new(-3.0, 0.0, 3.0),
            Vec3::new(3.0, 0.0, 3.0),
            Vec3::new(3.0, 0.0, -3.0),
        ],
        floor,
    );
    let with_sheet = b.scene(common::camera(Vec3::new(0.0, 0.5, -4.0), Vec3::ZERO, 8));
    // The same scene without the sheet: the estimator is exact there (polygon irradiance × a
    // visible share of 1), and with the same seeds the ratio is the visible share.
    let mut open = Builder::default();
    let lamp = open.material(material("lamp", 0.0, 1.0));
    let floor = open.material(material("floor", 0.5, 0.0));
    open.quad(
        [
            Vec3::new(-1.0, 2.0, -1.0),
            Vec3::new(1.0, 2.0, -1.0),
            Vec3::new(1.0, 2.0, 1.0),
            Vec3::new(-1.0, 2.0, 1.0),
        ],
        lamp,
    );
    open.quad(
        [
            Vec3::new(-3.0, 0.0, -3.0),
            Vec3::new(-3.0, 0.0, 3.0),
            Vec3::new(3.0, 0.0, 3.0),
            Vec3::new(3.0, 0.0, -3.0),
        ],
        floor,
    );
    let open = open.scene(common::camera(Vec3::new(0.0, 0.5, -4.0), Vec3::ZERO, 8));
    let rays = 16;
    // 400 receivers along x = 0 on the floor, facing up, each with its own shadow rays. The
    // floor is behind them, so they measure the direct light alone.
    let grid = Grid::new(
        "x = 0",
        Vec3::new(-0.5e-4, 0.0, -0.5),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1e-4, 0.0, 0.0),
        Some(Vec3::Y),
        Some(1.0 / 400.0),
    )
    .unwrap();
    assert_eq!(grid.counts_uv(), (400, 1));
    let lux = LuxOptions {
        light_samples: rays,
        seed: 7,
        threads: 2,
        ..LuxOptions::default()
    };
    for backend in backends() {
        let measure = |scene: &Scene| {
            let vis = backend.build(scene).unwrap();
            let options = Options {
                rounds: 0,
                ..Options::default()
            };
            let s = meshlight::solve(scene, vis.as_ref(), &options, &mut |_| Control::Continue)
                .unwrap();
            illuminance(scene, &s, vis.as_ref(), &grid, &lux, &mut |_| {
                Control::Continue
            })
            .unwrap()
            .values
        };
        let (hidden, full) = (measure(&with_sheet), measure(&open));
        let visible: Vec<f64> = hidden.iter().zip(&full).map(|(h, f)| h.x / f.x).collect();
        let n = visible.len() as f64;
        let mean = visible.iter().sum::<f64>() / n;
        let rms = (visible.iter().map(|v| (v - 0.5).powi(2)).sum::<f64>() / n).sqrt();
        // Independent rays would spread by √(p(1−p)/N) = 0.125 and leave the mean of 400
        // within 3 × 0.125/20 ≈ 0.019; the estimator must do at least twice as well on both.
        let independent = (0.25f64 / f64::from(rays)).sqrt();
        assert!(
            (mean - 0.5).abs() < 0.5 * 3.0 * independent / 20.0,
            "{backend}: mean {mean}"
        );
        assert!(rms < 0.5 * independent, "{backend}: spread {rms}");
    }
}

#[test]
fn a_furnace_with_boxes_standing_in_it_is_at_its_analytic_radiance() {
    // A closed 4 × 3 × 4 m room with two boxes on its floor (the `cornell` layout), every face
    // Kd 0.95 and Ke 0.05: every surface seen is at L = Ke / (1 − Kd) = 1, whatever the
    // shadows. Each wall is an emitter beside the floor it meets, so a receiver near an edge
    // has most of its light from a few square centimetres: shadow rays drawn uniformly over
    // an emitter's area gave the ratio estimator a denominator so uneven that the visible
    // share fell short (Jensen's inequality): this view was 0.21% dark (0.16-0.26% at 128²,
    // seeds 1-4); drawn over solid angle, 0.04% (within 0.02% at 128²).
    let mut b = Builder::default();
    let grey = b.material(material("grey", 0.95, 0.05));
    b.room(Vec3::ZERO, Vec3::new(4.0, 3.0, 4.0), grey, &[]);
    for (lo, hi) in [
        (Vec3::new(0.8, 0.0, 2.2), Vec3::new(1.8, 1.8, 3.2)),
        (Vec3::new(2.3, 0.0, 0.9), Vec3::new(3.2, 0.9, 1.8)),
    ] {
        // A box without a bottom, faces out: it stands on the floor.
        let first = b.mesh.triangles.len();
        b.room(lo, hi, grey, &["-y"]);
        for t in &mut b.mesh.triangles[first..] {
            t.swap(1, 2);
        }
    }
    let scene = b.scene(common::camera(
        Vec3::new(2.0, 1.5, 0.05),
        Vec3::new(2.0, 1.4, 4.0),
        64,
    ));
    for backend in backends() {
        let (_, image) = common::solve_and_render(&scene, backend, Options::default(), true);
        let mean = image.mean();
        assert!((mean - 1.0).abs() < 8e-4, "{backend}: mean radiance {mean}");
    }
}
