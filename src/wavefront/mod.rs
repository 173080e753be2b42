//! The wavefront engine: photons and camera-pass rays live in structure-of-arrays queues and
//! flow through bevy_ecs systems, one stage per file:
//!
//! ```text
//! photon pass (per batch):  emit ─► [ intersect ─► classify ─► deposit ─► shade ]* until no photon is left
//! camera pass (per wave):   emit ─► [ intersect ─► classify ─► deposit ─► gather ─► shade ]* until no ray is left ─► resolve
//! ```
//!
//! The bracketed loop is a sub-schedule run by an exclusive system until its queues are empty,
//! as physics engines run substeps. The systems call the same physics as the reference engine
//! (`reference::photons`, `reference::camera`) with the same random streams, so for the same seed
//! the two agree per pixel up to the order of floating-point additions. Within a system, lanes
//! are processed in fixed chunks on `threads` scoped threads and results are reduced in lane
//! order: the image is bit-identical at any thread count.
//!
//! Systems are gated on the [`Effects`] plan with run conditions: a scene without mirrors or
//! glass never runs the caustic systems, one without glass never runs refraction.

pub mod classify;
pub mod deposit;
pub mod emit;
pub mod gather;
pub mod intersect;
pub mod queues;
pub mod shade;

use crate::effects::Effects;
use crate::error::Result;
use crate::film::{Film, Terms};
use crate::photon_map::Photon;
use crate::reference::parallel::map_chunks;
use crate::reference::photons::{normalise_power, BATCH};
use crate::reference::{PhotonMaps, Progress};
use crate::rng::Domain;
use crate::scene::camera::CameraRays;
use crate::scene::Scene;
use crate::settings::Settings;
use crate::stats::{RayCounts, RenderStats};
use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{ExecutorKind, ScheduleLabel};
use queues::{Classified, PathQueue, PhotonQueue, ShadowQueue};
use std::sync::Arc;
use std::time::Instant;

/// The photon pass for one batch: emit, then the bounce loop.
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
pub struct PhotonPass;
/// One photon bounce.
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
pub struct PhotonBounce;
/// The camera pass for one wave of samples: emit, the bounce loop, resolve.
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
pub struct CameraPass;
/// One camera-pass bounce.
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
pub struct CameraBounce;

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

/// At most this many reference batches per photon wave.
pub const MAX_BATCHES_PER_WAVE: usize = 8;
/// Samples per camera wave (bounded memory: ~100 B of queue per lane in flight).
pub const WAVE: usize = 32_768;
/// Lanes per work chunk for cheap kernels (traversal, scattering).
pub const CHUNK: usize = 1024;
/// Lanes per work chunk for density estimates.
pub const GATHER_CHUNK: usize = 256;

/// What every system reads.
#[derive(Resource)]
pub struct Shared {
    /// The scene.
    pub scene: Arc<Scene>,
    /// The settings.
    pub settings: Settings,
    /// The plan.
    pub effects: Effects,
    /// Worker threads.
    pub threads: usize,
}

/// The photon maps (empty until the photon passes are done).
#[derive(Resource, Default)]
pub struct Maps(pub Arc<PhotonMaps>);

/// Photon-pass state.
#[derive(Resource, Default)]
pub struct PhotonWork {
    /// Which map this pass fills.
    pub domain: Option<Domain>,
    /// Path index of the wave's first photon.
    pub first_path: u64,
    /// Reference-engine batches ([`BATCH`] paths each) in this wave.
    pub batches: usize,
    /// Photons to trace this bounce.
    pub queue: PhotonQueue,
    /// Photons for the next bounce.
    pub next: PhotonQueue,
    /// The queue's lanes by outcome.
    pub classified: Classified,
    /// Diffuse lanes whose path goes on after deposit.
    pub survivors: Vec<u32>,
    /// Stored photons keyed by (path, bounce), the reference engine's order.
    pub deposits: Vec<(u64, u32, Photon)>,
    /// Ray segments traced.
    pub rays: u64,
    /// Paths dropped for non-finite power, at emission and at a bounce (the photon fields of
    /// [`Numerics`](crate::stats::Numerics)).
    pub numerics: crate::stats::Numerics,
}

