//! The microfacet distributions Mitsuba 3 offers, as it defines them: GGX (Trowbridge–Reitz) and
//! Beckmann, each with widths α_u, α_v along the local x and y axes. Each gives its normal
//! distribution D(m), Smith's masking G1(ω) and a sampler of the normals visible from a
//! direction: Heitz 2018 for GGX, for Beckmann the slope inversion of Heitz & d'Eon 2014 solved
//! to double precision.
//!
//! One departure from Mitsuba, measured: its Beckmann masking is Walter et al.'s rational
//! approximation of Smith's, which runs up to 0.31 % above it (at a = 1/(α tan θ) = 1.34) and
//! above 1 (by 5·10⁻⁵ near a = 1.5). Here it is Smith's own, from the error function: the
//! sampler then draws exactly the pdf reported, and no sample's weight exceeds 1. Mitsuba's
//! Beckmann values differ from these by at most that 0.31 % per G1 (`tests/mitsuba_bsdfs.rs`).
//!
//! Reads local directions (z along the shading normal) and uniform numbers; writes densities,
//! masking factors and normals. The BSDFs built on them are in the parent module.

use glam::Vec3;
use std::f32::consts::PI;

/// The smallest α used: below it D's peak overflows f32 arithmetic in `eval`.
pub const MIN_ALPHA: f32 = 1e-3;

/// The shape of a microfacet distribution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Distribution {
    /// GGX / Trowbridge–Reitz: long tails (Mitsuba's `ggx`).
    Ggx,
    /// Beckmann: Gaussian slopes (Mitsuba's default, `beckmann`).
    Beckmann,
}

/// A microfacet distribution and its widths: α_u along the local x axis, α_v along y (equal for
/// an isotropic surface).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Alpha {
    /// GGX or Beckmann.
    pub distribution: Distribution,
    /// Width along x.
    pub u: f32,
    /// Width along y.
    pub v: f32,
}

impl Alpha {
    /// An isotropic distribution of width `alpha` (at least [`MIN_ALPHA`]).
    #[must_use]
    pub fn new(distribution: Distribution, alpha: f32) -> Alpha {
        let a = alpha.max(MIN_ALPHA);
        Alpha { distribution, u: a, v: a }
    }

    /// Isotropic GGX of width `alpha`.
    #[must_use]
    pub fn ggx(alpha: f32) -> Alpha {
        Alpha::new(Distribution::Ggx, alpha)
    }

    /// Isotropic Beckmann of width `alpha`.
    #[must_use]
    pub fn beckmann(alpha: f32) -> Alpha {
        Alpha::new(Distribution::Beckmann, alpha)
    }

    /// This distribution with widths `u` along x and `v` along y.
    #[must_use]
    pub fn anisotropic(self, u: f32, v: f32) -> Alpha {
        Alpha { distribution: self.distribution, u: u.max(MIN_ALPHA), v: v.max(MIN_ALPHA) }
    }

    /// The larger width: what decides whether photons treat the surface as a mirror.
    #[must_use]
    pub fn width(&self) -> f32 {
        self.u.max(self.v)
    }

    /// The same distribution, isotropic of width `alpha` (a roughness texture's value).
    #[must_use]
    pub fn with_width(self, alpha: f32) -> Alpha {
        Alpha::new(self.distribution, alpha)
    }

