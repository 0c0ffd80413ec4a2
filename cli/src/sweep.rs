//! `meshlight sweep`: solve a scene over a grid of settings, measure each run's time and its
//! error against a reference image, and write a CSV and a plot of error against time with
//! the Pareto front marked and the path tracer's curve (doubling samples per pixel) beside.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Instant;

use anyhow::{anyhow, bail, Context, Result};
use meshlight::metrics::ImageError;
use meshlight::solver::Options;
use meshlight::{Backend, Image, Scene, Visibility};
use plotters::style::RGBColor;

use super::plot::{error_time_png, Series};
use crate::Method;

/// Added to the seed of the path tracer's curve, so it shares no random numbers with a
/// reference traced with the sweep's own seed.
const CURVE_SEED: u64 = 0x9E37_79B9;

/// What a sweep runs.
pub struct Sweep {
    /// The settings to vary and their values, in the order given.
    pub vary: Vec<(String, Vec<String>)>,
    /// How each run makes its image.
    pub method: Method,
    /// ε from the command line, for every run that does not vary it.
    pub epsilon: Option<f32>,
    /// The fixed knobs from the command line.
    pub knobs: super::Knobs,
    /// How each image is made, where the run does not vary it.
    pub render: crate::args::RenderFlags,
    /// Output prefix: PREFIX.csv and PREFIX.png.
    pub out: PathBuf,
    /// Add the path tracer's curve (doubling spp) to the CSV and the plot.
    pub pathtrace_curve: bool,
    /// Errors on averages over blocks of this many pixels a side (1: per pixel).
    pub block: u32,
    /// The curve's largest samples per pixel.
    pub max_spp: u32,
    /// The curve stops after a render longer than this (default: twice the slowest run).
    pub pathtrace_seconds: Option<f64>,
}

impl From<crate::SweepArgs> for Sweep {
    fn from(a: crate::SweepArgs) -> Sweep {
        Sweep {
            vary: a.vary,
            method: a.method,
            epsilon: a.solve.epsilon,
            knobs: a.solve.knobs,
            render: a.render,
            out: a.out,
            pathtrace_curve: !a.no_pathtrace,
            block: a.block,
            max_spp: a.max_spp,
            pathtrace_seconds: a.pathtrace_seconds,
        }
    }
}

/// Whether `method` uses the setting `key`: a sweep over a setting the method ignores would
/// label identical runs as different.
fn used_by(method: Method, key: &str) -> bool {
    match method {
        Method::Meshless => !matches!(key, "patch-size" | "spp"),
        Method::Patches => matches!(
            key,
            "epsilon"
                | "epsilon-scale"
                | "patch-size"
                | "tolerance"
                | "max-shots"
                | "backend"
                | "threads"
                | "seed"
                | "supersample"
        ),
        Method::Pathtrace => matches!(key, "spp" | "backend" | "threads" | "seed"),
    }
}

/// One run's settings beyond the solver's options.
#[derive(Clone, Copy)]
struct Extra {
    supersample: u32,
    /// Shadow rays per area light at each camera hit (0: direct light interpolated).
    direct_rays: u32,
    /// Gather rays at hits near another surface (0: none).
    gather_rays: u32,
    /// Rays drawn from a glossy lobe where a camera path meets one.
    glossy_rays: u32,
    patch_size: Option<f32>,
    spp: u32,
    /// Errors on averages over blocks of this many pixels a side.
    block: u32,
    /// The visibility backend.
    backend: Backend,
}

fn value<T: FromStr>(key: &str, v: &str) -> Result<T> {
    v.parse()
        .map_err(|_| anyhow!("--vary {key}: '{v}' is not a valid value"))
}

/// Sets one varied setting (`preset` is applied before, when the options are made): a knob
/// of the solver's table, or one of the render's.
fn apply(key: &str, v: &str, o: &mut Options, extra: &mut Extra) -> Result<()> {
    if meshlight::solver::knob(key).is_some() {
        return o.set(key, v).map_err(|e| match e {
            meshlight::Error::Option { problem, .. } => anyhow!("--vary {key}: {problem}"),
            other => anyhow!("--vary {key}: {other}"),
        });
    }
    match key {
        "preset" => {}
        "backend" => {
            extra.backend = Backend::from_str(v).map_err(|e| anyhow!("--vary {key}: {e}"))?
        }
        "supersample" => extra.supersample = value::<u32>(key, v)?.max(1),
        "direct-rays" => extra.direct_rays = value(key, v)?,
        "gather-rays" => extra.gather_rays = value(key, v)?,
        "glossy-rays" => extra.glossy_rays = value(key, v)?,
        "patch-size" => extra.patch_size = Some(value(key, v)?),
        "spp" => extra.spp = value(key, v)?,
        other => bail!("--vary: unknown setting '{other}'"),
    }
    Ok(())
}

