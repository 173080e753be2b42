//! The k nearest photons of a lookup, under its maximum radius: the search behind Jensen's
//! density estimate. Reads the map; writes a [`Nearest`] buffer.
//!
//! The walk visits blocks nearest first and keeps every block holding a candidate (a photon within
//! the radius that passes the filter) whole, its other lanes at +∞. Nothing is ordered while it
//! walks: once k + a few candidates have gathered, the radius shrinks to a guess r'² = r²·(k+1)/n
//! (photons on a surface: their number grows as r²) if a count shows at least k candidates
//! within it. At the end the k-th nearest is found the same way — counts narrow a range of
//! distances until at most a few candidates lie in it, and those few are ordered. A count of 8
//! candidates is one compare, so the k-th costs a handful of passes over ~20 blocks instead of
//! ordering ~130 candidates (BENCHMARKS.md, "k-nearest lookups by counting").
//!
//! The order is by (distance², index), so the k nearest are one set whatever order the walk met
//! them in; the SIMD kernel and its scalar twin fill, count and order the same lanes, so both
//! find the same photons and the same radius.

use super::tree::Walk;
use super::{Lookup, PhotonMap, Test};
use crate::code_path::CodePath;
use wide::f32x8;

/// Candidates of one k-nearest walk, a block at a time: reusable across lookups (hold one per
/// thread and pass it to each lookup).
#[derive(Clone, Debug, Default)]
pub struct Nearest {
    /// Per block, the squared distance of each lane that holds a candidate; +∞ elsewhere.
    pub(super) d2: Vec<[f32; 8]>,
    /// Per block, its first photon.
    pub(super) base: Vec<u32>,
    /// Candidates near the k-th, as (distance² bits, index), to be ordered.
    near_kth: Vec<u64>,
    /// The photons [`PhotonMap::nearest`] lists.
    pub(super) found: Vec<(f32, u32)>,
}

/// What a walk left in its [`Nearest`] buffer.
#[derive(Clone, Copy, Debug)]
pub(super) struct Walked {
    /// The final squared radius: every candidate in the buffer within it counts.
    pub r2: f32,
    /// Candidates within `r2`.
    pub live: usize,
    /// Photons within the radius at their block's turn that the normal test turned away (see
    /// [`super::Estimate::rejected`]).
    pub rejected: u32,
}

/// The k-th nearest candidate, as (distance², index); the k nearest are those up to it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Kth {
    pub d2: f32,
    pub index: u32,
}

impl Kth {
    /// Whether a candidate at `d2`, photon `index`, comes before the k-th.
    #[inline]
    pub(super) fn before(self, d2: f32, index: u32) -> bool {
        d2 < self.d2 || (d2 == self.d2 && index < self.index)
    }
}

/// Candidates beyond k before the radius is shrunk: a count costs a pass over the buffer, so it is
/// not worth making for every block.
fn slack(k: usize) -> usize {
    k / 8 + 1
}

impl Nearest {
    /// Candidates closer than `t` (squared): one compare per block of 8 in the SIMD kernel, one per
    /// lane in its scalar twin.
    #[inline]
    fn count_below(&self, set: CodePath, t: f32) -> usize {
        match set {
            CodePath::Simd => {
                let tv = f32x8::splat(t);
                self.d2.iter().map(|&d| f32x8::from(d).simd_lt(tv).to_bitmask().count_ones() as usize).sum()
            }
            CodePath::Scalar => self.d2.iter().flatten().filter(|&&d| d < t).count(),
        }
    }

