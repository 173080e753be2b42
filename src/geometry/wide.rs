//! The 8-wide BVH: a BVH2 ([`super::sah`]'s, over the scene's padded triangle boxes) collapsed
//! into nodes of up to eight children, whose boxes one ray tests at once (`wide::f32x8`, one
//! child per lane) — Embree's layout for incoherent rays (Wald et al. 2008, "Getting rid of
//! packets"; Benthin et al. 2012). Reads the BVH2 nodes; writes [`Node8`]s with the six box
//! planes of the children as SoA columns, and the leaves' triangles in [`TriBlock`]s.
//!
//! Collapse: [`super::wide_collapse`] chooses, by the surface area heuristic over the whole
//! tree, which inner BVH2 nodes become 8-wide nodes and which dissolve into their parent's
//! slots; this module builds that shape. BVH2 leaves (≤ 8 triangles) stay leaves with their
//! boxes. Each block lane keeps its triangle's index in the BVH-ordered columns the packets'
//! tree also addresses, so a tie in t goes to the same triangle whichever tree is walked, and
//! [`WideRay::settle`] makes the rest of every hit tree-independent ([`super::slab::settle`]).
//! Against the greedy collapse it replaced (the inner child of largest area opened until eight),
//! the bunny's tree has a third fewer nodes (4 887 → 3 289, 4.3 → 5.8 children each) and bounce
//! rays visit 7.4 nodes instead of 7.7 (BENCHMARKS.md, issue 18, eleventh part).
//!
//! The box test is [`box_entry`]'s, lane by lane ([`slab8`]): the same conservative slab test
//! (far distance grown by 1 + 2γ₃), the same operations in the same order. Both planes of each
//! axis are computed and ordered by min and max, rather than the near plane chosen by the sign
//! of the inverse direction: the mask and entry distances are the same ((b − o)·inv is
//! monotonic in b, rounding included, and never NaN; boxes have min ≤ max; only a zero's sign
//! may differ before the final max with 0), and three min/max per node cost less than reading
//! six plane indices back from the stack, where the compiler had spilled them (single-ray rows
//! up to 13 % faster: BENCHMARKS.md, issue 18, seventeenth part). [`Node8::entries_scalar`] is
//! the scalar twin, calling [`box_entry`] per child.

use super::slab::{box_entry, settle8, slab8};
use super::triangle8::TriBlock;
use super::wide_collapse::Layout;
use glam::{Vec3, Vec3A};
use obvhs::bvh2::node::Bvh2Node;
use wide::f32x8;

/// Children per node.
pub const WIDTH: usize = 8;

/// An 8-wide node: child boxes as plane columns, and per child a node index (inner) or a
/// triangle range (leaf).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct Node8 {
    /// Box planes of the children: min x, min y, min z, max x, max y, max z; one lane each.
    pub planes: [[f32; WIDTH]; 6],
    /// Inner child: its node index; leaf child: its first [`TriBlock`].
    pub child: [u32; WIDTH],
    /// Leaf child: its triangle count (1–255); inner child: 0.
    pub count: [u8; WIDTH],
    /// Bit i set for the children in use.
    pub valid: u8,
    /// Bit i set for the leaf children.
    pub leaves: u8,
}

impl Node8 {
    const EMPTY: Node8 = Node8 { planes: [[0.0; WIDTH]; 6], child: [0; WIDTH], count: [0; WIDTH], valid: 0, leaves: 0 };

    /// Child `i`'s box as (min, max).
    #[must_use]
    pub fn child_box(&self, i: usize) -> (Vec3A, Vec3A) {
        let p = &self.planes;
        (Vec3A::new(p[0][i], p[1][i], p[2][i]), Vec3A::new(p[3][i], p[4][i], p[5][i]))
    }

    /// Entry distances of one ray into the eight child boxes (lane = child), and the bit mask of
    /// children it enters at or before `t_max`. Lanes outside the mask hold garbage.
    #[inline(always)]
    #[must_use]
    pub fn entries(&self, r: &WideRay, t_max: f32) -> (u32, f32x8) {
        let p = &self.planes;
        let plane = |k: usize| f32x8::from(p[k]);
        let (lo, hi) = ([plane(0), plane(1), plane(2)], [plane(3), plane(4), plane(5)]);
        let (t_near, t_far) = slab8(lo, hi, [r.ox, r.oy, r.oz], [r.ix, r.iy, r.iz]);
        let hit = t_near.simd_le(t_far) & t_near.simd_le(f32x8::splat(t_max));
        (hit.to_bitmask() & u32::from(self.valid), t_near)
    }

    /// Scalar twin of [`Node8::entries`]: [`box_entry`] per child.
    #[must_use]
    pub fn entries_scalar(&self, o: Vec3, inv: Vec3, t_max: f32) -> (u32, [f32; WIDTH]) {
        let mut t = [f32::INFINITY; WIDTH];
        let mut mask = 0u32;
        for (i, ti) in t.iter_mut().enumerate() {
            if self.valid >> i & 1 == 1 {
                let (lo, hi) = self.child_box(i);
                *ti = box_entry(lo, hi, o.into(), inv.into(), t_max);
                if ti.is_finite() {
                    mask |= 1 << i;
                }
            }
        }
        (mask, t)
    }
}

