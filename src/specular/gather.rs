//! Chains from a receiver through specular bounces (`docs/method.md` §22): the light a diffuse
//! point receives by way of mirrors, glossy surfaces and glass. From the receiver, rays go out
//! over its hemisphere (cosine-weighted, on a Fibonacci lattice shifted at random per
//! receiver); those whose first hit is specular follow its branches — a mirror's reflection,
//! glass's reflection and refraction (both), one sampled direction of a glossy lobe — up to
//! the specular depth. Where a chain meets a surface with samples it ends there: the receiver
//! takes that point's reflected light, interpolated from its samples (the solver turns the ends
//! into a sparse transfer matrix, `solver::specular`). Where it meets an emitter after a glossy
//! bounce it takes the emitter's radiance, and at every glossy bounce the lights are sampled
//! (multiple importance sampling against the lobe); light reaching the receiver from a light
//! through mirrors and glass alone is the mirror images' (`images`), not the chains'.

use glam::{DVec3, Vec3};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::highlight::Highlights;
use super::images::ChainTree;
use super::lights::{LightSample, Lights};
use super::shadow::{self, LightPath};
use super::Specular;
use crate::error::Result;
use crate::material::{branches, Branches, Lobe};
use crate::sampling::poisson::side_seed;
use crate::sampling::{side_of, Side};
use crate::scene::Scene;
use crate::visibility::{Ray, Visibility};

/// A highlight sample drawn: (receiver, plane, light: area index `Err` or point index `Ok`,
/// light point and the light's normal there, ray).
type Drawn = (u32, usize, Result<usize, usize>, (Vec3, Vec3), Ray);

/// The golden ratio's fractional part: the Fibonacci lattice's second coordinate.
const GOLDEN: f64 = 0.618_033_988_749_894_8;

/// Chains whose weight falls below this share of their start are not followed further.
const NEGLIGIBLE: f64 = 1e-4;

/// A delta branch carrying less than this share of its bounce's light is followed with the
/// probability its share over this (Russian roulette).
const ROULETTE: f64 = 0.25;

/// Where a chain ends on a surface with samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct End {
    /// The receiver (its index in the batch's ids, as given).
    pub receiver: u32,
    pub point: Vec3,
    pub side: Side,
    /// The side's normal.
    pub normal: Vec3,
    /// Irradiance at the receiver per unit radiosity leaving the end point (the chain's
    /// throughput × 1/rays; radiosity B leaves as radiance B/π and the cosine-weighted
    /// estimator of irradiance is π × the mean radiance).
    pub weight: DVec3,
}

/// What the chains of a batch of receivers found.
#[derive(Clone, Debug, Default)]
pub(crate) struct Found {
    /// The ends, by receiver.
    pub ends: Vec<End>,
    /// Per receiver: irradiance from the lights by way of glossy bounces.
    pub direct: Vec<DVec3>,
    /// Per receiver: the share of its rays whose first hit is specular.
    pub specular_share: Vec<f32>,
    pub queries: u64,
}

/// What following chains needs.
pub(crate) struct Chains<'a> {
    pub scene: &'a Scene,
    pub spec: &'a Specular,
    pub lights: &'a Lights,
    pub vis: &'a dyn Visibility,
    pub lift: f32,
    pub depth: u32,
    /// Chains per receiver.
    pub rays: u32,
    /// Whether a side has samples (chains end there).
    pub has_samples: &'a (dyn Fn(Side) -> bool + Sync),
    /// The glossy planes highlights are drawn on.
    pub highlights: &'a Highlights,
    /// Where chains also take the light of area lights they meet after mirrors and glass
    /// alone, unless the images carry that path (the tree of their chains): for grid points,
    /// which no photon lands on. `None` for samples, whose photons carry it.
    pub unlisted: Option<&'a ChainTree>,
}

/// Highlight samples per receiver, glossy plane and light: one for every eight chains.
fn highlight_samples(rays: u32) -> u32 {
    rays.div_ceil(8)
}

