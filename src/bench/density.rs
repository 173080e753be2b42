//! `photonwave bench`'s density rows: SIMD photon lookups against their scalar twins and, built
//! with `--features baselines`, against kiddo's k-d tree, with the photons each lookup tests.
//! Reads a scene's camera hits and its global photon map; writes [`DensityRow`]s.

use super::{median, time_alternating, RaySets, CHUNK};
use crate::parallel::map_chunks;
use crate::scene::Scene;
use glam::Vec3;
use serde::Serialize;

/// Median seconds of our SIMD lookups and of the baseline's, timed alternately.
type Timed = (f64, f64);

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
    /// `photons_tested_per_query`, how tightly the tree's boxes fit the query's sphere.
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

/// SIMD against scalar density estimates on the scene's global photon map (default settings,
/// [`BENCH_PHOTONS`] photons), at the camera hits (in tile order, as the camera pass asks),
/// Lambertian reflectance. `knn`: the k = 64 nearest under the default maximum radius;
/// `radius`: every photon within a fixed radius, the median radius the k-NN lookups found.
pub(super) fn density(name: &str, scene: &Scene, sets: &RaySets, threads: usize, reps: usize) -> Vec<DensityRow> {
    use crate::code_path::CodePath;
    use crate::photon_map::{Filter, Lookup, Nearest, PhotonMap, Reflectance};
    use crate::reference::build_maps;
    use crate::settings::Settings;
    if sets.hits.is_empty() {
        return vec![];
    }
    let settings = Settings { photons: BENCH_PHOTONS, threads: threads as u32, ..Default::default() };
    // Default settings with a photon count: always valid, so an error here cannot happen.
    let Ok((maps, _, _)) = build_maps(scene, &settings) else { return vec![] };
    let map = &maps.global;
    if map.is_empty() {
        return vec![];
    }
    let step = sets.hits.len().div_ceil(QUERIES).max(1);
    let queries: Vec<(Vec3, Vec3)> = sets.hits.iter().step_by(step).copied().collect();
    let r_max = settings.global_radius * scene.diagonal();
    let lookup = |p: Vec3, n: Vec3, k: usize, r: f32| Lookup {
        p,
        k,
        r_max: r,
        kernel: settings.kernel,
        filter: Filter { n, flags_mask: 0, plane: 0.0, slack: 0.0 },
    };
    let f = |n: Vec3| Reflectance::Hemisphere { value: Vec3::splat(0.5 / std::f32::consts::PI), ng: n };
    let knn = |set: CodePath| {
        map_chunks(
            queries.len(),
            CHUNK,
            threads,
            |r| {
                let mut scratch = Nearest::default();
                queries[r]
                    .iter()
                    .map(|&(p, n)| map.estimate(set, &lookup(p, n, settings.k as usize, r_max), f(n), &mut scratch))
                    .collect::<Vec<_>>()
            },
            |_| {},
        )
        .concat()
    };
    let radius_lookup = |set: CodePath, r: f32| {
        map_chunks(
            queries.len(),
            CHUNK,
            threads,
            |range| {
                queries[range]
                    .iter()
                    .map(|&(p, n)| map.estimate_radius(set, &lookup(p, n, 0, r), f(n)).radiance.x)
                    .sum::<f32>()
            },
            |_| {},
        )
        .into_iter()
        .sum::<f32>()
    };
    // The fixed-radius estimates 8 consecutive queries at a time, one walk per packet.
    let radius_packets = |r: f32| {
        use crate::photon_map::query_packet::{RadiusQuery, PACKET};
        use crate::photon_map::Estimate;
        map_chunks(
            queries.len(),
            CHUNK,
            threads,
            |range| {
                let mut out = [Estimate::default(); PACKET];
                queries[range]
                    .chunks(PACKET)
                    .map(|chunk| {
                        let packet: Vec<RadiusQuery<'_>> = chunk
                            .iter()
                            .map(|&(p, n)| RadiusQuery { lookup: lookup(p, n, 0, r), f: f(n), edges: None })
                            .collect();
                        map.estimate_radius_packet(CodePath::Simd, &packet, false, &mut out);
                        out[..chunk.len()].iter().map(|e| e.radiance.x).sum::<f32>()
                    })
                    .sum::<f32>()
            },
            |_| {},
        )
        .into_iter()
        .sum::<f32>()
    };
    let scalar_knn = knn(CodePath::Scalar);
    let radii: Vec<f64> = scalar_knn.iter().map(|e| f64::from(e.radius)).collect();
    let r_fixed = if radii.is_empty() { r_max } else { median(radii) as f32 };
    let n = queries.len() as f64;
    // In the lookups' order through one scratch, as a thread runs them (k-nearest searches start
    // from the last one's radius).
    let tested = |k: usize, r: f32| {
        let mut scratch = Nearest::default();
        queries.iter().map(|&(p, nrm)| map.photons_tested(&lookup(p, nrm, k, r), &mut scratch)).sum::<u64>() as f64 / n
    };
    let k = settings.k as usize;
    let summed_knn = scalar_knn.iter().map(|e| f64::from(e.count)).sum::<f64>() / n;
    let summed_radius = queries
        .iter()
        .map(|&(p, nrm)| f64::from(map.estimate_radius(CodePath::Scalar, &lookup(p, nrm, 0, r_fixed), f(nrm)).count))
        .sum::<f64>()
        / n;
    // Each lookup through kiddo (k nearest, or `k` = 0: every photon within the radius), summed.
    #[cfg(feature = "baselines")]
    let tree = kiddo_baseline::Tree::new(map);
    #[cfg(feature = "baselines")]
    let through_kiddo = |k: usize, radius: f32| {
        map_chunks(
            queries.len(),
            CHUNK,
            threads,
            |r| {
                let mut found = Vec::new();
                queries[r]
                    .iter()
                    .map(|&(p, nrm)| tree.estimate(&lookup(p, nrm, k, radius), f(nrm), &mut found).radiance.x)
                    .sum::<f32>()
            },
            |_| {},
        )
        .into_iter()
        .sum::<f32>()
    };
    #[cfg(feature = "baselines")]
    let through_kiddo: Option<&dyn Fn(usize, f32) -> f32> = Some(&through_kiddo);
    #[cfg(not(feature = "baselines"))]
    let through_kiddo: Option<&dyn Fn(usize, f32) -> f32> = None;
    if let Some(kiddo) = through_kiddo {
        // The baseline computes the same estimates: the same photons within a fixed radius (sums
        // equal to rounding), nearly the same k nearest (its k are taken before the normal test).
        let ours_knn: f32 = scalar_knn.iter().map(|e| e.radiance.x).sum();
        let ours_radius = radius_lookup(CodePath::Simd, r_fixed);
        let (theirs_knn, theirs_radius) = (kiddo(k, r_max), kiddo(0, r_fixed));
        let close = |a: f32, b: f32, tol: f32| (a - b).abs() <= tol * a.abs().max(b.abs());
        assert!(close(ours_knn, theirs_knn, 0.02), "{name}: kiddo k-NN sum {theirs_knn} against {ours_knn}");
        assert!(
            close(ours_radius, theirs_radius, 1e-4),
            "{name}: kiddo radius sum {theirs_radius} against {ours_radius}"
        );
    }
    // Each packet estimate equals its single SIMD estimate to the bit (tests/simd.rs); the sums
    // differ only in the order they are added (chunk by chunk against packet by packet).
    let (single, packed) = (radius_lookup(CodePath::Simd, r_fixed), radius_packets(r_fixed));
    assert!(
        (single - packed).abs() <= 1e-5 * single.abs().max(packed.abs()),
        "{name}: packet radius sum {packed} against {single}"
    );
    // SIMD, scalar and (when built) kiddo in turn.
    let kiddo_run = |k: usize, r: f32| {
        if let Some(kiddo) = through_kiddo {
            std::hint::black_box(kiddo(k, r));
        }
    };
    let [ts, tk, tkd] = time_alternating(
        reps,
        [&mut || drop(knn(CodePath::Simd)), &mut || drop(knn(CodePath::Scalar)), &mut || kiddo_run(k, r_max)],
    );
    let [rs, rk, rkd, rp] = time_alternating(
        reps,
        [
            &mut || {
                std::hint::black_box(radius_lookup(CodePath::Simd, r_fixed));
            },
            &mut || {
                std::hint::black_box(radius_lookup(CodePath::Scalar, r_fixed));
            },
            &mut || kiddo_run(0, r_fixed),
            &mut || {
                std::hint::black_box(radius_packets(r_fixed));
            },
        ],
    );
    let kiddo_knn = through_kiddo.map(|_| (ts, tkd));
    let kiddo_radius = through_kiddo.map(|_| (rs, rkd));
    let row = |lookup, simd: f64, scalar: f64, tested: f64, summed: f64, kiddo: Option<Timed>, packet: Option<f64>| {
        DensityRow {
            scene: name.to_string(),
            lookup,
            count: queries.len(),
            photons: map.len(),
            simd_per_s: n / simd,
            scalar_per_s: n / scalar,
            ratio: scalar / simd,
            photons_tested_per_query: tested,
            ns_per_photon_tested: simd / n / tested * 1e9,
            photons_summed_per_query: summed,
            map_bytes_per_photon: PhotonMap::bytes_per_photon() as f64 + map.tree_bytes_per_photon(),
            kiddo_per_s: kiddo.map(|(_, k)| n / k),
            ratio_vs_kiddo: kiddo.map(|(s, k)| k / s),
            packet_per_s: packet.map(|p| n / p),
            packet_ratio: packet.map(|p| scalar / p),
        }
    };
    vec![
        row("knn", ts, tk, tested(k, r_max), summed_knn, kiddo_knn, None),
        row("radius", rs, rk, tested(0, r_fixed), summed_radius, kiddo_radius, Some(rp)),
    ]
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
