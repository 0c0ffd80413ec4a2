//! Interpolation of the samples at surface points (`docs/method.md` §7 and §18): the samples of
//! the point's side whose kernels reach it, weighted by the compactly supported kernel
//! (1 − d²/r²)³ with r = 2D, among those in sight of it (a sample behind a wall on the same
//! continuous side never contributes) and covered as the point is (`sampling::cover`), if any
//! such, and turned into the weights of a local-linear fit ([`local_linear`]); where no kernel
//! reaches a point in sight, its nearest visible sample. Shared by the camera's hits, the
//! points specular chains end at, and the grids.

use glam::{DVec2, Vec2, Vec3};

use super::Field;
use crate::error::Result;
use crate::sampling::{cover, is_back, surface_of, Obstruction, Side};
use crate::scene::Scene;
use crate::visibility::{Segment, Visibility};

/// Kernel support: a sample reaches this many of its radii D.
pub(crate) const SUPPORT: f32 = 2.0;

/// A point to interpolate at.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Site {
    pub point: Vec3,
    pub side: Side,
    /// The side's normal.
    pub normal: Vec3,
    /// Whether something hovers over it (`sampling::cover`).
    pub covered: bool,
}

impl Site {
    /// The site at `point` on `side` (whose normal is `normal`).
    pub(crate) fn at(point: Vec3, side: Side, normal: Vec3, covered: bool) -> Site {
        Site {
            point,
            side,
            normal,
            covered,
        }
    }
}

/// What interpolation reads of a field.
pub(crate) struct Interpolator<'a> {
    field: &'a Field,
    vis: &'a dyn Visibility,
    lift: f32,
    /// Largest kernel support among each side's samples (0: the side has none).
    support: Vec<f32>,
    /// Per sample: whether nothing crosses its side's band within its kernel's support, so
    /// that any point its kernel reaches sees it along the side (no query).
    clear: Vec<bool>,
    /// Whether weights are those of a local-linear fit (see [`local_linear`]); plain kernel
    /// weights (all positive) where they enter the solve as transport.
    linear: bool,
}

impl<'a> Interpolator<'a> {
    pub(crate) fn new(scene: &'a Scene, field: &'a Field, vis: &'a dyn Visibility) -> Self {
        let s = &field.samples;
        let mut support = vec![0.0f32; 2 * scene.surfaces.len()];
        for (&side, &d) in s.side.iter().zip(&s.radius) {
            support[side as usize] = support[side as usize].max(SUPPORT * d);
        }
        // A curved piece's sides reach all its samples.
        let pieces = field.layout.pieces();
        for p in 0..pieces.len() as u32 {
            let sides = pieces.sides(p);
            let most = sides
                .iter()
                .map(|&side| support.get(side as usize).copied().unwrap_or(0.0))
                .fold(0.0f32, f32::max);
            for &side in sides {
                if let Some(r) = support.get_mut(side as usize) {
                    *r = most;
                }
            }
        }
        // A segment from a point within a kernel's support to its sample lies in the support's
        // disc: nothing crossing the band there, nothing can block it.
        let obstruction = field.layout.obstruction();
        let clear = (0..s.len())
            .map(|k| {
                let r = Vec2::splat(SUPPORT * s.radius[k]);
                !obstruction.may_block(s.side[k], s.uv[k] - r, s.uv[k] + r)
            })
            .collect();
        Interpolator {
            field,
            vis,
            lift: crate::visibility::lift(scene),
            support,
            clear,
            linear: true,
        }
    }

    /// The same, with plain (positive) kernel weights: for weights that become transport in
    /// the solve, where a negative entry could create light.
    pub(crate) fn plain(mut self) -> Self {
        self.linear = false;
        self
    }

    /// The field read.
    pub(crate) fn field(&self) -> &Field {
        self.field
    }

    /// The samples interpolated.
    pub(crate) fn samples(&self) -> &crate::sampling::Samples {
        &self.field.samples
    }

    /// The sample of the site's side nearest to it (among those covered as it is, if any),
    /// seen from it or not: the cheapest reading of the light there, for the far hits of a
    /// final gather, each a small share of its answer, where kernels and their visibility
    /// queries would cost more than the rest of the render.
    pub(crate) fn nearest(&self, site: &Site) -> Option<u32> {
        let (s, index) = (&self.field.samples, &self.field.layout.index());
        let uv = self.field.layout.maps()[surface_of(site.side) as usize].to_2d(site.point);
        index
            .nearest_where(s, site.side, uv, |k| {
                self.sample_covered(k as usize) == site.covered
            })
            .or_else(|| index.nearest(s, site.side, uv))
    }

