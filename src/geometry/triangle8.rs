//! The watertight ray/triangle test of [`super::triangle`], 8 lanes at a time, in its two
//! shapes: eight rays against one triangle (packets, [`super::packet`]) and one ray against
//! eight triangles (a [`TriBlock`] of the 8-wide BVH's leaves, [`super::wide_traverse`]). Reads
//! sheared vertices or blocks; writes per-lane hits, t and barycentrics.
//!
//! Both run `watertight8`: the scalar test's operations in the same order (no fused
//! multiply-adds on either side), so every lane's decision, t and barycentrics are
//! bit-identical to [`super::triangle::intersect_triangle`]'s (its scalar twin). The scalar test
//! recomputes in f64 edge functions that round to exactly zero and the sign of a t that f32
//! cannot prove positive; lanes where either happens are handed back for the scalar test to
//! decide.

use super::offset::gamma;
use super::triangle::{dominant_axis, is_degenerate, TINY_T_TERM};
use glam::Vec3;
use wide::f32x8;

/// The watertight test after translation, permutation and shear: `x`, `y` the sheared
/// coordinates of the three vertices, `z` their permuted (unscaled) z, `sz` = 1/d'z, `t_max`
/// the exclusive bound on t. Returns (hit lanes, lanes the scalar test must decide, t, b0, b1,
/// b2), both masks within `lanes`.
#[inline(always)]
#[allow(clippy::many_single_char_names)]
pub(super) fn watertight8(
    x: [f32x8; 3],
    y: [f32x8; 3],
    z: [f32x8; 3],
    sz: f32x8,
    t_max: f32x8,
    lanes: u32,
) -> (u32, u32, f32x8, [f32x8; 3]) {
    let ([x0, x1, x2], [y0, y1, y2], [z0, z1, z2]) = (x, y, z);
    let e0 = x1 * y2 - y1 * x2;
    let e1 = x2 * y0 - y2 * x0;
    let e2 = x0 * y1 - y0 * x1;
    let zero = f32x8::ZERO;
    let any_zero = e0.simd_eq(zero) | e1.simd_eq(zero) | e2.simd_eq(zero);
    let fallback = bits(any_zero) & lanes;
    let neg = e0.simd_lt(zero) | e1.simd_lt(zero) | e2.simd_lt(zero);
    let pos = e0.simd_gt(zero) | e1.simd_gt(zero) | e2.simd_gt(zero);
    // Most tests miss on the edges or on t's range: the rest (a division and t's error bound)
    // runs only while some lane may still hit.
    let none = (0, 0, zero, [zero; 3]);
    let edges = !(neg & pos);
    if bits(edges) & lanes | fallback == 0 {
        return none;
    }
    let det = e0 + e1 + e2;
    // The shear's error is in length units: it takes z before the scaling to ray parameters.
    let max_z_len = z0.abs().max(z1.abs()).max(z2.abs());
    // Rounding is monotonic, so this is the largest scaled |z| exactly, as the scalar test has it.
    let max_zt = max_z_len * sz.abs();
    let plane = edges & det.simd_ne(zero) & det.is_finite();
    // Magnitudes too small for t in f32: the scalar test decides in f64.
    let tiny = plane & (det.abs() * max_zt).simd_lt(f32x8::splat(TINY_T_TERM));
    let fallback = fallback | (bits(tiny) & lanes);
    let (z0, z1, z2) = (z0 * sz, z1 * sz, z2 * sz);
    let t_scaled = e0 * z0 + e1 * z1 + e2 * z2;
    let bound = t_max * det;
    let det_neg = det.simd_lt(zero) & (t_scaled.simd_ge(zero) | t_scaled.simd_lt(bound));
    let det_pos = det.simd_gt(zero) & (t_scaled.simd_le(zero) | t_scaled.simd_gt(bound));
    let in_range = plane & !det_neg & !det_pos;
    if bits(in_range) & lanes | fallback == 0 {
        return none;
    }
    let inv_det = f32x8::ONE / det;
    let t = t_scaled * inv_det;
    // pbrt-v4's bound on t's error; t must exceed it.
    let delta_z = f32x8::splat(gamma(3)) * max_zt;
    let max_xt = x0.abs().max(x1.abs()).max(x2.abs());
    let max_yt = y0.abs().max(y1.abs()).max(y2.abs());
    let delta_x = f32x8::splat(gamma(5)) * (max_xt + max_z_len);
    let delta_y = f32x8::splat(gamma(5)) * (max_yt + max_z_len);
    let delta_e = f32x8::splat(2.0) * (f32x8::splat(gamma(2)) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = e0.abs().max(e1.abs()).max(e2.abs());
    let delta_t = f32x8::splat(3.0)
        * (f32x8::splat(gamma(3)) * max_e * max_zt + delta_e * max_zt + delta_z * max_e)
        * inv_det.abs();
    let inside = in_range & t.simd_lt(t_max);
    let ok = inside & t.simd_gt(delta_t);
    // Where f32 cannot prove t > 0 (slivers), the scalar test decides in f64.
    let undecided = inside & t.simd_gt(zero) & !t.simd_gt(delta_t);
    let fallback = fallback | (bits(undecided) & lanes);
    let hit = bits(ok) & lanes & !fallback;
    (hit, fallback, t, [e0 * inv_det, e1 * inv_det, e2 * inv_det])
}

/// Bit mask of lanes where `m` is set.
#[inline(always)]
pub(super) fn bits(m: f32x8) -> u32 {
    m.to_bitmask()
}

/// Up to eight triangles of one leaf as SoA columns: vertex k's axis a in `v[3k + a]`; lane l is
/// triangle `first + l`.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct TriBlock {
    /// Vertex columns: p0.x, p0.y, p0.z, p1.x, …, p2.z.
    pub v: [[f32; 8]; 9],
    /// Triangle index (of the BVH-ordered columns) per lane; padding lanes repeat the last.
    pub ids: [u32; 8],
    /// Lanes holding a triangle that can be hit (not padding, not degenerate).
    pub live: u8,
}

