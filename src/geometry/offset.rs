//! Spawning rays off surfaces without self-intersection and without a fixed epsilon.
//!
//! The hit point is computed from barycentrics, whose rounding error is bounded by
//! γ₇·(|b0·p0| + |b1·p1| + |b2·p2|) per axis (pbrt-v4 §6.8.6). The new origin is pushed along the
//! geometric normal just past that error box, then one ulp further away from the surface, so the
//! offset scales with the scene: a Cornell box at 1e-4 or 1e5 units behaves the same. The one
//! absolute length is a floor of 2⁻⁶³ ≈ 1.1·10⁻¹⁹ on a coordinate that would otherwise stay at
//! or near 0 ([`OFFSET_FLOOR`]): it matters only to geometry within 10⁻¹⁹ of a coordinate plane,
//! that is, to scenes whose units are below ~10⁻¹².

use glam::Vec3;

/// γₙ = n·ε / (1 − n·ε), ε = half an ulp of 1: the bound on n rounded f32 operations.
#[inline]
#[must_use]
pub const fn gamma(n: i32) -> f32 {
    let e = f32::EPSILON * 0.5;
    (n as f32 * e) / (1.0 - n as f32 * e)
}

/// Absolute error bound of a point interpolated from barycentrics.
#[inline]
#[must_use]
pub fn barycentric_error(b: [f32; 3], p0: Vec3, p1: Vec3, p2: Vec3) -> Vec3 {
    ((b[0] * p0).abs() + (b[1] * p1).abs() + (b[2] * p2).abs()) * gamma(7)
}

/// The smallest magnitude an offset coordinate moves to: 2⁻⁶³, the square root of the smallest
/// normal float. From a coordinate of 0 (a wall on a coordinate plane, whose error bound along
/// its normal is 0) one ulp is a subnormal; the smallest normal float itself is no better, as
/// every product of it with a factor below 1 (a box test's inverse direction, the triangle test's
/// shear) is subnormal again. Each subnormal operand or result costs a microcode assist, and
/// these rays test many boxes and triangles: at 2⁻⁶³ the products with factors down to 2⁻⁶³
/// stay normal (the product of two floored coordinates, 2⁻¹²⁶, is the smallest normal float, so
/// a third small factor can still underflow: a cost in speed only, and rare). Measured:
/// BENCHMARKS.md "The origin floor at 2⁻⁶³". An origin further out than its error box is still
/// on the side of the ray.
pub const OFFSET_FLOOR: f32 = 1.084_202_2e-19;

/// The origin for a ray leaving point `p` (error bound `p_error`, geometric normal `n`) toward
/// direction `w`: outside the error box, on the side of `w`.
#[inline]
#[must_use]
pub fn offset_ray_origin(p: Vec3, p_error: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    let d = n.abs().dot(p_error);
    let side = if w.dot(n) < 0.0 { -n } else { n };
    let mut po = p + side * d;
    // One more ulp away from the surface, so that a zero error bound still moves the origin, and
    // at least to [`OFFSET_FLOOR`].
    for i in 0..3 {
        if side[i] > 0.0 {
            po[i] = po[i].next_up();
        } else if side[i] < 0.0 {
            po[i] = po[i].next_down();
        }
        if side[i] != 0.0 && po[i].abs() < OFFSET_FLOOR {
            po[i] = OFFSET_FLOOR.copysign(side[i]);
        }
    }
    po
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_moves_to_the_side_of_w_at_any_scale() {
        for scale in [1e-4f32, 1.0, 1e5] {
            let p = Vec3::new(0.3, 0.7, 0.0) * scale;
            let err = barycentric_error([0.2, 0.3, 0.5], Vec3::ZERO, Vec3::X * scale, Vec3::Y * scale);
            let up = offset_ray_origin(p, err, Vec3::Z, Vec3::new(0.1, 0.0, 1.0));
            let down = offset_ray_origin(p, err, Vec3::Z, Vec3::new(0.1, 0.0, -1.0));
            assert!(up.z > 0.0 && down.z < 0.0);
            // The offset is tiny relative to the scale.
            assert!(up.z < scale * 1e-5);
        }
    }

    /// From a point on a coordinate plane with no error along its normal, the origin moves to
    /// the floor on the side of `w`, never to a subnormal (which would slow every test of the
    /// ray), and the floor is such that its products with ordinary factors and with itself are
    /// normal.
    #[test]
    fn offset_from_zero_is_never_subnormal() {
        let p = Vec3::new(0.25, 0.5, 0.0);
        let err = barycentric_error([0.2, 0.3, 0.5], Vec3::ZERO, Vec3::X, Vec3::Y);
        assert_eq!(err.z, 0.0);
        assert_eq!(OFFSET_FLOOR, 2f32.powi(-63));
        assert!((OFFSET_FLOOR * OFFSET_FLOOR).is_normal());
        assert!((OFFSET_FLOOR * 1e-18).is_normal() && (OFFSET_FLOOR / 1e18).is_normal());
        for (w, z) in [(Vec3::Z, OFFSET_FLOOR), (-Vec3::Z, -OFFSET_FLOOR)] {
            let o = offset_ray_origin(p, err, Vec3::Z, w);
            assert_eq!(o.z, z);
            assert_eq!((o.x, o.y), (p.x, p.y));
        }
        // Already beyond the floor: one ulp, as before.
        let o = offset_ray_origin(Vec3::new(0.0, 0.0, 1e-10), Vec3::ZERO, Vec3::Z, Vec3::Z);
        assert_eq!(o.z, 1e-10f32.next_up());
    }
}
