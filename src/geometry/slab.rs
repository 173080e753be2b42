//! The conservative slab test of a ray against a box, shared by every traversal: entry
//! distance with the far distance grown by 1 + 2γ₃ (pbrt-v4 §6.1.2), and inverse directions
//! that stay finite (zero or subnormal components get ±f32::MAX, so no 0·∞ NaN can arise); and
//! the rule that keeps every hit's t within its triangle's box ([`settle`]). Reads a ray and a
//! box; writes an entry distance.

use super::offset::gamma;
use super::triangle::{intersect_triangle, TriangleHit};
use glam::{Vec3, Vec3A};
use wide::f32x8;

/// Far-distance growth that makes the slab test conservative.
pub const FAR_GROWTH: f32 = 1.0 + 2.0 * gamma(3);

/// 1/d, with ±f32::MAX where that overflows (d = ±0 or subnormal): finite, so (b − o)·inv is
/// never 0·∞.
#[inline]
#[must_use]
pub fn safe_inverse(d: f32) -> f32 {
    let i = 1.0 / d;
    if i.is_finite() {
        i
    } else {
        f32::MAX.copysign(d)
    }
}

/// Entry distance (≥ 0) of the ray into the box, or +∞ when it misses or enters beyond `t_max`
/// (entry exactly at `t_max` counts: a tie may still win).
#[inline]
#[must_use]
pub fn box_entry(min: Vec3A, max: Vec3A, o: Vec3A, inv: Vec3A, t_max: f32) -> f32 {
    let t0 = (min - o) * inv;
    let t1 = (max - o) * inv;
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element() * FAR_GROWTH;
    if near <= far && near <= t_max {
        near
    } else {
        f32::INFINITY
    }
}

/// The near and far distances of [`box_entry`] for eight boxes or eight rays at once, lane by
/// lane with its operations (so its values bit for bit): box planes `lo`, `hi`, origin `o` and
/// inverse direction `inv`, per axis. No NaN can arise (finite origins, boxes and inverses), so
/// the min and max need no NaN handling.
#[inline(always)]
#[must_use]
pub fn slab8(lo: [f32x8; 3], hi: [f32x8; 3], o: [f32x8; 3], inv: [f32x8; 3]) -> (f32x8, f32x8) {
    let axis = |a: usize| {
        let t0 = (lo[a] - o[a]) * inv[a];
        let t1 = (hi[a] - o[a]) * inv[a];
        (t0.fast_min(t1), t0.fast_max(t1))
    };
    let ((nx, fx), (ny, fy), (nz, fz)) = (axis(0), axis(1), axis(2));
    let near = nx.fast_max(ny).fast_max(nz).fast_max(f32x8::ZERO);
    (near, fx.fast_min(fy).fast_min(fz) * f32x8::splat(FAR_GROWTH))
}

/// [`settle`] for eight (ray, box) pairs at once, with [`slab8`]'s arguments: each lane's `t`
/// raised to its ray's entry into its box, +∞ where the ray misses the box; the scalar
/// function's values bit for bit.
#[inline(always)]
#[must_use]
pub fn settle8(t: f32x8, lo: [f32x8; 3], hi: [f32x8; 3], o: [f32x8; 3], inv: [f32x8; 3]) -> f32x8 {
    let (near, far) = slab8(lo, hi, o, inv);
    t.fast_max(near.simd_le(far).select(near, f32x8::splat(f32::INFINITY)))
}

/// Inverse direction with finite components.
#[inline]
#[must_use]
pub fn inverse_direction(d: Vec3) -> Vec3 {
    // [`safe_inverse`] per component, as one select instead of a branch each.
    let i = Vec3::ONE / d;
    Vec3::select(i.is_finite_mask(), i, Vec3::splat(f32::MAX).copysign(d))
}

/// The box a hit on the triangle `p` must lie in: its vertices' box grown by `pad` on every
/// side ([`super::bvh::Bvh::pad`], the part of the BVH's padding that every triangle shares, so
/// this box lies inside the padded box every tree holds the triangle in).
#[inline]
#[must_use]
pub fn triangle_box(p: [Vec3; 3], pad: f32) -> (Vec3A, Vec3A) {
    let pad = Vec3::splat(pad);
    ((p[0].min(p[1]).min(p[2]) - pad).into(), (p[0].max(p[1]).max(p[2]) + pad).into())
}

