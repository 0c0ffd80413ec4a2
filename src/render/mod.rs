//! Rendering (`docs/method.md` §7 and §18): camera rays through the backend's closest hit. The direct light at
//! a hit is traced there with the solver's estimator ([`Direct::Traced`]; the paper
//! interpolates it too, [`Direct::Interpolated`]); the rest of its radiance is interpolated
//! from the samples of the same surface side with smooth, normalised, compactly supported
//! weights sized by each sample's radius D (after Zwicker et al. 2001, surface splatting). A
//! sample contributes only if the segment from the hit to it is clear, so light never passes
//! through a thin wall or around a corner. Pixels are box-filtered: one ray through the centre,
//! and a jittered grid of rays where the pixel or a neighbour sees another surface side, finer
//! where the edge's contrast is high.

mod gather;
pub(crate) mod image;
mod paths;

use glam::Vec3;

use crate::error::Result;
use crate::field::interpolate::{self, Interpolator, Site};
use crate::field::Field;
use crate::light::{DirectLight, Reach};
use crate::progress::{Callback, Control, Phase, Progress, Reporter};
use crate::sampling::{side_of, surface_of, Side};
use crate::scene::Scene;
use crate::solver::Solution;
use crate::visibility::{Hit, Ray, Visibility};
pub use gather::MAX_GATHER_RAYS;
pub use image::Image;

/// Edge pixels of high contrast get up to this many times `supersample` rays per side...
const MAX_EDGE_BOOST: usize = 8;
/// A pool of light with no edge in it (the ceiling over a lamp) gets up to this many times
/// `supersample` rays per side: its pixels' values are smooth, so the grid's error falls as
/// the square of its side, not as the side.
const MAX_POOL_BOOST: usize = 2;
/// ... but no more than this many per side (unless `supersample` itself asks for more): the
/// rim of a light 40 times the image's mean is measured to about a part in a thousand.
const MAX_EDGE_SIDE: usize = 32;

/// A pixel whose neighbour is brighter or darker by more than this many times the image's
/// mean is supersampled like an edge.
const CONTRAST_EDGE: f64 = 1.0;

/// Rendering settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    /// Worker threads.
    pub threads: usize,
    /// Pixels on an edge between surfaces get `supersample × supersample` rays (1 = never).
    pub supersample: u32,
    /// What each pixel holds.
    pub quantity: Quantity,
    /// How a pixel gets its direct light.
    pub direct: Direct,
    /// Rays drawn from a glossy surface's lobe where a camera path meets one (and as many light
    /// samples per area light there), 1 to [`MAX_GLOSSY_RAYS`]: more gives smoother glossy
    /// reflections at proportional cost. Unused in scenes without glossy surfaces.
    pub glossy_rays: u32,
    /// Rays gathered over the hemisphere at a hit within its samples' reach of another surface
    /// (contacts, creases), 0 to [`MAX_GATHER_RAYS`]; 0 interpolates there as everywhere.
    /// More: less noise along contacts and creases at proportional cost there. Scenes with
    /// specular surfaces interpolate.
    pub gather_rays: u32,
    /// The memory budget, bytes: an image whose working arrays would not fit
    /// ([`BYTES_PER_PIXEL`](crate::budget::BYTES_PER_PIXEL) a pixel) is refused before they are
    /// allocated.
    pub memory_budget: usize,
}

/// The most rays per side `supersample` may ask for (edge pixels of high contrast get up to
/// four times as many).
pub const MAX_SUPERSAMPLE: u32 = 16;

/// The most rays a glossy bounce may draw.
pub const MAX_GLOSSY_RAYS: u32 = 1024;

/// Where a pixel's direct light comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direct {
    /// Interpolated from the samples with the rest of their light, as the paper renders: shadow
    /// edges and highlights are as sharp as the samples are dense.
    Interpolated,
    /// Integrated at each camera hit with the solver's estimator (`light_samples` shadow rays per
    /// area light, one per point light); only the inter-reflected light is interpolated.
    Traced {
        /// Shadow rays per area light and hit, 1 to [`crate::light::MAX_LIGHT_SAMPLES`].
        light_samples: u32,
    },
}

impl Direct {
    /// The direct light traced with `light_samples` shadow rays per area light, or interpolated
    /// for 0 (as `render --direct-rays` takes it).
    pub fn from_rays(light_samples: u32) -> Direct {
        match light_samples {
            0 => Direct::Interpolated,
            n => Direct::Traced { light_samples: n },
        }
    }
}

/// What a rendered image holds per pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Quantity {
    /// Outgoing radiance (luminance in a photometric scene): what a camera sees.
    #[default]
    Radiance,
    /// Irradiance (illuminance) on the surface seen: the light arriving there, whatever its
    /// reflectance; emitters without samples and misses are 0.
    Irradiance,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            threads: crate::solver::Options::default().threads,
            supersample: 4,
            quantity: Quantity::Radiance,
            direct: Direct::Traced { light_samples: 16 },
            glossy_rays: 16,
            gather_rays: DEFAULT_GATHER_RAYS,
            memory_budget: crate::budget::DEFAULT_MEMORY_BUDGET,
        }
    }
}

