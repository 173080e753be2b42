//! Boundary correction of density estimates. A density estimate divides the photons' power by
//! the area of the kernel's disk, as if the whole disk lay on the query's surface. Near an edge
//! or in a corner — where a floor meets a wall, a box stands on the floor, a wall meets the
//! ceiling — part of the disk lies beyond the surface, the normal filter rightly turns the other
//! surface's photons away, and the estimate falls toward ½ at an edge and ¼ in a corner. The
//! radius shrinks only slowly in progressive passes (r ∝ N^(−1/6)), so this bias outlives the
//! noise: measured on CornellBox-Original, 256 progressive passes came out 0.8 % dark overall and
//! 3–8 % dark on the ceiling and around the boxes' feet, and the error scaled with the radius.
//!
//! The photons the normal filter turned away say where the other surfaces are. Each distinct
//! normal among them (up to [`MAX_PLANES`]) gives a plane through one of its photons; where that
//! plane meets the query's tangent plane, it cuts the disk. Above the query's plane the other
//! surface rises (a wall: the query's surface lies on the side the wall faces); below it the
//! surface falls away (a box's top edge: the query's surface lies on the side the face turns
//! from). The estimate is then divided by the kernel-weighted fraction of the disk on the valid
//! side of every cut ([`Neighbours::coverage`]), found by a fixed polar quadrature. For a uniform
//! density on a flat region this returns the interior value at an edge and in a corner (tested
//! in `tests/analytic.rs`). Planes nearly parallel to the query's (a thin wall's far side) cut
//! nothing and are ignored.
//!
//! Known limits. Each cut is a whole line, and the disk counts only where it is on the valid
//! side of every cut: right at a room's edges and corners, wrong beside an obstacle's outer
//! corner (the floor around a box's vertical edge), where ¾ of the disk is on the floor but ¼
//! is counted — up to 3× too bright in that small region. A surface that does not come down to
//! the query's plane (a table top above the floor) cuts it too. Limiting each cut to its
//! photons' extent fixes both in theory, but on CornellBox-Original it under-corrected the room's
//! edges (16×16-block error 1.1–1.4 % RMS against 0.85 % here; BENCHMARKS.md), so it is not done.

use super::packing::key_normal;
use super::{Kernel, PhotonMap};
use glam::Vec3;
use std::sync::OnceLock;
use wide::f32x8;

/// At most this many other surfaces per estimate (a corner has two, a box's foot corner three).
pub const MAX_PLANES: usize = 4;
/// At most this many cuts from the geometry per estimate.
pub const MAX_EXTRA_CUTS: usize = 4;
/// The correction never scales an estimate by more than 1 / this (a point with less of its disk
/// on its surface than this is left less corrected rather than amplified without bound).
pub const MIN_COVERAGE: f32 = 0.125;
/// Rings and angles of the polar quadrature over the unit disk.
const RINGS: usize = 8;
const ANGLES: usize = 32;

/// A cut known from the geometry rather than from photons (an open edge of the query's surface,
/// `scene::open_edges`): the disk is valid where `inward · (q − point) > 0`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Cut {
    /// A point on the cut line.
    pub point: Vec3,
    /// Unit direction in the query's plane, across the line, toward the valid side.
    pub inward: Vec3,
}

/// One other surface met by an estimate's normal filter.
#[derive(Clone, Copy, Debug, Default)]
struct Plane {
    /// The photons' stored normal (12 key bits): one per flat surface.
    key: u32,
    /// The photon nearest the query's tangent plane, and its height above it: the other surface
    /// meets the query's plane near this photon's foot. (Placing the cut with the stored normal
    /// instead would move it by height × the normal's 4° quantisation error.)
    low: (u32, f32),
    /// The signed height of the photon farthest from the query's plane: above (a wall rising) or
    /// below (a face falling away).
    high: f32,
}

/// The other surfaces an estimate's normal filter met, up to [`MAX_PLANES`].
#[derive(Clone, Copy, Debug, Default)]
pub struct Neighbours {
    planes: [Plane; MAX_PLANES],
    len: usize,
}

impl Neighbours {
    /// Notes photon `i`, turned away by the normal filter of a query at `p` with normal `n`.
    #[inline]
    pub(super) fn note(&mut self, map: &PhotonMap, i: usize, p: Vec3, n: Vec3) {
        let key = map.key[i] & 0xfff;
        let height = n.dot(map.position(i) - p);
        if let Some(plane) = self.planes[..self.len].iter_mut().find(|pl| pl.key == key) {
            if height.abs() < plane.low.1.abs() {
                plane.low = (i as u32, height);
            }
            if height.abs() > plane.high.abs() {
                plane.high = height;
            }
        } else if self.len < MAX_PLANES {
            self.planes[self.len] = Plane { key, low: (i as u32, height), high: height };
            self.len += 1;
        }
    }

