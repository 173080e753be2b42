//! Photon maps (Jensen 1996): a balanced kd-tree over photons, k-nearest search under a maximum
//! radius, and the kernel density estimate of reflected radiance.
//!
//! The estimate uses the (k−1)/(πr²) form: when the search fills k photons, r is the distance
//! to the k-th and only the k−1 strictly inside are summed — unbiased for a uniform density,
//! where k/(πr²) overestimates by k/(k−1). When fewer than k lie within the maximum radius, all of
//! them are summed over the maximum radius (a fixed-radius estimate, also unbiased).
//!
//! Layout: 20 bytes a photon (Jensen's own record was 20 B), five 4-byte columns in kd-tree
//! order — every subtree is a contiguous index range, so spatial neighbours are contiguous and
//! 8 of them load into one `f32x8` per column:
//! - `x`, `y`, `z`: position, f32 (exact);
//! - `key`: surface normal (octahedral, 6 + 6 bits), flags (2 bits), kd split axis (2 bits),
//!   incoming direction (octahedral, 8 + 8 bits);
//! - `power`: RGBE (Ward's shared exponent, as Jensen stored it).
//!
//! Error bounds of the packing: power per channel within 2⁻⁷ of the largest channel (dithered,
//! so unbiased even when all photons carry one power); incoming direction within 1° (octahedral step 2/254; 0.95° measured over 4·10⁵
//! random directions); normal within 4° (step 2/62; 3.9° measured), against a filter threshold
//! of 45°. The tree is implicit: the median of each index range
//! is its node; ranges of at most [`BUCKET`] photons are leaves, tested whole — 8 photons at a
//! time by the SIMD kernels, one at a time by their scalar twins, with the same arithmetic in the
//! same order, so both find the same photons.

use crate::kernels::KernelSet;
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::f32::consts::PI;
use wide::{f32x8, i32x8, u32x8};

/// Density-estimation kernel, each normalised so that a uniform photon density is returned exactly.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Kernel {
    /// Constant weight: ∑Φ / (πr²).
    Box,
    /// Jensen's cone filter, weight 1 − d/r, normalised by 3/(πr²).
    Cone,
    /// Epanechnikov, weight 1 − d²/r², normalised by 2/(πr²).
    Epanechnikov,
}

impl std::str::FromStr for Kernel {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "box" => Ok(Kernel::Box),
            "cone" => Ok(Kernel::Cone),
            "epanechnikov" => Ok(Kernel::Epanechnikov),
            _ => Err(format!("unknown kernel `{s}` (box, cone, epanechnikov)")),
        }
    }
}

/// Flags on a stored photon.
pub mod flags {
    /// Stored at the first surface hit after leaving the light (direct illumination).
    pub const DIRECT: u8 = 1;
    /// Every bounce before this hit was specular (mirror/glass): an `LS+D` caustic photon.
    pub const CAUSTIC: u8 = 2;
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

/// Leaf ranges: a range this short is tested whole rather than split further.
pub const BUCKET: usize = 64;

/// Padding after the last photon so that 8-wide loads at any bucket stay in bounds (positions
/// +∞: never within any radius).
const PAD: usize = 8;

/// Photons in a balanced kd-tree.
#[derive(Clone, Debug, Default)]
pub struct PhotonMap {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    /// Normal, flags, split axis, incoming direction (see the module notes).
    key: Vec<u32>,
    /// RGBE power.
    power: Vec<u32>,
    /// Photons (without padding).
    len: usize,
}

/// The result of a density estimate, with its search radius (for diagnostics).
#[derive(Clone, Copy, Debug, Default)]
pub struct Estimate {
    /// Reflected radiance.
    pub radiance: Vec3,
    /// Radius the estimate used.
    pub radius: f32,
    /// Photons summed.
    pub count: u32,
    /// Photons within the search radius (as it stood when each was examined) that the normal
    /// test of the [`Filter`] turned away: another surface's photons, around a corner or through
    /// a thin wall.
    pub rejected: u32,
}

/// What a [`Filter`] made of one photon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Test {
    Accepted,
    /// Carries a masked flag.
    Flags,
    /// Lies on a surface facing another way.
    Normal,
}

/// Which photons a lookup may use: those whose surface normal lies within ~45° of `n` (no leaks
/// around corners or through thin walls) and that carry none of the `flags_mask` flags.
#[derive(Clone, Copy, Debug)]
pub struct Filter {
    /// The query's geometric normal, on the side the light is reflected to.
    pub n: Vec3,
    /// Photons with any of these [`flags`] are skipped.
    pub flags_mask: u8,
}

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

