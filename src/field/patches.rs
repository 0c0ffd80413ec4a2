//! A value of the samples averaged over square patches of their side, any size, in constant
//! time: per side, a summed-area table of the samples' area-weighted values over a grid of
//! cells about a sample wide. A final-gather ray that stands for a cone of directions reads
//! the light of the patch its cone covers at a far hit (`render::gather`); read at one point,
//! a small bright region (the ceiling over a lamp) is a rare and large term, a sparkle.
//!
//! Light must not pass through a thin wall that stands on a side (a partition on a floor): on
//! such sides the samples are split into regions, neighbours joined where they see each other,
//! and each region has its own tables; a hit reads the region of its nearest sample, when it
//! sees that sample.

use glam::{DVec3, Vec2, Vec3};

use super::Field;
use crate::error::Result;
use crate::sampling::surface_of;
use crate::visibility::{Segment, Visibility};

/// Samples within this many of their radii are neighbours when regions are found.
const NEIGHBOURS: f32 = 2.5;
/// Neighbour tests asked at once.
const TESTS_AT_ONCE: usize = 1 << 18;

/// Per region of samples, the summed-area table of a per-sample value.
pub(crate) struct PatchSums {
    /// Each sample's region.
    region: Vec<u32>,
    grids: Vec<Grid>,
    /// The tables of the samples nothing hovers over, region after region: for corner (i, j)
    /// of a region's grid (row-major over (nx + 1) × (ny + 1) corners) the sums over the
    /// cells below and left of it of the samples' area × value (xyz) and area (w). Samples
    /// under a cover (`sampling::cover`: the ceiling over a panel 1 cm under it) are left out:
    /// a cone wide enough to read a patch is far wider than the slit between the cover and
    /// the side, and meets the cover, not what lies under it (read in full, the ceiling lit
    /// in the slit was a sparkle along every wall–ceiling edge).
    sums: Vec<[f64; 4]>,
}

#[derive(Clone, Copy)]
struct Grid {
    first: usize,
    nx: usize,
    ny: usize,
    min: Vec2,
    cell: f32,
}

impl Grid {
    /// The table at continuous grid coordinates (in cells from `min`), bilinear between the
    /// corners: each cell's sums spread evenly over it.
    fn at(&self, sums: &[[f64; 4]], p: Vec2) -> [f64; 4] {
        let q = ((p - self.min) / self.cell)
            .clamp(Vec2::ZERO, Vec2::new(self.nx as f32, self.ny as f32));
        let (i, j) = (
            (q.x as usize).min(self.nx - 1),
            (q.y as usize).min(self.ny - 1),
        );
        let (fx, fy) = (f64::from(q.x) - i as f64, f64::from(q.y) - j as f64);
        let corner = |a: usize, b: usize| sums[self.first + b * (self.nx + 1) + a];
        let (c00, c10, c01, c11) = (
            corner(i, j),
            corner(i + 1, j),
            corner(i, j + 1),
            corner(i + 1, j + 1),
        );
        std::array::from_fn(|c| {
            (1.0 - fy) * ((1.0 - fx) * c00[c] + fx * c10[c])
                + fy * ((1.0 - fx) * c01[c] + fx * c11[c])
        })
    }

    /// The sums over the rectangle from `a` to `b`, and the area weight of the whole table up
    /// to `b` (the scale of its rounding).
    fn box_sum(&self, sums: &[[f64; 4]], a: Vec2, b: Vec2) -> ([f64; 4], f64) {
        let (s11, s00) = (self.at(sums, b), self.at(sums, a));
        let (s10, s01) = (
            self.at(sums, Vec2::new(b.x, a.y)),
            self.at(sums, Vec2::new(a.x, b.y)),
        );
        (
            std::array::from_fn(|c| s11[c] - s10[c] - s01[c] + s00[c]),
            s11[3].abs(),
        )
    }
}

