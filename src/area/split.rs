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

use glam::Vec2;

use super::{Laid, Layout};
use crate::distributed::Ranks;
use crate::error::{Error, Result};
use crate::parallel::{for_chunks, for_chunks_halting, Report};
use crate::sampling::shares::{Writer, WHOLE};
use crate::sampling::{surface_of, Obstruction, Samples, Side, SideIndex, SurfaceMap};
use crate::visibility::Visibility;

/// Cells per run.
const RUN: usize = 1024;

/// Runs filled between two exchanges over several ranks (some four million shares).
const EXCHANGE_RUNS: usize = 512;

/// No cell (a sample's first share has no previous one).
pub(super) const NONE: u32 = u32::MAX;

/// One sample's shares from one run.
#[derive(Clone, Copy, Debug)]
struct Slot {
    sample: u32,
    /// How many (first pass); then the slot of its next share.
    next: u32,
    /// The cell of its last share in the run (first pass); then the cell of its share before
    /// the next one ([`NONE`] before its first).
    prev: u32,
}

/// What splitting a cell among samples reads besides the samples.
#[derive(Clone, Copy)]
pub(super) struct Reads<'a> {
    pub maps: &'a [SurfaceMap],
    pub index: &'a SideIndex,
    pub obstruction: &'a Obstruction,
    pub vis: &'a dyn Visibility,
    pub alpha: f32,
}

/// Splits cells among `samples`.
pub(super) struct Splitter<'a> {
    samples: &'a Samples,
    maps: &'a [SurfaceMap],
    index: &'a SideIndex,
    obstruction: &'a Obstruction,
    vis: &'a dyn Visibility,
    alpha: f32,
}

impl<'a> Splitter<'a> {
    pub fn new(samples: &'a Samples, reads: Reads<'a>) -> Splitter<'a> {
        let Reads {
            maps,
            index,
            obstruction,
            vis,
            alpha,
        } = reads;
        Splitter {
            samples,
            maps,
            index,
            obstruction,
            vis,
            alpha,
        }
    }
}

/// What the first pass learned about a run of cells.
#[derive(Clone, Debug, Default)]
pub(super) struct Run {
    /// Whether the run was split; a stopped computation gives later runs' cells whole to
    /// their nearest samples.
    done: bool,
    /// The samples the run gives shares to, in sample order.
    slots: Vec<Slot>,
    /// The visibility answers of the run's cells on obstructed sides, in the order asked.
    seen: Bits,
    /// Cells with no visible sample within R, given to the nearest one.
    pub orphans: usize,
    /// Visibility queries made.
    pub queries: u64,
    /// What filling it wrote, for the other ranks ([`sent`]).
    sent: Vec<u32>,
}

fn broken() -> Error {
    Error::Worker {
        problem: "a rank sent area runs that do not read back (a transport error)".into(),
    }
}

impl Run {
    /// Appends run `r` as words: r, done, orphans, queries (2 words), its slots (3 words each),
    /// and, for the tests, its answers (their count, then 2 words per 64; none are sent).
    fn put(&self, r: u32, out: &mut Vec<u32>) {
        self.put_with(r, out, false);
    }

    fn put_with(&self, r: u32, out: &mut Vec<u32>, answers: bool) {
        let split = |x: u64| [x as u32, (x >> 32) as u32];
        out.extend([r, u32::from(self.done), self.orphans as u32]);
        out.extend(split(self.queries));
        out.push(self.slots.len() as u32);
        for s in &self.slots {
            out.extend([s.sample, s.next, s.prev]);
        }
        if answers {
            out.extend(split(self.seen.len as u64));
            for &w in &self.seen.words {
                out.extend(split(w));
            }
        } else {
            out.extend([0, 0]);
        }
    }

