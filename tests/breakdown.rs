//! Where a solution's memory goes: the breakdown `Solution::memory` reports (and `meshlight
//! scale` prints per sample) against what the allocator saw, and the transient peak of a solve
//! against what the solution keeps.

mod common;

use common::counting::{self, Counting};
use common::shipped;
use meshlight::solver::{Control, Options};
use meshlight::{Backend, Scene};

#[global_allocator]
static ALLOCATOR: Counting = Counting;

#[test]
fn the_breakdown_is_what_the_allocator_saw_and_the_peak_is_bounded() {
    // The room at the defaults (adaptive rounds on): the last round's split is the largest
    // transient.
    let room = Scene::load(shipped("room")).unwrap();
    let vis = Backend::Bvh.build(&room).unwrap();
    let before = counting::live();
    counting::reset_peak();
    let s = meshlight::solve(&room, vis.as_ref(), &Options::default(), &mut |_| {
        Control::Continue
    })
    .unwrap();
    let kept = (counting::live() - before) as f64;
    let peak = (counting::peak() - before) as f64;
    let m = s.memory();
    let n = s.samples().len() as f64;
    eprintln!(
        "{n} samples; breakdown {m:?}: {:.0} bytes a sample; the allocator: kept {:.0}, peak {:.0}; links {:?}",
        m.total() as f64 / n,
        kept / n,
        peak / n,
        s.rounds().iter().map(|r| r.shooting.bytes).collect::<Vec<_>>()
    );
    assert_eq!(m.total(), s.bytes());
    // What the solution keeps beyond the breakdown is small: the rounds' statistics, the
    // obstruction flags, the maps' grids.
    assert!(
        m.total() as f64 <= kept && m.total() as f64 >= 0.85 * kept,
        "the breakdown says {} bytes, the allocator {kept}",
        m.total()
    );
    // At its peak a solve holds the solution, the links of its largest round, and for a
    // moment a second copy of the shares and cells (the last round's split, before they are
    // gathered by sample) but no more.
    let links = s.rounds().iter().map(|r| r.shooting.bytes).max().unwrap() as f64;
    let bound = kept + links + (m.shares + m.cells) as f64;
    assert!(
        peak <= bound,
        "peak {peak} bytes, over {bound}: kept {kept}, links {links}"
    );
}
