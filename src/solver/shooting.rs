//! Progressive radiosity between samples (method.md §5, after Cohen et al. 1988): repeatedly
//! shoot the sample with the largest unshot power to every sample it can see.
//!
//! The form factor from receiver i to shooter j is the point form cosθᵢ cosθⱼ Sⱼ / (π r²) for
//! r ≥ 4√Sⱼ; nearer, it is integrated over j's shares of the area cells, exactly (Lambert's
//! formula) for the nearest cells, so it stays finite as r → 0. A point-to-disc form
//! cosθᵢ cosθⱼ Sⱼ / (π r² + Sⱼ) for all pairs lost 18% of the inter-reflected light at the edges
//! of the furnace cube, and 2% of the form factor of perpendicular squares; the shares of all
//! samples tile the surfaces, so each receiver's form factors sum to the part of its
//! hemisphere they cover. Pairs where either cosine is ≤ 0 cost no visibility query. Positions
//! are the centroids of the samples' regions: a sample's radiosity is its region's average.
//!
//! Row normalisation: at albedo ρ a relative error δ in a receiver's Σⱼ Fᵢⱼ becomes an error
//! of about ρδ/(1 − ρ) in its radiance (100δ at ρ = 0.99). The first solve therefore computes
//! every shooter's form factors up front and scales each receiver's row: to sum to exactly 1
//! where all probe rays from the receiver hit the scene (a closed hemisphere), and to at most 1
//! elsewhere. Rows summing to at most 1 also make the iteration a contraction for any ρ < 1,
//! so energy can never build up. New samples of later rounds take the scale of their nearest
//! old sample.
//!
//! Workers (scoped threads fed over bounded crossbeam channels) compute the form factors and
//! batched visibility of fixed receiver ranges; the coordinator applies the results in range
//! order. Every receiver's increment is computed the same way whatever the thread count, so
//! the answer is bit-identical for 1 or many threads.
//!
//! A sample is usually shot several times before the unshot power converges; the visible
//! receivers and form factors of each shooter are kept (up to a memory budget) so that only
//! its first shot in a solve pays for visibility. And once a sample has shot, which samples
//! see it is known: a later shooter reads its visibility to that sample from a bit matrix
//! instead of asking again, so each pair is queried once, not twice.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use crossbeam_channel::{bounded, Receiver, Sender};
use glam::{DVec3, Vec3};

use crate::error::Result;
use crate::sampling::{Samples, SurfaceMap};
use crate::visibility::{Segment, Visibility};

/// Why a solve stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum StopReason {
    /// Unshot power fell below the tolerance.
    Converged,
    /// The shot limit was reached first.
    ShotLimit,
    /// The progress callback asked to stop.
    Stopped,
    /// The scene emits no light: nothing to shoot.
    NoLight,
    /// Unshot power grew instead of shrinking (it cannot with rows summing to at most 1 and
    /// reflectances below 1; this guards the image against infinities all the same).
    Diverged,
}

/// The host's answer to a progress report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Control {
    /// Go on.
    Continue,
    /// Stop at the next shot or round boundary; the current estimate is kept.
    Stop,
}

/// Where the light's energy went (W, RGB), kept as the solver runs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergyLedger {
    /// Power emitted by all lights.
    pub emitted: DVec3,
    /// Power that left the scene: direct light that hit no sample area, and the part of each
    /// shot its form factors did not deliver.
    pub escaped: DVec3,
}

/// The solver state that shooting changes.
pub(crate) struct State<'a> {
    pub samples: &'a Samples,
    pub maps: &'a [SurfaceMap],
    pub reflectance: &'a [DVec3],
    /// Irradiance received at each sample (direct + shot so far).
    pub irradiance: &'a mut [DVec3],
    /// Unshot radiosity ΔB.
    pub unshot: &'a mut [DVec3],
    pub ledger: &'a mut EnergyLedger,
    /// Per receiver, the factor its form factors are scaled by (see the module doc); filled by
    /// the prepass when `Settings::prepass` is set.
    pub row_scale: &'a mut [f32],
    /// Per receiver, whether every probe ray from it hit the scene.
    pub closed: &'a [bool],
}

