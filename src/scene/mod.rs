//! The scene: triangles grouped into planar surfaces, materials, area and point lights,
//! and a camera, loaded from a scene file (TOML + OBJ/MTL, `docs/scene-format.md`) or built
//! from parts by a host program.

pub(crate) mod adjacency;
mod camera;
mod file;
#[cfg(test)]
pub(crate) mod fixtures;
mod gltf;
mod grid;
mod luminaire;
mod material;
mod mtl;
mod obj;
mod overrides;
mod source;
mod surfaces;
mod texture;
mod two_sided;
mod validate;

use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::{DVec3, Vec2, Vec3};

use crate::error::{Error, Result};
pub use camera::Camera;
pub use grid::{Grid, MAX_GRID_POINTS};
pub use luminaire::{luminance, Luminaire, PointSource};
pub use material::{roughness_from_ns, Kind, Material};
pub use source::{Disk, Memory, Source};
pub use texture::{srgb_to_linear, Texture, MAX_TEXTURE_SIDE};
pub use validate::{MAX_OFFSET_IN_DIAGONALS, SCENE_SIZE};

/// A triangle of the scene, after degenerate ones were dropped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// Corners, counter-clockwise seen from the front.
    pub vertices: [Vec3; 3],
    /// Unit geometric normal, pointing to the front.
    pub normal: Vec3,
    /// Area.
    pub area: f32,
    /// The planar surface it belongs to.
    pub surface: u32,
}

/// A planar surface: connected triangles, coplanar within a tolerance, of one material and
/// facing one way. Later stages keep samples, areas and interpolation within one surface side.
#[derive(Clone, Debug, PartialEq)]
pub struct Surface {
    /// Index into [`Scene::materials`].
    pub material: u32,
    /// Unit normal of the plane (area-weighted over its triangles), pointing to the front.
    pub normal: Vec3,
    /// Plane offset: points x of the surface satisfy `normal · x ≈ offset`.
    pub offset: f32,
    /// Its triangles: a range of [`Scene::triangles`].
    pub triangles: Range<u32>,
    /// Total area.
    pub area: f64,
    /// Whether its back side reflects light too (`two_sided` scenes, non-emitting surfaces).
    pub two_sided: bool,
}

/// An isotropic point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// Position.
    pub position: Vec3,
    /// Radiant intensity, W/sr, RGB.
    pub intensity: Vec3,
}

impl PointLight {
    /// Emitted power, 4π·I.
    pub fn power(&self) -> DVec3 {
        4.0 * std::f64::consts::PI * self.intensity.as_dvec3()
    }
}

/// What a scene's numbers mean (`docs/scene-format.md`, "Units"). The solver does not care: it
/// carries radiance as luminance alike; only the labels of results change.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Units {
    /// W/sr, W·sr⁻¹·m⁻², W/m².
    #[default]
    Radiometric,
    /// Candela, cd/m², lux.
    Photometric,
}

impl Units {
    /// The unit of irradiance (illuminance).
    pub fn irradiance(self) -> &'static str {
        match self {
            Units::Radiometric => "W/m²",
            Units::Photometric => "lx",
        }
    }

    /// The unit of radiance (luminance).
    pub fn radiance(self) -> &'static str {
        match self {
            Units::Radiometric => "W·sr⁻¹·m⁻²",
            Units::Photometric => "cd/m²",
        }
    }

    /// The unit of a point's intensity.
    pub fn intensity(self) -> &'static str {
        match self {
            Units::Radiometric => "W/sr",
            Units::Photometric => "cd",
        }
    }

    /// The unit of flux (power).
    pub fn flux(self) -> &'static str {
        match self {
            Units::Radiometric => "W",
            Units::Photometric => "lm",
        }
    }
}

/// Solver defaults a scene file may carry in `[solver]`; command-line options override them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolverDefaults {
    /// Poisson-disk spacing of the initial samples, scene units.
    pub epsilon: Option<f32>,
    /// What a reflectance channel of exactly 1 in the MTL file is lowered to.
    pub max_reflectance: Option<f32>,
}

