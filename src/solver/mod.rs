//! The meshless solver (method.md §2): initial samples, representative areas, direct light,
//! progressive radiosity, then adaptive rounds that add samples where light changes and solve
//! again starting from the previous solution.
//!
//! Warm start: after samples are added and areas recomputed, the light already shot is taken to
//! be the old samples' shot radiosity (R − ΔB) spread over the new areas: old samples keep
//! their unshot ΔB; a new sample gets its exact direct light plus indirect light interpolated
//! from its old neighbours, and its unshot radiosity is the difference between that and the
//! shot radiosity interpolated at its place. Shooting then only carries the corrections the
//! new samples bring (mostly sharper direct light), not the whole solution again.

mod options;
pub mod shooting;

use std::time::Instant;

use glam::{DVec3, Vec3};

use crate::area::{self, AreaStats};
use crate::error::{Error, Result};
use crate::light::{Arrival, DirectLight};
use crate::parallel::for_chunks;
use crate::sampling::adaptive::{self, RefineSettings};
use crate::sampling::{
    poisson, reflecting_sides, surface_of, Obstruction, Samples, SideIndex, SurfaceMap,
};
use crate::scene::Scene;
use crate::visibility::Visibility;
pub use options::{Options, AUTO_SAMPLES};
pub use shooting::{Control, EnergyLedger, ShootStats, StopReason};

/// The phases the solver reports progress in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Phase {
    /// Placing initial samples.
    Sampling,
    /// Computing representative areas.
    Areas,
    /// Integrating direct light at the samples.
    DirectLight,
    /// Progressive shooting.
    Shooting,
    /// Adding samples where the error is large.
    Adaptive,
}

/// A progress report.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// Current phase.
    pub phase: Phase,
    /// Current round (0 = the first solve).
    pub round: u32,
    /// Samples now.
    pub samples: usize,
    /// Shots so far in this round's solve.
    pub shots: u64,
    /// Unshot power / emitted power (shooting only).
    pub unshot_fraction: f64,
    /// The tolerance the shooting aims at.
    pub tolerance: f64,
}

/// Seconds spent per phase.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhaseSeconds {
    /// Sample placement (initial or adaptive).
    pub sampling: f64,
    /// Representative areas.
    pub areas: f64,
    /// Direct light.
    pub direct: f64,
    /// Shooting.
    pub shooting: f64,
}

/// What one round did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoundStats {
    /// Round number (0 = the first solve).
    pub round: u32,
    /// Samples after this round's additions.
    pub samples: usize,
    /// Samples added this round (all of them in round 0).
    pub added: usize,
    /// Samples whose error exceeded ζ (rounds ≥ 1).
    pub refined: usize,
    /// Whether `max_samples` stopped the addition.
    pub capped: bool,
    /// Shadow-ray queries for direct light.
    pub direct_queries: u64,
    /// Area cells used.
    pub areas: AreaStats,
    /// The shooting.
    pub shooting: ShootStats,
    /// Time per phase.
    pub seconds: PhaseSeconds,
}

/// The solved samples.
#[derive(Clone, Debug)]
pub struct Solution {
    /// The samples (positions, normals, sides, radii, areas).
    pub samples: Samples,
    /// Radiosity B of each sample (W/m², RGB): emission π·Ke plus reflected light.
    pub radiosity: Vec<DVec3>,
    /// Irradiance at each sample (direct + inter-reflected).
    pub irradiance: Vec<DVec3>,
    /// Unshot radiosity left.
    pub unshot: Vec<DVec3>,
    /// Direct light at each sample.
    pub direct: Vec<Arrival>,
    /// ε used.
    pub epsilon: f32,
    /// Where ε came from.
    pub epsilon_source: EpsilonSource,
    /// Every round, in order.
    pub rounds: Vec<RoundStats>,
    /// Energy bookkeeping.
    pub ledger: EnergyLedger,
    /// The surfaces in 2D (for interpolation).
    pub maps: Vec<SurfaceMap>,
    /// Range queries over the samples.
    pub index: SideIndex,
    /// Which sides other geometry stands on.
    pub obstruction: Obstruction,
    /// Per sample: whether all its probe rays hit the scene (a closed hemisphere).
    pub closed: Vec<bool>,
    /// Per sample: the factor its received form factors are scaled by (row normalisation).
    pub row_scale: Vec<f32>,
}

