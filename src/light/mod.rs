//! Direct light at points, integrated from the light sources themselves (`docs/method.md` §11), so that
//! shadows do not depend on how many samples lie on a light.
//!
//! - Point lights: one shadow ray, irradiance I·cosθ/r².
//! - Area lights: the exact irradiance of each unoccluded emitter polygon (Lambert's formula,
//!   the polygon clipped to the receiver's upper half-space), times the visible fraction of
//!   stratified shadow rays weighted by their unshadowed contributions: the ratio estimator of
//!   Heitz, Hill and McGuire, "Combining Analytic Direct Illumination and Stochastic Shadows"
//!   (2018). Fully lit and fully shadowed points are exact; only penumbrae carry noise. The
//!   rays are drawn over the solid angle an emitter subtends ([`spherical`]), which keeps the
//!   ratio's bias small beside large emitters.

use glam::{DVec3, Vec3};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use crate::error::Result;
use crate::parallel::{for_chunks_reporting, Report};
use crate::sampling::poisson::side_seed;
use crate::sampling::triangles::{cumulative_area, in_triangle};
use crate::scene::{PointSource, Scene};
use crate::specular::images::{self, Chain};
use crate::specular::shadow::{self, LightPath};
use crate::specular::Specular;
use crate::visibility::{Ray, Segment, Visibility};

pub(crate) mod leaving;
mod spherical;
mod window;

/// Emitters subtending less than this (sr) from a receiver have their shadow rays drawn
/// uniformly over their area: their rays weigh nearly alike, and from so far rounding would
/// blur the solid-angle draw.
const MIN_SOLID_ANGLE: f64 = 1e-4;

/// The most shadow rays per area light and receiver a caller may ask for.
pub const MAX_LIGHT_SAMPLES: u32 = 1 << 16;

/// Shadow rays one visibility call carries at most: a batch of receivers is cut to fit, so
/// memory stays bounded whatever the count per receiver.
const RAYS_PER_CALL: usize = 1 << 20;

/// The golden ratio's fractional part: the Fibonacci lattice's second coordinate.
const GOLDEN: f64 = 0.618_033_988_749_894_8;

/// An area light: one emitting surface, or a piece of many (a tessellated sphere or tube, see
/// `scene::adjacency`).
struct Emitter {
    triangles: Vec<[Vec3; 3]>,
    cumulative: Vec<f64>,
    /// The plane of a planar emitter: unit normal (the front) and offset.
    normal: Vec3,
    offset: f32,
    /// Per triangle, its front normal and plane offset, where the emitter is not one plane;
    /// empty for a planar one.
    facets: Vec<(Vec3, f32)>,
    ke: DVec3,
    /// Whether its front reflects light too (then it has samples of its own).
    reflects: bool,
    /// A sphere around it (centre, radius): how near a receiver stands.
    bounds: (Vec3, f32),
}

impl Emitter {
    /// The same emitter made of `triangles` only (a planar one's part).
    fn cut_to(&self, triangles: Vec<[Vec3; 3]>) -> Emitter {
        let mut sum = 0.0;
        let cumulative = triangles
            .iter()
            .map(|t| {
                sum += 0.5 * f64::from((t[1] - t[0]).cross(t[2] - t[0]).length());
                sum
            })
            .collect();
        Emitter {
            bounds: bounds(&triangles),
            triangles,
            cumulative,
            facets: Vec::new(),
            ..*self
        }
    }
}

/// Point `s` of a Fibonacci lattice of `count` in the unit square, shifted by `shift`
/// (Cranley–Patterson): the first coordinate steps evenly, the second by the golden ratio.
pub(crate) fn lattice(s: u32, count: u32, shift: (f64, f64)) -> (f64, f64) {
    let u1 = ((f64::from(s) + 0.5) / f64::from(count) + shift.0).fract();
    let u2 = (f64::from(s) * GOLDEN + shift.1).fract();
    (u1, u2)
}

/// The sphere around some triangles: their vertices' mean and the farthest vertex from it.
fn bounds(triangles: &[[Vec3; 3]]) -> (Vec3, f32) {
    let n = (3 * triangles.len()).max(1) as f32;
    let centre = triangles.iter().flatten().fold(Vec3::ZERO, |a, &v| a + v) / n;
    let radius = triangles
        .iter()
        .flatten()
        .map(|v| v.distance(centre))
        .fold(0.0f32, f32::max);
    (centre, radius)
}

/// Direct light from a scene's lights.
pub struct DirectLight {
    emitters: Vec<Emitter>,
    points: Vec<PointSource>,
    light_samples: u32,
    lift: f32,
    /// The scene's mirrors, panes and glass, and the chains of reflectors lights are seen
    /// through; `None` where it has none (the shadow rays are then plain occlusion queries).
    specular: Option<(Specular, Vec<Chain>)>,
    /// Per chain, the emitters as seen through it (their mirror images).
    images: Vec<Vec<Emitter>>,
    /// Per reflector, its triangles: the outline an image is seen through.
    windows: Vec<Vec<[Vec3; 3]>>,
    /// Whether the lights are reached straight too (not only through mirrors).
    straight: bool,
    /// The sun, where daylight with sunlight enters the scene.
    sun: Option<Sun>,
}

/// The sun as a light: a disc of 0.533° delivering `illuminance` on a plane facing it.
#[derive(Clone, Copy, Debug)]
struct Sun {
    /// Unit direction towards its centre.
    dir: Vec3,
    illuminance: f64,
    /// Two unit directions across the disc.
    across: (Vec3, Vec3),
    /// How far a ray is followed to leave the scene.
    far: f32,
}

