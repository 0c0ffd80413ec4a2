//! The `meshlight` command: parses arguments, calls the library, reports. Nothing else.

mod annual;
mod args;
mod bench;
mod bench_render;
mod errors;
mod lux;
mod memory;
mod page;
mod plan;
mod plot;
mod progress;
mod ranks;
mod reference;
mod report;
mod scale;
mod sweep;
mod units;
mod workload;

use std::path::Path;
use std::process::ExitCode;

use args::*;
use bench::BenchOptions;
use clap::Parser;
use meshlight::scene::LoadOptions;
use meshlight::{Backend, Image, Scene};
use progress::solve_with_progress;
use report::*;

fn main() -> ExitCode {
    // Like other Unix tools, end quietly when the reader of our output goes away
    // (`meshlight compare a b | head -1`) instead of panicking on the failed write.
    #[cfg(unix)]
    // SAFETY: restoring the default action of one signal before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    // glibc gives each new thread an arena of its own up to 8 per core, and the solver's
    // parallel loops start threads often: freed memory then lies scattered over many arenas
    // and the resident peak grows by a fifth (the 2 x 2-room gallery: 2,430-2,690 bytes a
    // sample in three runs; one arena per core 2,197-2,248; performance.md "Memory per sample").
    // (A MALLOC_ARENA_MAX in the environment is the user's choice and stands.)
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    if std::env::var_os("MALLOC_ARENA_MAX").is_none() {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        // SAFETY: sets an allocator parameter before any thread starts.
        unsafe {
            libc::mallopt(libc::M_ARENA_MAX, cores.clamp(1, 1024) as libc::c_int);
        }
    }
    let args = Args::parse();
    progress::set_quiet(args.quiet);
    // MPI is finalised when the job drops, after everything else.
    let _job = ranks::start();
    let loading = LoadOptions {
        max_reflectance: args.max_reflectance,
        strict: args.strict,
        camera: args.camera,
    };
    let result = match &args.command {
        Command::Render(_) | Command::Lux { .. } | Command::Samples { .. } => Ok(()),
        _ if ranks::ranks().size() > 1 => Err(anyhow::anyhow!(
            "only render, lux and samples run on several ranks (`mpirun -np N meshlight render …`)"
        )),
        _ => Ok(()),
    };
    match result.and_then(|()| run(args.command, &loading)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            ranks::report_error(&format!("meshlight: error: {}", errors::explain(&e)));
            ranks::fail()
        }
    }
}

