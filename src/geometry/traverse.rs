//! Single-ray traversal of the obvhs BVH2: the scalar twin of the packet traversal in
//! [`super::packet`], and what the packet hands its rays to when its active lanes thin out.
//!
//! Both traversals make the same decisions where it matters: the box test is conservative (far
//! distances grown by 1 + 2γ₃, pbrt-v4 §6.1.2; zero direction components get a finite ±f32::MAX
//! inverse so no 0·∞ NaN can arise), every triangle is tested with the same watertight routine
//! and its t settled into the triangle's box ([`super::slab::settle`]), and a tie in t between
//! two triangles goes to the lower triangle index. The closest hit is therefore the same
//! whatever tree is walked and whatever order the leaves are visited in.

use super::bvh::{Bvh, Hit, TriangleColumns};
use super::slab::{box_entry, intersect_settled, inverse_direction};
use glam::{Vec3, Vec3A};

/// No triangle.
pub const NO_TRI: u32 = u32::MAX;

/// One ray query: origin, direction, and the open interval (0, `t_max`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayQuery {
    /// Origin.
    pub origin: Vec3,
    /// Direction (need not be unit length).
    pub direction: Vec3,
    /// Hits must have t < t_max.
    pub t_max: f32,
}

impl RayQuery {
    /// A query over (0, t_max).
    #[must_use]
    pub fn new(origin: Vec3, direction: Vec3, t_max: f32) -> Self {
        RayQuery { origin, direction, t_max }
    }
    /// True if the ray can be traced at all: finite origin, finite non-zero direction, t_max > 0.
    #[inline]
    #[must_use]
    pub fn is_valid(&self) -> bool {
        // Evaluated whole, without short-circuits: a branch per term cost the single ray more
        // than the terms (BENCHMARKS.md, issue 18, seventeenth part).
        let (o, d) = (self.origin, self.direction);
        (o.is_finite_mask() & d.is_finite_mask()).all() & d.cmpne(Vec3::ZERO).any() & (self.t_max > 0.0)
    }
}

/// Best hit so far of one ray: t and triangle ([`NO_TRI`] while none).
#[derive(Clone, Copy, Debug)]
pub struct Best {
    /// Distance of the best hit, or the query's t_max.
    pub t: f32,
    /// Its triangle.
    pub tri: u32,
    /// Its barycentrics.
    pub b: [f32; 3],
}

impl Best {
    /// Nothing hit yet below `t_max`.
    #[must_use]
    pub fn new(t_max: f32) -> Self {
        Best { t: t_max, tri: NO_TRI, b: [0.0; 3] }
    }
    /// The hit, if any.
    #[must_use]
    pub fn hit(&self) -> Option<Hit> {
        (self.tri != NO_TRI).then_some(Hit { tri: self.tri, t: self.t, b: self.b })
    }
    /// The largest t a triangle hit may have to matter (the triangle test's exclusive bound):
    /// strictly below t_max while nothing is hit; afterwards up to and including the best t, so
    /// that a tie may go to a lower index.
    #[inline]
    #[must_use]
    pub fn limit(&self) -> f32 {
        if self.tri == NO_TRI {
            self.t
        } else {
            self.t.next_up()
        }
    }
    /// Keeps a hit found below [`Best::limit`] if it is closer, or equally close with a lower
    /// index: the rule that makes every traversal order give the same hit.
    #[inline]
    pub fn offer(&mut self, t: f32, id: u32, b: [f32; 3]) {
        if t < self.t || id < self.tri {
            *self = Best { t, tri: id, b };
        }
    }
    /// Tests triangle `id` ([`intersect_settled`], boxes padded by `pad`) and keeps it by
    /// [`Best::offer`]'s rule unless the ray passes its cut-out.
    #[inline]
    pub fn test(&mut self, tris: TriangleColumns<'_>, o: Vec3, d: Vec3, inv: Vec3, pad: f32, id: u32) {
        let i = id as usize;
        let p = [tris.p0[i], tris.p1[i], tris.p2[i]];
        if let Some(h) = intersect_settled(o, d, inv, self.limit(), p, pad) {
            if !tris.passes(id, h.b, o, d) {
                self.offer(h.t, id, h.b);
            }
        }
    }
}

