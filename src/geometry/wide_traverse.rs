//! Single-ray traversal of the 8-wide BVH ([`super::wide`]): at each node one ray meets all
//! eight child boxes in one `f32x8` test; closest-hit traversal visits the children it enters
//! nearest first.
//! Reads rays and the [`Bvh8`]; writes hits or occlusion flags.
//!
//! The kernel is generic over the child test: `SIMD = true` runs [`Node8::entries`], `false` its
//! scalar twin [`Node8::entries_scalar`]; everything else is shared. Both make the decisions of
//! [`super::traverse`] (conservative box test, the same watertight triangle test, every hit's t
//! settled into its triangle's box by [`super::slab::settle`]'s operations, ties in t to the
//! lower triangle index), so the closest hit is the same triangle, t and barycentrics as every
//! other traversal's, whatever tree is walked and whatever order the leaves are met in;
//! tests/packet.rs checks it.
//!
//! Any-hit traversal tests a node's leaf children as soon as the node is reached, before
//! entering any inner child (as the BVH2 traversals do: a leaf is cheap and often ends the ray).
//! It takes the entered children in slot order, unsorted: any occluder ends the ray, and the
//! sort cost more than the order saved (any-hit bench rows 0.97–1.15×, all but one faster:
//! BENCHMARKS.md, issue 18, tenth part), and without reading entry distances at all: it walks
//! the hit mask's bits, leaf children (a per-node bit mask) first. Closest-hit traversal goes
//! straight to the only child it enters, without keys or a sort, and builds sorted keys only
//! when two or more are entered (any hit 6–34 % faster on the bench's rows, closest hit up to
//! 18 %: BENCHMARKS.md, issue 18, twelfth part); two are ordered by the min and max of their
//! two keys, without the key array and its loop (issue 18, seventeenth part).

use super::bvh::Hit;
use super::cut_out::{kept_lanes, passes, CutOuts};
use super::slab::{intersect_settled, inverse_direction};
use super::traverse::{Best, RayQuery, Stack};
use super::triangle8::{intersect_block, ShearedRay, TriBlock};
use super::wide::{Bvh8, Node8, WideRay, WIDTH};
use glam::Vec3;
use wide::f32x8;

/// A stack entry: child (node index, or first block of a leaf), leaf triangle count (0 for a
/// node) and entry distance (closest hit; any-hit walks leave it 0).
pub(super) type Entry = (u32, u32, f32);

/// Work one traversal did: nodes whose child boxes were tested, triangle blocks and triangles
/// (live lanes of those blocks) tested.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Visits {
    /// Nodes visited.
    pub nodes: u64,
    /// Triangle blocks tested.
    pub blocks: u64,
    /// Triangles tested.
    pub triangles: u64,
    /// Triangle tests the 8-wide test handed to the scalar one (edge functions of exactly zero,
    /// t not provably positive in f32, or a limit lowered within the block).
    pub scalar: u64,
}

impl Visits {
    #[inline(always)]
    fn leaf(&mut self, blocks: &[TriBlock]) {
        self.blocks += blocks.len() as u64;
        self.triangles += blocks.iter().map(|b| u64::from(b.live.count_ones())).sum::<u64>();
    }
}

/// The blocks of a leaf child.
#[inline(always)]
fn leaf(bvh: &Bvh8, first: u32, count: u32) -> &[TriBlock] {
    let first = first as usize;
    &bvh.blocks()[first..first + count.div_ceil(8) as usize]
}

/// Tests the leaf's triangles, keeping the closest hit by [`Best::offer`]'s rule, each hit's t
/// [`super::slab::settle`]d into its triangle's box. Each block is tested against the limit as
/// it stood before it; a lane hit after an earlier lane of the same block has lowered the limit
/// is decided again by the scalar test, so every triangle is decided exactly as the scalar
/// traversal, testing them one by one, would decide it (a miss under a limit stays a miss under
/// a lower one).
#[inline(always)]
fn closest_leaf(blocks: &[TriBlock], ray: &Prepared, pad: f32, cut: CutOuts<'_>, best: &mut Best) -> u64 {
    let r = &ray.sheared;
    let mut scalar = 0;
    for b in blocks {
        let limit = best.limit();
        let (hit, fallback, t, bary) = intersect_block(r, b, limit);
        if hit | fallback == 0 {
            continue;
        }
        // Only lanes that hit have a t to settle (fallback lanes are decided by the scalar test).
        let t = if hit == 0 { t } else { ray.wide.settle(t, b, pad) };
        let hit = hit & t.simd_lt(f32x8::splat(limit)).to_bitmask();
        let mut todo = hit | fallback;
        // Written out, not `bary.map(..)`: array maps on the single ray's path were left out of
        // line in some builds, depending on how the compiler split the crate into codegen units
        // (one that was in `WideRay::new`, a call per ray, made every single-ray bench row 7–26 %
        // slower: BENCHMARKS.md, issue 18, eighth part).
        let (t, bary) = (t.to_array(), [bary[0].to_array(), bary[1].to_array(), bary[2].to_array()]);
        while todo != 0 {
            let l = todo.trailing_zeros() as usize;
            todo &= todo - 1;
            let id = b.ids[l];
            if hit >> l & 1 == 1 && best.limit().to_bits() == limit.to_bits() {
                let b = [bary[0][l], bary[1][l], bary[2][l]];
                if !passes(cut, id, b, r.origin, r.dir) {
                    best.offer(t[l], id, b);
                }
            } else {
                scalar += 1;
                if let Some(h) = intersect_settled(r.origin, r.dir, ray.inv, best.limit(), b.triangle(l), pad) {
                    if !passes(cut, id, h.b, r.origin, r.dir) {
                        best.offer(h.t, id, h.b);
                    }
                }
            }
        }
    }
    scalar
}

