//! Visibility: the one trait the solver and renderer ask, answered a batch at a time by Embree
//! (through our C shim in `ffi/`) or by the pure-Rust `obvhs` BVH.

mod bvh;
mod checked;
#[cfg(feature = "embree")]
mod embree;

use std::fmt;
use std::str::FromStr;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::scene::Scene;

pub use bvh::{BvhPreset, BvhScene};
pub(crate) use checked::Checked;
#[cfg(feature = "embree")]
pub use embree::{
    headers as embree_headers, major as embree_major, EmbreeMode, EmbreeOptions, EmbreeScene,
};

/// A segment between two points. The backends test it over the parameter interval
/// [`SEGMENT_T_MIN`, `SEGMENT_T_MAX`] of `a + t (b − a)`: the ends themselves never block.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Segment {
    /// Start.
    pub a: Vec3,
    /// End.
    pub b: Vec3,
}

/// Hits closer to a segment's start than this fraction of its length are ignored.
///
/// Decision: 1e-5, not more. The ends are lifted off their surfaces already ([`lift`]), so
/// the trim only has to absorb rounding; whatever it ignores beyond that is a surface in
/// front of an end that does not block. With 1e-4, a poster 1 mm before a wall of a 6 m room
/// (Blender users leave such gaps against z-fighting) let light into the gap through segments
/// that ended there: the whole image came out 3% too dark (`tests/textures.rs`).
pub const SEGMENT_T_MIN: f32 = 1e-5;
/// Hits closer to a segment's end than `1 − SEGMENT_T_MAX` of its length are ignored.
pub const SEGMENT_T_MAX: f32 = 1.0 - 1e-5;

/// A ray with the distance interval in which hits count.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Ray {
    /// Origin.
    pub origin: Vec3,
    /// Direction; distances `t` are in units of its length.
    pub dir: Vec3,
    /// Nearest distance a hit may have.
    pub t_min: f32,
    /// Farthest distance a hit may have.
    pub t_max: f32,
}

/// The nearest hit of a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray, in units of its direction's length.
    pub t: f32,
    /// Index into [`Scene::triangles`].
    pub triangle: u32,
}

/// Distance by which query ends are lifted off their surfaces, as a fraction of the scene's
/// diagonal (see [`lift`]).
pub const LIFT: f32 = 1e-4;

/// How far every query lifts its ends off their surfaces along the normal, in scene units:
/// [`LIFT`] × the scene's diagonal, so a point never occludes itself and the answer
/// does not depend on the unit. One value for the solver, the renderer and the references.
pub fn lift(scene: &Scene) -> f32 {
    LIFT * scene.bounds.diagonal()
}

/// Answers visibility questions about one scene, a batch at a time, from any number of threads:
/// the extension point for a host's own ray caster (`examples/embed.rs` plugs one in).
///
/// The contract:
/// - **Geometry**: the triangles of [`Scene::triangles`] (the loaded scene's order, which is
///   not the order of the mesh a host handed to [`Scene::from_parts`]: surfaces are grouped),
///   both sides of each blocking light; a [`Hit`] names its triangle by that index.
/// - **Segments**: blocked when any triangle crosses `a + t (b − a)` for `t` in
///   [[`SEGMENT_T_MIN`], [`SEGMENT_T_MAX`]]: the ends never block, so a segment between two
///   points on surfaces is not blocked by those surfaces.
/// - **Rays**: the nearest hit with `t` in [`t_min`, `t_max`] (units of the direction's
///   length, which need not be 1), or `None`.
/// - **Batches**: any length, including 0 (the library asks up to about 65,000 at once);
///   `out` has the batch's length and every entry must be written.
/// - **Threads**: called concurrently from the solver's and renderer's worker threads; answers
///   must not depend on which thread asks or in which order, or results stop being
///   deterministic.
/// - **Failure**: return an error ([`Error::Backend`] is meant for it) and the solve or render
///   ends with it; a panic ends it with [`Error::Worker`] naming the panic. Never a hang.
///
/// [`t_min`]: Ray::t_min
/// [`t_max`]: Ray::t_max
pub trait Visibility: Send + Sync {
    /// The backend's name, as `--backend` spells it.
    fn name(&self) -> &'static str;

    /// For each segment, whether anything blocks it (see [`Segment`]); `out.len()` must equal
    /// `segments.len()`.
    fn occluded(&self, segments: &[Segment], out: &mut [bool]) -> Result<()>;

    /// For each ray, its nearest hit or `None`; `out.len()` must equal `rays.len()`.
    fn intersect(&self, rays: &[Ray], out: &mut [Option<Hit>]) -> Result<()>;
}

/// The visibility backends meshlight has.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Backend {
    /// Embree through `ffi/` (feature `embree`).
    Embree,
    /// The pure-Rust `obvhs` BVH.
    Bvh,
}

