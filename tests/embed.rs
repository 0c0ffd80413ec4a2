//! `examples/embed.rs`, a host with its own triangles and its own ray caster, run as a test:
//! its brute-force caster must give what the shipped backends give, its stop must hold, and
//! the estimate it renders must be the stopped one.

#[path = "../examples/embed.rs"]
mod embed;

use meshlight::solver::StopReason;
use meshlight::Backend;

#[test]
fn a_host_with_its_own_ray_caster_gets_what_the_shipped_backends_give() {
    let scene = embed::host_scene().unwrap();
    let mine = embed::BruteForce::new(&scene);
    let stopped = embed::run(&scene, &mine, 10).unwrap();
    assert_eq!(stopped.solution.stop(), StopReason::Stopped);
    assert!(stopped.shots_seen >= 10, "{}", stopped.shots_seen);
    assert!(stopped.reports > 0);
    let full = embed::run(&scene, &mine, u64::MAX).unwrap();
    assert_ne!(full.solution.stop(), StopReason::Stopped);
    // Stopped early, less light has been shot: the estimate is darker than the finished solve.
    let (early, done) = (stopped.image.mean(), full.image.mean());
    assert!(
        early.is_finite() && early > 0.0 && early < done,
        "{early} vs {done}"
    );

    // The same stop with the shipped backends: the same answer up to rounding at triangle edges.
    for backend in Backend::available() {
        let vis = backend.build(&scene).unwrap();
        let theirs = embed::run(&scene, vis.as_ref(), 10).unwrap();
        assert_eq!(
            theirs.solution.samples().len(),
            stopped.solution.samples().len()
        );
        let e = meshlight::metrics::compare(&stopped.image, &theirs.image).unwrap();
        assert!(
            e.mae_over_mean < 1e-3,
            "{backend}: MAE/mean {}",
            e.mae_over_mean
        );
    }
}
