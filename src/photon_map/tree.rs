//! The photon tree: photons in blocks of 8 (one `f32x8` per column), the blocks under a
//! bounding-volume hierarchy of 8-wide nodes, and the walk that finds every block within a
//! (possibly shrinking) radius of a query point that holds photons facing its way
//! ([`super::orientation`]). Reads photon positions at build; writes their order and the nodes. The node test (a sphere against 8 child boxes) has its scalar twin beside
//! it, with the same operations, so both code paths reach the same blocks in the same order.
//!
//! Each node splits its photons into up to 8 parts by repeated median splits along the longest
//! extent, on block boundaries, so that every part but the last is a complete subtree
//! ([`build_node`]): every subtree is a contiguous range of whole blocks (only the map's last
//! block may be short). A node keeps its children's boxes; a part of one block is a leaf.
//!
//! The box test prunes exactly: a box's distance to the query is computed with the photon
//! distance's operations on coordinates no farther, and rounding is monotone, so a photon within
//! the radius never lies in a pruned box.

use super::orientation::ALL;
use super::{Photon, PhotonMap};
use crate::code_path::CodePath;
use glam::Vec3;
use wide::bytemuck::cast;
use wide::{f32x8, u32x8};

/// Photons per block: one `f32x8` per column.
const BLOCK: usize = 8;

/// A child slot holding a leaf carries this bit and the block's index; otherwise a node's index.
pub(super) const LEAF: u32 = 1 << 31;

/// Depth of the walk's stack: each node pushes at most 7 more entries than it pops, and a tree of
/// 2³² photons is 10 nodes deep. A query packet's walk (depth first through the same nodes) is
/// bounded alike.
pub(super) const STACK: usize = 72;

/// One node: its children's boxes in SoA form and what each child is. Empty slots have inverted
/// boxes (low +∞, high −∞), which no sphere reaches.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Node {
    lo: [[f32; 8]; 3],
    hi: [[f32; 8]; 3],
    pub(super) child: [u32; 8],
    /// Per child (byte `c` for child `c`), the direction classes of the photons below it, as
    /// bits ([`super::orientation`]); 0 in an empty slot.
    pub(super) classes: [u8; 8],
    /// The slots holding leaves, as bits.
    pub(super) leaves: u8,
}

impl Node {
    const EMPTY: Node = Node {
        lo: [[f32::INFINITY; 8]; 3],
        hi: [[f32::NEG_INFINITY; 8]; 3],
        child: [0; 8],
        classes: [0; 8],
        leaves: 0,
    };

    /// Squared distances from `p` to the 8 child boxes (0 inside), and the mask of those below `r2`.
    #[inline]
    pub(super) fn distances8(&self, p: Vec3, r2: f32) -> ([f32; 8], u32) {
        let mut d2 = f32x8::ZERO;
        for a in 0..3 {
            let (lo, hi, pa) = (f32x8::from(self.lo[a]), f32x8::from(self.hi[a]), f32x8::splat(p[a]));
            // Never NaN (p is finite, box bounds are never NaN): the plain max instruction.
            let d = (lo - pa).fast_max(pa - hi).fast_max(f32x8::ZERO);
            d2 += d * d;
        }
        (d2.to_array(), d2.simd_lt(f32x8::splat(r2)).to_bitmask())
    }

    /// Scalar twin of [`Node::distances8`]: the same operations, one child at a time.
    #[inline]
    fn distances(&self, p: Vec3, r2: f32) -> ([f32; 8], u32) {
        let mut out = [0f32; 8];
        let mut mask = 0;
        for (c, d2) in out.iter_mut().enumerate() {
            for a in 0..3 {
                let d = (self.lo[a][c] - p[a]).max(p[a] - self.hi[a][c]).max(0.0);
                *d2 += d * d;
            }
            mask |= u32::from(*d2 < r2) << c;
        }
        (out, mask)
    }

    /// The children holding a photon of the classes `reach`, as bits: the 8 bytes of
    /// `classes` tested at once in a 64-bit word (each byte's high bit set where the byte
    /// is nonzero, then the 8 high bits gathered by one multiply). Every child for [`ALL`] (a
    /// walk that skips nothing: no test; an empty slot no sphere reaches anyway).
    #[inline]
    pub(super) fn facing8(&self, reach: u8) -> u32 {
        if reach == ALL {
            return 0xff;
        }
        let x = u64::from_le_bytes(self.classes) & (u64::from(reach) * 0x0101_0101_0101_0101);
        let low = 0x7f7f_7f7f_7f7f_7f7f;
        let high = (((x & low) + low) | x) & !low;
        ((high >> 7).wrapping_mul(0x0102_0408_1020_4080) >> 56) as u32
    }

