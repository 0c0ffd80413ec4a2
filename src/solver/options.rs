//! Every knob of the solver in one documented struct, with named presets.

use crate::budget::DEFAULT_MEMORY_BUDGET;

/// Solver settings. Each field says what it does, its useful range, and its effect on error and
/// time; the measurements are in `docs/performance.md`.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// ε, the Poisson-disk spacing of the initial samples (scene units). `None`: the scene
    /// file's `[solver] epsilon`, else chosen from the reflecting area so that about
    /// [`AUTO_SAMPLES`] initial samples result. Halving ε quadruples the samples and multiplies
    /// the flat solver's time by about 16. At most
    /// [`MAX_EPSILON_DIAGONALS`](crate::solver::MAX_EPSILON_DIAGONALS) times the scene's
    /// diagonal (an error beyond).
    pub epsilon: Option<f32>,
    /// Multiplies the ε taken from the scene file or chosen automatically (not one set in
    /// [`Options::epsilon`]), 1/16 to 16: presets use it to trade samples for time whatever
    /// scale the scene was modelled at. Default 1.
    pub epsilon_scale: f32,
    /// α, the fall-off of the area weights w(d) = exp(−α d) (eq. 5), useful 0–16: 0 splits a
    /// cell evenly among all samples within 2ε; large α gives each cell to its nearest sample.
    pub alpha: f32,
    /// ζ, the adaptive error threshold (eq. 7), relative to the mean radiosity: useful
    /// 0.01–0.5. Smaller adds more samples where light changes.
    pub zeta: f32,
    /// Adaptive rounds after the first solve (0 = none), useful 0–4; each adds samples where
    /// the error exceeds ζ and solves again from the previous solution.
    pub rounds: u32,
    /// Shadow rays per area light and sample, useful 4–256: more gives smoother penumbrae at
    /// proportional direct-light cost; at most [`crate::MAX_LIGHT_SAMPLES`]. Unused
    /// without area lights.
    pub light_samples: u32,
    /// Shooting stops when the unshot power falls below this fraction of the emitted power,
    /// useful 1e-5–1e-2.
    pub tolerance: f64,
    /// At most this many shots per solve (`None`: 200 per sample); a solve that reaches it
    /// says so.
    pub max_shots: Option<u64>,
    /// The solver refuses an ε that would place more samples than this, and adaptive rounds
    /// stop adding samples at it.
    pub max_samples: usize,
    /// The cluster hierarchy's error threshold τ, relative to the mean radiosity: a link between
    /// two clusters is accepted when the radiosity error it can make at its receiver is below
    /// τ × the mean radiosity; otherwise the larger cluster is split, down to single samples.
    /// Useful 0.01–1: larger is faster and coarser. 0 selects the flat solver (every sample
    /// linked to every sample, O(N²)), the reference the hierarchy is measured against.
    pub cluster_threshold: f64,
    /// Refine every partly visible link of the hierarchy down to single samples. By default a
    /// partly visible link whose whole transfer is below a quarter of the error threshold
    /// carries the visible share its probes measured (no wall is ever crossed: clusters never
    /// straddle an occluder). Exact visibility sharpens faint penumbrae at a cost that grows
    /// faster than the samples: on the shipped gallery 3.95 s instead of 3.26 s for about the
    /// same error against the flat solve (MAE/mean 0.21% and 0.20%); at 179k samples 97.6 M
    /// links and 2.57 GB instead of 5.1 M and 0.71 GB (`docs/performance.md`).
    pub exact_visibility: bool,
    /// The memory budget, bytes: every large structure counts against it. The samples and
    /// their results are predicted before they are placed ([`BYTES_PER_SAMPLE`](crate::budget::BYTES_PER_SAMPLE) each) and a
    /// solve that would not fit is refused before allocating; adaptive rounds stop adding
    /// samples at half of it; the rest is for the hierarchy's links (a solve whose links
    /// outgrow it ends with an error) or the flat solver's visibility memo (N²/8 bytes, left
    /// out if it does not fit in half the rest) and its kept form factors (as many as fit).
    /// Within the budget, results do not depend on it, only time.
    pub memory_budget: usize,
    /// How many specular bounces light may take between diffuse surfaces, 0 to
    /// [`MAX_SPECULAR_DEPTH`](crate::solver::MAX_SPECULAR_DEPTH): mirror images of lights
    /// across up to this many mirrors, panes and glass faces, and chains through mirrors,
    /// glossy surfaces and glass up to this long, in the solve, the image and the grids. 0
    /// treats every specular surface as black (its Kd still reflects). Unused in scenes
    /// without specular materials. Each bounce more costs the rays of one more link in every
    /// chain; what it adds falls as the product of the surfaces' reflectances.
    pub specular_depth: u32,
    /// Chains followed from each sample through specular surfaces, 1 to [`MAX_SPECULAR_RAYS`]:
    /// the rays of a final gather over the part of its hemisphere that is specular. More gives
    /// less noise in the light that arrives by way of mirrors, glossy surfaces and glass, at
    /// proportional cost. Unused in scenes without specular materials.
    pub specular_rays: u32,
    /// Photons sent from the lights towards mirrors and glass, 1 to [`MAX_PHOTONS`], where the
    /// mirror images do not carry all their light: curved mirrors, refracting solids (a glass
    /// ball, a block), chains of flat mirrors beyond the images listed. Where they land is
    /// spread over the samples' areas: the light focused onto diffuse surfaces (caustics).
    /// More gives less noise in that light, at proportional cost; unused where the images carry
    /// it all (flat mirrors and panes in rooms with few of them).
    pub photons: u64,
    /// Worker threads (≥ 1). Results do not depend on it.
    pub threads: usize,
    /// Jobs in flight in the solver's pipeline at most (≥ 1): bounds the memory the pipeline
    /// holds. Results do not depend on it.
    pub pipeline_capacity: usize,
    /// Seed of every random choice (sample placement, shadow rays).
    pub seed: u64,
}

