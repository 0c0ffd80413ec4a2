//! Curved pieces: narrow planar sides joined along shared edges into the smoothly bending
//! surface they tessellate (a column's facets, an arch's soffit, a moulding). Sampled alone,
//! each facet narrower than ε holds a row of samples ε apart along its length, where its area
//! asks for a fraction of one: a round column of 48 facets carries 48 rows where the walls'
//! density puts three around it. Sampled as a piece, Poisson-disk spacing holds across its
//! facets (in 3D), and a facet may hold no sample of its own: its area, its interpolation
//! and its neighbours come from the piece's samples (`SideIndex` answers by piece).
//!
//! A piece joins sides of one material whose normals turn by less than [`BEND`] across each
//! shared edge and stay within [`CONE`] of its first side's, so a kernel never reaches round
//! a column to its far side and a crease (a box's corner, a step) always parts two pieces.
//! Within a piece no visibility is asked: its sides bend so little that a chord between two
//! of its points runs along it (inside a convex piece by millimetres, where a ray would read
//! "blocked").

use std::collections::HashMap;

use glam::Vec3;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::poisson::{darts, side_seed};
use super::{is_back, side_of, surface_of, Side, SurfaceMap};
use crate::scene::Scene;

/// A side narrower than this many ε (its area over its bounding box's diagonal) is narrow.
pub(crate) const NARROW: f64 = 2.0;
/// Largest turn (degrees) between two joined sides' normals across their shared edge.
const BEND: f32 = 20.0;
/// Largest angle (degrees) between a piece's normals and its first side's: a sample stands for
/// light arriving at its own normal, and on the shipped atrium a wider piece spreads it too
/// far round a column (`docs/performance.md`: 45° gave 1.28% MAE/mean, 15° 1.09%).
const CONE: f32 = 15.0;
/// A piece holds at most this many ε² of area (some 180 first samples): queries scan a piece's
/// samples, and a gently curved mesh of narrow facets (a vault, a terrain) would otherwise join
/// into one piece of them all.
const MAX_AREA: f64 = 256.0;
/// No piece: the side is sampled, indexed and interpolated alone.
pub(crate) const NONE: u32 = u32::MAX;

/// Each surface's width, its area over its bounding box's diagonal (a strip's width whichever
/// way it lies; a box's longest side would read a diagonal strip wide), against `limit`:
/// whether it is narrower.
pub(crate) fn narrow_surfaces(scene: &Scene, limit: f64) -> Vec<bool> {
    let surfaces = scene.surfaces();
    let mut lo = vec![Vec3::splat(f32::INFINITY); surfaces.len()];
    let mut hi = vec![Vec3::splat(f32::NEG_INFINITY); surfaces.len()];
    for t in scene.triangles() {
        let k = t.surface as usize;
        for v in t.vertices {
            lo[k] = lo[k].min(v);
            hi[k] = hi[k].max(v);
        }
    }
    surfaces
        .iter()
        .enumerate()
        .map(|(k, surface)| {
            let length = f64::from((hi[k] - lo[k]).length());
            length.is_finite() && length > 0.0 && surface.area / length < limit
        })
        .collect()
}

/// The pieces of a scene's sampled sides: per side its piece (`NONE` where it stands alone),
/// and each piece's sides in ascending order.
#[derive(Clone, Debug, Default)]
pub(crate) struct Pieces {
    /// Per side (`2 × surfaces` entries): its piece, or [`NONE`].
    of_side: Vec<u32>,
    /// Piece p's sides are `sides[start[p]..start[p + 1]]`.
    start: Vec<u32>,
    sides: Vec<Side>,
    /// Whether the solve asked for pieces (it may have found none).
    joined: bool,
}

impl Pieces {
    /// No pieces: every side alone (what a solve without them sees).
    pub(crate) fn none(surfaces: usize) -> Pieces {
        Pieces {
            of_side: vec![NONE; 2 * surfaces],
            start: vec![0],
            sides: Vec::new(),
            joined: false,
        }
    }

