//! Visibility throughput as `meshlight bench-vis` reports it: build time, million occlusion
//! queries and closest-hit rays per second per backend and thread count, Embree's raw shim
//! paths beside the trait, and how often the backends disagree. Measured in one run, so ratios
//! between lines are meaningful on a noisy machine.

use std::time::{Duration, Instant};

use crate::workload::{camera_rays, facing_segments};
use meshlight::visibility::{Backend, BvhPreset, BvhScene, Hit, Visibility};
use meshlight::{Result, Scene};

/// What to measure.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// Occlusion queries (segments between facing surface points).
    pub segments: usize,
    /// Closest-hit queries (camera rays).
    pub rays: usize,
    /// Thread counts to measure.
    pub threads: Vec<usize>,
    /// Backends to measure.
    pub backends: Vec<Backend>,
    /// obvhs presets to measure for the `bvh` backend.
    pub bvh_presets: Vec<BvhPreset>,
    /// Queries per call through the trait (the solver's batch size).
    pub batch: usize,
    /// Each figure is the best of this many runs.
    pub repeats: usize,
    /// Seed of the query sets.
    pub seed: u64,
}

impl Default for BenchOptions {
    fn default() -> Self {
        BenchOptions {
            segments: 1_000_000,
            rays: 100_000,
            threads: vec![1, 2],
            backends: Backend::available(),
            bvh_presets: vec![BvhPreset::default()],
            batch: 1024,
            repeats: 3,
            seed: 1,
        }
    }
}

/// Queries per second at one thread count.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rate {
    /// Threads used.
    pub threads: usize,
    /// Queries per second (best run).
    pub per_second: f64,
}

/// One backend's figures.
#[derive(Clone, Debug)]
pub struct BackendReport {
    /// The backend.
    pub backend: Backend,
    /// Its settings, in words.
    pub detail: String,
    /// Build time (best run).
    pub build: Duration,
    /// Occlusion through the trait.
    pub occlusion: Vec<Rate>,
    /// Closest hit through the trait.
    pub intersect: Vec<Rate>,
}

/// Embree's shim called directly on the whole query set, one mode.
#[derive(Clone, Debug)]
pub struct RawReport {
    /// The shim mode.
    pub mode: &'static str,
    /// Occlusion rates.
    pub occlusion: Vec<Rate>,
    /// Closest-hit rates.
    pub intersect: Vec<Rate>,
}

/// How often two backends answered differently on the same queries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Agreement {
    /// Segments one backend found blocked and the other clear.
    pub occlusion: usize,
    /// Rays one backend found a hit for and the other did not.
    pub hit_or_miss: usize,
    /// Rays both hit, at distances differing by more than 1e-4 relative.
    pub distance: usize,
}

/// Everything `bench-vis` prints.
#[derive(Clone, Debug)]
pub struct BenchReport {
    /// Occlusion queries used.
    pub segments: usize,
    /// Camera rays used.
    pub rays: usize,
    /// Per backend (and obvhs preset).
    pub backends: Vec<BackendReport>,
    /// Embree's raw shim paths (empty without Embree).
    pub embree_raw: Vec<RawReport>,
    /// Embree against the first obvhs preset, when both ran.
    pub agreement: Option<Agreement>,
    /// The Embree headers the shim was built against, when it was.
    pub embree_headers: Option<&'static str>,
}

