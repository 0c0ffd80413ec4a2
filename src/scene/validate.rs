//! Checks shared by the file loader (which adds file and line) and by `Scene::from_parts`:
//! finite numbers, reflectance in [0, 1) (Kd + Ks ≤ 1), non-negative emission and intensities,
//! glass that is only glass, sane sizes.

use std::path::Path;

use glam::Vec3;

use super::{Kind, Material, PointLight, SceneParts};
use crate::error::{Error, Result};

/// Largest coordinate magnitude accepted: squared distances must stay finite in f32.
pub(crate) const MAX_COORDINATE: f32 = 1e15;

fn rgb(v: Vec3) -> String {
    format!("{} {} {}", v.x, v.y, v.z)
}

/// Which material field a problem is in (the loader points at that field's line).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum MaterialField {
    Kd,
    Ke,
    Ks,
    Roughness,
    Ior,
    Transmit,
}

/// Why a material is invalid, if it is, and in which field.
pub(crate) fn material_field(m: &Material) -> Option<(MaterialField, String)> {
    if !m.kd.is_finite() {
        let problem = format!(
            "material '{}': Kd {} is not a finite number",
            m.name,
            rgb(m.kd)
        );
        return Some((MaterialField::Kd, problem));
    }
    // With a texture Kd scales texels that are bounded already: 1 is allowed there.
    let textured = m.texture.is_some() && m.kd.max_element() <= 1.0;
    if m.kd.min_element() < 0.0 || (m.kd.max_element() >= 1.0 && !textured) {
        let problem = format!(
            "material '{}': Kd {} is outside [0, 1): a reflectance of 1 or more creates energy",
            m.name,
            rgb(m.kd)
        );
        return Some((MaterialField::Kd, problem));
    }
    if !m.ke.is_finite() {
        let problem = format!(
            "material '{}': Ke {} is not a finite number",
            m.name,
            rgb(m.ke)
        );
        return Some((MaterialField::Ke, problem));
    }
    if m.ke.min_element() < 0.0 {
        let problem = format!("material '{}': Ke {} is negative", m.name, rgb(m.ke));
        return Some((MaterialField::Ke, problem));
    }
    let name = &m.name;
    match m.kind {
        Kind::Diffuse => None,
        Kind::Specular { ks, roughness } => {
            if !(ks.is_finite() && ks.min_element() >= 0.0 && ks.max_element() <= 1.0) {
                let problem = format!("material '{name}': Ks {} is outside [0, 1]", rgb(ks));
                return Some((MaterialField::Ks, problem));
            }
            if (m.kd + ks).max_element() > 1.0 {
                let problem = format!(
                    "material '{name}': Kd {} + Ks {} exceeds 1: it would reflect more light \
                     than arrives",
                    rgb(m.kd),
                    rgb(ks)
                );
                return Some((MaterialField::Ks, problem));
            }
            if !(0.0..=1.0).contains(&roughness) {
                let problem = format!("material '{name}': roughness {roughness} is outside [0, 1]");
                return Some((MaterialField::Roughness, problem));
            }
            None
        }
        Kind::Glass { ior, transmit, .. } => {
            if !(1.0..=10.0).contains(&ior) {
                let problem = format!(
                    "material '{name}': index of refraction {ior} is outside [1, 10] (air is 1, \
                     glass about 1.5)"
                );
                return Some((MaterialField::Ior, problem));
            }
            if !(transmit.is_finite()
                && transmit.min_element() >= 0.0
                && transmit.max_element() <= 1.0)
            {
                let problem = format!(
                    "material '{name}': transmission filter {} is outside [0, 1]",
                    rgb(transmit)
                );
                return Some((MaterialField::Transmit, problem));
            }
            if m.kd != Vec3::ZERO || m.ke != Vec3::ZERO {
                let problem = format!(
                    "material '{name}': glass neither reflects diffusely nor emits: its Kd and \
                     Ke must be 0"
                );
                return Some((MaterialField::Kd, problem));
            }
            None
        }
    }
}

/// Why a `max_reflectance` (what a reflectance of exactly 1 is lowered to) is unusable.
pub(crate) fn max_reflectance(r: f32) -> Option<String> {
    (!(r > 0.0 && r < 1.0))
        .then(|| format!("max_reflectance {r} must lie strictly between 0 and 1"))
}

/// Why a point light is invalid, if it is.
pub(crate) fn point_light(l: &PointLight) -> Option<String> {
    if let Some(problem) = position(l.position) {
        return Some(format!("point light position: {problem}"));
    }
    if !l.intensity.is_finite() {
        return Some(format!(
            "point light intensity {} is not a finite number",
            rgb(l.intensity)
        ));
    }
    if l.intensity.min_element() < 0.0 {
        return Some(format!(
            "point light intensity {} is negative",
            rgb(l.intensity)
        ));
    }
    None
}

