//! glTF 2.0 input (`.gltf` with its buffers, or `.glb`), read with the `gltf` crate: every
//! triangle primitive of the default scene with its nodes' transforms, the materials, the first
//! perspective camera and `KHR_lights_punctual` point lights (`docs/scene-format.md`, "glTF").
//!
//! Units as Blender writes them: lengths in metres, emission strength as radiance
//! (W·sr⁻¹·m⁻²), lights in candela as W·683/4π. In a radiometric scene a light's candela
//! become W/sr (÷ 683) and Ke is the emission as written; in a photometric one the candela stay
//! and Ke is × 683 (cd/m²).

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use glam::{Mat4, Vec2, Vec3};

use super::mtl::Rules;
use super::{Camera, Kind, Luminaire, Material, Mesh, PointLight, Texture, Units};
use crate::error::{Error, Result};

/// Lumens per watt of the photometric conversion glTF exporters use.
const EFFICACY: f32 = 683.0;

/// What a glTF file holds that meshlight reads.
pub(super) struct GltfScene {
    pub mesh: Mesh,
    /// The cameras, by their node's name (else their own, else "camera N"), in node order.
    pub cameras: Vec<(String, Camera)>,
    pub point_lights: Vec<PointLight>,
    /// Spot lights, as luminaires with the cone glTF describes.
    pub luminaires: Vec<Luminaire>,
    pub warnings: Vec<String>,
}

/// Nodes a file's graph may unfold into (each instance of a node counts).
const MAX_NODE_VISITS: usize = 1_000_000;

/// Triangles a file's meshes may unfold into, instances counted.
const MAX_TRIANGLES: usize = 50_000_000;

/// Reads `path` (a `.gltf` or `.glb`); `units` decides how lights come across, `rules` how a
/// white base colour is treated, as for MTL files.
pub(super) fn read(
    files: &dyn super::Source,
    path: &Path,
    units: Units,
    rules: &Rules,
) -> Result<GltfScene> {
    let fail = |problem: String| Error::scene(path, None, problem);
    let bytes = files.read(path).map_err(|cause| Error::Read {
        path: path.into(),
        cause,
    })?;
    let gltf = gltf::Gltf::from_slice(&bytes)
        .map_err(|e| fail(format!("not a glTF 2.0 file meshlight can read: {e}")))?;
    let base = path.parent().unwrap_or(Path::new(""));
    let buffers = buffers(files, base, &gltf).map_err(fail)?;
    let mut file = File {
        files,
        path,
        base,
        document: &gltf.document,
        buffers: &buffers,
        rules,
        photometric: units == Units::Photometric,
        falloff: Falloff::of(&gltf.document),
        warnings: Vec::new(),
    };
    let (materials, texcoord_sets) = file.materials()?;
    let mut found = Found {
        out: GltfScene {
            mesh: Mesh::default(),
            cameras: Vec::new(),
            point_lights: Vec::new(),
            luminaires: Vec::new(),
            warnings: Vec::new(),
        },
        default_material: materials.len() as u32,
        used_default: false,
        texcoord_sets,
    };
    file.walk(&mut found)?;
    let mut out = found.out;
    if out.mesh.triangles.is_empty() {
        return Err(fail("its scene has no triangles".into()));
    }
    if found.used_default {
        file.warn("faces without a material get a grey diffuse one (Kd 0.8)".into());
    }
    out.mesh.materials = materials;
    out.mesh.materials.push(Material::diffuse(
        "(no material)",
        Vec3::splat(0.8),
        Vec3::ZERO,
    ));
    out.warnings = file.warnings;
    Ok(out)
}

/// A glTF file being read, and what reading it needs.
struct File<'a> {
    files: &'a dyn super::Source,
    path: &'a Path,
    /// The folder the file's own files (buffers, images) are named from.
    base: &'a Path,
    document: &'a gltf::Document,
    buffers: &'a [gltf::buffer::Data],
    rules: &'a Rules,
    photometric: bool,
    falloff: Falloff,
    warnings: Vec<String>,
}

/// What the walk of the node graph has found so far.
struct Found {
    out: GltfScene,
    /// The material of primitives without one (after the file's own).
    default_material: u32,
    used_default: bool,
    /// Per material: the texture coordinate set of its base colour texture, where it has one
    /// that could be read.
    texcoord_sets: Vec<Option<u32>>,
}