    /// Joins the narrow ones of `sampled` (narrow at spacing `epsilon`) into pieces; pieces of
    /// one side are left alone.
    pub(crate) fn find(scene: &Scene, sampled: &[Side], epsilon: f32) -> Pieces {
        let surfaces = scene.surfaces();
        let narrow = narrow_surfaces(scene, NARROW * f64::from(epsilon));
        let mut eligible = vec![false; 2 * surfaces.len()];
        for &side in sampled {
            if narrow.get(surface_of(side) as usize) == Some(&true) {
                eligible[side as usize] = true;
            }
        }
        let normal = |side: Side| {
            let n = surfaces[surface_of(side) as usize].normal;
            if is_back(side) {
                -n
            } else {
                n
            }
        };
        let material = |side: Side| surfaces[surface_of(side) as usize].material;
        // Sides across each shared edge that may join (each pair both ways).
        let (bend, cone) = (BEND.to_radians().cos(), CONE.to_radians().cos());
        let largest = MAX_AREA * f64::from(epsilon).powi(2);
        let mut next: Vec<Vec<Side>> = vec![Vec::new(); eligible.len()];
        for (a, b) in crate::scene::adjacency::shared_edges(scene) {
            for sa in [side_of(a, false), side_of(a, true)] {
                for sb in [side_of(b, false), side_of(b, true)] {
                    let fits = eligible[sa as usize]
                        && eligible[sb as usize]
                        && material(sa) == material(sb)
                        && normal(sa).dot(normal(sb)) >= bend;
                    if fits {
                        next[sa as usize].push(sb);
                        next[sb as usize].push(sa);
                    }
                }
            }
        }
        // Region growing from each side in order, breadth first: deterministic.
        let mut of_side = vec![NONE; eligible.len()];
        let (mut start, mut sides) = (vec![0u32], Vec::new());
        let mut queue = std::collections::VecDeque::new();
        for seed in 0..eligible.len() {
            if !eligible[seed] || of_side[seed] != NONE || next[seed].is_empty() {
                continue;
            }
            let p = start.len() as u32 - 1;
            let n0 = normal(seed as Side);
            let mut members = vec![seed as Side];
            let area_of = |side: Side| surfaces[surface_of(side) as usize].area;
            let mut area = area_of(seed as Side);
            of_side[seed] = p;
            queue.push_back(seed as Side);
            while let Some(s) = queue.pop_front() {
                for &t in &next[s as usize] {
                    let fits = of_side[t as usize] == NONE
                        && normal(t).dot(n0) >= cone
                        && area + area_of(t) <= largest;
                    if fits {
                        of_side[t as usize] = p;
                        area += area_of(t);
                        members.push(t);
                        queue.push_back(t);
                    }
                }
            }
            if members.len() < 2 {
                of_side[seed] = NONE;
                continue;
            }
            members.sort_unstable();
            sides.extend(members);
            start.push(sides.len() as u32);
        }
        Pieces {
            of_side,
            start,
            sides,
            joined: true,
        }
    }

    /// Whether the solve asked for pieces (`Options::join_facets`), found or not.
    pub(crate) fn joined(&self) -> bool {
        self.joined
    }

    /// The piece of `side`, if it is in one.
    pub(crate) fn of(&self, side: Side) -> Option<u32> {
        self.of_side
            .get(side as usize)
            .copied()
            .filter(|&p| p != NONE)
    }

    /// The sides of piece `p`.
    pub(crate) fn sides(&self, p: u32) -> &[Side] {
        let p = p as usize;
        match (self.start.get(p), self.start.get(p + 1)) {
            (Some(&a), Some(&b)) => &self.sides[a as usize..b as usize],
            _ => &[],
        }
    }

    /// How many pieces.
    pub(crate) fn len(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        super::vec_bytes(&self.of_side)
            + super::vec_bytes(&self.start)
            + super::vec_bytes(&self.sides)
    }
}

