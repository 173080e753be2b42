//! Packet traversal: 8 rays at a time (`wide::f32x8`) through the obvhs BVH2, masks rather than
//! branches. A node's two child boxes are tested against all 8 rays at once; a child is visited
//! while any lane enters it before its current closest hit. Leaves test each triangle against
//! all 8 rays with an 8-wide form of the watertight test that is bit-identical to the scalar one
//! (see `intersect8`). Any-hit traversal tests leaf children as soon as their parent is
//! reached, before entering an inner sibling: a leaf is cheap and usually ends the lanes that
//! leave a finely tessellated surface (3–4× faster on the 1 M-triangle sphere's bounce rays);
//! closest-hit traversal does not, since a far leaf is usually pruned by a nearer hit. When a
//! node is reached by at most `thin` active lanes ([`THIN_LANES`] by default), those lanes finish
//! its subtree by single-ray traversal.
//!
//! Decisions match [`super::traverse`] (same conservative box test, same triangle test, every
//! hit's t settled into its triangle's box by [`super::slab::settle`]'s operations, ties to the
//! lower triangle index), so hits are identical lane by lane; tests/packet.rs checks it.

use super::bvh::{Bvh, Hit, TriangleColumns};
use super::cut_out::kept_lanes;
use super::slab::{intersect_settled, settle8, slab8, triangle_box};
use super::traverse::{closest_from, occluded_from, Best, RayQuery, Stack};
use super::triangle::is_degenerate;
use super::triangle8::{bits, watertight8};
use glam::Vec3;
use obvhs::bvh2::node::Bvh2Node;
use wide::f32x8;

/// Lanes per packet.
pub const LANES: usize = 8;

/// A node reached by this many active lanes or fewer is finished by single-ray traversal.
/// Measured with `photonwave bench --thin-sweep` (BENCHMARKS.md): on every scene and ray set,
/// handing over at 1–4 lanes was slower than staying in the packet (the 8-wide box and triangle
/// tests cost about what one scalar test does), so by default packets never hand over.
pub const THIN_LANES: u32 = 0;

/// Eight rays in SIMD columns.
pub(super) struct Packet {
    ox: f32x8,
    oy: f32x8,
    oz: f32x8,
    dx: f32x8,
    dy: f32x8,
    dz: f32x8,
    ix: f32x8,
    iy: f32x8,
    iz: f32x8,
    /// Per-lane axis permutation of the watertight test (z = the direction's largest axis):
    /// lanes where that axis is z, and where it is x.
    kz2: f32x8,
    kz0: f32x8,
    /// Shear constants −d'x/d'z, −d'y/d'z, 1/d'z of the permuted direction.
    sx: f32x8,
    sy: f32x8,
    sz: f32x8,
    /// The rays' t_max as given (0 in lanes past the slice's end).
    pub(super) t_max: f32x8,
    /// Lanes holding a valid ray.
    pub(super) valid: u32,
}

