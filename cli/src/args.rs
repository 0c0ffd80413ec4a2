//! The command line's arguments and how they resolve into library options: clap's
//! definitions, sizes, presets and knobs. Reports are in `report.rs`.

use std::path::PathBuf;

use clap::builder::TypedValueParser as _;
use clap::{Parser, Subcommand};
use meshlight::visibility::BvhPreset;
use meshlight::{Backend, Options};

/// Meshless diffuse inter-reflection for rooms, galleries and other interiors.
#[derive(Parser)]
#[command(name = "meshlight", version, about)]
pub struct Args {
    #[command(subcommand)]
    pub command: Command,
    /// Refuse a reflectance (Kd) channel of exactly 1 instead of lowering it.
    #[arg(long, global = true)]
    pub strict: bool,
    /// What a reflectance channel of exactly 1 is lowered to (default: the scene file's
    /// `[solver]` max_reflectance, else 0.9).
    #[arg(long, global = true)]
    pub max_reflectance: Option<f32>,
    /// The glTF camera to render from, by name (default: the scene file's [camera], else the
    /// glTF's first).
    #[arg(long, global = true, value_name = "NAME")]
    pub camera: Option<String>,
    /// No progress lines (by default a bar on a terminal, a plain line every few seconds in a
    /// log).
    #[arg(long, global = true)]
    pub quiet: bool,
}

/// Solver settings shared by `render` and `samples`.
#[derive(clap::Args)]
pub struct SolveArgs {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Poisson-disk spacing ε of the initial samples (default: the scene file's, else automatic).
    #[arg(long)]
    pub epsilon: Option<f32>,
    #[command(flatten)]
    pub knobs: Knobs,
}

/// Every solver setting but the scene and ε: the preset, the backend, and the library's knob
/// table ([`meshlight::solver::KNOBS`]) as flags, one per knob, as the table names and
/// describes it (ε is [`SolveArgs`]' own, since `scale` takes a list of them).
#[derive(Clone, Debug)]
pub struct Knobs {
    /// Start from a preset: preview, default or final.
    pub preset: String,
    /// Visibility backend: embree or bvh.
    pub backend: Option<Backend>,
    /// The knobs given, by the table's name, as typed (switches as `true`).
    pub given: Vec<(&'static str, String)>,
}

/// The knobs that are flags of [`Knobs`].
fn knob_flags() -> impl Iterator<Item = &'static meshlight::solver::Knob> {
    meshlight::solver::KNOBS
        .iter()
        .filter(|k| k.name != "epsilon")
}

/// A knob's value as the command line gives it, checked by the table.
fn knob_value(
    knob: &'static meshlight::solver::Knob,
) -> impl Fn(&str) -> Result<String, String> + Clone {
    move |text: &str| {
        knob.set(&mut Options::default(), text)
            .map(|()| text.to_string())
            .map_err(|e| match e {
                meshlight::Error::Option { problem, .. } => problem,
                other => other.to_string(),
            })
    }
}

impl clap::Args for Knobs {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        let cmd = cmd
            .arg(
                clap::Arg::new("preset")
                    .long("preset")
                    .value_name("PRESET")
                    .default_value("default")
                    .help("Start from a preset: preview, default or final"),
            )
            .arg(
                clap::Arg::new("backend")
                    .long("backend")
                    .value_name("BACKEND")
                    .value_parser(clap::value_parser!(Backend))
                    .help("Visibility backend: embree or bvh"),
            );
        knob_flags().fold(cmd, |cmd, k| {
            let arg = clap::Arg::new(k.name)
                .long(k.name.replace('_', "-"))
                .help(k.help);
            cmd.arg(match k.value {
                Some(name) => arg.value_name(name).value_parser(knob_value(k)),
                None => arg.action(clap::ArgAction::SetTrue),
            })
        })
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

impl clap::FromArgMatches for Knobs {
    fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let mut given = Vec::new();
        for k in knob_flags() {
            match k.value {
                Some(_) => {
                    if let Some(text) = m.get_one::<String>(k.name) {
                        given.push((k.name, text.clone()));
                    }
                }
                None => {
                    if m.get_flag(k.name) {
                        given.push((k.name, "true".to_string()));
                    }
                }
            }
        }
        Ok(Knobs {
            preset: m
                .get_one::<String>("preset")
                .cloned()
                .unwrap_or_else(|| "default".into()),
            backend: m.get_one::<Backend>("backend").copied(),
            given,
        })
    }

    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

/// What `render --false-color` shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FalseColor {
    /// The luminance (radiance) seen.
    Luminance,
    /// The illuminance (irradiance) on the surface seen.
    Illuminance,
}

/// MIN:MAX, two numbers with MIN < MAX.
pub fn parse_range(text: &str) -> Result<(f64, f64), String> {
    let (a, b) = text
        .split_once(':')
        .ok_or_else(|| format!("'{text}': write MIN:MAX, e.g. 0:500"))?;
    let parse = |s: &str| {
        s.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("'{s}' is not a number"))
    };
    let (lo, hi) = (parse(a)?, parse(b)?);
    if lo >= hi {
        return Err(format!("'{text}': MIN must be below MAX"));
    }
    Ok((lo, hi))
}

