//! Ray generation at a camera path's non-specular hit for the two terms that trace further:
//! final gathering (Jensen's soft indirect term: `kd/N · Σ L(x, ωi)` over N cosine-weighted
//! rays, where the 1/π and the cosine cancel) and the glossy lobe's one reflected ray.

use super::specular::Bounce;
use crate::geometry::offset::offset_ray_origin;
use crate::material::Bsdf;
use crate::rng::Sampler;
use crate::sampling::{cosine_hemisphere, Frame};
use crate::scene::SurfacePoint;
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

/// The glossy lobe's ray at `sp` seen from `wo`, drawn from bounce 0 (dims 0–1) of `s`, with
/// its weight; `None` for a material without a glossy lobe or a sample below the surface.
#[must_use]
#[inline]
pub fn glossy_ray(sp: &SurfacePoint, bsdf: &Bsdf, wo: Vec3, s: &Sampler) -> Option<Bounce> {
    let bs = bsdf.sample_glossy(&sp.frame, wo, [s.get(0, 0), s.get(0, 1)])?;
    Some(Bounce {
        origin: offset_ray_origin(sp.p, sp.p_error, sp.frame.ng, bs.wi),
        dir: bs.wi,
        weight: bs.weight,
        delta: false,
    })
}
