//! The samples' shares of the area cells (eq. 5), stored compactly: they are the largest
//! arrays of a solve (some 120 a sample), so a share takes 4 bytes.
//!
//! Sample k's shares lie at `start[k]..start[k + 1]`, in ascending cell order. Each holds the
//! step from the previous share's cell (the first's cell is `base[k]`, its step 0) and its
//! part of its cell in units of 1 / [`CELL_UNITS`]. A sample's cells lie within a few rows of
//! one side's grid, so a step fits in 16 bits unless a side is thousands of cells wide; such a
//! step is stored as `u16::MAX` and its cell in `far`, by position.

use std::sync::atomic::{AtomicU16, AtomicU32, Ordering};
use std::sync::Mutex;

use super::CELL_UNITS;

/// A step too long for 16 bits: the cell is in `far`.
const FAR: u16 = u16::MAX;

/// The shares of every sample (see the module's docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Shares {
    /// Where each sample's shares start (length samples + 1 once areas are computed).
    pub start: Vec<u32>,
    /// Each sample's first cell.
    base: Vec<u32>,
    /// Each share's step from the previous share's cell.
    steps: Vec<u16>,
    /// Each share's part of its cell, in units of 1 / [`CELL_UNITS`].
    pub units: Vec<u16>,
    /// (position, cell) of the shares whose step is [`FAR`], by position.
    far: Vec<(u32, u32)>,
}

impl Shares {
    /// Bytes held.
    pub fn bytes(&self) -> usize {
        use super::vec_bytes;
        vec_bytes(&self.start)
            + vec_bytes(&self.base)
            + vec_bytes(&self.steps)
            + vec_bytes(&self.units)
            + vec_bytes(&self.far)
    }

    /// All shares.
    pub fn len(&self) -> usize {
        self.units.len()
    }

    /// Where sample k's shares lie (empty where it holds none or the offsets do not fit).
    pub fn range(&self, k: usize) -> std::ops::Range<usize> {
        match (self.start.get(k), self.start.get(k + 1)) {
            (Some(&a), Some(&b))
                if a <= b
                    && b as usize <= self.steps.len()
                    && b as usize <= self.units.len()
                    && k < self.base.len() =>
            {
                a as usize..b as usize
            }
            _ => 0..0,
        }
    }

    /// Sample k's shares: (cell, units), in cell order.
    pub fn of(&self, k: usize) -> impl Iterator<Item = (u32, u16)> + '_ {
        let range = self.range(k);
        let mut cell = self.base.get(k).copied().unwrap_or(0);
        range.map(move |i| {
            cell = match self.steps[i] {
                FAR => self.far_cell(i).unwrap_or(cell),
                step => cell.wrapping_add(u32::from(step)),
            };
            (cell, self.units[i])
        })
    }

    fn far_cell(&self, i: usize) -> Option<u32> {
        let at = self.far.binary_search_by_key(&(i as u32), |f| f.0).ok()?;
        Some(self.far[at].1)
    }

    /// Changes share `i`'s units (tests of the invariants' checks).
    #[cfg(test)]
    pub fn set_units(&mut self, i: usize, units: u16) {
        self.units[i] = units;
    }
}

/// Shares written from several threads at once, each into slots no other writes: the
/// positions of each sample's shares (`start`) are known before any is written.
pub(crate) struct Writer {
    start: Vec<u32>,
    base: Vec<AtomicU32>,
    steps: Vec<AtomicU16>,
    units: Vec<AtomicU16>,
    far: Mutex<Vec<(u32, u32)>>,
}

impl Writer {
    /// Room for the shares `start` places (length samples + 1).
    pub fn new(start: Vec<u32>) -> Writer {
        let n = start.len().saturating_sub(1);
        let total = start.last().copied().unwrap_or(0) as usize;
        Writer {
            start,
            base: (0..n).map(|_| AtomicU32::new(0)).collect(),
            steps: (0..total).map(|_| AtomicU16::new(0)).collect(),
            units: (0..total).map(|_| AtomicU16::new(0)).collect(),
            far: Mutex::new(Vec::new()),
        }
    }