/// How `render` computes its image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// The meshless solver, then interpolation at camera-ray hits.
    Meshless,
    /// Unbiased Monte Carlo path tracing: the reference.
    Pathtrace,
    /// The paper's baseline: progressive radiosity on a regular mesh of square patches.
    Patches,
}

/// How an image is made from a solution (or by the references): the flags `render` and
/// `sweep` share; `sweep --vary` takes the same names.
#[derive(clap::Args, Clone, Copy, Debug)]
pub struct RenderFlags {
    /// Rays per side on pixels that straddle an edge (1 = one ray per pixel; patches: per
    /// pixel) [default: the preset's: preview 2, default 4, final 8].
    #[arg(long)]
    pub supersample: Option<u32>,
    /// Meshless: shadow rays per area light traced at each camera hit for its direct light
    /// (one per point light); 0 interpolates the direct light from the samples, as the paper
    /// [default: the preset's: preview 4, default 16, final 64].
    #[arg(long,
          value_parser = clap::value_parser!(u32).range(0..=i64::from(meshlight::MAX_LIGHT_SAMPLES)))]
    pub direct_rays: Option<u32>,
    /// Meshless: rays gathered over the hemisphere at a camera hit within its samples' reach of
    /// another surface (contacts, creases: exact visibility there); 0 interpolates there too
    /// [default: the preset's: preview 0, default 32, final 128].
    #[arg(long,
          value_parser = clap::value_parser!(u32).range(0..=i64::from(meshlight::render::MAX_GATHER_RAYS)))]
    pub gather_rays: Option<u32>,
    /// Rays drawn from a glossy surface's lobe where a camera path meets one (and light samples
    /// per area light there).
    #[arg(long, default_value_t = 16,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(meshlight::render::MAX_GLOSSY_RAYS)))]
    pub glossy_rays: u32,
    /// Path tracing: samples per pixel.
    #[arg(long, default_value_t = 64)]
    pub spp: u32,
    /// Patches: the side of the square patches (default: the solver's ε).
    #[arg(long)]
    pub patch_size: Option<f32>,
}

/// The keys `sweep --vary` takes beyond the solver's knobs (`meshlight::solver::KNOBS`): the
/// preset, the backend and [`RenderFlags`], as the command line spells them.
pub const RENDER_KEYS: [&str; 8] = [
    "preset",
    "backend",
    "supersample",
    "direct-rays",
    "gather-rays",
    "glossy-rays",
    "spp",
    "patch-size",
];

/// The image's size in pixels, instead of the scene camera's.
#[derive(clap::Args, Clone, Copy, Debug, Default)]
pub struct ImageSize {
    /// Image width in pixels, instead of the scene's (a .glb carries none); with only one of
    /// --width and --height, the other keeps the camera's aspect ratio.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=32768))]
    pub width: Option<u32>,
    /// Image height in pixels, instead of the scene's.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=32768))]
    pub height: Option<u32>,
}

