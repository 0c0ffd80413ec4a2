//! Deterministic data parallelism on scoped threads: an output slice is cut into fixed chunks,
//! threads take chunks from a shared counter, and each chunk's result depends only on its
//! index, so the answer is the same for any thread count.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
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

/// [`for_chunks`] with `report` heard on the calling thread while the workers work: every
/// `REPORT_SECONDS` and at every twentieth of the work, whatever a chunk costs (a slow backend
/// does not make the host wait for a chunk to end), so a Stop is heard within about that.
/// Chunks are taken in order and each result depends on its index only, so the results are
/// those of one [`for_chunks`] call. `report(0.0)` is asked first: a Stop already given leaves
/// everything untouched. After a Stop no chunk is begun; the chunks begun are finished, so the
/// chunks done are a prefix. Whether every chunk was done.
pub(crate) fn for_chunks_reporting<T: Send>(
    out: &mut [T],
    chunk: usize,
    threads: usize,
    f: impl Fn(usize, &mut [T]) -> Result<()> + Sync,
    report: Report,
) -> Result<bool> {
    for_chunks_halting(out, chunk, threads, |i, c, _| f(i, c), report)
}

/// What a chunk of [`for_chunks_halting`] may read to give up part-way once the host has asked
/// to stop.
pub(crate) struct Halt(AtomicBool);

