//! The scalar reference renderer (Jensen 1996), one ray at a time, no ECS, no SIMD: the oracle
//! every faster engine is compared against. Written for obviousness: its loops are here, every
//! vertex of physics is the shared transport core's ([`crate::transport`]).
//!
//! A render is: photon passes (global, caustic, as the plan asks) → photon trees → camera pass
//! (direct + specular + caustic + indirect per pixel sample).

pub mod camera;
pub mod photons;

use crate::error::Result;
use crate::film::Film;
use crate::job::Job;
use crate::photon_map::Photon;
use crate::progress::{NoProgress, Progress};
use crate::rng::Domain;
use crate::scene::camera::CameraRays;
use crate::scene::Scene;
use crate::settings::Settings;
use crate::stats::{MapStats, RenderStats};
use crate::transport::photon::power_max_over_median;
use crate::transport::PhotonMaps;
use std::time::Instant;

/// Renders `scene` as seen by `camera` with `settings` (validated and planned here).
pub fn render(
    scene: &Scene,
    camera: &CameraRays,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<(Film, RenderStats)> {
    Ok(render_job(scene, camera, &Job::photon_mapping(scene, settings)?, progress))
}

/// Renders one pass of `job`.
#[must_use]
pub fn render_job(scene: &Scene, camera: &CameraRays, job: &Job, progress: &dyn Progress) -> (Film, RenderStats) {
    let start = Instant::now();
    let mut stats = RenderStats::new("reference", scene, &job.settings, job.threads);
    stats.guide = crate::transport::guide::ensure(scene, camera, job).map(|g| g.summary.clone());
    let maps = photon_passes(scene, job, progress, &mut stats);
    stats.effects = Some(job.plan.clone());

    let t = Instant::now();
    let (film, rays, numerics) = camera::render_image(scene, &maps, camera, job, progress);
    stats.times.camera_s = t.elapsed().as_secs_f64();
    stats.rays += rays;
    stats.numerics += numerics;
    stats.phases.push(if job.plan.final_gather.on {
        "final gather".into()
    } else {
        "global map read at first hit".into()
    });
    stats.times.total_s = start.elapsed().as_secs_f64();
    stats.mean_rgb = film.mean().to_array();
    (film, stats)
}

/// Runs the photon passes the plan calls for and builds the maps, recording counts and times
/// in `stats`.
pub fn photon_passes(scene: &Scene, job: &Job, progress: &dyn Progress, stats: &mut RenderStats) -> PhotonMaps {
    let plan = &job.plan;
    let mut pass = |build: bool, domain: Domain, target: u32, name: &str, time: &mut f64| -> Vec<Photon> {
        if !build {
            return Vec::new();
        }
        let t = Instant::now();
        let p = photons::trace_photons(scene, job, domain, target, progress);
        *time = t.elapsed().as_secs_f64();
        stats.rays.photon += p.rays;
        stats.numerics += p.numerics;
        stats.phases.push(name.to_string());
        let map = if domain == Domain::CausticPhoton { &mut stats.caustic_map } else { &mut stats.global_map };
        map.emitted = p.emitted;
        map.stored = p.photons.len() as u64;
        map.volume = p.photons.iter().filter(|ph| ph.flags & crate::photon_map::flags::VOLUME != 0).count() as u64;
        map.read = p.read;
        map.steered = crate::transport::guide::steers(job, domain);
        map.power_max_over_median = power_max_over_median(&p.photons);
        p.photons
    };
    let mut times = (0.0, 0.0);
    let global =
        pass(plan.global_map.on, Domain::GlobalPhoton, job.settings.photons, "global photon pass", &mut times.0);
    let caustic = pass(
        plan.caustic_map.on,
        Domain::CausticPhoton,
        job.settings.caustic_photons,
        "caustic photon pass",
        &mut times.1,
    );
    (stats.times.global_photons_s, stats.times.caustic_photons_s) = times;
    stats.record_plan(plan);
    let t = Instant::now();
    let maps = PhotonMaps::build(scene, job, global, caustic);
    stats.irradiance_points = maps.irradiance.len() as u64;
    stats.times.map_build_s = t.elapsed().as_secs_f64();
    maps
}

/// Builds just the photon maps of `job` (for tests and tools), with the plan's decisions.
#[must_use]
pub fn build_job_maps(scene: &Scene, job: &Job) -> (PhotonMaps, MapStats, MapStats) {
    let mut stats = RenderStats::default();
    let maps = photon_passes(scene, job, &NoProgress, &mut stats);
    (maps, stats.global_map, stats.caustic_map)
}

/// Builds just the photon maps for `settings` (validated and planned here).
pub fn build_maps(scene: &Scene, settings: &Settings) -> Result<(PhotonMaps, MapStats, MapStats)> {
    Ok(build_job_maps(scene, &Job::photon_mapping(scene, settings)?))
}
