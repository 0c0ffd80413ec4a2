//! One solve spread over several processes (MPI ranks, say): what the solver needs of the
//! transport between them, so that the library itself links no MPI.
//!
//! Every rank runs the same solve on the same scene and options. What is cheap to repeat or
//! must be the same everywhere is replicated: the geometry, the visibility structure, the
//! samples (placed deterministically), the cluster tree and the per-sample state. The work is
//! dealt out where one process cuts it (sides, runs of cells, chunks of samples or pixels, link
//! jobs) and what each rank finds is all-gathered; the cluster tree's receiver groups go to the
//! ranks in contiguous runs of about equal links, and each rank keeps only the links into its
//! own groups, so the links held per rank fall about as 1/N. Each sweep every rank gathers its
//! groups' irradiance and one all-gather gives every rank everyone's (24 bytes a sample); the
//! rest of the sweep is the same arithmetic in the same order on every rank, so the result is
//! the single-process solve's, bit for bit. See `docs/distributed.md`.
//!
//! The CLI implements [`Ranks`] over MPI (its `mpi` feature); a host may implement it over its
//! own transport. [`Single`] is one process alone, what [`solve`](crate::solve) uses.

use crate::error::{Error, Result};

/// The collective operations a distributed solve needs. Every rank calls them in the same
/// order with the same `counts`; each call returns on every rank or fails.
///
/// A rank that fails between calls leaves the others waiting in the next one: the
/// implementation (or its host) must end the whole job then (`MPI_Abort`, as the CLI does).
pub trait Ranks: Sync {
    /// This process's rank, `0..size()`.
    fn rank(&self) -> usize;
    /// How many ranks take part.
    fn size(&self) -> usize;
    /// Every rank's `mine` concatenated in rank order into `out`: rank r gives `counts[r]`
    /// values, and `out.len()` is their sum.
    fn all_gather(&self, mine: &[f64], counts: &[usize], out: &mut [f64]) -> Result<()>;

    /// [`all_gather`](Ranks::all_gather) for 32-bit words (shares, link lists). The default
    /// carries each word as an f64 (exact); an implementation over MPI overrides it to move
    /// 4 bytes a word, not 8.
    fn all_gather_words(&self, mine: &[u32], counts: &[usize], out: &mut [u32]) -> Result<()> {
        let values: Vec<f64> = mine.iter().map(|&w| f64::from(w)).collect();
        let mut all = vec![0.0; out.len()];
        self.all_gather(&values, counts, &mut all)?;
        for (o, v) in out.iter_mut().zip(all) {
            *o = v as u32;
        }
        Ok(())
    }

    /// Sends `to[r]` to each rank r (`to.len()` is `size()`) and returns what each rank sent
    /// this one, in rank order. The default goes through [`all_gather`](Ranks::all_gather),
    /// every rank receiving everything; an implementation over MPI overrides it with one
    /// `MPI_Alltoallv`.
    fn exchange(&self, to: &[Vec<u32>]) -> Result<Vec<Vec<u32>>> {
        let (me, size) = (self.rank(), self.size().max(1));
        if to.len() != size {
            return Err(Error::Worker {
                problem: format!("an exchange for {} ranks among {size}", to.len()),
            });
        }
        // Everyone's lengths first: lengths[r * size + t] is what r sends t.
        let lengths: Vec<f64> = to.iter().map(|v| v.len() as f64).collect();
        let mut all = vec![0.0; size * size];
        self.all_gather(&lengths, &vec![size; size], &mut all)?;
        let counts: Vec<usize> = (0..size)
            .map(|r| all[r * size..(r + 1) * size].iter().sum::<f64>() as usize)
            .collect();
        let mine: Vec<f64> = to.iter().flatten().map(|&w| f64::from(w)).collect();
        let mut everything = vec![0.0; counts.iter().sum()];
        self.all_gather(&mine, &counts, &mut everything)?;
        let mut from = Vec::with_capacity(size);
        let mut at = 0;
        for r in 0..size {
            let row = &all[r * size..(r + 1) * size];
            let before: usize = row[..me].iter().sum::<f64>() as usize;
            let length = row[me] as usize;
            from.push(
                everything[at + before..at + before + length]
                    .iter()
                    .map(|&w| w as u32)
                    .collect(),
            );
            at += counts[r];
        }
        Ok(from)
    }
}

