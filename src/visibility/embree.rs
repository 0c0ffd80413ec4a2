//! The Embree backend: a safe wrapper over meshlight's C shim (`ffi/`). One FFI crossing per
//! batch; segments, rays and hits cross without copying (layouts are checked at compile time).

use std::ffi::{c_char, c_int, CStr};
use std::ptr::NonNull;

use meshlight_embree_sys as sys;

use super::{
    check_lengths, check_rays, check_segments, Hit, Ray, Segment, Visibility, SEGMENT_T_MAX,
    SEGMENT_T_MIN,
};
use crate::error::{Error, Result};
use crate::scene::Scene;

// Our public query types are the shim's structs, field for field.
const _: () = assert!(std::mem::size_of::<Segment>() == std::mem::size_of::<sys::ml_segment>());
const _: () = assert!(std::mem::align_of::<Segment>() == std::mem::align_of::<sys::ml_segment>());
const _: () = assert!(std::mem::size_of::<Ray>() == std::mem::size_of::<sys::ml_ray>());
const _: () = assert!(std::mem::align_of::<Ray>() == std::mem::align_of::<sys::ml_ray>());

/// How the shim hands a batch to Embree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmbreeMode {
    /// One ray per call (`rtcOccluded1`).
    Single,
    /// Packets of 4.
    Packet4,
    /// Packets of 8.
    Packet8,
    /// Packets of 16.
    Packet16,
    /// Streams (`rtcOccluded1M`); Embree 3 only.
    Stream,
}

impl EmbreeMode {
    /// Every mode the linked Embree offers.
    pub fn all() -> Vec<EmbreeMode> {
        let mut modes = vec![Self::Single, Self::Packet4, Self::Packet8, Self::Packet16];
        if sys::MAJOR == "3" {
            modes.push(Self::Stream);
        }
        modes
    }

    /// Short name for reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Single => "single",
            Self::Packet4 => "packet4",
            Self::Packet8 => "packet8",
            Self::Packet16 => "packet16",
            Self::Stream => "stream",
        }
    }

    fn raw(self) -> c_int {
        match self {
            Self::Single => sys::ML_MODE_SINGLE,
            Self::Packet4 => sys::ML_MODE_PACKET4,
            Self::Packet8 => sys::ML_MODE_PACKET8,
            Self::Packet16 => sys::ML_MODE_PACKET16,
            Self::Stream => sys::ML_MODE_STREAM,
        }
    }
}

/// Settings of the Embree backend.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmbreeOptions {
    /// BVH build quality: 0 low, 1 medium, 2 high.
    pub quality: u8,
    /// Embree's robust (watertight) traversal: no ray slips between two triangles that share
    /// an edge.
    pub robust: bool,
    /// How occlusion batches are traced.
    pub occlusion_mode: EmbreeMode,
    /// How closest-hit batches are traced.
    pub intersect_mode: EmbreeMode,
}

impl Default for EmbreeOptions {
    /// Measured with `meshlight bench-vis` on room and gallery (`docs/performance.md`, "Visibility backends"): streams are the
    /// fastest occlusion path in Embree 3 (1.4x packets of 16 on the gallery); Embree 4 has no
    /// streams, and there packets of 8 are next best; packets of 8 lead for closest hits.
    /// Robust traversal keeps light from slipping through edges shared by two triangles.
    fn default() -> Self {
        EmbreeOptions {
            quality: 2,
            robust: true,
            occlusion_mode: if sys::MAJOR == "3" {
                EmbreeMode::Stream
            } else {
                EmbreeMode::Packet8
            },
            intersect_mode: EmbreeMode::Packet8,
        }
    }
}

/// An Embree scene over a meshlight scene's triangles.
pub struct EmbreeScene {
    raw: NonNull<sys::ml_scene>,
    options: EmbreeOptions,
}

// SAFETY: a committed Embree scene is immutable and Embree documents rtcOccluded*/rtcIntersect*
// as safe to call from any number of threads at once; each query reads and resets only its own
// thread's error code (rtcGetDeviceError is per device and thread), and the message is kept in
// thread-local storage; the build-time error slot is atomic.
unsafe impl Send for EmbreeScene {}
// SAFETY: as above; no method takes &mut self except Drop.
unsafe impl Sync for EmbreeScene {}

