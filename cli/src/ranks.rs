//! The processes a run is spread over: this one alone, or, built with the `mpi` feature and
//! launched by `mpirun` or `srun`, MPI's ranks. Rank 0 prints and writes; a rank that fails
//! ends the whole job (docs/distributed.md).

use std::sync::OnceLock;

use meshlight::distributed::{Ranks, Single};

static RANKS: OnceLock<Box<dyn Ranks + Send>> = OnceLock::new();

/// The job: keeps MPI initialised while it lives (finalised when it drops, at the end of main).
pub struct Job {
    #[cfg(feature = "mpi")]
    _universe: Option<mpi::environment::Universe>,
}

/// Joins the MPI job when launched as one (and built with the feature); else one process.
pub fn start() -> Job {
    #[cfg(feature = "mpi")]
    {
        if launched_by_mpi() {
            if let Some((universe, _)) = mpi::initialize_with_threading(mpi::Threading::Serialized)
            {
                let world = universe.world();
                let _ = RANKS.set(Box::new(mpi_ranks::Mpi { world }));
                if !root() {
                    quiet();
                }
                return Job {
                    _universe: Some(universe),
                };
            }
        }
        Job { _universe: None }
    }
    #[cfg(not(feature = "mpi"))]
    Job {}
}

/// The ranks this run is spread over.
pub fn ranks() -> &'static dyn Ranks {
    match RANKS.get() {
        Some(r) => r.as_ref(),
        None => &Single,
    }
}

/// Whether this process prints and writes: rank 0.
pub fn root() -> bool {
    ranks().rank() == 0
}

/// Ends the run after `message` (already printed): with other ranks, the whole job, at once,
/// since they may be waiting for this one in an exchange.
pub fn fail() -> std::process::ExitCode {
    #[cfg(feature = "mpi")]
    if ranks().size() > 1 {
        use mpi::traits::Communicator;
        mpi::topology::SimpleCommunicator::world().abort(1);
    }
    std::process::ExitCode::FAILURE
}

/// For the tests of a failing rank: with `MESHLIGHT_FAIL_RANK=r` in the environment, rank r
/// fails (panics) at its first sweep, as a rank that hits a bug mid-solve would.
pub fn injected_failure(progress: &meshlight::Progress) {
    if ranks().size() > 1 && progress.phase == meshlight::Phase::Shooting {
        let wanted = std::env::var("MESHLIGHT_FAIL_RANK").ok();
        if wanted.and_then(|r| r.parse::<usize>().ok()) == Some(ranks().rank()) {
            panic!(
                "rank {} failed on purpose (MESHLIGHT_FAIL_RANK)",
                ranks().rank()
            );
        }
    }
}

/// Open MPI, MPICH and Slurm each tell a process it is one of a job.
#[cfg(feature = "mpi")]
fn launched_by_mpi() -> bool {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "PMI_RANK"]
        .iter()
        .any(|v| std::env::var_os(v).is_some())
}

/// Where this rank's errors go when its stderr is quiet: the stderr it started with.
#[cfg(feature = "mpi")]
static ERRORS: OnceLock<std::fs::File> = OnceLock::new();

/// Ranks other than 0 print nothing, on stdout or stderr (progress, warnings, summaries are
/// rank 0's), but their errors: those go to the stderr they started with.
#[cfg(feature = "mpi")]
fn quiet() {
    use std::os::fd::{AsRawFd, FromRawFd};
    let Ok(null) = std::fs::OpenOptions::new().write(true).open("/dev/null") else {
        return;
    };
    // SAFETY: dup and dup2 on descriptors this process owns, before any thread starts; the
    // duplicate is owned by the File from here on.
    unsafe {
        let saved = libc::dup(2);
        if saved >= 0 {
            let _ = ERRORS.set(std::fs::File::from_raw_fd(saved));
        }
        libc::dup2(null.as_raw_fd(), 1);
        libc::dup2(null.as_raw_fd(), 2);
    }
}

/// Prints an error line where this rank's errors go (stderr, or the saved one when quiet).
pub fn report_error(line: &str) {
    #[cfg(feature = "mpi")]
    if let Some(mut file) = ERRORS.get() {
        use std::io::Write;
        let _ = writeln!(file, "{line}");
        return;
    }
    eprintln!("{line}");
}