/// A first glossy bounce on a glossy plane: what the third strategy's density needs.
#[derive(Clone, Copy, Debug)]
struct FirstBounce {
    /// The receiver (lifted) and cos θ there of the direction to the bounce.
    x: Vec3,
    cos_x: f64,
    /// The direction from the receiver to the bounce.
    omega: DVec3,
    plane: u32,
}

/// A ray of a chain in flight.
struct Link {
    ray: Ray,
    receiver: u32,
    /// The receiver's normal.
    normal: Vec3,
    weight: DVec3,
    depth: u32,
    glossy: bool,
    lobe_pdf: Option<f64>,
    /// Set when the lobe that cast it was a first bounce on a glossy plane.
    first: Option<FirstBounce>,
    rng: u64,
    /// Whether the images carry its path so far: crossings of glass only where shadow rays
    /// pass straight, and reflections (their node in [`Chains::unlisted`]'s tree) a listed
    /// chain.
    straight: bool,
    node: u32,
}

impl Link {
    /// The link after this one's bounce: from `origin` along `dir`, carrying `weight`, one
    /// deeper; its random stream, and what it says of the images, for the caller to set.
    fn bounce(&self, origin: Vec3, dir: Vec3, weight: DVec3) -> Link {
        Link {
            ray: Ray {
                origin,
                dir,
                t_min: 0.0,
                t_max: f32::INFINITY,
            },
            receiver: self.receiver,
            normal: self.normal,
            weight,
            depth: self.depth + 1,
            glossy: self.glossy,
            lobe_pdf: None,
            first: None,
            rng: self.rng,
            straight: self.straight,
            node: self.node,
        }
    }
}

