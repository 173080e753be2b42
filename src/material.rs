//! Materials and their BSDFs: Lambertian, glossy (Lambertian + normalised Phong lobe), perfect
//! mirror and smooth dielectric, each with evaluate, pdf and sample.
//!
//! Directions are world-space unit vectors pointing away from the surface: `wo` toward the viewer
//! (or where the photon came from), `wi` toward the next vertex. Opaque materials are two-sided:
//! the frame is flipped to the side of `wo`. The dielectric uses the unflipped normal to know
//! whether the ray enters or leaves.

use crate::microfacet;
pub use crate::optics::{fresnel_dielectric, reflect, refract};
use crate::sampling::{cosine_hemisphere, Frame};
use crate::texture::Texture;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;
use std::sync::Arc;

/// What flows along the path: radiance (camera paths) or power (photons). Refraction scales
/// radiance by (η_wo / η_wi)², never power.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    /// Camera paths carry radiance.
    Radiance,
    /// Photon paths carry power.
    Power,
}

/// The scattering part of a material.
#[derive(Clone, Copy, Debug, PartialEq)]
// Each variant's doc names and explains its fields.
#[allow(missing_docs)]
pub enum Bsdf {
    /// Lambertian reflection with albedo `kd`.
    Lambert { kd: Vec3 },
    /// Lambertian `kd` plus a normalised modified-Phong lobe `ks·(n+2)/(2π)·cos^n α` around the mirror
    /// direction (Lafortune & Willems 1994); kd + ks ≤ 1 per channel, so it never gains energy.
    Glossy { kd: Vec3, ks: Vec3, exponent: f32 },
    /// Perfect mirror with reflectance `ks`.
    Mirror { ks: Vec3 },
    /// Smooth clear dielectric with index of refraction `ior` (relative to the outside, the side
    /// the geometric normal points to), exact Fresnel.
    Glass { ior: f32 },
    /// Rough conductor ([`crate::microfacet`]): GGX of width `alpha` (roughness²), Schlick's
    /// Fresnel from the normal-incidence reflectance `ks`.
    RoughConductor { ks: Vec3, alpha: f32 },
    /// Rough (frosted) clear dielectric: GGX of width `alpha`, exact Fresnel, reflection and
    /// refraction through the microfacets; `ior` as for [`Bsdf::Glass`].
    RoughDielectric { ior: f32, alpha: f32 },
    /// Rough plastic: a GGX dielectric coat (index `ior`, width `alpha`) over a Lambertian base
    /// `kd` ([`microfacet::plastic_eval`]).
    RoughPlastic { kd: Vec3, ior: f32, alpha: f32 },
}

/// The GGX α below which a rough conductor acts as a mirror for photons (roughness 0.3): its
/// photons pass on as specular, so its caustics go into the caustic map, instead of being
/// stored on it. Rough dielectrics always pass photons on (a photon stored on frosted glass
/// could never light what lies behind it). The effects plan says which surfaces are which.
pub const PHOTON_SPECULAR_ALPHA: f32 = 0.09;

/// A named material: scattering plus emitted radiance from the front face.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name as in the MTL file or scene file.
    pub name: String,
    /// Scattering.
    pub bsdf: Bsdf,
    /// Emitted radiance from the front (counter-clockwise) face; zero for non-emitters.
    pub emission: Vec3,
    /// Image textures that replace the constant colours where the surface has them.
    pub maps: Maps,
}

/// A material's image textures: each, when present, replaces its constant colour at every
/// point by the texture's value at the point's texture coordinates.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Maps {
    /// Diffuse albedo (MTL `map_Kd`): replaces `kd`.
    pub kd: Option<Arc<Texture>>,
    /// Specular reflectance (MTL `map_Ks`): replaces `ks` of glossy and mirror materials.
    pub ks: Option<Arc<Texture>>,
    /// Roughness (MTL `map_Pr`, a linear data map read from its red channel): replaces the rough
    /// materials' roughness, within the material's photon class ([`Material::bsdf_at`]).
    pub roughness: Option<Arc<Texture>>,
    /// Emitted radiance (MTL `map_Ke`): multiplies the emission of an emitter.
    pub ke: Option<Arc<Texture>>,
    /// Metalness (MTL `map_Pm`, data, red channel): where it is at least ½ a rough material is a
    /// rough conductor of the base colour, elsewhere a rough plastic of it ([`Material::bsdf_at`]).
    pub metallic: Option<Arc<Texture>>,
}

impl Maps {
    /// True when the material has no texture.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.kd.is_none()
            && self.ks.is_none()
            && self.roughness.is_none()
            && self.ke.is_none()
            && self.metallic.is_none()
    }
}

