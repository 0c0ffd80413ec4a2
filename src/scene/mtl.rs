//! MTL material libraries: our own line-by-line pass reads every key the scene format uses
//! (`Kd`, `Ke`, the specular keys, `map_Kd`) with its line, hands tobj only `newmtl`, `Kd` and
//! `Ke`, and turns tobj's materials into ours, each problem named at its file and line.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::source::read_text;
use super::validate::{self, MaterialField};
use super::{Kind, Material, Texture};
use crate::error::{Error, Result};

/// Reflectance given to faces that name no material (`docs/scene-format.md`).
pub(super) const DEFAULT_KD: f32 = 0.5;

/// What the scene format leaves to the reader: reflectances of exactly 1.
pub(super) struct Rules {
    /// What a Kd channel of exactly 1 is lowered to.
    pub max_reflectance: f32,
    /// Whether such a channel is an error instead.
    pub strict: bool,
}

/// An MTL file reduced to `newmtl`, `Kd` and `Ke`, with where each material's lines are.
pub(super) struct MtlLibrary {
    /// What reading it found worth saying (ignored `map_Kd` options).
    pub warnings: Vec<String>,
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
    map_kd: Option<MapKd>,
}

/// A `map_Kd` statement: the file and the options read from before it.
pub(super) struct MapKd {
    file: String,
    line: usize,
    /// `-s`: texture coordinates are scaled by it, then `-o` added (u and v; w is unused).
    scale: Vec2,
    offset: Vec2,
}

/// How a material's OBJ texture coordinates become image coordinates: `-s` and `-o` from its
/// `map_Kd`, then v flipped (OBJ's v runs up the image).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct UvTransform {
    pub scale: Vec2,
    pub offset: Vec2,
}

impl UvTransform {
    /// The image coordinates of OBJ texture coordinates `vt`.
    pub fn apply(&self, vt: Vec2) -> Vec2 {
        let uv = vt * self.scale + self.offset;
        Vec2::new(uv.x, 1.0 - uv.y)
    }
}

/// Options `map_Kd` may carry before the file name, with how many values each takes; only
/// `-s` and `-o` change what meshlight shows, the others are ignored with a warning. Any other
/// option (exporters write `-colorspace sRGB`) is ignored with a warning too, with the one
/// value after it where a file name still follows.
const MAP_OPTIONS: [(&str, usize); 12] = [
    ("-blendu", 1),
    ("-blendv", 1),
    ("-bm", 1),
    ("-boost", 1),
    ("-cc", 1),
    ("-clamp", 1),
    ("-imfchan", 1),
    ("-mm", 2),
    ("-texres", 1),
    ("-type", 1),
    ("-o", 3),
    ("-s", 3),
];

pub(super) fn read_mtl(files: &dyn super::Source, path: &Path) -> Result<MtlLibrary> {
    let text = read_text(files, path)?;
    let mut out = String::with_capacity(text.len());
    let mut materials: Vec<MtlLines> = Vec::new();
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut warnings = Vec::new();
    for (i, raw) in text.split('\n').enumerate() {
        let line = i + 1;
        let mut words = raw.split_whitespace();
        let key = words.next();
        let read = match key {
            Some("newmtl") => newmtl(raw, line, &mut seen).map(|name| {
                out.push_str("newmtl ");
                out.push_str(&name);
                materials.push(MtlLines::new(name, line));
            }),
            Some(
                key @ ("Kd" | "Ke" | "Ks" | "Tf" | "Ns" | "Pr" | "Pm" | "Ni" | "illum" | "map_Kd"),
            ) => match materials.last_mut() {
                None => Err(format!("{key} before any newmtl")),
                Some(current) => {
                    let values: Vec<&str> = words.collect();
                    current.read(key, values, line, &mut out, &mut warnings, path)
                }
            },
            _ => Ok(()),
        };
        read.map_err(|problem| Error::scene(path, Some(line), problem))?;
        out.push('\n');
    }
    Ok(MtlLibrary {
        warnings,
        path: path.to_path_buf(),
        text: out,
        materials,
    })
}

/// `newmtl NAME`: the name, once per file.
fn newmtl(
    raw: &str,
    line: usize,
    seen: &mut HashMap<String, usize>,
) -> std::result::Result<String, String> {
    let name = raw.trim()["newmtl".len()..].trim();
    if name.is_empty() {
        return Err("newmtl without a material name".into());
    }
    if let Some(first) = seen.insert(name.to_string(), line) {
        return Err(format!(
            "material '{name}' is defined twice (lines {first} and {line})"
        ));
    }
    Ok(name.to_string())
}

