//! Wavefront OBJ and MTL through `tobj`, behind a line-by-line check of our own.
//!
//! The check runs first so that every problem is reported with its file and line (tobj's errors
//! carry neither) and so that tobj only ever sees statements the scene format uses, in a form it
//! cannot trip over: vertices as `v x y z`, faces as vertex indices only, `usemtl`, `mtllib`;
//! in MTL files `newmtl`, `Kd`, `Ke`. The specular keys (`illum`, `Ks`, `Ns`, `Pr`, `Pm`, `Ni`,
//! `Tf`) are read by the check itself. Everything else is ignored (`docs/scene-format.md`,
//! "Materials"). tobj then does the fan triangulation, the per-material split and the index
//! bookkeeping.

use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::Vec3;

use super::validate::{self, MaterialField};
use super::{Kind, Material, Mesh};
use crate::error::{Error, Result};

/// Reflectance given to faces that name no material (`docs/scene-format.md`).
const DEFAULT_KD: f32 = 0.5;

const OPTIONS: tobj::LoadOptions = tobj::LoadOptions {
    single_index: false,
    triangulate: true,
    ignore_points: true,
    ignore_lines: true,
};

/// What the scene format leaves to the reader: reflectances of exactly 1.
pub(super) struct Rules {
    /// What a Kd channel of exactly 1 is lowered to.
    pub max_reflectance: f32,
    /// Whether such a channel is an error instead.
    pub strict: bool,
}

/// Reads an OBJ file and the MTL files it names; returns the mesh and warnings.
pub(super) fn read(
    files: &dyn super::Source,
    path: &Path,
    rules: &Rules,
) -> Result<(Mesh, Vec<String>)> {
    let text = read_text(files, path)?;
    let prepared = prepare_obj(path, &text)?;
    let dir = path.parent().unwrap_or(Path::new(""));

    let libraries: RefCell<Vec<MtlLibrary>> = RefCell::new(Vec::new());
    let failure: RefCell<Option<Error>> = RefCell::new(None);
    let missing: RefCell<Vec<String>> = RefCell::new(Vec::new());
    // tobj hands over the rest of an `mtllib` line as one name: several files are allowed
    // there (separated by spaces), each read and their materials merged in order.
    let loader = |names: &Path| -> tobj::MTLLoadResult {
        let mut merged: (Vec<tobj::Material>, HashMap<String, usize>) = Default::default();
        let names = names.to_string_lossy();
        for name in names.split_whitespace() {
            let mtl_path = dir.join(name);
            let library = match read_mtl(files, &mtl_path) {
                Ok(library) => library,
                Err(Error::Read { cause, .. }) if cause.kind() == std::io::ErrorKind::NotFound => {
                    let line = prepared.mtllib.iter().find(|(n, _)| n.contains(name));
                    missing.borrow_mut().push(format!(
                        "{}:{}: MTL file {} not found: faces with its materials get Kd = \
                         {DEFAULT_KD} grey",
                        path.display(),
                        line.map_or(0, |l| l.1),
                        mtl_path.display()
                    ));
                    continue;
                }
                Err(e) => {
                    failure.borrow_mut().get_or_insert(e);
                    return Err(tobj::LoadError::OpenFileFailed);
                }
            };
            match tobj::load_mtl_buf(&mut library.text.as_bytes()) {
                Ok((materials, names)) => {
                    let offset = merged.0.len();
                    merged.0.extend(materials);
                    for (name, index) in names {
                        merged.1.entry(name).or_insert(index + offset);
                    }
                    libraries.borrow_mut().push(library);
                }
                Err(e) => {
                    let e = Error::scene(&mtl_path, None, format!("MTL parser: {e}"));
                    failure.borrow_mut().get_or_insert(e);
                    return Err(tobj::LoadError::OpenFileFailed);
                }
            }
        }
        Ok(merged)
    };
    let loaded = tobj::load_obj_buf(&mut prepared.text.as_bytes(), &OPTIONS, loader);
    if let Some(e) = failure.into_inner() {
        return Err(e);
    }
    let (models, tobj_materials) =
        loaded.map_err(|e| Error::scene(path, None, format!("OBJ parser: {e}")))?;
    let tobj_materials = tobj_materials.unwrap_or_default();
    let libraries = libraries.into_inner();

    let mut warnings = missing.into_inner();
    let any_missing = !warnings.is_empty();
    let mut materials = materials_from(&tobj_materials, &libraries, rules, &mut warnings)?;
    // A material a missing MTL file may have defined gets the default grey (below).
    if !any_missing {
        check_usemtl(
            path,
            &prepared.usemtl,
            &materials,
            &libraries,
            &mut warnings,
        );
    }

    let mut mesh = Mesh::default();
    let mut default_material: Option<u32> = None;
    let mut unassigned = 0usize;
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        let material = match m.material_id {
            Some(id) => id as u32,
            None => {
                unassigned += m.indices.len() / 3;
                *default_material.get_or_insert_with(|| {
                    materials.push(Material::diffuse(
                        "(default)",
                        Vec3::splat(DEFAULT_KD),
                        Vec3::ZERO,
                    ));
                    materials.len() as u32 - 1
                })
            }
        };
        for t in m.indices.chunks_exact(3) {
            mesh.triangles.push([base + t[0], base + t[1], base + t[2]]);
            mesh.triangle_materials.push(material);
        }
    }
    mesh.materials = materials;
    if unassigned > 0 {
        warnings.push(format!(
            "{}: {unassigned} triangle{} have no material: they get Kd = {DEFAULT_KD} grey",
            path.display(),
            if unassigned == 1 { "" } else { "s" }
        ));
    }
    if prepared.short_faces > 0 {
        warnings.push(format!(
            "{}: ignored {} face{} with fewer than 3 vertices",
            path.display(),
            prepared.short_faces,
            if prepared.short_faces == 1 { "" } else { "s" }
        ));
    }
    Ok((mesh, warnings))
}

