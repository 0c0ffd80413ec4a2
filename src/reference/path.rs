//! An unbiased Monte Carlo path tracer for the same scenes, the reference meshless results are
//! checked against. It shares only scene loading, the camera, the visibility backends and the
//! scattering formulas of `crate::material` (the contract's mirror, GGX lobe, Fresnel) with the
//! meshless solver: its own light sampling, its own shading.
//!
//! Materials (`docs/scene-format.md`): Lambertian Kd (emitters emit Ke from their fronts);
//! Kd/π + Ks·GGX (glossy); Kd/π + a mirror's Ks; glass (Fresnel and Snell, radiance ÷η²
//! entering, ×η² leaving) and thin panes (R', T'·Tf, unbent). At a hit the next direction comes
//! from the diffuse part, the lobe or a delta branch, each chosen with a probability
//! proportional to the luminance of its weight (Kd, Ks, the branch's); a direction from the
//! diffuse part or the lobe is weighed by the mixture f cos θ / (p_d·cos θ/π + p_g·pdf_GGX).
//!
//! Next-event estimation at every vertex with a diffuse part or a lobe: every point light and
//! luminaire (one connection each), and one point on an emitting triangle chosen by power,
//! combined with the bounces by the power heuristic (multiple importance sampling, Veach 1997)
//! against the mixture's density. Connections pass thin panes, × T'(θ)·Tf each (closest-hit
//! queries, at most 8 panes a leg); anything else blocks them. Then the same lights again
//! through chains of up to `mirror_depth` planar mirrors (mirror surfaces with r = 0, × Ks; thin
//! panes, × R'(θ)): the light's image across the mirror planes, each leg checked to hit its
//! mirror first on a side that reflects, the unfolded length in the geometry term and, for
//! area lights, in the area-to-solid-angle density. A path that leaves such a vertex and meets
//! an emitter after nothing but planar-mirror reflections (at most `mirror_depth`) and pane
//! crossings is exactly what those connections found: it counts with the power heuristic's
//! weight against them (the unfolded distance again), so each such path is counted once
//! over both. Paths from the camera through delta events alone see emitters whole, in mirrors
//! and through glass; point lights are never seen. After any other delta event (glass's
//! reflection and refraction, a mirror beyond `mirror_depth`) emission found counts whole.
//!
//! Limits. Light that reaches a diffuse or glossy surface only through a refracting solid
//! (thick glass) is found by paths alone, which hit area lights but never point lights or
//! luminaires: a point light behind or inside thick glass lights nothing the camera sees
//! through that glass, and caustics of area lights through it converge slowly. Thin panes are
//! exact both ways. Mirrors are planar (each surface its plane); the chains looked through are
//! capped at 1,024, the depth lowered to fit. Rays leave a vertex lifted off its surface by
//! 10⁻⁴ of the scene's diagonal; the lights' distances and angles are measured from the vertex
//! itself (from the lifted point, a ceiling 0.2 m over a lamp in a scene 29 m across read 3%
//! too bright).
//!
//! Russian roulette from the fourth bounce. Paths advance in waves: each bounce's rays, shadow
//! segments and probes go to the backend in batches. Every path draws from its own generator,
//! seeded from (seed, pixel, sample index), so the image is the same for any number of threads;
//! on a diffuse path the draws are those of the diffuse-only tracer, so scenes without specular
//! materials render bit for bit as before. Even and odd samples go to two half-images whose
//! difference estimates the noise.

mod mirrors;

use glam::{DVec3, Vec3};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use crate::error::{Error, Result};
use crate::material::{branches, Branches, Lobe};
use crate::parallel::for_chunks;
use crate::progress::{Callback, Phase, Progress, Reporter};
use crate::render::Image;
use crate::scene::{Kind, Scene};
use crate::visibility::{Hit, Ray, Segment, Visibility};
use mirrors::{Leg, Mirrors, Probe, Step, MAX_CROSSINGS, MAX_MIRROR_DEPTH};

