//! `photonwave bench`'s traversal rows: packets against obvhs's single rays (BVH2 and CWBVH), our
//! scalar twin, the 8-wide BVH (single rays and packets) and, built with `--features embree`,
//! Embree 3, on the same rays in the same alternating rounds. Reads a scene and its ray sets;
//! writes [`TraversalRow`]s.

use super::{median, time_each, time_pair, RaySets, CHUNK};
use crate::error::Error;
use crate::geometry::bvh::CwBaseline;
use crate::geometry::packet::{closest_packets, occluded_packets};
use crate::geometry::wide_traverse::Visits;
use crate::geometry::RayQuery;
use crate::parallel::map_chunks;
use crate::scene::Scene;
use serde::Serialize;
use std::cell::Cell;
use std::time::Instant;

/// One traversal measurement.
#[derive(Clone, Debug, Serialize)]
pub struct TraversalRow {
    /// Scene name.
    pub scene: String,
    /// Ray set: camera, shadow or diffuse.
    pub rays: &'static str,
    /// closest or any.
    pub query: &'static str,
    /// Rays in the set.
    pub count: usize,
    /// Packet traversal, million rays per second (median).
    pub packet_mrays: f64,
    /// obvhs single-ray traversal, million rays per second (median).
    pub single_mrays: f64,
    /// packet / single.
    pub ratio: f64,
    /// The packet kernel's scalar twin (our single-ray traversal), million rays per second.
    pub twin_mrays: f64,
    /// obvhs's CWBVH (8-wide nodes) single-ray traversal over the same boxes, million rays per
    /// second: the other tree obvhs offers.
    pub cwbvh_mrays: f64,
    /// Single-ray traversal of the 8-wide BVH (one ray against eight child boxes per step),
    /// million rays per second.
    pub wide_mrays: f64,
    /// Packets of 8 rays through the 8-wide BVH (8 rays against each child box in turn),
    /// million rays per second.
    pub wide_packet_mrays: f64,
    /// 8-wide BVH nodes visited per ray (each a test of one ray against up to eight boxes).
    pub nodes_per_ray: f64,
    /// Triangles tested per ray by the 8-wide traversal (one ray against a block of up to eight
    /// per test).
    pub triangles_per_ray: f64,
    /// Of those, tests the 8-wide triangle test handed to the scalar one, per ray.
    pub scalar_per_ray: f64,
    /// Rays the BVH2 traversals (packet, twin, obvhs) report hit and obvhs's CWBVH traversal
    /// does not (negative: the other way round).
    pub cwbvh_lost_hits: i64,
    /// Embree 3's single-ray traversal (`rtcIntersect1`, `rtcOccluded1`) over its own
    /// HIGH-quality BVH of the same triangles, million rays per second; `null` unless built with
    /// `--features embree`.
    pub embree1_mrays: Option<f64>,
    /// Embree 3's 8-ray packets (`rtcIntersect8`, `rtcOccluded8`) on the same packets of 8 the
    /// packet traversal takes, million rays per second; `null` without `--features embree`.
    pub embree8_mrays: Option<f64>,
    /// packet ÷ the faster of Embree's two.
    pub ratio_vs_embree: Option<f64>,
    /// The kernel the renderer's per-queue choice runs on such rays
    /// ([`crate::traversal_choice`]), named as its stats name them: the fastest here of BVH2
    /// packets (`packets`), the 8-wide single ray (`single`; not tried on camera rays) and 8-wide
    /// packets (`wide_packets`), as its trial picks.
    pub renderer_kernel: &'static str,
    /// That kernel's speed here, million rays per second.
    pub renderer_mrays: f64,
    /// `renderer_mrays` ÷ the faster of Embree's two.
    pub renderer_vs_embree: Option<f64>,
    /// Rays Embree reports hit minus rays ours report hit (Embree counts hits at t = 0 and
    /// differs from our watertight test on edges).
    pub embree_extra_hits: Option<i64>,
    /// Embree's single rays with `RTC_SCENE_FLAG_ROBUST` (its watertight triangle test and
    /// conservative box test, as ours always are), million rays per second; `null` without
    /// `--features embree`.
    pub embree_robust1_mrays: Option<f64>,
    /// Embree's 8-ray packets in robust mode, million rays per second.
    pub embree_robust8_mrays: Option<f64>,
    /// `renderer_mrays` ÷ the faster of robust Embree's two: the comparison at equal accuracy.
    pub renderer_vs_embree_robust: Option<f64>,
    /// Rays each of Embree's four calls reports hit minus rays ours report hit: default mode's
    /// single rays and packets, robust mode's single rays and packets. Embree's own calls may
    /// differ from each other by a ray or two on edges (seen: robust `rtcIntersect1` against
    /// `rtcIntersect8` on CornellBox-Glossy's shadow rays, one ray of 217 518), so they are
    /// reported, not asserted.
    pub embree_extra_hits_by_call: Option<[i64; 4]>,
}