    /// D(m) for a local normal `m`; zero below the surface and where D·cos θ underflows
    /// 10⁻²⁰ (Mitsuba's cut, which keeps the far tails out of the other stages).
    #[must_use]
    pub fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        // The slopes scaled by the widths; x² + y² + z² and (x² + y²)/z² are written from the
        // components, not from 1 − z², which cancels to a few ulps near a narrow lobe's peak.
        let (x, y) = (m.x / self.u, m.y / self.v);
        let z2 = m.z * m.z;
        let d = match self.distribution {
            Distribution::Ggx => {
                let t = x * x + y * y + z2;
                1.0 / (PI * self.u * self.v * t * t)
            }
            Distribution::Beckmann => (-(x * x + y * y) / z2).exp() / (PI * self.u * self.v * z2 * z2),
        };
        if d * m.z > 1e-20 {
            d
        } else {
            0.0
        }
    }

    /// Masking G1(ω) of a direction above the surface (zero at or below it).
    #[must_use]
    pub fn g1(&self, w: Vec3) -> f32 {
        if w.z <= 0.0 {
            return 0.0;
        }
        let xy = (self.u * w.x).powi(2) + (self.v * w.y).powi(2);
        if xy == 0.0 {
            return 1.0;
        }
        // α(φ)²·tan²θ.
        let t = xy / (w.z * w.z);
        match self.distribution {
            Distribution::Ggx => 2.0 / (1.0 + (1.0 + t).sqrt()),
            Distribution::Beckmann => {
                // Λ(a) = (exp(−a²)/(a√π) − erfc(a))/2, a = 1/(α tan θ); past a = 6 it is below
                // 10⁻¹⁸.
                let a = 1.0 / f64::from(t).sqrt();
                if a > SLOPE_LIMIT {
                    return 1.0;
                }
                let lambda = 0.5 * ((-a * a).exp() * INV_SQRT_PI / a - erfc(a));
                (1.0 / (1.0 + lambda)) as f32
            }
        }
    }

    /// The density of normals visible from `wo`: G1(wo)·max(0, wo·m)·D(m)/wo.z.
    #[must_use]
    pub fn visible_d(&self, wo: Vec3, m: Vec3) -> f32 {
        if wo.z <= 0.0 {
            return 0.0;
        }
        self.g1(wo) * wo.dot(m).max(0.0) * self.d(m) / wo.z
    }

    /// A normal sampled from those visible from `wo` (wo.z > 0), from two uniform numbers: the
    /// view is stretched to the unit-width configuration, a normal sampled there and stretched
    /// back.
    #[must_use]
    pub fn sample_visible_normal(&self, wo: Vec3, u: [f32; 2]) -> Vec3 {
        let vh = Vec3::new(self.u * wo.x, self.v * wo.y, wo.z).normalize();
        match self.distribution {
            Distribution::Ggx => {
                let nh = ggx_visible_unit(vh, u);
                Vec3::new(self.u * nh.x, self.v * nh.y, nh.z.max(1e-6)).normalize()
            }
            Distribution::Beckmann => {
                let len = (vh.x * vh.x + vh.y * vh.y).sqrt();
                let (cos_phi, sin_phi) = if len > 0.0 { (vh.x / len, vh.y / len) } else { (1.0, 0.0) };
                let (sx, sy) = beckmann_visible_slopes(vh.z, u);
                // Rotate to the view's azimuth, stretch by the widths; slopes are −m.x/m.z.
                let x = (cos_phi * sx - sin_phi * sy) * self.u;
                let y = (sin_phi * sx + cos_phi * sy) * self.v;
                Vec3::new(-x, -y, 1.0).normalize()
            }
        }
    }
}

/// GGX's visible normals for unit width, seen from `vh` (Heitz 2018): a point on the disk
/// facing `vh`, its far half squeezed by the projected hemisphere, lifted onto the hemisphere.
fn ggx_visible_unit(vh: Vec3, u: [f32; 2]) -> Vec3 {
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 { Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt() } else { Vec3::X };
    let t2 = vh.cross(t1);
    let r = u[0].sqrt();
    let phi = 2.0 * PI * u[1];
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt()
}

/// 1/√π.
const INV_SQRT_PI: f64 = 0.564_189_583_547_756_3;

/// Slopes beyond this are never drawn: erfc(6) ≈ 2·10⁻¹⁷ of the mass lies past it.
const SLOPE_LIMIT: f64 = 6.0;