    /// Reads one run written by [`Run::put`] at `*at`, moving past it.
    fn take(words: &[u32], at: &mut usize) -> Result<(usize, Run)> {
        let mut next = |n: usize| -> Result<&[u32]> {
            let w = words.get(*at..*at + n).ok_or_else(broken)?;
            *at += n;
            Ok(w)
        };
        let join = |w: &[u32]| u64::from(w[0]) | u64::from(w[1]) << 32;
        let head = next(6)?;
        let (r, done, orphans) = (head[0] as usize, head[1] != 0, head[2] as usize);
        let queries = join(&head[3..5]);
        let slots = head[5] as usize;
        let slots = next(3 * slots)?
            .chunks_exact(3)
            .map(|w| Slot {
                sample: w[0],
                next: w[1],
                prev: w[2],
            })
            .collect();
        let len = join(next(2)?) as usize;
        let words = next(2 * len.div_ceil(64))?
            .chunks_exact(2)
            .map(join)
            .collect();
        Ok((
            r,
            Run {
                done,
                slots,
                seen: Bits { words, len },
                orphans,
                queries,
                sent: Vec::new(),
            },
        ))
    }
}

/// A filled run's shares as words, for the other ranks: per slot its sample, first position,
/// count, whether it holds the sample's first share and the base cell then, and a word per
/// share ([`Writer::word`]); then the shares whose steps are too long, as (position, cell).
fn sent(run: &Run, begin: &[(u32, bool)], writer: &Writer) -> Vec<u32> {
    let mut out = Vec::new();
    let mut far = Vec::new();
    out.push(run.slots.len() as u32);
    for (slot, &(start, first)) in run.slots.iter().zip(begin) {
        let count = slot.next - start;
        let k = slot.sample;
        out.extend([k, start, count, u32::from(first), writer.base(k as usize)]);
        for at in start..slot.next {
            let (word, cell) = writer.word(at as usize);
            out.push(word);
            if let Some(cell) = cell {
                far.extend([at, cell]);
            }
        }
    }
    out.push((far.len() / 2) as u32);
    out.extend(far);
    out
}

/// Writes what another rank [`sent`].
fn receive(words: &[u32], writer: &Writer) -> Result<()> {
    let mut at = 0;
    let next = |at: &mut usize, n: usize| -> Result<&[u32]> {
        let w = words.get(*at..*at + n).ok_or_else(broken)?;
        *at += n;
        Ok(w)
    };
    while at < words.len() {
        let slots = next(&mut at, 1)?[0];
        for _ in 0..slots {
            let head = next(&mut at, 5)?;
            let (k, start, count, first, base) = (head[0], head[1], head[2], head[3], head[4]);
            if first != 0 && !writer.set_base(k as usize, base) {
                return Err(broken());
            }
            for (i, &word) in next(&mut at, count as usize)?.iter().enumerate() {
                if !writer.put(start as usize + i, word, None) {
                    return Err(broken());
                }
            }
        }
        let far = next(&mut at, 1)?[0] as usize;
        for pair in next(&mut at, 2 * far)?.chunks_exact(2) {
            let (slot, cell) = (pair[0] as usize, pair[1]);
            let (word, _) = writer.word(slot);
            if !writer.put(slot, word, Some(cell)) {
                return Err(broken());
            }
        }
    }
    Ok(())
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
    rest: Vec<(f64, usize)>,
}

