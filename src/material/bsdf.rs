//! The BSDFs' evaluate, pdf and sample for every [`Bsdf`]: Lambertian, glossy (Lambertian +
//! normalised Phong lobe), perfect mirror, smooth dielectric and the GGX rough ones, with the
//! adjoint treatment of refraction (radiance scaled by (η_wo / η_wi)², power not).
//!
//! Reads a [`SurfaceFrame`] and directions (world space, away from the surface); writes
//! [`BsdfSample`]s and values. The materials themselves are in the parent module.

use super::{
    Bsdf, BsdfSample, SmoothPlastic, SurfaceFrame, Tint, Transport, ZeroPdf, NARROW_PHONG_EXPONENT,
    PHOTON_SPECULAR_ALPHA,
};
use crate::microfacet;
use crate::optics::{conductor_reflectance, fresnel_dielectric, reflect, refract, thin_slab_reflectance};
use crate::sampling::{cosine_hemisphere, Frame};
use glam::Vec3;
use std::f32::consts::PI;

impl Bsdf {
    /// True for materials that only scatter into delta directions (mirror, glass).
    #[must_use]
    pub fn is_delta(&self) -> bool {
        matches!(self, Bsdf::Mirror { .. } | Bsdf::Glass { .. } | Bsdf::ThinGlass { .. })
    }

    /// For a thin sheet whose rays pass it in traversal (`ThinGlass` with `passed`): its index
    /// and the grey scale on what it transmits — the chance a ray along a direction at cos θ
    /// = `cos` to its normal passes is [`crate::optics::thin_pass_probability`] of them.
    #[must_use]
    pub fn thin_pass(&self) -> Option<(f32, f32)> {
        match *self {
            Bsdf::ThinGlass { ior, tint, passed: true } => Some((ior, tint.transmit.x)),
            _ => None,
        }
    }

    /// This material with rays passing it in traversal when it is a thin sheet that can be:
    /// one whose transmission tint is grey and at most 1, so that passing needs no weight (a
    /// coloured tint would: such a sheet stays a surface rays sample, and the light through it
    /// a caustic). Other materials unchanged.
    #[must_use]
    pub fn passing_thin_sheets(self) -> Bsdf {
        match self {
            Bsdf::ThinGlass { ior, tint, .. } => {
                let t = tint.transmit;
                let grey = t.x == t.y && t.y == t.z && (0.0..=1.0).contains(&t.x);
                Bsdf::ThinGlass { ior, tint, passed: grey }
            }
            other => other,
        }
    }

    /// True for materials that let light through (glass, rough glass).
    #[must_use]
    pub fn transmits(&self) -> bool {
        matches!(self, Bsdf::Glass { .. } | Bsdf::ThinGlass { .. } | Bsdf::RoughDielectric { .. })
    }

    /// True for surfaces photons pass on as specular (neither stored there nor ending a caustic
    /// path): delta materials, rough dielectrics, rough conductors below
    /// [`PHOTON_SPECULAR_ALPHA`].
    #[must_use]
    pub fn photon_specular(&self) -> bool {
        match *self {
            Bsdf::Mirror { .. } | Bsdf::Glass { .. } | Bsdf::ThinGlass { .. } | Bsdf::RoughDielectric { .. } => true,
            Bsdf::RoughConductor { alpha, .. } => alpha.width() < PHOTON_SPECULAR_ALPHA,
            _ => false,
        }
    }

    /// True for materials with a lobe that camera paths follow with one traced ray (the glossy
    /// reflection): Phong glossy, the rough materials and the smooth plastic's coat (a delta lobe
    /// beside its diffuse base).
    #[must_use]
    pub fn has_glossy_lobe(&self) -> bool {
        matches!(
            self,
            Bsdf::Glossy { .. }
                | Bsdf::RoughConductor { .. }
                | Bsdf::RoughDielectric { .. }
                | Bsdf::RoughPlastic { .. }
                | Bsdf::Plastic { .. }
        )
    }

