//! k-nearest-neighbour lookups and Jensen's density estimate over them (the (k−1)/(πr²) rule of
//! the module notes), optionally counting only the photons visible from the query. The search is
//! [`super::nearest`]'s; the SIMD estimate sums the k − 1 nearest straight from the blocks the
//! walk kept (no per-photon gather), its scalar twin one photon at a time.

use super::nearest::{Kth, Nearest};
use super::packing::key_normal;
use super::sum::reduce3;
use super::{Estimate, Lookup, PhotonMap, Reflectance};
use crate::code_path::CodePath;
use glam::Vec3;
use wide::{f32x8, u32x8};

impl PhotonMap {
    /// The `q.k` nearest photons to `q.p` within `q.r_max` that pass `q.filter`, as
    /// (distance², index), unordered (all of them within the radius when fewer than k are).
    pub fn nearest<'s>(&self, set: CodePath, q: &Lookup, scratch: &'s mut Nearest) -> &'s [(f32, u32)] {
        self.nearest_counted(set, q, scratch);
        &scratch.found
    }

    /// [`Self::nearest`] into `scratch.found`, returning how many photons the normal test turned
    /// away (see [`Estimate::rejected`]; both code paths count the same photons) and the k-th
    /// nearest when k were found.
    pub(super) fn nearest_counted(&self, set: CodePath, q: &Lookup, scratch: &mut Nearest) -> (u32, Option<Kth>) {
        let (walked, last) = self.search_nearest::<false>(set, q, scratch, &mut 0);
        let mut found = std::mem::take(&mut scratch.found);
        found.clear();
        found.extend(scratch.lanes().filter(|&(d, i)| match last {
            Some(kth) => kth.before(d, i) || (d, i) == (kth.d2, kth.index),
            None => d < walked.r2,
        }));
        scratch.found = found;
        (walked.rejected, last)
    }

    /// Reflected radiance at `q.p` from its k nearest photons: Σ f(wi_p)·Φ_p·K over the
    /// (k−1)-of-k rule above, as if the whole disk lay on the query's surface (k-nearest
    /// estimates are not boundary-corrected: measured no better, BENCHMARKS.md).
    #[inline]
    pub fn estimate(&self, set: CodePath, q: &Lookup, f: Reflectance<'_>, scratch: &mut Nearest) -> Estimate {
        if self.is_empty() {
            return Estimate { radius: q.r_max, ..Default::default() };
        }
        if q.k == 0 {
            return Estimate { radius: 0.0, ..Default::default() };
        }
        let (walked, last) = self.search_nearest::<false>(set, q, scratch, &mut 0);
        let (rejected, off_plane) = (walked.rejected, walked.off_plane);
        // The k-th photon defines r and lies on the boundary: the k − 1 before it are summed.
        // With fewer than k within the maximum radius, all of them over that radius.
        let (r2, count) = match last {
            Some(kth) => (kth.d2, q.k - 1),
            None => (q.r_max * q.r_max, walked.live),
        };
        if !(r2 > 0.0) {
            return Estimate { radius: 0.0, rejected, off_plane, ..Default::default() };
        }
        let sum = match set {
            CodePath::Simd => self.sum_kept8(scratch, r2, last, q, f),
            CodePath::Scalar => self.sum_kept(scratch, r2, last, q, f),
        };
        Estimate {
            radiance: sum * q.kernel.normalisation(r2),
            radius: r2.sqrt(),
            bias: Vec3::ZERO,
            count: count as u32,
            rejected,
            off_plane,
            coverage: 1.0,
        }
    }

    /// Σ f·Φ·K over the candidates in `buf` before `last` (or all within `r2` when `None`), 8
    /// lanes of a kept block at a time, loaded straight from the map's columns.
    fn sum_kept8(&self, buf: &Nearest, r2: f32, last: Option<Kth>, q: &Lookup, f: Reflectance<'_>) -> Vec3 {
        let bound = f32x8::splat(r2);
        let mut acc = [f32x8::ZERO; 3];
        for (d2, &base) in buf.d2.iter().zip(&buf.base) {
            let d = f32x8::from(*d2);
            let mut keep = d.simd_lt(bound);
            if let Some(kth) = last {
                // Photons exactly as far as the k-th come before it by index.
                let ties = d.simd_eq(bound);
                if ties.any() {
                    let index = u32x8::splat(base) + u32x8::from([0, 1, 2, 3, 4, 5, 6, 7]);
                    let earlier: f32x8 = wide::bytemuck::cast(u32x8::splat(kth.index).simd_gt(index));
                    keep |= ties & earlier;
                }
            }
            if keep.none() {
                continue;
            }
            let base = base as usize;
            let c = Self::contribution8(self.key8(base), self.power8(base), keep, d, r2, q.kernel, f);
            for (a, v) in acc.iter_mut().zip(c) {
                *a += v;
            }
        }
        reduce3(acc)
    }

    /// Scalar twin of [`Self::sum_kept8`]: the same candidates, one photon at a time.
    fn sum_kept(&self, buf: &Nearest, r2: f32, last: Option<Kth>, q: &Lookup, f: Reflectance<'_>) -> Vec3 {
        let mut sum = Vec3::ZERO;
        for (d, i) in buf.lanes() {
            let keep = match last {
                Some(kth) => kth.before(d, i),
                None => d < r2,
            };
            if keep {
                sum += self.contribution(i as usize, d, r2, q.kernel, f);
            }
        }
        sum
    }

    /// The squared radius of a k-nearest estimate over `found`, a baseline search's candidates
    /// (the k-th photon's distance, that photon removed: it lies on the boundary; or `q.r_max`²
    /// when fewer were found); `None` for a zero radius.
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
    /// photons for which `visible(position, normal)` holds: the k nearest *visible* photons set
    /// the radius, so that photons behind a wall neither count nor widen it (choosing the radius
    /// among all photons left a floor 1 cm above a sunlit ground 6.5 % dark: its k nearest were
    /// mostly the ground's). The search widens (k doubled) until k visible photons are found or
    /// every photon within the maximum radius has been tested; with fewer, all the visible ones
    /// over the maximum radius.
    pub fn estimate_visible(
        &self,
        set: CodePath,
        q: &Lookup,
        f: Reflectance<'_>,
        scratch: &mut Nearest,
        visible: &dyn Fn(Vec3, Vec3) -> bool,
    ) -> Estimate {
        if self.is_empty() {
            return Estimate { radius: q.r_max, ..Default::default() };
        }
        let r2_max = q.r_max * q.r_max;
        let is_visible =
            |i: u32| visible(self.position(i as usize), key_normal(self.key[i as usize]).normalize_or_zero());
        if q.k == 0 {
            // Every visible photon within the fixed radius (a bound no search reaches).
            let (rejected, _) = self.nearest_counted(set, &Lookup { k: usize::MAX, ..*q }, scratch);
            if !(r2_max > 0.0) || !r2_max.is_finite() {
                return Estimate { radius: q.r_max, ..Default::default() };
            }
            scratch.found.retain(|&(_, i)| is_visible(i));
            return Estimate { rejected, ..self.sum_estimate(set, q, r2_max, f, &scratch.found) };
        }
        let mut wanted = q.k;
        let (rejected, mut seen) = loop {
            let (rejected, last) = self.nearest_counted(set, &Lookup { k: wanted, ..*q }, scratch);
            let mut seen: Vec<(f32, u32)> = scratch.found.iter().copied().filter(|&(_, i)| is_visible(i)).collect();
            if seen.len() >= q.k || last.is_none() || wanted == usize::MAX {
                seen.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                break (rejected, seen);
            }
            wanted = wanted.saturating_mul(2);
        };
        // The k-th visible photon defines r and lies on the boundary: the k − 1 before it are
        // summed, as in [`Self::estimate`]; with fewer than k, all of them over the maximum radius.
        let r2 = if seen.len() >= q.k {
            let r2 = seen[q.k - 1].0;
            seen.truncate(q.k - 1);
            r2
        } else {
            r2_max
        };
        if !(r2 > 0.0) || !r2.is_finite() {
            return Estimate { radius: 0.0, rejected, ..Default::default() };
        }
        Estimate { rejected, ..self.sum_estimate(set, q, r2, f, &seen) }
    }
}