/// Where ε came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum EpsilonSource {
    /// The options (command line).
    Options,
    /// The scene file's `[solver]`.
    SceneFile,
    /// Chosen from the scene's reflecting area.
    Automatic,
}

impl Solution {
    /// Why the last solve stopped.
    pub fn stop(&self) -> StopReason {
        self.rounds
            .last()
            .map_or(StopReason::NoLight, |r| r.shooting.stop)
    }

    /// Power absorbed by the surfaces: Σ (1 − ρ) H S.
    pub fn absorbed(&self, scene: &Scene) -> DVec3 {
        (0..self.samples.len())
            .map(|k| {
                let rho = reflectance(scene, &self.samples, k);
                (DVec3::ONE - rho) * self.irradiance[k] * self.samples.area[k]
            })
            .sum()
    }

    /// Power still unshot: Σ ΔB S.
    pub fn unshot_power(&self) -> DVec3 {
        self.unshot
            .iter()
            .zip(&self.samples.area)
            .map(|(&u, &a)| u * a)
            .sum()
    }
}

fn reflectance(scene: &Scene, samples: &Samples, k: usize) -> DVec3 {
    scene.material_of(surface_of(samples.side[k])).kd.as_dvec3()
}

/// The ε a solve will use, and where it came from.
pub fn choose_epsilon(scene: &Scene, options: &Options) -> Result<(f32, EpsilonSource)> {
    let (epsilon, source) = match (options.epsilon, scene.solver.epsilon) {
        (Some(e), _) => (e, EpsilonSource::Options),
        (None, Some(e)) => (e, EpsilonSource::SceneFile),
        (None, None) => {
            let area = reflecting_area(scene);
            // Poisson-disk sets reach about 0.7 / ε² samples per unit area.
            let e = (0.7 * area / AUTO_SAMPLES).sqrt() as f32;
            (
                if e > 0.0 {
                    e
                } else {
                    scene.bounds.diagonal() / 50.0
                },
                EpsilonSource::Automatic,
            )
        }
    };
    if !(epsilon.is_finite() && epsilon > 0.0) {
        return Err(Error::Option {
            option: "epsilon",
            problem: format!("{epsilon} is not a positive length"),
        });
    }
    Ok((epsilon, source))
}

fn reflecting_area(scene: &Scene) -> f64 {
    reflecting_sides(scene)
        .iter()
        .map(|&s| scene.surfaces[surface_of(s) as usize].area)
        .sum()
}

/// Predicted initial sample count for ε (upper estimate: the jamming density 0.7/ε² plus one
/// per side), to refuse a too-small ε before allocating.
pub fn predicted_samples(scene: &Scene, epsilon: f32) -> f64 {
    let sides = reflecting_sides(scene);
    0.7 * reflecting_area(scene) / f64::from(epsilon).powi(2) + sides.len() as f64
}

