//! The scalar reference renderer (Jensen 1996), one ray at a time, no ECS, no SIMD: the oracle
//! every faster engine is compared against. Written for obviousness.
//!
//! A render is: plan which maps the scene needs → photon passes (global, caustic) → kd-trees →
//! camera pass (direct + specular + caustic + indirect per pixel sample).

pub mod camera;
pub mod parallel;
pub mod path;
pub mod photons;

use crate::effects::Effects;
use crate::error::Result;
use crate::film::Film;
use crate::photon_map::{Filter, Lookup, Photon, PhotonMap, Reflectance};
use crate::rng::Domain;
use crate::scene::camera::CameraRays;
use crate::scene::Scene;
use crate::settings::Settings;
use crate::stats::{MapStats, RenderStats};
use glam::Vec3;
use std::time::Instant;

/// Both photon maps (empty where the plan skipped one), and the irradiance precomputed at
/// global photons for final gathering.
#[derive(Default)]
pub struct PhotonMaps {
    /// Global map (all non-specular hits).
    pub global: PhotonMap,
    /// Caustic map (`LS+D` paths).
    pub caustic: PhotonMap,
    /// Irradiance at every [`IRRADIANCE_STRIDE`]-th global photon (`power` holds E); empty unless
    /// `precompute_irradiance` is on.
    pub irradiance: PhotonMap,
}

/// Irradiance is precomputed at every this-many-th global photon (Christensen 1999 used 4).
pub const IRRADIANCE_STRIDE: usize = 4;

