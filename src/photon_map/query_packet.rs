//! Query packets: up to 8 fixed-radius estimates sharing one walk of the photon tree. Reads the
//! queries (point, radius, filter, reflectance, open edges) and the map; writes one [`Estimate`]
//! per query.
//!
//! Each node is tested against every query still in the packet (the node test of a single walk,
//! query by query), and a child is visited with the set of queries whose sphere reaches it. A
//! block reached by several queries is loaded once and its normals, flags, powers and incoming
//! directions are decoded once; only the distance, the filter's dot products, the kernel weights
//! and the sums are per query. Visiting children in the single walk's order (a node's leaves in
//! slot order, then its inner children in slot order) means each query meets the same blocks in
//! the same order as its own walk would, with the same arithmetic: every estimate is identical
//! to the bit to [`PhotonMap::estimate_radius_with`] on the SIMD code path. The scalar twin is
//! that estimate on the scalar path, one query at a time.
//!
//! Queries pay off together only where their spheres overlap: in cornell-spheres' progressive
//! passes a packet reaches 1.6 times the blocks one of its queries reaches, and each block it
//! reaches serves 4.9 of its 8 queries (BENCHMARKS.md).

use super::boundary::{Cut, Neighbours};
use super::filter::Normals8;
use super::orientation::walked;
use super::sum::{reduce3, Decoded8};
use super::tree::{Node, LEAF, STACK};
use super::{Estimate, Kernel, Lookup, PhotonMap, Reflectance};
use crate::code_path::CodePath;
use glam::Vec3;
use wide::f32x8;

/// Queries in one packet.
pub const PACKET: usize = 8;

/// One fixed-radius estimate of a packet: the lookup (its `r_max` is the radius), the BSDF seen
/// by its photons, and the open edges of its surface for the boundary correction (`None`: no
/// correction), as [`PhotonMap::estimate_radius_with`] takes them.
#[derive(Clone, Copy)]
pub struct RadiusQuery<'a> {
    /// Point, radius, kernel and filter.
    pub lookup: Lookup,
    /// The BSDF seen by the photons.
    pub f: Reflectance<'a>,
    /// Cuts of the disk the photons cannot show; `None` for no boundary correction.
    pub edges: Option<&'a [Cut]>,
}

/// Bit `c` of a byte moved to bit 0 of byte `c`: a child mask spread into per-child bytes.
const SPREAD: [u64; 256] = {
    let mut table = [0u64; 256];
    let mut m = 0;
    while m < 256 {
        let mut c = 0;
        while c < 8 {
            table[m] |= ((m as u64 >> c) & 1) << (8 * c);
            c += 1;
        }
        m += 1;
    }
    table
};

/// Per-query running sums of a packet.
#[derive(Clone, Copy, Default)]
struct Sums {
    radiance: [f32x8; 3],
    bias: [f32x8; 3],
    count: u32,
    rejected: u32,
    off_plane: u32,
    neighbours: Neighbours,
}

