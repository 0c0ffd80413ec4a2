//! Daylight entering the model: the irradiance the sky and the ground give a point inside
//! through openings and glass, E = ∫ L(ω) T(ω) cos θ dω over the directions whose ray leaves
//! the model (`docs/method.md` §23).
//!
//! Most of a room's hemisphere is wall, so the rays are aimed at where light can enter: the
//! **portals**, found once per scene, are the thin panes' triangles and the holes in the mesh
//! (loops of edges that only one triangle uses, fanned from their centroid: a window cut in a
//! wall, the open top of a court). Each receiver draws most of its rays towards the portals
//! (a portal triangle picked by its approximate solid angle, a point uniform on it) and the
//! rest cosine-weighted over its hemisphere, and weighs every ray by the balance heuristic over
//! both ways of drawing it (Veach 1997, the multi-sample form): where the portals miss an
//! opening (a gap between separate wall pieces, say) the hemisphere's rays still find it, so
//! the estimate is unbiased whatever the portals; where they find them, a small window in a
//! large room is sampled as densely as a large one. A ray's light passes thin panes and slabs
//! with the glass's Fresnel transmittance (`specular::shadow`), and anything else blocks it.

use std::collections::HashMap;

use glam::{DVec3, Vec3};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::Daylight;
use crate::error::Result;
use crate::light::lattice;
use crate::sampling::poisson::side_seed;
use crate::scene::{Kind, Scene};
use crate::specular::shadow::{self, LightPath};
use crate::specular::Specular;
use crate::visibility::{Ray, Visibility};

/// Portal triangles a scene may have before they cost more than they save (every receiver
/// weighs each one, and every ray is tested against each one): beyond, the holes' are dropped
/// (the panes' kept if they fit), and rays go over the hemisphere only where none are left.
const MAX_PORTALS: usize = 512;

/// The share of a receiver's rays aimed at the portals (where it has any in front).
const PORTAL_SHARE: f64 = 0.75;

/// A salt for the receivers' seeds: their sky rays are not their shadow rays.
const SALT: u64 = 0x5ca1_ab1e_da11_9447;

/// One portal triangle.
#[derive(Clone, Debug)]
struct Portal {
    vertices: [Vec3; 3],
    normal: Vec3,
    area: f32,
    centroid: Vec3,
}

/// A ray that leaves the model: what one unit of luminance along it gives its receiver.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Escape {
    /// The receiver's index in the points asked about.
    pub receiver: u32,
    /// Towards the sky or the ground (unit).
    pub dir: Vec3,
    /// The glass's transmittance × the ray's weight (cos θ over its density × rays).
    pub light: DVec3,
}

/// The daylight entering a scene, ready to be measured at points.
pub(crate) struct Entering<'a> {
    daylight: &'a Daylight,
    portals: Vec<Portal>,
    specular: Option<Specular>,
    lift: f32,
    /// How far a ray is followed: past the scene's bounds from anywhere inside.
    far: f32,
    /// Rays per receiver.
    rays: u32,
}

