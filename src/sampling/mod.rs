//! Sample points on the reflecting surface sides: storage (structure of arrays), a per-side
//! spatial index for range queries, initial Poisson-disk placement (eq. 3) and adaptive
//! addition (eqs. 7-8).

pub mod adaptive;
pub(crate) mod cover;
pub(crate) mod directions;
pub mod free_path;
mod layout;
pub mod lit;
pub mod obstruction;
pub(crate) mod pieces;
pub mod poisson;
pub(crate) mod reflectance;
pub(crate) mod shares;
pub mod surface_map;
pub(crate) mod triangles;

use glam::{Vec2, Vec3};

use crate::scene::Scene;
pub(crate) use layout::Layout;
pub use lit::lit_sides;
pub use obstruction::Obstruction;
pub(crate) use shares::Shares;
pub use surface_map::SurfaceMap;

/// The side item `i` lies on, where `start[side]` is the first item of each side (items side
/// by side in side order, as the area cells are).
pub(crate) fn side_at(start: &[u32], i: usize) -> Side {
    (start.partition_point(|&s| s as usize <= i) as u32).saturating_sub(1)
}

/// A cell's whole area in share units: a cell is split among its samples in parts of
/// 1 / `CELL_UNITS` (see [`Samples`]' shares).
pub(crate) const CELL_UNITS: u32 = u16::MAX as u32;

/// A surface side: `2 × surface + 1` for the back, `2 × surface` for the front. Samples, areas
/// and interpolation never mix sides.
pub type Side = u32;

/// The side id of a surface's front or back.
pub fn side_of(surface: u32, back: bool) -> Side {
    2 * surface + u32::from(back)
}

/// The surface of a side.
pub fn surface_of(side: Side) -> u32 {
    side / 2
}

/// Whether a side is a back side.
pub fn is_back(side: Side) -> bool {
    side % 2 == 1
}

/// The sides that reflect light: fronts, and backs of two-sided surfaces, whose material has
/// a non-zero reflectance. Only these get samples.
pub fn reflecting_sides(scene: &Scene) -> Vec<Side> {
    let mut sides = Vec::new();
    for (i, s) in scene.surfaces.iter().enumerate() {
        if scene.materials[s.material as usize].reflects_diffusely() {
            sides.push(side_of(i as u32, false));
            if s.two_sided {
                sides.push(side_of(i as u32, true));
            }
        }
    }
    sides
}

/// The sample points, structure of arrays. Read through its accessors; only the solver
/// changes them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Samples {
    /// Positions, on their surfaces.
    pub(crate) position: Vec<Vec3>,
    /// Unit normal of the side each sample is on.
    pub(crate) normal: Vec<Vec3>,
    /// 2D position in its surface's frame.
    pub(crate) uv: Vec<Vec2>,
    /// The side each sample is on.
    pub(crate) side: Vec<Side>,
    /// Influence radius D (eq. 3: ε initially; shrunk by adaptive rounds).
    pub(crate) radius: Vec<f32>,
    /// Representative area S (eqs. 4-6).
    pub(crate) area: Vec<f64>,
    /// Centroid of each sample's shares of area (its region): form factors are taken between
    /// region centroids, since a sample's radiosity stands for its region's average.
    pub(crate) centroid: Vec<Vec3>,
    /// The shares of area cells each sample holds (eq. 5), 4 bytes each (see [`Shares`]).
    /// The shares of a cell add up to the cell exactly, so they tile the surfaces; near
    /// shooters are integrated over them.
    pub(crate) shares: Shares,
    /// The area cells (pieces of surface), side by side in side order.
    pub(crate) cells: Vec<AreaCell>,
    /// Per side: where its cells start in `cells` (length sides + 1 once areas are computed).
    pub(crate) cell_start: Vec<u32>,
    /// Per side: half the width of the grid cells it was cut into.
    pub(crate) cell_half: Vec<f32>,
    /// The adaptive round in which each sample was added (0 = initial Poisson disk).
    pub(crate) round: Vec<u16>,
    /// Each sample's diffuse reflectance when the scene has textures (see
    /// [`reflectance::means`]); empty otherwise, and then each sample's is its material's Kd.
    pub(crate) reflectance: Vec<Vec3>,
}

impl Samples {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Positions, on their surfaces.
    pub fn position(&self) -> &[Vec3] {
        &self.position
    }

