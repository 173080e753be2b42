//! The SAH build of the tree the 8-wide single ray walks: top-down splits of the padded triangle
//! boxes chosen by the surface area heuristic (MacDonald and Booth 1990), by sweeping every
//! sorted order of the centres (Wald, Boulos and Shirley 2007) and, for large nodes, over 32 bins
//! per axis (Wald 2007). Reads the boxes; writes obvhs [`Bvh2`] nodes (root first; an inner
//! node's children at `first_index` and the next) and `primitive_indices`, the boxes in leaf
//! order, for [`super::wide::Bvh8::collapse`].
//!
//! Why a second tree: over obvhs's PLOC build (`medium_build`, Morton-ordered), which the BVH2
//! packets keep, the 8-wide single ray ran 1.15–1.25× slower on the bunny's and the ogre's
//! bounce rays than over this one (measured in one process: BENCHMARKS.md, issue 18, thirteenth
//! part); Embree's own Morton build (LOW quality) runs its rays 20–30 % slower than its SAH
//! build. The packets lost over this tree instead (coherent any-hit rows 18–82 % slower), so
//! each kernel keeps the tree it is fastest on.
//!
//! **Leaves.** Every node of at most [`MAX_LEAF`] triangles — one 8-lane [`super::triangle8::
//! TriBlock`] — is a leaf: a block costs the same for one triangle as for eight, so splitting it
//! further only adds boxes to test (the heuristic weighing triangles one by one made the bunny's
//! rays 10–20 % slower than PLOC; leaves of up to 8 made them 18–25 % faster).
//!
//! **Determinism.** The build is a pure function of the boxes: centres sort by (coordinate,
//! index), every choice is strict and first-found, no threads. The tree's shape still follows the
//! rounding of areas, so another scale of the same scene may give another tree. No image depends
//! on it: triangles keep the indices of the BVH-ordered columns, and every traversal returns the
//! same hit whatever tree it walks, its t settled into the triangle's box
//! ([`super::slab::settle`]).

use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::Bvh2;

/// Most triangles in a leaf: one 8-lane triangle block.
pub const MAX_LEAF: usize = 8;
/// Nodes with more triangles than this are split over bins; smaller ones by the full sweep.
const SWEEP_MAX: usize = 1024;
/// Bins per axis.
const BINS: usize = 32;
/// Below this depth splits fall back to the median of the largest axis, bounding the depth (and
/// the build's time) whatever the heuristic chooses on pathological input.
const MAX_SAH_DEPTH: usize = 64;

/// The BVH2 over `boxes` (no nodes when there are none).
#[must_use]
pub fn build(boxes: &[Aabb]) -> Bvh2 {
    let mut bvh = Bvh2::default();
    let n = boxes.len();
    if n == 0 {
        return bvh;
    }
    let centres: Vec<Vec3A> = boxes.iter().map(Aabb::center).collect();
    let mut order: Vec<u32> = (0..n as u32).collect();
    let mut nodes = vec![Bvh2Node::new(Aabb::empty(), 0, 0)];
    let mut areas = vec![0.0f32; n];
    // (node, first, end, depth); the left child is popped first, so nodes lie in depth-first order.
    let mut work = vec![(0usize, 0usize, n, 0usize)];
    let mut depth_reached = 0;
    while let Some((node, lo, hi, depth)) = work.pop() {
        depth_reached = depth_reached.max(depth);
        let ids = &mut order[lo..hi];
        let bounds = ids.iter().fold(Aabb::empty(), |b, &i| b.union(&boxes[i as usize]));
        if ids.len() <= MAX_LEAF {
            nodes[node] = Bvh2Node::new(bounds, ids.len() as u32, lo as u32);
            continue;
        }
        let k = split(ids, boxes, &centres, depth, &mut areas);
        let first = nodes.len();
        nodes.push(Bvh2Node::new(Aabb::empty(), 0, 0));
        nodes.push(Bvh2Node::new(Aabb::empty(), 0, 0));
        nodes[node] = Bvh2Node::new(bounds, 0, first as u32);
        work.push((first + 1, lo + k, hi, depth + 1));
        work.push((first, lo, lo + k, depth + 1));
    }
    bvh.nodes = nodes;
    bvh.primitive_indices = order;
    bvh.max_depth = bvh.max_depth.max(depth_reached + 1);
    bvh
}