/// Seconds a pass of samples should take: progress, a Stop and the time limit act between
/// passes.
const PASS_SECONDS: f64 = 0.25;

/// Samples per pixel a pass takes at most: a pass holds 64 × this many paths in flight per
/// worker.
const MAX_PASS: u32 = 256;

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
    /// Planar mirrors (and thin panes' reflections) next-event estimation looks through in a
    /// row, at most (0 to 4; lowered where a scene has so many mirrors that the chains
    /// would exceed 1,024).
    pub mirror_depth: u32,
    /// The memory budget, bytes: an image whose sums would not fit is refused before they are
    /// allocated.
    pub memory_budget: usize,
}

impl Default for PathOptions {
    fn default() -> Self {
        PathOptions {
            spp: 64,
            seconds: None,
            seed: 1,
            threads: crate::solver::Options::default().threads,
            max_bounces: 256,
            mirror_depth: 2,
            memory_budget: crate::budget::DEFAULT_MEMORY_BUDGET,
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
    /// Solid-angle density with which the last non-delta vertex drew the direction `ray`
    /// continues; 0 when nothing else could have found what the path meets next (camera rays
    /// and what they pass by delta events, and paths after delta events light sampling does
    /// not follow): emission found is then taken whole.
    bounce_pdf: f64,
    bounces: u32,
    /// Distance from the last non-delta vertex to `ray`'s origin along the planar reflections
    /// since: with the ray's hit distance, the unfolded length light sampling would see.
    travelled: f64,
    /// Planar-mirror reflections since the last non-delta vertex.
    reflections: u32,
    /// Thin panes crossed since the last vertex that changed the direction.
    crossings: u32,
}

/// A shadow ray's contribution, if its segment is clear.
struct Shadow {
    path: usize,
    contribution: DVec3,
}

/// What shading a wave queues: plain shadow segments (scenes without thin panes), and probes.
#[derive(Default)]
struct Queue {
    segments: Vec<Segment>,
    shadows: Vec<Shadow>,
    probes: Vec<Probe>,
}

/// The non-delta part of a vertex's scattering (diffuse Kd, a glossy lobe), for light sampling
/// and the weights of multiple importance sampling.
struct Smooth {
    /// The side's normal.
    n: Vec3,
    /// The surface the vertex lies on.
    surface: u32,
    throughput: DVec3,
    /// throughput × Kd / π.
    reflect: DVec3,
    lobe: Option<Lobe>,
    /// The probabilities of drawing the next direction from the diffuse part, and from the lobe.
    p_diffuse: f64,
    p_lobe: f64,
}

impl Smooth {
    /// throughput × f cos θ towards unit `w`, `cos` = n·w > 0.
    fn value(&self, w: DVec3, cos: f64) -> DVec3 {
        match &self.lobe {
            None => self.reflect * cos,
            Some(l) => self.reflect * cos + self.throughput * l.eval(w),
        }
    }

    /// The density of drawing `w` as the next direction (per solid angle).
    fn pdf(&self, w: DVec3, cos: f64) -> f64 {
        let diffuse = self.p_diffuse * cos / std::f64::consts::PI;
        match &self.lobe {
            None => diffuse,
            Some(l) => diffuse + self.p_lobe * l.pdf(w),
        }
    }
}

/// A point drawn on an emitting triangle for next-event estimation.
struct AreaSample {
    y: Vec3,
    normal: Vec3,
    ke: DVec3,
    /// Density per area.
    area_pdf: f64,
}

impl PathOptions {
    /// Checks the path tracer's settings: the first out of its range, as
    /// [`Error::Option`](crate::Error::Option) naming it.
    pub fn validate(&self) -> Result<()> {
        if self.spp < 2 {
            return Err(Error::Option {
                option: "spp",
                problem: format!(
                    "{} is fewer than 2 (one sample for each half-image)",
                    self.spp
                ),
            });
        }
        if self.mirror_depth > MAX_MIRROR_DEPTH {
            return Err(Error::Option {
                option: "mirror_depth",
                problem: format!(
                    "{} is more than {MAX_MIRROR_DEPTH} mirrors in a row",
                    self.mirror_depth
                ),
            });
        }
        Ok(())
    }
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
        let checked = crate::visibility::Checked::new(vis, scene);
        let vis: &dyn crate::visibility::Visibility = &checked;
        options.validate()?;
        scene.camera.check()?;
        // The two half-sums, the three images returned.
        let per_pixel = std::mem::size_of::<[DVec3; 2]>() + 3 * std::mem::size_of::<Vec3>();
        let size = (scene.camera.width, scene.camera.height);
        crate::budget::check_image(options.memory_budget, size, per_pixel)?;
        let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
        let pixels = w * h;
        let lights = Lights::new(scene);
        let lift = crate::visibility::lift(scene);
        let mirrors = Mirrors::new(scene, options.mirror_depth, lift);
        let threads = options.threads.max(1);
        // Per pixel: sums of the even and of the odd samples.
        let mut sums = vec![[DVec3::ZERO; 2]; pixels];
        let mut rays = std::sync::atomic::AtomicU64::new(0);
        let started = std::time::Instant::now();
        // Passes of a few samples each: the time limit and progress act between them. Sized
        // by time (about PASS_SECONDS each, from the last pass's speed), never by the samples
        // asked for: a pass holds chunk × pass paths in flight, and spp/32 of 10⁷ samples
        // once asked for 20 M of them.
        let mut pass = 2u32.min(options.spp);
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
                mirrors: &mirrors,
                points: &points,
                lift,
                seed: options.seed,
                max_bounces: options.max_bounces,
            };
            let timer = std::time::Instant::now();
            for_chunks(&mut sums, 64, threads, |start, chunk| {
                let n = tracer.trace(start, chunk, first..first + count)?;
                rays.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
                Ok(())
            })?;
            done += count;
            let per_sample = timer.elapsed().as_secs_f64() / f64::from(count);
            let fit = (PASS_SECONDS / per_sample.max(1e-9)).clamp(2.0, f64::from(MAX_PASS));
            pass = (fit as u32) & !1;
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
        let rays = *rays.get_mut();
        Ok(finish(&sums, (w, h), done, rays, stopped))
    })
}