impl Sun {
    /// The most shadow rays a receiver sends to the sun: its disc is small, so its penumbrae
    /// are narrow and a few stratified rays draw them.
    const RAYS: u32 = 16;

    /// Direction `s` of `count` over the disc (uniform in solid angle, on a Fibonacci lattice
    /// shifted by `shift`).
    fn ray(&self, s: u32, count: u32, shift: (f64, f64)) -> Vec3 {
        let (u1, u2) = lattice(s, count, shift);
        let cos_max = crate::daylight::SUN_RADIUS_DEGREES.to_radians().cos();
        let cos = 1.0 - u1 * (1.0 - cos_max);
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = std::f64::consts::TAU * u2;
        (self.dir * cos as f32
            + self.across.0 * (sin * phi.cos()) as f32
            + self.across.1 * (sin * phi.sin()) as f32)
            .normalize()
    }
}

/// Which ways to the lights a [`DirectLight`] takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Reach {
    /// Straight, and through every chain of images listed.
    All,
    /// Straight, and through single reflectors: what the image traces at its pixels, where
    /// shadows and reflections are sharpest.
    Near,
    /// Through chains of two reflectors or more only: the dimmer, farther images the samples
    /// take whole and the image interpolates.
    Far,
}

/// The straight way from a receiver to a light: no reflector.
const STRAIGHT: &[u32] = &[];

/// Direct light arriving at one point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Arrival {
    /// Irradiance, W/m², RGB.
    pub irradiance: DVec3,
    /// Fraction of the unoccluded irradiance whose shadow rays get through (1 fully lit, 0 in
    /// full shadow); a mirror's or a pane's reflectance or transmittance along the way dims
    /// the irradiance but is no shadow.
    pub visible: f32,
    /// The form factor, as visible, from the point to the emitters that do not reflect:
    /// the part of its hemisphere that sends light but takes none back.
    pub dark_emitters: f64,
}

impl DirectLight {
    /// Receivers per chunk of [`DirectLight::at`]'s work.
    pub(crate) const CHUNK: usize = 256;

    /// Prepares the lights; `light_samples` shadow rays per area light and receiver.
    pub fn new(scene: &Scene, light_samples: u32) -> DirectLight {
        let emitters = scene
            .emitter_groups()
            .into_iter()
            .map(|group| {
                let triangles = scene.triangles_of(&group);
                let cumulative = cumulative_area(&triangles);
                let tris: Vec<[Vec3; 3]> = triangles.iter().map(|t| t.vertices).collect();
                let (first, material) = (group[0], scene.material_of(group[0]));
                let surface = &scene.surfaces[first as usize];
                Emitter {
                    bounds: bounds(&tris),
                    facets: if group.len() > 1 {
                        triangles
                            .iter()
                            .map(|t| (t.normal, t.normal.dot(t.vertices[0])))
                            .collect()
                    } else {
                        Vec::new()
                    },
                    triangles: tris,
                    cumulative,
                    normal: surface.normal,
                    offset: surface.offset,
                    ke: material.ke.as_dvec3(),
                    reflects: material.reflects_diffusely(),
                }
            })
            .collect();
        let points = scene.point_sources();
        let sun = scene
            .daylight()
            .and_then(crate::daylight::Daylight::sun_light)
            .map(|(dir, illuminance)| Sun {
                dir,
                illuminance,
                across: dir.any_orthonormal_pair(),
                far: 2.0 * scene.bounds.diagonal() + 1.0,
            });
        DirectLight {
            emitters,
            points,
            light_samples: light_samples.max(1),
            lift: crate::visibility::lift(scene),
            specular: None,
            images: Vec::new(),
            windows: Vec::new(),
            straight: true,
            sun,
        }
    }

    /// The sun alone (no lamps, no area lights), where daylight with sunlight enters the scene:
    /// what it brings is daylight's share of the emitted power.
    pub(crate) fn sun_only(scene: &Scene, light_samples: u32) -> Option<DirectLight> {
        let mut light = DirectLight::new(scene, light_samples);
        light.sun?;
        light.emitters.clear();
        light.points.clear();
        light.specular = Specular::of(scene)
            .any()
            .then(|| (Specular::of(scene), Vec::new()));
        Some(light)
    }

    /// The sun alone towards unit scene direction `dir`, delivering 1 on a plane facing it,
    /// whatever the scene's own sky: a year of weather's sunlight, hour by hour
    /// ([`DirectLight::aim_sun`]).
    pub(crate) fn unit_sun(scene: &Scene, light_samples: u32, dir: Vec3) -> DirectLight {
        let mut light = DirectLight::new(scene, light_samples);
        light.emitters.clear();
        light.points.clear();
        let spec = Specular::of(scene);
        light.specular = spec.any().then(|| (spec, Vec::new()));
        light.sun = Some(Sun {
            dir,
            illuminance: 1.0,
            across: dir.any_orthonormal_pair(),
            far: 2.0 * scene.bounds.diagonal() + 1.0,
        });
        light
    }

    /// Points the sun at unit scene direction `dir` (a light with a sun only).
    pub(crate) fn aim_sun(&mut self, dir: Vec3) {
        if let Some(sun) = &mut self.sun {
            sun.dir = dir;
            sun.across = dir.any_orthonormal_pair();
        }
    }