    /// Whether photons with a normal opposite to `m` (within 25°) were met: the other face of the
    /// surface whose photons have normal `m`.
    fn faces_opposite(&self, map: &PhotonMap, m: Vec3) -> bool {
        self.planes[..self.len]
            .iter()
            .any(|pl| key_normal(map.key[pl.low.0 as usize]).normalize_or_zero().dot(m) < -0.9)
    }

    /// The part of the disk of radius² `r2` around `p` (normal `n`) that lies on the query's
    /// side of every noted surface and of every cut in `extra` ([`Coverage`]); the whole disk
    /// where nothing cuts it.
    #[must_use]
    pub fn coverage(&self, map: &PhotonMap, p: Vec3, n: Vec3, r2: f32, kernel: Kernel, extra: &[Cut]) -> Coverage {
        let r = r2.sqrt();
        if (self.len == 0 && extra.is_empty()) || !(r > 0.0) || !r.is_finite() {
            return Coverage::WHOLE;
        }
        let (t, b) = n.any_orthonormal_pair();
        // Each cut as a half-plane in disk units: valid where a·cosθ·ρ + b·sinθ·ρ + c > 0.
        let mut cuts = [(0.0f32, 0.0f32, 0.0f32); MAX_PLANES + MAX_EXTRA_CUTS];
        let mut count = 0;
        for cut in extra.iter().take(MAX_EXTRA_CUTS) {
            let (wt, wb) = (cut.inward.dot(t), cut.inward.dot(b));
            let tangential = (wt * wt + wb * wb).sqrt();
            let c = cut.inward.dot(p - cut.point) / r;
            if tangential < 0.2 || c >= tangential || c < -0.05 * tangential {
                continue;
            }
            cuts[count] = (wt, wb, c.max(0.0));
            count += 1;
        }
        for plane in &self.planes[..self.len] {
            let (i, low) = (plane.low.0 as usize, plane.low.1);
            let m = key_normal(map.key[i]).normalize_or_zero();
            let (mt, mb) = (m.dot(t), m.dot(b));
            let tangential = (mt * mt + mb * mb).sqrt();
            // Nearly parallel planes (a thin wall's far side) meet the disk nowhere; witnesses
            // all in the query's own plane cannot tell the side.
            if tangential < 0.2 || plane.high.abs() < 1e-4 * r {
                continue;
            }
            // The cut passes through the foot of the lowest witness, across m's tangential part.
            // Rising surface: valid where m·(q − foot) > 0; falling: < 0.
            let foot = map.position(i) - n * low;
            let side = if plane.high > 0.0 { 1.0 } else { -1.0 };
            let c = side * m.dot(p - foot) / r;
            // A line at distance ≥ r cuts nothing. A query on the line is half covered (rounding
            // may put it a hair beyond); one clearly beyond it sees an inconsistent plane (not a
            // flat surface meeting its own), which cuts nothing. Nor does one beyond it at all
            // when photons with the opposite normal were met too: the far face of a zero-thickness
            // surface lit from both sides (a room's wall under a sun), whose near face, met as
            // well, makes the cut. (It used to halve the disk of points within 0.05 r of such a
            // wall: the daylit room's corners.)
            if c >= tangential || c < -0.05 * tangential || (c < 0.0 && self.faces_opposite(map, m)) {
                continue;
            }
            let c = c.max(0.0);
            cuts[count] = (side * mt, side * mb, c);
            count += 1;
        }
        if count == 0 {
            return Coverage::WHOLE;
        }
        // The quadrature 8 points at a time: a point counts where it is inside every cut.
        let table = quadrature(kernel);
        let (mut inside, mut bias) = (f32x8::ZERO, f32x8::ZERO);
        for k in 0..RINGS * ANGLES / 8 {
            let (x, y) = (f32x8::from(table.x[k]), f32x8::from(table.y[k]));
            let mut valid = f32x8::splat(f32::from_bits(u32::MAX));
            for &(ca, cb, cc) in &cuts[..count] {
                valid &= (f32x8::splat(ca) * x + f32x8::splat(cb) * y + f32x8::splat(cc)).simd_gt(f32x8::ZERO);
            }
            inside += valid.select(f32x8::from(table.weight[k]), f32x8::ZERO);
            bias += valid.select(f32x8::from(table.bias_weight[k]), f32x8::ZERO);
        }
        let (inside, bias, total) = (inside.reduce_add(), bias.reduce_add(), table.total);
        Coverage { fraction: (inside / total).max(MIN_COVERAGE), bias_weight: bias / total }
    }
}

