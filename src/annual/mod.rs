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

mod coefficients;
mod hours;
pub mod metrics;
mod suns;

use glam::{DVec3, Vec3};

use crate::daylight::epw::Weather;
use crate::daylight::patches::Patches;
use crate::daylight::AnnualSettings;
use crate::error::{Error, Result};
use crate::light::DirectLight;
use crate::lux::LuxOptions;
use crate::progress::{Callback, Phase, Progress, Reporter};
use crate::scene::Scene;
use crate::solver::{Options, StopReason};
use crate::visibility::Visibility;
use coefficients::{coefficients, DIRECT_SUBDIVISION};
use hours::{hour_values, hours, SkyPoints};
use metrics::Tally;
pub use metrics::{GridSummary, PointYear};
use suns::SunLattice;

/// Sun positions whose inter-reflected light is shot (the lattice's nodes, those below the
/// horizon skipped).
pub const SUN_POSITIONS: usize = suns::NODES;

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
    /// The site of `settings`, each figure it leaves out taken from the weather file.
    fn of(settings: &AnnualSettings, weather: &Weather) -> Frame {
        let site = &settings.site;
        let up = site.up.as_dvec3().normalize_or_zero();
        let north = site.north.as_dvec3();
        let north = (north - up * north.dot(up)).normalize_or_zero();
        Frame {
            latitude: site.latitude.unwrap_or(weather.site.latitude),
            longitude: site.longitude.unwrap_or(weather.site.longitude),
            timezone: site.timezone.unwrap_or(weather.site.timezone),
            up,
            north,
            east: north.cross(up),
            ground_reflectance: site.ground_reflectance,
        }
    }

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
    let settings = settings_of(scene)?;
    let dome = Dome::new(Frame::of(settings, weather), settings.sky_subdivision);
    let hours = hours(weather, &dome.frame, settings);
    // The solve, under an overcast sky: samples, areas, links, row scales.
    let mut lit = scene.clone();
    lit.set_daylight(Some(settings.overcast()?));
    let lit = &lit;
    let solution = crate::solver::solve(lit, vis, &options.solver, &mut *progress)?;
    let mut year = Year {
        grids: Vec::new(),
        sun_hours: Vec::new(),
        left_out: 0,
        samples: solution.field.samples.len(),
        bases: 0,
        coefficient_bytes: 0,
        stopped: solution.stop() == StopReason::Stopped,
    };
    let mut reporter = Reporter::new(progress);
    if year.stopped {
        return Ok(year);
    }
    let Some(grids) = coefficients(lit, &solution, vis, options, &dome, &mut reporter)? else {
        year.stopped = true;
        return Ok(year);
    };
    year.bases = dome.coarse.len() + 1 + dome.lattice.len();
    year.coefficient_bytes = grids
        .iter()
        .map(|g| {
            4 * (g.bounced.len() + g.sun_bounced.len())
                + g.direct.iter().map(|d| 8 * d.len()).sum::<usize>()
        })
        .sum();
    year.left_out = hours
        .iter()
        .filter(|h| h.sun.is_some() && h.light.is_none())
        .count();
    let lighting = Lighting {
        lit,
        vis,
        grids: &grids,
        dome: &dome,
        options,
    };
    let (lit_hours, values, finished) = lighting.hours(&hours, &mut reporter)?;
    let done = if finished {
        values.len()
    } else {
        year.stopped = true;
        values.iter().take_while(|v| !v.is_empty()).count()
    };
    // A stopped year counts the hours up to the first lit one not done.
    let limit = lit_hours.get(done).copied().unwrap_or(hours.len());
    tally(
        &mut year,
        &hours[..limit],
        &lit_hours[..done],
        &values,
        &grids,
        options.hourly,
    );
    Ok(year)
}

/// The scene's `[annual]`, where it has one and grids to measure it at.
fn settings_of(scene: &Scene) -> Result<&AnnualSettings> {
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
    Ok(settings)
}

