//! The command line's side of the references: progress lines and summaries for path tracing
//! and for the patch baseline.

use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};
use meshlight::solver::{Control, Options};
use meshlight::{Scene, Visibility};

fn spinner() -> ProgressBar {
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} {elapsed:>4} {msg}").expect("valid template"),
    );
    bar.enable_steady_tick(Duration::from_millis(200));
    bar
}

/// Path traces with a progress line on stderr (samples done, time left).
pub fn path_trace_with_progress(
    scene: &Scene,
    vis: &dyn Visibility,
    options: &meshlight::reference::PathOptions,
) -> anyhow::Result<meshlight::reference::PathImage> {
    let bar = spinner();
    let start = std::time::Instant::now();
    let traced = meshlight::reference::path_trace(scene, vis, options, &mut |p| {
        let f = f64::from(p.done) / f64::from(p.wanted.max(1));
        let elapsed = start.elapsed().as_secs_f64();
        let mut left = elapsed * (1.0 - f) / f.max(1e-9);
        if let Some(limit) = options.seconds {
            left = left.min((limit - elapsed).max(0.0));
        }
        bar.set_message(format!(
            "path tracing: {} of {} samples per pixel, {:.0}%, about {:.0} s left",
            p.done,
            p.wanted,
            100.0 * f,
            left.ceil()
        ));
    });
    bar.finish_and_clear();
    Ok(traced?)
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
        scene.path.display(),
        scene.triangles.len(),
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
/// and, from how fast its logarithm falls towards the tolerance's, the time left.
pub fn patches_with_progress(
    scene: &Scene,
    vis: &dyn Visibility,
    options: &meshlight::reference::PatchOptions,
) -> anyhow::Result<meshlight::reference::PatchImage> {
    let bar = spinner();
    let start = std::time::Instant::now();
    let solved = meshlight::reference::patch_radiosity(scene, vis, options, &mut |p| {
        let f = (p.unshot_fraction.max(1e-300).ln() / p.tolerance.ln()).clamp(0.0, 1.0);
        let elapsed = start.elapsed().as_secs_f64();
        let left = if f > 0.02 {
            format!("about {:.0} s left", (elapsed * (1.0 - f) / f).ceil())
        } else {
            "time left not known yet".to_string()
        };
        bar.set_message(format!(
            "patches: {} patches, {} shots, unshot {:.2e} (aim {:.0e}), {left}",
            p.patches, p.shots, p.unshot_fraction, p.tolerance
        ));
        Control::Continue
    });
    bar.finish_and_clear();
    Ok(solved?)
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
        scene.path.display(),
        scene.triangles.len(),
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
