//! Where the camera's estimates read a photon map: cells of a uniform grid, each on one side (a
//! signed axis of the surface normal), marked around the points a pilot of camera paths reads
//! the map at. A photon "is read" when its cell, on the side it arrived from, is marked.
//!
//! It reads points and normals and writes a set of cell keys; the photon pass reads it to count
//! the photons stored where the camera looks ([`ReadCells::reads`]), and the guide of photon
//! emission to weigh the lights by the power they bring there (Peter and Pietrek 1998 guide
//! emission by importance in the same spirit, with importons instead of cells).
//!
//! A query point at `q` reads photons within the map's largest radius `r` of `q` whose normal
//! agrees with its own. Cells are `r` wide and a query marks the 3×3×3 block around its own, so
//! every photon within `r` of a marked query lies in a marked cell. The side is the signed axis
//! of the normal's largest component for a photon; a query marks every signed axis its normal
//! leans along by at least [`SIDE_LEAN`], so a photon whose normal is near the query's (the
//! photon maps' normal filter) falls on a marked side. The two faces of a zero-thickness wall
//! share their cells but not their sides: light on the outside of a room is not read inside.
//!
//! The estimates also set aside photons off the query's plane (by more than
//! [`super::OFF_PLANE`] of their distance), so a parallel surface just behind — a floor 1 cm
//! above the ground outside — is not read either. A query whose normal lies along its axis
//! (within [`ALONG_AXIS`]) marks only a thin slab of its cells along that axis, [`SLAB`] fine
//! layers of `r`/[`LAYERS`] each way; any other marks its cells whole.
//!
//! The marks come from a sample of the camera's paths, so they are a guide, not a proof: no
//! estimate depends on them, only how many paths are emitted and which lights emit them.

use crate::sampling::Distribution1D;
use glam::Vec3;
use std::collections::HashSet;
use std::hash::{BuildHasherDefault, Hasher};

/// A query marks every signed axis along which its normal has at least this component (a
/// unit normal has one of at least 1/√3 ≈ 0.58, the side a photon on the same plane falls on).
pub const SIDE_LEAN: f32 = 0.3;

/// A query whose normal has at least this component along an axis (2.6° from it) marks a slab.
pub const ALONG_AXIS: f32 = 0.999;

/// Fine layers per cell along the normal's axis.
pub const LAYERS: i64 = 256;

/// Fine layers a slab spans each way from its query's: 2 to 3 of 256 per cell width, 0.8 to
/// 1.2 % of `r`, the off-plane slab at about two thirds of the largest radius.
pub const SLAB: i64 = 2;

/// The marked cells of one map.
#[derive(Clone, Debug, Default)]
pub struct ReadCells {
    /// The grid's corner.
    origin: Vec3,
    /// One over the cell width.
    inv_width: f32,
    /// Marked keys ([`key`]): cells marked whole, and fine layers along a side's axis.
    marked: HashSet<u128, BuildHasherDefault<MixHasher>>,
    /// The queries' own fine cells with the sides they marked: a query whose fine cell and sides
    /// another marked already marks nothing new.
    seen: HashSet<u128, BuildHasherDefault<MixHasher>>,
}

impl ReadCells {
    /// An empty set of cells `width` wide, with their corner at `origin`.
    #[must_use]
    pub fn new(origin: Vec3, width: f32) -> Self {
        ReadCells {
            origin,
            inv_width: 1.0 / width.max(f32::MIN_POSITIVE),
            marked: HashSet::default(),
            seen: HashSet::default(),
        }
    }

    /// Marked keys (cells whole and fine layers, each side counted).
    #[must_use]
    pub fn len(&self) -> usize {
        self.marked.len()
    }

    /// Whether nothing is marked (the pilot's camera paths found no surface reading the map).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.marked.is_empty()
    }

    /// Marks the cells around a query at `p` whose surface faces `normal` (unit, on the side the
    /// query reads).
    pub fn mark(&mut self, p: Vec3, normal: Vec3) {
        let Some(fine) = self.fine(p) else { return };
        let mask = (0..6u64).filter(|&side| lean(normal, side) >= SIDE_LEAN).fold(0u64, |m, s| m | 1 << s);
        let slab = normal.abs().max_element() >= ALONG_AXIS;
        let c = fine.map(|f| f.div_euclid(LAYERS));
        let own = if slab { key(fine, 64 | mask, false) } else { key(c, mask, true) };
        if !self.seen.insert(own) {
            return;
        }
        for side in (0..6u64).filter(|s| mask >> s & 1 == 1) {
            let axis = (side / 2) as usize;
            for d in neighbours() {
                let mut cell = [c[0] + d[0], c[1] + d[1], c[2] + d[2]];
                if slab {
                    if d[axis] != 0 {
                        continue;
                    }
                    for layer in -SLAB..=SLAB {
                        cell[axis] = fine[axis] + layer;
                        self.marked.insert(key(cell, side, false));
                    }
                } else {
                    self.marked.insert(key(cell, side, true));
                }
            }
        }
    }

    /// Whether a photon at `p` that arrived on the side of `normal` lies where a query reads.
    #[must_use]
    pub fn reads(&self, p: Vec3, normal: Vec3) -> bool {
        let Some(fine) = self.fine(p) else { return false };
        let side = dominant_side(normal);
        let mut cell = fine.map(|f| f.div_euclid(LAYERS));
        if self.marked.contains(&key(cell, side, true)) {
            return true;
        }
        let axis = (side / 2) as usize;
        cell[axis] = fine[axis];
        self.marked.contains(&key(cell, side, false))
    }

    /// The fine cell of `p`, [`LAYERS`] per cell on every axis (`None` for a point that is not
    /// finite or lies outside the keys' range).
    fn fine(&self, p: Vec3) -> Option<[i64; 3]> {
        let g = (p - self.origin) * (self.inv_width * LAYERS as f32);
        let ok = g.is_finite() && g.abs().max_element() < 5.0e11;
        ok.then(|| [g.x.floor() as i64, g.y.floor() as i64, g.z.floor() as i64])
    }
}

