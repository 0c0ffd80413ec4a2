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
        for (i, hit) in out.iter().enumerate() {
            if let Some(h) = hit {
                if h.triangle as usize >= self.triangles || h.t.is_nan() {
                    return Err(Error::Backend {
                        backend: self.inner.name(),
                        problem: format!(
                            "intersect answered ray {i} of {} with a hit on triangle {} at t = \
                             {}; the scene has {} triangles",
                            rays.len(),
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