impl Packet {
    /// Loads up to 8 rays. Validity ([`RayQuery::is_valid`]), inverse directions, the
    /// watertight test's axis choice and its shear are computed 8-wide with the scalar code's
    /// operations (IEEE division, the same comparisons), so every lane's values equal the scalar
    /// ones bit for bit. Lanes without a valid ray hold a stand-in (origin 0, direction +x).
    pub(super) fn load(rays: &[RayQuery]) -> Self {
        // Lanes past the slice's end read zeros: a zero direction and t_max, so not valid.
        let mut c = [[0.0f32; LANES]; 7];
        for (l, r) in rays.iter().take(LANES).enumerate() {
            (c[0][l], c[1][l], c[2][l]) = (r.origin.x, r.origin.y, r.origin.z);
            (c[3][l], c[4][l], c[5][l], c[6][l]) = (r.direction.x, r.direction.y, r.direction.z, r.t_max);
        }
        let (ox, oy, oz) = (f32x8::from(c[0]), f32x8::from(c[1]), f32x8::from(c[2]));
        let (dx, dy, dz, t_max) = (f32x8::from(c[3]), f32x8::from(c[4]), f32x8::from(c[5]), f32x8::from(c[6]));
        let zero = f32x8::ZERO;
        let finite_o = ox.is_finite() & oy.is_finite() & oz.is_finite();
        let finite_d = dx.is_finite() & dy.is_finite() & dz.is_finite();
        let nonzero_d = dx.simd_ne(zero) | dy.simd_ne(zero) | dz.simd_ne(zero);
        let valid = finite_o & finite_d & nonzero_d & t_max.simd_gt(zero);
        let (ox, oy, oz) = (valid.select(ox, zero), valid.select(oy, zero), valid.select(oz, zero));
        let (dx, dy, dz) = (valid.select(dx, f32x8::ONE), valid.select(dy, zero), valid.select(dz, zero));
        // slab::safe_inverse: 1/d, or ±f32::MAX (the sign of d) where that is not finite.
        let (rx, ry, rz) = (f32x8::ONE / dx, f32x8::ONE / dy, f32x8::ONE / dz);
        let safe = |i: f32x8, v: f32x8| i.is_finite().select(i, f32x8::splat(f32::MAX) | (v & f32x8::splat(-0.0)));
        let (ix, iy, iz) = (safe(rx, dx), safe(ry, dy), safe(rz, dz));
        // triangle::dominant_axis: x if |x| > |y| and |x| > |z|; y if not the former and
        // |y| > |z|; z otherwise.
        let (ax, ay, az) = (dx.abs(), dy.abs(), dz.abs());
        let x_gt_y = ax.simd_gt(ay);
        let kz0 = x_gt_y & ax.simd_gt(az);
        let kz1 = !x_gt_y & ay.simd_gt(az);
        let kz2 = !(kz0 | kz1);
        // triangle::permute, then the shear −d'x/d'z, −d'y/d'z, 1/d'z.
        let px = kz2.select(dx, kz0.select(dy, dz));
        let py = kz2.select(dy, kz0.select(dz, dx));
        let pz = kz2.select(dz, kz0.select(dx, dy));
        // 1/d'z is the permuted axis's reciprocal, taken before the safe inverse's substitution.
        let (sx, sy, sz) = (-px / pz, -py / pz, kz2.select(rz, kz0.select(rx, ry)));
        Packet { ox, oy, oz, dx, dy, dz, ix, iy, iz, kz2, kz0, sx, sy, sz, t_max, valid: bits(valid) }
    }

    /// Lane `l`'s origin (for the scalar tests that finish its fallbacks and hand-overs).
    #[inline]
    pub(super) fn origin(&self, l: usize) -> Vec3 {
        Vec3::new(self.ox.as_array()[l], self.oy.as_array()[l], self.oz.as_array()[l])
    }

    /// Lane `l`'s direction.
    #[inline]
    pub(super) fn dir(&self, l: usize) -> Vec3 {
        Vec3::new(self.dx.as_array()[l], self.dy.as_array()[l], self.dz.as_array()[l])
    }

    /// Lane `l`'s inverse direction ([`super::slab::inverse_direction`]'s values).
    #[inline]
    pub(super) fn inv(&self, l: usize) -> Vec3 {
        Vec3::new(self.ix.as_array()[l], self.iy.as_array()[l], self.iz.as_array()[l])
    }

    /// Entry distances into `node`'s box per lane, NaN where a lane misses or enters beyond its
    /// `t_max` (so that every ordered comparison with it is false, even against t_max = ∞): the
    /// 8-wide form of [`box_entry`](super::slab::box_entry), the same operations in the same order.
    #[inline(always)]
    fn entry(&self, node: &Bvh2Node, t_max: f32x8) -> f32x8 {
        let b = &node.aabb;
        self.entry_box([b.min.x, b.min.y, b.min.z], [b.max.x, b.max.y, b.max.z], t_max)
    }

    /// [`Self::entry`] for the box `lo`–`hi`.
    #[inline(always)]
    pub(super) fn entry_box(&self, lo: [f32; 3], hi: [f32; 3], t_max: f32x8) -> f32x8 {
        let (near, far) = self.slab(lo, hi);
        let hit = near.simd_le(far) & near.simd_le(t_max);
        hit.select(near, f32x8::splat(f32::NAN))
    }