/// A traversal stack: inline up to 96 entries, spilling to the heap beyond (deep trees only).
pub struct Stack<T: Copy + Default> {
    inline: [T; 96],
    len: usize,
    spill: Vec<T>,
}

impl<T: Copy + Default> Stack<T> {
    /// An empty stack.
    #[must_use]
    pub fn new() -> Self {
        Stack { inline: [T::default(); 96], len: 0, spill: Vec::new() }
    }
    /// Pushes `v`.
    #[inline]
    pub fn push(&mut self, v: T) {
        if self.len < self.inline.len() {
            self.inline[self.len] = v;
            self.len += 1;
        } else {
            self.spill.push(v);
        }
    }
    /// Empties the stack.
    #[inline]
    pub fn clear(&mut self) {
        self.len = 0;
        self.spill.clear();
    }
    /// Pops the top.
    #[inline]
    pub fn pop(&mut self) -> Option<T> {
        if let Some(v) = self.spill.pop() {
            return Some(v);
        }
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        Some(self.inline[self.len])
    }
}

impl<T: Copy + Default> Default for Stack<T> {
    fn default() -> Self {
        Self::new()
    }
}

/// Closest-hit traversal of one ray from node `start` (entry distance `start_t`), updating
/// `best`. Used for whole rays and for lanes a packet hands over.
#[allow(clippy::too_many_arguments)]
pub fn closest_from(
    bvh: &Bvh,
    tris: TriangleColumns<'_>,
    start: u32,
    start_t: f32,
    o: Vec3,
    d: Vec3,
    inv: Vec3,
    best: &mut Best,
    stack: &mut Stack<(u32, f32)>,
) {
    let (nodes, pad) = (bvh.nodes(), bvh.pad());
    let (oa, inva) = (Vec3A::from(o), Vec3A::from(inv));
    stack.push((start, start_t));
    while let Some((n, tn)) = stack.pop() {
        if tn > best.t {
            continue;
        }
        // Descend without a push while one child remains (one push per fork, as obvhs does).
        let mut cur = n;
        loop {
            let node = &nodes[cur as usize];
            if node.prim_count > 0 {
                for id in node.first_index..node.first_index + node.prim_count {
                    best.test(tris, o, d, inv, pad, id);
                }
                break;
            }
            let (l, r) = (node.first_index, node.first_index + 1);
            let bl = &nodes[l as usize].aabb;
            let br = &nodes[r as usize].aabb;
            let tl = box_entry(bl.min, bl.max, oa, inva, best.t);
            let tr = box_entry(br.min, br.max, oa, inva, best.t);
            let ((near, tnear), (far, tfar)) = if tl <= tr { ((l, tl), (r, tr)) } else { ((r, tr), (l, tl)) };
            match (tnear.is_finite(), tfar.is_finite()) {
                (true, true) => {
                    stack.push((far, tfar));
                    cur = near;
                }
                (true, false) => cur = near,
                (false, true) => cur = far,
                (false, false) => break,
            }
        }
    }
}

/// Whether triangle `id` blocks the ray within (0, t_max): hit, and not passed by its cut-out.
#[inline]
fn blocks(tris: TriangleColumns<'_>, id: u32, o: Vec3, d: Vec3, inv: Vec3, t_max: f32, pad: f32) -> bool {
    let i = id as usize;
    intersect_settled(o, d, inv, t_max, [tris.p0[i], tris.p1[i], tris.p2[i]], pad)
        .is_some_and(|h| !tris.passes(id, h.b, o, d))
}

