//! The traversal kernel of each ray queue, chosen by timing the candidates on the queue's own
//! rays.
//!
//! The SIMD traversal has three kernels that find the same hits: packets of 8 rays through the
//! PLOC BVH2 ([`crate::geometry::packet`]); single rays through the 8-wide BVH collapsed from a
//! second, SAH-built tree ([`crate::geometry::wide_traverse`]); and packets of 8 rays through
//! that 8-wide BVH, handing thin nodes to single rays ([`crate::geometry::wide_packet`],
//! Embree's hybrid traversal). Which is fastest depends on the scene, the queue and the machine,
//! not on the triangle count alone (BENCHMARKS.md, "Packets or single rays, chosen per queue by
//! timing", and issue 18's eighteenth part): on an Intel Xeon's bench rays BVH2 packets win on
//! the camera rays of the boxes, 8-wide packets on those of the meshes (+16–50 % on the bunny and
//! the ogre) and on some boxes' shadow rays, single rays on photon rays and on many final-gather
//! rays. So each queue traces its first chunks with every candidate and keeps the fastest for the
//! rest of the render (every later pass included); the camera queue's trial runs before the
//! camera pass, on chunks of camera rays from the middle of each sixth of the image
//! ([`TraversalChoice::choose_camera`]). Hits are identical whichever kernel runs and whatever
//! tree it walks (every hit's t is settled into its triangle's box:
//! [`crate::geometry::slab::settle`]), so the choice changes speed only, never an image. Reads
//! chunk timings; writes the choice per queue.

use crate::code_path::{in_coherent_order, CodePath};
use crate::geometry::bvh::{Bvh, Hit, TriangleColumns};
use crate::geometry::{packet, wide_packet, wide_traverse, RayQuery};
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::sync::Mutex;
use std::time::Instant;

/// Chunks each queue traces with every candidate kernel before it chooses.
pub const TRIAL_CHUNKS: u32 = 6;

/// Chunks shorter than this are not timed (a queue's last chunk of a bounce can be a few rays:
/// too short to time).
pub const TRIAL_MIN_RAYS: usize = 256;

const _: () =
    assert!(Kernel::Packets as usize == 0 && Kernel::Single as usize == 1 && Kernel::WidePackets as usize == 2);

/// A SIMD traversal kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kernel {
    /// Packets of 8 rays through the BVH2, rays sorted by coherence key.
    Packets,
    /// One ray at a time through the 8-wide BVH, in queue order.
    Single,
    /// Packets of 8 rays through the 8-wide BVH (thin nodes finished by single rays), closest-hit
    /// rays sorted by coherence key as for [`Kernel::Packets`].
    WidePackets,
}

impl Kernel {
    /// Every kernel, in the order of `Trial::nanos` (each one's index is its discriminant).
    pub const ALL: [Kernel; 3] = [Kernel::Packets, Kernel::Single, Kernel::WidePackets];

    /// Its name in the summary.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Kernel::Packets => "packets",
            Kernel::Single => "single rays",
            Kernel::WidePackets => "8-wide packets",
        }
    }
}

/// The ray queues that choose apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Queue {
    /// Global photons leaving the lights (their first segment: from a few points or one
    /// direction).
    Emitted,
    /// Global photons' later segments, from surfaces.
    Photons,
    /// Caustic photons leaving the lights, aimed at mirrors and glass (coherent).
    CausticEmitted,
    /// Caustic photons' later segments.
    CausticPhotons,
    /// Primary rays: packets of either tree, not single rays, which were slower than the faster
    /// packet kernel on the camera rays of every measured scene (BENCHMARKS.md). Their trial runs
    /// before the camera pass, on rays from every sixth of the image
    /// ([`TraversalChoice::choose_camera`]): the first chunks of the pass, the image's top rows,
    /// are often sky and would not tell.
    Camera,
    /// Camera paths' later segments: final-gather, glossy and specular rays.
    Secondary,
    /// Shadow rays (any hit).
    Shadows,
}

impl Queue {
    const ALL: [Queue; 7] = [
        Queue::Emitted,
        Queue::Photons,
        Queue::CausticEmitted,
        Queue::CausticPhotons,
        Queue::Camera,
        Queue::Secondary,
        Queue::Shadows,
    ];

