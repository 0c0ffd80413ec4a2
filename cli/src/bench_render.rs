//! The render's cost as `meshlight bench-render` reports it: one solve, then the same image
//! rendered at each thread count in turn (alternating, so a noisy machine's drift falls on
//! every count alike), its time per pixel, and the time the backend takes for the same number
//! of rays cast on their own, so the render's cost reads against the rays it casts.

use std::fmt::Write as _;
use std::time::Instant;

use crate::bench::parallel;
use crate::workload::{camera_rays, facing_segments};
use meshlight::render::RenderStats;
use meshlight::visibility::Visibility;
use meshlight::{Control, Image, RenderOptions, Result, Scene, Solution};

/// Queries per call when the rays are cast on their own (the solver's batch size).
const BATCH: usize = 1024;

/// One thread count's renders.
#[derive(Clone, Debug)]
pub struct ThreadRuns {
    /// Threads the render used.
    pub threads: usize,
    /// Each render's own time, seconds, in the order run.
    pub seconds: Vec<f64>,
    /// The rays the render cast, cast on their own at this thread count (camera rays as
    /// closest-hit queries, the rest as occlusion queries): the best of as many runs as the
    /// renders, seconds.
    pub rays_alone: f64,
}

impl ThreadRuns {
    /// The median render time, seconds.
    pub fn median(&self) -> f64 {
        median(&self.seconds)
    }

    /// The shortest render time, seconds: the run least disturbed by the rest of the machine.
    pub fn best(&self) -> f64 {
        self.seconds.iter().copied().fold(f64::INFINITY, f64::min)
    }
}

/// Everything `bench-render` prints.
#[derive(Clone, Debug)]
pub struct RenderBench {
    /// Image width and height.
    pub size: (u32, u32),
    /// Samples in the solution rendered.
    pub samples: usize,
    /// What one render cast (every render casts the same).
    pub stats: RenderStats,
    /// Per thread count, in the order given.
    pub runs: Vec<ThreadRuns>,
    /// Whether every render gave the same image, bit for bit.
    pub same_image: bool,
}

/// Renders `solution` `repeats` times at each of `threads` (in turn: 1, 2, 1, 2, …) and casts
/// the render's rays on their own at each; `progress` hears what is being measured.
pub fn run(
    scene: &Scene,
    solution: &Solution,
    vis: &dyn Visibility,
    options: &RenderOptions,
    (threads, repeats): (&[usize], usize),
    progress: &mut dyn FnMut(&str),
) -> Result<RenderBench> {
    let repeats = repeats.max(1);
    let mut runs: Vec<ThreadRuns> = threads
        .iter()
        .map(|&t| ThreadRuns {
            threads: t.max(1),
            seconds: Vec::new(),
            rays_alone: f64::INFINITY,
        })
        .collect();
    let mut first: Option<(Image, RenderStats)> = None;
    let mut same_image = true;
    for round in 0..repeats {
        for run in &mut runs {
            progress(&format!(
                "render {} of {repeats}, {} thread(s)",
                round + 1,
                run.threads
            ));
            let o = RenderOptions {
                threads: run.threads,
                ..*options
            };
            let t = Instant::now();
            let (image, stats) =
                meshlight::render(scene, solution, vis, &o, &mut |_| Control::Continue)?;
            run.seconds.push(t.elapsed().as_secs_f64());
            match &first {
                None => first = Some((image, stats)),
                Some((i, _)) => same_image &= i.pixels == image.pixels,
            }
        }
    }
    let (_, stats) = first.expect("at least one thread count and one repeat");

    // The render's rays on their own: its camera rays as closest-hit queries, its shadow rays
    // and interpolation queries as occlusion queries between facing surface points.
    progress("generating the rays alone");
    let rays = camera_rays(scene, stats.camera_rays as usize, 1);
    let segments = facing_segments(
        scene,
        (stats.shadow_rays + stats.interpolation_queries) as usize,
        2,
    );
    let mut hits = vec![None; rays.len()];
    let mut blocked = vec![false; segments.len()];
    progress(&format!(
        "the rays alone, {repeats} time(s) at each thread count"
    ));
    for _ in 0..repeats {
        for run in &mut runs {
            let t = Instant::now();
            parallel(&rays, &mut hits, run.threads, BATCH, |r, o| {
                vis.intersect(r, o)
            })?;
            parallel(&segments, &mut blocked, run.threads, BATCH, |s, o| {
                vis.occluded(s, o)
            })?;
            run.rays_alone = run.rays_alone.min(t.elapsed().as_secs_f64());
        }
    }
    let camera = scene.camera();
    Ok(RenderBench {
        size: (camera.width, camera.height),
        samples: solution.samples().len(),
        stats,
        runs,
        same_image,
    })
}

fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// The report `bench-render` prints.
pub fn report(scene: &Scene, backend: &str, b: &RenderBench) -> String {
    let mut s = String::new();
    let pixels = f64::from(b.size.0) * f64::from(b.size.1);
    let per = |n: u64| n as f64 / pixels;
    let st = &b.stats;
    let _ = writeln!(
        s,
        "scene {}: {} x {} ({} pixels), {} samples; backend {backend}",
        scene.path().display(),
        b.size.0,
        b.size.1,
        pixels,
        b.samples
    );
    let _ = writeln!(
        s,
        "each render: {} camera rays ({:.2} a pixel; {} edge pixels supersampled), {} shadow rays \
         ({:.2} a pixel), {} interpolation queries ({:.2} a pixel)",
        st.camera_rays,
        per(st.camera_rays),
        st.supersampled_pixels,
        st.shadow_rays,
        per(st.shadow_rays),
        st.interpolation_queries,
        per(st.interpolation_queries)
    );
    let _ = writeln!(
        s,
        "\n{:>7} {:>10} {:>8} {:>11} {:>13} {:>12}  renders (s, in order)",
        "threads", "median s", "best s", "ns a pixel", "rays alone s", "render/rays"
    );
    for r in &b.runs {
        let m = r.median();
        let each: Vec<String> = r.seconds.iter().map(|t| format!("{t:.3}")).collect();
        let _ = writeln!(
            s,
            "{:>7} {:>10.4} {:>8.4} {:>11.0} {:>13.4} {:>12.1}  {}",
            r.threads,
            m,
            r.best(),
            m * 1e9 / pixels,
            r.rays_alone,
            m / r.rays_alone,
            each.join(" ")
        );
    }
    if let (Some(one), Some(two)) = (
        b.runs.iter().find(|r| r.threads == 1),
        b.runs.iter().find(|r| r.threads == 2),
    ) {
        let _ = writeln!(
            s,
            "\n1 -> 2 threads: the render {:.2}x sooner (medians), {:.2}x (best runs); the rays \
             alone {:.2}x (best runs)",
            one.median() / two.median(),
            one.best() / two.best(),
            one.rays_alone / two.rays_alone
        );
    }
    let _ = writeln!(
        s,
        "every render's image the same bit for bit: {}",
        if b.same_image { "yes" } else { "NO" }
    );
    s
}

#[cfg(test)]
mod tests {
    use super::median;

    #[test]
    fn the_median_is_the_middle_run_or_the_mean_of_the_two_middle_ones() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert!(median(&[]).is_nan());
    }
}
