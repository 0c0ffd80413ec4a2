//! The paper's baseline: classical radiosity on a regular mesh of patches. Every surface is cut
//! into square cells of side H (clipped to the surface), light is shot progressively between
//! patch centres, and the image interpolates patch radiosities bilinearly per surface. It
//! shares scene loading, the camera and the visibility backends with the meshless solver, and
//! nothing else: its own meshing, form factors, direct light and shading.

mod mesh;
mod render;
mod solve;

use crate::error::{Error, Result};
use crate::progress::{Callback, Control, Phase, Progress, Reporter};
use crate::render::Image;
use crate::scene::Scene;
use crate::visibility::Visibility;

/// Most rays per side of a pixel when rendering patches.
pub const MAX_SUPERSAMPLE: u32 = 16;

/// Patch radiosity settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchOptions {
    /// Side of the square patches, in scene units.
    pub patch_size: f32,
    /// Stop when the unshot power is below this share of the power there was to shoot.
    pub tolerance: f64,
    /// Stop after this many shots at most.
    pub max_shots: u64,
    /// Refuse meshes of more patches than this (memory and O(N²) time grow with it).
    pub max_patches: usize,
    /// Rays per side of each pixel's jittered grid when rendering.
    pub supersample: u32,
    /// Seed of the pixel jitter.
    pub seed: u64,
    /// Worker threads (results do not depend on them).
    pub threads: usize,
    /// The memory budget, bytes: an image that would not fit is refused before it is
    /// allocated.
    pub memory_budget: usize,
}

impl Default for PatchOptions {
    fn default() -> Self {
        PatchOptions {
            patch_size: 0.25,
            tolerance: 1e-3,
            max_shots: u64::MAX,
            max_patches: 200_000,
            supersample: 2,
            seed: 1,
            threads: crate::solver::Options::default().threads,
            memory_budget: crate::budget::DEFAULT_MEMORY_BUDGET,
        }
    }
}

/// A rendered patch solution and what it cost.
#[derive(Clone, Debug)]
pub struct PatchImage {
    /// The camera view.
    pub image: Image,
    /// Patches in the mesh.
    pub patches: usize,
    /// Shots fired.
    pub shots: u64,
    /// Visibility queries in the solve (point lights and pairs of patches).
    pub queries: u64,
    /// Unshot power left / the power there was to shoot.
    pub unshot_fraction: f64,
    /// Whether the host stopped the solve early.
    pub stopped: bool,
    /// Seconds meshing, shooting and rendering.
    pub seconds: [f64; 3],
}

/// Meshes, solves and renders the scene's camera view with patches of side
/// `options.patch_size`. `progress` hears the meshing, the shooting now and then
/// ([`Phase::Shooting`]: `items` the patches, `shots`, `unshot_fraction`, `tolerance`) and the
/// rendering. A Stop ends the shooting; the estimate so far is then rendered in full (the
/// render is short beside the shooting) and [`PatchImage::stopped`] says so.
pub fn patch_radiosity(
    scene: &Scene,
    vis: &dyn Visibility,
    options: &PatchOptions,
    progress: Callback,
) -> Result<PatchImage> {
    crate::parallel::guarded("the patch solver", || {
        let checked = crate::visibility::Checked::new(vis, scene);
        let vis: &dyn crate::visibility::Visibility = &checked;
        check(scene, options)?;
        let size = options.patch_size;
        let mut reporter = Reporter::new(progress);
        reporter.report(Progress::of(Phase::Meshing));
        let t = std::time::Instant::now();
        let mesh = mesh::mesh(scene, size);
        if mesh.patches.len() > options.max_patches {
            return Err(Error::Option {
                option: "patch_size",
                problem: format!(
                    "{size} cuts the surfaces into {} patches (slivers of cells count too), more \
                     than the {} allowed: choose a larger size",
                    mesh.patches.len(),
                    options.max_patches
                ),
            });
        }
        let meshing = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let lift = crate::visibility::lift(scene);
        let mut state: Vec<solve::PatchState> = mesh
            .patches
            .iter()
            .map(|p| solve::PatchState {
                radiosity: p.emitted,
                unshot: p.emitted,
            })
            .collect();
        let direct =
            solve::point_lights(scene, &mesh.patches, &mut state, vis, lift, options.threads)?;
        let patches = mesh.patches.len();
        let shooting = solve::shoot(
            &mesh.patches,
            state,
            vis,
            lift,
            options,
            &mut |shots, unshot_fraction| {
                // The share of the way on a log scale: unshot power falls about geometrically.
                let fraction =
                    (unshot_fraction.max(1e-300).ln() / options.tolerance.ln()).clamp(0.0, 1.0);
                let stop = reporter.report(Progress {
                    items: patches,
                    shots,
                    unshot_fraction,
                    tolerance: options.tolerance,
                    fraction,
                    ..Progress::of(Phase::Shooting)
                });
                if stop {
                    Control::Stop
                } else {
                    Control::Continue
                }
            },
        )?;
        let solving = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let radiosity: Vec<_> = shooting.state.iter().map(|s| s.radiosity).collect();
        reporter.report(Progress {
            items: patches,
            ..Progress::of(Phase::Rendering)
        });
        let image = render::render(
            scene,
            &mesh,
            &radiosity,
            vis,
            options.supersample,
            options.seed,
            options.threads,
        )?;
        Ok(PatchImage {
            image,
            patches,
            shots: shooting.shots,
            queries: direct + shooting.queries,
            unshot_fraction: shooting.unshot_fraction,
            stopped: shooting.stopped,
            seconds: [meshing, solving, t.elapsed().as_secs_f64()],
        })
    })
}

