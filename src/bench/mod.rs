//! `photonwave bench`: throughput of the SIMD kernels against their baselines, in one process, on
//! identical rays and queries. Each pair of kernels is timed alternately (packet, single, packet,
//! …) and the median of the repetitions is reported, so machine noise hits both sides alike.
//!
//! Ray sets per scene, all from a 512 × 512 camera in 8 × 8 pixel tiles (packets of 8 are rows
//! of a tile):
//! - `camera`: primary rays;
//! - `shadow`: from each camera hit to a uniform point on a light above its surface (t_max just
//!   short of the light);
//! - `diffuse`: cosine-distributed bounce rays from each camera hit, sorted by the renderer's
//!   coherence key (direction octant, then origin cell) as the wavefront engine sorts its queues.
//!
//! Each set is traced for the closest hit and for any hit (shadow rays use their t_max, the
//! others t = ∞ — any hit then answers "is anything there").

mod density;
#[cfg(feature = "embree")]
pub mod embree;

use crate::error::Error;
use crate::geometry::packet::{closest_packets, occluded_packets};
use crate::geometry::{offset_ray_origin, RayQuery};
use crate::parallel::map_chunks;
use crate::rng::{Domain, Sampler};
use crate::sampling::{cosine_hemisphere, Frame};
use crate::scene::camera::CameraRays;
use crate::scene::{Light, Scene};
pub use density::{DensityRow, BENCH_PHOTONS};
use glam::Vec3;
use serde::Serialize;
use std::time::Instant;

/// The flags this build was compiled with: `(target_cpu, rustflags, enabled SIMD features)`.
#[must_use]
pub fn build_flags() -> (String, String, Vec<&'static str>) {
    let flags = env!("PHOTONWAVE_RUSTFLAGS").trim().to_string();
    let cpu = flags
        .split_whitespace()
        .flat_map(|w| w.split(','))
        .find_map(|w| w.strip_prefix("target-cpu="))
        .unwrap_or("default (x86-64: SSE2 only)")
        .to_string();
    let mut features = vec![];
    if cfg!(target_feature = "sse4.2") {
        features.push("sse4.2");
    }
    if cfg!(target_feature = "avx") {
        features.push("avx");
    }
    if cfg!(target_feature = "avx2") {
        features.push("avx2");
    }
    if cfg!(target_feature = "fma") {
        features.push("fma");
    }
    (cpu, flags, features)
}

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
    /// Rays Embree reports hit minus rays ours report hit (Embree counts hits at t = 0 and
    /// differs from our watertight test on edges).
    pub embree_extra_hits: Option<i64>,
}

/// Image side of the bench camera.
pub const SIDE: u32 = 512;

/// Rays of the three sets for a scene seen through `camera`.
pub struct RaySets {
    /// Primary rays.
    pub camera: Vec<RayQuery>,
    /// Rays from camera hits toward light samples.
    pub shadow: Vec<RayQuery>,
    /// Bounce rays from camera hits, sorted by coherence key.
    pub diffuse: Vec<RayQuery>,
    /// Camera hits on surfaces: position and geometric normal facing the camera.
    pub hits: Vec<(Vec3, Vec3)>,
}

/// Pixel (x, y) of the `i`-th ray in 8 × 8 tile order.
fn tile_pixel(i: u32) -> (u32, u32) {
    let tiles_x = SIDE / 8;
    let (tile, within) = (i / 64, i % 64);
    ((tile % tiles_x) * 8 + within % 8, (tile / tiles_x) * 8 + within / 8)
}

impl RaySets {
    /// Builds the sets (deterministic: fixed seed), shadow rays toward the scene's lights.
    #[must_use]
    pub fn new(scene: &Scene, cam: &CameraRays) -> Self {
        Self::with_light(scene, cam, None)
    }