    /// True for a material whose glossy lobe is too narrow for a photon-map estimate to read,
    /// beside a base that is not: a plastic's coat, smooth or rough below
    /// [`PHOTON_SPECULAR_ALPHA`], and a Phong lobe as narrow (exponent above
    /// [`NARROW_PHONG_EXPONENT`]). In the peak of a GGX coat of α 0.01 f is about 3 000 per
    /// steradian: one photon arriving there, or one light sample, makes an estimate a hundred
    /// times its neighbours'. Where a gather or glossy ray lands on such a surface the lobe
    /// sends a ray of its own instead (`transport::lobe`).
    #[must_use]
    pub fn narrow_lobe(&self) -> bool {
        match *self {
            Bsdf::Plastic { .. } => true,
            Bsdf::RoughPlastic { alpha, .. } => alpha.width() < PHOTON_SPECULAR_ALPHA,
            Bsdf::Glossy { exponent, .. } => exponent > NARROW_PHONG_EXPONENT,
            _ => false,
        }
    }

    /// Whether a final-gather ray's weight depends on its direction ([`Bsdf::gather_weight`]):
    /// only for the plastics, whose base is seen through their coat.
    #[must_use]
    pub fn gather_varies(&self) -> bool {
        matches!(self, Bsdf::RoughPlastic { .. } | Bsdf::Plastic { .. })
    }

    /// The weight of a cosine-sampled final-gather ray `wi` from the diffuse part: `kd` for
    /// Lambertian and glossy materials (the 1/π and the cosine cancel), the base's
    /// kd′·T(wo)·T(wi)/η² for the rough plastic ([`microfacet::Plastic::base`]), and the smooth
    /// plastic's kd′·(1 − F(wo))·(1 − F(wi))/η² ([`SmoothPlastic::base`]).
    #[must_use]
    pub fn gather_weight(&self, frame: &SurfaceFrame, wo: Vec3, wi: Vec3) -> Vec3 {
        if !self.gather_varies() {
            return self.diffuse();
        }
        let (_, ns) = frame.oriented(wo);
        let f = Frame::new(ns);
        let (lo, li) = (f.to_local(wo), f.to_local(wi));
        match (self.plastic(), self.smooth_plastic()) {
            (Some(p), _) => p.base(lo, li),
            (_, Some(p)) => p.base(lo, li),
            _ => self.diffuse(),
        }
    }

    /// A smooth plastic's model ([`SmoothPlastic`]); `None` for the other materials.
    #[must_use]
    pub fn smooth_plastic(&self) -> Option<SmoothPlastic> {
        match *self {
            Bsdf::Plastic { kd, ks, eta, nonlinear } => Some(SmoothPlastic { kd, ks, eta, nonlinear }),
            _ => None,
        }
    }

    /// A rough plastic's model ([`microfacet::Plastic`]); `None` for the other materials.
    #[must_use]
    pub fn plastic(&self) -> Option<microfacet::Plastic> {
        match *self {
            Bsdf::RoughPlastic { kd, ks, alpha, nonlinear, coat } => {
                Some(microfacet::Plastic { kd, ks, coat, alpha, nonlinear })
            }
            _ => None,
        }
    }

    /// Whether the material has a part its glossy ray does not sample (a Lambertian, a Phong
    /// material's kd, a plastic's base).
    #[must_use]
    pub fn has_base(&self) -> bool {
        matches!(self, Bsdf::Lambert { .. } | Bsdf::Glossy { .. } | Bsdf::RoughPlastic { .. } | Bsdf::Plastic { .. })
    }

