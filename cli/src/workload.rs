//! Query sets shaped like the solver's and the renderer's, for `bench-vis`, the criterion
//! benchmark and the backends' cross-check (which include this file): segments between random
//! points of facing surface sides, and camera rays. Deterministic from a seed; written against
//! the library's public interface only.

use glam::Vec3;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use meshlight::visibility::{Ray, Segment};
use meshlight::Scene;

/// A point on a reflecting surface side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Position on the surface.
    pub position: Vec3,
    /// Unit normal of the side the point is on.
    pub normal: Vec3,
    /// The surface.
    pub surface: u32,
}

/// Draws area-uniform points on the reflecting sides of a scene (fronts, and backs of two-sided
/// surfaces).
pub struct SurfacePointSampler<'a> {
    scene: &'a Scene,
    /// (triangle, back side?) and the cumulative area up to and including it.
    sides: Vec<(u32, bool)>,
    cumulative: Vec<f64>,
}

impl<'a> SurfacePointSampler<'a> {
    /// Prepares the area table.
    pub fn new(scene: &'a Scene) -> Self {
        let mut sides = Vec::new();
        let mut cumulative = Vec::new();
        let mut total = 0.0;
        for (i, t) in scene.triangles().iter().enumerate() {
            let back = scene.surfaces()[t.surface as usize].two_sided;
            for side in [false, true].into_iter().take(if back { 2 } else { 1 }) {
                total += f64::from(t.area);
                sides.push((i as u32, side));
                cumulative.push(total);
            }
        }
        SurfacePointSampler {
            scene,
            sides,
            cumulative,
        }
    }

    /// One point.
    pub fn sample(&self, rng: &mut Pcg64Mcg) -> SurfacePoint {
        let total = *self
            .cumulative
            .last()
            .expect("a scene has at least one triangle");
        let x = rng.random::<f64>() * total;
        let k = self
            .cumulative
            .partition_point(|&c| c <= x)
            .min(self.sides.len() - 1);
        let (t, back) = self.sides[k];
        let tri = &self.scene.triangles()[t as usize];
        let (mut u, mut v) = (rng.random::<f32>(), rng.random::<f32>());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let [a, b, c] = tri.vertices;
        SurfacePoint {
            position: a + u * (b - a) + v * (c - a),
            normal: if back { -tri.normal } else { tri.normal },
            surface: tri.surface,
        }
    }
}

/// Up to `n` segments between random points of surface sides that face each other, ends lifted
/// by `meshlight::visibility::LIFT` × diagonal along their normals. Fewer come back only if facing pairs are so rare
/// that 100·n draws do not find them.
pub fn facing_segments(scene: &Scene, n: usize, seed: u64) -> Vec<Segment> {
    let sampler = SurfacePointSampler::new(scene);
    let lift = meshlight::visibility::lift(scene);
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let mut segments = Vec::with_capacity(n);
    for _ in 0..n.saturating_mul(100) {
        if segments.len() == n {
            break;
        }
        let p = sampler.sample(&mut rng);
        let q = sampler.sample(&mut rng);
        let d = q.position - p.position;
        if p.normal.dot(d) > 0.0 && q.normal.dot(-d) > 0.0 {
            segments.push(Segment {
                a: p.position + lift * p.normal,
                b: q.position + lift * q.normal,
            });
        }
    }
    segments
}

/// `n` camera rays through random points of random pixels.
pub fn camera_rays(scene: &Scene, n: usize, seed: u64) -> Vec<Ray> {
    let camera = scene.camera();
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let x = rng.random::<f32>() * camera.width as f32;
            let y = rng.random::<f32>() * camera.height as f32;
            Ray {
                origin: camera.position,
                dir: camera.direction(x, y),
                t_min: 0.0,
                t_max: f32::INFINITY,
            }
        })
        .collect()
}
