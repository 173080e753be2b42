//! A BSDF prepared at one point toward one `wo`, for the many `wi` of a density estimate: each
//! of its photons asks f(wo, wi) or the base's f, and the parts that depend on `wo` alone — the
//! shading frame, `wo` in it, a rough plastic's coat transmittance and masking toward `wo` and its
//! base albedo kd′ — are found once instead of per photon. Reads the BSDF, the frame and `wo`; writes
//! nothing. Every value is the one [`Bsdf::eval`] and [`Bsdf::eval_base`] give, to the bit: the
//! same operations in the same order, the `wo` parts computed ahead.
//!
//! On the Modern Hall, whose floors and stairs are rough plastics read by every gather ray that
//! lands on them, the per-photon f was a quarter of a one-pass render (BENCHMARKS.md, issue 57).

use super::{Bsdf, SurfaceFrame};
use crate::microfacet::{plastic_coat_above, Plastic};
use crate::sampling::Frame;
use glam::Vec3;
use std::f32::consts::PI;

/// [`Bsdf::eval`] and [`Bsdf::eval_base`] at one point toward one `wo` ([`Bsdf::prepare`]).
pub struct Prepared<'a> {
    bsdf: &'a Bsdf,
    frame: &'a SurfaceFrame,
    wo: Vec3,
    /// A rough plastic's parts that `wo` alone decides.
    plastic: Option<PlasticAt>,
}

/// A rough plastic toward one `wo`: its geometric normal on `wo`'s side, its shading frame, `wo`
/// in it, the plastic, its base albedo kd′, and its coat's transmittance and masking toward `wo`.
struct PlasticAt {
    ng: Vec3,
    frame: Frame,
    lo: Vec3,
    plastic: Plastic,
    albedo: Vec3,
    t_out: f32,
    /// The coat's masking toward `wo`, G1(wo).
    g1_out: f32,
}

impl Bsdf {
    /// This BSDF at `frame` toward `wo`, for evaluating many directions.
    #[must_use]
    pub fn prepare<'a>(&'a self, frame: &'a SurfaceFrame, wo: Vec3) -> Prepared<'a> {
        let plastic = self.plastic().map(|plastic| {
            // As `rough_frame` and `eval_base` find them (the same for a plastic).
            let (ng, ns) = frame.oriented(wo);
            let f = Frame::new(ns);
            let lo = f.to_local(wo);
            let c = plastic.coat;
            PlasticAt {
                ng,
                frame: f,
                lo,
                plastic,
                albedo: c.base_albedo(plastic.kd, plastic.nonlinear),
                t_out: c.transmittance(lo.z),
                g1_out: plastic.alpha.g1(lo),
            }
        });
        Prepared { bsdf: self, frame, wo, plastic }
    }
}

impl Prepared<'_> {
    /// f(wo, wi): [`Bsdf::eval`].
    #[inline]
    #[must_use]
    pub fn eval(&self, wi: Vec3) -> Vec3 {
        let Some(at) = &self.plastic else { return self.bsdf.eval(self.frame, self.wo, wi) };
        match at.local(wi) {
            Some(li) if at.lo.z > 0.0 && li.z > 0.0 => {
                let p = &at.plastic;
                p.ks * plastic_coat_above(at.lo, li, p.coat.eta, p.alpha, at.g1_out) + at.base(li) / PI
            }
            _ => Vec3::ZERO,
        }
    }

    /// f of the part the glossy ray does not sample: [`Bsdf::eval_base`].
    #[inline]
    #[must_use]
    pub fn eval_base(&self, wi: Vec3) -> Vec3 {
        let Some(at) = &self.plastic else { return self.bsdf.eval_base(self.frame, self.wo, wi) };
        match at.local(wi) {
            Some(li) if at.lo.z > 0.0 && li.z > 0.0 => at.base(li) / PI,
            _ => Vec3::ZERO,
        }
    }
}

impl PlasticAt {
    /// `wi` in the shading frame, where it lies above the geometric normal (the plastic
    /// reflects only; `None` for a NaN direction too).
    #[inline]
    fn local(&self, wi: Vec3) -> Option<Vec3> {
        (wi.dot(self.ng) > 0.0).then(|| self.frame.to_local(wi))
    }

    /// [`Plastic::base`] toward `li`: kd′·T(wo.z)·T(wi.z)/η².
    #[inline]
    fn base(&self, li: Vec3) -> Vec3 {
        let c = self.plastic.coat;
        self.albedo * (self.t_out * c.transmittance(li.z) / (c.eta * c.eta))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::microfacet::{Alpha, CoatAt, Distribution};

    /// Prepared and plain evaluations agree to the bit: rough plastics (GGX and Beckmann,
    /// isotropic and not, linear and nonlinear) and a Lambertian, at shading normals tilted off
    /// the geometric one, `wo` and `wi` on both sides.
    #[test]
    fn a_prepared_bsdf_evaluates_as_the_bsdf_does() {
        let mut seed = 7u64;
        let mut rnd = move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut dir = || Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize();
        let mut bsdfs = vec![Bsdf::Lambert { kd: Vec3::new(0.5, 0.4, 0.3) }];
        for (distribution, u, v, nonlinear) in
            [(Distribution::Ggx, 0.1, 0.1, false), (Distribution::Beckmann, 0.3, 0.05, true)]
        {
            let alpha = Alpha { distribution, u, v };
            bsdfs.push(Bsdf::RoughPlastic {
                kd: Vec3::new(0.6, 0.3, 0.2),
                ks: Vec3::ONE,
                alpha,
                nonlinear,
                coat: CoatAt::new(1.5, alpha),
            });
        }
        let mut checked = 0;
        for bsdf in &bsdfs {
            for _ in 0..200 {
                let ng = dir();
                let ns = (ng + 0.3 * dir()).normalize();
                let frame = SurfaceFrame { ng, ns };
                let wo = dir();
                let prepared = bsdf.prepare(&frame, wo);
                for _ in 0..20 {
                    let wi = dir();
                    let (a, b) = (prepared.eval(wi), bsdf.eval(&frame, wo, wi));
                    assert_eq!(a.to_array().map(f32::to_bits), b.to_array().map(f32::to_bits), "{bsdf:?} {wo} {wi}");
                    let (a, b) = (prepared.eval_base(wi), bsdf.eval_base(&frame, wo, wi));
                    assert_eq!(a.to_array().map(f32::to_bits), b.to_array().map(f32::to_bits), "{bsdf:?} {wo} {wi}");
                    checked += u32::from(b != Vec3::ZERO);
                }
            }
        }
        assert!(checked > 3000, "{checked} nonzero values");
    }
}
