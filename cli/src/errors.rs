//! Errors as the command line reports them: the library's message, with the flag to change
//! where the library names an option (it speaks of its options by their field names).

use meshlight::Error;

/// The error's cause chain on one line, with a hint naming the command-line flag where the
/// library's error is about an option or the memory budget.
pub fn explain(e: &anyhow::Error) -> String {
    let text = format!("{e:#}");
    match e.downcast_ref::<Error>() {
        Some(Error::Option { option, .. }) => match flag(option) {
            Some(flag) => format!("{text} (set with {flag})"),
            None => text,
        },
        Some(Error::Budget { .. }) => format!("{text} (--memory-budget)"),
        _ => text,
    }
}

/// The command-line flag of a library option, where there is one: the flag spelt as the option
/// with hyphens, looked up in the command's own definition (the solver's flags are made from
/// its knob table, so every knob has one).
fn flag(option: &str) -> Option<String> {
    use clap::CommandFactory;
    let long = option.replace('_', "-");
    let command = crate::args::Args::command();
    let has = |c: &clap::Command| {
        c.get_arguments()
            .any(|a| a.get_long() == Some(long.as_str()))
    };
    (has(&command) || command.get_subcommands().any(has)).then(|| format!("--{long}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_are_reported_with_their_flags() {
        let e = anyhow::Error::from(Error::Option {
            option: "light_samples",
            problem: "0 must lie in 1..=65536".into(),
        });
        assert_eq!(
            explain(&e),
            "invalid option light_samples: 0 must lie in 1..=65536 (set with --light-samples)"
        );
        let e = anyhow::Error::from(Error::Budget {
            budget: 1 << 20,
            problem: "too much".into(),
        });
        assert_eq!(
            explain(&e),
            "memory budget of 1.0 MiB: too much (--memory-budget)"
        );
        // Every knob of the library's table has its flag, and the render's options theirs.
        for knob in meshlight::solver::KNOBS {
            let flag = flag(knob.name).unwrap_or_else(|| panic!("{} has no flag", knob.name));
            assert_eq!(flag, format!("--{}", knob.name.replace('_', "-")));
        }
        for option in [
            "gather_rays",
            "glossy_rays",
            "spp",
            "patch_size",
            "block",
            "preset",
        ] {
            assert!(flag(option).is_some(), "{option}");
        }
        assert_eq!(flag("brightness"), None);
    }
}