impl File<'_> {
    fn warn(&mut self, w: String) {
        self.warnings.push(format!("{}: {w}", self.path.display()));
    }

    fn fail(&self, problem: String) -> Error {
        Error::scene(self.path, None, problem)
    }

    /// The materials in file order, and each one's base colour texture coordinate set.
    fn materials(&mut self) -> Result<(Vec<Material>, Vec<Option<u32>>)> {
        let mut materials = Vec::new();
        let mut texcoord_sets: Vec<Option<u32>> = Vec::new();
        let mut images: HashMap<usize, Option<Arc<Texture>>> = HashMap::new();
        for m in self.document.materials() {
            let info = m.pbr_metallic_roughness().base_color_texture();
            let texture = match &info {
                Some(info) => self.base_colour_texture(&m, &info.texture().source(), &mut images),
                None => None,
            };
            let mut warnings = Vec::new();
            let mut material = material(
                &m,
                self.photometric,
                self.rules,
                texture.is_some(),
                &mut |w| warnings.push(w),
            )
            .map_err(|problem| self.fail(problem))?;
            warnings.into_iter().for_each(|w| self.warn(w));
            if let (Some(info), Some(texture)) = (&info, texture) {
                let sampler = info.texture().sampler();
                if sampler.wrap_s() != gltf::texture::WrappingMode::Repeat
                    || sampler.wrap_t() != gltf::texture::WrappingMode::Repeat
                {
                    self.warn(format!(
                        "material '{}': its texture's clamped or mirrored wrapping is read as \
                         repeat",
                        material.name
                    ));
                }
                material.texture = Some(texture);
                texcoord_sets.push(Some(info.tex_coord()));
            } else {
                texcoord_sets.push(None);
            }
            if let Some((_, problem)) = super::validate::material_field(&material) {
                return Err(self.fail(problem));
            }
            materials.push(material);
        }
        Ok((materials, texcoord_sets))
    }

    /// Material `m`'s base colour texture `image`, read once per image (`images`); none, with
    /// a warning, where it cannot be read.
    fn base_colour_texture(
        &mut self,
        m: &gltf::Material,
        image: &gltf::Image,
        images: &mut HashMap<usize, Option<Arc<Texture>>>,
    ) -> Option<Arc<Texture>> {
        if let Some(known) = images.get(&image.index()) {
            return known.clone();
        }
        let read = texture(
            self.files,
            (self.document, self.base),
            self.buffers,
            image,
            self.rules.max_reflectance,
        );
        let texture = match read {
            Ok(texture) => Some(Arc::new(texture)),
            Err(problem) => {
                self.warn(format!(
                    "material {}: its base colour texture (image {}) cannot be read \
                     ({problem}): the base colour factor is used",
                    m.name()
                        .map_or_else(|| m.index().unwrap_or(0).to_string(), |n| format!("'{n}'")),
                    image.index()
                ));
                None
            }
        };
        images.insert(image.index(), texture.clone());
        texture
    }

    /// Walks the default scene's node graph (else the first scene's), depth first with the
    /// path from the root: a node among its own ancestors is a cycle (the walk would never
    /// end). A node reached again by another way is an instance, as many times as the file
    /// says, up to MAX_NODE_VISITS.
    fn walk(&mut self, found: &mut Found) -> Result<()> {
        let document = self.document;
        let Some(scene) = document
            .default_scene()
            .or_else(|| document.scenes().next())
        else {
            return Err(self.fail("it has no scene".into()));
        };
        let mut stack: Vec<(gltf::Node, Mat4, usize)> =
            scene.nodes().map(|n| (n, Mat4::IDENTITY, 0)).collect();
        stack.reverse();
        let mut path_from_root: Vec<usize> = Vec::new();
        let mut visits = 0usize;
        while let Some((node, parent, depth)) = stack.pop() {
            path_from_root.truncate(depth);
            if path_from_root.contains(&node.index()) {
                return Err(self.fail(format!(
                    "node {} is its own ancestor (through nodes {:?}): the node graph has a cycle",
                    node.index(),
                    path_from_root
                )));
            }
            path_from_root.push(node.index());
            visits += 1;
            if visits > MAX_NODE_VISITS || found.out.mesh.triangles.len() > MAX_TRIANGLES {
                return Err(self.fail(format!(
                    "its nodes, instanced as the file asks, make more than {} nodes or {} \
                     triangles: refused",
                    crate::budget::human_count(MAX_NODE_VISITS as f64),
                    crate::budget::human_count(MAX_TRIANGLES as f64)
                )));
            }
            let local = Mat4::from_cols_array_2d(&node.transform().matrix());
            let world = parent * local;
            if !world.is_finite() {
                return Err(self.fail(format!(
                    "node {} has a transform that is not finite",
                    node.index()
                )));
            }
            if let Some(mesh) = node.mesh() {
                for prim in mesh.primitives() {
                    self.primitive(&mesh, &prim, world, found)?;
                }
            }
            if let Some(camera) = node.camera() {
                self.camera(&node, &camera, world, &mut found.out)?;
            }
            if let Some(light) = node.light() {
                self.light(&light, world, &mut found.out)?;
            }
            for child in node.children().collect::<Vec<_>>().into_iter().rev() {
                stack.push((child, world, depth + 1));
            }
        }
        Ok(())
    }

    /// The triangles of one primitive of `mesh`, placed by `world`, with their materials and
    /// texture coordinates; other modes than triangles are left out with a warning.
    fn primitive(
        &mut self,
        mesh: &gltf::Mesh,
        prim: &gltf::Primitive,
        world: Mat4,
        found: &mut Found,
    ) -> Result<()> {
        if prim.mode() != gltf::mesh::Mode::Triangles {
            self.warn(format!(
                "mesh {} has a primitive of mode {:?}: only triangles are read",
                mesh.index(),
                prim.mode()
            ));
            return Ok(());
        }
        self.check_accessors(mesh, prim)?;
        let buffers = self.buffers;
        let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
        let Some(positions) = reader.read_positions() else {
            self.warn(format!(
                "mesh {} has a primitive without positions",
                mesh.index()
            ));
            return Ok(());
        };
        let out = &mut found.out;
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
            return Err(self.fail(format!(
                "mesh {} indexes vertex {bad} of {count}",
                mesh.index()
            )));
        }
        let m = match prim.material().index() {
            Some(i) => i as u32,
            None => {
                found.used_default = true;
                found.default_material
            }
        };
        let mirrored = world.determinant() < 0.0;
        let set = found.texcoord_sets.get(m as usize).copied().flatten();
        let uv: Option<Vec<Vec2>> = set
            .and_then(|set| reader.read_tex_coords(set))
            .map(|tc| tc.into_f32().map(Vec2::from).collect())
            .filter(|uv: &Vec<Vec2>| {
                uv.len() == count as usize && uv.iter().all(|c| c.is_finite())
            });
        if set.is_some() && uv.is_none() {
            self.warn(format!(
                "mesh {} has a textured primitive without usable texture coordinates: it shows \
                 the base colour factor",
                mesh.index()
            ));
        }
        let out = &mut found.out;
        if let Some(uv) = &uv {
            out.mesh.texcoords.resize(out.mesh.triangles.len(), None);
            for t in indices.chunks_exact(3) {
                let corner = |i: usize| uv[t[i] as usize];
                let c = if mirrored {
                    [corner(0), corner(2), corner(1)]
                } else {
                    [corner(0), corner(1), corner(2)]
                };
                out.mesh.texcoords.push(Some(c));
            }
        } else if !out.mesh.texcoords.is_empty() {
            let n = out.mesh.triangles.len() + indices.len() / 3;
            out.mesh.texcoords.resize(n, None);
        }
        for t in indices.chunks_exact(3) {
            let t = [first + t[0], first + t[1], first + t[2]];
            out.mesh
                .triangles
                .push(if mirrored { [t[0], t[2], t[1]] } else { t });
            out.mesh.triangle_materials.push(m);
        }
        Ok(())
    }

    /// Checks every accessor a primitive's triangles are read through: the gltf crate's readers
    /// trust them (a count of 0 or a stride below the element size underflows in them).
    fn check_accessors(&self, mesh: &gltf::Mesh, prim: &gltf::Primitive) -> Result<()> {
        use gltf::accessor::{DataType as T, Dimensions as D};
        let read = prim
            .attributes()
            .filter_map(|(semantic, a)| match semantic {
                gltf::Semantic::Positions => Some((a, &[T::F32][..], D::Vec3)),
                gltf::Semantic::TexCoords(_) => Some((a, &[T::F32, T::U8, T::U16][..], D::Vec2)),
                _ => None,
            });
        let indices = prim
            .indices()
            .map(|a| (a, &[T::U8, T::U16, T::U32][..], D::Scalar));
        for (accessor, types, dimensions) in read.chain(indices) {
            let typed =
                types.contains(&accessor.data_type()) && accessor.dimensions() == dimensions;
            let fits = if typed {
                accessor_fits(&accessor, self.buffers)
            } else {
                Err(format!(
                    "{:?} {:?} elements where glTF allows {types:?} {dimensions:?}",
                    accessor.data_type(),
                    accessor.dimensions()
                ))
            };
            fits.map_err(|problem| {
                self.fail(format!(
                    "mesh {}: accessor {}: {problem}",
                    mesh.index(),
                    accessor.index()
                ))
            })?;
        }
        Ok(())
    }

    /// A node's perspective camera, named by the node (what a modelling tool shows: Blender's
    /// object name), else by itself; orthographic ones are left out with a warning.
    fn camera(
        &mut self,
        node: &gltf::Node,
        camera: &gltf::Camera,
        world: Mat4,
        out: &mut GltfScene,
    ) -> Result<()> {
        let p = match camera.projection() {
            gltf::camera::Projection::Perspective(p) => p,
            gltf::camera::Projection::Orthographic(_) => {
                self.warn(format!(
                    "camera {} is orthographic: only perspective cameras are read",
                    camera.index()
                ));
                return Ok(());
            }
        };
        let position = world.transform_point3(Vec3::ZERO);
        let forward = world.transform_vector3(-Vec3::Z).normalize_or_zero();
        let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
        let aspect = p.aspect_ratio().filter(|a| a.is_finite() && *a > 0.0);
        let width = 512u32;
        let height = aspect.map_or(512, |a| ((512.0 / a).round() as u32).max(1));
        let name = node
            .name()
            .or(camera.name())
            .map_or_else(|| format!("camera {}", camera.index()), str::to_string);
        let camera = Camera {
            position,
            look_at: position + forward,
            up,
            fov_y: p.yfov().to_degrees(),
            width,
            height,
        };
        // The checks a host's camera gets (`Scene::set_camera`).
        if let Some(problem) = camera.problem() {
            return Err(self.fail(format!("camera '{name}': {problem}")));
        }
        out.cameras.push((name, camera));
        Ok(())
    }

    /// A `KHR_lights_punctual` light: a point light, or a spot as a luminaire with its cone;
    /// directional lights are left out with a warning.
    fn light(
        &mut self,
        light: &gltf::khr_lights_punctual::Light,
        world: Mat4,
        out: &mut GltfScene,
    ) -> Result<()> {
        let colour = Vec3::from(light.color());
        let candela = colour * light.intensity();
        let intensity = if self.photometric {
            candela
        } else {
            candela / EFFICACY
        };
        // The checks a host's point light gets: finite, not negative.
        let point = PointLight {
            position: world.transform_point3(Vec3::ZERO),
            intensity,
        };
        if let Some(problem) = super::validate::point_light(&point) {
            return Err(self.fail(format!(
                "light {} (intensity {}, colour {:?}): {problem}",
                light.index(),
                light.intensity(),
                light.color()
            )));
        }
        match light.kind() {
            gltf::khr_lights_punctual::Kind::Point => out.point_lights.push(point),
            gltf::khr_lights_punctual::Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => {
                let aim = world.transform_vector3(-Vec3::Z).normalize_or_zero();
                if aim == Vec3::ZERO {
                    self.warn(format!(
                        "light {} is a spot whose node points nowhere: left out",
                        light.index()
                    ));
                } else {
                    out.luminaires.push(Luminaire {
                        position: world.transform_point3(Vec3::ZERO),
                        aim,
                        c0: aim.any_orthonormal_vector(),
                        tint: intensity,
                        photometry: Arc::new(spot_cone(
                            inner_cone_angle,
                            outer_cone_angle,
                            self.falloff,
                        )),
                    });
                }
            }
            gltf::khr_lights_punctual::Kind::Directional => self.warn(format!(
                "light {} is a directional light: only point and spot lights are read",
                light.index()
            )),
        }
        Ok(())
    }
}

