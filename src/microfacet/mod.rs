//! Rough surfaces: microfacet distributions ([`distribution`]: GGX and Beckmann, isotropic or
//! not) with Smith's separable masking–shadowing G1(wo)·G1(wi) (Mitsuba 3's, so that its scenes
//! render as it does), sampled by their distributions of visible normals, for a rough conductor
//! (the exact Fresnel of a complex index, or Schlick's from a reflectance colour:
//! [`crate::optics`]), a rough dielectric (Walter et al. 2007: reflection and refraction through
//! the microfacets) and a rough plastic (Mitsuba 3's `roughplastic`: a dielectric coat over a
//! Lambertian base, with the coat's transmittance and internal reflection from [`coat`]).
//!
//! Every function works in a local frame whose z axis is the shading normal on the side of
//! `wo`; directions are unit vectors pointing away from the surface. Single scattering only:
//! light that bounces between microfacets is lost, so these never gain energy, and a very rough
//! surface is a little darker than a real one (at α = 1 a white conductor keeps about 80 % of
//! its light at normal incidence; the tests measure it).

use crate::optics::{fresnel_dielectric, refract};
use glam::Vec3;
use std::f32::consts::PI;

pub mod coat;
pub mod distribution;
pub use coat::{Coat, CoatAt};
pub use distribution::{Alpha, Distribution, MIN_ALPHA};

/// GGX α for a roughness in [0, 1] (the PBR convention: α = roughness², perceptually linear).
#[must_use]
pub fn alpha_of(roughness: f32) -> f32 {
    (roughness * roughness).max(MIN_ALPHA)
}

/// Masking–shadowing G2(ωo, ωi) = G1(ωo)·G1(ωi): Smith's separable form, as Mitsuba 3 has it
/// (pbrt-v4's height-correlated 1/(1 + Λo + Λi) is up to a few per cent larger at grazing
/// angles; Mitsuba's scenes were made with this one).
#[must_use]
pub fn g2(wo: Vec3, wi: Vec3, alpha: Alpha) -> f32 {
    alpha.g1(wo) * alpha.g1(wi)
}

/// A sampled direction of a rough surface, in the local frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalSample {
    /// Direction toward the next vertex.
    pub wi: Vec3,
    /// Its weight f·|cos θi|/pdf (radiance or power, as asked).
    pub weight: Vec3,
}

/// Rough conductor: f = F(wo·m)·D(m)·G2 / (4·wo.z·wi.z), m the half vector, `fresnel` F as a
/// function of wo·m; zero unless both directions lie above the surface.
#[must_use]
pub fn conductor_eval(wo: Vec3, wi: Vec3, fresnel: impl Fn(f32) -> Vec3, alpha: Alpha) -> Vec3 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return Vec3::ZERO;
    }
    let m = (wo + wi).normalize();
    fresnel(wo.dot(m)) * (alpha.d(m) * g2(wo, wi, alpha) / (4.0 * wo.z * wi.z))
}

/// The pdf of [`conductor_sample`]: D_wo(m)/(4·wo·m).
#[must_use]
pub fn conductor_pdf(wo: Vec3, wi: Vec3, alpha: Alpha) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let m = (wo + wi).normalize();
    alpha.visible_d(wo, m) / (4.0 * wo.dot(m))
}

/// Samples the rough conductor: a visible normal, then mirror reflection about it; weight
/// F·G2/G1(wo). `None` when the reflection falls below the surface.
#[must_use]
pub fn conductor_sample(wo: Vec3, fresnel: impl Fn(f32) -> Vec3, alpha: Alpha, u: [f32; 2]) -> Option<LocalSample> {
    let m = alpha.sample_visible_normal(wo, u);
    let wi = 2.0 * wo.dot(m) * m - wo;
    if wi.z <= 0.0 {
        return None;
    }
    let weight = fresnel(wo.dot(m)) * (g2(wo, wi, alpha) / alpha.g1(wo));
    Some(LocalSample { wi, weight })
}

/// The refraction from `wo` to `wi` (opposite sides), `eta` = η(wi side)/η(wo side): its
/// generalised half vector m turned to wo's side, wo·m and wi·m; `None` unless they lie on the
/// two sides of the microfacet, as refraction needs.
fn refraction_half(wo: Vec3, wi: Vec3, eta: f32) -> Option<(Vec3, f32, f32)> {
    let m = (-(wo + wi * eta)).try_normalize()?;
    let m = if m.z < 0.0 { -m } else { m };
    let (om, im) = (wo.dot(m), wi.dot(m));
    (om > 0.0 && im < 0.0).then_some((m, om, im))
}

