//! Daylight coefficients: what each sky patch, the ground and each sun position of the lattice
//! give every grid point after the first bounce (shot through the solve's links once each),
//! and what the sky gives each point straight in, binned by patch (`docs/method.md` §24).

use glam::{DVec3, Vec3};

use super::suns;
use super::{AnnualOptions, Dome};
use crate::daylight::entering::{Entering, Escape};
use crate::error::{Error, Result};
use crate::light::DirectLight;
use crate::parallel::for_chunks;
use crate::progress::{Control, Phase, Progress, Reporter};
use crate::scene::{luminance, Grid, Scene};
use crate::solver::basis::Basis;
use crate::solver::Solution;
use crate::visibility::Visibility;

/// The altitude (degrees) of the sun that stands for lattice nodes at or below the horizon.
pub(super) const HORIZON_SUN: f64 = 0.5;

/// The subdivision the light arriving straight at grid points is binned on.
pub(super) const DIRECT_SUBDIVISION: u32 = 4;

/// The coefficients of one grid.
pub(super) struct GridCoefficients {
    pub(super) name: String,
    pub(super) points: Vec<Vec3>,
    pub(super) normal: Vec3,
    pub(super) counted: Vec<bool>,
    pub(super) target: f64,
    /// Per point, (fine patch, light) of the sky straight in; the ground's as patch `fine_len`.
    pub(super) direct: Vec<Vec<(u32, f32)>>,
    /// Per point, the light after the first bounce of each coarse patch and the ground
    /// (`coarse_len + 1` a point).
    pub(super) bounced: Vec<f32>,
    /// Per point, the light after the first bounce from the sun at each lattice node.
    pub(super) sun_bounced: Vec<f32>,
}

/// Every grid's daylight coefficients (see the module doc); `None` if the host stopped.
pub(super) fn coefficients(
    lit: &Scene,
    solution: &Solution,
    vis: &dyn Visibility,
    options: &AnnualOptions,
    dome: &Dome,
    reporter: &mut Reporter,
) -> Result<Option<Vec<GridCoefficients>>> {
    let (frame, coarse, lattice) = (&dome.frame, &dome.coarse, &dome.lattice);
    let threads = options.lux.threads.max(1);
    let seed = options.solver.seed;
    let s = &solution.field.samples;
    let n = s.len();
    let at: Vec<(Vec3, Vec3)> = (0..n).map(|k| (s.position[k], s.normal[k])).collect();
    let ids: Vec<u32> = (0..n as u32).collect();
    let bases = coarse.len() + 1 + lattice.len();
    let base = Progress {
        items: bases,
        ..Progress::of(Phase::Coefficients)
    };
    if reporter.report(base) {
        return Ok(None);
    }

    check_budget(lit, solution, options, bases)?;
    let ground = coarse.len();
    let by_patch = sky_by_patch(lit, vis, options, dome, (&at, &ids))?;

    // Each grid's light straight in (fine patches) and its gather rows.
    let grid_entering = Entering::of(lit, crate::lux::GRID_SKY_RAYS)
        .ok_or_else(|| Error::argument("scene", "no daylight to shoot"))?;
    let mut grids = Vec::new();
    let mut rows = Vec::new();
    for grid in lit.grids() {
        let (coefficients, gather) =
            grid_coefficients(lit, solution, vis, grid, &grid_entering, dome, options)?;
        grids.push(GridCoefficients {
            bounced: vec![0.0; coefficients.points.len() * (coarse.len() + 1)],
            sun_bounced: vec![0.0; coefficients.points.len() * lattice.len()],
            ..coefficients
        });
        rows.push(gather);
    }

    // Shoot each basis; keep what reaches the grid points.
    let mut stop = || reporter.stopped();
    let Some(mut shooter) = Basis::new(lit, solution, vis, &options.solver, &mut stop)? else {
        return Ok(None);
    };
    let mut sun = DirectLight::unit_sun(lit, options.solver.light_samples, Vec3::Y);
    let mut first = vec![DVec3::ZERO; n];
    for b in 0..bases {
        first.iter_mut().for_each(|f| *f = DVec3::ZERO);
        if let Some(patch) = by_patch.get(b) {
            for &(k, light) in patch {
                first[k as usize] += light.as_dvec3();
            }
        } else {
            let (altitude, azimuth) = lattice.position(b - ground - 1);
            // A node below the horizon partners suns just above it: it takes the light of a
            // sun grazing the horizon at its azimuth, not none (a low winter sun shines deep
            // into a south window). Nodes far below partner none.
            if altitude <= -suns::MAX_STEP {
                continue;
            }
            sun.aim_sun(frame.direction(altitude.max(HORIZON_SUN), azimuth));
            let mut quiet = |_: f64| Control::Continue;
            let (arrivals, _) = sun.at(vis, &at, &ids, seed, threads, &mut quiet)?;
            for (f, a) in first.iter_mut().zip(arrivals) {
                *f = a.irradiance;
            }
        }
        if first.iter().all(|f| *f == DVec3::ZERO) {
            continue;
        }
        let mut stop = || reporter.stopped();
        let (reflected, _) = shooter.reflected(&first, &mut stop)?;
        for (g, grid_rows) in grids.iter_mut().zip(&rows) {
            for (i, row) in grid_rows.iter().enumerate() {
                let e: DVec3 = row
                    .iter()
                    .map(|&(k, w)| reflected[k as usize] * w.as_dvec3())
                    .sum();
                let v = luminance(e.as_vec3());
                if b <= ground {
                    g.bounced[i * (coarse.len() + 1) + b] = v;
                } else {
                    g.sun_bounced[i * lattice.len() + (b - ground - 1)] = v;
                }
            }
        }
        if reporter.report(Progress {
            fraction: (b + 1) as f64 / bases as f64,
            ..base
        }) {
            return Ok(None);
        }
    }
    Ok(Some(grids))
}

