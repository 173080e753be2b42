//! Direct light by light sampling (Jensen's first term): at a non-specular point, every delta
//! light once and `light_samples` area-light samples, each light chosen by the light tree or by
//! power ([`crate::scene::Scene::choose_light`]) and each triangle's point by the solid angle it
//! subtends or by area ([`crate::scene::light`]), each a shadow ray that
//! carries its contribution if nothing blocks it. Where BSDF samples can find the same emitters
//! ([`super::mis::Strategies`]), an emissive triangle's, the environment's and a sun's samples
//! are weighted against them. In a medium filling the scene a shadow ray carries its
//! transmittance ([`unblocked`]).

use super::mis::{environment_density, light_density, receiver, sun_density, weighed_light, Strategies};
use super::Context;
use crate::geometry::offset::offset_ray_origin;
use crate::material::Bsdf;
use crate::medium::Medium;
use crate::rng::Sampler;
use crate::scene::light::{Incident, Light};
use crate::scene::{Receiver, SurfacePoint};
use crate::stats::RayCounts;
use glam::Vec3;

/// Shadow rays stop this fraction short of the light point (relative, so scale-free).
const SHADOW_SHORTEN: f32 = 1e-4;

/// A shadow ray and what it carries if nothing blocks it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowRay {
    /// Origin (offset off the surface).
    pub origin: Vec3,
    /// Direction; not unit for rays to a point (the point is at t = 1).
    pub direction: Vec3,
    /// Blocked by hits with t below this.
    pub t_max: f32,
    /// Reflected radiance it adds when unblocked: f·L·|cos|/pdf.
    pub contribution: Vec3,
}

/// Light sampling at receiver `r`: every delta light once, then (unless `delta_only`)
/// `light_samples` area-light samples, each light chosen by
/// [`crate::scene::Scene::choose_light`] from the sub-stream `s` (sample `j`: dim 0 the light,
/// dims 1–2 the point on it). `visit` gets each sample's light index, the incident light and
/// its weight 1/(pmf · samples) (1 for a delta light). Lights that send nothing toward `r.p`
/// (back faces, outside a spot cone) are skipped.
pub fn light_samples(
    ctx: &Context,
    r: &Receiver,
    s: &Sampler,
    delta_only: bool,
    mut visit: impl FnMut(u32, &Incident, f32),
) {
    let scene = ctx.scene;
    let mut add = |light_index: u32, u: [f32; 2], weight: f32| {
        let light = &scene.lights[light_index as usize];
        if let Some(inc) = scene.sample_incident(light, r.p, r.n, u) {
            visit(light_index, &inc, weight);
        }
    };
    for &li in &scene.delta_lights {
        add(li, [0.5, 0.5], 1.0);
    }
    if delta_only {
        return;
    }
    let n = ctx.settings.light_samples;
    for j in 0..n {
        if let Some((light, pmf)) = scene.choose_light(ctx.settings.light_sampler, r, s.get(j, 0)) {
            add(light, [s.get(j, 1), s.get(j, 2)], 1.0 / (pmf * n as f32));
        }
    }
}

/// The density with which light sampling at `r` drew `inc` from light `light_index`, where a
/// BSDF or phase-function sample can find the same light ([`super::mis`]): an emissive
/// triangle weighed by MIS, the environment, a sun; `None` (unweighted) otherwise or for
/// [`Strategies::LightOnly`].
#[must_use]
pub fn light_sample_density(
    ctx: &Context,
    r: &Receiver,
    mis: &Strategies,
    light_index: u32,
    inc: &Incident,
) -> Option<f32> {
    match (mis, &ctx.scene.lights[light_index as usize]) {
        (Strategies::LightOnly, _) => None,
        (_, Light::Area { tri, .. }) => {
            weighed_light(ctx.scene, *tri).map(|k| light_density(ctx, r, k, *tri, inc.distance, inc.wi))
        }
        (_, Light::Environment) => Some(environment_density(ctx, r, inc.wi)),
        (_, Light::Sun { .. }) => Some(sun_density(ctx, r, light_index)),
        _ => None,
    }
}

/// The direction (not unit for a light point, which lies at t = 1) and the t_max of a shadow
/// ray from `origin` to the light sample `inc`.
#[must_use]
pub fn shadow_segment(origin: Vec3, inc: &Incident) -> (Vec3, f32) {
    match inc.point {
        // The light point moved off its emitter toward the shading point, out of its error
        // box, as the origin is off the surface (pbrt-v4's spawn-ray-to between two surface
        // points).
        Some((q, n)) => (offset_ray_origin(q, inc.point_error, n, -inc.wi) - origin, 1.0 - SHADOW_SHORTEN),
        None => (inc.wi, f32::INFINITY),
    }
}