impl Material {
    /// A material without textures.
    #[must_use]
    pub fn new(name: impl Into<String>, bsdf: Bsdf, emission: Vec3) -> Material {
        Material { name: name.into(), bsdf, emission, maps: Maps::default() }
    }

    /// The radiance emitted at texture coordinates `uv` from the front face: the constant
    /// emission times the emission texture's value there (an 8-bit texture holds colours up to 1;
    /// `Ke` scales them, as the MTL spec multiplies a map by its constant).
    #[inline]
    #[must_use]
    pub fn emission_at(&self, uv: Vec2) -> Vec3 {
        match &self.maps.ke {
            Some(t) => self.emission * t.lookup(uv),
            None => self.emission,
        }
    }

    /// The scattering at texture coordinates `uv`: the constant BSDF with its textured colours
    /// replaced. Albedos are kept within energy conservation as the MTL mapping keeps the
    /// constants: a Lambertian or mirror colour at most 1, a glossy `kd + ks` at most 1 per
    /// channel (both scaled down together). A roughness map sets α = roughness² but keeps a rough
    /// conductor on its constant roughness's side of [`PHOTON_SPECULAR_ALPHA`]: whether photons
    /// pass a material is decided per material, so both engines route it alike.
    #[inline]
    #[must_use]
    pub fn bsdf_at(&self, uv: Vec2) -> Bsdf {
        if self.maps.is_empty() {
            return self.bsdf;
        }
        let kd_at = |kd: Vec3| self.maps.kd.as_ref().map_or(kd, |t| t.lookup(uv));
        let ks_at = |ks: Vec3| self.maps.ks.as_ref().map_or(ks, |t| t.lookup(uv));
        let alpha_at = |alpha: f32| {
            self.maps.roughness.as_ref().map_or(alpha, |t| microfacet::alpha_of(t.lookup(uv).x.clamp(0.0, 1.0)))
        };
        if let Some(m) = &self.maps.metallic {
            // The PBR extension's metallic workflow, per point: the base colour makes a metal's
            // reflectance or a plastic's base. Metal parts store photons (α at least
            // PHOTON_SPECULAR_ALPHA), as plastic does, so the material's photon class is one.
            let (base, ior, alpha) = match self.bsdf {
                Bsdf::RoughPlastic { kd, ior, alpha } => (kd_at(kd), ior, alpha_at(alpha)),
                Bsdf::RoughConductor { ks, alpha } => (ks_at(ks), 1.5, alpha_at(alpha)),
                other => return other,
            };
            let base = base.min(Vec3::ONE);
            return if m.lookup(uv).x >= 0.5 {
                Bsdf::RoughConductor { ks: base, alpha: alpha.max(PHOTON_SPECULAR_ALPHA) }
            } else {
                Bsdf::RoughPlastic { kd: base, ior, alpha }
            };
        }
        match self.bsdf {
            Bsdf::Lambert { kd } => Bsdf::Lambert { kd: kd_at(kd).min(Vec3::ONE) },
            Bsdf::Glossy { kd, ks, exponent } => {
                let (kd, ks) = (kd_at(kd), ks_at(ks));
                let sum = (kd + ks).max_element();
                let scale = if sum > 1.0 { 1.0 / sum } else { 1.0 };
                Bsdf::Glossy { kd: kd * scale, ks: ks * scale, exponent }
            }
            Bsdf::Mirror { ks } => Bsdf::Mirror { ks: ks_at(ks).min(Vec3::ONE) },
            Bsdf::RoughConductor { ks, alpha } => {
                let a = alpha_at(alpha);
                // The same photon class as the constant roughness.
                let a = if alpha < PHOTON_SPECULAR_ALPHA {
                    a.min(PHOTON_SPECULAR_ALPHA * (1.0 - f32::EPSILON))
                } else {
                    a.max(PHOTON_SPECULAR_ALPHA)
                };
                Bsdf::RoughConductor { ks: ks_at(ks).min(Vec3::ONE), alpha: a }
            }
            Bsdf::RoughPlastic { kd, ior, alpha } => {
                Bsdf::RoughPlastic { kd: kd_at(kd).min(Vec3::ONE), ior, alpha: alpha_at(alpha) }
            }
            Bsdf::RoughDielectric { ior, alpha } => Bsdf::RoughDielectric { ior, alpha: alpha_at(alpha) },
            b @ Bsdf::Glass { .. } => b,
        }
    }
}

/// A BSDF sample whose pdf came out zero (see [`Bsdf::sample_checked`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ZeroPdf;

