//! A year of daylight (scene-format v4, "A year of weather"; `docs/method.md` §24): every hour
//! of a weather file's year at a scene's grids, and the climate-based metrics of those hours.
//!
//! Radiosity is linear in its sources, so the year is one solve and a sum per hour:
//! - the samples are placed and their areas, links and row scales found once, under an
//!   overcast sky (`solve`);
//! - **daylight coefficients**: the sky is cut into Reinhart's patches (`[annual]`'s
//!   `sky_subdivision`) plus the ground; the light each patch of unit luminance sends straight
//!   in at every sample (the rays of `daylight::entering`, binned by patch) is shot through the
//!   solve's links once (`solver::basis`), and what reaches each grid point after the first
//!   bounce is kept, one number a point and patch;
//! - the same for the sun at the nodes of a lattice over its paths (`suns`), interpolated
//!   between nodes at each hour's sun;
//! - the light arriving straight at a grid point is not interpolated: the sky's and the
//!   ground's through the grid's own rays binned on a finer subdivision (MF:4), the sun's by
//!   shadow rays to its disc at each hour's true position;
//! - each hour: its Perez sky's patch luminances (means over each patch) times the
//!   coefficients, plus its sun.
//!
//! Lamps are not daylight: a year counts the sky, the ground and the sun only.

pub mod metrics;
mod suns;

use glam::{DVec3, Vec3};

use crate::daylight::entering::{Entering, Escape};
use crate::daylight::epw::Weather;
use crate::daylight::patches::Patches;
use crate::daylight::spa::{delta_t, sun_position, LocalTime, Observer};
use crate::daylight::{AnnualSettings, Sky, SkyModel};
use crate::error::{Error, Result};
use crate::light::DirectLight;
use crate::lux::LuxOptions;
use crate::parallel::for_chunks;
use crate::progress::{Callback, Control, Phase, Progress, Reporter};
use crate::scene::{luminance, Grid, Scene};
use crate::solver::basis::Basis;
use crate::solver::{Options, Solution, StopReason};
use crate::visibility::Visibility;
use metrics::Tally;
pub use metrics::{GridSummary, PointYear};
use suns::SunLattice;

/// Sun positions whose inter-reflected light is shot (the lattice's nodes, those below the
/// horizon skipped).
pub const SUN_POSITIONS: usize = suns::NODES;

/// The altitude (degrees) of the sun that stands for lattice nodes at or below the horizon.
const HORIZON_SUN: f64 = 0.5;

/// The subdivision the light arriving straight at grid points is binned on.
const DIRECT_SUBDIVISION: u32 = 4;

/// How a year is computed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AnnualOptions {
    /// The solve the coefficients are shot through.
    pub solver: Options,
    /// The grid points' rays (shadow rays to the sun, seed, threads).
    pub lux: LuxOptions,
    /// Keep every hour's illuminance at every point ([`GridYear::hourly`]).
    pub hourly: bool,
}

/// One hour of the year: its EPW month, day and hour (1-24).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HourStamp {
    /// 1-12.
    pub month: u32,
    /// 1-31.
    pub day: u32,
    /// 1-24: the hour ending at `hour`:00 local standard time.
    pub hour: u32,
}

/// A year at one grid.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct GridYear {
    /// The grid's name.
    pub name: String,
    /// Its points.
    pub points: Vec<Vec3>,
    /// Per point, its metrics (`None` inside a solid).
    pub metrics: Vec<Option<PointYear>>,
    /// The grid's metrics.
    pub summary: GridSummary,
    /// With [`AnnualOptions::hourly`]: the illuminance (lx) at every point in every hour of
    /// [`Year::sun_hours`], hour by hour (`points.len()` values each); else empty.
    pub hourly: Vec<f32>,
}

/// A year of daylight at a scene's grids.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Year {
    /// Per grid, in the scene's order.
    pub grids: Vec<GridYear>,
    /// The hours with the sun up and weather to light them, in the file's order.
    pub sun_hours: Vec<HourStamp>,
    /// Hours with the sun up but no usable diffuse light in the file: left out of the metrics.
    pub left_out: usize,
    /// The solve the coefficients were shot through.
    pub samples: usize,
    /// Sky patches (and the ground) and sun positions shot.
    pub bases: usize,
    /// Bytes the coefficients hold.
    pub coefficient_bytes: usize,
    /// Whether the host stopped the call (the metrics then count the hours done).
    pub stopped: bool,
}

