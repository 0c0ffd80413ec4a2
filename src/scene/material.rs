//! What a surface is made of (`docs/scene-format.md`, "Materials" and "Specular materials"):
//! diffuse reflectance and emission, and what it does with light beyond diffuse reflection —
//! a mirror or a glossy GGX lobe, or smooth glass.

use std::sync::Arc;

use glam::Vec3;

use super::Texture;

/// A material: diffuse reflectance Kd, Lambertian emission Ke, and its kind.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Material {
    /// The material's name (from `newmtl`).
    pub name: String,
    /// Diffuse reflectance, each channel in [0, 1); Kd + Ks ≤ 1 for specular materials; 0 for
    /// glass.
    pub kd: Vec3,
    /// Emitted radiance of a Lambertian emitter (W·sr⁻¹·m⁻²); non-zero makes an area light.
    pub ke: Vec3,
    /// Diffuse, specular (a mirror or a glossy lobe on top of Kd) or glass.
    pub kind: Kind,
    /// Whether it reflects on both sides whatever the scene's `two_sided` says.
    pub two_sided: bool,
    /// A diffuse-reflectance texture (`map_Kd`, glTF's base colour texture): where a face has
    /// texture coordinates its reflectance is Kd × the texel; elsewhere Kd.
    pub texture: Option<Arc<Texture>>,
}

/// What a material does with light beyond Lambertian reflection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// Lambertian reflection only (Kd).
    Diffuse,
    /// f = Kd/π + Ks·f_s: a perfect mirror for roughness 0, else a GGX (Trowbridge–Reitz)
    /// microfacet lobe with α = roughness², Smith's separable masking-shadowing, F = 1
    /// (Mitsuba 3's `roughconductor` with `material = "none"`).
    Specular {
        /// Specular reflectance, each channel in [0, 1].
        ks: Vec3,
        /// Roughness r in [0, 1]: α = r².
        roughness: f32,
    },
    /// A smooth dielectric against air: Fresnel reflection and Snell refraction, the
    /// transmitted light filtered by `transmit`. The front of its faces is the outside, unless
    /// `thin`: then each face is a pane, reflecting R' = 2R/(1 + R) and passing the rest
    /// (times `transmit`) without changing direction.
    Glass {
        /// Index of refraction, ≥ 1.
        ior: f32,
        /// Transmission filter, each channel in [0, 1].
        transmit: Vec3,
        /// A one-face pane.
        thin: bool,
    },
}

impl Kind {
    /// The name a scene file's `kind` key uses.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Diffuse => "diffuse",
            Kind::Specular { roughness: 0.0, .. } => "specular (mirror)",
            Kind::Specular { .. } => "specular (glossy)",
            Kind::Glass { thin: true, .. } => "glass (thin pane)",
            Kind::Glass { .. } => "glass",
        }
    }
}

impl Material {
    /// A diffuse material reflecting `kd` and emitting `ke`.
    pub fn diffuse(name: impl Into<String>, kd: Vec3, ke: Vec3) -> Material {
        Material {
            name: name.into(),
            kd,
            ke,
            kind: Kind::Diffuse,
            two_sided: false,
            texture: None,
        }
    }

    /// Whether it reflects light diffusely anywhere: Kd, or its texture, above 0.
    pub fn reflects_diffusely(&self) -> bool {
        let texture = self.texture.as_ref().map_or(Vec3::ZERO, |t| t.mean());
        self.kd.max_element() > 0.0 || (self.kd * texture).max_element() > 0.0
    }

    /// Whether faces of this material emit light.
    pub fn is_emitter(&self) -> bool {
        self.ke.max_element() > 0.0
    }

    /// Whether light leaves it other than diffusely: a mirror, a glossy lobe or glass. Diffuse
    /// materials, and specular ones whose Ks is 0, are not.
    pub fn is_specular(&self) -> bool {
        match self.kind {
            Kind::Diffuse => false,
            Kind::Specular { ks, .. } => ks.max_element() > 0.0,
            Kind::Glass { .. } => true,
        }
    }

    /// Whether it reflects specularly like a perfect mirror (no lobe).
    pub fn is_mirror(&self) -> bool {
        matches!(self.kind, Kind::Specular { ks, roughness } if roughness == 0.0 && ks.max_element() > 0.0)
    }
}

/// Roughness from a Phong exponent Ns: α = r² = √(2 / (Ns + 2)) (the Phong–Beckmann
/// correspondence of Walter et al. 2007); Ns ≥ 10,000 is a perfect mirror.
pub fn roughness_from_ns(ns: f32) -> f32 {
    if ns >= 10_000.0 {
        0.0
    } else {
        (2.0 / (ns.max(0.0) + 2.0)).sqrt().sqrt()
    }
}

/// Kd and Ks scaled down together so that their largest channel sum is `max_reflectance`, when
/// some channel of Kd + Ks exceeds 1 (what exporters write for metals); `None` when it does
/// not.
pub(crate) fn energy_capped(kd: Vec3, ks: Vec3, max_reflectance: f32) -> Option<(Vec3, Vec3)> {
    let sum = (kd + ks).max_element();
    (sum > 1.0).then(|| {
        let s = max_reflectance / sum;
        (kd * s, ks * s)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ns_maps_to_roughness_by_walter_et_al() {
        // α = √(2/(Ns+2)): Ns 0 gives α = 1 (r = 1); Ns 198 gives α = 0.1 (r = √0.1).
        assert!((roughness_from_ns(0.0) - 1.0).abs() < 1e-6);
        assert!((roughness_from_ns(198.0) - 0.1f32.sqrt()).abs() < 1e-6);
        assert_eq!(roughness_from_ns(10_000.0), 0.0);
    }

    #[test]
    fn kd_plus_ks_above_one_is_scaled_to_the_bound() {
        let (kd, ks) = energy_capped(Vec3::splat(0.8), Vec3::splat(0.5), 0.9).unwrap();
        assert!(((kd + ks).max_element() - 0.9).abs() < 1e-6);
        assert!((kd.x / ks.x - 0.8 / 0.5).abs() < 1e-5, "the ratio stays");
        assert_eq!(
            energy_capped(Vec3::ZERO, Vec3::ONE, 0.9),
            None,
            "an ideal mirror"
        );
    }
}
