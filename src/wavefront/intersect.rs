//! Intersect: closest hits for every lane of the photon or path queue, and any-hit tests for
//! the shadow queue, with the configured kernels: the SIMD set runs BVH2 packets, single rays or
//! 8-wide packets (packets trace closest-hit chunks in coherence-key order), chosen per queue by
//! timing ([`crate::traversal_choice`]). Reads rays; writes hit columns (and, for shadow rays, the
//! unblocked contributions into the wave's terms, in lane order).

use super::queues::PathKind;
use super::queues::{HitColumns, RayColumns};
use super::{chunks, CameraWork, PhotonWork, Shared, StageClock, StageStats, CHUNK};
use crate::geometry::RayQuery;
use crate::job::Job;
use crate::rng::Domain;
use crate::scene::camera::CameraRays;
use crate::scene::Scene;
use crate::transport::camera::camera_ray;
use crate::traversal_choice::{Queue, TRIAL_CHUNKS};
use bevy_ecs::prelude::*;

/// Fills `hits` with the closest hits of `rays` (of `queue`), [`CHUNK`] lanes a traversal call,
/// written in place (the columns keep their allocation from bounce to bounce).
fn closest_hits(shared: &Shared, queue: Queue, rays: &RayColumns, hits: &mut HitColumns) {
    let scene = &*shared.scene;
    let job = &shared.job;
    hits.clear();
    hits.reserve(rays.len());
    let mut queries = Vec::with_capacity(CHUNK);
    for r in chunks(rays.len(), CHUNK) {
        queries.clear();
        queries.extend(r.map(|i| RayQuery::new(rays.origin(i), rays.direction(i), f32::INFINITY)));
        let found =
            job.traversal.closest(queue, job.settings.code_path, scene.bvh(), scene.columns(), &queries, scene.bounds);
        hits.extend(&found);
    }
}

/// Chooses the camera queue's kernel before the first camera pass
/// ([`crate::traversal_choice::TraversalChoice::choose_camera`]): a chunk of the pass's own
/// camera rays (the same samples, jittered as [`super::emit::emit_camera_rays`] jitters them)
/// from the middle of each sixth of the image, so that the whole pass runs the faster packet
/// kernel and the choice does not rest on the image's top rows, often sky. Later passes find the
/// choice made.
pub fn choose_camera_kernel(scene: &Scene, camera: &CameraRays, job: &Job) {
    let settings = &job.settings;
    let total = u64::from(settings.width) * u64::from(settings.height) * u64::from(settings.spp);
    let parts = u64::from(TRIAL_CHUNKS);
    let chunks: Vec<Vec<RayQuery>> = (0..parts)
        .map(|b| {
            let first = ((2 * b + 1) * total / (2 * parts)).saturating_sub(CHUNK as u64 / 2);
            let first = first.min(total.saturating_sub(CHUNK as u64));
            (first..(first + CHUNK as u64).min(total))
                .map(|g| {
                    let (_, o, d) = camera_ray(job, camera, g);
                    RayQuery::new(o, d, f32::INFINITY)
                })
                .collect()
        })
        .collect();
    job.traversal.choose_camera(settings.code_path, scene.bvh(), scene.columns(), &chunks, scene.bounds);
}

/// Closest hits of the photon queue.
pub fn intersect_photons(shared: Res<Shared>, mut work: ResMut<PhotonWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let domain = work.domain;
    let q = &mut work.queue;
    // A bounce's queue holds photons of one map and one bounce count.
    let emitted = q.bounce.first() == Some(&0);
    let queue = match (domain, emitted) {
        (Some(Domain::CausticPhoton), true) => Queue::CausticEmitted,
        (Some(Domain::CausticPhoton), false) => Queue::CausticPhotons,
        (_, true) => Queue::Emitted,
        (_, false) => Queue::Photons,
    };
    closest_hits(&shared, queue, &q.rays, &mut q.hits);
    let n = q.len();
    let w = &mut *work;
    for &path in &w.queue.path {
        w.counts[(path - w.first_path) as usize].ray();
    }
    stats.record("intersect_photons", n, t);
}

/// Closest hits of the path queue.
pub fn intersect_paths(shared: Res<Shared>, mut work: ResMut<CameraWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let w = &mut *work;
    // The first bounce's queue holds the primary rays, and later ones none.
    let primary = w.paths.kind.first() == Some(&PathKind::Camera) && w.paths.depth.first() == Some(&0);
    let queue = if primary { Queue::Camera } else { Queue::Secondary };
    closest_hits(&shared, queue, &w.paths.rays, &mut w.paths.hits);
    for k in &w.paths.kind {
        match k {
            PathKind::Camera => w.rays.camera += 1,
            _ => w.rays.gather += 1,
        }
    }
    stats.record("intersect_paths", w.paths.len(), t);
}

/// Any-hit tests of the shadow queue; unblocked rays add their contribution.
pub fn trace_shadow_rays(shared: Res<Shared>, mut work: ResMut<CameraWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let scene = &*shared.scene;
    let w = &mut *work;
    let q = &w.shadows;
    let n = q.len();
    let job = &shared.job;
    let (mut queries, mut blocked) = (Vec::with_capacity(CHUNK), Vec::with_capacity(CHUNK));
    for r in chunks(n, CHUNK) {
        queries.clear();
        queries.extend(r.clone().map(|i| RayQuery::new(q.rays.origin(i), q.rays.direction(i), q.t_max[i])));
        // Shadow rays are queued in camera-lane order, from neighbouring hits toward the same
        // lights: already coherent, and sorting them cost more than it saved (BENCHMARKS.md).
        blocked.clear();
        blocked.resize(queries.len(), false);
        let code_path = job.settings.code_path;
        job.traversal.occluded(Queue::Shadows, code_path, scene.bvh(), scene.columns(), &queries, &mut blocked);
        for (i, &b) in r.zip(&blocked) {
            if !b {
                w.terms[q.sample[i] as usize].add(q.term[i], q.contribution[i]);
            }
        }
    }
    w.rays.shadow += n as u64;
    w.shadows.clear();
    stats.record("trace_shadow_rays", n, t);
}
