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
use std::path::Path;

use glam::{Vec2, Vec3};

use super::mtl::{materials_from, read_mtl, MtlLibrary, Rules, UvTransform, DEFAULT_KD};
use super::source::read_text;
use super::validate;
use super::{Material, Mesh};
use crate::error::{Error, Result};

const OPTIONS: tobj::LoadOptions = tobj::LoadOptions {
    single_index: false,
    triangulate: true,
    ignore_points: true,
    ignore_lines: true,
};

/// Reads an OBJ file and the MTL files it names; returns the mesh and warnings.
pub(super) fn read(
    files: &dyn super::Source,
    path: &Path,
    rules: &Rules,
) -> Result<(Mesh, Vec<String>)> {
    let text = read_text(files, path)?;
    let prepared = prepare_obj(path, &text)?;

    let Loaded {
        models,
        materials: tobj_materials,
        libraries,
        missing,
    } = load(files, path, &prepared)?;
    let mut warnings = missing;
    let any_missing = !warnings.is_empty();
    for library in &libraries {
        warnings.extend(library.warnings.iter().cloned());
    }
    let (mut materials, transforms) =
        materials_from(files, &tobj_materials, &libraries, rules, &mut warnings)?;
    // A material a missing MTL file may have defined gets the default grey (below).
    let before = warnings.len();
    if !any_missing {
        check_usemtl(
            path,
            &prepared.usemtl,
            &materials,
            &libraries,
            &mut warnings,
        );
    }

    let (mut mesh, unassigned) = triangles(&models, &mut materials);
    // Faces under a usemtl that names nothing, or from a missing MTL, were spoken for above.
    let said = any_missing || warnings.len() > before;
    mesh.materials = materials;
    mesh.texcoords = texcoords(path, &prepared, &mesh, &transforms, &mut warnings);
    if unassigned > 0 && !said {
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

/// What tobj reads of the prepared OBJ and the MTL files it names: the models, the materials,
/// the MTL files as read (with their lines), and a warning for each MTL file not found (its
/// materials' faces get the default grey). tobj hands over the rest of an `mtllib` line as one
/// name: several files are allowed there (separated by spaces), each read and their materials
/// merged in order.
fn load(files: &dyn super::Source, path: &Path, prepared: &PreparedObj) -> Result<Loaded> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let libraries: RefCell<Vec<MtlLibrary>> = RefCell::new(Vec::new());
    let failure: RefCell<Option<Error>> = RefCell::new(None);
    let missing: RefCell<Vec<String>> = RefCell::new(Vec::new());
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

    Ok(Loaded {
        models,
        materials: tobj_materials,
        libraries,
        missing: missing.into_inner(),
    })
}

/// What [`load`] read.
struct Loaded {
    models: Vec<tobj::Model>,
    materials: Vec<tobj::Material>,
    libraries: Vec<MtlLibrary>,
    /// A warning for each MTL file not found.
    missing: Vec<String>,
}

/// The models' triangles with their materials; faces without one get the default grey
/// material, added once. The number of such triangles.
fn triangles(models: &[tobj::Model], materials: &mut Vec<Material>) -> (Mesh, usize) {
    let mut mesh = Mesh::default();
    let mut default_material: Option<u32> = None;
    let mut unassigned = 0usize;
    for model in models {
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
    (mesh, unassigned)
}

/// Each triangle's image coordinates where its material has a texture and all its corners
/// have `vt`; empty when no triangle has any.
fn texcoords(
    path: &Path,
    prepared: &PreparedObj,
    mesh: &Mesh,
    transforms: &[Option<UvTransform>],
    warnings: &mut Vec<String>,
) -> Vec<Option<[Vec2; 3]>> {
    if prepared.vt.is_empty() || transforms.iter().all(Option::is_none) {
        return Vec::new();
    }
    if prepared.triangle_vt.len() != mesh.triangles.len() {
        // tobj triangulates faces in file order as fans; a mismatch would pair the wrong
        // coordinates with a triangle, so none are used rather than wrong ones.
        warnings.push(format!(
            "{}: texture coordinates not used: {} triangles read but {} counted",
            path.display(),
            mesh.triangles.len(),
            prepared.triangle_vt.len()
        ));
        return Vec::new();
    }
    let mut any = false;
    let out = prepared
        .triangle_vt
        .iter()
        .zip(&mesh.triangle_materials)
        .map(|(corners, &m)| {
            let transform = transforms.get(m as usize).copied().flatten()?;
            let mut uv = [Vec2::ZERO; 3];
            for (uv, &c) in uv.iter_mut().zip(corners) {
                *uv = transform.apply(*prepared.vt.get(c as usize)?);
            }
            any = true;
            Some(uv)
        })
        .collect();
    if any {
        out
    } else {
        Vec::new()
    }
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
    /// The `vt` coordinates (u, v), in file order.
    vt: Vec<Vec2>,
    /// Each triangle's `vt` indices (0-based; `NO_VT` where a corner has none), in the order
    /// tobj's fan triangulation gives the triangles: faces in file order, (0, i, i + 1).
    triangle_vt: Vec<[u32; 3]>,
}

/// A face corner without texture coordinates.
const NO_VT: u32 = u32::MAX;

fn prepare_obj(path: &Path, text: &str) -> Result<PreparedObj> {
    let mut p = Preparing {
        out: String::with_capacity(text.len()),
        ..Preparing::default()
    };
    for (i, raw) in text.split('\n').enumerate() {
        let line = i + 1;
        let mut words = raw.split_whitespace();
        let done = match words.next() {
            Some("v") => p.vertex(words),
            Some("vt") => p.texcoord(words),
            Some("f") => p.face(words, line),
            Some(keyword @ ("usemtl" | "mtllib")) => p.named(keyword, raw, line),
            // Comments, normals, groups, smoothing, lines, points and the rest are not used:
            // the line stays, empty, so line numbers do not move.
            _ => Ok(()),
        };
        done.map_err(|problem| Error::scene(path, Some(line), problem))?;
        p.out.push('\n');
    }
    p.finish()
        .map_err(|(line, problem)| Error::scene(path, Some(line), problem))
}

/// An OBJ text on its way to tobj: what is kept of it, and what the check has learnt.
#[derive(Default)]
struct Preparing {
    out: String,
    usemtl: Vec<(String, usize)>,
    mtllib: Vec<(String, usize)>,
    short_faces: usize,
    vertices: i64,
    /// The largest vertex index a face names, with its line.
    largest_index: Option<(i64, usize)>,
    vt: Vec<Vec2>,
    triangle_vt: Vec<[u32; 3]>,
    /// The largest texture index a face names, with its line.
    largest_vt: Option<(i64, usize)>,
}

impl Preparing {
    /// `v x y z`: three finite numbers.
    fn vertex<'w>(
        &mut self,
        mut words: impl Iterator<Item = &'w str>,
    ) -> std::result::Result<(), String> {
        let coords: Vec<&str> = words.by_ref().take(3).collect();
        let parsed: Vec<f32> = coords.iter().filter_map(|w| w.parse().ok()).collect();
        if parsed.len() != 3 {
            return Err(format!(
                "vertex needs three numbers x y z, found '{}'",
                coords.join(" ")
            ));
        }
        if let Some(problem) = validate::position(Vec3::from_slice(&parsed)) {
            return Err(format!("vertex {}: {problem}", self.vertices + 1));
        }
        self.out.push_str("v ");
        self.out.push_str(&coords.join(" "));
        self.vertices += 1;
        Ok(())
    }

    /// `vt u [v [w]]`: kept here (tobj is not given them).
    fn texcoord<'w>(
        &mut self,
        words: impl Iterator<Item = &'w str>,
    ) -> std::result::Result<(), String> {
        let coords: Vec<&str> = words.collect();
        let parsed: Vec<f32> = coords.iter().filter_map(|w| w.parse().ok()).collect();
        if parsed.len() != coords.len()
            || !(1..=3).contains(&parsed.len())
            || !parsed.iter().all(|c| c.is_finite())
        {
            return Err(format!(
                "texture coordinates need one to three finite numbers u [v [w]], found '{}'",
                coords.join(" ")
            ));
        }
        self.vt
            .push(Vec2::new(parsed[0], parsed.get(1).copied().unwrap_or(0.0)));
        Ok(())
    }

    /// `f v[/vt[/vn]] ...`: absolute vertex indices for tobj, each triangle's texture indices
    /// kept here; faces of fewer than three corners are counted and left out.
    fn face<'w>(
        &mut self,
        words: impl Iterator<Item = &'w str>,
        line: usize,
    ) -> std::result::Result<(), String> {
        let mut indices = Vec::new();
        let mut corners_vt = Vec::new();
        for word in words {
            let mut parts = word.split('/');
            let first = parts.next().unwrap_or("");
            let texture = parts.next().filter(|t| !t.is_empty());
            corners_vt.push(match texture {
                None => NO_VT as i64,
                Some(t) => self.texture_index(word, t, line)?,
            });
            indices.push(self.vertex_index(word, first, line)?);
        }
        if indices.len() < 3 {
            self.short_faces += 1;
            return Ok(());
        }
        let corner = |i: usize| u32::try_from(corners_vt[i]).unwrap_or(NO_VT);
        for i in 1..indices.len() - 1 {
            self.triangle_vt.push([corner(0), corner(i), corner(i + 1)]);
        }
        self.out.push('f');
        for index in indices {
            self.out.push(' ');
            self.out.push_str(&index.to_string());
        }
        Ok(())
    }

    /// A face corner's texture index `t` (of `word`), 0-based.
    fn texture_index(
        &mut self,
        word: &str,
        t: &str,
        line: usize,
    ) -> std::result::Result<i64, String> {
        let Ok(index) = t.parse::<i64>() else {
            return Err(format!(
                "face vertex '{word}': texture index '{t}' is not a number"
            ));
        };
        let count = self.vt.len() as i64;
        match index {
            0 => Err("texture index 0 in a face: OBJ indices start at 1".into()),
            i if i < 0 && -i > count => Err(format!(
                "relative texture index {i} points before the first vt ({count} defined so far)"
            )),
            i if i < 0 => Ok(count + i),
            i => {
                if self.largest_vt.is_none_or(|(largest, _)| i > largest) {
                    self.largest_vt = Some((i, line));
                }
                Ok(i - 1)
            }
        }
    }

    /// A face corner's vertex index `first` (of `word`), absolute and 1-based.
    fn vertex_index(
        &mut self,
        word: &str,
        first: &str,
        line: usize,
    ) -> std::result::Result<i64, String> {
        let Ok(index) = first.parse::<i64>() else {
            return Err(format!(
                "face vertex '{word}' does not start with a vertex index"
            ));
        };
        match index {
            0 => Err("vertex index 0 in a face: OBJ indices start at 1".into()),
            i if i < 0 => {
                if -i > self.vertices {
                    return Err(format!(
                        "relative vertex index {i} points before the first vertex ({} defined so \
                         far)",
                        self.vertices
                    ));
                }
                Ok(self.vertices + i + 1)
            }
            i => {
                if self.largest_index.is_none_or(|(largest, _)| i > largest) {
                    self.largest_index = Some((i, line));
                }
                Ok(i)
            }
        }
    }

    /// `usemtl NAME` or `mtllib FILE...`: kept with their line.
    fn named(&mut self, keyword: &str, raw: &str, line: usize) -> std::result::Result<(), String> {
        let name = raw.trim()[keyword.len()..].trim();
        if name.is_empty() {
            return Err(format!("{keyword} without a name"));
        }
        if keyword == "usemtl" {
            self.usemtl.push((name.to_string(), line));
        } else {
            self.mtllib.push((name.to_string(), line));
        }
        self.out.push_str(keyword);
        self.out.push(' ');
        self.out.push_str(name);
        Ok(())
    }

    /// The prepared text, once every index a face named is known to exist (a line and the
    /// problem where one does not).
    fn finish(self) -> std::result::Result<PreparedObj, (usize, String)> {
        if let Some((index, line)) = self.largest_index {
            if index > self.vertices {
                return Err((
                    line,
                    format!(
                        "vertex index {index} is out of range: the file defines {} vertices",
                        self.vertices
                    ),
                ));
            }
        }
        if let Some((index, line)) = self.largest_vt {
            if index > self.vt.len() as i64 {
                return Err((
                    line,
                    format!(
                        "texture index {index} is out of range: the file defines {} vt",
                        self.vt.len()
                    ),
                ));
            }
        }
        Ok(PreparedObj {
            text: self.out,
            usemtl: self.usemtl,
            mtllib: self.mtllib,
            short_faces: self.short_faces,
            vt: self.vt,
            triangle_vt: self.triangle_vt,
        })
    }
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
            "# comment\nv 0 0 0\nvt 0 0\nv 1 0 0 1\nv 0 1 0\nvn 0 0 1\nf 1/1/1 2/-1/1 -1//1\n";
        let p = prepare_obj(Path::new("t.obj"), text).unwrap();
        let lines: Vec<&str> = p.text.split('\n').collect();
        assert_eq!(lines[0], "");
        assert_eq!(lines[1], "v 0 0 0");
        assert_eq!(lines[2], "");
        assert_eq!(lines[3], "v 1 0 0");
        assert_eq!(lines[6], "f 1 2 3");
        assert_eq!(line_of(&p.text, p.text.find("f 1").unwrap()), 7);
        // The texture coordinates: one vt; corners 1 and 2 use it (-1 is the last one), the
        // third has none.
        assert_eq!(p.vt, vec![Vec2::ZERO]);
        assert_eq!(p.triangle_vt, vec![[0, 0, NO_VT]]);
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
