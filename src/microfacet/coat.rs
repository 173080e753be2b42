//! The dielectric coat of a rough plastic as Mitsuba 3's `roughplastic` precomputes it: the
//! coat's transmittance T(cos θ) from outside, tabulated at 64 equally spaced cosines and read by
//! linear interpolation, and its internal diffuse reflectance F_dr (light from the base reflected
//! back down by the coat's underside, total internal reflection included). The base's BSDF is
//! then kd′·T(θo)·T(θi) / (π η²), kd′ = kd / (1 − F_dr) or, `nonlinear`, kd / (1 − kd·F_dr)
//! ([`crate::microfacet::Plastic::base`]).
//!
//! Both come from the rough interface's single scattering over the normals m visible from wo
//! (cos θo = μ): its transmittance T(μ, η) = E_m[(1 − F(wo·m)) · G1(wt) · [wt below]], wt the
//! refraction through m, and its reflectance R(μ, η) = E_m[F(wo·m) · G1(wr) · [wr above]], wr
//! the reflection about m (light the microfacets shadow is in neither). Each is integrated by
//! Gauss–Legendre quadrature over the visible-normal sampler's unit square: 32 × 32 nodes from
//! outside (η > 1), 128 × 128 from inside, where total internal reflection makes the integrand
//! jump. The table holds T(μ, η); F_dr = 2 · mean over the 64 table cosines of μ·R(μ, 1/η)
//! (Mitsuba's own discretisation, kept so that the base matches it).
//!
//! Reads η and the microfacets; writes [`Coat`]s, built once per (η, distribution, α) and shared for the process's life
//! ([`Coat::get`]): a scene has a handful, a roughness texture at most [`ROUGHNESS_LEVELS`] per η and
//! distribution
//! ([`CoatAt::at`]).

use super::{Alpha, Distribution, MIN_ALPHA};
use crate::optics::{fresnel_dielectric, refract};
use glam::Vec3;
use std::collections::HashMap;
use std::sync::{OnceLock, RwLock};

/// Cosines in the transmittance table (Mitsuba's `MI_ROUGH_TRANSMITTANCE_RES`).
pub const TRANSMITTANCE_RES: usize = 64;

/// Roughness levels (α = roughness², equally spaced in roughness) a textured coat's tables are
/// blended from: a point's α reads the two levels around it, its own α shapes the coat's lobe.
pub const ROUGHNESS_LEVELS: u32 = 64;

/// A plastic's coat: index ratio, width and the tables of the base's light through it.
#[derive(Clone, Debug, PartialEq)]
pub struct Coat {
    /// η(inside) / η(outside).
    pub eta: f32,
    /// The coat's microfacets (isotropic).
    pub alpha: Alpha,
    /// T(μ) at μ = i / 63 (μ = 0 taken as 10⁻⁶).
    pub transmittance: [f32; TRANSMITTANCE_RES],
    /// F_dr: the share of the base's (cosine-distributed) light the coat sends back down.
    pub internal_reflectance: f32,
}

impl Coat {
    /// Computes the tables for relative index `eta` (> 0) and microfacets `alpha`.
    #[must_use]
    pub fn new(eta: f32, alpha: Alpha) -> Coat {
        let mu = |i: usize| (i as f32 / (TRANSMITTANCE_RES - 1) as f32).max(1e-6);
        let outside = GaussLegendre::new(if eta > 1.0 { 32 } else { 128 });
        let inside = GaussLegendre::new(if 1.0 / eta > 1.0 { 32 } else { 128 });
        // Each cosine's two integrals, on a few threads (a Beckmann coat's sampler inverts its
        // slope distribution by Newton's method: a million of them take half a second on one
        // core); summed in cosine order whatever the threads.
        let rows = per_cosine(|i| {
            (
                rough_transmittance(mu(i), eta, alpha, &outside),
                rough_reflectance(mu(i), 1.0 / eta, alpha, &inside) * mu(i),
            )
        });
        let transmittance = std::array::from_fn(|i| rows[i].0);
        let sum: f64 = rows.iter().map(|r| f64::from(r.1)).sum();
        let internal_reflectance = (2.0 * sum / TRANSMITTANCE_RES as f64) as f32;
        Coat { eta, alpha, transmittance, internal_reflectance }
    }