    /// Scalar twin of [`Node::facing8`]: one byte at a time.
    #[inline]
    pub(super) fn facing(&self, reach: u8) -> u32 {
        if reach == ALL {
            return 0xff;
        }
        (0..8).fold(0, |bits, c| bits | u32::from(self.classes[c] & reach != 0) << c)
    }
}

/// A walk through the tree toward a query point: [`Walk::next`] returns every block whose box lies
/// within the radius² it is given, which may shrink between calls, and that holds photons of the
/// direction classes the walk reaches ([`super::orientation`]). `NEAREST_FIRST`: a node's
/// children in order of their boxes' distance, so a shrinking radius shrinks early (k-nearest
/// lookups); otherwise in slot order. The caller's loop holds the per-block work, so its sums stay
/// in registers.
pub(super) struct Walk<const NEAREST_FIRST: bool> {
    set: CodePath,
    p: Vec3,
    /// The direction classes it reaches ([`super::orientation::reachable`]).
    reach: u8,
    /// Children still to visit, each with its box's squared distance (popped from the end).
    stack: [(u32, f32); STACK],
    top: usize,
    /// Slots of `node`'s leaves within the radius not yet returned (`NEAREST_FIRST` false).
    pending: u32,
    node: u32,
}

impl<const NEAREST_FIRST: bool> Walk<NEAREST_FIRST> {
    /// A walk of `map` toward `p` by code path `set` (the node tests or their scalar twins)
    /// through the children holding photons of the classes `reach`. A non-finite query lies at a
    /// non-finite distance from every photon: its walk is empty.
    #[inline]
    pub(super) fn new(map: &PhotonMap, set: CodePath, p: Vec3, reach: u8) -> Self {
        let top = usize::from(!map.nodes.is_empty() && p.is_finite());
        Walk { set, p, reach, stack: [(0, 0.0); STACK], top, pending: 0, node: 0 }
    }

    /// The next block (photons `lo..hi`, at most [`BLOCK`], `lo` a multiple of it) whose box lies
    /// within `r2` of the query and that holds photons of the classes the walk reaches. (Forcing it inline into the caller's loop measured 5–8 % slower.)
    #[inline]
    pub(super) fn next(&mut self, map: &PhotonMap, r2: f32) -> Option<(usize, usize)> {
        loop {
            if !NEAREST_FIRST && self.pending != 0 {
                let c = self.pending.trailing_zeros() as usize;
                self.pending &= self.pending - 1;
                return Some(map.block(map.nodes[self.node as usize].child[c]));
            }
            if self.top == 0 {
                return None;
            }
            self.top -= 1;
            let (child, d2) = self.stack[self.top];
            if d2 >= r2 {
                continue;
            }
            if child & LEAF != 0 {
                return Some(map.block(child));
            }
            let node = &map.nodes[child as usize];
            let (d2s, mut hits) = match self.set {
                CodePath::Simd => {
                    let (d2s, hits) = node.distances8(self.p, r2);
                    (d2s, hits & node.facing8(self.reach))
                }
                CodePath::Scalar => {
                    let (d2s, hits) = node.distances(self.p, r2);
                    (d2s, hits & node.facing(self.reach))
                }
            };
            if NEAREST_FIRST {
                // Pushed farthest first, so that the nearest is popped first (of equals, the
                // later slot). A child's place above `top` is the number of reached children
                // popped after it, counted 8 at a time without branches (an insertion sort's
                // mispredicted compares measured 4 % of a k-nearest lookup).
                let reached = hits.count_ones() as usize;
                let d = f32x8::from(d2s);
                let slot = u32x8::from([0, 1, 2, 3, 4, 5, 6, 7]);
                let mut rank = u32x8::ZERO;
                let mut left = hits;
                while left != 0 {
                    let c = left.trailing_zeros();
                    left &= left - 1;
                    let dc = f32x8::splat(d2s[c as usize]);
                    let earlier: f32x8 = cast(slot.simd_gt(u32x8::splat(c)));
                    // Child c is popped after child i: it lies farther, or as far in an earlier slot.
                    let after: u32x8 = cast(dc.simd_gt(d) | (dc.simd_eq(d) & earlier));
                    rank += after & u32x8::ONE;
                }
                let rank = rank.to_array();
                while hits != 0 {
                    let c = hits.trailing_zeros() as usize;
                    hits &= hits - 1;
                    self.stack[self.top + rank[c] as usize] = (node.child[c], d2s[c]);
                }
                self.top += reached;
            } else {
                // Leaves at once, in slot order; nodes pushed last slot first, so that they are
                // popped in slot order.
                let leaves = u32::from(node.leaves);
                (self.pending, self.node) = (hits & leaves, child);
                hits &= !leaves;
                while hits != 0 {
                    let c = 31 - hits.leading_zeros() as usize;
                    hits &= !(1 << c);
                    self.stack[self.top] = (node.child[c], d2s[c]);
                    self.top += 1;
                }
            }
        }
    }
}

