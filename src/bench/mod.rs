//! `photonwave bench`: throughput of the SIMD kernels against their baselines, in one process, on
//! identical rays and queries. The kernels compared on one set are timed in turn, round after
//! round (packet, obvhs, 8-wide, …, packet, obvhs, …), and each one's median over the rounds is
//! reported, so machine noise hits every side alike.
//!
//! Ray sets per scene, all from a 512 × 512 camera in 8 × 8 pixel tiles (packets of 8 are rows
//! of a tile):
//! - `camera`: primary rays;
//! - `shadow`: from each camera hit to a uniform point on a light above its surface, or to the
//!   point `--light` gives (t_max just short of the light);
//! - `diffuse`: cosine-distributed bounce rays from each camera hit, sorted by the renderer's
//!   coherence key (direction octant, then origin cell) as the wavefront engine sorts its queues.
//!
//! Each set is traced for the closest hit and for any hit (shadow rays use their t_max, the
//! others t = ∞ — any hit then answers "is anything there").

mod density;
#[cfg(feature = "embree")]
pub mod embree;
mod traversal;

use crate::error::Error;
use crate::geometry::{offset_ray_origin, RayQuery};
use crate::rng::{Domain, Sampler};
use crate::sampling::{cosine_hemisphere, Frame};
use crate::scene::camera::CameraRays;
use crate::scene::{Light, Scene};
pub use density::{DensityRow, BENCH_PHOTONS};
use glam::Vec3;
use serde::Serialize;
use std::time::Instant;
pub use traversal::{thin_sweep, traversal, TraversalRow};

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
        let grid = crate::code_path::MortonGrid::new(scene.bounds, crate::code_path::COHERENCE_CELLS);
        diffuse.sort_by_cached_key(|r| crate::code_path::coherence_key(r.origin, r.direction, &grid));
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
    /// The widest instruction set Embree was allowed (`max_isa=` of its device config: the
    /// widest this build targets); `null` without `--features embree`.
    pub embree_isa: Option<&'static str>,
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
        #[cfg(feature = "embree")]
        let embree_isa = Some(embree::isa());
        #[cfg(not(feature = "embree"))]
        let embree_isa = None;
        Report { target_cpu, rustflags, features, threads, embree_isa, traversal: vec![], density: vec![] }
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
/// As [`traversal`](fn@traversal).
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
            "  traversal {:<8} {:<8} {:>8} rays  packet {:>7.2} Mrays/s  8-wide packets {:>7.2}  wide {:>7.2} ({:.1} nodes, {:.1} tris, {:.2} scalar)  renderer's {} {:.2}  obvhs single {:>7.2} Mrays/s  ×{:.2}  (scalar twin {:.2}, obvhs CWBVH {:.2}, {} hits lost)  embree {}",
            r.rays, r.query, r.count, r.packet_mrays, r.wide_packet_mrays, r.wide_mrays, r.nodes_per_ray, r.triangles_per_ray, r.scalar_per_ray, r.renderer_kernel, r.renderer_mrays, r.single_mrays, r.ratio, r.twin_mrays, r.cwbvh_mrays, r.cwbvh_lost_hits,
            match (
                (r.embree1_mrays, r.embree8_mrays, r.ratio_vs_embree, r.renderer_vs_embree, r.embree_extra_hits),
                (r.embree_robust1_mrays, r.embree_robust8_mrays, r.renderer_vs_embree_robust),
            ) {
                ((Some(e1), Some(e8), Some(x), Some(y), Some(d)), (Some(r1), Some(r8), Some(ry))) => format!(
                    "1-ray {e1:.2}, 8-ray {e8:.2} Mrays/s, packet ×{x:.2}, renderer's {} ×{y:.2} ({d:+} hits{}); robust 1-ray {r1:.2}, 8-ray {r8:.2}, renderer's ×{ry:.2}",
                    r.renderer_kernel,
                    match r.embree_extra_hits_by_call {
                        Some(e) if e.iter().any(|&v| v != d) => format!("; by call {e:?}"),
                        _ => String::new(),
                    }
                ),
                _ => "– (build with --features embree)".to_string(),
            }
        );
    }
    for r in density {
        let _ = writeln!(
            s,
            "  density   {:<8} {:>8} queries over {} photons  simd {:>9.0}/s  scalar {:>9.0}/s  ×{:.2}  packets {}  kiddo {}  ({:.0} photons tested per query for {:.0} summed, {:.2} ns each; {:.1} B per photon)",
            r.lookup,
            r.count,
            r.photons,
            r.simd_per_s,
            r.scalar_per_s,
            r.ratio,
            match (r.packet_per_s, r.packet_ratio) {
                (Some(p), Some(x)) => format!("{p:>9.0}/s ×{x:.2}"),
                _ => "–".to_string(),
            },
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
