//! The cluster hierarchy against the flat solver it approximates and the physics it must keep:
//! the image of `room` within 0.5% of the flat solve, the furnace, no light through a wall at
//! any threshold, queries growing about linearly with the samples, and the same answer for any
//! number of workers and any pipeline capacity.

mod common;

use common::{
    assert_dark_room_is_dark, backends, shipped, shipped_at, solve, solve_and_render, two_rooms,
};
use meshlight::solver::{Control, Options, StopReason};
use meshlight::{Backend, Scene};

fn flat() -> Options {
    Options {
        cluster_threshold: 0.0,
        ..Options::default()
    }
}

#[test]
#[ignore = "full tier: a large or repeated solve (cargo test -- --include-ignored)"]
fn room_at_the_default_threshold_is_within_half_a_percent_of_the_flat_solve() {
    let scene = Scene::load(shipped("room")).unwrap();
    for backend in backends() {
        let (_, reference) = solve_and_render(&scene, backend, flat(), true);
        let (solution, image) = solve_and_render(&scene, backend, Options::default(), true);
        assert!(solution
            .rounds()
            .iter()
            .all(|r| r.shooting.links > 0 || r.shooting.shots == 0));
        let e = meshlight::metrics::compare(&image, &reference).unwrap();
        assert!(
            e.mae_over_mean <= 0.005,
            "{backend}: MAE/mean {:.5} against the flat solve",
            e.mae_over_mean
        );
    }
}

#[test]
fn furnace_holds_with_the_hierarchy_and_without_it() {
    // Closed cube, Kd 0.5, Ke 0.1 everywhere: L = Ke / (1 − Kd) = 0.2 at every sample and pixel.
    let scene = Scene::load(shipped("box")).unwrap();
    for backend in backends() {
        for threshold in [0.0, Options::default().cluster_threshold] {
            let options = Options {
                tolerance: 1e-5,
                cluster_threshold: threshold,
                ..Options::default()
            };
            let (s, image) = solve_and_render(&scene, backend, options, true);
            assert_eq!(s.stop(), StopReason::Converged);
            let worst_sample = s
                .radiosity()
                .iter()
                .map(|b| (b.x / std::f64::consts::PI - 0.2).abs() / 0.2)
                .fold(0.0, f64::max);
            let worst_pixel = image
                .pixels
                .iter()
                .map(|p| (f64::from(p.x) - 0.2).abs() / 0.2)
                .fold(0.0, f64::max);
            assert!(
                worst_sample < 0.01 && worst_pixel < 0.01,
                "{backend}, threshold {threshold}: worst sample {worst_sample:.4}, pixel {worst_pixel:.4}"
            );
            // B = Ke/(1 − Kd) holds by construction once rows are scaled to sum to 1; the
            // transfer itself must already be close: every closed row's raw sum (before the
            // scaling, target 1 here as every emitter reflects) within 1 ± 2% for the flat
            // solver (measured 0.997..1.013). The hierarchy's receiver field is first order,
            // and a tangent overestimates a concave field: at face centres, where irradiance
            // peaks, rows reach 1.021 (median 1.008), hence 2.5% for it.
            let closed: Vec<usize> = (0..s.samples().len()).filter(|&k| s.closed()[k]).collect();
            assert!(
                closed.len() > s.samples().len() * 9 / 10,
                "{} closed",
                closed.len()
            );
            let (lo, hi) = closed
                .iter()
                .map(|&k| 1.0 / f64::from(s.row_scales()[k]))
                .fold((f64::MAX, 0.0f64), |(lo, hi), r| (lo.min(r), hi.max(r)));
            let allowed = if threshold == 0.0 { 0.02 } else { 0.025 };
            assert!(
                lo > 1.0 - allowed && hi < 1.0 + allowed,
                "{backend}, threshold {threshold}: raw row sums span {lo:.4}..{hi:.4}"
            );
        }
    }
}

#[test]
fn no_light_goes_through_a_wall_at_the_default_threshold_or_a_hundred_times_it() {
    // Room B shares a solid wall and one continuous floor with room A, where the light is:
    // floor clusters reaching under the wall must never carry A's light into B.
    let scene = two_rooms();
    for backend in backends() {
        for (factor, exact_visibility) in [(1.0, false), (100.0, false), (1.0, true)] {
            let options = Options {
                cluster_threshold: factor * Options::default().cluster_threshold,
                exact_visibility,
                ..Options::default()
            };
            let (s, image) = solve_and_render(&scene, backend, options, true);
            let shooting = s.rounds()[0].shooting;
            assert!(
                shooting.links > shooting.leaf_links,
                "{backend}: the hierarchy made cluster links"
            );
            let label = format!("{backend}, ×{factor}, exact visibility {exact_visibility}");
            assert_dark_room_is_dark(&s, &label);
            // The camera looks into the dark room.
            assert!(
                image.pixels.iter().all(|p| *p == glam::Vec3::ZERO),
                "{label}: the dark room shows light"
            );
        }
    }
}

