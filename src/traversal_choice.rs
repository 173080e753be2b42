//! Packets or single rays, chosen per ray queue by timing both on the queue's own rays.
//!
//! The SIMD traversal has two kernels that find the same hits: packets of 8 rays through the
//! PLOC BVH2 ([`crate::geometry::packet`]) and single rays through the 8-wide BVH collapsed from
//! a second, SAH-built tree ([`crate::geometry::wide_traverse`]). Which is faster depends on the
//! scene and the queue, not on the triangle count alone (BENCHMARKS.md, "Packets or single
//! rays, chosen per queue by timing"): packets win on camera rays everywhere and on the shadow
//! rays of the bundled boxes; single rays on photon rays in every scene measured (1.3–2.2× in the
//! trials) and on the final-gather rays of the bundled Cornell boxes (1.19–1.35×, the packets'
//! coherence sort included). So each queue times both kernels on its first chunks and keeps the
//! faster for the rest of the render (every later pass included). Hits are identical either
//! way, whatever tree each walks (every hit's t is settled into its triangle's box:
//! [`crate::geometry::slab::settle`]), so the choice changes speed only, never an image.
//! Reads chunk timings; writes the choice per queue.

use crate::code_path::CodePath;
use crate::geometry::bvh::{Bvh, Hit, TriangleColumns};
use crate::geometry::{wide_traverse, RayQuery};
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::sync::Mutex;
use std::time::Instant;

/// Chunks each queue traces with both kernels before it chooses.
pub const TRIAL_PAIRS: u32 = 6;

/// Chunks shorter than this are not timed (a queue's last chunk of a bounce can be a few rays:
/// too short to time).
pub const TRIAL_MIN_RAYS: usize = 256;

/// A SIMD traversal kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Kernel {
    /// Packets of 8 rays through the BVH2, rays sorted by coherence key.
    Packets,
    /// One ray at a time through the 8-wide BVH, in queue order.
    Single,
}

