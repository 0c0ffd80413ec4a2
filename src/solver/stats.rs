//! What a solve reports about itself: why shooting stopped, where the energy went, and what
//! each round did and how long each phase took.

use glam::DVec3;

use crate::area::AreaStats;

/// Why a solve stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum StopReason {
    /// Unshot power fell below the tolerance.
    Converged,
    /// The shot limit was reached first.
    ShotLimit,
    /// The progress callback asked to stop.
    Stopped,
    /// The scene emits no light: nothing to shoot.
    NoLight,
    /// Unshot power grew instead of shrinking (it cannot with rows summing to at most 1 and
    /// reflectances below 1; this guards the image against infinities all the same).
    Diverged,
}

/// Where the light's energy went (W, RGB), kept as the solver runs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergyLedger {
    /// Power emitted by all lights.
    pub emitted: DVec3,
    /// Power that left the scene: direct light that hit no sample area, and the part of each
    /// shot its form factors did not deliver.
    pub escaped: DVec3,
}

/// What one solve's shooting did.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct ShootStats {
    /// Shots made. The flat solver shoots one sample at a time; the cluster hierarchy shoots
    /// every sample's unshot power at once along its links, and counts each such sweep as one.
    pub shots: u64,
    /// Visibility queries made (form factors, cluster links and row-sum probes excluded).
    pub queries: u64,
    /// Links between clusters or samples (the hierarchy only; 0 for the flat solver).
    pub links: u64,
    /// Of those, links between two single samples.
    pub leaf_links: u64,
    /// Links this process holds: all of them in one process, its receivers' share of them when
    /// the solve is spread over ranks ([`solve_distributed`](crate::solver::solve_distributed)).
    pub held_links: u64,
    /// The most links any one rank holds (`held_links` in one process).
    pub most_held_links: u64,
    /// Bytes this rank received from the others in the sweeps' exchanges (0 in one process).
    pub exchanged_bytes: u64,
    /// Unshot power / emitted power at the start.
    pub initial_unshot_fraction: f64,
    /// Unshot power / emitted power at the end.
    pub unshot_fraction: f64,
    /// Shots answered from the form-factor cache (flat solver).
    pub cached_shots: u64,
    /// Bytes the links (or the flat solver's cache and memo) held at their largest.
    pub bytes: u64,
    /// Why it stopped.
    pub stop: StopReason,
}

impl ShootStats {
    /// Stats of a solve that has not shot yet.
    pub(crate) fn new() -> ShootStats {
        ShootStats {
            shots: 0,
            queries: 0,
            links: 0,
            leaf_links: 0,
            held_links: 0,
            most_held_links: 0,
            exchanged_bytes: 0,
            initial_unshot_fraction: 0.0,
            unshot_fraction: 0.0,
            cached_shots: 0,
            bytes: 0,
            stop: StopReason::Converged,
        }
    }
}

/// Seconds spent per phase.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhaseSeconds {
    /// Sample placement (initial or adaptive).
    pub sampling: f64,
    /// Representative areas.
    pub areas: f64,
    /// Direct light.
    pub direct: f64,
    /// Building the cluster tree and its links, and the row sums (hierarchy only).
    pub links: f64,
    /// Shooting (with the flat solver: its form factors and row sums too).
    pub shooting: f64,
}

/// What one round did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoundStats {
    /// Round number (0 = the first solve).
    pub round: u32,
    /// Samples after this round's additions.
    pub samples: usize,
    /// Samples added this round (all of them in round 0).
    pub added: usize,
    /// Samples whose error exceeded ζ (rounds ≥ 1).
    pub refined: usize,
    /// Whether `max_samples` (or half the memory budget) stopped the addition.
    pub capped: bool,
    /// Bytes the solution held while shooting (samples, index, results); the links and
    /// caches are in [`ShootStats::bytes`].
    pub solution_bytes: u64,
    /// Shadow-ray queries for direct light.
    pub direct_queries: u64,
    /// Area cells used.
    pub areas: AreaStats,
    /// The shooting.
    pub shooting: ShootStats,
    /// Time per phase.
    pub seconds: PhaseSeconds,
}