/// `render`'s arguments.
#[derive(clap::Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub solve: SolveArgs,
    /// Output image (.exr); the PNG gets the same name with .png.
    #[arg(short, long, default_value = "out.exr")]
    pub output: PathBuf,
    #[command(flatten)]
    pub size: ImageSize,
    #[command(flatten)]
    pub render: RenderFlags,
    /// How to compute the image: meshless (the solver), or pathtrace (the independent
    /// reference: unbiased Monte Carlo path tracing).
    #[arg(long, default_value = "meshless")]
    pub method: Method,
    /// Path tracing: stop after this many seconds (with fewer samples per pixel).
    #[arg(long)]
    pub time: Option<f64>,
    /// Write the PNG as a false-colour picture with a legend in the scene's unit instead of
    /// a tone-mapped one: the luminance seen, or the illuminance on the surface seen (then
    /// the EXR holds the illuminance too).
    #[arg(long, value_enum)]
    pub false_color: Option<FalseColor>,
    /// The false colours' range, MIN:MAX (default 0 to the 99th percentile; with --log,
    /// the 1st to the 99th percentile of the non-zero values).
    #[arg(long, value_parser = parse_range)]
    pub range: Option<(f64, f64)>,
    /// Logarithmic false colours.
    #[arg(long)]
    pub log: bool,
}

/// `sweep`'s arguments.
#[derive(clap::Args)]
pub struct SweepArgs {
    #[command(flatten)]
    pub solve: SolveArgs,
    /// The reference image (.exr), e.g. from `render --method pathtrace` with many samples;
    /// every run renders at its size.
    #[arg(long)]
    pub reference: PathBuf,
    /// A setting and its values, KEY=V1,V2,...; repeat for a grid of every combination.
    /// Keys: every solver flag (epsilon, epsilon-scale, zeta, alpha, rounds, light-samples, …),
    /// preset, backend and the render flags (supersample, direct-rays, gather-rays, glossy-rays,
    /// spp, patch-size); an unknown key's error lists them all.
    #[arg(long, required = true, value_parser = parse_vary)]
    pub vary: Vec<(String, Vec<String>)>,
    /// How each run computes its image.
    #[arg(long, default_value = "meshless")]
    pub method: Method,
    #[command(flatten)]
    pub render: RenderFlags,
    /// Output prefix: writes PREFIX.csv and PREFIX.png.
    #[arg(long, default_value = "sweep")]
    pub out: PathBuf,
    /// Leave out the path tracer's curve.
    #[arg(long)]
    pub no_pathtrace: bool,
    /// Measure errors on averages over blocks of N × N pixels (see `compare --block`).
    #[arg(long, default_value_t = 1)]
    pub block: u32,
    /// The path tracer's curve doubles samples per pixel from 2 up to this many, or until a
    /// render takes longer than --pathtrace-seconds.
    #[arg(long, default_value_t = 4096)]
    pub max_spp: u32,
    /// The path tracer's curve stops after a render longer than this (default: twice the
    /// slowest run). Its seed differs from --seed, so it never repeats the samples of a
    /// reference traced with --seed.
    #[arg(long)]
    pub pathtrace_seconds: Option<f64>,
}

/// The settings `--vary` knows, as the command line spells them: the solver's knob table, then
/// the preset, the backend and the render flags.
pub fn vary_keys() -> Vec<String> {
    let knobs = meshlight::solver::KNOBS
        .iter()
        .map(|k| k.name.replace('_', "-"));
    knobs
        .chain(RENDER_KEYS.iter().map(|k| k.to_string()))
        .collect()
}

/// Parses `key=v1,v2,...`.
pub fn parse_vary(s: &str) -> std::result::Result<(String, Vec<String>), String> {
    let (key, values) = s
        .split_once('=')
        .ok_or_else(|| format!("'{s}' is not key=value1,value2,..."))?;
    let key = key.trim().replace('_', "-");
    let keys = vary_keys();
    if !keys.contains(&key) {
        return Err(format!(
            "unknown setting '{key}' (known: {})",
            keys.join(", ")
        ));
    }
    let values: Vec<String> = values
        .split(',')
        .map(|v| v.trim().to_string())
        .filter(|v| !v.is_empty())
        .collect();
    if values.is_empty() {
        return Err(format!("'{s}' gives {key} no values"));
    }
    Ok((key, values))
}

/// `bench-render`'s arguments: the solve's and the render's as `render` takes them.
#[derive(clap::Args)]
pub struct BenchRenderArgs {
    #[command(flatten)]
    pub solve: SolveArgs,
    #[command(flatten)]
    pub size: ImageSize,
    #[command(flatten)]
    pub render: RenderFlags,
    /// Thread counts to render with, comma-separated (the solve uses --threads).
    #[arg(long, value_delimiter = ',', default_values_t = [1, 2],
          value_parser = clap::value_parser!(u16).range(1..=1024).map(usize::from))]
    pub render_threads: Vec<usize>,
    /// Renders at each thread count (alternating between the counts); the figures are their
    /// median.
    #[arg(long, default_value_t = 5,
          value_parser = clap::value_parser!(u16).range(1..=1000).map(usize::from))]
    pub repeats: usize,
}