/// Reads a whole file as UTF-8 text; errors name the file and, for bad UTF-8, the line.
fn read_text(files: &dyn super::Source, path: &Path) -> Result<String> {
    let bytes = files.read(path).map_err(|source| Error::Read {
        path: path.into(),
        cause: source,
    })?;
    // A UTF-8 byte-order mark (some Windows tools write one) is not part of the first line.
    let bytes = match bytes.strip_prefix(b"\xEF\xBB\xBF") {
        Some(rest) => rest.to_vec(),
        None => bytes,
    };
    String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = valid.iter().filter(|&&b| b == b'\n').count() + 1;
        Error::scene(
            path,
            Some(line),
            "not valid UTF-8 text (is this a binary file?)",
        )
    })
}

/// The OBJ text reduced to what tobj needs, and what the check learnt.
struct PreparedObj {
    text: String,
    /// Each `usemtl` name with its line.
    usemtl: Vec<(String, usize)>,
    /// Each `mtllib` statement's file names with its line.
    mtllib: Vec<(String, usize)>,
    /// Faces with one or two vertices (points, lines), left out.
    short_faces: usize,
}

fn prepare_obj(path: &Path, text: &str) -> Result<PreparedObj> {
    let mut out = String::with_capacity(text.len());
    let mut usemtl = Vec::new();
    let mut mtllib = Vec::new();
    let mut short_faces = 0;
    let mut vertices: i64 = 0;
    let mut largest_index: Option<(i64, usize)> = None;
    for (i, raw) in text.split('\n').enumerate() {
        let line = i + 1;
        let fail = |problem: String| Err(Error::scene(path, Some(line), problem));
        let mut words = raw.split_whitespace();
        match words.next() {
            Some("v") => {
                let coords: Vec<&str> = words.by_ref().take(3).collect();
                let parsed: Vec<f32> = coords.iter().filter_map(|w| w.parse().ok()).collect();
                if parsed.len() != 3 {
                    return fail(format!(
                        "vertex needs three numbers x y z, found '{}'",
                        coords.join(" ")
                    ));
                }
                if let Some(problem) = validate::position(Vec3::from_slice(&parsed)) {
                    return fail(format!("vertex {}: {problem}", vertices + 1));
                }
                out.push_str("v ");
                out.push_str(&coords.join(" "));
                vertices += 1;
            }
            Some("f") => {
                let mut indices = Vec::new();
                for word in words {
                    let first = word.split('/').next().unwrap_or("");
                    let Ok(index) = first.parse::<i64>() else {
                        return fail(format!(
                            "face vertex '{word}' does not start with a vertex index"
                        ));
                    };
                    let absolute = match index {
                        0 => {
                            return fail("vertex index 0 in a face: OBJ indices start at 1".into())
                        }
                        i if i < 0 => {
                            if -i > vertices {
                                return fail(format!(
                                    "relative vertex index {i} points before the first vertex \
                                     ({vertices} defined so far)"
                                ));
                            }
                            vertices + i + 1
                        }
                        i => {
                            if largest_index.is_none_or(|(largest, _)| i > largest) {
                                largest_index = Some((i, line));
                            }
                            i
                        }
                    };
                    indices.push(absolute);
                }
                if indices.len() < 3 {
                    short_faces += 1;
                } else {
                    out.push('f');
                    for index in indices {
                        out.push(' ');
                        out.push_str(&index.to_string());
                    }
                }
            }
            Some(keyword @ ("usemtl" | "mtllib")) => {
                let name = raw.trim()[keyword.len()..].trim();
                if name.is_empty() {
                    return fail(format!("{keyword} without a name"));
                }
                if keyword == "usemtl" {
                    usemtl.push((name.to_string(), line));
                } else {
                    mtllib.push((name.to_string(), line));
                }
                out.push_str(keyword);
                out.push(' ');
                out.push_str(name);
            }
            // Comments, texture coordinates, normals, groups, smoothing, lines, points and the
            // rest are not used: the line stays, empty, so line numbers do not move.
            _ => {}
        }
        out.push('\n');
    }
    if let Some((index, line)) = largest_index {
        if index > vertices {
            return Err(Error::scene(
                path,
                Some(line),
                format!(
                    "vertex index {index} is out of range: the file defines {vertices} vertices"
                ),
            ));
        }
    }
    Ok(PreparedObj {
        text: out,
        usemtl,
        mtllib,
        short_faces,
    })
}