impl PhotonMap {
    /// The photon range of the block in a leaf slot (`child` carries [`LEAF`]).
    #[inline]
    pub(super) fn block(&self, child: u32) -> (usize, usize) {
        let lo = (child & !LEAF) as usize * BLOCK;
        (lo, (lo + BLOCK).min(self.len))
    }

    /// Bytes of the tree's nodes per stored photon.
    #[must_use]
    pub fn tree_bytes_per_photon(&self) -> f64 {
        (self.nodes.len() * std::mem::size_of::<Node>()) as f64 / self.len.max(1) as f64
    }

    /// Squared distance of photon `i` from `p`: the same operations as the 8-wide form.
    #[inline]
    pub(super) fn d2(&self, i: usize, p: Vec3) -> f32 {
        let (dx, dy, dz) = (self.x[i] - p.x, self.y[i] - p.y, self.z[i] - p.z);
        dx * dx + dy * dy + dz * dz
    }
}

/// Orders `photons` into the tree's blocks and returns its nodes (none for no photons; the root
/// is node 0), on `threads` threads ([`build_top`]); the tree is the same at any thread count.
pub(super) fn build_tree(photons: &mut [Photon], threads: usize) -> Vec<Node> {
    let mut nodes = Vec::new();
    if photons.len() >= PARALLEL_BUILD && threads > 1 {
        nodes = build_top(photons, threads);
    } else if !photons.is_empty() {
        nodes.push(Node::EMPTY);
        build_node(photons, 0, 0, photons.len(), 0, &mut nodes);
    }
    nodes
}

/// Maps of at least this many photons build their root's subtrees in parallel (below it the
/// fork costs more than it saves).
const PARALLEL_BUILD: usize = 1 << 14;

/// [`build_node`] at the root, then the root's subtrees at once, each into its own nodes, joined
/// in the order the serial build numbers them: a subtree's nodes are contiguous there, its root
/// first, so a subtree built alone (its root node 0) is the serial one with every node index
/// shifted by where its root lands. Leaves name their block by its place in the whole map.
fn build_top(photons: &mut [Photon], threads: usize) -> Vec<Node> {
    let (parts, len) = split_parts(photons, 0, photons.len());
    let parts = &parts[..len];
    let mut root = boxes(photons, parts);
    // The parts' photons as disjoint slices, each taken by the one chunk that builds its subtree.
    let mut rest = &mut photons[..];
    let mut slices = Vec::with_capacity(len);
    for &(a, b) in parts {
        let (part, tail) = std::mem::take(&mut rest).split_at_mut(b - a);
        slices.push(std::sync::Mutex::new((a, part)));
        rest = tail;
    }
    let subtrees = crate::parallel::map_chunks(
        len,
        1,
        threads,
        |range| {
            let mut slot = slices[range.start].lock().unwrap_or_else(|e| e.into_inner());
            let (base, part) = &mut *slot;
            let base = *base;
            if part.len() <= BLOCK {
                return Vec::new();
            }
            let mut nodes = vec![Node::EMPTY];
            build_node(part, base, 0, part.len(), 0, &mut nodes);
            nodes
        },
        |_| {},
    );
    let mut nodes = vec![Node::EMPTY];
    for (c, (&(a, b), subtree)) in parts.iter().zip(subtrees).enumerate() {
        if blocks(a, b) == 1 {
            root.leaves |= 1 << c;
            root.child[c] = LEAF | (a / BLOCK) as u32;
            continue;
        }
        let shift = nodes.len() as u32;
        root.child[c] = shift;
        nodes.extend(subtree.into_iter().map(|mut node| {
            // Inner children: neither a leaf nor an empty slot (child 0, which no inner child
            // of a subtree is: node 0 is its root).
            for (slot, child) in node.child.iter_mut().enumerate() {
                if node.leaves & (1 << slot) == 0 && *child != 0 {
                    *child += shift;
                }
            }
            node
        }));
    }
    nodes[0] = root;
    nodes
}

