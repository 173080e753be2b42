//! Watertight ray/triangle intersection (Woop, Benthin & Wald, JCGT 2013), with the conservative
//! t > 0 bound of pbrt-v4 (Pharr, Jakob & Humphreys, §6.8.4).
//!
//! The ray is translated to the origin and sheared so that it runs along +z; the edge functions
//! are then 2-D cross products that agree in sign along shared edges, so a ray through an edge
//! or vertex hits at least one of the triangles that share it. Edge functions that round to
//! exactly zero are recomputed in f64. Where the f32 bound cannot prove t > 0, or t's products
//! underflow, t's sign is decided in f64 with a bound taken term by term (`t_f64`).

use super::offset::gamma;
use glam::Vec3;

/// The largest coordinate magnitude, in scene units, for which intersection is guaranteed
/// watertight: every vertex, light position and camera must lie within ±`MAX_COORDINATE`, and
/// scenes beyond it are refused at load. The test's f32 products stay finite there with a wide
/// margin: edge functions grow as R² (≤ 3.2·10²¹), t·det as R³ times 1/|d.z| (≤ 2·10³⁰·/|d.z|).
/// Far beyond it they overflow — the cargo-fuzz target `edge_rays` found a ray slipping
/// between two triangles at coordinates of 10¹⁷ with wings of 10¹⁹ — and a fallback in f64 for
/// one of two triangles sharing an edge would round that edge differently from the other,
/// which is itself a crack. Scale such scenes down (`scale` in the scene file).
pub const MAX_COORDINATE: f32 = 1e10;

/// Whether `p` lies within ±[`MAX_COORDINATE`] on every axis (false for NaN).
#[inline]
#[must_use]
pub fn in_range(p: Vec3) -> bool {
    p.abs().max_element() <= MAX_COORDINATE
}

/// The unit normal (counter-clockwise) and area of a triangle: in f32 as everywhere else, and in
/// f64 where the f32 cross product's squared length overflows (edges longer than about 10⁹) or
/// leaves the normal range (edges shorter than about 10⁻¹⁹), so that large and tiny triangles
/// within ±[`MAX_COORDINATE`] keep their area. (0, 0) for a degenerate triangle.
#[must_use]
pub fn normal_and_area(p0: Vec3, p1: Vec3, p2: Vec3) -> (Vec3, f32) {
    let c = (p1 - p0).cross(p2 - p0);
    let len2 = c.length_squared();
    if len2.is_finite() && len2 >= f32::MIN_POSITIVE {
        return (c.normalize(), 0.5 * c.length());
    }
    let c = (p1 - p0).as_dvec3().cross((p2 - p0).as_dvec3());
    let len = c.length();
    if len > 0.0 && len.is_finite() {
        ((c / len).as_vec3(), (0.5 * len) as f32)
    } else {
        (Vec3::ZERO, 0.0)
    }
}

/// A ray/triangle hit: distance and barycentrics (b0 weights p0, …).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Barycentric weights of p0, p1, p2 (sum to 1).
    pub b: [f32; 3],
}

/// `v` with axis `kz` moved to z and the other two following cyclically (x, y keep handedness).
#[inline]
#[must_use]
pub fn permute(v: Vec3, kz: usize) -> Vec3 {
    let kx = (kz + 1) % 3;
    let ky = (kx + 1) % 3;
    Vec3::new(v[kx], v[ky], v[kz])
}

/// The axis along which |d| is largest (ties resolved toward z, then y).
#[inline]
#[must_use]
pub fn dominant_axis(d: Vec3) -> usize {
    let ad = d.abs();
    // x when it beats y and z; else y when it beats z; else z. Bitwise `&`, no branches: the
    // ray's direction decides them, so a branch is mispredicted often.
    let x = (ad.x > ad.y) & (ad.x > ad.z);
    let y = !(ad.x > ad.y) & (ad.y > ad.z);
    2 - 2 * usize::from(x) - usize::from(y)
}

/// True for a zero-area triangle (never hit): its edges' cross product is exactly zero.
/// Its components are compared, not its squared length, which underflows for edges shorter
/// than about 10⁻¹¹: a closed mesh of triangles that small leaked where the fuzzer aimed
/// (fuzz/regressions/edge_rays/tiny-edge-1e-12-at-2e-7).
#[inline]
#[must_use]
pub fn is_degenerate(p0: Vec3, p1: Vec3, p2: Vec3) -> bool {
    (p2 - p0).cross(p1 - p0) == Vec3::ZERO
}