/// An MTL file reduced to `newmtl`, `Kd` and `Ke`, with where each material's lines are.
struct MtlLibrary {
    path: PathBuf,
    text: String,
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

fn read_mtl(files: &dyn super::Source, path: &Path) -> Result<MtlLibrary> {
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
fn materials_from(
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

/// A `usemtl` naming a material no MTL file defines is one warning per name; its faces get the
/// default grey, as faces without a material do (tobj leaves their material unset).
fn check_usemtl(
    path: &Path,
    usemtl: &[(String, usize)],
    materials: &[Material],
    libraries: &[MtlLibrary],
    warnings: &mut Vec<String>,
) {
    let mut said: Vec<&str> = Vec::new();
    for (name, line) in usemtl {
        if materials.iter().any(|m| &m.name == name) || said.contains(&name.as_str()) {
            continue;
        }
        said.push(name);
        let files: Vec<String> = libraries
            .iter()
            .map(|l| l.path.display().to_string())
            .collect();
        let looked = if files.is_empty() {
            "the OBJ names no mtllib".to_string()
        } else {
            format!("not defined in {}", files.join(", "))
        };
        warnings.push(format!(
            "{}:{line}: usemtl '{name}': {looked}: its faces get Kd = {DEFAULT_KD} grey",
            path.display()
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::super::file::line_of;
    use super::*;

    #[test]
    fn prepare_keeps_line_numbers_and_strips_unused_statements() {
        let text =
            "# comment\nv 0 0 0\nvt 0 0\nv 1 0 0 1\nv 0 1 0\nvn 0 0 1\nf 1/1/1 2/2/1 -1//1\n";
        let p = prepare_obj(Path::new("t.obj"), text).unwrap();
        let lines: Vec<&str> = p.text.split('\n').collect();
        assert_eq!(lines[0], "");
        assert_eq!(lines[1], "v 0 0 0");
        assert_eq!(lines[2], "");
        assert_eq!(lines[3], "v 1 0 0");
        assert_eq!(lines[6], "f 1 2 3");
        assert_eq!(line_of(&p.text, p.text.find("f 1").unwrap()), 7);
    }

    #[test]
    fn prepare_reports_bad_indices_with_their_line() {
        let err = |text: &str| {
            prepare_obj(Path::new("t.obj"), text)
                .err()
                .unwrap()
                .to_string()
        };
        assert_eq!(
            err("v 0 0 0\nf 1 2 2000000000\n"),
            "t.obj:2: vertex index 2000000000 is out of range: the file defines 1 vertices"
        );
        assert!(err("v 0 0 0\nf 0 1 1\n").starts_with("t.obj:2: vertex index 0"));
        assert!(err("v 0 0 0\nf -2 1 1\n").starts_with("t.obj:2: relative vertex index -2"));
        assert!(err("v 0 0 0\nf a b c\n").starts_with("t.obj:2: face vertex 'a'"));
        assert!(err("\nv 0 nan 0\n").starts_with("t.obj:2: vertex 1: coordinate"));
        assert!(err("v 0 0\n").starts_with("t.obj:1: vertex needs three numbers"));
    }
}
