//! The kernel sum of an estimate: Σ f(ωᵢ)·Φ·K over the photons found, normalised — per photon
//! in the scalar twin, 8 photons per step in the SIMD kernel.

use super::packing::{dequantise8, key_wi, oct_decode8, rgbe_decode, rgbe_decode8, DIR_STEPS};
use super::{Estimate, Kernel, Lookup, PhotonMap, Reflectance};
use crate::code_path::CodePath;
use glam::Vec3;
use wide::{f32x8, u32x8};

/// The powers of 8 photons, decoded, and their incoming directions, decoded when first asked for,
/// with the last hemisphere test made of them (queries of a packet mostly share their normal).
pub(super) struct Decoded8 {
    key: u32x8,
    power: [f32x8; 3],
    wi: Option<[f32x8; 3]>,
    /// The bits of the last normal given to [`Self::above`], and its answer.
    above: Option<([u32; 3], f32x8)>,
}

impl Decoded8 {
    /// The 8 photons of the `key` and `power` columns.
    #[inline]
    pub(super) fn new(key: u32x8, power: u32x8) -> Self {
        Decoded8 { key, power: rgbe_decode8(power), wi: None, above: None }
    }

    /// Their incoming directions (octahedral decode, not normalised).
    #[inline]
    fn wi(&mut self) -> [f32x8; 3] {
        let key = self.key;
        *self.wi.get_or_insert_with(|| {
            oct_decode8(
                dequantise8((key >> 16_u32) & u32x8::splat(255), DIR_STEPS),
                dequantise8(key >> 24_u32, DIR_STEPS),
            )
        })
    }

    /// All-ones in the lanes whose incoming direction lies above the plane of `ng` (ωᵢ·n > 0);
    /// computed once for a run of queries with the same normal (same bits).
    #[inline]
    fn above(&mut self, ng: Vec3) -> f32x8 {
        let n = ng.to_array().map(f32::to_bits);
        if let Some((last, up)) = self.above {
            if last == n {
                return up;
            }
        }
        let [wx, wy, wz] = self.wi();
        let up = (wx * f32x8::splat(ng.x) + wy * f32x8::splat(ng.y) + wz * f32x8::splat(ng.z)).simd_gt(f32x8::ZERO);
        self.above = Some((n, up));
        up
    }
}

/// The sum of each of three 8-lane columns (per-channel sums of an estimate).
#[inline]
pub(super) fn reduce3(v: [f32x8; 3]) -> Vec3 {
    Vec3::new(v[0].reduce_add(), v[1].reduce_add(), v[2].reduce_add())
}

impl PhotonMap {
    /// The squared radius of the fixed-radius lookup `q` if it can find photons: a positive,
    /// finite radius in a map that holds some.
    #[inline]
    pub(super) fn fixed_radius2(&self, q: &Lookup) -> Option<f32> {
        let r2 = q.r_max * q.r_max;
        (!self.is_empty() && r2 > 0.0 && r2.is_finite()).then_some(r2)
    }

    /// The kernel estimate over `found` within squared radius `r2`.
    #[inline]
    pub(super) fn sum_estimate(
        &self,
        set: CodePath,
        q: &Lookup,
        r2: f32,
        f: Reflectance<'_>,
        found: &[(f32, u32)],
    ) -> Estimate {
        let sum = match set {
            CodePath::Scalar => self.sum_scalar(found, r2, q.kernel, f),
            CodePath::Simd => self.sum_simd(found, r2, q.kernel, f),
        };
        Estimate {
            radiance: sum * q.kernel.normalisation(r2),
            radius: r2.sqrt(),
            bias: Vec3::ZERO,
            count: found.len() as u32,
            ..Default::default()
        }
    }

    /// f(wi)·Φ·weight of photon `i` at squared distance `d2` (scalar twin of [`Self::contribution8`]).
    #[inline]
    pub(super) fn contribution(&self, i: usize, d2: f32, r2: f32, kernel: Kernel, f: Reflectance<'_>) -> Vec3 {
        self.reflected(i, f) * kernel.weight(d2, r2)
    }

    /// f(wi)·Φ of photon `i` times its kernel weight and times its [`Kernel::bias_weight`]
    /// (scalar twin of [`Self::contributions8`] with those two weights).
    #[inline]
    pub(super) fn contribution_and_bias(
        &self,
        i: usize,
        d2: f32,
        r2: f32,
        kernel: Kernel,
        f: Reflectance<'_>,
    ) -> (Vec3, Vec3) {
        let fp = self.reflected(i, f);
        (fp * kernel.weight(d2, r2), fp * Kernel::bias_weight(d2, r2))
    }

