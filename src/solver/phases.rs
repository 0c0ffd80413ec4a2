//! The solve as phases: initial samples, then per round representative areas, direct light
//! and a warm start for the new samples, the probes behind the row scales, shooting (flat or
//! clustered), and the adaptive samples for the next round.

use std::time::Instant;

use glam::{DVec3, Vec3};

use super::cluster::coherence::{Context, TriangleGrid};
use super::shooting::{Settings, State, Tick};
use super::warm::{emission, reflectance};
use super::{cluster, flat, normalise, warm};
use super::{Control, Options, Phase, PhaseSeconds, Progress, RoundStats, Solution};
use crate::area;
use crate::error::Result;
use crate::light::DirectLight;
use crate::parallel::for_chunks;
use crate::sampling::adaptive::{self, RefineSettings};
use crate::sampling::{
    cover, poisson, reflecting_sides, surface_of, Samples, SideIndex, SurfaceMap,
};
use crate::scene::Scene;
use crate::visibility::Visibility;

/// A reporter for a phase of a round: hears the share done, tells the host (stopping is
/// honoured at shots and round boundaries only).
pub(super) fn reporter<'a>(
    progress: &'a mut dyn FnMut(&Progress) -> Control,
    phase: Phase,
    round: u32,
    samples: usize,
    tolerance: f64,
) -> impl FnMut(f64) + 'a {
    move |fraction| {
        let _ = progress(&Progress {
            phase,
            round,
            samples,
            shots: 0,
            unshot_fraction: 1.0,
            tolerance,
            fraction,
        });
    }
}

/// What one solve holds across its rounds.
pub(super) struct Solve<'a> {
    pub(super) scene: &'a Scene,
    pub(super) vis: &'a dyn Visibility,
    pub(super) options: &'a Options,
    pub(super) light: DirectLight,
    /// The scene's triangles for the hierarchy's coherence tests (none for the flat solver).
    pub(super) grid: Option<TriangleGrid>,
    pub(super) lift: f32,
    pub(super) epsilon: f32,
    pub(super) progress: &'a mut dyn FnMut(&Progress) -> Control,
}

/// Samples an adaptive step (or the initial placement) added.
#[derive(Clone)]
pub(super) struct AddedSamples {
    pub(super) added: usize,
    pub(super) refined: usize,
    pub(super) capped: bool,
    pub(super) seconds: f64,
    /// Per side: whether it has new samples or changed radii (`None`: every side is new).
    pub(super) changed: Option<Vec<bool>>,
}

