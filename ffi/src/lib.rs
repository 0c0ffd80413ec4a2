//! Raw declarations of meshlight's C shim over Embree (`shim.h`): batched occlusion and closest
//! hit over one triangle scene. Safe wrappers live in meshlight's `visibility::embree`.
//!
//! Built against Embree 3 (Debian 12's `libembree-dev`) or Embree 4 (Debian 13), whichever
//! headers the build script finds; [`HEADERS`] and [`MAJOR`] say which.
#![allow(non_camel_case_types)]

use std::ffi::{c_char, c_int};

/// The Embree header the shim was compiled against.
pub const HEADERS: &str = env!("MESHLIGHT_EMBREE_HEADERS");

/// The Embree major version the shim was compiled against, as text ("3" or "4").
pub const MAJOR: &str = env!("MESHLIGHT_EMBREE_MAJOR");

/// A segment from `a` to `b` (mirror of `ml_segment`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ml_segment {
    /// Start point.
    pub a: [f32; 3],
    /// End point.
    pub b: [f32; 3],
}

/// A ray with its distance interval (mirror of `ml_ray`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ml_ray {
    /// Origin.
    pub org: [f32; 3],
    /// Direction (need not be unit length; distances are in its units).
    pub dir: [f32; 3],
    /// Nearest distance a hit may have.
    pub tnear: f32,
    /// Farthest distance a hit may have.
    pub tfar: f32,
}

/// The nearest hit of a ray (mirror of `ml_hit`): `prim == ML_MISS` when nothing was hit.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ml_hit {
    /// Distance along the ray.
    pub t: f32,
    /// Index of the triangle hit, as given at build, or [`ML_MISS`].
    pub prim: u32,
}

/// `prim` of a ray that hit nothing.
pub const ML_MISS: u32 = u32::MAX;

// The C side asserts the same sizes with _Static_assert (ML_*_SIZE in shim.h).
const _: () = assert!(std::mem::size_of::<ml_segment>() == 24);
const _: () = assert!(std::mem::size_of::<ml_ray>() == 32);
const _: () = assert!(std::mem::size_of::<ml_hit>() == 8);
const _: () = assert!(std::mem::align_of::<ml_segment>() == 4);
const _: () = assert!(std::mem::align_of::<ml_ray>() == 4);
const _: () = assert!(std::mem::align_of::<ml_hit>() == 4);
// `bool*` outputs: Rust's bool and C's _Bool are both one byte holding 0 or 1.
const _: () = assert!(std::mem::size_of::<bool>() == 1);

/// One ray at a time (`rtcOccluded1` / `rtcIntersect1`).
pub const ML_MODE_SINGLE: c_int = 0;
/// Packets of 4 rays.
pub const ML_MODE_PACKET4: c_int = 1;
/// Packets of 8 rays.
pub const ML_MODE_PACKET8: c_int = 2;
/// Packets of 16 rays.
pub const ML_MODE_PACKET16: c_int = 3;
/// Streams of single rays (`rtcOccluded1M`); Embree 3 only.
pub const ML_MODE_STREAM: c_int = 4;

/// Success.
pub const ML_OK: c_int = 0;
/// Embree reported an error on the calling thread during the call; `ml_thread_error` has its
/// text.
pub const ML_ERR_EMBREE: c_int = 1;
/// The mode does not exist in this Embree version.
pub const ML_ERR_UNSUPPORTED: c_int = 2;
/// A null pointer or out-of-range argument.
pub const ML_ERR_ARGUMENT: c_int = 3;

/// Opaque scene handle (device + committed scene). Neither `Send` nor `Sync` by itself (the
/// marker): a wrapper that shares it across threads must say why that is sound.
#[repr(C)]
pub struct ml_scene {
    _private: [u8; 0],
    _marker: core::marker::PhantomData<(*mut u8, core::marker::PhantomPinned)>,
}

