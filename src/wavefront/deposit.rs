//! Deposit: photons that reached a diffuse surface are stored (keyed by path and bounce, so the
//! map comes out in the reference engine's order); camera rays that reached an emitter add its
//! radiance, gather and glossy rays its MIS-weighted share. Reads the diffuse lane list and hits;
//! writes deposits, survivors, or the wave's terms.

use super::queues::PathKind;
use super::{CameraWork, PhotonWork, Shared, StageClock, StageStats};
use crate::film::Term;
use crate::photon_map::Photon;
use crate::rng::Domain;
use crate::transport::lobe::{lobe_emission, lobe_escape};
use crate::transport::mis::emission_found;
use crate::transport::photon::deposit_photon;
use crate::transport::specular::emission_toward;
use crate::transport::Context;
use bevy_ecs::prelude::*;
use glam::Vec3;

/// Stores photons at diffuse hits; lanes whose path goes on become survivors.
pub fn deposit_photons(shared: Res<Shared>, mut work: ResMut<PhotonWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let scene = &*shared.scene;
    let w = &mut *work;
    let domain = w.domain.unwrap_or(Domain::GlobalPhoton);
    let (queue, lanes) = (&w.queue, &w.classified.diffuse);
    let (deposits, survivors) = (&mut w.deposits, &mut w.survivors);
    survivors.clear();
    let mut out: Vec<Photon> = Vec::new();
    for &lane in lanes {
        let i = lane as usize;
        let Some(hit) = queue.hits.get(i) else { continue };
        let sp = scene.surface(&hit);
        let photon = queue.photon(i);
        out.clear();
        if deposit_photon(domain, &sp, &scene.bsdf(&sp), &photon, queue.bounce[i], &mut out) {
            survivors.push(lane);
        }
        deposits.extend(out.drain(..).map(|p| (queue.path[i], queue.bounce[i], p)));
    }
    stats.record("deposit_photons", lanes.len(), t);
}

/// Camera rays add the radiance of emitters whose front face they hit, and of the environment
/// and the sun when they leave the scene; gather and glossy rays add the emission and the
/// environment they find straight away, weighted against light sampling ([`emission_found`],
/// [`lobe_escape`]), to the direct term of the path they left; a narrow lobe's ray adds what it
/// finds to its landing's term (`transport::lobe`).
pub fn deposit_emission(
    shared: Res<Shared>,
    maps: Res<super::Maps>,
    mut work: ResMut<CameraWork>,
    mut stats: ResMut<StageStats>,
) {
    let t = StageClock::start();
    let scene = &*shared.scene;
    let ctx = Context::new(scene, &maps.0, &shared.job);
    let w = &mut *work;
    let mut n = 0;
    for i in 0..w.paths.len() {
        let (kind, sample, depth) = (w.paths.kind[i], w.paths.sample[i] as usize, w.paths.depth[i]);
        let (hit, dir) = (w.paths.hits.get(i), w.paths.rays.direction(i));
        if kind == PathKind::Camera {
            let emission = match hit {
                Some(hit) => emission_toward(scene, &hit, -dir),
                // Leaving the scene: the environment and the sun.
                None if scene.has_background() => scene.background(dir),
                None => continue,
            };
            if emission != Vec3::ZERO {
                n += 1;
                let term = Term::Emitted.seen(w.paths.through_specular[i]);
                w.terms[sample].add(term, w.paths.beta[i] * emission);
            }
            continue;
        }
        // Gather and glossy rays find emitters and the environment straight away, weighed
        // against the light samples of the point they left; rays from a narrow lobe — a
        // landing's lobe ray, a camera hit's glossy ray on one — also what they find through
        // mirrors and glass (`transport::lobe`).
        let density = w.paths.mis[i];
        let narrow = kind == PathKind::Lobe || (kind == PathKind::Glossy && w.narrow_hits[sample]);
        let from = if kind == PathKind::Lobe { &w.lobe_receivers[sample] } else { &w.receivers[sample] };
        let found = match hit {
            Some(hit) if narrow => lobe_emission(&ctx, from, &hit, dir, depth, density),
            Some(hit) if depth == 0 && density > 0.0 => emission_found(&ctx, from, &hit, dir, density),
            None if narrow || depth == 0 => lobe_escape(&ctx, from, dir, depth, density),
            _ => Vec3::ZERO,
        };
        if found != Vec3::ZERO {
            n += 1;
            // Found straight away: the direct term of the path the ray left (a lobe ray's goes
            // where its landing's light went, the term it carries).
            let term = if kind != PathKind::Lobe && depth == 0 {
                Term::Direct.seen(w.paths.through_specular[i])
            } else {
                w.paths.term[i]
            };
            w.terms[sample].add(term, w.paths.beta[i] * found);
        }
    }
    stats.record("deposit_emission", n, t);
}
