//! The one place that chooses between the SIMD kernels and their scalar twins.
//!
//! Every SIMD kernel has a scalar twin with the same signature: packet BVH traversal
//! ([`crate::geometry::packet`]) and single-ray traversal ([`crate::geometry::traverse`]); the
//! 8-wide and one-at-a-time photon lookups ([`crate::photon_map`]); query packets of fixed-radius
//! lookups ([`crate::photon_map::query_packet`], whose twin runs the lookups one at a time). The
//! twins make the same decisions (same hits, same photons found); sums over photons differ only
//! in rounding order.
//! The renderer runs [`CodePath::Simd`] unless `code_path = "scalar"` is set; within it,
//! [`crate::traversal_choice`] picks BVH2 packets, single rays or 8-wide packets per ray queue.

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

/// A grid of `cells`³ (at most 1024) over a box, for Morton codes: points close in code are
/// close in space. The scale is computed once (a division per coordinate per point measured
/// ~12 % of `intersect_paths`, the divider's latency).
#[derive(Clone, Copy, Debug)]
pub struct MortonGrid {
    lo: Vec3,
    /// Cells per unit length, per axis.
    scale: Vec3,
    /// The last cell's index.
    last: f32,
}

impl MortonGrid {
    /// The grid of `cells`³ over `bounds` (a flat or empty axis counts as tiny, not zero).
    #[must_use]
    pub fn new(bounds: (Vec3, Vec3), cells: u32) -> Self {
        let cells = cells.clamp(1, 1024);
        let ext = (bounds.1 - bounds.0).max(Vec3::splat(f32::MIN_POSITIVE));
        MortonGrid { lo: bounds.0, scale: cells as f32 / ext, last: (cells - 1) as f32 }
    }

