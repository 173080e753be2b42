//! The traversal kernel of each ray queue, chosen by timing the candidates on the queue's own
//! rays.
//!
//! The SIMD traversal has three kernels that find the same hits: packets of 8 rays through the
//! PLOC BVH2 ([`crate::geometry::packet`]); single rays through the 8-wide BVH collapsed from a
//! second, SAH-built tree ([`crate::geometry::wide_traverse`]); and packets of 8 rays through
//! that 8-wide BVH, handing thin nodes to single rays ([`crate::geometry::wide_packet`],
//! Embree's hybrid traversal). Which is fastest depends on the scene, the queue and the machine,
//! not on the triangle count alone (BENCHMARKS.md, "Packets or single rays, chosen per queue by
//! timing", and issue 18's eighteenth part): BVH2 packets win on the camera rays of the boxes,
//! 8-wide packets on those of the meshes (+16–50 % on the bunny and the ogre) and on some boxes'
//! shadow rays; single rays on photon rays and on final-gather rays. So each queue traces its
//! first chunks with every candidate and keeps the fastest for the rest of the render (every
//! later pass included). Hits are identical whichever kernel runs and whatever tree it walks
//! (every hit's t is settled into its triangle's box: [`crate::geometry::slab::settle`]), so the
//! choice changes speed only, never an image. Reads chunk timings; writes the choice per queue.

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

/// A SIMD traversal kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kernel {
    /// Packets of 8 rays through the BVH2, rays sorted by coherence key.
    Packets,
    /// One ray at a time through the 8-wide BVH, in queue order.
    Single,
    /// Packets of 8 rays through the 8-wide BVH (thin nodes finished by single rays), rays
    /// sorted by coherence key as for [`Kernel::Packets`].
    WidePackets,
}

impl Kernel {
    /// Every kernel, in the order of [`Trial::nanos`].
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
    /// Primary rays: packets of either tree, never single rays, which were slower on the camera
    /// rays of every measured scene (0.29–0.88×, from the Cornell boxes to the 1 M sphere;
    /// BENCHMARKS.md). Their trial chunks are spread over the image (the first chunks, the
    /// image's top rows, are often sky and would not tell).
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

/// One queue's trial: chunks traced by every candidate (started, finished), rays and nanoseconds
/// of each kernel on them (in [`Kernel::ALL`]'s order; 0 for kernels not tried), and the choice.
#[derive(Clone, Copy, Debug, Default)]
struct Trial {
    started: u32,
    finished: u32,
    rays: u64,
    nanos: [u64; 3],
    chosen: Option<Kernel>,
}

impl Trial {
    /// Million rays per second of kernel `k` over the trial's chunks (each chunk's time counts
    /// at least 1 ns, so once a chunk is in this is finite); `None` for a kernel not tried.
    fn rate(&self, k: Kernel) -> Option<f64> {
        let nanos = self.nanos[k as usize];
        (nanos > 0).then(|| self.rays as f64 * 1e3 / nanos as f64)
    }
}

/// How a chunk is traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Plan {
    /// With this kernel, untimed.
    Run(Kernel),
    /// With every candidate of the queue, each timed, starting with the candidate at this index
    /// (the order turns from one trial chunk to the next).
    Trial(usize),
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
/// queue's: one in each sixth of the image) are traced by every candidate kernel of the queue,
/// one after the other (which goes first turns), each timed: the same rays, so the comparison
/// does not depend on how chunks differ (sky or mesh, near or far). The queue then keeps the
/// kernel with the most rays per second over those chunks; ties keep the earlier in
/// [`Kernel::ALL`], BVH2 packets first.
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

    /// How to trace a chunk of `rays` rays of `queue` that starts `at` (in [0, 1)) of the way
    /// through the queue's pass; only the camera queue reads `at`, to spread its trial over the
    /// image.
    fn begin(&self, queue: Queue, rays: usize, at: f32) -> Plan {
        let trials = match &self.0 {
            Mode::Timed(trials) => trials,
            Mode::Fixed(k) => return Plan::Run(*k),
        };
        let mut trials = trials.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let t = &mut trials[queue as usize];
        if let Some(k) = t.chosen {
            return Plan::Run(k);
        }
        let default = Plan::Run(queue.candidates()[0]);
        if rays < TRIAL_MIN_RAYS || t.started >= TRIAL_CHUNKS {
            return default;
        }
        if queue == Queue::Camera && at < t.started as f32 / TRIAL_CHUNKS as f32 {
            return default;
        }
        let first = t.started as usize % queue.candidates().len();
        t.started += 1;
        Plan::Trial(first)
    }

