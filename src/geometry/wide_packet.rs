//! Packet traversal of the 8-wide BVH ([`super::wide`]): 8 rays (`f32x8`, one per lane) meet
//! each of a node's up to eight child boxes in turn, and a child is visited while any lane enters
//! it before its current closest hit — Embree's "hybrid" packets over wide nodes, where
//! [`super::packet`] walks the BVH2 two boxes a step. Reads rays, the [`Bvh8`] and the
//! BVH-ordered triangle columns; writes hits or occlusion flags.
//!
//! Box and triangle tests are [`super::packet`]'s (the same conservative slab test, the same
//! 8-wide watertight test with its scalar fallbacks, the same settled t, ties in t to the lower
//! triangle index), so every lane's hit is the one every other traversal finds; tests/packet.rs
//! checks it. Closest-hit traversal visits children nearest first by the entry distance of the
//! first lane that enters them. Any-hit traversal tests a node's leaf children as soon as the
//! node is reached, before entering any inner child, as the other traversals do, and takes
//! children unsorted (any occluder ends a lane): it tests them in slot order and pushes the inner
//! ones in slot order, so the last is entered first; its stack holds only inner nodes and their
//! lanes, no entry distances (Embree's occlusion walk keeps no more), 0.98–1.19× the speed of a
//! walk that built every node's keys, distances and lanes on the boxes, the bunny and the ogre
//! (BENCHMARKS.md, issue 18, eighteenth part).
//!
//! Hand-over (Embree's hybrid traversal, Benthin et al. 2012): a stack entry reached by at most
//! [`THIN_LANES`] active lanes is finished by each of those lanes alone, with the 8-wide single
//! ray's own loop ([`super::wide_traverse`]) started at that node and the lane's best hit so far.
//! A lane's hit does not depend on the order its leaves are met in, so the hits are the same as
//! without hand-over; tests/packet.rs checks 0, the default and 8 (every lane alone from the root).

use super::bvh::{Hit, TriangleColumns};
use super::packet::{any_leaf, best_ts, closest_leaf, limits, Packet, LANES};
use super::traverse::{Best, RayQuery, Stack};
use super::triangle8::bits;
use super::wide::{Bvh8, Node8, WIDTH};
use super::wide_traverse::{any_walk, closest_walk, key, sort_keys, unkey, Entry as SingleEntry, Prepared, Visits};
use wide::f32x8;

/// A child waiting on the closest-hit stack: node index or first block of a leaf, its triangle
/// count (0 for a node), per lane the entry distance (NaN where the lane does not enter), and the
/// lanes that enter it.
#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    count: u32,
    t: f32x8,
    lanes: u32,
}

impl Default for Entry {
    fn default() -> Self {
        Entry { child: 0, count: 0, t: f32x8::ZERO, lanes: 0 }
    }
}

/// The triangles of a leaf child: `count` of them, from its first block on.
#[inline(always)]
fn leaf_ids(bvh: &Bvh8, first_block: u32, count: u32) -> impl Iterator<Item = u32> + '_ {
    let first = first_block as usize;
    let blocks = &bvh.blocks()[first..first + count.div_ceil(8) as usize];
    blocks.iter().flat_map(|b| b.ids).take(count as usize)
}

/// Per lane, the entry distance into child `s` of `node` within `t` (NaN where the lane misses it:
/// [`Packet::entry_box`]).
#[inline(always)]
fn child_entry(p: &Packet, node: &Node8, s: usize, t: f32x8) -> f32x8 {
    let pl = &node.planes;
    p.entry_box([pl[0][s], pl[1][s], pl[2][s]], [pl[3][s], pl[4][s], pl[5][s]], t)
}