/// The site as a year sees it.
struct Frame {
    latitude: f64,
    longitude: f64,
    timezone: f64,
    up: DVec3,
    north: DVec3,
    east: DVec3,
    ground_reflectance: f64,
}

impl Frame {
    /// (altitude, azimuth) in degrees of a scene direction; `None` below the horizon.
    fn sky_angles(&self, dir: Vec3) -> Option<(f64, f64)> {
        let d = dir.as_dvec3().normalize_or_zero();
        let up = d.dot(self.up);
        (up > 0.0).then(|| {
            (
                up.min(1.0).asin().to_degrees(),
                d.dot(self.east)
                    .atan2(d.dot(self.north))
                    .to_degrees()
                    .rem_euclid(360.0),
            )
        })
    }

    /// The scene direction of (altitude, azimuth) in degrees.
    fn direction(&self, altitude: f64, azimuth: f64) -> Vec3 {
        let (a, z) = (altitude.to_radians(), azimuth.to_radians());
        (self.up * a.sin() + (self.north * z.cos() + self.east * z.sin()) * a.cos()).as_vec3()
    }
}

/// One hour's light from the weather file.
#[derive(Clone, Debug)]
struct Hour {
    stamp: HourStamp,
    occupied: bool,
    /// The sun's zenith and azimuth (degrees) when it is up.
    sun: Option<(f64, f64)>,
    /// Direct normal and diffuse horizontal illuminance (lx), when the sun is up and the file
    /// gives them.
    light: Option<(f64, f64)>,
    day_of_year: u32,
}

/// Every hour of `weather` at `frame`: the sun's place at the middle of the hour (EPW hour h
/// covers (h−1):00 to h:00 local standard time) and its light.
fn hours(weather: &Weather, frame: &Frame, settings: &AnnualSettings) -> Vec<Hour> {
    let observer = Observer {
        latitude: frame.latitude,
        longitude: frame.longitude,
        elevation: 0.0,
        pressure: 1010.0,
        temperature: 10.0,
    };
    let (start, end) = settings.hours;
    weather
        .hours
        .iter()
        .map(|w| {
            let time = LocalTime {
                year: w.year,
                month: w.month,
                day: w.day,
                hour: w.hour - 1,
                minute: 30,
                second: 0.0,
                timezone: frame.timezone,
            };
            let year = f64::from(w.year) + (f64::from(w.month) - 0.5) / 12.0;
            let sun = sun_position(&time, &observer, delta_t(year));
            let day_of_year = crate::daylight::day_of_year(w.year, w.month, w.day);
            let up = sun.zenith < 90.0;
            Hour {
                stamp: HourStamp {
                    month: w.month,
                    day: w.day,
                    hour: w.hour,
                },
                occupied: start < w.hour && w.hour <= end,
                sun: up.then_some((sun.zenith, sun.azimuth)),
                light: if up {
                    w.illuminance(sun.zenith, day_of_year)
                        .filter(|&(_, dh)| dh > 0.0)
                } else {
                    None
                },
                day_of_year,
            }
        })
        .collect()
}

/// Points on the sky at which an hour's luminance is taken: 2 × 2 per patch of the fine
/// subdivision (equal solid angles), each with its fine and coarse patch.
struct SkyPoints {
    /// (zenith angle, azimuth) in radians.
    angles: Vec<(f64, f64)>,
    /// cos θ × dω of each point.
    cos_solid: Vec<f64>,
    fine: Vec<u32>,
    coarse: Vec<u32>,
    fine_len: usize,
    coarse_len: usize,
    /// Σ dω of each coarse patch's points.
    coarse_solid: Vec<f64>,
}