/// A hit's t made consistent with the triangle's box: t raised to the ray's entry into
/// [`triangle_box`], or +∞ (never below a limit) where the slab test says the ray misses that
/// box. Every traversal applies it to every hit, before comparing with its limit.
///
/// Why: a sliver's or needle's computed t can lie outside its own box (the fuzzer found an
/// ordinary f32 hit 2.3·10⁻⁴ before it), and a traversal that prunes that box by a nearer hit
/// found earlier never tests the triangle, while one that meets the triangle first keeps it.
/// Which happens depended on the tree and the order of the walk. A settled t is at least the
/// entry into the triangle's box, which (same operations, rounding monotonic) is at least the
/// entry into every box that holds it; so every box on the way to the closest settled hit passes
/// whatever limit a walk holds, and every walk finds that hit. Raising t never lets a test pass
/// that failed against a limit, so a triangle test may still reject by its limit early. In a
/// scene the rule is a no-op: a hit's rounding moves it far less than the padding.
#[inline]
#[must_use]
pub fn settle(t: f32, o: Vec3A, inv: Vec3A, p: [Vec3; 3], pad: f32) -> f32 {
    let (lo, hi) = triangle_box(p, pad);
    t.max(box_entry(lo, hi, o, inv, f32::INFINITY))
}

/// The watertight test of triangle `p` within (0, `t_max`), its t [`settle`]d: the decision
/// every traversal makes about one ray and one triangle.
#[inline]
#[must_use]
pub fn intersect_settled(o: Vec3, d: Vec3, inv: Vec3, t_max: f32, p: [Vec3; 3], pad: f32) -> Option<TriangleHit> {
    let h = intersect_triangle(o, d, t_max, p[0], p[1], p[2])?;
    let t = settle(h.t, o.into(), inv.into(), p, pad);
    (t < t_max).then_some(TriangleHit { t, b: h.b })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A t before the triangle's box is raised to the ray's entry into it; a t inside is kept;
    /// a ray that misses the box gets +∞, which no limit accepts.
    #[test]
    fn settle_raises_t_to_the_box_and_refuses_misses() {
        let p = [Vec3::new(0.0, 0.0, 2.0), Vec3::new(1.0, 0.0, 3.0), Vec3::new(0.0, 1.0, 2.0)];
        let (o, d) = (Vec3::new(0.25, 0.25, 0.0), Vec3::Z);
        let inv = inverse_direction(d);
        let pad = 0.125;
        assert_eq!(settle(1.0, o.into(), inv.into(), p, pad), 2.0 - pad);
        assert_eq!(settle(2.5, o.into(), inv.into(), p, pad), 2.5);
        let beside = Vec3::new(2.0, 0.25, 0.0);
        assert_eq!(settle(2.5, beside.into(), inv.into(), p, pad), f32::INFINITY);
        assert!(intersect_settled(beside, d, inv, f32::INFINITY, p, pad).is_none());
        let h = intersect_settled(o, d, inv, f32::INFINITY, p, pad).unwrap();
        assert!((h.t - 2.25).abs() < 1e-6, "{h:?}");
    }

    /// The vector select gives [`safe_inverse`] per component, bit for bit: zeros of both signs
    /// and subnormals (whose reciprocal overflows) get ±f32::MAX, everything else 1/d (±0 for
    /// infinities; NaN, which no valid ray has, ±f32::MAX by its sign bit).
    #[test]
    fn inverse_direction_is_the_safe_inverse_per_component() {
        let values = [0.0, -0.0, 1e-45, -1e-45, 1e-39, -3e-39, 0.5, -2.0, 3.0e38, -1.0e-30, f32::INFINITY, -f32::NAN];
        for &x in &values {
            for &y in &values {
                for &z in &values {
                    let inv = inverse_direction(Vec3::new(x, y, z)).to_array();
                    for (got, d) in inv.iter().zip([x, y, z]) {
                        assert_eq!(got.to_bits(), safe_inverse(d).to_bits(), "d = ({x}, {y}, {z})");
                    }
                }
            }
        }
        assert_eq!(safe_inverse(-0.0), -f32::MAX);
        assert_eq!(safe_inverse(1e-45), f32::MAX);
    }
}
