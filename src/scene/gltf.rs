//! glTF 2.0 input (`.gltf` with its buffers, or `.glb`), read with the `gltf` crate: every
//! triangle primitive of the default scene with its nodes' transforms, the materials, the first
//! perspective camera and `KHR_lights_punctual` point lights (`docs/scene-format.md`, "glTF").
//!
//! Units as Blender writes them: lengths in metres, emission strength as radiance
//! (W·sr⁻¹·m⁻²), lights in candela as W·683/4π. In a radiometric scene a light's candela
//! become W/sr (÷ 683) and Ke is the emission as written; in a photometric one the candela stay
//! and Ke is × 683 (cd/m²).

use std::path::Path;

use glam::{Mat4, Vec3};

use super::{Camera, Kind, Material, Mesh, PointLight, Units};
use crate::error::{Error, Result};

/// Lumens per watt of the photometric conversion glTF exporters use.
const EFFICACY: f32 = 683.0;

/// What a glTF file holds that meshlight reads.
pub(super) struct GltfScene {
    pub mesh: Mesh,
    /// The cameras, by their node's name (else their own, else "camera N"), in node order.
    pub cameras: Vec<(String, Camera)>,
    pub point_lights: Vec<PointLight>,
    pub warnings: Vec<String>,
}

/// Reads `path` (a `.gltf` or `.glb`); `units` decides how lights come across, `max_reflectance`
/// and `strict` how a white base colour is treated, as for MTL files.
pub(super) fn read(
    files: &dyn super::Source,
    path: &Path,
    units: Units,
    (max_reflectance, strict): (f32, bool),
) -> Result<GltfScene> {
    let fail = |problem: String| Error::scene(path, None, problem);
    let bytes = files.read(path).map_err(|cause| Error::Read {
        path: path.into(),
        cause,
    })?;
    let gltf = gltf::Gltf::from_slice(&bytes)
        .map_err(|e| fail(format!("not a glTF 2.0 file meshlight can read: {e}")))?;
    let base = path.parent().unwrap_or(Path::new(""));
    let buffers = gltf::import_buffers(&gltf.document, Some(base), gltf.blob.clone())
        .map_err(|e| fail(format!("its buffers cannot be read: {e}")))?;
    let document = &gltf.document;
    let mut out = GltfScene {
        mesh: Mesh::default(),
        cameras: Vec::new(),
        point_lights: Vec::new(),
        warnings: Vec::new(),
    };
    let mut warn = |w: String| out.warnings.push(format!("{}: {w}", path.display()));
    let photometric = units == Units::Photometric;

    // Materials in file order; one more for primitives without a material.
    let mut materials = Vec::new();
    for m in document.materials() {
        materials
            .push(material(&m, photometric, (max_reflectance, strict), &mut warn).map_err(fail)?);
    }
    let default_material = materials.len() as u32;
    let mut used_default = false;

    let Some(scene) = document
        .default_scene()
        .or_else(|| document.scenes().next())
    else {
        return Err(fail("it has no scene".into()));
    };
    let mut stack: Vec<(gltf::Node, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() {
            return Err(fail(format!(
                "node {} has a transform that is not finite",
                node.index()
            )));
        }
        if let Some(mesh) = node.mesh() {
            let mirrored = world.determinant() < 0.0;
            for prim in mesh.primitives() {
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    warn(format!(
                        "mesh {} has a primitive of mode {:?}: only triangles are read",
                        mesh.index(),
                        prim.mode()
                    ));
                    continue;
                }
                let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                let Some(positions) = reader.read_positions() else {
                    warn(format!(
                        "mesh {} has a primitive without positions",
                        mesh.index()
                    ));
                    continue;
                };
                let first = out.mesh.positions.len() as u32;
                out.mesh
                    .positions
                    .extend(positions.map(|p| world.transform_point3(Vec3::from(p))));
                let count = out.mesh.positions.len() as u32 - first;
                let indices: Vec<u32> = match reader.read_indices() {
                    Some(i) => i.into_u32().collect(),
                    None => (0..count).collect(),
                };
                if let Some(bad) = indices.iter().find(|&&i| i >= count) {
                    return Err(fail(format!(
                        "mesh {} indexes vertex {bad} of {count}",
                        mesh.index()
                    )));
                }
                let m = match prim.material().index() {
                    Some(i) => i as u32,
                    None => {
                        used_default = true;
                        default_material
                    }
                };
                for t in indices.chunks_exact(3) {
                    let t = [first + t[0], first + t[1], first + t[2]];
                    out.mesh
                        .triangles
                        .push(if mirrored { [t[0], t[2], t[1]] } else { t });
                    out.mesh.triangle_materials.push(m);
                }
            }
        }
        if let Some(camera) = node.camera() {
            match camera.projection() {
                gltf::camera::Projection::Perspective(p) => {
                    let position = world.transform_point3(Vec3::ZERO);
                    let forward = world.transform_vector3(-Vec3::Z).normalize_or_zero();
                    let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
                    let aspect = p.aspect_ratio().filter(|a| a.is_finite() && *a > 0.0);
                    let width = 512u32;
                    let height = aspect.map_or(512, |a| ((512.0 / a).round() as u32).max(1));
                    // The node's name is what a modelling tool shows (Blender's object name).
                    let name = node
                        .name()
                        .or(camera.name())
                        .map_or_else(|| format!("camera {}", camera.index()), str::to_string);
                    out.cameras.push((
                        name,
                        Camera {
                            position,
                            look_at: position + forward,
                            up,
                            fov_y: p.yfov().to_degrees(),
                            width,
                            height,
                        },
                    ));
                }
                gltf::camera::Projection::Orthographic(_) => warn(format!(
                    "camera {} is orthographic: only perspective cameras are read",
                    camera.index()
                )),
            }
        }
        if let Some(light) = node.light() {
            let colour = Vec3::from(light.color());
            let candela = colour * light.intensity();
            let intensity = if photometric {
                candela
            } else {
                candela / EFFICACY
            };
            match light.kind() {
                gltf::khr_lights_punctual::Kind::Point => {
                    out.point_lights.push(PointLight {
                        position: world.transform_point3(Vec3::ZERO),
                        intensity,
                    });
                }
                other => warn(format!(
                    "light {} is a {} light: only point lights are read yet",
                    light.index(),
                    match other {
                        gltf::khr_lights_punctual::Kind::Directional => "directional",
                        _ => "spot",
                    }
                )),
            }
        }
        for child in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child, world));
        }
    }
    if out.mesh.triangles.is_empty() {
        return Err(fail("its scene has no triangles".into()));
    }
    if used_default {
        warn("faces without a material get a grey diffuse one (Kd 0.8)".into());
    }
    materials.push(Material::diffuse(
        "(no material)",
        Vec3::splat(0.8),
        Vec3::ZERO,
    ));
    out.mesh.materials = materials;
    Ok(out)
}