/// One glTF material as meshlight's: base colour → Kd, metallic/roughness → the metallic
/// workflow, emissive × strength → Ke, doubleSided → two_sided, transmission → glass.
fn material(
    m: &gltf::Material,
    photometric: bool,
    rules: &Rules,
    textured: bool,
    warn: &mut dyn FnMut(String),
) -> std::result::Result<Material, String> {
    let (max_reflectance, strict) = (rules.max_reflectance, rules.strict);
    let name = m.name().map_or_else(
        || format!("material {}", m.index().unwrap_or(0)),
        str::to_string,
    );
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, _] = pbr.base_color_factor();
    let mut base = Vec3::new(r, g, b);
    // With a texture the factor only scales texels that are bounded already.
    if base.to_array().contains(&1.0) && !textured {
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
    Ok(out)
}

/// Why an accessor cannot be read safely, if it cannot: none or sparse elements, a stride
/// shorter than an element, or elements beyond its buffer view or the view beyond its buffer.
fn accessor_fits(
    accessor: &gltf::Accessor,
    buffers: &[gltf::buffer::Data],
) -> std::result::Result<(), String> {
    if accessor.count() == 0 {
        return Err("it has no elements".into());
    }
    if accessor.sparse().is_some() {
        return Err("sparse accessors are not read".into());
    }
    let Some(view) = accessor.view() else {
        return Ok(()); // all zeros: the readers give nothing
    };
    let size = accessor.size();
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(format!("a stride of {stride} bytes for elements of {size}"));
    }
    let end = stride
        .checked_mul(accessor.count() - 1)
        .and_then(|n| n.checked_add(size))
        .and_then(|n| n.checked_add(accessor.offset()));
    if end.is_none_or(|end| end > view.length()) {
        return Err("its elements run past its buffer view".into());
    }
    let buffer = buffers.get(view.buffer().index()).map_or(0, |b| b.0.len());
    if view
        .offset()
        .checked_add(view.length())
        .is_none_or(|end| end > buffer)
    {
        return Err("its buffer view runs past its buffer".into());
    }
    Ok(())
}