/// The slopes (x along the view's azimuth, y across it) of a unit-width Beckmann normal visible
/// from a direction at cos θ (Heitz & d'Eon 2014). The slope x has the cumulative distribution
/// ∝ C(x) = erfc(−x) + tan θ/√π·exp(−x²) on x ≤ cot θ (normals facing the view): from the
/// inverse of its grazing limit (Mitsuba's first guess, erf(x) = m − (m + 1)·erf(√(−ln u)),
/// m = erf(cot θ)), Newton's method inside a shrinking bracket. y is Gaussian with density
/// exp(−y²)/√π: erf⁻¹(2u − 1) and one Newton step.
#[must_use]
pub fn beckmann_visible_slopes(cos: f32, u: [f32; 2]) -> (f32, f32) {
    let cos = f64::from(cos).clamp(1e-9, 1.0);
    let tan = (1.0 - cos * cos).max(0.0).sqrt() / cos;
    let hi = if tan > 1.0 / SLOPE_LIMIT { 1.0 / tan } else { SLOPE_LIMIT };
    let c = |x: f64| erfc(-x) + tan * INV_SQRT_PI * (-x * x).exp();
    let dc = |x: f64| 2.0 * INV_SQRT_PI * (-x * x).exp() * (1.0 - x * tan);
    let ux = f64::from(u[0]).clamp(1e-12, 1.0 - 1e-12);
    let m = 1.0 - erfc(hi);
    let guess = erfinv(m - (m + 1.0) * (1.0 - erfc((-ux.ln()).sqrt())));
    let x = invert(c, dc, ux * c(hi), guess, -SLOPE_LIMIT, hi);
    let uy = f64::from(u[1]).clamp(1e-12, 1.0 - 1e-12);
    let y0 = erfinv(2.0 * uy - 1.0);
    let y = y0 - (erfc(-y0) - 2.0 * uy) / (2.0 * INV_SQRT_PI * (-y0 * y0).exp());
    (x as f32, y.clamp(-SLOPE_LIMIT, SLOPE_LIMIT) as f32)
}

/// The x in [`lo`, `hi`] where the increasing `f` reaches `target`, from `guess`: Newton steps,
/// replaced by bisection whenever one would leave the bracket, until a step is below 10⁻⁹ (the
/// result is kept in f32).
fn invert(f: impl Fn(f64) -> f64, df: impl Fn(f64) -> f64, target: f64, guess: f64, mut lo: f64, mut hi: f64) -> f64 {
    let mut x = if guess.is_finite() { guess.clamp(lo, hi) } else { 0.5 * (lo + hi) };
    for _ in 0..100 {
        let v = f(x) - target;
        if v > 0.0 {
            hi = x;
        } else {
            lo = x;
        }
        let step = x - v / df(x);
        let next = if step > lo && step < hi { step } else { 0.5 * (lo + hi) };
        if (next - x).abs() < 1e-9 || hi - lo < 1e-9 {
            return next;
        }
        x = next;
    }
    x
}

/// The inverse error function for |x| < 1, to about 4·10⁻⁷ relative (Giles 2012, "Approximating
/// the erfinv function": a polynomial in w = −ln(1 − x²), one for w < 5, one in √w beyond).
#[must_use]
pub fn erfinv(x: f64) -> f64 {
    let w = -((1.0 - x) * (1.0 + x)).ln();
    let p = if w < 5.0 {
        let w = w - 2.5;
        [
            2.810_226_36e-08,
            3.432_739_39e-07,
            -3.523_387_7e-06,
            -4.391_506_54e-06,
            0.000_218_580_87,
            -0.001_253_725_03,
            -0.004_177_681_64,
            0.246_640_727,
            1.501_409_41,
        ]
        .iter()
        .fold(0.0, |p, c| c + p * w)
    } else {
        let w = w.sqrt() - 3.0;
        [
            -0.000_200_214_257,
            0.000_100_950_558,
            0.001_349_343_22,
            -0.003_673_428_44,
            0.005_739_507_73,
            -0.007_622_461_3,
            0.009_438_870_47,
            1.001_674_06,
            2.832_976_82,
        ]
        .iter()
        .fold(0.0, |p, c| c + p * w)
    };
    p * x
}