/// `bench-vis`'s arguments.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Occlusion queries: segments between random points of facing surfaces.
    #[arg(long, default_value_t = 1_000_000)]
    pub queries: usize,
    /// Closest-hit queries: camera rays.
    #[arg(long, default_value_t = 100_000)]
    pub rays: usize,
    /// Thread counts to measure, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1, 2])]
    pub threads: Vec<usize>,
    /// Backends to measure, comma-separated (embree, bvh); default: all in this build.
    #[arg(long, value_delimiter = ',')]
    pub backend: Vec<Backend>,
    /// obvhs presets to measure for `bvh`: fast, medium, very-slow, thorough, thorough-wide,
    /// or all.
    #[arg(long, value_delimiter = ',', default_value = "thorough-wide")]
    pub bvh_preset: Vec<String>,
    /// Queries per call through the backend trait.
    #[arg(long, default_value_t = 1024)]
    pub batch: usize,
    /// Each figure is the best of this many runs.
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Seed of the random queries.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

#[derive(Subcommand)]
pub enum Command {
    /// Solve a scene and render its camera view: linear OpenEXR plus a tone-mapped PNG beside it.
    Render(RenderArgs),
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
    Sweep(SweepArgs),
    /// Solve a scene and measure the illuminance on its grids ([[grid]]): per grid a CSV of
    /// x,y,z,E,in_solid, an isolux plan (PNG) and a line with Emin, Eavg, Emax and the uniformity.
    Lux {
        #[command(flatten)]
        solve: SolveArgs,
        /// Folder for <grid>.csv and <grid>.png.
        #[arg(short, long, default_value = ".")]
        output: PathBuf,
        /// Shadow rays per area light and grid point.
        #[arg(long, default_value_t = 64,
              value_parser = clap::value_parser!(u32).range(1..=i64::from(meshlight::MAX_LIGHT_SAMPLES)))]
        grid_light_samples: u32,
        /// Chains followed from each grid point through mirrors, glossy surfaces and glass
        /// (scenes with specular materials only).
        #[arg(long, default_value_t = meshlight::lux::LuxOptions::default().specular_rays,
              value_parser = clap::value_parser!(u32).range(1..=i64::from(meshlight::solver::MAX_SPECULAR_RAYS)))]
        grid_specular_rays: u32,
    },
    /// A year of weather ([annual]) at the scene's grids: per grid DIR/<grid>.csv with each
    /// point's daylight autonomy, useful daylight, direct-sun hours and yearly exposure, and a
    /// line with sDA, ASE, the EN 17037 verdict and the largest exposure.
    Annual {
        #[command(flatten)]
        solve: SolveArgs,
        /// Folder for the CSVs.
        #[arg(short, long, default_value = ".")]
        output: PathBuf,
        /// Also write DIR/<grid>-hourly.csv: every hour's illuminance at every point.
        #[arg(long)]
        hourly: bool,
        /// Shadow rays per grid point to the sun's disc (at most 16 are used).
        #[arg(long, default_value_t = 16,
              value_parser = clap::value_parser!(u32).range(1..=i64::from(meshlight::MAX_LIGHT_SAMPLES)))]
        grid_light_samples: u32,
    },
    /// Solve a scene and write a lighting report: one self-contained HTML page (DIR/index.html)
    /// with the luminaire schedule, every grid's figures and targets, the isolux plans, the
    /// rendered view and how it was computed; the grids' CSVs and plans beside it
    Report {
        #[command(flatten)]
        solve: SolveArgs,
        /// Folder for index.html, the grids' CSV and PNG files and view.png.
        #[arg(short, long, default_value = "report")]
        output: PathBuf,
        /// Shadow rays per area light and grid point.
        #[arg(long, default_value_t = 64,
              value_parser = clap::value_parser!(u32).range(1..=i64::from(meshlight::MAX_LIGHT_SAMPLES)))]
        grid_light_samples: u32,
        /// Chains followed from each grid point through mirrors, glossy surfaces and glass
        /// (scenes with specular materials only).
        #[arg(long, default_value_t = meshlight::lux::LuxOptions::default().specular_rays,
              value_parser = clap::value_parser!(u32).range(1..=i64::from(meshlight::solver::MAX_SPECULAR_RAYS)))]
        grid_specular_rays: u32,
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
        /// many seconds; 0 skips the flat solver altogether.
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
    BenchVis(BenchArgs),
    /// Measure the render: one solve, the image rendered at each thread count in turn, its
    /// time per pixel against the same rays cast on their own.
    BenchRender(BenchRenderArgs),
}