/// Reorders `ids` (more than [`MAX_LEAF`]) so that the left child's come first, and returns
/// their number (0 < k < len).
fn split(ids: &mut [u32], boxes: &[Aabb], centres: &[Vec3A], depth: usize, areas: &mut [f32]) -> usize {
    let (lo, hi) = ids.iter().fold((Vec3A::INFINITY, Vec3A::NEG_INFINITY), |(lo, hi), &i| {
        let c = centres[i as usize];
        (lo.min(c), hi.max(c))
    });
    let extent = hi - lo;
    let widest = extent.max_position();
    if extent[widest].is_nan() || extent[widest] <= 0.0 || depth >= MAX_SAH_DEPTH {
        return median(ids, centres, widest);
    }
    if ids.len() > SWEEP_MAX {
        if let Some(k) = binned(ids, boxes, centres, lo, extent) {
            return k;
        }
    }
    sweep(ids, boxes, centres, extent, areas)
}

/// Sorts `ids` by their centres' coordinate `axis`, ties by index.
fn sort_on(ids: &mut [u32], centres: &[Vec3A], axis: usize) {
    ids.sort_unstable_by(|&a, &b| centres[a as usize][axis].total_cmp(&centres[b as usize][axis]).then(a.cmp(&b)));
}

/// The object median along `axis`.
fn median(ids: &mut [u32], centres: &[Vec3A], axis: usize) -> usize {
    sort_on(ids, centres, axis);
    ids.len() / 2
}

/// The cheapest split of every sorted order: A(left)·N(left) + A(right)·N(right), over each axis
/// along which the centres spread.
fn sweep(ids: &mut [u32], boxes: &[Aabb], centres: &[Vec3A], extent: Vec3A, areas: &mut [f32]) -> usize {
    let n = ids.len();
    let mut best = (f32::INFINITY, usize::MAX, n / 2);
    let mut sorted_on = None;
    for axis in (0..3).filter(|&a| extent[a] > 0.0) {
        sort_on(ids, centres, axis);
        sorted_on = Some(axis);
        let mut right = Aabb::empty();
        for k in (1..n).rev() {
            right = right.union(&boxes[ids[k] as usize]);
            areas[k] = right.half_area();
        }
        let mut left = Aabb::empty();
        for k in 1..n {
            left = left.union(&boxes[ids[k - 1] as usize]);
            let cost = left.half_area() * k as f32 + areas[k] * (n - k) as f32;
            if cost < best.0 {
                best = (cost, axis, k);
            }
        }
    }
    // No finite cost (areas overflowing f32): the median of the widest axis.
    let axis = if best.1 == usize::MAX { extent.max_position() } else { best.1 };
    // The order (coordinate, then index) is total, so ids already sorted on it stay as they are.
    if sorted_on != Some(axis) {
        sort_on(ids, centres, axis);
    }
    best.2
}

/// The cheapest split between 32 equal bins of the centres' extent per axis, or `None` when the
/// centres all fall on one side of every boundary.
fn binned(ids: &mut [u32], boxes: &[Aabb], centres: &[Vec3A], lo: Vec3A, extent: Vec3A) -> Option<usize> {
    let scale = Vec3A::splat(BINS as f32) / extent;
    let bin = |i: u32, axis: usize| (((centres[i as usize][axis] - lo[axis]) * scale[axis]) as usize).min(BINS - 1);
    let mut best = (f32::INFINITY, 0usize, 0usize);
    for axis in (0..3).filter(|&a| extent[a] > 0.0) {
        let mut count = [0usize; BINS];
        let mut bounds = [Aabb::empty(); BINS];
        for &i in ids.iter() {
            let b = bin(i, axis);
            count[b] += 1;
            bounds[b] = bounds[b].union(&boxes[i as usize]);
        }
        let mut right_area = [0.0f32; BINS];
        let mut right = Aabb::empty();
        for b in (1..BINS).rev() {
            right = right.union(&bounds[b]);
            right_area[b] = right.half_area();
        }
        let (mut left, mut left_count) = (Aabb::empty(), 0);
        for b in 1..BINS {
            left = left.union(&bounds[b - 1]);
            left_count += count[b - 1];
            let right_count = ids.len() - left_count;
            if left_count == 0 || right_count == 0 {
                continue;
            }
            let cost = left.half_area() * left_count as f32 + right_area[b] * right_count as f32;
            if cost < best.0 {
                best = (cost, axis, b);
            }
        }
    }
    if !best.0.is_finite() {
        return None;
    }
    let (axis, boundary) = (best.1, best.2);
    let mut k = 0;
    for j in 0..ids.len() {
        if bin(ids[j], axis) < boundary {
            ids.swap(k, j);
            k += 1;
        }
    }
    Some(k)
}