/// Visibility queries of a solve of `scene` at ε (no adaptive rounds), and its sample count.
fn queries(scene: &Scene, epsilon: f32, threshold: f64) -> (u64, usize) {
    let s = solve(
        scene,
        Backend::default_backend(),
        Options {
            epsilon: Some(epsilon),
            rounds: 0,
            cluster_threshold: threshold,
            ..Options::default()
        },
    );
    (s.rounds()[0].shooting.queries, s.samples().len())
}

#[test]
#[ignore = "full tier: a large or repeated solve (cargo test -- --include-ignored)"]
fn from_n_to_4n_samples_queries_grow_less_than_five_times() {
    // A reduced gallery (big tiles, icosahedra); ε 0.6 → 0.28 about quadruples the samples
    // (every side keeps at least one, so halving ε alone gives less).
    let dir = tempfile::tempdir().unwrap();
    meshlight_gallery::write_scene(
        dir.path(),
        meshlight_gallery::GalleryOptions {
            tile: 0.5,
            sphere_detail: 0,
            ..Default::default()
        },
    )
    .unwrap();
    let scene = Scene::load(dir.path().join("scene.toml")).unwrap();
    let threshold = Options::default().cluster_threshold;
    let (q1, n1) = queries(&scene, 0.6, threshold);
    let (q4, n4) = queries(&scene, 0.28, threshold);
    let samples = n4 as f64 / n1 as f64;
    assert!((3.8..4.6).contains(&samples), "{n1} → {n4} samples");
    let growth = q4 as f64 / q1 as f64;
    assert!(
        growth < 5.0,
        "hierarchy: {n1} → {n4} samples ({samples:.2}×), queries {q1} → {q4} ({growth:.2}×)"
    );
    // The flat solver's grow with the square of the samples.
    let (f1, _) = queries(&scene, 0.6, 0.0);
    let (f4, _) = queries(&scene, 0.28, 0.0);
    let flat = f4 as f64 / f1 as f64;
    assert!(
        flat > 0.75 * samples * samples,
        "flat: queries {f1} → {f4} ({flat:.2}×) for {samples:.2}× the samples"
    );
}

#[test]
fn one_or_two_workers_and_any_pipeline_capacity_give_the_same_answer() {
    let scene = Scene::load(shipped("room")).unwrap();
    let vis = Backend::default_backend().build(&scene).unwrap();
    let run = |threads, pipeline_capacity| {
        let options = Options {
            threads,
            pipeline_capacity,
            ..Options::default()
        };
        meshlight::solve(&scene, vis.as_ref(), &options, &mut |_| Control::Continue).unwrap()
    };
    let reference = run(1, 16);
    assert!(reference.rounds()[0].shooting.links > 0);
    for (threads, capacity) in [(2, 16), (2, 1), (1, 1), (3, 2)] {
        let other = run(threads, capacity);
        assert_eq!(other.samples(), reference.samples());
        assert!(
            other.radiosity() == reference.radiosity(),
            "{threads} workers, capacity {capacity}: radiosity differs"
        );
        assert_eq!(
            other
                .rounds()
                .iter()
                .map(|r| r.shooting.links)
                .collect::<Vec<_>>(),
            reference
                .rounds()
                .iter()
                .map(|r| r.shooting.links)
                .collect::<Vec<_>>()
        );
    }
}

/// `cornell` with its whites (Kd 0.72) at Kd 0.95: light is reflected about twenty times, so a
/// small loss per transfer compounds.
/// `scene` solved on the same samples (no adaptive rounds) to 1e-6 by the flat solver and by
/// the hierarchy at its default threshold.
fn flat_and_tree(scene: &Scene, backend: Backend) -> (meshlight::Solution, meshlight::Solution) {
    flat_and_tree_seeded(scene, backend, Options::default().seed)
}

/// [`flat_and_tree`] with another seed (other samples, other probes).
fn flat_and_tree_seeded(
    scene: &Scene,
    backend: Backend,
    seed: u64,
) -> (meshlight::Solution, meshlight::Solution) {
    let at = |threshold| {
        let options = Options {
            tolerance: 1e-6,
            rounds: 0,
            cluster_threshold: threshold,
            seed,
            ..Options::default()
        };
        solve(scene, backend, options)
    };
    (at(0.0), at(Options::default().cluster_threshold))
}

