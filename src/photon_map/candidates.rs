//! Estimates over photons another search found (`photonwave bench`'s kiddo baseline), and the
//! count of photons a lookup of ours tests: the yardsticks of the density benchmark. Reads the
//! map and a candidate list; writes an [`Estimate`] or a count.
//!
//! A baseline search returns the nearest photons by distance alone; the photons a lookup may
//! use are then picked here as [`PhotonMap::estimate`] and [`PhotonMap::estimate_radius`]
//! pick them (the [`super::Filter`], the (k−1) rule) and summed by the scalar kernel, so that
//! the baseline pays for the same estimate. (Its k nearest are taken before the normal test,
//! ours after it: at corners the two sum slightly different photons.)

use super::orientation::reachable;
use super::{Estimate, Lookup, PhotonMap, Reflectance, Test};
use crate::code_path::CodePath;

impl PhotonMap {
    /// Jensen's k-nearest estimate over `found` (distance², index), the k nearest of a
    /// baseline's search within `q.r_max`: those the filter turns away are dropped, then the
    /// (k−1) rule and the scalar kernel sum of [`Self::estimate`].
    pub fn estimate_from_candidates(&self, q: &Lookup, f: Reflectance<'_>, found: &mut Vec<(f32, u32)>) -> Estimate {
        let all = found.len();
        found.retain(|&(d2, i)| self.test_at(i as usize, q.p, d2, &q.filter) == Test::Accepted);
        // The (k−1) rule applies when the search filled k: the k-th photon sets the radius.
        let q = if all == q.k { Lookup { k: found.len(), ..*q } } else { Lookup { k: usize::MAX, ..*q } };
        let Some(r2) = Self::knn_radius2(&q, found) else {
            return Estimate::default();
        };
        self.sum_estimate(CodePath::Scalar, &q, r2, f, found)
    }

    /// The fixed-radius estimate of [`Self::estimate_radius`] (without its bias) over `found`,
    /// every photon a baseline's search found within `q.r_max`: the filter, then the scalar
    /// kernel sum.
    pub fn estimate_radius_from_candidates(
        &self,
        q: &Lookup,
        f: Reflectance<'_>,
        found: &mut Vec<(f32, u32)>,
    ) -> Estimate {
        let r2 = q.r_max * q.r_max;
        found.retain(|&(d2, i)| d2 < r2 && self.test_at(i as usize, q.p, d2, &q.filter) == Test::Accepted);
        Estimate { radius: q.r_max, ..self.sum_estimate(CodePath::Scalar, q, r2, f, found) }
    }

    /// Photons the tree walk tests for a fixed-radius lookup (`q.k == 0`, not boundary-corrected)
    /// or a k-nearest one: the photons of every block it reaches, past the subtrees facing away
    /// (the scalar and SIMD lookups walk alike). A
    /// k-nearest search reads and leaves `scratch`'s hint as a lookup does (pass the same
    /// scratch through the lookups in their order to count what they test).
    #[must_use]
    pub fn photons_tested(&self, q: &Lookup, scratch: &mut super::Nearest) -> u64 {
        if self.is_empty() {
            return 0;
        }
        let mut tested = 0u64;
        if q.k == 0 {
            let r2 = q.r_max * q.r_max;
            let mut walk = super::tree::Walk::<false>::new(self, CodePath::Scalar, q.p, reachable(q.filter.n));
            while let Some((lo, hi)) = walk.next(self, r2) {
                tested += (hi - lo) as u64;
            }
        } else {
            self.search_nearest::<true>(CodePath::Scalar, q, scratch, &mut tested);
        }
        tested
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Filter, Kernel, Photon};
    use super::*;
    use glam::Vec3;

    /// Every photon within the radius, found by brute force, gives the fixed-radius estimate of
    /// the tree's own lookup (same photons, same count; sums to rounding), and the walk tests at
    /// least the photons it sums.
    #[test]
    fn candidates_found_elsewhere_give_the_same_estimate() {
        let mut rnd = super::super::test_uniforms(99);
        // Half the photons on the floor, half on a wall facing another way (filtered out).
        let photons: Vec<Photon> = (0..4000)
            .map(|i| {
                let (position, normal) = if i % 2 == 0 {
                    (Vec3::new(rnd(), 0.0, rnd()), Vec3::Y)
                } else {
                    (Vec3::new(rnd(), rnd(), 0.0), Vec3::Z)
                };
                Photon { position, power: Vec3::splat(1e-3), wi: normal, normal, flags: 0 }
            })
            .collect();
        let map = PhotonMap::build(photons);
        let f = Reflectance::Constant(Vec3::ONE);
        for p in [Vec3::new(0.5, 0.0, 0.5), Vec3::new(0.3, 0.0, 0.02)] {
            let q = Lookup {
                p,
                k: 0,
                r_max: 0.1,
                kernel: Kernel::Epanechnikov,
                filter: Filter { n: Vec3::Y, flags_mask: 0, plane: 0.0, slack: 0.0 },
            };
            let ours = map.estimate_radius_with(CodePath::Scalar, &q, f, None, false);
            let mut found: Vec<(f32, u32)> = (0..map.len())
                .map(|i| ((map.position(i) - p).length_squared(), i as u32))
                .filter(|&(d2, _)| d2 < 0.01)
                .collect();
            let theirs = map.estimate_radius_from_candidates(&q, f, &mut found);
            assert_eq!(theirs.count, ours.count);
            assert!(
                (theirs.radiance - ours.radiance).abs().max_element() <= 1e-5 * ours.radiance.x,
                "{theirs:?} {ours:?}"
            );
            assert!(
                map.photons_tested(&q, &mut super::super::Nearest::default())
                    >= u64::from(ours.count) + u64::from(ours.rejected)
            );
        }
    }
}
