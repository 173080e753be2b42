//! Fixed-radius density estimates (progressive passes): every photon within the radius, summed
//! as the walk finds them — 8 at a time by the SIMD kernel, one at a time by its scalar twin —
//! with the estimate's bias from the same photons ([`Kernel::bias_normalisation`]).

use super::boundary::{Coverage, Cut, Neighbours};
use super::orientation::{reachable, walked};
use super::sum::reduce3;
use super::tree::Walk;
use super::{Estimate, Kernel, Lookup, PhotonMap, Reflectance, Test};
use crate::code_path::CodePath;
use glam::Vec3;
use wide::f32x8;

impl PhotonMap {
    /// Reflected radiance at `q.p` from every photon within the fixed radius `q.r_max`, as if
    /// the whole disk lay on the query's surface.
    pub fn estimate_radius(&self, set: CodePath, q: &Lookup, f: Reflectance<'_>) -> Estimate {
        self.estimate_fixed::<true>(set, q, f, None)
    }

    /// [`Self::estimate_radius`] divided by the part of the kernel's disk that lies on the
    /// query's surface ([`Neighbours::coverage`]): no darkening at edges and in corners. `edges`
    /// are cuts the photons cannot show (open edges of the query's surface).
    pub fn estimate_radius_on_surface(&self, set: CodePath, q: &Lookup, f: Reflectance<'_>, edges: &[Cut]) -> Estimate {
        self.estimate_fixed::<true>(set, q, f, Some(edges))
    }

    /// [`Self::estimate_radius`] (`on_surface` `None`) or [`Self::estimate_radius_on_surface`],
    /// with the bias estimated only if `bias` (it costs about a tenth of the estimate; without
    /// it the radiance is the same to the bit and the bias 0).
    pub fn estimate_radius_with(
        &self,
        set: CodePath,
        q: &Lookup,
        f: Reflectance<'_>,
        on_surface: Option<&[Cut]>,
        bias: bool,
    ) -> Estimate {
        if bias {
            self.estimate_fixed::<true>(set, q, f, on_surface)
        } else {
            self.estimate_fixed::<false>(set, q, f, on_surface)
        }
    }

    /// The fixed-radius estimate, boundary-corrected when `on_surface` is given, with its bias
    /// when `BIAS`.
    fn estimate_fixed<const BIAS: bool>(
        &self,
        set: CodePath,
        q: &Lookup,
        f: Reflectance<'_>,
        on_surface: Option<&[Cut]>,
    ) -> Estimate {
        let Some(r2) = self.fixed_radius2(q) else {
            return Estimate { radius: q.r_max, ..Default::default() };
        };
        let (mut count, mut rejected, mut off_plane) = (0u32, 0u32, 0u32);
        let mut neighbours = Neighbours::default();
        let (mut sum, mut bias) = (Vec3::ZERO, Vec3::ZERO);
        let (mut sum8, mut bias8) = ([f32x8::ZERO; 3], [f32x8::ZERO; 3]);
        let mut walk = Walk::<false>::new(self, set, q.p, walked(q.filter.n, on_surface.is_some()));
        while let Some((lo, hi)) = walk.next(self, r2) {
            if set == CodePath::Simd {
                let v = self.accepts8(lo, q.p, r2, &q.filter);
                rejected += v.turned.count_ones();
                off_plane += v.off_plane.count_ones();
                if on_surface.is_some() {
                    // Lane order, as the scalar twin meets them.
                    let mut left = v.turned;
                    while left != 0 {
                        let l = left.trailing_zeros() as usize;
                        left &= left - 1;
                        neighbours.note(self, lo + l, q.p, q.filter.n);
                    }
                }
                if v.bits == 0 {
                    continue;
                }
                count += v.bits.count_ones();
                let power = self.power8(lo);
                if BIAS {
                    let r2_8 = f32x8::splat(r2);
                    let weights = [q.kernel.weight8(v.d2, r2_8), Kernel::bias_weight8(v.d2, r2_8)];
                    let [c, b] = Self::contributions8(v.key, power, v.inside, weights, f);
                    for (s, v) in sum8.iter_mut().zip(c) {
                        *s += v;
                    }
                    for (s, v) in bias8.iter_mut().zip(b) {
                        *s += v;
                    }
                } else {
                    let c = Self::contribution8(v.key, power, v.inside, v.d2, r2, q.kernel, f);
                    for (s, v) in sum8.iter_mut().zip(c) {
                        *s += v;
                    }
                }
            } else {
                for i in lo..hi {
                    let d2 = self.d2(i, q.p);
                    if d2 < r2 {
                        match self.test_at(i, q.p, d2, &q.filter) {
                            Test::Accepted => {
                                if BIAS {
                                    let (c, b) = self.contribution_and_bias(i, d2, r2, q.kernel, f);
                                    sum += c;
                                    bias += b;
                                } else {
                                    sum += self.contribution(i, d2, r2, q.kernel, f);
                                }
                                count += 1;
                            }
                            Test::Normal => {
                                rejected += 1;
                                if on_surface.is_some() {
                                    neighbours.note(self, i, q.p, q.filter.n);
                                }
                            }
                            Test::OffPlane => off_plane += 1,
                            Test::Flags => {}
                        }
                    }
                }
            }
        }
        let (sum, bias) = (sum + reduce3(sum8), bias + reduce3(bias8));
        let found = Found { count, rejected, off_plane };
        self.fixed_estimate::<BIAS>(q, r2, on_surface, &neighbours, [sum, bias], found)
    }

