//! Multiple importance sampling of direct light (Veach 1997, ch. 9). An emissive triangle
//! lights a non-specular point by two kinds of sample: light sampling's shadow rays
//! ([`super::direct`]) and the rays the BSDF sends out anyway — at the photon mapper's camera
//! hit the final-gather rays over the diffuse base and the glossy ray over the lobe, in the path
//! tracer the next bounce. Each kind weighs what it finds by the power heuristic against the
//! other kinds' densities for the same direction, so every emitter is counted once in
//! expectation, and a sample one kind draws badly (a light point across a crease of the
//! emitter, its d² near zero; a light point in a near-mirror lobe's peak) is carried by the
//! kind that draws it well: a weighted light sample is at most f·L·cos / (2·p_bsdf), bounded
//! where the BSDF's own sampling is.
//!
//! The weights come from densities (samples × pdf per steradian): light sampling's is
//! `light_samples × pmf(light | receiver) × pdf(direction)` ([`light_density`]: the light
//! tree's or the power's pick, and 1/Ω or d²/(A·cos θ_light) for the point on it); a BSDF
//! kind's is given by [`Strategies`]; the environment's and a sun's are the same pick probability
//! times the density of their direction ([`environment_density`], [`sun_density`]). Both depend on the receiver — the shading point and its
//! normal — so a BSDF sample's weight is computed for the receiver it left. Only emissive triangles whose surface ends a camera-side chain
//! (neither mirror, glass nor what photons pass as specular) are weighed: those are the ones a
//! BSDF ray can find; and the environment and the suns, which a BSDF ray finds where it leaves
//! the scene straight away.
//!
//! Reads the scene's lights and the BSDF's pdfs; writes weights and weighted emission. Every
//! engine weighs through these functions, so their images agree.

use super::Context;
use crate::geometry::Hit;
use crate::material::Bsdf;
use crate::scene::light::{area_light_pdf, Light};
use crate::scene::{Receiver, Scene, SurfacePoint};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// The BSDF samples that can find an emitter at a point, besides light sampling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Strategies {
    /// None: light sampling carries all direct light, unweighted (a secondary vertex of the
    /// photon mapper without a narrow lobe, whose rays read the maps instead; or MIS turned
    /// off).
    LightOnly,
    /// The photon mapper's camera hit: `gather` cosine-weighted final-gather rays over the
    /// diffuse base ([`Bsdf::eval_base`]) and, with `glossy`, the glossy ray over the lobe
    /// ([`Bsdf::eval_lobe`]); at a glossy ray's landing on a narrow lobe, that lobe's ray alone.
    Split {
        /// Final-gather rays (0 where none are sent).
        gather: u32,
        /// A glossy ray is sent.
        glossy: bool,
    },
    /// The path tracer: one sample of the whole BSDF ([`Bsdf::pdf`]).
    Whole,
}

impl Strategies {
    /// What a photon-mapping camera path sends at its non-specular hit on `bsdf`: final-gather
    /// rays when final gathering is on and the surface has a diffuse part, the glossy ray on a
    /// glossy material; light sampling alone when `mis = false`.
    #[must_use]
    pub fn at_camera_hit(ctx: &Context, bsdf: &Bsdf) -> Self {
        if !ctx.settings.mis {
            return Strategies::LightOnly;
        }
        let gather =
            if ctx.effects.final_gather.on && bsdf.diffuse() != Vec3::ZERO { ctx.settings.gather_rays } else { 0 };
        Strategies::Split { gather, glossy: bsdf.has_glossy_lobe() }
    }

    /// What the landing point of a glossy ray sends on `bsdf`: the lobe's own ray where the lobe
    /// is narrow ([`Bsdf::narrow_lobe`], `super::lobe`); light sampling alone elsewhere, or with
    /// `mis = false`.
    #[must_use]
    pub fn at_landing(ctx: &Context, bsdf: &Bsdf) -> Self {
        if ctx.settings.mis && bsdf.narrow_lobe() {
            Strategies::Split { gather: 0, glossy: true }
        } else {
            Strategies::LightOnly
        }
    }

