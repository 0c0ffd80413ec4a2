//! The CIE 171:2006-style case that checks inter-reflection as a whole: in a closed room whose
//! every surface has the same reflectance ρ, lit by sources of total flux Φ, the area-weighted
//! mean irradiance over all surfaces is Φ / (S (1 − ρ)), whatever the room's shape and wherever
//! the light is (the light arriving at the surfaces is Φ, then ρΦ, ρ²Φ, …). The other cases —
//! a point source over a plane, a luminaire aimed down and tilted, an area source over a
//! plane — are in `tests/solver.rs` and `tests/luminaires.rs`; docs/validation.md lists them all.

mod common;

use common::{backends, camera, material, solve, Builder};
use glam::Vec3;
use meshlight::scene::PointLight;
use meshlight::Options;

#[test]
fn a_closed_room_of_uniform_reflectance_receives_flux_over_s_times_one_minus_rho() {
    for rho in [0.5f32, 0.8] {
        // An L-shaped room would do as well; a 4 × 3 × 5 box with a pillar standing in it keeps
        // some surfaces in shadow. The lamp is off centre.
        let mut b = Builder::default();
        let wall = b.material(material("wall", rho, 0.0));
        let (lo, hi) = (Vec3::ZERO, Vec3::new(4.0, 3.0, 5.0));
        b.room(lo, hi, wall, &[]);
        // The room's faces point inwards; the pillar's outwards: its box built inside out.
        b.room(
            Vec3::new(2.6, 3.0, 2.0),
            Vec3::new(3.2, 0.0, 2.6),
            wall,
            &["-y", "+y"],
        );
        let intensity = 25.0f32;
        b.point_lights.push(PointLight {
            position: Vec3::new(1.0, 2.2, 1.5),
            intensity: Vec3::splat(intensity),
        });
        let scene = b.scene(camera(
            Vec3::new(2.0, 1.5, 0.2),
            Vec3::new(2.0, 1.5, 5.0),
            8,
        ));
        let area: f64 = scene.surfaces().iter().map(|s| s.area).sum();
        // S: the room's 94 m² and the pillar's four sides 0.6 × 3 (the test's own check).
        let s_by_hand = 2.0 * (4.0 * 3.0 + 4.0 * 5.0 + 3.0 * 5.0) + 4.0 * 0.6 * 3.0;
        assert!((area - s_by_hand).abs() < 1e-3, "{area} vs {s_by_hand}");
        let flux = 4.0 * std::f64::consts::PI * f64::from(intensity);
        let want = flux / (area * (1.0 - f64::from(rho)));
        for backend in backends() {
            let options = Options {
                tolerance: 1e-5,
                ..Options::default()
            };
            let s = solve(&scene, backend, options);
            let mean = (0..s.samples().len())
                .map(|k| s.irradiance()[k].y * s.samples().area()[k])
                .sum::<f64>()
                / s.samples().area().iter().sum::<f64>();
            let error = mean / want - 1.0;
            eprintln!(
                "ρ {rho}, {backend}: mean irradiance {mean:.5} vs Φ/(S(1 − ρ)) {want:.5}: {:+.2}%",
                100.0 * error
            );
            assert!(error.abs() < 0.02, "ρ {rho}, {backend}: {mean} vs {want}");
        }
    }
}