/// One process: nothing to exchange.
#[derive(Clone, Copy, Debug, Default)]
pub struct Single;

impl Ranks for Single {
    fn rank(&self) -> usize {
        0
    }

    fn size(&self) -> usize {
        1
    }

    fn all_gather(&self, mine: &[f64], counts: &[usize], out: &mut [f64]) -> Result<()> {
        check(mine.len(), counts, out.len(), 0)?;
        out.copy_from_slice(mine);
        Ok(())
    }

    fn exchange(&self, to: &[Vec<u32>]) -> Result<Vec<Vec<u32>>> {
        Ok(to.to_vec())
    }
}

/// Checks one all-gather's lengths (`rank` giving `mine` values into `out`): done before every
/// call to a host's transport, so an implementation need not.
pub(crate) fn check(mine: usize, counts: &[usize], out: usize, rank: usize) -> Result<()> {
    let total: usize = counts.iter().sum();
    if counts.get(rank) != Some(&mine) || total != out {
        return Err(Error::Worker {
            problem: format!(
                "an all-gather's lengths disagree on rank {rank}: gives {}, counts {:?}, \
                 receives {}",
                mine, counts, out
            ),
        });
    }
    Ok(())
}

/// The most ranks a solve may be spread over: beyond, the bookkeeping that grows with the
/// ranks (an exchange's lengths are ranks² numbers) would not fit, and no solve gains.
pub const MAX_RANKS: usize = 4096;

/// A host's transport, checked: its rank and size taken once and held to (a rank that changes
/// between calls is an error), and every answer of its collectives checked before the solver
/// uses it — numbers finite, words whole, what this rank gave handed back unchanged — so that a
/// faulty transport is an error that names it, not a wrong image.
pub(crate) struct Checked<'a> {
    inner: &'a dyn Ranks,
    rank: usize,
    size: usize,
}

impl<'a> Checked<'a> {
    /// The transport, if its rank and size make sense.
    pub(crate) fn new(inner: &'a dyn Ranks) -> Result<Checked<'a>> {
        let (rank, size) = (inner.rank(), inner.size());
        if !(1..=MAX_RANKS).contains(&size) || rank >= size {
            return Err(Error::argument(
                "ranks",
                format!("rank {rank} of {size} ranks: the size must lie in 1..={MAX_RANKS}, the rank below it"),
            ));
        }
        Ok(Checked { inner, rank, size })
    }

    fn fault(problem: String) -> Error {
        Error::Worker {
            problem: format!("the ranks' transport failed its check: {problem}"),
        }
    }

    /// Whether the transport still says what it said at first.
    fn steady(&self) -> Result<()> {
        let (rank, size) = (self.inner.rank(), self.inner.size());
        if (rank, size) != (self.rank, self.size) {
            return Err(Self::fault(format!(
                "it said rank {} of {}, now rank {rank} of {size}",
                self.rank, self.size
            )));
        }
        Ok(())
    }

    /// Where this rank's values start in a gather of `counts`.
    fn offset(&self, counts: &[usize]) -> usize {
        counts[..self.rank].iter().sum()
    }
}

impl Ranks for Checked<'_> {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.size
    }

    fn all_gather(&self, mine: &[f64], counts: &[usize], out: &mut [f64]) -> Result<()> {
        self.steady()?;
        check(mine.len(), counts, out.len(), self.rank)?;
        self.inner.all_gather(mine, counts, out)?;
        if let Some(bad) = out.iter().find(|v| !v.is_finite()) {
            return Err(Self::fault(format!("an all-gather handed back {bad}")));
        }
        let at = self.offset(counts);
        if out[at..at + mine.len()] != *mine {
            return Err(Self::fault(format!(
                "an all-gather handed rank {}'s own values back changed",
                self.rank
            )));
        }
        Ok(())
    }

    fn all_gather_words(&self, mine: &[u32], counts: &[usize], out: &mut [u32]) -> Result<()> {
        self.steady()?;
        check(mine.len(), counts, out.len(), self.rank)?;
        self.inner.all_gather_words(mine, counts, out)?;
        let at = self.offset(counts);
        if out[at..at + mine.len()] != *mine {
            return Err(Self::fault(format!(
                "an all-gather of words handed rank {}'s own words back changed",
                self.rank
            )));
        }
        Ok(())
    }

    fn exchange(&self, to: &[Vec<u32>]) -> Result<Vec<Vec<u32>>> {
        self.steady()?;
        let from = self.inner.exchange(to)?;
        if from.len() != self.size {
            return Err(Self::fault(format!(
                "an exchange among {} ranks gave {} lists",
                self.size,
                from.len()
            )));
        }
        if to.get(self.rank) != from.get(self.rank) {
            return Err(Self::fault(format!(
                "an exchange handed rank {}'s words to itself changed",
                self.rank
            )));
        }
        Ok(from)
    }
}