impl Kernel {
    /// Weight of a photon at squared distance `d2` from the query, radius² `r2`.
    #[inline]
    #[must_use]
    pub fn weight(self, d2: f32, r2: f32) -> f32 {
        match self {
            Kernel::Box => 1.0,
            Kernel::Cone => 1.0 - (d2 / r2).sqrt(),
            Kernel::Epanechnikov => 1.0 - d2 / r2,
        }
    }
    /// [`Kernel::weight`] for 8 photons, the same operations.
    #[inline]
    fn weight8(self, d2: f32x8, r2: f32x8) -> f32x8 {
        match self {
            Kernel::Box => f32x8::ONE,
            Kernel::Cone => f32x8::ONE - (d2 / r2).sqrt(),
            Kernel::Epanechnikov => f32x8::ONE - d2 / r2,
        }
    }
    /// 1 / ∫ weight dA over the disk of radius² `r2`: the normalisation that returns a uniform
    /// density exactly.
    #[inline]
    #[must_use]
    pub fn normalisation(self, r2: f32) -> f32 {
        match self {
            Kernel::Box => 1.0 / (PI * r2),
            Kernel::Cone => 3.0 / (PI * r2),
            Kernel::Epanechnikov => 2.0 / (PI * r2),
        }
    }
}

// ---- packing -------------------------------------------------------------------------------

/// Octahedral map of a unit vector to [−1, 1]².
fn oct_encode(n: Vec3) -> (f32, f32) {
    let s = n.x.abs() + n.y.abs() + n.z.abs();
    if !(s > 0.0) || !s.is_finite() {
        return (0.0, 0.0);
    }
    let (x, y) = (n.x / s, n.y / s);
    if n.z < 0.0 {
        ((1.0 - y.abs()) * x.signum(), (1.0 - x.abs()) * y.signum())
    } else {
        (x, y)
    }
}

/// Quantises v ∈ [−1, 1] to 0..=`steps` (even, so 0 and ±1 are exact).
fn quantise(v: f32, steps: u32) -> u32 {
    (((v.clamp(-1.0, 1.0) + 1.0) * 0.5 * steps as f32).round() as u32).min(steps)
}

const NORMAL_STEPS: u32 = 62;
const DIR_STEPS: u32 = 254;

/// Packs normal, flags (2 bits), split axis and incoming direction into a key.
fn pack_key(normal: Vec3, flags: u8, axis: u8, wi: Vec3) -> u32 {
    let (nu, nv) = oct_encode(normal);
    let (wu, wv) = oct_encode(wi);
    quantise(nu, NORMAL_STEPS)
        | quantise(nv, NORMAL_STEPS) << 6
        | u32::from(flags & 3) << 12
        | u32::from(axis & 3) << 14
        | quantise(wu, DIR_STEPS) << 16
        | quantise(wv, DIR_STEPS) << 24
}

/// Octahedral decode (not normalised): the same operations in [`oct_decode8`].
#[inline]
fn oct_decode(u: f32, v: f32) -> Vec3 {
    let z = 1.0 - u.abs() - v.abs();
    let t = (-z).max(0.0);
    Vec3::new(u + if u >= 0.0 { -t } else { t }, v + if v >= 0.0 { -t } else { t }, z)
}

#[inline]
fn oct_decode8(u: f32x8, v: f32x8) -> [f32x8; 3] {
    let z = f32x8::ONE - u.abs() - v.abs();
    let t = (-z).max(f32x8::ZERO);
    let zero = f32x8::ZERO;
    [u + u.simd_ge(zero).select(-t, t), v + v.simd_ge(zero).select(-t, t), z]
}

#[inline]
fn dequantise(q: u32, steps: u32) -> f32 {
    q as f32 * (2.0 / steps as f32) - 1.0
}

#[inline]
fn dequantise8(q: u32x8, steps: u32) -> f32x8 {
    let q: i32x8 = bytemuck_cast(q);
    q.round_float() * f32x8::splat(2.0 / steps as f32) - f32x8::ONE
}

/// Reinterprets lanes (all values here are < 2³¹).
#[inline]
fn bytemuck_cast(v: u32x8) -> i32x8 {
    wide::bytemuck::cast(v)
}

/// The stored normal of a key (not normalised).
#[inline]
fn key_normal(key: u32) -> Vec3 {
    oct_decode(dequantise(key & 63, NORMAL_STEPS), dequantise(key >> 6 & 63, NORMAL_STEPS))
}