impl PatchSums {
    /// The tables of `values` (one per sample of `field`); the regions' neighbour tests are
    /// asked of `vis`.
    pub(crate) fn new(field: &Field, values: &[DVec3], vis: &dyn Visibility) -> Result<PatchSums> {
        let s = &field.samples;
        let region = regions(field, vis)?;
        let count = region.iter().map(|&r| r as usize + 1).max().unwrap_or(0);
        let (mut lo, mut hi) = (vec![Vec2::MAX; count], vec![Vec2::MIN; count]);
        let (mut members, mut radius) = (vec![0usize; count], vec![0.0f64; count]);
        for ((&r, &uv), &d) in region.iter().zip(&s.uv).zip(&s.radius) {
            let r = r as usize;
            lo[r] = lo[r].min(uv);
            hi[r] = hi[r].max(uv);
            members[r] += 1;
            radius[r] += f64::from(d);
        }
        let mut grids = Vec::with_capacity(count);
        let mut corners = 0;
        for r in 0..count {
            let n = members[r].max(1);
            // Cells about a sample's radius wide, at most about four per sample.
            let size = (hi[r] - lo[r]).max(Vec2::splat(1e-6));
            let sparse = (size.x * size.y / (4.0 * n as f32 + 16.0)).sqrt();
            let cell = ((radius[r] / n as f64) as f32)
                .max(sparse)
                .max(size.max_element() / 4096.0);
            let nx = ((size.x / cell).ceil() as usize).max(1);
            let ny = ((size.y / cell).ceil() as usize).max(1);
            grids.push(Grid {
                first: corners,
                nx,
                ny,
                min: lo[r],
                cell,
            });
            corners += (nx + 1) * (ny + 1);
        }
        let covered = field.layout.covered();
        let mut sums = vec![[0.0f64; 4]; corners];
        for k in 0..s.len() {
            if covered.get(k).copied().unwrap_or(false) {
                continue;
            }
            let g = grids[region[k] as usize];
            let q = (s.uv[k] - g.min) / g.cell;
            let (i, j) = (
                (q.x.max(0.0) as usize).min(g.nx - 1),
                (q.y.max(0.0) as usize).min(g.ny - 1),
            );
            // Into the cell's far corner; the prefix sums below carry it on.
            let a = s.area[k];
            let v = values[k] * a;
            let e = &mut sums[g.first + (j + 1) * (g.nx + 1) + i + 1];
            *e = [e[0] + v.x, e[1] + v.y, e[2] + v.z, e[3] + a];
        }
        for g in &grids {
            prefix_sums(g, &mut sums);
        }
        Ok(PatchSums {
            region,
            grids,
            sums,
        })
    }

    /// The cell width of sample k's region.
    pub(crate) fn cell(&self, k: u32) -> f32 {
        self.grids[self.region[k as usize] as usize].cell
    }

    /// The area-weighted mean of the value over the square of half-width `half` about the
    /// point `point` of the region of sample `k` (its nearest, in sight of it), among the
    /// samples nothing covers; none where the square holds no such sample's area.
    pub(crate) fn mean(&self, field: &Field, k: u32, point: Vec3, half: f32) -> Option<DVec3> {
        let g = self.grids[self.region[k as usize] as usize];
        let side = field.samples.side[k as usize];
        let sums = &self.sums[..];
        let uv = field.layout.maps()[surface_of(side) as usize].to_2d(point);
        let d = Vec2::splat(half);
        let (sum, total) = g.box_sum(sums, uv - d, uv + d);
        // Rounding leaves crumbs where the square misses every sample.
        (sum[3] > 1e-9 * total.max(1e-30)).then(|| DVec3::new(sum[0], sum[1], sum[2]) / sum[3])
    }
}