    /// The coat for (`eta`, `alpha`), computed on first use and kept: every material and every
    /// point of one (η, distribution, α) shares it.
    #[must_use]
    pub fn get(eta: f32, alpha: Alpha) -> &'static Coat {
        type Key = (u32, Distribution, u32, u32);
        static COATS: OnceLock<RwLock<HashMap<Key, &'static Coat>>> = OnceLock::new();
        let key = (eta.to_bits(), alpha.distribution, alpha.u.to_bits(), alpha.v.to_bits());
        let coats = COATS.get_or_init(Default::default);
        if let Some(c) = coats.read().unwrap_or_else(std::sync::PoisonError::into_inner).get(&key) {
            return c;
        }
        let made = Coat::new(eta, alpha);
        let mut all = coats.write().unwrap_or_else(std::sync::PoisonError::into_inner);
        all.entry(key).or_insert_with(|| Box::leak(Box::new(made)))
    }

    /// T(cos θ): the table linearly interpolated (cos θ in [0, 1]).
    #[must_use]
    pub fn transmittance(&self, cos: f32) -> f32 {
        let x = cos.clamp(0.0, 1.0) * (TRANSMITTANCE_RES - 1) as f32;
        let i = (x as usize).min(TRANSMITTANCE_RES - 2);
        let w = x - i as f32;
        (1.0 - w) * self.transmittance[i] + w * self.transmittance[i + 1]
    }
}

/// The [`ROUGHNESS_LEVELS`] coats of one η and distribution, each computed on its first use: found once per
/// material ([`CoatAt::new`]), so that a textured point reads them without the shared map's lock.
#[derive(Debug)]
pub struct Levels {
    eta: f32,
    distribution: Distribution,
    coats: [OnceLock<&'static Coat>; ROUGHNESS_LEVELS as usize],
}

impl PartialEq for Levels {
    /// One per η: the same levels are the same object.
    fn eq(&self, other: &Levels) -> bool {
        std::ptr::eq(self, other)
    }
}

impl Levels {
    /// The levels of `eta` and `distribution`, made on first use and kept.
    fn of(eta: f32, distribution: Distribution) -> &'static Levels {
        static LEVELS: OnceLock<RwLock<HashMap<(u32, Distribution), &'static Levels>>> = OnceLock::new();
        let all = LEVELS.get_or_init(Default::default);
        let key = (eta.to_bits(), distribution);
        if let Some(l) = all.read().unwrap_or_else(std::sync::PoisonError::into_inner).get(&key) {
            return l;
        }
        let mut all = all.write().unwrap_or_else(std::sync::PoisonError::into_inner);
        all.entry(key).or_insert_with(|| {
            Box::leak(Box::new(Levels { eta, distribution, coats: std::array::from_fn(|_| OnceLock::new()) }))
        })
    }

    /// Level `k`: the coat of α = (k / (levels − 1))².
    fn level(&self, k: u32) -> &'static Coat {
        let steps = (ROUGHNESS_LEVELS - 1) as f32;
        self.coats[k as usize]
            .get_or_init(|| Coat::get(self.eta, Alpha::new(self.distribution, (k as f32 / steps).powi(2))))
    }
}

/// The coat a plastic reads at a point: its own (η, α) coat, or for a textured roughness the two
/// roughness levels around the point's α, blended linearly in roughness (√α).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoatAt {
    /// η(inside) / η(outside).
    pub eta: f32,
    lower: &'static Coat,
    upper: &'static Coat,
    blend: f32,
    levels: &'static Levels,
}