/// A sampled direction and its weight `f·|cos θi| / pdf` (for delta lobes, the lobe's weight).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// Sampled incident direction (unit).
    pub wi: Vec3,
    /// Throughput multiplier.
    pub weight: Vec3,
    /// True for mirror reflection and dielectric reflection/refraction.
    pub delta: bool,
}

/// Geometry the BSDF needs at a point: geometric and shading normals (unit, unflipped).
#[derive(Clone, Copy, Debug)]
pub struct SurfaceFrame {
    /// Geometric normal, as wound (front face).
    pub ng: Vec3,
    /// Shading normal (interpolated vertex normal, or `ng`).
    pub ns: Vec3,
}

impl SurfaceFrame {
    /// Normals flipped to the side of `wo`: (geometric, shading). The shading normal falls back to
    /// the geometric one when they disagree about the side.
    #[must_use]
    pub fn oriented(&self, wo: Vec3) -> (Vec3, Vec3) {
        let ng = if wo.dot(self.ng) < 0.0 { -self.ng } else { self.ng };
        let ns = if self.ns.dot(ng) < 0.0 { -self.ns } else { self.ns };
        let ns = if ns.dot(ng) > 0.0 && ns.is_finite() { ns } else { ng };
        (ng, ns)
    }
}

impl Bsdf {
    /// True for materials that only scatter into delta directions (mirror, glass).
    #[must_use]
    pub fn is_delta(&self) -> bool {
        matches!(self, Bsdf::Mirror { .. } | Bsdf::Glass { .. })
    }

    /// True for surfaces photons pass on as specular (neither stored there nor ending a caustic
    /// path): delta materials, rough dielectrics, rough conductors below
    /// [`PHOTON_SPECULAR_ALPHA`].
    #[must_use]
    pub fn photon_specular(&self) -> bool {
        match *self {
            Bsdf::Mirror { .. } | Bsdf::Glass { .. } | Bsdf::RoughDielectric { .. } => true,
            Bsdf::RoughConductor { alpha, .. } => alpha < PHOTON_SPECULAR_ALPHA,
            _ => false,
        }
    }

    /// True for materials with a lobe that camera paths follow with one traced ray (the glossy
    /// reflection): Phong glossy and the rough materials.
    #[must_use]
    pub fn has_glossy_lobe(&self) -> bool {
        matches!(
            self,
            Bsdf::Glossy { .. }
                | Bsdf::RoughConductor { .. }
                | Bsdf::RoughDielectric { .. }
                | Bsdf::RoughPlastic { .. }
        )
    }

    /// Whether a final-gather ray's weight depends on its direction ([`Bsdf::gather_weight`]):
    /// only for the rough plastic, whose base is seen through its coat.
    #[must_use]
    pub fn gather_varies(&self) -> bool {
        matches!(self, Bsdf::RoughPlastic { .. })
    }

    /// The weight of a cosine-sampled final-gather ray `wi` from the diffuse part: `kd` for
    /// Lambertian and glossy materials (the 1/π and the cosine cancel), the base's
    /// kd·(1 − F(wo))·(1 − F(wi)) for the rough plastic.
    #[must_use]
    pub fn gather_weight(&self, frame: &SurfaceFrame, wo: Vec3, wi: Vec3) -> Vec3 {
        match *self {
            Bsdf::RoughPlastic { kd, ior, .. } => {
                let (_, ns) = frame.oriented(wo);
                let f = Frame::new(ns);
                microfacet::plastic_base(f.to_local(wo), f.to_local(wi), kd, ior)
            }
            _ => self.diffuse(),
        }
    }

    /// Whether the material has a part its glossy ray does not sample (a Lambertian, a Phong
    /// material's kd, a rough plastic's base).
    #[must_use]
    pub fn has_base(&self) -> bool {
        matches!(self, Bsdf::Lambert { .. } | Bsdf::Glossy { .. } | Bsdf::RoughPlastic { .. })
    }

    /// f(wo, wi) of that part alone: kd/π, or the rough plastic's base
    /// kd/π·(1 − F(θo))(1 − F(θi)); zero for the others.
    #[must_use]
    pub fn eval_base(&self, frame: &SurfaceFrame, wo: Vec3, wi: Vec3) -> Vec3 {
        let (ng, ns) = frame.oriented(wo);
        if wi.dot(ng) <= 0.0 {
            return Vec3::ZERO;
        }
        match *self {
            Bsdf::Lambert { kd } | Bsdf::Glossy { kd, .. } => kd / PI,
            Bsdf::RoughPlastic { kd, ior, .. } => {
                let f = Frame::new(ns);
                let (lo, li) = (f.to_local(wo), f.to_local(wi));
                if lo.z <= 0.0 || li.z <= 0.0 {
                    return Vec3::ZERO;
                }
                microfacet::plastic_base(lo, li, kd, ior) / PI
            }
            _ => Vec3::ZERO,
        }
    }

