//! Where the samples lie (see [`Layout`]).

use super::pieces::Pieces;
use super::{vec_bytes, Obstruction, Samples, SideIndex, SurfaceMap};

/// Where the samples lie, beyond the samples themselves: the surfaces in 2D, the samples' index,
/// the sides other geometry stands on, the samples something hovers over. Grown by the solver as
/// it places samples (every stage that looks samples up by place takes it), kept in the solved
/// field for interpolation.
#[derive(Clone, Debug)]
pub(crate) struct Layout {
    /// The Poisson-disk spacing ε the samples were placed with.
    epsilon: f32,
    /// The surfaces in 2D.
    maps: Vec<SurfaceMap>,
    /// Range queries over the samples.
    index: SideIndex,
    /// Which sides other geometry stands on.
    obstruction: Obstruction,
    /// Per sample: whether something hovers over it (see `sampling::cover`).
    covered: Vec<bool>,
    /// The narrow sides sampled, indexed and interpolated as curved pieces.
    pieces: Pieces,
}

impl Layout {
    /// The layout of a solve that has placed no samples yet.
    pub(crate) fn new(
        epsilon: f32,
        maps: Vec<SurfaceMap>,
        obstruction: Obstruction,
        pieces: Pieces,
    ) -> Layout {
        Layout {
            epsilon,
            maps,
            index: SideIndex::default(),
            obstruction,
            covered: Vec::new(),
            pieces,
        }
    }

    /// The curved pieces (none unless the solve joins narrow sides).
    pub(crate) fn pieces(&self) -> &Pieces {
        &self.pieces
    }

    /// The surfaces in 2D, one per surface.
    pub(crate) fn maps(&self) -> &[SurfaceMap] {
        &self.maps
    }

    /// Range queries over the samples (as of the last [`Layout::reindex`]).
    pub(crate) fn index(&self) -> &SideIndex {
        &self.index
    }

    /// Which sides other geometry stands on.
    pub(crate) fn obstruction(&self) -> &Obstruction {
        &self.obstruction
    }

    /// Per sample: whether something hovers over it.
    pub(crate) fn covered(&self) -> &[bool] {
        &self.covered
    }

    /// Indexes `samples` anew (after samples were added).
    pub(crate) fn reindex(&mut self, samples: &Samples) {
        self.index = SideIndex::new(samples, &self.maps, self.epsilon, &self.pieces);
    }

    /// The Poisson-disk spacing ε.
    pub(crate) fn epsilon(&self) -> f32 {
        self.epsilon
    }

    /// Drops the index (a test's broken solution).
    #[cfg(test)]
    pub(crate) fn forget_index(&mut self) {
        self.index = SideIndex::default();
    }

    /// Appends the cover flags of newly added samples.
    pub(crate) fn cover(&mut self, flags: &[bool]) {
        self.covered.reserve_exact(flags.len());
        self.covered.extend_from_slice(flags);
    }

    /// Bytes of the index (with the pieces), the cover flags and the maps.
    pub(crate) fn bytes(&self) -> (usize, usize, usize) {
        (
            self.index.bytes() + self.pieces.bytes(),
            vec_bytes(&self.covered),
            self.maps.iter().map(|m| vec_bytes(&m.triangles)).sum(),
        )
    }
}
