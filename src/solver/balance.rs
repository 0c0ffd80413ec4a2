//! The direct light's power balance (`docs/method.md` §11). In a scene closed around its area
//! lights every watt they emit lands on a surface, so the samples' direct light, summed over
//! their areas, must add up to the emitted power. Measured at the sample points it falls
//! short: a sample by an edge sits on its region's rim, where the light is weaker than over the
//! region (Σ S·E was 0.19% short on `cornell`, 0.05% on `room`), and the shortfall read as light
//! leaving the scene. Where the lights see only surfaces, the direct light is scaled to balance,
//! as the row scales balance each receiver's form factors.

use glam::DVec3;
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

use crate::error::Result;
use crate::light::leaving;
use crate::scene::Scene;
use crate::visibility::Visibility;

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
    exec: crate::exec::Exec,
) -> Result<bool> {
    let (seed, lift) = (exec.seed, crate::visibility::lift(scene));
    if !scene.point_sources().is_empty() || scene.emitters().next().is_none() {
        return Ok(false);
    }
    let mut rays = Vec::new();
    for (s, _) in scene.emitters() {
        let mut rng = Pcg64Mcg::seed_from_u64(seed ^ (0x6261_6c61_6e63_6500 + u64::from(s)));
        rays.extend(leaving::rays(scene, s, RAYS_PER_LIGHT, lift, &mut rng));
    }
    let hits = crate::visibility::intersect_all(vis, &rays, exec.threads)?;
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
