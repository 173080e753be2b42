//! Photon maps (Jensen 1996): a balanced kd-tree over photons, k-nearest search under a maximum
//! radius, and the kernel density estimate of reflected radiance.
//!
//! The estimate uses the (k−1)/(πr²) form: when the search fills k photons, r is the distance
//! to the k-th and only the k−1 strictly inside are summed — unbiased for a uniform density,
//! where k/(πr²) overestimates by k/(k−1). When fewer than k lie within the maximum radius, all of
//! them are summed over the maximum radius (a fixed-radius estimate, also unbiased).
//!
//! Layout: structure-of-arrays columns in kd-tree order — every subtree is a contiguous index
//! range, so spatial neighbours are contiguous. Per photon: the search column 16 B (position and
//! a packed normal/flags filter key), power 12 B, incoming direction 12 B, normal 12 B, split
//! axis 1 B: 53 B, plain f32 for obviousness (packing toward Jensen's 20 B is SIMD work). The
//! search reads only the search column and the axis; power and direction only for photons it
//! keeps. The tree is implicit: the median of each index range is its node.

use crate::settings::Kernel;
use glam::Vec3;
use std::collections::BinaryHeap;
use std::f32::consts::PI;

/// Flags on a stored photon.
pub mod flags {
    /// Stored at the first surface hit after leaving the light (direct illumination).
    pub const DIRECT: u8 = 1;
    /// Every bounce before this hit was specular (mirror/glass): an `LS+D` caustic photon.
    pub const CAUSTIC: u8 = 2;
}

/// A stored photon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    /// Where it landed.
    pub position: Vec3,
    /// Power it carries (W per channel).
    pub power: Vec3,
    /// Unit direction back toward where it came from.
    pub wi: Vec3,
    /// Geometric normal of the surface it landed on, on the side it arrived from.
    pub normal: Vec3,
    /// [`flags`] bits.
    pub flags: u8,
}

/// Photons in a balanced kd-tree.
#[derive(Clone, Debug, Default)]
pub struct PhotonMap {
    /// Power per photon.
    power: Vec<Vec3>,
    /// Incoming direction per photon.
    wi: Vec<Vec3>,
    /// Surface normal per photon (on the side it arrived from).
    normal: Vec<Vec3>,
    /// What the search reads, in tree order, 16 B a photon: position, and the filter key
    /// (normal as three snorm8 + flags) in the fourth lane's bits. The search is memory-bound;
    /// reading the 52-byte record for the filter cost ~30 % of render time (perf, cornell-box).
    nodes: Vec<[f32; 4]>,
    axis: Vec<u8>,
}

/// The result of a density estimate, with its search radius (for diagnostics).
#[derive(Clone, Copy, Debug, Default)]
pub struct Estimate {
    /// Reflected radiance.
    pub radiance: Vec3,
    /// Radius the estimate used.
    pub radius: f32,
    /// Photons summed.
    pub count: u32,
}

/// A search candidate: (distance², photon index), ordered by distance for the max-heap.
#[derive(PartialEq)]
struct Candidate(f32, u32);
impl PartialOrd for Candidate {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Eq for Candidate {}
impl Ord for Candidate {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0).then(self.1.cmp(&other.1))
    }
}

impl Kernel {
    /// Weight of a photon at squared distance `d2` from the query, radius² `r2`.
    #[inline]
    #[must_use]
    pub fn weight(self, d2: f32, r2: f32) -> f32 {
        match self {
            Kernel::Box => 1.0,
            Kernel::Cone => 1.0 - (d2 / r2).sqrt(),
            Kernel::Epanechnikov => 1.0 - d2 / r2,
        }
    }
    /// 1 / ∫ weight dA over the disk of radius² `r2`: the normalisation that returns a uniform
    /// density exactly.
    #[inline]
    #[must_use]
    pub fn normalisation(self, r2: f32) -> f32 {
        match self {
            Kernel::Box => 1.0 / (PI * r2),
            Kernel::Cone => 3.0 / (PI * r2),
            Kernel::Epanechnikov => 2.0 / (PI * r2),
        }
    }
}

