//! The solved field (`docs/method.md` §7): the samples, the light the solver found at them, and
//! what reading that light at any other point takes (the surfaces in 2D, the samples' index,
//! the sides other geometry stands on, the samples something hovers over). The solver builds
//! it; the render, the grids, the PLY writer and the specular chains' ends only read it, through
//! [`interpolate`] and the accessors here.

pub(crate) mod interpolate;

use glam::DVec3;

use crate::light::Arrival;
use crate::sampling::{vec_bytes, Obstruction, Samples, SideIndex, SurfaceMap};

/// The samples and their light, as a solve leaves them.
#[derive(Clone, Debug)]
pub struct Field {
    pub(crate) samples: Samples,
    /// Radiosity B per sample: emission π·Ke plus reflected light.
    pub(crate) radiosity: Vec<DVec3>,
    /// Irradiance per sample, direct and inter-reflected.
    pub(crate) irradiance: Vec<DVec3>,
    /// Direct light per sample.
    pub(crate) direct: Vec<Arrival>,
    /// Per sample: the daylight entering straight from the sky and the ground (empty without
    /// daylight). Exact at each sample, not interpolated in warm starts; the image interpolates
    /// it with the rest of the samples' light.
    pub(crate) daylight: Vec<DVec3>,
    /// The specular depth solved with (the render and the grids light with the same).
    pub(crate) specular_depth: u32,
    /// Whether light by way of specular surfaces was solved (the grids gather it then).
    pub(crate) specular: bool,
    /// Where the samples lie, for reading the field between them.
    pub(crate) layout: Layout,
}

/// What reading the field between samples takes, kept from the solve: built and grown by the
/// solver as it places samples, read by interpolation.
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
}

impl Layout {
    /// The layout of a solve that has placed no samples yet.
    pub(crate) fn new(epsilon: f32, maps: Vec<SurfaceMap>, obstruction: Obstruction) -> Layout {
        Layout {
            epsilon,
            maps,
            index: SideIndex::default(),
            obstruction,
            covered: Vec::new(),
        }
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
        self.index = SideIndex::new(samples, &self.maps, self.epsilon);
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

    /// Bytes of the index, the cover flags and the maps.
    pub(crate) fn bytes(&self) -> (usize, usize, usize) {
        (
            self.index.bytes(),
            vec_bytes(&self.covered),
            self.maps.iter().map(|m| vec_bytes(&m.triangles)).sum(),
        )
    }
}

impl Field {
    /// The samples (positions, normals, sides, radii, areas).
    pub fn samples(&self) -> &Samples {
        &self.samples
    }

    /// Radiosity B of each sample (W/m², RGB): emission π·Ke plus reflected light.
    pub fn radiosity(&self) -> &[DVec3] {
        &self.radiosity
    }

    /// Irradiance at each sample (direct + inter-reflected).
    pub fn irradiance(&self) -> &[DVec3] {
        &self.irradiance
    }

    /// Direct light at each sample.
    pub fn direct(&self) -> &[Arrival] {
        &self.direct
    }

    /// The Poisson-disk spacing ε of the samples.
    pub fn epsilon(&self) -> f32 {
        self.layout.epsilon
    }

    /// The specular depth the field was solved with.
    pub fn specular_depth(&self) -> u32 {
        self.specular_depth
    }
}
