//! Directions drawn uniformly over the solid angle a triangle subtends (Arvo, "Stratified
//! Sampling of Spherical Triangles", SIGGRAPH 1995). Shadow rays drawn this way weigh only by
//! the receiver's cosine, where rays drawn uniformly over the emitter's area weigh by
//! cos·cos/r²: near an emitter (a wall beside the floor it meets, a panel over a desk) a few
//! area-drawn rays carry most of the weight, and the ratio estimator's denominator, a sum of
//! such weights, varies so much that its mean visible share falls short (Jensen: E[1/Y] >
//! 1/E[Y]); `docs/method.md` §11.

use glam::{DVec3, Vec3};

/// A triangle as seen from a point: its corners' directions and what sampling needs.
pub(super) struct SphericalTriangle {
    a: DVec3,
    b: DVec3,
    /// The unit direction in the plane of a and c, perpendicular to a.
    c_perp: DVec3,
    /// The angle at corner a, and its sine and cosine.
    alpha: f64,
    sin_alpha: f64,
    cos_alpha: f64,
    /// sin α · cos of the side from a to b.
    sin_alpha_cos_ab: f64,
    /// The solid angle, sr.
    pub area: f64,
}

/// Solid angles below this (sr) are not worth drawing from: rounding rules their corners.
const TINY: f64 = 1e-9;

/// An emitter is drawn over solid angle from receivers nearer than its radius / NEAR to its
/// centre, over its area from farther (where its rays' weights vary by less than about
/// ±2·NEAR, and the ratio's bias with them).
const NEAR: f32 = 0.3;

/// Receivers nearer an emitter's plane than this share of its radius draw over its area:
/// there Arvo's algebra loses its directions' uniformity (mean cosine 0.16% off at 5e-8
/// of the emitter's size, 27% at 5e-9).
const GRAZING: f32 = 1e-6;

/// Whether a receiver `height` over an emitter's plane and `distance` from its centre draws
/// its rays over the emitter's solid angle (an emitter of bounding `radius`).
pub(super) fn worth_drawing(height: f32, radius: f32, distance: f32) -> bool {
    radius > NEAR * distance && height > GRAZING * radius
}

impl SphericalTriangle {
    /// The triangle `t` seen from `x`; `None` when it subtends no measurable solid angle (far,
    /// edge-on, or x on its plane).
    pub fn new(t: &[Vec3; 3], x: Vec3) -> Option<SphericalTriangle> {
        let x = x.as_dvec3();
        let [a, b, c] = t.map(|v| (v.as_dvec3() - x).normalize_or_zero());
        if a == DVec3::ZERO || b == DVec3::ZERO || c == DVec3::ZERO {
            return None;
        }
        // Van Oosterom and Strackee's solid angle: stable for small and large triangles. With
        // x on the triangle's plane the corners' directions are coplanar, and the formula
        // would give 2π for a point inside: refused, as x is then beside the emitter.
        let triple = a.dot(b.cross(c)).abs();
        if triple.is_nan() || triple <= 1e-12 {
            return None;
        }
        let area = 2.0 * triple.atan2(1.0 + a.dot(b) + b.dot(c) + c.dot(a));
        let (n_ab, n_ac) = (
            a.cross(b).normalize_or_zero(),
            a.cross(c).normalize_or_zero(),
        );
        let c_perp = (c - a * c.dot(a)).normalize_or_zero();
        if area.is_nan()
            || area <= TINY
            || n_ab == DVec3::ZERO
            || n_ac == DVec3::ZERO
            || c_perp == DVec3::ZERO
        {
            return None;
        }
        let alpha = n_ab.dot(n_ac).clamp(-1.0, 1.0).acos();
        Some(SphericalTriangle {
            a,
            b,
            c_perp,
            alpha,
            sin_alpha: alpha.sin(),
            cos_alpha: alpha.cos(),
            sin_alpha_cos_ab: alpha.sin() * a.dot(b),
            area,
        })
    }