    /// The Lambertian albedo (zero for delta materials).
    #[must_use]
    pub fn diffuse(&self) -> Vec3 {
        match *self {
            Bsdf::Lambert { kd } | Bsdf::Glossy { kd, .. } | Bsdf::RoughPlastic { kd, .. } => kd,
            _ => Vec3::ZERO,
        }
    }

    /// f(wo, wi) for the non-delta part; zero unless wo and wi lie on the same geometric side.
    #[must_use]
    pub fn eval(&self, frame: &SurfaceFrame, wo: Vec3, wi: Vec3) -> Vec3 {
        match *self {
            Bsdf::Lambert { kd } => {
                let (ng, _) = frame.oriented(wo);
                if wi.dot(ng) <= 0.0 {
                    Vec3::ZERO
                } else {
                    kd / PI
                }
            }
            Bsdf::Glossy { kd, ks, exponent } => {
                let (ng, ns) = frame.oriented(wo);
                if wi.dot(ng) <= 0.0 {
                    Vec3::ZERO
                } else {
                    kd / PI + ks * phong_lobe(reflect(wo, ns), wi, exponent)
                }
            }
            Bsdf::Mirror { .. } | Bsdf::Glass { .. } => Vec3::ZERO,
            _ => self.eval_rough(frame, wo, wi).unwrap_or(Vec3::ZERO),
        }
    }

    /// The glossy lobe alone (zero for other materials).
    #[must_use]
    pub fn eval_glossy(&self, frame: &SurfaceFrame, wo: Vec3, wi: Vec3) -> Vec3 {
        if let Some(f) = self.eval_rough(frame, wo, wi) {
            return f;
        }
        match *self {
            Bsdf::Glossy { ks, exponent, .. } => {
                let (ng, ns) = frame.oriented(wo);
                if wi.dot(ng) <= 0.0 {
                    return Vec3::ZERO;
                }
                ks * phong_lobe(reflect(wo, ns), wi, exponent)
            }
            _ => Vec3::ZERO,
        }
    }

    /// Samples the whole BSDF with three uniform numbers. `None` when the sample is absorbed
    /// (below the surface, zero weight) or its pdf is zero.
    #[must_use]
    pub fn sample(&self, frame: &SurfaceFrame, wo: Vec3, u: [f32; 3], transport: Transport) -> Option<BsdfSample> {
        self.sample_checked(frame, wo, u, transport).ok().flatten()
    }

    /// [`Bsdf::sample`], telling a sample whose pdf is zero (`Err`: dividing by it would give ∞
    /// or NaN, so it is dropped; callers count it) from an absorbed one (`Ok(None)`).
    pub fn sample_checked(
        &self,
        frame: &SurfaceFrame,
        wo: Vec3,
        u: [f32; 3],
        transport: Transport,
    ) -> Result<Option<BsdfSample>, ZeroPdf> {
        Ok(match *self {
            Bsdf::Lambert { kd } => {
                let (ng, ns) = frame.oriented(wo);
                let wi = Frame::new(ns).to_world(cosine_hemisphere([u[0], u[1]]));
                // With cosine sampling f·cos/pdf = kd exactly.
                (wi.dot(ng) > 0.0).then_some(BsdfSample { wi, weight: kd, delta: false })
            }
            Bsdf::Glossy { kd, ks, exponent } => {
                let (ng, ns) = frame.oriented(wo);
                let p_diffuse = glossy_diffuse_probability(kd, ks);
                let r = reflect(wo, ns);
                let wi = if u[2] < p_diffuse {
                    Frame::new(ns).to_world(cosine_hemisphere([u[0], u[1]]))
                } else {
                    sample_phong(r, exponent, [u[0], u[1]])
                };
                let cos = wi.dot(ns);
                if wi.dot(ng) <= 0.0 || cos <= 0.0 {
                    return Ok(None);
                }
                let pdf = p_diffuse * cos / PI + (1.0 - p_diffuse) * phong_pdf(r, wi, exponent);
                if !(pdf > 0.0) {
                    return Err(ZeroPdf);
                }
                let f = kd / PI + ks * phong_lobe(r, wi, exponent);
                Some(BsdfSample { wi, weight: f * cos / pdf, delta: false })
            }
            Bsdf::Mirror { ks } => {
                let (ng, ns) = frame.oriented(wo);
                let wi = reflect(wo, ns);
                (wi.dot(ng) > 0.0).then_some(BsdfSample { wi, weight: ks, delta: true })
            }
            Bsdf::Glass { ior } => sample_glass(frame, wo, ior, u[0], transport),
            Bsdf::RoughConductor { .. } | Bsdf::RoughDielectric { .. } | Bsdf::RoughPlastic { .. } => {
                self.sample_rough(frame, wo, u, transport == Transport::Radiance)
            }
        })
    }

