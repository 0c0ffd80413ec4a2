//! The direct light's power balance (`docs/method.md` §11). In a scene closed around its area
//! lights every watt they emit lands on a surface, so the samples' direct light, summed over
//! their areas, must add up to the emitted power. Measured at the sample points it falls
//! short: a sample by an edge sits on its region's rim, where the light is weaker than over the
//! region (Σ S·E was 0.19% short on `cornell`, 0.05% on `room`), and the shortfall read as light
//! leaving the scene. Where the lights see only surfaces, the direct light is scaled to balance,
//! as the row scales balance each receiver's form factors.

use glam::{DVec3, Vec3};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use crate::error::Result;
use crate::scene::Scene;
use crate::visibility::{Ray, Visibility};

/// Rays traced from each area light to see whether any of its light leaves the scene.
pub(super) const RAYS_PER_LIGHT: usize = 1024;

/// A balance further than this from 1 is not a discretisation's: it is left alone (light
/// leaving through a gap the rays missed, say).
pub(super) const MAX_CORRECTION: f64 = 0.02;

/// Whether every ray from every area light, leaving its front in a cosine-weighted
/// direction, meets a surface: the lights' power then all lands in the scene. False for a scene
/// with point lights or luminaires (their light is not balanced here) or without lights.
pub(super) fn closed_to_the_lights(
    scene: &Scene,
    vis: &dyn Visibility,
    lift: f32,
    (seed, threads): (u64, usize),
) -> Result<bool> {
    if !scene.point_sources().is_empty() || scene.emitters().next().is_none() {
        return Ok(false);
    }
    let mut rays = Vec::new();
    for (s, _) in scene.emitters() {
        let surface = &scene.surfaces[s as usize];
        let triangles =
            &scene.triangles[surface.triangles.start as usize..surface.triangles.end as usize];
        let total: f32 = triangles.iter().map(|t| t.area).sum();
        if total <= 0.0 {
            continue;
        }
        let n = surface.normal;
        let (u, v) = n.any_orthonormal_pair();
        let mut rng = Pcg64Mcg::seed_from_u64(seed ^ (0x6261_6c61_6e63_6500 + u64::from(s)));
        for _ in 0..RAYS_PER_LIGHT {
            // A point uniform over the light's area, a direction cosine-weighted about its normal.
            let mut pick = rng.random::<f32>() * total;
            let t = triangles
                .iter()
                .find(|t| {
                    pick -= t.area;
                    pick <= 0.0
                })
                .unwrap_or(&triangles[triangles.len() - 1]);
            let (r1, r2) = (rng.random::<f32>().sqrt(), rng.random::<f32>());
            let [a, b, c] = t.vertices;
            let p = a * (1.0 - r1) + b * (r1 * (1.0 - r2)) + c * (r1 * r2);
            let (x1, x2) = (rng.random::<f32>(), rng.random::<f32>());
            let (r, phi) = (x1.sqrt(), std::f32::consts::TAU * x2);
            let dir: Vec3 =
                u * (r * phi.cos()) + v * (r * phi.sin()) + n * (1.0 - x1).max(0.0).sqrt();
            rays.push(Ray {
                origin: p + lift * n,
                dir,
                t_min: 0.0,
                t_max: f32::INFINITY,
            });
        }
    }
    let hits = crate::visibility::intersect_all(vis, &rays, threads)?;
    Ok(hits.iter().all(Option::is_some))
}

/// The scale per channel that makes the direct light the samples `received` (Σ S·E) add up to
/// the power `emitted`; 1 in a channel that received nothing, and in all if any channel would
/// move by more than [`MAX_CORRECTION`].
pub(super) fn scale(received: DVec3, emitted: DVec3) -> DVec3 {
    let mut out = DVec3::ONE;
    for c in 0..3 {
        if received[c] > 0.0 && emitted[c] > 0.0 {
            out[c] = emitted[c] / received[c];
            if (out[c] - 1.0).abs() > MAX_CORRECTION {
                return DVec3::ONE;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_shortfall_is_made_up_and_a_large_one_left_alone() {
        let s = scale(DVec3::new(0.998, 1.0, 0.0), DVec3::new(1.0, 1.0, 0.0));
        assert!((s.x - 1.0 / 0.998).abs() < 1e-12 && s.y == 1.0 && s.z == 1.0);
        assert_eq!(scale(DVec3::splat(0.95), DVec3::ONE), DVec3::ONE);
        assert_eq!(scale(DVec3::new(1.0, 0.95, 1.0), DVec3::ONE), DVec3::ONE);
    }
}
