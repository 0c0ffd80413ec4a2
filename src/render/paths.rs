//! Camera paths through mirrors, glass and glossy surfaces (`docs/method.md` §22): a camera ray
//! that meets a specular surface goes on along its branches — a mirror's reflection, glass's
//! reflection and refraction, both followed — up to the specular depth, and a glossy lobe's
//! `glossy_rays` importance-sampled directions, with the lights sampled there as well
//! (multiple importance sampling). Where a path reaches a surface with samples, that surface is
//! shaded as a camera hit is, weighted by the path's throughput; emitters seen along a path
//! show their radiance. Behind a glossy bounce the samples' whole light is interpolated (their
//! direct light is not traced again for every lobe sample).

use glam::{DVec3, Vec3};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::{Pending, Quantity, Shader};
use crate::error::Result;
use crate::material::{branches, Branches, Lobe};
use crate::sampling::poisson::side_seed;
use crate::sampling::side_of;
use crate::specular::lights::{LightSample, Lights};
use crate::specular::shadow::{self, LightPath};
use crate::specular::Specular;
use crate::visibility::{Ray, Segment};

/// What following specular paths needs.
pub(super) struct Paths {
    pub spec: Specular,
    pub lights: Lights,
    pub depth: u32,
    pub glossy_rays: u32,
}

/// Paths whose throughput falls below this are not followed further.
const NEGLIGIBLE: f64 = 1e-4;

/// A ray of a camera path in flight.
struct Branch {
    ray: Ray,
    /// The camera ray (pixel sample) it belongs to.
    origin: usize,
    weight: DVec3,
    depth: u32,
    /// Whether its direct light is traced where it ends: no glossy bounce came before, and at
    /// most one mirror or glass bounce (deeper reflections take their direct light
    /// interpolated, as their share of the pixel is small).
    traced: bool,
    /// Whether a glossy bounce came before (later ones draw one direction, not a fan).
    glossed: bool,
    /// Whether it is its pixel sample's main branch (the heaviest at every delta bounce): the
    /// side it ends on tells edges apart for supersampling, in mirrors and through glass too.
    main: bool,
    /// The seed of its random numbers.
    id: u32,
    /// The density the glossy lobe that cast it drew it with, and how many it drew (as many
    /// light samples were taken there): for MIS at an emitter.
    lobe_pdf: Option<(f64, u32)>,
}

/// What the paths of a batch of camera rays gather as they go.
struct Walk {
    /// Directions a first glossy bounce draws.
    fan: u32,
    /// Per camera ray: the radiance so far, and the side (or path) its main branch sees.
    radiance: Vec<DVec3>,
    sides: Vec<u32>,
    /// Surfaces with samples the paths end at: (pending hit, camera ray, weight).
    ends: Vec<(Pending, usize, DVec3)>,
    shadowed: Vec<Shadowed>,
    /// Scratch for a bounce's light samples.
    samples: Vec<LightSample>,
}

impl Branch {
    /// The branch after this one's bounce: from `origin` along `dir`, carrying `weight`, one
    /// deeper, the rest as this one's (its id and what it is for the caller to set).
    fn bounce(&self, origin: Vec3, dir: Vec3, weight: DVec3) -> Branch {
        Branch {
            ray: Ray {
                origin,
                dir,
                t_min: 0.0,
                t_max: f32::INFINITY,
            },
            origin: self.origin,
            weight,
            depth: self.depth + 1,
            traced: self.traced,
            glossed: self.glossed,
            main: self.main,
            id: self.id,
            lobe_pdf: None,
        }
    }
}

/// A light sample's shadow path waiting for its answer.
struct Shadowed {
    origin: usize,
    from: Vec3,
    sample: LightSample,
}