    /// Direct light that also arrives by way of the scene's mirrors, panes and glass: through
    /// mirror images of the lights up to `depth` reflections, and through glass along straight
    /// lines (`specular::shadow`). A scene with none of them, or a depth of 0 (specular surfaces
    /// then block light), is lit as by [`DirectLight::new`].
    pub(crate) fn with_specular(scene: &Scene, light_samples: u32, depth: u32) -> DirectLight {
        DirectLight::reaching(scene, light_samples, depth, Reach::All)
    }

    /// [`DirectLight::with_specular`] along some of the ways only (see [`Reach`]).
    pub(crate) fn reaching(
        scene: &Scene,
        light_samples: u32,
        depth: u32,
        reach: Reach,
    ) -> DirectLight {
        let mut light = DirectLight::new(scene, light_samples);
        light.straight = reach != Reach::Far;
        let spec = Specular::of(scene);
        if depth > 0 && !spec.reflectors.is_empty() {
            let mut chains = images::chains(&spec, depth).chains;
            chains.retain(|c| match reach {
                Reach::All => true,
                Reach::Near => c.reflectors.len() == 1,
                Reach::Far => c.reflectors.len() > 1,
            });
            light.images = chains
                .iter()
                .map(|c| {
                    light
                        .emitters
                        .iter()
                        .map(|e| {
                            let turn = |n: Vec3| (c.linear.transpose() * n.as_dvec3()).as_vec3();
                            let normal = turn(e.normal);
                            let triangles: Vec<[Vec3; 3]> = e
                                .triangles
                                .iter()
                                .map(|t| t.map(|v| c.image_of(&spec, v)))
                                .collect();
                            let facets = triangles
                                .iter()
                                .zip(&e.facets)
                                .map(|(t, &(n, _))| (turn(n), turn(n).dot(t[0])))
                                .collect();
                            Emitter {
                                offset: normal.dot(triangles[0][0]),
                                bounds: bounds(&triangles),
                                normal,
                                facets,
                                triangles,
                                cumulative: e.cumulative.clone(),
                                ke: e.ke,
                                reflects: e.reflects,
                            }
                        })
                        .collect()
                })
                .collect();
            light.windows = spec
                .reflectors
                .iter()
                .map(|r| {
                    let range = &scene.surfaces[r.surface as usize].triangles;
                    scene.triangles[range.start as usize..range.end as usize]
                        .iter()
                        .map(|t| t.vertices)
                        .collect()
                })
                .collect();
            light.specular = Some((spec, chains));
        }
        light
    }

    /// The ways to the lights: straight (if it goes straight), then each chain of reflectors
    /// with its index.
    fn ways(&self) -> impl Iterator<Item = Option<(usize, &Chain)>> {
        let chains = self
            .specular
            .iter()
            .flat_map(|(_, c)| c.iter().enumerate().map(Some));
        self.straight.then_some(None).into_iter().chain(chains)
    }

    /// Whether it takes no way at all (far images in a scene without any).
    pub(crate) fn is_empty(&self) -> bool {
        !self.straight && self.images.is_empty()
    }

    /// The share of light arriving along each path (1 or 0 without specular surfaces);
    /// returns the queries.
    fn shares(&self, vis: &dyn Visibility, paths: &[LightPath], out: &mut [DVec3]) -> Result<u64> {
        match &self.specular {
            Some((spec, _)) => shadow::arriving(spec, vis, self.lift, paths, out),
            None => {
                let segments: Vec<Segment> = paths
                    .iter()
                    .map(|p| Segment { a: p.from, b: p.to })
                    .collect();
                let mut blocked = vec![false; segments.len()];
                vis.occluded(&segments, &mut blocked)?;
                for (o, b) in out.iter_mut().zip(blocked) {
                    *o = if b { DVec3::ZERO } else { DVec3::ONE };
                }
                Ok(segments.len() as u64)
            }
        }
    }

    /// Shadow rays one receiver may cast (for progress and query counts).
    pub fn rays_per_receiver(&self) -> usize {
        self.points.len()
            + self.emitters.len() * self.light_samples as usize
            + self.sun.map_or(0, |_| self.sun_rays() as usize)
    }

    /// Shadow rays per receiver to the sun.
    fn sun_rays(&self) -> u32 {
        self.light_samples.min(Sun::RAYS)
    }

    /// Direct light at each (position, normal); receiver i draws its shadow rays from a seed
    /// derived from (`seed`, `ids[i]`), so answers do not depend on batching or threads.
    /// `report` hears the share done now and then; after a Stop the receivers not reached yet
    /// are left dark.
    pub fn at(
        &self,
        vis: &dyn Visibility,
        points: &[(Vec3, Vec3)],
        ids: &[u32],
        seed: u64,
        threads: usize,
        report: Report,
    ) -> Result<(Vec<Arrival>, u64)> {
        let mut out = vec![Arrival::default(); points.len()];
        let queries = std::sync::atomic::AtomicU64::new(0);
        let work = |first: usize, chunk: &mut [Arrival]| {
            let n = self.batch(
                vis,
                &points[first..first + chunk.len()],
                &ids[first..first + chunk.len()],
                seed,
                chunk,
            )?;
            queries.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
            Ok(())
        };
        for_chunks_reporting(&mut out, Self::CHUNK, threads, work, report)?;
        Ok((out, queries.into_inner()))
    }