fn cornell_at_0_95() -> Scene {
    let mut scene = Scene::load(shipped("cornell")).unwrap();
    let white = scene
        .materials()
        .iter()
        .position(|m| m.kd == glam::Vec3::splat(0.72))
        .unwrap();
    let mut m = scene.materials()[white].clone();
    m.kd = glam::Vec3::splat(0.95);
    scene.set_material(white, m).unwrap();
    scene
}

/// Reflected power Σ ρ H S of a solve (what the image shows, less the lights).
fn reflected(scene: &Scene, s: &meshlight::Solution) -> f64 {
    let absorbed = s.absorbed(scene).element_sum();
    let received: f64 = s
        .irradiance()
        .iter()
        .zip(s.samples().area())
        .map(|(h, a)| h.element_sum() * a)
        .sum();
    received - absorbed
}

#[test]
fn the_light_left_unshot_is_carried_to_its_end() {
    // Stopping at a tolerance of 1e-2 leaves a hundredth of the emitted power unshot, which at
    // Kd 0.95 would still be reflected many times: 1.0% of the reflected light was missing
    // (measured before the tail was extrapolated). Shooting on to 1e-7 is the second method.
    let scene = cornell_at_0_95();
    for backend in backends() {
        let run = |tolerance| {
            solve(
                &scene,
                backend,
                Options {
                    tolerance,
                    rounds: 0,
                    ..Options::default()
                },
            )
        };
        let (coarse, fine) = (run(1e-2), run(1e-7));
        let ratio = reflected(&scene, &coarse) / reflected(&scene, &fine);
        assert!(
            (ratio - 1.0).abs() < 1e-3,
            "{backend}: reflected power at tolerance 1e-2 is {ratio:.5} of that at 1e-7"
        );
        // The ledger still adds up: absorbed + escaped + unshot = emitted.
        for s in [&coarse, &fine] {
            let emitted = s.ledger().emitted.element_sum();
            let account = s.absorbed(&scene).element_sum()
                + s.ledger().escaped.element_sum()
                + s.unshot_power().element_sum();
            assert!(
                (account / emitted - 1.0).abs() < 1e-9,
                "{backend}: the ledger accounts for {:.6} of the emitted power",
                account / emitted
            );
        }
    }
}

#[test]
fn at_albedo_0_95_the_hierarchy_delivers_what_its_shooters_send() {
    // Each sweep's links must deliver what the shooters' own rows say leaves them (reciprocity);
    // cluster links delivered 0.46% less of what was shot, which at Kd 0.95 made the image 0.5%
    // darker than the flat solve's. Here the share of the emitted power that leaves the
    // surfaces (into the light, which reflects nothing): the flat solver's, from its exact
    // point-to-disc form factors, against the hierarchy's (measured: 4.48% and 4.58%; 4.94%
    // before the sweeps were balanced).
    let scene = cornell_at_0_95();
    for backend in backends() {
        let left = |s: meshlight::Solution| {
            s.ledger().escaped.element_sum() / s.ledger().emitted.element_sum()
        };
        let (flat, tree) = flat_and_tree(&scene, backend);
        let (flat, tree) = (left(flat), left(tree));
        assert!(
            (tree - flat).abs() < 0.002,
            "{backend}: {:.3}% of the emitted power leaves the hierarchy's surfaces, {:.3}% the flat solver's",
            100.0 * tree,
            100.0 * flat
        );
    }
}

#[test]
#[ignore = "full tier: a large or repeated solve (cargo test -- --include-ignored)"]
fn at_albedo_0_95_the_hierarchy_reflects_as_much_light_as_the_flat_solver() {
    // The same samples (no adaptive rounds), shot to convergence: the light all surfaces
    // reflect, Σ B S, by the hierarchy and by the flat solver, over five seeds. A cluster link
    // from its centre alone errs at second order in the shooter's extent, concave head-on and
    // convex edge-on, and the receivers' row scales cannot take that out: the hierarchy
    // reflected 0.10% less (0.21% with seed 5); shooting from four points with the node's
    // spread, 0.005% less at seed 1. The light hangs 1 cm under the ceiling, and a cluster
    // link's eight probes could all land on ceiling samples in its gap, or all beside it:
    // seeds 1-5 then gave -0.008, +0.083, +0.077, +0.026, -0.117%; refining the nodes the
    // fixture hovers over (and those holding samples beside it), -0.028, +0.043, +0.043,
    // +0.034, +0.020%.
    let scene = cornell_at_0_95();
    for backend in backends() {
        let reflected = |s: meshlight::Solution| {
            let samples = s.samples();
            (0..samples.len())
                .map(|k| s.radiosity()[k].element_sum() * samples.area()[k])
                .sum::<f64>()
        };
        for seed in 1..=5 {
            let (flat, tree) = flat_and_tree_seeded(&scene, backend, seed);
            let (flat, tree) = (reflected(flat), reflected(tree));
            let off = tree / flat - 1.0;
            eprintln!(
                "{backend}, seed {seed}: the hierarchy reflects {:+.4}% of the flat solver's light",
                100.0 * off
            );
            assert!(
                off.abs() < 6e-4,
                "{backend}, seed {seed}: {:+.4}%",
                100.0 * off
            );
        }
    }
}

