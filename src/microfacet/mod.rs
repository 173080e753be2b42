//! Rough surfaces: the GGX (Trowbridge–Reitz) microfacet distribution with Smith's separable
//! masking–shadowing G1(wo)·G1(wi) (Mitsuba 3's, so that its scenes render as it does), sampled
//! by its distribution of visible normals (Heitz 2018), for a rough conductor (the exact Fresnel
//! of a complex index, or Schlick's from a reflectance colour: [`crate::optics`]), a rough
//! dielectric (Walter et al. 2007: reflection and refraction through the microfacets) and a rough
//! plastic (Mitsuba 3's `roughplastic`: a dielectric coat over a Lambertian base, with the coat's
//! transmittance and internal reflection from [`coat`]).
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
pub use coat::{Coat, CoatAt};

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
    // m.z²(α² − 1) + 1 written with the sine² as m.x² + m.y², not 1 − m.z²: near the peak of
    // a narrow lobe 1 − m.z² cancels to a few ulps and D would be off by per cents.
    let a2 = alpha * alpha;
    let t = m.x * m.x + m.y * m.y + a2 * m.z * m.z;
    a2 / (PI * t * t)
}

/// Smith's Λ(ω) for GGX.
#[must_use]
pub fn lambda(w: Vec3, alpha: f32) -> f32 {
    let cos2 = w.z * w.z;
    if cos2 <= 0.0 {
        return f32::INFINITY;
    }
    // The sine² from x and y (1 − cos² cancels near the normal).
    let tan2 = (w.x * w.x + w.y * w.y) / cos2;
    0.5 * (-1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// Masking G1(ω).
#[must_use]
pub fn g1(w: Vec3, alpha: f32) -> f32 {
    1.0 / (1.0 + lambda(w, alpha))
}

/// Masking–shadowing G2(ωo, ωi) = G1(ωo)·G1(ωi): Smith's separable form, as Mitsuba 3 has it
/// (pbrt-v4's height-correlated 1/(1 + Λo + Λi) is up to a few per cent larger at grazing
/// angles; Mitsuba's scenes were made with this one).
#[must_use]
pub fn g2(wo: Vec3, wi: Vec3, alpha: f32) -> f32 {
    g1(wo, alpha) * g1(wi, alpha)
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
pub fn conductor_eval(wo: Vec3, wi: Vec3, fresnel: impl Fn(f32) -> Vec3, alpha: f32) -> Vec3 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return Vec3::ZERO;
    }
    let m = (wo + wi).normalize();
    fresnel(wo.dot(m)) * (d(m, alpha) * g2(wo, wi, alpha) / (4.0 * wo.z * wi.z))
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
pub fn conductor_sample(wo: Vec3, fresnel: impl Fn(f32) -> Vec3, alpha: f32, u: [f32; 2]) -> Option<LocalSample> {
    let m = sample_visible_normal(wo, alpha, u);
    let wi = 2.0 * wo.dot(m) * m - wo;
    if wi.z <= 0.0 {
        return None;
    }
    let weight = fresnel(wo.dot(m)) * (g2(wo, wi, alpha) / g1(wo, alpha));
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

/// A rough plastic at a point (Mitsuba 3's `roughplastic`): a GGX dielectric coat of width
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
    /// The coat's GGX width at this point.
    pub alpha: f32,
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
            let m = sample_visible_normal(wo, self.alpha, [u[0], u[1]]);
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