    /// One batch: the shadow rays of its receivers, one visibility call per kind of light and
    /// part of the batch (parts of at most [`RAYS_PER_CALL`] rays).
    pub(crate) fn batch(
        &self,
        vis: &dyn Visibility,
        points: &[(Vec3, Vec3)],
        ids: &[u32],
        seed: u64,
        out: &mut [Arrival],
    ) -> Result<u64> {
        let part = (RAYS_PER_CALL / self.rays_per_receiver().max(1)).max(1);
        let mut queries = 0;
        for ((points, ids), out) in points
            .chunks(part)
            .zip(ids.chunks(part))
            .zip(out.chunks_mut(part))
        {
            queries += self.batch_part(vis, points, ids, seed, out)?;
        }
        Ok(queries)
    }

    /// [`DirectLight::batch`] for a part that fits in one call per kind of light.
    fn batch_part(
        &self,
        vis: &dyn Visibility,
        points: &[(Vec3, Vec3)],
        ids: &[u32],
        seed: u64,
        out: &mut [Arrival],
    ) -> Result<u64> {
        // Per receiver: the light that arrives, and what would arrive with nothing in the way.
        let mut arrived = vec![DVec3::ZERO; points.len()];
        // What would arrive with nothing in the way, and the part of it whose rays got
        // through (a mirror's or a pane's reflectance along the way is not a shadow).
        let mut unoccluded = vec![0.0f64; points.len()];
        let mut open = vec![0.0f64; points.len()];
        let point_queries =
            self.point_lights_at(vis, points, &mut arrived, (&mut unoccluded, &mut open))?;
        let mut dark_emitters = vec![0.0f64; points.len()];
        let area_queries = self.area_lights_at(
            vis,
            (points, ids, seed),
            &mut arrived,
            (&mut unoccluded, &mut open),
            &mut dark_emitters,
        )?;
        let sun_queries = self.sun_at(
            vis,
            (points, ids, seed),
            &mut arrived,
            (&mut unoccluded, &mut open),
        )?;
        for (r, o) in out.iter_mut().enumerate() {
            let (h, full) = (arrived[r], unoccluded[r]);
            *o = Arrival {
                irradiance: h,
                visible: if full > 0.0 {
                    (open[r] / full).clamp(0.0, 1.0) as f32
                } else {
                    0.0
                },
                dark_emitters: dark_emitters[r],
            };
        }
        Ok(point_queries + area_queries + sun_queries)
    }

    /// The sun: its illuminance × cos θ × the share of stratified shadow rays over its disc
    /// that leave the model (through glass with its transmittance), straight only. Adds to
    /// `arrived` and `unoccluded`; returns the queries.
    fn sun_at(
        &self,
        vis: &dyn Visibility,
        (points, ids, seed): (&[(Vec3, Vec3)], &[u32], u64),
        arrived: &mut [DVec3],
        (unoccluded, open): (&mut [f64], &mut [f64]),
    ) -> Result<u64> {
        let Some(sun) = self.sun.filter(|_| self.straight) else {
            return Ok(0);
        };
        let count = self.sun_rays();
        let mut lit = Vec::new();
        let mut rays = Vec::new();
        for (r, (&(x, n), &id)) in points.iter().zip(ids).enumerate() {
            let cos = f64::from(n.dot(sun.dir));
            if cos <= 0.0 {
                continue;
            }
            let full = sun.illuminance * cos;
            unoccluded[r] += 3.0 * full;
            let mut rng = Pcg64Mcg::seed_from_u64(side_seed(seed, id, 5));
            let shift = (rng.random::<f64>(), rng.random::<f64>());
            let from = x + self.lift * n;
            for s in 0..count {
                let dir = sun.ray(s, count, shift);
                // Each ray carries its own cosine: a receiver the disc's edge grazes.
                let c = f64::from(n.dot(dir)).max(0.0);
                rays.push(Ray {
                    origin: from,
                    dir,
                    t_min: 0.0,
                    t_max: sun.far,
                });
                lit.push((r, sun.illuminance * c / f64::from(count)));
            }
        }
        if rays.is_empty() {
            return Ok(0);
        }
        let mut shares = vec![DVec3::ZERO; rays.len()];
        match &self.specular {
            Some((spec, _)) => {
                let paths: Vec<LightPath> = rays
                    .iter()
                    .map(|ray| LightPath {
                        from: ray.origin,
                        to: ray.origin + ray.dir * sun.far,
                        chain: STRAIGHT,
                    })
                    .collect();
                shadow::arriving(spec, vis, self.lift, &paths, &mut shares)?;
            }
            None => {
                // Rays, not segments: a segment out of the scene ignores hits within 10⁻⁵ of
                // its length of its start, nearer than a corner's sample to the next wall.
                let mut hits = vec![None; rays.len()];
                vis.intersect(&rays, &mut hits)?;
                for (share, hit) in shares.iter_mut().zip(hits) {
                    *share = if hit.is_some() {
                        DVec3::ZERO
                    } else {
                        DVec3::ONE
                    };
                }
            }
        }
        for (&(r, e), share) in lit.iter().zip(&shares) {
            arrived[r] += *share * e;
            if share.max_element() > 0.0 {
                open[r] += 3.0 * e;
            }
        }
        Ok(rays.len() as u64)
    }

