//! The direct-light estimator in a penumbra: unbiased, and steadier than independent rays.

mod common;

use common::{backends, material, Builder};
use glam::Vec3;
use meshlight::light::DirectLight;

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
    let scene = b.scene(common::camera(Vec3::new(0.0, 0.5, -4.0), Vec3::ZERO, 8));
    let rays = 16;
    let light = DirectLight::new(&scene, rays);
    // 400 receivers along x = 0, each with its own shadow rays.
    let points: Vec<(Vec3, Vec3)> = (0..400)
        .map(|i| (Vec3::new(0.0, 0.0, -0.5 + i as f32 / 400.0), Vec3::Y))
        .collect();
    let ids: Vec<u32> = (0..400).collect();
    for backend in backends() {
        let vis = backend.build(&scene).unwrap();
        let (arrivals, _) = light
            .at(vis.as_ref(), &points, &ids, 7, 2, &mut |_| {})
            .unwrap();
        let n = arrivals.len() as f64;
        let mean = arrivals.iter().map(|a| f64::from(a.visible)).sum::<f64>() / n;
        let rms = (arrivals
            .iter()
            .map(|a| (f64::from(a.visible) - 0.5).powi(2))
            .sum::<f64>()
            / n)
            .sqrt();
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