impl MtlLines {
    /// A material's lines before any statement of it.
    fn new(name: String, line: usize) -> MtlLines {
        MtlLines {
            name,
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
            map_kd: None,
        }
    }

    /// One statement `key values` of this material, on `line`: Kd and Ke go on to tobj (into
    /// `out`, normalised), the rest is kept here; `map_Kd`'s warnings (naming `path`) into
    /// `warnings`.
    fn read(
        &mut self,
        key: &str,
        values: Vec<&str>,
        line: usize,
        out: &mut String,
        warnings: &mut Vec<String>,
        path: &Path,
    ) -> std::result::Result<(), String> {
        match key {
            "Kd" | "Ke" => {
                let rgb = self.colour(key, &values, "")?;
                *if key == "Kd" {
                    &mut self.kd_line
                } else {
                    &mut self.ke_line
                } = Some(line);
                out.push_str(&format!("{key} {} {} {}", rgb.x, rgb.y, rgb.z));
            }
            "Ks" | "Tf" => {
                let rgb =
                    self.colour(key, &values, " (spectral and CIE XYZ forms are not read)")?;
                if !rgb.is_finite() || rgb.min_element() < 0.0 || rgb.max_element() > 1.0 {
                    return Err(format!(
                        "material '{}': {key} {} {} {} is outside [0, 1]",
                        self.name, rgb.x, rgb.y, rgb.z
                    ));
                }
                *if key == "Ks" {
                    &mut self.ks
                } else {
                    &mut self.tf
                } = Some((rgb, line));
            }
            "Ns" | "Pr" | "Pm" | "Ni" => self.scalar(key, &values, line)?,
            "map_Kd" => {
                self.map_kd = Some(map_kd(&self.name.clone(), values, line, path, warnings)?);
            }
            _ => {
                // illum
                let Some(model) = values.first().and_then(|v| v.parse::<u32>().ok()) else {
                    return Err(format!(
                        "material '{}': illum needs an illumination model number, found '{}'",
                        self.name,
                        values.join(" ")
                    ));
                };
                self.illum = Some((model, line));
            }
        }
        Ok(())
    }

    /// `key r g b` (or one number for all three), `note` said of what is not read.
    fn colour(&self, key: &str, values: &[&str], note: &str) -> std::result::Result<Vec3, String> {
        let numbers: Vec<f32> = values.iter().filter_map(|w| w.parse().ok()).collect();
        match numbers[..] {
            [r, g, b] if values.len() == 3 => Ok(Vec3::new(r, g, b)),
            [v] if values.len() == 1 => Ok(Vec3::splat(v)),
            _ => Err(format!(
                "material '{}': {key} needs three numbers r g b, found '{}'{note}",
                self.name,
                values.join(" ")
            )),
        }
    }

    /// `Ns`, `Pr`, `Pm` or `Ni`: one finite number in the key's range.
    fn scalar(
        &mut self,
        key: &str,
        values: &[&str],
        line: usize,
    ) -> std::result::Result<(), String> {
        let value = match values[..] {
            [v] => v.parse::<f32>().ok().filter(|v| v.is_finite()),
            _ => None,
        };
        let Some(value) = value else {
            return Err(format!(
                "material '{}': {key} needs one number, found '{}'",
                self.name,
                values.join(" ")
            ));
        };
        let name = self.name.clone();
        let (slot, range) = match key {
            "Ns" => (&mut self.ns, 0.0..=f32::MAX),
            "Pr" => (&mut self.pr, 0.0..=1.0),
            "Pm" => (&mut self.pm, 0.0..=1.0),
            _ => (&mut self.ni, 0.0..=f32::MAX),
        };
        if !range.contains(&value) {
            return Err(format!(
                "material '{name}': {key} {value} is outside [{}, {}]",
                range.start(),
                if *range.end() == f32::MAX {
                    "∞".to_string()
                } else {
                    range.end().to_string()
                }
            ));
        }
        *slot = Some((value, line));
        Ok(())
    }
}

