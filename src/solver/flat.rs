//! The flat solver: progressive radiosity between samples (`docs/method.md` §5 and §14, after Cohen et al.
//! 1988): repeatedly shoot the sample with the largest unshot power to every sample it can
//! see. Every shooter is linked to every receiver, so a solve is O(N²); the cluster hierarchy
//! (`cluster`) is what scales. It stays as the exact reference the hierarchy is checked
//! against, and as `--cluster-threshold 0`.
//!
//! Row normalisation (see `normalise`): the first solve computes every shooter's form factors
//! up front, for every receiver's row sum. New samples of later rounds take the scale of their
//! nearest old sample.
//!
//! Jobs of fixed receiver ranges go through the pipeline; the coordinator applies the results
//! in range order, so the answer is bit-identical for any thread count.
//!
//! A sample is usually shot several times before the unshot power converges; the visible
//! receivers and form factors of each shooter are kept (up to a memory budget) so that only
//! its first shot in a solve pays for visibility. And once a sample has shot, which samples
//! see it is known: a later shooter reads its visibility to that sample from a bit matrix
//! instead of asking again, so each pair is queried once, not twice. The bit matrix counts
//! against the same budget.

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use crate::error::Result;
use crate::sampling::Samples;
use crate::visibility::Visibility;

use super::form_factor::{segment, Shooter};
use super::normalise::row_scale;
use super::pipeline::with_pool;
use super::shooting::{nothing_to_shoot, unshot_power, Settings, State, Tick};
use super::stats::{ShootStats, StopReason};
use super::warm::{self, Regather};
use crate::progress::Control;

/// Visibility already known: row j holds, once sample j has shot, which samples see it.
/// Written by the coordinator between shots, read by workers during them (the channel hand-off
/// orders the two), hence relaxed atomics.
struct Memo {
    n: usize,
    shot: Vec<AtomicBool>,
    bits: Vec<AtomicU64>,
}

impl Memo {
    fn bytes(n: usize) -> usize {
        (n * n).div_ceil(64) * 8 + n
    }

    fn new(n: usize) -> Memo {
        let words = (n * n).div_ceil(64);
        Memo {
            n,
            shot: (0..n).map(|_| AtomicBool::new(false)).collect(),
            bits: (0..words).map(|_| AtomicU64::new(0)).collect(),
        }
    }

    /// Whether i sees j, if i has shot (then its row is complete).
    fn get(&self, i: usize, j: usize) -> Option<bool> {
        if !self.shot[i].load(Ordering::Relaxed) {
            return None;
        }
        let bit = i * self.n + j;
        Some(self.bits[bit / 64].load(Ordering::Relaxed) & (1 << (bit % 64)) != 0)
    }

    fn record(&self, j: usize, visible: &[(u32, f32)]) {
        for &(i, _) in visible {
            let bit = j * self.n + i as usize;
            self.bits[bit / 64].fetch_or(1 << (bit % 64), Ordering::Relaxed);
        }
        self.shot[j].store(true, Ordering::Relaxed);
    }
}

/// A shooter's visible receivers with their form factors.
type List = Box<[(u32, f32)]>;

/// A list kept for later shots, with Σ F·S over it.
type Kept = (List, f64);

struct Job {
    range: std::ops::Range<usize>,
    shooter: Shooter,
}

struct Done {
    /// (receiver, form factor) of every visible receiver in the range.
    factors: Vec<(u32, f32)>,
    queries: u64,
}

