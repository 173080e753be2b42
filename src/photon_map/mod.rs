//! Photon maps (Jensen 1996): photons in blocks of 8 under an 8-wide bounding-volume hierarchy,
//! k-nearest search under a maximum radius, every photon within a fixed radius, and the kernel
//! density estimate of reflected radiance.
//!
//! The estimate uses the (k−1)/(πr²) form: when the search fills k photons, r is the distance
//! to the k-th and only the k−1 strictly inside are summed — unbiased for a uniform density,
//! where k/(πr²) overestimates by k/(k−1). When fewer than k lie within the maximum radius, all of
//! them are summed over the maximum radius (a fixed-radius estimate, also unbiased).
//!
//! Layout: 20 bytes a photon (Jensen's own record was 20 B), five 4-byte columns in tree order —
//! every subtree is a contiguous range of whole blocks, so spatial neighbours are contiguous and
//! a block loads into one `f32x8` per column:
//! - `x`, `y`, `z`: position, f32 (exact);
//! - `key`: surface normal (octahedral, 6 + 6 bits), flags (2 bits), 2 spare bits, incoming
//!   direction (octahedral, 8 + 8 bits);
//! - `power`: RGBE (Ward's shared exponent, as Jensen stored it).
//!
//! The tree's nodes add [`PhotonMap::tree_bytes_per_photon`] (4.2 B: a 236-byte node per 7
//! blocks or so; 4.1 B measured before the nodes kept their children's direction classes).
//!
//! Error bounds of the packing: power per channel within 2⁻⁷ of the largest channel (dithered,
//! so unbiased even when all photons carry one power); incoming direction within 1° (octahedral
//! step 2/254; 0.95° measured over 4·10⁵ random directions); normal within 4° (step 2/62; 3.9°
//! measured), against a filter threshold of 45°. A lookup tests every block whose box its sphere
//! reaches and that holds photons facing its way ([`orientation`]) — 8 photons at a time by the
//! SIMD kernels, one at a time by their scalar twins, with the same arithmetic in the same order,
//! so both find the same photons.
//!
//! Files: [`kernel`] (the density kernels), `packing` (key and RGBE codecs), `tree` (build and
//! walk), `filter` (which photons a lookup may use), [`nearest`] (the k-nearest search, by
//! counting), [`knn`] (k-nearest lookups and estimates),
//! [`radius`] (fixed-radius estimates), [`query_packet`] (up to 8 fixed-radius estimates sharing
//! one walk), `sum` (the kernel sums), [`orientation`] (which way each subtree's photons face,
//! so that lookups skip those their normal test would turn away); each SIMD kernel beside its
//! scalar twin.

pub mod boundary;
mod candidates;
mod filter;
pub mod kernel;
pub mod knn;
pub mod nearest;
pub mod orientation;
mod packing;
pub mod query_packet;
pub mod radius;
pub mod reach;
mod sum;
mod tree;

pub use kernel::Kernel;
pub use nearest::Nearest;

use glam::Vec3;
use packing::{dither, key_flags, key_normal, key_wi, pack_key, rgbe_decode, rgbe_encode};
use tree::build_tree;

/// Flags on a stored photon.
pub mod flags {
    /// Stored at the first surface hit after leaving the light (direct illumination).
    pub const DIRECT: u8 = 1;
    /// Every bounce before this hit was specular (mirror/glass): an `LS+D` caustic photon.
    pub const CAUSTIC: u8 = 2;
    /// Photons whose light the direct and caustic terms compute on their own: masked wherever
    /// the global map stands for indirect light only.
    pub const OWN_TERMS: u8 = DIRECT | CAUSTIC;
    /// Stored on a flat-shaded triangle: an estimate at it (an irradiance point precomputed
    /// there) sets photons off its plane aside ([`super::Filter::plane`]). Never masked.
    pub const FLAT: u8 = 4;
    /// Stored in the medium filling the scene, not on a surface: set by the photon passes on
    /// the photons of the volume maps, and cleared when [`crate::transport::PhotonMaps::build`]
    /// sorts them there; never in a tree.
    pub const VOLUME: u8 = 8;
    /// The normal a volume photon is stored with (it has none): every volume lookup's filter
    /// ([`super::Filter::volume`]) faces it.
    pub const VOLUME_NORMAL: glam::Vec3 = glam::Vec3::Z;
}