impl Shader<'_> {
    /// [`Shader::shade`] in a scene with specular surfaces; `share` rays of a pixel share its
    /// glossy fans (a supersampled pixel's rays draw fewer directions each, as many in all).
    pub(super) fn shade_paths(
        &self,
        paths: &Paths,
        rays: &[Ray],
        first_id: u32,
        out: &mut [(Vec3, u32)],
        share: u32,
    ) -> Result<u64> {
        let mut walk = Walk {
            fan: (paths.glossy_rays / share.max(1)).max(1),
            radiance: vec![DVec3::ZERO; rays.len()],
            sides: vec![u32::MAX; rays.len()],
            ends: Vec::new(),
            shadowed: Vec::new(),
            samples: Vec::new(),
        };
        let mut level: Vec<Branch> = rays
            .iter()
            .enumerate()
            .map(|(i, &ray)| Branch {
                ray,
                origin: i,
                weight: DVec3::ONE,
                depth: 0,
                traced: true,
                glossed: false,
                main: true,
                id: first_id.wrapping_add(i as u32),
                lobe_pdf: None,
            })
            .collect();
        let mut queries = 0u64;
        while !level.is_empty() {
            let level_rays: Vec<Ray> = level.iter().map(|b| b.ray).collect();
            let mut hits = vec![None; level_rays.len()];
            self.vis.intersect(&level_rays, &mut hits)?;
            queries += level_rays.len() as u64;
            let mut next = Vec::new();
            for (b, hit) in level.iter().zip(&hits) {
                match hit {
                    Some(hit) => self.meet(paths, b, hit, &mut walk, &mut next),
                    None => self.escape(b, &mut walk),
                }
            }
            level = next;
        }
        queries += self.light_samples_seen(paths, &walk.shadowed, &mut walk.radiance)?;
        let pending: Vec<Pending> = walk.ends.iter().map(|(p, _, _)| p.clone()).collect();
        let (shown, q) = self.resolve(&pending, 0)?;
        queries += q;
        for ((_, origin, weight), value) in walk.ends.iter().zip(shown) {
            walk.radiance[*origin] += *weight * value.as_dvec3();
        }
        for ((o, l), side) in out.iter_mut().zip(walk.radiance).zip(walk.sides) {
            *o = (l.as_vec3(), side);
        }
        Ok(queries)
    }

    /// A branch that left the model (through a pane, by a mirror): the sky or the ground, and
    /// the sun's disc only along delta paths (a glossy lobe's rays are not weighed against the
    /// sun's).
    fn escape(&self, b: &Branch, walk: &mut Walk) {
        let Some(d) = self.scene.daylight() else {
            return;
        };
        if self.quantity == Quantity::Radiance {
            let sun = if b.lobe_pdf.is_none() {
                d.sun_radiance(b.ray.dir)
            } else {
                0.0
            };
            walk.radiance[b.origin] += b.weight * (d.radiance(b.ray.dir) + sun);
        }
    }

    /// A branch that met a surface: the side its pixel sample sees (main branches), an end
    /// where the side has samples or an emitter's light, and the branches that go on.
    fn meet(
        &self,
        paths: &Paths,
        b: &Branch,
        hit: &crate::visibility::Hit,
        walk: &mut Walk,
        next: &mut Vec<Branch>,
    ) {
        let tri = &self.scene.triangles[hit.triangle as usize];
        let dir = b.ray.dir.normalize();
        let back = dir.dot(tri.normal) > 0.0;
        let side = side_of(tri.surface, back);
        if b.main {
            // A side id past the scene's sides stands for a path: which side it met at which
            // depth.
            walk.sides[b.origin] = if b.depth == 0 {
                side
            } else {
                let n = 2 * self.scene.surfaces.len() as u32;
                n.wrapping_mul(b.depth).wrapping_add(side)
            };
        }
        let point = b.ray.origin + hit.t * b.ray.dir;
        let material = self.scene.material_of(tri.surface);
        let normal = if back { -tri.normal } else { tri.normal };
        if self.interpolator.has_samples(side) {
            walk.ends.push((
                Pending {
                    side,
                    fixed: None,
                    point,
                    normal,
                    traced: b.traced,
                    texel: self.texel(hit.triangle, point),
                    id: b.id,
                },
                b.origin,
                b.weight,
            ));
        } else if !back && material.is_emitter() && self.quantity == Quantity::Radiance {
            // An emitter seen along the path; one a glossy lobe's sample reached counts with
            // its share against the lights sampled at that lobe.
            let mis = match b.lobe_pdf {
                Some((pdf, n)) => {
                    let dist2 = f64::from(hit.t * hit.t * b.ray.dir.length_squared());
                    let cos_y = -f64::from(dir.dot(tri.normal));
                    paths
                        .lights
                        .lobe_weight(tri.surface, pdf, dist2, cos_y, n, n)
                }
                None => 1.0,
            };
            walk.radiance[b.origin] += b.weight * material.ke.as_dvec3() * mis;
        }
        if b.depth >= paths.depth || self.quantity != Quantity::Radiance {
            return;
        }
        let two_sided = self.scene.surfaces[tri.surface as usize].two_sided;
        match branches(material, dir.as_dvec3(), tri.normal.as_dvec3(), two_sided) {
            Branches::None => {}
            Branches::Delta(list) => self.delta_branches(b, tri.normal, point, &list, next),
            Branches::Glossy(lobe) => {
                let from = point + self.lift * normal;
                self.glossy_bounce(paths, b, &lobe, from, walk, next);
            }
        }
    }

    /// A mirror's or glass's branches (the heaviest one goes on as the main branch), each
    /// leaving from just off the surface (`normal` its plane's) on the side it goes to.
    fn delta_branches(
        &self,
        b: &Branch,
        normal: Vec3,
        point: Vec3,
        list: &[Option<(DVec3, DVec3)>],
        next: &mut Vec<Branch>,
    ) {
        let on = |d: DVec3| {
            let n = if d.dot(normal.as_dvec3()) > 0.0 {
                normal
            } else {
                -normal
            };
            point + self.lift * n
        };
        let heaviest = list
            .iter()
            .flatten()
            .enumerate()
            .max_by(|a, b| a.1 .1.max_element().total_cmp(&b.1 .1.max_element()))
            .map_or(0, |(k, _)| k);
        for (k, (d, w)) in list.iter().flatten().enumerate() {
            let weight = b.weight * *w;
            if weight.max_element() < NEGLIGIBLE {
                continue;
            }
            next.push(Branch {
                traced: b.traced && b.depth == 0,
                main: b.main && k == heaviest,
                id: side_seed(u64::from(b.id), b.depth, k as u64) as u32,
                ..b.bounce(on(*d), d.as_vec3(), weight)
            });
        }
    }

    /// A glossy bounce at `from`: a fan of directions at the first glossy bounce, one at later
    /// ones, and as many light samples, their shadow paths kept for the end.
    fn glossy_bounce(
        &self,
        paths: &Paths,
        b: &Branch,
        lobe: &Lobe,
        from: Vec3,
        walk: &mut Walk,
        next: &mut Vec<Branch>,
    ) {
        let mut rng =
            Pcg64Mcg::seed_from_u64(side_seed(0x676c_6f73_7379, b.id, u64::from(b.depth)));
        let mut uniforms = || (rng.random::<f64>(), rng.random::<f64>());
        let n = if b.glossed { 1 } else { walk.fan };
        self.glossy(n, b, lobe, from, &mut uniforms, next);
        walk.samples.clear();
        paths
            .lights
            .sample(lobe, from, n, n, &mut uniforms, &mut walk.samples);
        walk.shadowed
            .extend(walk.samples.drain(..).map(|mut sample| {
                sample.radiance *= b.weight;
                Shadowed {
                    origin: b.origin,
                    from,
                    sample,
                }
            }));
    }

    /// `n` directions drawn from a glossy lobe, each carrying 1/n of the path.
    fn glossy(
        &self,
        n: u32,
        b: &Branch,
        lobe: &Lobe,
        from: Vec3,
        uniforms: &mut impl FnMut() -> (f64, f64),
        next: &mut Vec<Branch>,
    ) {
        for j in 0..n {
            let (u1, u2) = uniforms();
            // Stratified along the first coordinate.
            let u1 = (f64::from(j) + u1) / f64::from(n);
            let Some((d, w)) = lobe.sample(u1, u2) else {
                continue;
            };
            let weight = b.weight * w / f64::from(n);
            if weight.max_element() < NEGLIGIBLE / f64::from(n) {
                continue;
            }
            next.push(Branch {
                traced: false,
                glossed: true,
                main: false,
                id: side_seed(u64::from(b.id), 1000 + j, u64::from(b.depth)) as u32,
                lobe_pdf: Some((lobe.pdf(d), n)),
                ..b.bounce(from, d.as_vec3(), weight)
            });
        }
    }

    /// Adds the light samples taken at glossy vertices that nothing blocks; returns the queries.
    fn light_samples_seen(
        &self,
        paths: &Paths,
        shadowed: &[Shadowed],
        radiance: &mut [DVec3],
    ) -> Result<u64> {
        let light_paths: Vec<LightPath> = shadowed
            .iter()
            .map(|s| LightPath {
                from: s.from,
                to: s.sample.to,
                chain: &[],
            })
            .collect();
        let mut shares = vec![DVec3::ZERO; light_paths.len()];
        let queries = if paths.spec.any_glass {
            shadow::arriving(&paths.spec, self.vis, self.lift, &light_paths, &mut shares)?
        } else {
            let segments: Vec<Segment> = light_paths
                .iter()
                .map(|p| Segment { a: p.from, b: p.to })
                .collect();
            let mut blocked = vec![false; segments.len()];
            self.vis.occluded(&segments, &mut blocked)?;
            for (s, b) in shares.iter_mut().zip(blocked) {
                *s = if b { DVec3::ZERO } else { DVec3::ONE };
            }
            segments.len() as u64
        };
        self.shadow_rays
            .fetch_add(queries, std::sync::atomic::Ordering::Relaxed);
        for (s, share) in shadowed.iter().zip(shares) {
            radiance[s.origin] += s.sample.radiance * share;
        }
        Ok(queries)
    }
}
