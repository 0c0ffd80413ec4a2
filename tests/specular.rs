//! Specular reflection and transmission against answers known without the solver: mirror images
//! of lights, a glass slab's and a pane's transmittance, and the furnace with specular faces.

mod common;

use common::{backends, camera, glass, material, specular, Builder};
use glam::{DVec3, Vec3};
use meshlight::lux::{illuminance, LuxOptions};
use meshlight::scene::{Grid, PointLight};
use meshlight::solver::{Control, Options};
use meshlight::Scene;

/// Illuminance at a grid's points (direct + inter-reflected), solved on `backend`.
fn lux(scene: &Scene, backend: meshlight::Backend, grid: &Grid) -> Vec<DVec3> {
    let vis = backend.build(scene).unwrap();
    let options = Options {
        rounds: 0,
        ..Options::default()
    };
    let s = meshlight::solve(scene, vis.as_ref(), &options, &mut |_| Control::Continue).unwrap();
    illuminance(
        scene,
        &s,
        vis.as_ref(),
        grid,
        &LuxOptions::default(),
        &mut |_| Control::Continue,
    )
    .unwrap()
    .values
}

/// A small square grid of 3 × 3 points centred at `centre`, facing `normal`.
fn grid(centre: Vec3, normal: Vec3) -> Grid {
    Grid::new(
        "g",
        centre - Vec3::new(0.3, 0.0, 0.3),
        Vec3::new(0.6, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 0.6),
        Some(normal),
        Some(0.2),
    )
    .unwrap()
}

#[test]
fn a_point_light_over_a_mirror_lights_a_grid_from_above_and_from_its_image_below() {
    // A 40 × 40 m mirror (Ks 0.8) at y = 0 facing up, a point light of 10 W/sr at y = 3: a grid
    // at y = 1 facing up sees the light at distance 2; facing down it sees the light's image at
    // y = −3, distance 4, through the mirror: 0.8 × 10 × cos/4².
    let mut b = Builder::default();
    let m = b.material(specular("mirror", 0.0, 0.8, 0.0));
    b.quad(
        [
            Vec3::new(-20.0, 0.0, -20.0),
            Vec3::new(-20.0, 0.0, 20.0),
            Vec3::new(20.0, 0.0, 20.0),
            Vec3::new(20.0, 0.0, -20.0),
        ],
        m,
    );
    b.point_lights.push(PointLight {
        position: Vec3::new(0.0, 3.0, 0.0),
        intensity: Vec3::splat(10.0),
    });
    let scene = b.scene(camera(Vec3::new(0.0, 2.0, -6.0), Vec3::ZERO, 8));
    for backend in backends() {
        let up = grid(Vec3::new(0.0, 1.0, 0.0), Vec3::Y);
        let down = grid(Vec3::new(0.0, 1.0, 0.0), Vec3::NEG_Y);
        let (e_up, e_down) = (lux(&scene, backend, &up), lux(&scene, backend, &down));
        for (i, p) in up.points().iter().enumerate() {
            let to_light = Vec3::new(0.0, 3.0, 0.0) - *p;
            let expected = 10.0 * f64::from(to_light.y / to_light.length().powi(3));
            assert!(
                (e_up[i].x / expected - 1.0).abs() < 5e-3,
                "{backend}: up at {p}: {} vs {expected}",
                e_up[i].x
            );
            let to_image = Vec3::new(0.0, -3.0, 0.0) - *p;
            let expected = 0.8 * 10.0 * f64::from(-to_image.y / to_image.length().powi(3));
            assert!(
                (e_down[i].x / expected - 1.0).abs() < 5e-3,
                "{backend}: down at {p}: {} vs {expected}",
                e_down[i].x
            );
        }
    }
}

#[test]
fn a_glass_slab_and_a_pane_pass_one_minus_r_over_one_plus_r_at_normal_incidence() {
    // A point light 3 m over a grid facing up; 1 m over the grid, a 6 × 6 m slab of glass
    // (Ni 1.5, 2 cm thick, faces pointing out), or a pane of one face. At normal incidence
    // R = ((n − 1)/(n + 1))² = 0.04 and the slab passes (1 − R)² / (1 − R²) = (1 − R)/(1 + R)
    // of the unobstructed I/r², its internal bounces summed; the pane the same.
    for thin in [false, true] {
        let mut b = Builder::default();
        let g = b.material(glass("glass", 1.5, thin));
        let (lo, hi) = (Vec3::new(-3.0, 0.99, -3.0), Vec3::new(3.0, 1.01, 3.0));
        if thin {
            b.quad(
                [
                    Vec3::new(-3.0, 1.0, -3.0),
                    Vec3::new(-3.0, 1.0, 3.0),
                    Vec3::new(3.0, 1.0, 3.0),
                    Vec3::new(3.0, 1.0, -3.0),
                ],
                g,
            );
        } else {
            b.solid(lo, hi, g);
        }
        // A dark floor far below, so the scene has something to sample.
        let floor = b.material(material("floor", 0.0, 0.0));
        b.quad(
            [
                Vec3::new(-5.0, -5.0, -5.0),
                Vec3::new(-5.0, -5.0, 5.0),
                Vec3::new(5.0, -5.0, 5.0),
                Vec3::new(5.0, -5.0, -5.0),
            ],
            floor,
        );
        b.point_lights.push(PointLight {
            position: Vec3::new(0.0, 3.0, 0.0),
            intensity: Vec3::splat(10.0),
        });
        let scene = b.scene(camera(Vec3::new(0.0, 2.0, -6.0), Vec3::ZERO, 8));
        for backend in backends() {
            let g = grid(Vec3::ZERO, Vec3::Y);
            let e = lux(&scene, backend, &g);
            let centre = e[4].x;
            let r = 0.04f64;
            let expected = (1.0 - r) / (1.0 + r) * 10.0 / 9.0;
            assert!(
                (centre / expected - 1.0).abs() < 5e-3,
                "{backend}, thin {thin}: {centre} vs {expected}"
            );
        }
    }
}
