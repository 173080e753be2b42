//! Which way the photons under each child of the tree face, so that a lookup skips the subtrees
//! whose photons its normal test would turn away to the last one: a floor's lookup then skips
//! the subtrees holding only the photons of the wall beside it, of the far face of a thin wall, or
//! of the underside of the tread above (a block that mixes them with its own is still read).
//! Reads the packed keys; writes each node's `classes` and a lookup's reachable classes.
//!
//! A stored normal is one of 64 × 64 octahedral codes. Each code belongs to one of 7 classes: the
//! six cones of half-angle 35° around ±x, ±y and ±z, where a room's surfaces lie, and the rest.
//! A node keeps, per child, a byte with the bits of the classes present below it. A lookup with
//! unit normal n reaches a cone only if the angle between n and the cone's axis is below
//! acos(0.7) + θ + a margin (θ the widest angle of the cone's codes from its axis): beyond it,
//! every normal in the cone is more than acos(0.7) from n, and the normal test
//! (n·m > 0.7·|m|, in `filter.rs`) turns it away. It always reaches the rest. A lookup whose
//! normal lies within 8° of an axis reaches its own cone and the rest: a floor skips the
//! subtrees of the walls', the ceiling's and the undersides' photons.
//!
//! Skipping is exact: the photons of a skipped child are all turned away, so every estimate keeps
//! the same photons, sums them in the same order and is the same to the bit; only the count of
//! photons turned away ([`super::Estimate::rejected`]) falls, as fewer are tested. Lookups that
//! read what the normal test turned away — a boundary-corrected estimate's edges and corners
//! ([`super::boundary`]) — walk every child ([`ALL`]).
//!
//! (26 classes — the cube's faces, edges and corners, 4 bytes per child in an array beside the
//! nodes — turned away as few photons on the Modern Hall, and cost cornell-spheres' default
//! render 2.8 % of its time, where a byte in the node costs nothing measurable.)

use super::packing::key_normal;
use super::PhotonMap;
use glam::Vec3;
use std::sync::OnceLock;

/// Every class: a walk that skips nothing.
pub const ALL: u8 = u8::MAX;

/// The class of normals in none of the cones: every lookup reaches it.
const REST: u8 = 6;

/// The cones' half-angle: the cosine of 35°.
const CONE_COS: f64 = 0.819_152_044_288_991_8;

/// How much wider than the normal test a cone's reach is, in radians: covers the f32 rounding of
/// the test and of the reach, and query normals up to 5·10⁻⁴ off unit length (a longer or
/// shorter normal is normalised as the test is not: the test's threshold moves by 5·10⁻⁴ of 0.7,
/// at most 5·10⁻⁴ rad of angle).
const MARGIN: f64 = 0.01;

/// The codes' classes and each cone's reach.
struct Classes {
    /// The class of each 12-bit normal code: 2·axis + (1 if it points down the axis), or [`REST`].
    of_code: [u8; 4096],
    /// A lookup with unit normal n reaches cone c when ±n[axis] exceeds this.
    threshold: [f32; 6],
}

/// The classes of the codes and the cones' reaches, computed once from the codes' decoded normals.
fn classes() -> &'static Classes {
    static TABLE: OnceLock<Classes> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut of_code = [REST; 4096];
        let mut half_angle = [0.0f64; 6];
        for (code, class) in of_code.iter_mut().enumerate() {
            let m = key_normal(code as u32).as_dvec3().normalize();
            let a = m.abs();
            let axis = if a.x >= a.y && a.x >= a.z {
                0
            } else if a.y >= a.z {
                1
            } else {
                2
            };
            if a[axis] >= CONE_COS {
                let c = 2 * axis + usize::from(m[axis] < 0.0);
                *class = c as u8;
                half_angle[c] = half_angle[c].max(a[axis].min(1.0).acos());
            }
        }
        let threshold = half_angle.map(|h| (0.7f64.acos() + h + MARGIN).cos() as f32);
        Classes { of_code, threshold }
    })
}

/// The class bit of a photon's key.
#[inline]
fn class_bit(key: u32) -> u8 {
    1 << classes().of_code[(key & 0xfff) as usize]
}

/// The classes a lookup with normal `n` reaches, as bits: those holding a normal its normal test
/// may keep. [`ALL`] for a normal that is not unit length to 5·10⁻⁴ (or not finite), whose test
/// this bound does not cover.
#[must_use]
pub fn reachable(n: Vec3) -> u8 {
    let len2 = n.length_squared();
    if !((len2 - 1.0).abs() <= 1e-3) {
        return ALL;
    }
    let n = n / len2.sqrt();
    let t = &classes().threshold;
    let mut bits = 1 << REST;
    for axis in 0..3 {
        bits |= u8::from(n[axis] > t[2 * axis]) << (2 * axis) | u8::from(-n[axis] > t[2 * axis + 1]) << (2 * axis + 1);
    }
    bits
}