impl CoatAt {
    /// The coat of exactly (`eta`, `alpha`) ([`Coat::get`]).
    #[must_use]
    pub fn new(eta: f32, alpha: Alpha) -> CoatAt {
        let c = Coat::get(eta, alpha);
        CoatAt { eta, lower: c, upper: c, blend: 0.0, levels: Levels::of(eta, alpha.distribution) }
    }

    /// This coat's η and distribution at a point whose roughness a texture sets: the
    /// [`ROUGHNESS_LEVELS`] levels on either side of √`alpha`, so that a texture needs at most
    /// that many tables per η and distribution.
    #[must_use]
    pub fn at(&self, alpha: f32) -> CoatAt {
        let steps = (ROUGHNESS_LEVELS - 1) as f32;
        let x = alpha.max(MIN_ALPHA).sqrt().min(1.0) * steps;
        let k = (x.floor() as u32).min(ROUGHNESS_LEVELS - 2);
        let l = self.levels;
        CoatAt {
            eta: self.eta,
            lower: l.level(k),
            upper: l.level(k + 1),
            blend: (x - k as f32).clamp(0.0, 1.0),
            levels: l,
        }
    }

    /// T(cos θ).
    #[must_use]
    pub fn transmittance(&self, cos: f32) -> f32 {
        let t = self.lower.transmittance(cos);
        if self.blend == 0.0 {
            return t;
        }
        t + self.blend * (self.upper.transmittance(cos) - t)
    }

    /// F_dr.
    #[must_use]
    pub fn internal_reflectance(&self) -> f32 {
        let f = self.lower.internal_reflectance;
        f + self.blend * (self.upper.internal_reflectance - f)
    }

    /// kd′: the base's albedo divided by what the coat's underside sends back,
    /// kd / (1 − F_dr), or kd / (1 − kd·F_dr) when `nonlinear`.
    #[must_use]
    pub fn base_albedo(&self, kd: Vec3, nonlinear: bool) -> Vec3 {
        let f_dr = self.internal_reflectance();
        let back = if nonlinear { kd * f_dr } else { Vec3::splat(f_dr) };
        kd / (Vec3::ONE - back)
    }
}

/// `row(i)` for each table cosine i, in order, computed on up to 8 scoped threads (fresh ones:
/// a coat may be built inside a render's worker, where the pool is busy).
fn per_cosine(row: impl Fn(usize) -> (f32, f32) + Sync) -> Vec<(f32, f32)> {
    let threads = std::thread::available_parallelism().map_or(1, std::num::NonZero::get).clamp(1, 8);
    let chunk = TRANSMITTANCE_RES.div_ceil(threads);
    let row = &row;
    std::thread::scope(|scope| {
        let parts: Vec<_> = (0..TRANSMITTANCE_RES)
            .step_by(chunk)
            .map(|start| {
                scope.spawn(move || (start..(start + chunk).min(TRANSMITTANCE_RES)).map(row).collect::<Vec<_>>())
            })
            .collect();
        parts.into_iter().flat_map(|p| p.join().unwrap_or_else(|e| std::panic::resume_unwind(e))).collect()
    })
}

/// Gauss–Legendre nodes and weights on [0, 1].
struct GaussLegendre {
    nodes: Vec<f32>,
    weights: Vec<f32>,
}

impl GaussLegendre {
    /// `n` nodes: the roots of the Legendre polynomial P_n by Newton's iteration from
    /// cos(π(i + ¾)/(n + ½)), weights 2/((1 − x²)P_n′(x)²), mapped from [−1, 1] to [0, 1].
    fn new(n: usize) -> GaussLegendre {
        let (mut nodes, mut weights) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for i in 0..n {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                // P_n(x) and P_n'(x) by the three-term recurrence.
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    (p0, p1) = (p1, p2);
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let step = p1 / dp;
                x -= step;
                if step.abs() < 1e-15 {
                    break;
                }
            }
            nodes.push((0.5 * (x + 1.0)) as f32);
            weights.push((1.0 / ((1.0 - x * x) * dp * dp)) as f32);
        }
        GaussLegendre { nodes, weights }
    }
}

