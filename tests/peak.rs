//! The memory budget holds where the links would outgrow it: on the atrium (columns, arches,
//! vaults: many links a sample), a solve under a budget its links cannot fit ends with the
//! budget error, and the most this process's Rust code held at any moment — the scene, the
//! samples, the tree, the links so far, the jobs in flight — stays under the budget. Counted
//! exactly by a global allocator (resident memory would add the program and the allocator's
//! caches); the bvh backend, whose structures are Rust's and so counted. One test in its own
//! binary, so that no other test's allocations share the count.

mod common;

use common::counting::{self, Counting};
use meshlight::solver::{Control, Options};
use meshlight::{Backend, Error, Scene};

#[global_allocator]
static ALLOCATOR: Counting = Counting;

#[test]
fn links_that_would_outgrow_the_budget_stop_the_solve_before_its_peak_passes_the_budget() {
    counting::reset_peak();
    let path = meshlight_atrium::ensure().expect("generate the atrium");
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let vis = Backend::Bvh.build(&scene).unwrap();
    let budget = 96usize << 20;
    let options = Options {
        memory_budget: budget,
        rounds: 0,
        ..Options::default()
    };
    let e =
        meshlight::solve(&scene, vis.as_ref(), &options, &mut |_| Control::Continue).unwrap_err();
    assert!(matches!(e, Error::Budget { .. }), "{e}");
    assert!(e.to_string().contains("cluster links outgrew"), "{e}");
    let peak = counting::peak() as f64;
    eprintln!(
        "{e}\npeak held: {:.1} MiB of {} MiB",
        peak / (1 << 20) as f64,
        budget >> 20
    );
    assert!(
        peak < budget as f64,
        "held {:.1} MiB",
        peak / (1 << 20) as f64
    );
}