    /// The direction for (u0, u1) in the unit square: uniform in solid angle, and a grid in
    /// the square stays a grid (stratified) on the sphere. `None` if rounding defeats it.
    pub fn sample(&self, u0: f64, u1: f64) -> Option<DVec3> {
        // The sub-triangle (a, b, c') of area u0 · area: c' on the arc from a to c.
        let sub = u0 * self.area;
        let (s, t) = (sub - self.alpha).sin_cos();
        let u = t - self.cos_alpha;
        let v = s + self.sin_alpha_cos_ab;
        let q = ((v * t - u * s) * self.cos_alpha - v) / ((v * s + u * t) * self.sin_alpha);
        let q = if q.is_finite() {
            q.clamp(-1.0, 1.0)
        } else {
            return None;
        };
        let c_prime = q * self.a + (1.0 - q * q).max(0.0).sqrt() * self.c_perp;
        // Then along the arc from b to c', uniform in area: linear in cos.
        let z = 1.0 - u1 * (1.0 - c_prime.dot(self.b));
        let across = (c_prime - self.b * c_prime.dot(self.b)).normalize_or_zero();
        let w = z * self.b + (1.0 - z * z).max(0.0).sqrt() * across;
        (w.is_finite() && w != DVec3::ZERO).then_some(w)
    }
}

/// Where the ray from `x` along `w` meets the plane n · p = offset (None if parallel or
/// behind).
pub(super) fn on_plane(normal: Vec3, offset: f32, x: Vec3, w: DVec3) -> Option<Vec3> {
    let n = normal.as_dvec3();
    let x = x.as_dvec3();
    let d = (f64::from(offset) - n.dot(x)) / n.dot(w);
    (d.is_finite() && d > 0.0).then(|| (x + d * w).as_vec3())
}

/// An emitter's triangles as seen from one receiver, ready to draw directions from; kept
/// between receivers so that its buffers are reused.
#[derive(Default)]
pub(super) struct Draw {
    seen: Vec<SphericalTriangle>,
    cumulative: Vec<f64>,
}

impl Draw {
    /// Sets up the draw over `triangles` seen from `x`; false (and the caller draws over the
    /// area) if one of them subtends no measurable solid angle or all together less than
    /// `min_solid_angle`.
    pub fn prepare(&mut self, triangles: &[[Vec3; 3]], x: Vec3, min_solid_angle: f64) -> bool {
        self.seen.clear();
        self.cumulative.clear();
        let mut total = 0.0;
        for t in triangles {
            let Some(s) = SphericalTriangle::new(t, x) else {
                return false;
            };
            total += s.area;
            self.cumulative.push(total);
            self.seen.push(s);
        }
        total >= min_solid_angle
    }

    /// The cumulative solid angles of the triangles, as prepared.
    pub fn cumulative(&self) -> &[f64] {
        &self.cumulative
    }