/// What a reflectance channel of exactly 1 is lowered to unless the scene file or the caller
/// says otherwise. Exporters write `Kd 1 1 1` for "white", but nothing real reflects all
/// light: fresh matte white paint reflects about 0.8–0.9. 0.9 keeps such a white as white as
/// real materials get, while the light it inter-reflects still fades within tens of bounces
/// (1/(1 − 0.9) = 10 on average) instead of never.
pub const DEFAULT_MAX_REFLECTANCE: f32 = 0.9;

/// How a scene file is read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadOptions {
    /// What a reflectance channel of exactly 1 is lowered to; overrides the scene file's
    /// `[solver] max_reflectance` (default [`DEFAULT_MAX_REFLECTANCE`]).
    pub max_reflectance: Option<f32>,
    /// A reflectance of exactly 1 is an error instead of being lowered.
    pub strict: bool,
    /// The glTF camera to use, by name (else the scene file's `[camera]`, else the glTF's
    /// first).
    pub camera: Option<String>,
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Bounds {
    /// The box around some points (an empty set gives an inverted box).
    pub fn around(points: impl IntoIterator<Item = Vec3>) -> Self {
        points.into_iter().fold(
            Bounds {
                min: Vec3::splat(f32::INFINITY),
                max: Vec3::splat(f32::NEG_INFINITY),
            },
            |b, p| Bounds {
                min: b.min.min(p),
                max: b.max.max(p),
            },
        )
    }

    /// Length of the diagonal: the scene's size scale.
    pub fn diagonal(&self) -> f32 {
        (self.max - self.min).length()
    }
}

/// The texture coordinates of a point of triangle `t` whose corners have `uv`: barycentric
/// weights from the point's projection on the triangle's plane.
pub(crate) fn texture_point(t: &Triangle, uv: &[Vec2; 3], point: Vec3) -> Vec2 {
    let [a, b, c] = t.vertices;
    let (e1, e2, d) = (b - a, c - a, point - a);
    let n = e1.cross(e2);
    let inv = 1.0 / n.length_squared();
    let wb = d.cross(e2).dot(n) * inv;
    let wc = e1.cross(d).dot(n) * inv;
    uv[0] + (uv[1] - uv[0]) * wb + (uv[2] - uv[0]) * wc
}

/// Triangle geometry with a material per triangle: what an OBJ file holds, or what a host
/// program hands over.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Triangles as indices into `positions`, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
    /// Material of each triangle: an index into `materials`.
    pub triangle_materials: Vec<u32>,
    /// The materials.
    pub materials: Vec<Material>,
    /// Texture coordinates of each triangle's corners (image coordinates: (0, 0) the image's
    /// top-left, v downwards), for triangles whose material has a texture: empty, or one entry
    /// per triangle (`None` where a triangle has none).
    pub texcoords: Vec<Option<[Vec2; 3]>>,
}

/// Everything a scene is made of, before validation and surface grouping.
#[derive(Clone, Debug)]
pub struct SceneParts {
    /// The geometry and materials.
    pub mesh: Mesh,
    /// Point lights.
    pub point_lights: Vec<PointLight>,
    /// The camera.
    pub camera: Camera,
    /// Whether non-emitting faces reflect on both sides.
    pub two_sided: bool,
    /// Solver defaults.
    pub solver: SolverDefaults,
}

