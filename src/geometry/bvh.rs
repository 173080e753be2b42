//! The bounding volume hierarchies: obvhs builds a BVH2 over padded triangle boxes, which orders
//! the scene's triangle columns and which the ray packets walk; [`super::sah`] builds a second
//! BVH2 over the same boxes, collapsed to the 8-wide tree the single rays walk. Traversal calls
//! our watertight triangle test, with every hit's t settled into its triangle's box
//! ([`super::slab::settle`]), so both trees give the same hits.
//!
//! obvhs 0.4.0 computes Morton codes over the union of the primitive boxes; a box centre lying
//! exactly on that union's max face gets a code that wraps to 0 (DESIGN.md §8), so the +x/+y/+z
//! walls of every closed room sort next to the opposite walls and traversal slows 5–13×. We pad
//! every primitive box symmetrically by a small fraction of the scene diagonal: centres do not
//! move, the union grows, and no centre lies on its max face. Padding also keeps the slab test
//! conservative for flat boxes and rays that graze box faces.

use super::cut_out::CutOuts;
use super::triangle::{intersect_triangle, TriangleHit};
use super::wide::Bvh8;
use glam::{Vec3, Vec3A};
use obvhs::{aabb::Aabb, bvh2::Bvh2, ray::Ray, BvhBuildParams};

/// Relative padding of primitive boxes (fraction of the scene diagonal).
pub const BOX_PAD: f32 = 1e-5;

/// A closest hit: triangle index (in the scene's BVH order), distance and barycentrics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Triangle index.
    pub tri: u32,
    /// Ray parameter.
    pub t: f32,
    /// Barycentrics of the three vertices.
    pub b: [f32; 3],
}

/// A BVH over triangles stored as three vertex columns.
pub struct Bvh {
    bvh: Bvh2,
    /// The SAH tree over the same triangles ([`super::sah`]) collapsed to 8-wide nodes, built
    /// on first use: by `photonwave bench`, and by renders whose ray queues try single rays or
    /// 8-wide packets ([`crate::traversal_choice`]).
    wide: std::sync::OnceLock<Bvh8>,
    /// [`shared_pad`] of the triangles: the padding of the boxes hits are settled against.
    pad: f32,
}

impl Bvh {
    /// Builds over the triangles (`p0[i]`, `p1[i]`, `p2[i]`). Returns the BVH and the permutation:
    /// `order[k]` is the input index of the triangle the BVH calls `k`; callers reorder their
    /// per-triangle columns by it so that leaf indices address them directly.
    #[must_use]
    pub fn build(p0: &[Vec3], p1: &[Vec3], p2: &[Vec3]) -> (Bvh, Vec<u32>) {
        let pad = shared_pad(p0, p1, p2);
        let boxes = padded_boxes(p0, p1, p2, pad);
        let mut build_time = std::time::Duration::ZERO;
        let bvh = obvhs::bvh2::builder::build_bvh2(&boxes, BvhBuildParams::medium_build(), &mut build_time);
        let order = bvh.primitive_indices.clone();
        (Bvh { bvh, wide: std::sync::OnceLock::new(), pad }, order)
    }

    /// The padding every triangle's box shares ([`shared_pad`]): the margin of the box a hit's
    /// t is settled against ([`super::slab::settle`]).
    #[must_use]
    pub fn pad(&self) -> f32 {
        self.pad
    }

    /// The obvhs nodes (root first; children of an inner node at `first_index` and the next).
    #[must_use]
    pub fn nodes(&self) -> &[obvhs::bvh2::node::Bvh2Node] {
        &self.bvh.nodes
    }

    /// The 8-wide tree over `tris` (the BVH-ordered columns, whose indices its leaves keep):
    /// [`super::sah`]'s BVH2 over their padded boxes, collapsed, with the leaves' triangles
    /// copied into blocks; built on first call.
    #[must_use]
    pub fn wide(&self, tris: TriangleColumns<'_>) -> &Bvh8 {
        self.wide.get_or_init(|| {
            let sah = super::sah::build(&padded_boxes(tris.p0, tris.p1, tris.p2, self.pad));
            Bvh8::collapse(&sah.nodes, &sah.primitive_indices, self.pad, |id| {
                let i = id as usize;
                [tris.p0[i], tris.p1[i], tris.p2[i]]
            })
        })
    }

