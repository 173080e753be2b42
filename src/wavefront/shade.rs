//! Shade: what each lane does next. Photons scatter (BSDF sample, Russian roulette) into the
//! next photon queue. Camera-pass lanes at diffuse hits queue shadow rays (direct light) and
//! spawn final-gather and glossy rays; gather lanes that landed near queue shadow rays and spawn
//! their secondary gather's ray; gather and glossy lanes that landed on a narrow lobe spawn its
//! ray; lanes at mirrors and glass continue. After the bounce loop,
//! `resolve_wave` turns the tile's samples into pixels. Reads classified lanes and hits; writes
//! the next queues, the shadow queue and the film.

use super::queues::{PathKind, PhotonLane, Segment, ShadowLane};
use super::{CameraWork, Maps, PhotonWork, Shared, StageClock, StageStats};
use crate::film::Term;
use crate::rng::{Domain, Sampler};
use crate::transport::direct::{direct_light_rays, ShadowRay};
use crate::transport::gather::{gather_rays, glossy_density, glossy_ray};
use crate::transport::lobe::lobe_density;
use crate::transport::mis::{receiver, Strategies};
use crate::transport::photon::{scatter_photon, PathEnd, Scattered};
use crate::transport::specular::continue_chain;
use crate::transport::{streams, Context};
use bevy_ecs::prelude::*;

/// Scatters the photon lanes `lanes` into the next queue, counting per path what the bounce
/// clamped, dropped or cut.
fn scatter_lanes(shared: &Shared, work: &mut PhotonWork, lanes: &[u32]) {
    let scene = &*shared.scene;
    let domain = work.domain.unwrap_or(Domain::GlobalPhoton);
    let PhotonWork { queue: q, next, counts: path_counts, first_path, .. } = work;
    for &lane in lanes {
        let i = lane as usize;
        let Some(hit) = q.hits.get(i) else { continue };
        let sp = scene.surface(&hit);
        let bsdf = scene.bsdf(&sp);
        let photon = q.photon(i);
        let s = Sampler::new(shared.job.pass.seed, domain, q.path[i]);
        let r = scatter_photon(&s, &sp, &bsdf, &photon, q.bounce[i]);
        let (path, bounce) = (q.path[i], q.bounce[i]);
        let counts = &mut path_counts[(path - *first_path) as usize];
        let p = match r {
            Scattered::Continue(p) => p,
            Scattered::Capped(p) => {
                counts.capped = counts.capped.saturating_add(1);
                p
            }
            Scattered::NonFinite => {
                counts.end = PathEnd::ScatterNonFinite;
                continue;
            }
            Scattered::ZeroPdf => {
                counts.end = PathEnd::ZeroPdf;
                continue;
            }
            Scattered::Absorbed => continue,
        };
        // Russian roulette did not end it within max_depth bounces: the safety cap does.
        if bounce + 1 >= shared.job.settings.max_depth {
            counts.end = PathEnd::DepthCut;
            continue;
        }
        next.push(PhotonLane {
            origin: p.origin,
            dir: p.dir,
            path,
            bounce: bounce + 1,
            power: p.power,
            emitted: p.emitted,
            specular_only: p.specular_only,
        });
    }
}

/// Photons at mirrors and surviving diffuse photons scatter into the next queue.
pub fn scatter_photons(shared: Res<Shared>, mut work: ResMut<PhotonWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let lanes: Vec<u32> = work.classified.mirror.iter().chain(&work.survivors).copied().collect();
    scatter_lanes(&shared, &mut work, &lanes);
    stats.record("scatter_photons", lanes.len(), t);
}

/// Photons at glass reflect or refract into the next queue (only in scenes with glass).
pub fn refract_photons(shared: Res<Shared>, mut work: ResMut<PhotonWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let lanes = std::mem::take(&mut work.classified.glass);
    scatter_lanes(&shared, &mut work, &lanes);
    stats.record("refract_photons", lanes.len(), t);
    work.classified.glass = lanes;
}

