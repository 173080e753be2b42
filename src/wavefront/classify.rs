//! Classify: splits the lanes of the last intersected queue into diffuse (diffuse or glossy),
//! mirror, glass and escaped, by the material hit; then marks the gather lanes that landed near
//! their origin for the secondary gather. Reads hit columns; writes the lane lists and kinds.

use super::queues::{Classified, HitColumns, PathKind};
use super::{CameraWork, PhotonWork, Shared, StageClock, StageStats};
use crate::material::Bsdf;
use crate::scene::Scene;
use crate::transport::gather::{lands_near, secondary_gather_distance};
use crate::transport::photon::PathEnd;
use bevy_ecs::prelude::*;

/// Fills `out` from `hits`, lanes in order. With `paths` (the camera pass), lanes at surfaces
/// that photons pass on as specular (frosted glass, smooth rough metal) join the mirror lanes
/// and continue, as the reference's camera and gather paths do, and escaped lanes are not
/// listed (the camera pass reads the hits for what escaped); photons at them deposit nothing
/// and scatter (`deposit_photon`), and escaped photons are listed for the leak count.
pub fn classify(scene: &Scene, hits: &HitColumns, paths: bool, out: &mut Classified) {
    out.clear();
    for (i, &tri) in hits.tri.iter().enumerate() {
        let list = if tri == HitColumns::MISS {
            if paths {
                continue;
            }
            &mut out.escaped
        } else {
            let bsdf = &scene.materials[scene.material[tri as usize] as usize].bsdf;
            match bsdf {
                Bsdf::Mirror { .. } => &mut out.mirror,
                Bsdf::Glass { .. } | Bsdf::ThinGlass { .. } => &mut out.glass,
                b if paths && b.photon_specular() => &mut out.mirror,
                _ => &mut out.diffuse,
            }
        };
        list.push(i as u32);
    }
}

/// Classifies the photon queue's hits.
pub fn classify_photons(shared: Res<Shared>, mut work: ResMut<PhotonWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let w = &mut *work;
    classify(&shared.scene, &w.queue.hits, false, &mut w.classified);
    if shared.scene.encloses_lights {
        for &l in &w.classified.escaped {
            let path = w.queue.path[l as usize];
            w.counts[(path - w.first_path) as usize].end = PathEnd::Escaped;
        }
    }
    stats.record("classify_photons", w.queue.len(), t);
}

/// Classifies the path queue's hits.
pub fn classify_paths(shared: Res<Shared>, mut work: ResMut<CameraWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let w = &mut *work;
    classify(&shared.scene, &w.paths.hits, true, &mut w.classified);
    stats.record("classify_paths", w.paths.len(), t);
}

/// Gather lanes at diffuse hits that landed near their origin become
/// [`PathKind::NearGather`] (`transport::gather`'s secondary gather).
pub fn mark_near_gathers(shared: Res<Shared>, mut work: ResMut<CameraWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let distance = secondary_gather_distance(&shared.scene, &shared.job);
    if distance <= 0.0 {
        return;
    }
    let scene = &*shared.scene;
    let w = &mut *work;
    let mut n = 0;
    for &l in &w.classified.diffuse {
        let i = l as usize;
        if w.paths.kind[i] != PathKind::Gather {
            continue;
        }
        let tri = w.paths.hits.tri[i] as usize;
        let bsdf = &scene.materials[scene.material[tri] as usize].bsdf;
        if lands_near(w.paths.hits.t[i], w.paths.depth[i], bsdf, distance) {
            w.paths.kind[i] = PathKind::NearGather;
            n += 1;
        }
    }
    stats.record("mark_near_gathers", n, t);
}
