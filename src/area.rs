//! Representative areas (method.md §4, eqs. 4-6): each surface side is cut by a regular grid of
//! small cells (each cell clipped exactly to the surface's triangles); a cell's area is split
//! among the samples of the same side within R of its centroid with weights
//! w(d/R) = exp(−α d/R), normalised (eq. 5), and a sample's area is the sum of its shares
//! (eq. 6). Every side's samples carry exactly the side's area. Where other geometry stands on
//! a side (a wall on a continuous floor), a cell shares its area only with samples it sees
//! along the side, so no sample takes area from behind a thin wall.
//!
//! Decision: R = 2D of the sample nearest the cell. With the initial samples D = ε, so this is
//! the paper's R = 2ε; where adaptive rounds shrank D, the cell is shared among the local,
//! denser samples instead of hundreds of samples within 2ε (which would smear areas and cost
//! O(samples²) per cell).

use glam::{DVec3, Vec2};

use crate::error::Result;
use crate::sampling::{surface_of, AreaCell, Obstruction, Samples, SideIndex, SurfaceMap};
use crate::visibility::Visibility;

/// What the area computation did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AreaStats {
    /// Non-empty cells.
    pub cells: usize,
    /// Cells with no visible sample within R, given to the nearest one.
    pub orphan_cells: usize,
    /// Visibility queries (cells to samples on obstructed sides).
    pub queries: u64,
}

/// Computes every sample's area `S`.
pub fn compute(
    samples: &mut Samples,
    maps: &[SurfaceMap],
    index: &SideIndex,
    obstruction: &Obstruction,
    vis: &dyn Visibility,
    epsilon: f32,
    alpha: f32,
) -> Result<AreaStats> {
    // ε bounds the cell size where a side has only initial samples.
    let mut stats = AreaStats::default();
    // Per side: the smallest radius among its samples sets the cell size.
    let sides = 2 * maps.len();
    let mut smallest = vec![f32::INFINITY; sides];
    let mut count = vec![0usize; sides];
    for (&side, &d) in samples.side.iter().zip(&samples.radius) {
        smallest[side as usize] = smallest[side as usize].min(d);
        count[side as usize] += 1;
    }
    let mut area = vec![0.0f64; samples.len()];
    // Every share, (sample, cell, area): the regions that carry the near-field form factors.
    let mut shares: Vec<(u32, u32, f32)> = Vec::new();
    let mut all_cells: Vec<AreaCell> = Vec::new();
    let mut near = Vec::new();
    let mut cells: Vec<(u64, f64, Vec2)> = Vec::new();
    for side in 0..sides {
        if count[side] == 0 {
            continue;
        }
        let map = &maps[surface_of(side as u32) as usize];
        let cell = cell_size(map, epsilon.min(smallest[side]), count[side]);
        clip_cells(map, cell, &mut cells);

        stats.cells += cells.len();
        for &(_, a, centroid) in &cells {
            let id = all_cells.len() as u32;
            all_cells.push(AreaCell {
                centroid: map.to_3d(centroid),
                area: a as f32,
                half: 0.5 * cell,
            });
            let Some(nearest) = index.nearest(samples, side as u32, centroid) else {
                continue;
            };
            let r = 2.0 * samples.radius[nearest as usize];
            index.within(samples, side as u32, centroid, r, &mut near);
            let point = map.to_3d(centroid);
            stats.queries +=
                obstruction.retain_visible(vis, maps, samples, side as u32, point, &mut near)?;
            if near.is_empty() {
                // Sealed off within R: the nearest sample it sees further out, else the nearest.
                stats.orphan_cells += 1;
                index.within(samples, side as u32, centroid, 4.0 * r, &mut near);
                near.sort_unstable_by(|x, y| x.1.total_cmp(&y.1).then(x.0.cmp(&y.0)));
                near.truncate(16);
                stats.queries += obstruction.retain_visible(
                    vis,
                    maps,
                    samples,
                    side as u32,
                    point,
                    &mut near,
                )?;
                let k = near.first().map_or(nearest, |n| n.0);
                area[k as usize] += a;
                shares.push((k, id, a as f32));
                continue;
            }
            // Ascending sample order: the sum does not depend on the grid's iteration order.
            near.sort_unstable_by_key(|&(k, _)| k);
            let weight = |d2: f32| f64::from((-alpha * d2.sqrt() / r).exp());
            let total: f64 = near.iter().map(|&(_, d2)| weight(d2)).sum();
            for &(k, d2) in &near {
                let share = a * weight(d2) / total;
                area[k as usize] += share;
                shares.push((k, id, share as f32));
            }
        }
    }
    // Group the shares by sample (stable: in cell order within each sample).
    shares.sort_by_key(|&(k, _, _)| k);
    let n = samples.len();
    samples.share_start = vec![0; n + 1];
    for &(k, _, _) in &shares {
        samples.share_start[k as usize + 1] += 1;
    }
    for k in 0..n {
        samples.share_start[k + 1] += samples.share_start[k];
    }
    samples.shares = shares.into_iter().map(|(_, c, a)| (c, a)).collect();
    samples.cells = all_cells;
    for k in 0..n {
        let mut mass = 0.0f64;
        let mut sum = DVec3::ZERO;
        for &(c, a) in samples.shares_of(k) {
            mass += f64::from(a);
            sum += f64::from(a) * samples.cells[c as usize].centroid.as_dvec3();
        }
        samples.centroid[k] = if mass > 0.0 {
            (sum / mass).as_vec3()
        } else {
            samples.position[k]
        };
    }
    samples.area = area;
    Ok(stats)
}