/// Initial sample count the automatic ε aims at.
pub const AUTO_SAMPLES: f64 = 4000.0;

/// The most chains per sample [`Options::specular_rays`] may ask for.
pub const MAX_SPECULAR_RAYS: u32 = 4096;

/// The most photons [`Options::photons`] may ask for.
pub const MAX_PHOTONS: u64 = 1 << 30;

/// The default [`Options::specular_depth`].
pub const DEFAULT_SPECULAR_DEPTH: u32 = 32;

/// The default [`Options::cluster_threshold`].
pub const DEFAULT_CLUSTER_THRESHOLD: f64 = 0.05;

impl Default for Options {
    fn default() -> Self {
        Options {
            epsilon: None,
            epsilon_scale: 1.0,
            alpha: 8.0,
            zeta: 0.2,
            rounds: 2,
            light_samples: 16,
            tolerance: 1e-3,
            max_shots: None,
            max_samples: 2_000_000,
            cluster_threshold: DEFAULT_CLUSTER_THRESHOLD,
            exact_visibility: false,
            memory_budget: DEFAULT_MEMORY_BUDGET,
            specular_depth: DEFAULT_SPECULAR_DEPTH,
            specular_rays: 64,
            photons: 1_000_000,
            threads: std::thread::available_parallelism()
                .map_or(2, |n| n.get())
                .min(8),
            pipeline_capacity: 16,
            seed: 1,
        }
    }
}

impl Options {
    /// Checks every knob's value ([`KNOBS`](crate::solver::KNOBS)): the first out of its range,
    /// as [`Error::Option`](crate::Error::Option) naming it. [`solve`](crate::solve) checks
    /// them too, before it starts.
    pub fn validate(&self) -> crate::Result<()> {
        super::knobs::KNOBS.iter().try_for_each(|k| k.check(self))
    }

