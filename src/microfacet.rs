//! Rough surfaces: the GGX (Trowbridge–Reitz) microfacet distribution with Smith's
//! height-correlated masking–shadowing, sampled by its distribution of visible normals (Heitz
//! 2018), for a rough conductor (Schlick's Fresnel from a reflectance colour), a rough
//! dielectric (Walter et al. 2007: reflection and refraction through the microfacets) and a
//! rough plastic (a dielectric coat over a Lambertian base).
//!
//! Every function works in a local frame whose z axis is the shading normal on the side of
//! `wo`; directions are unit vectors pointing away from the surface. Single scattering only:
//! light that bounces between microfacets is lost, so these never gain energy, and a very rough
//! surface is a little darker than a real one (at α = 1 a white conductor keeps about 80 % of
//! its light at normal incidence; the tests measure it).

use crate::optics::{fresnel_dielectric, refract};
use glam::Vec3;
use std::f32::consts::PI;

/// The smallest α used: below it D's peak overflows f32 arithmetic in `eval`.
pub const MIN_ALPHA: f32 = 1e-3;

/// GGX α for a roughness in [0, 1] (the PBR convention: α = roughness², perceptually linear).
#[must_use]
pub fn alpha_of(roughness: f32) -> f32 {
    (roughness * roughness).max(MIN_ALPHA)
}

/// The microfacet distribution D(m) for a local normal `m` (m.z > 0).
#[must_use]
pub fn d(m: Vec3, alpha: f32) -> f32 {
    if m.z <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let t = m.z * m.z * (a2 - 1.0) + 1.0;
    a2 / (PI * t * t)
}

/// Smith's Λ(ω) for GGX.
#[must_use]
pub fn lambda(w: Vec3, alpha: f32) -> f32 {
    let cos2 = w.z * w.z;
    if cos2 <= 0.0 {
        return f32::INFINITY;
    }
    let tan2 = ((1.0 - cos2) / cos2).max(0.0);
    0.5 * (-1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// Masking G1(ω).
#[must_use]
pub fn g1(w: Vec3, alpha: f32) -> f32 {
    1.0 / (1.0 + lambda(w, alpha))
}

/// Height-correlated masking–shadowing G2(ωo, ωi).
#[must_use]
pub fn g2(wo: Vec3, wi: Vec3, alpha: f32) -> f32 {
    1.0 / (1.0 + lambda(wo, alpha) + lambda(wi, alpha))
}

/// The density of visible normals seen from `wo`: G1(wo)·max(0, wo·m)·D(m)/wo.z.
#[must_use]
pub fn visible_d(wo: Vec3, m: Vec3, alpha: f32) -> f32 {
    if wo.z <= 0.0 {
        return 0.0;
    }
    g1(wo, alpha) * wo.dot(m).max(0.0) * d(m, alpha) / wo.z
}

/// A microfacet normal sampled from the visible normals seen from `wo` (wo.z > 0), two uniform
/// numbers (Heitz 2018, "Sampling the GGX distribution of visible normals").
#[must_use]
pub fn sample_visible_normal(wo: Vec3, alpha: f32, u: [f32; 2]) -> Vec3 {
    // The view direction in the hemisphere configuration (α stretched to 1).
    let vh = Vec3::new(alpha * wo.x, alpha * wo.y, wo.z).normalize();
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 { Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt() } else { Vec3::X };
    let t2 = vh.cross(t1);
    let r = u[0].sqrt();
    let phi = 2.0 * PI * u[1];
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(1e-6)).normalize()
}

/// Schlick's Fresnel for a conductor of normal-incidence reflectance `f0`.
#[must_use]
pub fn schlick(f0: Vec3, cos: f32) -> Vec3 {
    let c = (1.0 - cos.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::ONE - f0) * c
}

/// A sampled direction of a rough surface, in the local frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalSample {
    /// Direction toward the next vertex.
    pub wi: Vec3,
    /// Its weight f·|cos θi|/pdf (radiance or power, as asked).
    pub weight: Vec3,
}

/// Rough conductor: f = F(wo·m)·D(m)·G2 / (4·wo.z·wi.z), m the half vector; zero unless both
/// directions lie above the surface.
#[must_use]
pub fn conductor_eval(wo: Vec3, wi: Vec3, f0: Vec3, alpha: f32) -> Vec3 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return Vec3::ZERO;
    }
    let m = (wo + wi).normalize();
    schlick(f0, wo.dot(m)) * (d(m, alpha) * g2(wo, wi, alpha) / (4.0 * wo.z * wi.z))
}