/// The image from the sums of the even and of the odd samples (`done` in all), and its noise:
/// the two half-images' mean difference, halved, over the image's mean.
fn finish(
    sums: &[[DVec3; 2]],
    (w, h): (usize, usize),
    done: u32,
    rays: u64,
    stopped: bool,
) -> PathImage {
    let pixels = w * h;
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
    PathImage {
        image,
        halves,
        spp: done,
        noise: if mean > 0.0 { diff / 2.0 / mean } else { 0.0 },
        rays,
        stopped,
    }
}

/// What tracing reads.
struct Tracer<'a> {
    scene: &'a Scene,
    vis: &'a dyn Visibility,
    lights: &'a Lights,
    mirrors: &'a Mirrors,
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
                    travelled: 0.0,
                    reflections: 0,
                    crossings: 0,
                });
            }
        }
        let mut rays = 0u64;
        let mut batch: Vec<Ray> = Vec::new();
        let mut hits: Vec<Option<Hit>> = Vec::new();
        let mut queue = Queue::default();
        let mut blocked: Vec<bool> = Vec::new();
        while !paths.is_empty() {
            batch.clear();
            batch.extend(paths.iter().map(|p| p.ray));
            hits.clear();
            hits.resize(batch.len(), None);
            self.vis.intersect(&batch, &mut hits)?;
            rays += batch.len() as u64;
            queue.segments.clear();
            queue.shadows.clear();
            queue.probes.clear();
            let mut alive = vec![true; paths.len()];
            for (i, (path, hit)) in paths.iter_mut().zip(&hits).enumerate() {
                alive[i] = self.shade(i, path, *hit, &mut queue);
            }
            blocked.clear();
            blocked.resize(queue.segments.len(), false);
            self.vis.occluded(&queue.segments, &mut blocked)?;
            rays += queue.segments.len() as u64;
            for (s, &b) in queue.shadows.iter().zip(&blocked) {
                if !b {
                    paths[s.path].radiance += s.contribution;
                }
            }
            rays += self.probe(&mut queue.probes, &mut paths, &mut batch, &mut hits)?;
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

    /// Runs the probes to their ends, a closest-hit query per leg and per pane crossed, all
    /// probes' queries batched; adds the contributions of those that reach their light, in
    /// the probes' order. Returns the rays cast.
    fn probe(
        &self,
        probes: &mut [Probe],
        paths: &mut [Path],
        batch: &mut Vec<Ray>,
        hits: &mut Vec<Option<Hit>>,
    ) -> Result<u64> {
        let mut rays = 0u64;
        let mut clear = vec![false; probes.len()];
        let mut active: Vec<usize> = (0..probes.len()).collect();
        while !active.is_empty() {
            batch.clear();
            batch.extend(active.iter().map(|&i| probes[i].ray));
            hits.clear();
            hits.resize(batch.len(), None);
            self.vis.intersect(batch, hits)?;
            rays += batch.len() as u64;
            let mut next = Vec::with_capacity(active.len());
            for (&i, hit) in active.iter().zip(hits.iter()) {
                match probes[i].step(self.scene, *hit, self.lift) {
                    Step::Continue => next.push(i),
                    Step::Clear => clear[i] = true,
                    Step::Blocked => {}
                }
            }
            active = next;
        }
        for (p, _) in probes.iter().zip(&clear).filter(|(_, &c)| c) {
            paths[p.path].radiance += p.contribution;
        }
        Ok(rays)
    }

    /// Shades a path at its hit: emission, next-event estimation (queued as shadow segments
    /// and probes), and the next bounce. Returns whether the path goes on.
    fn shade(&self, index: usize, path: &mut Path, hit: Option<Hit>, queue: &mut Queue) -> bool {
        let scene = self.scene;
        let Some(hit) = hit else {
            // Out of the model: the sky or the ground, found by the path's own bounce (no
            // light sampling of the sky, so no weighing).
            if let Some(daylight) = scene.daylight() {
                // The sun's disc only where nothing sampled it: camera rays and delta paths.
                let sun = if path.bounce_pdf > 0.0 {
                    0.0
                } else {
                    daylight.sun_radiance(path.ray.dir)
                };
                path.radiance += path.throughput * (daylight.radiance(path.ray.dir) + sun);
            }
            return false;
        };
        let triangle = &scene.triangles[hit.triangle as usize];
        let surface = &scene.surfaces[triangle.surface as usize];
        let material = &scene.materials[surface.material as usize];
        let dir = path.ray.dir;
        let front = dir.dot(triangle.normal) < 0.0;
        let x = path.ray.origin + dir * hit.t;
        let distance = f64::from(hit.t * dir.length());

        // Emission seen: directly, or weighed against the light sampling that could have found
        // it (straight, through thin panes or by planar mirrors: the unfolded distance).
        if front && material.is_emitter() {
            let ke = material.ke.as_dvec3();
            let weight = if path.bounce_pdf > 0.0 {
                let cos_l = f64::from(-dir.normalize().dot(triangle.normal));
                let emitter = self.lights.of_triangle[hit.triangle as usize]
                    .map(|e| &self.lights.emitters[e as usize]);
                let unfolded = path.travelled + distance;
                match emitter {
                    Some(e) if cos_l > 0.0 => {
                        let light_pdf =
                            e.probability / f64::from(triangle.area) * unfolded * unfolded / cos_l;
                        power_heuristic(path.bounce_pdf, light_pdf)
                    }
                    _ => 1.0,
                }
            } else {
                1.0
            };
            path.radiance += path.throughput * ke * weight;
        }

        if material.is_specular() {
            return self.scatter(index, path, hit, distance, queue);
        }

        // What this side reflects: fronts with Kd (or the texel there), backs only of
        // two-sided surfaces.
        let kd = scene.reflectance_at(hit.triangle, x).as_dvec3();
        if kd.max_element() <= 0.0 || !(front || surface.two_sided) {
            return false;
        }
        let n = if front {
            triangle.normal
        } else {
            -triangle.normal
        };
        let from = x + self.lift * n;
        let smooth = Smooth {
            n,
            surface: triangle.surface,
            throughput: path.throughput,
            reflect: path.throughput * kd / std::f64::consts::PI,
            lobe: None,
            p_diffuse: 1.0,
            p_lobe: 0.0,
        };
        self.next_events(index, path, (x, from), &smooth, queue);

        // The next bounce: cosine-weighted about the normal, then Russian roulette.
        path.bounces += 1;
        if path.bounces > self.max_bounces {
            return false;
        }
        path.throughput *= kd;
        if !roulette(path) {
            return false;
        }
        let (d, cos) = cosine_direction(path, n);
        path.bounce_pdf = f64::from(cos) / std::f64::consts::PI;
        leave(path, from, d);
        true
    }

    /// Light sampling at a vertex with a non-delta part: every point light and luminaire, one
    /// point on an emitter (with the weight of multiple importance sampling against drawing
    /// the direction from `smooth`), and both again through each chain of planar mirrors.
    /// Draws three numbers from the path's generator. `at` is the vertex and the point its
    /// shadow rays leave from, lifted off the surface: distances and angles are measured from
    /// the vertex itself (from the lifted point, the ceiling 0.2 m over a lamp read 3% too
    /// bright in a scene 29 m across).
    fn next_events(
        &self,
        index: usize,
        path: &mut Path,
        at: (Vec3, Vec3),
        smooth: &Smooth,
        queue: &mut Queue,
    ) {
        let scene = self.scene;
        let n = smooth.n;
        let (x, from) = at;
        for light in self.points {
            let to = light.position - x;
            let r2 = f64::from(to.length_squared());
            let cos = f64::from(n.dot(to.normalize_or_zero()));
            if cos > 0.0 && r2 > 0.0 {
                let intensity = light.towards(-to).as_dvec3();
                let contribution = match &smooth.lobe {
                    None => smooth.reflect * intensity * cos / r2,
                    Some(_) => smooth.value(to.normalize().as_dvec3(), cos) * intensity / r2,
                };
                self.connect(index, from, light.position, contribution, queue);
            }
        }
        if let Some((towards, illuminance)) = scene.daylight().and_then(|d| d.sun_light()) {
            // The sun: one direction uniform over its disc (L Ω = E_n, so the estimate is
            // f E_n cos θ), followed out of the model.
            let cos_max = crate::daylight::SUN_RADIUS_DEGREES.to_radians().cos();
            let (u1, u2): (f64, f64) = (path.rng.random(), path.rng.random());
            let c = 1.0 - u1 * (1.0 - cos_max);
            let s = (1.0 - c * c).max(0.0).sqrt();
            let (a, b) = towards.any_orthonormal_pair();
            let phi = std::f64::consts::TAU * u2;
            let w = (towards * c as f32 + a * (s * phi.cos()) as f32 + b * (s * phi.sin()) as f32)
                .normalize();
            let cos = f64::from(n.dot(w));
            if cos > 0.0 {
                let contribution = match &smooth.lobe {
                    None => smooth.reflect * illuminance * cos,
                    Some(_) => smooth.value(w.as_dvec3(), cos) * illuminance,
                };
                let far = 2.0 * scene.bounds().diagonal() + 1.0;
                self.connect(index, from, from + w * far, contribution, queue);
            }
        }
        let u: f64 = path.rng.random();
        let (r1, r2): (f32, f32) = (path.rng.random(), path.rng.random());
        let mut area = None;
        if let Some(e) = self.lights.pick(u) {
            let t = &scene.triangles[e.triangle as usize];
            let s = r1.sqrt();
            let v = t.vertices;
            let y = v[0] * (1.0 - s) + v[1] * (s * (1.0 - r2)) + v[2] * (s * r2);
            let ke = scene.material_of(t.surface).ke.as_dvec3();
            let area_pdf = e.probability / f64::from(t.area);
            let to = y - x;
            let d2 = f64::from(to.length_squared());
            let omega = to.normalize_or_zero();
            let cos_x = f64::from(n.dot(omega));
            let cos_l = f64::from(-t.normal.dot(omega));
            if cos_x > 0.0 && cos_l > 0.0 && d2 > 0.0 {
                let light_pdf = area_pdf * d2 / cos_l;
                let w = omega.as_dvec3();
                let bsdf_pdf = smooth.pdf(w, cos_x);
                let weight = power_heuristic(light_pdf, bsdf_pdf);
                let contribution = match &smooth.lobe {
                    None => smooth.reflect * ke * (cos_x * weight / light_pdf),
                    Some(_) => smooth.value(w, cos_x) * ke * (weight / light_pdf),
                };
                self.connect(index, from, y, contribution, queue);
            }
            area = Some(AreaSample {
                y,
                normal: t.normal,
                ke,
                area_pdf,
            });
        }
        if self.mirrors.depth() > 0 {
            self.mirror_events(index, at, smooth, area.as_ref(), queue);
        }
    }

    /// The lights' images in chains of planar mirrors, seen from the vertex `at.0` (shadow
    /// probes leave from `at.1`, lifted off it).
    fn mirror_events(
        &self,
        index: usize,
        at: (Vec3, Vec3),
        smooth: &Smooth,
        area: Option<&AreaSample>,
        queue: &mut Queue,
    ) {
        let (x, from) = (at.0.as_dvec3(), at.1);
        let n = smooth.n.as_dvec3();
        for chain in self.mirrors.chains() {
            for light in self.points {
                let y = light.position.as_dvec3();
                let Some(u) = self.mirrors.unfold(chain, smooth.surface, x, y) else {
                    continue;
                };
                let cos = n.dot(u.omega);
                if cos <= 0.0 {
                    continue;
                }
                let intensity = light.towards((u.last - y).as_vec3()).as_dvec3();
                let contribution =
                    smooth.value(u.omega, cos) * intensity * u.weight / (u.distance * u.distance);
                queue
                    .probes
                    .push(Probe::new(index, contribution, from, &u.legs[..u.count]));
            }
            let Some(a) = area else { continue };
            let y = a.y.as_dvec3();
            let Some(u) = self.mirrors.unfold(chain, smooth.surface, x, y) else {
                continue;
            };
            let cos = n.dot(u.omega);
            let cos_l = a.normal.as_dvec3().dot((u.last - y).normalize_or_zero());
            if cos <= 0.0 || cos_l <= 0.0 {
                continue;
            }
            let light_pdf = a.area_pdf * u.distance * u.distance / cos_l;
            let weight = power_heuristic(light_pdf, smooth.pdf(u.omega, cos));
            let contribution = smooth.value(u.omega, cos) * a.ke * u.weight * (weight / light_pdf);
            queue
                .probes
                .push(Probe::new(index, contribution, from, &u.legs[..u.count]));
        }
    }

    /// Queues a shadow connection from `a` to the light point `b`: a segment, or where thin
    /// panes may stand between, a probe through them.
    fn connect(&self, index: usize, a: Vec3, b: Vec3, contribution: DVec3, queue: &mut Queue) {
        if self.mirrors.panes() {
            queue
                .probes
                .push(Probe::new(index, contribution, a, &[Leg::Point(b)]));
        } else {
            queue.segments.push(Segment { a, b });
            queue.shadows.push(Shadow {
                path: index,
                contribution,
            });
        }
    }

    /// Shading at a specular material: light sampling for its diffuse part and glossy lobe,
    /// then the next direction from the diffuse part, the lobe or a delta branch, each chosen
    /// by the luminance of its weight.
    fn scatter(
        &self,
        index: usize,
        path: &mut Path,
        hit: Hit,
        distance: f64,
        queue: &mut Queue,
    ) -> bool {
        let scene = self.scene;
        let triangle = &scene.triangles[hit.triangle as usize];
        let surface = &scene.surfaces[triangle.surface as usize];
        let material = &scene.materials[surface.material as usize];
        let dir = path.ray.dir;
        let front = dir.dot(triangle.normal) < 0.0;
        let x = path.ray.origin + dir * hit.t;
        let n = if front {
            triangle.normal
        } else {
            -triangle.normal
        };
        let d = dir.as_dvec3().normalize();
        let Mixture {
            kd,
            lobe,
            delta,
            w_diffuse,
            w_lobe,
            w_delta,
            total,
        } = Mixture::at(scene, hit.triangle, x, d, front);
        if total <= 0.0 {
            return false;
        }
        let smooth = Smooth {
            n,
            surface: triangle.surface,
            throughput: path.throughput,
            reflect: path.throughput * kd / std::f64::consts::PI,
            lobe,
            p_diffuse: w_diffuse / total,
            p_lobe: w_lobe / total,
        };
        let from = x + self.lift * n;
        if w_diffuse + w_lobe > 0.0 {
            self.next_events(index, path, (x, from), &smooth, queue);
        }

        path.bounces += 1;
        if path.bounces > self.max_bounces {
            return false;
        }
        let choice = path.rng.random::<f64>() * total;
        if choice < w_diffuse + w_lobe {
            return smooth_bounce(path, &smooth, from, choice < w_diffuse);
        }
        let i = if choice < w_diffuse + w_lobe + w_delta[0] || w_delta[1] <= 0.0 {
            0
        } else {
            1
        };
        let Some((w, weight)) = delta[i] else {
            return false;
        };
        path.throughput *= weight * (total / w_delta[i]);
        if !roulette(path) {
            return false;
        }
        let thin = matches!(material.kind, Kind::Glass { thin: true, .. });
        if w.dot(n.as_dvec3()) > 0.0 {
            // A reflection: light sampling follows planar mirrors and panes, so many in a row.
            path.crossings = 0;
            if self.mirrors.is_mirror(triangle.surface) && path.reflections < self.mirrors.depth() {
                path.reflections += 1;
                path.travelled += distance;
            } else {
                path.bounce_pdf = 0.0;
            }
            path.ray = Ray {
                origin: from,
                dir: w.as_vec3(),
                t_min: 0.0,
                t_max: f32::INFINITY,
            };
        } else if thin {
            // Through a pane, unbent: the same ray further on, as shadow rays cross it.
            path.crossings += 1;
            if path.crossings > MAX_CROSSINGS {
                path.bounce_pdf = 0.0;
            }
            path.ray.t_min = hit.t + self.lift / dir.length();
        } else {
            // Refracted into or out of a solid: light sampling does not follow.
            path.bounce_pdf = 0.0;
            path.ray = Ray {
                origin: x - self.lift * n,
                dir: w.as_vec3(),
                t_min: 0.0,
                t_max: f32::INFINITY,
            };
        }
        true
    }
}

