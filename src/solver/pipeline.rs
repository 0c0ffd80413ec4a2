//! The streaming pipeline the solvers run their heavy work on: the coordinator cuts work into
//! jobs and sends them over a bounded crossbeam channel to worker threads, which send results
//! back over another; the coordinator applies results in job order, whatever order they come
//! back in. So the answer is the same for any number of workers and any channel capacity, and
//! at most `capacity` jobs (and their results) are in flight: memory stays flat however much
//! work there is.
//!
//! A worker that fails or panics (a host's own `Visibility`, say) ends the run with an error
//! naming what happened; no worker dies silently and the coordinator never waits forever.

use std::collections::VecDeque;
use std::ops::ControlFlow;
use std::thread::Scope;

use crossbeam_channel::{bounded, Receiver, Sender};

use crate::error::{Error, Result};

/// A pool of workers running `work` on jobs of type `I`, giving results of type `O`.
pub(crate) struct Pool<'a, I, O> {
    capacity: usize,
    /// Jobs to the workers.
    jobs: Sender<(usize, I)>,
    /// Results back, with their job's index.
    done: Receiver<(usize, Result<O>)>,
    _work: std::marker::PhantomData<&'a ()>,
}

/// How long the coordinator waits for a result before it ticks (see [`Pool::run_ticking`]).
pub(crate) const TICK_SECONDS: f64 = 0.2;
const TICK: std::time::Duration = std::time::Duration::from_millis((TICK_SECONDS * 1000.0) as u64);

/// Runs `body` with a pool of `threads` workers (at least one: the coordinator stays free to
/// tick) that apply `work` to the jobs `body` hands it, with at most `capacity` jobs in flight.
pub(crate) fn with_pool<I: Send, O: Send, R>(
    threads: usize,
    capacity: usize,
    work: &(dyn Fn(I) -> Result<O> + Sync),
    body: impl FnOnce(&mut Pool<'_, I, O>) -> Result<R>,
) -> Result<R> {
    let capacity = capacity.max(1);
    std::thread::scope(|scope| {
        let mut pool = Pool::spawn(scope, threads.max(1), capacity, work);
        let result = body(&mut pool);
        // Closing the job channel ends the workers once they finish what they hold.
        drop(pool);
        result
    })
}

impl<'a, I: Send, O: Send> Pool<'a, I, O> {
    fn spawn<'s>(
        scope: &'s Scope<'s, '_>,
        threads: usize,
        capacity: usize,
        work: &'a (dyn Fn(I) -> Result<O> + Sync),
    ) -> Pool<'a, I, O>
    where
        'a: 's,
    {
        let (jobs, job_rx) = bounded::<(usize, I)>(capacity);
        let (done_tx, done) = bounded::<(usize, Result<O>)>(capacity);
        for _ in 0..threads {
            let (job_rx, done_tx) = (job_rx.clone(), done_tx.clone());
            scope.spawn(move || {
                for (index, job) in job_rx {
                    if done_tx.send((index, run(work, job))).is_err() {
                        break;
                    }
                }
            });
        }
        Pool {
            capacity,
            jobs,
            done,
            _work: std::marker::PhantomData,
        }
    }

    /// Runs every job of `jobs` and hands each result to `apply` in job order (with its index
    /// within this run). Stops at the first error, from a job or from `apply`, and sends no
    /// more jobs once `apply` answers `Break` (the jobs in flight are finished and dropped).
    pub fn run(
        &mut self,
        jobs: impl IntoIterator<Item = I>,
        apply: impl FnMut(usize, O) -> Result<ControlFlow<()>>,
    ) -> Result<ControlFlow<()>> {
        self.run_ticking(jobs, apply, || ControlFlow::Continue(()))
    }

    /// [`Pool::run`] that also calls `tick` on the coordinator whenever [`TICK_SECONDS`] pass
    /// without a result (a job of a slow backend can take seconds): its `Break` stops the run
    /// as `apply`'s does. Jobs that should give up part-way on a stop must be told so by the
    /// caller (a flag `tick` sets and `work` reads).
    pub fn run_ticking(
        &mut self,
        jobs: impl IntoIterator<Item = I>,
        mut apply: impl FnMut(usize, O) -> Result<ControlFlow<()>>,
        mut tick: impl FnMut() -> ControlFlow<()>,
    ) -> Result<ControlFlow<()>> {
        let (sender, receiver) = (&self.jobs, &self.done);
        let mut jobs = jobs.into_iter();
        let (mut sent, mut in_flight, mut next) = (0usize, 0usize, 0usize);
        // Results that came back before those ahead of them: slot k holds job next + k.
        let mut waiting: VecDeque<Option<O>> = VecDeque::new();
        let mut failure = None;
        let mut stopped = false;
        loop {
            while failure.is_none() && !stopped && in_flight < self.capacity {
                let Some(job) = jobs.next() else { break };
                sender
                    .send((sent, job))
                    .map_err(|_| worker_error("the workers are gone"))?;
                sent += 1;
                in_flight += 1;
            }
            if in_flight == 0 {
                break;
            }
            let (index, result) = match receiver.recv_timeout(TICK) {
                Ok(got) => got,
                Err(crossbeam_channel::RecvTimeoutError::Timeout) => {
                    if failure.is_none() && !stopped {
                        stopped = tick().is_break();
                    }
                    continue;
                }
                Err(crossbeam_channel::RecvTimeoutError::Disconnected) => {
                    return Err(worker_error("the workers are gone"))
                }
            };
            in_flight -= 1;
            if failure.is_some() || stopped {
                // Draining what is in flight, so no worker is left waiting.
                continue;
            }
            match result {
                Err(e) => failure = Some(e),
                Ok(out) => {
                    let slot = index - next;
                    if waiting.len() <= slot {
                        waiting.resize_with(slot + 1, || None);
                    }
                    waiting[slot] = Some(out);
                    while let Some(Some(_)) = waiting.front() {
                        let out = waiting.pop_front().flatten().expect("checked above");
                        match apply(next, out) {
                            Err(e) => failure = Some(e),
                            Ok(flow) => stopped = flow.is_break(),
                        }
                        next += 1;
                        if failure.is_some() || stopped {
                            break;
                        }
                    }
                }
            }
        }
        match (failure, stopped) {
            (Some(e), _) => Err(e),
            (None, true) => Ok(ControlFlow::Break(())),
            (None, false) => Ok(ControlFlow::Continue(())),
        }
    }
}