    /// obvhs's own single-ray traversal (closest hit) calling the same triangle test: the
    /// baseline the packet traversal is benchmarked against. Ties go to the first found.
    #[must_use]
    pub fn closest_obvhs(&self, tris: TriangleColumns<'_>, o: Vec3, d: Vec3, t_max: f32) -> Option<Hit> {
        if self.bvh.nodes.is_empty() || !o.is_finite() || !d.is_finite() {
            return None;
        }
        let ray = Ray::new(Vec3A::from(o), Vec3A::from(d), 0.0, t_max);
        let mut best: Option<TriangleHit> = None;
        let mut best_tri = 0u32;
        let mut rh = obvhs::ray::RayHit::none();
        self.bvh.ray_traverse(ray, &mut rh, |r, id| {
            match intersect_triangle(o, d, r.tmax, tris.p0[id], tris.p1[id], tris.p2[id]) {
                Some(h) if !tris.passes(id as u32, h.b, o, d) => {
                    best = Some(h);
                    best_tri = id as u32;
                    h.t
                }
                _ => f32::INFINITY,
            }
        });
        best.map(|h| Hit { tri: best_tri, t: h.t, b: h.b })
    }

    /// obvhs's single-ray any-hit traversal (baseline for the packet traversal).
    #[must_use]
    pub fn occluded_obvhs(&self, tris: TriangleColumns<'_>, o: Vec3, d: Vec3, t_max: f32) -> bool {
        if self.bvh.nodes.is_empty() || !o.is_finite() || !d.is_finite() {
            return false;
        }
        let ray = Ray::new(Vec3A::from(o), Vec3A::from(d), 0.0, t_max);
        !self.bvh.ray_traverse_miss(ray, |_, id| hit_t(tris, o, d, t_max, id))
    }

    /// Number of triangle tests a closest-hit query makes (a measure of BVH quality that does not
    /// depend on machine load; see the Morton-wrap note above).
    #[must_use]
    pub fn triangle_tests(&self, tris: TriangleColumns<'_>, o: Vec3, d: Vec3) -> u32 {
        if self.bvh.nodes.is_empty() || !o.is_finite() || !d.is_finite() {
            return 0;
        }
        let mut tests = 0u32;
        let mut rh = obvhs::ray::RayHit::none();
        let ray = Ray::new(Vec3A::from(o), Vec3A::from(d), 0.0, f32::INFINITY);
        self.bvh.ray_traverse(ray, &mut rh, |r, id| {
            tests += 1;
            hit_t(tris, o, d, r.tmax, id)
        });
        tests
    }
}

/// t of triangle `i`'s hit in (0, t_max), or +∞ (also where the ray passes a cut-out): what
/// obvhs's traversal callbacks return.
#[inline]
fn hit_t(tris: TriangleColumns<'_>, o: Vec3, d: Vec3, t_max: f32, i: usize) -> f32 {
    intersect_triangle(o, d, t_max, tris.p0[i], tris.p1[i], tris.p2[i])
        .filter(|h| !tris.passes(i as u32, h.b, o, d))
        .map_or(f32::INFINITY, |h| h.t)
}