/// A loaded, validated scene. Read through its accessors; the few things a host may change
/// after loading (camera, materials, grids) go through setters that check them.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Where it came from: the scene file, or the name a host program gave.
    pub(crate) path: PathBuf,
    /// Materials, indexed by [`Surface::material`].
    pub(crate) materials: Vec<Material>,
    /// Triangles, ordered so that each surface's triangles are contiguous.
    pub(crate) triangles: Vec<Triangle>,
    /// Texture coordinates of each triangle (see [`Mesh::texcoords`]): empty when no
    /// triangle has any.
    pub(crate) texcoords: Vec<Option<[Vec2; 3]>>,
    /// Planar surfaces.
    pub(crate) surfaces: Vec<Surface>,
    /// Point lights.
    pub(crate) point_lights: Vec<PointLight>,
    /// Luminaires (IES distributions) from the scene file.
    pub(crate) luminaires: Vec<Luminaire>,
    /// The scene's units: what its numbers mean, and what results are reported in.
    pub(crate) units: Units,
    /// Calculation surfaces where `meshlight lux` measures illuminance.
    pub(crate) grids: Vec<Grid>,
    /// The camera.
    pub(crate) camera: Camera,
    /// Whether non-emitting faces reflect on both sides.
    pub(crate) two_sided: bool,
    /// Solver defaults from the scene file.
    pub(crate) solver: SolverDefaults,
    /// Bounds of all triangles.
    pub(crate) bounds: Bounds,
    /// Things worth telling the user that did not stop loading (each said once).
    pub(crate) warnings: Vec<String>,
    /// The sky and ground outside (scene-format v4), if daylight enters the scene.
    pub(crate) daylight: Option<crate::daylight::Daylight>,
    /// A year of weather (`[annual]`), if the scene file asks for one.
    pub(crate) annual: Option<crate::daylight::AnnualSettings>,
}

impl Scene {
    /// Where it came from: the scene file, or the name a host program gave.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The daylight outside (`[site]` and `[sky]`), if any.
    pub fn daylight(&self) -> Option<&crate::daylight::Daylight> {
        self.daylight.as_ref()
    }

    /// The year of weather `meshlight annual` computes (`[annual]`), if any.
    pub fn annual(&self) -> Option<&crate::daylight::AnnualSettings> {
        self.annual.as_ref()
    }

    /// Sets (or, with `None`, removes) the year of weather: a host's own.
    pub fn set_annual(&mut self, annual: Option<crate::daylight::AnnualSettings>) {
        self.annual = annual;
    }

    /// Lets daylight in (or, with `None`, keeps it out): a host's own sky.
    pub fn set_daylight(&mut self, daylight: Option<crate::daylight::Daylight>) {
        self.daylight = daylight;
    }

    /// Materials, indexed by [`Surface::material`].
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// Triangles, ordered so that each surface's triangles are contiguous.
    pub fn triangles(&self) -> &[Triangle] {
        &self.triangles
    }

    /// Planar surfaces.
    pub fn surfaces(&self) -> &[Surface] {
        &self.surfaces
    }

    /// Where the point lights and luminaires stand, point lights first.
    pub(crate) fn lamp_positions(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.point_lights
            .iter()
            .map(|l| l.position)
            .chain(self.luminaires.iter().map(|l| l.position))
    }

    /// Point lights.
    pub fn point_lights(&self) -> &[PointLight] {
        &self.point_lights
    }

    /// Luminaires (IES distributions) from the scene file.
    pub fn luminaires(&self) -> &[Luminaire] {
        &self.luminaires
    }

    /// The scene's units: what its numbers mean, and what results are reported in.
    pub fn units(&self) -> Units {
        self.units
    }

    /// Calculation surfaces where illuminance is measured.
    pub fn grids(&self) -> &[Grid] {
        &self.grids
    }

    /// The camera.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Whether non-emitting faces reflect on both sides.
    pub fn two_sided(&self) -> bool {
        self.two_sided
    }

    /// Solver defaults from the scene file.
    pub fn solver_defaults(&self) -> &SolverDefaults {
        &self.solver
    }

    /// Bounds of all triangles.
    pub fn bounds(&self) -> Bounds {
        self.bounds
    }