/// How much of an estimate's disk lies on the query's surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coverage {
    /// The kernel-weighted fraction, at least [`MIN_COVERAGE`]: the estimate is divided by it.
    pub fraction: f32,
    /// ∫ [`Kernel::bias_weight`] dA over the covered part over ∫ kernel weight dA over the whole
    /// disk: 0 for the whole disk, where a uniform density gives a bias sum of 0; elsewhere the
    /// bias sum of a uniform density is this × the kernel sum / `fraction`, which the bias
    /// estimate subtracts so that a cut disk does not read as curvature.
    pub bias_weight: f32,
}

impl Coverage {
    /// The whole disk.
    pub const WHOLE: Coverage = Coverage { fraction: 1.0, bias_weight: 0.0 };
}

/// The kernel-weighted share of the disk of radius `r` around `p` (in the plane of normal `n`)
/// where the surface is present, `present` giving the presence (0 to 1) at a point of the disk:
/// what an estimate on a cut-out surface ([`crate::material::Opacity`]) is divided by, since its
/// photons land only on the present parts. At least [`MIN_COVERAGE`], as [`Coverage::fraction`].
#[must_use]
pub fn presence_share(p: Vec3, n: Vec3, r: f32, kernel: Kernel, present: impl Fn(Vec3) -> f32) -> f32 {
    if !(r > 0.0) || !r.is_finite() {
        return 1.0;
    }
    let (t, b) = n.any_orthonormal_pair();
    let table = quadrature(kernel);
    let mut inside = 0.0f32;
    for k in 0..RINGS * ANGLES {
        let (row, lane) = (k / 8, k % 8);
        let q = p + (t * table.x[row][lane] + b * table.y[row][lane]) * r;
        inside += table.weight[row][lane] * present(q);
    }
    (inside / table.total).clamp(MIN_COVERAGE, 1.0)
}

/// The quadrature's points in rows of 8 (x, y, kernel weight, bias weight), and the sum of the
/// kernel weights.
struct Quadrature {
    x: [[f32; 8]; RINGS * ANGLES / 8],
    y: [[f32; 8]; RINGS * ANGLES / 8],
    weight: [[f32; 8]; RINGS * ANGLES / 8],
    bias_weight: [[f32; 8]; RINGS * ANGLES / 8],
    total: f32,
}

/// The polar quadrature of `kernel` over the unit disk: points (x, y) at ring midpoints and
/// evenly spaced angles, each weighted by its cell's exact integral of the kernel weight and of
/// [`Kernel::bias_weight`] (ρ dρ dθ): over the whole disk the sums are exact, so a whole disk
/// has a bias sum of 0 (a midpoint rule was off by 0.8 % of the kernel's sum there).
fn quadrature(kernel: Kernel) -> &'static Quadrature {
    static TABLES: [OnceLock<Quadrature>; 3] = [OnceLock::new(), OnceLock::new(), OnceLock::new()];
    let slot = match kernel {
        Kernel::Box => 0,
        Kernel::Cone => 1,
        Kernel::Epanechnikov => 2,
    };
    // ∫ₐᵇ w(ρ)·ρ dρ for each weight, from their antiderivatives.
    let kernel_part = |rho: f64| match kernel {
        Kernel::Box => rho * rho / 2.0,
        Kernel::Cone => rho * rho / 2.0 - rho.powi(3) / 3.0,
        Kernel::Epanechnikov => rho * rho / 2.0 - rho.powi(4) / 4.0,
    };
    // Kernel::bias_weight = 2ρ² − 1.
    let bias_part = |rho: f64| rho.powi(4) / 2.0 - rho * rho / 2.0;
    TABLES[slot].get_or_init(|| {
        let mut q = Quadrature {
            x: [[0.0; 8]; RINGS * ANGLES / 8],
            y: [[0.0; 8]; RINGS * ANGLES / 8],
            weight: [[0.0; 8]; RINGS * ANGLES / 8],
            bias_weight: [[0.0; 8]; RINGS * ANGLES / 8],
            total: 0.0,
        };
        for k in 0..RINGS * ANGLES {
            let (ring, angle) = (k / ANGLES, k % ANGLES);
            let (a, b) = (ring as f64 / RINGS as f64, (ring + 1) as f64 / RINGS as f64);
            let rho = ((a + b) / 2.0) as f32;
            let theta = (angle as f32 + 0.5) * std::f32::consts::TAU / ANGLES as f32;
            let (row, lane) = (k / 8, k % 8);
            q.x[row][lane] = rho * theta.cos();
            q.y[row][lane] = rho * theta.sin();
            q.weight[row][lane] = (kernel_part(b) - kernel_part(a)) as f32;
            q.bias_weight[row][lane] = (bias_part(b) - bias_part(a)) as f32;
            q.total += q.weight[row][lane];
        }
        q
    })
}
