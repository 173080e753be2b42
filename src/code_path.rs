//! The one place that chooses between the SIMD kernels and their scalar twins.
//!
//! Every SIMD kernel has a scalar twin with the same signature: packet BVH traversal
//! ([`crate::geometry::packet`]) and single-ray traversal ([`crate::geometry::traverse`]); the
//! 8-wide and one-at-a-time photon lookups ([`crate::photon_map`]); query packets of fixed-radius
//! lookups ([`crate::photon_map::query_packet`], whose twin runs the lookups one at a time). The
//! twins make the same decisions (same hits, same photons found); sums over photons differ only
//! in rounding order.
//! The renderer runs [`CodePath::Simd`] unless `code_path = "scalar"` is set.

use crate::geometry::bvh::{Bvh, Hit, TriangleColumns};
use crate::geometry::{packet, traverse, RayQuery};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// Which implementation of the SIMD kernels runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum CodePath {
    /// 8-wide `wide::f32x8` kernels (the default: fastest, measured in BENCHMARKS.md).
    #[default]
    Simd,
    /// The scalar twins (the reference the SIMD kernels are tested against).
    Scalar,
}

impl CodePath {
    /// Closest hits of `rays` into `out`.
    pub fn closest(self, bvh: &Bvh, tris: TriangleColumns<'_>, rays: &[RayQuery], out: &mut [Option<Hit>]) {
        match self {
            CodePath::Simd => packet::closest_packets(bvh, tris, rays, out),
            CodePath::Scalar => traverse::closest_rays(bvh, tris, rays, out),
        }
    }

    /// Any-hit tests of `rays` into `out`.
    pub fn occluded(self, bvh: &Bvh, tris: TriangleColumns<'_>, rays: &[RayQuery], out: &mut [bool]) {
        match self {
            CodePath::Simd => packet::occluded_packets(bvh, tris, rays, out),
            CodePath::Scalar => traverse::occluded_rays(bvh, tris, rays, out),
        }
    }
}

/// The Morton code of the cell holding `p` in a grid of `cells`³ (at most 1024) over `bounds`:
/// points close in code are close in space. Points outside go to the nearest cell, NaN
/// coordinates to cell 0 (`as` saturates).
#[must_use]
pub fn morton_code(p: Vec3, bounds: (Vec3, Vec3), cells: u32) -> u32 {
    let ext = (bounds.1 - bounds.0).max(Vec3::splat(f32::MIN_POSITIVE));
    let last = (cells.min(1024) - 1) as f32;
    let cell = ((p - bounds.0) / ext * cells as f32).clamp(Vec3::ZERO, Vec3::splat(last));
    // Bit i of each 10-bit coordinate to bit 3i.
    let spread = |v: f32| {
        let mut x = v as u32 & 1023;
        x = (x | x << 16) & 0x0300_00ff;
        x = (x | x << 8) & 0x0300_f00f;
        x = (x | x << 4) & 0x030c_30c3;
        (x | x << 2) & 0x0924_9249
    };
    spread(cell.x) | spread(cell.y) << 1 | spread(cell.z) << 2
}

/// The coherence key of a ray: direction octant in the top 3 bits, then the Morton code of its
/// origin's cell in a 64³ grid over `bounds`, then the direction within the octant quantised
/// to 4 × 4 bins — so that a run of 8 rays in key order starts close together and points alike.
#[must_use]
pub fn coherence_key(o: Vec3, d: Vec3, bounds: (Vec3, Vec3)) -> u32 {
    let octant = u32::from(d.x < 0.0) | u32::from(d.y < 0.0) << 1 | u32::from(d.z < 0.0) << 2;
    let morton = morton_code(o, bounds, 64);
    let a = d.abs() / d.abs().element_sum().max(f32::MIN_POSITIVE);
    let bin = |v: f32| ((v * 4.0) as u32).min(3);
    let dir = bin(a.x) << 2 | bin(a.y);
    octant << 29 | morton << 4 | dir
}

/// Traces `rays` in coherence-key order (packets of 8 that start close together and point
/// alike) and returns the results in the input order. The SIMD kernels' results do not depend on
/// the order (each lane's hit is the scalar twin's), so sorting changes speed only.
fn in_coherent_order<T: Copy + Default>(
    rays: &[RayQuery],
    bounds: (Vec3, Vec3),
    trace: impl FnOnce(&[RayQuery], &mut [T]),
) -> Vec<T> {
    let mut order: Vec<(u32, u32)> =
        rays.iter().enumerate().map(|(i, r)| (coherence_key(r.origin, r.direction, bounds), i as u32)).collect();
    order.sort_unstable();
    let sorted: Vec<RayQuery> = order.iter().map(|&(_, i)| rays[i as usize]).collect();
    let mut traced = vec![T::default(); rays.len()];
    trace(&sorted, &mut traced);
    let mut out = vec![T::default(); rays.len()];
    for (&(_, i), t) in order.iter().zip(traced) {
        out[i as usize] = t;
    }
    out
}

impl CodePath {
    /// Closest hits of `rays` (in input order); the SIMD set traces them sorted for coherence.
    #[must_use]
    pub fn closest_coherent(
        self,
        bvh: &Bvh,
        tris: TriangleColumns<'_>,
        rays: &[RayQuery],
        bounds: (Vec3, Vec3),
    ) -> Vec<Option<Hit>> {
        match self {
            CodePath::Simd => in_coherent_order(rays, bounds, |r, o| packet::closest_packets(bvh, tris, r, o)),
            CodePath::Scalar => {
                let mut out = vec![None; rays.len()];
                traverse::closest_rays(bvh, tris, rays, &mut out);
                out
            }
        }
    }
}
