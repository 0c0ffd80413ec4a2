//! How a long call talks to its host while it runs: one report type and one answer for every
//! entry point ([`solve`](crate::solve), [`render`](crate::render()),
//! [`lux::illuminance`](crate::lux::illuminance), [`path_trace`](crate::reference::path_trace)
//! and [`patch_radiosity`](crate::reference::patch_radiosity)).
//!
//! The host's callback hears every phase as it starts and its progress now and then (at least
//! about twenty times a phase, and at every shot while shooting), on the calling thread. It
//! answers [`Control::Continue`] or [`Control::Stop`]. A Stop is remembered: the phase running
//! ends at its next part boundary, later phases are skipped, and the call returns the estimate
//! it has (each entry point says what that is). Reports after a Stop still reach the host,
//! whatever it answers then.

use std::time::Instant;

/// What a long call is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Phase {
    /// Finding the sides light can reach, where samples will go (solve, in scenes with
    /// two-sided faces).
    Reach,
    /// Placing the initial samples (solve).
    Sampling,
    /// Computing representative areas (solve).
    Areas,
    /// Integrating direct light at the samples (solve) or the grid points (lux).
    DirectLight,
    /// Sending photons from the lights through mirrors and glass (solve).
    Photons,
    /// Probing hemispheres for the row sums, building the cluster tree and its links (solve).
    Links,
    /// Progressive shooting (solve, patches).
    Shooting,
    /// Adding samples where the error is large (solve).
    Adaptive,
    /// Tracing camera rays and shading them (render, patches).
    Rendering,
    /// Gathering inter-reflected light at grid points (lux).
    Gathering,
    /// Path tracing passes (path tracer).
    Tracing,
    /// Cutting the surfaces into patches (patches).
    Meshing,
    /// Shooting each sky patch's and sun position's light (a year of daylight).
    Coefficients,
    /// Summing the hours of a year of daylight.
    Hours,
}

impl Phase {
    /// A few words for a progress line.
    pub fn describe(self) -> &'static str {
        match self {
            Phase::Reach => "sides light reaches",
            Phase::Sampling => "placing samples",
            Phase::Areas => "representative areas",
            Phase::DirectLight => "direct light",
            Phase::Photons => "photons",
            Phase::Links => "links and row sums",
            Phase::Shooting => "shooting",
            Phase::Adaptive => "adding samples",
            Phase::Rendering => "rendering",
            Phase::Gathering => "gathering",
            Phase::Tracing => "path tracing",
            Phase::Meshing => "meshing",
            Phase::Coefficients => "daylight coefficients",
            Phase::Hours => "hours of the year",
        }
    }
}

/// A progress report. Fields that do not apply to a phase are 0.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct Progress {
    /// The current phase.
    pub phase: Phase,
    /// Share of the phase done, in [0, 1], where it can be told (else 0).
    pub fraction: f64,
    /// Seconds since the phase started.
    pub elapsed: f64,
    /// Estimated seconds the phase still needs, from the share done and the time taken so far
    /// (a hint: `None` until about 2% is done).
    pub remaining: Option<f64>,
    /// The solve's round (0 = the first solve; adaptive rounds count on).
    pub round: u32,
    /// What the phase works on: samples (solve), patches (patches), pixels (render), points
    /// (lux), samples per pixel wanted (path tracer).
    pub items: usize,
    /// Shots so far (sweeps, with the hierarchy), or samples per pixel done (path tracer).
    pub shots: u64,
    /// Unshot power / emitted power (shooting).
    pub unshot_fraction: f64,
    /// The unshot fraction the shooting aims at.
    pub tolerance: f64,
}

impl Progress {
    /// A report of `phase` with nothing else known yet.
    pub(crate) fn of(phase: Phase) -> Progress {
        Progress {
            phase,
            fraction: 0.0,
            elapsed: 0.0,
            remaining: None,
            round: 0,
            items: 0,
            shots: 0,
            unshot_fraction: 0.0,
            tolerance: 0.0,
        }
    }
}