impl Splitter<'_> {
    /// The first pass: each run's shares per sample and visibility answers. Reports progress;
    /// after a Stop the runs not done are marked so, and [`Splitter::fill`] gives their cells
    /// whole to the nearest sample.
    ///
    /// Over several ranks, rank r counts every size-th run, and the runs are all-gathered.
    pub fn count(
        &self,
        layout: &Layout,
        threads: usize,
        ranks: &dyn Ranks,
        report: Report,
    ) -> Result<Vec<Run>> {
        let cells = &layout.cells;
        let size = ranks.size().max(1);
        let all = cells.len().div_ceil(RUN);
        let mine: Vec<usize> = (0..all)
            .filter(|&r| crate::distributed::deals(ranks, r))
            .collect();
        let mut runs = vec![Run::default(); mine.len()];
        let count = |i: usize, out: &mut [Run], halt: &crate::parallel::Halt| {
            let r = mine[i];
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
                // A run of a slow backend takes seconds: a Stop leaves it to the fallback.
                if halt.asked() {
                    *run = Run::default();
                    return Ok(());
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
                        .filter_map(|(&(k, _), &u)| (u > 0).then_some((k, id as u32))),
                );
            }
            run.seen.words.shrink_to_fit();
            run.slots = tally(samples);
            run.done = true;
            Ok(())
        };
        if !for_chunks_halting(&mut runs, 1, threads, count, report)? {
            for (i, run) in runs.iter_mut().enumerate().filter(|(_, run)| !run.done) {
                let r = mine[i];
                let nearest = (r * RUN..((r + 1) * RUN).min(cells.len()))
                    .filter(|&id| cells[id].is_new())
                    .filter_map(|id| {
                        let k = self.nearest(layout.side_of(id), cells[id].centroid)?;
                        Some((k, id as u32))
                    });
                run.slots = tally(nearest.collect());
            }
        }
        if size == 1 {
            return Ok(runs);
        }
        // The others need each run's slots, not its answers: a run is filled where it was
        // counted.
        let mut words = Vec::new();
        for (i, run) in runs.iter().enumerate() {
            run.put(mine[i] as u32, &mut words);
        }
        let (words, _) = crate::distributed::all_gather_words(ranks, &words)?;
        let mut every = vec![Run::default(); all];
        for (i, run) in runs.into_iter().enumerate() {
            every[mine[i]] = run;
        }
        let mut at = 0;
        while at < words.len() {
            let (r, run) = Run::take(&words, &mut at)?;
            if !crate::distributed::deals(ranks, r) {
                *every.get_mut(r).ok_or_else(broken)? = run;
            }
        }
        Ok(every)
    }

    /// The second pass: every run's shares written into the slots `place` gave its samples.
    ///
    /// Over several ranks, each rank fills the runs it counted (it holds their answers) and
    /// the filled slots are all-gathered (see [`sent`]).
    pub fn fill(
        &self,
        layout: &Layout,
        runs: &mut [Run],
        threads: usize,
        writer: &Writer,
        ranks: &dyn Ranks,
    ) -> Result<()> {
        let (rank, size) = (ranks.rank(), ranks.size().max(1));
        let fill = |r: usize, out: &mut [Run]| {
            if !crate::distributed::deals(ranks, r) {
                return Ok(());
            }
            let run = &mut out[0];
            // Where each slot starts, and whether it holds its sample's first share.
            let begin: Vec<(u32, bool)> = if size > 1 {
                run.slots.iter().map(|s| (s.next, s.prev == NONE)).collect()
            } else {
                Vec::new()
            };
            self.fill_run(layout, r, run, writer)?;
            if size > 1 {
                run.sent = sent(run, &begin, writer);
            }
            Ok(())
        };
        if size == 1 {
            return for_chunks(runs, 1, threads, fill);
        }
        // The filled runs cross in batches, so that what is in flight stays small beside the
        // shares (all at once, the 2 x 2-room gallery's ranks peaked 20% above one process).
        for (b, batch) in runs.chunks_mut(EXCHANGE_RUNS).enumerate() {
            let first = b * EXCHANGE_RUNS;
            for_chunks(batch, 1, threads, |i, out| fill(first + i, out))?;
            let mut mine = Vec::with_capacity(batch.iter().map(|r| r.sent.len()).sum());
            for run in batch.iter_mut() {
                mine.extend_from_slice(&std::mem::take(&mut run.sent));
            }
            let (words, counts) = crate::distributed::all_gather_words(ranks, &mine)?;
            drop(mine);
            let mut at = 0;
            for (r, &count) in counts.iter().enumerate() {
                if r != rank {
                    receive(&words[at..at + count], writer)?;
                }
                at += count;
            }
        }
        Ok(())
    }

    /// Fills run `r`.
    fn fill_run(&self, layout: &Layout, r: usize, run: &mut Run, writer: &Writer) -> Result<()> {
        let cells = &layout.cells;
        let mut write = |k: u32, id: usize, units: u16| -> Result<()> {
            let written = match run.slots.binary_search_by_key(&k, |s| s.sample) {
                Ok(i) => {
                    let slot = &mut run.slots[i];
                    let previous = (slot.prev != NONE).then_some(slot.prev);
                    let at = slot.next as usize;
                    slot.next += 1;
                    slot.prev = id as u32;
                    writer.write(at, k as usize, previous, id as u32, units)
                }
                Err(_) => false,
            };
            if written {
                Ok(())
            } else {
                Err(Error::Worker {
                    problem: format!(
                        "splitting area cell {id}: sample {k} was not counted (the \
                         visibility backend answered differently)"
                    ),
                })
            }
        };
        let ids = r * RUN..((r + 1) * RUN).min(cells.len());
        if !run.done {
            for id in ids.filter(|&id| cells[id].is_new()) {
                if let Some(k) = self.nearest(layout.side_of(id), cells[id].centroid) {
                    write(k, id, WHOLE)?;
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
        let Scratch { near, units, rest } = scratch;
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
            units.push(WHOLE);
            return Ok(true);
        }
        // Ascending sample order: the sum does not depend on the grid's iteration order.
        near.sort_unstable_by_key(|&(k, _)| k);
        split_units(weights(self.alpha, r, near), units, rest);
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
        // A candidate on another side lies on the same curved piece: asked too.
        let across = near
            .iter()
            .any(|&(k, _)| self.samples.side[k as usize] != side);
        if !self.obstruction.is_obstructed(side) && !across || near.is_empty() {
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

/// The area weights w(d) = exp(−α d / R) of a cell's samples at squared distances `near`
/// (eq. 5), normalised to add up to 1.
fn weights(alpha: f32, r: f32, near: &[(u32, f32)]) -> impl Iterator<Item = f64> + '_ {
    let weight = move |d2: f32, from: f32| f64::from((-alpha * (d2.sqrt() - from) / r).exp());
    let mut from = 0.0;
    let mut total: f64 = near.iter().map(|&(_, d2)| weight(d2, from)).sum();
    if !total.is_normal() {
        // A steep fall-off underflows every weight: measured from the nearest sample's
        // distance they give the same shares (the factor cancels), and the nearest weighs 1.
        from = near
            .iter()
            .map(|n| n.1)
            .fold(f32::INFINITY, f32::min)
            .sqrt();
        total = near.iter().map(|&(_, d2)| weight(d2, from)).sum();
    }
    near.iter().map(move |&(_, d2)| weight(d2, from) / total)
}

/// Each sample's shares from a run, from its (sample, cell) pairs.
fn tally(mut shares: Vec<(u32, u32)>) -> Vec<Slot> {
    shares.sort_unstable();
    let mut out: Vec<Slot> = Vec::new();
    for (k, cell) in shares {
        match out.last_mut() {
            Some(last) if last.sample == k => {
                last.next += 1;
                last.prev = cell;
            }
            _ => out.push(Slot {
                sample: k,
                next: 1,
                prev: cell,
            }),
        }
    }
    out.shrink_to_fit();
    out
}

/// Splits a cell's [`CELL_UNITS`](crate::sampling::CELL_UNITS) among parts (fractions adding up to 1) by largest
/// remainders, so that the units add up to the whole cell exactly; ties go to the earlier part.
pub(super) fn split_units(
    parts: impl Iterator<Item = f64>,
    units: &mut Vec<u16>,
    rest: &mut Vec<(f64, usize)>,
) {
    let whole = f64::from(crate::sampling::CELL_UNITS);
    rest.clear();
    units.clear();
    let mut given = 0u32;
    for (i, p) in parts.enumerate() {
        let exact = (p * whole).clamp(0.0, whole);
        let u = exact.floor();
        units.push(u as u16);
        given += u as u32;
        rest.push((exact - u, i));
    }
    let short = crate::sampling::CELL_UNITS.saturating_sub(given) as usize;
    if short > 0 {
        rest.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        for &(_, i) in rest.iter().cycle().take(short) {
            units[i] = units[i].saturating_add(1);
        }
    }
}

/// Gives each run the slots its samples' shares go to: after `next[k]` (the first free slot of
/// sample k), in run order, so that each sample's shares lie in cell order; and the cell each
/// run's first share of a sample follows (`last[k]`: the cell of sample k's last share so far).
pub(super) fn place(runs: &mut [Run], next: &mut [u32], last: &mut [u32]) {
    for run in runs {
        for slot in &mut run.slots {
            let k = slot.sample as usize;
            let (count, run_last) = (slot.next, slot.prev);
            slot.next = next[k];
            slot.prev = last[k];
            next[k] += count;
            last[k] = run_last;
        }
    }
}

/// The shares each run gives each sample, before `place`: (sample, count) pairs.
pub(super) fn counts(runs: &[Run]) -> impl Iterator<Item = (u32, u32)> + '_ {
    runs.iter()
        .flat_map(|r| r.slots.iter().map(|s| (s.sample, s.next)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_steep_fall_off_gives_the_cell_to_its_nearest_sample() {
        let near = [(0, 0.25), (1, 0.04), (2, 0.09)];
        // By hand at α = 2, R = 1: exp(−2 d) for d = 0.5, 0.2, 0.3, normalised.
        let w: Vec<f64> = [0.5f64, 0.2, 0.3]
            .iter()
            .map(|d| (-2.0 * d).exp())
            .collect();
        let sum: f64 = w.iter().sum();
        for (got, want) in weights(2.0, 1.0, &near).zip(&w) {
            assert!((got - want / sum).abs() < 1e-6, "{got} vs {}", want / sum);
        }
        // α = 10³⁰ underflows every weight: the nearest takes the whole cell.
        let got: Vec<f64> = weights(1e30, 1.0, &near).collect();
        assert_eq!(got, [0.0, 1.0, 0.0]);
    }

    #[test]
    fn runs_read_back_as_written() {
        let mut seen = Bits::default();
        // 70 answers: two words, the second partly used.
        for i in 0..70 {
            seen.push(i % 3 == 0);
        }
        let run = Run {
            done: true,
            slots: vec![
                Slot {
                    sample: 4,
                    next: 2,
                    prev: 17,
                },
                Slot {
                    sample: 9,
                    next: 1,
                    prev: NONE,
                },
            ],
            seen,
            orphans: 3,
            queries: (1 << 40) + 5,
            sent: Vec::new(),
        };
        let mut words = Vec::new();
        run.put_with(7, &mut words, true);
        Run::default().put(8, &mut words);
        // 6 head words, 3 a slot, 2 for the count of answers and 2 per 64 of them.
        assert_eq!(words.len(), (6 + 6 + 2 + 4) + (6 + 2));
        let mut at = 0;
        let (r, back) = Run::take(&words, &mut at).unwrap();
        assert_eq!(r, 7);
        assert!(back.done);
        assert_eq!((back.orphans, back.queries), (3, (1 << 40) + 5));
        assert_eq!(back.slots.len(), 2);
        assert_eq!(
            (back.slots[1].sample, back.slots[1].next, back.slots[1].prev),
            (9, 1, NONE)
        );
        assert_eq!(back.seen.len, 70);
        assert!((0..70).all(|i| back.seen.get(i) == (i % 3 == 0)));
        let (r, empty) = Run::take(&words, &mut at).unwrap();
        assert_eq!((r, empty.done, empty.slots.len()), (8, false, 0));
        assert_eq!(at, words.len());
        // Cut short: an error, not a panic.
        assert!(Run::take(&words[..5], &mut 0).is_err());
    }
}

#[cfg(test)]
mod sent_tests {
    use super::*;

    #[test]
    fn filled_slots_sent_and_received_write_the_same_shares() {
        // Sample 0: shares at 0..3 (first share here, one step too long for 16 bits);
        // sample 1: shares at 3..5, its first share written by an earlier run.
        let start = vec![0, 3, 5];
        let here = Writer::new(start.clone());
        assert!(here.write(0, 0, None, 10, 100));
        assert!(here.write(1, 0, Some(10), 11, 200));
        assert!(here.write(2, 0, Some(11), 90_000, 300));
        assert!(here.write(3, 1, Some(4), 5, 400));
        assert!(here.write(4, 1, Some(5), 6, 500));
        let run = Run {
            slots: vec![
                Slot {
                    sample: 0,
                    next: 3,
                    prev: 90_000,
                },
                Slot {
                    sample: 1,
                    next: 5,
                    prev: 6,
                },
            ],
            ..Run::default()
        };
        let words = sent(&run, &[(0, true), (3, false)], &here);
        let there = Writer::new(start);
        // Sample 1's base came from the earlier run, on this rank.
        assert!(there.set_base(1, 4));
        receive(&words, &there).unwrap();
        assert_eq!(there.finish(), {
            assert!(here.set_base(1, 4));
            here.finish()
        });
        // A message cut short is an error, not a panic.
        assert!(receive(&words[..words.len() - 1], &Writer::new(vec![0, 3, 5])).is_err());
    }
}
