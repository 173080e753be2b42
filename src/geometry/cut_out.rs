//! Alpha cut-outs in traversal: triangles whose texture makes parts of them transparent (Mitsuba's
//! `mask`, glTF's `alphaMode`, MTL's `map_d`). A hit on a transparent texel is no hit: every
//! traversal kernel, SIMD and scalar alike, asks [`CutOut::passes`] before it keeps a
//! closest-hit candidate or lets a triangle end an any-hit ray, and walks on when the ray passes
//! (pbrt-v4 and Embree filter in the same place). Reads a hit's triangle, barycentrics and ray;
//! writes nothing.
//!
//! The decision is a function of the triangle, its barycentrics and the ray's origin and
//! direction bits only, and every kernel finds the same barycentrics bit for bit, so every
//! kernel keeps the same hit; a fractional opacity α passes the ray when a hash of the ray
//! ([`coverage_sample`]) is at least α (probability 1 − α), so the same ray gets the same answer
//! in a closest-hit and an any-hit walk, on any thread and in any split of the render.

use glam::Vec3;
use wide::f32x8;

/// What decides whether a ray passes through a hit (implemented by the scene, which knows the
/// materials and their textures).
pub trait CutOut: Sync {
    /// True if the ray `o + t·d` passes through triangle `tri` at barycentrics `b` (a transparent
    /// texel, or a partly opaque one the ray's [`coverage_sample`] passes).
    fn passes(&self, tri: u32, b: [f32; 3], o: Vec3, d: Vec3) -> bool;
}

/// The cut-outs a traversal honours: `None` in a scene without any (every hit is kept, at the
/// cost of one predictable branch per hit).
pub type CutOuts<'a> = Option<&'a dyn CutOut>;

/// Whether `cut` lets the ray through triangle `tri` at `b`.
#[inline(always)]
#[must_use]
pub fn passes(cut: CutOuts<'_>, tri: u32, b: [f32; 3], o: Vec3, d: Vec3) -> bool {
    match cut {
        None => false,
        Some(c) => c.passes(tri, b, o, d),
    }
}

/// The lanes of `hit` (an 8-wide triangle test's hit mask, barycentrics `bary` per lane) whose
/// hit `kept` says stands: the cut-out test lane by lane, for the SIMD kernels' rare hits on a
/// scene with cut-outs.
#[cold]
pub(super) fn kept_lanes(hit: u32, bary: [f32x8; 3], kept: impl Fn(usize, [f32; 3]) -> bool) -> u32 {
    let bary = bary.map(f32x8::to_array);
    let (mut m, mut out) = (hit, 0);
    while m != 0 {
        let l = m.trailing_zeros() as usize;
        m &= m - 1;
        if kept(l, [bary[0][l], bary[1][l], bary[2][l]]) {
            out |= 1 << l;
        }
    }
    out
}

/// A number in [0, 1) drawn from the ray's origin and direction bits and the triangle: the
/// stochastic test of a partly opaque texel (the ray passes when it is at least the opacity).
/// Murmur3's finaliser over the seven words, so nearby rays draw unrelated numbers.
#[must_use]
pub fn coverage_sample(tri: u32, o: Vec3, d: Vec3) -> f32 {
    let words = [o.x.to_bits(), o.y.to_bits(), o.z.to_bits(), d.x.to_bits(), d.y.to_bits(), d.z.to_bits(), tri];
    let mut h: u32 = 0x9e37_79b9;
    for w in words {
        h = fmix(h ^ w).wrapping_add(0x632b_e5ab);
    }
    // The top 24 bits: every value exact in f32.
    (fmix(h) >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Murmur3's 32-bit finaliser.
#[inline]
fn fmix(mut h: u32) -> u32 {
    h ^= h >> 16;
    h = h.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 13;
    h = h.wrapping_mul(0xc2b2_ae35);
    h ^ h >> 16
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The samples are uniform enough to stand for a probability: over 2¹⁶ rays the share below
    /// each tenth is within 4σ of it (σ = √(p(1−p)/n) ≤ 0.002), and the mean within 4σ of ½.
    #[test]
    fn coverage_samples_are_uniform() {
        let n = 1 << 16;
        let mut below = [0u32; 10];
        let mut sum = 0.0f64;
        for i in 0..n {
            let o = Vec3::new(i as f32 * 0.37, 1.0, -2.0);
            let d = Vec3::new(0.3, -1.0, (i % 97) as f32 * 0.01);
            let u = coverage_sample(7, o, d);
            assert!((0.0..1.0).contains(&u));
            sum += f64::from(u);
            for (k, b) in below.iter_mut().enumerate() {
                *b += u32::from(u < (k + 1) as f32 / 10.0);
            }
        }
        for (k, &b) in below.iter().enumerate() {
            let p = (k + 1) as f64 / 10.0;
            let sigma = (p * (1.0 - p) / f64::from(n)).sqrt();
            assert!((f64::from(b) / f64::from(n) - p).abs() < 4.0 * sigma + 1e-12, "below {p}: {b}");
        }
        let sigma = (1.0 / 12.0 / f64::from(n)).sqrt();
        assert!((sum / f64::from(n) - 0.5).abs() < 4.0 * sigma, "mean {}", sum / f64::from(n));
    }

    /// The same ray and triangle draw the same number; another triangle, another number.
    #[test]
    fn the_sample_is_a_function_of_the_ray_and_triangle() {
        let (o, d) = (Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.0, -0.0, 1.0));
        assert_eq!(coverage_sample(3, o, d).to_bits(), coverage_sample(3, o, d).to_bits());
        assert_ne!(coverage_sample(3, o, d), coverage_sample(4, o, d));
        assert_ne!(coverage_sample(3, o, d), coverage_sample(3, o, Vec3::new(0.0, 0.0, 1.0)));
    }
}
