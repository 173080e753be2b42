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
//! A search starts from a guess: lookups come in coherent order, so the k nearest mostly lie
//! within a margin of the last search's k-th (`Hint`); a miss walks again under the maximum
//! radius.
//!
//! The order is by (distance², index), so the k nearest are one set whatever order the walk met
//! them in; the SIMD kernel and its scalar twin fill, count and order the same lanes, so both
//! find the same photons and the same radius.

use super::orientation::{reachable, ALL};
use super::tree::Walk;
use super::{Lookup, PhotonMap, Test};
use crate::code_path::CodePath;
use wide::f32x8;

/// Candidates of one k-nearest walk, a block at a time: reusable across lookups (hold one per
/// thread and pass it to each lookup, in a coherent order where there is one: each search starts
/// from the last one's radius, see `Hint`).
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
    /// Squared distances of the photons within the radius (at their block's turn) that the
    /// surface tests turned away, in the blocks the walk tested.
    turned: Vec<f32>,
    /// Squared distances of the photons within the radius set aside off a flat query's plane.
    off: Vec<f32>,
    /// What the last searches found, for the next ones' first guesses: the last two kinds of
    /// search (map and k), most recent first, so that lookups alternating between two maps (the
    /// global and caustic estimates at each camera hit) each follow their own.
    hints: [Option<Hint>; 2],
}

/// What a search left in its [`Nearest`] buffer.
#[derive(Clone, Copy, Debug)]
pub(super) struct Walked {
    /// The final squared radius: every candidate in the buffer within it counts.
    pub r2: f32,
    /// Candidates within `r2`.
    pub live: usize,
    /// Photons within the search radius (the k-th nearest's distance, or the maximum radius when
    /// fewer than k are found) that the normal test turned away, in the blocks the walk tested
    /// (see [`super::Estimate::rejected`]).
    pub rejected: u32,
    /// Photons within that radius set aside off a flat query's plane
    /// ([`super::Estimate::off_plane`]).
    pub off_plane: u32,
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

/// Lookups come in coherent order (camera hits in tiles, gather hits sorted along a curve), so a
/// search first assumes its k nearest lie within a margin of the last search's k-th — where they
/// do, the walk prunes from its first node instead of from the maximum radius; where they do not
/// (fewer than k within the guess), it walks again under the maximum radius. The k nearest are the
/// same either way, and so are the sums, to the bit: they run over the blocks holding the k
/// nearest in the walk's order, and pruning never reorders a walk.
///
/// The margin (on the squared radius) adapts toward the 97th percentile of the ratio between
/// consecutive searches' k-th distances² (a stochastic quantile estimate: up by [`Hint::UP`] after
/// a miss, down by [`Hint::DOWN`] after a hit, so that misses settle at 3 %). A fixed margin's
/// best lay at 1.32 on cornell-box's camera hits and at 1.1 or less on the 1 M-triangle sphere,
/// whose radii vary less (BENCHMARKS.md, "k-nearest lookups from the last one's radius").
#[derive(Clone, Copy, Debug)]
struct Hint {
    /// The map searched, by its address: used only to tell maps apart (a map built where a dropped
    /// one lay inherits its hint, which costs at most a second walk).
    map: usize,
    /// The search's k.
    k: usize,
    /// Its k-th nearest's squared distance.
    d2: f32,
    /// The guess for the next search's k-th is `d2 · margin`.
    margin: f32,
}

impl Hint {
    /// The margin a first guess starts from.
    const START: f32 = 1.32;
    /// After a miss.
    const UP: f32 = 1.1;
    /// After a hit: UP^(−3/97), so that the margin stands still at a 3 % miss rate.
    const DOWN: f32 = 0.997_06;
    /// The margin's range: a guess from the last k-th's distance to twice it.
    const RANGE: (f32, f32) = (1.0, 4.0);
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

