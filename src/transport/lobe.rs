//! Narrow lobes where gather and glossy rays land. A photon-map estimate weighs each photon by
//! f(wo, wi), and light sampling each sample by f too; on a near-mirror coat (the Modern Hall's
//! floor tiles, a GGX coat of α 0.01) f in the peak is about 3 000 per steradian, so one photon
//! or one light sample arriving there makes a pixel a hundred times its neighbours. Where a
//! gather or glossy ray lands on such a surface ([`Bsdf::narrow_lobe`]) the maps are read with
//! the base alone and the lobe sends one ray of its own, drawn from it as the camera hit's
//! glossy ray is ([`super::gather::glossy_ray`]): Jensen's rule that specular-like reflection
//! is traced, not estimated, kept one bounce further down. The lobe ray reads the maps where it
//! lands ([`map_radiance`], as a gather ray does) and adds the emission it finds.
//!
//! What that emission counts depends on what the landing did. Where a glossy ray landed, light
//! sampling ran with the whole BSDF, so the emission the lobe ray hits straight away is weighed
//! against those samples (MIS for the landing point's receiver), while emission reached through
//! mirrors and glass — the coat's caustics, which the base-only caustic estimate no longer
//! reads — is whole. Where a gather ray landed nothing sampled the lights: everything the lobe
//! ray finds is whole, the environment too where it escapes.
//!
//! Reads the scene and the maps; writes radiance and its bias. Both photon-mapping engines call
//! these functions (the wavefront engine as a lane kind of its own), so their images agree.

use super::estimate::{base_radiance, map_radiance};
use super::gather::{glossy_density, glossy_ray};
use super::mis::{emission_found, receiver, sky_found, Strategies};
use super::specular::{emission_toward, follow_chain, Chain, ChainEnd};
use super::{streams, Context};
use crate::geometry::Hit;
use crate::material::Bsdf;
use crate::photon_map::Nearest;
use crate::rng::Sampler;
use crate::scene::{Receiver, SurfacePoint};
use crate::stats::RayCounts;
use glam::Vec3;

/// Radiance a ray found and the estimated bias of the density estimates in it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Found {
    /// Radiance.
    pub radiance: Vec3,
    /// Its bias ([`crate::photon_map::Estimate::bias`]).
    pub bias: Vec3,
}

/// The density a narrow lobe's ray `density` field carries: the lobe's density toward `wi`
/// under the landing's light sampling `mis` where a glossy ray landed (`lit`), ∞ where a gather
/// ray did (nothing to weigh against: the ray counts all it finds).
#[must_use]
#[inline]
pub fn lobe_density(
    ray: &super::specular::Bounce,
    lit: Option<&Strategies>,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
) -> f32 {
    match lit {
        Some(mis) => glossy_density(ray, mis, sp, bsdf, wo),
        None => f32::INFINITY,
    }
}

/// Emission a ray from a narrow lobe, of density `density` (from [`lobe_density`]), finds at
/// `hit`, arriving along `dir` after `bounces` mirrors and glass: weighed against the light
/// samples at its origin (receiver `from`) where it is hit straight away and the density is
/// finite, whole otherwise (the origin's caustic estimate reads its base alone).
#[must_use]
#[inline]
pub fn lobe_emission(ctx: &Context, from: &Receiver, hit: &Hit, dir: Vec3, bounces: u32, density: f32) -> Vec3 {
    if bounces == 0 && density.is_finite() {
        emission_found(ctx, from, hit, dir, density)
    } else {
        emission_toward(ctx.scene, hit, -dir)
    }
}

/// The environment and the sun a ray from a narrow lobe, of density `density`, finds leaving
/// the scene along `dir` after `bounces` mirrors and glass: all of it through mirrors and glass
/// (the origin's caustic estimate reads its base alone) or where nothing sampled them at its
/// origin (∞: a gather ray's landing, a smooth coat's mirror direction); where light sampling
/// ran at its origin (receiver `from`), weighed against it.
#[must_use]
#[inline]
pub fn lobe_escape(ctx: &Context, from: &Receiver, dir: Vec3, bounces: u32, density: f32) -> Vec3 {
    let scene = ctx.scene;
    if !scene.has_background() {
        Vec3::ZERO
    } else if bounces == 0 && density.is_finite() {
        sky_found(ctx, from, dir, density)
    } else {
        scene.background(dir)
    }
}

/// The narrow lobe's ray at `y` (on `bsdf`, seen from `wo`), drawn from `s` (the landing ray's
/// stream forked [`streams::LANDING_LOBE`]), followed through mirrors and glass: the emission it
/// finds and the maps' radiance where it lands, times its weight. `lit` is the landing's light
/// sampling (a glossy ray's landing) or `None` (a gather ray's).
#[allow(clippy::too_many_arguments)]
pub fn lobe_ray(
    ctx: &Context,
    y: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    s: &Sampler,
    lit: Option<&Strategies>,
    rays: &mut RayCounts,
    scratch: &mut Nearest,
) -> Found {
    let Some(ray) = glossy_ray(y, bsdf, wo, s) else { return Found::default() };
    let density = lobe_density(&ray, lit, y, bsdf, wo);
    match follow_chain(ctx, ray.origin, ray.dir, s, streams::GLOSSY_CHAIN_BOUNCE, rays) {
        Chain::Hit(end) => {
            let w = ray.weight * end.beta;
            let e = lobe_emission(ctx, &receiver(y, bsdf, wo), &end.hit, end.dir, end.bounces, density);
            let m = map_radiance(ctx, &end.point, &ctx.scene.bsdf(&end.point), -end.dir, scratch).finish(ctx);
            Found { radiance: w * (e + m.radiance), bias: w * m.bias }
        }
        Chain::Escaped { dir, beta, bounces } => {
            let sky = lobe_escape(ctx, &receiver(y, bsdf, wo), dir, bounces, density);
            Found { radiance: ray.weight * beta * sky, bias: Vec3::ZERO }
        }
        Chain::Medium(end) => {
            Found { radiance: ray.weight * super::volume::gather_in_medium(ctx, &end, rays, scratch), bias: Vec3::ZERO }
        }
        Chain::Lost => Found::default(),
    }
}

/// Radiance leaving a gather ray's landing `end` toward the ray (drawn from stream `s`): the
/// maps' estimate there ([`map_radiance`]), or on a narrow lobe the base's estimate
/// ([`base_radiance`]) and the lobe's own ray ([`lobe_ray`], nothing sampled the lights there).
pub fn gather_landing(
    ctx: &Context,
    end: &ChainEnd,
    s: &Sampler,
    rays: &mut RayCounts,
    scratch: &mut Nearest,
) -> Found {
    let (y, wo) = (&end.point, -end.dir);
    let bsdf = &ctx.scene.bsdf(y);
    if !bsdf.narrow_lobe() {
        let e = map_radiance(ctx, y, bsdf, wo, scratch).finish(ctx);
        return Found { radiance: e.radiance, bias: e.bias };
    }
    let base = base_radiance(ctx, y, bsdf, wo, scratch).finish(ctx);
    let lobe = lobe_ray(ctx, y, bsdf, wo, &s.fork(streams::LANDING_LOBE), None, rays, scratch);
    Found { radiance: base.radiance + lobe.radiance, bias: base.bias + lobe.bias }
}
