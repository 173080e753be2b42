//! Which photons a lookup may use: the distance, flags and normal tests of one photon, and the
//! 8-wide twin that tests a block of 8 photons at once with the same operations.

use super::packing::{dequantise8, key_flags, key_normal, oct_decode8, NORMAL_STEPS};
use super::{Filter, PhotonMap, Test};
use glam::Vec3;
use wide::{f32x8, u32x8};

impl PhotonMap {
    /// Whether photon `key` passes `filter`: flags, and the normal test n·m > 0.7·|m| evaluated as
    /// n·m > 0 ∧ (n·m)² > 0.49·|m|² (no square root), the same operations as the 8-wide form;
    /// a rejection says which test failed.
    #[inline]
    pub(super) fn test(key: u32, filter: &Filter) -> Test {
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
    pub(super) fn key8(&self, base: usize) -> u32x8 {
        u32x8::from(<[u32; 8]>::try_from(&self.key[base..base + 8]).expect("padded column"))
    }

    /// The 8 RGBE powers from `base`.
    #[inline]
    pub(super) fn power8(&self, base: usize) -> u32x8 {
        u32x8::from(<[u32; 8]>::try_from(&self.power[base..base + 8]).expect("padded column"))
    }

    /// The filter's verdict on the 8 photons from `base` for a query at `p` within `r2`.
    #[inline]
    pub(super) fn accepts8(&self, base: usize, p: Vec3, r2: f32, filter: &Filter) -> Verdict8 {
        let load = |c: &[f32]| f32x8::from(<[f32; 8]>::try_from(&c[base..base + 8]).expect("padded column"));
        let (dx, dy, dz) =
            (load(&self.x) - f32x8::splat(p.x), load(&self.y) - f32x8::splat(p.y), load(&self.z) - f32x8::splat(p.z));
        let d2 = dx * dx + dy * dy + dz * dz;
        let near = d2.simd_lt(f32x8::splat(r2));
        if !near.any() {
            return Verdict8 { inside: f32x8::ZERO, bits: 0, turned: 0, d2, key: u32x8::ZERO };
        }
        let key = self.key8(base);
        let (inside, turned) = Self::filter8(&mut Normals8::decode(key), near, filter);
        Verdict8 { inside, bits: inside.to_bitmask(), turned, d2, key }
    }

    /// The filter's verdict on 8 photons (`normals`) for a query whose sphere holds the lanes of
    /// `near`: all-ones in the lanes it accepts, and the bits of the lanes its normal test turns
    /// away (they pass its flags).
    #[inline]
    pub(super) fn filter8(normals: &mut Normals8, near: f32x8, filter: &Filter) -> (f32x8, u32) {
        let (pass, turn) = normals.masks(filter);
        (near & pass, (near & turn).to_bitmask())
    }
}

/// The stored normals and flags of 8 photons, decoded once for any number of queries, with the
/// last filter's verdict: the queries of a packet mostly lie on one surface (in cornell-spheres'
/// progressive passes, 77 % of the queries testing a block have the normal of the query before
/// them), so the normal test runs once for all of them.
pub(super) struct Normals8 {
    /// The normals (octahedral decode, not normalised).
    m: [f32x8; 3],
    /// Their squared lengths.
    len2: f32x8,
    /// The [`super::flags`] bits.
    flags: u32x8,
    /// The last filter (its normal's bits and flags mask) and its [`Self::masks`].
    last: Option<([u32; 3], u8, (f32x8, f32x8))>,
}

impl Normals8 {
    /// Decodes the normals and flags of the 8 keys `key`.
    #[inline]
    pub(super) fn decode(key: u32x8) -> Self {
        let m = oct_decode8(
            dequantise8(key & u32x8::splat(63), NORMAL_STEPS),
            dequantise8((key >> 6_u32) & u32x8::splat(63), NORMAL_STEPS),
        );
        let len2 = m[0] * m[0] + m[1] * m[1] + m[2] * m[2];
        Normals8 { m, len2, flags: (key >> 12_u32) & u32x8::splat(3), last: None }
    }

    /// The lanes `filter` accepts, and the lanes whose normal test fails but whose flags pass,
    /// as all-ones lanes; computed once for a run of queries with the same filter (same bits).
    #[inline]
    fn masks(&mut self, filter: &Filter) -> (f32x8, f32x8) {
        let n = filter.n.to_array().map(f32::to_bits);
        if let Some((last_n, mask, masks)) = self.last {
            if last_n == n && mask == filter.flags_mask {
                return masks;
            }
        }
        let flags_ok: f32x8 =
            wide::bytemuck::cast((self.flags & u32x8::splat(u32::from(filter.flags_mask))).simd_eq(u32x8::ZERO));
        let [mx, my, mz] = self.m;
        let dot = mx * f32x8::splat(filter.n.x) + my * f32x8::splat(filter.n.y) + mz * f32x8::splat(filter.n.z);
        let normal_ok = dot.simd_gt(f32x8::ZERO) & (dot * dot).simd_gt(f32x8::splat(0.49) * self.len2);
        let masks = (normal_ok & flags_ok, !normal_ok & flags_ok);
        self.last = Some((n, filter.flags_mask, masks));
        masks
    }
}

/// What [`PhotonMap::accepts8`] made of 8 photons (padding lanes, at +∞, are never near).
pub(super) struct Verdict8 {
    /// All-ones in the lanes of photons within the radius that pass the filter, zero elsewhere.
    pub inside: f32x8,
    /// `inside` as a bit mask.
    pub bits: u32,
    /// Lanes within the radius that pass the filter's flags but fail its normal test.
    pub turned: u32,
    /// Squared distances from the query.
    pub d2: f32x8,
    /// The photons' keys (zero when none is near).
    pub key: u32x8,
}
