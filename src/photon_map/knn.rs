//! k-nearest-neighbour lookups and Jensen's density estimate over them (the (k−1)/(πr²) rule of
//! the module notes), optionally counting only the photons visible from the query. The SIMD
//! kernel and its scalar twin share the walk and the k-selection and visit photons in the same
//! order, so both find the same photons.

use super::packing::key_normal;
use super::tree::Walk;
use super::{Estimate, Lookup, PhotonMap, Reflectance, Test};
use crate::code_path::CodePath;
use glam::Vec3;

impl PhotonMap {
    /// The `k` nearest photons to `q.p` within `q.r_max` that pass `q.filter`, as
    /// (distance², index), unordered, into `out`.
    pub fn nearest(&self, set: CodePath, q: &Lookup, out: &mut Vec<(f32, u32)>) {
        self.nearest_counted(set, q, out);
    }

    /// [`Self::nearest`], returning how many photons the normal test turned away (see
    /// [`Estimate::rejected`]); both code paths count the same photons.
    #[inline]
    pub(super) fn nearest_counted(&self, set: CodePath, q: &Lookup, out: &mut Vec<(f32, u32)>) -> u32 {
        self.nearest_walk::<false>(set, q, out, &mut 0)
    }

    /// [`Self::nearest_counted`], adding the photons its walk tests to `tested` when `COUNT`.
    #[inline]
    pub(super) fn nearest_walk<const COUNT: bool>(
        &self,
        set: CodePath,
        q: &Lookup,
        out: &mut Vec<(f32, u32)>,
        tested: &mut u64,
    ) -> u32 {
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
        let mut walk = Walk::<true>::new(self, set, q.p);
        while let Some((lo, hi)) = walk.next(self, r2) {
            if COUNT {
                *tested += (hi - lo) as u64;
            }
            if set == CodePath::Simd {
                let v = self.accepts8(lo, q.p, r2, &q.filter);
                let d2 = v.d2.to_array();
                // Lane order, as the scalar twin walks them: r² may have shrunk since the
                // 8-wide test, so each lane is re-checked at its turn.
                let mut all = v.bits | v.turned;
                while all != 0 {
                    let l = all.trailing_zeros() as usize;
                    all &= all - 1;
                    if d2[l] < r2 {
                        if v.bits >> l & 1 == 1 {
                            offer(out, &mut r2, d2[l], lo + l);
                        } else {
                            rejected += 1;
                        }
                    }
                }
            } else {
                for i in lo..hi {
                    let d2 = self.d2(i, q.p);
                    if d2 < r2 {
                        match Self::test(self.key[i], &q.filter) {
                            Test::Accepted => offer(out, &mut r2, d2, i),
                            Test::Normal => rejected += 1,
                            Test::Flags => {}
                        }
                    }
                }
            }
        }
        if out.len() > k {
            out.select_nth_unstable_by_key(k - 1, by_distance);
            out.truncate(k);
        }
        rejected
    }

    /// Reflected radiance at `q.p` from its k nearest photons: Σ f(wi_p)·Φ_p·K over the
    /// (k−1)-of-k rule above, as if the whole disk lay on the query's surface (k-nearest
    /// estimates are not boundary-corrected: measured no better, BENCHMARKS.md).
    #[inline]
    pub fn estimate(&self, set: CodePath, q: &Lookup, f: Reflectance<'_>, scratch: &mut Vec<(f32, u32)>) -> Estimate {
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
    #[inline]
    pub(super) fn knn_radius2(q: &Lookup, found: &mut Vec<(f32, u32)>) -> Option<f32> {
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

    /// [`Self::estimate`] (or, with `q.k == 0`, [`Self::estimate_radius`]) counting only the
    /// photons for which `visible(position, normal)` holds. The radius is chosen among all
    /// photons, as without the test: where every photon near a point lies behind a wall, the
    /// estimate there is zero.
    pub fn estimate_visible(
        &self,
        set: CodePath,
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
}
