//! Spawning rays off surfaces without self-intersection and without a fixed epsilon.
//!
//! The hit point is computed from barycentrics, whose rounding error is bounded by
//! γ₇·(|b0·p0| + |b1·p1| + |b2·p2|) per axis (pbrt-v4 §6.8.6). The new origin is pushed along the
//! geometric normal just past that error box, then one ulp further away from the surface, so the
//! offset scales with the scene: a Cornell box at 1e-4 or 1e5 units behaves the same.

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

/// The origin for a ray leaving point `p` (error bound `p_error`, geometric normal `n`) toward
/// direction `w`: outside the error box, on the side of `w`.
#[inline]
#[must_use]
pub fn offset_ray_origin(p: Vec3, p_error: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    let d = n.abs().dot(p_error);
    let side = if w.dot(n) < 0.0 { -n } else { n };
    let mut po = p + side * d;
    // One more ulp away from the surface, so that a zero error bound still moves the origin.
    for i in 0..3 {
        if side[i] > 0.0 {
            po[i] = po[i].next_up();
        } else if side[i] < 0.0 {
            po[i] = po[i].next_down();
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
}
