//! Rays leaving an area light's front as its light does: from points uniform over its area, in
//! cosine-weighted directions. Where a light's power goes is then the share of these rays that
//! lands there; the scene checks (`diagnose`) and the solver's power balance both ask it.

use glam::Vec3;
use rand::RngExt;
use rand_pcg::Pcg64Mcg;

use crate::scene::Scene;
use crate::visibility::Ray;

/// `count` rays from the front of emitting `surface`, lifted off it by `lift`; none when the
/// surface has no area.
pub(crate) fn rays(
    scene: &Scene,
    surface: u32,
    count: usize,
    lift: f32,
    rng: &mut Pcg64Mcg,
) -> Vec<Ray> {
    let surface = &scene.surfaces()[surface as usize];
    let triangles =
        &scene.triangles()[surface.triangles.start as usize..surface.triangles.end as usize];
    let area: f32 = triangles.iter().map(|t| t.area).sum();
    if area <= 0.0 {
        return Vec::new();
    }
    (0..count)
        .map(|_| {
            let mut u = rng.random::<f32>() * area;
            let t = triangles
                .iter()
                .find(|t| {
                    u -= t.area;
                    u <= 0.0
                })
                .unwrap_or(&triangles[triangles.len() - 1]);
            let (a, b): (f32, f32) = (rng.random(), rng.random());
            let (a, b) = if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            };
            let [p, q, r] = t.vertices;
            let x = p + (q - p) * a + (r - p) * b;
            Ray {
                origin: x + lift * t.normal,
                dir: cosine_direction(t.normal, rng),
                t_min: 0.0,
                t_max: f32::INFINITY,
            }
        })
        .collect()
}

/// A unit direction, cosine-distributed about `n`.
fn cosine_direction(n: Vec3, rng: &mut Pcg64Mcg) -> Vec3 {
    let (u1, u2): (f32, f32) = (rng.random(), rng.random());
    crate::sampling::directions::cosine(n, u1, u2)
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;

    use super::*;
    use crate::scene::Scene;

    #[test]
    fn rays_leave_the_front_with_the_cosine_law() {
        // `room`'s ceiling panel: every origin on the panel's plane (up to the lift), every
        // direction in front, and the mean cosine 2/3 (∫cos²/∫cos over the hemisphere), to
        // within 4σ of 4,096 rays (σ of cos under the cosine law: √(1/2 − 4/9) = 0.236).
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let scene = Scene::load(root.join("scenes/room/scene.toml")).unwrap();
        let (s, _) = scene.emitters().next().unwrap();
        let t = &scene.triangles()[scene.surfaces()[s as usize].triangles.start as usize];
        let mut rng = Pcg64Mcg::seed_from_u64(7);
        let rays = rays(&scene, s, 4096, 1e-3, &mut rng);
        assert_eq!(rays.len(), 4096);
        let mut cosines = 0.0f64;
        for ray in &rays {
            let height = (ray.origin - t.vertices[0]).dot(t.normal);
            assert!(
                (height - 1e-3).abs() < 1e-4,
                "origin {height} off the plane"
            );
            let c = ray.dir.dot(t.normal);
            assert!(c >= 0.0 && (ray.dir.length() - 1.0).abs() < 1e-5);
            cosines += f64::from(c);
        }
        let mean = cosines / rays.len() as f64;
        assert!(
            (mean - 2.0 / 3.0).abs() < 4.0 * 0.236 / 64.0,
            "mean cosine {mean}"
        );
    }
}