/// One glTF material as meshlight's: base colour → Kd, metallic/roughness → the metallic
/// workflow, emissive × strength → Ke, doubleSided → two_sided, transmission → glass.
fn material(
    m: &gltf::Material,
    photometric: bool,
    (max_reflectance, strict): (f32, bool),
    warn: &mut dyn FnMut(String),
) -> std::result::Result<Material, String> {
    let name = m.name().map_or_else(
        || format!("material {}", m.index().unwrap_or(0)),
        str::to_string,
    );
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, _] = pbr.base_color_factor();
    let mut base = Vec3::new(r, g, b);
    if pbr.base_color_texture().is_some() {
        warn(format!(
            "material '{name}': its base colour texture is not read yet: the factor {} {} {} \
             is used",
            base.x, base.y, base.z
        ));
    }
    if base.to_array().contains(&1.0) {
        if strict {
            return Err(format!(
                "material '{name}': base colour {} {} {} reflects all light in a channel, which \
                 nothing real does (strict)",
                base.x, base.y, base.z
            ));
        }
        base = Vec3::from(
            base.to_array()
                .map(|c| if c >= 1.0 { max_reflectance } else { c }),
        );
        warn(format!(
            "material '{name}': a base colour channel of 1 reflects all light: lowered to \
             {max_reflectance} (max_reflectance)"
        ));
    }
    let strength = m.emissive_strength().unwrap_or(1.0);
    let scale = if photometric { EFFICACY } else { 1.0 };
    let ke = Vec3::from(m.emissive_factor()) * strength * scale;
    let mut out = Material::diffuse(name.clone(), base, ke);
    out.two_sided = m.double_sided();
    let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor());
    if transmission > 0.0 {
        if transmission < 1.0 {
            warn(format!(
                "material '{name}': transmission {transmission} is read as clear glass"
            ));
        }
        out.kd = Vec3::ZERO;
        out.ke = Vec3::ZERO;
        out.kind = Kind::Glass {
            ior: m.ior().unwrap_or(1.5),
            transmit: base,
            // Without KHR_materials_volume, glTF's transmission is thin-walled.
            thin: m.volume().is_none(),
        };
    } else {
        let metallic = pbr.metallic_factor();
        if metallic > 0.0 && ke == Vec3::ZERO {
            out.kd = base * (1.0 - metallic);
            out.kind = Kind::Specular {
                ks: base * metallic,
                roughness: pbr.roughness_factor(),
            };
        }
    }
    if let Some((_, problem)) = super::validate::material_field(&out) {
        return Err(format!("material '{name}': {problem}"));
    }
    Ok(out)
}