    /// Whether a side has samples to interpolate.
    pub(crate) fn has_samples(&self, side: Side) -> bool {
        self.support.get(side as usize).is_some_and(|&r| r > 0.0)
    }

    /// Whether something hovers over each (point, side normal), one query each.
    pub(crate) fn covered(&self, points: &[(Vec3, Vec3)]) -> Result<Vec<bool>> {
        let covers: Vec<Segment> = points
            .iter()
            .map(|&(p, n)| cover::segment(p, n, self.lift, self.field.layout.epsilon()))
            .collect();
        let mut answers = vec![false; covers.len()];
        self.vis.occluded(&covers, &mut answers)?;
        Ok(answers)
    }

    /// The samples each site interpolates, with their kernel weights (not normalised), in
    /// sample order; or its nearest visible sample (weight 1); or none when it is sealed off
    /// from them all. Returns the visibility queries.
    pub(crate) fn weights(&self, sites: &[Site], out: &mut Vec<Vec<(u32, f32)>>) -> Result<u64> {
        let s = &self.field.samples;
        let mut candidates: Vec<(u32, f32)> = Vec::new();
        let mut ranges = Vec::with_capacity(sites.len());
        let mut segments = Vec::new();
        let mut near = Vec::new();
        let obstruction = self.field.layout.obstruction();
        for site in sites {
            let map = &self.field.layout.maps()[surface_of(site.side) as usize];
            let from = site.point + self.lift * site.normal;
            let uv = map.to_2d(site.point);
            let reach = self.support[site.side as usize];
            self.field
                .layout
                .index()
                .within(s, site.side, uv, reach, &mut near);
            near.sort_unstable_by_key(|&(k, _)| k);
            let start = candidates.len();
            for &(k, d2) in &near {
                let r = SUPPORT * s.radius[k as usize];
                let q = d2 / (r * r);
                if q < 1.0 {
                    candidates.push((k, (1.0 - q).powi(3)));
                    // Where nothing stands within the kernel, or across the segment's box,
                    // the sample is in sight: no query. A sample of another side lies on the
                    // same curved piece: something may stand on any side of the piece.
                    let to = s.uv[k as usize];
                    let open = if s.side[k as usize] == site.side {
                        self.clear[k as usize]
                            || !obstruction.may_block(site.side, uv.min(to), uv.max(to))
                    } else {
                        !obstruction.may_block_between(
                            self.field.layout.maps(),
                            s,
                            site.side,
                            site.point,
                            k,
                        )
                    };
                    let (to, n) = (s.position[k as usize], s.normal[k as usize]);
                    segments.push((!open).then(|| {
                        if s.side[k as usize] == site.side {
                            Segment {
                                a: from,
                                b: to + self.lift * n,
                            }
                        } else {
                            Obstruction::lifted(self.lift, site.point, site.normal, to, n)
                        }
                    }));
                }
            }
            ranges.push(start..candidates.len());
        }
        let tested: Vec<Segment> = segments.iter().flatten().copied().collect();
        let mut answers = vec![false; tested.len()];
        self.vis.occluded(&tested, &mut answers)?;
        let mut queries = tested.len() as u64;
        let mut answer = answers.into_iter();
        let blocked: Vec<bool> = segments
            .iter()
            .map(|s| s.is_some() && answer.next().unwrap_or(false))
            .collect();
        out.clear();
        let mut offsets = Vec::new();
        for (site, range) in sites.iter().zip(ranges) {
            // Samples covered as the site is; any visible one if there is none such.
            let mut chosen = Vec::new();
            for alike in [true, false] {
                for c in range.clone() {
                    let (k, w) = candidates[c];
                    if !blocked[c] && (!alike || self.sample_covered(k as usize) == site.covered) {
                        chosen.push((k, w));
                    }
                }
                if !chosen.is_empty() {
                    break;
                }
            }
            if chosen.is_empty() {
                let (nearest, q) = self.nearest_visible(site.side, site.point)?;
                queries += q;
                chosen.extend(nearest.map(|k| (k, 1.0)));
            } else if self.linear {
                let map = &self.field.layout.maps()[surface_of(site.side) as usize];
                let at = map.to_2d(site.point);
                // Each value is its region's average, which a linear field takes at the
                // region's centroid: the fit places the values there.
                offsets.clear();
                offsets.extend(chosen.iter().map(|&(k, _)| {
                    let p = s
                        .centroid
                        .get(k as usize)
                        .unwrap_or(&s.position[k as usize]);
                    (map.to_2d(*p) - at).as_dvec2()
                }));
                local_linear(&offsets, &mut chosen);
            }
            out.push(chosen);
        }
        Ok(queries)
    }