/// E_m[scattered(wo, m)] over the normals visible from the direction at cos θ = μ: the
/// quadrature `q` over the sampler's unit square.
fn visible_mean(mu: f32, alpha: Alpha, q: &GaussLegendre, scattered: impl Fn(Vec3, Vec3) -> f32) -> f32 {
    let wo = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let mut sum = 0.0f64;
    for (&u, &wu) in q.nodes.iter().zip(&q.weights) {
        for (&v, &wv) in q.nodes.iter().zip(&q.weights) {
            let m = alpha.sample_visible_normal(wo, [u, v]);
            sum += f64::from(scattered(wo, m) * wu * wv);
        }
    }
    sum as f32
}

/// R(μ, η): the rough interface's single-scattering reflectance (see the module doc).
fn rough_reflectance(mu: f32, eta: f32, alpha: Alpha, q: &GaussLegendre) -> f32 {
    visible_mean(mu, alpha, q, |wo, m| {
        let wr = 2.0 * wo.dot(m) * m - wo;
        if wr.z <= 0.0 {
            return 0.0;
        }
        fresnel_dielectric(wo.dot(m), eta) * alpha.g1(wr)
    })
}

/// T(μ, η): the rough interface's single-scattering transmittance (see the module doc).
fn rough_transmittance(mu: f32, eta: f32, alpha: Alpha, q: &GaussLegendre) -> f32 {
    visible_mean(mu, alpha, q, |wo, m| match refract(wo, m, eta) {
        Some(wt) if wt.z < 0.0 => (1.0 - fresnel_dielectric(wo.dot(m), eta)) * alpha.g1(-wt),
        _ => 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        // n nodes integrate degree 2n − 1 exactly: ∫₀¹ x^k dx = 1/(k + 1).
        let q = GaussLegendre::new(8);
        for k in 0..16 {
            let s: f32 = q.nodes.iter().zip(&q.weights).map(|(x, w)| w * x.powi(k)).sum();
            assert!((s - 1.0 / (k + 1) as f32).abs() < 1e-6, "x^{k}: {s}");
        }
    }

    #[test]
    fn a_near_smooth_coat_transmits_one_minus_fresnel() {
        // At α = 10⁻³ the coat is a smooth interface: T(μ) = 1 − F(μ), and F_dr is the smooth
        // interface's internal diffuse reflectance for η = 1.5 (0.596 by 2∫ F(μ, 1/η) μ dμ; the
        // 64-point mean Mitsuba uses puts it within 0.01).
        let coat = Coat::new(1.5, Alpha::ggx(MIN_ALPHA));
        for i in [8, 32, 63] {
            let mu = i as f32 / 63.0;
            let want = 1.0 - fresnel_dielectric(mu, 1.5);
            assert!((coat.transmittance[i] - want).abs() < 2e-3, "μ = {mu}: {} against {want}", coat.transmittance[i]);
        }
        assert!((coat.internal_reflectance - 0.596).abs() < 0.01, "F_dr = {}", coat.internal_reflectance);
    }

    #[test]
    fn a_textured_roughness_blends_its_levels_closely() {
        // Between two levels, the blend against the exact table of the α in the middle: T is
        // smooth in √α, so the linear blend's error is second order.
        let steps = (ROUGHNESS_LEVELS - 1) as f32;
        let mut worst = 0.0f32;
        for k in [3u32, 12, 30, 50] {
            let r = (k as f32 + 0.5) / steps;
            let (exact, blended) = (Coat::new(1.5, Alpha::ggx(r * r)), CoatAt::new(1.5, Alpha::ggx(0.1)).at(r * r));
            for i in 1..TRANSMITTANCE_RES {
                let mu = i as f32 / steps;
                worst = worst.max((exact.transmittance(mu) - blended.transmittance(mu)).abs());
            }
            let f = (exact.internal_reflectance - blended.internal_reflectance()).abs();
            assert!(f < 1e-3, "F_dr at roughness {r}: off by {f}");
        }
        assert!(worst < 2e-3, "T off by {worst}");
    }
}