/// The children of `node` that lanes of `mask` enter within `t`: their keys (the entry distance of
/// the first lane that enters, as bits above the slot; distances are ≥ 0 and never NaN there, so
/// bits order as values do; the smallest over the lanes measured no better) and number, nearest
/// first; and per slot the entry distances and entering lanes.
#[inline(always)]
fn entered(p: &Packet, node: &Node8, t: f32x8, mask: u32) -> ([u64; WIDTH], usize, [f32x8; WIDTH], [u32; WIDTH]) {
    let (mut keys, mut n) = ([0u64; WIDTH], 0);
    let (mut ts, mut lanes) = ([f32x8::ZERO; WIDTH], [0u32; WIDTH]);
    let mut valid = u32::from(node.valid);
    while valid != 0 {
        let s = valid.trailing_zeros() as usize;
        valid &= valid - 1;
        let te = child_entry(p, node, s, t);
        let inside = te.simd_le(t);
        let m = bits(inside) & mask;
        if m == 0 {
            continue;
        }
        let near = te.to_array()[m.trailing_zeros() as usize];
        keys[n] = key(near, s);
        n += 1;
        (ts[s], lanes[s]) = (te, m);
    }
    sort_keys(&mut keys, n);
    (keys, n, ts, lanes)
}

/// Closest hits of 8 rays (fewer at the end of a slice).
fn closest8(
    bvh: &Bvh8,
    tris: TriangleColumns<'_>,
    rays: &[RayQuery],
    out: &mut [Option<Hit>],
    stacks: &mut Stacks,
    thin: u32,
) {
    let Stacks { packet: stack, single, .. } = stacks;
    let mut prepared: [Option<Prepared>; LANES] = Default::default();
    let nodes = bvh.nodes();
    let p = Packet::load(rays);
    let t_max = p.t_max.to_array();
    let mut best: [Best; LANES] = std::array::from_fn(|l| Best::new(t_max[l]));
    let mut t_best = best_ts(&best);
    let mut limit = limits(&best);
    stack.clear();
    if !nodes.is_empty() && p.valid != 0 {
        // Entered at 0 by every lane; invalid lanes are masked off by `lanes`.
        stack.push(Entry { child: 0, count: 0, t: f32x8::ZERO, lanes: p.valid });
    }
    while let Some(e) = stack.pop() {
        // Within the lanes that entered: entry distances are computed for every lane, and an
        // invalid lane holds a stand-in ray that must never be traced.
        let mask = bits(e.t.simd_le(t_best)) & e.lanes;
        if mask == 0 {
            continue;
        }
        if mask.count_ones() <= thin {
            // Few lanes left: each walks the subtree alone.
            let t = e.t.to_array();
            let mut m = mask;
            while m != 0 {
                let l = m.trailing_zeros() as usize;
                m &= m - 1;
                let ray = prepared[l].get_or_insert_with(|| Prepared::new(&rays[l]));
                closest_walk::<true, false>(
                    bvh,
                    tris.cut,
                    ray,
                    (e.child, e.count, t[l]),
                    &mut best[l],
                    single,
                    &mut Visits::default(),
                );
            }
            t_best = best_ts(&best);
            limit = limits(&best);
            continue;
        }
        if e.count > 0 {
            closest_leaf(&p, tris, leaf_ids(bvh, e.child, e.count), mask, bvh.pad(), &mut best, &mut limit);
            t_best = best_ts(&best);
            continue;
        }
        let node = &nodes[e.child as usize];
        let (keys, n, ts, lanes) = entered(&p, node, t_best, mask);
        // Farthest pushed first, so the nearest is popped first.
        for &k in keys[..n].iter().rev() {
            let s = unkey(k).0;
            stack.push(Entry { child: node.child[s], count: u32::from(node.count[s]), t: ts[s], lanes: lanes[s] });
        }
    }
    for (l, o) in out.iter_mut().enumerate() {
        *o = best[l].hit();
    }
}

