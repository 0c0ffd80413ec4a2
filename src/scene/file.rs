//! The scene file (TOML): where the OBJ is, the camera, point lights and solver defaults.
//! Unknown keys are errors, so a misspelt option never passes silently.

use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::Deserialize;
use toml::Spanned;

use super::{validate, Camera, PointLight, SolverDefaults};
use crate::error::{Error, Result};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneToml {
    obj: Spanned<String>,
    #[serde(default)]
    two_sided: bool,
    camera: Spanned<CameraToml>,
    #[serde(default)]
    point_light: Vec<Spanned<PointLightToml>>,
    #[serde(default)]
    solver: Option<Spanned<SolverToml>>,
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
struct SolverToml {
    epsilon: Option<f32>,
    max_reflectance: Option<f32>,
}

/// What the scene file says, checked, with the OBJ path resolved.
pub(super) struct SceneFile {
    pub obj: PathBuf,
    pub two_sided: bool,
    pub camera: Camera,
    pub point_lights: Vec<PointLight>,
    pub solver: SolverDefaults,
    /// The `obj =` line.
    pub obj_line: usize,
    /// Comment lines of the scene file that name the OBJ file (how to make it, say).
    pub obj_notes: Vec<String>,
}

/// 1-based line of a byte offset.
pub(crate) fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
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

    let camera_span = parsed.camera.span();
    let c = parsed.camera.into_inner();
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

    let obj_span = parsed.obj.span();
    let obj = parsed.obj.into_inner();
    if obj.trim().is_empty() {
        return Err(at(
            obj_span,
            "obj is empty: it must name the OBJ file".into(),
        ));
    }
    let dir = path.parent().unwrap_or(Path::new(""));
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
        obj: dir.join(&obj),
        two_sided: parsed.two_sided,
        camera,
        point_lights,
        solver,
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
