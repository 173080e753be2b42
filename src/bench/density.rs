//! `photonwave bench`'s density rows: SIMD photon lookups against their scalar twins and, built
//! with `--features baselines`, against kiddo's k-d tree, with the photons each lookup tests.
//! Reads a scene's camera hits and its global photon map; writes [`DensityRow`]s.

use super::{median, time_alternating, RaySets, CHUNK};
use crate::code_path::CodePath;
use crate::parallel::map_chunks;
use crate::photon_map::query_packet::{RadiusQuery, PACKET};
use crate::photon_map::{Estimate, Filter, Lookup, Nearest, PhotonMap, Reflectance};
use crate::reference::build_maps;
use crate::scene::Scene;
use crate::settings::Settings;
use glam::Vec3;
use serde::Serialize;

/// One density-estimate measurement.
#[derive(Clone, Debug, Serialize)]
pub struct DensityRow {
    /// Scene name.
    pub scene: String,
    /// knn (k nearest under a maximum radius) or radius (every photon within a fixed radius).
    pub lookup: &'static str,
    /// Queries in the set.
    pub count: usize,
    /// Photons in the map.
    pub photons: usize,
    /// SIMD estimates per second (median).
    pub simd_per_s: f64,
    /// Scalar estimates per second (median).
    pub scalar_per_s: f64,
    /// simd / scalar.
    pub ratio: f64,
    /// Photons the tree walk tests per query (those of every block it reaches).
    pub photons_tested_per_query: f64,
    /// SIMD time per photon tested, nanoseconds.
    pub ns_per_photon_tested: f64,
    /// Photons each estimate sums (within the radius, passing the filter), per query: with
    /// `photons_tested_per_query`, how tightly the tree's boxes fit the query's sphere (past the
    /// subtrees facing away, which the walk skips since 9498c5f).
    pub photons_summed_per_query: f64,
    /// Bytes of the map per photon: its 20-byte records and its tree's nodes.
    pub map_bytes_per_photon: f64,
    /// kiddo's k-d tree (`ImmutableKdTree`, buckets of 32) over the same positions, its search
    /// followed by the same filter and scalar kernel sum, estimates per second (median); `null`
    /// unless built with `--features baselines`.
    pub kiddo_per_s: Option<f64>,
    /// simd / kiddo.
    pub ratio_vs_kiddo: Option<f64>,
    /// Fixed-radius rows: the same estimates by query packets (8 consecutive queries sharing one
    /// walk), estimates per second (median); `null` on k-NN rows.
    pub packet_per_s: Option<f64>,
    /// packet / scalar.
    pub packet_ratio: Option<f64>,
}

/// Photons in the bench's global map.
pub const BENCH_PHOTONS: u32 = 200_000;

/// Queries per density row.
const QUERIES: usize = 65_536;

/// The density rows' queries on one photon map, and every way the rows estimate them.
struct Queries<'a> {
    map: &'a PhotonMap,
    /// Camera hits: position and normal.
    points: Vec<(Vec3, Vec3)>,
    settings: Settings,
    /// The default maximum radius, in scene units.
    r_max: f32,
    threads: usize,
}