    /// As [`Self::new`], but with `light` given, every shadow ray goes to that point instead of
    /// to a sample of the scene's lights (so that a bare mesh without lights has shadow rays).
    #[must_use]
    pub fn with_light(scene: &Scene, cam: &CameraRays, light: Option<Vec3>) -> Self {
        let n = SIDE * SIDE;
        let camera: Vec<RayQuery> = (0..n)
            .map(|i| {
                let (x, y) = tile_pixel(i);
                let (o, d) = cam.ray(x as f32 + 0.5, y as f32 + 0.5);
                RayQuery::new(o, d, f32::INFINITY)
            })
            .collect();
        let (mut shadow, mut diffuse, mut hits) = (vec![], vec![], vec![]);
        for (i, r) in camera.iter().enumerate() {
            let Some(h) = scene.intersect(r.origin, r.direction, f32::INFINITY) else { continue };
            let sp = scene.surface(&h);
            let ng = if sp.frame.ng.dot(r.direction) > 0.0 { -sp.frame.ng } else { sp.frame.ng };
            hits.push((sp.p, ng));
            let s = Sampler::new(1, Domain::Camera, i as u64);
            // As the renderer does, only toward lights above the surface.
            let target = light.or_else(|| light_point(scene, [s.get(0, 0), s.get(0, 1), s.get(0, 2)]));
            if let Some(target) = target.filter(|&q| (q - sp.p).dot(ng) > 0.0) {
                let o = offset_ray_origin(sp.p, sp.p_error, ng, target - sp.p);
                shadow.push(RayQuery::new(o, target - o, 1.0 - 1e-4));
            }
            let d = Frame::new(ng).to_world(cosine_hemisphere([s.get(0, 3), s.get(0, 4)]));
            diffuse.push(RayQuery::new(offset_ray_origin(sp.p, sp.p_error, ng, d), d, f32::INFINITY));
        }
        diffuse.sort_by_key(|r| crate::code_path::coherence_key(r.origin, r.direction, scene.bounds));
        RaySets { camera, shadow, diffuse, hits }
    }
}

/// A point on a light picked with three uniform numbers: area lights by power, then uniform on
/// the triangle; point and spot lights at their position; None for a scene lit only by
/// directional light.
fn light_point(scene: &Scene, u: [f32; 3]) -> Option<Vec3> {
    let idx = scene.light_power.sample(u[0]);
    match scene.lights.get(idx)? {
        Light::Area { tri, .. } => {
            let t = scene.triangle(*tri);
            let (b1, b2) = crate::sampling::uniform_triangle([u[1], u[2]]);
            Some(t.p[0] * (1.0 - b1 - b2) + t.p[1] * b1 + t.p[2] * b2)
        }
        Light::Point { position, .. } | Light::Spot { position, .. } => Some(*position),
        Light::Directional { .. } | Light::Sun { .. } | Light::Environment => None,
    }
}

/// Median of the samples.
pub(crate) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Times the `kernels` in turn, `reps` rounds of one run each; returns their median seconds.
pub fn time_alternating<const N: usize>(reps: usize, mut kernels: [&mut dyn FnMut(); N]) -> [f64; N] {
    let t = time_each(reps, &mut kernels);
    std::array::from_fn(|i| t[i])
}

/// [`time_alternating`] over a list whose length is known only at run time.
pub fn time_each(reps: usize, kernels: &mut [&mut dyn FnMut()]) -> Vec<f64> {
    let mut times: Vec<Vec<f64>> = vec![vec![]; kernels.len()];
    for _ in 0..reps.max(1) {
        for (k, t) in kernels.iter_mut().zip(&mut times) {
            let start = Instant::now();
            k();
            t.push(start.elapsed().as_secs_f64());
        }
    }
    times.into_iter().map(median).collect()
}

/// Times `a` and `b` alternately `reps` times each; returns their median seconds.
pub fn time_pair(reps: usize, mut a: impl FnMut(), mut b: impl FnMut()) -> (f64, f64) {
    let [ta, tb] = time_alternating(reps, [&mut a, &mut b]);
    (ta, tb)
}

/// Chunk of rays per thread task.
pub(crate) const CHUNK: usize = 4096;

/// A per-ray kernel as a chunk counter for [`count_hits`].
fn per_ray(hit: impl Fn(&RayQuery) -> bool + Sync) -> impl Fn(&[RayQuery]) -> usize + Sync {
    move |c| c.iter().filter(|q| hit(q)).count()
}

