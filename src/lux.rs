//! Illuminance at the points of a grid (`docs/scene-format.md`, "Grids"; `docs/method.md` §19): a grid floats in the
//! scene, so interpolating a surface's radiosity is not enough. Direct light comes from the
//! lights themselves with the solver's estimator (point lights and luminaires by a shadow
//! ray, area lights by Lambert's formula × the visible share of stratified shadow rays);
//! inter-reflected light is gathered from every solved sample — its reflected radiosity
//! (B − emission) through the point-to-disc form factor Aⱼ cosθ cosθⱼ / (πr² + Aⱼ), with a
//! visibility ray.

use glam::{DVec3, Vec3};

use crate::error::Result;
use crate::field::interpolate::{Interpolator, Site};
use crate::field::Field;
use crate::light::{Arrival, DirectLight};
use crate::parallel::for_chunks_reporting;
use crate::progress::{Callback, Phase, Progress, Reporter};
use crate::scene::{Grid, Scene};
use crate::solver::Solution;
use crate::specular::gather::Chains;
use crate::specular::highlight::Highlights;
use crate::specular::lights::Lights;
use crate::specular::Specular;
use crate::visibility::{Segment, Visibility};

/// Rays per grid point towards the sky and the ground, where daylight enters a scene.
pub(crate) const GRID_SKY_RAYS: u32 = 4096;

/// How grid points are measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LuxOptions {
    /// Shadow rays per area light and point, 1 to [`crate::light::MAX_LIGHT_SAMPLES`].
    pub light_samples: u32,
    /// Seed of the shadow rays.
    pub seed: u64,
    /// Worker threads.
    pub threads: usize,
    /// Chains followed from each point through specular surfaces (mirrors, glossy surfaces,
    /// glass), 1 to [`MAX_SPECULAR_RAYS`](crate::solver::MAX_SPECULAR_RAYS); unused in scenes
    /// without them.
    pub specular_rays: u32,
}

impl Default for LuxOptions {
    fn default() -> Self {
        LuxOptions {
            light_samples: 64,
            specular_rays: 256,
            seed: 1,
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
        }
    }
}

impl LuxOptions {
    /// Checks the grids' settings: the first out of its range, as an
    /// [`Error::Argument`](crate::Error::Argument) naming it.
    pub fn validate(&self) -> Result<()> {
        if !(1..=crate::solver::MAX_SPECULAR_RAYS).contains(&self.specular_rays) {
            return Err(crate::Error::argument(
                "specular_rays",
                format!(
                    "{} chains per point: must lie in 1..={}",
                    self.specular_rays,
                    crate::solver::MAX_SPECULAR_RAYS
                ),
            ));
        }
        if !(1..=crate::light::MAX_LIGHT_SAMPLES).contains(&self.light_samples) {
            return Err(crate::Error::argument(
                "light_samples",
                format!(
                    "{} shadow rays per area light: must lie in 1..={}",
                    self.light_samples,
                    crate::light::MAX_LIGHT_SAMPLES
                ),
            ));
        }
        Ok(())
    }
}

/// What a grid measured.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Illuminance {
    /// Illuminance (RGB; W/m², or lux in a photometric scene) at each of the grid's points, in
    /// [`Grid::points`] order: direct + inter-reflected.
    pub values: Vec<DVec3>,
    /// How many points, from the first, are measured in full: all of them unless the host
    /// stopped the call (the others then hold their direct light, or 0 if the stop came
    /// before it).
    pub measured: usize,
}