impl RenderOptions {
    /// Checks the render's settings: the first out of its range, as an
    /// [`Error::Argument`](crate::Error::Argument) naming it.
    pub fn validate(&self) -> Result<()> {
        if let Direct::Traced { light_samples } = self.direct {
            if !(1..=crate::light::MAX_LIGHT_SAMPLES).contains(&light_samples) {
                return Err(crate::Error::argument(
                    "direct",
                    format!(
                        "{light_samples} shadow rays per area light: must lie in 1..={}",
                        crate::light::MAX_LIGHT_SAMPLES
                    ),
                ));
            }
        }
        if !(1..=MAX_GLOSSY_RAYS).contains(&self.glossy_rays) {
            return Err(crate::Error::argument(
                "glossy_rays",
                format!(
                    "{} rays per glossy bounce: must lie in 1..={MAX_GLOSSY_RAYS}",
                    self.glossy_rays
                ),
            ));
        }
        if self.gather_rays > MAX_GATHER_RAYS {
            return Err(crate::Error::argument(
                "gather_rays",
                format!(
                    "{} gather rays per hit: must lie in 0..={MAX_GATHER_RAYS}",
                    self.gather_rays
                ),
            ));
        }
        if !(1..=MAX_SUPERSAMPLE).contains(&self.supersample) {
            return Err(crate::Error::argument(
                "supersample",
                format!(
                    "{} rays per side of an edge pixel: must lie in 1..={MAX_SUPERSAMPLE}",
                    self.supersample
                ),
            ));
        }
        Ok(())
    }

    /// Fast and rough: fewer shadow rays at the hits, fewer rays on edges, no gather at
    /// contacts and creases ([`crate::Preset::Preview`]).
    pub fn preview() -> Self {
        RenderOptions {
            supersample: PREVIEW_SUPERSAMPLE,
            gather_rays: 0,
            direct: Direct::Traced {
                light_samples: PREVIEW_DIRECT_RAYS,
            },
            ..RenderOptions::default()
        }
    }

    /// Slower and finer: more shadow rays at the hits, more rays on edges and in the gathers at
    /// contacts and creases ([`crate::Preset::Final`]).
    pub fn final_quality() -> Self {
        RenderOptions {
            supersample: FINAL_SUPERSAMPLE,
            gather_rays: FINAL_GATHER_RAYS,
            direct: Direct::Traced {
                light_samples: FINAL_DIRECT_RAYS,
            },
            ..RenderOptions::default()
        }
    }
}

/// Gather rays per hit near another surface, by default.
pub const DEFAULT_GATHER_RAYS: u32 = 32;
const PREVIEW_SUPERSAMPLE: u32 = 2;
const PREVIEW_DIRECT_RAYS: u32 = 4;
const FINAL_SUPERSAMPLE: u32 = 8;
const FINAL_DIRECT_RAYS: u32 = 64;
const FINAL_GATHER_RAYS: u32 = 128;

/// What rendering did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct RenderStats {
    /// Camera rays traced.
    pub camera_rays: u64,
    /// Visibility queries between hits and samples.
    pub interpolation_queries: u64,
    /// Shadow rays traced at hits for their direct light.
    pub shadow_rays: u64,
    /// Pixels that got the grid of rays.
    pub supersampled_pixels: u64,
    /// Whether the host stopped the render: pixels not reached are black, and edges not
    /// refined keep their centre ray's value.
    pub stopped: bool,
}

/// Share of the progress reports the centre rays take (the edges take the rest).
const CENTRE_SHARE: f64 = 0.7;

/// Renders the scene's camera view of a solution. `progress` hears the share of pixels done
/// ([`Phase::Rendering`]) and may stop the render (see [`RenderStats::stopped`]).
pub fn render(
    scene: &Scene,
    solution: &Solution,
    vis: &dyn Visibility,
    options: &RenderOptions,
    progress: Callback,
) -> Result<(Image, RenderStats)> {
    render_distributed(
        scene,
        solution,
        vis,
        options,
        &crate::distributed::Single,
        progress,
    )
}

/// [`render`] spread over `ranks` (each with the same solution, as
/// [`solve_distributed`](crate::solver::solve_distributed) leaves it): each rank shades a run
/// of the image's rows, then a run of its edge pixels, and every rank gets the whole image,
/// equal to one process's bit for bit (every ray's value depends only on its pixel and id).
/// A Stop on any rank stops all at the end of a pass.
pub fn render_distributed(
    scene: &Scene,
    solution: &Solution,
    vis: &dyn Visibility,
    options: &RenderOptions,
    ranks: &dyn crate::distributed::Ranks,
    progress: Callback,
) -> Result<(Image, RenderStats)> {
    crate::parallel::guarded("rendering", || {
        let checked = crate::visibility::Checked::new(vis, scene);
        let vis: &dyn crate::visibility::Visibility = &checked;
        let ranks = crate::distributed::Checked::new(ranks)?;
        let ranks: &dyn crate::distributed::Ranks = &ranks;
        let camera = &scene.camera;
        camera.check()?;
        solution.check_fits(scene)?;
        options.validate()?;
        crate::budget::check_image(
            options.memory_budget,
            (camera.width, camera.height),
            crate::budget::BYTES_PER_PIXEL,
        )?;
        let shader = Shader::new(scene, &solution.field, vis, options)?;
        draw(scene, &shader, options, ranks, progress)
    })
}

