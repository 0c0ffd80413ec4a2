//! Fresnel reflectance of a smooth dielectric (unpolarised light), Snell refraction, and the
//! thin pane's reflectance with its internal bounces.

use glam::DVec3;

/// Reflectance at an interface hit at cos θi = `cos_i` (≥ 0), going into a medium whose index
/// relative to the one the light comes from is `eta`; 1 beyond the critical angle.
pub(crate) fn reflectance(cos_i: f64, eta: f64) -> f64 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (parallel * parallel + perpendicular * perpendicular)
}

/// A thin pane's reflectance at cos θi: R' = 2R / (1 + R), its light bouncing between the two
/// faces summed (Mitsuba 3's `thindielectric`).
pub(crate) fn pane_reflectance(cos_i: f64, ior: f64) -> f64 {
    let r = reflectance(cos_i, ior);
    2.0 * r / (1.0 + r)
}

/// The direction refracted from `d` (unit, travelling) through a surface whose unit normal `n`
/// faces the incoming side (d·n < 0), with `eta` the relative index; `None` at total internal
/// reflection.
pub(crate) fn refract(d: DVec3, n: DVec3, eta: f64) -> Option<DVec3> {
    let cos_i = -d.dot(n);
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((d / eta + n * (cos_i / eta - cos_t)).normalize())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_and_grazing_by_hand() {
        // R = ((n − 1)/(n + 1))² = 0.04 for n = 1.5, from either side.
        assert!((reflectance(1.0, 1.5) - 0.04).abs() < 1e-12);
        assert!((reflectance(1.0, 1.0 / 1.5) - 0.04).abs() < 1e-12);
        assert!((reflectance(0.0, 1.5) - 1.0).abs() < 1e-12);
        // Total internal reflection beyond asin(1/1.5) = 41.8° inside glass.
        assert_eq!(reflectance(45f64.to_radians().cos(), 1.0 / 1.5), 1.0);
        // Brewster's angle atan(1.5): the parallel part vanishes, R = perpendicular² / 2.
        let b = 1.5f64.atan();
        let cos_t = (1.0 - (b.sin() / 1.5).powi(2)).sqrt();
        let perp = (b.cos() - 1.5 * cos_t) / (b.cos() + 1.5 * cos_t);
        assert!((reflectance(b.cos(), 1.5) - 0.5 * perp * perp).abs() < 1e-12);
        // The pane: 2 × 0.04 / 1.04.
        assert!((pane_reflectance(1.0, 1.5) - 0.08 / 1.04).abs() < 1e-12);
    }

    #[test]
    fn refraction_follows_snell() {
        let n = DVec3::Z;
        let theta = 0.6f64;
        let d = DVec3::new(theta.sin(), 0.0, -theta.cos());
        let t = refract(d, n, 1.5).unwrap();
        let sin_t = (t.x * t.x + t.y * t.y).sqrt();
        assert!((sin_t * 1.5 - theta.sin()).abs() < 1e-12);
        assert!(t.z < 0.0);
        assert_eq!(refract(DVec3::new(0.8, 0.0, -0.6), n, 1.0 / 1.5), None);
    }
}
