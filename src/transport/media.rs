//! Light in a scene-filling participating medium ([`crate::medium`]), for the path tracer:
//! the transmittance of shadow rays, direct light at a surface attenuated by the medium, and
//! the light a medium point scatters toward the camera path (in-scattering by light sampling
//! through the phase function, weighted by MIS against the phase function's own sample).
//!
//! A medium point is a receiver with no surface: it takes light from every direction (a
//! two-sided [`Receiver`] whose normal is the path's direction), so light choice and the MIS
//! densities are those of [`super::direct`] and [`super::mis`] for that receiver.
//!
//! Reads the scene's lights and medium; writes radiance. The photon-mapping engines do not use
//! it yet: a scene with a medium is refused there (`crate::engine::check_planned`).

use super::direct::{direct_light_rays, light_sample_density, light_samples, shadow_segment, ShadowRay};
use super::mis::{power_heuristic, Strategies};
use super::Context;
use crate::material::Bsdf;
use crate::medium::Medium;
use crate::rng::Sampler;
use crate::scene::{Receiver, SurfacePoint};
use crate::stats::RayCounts;
use glam::Vec3;

/// The fraction of a shadow ray's light the medium lets through over its length (the whole
/// ray for a distant light: none where σ_t > 0).
#[must_use]
pub fn shadow_transmittance(medium: &Medium, ray: &ShadowRay) -> Vec3 {
    let length = if ray.t_max.is_finite() { ray.direction.length() * ray.t_max } else { f32::INFINITY };
    medium.transmittance(length)
}

/// Direct light at `sp` toward `wo` by light sampling, each unblocked shadow ray's
/// contribution times the transmittance of the medium it travels in, `medium_toward` its
/// direction (none: clear) — the path tracer's [`super::direct::weighted_direct_light`] in
/// media.
#[allow(clippy::too_many_arguments)]
pub fn attenuated_direct_light<'m>(
    ctx: &Context,
    medium_toward: impl Fn(Vec3) -> Option<&'m Medium>,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    s: &Sampler,
    mis: &Strategies,
    rays: &mut RayCounts,
) -> Vec3 {
    let mut sum = Vec3::ZERO;
    direct_light_rays(ctx, sp, bsdf, wo, s, false, mis, |r| sum += through(ctx, medium_toward(r.direction), &r, rays));
    sum
}

/// What shadow ray `r` carries through `medium` (none: clear): its contribution times the
/// transmittance along it, if nothing blocks it (no ray is traced where the medium lets
/// nothing through).
fn through(ctx: &Context, medium: Option<&Medium>, r: &ShadowRay, rays: &mut RayCounts) -> Vec3 {
    let t = medium.map_or(Vec3::ONE, |m| shadow_transmittance(m, r));
    if t == Vec3::ZERO {
        return Vec3::ZERO;
    }
    rays.shadow += 1;
    if ctx.scene.occluded(r.origin, r.direction, r.t_max) {
        Vec3::ZERO
    } else {
        r.contribution * t
    }
}

/// The receiver light sampling works for at medium point `p` reached along unit `d`.
#[must_use]
pub fn medium_receiver(p: Vec3, d: Vec3) -> Receiver {
    Receiver { p, n: d, two_sided: true }
}

/// Light that medium point `p`, reached along unit `d`, scatters back along −d, per unit σ_s
/// (the path's weight carries σ_s): Σ over light samples of p(θ)·L·T / pdf, each sample that a
/// phase-function sample could also find weighted by the power heuristic against that
/// sample's density when `mis` is on.
pub fn in_scattered_light(
    ctx: &Context,
    medium: &Medium,
    p: Vec3,
    d: Vec3,
    s: &Sampler,
    mis: bool,
    rays: &mut RayCounts,
) -> Vec3 {
    let r = medium_receiver(p, d);
    let phase = medium.phase();
    let strategies = if mis { Strategies::Whole } else { Strategies::LightOnly };
    let mut sum = Vec3::ZERO;
    light_samples(ctx, &r, s, false, |light_index, inc, weight| {
        // Light arrives travelling along −wi and leaves along −d.
        let f = phase.eval(d, inc.wi);
        let w = light_sample_density(ctx, &r, &strategies, light_index, inc).map_or(1.0, |l| power_heuristic(l, f));
        if !(f * w > 0.0) {
            return;
        }
        let (direction, t_max) = shadow_segment(p, inc);
        let ray = ShadowRay { origin: p, direction, t_max, contribution: inc.value * (f * w * weight) };
        sum += through(ctx, Some(medium), &ray, rays);
    });
    sum
}
