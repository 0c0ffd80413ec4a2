//! Adaptive samples (`docs/method.md` §6 and §17, eqs. 7-8): where a sample's radiosity differs from its
//! neighbours' by more than ζ, its influence disc is split (D ← D/√m) and new samples are
//! placed by Poisson-disk with radii interpolated from their neighbours (eq. 8).
//!
//! Decisions: the error compares luminances relative to the mean radiosity of all samples, so
//! ζ means the same whatever the scene's units or light levels. Only samples whose error
//! exceeds ζ are refined, with m_k the least count that brings e_k n_k/(n_k + m_k) below ζ,
//! i.e. m_k = ⌊n_k (e_k/ζ − 1)⌋ + 1 (the paper's ⌊n_k e_k/ζ + 1⌋, `docs/method.md` §6, drops the −n_k and adds
//! more than n_k samples even where e_k barely exceeds ζ); the m_k new samples and the sample
//! itself share its disc, so D_k ← D_k/√(m_k + 1). Radii never shrink below ε/[`MAX_SPLIT`].

use std::collections::HashMap;

use glam::{DVec3, Vec2};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::poisson::side_seed;
use super::{surface_of, Obstruction, Samples, SideIndex, SurfaceMap};
use crate::error::Result;
use crate::parallel::{for_chunks, for_chunks_reporting, Report};
use crate::visibility::Visibility;

/// Radii stop shrinking at ε / MAX_SPLIT.
pub const MAX_SPLIT: f32 = 16.0;
/// Candidate darts per new sample a refined disc asks for.
const DARTS_PER_SAMPLE: u32 = 12;

/// Luminance of linear RGB (Rec. 709 weights).
pub fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// What one refinement did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Refinement {
    /// Samples whose error exceeded ζ.
    pub refined: usize,
    /// Samples added.
    pub added: usize,
    /// Whether the sample budget stopped the addition.
    pub capped: bool,
}

/// Settings of one refinement.
#[derive(Clone, Copy, Debug)]
pub struct RefineSettings {
    /// Initial spacing ε.
    pub epsilon: f32,
    /// Relative error threshold ζ.
    pub zeta: f32,
    /// Area weight parameter α (eq. 5), used for eq. 8's weights.
    pub alpha: f32,
    /// Threads for the errors (the result does not depend on their number).
    pub threads: usize,
    /// Round number stored in new samples.
    pub round: u16,
    /// Seed.
    pub seed: u64,
    /// The total number of samples may not exceed this.
    pub max_samples: usize,
}

/// Eq. 7's error of every sample, relative to the mean luminance of `radiosity`; NaN where a
/// sample has no neighbour within 2D that it sees along its side. On up to `threads` threads;
/// `None` if `report` answered Stop.
#[allow(clippy::too_many_arguments)]
pub fn errors(
    samples: &Samples,
    maps: &[SurfaceMap],
    index: &SideIndex,
    obstruction: &Obstruction,
    vis: &dyn Visibility,
    radiosity: &[DVec3],
    threads: usize,
    report: Report,
) -> Result<Option<Vec<f64>>> {
    let n = samples.len();
    let mean = radiosity.iter().map(|&b| luminance(b)).sum::<f64>() / n.max(1) as f64;
    let mut out = vec![0.0; n];
    let error = |first: usize, chunk: &mut [f64]| {
        let mut near = Vec::new();
        for (e, k) in chunk.iter_mut().zip(first..) {
            let (side, uv, d) = (samples.side[k], samples.uv[k], samples.radius[k]);
            index.within(samples, side, uv, 2.0 * d, &mut near);
            obstruction.retain_visible(vis, maps, samples, side, samples.position[k], &mut near)?;
            let yk = luminance(radiosity[k]);
            let (mut sum, mut count) = (0.0, 0usize);
            for &(j, _) in &near {
                if j as usize != k {
                    sum += (luminance(radiosity[j as usize]) - yk).abs();
                    count += 1;
                }
            }
            *e = if count == 0 || mean <= 0.0 {
                f64::NAN
            } else {
                sum / count as f64 / mean
            };
        }
        Ok(())
    };
    let all = for_chunks_reporting(&mut out, 1024, threads, error, report)?;
    Ok(all.then_some(out))
}