    /// Point lights: I·cosθ/r² through one shadow ray each, and from each mirror image with
    /// the intensity the light sends towards the image's last window. Adds to `arrived` and
    /// `unoccluded`; returns the queries.
    fn point_lights_at(
        &self,
        vis: &dyn Visibility,
        points: &[(Vec3, Vec3)],
        arrived: &mut [DVec3],
        (unoccluded, open): (&mut [f64], &mut [f64]),
    ) -> Result<u64> {
        let mut paths = Vec::new();
        let mut lit = Vec::new();
        for (r, &(x, n)) in points.iter().enumerate() {
            let from = x + self.lift * n;
            for source in &self.points {
                for way in self.ways() {
                    let (p, chain) = match (way, &self.specular) {
                        (Some((_, c)), Some((spec, _))) if c.faces(spec, x) => {
                            (c.image_of(spec, source.position), c.reflectors.as_slice())
                        }
                        (Some(_), _) => continue,
                        (None, _) => (source.position, STRAIGHT),
                    };
                    let d = p - x;
                    let r2 = d.length_squared();
                    let cos = n.dot(d) / r2.sqrt();
                    if cos > 0.0 && r2 > 0.0 {
                        // The direction the light leaves in: the unfolded line's, reflected.
                        let leaving = match way {
                            Some((_, c)) => (c.linear * -d.as_dvec3()).as_vec3(),
                            None => -d,
                        };
                        let intensity = source.towards(leaving).as_dvec3();
                        let contribution = intensity * f64::from(cos / r2);
                        unoccluded[r] += contribution.element_sum();
                        paths.push(LightPath { from, to: p, chain });
                        lit.push((r, contribution));
                    }
                }
            }
        }
        let mut shares = vec![DVec3::ZERO; paths.len()];
        let queries = self.shares(vis, &paths, &mut shares)?;
        for (&(r, contribution), share) in lit.iter().zip(&shares) {
            if share.max_element() > 0.0 {
                arrived[r] += contribution * *share;
                open[r] += contribution.element_sum();
            }
        }
        Ok(queries)
    }

    /// Area lights: Lambert's exact irradiance × the visible share of stratified shadow rays
    /// (the ratio estimator), for each emitter and each of its mirror images (whose rays must
    /// pass their windows; the share then carries the windows' reflectances). Adds to
    /// `arrived`, `unoccluded` and `dark_emitters` (the visible form factor to emitters that do
    /// not reflect, seen directly); returns the queries.
    fn area_lights_at(
        &self,
        vis: &dyn Visibility,
        (points, ids, seed): (&[(Vec3, Vec3)], &[u32], u64),
        arrived: &mut [DVec3],
        (unoccluded, open): (&mut [f64], &mut [f64]),
        dark_emitters: &mut [f64],
    ) -> Result<u64> {
        let ne = self.emitters.len();
        if ne == 0 {
            return Ok(0);
        }
        let ways = 1 + self.images.len();
        let slots = ne * ways;
        // Per receiver, emitter and way: analytic irradiance, the unoccluded form factor
        // (emitters that do not reflect, straight), and Σ weights, Σ weights × share of its
        // shadow rays.
        let mut tally = Tally {
            analytic: vec![DVec3::ZERO; points.len() * slots],
            factor: vec![0.0f64; points.len() * slots],
            weights: vec![(0.0f64, DVec3::ZERO); points.len() * slots],
            paths: Vec::new(),
            rays: Vec::new(),
        };
        let mut draw = spherical::Draw::default();
        for (r, (&(x, n), &id)) in points.iter().zip(ids).enumerate() {
            let from = x + self.lift * n;
            let mut rng = Pcg64Mcg::seed_from_u64(side_seed(seed, id, 2));
            for way in self.ways() {
                // Slot 0 is the straight way, 1 + i chain i.
                let w = way.map_or(0, |(i, _)| 1 + i);
                let (emitters, chain) = match (way, &self.specular) {
                    (Some((i, c)), Some((spec, _))) => {
                        if !c.faces(spec, x) {
                            continue;
                        }
                        (&self.images[i], c.reflectors.as_slice())
                    }
                    _ => (&self.emitters, STRAIGHT),
                };
                for (e, emitter) in emitters.iter().enumerate() {
                    if let (Some(&k), Some((spec, _))) = (chain.first(), &self.specular) {
                        if !spec.reflectors[k as usize].may_show(from, &emitter.triangles) {
                            // No line to the image passes the window: it brings nothing.
                            continue;
                        }
                    }
                    let slot = (r * ways + w) * ne + e;
                    let seen = Seen {
                        x,
                        n,
                        from,
                        slot,
                        chain,
                        straight: w == 0,
                    };
                    self.emitter_rays(
                        emitter,
                        &seen,
                        &mut rng,
                        &mut draw,
                        &mut tally,
                        unoccluded.get_mut(r).expect("one per receiver"),
                    );
                }
            }
        }
        let Tally {
            analytic,
            factor,
            mut weights,
            paths,
            rays,
        } = tally;
        let mut shares = vec![DVec3::ZERO; paths.len()];
        let queries = self.shares(vis, &paths, &mut shares)?;
        // Per slot, Σ weights of the rays that got through.
        let mut through = vec![0.0f64; weights.len()];
        for (&(slot, weight), share) in rays.iter().zip(&shares) {
            if share.max_element() > 0.0 {
                weights[slot].1 += weight * *share;
                through[slot] += weight;
            }
        }
        for r in 0..points.len() {
            for slot in r * slots..(r + 1) * slots {
                let (all, visible) = weights[slot];
                if all > 0.0 {
                    arrived[r] += analytic[slot] * (visible / all);
                    dark_emitters[r] += factor[slot] * (visible.x / all);
                    open[r] += analytic[slot].element_sum() * (through[slot] / all);
                }
            }
        }
        Ok(queries)
    }