    /// Unit normal of the side each sample is on.
    pub fn normal(&self) -> &[Vec3] {
        &self.normal
    }

    /// Influence radius D of each sample (eq. 3: ε initially; shrunk by adaptive rounds).
    pub fn radius(&self) -> &[f32] {
        &self.radius
    }

    /// Representative area S of each sample (eqs. 4-6).
    pub fn area(&self) -> &[f64] {
        &self.area
    }

    /// The adaptive round in which each sample was added (0 = initial Poisson disk).
    pub fn round(&self) -> &[u16] {
        &self.round
    }

    /// The scene surface sample k lies on (an index into [`Scene::surfaces`](crate::Scene)).
    pub fn surface(&self, k: usize) -> u32 {
        surface_of(self.side[k])
    }

    /// Whether sample k lies on the back of its surface (two-sided surfaces only).
    pub fn is_back(&self, k: usize) -> bool {
        is_back(self.side[k])
    }

    /// Appends one sample (area 0 until areas are computed).
    pub(crate) fn push(
        &mut self,
        maps: &[SurfaceMap],
        side: Side,
        uv: Vec2,
        radius: f32,
        round: u16,
    ) {
        let map = &maps[surface_of(side) as usize];
        self.position.push(map.to_3d(uv));
        self.normal.push(if is_back(side) {
            -map.normal
        } else {
            map.normal
        });
        self.uv.push(uv);
        self.side.push(side);
        self.radius.push(radius);
        self.area.push(0.0);
        self.centroid.push(map.to_3d(uv));
        self.round.push(round);
    }

    /// Bytes the samples hold (their arrays' capacities), for the memory budget: their own
    /// arrays, the area cells, and the shares.
    pub(crate) fn bytes(&self) -> (usize, usize, usize) {
        (
            vec_bytes(&self.position)
                + vec_bytes(&self.normal)
                + vec_bytes(&self.uv)
                + vec_bytes(&self.side)
                + vec_bytes(&self.radius)
                + vec_bytes(&self.area)
                + vec_bytes(&self.centroid)
                + vec_bytes(&self.round)
                + vec_bytes(&self.reflectance),
            vec_bytes(&self.cells) + vec_bytes(&self.cell_start) + vec_bytes(&self.cell_half),
            self.shares.bytes(),
        )
    }

    /// Total area of the samples of each of `sides` sides (index: side id, `2 × surface` for
    /// the front and `2 × surface + 1` for the back); an error if a sample lies on a side
    /// beyond them.
    pub fn area_per_side(&self, sides: usize) -> crate::Result<Vec<f64>> {
        let mut total = vec![0.0; sides];
        for (&s, &a) in self.side.iter().zip(&self.area) {
            let Some(t) = total.get_mut(s as usize) else {
                return Err(crate::Error::argument(
                    "sides",
                    format!("a sample lies on side {s}, beyond the {sides} sides asked for"),
                ));
            };
            *t += a;
        }
        Ok(total)
    }
}

/// A piece of surface: an area cell clipped to the surface, seen as the square of its area
/// around its centroid.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AreaCell {
    /// Centroid.
    pub centroid: Vec3,
    /// Area.
    pub area: f32,
}

impl Samples {
    /// The range of `cells` that lies on `side` (empty before areas are computed).
    pub(crate) fn cells_of(&self, side: Side) -> std::ops::Range<usize> {
        let side = side as usize;
        match (self.cell_start.get(side), self.cell_start.get(side + 1)) {
            (Some(&a), Some(&b)) => a as usize..b as usize,
            _ => 0..0,
        }
    }

    /// The side cell `c` lies on.
    pub(crate) fn side_of_cell(&self, c: usize) -> Side {
        side_at(&self.cell_start, c)
    }

    /// Gives back what the arrays hold beyond their length: samples are pushed one by one, and
    /// a vector grown by doubling can hold twice what it uses (a million samples' worth).
    pub(crate) fn shrink_to_fit(&mut self) {
        self.position.shrink_to_fit();
        self.normal.shrink_to_fit();
        self.uv.shrink_to_fit();
        self.side.shrink_to_fit();
        self.radius.shrink_to_fit();
        self.area.shrink_to_fit();
        self.centroid.shrink_to_fit();
        self.round.shrink_to_fit();
        self.reflectance.shrink_to_fit();
    }

