//! Which surface sides other geometry stands on. Two points of one side can be hidden from
//! each other only by geometry that crosses the thin band just above the side (a partition
//! wall on a continuous floor, a box on it, a picture frame on a wall). Sides that nothing
//! crosses never need a visibility query between their own points: areas, adaptive errors and
//! interpolation there skip the tests; elsewhere they make them, so light never spreads
//! through a thin wall.

use std::collections::HashMap;

use glam::{IVec3, Vec2, Vec3};

use super::{is_back, side_of, Samples, Side, SurfaceMap};
use crate::error::Result;
use crate::scene::Scene;
use crate::visibility::{Segment, Visibility};

/// Footprints kept per side: a side crossed by more pieces than this keeps none, and any
/// segment along it may be blocked (a floor among hundreds of columns: its queries are then
/// fewer than the footprints a test would scan).
const MAX_FOOTPRINTS: usize = 256;

/// Triangles a side may find in its band's box that do not cross the band before it stops
/// looking and counts as crossed everywhere (every segment along it asked, as beyond
/// [`MAX_FOOTPRINTS`]): thousands of facets fanned round one edge all lie in each other's
/// boxes, and looking through all of them for every side took time quadratic in the facets.
const MAX_MISSES: usize = 4 * MAX_FOOTPRINTS;