impl Kernel {
    /// The other kernel.
    fn other(self) -> Kernel {
        match self {
            Kernel::Packets => Kernel::Single,
            Kernel::Single => Kernel::Packets,
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
    /// Primary rays: always packets, which were faster on the camera rays of every measured
    /// scene (0.29–0.88× for single rays, from the Cornell boxes to the 1 M sphere; BENCHMARKS.md),
    /// and whose first chunks (the image's top rows, often sky) would not tell.
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

/// One queue's trial: chunks traced both ways (started, finished), rays and nanoseconds of each
/// kernel on them, and the choice.
#[derive(Clone, Copy, Debug, Default)]
struct Trial {
    started: u32,
    finished: u32,
    rays: u64,
    nanos: [u64; 2],
    chosen: Option<Kernel>,
}

impl Trial {
    /// Million rays per second of kernel `k` over the trial's chunks (each chunk's time counts
    /// at least 1 ns, so once a chunk is in this is finite).
    fn rate(&self, k: Kernel) -> f64 {
        self.rays as f64 * 1e3 / self.nanos[k as usize].max(1) as f64
    }
}

/// How a chunk is traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Plan {
    /// With this kernel, untimed.
    Run(Kernel),
    /// With both, this one first, each timed.
    Pair(Kernel),
}

/// What a queue chose, and the speeds it measured (million rays per second over its trial
/// chunks).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct QueueChoice {
    /// Queue name ([`Queue::name`]).
    pub queue: String,
    /// The kernel it runs.
    pub kernel: Kernel,
    /// Packets' speed in the trial.
    pub packets_mrays: f64,
    /// Single rays' speed in the trial.
    pub single_mrays: f64,
}

/// The per-queue choice of one render (shared by its passes).
///
/// A queue's first [`TRIAL_PAIRS`] chunks of [`TRIAL_MIN_RAYS`] rays or more are traced by
/// both kernels, one after the other (which goes first alternates), each timed: the same rays,
/// so the comparison does not depend on how chunks differ (sky or mesh, near or far). The queue
/// then keeps the kernel with more rays per second over those chunks; ties keep packets.
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
    /// Every queue but the camera rays' chooses by its trial (the renderer's default).
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
        if queue == Queue::Camera {
            return Plan::Run(Kernel::Packets);
        }
        let mut trials = trials.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let t = &mut trials[queue as usize];
        if let Some(k) = t.chosen {
            return Plan::Run(k);
        }
        if rays < TRIAL_MIN_RAYS || t.started >= TRIAL_PAIRS {
            return Plan::Run(Kernel::Packets);
        }
        t.started += 1;
        Plan::Pair(if t.started % 2 == 1 { Kernel::Packets } else { Kernel::Single })
    }

    /// Records a chunk of `rays` rays traced both ways in `nanos` (packets, single rays); after
    /// the last pair the queue chooses.
    fn end(&self, queue: Queue, rays: usize, nanos: [u64; 2]) {
        let Mode::Timed(trials) = &self.0 else { return };
        let mut trials = trials.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let t = &mut trials[queue as usize];
        t.finished += 1;
        t.rays += rays as u64;
        t.nanos[0] += nanos[0].max(1);
        t.nanos[1] += nanos[1].max(1);
        if t.chosen.is_none() && t.finished >= TRIAL_PAIRS {
            t.chosen = Some(if t.nanos[1] < t.nanos[0] { Kernel::Single } else { Kernel::Packets });
        }
    }

    /// Traces a chunk of `queue` into `out` with `trace(kernel, out)`: with the queue's kernel,
    /// or in a trial with both, keeping the packets' result whichever ran first (the two are
    /// identical; debug builds check it). The 8-wide BVH is built (once) before any timer starts.
    fn run<T: Clone + PartialEq + std::fmt::Debug>(
        &self,
        queue: Queue,
        bvh: &Bvh,
        tris: TriangleColumns<'_>,
        out: &mut [T],
        mut trace: impl FnMut(Kernel, &mut [T]),
    ) {
        let first = match self.begin(queue, out.len()) {
            Plan::Run(k) => return trace(k, out),
            Plan::Pair(k) => k,
        };
        let _ = bvh.wide(tris);
        let mut single = out.to_vec();
        let mut nanos = [0u64; 2];
        for k in [first, first.other()] {
            let into = if k == Kernel::Packets { &mut *out } else { &mut single[..] };
            let start = Instant::now();
            trace(k, into);
            nanos[k as usize] = u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX);
        }
        debug_assert_eq!(*out, single[..], "packets and single rays disagree");
        self.end(queue, out.len(), nanos);
    }

    /// Closest hits of a chunk of `queue` (in input order). The scalar code path runs the
    /// scalar twin, untimed.
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
            Kernel::Single => wide_traverse::closest_rays::<true>(bvh.wide(tris), rays, o),
        });
        out
    }

    /// Any-hit tests of a chunk of `queue` into `out`.
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
            Kernel::Packets => set.occluded(bvh, tris, rays, o),
            Kernel::Single => wide_traverse::occluded_rays::<true>(bvh.wide(tris), rays, o),
        });
    }

    /// Each queue's choice: the kernel and the speeds its trial measured. Queues without a trial
    /// (camera rays; every queue of a fixed choice), still in it, or never run are left out.
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
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trial traces its chunks both ways (packets first, then single rays first, in turn),
    /// leaves short chunks and chunks beyond the trial's count to packets, keeps the kernel with
    /// more rays per second once the pairs are in, and never times again; queues choose apart;
    /// camera rays never try single rays, and a fixed choice never times.
    #[test]
    fn queues_keep_the_faster_kernel() {
        let c = TraversalChoice::timed();
        assert_eq!(c.begin(Queue::Shadows, TRIAL_MIN_RAYS - 1), Plan::Run(Kernel::Packets));
        let plans: Vec<Plan> = (0..TRIAL_PAIRS).map(|_| c.begin(Queue::Shadows, 1024)).collect();
        assert_eq!(&plans[..2], &[Plan::Pair(Kernel::Packets), Plan::Pair(Kernel::Single)]);
        // All pairs under way: further chunks run packets until the trial ends.
        assert_eq!(c.begin(Queue::Shadows, 1024), Plan::Run(Kernel::Packets));
        for _ in 0..TRIAL_PAIRS {
            // 1024 rays: packets in 2 µs, single rays in 1 µs.
            c.end(Queue::Shadows, 1024, [2_000, 1_000]);
        }
        assert_eq!(c.begin(Queue::Shadows, 1024), Plan::Run(Kernel::Single));
        assert_eq!(c.begin(Queue::Camera, 1024), Plan::Run(Kernel::Packets));
        // The photon queue has not chosen: it starts its own trial, and the report leaves it out.
        assert_eq!(c.begin(Queue::Photons, 1024), Plan::Pair(Kernel::Packets));
        let r = c.report();
        assert_eq!(r.len(), 1);
        assert_eq!((r[0].queue.as_str(), r[0].kernel), ("shadow", Kernel::Single));
        let close = |a: f64, b: f64| (a - b).abs() < 1e-9;
        assert!(close(r[0].single_mrays, 1024.0) && close(r[0].packets_mrays, 512.0));

        let packets = TraversalChoice::fixed(Kernel::Packets);
        assert_eq!(packets.begin(Queue::Shadows, 1024), Plan::Run(Kernel::Packets));
        assert!(packets.report().is_empty());
        assert_eq!(TraversalChoice::fixed(Kernel::Single).begin(Queue::Camera, 1024), Plan::Run(Kernel::Single));
    }

    /// Equal times keep packets, the renderer's long-standing default; a trial's `run` traces
    /// with both kernels, in turn first, and returns the result.
    #[test]
    fn ties_keep_packets_and_trials_run_both() {
        let c = TraversalChoice::timed();
        for _ in 0..TRIAL_PAIRS {
            assert!(matches!(c.begin(Queue::Emitted, 1024), Plan::Pair(_)));
            c.end(Queue::Emitted, 1024, [1_000, 1_000]);
        }
        assert_eq!(c.begin(Queue::Emitted, 1024), Plan::Run(Kernel::Packets));

        // One triangle is tree enough: `run` only hands the kernel to the closure.
        let (p0, p1, p2) = ([Vec3::ZERO], [Vec3::X], [Vec3::Y]);
        let (bvh, _) = Bvh::build(&p0, &p1, &p2);
        let tris = TriangleColumns { p0: &p0, p1: &p1, p2: &p2 };
        let c = TraversalChoice::timed();
        let mut ran = vec![];
        let mut out = [0u32; 1024];
        c.run(Queue::Secondary, &bvh, tris, &mut out, |k, o| {
            ran.push(k);
            o.fill(1024);
        });
        assert_eq!((out[0], ran), (1024, vec![Kernel::Packets, Kernel::Single]));
        // The second pair runs single rays first.
        let mut ran = vec![];
        c.run(Queue::Secondary, &bvh, tris, &mut out, |k, o| {
            ran.push(k);
            o.fill(7);
        });
        assert_eq!((out[0], ran), (7, vec![Kernel::Single, Kernel::Packets]));
    }
}
