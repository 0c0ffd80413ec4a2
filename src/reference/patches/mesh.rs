//! Patches: a regular grid of square cells over each planar surface, clipped to its triangles.
//! A patch is the part of one cell on one reflecting side of one surface.

use glam::{DVec2, DVec3, Vec2, Vec3};

use crate::scene::Scene;

/// One patch: the part of a grid cell inside its surface, seen from one side.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Patch {
    /// Centroid of the clipped cell.
    pub centre: Vec3,
    /// The side's unit normal.
    pub normal: Vec3,
    /// Area of the clipped cell.
    pub area: f64,
    /// Reflectance of the side.
    pub kd: DVec3,
    /// Radiosity the side emits (π·Ke on an emitter's front).
    pub emitted: DVec3,
    /// The surface it lies on.
    pub surface: u32,
}

/// One surface's grid: its plane frame and, per cell, its patch on each side.
#[derive(Clone, Debug)]
pub(crate) struct Grid {
    /// A point of the plane and two unit axes in it.
    pub origin: Vec3,
    pub u: Vec3,
    pub v: Vec3,
    /// Cells along u and v.
    pub cells: [usize; 2],
    /// Per cell (row-major, u fastest) and side (front, back): its patch, or `u32::MAX`.
    pub patch: Vec<[u32; 2]>,
}

/// No patch in this cell on this side.
pub(crate) const NONE: u32 = u32::MAX;

/// Cells clipped to less than this share of a whole cell are dropped: their centroids are ill
/// placed and their light is carried by their neighbours' interpolation.
const MIN_SHARE: f64 = 1e-6;

/// The patches of a scene, and the grids that find them.
pub(crate) struct Mesh {
    pub patches: Vec<Patch>,
    pub grids: Vec<Grid>,
    pub size: f32,
}

/// Two unit axes perpendicular to `n`, chosen the same way for any surface with that normal.
fn frame(n: Vec3) -> (Vec3, Vec3) {
    let a = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let u = (a - n * n.dot(a)).normalize();
    (u, n.cross(u))
}

/// How many patches a patch size makes, counting both sides of two-sided surfaces, found
/// from areas (no meshing): cells cover at least the surfaces' area.
pub(crate) fn estimate(scene: &Scene, size: f32) -> f64 {
    let cell = f64::from(size) * f64::from(size);
    scene
        .surfaces
        .iter()
        .map(|s| {
            let sides = if s.two_sided { 2.0 } else { 1.0 };
            sides * (s.area / cell).ceil()
        })
        .sum()
}

