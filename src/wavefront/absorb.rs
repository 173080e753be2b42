//! Absorb: lanes that reached a dielectric's back face crossed its interior, and keep
//! exp(−σ_a·distance) of their throughput or power (Beer–Lambert,
//! [`crate::scene::Scene::interior_transmittance`], as the reference engine takes it at each
//! hit). Runs after classify, before anything reads the throughput, only in scenes with an
//! absorbing interior. Reads hits and ray directions; writes the path throughputs and photon
//! powers.

use super::queues::{HitColumns, RayColumns};
use super::{CameraWork, PhotonWork, Shared, StageClock, StageStats};
use crate::scene::Scene;
use bevy_ecs::prelude::*;
use glam::Vec3;

/// Multiplies each lane's `weight` by what its ray kept on the way to its hit; returns the
/// number of lanes it changed.
fn absorb(scene: &Scene, rays: &RayColumns, hits: &HitColumns, weight: &mut [Vec3]) -> usize {
    let mut n = 0;
    for (i, w) in weight.iter_mut().enumerate() {
        let Some(hit) = hits.get(i) else { continue };
        let kept = scene.interior_transmittance(&hit, rays.direction(i));
        if kept != Vec3::ONE {
            *w *= kept;
            n += 1;
        }
    }
    n
}

/// Camera, gather and glossy lanes that crossed an absorbing interior.
pub fn absorb_paths(shared: Res<Shared>, mut work: ResMut<CameraWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let p = &mut work.paths;
    let n = absorb(&shared.scene, &p.rays, &p.hits, &mut p.beta);
    stats.record("absorb_paths", n, t);
}

/// Photon lanes that crossed an absorbing interior.
pub fn absorb_photons(shared: Res<Shared>, mut work: ResMut<PhotonWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let q = &mut work.queue;
    let n = absorb(&shared.scene, &q.rays, &q.hits, &mut q.power);
    stats.record("absorb_photons", n, t);
}