    /// Whether sample k is covered (`sampling::cover`); a solution without the flags has none.
    fn sample_covered(&self, k: usize) -> bool {
        self.field.layout.covered().get(k).copied().unwrap_or(false)
    }

    /// Fallback where no sample's kernel reaches a visible point: the nearest visible sample of
    /// the side within a growing radius, if any.
    fn nearest_visible(&self, side: Side, point: Vec3) -> Result<(Option<u32>, u64)> {
        let s = &self.field.samples;
        let surface = surface_of(side);
        let map = &self.field.layout.maps()[surface as usize];
        let normal = if is_back(side) {
            -map.normal
        } else {
            map.normal
        };
        let from = point + self.lift * normal;
        let uv = map.to_2d(point);
        let mut near = Vec::new();
        let mut queries = 0;
        let mut r = self.support[side as usize];
        for _ in 0..4 {
            r *= 2.0;
            self.field.layout.index().within(s, side, uv, r, &mut near);
            near.sort_unstable_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            near.truncate(16);
            // A sample of another side lies on the same curved piece: seen along it where
            // nothing stands on any side of the piece (a straight ray would cut a convex one).
            let obstruction = self.field.layout.obstruction();
            let maps = self.field.layout.maps();
            if let Some(&(k, _)) = near
                .iter()
                .take_while(|n| s.side[n.0 as usize] != side)
                .find(|n| !obstruction.may_block_between(maps, s, side, point, n.0))
            {
                return Ok((Some(k), queries));
            }
            let segments: Vec<Segment> = near
                .iter()
                .map(|&(k, _)| {
                    let (to, n) = (s.position[k as usize], s.normal[k as usize]);
                    if s.side[k as usize] == side {
                        Segment {
                            a: from,
                            b: to + self.lift * n,
                        }
                    } else {
                        Obstruction::lifted(self.lift, point, normal, to, n)
                    }
                })
                .collect();
            let mut blocked = vec![false; segments.len()];
            self.vis.occluded(&segments, &mut blocked)?;
            queries += segments.len() as u64;
            if let Some(i) = blocked.iter().position(|b| !b) {
                return Ok((Some(near[i].0), queries));
            }
        }
        Ok((None, queries))
    }
}

/// How far the local-linear weights may stray from an average: the sum of their magnitudes
/// is at most this (1 is a plain weighted average).
const SPREAD: f64 = 2.0;