/// The image's passes: a centre ray per pixel (each rank a run of the rows), then the edge
/// pixels with more rays (each rank a run of them); a Stop on any rank ends a pass.
fn draw(
    scene: &Scene,
    shader: &Shader,
    options: &RenderOptions,
    ranks: &dyn crate::distributed::Ranks,
    progress: Callback,
) -> Result<(Image, RenderStats)> {
    let camera = &scene.camera;
    let (w, h) = (camera.width as usize, camera.height as usize);
    let mut stats = RenderStats::default();
    let mut reporter = Reporter::new(progress);
    let base = Progress {
        items: w * h,
        ..Progress::of(Phase::Rendering)
    };
    reporter.report(base);

    // Centre rays: radiance and the side each pixel sees.
    let mut centre: Vec<(Vec3, u32)> = vec![(Vec3::ZERO, u32::MAX); w * h];
    let queries = std::sync::atomic::AtomicU64::new(0);
    let trace = |first: usize, out: &mut [(Vec3, u32)]| {
        let rays: Vec<Ray> = (first..first + out.len())
            .map(|p| camera_ray(scene, (p % w) as f32 + 0.5, (p / w) as f32 + 0.5))
            .collect();
        queries.fetch_add(
            shader.shade(&rays, first as u32, out, 1)?,
            std::sync::atomic::Ordering::Relaxed,
        );
        Ok(())
    };
    // Each rank a run of the rows (a Stop heard before leaves them all black).
    // Every ray seeds its own shadow rays by its pixel: the stage needs no seed.
    let exec = crate::exec::Exec::new(options.threads, 0, ranks);
    let all = exec.for_share(
        &mut centre,
        w,
        |first, out, _: &_| trace(first, out),
        &mut |f| {
            control(reporter.report(Progress {
                fraction: CENTRE_SHARE * f,
                ..base
            }))
        },
        |c: &(Vec3, u32)| [c.0.x, c.0.y, c.0.z, c.1 as f32].map(f64::from),
        |v| {
            (
                Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32),
                v[3] as u32,
            )
        },
    )? && !reporter.stopped();
    stats.camera_rays = (w * h) as u64;

    // Edge pixels, refined with more rays.
    let edges = if all && options.supersample > 1 {
        // In mirrors and on glossy surfaces a value's edge may be a light's rim (its image):
        // boosted as a rim between sides is.
        let specular = shader.paths.is_some();
        edge_pixels(&centre, w, h, options.supersample as usize, specular)
    } else {
        Edges::default()
    };
    let mut refined = vec![None; edges.pixels.len()];
    let refine = |first: usize, out: &mut [Option<Vec3>]| {
        queries.fetch_add(
            edges.shade(scene, shader, first, out, w)?,
            std::sync::atomic::Ordering::Relaxed,
        );
        Ok(())
    };
    // Each rank a run of the edge pixels (none after a Stop: `edges` is empty then).
    let refined_all = exec.for_share(
        &mut refined,
        16,
        |first, out, _: &_| refine(first, out),
        &mut |f| {
            control(reporter.report(Progress {
                fraction: CENTRE_SHARE + (1.0 - CENTRE_SHARE) * f,
                ..base
            }))
        },
        |r: &Option<Vec3>| match r {
            Some(v) => [1.0, f64::from(v.x), f64::from(v.y), f64::from(v.z)],
            None => [0.0; 4],
        },
        |v| (v[0] != 0.0).then(|| Vec3::new(v[1] as f32, v[2] as f32, v[3] as f32)),
    )?;
    let all = all && refined_all;
    stats.camera_rays += (edges.first_ray.last().copied().unwrap_or(w * h) - w * h) as u64;
    stats.supersampled_pixels = refined.iter().filter(|r| r.is_some()).count() as u64;
    stats.interpolation_queries = crate::distributed::sum_over(ranks, queries.into_inner())?;
    let shadow_rays = shader
        .shadow_rays
        .load(std::sync::atomic::Ordering::Relaxed);
    stats.shadow_rays = crate::distributed::sum_over(ranks, shadow_rays)?;
    stats.stopped = !all;

    let mut pixels: Vec<Vec3> = centre.into_iter().map(|c| c.0).collect();
    for (&p, value) in edges.pixels.iter().zip(&refined) {
        if let Some(value) = value {
            pixels[p] = *value;
        }
    }
    Ok((
        Image {
            width: camera.width,
            height: camera.height,
            pixels,
        },
        stats,
    ))
}

