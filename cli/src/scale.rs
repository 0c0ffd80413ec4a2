//! `meshlight scale`: how time, visibility queries and memory grow with the number of samples,
//! for the cluster hierarchy and the flat solver side by side.

use std::fmt::Write as _;
use std::time::Instant;

use meshlight::solver::{Control, Options, Solution};
use meshlight::{Scene, Visibility};

use super::memory;

/// One measured solve.
struct Run {
    flat: bool,
    epsilon: f32,
    samples: usize,
    links: u64,
    queries: u64,
    /// Place, areas, direct, links, shooting, and the whole solve.
    seconds: [f64; 6],
    peak: Option<u64>,
    /// What the solution holds at the end, by part.
    held: meshlight::budget::Breakdown,
    /// The links, tree and caches of the largest round.
    links_bytes: u64,
}

/// Solves the scene at every ε with the hierarchy (and the flat solver while it is predicted
/// to fit in `flat_limit` seconds), printing a row per solve as it ends, then the exponents.
pub fn run(
    scene: &Scene,
    vis: &dyn Visibility,
    options: &Options,
    epsilons: &[f32],
    flat_limit: f64,
) -> anyhow::Result<()> {
    // The hierarchy's runs at the options' threshold, or the default's if they ask for flat.
    let threshold = if options.flat() {
        Options::default().cluster_threshold
    } else {
        options.cluster_threshold
    };
    println!(
        "scene {}: {} triangles; {} thread(s), {} rounds, backend {}; hierarchy threshold {threshold}",
        scene.path().display(),
        scene.triangles().len(),
        options.threads,
        options.rounds,
        vis.name()
    );
    println!(
        "{:<6} {:>8} {:>9} {:>11} {:>13} {:>8} {:>8} {:>8} {:>8} {:>8} {:>9} {:>10}",
        "solver",
        "epsilon",
        "samples",
        "links",
        "vis queries",
        "place s",
        "areas s",
        "direct s",
        "links s",
        "shoot s",
        "solve s",
        "peak mem"
    );
    let mut runs: Vec<Run> = Vec::new();
    let mut last_flat: Option<(usize, f64)> = None;
    // The hierarchy's solves first, then the flat solver's, each from the largest ε: memory a
    // solve freed may stay with the process, and only a larger solve after it measures its own
    // peak.
    let solvers: &[bool] = if flat_limit > 0.0 {
        &[false, true]
    } else {
        &[false]
    };
    for &flat in solvers {
        for (i, &epsilon) in epsilons.iter().enumerate() {
            if flat {
                // The hierarchy's solve at this ε says how many samples the flat one will have.
                let predicted = last_flat.map(|(n, t)| {
                    let n_now = runs.get(i).map_or(n, |r| r.samples) as f64;
                    t * (n_now / n as f64).powi(2)
                });
                if predicted.is_some_and(|t| t > flat_limit) {
                    println!(
                        "{:<6} {:>8} skipped: predicted {:.0} s, over the limit of {flat_limit:.0} s",
                        "flat",
                        epsilon,
                        predicted.unwrap_or(0.0)
                    );
                    continue;
                }
            }
            let options = Options {
                epsilon: Some(epsilon),
                cluster_threshold: if flat { 0.0 } else { threshold },
                ..options.clone()
            };
            let reset = memory::reset_peak();
            let start = Instant::now();
            let solution = meshlight::solve(scene, vis, &options, &mut |_| Control::Continue)?;
            let total = start.elapsed().as_secs_f64();
            let run = measure(
                flat,
                epsilon,
                &solution,
                total,
                reset.then(memory::peak_bytes).flatten(),
            );
            println!("{}", row(&run));
            println!("{}", per_sample(&run));
            if flat {
                last_flat = Some((run.samples, total));
            }
            runs.push(run);
        }
    }
    print!("{}", exponents(&runs));
    Ok(())
}

fn measure(flat: bool, epsilon: f32, s: &Solution, total: f64, peak: Option<u64>) -> Run {
    let mut seconds = [0.0; 6];
    for r in s.rounds() {
        let p = &r.seconds;
        for (x, y) in seconds
            .iter_mut()
            .zip([p.sampling, p.areas, p.direct, p.links, p.shooting])
        {
            *x += y;
        }
    }
    seconds[5] = total;
    Run {
        flat,
        epsilon,
        samples: s.samples().len(),
        links: s.rounds().iter().map(|r| r.shooting.links).sum(),
        queries: s.rounds().iter().map(|r| r.shooting.queries).sum(),
        seconds,
        peak,
        held: s.memory(),
        links_bytes: s
            .rounds()
            .iter()
            .map(|r| r.shooting.bytes)
            .max()
            .unwrap_or(0),
    }
}

/// Where the memory goes, per sample: what the solution holds by part, the links of its largest
/// round, and the process's peak.
fn per_sample(r: &Run) -> String {
    let n = r.samples.max(1) as f64;
    let h = &r.held;
    let mut s = String::from("       bytes per sample:");
    for (name, bytes) in [
        ("samples", h.samples),
        ("cells", h.cells),
        ("shares", h.shares),
        ("index", h.index),
        ("results", h.results),
        ("specular", h.specular),
        ("maps", h.maps),
        ("links+tree", r.links_bytes as usize),
    ] {
        let _ = write!(s, " {name} {:.0},", bytes as f64 / n);
    }
    let _ = write!(
        s,
        " held {:.0}; peak {}",
        (h.total() as f64 + r.links_bytes as f64) / n,
        r.peak
            .map_or("-".into(), |b| format!("{:.0}", b as f64 / n))
    );
    s
}

fn row(r: &Run) -> String {
    let mut s = format!(
        "{:<6} {:>8} {:>9} {:>11} {:>13}",
        if r.flat { "flat" } else { "hier" },
        r.epsilon,
        r.samples,
        r.links,
        r.queries
    );
    for t in &r.seconds {
        let _ = write!(s, " {t:>8.2}");
    }
    let _ = write!(
        s,
        " {:>10}",
        r.peak.map_or("-".into(), |b| crate::units::bytes(b as f64))
    );
    s
}

/// Least-squares slope of ln y against ln x.
fn slope(points: &[(f64, f64)]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

fn exponents(runs: &[Run]) -> String {
    let mut out = String::from("fitted exponents against samples N (least squares on logs):\n");
    for flat in [false, true] {
        let of = |f: &dyn Fn(&Run) -> f64| -> Vec<(f64, f64)> {
            runs.iter()
                .filter(|r| r.flat == flat)
                .map(|r| (r.samples as f64, f(r)))
                .collect()
        };
        if !runs.iter().any(|r| r.flat == flat) {
            continue;
        }
        let show = |x: Option<f64>| x.map_or("-".to_string(), |e| format!("N^{e:.2}"));
        let _ = writeln!(
            out,
            "  {:<10} time {}, queries {}",
            if flat { "flat" } else { "hierarchy" },
            show(slope(&of(&|r| r.seconds[5]))),
            show(slope(&of(&|r| r.queries as f64)))
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::slope;

    #[test]
    fn slope_of_a_power_law() {
        let pts: Vec<(f64, f64)> = [1e3, 4e3, 1.6e4]
            .iter()
            .map(|&n: &f64| (n, 3.0 * n.powf(1.5)))
            .collect();
        assert!((slope(&pts).unwrap() - 1.5).abs() < 1e-9);
        assert_eq!(slope(&pts[..1]), None);
    }
}