/// The glTF's buffers: the `.glb`'s binary chunk, `data:` URIs, or files beside it read
/// through `files` (so a host's in-memory source serves them too), each checked against the
/// length the glTF declares.
fn buffers(
    files: &dyn super::Source,
    base: &Path,
    gltf: &gltf::Gltf,
) -> std::result::Result<Vec<gltf::buffer::Data>, String> {
    let mut out = Vec::new();
    for buffer in gltf.document.buffers() {
        let mut bytes = match buffer.source() {
            gltf::buffer::Source::Bin => gltf.blob.clone().ok_or_else(|| {
                format!(
                    "buffer {} is the binary chunk, which is missing",
                    buffer.index()
                )
            })?,
            gltf::buffer::Source::Uri(uri) => match uri.strip_prefix("data:") {
                Some(data) => data
                    .split_once(";base64,")
                    .and_then(|(_, payload)| base64_decode(payload))
                    .ok_or_else(|| {
                        format!("buffer {}: a data URI that is not base64", buffer.index())
                    })?,
                None => {
                    let path = base.join(uri.replace("%20", " "));
                    files.read(&path).map_err(|e| {
                        format!("buffer {}: {}: {e}", buffer.index(), path.display())
                    })?
                }
            },
        };
        if bytes.len() < buffer.length() {
            return Err(format!(
                "buffer {} holds {} bytes, not the {} it declares",
                buffer.index(),
                bytes.len(),
                buffer.length()
            ));
        }
        // The binary chunk may be padded to 4 bytes.
        bytes.truncate(buffer.length());
        out.push(gltf::buffer::Data(bytes));
    }
    Ok(out)
}