/// The sky as a year of weather divides it: the site's frame, the coarse patches the
/// coefficients are taken on, the fine ones the light straight in is binned on, the sun
/// lattice, and the points each hour's sky is read at.
struct Dome {
    frame: Frame,
    coarse: Patches,
    fine: Patches,
    lattice: SunLattice,
    points: SkyPoints,
}

impl Dome {
    fn new(frame: Frame, subdivision: u32) -> Dome {
        let coarse = Patches::new(subdivision);
        let fine = Patches::new(subdivision.max(DIRECT_SUBDIVISION));
        let lattice = SunLattice::new(frame.latitude);
        let points = SkyPoints::new(&fine, &coarse);
        Dome {
            frame,
            coarse,
            fine,
            lattice,
            points,
        }
    }
}

/// What lighting the year's hours takes.
struct Lighting<'a> {
    lit: &'a Scene,
    vis: &'a dyn Visibility,
    grids: &'a [coefficients::GridCoefficients],
    dome: &'a Dome,
    options: &'a AnnualOptions,
}

/// One hour's illuminance and direct sunlight at each grid's points.
type HourValues = Vec<(Vec<f32>, Vec<f32>)>;

impl Lighting<'_> {
    /// Every hour with the sun up and weather to light it: which hours, their values (empty
    /// where a Stop left them undone) and whether all were done.
    fn hours(
        &self,
        hours: &[hours::Hour],
        reporter: &mut Reporter,
    ) -> Result<(Vec<usize>, Vec<HourValues>, bool)> {
        let lit_hours: Vec<usize> = (0..hours.len())
            .filter(|&h| hours[h].sun.is_some() && hours[h].light.is_some())
            .collect();
        let mut values: Vec<HourValues> = vec![Vec::new(); lit_hours.len()];
        let base = Progress {
            items: lit_hours.len(),
            ..Progress::of(Phase::Hours)
        };
        if reporter.report(base) {
            return Ok((lit_hours, values, false));
        }
        let options = self.options;
        let work = |first: usize, out: &mut [HourValues]| {
            let mut sun = DirectLight::unit_sun(self.lit, options.lux.light_samples, Vec3::Y);
            for (o, &h) in out.iter_mut().zip(&lit_hours[first..]) {
                *o = hour_values(
                    &hours[h],
                    self.grids,
                    self.dome,
                    &mut sun,
                    self.vis,
                    &options.lux,
                )?;
            }
            Ok(())
        };
        let threads = options.lux.threads.max(1);
        let finished = crate::parallel::for_chunks_reporting(
            &mut values,
            16,
            threads,
            work,
            &mut reporter.part(base),
        )?;
        Ok((lit_hours, values, finished))
    }
}

/// The metrics, hour by hour in the file's order, into `year`: the lit hours done
/// (`lit_done`, indices into `hours`, with their `values`) and the nights among `hours`.
fn tally(
    year: &mut Year,
    hours: &[hours::Hour],
    lit_done: &[usize],
    values: &[HourValues],
    grids: &[coefficients::GridCoefficients],
    hourly: bool,
) {
    let mut tallies: Vec<Tally> = grids
        .iter()
        .map(|g| Tally::new(g.counted.clone(), g.target))
        .collect();
    let mut by_hour: Vec<Vec<f32>> = vec![Vec::new(); grids.len()];
    let mut next = 0;
    for (h, hour) in hours.iter().enumerate() {
        if next < lit_done.len() && lit_done[next] == h {
            year.sun_hours.push(hour.stamp);
            for (g, (e, s)) in values[next].iter().enumerate() {
                let e64: Vec<f64> = e.iter().map(|&v| f64::from(v)).collect();
                let s64: Vec<f64> = s.iter().map(|&v| f64::from(v)).collect();
                tallies[g].add(&e64, &s64, hour.occupied, true);
                if hourly {
                    by_hour[g].extend_from_slice(e);
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
    for ((g, tally), hourly) in grids.iter().zip(&tallies).zip(by_hour) {
        let (metrics, summary) = tally.finish();
        year.grids.push(GridYear {
            name: g.name.clone(),
            points: g.points.clone(),
            metrics,
            summary,
            hourly,
        });
    }
}
