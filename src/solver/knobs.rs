//! The table of the solver's knobs: each [`Options`] field once, with its name, its text form
//! and the values it takes. [`Options::validate`] checks them all from here; the command line
//! makes its flags, `sweep` its keys and its errors their flag names from the same table, so a
//! knob is added in one place (and its field and default in `options.rs`).

use super::options::{Options, MAX_PHOTONS, MAX_SPECULAR_RAYS};
use crate::error::{Error, Result};
use crate::light::MAX_LIGHT_SAMPLES;
use crate::specular::MAX_SPECULAR_DEPTH;

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
        help: "Multiplies the ε from the scene file or the automatic choice (not --epsilon), 1/16 \
               to 16 [default: the preset's: 1, final 0.6]",
        value: Some("X"),
        parse: |o, t| number(t).map(|v| o.epsilon_scale = v),
        check: |o| match o.epsilon_scale {
            s if s.is_finite() && (0.0625..=16.0).contains(&s) => Ok(()),
            s => Err(format!("{s} must lie in [1/16, 16]")),
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
    fn every_knob_sets_its_own_field_and_refuses_bad_text() {
        // Each knob, set from text, changes the options in exactly one field: the table's
        // setters are not crossed (a copy-paste slip would set another knob's field).
        let base = Options::default();
        let values = [
            ("epsilon", "0.25"),
            ("epsilon_scale", "2"),
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
