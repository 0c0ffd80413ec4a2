//! Rendering (method.md §7): camera rays through the backend's closest hit; the radiance at a
//! hit is interpolated from the samples of the same surface side with smooth, normalised,
//! compactly supported weights sized by each sample's radius D (after Zwicker et al. 2001,
//! surface splatting). A sample contributes only if the segment from the hit to it is clear,
//! so light never passes through a thin wall or around a corner. Pixels are box-filtered:
//! one ray through the centre, and a grid of rays where the pixel straddles an edge between
//! surfaces.

pub(crate) mod image;

use glam::Vec3;

use crate::error::Result;
use crate::parallel::for_chunks;
use crate::sampling::{cover, is_back, side_of, surface_of, Side};
use crate::scene::Scene;
use crate::solver::Solution;
use crate::visibility::{Hit, Ray, Segment, Visibility};
pub use image::Image;

/// Kernel support: a sample reaches this many of its radii D.
const SUPPORT: f32 = 2.0;

/// Rendering settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    /// Worker threads.
    pub threads: usize,
    /// Pixels on an edge between surfaces get `supersample × supersample` rays (1 = never).
    pub supersample: u32,
    /// What each pixel holds.
    pub quantity: Quantity,
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
        }
    }
}

/// What rendering did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Camera rays traced.
    pub camera_rays: u64,
    /// Visibility queries between hits and samples.
    pub interpolation_queries: u64,
    /// Pixels that got the grid of rays.
    pub supersampled_pixels: u64,
}

