//! Representative areas (`docs/method.md` §4 and §10, eqs. 4-6): each surface side is cut by a regular grid of
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

mod split;

use glam::{DVec3, Vec2};

use crate::error::Result;
use crate::exec::Exec;
use crate::parallel::{for_chunks, Report};
use crate::sampling::shares::{self, Shares};
use crate::sampling::{surface_of, AreaCell, Samples, SurfaceMap, CELL_UNITS};
use crate::visibility::Visibility;

/// What the area computation did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct AreaStats {
    /// Non-empty cells.
    pub cells: usize,
    /// Cells with no visible sample within R, given to the nearest one.
    pub orphan_cells: usize,
    /// Visibility queries (cells to samples on obstructed sides).
    pub queries: u64,
}

/// Computes every sample's area `S` with the fall-off `alpha`, on `exec`'s threads and ranks
/// (the result depends on neither: the split's runs are dealt to the ranks and all-gathered). With
/// `changed` (per side), only the sides it marks are recomputed: the
/// others keep the cells and shares the last computation gave them (their samples and radii
/// must not have changed since). `report` hears the share of cells done now and then; if it
/// answers Stop, the cells not split yet go whole to their nearest sample, so every side's
/// area is still conserved.
pub(crate) fn compute(
    samples: &mut Samples,
    places: &crate::sampling::Layout,
    vis: &dyn Visibility,
    alpha: f32,
    exec: Exec,
    changed: Option<&[bool]>,
    report: Report,
) -> Result<AreaStats> {
    let (maps, epsilon, threads) = (places.maps(), places.epsilon(), exec.threads);
    let sides = 2 * maps.len();
    // A curved piece's cells are shared among all its samples: a change on any of its sides
    // redoes them all.
    let changed: Option<Vec<bool>> = changed.map(|c| {
        let mut widened = c.to_vec();
        let pieces = places.pieces();
        for p in 0..pieces.len() as u32 {
            let any = pieces
                .sides(p)
                .iter()
                .any(|&s| c.get(s as usize).copied().unwrap_or(true));
            if any {
                for &s in pieces.sides(p) {
                    if let Some(w) = widened.get_mut(s as usize) {
                        *w = true;
                    }
                }
            }
        }
        widened
    });
    let changed = changed.as_deref();
    let redo = |side: usize| changed.is_none_or(|c| c.get(side).copied().unwrap_or(true));
    let kept = if changed.is_some() {
        previous_cells(samples, sides)
    } else {
        vec![0..0; sides]
    };
    let layout = lay_cells(
        samples,
        places.index(),
        maps,
        epsilon,
        threads,
        &redo,
        &kept,
    )?;
    let mut stats = AreaStats {
        cells: layout.cells.len(),
        ..AreaStats::default()
    };
    let reads = split::Reads {
        maps,
        index: places.index(),
        obstruction: places.obstruction(),
        vis,
        alpha,
    };
    let runs = split::Splitter::new(samples, reads).count(&layout, threads, exec.ranks, report)?;
    for run in &runs {
        stats.queries += run.queries;
        stats.orphan_cells += run.orphans;
    }
    gather_shares(samples, reads, layout, runs, &redo, exec)?;
    region_centroids(samples, threads)?;
    Ok(stats)
}

/// The range of `samples.cells` each side holds from the last computation.
fn previous_cells(samples: &Samples, sides: usize) -> Vec<std::ops::Range<usize>> {
    (0..sides)
        .map(|side| samples.cells_of(side as u32))
        .collect()
}

/// The cells of one computation, side by side: kept cells where a side did not change (each
/// with its old index), new ones (to split among samples) elsewhere.
struct Layout {
    cells: Vec<Laid>,
    /// Per side: where its cells start in `cells` (length sides + 1).
    start: Vec<u32>,
    /// Per side: half the width of its new cells.
    half: Vec<f32>,
    /// Per old cell: its new index (`u32::MAX` if dropped).
    moved: Vec<u32>,
}

/// A cell of the layout (16 bytes: a round lays out some 16 a sample).
#[derive(Clone, Copy)]
struct Laid {
    /// Its index in the last computation if kept (its shares are kept too), else `u32::MAX`.
    old: u32,
    /// Area (0 for a kept cell).
    area: f32,
    /// Centroid, 2D (on its side's surface).
    centroid: Vec2,
}

impl Laid {
    fn is_new(&self) -> bool {
        self.old == u32::MAX
    }
}

impl Layout {
    /// The side cell `c` lies on.
    fn side_of(&self, c: usize) -> u32 {
        crate::sampling::side_at(&self.start, c)
    }
}

