//! Interpolation of the samples at surface points (`docs/method.md` §7 and §18): the samples of
//! the point's side whose kernels reach it, weighted by the compactly supported kernel
//! (1 − d²/r²)³ with r = 2D, among those in sight of it (a sample behind a wall on the same
//! continuous side never contributes) and covered as the point is (`sampling::cover`), if any
//! such; where no kernel reaches a point in sight, its nearest visible sample. Shared by the
//! camera's hits, the points specular chains end at, and the grids.

use glam::Vec3;

use crate::error::Result;
use crate::sampling::{cover, is_back, surface_of, Side};
use crate::scene::Scene;
use crate::solver::Solution;
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

/// What interpolation reads of a solution.
pub(crate) struct Interpolator<'a> {
    solution: &'a Solution,
    vis: &'a dyn Visibility,
    lift: f32,
    /// Largest kernel support among each side's samples (0: the side has none).
    support: Vec<f32>,
}

impl<'a> Interpolator<'a> {
    pub(crate) fn new(scene: &'a Scene, solution: &'a Solution, vis: &'a dyn Visibility) -> Self {
        let s = &solution.samples;
        let mut support = vec![0.0f32; 2 * scene.surfaces.len()];
        for (&side, &d) in s.side.iter().zip(&s.radius) {
            support[side as usize] = support[side as usize].max(SUPPORT * d);
        }
        Interpolator {
            solution,
            vis,
            lift: crate::visibility::lift(scene),
            support,
        }
    }

    /// Whether a side has samples to interpolate.
    pub(crate) fn has_samples(&self, side: Side) -> bool {
        self.support.get(side as usize).is_some_and(|&r| r > 0.0)
    }

    /// Whether something hovers over each (point, side normal), one query each.
    pub(crate) fn covered(&self, points: &[(Vec3, Vec3)]) -> Result<Vec<bool>> {
        let covers: Vec<Segment> = points
            .iter()
            .map(|&(p, n)| cover::segment(p, n, self.lift, self.solution.epsilon))
            .collect();
        let mut answers = vec![false; covers.len()];
        self.vis.occluded(&covers, &mut answers)?;
        Ok(answers)
    }

    /// The samples each site interpolates, with their kernel weights (not normalised), in
    /// sample order; or its nearest visible sample (weight 1); or none when it is sealed off
    /// from them all. Returns the visibility queries.
    pub(crate) fn weights(&self, sites: &[Site], out: &mut Vec<Vec<(u32, f32)>>) -> Result<u64> {
        let s = &self.solution.samples;
        let mut candidates: Vec<(u32, f32)> = Vec::new();
        let mut ranges = Vec::with_capacity(sites.len());
        let mut segments = Vec::new();
        let mut near = Vec::new();
        for site in sites {
            let map = &self.solution.maps[surface_of(site.side) as usize];
            let from = site.point + self.lift * site.normal;
            let uv = map.to_2d(site.point);
            let reach = self.support[site.side as usize];
            self.solution
                .index
                .within(s, site.side, uv, reach, &mut near);
            near.sort_unstable_by_key(|&(k, _)| k);
            let start = candidates.len();
            let test = self.solution.obstruction.is_obstructed(site.side);
            for &(k, d2) in &near {
                let r = SUPPORT * s.radius[k as usize];
                let q = d2 / (r * r);
                if q < 1.0 {
                    candidates.push((k, (1.0 - q).powi(3)));
                    // On sides nothing stands on, every sample is in sight: no query.
                    segments.push(test.then(|| Segment {
                        a: from,
                        b: s.position[k as usize] + self.lift * s.normal[k as usize],
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
            }
            out.push(chosen);
        }
        Ok(queries)
    }

    /// Whether sample k is covered (`sampling::cover`); a solution without the flags has none.
    fn sample_covered(&self, k: usize) -> bool {
        self.solution.covered.get(k).copied().unwrap_or(false)
    }

    /// Fallback where no sample's kernel reaches a visible point: the nearest visible sample of
    /// the side within a growing radius, if any.
    fn nearest_visible(&self, side: Side, point: Vec3) -> Result<(Option<u32>, u64)> {
        let s = &self.solution.samples;
        let surface = surface_of(side);
        let map = &self.solution.maps[surface as usize];
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
            self.solution.index.within(s, side, uv, r, &mut near);
            near.sort_unstable_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            near.truncate(16);
            let segments: Vec<Segment> = near
                .iter()
                .map(|&(k, _)| Segment {
                    a: from,
                    b: s.position[k as usize] + self.lift * s.normal[k as usize],
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
