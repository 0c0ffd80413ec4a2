//! Deterministic data parallelism on scoped threads: an output slice is cut into fixed chunks,
//! threads take chunks from a shared counter, and each chunk's result depends only on its
//! index, so the answer is the same for any thread count.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use crate::error::Result;

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
            f(i * chunk, c)?;
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
                if let Err(e) = f(i * chunk, c) {
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
