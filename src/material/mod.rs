//! What a surface does with light that does not leave it diffusely, shared by the renderer,
//! the solve's specular transfer, the lux grids and the path tracer: a mirror's reflection, a
//! glossy GGX lobe (`ggx`), smooth glass's Fresnel reflection and refraction, a thin pane's
//! (`fresnel`). The diffuse part (Kd) is the caller's.

pub(crate) mod fresnel;
pub(crate) mod ggx;

use glam::DVec3;

use crate::scene::{Kind, Material};
use ggx::Ggx;

/// Where a ray meeting a specular surface goes on.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Branches {
    /// Nothing beyond the diffuse part (a diffuse material, or the black back of a one-sided
    /// one).
    None,
    /// Up to two fixed directions with their weights (a mirror; glass's reflection and
    /// transmission).
    Delta([Option<(DVec3, DVec3)>; 2]),
    /// A glossy lobe, to sample or evaluate.
    Glossy(Lobe),
}

/// A glossy lobe at a hit: Ks × GGX, in the frame of the side hit.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lobe {
    ks: DVec3,
    ggx: Ggx,
    /// The side's normal and a tangent frame around it.
    n: DVec3,
    t: DVec3,
    b: DVec3,
    /// The outgoing direction (back along the incoming ray), local.
    wo: DVec3,
}

impl Lobe {
    fn local(&self, w: DVec3) -> DVec3 {
        DVec3::new(w.dot(self.t), w.dot(self.b), w.dot(self.n))
    }

    /// A direction drawn from the lobe with (u1, u2) and its weight Ks f cos / pdf; `None` when
    /// the drawn normal reflects below the surface.
    pub(crate) fn sample(&self, u1: f64, u2: f64) -> Option<(DVec3, DVec3)> {
        let wi = self.ggx.sample(self.wo, u1, u2)?;
        let world = self.t * wi.x + self.b * wi.y + self.n * wi.z;
        Some((world.normalize(), self.ks * self.ggx.g1(wi)))
    }

    /// Ks f(wo, ω) cos θ for a world direction ω leaving the side.
    pub(crate) fn eval(&self, w: DVec3) -> DVec3 {
        let wi = self.local(w);
        self.ks * (self.ggx.eval(self.wo, wi) * wi.z.max(0.0))
    }

    /// The density [`Lobe::sample`] draws world direction ω with.
    pub(crate) fn pdf(&self, w: DVec3) -> f64 {
        self.ggx.pdf(self.wo, self.local(w))
    }

    /// The side's normal.
    pub(crate) fn normal(&self) -> DVec3 {
        self.n
    }
}

/// Mirror reflection of travelling direction `d` about the unit normal `n`.
pub(crate) fn reflect(d: DVec3, n: DVec3) -> DVec3 {
    d - 2.0 * d.dot(n) * n
}

/// The specular branches of a ray travelling along `d` (unit) that meets a face of `m` whose
/// front normal is `n`; `two_sided`: whether the face reflects on its back too. Glass's
/// transmission carries the change of radiance across the interface: divided by η² where
/// the path enters the material, multiplied where it leaves (the path runs against the light).
pub(crate) fn branches(m: &Material, d: DVec3, n: DVec3, two_sided: bool) -> Branches {
    let front = d.dot(n) < 0.0;
    let side = if front { n } else { -n };
    match m.kind {
        Kind::Diffuse => Branches::None,
        Kind::Specular { ks, roughness } => {
            if (!front && !two_sided) || ks.max_element() <= 0.0 {
                return Branches::None;
            }
            let ks = ks.as_dvec3();
            if roughness == 0.0 {
                return Branches::Delta([Some((reflect(d, side), ks)), None]);
            }
            let (t, b) = side.any_orthonormal_pair();
            let wo = -d;
            Branches::Glossy(Lobe {
                ks,
                ggx: Ggx::of_roughness(roughness),
                n: side,
                t,
                b,
                wo: DVec3::new(wo.dot(t), wo.dot(b), wo.dot(side)),
            })
        }
        Kind::Glass {
            ior,
            transmit,
            thin,
        } => {
            let ior = f64::from(ior);
            let cos_i = -d.dot(side);
            let filter = transmit.as_dvec3();
            if thin {
                let r = fresnel::pane_reflectance(cos_i, ior);
                return Branches::Delta([
                    Some((reflect(d, side), DVec3::splat(r))),
                    Some((d, filter * (1.0 - r))),
                ]);
            }
            // Entering from the front (outside) the relative index is n, leaving it is 1/n.
            let eta = if front { ior } else { 1.0 / ior };
            let r = fresnel::reflectance(cos_i, eta);
            let transmitted = fresnel::refract(d, side, eta).map(|t| {
                let radiance = if front { 1.0 / (ior * ior) } else { ior * ior };
                (t, filter * ((1.0 - r) * radiance))
            });
            Branches::Delta([Some((reflect(d, side), DVec3::splat(r))), transmitted])
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn glass(thin: bool) -> Material {
        let mut m = Material::diffuse("glass", Vec3::ZERO, Vec3::ZERO);
        m.kind = Kind::Glass {
            ior: 1.5,
            transmit: Vec3::ONE,
            thin,
        };
        m
    }

    #[test]
    fn a_slab_passes_one_minus_r_squared_over_one_minus_r_squared_in_all() {
        // Normal incidence through two faces: in, then the internal bounces out. The series of
        // the branches' weights: T² Σ R^2k = (1 − R)² / (1 − R²) for R = 0.04 — and the η²
        // factors cancel.
        let m = glass(false);
        let down = DVec3::NEG_Z;
        let Branches::Delta([Some((r_dir, r)), Some((t_dir, t))]) =
            branches(&m, down, DVec3::Z, false)
        else {
            panic!("two branches")
        };
        assert!((r.x - 0.04).abs() < 1e-12 && r_dir.z > 0.0);
        assert!((t_dir - down).length() < 1e-12);
        // Inside, going down to the slab's bottom face, whose front (outside) faces down.
        let Branches::Delta([Some((_, r_in)), Some((_, t_out))]) =
            branches(&m, down, DVec3::NEG_Z, false)
        else {
            panic!("two branches")
        };
        let through = t.x * t_out.x / (1.0 - r_in.x * r_in.x);
        assert!(
            (through - 0.96 * 0.96 / (1.0 - 0.04 * 0.04)).abs() < 1e-12,
            "{through}"
        );
        // A pane the same in one face.
        let Branches::Delta([Some((_, r)), Some((dir, t))]) =
            branches(&glass(true), down, DVec3::Z, false)
        else {
            panic!("two branches")
        };
        assert!((t.x - 0.96 * 0.96 / (1.0 - 0.04 * 0.04)).abs() < 1e-12);
        assert!((r.x + t.x - 1.0).abs() < 1e-12 && dir == down);
    }

    #[test]
    fn a_one_sided_mirror_is_black_from_behind() {
        let mut m = Material::diffuse("mirror", Vec3::ZERO, Vec3::ZERO);
        m.kind = Kind::Specular {
            ks: Vec3::ONE,
            roughness: 0.0,
        };
        let d = DVec3::new(0.6, 0.0, -0.8);
        let Branches::Delta([Some((r, w)), None]) = branches(&m, d, DVec3::Z, false) else {
            panic!()
        };
        assert!((r - DVec3::new(0.6, 0.0, 0.8)).length() < 1e-12 && w == DVec3::ONE);
        assert!(matches!(branches(&m, -d, DVec3::Z, false), Branches::None));
        assert!(matches!(
            branches(&m, -d, DVec3::Z, true),
            Branches::Delta(_)
        ));
    }
}