/// Rough dielectric, radiance form: reflection F·D·G2/(4·wo.z·wi.z) on wo's side; refraction
/// (1−F)·D·G2·|wo·m||wi·m| / (wo.z·|wi.z|·(wo·m + η wi·m)²) through it, with `eta` =
/// η(wi side)/η(wo side). (For power, the refracted part is η² larger.)
#[must_use]
pub fn dielectric_eval(wo: Vec3, wi: Vec3, eta: f32, alpha: Alpha) -> f32 {
    if wo.z <= 0.0 || wi.z == 0.0 {
        return 0.0;
    }
    if wi.z > 0.0 {
        let m = (wo + wi).normalize();
        return fresnel_dielectric(wo.dot(m), eta) * alpha.d(m) * g2(wo, wi, alpha) / (4.0 * wo.z * wi.z);
    }
    let Some((m, om, im)) = refraction_half(wo, wi, eta) else { return 0.0 };
    let denom = om + eta * im;
    let f = 1.0 - fresnel_dielectric(om, eta);
    f * alpha.d(m) * g2(wo, -wi, alpha) * om * (-im) / (wo.z * (-wi.z) * denom * denom)
}

/// The pdf of [`dielectric_sample`] for `wi`.
#[must_use]
pub fn dielectric_pdf(wo: Vec3, wi: Vec3, eta: f32, alpha: Alpha) -> f32 {
    if wo.z <= 0.0 || wi.z == 0.0 {
        return 0.0;
    }
    if wi.z > 0.0 {
        let m = (wo + wi).normalize();
        return fresnel_dielectric(wo.dot(m), eta) * alpha.visible_d(wo, m) / (4.0 * wo.dot(m));
    }
    let Some((m, om, im)) = refraction_half(wo, wi, eta) else { return 0.0 };
    let denom = om + eta * im;
    (1.0 - fresnel_dielectric(om, eta)) * alpha.visible_d(wo, m) * eta * eta * (-im) / (denom * denom)
}

/// Samples the rough dielectric: a visible normal, then reflection with probability F(wo·m),
/// refraction otherwise; weight G2/G1(wo), times 1/η² for radiance through refraction. `None`
/// when the sampled direction falls on the wrong side.
#[must_use]
pub fn dielectric_sample(wo: Vec3, eta: f32, alpha: Alpha, u: [f32; 3], radiance: bool) -> Option<LocalSample> {
    let m = alpha.sample_visible_normal(wo, [u[0], u[1]]);
    let om = wo.dot(m);
    let f = fresnel_dielectric(om, eta);
    if u[2] < f {
        let wi = 2.0 * om * m - wo;
        if wi.z <= 0.0 {
            return None;
        }
        return Some(LocalSample { wi, weight: Vec3::splat(g2(wo, wi, alpha) / alpha.g1(wo)) });
    }
    let wi = refract(wo, m, eta)?;
    if wi.z >= 0.0 {
        return None;
    }
    let scale = if radiance { 1.0 / (eta * eta) } else { 1.0 };
    Some(LocalSample { wi, weight: Vec3::splat(g2(wo, -wi, alpha) / alpha.g1(wo) * scale) })
}

/// A rough plastic at a point (Mitsuba 3's `roughplastic`): a microfacet dielectric coat of width
/// `alpha` over a Lambertian base `kd`, the coat's index ratio and tables in `coat`.
/// f = ks·F(wo·m)·D·G2/(4·wo.z·wi.z) + kd′·T(wo.z)·T(wi.z)/(π η²): the coat reflects by its
/// microfacets; light crosses it into the base and back out (T each way, T the rough coat's
/// transmittance), is spread over the solid angle inside (1/η²), and bounces between the base and
/// the coat's underside (kd′ = kd / (1 − F_dr), or kd / (1 − kd·F_dr) when `nonlinear`).
#[derive(Clone, Copy, Debug)]
pub struct Plastic {
    /// Base albedo.
    pub kd: Vec3,
    /// The coat reflection's scale (Mitsuba's `specular_reflectance`).
    pub ks: Vec3,
    /// The coat's tables and index ratio.
    pub coat: CoatAt,
    /// The coat's distribution and width at this point.
    pub alpha: Alpha,
    /// Whether the base's internal bounces tint by kd (Mitsuba's `nonlinear`).
    pub nonlinear: bool,
}