/// Shoots until converged, out of shots, or told to stop; `report` hears every few shots.
pub(crate) fn shoot(
    state: &mut State,
    vis: &dyn Visibility,
    settings: &Settings,
    report: &mut dyn FnMut(Tick) -> Control,
) -> Result<ShootStats> {
    if let Some(stats) = nothing_to_shoot(state) {
        return Ok(stats);
    }
    let samples = state.samples;
    let n = samples.len();
    let mut stats = ShootStats::new();
    let threads = settings.exec.threads;
    let chunk = n.div_ceil(4 * threads).max(512);
    // The bit matrix is worth it within half the memory budget only.
    let memo_bytes = Memo::bytes(n);
    let memo = (memo_bytes <= settings.memory_bytes / 2).then(|| Memo::new(n));
    let memo = memo.as_ref();
    let ranges: Vec<std::ops::Range<usize>> = (0..n)
        .step_by(chunk)
        .map(|a| a..(a + chunk).min(n))
        .collect();
    let lift = settings.lift;
    let work = |job: Job| factors(samples, vis, lift, job.shooter, job.range, memo);
    // Every range of one shooter in flight at once, as before the pipeline existed.
    let capacity = settings.capacity.min(ranges.len()).max(1);
    with_pool(threads, capacity, &work, |pool| {
        // One shooter's visible receivers and form factors, range by range, in receiver order.
        let mut compute = |j: usize| -> Result<(List, u64)> {
            let shooter = Shooter::of(samples, state.maps, j);
            let mut list = Vec::new();
            let mut queries = 0;
            pool.run_all(
                ranges.iter().map(|range| Job {
                    range: range.clone(),
                    shooter,
                }),
                |_, done| {
                    list.extend_from_slice(&done.factors);
                    queries += done.queries;
                    Ok(())
                },
            )?;
            if let Some(memo) = memo {
                memo.record(j, &list);
            }
            Ok((list.into_boxed_slice(), queries))
        };
        let memo_held = if memo.is_some() { memo_bytes } else { 0 };
        let mut cache = Cache {
            lists: vec![None; n],
            left: settings.memory_bytes.saturating_sub(memo_held),
            held: memo_held,
        };
        if settings.normalise
            && normalise_rows(state, &mut compute, &mut cache, &mut stats, report)?.is_break()
        {
            stats.stop = StopReason::Stopped;
            return Ok(stats);
        }
        if let Some(regather) = state.regather {
            stats.queries += gather_new(state, vis, lift, regather, threads)?;
        }
        shots(
            state,
            &mut compute,
            &mut cache,
            settings,
            &mut stats,
            report,
        )?;
        stats.bytes = cache.held as u64;
        Ok(stats)
    })
}

/// What a shooter's form factors come from: computed on demand, `(list, queries)`.
type Compute<'a> = dyn FnMut(usize) -> Result<(List, u64)> + 'a;

/// Shooters' form factors kept for their later shots, within what the budget leaves.
struct Cache {
    /// Per shooter: its visible receivers with (row-scaled) form factors, and Σ F·S.
    lists: Vec<Option<Kept>>,
    /// Bytes still free for lists.
    left: usize,
    /// Bytes held (lists and the visibility memo).
    held: usize,
}

impl Cache {
    /// Whether a list of `bytes` fits; if so it is counted as held.
    fn take(&mut self, bytes: usize) -> bool {
        let fits = bytes <= self.left;
        if fits {
            self.left -= bytes;
            self.held += bytes;
        }
        fits
    }
}

/// Σ F·S over a shooter's receivers: the flux its unit radiosity delivers.
fn delivered_by(samples: &Samples, list: &[(u32, f32)]) -> f64 {
    list.iter()
        .map(|&(i, f)| f64::from(f) * samples.area[i as usize])
        .sum()
}

/// Every receiver's row sum Σⱼ Fᵢⱼ from every shooter's list, and the row scales from them
/// (see `normalise`); the lists that fit are kept, scaled. Whether the host let it finish.
fn normalise_rows(
    state: &mut State,
    compute: &mut Compute,
    cache: &mut Cache,
    stats: &mut ShootStats,
    report: &mut dyn FnMut(Tick) -> Control,
) -> Result<ControlFlow<()>> {
    let n = state.samples.len();
    let mut sums = vec![0.0f64; n];
    for j in 0..n {
        if j % 256 == 0 && report(Tick::linking(j as f64 / n as f64)) == Control::Stop {
            return Ok(ControlFlow::Break(()));
        }
        let (list, queries) = compute(j)?;
        stats.queries += queries;
        for &(i, f) in list.iter() {
            sums[i as usize] += f64::from(f);
        }
        if cache.take(std::mem::size_of_val(&*list)) {
            cache.lists[j] = Some((list, 0.0));
        }
    }
    for (i, scale) in state.row_scale.iter_mut().enumerate() {
        *scale = row_scale(sums[i], state.closed[i], state.dark_emitters[i]);
    }
    for kept in cache.lists.iter_mut().flatten() {
        for (i, f) in kept.0.iter_mut() {
            *f *= state.row_scale[*i as usize];
        }
        kept.1 = delivered_by(state.samples, &kept.0);
    }
    Ok(ControlFlow::Continue(()))
}

