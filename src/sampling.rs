//! Warping uniform numbers onto directions and shapes, and building orthonormal frames.

use glam::Vec3;
use std::f32::consts::PI;

/// An orthonormal frame around a unit normal `n` (Duff et al. 2017, branchless).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// First tangent.
    pub s: Vec3,
    /// Second tangent.
    pub t: Vec3,
    /// The normal.
    pub n: Vec3,
}

impl Frame {
    /// The frame whose z axis is `n` (unit length).
    #[must_use]
    pub fn new(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }
    /// World vector from local coordinates.
    #[must_use]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
    /// Local coordinates of a world vector.
    #[must_use]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
}

/// Concentric map of the unit square onto the unit disk (Shirley & Chiu 1997).
#[must_use]
pub fn concentric_disk(u: [f32; 2]) -> (f32, f32) {
    let a = 2.0 * u[0] - 1.0;
    let b = 2.0 * u[1] - 1.0;
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let (r, theta) = if a.abs() > b.abs() { (a, (PI / 4.0) * (b / a)) } else { (b, (PI / 2.0) - (PI / 4.0) * (a / b)) };
    (r * theta.cos(), r * theta.sin())
}

/// Cosine-weighted direction on the +z hemisphere; pdf = cos θ / π.
#[must_use]
pub fn cosine_hemisphere(u: [f32; 2]) -> Vec3 {
    let (x, y) = concentric_disk(u);
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    Vec3::new(x, y, z)
}

