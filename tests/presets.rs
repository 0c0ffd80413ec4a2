//! The presets: what ε each solves at, and the preview's accuracy against the path tracer on a
//! shipped scene (the preview is documented as within 2.5% MAE/mean of the path tracer on every
//! shipped scene; `docs/performance.md`, "Presets").

mod common;

use common::{backends, shipped, shipped_at};
use meshlight::reference::{path_trace, PathOptions};
use meshlight::solver::{choose_epsilon, EpsilonSource};
use meshlight::{Control, Options, Preset, Scene};

#[test]
fn the_epsilon_scale_multiplies_the_scenes_epsilon_and_never_an_explicit_one() {
    // The room's scene file asks for ε 0.25.
    let scene = Scene::load(shipped("room")).unwrap();
    let vis = meshlight::Backend::Bvh.build(&scene).unwrap();
    let scaled = |scale: f32, epsilon: Option<f32>| {
        let options = Options {
            epsilon_scale: scale,
            epsilon,
            ..Options::default()
        };
        choose_epsilon(&scene, vis.as_ref(), &options).unwrap()
    };
    assert_eq!(scaled(1.0, None), (0.25, EpsilonSource::SceneFile));
    assert_eq!(scaled(0.5, None), (0.125, EpsilonSource::SceneFile));
    assert_eq!(scaled(0.5, Some(0.3)), (0.3, EpsilonSource::Options));
    let final_epsilon = choose_epsilon(&scene, vis.as_ref(), &Preset::Final.options())
        .unwrap()
        .0;
    assert_eq!(final_epsilon, 0.25 * 0.6, "the final preset takes 0.6 ε");
    // Out of its range, a solve names the knob.
    for bad in [0.0, -1.0, f32::NAN, 17.0] {
        let options = Options {
            epsilon_scale: bad,
            ..Options::default()
        };
        let e = meshlight::solve(&scene, vis.as_ref(), &options, &mut |_| Control::Continue)
            .err()
            .unwrap_or_else(|| panic!("scale {bad} was accepted"))
            .to_string();
        assert!(e.contains("epsilon_scale"), "{e}");
    }
}

#[test]
#[ignore = "full tier: a reference comparison at many samples (cargo test -- --include-ignored)"]
fn the_preview_is_within_two_and_a_half_percent_of_the_path_tracer() {
    let scene = shipped_at("cornell", 64);
    let vis = meshlight::Backend::Bvh.build(&scene).unwrap();
    // Noise about 0.8% per pixel (measured: 0.42% at 128² and four times the samples).
    let traced = path_trace(
        &scene,
        vis.as_ref(),
        &PathOptions {
            spp: 4096,
            ..Default::default()
        },
        &mut |_| Control::Continue,
    )
    .unwrap();
    for backend in backends() {
        let vis = backend.build(&scene).unwrap();
        let preview = |preset: Preset| {
            let solution = meshlight::solve(&scene, vis.as_ref(), &preset.options(), &mut |_| {
                Control::Continue
            })
            .unwrap();
            let (image, stats) = meshlight::render(
                &scene,
                &solution,
                vis.as_ref(),
                &preset.render_options(),
                &mut |_| Control::Continue,
            )
            .unwrap();
            let error = meshlight::metrics::compare(&image, &traced.image).unwrap();
            (solution.samples().len(), stats.shadow_rays, error)
        };
        let (samples, rays, error) = preview(Preset::Preview);
        let (default_samples, default_rays, default_error) = preview(Preset::Default);
        eprintln!(
            "{backend}: preview {samples} samples, {rays} shadow rays, MAE/mean {:.3}%; \
             default {default_samples}, {default_rays}, {:.3}%",
            100.0 * error.mae_over_mean,
            100.0 * default_error.mae_over_mean
        );
        assert!(
            error.mae_over_mean < 0.025,
            "{backend}: preview MAE/mean {:.3}%",
            100.0 * error.mae_over_mean
        );
        // What makes it faster, counted rather than timed.
        assert!(
            samples < default_samples && rays < default_rays / 2,
            "{backend}"
        );
    }
}