    /// Sets the knob `name` (a field's name, or spelt with hyphens as on the command line) from
    /// its text form, and checks its value.
    pub fn set(&mut self, name: &str, text: &str) -> crate::Result<()> {
        match super::knobs::knob(name) {
            Some(k) => k.set(self, text),
            None => Err(crate::Error::argument(
                "knob",
                format!("unknown '{name}' (see meshlight::solver::KNOBS)"),
            )),
        }
    }

    /// Whether these options select the flat solver (every sample linked to every sample):
    /// a cluster threshold of 0. The one place that says what the threshold selects.
    pub fn flat(&self) -> bool {
        self.cluster_threshold == 0.0
    }

    /// Fast and rough: no adaptive rounds, few shadow rays, looser convergence (with
    /// [`crate::RenderOptions::preview`]: few shadow rays and edge rays at the pixels). The
    /// fastest setting measured within 2.5% MAE/mean of the path tracer on every shipped scene
    /// (`docs/performance.md`, "Presets"); it keeps the scene's ε because the gallery is 3%
    /// off at 1.2 ε, while simpler scenes allow [`Options::epsilon_scale`] 3 to 4.
    pub fn preview() -> Self {
        Options {
            rounds: 0,
            light_samples: 4,
            tolerance: 1e-2,
            ..Options::default()
        }
    }

    /// Slower and finer: samples at 0.6 of the scene's spacing, more rounds, a tighter ζ, more shadow rays,
    /// tighter convergence, and a hierarchy five times tighter (with
    /// [`crate::RenderOptions::final_quality`]: more shadow and edge rays at the pixels). The
    /// most accurate setting measured within 10 × the default's time on every shipped scene
    /// (`docs/performance.md`, "Presets"). About three times the samples: a scene near the
    /// memory budget at the defaults will not fit.
    pub fn final_quality() -> Self {
        Options {
            epsilon_scale: 0.6,
            rounds: 3,
            zeta: 0.1,
            light_samples: 64,
            tolerance: 1e-4,
            cluster_threshold: DEFAULT_CLUSTER_THRESHOLD / 5.0,
            ..Options::default()
        }
    }
}

/// A starting point for [`Options`], as `--preset` names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Preset {
    /// [`Options::preview`].
    Preview,
    /// [`Options::default`].
    Default,
    /// [`Options::final_quality`].
    Final,
}

impl Preset {
    /// Every preset, fastest first.
    pub const ALL: [Preset; 3] = [Preset::Preview, Preset::Default, Preset::Final];

    /// The preset's name, as `--preset` spells it.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Preview => "preview",
            Preset::Default => "default",
            Preset::Final => "final",
        }
    }

    /// The options it stands for.
    pub fn options(self) -> Options {
        match self {
            Preset::Preview => Options::preview(),
            Preset::Default => Options::default(),
            Preset::Final => Options::final_quality(),
        }
    }

    /// The preset's render settings.
    pub fn render_options(self) -> crate::RenderOptions {
        match self {
            Preset::Preview => crate::RenderOptions::preview(),
            Preset::Default => crate::RenderOptions::default(),
            Preset::Final => crate::RenderOptions::final_quality(),
        }
    }
}

impl std::str::FromStr for Preset {
    type Err = crate::Error;

    fn from_str(s: &str) -> crate::Result<Preset> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| crate::Error::Option {
                option: "preset",
                problem: format!("unknown '{s}' (known: preview, default, final)"),
            })
    }
}

impl std::fmt::Display for Preset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_parse_by_name_and_refuse_others() {
        for p in Preset::ALL {
            assert_eq!(p.name().parse::<Preset>().unwrap(), p);
        }
        assert_eq!(Preset::Preview.options().rounds, 0);
        assert_eq!(Preset::Final.options(), Options::final_quality());
        let e = "fast".parse::<Preset>().unwrap_err().to_string();
        assert!(
            e.contains("unknown 'fast' (known: preview, default, final)"),
            "{e}"
        );
    }
}