/// What a hit scatters into: the diffuse reflectance (where its side reflects), the glossy
/// lobe, the delta branches, and each part's weight (its luminance) for choosing among them.
struct Mixture {
    kd: DVec3,
    lobe: Option<Lobe>,
    delta: [Option<(DVec3, DVec3)>; 2],
    w_diffuse: f64,
    w_lobe: f64,
    w_delta: [f64; 2],
    total: f64,
}

impl Mixture {
    /// At point `x` of `triangle`, met along `d` from its front or back.
    fn at(scene: &Scene, triangle: u32, x: Vec3, d: DVec3, front: bool) -> Mixture {
        let tri = &scene.triangles[triangle as usize];
        let surface = &scene.surfaces[tri.surface as usize];
        let material = &scene.materials[surface.material as usize];
        let n = if front { tri.normal } else { -tri.normal };
        let kd = if front || surface.two_sided {
            scene.reflectance_at(triangle, x).as_dvec3()
        } else {
            DVec3::ZERO
        };
        let (lobe, delta) = match branches(material, d, tri.normal.as_dvec3(), surface.two_sided) {
            Branches::None => (None, [None, None]),
            Branches::Delta(b) => (None, b),
            Branches::Glossy(l) => {
                debug_assert!(
                    l.normal().dot(n.as_dvec3()) > 0.999,
                    "the lobe's side is the hit's"
                );
                (Some(l), [None, None])
            }
        };
        let ks = match material.kind {
            Kind::Specular { ks, .. } => ks.as_dvec3(),
            _ => DVec3::ZERO,
        };
        let w_diffuse = luminance(kd);
        let w_lobe = if lobe.is_some() { luminance(ks) } else { 0.0 };
        let w_delta = delta.map(|b| b.map_or(0.0, |(_, w)| luminance(w)));
        Mixture {
            kd,
            lobe,
            delta,
            w_diffuse,
            w_lobe,
            w_delta,
            total: w_diffuse + w_lobe + w_delta[0] + w_delta[1],
        }
    }
}