/// Rays of `rays` that a kernel reports as hitting anything: `hits(chunk)` counts one chunk;
/// chunks run on `threads` threads.
fn count_hits(rays: &[RayQuery], threads: usize, hits: impl Fn(&[RayQuery]) -> usize + Sync) -> usize {
    map_chunks(rays.len(), CHUNK, threads, |r| hits(&rays[r]), |_| {}).into_iter().sum()
}

/// Lanes of a closest-hit answer that found a triangle.
fn found<T>(out: &[Option<T>]) -> usize {
    out.iter().filter(|h| h.is_some()).count()
}

/// Lanes of an any-hit answer that are blocked.
fn blocked(out: &[bool]) -> usize {
    out.iter().filter(|&&b| b).count()
}

/// Every traversal the rows time, each as "how many rays of this chunk hit" for one query kind
/// (closest hit, or any hit when `any`).
struct Kernels<'a> {
    scene: &'a Scene,
    cw: &'a CwBaseline,
    any: bool,
}

impl Kernels<'_> {
    /// BVH2 packets of 8 (the renderer's default kernel).
    fn packet(&self, c: &[RayQuery]) -> usize {
        let (bvh, tris) = (self.scene.bvh(), self.scene.columns());
        if self.any {
            let mut out = vec![false; c.len()];
            occluded_packets(bvh, tris, c, &mut out);
            blocked(&out)
        } else {
            let mut out = vec![None; c.len()];
            closest_packets(bvh, tris, c, &mut out);
            found(&out)
        }
    }

    /// obvhs's single-ray traversal of the same BVH2.
    fn obvhs(&self, c: &[RayQuery]) -> usize {
        let (bvh, tris) = (self.scene.bvh(), self.scene.columns());
        let hit = |q: &RayQuery| {
            if self.any {
                bvh.occluded_obvhs(tris, q.origin, q.direction, q.t_max)
            } else {
                bvh.closest_obvhs(tris, q.origin, q.direction, q.t_max).is_some()
            }
        };
        c.iter().filter(|q| hit(q)).count()
    }

    /// The packet kernel's scalar twin (the scene's own single-ray queries).
    fn twin(&self, c: &[RayQuery]) -> usize {
        let hit = |q: &RayQuery| {
            if self.any {
                self.scene.occluded(q.origin, q.direction, q.t_max)
            } else {
                self.scene.intersect(q.origin, q.direction, q.t_max).is_some()
            }
        };
        c.iter().filter(|q| hit(q)).count()
    }

    /// obvhs's CWBVH over the same boxes.
    fn cwbvh(&self, c: &[RayQuery]) -> usize {
        let tris = self.scene.columns();
        let hit = |q: &RayQuery| {
            if self.any {
                self.cw.occluded(tris, q.origin, q.direction, q.t_max)
            } else {
                self.cw.closest(tris, q.origin, q.direction, q.t_max)
            }
        };
        c.iter().filter(|q| hit(q)).count()
    }

    /// Single rays through the 8-wide BVH.
    fn wide(&self, c: &[RayQuery]) -> usize {
        use crate::geometry::wide_traverse as w;
        let wide = self.scene.bvh().wide(self.scene.columns());
        if self.any {
            let mut out = vec![false; c.len()];
            w::occluded_rays::<true>(wide, None, c, &mut out);
            blocked(&out)
        } else {
            let mut out = vec![None; c.len()];
            w::closest_rays::<true>(wide, None, c, &mut out);
            found(&out)
        }
    }

    /// Packets of 8 through the 8-wide BVH.
    fn wide_packet(&self, c: &[RayQuery]) -> usize {
        use crate::geometry::wide_packet as w;
        let tris = self.scene.columns();
        let wide = self.scene.bvh().wide(tris);
        if self.any {
            let mut out = vec![false; c.len()];
            w::occluded_packets8(wide, tris, c, &mut out, w::THIN_LANES);
            blocked(&out)
        } else {
            let mut out = vec![None; c.len()];
            w::closest_packets8(wide, tris, c, &mut out, w::THIN_LANES);
            found(&out)
        }
    }
}