/// The host's answer to a progress report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Control {
    /// Go on.
    Continue,
    /// End the call at the next part boundary and return the estimate so far.
    Stop,
}

/// The host's callback, as every entry point takes it.
pub type Callback<'a> = &'a mut dyn FnMut(&Progress) -> Control;

/// Wraps a host's callback: times each phase, adds the time hint, and remembers a Stop.
pub(crate) struct Reporter<'a> {
    callback: Callback<'a>,
    stopped: bool,
    /// The phase and round being timed, and when it started.
    current: Option<(Phase, u32, Instant)>,
}

impl<'a> Reporter<'a> {
    pub(crate) fn new(callback: Callback<'a>) -> Reporter<'a> {
        Reporter {
            callback,
            stopped: false,
            current: None,
        }
    }

    /// Tells the host; whether the call should stop (now or at any earlier report).
    pub(crate) fn report(&mut self, mut progress: Progress) -> bool {
        let now = Instant::now();
        let start = match self.current {
            Some((phase, round, start)) if phase == progress.phase && round == progress.round => {
                start
            }
            _ => {
                self.current = Some((progress.phase, progress.round, now));
                now
            }
        };
        let elapsed = now.duration_since(start).as_secs_f64();
        let f = progress.fraction;
        progress.elapsed = elapsed;
        progress.remaining = (f > 0.02 && f < 1.0).then(|| elapsed * (1.0 - f) / f);
        if (self.callback)(&progress) == Control::Stop {
            self.stopped = true;
        }
        self.stopped
    }

    /// Whether the host has asked to stop.
    pub(crate) fn stopped(&self) -> bool {
        self.stopped
    }

    /// A reporter for the parts of one phase: hears the share done, answers whether to go on.
    pub(crate) fn part<'r>(
        &'r mut self,
        base: Progress,
    ) -> impl FnMut(f64) -> Control + use<'r, 'a> {
        move |fraction| {
            // A share of 0 asks whether to begin: the host heard the phase begin already.
            if fraction <= 0.0 {
                return if self.stopped {
                    Control::Stop
                } else {
                    Control::Continue
                };
            }
            let stop = self.report(Progress { fraction, ..base });
            if stop {
                Control::Stop
            } else {
                Control::Continue
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stop_is_remembered_and_later_reports_still_reach_the_host() {
        let mut heard = Vec::new();
        let mut callback = |p: &Progress| {
            heard.push((p.phase, p.fraction));
            if p.phase == Phase::Areas {
                Control::Stop
            } else {
                Control::Continue
            }
        };
        let mut reporter = Reporter::new(&mut callback);
        assert!(!reporter.report(Progress::of(Phase::Sampling)));
        assert!(reporter.report(Progress::of(Phase::Areas)));
        // The host now says go on; the stop stands.
        assert!(reporter.report(Progress::of(Phase::DirectLight)));
        assert!(reporter.stopped());
        assert_eq!(heard.len(), 3);
    }

    #[test]
    fn the_time_hint_follows_the_share_done() {
        let mut last = None;
        let mut callback = |p: &Progress| {
            last = Some(*p);
            Control::Continue
        };
        let mut reporter = Reporter::new(&mut callback);
        reporter.report(Progress::of(Phase::Rendering));
        std::thread::sleep(std::time::Duration::from_millis(20));
        reporter.report(Progress {
            fraction: 0.25,
            ..Progress::of(Phase::Rendering)
        });
        let p = last.unwrap();
        // A quarter done in `elapsed`: three times that left.
        let hint = p.remaining.unwrap();
        assert!(p.elapsed >= 0.02, "{}", p.elapsed);
        assert!(
            (hint - 3.0 * p.elapsed).abs() < 1e-9,
            "{hint} vs {}",
            p.elapsed
        );
    }
}