    /// f(wo, wi) of that part alone: kd/π, or the rough plastic's base
    /// kd′·T(θo)·T(θi)/(π η²); zero for the others.
    #[must_use]
    pub fn eval_base(&self, frame: &SurfaceFrame, wo: Vec3, wi: Vec3) -> Vec3 {
        let (ng, ns) = frame.oriented(wo);
        if wi.dot(ng) <= 0.0 {
            return Vec3::ZERO;
        }
        match *self {
            Bsdf::Lambert { kd } | Bsdf::Glossy { kd, .. } => kd / PI,
            Bsdf::RoughPlastic { .. } => {
                let f = Frame::new(ns);
                let (lo, li) = (f.to_local(wo), f.to_local(wi));
                match self.plastic() {
                    Some(p) if lo.z > 0.0 && li.z > 0.0 => p.base(lo, li) / PI,
                    _ => Vec3::ZERO,
                }
            }
            Bsdf::Plastic { kd, ks, eta, nonlinear } => {
                let f = Frame::new(ns);
                SmoothPlastic { kd, ks, eta, nonlinear }.base(f.to_local(wo), f.to_local(wi)) / PI
            }
            _ => Vec3::ZERO,
        }
    }

    /// The Lambertian albedo (zero for delta materials).
    #[must_use]
    pub fn diffuse(&self) -> Vec3 {
        match *self {
            Bsdf::Lambert { kd }
            | Bsdf::Glossy { kd, .. }
            | Bsdf::RoughPlastic { kd, .. }
            | Bsdf::Plastic { kd, .. } => kd,
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
            Bsdf::Mirror { .. } | Bsdf::Glass { .. } | Bsdf::ThinGlass { .. } => Vec3::ZERO,
            // The coat is a delta lobe: only the base has a value.
            Bsdf::Plastic { .. } => self.eval_base(frame, wo, wi),
            _ => self.eval_rough(frame, wo, wi).unwrap_or(Vec3::ZERO),
        }
    }

    /// f(wo, wi) of the part the glossy ray samples ([`Bsdf::sample_glossy`]): the Phong lobe,
    /// the whole rough conductor or dielectric, the rough plastic's coat; zero for the others.
    /// With [`Bsdf::eval_base`] it makes up [`Bsdf::eval`].
    #[must_use]
    pub fn eval_lobe(&self, frame: &SurfaceFrame, wo: Vec3, wi: Vec3) -> Vec3 {
        match *self {
            Bsdf::Glossy { ks, exponent, .. } => {
                let (ng, ns) = frame.oriented(wo);
                if wi.dot(ng) <= 0.0 {
                    return Vec3::ZERO;
                }
                ks * phong_lobe(reflect(wo, ns), wi, exponent)
            }
            Bsdf::RoughPlastic { ks, alpha, coat, .. } => {
                let (ng, f, _) = self.rough_frame(frame, wo);
                if wi.dot(ng) <= 0.0 {
                    return Vec3::ZERO;
                }
                ks * microfacet::plastic_coat_eval(f.to_local(wo), f.to_local(wi), coat.eta, alpha)
            }
            _ => self.eval_rough(frame, wo, wi).unwrap_or(Vec3::ZERO),
        }
    }