impl Queries<'_> {
    /// The lookup at `p` with normal `n`: the `k` nearest within `r` (`k` = 0: every photon
    /// within `r`).
    fn lookup(&self, p: Vec3, n: Vec3, k: usize, r: f32) -> Lookup {
        Lookup {
            p,
            k,
            r_max: r,
            kernel: self.settings.kernel,
            filter: Filter { n, flags_mask: 0, plane: 0.0, slack: 0.0 },
        }
    }

    /// Lambertian reflectance of albedo ½ about `n`.
    fn f(n: Vec3) -> Reflectance<'static> {
        Reflectance::Hemisphere { value: Vec3::splat(0.5 / std::f32::consts::PI), ng: n }
    }

    /// The default k.
    fn k(&self) -> usize {
        self.settings.k as usize
    }

    /// Sums `estimate(range)` over chunks of the queries on the bench's threads.
    fn sum_chunks(&self, estimate: impl Fn(std::ops::Range<usize>) -> f32 + Sync) -> f32 {
        map_chunks(self.points.len(), CHUNK, self.threads, estimate, |_| {}).into_iter().sum()
    }

    /// Every query's k-nearest estimate by code path `set`.
    fn knn(&self, set: CodePath) -> Vec<Estimate> {
        let (k, r) = (self.k(), self.r_max);
        let chunk = |range: std::ops::Range<usize>| {
            let mut scratch = Nearest::default();
            self.points[range]
                .iter()
                .map(|&(p, n)| self.map.estimate(set, &self.lookup(p, n, k, r), Self::f(n), &mut scratch))
                .collect::<Vec<_>>()
        };
        map_chunks(self.points.len(), CHUNK, self.threads, chunk, |_| {}).concat()
    }

    /// The sum of every query's fixed-radius estimate (red channel) by code path `set`.
    fn radius(&self, set: CodePath, r: f32) -> f32 {
        self.sum_chunks(|range| {
            self.points[range]
                .iter()
                .map(|&(p, n)| self.map.estimate_radius(set, &self.lookup(p, n, 0, r), Self::f(n)).radiance.x)
                .sum()
        })
    }

    /// [`Self::radius`] with 8 consecutive queries at a time, one walk per packet.
    fn radius_packets(&self, r: f32) -> f32 {
        self.sum_chunks(|range| {
            let mut out = [Estimate::default(); PACKET];
            self.points[range]
                .chunks(PACKET)
                .map(|chunk| {
                    let packet: Vec<RadiusQuery<'_>> = chunk
                        .iter()
                        .map(|&(p, n)| RadiusQuery { lookup: self.lookup(p, n, 0, r), f: Self::f(n), edges: None })
                        .collect();
                    self.map.estimate_radius_packet(CodePath::Simd, &packet, false, &mut out);
                    out[..chunk.len()].iter().map(|e| e.radiance.x).sum::<f32>()
                })
                .sum()
        })
    }

    /// Photons the tree walk tests per query, in the lookups' order through one scratch as a
    /// thread runs them (k-nearest searches start from the last one's radius).
    fn tested(&self, k: usize, r: f32) -> f64 {
        let mut scratch = Nearest::default();
        let tested: u64 =
            self.points.iter().map(|&(p, n)| self.map.photons_tested(&self.lookup(p, n, k, r), &mut scratch)).sum();
        tested as f64 / self.points.len() as f64
    }

    /// Photons each fixed-radius estimate sums, per query.
    fn summed_radius(&self, r: f32) -> f64 {
        let summed: f64 = self
            .points
            .iter()
            .map(|&(p, n)| {
                f64::from(self.map.estimate_radius(CodePath::Scalar, &self.lookup(p, n, 0, r), Self::f(n)).count)
            })
            .sum();
        summed / self.points.len() as f64
    }

    /// The sum of every query's estimate through kiddo (k nearest, or `k` = 0: every photon
    /// within the radius).
    #[cfg(feature = "baselines")]
    fn kiddo(&self, tree: &kiddo_baseline::Tree<'_>, k: usize, r: f32) -> f32 {
        self.sum_chunks(|range| {
            let mut found = Vec::new();
            self.points[range]
                .iter()
                .map(|&(p, n)| tree.estimate(&self.lookup(p, n, k, r), Self::f(n), &mut found).radiance.x)
                .sum()
        })
    }
}

/// SIMD against scalar density estimates on the scene's global photon map (default settings,
/// [`BENCH_PHOTONS`] photons), at the camera hits (in tile order, as the camera pass asks),
/// Lambertian reflectance. `knn`: the k = 64 nearest under the default maximum radius;
/// `radius`: every photon within a fixed radius, the median radius the k-NN lookups found.
pub(super) fn density(name: &str, scene: &Scene, sets: &RaySets, threads: usize, reps: usize) -> Vec<DensityRow> {
    if sets.hits.is_empty() {
        return vec![];
    }
    let settings = Settings { photons: BENCH_PHOTONS, threads: threads as u32, ..Default::default() };
    // Default settings with a photon count: always valid, so an error here cannot happen.
    let Ok((maps, _, _)) = build_maps(scene, &settings) else { return vec![] };
    if maps.global.is_empty() {
        return vec![];
    }
    let step = sets.hits.len().div_ceil(QUERIES).max(1);
    let q = Queries {
        map: &maps.global,
        points: sets.hits.iter().step_by(step).copied().collect(),
        r_max: settings.global_radius * scene.diagonal(),
        settings,
        threads,
    };
    let scalar_knn = q.knn(CodePath::Scalar);
    let radii: Vec<f64> = scalar_knn.iter().map(|e| f64::from(e.radius)).collect();
    let r_fixed = if radii.is_empty() { q.r_max } else { median(radii) as f32 };
    #[cfg(feature = "baselines")]
    let tree = kiddo_baseline::Tree::new(q.map);
    #[cfg(feature = "baselines")]
    let kiddo = Some(|k: usize, r: f32| q.kiddo(&tree, k, r));
    #[cfg(not(feature = "baselines"))]
    let kiddo: Option<fn(usize, f32) -> f32> = None;
    check_agreement(name, &q, &scalar_knn, r_fixed, kiddo.as_ref());
    // SIMD, scalar and (when built) kiddo in turn.
    let kiddo_run = |k: usize, r: f32| {
        if let Some(kiddo) = &kiddo {
            std::hint::black_box(kiddo(k, r));
        }
    };
    let (k, r_max) = (q.k(), q.r_max);
    let [ts, tk, tkd] = time_alternating(
        reps,
        [&mut || drop(q.knn(CodePath::Simd)), &mut || drop(q.knn(CodePath::Scalar)), &mut || kiddo_run(k, r_max)],
    );
    let [rs, rk, rkd, rp] = time_alternating(
        reps,
        [
            &mut || {
                std::hint::black_box(q.radius(CodePath::Simd, r_fixed));
            },
            &mut || {
                std::hint::black_box(q.radius(CodePath::Scalar, r_fixed));
            },
            &mut || kiddo_run(0, r_fixed),
            &mut || {
                std::hint::black_box(q.radius_packets(r_fixed));
            },
        ],
    );
    let n = q.points.len() as f64;
    let summed_knn = scalar_knn.iter().map(|e| f64::from(e.count)).sum::<f64>() / n;
    let row =
        |lookup, simd: f64, scalar: f64, tested: f64, summed, kiddo: Option<f64>, packet: Option<f64>| DensityRow {
            scene: name.to_string(),
            lookup,
            count: q.points.len(),
            photons: q.map.len(),
            simd_per_s: n / simd,
            scalar_per_s: n / scalar,
            ratio: scalar / simd,
            photons_tested_per_query: tested,
            ns_per_photon_tested: simd / n / tested * 1e9,
            photons_summed_per_query: summed,
            map_bytes_per_photon: PhotonMap::bytes_per_photon() as f64 + q.map.tree_bytes_per_photon(),
            kiddo_per_s: kiddo.map(|k| n / k),
            ratio_vs_kiddo: kiddo.map(|k| k / simd),
            packet_per_s: packet.map(|p| n / p),
            packet_ratio: packet.map(|p| scalar / p),
        };
    let timed_kiddo = |t| kiddo.as_ref().map(|_| t);
    vec![
        row("knn", ts, tk, q.tested(k, r_max), summed_knn, timed_kiddo(tkd), None),
        row("radius", rs, rk, q.tested(0, r_fixed), q.summed_radius(r_fixed), timed_kiddo(rkd), Some(rp)),
    ]
}

