//! The `meshlight` command: parses arguments, calls the library, reports. Nothing else.

mod cli;

use std::process::ExitCode;

use clap::Parser;
use cli::bench::BenchOptions;
use cli::{Args, Command, Method, LOADING};
use meshlight::{Backend, Scene};

fn main() -> ExitCode {
    // Like other Unix tools, end quietly when the reader of our output goes away
    // (`meshlight compare a b | head -1`) instead of panicking on the failed write.
    #[cfg(unix)]
    // SAFETY: restoring the default action of one signal before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let args = Args::parse();
    let _ = LOADING.set(meshlight::scene::LoadOptions {
        max_reflectance: args.max_reflectance,
        strict: args.strict,
    });
    match run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("meshlight: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: Args) -> anyhow::Result<()> {
    match args.command {
        Command::Render {
            solve,
            output,
            supersample,
            direct_rays,
            method,
            spp,
            time,
            patch_size,
            false_color,
            range,
            log,
        } => {
            let started = std::time::Instant::now();
            if method != Method::Meshless && false_color.is_some() {
                anyhow::bail!("--false-color works with --method meshless only");
            }
            let (scene, options) = cli::solve_setup(&solve.scene, solve.epsilon, &solve.knobs)?;
            let vis = cli::backend_from(&solve.knobs).build(&scene)?;
            // The image and what to say about how it was made, by each method.
            let (image, summary) = match method {
                Method::Pathtrace => {
                    let path_options = meshlight::reference::PathOptions {
                        spp,
                        seconds: time,
                        seed: options.seed,
                        threads: options.threads,
                        ..Default::default()
                    };
                    let traced = cli::reference::path_trace_with_progress(
                        &scene,
                        vis.as_ref(),
                        &path_options,
                    )?;
                    let summary = cli::reference::path_summary(
                        &scene,
                        &traced,
                        &path_options,
                        &options,
                        vis.name(),
                    );
                    (traced.image, summary)
                }
                Method::Patches => {
                    let patch_options = meshlight::reference::PatchOptions {
                        patch_size: match patch_size {
                            Some(h) => h,
                            None => meshlight::solver::choose_epsilon(&scene, &options)?.0,
                        },
                        supersample: supersample.max(1),
                        tolerance: options.tolerance,
                        max_shots: options.max_shots.unwrap_or(u64::MAX),
                        seed: options.seed,
                        threads: options.threads,
                        ..Default::default()
                    };
                    let solved = cli::reference::patches_with_progress(
                        &scene,
                        vis.as_ref(),
                        &patch_options,
                    )?;
                    let summary = cli::reference::patch_summary(
                        &scene,
                        &solved,
                        &patch_options,
                        &options,
                        vis.name(),
                    );
                    (solved.image, summary)
                }
                Method::Meshless => {
                    let solution = cli::solve_with_progress(&scene, vis.as_ref(), &options)?;
                    let render_options = meshlight::RenderOptions {
                        threads: options.threads,
                        supersample,
                        direct: meshlight::Direct::from_rays(direct_rays),
                        quantity: match false_color {
                            Some(cli::FalseColor::Illuminance) => meshlight::Quantity::Irradiance,
                            _ => meshlight::Quantity::Radiance,
                        },
                    };
                    let t = std::time::Instant::now();
                    let (image, stats) =
                        meshlight::render(&scene, &solution, vis.as_ref(), &render_options)?;
                    let summary = cli::solve_summary(&scene, &solution, &options, vis.name())
                        + &cli::render_summary(&image, &stats, t.elapsed().as_secs_f64());
                    (image, summary)
                }
            };
            image.write_exr(&output)?;
            let png = output.with_extension("png");
            match false_color {
                None => image.write_png(&png, image.auto_exposure())?,
                Some(kind) => {
                    cli::false_colour_render(&image, &png, kind, range, log, scene.units)?
                }
            }
            print!("{summary}");
            println!(
                "total {:.2} s{}; wrote {} and {}",
                started.elapsed().as_secs_f64(),
                cli::memory::peak_bytes().map_or(String::new(), |b| format!(
                    ", peak memory {}",
                    meshlight::solver::human_bytes(b as f64)
                )),
                output.display(),
                png.display()
            );
        }
        Command::Compare {
            image,
            reference,
            diff,
            diff_range,
            block,
        } => {
            let a = meshlight::Image::read_exr(&image)?;
            let b = meshlight::Image::read_exr(&reference)?;
            let e = meshlight::metrics::compare_blocks(&a, &b, block)?;
            println!("MAE/mean {:.5}", e.mae_over_mean);
            println!("bias {:+.5} (mean difference / reference mean)", e.bias);
            println!("RMSE/mean {:.5}", e.rmse_over_mean);
            println!("p99 error/mean {:.5}", e.p99_over_mean);
            println!(
                "mean {:.5} {:.5} {:.5} vs reference {:.5} {:.5} {:.5}",
                e.mean[0],
                e.mean[1],
                e.mean[2],
                e.reference_mean[0],
                e.reference_mean[1],
                e.reference_mean[2]
            );
            if let Some(path) = diff {
                let range = cli::plot::write_error_picture(&a, &b, &e, diff_range, &path)?;
                println!(
                    "wrote {} (colours saturate at ±{:.3}% of the reference mean)",
                    path.display(),
                    100.0 * range
                );
            }
        }
        Command::Sweep {
            solve,
            reference,
            vary,
            method,
            supersample,
            direct_rays,
            patch_size,
            spp,
            out,
            no_pathtrace,
            block,
            max_spp,
            pathtrace_seconds,
        } => {
            let scene = load(&solve.scene)?;
            let reference = meshlight::Image::read_exr(&reference)?;
            cli::sweep::run(
                &scene,
                &reference,
                &cli::sweep::Sweep {
                    vary,
                    method,
                    epsilon: solve.epsilon,
                    knobs: solve.knobs,
                    supersample,
                    direct_rays,
                    patch_size,
                    spp,
                    out,
                    pathtrace_curve: !no_pathtrace,
                    block,
                    max_spp,
                    pathtrace_seconds,
                },
            )?;
        }
        Command::Lux {
            solve,
            output,
            grid_light_samples,
        } => {
            let (scene, options) = cli::solve_setup(&solve.scene, solve.epsilon, &solve.knobs)?;
            let vis = cli::backend_from(&solve.knobs).build(&scene)?;
            let solution = cli::solve_with_progress(&scene, vis.as_ref(), &options)?;
            print!(
                "{}",
                cli::solve_summary(&scene, &solution, &options, vis.name())
            );
            let lux = meshlight::lux::LuxOptions {
                light_samples: grid_light_samples.max(1),
                seed: options.seed,
                threads: options.threads,
            };
            cli::lux::run(&scene, &solution, vis.as_ref(), &lux, &output)?;
        }
        Command::Samples { solve, output } => {
            let (scene, options) = cli::solve_setup(&solve.scene, solve.epsilon, &solve.knobs)?;
            let vis = cli::backend_from(&solve.knobs).build(&scene)?;
            let solution = cli::solve_with_progress(&scene, vis.as_ref(), &options)?;
            let mean = solution
                .radiosity
                .iter()
                .map(|b| b.element_sum() / 3.0)
                .sum::<f64>()
                / solution.radiosity.len().max(1) as f64
                / std::f64::consts::PI;
            let exposure = if mean > 0.0 { (0.4 / mean) as f32 } else { 1.0 };
            meshlight::ply::write_samples(&solution, &output, exposure)?;
            print!(
                "{}",
                cli::solve_summary(&scene, &solution, &options, vis.name())
            );
            println!(
                "wrote {} ({} samples)",
                output.display(),
                solution.samples.len()
            );
        }
        Command::Scale {
            scene,
            epsilon,
            flat_limit,
            knobs,
        } => {
            let (scene, options) = cli::solve_setup(&scene, None, &knobs)?;
            let vis = cli::backend_from(&knobs).build(&scene)?;
            cli::scale::run(&scene, vis.as_ref(), &options, &epsilon, flat_limit)?;
        }
        Command::Info { scene } => {
            let scene = load(&scene)?;
            print!("{}", cli::info(&scene));
        }
        Command::BenchVis {
            scene,
            queries,
            rays,
            threads,
            backend,
            bvh_preset,
            batch,
            repeats,
            seed,
        } => {
            let scene = load(&scene)?;
            let options = BenchOptions {
                segments: queries,
                rays,
                threads,
                backends: if backend.is_empty() {
                    Backend::available()
                } else {
                    backend
                },
                bvh_presets: cli::bvh_presets(&bvh_preset)?,
                batch,
                repeats,
                seed,
            };
            let report = cli::bench::run(&scene, &options, &mut |step| {
                eprintln!("  {step}...");
            })?;
            print!("{}", cli::bench_report(&scene, &report));
        }
    }
    Ok(())
}

/// Loads a scene and prints its warnings to stderr.
fn load(path: &std::path::Path) -> anyhow::Result<Scene> {
    let options = LOADING.get().copied().unwrap_or_default();
    let scene = Scene::load_with(&meshlight::scene::Disk, path, &options)?;
    for warning in &scene.warnings {
        eprintln!("meshlight: warning: {warning}");
    }
    Ok(scene)
}