/// A stored photon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    /// Where it landed.
    pub position: Vec3,
    /// Power it carries (W per channel).
    pub power: Vec3,
    /// Unit direction back toward where it came from.
    pub wi: Vec3,
    /// Geometric normal of the surface it landed on, on the side it arrived from.
    pub normal: Vec3,
    /// [`flags`] bits.
    pub flags: u8,
}

/// Padding after the last photon so that 8-wide loads of the last block stay in bounds (positions
/// +∞: never within any radius).
const PAD: usize = 8;

/// Photons in blocks of 8 under an 8-wide bounding-volume hierarchy.
#[derive(Clone, Debug, Default)]
pub struct PhotonMap {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    /// Normal, flags, incoming direction (see the module notes).
    key: Vec<u32>,
    /// RGBE power.
    power: Vec<u32>,
    /// Photons (without padding).
    len: usize,
    /// The tree over the photons' blocks (`tree`).
    nodes: Vec<tree::Node>,
}

/// The result of a density estimate, with its search radius (for diagnostics).
#[derive(Clone, Copy, Debug)]
pub struct Estimate {
    /// Reflected radiance.
    pub radiance: Vec3,
    /// Radius the estimate used.
    pub radius: f32,
    /// Fixed-radius estimates: the estimated bias of `radiance`, E[L̂] − L ≈ ½·μ₂·r²·ΔL, from
    /// the same photons ([`Kernel::bias_normalisation`]); zero for k-nearest estimates.
    pub bias: Vec3,
    /// Photons summed.
    pub count: u32,
    /// Photons within the search radius (a k-nearest lookup's: strictly nearer than the k-th)
    /// that the surface tests of the [`Filter`] turned away: another surface's photons, around
    /// a corner, through a thin wall or off a parallel surface. Only photons the walk tested
    /// count: it skips the subtrees whose photons all face away from the query ([`orientation`]),
    /// unless the estimate is boundary-corrected or looks for the nearest photon alone (k = 1).
    pub rejected: u32,
    /// Photons within the search radius set aside off a flat query's plane ([`Filter::plane`]):
    /// not in this estimate, which the caller completes with those of them that are visible.
    pub off_plane: u32,
    /// The part of the disk the estimate was divided by (the boundary correction's coverage; 1
    /// where it is not corrected): what photons added afterward are divided by too.
    pub coverage: f32,
}

impl Default for Estimate {
    /// Nothing found: zero radiance over the whole disk.
    fn default() -> Self {
        Estimate {
            radiance: Vec3::ZERO,
            radius: 0.0,
            bias: Vec3::ZERO,
            count: 0,
            rejected: 0,
            off_plane: 0,
            coverage: 1.0,
        }
    }
}

/// How far off the query's surface a photon may lie, as a fraction of its distance from the
/// query: the filter turns away a photon at `x` with unit normal `m` (the stored one) whose
/// offset from the query's surface, `|(x − p)·(n + m)| / 2`, exceeds this times `|x − p|`.
///
/// The offset is the mid-plane one: for two points on a sphere or a cylinder through both,
/// whatever its radius, `(x − p)·(n + m)` is exactly 0 (each point lies as far below the other's
/// tangent plane), so curved surfaces keep all their photons; for a parallel surface at height
/// `h` it is `2h`, so that surface's photons within `≈ 6.6 h` of the query are turned away — a
/// floor 1 cm above a sunlit ground or the far side of a room lies off the query's surface
/// however large the radius. (A flat-shaded point makes the plane test of [`Filter::plane`]
/// instead.) What it must
/// tolerate: the stored normals' quantisation (at most 3.9°: an offset of 0.034 of the
/// distance on a flat surface) and a tessellated surface's facets (about a quarter of the
/// angle between neighbouring facets: 0.13 for a 12-sided cylinder). Across a crease sharper
/// than about 17° some of the other face's photons are turned away, and the boundary correction
/// reads them as the other surface they are.
pub const SURFACE_OFFSET: f32 = 0.15;