/// Solves a scene: see the module doc. `progress` hears every phase and every few shots, and
/// may answer [`Control::Stop`]; the solution so far is then returned.
pub fn solve(
    scene: &Scene,
    vis: &dyn Visibility,
    options: &Options,
    progress: &mut dyn FnMut(&Progress) -> Control,
) -> Result<Solution> {
    check(options)?;
    let (epsilon, epsilon_source) = choose_epsilon(scene, options)?;
    let predicted = predicted_samples(scene, epsilon);
    if predicted > options.max_samples as f64 {
        return Err(Error::Option {
            option: "epsilon",
            problem: format!(
                "ε = {epsilon} would place about {predicted:.0} samples, more than the limit of {} \
                 (raise --max-samples or choose a larger ε)",
                options.max_samples
            ),
        });
    }
    let threads = options.threads.max(1);
    let lift = crate::visibility::workload::LIFT * scene.bounds.diagonal();
    let maps = SurfaceMap::all(scene);
    let obstruction = Obstruction::new(scene, &maps, lift);
    let light = DirectLight::new(scene, options.light_samples);
    let mut report = |phase, round, samples, shots, unshot_fraction| {
        progress(&Progress {
            phase,
            round,
            samples,
            shots,
            unshot_fraction,
            tolerance: options.tolerance,
        })
    };

    // Round 0: Poisson disk on every reflecting side.
    let t = Instant::now();
    let sides = reflecting_sides(scene);
    let mut reflecting = vec![false; 2 * scene.surfaces.len()];
    for &side in &sides {
        reflecting[side as usize] = true;
    }
    let mut samples = Samples::default();
    // Stopping is honoured from the first shot on: before it there is no estimate to return.
    let _ = report(Phase::Sampling, 0, 0, 0, 1.0);
    let mut per_side: Vec<Vec<glam::Vec2>> = vec![Vec::new(); sides.len()];
    for_chunks(&mut per_side, 1, threads, |i, out| {
        let side = sides[i];
        out[0] = poisson::sample_side(
            &maps[surface_of(side) as usize],
            side,
            epsilon,
            options.seed,
        );
        Ok(())
    })?;
    for (&side, points) in sides.iter().zip(&per_side) {
        for &p in points {
            samples.push(&maps, side, p, epsilon, 0);
        }
    }
    drop(per_side);
    let sampling_seconds = t.elapsed().as_secs_f64();

    let mut solution = Solution {
        samples,
        radiosity: Vec::new(),
        irradiance: Vec::new(),
        unshot: Vec::new(),
        direct: Vec::new(),
        epsilon,
        epsilon_source,
        rounds: Vec::new(),
        ledger: EnergyLedger {
            emitted: scene.emitted_power(),
            ..EnergyLedger::default()
        },
        maps,
        index: SideIndex::default(),
        obstruction,
        closed: Vec::new(),
        row_scale: Vec::new(),
    };
    let mut added = solution.samples.len();
    let mut refined = 0;
    let mut capped = false;
    let mut sampling = sampling_seconds;
    for round in 0..=options.rounds {
        let mut seconds = PhaseSeconds {
            sampling,
            ..PhaseSeconds::default()
        };
        let n = solution.samples.len();
        let first_new = n - added;

        // Areas over all samples, old and new.
        let t = Instant::now();
        let _ = report(Phase::Areas, round, n, 0, 1.0);
        solution.index = SideIndex::new(&solution.samples, &solution.maps, epsilon);
        let area_stats = area::compute(
            &mut solution.samples,
            &solution.maps,
            &solution.index,
            &solution.obstruction,
            vis,
            epsilon,
            options.alpha,
        )?;
        seconds.areas = t.elapsed().as_secs_f64();

        // Direct light at the new samples.
        let t = Instant::now();
        let _ = report(Phase::DirectLight, round, n, 0, 1.0);
        let s = &solution.samples;
        let points: Vec<(Vec3, Vec3)> = (first_new..n)
            .map(|k| (s.position[k], s.normal[k]))
            .collect();
        let ids: Vec<u32> = (first_new as u32..n as u32).collect();
        let (arrivals, direct_queries) = light.at(vis, &points, &ids, options.seed, threads)?;
        seconds.direct = t.elapsed().as_secs_f64();

        warm_start(
            scene,
            &mut solution,
            vis,
            first_new,
            &arrivals,
            epsilon,
            options.alpha,
        )?;
        if round == 0 {
            // Direct light that reached no sample area left the scene.
            let received: DVec3 = (0..n)
                .map(|k| solution.direct[k].irradiance * solution.samples.area[k])
                .sum();
            solution.ledger.escaped += solution.ledger.emitted - received;
        }

        // Shoot.
        let t = Instant::now();
        let reflectances: Vec<DVec3> = (0..n)
            .map(|k| reflectance(scene, &solution.samples, k))
            .collect();
        let max_shots = options.max_shots.unwrap_or(200 * n as u64);
        // Which new samples see the scene all around; row scales for new samples.
        let probes = closed_hemispheres(
            scene,
            &reflecting,
            &solution.samples,
            first_new,
            vis,
            options,
            lift,
        )?;
        solution.closed.extend(probes);
        for k in first_new..n {
            let s = &solution.samples;
            let scale = if round == 0 {
                1.0
            } else {
                solution
                    .index
                    .nearest_where(s, s.side[k], s.uv[k], |j| (j as usize) < first_new)
                    .map_or(1.0, |j| solution.row_scale[j as usize])
            };
            solution.row_scale.push(scale);
        }
        let mut state = shooting::State {
            samples: &solution.samples,
            maps: &solution.maps,
            reflectance: &reflectances,
            irradiance: &mut solution.irradiance,
            unshot: &mut solution.unshot,
            ledger: &mut solution.ledger,
            row_scale: &mut solution.row_scale,
            closed: &solution.closed,
        };
        let settings = shooting::Settings {
            threads,
            tolerance: options.tolerance,
            max_shots,
            lift,
            cache_bytes: options.cache_bytes,
            prepass: round == 0,
        };
        let shoot_stats = shooting::shoot(&mut state, vis, &settings, &mut |shots, fraction| {
            report(Phase::Shooting, round, n, shots, fraction)
        })?;
        seconds.shooting = t.elapsed().as_secs_f64();
        for (k, rho) in reflectances.iter().enumerate() {
            solution.radiosity[k] =
                emission(scene, &solution.samples, k) + *rho * solution.irradiance[k];
        }
        solution.rounds.push(RoundStats {
            round,
            samples: n,
            added,
            refined,
            capped,
            direct_queries,
            areas: area_stats,
            shooting: shoot_stats,
            seconds,
        });
        if shoot_stats.stop == StopReason::Stopped || round == options.rounds || capped {
            break;
        }

        // Adaptive: add samples where the error is large.
        let t = Instant::now();
        if report(Phase::Adaptive, round + 1, n, 0, 1.0) == Control::Stop {
            break;
        }
        let refinement = adaptive::refine(
            &mut solution.samples,
            &solution.maps,
            &solution.index,
            &solution.obstruction,
            vis,
            &solution.radiosity,
            RefineSettings {
                epsilon,
                zeta: options.zeta,
                alpha: options.alpha,
                round: (round + 1) as u16,
                seed: options.seed,
                max_samples: options.max_samples,
            },
        )?;
        sampling = t.elapsed().as_secs_f64();
        added = refinement.added;
        refined = refinement.refined;
        capped = refinement.capped;
        if added == 0 {
            break;
        }
    }
    Ok(solution)
}