impl SkyPoints {
    fn new(fine: &Patches, coarse: &Patches) -> SkyPoints {
        let mut p = SkyPoints {
            angles: Vec::new(),
            cos_solid: Vec::new(),
            fine: Vec::new(),
            coarse: Vec::new(),
            fine_len: fine.len(),
            coarse_len: coarse.len(),
            coarse_solid: vec![0.0; coarse.len()],
        };
        for (f, ((low, high), (a, b))) in fine.bounds().into_iter().enumerate() {
            let (s0, s1) = (low.to_radians().sin(), high.to_radians().sin());
            let solid = (s1 - s0) * (b - a).to_radians() / 4.0;
            for i in 0..2 {
                // Uniform in sin(altitude): equal solid angles.
                let s = s0 + (s1 - s0) * (i as f64 + 0.5) / 2.0;
                let alt = s.asin().to_degrees();
                for j in 0..2 {
                    let az = a + (b - a) * (j as f64 + 0.5) / 2.0;
                    let c = coarse.of(alt, az);
                    p.angles.push(((90.0 - alt).to_radians(), az.to_radians()));
                    p.cos_solid.push(s * solid);
                    p.fine.push(f as u32);
                    p.coarse.push(c as u32);
                    p.coarse_solid[c] += solid;
                }
            }
        }
        p
    }

    /// An hour's mean luminance over each fine and each coarse patch, its sky scaled to
    /// `diffuse_horizontal` over these points.
    fn luminances(&self, sky: &Sky, diffuse_horizontal: f64) -> (Vec<f64>, Vec<f64>) {
        let shape: Vec<f64> = self
            .angles
            .iter()
            .map(|&(t, p)| sky.luminance(t, p))
            .collect();
        let horizontal: f64 = shape.iter().zip(&self.cos_solid).map(|(l, w)| l * w).sum();
        let scale = if horizontal > 0.0 {
            diffuse_horizontal / horizontal
        } else {
            0.0
        };
        let (mut fine, mut coarse) = (vec![0.0; self.fine_len], vec![0.0; self.coarse_len]);
        for (i, l) in shape.iter().enumerate() {
            fine[self.fine[i] as usize] += scale * l / 4.0;
            coarse[self.coarse[i] as usize] += scale * l;
        }
        // Each point of a coarse patch stands for the same solid angle: the mean is the sum
        // over the count, which is Σ dω / dω.
        let counts = self.coarse_counts();
        for (c, n) in coarse.iter_mut().zip(counts) {
            if n > 0 {
                *c /= n as f64;
            }
        }
        (fine, coarse)
    }

    fn coarse_counts(&self) -> Vec<usize> {
        let mut counts = vec![0; self.coarse_len];
        for &c in &self.coarse {
            counts[c as usize] += 1;
        }
        counts
    }
}

/// The coefficients of one grid.
struct GridCoefficients {
    points: Vec<Vec3>,
    normal: Vec3,
    counted: Vec<bool>,
    target: f64,
    /// Per point, (fine patch, light) of the sky straight in; the ground's as patch `fine_len`.
    direct: Vec<Vec<(u32, f32)>>,
    /// Per point, the light after the first bounce of each coarse patch and the ground
    /// (`coarse_len + 1` a point).
    bounced: Vec<f32>,
    /// Per point, the light after the first bounce from the sun at each lattice node.
    sun_bounced: Vec<f32>,
}

/// A year of daylight at `scene`'s grids under `weather` (see the module doc). `progress`
/// hears the solve's phases, then [`Phase::Coefficients`] and [`Phase::Hours`], and may stop
/// the call: the year then counts the hours done.
pub fn annual(
    scene: &Scene,
    weather: &Weather,
    vis: &dyn Visibility,
    options: &AnnualOptions,
    progress: Callback,
) -> Result<Year> {
    crate::parallel::guarded("the annual run", || {
        let checked = crate::visibility::Checked::new(vis, scene);
        let vis: &dyn Visibility = &checked;
        run(scene, weather, vis, options, progress)
    })
}