fn run(command: Command, loading: &LoadOptions) -> anyhow::Result<()> {
    match command {
        Command::Render(render) => render_command(render, loading),
        Command::Compare {
            image,
            reference,
            diff,
            diff_range,
            block,
        } => compare(&image, &reference, diff.as_deref(), diff_range, block),
        Command::Sweep(sweep) => {
            let scene = load(&sweep.solve.scene, loading)?;
            let reference = Image::read_exr(&sweep.reference)?;
            sweep::run(&scene, &reference, &sweep::Sweep::from(sweep))
        }
        Command::Lux {
            solve,
            output,
            grid_light_samples,
            grid_specular_rays,
        } => {
            let (scene, options) = solve_setup(&solve, loading)?;
            let vis = backend_from(&solve.knobs).build(&scene)?;
            diagnose(&scene, vis.as_ref())?;
            let solution = solve_with_progress(&scene, vis.as_ref(), &options)?;
            if !ranks::root() {
                return Ok(());
            }
            print!("{}", solve_summary(&scene, &solution, &options, vis.name()));
            let lux = meshlight::lux::LuxOptions {
                light_samples: grid_light_samples.max(1),
                specular_rays: grid_specular_rays,
                seed: options.seed,
                threads: options.threads,
            };
            lux::run(&scene, &solution, vis.as_ref(), &lux, &output)
        }
        Command::Annual {
            solve,
            output,
            hourly,
            grid_light_samples,
        } => {
            let (scene, options) = solve_setup(&solve, loading)?;
            let vis = backend_from(&solve.knobs).build(&scene)?;
            let annual = meshlight::annual::AnnualOptions {
                lux: meshlight::lux::LuxOptions {
                    light_samples: grid_light_samples.max(1),
                    seed: options.seed,
                    threads: options.threads,
                    ..meshlight::lux::LuxOptions::default()
                },
                solver: options,
                hourly,
            };
            annual::run(&scene, vis.as_ref(), &annual, &output)
        }
        Command::Report {
            solve,
            output,
            grid_light_samples,
            grid_specular_rays,
        } => report_command(
            &solve,
            &output,
            (grid_light_samples, grid_specular_rays),
            loading,
        ),
        Command::Samples { solve, output } => samples(&solve, &output, loading),
        Command::Scale {
            scene,
            epsilon,
            flat_limit,
            knobs,
        } => {
            let scene = load(&scene, loading)?;
            let options = options_from(None, &knobs)?;
            let vis = backend_from(&knobs).build(&scene)?;
            scale::run(&scene, vis.as_ref(), &options, &epsilon, flat_limit)
        }
        Command::Info { scene } => {
            let scene = load(&scene, loading)?;
            print!("{}", info(&scene));
            let vis = meshlight::Backend::default_backend().build(&scene)?;
            let sides = meshlight::solver::lit_sides(&scene, vis.as_ref())?;
            match meshlight::solver::light_length(&scene, vis.as_ref(), &sides)? {
                Some(l) => {
                    println!(
                        "free path     {:.6} (mean, from the sides light reaches)",
                        l.free_path
                    );
                    if let Some(h) = l.lamp_clearance {
                        println!("lamps         the nearest surface {h:.6} from a lamp");
                    }
                    // The ε each preset would solve at, as the solve chooses it.
                    let epsilon = |preset: meshlight::Preset| {
                        meshlight::solver::choose_epsilon_for(
                            &scene,
                            vis.as_ref(),
                            &sides,
                            &preset.options(),
                        )
                        .map(|(e, _)| e)
                    };
                    println!(
                        "light length  {:.6}: preview's ε {:.6}; final's {:.6} (from the free \
                         path: its rounds resolve lamps' pools)",
                        l.length,
                        epsilon(meshlight::Preset::Preview)?,
                        epsilon(meshlight::Preset::Final)?
                    );
                }
                None => println!(
                    "free path     none: the scene is open (most rays from its surfaces meet \
                     nothing); the presets take the area rule"
                ),
            }
            // What sky each grid sees, where daylight enters (a ray caster is needed).
            if scene.daylight().is_some() && !scene.grids().is_empty() {
                let vis = meshlight::Backend::default_backend().build(&scene)?;
                for grid in scene.grids() {
                    let v = meshlight::daylight::sky_view(&scene, vis.as_ref(), grid)?;
                    let said = if v.sees_sky() {
                        format!(
                            "sees {:.2}% of its hemisphere as sky ({:.2}% through openings, \
                             {:.2}% through glass), {:.2}% as the ground outside",
                            100.0 * (v.open + v.glazed),
                            100.0 * v.open,
                            100.0 * v.glazed,
                            100.0 * v.ground
                        )
                    } else {
                        "sees no sky: no opening or glass lets daylight reach it (is the model \
                         closed, its glass facing inward, or [site] north or up pointing \
                         elsewhere?)"
                            .to_string()
                    };
                    println!("grid '{}'    {said}", grid.name());
                }
            }
            Ok(())
        }
        Command::BenchVis(bench) => bench_vis(bench, loading),
        Command::BenchRender(bench) => bench_render(bench, loading),
    }
}