/// Diffuse lanes of camera, glossy and near-landed gather rays queue their shadow rays (direct
/// light).
pub fn shade_direct(shared: Res<Shared>, maps: Res<Maps>, mut work: ResMut<CameraWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let ctx = Context::new(&shared.scene, &maps.0, &shared.job);
    let CameraWork { paths, classified, shadows, .. } = &mut *work;
    let scene = &*shared.scene;
    let before = shadows.len();
    // Camera lanes at surfaces passed by sampling (frosted glass, smooth rough metal) take the
    // delta lights' direct light there; lanes merged in order.
    let passed = |l: &u32| {
        let i = *l as usize;
        paths.kind[i] == PathKind::Camera
            && paths.hits.get(i).is_some_and(|h| {
                let b = &scene.materials[scene.material[h.tri as usize] as usize].bsdf;
                !b.is_delta() && b.photon_specular()
            })
    };
    let mut lanes: Vec<u32> =
        classified.diffuse.iter().copied().filter(|&l| !paths.kind[l as usize].reads_maps()).collect();
    if !scene.delta_lights.is_empty() {
        lanes.extend(classified.mirror.iter().copied().filter(passed));
        lanes.sort_unstable();
    }
    for &lane in &lanes {
        let i = lane as usize;
        let Some(hit) = paths.hits.get(i) else { continue };
        let sp = ctx.scene.surface(&hit);
        let bsdf = &ctx.scene.bsdf(&sp);
        let s = Sampler::from_key(paths.key[i]);
        let (stream, term) = match paths.kind[i] {
            PathKind::Camera => (s.fork(streams::light(paths.depth[i])), Term::Direct.seen(paths.through_specular[i])),
            PathKind::NearGather => (s.fork(streams::SECONDARY_LIGHT), paths.term[i]),
            _ => (s.fork(streams::GLOSSY_HIT_LIGHT), paths.term[i]),
        };
        let (beta, sample) = (paths.beta[i], paths.sample[i]);
        let delta_only = !bsdf.is_delta() && bsdf.photon_specular();
        // Only a camera path's own non-specular hit, and a glossy ray's landing on a narrow
        // lobe, send the rays their light samples are weighed against (as in the reference).
        let mis = match paths.kind[i] {
            PathKind::Camera if !delta_only => Strategies::at_camera_hit(&ctx, bsdf),
            PathKind::Glossy => Strategies::at_landing(&ctx, bsdf),
            _ => Strategies::LightOnly,
        };
        let wo = -paths.rays.direction(i);
        direct_light_rays(&ctx, &sp, bsdf, wo, &stream, delta_only, &mis, |ray: ShadowRay| {
            shadows.push(ShadowLane {
                origin: ray.origin,
                dir: ray.direction,
                t_max: ray.t_max,
                sample,
                term,
                contribution: ray.contribution * beta,
            });
        });
    }
    let n = shadows.len() - before;
    stats.record("shade_direct", n, t);
}

/// Diffuse camera lanes spawn `gather_rays` cosine-weighted rays, each weighted beta·kd/N;
/// near-landed gather lanes spawn their secondary gather's one ray, weighted beta·kd.
pub fn spawn_gather_rays(
    shared: Res<Shared>,
    maps: Res<Maps>,
    mut work: ResMut<CameraWork>,
    mut stats: ResMut<StageStats>,
) {
    let t = StageClock::start();
    let ctx = Context::new(&shared.scene, &maps.0, &shared.job);
    let scene = &*shared.scene;
    let n = shared.job.settings.gather_rays;
    // Rays go straight into the next queue (disjoint fields of the work resource).
    let CameraWork { paths, classified, next, receivers, .. } = &mut *work;
    let w = &*paths;
    let lanes: Vec<u32> = classified
        .diffuse
        .iter()
        .copied()
        .filter(|&l| matches!(w.kind[l as usize], PathKind::Camera | PathKind::NearGather))
        .collect();
    let before = next.len();
    next.reserve(lanes.len() * n as usize);
    for &lane in &lanes {
        let i = lane as usize;
        let Some(hit) = w.hits.get(i) else { continue };
        let sp = scene.surface(&hit);
        let bsdf = scene.bsdf(&sp);
        let kd = bsdf.diffuse();
        if kd == glam::Vec3::ZERO {
            continue;
        }
        let s = Sampler::from_key(w.key[i]);
        let (gs, rays, kind, term, mis) = match w.kind[i] {
            PathKind::Camera => (
                s.fork(streams::gather(w.depth[i])),
                n,
                PathKind::Gather,
                Term::Indirect.seen(w.through_specular[i]),
                Strategies::at_camera_hit(&ctx, &bsdf),
            ),
            _ => (s.fork(streams::SECONDARY_GATHER), 1, PathKind::SecondaryGather, w.term[i], Strategies::LightOnly),
        };
        let wo = -w.rays.direction(i);
        if kind == PathKind::Gather {
            receivers[w.sample[i] as usize] = receiver(&sp, &bsdf, wo);
        }
        let weight = w.beta[i] * kd / rays as f32;
        gather_rays(&sp, wo, rays, &gs, |g, origin, dir| {
            // A rough plastic weighs each ray by its base's share (as the reference).
            let weight = if bsdf.gather_varies() {
                w.beta[i] * bsdf.gather_weight(&sp.frame, wo, dir) / rays as f32
            } else {
                weight
            };
            next.push(Segment {
                origin,
                dir,
                sample: w.sample[i],
                kind,
                key: gs.fork(streams::gather_ray(g)).key(),
                base: streams::GATHER_CHAIN_BOUNCE as u8,
                depth: 0,
                beta: weight,
                term,
                through_specular: w.through_specular[i],
                mis: mis.gather_density(&sp, wo, dir),
            });
        });
    }
    let count = next.len() - before;
    stats.record("spawn_gather_rays", count, t);
}

