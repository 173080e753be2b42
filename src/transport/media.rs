//! Light in a scene-filling participating medium ([`crate::medium`]): the light a medium point
//! scatters toward the camera path (in-scattering by light sampling through the phase
//! function, weighted by MIS against the phase function's own sample). Direct light at a
//! surface in a medium is [`super::direct::attenuated_direct_light`].
//!
//! A medium point is a receiver with no surface: it takes light from every direction (a
//! two-sided [`Receiver`] whose normal is the path's direction), so light choice and the MIS
//! densities are those of [`super::direct`] and [`super::mis`] for that receiver.
//!
//! Reads the scene's lights and medium; writes radiance. The reference photon mapper uses the
//! in-scattering for its single scattering ([`super::volume`]).

use super::direct::{light_sample_density, light_samples, shadow_segment, unblocked, ShadowRay};
use super::mis::{power_heuristic, Strategies};
use super::Context;
use crate::medium::Medium;
use crate::rng::Sampler;
use crate::scene::Receiver;
use crate::stats::RayCounts;
use glam::Vec3;

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
        sum += unblocked(ctx, Some(medium), &ray, rays);
    });
    sum
}
