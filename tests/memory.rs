//! The memory budget: a solve that would not fit is refused before it allocates, naming the
//! predicted size; links that outgrow what is left end the solve with an error; within the
//! budget results do not depend on it.

mod common;

use common::counting::{self, Counting};
use common::shipped;
use meshlight::budget::BYTES_PER_SAMPLE;
use meshlight::solver::{Control, Options};
use meshlight::{Backend, Error, Scene};

#[global_allocator]
static ALLOCATOR: Counting = Counting;

fn solve(scene: &Scene, options: &Options) -> meshlight::Result<meshlight::Solution> {
    let vis = Backend::Bvh.build(scene).unwrap();
    meshlight::solve(scene, vis.as_ref(), options, &mut |_| Control::Continue)
}

#[test]
fn a_budget_too_small_is_refused_before_allocating_and_names_the_predicted_size() {
    let room = Scene::load(shipped("room")).unwrap();
    let budget = 4 << 20;
    let options = Options {
        memory_budget: budget,
        rounds: 0,
        ..Options::default()
    };
    let vis = Backend::Bvh.build(&room).unwrap();
    counting::reset_peak();
    let before = counting::live();
    let e =
        meshlight::solve(&room, vis.as_ref(), &options, &mut |_| Control::Continue).unwrap_err();
    // Refused before the samples existed: the call held far less than the budget at its peak.
    let held = counting::peak() - before;
    assert!(
        held < (budget / 8) as i64,
        "held {held} bytes before refusing"
    );
    let Error::Budget {
        budget: named,
        problem,
    } = &e
    else {
        panic!("{e}")
    };
    assert_eq!(*named, budget);
    // The prediction named: about 0.7 × area / ε² samples (ε 0.25, `room`: 296.6 m² of
    // reflecting area, 16 reflecting sides) at BYTES_PER_SAMPLE each.
    let area =
        4.0 * 5.5 * 9.0 + 2.0 * 5.5 * 5.5 + 5.0 * 1.65 * 1.65 + 4.0 * 1.65 * 3.3 + 1.65 * 1.65;
    let samples = 0.7 * area / (0.25f64 * 0.25) + 16.0;
    let mib = samples * BYTES_PER_SAMPLE as f64 / (1024.0 * 1024.0);
    assert!(
        problem.contains(&format!(
            "about {} samples",
            grouped(samples.round() as u64)
        )),
        "{problem}"
    );
    assert!(problem.contains(&format!("{mib:.1} MiB")), "{problem}");

    // The prediction holds the solve it refused: with room enough, round 0 takes less.
    let fits = Options {
        memory_budget: 1 << 30,
        rounds: 0,
        ..Options::default()
    };
    let s = solve(&room, &fits).unwrap();
    let actual = s.rounds()[0].solution_bytes as f64;
    assert!(
        actual <= samples * BYTES_PER_SAMPLE as f64,
        "{actual} bytes held"
    );
    assert!(
        actual >= samples * BYTES_PER_SAMPLE as f64 / 4.0,
        "{actual} bytes held"
    );
}

#[test]
fn links_that_outgrow_the_budget_end_the_solve_with_an_error() {
    let room = Scene::load(shipped("room")).unwrap();
    // A threshold this small links nearly every pair of samples: tens of MB of links.
    let greedy = Options {
        cluster_threshold: 1e-7,
        rounds: 0,
        memory_budget: 32 << 20,
        ..Options::default()
    };
    let e = solve(&room, &greedy).unwrap_err();
    assert!(matches!(e, Error::Budget { .. }), "{e}");
    assert!(e.to_string().contains("cluster links outgrew"), "{e}");
}

#[test]
fn where_the_budget_binds_the_flat_solver_keeps_fewer_form_factors_and_gives_the_same_light() {
    // The flat solver keeps each shooter's form factors for its later shots as long as they fit
    // in what the samples leave of the budget: `room`'s 3,189 samples keep them all in 8 GiB,
    // and a few hundred shooters' lists in 24 MiB (the samples are predicted at 10 MiB, so
    // 24 MiB is just above the 20 MiB the prediction needs).
    let room = Scene::load(shipped("room")).unwrap();
    let flat = |memory_budget| Options {
        cluster_threshold: 0.0,
        rounds: 0,
        memory_budget,
        ..Options::default()
    };
    let roomy = solve(&room, &flat(8 << 30)).unwrap();
    let tight = solve(&room, &flat(24 << 20)).unwrap();
    let (r, t) = (&roomy.rounds()[0].shooting, &tight.rounds()[0].shooting);
    assert!(
        t.bytes < r.bytes / 2,
        "the budget binds: {} bytes kept in 24 MiB, {} in 8 GiB",
        t.bytes,
        r.bytes
    );
    assert!(t.bytes <= 24 << 20, "{} bytes kept", t.bytes);
    assert!(
        t.cached_shots < r.cached_shots,
        "shots answered from kept form factors: {} tight, {} roomy",
        t.cached_shots,
        r.cached_shots
    );
    // What is not kept is computed again, the same way: the same light, bit for bit.
    assert_eq!(roomy.radiosity(), tight.radiosity());
    assert_eq!(r.shots, t.shots);

    // Below what the samples are predicted to take, the flat solver refuses too.
    let e = solve(&room, &flat(16 << 20)).unwrap_err();
    assert!(matches!(e, Error::Budget { .. }), "{e}");
}

/// Digits in groups of three, as messages print counts: 12,345.
fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}