/// Whether any triangle of the leaf is hit within (0, t_max), its t [`super::slab::settle`]d.
#[inline(always)]
fn any_leaf(blocks: &[TriBlock], ray: &Prepared, pad: f32, t_max: f32, cut: CutOuts<'_>, scalar: &mut u64) -> bool {
    let r = &ray.sheared;
    blocks.iter().any(|b| {
        let (hit, mut fallback, t, bary) = intersect_block(r, b, t_max);
        if hit != 0 {
            let hit = hit & ray.wide.settle(t, b, pad).simd_lt(f32x8::splat(t_max)).to_bitmask();
            let kept = |l: usize, bl| !passes(cut, b.ids[l], bl, r.origin, r.dir);
            if hit != 0 && (cut.is_none() || kept_lanes(hit, bary, kept) != 0) {
                return true;
            }
        }
        *scalar += u64::from(fallback.count_ones());
        while fallback != 0 {
            let l = fallback.trailing_zeros() as usize;
            fallback &= fallback - 1;
            if intersect_settled(r.origin, r.dir, ray.inv, t_max, b.triangle(l), pad)
                .is_some_and(|h| !passes(cut, b.ids[l], h.b, r.origin, r.dir))
            {
                return true;
            }
        }
        false
    })
}

/// The bit mask of the children of `node` that the ray enters within `t_max`, and their entry
/// distances by slot (lanes outside the mask hold garbage): the 8-wide test, or its scalar twin.
#[inline(always)]
fn enter<const SIMD: bool>(node: &Node8, r: &WideRay, o: Vec3, inv: Vec3, t_max: f32) -> (u32, f32x8) {
    if SIMD {
        node.entries(r, t_max)
    } else {
        let (m, t) = node.entries_scalar(o, inv, t_max);
        (m, f32x8::from(t))
    }
}

/// The children of `mask` (at least two) as (t bits, slot) keys sorted nearest first, and their
/// number. Entry distances are ≥ 0 and never NaN, so their bit patterns order as the values do.
#[inline(always)]
fn sorted(mut mask: u32, t: f32x8) -> ([u64; WIDTH], usize) {
    let t = t.to_array();
    let mut keys = [0u64; WIDTH];
    let mut n = 0;
    while mask != 0 {
        let i = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        keys[n] = key(t[i], i);
        n += 1;
    }
    sort_keys(&mut keys, n);
    (keys, n)
}

/// Sorts the first `n` of `keys` (distinct: each holds its slot) ascending. Two or three keys
/// (the usual counts) by a network of min and max, without a branch on their order (the
/// insertion sort's compares go either way with the ray: BENCHMARKS.md, issue 18, tenth part);
/// more by insertion sort (at most eight keys).
#[inline(always)]
pub(super) fn sort_keys(keys: &mut [u64; WIDTH], n: usize) {
    if n == 2 {
        let (a, b) = (keys[0], keys[1]);
        (keys[0], keys[1]) = (a.min(b), a.max(b));
        return;
    }
    if n == 3 {
        let (a, b, c) = (keys[0], keys[1], keys[2]);
        let (a, b) = (a.min(b), a.max(b));
        let (b, c) = (b.min(c), b.max(c));
        let (a, b) = (a.min(b), a.max(b));
        (keys[0], keys[1], keys[2]) = (a, b, c);
        return;
    }
    for j in 1..n {
        let k = keys[j];
        let mut m = j;
        while m > 0 && keys[m - 1] > k {
            keys[m] = keys[m - 1];
            m -= 1;
        }
        keys[m] = k;
    }
}

/// One ray as both tests want it: origin, inverse direction, splatted for the child test and
/// sheared for the triangle test.
pub(super) struct Prepared {
    o: Vec3,
    inv: Vec3,
    wide: WideRay,
    sheared: ShearedRay,
}

