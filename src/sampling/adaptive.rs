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
use super::{surface_of, Layout, Samples};
use crate::error::Result;
use crate::exec::Exec;
use crate::parallel::{for_chunks, Report};
use crate::progress::Control;
use crate::visibility::Visibility;

/// Radii stop shrinking at ε / MAX_SPLIT.
pub const MAX_SPLIT: f32 = 16.0;
/// Candidate darts per new sample a refined disc asks for.
const DARTS_PER_SAMPLE: u32 = 12;
/// The same, for counting darts.
const DARTS: u64 = DARTS_PER_SAMPLE as u64;
/// Darts a side throws between two reports, about (a disc is never split).
const PIECE_DARTS: u64 = 200_000;

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
    /// Relative error threshold ζ.
    pub zeta: f32,
    /// Area weight parameter α (eq. 5), used for eq. 8's weights.
    pub alpha: f32,
    /// Round number stored in new samples.
    pub round: u16,
    /// The total number of samples may not exceed this.
    pub max_samples: usize,
}

/// Eq. 7's error of every sample, relative to the mean luminance of `radiosity`; NaN where a
/// sample has no neighbour within 2D that it sees along its side. Each rank measures a run of
/// the samples; `None` if `report` answered Stop (on any rank).
pub(crate) fn errors(
    samples: &Samples,
    layout: &Layout,
    vis: &dyn Visibility,
    radiosity: &[DVec3],
    exec: Exec,
    report: Report,
) -> Result<Option<Vec<f64>>> {
    let (maps, index, obstruction) = (layout.maps(), layout.index(), layout.obstruction());
    let n = samples.len();
    let mean = radiosity.iter().map(|&b| luminance(b)).sum::<f64>() / n.max(1) as f64;
    let mut out = vec![0.0; n];
    let error = |first: usize, chunk: &mut [f64], halt: &crate::parallel::Halt| {
        let mut near = Vec::new();
        for (e, k) in chunk.iter_mut().zip(first..) {
            // A slow backend's chunk takes seconds; after a Stop the errors are not read.
            if halt.asked() {
                return Ok(());
            }
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
    let all = exec.for_share(
        &mut out,
        1024,
        error,
        report,
        // Across ranks "no neighbour" travels as −1: a transport carries finite numbers
        // (`distributed::Checked` refuses others).
        |&e| [if e.is_nan() { -1.0 } else { e }],
        |v| if v[0] < 0.0 { f64::NAN } else { v[0] },
    )?;
    if !all {
        return Ok(None);
    }
    Ok(Some(out))
}

/// Refines where the error exceeds ζ: shrinks those samples' radii and adds new samples
/// around them (appended to `samples`, area 0). The index must describe `samples` as given.
/// `report` hears the share of the errors computed now and then.
pub(crate) fn refine(
    samples: &mut Samples,
    layout: &Layout,
    vis: &dyn Visibility,
    radiosity: &[DVec3],
    settings: RefineSettings,
    exec: Exec,
    report: Report,
) -> Result<Refinement> {
    let (maps, ranks) = (layout.maps(), exec.ranks);
    // The errors take the first half of the phase's share, the darts the second.
    let Some(errors) = errors(samples, layout, vis, radiosity, exec, &mut |f| {
        report(0.5 * f)
    })?
    else {
        // Told to stop: nothing added.
        return Ok(Refinement::default());
    };
    let mut result = Refinement::default();
    let old = samples.len();
    let mut discs = discs_to_fill(samples, layout, &errors, settings);
    result.refined = discs.len();
    // The discs side by side (each side's in sample order), filled side by side in parallel:
    // a new sample is tested against the old samples and its own side's new ones only.
    discs.sort_by_key(|&(k, _, _)| (samples.side[k], k));
    let groups = sides_of(&discs, samples);
    // Each side's discs in pieces of about PIECE_DARTS darts, every side's next piece at once,
    // with a report between: a tiny ζ throws millions of darts, and the host must hear from
    // the call and may stop it. A side's darts go in the same order whatever the pieces, so
    // the samples are the same as in one pass.
    let total_darts: u64 = discs.iter().map(|d| u64::from(d.2) * DARTS).sum();
    let mut placed: Vec<Vec<(Vec2, f32)>> = vec![Vec::new(); groups.len()];
    let mut next: Vec<usize> = groups.iter().map(|g| g.start).collect();
    let mut thrown = 0u64;
    let shared: &Samples = samples;
    loop {
        let pieces = pieces_after(&groups, &next, &discs);
        if pieces.iter().all(|p| p.is_empty()) {
            break;
        }
        let mut work: Vec<(usize, &mut Vec<(Vec2, f32)>)> = placed.iter_mut().enumerate().collect();
        for_chunks(&mut work, 1, exec.threads, |_, out| {
            let (g, points) = &mut out[0];
            if !crate::distributed::deals(ranks, *g) {
                // Another rank's side.
                return Ok(());
            }
            let piece = &discs[pieces[*g].clone()];
            if !piece.is_empty() {
                fill_discs(shared, layout, piece, settings, exec.seed, old, points);
            }
            Ok(())
        })?;
        for (g, piece) in pieces.iter().enumerate() {
            thrown += discs[piece.clone()]
                .iter()
                .map(|d| u64::from(d.2) * DARTS)
                .sum::<u64>();
            next[g] = piece.end;
        }
        let more = next.iter().zip(&groups).any(|(&n, g)| n < g.end);
        if more
            && crate::distributed::any(
                ranks,
                report(0.5 + 0.5 * thrown as f64 / total_darts.max(1) as f64) == Control::Stop,
            )?
        {
            // The discs not filled keep their radii: as if they had not been refined.
            for (g, &from) in groups.iter().zip(&next) {
                for &(k, old_radius, _) in &discs[from..g.end] {
                    samples.radius[k] = old_radius;
                    result.refined -= 1;
                }
            }
            break;
        }
    }
    if next.iter().zip(&groups).all(|(&n, g)| n == g.end) {
        report(1.0);
    }
    crate::distributed::share_lists(
        ranks,
        &mut placed,
        |(p, r)| [p.x, p.y, *r].map(f64::from),
        |v| (Vec2::new(v[0] as f32, v[1] as f32), v[2] as f32),
    )?;
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

/// The samples whose error exceeds ζ, as discs to fill with new samples: (sample, its old
/// radius, how many new ones); their radii shrink to make room.
fn discs_to_fill(
    samples: &mut Samples,
    layout: &Layout,
    errors: &[f64],
    settings: RefineSettings,
) -> Vec<(usize, f32, u32)> {
    let (index, min_radius) = (layout.index(), layout.epsilon() / MAX_SPLIT);
    let mut near = Vec::new();
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
        let old_radius = samples.radius[k];
        // Darts for at most four times what the disc holds at the smallest radius: points at
        // least r apart in a disc of radius R number at most (2R / r + 1)² (their r/2-discs
        // are disjoint inside the disc grown by r/2). Past that, darts are only thrown away,
        // and a tiny ζ would throw billions of them with no report between. (At once what it
        // holds, the gallery lost 110 of 46,260 samples: more darts fill a disc more densely;
        // at four times, every shipped scene places the same samples as without a cap.)
        let holds = (2.0 * f64::from(old_radius / min_radius) + 1.0).powi(2);
        let wanted = (n * (e / f64::from(settings.zeta) - 1.0)).floor().max(0.0) + 1.0;
        let m = wanted.min(4.0 * holds);
        samples.radius[k] = (old_radius / (m as f32 + 1.0).sqrt()).max(min_radius);
        discs.push((k, old_radius, m as u32));
    }
    discs
}

/// The runs of `discs` (sorted by side) that lie on one side each.
fn sides_of(discs: &[(usize, f32, u32)], samples: &Samples) -> Vec<std::ops::Range<usize>> {
    let mut groups: Vec<std::ops::Range<usize>> = Vec::new();
    for (i, &(k, _, _)) in discs.iter().enumerate() {
        match groups.last_mut() {
            Some(g) if samples.side[discs[g.start].0] == samples.side[k] => g.end = i + 1,
            _ => groups.push(i..i + 1),
        }
    }
    groups
}

/// Each side's next piece of discs, from `next`: about PIECE_DARTS darts (a disc is never
/// split).
fn pieces_after(
    groups: &[std::ops::Range<usize>],
    next: &[usize],
    discs: &[(usize, f32, u32)],
) -> Vec<std::ops::Range<usize>> {
    groups
        .iter()
        .zip(next)
        .map(|(g, &from)| {
            let mut to = from;
            let mut darts = 0;
            while to < g.end && (to == from || darts < PIECE_DARTS) {
                darts += u64::from(discs[to].2) * DARTS;
                to += 1;
            }
            from..to
        })
        .collect()
}

/// Eq. 8's Poisson-disk darts in the discs of one side, in order: the new points with their
/// radii, appended to `out` (which holds the points the side's earlier discs placed). `old` is
/// the number of samples before this refinement.
fn fill_discs(
    samples: &Samples,
    layout: &Layout,
    discs: &[(usize, f32, u32)],
    settings: RefineSettings,
    seed: u64,
    old: usize,
    out: &mut Vec<(Vec2, f32)>,
) {
    let (maps, index) = (layout.maps(), layout.index());
    let eps = layout.epsilon();
    let min_radius = eps / MAX_SPLIT;
    let cell = eps / 2.0;
    let r_weights = 2.0 * eps;
    let mut near = Vec::new();
    // The new points so far, per cell of ε/2, to test spacing against them too.
    let mut added: HashMap<(i32, i32), Vec<u32>> = HashMap::new();
    for (i, (p, _)) in out.iter().enumerate() {
        let cell_of = ((p.x / cell).floor() as i32, (p.y / cell).floor() as i32);
        added.entry(cell_of).or_default().push(i as u32);
    }
    for &(k, old_radius, m) in discs {
        let side = samples.side[k];
        let map = &maps[surface_of(side) as usize];
        let centre = samples.uv[k];
        let mut rng =
            Pcg64Mcg::seed_from_u64(side_seed(seed, k as u32, 3 + u64::from(settings.round)));
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
}