/// Any-hit traversal of one ray from node `start`: true at the first triangle hit in (0, t_max).
/// Leaf children are tested as soon as their parent is reached (as obvhs's loop does).
#[allow(clippy::too_many_arguments)]
pub fn occluded_from(
    bvh: &Bvh,
    tris: TriangleColumns<'_>,
    start: u32,
    o: Vec3,
    d: Vec3,
    inv: Vec3,
    t_max: f32,
    stack: &mut Stack<u32>,
) -> bool {
    let (nodes, pad) = (bvh.nodes(), bvh.pad());
    let (oa, inva) = (Vec3A::from(o), Vec3A::from(inv));
    stack.push(start);
    while let Some(n) = stack.pop() {
        let mut cur = n;
        loop {
            let node = &nodes[cur as usize];
            if node.prim_count > 0 {
                for id in node.first_index..node.first_index + node.prim_count {
                    if blocks(tris, id, o, d, inv, t_max, pad) {
                        stack.clear();
                        return true;
                    }
                }
                break;
            }
            // Nearer child first: occluders near the origin end the search early.
            let (l, r) = (node.first_index, node.first_index + 1);
            let bl = &nodes[l as usize].aabb;
            let br = &nodes[r as usize].aabb;
            let tl = box_entry(bl.min, bl.max, oa, inva, t_max);
            let tr = box_entry(br.min, br.max, oa, inva, t_max);
            let ((near, tnear), (far, tfar)) = if tl <= tr { ((l, tl), (r, tr)) } else { ((r, tr), (l, tl)) };
            // Leaf children are tested at once, nearer first, before any inner child is entered:
            // a leaf is cheap and may end the search.
            let mut go = [(near, tnear.is_finite()), (far, tfar.is_finite())];
            for g in &mut go {
                let child = &nodes[g.0 as usize];
                if g.1 && child.prim_count > 0 {
                    for id in child.first_index..child.first_index + child.prim_count {
                        if blocks(tris, id, o, d, inv, t_max, pad) {
                            stack.clear();
                            return true;
                        }
                    }
                    g.1 = false;
                }
            }
            match (go[0].1, go[1].1) {
                (true, true) => {
                    stack.push(far);
                    cur = near;
                }
                (true, false) => cur = near,
                (false, true) => cur = far,
                (false, false) => break,
            }
        }
    }
    false
}

/// Closest hit of one ray, with a caller's stack.
#[must_use]
pub fn closest_with(
    bvh: &Bvh,
    tris: TriangleColumns<'_>,
    ray: &RayQuery,
    stack: &mut Stack<(u32, f32)>,
) -> Option<Hit> {
    if bvh.nodes().is_empty() || !ray.is_valid() {
        return None;
    }
    let inv = inverse_direction(ray.direction);
    let root = &bvh.nodes()[0].aabb;
    let t0 = box_entry(root.min, root.max, ray.origin.into(), inv.into(), ray.t_max);
    if !t0.is_finite() {
        return None;
    }
    let mut best = Best::new(ray.t_max);
    closest_from(bvh, tris, 0, t0, ray.origin, ray.direction, inv, &mut best, stack);
    best.hit()
}

/// True if anything is hit in (0, t_max), with a caller's stack.
#[must_use]
pub fn occluded_with(bvh: &Bvh, tris: TriangleColumns<'_>, ray: &RayQuery, stack: &mut Stack<u32>) -> bool {
    if bvh.nodes().is_empty() || !ray.is_valid() {
        return false;
    }
    let inv = inverse_direction(ray.direction);
    let root = &bvh.nodes()[0].aabb;
    if !box_entry(root.min, root.max, ray.origin.into(), inv.into(), ray.t_max).is_finite() {
        return false;
    }
    occluded_from(bvh, tris, 0, ray.origin, ray.direction, inv, ray.t_max, stack)
}

/// The closest-hit and any-hit stacks of single-ray traversal.
type SingleStacks = (Stack<(u32, f32)>, Stack<u32>);

