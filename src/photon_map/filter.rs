//! Which photons a lookup may use: the distance, flags and surface tests of one photon (its
//! normal within ~45° of the query's, its mid-plane offset within [`SURFACE_OFFSET`] of its
//! distance), and the 8-wide twin that tests a block of 8 photons at once with the same
//! operations.

use super::packing::{dequantise8, key_flags, key_normal, oct_decode8, NORMAL_STEPS};
use super::{Filter, PhotonMap, Test, SURFACE_OFFSET};
use glam::Vec3;
use wide::{f32x8, u32x8};

/// `(2 · SURFACE_OFFSET)²`: the surface test turns away a photon whose `((x − p)·(n + m̂))²`
/// exceeds this times its squared distance.
const OFFSET2: f32 = 4.0 * SURFACE_OFFSET * SURFACE_OFFSET;

impl PhotonMap {
    /// Whether photon `key` at `delta` = (x − p), `d2` = |x − p|² from the query passes
    /// `filter`: flags; the normal test n·m > 0.7·|m| evaluated as n·m > 0 ∧ (n·m)² > 0.49·|m|²
    /// (no square root); then for a flat query the plane test, which sets aside the photons
    /// behind its plane by more than `plane` of their distance ((x − p)·n < 0 and
    /// ((x − p)·n)² > plane²·d2, [`Filter::plane`]), and for any other the offset test
    /// ((x − p)·(n + m̂))² ≤ [`OFFSET2`]·d2, each allowing the filter's absolute
    /// [`Filter::slack`] (slack² and (2·slack)² added to the bound: the offset is measured along
    /// n + m̂, up to twice a unit) — the same operations as the 8-wide form. A
    /// rejection says which test failed. (Each test adds a sixth to a packet of estimates'
    /// instructions, so a query makes one: what a flat point's offset test would turn away lies
    /// behind its plane, set aside, or in front of it, kept as it always was.)
    #[inline]
    pub(super) fn test(key: u32, filter: &Filter, delta: [f32; 3], d2: f32) -> Test {
        if key_flags(key) & filter.flags_mask != 0 {
            return Test::Flags;
        }
        let m = key_normal(key);
        let dot = m.x * filter.n.x + m.y * filter.n.y + m.z * filter.n.z;
        let len2 = m.x * m.x + m.y * m.y + m.z * m.z;
        if !(dot > 0.0 && dot * dot > 0.49 * len2) {
            return Test::Normal;
        }
        let slack2 = filter.slack * filter.slack;
        if filter.plane > 0.0 {
            let height = delta[0] * filter.n.x + delta[1] * filter.n.y + delta[2] * filter.n.z;
            return if height < 0.0 && height * height > filter.plane * filter.plane * d2 + slack2 {
                Test::OffPlane
            } else {
                Test::Accepted
            };
        }
        let inv = 1.0 / len2.sqrt();
        let h = [filter.n.x + m.x * inv, filter.n.y + m.y * inv, filter.n.z + m.z * inv];
        let s = delta[0] * h[0] + delta[1] * h[1] + delta[2] * h[2];
        if s * s > OFFSET2 * d2 + 4.0 * slack2 {
            Test::Normal
        } else {
            Test::Accepted
        }
    }