    /// A direction in triangle `t` for (u0, u1): see [`SphericalTriangle::sample`].
    pub fn sample(&self, t: usize, u0: f64, u1: f64) -> Option<DVec3> {
        self.seen.get(t)?.sample(u0, u1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_square_overhead() -> [[Vec3; 3]; 2] {
        let (p, q, r, s) = (
            Vec3::new(-0.5, -0.5, 1.0),
            Vec3::new(0.5, -0.5, 1.0),
            Vec3::new(0.5, 0.5, 1.0),
            Vec3::new(-0.5, 0.5, 1.0),
        );
        [[p, q, r], [p, r, s]]
    }

    #[test]
    fn the_solid_angle_of_a_square_overhead() {
        // A square of side 2h centred at height h subtends 4π/6 (one face of a cube).
        let [t1, t2] = unit_square_overhead().map(|t| t.map(|v| v * Vec3::new(1.0, 1.0, 0.5)));
        let omega = SphericalTriangle::new(&t1, Vec3::ZERO).unwrap().area
            + SphericalTriangle::new(&t2, Vec3::ZERO).unwrap().area;
        let face = 4.0 * std::f64::consts::PI / 6.0;
        assert!((omega - face).abs() < 1e-9, "{omega} vs {face}");
    }

    #[test]
    fn samples_are_uniform_in_solid_angle() {
        // The mean of cos θ over directions uniform in the solid angle of a triangle, times
        // that solid angle, is the triangle's point form factor × π: Lambert's closed form
        // (`polygon_irradiance`). A draw uniform in area instead would weigh the near corner
        // more and miss it by percents.
        let t = [
            Vec3::new(-0.3, 0.2, 0.4),
            Vec3::new(1.5, -0.4, 0.6),
            Vec3::new(0.2, 1.8, 1.3),
        ];
        let tri = SphericalTriangle::new(&t, Vec3::ZERO).unwrap();
        let n = 400;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let w = tri
                    .sample((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64)
                    .unwrap();
                assert!((w.length() - 1.0).abs() < 1e-9);
                // Inside the triangle's cone: it meets the triangle's plane inside it.
                let normal = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
                let y = on_plane(normal, normal.dot(t[0]), Vec3::ZERO, w).unwrap();
                let (e1, e2, d) = (t[1] - t[0], t[2] - t[0], y - t[0]);
                let nn = e1.cross(e2);
                let b1 = d.cross(e2).dot(nn) / nn.length_squared();
                let b2 = e1.cross(d).dot(nn) / nn.length_squared();
                assert!(
                    b1 > -1e-4 && b2 > -1e-4 && b1 + b2 < 1.0 + 1e-4,
                    "{b1} {b2}"
                );
                sum += w.z;
            }
        }
        let estimate = sum / (n * n) as f64 * tri.area;
        let exact = crate::light::polygon_irradiance(&t, Vec3::ZERO, Vec3::Z);
        assert!(
            (estimate / exact - 1.0).abs() < 1e-4,
            "{estimate} vs {exact}"
        );
    }

    #[test]
    fn receivers_grazing_a_large_emitter_draw_finite_directions() {
        // A 200 m square 1e-6 .. 1 m over the receiver, facing it: nearly the whole upper
        // hemisphere. Every draw must give a direction (a refused draw drops a ray), and the
        // draw's mean cosine × solid angle must still be Lambert's irradiance; at 1e-5 and
        // 1e-6 m it was 0.16% and 27% off, and such receivers are now refused.
        let big = 100.0;
        for h in [1.0f32, 0.1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6] {
            let (p, q, r, s) = (
                Vec3::new(-big, -big, h),
                Vec3::new(-big, big, h),
                Vec3::new(big, big, h),
                Vec3::new(big, -big, h),
            );
            if !worth_drawing(h, big * 2f32.sqrt(), h) {
                // Refused: the caller draws over the area. Only where the draw would err.
                assert!(h < 1e-3, "h {h} refused");
                continue;
            }
            let mut draw = Draw::default();
            assert!(
                draw.prepare(&[[p, q, r], [p, r, s]], Vec3::ZERO, 1e-4),
                "h {h}"
            );
            let total = *draw.cumulative().last().unwrap();
            let n = 200;
            let mut sum = 0.0;
            for i in 0..n {
                for j in 0..n {
                    let u = (i as f64 + 0.5) / n as f64 * total;
                    let t = usize::from(u >= draw.cumulative()[0]);
                    let start = if t == 0 { 0.0 } else { draw.cumulative()[0] };
                    let within = (u - start) / (draw.cumulative()[t] - start);
                    let w = draw.sample(t, within, (j as f64 + 0.5) / n as f64);
                    let w = w.unwrap_or_else(|| panic!("h {h}: no direction at {i}, {j}"));
                    assert!(w.z >= -1e-9, "h {h}: {w}");
                    sum += w.z.max(0.0);
                }
            }
            let estimate = sum / (n * n) as f64 * total;
            let exact = crate::light::polygon_irradiance(&[p, q, r], Vec3::ZERO, Vec3::Z)
                + crate::light::polygon_irradiance(&[p, r, s], Vec3::ZERO, Vec3::Z);
            assert!(
                (estimate / exact - 1.0).abs() < 2e-3,
                "h {h}: {estimate} vs {exact}"
            );
        }
    }

    #[test]
    fn degenerate_triangles_are_refused() {
        let flat = [Vec3::ZERO, Vec3::X, Vec3::Y];
        assert!(SphericalTriangle::new(&flat, Vec3::new(0.2, 0.2, 0.0)).is_none());
        assert!(SphericalTriangle::new(&flat, Vec3::ZERO).is_none());
        let thin = [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(2.0, 0.0, 1.0),
        ];
        assert!(SphericalTriangle::new(&thin, Vec3::ZERO).is_none());
    }
}
