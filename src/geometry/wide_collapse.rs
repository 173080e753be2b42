//! How the BVH2 becomes 8-wide: which inner BVH2 nodes turn into 8-wide nodes and which
//! dissolve into their parent's child slots — chosen by the surface area heuristic over the whole
//! tree, by dynamic programming (after Ylitie, Karras and Laine 2017, "Efficient incoherent ray
//! traversal on GPUs through compressed wide BVHs", §4). Reads the BVH2 nodes; writes a
//! [`Layout`] that [`super::wide::Bvh8::collapse`] turns into nodes.
//!
//! The cost of a tree is the expected number of 8-wide nodes a ray visits: the sum of their box
//! areas (a ray meets a box with a chance proportional to its area). Every BVH2 leaf takes one
//! slot whatever the shape, so its tests cost the same in every tree and are left out. For a
//! BVH2 node n with box area A(n) and j = 1..8, C(n, j) is the least cost of the subtree under n
//! spread over at most j child slots:
//!
//! - C(n, 1): n as one slot: 0 for a leaf; for an inner node an 8-wide node of its own,
//!   A(n) + min over k of C(left, k) + C(right, 8 − k);
//! - C(n, j ≥ 2): the better of C(n, j − 1) and min over k of C(left, k) + C(right, j − k).
//!
//! BVH2 leaves stay leaves, with their own boxes. (Letting small sibling leaves share one leaf,
//! as Ylitie et al. do, ran 3–5 % faster over obvhs's PLOC tree; it was tried before hits were
//! settled into their triangles' boxes, when a union box could prune a hit the BVH2 found:
//! BENCHMARKS.md, issue 18, eleventh part. The tree collapsed now is the SAH build's, whose
//! leaves already fill their blocks.)

use obvhs::bvh2::node::Bvh2Node;

/// Children per 8-wide node.
const WIDTH: usize = 8;

/// What one BVH2 node becomes: per number of slots j (index j − 1), the least cost and how it is
/// reached. `split[0]`: the slots its left child gets when it is an 8-wide node (0 for a leaf);
/// `split[j − 1]` for j ≥ 2: 0 to spread over j − 1 slots instead, else the left child's slots.
#[derive(Clone, Copy)]
struct Choice {
    cost: [f32; WIDTH],
    split: [u8; WIDTH],
}

/// The chosen shape of the 8-wide tree over a BVH2.
pub struct Layout {
    choice: Vec<Choice>,
}

impl Layout {
    /// Chooses the layout over `nodes` (root first; an inner node's children at `first_index`
    /// and the next; not empty).
    #[must_use]
    pub fn choose(nodes: &[Bvh2Node]) -> Self {
        let mut choice = vec![Choice { cost: [0.0; WIDTH], split: [0; WIDTH] }; nodes.len()];
        // Post order: a node is decided after both its children.
        let mut work = vec![(0usize, false)];
        while let Some((n, children_done)) = work.pop() {
            let node = &nodes[n];
            if node.prim_count > 0 {
                continue;
            }
            let (l, r) = (node.first_index as usize, node.first_index as usize + 1);
            if !children_done {
                work.extend([(n, true), (l, false), (r, false)]);
                continue;
            }
            let (cl, cr) = (&choice[l].cost, &choice[r].cost);
            // The best split of j slots between the children, j = 2..8: (cost, left's slots).
            let spread = |j: usize| {
                (1..j).map(|k| (cl[k - 1] + cr[j - k - 1], k as u8)).min_by(|a, b| a.0.total_cmp(&b.0)).unwrap()
            };
            let (inner, k) = spread(WIDTH);
            let a = node.aabb.half_area();
            let mut c = Choice { cost: [0.0; WIDTH], split: [0; WIDTH] };
            (c.cost[0], c.split[0]) = (a + inner, k);
            for j in 2..=WIDTH {
                let (s, k) = spread(j);
                (c.cost[j - 1], c.split[j - 1]) = if s < c.cost[j - 2] { (s, k) } else { (c.cost[j - 2], 0) };
            }
            choice[n] = c;
        }
        Layout { choice }
    }