impl Prepared {
    /// `ray` prepared (a valid ray: [`RayQuery::is_valid`]).
    #[inline(always)]
    pub(super) fn new(ray: &RayQuery) -> Self {
        let (o, d) = (ray.origin, ray.direction);
        let inv = inverse_direction(d);
        Prepared { o, inv, wide: WideRay::new(o, inv), sheared: ShearedRay::new(o, d) }
    }
}

/// The ray prepared, or `None` when there is nothing to trace (no nodes, or an invalid ray).
#[inline(always)]
fn prepare(bvh: &Bvh8, ray: &RayQuery) -> Option<Prepared> {
    if bvh.nodes().is_empty() || !ray.is_valid() {
        return None;
    }
    Some(Prepared::new(ray))
}

/// The sort key of a child entered at `t` (≥ 0, never NaN, so the bits order as the values
/// do) in `slot`: t's bits above the slot, so that equal distances go to the lower slot.
#[inline(always)]
pub(super) fn key(t: f32, slot: usize) -> u64 {
    u64::from(t.to_bits()) << 32 | slot as u64
}

/// The slot and entry distance of a [`key`].
#[inline(always)]
pub(super) fn unkey(key: u64) -> (usize, f32) {
    ((key & 0xff) as usize, f32::from_bits((key >> 32) as u32))
}

/// Closest hit of one ray, with a caller's stack.
#[must_use]
pub fn closest_with<const SIMD: bool>(
    bvh: &Bvh8,
    cut: CutOuts<'_>,
    ray: &RayQuery,
    stack: &mut Stack<Entry>,
) -> Option<Hit> {
    closest_counted::<SIMD, false>(bvh, cut, ray, stack, &mut Visits::default())
}

/// [`closest_with`], adding its work to `visits` when `COUNT`.
#[must_use]
pub fn closest_counted<const SIMD: bool, const COUNT: bool>(
    bvh: &Bvh8,
    cut: CutOuts<'_>,
    ray: &RayQuery,
    stack: &mut Stack<Entry>,
    visits: &mut Visits,
) -> Option<Hit> {
    let prepared = prepare(bvh, ray)?;
    let mut best = Best::new(ray.t_max);
    closest_walk::<SIMD, COUNT>(bvh, cut, &prepared, (0, 0, 0.0), &mut best, stack, visits);
    best.hit()
}

/// Walks the subtree of `start` (a node, or a leaf; entered at its distance) for the closest
/// hit of a prepared ray, improving `best`: the single ray's loop, also run by the 8-wide
/// packets for lanes they hand over.
#[inline(always)]
pub(super) fn closest_walk<const SIMD: bool, const COUNT: bool>(
    bvh: &Bvh8,
    cut: CutOuts<'_>,
    prepared: &Prepared,
    start: Entry,
    best: &mut Best,
    stack: &mut Stack<Entry>,
    visits: &mut Visits,
) {
    let Prepared { o, inv, wide: r, .. } = prepared;
    let (o, inv) = (*o, *inv);
    let nodes = bvh.nodes();
    stack.clear();
    if start.2 > best.t {
        return;
    }
    // The child visited now: node index or first block, and triangle count (0 for a node). The
    // nearest entered child is visited next without a trip through the stack, and needs neither
    // its entry distance (it is within the limit it was tested against, which has not moved) nor,
    // when it is the only one entered, a sort.
    let (mut c, mut count) = (start.0, start.1);
    loop {
        if count > 0 {
            let blocks = leaf(bvh, c, count);
            if COUNT {
                visits.leaf(blocks);
            }
            let scalar = closest_leaf(blocks, prepared, bvh.pad(), cut, best);
            if COUNT {
                visits.scalar += scalar;
            }
        } else {
            if COUNT {
                visits.nodes += 1;
            }
            let node = &nodes[c as usize];
            let (mask, t) = enter::<SIMD>(node, r, o, inv, best.t);
            if mask != 0 {
                let rest = mask & (mask - 1);
                let i = if rest == 0 {
                    mask.trailing_zeros() as usize
                } else if rest & (rest - 1) == 0 {
                    // Two children (the usual case): their two keys ordered by min and max,
                    // without a branch on their order, the array of keys or a loop.
                    let t = t.as_array();
                    let (i, j) = (mask.trailing_zeros() as usize, rest.trailing_zeros() as usize);
                    let (a, b) = (key(t[i], i), key(t[j], j));
                    let (far, tf) = unkey(a.max(b));
                    stack.push((node.child[far], u32::from(node.count[far]), tf));
                    unkey(a.min(b)).0
                } else {
                    let (keys, n) = sorted(mask, t);
                    for &key in keys[1..n].iter().rev() {
                        let (i, t) = unkey(key);
                        stack.push((node.child[i], u32::from(node.count[i]), t));
                    }
                    unkey(keys[0]).0
                };
                (c, count) = (node.child[i], u32::from(node.count[i]));
                continue;
            }
        }
        // Popped children entered beyond the closest hit found since are skipped.
        loop {
            let Some((pc, pcount, tc)) = stack.pop() else {
                return;
            };
            if tc <= best.t {
                (c, count) = (pc, pcount);
                break;
            }
        }
    }
}

