//! Which nodes may stand for their members in a link. A link's visibility comes from a few
//! rays between members; if a wall stood between two members of one node (a floor running
//! under a partition into the next room, two parallel walls on either side of one), those rays
//! could all land on one side of it and the node's light would be pushed to members the
//! shooter cannot see: light through walls. So a node is coherent only when no triangle meeting
//! the box of its members' sample points has members on both sides of its plane. A surface
//! whose plane bounds the members (a floor under a wall node, the other facets of a convex
//! sculpture, a picture hanging in front of a wall) cannot stand between them; a partition on a
//! floor node, a pedestal, a frame bar across a wall node can.
//!
//! Incoherent nodes are split, and linked only in pairs of so few member pairs that every pair
//! is probed (then nothing can hide behind the occluder); single samples are always coherent. The
//! tree splits a side's (or a curved piece's) incoherent node along the plane of the triangle
//! standing among its members (as a BSP would), so that an occluder costs a few incoherent
//! nodes, not every node its outline crosses.
//! Occluders that merely hover between a node and a shooter are what the link's rays are for;
//! one hovering close in front of a node (`sheltered`, `hovered_sample`) makes its members see
//! differently, so the links refine such nodes rather than trust a few rays.

use std::ops::Range;

use glam::{IVec3, Vec3};

use crate::sampling::{Obstruction, Samples};
use crate::scene::Scene;

/// The scene's triangles in a uniform grid of their bounding boxes (compressed rows).
pub(crate) struct TriangleGrid {
    min: Vec3,
    cell: f32,
    dims: IVec3,
    starts: Vec<u32>,
    entries: Vec<u32>,
    /// How many triangles the scene has.
    triangles: usize,
}

impl TriangleGrid {
    /// Grids the scene's triangles: about 64 cells along the longest extent.
    pub fn new(scene: &Scene) -> TriangleGrid {
        let (min, max) = (scene.bounds.min, scene.bounds.max);
        let cell = ((max - min).max_element() / 64.0).max(1e-30);
        let dims = (((max - min) / cell).floor().as_ivec3() + 1).max(IVec3::ONE);
        let mut grid = TriangleGrid {
            min,
            cell,
            dims,
            starts: Vec::new(),
            entries: Vec::new(),
            triangles: scene.triangles.len(),
        };
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for (i, t) in scene.triangles.iter().enumerate() {
            let (lo, hi) = bounds(&t.vertices);
            grid.for_cells(lo, hi, |c| pairs.push((c, i as u32)));
        }
        pairs.sort_unstable();
        let cells = (dims.x * dims.y * dims.z) as usize;
        grid.starts = vec![0; cells + 1];
        for &(c, _) in &pairs {
            grid.starts[c as usize + 1] += 1;
        }
        for c in 0..cells {
            grid.starts[c + 1] += grid.starts[c];
        }
        grid.entries = pairs.into_iter().map(|(_, t)| t).collect();
        grid
    }

    fn key(&self, p: Vec3) -> IVec3 {
        ((p - self.min) / self.cell)
            .floor()
            .as_ivec3()
            .clamp(IVec3::ZERO, self.dims - 1)
    }

    fn for_cells(&self, lo: Vec3, hi: Vec3, mut f: impl FnMut(u32)) {
        let (a, b) = (self.key(lo), self.key(hi));
        for z in a.z..=b.z {
            for y in a.y..=b.y {
                for x in a.x..=b.x {
                    f(((z * self.dims.y + y) * self.dims.x + x) as u32);
                }
            }
        }
    }

