//! The packed photon record: octahedral normal and incoming direction, flags and the kd split
//! axis in one 32-bit key; power as RGBE with a dithered mantissa. Each decoder beside its 8-wide
//! twin, with the same operations. Error bounds are in the module notes of [`super`].

use glam::Vec3;
use wide::{f32x8, i32x8, u32x8};

/// Octahedral map of a unit vector to [−1, 1]².
pub(super) fn oct_encode(n: Vec3) -> (f32, f32) {
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
pub(super) fn quantise(v: f32, steps: u32) -> u32 {
    (((v.clamp(-1.0, 1.0) + 1.0) * 0.5 * steps as f32).round() as u32).min(steps)
}

pub(super) const NORMAL_STEPS: u32 = 62;

pub(super) const DIR_STEPS: u32 = 254;

/// Packs normal, flags (3 bits) and incoming direction into a key (bit 15 spare).
pub(super) fn pack_key(normal: Vec3, flags: u8, wi: Vec3) -> u32 {
    let (nu, nv) = oct_encode(normal);
    let (wu, wv) = oct_encode(wi);
    quantise(nu, NORMAL_STEPS)
        | quantise(nv, NORMAL_STEPS) << 6
        | u32::from(flags & 7) << 12
        | quantise(wu, DIR_STEPS) << 16
        | quantise(wv, DIR_STEPS) << 24
}

/// Octahedral decode (not normalised): the same operations in [`oct_decode8`].
#[inline]
pub(super) fn oct_decode(u: f32, v: f32) -> Vec3 {
    let z = 1.0 - u.abs() - v.abs();
    let t = (-z).max(0.0);
    Vec3::new(u + if u >= 0.0 { -t } else { t }, v + if v >= 0.0 { -t } else { t }, z)
}

#[inline]
pub(super) fn oct_decode8(u: f32x8, v: f32x8) -> [f32x8; 3] {
    let z = f32x8::ONE - u.abs() - v.abs();
    let t = (-z).max(f32x8::ZERO);
    let zero = f32x8::ZERO;
    [u + u.simd_ge(zero).select(-t, t), v + v.simd_ge(zero).select(-t, t), z]
}

#[inline]
pub(super) fn dequantise(q: u32, steps: u32) -> f32 {
    q as f32 * (2.0 / steps as f32) - 1.0
}

#[inline]
pub(super) fn dequantise8(q: u32x8, steps: u32) -> f32x8 {
    let q: i32x8 = bytemuck_cast(q);
    q.round_float() * f32x8::splat(2.0 / steps as f32) - f32x8::ONE
}

/// Reinterprets lanes (all values here are < 2³¹).
#[inline]
pub(super) fn bytemuck_cast(v: u32x8) -> i32x8 {
    wide::bytemuck::cast(v)
}

/// The stored normal of a key (not normalised).
#[inline]
pub(super) fn key_normal(key: u32) -> Vec3 {
    oct_decode(dequantise(key & 63, NORMAL_STEPS), dequantise(key >> 6 & 63, NORMAL_STEPS))
}

/// The stored incoming direction of a key (not normalised).
#[inline]
pub(super) fn key_wi(key: u32) -> Vec3 {
    oct_decode(dequantise(key >> 16 & 255, DIR_STEPS), dequantise(key >> 24, DIR_STEPS))
}

/// Flags of a key.
#[inline]
pub(super) fn key_flags(key: u32) -> u8 {
    (key >> 12 & 7) as u8
}

/// RGBE: three 8-bit mantissas sharing the exponent of the largest channel. Each mantissa is
/// rounded up with probability equal to its fraction (dithered by `u`, three uniform numbers), so
/// the decoded power is unbiased even when every photon carries the same power, as Russian
/// roulette makes them: plain rounding gives all of them the same error — up to 2⁻⁹ of the
/// largest channel, 0.5 % of a weaker one — and every estimate that bias.
pub(super) fn rgbe_encode(c: Vec3, u: Vec3) -> u32 {
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
pub(super) fn dither(i: usize) -> Vec3 {
    let h = crate::rng::mix64(i as u64 ^ 0x5047_4245); // "PGBE": any fixed salt
    let unit = |shift: u32| ((h >> shift) & 0x1f_ffff) as f32 * (1.0 / (1u32 << 21) as f32);
    Vec3::new(unit(0), unit(21), unit(42))
}

#[inline]
pub(super) fn rgbe_decode(v: u32) -> Vec3 {
    let e = v >> 24_u32;
    if e <= 8 {
        return Vec3::ZERO;
    }
    let scale = f32::from_bits((e - 8) << 23);
    Vec3::new((v & 255) as f32, (v >> 8 & 255) as f32, (v >> 16 & 255) as f32) * scale
}

#[inline]
pub(super) fn rgbe_decode8(v: u32x8) -> [f32x8; 3] {
    let byte = |shift: u32| bytemuck_cast((v >> shift) & u32x8::splat(255)).round_float();
    let e = v >> 24_u32;
    let valid = e.simd_gt(u32x8::splat(8));
    let bits = valid.select((e - u32x8::splat(8)) << 23_u32, u32x8::ZERO);
    let scale: f32x8 = wide::bytemuck::cast(bits);
    [byte(0) * scale, byte(8) * scale, byte(16) * scale]
}
