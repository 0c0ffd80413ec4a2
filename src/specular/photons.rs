//! Photons (`docs/method.md` §22): the light that reaches a diffuse surface from a light by way
//! of mirrors and glass where the mirror images (`images`) do not carry it — off curved
//! mirrors, through refracting solids (a ball, a block: the caustics under them), and along
//! chains of flat mirrors beyond the images listed. Photons leave the lights towards each
//! specular object (a cone around its bounding sphere), follow mirror reflection, Fresnel
//! reflection or refraction (chosen at random in proportion, so a photon keeps its power) and
//! pane crossings, and land on the first surface with samples after at least one specular
//! bounce. A landing the images already carry — every reflection on a listed chain's windows in
//! order, every crossing through glass shadow rays pass straight — is not kept; the others are
//! the solve's to spread over the samples' areas (`solver::specular`). Paths with a glossy
//! bounce are the chains' (`gather`), not the photons'.
//!
//! This is the first pass of Jensen's two-pass method (a caustic photon map) with the meshless
//! areas as the density estimate: a photon's power goes to the samples around its landing point
//! with the weights that share area cells among them (eq. 5), so a uniform irradiance is
//! reproduced exactly and the bias is the areas' own blur, which adaptive rounds shrink where
//! the caustic's light changes.

use glam::{DVec3, Vec3};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::images::{ChainTree, Listing};
use super::lights::Lights;
use super::Specular;
use crate::error::Result;
use crate::material::{fresnel, reflect};
use crate::parallel::{for_chunks_reporting, Report};
use crate::sampling::directions::cosine;
use crate::sampling::poisson::side_seed;
use crate::sampling::{side_of, Side};
use crate::scene::{Kind, Scene};
use crate::visibility::{Ray, Visibility};

/// A photon's landing on a surface with samples: where, on which side, with what power (W,
/// RGB).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Landing {
    pub point: Vec3,
    pub side: Side,
    pub power: [f32; 3],
}

/// What a photon pass found.
#[derive(Clone, Debug, Default)]
pub(crate) struct Found {
    pub landings: Vec<Landing>,
    /// Photons sent.
    pub photons: u64,
    pub queries: u64,
}

/// Photons whose power falls below this share of their start are not followed further.
const NEGLIGIBLE: f64 = 1e-4;

/// Photons one work item traces (their rays go to the backend a bounce at a time).
const CHUNK: u64 = 4096;

/// A cone narrower than this (sine of its half-angle) aims photons at an object; from nearer,
/// they leave as the light does, over the whole hemisphere.
const AIMED: f32 = 0.9;

/// Whether a scene needs photons: a curved mirror or refracting solid, or chains of images left
/// out of the listing.
pub(crate) fn needed(scene: &Scene, spec: &Specular, listing: &Listing) -> bool {
    !listing.complete
        || (0..scene.surfaces.len())
            .any(|s| delta(scene, spec, s as u32) && !covered_alone(spec, s))
}

/// Whether a surface's specular light goes on in fixed directions: a mirror or glass.
fn delta(scene: &Scene, spec: &Specular, surface: u32) -> bool {
    spec.specular[surface as usize]
        && match scene.material_of(surface).kind {
            Kind::Specular { roughness, .. } => roughness == 0.0,
            Kind::Glass { .. } => true,
            Kind::Diffuse => false,
        }
}

/// Whether the images carry all a surface's specular light: it is a reflector, and light passes
/// it straight if it is glass.
fn covered_alone(spec: &Specular, surface: usize) -> bool {
    spec.reflector_of[surface].is_some()
        && (spec.glass[surface].is_none() || spec.straight[surface])
}

/// An object photons are aimed at: specular surfaces joined along edges.
struct Target {
    centre: Vec3,
    radius: f32,
}

/// A light and an object, with the photons sent from one towards the other.
struct Pair {
    /// An area light (`Err`) or a point light or luminaire (`Ok`), by index in `Lights`.
    light: std::result::Result<usize, usize>,
    target: u32,
    photons: u64,
}