/// Poisson-disk points with spacing `epsilon` (in 3D) over all of piece `p`'s sides, as
/// (side, 2D point on it), by dart throwing; seeded by its first side, so the result depends
/// on neither thread count nor order.
pub(crate) fn sample_piece(
    pieces: &Pieces,
    p: u32,
    maps: &[SurfaceMap],
    epsilon: f32,
    seed: u64,
) -> Vec<(Side, glam::Vec2)> {
    let sides = pieces.sides(p);
    let Some(&first) = sides.first() else {
        return Vec::new();
    };
    let map = |side: Side| &maps[surface_of(side) as usize];
    let mut cumulative = Vec::with_capacity(sides.len());
    let mut total = 0.0;
    for &side in sides {
        total += map(side).area();
        cumulative.push(total);
    }
    let mut rng = Pcg64Mcg::seed_from_u64(side_seed(seed, first, 1));
    let key = |q: Vec3| (q / epsilon).floor().as_ivec3().to_array();
    let mut grid: HashMap<[i32; 3], Vec<u32>> = HashMap::new();
    let mut points: Vec<(Side, glam::Vec2, Vec3)> = Vec::new();
    let eps2 = epsilon * epsilon;
    for _ in 0..darts(total, epsilon) {
        let target = rng.random::<f64>() * total;
        let i = cumulative
            .partition_point(|&c| c <= target)
            .min(sides.len() - 1);
        let m = map(sides[i]);
        let uv = m.point_at(
            rng.random::<f64>(),
            rng.random::<f32>(),
            rng.random::<f32>(),
        );
        let q = m.to_3d(uv);
        let [x, y, z] = key(q);
        let mut free = true;
        'scan: for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    for &j in grid.get(&[x + dx, y + dy, z + dz]).into_iter().flatten() {
                        if points[j as usize].2.distance_squared(q) < eps2 {
                            free = false;
                            break 'scan;
                        }
                    }
                }
            }
        }
        if free {
            grid.entry([x, y, z]).or_default().push(points.len() as u32);
            points.push((sides[i], uv, q));
        }
    }
    points.into_iter().map(|(s, uv, _)| (s, uv)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::fixtures::Parts;
    use crate::scene::Material;

    /// A room 6 × 4 × 6 with a round column of `facets` facets (radius 0.3, 4 high) in it.
    fn hall(facets: u32) -> Scene {
        let mut parts = Parts::default();
        let grey = parts.material(Material::diffuse("grey", Vec3::splat(0.6), Vec3::ZERO));
        parts.cuboid(Vec3::ZERO, Vec3::new(6.0, 4.0, 6.0), true, grey);
        parts.column(Vec3::new(3.0, 0.0, 3.0), 0.3, 4.0, facets, grey);
        parts.scene(Vec3::new(0.5, 1.6, 0.5), Vec3::new(3.0, 1.5, 3.0))
    }

    fn all_fronts(scene: &Scene) -> Vec<Side> {
        (0..scene.surfaces().len() as u32)
            .map(|s| side_of(s, false))
            .collect()
    }

    #[test]
    fn a_round_column_joins_into_pieces_of_a_few_facets_and_walls_stay_alone() {
        // 48 facets 7.5° apart: within 15° of a piece's first facet lie up to 5 facets, so at
        // least ten pieces; greedy growth in facet order leaves a few short ones between. The
        // walls (6 m wide) are not narrow.
        let scene = hall(48);
        let pieces = Pieces::find(&scene, &all_fronts(&scene), 0.3);
        let mut joined: Vec<Side> = (0..pieces.len() as u32)
            .flat_map(|p| pieces.sides(p).to_vec())
            .collect();
        joined.sort_unstable();
        joined.dedup();
        assert_eq!(joined.len(), 48, "every facet in one piece");
        assert!((10..=24).contains(&pieces.len()), "{} pieces", pieces.len());
        for p in 0..pieces.len() as u32 {
            let sides = pieces.sides(p);
            let n0 = scene.surfaces()[surface_of(sides[0]) as usize].normal;
            for &s in sides {
                let n = scene.surfaces()[surface_of(s) as usize].normal;
                assert!(n.dot(n0) >= CONE.to_radians().cos() - 1e-6);
                assert_eq!(pieces.of(s), Some(p));
            }
        }
        // The room's six faces: wide, alone.
        let alone = all_fronts(&scene)
            .into_iter()
            .filter(|&s| pieces.of(s).is_none())
            .count();
        assert_eq!(alone, 6);
        // At ε 0.01 the facets (3.9 cm wide) are wide: no pieces.
        assert_eq!(Pieces::find(&scene, &all_fronts(&scene), 0.01).len(), 0);
    }

    #[test]
    fn a_piece_holds_at_most_its_share_of_area() {
        // ε 0.05: each facet (3.9 cm × 4 m, 0.157 m²) is narrow, and 256 ε² = 0.64 m² holds
        // four of them: a piece stops growing there, whatever its bend.
        let scene = hall(48);
        let eps = 0.05f32;
        let pieces = Pieces::find(&scene, &all_fronts(&scene), eps);
        assert!(pieces.len() >= 12, "{} pieces", pieces.len());
        for p in 0..pieces.len() as u32 {
            let sides = pieces.sides(p);
            let area: f64 = sides
                .iter()
                .map(|&s| scene.surfaces()[surface_of(s) as usize].area)
                .sum();
            assert!((2..=4).contains(&sides.len()), "{} sides", sides.len());
            assert!(area <= 256.0 * f64::from(eps * eps) + 1e-9, "{area} m²");
        }
    }

    #[test]
    fn a_square_column_has_creases_not_pieces() {
        // Four facets 90° apart, narrow at ε 1 (0.42 m wide against 2 m): a crease parts them.
        let scene = hall(4);
        assert_eq!(Pieces::find(&scene, &all_fronts(&scene), 1.0).len(), 0);
    }

    #[test]
    fn a_piece_is_sampled_by_its_area_with_its_spacing_in_3d() {
        // ε 0.1: the facets (3.9 cm) are narrow, and a piece of up to 5 of them (16 cm) is
        // about 1.6 ε wide.
        let scene = hall(48);
        let eps = 0.1;
        let pieces = Pieces::find(&scene, &all_fronts(&scene), eps);
        let maps = SurfaceMap::all(&scene);
        let (mut count, mut area) = (0usize, 0.0);
        for p in 0..pieces.len() as u32 {
            let points = sample_piece(&pieces, p, &maps, eps, 7);
            let at: Vec<Vec3> = points
                .iter()
                .map(|&(s, uv)| {
                    let m = &maps[surface_of(s) as usize];
                    assert!(m.contains(uv), "a point off its side");
                    assert!(pieces.sides(p).contains(&s));
                    m.to_3d(uv)
                })
                .collect();
            for (i, a) in at.iter().enumerate() {
                for b in &at[i + 1..] {
                    assert!(
                        a.distance(*b) >= eps * (1.0 - 1e-4),
                        "two points closer than ε"
                    );
                }
            }
            count += points.len();
            area += pieces
                .sides(p)
                .iter()
                .map(|&s| maps[surface_of(s) as usize].area())
                .sum::<f64>();
        }
        // The column's 7.5 m² by hand (2π · 0.3 · 4, less the facets' chords: 0.07%).
        let by_hand = std::f64::consts::TAU * 0.3 * 4.0;
        assert!(
            (area / by_hand - 1.0).abs() < 0.002,
            "area {area} against {by_hand}"
        );
        // Dart throwing near jamming packs about 0.7 points an ε² on a wide side, more on
        // strips 1-2 ε wide (points sit on both edges, and pieces are thrown apart). Alone,
        // the 48 facets 3.9 cm wide would hold a row of 4 / 0.1 = 40 each: 1,920.
        let density = count as f64 * f64::from(eps * eps) / area;
        eprintln!("{count} points: {density} an ε²");
        assert!(
            (0.5..1.3).contains(&density),
            "{count} points: {density} an ε²"
        );
        assert!(count < 1920 / 2, "{count} points");
    }
}