impl PhotonMap {
    /// Builds the tree (takes ownership, reorders).
    #[must_use]
    pub fn build(mut photons: Vec<Photon>) -> Self {
        let mut axis = vec![0u8; photons.len()];
        let n = photons.len();
        build_range(&mut photons, &mut axis, 0, n);
        let nodes = photons
            .iter()
            .map(|p| {
                let [x, y, z] = p.position.to_array();
                [x, y, z, f32::from_bits(FilterKey::pack(p.normal, p.flags).0)]
            })
            .collect();
        PhotonMap {
            power: photons.iter().map(|p| p.power).collect(),
            wi: photons.iter().map(|p| p.wi).collect(),
            normal: photons.iter().map(|p| p.normal).collect(),
            nodes,
            axis,
        }
    }

    /// Number of stored photons.
    #[must_use]
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True if the map holds no photon.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Photon `i` (in tree order) as a record.
    #[must_use]
    pub fn photon(&self, i: usize) -> Photon {
        let n = self.nodes[i];
        Photon {
            position: Vec3::new(n[0], n[1], n[2]),
            power: self.power[i],
            wi: self.wi[i],
            normal: self.normal[i],
            flags: FilterKey(n[3].to_bits()).flags(),
        }
    }

    /// Power of photon `i`.
    #[must_use]
    pub fn power(&self, i: usize) -> Vec3 {
        self.power[i]
    }

    /// The `k` nearest photons to `p` within `r_max` that pass `accept`, as (distance², index),
    /// unordered, into `out`.
    pub fn nearest(
        &self,
        p: Vec3,
        k: usize,
        r_max: f32,
        accept: impl Fn(FilterKey) -> bool,
        out: &mut Vec<(f32, u32)>,
    ) {
        out.clear();
        if k == 0 || self.nodes.is_empty() {
            return;
        }
        let mut heap: BinaryHeap<Candidate> = BinaryHeap::with_capacity(k);
        let mut r2 = r_max * r_max;
        // Explicit stack of index ranges, each with the squared distance from `p` to the
        // splitting plane that separated it (0 for ranges on p's side): a far range is skipped
        // when r² has since shrunk below it.
        let mut stack: [(u32, u32, f32); 64] = [(0, 0, 0.0); 64];
        let mut top = 1;
        stack[0] = (0, self.nodes.len() as u32, 0.0);
        while top > 0 {
            top -= 1;
            let (mut lo, mut hi, plane2) = stack[top];
            if plane2 >= r2 {
                continue;
            }
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                let node = self.nodes[mid as usize];
                let q = Vec3::new(node[0], node[1], node[2]);
                let a = self.axis[mid as usize] as usize;
                let delta = p[a] - q[a];
                let d2 = (q - p).length_squared();
                if d2 < r2 && accept(FilterKey(node[3].to_bits())) {
                    let c = Candidate(d2, mid);
                    if heap.len() < k {
                        heap.push(c);
                    } else if let Some(mut worst) = heap.peek_mut() {
                        *worst = c;
                    }
                    if heap.len() == k {
                        r2 = heap.peek().map_or(r2, |c| c.0);
                    }
                }
                // Descend into p's side now; remember the other side.
                let (near, far) = if delta < 0.0 { ((lo, mid), (mid + 1, hi)) } else { ((mid + 1, hi), (lo, mid)) };
                if far.0 < far.1 && delta * delta < r2 && top < stack.len() {
                    stack[top] = (far.0, far.1, delta * delta);
                    top += 1;
                }
                (lo, hi) = near;
            }
        }
        out.extend(heap.into_iter().map(|Candidate(d, i)| (d, i)));
    }

    /// Reflected radiance at `p` toward `wo` from photons near `p`: Σ f(wi_p)·Φ_p·K over the
    /// (k−1)-of-k rule above. `n` is the query's geometric normal on the side of `wo`; photons
    /// whose surface normal (stored on the side they arrived from) differs by more than ~45°
    /// are ignored: no leaks around corners or through thin walls. Photons with any flag in
    /// `flags_mask` are ignored too. `f` evaluates the BSDF for a photon direction.
    #[allow(clippy::too_many_arguments)]
    pub fn estimate(
        &self,
        p: Vec3,
        n: Vec3,
        k: usize,
        r_max: f32,
        kernel: Kernel,
        flags_mask: u8,
        f: impl Fn(Vec3) -> Vec3,
        scratch: &mut Vec<(f32, u32)>,
    ) -> Estimate {
        if self.is_empty() {
            return Estimate { radius: r_max, ..Default::default() };
        }
        // snorm8 normals are off by < 0.004 per component: the 0.7 threshold moves by < 0.7 %.
        let accept = |key: FilterKey| key.flags() & flags_mask == 0 && key.normal().dot(n) > 0.7;
        self.nearest(p, k, r_max, accept, scratch);
        let (r2, skip) = if scratch.len() == k {
            // The k-th photon defines r and lies on the boundary: sum the other k − 1.
            let (far_i, far) = scratch
                .iter()
                .enumerate()
                .max_by(|a, b| a.1 .0.total_cmp(&b.1 .0))
                .map(|(i, c)| (i, c.0))
                .unwrap_or((0, 0.0));
            (far, Some(far_i))
        } else {
            (r_max * r_max, None)
        };
        if !(r2 > 0.0) {
            return Estimate { radius: 0.0, ..Default::default() };
        }
        let mut sum = Vec3::ZERO;
        let mut count = 0;
        for (j, &(d2, i)) in scratch.iter().enumerate() {
            if Some(j) == skip {
                continue;
            }
            let i = i as usize;
            sum += f(self.wi[i]) * self.power[i] * kernel.weight(d2, r2);
            count += 1;
        }
        Estimate { radiance: sum * kernel.normalisation(r2), radius: r2.sqrt(), count }
    }
}