extern "C" {
    /// The Embree major version the shim was compiled against.
    pub fn ml_embree_major() -> c_int;
    /// Builds a scene; NULL on failure with a message in `err`.
    pub fn ml_scene_new(
        vertices: *const f32,
        nv: usize,
        indices: *const u32,
        nt: usize,
        quality: c_int,
        robust: bool,
        err: *mut c_char,
        errlen: usize,
    ) -> *mut ml_scene;
    /// Releases a scene built by `ml_scene_new`.
    pub fn ml_scene_free(scene: *mut ml_scene);
    /// Copies the first device error (or an empty string) into `buf`.
    pub fn ml_scene_error(scene: *const ml_scene, buf: *mut c_char, len: usize);
    /// Copies the error Embree reported on the calling thread during its last failed query
    /// (or an empty string) into `buf`.
    pub fn ml_thread_error(buf: *mut c_char, len: usize);
    /// Batched occlusion of segments over parameters `[t_min, t_max]`.
    pub fn ml_occluded(
        scene: *const ml_scene,
        segments: *const ml_segment,
        n: usize,
        t_min: f32,
        t_max: f32,
        mode: c_int,
        out: *mut bool,
    ) -> c_int;
    /// Batched closest hit.
    pub fn ml_intersect(
        scene: *const ml_scene,
        rays: *const ml_ray,
        n: usize,
        mode: c_int,
        out: *mut ml_hit,
    ) -> c_int;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reports_the_major_version_it_was_built_against() {
        // SAFETY: a pure function of the compile-time define.
        let major = unsafe { ml_embree_major() };
        assert_eq!(major.to_string(), MAJOR);
        assert!(HEADERS.contains(&format!("embree{MAJOR}")));
    }

    #[test]
    fn one_triangle_blocks_a_segment_through_it_and_not_one_beside_it() {
        let vertices = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let indices = [0u32, 1, 2];
        let mut err = [0 as c_char; 256];
        // SAFETY: the arrays outlive the call and have the lengths passed.
        let scene = unsafe {
            ml_scene_new(
                vertices.as_ptr(),
                3,
                indices.as_ptr(),
                1,
                1,
                true,
                err.as_mut_ptr(),
                256,
            )
        };
        assert!(!scene.is_null());
        let segments = [
            ml_segment {
                a: [0.2, 0.2, -1.0],
                b: [0.2, 0.2, 1.0],
            },
            ml_segment {
                a: [0.9, 0.9, -1.0],
                b: [0.9, 0.9, 1.0],
            },
        ];
        for mode in [
            ML_MODE_SINGLE,
            ML_MODE_PACKET4,
            ML_MODE_PACKET8,
            ML_MODE_PACKET16,
        ] {
            let mut out = [false; 2];
            // SAFETY: scene is live; segments and out have n = 2 elements.
            let status = unsafe {
                ml_occluded(
                    scene,
                    segments.as_ptr(),
                    2,
                    1e-4,
                    1.0 - 1e-4,
                    mode,
                    out.as_mut_ptr(),
                )
            };
            assert_eq!(status, ML_OK, "mode {mode}");
            assert_eq!(out, [true, false], "mode {mode}");
        }
        let rays = [ml_ray {
            org: [0.25, 0.25, 2.0],
            dir: [0.0, 0.0, -1.0],
            tnear: 0.0,
            tfar: 10.0,
        }];
        let mut hit = [ml_hit::default()];
        // SAFETY: as above, n = 1.
        let status =
            unsafe { ml_intersect(scene, rays.as_ptr(), 1, ML_MODE_PACKET16, hit.as_mut_ptr()) };
        assert_eq!(status, ML_OK);
        assert_eq!(hit[0].prim, 0);
        assert!((hit[0].t - 2.0).abs() < 1e-6, "t = {}", hit[0].t);
        // SAFETY: built above, freed once.
        unsafe { ml_scene_free(scene) };
    }
}