impl Plastic {
    /// f(wo, wi): coat and base; zero unless both lie above the surface.
    #[must_use]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        self.ks * plastic_coat_eval(wo, wi, self.coat.eta, self.alpha) + self.base(wo, wi) / PI
    }

    /// The base's share times π: kd′·T(wo.z)·T(wi.z)/η² (the weight of a cosine-sampled
    /// direction through the base alone).
    #[must_use]
    pub fn base(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        let c = self.coat;
        c.base_albedo(self.kd, self.nonlinear) * (c.transmittance(wo.z) * c.transmittance(wi.z) / (c.eta * c.eta))
    }

    /// Probability of sampling the coat rather than the base from `wo`, as Mitsuba weighs them:
    /// (1 − T(wo.z))·w against T(wo.z)·(1 − w), w = mean(ks)/(mean(ks) + mean(kd)).
    #[must_use]
    pub fn coat_probability(&self, wo: Vec3) -> f32 {
        let (s, d) = (self.ks.element_sum(), self.kd.element_sum());
        let w = if s + d > 0.0 { s / (s + d) } else { 1.0 };
        let t = self.coat.transmittance(wo.z);
        let (coat, base) = ((1.0 - t) * w, t * (1.0 - w));
        if coat + base > 0.0 {
            coat / (coat + base)
        } else {
            1.0
        }
    }

    /// The pdf of [`Plastic::sample`].
    #[must_use]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        self.mixture_pdf(self.coat_probability(wo), wo, wi)
    }

    /// The pdf of choosing the coat with probability `p`, the base otherwise.
    fn mixture_pdf(&self, p: f32, wo: Vec3, wi: Vec3) -> f32 {
        p * plastic_coat_pdf(wo, wi, self.alpha) + (1.0 - p) * wi.z / PI
    }

    /// Samples the coat (a visible normal, reflection about it) or the base (cosine-weighted),
    /// chosen by [`Plastic::coat_probability`]; weight f·cos/pdf of the mixture.
    #[must_use]
    pub fn sample(&self, wo: Vec3, u: [f32; 3]) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let p = self.coat_probability(wo);
        let wi = if u[2] < p {
            let m = self.alpha.sample_visible_normal(wo, [u[0], u[1]]);
            2.0 * wo.dot(m) * m - wo
        } else {
            crate::sampling::cosine_hemisphere([u[0], u[1]])
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.mixture_pdf(p, wo, wi);
        if !(pdf > 0.0) {
            return None;
        }
        Some(LocalSample { wi, weight: self.eval(wo, wi) * (wi.z / pdf) })
    }
}

/// The plastic's coat alone (its glossy lobe): F(wo·m)·D(m)·G2 / (4·wo.z·wi.z).
#[must_use]
pub fn plastic_coat_eval(wo: Vec3, wi: Vec3, eta: f32, alpha: Alpha) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    plastic_coat_above(wo, wi, eta, alpha, alpha.g1(wo))
}

/// [`plastic_coat_eval`] for `wo` and `wi` both above the surface, given G1(wo) (the same value
/// to the bit: G2 = G1(wo)·G1(wi)); for many `wi` toward one `wo`.
#[inline]
#[must_use]
pub fn plastic_coat_above(wo: Vec3, wi: Vec3, eta: f32, alpha: Alpha, g1_wo: f32) -> f32 {
    let m = (wo + wi).normalize();
    let g2 = g1_wo * alpha.g1(wi);
    fresnel_dielectric(wo.dot(m), eta) * alpha.d(m) * g2 / (4.0 * wo.z * wi.z)
}

/// The pdf of [`plastic_coat_sample`]: D_wo(m)/(4·wo·m), as the conductor's.
#[must_use]
pub fn plastic_coat_pdf(wo: Vec3, wi: Vec3, alpha: Alpha) -> f32 {
    conductor_pdf(wo, wi, alpha)
}

/// Samples the plastic's coat alone (its glossy lobe): weight F(wo·m)·G2/G1(wo).
#[must_use]
pub fn plastic_coat_sample(wo: Vec3, eta: f32, alpha: Alpha, u: [f32; 2]) -> Option<LocalSample> {
    let m = alpha.sample_visible_normal(wo, u);
    let wi = 2.0 * wo.dot(m) * m - wo;
    if wi.z <= 0.0 {
        return None;
    }
    let f = fresnel_dielectric(wo.dot(m), eta);
    Some(LocalSample { wi, weight: Vec3::splat(f * g2(wo, wi, alpha) / alpha.g1(wo)) })
}