/// Sides crossed by other geometry, where, and the lift used for point-to-point tests along
/// sides.
#[derive(Clone, Debug)]
pub struct Obstruction {
    /// Per side: the (u, v) boxes, in its surface's frame, of the parts of the triangles
    /// crossing its band (grown by the lift), or none when there are more than
    /// [`MAX_FOOTPRINTS`] (or more than [`MAX_MISSES`] triangles in its box that do not cross
    /// it). Empty for sides nothing crosses, which are the unobstructed ones.
    footprints: Vec<Option<Vec<(Vec2, Vec2)>>>,
    lift: f32,
    /// Per side of a curved piece: whether anything crosses the band of any of the piece's
    /// sides (a segment between two of its sides runs over the sides between). Empty: none.
    piece_obstructed: Vec<bool>,
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
        let mut footprints = vec![Some(Vec::new()); 2 * maps.len()];
        // Per triangle, the last side that looked at it (a triangle is listed in every grid
        // cell its box meets, and counts once a side, as a footprint or as a miss).
        let mut looked = vec![u32::MAX; scene.triangles.len()];
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
                let this = side_of(s as u32, back);
                let mut misses = 0;
                let mut prints: Option<Vec<(Vec2, Vec2)>> = Some(Vec::new());
                'cells: for x in klo.x..=khi.x {
                    for y in klo.y..=khi.y {
                        for z in klo.z..=khi.z {
                            let Some(list) = grid.get(&IVec3::new(x, y, z)) else {
                                continue;
                            };
                            for &t in list {
                                let tri = &scene.triangles[t as usize];
                                if tri.surface == s as u32 || looked[t as usize] == this {
                                    continue;
                                }
                                looked[t as usize] = this;
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
                                    let Some(list) = prints.as_mut() else {
                                        break 'cells;
                                    };
                                    if list.len() == MAX_FOOTPRINTS {
                                        // Too many to scan: every segment is asked.
                                        prints = None;
                                        break 'cells;
                                    }
                                    let part = in_band(&tri.vertices, h, reach);
                                    list.push(footprint(map, &part, lift));
                                } else {
                                    misses += 1;
                                    if misses > MAX_MISSES {
                                        prints = None;
                                        break 'cells;
                                    }
                                }
                            }
                        }
                    }
                }
                footprints[this as usize] = prints;
            }
        }
        Obstruction {
            footprints,
            lift,
            piece_obstructed: Vec::new(),
        }
    }

    /// Notes, for each side of a curved piece, whether something stands on any of its sides.
    pub(crate) fn with_pieces(mut self, pieces: &super::pieces::Pieces) -> Obstruction {
        if pieces.len() == 0 {
            return self;
        }
        let mut flags = vec![false; self.footprints.len()];
        for p in 0..pieces.len() as u32 {
            let sides = pieces.sides(p);
            if sides.iter().any(|&s| self.is_obstructed(s)) {
                for &s in sides {
                    if let Some(f) = flags.get_mut(s as usize) {
                        *f = true;
                    }
                }
            }
        }
        self.piece_obstructed = flags;
        self
    }

    /// Whether something crossing the side's band meets the (u, v) box `lo`..`hi` of its
    /// surface's frame: a segment along the side (lifted off it) whose ends lie in that box
    /// can be blocked only then. Conservative: any side whose footprints were not kept.
    pub fn may_block(&self, side: Side, lo: Vec2, hi: Vec2) -> bool {
        match self.footprints.get(side as usize) {
            Some(Some(prints)) => prints
                .iter()
                .any(|(plo, phi)| plo.cmple(hi).all() && phi.cmpge(lo).all()),
            Some(None) => true,
            None => false,
        }
    }

    /// Whether points of this side may hide from each other.
    pub fn is_obstructed(&self, side: Side) -> bool {
        self.footprints
            .get(side as usize)
            .is_some_and(|p| p.as_ref().is_none_or(|p| !p.is_empty()))
    }

    /// Whether something crossing a band may block the segment from `point` (on `side`) to
    /// sample `k`: in `side`'s band within the segment's box; for a sample on another side of
    /// the same curved piece, anywhere on the piece (a floor a column passes through, a wall
    /// meeting it; a convex piece's own facets cross none of its bands).
    pub(crate) fn may_block_between(
        &self,
        maps: &[SurfaceMap],
        samples: &Samples,
        side: Side,
        point: Vec3,
        k: u32,
    ) -> bool {
        let (Some(&other), Some(&to)) = (samples.side.get(k as usize), samples.uv.get(k as usize))
        else {
            return true;
        };
        if other != side {
            // The segment runs over the piece's sides between the two: asked wherever
            // anything stands on the piece.
            return self
                .piece_obstructed
                .get(side as usize)
                .copied()
                .unwrap_or(true);
        }
        let Some(map) = maps.get(super::surface_of(side) as usize) else {
            return true;
        };
        let from = map.to_2d(point);
        self.may_block(side, from.min(to), from.max(to))
    }

    /// The segment between a point (of normal `normal`) and a sample at `to` (of normal
    /// `to_normal`), each lifted along its own normal. Where the two normals differ (a sample
    /// on another side of a curved piece) the lift grows to clear the facets between: a chord
    /// between two points of a convex run of facets with normals φ apart dips at most
    /// d/2 · tan(φ/2) under them (the corner where the end facets' lines meet), and an end
    /// lifted along its own normal rises by cos φ of that against the other end's facet:
    /// (lift + d/2 · tan(φ/2)) / cos φ in all.
    pub(crate) fn lifted(
        lift: f32,
        point: Vec3,
        normal: Vec3,
        to: Vec3,
        to_normal: Vec3,
    ) -> Segment {
        let cos = normal.dot(to_normal).clamp(-1.0, 1.0);
        let up = if cos < 1.0 - 1e-6 {
            let half = 0.5 * cos.acos();
            (lift + 0.5 * point.distance(to) * half.tan()) / cos.max(0.5)
        } else {
            lift
        };
        Segment {
            a: point + up * normal,
            b: to + up * to_normal,
        }
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
        // A candidate on another side is one of the same curved piece (the index finds no
        // other): something may stand on any side of the piece between the two.
        let across = |k: u32| samples.side.get(k as usize).is_some_and(|&s| s != side);
        if candidates.is_empty()
            || !self.is_obstructed(side) && !candidates.iter().any(|&(k, _)| across(k))
        {
            return Ok(0);
        }
        let map = &maps[super::surface_of(side) as usize];
        let normal = if is_back(side) {
            -map.normal
        } else {
            map.normal
        };
        // Only segments whose box something crosses the band in are asked.
        let asked: Vec<bool> = candidates
            .iter()
            .map(|&(k, _)| self.may_block_between(maps, samples, side, point, k))
            .collect();
        let segments: Vec<Segment> = candidates
            .iter()
            .zip(&asked)
            .filter(|(_, &a)| a)
            .map(|(&(k, _), _)| {
                if samples.side[k as usize] == side {
                    self.segment(normal, point, samples, k)
                } else {
                    let (to, n) = (samples.position[k as usize], samples.normal[k as usize]);
                    Self::lifted(self.lift, point, normal, to, n)
                }
            })
            .collect();
        let mut blocked = vec![false; segments.len()];
        vis.occluded(&segments, &mut blocked)?;
        let mut answers = blocked.into_iter();
        let mut i = 0;
        candidates.retain(|_| {
            let keep = !(asked[i] && answers.next().unwrap_or(false));
            i += 1;
            keep
        });
        Ok(segments.len() as u64)
    }
}