    /// Whether `test` holds for some triangle whose grid cells meet the box [lo, hi], each
    /// tested once, in grid order. A triangle at a slant to the axes lies in many cells, and a
    /// box of such triangles (a sloping side's node) meets it in many: tested once per cell,
    /// a member-by-member test ran hundreds of times over. `test` must not query the grid
    /// itself (the stamps are borrowed for the query).
    fn any(&self, lo: Vec3, hi: Vec3, mut test: impl FnMut(u32) -> bool) -> bool {
        thread_local! {
            /// Per triangle, the last query that tested it; and the query count.
            static TESTED: std::cell::RefCell<(Vec<u32>, u32)> =
                const { std::cell::RefCell::new((Vec::new(), 0)) };
        }
        TESTED.with(|tested| {
            let mut guard = tested.borrow_mut();
            let (stamps, query) = &mut *guard;
            if stamps.len() < self.triangles {
                stamps.resize(self.triangles, 0);
            }
            *query = query.wrapping_add(1);
            if *query == 0 {
                // Wrapped: no stamp may match a new query by accident.
                stamps.fill(0);
                *query = 1;
            }
            let (a, b) = (self.key(lo), self.key(hi));
            for z in a.z..=b.z {
                for y in a.y..=b.y {
                    let row = ((z * self.dims.y + y) * self.dims.x) as usize;
                    let range: Range<usize> = self.starts[row + a.x as usize] as usize
                        ..self.starts[row + b.x as usize + 1] as usize;
                    for &t in &self.entries[range] {
                        if stamps[t as usize] != *query {
                            stamps[t as usize] = *query;
                            if test(t) {
                                return true;
                            }
                        }
                    }
                }
            }
            false
        })
    }
}

/// What the coherence tests look at.
pub(crate) struct Context<'a> {
    pub scene: &'a Scene,
    pub grid: &'a TriangleGrid,
    pub samples: &'a Samples,
    pub obstruction: &'a Obstruction,
    /// The curved pieces narrow sides were joined into (none unless the solve joins them).
    pub pieces: &'a crate::sampling::pieces::Pieces,
    /// How far sample points are lifted off their surfaces: the tolerance of the tests.
    pub lift: f32,
}

/// A plane that splits a set of samples: a triangle's, with members on both sides.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Splitter {
    pub normal: Vec3,
    pub offset: f32,
}

impl Splitter {
    /// Whether a point lies in front of the plane.
    pub fn in_front(&self, p: Vec3) -> bool {
        self.normal.dot(p) > self.offset
    }
}

/// The first triangle (in grid order) that stands among `members` (whose sample points have
/// bounds `lo`, `hi`): it meets their box and its plane has members strictly on both sides.
/// `None`: the members form a coherent node. `side` is the side all members lie on, if one:
/// when nothing stands on that side anywhere, no triangle is looked at.
pub(crate) fn splitter(
    cx: &Context,
    side: Option<u32>,
    members: &[u32],
    lo: Vec3,
    hi: Vec3,
) -> Option<Splitter> {
    if side.is_some_and(|side| !cx.obstruction.is_obstructed(side)) || members.len() < 2 {
        return None;
    }
    let pad = Vec3::splat(cx.lift);
    let (blo, bhi) = (lo - pad, hi + pad);
    let mut found = None;
    cx.grid.any(blo, bhi, |t| {
        let tri = &cx.scene.triangles[t as usize];
        if splits(tri.normal, tri.vertices[0], lo, hi, members, cx)
            && meets_box(&tri.vertices, blo, bhi)
        {
            found = Some(Splitter {
                normal: tri.normal,
                offset: tri.normal.dot(tri.vertices[0]),
            });
            return true;
        }
        false
    });
    found
}

/// Whether the plane through `point` with unit `normal` has members strictly (beyond the lift)
/// on both sides: first from the members' box, then member by member.
fn splits(normal: Vec3, point: Vec3, lo: Vec3, hi: Vec3, members: &[u32], cx: &Context) -> bool {
    let c = normal.dot(point);
    let centre = normal.dot(0.5 * (lo + hi)) - c;
    let half = normal.abs().dot(0.5 * (hi - lo));
    if centre - half >= -cx.lift || centre + half <= cx.lift {
        return false;
    }
    let (mut below, mut above) = (false, false);
    for &k in members {
        let h = normal.dot(cx.samples.position[k as usize]) - c;
        below |= h < -cx.lift;
        above |= h > cx.lift;
        if below && above {
            return true;
        }
    }
    false
}