/// The photon pass of a scene.
pub(crate) struct Photons<'a> {
    scene: &'a Scene,
    spec: &'a Specular,
    lights: &'a Lights,
    vis: &'a dyn Visibility,
    lift: f32,
    depth: u32,
    /// The chains of images listed, read from the light.
    listed: ChainTree,
    /// Per surface: its target, if it is a mirror or glass.
    target_of: Vec<Option<u32>>,
    targets: Vec<Target>,
    pairs: Vec<Pair>,
    /// Per surface side: whether it has samples (photons land there).
    has_samples: Vec<bool>,
}

/// A photon on its way.
struct Flight {
    ray: Ray,
    power: DVec3,
    start: f64,
    /// The object it must meet first.
    target: u32,
    bounces: u32,
    /// Whether the images carry its path so far (given its reflections are a listed chain).
    straight: bool,
    /// Where its reflections so far lead in the tree of listed chains.
    node: u32,
    rng: Pcg64Mcg,
}

impl<'a> Photons<'a> {
    /// The pass for `count` photons in all (shared among lights and objects by the power each
    /// light sends towards each object), following up to `depth` specular bounces.
    pub(crate) fn new(
        scene: &'a Scene,
        (spec, listing, lights): (&'a Specular, &Listing, &'a Lights),
        vis: &'a dyn Visibility,
        count: u64,
        depth: u32,
    ) -> Photons<'a> {
        use crate::scene::adjacency::{pieces, shared_edges};
        let n = scene.surfaces.len();
        let is_delta: Vec<bool> = (0..n as u32).map(|s| delta(scene, spec, s)).collect();
        let links = shared_edges(scene)
            .into_iter()
            .filter(|&(a, b)| is_delta[a as usize] && is_delta[b as usize]);
        let piece = pieces(n, links);
        let mut target_of = vec![None; n];
        let mut boxes: Vec<(Vec3, Vec3)> = Vec::new();
        let mut of_piece = std::collections::HashMap::new();
        for s in (0..n).filter(|&s| is_delta[s]) {
            let t = *of_piece.entry(piece[s]).or_insert_with(|| {
                boxes.push((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)));
                boxes.len() as u32 - 1
            });
            target_of[s] = Some(t);
            let range = &scene.surfaces[s].triangles;
            let b = &mut boxes[t as usize];
            for v in scene.triangles[range.start as usize..range.end as usize]
                .iter()
                .flat_map(|t| t.vertices)
            {
                *b = (b.0.min(v), b.1.max(v));
            }
        }
        let lift = crate::visibility::lift(scene);
        let targets: Vec<Target> = boxes
            .iter()
            .map(|&(lo, hi)| Target {
                centre: 0.5 * (lo + hi),
                radius: 0.5 * (hi - lo).length() + 2.0 * lift,
            })
            .collect();
        let pairs = share(lights, &targets, count);
        let mut has_samples = vec![false; 2 * n];
        for side in crate::sampling::reflecting_sides(scene) {
            has_samples[side as usize] = true;
        }
        Photons {
            scene,
            spec,
            lights,
            vis,
            lift,
            depth,
            listed: ChainTree::new(&listing.chains, true),
            target_of,
            targets,
            pairs,
            has_samples,
        }
    }

    /// Photons sent in all (each light and object's share, at least a few each).
    pub(crate) fn count(&self) -> u64 {
        self.pairs.iter().map(|p| p.photons).sum()
    }

    /// Traces every photon on up to `threads` threads; the landings come in a fixed order
    /// (pair by pair, photon by photon), whatever the threads. A Stop heard in `report` leaves
    /// the photons not traced yet out.
    pub(crate) fn trace(&self, seed: u64, threads: usize, report: Report) -> Result<Found> {
        // Work items: (pair, first photon, photons).
        let mut items: Vec<(usize, u64, u64)> = Vec::new();
        for (p, pair) in self.pairs.iter().enumerate() {
            let mut first = 0;
            while first < pair.photons {
                let n = CHUNK.min(pair.photons - first);
                items.push((p, first, n));
                first += n;
            }
        }
        let mut out: Vec<Option<(Vec<Landing>, u64)>> = vec![None; items.len()];
        for_chunks_reporting(
            &mut out,
            1,
            threads,
            |i, slot| {
                let (p, first, n) = items[i];
                slot[0] = Some(self.trace_item(p, first, n, seed)?);
                Ok(())
            },
            report,
        )?;
        let mut found = Found::default();
        for ((_, _, n), done) in items.iter().zip(out) {
            if let Some((landings, queries)) = done {
                found.landings.extend(landings);
                found.queries += queries;
                found.photons += n;
            }
        }
        Ok(found)
    }

    /// Photons `first..first + n` of pair `p`: their landings, and the queries.
    fn trace_item(&self, p: usize, first: u64, n: u64, seed: u64) -> Result<(Vec<Landing>, u64)> {
        let pair = &self.pairs[p];
        let mut flights: Vec<Flight> = (first..first + n)
            .filter_map(|i| {
                let rng = Pcg64Mcg::seed_from_u64(side_seed(seed ^ 0x7068_6f74, p as u32, i));
                self.emit(pair, rng)
            })
            .collect();
        let mut landings = Vec::new();
        let mut queries = 0;
        let mut hits = Vec::new();
        while !flights.is_empty() {
            let rays: Vec<Ray> = flights.iter().map(|f| f.ray).collect();
            hits.clear();
            hits.resize(rays.len(), None);
            self.vis.intersect(&rays, &mut hits)?;
            queries += rays.len() as u64;
            let mut next = Vec::with_capacity(flights.len());
            for (mut f, hit) in flights.into_iter().zip(&hits) {
                let Some(hit) = hit else { continue };
                if self.step(&mut f, hit.t, hit.triangle, &mut landings) {
                    next.push(f);
                }
            }
            flights = next;
        }
        Ok((landings, queries))
    }

    /// A photon of `pair` drawn with `rng`: from a point of the light, in a cone around the
    /// object's bounding sphere (or over the light's whole hemisphere, or sphere, from near),
    /// carrying its share of the light's power; `None` if drawn where the light sends nothing.
    fn emit(&self, pair: &Pair, mut rng: Pcg64Mcg) -> Option<Flight> {
        let target = &self.targets[pair.target as usize];
        let count = pair.photons as f64;
        let (origin, dir, power) = match pair.light {
            Err(i) => {
                let (area, ke) = self
                    .lights
                    .area_lights()
                    .nth(i)
                    .map(|(_, area, ke)| (area, ke))?;
                let (y, normal) = self.lights.point_on(i, rng.random(), rng.random());
                let (dir, power) = match cone(y, target) {
                    Some((axis, cos_max)) => {
                        let dir = in_cone(axis, cos_max, rng.random(), rng.random());
                        let cos = f64::from(normal.dot(dir));
                        if cos <= 0.0 {
                            return None;
                        }
                        let solid = std::f64::consts::TAU * (1.0 - f64::from(cos_max));
                        (dir, ke * cos * area * solid / count)
                    }
                    None => (
                        cosine(normal, rng.random(), rng.random()),
                        ke * std::f64::consts::PI * area / count,
                    ),
                };
                (y + self.lift * normal, dir, power)
            }
            Ok(j) => {
                let source = &self.lights.point_sources()[j];
                let (dir, solid) = match cone(source.position, target) {
                    Some((axis, cos_max)) => (
                        in_cone(axis, cos_max, rng.random(), rng.random()),
                        std::f64::consts::TAU * (1.0 - f64::from(cos_max)),
                    ),
                    None => (
                        in_cone(Vec3::Z, -1.0, rng.random(), rng.random()),
                        4.0 * std::f64::consts::PI,
                    ),
                };
                let intensity = source.towards(dir).as_dvec3();
                (source.position, dir, intensity * solid / count)
            }
        };
        if power.max_element() <= 0.0 {
            return None;
        }
        Some(Flight {
            ray: Ray {
                origin,
                dir,
                t_min: 0.0,
                t_max: f32::INFINITY,
            },
            start: power.max_element(),
            power,
            target: pair.target,
            bounces: 0,
            straight: true,
            node: ChainTree::ROOT,
            rng,
        })
    }

    /// A photon meets triangle `triangle` at distance `t`: lands there if it may, then bounces
    /// off or through it. Whether it goes on.
    fn step(&self, f: &mut Flight, t: f32, triangle: u32, landings: &mut Vec<Landing>) -> bool {
        let tri = &self.scene.triangles[triangle as usize];
        let surface = tri.surface;
        let point = f.ray.origin + t * f.ray.dir;
        let dir = f.ray.dir.normalize();
        let back = dir.dot(tri.normal) > 0.0;
        if f.bounces == 0 && self.target_of[surface as usize] != Some(f.target) {
            // Another object's photons (or the direct light's) carry this path.
            return false;
        }
        let side = side_of(surface, back);
        if f.bounces > 0 && self.has_samples[side as usize] && !self.carried(f) {
            landings.push(Landing {
                point,
                side,
                power: f.power.as_vec3().to_array(),
            });
        }
        if f.bounces >= self.depth || self.target_of[surface as usize].is_none() {
            return false;
        }
        let material = self.scene.material_of(surface);
        let s = surface as usize;
        let facing = if back { -tri.normal } else { tri.normal };
        let d = dir.as_dvec3();
        let cos = -d.dot(facing.as_dvec3());
        // The way on: (direction, a reflection?, power factor). Not `material::branches`: its
        // weights carry radiance (÷η² into glass, where a path runs against the light), a
        // photon carries power, and it takes one branch at random, not both.
        let (next, reflected, factor) = match material.kind {
            Kind::Specular { ks, .. } => {
                if back && !self.scene.surfaces[s].two_sided {
                    return false;
                }
                (reflect(d, facing.as_dvec3()), true, ks.as_dvec3())
            }
            Kind::Glass {
                ior,
                transmit,
                thin,
            } => {
                let ior = f64::from(ior);
                let filter = transmit.as_dvec3();
                let u: f64 = f.rng.random();
                if thin {
                    if u < fresnel::pane_reflectance(cos, ior) {
                        (reflect(d, facing.as_dvec3()), true, DVec3::ONE)
                    } else {
                        (d, false, filter)
                    }
                } else {
                    let eta = if back { 1.0 / ior } else { ior };
                    let refracted = fresnel::refract(d, facing.as_dvec3(), eta);
                    match refracted {
                        Some(r) if u >= fresnel::reflectance(cos, eta) => (r, false, filter),
                        _ => (reflect(d, facing.as_dvec3()), true, DVec3::ONE),
                    }
                }
            }
            Kind::Diffuse => return false,
        };
        // What the images carry: reflections on reflectors from their reflecting side, and
        // crossings of glass that shadow rays pass straight (a slab's inner bounces among them).
        if reflected {
            match self.spec.reflector_of[s] {
                Some(r) if !back || self.spec.reflectors[r as usize].both_sides => {
                    f.node = self.listed.step(f.node, r)
                }
                _ if back && self.spec.straight[s] => {}
                _ => f.straight = false,
            }
        } else if !self.spec.straight[s] {
            f.straight = false;
        }
        f.power *= factor;
        f.bounces += 1;
        if f.power.max_element() < NEGLIGIBLE * f.start {
            return false;
        }
        let next = next.as_vec3();
        let lift = if next.dot(tri.normal) > 0.0 {
            tri.normal
        } else {
            -tri.normal
        };
        f.ray = Ray {
            origin: point + self.lift * lift,
            dir: next,
            t_min: 0.0,
            t_max: f32::INFINITY,
        };
        true
    }

    /// Whether the images carry a photon's path so far: straight through glass, and its
    /// reflections a listed chain (or none).
    fn carried(&self, f: &Flight) -> bool {
        f.straight && self.listed.listed(f.node)
    }
}

