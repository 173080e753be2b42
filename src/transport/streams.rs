//! The random-stream layout, in one place. Every number a render draws is
//! `Sampler::get(bounce, dimension)` of a stream keyed by (seed, domain, path index), or of a
//! sub-stream forked from one with a tag below. Both photon-mapping engines draw the same numbers
//! for the same decision, which is what makes their images agree; the path tracer shares the
//! camera jitter and BSDF bounces and has its own light stream ([`path_light`]).
//!
//! Camera path of sample `i` (`Domain::Camera`, index `i`):
//! - bounce 0, dims 0–1: the jitter inside the pixel;
//! - bounce `d + 1`, dims 0–2: the BSDF sample leaving the `d`-th hit (mirror, glass, or in the
//!   path tracer any surface); dim 3: the path tracer's Russian roulette;
//! - fork [`light`]`(d)`: direct light at the `d`-th hit, bounce `j` = light sample `j`
//!   (dim 0 picks the light, dims 1–2 the point on it);
//! - fork [`gather`]`(d)`: final gather at the `d`-th hit, bounce `g` dims 0–1 = direction of
//!   gather ray `g`; the ray's own specular chain forks [`gather_ray`]`(g)` and samples from bounce 0;
//!   where it lands near its origin (secondary gather) its stream forks [`SECONDARY_LIGHT`] for
//!   direct light there and [`SECONDARY_GATHER`] for its one more gather ray, drawn as gather ray 0
//!   of a one-ray final gather;
//! - fork [`glossy`]`(d)`: the glossy lobe at the `d`-th hit, bounce 0 dims 0–1 = its direction;
//!   its specular chain samples from bounce 1; direct light where it lands forks
//!   [`GLOSSY_HIT_LIGHT`];
//! - where a gather ray (its own stream) or the glossy ray lands on a narrow lobe, that lobe's
//!   ray forks [`LANDING_LOBE`] from the landing ray's stream.
//!
//! Photon path `i` (`Domain::GlobalPhoton` or `Domain::CausticPhoton`, index `i`): bounce 0
//! dim 0 picks the light, dims 1–4 sample its emission; bounce `b + 1` dims 0–2 sample the BSDF
//! at the `b`-th hit and dim 3 decides Russian roulette.
//!
//! The path tracer's direct light at depth `d` forks [`path_light`]`(d)`. In a medium, the
//! free flight of the path tracer's segment `d` (the camera ray is segment 0) draws bounce `d`
//! dims 4–5 (the channel, the distance); where it scatters, the phase-function sample that
//! continues the path draws bounce `d + 1` dims 0–1, and its in-scattered light forks
//! [`path_light`]`(d)`. The photon mappers' camera segment `d` draws its marching points'
//! channel and stratum at [`segment`]`(d)` dims 4–5, and point `i` its single scattering from
//! [`light`]`(d)` forked by `i` (the phase sample at bounce 0, dims 3–4); a gather, glossy or lobe ray's
//! chain segment `c` draws dims 4–5 of the bounce its chain samples at `c` draws dims 0–3 of.
//! A photon's segment leading to its `b`-th vertex draws bounce `b + 1` dims 4–5; where it
//! scatters in the medium, the phase function draws bounce `b + 1` dims 0–1 and Russian
//! roulette dim 3, as at a surface.

/// Tags of the per-hit sub-streams of a camera path (added to the hit's depth).
const GATHER: u64 = 1 << 32;
const GLOSSY: u64 = 2 << 32;
const LIGHT: u64 = 3 << 32;

/// Bounce of a camera stream whose dimensions 0–1 jitter the sample in its pixel.
pub const JITTER_BOUNCE: u32 = 0;
/// Bounce at which a glossy ray's specular chain starts drawing (bounce 0 chose its direction).
pub const GLOSSY_CHAIN_BOUNCE: u32 = 1;
/// Bounce at which a camera path's specular chain starts drawing (bounce 0 jittered it).
pub const CAMERA_CHAIN_BOUNCE: u32 = 1;
/// Bounce at which a gather ray's own stream starts drawing for its specular chain.
pub const GATHER_CHAIN_BOUNCE: u32 = 0;
/// Fork of a glossy ray's stream for the direct light where it lands.
pub const GLOSSY_HIT_LIGHT: u64 = 7;
/// Fork of a gather ray's stream for direct light where it lands near its origin.
pub const SECONDARY_LIGHT: u64 = 8;
/// Fork of a gather ray's stream for the one-ray gather where it lands near its origin.
pub const SECONDARY_GATHER: u64 = 9;

/// Fork of a gather or glossy ray's stream for the ray of the narrow lobe it landed on
/// (`super::lobe`), drawn as a glossy ray: bounce 0 its direction, its chain from
/// [`GLOSSY_CHAIN_BOUNCE`].
pub const LANDING_LOBE: u64 = 10;

/// Fork tag of direct light at a camera path's `depth`-th hit.
#[must_use]
pub const fn light(depth: u32) -> u64 {
    LIGHT + depth as u64
}

/// Fork tag of the final gather at a camera path's `depth`-th hit.
#[must_use]
pub const fn gather(depth: u32) -> u64 {
    GATHER + depth as u64
}

/// Fork tag of gather ray `g`'s own stream (forked from the gather stream).
#[must_use]
pub const fn gather_ray(g: u32) -> u64 {
    g as u64
}

/// Fork tag of the glossy lobe's ray at a camera path's `depth`-th hit.
#[must_use]
pub const fn glossy(depth: u32) -> u64 {
    GLOSSY + depth as u64
}

/// Bounce of a camera stream whose dimensions 4–5 draw the path's segment `depth` in a medium
/// (the camera ray is segment 0): the bounce whose dimensions 0–3 the chain's sample leaving
/// hit `depth − 1` used. The path tracer's free flight and the photon mappers' marching points
/// draw there.
#[must_use]
pub const fn segment(depth: u32) -> u32 {
    depth
}

/// Fork tag of the path tracer's direct light at depth `depth`.
#[must_use]
pub const fn path_light(depth: u32) -> u64 {
    ((depth as u64) << 32) | 0xd1
}