/// Progressive shooting (Southwell): the sample of largest unshot power shoots, until the
/// unshot power is below the tolerance, the shots run out, or the host stops.
fn shots(
    state: &mut State,
    compute: &mut Compute,
    cache: &mut Cache,
    settings: &Settings,
    stats: &mut ShootStats,
    report: &mut dyn FnMut(Tick) -> Control,
) -> Result<()> {
    let samples = state.samples;
    let n = samples.len();
    let emitted = state.ledger.emitted.element_sum();
    let mut first = true;
    // Unshot power per sample, kept up to date as shots land: the shooter search is then
    // one pass over a flat array.
    let mut power: Vec<f64> = (0..n)
        .map(|k| unshot_power(state.unshot[k], samples.area[k]))
        .collect();
    loop {
        // The shooter: largest unshot power (lowest index on ties).
        let mut total = 0.0;
        let mut best = (0.0, usize::MAX);
        for (k, &p) in power.iter().enumerate() {
            total += p;
            if p > best.0 {
                best = (p, k);
            }
        }
        stats.unshot_fraction = total / emitted;
        if stats.unshot_fraction.is_nan() || stats.unshot_fraction >= 1e6 {
            stats.stop = StopReason::Diverged;
            break;
        }
        if first {
            stats.initial_unshot_fraction = stats.unshot_fraction;
            first = false;
        }
        if stats.unshot_fraction < settings.tolerance || best.1 == usize::MAX {
            stats.stop = StopReason::Converged;
            break;
        }
        if stats.shots >= settings.max_shots {
            stats.stop = StopReason::ShotLimit;
            break;
        }
        if stats.shots % 32 == 0
            && report(Tick::shooting(
                stats.shots,
                stats.unshot_fraction,
                stats.initial_unshot_fraction,
                settings.tolerance,
            )) == Control::Stop
        {
            stats.stop = StopReason::Stopped;
            break;
        }
        let j = best.1;

        // This shooter's form factors, unless they are kept from before.
        let mut keep = true;
        if cache.lists[j].is_none() {
            let (mut list, queries) = compute(j)?;
            stats.queries += queries;
            for (i, f) in list.iter_mut() {
                *f *= state.row_scale[*i as usize];
            }
            let delivered = delivered_by(samples, &list);
            // Over budget, the list serves this shot only.
            keep = cache.take(std::mem::size_of_val(&*list));
            cache.lists[j] = Some((list, delivered));
        } else {
            stats.cached_shots += 1;
        }
        let (list, delivered) = cache.lists[j].as_ref().expect("filled above");

        let db = state.unshot[j];
        for &(i, f) in list.iter() {
            let h = db * f64::from(f);
            let i = i as usize;
            state.irradiance[i] += h;
            state.unshot[i] += state.reflectance[i] * h;
            power[i] = unshot_power(state.unshot[i], samples.area[i]);
        }
        state.ledger.escaped += db * (samples.area[j] - delivered);
        if !keep {
            cache.lists[j] = None;
        }
        state.unshot[j] = glam::DVec3::ZERO;
        power[j] = 0.0;
        // And by way of specular surfaces: G's column of the shooter (which may reach the
        // shooter itself, in a mirror).
        if let Some(g) = state.specular {
            for (i, w) in g.column(j) {
                let h = db * w;
                state.irradiance[i] += h;
                state.unshot[i] += state.reflectance[i] * h;
                power[i] = unshot_power(state.unshot[i], samples.area[i]);
            }
            state.ledger.escaped -= db * g.column_flux[j];
        }
        stats.shots += 1;
    }
    Ok(())
}