/// Camera-pass state for one wave of samples.
#[derive(Resource)]
pub struct CameraWork {
    /// Primary-ray generator.
    pub camera: CameraRays,
    /// Global index of the wave's first sample.
    pub first_sample: u64,
    /// Samples in the wave.
    pub count: usize,
    /// Segments to trace this bounce.
    pub paths: PathQueue,
    /// Segments for the next bounce.
    pub next: PathQueue,
    /// `paths` lanes by outcome.
    pub classified: Classified,
    /// Shadow rays waiting for the next intersect stage.
    pub shadows: ShadowQueue,
    /// Per-sample terms of the wave.
    pub terms: Vec<Terms>,
    /// The image (per pixel), filled wave by wave.
    pub film: Vec<Terms>,
    /// Rays traced.
    pub rays: RayCounts,
    /// Samples dropped as non-finite, and pixel sums that overflowed.
    pub numerics: crate::stats::Numerics,
}

pub use crate::stats::{StageStat, StageStats};

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

/// Runs `f` over `0..n` in chunks on `threads` threads; results in lane order.
pub fn par_lanes<T: Send>(
    n: usize,
    chunk: usize,
    threads: usize,
    f: impl Fn(std::ops::Range<usize>) -> Vec<T> + Sync,
) -> Vec<T> {
    map_chunks(n, chunk, threads, f, |_| {}).into_iter().flatten().collect()
}

/// Film term indices (see [`crate::film::TERM_NAMES`]).
pub mod slot {
    /// Emission seen directly.
    pub const EMITTED: u8 = 0;
    /// Direct light.
    pub const DIRECT: u8 = 1;
    /// Through mirrors and glass, and glossy reflection.
    pub const SPECULAR: u8 = 2;
    /// Caustic map.
    pub const CAUSTIC: u8 = 3;
    /// Indirect diffuse.
    pub const INDIRECT: u8 = 4;
}

/// Adds `v` to term `slot`.
pub fn add_term(t: &mut Terms, slot: u8, v: glam::Vec3) {
    match slot {
        slot::EMITTED => t.emitted += v,
        slot::DIRECT => t.direct += v,
        slot::SPECULAR => t.specular += v,
        slot::CAUSTIC => t.caustic += v,
        _ => t.indirect += v,
    }
}

// Run conditions from the plan.
fn caustics_on(s: Res<Shared>) -> bool {
    s.effects.caustic_map.on
}
fn global_on(s: Res<Shared>) -> bool {
    s.effects.global_map.on
}
fn final_gather_on(s: Res<Shared>) -> bool {
    s.effects.final_gather.on
}
fn refraction_on(s: Res<Shared>) -> bool {
    s.effects.refraction.on
}
fn shadow_rays_on(s: Res<Shared>) -> bool {
    s.effects.shadow_rays.on
}

/// Runs [`PhotonBounce`] until no photon is in flight.
fn run_photon_bounces(world: &mut World) {
    while !world.resource::<PhotonWork>().queue.is_empty() {
        world.run_schedule(PhotonBounce);
        let mut w = world.resource_mut::<PhotonWork>();
        let w = &mut *w;
        std::mem::swap(&mut w.queue, &mut w.next);
        w.next.clear();
    }
}

/// Runs [`CameraBounce`] until no ray and no shadow ray is in flight.
fn run_camera_bounces(world: &mut World) {
    loop {
        let w = world.resource::<CameraWork>();
        if w.paths.is_empty() && w.shadows.is_empty() {
            break;
        }
        world.run_schedule(CameraBounce);
        let mut w = world.resource_mut::<CameraWork>();
        let w = &mut *w;
        std::mem::swap(&mut w.paths, &mut w.next);
        w.next.clear();
    }
}

/// The recipe: every schedule and the order of its systems, top to bottom.
#[must_use]
pub fn schedules() -> [Schedule; 4] {
    let stages =
        || (Stage::Emit, Stage::Intersect, Stage::Classify, Stage::Deposit, Stage::Gather, Stage::Shade).chain();

    let mut photon_pass = Schedule::new(PhotonPass);
    photon_pass.add_systems((emit::emit_photons, run_photon_bounces).chain());

    let mut photon_bounce = Schedule::new(PhotonBounce);
    photon_bounce.configure_sets(stages());
    photon_bounce.add_systems((
        intersect::intersect_photons.in_set(Stage::Intersect),
        classify::classify_photons.in_set(Stage::Classify),
        deposit::deposit_photons.in_set(Stage::Deposit),
        (shade::scatter_photons, shade::refract_photons.run_if(refraction_on)).chain().in_set(Stage::Shade),
    ));

    let mut camera_pass = Schedule::new(CameraPass);
    camera_pass.add_systems((emit::emit_camera_rays, run_camera_bounces, shade::resolve_wave).chain());

    let mut camera_bounce = Schedule::new(CameraBounce);
    camera_bounce.configure_sets(stages());
    camera_bounce.add_systems((
        (intersect::trace_shadow_rays, intersect::intersect_paths).chain().in_set(Stage::Intersect),
        classify::classify_paths.in_set(Stage::Classify),
        deposit::deposit_emission.in_set(Stage::Deposit),
        (gather::gather_caustics.run_if(caustics_on), gather::gather_global.run_if(global_on))
            .chain()
            .in_set(Stage::Gather),
        (
            shade::shade_direct.run_if(shadow_rays_on),
            shade::spawn_gather_rays.run_if(final_gather_on),
            shade::spawn_glossy_rays,
            shade::reflect_paths,
            shade::refract_paths.run_if(refraction_on),
        )
            .chain()
            .in_set(Stage::Shade),
    ));

    let mut all = [photon_pass, photon_bounce, camera_pass, camera_bounce];
    for s in &mut all {
        // Parallelism is inside the systems (fixed chunks, ordered reduction); the systems
        // themselves run one after another in the recipe's order.
        s.set_executor_kind(ExecutorKind::SingleThreaded);
    }
    all
}

