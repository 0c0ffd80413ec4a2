//! Material overrides (`docs/scene-format.md`, "Material overrides"): `[material.NAME]` tables
//! in the scene file that fix a material without editing an export. Every key is optional and
//! replaces what the MTL said; the same checks apply, naming the scene file and the key's line.

use std::path::Path;

use glam::Vec3;

use super::material::energy_capped;
use super::mtl::Rules;
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
/// (an error when `rules.strict`), like the MTL's.
pub(crate) fn apply(
    path: &Path,
    overrides: &[Override],
    materials: &mut [Material],
    rules: &Rules,
    warnings: &mut Vec<String>,
) -> Result<()> {
    for o in overrides {
        let Some(m) = materials.iter_mut().find(|m| m.name == o.name) else {
            let known: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
            return Err(Error::scene(
                path,
                Some(o.line),
                format!(
                    "[material.{}]: the scene has no such material (it has {})",
                    o.name,
                    known.join(", ")
                ),
            ));
        };
        let warned = |said: String| warnings.push(format!("{}:{said}", path.display()));
        apply_one(o, m, rules, warned)
            .map_err(|(line, problem)| Error::scene(path, Some(line), problem))?;
    }
    Ok(())
}

/// Why an override is refused: the line of the key at fault, and the problem.
type Refusal = (usize, String);

/// One override on its material: the plain keys, the kind and that kind's keys, then the
/// energy cap and the checks every material gets.
fn apply_one(
    o: &Override,
    m: &mut Material,
    rules: &Rules,
    warn: impl FnMut(String),
) -> std::result::Result<(), Refusal> {
    if let Some((kd, _)) = o.kd {
        m.kd = kd;
    }
    if let Some((ke, _)) = o.ke {
        m.ke = ke;
    }
    if let Some((two_sided, _)) = o.two_sided {
        m.two_sided = two_sided;
    }
    m.kind = kind(o, m.kind)?;
    specular_keys(o, m)?;
    glass_keys(o, m)?;
    cap_energy(o, m, rules, warn)?;
    match validate::material_field(m) {
        Some((field, problem)) => {
            let line = match field {
                MaterialField::Kd => o.kd.map(|v| v.1),
                MaterialField::Ke => o.ke.map(|v| v.1),
                MaterialField::Ks => o.ks.map(|v| v.1),
                MaterialField::Roughness => o.roughness.map(|v| v.1),
                MaterialField::Ior => o.ior.map(|v| v.1),
                MaterialField::Transmit => o.transmit.map(|v| v.1),
            };
            Err((
                line.unwrap_or(o.line),
                format!("[material.{}]: {problem}", o.name),
            ))
        }
        None => Ok(()),
    }
}

/// The kind `kind = "..."` asks for; a material that already is of that kind keeps its
/// parameters, another one starts from the kind's defaults.
fn kind(o: &Override, was: Kind) -> std::result::Result<Kind, Refusal> {
    Ok(match o.kind.as_ref().map(|(k, l)| (k.as_str(), *l)) {
        None => was,
        Some(("diffuse", _)) => Kind::Diffuse,
        Some(("specular", _)) => match was {
            Kind::Specular { .. } => was,
            _ => Kind::Specular {
                ks: Vec3::ZERO,
                roughness: 0.0,
            },
        },
        Some(("glass", _)) => match was {
            Kind::Glass { .. } => was,
            _ => Kind::Glass {
                ior: 1.5,
                transmit: Vec3::ONE,
                thin: false,
            },
        },
        Some((other, line)) => {
            return Err((
                line,
                format!(
                    "[material.{}]: kind = \"{other}\": one of \"diffuse\", \"specular\", \
                     \"glass\"",
                    o.name
                ),
            ))
        }
    })
}

/// A key that applies to another kind than the material's.
fn key_on(o: &Override, key: &str, wanted: &str, line: usize, kind: Kind) -> Refusal {
    (
        line,
        format!(
            "[material.{}]: {key} applies to kind = \"{wanted}\"; this material is {}",
            o.name,
            kind.name()
        ),
    )
}

/// `ks` and `roughness`, on a specular material only.
fn specular_keys(o: &Override, m: &mut Material) -> std::result::Result<(), Refusal> {
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
                return Err(key_on(o, "ks", "specular", line, m.kind));
            }
            if let Some((_, line)) = o.roughness {
                return Err(key_on(o, "roughness", "specular", line, m.kind));
            }
        }
    }
    Ok(())
}

/// `ior`, `transmit` and `thin`, on glass only; glass neither reflects diffusely nor emits, so
/// what the MTL said of those is dropped (what the table says is checked with the rest).
fn glass_keys(o: &Override, m: &mut Material) -> std::result::Result<(), Refusal> {
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
                    return Err(key_on(o, key, "glass", line, m.kind));
                }
            }
        }
    }
    Ok(())
}

/// A specular material whose Kd + Ks passes 1 in a channel: both scaled down to
/// `max_reflectance`, with a warning (refused when strict).
fn cap_energy(
    o: &Override,
    m: &mut Material,
    rules: &Rules,
    mut warn: impl FnMut(String),
) -> std::result::Result<(), Refusal> {
    let Kind::Specular { ks, roughness } = m.kind else {
        return Ok(());
    };
    let Some((kd, lower)) = energy_capped(m.kd, ks, rules.max_reflectance) else {
        return Ok(());
    };
    let line = o.ks.or(o.kd).map_or(o.line, |v| v.1);
    let said = format!(
        "[material.{}]: kd {} {} {} + ks {} {} {} exceeds 1",
        o.name, m.kd.x, m.kd.y, m.kd.z, ks.x, ks.y, ks.z
    );
    if rules.strict {
        return Err((
            line,
            format!("{said}: it would reflect more light than arrives (strict)"),
        ));
    }
    warn(format!(
        "{line}: {said}: both scaled down to sum to {} (max_reflectance; strict loading refuses \
         it)",
        rules.max_reflectance
    ));
    m.kd = kd;
    m.kind = Kind::Specular {
        ks: lower,
        roughness,
    };
    Ok(())
}