/// Cells a third of the smallest spacing wide, but no more than ~16 per sample of the side.
fn cell_size(map: &SurfaceMap, spacing: f32, samples: usize) -> f32 {
    let floor = (map.area() as f32 / (16.0 * samples as f32)).sqrt();
    (spacing / 3.0).max(floor).max(1e-30)
}

/// The non-empty cells of a surface: (cell key, area, centroid), sorted by key; each cell is
/// the union of the triangles' pieces inside it, clipped exactly.
fn clip_cells(map: &SurfaceMap, cell: f32, out: &mut Vec<(u64, f64, Vec2)>) {
    out.clear();
    // One column more than the bounds need: a vertex on the far edge maps to column nx - 1.
    let nx = ((map.max.x - map.min.x) / cell).floor() as u64 + 2;
    let mut pieces: Vec<(u64, f64, Vec2)> = Vec::new();
    let mut poly = Vec::with_capacity(8);
    let mut scratch = Vec::with_capacity(8);
    for t in &map.triangles {
        let lo = (t[0].min(t[1]).min(t[2]) - map.min) / cell;
        let hi = (t[0].max(t[1]).max(t[2]) - map.min) / cell;
        let (x0, y0) = (lo.x.floor().max(0.0) as u64, lo.y.floor().max(0.0) as u64);
        let (x1, y1) = (hi.x.floor().max(0.0) as u64, hi.y.floor().max(0.0) as u64);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let cmin = map.min + Vec2::new(x as f32, y as f32) * cell;
                let cmax = cmin + Vec2::splat(cell);
                poly.clear();
                poly.extend_from_slice(t);
                clip_to_box(&mut poly, &mut scratch, cmin, cmax);
                if let Some((a, c)) = area_centroid(&poly) {
                    pieces.push((y * nx + x, a, c));
                }
            }
        }
    }
    pieces.sort_unstable_by_key(|p| p.0);
    for (key, a, c) in pieces {
        match out.last_mut() {
            Some(last) if last.0 == key => {
                let total = last.1 + a;
                last.2 = (last.2 * last.1 as f32 + c * a as f32) / total as f32;
                last.1 = total;
            }
            _ => out.push((key, a, c)),
        }
    }
}

/// Sutherland–Hodgman clipping of a convex polygon to an axis-aligned box.
pub(crate) fn clip_to_box(poly: &mut Vec<Vec2>, scratch: &mut Vec<Vec2>, lo: Vec2, hi: Vec2) {
    for (axis, bound, keep_below) in [
        (0, lo.x, false),
        (0, hi.x, true),
        (1, lo.y, false),
        (1, hi.y, true),
    ] {
        scratch.clear();
        let inside = |p: Vec2| {
            if keep_below {
                p[axis] <= bound
            } else {
                p[axis] >= bound
            }
        };
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            let (ia, ib) = (inside(a), inside(b));
            if ia {
                scratch.push(a);
            }
            if ia != ib {
                let t = (bound - a[axis]) / (b[axis] - a[axis]);
                scratch.push(a + (b - a) * t);
            }
        }
        std::mem::swap(poly, scratch);
        if poly.len() < 3 {
            poly.clear();
            return;
        }
    }
}

/// Area and centroid of a simple polygon (shoelace), if it has an area.
fn area_centroid(poly: &[Vec2]) -> Option<(f64, Vec2)> {
    if poly.len() < 3 {
        return None;
    }
    let o = poly[0];
    let (mut twice, mut cx, mut cy) = (0.0f64, 0.0f64, 0.0f64);
    for i in 1..poly.len() - 1 {
        let (a, b) = ((poly[i] - o).as_dvec2(), (poly[i + 1] - o).as_dvec2());
        let cross = a.perp_dot(b);
        twice += cross;
        cx += cross * (a.x + b.x) / 3.0;
        cy += cross * (a.y + b.y) / 3.0;
    }
    if twice.abs() <= 0.0 {
        return None;
    }
    let centroid = o + Vec2::new((cx / twice) as f32, (cy / twice) as f32);
    Some((0.5 * twice.abs(), centroid))
}

/// Area carried by each side's samples minus the side's area, relative (0 when conserved).
pub fn conservation_error(samples: &Samples, maps: &[SurfaceMap]) -> f64 {
    let per_side = samples.area_per_side(2 * maps.len());
    per_side
        .iter()
        .enumerate()
        .filter(|(_, &a)| a > 0.0)
        .map(|(side, &a)| {
            let expected = maps[surface_of(side as u32) as usize].area();
            (a - expected).abs() / expected
        })
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_a_triangle_into_cells_keeps_its_area() {
        let t = [
            Vec2::new(0.05, 0.1),
            Vec2::new(2.3, 0.4),
            Vec2::new(0.7, 1.9),
        ];
        let poly_area = 0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0]).abs() as f64;
        let mut total = 0.0;
        let mut poly = Vec::new();
        let mut scratch = Vec::new();
        for x in 0..10 {
            for y in 0..10 {
                poly.clear();
                poly.extend_from_slice(&t);
                let lo = Vec2::new(x as f32, y as f32) * 0.25;
                clip_to_box(&mut poly, &mut scratch, lo, lo + Vec2::splat(0.25));
                if let Some((a, c)) = area_centroid(&poly) {
                    assert!(c.cmpge(lo).all() && c.cmple(lo + Vec2::splat(0.25)).all());
                    total += a;
                }
            }
        }
        assert!(
            (total - poly_area).abs() < 1e-5 * poly_area,
            "{total} vs {poly_area}"
        );
    }
}
