//! Deterministic work sharing: items are split into fixed chunks; threads take chunks in any
//! order, but results are returned in chunk order, so the output never depends on scheduling.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

use rayon_core::{ThreadPool, ThreadPoolBuilder};

/// A persistent pool of `threads` workers, built on first use and kept for the process. Spawning
/// and joining two OS threads costs ~100 µs on this machine, and the wavefront engine shares
/// work ~3 000 times per render (every stage of every bounce), so fresh threads per call cost ~9 %
/// of a two-thread render (BENCHMARKS.md). `None` if the OS refuses the threads.
fn pool(threads: usize) -> Option<Arc<ThreadPool>> {
    /// Pools built so far, by worker count.
    type Pools = Mutex<Vec<(usize, Arc<ThreadPool>)>>;
    static POOLS: OnceLock<Pools> = OnceLock::new();
    let mut pools = POOLS.get_or_init(Mutex::default).lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, p)) = pools.iter().find(|(t, _)| *t == threads) {
        return Some(Arc::clone(p));
    }
    let p = Arc::new(
        ThreadPoolBuilder::new().num_threads(threads).thread_name(|i| format!("photonwave-{i}")).build().ok()?,
    );
    pools.push((threads, Arc::clone(&p)));
    Some(p)
}

/// Runs `worker` `copies` times at once, one on the calling thread and the others on a pool of
/// `threads − 1` workers, and returns when all copies have returned (on fresh scoped threads if
/// no pool could be built).
fn run_workers(threads: usize, copies: usize, worker: &(dyn Fn() + Sync)) {
    match pool(threads - 1) {
        // The calling thread runs one copy itself, so only `copies − 1` workers must wake.
        Some(p) => p.in_place_scope(|s| {
            for _ in 1..copies {
                s.spawn(|_| worker());
            }
            worker();
        }),
        None => std::thread::scope(|s| {
            for _ in 0..copies {
                s.spawn(worker);
            }
        }),
    }
}

/// Runs `work(range)` over `0..n` in chunks of `chunk` on `threads` threads and
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
    run_workers(threads, threads.min(count), &|| loop {
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
    slots
        .into_iter()
        .map(|m| m.into_inner().unwrap_or_else(|e| e.into_inner()).expect("every chunk is processed"))
        .collect()
}