/// `report`: solve, measure the grids, render the view, and write the page.
fn report_command(
    solve: &SolveArgs,
    output: &Path,
    (light_samples, specular_rays): (u32, u32),
    loading: &LoadOptions,
) -> anyhow::Result<()> {
    let (scene, options) = solve_setup(solve, loading)?;
    // A year's scene without a sky of its own: its grids and view under the daylight
    // factor's sky, the CIE overcast.
    let scene = match (scene.annual(), scene.daylight()) {
        (Some(annual), None) => {
            let mut overcast = scene.clone();
            overcast.set_daylight(Some(annual.overcast()?));
            overcast
        }
        _ => scene,
    };
    let vis = backend_from(&solve.knobs).build(&scene)?;
    diagnose(&scene, vis.as_ref())?;
    let t = std::time::Instant::now();
    let solution = solve_with_progress(&scene, vis.as_ref(), &options)?;
    let summary = solve_summary(&scene, &solution, &options, vis.name());
    print!("{summary}");
    let solving = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let lux_options = meshlight::lux::LuxOptions {
        light_samples: light_samples.max(1),
        specular_rays,
        seed: options.seed,
        threads: options.threads,
    };
    let grids = lux::measure(&scene, &solution, vis.as_ref(), &lux_options, output)?;
    let measuring = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let render_options = meshlight::RenderOptions {
        threads: options.threads,
        ..meshlight::RenderOptions::default()
    };
    let (image, _) = progress::with_progress("render", |progress| {
        meshlight::render(&scene, &solution, vis.as_ref(), &render_options, progress)
    })?;
    let view_path = output.join("view.png");
    image.write_png(&view_path, image.auto_exposure())?;
    let false_path = output.join("view-luminance.png");
    let luminance = FalseColor::Luminance;
    false_colour_render(&image, &false_path, luminance, None, false, scene.units())?;
    let views = vec![std::fs::read(&view_path)?, std::fs::read(&false_path)?];
    let rendering = t.elapsed().as_secs_f64();
    let annual = match scene.annual() {
        Some(_) => {
            let year_options = meshlight::annual::AnnualOptions {
                lux: meshlight::lux::LuxOptions {
                    light_samples: light_samples.clamp(1, 16),
                    ..lux_options
                },
                solver: options.clone(),
                hourly: false,
            };
            let (year, lines) = annual::year(&scene, vis.as_ref(), &year_options, output)?;
            let plans = annual::plans(&scene, &year, output)?;
            Some(page::AnnualPage { lines, year, plans })
        }
        None => None,
    };
    let extras = page::Extras {
        views,
        summary: &summary,
        seconds: (solving, measuring, rendering),
        annual,
    };
    let path = page::write(output, &scene, &solution, &grids, &extras)?;
    println!("wrote {}", path.display());
    Ok(())
}

/// `render`: solve (or trace, or patch) and write the image, its PNG and a summary.
fn render_command(r: RenderArgs, loading: &LoadOptions) -> anyhow::Result<()> {
    let started = std::time::Instant::now();
    if r.method != Method::Meshless && r.false_color.is_some() {
        anyhow::bail!("--false-color works with --method meshless only");
    }
    let (mut scene, options) = solve_setup(&r.solve, loading)?;
    resize(&mut scene, r.size)?;
    if r.method != Method::Meshless && ranks::ranks().size() > 1 {
        anyhow::bail!("--method {:?} runs on one rank only", r.method);
    }
    let vis = backend_from(&r.solve.knobs).build(&scene)?;
    diagnose(&scene, vis.as_ref())?;
    // The image and what to say about how it was made, by each method.
    let (image, summary) = match r.method {
        Method::Pathtrace => {
            let path_options = path_options(&r, &options);
            let traced = reference::path_trace_with_progress(&scene, vis.as_ref(), &path_options)?;
            let summary =
                reference::path_summary(&scene, &traced, &path_options, &options, vis.name());
            (traced.image, summary)
        }
        Method::Patches => {
            let patch_options = patch_options(&scene, vis.as_ref(), &r, &options)?;
            let solved = reference::patches_with_progress(&scene, vis.as_ref(), &patch_options)?;
            let summary =
                reference::patch_summary(&scene, &solved, &patch_options, &options, vis.name());
            (solved.image, summary)
        }
        Method::Meshless => {
            let solution = solve_with_progress(&scene, vis.as_ref(), &options)?;
            let preset = render_options_from(&r.solve.knobs, &r.render)?;
            let render_options = meshlight::RenderOptions {
                threads: options.threads,
                supersample: preset.supersample,
                direct: preset.direct,
                quantity: match r.false_color {
                    Some(FalseColor::Illuminance) => meshlight::Quantity::Irradiance,
                    _ => meshlight::Quantity::Radiance,
                },
                glossy_rays: preset.glossy_rays,
                gather_rays: preset.gather_rays,
                memory_budget: options.memory_budget,
            };
            let t = std::time::Instant::now();
            let (image, stats) = progress::with_progress("render", |progress| {
                meshlight::render::render_distributed(
                    &scene,
                    &solution,
                    vis.as_ref(),
                    &render_options,
                    ranks::ranks(),
                    progress,
                )
            })?;
            if !ranks::root() {
                return Ok(());
            }
            let summary = solve_summary(&scene, &solution, &options, vis.name())
                + &render_summary(&image, &stats, t.elapsed().as_secs_f64());
            (image, summary)
        }
    };
    if let Some(finding) = meshlight::diagnose::image(&scene, &image) {
        eprintln!("meshlight: warning: {}", finding.message);
    }
    image.write_exr(&r.output)?;
    let png = r.output.with_extension("png");
    match r.false_color {
        None => image.write_png(&png, image.auto_exposure())?,
        Some(kind) => false_colour_render(&image, &png, kind, r.range, r.log, scene.units())?,
    }
    print!("{summary}");
    println!(
        "total {:.2} s{}; wrote {} and {}",
        started.elapsed().as_secs_f64(),
        memory::peak_bytes().map_or(String::new(), |b| format!(
            ", peak memory {}",
            crate::units::bytes(b as f64)
        )),
        r.output.display(),
        png.display()
    );
    Ok(())
}