    /// Records a chunk of `rays` rays traced by every candidate of `queue` in `nanos` (per
    /// kernel, in [`Kernel::ALL`]'s order); after the last trial chunk the queue chooses.
    fn end(&self, queue: Queue, rays: usize, nanos: [u64; 3]) {
        let Mode::Timed(trials) = &self.0 else { return };
        let mut trials = trials.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let t = &mut trials[queue as usize];
        t.finished += 1;
        t.rays += rays as u64;
        for &k in queue.candidates() {
            t.nanos[k as usize] += nanos[k as usize].max(1);
        }
        if t.chosen.is_none() && t.finished >= TRIAL_CHUNKS {
            let mut best = queue.candidates()[0];
            for &k in queue.candidates() {
                if t.nanos[k as usize] < t.nanos[best as usize] {
                    best = k;
                }
            }
            t.chosen = Some(best);
        }
    }

    /// Traces a chunk of `queue` that starts `at` of the way through its pass into `out` with
    /// `trace(kernel, out)`: with the queue's kernel, or in a trial with every candidate, keeping
    /// the first one's result (they are identical; debug builds check it). The 8-wide BVH is
    /// built (once) before any timer starts.
    #[allow(clippy::too_many_arguments)]
    fn run<T: Clone + PartialEq + std::fmt::Debug>(
        &self,
        queue: Queue,
        at: f32,
        bvh: &Bvh,
        tris: TriangleColumns<'_>,
        out: &mut [T],
        mut trace: impl FnMut(Kernel, &mut [T]),
    ) {
        let first = match self.begin(queue, out.len(), at) {
            Plan::Run(k) => return trace(k, out),
            Plan::Trial(first) => first,
        };
        let _ = bvh.wide(tris);
        let candidates = queue.candidates();
        let mut other = out.to_vec();
        let mut nanos = [0u64; 3];
        for i in 0..candidates.len() {
            let k = candidates[(first + i) % candidates.len()];
            let into = if i == 0 { &mut *out } else { &mut other[..] };
            let start = Instant::now();
            trace(k, into);
            nanos[k as usize] = u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX);
            debug_assert!(i == 0 || *out == other[..], "{k:?} disagrees with {:?}", candidates[first]);
        }
        self.end(queue, out.len(), nanos);
    }

    /// Closest hits of a chunk of `queue` (in input order) that starts `at` (in [0, 1)) of the
    /// way through the queue's pass. The scalar code path runs the scalar twin, untimed.
    #[allow(clippy::too_many_arguments)]
    #[must_use]
    pub fn closest(
        &self,
        queue: Queue,
        at: f32,
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
        self.run(queue, at, bvh, tris, &mut out, |k, o| match k {
            Kernel::Packets => set.closest_coherent(bvh, tris, rays, bounds, o),
            Kernel::Single => wide_traverse::closest_rays::<true>(bvh.wide(tris), rays, o),
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
        self.run(queue, 0.0, bvh, tris, out, |k, o| match k {
            Kernel::Packets => packet::occluded_packets(bvh, tris, rays, o),
            Kernel::Single => wide_traverse::occluded_rays::<true>(bvh.wide(tris), rays, o),
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

    /// A trial traces its chunks with every candidate (the first one turning: packets, single
    /// rays, 8-wide packets), leaves short chunks and chunks beyond the trial's count to the
    /// default, keeps the kernel with the most rays per second once the chunks are in, and never
    /// times again; queues choose apart; a fixed choice never times.
    #[test]
    fn queues_keep_the_fastest_kernel() {
        let c = TraversalChoice::timed();
        assert_eq!(c.begin(Queue::Shadows, TRIAL_MIN_RAYS - 1, 0.0), Plan::Run(Kernel::Packets));
        let plans: Vec<Plan> = (0..TRIAL_CHUNKS).map(|_| c.begin(Queue::Shadows, 1024, 0.0)).collect();
        assert_eq!(&plans[..4], &[Plan::Trial(0), Plan::Trial(1), Plan::Trial(2), Plan::Trial(0)]);
        // All trial chunks under way: further chunks run packets until the trial ends.
        assert_eq!(c.begin(Queue::Shadows, 1024, 0.0), Plan::Run(Kernel::Packets));
        for _ in 0..TRIAL_CHUNKS {
            // 1024 rays: packets in 2 µs, single rays in 1.5 µs, 8-wide packets in 1 µs.
            c.end(Queue::Shadows, 1024, [2_000, 1_500, 1_000]);
        }
        assert_eq!(c.begin(Queue::Shadows, 1024, 0.0), Plan::Run(Kernel::WidePackets));
        // The photon queue has not chosen: it starts its own trial, and the report leaves it out.
        assert_eq!(c.begin(Queue::Photons, 1024, 0.0), Plan::Trial(0));
        let r = c.report();
        assert_eq!(r.len(), 1);
        assert_eq!((r[0].queue.as_str(), r[0].kernel), ("shadow", Kernel::WidePackets));
        let close = |a: Option<f64>, b: f64| a.is_some_and(|a| (a - b).abs() < 1e-9);
        assert!(close(r[0].packets_mrays, 512.0) && close(r[0].wide_packets_mrays, 1024.0), "{r:?}");

        let packets = TraversalChoice::fixed(Kernel::Packets);
        assert_eq!(packets.begin(Queue::Shadows, 1024, 0.0), Plan::Run(Kernel::Packets));
        assert!(packets.report().is_empty());
        assert_eq!(TraversalChoice::fixed(Kernel::Single).begin(Queue::Camera, 1024, 0.0), Plan::Run(Kernel::Single));
    }

    /// The camera queue compares the two packet kernels only, on chunks spread over the image:
    /// one at or after each sixth of the pass; single rays get no time (`null` in the report).
    #[test]
    fn camera_rays_try_both_packet_kernels_across_the_image() {
        let c = TraversalChoice::timed();
        let mut trials = vec![];
        for chunk in 0..60 {
            let at = chunk as f32 / 60.0;
            if let Plan::Trial(first) = c.begin(Queue::Camera, 1024, at) {
                trials.push((chunk, first));
            } else {
                assert_eq!(c.begin(Queue::Camera, 1024, at), Plan::Run(Kernel::Packets), "chunk {chunk}");
            }
        }
        assert_eq!(trials, [(0, 0), (10, 1), (20, 0), (30, 1), (40, 0), (50, 1)]);
        for _ in 0..TRIAL_CHUNKS {
            // Single rays' time is ignored: the camera queue never runs them.
            c.end(Queue::Camera, 1024, [2_000, 1, 1_000]);
        }
        assert_eq!(c.begin(Queue::Camera, 1024, 0.0), Plan::Run(Kernel::WidePackets));
        let r = c.report();
        assert_eq!((r[0].queue.as_str(), r[0].single_mrays), ("camera", None), "{r:?}");
    }

    /// Equal times keep packets, the renderer's long-standing default; a trial's `run` traces
    /// with every candidate, the first in turn, and returns the first one's result.
    #[test]
    fn ties_keep_packets_and_trials_run_every_candidate() {
        let c = TraversalChoice::timed();
        for _ in 0..TRIAL_CHUNKS {
            assert!(matches!(c.begin(Queue::Emitted, 1024, 0.0), Plan::Trial(_)));
            c.end(Queue::Emitted, 1024, [1_000, 1_000, 1_000]);
        }
        assert_eq!(c.begin(Queue::Emitted, 1024, 0.0), Plan::Run(Kernel::Packets));

        // One triangle is tree enough: `run` only hands the kernel to the closure.
        let (p0, p1, p2) = ([Vec3::ZERO], [Vec3::X], [Vec3::Y]);
        let (bvh, _) = Bvh::build(&p0, &p1, &p2);
        let tris = TriangleColumns { p0: &p0, p1: &p1, p2: &p2 };
        let c = TraversalChoice::timed();
        let mut ran = vec![];
        let mut out = [0u32; 1024];
        c.run(Queue::Secondary, 0.0, &bvh, tris, &mut out, |k, o| {
            ran.push(k);
            o.fill(1024);
        });
        assert_eq!((out[0], ran), (1024, vec![Kernel::Packets, Kernel::Single, Kernel::WidePackets]));
        // The second trial chunk starts with single rays.
        let mut ran = vec![];
        c.run(Queue::Secondary, 0.0, &bvh, tris, &mut out, |k, o| {
            ran.push(k);
            o.fill(7);
        });
        assert_eq!((out[0], ran), (7, vec![Kernel::Single, Kernel::WidePackets, Kernel::Packets]));
    }
}