/// Measures the illuminance at `grid`'s points (see the module doc). `progress` hears the
/// direct light's and the gather's share done (phases [`Phase::DirectLight`] and
/// [`Phase::Gathering`]) and may stop the call.
pub fn illuminance(
    scene: &Scene,
    solution: &Solution,
    vis: &dyn Visibility,
    grid: &Grid,
    options: &LuxOptions,
    progress: Callback,
) -> Result<Illuminance> {
    crate::parallel::guarded("the illuminance gather", || {
        let checked = crate::visibility::Checked::new(vis, scene);
        let vis: &dyn crate::visibility::Visibility = &checked;
        solution.check_fits(scene)?;
        options.validate()?;
        let points = grid.points();
        let n = grid.normal;
        let mut reporter = Reporter::new(progress);
        let base = Progress {
            items: points.len(),
            ..Progress::of(Phase::DirectLight)
        };
        // Direct light: the solver's estimator at the points, facing the grid's normal.
        let light =
            DirectLight::with_specular(scene, options.light_samples, solution.field.specular_depth);
        let at: Vec<(Vec3, Vec3)> = points.iter().map(|&p| (p, n)).collect();
        let ids: Vec<u32> = (0..points.len() as u32).collect();
        let (mut direct, _) = if reporter.report(base) {
            (vec![Arrival::default(); points.len()], 0)
        } else {
            let part = &mut reporter.part(base);
            light.at(vis, &at, &ids, options.seed, options.threads, part)?
        };
        // Daylight entering, with more rays than a sample's: a grid has few points.
        if let Some(entering) = crate::daylight::entering::Entering::of(scene, GRID_SKY_RAYS) {
            let daylight = if reporter.stopped() {
                vec![DVec3::ZERO; points.len()]
            } else {
                entering_at(&entering, vis, &at, &ids, options, &mut reporter.part(base))?
            };
            for (d, e) in direct.iter_mut().zip(daylight) {
                d.irradiance += e;
            }
        }
        // Inter-reflected light from every sample.
        let s = &solution.field.samples;
        let reflected: Vec<DVec3> = (0..s.len())
            .map(|k| solution.field.radiosity[k] - crate::solver::emission_of(scene, s, k))
            .collect();
        let lift = crate::visibility::lift(scene);
        let specular = specular_gather(scene, &solution.field, vis, options)?;
        let mut gathered: Vec<Option<DVec3>> = vec![None; points.len()];
        let gather = |first: usize, out: &mut [Option<DVec3>]| {
            let by_way_of_specular = match &specular {
                Some(g) => g.at(
                    &points[first..first + out.len()],
                    n,
                    first as u32,
                    &reflected,
                )?,
                None => vec![DVec3::ZERO; out.len()],
            };
            let (mut segments, mut factors) = (Vec::new(), Vec::new());
            for ((o, &x), extra) in out.iter_mut().zip(&points[first..]).zip(by_way_of_specular) {
                let lit = |k: usize| reflected[k].max_element() > 0.0;
                facing(s, (x, n), lift, lit, &mut segments, &mut factors);
                let mut blocked = vec![false; segments.len()];
                vis.occluded(&segments, &mut blocked)?;
                *o = Some(
                    factors
                        .iter()
                        .zip(&blocked)
                        .filter(|(_, &b)| !b)
                        .map(|(&(k, f), _)| reflected[k as usize] * f)
                        .sum::<DVec3>()
                        + extra,
                );
            }
            Ok(())
        };
        let base = Progress {
            phase: Phase::Gathering,
            ..base
        };
        let measured = if reporter.report(base) {
            0
        } else {
            let part = &mut reporter.part(base);
            match for_chunks_reporting(&mut gathered, 4, options.threads, gather, part)? {
                true => points.len(),
                // Parts are done in order: the measured points are those with a gather.
                false => gathered.iter().take_while(|g| g.is_some()).count(),
            }
        };
        let values = direct
            .iter()
            .zip(&gathered)
            .map(|(d, g)| d.irradiance + g.unwrap_or(DVec3::ZERO))
            .collect();
        Ok(Illuminance { values, measured })
    })
}

/// The daylight entering at grid points `at` (with their ids).
fn entering_at(
    entering: &crate::daylight::entering::Entering,
    vis: &dyn Visibility,
    at: &[(Vec3, Vec3)],
    ids: &[u32],
    options: &LuxOptions,
    report: crate::parallel::Report,
) -> Result<Vec<DVec3>> {
    let mut daylight = vec![DVec3::ZERO; at.len()];
    let work = |first: usize, chunk: &mut [DVec3]| {
        let range = first..first + chunk.len();
        let (got, _) = entering.at(vis, &at[range.clone()], &ids[range], options.seed)?;
        chunk.copy_from_slice(&got);
        Ok(())
    };
    crate::parallel::for_chunks_reporting(&mut daylight, 8, options.threads, work, report)?;
    Ok(daylight)
}