/// The padding every triangle's box gets: [`BOX_PAD`] of the scene diagonal (1 for no triangles).
#[must_use]
pub fn shared_pad(p0: &[Vec3], p1: &[Vec3], p2: &[Vec3]) -> f32 {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for p in p0.iter().chain(p1).chain(p2) {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let diag = if p0.is_empty() { 1.0 } else { (hi - lo).length().max(f32::MIN_POSITIVE) };
    diag * BOX_PAD
}

/// Triangle boxes padded as [`Bvh::build`] pads them (module notes): by `shared`, the triangles'
/// [`shared_pad`], plus a few ulps of their own magnitude.
#[must_use]
pub fn padded_boxes(p0: &[Vec3], p1: &[Vec3], p2: &[Vec3], shared: f32) -> Vec<Aabb> {
    (0..p0.len())
        .map(|i| {
            let mn = p0[i].min(p1[i]).min(p2[i]);
            let mx = p0[i].max(p1[i]).max(p2[i]);
            // Padding relative to both the scene and the box's own magnitude.
            let pad = Vec3::splat(shared) + mn.abs().max(mx.abs()) * 4.0 * f32::EPSILON;
            Aabb::new(Vec3A::from(mn - pad), Vec3A::from(mx + pad))
        })
        .collect()
}

/// obvhs's CWBVH (8-wide compressed nodes) over the same padded boxes, traversed by obvhs's own
/// single-ray code: a second baseline for the packet traversal (`photonwave bench`).
pub struct CwBaseline {
    bvh: obvhs::cwbvh::CwBvh,
}

impl CwBaseline {
    /// Builds over BVH-ordered columns (so primitive indices address them directly).
    #[must_use]
    pub fn build(tris: TriangleColumns<'_>) -> Self {
        let boxes = padded_boxes(tris.p0, tris.p1, tris.p2, shared_pad(tris.p0, tris.p1, tris.p2));
        let mut t = std::time::Duration::ZERO;
        CwBaseline { bvh: obvhs::cwbvh::builder::build_cwbvh(&boxes, BvhBuildParams::medium_build(), &mut t) }
    }

    /// Closest hit (obvhs CWBVH traversal, same triangle test).
    #[must_use]
    pub fn closest(&self, tris: TriangleColumns<'_>, o: Vec3, d: Vec3, t_max: f32) -> bool {
        if self.bvh.nodes.is_empty() || !o.is_finite() || !d.is_finite() {
            return false;
        }
        let ray = Ray::new(Vec3A::from(o), Vec3A::from(d), 0.0, t_max);
        let mut rh = obvhs::ray::RayHit::none();
        let idx = &self.bvh.primitive_indices;
        self.bvh.ray_traverse(ray, &mut rh, |r, id| hit_t(tris, o, d, r.tmax, idx[id] as usize))
    }

    /// Any hit (obvhs CWBVH traversal).
    #[must_use]
    pub fn occluded(&self, tris: TriangleColumns<'_>, o: Vec3, d: Vec3, t_max: f32) -> bool {
        if self.bvh.nodes.is_empty() || !o.is_finite() || !d.is_finite() {
            return false;
        }
        let ray = Ray::new(Vec3A::from(o), Vec3A::from(d), 0.0, t_max);
        let idx = &self.bvh.primitive_indices;
        !self.bvh.ray_traverse_miss(ray, |_, id| hit_t(tris, o, d, t_max, idx[id] as usize))
    }
}

/// Borrowed vertex columns in BVH order, and the cut-outs that traversals over them honour.
#[derive(Clone, Copy)]
pub struct TriangleColumns<'a> {
    /// First vertices.
    pub p0: &'a [Vec3],
    /// Second vertices.
    pub p1: &'a [Vec3],
    /// Third vertices.
    pub p2: &'a [Vec3],
    /// What lets rays through parts of triangles ([`super::cut_out`]); `None`: every hit counts.
    pub cut: CutOuts<'a>,
}

impl<'a> TriangleColumns<'a> {
    /// The columns, without cut-outs.
    #[must_use]
    pub fn new(p0: &'a [Vec3], p1: &'a [Vec3], p2: &'a [Vec3]) -> Self {
        TriangleColumns { p0, p1, p2, cut: None }
    }

    /// Whether the ray `o + t·d` passes through triangle `id` at barycentrics `b`
    /// ([`super::cut_out::passes`]).
    #[inline(always)]
    #[must_use]
    pub fn passes(&self, id: u32, b: [f32; 3], o: Vec3, d: Vec3) -> bool {
        super::cut_out::passes(self.cut, id, b, o, d)
    }
}