/// Each new sample's own inter-reflected light (`warm::Regather`): the light every sample has
/// shot so far (`warm::shot`), through the form factors and rays its shots take, row-scaled as
/// they are, and by way of specular surfaces. The visibility queries.
fn gather_new(
    state: &mut State,
    vis: &dyn Visibility,
    lift: f32,
    regather: Regather,
    threads: usize,
) -> Result<u64> {
    let samples = state.samples;
    let shot = warm::shot(state.irradiance, state.unshot, state.reflectance);
    let shooters: Vec<Shooter> = (0..samples.len())
        .filter(|&j| shot[j] != glam::DVec3::ZERO)
        .map(|j| Shooter::of(samples, state.maps, j))
        .collect();
    let row_scale: &[f32] = state.row_scale;
    let mut gathered = vec![(glam::DVec3::ZERO, 0u64); samples.len() - regather.first];
    crate::parallel::for_chunks(&mut gathered, 64, threads, |first, chunk| {
        let (mut segments, mut found, mut blocked) = (Vec::new(), Vec::new(), Vec::new());
        for (out, k) in chunk.iter_mut().zip(regather.first + first..) {
            segments.clear();
            found.clear();
            for shooter in &shooters {
                let j = shooter.index as usize;
                if j == k {
                    continue;
                }
                if let Some(f) = shooter.factor_to(samples, k) {
                    segments.push(segment(samples, lift, j, k));
                    found.push((j, f));
                }
            }
            blocked.clear();
            blocked.resize(segments.len(), false);
            vis.occluded(&segments, &mut blocked)?;
            let mut h = glam::DVec3::ZERO;
            for (&(j, f), &blocked) in found.iter().zip(&blocked) {
                if !blocked {
                    h += shot[j] * f64::from(f);
                }
            }
            *out = (h * f64::from(row_scale[k]), segments.len() as u64);
        }
        Ok(())
    })?;
    let mut queries = 0;
    for (k, &(h, q)) in (regather.first..).zip(&gathered) {
        let through = state
            .specular
            .map_or(glam::DVec3::ZERO, |g| g.row_times(k, &shot));
        regather.apply(
            state.irradiance,
            state.unshot,
            state.reflectance,
            k,
            h + through,
        );
        queries += q;
    }
    Ok(queries)
}

/// Form factors from every sample that sees sample `j` to `j`'s region: (receiver, F).
pub(crate) fn form_factors(
    samples: &Samples,
    maps: &[crate::sampling::SurfaceMap],
    vis: &dyn Visibility,
    lift: f32,
    j: usize,
) -> Result<Vec<(u32, f32)>> {
    let shooter = Shooter::of(samples, maps, j);
    Ok(factors(samples, vis, lift, shooter, 0..samples.len(), None)?.factors)
}

/// Form factors from every visible receiver in `range` to the shooter's region.
fn factors(
    samples: &Samples,
    vis: &dyn Visibility,
    lift: f32,
    shooter: Shooter,
    range: std::ops::Range<usize>,
    memo: Option<&Memo>,
) -> Result<Done> {
    let mut candidates = Vec::new();
    let mut known = Vec::new();
    let mut segments = Vec::new();
    let j = shooter.index as usize;
    for i in range {
        if i == j {
            continue;
        }
        let Some(f) = shooter.factor_to(samples, i) else {
            continue;
        };
        let memory = memo.and_then(|m| m.get(i, j));
        if memory.is_none() {
            segments.push(segment(samples, lift, j, i));
        }
        known.push(memory);
        candidates.push((i as u32, f));
    }
    let mut blocked = vec![false; segments.len()];
    vis.occluded(&segments, &mut blocked)?;
    let mut answers = blocked.into_iter();
    let mut factors = Vec::with_capacity(candidates.len());
    for (c, memory) in candidates.into_iter().zip(known) {
        let visible = memory.unwrap_or_else(|| !answers.next().unwrap_or(true));
        if visible {
            factors.push(c);
        }
    }
    Ok(Done {
        factors,
        queries: segments.len() as u64,
    })
}