/// Blocks in the photon range `lo..hi`.
fn blocks(lo: usize, hi: usize) -> usize {
    (hi - lo).div_ceil(BLOCK)
}

/// Fills node `index` with the parts of the photon range `lo..hi` ([`split_parts`]), and builds
/// the nodes below it. `photons` starts at photon `base` of the map (where a leaf's block index
/// counts from).
fn build_node(photons: &mut [Photon], base: usize, lo: usize, hi: usize, index: usize, nodes: &mut Vec<Node>) {
    let (parts, len) = split_parts(photons, lo, hi);
    let mut node = boxes(photons, &parts[..len]);
    for (c, &(a, b)) in parts[..len].iter().enumerate() {
        node.child[c] = if blocks(a, b) == 1 {
            node.leaves |= 1 << c;
            LEAF | ((base + a) / BLOCK) as u32
        } else {
            let child = nodes.len();
            nodes.push(Node::EMPTY);
            build_node(photons, base, a, b, child, nodes);
            child as u32
        };
    }
    nodes[index] = node;
}

/// Splits the photon range `lo..hi` into up to 8 parts (reordering the photons), each of at
/// most `cap` blocks, the smallest power of 8 that leaves at most 8 parts, and all but the last
/// full: subtrees are complete, so nodes have 8 children wherever the photons allow (halving at
/// the median instead left nodes of two leaves: 5.3 bytes of nodes per photon, against 4.1). The
/// parts depend on the count alone; which photons go where, on their positions.
fn split_parts(photons: &mut [Photon], lo: usize, hi: usize) -> ([(usize, usize); 8], usize) {
    let mut cap = 1;
    while cap * 8 < blocks(lo, hi) {
        cap *= 8;
    }
    let chunks = |a: usize, b: usize| blocks(a, b).div_ceil(cap);
    let mut parts = [(0usize, 0usize); 8];
    parts[0] = (lo, hi);
    let mut len = 1;
    loop {
        // The part with the most chunks (the first of equals) is split: its first half of whole
        // chunks below the median of its longest extent, the rest above.
        let (j, &(a, b)) =
            parts[..len].iter().enumerate().max_by_key(|&(j, &(a, b))| (chunks(a, b), usize::MAX - j)).expect("a part");
        if chunks(a, b) < 2 {
            break;
        }
        let mid = a + chunks(a, b) / 2 * cap * BLOCK;
        let (mn, mx) = bounds(&photons[a..b]);
        let ext = mx - mn;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        photons[a..b].select_nth_unstable_by(mid - a, |x, y| x.position[axis].total_cmp(&y.position[axis]));
        parts.copy_within(j + 1..len, j + 2);
        parts[j] = (a, mid);
        parts[j + 1] = (mid, b);
        len += 1;
    }
    (parts, len)
}

/// A node whose children's boxes are those of `parts` (children not yet set).
fn boxes(photons: &[Photon], parts: &[(usize, usize)]) -> Node {
    let mut node = Node::EMPTY;
    for (c, &(a, b)) in parts.iter().enumerate() {
        let (mn, mx) = bounds(&photons[a..b]);
        for axis in 0..3 {
            node.lo[axis][c] = mn[axis];
            node.hi[axis][c] = mx[axis];
        }
    }
    node
}