/// What a node's members lie on, as the hover tests see it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Owner {
    /// One side.
    Side(u32),
    /// Several sides of one curved piece.
    Piece(u32),
    /// Sides of several surfaces or pieces.
    Several,
}

/// Where a node's members lie: the world's box of their points, their bounds along two axes in
/// its plane (its surface's own, which follow an edge of it; where that edge is a diagonal the
/// two boxes cut an octagon, tighter than either), and the plane through the lowest of their
/// centroids. The world's box alone is loose for a side at a slant to the axes: it holds the
/// walls the side meets, which were taken for things hovering in front of it (`cornell` turned
/// at a slant, rendered: 1.69 times the upright room's links, now 1.19).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Footprint {
    normal: Vec3,
    world: (Vec3, Vec3),
    axes: [Vec3; 2],
    lo: [f32; 2],
    hi: [f32; 2],
    base: f32,
}

impl Footprint {
    /// The footprint of `members` (their sample points and centroids) under `normal` (unit),
    /// measured along `along` (a direction in the plane) and across it.
    pub(crate) fn of(samples: &Samples, normal: Vec3, along: Vec3, members: &[u32]) -> Footprint {
        let first = (along - normal * normal.dot(along))
            .try_normalize()
            .unwrap_or_else(|| normal.any_orthonormal_vector());
        let axes = [first, normal.cross(first)];
        let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
        let mut world = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        let mut base = f32::INFINITY;
        for &k in members {
            let (p, c) = (samples.position[k as usize], samples.centroid[k as usize]);
            for q in [p, c] {
                world = (world.0.min(q), world.1.max(q));
                for (i, axis) in axes.iter().enumerate() {
                    lo[i] = lo[i].min(axis.dot(q));
                    hi[i] = hi[i].max(axis.dot(q));
                }
            }
            base = base.min(normal.dot(c));
        }
        Footprint {
            normal,
            world,
            axes,
            lo,
            hi,
            base,
        }
    }
}

/// Whether something hovers close in front of the members of a node on one side or one curved
/// piece (between the lift and `depth` in front of the plane through its lowest centroid, over
/// their footprint shrunk by the lift: a wall meeting the side along the footprint's edge does
/// not shelter it): a light fixture under a ceiling, a canvas before a wall. Such a node may
/// hold members that see a shooter and members sheltered from it, in a gap the probes of a faint
/// link can miss; light is never averaged into it. A piece's own facets do not count (a vault's
/// curve rises in front of its lowest member). Nodes over several sides of more than one
/// surface or piece count as sheltered.
pub(crate) fn sheltered(cx: &Context, owner: Owner, at: &Footprint, depth: f32) -> bool {
    let n = at.normal;
    // The slab in front; the world's box of the members, shrunk across the plane by the lift
    // and reaching `depth` in front; and their bounds in the plane's frame, shrunk by the lift.
    let pad = Vec3::splat(cx.lift) * (Vec3::ONE - n.abs());
    let (lo, hi) = (at.world.0 + pad, at.world.1 - pad);
    let (lo, hi) = (lo.min(lo + depth * n), hi.max(hi + depth * n));
    let [u, v] = at.axes;
    let planes = [
        (n, at.base + cx.lift),
        (-n, -(at.base + depth)),
        (u, at.lo[0] + cx.lift),
        (-u, -(at.hi[0] - cx.lift)),
        (v, at.lo[1] + cx.lift),
        (-v, -(at.hi[1] - cx.lift)),
    ];
    match owner {
        Owner::Several => true,
        Owner::Side(side) => {
            let surface = side / 2;
            in_front(cx, (lo, hi), &planes, |tri| tri.surface != surface)
        }
        Owner::Piece(piece) => in_front(cx, (lo, hi), &planes, |tri| {
            let side = crate::sampling::side_of(tri.surface, false);
            cx.pieces.of(side) != Some(piece) && cx.pieces.of(side + 1) != Some(piece)
        }),
    }
}

