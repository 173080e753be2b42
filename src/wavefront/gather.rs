//! Gather: photon-map density estimates where lanes reached a diffuse surface — the caustic map
//! for camera and glossy rays, the global map for gather rays (precomputed irradiance where it
//! applies), and the global map without direct and caustic photons for glossy rays and for camera
//! rays when final gathering is off. Reads the diffuse lane list, hits and maps; writes the wave's
//! terms in lane order.

use super::queues::PathKind;
use super::{add_term, par_lanes, slot, CameraWork, Maps, Shared, StageStats, GATHER_CHUNK};
use crate::photon_map::flags;
use crate::reference::camera::{caustic_estimate, global_estimate, map_radiance, Context};
use bevy_ecs::prelude::*;
use glam::Vec3;
use std::time::Instant;

/// The term a camera lane's findings at its first diffuse hit go to.
pub fn camera_slot(through_specular: u8, own: u8) -> u8 {
    if through_specular != 0 {
        slot::SPECULAR
    } else {
        own
    }
}

/// Applies `(sample, slot, value)` contributions in order.
fn apply(work: &mut CameraWork, contributions: Vec<(u32, u8, Vec3)>) {
    for (sample, s, v) in contributions {
        add_term(&mut work.terms[sample as usize], s, v);
    }
}

/// Caustic-map estimates at the diffuse hits of camera and glossy rays.
pub fn gather_caustics(
    shared: Res<Shared>,
    maps: Res<Maps>,
    mut work: ResMut<CameraWork>,
    mut stats: ResMut<StageStats>,
) {
    let t = Instant::now();
    let ctx = Context::new(&shared.scene, &maps.0, &shared.settings);
    let w = &*work;
    let lanes: Vec<u32> =
        w.classified.diffuse.iter().copied().filter(|&l| w.paths.kind[l as usize] != PathKind::Gather).collect();
    let out = par_lanes(lanes.len(), GATHER_CHUNK, shared.threads, |r| {
        let mut scratch = Vec::new();
        r.filter_map(|j| {
            let i = lanes[j] as usize;
            let sp = ctx.scene.surface(&w.paths.hits.get(i)?);
            let bsdf = &ctx.scene.materials[sp.material as usize].bsdf;
            let v = w.paths.beta[i] * caustic_estimate(&ctx, &sp, bsdf, -w.paths.rays.direction(i), &mut scratch);
            let s = match w.paths.kind[i] {
                PathKind::Camera => camera_slot(w.paths.through_specular[i], slot::CAUSTIC),
                _ => w.paths.slot[i],
            };
            Some((w.paths.sample[i], s, v))
        })
        .collect()
    });
    apply(&mut work, out);
    stats.record("gather_caustics", lanes.len(), t);
}

/// Global-map estimates at diffuse hits: gather rays read the maps' radiance; glossy rays, and
/// camera rays when final gathering is off, read the global map without direct and caustic
/// photons (those terms are computed separately).
pub fn gather_global(
    shared: Res<Shared>,
    maps: Res<Maps>,
    mut work: ResMut<CameraWork>,
    mut stats: ResMut<StageStats>,
) {
    let t = Instant::now();
    let ctx = Context::new(&shared.scene, &maps.0, &shared.settings);
    let gather_on = shared.effects.final_gather.on;
    let w = &*work;
    let lanes: Vec<u32> = w
        .classified
        .diffuse
        .iter()
        .copied()
        .filter(|&l| !(w.paths.kind[l as usize] == PathKind::Camera && gather_on))
        .collect();
    let out = par_lanes(lanes.len(), GATHER_CHUNK, shared.threads, |r| {
        let mut scratch = Vec::new();
        r.filter_map(|j| {
            let i = lanes[j] as usize;
            let sp = ctx.scene.surface(&w.paths.hits.get(i)?);
            let bsdf = &ctx.scene.materials[sp.material as usize].bsdf;
            let wo = -w.paths.rays.direction(i);
            let (value, s) = match w.paths.kind[i] {
                PathKind::Gather => (map_radiance(&ctx, &sp, bsdf, wo, &mut scratch), w.paths.slot[i]),
                kind => {
                    let v = global_estimate(&ctx, &sp, bsdf, wo, flags::DIRECT | flags::CAUSTIC, &mut scratch);
                    let s = if kind == PathKind::Camera {
                        camera_slot(w.paths.through_specular[i], slot::INDIRECT)
                    } else {
                        w.paths.slot[i]
                    };
                    (v, s)
                }
            };
            Some((w.paths.sample[i], s, w.paths.beta[i] * value))
        })
        .collect()
    });
    apply(&mut work, out);
    stats.record("gather_global", lanes.len(), t);
}