/// The 27 offsets of a 3×3×3 block.
fn neighbours() -> impl Iterator<Item = [i64; 3]> {
    (0..27).map(|k| [k % 3 - 1, k / 3 % 3 - 1, k / 9 - 1])
}

/// The key of `cell` on `side`: whole (coarse coordinates) or a fine layer (the side's axis in
/// fine layers, the others coarse). 40 bits per coordinate, wrapping.
fn key(cell: [i64; 3], side: u64, whole: bool) -> u128 {
    let c = |v: i64| u128::from(v as u64 & ((1 << 40) - 1));
    c(cell[0]) | c(cell[1]) << 40 | c(cell[2]) << 80 | u128::from(side) << 120 | u128::from(whole) << 127
}

/// How one map's photons are guided: where the camera reads the map, and the lights' photon
/// distribution (`None`: by power).
#[derive(Clone, Debug, Default)]
pub struct MapGuide {
    /// Where the camera's estimates read the map.
    pub cells: ReadCells,
    /// The probability of each light (the scene's order) as a photon's source.
    pub lights: Option<Distribution1D>,
}

/// The guide of a render's photon passes, made once per render from its pilot.
#[derive(Clone, Debug, Default)]
pub struct PhotonGuide {
    /// The global map's.
    pub global: MapGuide,
    /// The caustic map's.
    pub caustic: MapGuide,
    /// What the pilot found and how long it took, in a line for `--stats`.
    pub summary: String,
}

/// The component of `n` along signed axis `side` (0: +x, 1: −x, 2: +y, …).
fn lean(n: Vec3, side: u64) -> f32 {
    let c = n[(side / 2) as usize];
    if side.is_multiple_of(2) {
        c
    } else {
        -c
    }
}

/// The signed axis of `n`'s largest component.
fn dominant_side(n: Vec3) -> u64 {
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    axis * 2 + u64::from(n[axis as usize] < 0.0)
}

/// A hasher for keys that are already well spread in their low bits but not their high ones: one
/// multiply-xorshift round (splitmix64's finaliser).
#[derive(Default)]
pub struct MixHasher(u64);

impl Hasher for MixHasher {
    fn finish(&self) -> u64 {
        let mut z = self.0.wrapping_mul(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z ^ (z >> 27)
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = self.0.rotate_left(8) ^ u64::from(b);
        }
    }

    fn write_u64(&mut self, v: u64) {
        self.0 = self.0.rotate_left(29) ^ v;
    }

    fn write_u128(&mut self, v: u128) {
        self.write_u64(v as u64);
        self.0 = self.finish();
        self.write_u64((v >> 64) as u64);
    }
}

#[cfg(test)]
mod tests {
    use super::ReadCells;
    use glam::Vec3;

    #[test]
    fn a_query_reads_photons_within_a_cell_on_its_side_only() {
        let mut cells = ReadCells::new(Vec3::ZERO, 0.1);
        cells.mark(Vec3::new(0.5, 0.5, 0.5), Vec3::Y);
        // Within one cell width, on the same side: read.
        assert!(cells.reads(Vec3::new(0.59, 0.5, 0.41), Vec3::Y));
        assert!(cells.reads(Vec3::new(0.5, 0.5, 0.5), Vec3::new(0.3, 0.9, 0.0).normalize()));
        // The other face of a zero-thickness wall: not read.
        assert!(!cells.reads(Vec3::new(0.5, 0.5, 0.5), -Vec3::Y));
        // A parallel plane a hundredth of a cell below (a floor over the ground outside): not
        // read; a photon a fine layer off the query's plane is.
        assert!(!cells.reads(Vec3::new(0.5, 0.499, 0.5), Vec3::Y));
        assert!(cells.reads(Vec3::new(0.5, 0.4996, 0.5), Vec3::Y));
        // Two cells away: not read.
        assert!(!cells.reads(Vec3::new(0.75, 0.5, 0.5), Vec3::Y));
        // Outside the grid or not finite: not read, no panic.
        assert!(!cells.reads(Vec3::new(-5.0, 0.5, 0.5), Vec3::Y));
        assert!(!cells.reads(Vec3::NAN, Vec3::Y));
    }

    #[test]
    fn a_leaning_normal_marks_every_side_it_leans_along() {
        let mut cells = ReadCells::new(Vec3::ZERO, 1.0);
        let n = Vec3::new(1.0, 1.0, 0.0).normalize();
        cells.mark(Vec3::splat(3.5), n);
        assert!(cells.reads(Vec3::splat(3.5), Vec3::X));
        assert!(cells.reads(Vec3::splat(3.5), Vec3::Y));
        assert!(!cells.reads(Vec3::splat(3.5), Vec3::Z));
        // Two sides, 27 cells each.
        assert_eq!(cells.len(), 54);
    }
}