    /// One emitter (or its image) seen from receiver x: its analytic irradiance, and its
    /// shadow rays on a Fibonacci lattice shifted at random per receiver (Cranley and
    /// Patterson): as even in two dimensions as a grid for any count, and unbiased.
    fn emitter_rays<'c>(
        &self,
        emitter: &Emitter,
        seen: &Seen<'c>,
        rng: &mut Pcg64Mcg,
        draw: &mut spherical::Draw,
        tally: &mut Tally<'c>,
        unoccluded: &mut f64,
    ) {
        if !emitter.facets.is_empty() {
            return self.facet_rays(emitter, seen, rng, tally, unoccluded);
        }
        let (x, n) = (seen.x, seen.n);
        // An image seen through one mirror: only the part its outline lets through.
        let clipped;
        let emitter = match (seen.chain, &self.specular) {
            (&[k], Some((spec, _))) if (k as usize) < self.windows.len() => {
                let r = &spec.reflectors[k as usize];
                let pieces = window::through(
                    &emitter.triangles,
                    x,
                    &self.windows[k as usize],
                    (r.normal, r.offset),
                );
                if pieces.is_empty() {
                    return;
                }
                clipped = emitter.cut_to(pieces);
                &clipped
            }
            _ => emitter,
        };
        // Emitters light only what lies in front of them.
        let height = emitter.normal.dot(x) - emitter.offset;
        if height <= 0.0 {
            return;
        }
        let irradiance: f64 = emitter
            .triangles
            .iter()
            .map(|t| polygon_irradiance(t, x, n))
            .sum();
        if irradiance <= 0.0 {
            return;
        }
        tally.exact(seen, emitter, irradiance, unoccluded);
        // Near emitters are drawn uniformly in solid angle, far ones (or ones rounding defeats)
        // uniformly in area: see `spherical`.
        let (centre, radius) = emitter.bounds;
        let solid = spherical::worth_drawing(height, radius, x.distance(centre))
            && draw.prepare(&emitter.triangles, x, MIN_SOLID_ANGLE);
        let cumulative = if solid {
            draw.cumulative()
        } else {
            emitter.cumulative.as_slice()
        };
        let total = *cumulative.last().unwrap_or(&0.0);
        let count = self.light_samples;
        let shift = (rng.random::<f64>(), rng.random::<f64>());
        for s in 0..count {
            let (u1, u2) = lattice(s, count, shift);
            // The first coordinate runs along the emitter's cumulative solid angle (or area):
            // it picks the triangle, and what is left of it places the point inside.
            let u = u1 * total;
            let t = cumulative
                .partition_point(|&c| c <= u)
                .min(emitter.triangles.len() - 1);
            let start = if t == 0 { 0.0 } else { cumulative[t - 1] };
            let within = ((u - start) / (cumulative[t] - start)).clamp(0.0, 1.0);
            let y = if solid {
                let w = draw.sample(t, within, u2);
                match w.and_then(|w| spherical::on_plane(emitter.normal, emitter.offset, x, w)) {
                    Some(y) => y,
                    None => continue,
                }
            } else {
                in_triangle(emitter.triangles[t], within, u2)
            };
            let d = y - x;
            let dist2 = d.length_squared();
            let cos_x = n.dot(d);
            let cos_y = -emitter.normal.dot(d);
            if cos_x <= 0.0 || cos_y <= 0.0 || dist2 <= 0.0 {
                continue;
            }
            // The integrand over the density the ray was drawn with, up to a factor common to
            // all of this emitter's rays: cos_x over solid angle, cos_x·cos_y/r² over area.
            let weight = if solid {
                f64::from(cos_x / dist2.sqrt())
            } else {
                f64::from(cos_x * cos_y / (dist2 * dist2))
            };
            self.shadow_ray(seen, y + self.lift * emitter.normal, weight, tally);
        }
    }
}

impl DirectLight {
    /// [`DirectLight::emitter_rays`] for an emitter of many planes (a sphere, a tube): the
    /// analytic irradiance summed over the triangles facing x, and the shadow rays spread over
    /// the triangles by their share of it (uniform over each triangle's area), so one ray budget
    /// serves the whole light whatever its tessellation.
    fn facet_rays<'c>(
        &self,
        emitter: &Emitter,
        seen: &Seen<'c>,
        rng: &mut Pcg64Mcg,
        tally: &mut Tally<'c>,
        unoccluded: &mut f64,
    ) {
        let (x, n) = (seen.x, seen.n);
        // Per facing triangle: (triangle, its irradiance, cumulative irradiance).
        let mut facing: Vec<(usize, f64, f64)> = Vec::new();
        let mut irradiance = 0.0;
        for (t, (tri, &(normal, offset))) in
            emitter.triangles.iter().zip(&emitter.facets).enumerate()
        {
            if normal.dot(x) - offset <= 0.0 {
                continue;
            }
            let e = polygon_irradiance(tri, x, n);
            if e > 0.0 {
                irradiance += e;
                facing.push((t, e, irradiance));
            }
        }
        if irradiance <= 0.0 {
            return;
        }
        tally.exact(seen, emitter, irradiance, unoccluded);
        let count = self.light_samples;
        let shift = (rng.random::<f64>(), rng.random::<f64>());
        for s in 0..count {
            let (u1, u2) = lattice(s, count, shift);
            // The first coordinate picks a triangle by its irradiance; what is left of it and
            // the second place the point uniformly inside.
            let u = u1 * irradiance;
            let k = facing
                .partition_point(|&(_, _, c)| c <= u)
                .min(facing.len() - 1);
            let (t, e, end) = facing[k];
            let within = ((u - (end - e)) / e).clamp(0.0, 1.0);
            let [a, b, c] = emitter.triangles[t];
            let y = in_triangle([a, b, c], within, u2);
            let normal = emitter.facets[t].0;
            let d = y - x;
            let dist2 = d.length_squared();
            let (cos_x, cos_y) = (n.dot(d), -normal.dot(d));
            if cos_x <= 0.0 || cos_y <= 0.0 || dist2 <= 0.0 {
                continue;
            }
            // The integrand cos·cos/r² over the density (e/E)/A of the point, up to E.
            let area = 0.5 * f64::from((b - a).cross(c - a).length());
            let weight = f64::from(cos_x * cos_y / (dist2 * dist2)) * area / e;
            self.shadow_ray(seen, y + self.lift * normal, weight, tally);
        }
    }
}