/// Cells the grids of all surfaces would hold (each surface's bounding box in its plane, in
/// cells of side `size`), in floating point so no count overflows.
pub(crate) fn grid_cells(scene: &Scene, size: f32) -> f64 {
    let h = f64::from(size);
    scene
        .surfaces
        .iter()
        .map(|surface| {
            let (u, v) = frame(surface.normal);
            let triangles =
                &scene.triangles[surface.triangles.start as usize..surface.triangles.end as usize];
            let (mut lo, mut hi) = (DVec2::splat(f64::MAX), DVec2::splat(f64::MIN));
            for t in triangles {
                for &p in &t.vertices {
                    let q = DVec2::new(p.dot(u).into(), p.dot(v).into());
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
            }
            if triangles.is_empty() {
                0.0
            } else {
                ((hi.x - lo.x) / h).ceil().max(1.0) * ((hi.y - lo.y) / h).ceil().max(1.0)
            }
        })
        .sum()
}

/// Meshes every surface that reflects or emits into patches of side `size`.
pub(crate) fn mesh(scene: &Scene, size: f32) -> Mesh {
    let h = f64::from(size);
    let mut patches = Vec::new();
    let mut grids = Vec::with_capacity(scene.surfaces.len());
    for (s, surface) in scene.surfaces.iter().enumerate() {
        let material = scene.material_of(s as u32);
        let (u, v) = frame(surface.normal);
        let triangles =
            &scene.triangles[surface.triangles.start as usize..surface.triangles.end as usize];
        let origin = triangles.first().map_or(Vec3::ZERO, |t| t.vertices[0]);
        let project = |p: Vec3| {
            let d = (p - origin).as_dvec3();
            DVec2::new(d.dot(u.as_dvec3()), d.dot(v.as_dvec3()))
        };
        let (mut lo, mut hi) = (DVec2::splat(f64::MAX), DVec2::splat(f64::MIN));
        for t in triangles {
            for &p in &t.vertices {
                let q = project(p);
                lo = lo.min(q);
                hi = hi.max(q);
            }
        }
        let reflects = material.reflects_diffusely();
        let emits = material.is_emitter();
        if triangles.is_empty() || !(reflects || emits) {
            grids.push(Grid {
                origin,
                u,
                v,
                cells: [0, 0],
                patch: Vec::new(),
            });
            continue;
        }
        let cells = [
            (((hi.x - lo.x) / h).ceil() as usize).max(1),
            (((hi.y - lo.y) / h).ceil() as usize).max(1),
        ];
        // Area and area-weighted centroid (in plane coordinates) of each cell's clipped part.
        let mut area = vec![0.0f64; cells[0] * cells[1]];
        let mut moment = vec![DVec2::ZERO; cells[0] * cells[1]];
        for t in triangles {
            let q = t.vertices.map(project);
            let (tlo, thi) = (q[0].min(q[1]).min(q[2]), q[0].max(q[1]).max(q[2]));
            let c0 = ((tlo - lo) / h).floor().max(DVec2::ZERO);
            let c1 = ((thi - lo) / h).ceil();
            for cy in c0.y as usize..(c1.y as usize).min(cells[1]) {
                for cx in c0.x as usize..(c1.x as usize).min(cells[0]) {
                    let min = lo + DVec2::new(cx as f64, cy as f64) * h;
                    let (a, m) = clipped_area_moment(&q, min, min + DVec2::splat(h));
                    area[cy * cells[0] + cx] += a;
                    moment[cy * cells[0] + cx] += m;
                }
            }
        }
        // The grid's origin moves to the lower corner, so cell (i, j) spans [i, i+1)·h along u.
        let corner = origin + (u.as_dvec3() * lo.x + v.as_dvec3() * lo.y).as_vec3();
        let mut patch = vec![[NONE; 2]; cells[0] * cells[1]];
        let sides: &[(usize, f32)] = if surface.two_sided {
            &[(0, 1.0), (1, -1.0)]
        } else {
            &[(0, 1.0)]
        };
        for (c, (&a, &m)) in area.iter().zip(&moment).enumerate() {
            if a < MIN_SHARE * h * h {
                continue;
            }
            let centroid = m / a;
            let centre = origin + (u.as_dvec3() * centroid.x + v.as_dvec3() * centroid.y).as_vec3();
            for &(side, sign) in sides {
                patch[c][side] = patches.len() as u32;
                patches.push(Patch {
                    centre,
                    normal: surface.normal * sign,
                    area: a,
                    kd: material.kd.as_dvec3(),
                    emitted: if side == 0 {
                        material.ke.as_dvec3() * std::f64::consts::PI
                    } else {
                        DVec3::ZERO
                    },
                    surface: s as u32,
                });
            }
        }
        grids.push(Grid {
            origin: corner,
            u,
            v,
            cells,
            patch,
        });
    }
    Mesh {
        patches,
        grids,
        size,
    }
}

/// Area and first moment of a triangle (plane coordinates) clipped to an axis-aligned box.
fn clipped_area_moment(t: &[DVec2; 3], min: DVec2, max: DVec2) -> (f64, DVec2) {
    let mut poly: Vec<DVec2> = t.to_vec();
    // Sutherland–Hodgman against the box's four sides: inside when `sign·(p[axis] − edge) ≥ 0`.
    for (axis, edge, sign) in [
        (0, min.x, 1.0),
        (0, max.x, -1.0),
        (1, min.y, 1.0),
        (1, max.y, -1.0),
    ] {
        if poly.is_empty() {
            break;
        }
        let inside = |p: DVec2| sign * (p[axis] - edge) >= 0.0;
        let mut out = Vec::with_capacity(poly.len() + 2);
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            let (ia, ib) = (inside(a), inside(b));
            if ia {
                out.push(a);
            }
            if ia != ib {
                let f = (edge - a[axis]) / (b[axis] - a[axis]);
                out.push(a + (b - a) * f);
            }
        }
        poly = out;
    }
    if poly.len() < 3 {
        return (0.0, DVec2::ZERO);
    }
    // Shoelace: signed area and centroid moment; the triangle's winding in the plane frame
    // follows the surface normal (u × v = n), so areas come out positive.
    let (mut a2, mut m) = (0.0, DVec2::ZERO);
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let cross = p.x * q.y - q.x * p.y;
        a2 += cross;
        m += (p + q) * cross;
    }
    let area = a2 / 2.0;
    // Moment = area × centroid = Σ (p + q)·cross / 6.
    (area.abs(), m / 6.0 * area.signum())
}

/// Where a point of a surface falls in its grid: the cell-centre lattice coordinates
/// ((u, v) / h − ½), so integer values sit at cell centres.
pub(crate) fn lattice(grid: &Grid, size: f32, p: Vec3) -> Vec2 {
    let d = p - grid.origin;
    Vec2::new(d.dot(grid.u), d.dot(grid.v)) / size - Vec2::splat(0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_keeps_area_and_centroid() {
        let t = [
            DVec2::new(0.0, 0.0),
            DVec2::new(2.0, 0.0),
            DVec2::new(0.0, 2.0),
        ];
        // Whole triangle inside: area 2, centroid (2/3, 2/3).
        let (a, m) = clipped_area_moment(&t, DVec2::splat(-1.0), DVec2::splat(3.0));
        assert!((a - 2.0).abs() < 1e-12);
        assert!((m / a - DVec2::splat(2.0 / 3.0)).length() < 1e-12);
        // The unit square at the origin lies wholly under the hypotenuse x + y = 2.
        let (a, m) = clipped_area_moment(&t, DVec2::ZERO, DVec2::ONE);
        assert!((a - 1.0).abs() < 1e-12);
        assert!((m / a - DVec2::splat(0.5)).length() < 1e-12);
        // The square [1,2]² touches the triangle only at the point (1, 1).
        let (a, _) = clipped_area_moment(&t, DVec2::ONE, DVec2::splat(2.0));
        assert!(a.abs() < 1e-12);
        // The square [0,1]×[1,2]: the triangle (0,1),(1,1),(0,2), area ½, centroid (1/3, 4/3).
        let (a, m) = clipped_area_moment(&t, DVec2::new(0.0, 1.0), DVec2::new(1.0, 2.0));
        assert!((a - 0.5).abs() < 1e-12);
        assert!((m / a - DVec2::new(1.0 / 3.0, 4.0 / 3.0)).length() < 1e-12);
        // Clockwise winding gives the same.
        let r = [t[0], t[2], t[1]];
        let (a2, m2) = clipped_area_moment(&r, DVec2::new(0.0, 1.0), DVec2::new(1.0, 2.0));
        assert!((a2 - a).abs() < 1e-12 && (m2 - m).length() < 1e-12);
    }
}