/// What a [`Filter`] made of one photon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Test {
    Accepted,
    /// Carries a masked flag.
    Flags,
    /// Lies on another surface: one facing another way, or off the query's (the filter's
    /// surface test, [`SURFACE_OFFSET`]).
    Normal,
    /// Passes every test but lies off the plane of a flat query ([`Filter::plane`]): a parallel
    /// surface's photon, or a neighbouring face's across a gentle crease; the caller decides by
    /// visibility.
    OffPlane,
}

/// Which photons a lookup may use: those on the query's own surface — whose surface normal lies
/// within ~45° of `n` (no leaks around corners or through zero-thickness walls) and that lie
/// on it rather than on a parallel surface off it (a floor thinner than the search radius, the
/// far side of a room: [`SURFACE_OFFSET`]) — and that carry none of the `flags_mask`
/// flags.
#[derive(Clone, Copy, Debug)]
pub struct Filter {
    /// The query's geometric normal, on the side the light is reflected to.
    pub n: Vec3,
    /// Photons with any of these [`flags`] are skipped.
    pub flags_mask: u8,
    /// For a query on a flat surface (a flat-shaded triangle), whose own photons lie in its
    /// plane: a photon behind that plane by more than this fraction of its distance is set aside
    /// ([`Estimate::off_plane`]) for the caller to keep only if visible — a floor 1 cm above a
    /// sunlit ground is thinner than any normal test can see at the radius. Light that leaks
    /// through a surface comes from behind it; photons in front of the plane (a gentle rise, a
    /// lamp's shade just below the ceiling) are kept as before, at no cost: on CornellBox-Mirror
    /// testing those too traced rays for most estimates on the ceiling near the light, 1 cm
    /// below it.
    /// [`OFF_PLANE`] where `n` is the exact geometric normal, [`OFF_PLANE_QUANTISED`] where it is
    /// a stored photon's; 0 for a curved query (no such test).
    pub plane: f32,
    /// An absolute height, in scene units, that the plane and offset tests allow whatever a
    /// photon's distance: the rounding of the query's position and of a photon's beside it
    /// ([`position_slack`]). Both tests are relative to the distance, and a point is only known to
    /// a few ulps of its coordinates: 30 000 units from the origin an ulp is 0.002, and photons a
    /// few centimetres from the query, on its own floor, lay "off" it by their rounding (the
    /// Cornell box moved there turned away 300 times the photons and its indirect layer lost
    /// 11 %). 0 tests the distance alone.
    pub slack: f32,
}

/// [`Filter::slack`] for a query at `p` with normal `n`: twice the error bound of a point
/// interpolated on a triangle, γ₇·|p| per axis (the query's and a nearby photon's), along `n`.
/// Relative to the coordinates, so a scene moved far from the origin keeps its photons, and
/// negligible near it (8·10⁻⁷ one unit out; a photon within 10⁻⁴ of the query is the first
/// whose verdict it could change).
#[inline]
#[must_use]
pub fn position_slack(p: Vec3, n: Vec3) -> f32 {
    2.0 * crate::geometry::gamma(7) * n.abs().dot(p.abs())
}

impl Filter {
    /// The surface tests of a query at `p` with normal `n` (no plane test), skipping photons
    /// with any of `flags_mask`.
    #[inline]
    #[must_use]
    pub fn at(p: Vec3, n: Vec3, flags_mask: u8) -> Filter {
        Filter { n, flags_mask, plane: 0.0, slack: position_slack(p, n) }
    }

    /// The filter of a lookup in a volume map: every photon within the radius that carries
    /// none of `flags_mask`. Volume photons are stored with [`flags::VOLUME_NORMAL`], which this
    /// filter's normal is, so the normal test passes them all; and its plane test can set none
    /// aside — a photon's height is at most its distance, and the bound is twice that.
    #[inline]
    #[must_use]
    pub fn volume(flags_mask: u8) -> Filter {
        Filter { n: flags::VOLUME_NORMAL, flags_mask, plane: 2.0, slack: 0.0 }
    }

    /// This filter with the plane test of a flat query ([`Filter::plane`]).
    #[inline]
    #[must_use]
    pub fn with_plane(self, plane: f32) -> Filter {
        Filter { plane, ..self }
    }
}