impl Backend {
    /// Every backend compiled into this build, the default first.
    pub fn available() -> Vec<Backend> {
        let mut all = Vec::new();
        if cfg!(feature = "embree") {
            all.push(Backend::Embree);
        }
        all.push(Backend::Bvh);
        all
    }

    /// Embree where compiled in, else obvhs.
    pub fn default_backend() -> Backend {
        Backend::available()[0]
    }

    /// The name `--backend` takes.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Embree => "embree",
            Backend::Bvh => "bvh",
        }
    }

    /// Builds this backend over a scene's triangles with its default settings.
    pub fn build(self, scene: &Scene) -> Result<Box<dyn Visibility>> {
        match self {
            #[cfg(feature = "embree")]
            Backend::Embree => Ok(Box::new(EmbreeScene::new(scene, EmbreeOptions::default())?)),
            #[cfg(not(feature = "embree"))]
            Backend::Embree => Err(Error::Backend {
                backend: "embree",
                problem: "this build has no Embree backend (built without the `embree` feature)"
                    .into(),
            }),
            Backend::Bvh => Ok(Box::new(BvhScene::new(scene, BvhPreset::default()))),
        }
    }
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Backend {
    type Err = Error;

    fn from_str(s: &str) -> Result<Backend> {
        match s {
            "embree" => Ok(Backend::Embree),
            "bvh" | "obvhs" => Ok(Backend::Bvh),
            other => Err(Error::Option {
                option: "backend",
                problem: format!("unknown backend '{other}' (known: embree, bvh)"),
            }),
        }
    }
}

/// Fails unless a batch's output has one slot per query.
pub(crate) fn check_lengths(backend: &'static str, queries: usize, out: usize) -> Result<()> {
    if queries == out {
        Ok(())
    } else {
        Err(Error::Backend {
            backend,
            problem: format!("{queries} queries but {out} output slots"),
        })
    }
}

/// Embree asserts, and so aborts the process, on a ray with a coordinate beyond its
/// `FLT_LARGE` (1.844e18) or NaN, or a NaN distance, and obvhs asserts finite rays: both
/// backends check every batch before tracing it, in release builds too (one pass over the
/// rays, next to nothing beside tracing them), and refuse the first bad one by name. A t_max
/// below t_min is an empty interval, answered as a miss (the path tracer steps past segment
/// ends that way).
const LARGE: f32 = 1.8e18;

fn within(v: glam::Vec3, bound: f32) -> bool {
    v.is_finite() && v.abs().max_element() <= bound
}

/// The first ray Embree cannot take, as an error naming it.
pub(crate) fn check_rays(rays: &[Ray]) -> Result<()> {
    for (i, r) in rays.iter().enumerate() {
        let problem = if !within(r.origin, LARGE) {
            format!("origin {}", r.origin)
        } else if !within(r.dir, LARGE) {
            format!("direction {}", r.dir)
        } else if !(r.t_min.is_finite() && r.t_min >= 0.0) {
            format!("t_min {}", r.t_min)
        } else if r.t_max.is_nan() {
            format!("t_max {}", r.t_max)
        } else {
            continue;
        };
        return Err(Error::Argument {
            argument: "rays",
            problem: format!(
                "ray {i} of {}: {problem}: a ray needs finite coordinates within ±{LARGE:e}, \
                 a finite t_min ≥ 0 and a t_max that is a number",
                rays.len()
            ),
        });
    }
    Ok(())
}

/// The first segment Embree cannot take (ends within half the range, so that their
/// difference, the direction, is within it too).
pub(crate) fn check_segments(segments: &[Segment]) -> Result<()> {
    for (i, s) in segments.iter().enumerate() {
        if !within(s.a, 0.5 * LARGE) || !within(s.b, 0.5 * LARGE) {
            return Err(Error::Argument {
                argument: "segments",
                problem: format!(
                    "segment {i} of {}: {} to {}: its ends need finite coordinates within \
                     ±{:e}",
                    segments.len(),
                    s.a,
                    s.b,
                    0.5 * LARGE
                ),
            });
        }
    }
    Ok(())
}

/// Occlusion of many segments on up to `threads` threads (batches of 4,096), for tests and
/// tools.
pub fn occluded_all(
    vis: &dyn Visibility,
    segments: &[Segment],
    threads: usize,
) -> Result<Vec<bool>> {
    let mut out = vec![false; segments.len()];
    crate::parallel::for_chunks(&mut out, 4096, threads, |first, o| {
        vis.occluded(&segments[first..first + o.len()], o)
    })?;
    Ok(out)
}

/// Closest hits of many rays on up to `threads` threads (batches of 4,096), for tests and
/// tools.
pub fn intersect_all(
    vis: &dyn Visibility,
    rays: &[Ray],
    threads: usize,
) -> Result<Vec<Option<Hit>>> {
    let mut out = vec![None; rays.len()];
    crate::parallel::for_chunks(&mut out, 4096, threads, |first, o| {
        vis.intersect(&rays[first..first + o.len()], o)
    })?;
    Ok(out)
}