#[cfg(feature = "mpi")]
mod mpi_ranks {
    use meshlight::distributed::Ranks;
    use meshlight::Error;
    use mpi::datatype::{Partition, PartitionMut};
    use mpi::topology::SimpleCommunicator;
    use mpi::traits::*;

    pub struct Mpi {
        pub world: SimpleCommunicator,
    }

    // SAFETY: MPI was initialised with MPI_THREAD_SERIALIZED, and the solver calls these
    // collectives from its coordinator alone, one call at a time.
    unsafe impl Sync for Mpi {}
    // SAFETY: as above; the handle is a process-wide communicator, not tied to a thread.
    unsafe impl Send for Mpi {}

    /// MPI's counts and displacements for `counts`, which must fit its 32-bit integers.
    fn partition(counts: &[usize]) -> meshlight::Result<(Vec<i32>, Vec<i32>)> {
        let too_many = || Error::Worker {
            problem: format!(
                "an exchange of {} values is beyond MPI's 32-bit counts",
                counts.iter().sum::<usize>()
            ),
        };
        let mut displs = Vec::with_capacity(counts.len());
        let mut sizes = Vec::with_capacity(counts.len());
        let mut at = 0usize;
        for &c in counts {
            displs.push(i32::try_from(at).map_err(|_| too_many())?);
            sizes.push(i32::try_from(c).map_err(|_| too_many())?);
            at += c;
        }
        Ok((sizes, displs))
    }

    impl Mpi {
        /// One MPI_Allgatherv of values of either kind.
        fn gather<T: Equivalence>(
            &self,
            mine: &[T],
            counts: &[usize],
            out: &mut [T],
        ) -> meshlight::Result<()> {
            // The library checked the lengths (`distributed::Checked`) before this call.
            let (sizes, displs) = partition(counts)?;
            let mut partition = PartitionMut::new(out, sizes, displs);
            self.world.all_gather_varcount_into(mine, &mut partition);
            Ok(())
        }
    }

    impl Ranks for Mpi {
        fn rank(&self) -> usize {
            self.world.rank() as usize
        }

        fn size(&self) -> usize {
            self.world.size() as usize
        }

        fn all_gather(
            &self,
            mine: &[f64],
            counts: &[usize],
            out: &mut [f64],
        ) -> meshlight::Result<()> {
            self.gather(mine, counts, out)
        }

        fn all_gather_words(
            &self,
            mine: &[u32],
            counts: &[usize],
            out: &mut [u32],
        ) -> meshlight::Result<()> {
            self.gather(mine, counts, out)
        }

        fn exchange(&self, to: &[Vec<u32>]) -> meshlight::Result<Vec<Vec<u32>>> {
            let size = self.size();
            let count = |n: usize| {
                i32::try_from(n).map_err(|_| Error::Worker {
                    problem: format!("an exchange of {n} words is beyond MPI's 32-bit counts"),
                })
            };
            if to.len() != size {
                return Err(Error::Worker {
                    problem: format!("an exchange for {} ranks among {size}", to.len()),
                });
            }
            let sizes = to
                .iter()
                .map(|v| count(v.len()))
                .collect::<Result<Vec<_>, _>>()?;
            let mut incoming = vec![0i32; size];
            self.world.all_to_all_into(&sizes[..], &mut incoming[..]);
            let offsets = |c: &[i32]| -> Result<Vec<i32>, Error> {
                let mut at = 0usize;
                c.iter()
                    .map(|&n| {
                        let here = count(at);
                        at += n as usize;
                        here
                    })
                    .collect()
            };
            let send: Vec<u32> = to.concat();
            let mut received = vec![0u32; incoming.iter().map(|&n| n as usize).sum()];
            {
                let out_displs = offsets(&sizes)?;
                let in_displs = offsets(&incoming)?;
                let outgoing = Partition::new(&send[..], &sizes[..], &out_displs[..]);
                let mut partition =
                    PartitionMut::new(&mut received[..], &incoming[..], &in_displs[..]);
                self.world
                    .all_to_all_varcount_into(&outgoing, &mut partition);
            }
            let mut from = Vec::with_capacity(size);
            let mut at = 0usize;
            for &n in &incoming {
                from.push(received[at..at + n as usize].to_vec());
                at += n as usize;
            }
            Ok(from)
        }
    }
}