/// Our materials from tobj's, checked, each error at its MTL file and line.
/// Also returns, per material, how its texture coordinates map onto its texture (`None`
/// without one).
pub(super) fn materials_from(
    files: &dyn super::Source,
    loaded: &[tobj::Material],
    libraries: &[MtlLibrary],
    rules: &Rules,
    warnings: &mut Vec<String>,
) -> Result<(Vec<Material>, Vec<Option<UvTransform>>)> {
    let mut transforms = Vec::with_capacity(loaded.len());
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
        let transform = at.map_kd.as_ref().and_then(|map| {
            let has_kd = at.kd_line.is_some();
            texture_of(
                files,
                path,
                map,
                &mut material,
                has_kd,
                rules.max_reflectance,
                warnings,
            )
        });
        transforms.push(transform);
        let kd = material.kd;
        // With a texture Kd only scales texels that are bounded already.
        if kd.to_array().contains(&1.0) && material.texture.is_none() {
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
        if at.kd_line.is_none()
            && at.map_kd.is_none()
            && !material.is_emitter()
            && !material.is_specular()
        {
            warnings.push(format!(
                "{}:{}: material '{}' has no Kd: it reflects no light",
                path.display(),
                at.line,
                at.name
            ));
        }
        materials.push(material);
    }
    Ok((materials, transforms))
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

/// Reads a `map_Kd` statement's words: options, then the file name (which may hold spaces).
fn map_kd(
    material: &str,
    words: Vec<&str>,
    line: usize,
    path: &Path,
    warnings: &mut Vec<String>,
) -> std::result::Result<MapKd, String> {
    let mut map = MapKd {
        file: String::new(),
        line,
        scale: Vec2::ONE,
        offset: Vec2::ZERO,
    };
    let mut i = 0;
    while let Some(&option) = words.get(i).filter(|w| w.starts_with('-')) {
        i += 1;
        let Some(&(_, most)) = MAP_OPTIONS.iter().find(|(o, _)| *o == option) else {
            // Its value, if a word that is not an option follows and the file name after it.
            if words.len() > i + 1 && !words[i].starts_with('-') {
                i += 1;
            }
            warnings.push(format!(
                "{}:{line}: material '{material}': map_Kd option {option} is not one this \
                 reader knows: ignored",
                path.display()
            ));
            continue;
        };
        // -o, -s and -t take one to three numbers; the others a fixed count.
        let mut values = Vec::new();
        while values.len() < most {
            let Some(word) = words.get(i) else { break };
            match word.parse::<f32>() {
                Ok(v) if v.is_finite() => values.push(v),
                _ if matches!(option, "-o" | "-s") && !values.is_empty() => break,
                _ if !matches!(option, "-o" | "-s" | "-mm") => values.push(f32::NAN),
                _ => break,
            }
            i += 1;
        }
        match option {
            "-s" | "-o" => {
                let Some(&u) = values.first() else {
                    return Err(format!(
                        "material '{material}': map_Kd {option} needs one to three numbers"
                    ));
                };
                let uv = Vec2::new(u, values.get(1).copied().unwrap_or(u));
                if option == "-s" {
                    map.scale = uv;
                } else {
                    map.offset = uv;
                }
            }
            _ => warnings.push(format!(
                "{}:{line}: material '{material}': map_Kd option {option} is ignored",
                path.display()
            )),
        }
    }
    map.file = words[i.min(words.len())..].join(" ");
    if map.file.is_empty() {
        return Err(format!("material '{material}': map_Kd without a file name"));
    }
    Ok(map)
}

/// The texture a material's `map_Kd` names, read relative to its MTL file; a file missing or
/// unreadable is a warning (the material keeps Kd, or the default grey without one).
fn texture_of(
    files: &dyn super::Source,
    mtl: &Path,
    map: &MapKd,
    material: &mut Material,
    has_kd: bool,
    max_reflectance: f32,
    warnings: &mut Vec<String>,
) -> Option<UvTransform> {
    let file = mtl.parent().unwrap_or(Path::new("")).join(&map.file);
    let read = files
        .read(&file)
        .map_err(|e| e.to_string())
        .and_then(|bytes| Texture::decode(file.display().to_string(), &bytes, max_reflectance));
    match read {
        Ok(texture) => {
            if !has_kd {
                material.kd = Vec3::ONE;
            }
            material.texture = Some(Arc::new(texture));
            Some(UvTransform {
                scale: map.scale,
                offset: map.offset,
            })
        }
        Err(problem) => {
            let fallback = if has_kd {
                "the material keeps its Kd".to_string()
            } else {
                material.kd = Vec3::splat(DEFAULT_KD);
                format!("the material gets Kd = {} grey", DEFAULT_KD)
            };
            warnings.push(format!(
                "{}:{}: material '{}': texture {} cannot be read ({problem}): {fallback}",
                mtl.display(),
                map.line,
                material.name,
                file.display()
            ));
            None
        }
    }
}
