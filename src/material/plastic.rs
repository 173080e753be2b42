//! Mitsuba 3's smooth `plastic`: a smooth dielectric coat over a Lambertian base. The coat
//! reflects as a mirror with its Fresnel reflectance F(cos θ)·ks (a delta lobe); light that
//! crosses it reaches the base, is spread over the solid angle inside (1/η²), bounces between the
//! base and the coat's underside (kd′ = kd / (1 − F_dr), or kd / (1 − kd·F_dr) when
//! `nonlinear`) and leaves through the coat again: f = kd′·(1 − F(θo))·(1 − F(θi)) / (π η²).
//! F_dr is Mitsuba's fit of a smooth interface's internal diffuse reflectance.
//!
//! Sampling picks the coat with probability F(θo)·w / (F(θo)·w + (1 − F(θo))·(1 − w)),
//! w = mean(ks) / (mean(ks) + mean(kd)), as Mitsuba does; the base cosine-weighted.
//!
//! Reads local directions (z along the shading normal on the side of `wo`); writes values, pdfs
//! and samples. The rough coat (`roughplastic`) is [`crate::microfacet::Plastic`].

use crate::microfacet::LocalSample;
use crate::optics::fresnel_dielectric;
use crate::sampling::cosine_hemisphere;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// A smooth plastic at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmoothPlastic {
    /// Base albedo.
    pub kd: Vec3,
    /// The coat reflection's scale (Mitsuba's `specular_reflectance`).
    pub ks: Vec3,
    /// η(inside) / η(outside) of the coat.
    pub eta: f32,
    /// Whether the base's internal bounces tint by kd (Mitsuba's `nonlinear`).
    pub nonlinear: bool,
}

/// A smooth plastic's sample: the direction, its weight f·cos/pdf (for the coat, the delta
/// lobe's F·ks over its probability) and whether it is the coat's mirror direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlasticSample {
    /// The direction and its weight.
    pub sample: LocalSample,
    /// True for the coat's mirror reflection.
    pub coat: bool,
}

impl SmoothPlastic {
    /// The base's f(wo, wi)·π: kd′·(1 − F(θo))·(1 − F(θi))/η²; zero unless both lie above.
    #[must_use]
    pub fn base(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        let f_dr = fresnel_diffuse_reflectance(1.0 / self.eta);
        let back = if self.nonlinear { self.kd * f_dr } else { Vec3::splat(f_dr) };
        let kd = self.kd / (Vec3::ONE - back);
        let (fo, fi) = (fresnel_dielectric(wo.z, self.eta), fresnel_dielectric(wi.z, self.eta));
        kd * ((1.0 - fo) * (1.0 - fi) / (self.eta * self.eta))
    }

    /// The probability of sampling the coat from `wo` (see the module doc).
    #[must_use]
    pub fn coat_probability(&self, wo: Vec3) -> f32 {
        self.coat_share(fresnel_dielectric(wo.z.max(0.0), self.eta))
    }

    /// The coat probability for the coat's Fresnel reflectance `f` toward the viewer.
    fn coat_share(&self, f: f32) -> f32 {
        let (s, d) = (self.ks.element_sum(), self.kd.element_sum());
        let w = if s + d > 0.0 { s / (s + d) } else { 1.0 };
        let (coat, base) = (f * w, (1.0 - f) * (1.0 - w));
        if coat + base > 0.0 {
            coat / (coat + base)
        } else {
            1.0
        }
    }

    /// The coat's mirror reflection of `wo` and its weight F(θo)·ks (the glossy ray of a camera
    /// path, which follows the coat alone).
    #[must_use]
    pub fn coat(&self, wo: Vec3) -> LocalSample {
        let wi = Vec3::new(-wo.x, -wo.y, wo.z);
        LocalSample { wi, weight: self.ks * fresnel_dielectric(wo.z, self.eta) }
    }

    /// The pdf of a base sample toward `wi`: (1 − coat probability)·cos θi/π.
    #[must_use]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        (1.0 - self.coat_probability(wo)) * wi.z * FRAC_1_PI
    }

    /// Samples the coat (with `u[2]` below its probability) or the base; `None` from below.
    #[must_use]
    pub fn sample(&self, wo: Vec3, u: [f32; 3]) -> Option<PlasticSample> {
        if wo.z <= 0.0 {
            return None;
        }
        // One Fresnel reflectance serves the choice and the coat's weight.
        let f = fresnel_dielectric(wo.z, self.eta);
        let p = self.coat_share(f);
        if u[2] < p {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            return Some(PlasticSample { sample: LocalSample { wi, weight: self.ks * f / p }, coat: true });
        }
        let wi = cosine_hemisphere([u[0], u[1]]);
        if wi.z <= 0.0 || p >= 1.0 {
            return None;
        }
        // f·cos/pdf = base/π·cos / ((1 − p)·cos/π).
        Some(PlasticSample { sample: LocalSample { wi, weight: self.base(wo, wi) / (1.0 - p) }, coat: false })
    }
}