/// The stored incoming direction of a key (not normalised).
#[inline]
fn key_wi(key: u32) -> Vec3 {
    oct_decode(dequantise(key >> 16 & 255, DIR_STEPS), dequantise(key >> 24, DIR_STEPS))
}

/// Flags of a key.
#[inline]
fn key_flags(key: u32) -> u8 {
    (key >> 12 & 3) as u8
}

/// RGBE: three 8-bit mantissas sharing the exponent of the largest channel. Each mantissa is
/// rounded up with probability equal to its fraction (dithered by `u`, three uniform numbers), so
/// the decoded power is unbiased even when every photon carries the same power, as Russian
/// roulette makes them: plain rounding gives all of them the same error — up to 2⁻⁹ of the
/// largest channel, 0.5 % of a weaker one — and every estimate that bias.
fn rgbe_encode(c: Vec3, u: Vec3) -> u32 {
    let c = c.max(Vec3::ZERO);
    let m = c.max_element();
    if !(m > 0.0) || !m.is_finite() {
        return 0;
    }
    // m < 2^(e − 127) with m ≥ 2^(e − 128): e = biased exponent of m, plus one, so that
    // m·2^(135 − e) lies in [128, 256).
    let mut e = (m.to_bits() >> 23 & 255) as i32 + 1;
    if e <= 8 {
        return 0; // below 2⁻¹¹⁸ W: nothing any estimate could see
    }
    // Above 255 a dithered mantissa could round up to 256: take the next exponent.
    if m * 2f32.powi(135 - e) > 255.0 && e < 255 {
        e += 1;
    }
    let q = (c * 2f32.powi(135 - e) + u).floor().min(Vec3::splat(255.0));
    q.x as u32 | (q.y as u32) << 8 | (q.z as u32) << 16 | (e as u32) << 24
}

/// Three uniform numbers in [0, 1) for dithering photon `i`'s power (a hash: the same photons
/// give the same map).
fn dither(i: usize) -> Vec3 {
    let h = crate::rng::mix64(i as u64 ^ 0x5047_4245); // "PGBE": any fixed salt
    let unit = |shift: u32| ((h >> shift) & 0x1f_ffff) as f32 * (1.0 / (1u32 << 21) as f32);
    Vec3::new(unit(0), unit(21), unit(42))
}

#[inline]
fn rgbe_decode(v: u32) -> Vec3 {
    let e = v >> 24_u32;
    if e <= 8 {
        return Vec3::ZERO;
    }
    let scale = f32::from_bits((e - 8) << 23);
    Vec3::new((v & 255) as f32, (v >> 8 & 255) as f32, (v >> 16 & 255) as f32) * scale
}

#[inline]
fn rgbe_decode8(v: u32x8) -> [f32x8; 3] {
    let byte = |shift: u32| bytemuck_cast((v >> shift) & u32x8::splat(255)).round_float();
    let e = v >> 24_u32;
    let valid = e.simd_gt(u32x8::splat(8));
    let bits = valid.select((e - u32x8::splat(8)) << 23_u32, u32x8::ZERO);
    let scale: f32x8 = wide::bytemuck::cast(bits);
    [byte(0) * scale, byte(8) * scale, byte(16) * scale]
}

