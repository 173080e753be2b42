//! Ray continuation: a ray leaving a surface by sampling its BSDF, the chain of mirrors and
//! glass a camera-side ray follows to its first non-specular hit (or, in a medium filling the
//! scene, to where its free flight stops), and emission seen along a ray.

use super::Context;
use crate::geometry::offset::offset_ray_origin;
use crate::material::{Bsdf, Transport};
use crate::medium::{FreeFlight, Medium};
use crate::rng::Sampler;
use crate::scene::{Scene, SurfacePoint};
use crate::stats::RayCounts;
use glam::Vec3;

/// A ray leaving a surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounce {
    /// Origin, offset off the surface to the side the ray leaves on.
    pub origin: Vec3,
    /// Unit direction.
    pub dir: Vec3,
    /// Throughput factor f·|cos|/pdf (radiance transport).
    pub weight: Vec3,
    /// Sampled from a delta lobe (mirror or glass).
    pub delta: bool,
}

/// Samples the BSDF at `sp` toward `wo` with the numbers of bounce `bounce` (dims 0–2), for
/// radiance: the ray that continues the path, or `None` where the sample is absorbed.
#[must_use]
#[inline]
pub fn continue_ray(sp: &SurfacePoint, bsdf: &Bsdf, wo: Vec3, s: &Sampler, bounce: u32) -> Option<Bounce> {
    let u = [s.get(bounce, 0), s.get(bounce, 1), s.get(bounce, 2)];
    let bs = bsdf.sample(&sp.frame, wo, u, Transport::Radiance)?;
    Some(Bounce {
        origin: offset_ray_origin(sp.p, sp.p_error, sp.frame.ng, bs.wi),
        dir: bs.wi,
        weight: bs.weight,
        delta: bs.delta,
    })
}

/// Chain depth (specular bounces so far) from which camera-side chains play Russian roulette
/// ([`continue_chain`]). Below it every chain goes on: a camera ray seeing a mirror of
/// reflectance 0.95 would otherwise be killed one time in twenty, each kill adding noise (a
/// survivor's weight of 1/0.95) for no work saved; from it on, chains that lose light (mirrors
/// facing each other) end by roulette rather than at the `max_depth` safety cap.
pub const CHAIN_ROULETTE_DEPTH: u32 = 3;

/// [`continue_ray`] for a camera-side chain (camera, gather or glossy ray) at chain depth
/// `depth`: from [`CHAIN_ROULETTE_DEPTH`] on, Russian roulette on the bounce's weight without
/// refraction's radiance scale ([`Bsdf::radiance_scale`]): the chain survives with probability
/// min(1, its largest channel) — dimension 3 of `bounce` — and the survivor's weight is divided
/// by it (unbiased). Glass and water (weight 1) always go on; they end where the ray leaves
/// them.
#[must_use]
#[inline]
pub fn continue_chain(
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    s: &Sampler,
    bounce: u32,
    depth: u32,
) -> Option<Bounce> {
    let mut next = continue_ray(sp, bsdf, wo, s, bounce)?;
    if depth >= CHAIN_ROULETTE_DEPTH {
        let kept = (next.weight / bsdf.radiance_scale(&sp.frame, wo, next.dir)).max_element();
        if kept < 1.0 {
            if !(kept > 0.0) || s.get(bounce, 3) >= kept {
                return None;
            }
            next.weight /= kept;
        }
    }
    Some(next)
}

/// Where a chain through mirrors and glass ends: its first non-specular hit.
#[derive(Clone, Copy, Debug)]
pub struct ChainEnd {
    /// The hit.
    pub point: SurfacePoint,
    /// Direction of the segment arriving there.
    pub dir: Vec3,
    /// Throughput of the specular chain (1 without mirrors or glass on the way).
    pub beta: Vec3,
    /// The hit itself (its `t` is the length of the arriving segment; directions are unit).
    pub hit: crate::geometry::Hit,
    /// Mirrors and glass on the way (0: the ray's own first hit).
    pub bounces: u32,
}

/// How a chain through mirrors and glass ended.
#[derive(Clone, Copy, Debug)]
pub enum Chain {
    /// At its first non-specular hit.
    Hit(ChainEnd),
    /// Leaving the scene along `dir` with throughput `beta`.
    Escaped {
        /// Direction of the last segment.
        dir: Vec3,
        /// Throughput of the chain.
        beta: Vec3,
        /// Mirrors and glass on the way.
        bounces: u32,
    },
    /// Stopped in the medium filling the scene (its free flight scattered there).
    Medium(MediumEnd),
    /// Absorbed, ended by roulette, or cut at `max_depth` (counted in the context).
    Lost,
}

/// Where a chain's free flight stopped in the medium filling the scene.
#[derive(Clone, Copy, Debug)]
pub struct MediumEnd {
    /// The point.
    pub p: Vec3,
    /// Direction of the segment arriving there.
    pub dir: Vec3,
    /// Throughput of the chain, the free flight's weight (σ_s·T/pdf) included.
    pub beta: Vec3,
    /// The medium.
    pub medium: Medium,
    /// Mirrors and glass on the way.
    pub bounces: u32,
}

