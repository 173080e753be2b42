//! Emit: new lanes. Reads the scene and settings; writes the photon queue (a batch of paths
//! starting at lights) or the path queue (a wave of camera rays) and the wave's empty terms.

use super::queues::{PathKind, PhotonLane, Segment};
use super::{CameraWork, PhotonWork, Shared, StageClock, StageStats};
use crate::film::{Term, Terms};
use crate::rng::Domain;
use crate::scene::Receiver;
use crate::transport::camera::camera_ray;
use crate::transport::photon::{start_photon, PathCounts, PathEnd, Start};
use crate::transport::streams;
use bevy_ecs::prelude::*;
use glam::Vec3;

/// Starts the piece's photon paths at its first path index.
pub fn emit_photons(shared: Res<Shared>, mut work: ResMut<PhotonWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let scene = &*shared.scene;
    let domain = work.domain.unwrap_or(Domain::GlobalPhoton);
    let first = work.first_path;
    let n = work.paths;
    let w = &mut *work;
    w.queue.clear();
    w.counts.clear();
    w.counts.resize(n, PathCounts::default());
    w.queue.reserve(n);
    for i in 0..n {
        let path = first + i as u64;
        match start_photon(scene, &shared.job, domain, path) {
            Start::Photon(p) => w.queue.push(PhotonLane {
                origin: p.origin,
                dir: p.dir,
                path,
                bounce: 0,
                power: p.power,
                emitted: p.emitted,
                specular_only: true,
            }),
            Start::Dark => {}
            Start::NonFinite => w.counts[i].end = PathEnd::EmissionNonFinite,
        }
    }
    stats.record("emit_photons", n, t);
}

/// Generates the wave's camera rays: sample `g` is sample `g % spp` of pixel `g / spp`, jittered
/// (stratified when spp is a square) exactly as the reference engine does.
pub fn emit_camera_rays(shared: Res<Shared>, mut work: ResMut<CameraWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let w = &mut *work;
    w.paths.clear();
    w.next.clear();
    w.shadows.clear();
    w.terms.clear();
    w.terms.resize(w.count, Terms::default());
    w.receivers.clear();
    w.receivers.resize(w.count, Receiver::default());
    w.lobe_receivers.clear();
    w.lobe_receivers.resize(w.count, Receiver::default());
    w.narrow_hits.clear();
    w.narrow_hits.resize(w.count, false);
    for lane in 0..w.count {
        let (sampler, origin, dir) = camera_ray(&shared.job, &w.camera, w.first_sample + lane as u64);
        w.paths.push(Segment {
            origin,
            dir,
            sample: lane as u32,
            kind: PathKind::Camera,
            key: sampler.key(),
            base: streams::CAMERA_CHAIN_BOUNCE as u8,
            depth: 0,
            beta: Vec3::ONE,
            term: Term::Emitted,
            through_specular: false,
            mis: 0.0,
        });
    }
    stats.record("emit_camera_rays", w.count, t);
}
