//! The solve as phases: initial samples, then per round representative areas, direct light
//! and a warm start for the new samples, the probes behind the row scales, shooting (flat or
//! clustered), and the adaptive samples for the next round.

use std::time::Instant;

use glam::{DVec3, Vec3};

use super::cluster::coherence::{Context, TriangleGrid};
use super::shooting::{Settings, State, Tick};
use super::warm::{emission, reflectance};
use super::{balance, cluster, flat, normalise, warm};
use super::{Options, PhaseSeconds, RoundStats, ShootStats, Solution, StopReason};
use crate::area::{self, AreaStats};
use crate::error::Result;
use crate::light::{Arrival, DirectLight};
use crate::parallel::for_chunks_reporting;
use crate::progress::{Control, Phase, Progress, Reporter};
use crate::sampling::adaptive::{self, RefineSettings};
use crate::sampling::{cover, poisson, reflecting_sides, surface_of, Samples, Side, SurfaceMap};
use crate::scene::Scene;
use crate::specular::lights::Lights;
use crate::specular::Specular;
use crate::visibility::Visibility;

/// What one solve holds across its rounds.
pub(super) struct Solve<'a> {
    pub(super) scene: &'a Scene,
    pub(super) vis: &'a dyn Visibility,
    pub(super) options: &'a Options,
    /// The lights, straight and through single reflectors (what the image traces again).
    pub(super) light: DirectLight,
    /// The lights through chains of two reflectors or more, where the scene has any.
    pub(super) far_light: Option<DirectLight>,
    /// The scene's triangles for the hierarchy's coherence tests (none for the flat solver).
    pub(super) grid: Option<TriangleGrid>,
    pub(super) lift: f32,
    pub(super) epsilon: f32,
    /// The sides that get samples: those light can reach ([`crate::sampling::lit_sides`]).
    pub(super) sides: Vec<Side>,
    pub(super) reporter: Reporter<'a>,
    /// The processes the solve is spread over (see `distributed`).
    pub(super) ranks: &'a dyn crate::distributed::Ranks,
    /// The scene's specular surfaces and lights, where it has any (and the depth is not 0).
    pub(super) specular: Option<(Specular, Lights)>,
    /// What the samples' direct light is scaled by to balance the lights' power (`balance`).
    pub(super) light_scale: DVec3,
    /// The daylight entering, where the scene has a sky.
    pub(super) entering: Option<crate::daylight::entering::Entering<'a>>,
    /// This round's new samples' inter-reflected irradiance as their warm start interpolated
    /// it (see `warm::Regather`); empty in the first round.
    pub(super) interpolated: Vec<DVec3>,
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

/// Direct light from `light` at the samples `points` (position, normal) with ids `ids`, each
/// rank a run of them in the light's own chunks, all-gathered; the shadow queries over all
/// ranks.
fn arrive(
    light: &DirectLight,
    vis: &dyn Visibility,
    exec: crate::exec::Exec,
    (points, ids): (&[(Vec3, Vec3)], &[u32]),
    report: crate::parallel::Report,
) -> Result<(Vec<Arrival>, u64)> {
    let (ranks, seed, threads) = (exec.ranks, exec.seed, exec.threads);
    let mine = crate::distributed::share_of(ranks, points.len(), DirectLight::CHUNK);
    let (part, queries) = light.at(
        vis,
        &points[mine.clone()],
        &ids[mine.clone()],
        seed,
        threads,
        report,
    )?;
    let mut arrivals = vec![Arrival::default(); points.len()];
    arrivals[mine].copy_from_slice(&part);
    drop(part);
    crate::distributed::gather_shares(
        ranks,
        &mut arrivals,
        DirectLight::CHUNK,
        |a: &Arrival| {
            [
                a.irradiance.x,
                a.irradiance.y,
                a.irradiance.z,
                f64::from(a.visible),
                a.dark_emitters,
            ]
        },
        |v| Arrival {
            irradiance: DVec3::new(v[0], v[1], v[2]),
            visible: v[3] as f32,
            dark_emitters: v[4],
        },
    )?;
    Ok((arrivals, crate::distributed::sum_over(ranks, queries)?))
}