    /// Sample k's shares of area cells: (cell index, area).
    pub(crate) fn shares_of(&self, k: usize) -> impl Iterator<Item = (u32, f32)> + '_ {
        self.shares.of(k).map(|(c, units)| {
            let area = self.cells.get(c as usize).map_or(0.0, |cell| cell.area);
            (c, f32::from(units) * (area / CELL_UNITS as f32))
        })
    }

    /// Checks the invariants the solver keeps (run in debug builds after every area
    /// computation, and by tests): arrays of one length; samples of one side no closer than
    /// the smaller of their radii (Poisson-disk spacing, eqs. 3 and 8); shares that point at
    /// existing cells and split each cell exactly; every sampled side's areas summing to the
    /// side's area; an index that finds every sample near itself. The first broken one, in
    /// words.
    pub(crate) fn validate(&self, maps: &[SurfaceMap], index: &SideIndex) -> Result<(), String> {
        let n = self.len();
        let lengths = [
            ("normal", self.normal.len()),
            ("uv", self.uv.len()),
            ("side", self.side.len()),
            ("radius", self.radius.len()),
            ("area", self.area.len()),
            ("centroid", self.centroid.len()),
            ("round", self.round.len()),
        ];
        if let Some((name, len)) = lengths.iter().find(|(_, len)| *len != n) {
            return Err(format!("{len} {name} entries for {n} samples"));
        }
        if let Some(k) = (0..n).find(|&k| self.side[k] as usize >= 2 * maps.len()) {
            return Err(format!(
                "sample {k} lies on side {}, beyond the scene",
                self.side[k]
            ));
        }
        // Spacing, found through the index (which must find each sample at its own place).
        let mut near = Vec::new();
        for k in 0..n {
            let (side, uv, d) = (self.side[k], self.uv[k], self.radius[k]);
            index.within(self, side, uv, d, &mut near);
            if !near.iter().any(|&(j, _)| j as usize == k) {
                return Err(format!(
                    "the index does not find sample {k} at its own place"
                ));
            }
            for &(j, d2) in &near {
                let limit = d.min(self.radius[j as usize]) * (1.0 - 1e-3);
                // Across a curved piece's sides the first round keeps its spacing, and new
                // samples keep it from old ones; only one round's new samples on two sides
                // are placed apart (side by side).
                let apart = self.side[j as usize] != side
                    && self.round[j as usize] == self.round[k]
                    && self.round[k] > 0;
                if j as usize != k && !apart && d2 < limit * limit {
                    return Err(format!(
                        "samples {k} and {j} lie {} apart, closer than their radii allow ({limit})",
                        d2.sqrt()
                    ));
                }
            }
        }
        let start = &self.shares.start;
        if start.len() != n + 1 {
            // Areas not computed yet: nothing more to check.
            return Ok(());
        }
        if start.windows(2).any(|w| w[0] > w[1]) || start[n] as usize != self.shares.len() {
            return Err("share offsets out of order".into());
        }
        let mut per_cell = vec![0.0f64; self.cells.len()];
        for k in 0..n {
            let mut total = 0.0f64;
            for (c, a) in self.shares_of(k) {
                if c as usize >= self.cells.len() {
                    return Err(format!(
                        "sample {k} holds a share of cell {c}, which does not exist"
                    ));
                }
                let cell_side = self.side_of_cell(c as usize);
                if cell_side != self.side[k] && !index.together(cell_side, self.side[k]) {
                    return Err(format!(
                        "sample {k} holds a share of a cell on another side"
                    ));
                }
                per_cell[c as usize] += f64::from(a);
                total += f64::from(a);
            }
            if (total - self.area[k]).abs() > 1e-4 * total.max(1e-30) {
                return Err(format!(
                    "sample {k}'s area {} is not its shares' {total}",
                    self.area[k]
                ));
            }
        }
        for (c, (cell, &shared)) in self.cells.iter().zip(&per_cell).enumerate() {
            let a = f64::from(cell.area);
            if (shared - a).abs() > 1e-3 * a {
                return Err(format!("cell {c} of area {a} is shared out as {shared}"));
            }
        }
        let mut per_side = self
            .area_per_side(2 * maps.len())
            .map_err(|e| e.to_string())?;
        // A piece's samples carry its sides' areas together: counted on its first side.
        let expected_of = |side: usize| maps[surface_of(side as u32) as usize].area();
        let mut piece_area = vec![0.0f64; 2 * maps.len()];
        for side in 0..per_side.len() {
            if let Some(first) = index.first_of_piece(side as u32) {
                piece_area[first as usize] += expected_of(side);
                if first as usize != side {
                    per_side[first as usize] += per_side[side];
                    per_side[side] = 0.0;
                }
            }
        }
        for (side, &a) in per_side.iter().enumerate().filter(|(_, &a)| a > 0.0) {
            let expected = if piece_area[side] > 0.0 {
                piece_area[side]
            } else {
                expected_of(side)
            };
            if (a - expected).abs() > 1e-3 * expected {
                return Err(format!(
                    "side {side}'s samples carry {a} of its area {expected}"
                ));
            }
        }
        Ok(())
    }
}