/// The classes a walk for a lookup with normal `n` visits: [`reachable`], or [`ALL`] for a
/// boundary-corrected estimate (`corrected`), which reads the photons the normal test turns away
/// for its cuts.
#[must_use]
pub fn walked(n: Vec3, corrected: bool) -> u8 {
    if corrected {
        ALL
    } else {
        reachable(n)
    }
}

impl PhotonMap {
    /// Fills every node's `classes` from the photons' keys: a leaf's, the classes of its
    /// block; an inner child's, the union of its own children's. Children follow their parents
    /// in the node list, so one pass from the last node back fills them.
    pub(super) fn fill_classes(&mut self) {
        for index in (0..self.nodes.len()).rev() {
            let mut bytes = [0u8; 8];
            let node = &self.nodes[index];
            for (c, byte) in bytes.iter_mut().enumerate() {
                let child = node.child[c];
                *byte = if node.leaves & (1 << c) != 0 {
                    let (lo, hi) = self.block(child);
                    self.key[lo..hi].iter().fold(0, |b, &k| b | class_bit(k))
                } else if child != 0 {
                    debug_assert!(child as usize > index, "children follow their parents");
                    self.nodes[child as usize].classes.iter().fold(0, |b, &x| b | x)
                } else {
                    0 // an empty slot (node 0, the root, is no one's child)
                };
            }
            self.nodes[index].classes = bytes;
        }
    }

