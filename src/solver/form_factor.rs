//! Form factors between two samples (`docs/method.md` eq. 2 and §12, with the near field integrated), and the
//! segment whose visibility decides whether they see each other. The flat solver and the
//! cluster hierarchy's leaf links both use these, so both build the same discrete operator.
//!
//! The form factor from receiver i to shooter j is the point form cosθᵢ cosθⱼ Sⱼ / (π r²) for
//! r ≥ 4√Sⱼ; nearer, it is integrated over j's shares of the area cells, exactly (Lambert's
//! formula) for the nearest cells, so it stays finite as r → 0. A point-to-disc form
//! cosθᵢ cosθⱼ Sⱼ / (π r² + Sⱼ) for all pairs lost 18% of the inter-reflected light at the edges
//! of the furnace cube, and 2% of the form factor of perpendicular squares; the shares of all
//! samples tile the surfaces, so each receiver's form factors sum to the part of its
//! hemisphere they cover. Positions are the centroids of the samples' regions: a sample's
//! radiosity is its region's average, and near an edge the sample point can sit far from the
//! middle of its region.

use glam::Vec3;

use crate::sampling::{Samples, SurfaceMap, CELL_UNITS};
use crate::visibility::Segment;

/// Receivers nearer than this many √S of the shooter are integrated over its shares of cells.
pub(crate) const NEAR: f32 = 4.0;

/// A shooter as the form factors see it.
#[derive(Clone, Copy)]
pub(crate) struct Shooter {
    pub index: u32,
    pub centroid: Vec3,
    pub normal: Vec3,
    pub area: f32,
    /// Axes of its surface's plane (for its cells' squares).
    pub u: Vec3,
    pub v: Vec3,
}

impl Shooter {
    /// Sample j as a shooter.
    pub fn of(samples: &Samples, maps: &[SurfaceMap], j: usize) -> Shooter {
        let map = &maps[crate::sampling::surface_of(samples.side[j]) as usize];
        Shooter {
            index: j as u32,
            centroid: samples.centroid[j],
            normal: samples.normal[j],
            area: samples.area[j] as f32,
            u: map.u,
            v: map.v,
        }
    }

    /// The form factor from receiver i to this shooter's region, or `None` when the two do not
    /// face each other (then no visibility query is needed).
    pub fn factor_to(&self, samples: &Samples, i: usize) -> Option<f32> {
        let d = samples.centroid[i] - self.centroid;
        let r2 = d.length_squared();
        let cos_j = self.normal.dot(d);
        let cos_i = -samples.normal[i].dot(d);
        if cos_j <= 0.0 || cos_i <= 0.0 || r2 <= 0.0 {
            return None;
        }
        Some(if r2 < NEAR * NEAR * self.area {
            near_factor(samples, self, samples.centroid[i], samples.normal[i])
        } else {
            // Far: the point form factor (the near range already keeps r ≥ 4√S).
            cos_i * cos_j / (r2 * r2) * self.area / std::f32::consts::PI
        })
    }
}

/// The segment tested for whether samples j and i see each other: between the sample points,
/// each lifted off its surface by `lift` so that neither occludes itself.
pub(crate) fn segment(samples: &Samples, lift: f32, j: usize, i: usize) -> Segment {
    Segment {
        a: samples.position[j] + lift * samples.normal[j],
        b: samples.position[i] + lift * samples.normal[i],
    }
}

/// Form factor from a near receiver point to a shooter's region, summed over its shares of
/// the area cells (the shares of all samples tile the surfaces): exact (Lambert's formula on
/// the cell's square) for cells within two cell widths, point to point beyond.
fn near_factor(samples: &Samples, shooter: &Shooter, x: Vec3, n: Vec3) -> f32 {
    let k = shooter.index as usize;
    let half = samples
        .side
        .get(k)
        .and_then(|&side| samples.cell_half.get(side as usize))
        .copied()
        .unwrap_or(0.0);
    let mut sum = 0.0f64;
    // The stored units are the fraction of the cell itself: no area to divide back out.
    for (c, units) in samples.shares.of(k) {
        let cell = &samples.cells[c as usize];
        let d = x - cell.centroid;
        let r2 = d.length_squared();
        let cos_j = shooter.normal.dot(d);
        if cos_j <= 0.0 {
            continue;
        }
        let fraction = f64::from(units) / f64::from(CELL_UNITS);
        if r2 < 16.0 * half * half {
            let h = 0.5 * cell.area.sqrt();
            let (u, v) = (shooter.u * h, shooter.v * h);
            let c = cell.centroid;
            let square = [c - u - v, c + u - v, c + u + v, c - u + v];
            sum += fraction * crate::light::convex_polygon_irradiance(&square, x, n)
                / std::f64::consts::PI;
        } else {
            let cos_i = -n.dot(d);
            if cos_i > 0.0 {
                let share = fraction * f64::from(cell.area);
                sum += f64::from(cos_i * cos_j / (r2 * r2) / std::f32::consts::PI) * share;
            }
        }
    }
    sum as f32
}