/// Embree's trees over the scene: default and robust mode.
#[cfg(feature = "embree")]
struct Embree {
    fast: super::embree::EmbreeScene,
    robust: super::embree::EmbreeScene,
}

/// Without `--features embree` there is no Embree to time.
#[cfg(not(feature = "embree"))]
struct Embree;

impl Embree {
    #[cfg(feature = "embree")]
    fn build(scene: &Scene) -> Result<Self, Error> {
        use super::embree::EmbreeScene;
        let build = |robust| EmbreeScene::build(scene.columns(), robust).map_err(|message| Error::Scene { message });
        Ok(Embree { fast: build(false)?, robust: build(true)? })
    }

    #[cfg(not(feature = "embree"))]
    #[allow(clippy::unnecessary_wraps)]
    fn build(_: &Scene) -> Result<Self, Error> {
        Ok(Embree)
    }

    /// Embree's four calls (default single rays and packets, robust single rays and packets),
    /// each storing its hit count in `hits`; none without the feature.
    #[cfg(feature = "embree")]
    fn runs<'a>(
        &'a self,
        rays: &'a [RayQuery],
        threads: usize,
        any: bool,
        hits: &'a [Cell<usize>],
    ) -> Vec<Box<dyn FnMut() + 'a>> {
        vec![
            Box::new(move || hits[0].set(count_hits(rays, threads, |c| self.fast.count_single(c, any)))),
            Box::new(move || hits[1].set(count_hits(rays, threads, |c| self.fast.count_packets(c, any)))),
            Box::new(move || hits[2].set(count_hits(rays, threads, |c| self.robust.count_single(c, any)))),
            Box::new(move || hits[3].set(count_hits(rays, threads, |c| self.robust.count_packets(c, any)))),
        ]
    }

    #[cfg(not(feature = "embree"))]
    #[allow(clippy::unused_self)]
    fn runs<'a>(&'a self, _: &'a [RayQuery], _: usize, _: bool, _: &'a [Cell<usize>]) -> Vec<Box<dyn FnMut() + 'a>> {
        vec![]
    }
}

/// Median seconds and hit counts of one ray set and query.
struct Timings {
    /// packet, obvhs, 8-wide single, 8-wide packet, twin, CWBVH.
    seconds: [f64; 6],
    /// Rays each of those reports hit.
    hits: [usize; 6],
    /// Embree's four calls' seconds and hit counts, when built with the feature.
    embree: Option<([f64; 4], [usize; 4])>,
}

