//! How a stage runs: its worker threads, the seed of its random choices and the processes it
//! is spread over, handed down the stages as one value. Progress is not in it: each stage
//! reports its own share of its phase through the callback it is given.

use crate::distributed::{Ranks, Single};
use crate::error::Result;

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

    /// [`for_chunks_halting`](crate::parallel::for_chunks_halting) over this rank's run of
    /// `out` ([`share_of`](crate::distributed::share_of)), then every rank's run to every rank
    /// as `W` numbers an item. Whether every rank went through its run (a Stop on any rank: no;
    /// a chunk that gave up on the [`Halt`](crate::parallel::Halt) must then not be read).
    pub(crate) fn for_share<T: Send, const W: usize>(
        self,
        out: &mut [T],
        chunk: usize,
        f: impl Fn(usize, &mut [T], &crate::parallel::Halt) -> Result<()> + Sync,
        report: crate::parallel::Report,
        put: impl Fn(&T) -> [f64; W],
        take: impl Fn(&[f64]) -> T,
    ) -> Result<bool> {
        let ranks = self.ranks;
        let mine = crate::distributed::share_of(ranks, out.len(), chunk);
        let offset = mine.start;
        let all = crate::parallel::for_chunks_halting(
            &mut out[mine],
            chunk,
            self.threads,
            |first, part, halt| f(offset + first, part, halt),
            report,
        )?;
        let all = !crate::distributed::any(ranks, !all)?;
        crate::distributed::gather_shares(ranks, out, chunk, put, take)?;
        Ok(all)
    }
}
