//! An unbiased Monte Carlo path tracer for the same scenes, the reference meshless results are
//! checked against. It shares only scene loading, the camera and the visibility backends with
//! the meshless solver: its own light sampling, its own shading.
//!
//! Diffuse surfaces (Lambertian, Kd; emitters emit Ke from their fronts); next-event
//! estimation at every bounce: every point light (one shadow ray each), and one point on an
//! emitting triangle chosen by power, combined with cosine-sampled bounces by the power
//! heuristic (multiple importance sampling, Veach 1997); Russian roulette from the fourth
//! bounce. Paths advance in waves: each bounce's rays and shadow segments go to the backend in
//! batches. Every path draws from its own generator, seeded from (seed, pixel, sample index),
//! so the image is the same for any number of threads. Even and odd samples go to two
//! half-images whose difference estimates the noise.

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use crate::error::{Error, Result};
use crate::parallel::for_chunks;
use crate::progress::{Callback, Phase, Progress, Reporter};
use crate::render::Image;
use crate::scene::Scene;
use crate::visibility::{Hit, Ray, Segment, Visibility};

/// Path tracing settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathOptions {
    /// Samples per pixel (at least 2: one for each half-image).
    pub spp: u32,
    /// Stop after this many seconds (at a whole pass), with fewer samples if need be.
    pub seconds: Option<f64>,
    /// Seed of every random choice.
    pub seed: u64,
    /// Worker threads (the image does not depend on them).
    pub threads: usize,
    /// Bounces at most (Russian roulette ends most paths far earlier).
    pub max_bounces: u32,
}

impl Default for PathOptions {
    fn default() -> Self {
        PathOptions {
            spp: 64,
            seconds: None,
            seed: 1,
            threads: crate::solver::Options::default().threads,
            max_bounces: 256,
        }
    }
}

/// A path-traced image, with its noise estimate.
#[derive(Clone, Debug)]
pub struct PathImage {
    /// The image: the mean of all samples.
    pub image: Image,
    /// The image from even samples, and from odd ones.
    pub halves: [Image; 2],
    /// Samples per pixel taken.
    pub spp: u32,
    /// Noise estimate of `image`: mean |A − B| / 2 over pixels and channels, divided by the
    /// image's mean. With independent halves of standard deviation σ√2 each (σ the image's),
    /// A − B has standard deviation 2σ, so E|A − B| / 2 = σ√(2/π) = E|image − truth| for
    /// normal noise: the image's expected MAE/mean against the converged image.
    pub noise: f64,
    /// Paths traced and rays cast (camera, bounces and shadow rays).
    pub rays: u64,
    /// Whether the host stopped the render (after a whole pass: `spp` says how many samples
    /// each pixel got).
    pub stopped: bool,
}

/// An emitting triangle, with its choice probability by power.
#[derive(Clone, Copy, Debug)]
struct Emitter {
    triangle: u32,
    probability: f64,
}

/// The emitters by power, to pick from.
struct Lights {
    emitters: Vec<Emitter>,
    /// Cumulative probabilities.
    cumulative: Vec<f64>,
    /// Per triangle: its index in `emitters`, if it emits.
    of_triangle: Vec<Option<u32>>,
}

impl Lights {
    fn new(scene: &Scene) -> Lights {
        let mut weights = Vec::new();
        let mut of_triangle = vec![None; scene.triangles.len()];
        for (i, t) in scene.triangles.iter().enumerate() {
            let m = scene.material_of(t.surface);
            if m.is_emitter() {
                of_triangle[i] = Some(weights.len() as u32);
                weights.push((
                    i as u32,
                    f64::from(t.area) * luminance(m.ke.as_dvec3()).max(1e-30),
                ));
            }
        }
        let total: f64 = weights.iter().map(|w| w.1).sum();
        let mut emitters = Vec::with_capacity(weights.len());
        let mut cumulative = Vec::with_capacity(weights.len());
        let mut sum = 0.0;
        for (triangle, w) in weights {
            let probability = w / total;
            sum += probability;
            emitters.push(Emitter {
                triangle,
                probability,
            });
            cumulative.push(sum);
        }
        Lights {
            emitters,
            cumulative,
            of_triangle,
        }
    }

    fn pick(&self, u: f64) -> Option<&Emitter> {
        if self.emitters.is_empty() {
            return None;
        }
        let i = self
            .cumulative
            .partition_point(|&c| c <= u)
            .min(self.emitters.len() - 1);
        Some(&self.emitters[i])
    }
}

fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// One path in flight.
struct Path {
    pixel: usize,
    sample: u32,
    rng: Pcg64Mcg,
    ray: Ray,
    throughput: DVec3,
    radiance: DVec3,
    /// Solid-angle density of the bounce that cast `ray` (0 for camera rays: no MIS).
    bounce_pdf: f64,
    bounces: u32,
}

/// A shadow ray's contribution, if its segment is clear.
struct Shadow {
    path: usize,
    contribution: DVec3,
}

/// Renders the scene's camera view by path tracing. `progress` hears every pass
/// ([`Phase::Tracing`]: `items` the samples per pixel wanted, `shots` those done) and may stop
/// the render after a pass that leaves an even number of samples per pixel (each half-image
/// gets its share; the first pass always runs).
pub fn path_trace(
    scene: &Scene,
    vis: &dyn Visibility,
    options: &PathOptions,
    progress: Callback,
) -> Result<PathImage> {
    crate::parallel::guarded("the path tracer", || {
        if options.spp < 2 {
            return Err(Error::Option {
                option: "spp",
                problem: format!(
                    "{} is fewer than 2 (one sample for each half-image)",
                    options.spp
                ),
            });
        }
        scene.camera.check()?;
        let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
        let pixels = w * h;
        let lights = Lights::new(scene);
        let lift = crate::visibility::lift(scene);
        let threads = options.threads.max(1);
        // Per pixel: sums of the even and of the odd samples.
        let mut sums = vec![[DVec3::ZERO; 2]; pixels];
        let mut rays = std::sync::atomic::AtomicU64::new(0);
        let started = std::time::Instant::now();
        // Passes of a few samples each: the time limit and progress act between them.
        let pass = 2u32.max(options.spp / 32).min(options.spp);
        let mut done = 0u32;
        let points = scene.point_sources();
        let mut reporter = Reporter::new(progress);
        let base = Progress {
            items: options.spp as usize,
            ..Progress::of(Phase::Tracing)
        };
        // The first pass runs whatever the host says: both half-images need samples.
        reporter.report(base);
        let mut stopped = false;
        while done < options.spp && !stopped {
            let count = pass.min(options.spp - done);
            let first = done;
            let tracer = Tracer {
                scene,
                vis,
                lights: &lights,
                points: &points,
                lift,
                seed: options.seed,
                max_bounces: options.max_bounces,
            };
            for_chunks(&mut sums, 64, threads, |start, chunk| {
                let n = tracer.trace(start, chunk, first..first + count)?;
                rays.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
                Ok(())
            })?;
            done += count;
            let stop = reporter.report(Progress {
                fraction: f64::from(done) / f64::from(options.spp),
                shots: u64::from(done),
                ..base
            });
            // Whole pairs of samples only: the half-images need one each.
            if done % 2 == 0 && done < options.spp {
                if stop {
                    stopped = true;
                } else if options
                    .seconds
                    .is_some_and(|s| started.elapsed().as_secs_f64() >= s)
                {
                    break;
                }
            }
        }
        let image_of = |f: &dyn Fn(&[DVec3; 2]) -> DVec3| Image {
            width: w as u32,
            height: h as u32,
            pixels: sums.iter().map(|s| f(s).as_vec3()).collect(),
        };
        let half = f64::from(done / 2);
        let odd = f64::from(done - done / 2);
        let image = image_of(&|s| (s[0] + s[1]) / f64::from(done));
        let halves = [image_of(&|s| s[0] / half), image_of(&|s| s[1] / odd)];
        let mean = image.mean();
        let diff: f64 = halves[0]
            .pixels
            .iter()
            .zip(&halves[1].pixels)
            .map(|(a, b)| f64::from((*a - *b).abs().element_sum()))
            .sum::<f64>()
            / (3 * pixels.max(1)) as f64;
        Ok(PathImage {
            image,
            halves,
            spp: done,
            noise: if mean > 0.0 { diff / 2.0 / mean } else { 0.0 },
            rays: *rays.get_mut(),
            stopped,
        })
    })
}

/// What tracing reads.
struct Tracer<'a> {
    scene: &'a Scene,
    vis: &'a dyn Visibility,
    lights: &'a Lights,
    /// Point lights and luminaires.
    points: &'a [crate::scene::PointSource],
    lift: f32,
    seed: u64,
    max_bounces: u32,
}