/// The cone from `from` around a target's bounding sphere, as (axis, cos of the half-angle);
/// `None` from so near that the photons leave over the whole hemisphere instead.
fn cone(from: Vec3, target: &Target) -> Option<(Vec3, f32)> {
    let to = target.centre - from;
    let d = to.length();
    let sin = target.radius / d;
    (d > 0.0 && sin < AIMED).then(|| (to / d, (1.0 - sin * sin).sqrt()))
}

/// A direction uniform in the cone around unit `axis` of half-angle cos⁻¹ `cos_max` (−1: the
/// whole sphere).
fn in_cone(axis: Vec3, cos_max: f32, u1: f32, u2: f32) -> Vec3 {
    let cos = 1.0 - u1 * (1.0 - cos_max);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * u2;
    let (t, b) = axis.any_orthonormal_pair();
    (t * (sin * phi.cos()) + b * (sin * phi.sin()) + axis * cos).normalize()
}

/// `count` photons shared among (light, object) pairs by the power each light sends towards
/// each object, about: its power × the share of its hemisphere the object's cone fills. Every
/// pair that can get light gets some photons.
fn share(lights: &Lights, targets: &[Target], count: u64) -> Vec<Pair> {
    let mut pairs = Vec::new();
    let mut weights = Vec::new();
    let luminance = |c: DVec3| c.dot(DVec3::new(0.2126, 0.7152, 0.0722)).max(0.0);
    for (i, area, ke) in lights.area_lights() {
        let (centre, _) = lights.bounds_of(i);
        for (t, target) in targets.iter().enumerate() {
            let fill = cone(centre, target).map_or(1.0, |(_, c)| 2.0 * (1.0 - f64::from(c)));
            pairs.push(Pair {
                light: Err(i),
                target: t as u32,
                photons: 0,
            });
            weights.push(luminance(ke) * std::f64::consts::PI * area * fill.min(1.0));
        }
    }
    for (j, source) in lights.point_sources().iter().enumerate() {
        for (t, target) in targets.iter().enumerate() {
            let w = match cone(source.position, target) {
                Some((axis, c)) => {
                    luminance(source.towards(axis).as_dvec3())
                        * std::f64::consts::TAU
                        * (1.0 - f64::from(c))
                }
                None => luminance(source.intensity.as_dvec3()) * 4.0 * std::f64::consts::PI,
            };
            pairs.push(Pair {
                light: Ok(j),
                target: t as u32,
                photons: 0,
            });
            weights.push(w);
        }
    }
    let total: f64 = weights.iter().sum();
    if total <= 0.0 {
        return Vec::new();
    }
    // At least a little for every pair: the estimate is rough (a light's normals, a luminaire's
    // beam), and a pair left out would drop its light.
    let floor = (count / (10 * pairs.len() as u64).max(1)).max(1);
    for (p, w) in pairs.iter_mut().zip(&weights) {
        if *w > 0.0 {
            p.photons = ((count as f64 * w / total).round() as u64).max(floor);
        }
    }
    pairs.retain(|p| p.photons > 0);
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_in_a_cone_stay_in_it_and_cover_it_evenly() {
        // Uniform in solid angle: the share with cos θ above the cap's middle value is half.
        let axis = Vec3::new(1.0, 2.0, -0.5).normalize();
        let cos_max = 0.8f32;
        let mid = 0.5 * (1.0 + cos_max);
        let n = 100;
        let mut upper = 0;
        for i in 0..n {
            for j in 0..n {
                let w = in_cone(
                    axis,
                    cos_max,
                    (i as f32 + 0.5) / n as f32,
                    (j as f32 + 0.5) / n as f32,
                );
                assert!(w.dot(axis) >= cos_max - 1e-5);
                upper += usize::from(w.dot(axis) > mid);
            }
        }
        assert_eq!(upper, n * n / 2);
    }
}