/// A world holding the shared resources and the schedules of both passes.
fn new_world(scene: &Arc<Scene>, settings: &Settings, effects: &Effects, threads: usize) -> World {
    let mut world = World::new();
    world.insert_resource(Shared {
        scene: scene.clone(),
        settings: settings.clone(),
        effects: effects.clone(),
        threads,
    });
    world.insert_resource(Maps::default());
    world.insert_resource(PhotonWork::default());
    world.insert_resource(StageStats::default());
    for s in schedules() {
        world.add_schedule(s);
    }
    world
}

/// The photon pass of both maps the plan wants, run through the photon schedule, and the maps
/// built from it; counts and times go into `stats`.
fn photon_pass(
    world: &mut World,
    scene: &Arc<Scene>,
    settings: &Settings,
    effects: &Effects,
    stats: &mut RenderStats,
    progress: &dyn Progress,
) -> PhotonMaps {
    let threads = settings.thread_count();
    // Photon passes, batch by batch, exactly as many batches as the reference engine emits.
    let mut maps_photons: [Vec<Photon>; 2] = [Vec::new(), Vec::new()];
    for (k, (domain, on, target)) in [
        (Domain::GlobalPhoton, effects.global_map.on, settings.photons),
        (Domain::CausticPhoton, effects.caustic_map.on, settings.caustic_photons),
    ]
    .into_iter()
    .enumerate()
    {
        if !on {
            continue;
        }
        let t = Instant::now();
        let name = if domain == Domain::CausticPhoton { "caustic photons" } else { "global photons" };
        progress.start(name, target as u64);
        let cap = (target as u64 * crate::reference::photons::MAX_PATHS_PER_PHOTON).max(BATCH as u64);
        let mut photons: Vec<Photon> = Vec::new();
        let mut emitted = 0u64;
        let mut reported = 0u64;
        {
            let mut w = world.resource_mut::<PhotonWork>();
            *w = PhotonWork { domain: Some(domain), ..Default::default() };
        }
        // A wave holds several of the reference engine's batches — large queues keep both cores
        // busy in the deep bounces — sized from the photons per batch seen so far. The reference
        // stopping rule is then applied batch by batch, so the photons are the same; paths traced
        // past the stopping batch are discarded.
        let mut per_batch = 0.0f64;
        while (photons.len() as u64) < target as u64 && emitted < cap {
            let left = (cap - emitted).div_ceil(BATCH as u64) as usize;
            let wanted =
                if per_batch > 0.0 { ((target as f64 - photons.len() as f64) / per_batch).ceil() as usize } else { 1 };
            let batches = wanted.clamp(1, MAX_BATCHES_PER_WAVE).min(left);
            {
                let mut w = world.resource_mut::<PhotonWork>();
                w.first_path = emitted;
                w.batches = batches;
            }
            world.run_schedule(PhotonPass);
            let mut w = world.resource_mut::<PhotonWork>();
            let mut deposits = std::mem::take(&mut w.deposits);
            deposits.sort_by_key(|(path, bounce, _)| (*path, *bounce));
            let mut rest = deposits.as_slice();
            for _ in 0..batches {
                if (photons.len() as u64) >= target as u64 || emitted >= cap {
                    break;
                }
                let end = emitted + BATCH as u64;
                let n = rest.partition_point(|(path, _, _)| *path < end);
                let need = target as usize - photons.len();
                if n >= need {
                    // Exactly the photons asked for, up to the path that stores the last one,
                    // as the reference engine cuts (`reference::photons::stop_path`).
                    photons.extend(rest[..need].iter().map(|(_, _, p)| *p));
                    emitted = rest[need - 1].0 + 1;
                    break;
                }
                photons.extend(rest[..n].iter().map(|(_, _, p)| *p));
                rest = &rest[n..];
                emitted = end;
            }
            per_batch = photons.len() as f64 / (emitted / BATCH as u64) as f64;
            let now = (photons.len() as u64).min(target as u64);
            progress.advance(now - reported);
            reported = now;
        }
        progress.finish();
        normalise_power(&mut photons, emitted);
        let w = world.resource::<PhotonWork>();
        stats.rays.photon += w.rays;
        stats.numerics += w.numerics;
        let (map, time) = if k == 0 {
            (&mut stats.global_map, &mut stats.times.global_photons_s)
        } else {
            (&mut stats.caustic_map, &mut stats.times.caustic_photons_s)
        };
        map.emitted = emitted;
        map.stored = photons.len() as u64;
        *time = t.elapsed().as_secs_f64();
        stats.phases.push(format!("{name} (wavefront)"));
        maps_photons[k] = photons;
    }
    stats.global_map.built = effects.global_map.on;
    stats.global_map.reason = effects.global_map.reason.clone();
    stats.caustic_map.built = effects.caustic_map.on;
    stats.caustic_map.reason = effects.caustic_map.reason.clone();

    let t = Instant::now();
    let [global, caustic] = maps_photons;
    let maps = PhotonMaps::build(scene, settings, global, caustic, threads);
    stats.irradiance_points = maps.irradiance.len() as u64;
    stats.times.map_build_s = t.elapsed().as_secs_f64();

    maps
}