    /// Every lane's near and far distances for the box `lo`–`hi` ([`slab8`]).
    #[inline(always)]
    fn slab(&self, lo: [f32; 3], hi: [f32; 3]) -> (f32x8, f32x8) {
        slab8(splat(lo), splat(hi), [self.ox, self.oy, self.oz], [self.ix, self.iy, self.iz])
    }

    /// [`super::slab::settle`] for the eight rays at once: each lane's `t` raised to its entry
    /// into the triangle's box, +∞ where it misses that box ([`settle8`]: the scalar function's
    /// values bit for bit).
    #[inline(always)]
    fn settle(&self, t: f32x8, v: [Vec3; 3], pad: f32) -> f32x8 {
        let (lo, hi) = triangle_box(v, pad);
        settle8(t, splat(lo.into()), splat(hi.into()), [self.ox, self.oy, self.oz], [self.ix, self.iy, self.iz])
    }
}

/// A point's coordinates splatted across the lanes. Written out, not with array maps (left out
/// of line in some builds: BENCHMARKS.md, issue 18, eighth part).
#[inline(always)]
fn splat(v: [f32; 3]) -> [f32x8; 3] {
    [f32x8::splat(v[0]), f32x8::splat(v[1]), f32x8::splat(v[2])]
}

/// The watertight ray/triangle test of [`super::triangle::intersect_triangle`] for 8 rays
/// against one triangle: each lane's vertices relative to its origin, permuted by its axis
/// choice and sheared, then [`watertight8`] (see there for the fallbacks).
#[inline(always)]
fn intersect8(p: &Packet, lanes: u32, v: [Vec3; 3], t_max: f32x8) -> (u32, u32, f32x8, [f32x8; 3]) {
    let perm = |q: Vec3| {
        let x = f32x8::splat(q.x) - p.ox;
        let y = f32x8::splat(q.y) - p.oy;
        let z = f32x8::splat(q.z) - p.oz;
        let px = p.kz2.select(x, p.kz0.select(y, z));
        let py = p.kz2.select(y, p.kz0.select(z, x));
        let pz = p.kz2.select(z, p.kz0.select(x, y));
        (px + p.sx * pz, py + p.sy * pz, pz)
    };
    let (x0, y0, z0) = perm(v[0]);
    let (x1, y1, z1) = perm(v[1]);
    let (x2, y2, z2) = perm(v[2]);
    watertight8([x0, x1, x2], [y0, y1, y2], [z0, z1, z2], p.sz, t_max, lanes)
}

/// [`Best::limit`] per lane.
pub(super) fn limits(best: &[Best; LANES]) -> f32x8 {
    f32x8::from(std::array::from_fn::<f32, LANES, _>(|l| best[l].limit()))
}

/// The best t per lane (the pruning bound of boxes).
pub(super) fn best_ts(best: &[Best; LANES]) -> f32x8 {
    f32x8::from(std::array::from_fn::<f32, LANES, _>(|l| best[l].t))
}

/// The two children of inner `node` with each one's per-lane entry distances and the lanes of
/// `mask` that enter it within `t`, the child most lanes enter first coming first.
#[inline]
fn ordered_children(p: &Packet, nodes: &[Bvh2Node], node: &Bvh2Node, t: f32x8, mask: u32) -> [(u32, f32x8, u32); 2] {
    let (l, r) = (node.first_index, node.first_index + 1);
    let tl = p.entry(&nodes[l as usize], t);
    let tr = p.entry(&nodes[r as usize], t);
    let ml = bits(tl.simd_le(t)) & mask;
    let mr = bits(tr.simd_le(t)) & mask;
    let left_first = (bits(tl.simd_le(tr)) & ml & mr).count_ones() * 2 >= (ml & mr).count_ones();
    if left_first {
        [(l, tl, ml), (r, tr, mr)]
    } else {
        [(r, tr, mr), (l, tl, ml)]
    }
}