fn control(stop: bool) -> Control {
    if stop {
        Control::Stop
    } else {
        Control::Continue
    }
}

/// The pixels on edges between surface sides, and how many rays each gets.
#[derive(Default)]
struct Edges {
    /// Pixel indices.
    pixels: Vec<usize>,
    /// Rays per side of each pixel's jittered grid.
    per_side: Vec<usize>,
    /// First ray id of each edge pixel (ids past the centre rays', one per ray), and one past
    /// the last.
    first_ray: Vec<usize>,
}

/// Edge pixels: a neighbour, diagonal ones included (a corner may cut a pixel whose four
/// nearest neighbours all see what it sees), sees another side, or its brightest channel
/// differs from the pixel's by more than [`CONTRAST_EDGE`] × the image's mean (a highlight or
/// a light in a mirror, smaller than a pixel; the ceiling a few decimetres over a lamp, whose
/// pool a pixel's centre reads 10% above the pixel's mean). Each gets `n` rays per side, more
/// where an edge between sides (or, with `specular`, any edge) has high contrast (the rim of a
/// light): a jittered grid's coverage error scales with the contrast, while `n` × `n` rays
/// measure a smooth pool to a part in a thousand.
fn edge_pixels(centre: &[(Vec3, u32)], w: usize, h: usize, n: usize, specular: bool) -> Edges {
    let mean = centre
        .iter()
        .map(|c| f64::from(c.0.element_sum()))
        .sum::<f64>()
        / (3 * w * h) as f64;
    let step = (CONTRAST_EDGE * mean) as f32;
    let between_sides = |p: usize| neighbours(p, w, h).any(|q| centre[q].1 != centre[p].1);
    let pixels: Vec<usize> = (0..w * h)
        .filter(|&p| {
            let here = centre[p].0.max_element();
            between_sides(p)
                || neighbours(p, w, h).any(|q| (centre[q].0.max_element() - here).abs() > step)
        })
        .collect();
    let per_side: Vec<usize> = pixels
        .iter()
        .map(|&p| {
            let values = || neighbours(p, w, h).map(|q| centre[q].0.max_element());
            let here = centre[p].0.max_element();
            let contrast = values().fold(here, f32::max) - values().fold(here, f32::min);
            let ratio = f64::from(contrast) / mean;
            let most = if specular || between_sides(p) {
                MAX_EDGE_BOOST
            } else {
                MAX_POOL_BOOST
            };
            let m = if ratio.is_finite() && ratio > 1.0 {
                (ratio.sqrt().ceil() as usize).min(most)
            } else {
                1
            };
            (n * m).min(MAX_EDGE_SIDE.max(n))
        })
        .collect();
    let mut first_ray = Vec::with_capacity(pixels.len() + 1);
    let mut total = w * h;
    for &k in &per_side {
        first_ray.push(total);
        total += k * k;
    }
    first_ray.push(total);
    Edges {
        pixels,
        per_side,
        first_ray,
    }
}

impl Edges {
    /// Shades edge pixels `first..first + out.len()` with their grids of rays; the
    /// interpolation queries made.
    fn shade(
        &self,
        scene: &Scene,
        shader: &Shader,
        first: usize,
        out: &mut [Option<Vec3>],
        w: usize,
    ) -> Result<u64> {
        let mut rays =
            Vec::with_capacity(self.first_ray[first + out.len()] - self.first_ray[first]);
        for (&p, &n) in self.pixels[first..first + out.len()]
            .iter()
            .zip(&self.per_side[first..])
        {
            let (x, y) = ((p % w) as f32, (p / w) as f32);
            // Stratified and jittered: a regular grid measures a straight edge's coverage in
            // steps of 1/n with the same error all along the edge, which biased the mean of a
            // small image by the bright edge pixels of a light.
            let mut h = p as u64 ^ 0x5851_f42d_4c95_7f2d;
            let mut jitter = || {
                h = h
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                ((h >> 40) as f32) / (1u64 << 24) as f32
            };
            for j in 0..n {
                for i in 0..n {
                    let (dx, dy) = (
                        (i as f32 + jitter()) / n as f32,
                        (j as f32 + jitter()) / n as f32,
                    );
                    rays.push(camera_ray(scene, x + dx, y + dy));
                }
            }
        }
        let mut shaded = vec![(Vec3::ZERO, 0u32); rays.len()];
        // A pixel's rays share its gather (the grid averages their answers): runs of pixels
        // with grids of one size are shaded together, so what a pixel gets does not depend on
        // the batch it falls in.
        let sides = &self.per_side[first..first + out.len()];
        let mut queries = 0;
        let (mut pixel, mut ray) = (0, 0);
        while pixel < sides.len() {
            let n = sides[pixel];
            let run = sides[pixel..].iter().take_while(|&&m| m == n).count();
            let rays_in_run = run * n * n;
            queries += shader.shade(
                &rays[ray..ray + rays_in_run],
                (self.first_ray[first] + ray) as u32,
                &mut shaded[ray..ray + rays_in_run],
                (n * n) as u32,
            )?;
            pixel += run;
            ray += rays_in_run;
        }
        let mut rest = &shaded[..];
        for (o, &n) in out.iter_mut().zip(&self.per_side[first..]) {
            let (group, tail) = rest.split_at(n * n);
            *o = Some(group.iter().map(|s| s.0).sum::<Vec3>() / (n * n) as f32);
            rest = tail;
        }
        Ok(queries)
    }
}