    /// Writes the share at `slot` of sample k: `cell`, after the sample's share in `previous`
    /// (`None` for its first), with `units`. Whether the slot exists.
    pub fn write(
        &self,
        slot: usize,
        k: usize,
        previous: Option<u32>,
        cell: u32,
        units: u16,
    ) -> bool {
        let (Some(s), Some(u)) = (self.steps.get(slot), self.units.get(slot)) else {
            return false;
        };
        let step = match previous {
            None => {
                let Some(b) = self.base.get(k) else {
                    return false;
                };
                b.store(cell, Ordering::Relaxed);
                0
            }
            Some(p) => match cell.checked_sub(p) {
                Some(d) if d < u32::from(FAR) => d as u16,
                _ => {
                    if let Ok(mut far) = self.far.lock() {
                        far.push((slot as u32, cell));
                    }
                    FAR
                }
            },
        };
        s.store(step, Ordering::Relaxed);
        u.store(units, Ordering::Relaxed);
        true
    }

    /// The written shares.
    /// Share `slot` as one word (its step above its units), and its cell where the step is too
    /// long for 16 bits; and the base cell of sample `k` (the cell of its first share).
    pub fn word(&self, slot: usize) -> (u32, Option<u32>) {
        let step = self
            .steps
            .get(slot)
            .map_or(0, |s| s.load(Ordering::Relaxed));
        let units = self
            .units
            .get(slot)
            .map_or(0, |u| u.load(Ordering::Relaxed));
        let far = (step == FAR)
            .then(|| {
                let far = self.far.lock().unwrap_or_else(|e| e.into_inner());
                far.iter().find(|f| f.0 == slot as u32).map(|f| f.1)
            })
            .flatten();
        (u32::from(step) << 16 | u32::from(units), far)
    }

    /// The base cell written for sample `k`.
    pub fn base(&self, k: usize) -> u32 {
        self.base.get(k).map_or(0, |b| b.load(Ordering::Relaxed))
    }

    /// Writes what [`Writer::word`] read on another rank; false if out of range.
    pub fn put(&self, slot: usize, word: u32, far: Option<u32>) -> bool {
        let (Some(s), Some(u)) = (self.steps.get(slot), self.units.get(slot)) else {
            return false;
        };
        s.store((word >> 16) as u16, Ordering::Relaxed);
        u.store(word as u16, Ordering::Relaxed);
        if let Some(cell) = far {
            self.far
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .push((slot as u32, cell));
        }
        true
    }

    /// Sets sample `k`'s base cell (read on another rank); false if out of range.
    pub fn set_base(&self, k: usize, cell: u32) -> bool {
        self.base
            .get(k)
            .map(|b| b.store(cell, Ordering::Relaxed))
            .is_some()
    }

    pub fn finish(self) -> Shares {
        let mut far = self.far.into_inner().unwrap_or_else(|e| e.into_inner());
        far.sort_unstable();
        far.shrink_to_fit();
        // Same size and alignment: collected in place, without a second array.
        Shares {
            start: self.start,
            base: self.base.into_iter().map(AtomicU32::into_inner).collect(),
            steps: self.steps.into_iter().map(AtomicU16::into_inner).collect(),
            units: self.units.into_iter().map(AtomicU16::into_inner).collect(),
            far,
        }
    }
}

/// A cell's whole area, as units.
pub(crate) const WHOLE: u16 = CELL_UNITS as u16;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_read_back_as_written_also_with_steps_too_long_for_16_bits() {
        // Sample 0: cells 5, 9, 100,000 (a step of 99,991); sample 1: none; sample 2: 7, 8.
        let w = Writer::new(vec![0, 3, 3, 5]);
        // Out of order, as threads would.
        assert!(w.write(4, 2, Some(7), 8, 30));
        assert!(w.write(2, 0, Some(9), 100_000, 3));
        assert!(w.write(0, 0, None, 5, 10));
        assert!(w.write(3, 2, None, 7, 40));
        assert!(w.write(1, 0, Some(5), 9, 20));
        assert!(!w.write(5, 2, Some(8), 9, 1), "no slot 5");
        let s = w.finish();
        assert_eq!(
            s.of(0).collect::<Vec<_>>(),
            [(5, 10), (9, 20), (100_000, 3)]
        );
        assert_eq!(s.of(1).count(), 0);
        assert_eq!(s.of(2).collect::<Vec<_>>(), [(7, 40), (8, 30)]);
        assert_eq!(s.of(3).count(), 0, "no sample 3");
        // 4 bytes a share, 4 a sample for its base and 4 for its start, 8 a far step.
        assert_eq!(s.bytes(), 5 * 4 + 3 * 4 + 4 * 4 + 8);
    }
}