/// One combination of the varied settings: (key, value) in the order given.
type Point = Vec<(String, String)>;

/// Every combination of the varied values, the first key varying slowest.
fn grid(vary: &[(String, Vec<String>)]) -> Vec<Vec<(String, String)>> {
    let mut points: Vec<Vec<(String, String)>> = vec![Vec::new()];
    for (key, values) in vary {
        points = points
            .into_iter()
            .flat_map(|p| {
                values.iter().map(move |v| {
                    let mut q = p.clone();
                    q.push((key.clone(), v.clone()));
                    q
                })
            })
            .collect();
    }
    points
}

/// One measured run.
struct Row {
    method: &'static str,
    settings: Vec<String>,
    spp: Option<u32>,
    /// Samples (meshless) or patches.
    samples: usize,
    shots: u64,
    queries: u64,
    /// Place (or mesh), areas, direct, links, shoot, render.
    seconds: [f64; 6],
    total: f64,
    error: ImageError,
    pareto: bool,
}

/// Runs the sweep, printing a line per run, and writes PREFIX.csv and PREFIX.png.
pub fn run(scene: &Scene, reference: &Image, sweep: &Sweep) -> Result<()> {
    let mut scene = scene.clone();
    let camera = meshlight::scene::Camera {
        width: reference.width,
        height: reference.height,
        ..*scene.camera()
    };
    if let Err(e) = scene.set_camera(camera) {
        bail!("the reference's size does not make a camera: {e}");
    }
    check(reference, sweep)?;
    let points = grid(&sweep.vary);
    let runs = plan(&points, sweep)?;
    let keys: Vec<&str> = sweep.vary.iter().map(|(k, _)| k.as_str()).collect();
    println!(
        "sweep of {} on {} at {}x{}: {} run(s) of {}{}",
        keys.join(" × "),
        scene.path().display(),
        reference.width,
        reference.height,
        runs.len(),
        method_name(sweep.method),
        if sweep.block > 1 {
            format!("; errors over blocks of {0}x{0} pixels", sweep.block)
        } else {
            String::new()
        }
    );
    let mut backends: HashMap<Backend, Box<dyn Visibility>> = HashMap::new();
    let mut rows = Vec::new();
    for (i, (point, options, extra)) in runs.iter().enumerate() {
        let vis = built(&mut backends, &scene, extra.backend)?;
        let mut row = measure(&scene, vis, reference, sweep.method, options, extra)?;
        row.settings = point.iter().map(|(_, v)| v.clone()).collect();
        println!(
            "run {}/{}: {}: {} {}, {:.3} s, MAE/mean {:.3}%, bias {:+.3}%",
            i + 1,
            runs.len(),
            point
                .iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect::<Vec<_>>()
                .join(" "),
            row.samples,
            if sweep.method == Method::Patches {
                "patches"
            } else {
                "samples"
            },
            row.total,
            100.0 * row.error.mae_over_mean,
            100.0 * row.error.bias
        );
        rows.push(row);
    }
    mark_pareto(&mut rows);
    let curve = if sweep.pathtrace_curve && sweep.method != Method::Pathtrace {
        let slowest = rows.iter().map(|r| r.total).fold(0.0, f64::max);
        pathtrace_curve(&scene, reference, sweep, slowest, &mut backends)?
    } else {
        Vec::new()
    };
    let csv = sweep.out.with_extension("csv");
    std::fs::write(&csv, to_csv(&keys, &rows, &curve))
        .with_context(|| format!("cannot write {}", csv.display()))?;
    let png = sweep.out.with_extension("png");
    plot(&png, &scene, sweep.method, &rows, &curve)?;
    print_front(&keys, &rows);
    println!("wrote {} and {}", csv.display(), png.display());
    Ok(())
}

/// Checks every setting before the first run: the block size against the reference, and that
/// the method uses every setting varied.
fn check(reference: &Image, sweep: &Sweep) -> Result<()> {
    if sweep.block != 1 {
        meshlight::metrics::block_average(reference, sweep.block)?;
    }
    for (key, _) in &sweep.vary {
        if !used_by(sweep.method, key) {
            bail!(
                "--vary {key}: the {} method does not use it",
                method_name(sweep.method)
            );
        }
    }
    Ok(())
}