/// What free flight did on a segment ([`segment_flight`]).
#[derive(Clone, Copy, Debug)]
pub enum Flight {
    /// It reaches the segment's end; the throughput takes this weight (1 outside a medium).
    Pass(Vec3),
    /// It scatters at `p` in `medium`; the throughput takes `weight` (σ_s·T/pdf).
    Scatter {
        /// The medium.
        medium: Medium,
        /// Where.
        p: Vec3,
        /// The throughput factor.
        weight: Vec3,
    },
}

/// Free flight along a segment from `o` along unit `d` to `hit` (or to infinity) in the medium
/// filling the scene, if the segment lies in it ([`Scene::filling_medium`]), with dimensions 4
/// (the channel) and 5 (the distance) of `s`'s bounce `bounce`. Camera-side chains and photons
/// alike.
#[inline]
#[must_use]
pub fn segment_flight(
    scene: &Scene,
    o: Vec3,
    d: Vec3,
    hit: Option<&crate::geometry::Hit>,
    s: &Sampler,
    bounce: u32,
) -> Flight {
    let Some(medium) = scene.filling_medium(hit, d) else { return Flight::Pass(Vec3::ONE) };
    let length = hit.map_or(f32::INFINITY, |h| h.t);
    match medium.free_flight(length, s.get(bounce, 4), s.get(bounce, 5)) {
        FreeFlight::Scatter { distance, weight } => Flight::Scatter { medium: *medium, p: o + d * distance, weight },
        FreeFlight::Pass { weight } => Flight::Pass(weight),
    }
}

/// Follows a ray through mirrors and glass (at most `max_depth` bounces, sampling each with `s`
/// at bounce `first_bounce + depth`, [`continue_chain`]'s roulette included) to its first
/// non-specular hit, out of the scene, or, in a medium filling the scene, to where its free
/// flight stops ([`segment_flight`] with the same bounce). It also passes what photons pass
/// ([`Bsdf::photon_specular`]: frosted glass, smooth rough metal), sampling their BSDF: every
/// path ends where photons are stored, so the maps read there hold the light that came through.
pub fn follow_chain(
    ctx: &Context,
    mut o: Vec3,
    mut d: Vec3,
    s: &Sampler,
    first_bounce: u32,
    rays: &mut RayCounts,
) -> Chain {
    let scene = ctx.scene;
    let mut beta = Vec3::ONE;
    for depth in 0..=ctx.settings.max_depth {
        rays.gather += 1;
        let hit = scene.intersect(o, d, f32::INFINITY);
        match segment_flight(scene, o, d, hit.as_ref(), s, first_bounce + depth) {
            Flight::Pass(weight) => beta *= weight,
            Flight::Scatter { medium, p, weight } => {
                return Chain::Medium(MediumEnd { p, dir: d, beta: beta * weight, medium, bounces: depth });
            }
        }
        let Some(hit) = hit else {
            return Chain::Escaped { dir: d, beta, bounces: depth };
        };
        beta *= scene.interior_transmittance(&hit, d);
        let sp = scene.surface(&hit);
        let bsdf = &scene.bsdf(&sp);
        if !(bsdf.is_delta() || bsdf.photon_specular()) {
            return Chain::Hit(ChainEnd { point: sp, dir: d, beta, hit, bounces: depth });
        }
        if depth == ctx.settings.max_depth {
            ctx.cut();
            return Chain::Lost;
        }
        let Some(next) = continue_chain(&sp, bsdf, -d, s, first_bounce + depth, depth) else { return Chain::Lost };
        beta *= next.weight;
        (o, d) = (next.origin, next.dir);
    }
    Chain::Lost
}

/// [`follow_chain`]'s first non-specular hit; `None` if the chain escapes, is absorbed, or is
/// cut at `max_depth` (counted in `ctx`).
#[inline]
pub fn first_non_specular(
    ctx: &Context,
    o: Vec3,
    d: Vec3,
    s: &Sampler,
    first_bounce: u32,
    rays: &mut RayCounts,
) -> Option<ChainEnd> {
    match follow_chain(ctx, o, d, s, first_bounce, rays) {
        Chain::Hit(end) => Some(end),
        _ => None,
    }
}

/// Radiance emitted at `hit` toward `wo` (zero from its back face or a non-emitter; an
/// emission texture read at the hit's texture coordinates).
#[inline]
#[must_use]
pub fn emission_toward(scene: &Scene, hit: &crate::geometry::Hit, wo: Vec3) -> Vec3 {
    let tri = hit.tri as usize;
    let m = &scene.materials[scene.material[tri] as usize];
    if m.emission != Vec3::ZERO && wo.dot(scene.ng[tri]) > 0.0 {
        scene.emitted_at(hit.tri, hit.b)
    } else {
        Vec3::ZERO
    }
}
