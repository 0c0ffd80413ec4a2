//! MTL material libraries: our own line-by-line pass reads every key the scene format uses
//! (`Kd`, `Ke`, the specular keys, `map_Kd`) with its line, hands tobj only `newmtl`, `Kd` and
//! `Ke`, and turns tobj's materials into ours, each problem named at its file and line.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::Vec3;

use super::obj::{read_text, Rules};
use super::validate::{self, MaterialField};
use super::{Kind, Material};
use crate::error::{Error, Result};

/// An MTL file reduced to `newmtl`, `Kd` and `Ke`, with where each material's lines are.
pub(super) struct MtlLibrary {
    pub path: PathBuf,
    /// The text tobj reads: `newmtl`, `Kd` and `Ke` only, at their lines.
    pub text: String,
    /// One entry per `newmtl`, in file order (the order tobj returns materials in).
    materials: Vec<MtlLines>,
}

struct MtlLines {
    name: String,
    line: usize,
    kd_line: Option<usize>,
    ke_line: Option<usize>,
    /// The specular keys, each with its value and line.
    ks: Option<(Vec3, usize)>,
    ns: Option<(f32, usize)>,
    pr: Option<(f32, usize)>,
    pm: Option<(f32, usize)>,
    ni: Option<(f32, usize)>,
    tf: Option<(Vec3, usize)>,
    illum: Option<(u32, usize)>,
}

pub(super) fn read_mtl(files: &dyn super::Source, path: &Path) -> Result<MtlLibrary> {
    let text = read_text(files, path)?;
    let mut out = String::with_capacity(text.len());
    let mut materials: Vec<MtlLines> = Vec::new();
    let mut seen: HashMap<String, usize> = HashMap::new();
    for (i, raw) in text.split('\n').enumerate() {
        let line = i + 1;
        let fail = |problem: String| Err(Error::scene(path, Some(line), problem));
        let mut words = raw.split_whitespace();
        match words.next() {
            Some("newmtl") => {
                let name = raw.trim()["newmtl".len()..].trim();
                if name.is_empty() {
                    return fail("newmtl without a material name".into());
                }
                if let Some(first) = seen.insert(name.to_string(), line) {
                    return fail(format!(
                        "material '{name}' is defined twice (lines {first} and {line})"
                    ));
                }
                materials.push(MtlLines {
                    name: name.into(),
                    line,
                    kd_line: None,
                    ke_line: None,
                    ks: None,
                    ns: None,
                    pr: None,
                    pm: None,
                    ni: None,
                    tf: None,
                    illum: None,
                });
                out.push_str("newmtl ");
                out.push_str(name);
            }
            Some(key @ ("Kd" | "Ke")) => {
                let Some(current) = materials.last_mut() else {
                    return fail(format!("{key} before any newmtl"));
                };
                let values: Vec<&str> = words.collect();
                let numbers: Vec<f32> = values.iter().filter_map(|w| w.parse().ok()).collect();
                let rgb = match numbers[..] {
                    [r, g, b] if values.len() == 3 => [r, g, b],
                    [v] if values.len() == 1 => [v; 3],
                    _ => {
                        return fail(format!(
                            "material '{}': {key} needs three numbers r g b, found '{}'",
                            current.name,
                            values.join(" ")
                        ))
                    }
                };
                *if key == "Kd" {
                    &mut current.kd_line
                } else {
                    &mut current.ke_line
                } = Some(line);
                out.push_str(&format!("{key} {} {} {}", rgb[0], rgb[1], rgb[2]));
            }
            Some(key @ ("Ks" | "Tf")) => {
                let Some(current) = materials.last_mut() else {
                    return fail(format!("{key} before any newmtl"));
                };
                let values: Vec<&str> = words.collect();
                let numbers: Vec<f32> = values.iter().filter_map(|w| w.parse().ok()).collect();
                let rgb = match numbers[..] {
                    [r, g, b] if values.len() == 3 => Vec3::new(r, g, b),
                    [v] if values.len() == 1 => Vec3::splat(v),
                    _ => {
                        return fail(format!(
                            "material '{}': {key} needs three numbers r g b, found '{}' (spectral \
                             and CIE XYZ forms are not read)",
                            current.name,
                            values.join(" ")
                        ))
                    }
                };
                if !rgb.is_finite() || rgb.min_element() < 0.0 || rgb.max_element() > 1.0 {
                    return fail(format!(
                        "material '{}': {key} {} {} {} is outside [0, 1]",
                        current.name, rgb.x, rgb.y, rgb.z
                    ));
                }
                *if key == "Ks" {
                    &mut current.ks
                } else {
                    &mut current.tf
                } = Some((rgb, line));
            }
            Some(key @ ("Ns" | "Pr" | "Pm" | "Ni")) => {
                let Some(current) = materials.last_mut() else {
                    return fail(format!("{key} before any newmtl"));
                };
                let values: Vec<&str> = words.collect();
                let value = match values[..] {
                    [v] => v.parse::<f32>().ok().filter(|v| v.is_finite()),
                    _ => None,
                };
                let Some(value) = value else {
                    return fail(format!(
                        "material '{}': {key} needs one number, found '{}'",
                        current.name,
                        values.join(" ")
                    ));
                };
                let (slot, range) = match key {
                    "Ns" => (&mut current.ns, 0.0..=f32::MAX),
                    "Pr" => (&mut current.pr, 0.0..=1.0),
                    "Pm" => (&mut current.pm, 0.0..=1.0),
                    _ => (&mut current.ni, 0.0..=f32::MAX),
                };
                if !range.contains(&value) {
                    return fail(format!(
                        "material '{}': {key} {value} is outside [{}, {}]",
                        current.name,
                        range.start(),
                        if *range.end() == f32::MAX {
                            "∞".to_string()
                        } else {
                            range.end().to_string()
                        }
                    ));
                }
                *slot = Some((value, line));
            }
            Some("illum") => {
                let Some(current) = materials.last_mut() else {
                    return fail("illum before any newmtl".into());
                };
                let values: Vec<&str> = words.collect();
                let Some(model) = values.first().and_then(|v| v.parse::<u32>().ok()) else {
                    return fail(format!(
                        "material '{}': illum needs an illumination model number, found '{}'",
                        current.name,
                        values.join(" ")
                    ));
                };
                current.illum = Some((model, line));
            }
            _ => {}
        }
        out.push('\n');
    }
    Ok(MtlLibrary {
        path: path.to_path_buf(),
        text: out,
        materials,
    })
}