/// Asserts that every timed way computes the same estimates: kiddo (when built) the same
/// photons within a fixed radius (sums equal to rounding) and nearly the same k nearest (its k
/// are taken before the normal test); the packets each equal to their single SIMD estimate to
/// the bit (tests/simd.rs), so their sums differ only in the order they are added.
fn check_agreement(
    name: &str,
    q: &Queries<'_>,
    scalar_knn: &[Estimate],
    r_fixed: f32,
    kiddo: Option<&impl Fn(usize, f32) -> f32>,
) {
    let close = |a: f32, b: f32, tol: f32| (a - b).abs() <= tol * a.abs().max(b.abs());
    let single = q.radius(CodePath::Simd, r_fixed);
    if let Some(kiddo) = kiddo {
        let ours_knn: f32 = scalar_knn.iter().map(|e| e.radiance.x).sum();
        let (theirs_knn, theirs_radius) = (kiddo(q.k(), q.r_max), kiddo(0, r_fixed));
        assert!(close(ours_knn, theirs_knn, 0.02), "{name}: kiddo k-NN sum {theirs_knn} against {ours_knn}");
        assert!(close(single, theirs_radius, 1e-4), "{name}: kiddo radius sum {theirs_radius} against {single}");
    }
    let packed = q.radius_packets(r_fixed);
    assert!(close(single, packed, 1e-5), "{name}: packet radius sum {packed} against {single}");
}

/// kiddo's k-d tree over a photon map's positions: the density benchmark's outside yardstick.
#[cfg(feature = "baselines")]
mod kiddo_baseline {
    use crate::photon_map::{Estimate, Lookup, PhotonMap, Reflectance};
    use kiddo::immutable::float::kdtree::ImmutableKdTree;
    use kiddo::SquaredEuclidean;
    use std::num::NonZero;

    /// The tree (items: the map's photon indices) and the map.
    pub struct Tree<'a> {
        tree: ImmutableKdTree<f32, u32, 3, 32>,
        map: &'a PhotonMap,
    }

    impl<'a> Tree<'a> {
        /// Builds over the map's photon positions.
        pub fn new(map: &'a PhotonMap) -> Self {
            let points: Vec<[f32; 3]> = (0..map.len()).map(|i| map.position(i).to_array()).collect();
            Tree { tree: ImmutableKdTree::new_from_slice(&points), map }
        }

        /// The estimate of `q` (k nearest, or every photon within the radius for `q.k == 0`):
        /// kiddo's search, then the map's filter and scalar kernel sum.
        pub fn estimate(&self, q: &Lookup, f: Reflectance<'_>, found: &mut Vec<(f32, u32)>) -> Estimate {
            let p = q.p.to_array();
            let r2 = q.r_max * q.r_max;
            found.clear();
            if q.k == 0 {
                let near = self.tree.within_unsorted::<SquaredEuclidean>(&p, r2);
                found.extend(near.iter().map(|n| (n.distance, n.item)));
                self.map.estimate_radius_from_candidates(q, f, found)
            } else {
                let k = NonZero::new(q.k).unwrap_or(NonZero::<usize>::MIN);
                let near = self.tree.nearest_n_within::<SquaredEuclidean>(&p, r2, k, false);
                found.extend(near.iter().map(|n| (n.distance, n.item)));
                self.map.estimate_from_candidates(q, f, found)
            }
        }
    }
}