impl PhotonMap {
    /// Builds the tree (takes ownership, reorders) and packs the photons.
    #[must_use]
    pub fn build(mut photons: Vec<Photon>) -> Self {
        let n = photons.len();
        let mut axis = vec![0u8; n];
        build_range(&mut photons, &mut axis, 0, n);
        let inf = f32::INFINITY;
        let col = |f: &dyn Fn(&Photon) -> f32| {
            photons.iter().map(f).chain(std::iter::repeat_n(inf, PAD)).collect::<Vec<f32>>()
        };
        PhotonMap {
            x: col(&|p| p.position.x),
            y: col(&|p| p.position.y),
            z: col(&|p| p.position.z),
            key: photons
                .iter()
                .zip(&axis)
                .map(|(p, &a)| pack_key(p.normal, p.flags, a, p.wi))
                .chain(std::iter::repeat_n(0, PAD))
                .collect(),
            power: photons
                .iter()
                .enumerate()
                .map(|(i, p)| rgbe_encode(p.power, dither(i)))
                .chain(std::iter::repeat_n(0, PAD))
                .collect(),
            len: n,
        }
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

    #[inline]
    fn axis(&self, i: usize) -> usize {
        (self.key[i] >> 14 & 3) as usize
    }

    /// Squared distance of photon `i` from `p`: the same operations as the 8-wide form.
    #[inline]
    fn d2(&self, i: usize, p: Vec3) -> f32 {
        let (dx, dy, dz) = (self.x[i] - p.x, self.y[i] - p.y, self.z[i] - p.z);
        dx * dx + dy * dy + dz * dz
    }

    /// Walks the implicit tree, calling `visit(lo, hi, simd_ok, r2)` for every bucket (`simd_ok`
    /// true) and every inner node's photon (a range of one, `simd_ok` false) that can lie within
    /// the (shrinking) radius² `r2`.
    fn walk(&self, p: Vec3, r2: &mut f32, mut visit: impl FnMut(usize, usize, bool, &mut f32)) {
        // Explicit stack of index ranges, each with the squared distance from `p` to the
        // splitting plane that separated it (0 for ranges on p's side): a far range is skipped
        // when r² has since shrunk below it.
        let mut stack: [(u32, u32, f32); 64] = [(0, 0, 0.0); 64];
        let mut top = 1;
        stack[0] = (0, self.len as u32, 0.0);
        while top > 0 {
            top -= 1;
            let (mut lo, mut hi, plane2) = stack[top];
            if plane2 >= *r2 {
                continue;
            }
            while lo < hi {
                if (hi - lo) as usize <= BUCKET {
                    visit(lo as usize, hi as usize, true, r2);
                    break;
                }
                let mid = lo + (hi - lo) / 2;
                let m = mid as usize;
                let a = self.axis(m);
                let q = [self.x[m], self.y[m], self.z[m]][a];
                let delta = p[a] - q;
                visit(m, m + 1, false, r2);
                // Descend into p's side now; remember the other side.
                let (near, far) = if delta < 0.0 { ((lo, mid), (mid + 1, hi)) } else { ((mid + 1, hi), (lo, mid)) };
                if far.0 < far.1 && delta * delta < *r2 && top < stack.len() {
                    stack[top] = (far.0, far.1, delta * delta);
                    top += 1;
                }
                (lo, hi) = near;
            }
        }
    }

    /// Whether photon `key` passes `filter`: flags, and the normal test n·m > 0.7·|m| evaluated as
    /// n·m > 0 ∧ (n·m)² > 0.49·|m|² (no square root), the same operations as the 8-wide form;
    /// a rejection says which test failed.
    #[inline]
    fn test(key: u32, filter: &Filter) -> Test {
        if key_flags(key) & filter.flags_mask != 0 {
            return Test::Flags;
        }
        let m = key_normal(key);
        let dot = m.x * filter.n.x + m.y * filter.n.y + m.z * filter.n.z;
        let len2 = m.x * m.x + m.y * m.y + m.z * m.z;
        if dot > 0.0 && dot * dot > 0.49 * len2 {
            Test::Accepted
        } else {
            Test::Normal
        }
    }

    /// The 8 keys from `base`.
    #[inline]
    fn key8(&self, base: usize) -> u32x8 {
        u32x8::from(<[u32; 8]>::try_from(&self.key[base..base + 8]).expect("padded column"))
    }

    /// The 8 RGBE powers from `base`.
    #[inline]
    fn power8(&self, base: usize) -> u32x8 {
        u32x8::from(<[u32; 8]>::try_from(&self.power[base..base + 8]).expect("padded column"))
    }

    /// Lanes of the 8 photons from `base` that lie within `r2` of `p` and pass `filter`, and the
    /// lanes within `r2` that pass its flags but fail its normal test.
    #[inline]
    fn accepts8(&self, base: usize, p: Vec3, r2: f32, filter: &Filter) -> (u32, u32, f32x8) {
        let load = |c: &[f32]| f32x8::from(<[f32; 8]>::try_from(&c[base..base + 8]).expect("padded column"));
        let (dx, dy, dz) =
            (load(&self.x) - f32x8::splat(p.x), load(&self.y) - f32x8::splat(p.y), load(&self.z) - f32x8::splat(p.z));
        let d2 = dx * dx + dy * dy + dz * dz;
        let near = d2.simd_lt(f32x8::splat(r2));
        if !near.any() {
            return (0, 0, d2);
        }
        let key = self.key8(base);
        let flags = (key >> 12_u32) & u32x8::splat(3);
        let flags_ok = (flags & u32x8::splat(u32::from(filter.flags_mask))).simd_eq(u32x8::ZERO);
        let [mx, my, mz] = oct_decode8(
            dequantise8(key & u32x8::splat(63), NORMAL_STEPS),
            dequantise8((key >> 6_u32) & u32x8::splat(63), NORMAL_STEPS),
        );
        let dot = mx * f32x8::splat(filter.n.x) + my * f32x8::splat(filter.n.y) + mz * f32x8::splat(filter.n.z);
        let len2 = mx * mx + my * my + mz * mz;
        let normal_ok = dot.simd_gt(f32x8::ZERO) & (dot * dot).simd_gt(f32x8::splat(0.49) * len2);
        let inside = near & normal_ok;
        let flags_bits = flags_ok.to_bitmask();
        let turned = (near & !normal_ok).to_bitmask() & flags_bits;
        (inside.to_bitmask() & flags_bits, turned, d2)
    }

    /// The `k` nearest photons to `q.p` within `q.r_max` that pass `q.filter`, as
    /// (distance², index), unordered, into `out`.
    pub fn nearest(&self, set: KernelSet, q: &Lookup, out: &mut Vec<(f32, u32)>) {
        self.nearest_counted(set, q, out);
    }

    /// [`Self::nearest`], returning how many photons the normal test turned away (see
    /// [`Estimate::rejected`]); both kernel sets count the same photons.
    fn nearest_counted(&self, set: KernelSet, q: &Lookup, out: &mut Vec<(f32, u32)>) -> u32 {
        out.clear();
        if q.k == 0 || self.is_empty() {
            return 0;
        }
        let mut rejected = 0u32;
        let k = q.k;
        // Candidates gather unsorted in `out`; when 2k have gathered, the k nearest are selected
        // (O(k)) and r² shrinks to the k-th distance. Amortised O(1) per candidate, no heap.
        // Order by (distance², index) as one integer: distances are non-negative (never −0 or
        // NaN here), so their bit patterns order as the values do.
        let by_distance = |c: &(f32, u32)| u64::from(c.0.to_bits()) << 32 | u64::from(c.1);
        let offer = |out: &mut Vec<(f32, u32)>, r2: &mut f32, d2: f32, i: usize| {
            if k == 1 {
                // The nearest alone (precomputed-irradiance lookups): keep the best so far.
                out.clear();
                out.push((d2, i as u32));
                *r2 = d2;
                return;
            }
            out.push((d2, i as u32));
            if out.len() == 2 * k {
                out.select_nth_unstable_by_key(k - 1, by_distance);
                out.truncate(k);
                *r2 = out[k - 1].0;
            }
        };
        let mut r2 = q.r_max * q.r_max;
        self.walk(q.p, &mut r2, |lo, hi, simd_ok, r2| {
            if simd_ok && set == KernelSet::Simd {
                for base in (lo..hi).step_by(8) {
                    let (m, turned, d2) = self.accepts8(base, q.p, *r2, &q.filter);
                    let valid = (1u32 << (hi - base).min(8)) - 1;
                    let (m, turned) = (m & valid, turned & valid);
                    let d2 = d2.to_array();
                    // Lane order, as the scalar twin walks them: r² may have shrunk since the
                    // 8-wide test, so each lane is re-checked at its turn.
                    let mut all = m | turned;
                    while all != 0 {
                        let l = all.trailing_zeros() as usize;
                        all &= all - 1;
                        if d2[l] < *r2 {
                            if m >> l & 1 == 1 {
                                offer(out, r2, d2[l], base + l);
                            } else {
                                rejected += 1;
                            }
                        }
                    }
                }
            } else {
                for i in lo..hi {
                    let d2 = self.d2(i, q.p);
                    if d2 < *r2 {
                        match Self::test(self.key[i], &q.filter) {
                            Test::Accepted => offer(out, r2, d2, i),
                            Test::Normal => rejected += 1,
                            Test::Flags => {}
                        }
                    }
                }
            }
        });
        if out.len() > k {
            out.select_nth_unstable_by_key(k - 1, by_distance);
            out.truncate(k);
        }
        rejected
    }

    /// Reflected radiance at `q.p` from its k nearest photons: Σ f(wi_p)·Φ_p·K over the
    /// (k−1)-of-k rule above.
    pub fn estimate(&self, set: KernelSet, q: &Lookup, f: Reflectance<'_>, scratch: &mut Vec<(f32, u32)>) -> Estimate {
        if self.is_empty() {
            return Estimate { radius: q.r_max, ..Default::default() };
        }
        let rejected = self.nearest_counted(set, q, scratch);
        let Some(r2) = Self::knn_radius2(q, scratch) else {
            return Estimate { radius: 0.0, rejected, ..Default::default() };
        };
        Estimate { rejected, ..self.sum_estimate(set, q, r2, f, scratch) }
    }

    /// The squared radius of a k-nearest estimate over `found` (the k-th photon's distance, that
    /// photon removed: it lies on the boundary; or `q.r_max`² when fewer were found); `None`
    /// for a zero radius.
    fn knn_radius2(q: &Lookup, found: &mut Vec<(f32, u32)>) -> Option<f32> {
        let (r2, skip) = if found.len() == q.k {
            // The k-th photon defines r and lies on the boundary: sum the other k − 1.
            let (far_i, far) = found
                .iter()
                .enumerate()
                .max_by(|a, b| a.1 .0.total_cmp(&b.1 .0))
                .map(|(i, c)| (i, c.0))
                .unwrap_or((0, 0.0));
            (far, Some(far_i))
        } else {
            (q.r_max * q.r_max, None)
        };
        if !(r2 > 0.0) {
            return None;
        }
        if let Some(j) = skip {
            found.swap_remove(j);
        }
        Some(r2)
    }

    /// The kernel estimate over `found` within squared radius `r2`.
    fn sum_estimate(&self, set: KernelSet, q: &Lookup, r2: f32, f: Reflectance<'_>, found: &[(f32, u32)]) -> Estimate {
        let sum = match set {
            KernelSet::Scalar => self.sum_scalar(found, r2, q.kernel, f),
            KernelSet::Simd => self.sum_simd(found, r2, q.kernel, f),
        };
        Estimate {
            radiance: sum * q.kernel.normalisation(r2),
            radius: r2.sqrt(),
            count: found.len() as u32,
            rejected: 0,
        }
    }

    /// [`Self::estimate`] (or, with `q.k == 0`, [`Self::estimate_radius`]) counting only the
    /// photons for which `visible(position, normal)` holds. The radius is chosen among all
    /// photons, as without the test: where every photon near a point lies behind a wall, the
    /// estimate there is zero.
    pub fn estimate_visible(
        &self,
        set: KernelSet,
        q: &Lookup,
        f: Reflectance<'_>,
        scratch: &mut Vec<(f32, u32)>,
        visible: &dyn Fn(Vec3, Vec3) -> bool,
    ) -> Estimate {
        if self.is_empty() {
            return Estimate { radius: q.r_max, ..Default::default() };
        }
        let (r2, rejected) = if q.k == 0 {
            // Every photon within the fixed radius (a bound no search reaches).
            let rejected = self.nearest_counted(set, &Lookup { k: u32::MAX as usize, ..*q }, scratch);
            let r2 = q.r_max * q.r_max;
            if !(r2 > 0.0) || !r2.is_finite() {
                return Estimate { radius: q.r_max, ..Default::default() };
            }
            (r2, rejected)
        } else {
            let rejected = self.nearest_counted(set, q, scratch);
            let Some(r2) = Self::knn_radius2(q, scratch) else {
                return Estimate { radius: 0.0, rejected, ..Default::default() };
            };
            (r2, rejected)
        };
        scratch.retain(|&(_, i)| {
            let key = self.key[i as usize];
            visible(self.position(i as usize), key_normal(key).normalize_or_zero())
        });
        Estimate { rejected, ..self.sum_estimate(set, q, r2, f, scratch) }
    }

    /// Reflected radiance at `q.p` from every photon within the fixed radius `q.r_max`.
    pub fn estimate_radius(&self, set: KernelSet, q: &Lookup, f: Reflectance<'_>) -> Estimate {
        let r2 = q.r_max * q.r_max;
        if self.is_empty() || !(r2 > 0.0) || !r2.is_finite() {
            return Estimate { radius: q.r_max, ..Default::default() };
        }
        let (mut count, mut rejected) = (0u32, 0u32);
        let mut sum = Vec3::ZERO;
        let mut sum8 = [f32x8::ZERO; 3];
        let mut r2_walk = r2;
        self.walk(q.p, &mut r2_walk, |lo, hi, simd_ok, _| {
            if simd_ok && set == KernelSet::Simd {
                for base in (lo..hi).step_by(8) {
                    let (mut m, turned, d2) = self.accepts8(base, q.p, r2, &q.filter);
                    let valid = (1u32 << (hi - base).min(8)) - 1;
                    m &= valid;
                    rejected += (turned & valid).count_ones();
                    if m == 0 {
                        continue;
                    }
                    count += m.count_ones();
                    let lanes = f32x8::from(std::array::from_fn::<f32, 8, _>(|l| {
                        if m >> l & 1 == 1 {
                            f32::from_bits(u32::MAX)
                        } else {
                            0.0
                        }
                    }));
                    let c = Self::contribution8(self.key8(base), self.power8(base), lanes, d2, r2, q.kernel, f);
                    for (s, v) in sum8.iter_mut().zip(c) {
                        *s += v;
                    }
                }
            } else {
                for i in lo..hi {
                    let d2 = self.d2(i, q.p);
                    if d2 < r2 {
                        match Self::test(self.key[i], &q.filter) {
                            Test::Accepted => {
                                sum += self.contribution(i, d2, r2, q.kernel, f);
                                count += 1;
                            }
                            Test::Normal => rejected += 1,
                            Test::Flags => {}
                        }
                    }
                }
            }
        });
        let simd = Vec3::new(sum8[0].reduce_add(), sum8[1].reduce_add(), sum8[2].reduce_add());
        Estimate { radiance: (sum + simd) * q.kernel.normalisation(r2), radius: q.r_max, count, rejected }
    }

    /// f(wi)·Φ·weight of photon `i` at squared distance `d2` (scalar twin of [`Self::contribution8`]).
    #[inline]
    fn contribution(&self, i: usize, d2: f32, r2: f32, kernel: Kernel, f: Reflectance<'_>) -> Vec3 {
        let key = self.key[i];
        let w = kernel.weight(d2, r2);
        let fp = match f {
            Reflectance::Constant(v) => v,
            Reflectance::Hemisphere { value, ng } => {
                let wi = key_wi(key);
                if wi.x * ng.x + wi.y * ng.y + wi.z * ng.z > 0.0 {
                    value
                } else {
                    Vec3::ZERO
                }
            }
            Reflectance::PerPhoton(g) => g(key_wi(key).normalize_or_zero()),
        };
        fp * rgbe_decode(self.power[i]) * w
    }

    /// f(wi)·Φ·weight of 8 photons (`key`, `power` columns, squared distances `d2`) in the lanes
    /// of `lanes` (others 0), per channel.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn contribution8(
        key: u32x8,
        power: u32x8,
        lanes: f32x8,
        d2: f32x8,
        r2: f32,
        kernel: Kernel,
        f: Reflectance<'_>,
    ) -> [f32x8; 3] {
        let w = lanes.select(kernel.weight8(d2, f32x8::splat(r2)), f32x8::ZERO);
        let [pr, pg, pb] = rgbe_decode8(power);
        let (pr, pg, pb) = (pr * w, pg * w, pb * w);
        match f {
            Reflectance::Constant(v) => [pr * f32x8::splat(v.x), pg * f32x8::splat(v.y), pb * f32x8::splat(v.z)],
            Reflectance::Hemisphere { value, ng } => {
                let [wx, wy, wz] = oct_decode8(
                    dequantise8((key >> 16_u32) & u32x8::splat(255), DIR_STEPS),
                    dequantise8(key >> 24_u32, DIR_STEPS),
                );
                let up =
                    (wx * f32x8::splat(ng.x) + wy * f32x8::splat(ng.y) + wz * f32x8::splat(ng.z)).simd_gt(f32x8::ZERO);
                let zero = f32x8::ZERO;
                [
                    up.select(pr * f32x8::splat(value.x), zero),
                    up.select(pg * f32x8::splat(value.y), zero),
                    up.select(pb * f32x8::splat(value.z), zero),
                ]
            }
            Reflectance::PerPhoton(g) => {
                let (pr, pg, pb) = (pr.to_array(), pg.to_array(), pb.to_array());
                let (keys, on) = (key.to_array(), lanes.to_bitmask());
                let mut out = [[0f32; 8]; 3];
                for l in 0..8 {
                    if on >> l & 1 == 1 {
                        let fp = g(key_wi(keys[l]).normalize_or_zero());
                        out[0][l] = fp.x * pr[l];
                        out[1][l] = fp.y * pg[l];
                        out[2][l] = fp.z * pb[l];
                    }
                }
                out.map(f32x8::from)
            }
        }
    }

