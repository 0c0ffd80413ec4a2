//! The scene file (TOML): where the OBJ is, the camera, point lights and solver defaults.
//! Unknown keys are errors, so a misspelt option never passes silently.

use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::Deserialize;
use toml::Spanned;

use super::overrides::Override;
use super::{luminance, validate, Camera, Grid, Luminaire, PointLight, SolverDefaults, Units};
use crate::error::{Error, Result};
use crate::ies::Photometry;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneToml {
    obj: Option<Spanned<String>>,
    gltf: Option<Spanned<String>>,
    #[serde(default)]
    two_sided: bool,
    camera: Option<Spanned<CameraToml>>,
    #[serde(default)]
    point_light: Vec<Spanned<PointLightToml>>,
    #[serde(default)]
    luminaire: Vec<Spanned<LuminaireToml>>,
    units: Option<Spanned<String>>,
    #[serde(default)]
    grid: Vec<Spanned<GridToml>>,
    #[serde(default)]
    solver: Option<Spanned<SolverToml>>,
    #[serde(default)]
    material: std::collections::BTreeMap<String, Spanned<MaterialToml>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialToml {
    kind: Option<Spanned<String>>,
    kd: Option<Spanned<[f32; 3]>>,
    ks: Option<Spanned<[f32; 3]>>,
    roughness: Option<Spanned<f32>>,
    ior: Option<Spanned<f32>>,
    transmit: Option<Spanned<[f32; 3]>>,
    thin: Option<Spanned<bool>>,
    ke: Option<Spanned<[f32; 3]>>,
    two_sided: Option<Spanned<bool>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraToml {
    position: [f32; 3],
    look_at: [f32; 3],
    up: Option<[f32; 3]>,
    fov_y: f32,
    width: u32,
    height: u32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PointLightToml {
    position: [f32; 3],
    intensity: [f32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LuminaireToml {
    ies: String,
    position: [f32; 3],
    aim: Option<[f32; 3]>,
    c0: Option<[f32; 3]>,
    multiplier: Option<f32>,
    color: Option<[f32; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GridToml {
    name: String,
    origin: [f32; 3],
    u: [f32; 3],
    v: [f32; 3],
    normal: Option<[f32; 3]>,
    spacing: Option<f32>,
    target_em: Option<f64>,
    target_u0: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SolverToml {
    epsilon: Option<f32>,
    max_reflectance: Option<f32>,
}

/// Where a scene's geometry comes from.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Geometry {
    /// An OBJ file (with its MTL files).
    Obj(PathBuf),
    /// A glTF 2.0 file (`.gltf` or `.glb`).
    Gltf(PathBuf),
}

impl Geometry {
    /// The file named.
    pub fn path(&self) -> &Path {
        match self {
            Geometry::Obj(p) | Geometry::Gltf(p) => p,
        }
    }
}

/// What the scene file says, checked, with the geometry's path resolved.
pub(super) struct SceneFile {
    pub geometry: Geometry,
    pub two_sided: bool,
    /// The camera; an OBJ scene must give one, a glTF's may come from the file.
    pub camera: Option<Camera>,
    pub point_lights: Vec<PointLight>,
    pub luminaires: Vec<Luminaire>,
    pub units: Units,
    pub grids: Vec<Grid>,
    pub solver: SolverDefaults,
    /// `[material.NAME]` overrides, in name order.
    pub overrides: Vec<Override>,
    /// The `obj =` (or `gltf =`) line.
    pub obj_line: usize,
    /// Comment lines of the scene file that name the OBJ file (how to make it, say).
    pub obj_notes: Vec<String>,
}

impl SceneFile {
    /// A glTF read on its own, as if a scene file named it and nothing else.
    pub fn of_gltf(path: &Path) -> SceneFile {
        SceneFile {
            geometry: Geometry::Gltf(path.to_path_buf()),
            two_sided: false,
            camera: None,
            point_lights: Vec::new(),
            luminaires: Vec::new(),
            units: Units::default(),
            grids: Vec::new(),
            solver: SolverDefaults::default(),
            overrides: Vec::new(),
            obj_line: 1,
            obj_notes: Vec::new(),
        }
    }
}

/// 1-based line of a byte offset.
pub(crate) fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// A luminaire from its table: the IES file read (relative to the scene file) and the
/// orientation checked; problems name the scene file's line, or the IES file's.
fn luminaire(
    files: &dyn super::Source,
    dir: &Path,
    l: LuminaireToml,
    fail: &dyn Fn(String) -> Error,
) -> Result<Luminaire> {
    let position = Vec3::from(l.position);
    if let Some(problem) = validate::position(position) {
        return Err(fail(format!("luminaire position: {problem}")));
    }
    let aim = Vec3::from(l.aim.unwrap_or([0.0, -1.0, 0.0]));
    if !aim.is_finite() || aim.length_squared() < 1e-12 {
        return Err(fail(format!("luminaire aim {aim} is not a direction")));
    }
    let aim = aim.normalize();
    // The default C = 0 direction: +x, or +z when the aim lies along x.
    let default_c0 = if aim.x.abs() > 0.9 { Vec3::Z } else { Vec3::X };
    let c0 = Vec3::from(l.c0.map_or(default_c0.to_array(), |c| c));
    let c0 = c0 - aim * c0.dot(aim);
    if !c0.is_finite() || c0.length_squared() < 1e-8 {
        return Err(fail(format!(
            "luminaire c0 {c0} is parallel to its aim {aim}"
        )));
    }
    let multiplier = l.multiplier.unwrap_or(1.0);
    if !(multiplier.is_finite() && multiplier >= 0.0) {
        return Err(fail(format!(
            "luminaire multiplier {multiplier} must be a number ≥ 0"
        )));
    }
    let color = Vec3::from(l.color.unwrap_or([1.0, 1.0, 1.0]));
    if !color.is_finite() || color.min_element() < 0.0 || luminance(color) <= 0.0 {
        return Err(fail(format!(
            "luminaire color {color} must be non-negative with a luminance above 0"
        )));
    }
    let ies_path = dir.join(&l.ies);
    let bytes = files.read(&ies_path).map_err(|cause| Error::Read {
        path: ies_path.clone(),
        cause,
    })?;
    let text = String::from_utf8_lossy(&bytes);
    let photometry = Photometry::parse(&ies_path, &text)?;
    Ok(Luminaire {
        position,
        aim,
        c0: c0.normalize(),
        tint: color / luminance(color) * multiplier,
        photometry: std::sync::Arc::new(photometry),
    })
}

/// A grid from its table, checked; `fail` names the table's line and the key at fault.
fn grid(g: GridToml, fail: &dyn Fn(String) -> Error) -> Result<Grid> {
    let name = g.name.clone();
    Grid::new(
        g.name,
        Vec3::from(g.origin),
        Vec3::from(g.u),
        Vec3::from(g.v),
        g.normal.map(Vec3::from),
        g.spacing,
    )
    .and_then(|grid| grid.with_targets(g.target_em, g.target_u0))
    .map_err(|problem| fail(format!("grid '{name}': {problem}")))
}

/// Reads and checks a scene file.
pub(super) fn read(files: &dyn super::Source, path: &Path) -> Result<SceneFile> {
    let bytes = files.read(path).map_err(|source| Error::Read {
        path: path.into(),
        cause: source,
    })?;
    let text = std::str::from_utf8(&bytes).map_err(|e| {
        let line = line_of(
            &String::from_utf8_lossy(&bytes[..e.valid_up_to()]),
            usize::MAX,
        );
        Error::scene(
            path,
            Some(line),
            "not valid UTF-8 text (is this really a scene file?)",
        )
    })?;
    let parsed: SceneToml = toml::from_str(text).map_err(|e| {
        let line = e.span().map(|span| line_of(text, span.start));
        Error::scene(path, line, e.message().trim_end().to_string())
    })?;
    let at = |span: Range<usize>, problem: String| {
        Error::scene(path, Some(line_of(text, span.start)), problem)
    };

    let camera = match parsed.camera {
        None => None,
        Some(c) => {
            let camera_span = c.span();
            let c = c.into_inner();
            let camera = Camera {
                position: Vec3::from(c.position),
                look_at: Vec3::from(c.look_at),
                up: Vec3::from(c.up.unwrap_or([0.0, 1.0, 0.0])),
                fov_y: c.fov_y,
                width: c.width,
                height: c.height,
            };
            if let Some(problem) = camera.problem() {
                return Err(at(camera_span, problem));
            }
            Some(camera)
        }
    };

    let mut point_lights = Vec::with_capacity(parsed.point_light.len());
    for light in parsed.point_light {
        let span = light.span();
        let l = light.into_inner();
        let light = PointLight {
            position: Vec3::from(l.position),
            intensity: Vec3::from(l.intensity),
        };
        if let Some(problem) = validate::point_light(&light) {
            return Err(at(span, problem));
        }
        point_lights.push(light);
    }

    let dir = path.parent().unwrap_or(Path::new(""));
    let mut luminaires = Vec::with_capacity(parsed.luminaire.len());
    for l in parsed.luminaire {
        let span = l.span();
        let fail = |problem: String| at(span.clone(), problem);
        luminaires.push(luminaire(files, dir, l.into_inner(), &fail)?);
    }
    let mut grids: Vec<Grid> = Vec::with_capacity(parsed.grid.len());
    for g in parsed.grid {
        let span = g.span();
        let fail = |problem: String| at(span.clone(), problem);
        let g = grid(g.into_inner(), &fail)?;
        if grids.iter().any(|other| other.name == g.name) {
            return Err(fail(format!("grid '{}': name used twice", g.name)));
        }
        grids.push(g);
    }
    let units = match parsed.units {
        None => Units::Radiometric,
        Some(u) => match u.get_ref().as_str() {
            "radiometric" => Units::Radiometric,
            "photometric" => Units::Photometric,
            other => {
                return Err(at(
                    u.span(),
                    format!("units = \"{other}\": either \"radiometric\" or \"photometric\""),
                ))
            }
        },
    };

    let mut solver = SolverDefaults::default();
    if let Some(s) = parsed.solver {
        let span = s.span();
        let s = s.into_inner();
        if let Some(problem) = s.epsilon.and_then(validate::epsilon) {
            return Err(at(span, format!("[solver] {problem}")));
        }
        solver.epsilon = s.epsilon;
        if let Some(problem) = s.max_reflectance.and_then(validate::max_reflectance) {
            return Err(at(span, format!("[solver] {problem}")));
        }
        solver.max_reflectance = s.max_reflectance;
    }

    let line = |span: Range<usize>| line_of(text, span.start);
    let rgb = |v: Spanned<[f32; 3]>| (Vec3::from(*v.get_ref()), line(v.span()));
    let overrides = parsed
        .material
        .into_iter()
        .map(|(name, table)| {
            let table_line = line(table.span());
            let m = table.into_inner();
            Override {
                name,
                line: table_line,
                kind: m.kind.map(|k| (k.get_ref().clone(), line(k.span()))),
                kd: m.kd.map(rgb),
                ks: m.ks.map(rgb),
                roughness: m.roughness.map(|r| (*r.get_ref(), line(r.span()))),
                ior: m.ior.map(|r| (*r.get_ref(), line(r.span()))),
                transmit: m.transmit.map(rgb),
                thin: m.thin.map(|b| (*b.get_ref(), line(b.span()))),
                ke: m.ke.map(rgb),
                two_sided: m.two_sided.map(|b| (*b.get_ref(), line(b.span()))),
            }
        })
        .collect();

    let (key, named) = match (parsed.obj, parsed.gltf) {
        (Some(obj), None) => ("obj", obj),
        (None, Some(gltf)) => ("gltf", gltf),
        (Some(_), Some(gltf)) => {
            return Err(at(
                gltf.span(),
                "the scene names both an obj and a gltf: give one of them".into(),
            ))
        }
        (None, None) => {
            return Err(Error::scene(
                path,
                Some(1),
                "the scene names no geometry: give obj = \"FILE.obj\" or gltf = \"FILE.glb\"",
            ))
        }
    };
    let obj_span = named.span();
    let obj = named.into_inner();
    if obj.trim().is_empty() {
        return Err(at(
            obj_span,
            format!("{key} is empty: it must name the geometry file"),
        ));
    }
    if key == "obj" && camera.is_none() {
        return Err(Error::scene(
            path,
            Some(1),
            "the scene has no [camera] (an OBJ carries none)",
        ));
    }
    let name = Path::new(&obj).file_name().map(|n| n.to_string_lossy());
    let obj_notes = name
        .map(|name| {
            let comments = text.lines().filter_map(|l| l.trim().strip_prefix('#'));
            comments
                .filter(|c| c.contains(name.as_ref()))
                .map(|c| c.trim().to_string())
                .collect()
        })
        .unwrap_or_default();
    Ok(SceneFile {
        geometry: if key == "obj" {
            Geometry::Obj(dir.join(&obj))
        } else {
            Geometry::Gltf(dir.join(&obj))
        },
        two_sided: parsed.two_sided,
        camera,
        point_lights,
        luminaires,
        units,
        grids,
        solver,
        overrides,
        obj_line: line_of(text, obj_span.start),
        obj_notes,
    })
}

#[cfg(test)]
mod tests {
    use super::line_of;

    #[test]
    fn lines_count_from_one() {
        let text = "a\nb\nc";
        assert_eq!(line_of(text, 0), 1);
        assert_eq!(line_of(text, 2), 2);
        assert_eq!(line_of(text, 4), 3);
        assert_eq!(line_of(text, 999), 3);
    }
}
