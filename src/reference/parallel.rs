//! Deterministic work sharing: items are split into fixed chunks; threads take chunks in any
//! order, but results are returned in chunk order, so the output never depends on scheduling.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Runs `work(chunk_index, range)` over `0..n` in chunks of `chunk` on `threads` threads and
/// returns the results in chunk order. `done(k)` is called after each chunk with its size.
pub fn map_chunks<T: Send>(
    n: usize,
    chunk: usize,
    threads: usize,
    work: impl Fn(std::ops::Range<usize>) -> T + Sync,
    done: impl Fn(usize) + Sync,
) -> Vec<T> {
    let chunk = chunk.max(1);
    let count = n.div_ceil(chunk);
    if threads <= 1 || count <= 1 {
        // One worker: no thread to spawn (the wavefront engine calls this for every stage of every
        // bounce, and deep bounces hold few lanes; spawning cost more than their work).
        return (0..count)
            .map(|c| {
                let range = c * chunk..((c + 1) * chunk).min(n);
                let len = range.len();
                let r = work(range);
                done(len);
                r
            })
            .collect();
    }
    let next = AtomicUsize::new(0);
    let slots: Vec<Mutex<Option<T>>> = (0..count).map(|_| Mutex::new(None)).collect();
    std::thread::scope(|s| {
        for _ in 0..threads.clamp(1, count.max(1)) {
            s.spawn(|| loop {
                let c = next.fetch_add(1, Ordering::Relaxed);
                if c >= count {
                    break;
                }
                let range = c * chunk..((c + 1) * chunk).min(n);
                let len = range.len();
                let r = work(range);
                *slots[c].lock().unwrap_or_else(|e| e.into_inner()) = Some(r);
                done(len);
            });
        }
    });
    slots
        .into_iter()
        .map(|m| m.into_inner().unwrap_or_else(|e| e.into_inner()).expect("every chunk is processed"))
        .collect()
}