/// Settings of one solve.
pub(crate) struct Settings {
    pub threads: usize,
    pub tolerance: f64,
    pub max_shots: u64,
    pub lift: f32,
    /// Bytes the form-factor cache may hold.
    pub cache_bytes: usize,
    /// Compute every shooter's form factors first, for the receivers' row sums.
    pub prepass: bool,
}

/// What one solve did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShootStats {
    /// Shots made.
    pub shots: u64,
    /// Visibility queries made.
    pub queries: u64,
    /// Unshot power / emitted power at the start.
    pub initial_unshot_fraction: f64,
    /// Unshot power / emitted power at the end.
    pub unshot_fraction: f64,
    /// Shots answered from the form-factor cache.
    pub cached_shots: u64,
    /// Why it stopped.
    pub stop: StopReason,
}

/// Visibility already known: row j holds, once sample j has shot, which samples see it.
/// Written by the coordinator between shots, read by workers during them (the channel hand-off
/// orders the two), hence relaxed atomics.
struct Memo {
    n: usize,
    shot: Vec<AtomicBool>,
    bits: Vec<AtomicU64>,
}

impl Memo {
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

/// A shooter as the workers see it.
#[derive(Clone, Copy)]
struct Shooter {
    index: u32,
    position: Vec3,
    centroid: Vec3,
    normal: Vec3,
    area: f32,
    /// Axes of its surface's plane (for its cells' squares).
    u: Vec3,
    v: Vec3,
}

/// Receivers nearer than this many √S of the shooter are integrated over its shares of cells.
const NEAR: f32 = 4.0;

impl Shooter {
    fn of(samples: &Samples, maps: &[SurfaceMap], j: usize) -> Shooter {
        let map = &maps[crate::sampling::surface_of(samples.side[j]) as usize];
        Shooter {
            index: j as u32,
            position: samples.position[j],
            centroid: samples.centroid[j],
            normal: samples.normal[j],
            area: samples.area[j] as f32,
            u: map.u,
            v: map.v,
        }
    }
}

struct Job {
    range: std::ops::Range<usize>,
    order: usize,
    shooter: Shooter,
}

struct Done {
    order: usize,
    /// (receiver, form factor) of every visible receiver in the range.
    factors: Vec<(u32, f32)>,
    queries: u64,
}

/// Unshot power of sample k (all channels, absolute: warm starts may leave negative unshot).
fn unshot_power(unshot: DVec3, area: f64) -> f64 {
    unshot.abs().element_sum() * area
}

/// Shoots until converged, out of shots, or told to stop. `report(shots, unshot fraction)` is
/// called every few shots.
pub(crate) fn shoot(
    state: &mut State,
    vis: &dyn Visibility,
    settings: &Settings,
    report: &mut dyn FnMut(u64, f64) -> Control,
) -> Result<ShootStats> {
    let samples = state.samples;
    let n = samples.len();
    let emitted = state.ledger.emitted.element_sum();
    let mut stats = ShootStats {
        shots: 0,
        queries: 0,
        initial_unshot_fraction: 0.0,
        unshot_fraction: 0.0,
        cached_shots: 0,
        stop: StopReason::Converged,
    };
    if emitted <= 0.0 || n == 0 {
        stats.stop = StopReason::NoLight;
        return Ok(stats);
    }
    let threads = settings.threads.max(1);
    let chunk = n.div_ceil(4 * threads).max(512);
    // The bit matrix costs n²/8 bytes: within half the cache budget only.
    let memo = ((n * n) / 8 <= settings.cache_bytes / 2).then(|| Memo::new(n));
    let memo = memo.as_ref();
    let ranges: Vec<std::ops::Range<usize>> = (0..n)
        .step_by(chunk)
        .map(|a| a..(a + chunk).min(n))
        .collect();

    std::thread::scope(|scope| -> Result<ShootStats> {
        // Workers only when there is more than one thread and more than one range.
        let pool = if threads > 1 && ranges.len() > 1 {
            let (job_tx, job_rx) = bounded::<Job>(2 * ranges.len());
            let (done_tx, done_rx) = bounded::<Result<Done>>(2 * ranges.len());
            for _ in 0..threads {
                let (job_rx, done_tx): (Receiver<Job>, Sender<Result<Done>>) =
                    (job_rx.clone(), done_tx.clone());
                scope.spawn(move || {
                    for job in job_rx {
                        let done = factors(
                            samples,
                            vis,
                            settings.lift,
                            job.shooter,
                            job.range,
                            job.order,
                            memo,
                        );
                        if done_tx.send(done).is_err() {
                            break;
                        }
                    }
                });
            }
            Some((job_tx, done_rx))
        } else {
            None
        };

        // One shooter's visible receivers and form factors, range by range (on the workers
        // when there are some), in receiver order.
        let mut results: Vec<Option<Done>> = Vec::new();
        let mut compute = |j: usize| -> Result<(List, u64)> {
            let shooter = Shooter::of(samples, state.maps, j);
            results.clear();
            results.resize_with(ranges.len(), || None);
            match &pool {
                Some((job_tx, done_rx)) => {
                    for (order, range) in ranges.iter().enumerate() {
                        job_tx
                            .send(Job {
                                range: range.clone(),
                                order,
                                shooter,
                            })
                            .expect("workers outlive the coordinator's sends");
                    }
                    for _ in 0..ranges.len() {
                        let done = done_rx.recv().expect("workers answer every job")?;
                        let order = done.order;
                        results[order] = Some(done);
                    }
                }
                None => {
                    for (order, range) in ranges.iter().enumerate() {
                        results[order] = Some(factors(
                            samples,
                            vis,
                            settings.lift,
                            shooter,
                            range.clone(),
                            order,
                            memo,
                        )?);
                    }
                }
            }
            let list: Box<[(u32, f32)]> = results
                .iter()
                .flatten()
                .flat_map(|d| d.factors.iter().copied())
                .collect();
            if let Some(memo) = memo {
                memo.record(j, &list);
            }
            Ok((list, results.iter().flatten().map(|d| d.queries).sum()))
        };
        let delivered_by = |list: &[(u32, f32)]| -> f64 {
            list.iter()
                .map(|&(i, f)| f64::from(f) * samples.area[i as usize])
                .sum()
        };

        // Per shooter: its visible receivers with (row-scaled) form factors, and Σ F·S.
        let mut cache: Vec<Option<Kept>> = vec![None; n];
        let mut cache_left = settings.cache_bytes;

        if settings.prepass {
            // Every receiver's row sum Σⱼ Fᵢⱼ, from every shooter's list.
            let mut sums = vec![0.0f64; n];
            for (j, slot) in cache.iter_mut().enumerate() {
                if j % 256 == 0 && report(0, 1.0) == Control::Stop {
                    stats.stop = StopReason::Stopped;
                    return Ok(stats);
                }
                let (list, queries) = compute(j)?;
                stats.queries += queries;
                for &(i, f) in list.iter() {
                    sums[i as usize] += f64::from(f);
                }
                let bytes = std::mem::size_of_val(&*list);
                if bytes <= cache_left {
                    cache_left -= bytes;
                    *slot = Some((list, 0.0));
                }
            }
            for (i, scale) in state.row_scale.iter_mut().enumerate() {
                let sum = sums[i];
                // A closed row off by more than a fifth is not a discretisation error to
                // correct (something hides what the probes saw): then only cap it.
                *scale = if sum <= 0.0 {
                    1.0
                } else if state.closed[i] && (0.8..1.25).contains(&sum) {
                    (1.0 / sum) as f32
                } else {
                    (1.0 / sum).min(1.0) as f32
                };
            }
            for kept in cache.iter_mut().flatten() {
                for (i, f) in kept.0.iter_mut() {
                    *f *= state.row_scale[*i as usize];
                }
                kept.1 = delivered_by(&kept.0);
            }
        }

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
            if stats.shots % 32 == 0 && report(stats.shots, stats.unshot_fraction) == Control::Stop
            {
                stats.stop = StopReason::Stopped;
                break;
            }
            let j = best.1;

            // This shooter's form factors, unless they are kept from before.
            let mut keep = true;
            if cache[j].is_none() {
                let (mut list, queries) = compute(j)?;
                stats.queries += queries;
                for (i, f) in list.iter_mut() {
                    *f *= state.row_scale[*i as usize];
                }
                let delivered = delivered_by(&list);
                let bytes = std::mem::size_of_val(&*list);
                // Over budget, the list serves this shot only.
                keep = bytes <= cache_left;
                if keep {
                    cache_left -= bytes;
                }
                cache[j] = Some((list, delivered));
            } else {
                stats.cached_shots += 1;
            }
            let (list, delivered) = cache[j].as_ref().expect("filled above");

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
                cache[j] = None;
            }
            state.unshot[j] = DVec3::ZERO;
            power[j] = 0.0;
            stats.shots += 1;
        }
        drop(pool);
        Ok(stats)
    })
}

