//! The scene file (TOML): where the OBJ is, the camera, point lights and solver defaults.
//! Unknown keys are errors, so a misspelt option never passes silently.

use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::Deserialize;
use toml::Spanned;

use super::overrides::Override;
use super::{luminance, validate, Camera, Grid, Luminaire, PointLight, SolverDefaults, Units};
use crate::daylight::spa::{sun_position, LocalTime, Observer};
use crate::daylight::{Daylight, Site, Sky, SkyModel};
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
    site: Option<Spanned<SiteToml>>,
    sky: Option<Spanned<SkyToml>>,
    annual: Option<Spanned<AnnualToml>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AnnualToml {
    weather: String,
    hours: Option<[i64; 2]>,
    sky_subdivision: Option<u32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SiteToml {
    latitude: Option<f64>,
    longitude: Option<f64>,
    timezone: Option<f64>,
    north: Option<[f32; 3]>,
    up: Option<[f32; 3]>,
    ground_reflectance: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SkyToml {
    model: String,
    #[serde(rename = "type")]
    kind: Option<u8>,
    time: Option<String>,
    diffuse_horizontal: Option<f64>,
    direct_normal: Option<f64>,
    sun_altitude: Option<f64>,
    sun_azimuth: Option<f64>,
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
    target_df: Option<f64>,
    target_df_median: Option<f64>,
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
    /// `[site]` and `[sky]`: the daylight outside.
    pub daylight: Option<crate::daylight::Daylight>,
    /// `[site]` and `[annual]`: a year of weather.
    pub annual: Option<crate::daylight::AnnualSettings>,
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
            daylight: None,
            annual: None,
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
    .and_then(|grid| grid.with_df_targets(g.target_df, g.target_df_median))
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
    let dir = path.parent().unwrap_or(Path::new(""));
    let camera = parsed.camera.map(|c| camera(c, &at)).transpose()?;
    let point_lights = point_lights(parsed.point_light, &at)?;
    let mut luminaires = Vec::with_capacity(parsed.luminaire.len());
    for l in parsed.luminaire {
        let span = l.span();
        let fail = |problem: String| at(span.clone(), problem);
        luminaires.push(luminaire(files, dir, l.into_inner(), &fail)?);
    }
    let grids = grids(parsed.grid, &at)?;
    let units = units(parsed.units, &at)?;
    let solver = solver_defaults(parsed.solver, &at)?;
    let (daylight, annual) = sky_and_year(dir, parsed.site, parsed.sky, parsed.annual, &at)?;
    let overrides = overrides(parsed.material, text);
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
        obj_notes: notes_naming(text, &obj),
        daylight,
        annual,
    })
}

/// Where in the scene file a problem is: (span, problem) to an error naming its line.
type At<'a> = dyn Fn(Range<usize>, String) -> Error + 'a;

/// `[camera]`, checked as a host's camera is.
fn camera(c: Spanned<CameraToml>, at: &At) -> Result<Camera> {
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
    match camera.problem() {
        Some(problem) => Err(at(camera_span, problem)),
        None => Ok(camera),
    }
}