/// Each point of the grid as a run: its options and the render's settings, the preset first,
/// then the point's other values.
fn plan<'p>(points: &'p [Point], sweep: &Sweep) -> Result<Vec<(&'p Point, Options, Extra)>> {
    let mut runs = Vec::with_capacity(points.len());
    for point in points {
        let mut knobs = sweep.knobs.clone();
        for (k, v) in point {
            if k == "preset" {
                knobs.preset = v.clone();
            }
        }
        let mut options = super::options_from(sweep.epsilon, &knobs)?;
        let render = super::render_options_from(&knobs, &sweep.render)?;
        let mut extra = Extra {
            supersample: render.supersample,
            direct_rays: match render.direct {
                meshlight::Direct::Interpolated => 0,
                meshlight::Direct::Traced { light_samples } => light_samples,
            },
            gather_rays: render.gather_rays,
            glossy_rays: render.glossy_rays,
            patch_size: sweep.render.patch_size,
            spp: sweep.render.spp,
            block: sweep.block,
            backend: super::backend_from(&sweep.knobs),
        };
        for (k, v) in point {
            apply(k, v, &mut options, &mut extra)?;
        }
        runs.push((point, options, extra));
    }
    Ok(runs)
}

/// The path tracer's curve: samples per pixel doubling from 2 up to `--max-spp`, or until a
/// render takes longer than `--pathtrace-seconds` (default: twice the `slowest` run). A
/// reference is usually path traced with the same seed: its samples would then include the
/// curve's own, and the curve would meet it too soon, so the curve takes another stream.
fn pathtrace_curve(
    scene: &Scene,
    reference: &Image,
    sweep: &Sweep,
    slowest: f64,
    backends: &mut HashMap<Backend, Box<dyn Visibility>>,
) -> Result<Vec<Row>> {
    let mut curve = Vec::new();
    let budget = sweep.pathtrace_seconds.unwrap_or((2.0 * slowest).max(1.0));
    let mut options = super::options_from(sweep.epsilon, &sweep.knobs)?;
    options.seed = options.seed.wrapping_add(CURVE_SEED);
    let vis = built(backends, scene, super::backend_from(&sweep.knobs))?;
    let mut spp = 2u32;
    while spp <= sweep.max_spp.max(2) {
        let extra = Extra {
            supersample: 1,
            direct_rays: 0,
            gather_rays: 0,
            glossy_rays: 0,
            patch_size: None,
            spp,
            block: sweep.block,
            backend: super::backend_from(&sweep.knobs),
        };
        let row = measure(scene, vis, reference, Method::Pathtrace, &options, &extra)?;
        println!(
            "path tracer {spp} spp: {:.3} s, MAE/mean {:.3}%, bias {:+.3}%",
            row.total,
            100.0 * row.error.mae_over_mean,
            100.0 * row.error.bias
        );
        let total = row.total;
        curve.push(row);
        match spp.checked_mul(2) {
            Some(next) if total <= budget => spp = next,
            _ => break,
        }
    }
    Ok(curve)
}

/// The Pareto front, fastest first.
fn print_front(keys: &[&str], rows: &[Row]) {
    println!("Pareto front (no run both faster and more accurate):");
    let mut front: Vec<&Row> = rows.iter().filter(|r| r.pareto).collect();
    front.sort_by(|a, b| a.total.total_cmp(&b.total));
    for r in front {
        let settings: Vec<String> = keys
            .iter()
            .zip(&r.settings)
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        println!(
            "  {}: {:.3} s, MAE/mean {:.3}%",
            settings.join(" "),
            r.total,
            100.0 * r.error.mae_over_mean
        );
    }
}

/// The backend `b` over the scene, built once per sweep.
fn built<'a>(
    cache: &'a mut HashMap<Backend, Box<dyn Visibility>>,
    scene: &Scene,
    b: Backend,
) -> Result<&'a dyn Visibility> {
    if let std::collections::hash_map::Entry::Vacant(e) = cache.entry(b) {
        e.insert(b.build(scene)?);
    }
    Ok(cache[&b].as_ref())
}

fn method_name(m: Method) -> &'static str {
    match m {
        Method::Meshless => "meshless",
        Method::Pathtrace => "pathtrace",
        Method::Patches => "patches",
    }
}

