//! The solved field (`docs/method.md` §7): the samples, the light the solver found at them, and
//! what reading that light at any other point takes (the surfaces in 2D, the samples' index,
//! the sides other geometry stands on, the samples something hovers over). The solver builds
//! it; the render, the grids, the PLY writer and the specular chains' ends only read it, through
//! `interpolate` and the accessors here. Where the samples lie (`sampling::Layout`) is the
//! solver's to grow and the field's to keep.

pub(crate) mod interpolate;
pub(crate) mod patches;

use glam::DVec3;

use crate::light::Arrival;
use crate::sampling::{Layout, Samples};

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
        self.layout.epsilon()
    }

    /// The specular depth the field was solved with.
    pub fn specular_depth(&self) -> u32 {
        self.specular_depth
    }
}