/// Irradiance arriving at every sample when the samples `shooters` have radiosity `source`,
/// through the same form factors and visibility the shooting uses (without its clamp): the
/// meshless transfer on its own, for tests and analysis.
pub fn transfer(
    scene: &Scene,
    solution: &Solution,
    vis: &dyn Visibility,
    shooters: &[u32],
    source: DVec3,
) -> Result<Vec<DVec3>> {
    let (samples, maps) = (&solution.samples, &solution.maps);
    let lift = crate::visibility::workload::LIFT * scene.bounds.diagonal();
    let mut irradiance = vec![DVec3::ZERO; samples.len()];
    for &j in shooters {
        for (i, f) in shooting::form_factors(samples, maps, vis, lift, j as usize)? {
            irradiance[i as usize] += source * f64::from(f);
        }
    }
    Ok(irradiance)
}

/// Probe rays per sample for [`closed_hemispheres`].
const PROBES: u32 = 32;

/// For samples `first..`, whether all of [`PROBES`] cosine-distributed (stratified) rays from
/// each hit a reflecting surface side (one that has samples): only then do the receiver's form
/// factors have to cover its whole hemisphere. A probe that escapes, or meets a black side (the
/// back of a light, say), leaves the row unnormalised. Rays, not segments: a segment ignores
/// hits near its ends, which lets a probe from a sample beside an edge slip past the
/// neighbouring face.
fn closed_hemispheres(
    scene: &Scene,
    reflecting: &[bool],
    samples: &Samples,
    first: usize,
    vis: &dyn Visibility,
    options: &Options,
    lift: f32,
) -> Result<Vec<bool>> {
    use rand::{RngExt, SeedableRng};
    let (seed, threads, diagonal) = (
        options.seed,
        options.threads.max(1),
        scene.bounds.diagonal(),
    );
    let mut out = vec![true; samples.len() - first];
    for_chunks(&mut out, 128, threads, |start, chunk| {
        let mut rays = Vec::with_capacity(chunk.len() * PROBES as usize);
        for k in first + start..first + start + chunk.len() {
            let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(poisson::side_seed(seed, k as u32, 11));
            let n = samples.normal[k];
            let (t, b) = n.any_orthonormal_pair();
            let from = samples.position[k] + lift * n;
            let rows = PROBES / 4;
            for i in 0..PROBES {
                // Stratified over (radius², angle): cosine-weighted directions.
                let u = ((i / 4) as f32 + rng.random::<f32>()) / rows as f32;
                let v = ((i % 4) as f32 + rng.random::<f32>()) / 4.0;
                let (r, phi) = (u.sqrt(), v * std::f32::consts::TAU);
                let d = t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u).max(0.0).sqrt();
                rays.push(crate::visibility::Ray {
                    origin: from,
                    dir: d,
                    t_min: 0.0,
                    t_max: 2.0 * diagonal,
                });
            }
        }
        let mut hits = vec![None; rays.len()];
        vis.intersect(&rays, &mut hits)?;
        for ((o, hits), rays) in chunk
            .iter_mut()
            .zip(hits.chunks(PROBES as usize))
            .zip(rays.chunks(PROBES as usize))
        {
            *o = hits.iter().zip(rays).all(|(hit, ray)| {
                hit.is_some_and(|h| {
                    let t = &scene.triangles[h.triangle as usize];
                    let side = crate::sampling::side_of(t.surface, ray.dir.dot(t.normal) > 0.0);
                    reflecting[side as usize]
                })
            });
        }
        Ok(())
    })?;
    Ok(out)
}