/// [`Filter::plane`] for a query with its exact geometric normal: 0.015, the sine of 0.86°. The
/// plane holds the query's own photons to rounding; this lets pass the photons across a crease
/// gentler than 0.86° — a measured quad that is not quite flat, split into two triangles, as the
/// faces of McGuire's Cornell boxes are (0.7°): at 10⁻³ each estimate near such a diagonal set
/// photons aside and traced their visibility, and the estimates of CornellBox-Mirror took 60 %
/// longer. The price: a parallel surface h behind is set aside only within 67 h (a 1 cm floor:
/// within 67 cm), so a disk wider than that still reads it at its rim.
pub const OFF_PLANE: f32 = 0.015;

/// [`Filter::plane`] for a query at a stored photon (a precomputed irradiance point), whose
/// normal is quantised by up to 3.9°: the sine of 4°. A parallel surface is then set aside only
/// within 14 of its heights (1 cm below: within 14 cm); the offset test turns it away within 6.6.
pub const OFF_PLANE_QUANTISED: f32 = 0.07;

/// One density lookup: where, how many photons, how far, which kernel, which photons.
#[derive(Clone, Copy, Debug)]
pub struct Lookup {
    /// Query point.
    pub p: Vec3,
    /// k nearest (k-NN lookups).
    pub k: usize,
    /// Maximum (k-NN) or fixed (radius lookups) search radius.
    pub r_max: f32,
    /// Density kernel.
    pub kernel: Kernel,
    /// Photon filter.
    pub filter: Filter,
}

/// The BSDF seen by the estimate, per photon direction.
#[derive(Clone, Copy)]
pub enum Reflectance<'a> {
    /// The same value for every photon (irradiance: 1).
    Constant(Vec3),
    /// `value` for photons arriving from above `ng`, 0 below (Lambertian).
    Hemisphere {
        /// f for directions above the surface.
        value: Vec3,
        /// The surface's geometric normal on the side of wo.
        ng: Vec3,
    },
    /// Any BSDF, evaluated per photon direction.
    PerPhoton(&'a dyn Fn(Vec3) -> Vec3),
}

impl PhotonMap {
    /// Builds the tree (takes ownership, reorders) and packs the photons.
    #[must_use]
    pub fn build(photons: Vec<Photon>) -> Self {
        Self::build_on(photons, 1)
    }

    /// [`Self::build`] on `threads` threads (the root's subtrees at once, for large maps): the
    /// same map at any thread count.
    #[must_use]
    pub fn build_on(mut photons: Vec<Photon>, threads: usize) -> Self {
        let n = photons.len();
        let nodes = build_tree(&mut photons, threads);
        let inf = f32::INFINITY;
        let col = |f: &dyn Fn(&Photon) -> f32| {
            photons.iter().map(f).chain(std::iter::repeat_n(inf, PAD)).collect::<Vec<f32>>()
        };
        let mut map = PhotonMap {
            x: col(&|p| p.position.x),
            y: col(&|p| p.position.y),
            z: col(&|p| p.position.z),
            key: photons.iter().map(|p| pack_key(p.normal, p.flags, p.wi)).chain(std::iter::repeat_n(0, PAD)).collect(),
            power: photons
                .iter()
                .enumerate()
                .map(|(i, p)| rgbe_encode(p.power, dither(i)))
                .chain(std::iter::repeat_n(0, PAD))
                .collect(),
            len: n,
            nodes,
        };
        map.fill_classes();
        map
    }

    /// Number of stored photons.
    #[must_use]
    pub fn len(&self) -> usize {
        self.len
    }

    /// True if the map holds no photon.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Bytes per stored photon (the five columns).
    #[must_use]
    pub const fn bytes_per_photon() -> usize {
        5 * 4
    }

    /// Photon `i` (in tree order) as a record, with its packed fields decoded.
    #[must_use]
    pub fn photon(&self, i: usize) -> Photon {
        let key = self.key[i];
        Photon {
            position: self.position(i),
            power: self.power(i),
            wi: key_wi(key).normalize_or_zero(),
            normal: key_normal(key).normalize_or_zero(),
            flags: key_flags(key),
        }
    }

    /// Position of photon `i`.
    #[inline]
    #[must_use]
    pub fn position(&self, i: usize) -> Vec3 {
        Vec3::new(self.x[i], self.y[i], self.z[i])
    }

