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

/// The command-line flag of a library option, where there is one.
fn flag(option: &str) -> Option<String> {
    const FLAGS: [(&str, &str); 21] = [
        ("gather_rays", "--gather-rays"),
        ("specular_rays", "--specular-rays"),
        ("photons", "--photons"),
        ("specular_depth", "--specular-depth"),
        ("glossy_rays", "--glossy-rays"),
        ("epsilon", "--epsilon"),
        ("alpha", "--alpha"),
        ("zeta", "--zeta"),
        ("rounds", "--rounds"),
        ("light_samples", "--light-samples"),
        ("tolerance", "--tolerance"),
        ("max_shots", "--max-shots"),
        ("max_samples", "--max-samples"),
        ("cluster_threshold", "--cluster-threshold"),
        ("memory_budget", "--memory-budget"),
        ("max_reflectance", "--max-reflectance"),
        ("patch_size", "--patch-size"),
        ("supersample", "--supersample"),
        ("spp", "--spp"),
        ("preset", "--preset"),
        ("block", "--block"),
    ];
    FLAGS
        .iter()
        .find(|(name, _)| *name == option)
        .map(|(_, flag)| flag.to_string())
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
    }
}