impl DirectLight {
    /// One shadow ray of weight `weight` from the receiver `seen` to the point `to` (lifted off
    /// its emitter): it counts in the slot's weights, and is traced unless its line misses the
    /// chain's first window (then it brings nothing, without a path).
    fn shadow_ray<'c>(&self, seen: &Seen<'c>, to: Vec3, weight: f64, tally: &mut Tally<'c>) {
        tally.weights[seen.slot].0 += weight;
        if let (Some(&k), Some((spec, _))) = (seen.chain.first(), &self.specular) {
            if !spec.reflectors[k as usize].may_pass(seen.from, to) {
                return;
            }
        }
        tally.paths.push(LightPath {
            from: seen.from,
            to,
            chain: seen.chain,
        });
        tally.rays.push((seen.slot, weight));
    }
}

/// A receiver as one emitter (or one of its images) sees it: the point, its normal, where its
/// shadow rays start, and the slot their tally goes to (receiver × way × emitter) with the
/// chain of reflectors the way passes (none straight).
#[derive(Clone, Copy)]
struct Seen<'c> {
    x: Vec3,
    n: Vec3,
    from: Vec3,
    slot: usize,
    chain: &'c [u32],
    straight: bool,
}

impl Tally<'_> {
    /// An emitter's unoccluded light at a receiver's slot: its analytic irradiance (Lambert's,
    /// `irradiance` per unit radiance), the form factor to it where it reflects nothing and is
    /// seen straight, and its share of `unoccluded`.
    fn exact(&mut self, seen: &Seen, emitter: &Emitter, irradiance: f64, unoccluded: &mut f64) {
        self.analytic[seen.slot] = emitter.ke * irradiance;
        if !emitter.reflects && seen.straight {
            self.factor[seen.slot] = irradiance / std::f64::consts::PI;
        }
        *unoccluded += (emitter.ke * irradiance).element_sum();
    }
}

/// Per slot, what a batch of receivers' area lights add up to: the analytic irradiance, the
/// unoccluded form factor to dark emitters, Σ weights and Σ weights × visible share; and the
/// shadow rays to trace, each with its slot and weight.
struct Tally<'c> {
    analytic: Vec<DVec3>,
    factor: Vec<f64>,
    weights: Vec<(f64, DVec3)>,
    paths: Vec<LightPath<'c>>,
    rays: Vec<(usize, f64)>,
}

/// Irradiance at x (normal n) from a triangle of unit radiance emitting towards x: Lambert's
/// formula E = ½ Σ θ_i (n · Γ_i) over the triangle clipped to the half-space above x's plane.
pub fn polygon_irradiance(t: &[Vec3; 3], x: Vec3, n: Vec3) -> f64 {
    convex_polygon_irradiance(t, x, n)
}

/// Lambert's formula for a convex polygon of any number of vertices (see
/// [`polygon_irradiance`]).
pub fn convex_polygon_irradiance(polygon: &[Vec3], x: Vec3, n: Vec3) -> f64 {
    // Clipping adds at most one vertex per edge (one in all for a convex polygon): small
    // polygons, the hot case, stay on the stack.
    if polygon.len() <= 8 {
        clipped_irradiance(polygon, x, n, &mut [DVec3::ZERO; 16])
    } else {
        clipped_irradiance(polygon, x, n, &mut vec![DVec3::ZERO; 2 * polygon.len()])
    }
}