/// The options and the scene's camera checked, and the patch count bounded before meshing.
fn check(scene: &Scene, options: &PatchOptions) -> Result<()> {
    // Nor does it let daylight in: a daylit scene would come out dark without a word.
    if scene.daylight().is_some() {
        return Err(Error::argument(
            "scene",
            "the patch baseline models lamps only, and the scene is lit by a [sky]: render it \
             with the meshless solver or the path tracer"
                .to_string(),
        ));
    }
    // The paper's baseline is diffuse radiosity: it would show mirrors and glass as matte.
    let specular: Vec<String> = scene
        .materials
        .iter()
        .filter(|m| m.is_specular())
        .map(|m| format!("'{}' ({})", m.name, m.kind.name()))
        .collect();
    if !specular.is_empty() {
        return Err(Error::argument(
            "scene",
            format!(
                "the patch baseline models diffuse reflection only, and {} {} specular: render \
                 it with the meshless solver or the path tracer",
                specular.join(", "),
                if specular.len() == 1 { "is" } else { "are" }
            ),
        ));
    }
    // Constant patches would show a texture as one colour per patch: refused, not smeared.
    let textured: Vec<String> = scene
        .materials
        .iter()
        .filter(|m| m.texture.is_some())
        .map(|m| format!("'{}'", m.name))
        .collect();
    if !textured.is_empty() && !scene.texcoords.is_empty() {
        return Err(Error::argument(
            "scene",
            format!(
                "the patch baseline gives each patch one reflectance, and {} {} textured: render \
                 it with the meshless solver or the path tracer",
                textured.join(", "),
                if textured.len() == 1 { "is" } else { "are" }
            ),
        ));
    }
    let size = options.patch_size;
    if !(size.is_finite() && size > 0.0) {
        return Err(Error::Option {
            option: "patch_size",
            problem: format!("must be a positive length, not {size}"),
        });
    }
    if !(options.tolerance.is_finite() && options.tolerance > 0.0 && options.tolerance < 1.0) {
        return Err(Error::Option {
            option: "tolerance",
            problem: format!("must lie in (0, 1), not {}", options.tolerance),
        });
    }
    scene.camera.check()?;
    let image = (scene.camera.width, scene.camera.height);
    crate::budget::check_image(options.memory_budget, image, crate::budget::BYTES_PER_PIXEL)?;
    if !(1..=MAX_SUPERSAMPLE).contains(&options.supersample) {
        return Err(Error::Option {
            option: "supersample",
            problem: format!(
                "{} rays per side of a pixel: it must lie in 1..={MAX_SUPERSAMPLE}",
                options.supersample
            ),
        });
    }
    // The grids span each surface's bounding box in its plane: a thin diagonal strip or a
    // ring holds far more cells than its area says. Bound them before allocating.
    let cells = mesh::grid_cells(scene, size);
    let cell_limit = 16.0 * options.max_patches as f64;
    if cells > cell_limit {
        return Err(Error::Option {
            option: "patch_size",
            problem: format!(
                "{size} lays grids of {} cells over the surfaces' bounding boxes, more than \
                 the {} allowed (16 × the patch limit): choose a larger size",
                crate::budget::human_count(cells),
                crate::budget::human_count(cell_limit)
            ),
        });
    }
    let estimate = mesh::estimate(scene, size);
    if estimate > options.max_patches as f64 {
        return Err(Error::Option {
            option: "patch_size",
            problem: format!(
                "{size} cuts the scene's {:.1} area units into about {} patches, more than the \
                 {} allowed (the solve grows as the square): choose a larger size",
                scene.total_area(),
                crate::budget::human_count(estimate),
                crate::budget::human_count(options.max_patches as f64)
            ),
        });
    }
    Ok(())
}
