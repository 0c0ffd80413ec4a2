//! What the two shooting solvers (flat and clustered) share: the solver state they change,
//! their settings, and how they report progress.

use glam::DVec3;

use super::stats::EnergyLedger;
use crate::progress::Phase;
use crate::sampling::{Samples, SurfaceMap};

/// The solver state that shooting changes.
pub(crate) struct State<'a> {
    pub samples: &'a Samples,
    pub maps: &'a [SurfaceMap],
    pub reflectance: &'a [DVec3],
    /// Radiosity of each sample when shooting starts: what the hierarchy's error bound
    /// weighs each shooter by.
    pub radiosity: &'a [DVec3],
    /// Irradiance received at each sample (direct + shot so far).
    pub irradiance: &'a mut [DVec3],
    /// Unshot radiosity ΔB.
    pub unshot: &'a mut [DVec3],
    pub ledger: &'a mut EnergyLedger,
    /// Per receiver, the factor its form factors are scaled by (see `normalise`); filled by the
    /// solver when `Settings::normalise` is set.
    pub row_scale: &'a mut [f32],
    /// Per receiver, whether every probe ray from it hit the scene.
    pub closed: &'a [bool],
    /// Per receiver, the form factor to emitters that do not reflect (see `normalise`).
    pub dark_emitters: &'a [f64],
    /// Light by way of specular surfaces, shot beside the links.
    pub specular: Option<&'a super::specular::Transfer>,
    /// A round's new samples, whose inter-reflected light is gathered before shooting.
    pub regather: Option<super::warm::Regather<'a>>,
}

/// Settings of one solve.
pub(crate) struct Settings<'a> {
    /// Threads, the seed of the hierarchy's visibility rays, and the processes this solve is
    /// spread over ([`Single`](crate::distributed::Single) alone).
    pub exec: crate::exec::Exec<'a>,
    /// Jobs in flight in the pipeline at most.
    pub capacity: usize,
    pub tolerance: f64,
    pub max_shots: u64,
    pub lift: f32,
    /// Bytes the solver's large structures (caches, links) may hold.
    pub memory_bytes: usize,
    /// The whole memory budget (for messages).
    pub budget: usize,
    /// Compute the receivers' row sums and scales (see `normalise`) before shooting.
    pub normalise: bool,
    /// The hierarchy's error threshold (0: the flat solver).
    pub threshold: f64,
    /// Refine every partly visible link of the hierarchy, however faint.
    pub exact_visibility: bool,
}

/// What a shooting solver tells the solve between steps.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tick {
    /// [`Phase::Links`] or [`Phase::Shooting`].
    pub phase: Phase,
    pub shots: u64,
    pub unshot_fraction: f64,
    /// Share of the phase done, where known.
    pub fraction: f64,
}

impl Tick {
    /// Building links (or the flat solver's row sums), `fraction` of the way.
    pub fn linking(fraction: f64) -> Tick {
        Tick {
            phase: Phase::Links,
            shots: 0,
            unshot_fraction: 1.0,
            fraction,
        }
    }

    /// Shooting, after `shots` shots with `unshot_fraction` of the emitted power left, from
    /// `initial` at the start towards `tolerance`: the share done is the share of the way on a
    /// log scale (unshot power falls about geometrically).
    pub fn shooting(shots: u64, unshot_fraction: f64, initial: f64, tolerance: f64) -> Tick {
        let way = (initial / tolerance).ln();
        let fraction = if way > 0.0 && unshot_fraction > 0.0 {
            ((initial / unshot_fraction).ln() / way).clamp(0.0, 1.0)
        } else {
            0.0
        };
        Tick {
            phase: Phase::Shooting,
            shots,
            unshot_fraction,
            fraction,
        }
    }
}

/// Unshot power of sample k (all channels, absolute: warm starts may leave negative unshot).
pub(crate) fn unshot_power(unshot: DVec3, area: f64) -> f64 {
    unshot.abs().element_sum() * area
}

/// The stats of a solve with nothing to shoot (no light, or no samples), if so.
pub(crate) fn nothing_to_shoot(state: &State) -> Option<super::stats::ShootStats> {
    let emitted = state.ledger.emitted.element_sum();
    (emitted <= 0.0 || state.samples.is_empty()).then(|| {
        let mut stats = super::stats::ShootStats::new();
        stats.stop = super::stats::StopReason::NoLight;
        stats
    })
}