/// The sky straight in at every sample (`at`, with its ids), binned by coarse patch (the ground
/// last): per patch, (sample, light) of every ray that leaves through it.
fn sky_by_patch(
    lit: &Scene,
    vis: &dyn Visibility,
    options: &AnnualOptions,
    dome: &Dome,
    (at, ids): (&[(Vec3, Vec3)], &[u32]),
) -> Result<Vec<Vec<(u32, Vec3)>>> {
    let (frame, coarse) = (&dome.frame, &dome.coarse);
    let (threads, seed) = (options.lux.threads.max(1), options.solver.seed);
    let n = at.len();
    let entering = Entering::of(lit, crate::solver::SKY_RAYS)
        .ok_or_else(|| Error::argument("scene", "no daylight to shoot"))?;
    let ground = coarse.len();
    // (patch, sample, light) of every ray that leaves, binned chunk by chunk.
    let mut escapes: Vec<Vec<(u32, u32, Vec3)>> = vec![Vec::new(); n.div_ceil(256)];
    for_chunks(&mut escapes, 1, threads, |c, out| {
        let range = c * 256..((c + 1) * 256).min(n);
        let (got, _) = entering.escapes(vis, &at[range.clone()], &ids[range.clone()], seed)?;
        out[0] = got
            .iter()
            .map(|e: &Escape| {
                let p = frame
                    .sky_angles(e.dir)
                    .map_or(ground, |(alt, az)| coarse.of(alt, az));
                (p as u32, e.receiver + range.start as u32, e.light.as_vec3())
            })
            .collect();
        Ok(())
    })?;
    let mut by_patch: Vec<Vec<(u32, Vec3)>> = vec![Vec::new(); coarse.len() + 1];
    for (p, k, light) in escapes.into_iter().flatten() {
        by_patch[p as usize].push((k, light));
    }

    Ok(by_patch)
}

/// Bytes a sample's sky rays may hold while they are binned by patch: every one of its rays
/// leaving (a patch, a sample and an RGB light each, twice while they are sorted).
const ESCAPE_BYTES_PER_SAMPLE: usize = 2 * 20 * crate::solver::SKY_RAYS as usize;