/// Form factors from every sample that sees sample `j` to `j`'s disc: (receiver, F).
pub(crate) fn form_factors(
    samples: &Samples,
    maps: &[SurfaceMap],
    vis: &dyn Visibility,
    lift: f32,
    j: usize,
) -> Result<Vec<(u32, f32)>> {
    let shooter = Shooter::of(samples, maps, j);
    Ok(factors(samples, vis, lift, shooter, 0..samples.len(), 0, None)?.factors)
}

/// Form factor from a near receiver point to a shooter's region, summed over its shares of
/// the area cells (the shares of all samples tile the surfaces): exact (Lambert's formula on
/// the cell's square) for cells within two cell widths, point to point beyond.
fn near_factor(samples: &Samples, shooter: &Shooter, x: Vec3, n: Vec3) -> f32 {
    let mut sum = 0.0f64;
    for &(c, share) in samples.shares_of(shooter.index as usize) {
        let cell = &samples.cells[c as usize];
        let d = x - cell.centroid;
        let r2 = d.length_squared();
        let cos_j = shooter.normal.dot(d);
        if cos_j <= 0.0 {
            continue;
        }
        let fraction = f64::from(share / cell.area);
        if r2 < 16.0 * cell.half * cell.half {
            let h = 0.5 * cell.area.sqrt();
            let (u, v) = (shooter.u * h, shooter.v * h);
            let c = cell.centroid;
            let square = [c - u - v, c + u - v, c + u + v, c - u + v];
            sum += fraction * crate::light::convex_polygon_irradiance(&square, x, n)
                / std::f64::consts::PI;
        } else {
            let cos_i = -n.dot(d);
            if cos_i > 0.0 {
                sum += f64::from(cos_i * cos_j / (r2 * r2) * share / std::f32::consts::PI);
            }
        }
    }
    sum as f32
}

