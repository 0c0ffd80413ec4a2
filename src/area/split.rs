//! Splitting the new area cells among the samples (eq. 5), and gathering every sample's
//! shares in one array by sample.
//!
//! A round's shares are the largest arrays of a solve (some 120 a sample), so they are written
//! once, in place, in two passes over runs of cells: the first finds each cell's samples (range
//! queries, and visibility along obstructed sides) and keeps only how many shares each sample
//! gets from the run and the visibility answers (a bit each); the coordinator turns the counts
//! into the slots each run writes; the second pass finds the same samples again, replaying the
//! answers instead of asking the backend, and writes each share into its slot. No list of
//! shares by cell is ever held beside the array by sample. The runs are fixed, so the shares'
//! order (cell order within each sample) does not depend on the thread count.

use std::sync::atomic::{AtomicU16, AtomicU32, Ordering};

use glam::Vec2;

use super::{Laid, Layout};
use crate::error::{Error, Result};
use crate::parallel::{for_chunks, for_chunks_reporting, Report};
use crate::sampling::{surface_of, Obstruction, Samples, Side, SideIndex, SurfaceMap, CELL_UNITS};
use crate::visibility::Visibility;

/// Cells per run.
const RUN: usize = 1024;

/// What splitting a cell among samples reads.
pub(super) struct Splitter<'a> {
    pub samples: &'a Samples,
    pub maps: &'a [SurfaceMap],
    pub index: &'a SideIndex,
    pub obstruction: &'a Obstruction,
    pub vis: &'a dyn Visibility,
    pub alpha: f32,
}

/// What the first pass learned about a run of cells.
#[derive(Clone, Debug, Default)]
pub(super) struct Run {
    /// Whether the run was split; a stopped computation gives later runs' cells whole to
    /// their nearest samples.
    done: bool,
    /// (sample, shares it gets from the run) in sample order; once placed, (sample, the slot
    /// of its next share).
    slots: Vec<(u32, u32)>,
    /// The visibility answers of the run's cells on obstructed sides, in the order asked.
    seen: Bits,
    /// Cells with no visible sample within R, given to the nearest one.
    pub orphans: usize,
    /// Visibility queries made.
    pub queries: u64,
}

/// A growable bit list.
#[derive(Clone, Debug, Default)]
struct Bits {
    words: Vec<u64>,
    len: usize,
}

impl Bits {
    fn push(&mut self, bit: bool) {
        if self.len % 64 == 0 {
            self.words.push(0);
        }
        if bit {
            self.words[self.len / 64] |= 1 << (self.len % 64);
        }
        self.len += 1;
    }

    fn get(&self, i: usize) -> bool {
        i < self.len && self.words[i / 64] >> (i % 64) & 1 == 1
    }
}

/// Where the visibility answers come from: the backend (recorded), or the first pass's record.
enum Answers<'r> {
    Ask {
        seen: &'r mut Bits,
        queries: &'r mut u64,
        asked: Vec<u32>,
    },
    Replay {
        seen: &'r Bits,
        at: usize,
    },
}

/// Scratch lists of one worker: a cell's samples (sample, d²) and their units.
#[derive(Default)]
struct Scratch {
    near: Vec<(u32, f32)>,
    units: Vec<u16>,
}