/// Any-hit tests of 8 rays. A node's children are tested in slot order: a leaf child that lanes
/// enter is tested at once, an inner one is pushed with the lanes that enter it (no entry
/// distances: any occluder ends a lane), so every leaf child of a node is tested before any of
/// its inner children is entered, and the last inner child pushed is entered first.
fn occluded8(
    bvh: &Bvh8,
    tris: TriangleColumns<'_>,
    rays: &[RayQuery],
    out: &mut [bool],
    stacks: &mut Stacks,
    thin: u32,
) {
    let Stacks { any: stack, single, .. } = stacks;
    let mut prepared: [Option<Prepared>; LANES] = Default::default();
    let nodes = bvh.nodes();
    let p = Packet::load(rays);
    let t_max = p.t_max;
    let t_arr = t_max.to_array();
    let mut blocked = 0u32;
    stack.clear();
    if !nodes.is_empty() && p.valid != 0 {
        stack.push((0, p.valid));
    }
    'walk: while let Some((n, lanes)) = stack.pop() {
        let mask = lanes & !blocked;
        if mask == 0 {
            continue;
        }
        if mask.count_ones() <= thin {
            // Few lanes left: each walks the subtree alone.
            let mut m = mask;
            while m != 0 {
                let l = m.trailing_zeros() as usize;
                m &= m - 1;
                let ray = prepared[l].get_or_insert_with(|| Prepared::new(&rays[l]));
                if any_walk::<true, false>(bvh, tris.cut, ray, (n, 0, 0.0), t_arr[l], single, &mut Visits::default()) {
                    blocked |= 1 << l;
                }
            }
            if blocked & p.valid == p.valid {
                break;
            }
            continue;
        }
        let node = &nodes[n as usize];
        let mut valid = u32::from(node.valid);
        while valid != 0 {
            let s = valid.trailing_zeros() as usize;
            valid &= valid - 1;
            let m = bits(child_entry(&p, node, s, t_max).simd_le(t_max)) & mask & !blocked;
            if m == 0 {
                continue;
            }
            let count = u32::from(node.count[s]);
            if count == 0 {
                stack.push((node.child[s], m));
                continue;
            }
            blocked |= any_leaf(&p, tris, leaf_ids(bvh, node.child[s], count), m, bvh.pad(), t_max, &t_arr);
            if blocked & p.valid == p.valid {
                break 'walk;
            }
        }
    }
    for (l, o) in out.iter_mut().enumerate() {
        *o = blocked >> l & 1 == 1;
    }
}

/// Active lanes at or below which a stack entry is finished by each lane alone. 4 measured best
/// or within noise of the best on the bunny's and the ogre's rays (`thin` 0–8, BENCHMARKS.md,
/// issue 18, eleventh part): bunny camera rays 19.0 → 21.6 Mrays/s against none.
pub const THIN_LANES: u32 = 4;

/// The stacks of a packet walk: the closest-hit packet's, the any-hit packet's (inner nodes and
/// the lanes that enter them), and the single ray's for lanes handed over.
struct Stacks {
    packet: Stack<Entry>,
    any: Stack<(u32, u32)>,
    single: Stack<SingleEntry>,
}

impl Stacks {
    fn new() -> Self {
        Stacks { packet: Stack::new(), any: Stack::new(), single: Stack::new() }
    }
}

/// Closest hits of `rays` into `out`, 8 at a time through the 8-wide BVH (`tris`: the
/// BVH-ordered columns its leaves address), a node reached by at most `thin` lanes finished by
/// each lane alone.
pub fn closest_packets8(bvh: &Bvh8, tris: TriangleColumns<'_>, rays: &[RayQuery], out: &mut [Option<Hit>], thin: u32) {
    let mut stacks = Stacks::new();
    for (r, o) in rays.chunks(LANES).zip(out.chunks_mut(LANES)) {
        closest8(bvh, tris, r, o, &mut stacks, thin);
    }
}

/// Any-hit tests of `rays` into `out`, 8 at a time through the 8-wide BVH (`thin` as in
/// [`closest_packets8`]).
pub fn occluded_packets8(bvh: &Bvh8, tris: TriangleColumns<'_>, rays: &[RayQuery], out: &mut [bool], thin: u32) {
    let mut stacks = Stacks::new();
    for (r, o) in rays.chunks(LANES).zip(out.chunks_mut(LANES)) {
        occluded8(bvh, tris, r, o, &mut stacks, thin);
    }
}
