//! How a solve talks to its host while it runs: a report per step, and the host's answer.

/// The phases the solver reports progress in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Phase {
    /// Placing initial samples.
    Sampling,
    /// Computing representative areas.
    Areas,
    /// Integrating direct light at the samples.
    DirectLight,
    /// Building the cluster tree and linking clusters (hierarchy only).
    Links,
    /// Progressive shooting.
    Shooting,
    /// Adding samples where the error is large.
    Adaptive,
}

/// A progress report.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// Current phase.
    pub phase: Phase,
    /// Current round (0 = the first solve).
    pub round: u32,
    /// Samples now.
    pub samples: usize,
    /// Shots so far in this round's solve (sweeps, with the hierarchy).
    pub shots: u64,
    /// Unshot power / emitted power (shooting only).
    pub unshot_fraction: f64,
    /// The tolerance the shooting aims at.
    pub tolerance: f64,
    /// Share of the current phase done, in [0, 1], where it can be told (else 0): the basis of
    /// an estimated time to finish the phase.
    pub fraction: f64,
}

/// The host's answer to a progress report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Control {
    /// Go on.
    Continue,
    /// Stop at the next shot or round boundary; the current estimate is kept.
    Stop,
}