    /// Forgets which way the photons face: every walk then tests every photon within its radius.
    #[cfg(test)]
    pub(super) fn without_classes(mut self) -> Self {
        self.nodes.iter_mut().for_each(|n| n.classes = [ALL; 8]);
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Random unit normals (and a few off unit length by up to 4·10⁻⁴), and the axes, their
    /// diagonals and the normals of every code: for each, every code the normal test keeps lies
    /// in a reachable class.
    #[test]
    fn a_reachable_class_holds_every_code_the_normal_test_keeps() {
        let mut rnd = super::super::test_uniforms(2026);
        let mut normals: Vec<Vec3> = (0..3000)
            .map(|i| {
                let v = Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize();
                v * if i % 3 == 0 { 1.0 + (rnd() - 0.5) * 8e-4 } else { 1.0 }
            })
            .collect();
        normals.extend([Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z, Vec3::ONE.normalize()]);
        normals.extend((0..4096).step_by(7).map(|c| key_normal(c).normalize()));
        let mut kept = 0u64;
        for n in normals {
            let reach = reachable(n);
            assert_ne!(reach, ALL, "{n}");
            for code in 0..4096u32 {
                let m = key_normal(code);
                // The filter's normal test, as `PhotonMap::test` computes it.
                let dot = m.x * n.x + m.y * n.y + m.z * n.z;
                let len2 = m.x * m.x + m.y * m.y + m.z * m.z;
                if dot > 0.0 && dot * dot > 0.49 * len2 {
                    kept += 1;
                    assert_ne!(class_bit(code) & reach, 0, "normal {n}, code {code} ({m})");
                }
            }
        }
        assert!(kept > 1_000_000, "{kept}");
    }

    /// A floor's lookup reaches its own cone and the rest, not the walls', the ceiling's or the
    /// undersides'; a lookup tilted 8° still; a normal between two axes reaches both their cones.
    #[test]
    fn a_floor_reaches_its_own_cone_and_no_wall() {
        let floor = reachable(Vec3::Y);
        assert_eq!(floor, class_bit_of(Vec3::Y) | 1 << REST, "{floor:b}");
        let tilted = reachable(Vec3::new(8f32.to_radians().sin(), 8f32.to_radians().cos(), 0.0));
        assert_eq!(tilted, floor, "{tilted:b}");
        let ramp = reachable(Vec3::new(1.0, 1.0, 0.0).normalize());
        assert_ne!(class_bit_of(Vec3::X) & ramp, 0);
        assert_ne!(class_bit_of(Vec3::Y) & ramp, 0);
        assert_eq!(class_bit_of(Vec3::new(1.0, 1.0, 1.0).normalize()), 1 << REST);
        assert_eq!(reachable(Vec3::ZERO), ALL);
        assert_eq!(reachable(Vec3::splat(f32::NAN)), ALL);
    }

    fn class_bit_of(n: Vec3) -> u8 {
        class_bit(super::super::packing::pack_key(n, 0, Vec3::Y))
    }

    /// Photons of a room's hard places: a floor on both sides of a zero-thickness wall lit on one
    /// side; two walls back to back, 1 mm apart; a stair of 4 cm treads (tops, undersides and
    /// risers). Every lookup on every surface — k nearest, fixed radius with and without the
    /// boundary correction, curved and flat filters, in packets of 8, on both code paths — gives
    /// the same estimate to the bit with the classes as without them (every photon within the
    /// radius tested), and turns away no more photons; over all of them, fewer than a third (27 %:
    /// the rest lie in blocks shared with the lookup's own surface, where the walls 1 mm apart
    /// and the treads' two faces meet).
    #[test]
    fn skipping_classes_changes_no_estimate() {
        use super::super::boundary::Cut;
        use super::super::query_packet::RadiusQuery;
        use super::super::{Estimate, Filter, Kernel, Lookup, Nearest, Photon, Reflectance, OFF_PLANE};
        use crate::code_path::CodePath;
        let mut rnd = super::super::test_uniforms(44);
        // (a corner, two edge vectors, the normal) of each surface.
        let mut surfaces = vec![
            (Vec3::ZERO, Vec3::X * 2.0, Vec3::Z, Vec3::Y),               // the floor
            (Vec3::new(1.0, 0.0, 0.0), Vec3::Y, Vec3::Z, -Vec3::X),      // the thin wall, lit side
            (Vec3::new(0.0, 0.0, 0.0), Vec3::X * 2.0, Vec3::Y, Vec3::Z), // back to back: the room's
            (Vec3::new(0.0, 0.0, -0.001), Vec3::X * 2.0, Vec3::Y, -Vec3::Z), // and the next room's
        ];
        for i in 0..4 {
            let (x, y) = (1.2 + 0.2 * i as f32, 0.2 * (i + 1) as f32);
            surfaces.push((Vec3::new(x, y, 0.0), Vec3::X * 0.2, Vec3::Z, Vec3::Y));
            surfaces.push((Vec3::new(x, y - 0.04, 0.0), Vec3::X * 0.2, Vec3::Z, -Vec3::Y));
            surfaces.push((Vec3::new(x, y - 0.2, 0.0), Vec3::Y * 0.2, Vec3::Z, -Vec3::X));
        }
        let photons: Vec<Photon> = (0..24_000)
            .map(|i| {
                let (o, a, b, n) = surfaces[i % surfaces.len()];
                let wi = (n + Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5)).normalize();
                let power = Vec3::new(1.0, rnd(), rnd()) * 1e-3;
                Photon { position: o + a * rnd() + b * rnd(), power, wi, normal: n, flags: 0 }
            })
            .collect();
        let map = super::super::PhotonMap::build(photons);
        let all = map.clone().without_classes();
        let same = |a: &Estimate, b: &Estimate, what: &str| {
            assert_eq!(a.radiance.to_array().map(f32::to_bits), b.radiance.to_array().map(f32::to_bits), "{what}");
            assert_eq!((a.radius, a.count, a.off_plane), (b.radius, b.count, b.off_plane), "{what}");
            assert!(a.rejected <= b.rejected, "{what}: {} turned away against {}", a.rejected, b.rejected);
            (u64::from(a.rejected), u64::from(b.rejected))
        };
        let (mut pruned, mut full) = (0u64, 0u64);
        for set in [CodePath::Simd, CodePath::Scalar] {
            let (mut s1, mut s2) = (Nearest::default(), Nearest::default());
            for (j, &(o, a, b, n)) in surfaces.iter().enumerate() {
                let mut packet = Vec::new();
                for q in 0..8 {
                    let p = o + a * rnd() + b * rnd() + n * 1e-4 * (q % 2) as f32;
                    let plane = if q % 4 < 2 { 0.0 } else { OFF_PLANE };
                    let filter = Filter::at(p, n, 0).with_plane(plane);
                    let f = Reflectance::Hemisphere { value: Vec3::splat(0.3), ng: n };
                    let knn = Lookup { p, k: 32, r_max: 0.3, kernel: Kernel::Epanechnikov, filter };
                    let what = format!("{set:?}, surface {j}, lookup {q}");
                    let (x, y) =
                        same(&map.estimate(set, &knn, f, &mut s1), &all.estimate(set, &knn, f, &mut s2), &what);
                    (pruned, full) = (pruned + x, full + y);
                    let fixed = Lookup { k: 0, r_max: 0.12, ..knn };
                    let (x, y) =
                        same(&map.estimate_radius(set, &fixed, f), &all.estimate_radius(set, &fixed, f), &what);
                    (pruned, full) = (pruned + x, full + y);
                    let edges: &[Cut] = &[];
                    same(
                        &map.estimate_radius_on_surface(set, &fixed, f, edges),
                        &all.estimate_radius_on_surface(set, &fixed, f, edges),
                        &what,
                    );
                    packet.push(RadiusQuery { lookup: fixed, f, edges: (q % 3 == 0).then_some(edges) });
                }
                let (mut a8, mut b8) = ([Estimate::default(); 8], [Estimate::default(); 8]);
                map.estimate_radius_packet(set, &packet, true, &mut a8);
                all.estimate_radius_packet(set, &packet, true, &mut b8);
                for (q, (a, b)) in a8.iter().zip(&b8).enumerate() {
                    same(a, b, &format!("{set:?}, surface {j}, packet lookup {q}"));
                    assert_eq!(a.bias.to_array().map(f32::to_bits), b.bias.to_array().map(f32::to_bits));
                }
            }
        }
        assert!(full > 10_000 && 3 * pruned < full, "turned away: {pruned} with the classes, {full} without");
    }
}