/// Tests the triangles `ids` of a leaf against the lanes of `lanes`, keeping each lane's closest
/// hit (ties to the lower index), and refreshes the lanes' `limit`s.
#[inline]
pub(super) fn closest_leaf(
    p: &Packet,
    tris: TriangleColumns<'_>,
    ids: impl IntoIterator<Item = u32>,
    lanes: u32,
    pad: f32,
    best: &mut [Best; LANES],
    limit: &mut f32x8,
) {
    for id in ids {
        let i = id as usize;
        let v = [tris.p0[i], tris.p1[i], tris.p2[i]];
        if is_degenerate(v[0], v[1], v[2]) {
            continue;
        }
        let (hit, mut fallback, t, b) = intersect8(p, lanes, v, *limit);
        if hit | fallback == 0 {
            continue;
        }
        // Only lanes that hit have a t to settle (fallback lanes are decided by the scalar test).
        let t = if hit == 0 { t } else { p.settle(t, v, pad) };
        let mut hit = hit & bits(t.simd_lt(*limit));
        let (t, b) = (t.to_array(), b.map(f32x8::to_array));
        while hit != 0 {
            let l = hit.trailing_zeros() as usize;
            hit &= hit - 1;
            let b = [b[0][l], b[1][l], b[2][l]];
            if !tris.passes(id, b, p.origin(l), p.dir(l)) {
                best[l].offer(t[l], id, b);
            }
        }
        while fallback != 0 {
            let l = fallback.trailing_zeros() as usize;
            fallback &= fallback - 1;
            best[l].test(tris, p.origin(l), p.dir(l), p.inv(l), pad, id);
        }
        *limit = limits(best);
    }
}

/// Closest hits of 8 rays (fewer at the end of a slice).
fn closest8(
    bvh: &Bvh,
    tris: TriangleColumns<'_>,
    rays: &[RayQuery],
    thin: u32,
    out: &mut [Option<Hit>],
    stacks: &mut ClosestStacks,
) {
    let (stack, single) = (&mut stacks.0, &mut stacks.1);
    let nodes = bvh.nodes();
    let p = Packet::load(rays);
    let t_max = p.t_max.to_array();
    let mut best: [Best; LANES] = std::array::from_fn(|l| Best::new(t_max[l]));
    let mut t_best = best_ts(&best);
    let mut limit = limits(&best);
    if !nodes.is_empty() && p.valid != 0 {
        // Invalid lanes are masked off at every pop.
        stack.push((0, Entry(p.entry(&nodes[0], t_best))));
    }
    while let Some((n, Entry(tn))) = stack.pop() {
        // Only valid lanes: children's entry distances are computed for every lane, and an
        // invalid lane holds a stand-in ray (origin 0, direction +x) that must never be traced.
        let mut mask = bits(tn.simd_le(t_best)) & p.valid;
        if mask == 0 {
            continue;
        }
        let node = &nodes[n as usize];
        if mask.count_ones() <= thin {
            let tn = tn.to_array();
            while mask != 0 {
                let l = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                closest_from(bvh, tris, n, tn[l], p.origin(l), p.dir(l), p.inv(l), &mut best[l], single);
            }
            t_best = best_ts(&best);
            limit = limits(&best);
            continue;
        }
        if node.prim_count > 0 {
            closest_leaf(&p, tris, leaf_ids(node), mask, bvh.pad(), &mut best, &mut limit);
            t_best = best_ts(&best);
            continue;
        }
        // The child most of the lanes enter first is visited first.
        let [first, second] = ordered_children(&p, nodes, node, t_best, mask);
        for (child, t, lanes) in [second, first] {
            if lanes != 0 {
                stack.push((child, Entry(t)));
            }
        }
    }
    for (l, o) in out.iter_mut().enumerate() {
        *o = best[l].hit();
    }
}

/// The triangles of leaf `node`.
#[inline(always)]
fn leaf_ids(node: &Bvh2Node) -> std::ops::Range<u32> {
    node.first_index..node.first_index + node.prim_count
}

