//! The wavefront engine: photons and camera-pass rays live in structure-of-arrays queues and
//! flow through bevy_ecs systems, one stage per file:
//!
//! ```text
//! photon pass (per wave):   emit ─► [ intersect ─► classify ─► deposit ─► shade ]* until no photon is left
//! camera pass (per tile):   emit ─► [ intersect ─► classify ─► deposit ─► gather ─► shade ]* until no ray is left ─► resolve
//! ```
//!
//! The bracketed loop is a sub-schedule run by an exclusive system until its queues are empty,
//! as physics engines run substeps ([`schedule`]). The systems call the transport core
//! ([`crate::transport`]) per lane with the same random streams as the oracle, so for the same
//! seed the two agree per pixel up to the order of floating-point additions. The photon pass's
//! waves are shared by all threads: within a system, lanes are processed in fixed chunks on the
//! persistent worker pool ([`crate::parallel`]) and results are reduced in lane order. The
//! camera pass runs per worker ([`camera_pass`]): each worker takes tiles of samples through the
//! whole camera schedule on its own world. Either way the image is bit-identical at any thread
//! count.
//!
//! Systems are gated on the [`Effects`](crate::effects::Effects) plan with run conditions: a
//! scene without mirrors or glass never runs the caustic systems, one without glass never runs
//! refraction.
//!
//! Files: [`schedule`] (the recipe), [`resources`] (what the systems share), [`queues`] (the SoA
//! queues), [`photon_pass`] (waves of photon paths until the maps are full), [`camera_pass`]
//! (tiles of samples, each through the camera schedule on one worker's own world), and one file
//! per stage.

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
pub use schedule::{schedules, CameraBounce, CameraPass, PhotonBounce, PhotonPass};
use std::sync::Arc;
use std::time::Instant;

/// The stages, in order.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Stage {
    /// New rays and photons.
    Emit,
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

/// Lanes per work chunk for cheap kernels (traversal, scattering).
pub const CHUNK: usize = 1024;
/// Lanes per work chunk for density estimates.
pub const GATHER_CHUNK: usize = 256;

/// Runs `f` over `0..n` in chunks on `threads` threads; each chunk fills its own `T` (a queue
/// or columns) and the chunks are appended in lane order with `append` (column copies, so the
/// sequential part stays small).
pub fn par_columns<T: Send + Default>(
    n: usize,
    chunk: usize,
    threads: usize,
    f: impl Fn(std::ops::Range<usize>, &mut T) + Sync,
    mut append: impl FnMut(&mut T),
) {
    for mut part in map_chunks(
        n,
        chunk,
        threads,
        |r| {
            let mut t = T::default();
            f(r, &mut t);
            t
        },
        |_| {},
    ) {
        append(&mut part);
    }
}

/// Runs `f` over `0..n` in chunks on `threads` threads, chunk `c` with `pieces[c]` (lanes
/// `c·chunk..` of some columns, split as [`queues::HitColumns::pieces`] splits them): each chunk
/// writes its own lanes in place, so nothing is appended or copied afterwards.
///
/// # Panics
/// If there are fewer pieces than chunks.
pub fn par_pieces<P: Send>(
    n: usize,
    chunk: usize,
    threads: usize,
    pieces: Vec<P>,
    f: impl Fn(std::ops::Range<usize>, &mut P) + Sync,
) {
    let chunk = chunk.max(1);
    assert!(pieces.len() >= n.div_ceil(chunk), "a piece for every chunk");
    let slots: Vec<std::sync::Mutex<Option<P>>> = pieces.into_iter().map(|p| std::sync::Mutex::new(Some(p))).collect();
    map_chunks(
        n,
        chunk,
        threads,
        |r| {
            let piece = slots[r.start / chunk].lock().unwrap_or_else(std::sync::PoisonError::into_inner).take();
            f(r, &mut piece.expect("each chunk runs once"));
        },
        |_| {},
    );
}

/// Runs `f` over `0..n` in chunks on `threads` threads; results in lane order, read from each
/// chunk's own vector (collecting them into one new vector cost `gather_global` 7 % of its
/// samples, most of them fresh pages for ~10⁶ lanes every bounce).
pub fn par_lanes<T: Send>(
    n: usize,
    chunk: usize,
    threads: usize,
    f: impl Fn(std::ops::Range<usize>) -> Vec<T> + Sync,
) -> std::iter::Flatten<std::vec::IntoIter<Vec<T>>> {
    map_chunks(n, chunk, threads, f, |_| {}).into_iter().flatten()
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

/// A world holding the shared resources and the schedules of both passes.
fn new_world(scene: &Arc<Scene>, job: &Job) -> World {
    let mut world = World::new();
    world.insert_resource(Shared { scene: scene.clone(), job: job.clone() });
    world.insert_resource(Maps::default());
    world.insert_resource(PhotonWork::default());
    world.insert_resource(StageStats::default());
    for s in schedules() {
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