/// Times every kernel on `rays`: ours, obvhs and (with the feature) Embree's four calls in the
/// same alternating rounds; then the twin against the CWBVH, which are slower, as a pair.
fn time_kernels(kernels: &Kernels<'_>, embree: &Embree, rays: &[RayQuery], threads: usize, reps: usize) -> Timings {
    let hits: [Cell<usize>; 10] = Default::default();
    let mut runs: Vec<Box<dyn FnMut() + '_>> = vec![
        Box::new(|| hits[0].set(count_hits(rays, threads, |c| kernels.packet(c)))),
        Box::new(|| hits[1].set(count_hits(rays, threads, |c| kernels.obvhs(c)))),
        Box::new(|| hits[2].set(count_hits(rays, threads, |c| kernels.wide(c)))),
        Box::new(|| hits[3].set(count_hits(rays, threads, |c| kernels.wide_packet(c)))),
    ];
    runs.extend(embree.runs(rays, threads, kernels.any, &hits[6..]));
    let mut refs: Vec<&mut dyn FnMut()> = runs.iter_mut().map(|r| &mut **r as &mut dyn FnMut()).collect();
    let t = time_each(reps, &mut refs);
    drop(refs);
    drop(runs);
    let (tt, tc) = time_pair(
        reps,
        || hits[4].set(count_hits(rays, threads, |c| kernels.twin(c))),
        || hits[5].set(count_hits(rays, threads, |c| kernels.cwbvh(c))),
    );
    let hits = hits.map(Cell::into_inner);
    Timings {
        seconds: [t[0], t[1], t[2], t[3], tt, tc],
        hits: std::array::from_fn(|i| hits[i]),
        embree: (t.len() == 8).then(|| ([t[4], t[5], t[6], t[7]], [hits[6], hits[7], hits[8], hits[9]])),
    }
}

/// Packet against obvhs single-ray traversal on every set and query. Also checks that both
/// report the same number of hits (they differ only in ties between equally distant triangles,
/// which do not change whether a ray hits).
///
/// # Errors
/// With `--features embree`, if Embree cannot build its BVH over the scene.
pub fn traversal(
    name: &str,
    scene: &Scene,
    sets: &RaySets,
    threads: usize,
    reps: usize,
) -> Result<Vec<TraversalRow>, Error> {
    let cw = CwBaseline::build(scene.columns());
    let embree = Embree::build(scene)?;
    let mut rows = vec![];
    for (label, rays) in [("camera", &sets.camera), ("shadow", &sets.shadow), ("diffuse", &sets.diffuse)] {
        if rays.is_empty() {
            continue;
        }
        for any in [false, true] {
            let query = if any { "any" } else { "closest" };
            let timings = time_kernels(&Kernels { scene, cw: &cw, any }, &embree, rays, threads, reps);
            let [hp, hs, hw, hwp, ht, _] = timings.hits;
            assert_eq!(hp, hs, "{name} {label} {query}: packet and single-ray hit counts differ");
            assert_eq!(hw, hs, "{name} {label} {query}: 8-wide and obvhs hit counts differ");
            assert_eq!(hwp, hs, "{name} {label} {query}: 8-wide packets and obvhs hit counts differ");
            assert_eq!(ht, hs, "{name} {label} {query}: scalar twin and obvhs hit counts differ");
            // Not asserted: obvhs's CWBVH traversal loses a few hits (recorded, see BENCHMARKS.md).
            let visits = count_visits(scene.bvh().wide(scene.columns()), rays, any);
            rows.push(TraversalRow::new(name, label, query, rays.len(), &timings, &visits));
        }
    }
    Ok(rows)
}