    /// Power of photon `i` (decoded).
    #[must_use]
    pub fn power(&self, i: usize) -> Vec3 {
        rgbe_decode(self.power[i])
    }
}

/// Uniform numbers in [0, 1) from a 64-bit linear congruential generator seeded with `seed`:
/// the photon-map tests' fixed random photons and queries.
#[cfg(test)]
pub(crate) fn test_uniforms(mut seed: u64) -> impl FnMut() -> f32 {
    move || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 40) as f32 / (1u64 << 24) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::code_path::CodePath;

    fn photon(x: f32, z: f32, power: f32) -> Photon {
        Photon { position: Vec3::new(x, 0.0, z), power: Vec3::splat(power), wi: Vec3::Y, normal: Vec3::Y, flags: 0 }
    }

    /// Far from the origin a point is known only to its coordinates' rounding: photons on the
    /// query's own floor, 30 000 units out, lie an ulp or two (2–4 mm) above or below it. With
    /// the slack of [`Filter::at`] every one is kept by both code paths, a flat query's plane
    /// test and a curved one's offset test alike; without it (slack 0, the tests relative to
    /// the distance alone) the plane test sets aside and the offset test turns away the nearest.
    #[test]
    fn photons_a_rounding_off_the_plane_are_kept_far_from_the_origin() {
        let p = Vec3::new(30_000.0, -20_000.0, 10_000.0);
        let ulp = p.y.abs().next_up() - p.y.abs();
        let photons: Vec<Photon> = (0..400)
            .map(|i| {
                let (a, b) = ((i % 20) as f32 - 9.5, (i / 20) as f32 - 9.5);
                let h = [-2.0, -1.0, 0.0, 1.0, 2.0][i % 5] * ulp;
                let q = p + Vec3::new(a * 0.004, h, b * 0.004);
                Photon { position: q, power: Vec3::ONE, wi: Vec3::Y, normal: Vec3::Y, flags: 0 }
            })
            .collect();
        assert!(photons.iter().any(|ph| ph.position.y != p.y), "the heights must survive the rounding");
        let map = PhotonMap::build(photons);
        let f = Reflectance::Constant(Vec3::ONE);
        for set in [CodePath::Scalar, CodePath::Simd] {
            for plane in [OFF_PLANE, 0.0] {
                let filter = Filter::at(p, Vec3::Y, 0).with_plane(plane);
                assert!(filter.slack > 4.0 * ulp, "{}", filter.slack);
                let q = Lookup { p, k: 0, r_max: 0.1, kernel: Kernel::Box, filter };
                let e = map.estimate_radius(set, &q, f);
                assert_eq!((e.count, e.rejected, e.off_plane), (400, 0, 0), "{set:?}, plane {plane}");
                let bare = Lookup { filter: Filter { slack: 0.0, ..filter }, ..q };
                let e = map.estimate_radius(set, &bare, f);
                assert!(e.rejected + e.off_plane > 0, "{set:?}, plane {plane}: {e:?}");
            }
        }
    }

    /// `estimate_visible` with every photon visible is the plain estimate (the same photons; the
    /// sum in another order, so to 1e-6), with none visible it is zero, and with half the plane
    /// hidden a fixed-radius estimate keeps its radius and loses the hidden photons, while a
    /// k-nearest one widens to the k nearest visible photons.
    #[test]
    fn visible_estimates_filter_photons_and_keep_the_radius() {
        let photons: Vec<Photon> =
            (0..400).map(|i| photon((i % 20) as f32 * 0.05 - 0.5, (i / 20) as f32 * 0.05 - 0.5, 1.0)).collect();
        let map = PhotonMap::build(photons);
        let f = Reflectance::Constant(Vec3::ONE);
        let mut scratch = Nearest::default();
        for set in [CodePath::Scalar, CodePath::Simd] {
            for (k, r) in [(20usize, 0.3f32), (0, 0.2)] {
                let q = Lookup {
                    p: Vec3::ZERO,
                    k,
                    r_max: r,
                    kernel: Kernel::Box,
                    filter: Filter { n: Vec3::Y, flags_mask: 0, plane: 0.0, slack: 0.0 },
                };
                let plain =
                    if k == 0 { map.estimate_radius(set, &q, f) } else { map.estimate(set, &q, f, &mut scratch) };
                let all = map.estimate_visible(set, &q, f, &mut scratch, &|_, _| true);
                assert_eq!(all.count, plain.count, "{set:?}, k {k}");
                assert!(
                    (all.radiance - plain.radiance).abs().max_element() <= 1e-6 * plain.radiance.x,
                    "{set:?}, k {k}"
                );
                let none = map.estimate_visible(set, &q, f, &mut scratch, &|_, _| false);
                assert_eq!((none.radiance, none.count), (Vec3::ZERO, 0), "{set:?}, k {k}");
                let half = map.estimate_visible(set, &q, f, &mut scratch, &|p, _| p.x < 0.0);
                if k == 0 {
                    assert_eq!(half.radius, plain.radius, "{set:?}, k {k}");
                    assert!(half.count > 0 && half.count < plain.count, "{set:?}: {} of {}", half.count, plain.count);
                } else {
                    assert!(half.radius > plain.radius, "{set:?}: {} for {}", half.radius, plain.radius);
                    assert_eq!(half.count, plain.count, "{set:?}");
                    // The query lies on the hidden half's edge: its disk holds visible photons on
                    // one side only, and the estimate falls toward ½, as at any edge.
                    let ratio = half.radiance.x / plain.radiance.x;
                    assert!(ratio > 0.2 && ratio < 0.8, "{set:?}: {ratio}");
                }
            }
        }
    }

    /// Photons that all carry one power (as Russian roulette makes them) decode, on average, to
    /// that power: the dithered mantissas are unbiased. Each photon's error is a Bernoulli step of
    /// at most 1/128 of the largest channel, σ ≤ 1/256 of it; the mean of 20 000 photons has
    /// σ ≤ 2⁻⁸/√20 000 = 2.8·10⁻⁵, and the tolerance is 5 of those. Plain rounding was off by
    /// the same fraction in every photon — 0.30 %, 0.33 % and 0.35 % in the three channels here,
    /// a bias this test would catch 20 times over.
    #[test]
    fn equal_powers_decode_to_their_mean() {
        let power = Vec3::new(0.9, 0.6613, 0.3711) * 1.37e-6;
        let n = 20_000;
        let photons: Vec<Photon> = (0..n).map(|i| Photon { power, ..photon(i as f32, 0.0, 0.0) }).collect();
        let map = PhotonMap::build(photons);
        let mean = (0..n).map(|i| map.power(i).as_dvec3()).sum::<glam::DVec3>() / n as f64;
        let err = (mean - power.as_dvec3()).abs() / f64::from(power.max_element());
        let tol = 5.0 * 2f64.powi(-8) / (n as f64).sqrt();
        assert!(err.max_element() < tol, "mean {mean} for {power}: {err}");
        let plain = rgbe_decode(rgbe_encode(power, Vec3::splat(0.5)));
        let plain_err = f64::from((plain - power).abs().max_element() / power.max_element());
        assert!(plain_err > 20.0 * tol, "plain rounding is off by {plain_err} only");
    }

    #[test]
    fn nearest_matches_brute_force() {
        let mut rnd = super::test_uniforms(12345);
        let ps: Vec<Photon> = (0..2000).map(|_| photon(rnd(), rnd(), 1.0)).collect();
        let map = PhotonMap::build(ps.clone());
        let mut out = Nearest::default();
        for i in 0..100 {
            let q = Vec3::new(rnd(), 0.0, rnd());
            let k = if i % 2 == 0 { 10 } else { 1 };
            let lookup = Lookup {
                p: q,
                k,
                r_max: 0.2,
                kernel: Kernel::Box,
                filter: Filter { n: Vec3::Y, flags_mask: 0, plane: 0.0, slack: 0.0 },
            };
            let mut got: Vec<f32> = map.nearest(CodePath::Simd, &lookup, &mut out).iter().map(|c| c.0).collect();
            got.sort_by(f32::total_cmp);
            let mut want: Vec<f32> =
                ps.iter().map(|p| (p.position - q).length_squared()).filter(|&d| d < 0.04).collect();
            want.sort_by(f32::total_cmp);
            want.truncate(k);
            assert_eq!(got, want);
        }
    }
}