/// Diffuse camera lanes on glossy materials spawn one ray from the glossy lobe.
pub fn spawn_glossy_rays(
    shared: Res<Shared>,
    maps: Res<Maps>,
    mut work: ResMut<CameraWork>,
    mut stats: ResMut<StageStats>,
) {
    let t = StageClock::start();
    let ctx = Context::new(&shared.scene, &maps.0, &shared.job);
    let scene = &*shared.scene;
    let CameraWork { paths, classified, next, receivers, narrow_hits, .. } = &mut *work;
    let before = next.len();
    for &l in &classified.diffuse {
        let i = l as usize;
        if paths.kind[i] != PathKind::Camera {
            continue;
        }
        let Some(hit) = paths.hits.get(i) else { continue };
        let sp = scene.surface(&hit);
        let bsdf = &scene.bsdf(&sp);
        // Only glossy materials have the lobe (glossy_ray says so too, after the stream's fork).
        if !bsdf.has_glossy_lobe() {
            continue;
        }
        let gls = Sampler::from_key(paths.key[i]).fork(streams::glossy(paths.depth[i]));
        let wo = -paths.rays.direction(i);
        let Some(ray) = glossy_ray(&sp, bsdf, wo, &gls) else { continue };
        let mis = Strategies::at_camera_hit(&ctx, bsdf);
        receivers[paths.sample[i] as usize] = receiver(&sp, bsdf, wo);
        narrow_hits[paths.sample[i] as usize] = bsdf.narrow_lobe();
        next.push(Segment {
            origin: ray.origin,
            dir: ray.dir,
            sample: paths.sample[i],
            kind: PathKind::Glossy,
            key: gls.key(),
            base: streams::GLOSSY_CHAIN_BOUNCE as u8,
            depth: 0,
            beta: paths.beta[i] * ray.weight,
            term: Term::Specular,
            through_specular: paths.through_specular[i],
            mis: glossy_density(&ray, &mis, &sp, bsdf, wo),
        });
    }
    let count = next.len() - before;
    stats.record("spawn_glossy_rays", count, t);
}

/// Gather and glossy lanes that landed on a narrow lobe spawn that lobe's ray
/// (`transport::lobe`): from a glossy lane's landing, whose light samples it is weighed
/// against, with that point as the sample's lobe receiver; from a gather lane's, with nothing to
/// weigh against (density ∞).
pub fn spawn_lobe_rays(
    shared: Res<Shared>,
    maps: Res<Maps>,
    mut work: ResMut<CameraWork>,
    mut stats: ResMut<StageStats>,
) {
    let t = StageClock::start();
    let ctx = Context::new(&shared.scene, &maps.0, &shared.job);
    let scene = &*shared.scene;
    let CameraWork { paths, classified, next, lobe_receivers, .. } = &mut *work;
    let before = next.len();
    for &l in &classified.diffuse {
        let i = l as usize;
        let kind = paths.kind[i];
        if !matches!(kind, PathKind::Gather | PathKind::SecondaryGather | PathKind::Glossy) {
            continue;
        }
        let Some(hit) = paths.hits.get(i) else { continue };
        // Most landings are on materials without one: no surface point built for those.
        if !scene.materials[scene.material[hit.tri as usize] as usize].may_have_narrow_lobe() {
            continue;
        }
        let sp = scene.surface(&hit);
        let bsdf = &scene.bsdf(&sp);
        if !bsdf.narrow_lobe() {
            continue;
        }
        let s = Sampler::from_key(paths.key[i]).fork(streams::LANDING_LOBE);
        let wo = -paths.rays.direction(i);
        let Some(ray) = glossy_ray(&sp, bsdf, wo, &s) else { continue };
        let lit = (kind == PathKind::Glossy).then(|| Strategies::at_landing(&ctx, bsdf));
        if lit.is_some() {
            lobe_receivers[paths.sample[i] as usize] = receiver(&sp, bsdf, wo);
        }
        next.push(Segment {
            origin: ray.origin,
            dir: ray.dir,
            sample: paths.sample[i],
            kind: PathKind::Lobe,
            key: s.key(),
            base: streams::GLOSSY_CHAIN_BOUNCE as u8,
            depth: 0,
            beta: paths.beta[i] * ray.weight,
            term: paths.term[i],
            through_specular: paths.through_specular[i],
            mis: lobe_density(&ray, lit.as_ref(), &sp, bsdf, wo),
        });
    }
    let count = next.len() - before;
    stats.record("spawn_lobe_rays", count, t);
}