/// The shadow rays of direct light at `sp` toward `wo`: every delta light once, then (unless
/// `delta_only`) `light_samples` area-light samples ([`light_samples`]), an emissive
/// triangle's weighted by MIS against `mis`. Lights that cannot contribute (behind the surface,
/// back faces, outside a spot cone) get no ray.
#[allow(clippy::too_many_arguments)]
pub fn direct_light_rays(
    ctx: &Context,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    s: &Sampler,
    delta_only: bool,
    mis: &Strategies,
    mut emit: impl FnMut(ShadowRay),
) {
    // The point, its shading normal on wo's side, and whether it takes light from behind.
    let r = receiver(sp, bsdf, wo);
    let ns = r.n;
    light_samples(ctx, &r, s, delta_only, |light_index, inc, weight| {
        // The density of the light sample where a BSDF ray can find the same light.
        let f = match light_sample_density(ctx, &r, mis, light_index, inc) {
            Some(density) => mis.weighted_f(sp, bsdf, wo, inc.wi, density),
            None => bsdf.eval(&sp.frame, wo, inc.wi),
        };
        // A surface that only reflects takes no light from below its shading normal's
        // hemisphere (above the geometric surface, where smooth normals tilt): there neither
        // the gather rays nor the glossy ray could find it, so MIS could not weigh it, and a
        // light point across a crease of a smooth-shaded emitter, d² near zero, made a pixel 38
        // times its neighbours (the rough materials' frames, and pbrt's, exclude it too).
        // Rough glass takes light through itself.
        let cos = if bsdf.transmits() { inc.wi.dot(ns).abs() } else { inc.wi.dot(ns).max(0.0) };
        if f == Vec3::ZERO || cos == 0.0 {
            return;
        }
        let origin = offset_ray_origin(sp.p, sp.p_error, sp.frame.ng, inc.wi);
        let (direction, t_max) = shadow_segment(origin, inc);
        emit(ShadowRay { origin, direction, t_max, contribution: f * inc.value * (cos * weight) });
    });
}

/// Direct light at `sp` toward `wo` by light sampling alone: the unblocked shadow rays'
/// contributions summed.
pub fn direct_light(
    ctx: &Context,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    s: &Sampler,
    rays: &mut RayCounts,
) -> Vec3 {
    weighted_direct_light(ctx, sp, bsdf, wo, s, &Strategies::LightOnly, rays)
}

/// [`direct_light`] with emissive triangles weighted by MIS against `mis`: the light
/// sampling's share, to which the BSDF samples add theirs ([`super::mis::emission_found`]).
pub fn weighted_direct_light(
    ctx: &Context,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    s: &Sampler,
    mis: &Strategies,
    rays: &mut RayCounts,
) -> Vec3 {
    let scene = ctx.scene;
    attenuated_direct_light(ctx, |v| scene.filling_medium_toward(sp.tri, v), sp, bsdf, wo, s, false, mis, rays)
}

/// The shadow rays of [`direct_light_rays`] summed, each unblocked one's contribution times the
/// transmittance of the medium it travels in, `medium_toward` its direction (none: clear). The
/// photon mappers' media rule gives it [`crate::scene::Scene::filling_medium_toward`] (through
/// [`weighted_direct_light`] and [`delta_light`]), the path tracer's
/// [`crate::scene::Scene::medium_on_side`].
#[allow(clippy::too_many_arguments)]
pub fn attenuated_direct_light<'m>(
    ctx: &Context,
    medium_toward: impl Fn(Vec3) -> Option<&'m Medium>,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    s: &Sampler,
    delta_only: bool,
    mis: &Strategies,
    rays: &mut RayCounts,
) -> Vec3 {
    let mut sum = Vec3::ZERO;
    direct_light_rays(ctx, sp, bsdf, wo, s, delta_only, mis, |r| {
        sum += unblocked(ctx, medium_toward(r.direction), &r, rays);
    });
    sum
}

/// The fraction of a shadow ray's light `medium` lets through over its length (the whole ray
/// for a distant light: none where σ_t > 0).
#[must_use]
pub fn shadow_transmittance(medium: &Medium, ray: &ShadowRay) -> Vec3 {
    let length = if ray.t_max.is_finite() { ray.direction.length() * ray.t_max } else { f32::INFINITY };
    medium.transmittance(length)
}

/// What shadow ray `r` carries through `medium` (none: clear): its contribution times the
/// transmittance along it if nothing blocks it. No ray is traced where the medium lets
/// nothing through.
pub fn unblocked(ctx: &Context, medium: Option<&Medium>, r: &ShadowRay, rays: &mut RayCounts) -> Vec3 {
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

/// Direct light from the delta lights alone (point, spot, directional) at a surface that camera
/// paths pass by sampling (frosted glass, smooth rough metal): sampling never reaches a delta
/// light, and the other lights are found as emission along the sampled path.
pub fn delta_light(ctx: &Context, sp: &SurfacePoint, bsdf: &Bsdf, wo: Vec3, s: &Sampler, rays: &mut RayCounts) -> Vec3 {
    let scene = ctx.scene;
    let toward = |v| scene.filling_medium_toward(sp.tri, v);
    attenuated_direct_light(ctx, toward, sp, bsdf, wo, s, true, &Strategies::LightOnly, rays)
}
