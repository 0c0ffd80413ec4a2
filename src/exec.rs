//! How a stage runs: its worker threads, the seed of its random choices and the processes it
//! is spread over, handed down the stages as one value. Progress is not in it: each stage
//! reports its own share of its phase through the callback it is given.

use crate::distributed::{Ranks, Single};

/// Threads, seed and ranks of a stage.
#[derive(Clone, Copy)]
pub(crate) struct Exec<'a> {
    /// Worker threads (at least 1).
    pub threads: usize,
    /// The seed of every random choice.
    pub seed: u64,
    /// The processes the work is shared out over (one: [`Single`]).
    pub ranks: &'a dyn Ranks,
}

impl<'a> Exec<'a> {
    /// A stage on `threads` threads (0 counts as 1) of the processes `ranks`.
    pub(crate) fn new(threads: usize, seed: u64, ranks: &'a dyn Ranks) -> Exec<'a> {
        Exec {
            threads: threads.max(1),
            seed,
            ranks,
        }
    }

    /// A stage of one process.
    pub(crate) fn local(threads: usize, seed: u64) -> Exec<'static> {
        Exec::new(threads, seed, &Single)
    }
}