/// `[[point_light]]`, each checked as a host's light is.
fn point_lights(lights: Vec<Spanned<PointLightToml>>, at: &At) -> Result<Vec<PointLight>> {
    let mut point_lights = Vec::with_capacity(lights.len());
    for light in lights {
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
    Ok(point_lights)
}

/// `[[grid]]`, each name once.
fn grids(tables: Vec<Spanned<GridToml>>, at: &At) -> Result<Vec<Grid>> {
    let mut grids: Vec<Grid> = Vec::with_capacity(tables.len());
    for g in tables {
        let span = g.span();
        let fail = |problem: String| at(span.clone(), problem);
        let g = grid(g.into_inner(), &fail)?;
        if grids.iter().any(|other| other.name == g.name) {
            return Err(fail(format!("grid '{}': name used twice", g.name)));
        }
        grids.push(g);
    }
    Ok(grids)
}

/// `units`: radiometric unless it says photometric.
fn units(units: Option<Spanned<String>>, at: &At) -> Result<Units> {
    match units {
        None => Ok(Units::Radiometric),
        Some(u) => match u.get_ref().as_str() {
            "radiometric" => Ok(Units::Radiometric),
            "photometric" => Ok(Units::Photometric),
            other => Err(at(
                u.span(),
                format!("units = \"{other}\": either \"radiometric\" or \"photometric\""),
            )),
        },
    }
}

/// `[solver]`: the scene's own ε and max_reflectance, checked.
fn solver_defaults(table: Option<Spanned<SolverToml>>, at: &At) -> Result<SolverDefaults> {
    let mut solver = SolverDefaults::default();
    if let Some(s) = table {
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
    Ok(solver)
}

/// `[site]`, `[sky]` and `[annual]`: the daylight of one moment and the year's settings. A
/// site needs a sky or a year to light.
fn sky_and_year(
    dir: &Path,
    site_table: Option<Spanned<SiteToml>>,
    sky: Option<Spanned<SkyToml>>,
    year: Option<Spanned<AnnualToml>>,
    at: &At,
) -> Result<(Option<Daylight>, Option<crate::daylight::AnnualSettings>)> {
    let (site_span, site) = match site_table {
        Some(s) => {
            let span = s.span();
            (Some(span.clone()), Some(site(s.into_inner(), span, at)?))
        }
        None => (None, None),
    };
    if let (Some(span), None, None) = (&site_span, &sky, &year) {
        return Err(at(
            span.clone(),
            "[site] without a [sky] or an [annual]: give the sky (model = \"cie-overcast\", \
             say)"
                .into(),
        ));
    }
    let site_fail = |problem: String, fallback: &Range<usize>| match &site_span {
        Some(span) => at(span.clone(), format!("[site] {problem}")),
        None => at(fallback.clone(), problem),
    };
    let daylight = match sky {
        Some(sky) => Some(daylight(site.as_ref(), sky, at, &site_fail)?),
        None => None,
    };
    let annual = match year {
        Some(a) => {
            let span = a.span();
            Some(annual(dir, site, a.into_inner(), &|p| {
                at(span.clone(), format!("[annual] {p}"))
            })?)
        }
        None => None,
    };
    Ok((daylight, annual))
}

/// `[material.NAME]` tables, each key with its line in `text`.
fn overrides(
    tables: std::collections::BTreeMap<String, Spanned<MaterialToml>>,
    text: &str,
) -> Vec<Override> {
    let line = |span: Range<usize>| line_of(text, span.start);
    let rgb = |v: Spanned<[f32; 3]>| (Vec3::from(*v.get_ref()), line(v.span()));
    tables
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
        .collect()
}

/// The scene file's comments that name the geometry file (`geometry`'s file name): the notes
/// a summary repeats (where the export came from, say).
fn notes_naming(text: &str, geometry: &str) -> Vec<String> {
    let name = Path::new(geometry).file_name().map(|n| n.to_string_lossy());
    name.map(|name| {
        let comments = text.lines().filter_map(|l| l.trim().strip_prefix('#'));
        comments
            .filter(|c| c.contains(name.as_ref()))
            .map(|c| c.trim().to_string())
            .collect()
    })
    .unwrap_or_default()
}

/// `"YYYY-MM-DDTHH:MM"` (or with `:SS`) as a local standard time in `timezone`.
fn local_time(text: &str, timezone: f64) -> std::result::Result<LocalTime, String> {
    let bad = || format!("time = \"{text}\" is not YYYY-MM-DDTHH:MM (local standard time)");
    let (date, clock) = text.trim().split_once(['T', ' ']).ok_or_else(bad)?;
    let d: Vec<&str> = date.split('-').collect();
    let c: Vec<&str> = clock.split(':').collect();
    if d.len() != 3 || !(2..=3).contains(&c.len()) {
        return Err(bad());
    }
    let num = |s: &str| s.parse::<u32>().map_err(|_| bad());
    let (year, month, day) = (
        d[0].parse::<i32>().map_err(|_| bad())?,
        num(d[1])?,
        num(d[2])?,
    );
    let (hour, minute) = (num(c[0])?, num(c[1])?);
    let second = match c.get(2) {
        Some(s) => s.parse::<f64>().map_err(|_| bad())?,
        None => 0.0,
    };
    let valid = (1..=12).contains(&month)
        && day >= 1
        && day <= crate::daylight::days_in_month(year, month.clamp(1, 12))
        && hour < 24
        && minute < 60
        && (0.0..60.0).contains(&second)
        && (1..=9999).contains(&year);
    if !valid {
        return Err(format!("time = \"{text}\" is not a date and time of day"));
    }
    Ok(LocalTime {
        year,
        month,
        day,
        hour,
        minute,
        second,
        timezone,
    })
}

/// `[site]`, checked: its keys within their ranges; errors name the table's line.
fn site(
    s: SiteToml,
    span: Range<usize>,
    at: &dyn Fn(Range<usize>, String) -> Error,
) -> Result<Site> {
    for (name, value, range) in [
        ("latitude", s.latitude, -90.0..=90.0),
        ("longitude", s.longitude, -180.0..=180.0),
        ("timezone", s.timezone, -14.0..=14.0),
        ("ground_reflectance", s.ground_reflectance, 0.0..=1.0),
    ] {
        if let Some(v) = value.filter(|v| !range.contains(v)) {
            return Err(at(
                span,
                format!(
                    "[site] {name} = {v} is outside {} to {}",
                    range.start(),
                    range.end()
                ),
            ));
        }
    }
    Ok(Site {
        latitude: s.latitude,
        longitude: s.longitude,
        timezone: s.timezone,
        north: s.north.map_or(-Vec3::Z, Vec3::from),
        up: s.up.map_or(Vec3::Y, Vec3::from),
        ground_reflectance: s.ground_reflectance.unwrap_or(0.2),
    })
}

/// `[annual]`: the weather file (relative to the scene file's folder), the occupied hours and
/// the sky's subdivision; errors name the table's line.
fn annual(
    dir: &Path,
    site: Option<Site>,
    a: AnnualToml,
    fail: &dyn Fn(String) -> Error,
) -> Result<crate::daylight::AnnualSettings> {
    let hours = a.hours.unwrap_or([8, 18]);
    if !(0 <= hours[0] && hours[0] < hours[1] && hours[1] <= 24) {
        return Err(fail(format!(
            "hours = [{}, {}]: the occupied hours are [start, end) with 0 ≤ start < end ≤ 24",
            hours[0], hours[1]
        )));
    }
    let subdivision = a.sky_subdivision.unwrap_or(1);
    if ![1, 2, 4].contains(&subdivision) {
        return Err(fail(format!(
            "sky_subdivision = {subdivision}: 1 (Tregenza's 145 patches), 2 (577) or 4 (2305)"
        )));
    }
    if a.weather.trim().is_empty() {
        return Err(fail("weather names no file".into()));
    }
    Ok(crate::daylight::AnnualSettings {
        weather: dir.join(&a.weather),
        hours: (hours[0] as u32, hours[1] as u32),
        sky_subdivision: subdivision,
        site: site.unwrap_or_default(),
    })
}

/// `[sky]` over the `[site]` as the daylight outside; errors name the table's line.
fn daylight(
    site: Option<&Site>,
    sky: Spanned<SkyToml>,
    at: &dyn Fn(Range<usize>, String) -> Error,
    site_fail: &dyn Fn(String, &Range<usize>) -> Error,
) -> Result<Daylight> {
    let (sky_span, k) = (sky.span(), sky.into_inner());
    let fail = |problem: String| at(sky_span.clone(), format!("[sky] {problem}"));
    let site_fail = |problem: String| site_fail(problem, &sky_span);
    let s = site.cloned().unwrap_or_default();
    let sun_needed = !matches!(k.model.as_str(), "cie-overcast" | "uniform");
    let model = sky_model(&k.model, k.kind).map_err(&fail)?;
    let diffuse = match k.diffuse_horizontal {
        Some(e) if e.is_finite() && e >= 0.0 => e,
        Some(e) => {
            return Err(fail(format!(
                "diffuse_horizontal = {e} is not an illuminance ≥ 0"
            )))
        }
        None if !sun_needed => 10_000.0,
        None => {
            return Err(fail(format!(
                "model = \"{}\" needs diffuse_horizontal",
                k.model
            )))
        }
    };
    let direct = match k.direct_normal {
        Some(e) if e.is_finite() && e >= 0.0 => e,
        Some(e) => {
            return Err(fail(format!(
                "direct_normal = {e} is not an illuminance ≥ 0"
            )))
        }
        None => 0.0,
    };
    // The sun: from the time at the site, or given.
    let (sun, day) = sun_of(&k, &s, &fail, &site_fail)?;
    if sun.is_none() && (sun_needed || direct > 0.0) {
        return Err(fail(format!(
            "model = \"{}\"{} needs the sun's position: a time (with the site's latitude, \
             longitude and timezone) or sun_altitude and sun_azimuth",
            k.model,
            if direct > 0.0 {
                " with direct_normal"
            } else {
                ""
            }
        )));
    }
    let (zenith, azimuth) = sun.unwrap_or((0.0, 0.0));
    let model = match model {
        SkyModel::Perez { .. } => {
            let (clearness, brightness) =
                crate::daylight::sky::perez_parameters(diffuse, direct, zenith.min(90.0), day);
            SkyModel::Perez {
                clearness,
                brightness,
            }
        }
        m => m,
    };
    let sky = Sky::new(model, zenith, azimuth, diffuse).map_err(|e| fail(e.to_string()))?;
    Daylight::new(
        sky,
        s.up,
        s.north,
        s.ground_reflectance,
        diffuse,
        sun,
        direct,
    )
    .map_err(|e| site_fail(e.to_string()))
}

/// `model` (and `type`) of `[sky]`; a Perez sky's parameters come later, from the light.
fn sky_model(model: &str, kind: Option<u8>) -> std::result::Result<SkyModel, String> {
    Ok(match (model, kind) {
        ("cie-overcast", None) => SkyModel::CieOvercast,
        ("uniform", None) => SkyModel::Uniform,
        ("cie", Some(t)) if (1..=15).contains(&t) => SkyModel::Cie(t),
        ("cie", Some(t)) => return Err(format!("type = {t}: the general skies are 1 to 15")),
        ("cie", None) => return Err("model = \"cie\" needs type = 1 to 15".into()),
        ("perez", None) => SkyModel::Perez {
            clearness: 1.0,
            brightness: 0.2,
        },
        (m @ ("cie-overcast" | "uniform" | "perez"), Some(_)) => {
            return Err(format!("type is for model = \"cie\", not \"{m}\""))
        }
        (other, _) => {
            return Err(format!(
                "model = \"{other}\": one of \"cie-overcast\", \"uniform\", \"cie\", \"perez\""
            ))
        }
    })
}

/// A direction in the sky: zenith angle and azimuth, degrees.
type ZenithAzimuth = (f64, f64);

/// The sun's (zenith, azimuth) and the day of the year: from `[sky]`'s time at the site, or its
/// given altitude and azimuth, or none.
fn sun_of(
    k: &SkyToml,
    s: &Site,
    fail: &dyn Fn(String) -> Error,
    site_fail: &dyn Fn(String) -> Error,
) -> Result<(Option<ZenithAzimuth>, Option<u32>)> {
    Ok(match (k.time.as_deref(), k.sun_altitude, k.sun_azimuth) {
        (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
            return Err(fail(
                "give the time or sun_altitude and sun_azimuth, not both".into(),
            ))
        }
        (Some(text), None, None) => {
            let (Some(latitude), Some(longitude), Some(timezone)) =
                (s.latitude, s.longitude, s.timezone)
            else {
                return Err(site_fail(
                    "a sun from the time needs the site's latitude, longitude and timezone".into(),
                ));
            };
            let time = local_time(text, timezone).map_err(&fail)?;
            let observer = Observer {
                latitude,
                longitude,
                elevation: 0.0,
                pressure: 1010.0,
                temperature: 10.0,
            };
            let year = f64::from(time.year) + (f64::from(time.month) - 0.5) / 12.0;
            let sun = sun_position(&time, &observer, crate::daylight::spa::delta_t(year));
            (
                Some((sun.zenith, sun.azimuth)),
                Some(crate::daylight::day_of_year(
                    time.year, time.month, time.day,
                )),
            )
        }
        (None, Some(alt), Some(az)) => {
            if !((-90.0..=90.0).contains(&alt) && az.is_finite()) {
                return Err(fail(format!(
                    "sun_altitude = {alt} must be within −90 to 90 and sun_azimuth finite"
                )));
            }
            (Some((90.0 - alt, az.rem_euclid(360.0))), None)
        }
        (None, Some(_), None) | (None, None, Some(_)) => {
            return Err(fail("give both sun_altitude and sun_azimuth".into()))
        }
        (None, None, None) => (None, None),
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