    fn sum_scalar(&self, found: &[(f32, u32)], r2: f32, kernel: Kernel, f: Reflectance<'_>) -> Vec3 {
        found.iter().map(|&(d2, i)| self.contribution(i as usize, d2, r2, kernel, f)).sum()
    }

    fn sum_simd(&self, found: &[(f32, u32)], r2: f32, kernel: Kernel, f: Reflectance<'_>) -> Vec3 {
        let mut acc = [f32x8::ZERO; 3];
        for chunk in found.chunks(8) {
            let mut key = [0u32; 8];
            let mut power = [0u32; 8];
            let mut d2 = [0f32; 8];
            let mut lanes = [0f32; 8];
            for (l, &(d, i)) in chunk.iter().enumerate() {
                key[l] = self.key[i as usize];
                power[l] = self.power[i as usize];
                d2[l] = d;
                lanes[l] = f32::from_bits(u32::MAX);
            }
            let c = Self::contribution8(
                u32x8::from(key),
                u32x8::from(power),
                f32x8::from(lanes),
                f32x8::from(d2),
                r2,
                kernel,
                f,
            );
            for (a, v) in acc.iter_mut().zip(c) {
                *a += v;
            }
        }
        Vec3::new(acc[0].reduce_add(), acc[1].reduce_add(), acc[2].reduce_add())
    }
}

