//! Ray generation at a camera path's non-specular hit for the two terms that trace further:
//! final gathering (Jensen's soft indirect term: `kd/N · Σ L(x, ωi)` over N cosine-weighted
//! rays, where the 1/π and the cosine cancel) and the glossy lobe's one reflected ray; and
//! Jensen's secondary gather, which decides where a gather ray does not read the maps.
//!
//! Secondary gather: a gather ray that lands on a Lambertian surface within a few global-map
//! radii of its origin (no mirror or glass between) would read an estimate whose disk reaches
//! back toward the point being gathered. In a corner that disk averages the dark corner with the
//! brighter surface beyond, and the gathered light comes out too bright: on CornellBox-Original
//! the front face of the short box where it meets the floor was 2 % too bright at 120 s, with
//! or without the boundary correction (BENCHMARKS.md). There the ray instead takes direct light
//! and the caustic map at its hit, and one cosine-weighted gather ray (weight kd) that reads the
//! maps where it lands, farther away. It is still the same sum over paths, only one bounce later
//! read from the maps; LuxCore's PhotonGI does the same below its "usage threshold".

use super::mis::Strategies;
use super::specular::{follow_chain, Bounce, Chain};
use super::{streams, Context};
use crate::geometry::offset::offset_ray_origin;
use crate::job::Job;
use crate::material::Bsdf;
use crate::rng::Sampler;
use crate::sampling::{cosine_hemisphere, Frame};
use crate::scene::{Scene, SurfacePoint};
use crate::stats::RayCounts;
use glam::Vec3;

/// The `n` final-gather rays at `sp` seen from `wo`: cosine-weighted directions about the
/// shading normal on `wo`'s side, ray `g` drawn from bounce `g` (dims 0–1) of `s`. A direction
/// below the geometric surface gives no ray but still counts in the estimator's N. Calls
/// `emit(g, origin, direction)` for each ray, in order.
#[inline]
pub fn gather_rays(sp: &SurfacePoint, wo: Vec3, n: u32, s: &Sampler, mut emit: impl FnMut(u32, Vec3, Vec3)) {
    let (ng, ns) = sp.frame.oriented(wo);
    let frame = Frame::new(ns);
    for g in 0..n {
        let wi = frame.to_world(cosine_hemisphere([s.get(g, 0), s.get(g, 1)]));
        if wi.dot(ng) <= 0.0 {
            continue;
        }
        emit(g, offset_ray_origin(sp.p, sp.p_error, sp.frame.ng, wi), wi);
    }
}

/// Traces the final-gather rays of [`gather_rays`] through mirrors and glass, each on its own
/// stream (forked [`streams::gather_ray`]`(g)` from `s`), and calls `read(chain, wi, stream,
/// rays)` with how each one's chain ended (`wi` the ray's first direction), in ray order.
pub fn trace_gather_rays(
    ctx: &Context,
    sp: &SurfacePoint,
    wo: Vec3,
    n: u32,
    s: &Sampler,
    rays: &mut RayCounts,
    mut read: impl FnMut(&Chain, Vec3, &Sampler, &mut RayCounts),
) {
    gather_rays(sp, wo, n, s, |g, o, wi| {
        let stream = s.fork(streams::gather_ray(g));
        let chain = follow_chain(ctx, o, wi, &stream, streams::GATHER_CHAIN_BOUNCE, rays);
        read(&chain, wi, &stream, rays);
    });
}

/// The glossy lobe's ray at `sp` seen from `wo`, drawn from bounce 0 (dims 0–1) of `s`, with
/// its weight; `delta` for a smooth plastic's coat (a mirror direction, which light sampling
/// never finds: [`glossy_density`]). `None` for a material without a glossy lobe or a sample
/// below the surface.
#[must_use]
#[inline]
pub fn glossy_ray(sp: &SurfacePoint, bsdf: &Bsdf, wo: Vec3, s: &Sampler) -> Option<Bounce> {
    let bs = bsdf.sample_glossy(&sp.frame, wo, [s.get(0, 0), s.get(0, 1), s.get(0, 2)])?;
    Some(Bounce {
        origin: offset_ray_origin(sp.p, sp.p_error, sp.frame.ng, bs.wi),
        dir: bs.wi,
        weight: bs.weight,
        delta: bs.delta,
    })
}

/// The density to weigh the emission a glossy ray `ray` finds against light sampling: the lobe's
/// density toward it under `mis`, or for a delta lobe ∞ (light sampling never finds a mirror
/// direction, so the ray counts all of it).
#[must_use]
#[inline]
pub fn glossy_density(ray: &Bounce, mis: &Strategies, sp: &SurfacePoint, bsdf: &Bsdf, wo: Vec3) -> f32 {
    if ray.delta {
        f32::INFINITY
    } else {
        mis.glossy_density(sp, bsdf, wo, ray.dir)
    }
}

/// The distance below which a gather ray's hit takes the secondary gather, in scene units:
/// [`Settings::secondary_gather`](crate::settings::Settings::secondary_gather) global-map radii
/// (the pass's fixed radius in progressive passes, the maximum k-nearest radius otherwise); 0
/// when it is off.
#[must_use]
pub fn secondary_gather_distance(scene: &Scene, job: &Job) -> f32 {
    let radius = job.pass.radii.as_ref().map_or(job.settings.global_radius * scene.diagonal(), |r| r.global);
    job.settings.secondary_gather * radius
}

/// Whether a gather ray ending at `end` on `bsdf` takes the secondary gather there: a Lambertian
/// hit closer than `distance` ([`secondary_gather_distance`]) straight from the ray's origin.
#[must_use]
#[inline]
pub fn lands_near(end_t: f32, bounces: u32, bsdf: &Bsdf, distance: f32) -> bool {
    bounces == 0 && end_t < distance && matches!(bsdf, Bsdf::Lambert { .. })
}