/// `v` per unit reflectance `rho`, channel by channel (0 where a channel reflects nothing).
fn per_unit(v: glam::DVec3, rho: glam::DVec3) -> glam::DVec3 {
    let ratio = |v: f64, rho: f64| if rho > 0.0 { v / rho } else { 0.0 };
    glam::DVec3::new(ratio(v.x, rho.x), ratio(v.y, rho.y), ratio(v.z, rho.z))
}

/// The up to eight pixels around pixel p of a w × h image.
fn neighbours(p: usize, w: usize, h: usize) -> impl Iterator<Item = usize> {
    let (x, y) = ((p % w) as isize, (p / w) as isize);
    (-1..=1isize)
        .flat_map(move |dy| (-1..=1isize).map(move |dx| (x + dx, y + dy)))
        .filter(move |&(i, j)| {
            (i, j) != (x, y) && i >= 0 && j >= 0 && (i as usize) < w && (j as usize) < h
        })
        .map(move |(i, j)| j as usize * w + i as usize)
}

fn camera_ray(scene: &Scene, x: f32, y: f32) -> Ray {
    Ray {
        origin: scene.camera.position,
        dir: scene.camera.direction(x, y),
        t_min: 0.0,
        t_max: f32::INFINITY,
    }
}

/// Radiance at ray hits.
struct Shader<'a> {
    scene: &'a Scene,
    vis: &'a dyn Visibility,
    interpolator: Interpolator<'a>,
    /// What the pixels hold.
    quantity: Quantity,
    /// What each sample shows (see [`Shader::new`]), computed once: hits ask for it many times.
    values: Vec<glam::DVec3>,
    /// What each sample shows with its direct light (for hits whose direct light is not traced).
    full: Vec<glam::DVec3>,
    /// What a gather ray sees of each sample: the direct light and the inter-reflected light
    /// it reflects, per unit reflectance and over π (its emission is direct light, traced at
    /// the hits). Empty when nothing gathers.
    outgoing: Vec<(glam::DVec3, glam::DVec3)>,
    /// The sum of each sample's two parts of `outgoing` over patches of its side, for the
    /// far hits of a gather (none when nothing gathers).
    patches: Option<crate::field::patches::PatchSums>,
    /// Gather rays per pixel.
    gather_rays: u32,
    /// Direct light traced at a gather's hits near its point (none: nothing gathers).
    near_light: Option<DirectLight>,
    /// Direct light traced at the hits, when the pixels take theirs from there.
    light: Option<DirectLight>,
    /// The same with [`PENUMBRA_RAYS`] times the rays, for hits in a penumbra, and the weight
    /// of its answer beside the first look's.
    penumbra: Option<(DirectLight, f64)>,
    /// How camera paths go on through specular surfaces (none: the scene has none).
    paths: Option<paths::Paths>,
    lift: f32,
    /// Shadow rays traced so far.
    shadow_rays: std::sync::atomic::AtomicU64,
}

/// Seed of the shadow rays traced at camera hits: a fixed one, so a render repeats.
const DIRECT_SEED: u64 = 0x6d65_7368_6c69_6768;
/// The seed of the second look at hits in a penumbra.
const PENUMBRA_SEED: u64 = 0x7065_6e75_6d62_7261;
/// A hit next to one whose shadow rays disagree (some blocked, some not: a penumbra) is traced
/// again with this many times the rays, pooled with its first: the noise of a few rays is
/// there and only there, so the extra rays go where they matter.
const PENUMBRA_RAYS: u32 = 4;

/// A hit waiting for its interpolation.
#[derive(Clone)]
struct Pending {
    side: Side,
    /// Radiance when no sample is involved (misses, emitters without samples, black sides).
    fixed: Option<Vec3>,
    point: Vec3,
    normal: Vec3,
    /// Whether its direct light is traced (else interpolated with the rest).
    traced: bool,
    /// The reflectance at the hit, on a textured surface (its samples then show their light per
    /// unit reflectance).
    texel: Option<Vec3>,
    /// The seed of its shadow rays.
    id: u32,
}