impl PhotonMap {
    /// The estimates of up to [`PACKET`] `queries` (one per query, into `out`), each as
    /// [`Self::estimate_radius_with`] would give it, with the bias estimated only if `bias`.
    ///
    /// # Panics
    /// If `queries` holds more than [`PACKET`] queries or `out` is shorter than `queries`.
    pub fn estimate_radius_packet(&self, set: CodePath, queries: &[RadiusQuery<'_>], bias: bool, out: &mut [Estimate]) {
        assert!(
            queries.len() <= PACKET && out.len() >= queries.len(),
            "a packet holds at most {PACKET} queries, and needs an estimate slot for each"
        );
        if set == CodePath::Scalar || queries.len() == 1 {
            for (q, e) in queries.iter().zip(out.iter_mut()) {
                *e = self.estimate_radius_with(set, &q.lookup, q.f, q.edges, bias);
            }
        } else if bias {
            self.packet_fixed::<true>(queries, out);
        } else {
            self.packet_fixed::<false>(queries, out);
        }
    }

    /// The packet walk: [`Self::estimate_radius_packet`] on the SIMD path, with the bias if `BIAS`.
    fn packet_fixed<const BIAS: bool>(&self, queries: &[RadiusQuery<'_>], out: &mut [Estimate]) {
        let r2: [f32; PACKET] =
            std::array::from_fn(|j| queries.get(j).map_or(0.0, |q| q.lookup.r_max * q.lookup.r_max));
        // Queries a single estimate would answer with nothing: no photons, no radius, or a point
        // at no finite distance from any photon.
        let live = queries.iter().enumerate().fold(0u8, |m, (j, q)| {
            let ok = self.fixed_radius2(&q.lookup).is_some() && q.lookup.p.is_finite();
            m | u8::from(ok) << j
        });
        // The classes each query's walk visits, as `estimate_radius_with` walks.
        let classes: [u8; PACKET] =
            std::array::from_fn(|j| queries.get(j).map_or(0, |q| walked(q.lookup.filter.n, q.edges.is_some())));
        let mut sums = [Sums::default(); PACKET];
        let mut stack = [(0u32, 0u8); STACK];
        let mut top = usize::from(live != 0);
        stack[0] = (0, live);
        while top > 0 {
            top -= 1;
            let (index, qmask) = stack[top];
            let node = &self.nodes[index as usize];
            let (reach, reached) = Self::node_reach(node, queries, &r2, &classes, qmask);
            // Leaves first, in slot order; inner children pushed last slot first, so that they are
            // popped in slot order: the order of a single fixed-radius walk. (The set bits of the
            // reached children, not a test of every slot: `gather_global` on cornell-spheres
            // 1.60–1.63 → 1.50–1.58 s.)
            let mut leaves = reached & node.leaves;
            while leaves != 0 {
                let c = leaves.trailing_zeros() as usize;
                leaves &= leaves - 1;
                let (lo, _) = self.block(node.child[c]);
                self.packet_block::<BIAS>(lo, queries, &r2, reach[c], &mut sums);
            }
            let mut inner = reached & !node.leaves;
            while inner != 0 {
                let c = 7 - inner.leading_zeros() as usize;
                inner &= !(1 << c);
                debug_assert_eq!(node.child[c] & LEAF, 0);
                stack[top] = (node.child[c], reach[c]);
                top += 1;
            }
        }
        for (j, q) in queries.iter().enumerate() {
            out[j] = self.finish::<BIAS>(&q.lookup, q.edges, &sums[j]);
        }
    }

    /// For each of `node`'s 8 children, the queries of `qmask` whose sphere reaches its box and
    /// whose `classes` it holds photons of, as bits (child `c`'s in byte `c`), and the children
    /// some query reaches, as bits.
    #[inline]
    fn node_reach(
        node: &Node,
        queries: &[RadiusQuery<'_>],
        r2: &[f32; PACKET],
        classes: &[u8; PACKET],
        qmask: u8,
    ) -> ([u8; 8], u8) {
        let (mut reach, mut reached) = (0u64, 0u32);
        let mut left = qmask;
        while left != 0 {
            let j = left.trailing_zeros() as usize;
            left &= left - 1;
            let (_, hits) = node.distances8(queries[j].lookup.p, r2[j]);
            let hits = hits & node.facing8(classes[j]);
            reach |= SPREAD[hits as usize] << j;
            reached |= hits;
        }
        (reach.to_le_bytes(), reached as u8)
    }

    /// Tests the block of 8 photons from `lo` against the queries of `qmask` and adds what each
    /// accepts to its sums: the photons are decoded once, for all of them.
    ///
    /// A query that finds no photon of the block runs on and adds zeros (a sum plus +0 is the
    /// same sum, to the bit): skipping it was a branch mispredicted often enough to cost 4 % of
    /// `gather_global` on cornell-spheres (BENCHMARKS.md, issue 18, tenth part).
    #[inline]
    fn packet_block<const BIAS: bool>(
        &self,
        lo: usize,
        queries: &[RadiusQuery<'_>],
        r2: &[f32; PACKET],
        qmask: u8,
        sums: &mut [Sums; PACKET],
    ) {
        let load = |c: &[f32]| f32x8::from(<[f32; 8]>::try_from(&c[lo..lo + 8]).expect("padded column"));
        let (x, y, z) = (load(&self.x), load(&self.y), load(&self.z));
        let key = self.key8(lo);
        let (mut normals, mut photons) = (Normals8::decode(key), Decoded8::new(key, self.power8(lo)));
        let mut left = qmask;
        while left != 0 {
            let j = left.trailing_zeros() as usize;
            left &= left - 1;
            let q = &queries[j].lookup;
            let (dx, dy, dz) = (x - f32x8::splat(q.p.x), y - f32x8::splat(q.p.y), z - f32x8::splat(q.p.z));
            let d2 = dx * dx + dy * dy + dz * dz;
            let near = d2.simd_lt(f32x8::splat(r2[j]));
            let super::filter::Filtered8 { inside, turned, off_plane } =
                Self::filter8(&mut normals, near, &q.filter, [dx, dy, dz], d2);
            let s = &mut sums[j];
            s.rejected += turned.count_ones();
            s.off_plane += off_plane.count_ones();
            if queries[j].edges.is_some() {
                // Lane order, as the scalar twin meets them.
                let mut t = turned;
                while t != 0 {
                    let l = t.trailing_zeros() as usize;
                    t &= t - 1;
                    s.neighbours.note(self, lo + l, q.p, q.filter.n);
                }
            }
            let bits = inside.to_bitmask();
            s.count += bits.count_ones();
            let r2_8 = f32x8::splat(r2[j]);
            if BIAS {
                let weights = [q.kernel.weight8(d2, r2_8), Kernel::bias_weight8(d2, r2_8)];
                let [c, b] = Self::contributions8_decoded(&mut photons, inside, weights, queries[j].f);
                for (s, v) in s.radiance.iter_mut().zip(c) {
                    *s += v;
                }
                for (s, v) in s.bias.iter_mut().zip(b) {
                    *s += v;
                }
            } else {
                let [c] =
                    Self::contributions8_decoded(&mut photons, inside, [q.kernel.weight8(d2, r2_8)], queries[j].f);
                for (s, v) in s.radiance.iter_mut().zip(c) {
                    *s += v;
                }
            }
        }
    }

    /// One query's estimate from its sums, as [`Self::estimate_radius_with`] finishes it.
    fn finish<const BIAS: bool>(&self, q: &Lookup, edges: Option<&[Cut]>, s: &Sums) -> Estimate {
        let Some(r2) = self.fixed_radius2(q) else {
            return Estimate { radius: q.r_max, ..Default::default() };
        };
        let sums = [Vec3::ZERO + reduce3(s.radiance), Vec3::ZERO + reduce3(s.bias)];
        let found = super::radius::Found { count: s.count, rejected: s.rejected, off_plane: s.off_plane };
        self.fixed_estimate::<BIAS>(q, r2, edges, &s.neighbours, sums, found)
    }
}