/// Range queries over the samples of one side: a uniform 2D grid per side, in compressed rows.
#[derive(Clone, Debug, Default)]
pub struct SideIndex {
    /// Per side: (first cell, nx, ny, min corner, cell size); `None` for sides without samples.
    grids: Vec<Option<Grid>>,
    /// Cell k's samples are entries[starts[k]..starts[k+1]].
    starts: Vec<u32>,
    entries: Vec<u32>,
    /// The sides joined into curved pieces (`sampling::pieces`): a query on one of their sides
    /// answers with the piece's samples by distance in 3D.
    pieces: ByPiece,
}

/// The samples of each curved piece, and the frames that lift a side's 2D points to 3D.
#[derive(Clone, Debug, Default)]
struct ByPiece {
    /// Per side: its piece, or `pieces::NONE` (empty: no pieces).
    of_side: Vec<u32>,
    /// Piece p's samples are `entries[starts[p]..starts[p + 1]]`, ascending.
    starts: Vec<u32>,
    entries: Vec<u32>,
    /// Per surface: origin and in-plane axes of its map (empty: no pieces).
    frames: Vec<[Vec3; 3]>,
    /// Per piece: its first side.
    first: Vec<Side>,
}

impl ByPiece {
    fn new(samples: &Samples, maps: &[SurfaceMap], pieces: &pieces::Pieces) -> ByPiece {
        if pieces.len() == 0 {
            return ByPiece::default();
        }
        let of_side: Vec<u32> = (0..2 * maps.len() as u32)
            .map(|side| pieces.of(side).unwrap_or(pieces::NONE))
            .collect();
        let mut starts = vec![0u32; pieces.len() + 1];
        for &side in &samples.side {
            if let Some(&p) = of_side.get(side as usize).filter(|&&p| p != pieces::NONE) {
                starts[p as usize + 1] += 1;
            }
        }
        for p in 0..pieces.len() {
            starts[p + 1] += starts[p];
        }
        let mut next = starts.clone();
        let mut entries = vec![0u32; starts[pieces.len()] as usize];
        for (k, &side) in samples.side.iter().enumerate() {
            if let Some(&p) = of_side.get(side as usize).filter(|&&p| p != pieces::NONE) {
                entries[next[p as usize] as usize] = k as u32;
                next[p as usize] += 1;
            }
        }
        ByPiece {
            of_side,
            starts,
            entries,
            frames: maps.iter().map(|m| [m.origin, m.u, m.v]).collect(),
            first: (0..pieces.len() as u32)
                .map(|p| pieces.sides(p).first().copied().unwrap_or(0))
                .collect(),
        }
    }

    /// The piece of `side` and the 3D point of `uv` on it, if the side is in a piece.
    fn lift(&self, side: Side, uv: Vec2) -> Option<(u32, Vec3)> {
        let p = *self.of_side.get(side as usize)?;
        let [o, u, v] = *self.frames.get(surface_of(side) as usize)?;
        (p != pieces::NONE).then(|| (p, o + uv.x * u + uv.y * v))
    }

    fn samples(&self, p: u32) -> &[u32] {
        let p = p as usize;
        match (self.starts.get(p), self.starts.get(p + 1)) {
            (Some(&a), Some(&b)) if a <= b && b as usize <= self.entries.len() => {
                &self.entries[a as usize..b as usize]
            }
            _ => &[],
        }
    }
}