/// The path tracer's settings from `render`'s arguments.
fn path_options(r: &RenderArgs, options: &meshlight::Options) -> meshlight::reference::PathOptions {
    meshlight::reference::PathOptions {
        spp: r.render.spp,
        seconds: r.time,
        seed: options.seed,
        threads: options.threads,
        memory_budget: options.memory_budget,
        ..Default::default()
    }
}

/// The patch baseline's settings from `render`'s arguments (patch size: the solver's ε unless
/// given).
fn patch_options(
    scene: &Scene,
    vis: &dyn meshlight::Visibility,
    r: &RenderArgs,
    options: &meshlight::Options,
) -> anyhow::Result<meshlight::reference::PatchOptions> {
    Ok(meshlight::reference::PatchOptions {
        patch_size: match r.render.patch_size {
            Some(h) => h,
            None => meshlight::solver::choose_epsilon(scene, vis, options)?.0,
        },
        supersample: r
            .render
            .supersample
            .unwrap_or(meshlight::RenderOptions::default().supersample)
            .max(1),
        tolerance: options.tolerance,
        max_shots: options.max_shots.unwrap_or(u64::MAX),
        seed: options.seed,
        threads: options.threads,
        memory_budget: options.memory_budget,
        ..Default::default()
    })
}

/// `compare`: the error measures of an image against a reference, and a picture of the error.
fn compare(
    image: &Path,
    reference: &Path,
    diff: Option<&Path>,
    diff_range: Option<f64>,
    block: u32,
) -> anyhow::Result<()> {
    let a = Image::read_exr(image)?;
    let b = Image::read_exr(reference)?;
    if (a.width, a.height) != (b.width, b.height) {
        anyhow::bail!(
            "{} is {}x{} but {} is {}x{}: compare images of one size (render the image at \
             the reference's with --width/--height)",
            image.display(),
            a.width,
            a.height,
            reference.display(),
            b.width,
            b.height
        );
    }
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
    let ratio = meshlight::metrics::SPARKLE_RATIO;
    println!(
        "sparkles {} vs reference {} (pixels above {ratio}x their 3x3 median)",
        meshlight::metrics::sparkles(&a, ratio)?,
        meshlight::metrics::sparkles(&b, ratio)?
    );
    if let Some(path) = diff {
        let range = plot::write_error_picture(&a, &b, &e, diff_range, path)?;
        println!(
            "wrote {} (colours saturate at ±{:.3}% of the reference mean)",
            path.display(),
            100.0 * range
        );
    }
    Ok(())
}

/// `samples`: solve and write the samples as PLY, coloured by radiosity.
fn samples(solve: &SolveArgs, output: &Path, loading: &LoadOptions) -> anyhow::Result<()> {
    let (scene, options) = solve_setup(solve, loading)?;
    let vis = backend_from(&solve.knobs).build(&scene)?;
    diagnose(&scene, vis.as_ref())?;
    let solution = solve_with_progress(&scene, vis.as_ref(), &options)?;
    if !ranks::root() {
        return Ok(());
    }
    let radiosity = solution.radiosity();
    let mean = radiosity.iter().map(|b| b.element_sum() / 3.0).sum::<f64>()
        / radiosity.len().max(1) as f64
        / std::f64::consts::PI;
    let exposure = if mean > 0.0 { (0.4 / mean) as f32 } else { 1.0 };
    meshlight::ply::write_samples(&solution, output, exposure)?;
    print!("{}", solve_summary(&scene, &solution, &options, vis.name()));
    println!(
        "wrote {} ({} samples)",
        output.display(),
        solution.samples().len()
    );
    Ok(())
}

