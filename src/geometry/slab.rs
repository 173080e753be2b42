//! The conservative slab test of a ray against a box, shared by every traversal: entry
//! distance with the far distance grown by 1 + 2γ₃ (pbrt-v4 §6.1.2), and inverse directions
//! that stay finite (zero components get ±f32::MAX, so no 0·∞ NaN can arise). Reads a ray and a
//! box; writes an entry distance.

use super::offset::gamma;
use glam::{Vec3, Vec3A};

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

/// Inverse direction with finite components.
#[inline]
#[must_use]
pub fn inverse_direction(d: Vec3) -> Vec3 {
    Vec3::new(safe_inverse(d.x), safe_inverse(d.y), safe_inverse(d.z))
}