    /// The factor refraction from `wo` into `wi` puts on radiance, (η_wo / η_wi)² — 1 for
    /// reflection and for materials that do not refract. A chain's Russian roulette divides it
    /// out: it is not absorption (it cancels when the ray leaves the medium again), and a
    /// survival probability of 1/1.5² on entering glass would kill most paths for nothing.
    #[must_use]
    pub fn radiance_scale(&self, frame: &SurfaceFrame, wo: Vec3, wi: Vec3) -> f32 {
        let (Bsdf::Glass { ior } | Bsdf::RoughDielectric { ior, .. }) = *self else { return 1.0 };
        let (o, i) = (wo.dot(frame.ng), wi.dot(frame.ng));
        if (o > 0.0) == (i > 0.0) {
            return 1.0;
        }
        let eta = if o > 0.0 { ior } else { 1.0 / ior };
        1.0 / (eta * eta)
    }

    /// Samples the glossy lobe alone (radiance): for Phong, weight `ks·(n+2)/(n+1)·cos θi`; for
    /// the rough conductor and dielectric, the whole BSDF; for the rough plastic, its coat (its
    /// base is the final gather's). `None` for other materials.
    #[must_use]
    pub fn sample_glossy(&self, frame: &SurfaceFrame, wo: Vec3, u: [f32; 3]) -> Option<BsdfSample> {
        if let Bsdf::RoughConductor { .. } | Bsdf::RoughDielectric { .. } = self {
            return self.sample_rough(frame, wo, u, true);
        }
        if let Bsdf::RoughPlastic { ior, alpha, .. } = *self {
            let (ng, f, _) = self.rough_frame(frame, wo);
            let lo = f.to_local(wo);
            if lo.z <= 0.0 {
                return None;
            }
            let s = microfacet::plastic_coat_sample(lo, ior, alpha, [u[0], u[1]])?;
            let wi = f.to_world(s.wi);
            return (wi.dot(ng) > 0.0).then_some(BsdfSample { wi, weight: s.weight, delta: false });
        }
        let Bsdf::Glossy { ks, exponent, .. } = *self else { return None };
        let (ng, ns) = frame.oriented(wo);
        let wi = sample_phong(reflect(wo, ns), exponent, [u[0], u[1]]);
        let cos = wi.dot(ns);
        if wi.dot(ng) <= 0.0 || cos <= 0.0 {
            return None;
        }
        Some(BsdfSample { wi, weight: ks * ((exponent + 2.0) / (exponent + 1.0) * cos), delta: false })
    }

    /// The local frame of a rough material at `wo`: the geometric and shading normals on the
    /// side of `wo`, and η(other side)/η(wo's side) (1 for a conductor).
    fn rough_frame(&self, frame: &SurfaceFrame, wo: Vec3) -> (Vec3, Frame, f32) {
        match *self {
            Bsdf::RoughDielectric { ior, .. } => {
                let entering = wo.dot(frame.ng) > 0.0;
                let eta = if entering { ior } else { 1.0 / ior };
                let ng = if entering { frame.ng } else { -frame.ng };
                let ns = if entering { frame.ns } else { -frame.ns };
                let ns = if ns.dot(ng) > 0.0 && ns.is_finite() { ns } else { ng };
                (ng, Frame::new(ns), eta)
            }
            _ => {
                let (ng, ns) = frame.oriented(wo);
                (ng, Frame::new(ns), 1.0)
            }
        }
    }

    /// f(wo, wi) of a rough material (radiance); `None` for the others.
    fn eval_rough(&self, frame: &SurfaceFrame, wo: Vec3, wi: Vec3) -> Option<Vec3> {
        let (ng, f, eta) = match self {
            Bsdf::RoughConductor { .. } | Bsdf::RoughDielectric { .. } | Bsdf::RoughPlastic { .. } => {
                self.rough_frame(frame, wo)
            }
            _ => return None,
        };
        let (lo, li) = (f.to_local(wo), f.to_local(wi));
        Some(match *self {
            Bsdf::RoughConductor { ks, alpha } if wi.dot(ng) > 0.0 => microfacet::conductor_eval(lo, li, ks, alpha),
            Bsdf::RoughPlastic { kd, ior, alpha } if wi.dot(ng) > 0.0 => {
                microfacet::plastic_eval(lo, li, kd, ior, alpha)
            }
            // Reflection stays on wo's geometric side, refraction crosses it.
            Bsdf::RoughDielectric { alpha, .. } if (wi.dot(ng) > 0.0) == (li.z > 0.0) => {
                Vec3::splat(microfacet::dielectric_eval(lo, li, eta, alpha))
            }
            _ => Vec3::ZERO,
        })
    }