impl PhotonMaps {
    /// Builds the kd-trees and, if the settings ask for final gathering with precomputed
    /// irradiance, the irradiance map.
    #[must_use]
    pub fn build(
        scene: &Scene,
        settings: &Settings,
        global: Vec<Photon>,
        caustic: Vec<Photon>,
        threads: usize,
    ) -> Self {
        // The two trees are independent: built side by side when there is a second thread.
        let (global, caustic) = if threads > 1 {
            std::thread::scope(|s| {
                let c = s.spawn(|| PhotonMap::build(caustic));
                let g = PhotonMap::build(global);
                (g, c.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            })
        } else {
            (PhotonMap::build(global), PhotonMap::build(caustic))
        };
        let mut maps = PhotonMaps { global, caustic, irradiance: PhotonMap::default() };
        // Not under a progressive pass's fixed radii: reading the nearest precomputed point is
        // biased low there (see `precompute_irradiance`).
        if Effects::plan(scene, settings).final_gather.on
            && settings.precompute_irradiance
            && settings.fixed_radii.is_none()
            && !maps.global.is_empty()
        {
            maps.irradiance = precompute_irradiance(&maps.global, scene, settings, threads);
        }
        maps
    }
}

/// Christensen's precomputation: the global-map irradiance estimate E at every
/// [`IRRADIANCE_STRIDE`]-th photon, stored as a photon whose `power` is E. A final-gather ray that
/// ends on a Lambertian surface then reads kd/π·E of the nearest such point (one nearest-neighbour
/// search instead of a k-nearest density estimate).
///
/// Only with k-nearest-neighbour estimates. Under a progressive pass's small fixed radii it is
/// biased: a point's estimate and how often gather rays read it (its nearest-neighbour cell among
/// the other points) both follow the same local clustering of photons — a point in a chance
/// cluster reads high but has a small cell — so the rays read low values more often. Measured on
/// the glass-sphere box against the path tracer: caustic + indirect 3.6 % low after 64 passes,
/// 5.2 % after 512, growing as the radius shrinks; the estimate at each point itself was
/// unbiased (leaving the point's own photon out, it matched an independent map within 0.4 %).
/// Full fixed-radius estimates at the gather hits are unbiased (0.04 % off) and cost ~18 % more
/// per pass, so progressive passes use those.
fn precompute_irradiance(global: &PhotonMap, scene: &Scene, settings: &Settings, threads: usize) -> PhotonMap {
    let radius = settings.global_radius * scene.diagonal();
    let picks: Vec<usize> = (0..global.len()).step_by(IRRADIANCE_STRIDE).collect();
    let chunks = parallel::map_chunks(
        picks.len(),
        4096,
        threads,
        |range| {
            let mut scratch = Vec::new();
            range
                .map(|j| {
                    let src = global.photon(picks[j]);
                    let lookup = Lookup {
                        p: src.position,
                        k: settings.k as usize,
                        r_max: radius,
                        kernel: settings.kernel,
                        filter: Filter { n: src.normal, flags_mask: 0 },
                    };
                    let f = Reflectance::Constant(Vec3::ONE);
                    let e = if settings.visibility {
                        let visible = camera::photon_visibility(scene, src.position, src.normal, radius);
                        global.estimate_visible(settings.kernels, &lookup, f, &mut scratch, &visible)
                    } else {
                        global.estimate(settings.kernels, &lookup, f, &mut scratch)
                    };
                    Photon { position: src.position, power: e.radiance, wi: src.normal, normal: src.normal, flags: 0 }
                })
                .collect::<Vec<_>>()
        },
        |_| {},
    );
    PhotonMap::build(chunks.into_iter().flatten().collect())
}

/// Progress reporting hooks (the CLI wires these to progress bars; tests pass [`NoProgress`]).
pub trait Progress: Sync {
    /// A phase starts with `total` units of work.
    fn start(&self, phase: &str, total: u64);
    /// `n` more units are done.
    fn advance(&self, n: u64);
    /// A status line beside the bar (passes, time left).
    fn message(&self, _text: &str) {}
    /// The phase is over.
    fn finish(&self);
}

/// Reports nothing.
pub struct NoProgress;
impl Progress for NoProgress {
    fn start(&self, _: &str, _: u64) {}
    fn advance(&self, _: u64) {}
    fn finish(&self) {}
}

/// Renders `scene` as seen by `camera` with `settings`.
pub fn render(
    scene: &Scene,
    camera: &CameraRays,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<(Film, RenderStats)> {
    settings.validate()?;
    let plan = Effects::plan(scene, settings);
    plan.check(settings)?;
    let threads = settings.thread_count();
    let start = Instant::now();
    let mut stats = RenderStats::new("reference", scene, settings, threads);

    let maps = photon_passes(scene, settings, &plan, threads, progress, &mut stats);
    stats.effects = Some(plan.clone());

    let t = Instant::now();
    let (film, rays, numerics) = camera::render_image(scene, &maps, camera, settings, threads, progress);
    stats.times.camera_s = t.elapsed().as_secs_f64();
    stats.rays += rays;
    stats.numerics += numerics;
    stats.phases.push(if plan.final_gather.on { "final gather".into() } else { "global map read at first hit".into() });
    stats.times.total_s = start.elapsed().as_secs_f64();
    stats.mean_rgb = film.mean().to_array();
    Ok((film, stats))
}

/// Runs the photon passes the plan calls for and builds the maps, recording counts and times
/// in `stats`.
pub fn photon_passes(
    scene: &Scene,
    settings: &Settings,
    plan: &Effects,
    threads: usize,
    progress: &dyn Progress,
    stats: &mut RenderStats,
) -> PhotonMaps {
    let mut pass = |build: bool, domain: Domain, target: u32, name: &str, time: &mut f64| -> Vec<Photon> {
        if !build {
            return Vec::new();
        }
        let t = Instant::now();
        let p = photons::trace_photons(scene, settings, domain, target, threads, progress);
        *time = t.elapsed().as_secs_f64();
        stats.rays.photon += p.rays;
        stats.numerics += p.numerics;
        stats.phases.push(name.to_string());
        let map = if domain == Domain::CausticPhoton { &mut stats.caustic_map } else { &mut stats.global_map };
        map.emitted = p.emitted;
        map.stored = p.photons.len() as u64;
        p.photons
    };
    let mut times = (0.0, 0.0);
    let global = pass(plan.global_map.on, Domain::GlobalPhoton, settings.photons, "global photon pass", &mut times.0);
    let caustic =
        pass(plan.caustic_map.on, Domain::CausticPhoton, settings.caustic_photons, "caustic photon pass", &mut times.1);
    (stats.times.global_photons_s, stats.times.caustic_photons_s) = times;
    stats.global_map.built = plan.global_map.on;
    stats.global_map.reason = plan.global_map.reason.clone();
    stats.caustic_map.built = plan.caustic_map.on;
    stats.caustic_map.reason = plan.caustic_map.reason.clone();
    let t = Instant::now();
    let maps = PhotonMaps::build(scene, settings, global, caustic, threads);
    stats.irradiance_points = maps.irradiance.len() as u64;
    stats.times.map_build_s = t.elapsed().as_secs_f64();
    maps
}

/// Builds just the photon maps (for tests and tools), with the plan's decisions.
#[must_use]
pub fn build_maps(scene: &Scene, settings: &Settings) -> (PhotonMaps, MapStats, MapStats) {
    let mut stats = RenderStats::default();
    let maps = photon_passes(
        scene,
        settings,
        &Effects::plan(scene, settings),
        settings.thread_count(),
        &NoProgress,
        &mut stats,
    );
    (maps, stats.global_map, stats.caustic_map)
}