impl<'a> Shader<'a> {
    fn new(
        scene: &'a Scene,
        field: &'a Field,
        vis: &'a dyn Visibility,
        options: &RenderOptions,
    ) -> Result<Self> {
        let s = &field.samples;
        let light = match options.direct {
            // A solution without its samples' direct light cannot be split.
            Direct::Traced { light_samples } if field.direct.len() == s.len() => Some(
                DirectLight::reaching(scene, light_samples, field.specular_depth, Reach::Near),
            ),
            _ => None,
        };
        // What sample k shows: its radiance B/π, or its irradiance; without its direct light
        // when that is traced at the hits. On a textured surface, its reflected radiance per
        // unit reflectance: each hit multiplies it by the texel it sees and adds the emission.
        let shown = |k: usize, direct: glam::DVec3| match options.quantity {
            Quantity::Radiance => {
                let rho = crate::solver::reflectance_of(scene, s, k);
                let reflected = field.radiosity[k] - rho * direct;
                if scene.is_textured(crate::sampling::surface_of(s.side[k])) {
                    let e = crate::solver::emission_of(scene, s, k);
                    per_unit(reflected - e, rho) / std::f64::consts::PI
                } else {
                    reflected / std::f64::consts::PI
                }
            }
            Quantity::Irradiance => field.irradiance[k] - direct,
        };
        let values = (0..s.len())
            .map(|k| {
                let direct = match light {
                    Some(_) => field.direct[k].irradiance,
                    None => glam::DVec3::ZERO,
                };
                shown(k, direct)
            })
            .collect();
        let full = (0..s.len()).map(|k| shown(k, glam::DVec3::ZERO)).collect();
        let gathers = options.gather_rays > 0
            && light.is_some()
            && !crate::specular::Specular::of(scene).any();
        let outgoing = if gathers {
            (0..s.len())
                .map(|k| {
                    // Per unit reflectance: each gather hit multiplies by its own.
                    let rho = crate::solver::reflectance_of(scene, s, k);
                    let direct = field.direct[k].irradiance;
                    let reflected =
                        field.radiosity[k] - crate::solver::emission_of(scene, s, k) - rho * direct;
                    (
                        direct / std::f64::consts::PI,
                        per_unit(reflected, rho) / std::f64::consts::PI,
                    )
                })
                .collect()
        } else {
            Vec::new()
        };
        let patches = (!outgoing.is_empty()).then(|| {
            let sums: Vec<glam::DVec3> = outgoing.iter().map(|&(d, r)| d + r).collect();
            crate::field::patches::PatchSums::new(field, &sums, vis)
        });
        let patches = patches.transpose()?;
        let penumbra = match options.direct {
            Direct::Traced { light_samples } if light.is_some() => {
                let first = light_samples.max(1);
                let again = (first * PENUMBRA_RAYS).min(crate::light::MAX_LIGHT_SAMPLES);
                let light = DirectLight::reaching(scene, again, field.specular_depth, Reach::Near);
                // The two looks pooled by their rays.
                Some((light, f64::from(again) / f64::from(first + again)))
            }
            _ => None,
        };
        Ok(Shader {
            scene,
            vis,
            interpolator: Interpolator::new(scene, field, vis),
            quantity: options.quantity,
            values,
            full,
            outgoing,
            patches,
            gather_rays: options.gather_rays,
            near_light: gathers.then(|| {
                DirectLight::with_specular(scene, gather::NEAR_LIGHT_SAMPLES, field.specular_depth)
            }),
            light,
            penumbra,
            paths: {
                let spec = crate::specular::Specular::of(scene);
                (spec.any() && field.specular_depth > 0).then(|| paths::Paths {
                    lights: crate::specular::lights::Lights::new(scene),
                    spec,
                    depth: field.specular_depth,
                    glossy_rays: options.glossy_rays,
                })
            },
            lift: crate::visibility::lift(scene),
            shadow_rays: std::sync::atomic::AtomicU64::new(0),
        })
    }

    /// The reflectance at a hit on a textured surface; `None` elsewhere.
    fn texel(&self, triangle: u32, point: Vec3) -> Option<Vec3> {
        let surface = self.scene.triangles[triangle as usize].surface;
        self.scene
            .is_textured(surface)
            .then(|| self.scene.reflectance_at(triangle, point))
    }