/// Lanes of `lanes` blocked by a triangle of the leaf's `ids` within (0, t_max).
#[inline]
pub(super) fn any_leaf(
    p: &Packet,
    tris: TriangleColumns<'_>,
    ids: impl IntoIterator<Item = u32>,
    lanes: u32,
    pad: f32,
    t_max: f32x8,
    t_arr: &[f32; LANES],
) -> u32 {
    let mut blocked = 0u32;
    for id in ids {
        let i = id as usize;
        let v = [tris.p0[i], tris.p1[i], tris.p2[i]];
        let open = lanes & !blocked;
        if open == 0 {
            break;
        }
        if is_degenerate(v[0], v[1], v[2]) {
            continue;
        }
        let (hit, mut fallback, t, b) = intersect8(p, open, v, t_max);
        if hit != 0 {
            let hit = hit & bits(p.settle(t, v, pad).simd_lt(t_max));
            blocked |= if tris.cut.is_none() {
                hit
            } else {
                kept_lanes(hit, b, |l, b| !tris.passes(id, b, p.origin(l), p.dir(l)))
            };
        }
        while fallback != 0 {
            let l = fallback.trailing_zeros() as usize;
            fallback &= fallback - 1;
            let (o, d) = (p.origin(l), p.dir(l));
            if intersect_settled(o, d, p.inv(l), t_arr[l], v, pad).is_some_and(|h| !tris.passes(id, h.b, o, d)) {
                blocked |= 1 << l;
            }
        }
    }
    blocked
}

/// Any-hit tests of 8 rays.
fn occluded8(
    bvh: &Bvh,
    tris: TriangleColumns<'_>,
    rays: &[RayQuery],
    thin: u32,
    out: &mut [bool],
    stacks: &mut AnyStacks,
) {
    let (stack, single) = (&mut stacks.0, &mut stacks.1);
    let nodes = bvh.nodes();
    let p = Packet::load(rays);
    let t_max = p.t_max;
    let t_arr = t_max.to_array();
    let mut blocked = 0u32;
    if !nodes.is_empty() && p.valid != 0 {
        let root = bits(p.entry(&nodes[0], t_max).simd_le(t_max)) & p.valid;
        stack.push((0, root));
    }
    while let Some((n, m)) = stack.pop() {
        let mut mask = m & !blocked;
        if mask == 0 {
            continue;
        }
        let node = &nodes[n as usize];
        if mask.count_ones() <= thin {
            while mask != 0 {
                let l = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                if occluded_from(bvh, tris, n, p.origin(l), p.dir(l), p.inv(l), t_arr[l], single) {
                    blocked |= 1 << l;
                }
            }
            continue;
        }
        if node.prim_count > 0 {
            blocked |= any_leaf(&p, tris, leaf_ids(node), mask & !blocked, bvh.pad(), t_max, &t_arr);
            if blocked & p.valid == p.valid {
                stack.clear();
                break;
            }
            continue;
        }
        // Nearer child first, as most lanes see it: an occluder near the origin ends lanes early.
        let mut children = ordered_children(&p, nodes, node, t_max, mask);
        // Leaf children are tested at once, before any inner child is entered: a leaf is cheap
        // and may end lanes (what makes obvhs's single-ray any-hit fast).
        for (child, _, lanes) in &mut children {
            let c = &nodes[*child as usize];
            if *lanes != 0 && c.prim_count > 0 {
                blocked |= any_leaf(&p, tris, leaf_ids(c), *lanes & !blocked, bvh.pad(), t_max, &t_arr);
                *lanes = 0;
            }
        }
        if blocked & p.valid == p.valid {
            stack.clear();
            break;
        }
        let [first, second] = children;
        for (child, _, lanes) in [second, first] {
            if lanes != 0 {
                stack.push((child, lanes));
            }
        }
    }
    for (l, o) in out.iter_mut().enumerate() {
        *o = blocked >> l & 1 == 1;
    }
}

/// Packet and single-ray stacks of the closest-hit traversal, made once per slice of rays
/// (initialising them per packet cost up to 20 % of camera-ray time).
type ClosestStacks = (Stack<(u32, Entry)>, Stack<(u32, f32)>);
/// The same for any-hit traversal.
type AnyStacks = (Stack<(u32, u32)>, Stack<u32>);

/// A stack entry's per-lane entry distances.
#[derive(Clone, Copy)]
struct Entry(f32x8);
impl Default for Entry {
    fn default() -> Self {
        Entry(f32x8::ZERO)
    }
}