/// Uniform direction on the unit sphere; pdf = 1 / 4π.
#[must_use]
pub fn uniform_sphere(u: [f32; 2]) -> Vec3 {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform direction in the cone of half-angle acos(`cos_max`) around +z; pdf = 1 / (2π(1 − cos_max)).
#[must_use]
pub fn uniform_cone(u: [f32; 2], cos_max: f32) -> Vec3 {
    let z = 1.0 - u[0] * (1.0 - cos_max);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform barycentrics (b1, b2) on a triangle (Heitz 2019's low-distortion map).
#[must_use]
pub fn uniform_triangle(u: [f32; 2]) -> (f32, f32) {
    let (b0, b1);
    if u[0] < u[1] {
        b0 = u[0] / 2.0;
        b1 = u[1] - b0;
    } else {
        b1 = u[1] / 2.0;
        b0 = u[0] - b1;
    }
    // (b0, b1) weight vertices 0 and 1; return the weights of vertices 1 and 2.
    (b1, 1.0 - b0 - b1)
}

/// A discrete distribution over items by weight, sampled by inverting its CDF.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    cdf: Vec<f64>,
    total: f64,
}

impl Distribution1D {
    /// Builds from non-negative weights; `None` if their sum is not positive and finite.
    #[must_use]
    pub fn try_new(weights: &[f64]) -> Option<Self> {
        let mut cdf = Vec::with_capacity(weights.len());
        let mut acc = 0.0;
        for &w in weights {
            acc += w.max(0.0);
            cdf.push(acc);
        }
        (acc > 0.0 && acc.is_finite()).then_some(Distribution1D { cdf, total: acc })
    }
    /// The sum of all weights.
    #[must_use]
    pub fn total(&self) -> f64 {
        self.total
    }
    /// Probability of item `i`.
    #[must_use]
    pub fn pmf(&self, i: usize) -> f64 {
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        (self.cdf[i] - lo) / self.total
    }
    /// Picks an item for uniform `u`; items of zero weight are never returned.
    #[must_use]
    pub fn sample(&self, u: f32) -> usize {
        let target = u as f64 * self.total;
        let i = self.cdf.partition_point(|&c| c <= target);
        i.min(self.cdf.len() - 1)
    }
    /// [`Distribution1D::sample`], and where `u` fell within the item's share of [0, 1),
    /// rescaled to [0, 1): a second uniform number for free (continuous sampling inside a bin).
    #[must_use]
    pub fn sample_remapped(&self, u: f32) -> (usize, f32) {
        let i = self.sample(u);
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let width = self.cdf[i] - lo;
        let r = if width > 0.0 { (u as f64 * self.total - lo) / width } else { 0.5 };
        (i, (r as f32).clamp(0.0, ONE_BELOW))
    }
}

/// The largest f32 below 1: where a uniform number rescaled into [0, 1) is clamped.
pub const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// Solid angles (sr) within which a triangle's light is sampled by the solid angle it subtends
/// ([`SphericalTriangle`]); outside, by area. Below the lower bound the triangle is far and
/// small, where area sampling is already uniform in solid angle; above the upper one (near 2π)
/// the point lies almost in the triangle's plane, inside it, where the spherical triangle is a
/// near-hemisphere whose sampling loses precision. The bounds are pbrt-v4's.
pub const SPHERICAL_SAMPLING: std::ops::RangeInclusive<f64> = 3e-4..=6.22;

/// A triangle seen from a point: the unit vectors a, b, c toward its vertices, in f64, computed
/// once for both its solid angle and a direction sampled in it.
#[derive(Clone, Copy, Debug)]
pub struct SphericalTriangle {
    a: glam::DVec3,
    b: glam::DVec3,
    c: glam::DVec3,
}

impl SphericalTriangle {
    /// Triangle `v` seen from `p`.
    #[must_use]
    pub fn new(v: [Vec3; 3], p: Vec3) -> Self {
        let p = p.as_dvec3();
        let [a, b, c] = v.map(|q| (q.as_dvec3() - p).normalize_or_zero());
        SphericalTriangle { a, b, c }
    }

    /// Its solid angle (sr) (Van Oosterom and Strackee 1983: tan(Ω/2) = |a·(b×c)| / (1 + a·b +
    /// b·c + c·a)): exact to rounding for triangles of any size or distance. 0 where the point
    /// lies on a vertex.
    #[must_use]
    pub fn solid_angle(&self) -> f64 {
        let (a, b, c) = (self.a, self.b, self.c);
        let num = a.dot(b.cross(c)).abs();
        let den = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
        let omega = 2.0 * num.atan2(den);
        if omega.is_finite() {
            omega
        } else {
            0.0
        }
    }

    /// A direction uniform in its solid angle, with two uniform numbers (Arvo 1995, "Stratified
    /// Sampling of Spherical Triangles": the first number picks the sub-triangle A B Ĉ of area
    /// u₀·Ω, whose far vertex Ĉ lies on the arc A C, the second a point on the arc B Ĉ whose
    /// cosine to B is uniform). pdf = 1/[`SphericalTriangle::solid_angle`]. In f64, as the
    /// sub-area's angle sum α + β + γ − π cancels for small triangles. `None` where the
    /// spherical triangle is degenerate (a vertex at the point, or the point in the triangle's
    /// plane).
    #[must_use]
    pub fn sample(&self, u: [f32; 2]) -> Option<Vec3> {
        use glam::DVec3;
        let (a, b, c) = (self.a, self.b, self.c);
        // The great circles' plane normals, and the triangle's angles between them.
        let (n_ab, n_bc, n_ca) = (a.cross(b), b.cross(c), c.cross(a));
        if n_ab.length_squared() == 0.0 || n_bc.length_squared() == 0.0 || n_ca.length_squared() == 0.0 {
            return None;
        }
        let (n_ab, n_bc, n_ca) = (n_ab.normalize(), n_bc.normalize(), n_ca.normalize());
        let alpha = angle_between(n_ab, -n_ca);
        let beta = angle_between(n_bc, -n_ab);
        let gamma = angle_between(n_ca, -n_bc);
        let area = alpha + beta + gamma - std::f64::consts::PI;
        if !(area > 0.0) {
            return None;
        }
        // The sub-triangle of area u₀·Ω: where Ĉ lies on the arc A C (its cosine q to A).
        let sub = f64::from(u[0]) * area;
        let (s, t) = (sub - alpha).sin_cos();
        let (sin_alpha, cos_alpha) = alpha.sin_cos();
        let (k1, k2) = (t - cos_alpha, s + sin_alpha * a.dot(b));
        let q = (((k2 * t - k1 * s) * cos_alpha - k2) / ((k2 * s + k1 * t) * sin_alpha)).clamp(-1.0, 1.0);
        let across = |x: DVec3, from: DVec3| (x - x.dot(from) * from).normalize_or_zero();
        let c_hat = q * a + (1.0 - q * q).max(0.0).sqrt() * across(c, a);
        // Along the arc B Ĉ, cosine to B uniform between 1 and B·Ĉ.
        let z = 1.0 - f64::from(u[1]) * (1.0 - c_hat.dot(b));
        let w = z * b + (1.0 - z * z).max(0.0).sqrt() * across(c_hat, b);
        let w = w.as_vec3();
        (w.is_finite() && w != Vec3::ZERO).then(|| w.normalize())
    }
}

/// The angle between unit vectors `a` and `b`, accurate near 0 and π alike (the half chord's
/// arcsine instead of the dot product's arccosine).
fn angle_between(a: glam::DVec3, b: glam::DVec3) -> f64 {
    if a.dot(b) < 0.0 {
        std::f64::consts::PI - 2.0 * ((a + b).length() / 2.0).min(1.0).asin()
    } else {
        2.0 * ((b - a).length() / 2.0).min(1.0).asin()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal() {
        for n in [Vec3::Z, -Vec3::Z, Vec3::X, Vec3::new(0.3, -0.4, 0.866).normalize()] {
            let f = Frame::new(n);
            assert!(f.s.dot(f.t).abs() < 1e-6 && f.s.dot(f.n).abs() < 1e-6);
            assert!((f.s.length() - 1.0).abs() < 1e-6 && (f.t.length() - 1.0).abs() < 1e-6);
            let v = Vec3::new(0.2, 0.5, -0.7);
            assert!((f.to_local(f.to_world(v)) - v).length() < 1e-6);
        }
    }

    #[test]
    fn zero_weight_items_are_never_sampled() {
        let d = Distribution1D::try_new(&[1.0, 0.0, 3.0]).unwrap();
        for i in 0..1000 {
            assert_ne!(d.sample(i as f32 / 1000.0), 1);
        }
        assert!((d.pmf(2) - 0.75).abs() < 1e-12);
        assert!(Distribution1D::try_new(&[0.0, 0.0]).is_none());
    }

    /// Lambert's formula for the projected solid angle of a polygon seen from the origin about
    /// unit normal `n`: ½ Σ θᵢ n·(vᵢ × vᵢ₊₁)/|vᵢ × vᵢ₊₁|, θᵢ the angle between consecutive vertices
    /// (signed by the winding: its magnitude is taken).
    fn projected_solid_angle(v: [Vec3; 3], n: Vec3) -> f64 {
        (0..3)
            .map(|i| {
                let (a, b) = (v[i].as_dvec3().normalize(), v[(i + 1) % 3].as_dvec3().normalize());
                let g = a.cross(b);
                0.5 * a.dot(b).clamp(-1.0, 1.0).acos() * n.as_dvec3().dot(g.normalize())
            })
            .sum::<f64>()
            .abs()
    }

    #[test]
    fn spherical_triangle_samples_are_uniform_in_solid_angle() {
        // Near and wide (Ω ≈ 1.4 sr), oblique and far (Ω ≈ 3e-3): the samples hit the triangle,
        // and Ω times their mean cosine about a normal is Lambert's projected solid angle within
        // 4 standard errors of the mean.
        let n = Vec3::new(0.1, 0.2, 1.0).normalize();
        let cases = [
            [Vec3::new(-1.0, -1.0, 1.0), Vec3::new(1.5, -0.5, 1.2), Vec3::new(0.0, 1.0, 0.8)],
            [Vec3::new(3.0, 0.5, 9.0), Vec3::new(3.4, 0.6, 9.5), Vec3::new(3.1, 0.9, 9.1)],
        ];
        for v in cases {
            let seen = SphericalTriangle::new(v, Vec3::ZERO);
            let omega = seen.solid_angle();
            assert!(SPHERICAL_SAMPLING.contains(&omega), "Ω {omega}");
            let m = 20_000;
            let mut sum = 0.0f64;
            let mut sum2 = 0.0f64;
            for i in 0..m {
                let u = [(i as f32 + 0.5) / m as f32, ((i as u64 * 2_654_435_761) % 65_521) as f32 / 65_521.0];
                let w = seen.sample(u).expect("a direction");
                // The direction crosses the triangle: its barycentrics are all ≥ 0.
                let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
                let pv = w.cross(e2);
                let det = e1.dot(pv);
                let b1 = (-v[0]).dot(pv) / det;
                let b2 = w.dot((-v[0]).cross(e1)) / det;
                assert!(b1 > -1e-4 && b2 > -1e-4 && b1 + b2 < 1.0 + 1e-4, "{w} misses: {b1} {b2}");
                let f = f64::from(w.dot(n).max(0.0)) * omega;
                sum += f;
                sum2 += f * f;
            }
            let mean = sum / m as f64;
            let se = ((sum2 / m as f64 - mean * mean) / m as f64).sqrt();
            let exact = projected_solid_angle(v, n);
            assert!((mean - exact).abs() < 4.0 * se + 1e-9, "estimate {mean} against {exact} (se {se})");
        }
    }

    #[test]
    fn solid_angle_of_a_far_triangle_is_its_area_over_distance_squared() {
        let v = [Vec3::new(0.0, 0.0, 1000.0), Vec3::new(1.0, 0.0, 1000.0), Vec3::new(0.0, 1.0, 1000.0)];
        let omega = SphericalTriangle::new(v, Vec3::ZERO).solid_angle();
        assert!((omega / 5e-7 - 1.0).abs() < 2e-3, "{omega}");
        assert_eq!(SphericalTriangle::new(v, v[0]).solid_angle(), 0.0, "seen from a vertex");
    }
}
