//! The `meshlight` command: parses arguments, calls the library, reports. Nothing else.

mod cli;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use cli::bench::BenchOptions;
use meshlight::{Backend, Scene};

/// Meshless diffuse inter-reflection for rooms, galleries and other interiors.
#[derive(Parser)]
#[command(name = "meshlight", version, about)]
struct Args {
    #[command(subcommand)]
    command: Command,
    /// Refuse a reflectance (Kd) channel of exactly 1 instead of lowering it.
    #[arg(long, global = true)]
    strict: bool,
    /// What a reflectance channel of exactly 1 is lowered to (default: the scene file's
    /// [solver] max_reflectance, else 0.9).
    #[arg(long, global = true)]
    max_reflectance: Option<f32>,
}

/// How scenes are read, from the command line (set once, before any scene is loaded).
static LOADING: std::sync::OnceLock<meshlight::scene::LoadOptions> = std::sync::OnceLock::new();

/// Solver settings shared by `render` and `samples`.
#[derive(clap::Args)]
struct SolveArgs {
    /// The scene file (TOML).
    scene: PathBuf,
    /// Poisson-disk spacing ε of the initial samples (default: the scene file's, else automatic).
    #[arg(long)]
    epsilon: Option<f32>,
    #[command(flatten)]
    knobs: Knobs,
}

/// Every solver setting but the scene and ε.
#[derive(clap::Args, Clone)]
struct Knobs {
    /// Start from a preset: preview, default or final.
    #[arg(long, default_value = "default")]
    preset: String,
    /// Adaptive error threshold ζ, relative to the mean radiosity.
    #[arg(long)]
    zeta: Option<f32>,
    /// Area weight fall-off α (eq. 5).
    #[arg(long)]
    alpha: Option<f32>,
    /// Adaptive rounds after the first solve.
    #[arg(long)]
    rounds: Option<u32>,
    /// Shadow rays per area light and sample.
    #[arg(long)]
    light_samples: Option<u32>,
    /// Stop shooting when unshot power < this fraction of emitted power.
    #[arg(long)]
    tolerance: Option<f64>,
    /// At most this many shots per solve.
    #[arg(long)]
    max_shots: Option<u64>,
    /// Refuse to place more samples than this.
    #[arg(long)]
    max_samples: Option<usize>,
    /// The memory budget every large structure counts against: bytes, or with a K, M or G
    /// suffix (binary units), e.g. 512M, 8G (default 8G).
    #[arg(long, value_parser = cli::parse_bytes)]
    memory_budget: Option<usize>,
    /// Cluster hierarchy error threshold, relative to the mean radiosity (0: the flat solver).
    #[arg(long)]
    cluster_threshold: Option<f64>,
    /// Refine every partly visible cluster link down to samples, however faint (slower).
    #[arg(long)]
    exact_visibility: bool,
    /// Visibility backend: embree or bvh.
    #[arg(long)]
    backend: Option<Backend>,
    /// Worker threads.
    #[arg(long)]
    threads: Option<usize>,
    /// Seed of all random choices.
    #[arg(long)]
    seed: Option<u64>,
}

/// How `render` computes its image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum Method {
    /// The meshless solver, then interpolation at camera-ray hits.
    Meshless,
    /// Unbiased Monte Carlo path tracing: the reference.
    Pathtrace,
    /// The paper's baseline: progressive radiosity on a regular mesh of square patches.
    Patches,
}