/// [`convex_polygon_irradiance`] with room for the clipped polygon in `poly` (2 × vertices).
fn clipped_irradiance(polygon: &[Vec3], x: Vec3, n: Vec3, poly: &mut [DVec3]) -> f64 {
    let n = n.as_dvec3();
    let x = x.as_dvec3();
    // Clip to n · (p − x) ≥ 0 (Sutherland–Hodgman).
    let mut len = 0;
    let m = polygon.len();
    for i in 0..m {
        let a = polygon[i].as_dvec3() - x;
        let b = polygon[(i + 1) % m].as_dvec3() - x;
        let (da, db) = (n.dot(a), n.dot(b));
        if da >= 0.0 {
            poly[len] = a;
            len += 1;
        }
        if (da >= 0.0) != (db >= 0.0) {
            poly[len] = a + (b - a) * (da / (da - db));
            len += 1;
        }
    }
    if len < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for i in 0..len {
        let (a, b) = (poly[i], poly[(i + 1) % len]);
        let cross = a.cross(b);
        let cl = cross.length();
        if cl <= 0.0 || a.length_squared() <= 0.0 || b.length_squared() <= 0.0 {
            continue;
        }
        let theta = cl.atan2(a.dot(b));
        sum += theta * n.dot(cross / cl);
    }
    0.5 * sum.abs()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tessellated_sphere_light_is_one_light_seen_by_its_projected_area() {
        // A ball of 320 emitting facets (radiance 1) in a dark room: one light, not 320. Far
        // from it, its irradiance on a surface facing it is its projected area / d² (the
        // facets' areas × their cosines towards the receiver, summed over the facets facing
        // it; worked out here without Lambert's formula), to within (r/d)².
        use crate::scene::fixtures::Parts;
        let mut p = Parts::default();
        let dark = p.material(crate::scene::Material::diffuse(
            "dark",
            Vec3::splat(0.5),
            Vec3::ZERO,
        ));
        let lamp = p.material(crate::scene::Material::diffuse(
            "lamp",
            Vec3::ZERO,
            Vec3::ONE,
        ));
        p.cuboid(Vec3::splat(-60.0), Vec3::splat(60.0), true, dark);
        p.sphere(Vec3::ZERO, 0.5, 2, lamp);
        let scene = p.scene(Vec3::new(0.0, 0.0, 50.0), Vec3::ZERO);
        assert_eq!(scene.emitters().count(), 320);
        let light = DirectLight::new(&scene, 16);
        assert_eq!(light.emitters.len(), 1);
        let vis = crate::visibility::Backend::Bvh.build(&scene).unwrap();
        let d = 50.0f32;
        for dir in [Vec3::Z, Vec3::new(1.0, 2.0, -0.5).normalize(), Vec3::NEG_Y] {
            let projected: f64 = scene
                .triangles
                .iter()
                .filter(|t| scene.material_of(t.surface).is_emitter())
                .map(|t| f64::from(t.area) * f64::from(t.normal.dot(dir)).max(0.0))
                .sum();
            let expected = projected / f64::from(d * d);
            let (arrivals, _) = light
                .at(vis.as_ref(), &[(dir * d, -dir)], &[0], 1, 1, &mut |_| {
                    crate::progress::Control::Continue
                })
                .unwrap();
            let e = arrivals[0].irradiance.x;
            assert!(
                (e / expected - 1.0).abs() < 1e-3,
                "{dir}: {e} against {expected}"
            );
            assert_eq!(arrivals[0].visible, 1.0);
        }
    }

    #[test]
    fn polygons_of_many_vertices_count_every_vertex() {
        // A regular 256-gon of radius 1 at height 1 over x, facing it: nearly the disc, whose
        // irradiance at unit radiance is π R² / (R² + h²) = π/2; the inscribed polygon's area
        // is 0.01% smaller. Dropping vertices beyond 8 gave a fraction of that.
        let polygon: Vec<Vec3> = (0..256)
            .map(|i| {
                let a = std::f32::consts::TAU * i as f32 / 256.0;
                Vec3::new(a.cos(), a.sin(), 1.0)
            })
            .collect();
        let e = convex_polygon_irradiance(&polygon, Vec3::ZERO, Vec3::Z);
        let disc = std::f64::consts::PI / 2.0;
        assert!((e / disc - 1.0).abs() < 2e-3, "{e} vs {disc}");
    }

    #[test]
    fn a_large_square_overhead_gives_nearly_pi() {
        // Radiance 1 over a huge plane fills the hemisphere: irradiance π.
        let big = 1e4;
        let a = [
            Vec3::new(-big, -big, 1.0),
            Vec3::new(big, -big, 1.0),
            Vec3::new(big, big, 1.0),
        ];
        let b = [
            Vec3::new(-big, -big, 1.0),
            Vec3::new(big, big, 1.0),
            Vec3::new(-big, big, 1.0),
        ];
        let e = polygon_irradiance(&a, Vec3::ZERO, Vec3::Z)
            + polygon_irradiance(&b, Vec3::ZERO, Vec3::Z);
        assert!((e - std::f64::consts::PI).abs() < 1e-3, "{e}");
    }

    #[test]
    fn parallel_unit_squares_at_distance_one() {
        // Point form factor at the centre below a unit square at height 1 (closed form):
        // F = (2/π)·[a/√(1+a²)·atan(a/√(1+a²))]·… here checked against numeric integration.
        let sq = [
            [
                Vec3::new(-0.5, -0.5, 1.0),
                Vec3::new(0.5, -0.5, 1.0),
                Vec3::new(0.5, 0.5, 1.0),
            ],
            [
                Vec3::new(-0.5, -0.5, 1.0),
                Vec3::new(0.5, 0.5, 1.0),
                Vec3::new(-0.5, 0.5, 1.0),
            ],
        ];
        let e: f64 = sq
            .iter()
            .map(|t| polygon_irradiance(t, Vec3::ZERO, Vec3::Z))
            .sum();
        let n = 2000;
        let mut numeric = 0.0;
        for i in 0..n {
            for j in 0..n {
                let x = -0.5 + (i as f64 + 0.5) / n as f64;
                let y = -0.5 + (j as f64 + 0.5) / n as f64;
                let r2 = x * x + y * y + 1.0;
                numeric += 1.0 / (r2 * r2) / (n * n) as f64;
            }
        }
        assert!((e - numeric).abs() < 1e-6, "{e} vs {numeric}");
    }

    #[test]
    fn clipping_below_the_horizon() {
        // A triangle half below the receiver's plane counts only its upper half.
        let t = [
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(1.0, 1.0, -1.0),
            Vec3::new(1.0, 0.0, 1.0),
        ];
        let full = polygon_irradiance(&t, Vec3::ZERO, Vec3::X);
        let upper = polygon_irradiance(&t, Vec3::ZERO, Vec3::Z);
        assert!(full > 0.0 && upper > 0.0 && upper < full, "{upper} {full}");
    }
}