    /// The pdf per steradian with which [`Bsdf::sample_glossy`] picks `wi` (0 for materials
    /// without a glossy lobe, and where the glossy ray would be dropped: below the geometric
    /// surface, or for Phong below the shading one).
    #[must_use]
    pub fn glossy_pdf(&self, frame: &SurfaceFrame, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            Bsdf::Glossy { exponent, .. } => {
                let (ng, ns) = frame.oriented(wo);
                if wi.dot(ng) <= 0.0 || wi.dot(ns) <= 0.0 {
                    return 0.0;
                }
                phong_pdf(reflect(wo, ns), wi, exponent)
            }
            Bsdf::RoughPlastic { alpha, .. } => {
                let (ng, f, _) = self.rough_frame(frame, wo);
                if wi.dot(ng) <= 0.0 {
                    return 0.0;
                }
                microfacet::plastic_coat_pdf(f.to_local(wo), f.to_local(wi), alpha)
            }
            Bsdf::RoughConductor { .. } | Bsdf::RoughDielectric { .. } => self.pdf(frame, wo, wi),
            _ => 0.0,
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
            Bsdf::Mirror { ks, eta_k } => {
                let (ng, ns) = frame.oriented(wo);
                let wi = reflect(wo, ns);
                let weight = match eta_k {
                    Some(ior) => ks * crate::optics::fresnel_conductor(wo.dot(ns), ior),
                    None => ks,
                };
                (wi.dot(ng) > 0.0).then_some(BsdfSample { wi, weight, delta: true })
            }
            Bsdf::Glass { ior, tint } => {
                sample_glass(frame, wo, ior, u[0], transport).map(|s| tinted(s, &tint, frame, wo))
            }
            Bsdf::Plastic { kd, ks, eta, nonlinear } => {
                let (ng, ns) = frame.oriented(wo);
                let f = Frame::new(ns);
                let Some(s) = (SmoothPlastic { kd, ks, eta, nonlinear }).sample(f.to_local(wo), u) else {
                    return Ok(None);
                };
                let wi = f.to_world(s.sample.wi);
                (wi.dot(ng) > 0.0).then_some(BsdfSample { wi, weight: s.sample.weight, delta: s.coat })
            }
            Bsdf::ThinGlass { ior, tint, passed: false } => {
                sample_thin_glass(frame, wo, ior, u[0]).map(|s| tinted(s, &tint, frame, wo))
            }
            Bsdf::ThinGlass { ior, tint, passed: true } => reflect_thin_glass(frame, wo, ior, tint),
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
        let (Bsdf::Glass { ior, .. } | Bsdf::RoughDielectric { ior, .. }) = *self else { return 1.0 };
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
        if let Some(p) = self.smooth_plastic() {
            // The coat's mirror reflection, weight F·ks: a delta lobe.
            let (ng, ns) = frame.oriented(wo);
            let f = Frame::new(ns);
            let lo = f.to_local(wo);
            if lo.z <= 0.0 {
                return None;
            }
            let c = p.coat(lo);
            let wi = f.to_world(c.wi);
            return (wi.dot(ng) > 0.0).then_some(BsdfSample { wi, weight: c.weight, delta: true });
        }
        if let Bsdf::RoughConductor { .. } | Bsdf::RoughDielectric { .. } = self {
            return self.sample_rough(frame, wo, u, true);
        }
        if let Bsdf::RoughPlastic { ks, alpha, coat, .. } = *self {
            let (ng, f, _) = self.rough_frame(frame, wo);
            let lo = f.to_local(wo);
            if lo.z <= 0.0 {
                return None;
            }
            let s = microfacet::plastic_coat_sample(lo, coat.eta, alpha, [u[0], u[1]])?;
            let wi = f.to_world(s.wi);
            return (wi.dot(ng) > 0.0).then_some(BsdfSample { wi, weight: ks * s.weight, delta: false });
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
            Bsdf::RoughConductor { ks, alpha, eta_k } if wi.dot(ng) > 0.0 => {
                microfacet::conductor_eval(lo, li, |cos| conductor_reflectance(ks, eta_k, cos), alpha)
            }
            Bsdf::RoughPlastic { .. } if wi.dot(ng) > 0.0 => self.plastic().map_or(Vec3::ZERO, |p| p.eval(lo, li)),
            // Reflection stays on wo's geometric side, refraction crosses it.
            Bsdf::RoughDielectric { alpha, tint, .. } if (wi.dot(ng) > 0.0) == (li.z > 0.0) => {
                let scale = if li.z > 0.0 { tint.reflect } else { tint.transmit };
                scale * microfacet::dielectric_eval(lo, li, eta, alpha)
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
            Bsdf::RoughPlastic { .. } => {
                let (ng, f, _) = self.rough_frame(frame, wo);
                match self.plastic() {
                    Some(p) if wi.dot(ng) > 0.0 => p.pdf(f.to_local(wo), f.to_local(wi)),
                    _ => 0.0,
                }
            }
            Bsdf::RoughDielectric { alpha, .. } => {
                let (ng, f, eta) = self.rough_frame(frame, wo);
                let li = f.to_local(wi);
                if (wi.dot(ng) > 0.0) != (li.z > 0.0) {
                    return 0.0;
                }
                microfacet::dielectric_pdf(f.to_local(wo), li, eta, alpha)
            }
            Bsdf::Plastic { kd, ks, eta, nonlinear } => {
                let (ng, ns) = frame.oriented(wo);
                if wi.dot(ng) <= 0.0 {
                    return 0.0;
                }
                let f = Frame::new(ns);
                SmoothPlastic { kd, ks, eta, nonlinear }.pdf(f.to_local(wo), f.to_local(wi))
            }
            Bsdf::Mirror { .. } | Bsdf::Glass { .. } | Bsdf::ThinGlass { .. } => 0.0,
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
            Bsdf::RoughConductor { ks, alpha, eta_k } => {
                microfacet::conductor_sample(lo, |cos| conductor_reflectance(ks, eta_k, cos), alpha, [u[0], u[1]])?
            }
            Bsdf::RoughDielectric { alpha, tint, .. } => {
                let s = microfacet::dielectric_sample(lo, eta, alpha, u, radiance)?;
                let scale = if s.wi.z > 0.0 { tint.reflect } else { tint.transmit };
                microfacet::LocalSample { weight: s.weight * scale, ..s }
            }
            Bsdf::RoughPlastic { .. } => self.plastic()?.sample(lo, u)?,
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

/// A thin sheet: reflection about the shading normal with the slab's reflectance R′
/// ([`thin_slab_reflectance`]) as its probability, otherwise straight through (wi = −wo); the
/// weight is 1 either way, and no (η_wo/η_wi)² (the light leaves into the medium it came from).
/// Sample `s` of a dielectric from `wo`, its weight scaled by `tint`'s reflection or
/// transmission.
#[inline]
fn tinted(s: BsdfSample, tint: &Tint, frame: &SurfaceFrame, wo: Vec3) -> BsdfSample {
    BsdfSample { weight: s.weight * tint.of(frame.ng, wo, s.wi), ..s }
}

fn sample_thin_glass(frame: &SurfaceFrame, wo: Vec3, ior: f32, u: f32) -> Option<BsdfSample> {
    let (ng, ns) = frame.oriented(wo);
    if u < thin_slab_reflectance(wo.dot(ns), ior) {
        let wi = reflect(wo, ns);
        return (wi.dot(ng) > 0.0).then_some(BsdfSample { wi, weight: Vec3::ONE, delta: true });
    }
    Some(BsdfSample { wi: -wo, weight: Vec3::ONE, delta: true })
}

/// A thin sheet passed in traversal, met by a ray that did not pass it (probability
/// 1 − t·(1 − R′) at cos θ = |wo·ng|, the traversal's own): reflection about the shading
/// normal with weight `tint.reflect`·R′ / (1 − t·(1 − R′)), so reflection's expected share is
/// R′·`tint.reflect` as when sampled; at most `tint.reflect` (R′ ≤ 1 − t·(1 − R′) for t ≤ 1).
fn reflect_thin_glass(frame: &SurfaceFrame, wo: Vec3, ior: f32, tint: Tint) -> Option<BsdfSample> {
    let (ng, ns) = frame.oriented(wo);
    let cos = wo.dot(ng).abs();
    let r = thin_slab_reflectance(cos, ior);
    // 1 − thin_pass_probability, from the R′ just found.
    let stopped = 1.0 - tint.transmit.x * (1.0 - r);
    let wi = reflect(wo, ns);
    if !(stopped > 0.0) || wi.dot(ng) <= 0.0 {
        return None;
    }
    Some(BsdfSample { wi, weight: tint.reflect * (r / stopped).min(1.0), delta: true })
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