#[derive(Subcommand)]
enum Command {
    /// Solve a scene and render its camera view: linear OpenEXR plus a tone-mapped PNG beside it.
    Render {
        #[command(flatten)]
        solve: SolveArgs,
        /// Output image (.exr); the PNG gets the same name with .png.
        #[arg(short, long, default_value = "out.exr")]
        output: PathBuf,
        /// Rays per side on pixels that straddle an edge (1 = one ray per pixel).
        #[arg(long, default_value_t = 4)]
        supersample: u32,
        /// How to compute the image: meshless (the solver), or pathtrace (the independent
        /// reference: unbiased Monte Carlo path tracing).
        #[arg(long, default_value = "meshless")]
        method: Method,
        /// Path tracing: samples per pixel.
        #[arg(long, default_value_t = 64)]
        spp: u32,
        /// Path tracing: stop after this many seconds (with fewer samples per pixel).
        #[arg(long)]
        time: Option<f64>,
        /// Patches: the side of the square patches (default: the solver's ε).
        #[arg(long)]
        patch_size: Option<f32>,
    },
    /// Compare an image with a reference: mean absolute error / mean (the paper's measure) and more.
    Compare {
        /// The image to judge (.exr).
        image: PathBuf,
        /// The reference (.exr).
        reference: PathBuf,
        /// Also write a false-colour picture of the signed error per pixel (PNG, with a legend):
        /// red where the image is too bright, blue where too dark.
        #[arg(long)]
        diff: Option<PathBuf>,
        /// The error at which the picture's colours saturate, as a fraction of the reference's
        /// mean (default: the 99th percentile of |error|, rounded up to 1, 2 or 5).
        #[arg(long)]
        diff_range: Option<f64>,
        /// Compare averages over blocks of N × N pixels: a noisy reference's noise falls by
        /// about N, errors spanning several pixels stay.
        #[arg(long, default_value_t = 1)]
        block: u32,
    },
    /// Run a grid of settings against a reference image: a CSV of time and error per run, and
    /// a plot of error against time with the Pareto front and the path tracer's curve.
    Sweep {
        #[command(flatten)]
        solve: SolveArgs,
        /// The reference image (.exr), e.g. from `render --method pathtrace` with many samples;
        /// every run renders at its size.
        #[arg(long)]
        reference: PathBuf,
        /// A setting and its values, KEY=V1,V2,...; repeat for a grid of every combination.
        /// Keys: preset, epsilon, zeta, alpha, rounds, light-samples, tolerance, max-shots,
        /// max-samples, cluster-threshold, exact-visibility, backend, threads, seed,
        /// supersample, patch-size, spp.
        #[arg(long, required = true, value_parser = cli::sweep::parse_vary)]
        vary: Vec<(String, Vec<String>)>,
        /// How each run computes its image.
        #[arg(long, default_value = "meshless")]
        method: Method,
        /// Rays per side on edge pixels (meshless) or per pixel (patches).
        #[arg(long, default_value_t = 4)]
        supersample: u32,
        /// Patches: the side of the square patches (default: the solver's ε).
        #[arg(long)]
        patch_size: Option<f32>,
        /// Path tracing runs: samples per pixel.
        #[arg(long, default_value_t = 64)]
        spp: u32,
        /// Output prefix: writes PREFIX.csv and PREFIX.png.
        #[arg(long, default_value = "sweep")]
        out: PathBuf,
        /// Leave out the path tracer's curve.
        #[arg(long)]
        no_pathtrace: bool,
        /// Measure errors on averages over blocks of N × N pixels (see `compare --block`).
        #[arg(long, default_value_t = 1)]
        block: u32,
        /// The path tracer's curve doubles samples per pixel from 2 up to this many, or until a
        /// render takes longer than --pathtrace-seconds.
        #[arg(long, default_value_t = 4096)]
        max_spp: u32,
        /// The path tracer's curve stops after a render longer than this (default: twice the
        /// slowest run). Its seed differs from --seed, so it never repeats the samples of a
        /// reference traced with --seed.
        #[arg(long)]
        pathtrace_seconds: Option<f64>,
    },
    /// Solve a scene and write the samples (position, normal, colour, radius) as PLY.
    Samples {
        #[command(flatten)]
        solve: SolveArgs,
        /// Output point cloud (.ply).
        #[arg(short, long, default_value = "samples.ply")]
        output: PathBuf,
    },
    /// Measure how the solver scales: solve at several ε with the cluster hierarchy and (where
    /// it fits in the time limit) the flat solver, print samples, links, queries, seconds per
    /// phase and peak memory, and the exponents of time and queries against the samples.
    Scale {
        /// The scene file (TOML).
        scene: PathBuf,
        /// The spacings to solve at, comma-separated, largest first (e.g. 0.6,0.3,0.15).
        #[arg(long, value_delimiter = ',', required = true)]
        epsilon: Vec<f32>,
        /// Skip a flat solve predicted (from the previous one, as N²) to take longer than this
        /// many seconds.
        #[arg(long, default_value_t = 600.0)]
        flat_limit: f64,
        #[command(flatten)]
        knobs: Knobs,
    },
    /// Print a summary of a scene: geometry, surfaces, lights, camera.
    Info {
        /// The scene file (TOML).
        scene: PathBuf,
    },
    /// Measure the visibility backends on a scene (occlusion and closest-hit rates).
    BenchVis {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Occlusion queries: segments between random points of facing surfaces.
        #[arg(long, default_value_t = 1_000_000)]
        queries: usize,
        /// Closest-hit queries: camera rays.
        #[arg(long, default_value_t = 100_000)]
        rays: usize,
        /// Thread counts to measure, comma-separated.
        #[arg(long, value_delimiter = ',', default_values_t = [1, 2])]
        threads: Vec<usize>,
        /// Backends to measure, comma-separated (embree, bvh); default: all in this build.
        #[arg(long, value_delimiter = ',')]
        backend: Vec<Backend>,
        /// obvhs presets to measure for `bvh`: fast, medium, very-slow, thorough, thorough-wide,
        /// or all.
        #[arg(long, value_delimiter = ',', default_value = "thorough-wide")]
        bvh_preset: Vec<String>,
        /// Queries per call through the backend trait.
        #[arg(long, default_value_t = 1024)]
        batch: usize,
        /// Each figure is the best of this many runs.
        #[arg(long, default_value_t = 3)]
        repeats: usize,
        /// Seed of the random queries.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
}

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
            method,
            spp,
            time,
            patch_size,
        } => {
            let started = std::time::Instant::now();
            let (scene, options) = cli::solve_setup(&solve.scene, solve.epsilon, &solve.knobs)?;
            let vis = cli::backend_from(&solve.knobs).build(&scene)?;
            if method == Method::Pathtrace {
                let path_options = meshlight::reference::PathOptions {
                    spp,
                    seconds: time,
                    seed: options.seed,
                    threads: options.threads,
                    ..Default::default()
                };
                let traced =
                    cli::reference::path_trace_with_progress(&scene, vis.as_ref(), &path_options)?;
                traced.image.write_exr(&output)?;
                let png = output.with_extension("png");
                traced.image.write_png(&png, traced.image.auto_exposure())?;
                print!(
                    "{}",
                    cli::reference::path_summary(
                        &scene,
                        &traced,
                        &path_options,
                        &options,
                        vis.name()
                    )
                );
                println!(
                    "total {:.2} s{}; wrote {} and {}",
                    started.elapsed().as_secs_f64(),
                    cli::memory::peak_bytes().map_or(String::new(), |b| format!(
                        ", peak memory {}",
                        cli::memory::human(b)
                    )),
                    output.display(),
                    png.display()
                );
                return Ok(());
            }
            if method == Method::Patches {
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
                let solved =
                    cli::reference::patches_with_progress(&scene, vis.as_ref(), &patch_options)?;
                solved.image.write_exr(&output)?;
                let png = output.with_extension("png");
                solved.image.write_png(&png, solved.image.auto_exposure())?;
                print!(
                    "{}",
                    cli::reference::patch_summary(
                        &scene,
                        &solved,
                        &patch_options,
                        &options,
                        vis.name()
                    )
                );
                println!(
                    "total {:.2} s; wrote {} and {}",
                    started.elapsed().as_secs_f64(),
                    output.display(),
                    png.display()
                );
                return Ok(());
            }
            let solution = cli::solve_with_progress(&scene, vis.as_ref(), &options)?;
            let render_options = meshlight::RenderOptions {
                threads: options.threads,
                supersample,
            };
            let t = std::time::Instant::now();
            let (image, stats) =
                meshlight::render(&scene, &solution, vis.as_ref(), &render_options)?;
            let render_seconds = t.elapsed().as_secs_f64();
            image.write_exr(&output)?;
            let png = output.with_extension("png");
            image.write_png(&png, image.auto_exposure())?;
            print!(
                "{}",
                cli::solve_summary(&scene, &solution, &options, vis.name())
            );
            print!("{}", cli::render_summary(&image, &stats, render_seconds));
            println!(
                "total {:.2} s{}; wrote {} and {}",
                started.elapsed().as_secs_f64(),
                cli::memory::peak_bytes().map_or(String::new(), |b| format!(
                    ", peak memory {}",
                    cli::memory::human(b)
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
