//! A solve (and a render) spread over ranks gives one process's solution (and image), bit for
//! bit: ranks simulated by
//! threads of this process, exchanging through shared memory (the CLI's MPI ranks are tested
//! in cli/tests/mpi.rs, with the `mpi` feature). The threads' transport implements only
//! `all_gather`, so the links also go through `Ranks::exchange`'s default.

mod common;

use std::sync::{Arc, Barrier, Mutex};

use meshlight::distributed::Ranks;
use meshlight::{Backend, Control, Image, Options, RenderOptions, Scene, Solution};

/// What the simulated ranks share: a slot per rank, and a barrier.
struct Shared {
    slots: Mutex<Vec<Vec<f64>>>,
    barrier: Barrier,
}

/// One simulated rank.
struct Threaded {
    rank: usize,
    size: usize,
    shared: Arc<Shared>,
}

impl Ranks for Threaded {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.size
    }

    fn all_gather(&self, mine: &[f64], counts: &[usize], out: &mut [f64]) -> meshlight::Result<()> {
        self.shared.slots.lock().unwrap()[self.rank] = mine.to_vec();
        self.shared.barrier.wait();
        {
            let slots = self.shared.slots.lock().unwrap();
            let mut at = 0;
            for (slot, &count) in slots.iter().zip(counts) {
                assert_eq!(slot.len(), count, "every rank agrees on the counts");
                out[at..at + count].copy_from_slice(slot);
                at += count;
            }
        }
        // Nobody writes the next call's slot before everyone has read this one's.
        self.shared.barrier.wait();
        Ok(())
    }
}

/// Solves and renders `scene` on `size` simulated ranks; every rank's solution and image.
fn on_ranks(
    scene: &Scene,
    backend: meshlight::Backend,
    options: &Options,
    size: usize,
) -> Vec<(Solution, Image)> {
    let shared = Arc::new(Shared {
        slots: Mutex::new(vec![Vec::new(); size]),
        barrier: Barrier::new(size),
    });
    let vis = backend.build(scene).unwrap();
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..size)
            .map(|rank| {
                let ranks = Threaded {
                    rank,
                    size,
                    shared: shared.clone(),
                };
                let vis = vis.as_ref();
                s.spawn(move || {
                    let solution = meshlight::solver::solve_distributed(
                        scene,
                        vis,
                        options,
                        &ranks,
                        &mut |_| Control::Continue,
                    )
                    .unwrap();
                    let render = RenderOptions {
                        threads: 1,
                        ..RenderOptions::default()
                    };
                    let (image, _) = meshlight::render::render_distributed(
                        scene,
                        &solution,
                        vis,
                        &render,
                        &ranks,
                        &mut |_| Control::Continue,
                    )
                    .unwrap();
                    (solution, image)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    })
}

fn same(a: &Solution, b: &Solution, what: &str) {
    assert_eq!(a.samples().len(), b.samples().len(), "{what}: samples");
    // Bit for bit: the same arithmetic in the same order.
    assert!(
        a.radiosity() == b.radiosity() && a.irradiance() == b.irradiance(),
        "{what}: the radiosity differs"
    );
    for (ra, rb) in a.rounds().iter().zip(b.rounds()) {
        assert_eq!(ra.shooting.links, rb.shooting.links, "{what}: links");
        assert_eq!(ra.shooting.shots, rb.shooting.shots, "{what}: sweeps");
        assert_eq!(ra.shooting.queries, rb.shooting.queries, "{what}: queries");
    }
}

fn check_scene(scene: &Scene, options: &Options, backends: &[Backend]) {
    for &backend in backends {
        let vis = backend.build(scene).unwrap();
        let one =
            meshlight::solve(scene, vis.as_ref(), options, &mut |_| Control::Continue).unwrap();
        let largest = |s: &Solution| {
            s.rounds()
                .iter()
                .max_by_key(|r| r.shooting.links)
                .map(|r| r.shooting)
                .unwrap()
        };
        assert!(largest(&one).links > 0);
        let render = RenderOptions {
            threads: 2,
            ..RenderOptions::default()
        };
        let (image, _) = meshlight::render(scene, &one, vis.as_ref(), &render, &mut |_| {
            Control::Continue
        })
        .unwrap();
        for size in [2, 3] {
            let (solutions, images): (Vec<Solution>, Vec<Image>) =
                on_ranks(scene, backend, options, size).into_iter().unzip();
            for (rank, (s, i)) in solutions.iter().zip(&images).enumerate() {
                same(&one, s, &format!("{backend:?}, rank {rank} of {size}"));
                assert!(
                    i.pixels == image.pixels,
                    "{backend:?}, rank {rank} of {size}: the image differs"
                );
            }
            let sh = largest(&solutions[0]);
            // The ranks hold the links between them, and none holds much more than its share:
            // at most 0.6 of all at 2 ranks (the groups are whole, so not exactly a half).
            let held: u64 = solutions.iter().map(|s| largest(s).held_links).sum();
            assert_eq!(
                held, sh.links,
                "{backend:?}, {size} ranks: held links add up"
            );
            assert_eq!(
                sh.most_held_links,
                solutions
                    .iter()
                    .map(|s| largest(s).held_links)
                    .max()
                    .unwrap()
            );
            let limit = if size == 2 { 0.6 } else { 0.45 };
            assert!(
                (sh.most_held_links as f64) <= limit * sh.links as f64,
                "{backend:?}, {size} ranks: a rank holds {} of {} links",
                sh.most_held_links,
                sh.links
            );
            assert!(sh.exchanged_bytes > 0);
        }
    }
}

#[test]
fn the_room_on_two_and_three_ranks_is_one_process_solve() {
    let scene = common::shipped_at("room", 96);
    let options = Options {
        threads: 1,
        ..Options::default()
    };
    check_scene(&scene, &options, &common::backends());
}

#[test]
#[ignore = "full tier: a large or repeated solve (cargo test -- --include-ignored)"]
fn a_reduced_gallery_on_two_and_three_ranks_is_one_process_solve() {
    let scene = common::shipped_at("gallery", 96);
    let options = Options {
        threads: 1,
        epsilon: Some(0.45),
        rounds: 1,
        ..Options::default()
    };
    // One backend: what the ranks share does not depend on the ray caster, which the room
    // above checks on every backend; the gallery adds its size (many groups, long messages).
    check_scene(&scene, &options, &[Backend::default_backend()]);
}