    /// Things worth telling the user that did not stop loading (each said once).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Looks through another camera (the same checks as a scene file's `[camera]`).
    pub fn set_camera(&mut self, camera: Camera) -> Result<()> {
        if let Some(problem) = camera.problem() {
            return Err(Error::argument("camera", problem));
        }
        self.camera = camera;
        Ok(())
    }

    /// Replaces material `index` (the same checks as an MTL file's). Whether it emits decides
    /// whether its surfaces reflect on both sides in a two-sided scene, so that follows.
    pub fn set_material(&mut self, index: usize, material: Material) -> Result<()> {
        if index >= self.materials.len() {
            return Err(Error::argument(
                "material",
                format!(
                    "index {index} is out of range ({} materials)",
                    self.materials.len()
                ),
            ));
        }
        if let Some((_, problem)) = validate::material_field(&material) {
            return Err(Error::argument("material", problem));
        }
        for surface in self.surfaces.iter_mut() {
            if surface.material as usize == index {
                surface.two_sided =
                    (self.two_sided || material.two_sided) && !material.is_emitter();
            }
        }
        self.materials[index] = material;
        Ok(())
    }

    /// Adds a calculation grid; its name must be new to the scene.
    pub fn add_grid(&mut self, grid: Grid) -> Result<()> {
        if self.grids.iter().any(|g| g.name == grid.name) {
            return Err(Error::argument(
                "grid",
                format!("the name '{}' is taken", grid.name),
            ));
        }
        self.grids.push(grid);
        Ok(())
    }