fn run(
    scene: &Scene,
    weather: &Weather,
    vis: &dyn Visibility,
    options: &AnnualOptions,
    progress: Callback,
) -> Result<Year> {
    let Some(settings) = scene.annual() else {
        return Err(Error::argument(
            "scene",
            format!(
                "{} has no [annual]: a year of weather needs its weather file",
                scene.path().display()
            ),
        ));
    };
    if scene.grids().is_empty() {
        return Err(Error::argument(
            "scene",
            format!(
                "{} has no [[grid]]: a year is measured at grid points",
                scene.path().display()
            ),
        ));
    }
    let site = &settings.site;
    let up = site.up.as_dvec3().normalize_or_zero();
    let north = site.north.as_dvec3();
    let north = (north - up * north.dot(up)).normalize_or_zero();
    let frame = Frame {
        latitude: site.latitude.unwrap_or(weather.site.latitude),
        longitude: site.longitude.unwrap_or(weather.site.longitude),
        timezone: site.timezone.unwrap_or(weather.site.timezone),
        up,
        north,
        east: north.cross(up),
        ground_reflectance: site.ground_reflectance,
    };
    let hours = hours(weather, &frame, settings);

    // The solve, under an overcast sky: samples, areas, links, row scales.
    let mut lit = scene.clone();
    lit.set_daylight(Some(settings.overcast()?));
    let lit = &lit;
    let solution = crate::solver::solve(lit, vis, &options.solver, &mut *progress)?;
    let mut year = Year {
        grids: Vec::new(),
        sun_hours: Vec::new(),
        left_out: 0,
        samples: solution.samples.len(),
        bases: 0,
        coefficient_bytes: 0,
        stopped: solution.stop() == StopReason::Stopped,
    };
    let mut reporter = Reporter::new(progress);
    if year.stopped {
        return Ok(year);
    }

    let coarse = Patches::new(settings.sky_subdivision);
    let fine = Patches::new(settings.sky_subdivision.max(DIRECT_SUBDIVISION));
    let lattice = SunLattice::new(frame.latitude);
    let sky = SkyPoints::new(&fine, &coarse);
    let Some(grids) = coefficients(
        lit,
        &solution,
        vis,
        options,
        (&frame, &coarse, &fine, &lattice),
        &mut reporter,
    )?
    else {
        year.stopped = true;
        return Ok(year);
    };
    year.bases = coarse.len() + 1 + lattice.len();
    year.coefficient_bytes = grids
        .iter()
        .map(|g| {
            4 * (g.bounced.len() + g.sun_bounced.len())
                + g.direct.iter().map(|d| 8 * d.len()).sum::<usize>()
        })
        .sum();

    // Every hour with the sun up and weather to light it.
    let lit_hours: Vec<usize> = (0..hours.len())
        .filter(|&h| hours[h].sun.is_some() && hours[h].light.is_some())
        .collect();
    year.left_out = hours
        .iter()
        .filter(|h| h.sun.is_some() && h.light.is_none())
        .count();
    let mut values: Vec<Vec<(Vec<f32>, Vec<f32>)>> = vec![Vec::new(); lit_hours.len()];
    let base = Progress {
        items: lit_hours.len(),
        ..Progress::of(Phase::Hours)
    };
    let finished = if reporter.report(base) {
        false
    } else {
        let work = |first: usize, out: &mut [Vec<(Vec<f32>, Vec<f32>)>]| {
            let mut sun = DirectLight::unit_sun(lit, options.lux.light_samples, Vec3::Y);
            for (o, &h) in out.iter_mut().zip(&lit_hours[first..]) {
                *o = hour_values(
                    &hours[h],
                    &grids,
                    (&frame, &sky, &lattice),
                    &mut sun,
                    vis,
                    &options.lux,
                )?;
            }
            Ok(())
        };
        let threads = options.lux.threads.max(1);
        crate::parallel::for_chunks_reporting(
            &mut values,
            16,
            threads,
            work,
            &mut reporter.part(base),
        )?
    };
    let done = if finished {
        values.len()
    } else {
        year.stopped = true;
        values.iter().take_while(|v| !v.is_empty()).count()
    };

    // The metrics, hour by hour in the file's order.
    let mut tallies: Vec<Tally> = grids
        .iter()
        .map(|g| Tally::new(g.counted.clone(), g.target))
        .collect();
    let mut hourly: Vec<Vec<f32>> = vec![Vec::new(); grids.len()];
    let mut next = 0;
    let lit_done = &lit_hours[..done];
    // A stopped year counts the hours up to the first not done.
    let limit = lit_hours.get(done).copied().unwrap_or(hours.len());
    for (h, hour) in hours.iter().enumerate().take(limit) {
        if next < lit_done.len() && lit_done[next] == h {
            year.sun_hours.push(hour.stamp);
            for (g, (e, s)) in values[next].iter().enumerate() {
                let e64: Vec<f64> = e.iter().map(|&v| f64::from(v)).collect();
                let s64: Vec<f64> = s.iter().map(|&v| f64::from(v)).collect();
                tallies[g].add(&e64, &s64, hour.occupied, true);
                if options.hourly {
                    hourly[g].extend_from_slice(e);
                }
            }
            next += 1;
        } else if hour.sun.is_none() {
            // Night: dark, and occupied hours in the dark count against autonomy.
            for (g, t) in tallies.iter_mut().enumerate() {
                let n = grids[g].points.len();
                t.add(&vec![0.0; n], &vec![0.0; n], hour.occupied, false);
            }
        }
    }
    for ((g, tally), hourly) in grids.iter().zip(&tallies).zip(hourly) {
        let (metrics, summary) = tally.finish();
        year.grids.push(GridYear {
            name: g.name.clone(),
            points: g.points.clone(),
            metrics,
            summary,
            hourly,
        });
    }
    Ok(year)
}

