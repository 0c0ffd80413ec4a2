//! The progress line on stderr while a solve runs: the phase, the share done and the time it
//! still needs.

use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};
use meshlight::solver::{Control, EpsilonSource, Options, Phase, Progress};
use meshlight::{Scene, Solution, Visibility};

/// Solves with a progress line on stderr: the phase, how far it has got, and an estimate of
/// the time it still needs.
pub fn solve_with_progress(
    scene: &Scene,
    vis: &dyn Visibility,
    options: &Options,
) -> anyhow::Result<Solution> {
    let (epsilon, source) = meshlight::solver::choose_epsilon(scene, options)?;
    if source == EpsilonSource::Automatic {
        eprintln!(
            "meshlight: no epsilon given: chose ε = {epsilon:.4} from the reflecting area (about {} initial samples)",
            meshlight::solver::AUTO_SAMPLES
        );
    }
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} {elapsed:>4} {msg}").expect("valid template"),
    );
    bar.enable_steady_tick(Duration::from_millis(200));
    let mut phase = Eta::default();
    let solution = meshlight::solve(scene, vis, options, &mut |p: &Progress| {
        bar.set_message(progress_line(p, phase.update(p)));
        Control::Continue
    });
    bar.finish_and_clear();
    Ok(solution?)
}

/// Time left in the current phase, from how long it has run and the share done.
#[derive(Default)]
struct Eta {
    current: Option<(Phase, u32, std::time::Instant)>,
}

impl Eta {
    fn update(&mut self, p: &Progress) -> Option<Duration> {
        let now = std::time::Instant::now();
        match self.current {
            Some((phase, round, _)) if phase == p.phase && round == p.round => {}
            _ => self.current = Some((p.phase, p.round, now)),
        }
        let (_, _, start) = self.current?;
        let f = p.fraction;
        (f > 0.02 && f < 1.0)
            .then(|| Duration::from_secs_f64(start.elapsed().as_secs_f64() * (1.0 - f) / f))
    }
}

fn progress_line(p: &Progress, eta: Option<Duration>) -> String {
    let phase = match p.phase {
        Phase::Sampling => "placing samples",
        Phase::Areas => "representative areas",
        Phase::DirectLight => "direct light",
        Phase::Links => "links and row sums",
        Phase::Shooting => "shooting",
        Phase::Adaptive => "adding samples",
        _ => "working",
    };
    let done = if p.fraction > 0.0 {
        format!(", {:.0}%", 100.0 * p.fraction)
    } else {
        String::new()
    };
    let left = eta.map_or(String::new(), |d| {
        format!(", about {:.0} s left", d.as_secs_f64().ceil())
    });
    if p.phase == Phase::Shooting {
        format!(
            "round {}: {phase}: {} samples, {} shots, unshot {:.2e} of emitted (target {:.0e}){done}{left}",
            p.round, p.samples, p.shots, p.unshot_fraction, p.tolerance
        )
    } else {
        format!(
            "round {}: {phase}: {} samples{done}{left}",
            p.round, p.samples
        )
    }
}