impl Tracer<'_> {
    /// Traces samples `samples` of the pixels `start..start + out.len()`, adding each to its
    /// half-image sum. Returns the rays cast.
    fn trace(
        &self,
        start: usize,
        out: &mut [[DVec3; 2]],
        samples: std::ops::Range<u32>,
    ) -> Result<u64> {
        let camera = &self.scene.camera;
        let width = camera.width as usize;
        let mut paths: Vec<Path> = Vec::with_capacity(out.len() * samples.len());
        for (i, _) in out.iter().enumerate() {
            let pixel = start + i;
            // Where in the pixel: the R2 sequence (Roberts 2018), rotated per pixel, so the
            // box filter is integrated evenly whatever the sample count.
            let mut shift = Pcg64Mcg::seed_from_u64(stream(self.seed, pixel as u64, u32::MAX));
            let rotation: (f64, f64) = (shift.random(), shift.random());
            for sample in samples.clone() {
                let rng = Pcg64Mcg::seed_from_u64(stream(self.seed, pixel as u64, sample));
                let k = f64::from(sample);
                let u = (rotation.0 + k * 0.754_877_666_246_692_8).fract() as f32;
                let v = (rotation.1 + k * 0.569_840_290_998_053_3).fract() as f32;
                let x = (pixel % width) as f32 + u;
                let y = (pixel / width) as f32 + v;
                paths.push(Path {
                    pixel,
                    sample,
                    rng,
                    ray: Ray {
                        origin: camera.position,
                        dir: camera.direction(x, y),
                        t_min: 0.0,
                        t_max: f32::INFINITY,
                    },
                    throughput: DVec3::ONE,
                    radiance: DVec3::ZERO,
                    bounce_pdf: 0.0,
                    bounces: 0,
                });
            }
        }
        let mut rays = 0u64;
        let mut batch: Vec<Ray> = Vec::new();
        let mut hits: Vec<Option<Hit>> = Vec::new();
        let mut segments: Vec<Segment> = Vec::new();
        let mut shadows: Vec<Shadow> = Vec::new();
        let mut blocked: Vec<bool> = Vec::new();
        while !paths.is_empty() {
            batch.clear();
            batch.extend(paths.iter().map(|p| p.ray));
            hits.clear();
            hits.resize(batch.len(), None);
            self.vis.intersect(&batch, &mut hits)?;
            rays += batch.len() as u64;
            segments.clear();
            shadows.clear();
            let mut alive = vec![true; paths.len()];
            for (i, (path, hit)) in paths.iter_mut().zip(&hits).enumerate() {
                alive[i] = self.shade(i, path, *hit, &mut segments, &mut shadows);
            }
            blocked.clear();
            blocked.resize(segments.len(), false);
            self.vis.occluded(&segments, &mut blocked)?;
            rays += segments.len() as u64;
            for (s, &b) in shadows.iter().zip(&blocked) {
                if !b {
                    paths[s.path].radiance += s.contribution;
                }
            }
            // Finished paths join their half-image: in an order fixed by the paths themselves
            // (each draws from its own generator), whatever the thread count.
            let mut i = 0;
            paths.retain(|p| {
                let keep = alive[i];
                i += 1;
                if !keep {
                    out[p.pixel - start][(p.sample % 2) as usize] += p.radiance;
                }
                keep
            });
        }
        Ok(rays)
    }

    /// Shades a path at its hit: emission, next-event estimation (queued as shadow segments),
    /// and the next bounce. Returns whether the path goes on.
    fn shade(
        &self,
        index: usize,
        path: &mut Path,
        hit: Option<Hit>,
        segments: &mut Vec<Segment>,
        shadows: &mut Vec<Shadow>,
    ) -> bool {
        let scene = self.scene;
        let Some(hit) = hit else { return false };
        let triangle = &scene.triangles[hit.triangle as usize];
        let surface = &scene.surfaces[triangle.surface as usize];
        let material = &scene.materials[surface.material as usize];
        let dir = path.ray.dir;
        let front = dir.dot(triangle.normal) < 0.0;
        let x = path.ray.origin + dir * hit.t;
        let distance = f64::from(hit.t * dir.length());

        // Emission seen: directly, or weighed against the light sampling that could have found it.
        if front && material.is_emitter() {
            let ke = material.ke.as_dvec3();
            let weight = if path.bounce_pdf > 0.0 {
                let cos_l = f64::from(-dir.normalize().dot(triangle.normal));
                let emitter = self.lights.of_triangle[hit.triangle as usize]
                    .map(|e| &self.lights.emitters[e as usize]);
                match emitter {
                    Some(e) if cos_l > 0.0 => {
                        let light_pdf =
                            e.probability / f64::from(triangle.area) * distance * distance / cos_l;
                        power_heuristic(path.bounce_pdf, light_pdf)
                    }
                    _ => 1.0,
                }
            } else {
                1.0
            };
            path.radiance += path.throughput * ke * weight;
        }

        // What this side reflects: fronts with Kd, backs only of two-sided surfaces.
        let kd = material.kd.as_dvec3();
        if kd.max_element() <= 0.0 || !(front || surface.two_sided) {
            return false;
        }
        let n = if front {
            triangle.normal
        } else {
            -triangle.normal
        };
        let from = x + self.lift * n;
        let reflect = path.throughput * kd / std::f64::consts::PI;

        // Next events: every point light, and one point on an emitter.
        for light in self.points {
            let to = light.position - from;
            let r2 = f64::from(to.length_squared());
            let cos = f64::from(n.dot(to.normalize_or_zero()));
            if cos > 0.0 && r2 > 0.0 {
                segments.push(Segment {
                    a: from,
                    b: light.position,
                });
                shadows.push(Shadow {
                    path: index,
                    contribution: reflect * light.towards(-to).as_dvec3() * cos / r2,
                });
            }
        }
        let u: f64 = path.rng.random();
        let (r1, r2): (f32, f32) = (path.rng.random(), path.rng.random());
        if let Some(e) = self.lights.pick(u) {
            let t = &scene.triangles[e.triangle as usize];
            let s = r1.sqrt();
            let v = t.vertices;
            let y = v[0] * (1.0 - s) + v[1] * (s * (1.0 - r2)) + v[2] * (s * r2);
            let to = y - from;
            let d2 = f64::from(to.length_squared());
            let omega = to.normalize_or_zero();
            let cos_x = f64::from(n.dot(omega));
            let cos_l = f64::from(-t.normal.dot(omega));
            if cos_x > 0.0 && cos_l > 0.0 && d2 > 0.0 {
                let ke = scene.material_of(t.surface).ke.as_dvec3();
                let area_pdf = e.probability / f64::from(t.area);
                let light_pdf = area_pdf * d2 / cos_l;
                let bsdf_pdf = cos_x / std::f64::consts::PI;
                let weight = power_heuristic(light_pdf, bsdf_pdf);
                segments.push(Segment { a: from, b: y });
                shadows.push(Shadow {
                    path: index,
                    contribution: reflect * ke * (cos_x * weight / light_pdf),
                });
            }
        }

        // The next bounce: cosine-weighted about the normal, then Russian roulette.
        path.bounces += 1;
        if path.bounces > self.max_bounces {
            return false;
        }
        path.throughput *= kd;
        if path.bounces > 3 {
            let q = path.throughput.max_element().min(0.95);
            if path.rng.random::<f64>() >= q {
                return false;
            }
            path.throughput /= q;
        }
        let (a, b) = n.any_orthonormal_pair();
        let (u1, u2): (f32, f32) = (path.rng.random(), path.rng.random());
        let (r, phi) = (u1.sqrt(), u2 * std::f32::consts::TAU);
        let cos = (1.0 - u1).max(0.0).sqrt();
        let d = a * (r * phi.cos()) + b * (r * phi.sin()) + n * cos;
        path.bounce_pdf = f64::from(cos) / std::f64::consts::PI;
        path.ray = Ray {
            origin: from,
            dir: d,
            t_min: 0.0,
            t_max: f32::INFINITY,
        };
        true
    }
}

/// The power heuristic's weight for a sample from the first density.
fn power_heuristic(a: f64, b: f64) -> f64 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}

/// A well-mixed seed for (seed, pixel, sample) (SplitMix64's finaliser over their mix).
fn stream(seed: u64, pixel: u64, sample: u32) -> u64 {
    let mut z = seed
        ^ pixel.wrapping_mul(0x9e37_79b9_7f4a_7c15)
        ^ u64::from(sample).wrapping_mul(0xc2b2_ae3d_27d4_eb4f);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}