    /// Density of the final-gather rays toward `wi` (rays × pdf); 0 without them. Inline: out of
    /// line it cost `spawn_gather_rays` 13–21 % (a call per gather ray).
    #[inline]
    #[must_use]
    pub fn gather_density(&self, sp: &SurfacePoint, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            Strategies::Split { gather, .. } if gather > 0 => gather as f32 * gather_pdf(sp, wo, wi),
            _ => 0.0,
        }
    }

    /// Density of the glossy ray toward `wi`; 0 without it.
    #[must_use]
    pub fn glossy_density(&self, sp: &SurfacePoint, bsdf: &Bsdf, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            Strategies::Split { glossy: true, .. } => bsdf.glossy_pdf(&sp.frame, wo, wi),
            _ => 0.0,
        }
    }

    /// f(wo, wi) for a light sample of density `light` toward `wi`, each part weighted against
    /// the BSDF kind that samples it.
    #[must_use]
    pub fn weighted_f(&self, sp: &SurfacePoint, bsdf: &Bsdf, wo: Vec3, wi: Vec3, light: f32) -> Vec3 {
        let frame = &sp.frame;
        match *self {
            Strategies::LightOnly => bsdf.eval(frame, wo, wi),
            Strategies::Split { .. } => {
                let base = bsdf.eval_base(frame, wo, wi) * power_heuristic(light, self.gather_density(sp, wo, wi));
                let lobe =
                    bsdf.eval_lobe(frame, wo, wi) * power_heuristic(light, self.glossy_density(sp, bsdf, wo, wi));
                base + lobe
            }
            Strategies::Whole => bsdf.eval(frame, wo, wi) * power_heuristic(light, bsdf.pdf(frame, wo, wi)),
        }
    }
}

/// The pdf of a final-gather ray toward `wi` ([`super::gather::gather_rays`]): cos θ/π about
/// the shading normal on `wo`'s side; 0 below the geometric surface, where no ray is sent.
#[must_use]
#[inline]
pub fn gather_pdf(sp: &SurfacePoint, wo: Vec3, wi: Vec3) -> f32 {
    let (ng, ns) = sp.frame.oriented(wo);
    if wi.dot(ng) <= 0.0 {
        return 0.0;
    }
    wi.dot(ns).max(0.0) * FRAC_1_PI
}

/// The power heuristic (β = 2) weight of a sample drawn with density `f` against another kind
/// of density `g`: f²/(f² + g²), computed as 1/(1 + (g/f)²) so that huge densities (a light
/// seen edge-on) give 0 or 1, not ∞/∞.
#[must_use]
#[inline]
pub fn power_heuristic(f: f32, g: f32) -> f32 {
    if !(f > 0.0) {
        return 0.0;
    }
    let r = g / f;
    let w = 1.0 / (1.0 + r * r);
    if w.is_nan() {
        0.0
    } else {
        w
    }
}

/// The light of emissive triangle `tri` if its emission is weighed by MIS: its index in the
/// scene's area-light distribution, for an emitter whose surface ends camera-side chains (a
/// BSDF ray that hits it stops there and can count it).
#[must_use]
#[inline]
pub fn weighed_light(scene: &Scene, tri: u32) -> Option<usize> {
    let bsdf = &scene.materials[scene.material[tri as usize] as usize].bsdf;
    if bsdf.is_delta() || bsdf.photon_specular() {
        return None;
    }
    scene.area_light_of(tri)
}

/// The receiver light sampling works for at `sp` on `bsdf`, seen from `wo`: its point, its
/// shading normal on `wo`'s side, and whether it takes light through itself.
#[must_use]
#[inline]
pub fn receiver(sp: &SurfacePoint, bsdf: &Bsdf, wo: Vec3) -> Receiver {
    let (_, ns) = sp.frame.oriented(wo);
    Receiver { p: sp.p, n: ns, two_sided: bsdf.transmits() }
}

/// Light sampling's density at receiver `r` toward a point of emissive triangle `tri` (light
/// `light` of the scene, see [`weighed_light`]) at `distance` along unit `wi`: `light_samples`
/// × the light's pick probability there ([`Scene::light_pmf`]) × the density per steradian of
/// its point ([`area_light_pdf`]: by solid angle or by area, as the sample was drawn).
#[must_use]
#[inline]
pub fn light_density(ctx: &Context, r: &Receiver, light: usize, tri: u32, distance: f32, wi: Vec3) -> f32 {
    let scene = ctx.scene;
    let pmf = scene.light_pmf(ctx.settings.light_sampler, r, light as u32);
    if !(pmf > 0.0) {
        return 0.0;
    }
    ctx.settings.light_samples as f32 * pmf * area_light_pdf(&scene.triangle(tri), r.p, wi, distance)
}

