//! Deterministic work sharing: items are split into fixed chunks; threads take chunks in any
//! order, but results are returned in chunk order, so the output never depends on scheduling.
//!
//! A render can be metered ([`metered`]): every parallel region its thread starts adds its wall
//! time, the workers' busy time (the chunks' own durations) and its capacity (threads × wall) to
//! a [`Meter`], from which `--stats` reports the render's parallel utilisation and the time it
//! spent outside parallel regions — what decides how it would scale on more cores.

use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Instant;

use rayon_core::{ThreadPool, ThreadPoolBuilder};

/// A persistent pool of `threads` workers, built on first use and kept for the process. Spawning
/// and joining two OS threads costs ~100 µs on this machine; when the wavefront engine still
/// shared work ~3 000 times per render (every stage of every bounce), fresh threads per call cost
/// ~9 % of a two-thread render (BENCHMARKS.md). Its passes now meet the pool once per pass and
/// photon wave, the reference engine once per row range and photon batch. `None` if the OS
/// refuses the threads.
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

/// Time accounts of the parallel regions started by the threads that run under it
/// ([`metered`]), in nanoseconds. Workers add to it from any thread.
#[derive(Debug, Default)]
pub struct Meter {
    /// The chunks' own durations, summed over every worker.
    busy_ns: AtomicU64,
    /// Wall time inside parallel regions (from a region's start to its last chunk's return).
    region_ns: AtomicU64,
    /// Σ threads × region wall time: what the workers could have done in the regions.
    capacity_ns: AtomicU64,
    /// Parallel regions (fork-joins, and one-worker regions alike).
    regions: AtomicU64,
}

/// What a [`Meter`] has counted so far.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MeterReading {
    /// Σ chunk durations over all workers (s).
    pub busy_s: f64,
    /// Wall time inside parallel regions (s).
    pub in_regions_s: f64,
    /// Σ threads × region wall time (s).
    pub capacity_s: f64,
    /// Parallel regions.
    pub regions: u64,
}

impl Meter {
    /// The counts so far.
    #[must_use]
    pub fn reading(&self) -> MeterReading {
        let s = |a: &AtomicU64| a.load(Ordering::Relaxed) as f64 * 1e-9;
        MeterReading {
            busy_s: s(&self.busy_ns),
            in_regions_s: s(&self.region_ns),
            capacity_s: s(&self.capacity_ns),
            regions: self.regions.load(Ordering::Relaxed),
        }
    }
}

thread_local! {
    /// The meter of the render running on this thread, if it is metered.
    static CURRENT: RefCell<Option<Arc<Meter>>> = const { RefCell::new(None) };
}

/// Runs `f` with `meter` counting the parallel regions this thread starts (the ones started
/// inside a chunk, on any thread, are part of that chunk's time). Renders of other threads in the same
/// process (tests run several at once) count in their own meters.
pub fn metered<R>(meter: &Arc<Meter>, f: impl FnOnce() -> R) -> R {
    let previous = CURRENT.with(|c| c.replace(Some(Arc::clone(meter))));
    let r = f();
    CURRENT.with(|c| *c.borrow_mut() = previous);
    r
}

/// The busy time (s) counted so far by this thread's render's meter; `None` when it is not
/// metered, or when this thread is inside a chunk of a metered region (where it is busy).
#[must_use]
pub fn busy_seconds() -> Option<f64> {
    current_meter().map(|m| m.reading().busy_s)
}

/// The meter of this thread's render, if any.
fn current_meter() -> Option<Arc<Meter>> {
    CURRENT.with(|c| c.borrow().clone())
}

/// Runs `work(range)` over `0..n` in chunks of `chunk` on `threads` threads and
/// returns the results in chunk order. `done(k)` is called after each chunk with its size.
/// Under a [`metered`] render the region's wall, busy and capacity times are counted, the
/// capacity at all `threads` even when there are fewer chunks (idle workers are the loss).
pub fn map_chunks<T: Send>(
    n: usize,
    chunk: usize,
    threads: usize,
    work: impl Fn(std::ops::Range<usize>) -> T + Sync,
    done: impl Fn(usize) + Sync,
) -> Vec<T> {
    let Some(meter) = current_meter() else {
        return share_chunks(n, chunk, threads, work, done);
    };
    let start = Instant::now();
    let timed = |range: std::ops::Range<usize>| {
        let t = Instant::now();
        // Regions started inside a chunk are part of its busy time, whichever thread runs it
        // (the pool's threads have no meter; the calling thread's is set aside meanwhile).
        let outer = CURRENT.with(|c| c.replace(None));
        let r = work(range);
        CURRENT.with(|c| *c.borrow_mut() = outer);
        let ns = u64::try_from(t.elapsed().as_nanos()).unwrap_or(u64::MAX);
        meter.busy_ns.fetch_add(ns, Ordering::Relaxed);
        r
    };
    let out = share_chunks(n, chunk, threads, timed, done);
    let wall = u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX);
    meter.region_ns.fetch_add(wall, Ordering::Relaxed);
    meter.capacity_ns.fetch_add(wall.saturating_mul(threads.max(1) as u64), Ordering::Relaxed);
    meter.regions.fetch_add(1, Ordering::Relaxed);
    out
}

/// [`map_chunks`] without the meter.
fn share_chunks<T: Send>(
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