/// Our materials from tobj's, checked, each error at its MTL file and line.
pub(super) fn materials_from(
    loaded: &[tobj::Material],
    libraries: &[MtlLibrary],
    rules: &Rules,
    warnings: &mut Vec<String>,
) -> Result<Vec<Material>> {
    let lines: Vec<(&Path, &MtlLines)> = libraries
        .iter()
        .flat_map(|l| l.materials.iter().map(move |m| (l.path.as_path(), m)))
        .collect();
    let mut seen: HashMap<&str, &Path> = HashMap::new();
    let mut materials = Vec::with_capacity(loaded.len());
    for (i, t) in loaded.iter().enumerate() {
        let Some(&(path, at)) = lines.get(i).filter(|(_, at)| at.name == t.name) else {
            return Err(Error::Scene {
                path: libraries
                    .first()
                    .map(|l| l.path.clone())
                    .unwrap_or_default(),
                line: None,
                problem: format!("material '{}' could not be matched to its MTL line", t.name),
            });
        };
        if let Some(first) = seen.insert(&at.name, path) {
            return Err(Error::scene(
                path,
                Some(at.line),
                format!(
                    "material '{}' is also defined in {}",
                    at.name,
                    first.display()
                ),
            ));
        }
        let mut material = Material::diffuse(
            t.name.clone(),
            t.diffuse.map(Vec3::from).unwrap_or(Vec3::ZERO),
            t.emissive.map(Vec3::from).unwrap_or(Vec3::ZERO),
        );
        let kd = material.kd;
        if kd.to_array().contains(&1.0) {
            // Many exporters write white as 1: lowered, or refused when asked to be strict.
            let at_kd = at.kd_line.or(Some(at.line));
            let said = format!("material '{}': Kd {} {} {}", at.name, kd.x, kd.y, kd.z);
            if rules.strict {
                return Err(Error::scene(
                    path,
                    at_kd,
                    format!(
                        "{said} reflects all light in a channel, which nothing real does (strict)"
                    ),
                ));
            }
            let r = rules.max_reflectance;
            material.kd = Vec3::from(kd.to_array().map(|c| if c == 1.0 { r } else { c }));
            warnings.push(format!(
                "{}:{}: {said}: a channel of 1 reflects all light, which nothing real does: \
                 lowered to {r} (max_reflectance; strict loading refuses it)",
                path.display(),
                at_kd.unwrap_or(at.line),
            ));
        }
        specular_kind(&mut material, at, path, rules, warnings)?;
        if let Some((field, problem)) = validate::material_field(&material) {
            let line = match field {
                MaterialField::Kd => at.kd_line,
                MaterialField::Ke => at.ke_line,
                MaterialField::Ks => at.ks.map(|v| v.1).or(at.pm.map(|v| v.1)),
                MaterialField::Roughness => at.pr.or(at.ns).map(|v| v.1),
                MaterialField::Ior => at.ni.map(|v| v.1),
                MaterialField::Transmit => at.tf.map(|v| v.1),
            };
            return Err(Error::scene(path, line.or(Some(at.line)), problem));
        }
        if at.kd_line.is_none() && !material.is_emitter() && !material.is_specular() {
            warnings.push(format!(
                "{}:{}: material '{}' has no Kd: it reflects no light",
                path.display(),
                at.line,
                at.name
            ));
        }
        materials.push(material);
    }
    Ok(materials)
}

