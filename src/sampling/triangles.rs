//! Points drawn uniformly by area over triangles: for lights' shadow rays and the rays that
//! carry daylight in through windows.

use glam::Vec3;

use crate::scene::Triangle;

/// The point of triangle `[a, b, c]` at (u1, u2) in the unit square, uniform over its area.
pub(crate) fn in_triangle([a, b, c]: [Vec3; 3], u1: f64, u2: f64) -> Vec3 {
    let (r1, r2) = (u1.sqrt() as f32, u2 as f32);
    a * (1.0 - r1) + b * (r1 * (1.0 - r2)) + c * (r1 * r2)
}

/// The running sum of the triangles' areas: a triangle is picked by area where it passes a
/// uniform number × the total (the last entry).
pub(crate) fn cumulative_area(triangles: &[&Triangle]) -> Vec<f64> {
    let mut total = 0.0;
    triangles
        .iter()
        .map(|t| {
            total += f64::from(t.area);
            total
        })
        .collect()
}
