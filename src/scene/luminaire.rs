//! Lights at points: isotropic point lights, and luminaires whose intensity follows an IES
//! distribution (`docs/scene-format.md`, "Luminaires"). Both light a point x by I(direction)·cosθ/r²
//! through one shadow ray; [`PointSource`] is what every consumer of light sees of either.

use std::sync::Arc;

use glam::{DVec3, Vec3};

use crate::ies::Photometry;

/// A luminaire: a point with a measured distribution.
#[derive(Clone, Debug, PartialEq)]
pub struct Luminaire {
    /// Position.
    pub position: Vec3,
    /// Where γ = 0 (the file's nadir) points: unit length.
    pub aim: Vec3,
    /// Where the C = 0° half-plane points: unit length, perpendicular to `aim`.
    pub c0: Vec3,
    /// RGB scale of the file's candela: the colour (luminance 1) × the multiplier.
    pub tint: Vec3,
    /// The distribution, candela.
    pub photometry: Arc<Photometry>,
}

impl Luminaire {
    /// Candela towards `dir` (any length), before the tint: C measured from `c0`, increasing
    /// towards (−aim) × c0; γ from `aim`.
    pub fn candela_towards(&self, dir: Vec3) -> f64 {
        let d = dir.normalize_or_zero().as_dvec3();
        let (aim, c0) = (self.aim.as_dvec3(), self.c0.as_dvec3());
        let c90 = (-aim).cross(c0);
        let gamma = d.dot(aim).clamp(-1.0, 1.0).acos().to_degrees();
        // Along the axis C is undefined (and atan2 of signed zeros would pick 180°): take 0.
        let (y, x) = (d.dot(c90), d.dot(c0));
        let c = if x.abs() + y.abs() < 1e-12 {
            0.0
        } else {
            y.atan2(x).to_degrees()
        };
        self.photometry.intensity(c, gamma)
    }

    /// Luminous (or radiant) flux, RGB: the tint × the distribution's integral.
    pub fn flux(&self) -> DVec3 {
        self.tint.as_dvec3() * self.photometry.flux()
    }
}

/// Luminance of an RGB triple (Rec. 709 weights, as `docs/scene-format.md` reports one number).
pub fn luminance(rgb: Vec3) -> f32 {
    0.2126 * rgb.x + 0.7152 * rgb.y + 0.0722 * rgb.z
}

/// A light at a point, as direct light, the path tracer and the patches see it.
#[derive(Clone, Debug, PartialEq)]
pub struct PointSource {
    /// Position.
    pub position: Vec3,
    /// Isotropic intensity (RGB), or the luminaire's tint.
    pub intensity: Vec3,
    /// The luminaire's distribution, if any.
    pub luminaire: Option<Luminaire>,
}

impl PointSource {
    /// Intensity (RGB) towards `dir` (from the source, any length).
    pub fn towards(&self, dir: Vec3) -> Vec3 {
        match &self.luminaire {
            None => self.intensity,
            Some(l) => self.intensity * l.candela_towards(dir) as f32,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn c_and_gamma_follow_aim_and_c0() {
        // Aimed down, C 0 along +x; the file: 0–180 bilateral, C 0 → 100 cd, C 90 → 200,
        // C 180 → 300 at every γ up to 90.
        let text =
            "TILT=NONE\n1 1 1 2 3 1 2 0 0 0\n1 1 0\n0 90\n0 90 180\n100 100\n200 200\n300 300\n";
        let photometry = Arc::new(Photometry::parse(Path::new("t.ies"), text).unwrap());
        let l = Luminaire {
            position: Vec3::ZERO,
            aim: -Vec3::Y,
            c0: Vec3::X,
            tint: Vec3::ONE,
            photometry,
        };
        // Straight down: γ 0 (C undefined; 0 here).
        assert_eq!(l.candela_towards(-Vec3::Y), 100.0);
        // Towards +x, 45° down: C 0.
        assert!((l.candela_towards(Vec3::new(1.0, -1.0, 0.0)) - 100.0).abs() < 1e-6);
        // C 90 lies along (−aim) × c0 = +y × +x = −z.
        assert!((l.candela_towards(Vec3::new(0.0, -1.0, -1.0)) - 200.0).abs() < 1e-6);
        // −x: C 180; +z: C 270, mirrored to 90.
        assert!((l.candela_towards(Vec3::new(-1.0, -0.2, 0.0)) - 300.0).abs() < 1e-6);
        assert!((l.candela_towards(Vec3::new(0.0, -0.5, 1.0)) - 200.0).abs() < 1e-6);
        // Above the horizon: γ > 90, dark.
        assert_eq!(l.candela_towards(Vec3::new(1.0, 0.5, 0.0)), 0.0);
    }
}