impl<I: Send, O: Send> Pool<'_, I, O> {
    /// [`Pool::run`] for an `apply` that never stops early.
    pub fn run_all(
        &mut self,
        jobs: impl IntoIterator<Item = I>,
        mut apply: impl FnMut(usize, O) -> Result<()>,
    ) -> Result<()> {
        self.run(jobs, |i, out| {
            apply(i, out).map(|()| ControlFlow::Continue(()))
        })
        .map(|_| ())
    }
}

/// Runs one job, turning a panic into an error.
fn run<I, O>(work: &(dyn Fn(I) -> Result<O> + Sync), job: I) -> Result<O> {
    crate::parallel::guarded("a worker", || work(job))
}

fn worker_error(problem: &str) -> Error {
    Error::Worker {
        problem: problem.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn squares(threads: usize, capacity: usize) -> Vec<(usize, u64)> {
        let work = |x: u64| -> Result<u64> {
            // Uneven job lengths, so results come back out of order with several workers.
            std::thread::sleep(std::time::Duration::from_micros((x * 7919) % 300));
            Ok(x * x)
        };
        let mut out = Vec::new();
        with_pool(threads, capacity, &work, |pool| {
            pool.run_all(0..100u64, |i, y| {
                out.push((i, y));
                Ok(())
            })?;
            // A pool serves several runs.
            pool.run_all(100..110u64, |i, y| {
                out.push((i, y));
                Ok(())
            })
        })
        .unwrap();
        out
    }

    #[test]
    fn results_arrive_in_job_order_for_any_thread_count_and_capacity() {
        let expected: Vec<(usize, u64)> = (0..100u64)
            .map(|x| (x as usize, x * x))
            .chain((100..110u64).map(|x| (x as usize - 100, x * x)))
            .collect();
        for (threads, capacity) in [(1, 1), (2, 1), (2, 2), (3, 8), (2, 1000)] {
            assert_eq!(squares(threads, capacity), expected, "{threads} {capacity}");
        }
    }

    #[test]
    fn breaking_stops_sending_jobs() {
        let work = |x: u32| -> Result<u32> { Ok(x) };
        for threads in [1, 2] {
            let mut seen = Vec::new();
            let flow = with_pool(threads, 3, &work, |pool| {
                pool.run(0..1000u32, |i, x| {
                    seen.push(x);
                    Ok(if i == 9 {
                        ControlFlow::Break(())
                    } else {
                        ControlFlow::Continue(())
                    })
                })
            })
            .unwrap();
            assert!(flow.is_break());
            assert_eq!(seen, (0..10).collect::<Vec<u32>>());
        }
    }

    #[test]
    fn a_panicking_job_is_an_error_not_a_hang() {
        let work = |x: u32| -> Result<u32> {
            if x == 37 {
                panic!("job {x} fails");
            }
            Ok(x)
        };
        for threads in [1, 2] {
            let e = with_pool(threads, 4, &work, |pool| {
                pool.run_all(0..1000u32, |_, _| Ok(()))
            })
            .unwrap_err()
            .to_string();
            assert!(e.contains("job 37 fails"), "{e}");
        }
    }
}
