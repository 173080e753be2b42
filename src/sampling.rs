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
        (i, (r as f32).clamp(0.0, 1.0 - f32::EPSILON / 2.0))
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
}