    /// The kernels its trial compares, the default (run before a choice is made) first.
    fn candidates(self) -> &'static [Kernel] {
        match self {
            Queue::Camera => &[Kernel::Packets, Kernel::WidePackets],
            _ => &Kernel::ALL,
        }
    }

    /// Its name in stats.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Queue::Emitted => "emitted",
            Queue::Photons => "photon",
            Queue::CausticEmitted => "caustic emitted",
            Queue::CausticPhotons => "caustic photon",
            Queue::Camera => "camera",
            Queue::Secondary => "secondary",
            Queue::Shadows => "shadow",
        }
    }
}

/// One queue's trial: chunks traced by every candidate (started, finished), and each finished
/// chunk's rays and nanoseconds per kernel (in [`Kernel::ALL`]'s order; 0 for kernels not
/// tried), and the choice.
#[derive(Clone, Copy, Debug, Default)]
struct Trial {
    started: u32,
    finished: u32,
    rays: [u64; TRIAL_CHUNKS as usize],
    nanos: [[u64; 3]; TRIAL_CHUNKS as usize],
    chosen: Option<Kernel>,
}

impl Trial {
    /// Million rays per second of kernel `k`: the median over the trial's finished chunks of
    /// each chunk's rate (each chunk's time counts at least 1 ns, so once a chunk is in this is
    /// finite), so that one chunk stalled by something else on the machine (measured: a kernel's
    /// total over six chunks fell to a quarter of its usual rate) does not decide; `None` for a
    /// kernel not tried.
    fn rate(&self, k: Kernel) -> Option<f64> {
        let n = (self.finished as usize).min(self.rays.len());
        let mut rates: Vec<f64> = (0..n)
            .filter(|&c| self.nanos[c][k as usize] > 0)
            .map(|c| self.rays[c] as f64 * 1e3 / self.nanos[c][k as usize] as f64)
            .collect();
        if rates.is_empty() {
            return None;
        }
        rates.sort_by(f64::total_cmp);
        let m = rates.len() / 2;
        Some(if rates.len() % 2 == 1 { rates[m] } else { 0.5 * (rates[m - 1] + rates[m]) })
    }
}

/// How a chunk is traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Plan {
    /// With this kernel, untimed.
    Run(Kernel),
    /// With every candidate of the queue, each timed, in the order [`trial_order`] gives this
    /// trial chunk (the chunk's number in the trial).
    Trial(u32),
}

/// The order in which trial chunk `chunk` runs `n` candidates (indices into the queue's
/// candidates): every order in turn, so that over [`TRIAL_CHUNKS`] chunks each candidate runs
/// first, second and last equally often and follows each other candidate equally often (a kernel
/// run right after another that walks the same tree finds it in cache).
fn trial_order(n: usize, chunk: u32) -> &'static [usize] {
    const TWO: [[usize; 2]; 2] = [[0, 1], [1, 0]];
    const THREE: [[usize; 3]; 6] = [[0, 1, 2], [1, 2, 0], [2, 0, 1], [0, 2, 1], [2, 1, 0], [1, 0, 2]];
    match n {
        2 => &TWO[chunk as usize % 2],
        3 => &THREE[chunk as usize % 6],
        _ => &[0],
    }
}

/// What a queue chose, and the speeds it measured (million rays per second over its trial
/// chunks; `null` for a kernel the queue does not try).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct QueueChoice {
    /// Queue name ([`Queue::name`]).
    pub queue: String,
    /// The kernel it runs.
    pub kernel: Kernel,
    /// BVH2 packets' speed in the trial.
    pub packets_mrays: Option<f64>,
    /// Single rays' speed in the trial.
    pub single_mrays: Option<f64>,
    /// 8-wide packets' speed in the trial.
    pub wide_packets_mrays: Option<f64>,
}