#[test]
#[ignore = "full tier: a large or repeated solve (cargo test -- --include-ignored)"]
fn after_adaptive_rounds_the_hierarchy_matches_the_flat_solver_block_by_block() {
    // The shipped room at the defaults (two adaptive rounds), 128²: over 4 × 4 blocks the
    // hierarchy's image against the flat solver's, the independent O(N²) transport. The tail
    // extrapolated after a warm start left a blotch by the front box's foot: p99 2.59% (0.44%
    // since it is taken only for unshot power of one sign).
    let scene = shipped_at("room", 128);
    for backend in backends() {
        let (_, hierarchy) = solve_and_render(&scene, backend, Options::default(), true);
        let flat = Options {
            cluster_threshold: 0.0,
            ..Options::default()
        };
        let (_, flat) = solve_and_render(&scene, backend, flat, true);
        let e = meshlight::metrics::compare_blocks(&hierarchy, &flat, 4).unwrap();
        eprintln!(
            "{backend}: hierarchy vs flat over 4 x 4 blocks: MAE/mean {:.3}%, p99 {:.3}%",
            100.0 * e.mae_over_mean,
            100.0 * e.p99_over_mean
        );
        assert!(
            e.p99_over_mean < 0.01,
            "{backend}: p99 {:.3}%",
            100.0 * e.p99_over_mean
        );
    }
}

#[test]
#[ignore = "full tier: a large or repeated solve (cargo test -- --include-ignored)"]
fn on_artist_made_facets_the_hierarchy_matches_the_flat_solve_sample_by_sample() {
    // The atrium: columns of 48 facets, arches, vaults, cloths, most surfaces under 0.5 m², so
    // most nodes span several surfaces with something standing among their members. Both
    // solvers on the same samples (no adaptive rounds): the flat solver is the independent
    // O(N²) transport: 0.15% apart on average, bias -0.02% (measured). Links: 515 a sample;
    // 662 when larger pairs with something standing among their members were refined however
    // faint, 1,090 when small ones were refined to samples too, and a partly visible pair whose
    // every member pair was probed gave a leaf link for each visible member pair.
    // Joined into curved pieces, each piece's samples one subtree of the tree, split by place
    // (3,665 samples; before, facet by facet: 287 links a sample; now 277, 0.12% from the flat
    // solve, measured).
    let path = meshlight_atrium::ensure().expect("generate the atrium");
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    for (backend, join_facets) in backends().into_iter().flat_map(|b| [(b, false), (b, true)]) {
        let at = |threshold| {
            let options = Options {
                epsilon: Some(1.5),
                rounds: 0,
                cluster_threshold: threshold,
                join_facets,
                ..Options::default()
            };
            solve(&scene, backend, options)
        };
        let (flat, tree) = (at(0.0), at(Options::default().cluster_threshold));
        assert_eq!(flat.samples().len(), tree.samples().len());
        let area = flat.samples().area();
        let (mut diff, mut total, mut bias) = (0.0, 0.0, 0.0);
        for ((f, t), a) in flat.radiosity().iter().zip(tree.radiosity()).zip(area) {
            let (f, t) = (f.element_sum(), t.element_sum());
            diff += (t - f).abs() * a;
            bias += (t - f) * a;
            total += f * a;
        }
        let n = tree.samples().len() as f64;
        let links = tree.rounds()[0].shooting.links as f64;
        eprintln!(
            "{backend}, joined {join_facets}: {n} samples, {:.0} links a sample; radiosity \
             against the flat solve: mean |difference| {:.3}%, bias {:+.3}%",
            links / n,
            100.0 * diff / total,
            100.0 * bias / total
        );
        assert!(
            diff / total < 0.01,
            "{backend}: {:.3}%",
            100.0 * diff / total
        );
        assert!(
            bias.abs() / total < 0.003,
            "{backend}: bias {:.3}%",
            100.0 * bias / total
        );
        assert!(
            links / n < 600.0,
            "{backend}: {:.0} links a sample",
            links / n
        );
        // Joined, grouped by place: 287 a sample grouped facet by facet.
        assert!(
            !join_facets || links / n < 283.0,
            "{backend}: {:.0} links a sample joined",
            links / n
        );
    }
}