    /// The pdf per steradian with which [`Bsdf::sample`] picks `wi` (non-delta materials; 0 for
    /// delta ones, whose directions are not in a density).
    #[must_use]
    pub fn pdf(&self, frame: &SurfaceFrame, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            Bsdf::Lambert { .. } => {
                let (ng, ns) = frame.oriented(wo);
                if wi.dot(ng) > 0.0 {
                    wi.dot(ns).max(0.0) / PI
                } else {
                    0.0
                }
            }
            Bsdf::Glossy { kd, ks, exponent } => {
                let (ng, ns) = frame.oriented(wo);
                if wi.dot(ng) <= 0.0 {
                    return 0.0;
                }
                let p = glossy_diffuse_probability(kd, ks);
                p * wi.dot(ns).max(0.0) / PI + (1.0 - p) * phong_pdf(reflect(wo, ns), wi, exponent)
            }
            Bsdf::RoughConductor { alpha, .. } => {
                let (ng, f, _) = self.rough_frame(frame, wo);
                if wi.dot(ng) <= 0.0 {
                    return 0.0;
                }
                microfacet::conductor_pdf(f.to_local(wo), f.to_local(wi), alpha)
            }
            Bsdf::RoughPlastic { kd, ior, alpha } => {
                let (ng, f, _) = self.rough_frame(frame, wo);
                if wi.dot(ng) <= 0.0 {
                    return 0.0;
                }
                microfacet::plastic_pdf(f.to_local(wo), f.to_local(wi), kd, ior, alpha)
            }
            Bsdf::RoughDielectric { alpha, .. } => {
                let (ng, f, eta) = self.rough_frame(frame, wo);
                let li = f.to_local(wi);
                if (wi.dot(ng) > 0.0) != (li.z > 0.0) {
                    return 0.0;
                }
                microfacet::dielectric_pdf(f.to_local(wo), li, eta, alpha)
            }
            Bsdf::Mirror { .. } | Bsdf::Glass { .. } => 0.0,
        }
    }

    /// Samples a rough material; `radiance` picks the transport (refraction scales radiance by
    /// 1/η², not power). `None` for the others, or when the sample leaves through the wrong side
    /// of the geometric surface.
    fn sample_rough(&self, frame: &SurfaceFrame, wo: Vec3, u: [f32; 3], radiance: bool) -> Option<BsdfSample> {
        let (ng, f, eta) = self.rough_frame(frame, wo);
        let lo = f.to_local(wo);
        if lo.z <= 0.0 {
            return None;
        }
        let s = match *self {
            Bsdf::RoughConductor { ks, alpha } => microfacet::conductor_sample(lo, ks, alpha, [u[0], u[1]])?,
            Bsdf::RoughDielectric { alpha, .. } => microfacet::dielectric_sample(lo, eta, alpha, u, radiance)?,
            Bsdf::RoughPlastic { kd, ior, alpha } => microfacet::plastic_sample(lo, kd, ior, alpha, u)?,
            _ => return None,
        };
        let wi = f.to_world(s.wi);
        ((wi.dot(ng) > 0.0) == (s.wi.z > 0.0)).then_some(BsdfSample { wi, weight: s.weight, delta: false })
    }
}

/// Probability of picking the diffuse lobe of a glossy material: proportional to mean albedo.
fn glossy_diffuse_probability(kd: Vec3, ks: Vec3) -> f32 {
    let d = kd.element_sum();
    let s = ks.element_sum();
    if d + s > 0.0 {
        d / (d + s)
    } else {
        1.0
    }
}

/// Normalised Phong lobe `(n+2)/(2π)·cos^n α` around `r`. The cosine of two unit vectors can
/// round above 1; clamped, so that a huge exponent (an MTL's `Ns 1e30`) gives cos^n ≤ 1, not ∞
/// (and ∞/∞ = NaN sample weights).
fn phong_lobe(r: Vec3, wi: Vec3, n: f32) -> f32 {
    let c = r.dot(wi).min(1.0);
    if c <= 0.0 {
        0.0
    } else {
        (n + 2.0) / (2.0 * PI) * c.powf(n)
    }
}