/// Rays of `rays` that a kernel reports as hitting anything: `hits(chunk)` counts one chunk;
/// chunks run on `threads` threads.
fn count_hits(rays: &[RayQuery], threads: usize, hits: impl Fn(&[RayQuery]) -> usize + Sync) -> usize {
    map_chunks(rays.len(), CHUNK, threads, |r| hits(&rays[r]), |_| {}).into_iter().sum()
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
    let cw = crate::geometry::bvh::CwBaseline::build(scene.columns());
    #[cfg(feature = "embree")]
    let embree_scene = embree::EmbreeScene::build(scene.columns()).map_err(|message| Error::Scene { message })?;
    let (bvh, tris) = (scene.bvh(), scene.columns());
    let mut rows = vec![];
    for (label, rays) in [("camera", &sets.camera), ("shadow", &sets.shadow), ("diffuse", &sets.diffuse)] {
        if rays.is_empty() {
            continue;
        }
        for any in [false, true] {
            let query = if any { "any" } else { "closest" };
            // Each kernel as "how many rays of this chunk hit".
            let packet = |c: &[RayQuery]| {
                if any {
                    let mut out = vec![false; c.len()];
                    occluded_packets(bvh, tris, c, &mut out);
                    out.iter().filter(|&&b| b).count()
                } else {
                    let mut out = vec![None; c.len()];
                    closest_packets(bvh, tris, c, &mut out);
                    out.iter().filter(|h| h.is_some()).count()
                }
            };
            let obvhs = per_ray(|q: &RayQuery| {
                if any {
                    bvh.occluded_obvhs(tris, q.origin, q.direction, q.t_max)
                } else {
                    bvh.closest_obvhs(tris, q.origin, q.direction, q.t_max).is_some()
                }
            });
            let twin = per_ray(|q: &RayQuery| {
                if any {
                    scene.occluded(q.origin, q.direction, q.t_max)
                } else {
                    scene.intersect(q.origin, q.direction, q.t_max).is_some()
                }
            });
            let cwbvh = per_ray(|q: &RayQuery| {
                if any {
                    cw.occluded(tris, q.origin, q.direction, q.t_max)
                } else {
                    cw.closest(tris, q.origin, q.direction, q.t_max)
                }
            });
            let wide = |c: &[RayQuery]| {
                use crate::geometry::wide_traverse as w;
                if any {
                    let mut out = vec![false; c.len()];
                    w::occluded_rays::<true>(bvh.wide(tris), c, &mut out);
                    out.iter().filter(|&&b| b).count()
                } else {
                    let mut out = vec![None; c.len()];
                    w::closest_rays::<true>(bvh.wide(tris), c, &mut out);
                    out.iter().filter(|h| h.is_some()).count()
                }
            };
            let (mut hp, mut hs, mut ht, mut hc, mut hw) = (0, 0, 0, 0, 0);
            // One alternating round: ours, obvhs, and (with the feature) Embree's two.
            let mut run_packet = || hp = count_hits(rays, threads, packet);
            let mut run_obvhs = || hs = count_hits(rays, threads, &obvhs);
            let mut run_wide = || hw = count_hits(rays, threads, wide);
            let mut kernels: Vec<&mut dyn FnMut()> = vec![&mut run_packet, &mut run_obvhs, &mut run_wide];
            #[cfg(feature = "embree")]
            let (mut h1, mut h8) = (0, 0);
            #[cfg(feature = "embree")]
            let mut run_embree1 = || h1 = count_hits(rays, threads, |c| embree_scene.count_single(c, any));
            #[cfg(feature = "embree")]
            let mut run_embree8 = || h8 = count_hits(rays, threads, |c| embree_scene.count_packets(c, any, false));
            #[cfg(feature = "embree")]
            kernels.extend([&mut run_embree1 as &mut dyn FnMut(), &mut run_embree8]);
            let t = time_each(reps, &mut kernels);
            drop(kernels);
            let (tp, ts, tw) = (t[0], t[1], t[2]);
            #[cfg(feature = "embree")]
            let embree = {
                assert_eq!(h1, h8, "{name} {label} {query}: Embree's single rays and packets disagree");
                Some((t[3], t[4], h1 as i64 - hp as i64))
            };
            #[cfg(not(feature = "embree"))]
            let embree: Option<(f64, f64, i64)> = None;
            assert_eq!(hp, hs, "{name} {label} {query}: packet and single-ray hit counts differ");
            assert_eq!(hw, hs, "{name} {label} {query}: 8-wide and obvhs hit counts differ");
            let (tt, tc) =
                time_pair(reps, || ht = count_hits(rays, threads, &twin), || hc = count_hits(rays, threads, &cwbvh));
            assert_eq!(ht, hs, "{name} {label} {query}: scalar twin and obvhs hit counts differ");
            // Not asserted: obvhs's CWBVH traversal loses a few hits (recorded, see BENCHMARKS.md).
            let visits = count_visits(bvh.wide(tris), rays, any);
            let m = rays.len() as f64 * 1e-6;
            rows.push(TraversalRow {
                nodes_per_ray: visits.nodes as f64 / rays.len() as f64,
                triangles_per_ray: visits.triangles as f64 / rays.len() as f64,
                scalar_per_ray: visits.scalar as f64 / rays.len() as f64,
                scene: name.to_string(),
                rays: label,
                query,
                count: rays.len(),
                packet_mrays: m / tp,
                single_mrays: m / ts,
                ratio: ts / tp,
                twin_mrays: m / tt,
                cwbvh_mrays: m / tc,
                wide_mrays: m / tw,
                cwbvh_lost_hits: hs as i64 - hc as i64,
                embree1_mrays: embree.map(|e| m / e.0),
                embree8_mrays: embree.map(|e| m / e.1),
                ratio_vs_embree: embree.map(|e| e.0.min(e.1) / tp),
                embree_extra_hits: embree.map(|e| e.2),
            });
        }
    }
    Ok(rows)
}

