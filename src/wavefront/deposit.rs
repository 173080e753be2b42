//! Deposit: photons that reached a diffuse surface are stored (keyed by path and bounce, so the
//! map comes out in the reference engine's order); camera rays that reached an emitter add its
//! radiance. Reads the diffuse lane list and hits; writes deposits, survivors, or the wave's terms.

use super::queues::PathKind;
use super::{add_term, slot, CameraWork, PhotonWork, Shared, StageStats};
use crate::reference::photons::{deposit_photon, PhotonRay};
use crate::rng::Domain;
use bevy_ecs::prelude::*;
use glam::Vec3;
use std::time::Instant;

/// Stores photons at diffuse hits; lanes whose path goes on become survivors.
pub fn deposit_photons(shared: Res<Shared>, mut work: ResMut<PhotonWork>, mut stats: ResMut<StageStats>) {
    let t = Instant::now();
    let scene = &*shared.scene;
    let w = &mut *work;
    let domain = w.domain.unwrap_or(Domain::GlobalPhoton);
    w.survivors.clear();
    let mut out = Vec::new();
    for &lane in &w.classified.diffuse {
        let i = lane as usize;
        let Some(hit) = w.queue.hits.get(i) else { continue };
        let sp = scene.surface(&hit);
        let photon = PhotonRay {
            origin: w.queue.rays.origin(i),
            dir: w.queue.rays.direction(i),
            power: w.queue.power[i],
            specular_only: w.queue.specular_only[i] != 0,
        };
        out.clear();
        let goes_on = deposit_photon(domain, &sp, &photon, w.queue.bounce[i], &mut out);
        for p in out.drain(..) {
            w.deposits.push((w.queue.path[i], w.queue.bounce[i], p));
        }
        if goes_on {
            w.survivors.push(lane);
        }
    }
    stats.record("deposit_photons", w.classified.diffuse.len(), t);
}

/// Camera rays (not gather or glossy rays, whose emission is the direct term's) add the
/// radiance of emitters whose front face they hit.
pub fn deposit_emission(shared: Res<Shared>, mut work: ResMut<CameraWork>, mut stats: ResMut<StageStats>) {
    let t = Instant::now();
    let scene = &*shared.scene;
    let w = &mut *work;
    let mut n = 0;
    for i in 0..w.paths.len() {
        if w.paths.kind[i] != PathKind::Camera {
            continue;
        }
        let Some(hit) = w.paths.hits.get(i) else { continue };
        let emission = scene.materials[scene.material[hit.tri as usize] as usize].emission;
        if emission == Vec3::ZERO || w.paths.rays.direction(i).dot(scene.ng[hit.tri as usize]) >= 0.0 {
            continue;
        }
        n += 1;
        let s = if w.paths.through_specular[i] != 0 { slot::SPECULAR } else { slot::EMITTED };
        add_term(&mut w.terms[w.paths.sample[i] as usize], s, w.paths.beta[i] * emission);
    }
    stats.record("deposit_emission", n, t);
}
