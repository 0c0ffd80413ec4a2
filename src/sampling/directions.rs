//! Directions drawn over a side's hemisphere.

use glam::Vec3;

/// A unit direction, cosine-distributed about unit `n`, from two uniform numbers in [0, 1).
pub(crate) fn cosine(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let (r, phi) = (u1.sqrt(), std::f32::consts::TAU * u2);
    let (t, b) = n.any_orthonormal_pair();
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt()).normalize()
}