    /// The Morton code of the cell holding `p`. Points outside go to the nearest cell, NaN
    /// coordinates to cell 0 (`as` saturates).
    #[must_use]
    pub fn code(&self, p: Vec3) -> u32 {
        let cell = ((p - self.lo) * self.scale).clamp(Vec3::ZERO, Vec3::splat(self.last));
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
}

/// Cells per axis of the origin grid in a ray's [`coherence_key`].
pub const COHERENCE_CELLS: u32 = 64;

/// The coherence key of a ray: direction octant in the top 3 bits, then the Morton code of its
/// origin's cell in `grid` (a [`COHERENCE_CELLS`]³ grid over the scene's bounds), then the
/// direction within the octant quantised to 4 × 4 bins — so that a run of 8 rays in key order
/// starts close together and points alike. The bins are counted by compares, without a division.
#[must_use]
pub fn coherence_key(o: Vec3, d: Vec3, grid: &MortonGrid) -> u32 {
    let octant = u32::from(d.x < 0.0) | u32::from(d.y < 0.0) << 1 | u32::from(d.z < 0.0) << 2;
    let a = d.abs();
    let sum = a.element_sum().max(f32::MIN_POSITIVE);
    // ⌊4·a/sum⌋ capped at 3.
    let bin = |v: f32| u32::from(4.0 * v >= sum) + u32::from(4.0 * v >= 2.0 * sum) + u32::from(4.0 * v >= 3.0 * sum);
    let dir = bin(a.x) << 2 | bin(a.y);
    octant << 29 | grid.code(o) << 4 | dir
}

/// Traces `rays` in coherence-key order (packets of 8 that start close together and point
/// alike) and writes the results into `out` in the input order. The SIMD kernels' results do not
/// depend on the order (each lane's hit is the scalar twin's), so sorting changes speed only.
pub(crate) fn in_coherent_order<T: Copy + Default>(
    rays: &[RayQuery],
    bounds: (Vec3, Vec3),
    out: &mut [T],
    trace: impl FnOnce(&[RayQuery], &mut [T]),
) {
    let grid = MortonGrid::new(bounds, COHERENCE_CELLS);
    let mut order: Vec<(u32, u32)> =
        rays.iter().enumerate().map(|(i, r)| (coherence_key(r.origin, r.direction, &grid), i as u32)).collect();
    order.sort_unstable();
    let sorted: Vec<RayQuery> = order.iter().map(|&(_, i)| rays[i as usize]).collect();
    let mut traced = vec![T::default(); rays.len()];
    trace(&sorted, &mut traced);
    for (&(_, i), t) in order.iter().zip(traced) {
        out[i as usize] = t;
    }
}

impl CodePath {
    /// Closest hits of `rays` into `out` (in input order); the SIMD set traces them sorted for
    /// coherence.
    pub fn closest_coherent(
        self,
        bvh: &Bvh,
        tris: TriangleColumns<'_>,
        rays: &[RayQuery],
        bounds: (Vec3, Vec3),
        out: &mut [Option<Hit>],
    ) {
        match self {
            CodePath::Simd => in_coherent_order(rays, bounds, out, |r, o| packet::closest_packets(bvh, tris, r, o)),
            CodePath::Scalar => traverse::closest_rays(bvh, tris, rays, out),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Morton codes: the box's corners are the first and last cells, points outside go to the
    /// nearest cell and NaN to cell 0, and one cell's step along x, y or z is bit 0, 1 or 2.
    #[test]
    fn morton_codes_interleave_the_cells() {
        let grid = MortonGrid::new((Vec3::splat(-1.0), Vec3::new(3.0, 1.0, 1.0)), 1024);
        assert_eq!(grid.code(Vec3::splat(-1.0)), 0);
        assert_eq!(grid.code(Vec3::new(3.0, 1.0, 1.0)), (1 << 30) - 1);
        assert_eq!(grid.code(Vec3::splat(-7.0)), 0);
        assert_eq!(grid.code(Vec3::splat(9.0)), (1 << 30) - 1);
        assert_eq!(grid.code(Vec3::new(f32::NAN, f32::NAN, f32::NAN)), 0);
        // Cell sides: 4/1024 along x, 2/1024 along y and z; points at cell centres.
        let cell = |i: u32, j: u32, k: u32| {
            grid.code(Vec3::new(
                -1.0 + (i as f32 + 0.5) * 4.0 / 1024.0,
                -1.0 + (j as f32 + 0.5) * 2.0 / 1024.0,
                -1.0 + (k as f32 + 0.5) * 2.0 / 1024.0,
            ))
        };
        assert_eq!(cell(1, 0, 0), 1);
        assert_eq!(cell(0, 1, 0), 2);
        assert_eq!(cell(0, 0, 1), 4);
        assert_eq!(cell(3, 3, 3), 63);
        assert_eq!(cell(512, 0, 0), 1 << 27);
    }

    /// A ray's direction bins are ⌊4·|d|/Σ|d|⌋ capped at 3 per axis, counted by compares as the
    /// division would give them (directions away from the bins' edges, where the two may round
    /// apart); the octant is the direction's signs.
    #[test]
    fn coherence_keys_bin_directions_as_the_division_does() {
        let grid = MortonGrid::new((Vec3::ZERO, Vec3::ONE), COHERENCE_CELLS);
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        let mut checked = 0;
        for _ in 0..10_000 {
            let d = Vec3::new(rnd(), rnd(), rnd());
            let a = d.abs() / d.abs().element_sum();
            let near_edge = |v: f32| ((v * 4.0) - (v * 4.0).round()).abs() < 1e-4;
            if near_edge(a.x) || near_edge(a.y) {
                continue;
            }
            let bin = |v: f32| ((v * 4.0) as u32).min(3);
            let key = coherence_key(Vec3::splat(0.5), d, &grid);
            assert_eq!(key & 15, bin(a.x) << 2 | bin(a.y), "{d}");
            let octant = u32::from(d.x < 0.0) | u32::from(d.y < 0.0) << 1 | u32::from(d.z < 0.0) << 2;
            assert_eq!(key >> 29, octant, "{d}");
            checked += 1;
        }
        assert!(checked > 9_000, "{checked}");
        assert_eq!(coherence_key(Vec3::ZERO, Vec3::ZERO, &grid) & 15, 0);
    }
}