/// The wavefront engine's photon maps for `scene` with `settings` (no camera pass): the same
/// photons as [`crate::reference::build_maps`].
pub fn build_maps(scene: Arc<Scene>, settings: &Settings) -> Result<(PhotonMaps, RenderStats)> {
    settings.validate()?;
    let effects = Effects::plan(&scene, settings);
    effects.check(settings)?;
    let threads = settings.thread_count();
    let mut stats = RenderStats::new("wavefront", &scene, settings, threads);
    let mut world = new_world(&scene, settings, &effects, threads);
    let maps = photon_pass(&mut world, &scene, settings, &effects, &mut stats, &crate::reference::NoProgress);
    Ok((maps, stats))
}

/// Renders with the wavefront engine.
pub fn render(
    scene: Arc<Scene>,
    camera: &CameraRays,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<(Film, RenderStats)> {
    settings.validate()?;
    let effects = Effects::plan(&scene, settings);
    effects.check(settings)?;
    let threads = settings.thread_count();
    let start = Instant::now();
    let mut stats =
        RenderStats { effects: Some(effects.clone()), ..RenderStats::new("wavefront", &scene, settings, threads) };
    let mut world = new_world(&scene, settings, &effects, threads);
    let maps = photon_pass(&mut world, &scene, settings, &effects, &mut stats, progress);
    world.insert_resource(Maps(Arc::new(maps)));

    // Camera pass, wave by wave.
    let t = Instant::now();
    let pixels = settings.width as usize * settings.height as usize;
    let total = pixels as u64 * settings.spp as u64;
    world.insert_resource(CameraWork {
        camera: *camera,
        first_sample: 0,
        count: 0,
        paths: PathQueue::default(),
        next: PathQueue::default(),
        classified: Classified::default(),
        shadows: ShadowQueue::default(),
        terms: Vec::new(),
        film: vec![Terms::default(); pixels],
        rays: RayCounts::default(),
        numerics: crate::stats::Numerics::default(),
    });
    progress.start("camera", pixels as u64);
    // Waves hold whole pixels.
    let wave = (WAVE / settings.spp as usize).max(1) as u64 * settings.spp as u64;
    let mut first = 0u64;
    while first < total {
        let count = wave.min(total - first);
        {
            let mut w = world.resource_mut::<CameraWork>();
            w.first_sample = first;
            w.count = count as usize;
        }
        world.run_schedule(CameraPass);
        progress.advance(count / settings.spp as u64);
        first += count;
    }
    progress.finish();
    let mut w = world.resource_mut::<CameraWork>();
    let film = Film { width: settings.width, height: settings.height, pixels: std::mem::take(&mut w.film) };
    stats.rays += w.rays;
    stats.numerics += w.numerics;
    stats.times.camera_s = t.elapsed().as_secs_f64();
    stats.phases.push(if effects.final_gather.on {
        "final gather (wavefront)".into()
    } else {
        "global map read at first hit (wavefront)".into()
    });
    stats.stages = Some(world.resource::<StageStats>().clone());
    stats.times.total_s = start.elapsed().as_secs_f64();
    stats.mean_rgb = film.mean().to_array();
    Ok((film, stats))
}
