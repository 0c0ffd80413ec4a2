//! The command line's side of the references: progress lines and summaries for path tracing
//! and for the patch baseline.

use meshlight::solver::Options;
use meshlight::{Scene, Visibility};

use crate::progress::with_progress;

/// Path traces with a progress line on stderr (samples done, time left).
pub fn path_trace_with_progress(
    scene: &Scene,
    vis: &dyn Visibility,
    options: &meshlight::reference::PathOptions,
) -> anyhow::Result<meshlight::reference::PathImage> {
    Ok(with_progress("path tracer", |progress| {
        meshlight::reference::path_trace(scene, vis, options, progress)
    })?)
}

/// The path tracer's summary.
pub fn path_summary(
    scene: &Scene,
    traced: &meshlight::reference::PathImage,
    path: &meshlight::reference::PathOptions,
    o: &Options,
    backend: &str,
) -> String {
    format!(
        "scene {}: {} triangles; backend {}, {} thread(s); path tracing, seed {}\n\
         path tracer {}x{}: {} samples per pixel, {} rays; mean radiance {:.5}; noise estimate {:.3}% (MAE/mean between the even and odd half-images / 2)\n",
        scene.path().display(),
        scene.triangles().len(),
        backend,
        o.threads,
        path.seed,
        traced.image.width,
        traced.image.height,
        traced.spp,
        traced.rays,
        traced.image.mean(),
        100.0 * traced.noise
    )
}

/// Solves and renders with patches, with a progress line on stderr: shots, the unshot share
/// and the time left.
pub fn patches_with_progress(
    scene: &Scene,
    vis: &dyn Visibility,
    options: &meshlight::reference::PatchOptions,
) -> anyhow::Result<meshlight::reference::PatchImage> {
    Ok(with_progress("patches", |progress| {
        meshlight::reference::patch_radiosity(scene, vis, options, progress)
    })?)
}

/// The patch baseline's summary.
pub fn patch_summary(
    scene: &Scene,
    solved: &meshlight::reference::PatchImage,
    patch: &meshlight::reference::PatchOptions,
    o: &Options,
    backend: &str,
) -> String {
    format!(
        "scene {}: {} triangles; backend {}, {} thread(s); patches of side {}\n\
         patches: {} patches, {} shots, {} visibility queries, unshot {:.2e}{}; mesh {:.3} s, shoot {:.3} s, render {:.3} s\n\
         render {}x{}: {} rays per pixel; mean radiance {:.5}\n",
        scene.path().display(),
        scene.triangles().len(),
        backend,
        o.threads,
        patch.patch_size,
        solved.patches,
        solved.shots,
        solved.queries,
        solved.unshot_fraction,
        if solved.stopped { " (stopped)" } else { "" },
        solved.seconds[0],
        solved.seconds[1],
        solved.seconds[2],
        solved.image.width,
        solved.image.height,
        patch.supersample * patch.supersample,
        solved.image.mean()
    )
}