/// Light sampling's density at receiver `r` toward the environment along unit `wi`:
/// `light_samples` × the environment's pick probability there × the density of its direction
/// (half cosine-weighted about the receiver's normal, half by the map or, where the scene has
/// portals, through them: [`Scene::sample_incident`]). 0 without an environment.
#[must_use]
#[inline]
pub fn environment_density(ctx: &Context, r: &Receiver, wi: Vec3) -> f32 {
    let Some(env) = &ctx.scene.environment else { return 0.0 };
    density_with_map_pdf(ctx, r, wi, env.sampling_pdf(r.p, wi, || env.pdf(wi)))
}

/// [`environment_density`] given the density of its second half toward `wi` (the map's, read
/// with its radiance in one texel lookup, [`crate::scene::Environment::radiance_pdf`], or the
/// portals': [`crate::scene::Environment::sampling_pdf`]).
#[inline]
fn density_with_map_pdf(ctx: &Context, r: &Receiver, wi: Vec3, map_pdf: f32) -> f32 {
    let scene = ctx.scene;
    // The environment is the last light.
    let pmf = scene.light_pmf(ctx.settings.light_sampler, r, scene.lights.len() as u32 - 1);
    if !(pmf > 0.0) {
        return 0.0;
    }
    let pdf = 0.5 * wi.dot(r.n).max(0.0) * FRAC_1_PI + 0.5 * map_pdf;
    ctx.settings.light_samples as f32 * pmf * pdf
}

/// Light sampling's density at receiver `r` toward sun `light` (index in the scene's lights),
/// for a direction inside its disk: `light_samples` × its pick probability × 1/(2π(1 − cos θ))
/// (uniform in its cone, [`crate::scene::light::Light::sample_incident`]).
#[must_use]
#[inline]
pub fn sun_density(ctx: &Context, r: &Receiver, light: u32) -> f32 {
    let scene = ctx.scene;
    let Light::Sun { one_minus_cos, .. } = scene.lights[light as usize] else { return 0.0 };
    let pmf = scene.light_pmf(ctx.settings.light_sampler, r, light);
    ctx.settings.light_samples as f32 * pmf / (2.0 * std::f32::consts::PI * one_minus_cos)
}

/// The environment and the suns a BSDF-sampled ray from receiver `r` finds leaving the scene
/// along unit `d` (no mirror or glass before), each weighted against its light samples;
/// `density` is the BSDF kind's density for `d`.
#[must_use]
pub fn sky_found(ctx: &Context, r: &Receiver, d: Vec3, density: f32) -> Vec3 {
    if !(density > 0.0) {
        return Vec3::ZERO;
    }
    let scene = ctx.scene;
    let mut sum = Vec3::ZERO;
    if let Some(env) = &scene.environment {
        let (l, map_pdf) = env.radiance_pdf(d);
        if l != Vec3::ZERO {
            let second = env.sampling_pdf(r.p, d, || map_pdf);
            sum += l * power_heuristic(density, density_with_map_pdf(ctx, r, d, second));
        }
    }
    for &i in scene.suns() {
        let l = scene.lights[i as usize].radiance_at_infinity(d);
        if l != Vec3::ZERO {
            sum += l * power_heuristic(density, sun_density(ctx, r, i));
        }
    }
    sum
}

/// Emission a BSDF-sampled ray from receiver `r` finds at its first hit `hit` (no mirror or
/// glass before it), arriving along unit `d`, weighted against light sampling; `density` is the
/// BSDF kind's density for `d` at the ray's origin. Zero from a back face, a non-emitter, an emitter that
/// light sampling does not weigh, or with no density.
#[must_use]
pub fn emission_found(ctx: &Context, r: &Receiver, hit: &Hit, d: Vec3, density: f32) -> Vec3 {
    if !(density > 0.0) {
        return Vec3::ZERO;
    }
    let scene = ctx.scene;
    let Some(light) = weighed_light(scene, hit.tri) else { return Vec3::ZERO };
    let e = super::specular::emission_toward(scene, hit, -d);
    if e == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let p_light = light_density(ctx, r, light, hit.tri, hit.t, d);
    e * power_heuristic(density, p_light)
}
