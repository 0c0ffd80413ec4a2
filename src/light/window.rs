//! The part of a light's mirror image that a receiver sees through the mirror's outline. Light
//! from an image arrives only along lines that cross the mirror itself; drawing shadow rays over
//! the whole image and letting the outline stop some made every receiver near the edge of a
//! light's reflection a "penumbra" (half the mirror room's hits), noisy and traced again with
//! four times the rays. Clipped to the outline, the image's light there is Lambert's exact
//! irradiance, and the rays go only where it can come from.

use glam::Vec3;

/// The pieces of `image` (triangles of a light's mirror image) that receiver `x` sees through
/// `window` (the mirror's triangles, on the plane `normal · p = offset`), as triangles: each
/// image triangle clipped to the pyramid from `x` through each window triangle, and to the far
/// side of the mirror's plane.
pub(super) fn through(
    image: &[[Vec3; 3]],
    x: Vec3,
    window: &[[Vec3; 3]],
    (normal, offset): (Vec3, f32),
) -> Vec<[Vec3; 3]> {
    let side = (normal.dot(x) - offset).signum();
    let mut pieces = Vec::new();
    let mut polygon = Vec::with_capacity(8);
    let mut scratch = Vec::with_capacity(8);
    for w in window {
        // The pyramid's three planes through x, each keeping the side the window's third
        // corner is on.
        let planes = [(0, 1, 2), (1, 2, 0), (2, 0, 1)].map(|(a, b, c)| {
            let m = (w[a] - x).cross(w[b] - x);
            let m = if m.dot(w[c] - x) < 0.0 { -m } else { m };
            (m, m.dot(x))
        });
        for t in image {
            polygon.clear();
            polygon.extend_from_slice(t);
            for &(m, d) in &planes {
                clip(&polygon, m, d, &mut scratch);
                std::mem::swap(&mut polygon, &mut scratch);
            }
            // Beyond the mirror, seen from x.
            clip(&polygon, -side * normal, -side * offset, &mut scratch);
            std::mem::swap(&mut polygon, &mut scratch);
            for k in 1..polygon.len().saturating_sub(1) {
                pieces.push([polygon[0], polygon[k], polygon[k + 1]]);
            }
        }
    }
    pieces
}

/// Sutherland–Hodgman: the part of convex `polygon` where `m · p ≥ d`, into `out`.
fn clip(polygon: &[Vec3], m: Vec3, d: f32, out: &mut Vec<Vec3>) {
    out.clear();
    let n = polygon.len();
    for i in 0..n {
        let (p, q) = (polygon[i], polygon[(i + 1) % n]);
        let (a, b) = (m.dot(p) - d, m.dot(q) - d);
        if a >= 0.0 {
            out.push(p);
        }
        if (a >= 0.0) != (b >= 0.0) {
            out.push(p + (q - p) * (a / (a - b)));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(pieces: &[[Vec3; 3]]) -> f32 {
        pieces
            .iter()
            .map(|t| 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length())
            .sum()
    }

    #[test]
    fn an_image_is_cut_to_what_the_mirror_s_outline_lets_through() {
        // A 1 × 1 mirror in the plane z = 0 (two triangles), the receiver 1 above its centre,
        // an image 2 × 2 at z = −1: through the mirror the receiver sees the image's square of
        // side 2 (the outline's shadow from x doubles at twice the distance), all of it; an
        // image 4 × 4 is cut to that 2 × 2 square.
        let window = [
            [
                Vec3::new(-0.5, -0.5, 0.0),
                Vec3::new(0.5, -0.5, 0.0),
                Vec3::new(0.5, 0.5, 0.0),
            ],
            [
                Vec3::new(-0.5, -0.5, 0.0),
                Vec3::new(0.5, 0.5, 0.0),
                Vec3::new(-0.5, 0.5, 0.0),
            ],
        ];
        let square = |h: f32| {
            [
                [
                    Vec3::new(-h, -h, -1.0),
                    Vec3::new(h, -h, -1.0),
                    Vec3::new(h, h, -1.0),
                ],
                [
                    Vec3::new(-h, -h, -1.0),
                    Vec3::new(h, h, -1.0),
                    Vec3::new(-h, h, -1.0),
                ],
            ]
        };
        let x = Vec3::new(0.0, 0.0, 1.0);
        let plane = (Vec3::Z, 0.0);
        let whole = through(&square(1.0), x, &window, plane);
        assert!((area(&whole) - 4.0).abs() < 1e-4, "{}", area(&whole));
        let cut = through(&square(2.0), x, &window, plane);
        assert!((area(&cut) - 4.0).abs() < 1e-4, "{}", area(&cut));
        // Off to the side by 1: the outline's shadow moves by 2 the other way, half of the
        // 2 × 2 image stays in it.
        let aside = through(&square(1.0), Vec3::new(1.0, 0.0, 1.0), &window, plane);
        assert!((area(&aside) - 2.0).abs() < 1e-4, "{}", area(&aside));
        // An image on the receiver's side of the mirror is not seen through it.
        let front = [[
            Vec3::new(-1.0, -1.0, 0.5),
            Vec3::new(1.0, -1.0, 0.5),
            Vec3::new(0.0, 1.0, 0.5),
        ]];
        assert!(through(&front, x, &window, plane).is_empty());
    }
}