/// Form factors from every visible receiver in `range` to the shooter's disc.
fn factors(
    samples: &Samples,
    vis: &dyn Visibility,
    lift: f32,
    shooter: Shooter,
    range: std::ops::Range<usize>,
    order: usize,
    memo: Option<&Memo>,
) -> Result<Done> {
    let mut candidates = Vec::new();
    let mut known = Vec::new();
    let mut segments = Vec::new();
    let from = shooter.position + lift * shooter.normal;
    let j = shooter.index as usize;
    for i in range {
        if i == shooter.index as usize {
            continue;
        }
        // Between region centres: a sample's radiosity is its region's average, and near an
        // edge the sample point can sit far from the middle of its region.
        let d = samples.centroid[i] - shooter.centroid;
        let r2 = d.length_squared();
        let cos_j = shooter.normal.dot(d);
        let cos_i = -samples.normal[i].dot(d);
        if cos_j <= 0.0 || cos_i <= 0.0 || r2 <= 0.0 {
            continue;
        }
        let f = if r2 < NEAR * NEAR * shooter.area {
            near_factor(samples, &shooter, samples.centroid[i], samples.normal[i])
        } else {
            // Far: the point form factor (the near range already keeps r ≥ 4√S).
            cos_i * cos_j / (r2 * r2) * shooter.area / std::f32::consts::PI
        };
        let memory = memo.and_then(|m| m.get(i, j));
        if memory.is_none() {
            segments.push(Segment {
                a: from,
                b: samples.position[i] + lift * samples.normal[i],
            });
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
        order,
        factors,
        queries: segments.len() as u64,
    })
}