/// A photon's surface normal (three snorm8) and flags (u8) in 32 bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FilterKey(pub u32);

impl FilterKey {
    /// Packs a unit normal and flags.
    #[must_use]
    pub fn pack(n: Vec3, flags: u8) -> Self {
        let q = |c: f32| ((c.clamp(-1.0, 1.0) * 127.0).round() as i8) as u8 as u32;
        FilterKey(q(n.x) | q(n.y) << 8 | q(n.z) << 16 | (flags as u32) << 24)
    }
    /// The normal (not renormalised).
    #[must_use]
    pub fn normal(self) -> Vec3 {
        let c = |shift: u32| ((self.0 >> shift) as u8 as i8) as f32 * (1.0 / 127.0);
        Vec3::new(c(0), c(8), c(16))
    }
    /// The flags.
    #[must_use]
    pub fn flags(self) -> u8 {
        (self.0 >> 24) as u8
    }
}

fn build_range(photons: &mut [Photon], axis: &mut [u8], lo: usize, hi: usize) {
    if hi - lo <= 1 {
        return;
    }
    let mut mn = Vec3::splat(f32::INFINITY);
    let mut mx = Vec3::splat(f32::NEG_INFINITY);
    for ph in &photons[lo..hi] {
        mn = mn.min(ph.position);
        mx = mx.max(ph.position);
    }
    let ext = mx - mn;
    let a = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = lo + (hi - lo) / 2;
    photons[lo..hi].select_nth_unstable_by(mid - lo, |x, y| x.position[a].total_cmp(&y.position[a]));
    axis[mid] = a as u8;
    build_range(photons, axis, lo, mid);
    build_range(photons, axis, mid + 1, hi);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn photon(x: f32, z: f32, power: f32) -> Photon {
        Photon { position: Vec3::new(x, 0.0, z), power: Vec3::splat(power), wi: Vec3::Y, normal: Vec3::Y, flags: 0 }
    }

    #[test]
    fn nearest_matches_brute_force() {
        let mut s = 12345u64;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        let ps: Vec<Photon> = (0..2000).map(|_| photon(rnd(), rnd(), 1.0)).collect();
        let map = PhotonMap::build(ps.clone());
        let mut out = vec![];
        for _ in 0..50 {
            let q = Vec3::new(rnd(), 0.0, rnd());
            map.nearest(q, 10, 0.2, |_| true, &mut out);
            let mut got: Vec<f32> = out.iter().map(|c| c.0).collect();
            got.sort_by(f32::total_cmp);
            let mut want: Vec<f32> =
                ps.iter().map(|p| (p.position - q).length_squared()).filter(|&d| d < 0.04).collect();
            want.sort_by(f32::total_cmp);
            want.truncate(10);
            assert_eq!(got, want);
        }
    }
}
