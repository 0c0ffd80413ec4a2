//! The progress line on stderr while the library works: the phase, the share done and the time
//! it still needs, for every long call through the library's one progress contract.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use meshlight::progress::{Control, Phase, Progress};
use meshlight::solver::{EpsilonSource, Options};
use meshlight::{Scene, Solution, Visibility};

/// Whether `--quiet` silenced the progress lines.
static QUIET: AtomicBool = AtomicBool::new(false);

/// Seconds between the plain progress lines written where stderr is not a terminal.
const PLAIN_EVERY: f64 = 5.0;

/// Silences (or not) every progress line from now on (`--quiet`).
pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
}

/// Whether `--quiet` silenced the progress lines.
pub fn quiet() -> bool {
    QUIET.load(Ordering::Relaxed)
}

/// Runs `call` with a progress line on stderr about `what` ("solve" gives rounds and samples),
/// cleared when it returns. Where stderr is not a terminal (a log file, a batch job) a bar
/// would show nothing: a plain line is written instead at the first report and then every
/// [`PLAIN_EVERY`] seconds. `--quiet` writes neither.
pub fn with_progress<T>(
    what: &str,
    call: impl FnOnce(&mut dyn FnMut(&Progress) -> Control) -> T,
) -> T {
    if QUIET.load(Ordering::Relaxed) {
        return call(&mut |p: &Progress| {
            crate::ranks::injected_failure(p);
            Control::Continue
        });
    }
    if !std::io::stderr().is_terminal() {
        let start = Instant::now();
        let mut next = 0.0;
        return call(&mut |p: &Progress| {
            crate::ranks::injected_failure(p);
            let t = start.elapsed().as_secs_f64();
            if t >= next {
                eprintln!("meshlight: {t:>5.0} s: {}", line(what, p));
                next = t + PLAIN_EVERY;
            }
            Control::Continue
        });
    }
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} {elapsed:>4} {msg}").expect("valid template"),
    );
    bar.enable_steady_tick(Duration::from_millis(200));
    let result = call(&mut |p: &Progress| {
        crate::ranks::injected_failure(p);
        bar.set_message(line(what, p));
        Control::Continue
    });
    bar.finish_and_clear();
    result
}

/// Solves with a progress line, saying first where an automatic ε came from.
pub fn solve_with_progress(
    scene: &Scene,
    vis: &dyn Visibility,
    options: &Options,
) -> anyhow::Result<Solution> {
    // Which sides light reaches, cast once for the ε and the message (the solve casts its own).
    let all = meshlight::solver::reflecting_sides(scene);
    let lit = meshlight::solver::lit_sides(scene, vis)?;
    let (epsilon, source) = meshlight::solver::choose_epsilon_for(scene, vis, &lit, options)?;
    if source == EpsilonSource::Automatic {
        eprintln!(
            "meshlight: no epsilon given: chose ε = {epsilon:.4} from the reflecting area light reaches (about {} initial samples{})",
            meshlight::solver::AUTO_SAMPLES,
            if options.epsilon_scale == 1.0 {
                String::new()
            } else {
                format!(
                    "; scaled by {} (--epsilon-scale or the preset)",
                    options.epsilon_scale
                )
            }
        );
    }
    if source == EpsilonSource::LightLength {
        if let Some(l) = meshlight::solver::light_length(scene, vis, &lit)? {
            let lamps = match l.lamp_clearance {
                Some(h) if l.length < l.free_path && options.rounds == 0 => {
                    format!(", shortened by a lamp {h:.3} from a surface")
                }
                _ => String::new(),
            };
            eprintln!(
                "meshlight: ε = {epsilon:.4}: {} of the length over which the scene's light changes, {:.3} (its mean free path {:.3}{lamps}); a scene file's ε is for the default preset",
                options.epsilon_fraction.unwrap_or(0.0) * options.epsilon_scale,
                l.for_rounds(options.rounds),
                l.free_path,
            );
        }
    }
    if lit.len() < all.len() {
        let (lit_area, area) = (
            meshlight::solver::area_of(scene, &lit),
            meshlight::solver::area_of(scene, &all),
        );
        eprintln!(
            "meshlight: {} of {} reflecting sides ({:.0}% of their area) get no samples: no light \
             reaches them (the outsides and insides of two-sided objects); they render black",
            all.len() - lit.len(),
            all.len(),
            100.0 * (1.0 - lit_area / area)
        );
    }
    let solution = with_progress("solve", |progress| {
        meshlight::solver::solve_distributed(scene, vis, options, crate::ranks::ranks(), progress)
    })?;
    if let Some(finding) = meshlight::diagnose::samples(scene, &solution) {
        eprintln!("meshlight: note: {}", finding.message);
    }
    Ok(solution)
}

/// One progress line: what is being done, how far, and the time left.
fn line(what: &str, p: &Progress) -> String {
    let done = if p.fraction > 0.0 {
        format!(", {:.0}%", 100.0 * p.fraction)
    } else {
        String::new()
    };
    let left = p
        .remaining
        .map_or(String::new(), |s| format!(", about {:.0} s left", s.ceil()));
    let phase = p.phase.describe();
    let detail = match p.phase {
        Phase::Shooting => format!(
            ", {} shots, unshot {:.2e} of emitted (target {:.0e})",
            p.shots, p.unshot_fraction, p.tolerance
        ),
        Phase::Tracing => format!(", {} of {} samples per pixel", p.shots, p.items),
        _ => String::new(),
    };
    if what == "solve" {
        // Before the first samples are placed (the probes for the sides light reaches, the
        // first placing) there are none to count.
        let samples = if p.items > 0 {
            format!(": {} samples", p.items)
        } else {
            String::new()
        };
        format!("round {}: {phase}{samples}{detail}{done}{left}", p.round)
    } else {
        format!("{what}: {phase}{detail}{done}{left}")
    }
}