/// Bytes a vector holds.
pub(crate) fn vec_bytes<T>(v: &Vec<T>) -> usize {
    v.capacity() * std::mem::size_of::<T>()
}

impl SideIndex {
    /// Bytes the index holds.
    pub fn bytes(&self) -> usize {
        let p = &self.pieces;
        vec_bytes(&self.grids)
            + vec_bytes(&self.starts)
            + vec_bytes(&self.entries)
            + vec_bytes(&p.of_side)
            + vec_bytes(&p.starts)
            + vec_bytes(&p.entries)
            + vec_bytes(&p.frames)
            + vec_bytes(&p.first)
    }

    /// Whether the index holds no more sides than `sides` and only samples below `samples`
    /// (so queries on a solution a host has edited cannot reach past its arrays).
    pub fn fits(&self, sides: usize, samples: usize) -> bool {
        self.grids.len() <= sides
            && self.entries.iter().all(|&k| (k as usize) < samples)
            && self.pieces.of_side.len() <= sides
            && self.pieces.entries.iter().all(|&k| (k as usize) < samples)
            && self.starts.windows(2).all(|w| w[0] <= w[1])
            && self
                .starts
                .last()
                .is_none_or(|&e| e as usize <= self.entries.len())
    }
}

#[derive(Clone, Copy, Debug)]
struct Grid {
    first: usize,
    nx: usize,
    ny: usize,
    min: Vec2,
    cell: f32,
}

impl SideIndex {
    /// Whether two sides lie in one curved piece.
    pub(crate) fn together(&self, a: Side, b: Side) -> bool {
        let of = |s: Side| self.pieces.of_side.get(s as usize).copied();
        of(a).is_some_and(|p| p != pieces::NONE && of(b) == Some(p))
    }

    /// The first side of the curved piece `side` lies in, if any.
    pub(crate) fn first_of_piece(&self, side: Side) -> Option<Side> {
        let p = *self.pieces.of_side.get(side as usize)?;
        self.pieces.first.get(p as usize).copied()
    }

    /// Whether `side` lies in a curved piece with samples.
    pub(crate) fn piece_has_samples(&self, side: Side) -> bool {
        self.pieces
            .of_side
            .get(side as usize)
            .is_some_and(|&p| p != pieces::NONE && !self.pieces.samples(p).is_empty())
    }

    /// Indexes the samples. A side's cells are `cell` wide (ε), narrower where adaptive rounds
    /// shrank radii (down to twice the smallest radius), but never more than about four per
    /// sample of the side, so big sparse sides stay small. Sides in `pieces` are also
    /// indexed by piece.
    pub(crate) fn new(
        samples: &Samples,
        maps: &[SurfaceMap],
        cell: f32,
        pieces: &pieces::Pieces,
    ) -> SideIndex {
        let sides = 2 * maps.len();
        let mut count = vec![0usize; sides];
        let mut smallest = vec![f32::INFINITY; sides];
        for (&s, &d) in samples.side.iter().zip(&samples.radius) {
            count[s as usize] += 1;
            smallest[s as usize] = smallest[s as usize].min(d);
        }
        let mut grids = vec![None; sides];
        let mut cells = 0usize;
        for (side, &n) in count.iter().enumerate() {
            if n == 0 {
                continue;
            }
            let map = &maps[surface_of(side as u32) as usize];
            let size = (map.max - map.min).max(Vec2::splat(1e-30));
            let sparse = (map.area() as f32 / (4.0 * n as f32 + 16.0)).sqrt();
            let c = (2.0 * smallest[side])
                .min(cell)
                .max(sparse)
                .max(size.max_element() / 4096.0);
            let nx = ((size.x / c).ceil() as usize).max(1);
            let ny = ((size.y / c).ceil() as usize).max(1);
            grids[side] = Some(Grid {
                first: cells,
                nx,
                ny,
                min: map.min,
                cell: c,
            });
            cells += nx * ny;
        }
        let mut keys: Vec<(u32, u32)> = Vec::with_capacity(samples.len());
        for (k, (&side, &uv)) in samples.side.iter().zip(&samples.uv).enumerate() {
            let g = grids[side as usize].expect("a grid for every side with samples");
            let (x, y) = g.cell_of(uv);
            keys.push(((g.first + y * g.nx + x) as u32, k as u32));
        }
        keys.sort_unstable();
        let mut starts = vec![0u32; cells + 1];
        for &(c, _) in &keys {
            starts[c as usize + 1] += 1;
        }
        for c in 0..cells {
            starts[c + 1] += starts[c];
        }
        SideIndex {
            grids,
            starts,
            entries: keys.into_iter().map(|(_, k)| k).collect(),
            pieces: ByPiece::new(samples, maps, pieces),
        }
    }