/// Bytes each grid point's coefficients take: one `f32` a basis, a fine patch's share of the
/// light straight in (8 bytes each, at most one a ray), and the hours' values (8 bytes an
/// hour, at most 8,784).
fn point_bytes(bases: usize) -> usize {
    4 * bases + 8 * crate::lux::GRID_SKY_RAYS as usize + 8 * 8784
}

/// Refuses a year whose coefficients would not fit what the solution leaves of the memory
/// budget, before any is allocated.
fn check_budget(
    lit: &Scene,
    solution: &Solution,
    options: &AnnualOptions,
    bases: usize,
) -> Result<()> {
    let points: usize = lit.grids().iter().map(|g| g.points().len()).sum();
    let samples = solution.field.samples.len();
    let needed = samples * ESCAPE_BYTES_PER_SAMPLE + points * point_bytes(bases);
    let budget = options.solver.memory_budget;
    let left = crate::budget::usable(budget).saturating_sub(solution.bytes());
    if needed > left {
        return Err(crate::budget::exceeded(
            budget,
            format!(
                "a year of daylight needs about {} for its coefficients ({} samples × {} bytes \
                 of sky rays, {} grid points × {} bytes of coefficients and hours) beside the \
                 solution's {}: raise the budget, choose a larger ε, or measure fewer points",
                crate::budget::human_bytes(needed as f64),
                samples,
                ESCAPE_BYTES_PER_SAMPLE,
                points,
                point_bytes(bases),
                crate::budget::human_bytes(solution.bytes() as f64)
            ),
        ));
    }
    Ok(())
}

/// A grid's points, which count, its light straight in from the sky and the ground (binned on
/// `fine`), and its gather rows.
#[allow(clippy::type_complexity)]
fn grid_coefficients(
    lit: &Scene,
    solution: &Solution,
    vis: &dyn Visibility,
    grid: &Grid,
    entering: &Entering,
    dome: &Dome,
    options: &AnnualOptions,
) -> Result<(GridCoefficients, Vec<Vec<(u32, Vec3)>>)> {
    let (frame, fine) = (&dome.frame, &dome.fine);
    let points = grid.points();
    let normal = grid.normal;
    let at: Vec<(Vec3, Vec3)> = points.iter().map(|&p| (p, normal)).collect();
    let ids: Vec<u32> = (0..points.len() as u32).collect();
    let threads = options.lux.threads.max(1);
    let mut direct: Vec<Vec<(u32, f32)>> = vec![Vec::new(); points.len()];
    for_chunks(&mut direct, 8, threads, |first, out| {
        let range = first..first + out.len();
        let (escapes, _) =
            entering.escapes(vis, &at[range.clone()], &ids[range], options.lux.seed)?;
        let mut bins: Vec<std::collections::BTreeMap<u32, f64>> =
            vec![Default::default(); out.len()];
        for e in escapes {
            let p = frame
                .sky_angles(e.dir)
                .map_or(fine.len(), |(alt, az)| fine.of(alt, az));
            *bins[e.receiver as usize].entry(p as u32).or_default() +=
                f64::from(luminance(e.light.as_vec3()));
        }
        for (o, b) in out.iter_mut().zip(bins) {
            *o = b.into_iter().map(|(p, w)| (p, w as f32)).collect();
        }
        Ok(())
    })?;
    let mut quiet = |_: f64| Control::Continue;
    let rows = crate::lux::gather_rows(lit, solution, vis, grid, &options.lux, &mut quiet)?;
    let inside = crate::lux::enclosed(lit, vis, grid)?;
    Ok((
        GridCoefficients {
            name: grid.name().to_string(),
            points,
            normal,
            counted: inside.iter().map(|&i| !i).collect(),
            target: grid.target_em().unwrap_or(super::metrics::DA_TARGET),
            direct,
            bounced: Vec::new(),
            sun_bounced: Vec::new(),
        },
        rows,
    ))
}