/// The samples that face grid point `x` (facing `n`) and that `wanted` keeps: each one's
/// point-to-disc form factor Aⱼ cosθ cosθⱼ / (πr² + Aⱼ) in `factors`, and in `segments` the
/// segment whose visibility decides whether it counts (both cleared first).
fn facing(
    s: &crate::sampling::Samples,
    (x, n): (Vec3, Vec3),
    lift: f32,
    wanted: impl Fn(usize) -> bool,
    segments: &mut Vec<Segment>,
    factors: &mut Vec<(u32, f64)>,
) {
    segments.clear();
    factors.clear();
    for k in 0..s.len() {
        if !wanted(k) {
            continue;
        }
        let (y, m) = (s.position[k], s.normal[k]);
        let d = y - x;
        let r2 = d.length_squared();
        if r2 <= 0.0 {
            continue;
        }
        let r = r2.sqrt();
        let (cos_x, cos_y) = (n.dot(d) / r, -m.dot(d) / r);
        if cos_x <= 0.0 || cos_y <= 0.0 {
            continue;
        }
        let area = s.area[k];
        let factor =
            area * f64::from(cos_x * cos_y) / (std::f64::consts::PI * f64::from(r2) + area);
        segments.push(Segment {
            a: x,
            b: y + lift * m,
        });
        factors.push((k as u32, factor));
    }
}

/// Per grid point, what each sample's reflected radiosity gives it: the inter-reflected part
/// of [`illuminance`] as a sparse linear map (sample, weight), for a host of many lightings of
/// one solution (a year of daylight coefficients). Direct light is not in it.
pub(crate) fn gather_rows(
    scene: &Scene,
    solution: &Solution,
    vis: &dyn Visibility,
    grid: &Grid,
    options: &LuxOptions,
    report: &mut dyn FnMut(f64) -> crate::progress::Control,
) -> Result<Vec<Vec<(u32, Vec3)>>> {
    let points = grid.points();
    let n = grid.normal;
    let s = &solution.field.samples;
    let lift = crate::visibility::lift(scene);
    let specular = specular_gather(scene, &solution.field, vis, options)?;
    let mut rows: Vec<Vec<(u32, Vec3)>> = vec![Vec::new(); points.len()];
    let gather = |first: usize, out: &mut [Vec<(u32, Vec3)>]| {
        let through = match &specular {
            Some(g) => g.rows(&points[first..first + out.len()], n, first as u32)?,
            None => vec![Vec::new(); out.len()],
        };
        let (mut segments, mut factors) = (Vec::new(), Vec::new());
        for ((row, &x), mut extra) in out.iter_mut().zip(&points[first..]).zip(through) {
            facing(s, (x, n), lift, |_| true, &mut segments, &mut factors);
            let mut blocked = vec![false; segments.len()];
            vis.occluded(&segments, &mut blocked)?;
            row.extend(
                factors
                    .iter()
                    .zip(&blocked)
                    .filter(|(_, &b)| !b)
                    .map(|(&(k, f), _)| (k, Vec3::splat(f as f32))),
            );
            row.append(&mut extra);
            row.shrink_to_fit();
        }
        Ok(())
    };
    for_chunks_reporting(&mut rows, 4, options.threads.max(1), gather, report)?;
    Ok(rows)
}

/// Light by way of specular surfaces at grid points: chains from each point
/// (`specular::gather`), their ends interpolated from the solved samples.
struct SpecularGather<'a> {
    spec: Specular,
    lights: Lights,
    interpolator: Interpolator<'a>,
    scene: &'a Scene,
    vis: &'a dyn Visibility,
    depth: u32,
    rays: u32,
    seed: u64,
}

/// The gather through specular surfaces, where the field has them.
fn specular_gather<'a>(
    scene: &'a Scene,
    field: &'a Field,
    vis: &'a dyn Visibility,
    options: &LuxOptions,
) -> Result<Option<SpecularGather<'a>>> {
    if !field.specular {
        return Ok(None);
    }
    Ok(Some(SpecularGather {
        spec: Specular::of(scene),
        lights: Lights::new(scene),
        interpolator: Interpolator::new(scene, field, vis),
        scene,
        vis,
        depth: field.specular_depth,
        rays: options.specular_rays,
        seed: options.seed,
    }))
}