/// Closest hits of `rays` into `out`, 8 at a time. Same signature and results as
/// [`super::traverse::closest_rays`].
pub fn closest_packets(bvh: &Bvh, tris: TriangleColumns<'_>, rays: &[RayQuery], out: &mut [Option<Hit>]) {
    closest_packets_thin(bvh, tris, rays, out, THIN_LANES);
}

/// [`closest_packets`] handing lanes to single-ray traversal at `thin` active lanes or fewer
/// (0: never; 8: always, i.e. single-ray traversal with a packet root test).
pub fn closest_packets_thin(
    bvh: &Bvh,
    tris: TriangleColumns<'_>,
    rays: &[RayQuery],
    out: &mut [Option<Hit>],
    thin: u32,
) {
    let mut stacks: ClosestStacks = (Stack::new(), Stack::new());
    for (r, o) in rays.chunks(LANES).zip(out.chunks_mut(LANES)) {
        closest8(bvh, tris, r, thin, o, &mut stacks);
    }
}

/// Any-hit tests of `rays` into `out`, 8 at a time. Same signature and results as
/// [`super::traverse::occluded_rays`].
pub fn occluded_packets(bvh: &Bvh, tris: TriangleColumns<'_>, rays: &[RayQuery], out: &mut [bool]) {
    occluded_packets_thin(bvh, tris, rays, out, THIN_LANES);
}

/// [`occluded_packets`] with its own hand-over threshold (see [`closest_packets_thin`]).
pub fn occluded_packets_thin(bvh: &Bvh, tris: TriangleColumns<'_>, rays: &[RayQuery], out: &mut [bool], thin: u32) {
    let mut stacks: AnyStacks = (Stack::new(), Stack::new());
    for (r, o) in rays.chunks(LANES).zip(out.chunks_mut(LANES)) {
        occluded8(bvh, tris, r, thin, o, &mut stacks);
    }
}

#[cfg(test)]
mod tests {
    use super::super::slab::{box_entry, inverse_direction};
    use super::*;

    /// `load` computes 8-wide what the scalar traversal computes per ray, bit for bit: which
    /// rays are valid ([`RayQuery::is_valid`]: NaN and infinite origins or directions, zero
    /// directions of either sign, t_max of 0, below 0 or NaN), and for valid ones the origin,
    /// direction, inverse direction (subnormal and zero components included) and the watertight
    /// test's shear; lanes past a short slice are not valid.
    #[test]
    fn load_matches_the_scalar_ray() {
        use super::super::triangle::{dominant_axis, permute};
        let (nan, inf, tiny) = (f32::NAN, f32::INFINITY, 1e-40f32);
        let rays = [
            RayQuery::new(Vec3::new(1.0, -2.0, 3.0), Vec3::new(0.3, -0.5, 0.8), 10.0),
            RayQuery::new(Vec3::new(nan, 0.0, 0.0), Vec3::X, 1.0),
            RayQuery::new(Vec3::ZERO, Vec3::new(0.0, inf, 0.0), 1.0),
            RayQuery::new(Vec3::ZERO, Vec3::new(-0.0, 0.0, -0.0), 1.0),
            RayQuery::new(Vec3::ONE, Vec3::new(tiny, -0.0, 0.0), f32::INFINITY),
            RayQuery::new(Vec3::ONE, Vec3::new(0.0, -1.0, 1.0), 0.0),
            RayQuery::new(Vec3::ONE, Vec3::new(-2.0, 1.0, 0.5), nan),
            RayQuery::new(Vec3::new(-1e30, 5.0, 0.0), Vec3::new(-0.2, 0.1, -0.3), -1.0),
            RayQuery::new(Vec3::new(0.5, 0.25, -8.0), Vec3::new(0.0, 0.0, -1.0), 2.0),
            RayQuery::new(Vec3::new(7.0, 0.0, 1.0), Vec3::new(0.1, 0.9, -0.1), 2.0),
            // Ties in |d| between axes (the axis choice breaks them toward z, then y).
            RayQuery::new(Vec3::ZERO, Vec3::new(1.0, -1.0, 0.5), 3.0),
            RayQuery::new(Vec3::ZERO, Vec3::new(-1.0, 1.0, 1.0), 3.0),
            RayQuery::new(Vec3::ZERO, Vec3::new(0.5, 2.0, -2.0), 3.0),
        ];
        for slice in [&rays[..8], &rays[2..10], &rays[5..], &rays[4..7]] {
            let p = Packet::load(slice);
            let (sx, sy, sz) = (p.sx.to_array(), p.sy.to_array(), p.sz.to_array());
            for l in 0..LANES {
                // t_max as given in every lane, valid or not; 0 past the slice.
                let t_max = slice.get(l).map_or(0.0, |r| r.t_max);
                assert_eq!(p.t_max.to_array()[l].to_bits(), t_max.to_bits(), "lane {l}");
                let r = slice.get(l).filter(|r| r.is_valid());
                assert_eq!(p.valid >> l & 1 == 1, r.is_some(), "lane {l}");
                let Some(r) = r else { continue };
                let (o, d) = (r.origin, r.direction);
                let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                assert_eq!(bits(p.origin(l)), bits(o), "lane {l}");
                assert_eq!(bits(p.dir(l)), bits(d), "lane {l}");
                assert_eq!(bits(p.inv(l)), bits(inverse_direction(d)), "lane {l}");
                let q = permute(d, dominant_axis(d));
                let want = [-q.x / q.z, -q.y / q.z, 1.0 / q.z].map(f32::to_bits);
                assert_eq!([sx[l], sy[l], sz[l]].map(f32::to_bits), want, "lane {l}");
            }
        }
    }