/// Cuts every changed side into cells (clipped side by side in parallel) and lists them with
/// the kept ones.
fn lay_cells(
    samples: &Samples,
    index: &crate::sampling::SideIndex,
    maps: &[SurfaceMap],
    epsilon: f32,
    threads: usize,
    redo: &(dyn Fn(usize) -> bool + Sync),
    kept: &[std::ops::Range<usize>],
) -> Result<Layout> {
    // Per side: the smallest radius among its samples sets the cell size (ε bounds it where a
    // side has only initial samples).
    let sides = 2 * maps.len();
    let mut smallest = vec![f32::INFINITY; sides];
    let mut count = vec![0usize; sides];
    for (&side, &d) in samples.side.iter().zip(&samples.radius) {
        smallest[side as usize] = smallest[side as usize].min(d);
        count[side as usize] += 1;
    }
    // A curved piece's sides without samples of their own have cells too: the piece's
    // samples share them.
    let active: Vec<usize> = (0..sides)
        .filter(|&side| count[side] > 0 || index.piece_has_samples(side as u32))
        .collect();
    let mut clipped: Vec<Clipped> = vec![(0.0, Vec::new()); active.len()];
    for_chunks(&mut clipped, 1, threads, |i, out| {
        let side = active[i];
        if !redo(side) {
            return Ok(());
        }
        let map = &maps[surface_of(side as u32) as usize];
        let cell = cell_size(map, epsilon.min(smallest[side]), count[side].max(1));
        out[0].0 = cell;
        clip_cells(map, cell, &mut out[0].1);
        Ok(())
    })?;
    // Memory: every side's list is freed as soon as it is laid out, and the layout is
    // reserved exactly (the cells are this phase's largest arrays after the shares).
    let total: usize = active
        .iter()
        .zip(&clipped)
        .map(|(&side, c)| {
            if redo(side) {
                c.1.len()
            } else {
                kept[side].len()
            }
        })
        .sum();
    let mut layout = Layout {
        cells: Vec::with_capacity(total),
        start: vec![0; sides + 1],
        half: vec![0.0; sides],
        moved: vec![u32::MAX; samples.cells.len()],
    };
    let mut at = 0;
    for (&side, (cell, list)) in active.iter().zip(clipped) {
        // Sides without cells start where the next one does.
        for s in &mut layout.start[at..=side] {
            *s = layout.cells.len() as u32;
        }
        at = side + 1;
        if !redo(side) {
            for i in kept[side].clone() {
                layout.moved[i] = layout.cells.len() as u32;
                layout.cells.push(Laid {
                    old: i as u32,
                    area: 0.0,
                    centroid: Vec2::ZERO,
                });
            }
            continue;
        }
        layout.half[side] = 0.5 * cell;
        layout
            .cells
            .extend(list.into_iter().map(|(_, area, centroid)| Laid {
                old: u32::MAX,
                area: area as f32,
                centroid,
            }));
    }
    for s in &mut layout.start[at..] {
        *s = layout.cells.len() as u32;
    }
    Ok(layout)
}

