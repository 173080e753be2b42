//! Gather: photon-map density estimates where lanes reached a diffuse surface — the caustic map
//! for camera, glossy and near-landed gather rays, the global map for the other gather rays
//! (precomputed irradiance where it applies), and the global map without direct and caustic
//! photons for glossy rays and for camera rays when final gathering is off. Reads the diffuse
//! lane list, hits and maps; writes the wave's terms in lane order.

use super::queues::PathKind;
use super::{par_lanes, CameraWork, Maps, Shared, StageStats, GATHER_CHUNK};
use crate::film::Term;
use crate::material::Bsdf;
use crate::photon_map::Estimate;
use crate::scene::SurfacePoint;
use crate::transport::estimate::{camera_indirect_estimate, caustic_estimate, indirect_estimate, map_radiance};
use crate::transport::Context;
use bevy_ecs::prelude::*;
use glam::Vec3;
use std::time::Instant;

/// Runs `estimate(ctx, point, bsdf, wo, kind, pixel, scratch)` at the diffuse hit of every lane
/// whose kind passes `wanted` (`pixel` is the lane's pixel for camera lanes, `None` for
/// others), in parallel, and adds `beta × radiance` to the lane's sample in lane order (and
/// `beta × bias` to its bias). `own` is
/// the term of camera lanes (routed to specular behind a mirror or glass); gather and glossy
/// lanes use the term they carry. Returns the number of estimates.
fn estimate_at_diffuse_hits(
    shared: &Shared,
    maps: &Maps,
    work: &mut CameraWork,
    wanted: impl Fn(PathKind) -> bool,
    own: Term,
    estimate: impl Fn(&Context, &SurfacePoint, &Bsdf, Vec3, PathKind, Option<usize>, &mut Vec<(f32, u32)>) -> Estimate
        + Sync,
) -> usize {
    let ctx = Context::new(&shared.scene, &maps.0, &shared.job);
    let spp = u64::from(shared.job.settings.spp);
    let w = &*work;
    let lanes: Vec<u32> = w.classified.diffuse.iter().copied().filter(|&l| wanted(w.paths.kind[l as usize])).collect();
    let out: Vec<(u32, Term, Vec3, Vec3)> = par_lanes(lanes.len(), GATHER_CHUNK, shared.job.threads, |r| {
        let mut scratch = Vec::new();
        r.filter_map(|j| {
            let i = lanes[j] as usize;
            let sp = ctx.scene.surface(&w.paths.hits.get(i)?);
            let bsdf = &ctx.scene.bsdf(&sp);
            let kind = w.paths.kind[i];
            let pixel =
                (kind == PathKind::Camera).then(|| ((w.first_sample + u64::from(w.paths.sample[i])) / spp) as usize);
            let e = estimate(&ctx, &sp, bsdf, -w.paths.rays.direction(i), kind, pixel, &mut scratch);
            let term = match kind {
                PathKind::Camera => own.seen(w.paths.through_specular[i]),
                _ => w.paths.term[i],
            };
            let beta = w.paths.beta[i];
            Some((w.paths.sample[i], term, beta * e.radiance, beta * e.bias))
        })
        .collect()
    });
    for &(sample, term, v, bias) in &out {
        let t = &mut work.terms[sample as usize];
        t.add(term, v);
        t.bias += bias;
    }
    work.numerics.photons_filtered += ctx.filtered();
    lanes.len()
}

/// Caustic-map estimates at the diffuse hits of camera, glossy and near-landed gather rays.
pub fn gather_caustics(
    shared: Res<Shared>,
    maps: Res<Maps>,
    mut work: ResMut<CameraWork>,
    mut stats: ResMut<StageStats>,
) {
    let t = Instant::now();
    let n = estimate_at_diffuse_hits(
        &shared,
        &maps,
        &mut work,
        |kind| !kind.reads_maps(),
        Term::Caustic,
        |ctx, sp, bsdf, wo, _, pixel, scratch| caustic_estimate(ctx, sp, bsdf, wo, pixel, scratch),
    );
    stats.record("gather_caustics", n, t);
}

/// Global-map estimates at diffuse hits: gather rays read the maps' radiance (not those that
/// landed near, whose secondary gather reads them a bounce later); glossy rays, and camera rays
/// when final gathering is off, read the global map without direct and caustic photons (those
/// terms are computed separately).
pub fn gather_global(
    shared: Res<Shared>,
    maps: Res<Maps>,
    mut work: ResMut<CameraWork>,
    mut stats: ResMut<StageStats>,
) {
    let t = Instant::now();
    let gather_on = shared.job.plan.final_gather.on;
    let n = estimate_at_diffuse_hits(
        &shared,
        &maps,
        &mut work,
        |kind| match kind {
            PathKind::Camera => !gather_on,
            PathKind::NearGather => false,
            _ => true,
        },
        Term::Indirect,
        |ctx, sp, bsdf, wo, kind, pixel, scratch| {
            if kind.reads_maps() {
                map_radiance(ctx, sp, bsdf, wo, scratch)
            } else if kind == PathKind::Camera {
                camera_indirect_estimate(ctx, sp, bsdf, wo, pixel, scratch)
            } else {
                indirect_estimate(ctx, sp, bsdf, wo, pixel, scratch)
            }
        },
    );
    stats.record("gather_global", n, t);
}