/// The complementary error function, to a relative error below 1.2·10⁻⁷ everywhere (the
/// Chebyshev fit of Press et al., "Numerical Recipes", §6.2: t·exp(−z² + P(t)), t = 1/(1 + z/2)).
#[must_use]
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let p = -1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98 + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * (-z * z + p).exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erfc_matches_known_values() {
        // erfc(0) = 1, erfc(1) = 0.157299207050285, erfc(2) = 0.004677734981047,
        // erfc(−1) = 2 − erfc(1), erfc(4) = 1.541725790028e-8 (relative error < 1.2e-7).
        for (x, want) in [
            (0.0, 1.0),
            (1.0, 0.157_299_207_050_285),
            (2.0, 0.004_677_734_981_047),
            (-1.0, 1.842_700_792_949_715),
            (4.0, 1.541_725_790_028e-8),
        ] {
            let got = erfc(x);
            assert!(((got - want) / want).abs() < 1.2e-7, "erfc({x}) = {got}, want {want}");
        }
    }

    #[test]
    fn erfinv_inverts_erf() {
        // erf(erfinv(x)) = x to Giles' 4·10⁻⁷ relative, across the range and into the tails;
        // erf is read as 1 − erfc, whose 1.2·10⁻⁷ relative error is absolute here.
        for x in [-0.999_999, -0.99, -0.5, -1e-3, 1e-4, 0.3, 0.9, 0.9999, 0.999_999_9] {
            let back = 1.0 - erfc(erfinv(x));
            assert!((back - x).abs() < 1e-6 * x.abs() + 2.5e-7, "erf(erfinv({x})) = {back}");
        }
    }

    #[test]
    fn each_distribution_projects_to_unit_area() {
        // ∫ D(m) cos θm dω = 1, and the visible normals integrate to 1 from any view (Smith's
        // G1 is what makes them): a 400 × 800 midpoint quadrature over the hemisphere, in θ
        // dense near the normal.
        for a in [
            Alpha::ggx(0.2),
            Alpha::beckmann(0.2),
            Alpha::ggx(0.5).anisotropic(0.1, 0.6),
            Alpha::beckmann(0.3).anisotropic(0.5, 0.15),
        ] {
            for wo in [Vec3::Z, Vec3::new(0.6, 0.0, 0.8), Vec3::new(-0.5, 0.7, 0.5).normalize()] {
                let (nt, np) = (400usize, 800usize);
                let (mut proj, mut vis) = (0.0f64, 0.0f64);
                for i in 0..nt {
                    // θ = (π/2)·s², s uniform: more nodes near the peak.
                    let s = (i as f64 + 0.5) / nt as f64;
                    let theta = std::f64::consts::FRAC_PI_2 * s * s;
                    let dtheta = std::f64::consts::PI * s / nt as f64;
                    for j in 0..np {
                        let phi = (j as f64 + 0.5) / np as f64 * 2.0 * std::f64::consts::PI;
                        let m = Vec3::new(
                            (theta.sin() * phi.cos()) as f32,
                            (theta.sin() * phi.sin()) as f32,
                            theta.cos() as f32,
                        );
                        let dw = theta.sin() * dtheta * 2.0 * std::f64::consts::PI / np as f64;
                        proj += f64::from(a.d(m)) * theta.cos() * dw;
                        vis += f64::from(a.visible_d(wo, m)) * dw;
                    }
                }
                assert!((proj - 1.0).abs() < 1e-3, "{a:?}: ∫ D cos = {proj}");
                assert!((vis - 1.0).abs() < 1e-3, "{a:?}, wo = {wo}: ∫ D_wo = {vis}");
            }
        }
    }

    #[test]
    fn beckmann_slopes_invert_their_distributions() {
        // The slope x drawn for u satisfies C(x) = u·C(cot θ); y satisfies erfc(−y) = 2u.
        for cos in [1.0f32, 0.9, 0.5, 0.1, 0.01] {
            let tan = f64::from((1.0 - cos * cos).sqrt() / cos);
            let c = |x: f64| erfc(-x) + tan * INV_SQRT_PI * (-x * x).exp();
            let hi = if tan > 1.0 / SLOPE_LIMIT { 1.0 / tan } else { SLOPE_LIMIT };
            for u in [0.001f32, 0.25, 0.5, 0.75, 0.999] {
                let (x, y) = beckmann_visible_slopes(cos, [u, u]);
                let got = c(f64::from(x)) / c(hi);
                assert!((got - f64::from(u)).abs() < 1e-6, "cos {cos}, u {u}: C(x)/C(max) = {got}");
                assert!(f64::from(x) <= hi + 1e-6, "x = {x} beyond cot θ = {hi}");
                assert!((erfc(-f64::from(y)) / 2.0 - f64::from(u)).abs() < 1e-6, "y = {y} for u = {u}");
            }
        }
    }
}
