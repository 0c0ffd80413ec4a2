//! What every entry point puts between itself and a backend (ours or a host's): hits naming a
//! triangle the scene lacks, or at a distance that is not a number, are refused before the
//! library indexes with them, and a backend's panic becomes an error naming the backend and
//! the call.

use super::{Hit, Ray, Segment, Visibility};
use crate::error::{Error, Result};
use crate::scene::Scene;

/// A backend whose answers are checked before use.
pub(crate) struct Checked<'a> {
    inner: &'a dyn Visibility,
    triangles: usize,
}

impl<'a> Checked<'a> {
    /// `vis` answering for `scene`'s triangles.
    pub(crate) fn new(vis: &'a dyn Visibility, scene: &Scene) -> Checked<'a> {
        Checked {
            inner: vis,
            triangles: scene.triangles.len(),
        }
    }

    /// Runs one call of the backend, turning its panic into an error that names it.
    fn call(&self, what: &str, f: impl FnOnce() -> Result<()>) -> Result<()> {
        crate::parallel::caught(f).map_err(|message| Error::Backend {
            backend: self.inner.name(),
            problem: format!("{what} panicked: {message}"),
        })?
    }
}

impl Visibility for Checked<'_> {
    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn occluded(&self, segments: &[Segment], out: &mut [bool]) -> Result<()> {
        self.call("occluded", || self.inner.occluded(segments, out))
    }

    fn intersect(&self, rays: &[Ray], out: &mut [Option<Hit>]) -> Result<()> {
        self.call("intersect", || self.inner.intersect(rays, out))?;
        for (i, (hit, ray)) in out.iter().zip(rays).enumerate() {
            if let Some(h) = hit {
                // A hit must lie on the ray between its ends: t < 0 or ∞ (or past the far
                // end by more than rounding) is the backend's error, not the scene's.
                let beyond = h.t > ray.t_max + 1e-4 * ray.t_max.abs().max(1.0);
                if h.triangle as usize >= self.triangles || !h.t.is_finite() || h.t < 0.0 || beyond
                {
                    return Err(Error::Backend {
                        backend: self.inner.name(),
                        problem: format!(
                            "intersect answered ray {i} of {} (t from {} to {}) with a hit on \
                             triangle {} at t = {}; the scene has {} triangles",
                            rays.len(),
                            ray.t_min,
                            ray.t_max,
                            h.triangle,
                            h.t,
                            self.triangles
                        ),
                    });
                }
            }
        }
        Ok(())
    }
}