/// Runs one setting and measures it against the reference.
fn measure(
    scene: &Scene,
    vis: &dyn Visibility,
    reference: &Image,
    method: Method,
    options: &Options,
    extra: &Extra,
) -> Result<Row> {
    let started = Instant::now();
    let mut row = Row {
        method: method_name(method),
        settings: Vec::new(),
        spp: None,
        samples: 0,
        shots: 0,
        queries: 0,
        seconds: [0.0; 6],
        total: 0.0,
        error: meshlight::metrics::compare(reference, reference)?,
        pareto: false,
    };
    let image = match method {
        Method::Meshless => {
            let solution = super::solve_with_progress(scene, vis, options)?;
            for r in solution.rounds() {
                let s = r.seconds;
                for (acc, v) in row
                    .seconds
                    .iter_mut()
                    .zip([s.sampling, s.areas, s.direct, s.links, s.shooting])
                {
                    *acc += v;
                }
                row.shots += r.shooting.shots;
                row.queries += r.shooting.queries + r.direct_queries;
            }
            row.samples = solution.samples().len();
            let t = Instant::now();
            let (image, _) = crate::progress::with_progress("render", |progress| {
                meshlight::render(
                    scene,
                    &solution,
                    vis,
                    &meshlight::RenderOptions {
                        threads: options.threads,
                        supersample: extra.supersample,
                        direct: meshlight::Direct::from_rays(extra.direct_rays),
                        gather_rays: extra.gather_rays,
                        glossy_rays: extra.glossy_rays,
                        ..meshlight::RenderOptions::default()
                    },
                    progress,
                )
            })?;
            row.seconds[5] = t.elapsed().as_secs_f64();
            image
        }
        Method::Patches => {
            let patch = meshlight::reference::PatchOptions {
                patch_size: match extra.patch_size {
                    Some(h) => h,
                    None => meshlight::solver::choose_epsilon(scene, vis, options)?.0,
                },
                supersample: extra.supersample,
                tolerance: options.tolerance,
                max_shots: options.max_shots.unwrap_or(u64::MAX),
                seed: options.seed,
                threads: options.threads,
                ..Default::default()
            };
            let solved = super::reference::patches_with_progress(scene, vis, &patch)?;
            row.samples = solved.patches;
            row.shots = solved.shots;
            row.queries = solved.queries;
            row.seconds[0] = solved.seconds[0];
            row.seconds[4] = solved.seconds[1];
            row.seconds[5] = solved.seconds[2];
            solved.image
        }
        Method::Pathtrace => {
            let path = meshlight::reference::PathOptions {
                spp: extra.spp,
                seed: options.seed,
                threads: options.threads,
                ..Default::default()
            };
            let traced = super::reference::path_trace_with_progress(scene, vis, &path)?;
            row.spp = Some(traced.spp);
            row.queries = traced.rays;
            row.seconds[5] = started.elapsed().as_secs_f64();
            traced.image
        }
    };
    row.total = started.elapsed().as_secs_f64();
    row.error = meshlight::metrics::compare_blocks(&image, reference, extra.block)?;
    Ok(row)
}

/// Marks the runs no other run beats on both time and error.
fn mark_pareto(rows: &mut [Row]) {
    let points: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| (r.total, r.error.mae_over_mean))
        .collect();
    for (i, r) in rows.iter_mut().enumerate() {
        let (t, e) = points[i];
        r.pareto = !points
            .iter()
            .enumerate()
            .any(|(j, &(u, f))| j != i && u <= t && f <= e && (u < t || f < e));
    }
}

fn to_csv(keys: &[&str], rows: &[Row], curve: &[Row]) -> String {
    let mut out = String::from("method");
    for k in keys {
        let _ = write!(out, ",{k}");
    }
    out.push_str(
        ",spp,samples,shots,queries,place_s,areas_s,direct_s,links_s,shoot_s,render_s,total_s,\
         mae_over_mean,rmse_over_mean,p99_over_mean,bias,pareto\n",
    );
    for r in rows.iter().chain(curve) {
        out.push_str(r.method);
        for i in 0..keys.len() {
            let _ = write!(out, ",{}", r.settings.get(i).map_or("", String::as_str));
        }
        let _ = write!(
            out,
            ",{},{},{},{}",
            r.spp.map_or(String::new(), |s| s.to_string()),
            r.samples,
            r.shots,
            r.queries
        );
        for s in r.seconds {
            let _ = write!(out, ",{s:.4}");
        }
        let _ = writeln!(
            out,
            ",{:.4},{:.6},{:.6},{:.6},{:+.6},{}",
            r.total,
            r.error.mae_over_mean,
            r.error.rmse_over_mean,
            r.error.p99_over_mean,
            r.error.bias,
            u8::from(r.pareto)
        );
    }
    out
}