impl Solve<'_> {
    fn report(&mut self, phase: Phase, round: u32, samples: usize, tick: Option<Tick>) -> Control {
        let tick = tick.unwrap_or(Tick {
            phase,
            shots: 0,
            unshot_fraction: 1.0,
            fraction: 0.0,
        });
        (self.progress)(&Progress {
            phase: tick.phase,
            round,
            samples,
            shots: tick.shots,
            unshot_fraction: tick.unshot_fraction,
            tolerance: self.options.tolerance,
            fraction: tick.fraction,
        })
    }

    /// Poisson-disk samples on every reflecting side (eq. 3), each side seeded on its own.
    pub(super) fn initial_samples(&mut self, maps: &[SurfaceMap]) -> Result<Samples> {
        // Stopping is honoured from the first shot on: before it there is no estimate to return.
        let _ = self.report(Phase::Sampling, 0, 0, None);
        let sides = reflecting_sides(self.scene);
        let mut per_side: Vec<Vec<glam::Vec2>> = vec![Vec::new(); sides.len()];
        let (epsilon, seed) = (self.epsilon, self.options.seed);
        for_chunks(&mut per_side, 1, self.options.threads.max(1), |i, out| {
            let side = sides[i];
            out[0] = poisson::sample_side(&maps[surface_of(side) as usize], side, epsilon, seed);
            Ok(())
        })?;
        let mut samples = Samples::default();
        for (&side, points) in sides.iter().zip(&per_side) {
            for &p in points {
                samples.push(maps, side, p, epsilon, 0);
            }
        }
        Ok(samples)
    }

    /// One round: areas over all samples, direct light and a warm start for the new ones,
    /// then shooting.
    pub(super) fn round(
        &mut self,
        solution: &mut Solution,
        round: u32,
        added: &AddedSamples,
    ) -> Result<RoundStats> {
        let (scene, vis, options) = (self.scene, self.vis, self.options);
        let threads = options.threads.max(1);
        let mut seconds = PhaseSeconds {
            sampling: added.seconds,
            ..PhaseSeconds::default()
        };
        let n = solution.samples.len();
        let first_new = n - added.added;

        // Areas over all samples, old and new.
        let t = Instant::now();
        let _ = self.report(Phase::Areas, round, n, None);
        solution.index = SideIndex::new(&solution.samples, &solution.maps, self.epsilon);
        let area_stats = area::compute(
            &mut solution.samples,
            &solution.maps,
            &solution.index,
            &solution.obstruction,
            vis,
            (self.epsilon, options.alpha),
            threads,
            added.changed.as_deref(),
            &mut reporter(
                &mut *self.progress,
                Phase::Areas,
                round,
                n,
                options.tolerance,
            ),
        )?;
        seconds.areas = t.elapsed().as_secs_f64();

        // Direct light at the new samples.
        let t = Instant::now();
        let _ = self.report(Phase::DirectLight, round, n, None);
        let s = &solution.samples;
        let points: Vec<(Vec3, Vec3)> = (first_new..n)
            .map(|k| (s.position[k], s.normal[k]))
            .collect();
        let ids: Vec<u32> = (first_new as u32..n as u32).collect();
        let (arrivals, direct_queries) = self.light.at(
            vis,
            &points,
            &ids,
            options.seed,
            threads,
            &mut reporter(
                &mut *self.progress,
                Phase::DirectLight,
                round,
                n,
                options.tolerance,
            ),
        )?;
        let covered = cover::covered(vis, &points, self.lift, self.epsilon, threads)?;
        solution.covered.extend(covered);
        seconds.direct = t.elapsed().as_secs_f64();
        warm::start(
            scene,
            solution,
            vis,
            first_new,
            &arrivals,
            self.epsilon,
            options.alpha,
            threads,
        )?;
        if round == 0 {
            // Direct light that reached no sample area left the scene.
            let received: DVec3 = (0..n)
                .map(|k| solution.direct[k].irradiance * solution.samples.area[k])
                .sum();
            solution.ledger.escaped += solution.ledger.emitted - received;
        }

        // Which new samples see the scene all around (for the row scales).
        let t = Instant::now();
        let sides = reflecting_sides(scene);
        let mut reflecting = vec![false; 2 * scene.surfaces.len()];
        for &side in &sides {
            reflecting[side as usize] = true;
        }
        let probes = normalise::closed_hemispheres(
            scene,
            &reflecting,
            &solution.samples,
            first_new,
            vis,
            (options.seed, threads),
            self.lift,
            &mut reporter(
                &mut *self.progress,
                Phase::Links,
                round,
                n,
                options.tolerance,
            ),
        )?;
        solution.closed.extend(probes);
        let hierarchical = self.grid.is_some();
        for k in first_new..n {
            // The flat solver sums rows in its first round only: later samples take the scale
            // of their nearest old sample. The hierarchy sums every round's rows.
            // A neighbour covered as it is: a row scale corrects the discretisation, which
            // differs under a cover and beside it.
            let s = &solution.samples;
            let scale = if round == 0 || hierarchical {
                1.0
            } else {
                let covered = &solution.covered;
                let old = |j: u32| (j as usize) < first_new;
                let alike = |j: u32| old(j) && covered[j as usize] == covered[k];
                (solution.index.nearest_where(s, s.side[k], s.uv[k], alike))
                    .or_else(|| solution.index.nearest_where(s, s.side[k], s.uv[k], old))
                    .map_or(1.0, |j| solution.row_scale[j as usize])
            };
            solution.row_scale.push(scale);
        }
        let probe_seconds = t.elapsed().as_secs_f64();

        // Shoot, with what the samples leave of the memory budget.
        let solution_bytes = solution.bytes();
        let memory_left = options.memory_budget.saturating_sub(solution_bytes);
        let t = Instant::now();
        let reflectances: Vec<DVec3> = (0..n)
            .map(|k| reflectance(scene, &solution.samples, k))
            .collect();
        let dark_emitters: Vec<f64> = solution.direct.iter().map(|a| a.dark_emitters).collect();
        let mut state = State {
            samples: &solution.samples,
            maps: &solution.maps,
            reflectance: &reflectances,
            radiosity: &solution.radiosity,
            irradiance: &mut solution.irradiance,
            unshot: &mut solution.unshot,
            ledger: &mut solution.ledger,
            row_scale: &mut solution.row_scale,
            closed: &solution.closed,
            dark_emitters: &dark_emitters,
        };
        let settings = Settings {
            threads,
            capacity: options.pipeline_capacity.max(1),
            tolerance: options.tolerance,
            max_shots: options.max_shots.unwrap_or(if hierarchical {
                u64::MAX
            } else {
                200 * n as u64
            }),
            lift: self.lift,
            memory_bytes: memory_left,
            normalise: round == 0 || hierarchical,
            threshold: options.cluster_threshold,
            exact_visibility: options.exact_visibility,
            seed: options.seed,
        };
        let progress = &mut *self.progress;
        let mut link_seconds = None;
        let link_start = Instant::now();
        let mut report = |tick: Tick| {
            if tick.phase == Phase::Shooting && link_seconds.is_none() {
                link_seconds = Some(link_start.elapsed().as_secs_f64());
            }
            progress(&Progress {
                phase: tick.phase,
                round,
                samples: n,
                shots: tick.shots,
                unshot_fraction: tick.unshot_fraction,
                tolerance: options.tolerance,
                fraction: tick.fraction,
            })
        };
        let shooting = match &self.grid {
            Some(grid) => {
                let cx = Context {
                    scene,
                    grid,
                    samples: state.samples,
                    obstruction: &solution.obstruction,
                    lift: self.lift,
                };
                cluster::shoot(&mut state, vis, &settings, &cx, &mut report)?
            }
            None => flat::shoot(&mut state, vis, &settings, &mut report)?,
        };
        let total = t.elapsed().as_secs_f64();
        let linking = link_seconds.unwrap_or(total);
        if hierarchical {
            seconds.links = linking + probe_seconds;
            seconds.shooting = total - linking;
        } else {
            seconds.shooting = total + probe_seconds;
        }
        for (k, rho) in reflectances.iter().enumerate() {
            solution.radiosity[k] =
                emission(scene, &solution.samples, k) + *rho * solution.irradiance[k];
        }
        Ok(RoundStats {
            round,
            samples: n,
            added: added.added,
            refined: added.refined,
            capped: added.capped,
            solution_bytes: solution_bytes as u64,
            direct_queries,
            areas: area_stats,
            shooting,
            seconds,
        })
    }

    /// Adds samples where the error is large (eqs. 7-8), unless told to stop.
    pub(super) fn add_samples(
        &mut self,
        solution: &mut Solution,
        round: u32,
    ) -> Result<Option<AddedSamples>> {
        let t = Instant::now();
        if self.report(Phase::Adaptive, round, solution.samples.len(), None) == Control::Stop {
            return Ok(None);
        }
        let options = self.options;
        let n = solution.samples.len();
        let radii = solution.samples.radius.clone();
        let refinement = adaptive::refine(
            &mut solution.samples,
            &solution.maps,
            &solution.index,
            &solution.obstruction,
            self.vis,
            &solution.radiosity,
            RefineSettings {
                epsilon: self.epsilon,
                zeta: options.zeta,
                alpha: options.alpha,
                threads: options.threads.max(1),
                round: round as u16,
                seed: options.seed,
                // Half the budget for the samples, the rest for links and caches.
                max_samples: options
                    .max_samples
                    .min(options.memory_budget / 2 / super::BYTES_PER_SAMPLE),
            },
            &mut reporter(
                &mut *self.progress,
                Phase::Adaptive,
                round,
                n,
                options.tolerance,
            ),
        )?;
        let samples = &solution.samples;
        let mut changed = vec![false; 2 * solution.maps.len()];
        for k in 0..samples.len() {
            if radii.get(k) != Some(&samples.radius[k]) {
                changed[samples.side[k] as usize] = true;
            }
        }
        Ok(Some(AddedSamples {
            added: refinement.added,
            refined: refinement.refined,
            capped: refinement.capped,
            seconds: t.elapsed().as_secs_f64(),
            changed: Some(changed),
        }))
    }
}
