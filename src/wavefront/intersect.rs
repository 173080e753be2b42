//! Intersect: closest hits for every lane of the photon or path queue, and any-hit tests for
//! the shadow queue, with the configured kernels (8-wide packets by default; path and photon
//! chunks traced in coherence-key order). Reads rays; writes hit columns (and, for shadow rays, the unblocked
//! contributions into the wave's terms, in lane order).

use super::queues::PathKind;
use super::queues::{HitColumns, RayColumns};
use super::{par_columns, par_lanes, CameraWork, PhotonWork, Shared, StageStats, CHUNK};
use crate::geometry::RayQuery;
use bevy_ecs::prelude::*;
use std::time::Instant;

/// Fills `hits` with the closest hits of `rays`, each chunk into its own columns.
fn closest_hits(shared: &Shared, rays: &RayColumns, hits: &mut HitColumns) {
    let scene = &*shared.scene;
    hits.clear();
    hits.reserve(rays.len());
    par_columns(
        rays.len(),
        CHUNK,
        shared.job.threads,
        |r, part: &mut HitColumns| {
            part.reserve(r.len());
            let queries: Vec<RayQuery> =
                r.map(|i| RayQuery::new(rays.origin(i), rays.direction(i), f32::INFINITY)).collect();
            let hits =
                shared.job.settings.code_path.closest_coherent(scene.bvh(), scene.columns(), &queries, scene.bounds);
            part.extend(hits.into_iter())
        },
        |part| hits.append(part),
    );
}

/// Closest hits of the photon queue.
pub fn intersect_photons(shared: Res<Shared>, mut work: ResMut<PhotonWork>, mut stats: ResMut<StageStats>) {
    let t = Instant::now();
    let q = &mut work.queue;
    closest_hits(&shared, &q.rays, &mut q.hits);
    let n = q.len();
    work.rays += n as u64;
    stats.record("intersect_photons", n, t);
}

/// Closest hits of the path queue.
pub fn intersect_paths(shared: Res<Shared>, mut work: ResMut<CameraWork>, mut stats: ResMut<StageStats>) {
    let t = Instant::now();
    let w = &mut *work;
    closest_hits(&shared, &w.paths.rays, &mut w.paths.hits);
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
        shared.job.settings.code_path.occluded(scene.bvh(), scene.columns(), &queries, &mut blocked);
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