/// Each sample's region: on a side nothing stands on, the side's samples; on one something
/// stands on, the samples joined by chains of neighbours (within [`NEIGHBOURS`] radii) that
/// see each other along the side, so a wall standing on the side parts its two rooms.
fn regions(field: &Field, vis: &dyn Visibility) -> Result<Vec<u32>> {
    let s = &field.samples;
    let (index, obstruction) = (field.layout.index(), field.layout.obstruction());
    let mut parent: Vec<u32> = (0..s.len() as u32).collect();
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    let mut near = Vec::new();
    let mut first_of = vec![u32::MAX; 2 * field.layout.maps().len()];
    for k in 0..s.len() as u32 {
        let side = s.side[k as usize];
        if obstruction.is_obstructed(side) {
            let reach = NEIGHBOURS * s.radius[k as usize];
            index.within(s, side, s.uv[k as usize], reach, &mut near);
            // A region's table is in its side's frame: a curved piece's other sides keep their
            // own regions.
            pairs.extend(
                near.iter()
                    .filter(|&&(j, _)| j > k && s.side[j as usize] == side)
                    .map(|&(j, _)| (k, j)),
            );
        } else if first_of[side as usize] == u32::MAX {
            first_of[side as usize] = k;
        } else {
            // Nothing stands on the side: all of it is one region, without a test.
            join(&mut parent, first_of[side as usize], k);
        }
    }
    for chunk in pairs.chunks(TESTS_AT_ONCE) {
        let segments: Vec<Segment> = chunk
            .iter()
            .map(|&(a, b)| obstruction.segment(s.normal[a as usize], s.position[a as usize], s, b))
            .collect();
        let mut blocked = vec![false; segments.len()];
        vis.occluded(&segments, &mut blocked)?;
        for (&(a, b), &blocked) in chunk.iter().zip(&blocked) {
            if !blocked {
                join(&mut parent, a, b);
            }
        }
    }
    // Roots numbered in sample order.
    let mut label = vec![u32::MAX; s.len()];
    let mut next = 0u32;
    let mut region = vec![0u32; s.len()];
    for k in 0..s.len() as u32 {
        let r = root(&mut parent, k) as usize;
        if label[r] == u32::MAX {
            label[r] = next;
            next += 1;
        }
        region[k as usize] = label[r];
    }
    Ok(region)
}

/// Joins the sets of a and b; the smaller root roots both, so the labels do not depend on the
/// order of joins.
fn join(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (root(parent, a), root(parent, b));
    parent[ra.max(rb) as usize] = ra.min(rb);
}

/// The root of k's set, halving the path on the way.
fn root(parent: &mut [u32], mut k: u32) -> u32 {
    while parent[k as usize] != k {
        let up = parent[parent[k as usize] as usize];
        parent[k as usize] = up;
        k = up;
    }
    k
}

/// Turns a region's deposits (each cell's sums at its far corner) into its summed-area table.
fn prefix_sums(g: &Grid, table: &mut [[f64; 4]]) {
    let row = g.nx + 1;
    for j in 1..=g.ny {
        for i in 1..=g.nx {
            let at = g.first + j * row + i;
            let (left, below, diagonal) = (table[at - 1], table[at - row], table[at - row - 1]);
            for c in 0..4 {
                table[at][c] += left[c] + below[c] - diagonal[c];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_reads_the_area_weighted_mean_of_the_samples_it_holds_whole() {
        // Two samples in separate cells of a unit grid: a box holding one cell whole reads its
        // sample's value; a box holding both their area-weighted mean; one holding none, none.
        let g = Grid {
            first: 0,
            nx: 4,
            ny: 1,
            min: Vec2::ZERO,
            cell: 1.0,
        };
        // Sample of area 1, value 2 in cell 0; area 3, value 6 in cell 2, deposited at their
        // cells' far corners as `new` does.
        let mut sums = vec![[0.0f64; 4]; 5 * 2];
        sums[5 + 1] = [2.0, 2.0, 2.0, 1.0];
        sums[5 + 3] = [18.0, 18.0, 18.0, 3.0];
        prefix_sums(&g, &mut sums);
        let mean = |a: Vec2, b: Vec2| {
            let (sum, _) = g.box_sum(&sums, a, b);
            (sum[0] / sum[3], sum[3])
        };
        assert!((mean(Vec2::new(0.0, 0.0), Vec2::new(1.0, 1.0)).0 - 2.0).abs() < 1e-12);
        assert!((mean(Vec2::new(0.0, 0.0), Vec2::new(4.0, 1.0)).0 - 5.0).abs() < 1e-12);
        // Half of cell 2 holds half of its sample's area.
        assert!((mean(Vec2::new(2.5, 0.0), Vec2::new(4.0, 1.0)).1 - 1.5).abs() < 1e-12);
        assert!(mean(Vec2::new(3.0, 0.0), Vec2::new(4.0, 1.0)).1.abs() < 1e-12);
    }
}
