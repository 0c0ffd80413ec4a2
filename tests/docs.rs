//! The documentation a newcomer reads first stays true: the README's library example is the
//! crate's own (which runs as a doctest), and every document the README links exists.

use std::path::Path;

fn read(path: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(path)).unwrap()
}

#[test]
fn the_readme_example_is_the_crate_doc_example() {
    let lib = read("src/lib.rs");
    let start = lib.find("//! ```\n").expect("a doc example") + "//! ```\n".len();
    let end = start + lib[start..].find("//! ```").unwrap();
    // The example's lines, without the doc prefix and without hidden lines.
    let example: String = lib[start..end]
        .lines()
        .filter(|l| !l.starts_with("//! # "))
        .map(|l| format!("{}\n", l.strip_prefix("//! ").unwrap_or("")))
        .collect();
    let readme = read("README.md");
    assert!(
        readme.contains(&format!("```rust\n{example}```")),
        "README.md's library example differs from src/lib.rs's:\n{example}"
    );
}

#[test]
fn the_readme_is_short_and_its_links_lead_somewhere() {
    let readme = read("README.md");
    assert!(
        readme.lines().count() <= 200,
        "{} lines",
        readme.lines().count()
    );
    let mut links = 0;
    for part in readme.split("](").skip(1) {
        let target = &part[..part.find(')').unwrap()];
        if target.starts_with("http") {
            continue;
        }
        let file = target.split('#').next().unwrap();
        assert!(
            Path::new(env!("CARGO_MANIFEST_DIR")).join(file).exists(),
            "README links to {target}, which does not exist"
        );
        links += 1;
    }
    assert!(links >= 7, "{links} links");
}
