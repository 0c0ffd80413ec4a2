//! Warm starts: after adaptive rounds add samples and areas are recomputed, the light already
//! shot is taken to be the old samples' shot radiosity (R − ΔB) spread over the new areas: old
//! samples keep their unshot ΔB; a new sample gets its exact direct light plus indirect light
//! interpolated from its old neighbours, and its unshot radiosity is the difference between
//! that and the shot radiosity interpolated at its place. Shooting then only carries the
//! corrections the new samples bring (mostly sharper direct light), not the whole solution
//! again. Where the round links its samples, the interpolated indirect light is only a
//! stand-in: the shooters gather each new sample's own before they shoot (see [`Regather`]).

use glam::DVec3;

use super::Solution;
use crate::error::Result;
use crate::light::Arrival;
use crate::sampling::{is_back, surface_of, Samples};
use crate::scene::Scene;
use crate::visibility::Visibility;

/// Diffuse reflectance of sample k: its surface's Kd, or on a textured surface the texture's
/// mean over its area.
pub(crate) fn reflectance(scene: &Scene, samples: &Samples, k: usize) -> DVec3 {
    match samples.reflectance.get(k) {
        Some(rho) => rho.as_dvec3(),
        None => scene.material_of(surface_of(samples.side[k])).kd.as_dvec3(),
    }
}

/// Emitted radiosity π·Ke of sample k (emitters emit from their front only).
pub(crate) fn emission(scene: &Scene, samples: &Samples, k: usize) -> DVec3 {
    let side = samples.side[k];
    if is_back(side) {
        return DVec3::ZERO;
    }
    std::f64::consts::PI * scene.material_of(surface_of(side)).ke.as_dvec3()
}

/// Sample k's light that is exact at it but not its direct light: from the lights by way of
/// specular surfaces (by glossy bounces, through chains of images, the photons') and the
/// daylight entering (0 without either).
pub(crate) fn exact_beyond_direct(solution: &Solution, k: usize) -> DVec3 {
    let daylight = solution.field.daylight.get(k).copied().unwrap_or_default();
    daylight
        + solution.specular.as_ref().map_or(DVec3::ZERO, |t| {
            [&t.direct, &t.far, &t.caustic]
                .iter()
                .map(|v| v.get(k).copied().unwrap_or_default())
                .sum()
        })
}

/// A round's new samples, whose inter-reflected light the warm start interpolated from their
/// old neighbours: the solvers gather each one's own from the light every sample has shot so
/// far (the radiosity it reflects, less what it has not shot), along the same form factors
/// and visibility the shots take, and put it in place of the interpolated light, the
/// difference joining the sample's unshot radiosity. Interpolated, a sample added beside
/// something that hides part of the room from it (the strip of a pedestal's top a sculpture
/// overhangs, a wall just under a picture frame) only ever had its neighbours' light, however
/// many samples a round added there.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Regather<'a> {
    /// The first new sample (they run to the end).
    pub first: usize,
    /// Each new sample's inter-reflected irradiance as the warm start interpolated it.
    pub interpolated: &'a [DVec3],
}

impl Regather<'_> {
    /// Puts sample k's gathered inter-reflected irradiance in place of the one its warm start
    /// interpolated (an old sample keeps its own).
    pub(crate) fn apply(
        &self,
        irradiance: &mut [DVec3],
        unshot: &mut [DVec3],
        reflectance: &[DVec3],
        k: usize,
        gathered: DVec3,
    ) {
        if k >= self.first {
            let change = gathered - self.interpolated[k - self.first];
            irradiance[k] += change;
            unshot[k] += reflectance[k] * change;
        }
    }
}

/// The radiosity each sample has shot so far (what it reflects, less what it has not shot):
/// what a [`Regather`] gathers.
pub(crate) fn shot(irradiance: &[DVec3], unshot: &[DVec3], reflectance: &[DVec3]) -> Vec<DVec3> {
    (0..irradiance.len())
        .map(|k| reflectance[k] * irradiance[k] - unshot[k])
        .collect()
}