    /// Loads a scene file (TOML) and the OBJ/MTL it points at.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene> {
        Scene::load_from(&Disk, path)
    }

    /// Loads a scene whose files come from `files` (paths as the scene file names them,
    /// relative to its folder).
    pub fn load_from(files: &dyn Source, path: impl AsRef<Path>) -> Result<Scene> {
        Scene::load_with(files, path, &LoadOptions::default())
    }

    /// Loads a scene as [`Scene::load_from`], with `options` for what the files may leave
    /// open (a reflectance of exactly 1).
    pub fn load_with(
        files: &dyn Source,
        path: impl AsRef<Path>,
        options: &LoadOptions,
    ) -> Result<Scene> {
        let path = path.as_ref();
        let file = if is_gltf(path) {
            // A glTF on its own: geometry, camera, lights and materials all from the file.
            file::SceneFile::of_gltf(path)
        } else {
            file::read(files, path)?
        };
        let max_reflectance = match options.max_reflectance {
            Some(r) => match validate::max_reflectance(r) {
                Some(problem) => {
                    return Err(Error::Option {
                        option: "max_reflectance",
                        problem,
                    })
                }
                None => r,
            },
            None => (file.solver.max_reflectance).unwrap_or(DEFAULT_MAX_REFLECTANCE),
        };
        let rules = mtl::Rules {
            max_reflectance,
            strict: options.strict,
        };
        let geometry_path = file.geometry.path().to_path_buf();
        let mut point_lights = file.point_lights;
        let mut luminaires = file.luminaires;
        let mut camera = file.camera;
        let (mesh, mut warnings) = match &file.geometry {
            file::Geometry::Obj(obj) => {
                if let Some(name) = &options.camera {
                    return Err(Error::Option {
                        option: "camera",
                        problem: format!(
                            "'{name}': only glTF files carry named cameras; {} is an OBJ scene",
                            path.display()
                        ),
                    });
                }
                Scene::read_obj(files, obj, &rules, &file.obj_notes, (path, file.obj_line))?
            }
            file::Geometry::Gltf(gltf_path) => {
                // The gltf crate is trusted with hostile files only behind a catch: a panic in
                // it is an error naming the file, not an abort of the host.
                let read =
                    crate::parallel::caught(|| gltf::read(files, gltf_path, file.units, &rules))
                        .unwrap_or_else(|panic| {
                            Err(Error::scene(
                                gltf_path,
                                None,
                                format!("the glTF reader failed on it ({panic})"),
                            ))
                        })?;
                point_lights.extend(read.point_lights);
                luminaires.extend(read.luminaires);
                match &options.camera {
                    Some(name) => {
                        let Some((_, c)) = read.cameras.iter().find(|(n, _)| n == name) else {
                            let names: Vec<&str> =
                                read.cameras.iter().map(|(n, _)| n.as_str()).collect();
                            return Err(Error::Option {
                                option: "camera",
                                problem: format!(
                                    "{} has no camera '{name}' (its cameras: {})",
                                    gltf_path.display(),
                                    if names.is_empty() {
                                        "none".to_string()
                                    } else {
                                        names.join(", ")
                                    }
                                ),
                            });
                        };
                        camera = Some(*c);
                    }
                    None if camera.is_none() => {
                        camera = read.cameras.into_iter().next().map(|(_, c)| c);
                    }
                    None => {}
                }
                (read.mesh, read.warnings)
            }
        };
        let Some(camera) = camera else {
            return Err(Error::scene(
                &geometry_path,
                None,
                "it has no perspective camera, and no scene file gives a [camera]",
            ));
        };
        let mut mesh = mesh;
        overrides::apply(
            path,
            &file.overrides,
            &mut mesh.materials,
            &rules,
            &mut warnings,
        )?;
        let parts = SceneParts {
            mesh,
            point_lights,
            camera,
            two_sided: file.two_sided,
            solver: file.solver,
        };
        let mut scene = Scene::build(path, parts, &geometry_path)?;
        scene.luminaires = luminaires;
        scene.units = file.units;
        scene.grids = file.grids;
        scene.daylight = file.daylight;
        scene.annual = file.annual;
        warnings.append(&mut scene.warnings);
        scene.warnings = warnings;
        Ok(scene)
    }

    /// The OBJ of a scene file, a missing one explained by the scene file's comments on it.
    fn read_obj(
        files: &dyn Source,
        obj_path: &Path,
        rules: &mtl::Rules,
        notes: &[String],
        (path, line): (&Path, usize),
    ) -> Result<(Mesh, Vec<String>)> {
        obj::read(files, obj_path, rules).map_err(|e| match e {
            // A generated OBJ not made yet: say what the scene file says about it.
            Error::Read { path: obj, cause }
                if cause.kind() == std::io::ErrorKind::NotFound && !notes.is_empty() =>
            {
                Error::scene(
                    path,
                    Some(line),
                    format!(
                        "{} not found; the scene file says: {}",
                        obj.display(),
                        notes.join(" ")
                    ),
                )
            }
            e => e,
        })
    }

    /// Builds a scene from parts a host program made; errors name `name`.
    pub fn from_parts(name: impl Into<PathBuf>, parts: SceneParts) -> Result<Scene> {
        let name = name.into();
        validate::parts(&name, &parts)?;
        Scene::build(&name, parts.clone(), &name)
    }

    /// Drops degenerate triangles, groups surfaces; `geometry_path` is named in geometry errors.
    fn build(path: &Path, parts: SceneParts, geometry_path: &Path) -> Result<Scene> {
        let SceneParts {
            mesh,
            point_lights,
            camera,
            two_sided,
            solver,
        } = parts;
        let mut warnings = Vec::new();
        let mut mesh = mesh;
        if two_sided::any(&mesh) {
            let used = mesh.triangles.iter().flatten();
            let diagonal =
                Bounds::around(used.filter_map(|&i| mesh.positions.get(i as usize).copied()))
                    .diagonal();
            if diagonal.is_finite() && diagonal > 0.0 {
                two_sided::split(&mut mesh, diagonal);
            }
        }
        let (kept, dropped) = surfaces::drop_degenerate(&mesh);
        if dropped > 0 {
            warnings.push(format!(
                "{}: dropped {dropped} zero-area triangle{}",
                geometry_path.display(),
                if dropped == 1 { "" } else { "s" }
            ));
        }
        if kept.is_empty() {
            return Err(Error::scene(
                geometry_path,
                None,
                "the scene has no geometry (no triangle with a non-zero area)",
            ));
        }
        let bounds = Bounds::around(kept.iter().flat_map(|t| t.vertices));
        if let Some(problem) = validate::extent(&bounds) {
            return Err(Error::scene(geometry_path, None, problem));
        }
        let (triangles, surfaces, texcoords) =
            surfaces::group(&kept, &mesh.materials, two_sided, bounds.diagonal());
        Ok(Scene {
            path: path.to_path_buf(),
            materials: mesh.materials,
            triangles,
            texcoords,
            surfaces,
            point_lights,
            luminaires: Vec::new(),
            units: Units::default(),
            grids: Vec::new(),
            camera,
            two_sided,
            solver,
            bounds,
            warnings,
            daylight: None,
            annual: None,
        })
    }

    /// The same scene in other units: every length × `s`, point-light intensities × s² (so
    /// irradiance at scaled distances is unchanged) and ε × s. Radiances (Ke) stay, so a
    /// solve gives the same image. `s` must be a positive number that keeps every length and
    /// area representable.
    pub fn scaled(&self, s: f32) -> Result<Scene> {
        if !(s.is_finite() && s > 0.0) {
            return Err(Error::argument(
                "scale",
                format!("{s} is not a positive number"),
            ));
        }
        let largest = self
            .bounds
            .min
            .abs()
            .max(self.bounds.max.abs())
            .max_element()
            * s;
        let smallest = self
            .triangles
            .iter()
            .map(|t| t.area)
            .fold(f32::INFINITY, f32::min);
        let smallest = f64::from(smallest) * f64::from(s) * f64::from(s);
        if !(largest <= validate::MAX_COORDINATE && smallest >= f64::from(f32::MIN_POSITIVE)) {
            return Err(Error::argument(
                "scale",
                format!("× {s} takes the scene beyond what 32-bit floats hold"),
            ));
        }
        let mut scene = self.clone();
        for t in &mut scene.triangles {
            t.vertices = t.vertices.map(|v| v * s);
            t.area *= s * s;
        }
        for surface in &mut scene.surfaces {
            surface.offset *= s;
            surface.area *= f64::from(s) * f64::from(s);
        }
        for light in &mut scene.point_lights {
            light.position *= s;
            light.intensity *= s * s;
        }
        for l in &mut scene.luminaires {
            l.position *= s;
            l.tint *= s * s;
        }
        for g in &mut scene.grids {
            g.origin *= s;
            g.u *= s;
            g.v *= s;
            g.spacing *= s;
        }
        scene.camera.position *= s;
        scene.camera.look_at *= s;
        scene.bounds = Bounds {
            min: self.bounds.min * s,
            max: self.bounds.max * s,
        };
        if let Some(problem) = validate::extent(&scene.bounds) {
            let factor = crate::budget::human_number(s);
            return Err(Error::argument("scale", format!("× {factor}: {problem}")));
        }
        scene.solver.epsilon = self.solver.epsilon.map(|e| e * s);
        Ok(scene)
    }

    /// The same scene with every light × `f`: emitted radiance Ke and point-light intensities.
    /// `f` must be a number ≥ 0 that keeps them finite.
    pub fn with_lights_scaled(&self, f: f32) -> Result<Scene> {
        let mut scene = self.clone();
        for m in &mut scene.materials {
            m.ke *= f;
        }
        for light in &mut scene.point_lights {
            light.intensity *= f;
        }
        for l in &mut scene.luminaires {
            l.tint *= f;
        }
        let lights = scene.materials.iter().map(|m| m.ke);
        let lights = lights.chain(scene.point_lights.iter().map(|l| l.intensity));
        let lights = lights.chain(scene.luminaires.iter().map(|l| l.tint));
        if f.is_nan() || f < 0.0 || !lights.into_iter().all(|v| v.is_finite()) {
            return Err(Error::argument(
                "light scale",
                format!("× {f} does not give finite, non-negative lights"),
            ));
        }
        Ok(scene)
    }

    /// The material of a surface (`surface` below `surfaces().len()`).
    pub(crate) fn material_of(&self, surface: u32) -> &Material {
        &self.materials[self.surfaces[surface as usize].material as usize]
    }

    /// Texture coordinates of each triangle (see [`Mesh::texcoords`]): empty when no
    /// triangle has any.
    pub fn texcoords(&self) -> &[Option<[Vec2; 3]>] {
        &self.texcoords
    }

    /// Whether a surface's material has a texture (its reflectance varies over it).
    pub(crate) fn is_textured(&self, surface: u32) -> bool {
        self.material_of(surface).texture.is_some()
    }

    /// The diffuse reflectance at a point of a triangle: Kd × the texel there where the
    /// triangle's material has a texture and the triangle has coordinates, else Kd.
    pub(crate) fn reflectance_at(&self, triangle: u32, point: Vec3) -> Vec3 {
        let t = &self.triangles[triangle as usize];
        let material = self.material_of(t.surface);
        match (&material.texture, self.texcoords.get(triangle as usize)) {
            (Some(texture), Some(Some(uv))) => {
                material.kd * texture.at(texture_point(t, uv, point))
            }
            (Some(texture), _) => material.kd.min(Vec3::splat(texture.bound())),
            _ => material.kd,
        }
    }

    /// Total area of all triangles.
    pub fn total_area(&self) -> f64 {
        self.surfaces.iter().map(|s| s.area).sum()
    }

    /// Emitting surfaces with the power each emits, π·Ke·area (W, RGB).
    pub fn emitters(&self) -> impl Iterator<Item = (u32, DVec3)> + '_ {
        self.surfaces.iter().enumerate().filter_map(|(i, s)| {
            let m = &self.materials[s.material as usize];
            m.is_emitter()
                .then(|| (i as u32, std::f64::consts::PI * m.ke.as_dvec3() * s.area))
        })
    }

    /// How many area lights the emitting surfaces make: each surface one, but pieces of eight
    /// or more joined along edges (a tessellated sphere or tube) one each.
    pub fn area_light_count(&self) -> usize {
        self.emitter_groups().len()
    }

    /// The triangles of some surfaces, surface by surface.
    pub(crate) fn triangles_of(&self, surfaces: &[u32]) -> Vec<&Triangle> {
        surfaces
            .iter()
            .flat_map(|&s| {
                let range = &self.surfaces[s as usize].triangles;
                &self.triangles[range.start as usize..range.end as usize]
            })
            .collect()
    }

    /// The area lights as lights are sampled: lists of emitting surfaces, each a light (see
    /// `adjacency::emitter_groups`).
    pub(crate) fn emitter_groups(&self) -> Vec<Vec<u32>> {
        adjacency::emitter_groups(self)
    }

    /// Power emitted by all area lights and point lights (W, RGB).
    pub fn emitted_power(&self) -> DVec3 {
        let area: DVec3 = self.emitters().map(|(_, p)| p).sum();
        let points: DVec3 = self.point_lights.iter().map(PointLight::power).sum();
        let luminaires: DVec3 = self.luminaires.iter().map(Luminaire::flux).sum();
        area + points + luminaires
    }

    /// Every light at a point: the point lights, then the luminaires.
    pub fn point_sources(&self) -> Vec<PointSource> {
        let points = self.point_lights.iter().map(|l| PointSource {
            position: l.position,
            intensity: l.intensity,
            luminaire: None,
        });
        let luminaires = self.luminaires.iter().map(|l| PointSource {
            position: l.position,
            intensity: l.tint,
            luminaire: Some(l.clone()),
        });
        points.chain(luminaires).collect()
    }
}
/// Whether a path names a glTF file (`.gltf` or `.glb`, any case).
pub(crate) fn is_gltf(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}