/// Runs the benchmark; `progress` hears what is being measured.
pub fn run(
    scene: &Scene,
    options: &BenchOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<BenchReport> {
    progress("generating queries");
    let segments = facing_segments(scene, options.segments, options.seed);
    let rays = camera_rays(scene, options.rays, options.seed.wrapping_add(1));
    let repeats = options.repeats.max(1);
    let mut report = BenchReport {
        segments: segments.len(),
        rays: rays.len(),
        backends: Vec::new(),
        embree_raw: Vec::new(),
        agreement: None,
        embree_headers: None,
    };
    let mut answers: Vec<(Backend, Vec<bool>, Vec<Option<Hit>>)> = Vec::new();

    for &backend in &options.backends {
        let presets: Vec<Option<BvhPreset>> = match backend {
            Backend::Bvh => options.bvh_presets.iter().copied().map(Some).collect(),
            _ => vec![None],
        };
        for preset in presets {
            progress(&format!(
                "building {}",
                preset.map_or(backend.name(), BvhPreset::name)
            ));
            let (build, built) = best_of(repeats, || build(scene, backend, preset))?;
            let (vis, detail) = built;
            let mut occluded = vec![false; segments.len()];
            let mut hits = vec![None; rays.len()];
            let mut occlusion = Vec::new();
            let mut intersect = Vec::new();
            for &threads in &options.threads {
                progress(&format!("{detail}: occlusion, {threads} thread(s)"));
                let (time, ()) = best_of(repeats, || {
                    parallel(&segments, &mut occluded, threads, options.batch, |s, o| {
                        vis.occluded(s, o)
                    })
                })?;
                occlusion.push(Rate {
                    threads,
                    per_second: segments.len() as f64 / time.as_secs_f64(),
                });
                progress(&format!("{detail}: closest hit, {threads} thread(s)"));
                let (time, ()) = best_of(repeats, || {
                    parallel(&rays, &mut hits, threads, options.batch, |r, o| {
                        vis.intersect(r, o)
                    })
                })?;
                intersect.push(Rate {
                    threads,
                    per_second: rays.len() as f64 / time.as_secs_f64(),
                });
            }
            answers.push((backend, occluded, hits));
            report.backends.push(BackendReport {
                backend,
                detail,
                build,
                occlusion,
                intersect,
            });
        }
    }

    #[cfg(feature = "embree")]
    if options.backends.contains(&Backend::Embree) {
        report.embree_headers = Some(meshlight::visibility::embree_headers());
        report.embree_raw = embree_raw(scene, options, &segments, &rays, progress)?;
    }

    let embree = answers.iter().find(|a| a.0 == Backend::Embree);
    let bvh = answers.iter().find(|a| a.0 == Backend::Bvh);
    if let (Some(e), Some(b)) = (embree, bvh) {
        report.agreement = Some(compare(&e.1, &b.1, &e.2, &b.2));
    }
    Ok(report)
}

/// The Embree shim's rates in each of its modes, the whole per-thread share in one call: the
/// shim's best case, against which the trait's overhead shows.
#[cfg(feature = "embree")]
fn embree_raw(
    scene: &Scene,
    options: &BenchOptions,
    segments: &[meshlight::visibility::Segment],
    rays: &[meshlight::visibility::Ray],
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<RawReport>> {
    use meshlight::visibility::{EmbreeMode, EmbreeOptions, EmbreeScene};
    let repeats = options.repeats.max(1);
    let mut reports = Vec::new();
    let embree = EmbreeScene::new(scene, EmbreeOptions::default())?;
    let mut occluded = vec![false; segments.len()];
    let mut hits = vec![None; rays.len()];
    for mode in EmbreeMode::all() {
        let mut raw = RawReport {
            mode: mode.name(),
            occlusion: Vec::new(),
            intersect: Vec::new(),
        };
        for &threads in &options.threads {
            progress(&format!(
                "embree raw shim {}: {threads} thread(s)",
                mode.name()
            ));
            // The whole per-thread share in one call: the shim's best case.
            let (time, ()) = best_of(repeats, || {
                parallel(segments, &mut occluded, threads, usize::MAX, |s, o| {
                    embree.occluded_with(mode, s, o)
                })
            })?;
            raw.occlusion.push(Rate {
                threads,
                per_second: segments.len() as f64 / time.as_secs_f64(),
            });
            let (time, ()) = best_of(repeats, || {
                parallel(rays, &mut hits, threads, usize::MAX, |r, o| {
                    embree.intersect_with(mode, r, o)
                })
            })?;
            raw.intersect.push(Rate {
                threads,
                per_second: rays.len() as f64 / time.as_secs_f64(),
            });
        }
        reports.push(raw);
    }
    Ok(reports)
}

/// Counts where two backends' answers differ.
pub fn compare(
    occ_a: &[bool],
    occ_b: &[bool],
    hits_a: &[Option<Hit>],
    hits_b: &[Option<Hit>],
) -> Agreement {
    let mut agreement = Agreement {
        occlusion: occ_a.iter().zip(occ_b).filter(|(a, b)| a != b).count(),
        ..Agreement::default()
    };
    for (a, b) in hits_a.iter().zip(hits_b) {
        match (a, b) {
            (Some(a), Some(b)) => {
                if (a.t - b.t).abs() > 1e-4 * a.t.abs().max(b.t.abs()) {
                    agreement.distance += 1;
                }
            }
            (None, None) => {}
            _ => agreement.hit_or_miss += 1,
        }
    }
    agreement
}

fn build(
    scene: &Scene,
    backend: Backend,
    preset: Option<BvhPreset>,
) -> Result<(Box<dyn Visibility>, String)> {
    match (backend, preset) {
        (Backend::Bvh, Some(preset)) => Ok((
            Box::new(BvhScene::new(scene, preset)),
            format!("bvh {}", preset.name()),
        )),
        #[cfg(feature = "embree")]
        (Backend::Embree, _) => {
            let options = meshlight::visibility::EmbreeOptions::default();
            let detail = format!(
                "embree {} {}{}",
                meshlight::visibility::embree_major(),
                options.occlusion_mode.name(),
                if options.robust { " robust" } else { "" }
            );
            Ok((
                Box::new(meshlight::visibility::EmbreeScene::new(scene, options)?),
                detail,
            ))
        }
        _ => Ok((backend.build(scene)?, backend.name().to_string())),
    }
}

/// Runs `f` `repeats` times; the shortest time and the last result.
fn best_of<T>(repeats: usize, mut f: impl FnMut() -> Result<T>) -> Result<(Duration, T)> {
    let mut best = Duration::MAX;
    let mut last = None;
    for _ in 0..repeats {
        let start = Instant::now();
        let value = f()?;
        best = best.min(start.elapsed());
        last = Some(value);
    }
    Ok((best, last.expect("repeats >= 1")))
}

/// Splits queries into one contiguous share per thread; each thread answers its share in
/// batches of `batch`.
pub fn parallel<Q: Sync, O: Send>(
    queries: &[Q],
    out: &mut [O],
    threads: usize,
    batch: usize,
    f: impl Fn(&[Q], &mut [O]) -> Result<()> + Sync,
) -> Result<()> {
    let threads = threads.max(1);
    let share = queries.len().div_ceil(threads).max(1);
    let batch = batch.max(1);
    let work = |q: &[Q], o: &mut [O]| -> Result<()> {
        for (q, o) in q.chunks(batch).zip(o.chunks_mut(batch)) {
            f(q, o)?;
        }
        Ok(())
    };
    if threads == 1 {
        return work(queries, out);
    }
    std::thread::scope(|scope| {
        let handles: Vec<_> = queries
            .chunks(share)
            .zip(out.chunks_mut(share))
            .map(|(q, o)| scope.spawn(move || work(q, o)))
            .collect();
        handles
            .into_iter()
            .try_for_each(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
    })
}