impl EmbreeScene {
    /// Builds the Embree scene.
    pub fn new(scene: &Scene, options: EmbreeOptions) -> Result<Self> {
        let vertices: Vec<f32> = scene
            .triangles
            .iter()
            .flat_map(|t| t.vertices)
            .flat_map(|v| v.to_array())
            .collect();
        let indices: Vec<u32> = (0..3 * scene.triangles.len() as u32).collect();
        let mut err = [0 as c_char; 512];
        // SAFETY: both arrays live through the call and hold 3·nv floats and 3·nt indices (all
        // below nv); err is a writable buffer of the length passed.
        let raw = unsafe {
            sys::ml_scene_new(
                vertices.as_ptr(),
                vertices.len() / 3,
                indices.as_ptr(),
                scene.triangles.len(),
                c_int::from(options.quality.min(2)),
                options.robust,
                err.as_mut_ptr(),
                err.len(),
            )
        };
        match NonNull::new(raw) {
            Some(raw) => Ok(EmbreeScene { raw, options }),
            None => {
                // SAFETY: the shim NUL-terminates err within its length.
                let message = unsafe { CStr::from_ptr(err.as_ptr()) };
                Err(Error::Backend {
                    backend: "embree",
                    problem: message.to_string_lossy().into(),
                })
            }
        }
    }

    /// The settings it was built with.
    pub fn options(&self) -> EmbreeOptions {
        self.options
    }

    /// Occlusion through a chosen mode: the raw shim path `bench-vis` compares the trait with.
    pub fn occluded_with(
        &self,
        mode: EmbreeMode,
        segments: &[Segment],
        out: &mut [bool],
    ) -> Result<()> {
        check_lengths("embree", segments.len(), out.len())?;
        check_segments(segments)?;
        // SAFETY: Segment has ml_segment's layout (asserted above); both slices hold n items;
        // the scene is live for &self.
        let status = unsafe {
            sys::ml_occluded(
                self.raw.as_ptr(),
                segments.as_ptr().cast::<sys::ml_segment>(),
                segments.len(),
                SEGMENT_T_MIN,
                SEGMENT_T_MAX,
                mode.raw(),
                out.as_mut_ptr(),
            )
        };
        self.status(status, mode)
    }

    /// Closest hits through a chosen mode.
    pub fn intersect_with(
        &self,
        mode: EmbreeMode,
        rays: &[Ray],
        out: &mut [Option<Hit>],
    ) -> Result<()> {
        check_lengths("embree", rays.len(), out.len())?;
        check_rays(rays)?;
        const CHUNK: usize = 256;
        let mut hits = [sys::ml_hit::default(); CHUNK];
        for (rays, out) in rays.chunks(CHUNK).zip(out.chunks_mut(CHUNK)) {
            // SAFETY: Ray has ml_ray's layout (asserted above); rays and hits hold at least
            // rays.len() items; the scene is live for &self.
            let status = unsafe {
                sys::ml_intersect(
                    self.raw.as_ptr(),
                    rays.as_ptr().cast::<sys::ml_ray>(),
                    rays.len(),
                    mode.raw(),
                    hits.as_mut_ptr(),
                )
            };
            self.status(status, mode)?;
            for (o, h) in out.iter_mut().zip(&hits) {
                *o = (h.prim != sys::ML_MISS).then_some(Hit {
                    t: h.t,
                    triangle: h.prim,
                });
            }
        }
        Ok(())
    }

    fn status(&self, status: c_int, mode: EmbreeMode) -> Result<()> {
        let problem = match status {
            sys::ML_OK => return Ok(()),
            sys::ML_ERR_UNSUPPORTED => {
                format!(
                    "mode {} is not available in Embree {}",
                    mode.name(),
                    sys::MAJOR
                )
            }
            sys::ML_ERR_ARGUMENT => "invalid arguments to the shim".to_string(),
            _ => {
                let mut buf = [0 as c_char; 512];
                // SAFETY: buf is writable for its length; the shim NUL-terminates it. The
                // message is this thread's, from the call that just failed.
                unsafe { sys::ml_thread_error(buf.as_mut_ptr(), buf.len()) };
                // SAFETY: NUL-terminated by the call above.
                unsafe { CStr::from_ptr(buf.as_ptr()) }
                    .to_string_lossy()
                    .into_owned()
            }
        };
        Err(Error::Backend {
            backend: "embree",
            problem,
        })
    }
}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: raw came from ml_scene_new and is released exactly once.
        unsafe { sys::ml_scene_free(self.raw.as_ptr()) };
    }
}

impl Visibility for EmbreeScene {
    fn name(&self) -> &'static str {
        "embree"
    }

    fn occluded(&self, segments: &[Segment], out: &mut [bool]) -> Result<()> {
        self.occluded_with(self.options.occlusion_mode, segments, out)
    }

    fn intersect(&self, rays: &[Ray], out: &mut [Option<Hit>]) -> Result<()> {
        self.intersect_with(self.options.intersect_mode, rays, out)
    }
}

/// The Embree headers the shim was compiled against, for reports.
pub fn headers() -> &'static str {
    sys::HEADERS
}

/// The major version of the Embree the shim was compiled against ("3" or "4").
pub fn major() -> &'static str {
    sys::MAJOR
}