    /// Shades a batch of rays: (radiance, side seen or u32::MAX). Ray i seeds its shadow rays
    /// with id `first_id + i`. Returns visibility queries.
    /// Hits near another surface gather light (see [`gather`]), `share` rays of a pixel
    /// sharing its gather.
    fn shade(
        &self,
        rays: &[Ray],
        first_id: u32,
        out: &mut [(Vec3, u32)],
        share: u32,
    ) -> Result<u64> {
        if let Some(paths) = &self.paths {
            return self.shade_paths(paths, rays, first_id, out, share);
        }
        let mut hits = vec![None; rays.len()];
        self.vis.intersect(rays, &mut hits)?;
        let mut pending = Vec::with_capacity(rays.len());
        for (ray, hit) in rays.iter().zip(&hits) {
            let Some(Hit { t, triangle }) = *hit else {
                // Out of the model: the sky or the ground (black without daylight).
                let outside = self.scene.daylight().map_or(0.0, |d| {
                    (d.radiance(ray.dir) + d.sun_radiance(ray.dir)) as f32
                });
                pending.push(Pending {
                    side: u32::MAX,
                    fixed: Some(Vec3::splat(outside)),
                    point: Vec3::ZERO,
                    normal: Vec3::ZERO,
                    traced: true,
                    texel: None,
                    id: 0,
                });
                continue;
            };
            let tri = &self.scene.triangles[triangle as usize];
            let back = ray.dir.dot(tri.normal) > 0.0;
            let side = side_of(tri.surface, back);
            let point = ray.origin + t * ray.dir;
            if !self.interpolator.has_samples(side) {
                let material = self.scene.material_of(tri.surface);
                let fixed = if back || self.quantity == Quantity::Irradiance {
                    Vec3::ZERO
                } else {
                    material.ke
                };
                pending.push(Pending {
                    side,
                    fixed: Some(fixed),
                    point,
                    normal: tri.normal,
                    traced: true,
                    texel: None,
                    id: 0,
                });
                continue;
            }
            let normal = if back { -tri.normal } else { tri.normal };
            pending.push(Pending {
                side,
                fixed: None,
                point,
                normal,
                traced: true,
                texel: self.texel(triangle, point),
                id: first_id.wrapping_add(pending.len() as u32),
            });
        }
        let (radiance, queries) = self.resolve(&pending, share)?;
        for ((p, o), radiance) in pending.iter().zip(out.iter_mut()).zip(radiance) {
            *o = (radiance, p.side);
        }
        Ok(queries)
    }

    /// The radiance (or irradiance) each pending hit shows: its fixed value, or its samples
    /// interpolated plus its direct light traced; hits near another surface whose direct light
    /// is traced blend in the light gathered there, `share` hits of a pixel sharing its
    /// gather (0: none gathers). Returns the visibility queries too.
    fn resolve(&self, pending: &[Pending], share: u32) -> Result<(Vec<Vec3>, u64)> {
        // Whether each hit that is interpolated is covered, asked in one batch.
        let lit: Vec<usize> = (0..pending.len())
            .filter(|&i| pending[i].fixed.is_none())
            .collect();
        let points: Vec<(Vec3, Vec3)> = lit
            .iter()
            .map(|&i| (pending[i].point, pending[i].normal))
            .collect();
        let covered = self.interpolator.covered(&points)?;
        let sites: Vec<Site> = lit
            .iter()
            .zip(&covered)
            .map(|(&i, &covered)| Site {
                point: pending[i].point,
                side: pending[i].side,
                normal: pending[i].normal,
                covered,
            })
            .collect();
        let mut weights = Vec::new();
        let mut queries = self.interpolator.weights(&sites, &mut weights)? + covered.len() as u64;
        let gathering = share > 0 && !self.outgoing.is_empty();
        let gathered: Vec<(&Pending, f32)> = lit
            .iter()
            .zip(&weights)
            .filter(|&(&i, _)| gathering && pending[i].traced)
            .map(|(&i, chosen)| (&pending[i], self.reach(chosen)))
            .collect();
        let (gathered, q) = self.gather(&gathered, share)?;
        queries += q;
        let mut gathered = gathered.into_iter();
        let direct = self.direct_at(pending, share)?;
        self.shadow_rays
            .fetch_add(direct.1, std::sync::atomic::Ordering::Relaxed);
        let mut interpolated = weights.iter();
        let mut out = Vec::with_capacity(pending.len());
        for (p, direct) in pending.iter().zip(&direct.0) {
            out.push(match p.fixed {
                Some(l) => l,
                None => {
                    let chosen = interpolated.next().expect("one per interpolated hit");
                    // Hits whose direct light is not traced show the samples' whole light.
                    let values = if p.traced && self.light.is_some() {
                        &self.values
                    } else {
                        &self.full
                    };
                    let (mut wsum, mut sum) = (0.0f64, glam::DVec3::ZERO);
                    for &(k, w) in chosen {
                        wsum += f64::from(w);
                        sum += f64::from(w) * values[k as usize];
                    }
                    // A local-linear fit may extrapolate below zero near a dark edge.
                    let mut interpolated = if wsum > 0.0 {
                        (sum / wsum).as_vec3().max(Vec3::ZERO)
                    } else {
                        Vec3::ZERO
                    };
                    if gathering && p.traced {
                        let g = gathered.next().expect("one per traced interpolated hit");
                        if g.alpha > 0.0 {
                            let shown = self.shown_gathered(p, g.irradiance);
                            interpolated += g.alpha * (shown - interpolated);
                        }
                    }
                    match p.texel {
                        Some(rho) if self.quantity == Quantity::Radiance => {
                            let material = self.scene.material_of(surface_of(p.side));
                            let emitted = if crate::sampling::is_back(p.side) {
                                Vec3::ZERO
                            } else {
                                material.ke
                            };
                            rho * interpolated + emitted + *direct
                        }
                        _ => interpolated + *direct,
                    }
                }
            });
        }
        Ok((out, queries))
    }