/// Continues the lanes at mirrors (or, with `glass`, at glass) into the next queue by sampling
/// the delta BSDF with the random numbers of bounce `base + depth` ([`continue_chain`]'s roulette
/// included); chains stop after `max_depth` bounces, counted in the numerics. Returns the lanes
/// it looked at.
fn continue_specular(shared: &Shared, work: &mut CameraWork, glass: bool) -> usize {
    let scene = &*shared.scene;
    let max_depth = shared.job.settings.max_depth;
    let CameraWork { paths, classified, next, numerics, .. } = work;
    let lanes = if glass { &classified.glass } else { &classified.mirror };
    for &lane in lanes {
        let i = lane as usize;
        let Some(hit) = paths.hits.get(i) else { continue };
        let sp = scene.surface(&hit);
        if paths.depth[i] >= max_depth {
            numerics.camera_depth_cut += 1;
            continue;
        }
        let bsdf = &scene.bsdf(&sp);
        let s = Sampler::from_key(paths.key[i]);
        let (depth, bounce) = (paths.depth[i], u32::from(paths.base[i]) + paths.depth[i]);
        let Some(bounced) = continue_chain(&sp, bsdf, -paths.rays.direction(i), &s, bounce, depth) else { continue };
        next.push(Segment {
            origin: bounced.origin,
            dir: bounced.dir,
            sample: paths.sample[i],
            kind: paths.kind[i],
            key: paths.key[i],
            base: paths.base[i],
            depth: paths.depth[i] + 1,
            beta: paths.beta[i] * bounced.weight,
            term: paths.term[i],
            through_specular: paths.kind[i] == PathKind::Camera,
            mis: 0.0,
        });
    }
    lanes.len()
}

/// Lanes at mirrors continue.
pub fn reflect_paths(shared: Res<Shared>, mut work: ResMut<CameraWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let n = continue_specular(&shared, &mut work, false);
    stats.record("reflect_paths", n, t);
}

/// Lanes at glass reflect or refract (only in scenes with glass).
pub fn refract_paths(shared: Res<Shared>, mut work: ResMut<CameraWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let n = continue_specular(&shared, &mut work, true);
    stats.record("refract_paths", n, t);
}

/// Averages each pixel's samples (dropping non-finite ones, as the reference does) into the
/// tile's pixels, in sample order; a pixel whose samples go on in the tile's next wave is left
/// open ([`CameraWork::open`]).
pub fn resolve_wave(shared: Res<Shared>, mut work: ResMut<CameraWork>, mut stats: ResMut<StageStats>) {
    let t = StageClock::start();
    let spp = shared.job.settings.spp as u64;
    let inv = 1.0 / spp as f32;
    let w = &mut *work;
    // In sample order, each pixel's mean finished at its last sample; a pixel this wave does
    // not finish stays open for the tile's next wave.
    for (lane, t) in w.terms.iter().enumerate() {
        w.open.add(*t, inv);
        if (w.first_sample + lane as u64 + 1).is_multiple_of(spp) {
            let pixel = std::mem::take(&mut w.open).finish(inv, &mut w.numerics);
            w.film.push(pixel);
        }
    }
    stats.record("resolve_wave", w.count, t);
}