/// One hour's illuminance and direct sunlight (lx) at every grid's points.
fn hour_values(
    hour: &Hour,
    grids: &[GridNamed],
    (frame, sky_points, lattice): (&Frame, &SkyPoints, &SunLattice),
    sun_light: &mut DirectLight,
    vis: &dyn Visibility,
    lux: &LuxOptions,
) -> Result<Vec<(Vec<f32>, Vec<f32>)>> {
    let (Some((zenith, azimuth)), Some((dn, dh))) = (hour.sun, hour.light) else {
        return Ok(Vec::new());
    };
    let (clearness, brightness) =
        crate::daylight::sky::perez_parameters(dh, dn, zenith.min(90.0), Some(hour.day_of_year));
    let shape = Sky::unscaled(
        SkyModel::Perez {
            clearness,
            brightness,
        },
        zenith,
        azimuth,
    )?;
    let (fine, coarse) = sky_points.luminances(&shape, dh);
    let ground = frame.ground_reflectance * (dh + dn * zenith.to_radians().cos().max(0.0))
        / std::f64::consts::PI;
    let altitude = 90.0 - zenith;
    let around = lattice.around(altitude, azimuth);
    sun_light.aim_sun(frame.direction(altitude, azimuth));
    let mut out = Vec::with_capacity(grids.len());
    for g in grids {
        let n = g.points.len();
        let at: Vec<(Vec3, Vec3)> = g.points.iter().map(|&p| (p, g.normal)).collect();
        let ids: Vec<u32> = (0..n as u32).collect();
        let mut quiet = |_: f64| Control::Continue;
        let sun_direct = if dn > 0.0 {
            let (arrivals, _) = sun_light.at(vis, &at, &ids, lux.seed, 1, &mut quiet)?;
            arrivals
                .iter()
                .map(|a| dn * f64::from(luminance(a.irradiance.as_vec3())))
                .collect()
        } else {
            vec![0.0; n]
        };
        let stride = coarse.len() + 1;
        let mut e = Vec::with_capacity(n);
        for (i, &sun) in sun_direct.iter().enumerate() {
            let mut v = sun;
            for &(f, w) in &g.direct[i] {
                let l = fine.get(f as usize).copied().unwrap_or(ground);
                v += f64::from(w) * l;
            }
            let bounced = &g.bounced[i * stride..(i + 1) * stride];
            v += bounced[..coarse.len()]
                .iter()
                .zip(&coarse)
                .map(|(&c, &l)| f64::from(c) * l)
                .sum::<f64>();
            v += f64::from(bounced[coarse.len()]) * ground;
            let suns = &g.sun_bounced[i * lattice.len()..(i + 1) * lattice.len()];
            v += dn
                * around
                    .iter()
                    .map(|&(node, w)| w * f64::from(suns[node]))
                    .sum::<f64>();
            e.push(v as f32);
        }
        out.push((e, sun_direct.iter().map(|&s| s as f32).collect()));
    }
    Ok(out)
}

/// A grid's coefficients with its name.
struct GridNamed {
    name: String,
    coefficients: GridCoefficients,
}

