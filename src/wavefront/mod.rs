//! The wavefront engine: photons and camera-pass rays live in structure-of-arrays queues and
//! flow through bevy_ecs systems, one stage per file:
//!
//! ```text
//! photon pass (per piece):  emit ─► [ intersect ─► classify ─► deposit ─► shade ]* until no photon is left
//! camera pass (per wave):   emit ─► [ intersect ─► classify ─► deposit ─► gather ─► shade ]* until no ray is left ─► resolve
//! ```
//!
//! The bracketed loop is a sub-schedule run by an exclusive system until its queues are empty,
//! as physics engines run substeps ([`schedule`]). The systems call the transport core
//! ([`crate::transport`]) per lane with the same random streams as the oracle, so for the same
//! seed the two agree per pixel up to the order of floating-point additions.
//!
//! Parallelism is outside the schedules: each worker takes a unit of work — a *piece* of a
//! photon wave ([`photon_pass`](mod@photon_pass): up to 2 048 consecutive paths) or a *tile* of the image
//! ([`camera_pass`](mod@camera_pass): whole pixels, its samples run as one or more *waves* of at most a tile's
//! samples in flight) — through the whole schedule on its own world, and every system is a plain
//! loop over its queue on that worker's thread, pushing into the next queue in lane order. The
//! image is bit-identical at any thread count.
//!
//! Systems are gated on the [`Effects`](crate::effects::Effects) plan with run conditions: a
//! scene without mirrors or glass never runs the caustic systems, one without glass never runs
//! refraction.
//!
//! Files: [`schedule`] (the recipe), [`resources`] (what the systems share), [`queues`] (the SoA
//! queues), [`photon_pass`](mod@photon_pass) (waves of photon paths until the maps are full), [`camera_pass`](mod@camera_pass)
//! (tiles of samples, each through the camera schedule on one worker's own world), and one file
//! per stage.

pub mod absorb;
pub mod camera_pass;
pub mod classify;
pub mod deposit;
pub mod emit;
pub mod gather;
pub mod intersect;
pub mod photon_pass;
pub mod queues;
pub mod resources;
pub mod schedule;
pub mod shade;

use crate::error::Result;
use crate::film::Film;
use crate::job::Job;
use crate::parallel::map_chunks;
use crate::progress::{NoProgress, Progress};
use crate::scene::camera::CameraRays;
use crate::scene::Scene;
use crate::settings::Settings;
use crate::stats::RenderStats;
pub use crate::stats::{StageClock, StageStat, StageStats};
use crate::transport::PhotonMaps;
use bevy_ecs::prelude::*;
use camera_pass::camera_pass;
use photon_pass::photon_pass;
pub use resources::{CameraWork, Maps, PhotonWork, Shared};
pub use schedule::{camera_schedules, photon_schedules, CameraBounce, CameraPass, PhotonBounce, PhotonPass};
use std::sync::Arc;
use std::time::Instant;

/// The stages of a bounce, in order (emit runs before the bounce loop, in the pass's schedule).
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Stage {
    /// Closest hits (and shadow rays' any-hits).
    Intersect,
    /// Split hits into diffuse, mirror, glass, escaped.
    Classify,
    /// Store photons; add emission seen by the camera.
    Deposit,
    /// Photon-map density estimates.
    Gather,
    /// Scatter: next rays, shadow rays, gather and glossy rays.
    Shade,
}

/// Lanes per traversal call: the unit the traversal kernels are timed and chosen on
/// ([`crate::traversal_choice`]) and the packets' sorting unit.
pub const CHUNK: usize = 1024;
/// Fewest lanes in one sorted unit of density estimates ([`gather`]).
pub const GATHER_CHUNK: usize = 256;

/// The ranges of `0..n` in order, each `chunk` long but the last.
pub fn chunks(n: usize, chunk: usize) -> impl Iterator<Item = std::ops::Range<usize>> {
    let chunk = chunk.max(1);
    (0..n).step_by(chunk).map(move |s| s..(s + chunk).min(n))
}

/// The worlds of a pass's workers: a tile or piece takes an idle one (or builds one) and puts it
/// back after, so a worker's queues keep their allocations from one to the next. At most one
/// world per worker is ever built.
#[derive(Default)]
pub struct IdleWorlds(std::sync::Mutex<Vec<World>>);