    /// f(wi)·Φ of photon `i`, unweighted.
    #[inline]
    fn reflected(&self, i: usize, f: Reflectance<'_>) -> Vec3 {
        let key = self.key[i];
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
        fp * rgbe_decode(self.power[i])
    }

    /// f(wi)·Φ·weight of 8 photons (`key`, `power` columns, squared distances `d2`) in the lanes
    /// of `lanes` (others 0), per channel.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn contribution8(
        key: u32x8,
        power: u32x8,
        lanes: f32x8,
        d2: f32x8,
        r2: f32,
        kernel: Kernel,
        f: Reflectance<'_>,
    ) -> [f32x8; 3] {
        let [c] = Self::contributions8(key, power, lanes, [kernel.weight8(d2, f32x8::splat(r2))], f);
        c
    }

    /// f(wi)·Φ·w of 8 photons for each of `W` per-photon weights `weights`, in the lanes of
    /// `lanes` (others 0), per channel: the photons' powers and directions are decoded once.
    #[inline]
    pub(super) fn contributions8<const W: usize>(
        key: u32x8,
        power: u32x8,
        lanes: f32x8,
        weights: [f32x8; W],
        f: Reflectance<'_>,
    ) -> [[f32x8; 3]; W] {
        Self::contributions8_decoded(&mut Decoded8::new(key, power), lanes, weights, f)
    }

    /// [`Self::contributions8`] of photons already (partly) decoded: a block tested against
    /// several queries decodes its powers and directions once.
    #[inline(always)]
    pub(super) fn contributions8_decoded<const W: usize>(
        photons: &mut Decoded8,
        lanes: f32x8,
        weights: [f32x8; W],
        f: Reflectance<'_>,
    ) -> [[f32x8; 3]; W] {
        let [pr, pg, pb] = photons.power;
        let key = photons.key;
        let weighted = weights.map(|w| {
            let w = lanes.select(w, f32x8::ZERO);
            (pr * w, pg * w, pb * w)
        });
        match f {
            Reflectance::Constant(v) => {
                weighted.map(|(pr, pg, pb)| [pr * f32x8::splat(v.x), pg * f32x8::splat(v.y), pb * f32x8::splat(v.z)])
            }
            Reflectance::Hemisphere { value, ng } => {
                let up = photons.above(ng);
                let zero = f32x8::ZERO;
                weighted.map(|(pr, pg, pb)| {
                    [
                        up.select(pr * f32x8::splat(value.x), zero),
                        up.select(pg * f32x8::splat(value.y), zero),
                        up.select(pb * f32x8::splat(value.z), zero),
                    ]
                })
            }
            Reflectance::PerPhoton(g) => Self::per_photon8(key, lanes, weighted, g),
        }
    }

    /// f(wi)·Φ·w of 8 photons for a reflectance evaluated per photon (`g`, once per photon), in
    /// the lanes of `lanes`, for each of the `W` weighted powers `weighted` (per channel). Out of
    /// line on purpose: inlined, the compiler hoisted the eight direction decodes and
    /// normalisations (a square root and a division each) out of the arms of the reflectance
    /// match and out of the loop over a block's queries, so that every block of every Lambertian
    /// estimate paid for them (BENCHMARKS.md, issue 18, eighteenth part).
    #[inline(never)]
    fn per_photon8<const W: usize>(
        key: u32x8,
        lanes: f32x8,
        weighted: [(f32x8, f32x8, f32x8); W],
        g: &dyn Fn(Vec3) -> Vec3,
    ) -> [[f32x8; 3]; W] {
        let (keys, on) = (key.to_array(), lanes.to_bitmask());
        let fps: [Vec3; 8] =
            std::array::from_fn(|l| if on >> l & 1 == 1 { g(key_wi(keys[l]).normalize_or_zero()) } else { Vec3::ZERO });
        weighted.map(|(pr, pg, pb)| {
            let (pr, pg, pb) = (pr.to_array(), pg.to_array(), pb.to_array());
            let mut out = [[0f32; 8]; 3];
            for l in 0..8 {
                if on >> l & 1 == 1 {
                    out[0][l] = fps[l].x * pr[l];
                    out[1][l] = fps[l].y * pg[l];
                    out[2][l] = fps[l].z * pb[l];
                }
            }
            out.map(f32x8::from)
        })
    }

    #[inline]
    pub(super) fn sum_scalar(&self, found: &[(f32, u32)], r2: f32, kernel: Kernel, f: Reflectance<'_>) -> Vec3 {
        found.iter().map(|&(d2, i)| self.contribution(i as usize, d2, r2, kernel, f)).sum()
    }

    #[inline]
    pub(super) fn sum_simd(&self, found: &[(f32, u32)], r2: f32, kernel: Kernel, f: Reflectance<'_>) -> Vec3 {
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