/// Why a position is unusable, if it is.
pub(crate) fn position(p: Vec3) -> Option<String> {
    if !p.is_finite() {
        return Some(format!("coordinate {} is NaN or infinite", rgb(p)));
    }
    if p.abs().max_element() > MAX_COORDINATE {
        return Some(format!(
            "coordinate {} is too large (magnitude at most {MAX_COORDINATE:e})",
            rgb(p)
        ));
    }
    None
}

/// The smallest and largest scene (bounding-box diagonal, in its own units) results are valid
/// for. Measured on a 2 m room scaled (`tests/hostile.rs`): both backends give the same image
/// from a diagonal of 3.5e-4 to 3.5e9; below, obvhs's fixed ray epsilon loses every hit; above,
/// the light's f32 arithmetic loses energy (−37% at 3.5e10). The bounds leave a factor of about
/// three on each side: a 1 mm part in metres, a continent in millimetres.
pub const SCENE_SIZE: std::ops::RangeInclusive<f32> = 1e-3..=1e9;

/// How far from the origin, in diagonals, a scene may lie: 32-bit coordinates keep about 7
/// digits, so a room 5 units across at 5e6 resolves only 0.5, coarser than anything the solver
/// lifts or interpolates over. The room measured the same within 0.03% out to 1e5 diagonals.
pub const MAX_OFFSET_IN_DIAGONALS: f32 = 1e5;

/// Why a scene of these bounds is outside the scale results are valid for, if it is.
pub(crate) fn extent(bounds: &super::Bounds) -> Option<String> {
    let diagonal = bounds.diagonal();
    if !SCENE_SIZE.contains(&diagonal) {
        return Some(format!(
            "the scene is {} units across (its bounding box's diagonal), outside the {:e} to \
             {:e} meshlight is valid for: scale the scene into that range (a unit change: say \
             millimetres to metres)",
            crate::budget::human_number(diagonal),
            SCENE_SIZE.start(),
            SCENE_SIZE.end()
        ));
    }
    let far = bounds.min.abs().max(bounds.max.abs()).max_element();
    if far > MAX_OFFSET_IN_DIAGONALS * diagonal {
        return Some(format!(
            "the scene is {} units across but lies {} units from the origin, more than \
             {MAX_OFFSET_IN_DIAGONALS:e} times its size: 32-bit coordinates cannot resolve it \
             there; move it near the origin (georeferenced exports: subtract the site origin)",
            crate::budget::human_number(diagonal),
            crate::budget::human_number(far)
        ));
    }
    None
}

/// Why a Poisson-disk spacing is unusable, if it is.
pub(crate) fn epsilon(epsilon: f32) -> Option<String> {
    (!(epsilon.is_finite() && epsilon > 0.0))
        .then(|| format!("epsilon = {epsilon}: it must be a positive finite length"))
}

/// Checks scene parts a host program built; errors name `name`.
pub(crate) fn parts(name: &Path, parts: &SceneParts) -> Result<()> {
    let fail = |problem: String| Err(Error::scene(name, None, problem));
    let mesh = &parts.mesh;
    if let Some(problem) = mesh
        .materials
        .iter()
        .find_map(material_field)
        .map(|(_, p)| p)
    {
        return fail(problem);
    }
    for (i, p) in mesh.positions.iter().enumerate() {
        if let Some(problem) = position(*p) {
            return fail(format!("vertex {i}: {problem}"));
        }
    }
    if mesh.triangle_materials.len() != mesh.triangles.len() {
        return fail(format!(
            "{} triangles but {} triangle materials",
            mesh.triangles.len(),
            mesh.triangle_materials.len()
        ));
    }
    if !mesh.texcoords.is_empty() && mesh.texcoords.len() != mesh.triangles.len() {
        return fail(format!(
            "{} triangles but {} texture coordinate entries (give none, or one per triangle)",
            mesh.triangles.len(),
            mesh.texcoords.len()
        ));
    }
    if let Some(i) = mesh
        .texcoords
        .iter()
        .position(|t| t.is_some_and(|uv| !uv.iter().all(|c| c.is_finite())))
    {
        return fail(format!(
            "triangle {i}: its texture coordinates are not finite"
        ));
    }
    for (i, (t, &m)) in mesh
        .triangles
        .iter()
        .zip(&mesh.triangle_materials)
        .enumerate()
    {
        if let Some(&v) = t.iter().find(|&&v| v as usize >= mesh.positions.len()) {
            return fail(format!(
                "triangle {i}: vertex index {v} is out of range ({} vertices)",
                mesh.positions.len()
            ));
        }
        if m as usize >= mesh.materials.len() {
            return fail(format!(
                "triangle {i}: material index {m} is out of range ({} materials)",
                mesh.materials.len()
            ));
        }
    }
    if let Some(problem) = parts.point_lights.iter().find_map(point_light) {
        return fail(problem);
    }
    if let Some(problem) = parts.camera.problem() {
        return fail(problem);
    }
    if let Some(problem) = parts.solver.epsilon.and_then(epsilon) {
        return fail(format!("solver {problem}"));
    }
    Ok(())
}
