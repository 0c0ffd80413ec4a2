//! Every knob of the solver in one documented struct, with named presets, and the table of
//! the knobs ([`KNOBS`]): each once, with its name, its text form and the values it takes.
//! [`Options::validate`] checks them all from the table; the command line makes its flags,
//! `sweep` its keys and its errors their flag names from the same table, so a knob is added in
//! this file alone.

use crate::budget::DEFAULT_MEMORY_BUDGET;
use crate::error::{Error, Result};
use crate::light::MAX_LIGHT_SAMPLES;
use crate::specular::MAX_SPECULAR_DEPTH;

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
    /// ε as this fraction of the length over which the scene's light changes
    /// ([`light_length`](crate::solver::light_length): its mean free path, shortened by lamps
    /// close to surfaces where there are no adaptive rounds to resolve their pools), instead
    /// of the scene file's ε or the area rule; 0.005 to 1. The
    /// presets `preview` and `final` set it, so they place the same samples on a scene however
    /// it was scaled and whatever ε its file asks for. [`Options::epsilon`] still wins;
    /// [`Options::epsilon_scale`] multiplies it. `None` (the default preset): the scene file's
    /// ε, else the area rule. A scene too open to have a free path takes the area rule.
    pub epsilon_fraction: Option<f32>,
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
    /// faster than the samples: on the shipped gallery 10.2 s instead of 9.1 s for about the
    /// same error against the flat solve (MAE/mean 0.35% and 0.34%); at 179k samples 97.6 M
    /// links and 2.57 GB instead of 5.1 M and 0.71 GB (`docs/performance.md`).
    pub exact_visibility: bool,
    /// Sample, index and interpolate narrow facets (narrower than 2ε) that meet along edges
    /// at under 20°, of one material, as the curved piece they tessellate (a column, an
    /// arch, a moulding): Poisson-disk spacing across the piece instead of a row of samples
    /// along every facet, so the samples follow ε, not the tessellation. Off by default. On
    /// the shipped atrium's solve 2.4 × faster; its image MAE/mean 1.27% against 1.09% and the
    /// worst 1% of blocks 6.6% against 5.8%; with [`Options::epsilon_scale`] 0.7 as well,
    /// about the same errors in 0.65 of the time (`docs/performance.md`). Scenes without narrow
    /// facets: no effect.
    pub join_facets: bool,
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

/// [`Options::epsilon_fraction`] of the preview preset.
pub const PREVIEW_EPSILON_FRACTION: f32 = 0.14;

/// [`Options::epsilon_fraction`] of the final preset.
pub const FINAL_EPSILON_FRACTION: f32 = 0.04;

/// The default [`Options::specular_depth`].
pub const DEFAULT_SPECULAR_DEPTH: u32 = 32;

/// The default [`Options::cluster_threshold`].
pub const DEFAULT_CLUSTER_THRESHOLD: f64 = 0.05;