/// A non-delta bounce from `from`: a direction from the diffuse part (`diffuse`) or the lobe,
/// weighed by the mixture; whether the path goes on.
fn smooth_bounce(path: &mut Path, smooth: &Smooth, from: Vec3, diffuse: bool) -> bool {
    let n = smooth.n;
    let (w, cos) = if diffuse {
        let (d, _) = cosine_direction(path, n);
        let w = d.as_dvec3().normalize();
        (w, w.dot(n.as_dvec3()))
    } else {
        let (u1, u2): (f64, f64) = (path.rng.random(), path.rng.random());
        let Some((w, _)) = smooth.lobe.as_ref().and_then(|l| l.sample(u1, u2)) else {
            return false;
        };
        (w, w.dot(n.as_dvec3()))
    };
    let pdf = smooth.pdf(w, cos);
    if cos <= 0.0 || pdf <= 0.0 {
        return false;
    }
    path.throughput = smooth.value(w, cos) / pdf;
    if !roulette(path) {
        return false;
    }
    path.bounce_pdf = pdf;
    leave(path, from, w.as_vec3());
    true
}

/// Russian roulette from the fourth bounce: keeps the path with probability q (its
/// throughput's largest channel, at most 0.95) and divides by it. Returns whether it goes on.
fn roulette(path: &mut Path) -> bool {
    if path.bounces > 3 {
        let q = path.throughput.max_element().min(0.95);
        if path.rng.random::<f64>() >= q {
            return false;
        }
        path.throughput /= q;
    }
    true
}

/// A cosine-weighted direction about `n`, and its cosine.
fn cosine_direction(path: &mut Path, n: Vec3) -> (Vec3, f32) {
    let (a, b) = n.any_orthonormal_pair();
    let (u1, u2): (f32, f32) = (path.rng.random(), path.rng.random());
    let (r, phi) = (u1.sqrt(), u2 * std::f32::consts::TAU);
    let cos = (1.0 - u1).max(0.0).sqrt();
    (a * (r * phi.cos()) + b * (r * phi.sin()) + n * cos, cos)
}

/// The path leaves a non-delta vertex at `from` along `dir`.
fn leave(path: &mut Path, from: Vec3, dir: Vec3) {
    path.travelled = 0.0;
    path.reflections = 0;
    path.crossings = 0;
    path.ray = Ray {
        origin: from,
        dir,
        t_min: 0.0,
        t_max: f32::INFINITY,
    };
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