/// How a spot light fades between its cones: glTF leaves it to the reader.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Falloff {
    /// What glTF's specification recommends: t² with t linear in cos γ from the outer angle
    /// (0) to the inner (1).
    Gltf,
    /// What Blender's Cycles draws (`kernel/light/spot.h`): smoothstep(t), t linear in cos γ
    /// from the outer angle over (1 − cos outer) × blend, with blend = 1 − inner / outer (how
    /// Blender's exporter wrote the inner angle from the spot's blend).
    Cycles,
}

impl Falloff {
    /// Decision: a spot fades as the tool that wrote the file showed it, where we know that
    /// tool: Blender's files as Cycles draws them (with the specification's falloff a Blender
    /// spot's room came out 26% darker than in Cycles), others as glTF recommends.
    fn of(document: &gltf::Document) -> Falloff {
        match document.as_json().asset.generator.as_deref() {
            Some(g) if g.starts_with("Khronos glTF Blender") => Falloff::Cycles,
            _ => Falloff::Gltf,
        }
    }
}

/// A spot's cone as a distribution of peak 1 (the light's intensity is the tint): full inside,
/// none beyond the outer angle, and between them `falloff`.
fn spot_cone(inner: f32, outer: f32, falloff: Falloff) -> crate::ies::Photometry {
    let outer = f64::from(outer).clamp(0.0, std::f64::consts::FRAC_PI_2);
    let inner = f64::from(inner).clamp(0.0, outer);
    let spread = match falloff {
        Falloff::Gltf => (inner.cos() - outer.cos()).max(1e-3),
        Falloff::Cycles => {
            let blend = if outer > 0.0 {
                1.0 - inner / outer
            } else {
                0.0
            };
            ((1.0 - outer.cos()) * blend).max(1e-6)
        }
    };
    let falloff = |gamma: f64| {
        let t = ((gamma.cos() - outer.cos()) / spread).clamp(0.0, 1.0);
        match falloff {
            Falloff::Gltf => t * t,
            Falloff::Cycles => t * t * (3.0 - 2.0 * t),
        }
    };
    // Every 0.1° up to the outer angle, then dark to 180°.
    let steps = (outer.to_degrees() * 10.0).ceil().max(1.0) as usize;
    let mut vertical: Vec<f64> = (0..=steps)
        .map(|i| outer.to_degrees() * i as f64 / steps as f64)
        .collect();
    let mut candela: Vec<f64> = vertical.iter().map(|g| falloff(g.to_radians())).collect();
    if let Some(last) = candela.last_mut() {
        *last = 0.0;
    }
    vertical.push(180.0);
    candela.push(0.0);
    let source = format!(
        "glTF spot, cones {:.1}° and {:.1}°",
        inner.to_degrees(),
        outer.to_degrees()
    );
    crate::ies::Photometry::symmetric(source, vertical, candela)
}