fn plot(path: &Path, scene: &Scene, method: Method, rows: &[Row], curve: &[Row]) -> Result<()> {
    let percent = |r: &Row| (r.total, 100.0 * r.error.mae_over_mean);
    let mut front: Vec<(f64, f64)> = rows.iter().filter(|r| r.pareto).map(percent).collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut series = vec![
        Series {
            name: format!("{} runs", method_name(method)),
            points: rows.iter().map(percent).collect(),
            line: false,
            colour: RGBColor(150, 150, 150),
        },
        Series {
            name: "Pareto front".to_string(),
            points: front,
            line: true,
            colour: RGBColor(33, 102, 172),
        },
    ];
    if !curve.is_empty() {
        series.push(Series {
            name: "path tracer (doubling spp)".to_string(),
            points: curve.iter().map(percent).collect(),
            line: true,
            colour: RGBColor(178, 24, 43),
        });
    }
    let name = scene
        .path()
        .parent()
        .and_then(|p| p.file_name())
        .map_or_else(
            || scene.path().display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
    error_time_png(path, &format!("{name}: error against time"), &series)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::args::parse_vary;

    #[test]
    fn every_key_is_a_flag_of_the_sweep_and_every_setting_flag_a_key() {
        use clap::CommandFactory;
        let command = crate::args::Args::command();
        let sweep = command.find_subcommand("sweep").unwrap();
        let flags: Vec<&str> = sweep.get_arguments().filter_map(|a| a.get_long()).collect();
        let keys = crate::args::vary_keys();
        for key in &keys {
            assert!(flags.contains(&key.as_str()), "--vary {key} is not a flag");
        }
        // The render's flags that set how an image is made are keys too.
        let render = command.find_subcommand("render").unwrap();
        let not_settings = [
            "output",
            "width",
            "height",
            "method",
            "time",
            "false-color",
            "range",
            "log",
        ];
        for flag in render.get_arguments().filter_map(|a| a.get_long()) {
            let global = ["strict", "max-reflectance", "camera", "quiet", "help"];
            if !not_settings.contains(&flag) && !global.contains(&flag) {
                assert!(
                    keys.iter().any(|k| k == flag),
                    "render --{flag} cannot be varied"
                );
            }
        }
    }

    #[test]
    fn vary_parses_and_refuses() {
        assert_eq!(
            parse_vary("epsilon=0.3, 0.2").unwrap(),
            (
                "epsilon".to_string(),
                vec!["0.3".to_string(), "0.2".to_string()]
            )
        );
        assert_eq!(parse_vary("light_samples=4").unwrap().0, "light-samples");
        assert!(parse_vary("colour=red")
            .unwrap_err()
            .contains("unknown setting 'colour'"));
        assert!(parse_vary("zeta").unwrap_err().contains("key=value1"));
        assert!(parse_vary("zeta=").unwrap_err().contains("no values"));
    }

    fn row(total: f64, mae: f64) -> Row {
        let image = Image {
            width: 1,
            height: 1,
            pixels: vec![glam::Vec3::ONE],
        };
        let mut error = meshlight::metrics::compare(&image, &image).unwrap();
        error.mae_over_mean = mae;
        Row {
            method: "meshless",
            settings: Vec::new(),
            spp: None,
            samples: 0,
            shots: 0,
            queries: 0,
            seconds: [0.0; 6],
            total,
            error,
            pareto: false,
        }
    }

    #[test]
    fn the_pareto_front_holds_the_runs_nothing_beats() {
        // (1 s, 5%) and (3 s, 1%) are beaten by nothing; (2 s, 6%) by the first; (4 s, 1%)
        // ties the second on error but is slower; (3 s, 1%) twice: neither beats the other.
        let mut rows = vec![
            row(1.0, 0.05),
            row(2.0, 0.06),
            row(3.0, 0.01),
            row(4.0, 0.01),
            row(3.0, 0.01),
        ];
        mark_pareto(&mut rows);
        let front: Vec<bool> = rows.iter().map(|r| r.pareto).collect();
        assert_eq!(front, [true, false, true, false, true]);
    }

    #[test]
    fn the_grid_is_every_combination_first_key_slowest() {
        let g = grid(&[
            ("a".into(), vec!["1".into(), "2".into()]),
            ("b".into(), vec!["x".into(), "y".into(), "z".into()]),
        ]);
        let flat: Vec<String> = g
            .iter()
            .map(|p| p.iter().map(|(_, v)| v.as_str()).collect::<String>())
            .collect();
        assert_eq!(flat, ["1x", "1y", "1z", "2x", "2y", "2z"]);
    }
}