/// One ray splatted across the lanes for [`Node8::entries`]: origin and inverse direction.
#[derive(Clone, Copy, Debug)]
pub struct WideRay {
    ox: f32x8,
    oy: f32x8,
    oz: f32x8,
    ix: f32x8,
    iy: f32x8,
    iz: f32x8,
}

impl WideRay {
    /// The ray from `o` with inverse direction `inv` (finite: [`super::slab::inverse_direction`]).
    #[inline]
    #[must_use]
    pub fn new(o: Vec3, inv: Vec3) -> Self {
        WideRay {
            ox: f32x8::splat(o.x),
            oy: f32x8::splat(o.y),
            oz: f32x8::splat(o.z),
            ix: f32x8::splat(inv.x),
            iy: f32x8::splat(inv.y),
            iz: f32x8::splat(inv.z),
        }
    }

    /// [`super::slab::settle`] for the eight triangles of `block` at once: `t` per lane raised
    /// to the ray's entry into the lane's [`super::slab::triangle_box`], +∞ where it misses that
    /// box ([`settle8`]; min and max are exact, so the order they take the vertices in does not
    /// matter: the scalar function's values bit for bit).
    #[inline(always)]
    #[must_use]
    pub fn settle(&self, t: f32x8, block: &TriBlock, pad: f32) -> f32x8 {
        let pad = f32x8::splat(pad);
        let col = |i: usize| f32x8::from(block.v[i]);
        let lo = |a: usize| col(a).fast_min(col(3 + a)).fast_min(col(6 + a)) - pad;
        let hi = |a: usize| col(a).fast_max(col(3 + a)).fast_max(col(6 + a)) + pad;
        // Written out, not with array maps (left out of line in some builds: BENCHMARKS.md,
        // issue 18, eighth part).
        let (lo, hi) = ([lo(0), lo(1), lo(2)], [hi(0), hi(1), hi(2)]);
        settle8(t, lo, hi, [self.ox, self.oy, self.oz], [self.ix, self.iy, self.iz])
    }
}

/// The 8-wide nodes, root first (empty for a scene without triangles), and the leaves'
/// triangles in blocks of eight.
#[derive(Clone, Debug, Default)]
pub struct Bvh8 {
    nodes: Vec<Node8>,
    blocks: Vec<TriBlock>,
    /// The BVH2's [`super::bvh::Bvh::pad`].
    pad: f32,
}

impl Bvh8 {
    /// Collapses the BVH2 `nodes` (root first; children of an inner node at `first_index` and
    /// the next; a leaf holds `ids[first_index..][..prim_count]`, indices of the triangles
    /// `tri(id)`), in the shape [`Layout::choose`] finds cheapest; `pad` is the
    /// [`super::bvh::Bvh::pad`] of the triangles.
    #[must_use]
    pub fn collapse(nodes: &[Bvh2Node], ids: &[u32], pad: f32, tri: impl Fn(u32) -> [Vec3; 3]) -> Self {
        if nodes.is_empty() {
            return Bvh8 { pad, ..Bvh8::default() };
        }
        let layout = Layout::choose(nodes);
        let mut out = vec![Node8::EMPTY];
        let mut blocks = Vec::new();
        // (BVH2 node, index of the Node8 that takes its children); a root leaf becomes the one
        // child of the root.
        let mut work = vec![(0usize, 0usize)];
        while let Some((n2, at)) = work.pop() {
            let kids = if nodes[n2].prim_count > 0 { vec![n2] } else { layout.children(nodes, n2) };
            let mut node = Node8::EMPTY;
            for (slot, &k) in kids.iter().enumerate() {
                let b = &nodes[k];
                let (lo, hi) = (b.aabb.min, b.aabb.max);
                for a in 0..3 {
                    node.planes[a][slot] = lo[a];
                    node.planes[a + 3][slot] = hi[a];
                }
                if b.prim_count > 0 {
                    // obvhs caps leaves at 255 primitives.
                    let count = b.prim_count.min(255);
                    node.child[slot] = blocks.len() as u32;
                    node.count[slot] = count as u8;
                    node.leaves |= 1 << slot;
                    let first = b.first_index as usize;
                    TriBlock::push_leaf(&mut blocks, &ids[first..first + count as usize], &tri);
                } else {
                    node.child[slot] = out.len() as u32;
                    work.push((k, out.len()));
                    out.push(Node8::EMPTY);
                }
                node.valid |= 1 << slot;
            }
            out[at] = node;
        }
        Bvh8 { nodes: out, blocks, pad }
    }

    /// The padding of the boxes hits are settled against ([`super::slab::settle`]).
    #[must_use]
    pub fn pad(&self) -> f32 {
        self.pad
    }

    /// The nodes, root first.
    #[must_use]
    pub fn nodes(&self) -> &[Node8] {
        &self.nodes
    }

    /// The leaves' triangle blocks.
    #[must_use]
    pub fn blocks(&self) -> &[TriBlock] {
        &self.blocks
    }

