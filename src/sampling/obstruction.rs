//! Which surface sides other geometry stands on. Two points of one side can be hidden from
//! each other only by geometry that crosses the thin band just above the side (a partition
//! wall on a continuous floor, a box on it, a picture frame on a wall). Sides that nothing
//! crosses never need a visibility query between their own points: areas, adaptive errors and
//! interpolation there skip the tests; elsewhere they make them, so light never spreads
//! through a thin wall.

use std::collections::HashMap;

use glam::{IVec3, Vec3};

use super::{is_back, side_of, Samples, Side, SurfaceMap};
use crate::error::Result;
use crate::scene::Scene;
use crate::visibility::{Segment, Visibility};

/// Sides crossed by other geometry, and the lift used for point-to-point tests along sides.
#[derive(Clone, Debug)]
pub struct Obstruction {
    obstructed: Vec<bool>,
    lift: f32,
}

impl Obstruction {
    /// Finds, for every side, whether any triangle of another surface crosses the band
    /// between its plane and 2 × `lift` above it, within its bounds (conservatively: by
    /// bounding box in the plane).
    pub fn new(scene: &Scene, maps: &[SurfaceMap], lift: f32) -> Obstruction {
        let diagonal = scene.bounds.diagonal().max(1e-30);
        let cell = diagonal / 64.0;
        let key = |p: Vec3| ((p - scene.bounds.min) / cell).floor().as_ivec3();
        // Triangles by grid cell of their bounding boxes.
        let mut grid: HashMap<IVec3, Vec<u32>> = HashMap::new();
        for (i, t) in scene.triangles.iter().enumerate() {
            let lo = key(t.vertices[0].min(t.vertices[1]).min(t.vertices[2]));
            let hi = key(t.vertices[0].max(t.vertices[1]).max(t.vertices[2]));
            for x in lo.x..=hi.x {
                for y in lo.y..=hi.y {
                    for z in lo.z..=hi.z {
                        grid.entry(IVec3::new(x, y, z)).or_default().push(i as u32);
                    }
                }
            }
        }
        let mut obstructed = vec![false; 2 * maps.len()];
        for (s, map) in maps.iter().enumerate() {
            let surface = &scene.surfaces[s];
            let tris =
                &scene.triangles[surface.triangles.start as usize..surface.triangles.end as usize];
            let (lo, hi) = tris.iter().flat_map(|t| t.vertices).fold(
                (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |(lo, hi), p| (lo.min(p), hi.max(p)),
            );
            for back in [false, true] {
                let normal = if back { -map.normal } else { map.normal };
                let reach = 2.0 * lift;
                let (blo, bhi) = (
                    lo.min(lo + reach * normal) - Vec3::splat(lift),
                    hi.max(hi + reach * normal) + Vec3::splat(lift),
                );
                let base = normal.dot(map.origin);
                let (klo, khi) = (key(blo), key(bhi));
                let mut found = false;
                'cells: for x in klo.x..=khi.x {
                    for y in klo.y..=khi.y {
                        for z in klo.z..=khi.z {
                            let Some(list) = grid.get(&IVec3::new(x, y, z)) else {
                                continue;
                            };
                            for &t in list {
                                let tri = &scene.triangles[t as usize];
                                if tri.surface == s as u32 {
                                    continue;
                                }
                                let (tlo, thi) = (
                                    tri.vertices[0].min(tri.vertices[1]).min(tri.vertices[2]),
                                    tri.vertices[0].max(tri.vertices[1]).max(tri.vertices[2]),
                                );
                                if tlo.cmpgt(bhi).any() || thi.cmplt(blo).any() {
                                    continue;
                                }
                                let h = tri.vertices.map(|v| normal.dot(v) - base);
                                let (hmin, hmax) =
                                    (h[0].min(h[1]).min(h[2]), h[0].max(h[1]).max(h[2]));
                                if hmax > 0.0 && hmin < reach {
                                    found = true;
                                    break 'cells;
                                }
                            }
                        }
                    }
                }
                obstructed[side_of(s as u32, back) as usize] = found;
            }
        }
        Obstruction { obstructed, lift }
    }

    /// Whether points of this side may hide from each other.
    pub fn is_obstructed(&self, side: Side) -> bool {
        self.obstructed.get(side as usize).copied().unwrap_or(false)
    }

    /// The segment between a point of a side and a sample, both lifted off the side.
    pub fn segment(&self, side_normal: Vec3, point: Vec3, samples: &Samples, k: u32) -> Segment {
        Segment {
            a: point + self.lift * side_normal,
            b: samples.position[k as usize] + self.lift * side_normal,
        }
    }

    /// Keeps the candidates (sample, anything) that `point`, on `side`, sees along the side.
    /// Returns the number of visibility queries made.
    pub fn retain_visible<T>(
        &self,
        vis: &dyn Visibility,
        maps: &[SurfaceMap],
        samples: &Samples,
        side: Side,
        point: Vec3,
        candidates: &mut Vec<(u32, T)>,
    ) -> Result<u64> {
        if !self.is_obstructed(side) || candidates.is_empty() {
            return Ok(0);
        }
        let map = &maps[super::surface_of(side) as usize];
        let normal = if is_back(side) {
            -map.normal
        } else {
            map.normal
        };
        let segments: Vec<Segment> = candidates
            .iter()
            .map(|&(k, _)| self.segment(normal, point, samples, k))
            .collect();
        let mut blocked = vec![false; segments.len()];
        vis.occluded(&segments, &mut blocked)?;
        let mut i = 0;
        candidates.retain(|_| {
            let keep = !blocked[i];
            i += 1;
            keep
        });
        Ok(segments.len() as u64)
    }
}