thread_local! {
    /// Per-thread stacks for one-off queries: initialising a fresh 96-entry stack per ray cost
    /// more than some traversals (BENCHMARKS.md).
    static STACKS: std::cell::RefCell<SingleStacks> =
        std::cell::RefCell::new((Stack::new(), Stack::new()));
}

/// Closest hit of one ray.
#[must_use]
pub fn closest(bvh: &Bvh, tris: TriangleColumns<'_>, ray: &RayQuery) -> Option<Hit> {
    STACKS.with(|s| match s.try_borrow_mut() {
        Ok(mut s) => closest_with(bvh, tris, ray, &mut s.0),
        Err(_) => closest_with(bvh, tris, ray, &mut Stack::new()),
    })
}

/// True if anything is hit in (0, t_max).
#[must_use]
pub fn occluded(bvh: &Bvh, tris: TriangleColumns<'_>, ray: &RayQuery) -> bool {
    STACKS.with(|s| match s.try_borrow_mut() {
        Ok(mut s) => occluded_with(bvh, tris, ray, &mut s.1),
        Err(_) => occluded_with(bvh, tris, ray, &mut Stack::new()),
    })
}

/// Scalar twin of [`super::packet::closest_packets`]: closest hits of `rays` into `out`, one ray
/// at a time.
pub fn closest_rays(bvh: &Bvh, tris: TriangleColumns<'_>, rays: &[RayQuery], out: &mut [Option<Hit>]) {
    let mut stack = Stack::new();
    for (r, o) in rays.iter().zip(out.iter_mut()) {
        *o = closest_with(bvh, tris, r, &mut stack);
    }
}

/// Scalar twin of [`super::packet::occluded_packets`].
pub fn occluded_rays(bvh: &Bvh, tris: TriangleColumns<'_>, rays: &[RayQuery], out: &mut [bool]) {
    let mut stack = Stack::new();
    for (r, o) in rays.iter().zip(out.iter_mut()) {
        *o = occluded_with(bvh, tris, r, &mut stack);
    }
}
/// The single-ray traversals as methods of the tree (kept here, beside the traversal, so that
/// `bvh.rs` needs nothing from this file).
impl Bvh {
    /// Closest hit with 0 < t < `t_max` among triangles given by the BVH-ordered columns
    /// (single-ray traversal; ties in t go to the lower triangle index).
    #[must_use]
    pub fn closest(&self, tris: TriangleColumns<'_>, o: Vec3, d: Vec3, t_max: f32) -> Option<Hit> {
        closest(self, tris, &RayQuery::new(o, d, t_max))
    }

    /// True if any triangle is hit with 0 < t < `t_max` (shadow rays).
    #[must_use]
    pub fn occluded(&self, tris: TriangleColumns<'_>, o: Vec3, d: Vec3, t_max: f32) -> bool {
        occluded(self, tris, &RayQuery::new(o, d, t_max))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ray is traced only with a finite origin, a finite direction with some non-zero
    /// component (−0 counts as zero) and t_max > 0 (NaN is not).
    #[test]
    fn is_valid_needs_finite_rays_a_direction_and_a_positive_range() {
        let ray = |o: Vec3, d: Vec3, t: f32| RayQuery::new(o, d, t).is_valid();
        let (o, d) = (Vec3::new(1.0, -2.0, 3.0), Vec3::new(0.0, -0.0, 1e-45));
        assert!(ray(o, d, 1.0) && ray(o, d, f32::INFINITY));
        assert!(!ray(o, Vec3::new(0.0, -0.0, 0.0), 1.0));
        assert!(!ray(o, Vec3::ZERO, 1.0));
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            for axis in 0..3 {
                let mut v = Vec3::ONE;
                v[axis] = bad;
                assert!(!ray(v, d, 1.0), "origin {v}");
                assert!(!ray(o, v, 1.0), "direction {v}");
            }
        }
        for t in [0.0, -0.0, -1.0, f32::NAN] {
            assert!(!ray(o, d, t), "t_max {t}");
        }
    }
}