/// Gathers the shares by sample, in cell order within each sample (a counting sort): a sample
/// on a kept side keeps its shares (their cells renumbered), the others take the new ones,
/// written in place by the second pass of the split. The old shares are freed before the new
/// array is allocated (kept ones copied out first), so the two are not held at once.
fn gather_shares(
    samples: &mut Samples,
    reads: split::Reads,
    layout: Layout,
    mut runs: Vec<split::Run>,
    redo: &dyn Fn(usize) -> bool,
    exec: Exec,
) -> Result<()> {
    let (threads, ranks) = (exec.threads, exec.ranks);
    let maps = reads.maps;
    let n = samples.len();
    // Samples of the last computation on sides that did not change keep their shares.
    let old_starts = samples.shares.start.len();
    let kept_sample = |k: usize| !redo(samples.side[k] as usize) && k + 1 < old_starts;
    let mut start = vec![0u32; n + 1];
    for k in 0..n {
        if kept_sample(k) {
            start[k + 1] = samples.shares.range(k).len() as u32;
        }
    }
    for (k, count) in split::counts(&runs) {
        start[k as usize + 1] += count;
    }
    for k in 0..n {
        start[k + 1] += start[k];
    }
    let kept: Vec<(u32, u16)> = (0..n)
        .filter(|&k| kept_sample(k))
        .flat_map(|k| samples.shares.of(k))
        .map(|(c, u)| (layout.moved.get(c as usize).copied().unwrap_or(0), u))
        .collect();
    samples.shares = Shares::default();
    let mut next = start.clone();
    let writer = shares::Writer::new(start);
    // Per sample: the cell of its last share written so far.
    let mut last = vec![split::NONE; n];
    let mut kept = kept.into_iter();
    for k in 0..n {
        if kept_sample(k) {
            // A kept sample holds only its old shares (the old array is gone by now).
            let count = (next[k + 1] - next[k]) as usize;
            for (c, u) in kept.by_ref().take(count) {
                let previous = (last[k] != split::NONE).then_some(last[k]);
                writer.write(next[k] as usize, k, previous, c, u);
                last[k] = c;
                next[k] += 1;
            }
        }
    }
    split::place(&mut runs, &mut next, &mut last);
    drop((next, last));
    split::Splitter::new(samples, reads).fill(&layout, &mut runs, threads, &writer, ranks)?;
    drop(runs);
    samples.shares = writer.finish();

    let old = std::mem::take(&mut samples.cells);
    let cell_start = layout.start;
    // A kept side keeps its cells' width; a side without cells has none.
    let mut cell_half = layout.half;
    for (side, half) in cell_half.iter_mut().enumerate() {
        if cell_start[side] == cell_start[side + 1] {
            *half = 0.0;
        } else if !redo(side) {
            *half = samples.cell_half.get(side).copied().unwrap_or(0.0);
        }
    }
    let mut cells = Vec::with_capacity(layout.cells.len());
    for (side, w) in cell_start.windows(2).enumerate() {
        let map = &maps[surface_of(side as u32) as usize];
        cells.extend(layout.cells[w[0] as usize..w[1] as usize].iter().map(|c| {
            if c.is_new() {
                AreaCell {
                    centroid: map.to_3d(c.centroid),
                    area: c.area,
                }
            } else {
                old[c.old as usize]
            }
        }));
    }
    drop(old);
    samples.cells = cells;
    samples.cell_start = cell_start;
    samples.cell_half = cell_half;

    // Each sample's area: the sum of its shares, in their order.
    let mut area = std::mem::take(&mut samples.area);
    area.resize(n, 0.0);
    let shared: &Samples = samples;
    for_chunks(&mut area, 4096, threads, |first, chunk| {
        for (a, k) in chunk.iter_mut().zip(first..) {
            *a = shared
                .shares
                .of(k)
                .map(|(c, u)| {
                    let cell = shared.cells.get(c as usize).map_or(0.0, |c| c.area);
                    f64::from(u) * f64::from(cell)
                })
                .sum::<f64>()
                / f64::from(CELL_UNITS);
        }
        Ok(())
    })?;
    samples.area = area;
    Ok(())
}

/// Each sample's region centroid: the area-weighted centre of its shares (its position if it
/// holds none).
fn region_centroids(samples: &mut Samples, threads: usize) -> Result<()> {
    let mut centroids = std::mem::take(&mut samples.centroid);
    let shared: &Samples = samples;
    for_chunks(&mut centroids, 4096, threads, |first, chunk| {
        for (c, k) in chunk.iter_mut().zip(first..) {
            let mut mass = 0.0f64;
            let mut sum = DVec3::ZERO;
            for (cell, a) in shared.shares_of(k) {
                mass += f64::from(a);
                sum += f64::from(a) * shared.cells[cell as usize].centroid.as_dvec3();
            }
            *c = if mass > 0.0 {
                (sum / mass).as_vec3()
            } else {
                shared.position[k]
            };
        }
        Ok(())
    })?;
    samples.centroid = centroids;
    Ok(())
}

/// A side's clipped cells: the grid's cell size, and (key, area, centroid) of each cell.
type Clipped = (f32, Vec<(u64, f64, Vec2)>);

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cell_is_split_into_units_that_add_up_to_it() {
        // By hand: 65535 x (1/2, 1/4, 1/4) = 32767.5, 16383.75, 16383.75; the floors leave 2
        // units, which go to the two largest remainders (0.75 each).
        let (mut units, mut rest) = (Vec::new(), Vec::new());
        split::split_units([0.5, 0.25, 0.25].into_iter(), &mut units, &mut rest);
        assert_eq!(units, [32767, 16384, 16384]);
        // Any split: the whole cell, each part within one unit of its exact share.
        let parts: Vec<f64> = (1..=13).map(|i| f64::from(i * i)).collect();
        let total: f64 = parts.iter().sum();
        split::split_units(parts.iter().map(|p| p / total), &mut units, &mut rest);
        assert_eq!(units.iter().map(|&u| u32::from(u)).sum::<u32>(), CELL_UNITS);
        for (p, &u) in parts.iter().zip(&units) {
            assert!((p / total * f64::from(CELL_UNITS) - f64::from(u)).abs() < 1.0);
        }
        // One part takes it all.
        split::split_units([1.0].into_iter(), &mut units, &mut rest);
        assert_eq!(units, [u16::MAX]);
    }

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