    /// Bytes the nodes and blocks occupy.
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node8>() + self.blocks.len() * std::mem::size_of::<TriBlock>()
    }
}

#[cfg(test)]
mod tests {
    use super::super::slab::{inverse_direction, settle};
    use super::*;

    /// The block form of `settle` returns the scalar function's t bit for bit: t below, inside
    /// and beyond each triangle's box, boxes the ray misses, flat and needle-thin triangles,
    /// zero direction components.
    #[test]
    fn settle_matches_the_scalar_twin() {
        let tris = [
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec3::new(0.0, 0.0, 2.0), Vec3::new(1.0, 0.0, 2.0), Vec3::new(0.0, 1.0, 2.0)],
            [Vec3::new(-3.0, 0.0, -1.0), Vec3::new(-2.0, 0.0, 1.0), Vec3::new(-2.5, 0.0, 0.0)],
            [Vec3::new(1.0, 1.0, 1.0), Vec3::new(4.0, 4.0, 4.0), Vec3::new(1.0, 4.0, 1.0)],
            [Vec3::new(-0.5, -0.5, 5.0), Vec3::new(0.5, 0.5, 6.0), Vec3::new(0.5, -0.5, 5.5)],
            [Vec3::new(0.0, 0.0, -10.0), Vec3::new(2e-7, 0.0, 10.0), Vec3::new(0.0, 2e-7, 10.0)],
        ];
        let mut block = TriBlock { v: [[0.0; 8]; 9], ids: [0; 8], live: 0 };
        for (l, p) in tris.iter().enumerate() {
            for (k, v) in p.iter().enumerate() {
                for a in 0..3 {
                    block.v[3 * k + a][l] = v[a];
                }
            }
            block.live |= 1 << l;
        }
        let dirs = [Vec3::Z, -Vec3::Z, Vec3::X, Vec3::new(1.0, 1.0, 1.0), Vec3::new(0.0, -1.0, 1e-30)];
        let origins = [Vec3::ZERO, Vec3::new(0.0, 0.0, -5.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(-2.0, 0.0, 0.0)];
        for o in origins {
            for d in dirs {
                let inv = inverse_direction(d);
                let ray = WideRay::new(o, inv);
                for pad in [0.0, 1e-5, 0.25] {
                    for t in [1e-3f32, 0.5, 1.0, 2.0, 7.5, 100.0] {
                        let wide = ray.settle(f32x8::splat(t), &block, pad).to_array();
                        for (l, p) in tris.iter().enumerate() {
                            let want = settle(t, o.into(), inv.into(), *p, pad);
                            assert_eq!(wide[l].to_bits(), want.to_bits(), "o {o}, d {d}, pad {pad}, t {t}, lane {l}");
                        }
                    }
                }
            }
        }
    }

    /// The 8-wide child test returns the scalar twin's mask and entry distances bit for bit,
    /// for rays with zero direction components, rays on slab planes and flat boxes.
    #[test]
    fn entries_match_the_scalar_twin() {
        let mut node = Node8::EMPTY;
        let boxes = [
            (Vec3::new(-1.0, -1.0, -1.0), Vec3::new(1.0, 1.0, 1.0)),
            (Vec3::new(0.0, 0.0, 2.0), Vec3::new(1.0, 1.0, 2.0)),
            (Vec3::new(-3.0, 0.0, -1.0), Vec3::new(-2.0, 0.0, 1.0)),
            (Vec3::new(1.0, 1.0, 1.0), Vec3::new(4.0, 4.0, 4.0)),
            (Vec3::new(-0.5, -0.5, 5.0), Vec3::new(0.5, 0.5, 6.0)),
            (Vec3::new(2.0, -1.0, -1.0), Vec3::new(3.0, 1.0, 1.0)),
            (Vec3::new(-1e-7, -1e-7, -10.0), Vec3::new(1e-7, 1e-7, 10.0)),
        ];
        for (i, (lo, hi)) in boxes.iter().enumerate() {
            for a in 0..3 {
                node.planes[a][i] = lo[a];
                node.planes[a + 3][i] = hi[a];
            }
            node.valid |= 1 << i;
        }
        let dirs = [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(0.0, -1.0, 1e-30),
            Vec3::new(-2.0, 0.5, 0.0),
        ];
        let origins = [Vec3::ZERO, Vec3::new(0.0, 0.0, -5.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(-2.0, 0.0, 0.0)];
        for o in origins {
            for d in dirs {
                let inv = inverse_direction(d);
                for t_max in [f32::INFINITY, 2.0, 0.0] {
                    let (m, t) = node.entries(&WideRay::new(o, inv), t_max);
                    let (ms, ts) = node.entries_scalar(o, inv, t_max);
                    assert_eq!(m, ms, "o {o}, d {d}, t_max {t_max}");
                    let t = t.to_array();
                    for l in 0..WIDTH {
                        if m >> l & 1 == 1 {
                            assert_eq!(t[l].to_bits(), ts[l].to_bits(), "o {o}, d {d}, lane {l}");
                        }
                    }
                }
            }
        }
    }
}
