//! Each planar surface seen in 2D: an orthonormal frame in its plane, its triangles in that
//! frame, and a bucket grid to tell whether a point lies on the surface. Poisson-disk sampling,
//! representative areas and adaptive sampling all work in these 2D coordinates.

use glam::{Vec2, Vec3};

use crate::scene::Scene;

/// A surface in its own plane.
#[derive(Clone, Debug)]
pub struct SurfaceMap {
    /// A point of the plane: the frame's origin.
    pub origin: Vec3,
    /// First in-plane axis.
    pub u: Vec3,
    /// Second in-plane axis (normal × u).
    pub v: Vec3,
    /// Unit normal of the front side.
    pub normal: Vec3,
    /// The triangles in (u, v) coordinates.
    pub triangles: Vec<[Vec2; 3]>,
    /// Area of each triangle, and the cumulative areas for area-uniform picks.
    cumulative: Vec<f64>,
    /// 2D bounds.
    pub min: Vec2,
    /// 2D bounds.
    pub max: Vec2,
    /// Bucket grid over the bounds: the triangles overlapping each cell.
    cell: f32,
    nx: usize,
    ny: usize,
    starts: Vec<u32>,
    entries: Vec<u32>,
}

impl SurfaceMap {
    /// Maps every surface of a scene.
    pub fn all(scene: &Scene) -> Vec<SurfaceMap> {
        scene
            .surfaces
            .iter()
            .map(|s| SurfaceMap::new(scene, s))
            .collect()
    }

    fn new(scene: &Scene, surface: &crate::scene::Surface) -> SurfaceMap {
        let tris =
            &scene.triangles[surface.triangles.start as usize..surface.triangles.end as usize];
        let normal = surface.normal;
        let first = tris[0].vertices;
        // The plane through the surface (offset along the normal), seen from the first vertex.
        let origin = first[0] + (surface.offset - normal.dot(first[0])) * normal;
        let e = first[1] - first[0];
        let u = (e - normal * normal.dot(e)).normalize_or(normal.any_orthonormal_vector());
        let v = normal.cross(u);
        let to2 = |p: Vec3| Vec2::new((p - origin).dot(u), (p - origin).dot(v));
        let triangles: Vec<[Vec2; 3]> = tris.iter().map(|t| t.vertices.map(to2)).collect();
        let mut cumulative = Vec::with_capacity(triangles.len());
        let mut total = 0.0;
        for t in &triangles {
            total += f64::from(area2(t));
            cumulative.push(total);
        }
        let (min, max) = triangles.iter().flatten().fold(
            (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let mut map = SurfaceMap {
            origin,
            u,
            v,
            normal,
            triangles,
            cumulative,
            min,
            max,
            cell: 1.0,
            nx: 1,
            ny: 1,
            starts: Vec::new(),
            entries: Vec::new(),
        };
        map.bucket();
        map
    }

    /// Buckets triangles into a grid of about as many cells as triangles.
    fn bucket(&mut self) {
        let size = (self.max - self.min).max(Vec2::splat(1e-30));
        let n = self.triangles.len().max(1) as f32;
        self.cell = (size.x * size.y / n)
            .sqrt()
            .max(size.max_element() / 1024.0)
            .max(1e-30);
        self.nx = ((size.x / self.cell).ceil() as usize).clamp(1, 1024);
        self.ny = ((size.y / self.cell).ceil() as usize).clamp(1, 1024);
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for (i, t) in self.triangles.iter().enumerate() {
            let lo = t[0].min(t[1]).min(t[2]);
            let hi = t[0].max(t[1]).max(t[2]);
            let (x0, y0) = self.cell_of(lo);
            let (x1, y1) = self.cell_of(hi);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    pairs.push(((y * self.nx + x) as u32, i as u32));
                }
            }
        }
        pairs.sort_unstable();
        self.starts = vec![0; self.nx * self.ny + 1];
        for &(c, _) in &pairs {
            self.starts[c as usize + 1] += 1;
        }
        for c in 0..self.nx * self.ny {
            self.starts[c + 1] += self.starts[c];
        }
        self.entries = pairs.into_iter().map(|(_, t)| t).collect();
    }

    fn cell_of(&self, p: Vec2) -> (usize, usize) {
        let q = (p - self.min) / self.cell;
        (
            (q.x.max(0.0) as usize).min(self.nx - 1),
            (q.y.max(0.0) as usize).min(self.ny - 1),
        )
    }

    /// 2D coordinates of a point of the plane.
    pub fn to_2d(&self, p: Vec3) -> Vec2 {
        Vec2::new((p - self.origin).dot(self.u), (p - self.origin).dot(self.v))
    }

    /// The 3D point of 2D coordinates.
    pub fn to_3d(&self, q: Vec2) -> Vec3 {
        self.origin + q.x * self.u + q.y * self.v
    }

    /// Total area (as the 2D triangles give it).
    pub fn area(&self) -> f64 {
        self.cumulative.last().copied().unwrap_or(0.0)
    }

    /// The point at area fraction `x` ∈ [0, 1) with in-triangle coordinates (r1, r2) ∈ [0, 1)².
    pub fn point_at(&self, x: f64, r1: f32, r2: f32) -> Vec2 {
        let target = x * self.area();
        let i = self
            .cumulative
            .partition_point(|&c| c <= target)
            .min(self.triangles.len() - 1);
        let [a, b, c] = self.triangles[i];
        let s = r1.sqrt();
        a * (1.0 - s) + b * (s * (1.0 - r2)) + c * (s * r2)
    }

    /// Whether a 2D point lies on the surface (inside one of its triangles, edges included).
    pub fn contains(&self, p: Vec2) -> bool {
        self.triangle_at(p).is_some()
    }

    /// The triangle (index among the surface's) a 2D point lies in, edges included.
    pub fn triangle_at(&self, p: Vec2) -> Option<usize> {
        if p.cmplt(self.min).any() || p.cmpgt(self.max).any() {
            return None;
        }
        let (x, y) = self.cell_of(p);
        let c = y * self.nx + x;
        self.entries[self.starts[c] as usize..self.starts[c + 1] as usize]
            .iter()
            .find(|&&t| inside(&self.triangles[t as usize], p))
            .map(|&t| t as usize)
    }

    /// The triangle whose centre is nearest a 2D point (for points just off the surface).
    pub fn nearest_triangle(&self, p: Vec2) -> usize {
        let distance = |t: &[Vec2; 3]| ((t[0] + t[1] + t[2]) / 3.0).distance_squared(p);
        (0..self.triangles.len())
            .min_by(|&a, &b| distance(&self.triangles[a]).total_cmp(&distance(&self.triangles[b])))
            .unwrap_or(0)
    }
}

/// Area of a 2D triangle (unsigned).
pub fn area2(t: &[Vec2; 3]) -> f32 {
    0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0]).abs()
}

/// Whether p is inside triangle t (either winding), edges included with a small tolerance.
fn inside(t: &[Vec2; 3], p: Vec2) -> bool {
    let d0 = (t[1] - t[0]).perp_dot(p - t[0]);
    let d1 = (t[2] - t[1]).perp_dot(p - t[1]);
    let d2 = (t[0] - t[2]).perp_dot(p - t[2]);
    let scale = (t[1] - t[0]).perp_dot(t[2] - t[0]).abs() * 1e-6;
    (d0 >= -scale && d1 >= -scale && d2 >= -scale) || (d0 <= scale && d1 <= scale && d2 <= scale)
}
