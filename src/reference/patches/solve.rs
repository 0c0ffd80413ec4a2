//! Progressive radiosity between patch centres (Cohen, Chen, Wallace and Greenberg 1988): the
//! patch with the most unshot power shoots it to every patch it sees, with the form factor of
//! a disc of the shooter's area seen from the receiver's centre and one visibility ray between
//! centres.

use std::sync::atomic::{AtomicU8, Ordering};

use glam::DVec3;

use super::mesh::Patch;
use crate::error::Result;
use crate::parallel::for_chunks;
use crate::solver::Control;
use crate::visibility::{Segment, Visibility};

/// Receivers per parallel chunk of the point-light pass.
const CHUNK: usize = 4096;

/// Receivers per thread a shot needs before it is worth spreading over threads: below, a
/// shot takes less time than starting threads for it (measured: 9,325 patches shoot in 6.3 s
/// on one thread, 9.6 s on two).
const PARALLEL_SHOT: usize = 32_768;

/// Pair visibility is remembered in 2 bits (known, visible) per ordered pair, a row per
/// shooter so a shot reads its row in order; past this budget (bytes) rays are cast again at
/// every shot.
const MEMO_BUDGET: usize = 256 << 20;

/// Radiosity and what is still to shoot, per patch.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PatchState {
    pub radiosity: DVec3,
    pub unshot: DVec3,
}

/// What the shooting did.
pub(crate) struct Shooting {
    pub state: Vec<PatchState>,
    pub shots: u64,
    pub queries: u64,
    pub unshot_fraction: f64,
    pub stopped: bool,
}

fn luminance(c: DVec3) -> f64 {
    c.dot(DVec3::new(0.2126, 0.7152, 0.0722))
}

/// Remembers pair visibility, both ways once either is known.
struct Memo {
    bits: Vec<AtomicU8>,
    n: usize,
}

impl Memo {
    fn new(n: usize) -> Option<Memo> {
        let bytes = n.checked_mul(n)?.div_ceil(4);
        (bytes <= MEMO_BUDGET).then(|| Memo {
            bits: (0..bytes).map(|_| AtomicU8::new(0)).collect(),
            n,
        })
    }

    fn slot(&self, i: usize, j: usize) -> (usize, u32) {
        let k = i * self.n + j;
        (k / 4, (k % 4) as u32 * 2)
    }

    /// `Some(visible)` if known.
    fn get(&self, i: usize, j: usize) -> Option<bool> {
        let (byte, shift) = self.slot(i, j);
        let v = self.bits[byte].load(Ordering::Relaxed) >> shift;
        (v & 1 == 1).then_some(v & 2 == 2)
    }

    fn set(&self, i: usize, j: usize, visible: bool) {
        let v = 1u8 | if visible { 2 } else { 0 };
        for (a, b) in [(i, j), (j, i)] {
            let (byte, shift) = self.slot(a, b);
            self.bits[byte].fetch_or(v << shift, Ordering::Relaxed);
        }
    }
}

/// Direct light of point lights at every patch centre, reflected: the first radiosity.
pub(crate) fn point_lights(
    scene: &crate::scene::Scene,
    patches: &[Patch],
    state: &mut [PatchState],
    vis: &dyn Visibility,
    lift: f32,
    threads: usize,
) -> Result<u64> {
    let lights = &scene.point_sources();
    if lights.is_empty() {
        return Ok(0);
    }
    let queries = std::sync::atomic::AtomicU64::new(0);
    for_chunks(state, CHUNK, threads, |first, out| {
        let mut segments = Vec::new();
        let mut gains = Vec::new();
        for (k, _) in out.iter().enumerate() {
            let p = &patches[first + k];
            if p.kd.max_element() <= 0.0 {
                continue;
            }
            let from = p.centre + lift * p.normal;
            for light in lights {
                let to = light.position - from;
                let r2 = f64::from(to.length_squared());
                let cos = f64::from(p.normal.dot(to.normalize_or_zero()));
                if cos > 0.0 && r2 > 0.0 {
                    segments.push(Segment {
                        a: from,
                        b: light.position,
                    });
                    gains.push((k, p.kd * light.towards(-to).as_dvec3() * cos / r2));
                }
            }
        }
        let mut blocked = vec![false; segments.len()];
        vis.occluded(&segments, &mut blocked)?;
        queries.fetch_add(segments.len() as u64, Ordering::Relaxed);
        for (&(k, gain), &b) in gains.iter().zip(&blocked) {
            if !b {
                out[k].radiosity += gain;
                out[k].unshot += gain;
            }
        }
        Ok(())
    })?;
    Ok(queries.into_inner())
}