/// What the MTL's `illum`, `Ks`, `Ns`, `Pr`, `Pm`, `Ni` and `Tf` make of a material
/// (`docs/scene-format.md`, "Specular materials"): `Pm` the metallic workflow whatever `illum`
/// says; `illum` 3 or 5 reflection (Ks, roughness from `Pr` or `Ns`); 4, 6 or 7 smooth glass
/// (`Ni`, `Tf`); 0, 1, 2 or none diffuse (the Phong `Ks` exporters write is no reflected light).
/// Kd + Ks above 1 is scaled down to `max_reflectance` with a warning, or refused when strict.
fn specular_kind(
    material: &mut Material,
    at: &MtlLines,
    path: &Path,
    rules: &Rules,
    warnings: &mut Vec<String>,
) -> Result<()> {
    let name = &at.name;
    let here = |line: Option<usize>| format!("{}:{}", path.display(), line.unwrap_or(at.line));
    let roughness = |default: f32| match (at.pr, at.ns) {
        (Some((r, _)), _) => r,
        (None, Some((ns, _))) => super::roughness_from_ns(ns),
        (None, None) => default,
    };
    if let Some((pm, _)) = at.pm {
        if pm > 0.0 {
            let kd = material.kd;
            material.kd = kd * (1.0 - pm);
            material.kind = Kind::Specular {
                ks: kd * pm,
                roughness: at.pr.map_or(0.5, |p| p.0),
            };
        }
        return Ok(());
    }
    match at.illum.map(|i| i.0) {
        None | Some(0..=2) => {}
        Some(3 | 5) => {
            let ks = at.ks.map_or(Vec3::ZERO, |k| k.0);
            if ks == Vec3::ZERO {
                warnings.push(format!(
                    "{}: material '{name}': illum 3 or 5 asks for reflection, but it has no Ks: \
                     it reflects nothing specularly",
                    here(at.illum.map(|i| i.1))
                ));
            }
            let mut kd = material.kd;
            let mut ks = ks;
            if let Some((lower_kd, lower_ks)) =
                super::material::energy_capped(kd, ks, rules.max_reflectance)
            {
                let said = format!(
                    "material '{name}': Kd {} {} {} + Ks {} {} {} exceeds 1",
                    kd.x, kd.y, kd.z, ks.x, ks.y, ks.z
                );
                let line = at.ks.map(|k| k.1);
                if rules.strict {
                    return Err(Error::scene(
                        path,
                        line,
                        format!("{said}: it would reflect more light than arrives (strict)"),
                    ));
                }
                warnings.push(format!(
                    "{}: {said}: both scaled down to sum to {} (max_reflectance; strict loading \
                     refuses it)",
                    here(line),
                    rules.max_reflectance
                ));
                (kd, ks) = (lower_kd, lower_ks);
            }
            material.kd = kd;
            material.kind = Kind::Specular {
                ks,
                roughness: roughness(0.0),
            };
        }
        Some(4 | 6 | 7) => {
            if material.kd != Vec3::ZERO
                || material.ke != Vec3::ZERO
                || at.ks.is_some_and(|k| k.0 != Vec3::ZERO)
            {
                warnings.push(format!(
                    "{}: material '{name}' is glass (illum {}): its Kd, Ks and Ke are ignored",
                    here(at.illum.map(|i| i.1)),
                    at.illum.map_or(0, |i| i.0)
                ));
            }
            material.kd = Vec3::ZERO;
            material.ke = Vec3::ZERO;
            material.kind = Kind::Glass {
                ior: at.ni.map_or(1.5, |n| n.0),
                transmit: at.tf.map_or(Vec3::ONE, |t| t.0),
                thin: false,
            };
        }
        Some(other) => warnings.push(format!(
            "{}: material '{name}': illum {other} is not a model meshlight reads (0-2 diffuse, \
             3 or 5 reflection, 4, 6 or 7 glass): read as diffuse",
            here(at.illum.map(|i| i.1))
        )),
    }
    Ok(())
}