/// The pdf of [`conductor_sample`]: D_wo(m)/(4·wo·m).
#[must_use]
pub fn conductor_pdf(wo: Vec3, wi: Vec3, alpha: f32) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let m = (wo + wi).normalize();
    visible_d(wo, m, alpha) / (4.0 * wo.dot(m))
}

/// Samples the rough conductor: a visible normal, then mirror reflection about it; weight
/// F·G2/G1(wo). `None` when the reflection falls below the surface.
#[must_use]
pub fn conductor_sample(wo: Vec3, f0: Vec3, alpha: f32, u: [f32; 2]) -> Option<LocalSample> {
    let m = sample_visible_normal(wo, alpha, u);
    let wi = 2.0 * wo.dot(m) * m - wo;
    if wi.z <= 0.0 {
        return None;
    }
    let weight = schlick(f0, wo.dot(m)) * (g2(wo, wi, alpha) / g1(wo, alpha));
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
pub fn dielectric_eval(wo: Vec3, wi: Vec3, eta: f32, alpha: f32) -> f32 {
    if wo.z <= 0.0 || wi.z == 0.0 {
        return 0.0;
    }
    if wi.z > 0.0 {
        let m = (wo + wi).normalize();
        return fresnel_dielectric(wo.dot(m), eta) * d(m, alpha) * g2(wo, wi, alpha) / (4.0 * wo.z * wi.z);
    }
    let Some((m, om, im)) = refraction_half(wo, wi, eta) else { return 0.0 };
    let denom = om + eta * im;
    let f = 1.0 - fresnel_dielectric(om, eta);
    f * d(m, alpha) * g2(wo, -wi, alpha) * om * (-im) / (wo.z * (-wi.z) * denom * denom)
}

/// The pdf of [`dielectric_sample`] for `wi`.
#[must_use]
pub fn dielectric_pdf(wo: Vec3, wi: Vec3, eta: f32, alpha: f32) -> f32 {
    if wo.z <= 0.0 || wi.z == 0.0 {
        return 0.0;
    }
    if wi.z > 0.0 {
        let m = (wo + wi).normalize();
        return fresnel_dielectric(wo.dot(m), eta) * visible_d(wo, m, alpha) / (4.0 * wo.dot(m));
    }
    let Some((m, om, im)) = refraction_half(wo, wi, eta) else { return 0.0 };
    let denom = om + eta * im;
    (1.0 - fresnel_dielectric(om, eta)) * visible_d(wo, m, alpha) * eta * eta * (-im) / (denom * denom)
}

/// Samples the rough dielectric: a visible normal, then reflection with probability F(wo·m),
/// refraction otherwise; weight G2/G1(wo), times 1/η² for radiance through refraction. `None`
/// when the sampled direction falls on the wrong side.
#[must_use]
pub fn dielectric_sample(wo: Vec3, eta: f32, alpha: f32, u: [f32; 3], radiance: bool) -> Option<LocalSample> {
    let m = sample_visible_normal(wo, alpha, [u[0], u[1]]);
    let om = wo.dot(m);
    let f = fresnel_dielectric(om, eta);
    if u[2] < f {
        let wi = 2.0 * om * m - wo;
        if wi.z <= 0.0 {
            return None;
        }
        return Some(LocalSample { wi, weight: Vec3::splat(g2(wo, wi, alpha) / g1(wo, alpha)) });
    }
    let wi = refract(wo, m, eta)?;
    if wi.z >= 0.0 {
        return None;
    }
    let scale = if radiance { 1.0 / (eta * eta) } else { 1.0 };
    Some(LocalSample { wi, weight: Vec3::splat(g2(wo, -wi, alpha) / g1(wo, alpha) * scale) })
}

/// Rough plastic: a GGX dielectric coat of relative index `eta` over a Lambertian base `kd`.
/// f = F(wo·m)·D·G2/(4·wo.z·wi.z) + kd/π·(1 − F(wo.z))·(1 − F(wi.z)): the coat reflects by its
/// microfacets; light that enters it (1 − F on the way in and out) meets the base. Reciprocal;
/// it never gains energy (the coat's light and the base's share of what the coat lets through
/// sum to at most 1; the tests measure it). Light bouncing between the base and the coat's
/// underside is not followed, so a plastic is slightly darker than a real one.
#[must_use]
pub fn plastic_eval(wo: Vec3, wi: Vec3, kd: Vec3, eta: f32, alpha: f32) -> Vec3 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return Vec3::ZERO;
    }
    let m = (wo + wi).normalize();
    let coat = fresnel_dielectric(wo.dot(m), eta) * d(m, alpha) * g2(wo, wi, alpha) / (4.0 * wo.z * wi.z);
    Vec3::splat(coat) + plastic_base(wo, wi, kd, eta) / PI
}