/// Shoots until the unshot power falls below `options.tolerance` × the power there was to shoot
/// at the start, or `options.max_shots`, or the host says stop; on `options.threads`.
pub(crate) fn shoot(
    patches: &[Patch],
    mut state: Vec<PatchState>,
    vis: &dyn Visibility,
    lift: f32,
    options: &super::PatchOptions,
    report: &mut dyn FnMut(u64, f64) -> Control,
) -> Result<Shooting> {
    let (threads, tolerance, max_shots) = (options.threads, options.tolerance, options.max_shots);
    let n = patches.len();
    let memo = Memo::new(n);
    let power = |s: &PatchState, p: &Patch| luminance(s.unshot) * p.area;
    let initial: f64 = state.iter().zip(patches).map(|(s, p)| power(s, p)).sum();
    let (mut shots, mut queries, mut stopped) = (0u64, 0u64, false);
    let mut fraction = if initial > 0.0 { 1.0 } else { 0.0 };
    let mut last_report = std::time::Instant::now();
    while fraction > tolerance && shots < max_shots {
        // The shooter: most unshot power; ties to the lowest index.
        let (mut best, mut best_power, mut total) = (0usize, -1.0f64, 0.0f64);
        for (i, (s, p)) in state.iter().zip(patches).enumerate() {
            let w = power(s, p);
            total += w;
            if w > best_power {
                (best, best_power) = (i, w);
            }
        }
        fraction = total / initial;
        if fraction <= tolerance {
            break;
        }
        if last_report.elapsed().as_secs_f64() > 0.1 || shots == 0 {
            last_report = std::time::Instant::now();
            if report(shots, fraction) == Control::Stop {
                stopped = true;
                break;
            }
        }
        let unshot = std::mem::take(&mut state[best].unshot);
        let cast = std::sync::atomic::AtomicU64::new(0);
        let workers = threads.min(n / PARALLEL_SHOT).max(1);
        for_chunks(&mut state, n.div_ceil(workers), workers, |first, out| {
            let Receivers {
                mut targets,
                unknown,
                segments,
            } = receivers(patches, best, first..first + out.len(), memo.as_ref(), lift);
            let mut blocked = vec![false; segments.len()];
            vis.occluded(&segments, &mut blocked)?;
            cast.fetch_add(segments.len() as u64, Ordering::Relaxed);
            for (&t, &b) in unknown.iter().zip(&blocked) {
                if let Some(m) = memo.as_ref() {
                    m.set(best, first + targets[t].0, !b);
                }
                if b {
                    targets[t].1 = 0.0;
                }
            }
            for &(k, f) in &targets {
                if f > 0.0 {
                    let gain = patches[first + k].kd * unshot * f;
                    out[k].radiosity += gain;
                    out[k].unshot += gain;
                }
            }
            Ok(())
        })?;
        queries += cast.into_inner();
        shots += 1;
    }
    if initial > 0.0 {
        fraction = state
            .iter()
            .zip(patches)
            .map(|(s, p)| power(s, p))
            .sum::<f64>()
            / initial;
    }
    Ok(Shooting {
        state,
        shots,
        queries,
        unshot_fraction: fraction,
        stopped,
    })
}

/// The patches of `range` that patch `best` shoots to: (index in the range, form factor from
/// the receiver's centre to a disc of the shooter's area); which of them still need a
/// visibility query (the memo does not know them), and those queries' segments.
fn receivers(
    patches: &[Patch],
    best: usize,
    range: std::ops::Range<usize>,
    memo: Option<&Memo>,
    lift: f32,
) -> Receivers {
    let shooter = patches[best];
    let from = shooter.centre + lift * shooter.normal;
    let mut targets: Vec<(usize, f64)> = Vec::new();
    let mut unknown: Vec<usize> = Vec::new();
    let mut segments: Vec<Segment> = Vec::new();
    for (k, j) in range.enumerate() {
        let r = &patches[j];
        if j == best || r.surface == shooter.surface || r.kd.max_element() <= 0.0 {
            continue;
        }
        let d = r.centre - shooter.centre;
        let r2 = f64::from(d.length_squared());
        if r2 <= 0.0 {
            continue;
        }
        let dir = d / r2.sqrt() as f32;
        let (cos_s, cos_r) = (
            f64::from(shooter.normal.dot(dir)),
            f64::from(-r.normal.dot(dir)),
        );
        if cos_s <= 0.0 || cos_r <= 0.0 {
            continue;
        }
        // The form factor from the receiver's centre to a disc of the shooter's area.
        let f = shooter.area * cos_s * cos_r / (std::f64::consts::PI * r2 + shooter.area);
        match memo.as_ref().and_then(|m| m.get(best, j)) {
            Some(true) => targets.push((k, f)),
            Some(false) => {}
            None => {
                unknown.push(targets.len());
                targets.push((k, f));
                segments.push(Segment {
                    a: from,
                    b: r.centre + lift * r.normal,
                });
            }
        }
    }
    Receivers {
        targets,
        unknown,
        segments,
    }
}

/// What [`receivers`] finds.
struct Receivers {
    targets: Vec<(usize, f64)>,
    unknown: Vec<usize>,
    segments: Vec<Segment>,
}