/// The per-queue choice of one render (shared by its passes).
///
/// A queue's first [`TRIAL_CHUNKS`] chunks of [`TRIAL_MIN_RAYS`] rays or more (the camera
/// queue's: the chunks [`TraversalChoice::choose_camera`] is given) are traced by every candidate
/// kernel of the queue, one after the other (in every order in turn), each timed: the same rays,
/// so the comparison does not depend on how chunks differ (sky or mesh, near or far). The queue
/// then keeps the kernel with the highest median rate over those chunks (robust to a chunk that
/// something else on the machine stalled); ties keep the earlier in [`Kernel::ALL`], BVH2
/// packets first.
#[derive(Debug)]
pub struct TraversalChoice(Mode);

/// Trials or a fixed kernel.
#[derive(Debug)]
enum Mode {
    /// Each queue's trial (the camera rays' slot unused).
    Timed(Box<Mutex<[Trial; 7]>>),
    /// Every queue runs this kernel.
    Fixed(Kernel),
}

impl TraversalChoice {
    /// Every queue chooses by its trial (the renderer's default).
    #[must_use]
    pub fn timed() -> Self {
        TraversalChoice(Mode::Timed(Box::new(Mutex::new([Trial::default(); 7]))))
    }

    /// Every queue runs `kernel` (tests).
    #[must_use]
    pub fn fixed(kernel: Kernel) -> Self {
        TraversalChoice(Mode::Fixed(kernel))
    }

    /// How to trace a chunk of `rays` rays of `queue`.
    fn begin(&self, queue: Queue, rays: usize) -> Plan {
        let trials = match &self.0 {
            Mode::Timed(trials) => trials,
            Mode::Fixed(k) => return Plan::Run(*k),
        };
        let mut trials = trials.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let t = &mut trials[queue as usize];
        if let Some(k) = t.chosen {
            return Plan::Run(k);
        }
        if rays < TRIAL_MIN_RAYS || t.started >= TRIAL_CHUNKS {
            return Plan::Run(queue.candidates()[0]);
        }
        t.started += 1;
        Plan::Trial(t.started - 1)
    }

    /// Records a chunk of `rays` rays traced by every candidate of `queue` in `nanos` (per
    /// kernel, in [`Kernel::ALL`]'s order); after the last trial chunk the queue chooses the
    /// kernel of the highest median rate ([`Trial::rate`]).
    fn end(&self, queue: Queue, rays: usize, nanos: [u64; 3]) {
        let Mode::Timed(trials) = &self.0 else { return };
        let mut trials = trials.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let t = &mut trials[queue as usize];
        let Some(slot) = t.rays.get_mut(t.finished as usize) else { return };
        *slot = rays as u64;
        for &k in queue.candidates() {
            t.nanos[t.finished as usize][k as usize] = nanos[k as usize].max(1);
        }
        t.finished += 1;
        if t.chosen.is_none() && t.finished >= TRIAL_CHUNKS {
            let rate = |k: Kernel| t.rate(k).unwrap_or(0.0);
            let mut best = queue.candidates()[0];
            for &k in queue.candidates() {
                if rate(k) > rate(best) {
                    best = k;
                }
            }
            t.chosen = Some(best);
        }
    }