    /// The child slots of inner BVH2 node `n` as an 8-wide node: BVH2 nodes whose subtrees
    /// together cover n's.
    #[must_use]
    pub fn children(&self, nodes: &[Bvh2Node], n: usize) -> Vec<usize> {
        let mut out = Vec::with_capacity(WIDTH);
        let k = usize::from(self.choice[n].split[0]);
        let l = nodes[n].first_index as usize;
        self.slots(nodes, l, k, &mut out);
        self.slots(nodes, l + 1, WIDTH - k, &mut out);
        out
    }

    /// Appends the slots that the subtree under `n`, spread over at most `j` of them, takes.
    fn slots(&self, nodes: &[Bvh2Node], n: usize, mut j: usize, out: &mut Vec<usize>) {
        let split = &self.choice[n].split;
        while j > 1 && split[j - 1] == 0 {
            j -= 1;
        }
        if j == 1 || nodes[n].prim_count > 0 {
            out.push(n);
            return;
        }
        let k = usize::from(split[j - 1]);
        let l = nodes[n].first_index as usize;
        self.slots(nodes, l, k, out);
        self.slots(nodes, l + 1, j - k, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;
    use obvhs::aabb::Aabb;

    fn node(lo: [f32; 3], hi: [f32; 3], prims: u32, first: u32) -> Bvh2Node {
        Bvh2Node::new(Aabb::new(Vec3A::from(lo), Vec3A::from(hi)), prims, first)
    }

    /// A root over two inner nodes over two leaves each (nodes 3–6), leaf k holding `per_leaf`
    /// triangles in the box `boxes[k]`.
    fn two_level(boxes: [([f32; 3], [f32; 3]); 4], per_leaf: u32) -> Vec<Bvh2Node> {
        let union = |a: ([f32; 3], [f32; 3]), b: ([f32; 3], [f32; 3])| {
            (std::array::from_fn(|i| a.0[i].min(b.0[i])), std::array::from_fn(|i| a.1[i].max(b.1[i])))
        };
        let (l, r) = (union(boxes[0], boxes[1]), union(boxes[2], boxes[3]));
        let all = union(l, r);
        let mut nodes = vec![node(all.0, all.1, 0, 1), node(l.0, l.1, 0, 3), node(r.0, r.1, 0, 5)];
        for (k, b) in boxes.iter().enumerate() {
            nodes.push(node(b.0, b.1, per_leaf, k as u32 * per_leaf));
        }
        nodes
    }

    /// Four leaves in small boxes far apart: the root's node takes the four BVH2 leaves as its
    /// slots, the two inner BVH2 nodes between them dissolved (each would cost its area).
    #[test]
    fn distant_leaves_become_the_slots_of_one_node() {
        let at = |x: f32| ([x, 0.0, 0.0], [x + 0.1, 0.1, 0.1]);
        let nodes = two_level([at(0.0), at(10.0), at(20.0), at(30.0)], 4);
        let layout = Layout::choose(&nodes);
        assert_eq!(layout.children(&nodes, 0), vec![3, 4, 5, 6]);
    }

    /// Sixteen leaves under a balanced tree need two levels of 8-wide nodes: the nodes reached
    /// from the root have at most eight slots and cover every leaf exactly once.
    #[test]
    fn slots_cover_the_tree_once() {
        // A complete BVH2 of depth 4: node i's children at 2i + 1 and 2i + 2, leaves 15–30.
        let mut nodes = Vec::new();
        for i in 0..31u32 {
            let depth = 31 - (i + 1).leading_zeros();
            let (first_leaf, span) = {
                let level_start = (1 << depth) - 1;
                let width = 16 >> depth;
                ((i - level_start) * width, width)
            };
            let (lo, hi) = ([first_leaf as f32 * 2.0, 0.0, 0.0], [(first_leaf + span) as f32 * 2.0 - 1.0, 1.0, 1.0]);
            nodes.push(if i >= 15 { node(lo, hi, 8, (i - 15) * 8) } else { node(lo, hi, 0, 2 * i + 1) });
        }
        let layout = Layout::choose(&nodes);
        let mut seen = vec![0; 31];
        let mut work = vec![0usize];
        while let Some(n) = work.pop() {
            let kids = layout.children(&nodes, n);
            assert!(kids.len() <= 8);
            for k in kids {
                if nodes[k].prim_count > 0 {
                    seen[(nodes[k].first_index / 8) as usize] += 1;
                } else {
                    work.push(k);
                }
            }
        }
        assert!(seen[..16].iter().all(|&c| c == 1), "{seen:?}");
    }
}