/// Mitsuba's fit of the diffuse reflectance of a smooth interface of relative index `eta` (the
/// share of cosine-distributed light it reflects): Egan & Hilgeman (1973) below 1, d'Eon &
/// Irving (2011) above, each within 0.1 % for 1/1.5 ≤ η ≤ 1.5.
#[must_use]
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    if eta < 1.0 {
        -1.4399 * eta * eta + 0.7099 * eta + 0.6681 + 0.0636 / eta
    } else {
        let x = 1.0 / eta;
        0.919_317 + x * (-3.4793 + x * (6.753_35 + x * (-7.809_89 + x * (4.985_54 + x * -1.368_81))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fit_matches_the_integral_of_fresnel() {
        // F_dr(η) = 2∫₀¹ F(μ, η) μ dμ, by a 20 000-point midpoint rule, against the fit (within
        // its stated 0.1 %, and 0.2 % where total internal reflection makes F jump).
        for eta in [1.0 / 1.5, 1.0 / 1.33, 1.33, 1.5] {
            let n = 20_000;
            let integral: f64 = (0..n)
                .map(|i| {
                    let mu = (i as f32 + 0.5) / n as f32;
                    f64::from(fresnel_dielectric(mu, eta) * mu)
                })
                .sum::<f64>()
                * 2.0
                / f64::from(n);
            let fit = f64::from(fresnel_diffuse_reflectance(eta));
            assert!((fit - integral).abs() < 2e-3 * integral, "η {eta}: fit {fit}, integral {integral}");
        }
    }

    #[test]
    fn samples_pick_the_coat_as_often_as_its_probability_and_weigh_the_base_by_its_pdf() {
        // From each angle: the share of coat samples is the coat probability p (within 4σ of a
        // binomial over n draws), each coat sample is the mirror direction with weight F·ks/p, and
        // each base sample's weight is f·cos/pdf with pdf() (f32 rounding: 1e-5).
        let p = SmoothPlastic { kd: Vec3::new(0.8, 0.5, 0.2), ks: Vec3::new(0.9, 0.6, 0.3), eta: 1.5, nonlinear: true };
        for cos in [1.0f32, 0.5, 0.1] {
            let wo = Vec3::new((1.0 - cos * cos).sqrt(), 0.0, cos);
            let prob = p.coat_probability(wo);
            let n: u64 = 20_000;
            let mut coats = 0u64;
            for k in 0..n {
                let u = [
                    (k as f32 + 0.5) / n as f32,
                    ((k * 7919) % n) as f32 / n as f32,
                    ((k * 104_729) % n) as f32 / n as f32,
                ];
                let s = p.sample(wo, u).expect("from above every sample scatters");
                if s.coat {
                    coats += 1;
                    let want = p.ks * fresnel_dielectric(cos, 1.5) / prob;
                    assert!((s.sample.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
                    assert!((s.sample.weight - want).abs().max_element() < 1e-5 * want.max_element());
                } else {
                    let want = p.base(wo, s.sample.wi) * FRAC_1_PI * s.sample.wi.z / p.pdf(wo, s.sample.wi);
                    assert!((s.sample.weight - want).abs().max_element() < 1e-5 * want.max_element().max(1e-3));
                }
            }
            let share = coats as f64 / n as f64;
            let sigma = (f64::from(prob) * (1.0 - f64::from(prob)) / n as f64).sqrt();
            assert!((share - f64::from(prob)).abs() < 4.0 * sigma + 1e-9, "cos {cos}: {share} against {prob}");
        }
    }

    #[test]
    fn a_white_plastic_never_gains_energy() {
        // Albedo from wo = E[weight] over the sampler; ≤ 1 at every angle (4 standard errors).
        let p = SmoothPlastic { kd: Vec3::ONE, ks: Vec3::ONE, eta: 1.5, nonlinear: false };
        for cos in [1.0f32, 0.7, 0.3, 0.05] {
            let wo = Vec3::new((1.0 - cos * cos).sqrt(), 0.0, cos);
            let n: u64 = 40_000;
            let (mut sum, mut sum2) = (0.0f64, 0.0f64);
            for k in 0..n {
                let u = [
                    (k as f32 + 0.5) / n as f32,
                    ((k * 7919) % n) as f32 / n as f32,
                    ((k * 104_729) % n) as f32 / n as f32,
                ];
                let w = p.sample(wo, u).map_or(0.0, |s| f64::from(s.sample.weight.x));
                sum += w;
                sum2 += w * w;
            }
            let mean = sum / n as f64;
            let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
            assert!(mean <= 1.0 + 4.0 * se, "cos {cos}: albedo {mean} ± {se}");
        }
    }
}