/// `bench-vis`: the visibility backends measured on a scene.
fn bench_vis(b: BenchArgs, loading: &LoadOptions) -> anyhow::Result<()> {
    let scene = load(&b.scene, loading)?;
    let options = BenchOptions {
        segments: b.queries,
        rays: b.rays,
        threads: b.threads,
        backends: if b.backend.is_empty() {
            Backend::available()
        } else {
            b.backend
        },
        bvh_presets: bvh_presets(&b.bvh_preset)?,
        batch: b.batch,
        repeats: b.repeats,
        seed: b.seed,
    };
    let report = bench::run(&scene, &options, &mut |step| {
        eprintln!("  {step}...");
    })?;
    print!("{}", bench_report(&scene, &report));
    Ok(())
}

/// `bench-render`: one solve, then the render timed at each thread count.
fn bench_render(b: BenchRenderArgs, loading: &LoadOptions) -> anyhow::Result<()> {
    let (mut scene, options) = solve_setup(&b.solve, loading)?;
    resize(&mut scene, b.size)?;
    let vis = backend_from(&b.solve.knobs).build(&scene)?;
    diagnose(&scene, vis.as_ref())?;
    let solution = solve_with_progress(&scene, vis.as_ref(), &options)?;
    let preset = render_options_from(&b.solve.knobs, &b.render)?;
    let render = meshlight::RenderOptions {
        memory_budget: options.memory_budget,
        ..preset
    };
    let report = bench_render::run(
        &scene,
        &solution,
        vis.as_ref(),
        &render,
        (&b.render_threads, b.repeats),
        &mut |step| {
            if !progress::quiet() {
                eprintln!("  {step}...");
            }
        },
    )?;
    print!("{}", bench_render::report(&scene, vis.name(), &report));
    Ok(())
}

/// What would make the result black or wrong without an error: warnings on stderr, and an
/// error where nothing emits light.
fn diagnose(scene: &Scene, vis: &dyn meshlight::Visibility) -> anyhow::Result<()> {
    for finding in meshlight::diagnose::before_solve(scene, vis)? {
        if finding.fatal {
            anyhow::bail!("{}: {}", scene.path().display(), finding.message);
        }
        eprintln!("meshlight: warning: {}", finding.message);
    }
    Ok(())
}

/// The scene's camera resized where the command line gives a size.
fn resize(scene: &mut Scene, size: ImageSize) -> anyhow::Result<()> {
    if size.width.is_some() || size.height.is_some() {
        let camera = resized(*scene.camera(), size.width, size.height);
        scene.set_camera(camera)?;
    }
    Ok(())
}

/// The camera at `width` × `height` pixels; a side not given keeps the aspect ratio (at least
/// one pixel). The field of view is vertical, so the picture's height spans the same angle.
fn resized(
    mut camera: meshlight::scene::Camera,
    width: Option<u32>,
    height: Option<u32>,
) -> meshlight::scene::Camera {
    let aspect = f64::from(camera.width) / f64::from(camera.height);
    let (w, h) = match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, (f64::from(w) / aspect).round().max(1.0) as u32),
        (None, Some(h)) => ((f64::from(h) * aspect).round().max(1.0) as u32, h),
        (None, None) => (camera.width, camera.height),
    };
    camera.width = w;
    camera.height = h;
    camera
}

/// Loads a scene and prints its warnings to stderr.
fn load(path: &Path, loading: &LoadOptions) -> anyhow::Result<Scene> {
    let scene = Scene::load_with(&meshlight::scene::Disk, path, loading)?;
    for warning in scene.warnings() {
        eprintln!("meshlight: warning: {warning}");
    }
    Ok(scene)
}

/// The scene, and options from a preset, the scene file and the command line, in that order
/// of precedence.
fn solve_setup(
    solve: &SolveArgs,
    loading: &LoadOptions,
) -> anyhow::Result<(Scene, meshlight::Options)> {
    let scene = load(&solve.scene, loading)?;
    let options = options_from(solve.epsilon, &solve.knobs)?;
    Ok((scene, options))
}
