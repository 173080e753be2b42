//! Direct light by light sampling (Jensen's first term): at a non-specular point, every delta
//! light once and `light_samples` area-light samples chosen by power, each a shadow ray that
//! carries its contribution if nothing blocks it.

use super::Context;
use crate::geometry::offset::offset_ray_origin;
use crate::material::Bsdf;
use crate::rng::Sampler;
use crate::scene::SurfacePoint;
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

/// The shadow rays of direct light at `sp` toward `wo`: every delta light once, then (unless
/// `delta_only`) `light_samples` area-light samples chosen by power. Lights that cannot contribute (behind
/// the surface, back faces, outside a spot cone) get no ray.
pub fn direct_light_rays(
    ctx: &Context,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    s: &Sampler,
    delta_only: bool,
    mut emit: impl FnMut(ShadowRay),
) {
    let scene = ctx.scene;
    let (_, ns) = sp.frame.oriented(wo);
    let mut add = |light_index: u32, u: [f32; 2], weight: f32| {
        let light = &scene.lights[light_index as usize];
        let Some(inc) = scene.sample_incident(light, sp.p, ns, u) else { return };
        let f = bsdf.eval(&sp.frame, wo, inc.wi);
        let cos = inc.wi.dot(ns).abs();
        if f == Vec3::ZERO || cos == 0.0 {
            return;
        }
        let origin = offset_ray_origin(sp.p, sp.p_error, sp.frame.ng, inc.wi);
        let (direction, t_max) = match inc.point {
            // The light point moved off its emitter toward the shading point, out of its error
            // box, as the origin is off the surface (pbrt-v4's spawn-ray-to between two
            // surface points).
            Some((q, n)) => (offset_ray_origin(q, inc.point_error, n, -inc.wi) - origin, 1.0 - SHADOW_SHORTEN),
            None => (inc.wi, f32::INFINITY),
        };
        emit(ShadowRay { origin, direction, t_max, contribution: f * inc.value * (cos * weight) });
    };
    for &li in &scene.delta_lights {
        add(li, [0.5, 0.5], 1.0);
    }
    if delta_only {
        return;
    }
    if let Some(dist) = &scene.area_power {
        let n = ctx.settings.light_samples;
        for j in 0..n {
            let pick = dist.sample(s.get(j, 0));
            let pmf = dist.pmf(pick) as f32;
            add(scene.area_lights[pick], [s.get(j, 1), s.get(j, 2)], 1.0 / (pmf * n as f32));
        }
    }
}

/// Direct light at `sp` toward `wo`: the unblocked shadow rays' contributions summed.
pub fn direct_light(
    ctx: &Context,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    s: &Sampler,
    rays: &mut RayCounts,
) -> Vec3 {
    let mut sum = Vec3::ZERO;
    direct_light_rays(ctx, sp, bsdf, wo, s, false, |r| {
        rays.shadow += 1;
        if !ctx.scene.occluded(r.origin, r.direction, r.t_max) {
            sum += r.contribution;
        }
    });
    sum
}

/// Direct light from the delta lights alone (point, spot, directional) at a surface that camera
/// paths pass by sampling (frosted glass, smooth rough metal): sampling never reaches a delta
/// light, and the other lights are found as emission along the sampled path.
pub fn delta_light(ctx: &Context, sp: &SurfacePoint, bsdf: &Bsdf, wo: Vec3, s: &Sampler, rays: &mut RayCounts) -> Vec3 {
    let mut sum = Vec3::ZERO;
    direct_light_rays(ctx, sp, bsdf, wo, s, true, |r| {
        rays.shadow += 1;
        if !ctx.scene.occluded(r.origin, r.direction, r.t_max) {
            sum += r.contribution;
        }
    });
    sum
}