/// The box of `photons`' positions, ignoring NaN coordinates (such a photon is never within any
/// radius); inverted (+∞, −∞) on an axis where every coordinate is NaN.
fn bounds(photons: &[Photon]) -> (Vec3, Vec3) {
    let mut mn = [f32::INFINITY; 3];
    let mut mx = [f32::NEG_INFINITY; 3];
    for ph in photons {
        for a in 0..3 {
            mn[a] = mn[a].min(ph.position[a]);
            mx[a] = mx[a].max(ph.position[a]);
        }
    }
    (Vec3::from(mn), Vec3::from(mx))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The node test's SIMD form and scalar twin give the same distances and masks to the bit,
    /// inside, outside, on the faces and with inverted (empty) slots.
    #[test]
    fn node_test_matches_its_scalar_twin() {
        let mut node = Node::EMPTY;
        for c in 0..6 {
            let o = c as f32 * 0.25 - 0.5;
            for a in 0..3 {
                node.lo[a][c] = o + a as f32 * 0.1;
                node.hi[a][c] = o + 0.3 + a as f32 * 0.05;
            }
        }
        node.lo[0][6] = f32::NEG_INFINITY; // an infinite box
        node.hi[0][6] = f32::INFINITY;
        for p in [Vec3::ZERO, Vec3::splat(-0.5), Vec3::new(0.3, -0.2, 0.75), Vec3::splat(1e6), Vec3::splat(-0.2)] {
            for r2 in [0.0, 1e-3, 0.04, 1.0, 1e30] {
                let (a, ma) = node.distances8(p, r2);
                let (b, mb) = node.distances(p, r2);
                assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits), "{p} {r2}");
                assert_eq!(ma, mb, "{p} {r2}");
                assert_eq!(ma & 0x80, 0, "the empty slot is never reached");
            }
        }
    }

    /// The class test (8 bytes in a 64-bit word) and its scalar twin agree on random byte
    /// patterns, empty children included.
    #[test]
    fn class_test_matches_its_scalar_twin() {
        let mut rnd = super::super::test_uniforms(8);
        let mut node = Node::EMPTY;
        for _ in 0..2000 {
            node.classes = std::array::from_fn(|_| if rnd() < 0.3 { 0 } else { (rnd() * 256.0) as u8 });
            let reach = (rnd() * 256.0) as u8;
            assert_eq!(node.facing8(reach), node.facing(reach), "{:?} {reach:b}", node.classes);
        }
    }

    /// Every photon sits in exactly one leaf block, inside its box; nodes never nest a block twice.
    #[test]
    fn every_photon_lies_in_one_block_inside_its_box() {
        let mut rnd = super::super::test_uniforms(7);
        for n in [1usize, 7, 8, 9, 63, 64, 65, 1000, 4099] {
            let mut photons: Vec<Photon> = (0..n)
                .map(|i| Photon {
                    position: Vec3::new(rnd(), rnd() * 0.1, i as f32 * 1e-3),
                    power: Vec3::ONE,
                    wi: Vec3::Y,
                    normal: Vec3::Y,
                    flags: 0,
                })
                .collect();
            let nodes = build_tree(&mut photons, 1);
            let mut seen = vec![0u32; n.div_ceil(BLOCK)];
            for node in &nodes {
                for c in 0..8 {
                    if node.lo[0][c] > node.hi[0][c] {
                        continue;
                    }
                    if node.child[c] & LEAF != 0 {
                        let b = (node.child[c] & !LEAF) as usize;
                        seen[b] += 1;
                        for ph in &photons[b * BLOCK..(b * BLOCK + BLOCK).min(n)] {
                            for a in 0..3 {
                                assert!(node.lo[a][c] <= ph.position[a] && ph.position[a] <= node.hi[a][c]);
                            }
                        }
                    }
                }
            }
            assert!(seen.iter().all(|&k| k == 1), "n {n}: {seen:?}");
        }
    }

    /// A map built on 2 or 3 threads has the serial build's tree and photon order, bit for bit:
    /// above [`PARALLEL_BUILD`] photons, where the root's subtrees are built apart and joined.
    #[test]
    fn a_parallel_build_is_the_serial_build() {
        let mut rnd = super::super::test_uniforms(11);
        for n in [PARALLEL_BUILD, PARALLEL_BUILD + 1, 3 * PARALLEL_BUILD + 77, 70_001] {
            let photons: Vec<Photon> = (0..n)
                .map(|_| Photon {
                    position: Vec3::new(rnd(), rnd() * 0.3, rnd() * 2.0),
                    power: Vec3::ONE,
                    wi: Vec3::Y,
                    normal: Vec3::Y,
                    flags: 0,
                })
                .collect();
            let mut serial = photons.clone();
            let serial_nodes = build_tree(&mut serial, 1);
            for threads in [2, 3] {
                let mut parallel = photons.clone();
                let nodes = build_tree(&mut parallel, threads);
                assert!(nodes == serial_nodes, "n {n}, {threads} threads: the nodes differ");
                assert!(parallel == serial, "n {n}, {threads} threads: the photon order differs");
            }
        }
    }
}
