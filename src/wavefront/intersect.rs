//! Intersect: closest hits for every lane of the photon or path queue, and any-hit tests for
//! the shadow queue, with the configured kernels: the SIMD set runs packets (chunks traced in
//! coherence-key order) or single rays, chosen per queue by timing
//! ([`crate::traversal_choice`]). Reads rays; writes hit columns (and, for shadow rays, the
//! unblocked contributions into the wave's terms, in lane order).

use super::queues::PathKind;
use super::queues::{HitColumns, RayColumns};
use super::{par_lanes, par_pieces, CameraWork, PhotonWork, Shared, StageStats, CHUNK};
use crate::geometry::RayQuery;
use crate::rng::Domain;
use crate::traversal_choice::Queue;
use bevy_ecs::prelude::*;
use std::time::Instant;

/// Fills `hits` with the closest hits of `rays` (of `queue`), each chunk writing its own lanes
/// in place (per-chunk columns appended afterwards cost `intersect_paths` ~6 % of its samples:
/// the copy and fresh pages for every bounce). `span` places the queue in its pass, for the
/// kernel trial ([`crate::traversal_choice`]): its first lane's index and the pass's lane count
/// (the camera queue: the wave's first sample and the image's samples).
fn closest_hits(shared: &Shared, queue: Queue, span: (u64, u64), rays: &RayColumns, hits: &mut HitColumns) {
    let scene = &*shared.scene;
    let n = rays.len();
    par_pieces(n, CHUNK, shared.job.threads, hits.pieces(n, CHUNK), |r, piece| {
        let at = (span.0 + r.start as u64) as f32 / span.1.max(1) as f32;
        let queries: Vec<RayQuery> =
            r.map(|i| RayQuery::new(rays.origin(i), rays.direction(i), f32::INFINITY)).collect();
        let job = &shared.job;
        let found = job.traversal.closest(
            queue,
            at,
            job.settings.code_path,
            scene.bvh(),
            scene.columns(),
            &queries,
            scene.bounds,
        );
        piece.write(&found);
    });
}

/// Closest hits of the photon queue.
pub fn intersect_photons(shared: Res<Shared>, mut work: ResMut<PhotonWork>, mut stats: ResMut<StageStats>) {
    let t = Instant::now();
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
    // Photon queues choose on their first chunks, wherever they lie.
    closest_hits(&shared, queue, (0, 1), &q.rays, &mut q.hits);
    let n = q.len();
    work.rays += n as u64;
    stats.record("intersect_photons", n, t);
}

/// Closest hits of the path queue.
pub fn intersect_paths(shared: Res<Shared>, mut work: ResMut<CameraWork>, mut stats: ResMut<StageStats>) {
    let t = Instant::now();
    let w = &mut *work;
    // The first bounce's queue holds the primary rays, and later ones none.
    let primary = w.paths.kind.first() == Some(&PathKind::Camera) && w.paths.depth.first() == Some(&0);
    let queue = if primary { Queue::Camera } else { Queue::Secondary };
    // A primary queue holds the wave's samples in order: the camera trial spreads over the image.
    let samples = u64::from(shared.job.settings.width)
        * u64::from(shared.job.settings.height)
        * u64::from(shared.job.settings.spp);
    closest_hits(&shared, queue, (w.first_sample, samples), &w.paths.rays, &mut w.paths.hits);
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
    let t = Instant::now();
    let scene = &*shared.scene;
    let w = &mut *work;
    let q = &w.shadows;
    let n = q.len();
    let blocked = par_lanes(n, CHUNK, shared.job.threads, |r| {
        let queries: Vec<RayQuery> =
            r.map(|i| RayQuery::new(q.rays.origin(i), q.rays.direction(i), q.t_max[i])).collect();
        // Shadow rays are queued in camera-lane order, from neighbouring hits toward the same
        // lights: already coherent, and sorting them cost more than it saved (BENCHMARKS.md).
        let mut blocked = vec![false; queries.len()];
        let job = &shared.job;
        job.traversal.occluded(
            Queue::Shadows,
            job.settings.code_path,
            scene.bvh(),
            scene.columns(),
            &queries,
            &mut blocked,
        );
        blocked
    });
    for (i, b) in blocked.into_iter().enumerate() {
        if !b {
            w.terms[q.sample[i] as usize].add(q.term[i], q.contribution[i]);
        }
    }
    w.rays.shadow += n as u64;
    w.shadows.clear();
    stats.record("trace_shadow_rays", n, t);
}
