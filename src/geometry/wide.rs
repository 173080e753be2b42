//! The 8-wide BVH: obvhs's BVH2 collapsed into nodes of up to eight children, whose boxes one
//! ray tests at once (`wide::f32x8`, one child per lane) — Embree's layout for incoherent rays
//! (Wald et al. 2008, "Getting rid of packets"; Benthin et al. 2012). Reads the BVH2 nodes;
//! writes [`Node8`]s with the six box planes of the children as SoA columns.
//!
//! Collapse: [`super::wide_collapse`] chooses, by the surface area heuristic over the whole
//! tree, which inner BVH2 nodes become 8-wide nodes and which dissolve into their parent's
//! slots; this module builds that shape. BVH2 leaves (≤ 8 triangles from obvhs's build) stay
//! leaves with their boxes, so every traversal prunes by the BVH2's leaf boxes (what that does
//! and does not guarantee: [`super::wide_collapse`]).
//! Triangle indices are unchanged, so leaves address the same BVH-ordered columns as the BVH2.
//! Against the greedy collapse it replaced (the inner child of largest area opened until eight),
//! the bunny's tree has a third fewer nodes (4 887 → 3 289, 4.3 → 5.8 children each) and bounce
//! rays visit 7.4 nodes instead of 7.7 (BENCHMARKS.md, issue 18, eleventh part).
//!
//! The box test is [`box_entry`]'s, lane by lane: the same conservative slab test (far
//! distance grown by 1 + 2γ₃), the same operations in the same order. Taking the near plane by
//! the sign of the inverse direction instead of min(t0, t1) gives the same values: (b − o)·inv
//! is monotonic in b, rounding included, and never NaN (finite origins, boxes and inverses).
//! [`Node8::entries_scalar`] is the scalar twin, calling [`box_entry`] per child.

use super::slab::{box_entry, FAR_GROWTH};
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
        let slab = |k: usize, o: f32x8, inv: f32x8| (plane(k) - o) * inv;
        let (nx, ny, nz) = (slab(r.near[0], r.ox, r.ix), slab(r.near[1], r.oy, r.iy), slab(r.near[2], r.oz, r.iz));
        let (fx, fy, fz) = (slab(r.far[0], r.ox, r.ix), slab(r.far[1], r.oy, r.iy), slab(r.far[2], r.oz, r.iz));
        let t_near = nx.fast_max(ny).fast_max(nz).fast_max(f32x8::ZERO);
        let t_far = fx.fast_min(fy).fast_min(fz) * f32x8::splat(FAR_GROWTH);
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

/// One ray splatted across the lanes for [`Node8::entries`], with the plane of each axis it
/// enters first (the min plane where the inverse direction is ≥ 0, else the max plane).
#[derive(Clone, Copy, Debug)]
pub struct WideRay {
    ox: f32x8,
    oy: f32x8,
    oz: f32x8,
    ix: f32x8,
    iy: f32x8,
    iz: f32x8,
    near: [usize; 3],
    far: [usize; 3],
}

impl WideRay {
    /// The ray from `o` with inverse direction `inv` (finite: [`super::slab::inverse_direction`]).
    #[inline]
    #[must_use]
    pub fn new(o: Vec3, inv: Vec3) -> Self {
        // Written out, not with array maps: one build left this map out of line, a call per ray
        // that made every single-ray bench row 7–26 % slower (BENCHMARKS.md, issue 18, eighth part).
        let side = |a: usize| if inv[a] >= 0.0 { a } else { a + 3 };
        let near = [side(0), side(1), side(2)];
        let opposite = |k: usize| if k < 3 { k + 3 } else { k - 3 };
        WideRay {
            ox: f32x8::splat(o.x),
            oy: f32x8::splat(o.y),
            oz: f32x8::splat(o.z),
            ix: f32x8::splat(inv.x),
            iy: f32x8::splat(inv.y),
            iz: f32x8::splat(inv.z),
            near,
            far: [opposite(near[0]), opposite(near[1]), opposite(near[2])],
        }
    }
}

/// The 8-wide nodes, root first (empty for a scene without triangles), and the leaves'
/// triangles in blocks of eight.
#[derive(Clone, Debug, Default)]
pub struct Bvh8 {
    nodes: Vec<Node8>,
    blocks: Vec<TriBlock>,
}

impl Bvh8 {
    /// Collapses the BVH2 `nodes` (root first; children of an inner node at `first_index` and
    /// the next) whose leaves hold the triangles `tri(id)` (BVH order), in the shape
    /// [`Layout::choose`] finds cheapest.
    #[must_use]
    pub fn collapse(nodes: &[Bvh2Node], tri: impl Fn(u32) -> [Vec3; 3]) -> Self {
        if nodes.is_empty() {
            return Bvh8::default();
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
                    TriBlock::push_leaf(&mut blocks, b.first_index, count, &tri);
                } else {
                    node.child[slot] = out.len() as u32;
                    work.push((k, out.len()));
                    out.push(Node8::EMPTY);
                }
                node.valid |= 1 << slot;
            }
            out[at] = node;
        }
        Bvh8 { nodes: out, blocks }
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
    use super::super::slab::inverse_direction;
    use super::*;

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
