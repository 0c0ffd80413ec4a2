//! The GGX (Trowbridge–Reitz) microfacet lobe with Smith's separable masking-shadowing and no
//! Fresnel term (F = 1): Mitsuba 3's `roughconductor` with `material = "none"`. Directions are
//! in the local frame of the surface (normal +z); sampling follows the distribution of visible
//! normals (Heitz 2018, "Sampling the GGX Distribution of Visible Normals").

use glam::DVec3;
use std::f64::consts::PI;

/// A GGX lobe of width α = roughness².
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Ggx {
    pub alpha: f64,
}

impl Ggx {
    /// The lobe of a roughness r in (0, 1]: α = r².
    pub(crate) fn of_roughness(r: f32) -> Ggx {
        // A floor keeps the densities finite for the roughest glossy surfaces users write
        // (r = 0 is a mirror and never comes here).
        Ggx {
            alpha: f64::from(r * r).max(1e-4),
        }
    }

    /// The microfacet distribution D(h): normals per solid angle, ∫ D(h) cos θh dω = 1.
    pub(crate) fn d(&self, h: DVec3) -> f64 {
        let c = h.z;
        if c <= 0.0 {
            return 0.0;
        }
        let a2 = self.alpha * self.alpha;
        let t = c * c * (a2 - 1.0) + 1.0;
        a2 / (PI * t * t)
    }

    /// Smith's Λ(ω): G1 = 1 / (1 + Λ).
    fn lambda(&self, w: DVec3) -> f64 {
        let c2 = w.z * w.z;
        if c2 <= 0.0 {
            return f64::INFINITY;
        }
        let tan2 = (1.0 - c2).max(0.0) / c2;
        0.5 * (-1.0 + (1.0 + self.alpha * self.alpha * tan2).sqrt())
    }

    /// Masking of one direction (0 below the surface).
    pub(crate) fn g1(&self, w: DVec3) -> f64 {
        if w.z <= 0.0 {
            0.0
        } else {
            1.0 / (1.0 + self.lambda(w))
        }
    }

    /// f_s(wo, wi) = D(h) G1(wo) G1(wi) / (4 cos θo cos θi), 0 unless both lie above.
    pub(crate) fn eval(&self, wo: DVec3, wi: DVec3) -> f64 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        self.d(h) * self.g1(wo) * self.g1(wi) / (4.0 * wo.z * wi.z)
    }

    /// Density (per solid angle of wi) of [`Ggx::sample`]: G1(wo) D(h) / (4 cos θo).
    pub(crate) fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        self.g1(wo) * self.d(h) / (4.0 * wo.z)
    }

    /// A reflected direction for wo, from a visible normal drawn with (u1, u2) ∈ [0, 1)²; `None`
    /// when it points below the surface (masked). The estimator f_s cos θi / pdf of a kept
    /// direction is G1(wi).
    pub(crate) fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<DVec3> {
        if wo.z <= 0.0 {
            return None;
        }
        let a = self.alpha;
        // The view direction stretched to the hemisphere configuration.
        let v = DVec3::new(a * wo.x, a * wo.y, wo.z).normalize();
        let len2 = v.x * v.x + v.y * v.y;
        let t1 = if len2 > 0.0 {
            DVec3::new(-v.y, v.x, 0.0) / len2.sqrt()
        } else {
            DVec3::X
        };
        let t2 = v.cross(t1);
        let r = u1.sqrt();
        let phi = 2.0 * PI * u2;
        let p1 = r * phi.cos();
        let s = 0.5 * (1.0 + v.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
        let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * v;
        // Back to the ellipsoid configuration.
        let h = DVec3::new(a * nh.x, a * nh.y, nh.z.max(0.0)).normalize();
        let wi = 2.0 * wo.dot(h) * h - wo;
        (wi.z > 0.0).then_some(wi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Direction at polar angle θ and azimuth φ.
    fn dir(theta: f64, phi: f64) -> DVec3 {
        DVec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    }

    /// ∫ g(ω) dω over the upper hemisphere by the midpoint rule in (θ, φ).
    fn hemisphere(n: usize, g: impl Fn(DVec3) -> f64) -> f64 {
        let (dt, dp) = (0.5 * PI / n as f64, 2.0 * PI / (2 * n) as f64);
        let mut sum = 0.0;
        for i in 0..n {
            let theta = (i as f64 + 0.5) * dt;
            for j in 0..2 * n {
                sum += g(dir(theta, (j as f64 + 0.5) * dp)) * theta.sin();
            }
        }
        sum * dt * dp
    }

    #[test]
    fn the_normal_distribution_projects_to_one() {
        for alpha in [0.09, 0.3, 0.8] {
            let g = Ggx { alpha };
            let total = hemisphere(1000, |h| g.d(h) * h.z);
            assert!((total - 1.0).abs() < 1e-3, "α {alpha}: ∫ D cos = {total}");
        }
    }

    #[test]
    fn the_sampling_density_integrates_to_the_unmasked_share_and_matches_the_samples() {
        let g = Ggx { alpha: 0.3 };
        let wo = dir(0.7, 0.4);
        // ∫ pdf over the hemisphere is the share of visible normals whose reflection stays
        // above: at most 1.
        let total = hemisphere(800, |wi| g.pdf(wo, wi));
        assert!(total <= 1.0 + 2e-3 && total > 0.9, "{total}");
        // The estimator f cos / pdf of a sample is G1(wi): its mean is the lobe's albedo, which
        // quadrature gives independently.
        let albedo = hemisphere(800, |wi| g.eval(wo, wi) * wi.z);
        let n = 400;
        let mut mean = 0.0;
        for i in 0..n {
            for j in 0..n {
                let (u1, u2) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                if let Some(wi) = g.sample(wo, u1, u2) {
                    let estimate = g.eval(wo, wi) * wi.z / g.pdf(wo, wi);
                    assert!((estimate - g.g1(wi)).abs() < 1e-9);
                    mean += estimate;
                }
            }
        }
        mean /= (n * n) as f64;
        assert!(
            (mean - albedo).abs() < 2e-3,
            "sampled {mean} vs quadrature {albedo}"
        );
        // Single scattering loses what reflects below the horizon or is masked: at α 0.3 and
        // 40°, about 15% (the same quadrature in another language gave 0.8517).
        assert!((albedo - 0.8517).abs() < 2e-3, "{albedo}");
    }
}