    /// Traces a chunk of `queue` into `out` with `trace(kernel, out)`: with the queue's kernel,
    /// or in a trial with every candidate, keeping the first one's result (they are identical;
    /// debug builds check it). The 8-wide BVH is built (once) before any timer starts.
    fn run<T: Clone + PartialEq + std::fmt::Debug>(
        &self,
        queue: Queue,
        bvh: &Bvh,
        tris: TriangleColumns<'_>,
        out: &mut [T],
        mut trace: impl FnMut(Kernel, &mut [T]),
    ) {
        let chunk = match self.begin(queue, out.len()) {
            Plan::Run(k) => return trace(k, out),
            Plan::Trial(chunk) => chunk,
        };
        let _ = bvh.wide(tris);
        let candidates = queue.candidates();
        let order = trial_order(candidates.len(), chunk);
        let pristine = out.to_vec();
        let mut other = pristine.clone();
        let mut nanos = [0u64; 3];
        for (i, &c) in order.iter().enumerate() {
            let k = candidates[c];
            let into = if i == 0 { &mut *out } else { &mut other[..] };
            let start = Instant::now();
            trace(k, into);
            nanos[k as usize] = u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX);
            if i > 0 {
                debug_assert!(*out == other[..], "{k:?} disagrees with {:?}", candidates[order[0]]);
                other.clone_from_slice(&pristine);
            }
        }
        self.end(queue, out.len(), nanos);
    }

    /// Chooses the camera queue's kernel before the first camera pass: times both packet kernels
    /// on `chunks` (camera rays from every part of the image, [`TRIAL_CHUNKS`] of them), so that
    /// the whole pass runs the faster one. Does nothing once the camera queue has chosen (a later
    /// pass) or when the choice is fixed; chunks shorter than [`TRIAL_MIN_RAYS`] do not count, and
    /// a trial these do not complete goes on in the pass's first chunks.
    pub fn choose_camera(
        &self,
        set: CodePath,
        bvh: &Bvh,
        tris: TriangleColumns<'_>,
        chunks: &[Vec<RayQuery>],
        bounds: (Vec3, Vec3),
    ) {
        if set == CodePath::Scalar || !self.in_trial(Queue::Camera) {
            return;
        }
        for rays in chunks {
            let _ = self.closest(Queue::Camera, set, bvh, tris, rays, bounds);
        }
    }

    /// Whether `queue` is timing its candidates still (never for a fixed choice).
    fn in_trial(&self, queue: Queue) -> bool {
        let Mode::Timed(trials) = &self.0 else { return false };
        trials.lock().unwrap_or_else(std::sync::PoisonError::into_inner)[queue as usize].chosen.is_none()
    }

    /// Closest hits of a chunk of `queue` (in input order). The scalar code path runs the scalar
    /// twin, untimed.
    #[must_use]
    pub fn closest(
        &self,
        queue: Queue,
        set: CodePath,
        bvh: &Bvh,
        tris: TriangleColumns<'_>,
        rays: &[RayQuery],
        bounds: (Vec3, Vec3),
    ) -> Vec<Option<Hit>> {
        let mut out = vec![None; rays.len()];
        if set == CodePath::Scalar {
            set.closest_coherent(bvh, tris, rays, bounds, &mut out);
            return out;
        }
        self.run(queue, bvh, tris, &mut out, |k, o| match k {
            Kernel::Packets => set.closest_coherent(bvh, tris, rays, bounds, o),
            Kernel::Single => wide_traverse::closest_rays::<true>(bvh.wide(tris), tris.cut, rays, o),
            Kernel::WidePackets => in_coherent_order(rays, bounds, o, |r, o| {
                wide_packet::closest_packets8(bvh.wide(tris), tris, r, o, wide_packet::THIN_LANES);
            }),
        });
        out
    }

    /// Any-hit tests of a chunk of `queue` into `out` (shadow rays: queued in camera-lane order,
    /// already coherent, so no kernel sorts them).
    pub fn occluded(
        &self,
        queue: Queue,
        set: CodePath,
        bvh: &Bvh,
        tris: TriangleColumns<'_>,
        rays: &[RayQuery],
        out: &mut [bool],
    ) {
        if set == CodePath::Scalar {
            return set.occluded(bvh, tris, rays, out);
        }
        self.run(queue, bvh, tris, out, |k, o| match k {
            Kernel::Packets => packet::occluded_packets(bvh, tris, rays, o),
            Kernel::Single => wide_traverse::occluded_rays::<true>(bvh.wide(tris), tris.cut, rays, o),
            Kernel::WidePackets => {
                wide_packet::occluded_packets8(bvh.wide(tris), tris, rays, o, wide_packet::THIN_LANES);
            }
        });
    }

    /// Each queue's choice: the kernel and the speeds its trial measured. Queues without a trial
    /// (every queue of a fixed choice), still in it, or never run are left out.
    #[must_use]
    pub fn report(&self) -> Vec<QueueChoice> {
        let Mode::Timed(trials) = &self.0 else { return vec![] };
        let trials = *trials.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        Queue::ALL
            .iter()
            .filter_map(|&q| {
                let t = &trials[q as usize];
                Some(QueueChoice {
                    queue: q.name().into(),
                    kernel: t.chosen?,
                    packets_mrays: t.rate(Kernel::Packets),
                    single_mrays: t.rate(Kernel::Single),
                    wide_packets_mrays: t.rate(Kernel::WidePackets),
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trial traces its chunks with every candidate, leaves short chunks and chunks beyond the
    /// trial's count to the default, keeps the kernel with the most rays per second once the
    /// chunks are in, and never times again; queues choose apart; a fixed choice never times.
    #[test]
    fn queues_keep_the_fastest_kernel() {
        let c = TraversalChoice::timed();
        assert_eq!(c.begin(Queue::Shadows, TRIAL_MIN_RAYS - 1), Plan::Run(Kernel::Packets));
        let plans: Vec<Plan> = (0..TRIAL_CHUNKS).map(|_| c.begin(Queue::Shadows, 1024)).collect();
        assert_eq!(plans, (0..TRIAL_CHUNKS).map(Plan::Trial).collect::<Vec<_>>());
        // All trial chunks under way: further chunks run packets until the trial ends.
        assert_eq!(c.begin(Queue::Shadows, 1024), Plan::Run(Kernel::Packets));
        for _ in 0..TRIAL_CHUNKS {
            // 1024 rays: packets in 2 µs, single rays in 1.5 µs, 8-wide packets in 1 µs.
            c.end(Queue::Shadows, 1024, [2_000, 1_500, 1_000]);
        }
        assert_eq!(c.begin(Queue::Shadows, 1024), Plan::Run(Kernel::WidePackets));
        // The photon queue has not chosen: it starts its own trial, and the report leaves it out.
        assert_eq!(c.begin(Queue::Photons, 1024), Plan::Trial(0));
        let r = c.report();
        assert_eq!(r.len(), 1);
        assert_eq!((r[0].queue.as_str(), r[0].kernel), ("shadow", Kernel::WidePackets));
        let close = |a: Option<f64>, b: f64| a.is_some_and(|a| (a - b).abs() < 1e-9);
        assert!(close(r[0].packets_mrays, 512.0) && close(r[0].wide_packets_mrays, 1024.0), "{r:?}");

        let packets = TraversalChoice::fixed(Kernel::Packets);
        assert_eq!(packets.begin(Queue::Shadows, 1024), Plan::Run(Kernel::Packets));
        assert!(packets.report().is_empty());
        assert_eq!(TraversalChoice::fixed(Kernel::Single).begin(Queue::Camera, 1024), Plan::Run(Kernel::Single));
    }

    /// One stalled chunk does not decide: a kernel fastest on five chunks of six is kept though
    /// the sixth took it a second (its total would have lost to the others).
    #[test]
    fn a_stalled_chunk_does_not_decide() {
        let c = TraversalChoice::timed();
        for chunk in 0..TRIAL_CHUNKS {
            assert_eq!(c.begin(Queue::Photons, 1024), Plan::Trial(chunk));
            let wide = if chunk == 2 { 1_000_000_000 } else { 1_000 };
            c.end(Queue::Photons, 1024, [2_000, 1_500, wide]);
        }
        assert_eq!(c.begin(Queue::Photons, 1024), Plan::Run(Kernel::WidePackets));
        let r = c.report();
        assert!(r[0].wide_packets_mrays.is_some_and(|v| (v - 1024.0).abs() < 1e-9), "{r:?}");
    }

    /// Over a trial's chunks every candidate runs in every position equally often and right
    /// after each other candidate equally often (of three: the six orders; of two: both).
    #[test]
    fn trial_orders_are_balanced() {
        for n in [2usize, 3] {
            let orders: Vec<&[usize]> = (0..TRIAL_CHUNKS).map(|c| trial_order(n, c)).collect();
            let mut position = vec![vec![0; n]; n];
            let mut follows = vec![vec![0; n]; n];
            for o in &orders {
                let mut seen = o.to_vec();
                seen.sort_unstable();
                assert_eq!(seen, (0..n).collect::<Vec<_>>(), "{o:?} is not an order of {n}");
                for (i, &k) in o.iter().enumerate() {
                    position[k][i] += 1;
                }
                for w in o.windows(2) {
                    follows[w[1]][w[0]] += 1;
                }
            }
            let per = TRIAL_CHUNKS as usize / n;
            assert!(position.iter().flatten().all(|&p| p == per), "{n}: positions {position:?}");
            for (k, row) in follows.iter().enumerate() {
                for (j, &f) in row.iter().enumerate() {
                    let want = if j == k { 0 } else { (TRIAL_CHUNKS as usize * (n - 1)) / (n * (n - 1)) };
                    assert_eq!(f, want, "{n}: {k} after {j}: {follows:?}");
                }
            }
        }
    }

    /// The camera queue compares the two packet kernels only, on the chunks `choose_camera` is
    /// given, before any chunk of the pass; single rays get no time (`null` in the report); a
    /// later call, once chosen, does nothing.
    #[test]
    fn camera_rays_try_both_packet_kernels_before_the_pass() {
        let (p0, p1, p2) = ([Vec3::new(-1.0, -1.0, 2.0)], [Vec3::new(1.0, -1.0, 2.0)], [Vec3::new(0.0, 1.0, 2.0)]);
        let (bvh, _) = Bvh::build(&p0, &p1, &p2);
        let tris = TriangleColumns::new(&p0, &p1, &p2);
        let bounds = (Vec3::splat(-1.0), Vec3::new(1.0, 1.0, 2.0));
        let ray = RayQuery::new(Vec3::ZERO, Vec3::Z, f32::INFINITY);
        let chunks = vec![vec![ray; 1024]; TRIAL_CHUNKS as usize];
        let c = TraversalChoice::timed();
        c.choose_camera(CodePath::Simd, &bvh, tris, &chunks, bounds);
        assert!(!c.in_trial(Queue::Camera));
        let r = c.report();
        assert_eq!(r.len(), 1, "{r:?}");
        assert_eq!((r[0].queue.as_str(), r[0].single_mrays), ("camera", None), "{r:?}");
        assert!(r[0].packets_mrays.is_some() && r[0].wide_packets_mrays.is_some(), "{r:?}");
        assert!(matches!(c.begin(Queue::Camera, 1024), Plan::Run(Kernel::Packets | Kernel::WidePackets)));
        // Chosen: a second call traces nothing (the speeds stay as they were).
        c.choose_camera(CodePath::Simd, &bvh, tris, &chunks, bounds);
        assert_eq!(c.report(), r);
        // Fixed or scalar: no trial at all.
        let fixed = TraversalChoice::fixed(Kernel::Packets);
        fixed.choose_camera(CodePath::Simd, &bvh, tris, &chunks, bounds);
        assert!(fixed.report().is_empty());
        let scalar = TraversalChoice::timed();
        scalar.choose_camera(CodePath::Scalar, &bvh, tris, &chunks, bounds);
        assert!(scalar.report().is_empty() && scalar.in_trial(Queue::Camera));
    }

    /// Equal times keep packets, the renderer's long-standing default; a trial's `run` traces
    /// with every candidate in the chunk's order and returns the first one's result.
    #[test]
    fn ties_keep_packets_and_trials_run_every_candidate() {
        let c = TraversalChoice::timed();
        for _ in 0..TRIAL_CHUNKS {
            assert!(matches!(c.begin(Queue::Emitted, 1024), Plan::Trial(_)));
            c.end(Queue::Emitted, 1024, [1_000, 1_000, 1_000]);
        }
        assert_eq!(c.begin(Queue::Emitted, 1024), Plan::Run(Kernel::Packets));

        // One triangle is tree enough: `run` only hands the kernel to the closure.
        let (p0, p1, p2) = ([Vec3::ZERO], [Vec3::X], [Vec3::Y]);
        let (bvh, _) = Bvh::build(&p0, &p1, &p2);
        let tris = TriangleColumns::new(&p0, &p1, &p2);
        let c = TraversalChoice::timed();
        let mut out = [0u32; 1024];
        for chunk in 0..2 {
            let mut ran = vec![];
            c.run(Queue::Secondary, &bvh, tris, &mut out, |k, o| {
                ran.push(k);
                o.fill(chunk);
            });
            let want: Vec<Kernel> = trial_order(3, chunk).iter().map(|&i| Kernel::ALL[i]).collect();
            assert_eq!((out[0], ran), (chunk, want));
        }
    }
}