impl Chains<'_> {
    /// Whether the images carry a chain after it reflects (`reflected`) on or crosses
    /// `surface` from its back or front: (straight so far, its node in the tree of chains).
    fn carried(&self, l: &Link, surface: u32, back: bool, reflected: bool) -> (bool, u32) {
        let Some(tree) = self.unlisted else {
            return (false, ChainTree::OFF);
        };
        let s = surface as usize;
        if reflected {
            match self.spec.reflector_of[s] {
                Some(r) if !back || self.spec.reflectors[r as usize].both_sides => {
                    (l.straight, tree.step(l.node, r))
                }
                // Inside a slab: its inner bounces are the straight way's.
                _ if back && self.spec.straight[s] => (l.straight, l.node),
                _ => (false, ChainTree::OFF),
            }
        } else {
            (l.straight && self.spec.straight[s], l.node)
        }
    }

    /// The highlight strategy's density for the path receiver → first bounce → light point
    /// `light`, relative to the light samples' (× their density, for area lights): the
    /// cone's density × highlight samples, over the gather's rays × cos θ/π at the receiver.
    fn third(&self, f: &FirstBounce, light: Vec3) -> f64 {
        let Some(plane) = self.highlights.plane_of(f.plane) else {
            return 0.0;
        };
        if f.cos_x <= 0.0 {
            return 0.0;
        }
        let m = f64::from(highlight_samples(self.rays));
        let k = f64::from(self.rays.max(1));
        m * plane.density(f.x, light, f.omega) * std::f64::consts::PI / (k * f.cos_x)
    }

    /// Highlight samples of every receiver (see `highlight`): directions drawn towards the
    /// images of the lights in the glossy planes, kept where they meet the plane, weighed
    /// against the gather's light and lobe samples; their light samples go to `samples` (the
    /// irradiance at the receiver, before visibility). Returns the queries.
    fn highlight_samples(
        &self,
        receivers: &[(Vec3, Vec3, u32)],
        seed: u64,
        samples: &mut Vec<(u32, Vec3, LightSample)>,
    ) -> Result<u64> {
        if self.highlights.planes.is_empty() {
            return Ok(0);
        }
        let m = highlight_samples(self.rays);
        let k = f64::from(self.rays.max(1));
        let pi = std::f64::consts::PI;
        let drawn = self.draw_highlights(receivers, seed);
        let rays: Vec<Ray> = drawn.iter().map(|d| d.4).collect();
        let mut hits = vec![None; rays.len()];
        self.vis.intersect(&rays, &mut hits)?;
        let lights: Vec<(usize, f64, DVec3)> = self.lights.area_lights().collect();
        for ((r, p, light, (l, normal), ray), hit) in drawn.iter().zip(&hits) {
            let plane = &self.highlights.planes[*p];
            let Some(hit) = hit else { continue };
            let tri = &self.scene.triangles[hit.triangle as usize];
            if tri.surface != plane.surface {
                continue;
            }
            let omega = ray.dir.as_dvec3();
            let y = ray.origin + hit.t * ray.dir;
            let material = self.scene.material_of(tri.surface);
            let two_sided = self.scene.surfaces[tri.surface as usize].two_sided;
            let Branches::Glossy(lobe) =
                branches(material, omega, tri.normal.as_dvec3(), two_sided)
            else {
                continue;
            };
            let from = y + self.lift * lobe.normal().as_vec3();
            let n_x = receivers[*r as usize].1;
            let cos_x = f64::from(n_x.dot(ray.dir));
            let density = plane.density(ray.origin, *l, omega);
            let (to, contribution) = match *light {
                Err(i) => {
                    let (_, area, ke) = lights[i];
                    let normal = *normal;
                    let to = *l + self.lights.lift() * normal;
                    let d = (*l - y).as_dvec3();
                    let dist2 = d.length_squared();
                    let dir = d / dist2.sqrt();
                    let cos_l = -dir.dot(normal.as_dvec3());
                    if cos_l <= 0.0 {
                        continue;
                    }
                    let f = lobe.eval(dir);
                    let geometry = cos_l / dist2;
                    let p_c = f64::from(m) * density / area;
                    let p_a = k * cos_x / pi / area;
                    let p_b = k * cos_x / pi * lobe.pdf(dir) * geometry;
                    let w = crate::specular::lights::power3(p_c, p_a, p_b);
                    (to, ke * f * geometry * cos_x * w / p_c)
                }
                Ok(j) => {
                    let source = &self.lights.point_sources()[j];
                    let d = (*l - y).as_dvec3();
                    let dist2 = d.length_squared();
                    let dir = d / dist2.sqrt();
                    let intensity = source.towards((-dir).as_vec3()).as_dvec3();
                    let p_c = f64::from(m) * density;
                    let p_a = k * cos_x / pi;
                    let w = crate::specular::lights::power(p_c, p_a);
                    (*l, intensity * lobe.eval(dir) / dist2 * cos_x * w / p_c)
                }
            };
            if contribution.max_element() > 0.0 {
                samples.push((
                    *r,
                    from,
                    LightSample {
                        to,
                        radiance: contribution,
                    },
                ));
            }
        }
        Ok(rays.len() as u64)
    }

    /// For each receiver, glossy plane it faces and light: `highlight_samples` directions
    /// towards the plane drawn where the light's mirror image would be seen in it.
    fn draw_highlights(&self, receivers: &[(Vec3, Vec3, u32)], seed: u64) -> Vec<Drawn> {
        let m = highlight_samples(self.rays);
        let mut drawn: Vec<Drawn> = Vec::new();
        for (r, &(x, n, id)) in receivers.iter().enumerate() {
            let from = x + self.lift * n;
            let mut rng = Pcg64Mcg::seed_from_u64(side_seed(seed, id, 41));
            for (p, plane) in self.highlights.planes.iter().enumerate() {
                if !plane.faces(x) {
                    continue;
                }
                let areas = self
                    .lights
                    .area_lights()
                    .map(|(i, ..)| Err::<usize, usize>(i));
                let points = (0..self.lights.point_sources().len()).map(Ok);
                for light in areas.chain(points) {
                    for _ in 0..m {
                        let (l, normal) = match light {
                            Err(i) => self.lights.point_on(i, rng.random(), rng.random()),
                            Ok(j) => (self.lights.point_sources()[j].position, Vec3::ZERO),
                        };
                        let (u1, u2) = (rng.random(), rng.random());
                        let Some(omega) = plane.draw(from, l, u1, u2) else {
                            continue;
                        };
                        if f64::from(n.dot(omega.as_vec3())) <= 0.0 || !plane.faces(l) {
                            continue;
                        }
                        drawn.push((
                            r as u32,
                            p,
                            light,
                            (l, normal),
                            Ray {
                                origin: from,
                                dir: omega.as_vec3(),
                                t_min: 0.0,
                                t_max: f32::INFINITY,
                            },
                        ));
                    }
                }
            }
        }
        drawn
    }

    /// Follows `rays` chains from each receiver (point, normal, id: the seed of its random
    /// numbers), level by level (one batch of rays a level), and the light samples taken at
    /// their glossy bounces.
    pub(crate) fn follow(&self, receivers: &[(Vec3, Vec3, u32)], seed: u64) -> Result<Found> {
        let mut found = Found {
            ends: Vec::new(),
            direct: vec![DVec3::ZERO; receivers.len()],
            specular_share: vec![0.0; receivers.len()],
            queries: 0,
        };
        let mut level = self.first_links(receivers, seed);
        let mut samples: Vec<(u32, Vec3, LightSample)> = Vec::new();
        found.queries += self.highlight_samples(receivers, seed, &mut samples)?;
        while !level.is_empty() {
            level = self.next_level(&level, &mut found, &mut samples)?;
        }
        found.queries += self.glossy_light(&samples, &mut found.direct)?;
        // By receiver (the levels came out depth by depth), in a fixed order.
        found.ends.sort_by_key(|e| e.receiver);
        Ok(found)
    }

    /// Each chain's weight at its start: the receiver's share of its `rays`.
    fn share(&self) -> f64 {
        1.0 / f64::from(self.rays.max(1))
    }

    /// The chains' first rays: `rays` a receiver, cosine-distributed on a Fibonacci lattice
    /// shifted at random per receiver.
    fn first_links(&self, receivers: &[(Vec3, Vec3, u32)], seed: u64) -> Vec<Link> {
        let k = self.rays.max(1);
        let share = self.share();
        let mut level: Vec<Link> = Vec::with_capacity(receivers.len() * k as usize);
        for (r, &(x, n, id)) in receivers.iter().enumerate() {
            let mut rng = Pcg64Mcg::seed_from_u64(side_seed(seed, id, 23));
            let shift = (rng.random::<f64>(), rng.random::<f64>());
            let (t, b) = n.any_orthonormal_pair();
            for s in 0..k {
                let u1 = ((f64::from(s) + 0.5) / f64::from(k) + shift.0).fract();
                let u2 = (f64::from(s) * GOLDEN + shift.1).fract();
                let (radius, phi) = (u1.sqrt() as f32, (u2 * std::f64::consts::TAU) as f32);
                let dir = t * (radius * phi.cos())
                    + b * (radius * phi.sin())
                    + n * (1.0 - u1).max(0.0).sqrt() as f32;
                level.push(Link {
                    ray: Ray {
                        origin: x + self.lift * n,
                        dir,
                        t_min: 0.0,
                        t_max: f32::INFINITY,
                    },
                    receiver: r as u32,
                    normal: n,
                    weight: DVec3::splat(share),
                    depth: 0,
                    glossy: false,
                    lobe_pdf: None,
                    first: None,
                    rng: side_seed(seed, id, 29 + u64::from(s)),
                    straight: true,
                    node: ChainTree::ROOT,
                });
            }
        }
        level
    }

    /// Traces one level of links: what each hit ends or brings (into `found`, light samples
    /// at glossy bounces into `samples`), and the links of the next level.
    fn next_level(
        &self,
        level: &[Link],
        found: &mut Found,
        samples: &mut Vec<(u32, Vec3, LightSample)>,
    ) -> Result<Vec<Link>> {
        let rays: Vec<Ray> = level.iter().map(|l| l.ray).collect();
        let mut hits = vec![None; rays.len()];
        self.vis.intersect(&rays, &mut hits)?;
        found.queries += rays.len() as u64;
        let mut next = Vec::new();
        let mut scratch = Vec::new();
        for (l, hit) in level.iter().zip(&hits) {
            let Some(hit) = hit else { continue };
            let tri = &self.scene.triangles[hit.triangle as usize];
            let specular = self.spec.specular[tri.surface as usize];
            // A chain starts at a specular surface: what is diffuse from the receiver is
            // the links'.
            if l.depth == 0 {
                if !specular {
                    continue;
                }
                found.specular_share[l.receiver as usize] += self.share() as f32;
            }
            let at = At {
                tri,
                dir: l.ray.dir.normalize(),
                point: l.ray.origin + hit.t * l.ray.dir,
                t: hit.t,
            };
            if l.depth > 0 {
                self.arrive(l, &at, found);
            }
            if l.depth >= self.depth || !specular {
                continue;
            }
            let material = self.scene.material_of(tri.surface);
            let two_sided = self.scene.surfaces[tri.surface as usize].two_sided;
            let (dir, normal) = (at.dir.as_dvec3(), tri.normal.as_dvec3());
            match branches(material, dir, normal, two_sided) {
                Branches::None => {}
                Branches::Delta(list) => self.delta_branches(l, &at, &list, &mut next),
                Branches::Glossy(lobe) => {
                    self.glossy_branch(l, &at, &lobe, &mut next, samples, &mut scratch)
                }
            }
        }
        Ok(next)
    }

    /// What a link that reached a surface brings: an end where the surface has samples (its
    /// light is interpolated there), and an emitter's light where the images do not carry the
    /// path, or where a glossy bounce saw it (weighed against the light samples).
    fn arrive(&self, l: &Link, at: &At, found: &mut Found) {
        let tri = at.tri;
        let back = at.dir.dot(tri.normal) > 0.0;
        let side = side_of(tri.surface, back);
        let material = self.scene.material_of(tri.surface);
        if (self.has_samples)(side) {
            found.ends.push(End {
                receiver: l.receiver,
                point: at.point,
                side,
                normal: if back { -tri.normal } else { tri.normal },
                weight: l.weight,
            });
        }
        if let Some(tree) = self.unlisted.filter(|_| !l.glossy) {
            if !back && material.is_emitter() && !(l.straight && tree.listed(l.node)) {
                found.direct[l.receiver as usize] +=
                    std::f64::consts::PI * l.weight * material.ke.as_dvec3();
            }
        }
        if l.glossy && !back && material.is_emitter() {
            let mis = l.lobe_pdf.map_or(1.0, |pdf| {
                let dist2 = f64::from(at.t * at.t * l.ray.dir.length_squared());
                let cos_y = -f64::from(at.dir.dot(tri.normal));
                let third = l.first.map_or(0.0, |f| self.third(&f, at.point));
                self.lights
                    .lobe_weight_with(tri.surface, pdf, (dist2, cos_y), (1, 1), third)
            });
            found.direct[l.receiver as usize] +=
                std::f64::consts::PI * l.weight * material.ke.as_dvec3() * mis;
        }
    }

    /// The point just off the surface hit, on the side direction `d` leaves to.
    fn off(&self, at: &At, d: DVec3) -> Vec3 {
        let n = if d.dot(at.tri.normal.as_dvec3()) > 0.0 {
            at.tri.normal
        } else {
            -at.tri.normal
        };
        at.point + self.lift * n
    }

    /// A mirror's or glass's branches as links of the next level; a faint branch (glass's
    /// reflection beside its refraction) goes on at random, its weight raised by as much: a
    /// chain through a glass ball would otherwise end at every one of its inner bounces.
    fn delta_branches(
        &self,
        l: &Link,
        at: &At,
        list: &[Option<(DVec3, DVec3)>],
        next: &mut Vec<Link>,
    ) {
        let share = self.share();
        let back = at.dir.dot(at.tri.normal) > 0.0;
        let all: f64 = list.iter().flatten().map(|(_, w)| w.max_element()).sum();
        for (j, (d, w)) in list.iter().flatten().enumerate() {
            let mut weight = l.weight * *w;
            if weight.max_element() < NEGLIGIBLE * share {
                continue;
            }
            let kept = w.max_element() / (ROULETTE * all);
            if kept < 1.0 {
                let u = Pcg64Mcg::seed_from_u64(side_seed(l.rng, j as u32, 37)).random::<f64>();
                if u >= kept {
                    continue;
                }
                weight /= kept;
            }
            // The first branch is the reflection, the second the crossing
            // (`material::branches`).
            let (straight, node) = self.carried(l, at.tri.surface, back, j == 0);
            next.push(Link {
                rng: side_seed(l.rng, j as u32, 31),
                straight,
                node,
                ..l.bounce(self.off(at, *d), d.as_vec3(), weight)
            });
        }
    }

    /// A glossy bounce: light samples towards the lights (kept in `samples`, traced together
    /// at the end) and one link drawn from the lobe.
    fn glossy_branch(
        &self,
        l: &Link,
        at: &At,
        lobe: &Lobe,
        next: &mut Vec<Link>,
        samples: &mut Vec<(u32, Vec3, LightSample)>,
        scratch: &mut Vec<LightSample>,
    ) {
        let mut rng = Pcg64Mcg::seed_from_u64(l.rng);
        let mut uniforms = || (rng.random::<f64>(), rng.random::<f64>());
        let from = at.point + self.lift * lobe.normal().as_vec3();
        // A first bounce on a glossy plane weighs against highlight sampling.
        let first = match self.highlights.plane_of(at.tri.surface) {
            Some(plane) if l.depth == 0 => Some(FirstBounce {
                x: l.ray.origin,
                cos_x: f64::from(l.normal.dot(at.dir)),
                omega: at.dir.as_dvec3(),
                plane: plane.surface,
            }),
            _ => None,
        };
        scratch.clear();
        let third = |light: Vec3, density: Option<f64>| match first {
            Some(f) => self.third(&f, light) * density.unwrap_or(1.0),
            None => 0.0,
        };
        self.lights
            .sample_with(lobe, from, (1, 1), &mut uniforms, &third, scratch);
        for mut sample in scratch.drain(..) {
            sample.radiance *= std::f64::consts::PI * l.weight;
            samples.push((l.receiver, from, sample));
        }
        let (u1, u2) = uniforms();
        let Some((d, w)) = lobe.sample(u1, u2) else {
            return;
        };
        let weight = l.weight * w;
        if weight.max_element() >= NEGLIGIBLE * self.share() {
            next.push(Link {
                glossy: true,
                lobe_pdf: Some(lobe.pdf(d)),
                first,
                rng: side_seed(l.rng, 7, 37),
                straight: false,
                node: ChainTree::OFF,
                ..l.bounce(from, d.as_vec3(), weight)
            });
        }
    }

    /// The light samples taken at glossy bounces, added to their receivers' direct light where
    /// nothing blocks them; the queries.
    fn glossy_light(
        &self,
        samples: &[(u32, Vec3, LightSample)],
        direct: &mut [DVec3],
    ) -> Result<u64> {
        let paths: Vec<LightPath> = samples
            .iter()
            .map(|(_, from, s)| LightPath {
                from: *from,
                to: s.to,
                chain: &[],
            })
            .collect();
        let mut shares = vec![DVec3::ZERO; paths.len()];
        let queries = shadow::arriving(self.spec, self.vis, self.lift, &paths, &mut shares)?;
        for ((receiver, _, s), share) in samples.iter().zip(shares) {
            direct[*receiver as usize] += s.radiance * share;
        }
        Ok(queries)
    }
}

/// Where a link met a surface.
struct At<'s> {
    tri: &'s crate::scene::Triangle,
    /// The link's direction, normalised.
    dir: Vec3,
    point: Vec3,
    /// The hit's ray parameter.
    t: f32,
}
