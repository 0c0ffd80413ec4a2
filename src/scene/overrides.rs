//! Material overrides (`docs/scene-format.md`, "Material overrides"): `[material.NAME]` tables
//! in the scene file that fix a material without editing an export. Every key is optional and
//! replaces what the MTL said; the same checks apply, naming the scene file and the key's line.

use std::path::Path;

use glam::Vec3;

use super::material::energy_capped;
use super::validate::{self, MaterialField};
use super::{Kind, Material};
use crate::error::{Error, Result};

/// One `[material.NAME]` table, each key with the line it is on.
#[derive(Clone, Debug, Default)]
pub(crate) struct Override {
    pub name: String,
    pub line: usize,
    pub kind: Option<(String, usize)>,
    pub kd: Option<(Vec3, usize)>,
    pub ks: Option<(Vec3, usize)>,
    pub roughness: Option<(f32, usize)>,
    pub ior: Option<(f32, usize)>,
    pub transmit: Option<(Vec3, usize)>,
    pub thin: Option<(bool, usize)>,
    pub ke: Option<(Vec3, usize)>,
    pub two_sided: Option<(bool, usize)>,
}

/// Applies the overrides to the materials they name; `path` is the scene file. A name no
/// material has is an error naming the table; Kd + Ks above 1 is scaled down with a warning
/// (an error when `strict`), like the MTL's.
pub(crate) fn apply(
    path: &Path,
    overrides: &[Override],
    materials: &mut [Material],
    (max_reflectance, strict): (f32, bool),
    warnings: &mut Vec<String>,
) -> Result<()> {
    for o in overrides {
        let fail = |line: usize, problem: String| Err(Error::scene(path, Some(line), problem));
        let Some(m) = materials.iter_mut().find(|m| m.name == o.name) else {
            let known: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
            return fail(
                o.line,
                format!(
                    "[material.{}]: the scene has no such material (it has {})",
                    o.name,
                    known.join(", ")
                ),
            );
        };
        let name = &o.name;
        let key_on = |key: &str, wanted: &str, line: usize, kind: Kind| {
            fail(
                line,
                format!(
                    "[material.{name}]: {key} applies to kind = \"{wanted}\"; this material is {}",
                    kind.name()
                ),
            )
        };
        if let Some((kd, _)) = o.kd {
            m.kd = kd;
        }
        if let Some((ke, _)) = o.ke {
            m.ke = ke;
        }
        if let Some((two_sided, _)) = o.two_sided {
            m.two_sided = two_sided;
        }
        m.kind = match o.kind.as_ref().map(|(k, l)| (k.as_str(), *l)) {
            None => m.kind,
            Some(("diffuse", _)) => Kind::Diffuse,
            Some(("specular", _)) => match m.kind {
                Kind::Specular { .. } => m.kind,
                _ => Kind::Specular {
                    ks: Vec3::ZERO,
                    roughness: 0.0,
                },
            },
            Some(("glass", _)) => match m.kind {
                Kind::Glass { .. } => m.kind,
                _ => Kind::Glass {
                    ior: 1.5,
                    transmit: Vec3::ONE,
                    thin: false,
                },
            },
            Some((other, line)) => {
                return fail(
                    line,
                    format!(
                        "[material.{name}]: kind = \"{other}\": one of \"diffuse\", \"specular\", \
                         \"glass\""
                    ),
                )
            }
        };
        match &mut m.kind {
            Kind::Specular { ks, roughness } => {
                if let Some((v, _)) = o.ks {
                    *ks = v;
                }
                if let Some((r, _)) = o.roughness {
                    *roughness = r;
                }
            }
            _ => {
                if let Some((_, line)) = o.ks {
                    return key_on("ks", "specular", line, m.kind);
                }
                if let Some((_, line)) = o.roughness {
                    return key_on("roughness", "specular", line, m.kind);
                }
            }
        }
        match &mut m.kind {
            Kind::Glass {
                ior,
                transmit,
                thin,
            } => {
                if let Some((v, _)) = o.ior {
                    *ior = v;
                }
                if let Some((v, _)) = o.transmit {
                    *transmit = v;
                }
                if let Some((v, _)) = o.thin {
                    *thin = v;
                }
                // Glass neither reflects diffusely nor emits: what the MTL said is dropped,
                // what the table says is checked below.
                if o.kd.is_none() {
                    m.kd = Vec3::ZERO;
                }
                if o.ke.is_none() {
                    m.ke = Vec3::ZERO;
                }
            }
            _ => {
                for (key, line) in [
                    ("ior", o.ior.map(|v| v.1)),
                    ("transmit", o.transmit.map(|v| v.1)),
                    ("thin", o.thin.map(|v| v.1)),
                ] {
                    if let Some(line) = line {
                        return key_on(key, "glass", line, m.kind);
                    }
                }
            }
        }
        if let Kind::Specular { ks, roughness } = m.kind {
            if let Some((kd, lower)) = energy_capped(m.kd, ks, max_reflectance) {
                let line = o.ks.or(o.kd).map_or(o.line, |v| v.1);
                let said = format!(
                    "[material.{name}]: kd {} {} {} + ks {} {} {} exceeds 1",
                    m.kd.x, m.kd.y, m.kd.z, ks.x, ks.y, ks.z
                );
                if strict {
                    return fail(
                        line,
                        format!("{said}: it would reflect more light than arrives (strict)"),
                    );
                }
                warnings.push(format!(
                    "{}:{line}: {said}: both scaled down to sum to {max_reflectance} \
                     (max_reflectance; strict loading refuses it)",
                    path.display()
                ));
                m.kd = kd;
                m.kind = Kind::Specular {
                    ks: lower,
                    roughness,
                };
            }
        }
        if let Some((field, problem)) = validate::material_field(m) {
            let line = match field {
                MaterialField::Kd => o.kd.map(|v| v.1),
                MaterialField::Ke => o.ke.map(|v| v.1),
                MaterialField::Ks => o.ks.map(|v| v.1),
                MaterialField::Roughness => o.roughness.map(|v| v.1),
                MaterialField::Ior => o.ior.map(|v| v.1),
                MaterialField::Transmit => o.transmit.map(|v| v.1),
            };
            return fail(
                line.unwrap_or(o.line),
                format!("[material.{name}]: {problem}"),
            );
        }
    }
    Ok(())
}