impl IdleWorlds {
    /// Runs `f` on an idle world, or on a new one from `make`, and keeps the world for the next.
    pub fn with<R>(&self, make: impl FnOnce() -> World, f: impl FnOnce(&mut World) -> R) -> R {
        let lock = || self.0.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let taken = lock().pop();
        let mut world = taken.unwrap_or_else(make);
        let r = f(&mut world);
        lock().push(world);
        r
    }

    /// Runs `unit(k, world)` for every unit of work `k` in `0..units` (a piece or a tile) on
    /// `threads` workers, each on an idle world (or a new one from `make`); the results in unit
    /// order. The one worker loop of both passes.
    pub fn run_units<T: Send>(
        &self,
        units: usize,
        threads: usize,
        make: impl Fn() -> World + Sync,
        unit: impl Fn(usize, &mut World) -> T + Sync,
    ) -> Vec<T> {
        map_chunks(units, 1, threads, |k| self.with(&make, |world| unit(k.start, world)), |_| {})
    }

    /// The worlds, and their stage counts and times summed (sums of counts and times: they do
    /// not depend on which worker took which tile).
    #[must_use]
    pub fn finish(self) -> (Vec<World>, StageStats) {
        let worlds = self.0.into_inner().unwrap_or_else(std::sync::PoisonError::into_inner);
        let mut stages = StageStats::default();
        for w in &worlds {
            stages += w.resource::<StageStats>();
        }
        (worlds, stages)
    }
}

/// A worker's world: the shared resources, empty maps and stage counts, and `schedules` (one
/// pass's).
fn new_world(scene: &Arc<Scene>, job: &Job, schedules: [Schedule; 2]) -> World {
    let mut world = World::new();
    world.insert_resource(Shared { scene: scene.clone(), job: job.clone() });
    world.insert_resource(Maps::default());
    world.insert_resource(StageStats::default());
    for s in schedules {
        world.add_schedule(s);
    }
    world
}

/// The wavefront engine's photon maps for `scene` with `settings` (no camera pass): the same
/// photons as [`crate::reference::build_maps`].
pub fn build_maps(scene: Arc<Scene>, settings: &Settings) -> Result<(PhotonMaps, RenderStats)> {
    let job = Job::photon_mapping(&scene, settings)?;
    let mut stats = RenderStats::new("wavefront", &scene, settings, job.threads);
    let maps = photon_pass(&scene, &job, &mut stats, &mut StageStats::default(), &NoProgress);
    Ok((maps, stats))
}

/// Renders with the wavefront engine, `settings` validated and planned here.
pub fn render(
    scene: Arc<Scene>,
    camera: &CameraRays,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<(Film, RenderStats)> {
    let job = Job::photon_mapping(&scene, settings)?;
    Ok(render_job(scene, camera, &job, progress))
}

/// Renders one pass of `job` with the wavefront engine.
#[must_use]
pub fn render_job(scene: Arc<Scene>, camera: &CameraRays, job: &Job, progress: &dyn Progress) -> (Film, RenderStats) {
    let settings = &job.settings;
    let start = Instant::now();
    let mut stats =
        RenderStats { effects: Some(job.plan.clone()), ..RenderStats::new("wavefront", &scene, settings, job.threads) };
    let mut stages = StageStats::default();
    stats.guide = crate::transport::guide::ensure(&scene, camera, job).map(|g| g.summary.clone());
    let maps = Arc::new(photon_pass(&scene, job, &mut stats, &mut stages, progress));

    // Camera pass, tile by tile on every worker, with the camera rays' kernel chosen first.
    let t = Instant::now();
    intersect::choose_camera_kernel(&scene, camera, job);
    progress.start("camera", u64::from(settings.width) * u64::from(settings.height));
    let samples = settings.width as usize * settings.height as usize * settings.spp as usize;
    let tile = camera_pass::tile_for(samples, job.threads);
    let out = camera_pass(&scene, camera, job, &maps, tile, progress);
    progress.finish();
    let film = Film::new(settings.width, settings.height, out.film);
    stats.rays += out.rays;
    stats.numerics += out.numerics;
    stats.times.camera_s = t.elapsed().as_secs_f64();
    stats.phases.push(if job.plan.final_gather.on {
        "final gather (wavefront)".into()
    } else {
        "global map read at first hit (wavefront)".into()
    });
    stages += &out.stages;
    stats.stages = Some(stages);
    stats.traversal = job.traversal.report();
    stats.times.total_s = start.elapsed().as_secs_f64();
    stats.mean_rgb = film.mean().to_array();
    (film, stats)
}