    /// Fills `near_kth` with the candidates at squared distances in [a, b), as (distance² bits,
    /// index): a block's lanes tested by two compares in the SIMD kernel, one lane at a time in
    /// its scalar twin.
    fn collect_between(&mut self, set: CodePath, a: f32, b: f32) {
        let key = |d: f32, i: u32| u64::from(d.to_bits()) << 32 | u64::from(i);
        self.near_kth.clear();
        match set {
            CodePath::Simd => {
                // Every lane is written and only those in range advance the end: no branch
                // on the data (a branch per block and per candidate measured 10 % of a lookup).
                let (av, bv) = (f32x8::splat(a), f32x8::splat(b));
                self.near_kth.resize(8 * self.d2.len(), 0);
                let mut n = 0;
                for (d2, &base) in self.d2.iter().zip(&self.base) {
                    let d = f32x8::from(*d2);
                    let m = (d.simd_ge(av) & d.simd_lt(bv)).to_bitmask();
                    for (l, &dl) in d2.iter().enumerate() {
                        self.near_kth[n] = key(dl, base + l as u32);
                        n += (m >> l & 1) as usize;
                    }
                }
                self.near_kth.truncate(n);
            }
            CodePath::Scalar => {
                let mut near = std::mem::take(&mut self.near_kth);
                near.extend(self.lanes().filter(|&(d, _)| d >= a && d < b).map(|(d, i)| key(d, i)));
                self.near_kth = near;
            }
        }
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
        self.collect_between(set, a, b);
        // Distances are non-negative (never −0 or NaN here): their bits order as the values do.
        let (_, &mut kth, _) = self.near_kth.select_nth_unstable(k - ca - 1);
        Kth { d2: f32::from_bits((kth >> 32) as u32), index: kth as u32 }
    }
}

impl PhotonMap {
    /// The search for `q`'s `q.k` nearest: the walk, and the k-th nearest when at least k
    /// candidates lie within the radius (`None` otherwise, or for k = 0).
    /// With `COUNT`, adds the photons its walks test to `tested`.
    pub(super) fn search_nearest<const COUNT: bool>(
        &self,
        set: CodePath,
        q: &Lookup,
        buf: &mut Nearest,
        tested: &mut u64,
    ) -> (Walked, Option<Kth>) {
        let r2_max = q.r_max * q.r_max;
        let map = std::ptr::from_ref(self) as usize;
        if buf.hints[0].is_none_or(|h| (h.map, h.k) != (map, q.k)) {
            buf.hints.swap(0, 1);
            if buf.hints[0].is_none_or(|h| (h.map, h.k) != (map, q.k)) {
                buf.hints[0] = None; // the least recent kind gives way
            }
        }
        let hint = buf.hints[0].filter(|_| q.k > 1);
        let guess = hint.map_or(f32::INFINITY, |h| h.d2 * h.margin);
        let mut walked = self.walk_nearest::<COUNT>(set, q, r2_max.min(guess), buf, tested);
        if walked.live < q.k && guess < r2_max {
            walked = self.walk_nearest::<COUNT>(set, q, r2_max, buf, tested);
        }
        let last = (q.k > 0 && walked.live >= q.k).then(|| buf.kth(set, q.k, walked.live, walked.r2));
        buf.hints[0] = last.map(|kth| {
            let margin = match hint {
                Some(h) if kth.d2 >= h.d2 * h.margin => h.margin * Hint::UP,
                Some(h) => h.margin * Hint::DOWN,
                None => Hint::START,
            };
            Hint { map, k: q.k, d2: kth.d2, margin: margin.clamp(Hint::RANGE.0, Hint::RANGE.1) }
        });
        let bound = last.map_or(r2_max, |kth| kth.d2);
        walked.rejected = buf.turned.iter().filter(|&&d| d < bound).count() as u32;
        walked.off_plane = buf.off.iter().filter(|&&d| d < bound).count() as u32;
        (walked, last)
    }