/// Renders the scene's camera view of a solution.
pub fn render(
    scene: &Scene,
    solution: &Solution,
    vis: &dyn Visibility,
    options: &RenderOptions,
) -> Result<(Image, RenderStats)> {
    crate::parallel::guarded("rendering", || {
        let camera = &scene.camera;
        camera.check()?;
        solution.check_fits(scene)?;
        let (w, h) = (camera.width as usize, camera.height as usize);
        let shader = Shader::new(scene, solution, vis, options.quantity);
        let mut stats = RenderStats::default();

        // Centre rays: radiance and the side each pixel sees.
        let mut centre: Vec<(Vec3, u32)> = vec![(Vec3::ZERO, u32::MAX); w * h];
        let queries = std::sync::atomic::AtomicU64::new(0);
        for_chunks(&mut centre, w * 4, options.threads, |first, out| {
            let rays: Vec<Ray> = (first..first + out.len())
                .map(|p| camera_ray(scene, (p % w) as f32 + 0.5, (p / w) as f32 + 0.5))
                .collect();
            queries.fetch_add(
                shader.shade(&rays, out)?,
                std::sync::atomic::Ordering::Relaxed,
            );
            Ok(())
        })?;
        stats.camera_rays = (w * h) as u64;

        // Edge pixels: a neighbour sees another side.
        let n = options.supersample.max(1) as usize;
        let edges: Vec<usize> = if n > 1 {
            (0..w * h)
                .filter(|&p| {
                    let (x, y) = (p % w, p / w);
                    let side = centre[p].1;
                    (x > 0 && centre[p - 1].1 != side)
                        || (x + 1 < w && centre[p + 1].1 != side)
                        || (y > 0 && centre[p - w].1 != side)
                        || (y + 1 < h && centre[p + w].1 != side)
                })
                .collect()
        } else {
            Vec::new()
        };
        let mut refined = vec![Vec3::ZERO; edges.len()];
        for_chunks(&mut refined, 64, options.threads, |first, out| {
            let mut rays = Vec::with_capacity(out.len() * n * n);
            for &p in &edges[first..first + out.len()] {
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
            queries.fetch_add(
                shader.shade(&rays, &mut shaded)?,
                std::sync::atomic::Ordering::Relaxed,
            );
            for (o, group) in out.iter_mut().zip(shaded.chunks(n * n)) {
                *o = group.iter().map(|s| s.0).sum::<Vec3>() / (n * n) as f32;
            }
            Ok(())
        })?;
        stats.camera_rays += (edges.len() * n * n) as u64;
        stats.supersampled_pixels = edges.len() as u64;
        stats.interpolation_queries = queries.into_inner();

        let mut pixels: Vec<Vec3> = centre.into_iter().map(|c| c.0).collect();
        for (&p, &value) in edges.iter().zip(&refined) {
            pixels[p] = value;
        }
        Ok((
            Image {
                width: camera.width,
                height: camera.height,
                pixels,
            },
            stats,
        ))
    })
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
    solution: &'a Solution,
    vis: &'a dyn Visibility,
    lift: f32,
    /// Largest kernel support among each side's samples (0: the side has none).
    support: Vec<f32>,
    /// What the pixels hold.
    quantity: Quantity,
}

/// A hit waiting for its visibility answers.
struct Pending {
    side: Side,
    /// Range of its candidates in the batch's candidate list.
    candidates: std::ops::Range<usize>,
    /// Radiance when no sample is involved (misses, emitters without samples, black sides).
    fixed: Option<Vec3>,
    point: Vec3,
    /// Whether something hovers over the hit.
    covered: bool,
}

impl<'a> Shader<'a> {
    fn new(
        scene: &'a Scene,
        solution: &'a Solution,
        vis: &'a dyn Visibility,
        quantity: Quantity,
    ) -> Self {
        let s = &solution.samples;
        let mut support = vec![0.0f32; 2 * scene.surfaces.len()];
        for (&side, &d) in s.side.iter().zip(&s.radius) {
            support[side as usize] = support[side as usize].max(SUPPORT * d);
        }
        Shader {
            scene,
            solution,
            vis,
            lift: crate::visibility::lift(scene),
            support,
            quantity,
        }
    }

    /// What sample k shows: its radiance B/π, or its irradiance.
    fn value(&self, k: usize) -> glam::DVec3 {
        match self.quantity {
            Quantity::Radiance => self.solution.radiosity[k] / std::f64::consts::PI,
            Quantity::Irradiance => self.solution.irradiance[k],
        }
    }

    /// Whether sample k is covered (`sampling::cover`); a solution without the flags has none.
    fn sample_covered(&self, k: usize) -> bool {
        self.solution.covered.get(k).copied().unwrap_or(false)
    }

    /// Shades a batch of rays: (radiance, side seen or u32::MAX). Returns visibility queries.
    fn shade(&self, rays: &[Ray], out: &mut [(Vec3, u32)]) -> Result<u64> {
        let mut hits = vec![None; rays.len()];
        self.vis.intersect(rays, &mut hits)?;
        // Whether each hit that will be interpolated is covered, asked in one batch (hits on
        // emitters and sides without samples show a fixed value and need not ask).
        let interpolated: Vec<Option<(Vec3, Vec3)>> = rays
            .iter()
            .zip(&hits)
            .map(|(ray, hit)| {
                let Hit { t, triangle } = (*hit)?;
                let tri = &self.scene.triangles[triangle as usize];
                let back = ray.dir.dot(tri.normal) > 0.0;
                if self.support[side_of(tri.surface, back) as usize] <= 0.0 {
                    return None;
                }
                let normal = if back { -tri.normal } else { tri.normal };
                Some((ray.origin + t * ray.dir, normal))
            })
            .collect();
        let covers: Vec<Segment> = interpolated
            .iter()
            .flatten()
            .map(|&(p, n)| cover::segment(p, n, self.lift, self.solution.epsilon))
            .collect();
        let mut answers = vec![false; covers.len()];
        self.vis.occluded(&covers, &mut answers)?;
        let mut answer = answers.into_iter();
        let covered: Vec<bool> = interpolated
            .iter()
            .map(|h| h.is_some() && answer.next().unwrap_or(false))
            .collect();
        let s = &self.solution.samples;
        let mut pending = Vec::with_capacity(rays.len());
        let mut candidates: Vec<(u32, f32)> = Vec::new();
        let mut segments = Vec::new();
        let mut near = Vec::new();
        for ((ray, hit), &hit_covered) in rays.iter().zip(&hits).zip(&covered) {
            let Some(Hit { t, triangle }) = *hit else {
                pending.push(Pending {
                    side: u32::MAX,
                    candidates: 0..0,
                    fixed: Some(Vec3::ZERO),
                    point: Vec3::ZERO,
                    covered: false,
                });
                continue;
            };
            let tri = &self.scene.triangles[triangle as usize];
            let back = ray.dir.dot(tri.normal) > 0.0;
            let side = side_of(tri.surface, back);
            let point = ray.origin + t * ray.dir;
            let reach = self.support[side as usize];
            if reach <= 0.0 {
                let material = self.scene.material_of(tri.surface);
                let fixed = if back || self.quantity == Quantity::Irradiance {
                    Vec3::ZERO
                } else {
                    material.ke
                };
                pending.push(Pending {
                    side,
                    candidates: 0..0,
                    fixed: Some(fixed),
                    point,
                    covered: hit_covered,
                });
                continue;
            }
            let map = &self.solution.maps[tri.surface as usize];
            let normal = if back { -tri.normal } else { tri.normal };
            let from = point + self.lift * normal;
            let uv = map.to_2d(point);
            self.solution.index.within(s, side, uv, reach, &mut near);
            near.sort_unstable_by_key(|&(k, _)| k);
            let start = candidates.len();
            let test = self.solution.obstruction.is_obstructed(side);
            for &(k, d2) in &near {
                let r = SUPPORT * s.radius[k as usize];
                let q = d2 / (r * r);
                if q < 1.0 {
                    let w = (1.0 - q).powi(3);
                    candidates.push((k, w));
                    // On sides nothing stands on, every sample is in sight: no query.
                    segments.push(test.then(|| Segment {
                        a: from,
                        b: s.position[k as usize] + self.lift * s.normal[k as usize],
                    }));
                }
            }
            pending.push(Pending {
                side,
                candidates: start..candidates.len(),
                fixed: None,
                point,
                covered: hit_covered,
            });
        }
        let tested: Vec<Segment> = segments.iter().flatten().copied().collect();
        let mut answers = vec![false; tested.len()];
        self.vis.occluded(&tested, &mut answers)?;
        let mut queries = (tested.len() + covers.len()) as u64;
        let mut answer = answers.into_iter();
        let blocked: Vec<bool> = segments
            .iter()
            .map(|s| s.is_some() && answer.next().unwrap_or(false))
            .collect();
        for (p, o) in pending.iter().zip(out.iter_mut()) {
            let radiance = match p.fixed {
                Some(l) => l,
                None => {
                    // Samples covered as the hit is; any visible one if there is none such.
                    let (mut wsum, mut sum) = (0.0f64, glam::DVec3::ZERO);
                    for alike in [true, false] {
                        for c in p.candidates.clone() {
                            let (k, w) = candidates[c];
                            if !blocked[c]
                                && (!alike || self.sample_covered(k as usize) == p.covered)
                            {
                                wsum += f64::from(w);
                                sum += f64::from(w) * self.value(k as usize);
                            }
                        }
                        if wsum > 0.0 {
                            break;
                        }
                    }
                    if wsum > 0.0 {
                        (sum / wsum).as_vec3()
                    } else {
                        let (l, q) = self.nearest_visible(p.side, p.point)?;
                        queries += q;
                        l
                    }
                }
            };
            *o = (radiance, p.side);
        }
        Ok(queries)
    }

    /// Fallback where no sample's kernel reaches a visible hit: the nearest visible sample of
    /// the side within a growing radius, or black if the hit is sealed off from all of them.
    fn nearest_visible(&self, side: Side, point: Vec3) -> Result<(Vec3, u64)> {
        let s = &self.solution.samples;
        let surface = surface_of(side);
        let map = &self.solution.maps[surface as usize];
        let normal = if is_back(side) {
            -map.normal
        } else {
            map.normal
        };
        let from = point + self.lift * normal;
        let uv = map.to_2d(point);
        let mut near = Vec::new();
        let mut queries = 0;
        let mut r = self.support[side as usize];
        for _ in 0..4 {
            r *= 2.0;
            self.solution.index.within(s, side, uv, r, &mut near);
            near.sort_unstable_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            near.truncate(16);
            let segments: Vec<Segment> = near
                .iter()
                .map(|&(k, _)| Segment {
                    a: from,
                    b: s.position[k as usize] + self.lift * s.normal[k as usize],
                })
                .collect();
            let mut blocked = vec![false; segments.len()];
            self.vis.occluded(&segments, &mut blocked)?;
            queries += segments.len() as u64;
            if let Some(i) = blocked.iter().position(|b| !b) {
                let k = near[i].0 as usize;
                return Ok((self.value(k).as_vec3(), queries));
            }
        }
        Ok((Vec3::ZERO, queries))
    }
}