/// A rank's place alone, to work out what another rank gives (its collectives are not used).
pub(crate) struct Fixed {
    pub rank: usize,
    pub size: usize,
}

impl Ranks for Fixed {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.size
    }

    fn all_gather(&self, _: &[f64], _: &[usize], _: &mut [f64]) -> Result<()> {
        Err(Error::Worker {
            problem: "a rank's place was asked to exchange".into(),
        })
    }
}

/// Each rank's values gathered: `out[r]` is what rank r gave (one value each).
pub(crate) fn gather_one(ranks: &dyn Ranks, value: f64) -> Result<Vec<f64>> {
    let n = ranks.size().max(1);
    let mut out = vec![0.0; n];
    ranks.all_gather(&[value], &vec![1; n], &mut out)?;
    Ok(out)
}

/// Every rank's `mine` (32-bit words) concatenated in rank order, on every rank, with what
/// each rank gave.
pub(crate) fn all_gather_words(ranks: &dyn Ranks, mine: &[u32]) -> Result<(Vec<u32>, Vec<usize>)> {
    let counts: Vec<usize> = gather_one(ranks, mine.len() as f64)?
        .iter()
        .map(|&c| c as usize)
        .collect();
    let mut out = vec![0; counts.iter().sum()];
    ranks.all_gather_words(mine, &counts, &mut out)?;
    Ok((out, counts))
}

/// Whether item `i` of a list dealt in turn (rank r takes items r, r + N, …) is this rank's.
pub(crate) fn deals(ranks: &dyn Ranks, i: usize) -> bool {
    i % ranks.size().max(1) == ranks.rank()
}

/// This rank's run of `len` items cut in chunks of `chunk`: whole chunks, so that each rank
/// cuts its run where one process would (work done chunk by chunk then does not depend on the
/// ranks either).
pub(crate) fn share_of(ranks: &dyn Ranks, len: usize, chunk: usize) -> std::ops::Range<usize> {
    let (rank, size) = (ranks.rank(), ranks.size().max(1));
    let chunks = len.div_ceil(chunk.max(1));
    let edge = |r: usize| (r * chunks / size * chunk).min(len);
    edge(rank)..edge(rank + 1)
}

/// Every rank's run of `out` ([`share_of`]) to every rank, as `W` numbers an item.
pub(crate) fn gather_shares<T, const W: usize>(
    ranks: &dyn Ranks,
    out: &mut [T],
    chunk: usize,
    put: impl Fn(&T) -> [f64; W],
    take: impl Fn(&[f64]) -> T,
) -> Result<()> {
    let size = ranks.size().max(1);
    if size == 1 {
        return Ok(());
    }
    let counts: Vec<usize> = (0..size)
        .map(|rank| W * share_of(&Fixed { rank, size }, out.len(), chunk).len())
        .collect();
    let mine: Vec<f64> = out[share_of(ranks, out.len(), chunk)]
        .iter()
        .flat_map(&put)
        .collect();
    let mut all = vec![0.0; W * out.len()];
    ranks.all_gather(&mine, &counts, &mut all)?;
    for (item, values) in out.iter_mut().zip(all.chunks_exact(W)) {
        *item = take(values);
    }
    Ok(())
}