    /// Every lane in the buffer as (distance², photon index), +∞ where no candidate is.
    pub(super) fn lanes(&self) -> impl Iterator<Item = (f32, u32)> + '_ {
        self.d2
            .iter()
            .zip(&self.base)
            .flat_map(|(d2, &base)| d2.iter().enumerate().map(move |(l, &d)| (d, base + l as u32)))
    }

    /// The farthest candidate's squared distance (0 for none).
    fn farthest(&self) -> f32 {
        self.d2.iter().flatten().filter(|d| d.is_finite()).fold(0.0, |m: f32, &d| m.max(d))
    }

    /// Drops the blocks with no candidate within `r2`, keeping the others in order (the passes
    /// stay short when the radius has shrunk far).
    fn drop_dead(&mut self, r2: f32) {
        let mut kept = 0;
        for b in 0..self.d2.len() {
            if self.d2[b].iter().any(|&d| d < r2) {
                self.d2[kept] = self.d2[b];
                self.base[kept] = self.base[b];
                kept += 1;
            }
        }
        self.d2.truncate(kept);
        self.base.truncate(kept);
    }

    /// The `k`-th nearest of `live` ≥ `k` candidates all within `r2`: counts narrow the range of
    /// distances that holds it (by the candidates' spread, as the walk's guess, or by halves
    /// when that is slow) to at most 16 candidates, which are then ordered.
    pub(super) fn kth(&mut self, set: CodePath, k: usize, live: usize, r2: f32) -> Kth {
        // count(d² < a) = ca < k ≤ cb = count(d² < b); distances are never negative.
        let (mut a, mut ca, mut b, mut cb) = (0.0f32, 0usize, r2, live);
        let mut halve = false;
        while cb - ca > 16 {
            let width = cb - ca;
            let g = if halve { 0.5 * (a + b) } else { a + (b - a) * ((k - ca) as f32 + 0.5) / width as f32 };
            if !(g > a && g < b) {
                break; // as narrow as the distances' precision allows
            }
            let c = self.count_below(set, g);
            if c >= k {
                (b, cb) = (g, c);
            } else {
                (a, ca) = (g, c);
            }
            halve = 2 * (cb - ca) > width;
        }
        let mut near_kth = std::mem::take(&mut self.near_kth);
        near_kth.clear();
        near_kth.extend(
            self.lanes().filter(|&(d, _)| d >= a && d < b).map(|(d, i)| u64::from(d.to_bits()) << 32 | u64::from(i)),
        );
        self.near_kth = near_kth;
        // Distances are non-negative (never −0 or NaN here): their bits order as the values do.
        let (_, &mut kth, _) = self.near_kth.select_nth_unstable(k - ca - 1);
        Kth { d2: f32::from_bits((kth >> 32) as u32), index: kth as u32 }
    }
}

impl PhotonMap {
    /// The search for `q`'s `q.k` nearest: the walk, and the k-th nearest when at least k
    /// candidates lie within the radius (`None` otherwise, or for k = 0).
    pub(super) fn search_nearest(&self, set: CodePath, q: &Lookup, buf: &mut Nearest) -> (Walked, Option<Kth>) {
        let walked = self.walk_nearest::<false>(set, q, buf, &mut 0);
        let last = (q.k > 0 && walked.live >= q.k).then(|| buf.kth(set, q.k, walked.live, walked.r2));
        (walked, last)
    }