impl std::ops::Deref for GridNamed {
    type Target = GridCoefficients;
    fn deref(&self) -> &GridCoefficients {
        &self.coefficients
    }
}

/// Every grid's daylight coefficients (see the module doc); `None` if the host stopped.
fn coefficients(
    lit: &Scene,
    solution: &Solution,
    vis: &dyn Visibility,
    options: &AnnualOptions,
    (frame, coarse, fine, lattice): (&Frame, &Patches, &Patches, &SunLattice),
    reporter: &mut Reporter,
) -> Result<Option<Vec<GridNamed>>> {
    let threads = options.lux.threads.max(1);
    let seed = options.solver.seed;
    let s = &solution.samples;
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

    // The sky straight in at every sample, by coarse patch (the ground last).
    let entering = Entering::of(lit, crate::solver::SKY_RAYS)
        .ok_or_else(|| Error::argument("scene", "no daylight to shoot"))?;
    let ground = coarse.len();
    check_budget(lit, solution, options, coarse.len() + 1 + lattice.len())?;
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

    // Each grid's light straight in (fine patches) and its gather rows.
    let grid_entering = Entering::of(lit, crate::lux::GRID_SKY_RAYS)
        .ok_or_else(|| Error::argument("scene", "no daylight to shoot"))?;
    let mut grids = Vec::new();
    let mut rows = Vec::new();
    for grid in lit.grids() {
        let (coefficients, gather) = grid_coefficients(
            lit,
            solution,
            vis,
            grid,
            &grid_entering,
            (frame, fine),
            options,
        )?;
        grids.push(GridNamed {
            name: grid.name().to_string(),
            coefficients: GridCoefficients {
                bounced: vec![0.0; coefficients.points.len() * (coarse.len() + 1)],
                sun_bounced: vec![0.0; coefficients.points.len() * lattice.len()],
                ..coefficients
            },
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
                    g.coefficients.bounced[i * (coarse.len() + 1) + b] = v;
                } else {
                    g.coefficients.sun_bounced[i * lattice.len() + (b - ground - 1)] = v;
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
    let samples = solution.samples.len();
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
    (frame, fine): (&Frame, &Patches),
    options: &AnnualOptions,
) -> Result<(GridCoefficients, Vec<Vec<(u32, Vec3)>>)> {
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
            points,
            normal,
            counted: inside.iter().map(|&i| !i).collect(),
            target: grid.target_em().unwrap_or(metrics::DA_TARGET),
            direct,
            bounced: Vec::new(),
            sun_bounced: Vec::new(),
        },
        rows,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_hours_sky_scaled_on_its_points_matches_the_skys_own_integral() {
        // The year scales each hour's sky on 9,220 points; a one-moment sky on 259,200 cells.
        let sky_points = SkyPoints::new(&Patches::new(4), &Patches::new(1));
        let mut worst: f64 = 0.0;
        for (dn, dh, zenith, azimuth) in [
            (60_000.0, 10_000.0, 30.0, 180.0),
            (20_000.0, 25_000.0, 70.0, 100.0),
            (0.0, 15_000.0, 50.0, 250.0),
            (80_000.0, 8_000.0, 85.0, 280.0),
        ] {
            let (clearness, brightness) =
                crate::daylight::sky::perez_parameters(dh, dn, zenith, Some(172));
            let model = SkyModel::Perez {
                clearness,
                brightness,
            };
            let exact = Sky::new(model, zenith, azimuth, dh).unwrap();
            let shape = Sky::unscaled(model, zenith, azimuth).unwrap();
            let (fine, _) = sky_points.luminances(&shape, dh);
            // The zenith patch's mean, against the exact sky's over the same 4 points.
            let zenith_patch = fine.len() - 1;
            let mean_exact: f64 = (0..sky_points.angles.len())
                .filter(|&i| sky_points.fine[i] as usize == zenith_patch)
                .map(|i| {
                    let (t, p) = sky_points.angles[i];
                    exact.luminance(t, p) / 4.0
                })
                .sum();
            worst = worst.max((fine[zenith_patch] / mean_exact - 1.0).abs());
        }
        assert!(worst < 1e-3, "{worst}");
    }
}
