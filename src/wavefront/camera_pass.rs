//! The wavefront camera pass, per worker: the image's samples are cut into tiles of whole pixels,
//! and each worker streams the tiles it takes through the whole camera schedule on its own world
//! and SoA queues (emit → [intersect → classify → deposit → gather → shade]* → resolve), one
//! thread per tile. Reads the scene, the maps and the camera; writes the film.
//!
//! Why per worker, not one wave shared by all threads: a shared wave meets the other threads at
//! every stage of every bounce (~12 700 fork-joins per frame at 320², each followed by serial
//! appends in lane order), and a stage too small to split runs on one thread while the others
//! wait. Measured on a 16-core Xeon (issue 46), the shared waves scaled 5.0× where the
//! one-ray-at-a-time oracle scaled 13.5×. Per-worker tiles meet once per tile; the SIMD
//! coherence stays inside a tile's queues. Determinism: a sample's terms are added in the order
//! of its own lanes (queues are concatenations of lane-ordered lists), whatever other samples
//! share its wave, so the image does not depend on the tile size or on which worker took which
//! tile, and tiles write disjoint pixels.

use super::queues::{Classified, PathQueue, ShadowQueue};
use super::resources::{CameraWork, Maps};
use super::schedule::{camera_schedules, CameraPass};
use super::{new_world, IdleWorlds, StageStats};
use crate::film::{PixelMean, Terms};
use crate::job::Job;
use crate::progress::Progress;
use crate::scene::camera::CameraRays;
use crate::scene::Scene;
use crate::stats::{Numerics, RayCounts};
use crate::transport::PhotonMaps;
use bevy_ecs::prelude::*;
use std::sync::Arc;

/// Samples per tile at most (rounded down to whole pixels, at least one pixel): large enough
/// that a stage's queues fill SIMD packets and amortise its fixed cost, small enough that a
/// 320² image at 16 spp makes 400 tiles; a worker's queues then hold ~`TILE` × (1 + gather
/// rays) lanes of ~100 B.
pub const TILE: usize = 4096;
/// Samples per tile at least, where smaller images or many workers cut finer ([`tile_for`]).
pub const MIN_TILE: usize = 512;
/// Samples in flight over all workers at most (down to [`MIN_TILE`] per worker), at any spp (a
/// pixel of more samples than a tile runs as several waves): a worker's queues take ~9 MB per
/// 4 096 samples at 16 gather rays (measured on cornell-spheres), so without this bound 16
/// workers held 3.3× the queues of two.
pub const IN_FLIGHT: usize = 2 * TILE;
/// Tiles per worker wanted, so that the last tiles even out the workers' loads.
const TILES_PER_WORKER: usize = 8;

/// The tile size for `samples` samples on `threads` workers: [`TILE`], or less where the workers
/// would hold more than [`IN_FLIGHT`] samples together, or where it would leave fewer than
/// `TILES_PER_WORKER` tiles per worker (a progressive pass of one sample per pixel at 320²
/// makes 25 tiles of 4 096: on 16 workers the second round would keep 9 busy), but not below
/// [`MIN_TILE`]. Only the speed and the memory depend on it, never the image.
#[must_use]
pub fn tile_for(samples: usize, threads: usize) -> usize {
    let threads = threads.max(1);
    TILE.min(IN_FLIGHT / threads).min(samples.div_ceil(threads * TILES_PER_WORKER)).max(MIN_TILE)
}

/// What the camera pass returns: the film's pixels (row-major) and the workers' counts.
pub struct CameraPassOut {
    /// Resolved pixels.
    pub film: Vec<Terms>,
    /// Rays traced.
    pub rays: RayCounts,
    /// Dropped samples and overflowed sums.
    pub numerics: Numerics,
    /// The stages' runs, lanes and times, summed over the workers.
    pub stages: StageStats,
}