    #[test]
    fn packet_entry_matches_scalar_box_entry() {
        let node = Bvh2Node {
            aabb: obvhs::aabb::Aabb::new(glam::Vec3A::new(-1.0, 0.0, -1.0), glam::Vec3A::new(1.0, 0.0, 1.0)),
            ..Default::default()
        };
        let rays: Vec<RayQuery> = (0..8)
            .map(|i| {
                let x = i as f32 * 0.4 - 1.6;
                RayQuery::new(Vec3::new(x, 0.0, -3.0), Vec3::new(0.0, 0.0, 1.0), f32::INFINITY)
            })
            .collect();
        let p = Packet::load(&rays);
        let got = p.entry(&node, f32x8::splat(f32::INFINITY)).to_array();
        let got = got.map(|t| if t.is_nan() { f32::INFINITY } else { t });
        for (l, r) in rays.iter().enumerate() {
            let want = box_entry(
                node.aabb.min,
                node.aabb.max,
                r.origin.into(),
                inverse_direction(r.direction).into(),
                f32::INFINITY,
            );
            assert_eq!(got[l].to_bits(), want.to_bits(), "lane {l}");
        }
    }

    /// The packet form of `settle` returns the scalar function's t bit for bit, lane by lane:
    /// rays entering the triangle's box before, at and after t, and rays missing it.
    #[test]
    fn packet_settle_matches_scalar_settle() {
        let tris = [
            [Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0)],
            [Vec3::new(0.0, 0.0, -10.0), Vec3::new(2e-7, 0.0, 10.0), Vec3::new(0.0, 2e-7, 10.0)],
        ];
        let rays: Vec<RayQuery> = (0..8)
            .map(|i| {
                let x = i as f32 * 0.4 - 1.6;
                RayQuery::new(Vec3::new(x, 0.5, -3.0), Vec3::new(0.1 * x, -0.2, 1.0), f32::INFINITY)
            })
            .collect();
        let p = Packet::load(&rays);
        for v in tris {
            for pad in [0.0, 1e-5, 0.5] {
                for t in [1e-3f32, 1.0, 3.0, 50.0] {
                    let got = p.settle(f32x8::splat(t), v, pad).to_array();
                    for (l, r) in rays.iter().enumerate() {
                        let inv = inverse_direction(r.direction);
                        let want = super::super::slab::settle(t, r.origin.into(), inv.into(), v, pad);
                        assert_eq!(got[l].to_bits(), want.to_bits(), "lane {l}, pad {pad}, t {t}");
                    }
                }
            }
        }
    }
}