/// True if anything is hit in (0, t_max), with a caller's stack.
#[must_use]
pub fn occluded_with<const SIMD: bool>(bvh: &Bvh8, cut: CutOuts<'_>, ray: &RayQuery, stack: &mut Stack<Entry>) -> bool {
    occluded_counted::<SIMD, false>(bvh, cut, ray, stack, &mut Visits::default())
}

/// [`occluded_with`], adding its work to `visits` when `COUNT`.
#[must_use]
pub fn occluded_counted<const SIMD: bool, const COUNT: bool>(
    bvh: &Bvh8,
    cut: CutOuts<'_>,
    ray: &RayQuery,
    stack: &mut Stack<Entry>,
    visits: &mut Visits,
) -> bool {
    let Some(prepared) = prepare(bvh, ray) else {
        return false;
    };
    any_walk::<SIMD, COUNT>(bvh, cut, &prepared, (0, 0, 0.0), ray.t_max, stack, visits)
}

/// Whether the subtree of `start` (a node or a leaf) holds a hit of a prepared ray within
/// (0, `t_max`): the single ray's any-hit loop, also run by the 8-wide packets for lanes they
/// hand over.
#[inline(always)]
pub(super) fn any_walk<const SIMD: bool, const COUNT: bool>(
    bvh: &Bvh8,
    cut: CutOuts<'_>,
    prepared: &Prepared,
    start: Entry,
    t_max: f32,
    stack: &mut Stack<Entry>,
    visits: &mut Visits,
) -> bool {
    let Prepared { o, inv, wide: r, .. } = prepared;
    let (o, inv) = (*o, *inv);
    let nodes = bvh.nodes();
    let leaf_hit = |first: u32, count: u32, visits: &mut Visits| {
        let blocks = leaf(bvh, first, count);
        if COUNT {
            visits.leaf(blocks);
        }
        any_leaf(blocks, prepared, bvh.pad(), t_max, cut, &mut visits.scalar)
    };
    stack.clear();
    // The nearest entered inner child is visited next without a trip through the stack.
    let mut next = Some(start);
    while let Some((c, count, _)) = next.take().or_else(|| stack.pop()) {
        if count > 0 {
            if leaf_hit(c, count, visits) {
                return true;
            }
            continue;
        }
        let node = &nodes[c as usize];
        if COUNT {
            visits.nodes += 1;
        }
        let (mask, _) = enter::<SIMD>(node, r, o, inv, t_max);
        // Leaf children first; then the inner children: the first in slot order next, the
        // others on the stack, earlier slots on top. Entry distances are not needed: any hit
        // ends the walk, and the limit never moves.
        let leaves = mask & u32::from(node.leaves);
        let mut m = leaves;
        while m != 0 {
            let i = m.trailing_zeros() as usize;
            m &= m - 1;
            if leaf_hit(node.child[i], u32::from(node.count[i]), visits) {
                return true;
            }
        }
        let mut inner = mask & !leaves;
        while inner != 0 {
            let i = (31 - inner.leading_zeros()) as usize;
            inner &= !(1 << i);
            if let Some(farther) = next.replace((node.child[i], 0, 0.0)) {
                stack.push(farther);
            }
        }
    }
    false
}

/// Closest hits of `rays` into `out`, one ray at a time through the 8-wide BVH (`SIMD`: the
/// 8-wide child test; otherwise its scalar twin).
pub fn closest_rays<const SIMD: bool>(bvh: &Bvh8, cut: CutOuts<'_>, rays: &[RayQuery], out: &mut [Option<Hit>]) {
    let mut stack = Stack::new();
    for (r, o) in rays.iter().zip(out.iter_mut()) {
        *o = closest_with::<SIMD>(bvh, cut, r, &mut stack);
    }
}

/// Any-hit tests of `rays` into `out` (see [`closest_rays`]).
pub fn occluded_rays<const SIMD: bool>(bvh: &Bvh8, cut: CutOuts<'_>, rays: &[RayQuery], out: &mut [bool]) {
    let mut stack = Stack::new();
    for (r, o) in rays.iter().zip(out.iter_mut()) {
        *o = occluded_with::<SIMD>(bvh, cut, r, &mut stack);
    }
}