impl Splitter<'_> {
    /// The first pass: each run's shares per sample and visibility answers. Reports progress;
    /// after a Stop the runs not done are marked so, and [`Splitter::fill`] gives their cells
    /// whole to the nearest sample.
    pub fn count(&self, layout: &Layout, threads: usize, report: Report) -> Result<Vec<Run>> {
        let cells = &layout.cells;
        let mut runs = vec![Run::default(); cells.len().div_ceil(RUN)];
        let count = |r: usize, out: &mut [Run]| {
            let run = &mut out[0];
            let mut scratch = Scratch::default();
            let mut samples = Vec::new();
            let mut answers = Answers::Ask {
                seen: &mut run.seen,
                queries: &mut run.queries,
                asked: Vec::new(),
            };
            let ids = r * RUN..((r + 1) * RUN).min(cells.len());
            for (cell, id) in cells[ids.clone()].iter().zip(ids) {
                if !cell.is_new() {
                    continue;
                }
                let side = layout.side_of(id);
                if self.of_cell(side, cell, &mut answers, &mut scratch)? {
                    run.orphans += 1;
                }
                samples.extend(
                    scratch
                        .near
                        .iter()
                        .zip(&scratch.units)
                        .filter_map(|(&(k, _), &u)| (u > 0).then_some(k)),
                );
            }
            run.seen.words.shrink_to_fit();
            run.slots = tally(samples);
            run.done = true;
            Ok(())
        };
        if !for_chunks_reporting(&mut runs, 1, threads, count, report)? {
            for (r, run) in runs.iter_mut().enumerate().filter(|(_, run)| !run.done) {
                let nearest = (r * RUN..((r + 1) * RUN).min(cells.len()))
                    .filter(|&id| cells[id].is_new())
                    .filter_map(|id| self.nearest(layout.side_of(id), cells[id].centroid));
                run.slots = tally(nearest.collect());
            }
        }
        Ok(runs)
    }

    /// The second pass: every run's shares written into the slots `place` gave its samples,
    /// as (cell, units) in `shares` and `units`.
    pub fn fill(
        &self,
        layout: &Layout,
        runs: &mut [Run],
        threads: usize,
        (shares, units): (&[AtomicU32], &[AtomicU16]),
    ) -> Result<()> {
        let cells = &layout.cells;
        let fill = |r: usize, out: &mut [Run]| {
            let run = &mut out[0];
            let mut write = |k: u32, id: usize, u: u16| -> Result<()> {
                let slot = match run.slots.binary_search_by_key(&k, |s| s.0) {
                    Ok(i) => {
                        run.slots[i].1 += 1;
                        run.slots[i].1 - 1
                    }
                    Err(_) => u32::MAX,
                } as usize;
                match (shares.get(slot), units.get(slot)) {
                    (Some(s), Some(v)) => {
                        s.store(id as u32, Ordering::Relaxed);
                        v.store(u, Ordering::Relaxed);
                        Ok(())
                    }
                    _ => Err(Error::Worker {
                        problem: format!(
                            "splitting area cell {id}: sample {k} was not counted (the \
                             visibility backend answered differently)"
                        ),
                    }),
                }
            };
            let ids = r * RUN..((r + 1) * RUN).min(cells.len());
            if !run.done {
                for id in ids.filter(|&id| cells[id].is_new()) {
                    if let Some(k) = self.nearest(layout.side_of(id), cells[id].centroid) {
                        write(k, id, CELL_UNITS as u16)?;
                    }
                }
                return Ok(());
            }
            let seen = std::mem::take(&mut run.seen);
            let mut answers = Answers::Replay { seen: &seen, at: 0 };
            let mut scratch = Scratch::default();
            for id in ids.filter(|&id| cells[id].is_new()) {
                self.of_cell(layout.side_of(id), &cells[id], &mut answers, &mut scratch)?;
                for (&(k, _), &u) in scratch.near.iter().zip(&scratch.units) {
                    if u > 0 {
                        write(k, id, u)?;
                    }
                }
            }
            Ok(())
        };
        for_chunks(runs, 1, threads, fill)
    }

    fn nearest(&self, side: Side, centroid: Vec2) -> Option<u32> {
        self.index.nearest(self.samples, side, centroid)
    }

    /// The samples a new cell is split among, as (sample, d²) in `scratch.near`, with their
    /// units (some may be 0) in `scratch.units`: those of its side within R of it (eq. 5),
    /// else, sealed off, the nearest it sees. Whether it was sealed off.
    fn of_cell(
        &self,
        side: Side,
        cell: &Laid,
        answers: &mut Answers,
        scratch: &mut Scratch,
    ) -> Result<bool> {
        let (samples, index) = (self.samples, self.index);
        let Scratch { near, units } = scratch;
        near.clear();
        units.clear();
        let centroid = cell.centroid;
        let Some(nearest) = index.nearest(samples, side, centroid) else {
            return Ok(false);
        };
        let map = &self.maps[surface_of(side) as usize];
        let r = 2.0 * samples.radius[nearest as usize];
        index.within(samples, side, centroid, r, near);
        let point = map.to_3d(centroid);
        self.filter(side, point, near, answers)?;
        if near.is_empty() {
            // Sealed off within R: the nearest sample it sees further out, else the nearest.
            index.within(samples, side, centroid, 4.0 * r, near);
            near.sort_unstable_by(|x, y| x.1.total_cmp(&y.1).then(x.0.cmp(&y.0)));
            near.truncate(16);
            self.filter(side, point, near, answers)?;
            let k = near.first().map_or(nearest, |n| n.0);
            near.clear();
            near.push((k, 0.0));
            units.push(CELL_UNITS as u16);
            return Ok(true);
        }
        // Ascending sample order: the sum does not depend on the grid's iteration order.
        near.sort_unstable_by_key(|&(k, _)| k);
        let weight = |d2: f32| f64::from((-self.alpha * d2.sqrt() / r).exp());
        let total: f64 = near.iter().map(|&(_, d2)| weight(d2)).sum();
        split_units(near.iter().map(|&(_, d2)| weight(d2) / total), units);
        Ok(false)
    }

    /// Keeps the candidates `point` sees along its side (where other geometry stands on it),
    /// asking the backend and recording its answers, or replaying them.
    fn filter(
        &self,
        side: Side,
        point: glam::Vec3,
        near: &mut Vec<(u32, f32)>,
        answers: &mut Answers,
    ) -> Result<()> {
        if !self.obstruction.is_obstructed(side) || near.is_empty() {
            return Ok(());
        }
        match answers {
            Answers::Ask {
                seen,
                queries,
                asked,
            } => {
                asked.clear();
                asked.extend(near.iter().map(|&(k, _)| k));
                **queries += self.obstruction.retain_visible(
                    self.vis,
                    self.maps,
                    self.samples,
                    side,
                    point,
                    near,
                )?;
                // What is left is a subsequence of what was asked (each sample once).
                let mut left = near.iter().peekable();
                for &k in asked.iter() {
                    let kept = left.next_if(|n| n.0 == k).is_some();
                    seen.push(kept);
                }
            }
            Answers::Replay { seen, at } => {
                near.retain(|_| {
                    *at += 1;
                    seen.get(*at - 1)
                });
            }
        }
        Ok(())
    }
}