/// Whether something hovers within `depth` in front of sample `k`, over the disc of its
/// influence radius: a light fixture just under a ceiling, seen from a sample beside it as well
/// as from one under it. Geometry that reaches down to the side's plane (a wall meeting it, a
/// box standing on it) does not hover: the coherence tests see to it.
pub(crate) fn hovered_sample(cx: &Context, k: usize, depth: f32) -> bool {
    let (p, n) = (cx.samples.position[k], cx.samples.normal[k]);
    let surface = crate::sampling::surface_of(cx.samples.side[k]);
    let half = cx.samples.radius[k] * (Vec3::ONE - n * n).max(Vec3::ZERO).sqrt();
    let (lo, hi) = (p - half, p + half);
    let (blo, bhi) = (lo.min(lo + depth * n), hi.max(hi + depth * n));
    let base = n.dot(p);
    let slab = [(n, base + cx.lift), (-n, -(base + depth))];
    in_front(cx, (blo, bhi), &slab, |tri| {
        tri.surface != surface && {
            let lowest = tri
                .vertices
                .iter()
                .map(|v| n.dot(*v) - base)
                .fold(f32::INFINITY, f32::min);
            lowest > 2.0 * cx.lift
        }
    })
}

/// Whether a triangle that `keep` accepts has a part inside every half-space n · x ≥ c of
/// `planes` and inside the box [lo, hi].
fn in_front(
    cx: &Context,
    (lo, hi): (Vec3, Vec3),
    planes: &[(Vec3, f32)],
    keep: impl Fn(&crate::scene::Triangle) -> bool,
) -> bool {
    let mut poly: Vec<Vec3> = Vec::with_capacity(9);
    let mut scratch: Vec<Vec3> = Vec::with_capacity(9);
    cx.grid.any(lo, hi, |t| {
        let tri = &cx.scene.triangles[t as usize];
        if !keep(tri) {
            return false;
        }
        poly.clear();
        poly.extend_from_slice(&tri.vertices);
        for &(n, c) in planes {
            clip_half_space(&mut poly, &mut scratch, n, c);
        }
        clip_box(&mut poly, &mut scratch, lo, hi)
    })
}

/// Whether a triangle meets an axis-aligned box (clipped to its six planes, something is left).
fn meets_box(t: &[Vec3; 3], lo: Vec3, hi: Vec3) -> bool {
    let (tlo, thi) = bounds(t);
    if tlo.cmpgt(hi).any() || thi.cmplt(lo).any() {
        return false;
    }
    let mut poly: Vec<Vec3> = t.to_vec();
    clip_box(&mut poly, &mut Vec::with_capacity(9), lo, hi)
}

/// Clips a convex polygon to an axis-aligned box; whether something is left.
fn clip_box(poly: &mut Vec<Vec3>, scratch: &mut Vec<Vec3>, lo: Vec3, hi: Vec3) -> bool {
    for axis in 0..3 {
        let mut n = Vec3::ZERO;
        n[axis] = 1.0;
        clip_half_space(poly, scratch, n, lo[axis]);
        clip_half_space(poly, scratch, -n, -hi[axis]);
        if poly.is_empty() {
            return false;
        }
    }
    true
}

/// Clips a convex polygon to the half-space n·x ≥ c (closed, so a polygon touching the plane
/// keeps its touching points).
fn clip_half_space(poly: &mut Vec<Vec3>, scratch: &mut Vec<Vec3>, n: Vec3, c: f32) {
    scratch.clear();
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (da, db) = (n.dot(a) - c, n.dot(b) - c);
        if da >= 0.0 {
            scratch.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            scratch.push(a + (b - a) * (da / (da - db)));
        }
    }
    std::mem::swap(poly, scratch);
}

fn bounds(v: &[Vec3; 3]) -> (Vec3, Vec3) {
    (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]))
}