impl<'a> Solve<'a> {
    /// How the stages run: the options' threads and seed, over the solve's ranks.
    fn exec(&self) -> crate::exec::Exec<'a> {
        crate::exec::Exec::new(self.options.threads, self.options.seed, self.ranks)
    }

    /// The report of `phase` in `round` over `samples` samples, nothing done yet.
    fn base(&self, phase: Phase, round: u32, samples: usize) -> Progress {
        Progress {
            round,
            items: samples,
            tolerance: self.options.tolerance,
            unshot_fraction: 1.0,
            ..Progress::of(phase)
        }
    }

    /// Tells the host a phase starts; whether to stop.
    fn begin(&mut self, phase: Phase, round: u32, samples: usize) -> bool {
        let base = self.base(phase, round, samples);
        self.reporter.report(base)
    }

    /// Poisson-disk samples on every side light reaches (eq. 3), each side seeded on its own. A
    /// Stop leaves the sides not reached yet without samples.
    pub(super) fn initial_samples(
        &mut self,
        maps: &[SurfaceMap],
        pieces: &crate::sampling::pieces::Pieces,
    ) -> Result<Samples> {
        self.begin(Phase::Sampling, 0, 0);
        let sides = &self.sides;
        let mut per_side: Vec<Vec<glam::Vec2>> = vec![Vec::new(); sides.len()];
        let (epsilon, seed) = (self.epsilon, self.options.seed);
        let threads = self.options.threads.max(1);
        // The curved pieces' points, thrown over each piece as a whole, by side (every rank
        // throws them all: they are few beside the sides').
        let mut by_piece: Vec<Vec<(u32, glam::Vec2)>> = vec![Vec::new(); pieces.len()];
        if !self.reporter.stopped() {
            crate::parallel::for_chunks(&mut by_piece, 1, threads, |p, out| {
                out[0] =
                    crate::sampling::pieces::sample_piece(pieces, p as u32, maps, epsilon, seed);
                Ok(())
            })?;
        }
        let mut from_pieces: std::collections::HashMap<u32, Vec<glam::Vec2>> = Default::default();
        for (side, uv) in by_piece.into_iter().flatten() {
            from_pieces.entry(side).or_default().push(uv);
        }
        if !self.reporter.stopped() {
            let base = self.base(Phase::Sampling, 0, 0);
            // Over several ranks, each places the sides it deals.
            let ranks = self.ranks;
            let place = |i: usize, out: &mut [Vec<glam::Vec2>]| {
                if !crate::distributed::deals(ranks, i) {
                    return Ok(());
                }
                let side = sides[i];
                out[0] = if pieces.of(side).is_some() {
                    from_pieces.get(&side).cloned().unwrap_or_default()
                } else {
                    poisson::sample_side(&maps[surface_of(side) as usize], side, epsilon, seed)
                };
                Ok(())
            };
            for_chunks_reporting(
                &mut per_side,
                1,
                threads,
                place,
                &mut self.reporter.part(base),
            )?;
            crate::distributed::share_lists(
                self.ranks,
                &mut per_side,
                |p| [p.x, p.y].map(f64::from),
                |v| glam::Vec2::new(v[0] as f32, v[1] as f32),
            )?;
        }
        let mut samples = Samples::default();
        for (&side, points) in sides.iter().zip(&per_side) {
            for &p in points {
                samples.push(maps, side, p, epsilon, 0);
            }
        }
        samples.shrink_to_fit();
        Ok(samples)
    }

    /// One round: areas over all samples, direct light and a warm start for the new ones,
    /// the probes behind the row scales, then shooting. After a Stop the remaining phases are
    /// skipped, leaving a consistent solution: new samples without direct light or probes,
    /// and no shooting.
    pub(super) fn round(
        &mut self,
        solution: &mut Solution,
        round: u32,
        added: &AddedSamples,
    ) -> Result<RoundStats> {
        let mut seconds = PhaseSeconds {
            sampling: added.seconds,
            ..PhaseSeconds::default()
        };
        let n = solution.field.samples.len();
        let first_new = n - added.added;

        let t = Instant::now();
        let area_stats = self.areas(solution, round, added)?;
        seconds.areas = t.elapsed().as_secs_f64();

        let t = Instant::now();
        let direct_queries = self.direct_light(solution, round, first_new)?;
        seconds.direct = t.elapsed().as_secs_f64();

        let t = Instant::now();
        self.row_scales(solution, round, first_new)?;
        let probe_seconds = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let specular_queries = self.specular_transfer(solution)?;
        seconds.direct += t.elapsed().as_secs_f64();

        let solution_bytes = solution.bytes();
        let t = Instant::now();
        let (shooting, link_seconds) = self.shoot(solution, round, solution_bytes)?;
        let total = t.elapsed().as_secs_f64();
        let linking = link_seconds.unwrap_or(total);
        if self.grid.is_some() {
            seconds.links = linking + probe_seconds;
            seconds.shooting = total - linking;
        } else {
            seconds.shooting = total + probe_seconds;
        }
        for k in 0..n {
            solution.field.radiosity[k] = emission(self.scene, &solution.field.samples, k)
                + reflectance(self.scene, &solution.field.samples, k)
                    * solution.field.irradiance[k];
        }
        Ok(RoundStats {
            round,
            samples: n,
            added: added.added,
            refined: added.refined,
            capped: added.capped,
            solution_bytes: solution_bytes as u64,
            direct_queries: direct_queries + specular_queries,
            areas: area_stats,
            shooting,
            seconds,
        })
    }

    /// Representative areas over all samples, old and new (eqs. 4-6).
    fn areas(
        &mut self,
        solution: &mut Solution,
        round: u32,
        added: &AddedSamples,
    ) -> Result<AreaStats> {
        let n = solution.field.samples.len();
        self.begin(Phase::Areas, round, n);
        solution.field.layout.reindex(&solution.field.samples);
        let base = self.base(Phase::Areas, round, n);
        let stats = area::compute(
            &mut solution.field.samples,
            &solution.field.layout,
            self.vis,
            self.options.alpha,
            self.exec(),
            added.changed.as_deref(),
            &mut self.reporter.part(base),
        )?;
        solution.field.samples.reflectance = crate::sampling::reflectance::means(
            self.scene,
            &solution.field.samples,
            solution.field.layout.maps(),
            self.options.threads.max(1),
        )?;
        debug_assert_eq!(solution.validate(), Ok(()));
        Ok(stats)
    }

    /// The scale of the samples' direct light that balances it with the lights' power, in a
    /// scene closed around its area lights and without specular surfaces (`balance`); 1
    /// elsewhere. From the first samples' `arrivals`; later rounds' samples take it too.
    fn balance(&self, solution: &Solution, arrivals: &[Arrival]) -> Result<DVec3> {
        // Daylight is not the lights' power: a scene it enters is not closed around them.
        if self.specular.is_some() || self.reporter.stopped() || self.scene.daylight().is_some() {
            return Ok(DVec3::ONE);
        }
        if !balance::closed_to_the_lights(self.scene, self.vis, self.exec())? {
            return Ok(DVec3::ONE);
        }
        let area = &solution.field.samples.area;
        let received: DVec3 = arrivals
            .iter()
            .zip(area)
            .map(|(a, &s)| a.irradiance * s)
            .sum();
        Ok(balance::scale(received, self.scene.emitted_power()))
    }

    /// Direct light at the new samples, whether something covers them, and their warm start;
    /// the shadow queries made.
    fn direct_light(
        &mut self,
        solution: &mut Solution,
        round: u32,
        first_new: usize,
    ) -> Result<u64> {
        let n = solution.field.samples.len();
        self.begin(Phase::DirectLight, round, n);
        let s = &solution.field.samples;
        let points: Vec<(Vec3, Vec3)> = (first_new..n)
            .map(|k| (s.position[k], s.normal[k]))
            .collect();
        let ids: Vec<u32> = (first_new as u32..n as u32).collect();
        let at = (points.as_slice(), ids.as_slice());
        let (mut arrivals, mut queries, covered) = self.lights_and_cover(round, n, at)?;
        if first_new == 0 {
            self.light_scale = self.balance(solution, &arrivals)?;
        }
        for a in &mut arrivals {
            a.irradiance *= self.light_scale;
        }
        solution.field.layout.cover(&covered);
        queries += self.specular_light(solution, round, first_new, at)?;
        queries += self.daylight(solution, round, at)?;
        let (scene, vis, alpha) = (self.scene, self.vis, self.options.alpha);
        self.interpolated = warm::start(
            scene,
            solution,
            vis,
            first_new,
            &arrivals,
            alpha,
            self.exec(),
        )?;
        if round == 0 {
            queries += self.book_first_light(solution)?;
        }
        Ok(queries)
    }

    /// The lights' direct light at the new samples `at` (of `n` in all) and whether something
    /// covers each; nothing (and no queries) once the host has stopped the solve.
    fn lights_and_cover(
        &mut self,
        round: u32,
        n: usize,
        at: (&[(Vec3, Vec3)], &[u32]),
    ) -> Result<(Vec<Arrival>, u64, Vec<bool>)> {
        let count = at.0.len();
        if self.reporter.stopped() {
            return Ok((vec![Arrival::default(); count], 0, vec![false; count]));
        }
        let base = self.base(Phase::DirectLight, round, n);
        let exec = self.exec();
        let mut report = self.reporter.part(base);
        let (arrivals, queries) = arrive(&self.light, self.vis, exec, at, &mut report)?;
        let covered = cover::covered(self.vis, at.0, self.lift, self.epsilon, exec.threads)?;
        Ok((arrivals, queries, covered))
    }

    /// The first round's energy account: daylight entering is a source too (what the shooting
    /// measures against: the sky's and the ground's, and the sun's, which the samples' direct
    /// light holds mixed with the lamps', measured on its own here), and direct light that
    /// reached no sample's area left the scene. The queries the sun's share took.
    fn book_first_light(&mut self, solution: &mut Solution) -> Result<u64> {
        let n = solution.field.samples.len();
        let mut queries = 0;
        if !solution.field.daylight.is_empty() {
            let mut entering: DVec3 = (0..n)
                .map(|k| solution.field.daylight[k] * solution.field.samples.area[k])
                .sum();
            let sun = DirectLight::sun_only(self.scene, self.options.light_samples);
            if let Some(sun) = sun.filter(|_| !self.reporter.stopped()) {
                let s = &solution.field.samples;
                let points: Vec<(Vec3, Vec3)> =
                    (0..n).map(|k| (s.position[k], s.normal[k])).collect();
                let ids: Vec<u32> = (0..n as u32).collect();
                let mut quiet = |_: f64| crate::progress::Control::Continue;
                let exec = self.exec();
                let (arrivals, q) =
                    sun.at(self.vis, &points, &ids, exec.seed, exec.threads, &mut quiet)?;
                queries += q;
                entering += arrivals
                    .iter()
                    .zip(&s.area)
                    .map(|(a, &area)| a.irradiance * area)
                    .sum::<DVec3>();
            }
            solution.ledger.emitted += entering;
        }
        let received: DVec3 = (0..n)
            .map(|k| {
                let exact =
                    solution.field.direct[k].irradiance + warm::exact_beyond_direct(solution, k);
                exact * solution.field.samples.area[k]
            })
            .sum();
        solution.ledger.escaped += solution.ledger.emitted - received;
        Ok(queries)
    }

    /// The daylight entering at the new samples (`daylight::entering`); the queries.
    fn daylight(
        &mut self,
        solution: &mut Solution,
        round: u32,
        (points, ids): (&[(Vec3, Vec3)], &[u32]),
    ) -> Result<u64> {
        let Some(entering) = &self.entering else {
            return Ok(0);
        };
        let n = solution.field.samples.len();
        let mut out = vec![DVec3::ZERO; points.len()];
        if self.reporter.stopped() {
            solution.field.daylight.extend(out);
            return Ok(0);
        }
        let (vis, seed) = (self.vis, self.options.seed);
        let queries = std::sync::atomic::AtomicU64::new(0);
        let work = |first: usize, chunk: &mut [DVec3]| {
            let range = first..first + chunk.len();
            let (got, q) = entering.at(vis, &points[range.clone()], &ids[range], seed)?;
            chunk.copy_from_slice(&got);
            queries.fetch_add(q, std::sync::atomic::Ordering::Relaxed);
            Ok(())
        };
        let base = self.base(Phase::DirectLight, round, n);
        let threads = self.options.threads.max(1);
        for_chunks_reporting(&mut out, 64, threads, work, &mut self.reporter.part(base))?;
        solution.field.daylight.extend(out);
        Ok(queries.into_inner())
    }

    /// The new samples' light by way of specular surfaces that is not interpolated: their
    /// chains (and the lights' light through glossy bounces), the lights through chains of two
    /// reflectors or more, and the photons' (sent in the first round, spread over every
    /// round's areas: old samples take the change their new areas make); the queries.
    fn specular_light(
        &mut self,
        solution: &mut Solution,
        round: u32,
        first_new: usize,
        (points, ids): (&[(Vec3, Vec3)], &[u32]),
    ) -> Result<u64> {
        let Some((spec, lights)) = &self.specular else {
            return Ok(0);
        };
        let Some(mut transfer) = solution.specular.as_mut().map(std::mem::take) else {
            return Ok(0);
        };
        let (scene, vis, options) = (self.scene, self.vis, self.options);
        let n = solution.field.samples.len();
        let mut queries = 0;
        // The chains of the new samples, and the lights' light they bring.
        queries += if self.reporter.stopped() {
            transfer.direct.resize(n, DVec3::ZERO);
            transfer.specular_share.resize(n, 0.0);
            0
        } else {
            transfer.follow(scene, solution, vis, (spec, lights), options, first_new)?
        };
        // The lights seen through two reflectors or more: taken whole, not interpolated.
        if let Some(far) = &self.far_light {
            let base = self.base(Phase::DirectLight, round, n);
            let at = (points, ids);
            let (part, q) = if self.reporter.stopped() {
                (vec![Arrival::default(); points.len()], 0)
            } else {
                let exec = self.exec();
                let mut report = self.reporter.part(base);
                arrive(far, vis, exec, at, &mut report)?
            };
            queries += q;
            transfer.far.extend(part.iter().map(|a| a.irradiance));
        }
        // Photons: sent once, spread over each round's areas. Old samples take the change
        // their new areas make; new ones start from theirs (`warm`).
        if first_new == 0 && !self.reporter.stopped() {
            let base = self.base(Phase::Photons, round, n);
            let mut report = self.reporter.part(base);
            queries += transfer.trace_photons(scene, vis, (spec, lights), options, &mut report)?;
        }
        let caustic = if transfer.landings.is_empty() || self.reporter.stopped() {
            let mut kept = transfer.caustic.clone();
            kept.resize(n, DVec3::ZERO);
            kept
        } else {
            transfer.deposit(solution)
        };
        for (k, new) in caustic.iter().enumerate().take(first_new) {
            let change = *new - transfer.caustic.get(k).copied().unwrap_or_default();
            let rho = reflectance(scene, &solution.field.samples, k);
            solution.field.irradiance[k] += change;
            solution.unshot[k] += rho * change;
            solution.field.radiosity[k] += rho * change;
        }
        transfer.caustic = caustic;
        solution.specular = Some(transfer);
        Ok(queries)
    }

    /// Which new samples see the scene all around (the probes behind the row scales), and the
    /// row scales the new samples start from.
    fn row_scales(&mut self, solution: &mut Solution, round: u32, first_new: usize) -> Result<()> {
        let scene = self.scene;
        let n = solution.field.samples.len();
        let sides = reflecting_sides(scene);
        let mut reflecting = vec![false; 2 * scene.surfaces.len()];
        for &side in &sides {
            reflecting[side as usize] = true;
        }
        let probes = if self.reporter.stopped() {
            vec![false; n - first_new]
        } else {
            let base = self.base(Phase::Links, round, n);
            normalise::closed_hemispheres(
                scene,
                &reflecting,
                &solution.field.samples,
                first_new,
                self.vis,
                self.exec(),
                &mut self.reporter.part(base),
            )?
        };
        solution.closed.reserve_exact(probes.len());
        // A hemisphere that shows specular surfaces (to the chains, if not to the probes) is not
        // all links': its row must not be scaled up to the whole of it.
        let shows_specular = |k: usize| {
            let t = solution.specular.as_ref();
            t.and_then(|t| t.specular_share.get(k))
                .is_some_and(|&s| s > 0.0)
        };
        let probes: Vec<bool> = probes
            .into_iter()
            .enumerate()
            .map(|(i, closed)| closed && !shows_specular(first_new + i))
            .collect();
        solution.closed.extend(probes);
        solution.row_scale.reserve_exact(n - first_new);
        let hierarchical = self.grid.is_some();
        for k in first_new..n {
            // The flat solver sums rows in its first round only: later samples take the scale
            // of their nearest old sample. The hierarchy sums every round's rows.
            // A neighbour covered as it is: a row scale corrects the discretisation, which
            // differs under a cover and beside it.
            let s = &solution.field.samples;
            let scale = if round == 0 || hierarchical {
                1.0
            } else {
                let covered = solution.field.layout.covered();
                let old = |j: u32| (j as usize) < first_new;
                let alike = |j: u32| old(j) && covered[j as usize] == covered[k];
                (solution
                    .field
                    .layout
                    .index()
                    .nearest_where(s, s.side[k], s.uv[k], alike))
                .or_else(|| {
                    solution
                        .field
                        .layout
                        .index()
                        .nearest_where(s, s.side[k], s.uv[k], old)
                })
                .map_or(1.0, |j| solution.row_scale[j as usize])
            };
            solution.row_scale.push(scale);
        }
        Ok(())
    }

    /// The specular transfer matrix for this round's samples; the queries.
    fn specular_transfer(&mut self, solution: &mut Solution) -> Result<u64> {
        let Some(mut transfer) = solution.specular.take() else {
            return Ok(0);
        };
        let queries = if self.reporter.stopped() {
            0
        } else {
            transfer.build(self.scene, solution, self.vis)?
        };
        solution.specular = Some(transfer);
        Ok(queries)
    }

    /// Shoots (flat or clustered) with what the samples leave of the memory budget; the stats
    /// and, for the hierarchy, the seconds its links took.
    fn shoot(
        &mut self,
        solution: &mut Solution,
        round: u32,
        solution_bytes: usize,
    ) -> Result<(ShootStats, Option<f64>)> {
        let (scene, vis, options) = (self.scene, self.vis, self.options);
        let n = solution.field.samples.len();
        if self.reporter.stopped() {
            let mut stats = ShootStats::new();
            stats.stop = StopReason::Stopped;
            return Ok((stats, None));
        }
        let hierarchical = self.grid.is_some();
        let reflectances: Vec<DVec3> = (0..n)
            .map(|k| reflectance(scene, &solution.field.samples, k))
            .collect();
        let dark_emitters: Vec<f64> = solution
            .field
            .direct
            .iter()
            .map(|a| a.dark_emitters)
            .collect();
        let mut state = State {
            samples: &solution.field.samples,
            maps: solution.field.layout.maps(),
            reflectance: &reflectances,
            radiosity: &solution.field.radiosity,
            irradiance: &mut solution.field.irradiance,
            unshot: &mut solution.unshot,
            ledger: &mut solution.ledger,
            row_scale: &mut solution.row_scale,
            closed: &solution.closed,
            dark_emitters: &dark_emitters,
            specular: solution.specular.as_ref(),
            regather: (round > 0 && !self.interpolated.is_empty()).then(|| warm::Regather {
                first: n - self.interpolated.len(),
                interpolated: &self.interpolated,
            }),
        };
        let settings = Settings {
            exec: self.exec(),
            capacity: options.pipeline_capacity.max(1),
            tolerance: options.tolerance,
            max_shots: options.max_shots.unwrap_or(if hierarchical {
                u64::MAX
            } else {
                200 * n as u64
            }),
            lift: self.lift,
            memory_bytes: options.memory_budget.saturating_sub(solution_bytes),
            budget: options.memory_budget,
            normalise: round == 0 || hierarchical,
            threshold: options.cluster_threshold,
            exact_visibility: options.exact_visibility,
        };
        let mut link_seconds = None;
        let link_start = Instant::now();
        let reporter = &mut self.reporter;
        let mut report = |tick: Tick| {
            if tick.phase == Phase::Shooting && link_seconds.is_none() {
                link_seconds = Some(link_start.elapsed().as_secs_f64());
            }
            let stop = reporter.report(Progress {
                phase: tick.phase,
                round,
                items: n,
                shots: tick.shots,
                unshot_fraction: tick.unshot_fraction,
                tolerance: options.tolerance,
                fraction: tick.fraction,
                ..Progress::of(tick.phase)
            });
            if stop {
                Control::Stop
            } else {
                Control::Continue
            }
        };
        let shooting = match &self.grid {
            Some(grid) => {
                let cx = Context {
                    scene,
                    grid,
                    samples: state.samples,
                    obstruction: solution.field.layout.obstruction(),
                    pieces: solution.field.layout.pieces(),
                    lift: self.lift,
                };
                cluster::shoot(&mut state, vis, &settings, &cx, &mut report)?
            }
            None => flat::shoot(&mut state, vis, &settings, &mut report)?,
        };
        Ok((shooting, link_seconds))
    }

    /// Adds samples where the error is large (eqs. 7-8), unless told to stop.
    pub(super) fn add_samples(
        &mut self,
        solution: &mut Solution,
        round: u32,
    ) -> Result<Option<AddedSamples>> {
        let t = Instant::now();
        if self.begin(Phase::Adaptive, round, solution.field.samples.len()) {
            return Ok(None);
        }
        let options = self.options;
        let n = solution.field.samples.len();
        let radii = solution.field.samples.radius.clone();
        let base = self.base(Phase::Adaptive, round, n);
        let refinement = adaptive::refine(
            &mut solution.field.samples,
            &solution.field.layout,
            self.vis,
            &solution.field.radiosity,
            RefineSettings {
                zeta: options.zeta,
                alpha: options.alpha,
                round: round as u16,
                // Half the budget for the samples, the rest for links and caches.
                max_samples: options
                    .max_samples
                    .min(options.memory_budget / 2 / crate::budget::BYTES_PER_SAMPLE),
            },
            self.exec(),
            &mut self.reporter.part(base),
        )?;
        // A Stop heard while the errors were measured added nothing; one heard at their last
        // report may have, and the round that follows then keeps the arrays whole (its
        // phases are skipped).
        solution.field.samples.shrink_to_fit();
        let samples = &solution.field.samples;
        let mut changed = vec![false; 2 * solution.field.layout.maps().len()];
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