impl SpecularGather<'_> {
    /// Irradiance at `points` (facing `normal`; ids from `first`) by way of specular surfaces:
    /// the lights' light through glossy bounces, and the samples' reflected radiosity
    /// `reflected` where the chains end.
    fn at(
        &self,
        points: &[Vec3],
        normal: Vec3,
        first: u32,
        reflected: &[DVec3],
    ) -> Result<Vec<DVec3>> {
        let (mut out, ends) = self.ends(points, normal, first)?;
        for (receiver, weight, chosen) in ends {
            let b: DVec3 = chosen
                .iter()
                .map(|&(k, w)| reflected[k as usize] * f64::from(w))
                .sum();
            // A local-linear fit may extrapolate below zero near a dark edge.
            out[receiver as usize] += weight * b.max(DVec3::ZERO);
        }
        Ok(out)
    }

    /// [`SpecularGather::at`] as a linear map: per point, (sample, weight) of the chains' ends
    /// (without the fit's floor at zero, which a sum of bases cannot hold).
    fn rows(&self, points: &[Vec3], normal: Vec3, first: u32) -> Result<Vec<Vec<(u32, Vec3)>>> {
        let (_, ends) = self.ends(points, normal, first)?;
        let mut rows = vec![Vec::new(); points.len()];
        for (receiver, weight, chosen) in ends {
            let row: &mut Vec<(u32, Vec3)> = &mut rows[receiver as usize];
            row.extend(
                chosen
                    .iter()
                    .map(|&(k, w)| (k, (weight * f64::from(w)).as_vec3())),
            );
        }
        Ok(rows)
    }

    /// The lights' light through glossy bounces at each point, and every chain's end: its
    /// point, its weight, and the samples it interpolates with their normalised weights.
    #[allow(clippy::type_complexity)]
    fn ends(
        &self,
        points: &[Vec3],
        normal: Vec3,
        first: u32,
    ) -> Result<(Vec<DVec3>, Vec<(u32, DVec3, Vec<(u32, f32)>)>)> {
        let has_samples = |side| self.interpolator.has_samples(side);
        let highlights = Highlights::of(self.scene, &self.spec);
        // No photon lands on a grid point: its chains take the lights they meet where the
        // images do not carry them (through curved mirrors and refracting solids).
        let listing = crate::specular::images::chains(&self.spec, self.depth);
        let tree = crate::specular::images::ChainTree::new(&listing.chains, false);
        let chains = Chains {
            scene: self.scene,
            spec: &self.spec,
            lights: &self.lights,
            vis: self.vis,
            lift: crate::visibility::lift(self.scene),
            depth: self.depth,
            rays: self.rays,
            has_samples: &has_samples,
            highlights: &highlights,
            unlisted: Some(&tree),
        };
        let receivers: Vec<(Vec3, Vec3, u32)> = points
            .iter()
            .enumerate()
            .map(|(i, &p)| (p, normal, first + i as u32))
            .collect();
        let found = chains.follow(&receivers, self.seed)?;
        let covered = self.interpolator.covered(
            &found
                .ends
                .iter()
                .map(|e| (e.point, e.normal))
                .collect::<Vec<_>>(),
        )?;
        let sites: Vec<Site> = found
            .ends
            .iter()
            .zip(covered)
            .map(|(e, covered)| Site::at(e.point, e.side, e.normal, covered))
            .collect();
        let mut weights = Vec::new();
        self.interpolator.weights(&sites, &mut weights)?;
        let mut ends = Vec::with_capacity(found.ends.len());
        for (e, chosen) in found.ends.iter().zip(weights) {
            let total: f32 = chosen.iter().map(|&(_, w)| w).sum();
            if total > 0.0 {
                let chosen = chosen.into_iter().map(|(k, w)| (k, w / total)).collect();
                ends.push((e.receiver, e.weight, chosen));
            }
        }
        Ok((found.direct, ends))
    }
}

/// Which of `grid`'s points lie inside a solid (a pedestal standing through a work plane): the
/// first surface a ray along the grid's normal meets is seen from behind. Such points receive
/// nothing; a summary leaves them out.
pub fn enclosed(scene: &Scene, vis: &dyn Visibility, grid: &Grid) -> Result<Vec<bool>> {
    let checked = crate::visibility::Checked::new(vis, scene);
    let vis: &dyn Visibility = &checked;
    let points = grid.points();
    let reach = 2.0 * scene.bounds.diagonal();
    let rays: Vec<crate::visibility::Ray> = points
        .iter()
        .map(|&p| crate::visibility::Ray {
            origin: p,
            dir: grid.normal,
            t_min: 0.0,
            t_max: reach,
        })
        .collect();
    let hits = crate::visibility::intersect_all(vis, &rays, 1)?;
    Ok(hits
        .iter()
        .map(|h| {
            h.is_some_and(|h| {
                let t = &scene.triangles[h.triangle as usize];
                // Seen from behind, and its back is black (a solid's inside).
                grid.normal.dot(t.normal) > 0.0 && !scene.two_sided
            })
        })
        .collect())
}