impl Default for Options {
    fn default() -> Self {
        Options {
            epsilon: None,
            epsilon_scale: 1.0,
            epsilon_fraction: None,
            alpha: 8.0,
            zeta: 0.2,
            rounds: 2,
            light_samples: 16,
            tolerance: 1e-3,
            max_shots: None,
            max_samples: 2_000_000,
            cluster_threshold: DEFAULT_CLUSTER_THRESHOLD,
            exact_visibility: false,
            join_facets: false,
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
        KNOBS.iter().try_for_each(|k| k.check(self))
    }

    /// Sets the knob `name` (a field's name, or spelt with hyphens as on the command line) from
    /// its text form, and checks its value.
    pub fn set(&mut self, name: &str, text: &str) -> crate::Result<()> {
        match knob(name) {
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

    /// Fast and rough: ε 0.14 of the scene's light length (not its file's ε), no adaptive
    /// rounds, few shadow rays, looser convergence (with [`crate::RenderOptions::preview`]: few
    /// shadow rays and edge rays at the pixels). The fastest setting measured within 2.5%
    /// MAE/mean of the path tracer on every shipped scene (`docs/performance.md`, "Presets");
    /// the gallery, whose lamps' pools ε itself must sample without rounds, set the lamp term.
    pub fn preview() -> Self {
        Options {
            epsilon_fraction: Some(PREVIEW_EPSILON_FRACTION),
            rounds: 0,
            light_samples: 4,
            tolerance: 1e-2,
            ..Options::default()
        }
    }

    /// Slower and finer: ε 0.04 of the scene's mean free path (not its file's ε), more rounds,
    /// a tighter ζ, more shadow rays, tighter convergence, and a hierarchy five times tighter (with
    /// [`crate::RenderOptions::final_quality`]: more shadow and edge rays at the pixels). The
    /// most accurate setting measured within 10 × the default's time on every shipped scene
    /// (`docs/performance.md`, "Presets"). About three times the samples: a scene near the
    /// memory budget at the defaults will not fit.
    pub fn final_quality() -> Self {
        Options {
            epsilon_fraction: Some(FINAL_EPSILON_FRACTION),
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

/// The most worker threads a call takes: far beyond any machine this runs on, and well short of
/// what spawning would exhaust.
pub const MAX_THREADS: usize = 1024;

/// The most jobs the solver's pipeline may hold in flight ([`Options::pipeline_capacity`]).
pub const MAX_PIPELINE_CAPACITY: usize = 4096;

/// One knob of [`Options`].
pub struct Knob {
    /// The field's name, as errors name the knob (`light_samples`); the command line spells it
    /// with hyphens (`--light-samples`).
    pub name: &'static str,
    /// What it does, in a line (the field's documentation says more).
    pub help: &'static str,
    /// What its value is called on the command line (`N`, `X`, `BYTES`), or `None` for a switch
    /// that takes `true` or `false`.
    pub value: Option<&'static str>,
    parse: fn(&mut Options, &str) -> std::result::Result<(), String>,
    check: fn(&Options) -> std::result::Result<(), String>,
}

impl Knob {
    /// Sets the knob in `options` from its text form (a number; a size with a K, M or G suffix
    /// for the memory budget; `true` or `false` for a switch) and checks the value.
    pub fn set(&self, options: &mut Options, text: &str) -> Result<()> {
        (self.parse)(options, text.trim()).map_err(|problem| self.error(problem))?;
        self.check(options)
    }

    /// Checks the knob's value in `options`.
    pub fn check(&self, options: &Options) -> Result<()> {
        (self.check)(options).map_err(|problem| self.error(problem))
    }

    fn error(&self, problem: String) -> Error {
        Error::Option {
            option: self.name,
            problem,
        }
    }
}

/// The knob named `name` (the field's name, or the command line's spelling with hyphens).
pub fn knob(name: &str) -> Option<&'static Knob> {
    let name = name.replace('-', "_");
    KNOBS.iter().find(|k| k.name == name)
}

fn number<T: std::str::FromStr>(text: &str) -> std::result::Result<T, String> {
    text.parse()
        .map_err(|_| format!("'{text}' is not a valid value"))
}

fn within<T: PartialOrd + std::fmt::Display>(
    value: T,
    range: std::ops::RangeInclusive<T>,
) -> std::result::Result<(), String> {
    if range.contains(&value) {
        Ok(())
    } else {
        Err(format!(
            "{value} must lie in {}..={}",
            range.start(),
            range.end()
        ))
    }
}

fn anything(_: &Options) -> std::result::Result<(), String> {
    Ok(())
}

/// Every knob of [`Options`], in the order `--help` lists them.
pub const KNOBS: &[Knob] = &[
    Knob {
        name: "epsilon",
        help: "Poisson-disk spacing ε of the initial samples (default: the scene file's, else \
               automatic)",
        value: Some("LENGTH"),
        parse: |o, t| number(t).map(|v| o.epsilon = Some(v)),
        check: |o| match o.epsilon {
            Some(e) if !(e.is_finite() && e > 0.0) => Err(format!("{e} is not a positive length")),
            _ => Ok(()),
        },
    },
    Knob {
        name: "epsilon_scale",
        help: "Multiplies the ε from the scene file, the automatic choice or the preset's fraction (not --epsilon), 1/16 \
               to 16 [default: 1]",
        value: Some("X"),
        parse: |o, t| number(t).map(|v| o.epsilon_scale = v),
        check: |o| match o.epsilon_scale {
            s if s.is_finite() && (0.0625..=16.0).contains(&s) => Ok(()),
            s => Err(format!("{s} must lie in [1/16, 16]")),
        },
    },
    Knob {
        name: "epsilon_fraction",
        help: "ε as this fraction of the length over which the scene's light changes (its mean \
               free path, shortened by lamps near surfaces), not the scene file's ε \
               [default: the preset's: preview 0.14, final 0.04; none by default]",
        value: Some("X"),
        parse: |o, t| number(t).map(|v| o.epsilon_fraction = Some(v)),
        check: |o| match o.epsilon_fraction {
            Some(f) if !(f.is_finite() && (0.005..=1.0).contains(&f)) => {
                Err(format!("{f} must lie in [0.005, 1]"))
            }
            _ => Ok(()),
        },
    },
    Knob {
        name: "zeta",
        help: "Adaptive error threshold ζ, relative to the mean radiosity",
        value: Some("X"),
        parse: |o, t| number(t).map(|v| o.zeta = v),
        check: |o| match o.zeta {
            z if z.is_finite() && z > 0.0 => Ok(()),
            z => Err(format!("{z} must be a positive number")),
        },
    },
    Knob {
        name: "alpha",
        help: "Area weight fall-off α (eq. 5)",
        value: Some("X"),
        parse: |o, t| number(t).map(|v| o.alpha = v),
        check: |o| match o.alpha {
            a if a.is_finite() && a >= 0.0 => Ok(()),
            a => Err(format!("{a} must be a finite number ≥ 0")),
        },
    },
    Knob {
        name: "rounds",
        help: "Adaptive rounds after the first solve",
        value: Some("N"),
        parse: |o, t| number(t).map(|v| o.rounds = v),
        check: anything,
    },
    Knob {
        name: "light_samples",
        help: "Shadow rays per area light and sample",
        value: Some("N"),
        parse: |o, t| number(t).map(|v| o.light_samples = v),
        check: |o| within(o.light_samples, 1..=MAX_LIGHT_SAMPLES),
    },
    Knob {
        name: "tolerance",
        help: "Stop shooting when unshot power < this fraction of emitted power",
        value: Some("X"),
        parse: |o, t| number(t).map(|v| o.tolerance = v),
        check: |o| match o.tolerance {
            t if t.is_finite() && t > 0.0 && t < 1.0 => Ok(()),
            t => Err(format!("{t} must lie in (0, 1)")),
        },
    },
    Knob {
        name: "max_shots",
        help: "At most this many shots per solve",
        value: Some("N"),
        parse: |o, t| number(t).map(|v| o.max_shots = Some(v)),
        check: anything,
    },
    Knob {
        name: "max_samples",
        help: "Refuse to place more samples than this",
        value: Some("N"),
        parse: |o, t| number(t).map(|v| o.max_samples = v),
        check: anything,
    },
    Knob {
        name: "memory_budget",
        help: "The memory budget every large structure counts against: bytes, or with a K, M or \
               G suffix (binary units), e.g. 512M, 8G (default 8G)",
        value: Some("BYTES"),
        parse: |o, t| crate::budget::parse_bytes(t).map(|v| o.memory_budget = v),
        check: |o| match o.memory_budget {
            0 => Err("0 bytes: the budget must be positive".into()),
            _ => Ok(()),
        },
    },
    Knob {
        name: "cluster_threshold",
        help: "Cluster hierarchy error threshold, relative to the mean radiosity (0: the flat \
               solver)",
        value: Some("X"),
        parse: |o, t| number(t).map(|v| o.cluster_threshold = v),
        check: |o| match o.cluster_threshold {
            c if c.is_finite() && c >= 0.0 => Ok(()),
            c => Err(format!(
                "{c} must be a finite number ≥ 0 (0: the flat solver)"
            )),
        },
    },
    Knob {
        name: "exact_visibility",
        help: "Refine every partly visible cluster link down to samples, however faint (slower)",
        value: None,
        parse: |o, t| number(t).map(|v| o.exact_visibility = v),
        check: anything,
    },
    Knob {
        name: "join_facets",
        help: "Sample narrow facets that bend by under 20° as the curved piece they make (a \
               column, an arch), spaced by ε, not a row of samples per facet",
        value: None,
        parse: |o, t| number(t).map(|v| o.join_facets = v),
        check: anything,
    },
    Knob {
        name: "specular_depth",
        help: "Specular bounces light may take between diffuse surfaces (mirror images of \
               lights, and chains through mirrors, glossy surfaces and glass); 0 makes specular \
               surfaces black",
        value: Some("N"),
        parse: |o, t| number(t).map(|v| o.specular_depth = v),
        check: |o| within(o.specular_depth, 0..=MAX_SPECULAR_DEPTH),
    },
    Knob {
        name: "specular_rays",
        help: "Chains followed from each sample through specular surfaces (more: less noise in \
               the light that arrives by way of mirrors, glossy surfaces and glass)",
        value: Some("N"),
        parse: |o, t| number(t).map(|v| o.specular_rays = v),
        check: |o| within(o.specular_rays, 1..=MAX_SPECULAR_RAYS),
    },
    Knob {
        name: "photons",
        help: "Photons sent from the lights through curved mirrors and refracting solids (more: \
               less noise in the light they focus onto surfaces, the caustics)",
        value: Some("N"),
        parse: |o, t| number(t).map(|v| o.photons = v),
        check: |o| within(o.photons, 1..=MAX_PHOTONS),
    },
    Knob {
        name: "threads",
        help: "Worker threads",
        value: Some("N"),
        parse: |o, t| number(t).map(|v| o.threads = v),
        check: |o| within(o.threads, 1..=MAX_THREADS),
    },
    Knob {
        name: "pipeline_capacity",
        help: "Jobs in flight in the solver's pipeline at most (bounds its memory; results do \
               not depend on it)",
        value: Some("N"),
        parse: |o, t| number(t).map(|v| o.pipeline_capacity = v),
        check: |o| {
            within(o.pipeline_capacity, 1..=MAX_PIPELINE_CAPACITY).map_err(|e| {
                format!(
                    "{e} (each job in flight may hold a group's links, megabytes, against the \
                     budget)"
                )
            })
        },
    },
    Knob {
        name: "seed",
        help: "Seed of all random choices",
        value: Some("N"),
        parse: |o, t| number(t).map(|v| o.seed = v),
        check: anything,
    },
];

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

    #[test]
    fn every_knob_sets_its_own_field_and_refuses_bad_text() {
        // Each knob, set from text, changes the options in exactly one field: the table's
        // setters are not crossed (a copy-paste slip would set another knob's field).
        let base = Options::default();
        let values = [
            ("epsilon", "0.25"),
            ("epsilon_scale", "2"),
            ("epsilon_fraction", "0.2"),
            ("zeta", "0.3"),
            ("alpha", "4"),
            ("rounds", "5"),
            ("light_samples", "7"),
            ("tolerance", "0.002"),
            ("max_shots", "99"),
            ("max_samples", "1234"),
            ("memory_budget", "3M"),
            ("cluster_threshold", "0.5"),
            ("exact_visibility", "true"),
            ("join_facets", "true"),
            ("specular_depth", "3"),
            ("specular_rays", "9"),
            ("photons", "77"),
            ("threads", "3"),
            ("pipeline_capacity", "5"),
            ("seed", "42"),
        ];
        assert_eq!(values.len(), KNOBS.len(), "a value for every knob");
        for (name, text) in values {
            let mut o = base.clone();
            knob(name).unwrap().set(&mut o, text).unwrap();
            assert_ne!(o, base, "{name} changed nothing");
            let expected = match name {
                "epsilon" => Options {
                    epsilon: Some(0.25),
                    ..base.clone()
                },
                "epsilon_scale" => Options {
                    epsilon_scale: 2.0,
                    ..base.clone()
                },
                "epsilon_fraction" => Options {
                    epsilon_fraction: Some(0.2),
                    ..base.clone()
                },
                "zeta" => Options {
                    zeta: 0.3,
                    ..base.clone()
                },
                "alpha" => Options {
                    alpha: 4.0,
                    ..base.clone()
                },
                "rounds" => Options {
                    rounds: 5,
                    ..base.clone()
                },
                "light_samples" => Options {
                    light_samples: 7,
                    ..base.clone()
                },
                "tolerance" => Options {
                    tolerance: 0.002,
                    ..base.clone()
                },
                "max_shots" => Options {
                    max_shots: Some(99),
                    ..base.clone()
                },
                "max_samples" => Options {
                    max_samples: 1234,
                    ..base.clone()
                },
                "memory_budget" => Options {
                    memory_budget: 3 << 20,
                    ..base.clone()
                },
                "cluster_threshold" => Options {
                    cluster_threshold: 0.5,
                    ..base.clone()
                },
                "exact_visibility" => Options {
                    exact_visibility: true,
                    ..base.clone()
                },
                "join_facets" => Options {
                    join_facets: true,
                    ..base.clone()
                },
                "specular_depth" => Options {
                    specular_depth: 3,
                    ..base.clone()
                },
                "specular_rays" => Options {
                    specular_rays: 9,
                    ..base.clone()
                },
                "photons" => Options {
                    photons: 77,
                    ..base.clone()
                },
                "threads" => Options {
                    threads: 3,
                    ..base.clone()
                },
                "pipeline_capacity" => Options {
                    pipeline_capacity: 5,
                    ..base.clone()
                },
                "seed" => Options {
                    seed: 42,
                    ..base.clone()
                },
                other => panic!("{other}"),
            };
            assert_eq!(o, expected, "{name}");
            let e = knob(name).unwrap().set(&mut o.clone(), "lots").unwrap_err();
            assert!(e.to_string().contains(name), "{e}");
        }
        // Hyphens as the command line spells them.
        assert_eq!(knob("light-samples").unwrap().name, "light_samples");
        assert!(knob("brightness").is_none());
    }

    #[test]
    fn values_out_of_range_are_refused_with_the_range() {
        let mut o = Options::default();
        let e = knob("light_samples").unwrap().set(&mut o, "0").unwrap_err();
        assert_eq!(
            e.to_string(),
            format!("invalid option light_samples: 0 must lie in 1..={MAX_LIGHT_SAMPLES}")
        );
        for (name, bad) in [
            ("epsilon", "-1"),
            ("epsilon_scale", "17"),
            ("epsilon_fraction", "0"),
            ("epsilon_fraction", "1.5"),
            ("zeta", "0"),
            ("alpha", "NaN"),
            ("tolerance", "1"),
            ("memory_budget", "0"),
            ("cluster_threshold", "-0.1"),
            ("specular_depth", "65"),
            ("specular_rays", "0"),
            ("photons", "0"),
            ("threads", "0"),
            ("pipeline_capacity", "0"),
        ] {
            let mut o = Options::default();
            assert!(
                knob(name).unwrap().set(&mut o, bad).is_err(),
                "{name} = {bad}"
            );
        }
    }
}