    /// Calls `f(k)` for every sample k of `side` whose 2D position may lie within `r` of `uv`
    /// (a superset: callers check the distance). In ascending sample order within each cell.
    /// Sides in pieces are not asked here (see [`SideIndex::within`]).
    fn for_each_near(&self, side: Side, uv: Vec2, r: f32, mut f: impl FnMut(u32)) {
        let Some(Some(g)) = self.grids.get(side as usize) else {
            return;
        };
        let (x0, y0) = g.cell_of(uv - Vec2::splat(r));
        let (x1, y1) = g.cell_of(uv + Vec2::splat(r));
        for y in y0..=y1 {
            let row = g.first + y * g.nx;
            let (a, b) = (
                self.starts[row + x0] as usize,
                self.starts[row + x1 + 1] as usize,
            );
            for &k in &self.entries[a..b] {
                f(k);
            }
        }
    }

    /// The samples of `side` within distance `r` of `uv`, with their squared distances; for a
    /// side in a curved piece, the piece's samples within `r` in 3D (on any of its sides).
    pub fn within(
        &self,
        samples: &Samples,
        side: Side,
        uv: Vec2,
        r: f32,
        out: &mut Vec<(u32, f32)>,
    ) {
        out.clear();
        let r2 = r * r;
        if let Some((p, at)) = self.pieces.lift(side, uv) {
            for &k in self.pieces.samples(p) {
                let d2 = samples.position[k as usize].distance_squared(at);
                if d2 <= r2 {
                    out.push((k, d2));
                }
            }
            return;
        }
        self.for_each_near(side, uv, r, |k| {
            let d2 = samples.uv[k as usize].distance_squared(uv);
            if d2 <= r2 {
                out.push((k, d2));
            }
        });
    }

    /// The nearest sample of `side` to `uv` (searching outwards), if the side has any; for a
    /// side in a curved piece, the piece's nearest in 3D.
    pub fn nearest(&self, samples: &Samples, side: Side, uv: Vec2) -> Option<u32> {
        self.nearest_where(samples, side, uv, |_| true)
    }

    /// The nearest sample of `side` to `uv` among those `keep` accepts.
    pub fn nearest_where(
        &self,
        samples: &Samples,
        side: Side,
        uv: Vec2,
        keep: impl Fn(u32) -> bool,
    ) -> Option<u32> {
        if let Some((p, at)) = self.pieces.lift(side, uv) {
            let mut best: Option<(f32, u32)> = None;
            for &k in self.pieces.samples(p) {
                let d2 = samples.position[k as usize].distance_squared(at);
                if keep(k) && best.is_none_or(|(b, bk)| d2 < b || (d2 == b && k < bk)) {
                    best = Some((d2, k));
                }
            }
            return best.map(|(_, k)| k);
        }
        let g = (*self.grids.get(side as usize)?)?;
        let mut r = g.cell;
        let reach = g.cell * (g.nx.max(g.ny) as f32 + 2.0);
        loop {
            let mut best: Option<(f32, u32)> = None;
            self.for_each_near(side, uv, r, |k| {
                let d2 = samples.uv[k as usize].distance_squared(uv);
                if keep(k) && best.is_none_or(|(b, bk)| d2 < b || (d2 == b && k < bk)) {
                    best = Some((d2, k));
                }
            });
            // A hit within r is the nearest only if nothing outside the searched square is closer.
            if let Some((d2, k)) = best {
                if d2.sqrt() <= r || r > reach {
                    return Some(k);
                }
            } else if r > reach {
                return None;
            }
            r *= 2.0;
        }
    }
}

impl Grid {
    fn cell_of(&self, p: Vec2) -> (usize, usize) {
        let q = (p - self.min) / self.cell;
        (
            (q.x.max(0.0) as usize).min(self.nx - 1),
            (q.y.max(0.0) as usize).min(self.ny - 1),
        )
    }
}