impl Halt {
    /// Whether the host has asked to stop (or a worker failed).
    pub(crate) fn asked(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// Seconds between reports while a phase's workers work.
const REPORT_SECONDS: f64 = 0.2;

/// [`for_chunks_reporting`] for chunks long enough to give up part-way: `f` reads the [`Halt`]
/// and may leave its chunk unfinished (marked so in its output) once it is asked. Whether
/// every chunk was begun and the host never asked to stop.
pub(crate) fn for_chunks_halting<T: Send>(
    out: &mut [T],
    chunk: usize,
    threads: usize,
    f: impl Fn(usize, &mut [T], &Halt) -> Result<()> + Sync,
    report: Report,
) -> Result<bool> {
    const STEPS: usize = 20;
    let chunk = chunk.max(1);
    let total = out.len();
    if total == 0 {
        return Ok(true);
    }
    if report(0.0) == Control::Stop {
        return Ok(false);
    }
    let count = total.div_ceil(chunk);
    let threads = threads.max(1).min(count);
    let chunks: Vec<Mutex<Option<&mut [T]>>> =
        out.chunks_mut(chunk).map(|c| Mutex::new(Some(c))).collect();
    let next = AtomicUsize::new(0);
    let halt = Halt(AtomicBool::new(false));
    let first_error: Mutex<Option<Error>> = Mutex::new(None);
    let (done_tx, done_rx) = std::sync::mpsc::channel::<usize>();
    let mut stopped = false;
    std::thread::scope(|scope| {
        for _ in 0..threads {
            let done_tx = done_tx.clone();
            let (chunks, next, halt, first_error, f) = (&chunks, &next, &halt, &first_error, &f);
            scope.spawn(move || {
                while !halt.asked() {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(slot) = chunks.get(i) else { break };
                    let Some(c) = slot.lock().unwrap_or_else(|e| e.into_inner()).take() else {
                        continue;
                    };
                    let len = c.len();
                    if let Err(e) = guarded("a worker", || f(i * chunk, c, halt)) {
                        first_error
                            .lock()
                            .unwrap_or_else(|e| e.into_inner())
                            .get_or_insert(e);
                        halt.0.store(true, Ordering::Relaxed);
                        break;
                    }
                    // The caller may have returned from its loop already (a Stop): fine.
                    done_tx.send(len).ok();
                }
            });
        }
        // The workers hold the only senders: the channel closes when the last one ends.
        drop(done_tx);
        let step = total.div_ceil(STEPS).max(1);
        let every = std::time::Duration::from_secs_f64(REPORT_SECONDS);
        let (mut done, mut reported) = (0usize, 0usize);
        let mut last = std::time::Instant::now();
        loop {
            if halt.asked() {
                // Stopped or failed: wait for the chunks begun, hearing nothing more.
                while done_rx.recv().is_ok() {}
                break;
            }
            let wait = (last + every).saturating_duration_since(std::time::Instant::now());
            match done_rx.recv_timeout(wait) {
                Ok(len) => {
                    done += len;
                    // Reported at every step of the work as well as by the clock.
                    let due = last.elapsed() >= every;
                    if done < total && done / step == reported / step && !due {
                        continue;
                    }
                }
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => break,
            }
            last = std::time::Instant::now();
            reported = done;
            // Above 0 even before a chunk ends: a report of 0 only asks whether to begin.
            let share = (done as f64 / total as f64).max(f64::MIN_POSITIVE);
            if report(share) == Control::Stop && done < total {
                stopped = true;
                halt.0.store(true, Ordering::Relaxed);
            }
        }
    });
    match first_error.into_inner().unwrap_or_else(|e| e.into_inner()) {
        Some(e) => Err(e),
        None => Ok(!stopped),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reporting_gives_the_same_chunks_and_counts_up_to_one() {
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
            assert!(reports.windows(2).all(|w| w[0] <= w[1]), "{reports:?}");
            assert_eq!(reports.first(), Some(&0.0));
            assert_eq!(reports.last(), Some(&1.0));
            // Every twentieth of the work is heard (158 chunks of 64: 20 steps of 501).
            assert!(reports.len() >= 20, "{}", reports.len());
        }
    }

    #[test]
    fn a_stop_leaves_a_prefix_done_and_the_rest_untouched() {
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

        for threads in [1, 2] {
            let mut out = vec![0u32; 1000];
            let all = for_chunks_reporting(
                &mut out,
                10,
                threads,
                |_, c| {
                    std::thread::sleep(std::time::Duration::from_millis(2));
                    c.fill(1);
                    Ok(())
                },
                &mut |f| {
                    if f > 0.0 {
                        Control::Stop
                    } else {
                        Control::Continue
                    }
                },
            );
            assert!(!all.unwrap());
            let done = out.iter().take_while(|&&x| x == 1).count();
            assert!(done > 0 && done < 1000 && done % 10 == 0, "{done}");
            assert!(out[done..].iter().all(|&x| x == 0));
        }
    }

    #[test]
    fn a_slow_chunk_does_not_keep_the_host_waiting() {
        // Two chunks of 2 s each; the host asks to stop at its first report after 0.3 s and
        // the chunks read the halt every 10 ms.
        let start = std::time::Instant::now();
        let mut out = vec![false; 2];
        let mut times = Vec::new();
        let all = for_chunks_halting(
            &mut out,
            1,
            2,
            |_, c, halt| {
                for _ in 0..200 {
                    if halt.asked() {
                        return Ok(());
                    }
                    std::thread::sleep(std::time::Duration::from_millis(10));
                }
                c[0] = true;
                Ok(())
            },
            &mut |_| {
                times.push(start.elapsed().as_secs_f64());
                if start.elapsed().as_secs_f64() > 0.3 {
                    Control::Stop
                } else {
                    Control::Continue
                }
            },
        );
        assert!(!all.unwrap());
        let end = start.elapsed().as_secs_f64();
        assert_eq!(out, [false, false]);
        // Heard by the clock (about every 0.2 s), not at the chunks' end (2 s).
        assert!(times.len() >= 3 && end < 1.0, "{times:?}, ended at {end}");
    }

    #[test]
    fn a_failing_chunk_is_the_error_and_ends_the_others() {
        let mut out = vec![0u8; 100];
        let result = for_chunks_reporting(
            &mut out,
            1,
            2,
            |i, _| {
                if i == 3 {
                    panic!("chunk three");
                }
                Ok(())
            },
            &mut |_| Control::Continue,
        );
        let e = result.unwrap_err().to_string();
        assert!(e.contains("chunk three"), "{e}");
    }
}