/// Parses `--bvh-preset` names.
pub fn bvh_presets(names: &[String]) -> anyhow::Result<Vec<BvhPreset>> {
    let mut presets = Vec::new();
    for name in names {
        match (name.as_str(), BvhPreset::from_name(name)) {
            ("all", _) => presets.extend(BvhPreset::ALL),
            (_, Some(preset)) => presets.push(preset),
            (other, None) => {
                let known: Vec<&str> = BvhPreset::ALL.iter().map(|p| p.name()).collect();
                anyhow::bail!(
                    "unknown --bvh-preset '{other}' (known: {}, all)",
                    known.join(", ")
                )
            }
        }
    }
    Ok(presets)
}

/// The visibility backend the command line asks for (default: Embree if built in).
pub fn backend_from(args: &Knobs) -> meshlight::Backend {
    args.backend
        .unwrap_or_else(meshlight::Backend::default_backend)
}

/// The render's settings from a preset and the command line: its flags where given, the
/// preset's otherwise.
pub fn render_options_from(
    args: &Knobs,
    flags: &RenderFlags,
) -> anyhow::Result<meshlight::RenderOptions> {
    let mut o = args
        .preset
        .parse::<meshlight::solver::Preset>()?
        .render_options();
    o.supersample = flags.supersample.unwrap_or(o.supersample).max(1);
    o.direct = flags
        .direct_rays
        .map_or(o.direct, meshlight::Direct::from_rays);
    o.gather_rays = flags.gather_rays.unwrap_or(o.gather_rays);
    o.glossy_rays = flags.glossy_rays;
    Ok(o)
}

/// Options from a preset and the command line's knobs.
pub fn options_from(epsilon: Option<f32>, args: &Knobs) -> anyhow::Result<Options> {
    let mut o = args.preset.parse::<meshlight::solver::Preset>()?.options();
    o.epsilon = epsilon.or(o.epsilon);
    for (name, text) in &args.given {
        o.set(name, text)?;
    }
    Ok(o)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<Args, clap::Error> {
        Args::try_parse_from(["meshlight", "render", "scene.toml"].iter().chain(args))
    }

    fn knobs_of(args: &Args) -> (&Option<f32>, &Knobs) {
        match &args.command {
            Command::Render(r) => (&r.solve.epsilon, &r.solve.knobs),
            _ => unreachable!(),
        }
    }

    #[test]
    fn the_knob_flags_set_what_the_library_table_sets() {
        let args = parse(&[
            "--preset",
            "final",
            "--light-samples",
            "7",
            "--exact-visibility",
            "--memory-budget",
            "3M",
            "--epsilon",
            "0.5",
        ])
        .unwrap();
        let (epsilon, knobs) = knobs_of(&args);
        let o = options_from(*epsilon, knobs).unwrap();
        let mut expected = Options::final_quality();
        expected.light_samples = 7;
        expected.exact_visibility = true;
        expected.memory_budget = 3 << 20;
        expected.epsilon = Some(0.5);
        assert_eq!(o, expected);
        // No flag given: the preset's options as they are.
        let args = parse(&[]).unwrap();
        let (epsilon, knobs) = knobs_of(&args);
        assert_eq!(options_from(*epsilon, knobs).unwrap(), Options::default());
    }

    #[test]
    fn a_knob_out_of_range_is_refused_when_parsed_with_its_range() {
        let e = parse(&["--light-samples", "0"]).err().unwrap().to_string();
        assert!(e.contains("--light-samples"), "{e}");
        assert!(
            e.contains(&format!("must lie in 1..={}", meshlight::MAX_LIGHT_SAMPLES)),
            "{e}"
        );
        let e = parse(&["--threads", "many"]).err().unwrap().to_string();
        assert!(e.contains("'many' is not a valid value"), "{e}");
    }
}