/// The portal triangles of a scene: its thin panes and its holes.
fn portals(scene: &Scene) -> Vec<Portal> {
    fn push(out: &mut Vec<Portal>, vertices: [Vec3; 3]) {
        let e = (vertices[1] - vertices[0]).cross(vertices[2] - vertices[0]);
        let area = 0.5 * e.length();
        if area > 0.0 && area.is_finite() {
            out.push(Portal {
                vertices,
                normal: e.normalize(),
                area,
                centroid: (vertices[0] + vertices[1] + vertices[2]) / 3.0,
            });
        }
    }
    let mut out = Vec::new();
    for t in &scene.triangles {
        if matches!(
            scene.material_of(t.surface).kind,
            Kind::Glass { thin: true, .. }
        ) {
            push(&mut out, t.vertices);
        }
    }
    let panes = out.len();
    // Edges used by one triangle only (corners compared by their bits).
    let key = |v: Vec3| (v + Vec3::ZERO).to_array().map(f32::to_bits);
    let mut uses: HashMap<([u32; 3], [u32; 3]), u32> = HashMap::new();
    for t in &scene.triangles {
        for i in 0..3 {
            let (a, b) = (key(t.vertices[i]), key(t.vertices[(i + 1) % 3]));
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut next: HashMap<[u32; 3], Vec<[u32; 3]>> = HashMap::new();
    let mut position: HashMap<[u32; 3], Vec3> = HashMap::new();
    for t in &scene.triangles {
        for v in t.vertices {
            position.insert(key(v), v);
        }
    }
    let mut boundary: Vec<_> = uses
        .into_iter()
        .filter(|&(_, n)| n == 1)
        .map(|(e, _)| e)
        .collect();
    // A fixed order: the loops, and so the portals, do not depend on the hash map's.
    boundary.sort_unstable();
    for &(a, b) in &boundary {
        next.entry(a).or_default().push(b);
        next.entry(b).or_default().push(a);
    }
    let mut starts: Vec<[u32; 3]> = next.keys().copied().collect();
    starts.sort_unstable();
    for start in starts {
        // Walk a loop, taking each boundary edge once.
        let mut ring = vec![start];
        let mut at = start;
        while let Some(to) = next.get_mut(&at).and_then(Vec::pop) {
            if let Some(back) = next.get_mut(&to) {
                if let Some(i) = back.iter().position(|&v| v == at) {
                    back.swap_remove(i);
                }
            }
            if to == start {
                break;
            }
            ring.push(to);
            at = to;
        }
        if ring.len() < 3 {
            continue;
        }
        let points: Vec<Vec3> = ring.iter().map(|k| position[k]).collect();
        let centroid = points.iter().sum::<Vec3>() / points.len() as f32;
        for i in 0..points.len() {
            push(
                &mut out,
                [centroid, points[i], points[(i + 1) % points.len()]],
            );
        }
    }
    // A mesh full of T-junctions (tiled walls under one large ceiling quad, say) has "holes"
    // everywhere: then the loops are dropped and only the panes kept; past the bound even
    // they are (the hemisphere's rays still find every way out).
    if out.len() > MAX_PORTALS {
        out.truncate(panes);
    }
    if out.len() > MAX_PORTALS {
        out.clear();
    }
    out
}

/// Where a ray from `origin` along unit `dir` crosses a triangle, if it does (t > 0).
fn crossing(origin: Vec3, dir: Vec3, [a, b, c]: [Vec3; 3]) -> Option<f32> {
    let (e1, e2) = (b - a, c - a);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0).then_some(t)
}

impl<'a> Entering<'a> {
    /// The scene's daylight entering, `rays` rays per receiver; `None` for a scene without
    /// daylight.
    pub(crate) fn of(scene: &'a Scene, rays: u32) -> Option<Entering<'a>> {
        let daylight = scene.daylight.as_ref()?;
        let portals = portals(scene);
        let specular = Some(Specular::of(scene)).filter(Specular::any);
        Some(Entering {
            daylight,
            portals,
            specular,
            lift: crate::visibility::lift(scene),
            far: 2.0 * scene.bounds.diagonal() + 1.0,
            rays: rays.max(1),
        })
    }

    /// Daylight irradiance at each (position, normal), receiver i drawing its rays from a seed
    /// of (`seed`, `ids[i]`); the visibility queries made.
    pub(crate) fn at(
        &self,
        vis: &dyn Visibility,
        points: &[(Vec3, Vec3)],
        ids: &[u32],
        seed: u64,
    ) -> Result<(Vec<DVec3>, u64)> {
        let (escapes, queries) = self.escapes(vis, points, ids, seed)?;
        let mut out = vec![DVec3::ZERO; points.len()];
        for e in escapes {
            out[e.receiver as usize] += e.light * self.daylight.radiance(e.dir);
        }
        Ok((out, queries))
    }

    /// The rays of [`Entering::at`] that leave the model: the irradiance at receiver r is
    /// Σ L(dir) × light over its escapes, whatever the sky's luminance L (daylight
    /// coefficients bin them by sky patch).
    pub(crate) fn escapes(
        &self,
        vis: &dyn Visibility,
        points: &[(Vec3, Vec3)],
        ids: &[u32],
        seed: u64,
    ) -> Result<(Vec<Escape>, u64)> {
        let n_rays = self.rays as usize;
        let mut dirs: Vec<Vec3> = Vec::with_capacity(points.len() * n_rays);
        // Per ray: cos θ at the receiver over the mixture's density × rays (the weight of
        // its light), 0 where it points below the receiver's horizon.
        let mut weights: Vec<f64> = Vec::with_capacity(points.len() * n_rays);
        for (&(x, n), &id) in points.iter().zip(ids) {
            let mut rng = Pcg64Mcg::seed_from_u64(side_seed(seed, id, SALT));
            self.draw(x, n, &mut rng, &mut dirs, &mut weights);
        }
        let (shares, live, queries) = self.leaving(vis, points, &dirs, &weights)?;
        let escapes = live
            .into_iter()
            .filter(|&i| shares[i] != DVec3::ZERO)
            .map(|i| Escape {
                receiver: (i / n_rays) as u32,
                dir: dirs[i],
                light: shares[i] * weights[i],
            })
            .collect();
        Ok((escapes, queries))
    }

    /// A receiver's `rays` directions (at `x`, normal `n`) and their weights, appended: some
    /// aimed at the portals in proportion to each one's weight and spread over its area, the
    /// rest cosine-weighted over the hemisphere. Both ways draw from Fibonacci lattices shifted
    /// at random per receiver (as even as a grid for any count, and unbiased); each ray's
    /// weight is cos θ over the mixture's density.
    fn draw(
        &self,
        x: Vec3,
        n: Vec3,
        rng: &mut Pcg64Mcg,
        dirs: &mut Vec<Vec3>,
        weights: &mut Vec<f64>,
    ) {
        let n_rays = self.rays as usize;
        let from = x + self.lift * n;
        // Each portal's weight: its solid angle from the receiver times the cosine there,
        // roughly (a near portal is held to its area so the weight stays finite).
        let mut solid: Vec<f64> = Vec::with_capacity(self.portals.len());
        let mut total = 0.0;
        for p in &self.portals {
            let front = p.vertices.iter().any(|&v| (v - from).dot(n) > 0.0);
            let w = if front {
                let d = p.centroid - from;
                let d2 = d.length_squared().max(p.area);
                let dir = d / d.length().max(1e-12);
                f64::from(p.area * p.normal.dot(dir).abs() * dir.dot(n).max(0.05) / d2)
            } else {
                0.0
            };
            total += w;
            solid.push(total);
        }
        let aimed = if total > 0.0 {
            (PORTAL_SHARE * n_rays as f64).round() as usize
        } else {
            0
        };
        let spread = n_rays - aimed;
        let (t, b) = n.any_orthonormal_pair();
        let shift = (rng.random::<f64>(), rng.random::<f64>());
        for i in 0..n_rays {
            let dir = if i < aimed {
                let (u1, u2) = lattice(i as u32, aimed as u32, shift);
                let pick = u1 * total;
                let j = solid.partition_point(|&c| c <= pick).min(solid.len() - 1);
                // Where in its share of the line the pick fell: the point's first coordinate,
                // so the portal's rays stay stratified over it.
                let below = if j == 0 { 0.0 } else { solid[j - 1] };
                let within = ((pick - below) / (solid[j] - below)).clamp(0.0, 1.0);
                let p = &self.portals[j];
                let at = crate::sampling::triangles::in_triangle(p.vertices, within, u2);
                (at - from).normalize_or_zero()
            } else {
                // Cosine-weighted over the receiver's hemisphere.
                let (u, v) = lattice((i - aimed) as u32, spread as u32, shift);
                let phi = std::f64::consts::TAU * v;
                let r = u.sqrt();
                (t * (r * phi.cos()) as f32
                    + b * (r * phi.sin()) as f32
                    + n * (1.0 - u).max(0.0).sqrt() as f32)
                    .normalize_or_zero()
            };
            let cos = f64::from(dir.dot(n));
            let weight = if cos > 0.0 {
                let density = spread as f64 * cos / std::f64::consts::PI
                    + aimed as f64 * self.portal_pdf(from, dir, &solid, total, aimed);
                if density > 0.0 {
                    cos / density
                } else {
                    0.0
                }
            } else {
                0.0
            };
            dirs.push(dir);
            weights.push(weight);
        }
    }

    /// The density of drawing `dir` from `from` by way of the portals (cumulative weights
    /// `solid`, summing to `total`), where any ray is aimed at them.
    fn portal_pdf(&self, from: Vec3, dir: Vec3, solid: &[f64], total: f64, aimed: usize) -> f64 {
        let mut portal_pdf = 0.0;
        if aimed > 0 {
            let mut below = 0.0;
            for (p, &c) in self.portals.iter().zip(solid) {
                let w = c - below;
                below = c;
                if w <= 0.0 {
                    continue;
                }
                if let Some(t) = crossing(from, dir, p.vertices) {
                    let cos_p = f64::from(p.normal.dot(dir).abs()).max(1e-9);
                    portal_pdf +=
                        w / total * f64::from(t) * f64::from(t) / (f64::from(p.area) * cos_p);
                }
            }
        }
        portal_pdf
    }

    /// Which of the rays (weighted, those of weight 0 left out) leave the model, and what
    /// glass passes of each: per ray its share, the rays traced, and the queries.
    fn leaving(
        &self,
        vis: &dyn Visibility,
        points: &[(Vec3, Vec3)],
        dirs: &[Vec3],
        weights: &[f64],
    ) -> Result<(Vec<DVec3>, Vec<usize>, u64)> {
        let n_rays = self.rays as usize;
        let mut shares = vec![DVec3::ZERO; dirs.len()];
        let mut queries = 0;
        let live: Vec<usize> = (0..dirs.len()).filter(|&i| weights[i] > 0.0).collect();
        let from_of = |i: usize| {
            let (x, n) = points[i / n_rays];
            x + self.lift * n
        };
        match &self.specular {
            Some(spec) => {
                let paths: Vec<LightPath> = live
                    .iter()
                    .map(|&i| LightPath {
                        from: from_of(i),
                        to: from_of(i) + dirs[i] * self.far,
                        chain: &[],
                    })
                    .collect();
                let mut out = vec![DVec3::ZERO; paths.len()];
                queries += shadow::arriving(spec, vis, self.lift, &paths, &mut out)?;
                for (&i, s) in live.iter().zip(out) {
                    shares[i] = s;
                }
            }
            None => {
                // Rays, not segments: a segment this long ignores hits within 10⁻⁵ of its
                // length of its start, and a sample in a corner lies nearer than that to the
                // next wall (light leaked into a closed box that way).
                let rays: Vec<Ray> = live
                    .iter()
                    .map(|&i| Ray {
                        origin: from_of(i),
                        dir: dirs[i],
                        t_min: 0.0,
                        t_max: self.far,
                    })
                    .collect();
                let mut hits = vec![None; rays.len()];
                vis.intersect(&rays, &mut hits)?;
                queries += rays.len() as u64;
                for (&i, hit) in live.iter().zip(hits) {
                    shares[i] = if hit.is_some() {
                        DVec3::ZERO
                    } else {
                        DVec3::ONE
                    };
                }
            }
        }
        Ok((shares, live, queries))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit box without its top (+y) face, faces inward, corners shared between faces by
    /// position only (each face its own four vertices, as OBJ exporters write them).
    fn open_box() -> Scene {
        use crate::scene::{Camera, Material, Mesh, SceneParts, SolverDefaults};
        let v = Vec3::new;
        let faces = [
            [v(0., 0., 0.), v(0., 0., 1.), v(1., 0., 1.), v(1., 0., 0.)],
            [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
            [v(0., 0., 1.), v(0., 1., 1.), v(1., 1., 1.), v(1., 0., 1.)],
            [v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)],
            [v(1., 0., 0.), v(1., 0., 1.), v(1., 1., 1.), v(1., 1., 0.)],
        ];
        let mut mesh = Mesh {
            positions: Vec::new(),
            triangles: Vec::new(),
            triangle_materials: Vec::new(),
            materials: vec![Material::diffuse("w", Vec3::splat(0.5), Vec3::ZERO)],
            texcoords: Vec::new(),
        };
        for f in faces {
            let base = mesh.positions.len() as u32;
            mesh.positions.extend(f);
            mesh.triangles
                .extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
            mesh.triangle_materials.extend([0, 0]);
        }
        let parts = SceneParts {
            mesh,
            point_lights: Vec::new(),
            camera: Camera {
                position: Vec3::splat(0.5),
                look_at: v(0.5, 0.0, 0.5),
                up: Vec3::Z,
                fov_y: 60.0,
                width: 4,
                height: 4,
            },
            two_sided: false,
            solver: SolverDefaults::default(),
        };
        Scene::from_parts("open box", parts).unwrap()
    }

    #[test]
    fn the_hole_of_an_open_box_is_its_portal() {
        // The missing top: one loop of four edges, fanned into four triangles of area 1/4
        // at height 1.
        let found = portals(&open_box());
        assert_eq!(found.len(), 4, "{found:?}");
        let area: f32 = found.iter().map(|p| p.area).sum();
        assert!((area - 1.0).abs() < 1e-6, "{area}");
        assert!(found.iter().all(|p| p.vertices.iter().all(|v| v.y == 1.0)));
    }

    #[test]
    fn a_ray_crosses_a_triangle_where_it_lies() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let t = crossing(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z, tri).unwrap();
        assert!((t - 1.0).abs() < 1e-6);
        assert!(crossing(Vec3::new(0.8, 0.8, 1.0), -Vec3::Z, tri).is_none());
        assert!(crossing(Vec3::new(0.2, 0.2, 1.0), Vec3::Z, tri).is_none());
    }
}