/// A glTF image as a texture: from a buffer view, a `data:` URI, or a file beside the glTF.
fn texture(
    files: &dyn super::Source,
    (document, base): (&gltf::Document, &Path),
    buffers: &[gltf::buffer::Data],
    image: &gltf::Image,
    max_reflectance: f32,
) -> std::result::Result<Texture, String> {
    let name = image
        .name()
        .map_or_else(|| format!("image {}", image.index()), str::to_string);
    // `Image::source` unwraps what the JSON may lack: checked here first.
    let json = document.as_json().images.get(image.index());
    let complete = json.is_some_and(|j| match j.buffer_view {
        Some(_) => j.mime_type.is_some(),
        None => j.uri.is_some(),
    });
    if !complete {
        return Err("it names neither a buffer view with a MIME type nor a URI".into());
    }
    let bytes = match image.source() {
        gltf::image::Source::View { view, .. } => {
            let buffer = buffers
                .get(view.buffer().index())
                .ok_or("its buffer is missing")?;
            let range = view.offset()..view.offset().saturating_add(view.length());
            buffer
                .0
                .get(range)
                .ok_or("its buffer view lies outside its buffer")?
                .to_vec()
        }
        gltf::image::Source::Uri { uri, .. } => match uri.strip_prefix("data:") {
            Some(data) => {
                let (_, payload) = data
                    .split_once(";base64,")
                    .ok_or("a data URI that is not base64")?;
                base64_decode(payload).ok_or("a data URI with bad base64")?
            }
            None => {
                let path = base.join(uri.replace("%20", " "));
                files
                    .read(&path)
                    .map_err(|e| format!("{}: {e}", path.display()))?
            }
        },
    };
    Texture::decode(name, &bytes, max_reflectance)
}

/// Standard base64 (RFC 4648, padding optional; whitespace skipped); `None` on a bad symbol.
fn base64_decode(text: &str) -> Option<Vec<u8>> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => Some(c - b'A'),
        b'a'..=b'z' => Some(c - b'a' + 26),
        b'0'..=b'9' => Some(c - b'0' + 52),
        b'+' | b'-' => Some(62),
        b'/' | b'_' => Some(63),
        _ => None,
    };
    let mut out = Vec::with_capacity(text.len() * 3 / 4);
    let (mut bits, mut count) = (0u32, 0);
    for c in text.bytes().filter(|c| !c.is_ascii_whitespace()) {
        if c == b'=' {
            break;
        }
        bits = (bits << 6) | u32::from(value(c)?);
        count += 6;
        if count >= 8 {
            count -= 8;
            out.push((bits >> count) as u8);
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    #[test]
    fn base64_decodes_rfc_4648_examples() {
        // RFC 4648, section 10.
        assert_eq!(super::base64_decode("Zm9vYmFy").unwrap(), b"foobar");
        assert_eq!(super::base64_decode("Zm9vYg==").unwrap(), b"foob");
        assert_eq!(super::base64_decode("Zg").unwrap(), b"f");
        assert!(super::base64_decode("Zm9v!").is_none());
    }
}