/// Extends the solution's per-sample arrays to the new samples `first_new..` and sets their
/// unshot radiosity for a (warm) start: see the module doc. Each rank a run of the new samples.
/// Returns each new sample's interpolated inter-reflected irradiance (for a [`Regather`]).
pub(crate) fn start(
    scene: &Scene,
    solution: &mut Solution,
    vis: &dyn Visibility,
    first_new: usize,
    arrivals: &[Arrival],
    alpha: f32,
    exec: crate::exec::Exec,
) -> Result<Vec<DVec3>> {
    let n = solution.field.samples.len();
    let epsilon = solution.field.layout.epsilon();
    // (irradiance, unshot, radiosity, interpolated indirect irradiance) of each new sample.
    let mut out = vec![(DVec3::ZERO, DVec3::ZERO, DVec3::ZERO, DVec3::ZERO); n - first_new];
    let shared: &Solution = solution;
    let each = |first: usize, chunk: &mut [(DVec3, DVec3, DVec3, DVec3)]| {
        let samples = &shared.field.samples;
        let mut near = Vec::new();
        let r = 2.0 * epsilon;
        for (o, k) in chunk.iter_mut().zip(first_new + first..) {
            let rho = reflectance(scene, samples, k);
            // Interpolated from the old samples: indirect irradiance, and radiosity already shot.
            let (mut wsum, mut indirect, mut shot) = (0.0, DVec3::ZERO, DVec3::ZERO);
            if first_new > 0 {
                shared.field.layout.index().within(
                    samples,
                    samples.side[k],
                    samples.uv[k],
                    r,
                    &mut near,
                );
                near.retain(|&(j, _)| (j as usize) < first_new);
                near.sort_unstable_by_key(|&(j, _)| j);
                shared.field.layout.obstruction().retain_visible(
                    vis,
                    shared.field.layout.maps(),
                    samples,
                    samples.side[k],
                    samples.position[k],
                    &mut near,
                )?;
                // Neighbours covered as this sample is, if there are any (`sampling::cover`).
                let covered = shared.field.layout.covered();
                if near.iter().any(|&(j, _)| covered[j as usize] == covered[k]) {
                    near.retain(|&(j, _)| covered[j as usize] == covered[k]);
                }
                for &(j, d2) in &near {
                    let j = j as usize;
                    let w = f64::from((-alpha * d2.sqrt() / r).exp());
                    wsum += w;
                    // What is exact at the new sample (its direct light, and the lights' light
                    // by way of glossy bounces) is not interpolated.
                    let exact = shared.field.direct[j].irradiance + exact_beyond_direct(shared, j);
                    indirect += w * (shared.field.irradiance[j] - exact);
                    shot += w * (rho * shared.field.irradiance[j] - shared.unshot[j]);
                }
            }
            if wsum > 0.0 {
                indirect /= wsum;
                shot /= wsum;
            }
            let h = arrivals[k - first_new].irradiance + indirect + exact_beyond_direct(shared, k);
            *o = (
                h,
                rho * h - shot,
                emission(scene, samples, k) + rho * h,
                indirect,
            );
        }
        Ok(())
    };
    // Each rank a run of the new samples.
    exec.for_share(
        &mut out,
        256,
        |first, out, _: &_| each(first, out),
        &mut |_| crate::progress::Control::Continue,
        |(h, u, b, i)| [h.x, h.y, h.z, u.x, u.y, u.z, b.x, b.y, b.z, i.x, i.y, i.z],
        |v| {
            (
                DVec3::new(v[0], v[1], v[2]),
                DVec3::new(v[3], v[4], v[5]),
                DVec3::new(v[6], v[7], v[8]),
                DVec3::new(v[9], v[10], v[11]),
            )
        },
    )?;
    // Exactly: a round's new samples would leave up to as many slots unused.
    solution.field.direct.reserve_exact(arrivals.len());
    solution.field.irradiance.reserve_exact(out.len());
    solution.unshot.reserve_exact(out.len());
    solution.field.radiosity.reserve_exact(out.len());
    solution.field.direct.extend_from_slice(arrivals);
    let mut interpolated = Vec::with_capacity(out.len());
    for (h, unshot, radiosity, indirect) in out {
        solution.field.irradiance.push(h);
        solution.unshot.push(unshot);
        solution.field.radiosity.push(radiosity);
        interpolated.push(indirect);
    }
    debug_assert_eq!(solution.field.irradiance.len(), n);
    Ok(interpolated)
}
