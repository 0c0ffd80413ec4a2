//! Deterministic data parallelism on scoped threads: an output slice is cut into fixed chunks,
//! threads take chunks from a shared counter, and each chunk's result depends only on its
//! index, so the answer is the same for any thread count.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use std::panic::{catch_unwind, AssertUnwindSafe};

use crate::error::{Error, Result};
use crate::progress::Control;

/// Runs `f`, turning a panic (in a host's own `Visibility`, say) into [`Error::Worker`] naming
/// `what` and the panic's message: a host must never be taken down by the library.
pub(crate) fn guarded<R>(what: &str, f: impl FnOnce() -> Result<R>) -> Result<R> {
    caught(f).unwrap_or_else(|message| {
        Err(Error::Worker {
            problem: format!("{what} panicked: {message}"),
        })
    })
}

/// Runs `f`; its panic's message if it panicked.
pub(crate) fn caught<R>(f: impl FnOnce() -> R) -> std::result::Result<R, String> {
    catch_unwind(AssertUnwindSafe(f)).map_err(|panic| {
        panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "a panic without a message".into())
    })
}

/// Fills `out` chunk by chunk: `f(first_index, chunk)`, on up to `threads` threads.
pub(crate) fn for_chunks<T: Send>(
    out: &mut [T],
    chunk: usize,
    threads: usize,
    f: impl Fn(usize, &mut [T]) -> Result<()> + Sync,
) -> Result<()> {
    let chunk = chunk.max(1);
    let threads = threads.max(1).min(out.len().div_ceil(chunk).max(1));
    if threads == 1 {
        for (i, c) in out.chunks_mut(chunk).enumerate() {
            guarded("a worker", || f(i * chunk, c))?;
        }
        return Ok(());
    }
    let chunks: Vec<Mutex<Option<&mut [T]>>> =
        out.chunks_mut(chunk).map(|c| Mutex::new(Some(c))).collect();
    let next = AtomicUsize::new(0);
    let first_error: Mutex<Option<crate::error::Error>> = Mutex::new(None);
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(slot) = chunks.get(i) else { break };
                let Some(c) = slot.lock().unwrap_or_else(|e| e.into_inner()).take() else {
                    continue;
                };
                if let Err(e) = guarded("a worker", || f(i * chunk, c)) {
                    first_error
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .get_or_insert(e);
                    break;
                }
            });
        }
    });
    match first_error.into_inner().unwrap_or_else(|e| e.into_inner()) {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// How a long parallel job tells its caller how far it has got: the share done, in [0, 1],
/// called on the calling thread between parts of the work; the answer says whether to go on.
pub(crate) type Report<'a> = &'a mut dyn FnMut(f64) -> Control;

/// [`for_chunks`] in parts, with `report` after each: at least `PARTS` parts, and parts sized
/// to take about `PART_SECONDS` each (a slow backend gets small parts), so a host hears from
/// the call several times a second and a Stop is honoured within about that. Part boundaries
/// fall on chunk boundaries, so the chunks and their results are the same as one call's.
/// `report(0.0)` is asked first: a Stop already given leaves everything untouched. Whether
/// every part was done: a [`Control::Stop`] leaves the parts after it untouched.
pub(crate) fn for_chunks_reporting<T: Send>(
    out: &mut [T],
    chunk: usize,
    threads: usize,
    f: impl Fn(usize, &mut [T]) -> Result<()> + Sync,
    report: Report,
) -> Result<bool> {
    const PARTS: usize = 20;
    const PART_SECONDS: f64 = 0.2;
    let chunk = chunk.max(1);
    let threads = threads.max(1);
    let total = out.len();
    if total > 0 && report(0.0) == Control::Stop {
        return Ok(false);
    }
    let largest = total.div_ceil(PARTS).div_ceil(chunk).max(1) * chunk;
    // Start with a chunk per thread; then as many as take about PART_SECONDS.
    let mut part = (threads * chunk).min(largest);
    let mut done = 0;
    while done < total {
        let len = part.min(total - done);
        let first = done;
        let started = std::time::Instant::now();
        for_chunks(&mut out[first..first + len], chunk, threads, |i, c| {
            f(first + i, c)
        })?;
        done += len;
        if report(done as f64 / total as f64) == Control::Stop && done < total {
            return Ok(false);
        }
        let per_item = started.elapsed().as_secs_f64() / len as f64;
        let wanted = (PART_SECONDS / per_item.max(1e-12)).min(total as f64) as usize;
        part = (wanted / chunk)
            .max(threads)
            .saturating_mul(chunk)
            .min(largest);
    }
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reporting_in_parts_gives_the_same_chunks_and_counts_up_to_one() {
        let f = |first: usize, c: &mut [u64]| {
            // Each chunk's value depends on its first index and length only.
            let len = c.len();
            for (i, x) in c.iter_mut().enumerate() {
                *x = (first * 1000 + len * 10 + i) as u64;
            }
            Ok(())
        };
        for threads in [1, 2] {
            let (mut a, mut b) = (vec![0u64; 10_007], vec![0u64; 10_007]);
            for_chunks(&mut a, 64, threads, f).unwrap();
            let mut reports = Vec::new();
            let all = for_chunks_reporting(&mut b, 64, threads, f, &mut |x| {
                reports.push(x);
                Control::Continue
            });
            assert!(all.unwrap());
            assert_eq!(a, b);
            assert!(reports.windows(2).all(|w| w[0] < w[1]), "{reports:?}");
            assert_eq!(reports.last(), Some(&1.0));
            assert!(reports.len() >= 10, "{}", reports.len());
        }
    }

    #[test]
    fn a_stop_leaves_the_later_parts_untouched() {
        let mut out = vec![0u32; 1000];
        let mut reports = 0;
        let all = for_chunks_reporting(
            &mut out,
            10,
            2,
            |_, c| {
                c.fill(1);
                Ok(())
            },
            &mut |_| {
                reports += 1;
                Control::Stop
            },
        );
        assert!(!all.unwrap());
        // Asked first: nothing is done.
        assert_eq!(reports, 1);
        assert!(out.iter().all(|&x| x == 0));

        let mut reports = 0;
        let all = for_chunks_reporting(
            &mut out,
            10,
            2,
            |_, c| {
                c.fill(1);
                Ok(())
            },
            &mut |f| {
                reports += 1;
                if f > 0.0 {
                    Control::Stop
                } else {
                    Control::Continue
                }
            },
        );
        assert!(!all.unwrap());
        assert_eq!(reports, 2);
        let done = out.iter().filter(|&&x| x == 1).count();
        assert_eq!(done, 20, "the first part: a chunk per thread");
        assert!(out[done..].iter().all(|&x| x == 0));
    }
}