/// Pdf of [`sample_phong`]: `(n+1)/(2π)·cos^n α` (the cosine clamped as in [`phong_lobe`]).
fn phong_pdf(r: Vec3, wi: Vec3, n: f32) -> f32 {
    let c = r.dot(wi).min(1.0);
    if c <= 0.0 {
        0.0
    } else {
        (n + 1.0) / (2.0 * PI) * c.powf(n)
    }
}

/// Direction around `r` with pdf ∝ cos^n α.
fn sample_phong(r: Vec3, n: f32, u: [f32; 2]) -> Vec3 {
    let cos_a = u[0].powf(1.0 / (n + 1.0));
    let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    Frame::new(r).to_world(Vec3::new(sin_a * phi.cos(), sin_a * phi.sin(), cos_a))
}

/// Chooses reflection with probability F, refraction otherwise; the weight is 1 (power) or
/// (η_wo/η_wi)² for radiance through refraction. Total internal reflection reflects with F = 1.
fn sample_glass(frame: &SurfaceFrame, wo: Vec3, ior: f32, u: f32, transport: Transport) -> Option<BsdfSample> {
    let entering = wo.dot(frame.ng) > 0.0;
    let eta = if entering { ior } else { 1.0 / ior };
    // Normals on the side of wo; the shading normal bends the boundary where it agrees with ng.
    let ng = if entering { frame.ng } else { -frame.ng };
    let ns = if entering { frame.ns } else { -frame.ns };
    let ns = if ns.dot(ng) > 0.0 && ns.is_finite() { ns } else { ng };
    let cos_o = wo.dot(ns);
    if cos_o <= 0.0 {
        return None;
    }
    let f = fresnel_dielectric(cos_o, eta);
    if u < f {
        let wi = reflect(wo, ns);
        return (wi.dot(ng) > 0.0).then_some(BsdfSample { wi, weight: Vec3::ONE, delta: true });
    }
    let wi = refract(wo, ns, eta)?;
    if wi.dot(ng) >= 0.0 {
        return None;
    }
    let scale = match transport {
        Transport::Radiance => 1.0 / (eta * eta),
        Transport::Power => 1.0,
    };
    Some(BsdfSample { wi, weight: Vec3::splat(scale), delta: true })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_roughness_map_sets_alpha_within_the_photon_class() {
        let grey =
            |v: f32| Some(Arc::new(Texture::new(std::path::Path::new("r.png"), 1, 1, vec![Vec3::splat(v)]).unwrap()));
        let rough = |bsdf: Bsdf, v: f32| Material {
            maps: Maps { roughness: grey(v), ..Maps::default() },
            ..Material::new("m", bsdf, Vec3::ZERO)
        };
        let uv = Vec2::splat(0.5);
        let Bsdf::RoughPlastic { alpha, .. } =
            rough(Bsdf::RoughPlastic { kd: Vec3::ONE, ior: 1.5, alpha: 0.5 }, 0.6).bsdf_at(uv)
        else {
            panic!()
        };
        assert!((alpha - 0.36).abs() < 1e-6);
        // A conductor whose photons are stored (α ≥ 0.09) stays there, and one whose photons pass stays below.
        let stored = rough(Bsdf::RoughConductor { ks: Vec3::ONE, alpha: 0.25 }, 0.1).bsdf_at(uv);
        assert_eq!(stored, Bsdf::RoughConductor { ks: Vec3::ONE, alpha: PHOTON_SPECULAR_ALPHA });
        let passed = rough(Bsdf::RoughConductor { ks: Vec3::ONE, alpha: 0.01 }, 0.9).bsdf_at(uv);
        assert!(passed.photon_specular(), "{passed:?}");
        let Bsdf::RoughConductor { alpha, .. } =
            rough(Bsdf::RoughConductor { ks: Vec3::ONE, alpha: 0.01 }, 0.2).bsdf_at(uv)
        else {
            panic!()
        };
        assert!((alpha - 0.04).abs() < 1e-6);
    }

    #[test]
    fn a_metallic_map_picks_conductor_or_plastic_per_point() {
        let two =
            Some(Arc::new(Texture::new(std::path::Path::new("m.png"), 2, 1, vec![Vec3::ZERO, Vec3::ONE]).unwrap()));
        let m = Material {
            maps: Maps { metallic: two, ..Maps::default() },
            ..Material::new("m", Bsdf::RoughPlastic { kd: Vec3::new(0.9, 0.5, 0.1), ior: 1.4, alpha: 0.04 }, Vec3::ZERO)
        };
        assert_eq!(
            m.bsdf_at(Vec2::new(0.25, 0.5)),
            Bsdf::RoughPlastic { kd: Vec3::new(0.9, 0.5, 0.1), ior: 1.4, alpha: 0.04 }
        );
        let metal = m.bsdf_at(Vec2::new(0.75, 0.5));
        assert_eq!(metal, Bsdf::RoughConductor { ks: Vec3::new(0.9, 0.5, 0.1), alpha: PHOTON_SPECULAR_ALPHA });
        assert!(!metal.photon_specular(), "metal parts store photons, as the plastic does");
    }

    #[test]
    fn fresnel_known_values() {
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        let c45 = std::f32::consts::FRAC_1_SQRT_2;
        assert!((fresnel_dielectric(c45, 1.5) - 0.0502).abs() < 1e-4, "{}", fresnel_dielectric(c45, 1.5));
        // Glass → air: critical angle asin(1/1.5) = 41.81°.
        let crit = (1.0f32 / 1.5).asin();
        assert_eq!(fresnel_dielectric((crit + 1e-3).cos(), 1.0 / 1.5), 1.0);
        assert!(fresnel_dielectric((crit - 1e-3).cos(), 1.0 / 1.5) < 1.0);
    }

    #[test]
    fn reflectance_plus_transmittance_is_one() {
        // Energy through the boundary: T = 1 − R, and T computed from the Fresnel amplitudes agrees.
        for i in 0..90 {
            let th = (i as f32).to_radians();
            let (ci, eta) = (th.cos(), 1.5f32);
            let r = fresnel_dielectric(ci, eta);
            let st2 = (1.0 - ci * ci) / (eta * eta);
            let ct = (1.0 - st2).sqrt();
            let ts = 2.0 * ci / (ci + eta * ct);
            let tp = 2.0 * ci / (eta * ci + ct);
            let t = eta * ct / ci * 0.5 * (ts * ts + tp * tp);
            assert!((r + t - 1.0).abs() < 1e-4, "θ={i}: R={r} T={t}");
        }
    }

    #[test]
    fn total_internal_reflection_is_exact() {
        let frame = SurfaceFrame { ng: Vec3::Z, ns: Vec3::Z };
        // Inside the glass (wo below the surface), 60° from the normal: past 41.8°.
        let wo = Vec3::new(60f32.to_radians().sin(), 0.0, -60f32.to_radians().cos());
        for k in 0..100 {
            let s =
                Bsdf::Glass { ior: 1.5 }.sample(&frame, wo, [k as f32 / 100.0, 0.5, 0.5], Transport::Power).unwrap();
            assert_eq!(s.weight, Vec3::ONE);
            assert!(s.wi.z < 0.0, "must stay inside");
        }
    }

    #[test]
    fn lambert_sample_weight_is_kd_exactly() {
        let kd = Vec3::new(0.7, 0.3, 0.05);
        let frame = SurfaceFrame { ng: Vec3::Y, ns: Vec3::Y };
        for i in 0..64 {
            let u = [(i % 8) as f32 / 8.0 + 0.03, (i / 8) as f32 / 8.0 + 0.05, 0.5];
            let s = Bsdf::Lambert { kd }.sample(&frame, Vec3::Y, u, Transport::Radiance).unwrap();
            assert_eq!(s.weight, kd);
            assert!(s.wi.dot(Vec3::Y) > 0.0);
        }
    }

    #[test]
    fn glossy_never_reflects_more_than_it_receives() {
        // Monte Carlo albedo (mean of sample weights) at several incidence angles, per channel ≤ 1.
        let b = Bsdf::Glossy { kd: Vec3::splat(0.5), ks: Vec3::splat(0.5), exponent: 20.0 };
        let frame = SurfaceFrame { ng: Vec3::Z, ns: Vec3::Z };
        for deg in [0.0f32, 30.0, 60.0, 85.0] {
            let wo = Vec3::new(deg.to_radians().sin(), 0.0, deg.to_radians().cos());
            let n = 64;
            let mut sum = Vec3::ZERO;
            for i in 0..n * n {
                let u = [
                    ((i % n) as f32 + 0.5) / n as f32,
                    ((i / n) as f32 + 0.5) / n as f32,
                    ((i * 7919) % 1000) as f32 / 1000.0,
                ];
                if let Some(s) = b.sample(&frame, wo, u, Transport::Radiance) {
                    sum += s.weight;
                }
            }
            let albedo = sum / (n * n) as f32;
            // Stratified estimate; 2 % slack for its error.
            assert!(albedo.max_element() <= 1.02, "θ={deg}: albedo {albedo}");
        }
    }
}
