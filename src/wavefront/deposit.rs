//! Deposit: photons that reached a diffuse surface are stored (keyed by path and bounce, so the
//! map comes out in the reference engine's order), each worker into its own range; camera rays that reached an emitter add its
//! radiance. Reads the diffuse lane list and hits; writes deposits, survivors, or the wave's terms.

use super::queues::PathKind;
use super::{add_term, par_columns, slot, CameraWork, PhotonWork, Shared, StageStats, CHUNK};
use crate::photon_map::Photon;
use crate::reference::photons::{deposit_photon, PhotonRay};
use crate::rng::Domain;
use bevy_ecs::prelude::*;
use glam::Vec3;
use std::time::Instant;

/// One worker's deposits: its own range of stored photons and surviving lanes, appended in
/// chunk order (no atomics, no shared writes).
#[derive(Default)]
pub struct DepositPart {
    /// (path, bounce, photon).
    pub deposits: Vec<(u64, u32, Photon)>,
    /// Lanes whose path goes on.
    pub survivors: Vec<u32>,
}

/// Stores photons at diffuse hits; lanes whose path goes on become survivors.
pub fn deposit_photons(shared: Res<Shared>, mut work: ResMut<PhotonWork>, mut stats: ResMut<StageStats>) {
    let t = Instant::now();
    let scene = &*shared.scene;
    let w = &mut *work;
    let domain = w.domain.unwrap_or(Domain::GlobalPhoton);
    let (queue, lanes) = (&w.queue, &w.classified.diffuse);
    let (deposits, survivors) = (&mut w.deposits, &mut w.survivors);
    survivors.clear();
    par_columns(
        lanes.len(),
        CHUNK,
        shared.threads,
        |r, part: &mut DepositPart| {
            let mut out = Vec::new();
            for &lane in &lanes[r] {
                let i = lane as usize;
                let Some(hit) = queue.hits.get(i) else { continue };
                let sp = scene.surface(&hit);
                let photon = PhotonRay {
                    origin: queue.rays.origin(i),
                    dir: queue.rays.direction(i),
                    power: queue.power[i],
                    specular_only: queue.specular_only[i] != 0,
                };
                out.clear();
                if deposit_photon(domain, &sp, &photon, queue.bounce[i], &mut out) {
                    part.survivors.push(lane);
                }
                part.deposits.extend(out.drain(..).map(|p| (queue.path[i], queue.bounce[i], p)));
            }
        },
        |part| {
            deposits.append(&mut part.deposits);
            survivors.append(&mut part.survivors);
        },
    );
    stats.record("deposit_photons", lanes.len(), t);
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