/// Turns kernel weights into those of a local-linear fit evaluated at the point, given each
/// sample's offset from it in the side's plane: a field varying linearly over the kernels is
/// then reproduced where the samples all lie on one side of the point (near an edge or a
/// contact), where a weighted average returns the field at the samples' weighted centroid,
/// inward of the point. The weights still add up to 1; where the fit would amplify the
/// samples' differences more than [`SPREAD`] allows (samples nearly in a line, or the point
/// far outside them) it is blended toward the average just enough.
fn local_linear(offsets: &[DVec2], chosen: &mut [(u32, f32)]) {
    if chosen.len() < 3 {
        return;
    }
    let total: f64 = chosen.iter().map(|&(_, w)| f64::from(w)).sum();
    if total.is_nan() || total <= 0.0 {
        return;
    }
    let share = |w: f32| f64::from(w) / total;
    let mean: DVec2 = chosen
        .iter()
        .zip(offsets)
        .map(|(&(_, w), &d)| share(w) * d)
        .sum();
    let (mut xx, mut xy, mut yy) = (0.0, 0.0, 0.0);
    for (&(_, w), &d) in chosen.iter().zip(offsets) {
        let d = d - mean;
        xx += share(w) * d.x * d.x;
        xy += share(w) * d.x * d.y;
        yy += share(w) * d.y * d.y;
    }
    // A little ridge keeps samples in a line (a narrow strip) from an unbounded slope.
    let ridge = 1e-3 * (xx + yy);
    let (xx, yy) = (xx + ridge, yy + ridge);
    let det = xx * yy - xy * xy;
    if !(det > 0.0 && det.is_finite()) {
        return;
    }
    // The fit's value at the point: l_k = c_k (1 − mean·C⁻¹(d_k − mean)), C the weighted
    // covariance of the offsets.
    let g = DVec2::new(yy * mean.x - xy * mean.y, xx * mean.y - xy * mean.x) / det;
    let fitted = |w: f32, d: DVec2| share(w) * (1.0 - g.dot(d - mean));
    let spread: f64 = chosen
        .iter()
        .zip(offsets)
        .map(|(&(_, w), &d)| fitted(w, d).abs())
        .sum();
    if !spread.is_finite() {
        return;
    }
    let blend = if spread > SPREAD {
        (SPREAD - 1.0) / (spread - 1.0)
    } else {
        1.0
    };
    for ((_, w), &d) in chosen.iter_mut().zip(offsets) {
        *w = (blend * fitted(*w, d) + (1.0 - blend) * share(*w)) as f32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Offsets and kernel weights of samples on one side of the point (as at a surface's
    /// edge), in a deterministic scatter.
    fn one_sided() -> (Vec<DVec2>, Vec<(u32, f32)>) {
        let offsets: Vec<DVec2> = (0..12)
            .map(|i| {
                let a = 0.7 * i as f64;
                DVec2::new(0.05 + 0.3 * (a.sin() * 0.5 + 0.5), 0.4 * a.cos())
            })
            .collect();
        let weights = offsets
            .iter()
            .enumerate()
            .map(|(k, d)| (k as u32, (1.0 - d.length_squared() / 0.5).powi(3) as f32))
            .collect();
        (offsets, weights)
    }

    #[test]
    fn a_linear_field_is_reproduced_at_an_edge() {
        let (offsets, mut weights) = one_sided();
        let field = |d: DVec2| 2.0 + 3.0 * d.x - 1.5 * d.y;
        let average: f64 = {
            let t: f64 = weights.iter().map(|&(_, w)| f64::from(w)).sum();
            weights
                .iter()
                .zip(&offsets)
                .map(|(&(_, w), &d)| f64::from(w) / t * field(d))
                .sum()
        };
        local_linear(&offsets, &mut weights);
        let fitted: f64 = weights
            .iter()
            .zip(&offsets)
            .map(|(&(_, w), &d)| f64::from(w) * field(d))
            .sum();
        let sum: f64 = weights.iter().map(|&(_, w)| f64::from(w)).sum();
        // The field at the point is 2; the plain average reads it inward, where it is higher.
        assert!(
            average > 2.3,
            "the average {average} should be biased inward"
        );
        assert!((sum - 1.0).abs() < 1e-6, "weights add up to {sum}");
        let spread: f64 = weights.iter().map(|&(_, w)| f64::from(w).abs()).sum();
        // Within the bound, so not blended: the fit is exact but for the ridge's 0.1%.
        assert!(spread < SPREAD, "spread {spread}");
        assert!(
            (fitted - 2.0).abs() < 0.01 * (average - 2.0),
            "fitted {fitted}"
        );
    }

    #[test]
    fn the_weights_never_spread_beyond_the_bound() {
        // Samples nearly in a line, the point off it: the fit alone would extrapolate far.
        let offsets: Vec<DVec2> = (0..6)
            .map(|i| DVec2::new(1.0 + 1e-3 * (i % 2) as f64, -0.5 + 0.2 * i as f64))
            .collect();
        let mut weights: Vec<(u32, f32)> = (0..6).map(|k| (k, 1.0)).collect();
        local_linear(&offsets, &mut weights);
        let spread: f64 = weights.iter().map(|&(_, w)| f64::from(w).abs()).sum();
        let sum: f64 = weights.iter().map(|&(_, w)| f64::from(w)).sum();
        assert!(spread <= SPREAD + 1e-5, "spread {spread}");
        assert!((sum - 1.0).abs() < 1e-5, "sum {sum}");
        // Two samples: nothing to fit, the weights are left alone.
        let mut two = vec![(0, 0.3), (1, 0.7)];
        local_linear(&offsets[..2], &mut two);
        assert_eq!(two, vec![(0, 0.3), (1, 0.7)]);
    }
}