fn check(options: &Options) -> Result<()> {
    let fail = |option, problem: String| Err(Error::Option { option, problem });
    if !(options.alpha.is_finite() && options.alpha >= 0.0) {
        return fail(
            "alpha",
            format!("{} must be a finite number ≥ 0", options.alpha),
        );
    }
    if !(options.zeta.is_finite() && options.zeta > 0.0) {
        return fail(
            "zeta",
            format!("{} must be a positive number", options.zeta),
        );
    }
    if !(options.tolerance.is_finite() && options.tolerance > 0.0 && options.tolerance < 1.0) {
        return fail(
            "tolerance",
            format!("{} must lie in (0, 1)", options.tolerance),
        );
    }
    if options.light_samples == 0 {
        return fail("light-samples", "must be at least 1".into());
    }
    Ok(())
}

/// Emitted radiosity π·Ke of sample k (emitters emit from their front only).
fn emission(scene: &Scene, samples: &Samples, k: usize) -> DVec3 {
    let side = samples.side[k];
    if crate::sampling::is_back(side) {
        return DVec3::ZERO;
    }
    std::f64::consts::PI * scene.material_of(surface_of(side)).ke.as_dvec3()
}

/// Extends the solution's per-sample arrays to the new samples and sets their unshot
/// radiosity for a (warm) start: see the module doc.
fn warm_start(
    scene: &Scene,
    solution: &mut Solution,
    vis: &dyn Visibility,
    first_new: usize,
    arrivals: &[Arrival],
    epsilon: f32,
    alpha: f32,
) -> Result<()> {
    let n = solution.samples.len();
    let samples = &solution.samples;
    let mut near = Vec::new();
    let r = 2.0 * epsilon;
    for (a, k) in arrivals.iter().zip(first_new..n) {
        let rho = reflectance(scene, samples, k);
        // Interpolated from the old samples: indirect irradiance, and radiosity already shot.
        let (mut wsum, mut indirect, mut shot) = (0.0, DVec3::ZERO, DVec3::ZERO);
        if first_new > 0 {
            solution
                .index
                .within(samples, samples.side[k], samples.uv[k], r, &mut near);
            near.retain(|&(j, _)| (j as usize) < first_new);
            near.sort_unstable_by_key(|&(j, _)| j);
            let side = samples.side[k];
            solution.obstruction.retain_visible(
                vis,
                &solution.maps,
                samples,
                side,
                samples.position[k],
                &mut near,
            )?;
            for &(j, d2) in &near {
                let j = j as usize;
                let w = f64::from((-alpha * d2.sqrt() / r).exp());
                wsum += w;
                indirect += w * (solution.irradiance[j] - solution.direct[j].irradiance);
                shot += w * (rho * solution.irradiance[j] - solution.unshot[j]);
            }
        }
        if wsum > 0.0 {
            indirect /= wsum;
            shot /= wsum;
        }
        let h = a.irradiance + indirect;
        solution.direct.push(*a);
        solution.irradiance.push(h);
        solution.unshot.push(rho * h - shot);
        solution
            .radiosity
            .push(emission(scene, samples, k) + rho * h);
    }
    debug_assert_eq!(solution.irradiance.len(), n);
    Ok(())
}