/// The 8-wide traversal's work over `rays` (closest hit, or any hit when `any`).
fn count_visits(
    bvh: &crate::geometry::wide::Bvh8,
    rays: &[RayQuery],
    any: bool,
) -> crate::geometry::wide_traverse::Visits {
    use crate::geometry::wide_traverse::{closest_counted, occluded_counted, Visits};
    let mut stack = crate::geometry::traverse::Stack::new();
    let mut v = Visits::default();
    for r in rays {
        if any {
            let _ = occluded_counted::<true, true>(bvh, r, &mut stack, &mut v);
        } else {
            let _ = closest_counted::<true, true>(bvh, r, &mut stack, &mut v);
        }
    }
    v
}

/// Everything `photonwave bench --json` prints.
#[derive(Debug, Serialize)]
pub struct Report {
    /// `-C target-cpu` the crate was compiled for.
    pub target_cpu: String,
    /// The full RUSTFLAGS of the build.
    pub rustflags: String,
    /// SIMD target features enabled at compile time.
    pub features: Vec<&'static str>,
    /// Worker threads every kernel ran on.
    pub threads: usize,
    /// Traversal rows.
    pub traversal: Vec<TraversalRow>,
    /// Density rows.
    pub density: Vec<DensityRow>,
}

impl Report {
    /// An empty report for this build.
    #[must_use]
    pub fn new(threads: usize) -> Self {
        let (target_cpu, rustflags, features) = build_flags();
        Report { target_cpu, rustflags, features, threads, traversal: vec![], density: vec![] }
    }
    /// Adds one scene's rows.
    pub fn add(&mut self, rows: (Vec<TraversalRow>, Vec<DensityRow>)) {
        self.traversal.extend(rows.0);
        self.density.extend(rows.1);
    }
}

/// What `bench` measures and how.
#[derive(Clone, Debug)]
pub struct Options {
    /// Shadow rays go to this point instead of the scene's lights (see [`RaySets::with_light`]).
    pub light: Option<Vec3>,
    /// Worker threads for every kernel.
    pub threads: usize,
    /// Timed repetitions of each kernel.
    pub reps: usize,
    /// Measure traversal.
    pub traversal: bool,
    /// Measure density estimates.
    pub density: bool,
}

/// The measurements `options` asks for on one scene.
///
/// # Errors
/// As [`traversal`].
pub fn run_scene(
    name: &str,
    scene: &Scene,
    cam: &CameraRays,
    options: &Options,
) -> Result<(Vec<TraversalRow>, Vec<DensityRow>), Error> {
    let (threads, reps) = (options.threads, options.reps);
    let sets = RaySets::with_light(scene, cam, options.light);
    let t = if options.traversal { traversal(name, scene, &sets, threads, reps)? } else { vec![] };
    let d = if options.density { density::density(name, scene, &sets, threads, reps) } else { vec![] };
    Ok((t, d))
}

/// The rows as a plain-text table.
#[must_use]
pub fn table(traversal: &[TraversalRow], density: &[DensityRow]) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    for r in traversal {
        let _ = writeln!(
            s,
            "  traversal {:<8} {:<8} {:>8} rays  packet {:>7.2} Mrays/s  wide {:>7.2} ({:.1} nodes, {:.1} tris, {:.2} scalar)  obvhs single {:>7.2} Mrays/s  ×{:.2}  (scalar twin {:.2}, obvhs CWBVH {:.2}, {} hits lost)  embree {}",
            r.rays, r.query, r.count, r.packet_mrays, r.wide_mrays, r.nodes_per_ray, r.triangles_per_ray, r.scalar_per_ray, r.single_mrays, r.ratio, r.twin_mrays, r.cwbvh_mrays, r.cwbvh_lost_hits,
            match (r.embree1_mrays, r.embree8_mrays, r.ratio_vs_embree, r.embree_extra_hits) {
                (Some(e1), Some(e8), Some(x), Some(d)) => format!("1-ray {e1:.2}, 8-ray {e8:.2} Mrays/s, packet ×{x:.2} ({d:+} hits)"),
                _ => "– (build with --features embree)".to_string(),
            }
        );
    }
    for r in density {
        let _ = writeln!(
            s,
            "  density   {:<8} {:>8} queries over {} photons  simd {:>9.0}/s  scalar {:>9.0}/s  ×{:.2}  kiddo {}  ({:.0} photons tested per query for {:.0} summed, {:.2} ns each; {:.1} B per photon)",
            r.lookup,
            r.count,
            r.photons,
            r.simd_per_s,
            r.scalar_per_s,
            r.ratio,
            match (r.kiddo_per_s, r.ratio_vs_kiddo) {
                (Some(k), Some(x)) => format!("{k:>9.0}/s ×{x:.2}"),
                _ => "– (build with --features baselines)".to_string(),
            },
            r.photons_tested_per_query,
            r.photons_summed_per_query,
            r.ns_per_photon_tested,
            r.map_bytes_per_photon
        );
    }
    s
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
