//! Classify: splits the lanes of the last intersected queue into diffuse (diffuse or glossy),
//! mirror, glass and escaped, by the material hit. Reads hit columns; writes the lane lists.

use super::queues::{Classified, HitColumns};
use super::{CameraWork, PhotonWork, Shared, StageStats};
use crate::material::Bsdf;
use crate::scene::Scene;
use bevy_ecs::prelude::*;
use std::time::Instant;

/// Fills `out` from `hits`, lanes in order.
pub fn classify(scene: &Scene, hits: &HitColumns, out: &mut Classified) {
    out.clear();
    for (i, &tri) in hits.tri.iter().enumerate() {
        let list = if tri == HitColumns::MISS {
            &mut out.escaped
        } else {
            match scene.materials[scene.material[tri as usize] as usize].bsdf {
                Bsdf::Mirror { .. } => &mut out.mirror,
                Bsdf::Glass { .. } => &mut out.glass,
                _ => &mut out.diffuse,
            }
        };
        list.push(i as u32);
    }
}

/// Classifies the photon queue's hits.
pub fn classify_photons(shared: Res<Shared>, mut work: ResMut<PhotonWork>, mut stats: ResMut<StageStats>) {
    let t = Instant::now();
    let w = &mut *work;
    classify(&shared.scene, &w.queue.hits, &mut w.classified);
    if shared.scene.encloses_lights {
        w.numerics.photon_escaped += w.classified.escaped.len() as u64;
    }
    stats.record("classify_photons", w.queue.len(), t);
}

/// Classifies the path queue's hits.
pub fn classify_paths(shared: Res<Shared>, mut work: ResMut<CameraWork>, mut stats: ResMut<StageStats>) {
    let t = Instant::now();
    let w = &mut *work;
    classify(&shared.scene, &w.paths.hits, &mut w.classified);
    stats.record("classify_paths", w.paths.len(), t);
}