/// Refines where the error exceeds ζ: shrinks those samples' radii and adds new samples
/// around them (appended to `samples`, area 0). The index must describe `samples` as given.
/// `report` hears the share of the errors computed now and then.
#[allow(clippy::too_many_arguments)]
pub fn refine(
    samples: &mut Samples,
    maps: &[SurfaceMap],
    index: &SideIndex,
    obstruction: &Obstruction,
    vis: &dyn Visibility,
    radiosity: &[DVec3],
    settings: RefineSettings,
    report: Report,
) -> Result<Refinement> {
    let Some(errors) = errors(
        samples,
        maps,
        index,
        obstruction,
        vis,
        radiosity,
        settings.threads,
        report,
    )?
    else {
        // Told to stop: nothing added.
        return Ok(Refinement::default());
    };
    let mut result = Refinement::default();
    let eps = settings.epsilon;
    let min_radius = eps / MAX_SPLIT;
    let mut near = Vec::new();
    let old = samples.len();
    // Discs to fill: (sample, old radius, count m).
    let mut discs = Vec::new();
    for (k, &e) in errors.iter().enumerate() {
        // NaN (no neighbour) never refines.
        let above = e > f64::from(settings.zeta);
        if !above || samples.radius[k] <= min_radius {
            continue;
        }
        near.clear();
        index.within(
            samples,
            samples.side[k],
            samples.uv[k],
            2.0 * samples.radius[k],
            &mut near,
        );
        let n = near.len().saturating_sub(1).max(1) as f64;
        let m = (n * (e / f64::from(settings.zeta) - 1.0)).floor().max(0.0) + 1.0;
        let old_radius = samples.radius[k];
        samples.radius[k] = (old_radius / (m as f32 + 1.0).sqrt()).max(min_radius);
        discs.push((k, old_radius, m as u32));
        result.refined += 1;
    }
    // The discs side by side (each side's in sample order), filled side by side in parallel:
    // a new sample is tested against the old samples and its own side's new ones only.
    discs.sort_by_key(|&(k, _, _)| (samples.side[k], k));
    let mut groups: Vec<std::ops::Range<usize>> = Vec::new();
    for (i, &(k, _, _)) in discs.iter().enumerate() {
        match groups.last_mut() {
            Some(g) if samples.side[discs[g.start].0] == samples.side[k] => g.end = i + 1,
            _ => groups.push(i..i + 1),
        }
    }
    let mut placed: Vec<Vec<(Vec2, f32)>> = vec![Vec::new(); groups.len()];
    let shared: &Samples = samples;
    for_chunks(&mut placed, 1, settings.threads, |g, out| {
        out[0] = fill_discs(
            shared,
            maps,
            index,
            &discs[groups[g].clone()],
            settings,
            old,
        );
        Ok(())
    })?;
    'sides: for (group, points) in groups.iter().zip(placed) {
        let side = samples.side[discs[group.start].0];
        for (p, radius) in points {
            if samples.len() >= settings.max_samples {
                result.capped = true;
                break 'sides;
            }
            samples.push(maps, side, p, radius, settings.round);
            result.added += 1;
        }
    }
    Ok(result)
}

/// Eq. 8's Poisson-disk darts in the discs of one side, in order: the new points with their
/// radii. `old` is the number of samples before this refinement.
fn fill_discs(
    samples: &Samples,
    maps: &[SurfaceMap],
    index: &SideIndex,
    discs: &[(usize, f32, u32)],
    settings: RefineSettings,
    old: usize,
) -> Vec<(Vec2, f32)> {
    let eps = settings.epsilon;
    let min_radius = eps / MAX_SPLIT;
    let cell = eps / 2.0;
    let r_weights = 2.0 * eps;
    let mut near = Vec::new();
    let mut out: Vec<(Vec2, f32)> = Vec::new();
    // The new points so far, per cell of ε/2, to test spacing against them too.
    let mut added: HashMap<(i32, i32), Vec<u32>> = HashMap::new();
    for &(k, old_radius, m) in discs {
        let side = samples.side[k];
        let map = &maps[surface_of(side) as usize];
        let centre = samples.uv[k];
        let mut rng = Pcg64Mcg::seed_from_u64(side_seed(
            settings.seed,
            k as u32,
            3 + u64::from(settings.round),
        ));
        for _ in 0..m * DARTS_PER_SAMPLE {
            // Uniform in the old disc.
            let angle = rng.random::<f32>() * std::f32::consts::TAU;
            let p = centre
                + old_radius * rng.random::<f32>().sqrt() * Vec2::new(angle.cos(), angle.sin());
            if !map.contains(p) {
                continue;
            }
            // Eq. 8: the radius here, interpolated from the samples within ε.
            index.within(samples, side, p, eps, &mut near);
            near.sort_unstable_by_key(|&(j, _)| j);
            let (mut wsum, mut dsum) = (0.0f64, 0.0f64);
            for &(j, d2) in &near {
                let w = f64::from((-settings.alpha * d2.sqrt() / r_weights).exp());
                wsum += w;
                dsum += w * f64::from(samples.radius[j as usize]);
            }
            let radius = if wsum > 0.0 {
                (dsum / wsum) as f32
            } else {
                samples.radius[k]
            };
            let radius = radius.max(min_radius);
            // Keep the dart only if no sample, old or new, lies within its radius.
            let r2 = radius * radius;
            if near.iter().any(|&(j, d2)| d2 < r2 && j < old as u32) {
                continue;
            }
            let (cx, cy) = ((p.x / cell).floor() as i32, (p.y / cell).floor() as i32);
            let reach = (radius / cell).ceil() as i32;
            let clash = (cy - reach..=cy + reach).any(|y| {
                (cx - reach..=cx + reach).any(|x| {
                    added.get(&(x, y)).is_some_and(|list| {
                        list.iter()
                            .any(|&j| out[j as usize].0.distance_squared(p) < r2)
                    })
                })
            });
            if clash {
                continue;
            }
            added.entry((cx, cy)).or_default().push(out.len() as u32);
            out.push((p, radius));
        }
    }
    out
}