impl TraversalRow {
    /// The row of one ray set (`label`, `count` rays) and query from its timings and the 8-wide
    /// traversal's work.
    fn new(name: &str, label: &'static str, query: &'static str, count: usize, t: &Timings, visits: &Visits) -> Self {
        let [tp, ts, tw, twp, tt, tc] = t.seconds;
        let hs = t.hits[1];
        let m = count as f64 * 1e-6;
        let per_ray = |n: u64| n as f64 / count as f64;
        // What the renderer's trial would keep: the fastest candidate, ties to the earlier
        // (camera rays never try single rays).
        let mut candidates = vec![("packets", tp)];
        if label != "camera" {
            candidates.push(("single", tw));
        }
        candidates.push(("wide_packets", twp));
        let (renderer_kernel, t_renderer) =
            candidates.into_iter().reduce(|best, c| if c.1 < best.1 { c } else { best }).expect("packets");
        let embree = t.embree.map(|(e, hits)| (e, hits.map(|h| h as i64 - t.hits[0] as i64)));
        TraversalRow {
            scene: name.to_string(),
            rays: label,
            query,
            count,
            packet_mrays: m / tp,
            single_mrays: m / ts,
            ratio: ts / tp,
            twin_mrays: m / tt,
            cwbvh_mrays: m / tc,
            wide_mrays: m / tw,
            wide_packet_mrays: m / twp,
            nodes_per_ray: per_ray(visits.nodes),
            triangles_per_ray: per_ray(visits.triangles),
            scalar_per_ray: per_ray(visits.scalar),
            cwbvh_lost_hits: hs as i64 - t.hits[5] as i64,
            embree1_mrays: embree.map(|(e, _)| m / e[0]),
            embree8_mrays: embree.map(|(e, _)| m / e[1]),
            ratio_vs_embree: embree.map(|(e, _)| e[0].min(e[1]) / tp),
            renderer_kernel,
            renderer_mrays: m / t_renderer,
            renderer_vs_embree: embree.map(|(e, _)| e[0].min(e[1]) / t_renderer),
            embree_extra_hits: embree.map(|(_, x)| x[0]),
            embree_robust1_mrays: embree.map(|(e, _)| m / e[2]),
            embree_robust8_mrays: embree.map(|(e, _)| m / e[3]),
            renderer_vs_embree_robust: embree.map(|(e, _)| e[2].min(e[3]) / t_renderer),
            embree_extra_hits_by_call: embree.map(|(_, x)| x),
        }
    }
}

/// The 8-wide traversal's work over `rays` (closest hit, or any hit when `any`).
fn count_visits(bvh: &crate::geometry::wide::Bvh8, rays: &[RayQuery], any: bool) -> Visits {
    use crate::geometry::wide_traverse::{closest_counted, occluded_counted};
    let mut stack = crate::geometry::traverse::Stack::new();
    let mut v = Visits::default();
    for r in rays {
        if any {
            let _ = occluded_counted::<true, true>(bvh, None, r, &mut stack, &mut v);
        } else {
            let _ = closest_counted::<true, true>(bvh, None, r, &mut stack, &mut v);
        }
    }
    v
}

/// Throughput (Mrays/s, median) of packet traversal on each ray set and query for each
/// hand-over threshold in `thins` (lanes at or below which a node goes to single-ray traversal).
#[must_use]
pub fn thin_sweep(
    scene: &Scene,
    sets: &RaySets,
    thins: &[u32],
    reps: usize,
) -> Vec<(&'static str, &'static str, u32, f64)> {
    use crate::geometry::packet::{closest_packets_thin, occluded_packets_thin};
    let mut rows = vec![];
    for (label, rays) in [("camera", &sets.camera), ("shadow", &sets.shadow), ("diffuse", &sets.diffuse)] {
        for query in ["closest", "any"] {
            let mut hits = vec![None; rays.len()];
            let mut blocked = vec![false; rays.len()];
            let mut times: Vec<Vec<f64>> = vec![vec![]; thins.len()];
            // Interleaved: every threshold once per round.
            for _ in 0..reps.max(1) {
                for (k, &thin) in thins.iter().enumerate() {
                    let t = Instant::now();
                    if query == "closest" {
                        closest_packets_thin(scene.bvh(), scene.columns(), rays, &mut hits, thin);
                    } else {
                        occluded_packets_thin(scene.bvh(), scene.columns(), rays, &mut blocked, thin);
                    }
                    times[k].push(t.elapsed().as_secs_f64());
                }
            }
            for (k, &thin) in thins.iter().enumerate() {
                rows.push((label, query, thin, rays.len() as f64 * 1e-6 / median(times[k].clone())));
            }
        }
    }
    rows
}