/// Intersects the ray `o + t·d`, 0 < t < `t_max`, with the triangle (p0, p1, p2).
/// Degenerate (zero-area) triangles and rays with a zero or non-finite direction never hit.
#[inline]
#[must_use]
pub fn intersect_triangle(o: Vec3, d: Vec3, t_max: f32, p0: Vec3, p1: Vec3, p2: Vec3) -> Option<TriangleHit> {
    match intersect_f32(o, d, t_max, p0, p1, p2) {
        F32Test::Hit(h) => Some(h),
        F32Test::Miss => None,
        // The f32 bound on t's error is loose for slivers: their det is tiny beside the edge
        // functions' error, and the bound can exceed a t of 1 — two slivers sharing an edge
        // would both refuse a ray through it, and a closed mesh would leak. Decide in f64.
        F32Test::Unproven(h) => positive_t_f64(o, d, [p0, p1, p2]).then_some(h),
        // Coordinates so small (≲ 10⁻¹³ of the ray's length scale) that f32's products for t
        // underflow: t and the barycentrics in f64, the edges' f32 decision kept.
        F32Test::Tiny => {
            let (t, proven, b) = t_f64(o, d, [p0, p1, p2])?;
            let t32 = t as f32;
            let b = b.map(|v| v as f32);
            (proven && t32 < t_max && t32 > 0.0 && b.iter().all(|v| v.is_finite())).then_some(TriangleHit { t: t32, b })
        }
    }
}

/// Below this, the product of the determinant (for a ray inside the edges, one to three times
/// the largest edge function) and the largest scaled z — about the largest term of t's
/// numerator — comes so near f32's subnormal range that t (or its error bound) underflows: such
/// a test is decided in f64 (`F32Test::Tiny`). Reached only by triangles
/// and origins ~10⁻¹³ apart or less, far below any scene's features; the SIMD tests hand such
/// lanes to the scalar test.
pub const TINY_T_TERM: f32 = 7.888_609e-31;

/// What the f32 test decided.
enum F32Test {
    Hit(TriangleHit),
    Miss,
    /// Inside the edges at 0 < t < t_max, but t does not exceed the bound on its error.
    Unproven(TriangleHit),
    /// Inside the edges, with magnitudes too small for t in f32 ([`TINY_T_TERM`]).
    Tiny,
}