/// The part of a triangle (its vertices `v`, their heights `h` over a side's plane) between
/// heights 0 and `reach`: the piece that may block a segment lifted along the side.
fn in_band(v: &[Vec3; 3], h: [f32; 3], reach: f32) -> Vec<Vec3> {
    let mut poly: Vec<(Vec3, f32)> = v.iter().copied().zip(h).collect();
    for (keep, level) in [(1.0f32, 0.0f32), (-1.0, -reach)] {
        // Keep keep × height ≥ level (Sutherland–Hodgman on one plane).
        let mut out = Vec::with_capacity(poly.len() + 1);
        for i in 0..poly.len() {
            let (a, ha) = poly[i];
            let (b, hb) = poly[(i + 1) % poly.len()];
            let (da, db) = (keep * ha - level, keep * hb - level);
            if da >= 0.0 {
                out.push((a, ha));
            }
            if (da >= 0.0) != (db >= 0.0) {
                let t = da / (da - db);
                out.push((a + t * (b - a), ha + t * (hb - ha)));
            }
        }
        poly = out;
    }
    if poly.is_empty() {
        // Round-off at a band's edge: the whole triangle, which is safe.
        return v.to_vec();
    }
    poly.into_iter().map(|(p, _)| p).collect()
}

/// The (u, v) box of `points` in `map`'s frame, grown by `margin`.
fn footprint(map: &SurfaceMap, points: &[Vec3], margin: f32) -> (Vec2, Vec2) {
    let (lo, hi) = points.iter().map(|&p| map.to_2d(p)).fold(
        (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
        |(lo, hi), q| (lo.min(q), hi.max(q)),
    );
    (lo - Vec2::splat(margin), hi + Vec2::splat(margin))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::fixtures::Parts;
    use crate::scene::Material;
    use crate::visibility::Backend;
    use rand::{RngExt, SeedableRng};
    use rand_pcg::Pcg64Mcg;

    #[test]
    fn a_segment_the_footprints_pass_is_one_no_ray_finds_blocked() {
        // A room with a box standing on its floor and a shelf floating before a wall: the
        // backend's rays are the second method. Every lifted segment between two points of one
        // side that a ray finds blocked must be one the footprints say may be; and segments far
        // from the box and the shelf must be let through without a ray.
        let mut parts = Parts::default();
        let white = parts.material(Material::diffuse("white", Vec3::splat(0.5), Vec3::ZERO));
        parts.cuboid(Vec3::ZERO, Vec3::new(4.0, 3.0, 2.0), true, white);
        parts.cuboid(
            Vec3::new(1.0, 0.0, 0.5),
            Vec3::new(1.6, 0.7, 1.1),
            false,
            white,
        );
        parts.cuboid(
            Vec3::new(2.5, 1.5, 0.05),
            Vec3::new(3.5, 1.55, 0.4),
            false,
            white,
        );
        let scene = parts.scene(Vec3::new(2.0, 1.5, 1.9), Vec3::new(2.0, 1.0, 0.0));
        let vis = Backend::Bvh.build(&scene).unwrap();
        let maps = SurfaceMap::all(&scene);
        let lift = crate::visibility::lift(&scene);
        let obstruction = Obstruction::new(&scene, &maps, lift);
        let mut rng = Pcg64Mcg::seed_from_u64(7);
        let (mut blocked_seen, mut spared, mut tried) = (0, 0, 0);
        for (s, map) in maps.iter().enumerate() {
            for back in [false, true] {
                let side = side_of(s as u32, back);
                if !obstruction.is_obstructed(side) {
                    continue;
                }
                let normal = if back { -map.normal } else { map.normal };
                let pick =
                    |rng: &mut Pcg64Mcg| map.point_at(rng.random(), rng.random(), rng.random());
                let pairs: Vec<(Vec2, Vec2)> =
                    (0..400).map(|_| (pick(&mut rng), pick(&mut rng))).collect();
                let segments: Vec<Segment> = pairs
                    .iter()
                    .map(|&(a, b)| Segment {
                        a: map.to_3d(a) + lift * normal,
                        b: map.to_3d(b) + lift * normal,
                    })
                    .collect();
                let mut blocked = vec![false; segments.len()];
                vis.occluded(&segments, &mut blocked).unwrap();
                for (&(a, b), &hit) in pairs.iter().zip(&blocked) {
                    let may = obstruction.may_block(side, a.min(b), a.max(b));
                    assert!(
                        !hit || may,
                        "side {side}: a blocked segment {a} → {b} let through"
                    );
                    blocked_seen += usize::from(hit);
                    spared += usize::from(!may);
                    tried += 1;
                }
            }
        }
        eprintln!("{blocked_seen} blocked, {spared} spared of {tried}");
        assert!(blocked_seen > 50, "{blocked_seen} blocked of {tried}");
        // Most segments of the floor and the walls pass nowhere near the box or the shelf.
        assert!(
            spared * 2 > tried,
            "only {spared} of {tried} segments spared a ray"
        );
    }

    #[test]
    fn a_side_with_too_many_triangles_in_its_box_is_asked_everywhere() {
        // A 4 m floor with `n` chips of 1 cm just under it: each lies in the floor's band box
        // and none crosses its band. A few hundred leave the floor clear (no footprint); past
        // MAX_MISSES the floor stops looking and counts as crossed everywhere, which asks more
        // rays but can hide no wall.
        let floor = |n: usize| {
            let mut parts = Parts::default();
            let white = parts.material(Material::diffuse("white", Vec3::splat(0.5), Vec3::ZERO));
            let mut triangle = |t: [Vec3; 3]| {
                let first = parts.mesh.positions.len() as u32;
                parts.mesh.positions.extend(t);
                parts.mesh.triangles.push([first, first + 1, first + 2]);
                parts.mesh.triangle_materials.push(white);
            };
            let (o, x, z) = (Vec3::ZERO, Vec3::X * 4.0, Vec3::Z * 4.0);
            triangle([o, o + z, o + x + z]);
            triangle([o, o + x + z, o + x]);
            // A 3 m sheet just under the floor too: two triangles listed in hundreds of grid
            // cells, which count once each.
            let (a, b) = (Vec3::new(0.5, -1e-6, 0.5), Vec3::new(3.5, -1e-6, 3.5));
            triangle([a, Vec3::new(b.x, a.y, a.z), b]);
            triangle([a, b, Vec3::new(a.x, a.y, b.z)]);
            let per_row = (n as f32).sqrt().ceil() as usize;
            for i in 0..n {
                let (r, c) = (i / per_row, i % per_row);
                let p = Vec3::new(
                    0.2 + 3.6 * c as f32 / per_row as f32,
                    -1e-6,
                    0.2 + 3.6 * r as f32 / per_row as f32,
                );
                triangle([p, p + Vec3::X * 0.01, p + Vec3::Z * 0.01]);
            }
            let scene = parts.scene(Vec3::new(2.0, 1.0, 2.0), Vec3::ZERO);
            let maps = SurfaceMap::all(&scene);
            let lift = crate::visibility::lift(&scene);
            assert!(lift > 1e-5, "lift {lift}");
            let obstruction = Obstruction::new(&scene, &maps, lift);
            // The floor is the surface whose normal points up.
            let s = maps
                .iter()
                .position(|m| m.normal.y > 0.9 && m.normal.dot(m.origin).abs() < 1e-3);
            let side = side_of(s.unwrap() as u32, false);
            (
                obstruction.is_obstructed(side),
                obstruction.may_block(side, Vec2::splat(0.1), Vec2::splat(0.2)),
            )
        };
        assert_eq!(floor(400), (false, false));
        const { assert!(2 * MAX_MISSES <= 2_500) };
        assert_eq!(floor(2_500), (true, true));
    }
}
