//! The one place that chooses between the SIMD kernels and their scalar twins.
//!
//! Every SIMD kernel has a scalar twin with the same signature: packet BVH traversal
//! ([`crate::geometry::packet`]) and single-ray traversal ([`crate::geometry::traverse`]); the
//! 8-wide and one-at-a-time photon lookups ([`crate::photon_map`]). The twins make the same
//! decisions (same hits, same photons found); sums over photons differ only in rounding order.
//! The renderer runs [`KernelSet::Simd`] unless `kernels = "scalar"` is set.

use crate::geometry::bvh::{Bvh, Hit, TriangleColumns};
use crate::geometry::{packet, traverse, RayQuery};
use serde::{Deserialize, Serialize};

/// Which implementation of the SIMD kernels runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum KernelSet {
    /// 8-wide `wide::f32x8` kernels (the default: fastest, measured in BENCHMARKS.md).
    #[default]
    Simd,
    /// The scalar twins (the reference the SIMD kernels are tested against).
    Scalar,
}

impl KernelSet {
    /// Closest hits of `rays` into `out`.
    pub fn closest(self, bvh: &Bvh, tris: TriangleColumns<'_>, rays: &[RayQuery], out: &mut [Option<Hit>]) {
        match self {
            KernelSet::Simd => packet::closest_packets(bvh, tris, rays, out),
            KernelSet::Scalar => traverse::closest_rays(bvh, tris, rays, out),
        }
    }

    /// Any-hit tests of `rays` into `out`.
    pub fn occluded(self, bvh: &Bvh, tris: TriangleColumns<'_>, rays: &[RayQuery], out: &mut [bool]) {
        match self {
            KernelSet::Simd => packet::occluded_packets(bvh, tris, rays, out),
            KernelSet::Scalar => traverse::occluded_rays(bvh, tris, rays, out),
        }
    }
}