/// Lists filled rank by rank (each rank the lists it [`deals`]) to every rank, as `W`
/// numbers an item.
pub(crate) fn share_lists<T, const W: usize>(
    ranks: &dyn Ranks,
    lists: &mut [Vec<T>],
    put: impl Fn(&T) -> [f64; W],
    take: impl Fn(&[f64]) -> T,
) -> Result<()> {
    if ranks.size() <= 1 {
        return Ok(());
    }
    // Per list: its index, its length, then its items.
    let mut mine = Vec::new();
    for (i, list) in lists.iter().enumerate().filter(|&(i, _)| deals(ranks, i)) {
        mine.extend([i as f64, list.len() as f64]);
        for item in list {
            mine.extend(put(item));
        }
    }
    let counts: Vec<usize> = gather_one(ranks, mine.len() as f64)?
        .iter()
        .map(|&c| c as usize)
        .collect();
    let mut all = vec![0.0; counts.iter().sum()];
    ranks.all_gather(&mine, &counts, &mut all)?;
    drop(mine);
    let broken = || Error::Worker {
        problem: "a rank sent lists that do not read back (a transport error)".into(),
    };
    let mut at = 0;
    while at < all.len() {
        let head = all.get(at..at + 2).ok_or_else(broken)?;
        let (i, len) = (head[0] as usize, head[1] as usize);
        at += 2;
        let body = all.get(at..at + W * len).ok_or_else(broken)?;
        at += W * len;
        if !deals(ranks, i) {
            *lists.get_mut(i).ok_or_else(broken)? = body.chunks_exact(W).map(&take).collect();
        }
    }
    Ok(())
}

/// A count summed over the ranks.
pub(crate) fn sum_over(ranks: &dyn Ranks, count: u64) -> Result<u64> {
    if ranks.size() <= 1 {
        return Ok(count);
    }
    Ok(gather_one(ranks, count as f64)?.iter().sum::<f64>() as u64)
}

/// Whether any rank says yes.
pub(crate) fn any(ranks: &dyn Ranks, yes: bool) -> Result<bool> {
    if ranks.size() <= 1 {
        return Ok(yes);
    }
    Ok(gather_one(ranks, if yes { 1.0 } else { 0.0 })?
        .iter()
        .any(|&v| v != 0.0))
}

/// The rank that owns each item given its weight: contiguous runs of about equal weight, an
/// item going to the rank its weight's middle falls in (receiver groups by their links, so that
/// a rank's groups' samples are one run of the tree's order).
pub(crate) fn owners(weights: &[usize], size: usize) -> Vec<usize> {
    let size = size.max(1);
    let total: usize = weights.iter().sum();
    let mut first = 0usize;
    weights
        .iter()
        .map(|&m| {
            let middle = first + m / 2;
            first += m;
            (middle * size)
                .checked_div(total)
                .map_or(0, |r| r.min(size - 1))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn owners_are_contiguous_and_balanced() {
        // Ten groups of 100 samples over three ranks: the middles 50, 150, ... 950 against
        // thirds of 1000 (333, 667): groups 0-2, 3-6, 7-9.
        let owner = owners(&[100; 10], 3);
        assert_eq!(owner, vec![0, 0, 0, 1, 1, 1, 1, 2, 2, 2]);
        // One rank owns everything; no samples at all is rank 0's.
        assert_eq!(owners(&[5, 7, 1], 1), vec![0, 0, 0]);
        assert_eq!(owners(&[0, 0], 4), vec![0, 0]);
        // A group far larger than the others still goes to one rank (its middle, 501 of
        // 1002, is in the second half).
        assert_eq!(owners(&[1, 1000, 1], 2), vec![0, 1, 1]);
    }

    #[test]
    fn single_checks_lengths() {
        let mut out = [0.0; 2];
        assert!(Single.all_gather(&[1.0, 2.0], &[2], &mut out).is_ok());
        assert_eq!(out, [1.0, 2.0]);
        assert!(Single.all_gather(&[1.0], &[2], &mut out).is_err());
        assert!(any(&Single, true).unwrap());
        assert!(!any(&Single, false).unwrap());
    }
}