/// (sample, how many times it occurs), in sample order.
fn tally(mut samples: Vec<u32>) -> Vec<(u32, u32)> {
    samples.sort_unstable();
    let mut out: Vec<(u32, u32)> = Vec::new();
    for k in samples {
        match out.last_mut() {
            Some(last) if last.0 == k => last.1 += 1,
            _ => out.push((k, 1)),
        }
    }
    out.shrink_to_fit();
    out
}

/// Splits a cell's [`CELL_UNITS`] among parts (fractions adding up to 1) by largest
/// remainders, so that the units add up to the whole cell exactly; ties go to the earlier part.
pub(super) fn split_units(parts: impl Iterator<Item = f64>, units: &mut Vec<u16>) {
    let whole = f64::from(CELL_UNITS);
    let mut rest: Vec<(f64, usize)> = Vec::new();
    units.clear();
    let mut given = 0u32;
    for (i, p) in parts.enumerate() {
        let exact = (p * whole).clamp(0.0, whole);
        let u = exact.floor();
        units.push(u as u16);
        given += u as u32;
        rest.push((exact - u, i));
    }
    let short = CELL_UNITS.saturating_sub(given) as usize;
    if short > 0 {
        rest.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        for &(_, i) in rest.iter().cycle().take(short) {
            units[i] = units[i].saturating_add(1);
        }
    }
}

/// Gives each run the slots its samples' shares go to: after `next[k]` (the first free slot of
/// sample k), in run order, so that each sample's shares lie in cell order.
pub(super) fn place(runs: &mut [Run], next: &mut [u32]) {
    for run in runs {
        for (k, count) in &mut run.slots {
            let first = next[*k as usize];
            next[*k as usize] += *count;
            *count = first;
        }
    }
}

/// The shares each run gives each sample: (sample, count) pairs.
pub(super) fn counts(runs: &[Run]) -> impl Iterator<Item = (u32, u32)> + '_ {
    runs.iter().flat_map(|r| r.slots.iter().copied())
}