    /// A fixed-radius estimate from its kernel sum and bias sum over the photons found: normalised,
    /// divided by the part of the disk on the query's surface (`on_surface`: the cuts beyond the
    /// `neighbours` the filter met) and, with `BIAS`, its bias.
    #[inline]
    pub(super) fn fixed_estimate<const BIAS: bool>(
        &self,
        q: &Lookup,
        r2: f32,
        on_surface: Option<&[Cut]>,
        neighbours: &Neighbours,
        [sum, bias]: [Vec3; 2],
        found: Found,
    ) -> Estimate {
        let coverage = match on_surface {
            Some(edges) => neighbours.coverage(self, q.p, q.filter.n, r2, q.kernel, edges),
            None => Coverage::WHOLE,
        };
        let radiance = sum * q.kernel.normalisation(r2) / coverage.fraction;
        // A cut disk's bias sum is not zero even for a uniform density: subtract that part.
        let bias = if BIAS {
            (bias - sum * (coverage.bias_weight / coverage.fraction)) * q.kernel.bias_normalisation(r2)
                / coverage.fraction
        } else {
            Vec3::ZERO
        };
        let Found { count, rejected, off_plane } = found;
        Estimate { radiance, bias, radius: q.r_max, count, rejected, off_plane, coverage: coverage.fraction }
    }

    /// The fixed-radius kernel estimate over `found` (distance², index within `q.r_max`), none
    /// tested by the filter: for the photons a caller adds to an estimate.
    #[must_use]
    pub fn estimate_photons(&self, set: CodePath, q: &Lookup, f: Reflectance<'_>, found: &[(f32, u32)]) -> Estimate {
        match self.fixed_radius2(q) {
            Some(r2) => self.sum_estimate(set, q, r2, f, found),
            None => Estimate { radius: q.r_max, ..Default::default() },
        }
    }

    /// The photons within `q.r_max` of `q.p` that `q.filter` sets aside off its flat plane, as
    /// (distance², index) in walk order: for the caller to add the visible ones to a fixed-radius
    /// estimate that reported [`Estimate::off_plane`] of them.
    #[must_use]
    pub fn off_plane_photons(&self, q: &Lookup) -> Vec<(f32, u32)> {
        let mut out = Vec::new();
        let Some(r2) = self.fixed_radius2(q) else { return out };
        let mut walk = Walk::<false>::new(self, CodePath::Scalar, q.p, reachable(q.filter.n));
        while let Some((lo, hi)) = walk.next(self, r2) {
            for i in lo..hi {
                let d2 = self.d2(i, q.p);
                if d2 < r2 && self.test_at(i, q.p, d2, &q.filter) == Test::OffPlane {
                    out.push((d2, i as u32));
                }
            }
        }
        out
    }
}

/// What a fixed-radius walk counted: photons summed, turned away, and set aside off the plane.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Found {
    pub count: u32,
    pub rejected: u32,
    pub off_plane: u32,
}