    /// How far a hit's interpolation reaches: its samples' kernel support (twice their mean
    /// radius). A surface nearer than that changes the light within the kernels.
    fn reach(&self, chosen: &[(u32, f32)]) -> f32 {
        let radius = &self.interpolator.samples().radius;
        let (mut wsum, mut sum) = (0.0f32, 0.0f32);
        for &(k, w) in chosen {
            wsum += w.abs();
            sum += w.abs() * radius[k as usize];
        }
        if wsum > 0.0 {
            interpolate::SUPPORT * sum / wsum
        } else {
            0.0
        }
    }

    /// What a hit shows of the inter-reflected irradiance gathered there, as its interpolated
    /// value would: reflected radiance, per unit reflectance on a textured surface, or the
    /// irradiance itself.
    fn shown_gathered(&self, p: &Pending, irradiance: glam::DVec3) -> Vec3 {
        let e = irradiance.as_vec3();
        match self.quantity {
            Quantity::Irradiance => e,
            Quantity::Radiance if p.texel.is_some() => e / std::f32::consts::PI,
            Quantity::Radiance => {
                // Its samples show their emission too (a luminous ceiling's crease).
                let material = self.scene.material_of(surface_of(p.side));
                let emitted = if crate::sampling::is_back(p.side) {
                    Vec3::ZERO
                } else {
                    material.ke
                };
                material.kd * e / std::f32::consts::PI + emitted
            }
        }
    }

    /// The direct light each interpolated hit shows, traced there (zero where the pixels take it
    /// from the samples); and the queries it took.
    fn direct_at(&self, pending: &[Pending], share: u32) -> Result<(Vec<Vec3>, u64)> {
        let mut shown = vec![Vec3::ZERO; pending.len()];
        let Some(light) = &self.light else {
            return Ok((shown, 0));
        };
        let lit: Vec<usize> = (0..pending.len())
            .filter(|&i| pending[i].fixed.is_none() && pending[i].traced)
            .collect();
        let points: Vec<(Vec3, Vec3)> = lit
            .iter()
            .map(|&i| (pending[i].point, pending[i].normal))
            .collect();
        let ids: Vec<u32> = lit.iter().map(|&i| pending[i].id).collect();
        let mut arrivals = vec![crate::light::Arrival::default(); lit.len()];
        let mut queries = light.batch(self.vis, &points, &ids, DIRECT_SEED, &mut arrivals)?;
        if let Some((penumbra, weight)) = &self.penumbra {
            // A hit is looked at again where a neighbouring hit's shadow rays disagree, not
            // its own: chosen by its own rays, a hit near a penumbra's rim whose few rays all
            // missed the blocker would keep its first look (all light) while one whose rays
            // found it got a second (less), and the rim came out too bright (+1.7% over 4 × 4
            // blocks along a strip of `cornell`'s floor). A neighbour's rays are drawn apart
            // from its own, so choosing by them adds no bias, and its own rays join the second
            // look's. Neighbours: the next hits of the same batch (a row of centre rays) or of
            // the same pixel's grid (`share` rays each), so the choice does not depend on how
            // the image was split among threads or ranks.
            let mut disagree = vec![false; pending.len()];
            for (&i, a) in lit.iter().zip(&arrivals) {
                disagree[i] = (1e-4..1.0 - 1e-4).contains(&a.visible);
            }
            let group = |i: usize| if share > 1 { i / share as usize } else { 0 };
            let partial: Vec<usize> = (0..lit.len())
                .filter(|&j| {
                    let i = lit[j];
                    [i.checked_sub(1), Some(i + 1)]
                        .into_iter()
                        .flatten()
                        .any(|k| k < pending.len() && group(k) == group(i) && disagree[k])
                })
                .collect();
            let points: Vec<(Vec3, Vec3)> = partial.iter().map(|&j| points[j]).collect();
            let ids: Vec<u32> = partial.iter().map(|&j| ids[j]).collect();
            let mut again = vec![crate::light::Arrival::default(); partial.len()];
            queries += penumbra.batch(self.vis, &points, &ids, PENUMBRA_SEED, &mut again)?;
            for (&j, a) in partial.iter().zip(again) {
                arrivals[j].irradiance =
                    arrivals[j].irradiance * (1.0 - weight) + a.irradiance * *weight;
            }
        }
        for (&i, arrival) in lit.iter().zip(&arrivals) {
            let e = arrival.irradiance;
            shown[i] = match self.quantity {
                Quantity::Radiance => {
                    let kd = || self.scene.material_of(surface_of(pending[i].side)).kd;
                    let rho = pending[i].texel.unwrap_or_else(kd);
                    rho * e.as_vec3() / std::f32::consts::PI
                }
                Quantity::Irradiance => e.as_vec3(),
            };
        }
        Ok((shown, queries))
    }
}