#[inline(always)]
fn intersect_f32(o: Vec3, d: Vec3, t_max: f32, p0: Vec3, p1: Vec3, p2: Vec3) -> F32Test {
    use F32Test::Miss;
    if is_degenerate(p0, p1, p2) {
        return Miss;
    }
    // Axis along which the direction is largest becomes z.
    let kz = dominant_axis(d);
    let d = permute(d, kz);
    if d.z == 0.0 || !d.is_finite() {
        return Miss;
    }
    let mut p0t = permute(p0 - o, kz);
    let mut p1t = permute(p1 - o, kz);
    let mut p2t = permute(p2 - o, kz);

    let sx = -d.x / d.z;
    let sy = -d.y / d.z;
    let sz = 1.0 / d.z;
    p0t.x += sx * p0t.z;
    p0t.y += sy * p0t.z;
    p1t.x += sx * p1t.z;
    p1t.y += sy * p1t.z;
    p2t.x += sx * p2t.z;
    p2t.y += sy * p2t.z;

    let mut e0 = p1t.x * p2t.y - p1t.y * p2t.x;
    let mut e1 = p2t.x * p0t.y - p2t.y * p0t.x;
    let mut e2 = p0t.x * p1t.y - p0t.y * p1t.x;
    // Only the edge functions that are exactly zero are recomputed in f64. pbrt-v4 recomputes
    // all three when any is zero, but then a triangle whose *other* edge is zero rounds the
    // edge it shares with a neighbour differently from that neighbour (f64 against f32), and
    // where the f32 value's sign is wrong both can refuse a ray through it (found by the
    // cargo-fuzz target `edge_rays`: fuzz/regressions/edge_rays/). A shared edge's f32 value is
    // exactly the negation of its neighbour's, so it is zero for both or for neither.
    let f = |ax: f32, ay: f32, bx: f32, by: f32| (ax as f64 * by as f64 - ay as f64 * bx as f64) as f32;
    if e0 == 0.0 {
        e0 = f(p1t.x, p1t.y, p2t.x, p2t.y);
    }
    if e1 == 0.0 {
        e1 = f(p2t.x, p2t.y, p0t.x, p0t.y);
    }
    if e2 == 0.0 {
        e2 = f(p0t.x, p0t.y, p1t.x, p1t.y);
    }
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return Miss;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 || !det.is_finite() {
        return Miss;
    }
    // The shear's error (below) is in length units: it takes z before the scaling to ray
    // parameters. pbrt-v4 uses the scaled z there, which is the same only for |d| ≈ 1; a shadow
    // ray aimed at a light point (|d| = the distance) in a scene 1e-4 units across then rejects
    // true hits as "not provably positive" and light leaks through closed objects.
    let max_z_len = p0t.z.abs().max(p1t.z.abs()).max(p2t.z.abs());
    // Rounding is monotonic, so this is the largest scaled |z| exactly, one product cheaper.
    let max_zt = max_z_len * sz.abs();
    if det.abs() * max_zt < TINY_T_TERM {
        return F32Test::Tiny;
    }
    p0t.z *= sz;
    p1t.z *= sz;
    p2t.z *= sz;
    let t_scaled = e0 * p0t.z + e1 * p1t.z + e2 * p2t.z;
    if det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det) {
        return Miss;
    }
    if det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det) {
        return Miss;
    }
    let inv_det = 1.0 / det;
    let b = [e0 * inv_det, e1 * inv_det, e2 * inv_det];
    let t = t_scaled * inv_det;
    if !(t < t_max) {
        return Miss;
    }

    // Reject hits whose t is not provably positive (pbrt-v4 eq. 6.8.4 bounds).
    let delta_z = gamma(3) * max_zt;
    let max_xt = p0t.x.abs().max(p1t.x.abs()).max(p2t.x.abs());
    let max_yt = p0t.y.abs().max(p1t.y.abs()).max(p2t.y.abs());
    let delta_x = gamma(5) * (max_xt + max_z_len);
    let delta_y = gamma(5) * (max_yt + max_z_len);
    let delta_e = 2.0 * (gamma(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = e0.abs().max(e1.abs()).max(e2.abs());
    let delta_t = 3.0 * (gamma(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv_det.abs();
    if t > delta_t {
        F32Test::Hit(TriangleHit { t, b })
    } else if t > 0.0 {
        F32Test::Unproven(TriangleHit { t, b })
    } else {
        Miss
    }
}

/// γₙ in f64.
fn gamma64(n: f64) -> f64 {
    let e = f64::EPSILON * 0.5;
    n * e / (1.0 - n * e)
}

/// Whether the ray provably meets the triangle's plane at t > 0, by the same steps as
/// [`intersect_triangle`] in f64 with the error bound of [`t_f64`]. Only the sign of t is decided
/// here: the hit, t and barycentrics stay the f32 ones, so neighbouring triangles still agree on
/// which of them an edge belongs to.
#[cold]
#[inline(never)]
fn positive_t_f64(o: Vec3, d: Vec3, p: [Vec3; 3]) -> bool {
    t_f64(o, d, p).is_some_and(|(_, proven, _)| proven)
}

/// t of the ray's meeting with the triangle's plane, whether t > 0 is proven, and the
/// barycentrics, by the steps of [`intersect_triangle`] in f64; `None` where the plane is
/// parallel to the ray.
///
/// The proof bounds the rounding error of every vertex, edge function and term of t's numerator
/// on its own, where pbrt-v4's bound (the f32 test's) takes the largest coordinate, edge function
/// and z for all three. The two differ on a sliver whose third vertex is far away: its shear
/// error then weighs on the two short vertices' edge function as if it were theirs. The fuzzer
/// found a ray through an edge 6.9·10⁻⁶ long between wings 4.2·10⁶ and 4.3·10⁹ away, at t = 6·10⁻⁶,
/// that both triangles refused because that bound was 3·10¹⁰ even in f64; per term it is 10⁻¹⁰
/// of t (fuzz/regressions/edge_rays/sliver-edge-between-far-wings).
///
/// The bound, with γₙ = nε/(1 − nε): a sheared coordinate x = (v.x − o.x) + sx·(v.z − o.z), |sx| ≤ 1,
/// is off by at most δx = γ₅(|x| + |z|) (z in length units), likewise y; the scaled z by γ₃|z·sz|.
/// The edge function e = xᵢyⱼ − yᵢxⱼ is off by γ₂(|xᵢyⱼ| + |yᵢxⱼ|) from its rounded inputs plus
/// δxᵢ|yⱼ| + |xᵢ|δyⱼ + δyᵢ|xⱼ| + |yᵢ|δxⱼ + δxᵢδyⱼ + δyᵢδxⱼ from their errors, all widened by
/// (1 + γ₂). t's numerator Σ eₖ zₖ is off by γ₃Σ|eₖzₖ| + Σ(δeₖ|zₖ| + |eₖ|δzₖ + δeₖδzₖ), the
/// determinant Σ eₖ by γ₂Σ|eₖ| + Σδeₖ. t > 0 is proven when both exceed their bounds and share
/// their sign.
#[cold]
#[inline(never)]
fn t_f64(o: Vec3, d: Vec3, p: [Vec3; 3]) -> Option<(f64, bool, [f64; 3])> {
    let kz = dominant_axis(d);
    let perm = |v: Vec3| {
        let v = permute(v, kz);
        [f64::from(v.x), f64::from(v.y), f64::from(v.z)]
    };
    let (o, d) = (perm(o), perm(d));
    let (sx, sy, sz) = (-d[0] / d[2], -d[1] / d[2], 1.0 / d[2]);
    let q = p.map(|v| {
        let v = perm(v);
        let z = v[2] - o[2];
        [v[0] - o[0] + sx * z, v[1] - o[1] + sy * z, z]
    });
    // Edge k is opposite vertex k: it joins vertices k + 1 and k + 2.
    let ends = |k: usize| (q[(k + 1) % 3], q[(k + 2) % 3]);
    let e = [0, 1, 2].map(|k| {
        let (a, b) = ends(k);
        a[0] * b[1] - a[1] * b[0]
    });
    let det = e[0] + e[1] + e[2];
    let zt = q.map(|v| v[2] * sz);
    let num = e[0] * zt[0] + e[1] * zt[1] + e[2] * zt[2];

    let (g2, g3, g5) = (gamma64(2.0), gamma64(3.0), gamma64(5.0));
    let dx = |v: [f64; 3]| g5 * (v[0].abs() + v[2].abs());
    let dy = |v: [f64; 3]| g5 * (v[1].abs() + v[2].abs());
    let de = [0, 1, 2].map(|k| {
        let (a, b) = ends(k);
        let (ax, ay, bx, by) = (a[0].abs(), a[1].abs(), b[0].abs(), b[1].abs());
        let (dax, day, dbx, dby) = (dx(a), dy(a), dx(b), dy(b));
        (1.0 + g2) * (g2 * (ax * by + ay * bx) + dax * by + ax * dby + day * bx + ay * dbx + dax * dby + day * dbx)
    });
    let mut num_err = 0.0;
    for k in 0..3 {
        let (ek, zk, dz) = (e[k].abs(), zt[k].abs(), g3 * zt[k].abs());
        num_err += g3 * ek * zk + de[k] * zk + ek * dz + de[k] * dz;
    }
    let det_err = g2 * (e[0].abs() + e[1].abs() + e[2].abs()) + de[0] + de[1] + de[2];
    let proven = num.abs() > num_err && det.abs() > det_err && (num > 0.0) == (det > 0.0);
    (det != 0.0).then_some((num / det, proven, e.map(|v| v / det)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The axis of largest |d|, ties going to z, then to y: every combination of magnitudes 0,
    /// 1 and 2 with both signs, against that rule stated directly.
    #[test]
    fn dominant_axis_is_the_largest_magnitude_ties_to_z_then_y() {
        let values = [0.0, -0.0, 1.0, -1.0, 2.0, -2.0];
        for &x in &values {
            for &y in &values {
                for &z in &values {
                    let (ax, ay, az) = (f32::abs(x), f32::abs(y), f32::abs(z));
                    let expected = if az >= ax.max(ay) {
                        2
                    } else if ay >= ax {
                        1
                    } else {
                        0
                    };
                    assert_eq!(dominant_axis(Vec3::new(x, y, z)), expected, "d = ({x}, {y}, {z})");
                }
            }
        }
    }

    /// Two slivers 10⁻⁶ wide sharing an edge, and a ray through the edge's midpoint from 1 away:
    /// f32's bound on t's error exceeds t itself (1.8 against 1), so both refused the ray and a
    /// closed mesh leaked; with the f64 decision the edge is hit (by one or both: watertightness
    /// promises at least one).
    #[test]
    fn a_ray_through_an_edge_between_slivers_hits() {
        let (a, b) = (Vec3::new(-1e-6, 0.0, 1.0), Vec3::new(0.0, 0.0, 1.0));
        let above = [Vec3::new(-1e-6, 0.5, 1.0), b, a];
        let below = [a, b, Vec3::new(0.0, -1e-6, 1.0)];
        let d = (a + b) * 0.5;
        let hits: Vec<_> = [above, below]
            .iter()
            .filter_map(|p| intersect_triangle(Vec3::ZERO, d, f32::INFINITY, p[0], p[1], p[2]))
            .collect();
        assert!(!hits.is_empty() && hits.iter().all(|h| (h.t - 1.0).abs() < 1e-6), "{hits:?}");
    }

    /// An edge 6.9·10⁻⁶ long whose two wings reach 4.2·10⁶ and 4.3·10⁹ away, and a ray from
    /// the origin through its middle (found by the fuzzer). The f32 test puts the ray inside one
    /// of the two; bounding t's error with the largest coordinates, as pbrt-v4 does, gave 3·10¹⁰
    /// even in f64 against t = 6·10⁻⁶, so neither accepted the ray. Per term the bound proves t > 0.
    #[test]
    fn a_ray_through_a_sliver_edge_between_far_wings_hits() {
        let a = Vec3::new(6.866_657_3e-6, 0.0, 3.700_852_6e-16);
        let b = Vec3::new(0.0, 6.866_495e-6, 6.866_657_7e-6);
        let c1 = Vec3::new(0.0, -4_227_069.0, 0.0);
        let c2 = Vec3::new(0.0, 0.0, -4_295_094_300.0);
        let d = (a + (b - a) * 0.503_894_75).normalize();
        let hits: Vec<_> = [[a, b, c1], [b, a, c2]]
            .iter()
            .filter_map(|p| intersect_triangle(Vec3::ZERO, d, f32::INFINITY, p[0], p[1], p[2]))
            .collect();
        let want = (a + (b - a) * 0.503_894_75).length();
        assert!(!hits.is_empty() && hits.iter().all(|h| (h.t - want).abs() < 1e-5 * want), "{hits:?}");
    }

    /// A shadow ray's direction is the vector to the light point, so its length is a distance in
    /// scene units, and t runs over [0, 1]. A triangle 10⁻³ of that distance across must be hit
    /// at every scale; when the positivity bound mixed t with lengths, it was lost at 1e-4.
    #[test]
    fn unnormalised_rays_hit_small_triangles_at_any_scale() {
        for s in [1e-4f32, 1.0, 1e5] {
            let a = 1e-3 * s;
            let (p0, p1, p2) = (Vec3::new(-a, -a, 0.5 * s), Vec3::new(a, -a, 0.5 * s), Vec3::new(0.0, a, 0.5 * s));
            for d in [Vec3::new(0.0, 0.0, s), Vec3::Z, Vec3::new(1e-4 * s, 2e-4 * s, s)] {
                let h = intersect_triangle(Vec3::ZERO, d, f32::INFINITY, p0, p1, p2);
                let want = 0.5 * s / d.z;
                assert!(h.is_some_and(|h| (h.t - want).abs() <= 1e-6 * want), "scale {s}, d {d}: {h:?}");
            }
        }
    }

    #[test]
    fn hits_centre_and_misses_outside() {
        let (p0, p1, p2) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let h = intersect_triangle(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z, f32::INFINITY, p0, p1, p2).unwrap();
        assert!((h.t - 1.0).abs() < 1e-6);
        assert!((h.b[0] - 0.5).abs() < 1e-6 && (h.b[1] - 0.25).abs() < 1e-6);
        assert!(intersect_triangle(Vec3::new(0.75, 0.75, 1.0), -Vec3::Z, f32::INFINITY, p0, p1, p2).is_none());
        // Behind the origin and beyond t_max.
        assert!(intersect_triangle(Vec3::new(0.25, 0.25, 1.0), Vec3::Z, f32::INFINITY, p0, p1, p2).is_none());
        assert!(intersect_triangle(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z, 0.5, p0, p1, p2).is_none());
    }

    #[test]
    fn shared_edge_is_watertight() {
        // Two triangles sharing the diagonal of the unit square; rays along the diagonal hit one.
        let (a, b, c, d) = (Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y);
        for i in 0..=1000 {
            let s = i as f32 / 1000.0;
            let o = Vec3::new(s, s, 1.0);
            let dir = Vec3::new(0.0, 0.0, -1.0);
            let h1 = intersect_triangle(o, dir, f32::INFINITY, a, b, c);
            let h2 = intersect_triangle(o, dir, f32::INFINITY, a, c, d);
            assert!(h1.is_some() || h2.is_some(), "ray at s={s} slipped through the shared edge");
        }
    }

    #[test]
    fn degenerate_triangles_and_zero_directions_never_hit() {
        let o = Vec3::new(0.0, 0.0, 1.0);
        assert!(intersect_triangle(o, -Vec3::Z, 10.0, Vec3::ZERO, Vec3::X, Vec3::X * 2.0).is_none());
        assert!(intersect_triangle(o, Vec3::ZERO, 10.0, Vec3::ZERO, Vec3::X, Vec3::Y).is_none());
        assert!(intersect_triangle(o, Vec3::splat(f32::NAN), 10.0, Vec3::ZERO, Vec3::X, Vec3::Y).is_none());
    }
}