    /// Walks toward `q.p` gathering the blocks that hold candidates for its `q.k` nearest into
    /// `buf` (cleared first), adding the photons tested to `tested` when `COUNT`.
    pub(super) fn walk_nearest<const COUNT: bool>(
        &self,
        set: CodePath,
        q: &Lookup,
        buf: &mut Nearest,
        tested: &mut u64,
    ) -> Walked {
        buf.d2.clear();
        buf.base.clear();
        let k = q.k;
        let mut r2 = q.r_max * q.r_max;
        let (mut live, mut rejected) = (0usize, 0u32);
        if k == 0 || self.is_empty() {
            return Walked { r2, live, rejected };
        }
        let mut walk = Walk::<true>::new(self, set, q.p);
        while let Some((lo, hi)) = walk.next(self, r2) {
            if COUNT {
                *tested += (hi - lo) as u64;
            }
            let mut lanes = [f32::INFINITY; 8];
            let found = if set == CodePath::Simd {
                let v = self.accepts8(lo, q.p, r2, &q.filter);
                rejected += v.turned.count_ones();
                lanes = v.inside.select(v.d2, f32x8::splat(f32::INFINITY)).to_array();
                v.bits.count_ones() as usize
            } else {
                let mut found = 0;
                for i in lo..hi {
                    let d2 = self.d2(i, q.p);
                    if d2 < r2 {
                        match Self::test(self.key[i], &q.filter) {
                            Test::Accepted => {
                                lanes[i - lo] = d2;
                                found += 1;
                            }
                            Test::Normal => rejected += 1,
                            Test::Flags => {}
                        }
                    }
                }
                found
            };
            if found == 0 {
                continue;
            }
            buf.d2.push(lanes);
            buf.base.push(lo as u32);
            live += found;
            if k == 1 {
                // The nearest alone (precomputed-irradiance lookups): just beyond the best so far.
                let best = lanes.iter().fold(f32::INFINITY, |m, &d| m.min(d));
                r2 = f32::from_bits(best.to_bits() + 1);
                live = buf.count_below(set, r2);
            } else if live >= k.saturating_add(slack(k)) {
                // The first guess of an unbounded lookup is the farthest candidate's distance.
                let top = if r2.is_finite() { r2 } else { f32::from_bits(buf.farthest().to_bits() + 1) };
                let t = top * ((k + 1) as f32 / live as f32);
                let c = if t < r2 { buf.count_below(set, t) } else { 0 };
                if c >= k {
                    (r2, live) = (t, c);
                    if buf.d2.len() * 8 > 4 * (live + 8) {
                        buf.drop_dead(r2);
                    }
                }
            }
        }
        Walked { r2, live, rejected }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Filter, Kernel, Photon};
    use super::*;
    use glam::Vec3;

    /// The k nearest by (distance², index), found by ordering every photon: on a lattice, where
    /// many photons lie exactly as far from the query (the counts cannot split them and the
    /// index must), and among scattered ones; bounded and unbounded radii, k from 1 to more
    /// than the map holds, both code paths.
    #[test]
    fn the_k_nearest_are_the_first_k_by_distance_then_index() {
        let mut rnd = super::super::test_uniforms(31);
        let lattice = (0..900).map(|i| Vec3::new((i % 30) as f32 * 0.01, 0.0, (i / 30) as f32 * 0.01));
        let scattered: Vec<Vec3> = (0..3000).map(|_| Vec3::new(rnd(), 0.0, rnd())).collect();
        for positions in [lattice.collect::<Vec<_>>(), scattered] {
            let photons = positions
                .iter()
                .map(|&position| Photon { position, power: Vec3::ONE, wi: Vec3::Y, normal: Vec3::Y, flags: 0 })
                .collect();
            let map = PhotonMap::build(photons);
            let mut buf = Nearest::default();
            for p in [Vec3::new(0.15, 0.0, 0.15), Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.123, 0.0, 0.071)] {
                for r_max in [0.05, 0.3, f32::INFINITY] {
                    for k in [1, 2, 7, 64, 500, 5000] {
                        let q =
                            Lookup { p, k, r_max, kernel: Kernel::Box, filter: Filter { n: Vec3::Y, flags_mask: 0 } };
                        let mut want: Vec<(u32, u32)> = (0..map.len())
                            .map(|i| ((map.position(i) - p).length_squared(), i as u32))
                            .filter(|&(d2, _)| d2 < r_max * r_max)
                            .map(|(d2, i)| (d2.to_bits(), i))
                            .collect();
                        want.sort_unstable();
                        want.truncate(k);
                        for set in [CodePath::Simd, CodePath::Scalar] {
                            let mut got: Vec<(u32, u32)> =
                                map.nearest(set, &q, &mut buf).iter().map(|&(d2, i)| (d2.to_bits(), i)).collect();
                            got.sort_unstable();
                            assert_eq!(got, want, "{set:?} {p} r_max {r_max} k {k}");
                        }
                    }
                }
            }
        }
    }
}