fn build_range(photons: &mut [Photon], axis: &mut [u8], lo: usize, hi: usize) {
    if hi - lo <= BUCKET {
        return;
    }
    let mut mn = Vec3::splat(f32::INFINITY);
    let mut mx = Vec3::splat(f32::NEG_INFINITY);
    for ph in &photons[lo..hi] {
        mn = mn.min(ph.position);
        mx = mx.max(ph.position);
    }
    let ext = mx - mn;
    let a = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = lo + (hi - lo) / 2;
    photons[lo..hi].select_nth_unstable_by(mid - lo, |x, y| x.position[a].total_cmp(&y.position[a]));
    axis[mid] = a as u8;
    build_range(photons, axis, lo, mid);
    build_range(photons, axis, mid + 1, hi);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn photon(x: f32, z: f32, power: f32) -> Photon {
        Photon { position: Vec3::new(x, 0.0, z), power: Vec3::splat(power), wi: Vec3::Y, normal: Vec3::Y, flags: 0 }
    }

    /// `estimate_visible` with every photon visible is the plain estimate (the same photons; the
    /// fixed-radius sum in another order, so to 1e-6), with none visible it is zero,
    /// and with half the plane hidden it keeps the radius and loses the hidden photons.
    #[test]
    fn visible_estimates_filter_photons_and_keep_the_radius() {
        let photons: Vec<Photon> =
            (0..400).map(|i| photon((i % 20) as f32 * 0.05 - 0.5, (i / 20) as f32 * 0.05 - 0.5, 1.0)).collect();
        let map = PhotonMap::build(photons);
        let f = Reflectance::Constant(Vec3::ONE);
        let mut scratch = Vec::new();
        for set in [KernelSet::Scalar, KernelSet::Simd] {
            for (k, r) in [(20usize, 0.3f32), (0, 0.2)] {
                let q = Lookup {
                    p: Vec3::ZERO,
                    k,
                    r_max: r,
                    kernel: Kernel::Box,
                    filter: Filter { n: Vec3::Y, flags_mask: 0 },
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
                assert_eq!(half.radius, plain.radius, "{set:?}, k {k}");
                assert!(
                    half.count > 0 && half.count < plain.count,
                    "{set:?}, k {k}: {} of {}",
                    half.count,
                    plain.count
                );
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
        let mut s = 12345u64;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        let ps: Vec<Photon> = (0..2000).map(|_| photon(rnd(), rnd(), 1.0)).collect();
        let map = PhotonMap::build(ps.clone());
        let mut out = vec![];
        for _ in 0..50 {
            let q = Vec3::new(rnd(), 0.0, rnd());
            let lookup =
                Lookup { p: q, k: 10, r_max: 0.2, kernel: Kernel::Box, filter: Filter { n: Vec3::Y, flags_mask: 0 } };
            map.nearest(KernelSet::Simd, &lookup, &mut out);
            let mut got: Vec<f32> = out.iter().map(|c| c.0).collect();
            got.sort_by(f32::total_cmp);
            let mut want: Vec<f32> =
                ps.iter().map(|p| (p.position - q).length_squared()).filter(|&d| d < 0.04).collect();
            want.sort_by(f32::total_cmp);
            want.truncate(10);
            assert_eq!(got, want);
        }
    }
}