/// The base's share times π: kd·(1 − F(wo.z))·(1 − F(wi.z)) (the weight of a cosine-sampled
/// direction through the base alone).
#[must_use]
pub fn plastic_base(wo: Vec3, wi: Vec3, kd: Vec3, eta: f32) -> Vec3 {
    kd * ((1.0 - fresnel_dielectric(wo.z, eta)) * (1.0 - fresnel_dielectric(wi.z, eta)))
}

/// Probability of sampling the plastic's coat rather than its base from `wo`: F(wo.z) against
/// (1 − F(wo.z))·mean(kd).
fn plastic_coat_probability(wo: Vec3, kd: Vec3, eta: f32) -> f32 {
    let f = fresnel_dielectric(wo.z, eta);
    let base = (1.0 - f) * kd.element_sum() / 3.0;
    if f + base > 0.0 {
        f / (f + base)
    } else {
        1.0
    }
}

/// The pdf of [`plastic_sample`].
#[must_use]
pub fn plastic_pdf(wo: Vec3, wi: Vec3, kd: Vec3, eta: f32, alpha: f32) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let p = plastic_coat_probability(wo, kd, eta);
    let m = (wo + wi).normalize();
    p * visible_d(wo, m, alpha) / (4.0 * wo.dot(m)) + (1.0 - p) * wi.z / PI
}

/// Samples the rough plastic: its coat (a visible normal, reflection about it) or its base
/// (cosine-weighted), chosen by `plastic_coat_probability`; weight f·cos/pdf of the mixture.
#[must_use]
pub fn plastic_sample(wo: Vec3, kd: Vec3, eta: f32, alpha: f32, u: [f32; 3]) -> Option<LocalSample> {
    let p = plastic_coat_probability(wo, kd, eta);
    let wi = if u[2] < p {
        let m = sample_visible_normal(wo, alpha, [u[0], u[1]]);
        2.0 * wo.dot(m) * m - wo
    } else {
        crate::sampling::cosine_hemisphere([u[0], u[1]])
    };
    if wi.z <= 0.0 {
        return None;
    }
    let pdf = plastic_pdf(wo, wi, kd, eta, alpha);
    if !(pdf > 0.0) {
        return None;
    }
    Some(LocalSample { wi, weight: plastic_eval(wo, wi, kd, eta, alpha) * (wi.z / pdf) })
}

/// The plastic's coat alone (its glossy lobe): F(wo·m)·D(m)·G2 / (4·wo.z·wi.z).
#[must_use]
pub fn plastic_coat_eval(wo: Vec3, wi: Vec3, eta: f32, alpha: f32) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let m = (wo + wi).normalize();
    fresnel_dielectric(wo.dot(m), eta) * d(m, alpha) * g2(wo, wi, alpha) / (4.0 * wo.z * wi.z)
}

/// The pdf of [`plastic_coat_sample`]: D_wo(m)/(4·wo·m), as the conductor's.
#[must_use]
pub fn plastic_coat_pdf(wo: Vec3, wi: Vec3, alpha: f32) -> f32 {
    conductor_pdf(wo, wi, alpha)
}

/// Samples the plastic's coat alone (its glossy lobe): weight F(wo·m)·G2/G1(wo).
#[must_use]
pub fn plastic_coat_sample(wo: Vec3, eta: f32, alpha: f32, u: [f32; 2]) -> Option<LocalSample> {
    let m = sample_visible_normal(wo, alpha, u);
    let wi = 2.0 * wo.dot(m) * m - wo;
    if wi.z <= 0.0 {
        return None;
    }
    let f = fresnel_dielectric(wo.dot(m), eta);
    Some(LocalSample { wi, weight: Vec3::splat(f * g2(wo, wi, alpha) / g1(wo, alpha)) })
}