impl TriBlock {
    /// Blocks for the triangles `ids` (indices of the BVH-ordered vertices `tri(id)`), eight to
    /// a block.
    pub fn push_leaf(out: &mut Vec<TriBlock>, ids: &[u32], tri: impl Fn(u32) -> [Vec3; 3]) {
        for chunk in ids.chunks(8) {
            let last = chunk[chunk.len() - 1];
            let mut b = TriBlock { v: [[0.0; 8]; 9], ids: [last; 8], live: 0 };
            for (l, &id) in chunk.iter().enumerate() {
                b.ids[l] = id;
                let p = tri(id);
                for (k, v) in p.iter().enumerate() {
                    for a in 0..3 {
                        b.v[3 * k + a][l] = v[a];
                    }
                }
                if !is_degenerate(p[0], p[1], p[2]) {
                    b.live |= 1 << l;
                }
            }
            out.push(b);
        }
    }

    /// Lane `l`'s triangle.
    #[inline]
    #[must_use]
    pub fn triangle(&self, l: usize) -> [Vec3; 3] {
        // Written out, not `[0, 1, 2].map(..)`: the map was left out of line wherever the
        // traversals inlined this fallback.
        let vertex = |k: usize| Vec3::new(self.v[3 * k][l], self.v[3 * k + 1][l], self.v[3 * k + 2][l]);
        [vertex(0), vertex(1), vertex(2)]
    }
}

/// One ray prepared for [`intersect_block`]: its axis permutation (z = the direction's largest
/// axis, as [`super::triangle::intersect_triangle`] chooses it) and shear, splatted.
#[derive(Clone, Copy, Debug)]
pub struct ShearedRay {
    /// Source axes of the permuted x, y, z.
    axes: [usize; 3],
    /// Permuted origin.
    o: [f32x8; 3],
    sx: f32x8,
    sy: f32x8,
    sz: f32x8,
    /// The ray, for the scalar fallbacks.
    pub origin: Vec3,
    /// Its direction.
    pub dir: Vec3,
}

impl ShearedRay {
    /// Prepares the ray `o + t·d` (d finite and non-zero).
    #[inline]
    #[must_use]
    pub fn new(o: Vec3, d: Vec3) -> Self {
        // Arrays, not glam's `Vec3` indexing (a match on the index: branches the ray decides).
        const NEXT: [usize; 3] = [1, 2, 0];
        let kz = dominant_axis(d);
        let kx = NEXT[kz];
        let ky = NEXT[kx];
        let (oa, da) = (o.to_array(), d.to_array());
        let (dx, dy, dz) = (da[kx], da[ky], da[kz]);
        ShearedRay {
            axes: [kx, ky, kz],
            o: [f32x8::splat(oa[kx]), f32x8::splat(oa[ky]), f32x8::splat(oa[kz])],
            sx: f32x8::splat(-dx / dz),
            sy: f32x8::splat(-dy / dz),
            sz: f32x8::splat(1.0 / dz),
            origin: o,
            dir: d,
        }
    }
}

/// One ray against the eight lanes of `block` within (0, `t_max`): (hit lanes, lanes for the
/// scalar test, t, b0, b1, b2), as `watertight8`.
#[inline(always)]
#[must_use]
pub fn intersect_block(r: &ShearedRay, block: &TriBlock, t_max: f32) -> (u32, u32, f32x8, [f32x8; 3]) {
    let [kx, ky, kz] = r.axes;
    let col = |k: usize, a: usize| f32x8::from(block.v[3 * k + a]);
    let vertex = |k: usize| {
        let x = col(k, kx) - r.o[0];
        let y = col(k, ky) - r.o[1];
        let z = col(k, kz) - r.o[2];
        (x + r.sx * z, y + r.sy * z, z)
    };
    let (x0, y0, z0) = vertex(0);
    let (x1, y1, z1) = vertex(1);
    let (x2, y2, z2) = vertex(2);
    watertight8([x0, x1, x2], [y0, y1, y2], [z0, z1, z2], r.sz, f32x8::splat(t_max), u32::from(block.live))
}