    /// Walks toward `q.p` gathering the blocks that hold candidates for its `q.k` nearest
    /// within squared radius `r2` into `buf` (cleared first), adding the photons tested to
    /// `tested` when `COUNT`. The walk's `rejected` and `off_plane` are left 0 (the search
    /// counts them).
    fn walk_nearest<const COUNT: bool>(
        &self,
        set: CodePath,
        q: &Lookup,
        mut r2: f32,
        buf: &mut Nearest,
        tested: &mut u64,
    ) -> Walked {
        buf.d2.clear();
        buf.base.clear();
        buf.turned.clear();
        buf.off.clear();
        let k = q.k;
        let mut live = 0usize;
        if k == 0 || self.is_empty() {
            return Walked { r2, live, rejected: 0, off_plane: 0 };
        }
        // The farthest candidate so far (its SIMD form lane by lane).
        let (mut far, mut far8) = (0.0f32, f32x8::ZERO);
        // The nearest alone (a precomputed irradiance point) is found in a short walk, which the
        // class test slows more than it shortens (cornell-spheres' final gather 4 % slower).
        let reach = if k == 1 { ALL } else { reachable(q.filter.n) };
        let mut walk = Walk::<true>::new(self, set, q.p, reach);
        while let Some((lo, hi)) = walk.next(self, r2) {
            if COUNT {
                *tested += (hi - lo) as u64;
            }
            let mut lanes = [f32::INFINITY; 8];
            let found = if set == CodePath::Simd {
                let v = self.accepts8(lo, q.p, r2, &q.filter);
                let (mut turned, mut off) = (v.turned, v.off_plane);
                if turned | off != 0 {
                    let d2 = v.d2.to_array();
                    while turned != 0 {
                        buf.turned.push(d2[turned.trailing_zeros() as usize]);
                        turned &= turned - 1;
                    }
                    while off != 0 {
                        buf.off.push(d2[off.trailing_zeros() as usize]);
                        off &= off - 1;
                    }
                }
                lanes = v.inside.select(v.d2, f32x8::splat(f32::INFINITY)).to_array();
                far8 = far8.fast_max(v.inside.select(v.d2, f32x8::ZERO));
                v.bits.count_ones() as usize
            } else {
                let mut found = 0;
                for i in lo..hi {
                    let d2 = self.d2(i, q.p);
                    if d2 < r2 {
                        match self.test_at(i, q.p, d2, &q.filter) {
                            Test::Accepted => {
                                lanes[i - lo] = d2;
                                far = far.max(d2);
                                found += 1;
                            }
                            Test::Normal => buf.turned.push(d2),
                            Test::OffPlane => buf.off.push(d2),
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
                // Every candidate lies below `top`: the radius, or just beyond the farthest
                // candidate when that is nearer (as it is until the radius first shrinks).
                if set == CodePath::Simd {
                    far = far8.to_array().into_iter().fold(0.0, f32::max);
                }
                let top = r2.min(f32::from_bits(far.to_bits() + 1));
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
        Walked { r2, live, rejected: 0, off_plane: 0 }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Filter, Kernel, Photon};
    use super::*;
    use glam::Vec3;

    /// A search guided by the last one's radius ([`Hint`]) gives the estimate a fresh search
    /// gives, to the bit (radiance, radius, count, photons turned away), on both code paths:
    /// lookups in coherent order (the guess holds), alternating between a dense and a sparse
    /// region (after a dense lookup, the sparse one's guess holds too few: a second walk), with
    /// k changing between lookups, and each point looked up in two maps in turn (one a seventh
    /// as dense). Photons on two facing planes, so the normal test turns some away.
    #[test]
    fn a_guided_search_finds_what_a_fresh_one_does() {
        use super::super::Reflectance;
        let mut rnd = super::super::test_uniforms(5);
        let photons = (0..20_000)
            .map(|i| {
                // Denser toward x = 0 (the radius varies fourfold across the map).
                let x = rnd() * rnd();
                let (y, normal) = if i % 5 == 0 { (0.002, -Vec3::Y) } else { (0.0, Vec3::Y) };
                let wi = Vec3::new(rnd() - 0.5, 1.0, rnd() - 0.5).normalize();
                Photon { position: Vec3::new(x, y, rnd()), power: Vec3::new(1.0, 0.5, 0.25), wi, normal, flags: 0 }
            })
            .collect::<Vec<_>>();
        let sparse = PhotonMap::build(photons.iter().step_by(7).copied().collect());
        let map = PhotonMap::build(photons);
        let f = Reflectance::Hemisphere { value: Vec3::splat(0.3), ng: Vec3::Y };
        let coherent = (0..200).map(|i| (Vec3::new(0.004 * i as f32, 0.0, 0.5), 64));
        let alternating = (0..200).map(|i| (Vec3::new(if i % 2 == 0 { 0.01 } else { 0.9 }, 0.0, 0.3), 64));
        let k_changing = (0..200).map(|i| (Vec3::new(0.3, 0.0, 0.002 * i as f32), [8, 64, 65][i % 3]));
        let mut turned = 0;
        for set in [CodePath::Simd, CodePath::Scalar] {
            let mut guided = Nearest::default();
            let lookups = coherent.clone().chain(alternating.clone()).chain(k_changing.clone());
            for ((p, k), map) in lookups.flat_map(|pk| [(pk, &map), (pk, &sparse)]) {
                let q = Lookup {
                    p,
                    k,
                    r_max: 0.5,
                    kernel: Kernel::Epanechnikov,
                    filter: Filter { n: Vec3::Y, flags_mask: 0, plane: 0.0, slack: 0.0 },
                };
                let a = map.estimate(set, &q, f, &mut guided);
                let b = map.estimate(set, &q, f, &mut Nearest::default());
                assert_eq!(a.radiance.to_array().map(f32::to_bits), b.radiance.to_array().map(f32::to_bits), "{p} {k}");
                assert_eq!((a.radius, a.count, a.rejected), (b.radius, b.count, b.rejected), "{p} {k} {set:?}");
                assert_eq!(a.count as usize, k - 1, "{p} {k}: {a:?}");
                turned += a.rejected;
            }
        }
        assert!(turned > 1000, "{turned} photons turned away");
    }

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
                        let q = Lookup {
                            p,
                            k,
                            r_max,
                            kernel: Kernel::Box,
                            filter: Filter { n: Vec3::Y, flags_mask: 0, plane: 0.0, slack: 0.0 },
                        };
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
