//! The `meshlight` command: parses arguments, calls the library, reports. Nothing else.

mod cli;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use meshlight::visibility::bench::BenchOptions;
use meshlight::{Backend, Scene};

/// Meshless diffuse inter-reflection for rooms, galleries and other interiors.
#[derive(Parser)]
#[command(name = "meshlight", version, about)]
struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
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
    match run(Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("meshlight: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: Args) -> anyhow::Result<()> {
    match args.command {
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
            let report = meshlight::visibility::bench::run(&scene, &options, &mut |step| {
                eprintln!("  {step}...");
            })?;
            print!("{}", cli::bench_report(&scene, &report));
        }
    }
    Ok(())
}

/// Loads a scene and prints its warnings to stderr.
fn load(path: &std::path::Path) -> anyhow::Result<Scene> {
    let scene = Scene::load(path)?;
    for warning in &scene.warnings {
        eprintln!("meshlight: warning: {warning}");
    }
    Ok(scene)
}