    /// [`Self::test`] for photon `i` at squared distance `d2` from `p` (as [`Self::d2`] computes
    /// it).
    #[inline]
    pub(super) fn test_at(&self, i: usize, p: Vec3, d2: f32, filter: &Filter) -> Test {
        Self::test(self.key[i], filter, [self.x[i] - p.x, self.y[i] - p.y, self.z[i] - p.z], d2)
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
            return Verdict8 { inside: f32x8::ZERO, bits: 0, turned: 0, off_plane: 0, d2, key: u32x8::ZERO };
        }
        let key = self.key8(base);
        let f = Self::filter8(&mut Normals8::decode(key), near, filter, [dx, dy, dz], d2);
        Verdict8 { inside: f.inside, bits: f.inside.to_bitmask(), turned: f.turned, off_plane: f.off_plane, d2, key }
    }

    /// The filter's verdict on 8 photons (`normals`, at `delta` = x − p and squared distances
    /// `d2` from the query) for a query whose sphere holds the lanes of `near` ([`Filtered8`]).
    #[inline]
    pub(super) fn filter8(
        normals: &mut Normals8,
        near: f32x8,
        filter: &Filter,
        delta: [f32x8; 3],
        d2: f32x8,
    ) -> Filtered8 {
        let (pass, flags_ok, [hx, hy, hz]) = normals.masks(filter);
        let [dx, dy, dz] = delta;
        let facing = near & pass;
        let turned = (near & flags_ok & !pass).to_bitmask();
        if filter.plane > 0.0 {
            let n = filter.n;
            let height = dx * f32x8::splat(n.x) + dy * f32x8::splat(n.y) + dz * f32x8::splat(n.z);
            let below = height.simd_lt(f32x8::ZERO);
            let bound = f32x8::splat(filter.plane * filter.plane) * d2 + f32x8::splat(filter.slack * filter.slack);
            let off = facing & below & (height * height).simd_gt(bound);
            return Filtered8 { inside: facing & !off, turned, off_plane: off.to_bitmask() };
        }
        let s = dx * hx + dy * hy + dz * hz;
        let bound = f32x8::splat(OFFSET2) * d2 + f32x8::splat(4.0 * (filter.slack * filter.slack));
        let on_surface = facing & !(s * s).simd_gt(bound);
        Filtered8 { inside: on_surface, turned: turned | (facing & !on_surface).to_bitmask(), off_plane: 0 }
    }
}

/// What [`PhotonMap::filter8`] made of 8 photons within a query's sphere.
pub(super) struct Filtered8 {
    /// All-ones in the lanes it accepts.
    pub inside: f32x8,
    /// Bits of the lanes its surface tests turn away (they pass its flags).
    pub turned: u32,
    /// Bits of the lanes off a flat query's plane ([`Filter::plane`]), set aside.
    pub off_plane: u32,
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
    /// 1 / their lengths.
    inv: f32x8,
    /// The [`super::flags`] bits.
    flags: u32x8,
    /// The last filter (its normal's bits and flags mask) and its [`Self::masks`].
    last: Option<([u32; 3], u8, Masks)>,
}

/// What a filter's normal makes of 8 photons, whatever the query's position: the lanes whose
/// normal test and flags pass, the lanes whose flags pass, and n + m̂ per lane (the offset test's
/// direction).
type Masks = (f32x8, f32x8, [f32x8; 3]);

impl Normals8 {
    /// Decodes the normals and flags of the 8 keys `key`.
    #[inline]
    pub(super) fn decode(key: u32x8) -> Self {
        let m = oct_decode8(
            dequantise8(key & u32x8::splat(63), NORMAL_STEPS),
            dequantise8((key >> 6_u32) & u32x8::splat(63), NORMAL_STEPS),
        );
        let len2 = m[0] * m[0] + m[1] * m[1] + m[2] * m[2];
        let inv = f32x8::ONE / len2.sqrt();
        Normals8 { m, len2, inv, flags: (key >> 12_u32) & u32x8::splat(7), last: None }
    }

    /// The lanes whose flags and normal test pass `filter`, the lanes whose flags pass (as
    /// all-ones lanes), and n + m̂; computed once for a run of queries with the same filter
    /// (same bits).
    #[inline]
    fn masks(&mut self, filter: &Filter) -> Masks {
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
        let h = [
            f32x8::splat(filter.n.x) + mx * self.inv,
            f32x8::splat(filter.n.y) + my * self.inv,
            f32x8::splat(filter.n.z) + mz * self.inv,
        ];
        let masks = (normal_ok & flags_ok, flags_ok, h);
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
    /// Lanes within the radius that pass the filter's flags but fail its surface tests.
    pub turned: u32,
    /// Lanes within the radius off a flat query's plane, set aside.
    pub off_plane: u32,
    /// Squared distances from the query.
    pub d2: f32x8,
    /// The photons' keys (zero when none is near).
    pub key: u32x8,
}