/// A world for one worker: the shared resources, the maps and an empty tile.
fn worker_world(scene: &Arc<Scene>, job: &Job, maps: &Arc<PhotonMaps>, camera: &CameraRays) -> World {
    let mut world = new_world(scene, job, camera_schedules());
    world.insert_resource(Maps(Arc::clone(maps)));
    world.insert_resource(CameraWork {
        camera: *camera,
        first_sample: 0,
        count: 0,
        paths: PathQueue::default(),
        next: PathQueue::default(),
        classified: Classified::default(),
        shadows: ShadowQueue::default(),
        terms: Vec::new(),
        receivers: Vec::new(),
        lobe_receivers: Vec::new(),
        narrow_hits: Vec::new(),
        film: Vec::new(),
        open: PixelMean::default(),
        rays: RayCounts::default(),
        numerics: Numerics::default(),
    });
    world
}

/// Renders every sample of `job`'s image through the camera schedule, in tiles of `tile`
/// samples (whole pixels, at least one; the render uses [`tile_for`]) on `job.threads` workers, each
/// with its own world (built on first use, kept for its next tiles). A tile of one pixel with more
/// samples than `tile` (`--spp` above it) runs as waves of `tile` samples, so a worker's queues
/// never hold more than `tile` samples whatever the spp. The image is the same for any `tile` and
/// thread count.
#[must_use]
pub fn camera_pass(
    scene: &Arc<Scene>,
    camera: &CameraRays,
    job: &Job,
    maps: &Arc<PhotonMaps>,
    tile: usize,
    progress: &dyn Progress,
) -> CameraPassOut {
    let settings = &job.settings;
    let spp = settings.spp as usize;
    let pixels = settings.width as usize * settings.height as usize;
    let tile_pixels = (tile / spp).max(1);
    // Inside a tile everything runs on its worker's thread.
    let worker_job = Job { threads: 1, ..job.clone() };
    let idle = IdleWorlds::default();
    let tiles = idle.run_units(
        pixels.div_ceil(tile_pixels),
        job.threads,
        || worker_world(scene, &worker_job, maps, camera),
        |k, world| {
            let first = k * tile_pixels;
            let count = tile_pixels.min(pixels - first);
            // One wave of the tile's samples, or, for a pixel of more samples than a tile
            // holds, waves of `tile` samples each, the pixel's mean carried from one to the
            // next in sample order (the same sums, so the same image).
            let samples = count * spp;
            world.resource_mut::<CameraWork>().film.clear();
            for start in (0..samples).step_by(tile.max(1)) {
                {
                    let mut w = world.resource_mut::<CameraWork>();
                    w.first_sample = (first * spp + start) as u64;
                    w.count = tile.max(1).min(samples - start);
                }
                world.run_schedule(CameraPass);
            }
            progress.advance(count as u64);
            std::mem::take(&mut world.resource_mut::<CameraWork>().film)
        },
    );
    let (worlds, stages) = idle.finish();
    let mut out = CameraPassOut {
        film: Vec::with_capacity(pixels),
        rays: RayCounts::default(),
        numerics: Numerics::default(),
        stages,
    };
    for mut t in tiles {
        out.film.append(&mut t);
    }
    // Integer counts: the sums do not depend on which worker ran which tile.
    for world in &worlds {
        let w = world.resource::<CameraWork>();
        out.rays += w.rays;
        out.numerics += w.numerics;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{tile_for, IN_FLIGHT, MIN_TILE, TILE, TILES_PER_WORKER};

    #[test]
    fn tiles_are_cut_finer_only_where_workers_would_wait() {
        // 320² at 16 spp on 1 or 2 threads: full tiles (400 of them).
        assert_eq!(tile_for(320 * 320 * 16, 1), TILE);
        assert_eq!(tile_for(320 * 320 * 16, 2), TILE);
        // On 16 threads the workers hold IN_FLIGHT samples together.
        assert_eq!(tile_for(320 * 320 * 16, 16) * 16, IN_FLIGHT);
        // One sample per pixel at 320² on 16 threads: at least 8 tiles per worker.
        let t = tile_for(320 * 320, 16);
        assert!((320 * 320usize).div_ceil(t) >= 16 * TILES_PER_WORKER && t >= MIN_TILE, "{t}");
        // A tiny image is one tile of at least MIN_TILE samples, whatever the thread count.
        for threads in [0, 1, 2, 16, 1000] {
            assert_eq!(tile_for(32, threads), MIN_TILE);
        }
    }
}
