//! The first radii of a progressive render, from a pilot photon pass: reads the scene, the
//! camera rays and the job, and writes each map's first radius and, with `per_pixel_radii`,
//! each pixel's. Deterministic given the seed, so every worker of a divided render derives the
//! same radii.
//!
//! Each map's first radius is the median k-nearest radius where the camera reads the map — at
//! the camera paths' first non-specular points, and for the global map under final gathering
//! where one gather ray from each lands, weighed by the photon density there as a median over
//! photons is — not over all the map's photons, most of which may lie where the camera never
//! looks: a closed room under a sun outside (`scenes/hard/room-sunlit`)
//! had a first global radius of 0.49 from the sunlit ground's photons against 0.14 from its own,
//! and its inside rendered 7 % too bright with the edge correction (7 % too dark without). The
//! median over the map's photons remains the fallback where the camera finds no such point.

use crate::code_path::CodePath;
use crate::job::{FixedRadii, Job, Pass, PixelRadii};
use crate::photon_map::{flags, Filter, Kernel, Lookup, Nearest, PhotonMap};
use crate::reference::build_job_maps;
use crate::scene::camera::CameraRays;
use crate::scene::Scene;
use crate::settings::Settings;
use crate::transport::camera::probe_first_surfaces;
use crate::transport::gather::trace_gather_rays;
use crate::transport::specular::Chain;
use crate::transport::{streams, Context, PhotonMaps};
use std::sync::Arc;

/// Photons sampled for the first radii.
pub const RADIUS_SAMPLES: usize = 1024;

/// The seed of pass `i`: pass 0 keeps the user's seed; later ones are mixed from it.
#[must_use]
pub fn pass_seed(seed: u64, i: u32) -> u64 {
    if i == 0 {
        return seed;
    }
    crate::rng::mix64(seed ^ u64::from(i).wrapping_mul(0x9e37_79b9_7f4a_7c15))
}

/// Median distance from a photon of `map` to its `k`-th nearest neighbour (same-facing photons,
/// within `r_max`), over up to [`RADIUS_SAMPLES`] photons spread through the map. `None` for an
/// empty map or when no sampled photon has k neighbours within `r_max`.
#[must_use]
pub fn median_knn_radius(map: &PhotonMap, k: u32, r_max: f32, code_path: CodePath) -> Option<f32> {
    median_radius_with(map, k, r_max, code_path, |p| Filter::at(p.position, p.normal, 0))
}

/// [`median_knn_radius`] in a volume map: each photon's k nearest in 3-D
/// ([`Filter::volume`]).
#[must_use]
pub fn median_volume_radius(map: &PhotonMap, k: u32, r_max: f32, code_path: CodePath) -> Option<f32> {
    median_radius_with(map, k, r_max, code_path, |_| Filter::volume(0))
}

/// The median k-nearest radius over the sampled photons of `map`, each searched with the
/// filter `filter` gives it.
fn median_radius_with(
    map: &PhotonMap,
    k: u32,
    r_max: f32,
    code_path: CodePath,
    filter: impl Fn(&crate::photon_map::Photon) -> Filter,
) -> Option<f32> {
    if map.is_empty() {
        return None;
    }
    let step = map.len().div_ceil(RADIUS_SAMPLES).max(1);
    let mut scratch = Nearest::default();
    let mut radii: Vec<f32> = (0..map.len())
        .step_by(step)
        .filter_map(|i| {
            let p = map.photon(i);
            let q = Lookup { p: p.position, k: k as usize, r_max, kernel: Kernel::Box, filter: filter(&p) };
            let found = map.nearest(code_path, &q, &mut scratch);
            (found.len() == k as usize).then(|| found.iter().map(|c| c.0).fold(0.0, f32::max).sqrt())
        })
        .collect();
    if radii.is_empty() {
        return None;
    }
    let mid = radii.len() / 2;
    Some(*radii.select_nth_unstable_by(mid, f32::total_cmp).1)
}

/// The pilot photon pass's seed: its photons are independent of every pass's.
#[must_use]
pub fn pilot_seed(seed: u64) -> u64 {
    pass_seed(seed, u32::MAX)
}

/// The first pass's radii from a pilot photon pass (traced with [`pilot_seed`]): per map, the
/// density-weighed median k-nearest radius where the camera reads it (`camera_knn_radii`),
/// else the median over the pilot's photons ([`median_knn_radius`]), else the maximum radius (a
/// map empty or too sparse); with `per_pixel_radii`, each pixel's own as well ([`pixel_radii`]).
/// `job` is the render's, whose pass (the user's seed, no radii) is the first; its photon guide
/// is made here when it has none yet.
#[must_use]
pub fn initial_radii(scene: &Scene, rays: &CameraRays, job: &Job) -> FixedRadii {
    let settings = &job.settings;
    let d = scene.diagonal();
    let (r_global, r_caustic) = (settings.global_radius * d, settings.caustic_radius * d);
    // The pilot map is guided as the passes' maps will be (the job shares the guide with them),
    // so its radii follow the photons the passes will store where the camera reads.
    crate::transport::guide::ensure(scene, rays, job);
    let pilot = Job {
        settings: Settings { precompute_irradiance: false, ..settings.clone() },
        pass: Pass { seed: pilot_seed(settings.seed), radii: None },
        ..job.clone()
    };
    let (maps, _, _) = build_job_maps(scene, &pilot);
    let (seen_global, seen_caustic) = camera_knn_radii(scene, rays, job, &maps);
    let uniform = FixedRadii::uniform(
        seen_global
            .or_else(|| median_knn_radius(&maps.global, settings.k, r_global, settings.code_path))
            .unwrap_or(r_global),
        seen_caustic
            .or_else(|| median_knn_radius(&maps.caustic, settings.caustic_k, r_caustic, settings.code_path))
            .unwrap_or(r_caustic),
    );
    // The pixels' first radii follow the first pass's camera samples: `job`'s own seed.
    let pixels = settings.per_pixel_radii.then(|| Arc::new(pixel_radii(scene, rays, job, &maps, &uniform)));
    // The volume maps' first radii: the median over their photons (the camera's medium points
    // are spread through the medium as the photons are), else the surface maps' maximum radii.
    let volume = (
        median_volume_radius(&maps.volume, settings.k, r_global, settings.code_path).unwrap_or(r_global),
        median_volume_radius(&maps.volume_caustic, settings.caustic_k, r_caustic, settings.code_path)
            .unwrap_or(r_caustic),
    );
    FixedRadii { pixels, volume, ..uniform }
}

/// The median k-nearest radius of each map where the camera reads it: the caustic map at each
/// pixel's first non-specular point (its first camera sample, through mirrors and glass as that
/// sample's path goes), the global map there too with final gathering off (without direct and
/// caustic photons, as read there) or, with it on, where the pixel's first gather ray lands (the
/// whole map, as read there), weighed by the photon density there ([`density_median`]). Points
/// with fewer than k photons within the maximum radius are left out, as photons with fewer
/// neighbours are from the median over photons; `None` where no point has k.
#[must_use]
pub fn camera_knn_radii(scene: &Scene, rays: &CameraRays, job: &Job, maps: &PhotonMaps) -> (Option<f32>, Option<f32>) {
    let settings = &job.settings;
    let ctx = Context::new(scene, maps, job);
    let knn = |map: &PhotonMap, k: u32, r_max: f32, q: Lookup, scratch: &mut Nearest| {
        let found = map.nearest(settings.code_path, &Lookup { k: k as usize, r_max, ..q }, scratch);
        let r = found.iter().map(|c| c.0).fold(0.0, f32::max).sqrt();
        (found.len() == k as usize && r > 0.0 && r.is_finite()).then_some(r)
    };
    let (global_on, gather) = (ctx.effects.global_map.on, ctx.effects.final_gather.on);
    let found = probe_first_surfaces(&ctx, job, rays, (None, None), |_, s, sp, d, scratch, counts| {
        let (ng, _) = sp.frame.oriented(-d);
        let at = |p, n, mask| Lookup { p, k: 0, r_max: 0.0, kernel: settings.kernel, filter: Filter::at(p, n, mask) };
        let caustic = knn(&maps.caustic, settings.caustic_k, ctx.caustic_radius, at(sp.p, ng, 0), scratch);
        let global = match (global_on, gather) {
            (false, _) => None,
            (true, false) => knn(&maps.global, settings.k, ctx.global_radius, at(sp.p, ng, flags::OWN_TERMS), scratch),
            (true, true) => {
                let mut r = None;
                trace_gather_rays(&ctx, sp, -d, 1, &s.fork(streams::gather(0)), counts, |chain, _, _, _| {
                    let Chain::Hit(end) = chain else { return };
                    let (n, _) = end.point.frame.oriented(-end.dir);
                    r = knn(&maps.global, settings.k, ctx.global_radius, at(end.point.p, n, 0), scratch);
                });
                r
            }
        };
        (global, caustic)
    });
    let (global, caustic): (Vec<_>, Vec<_>) = found.into_iter().unzip();
    (density_median(global.into_iter().flatten().collect()), density_median(caustic.into_iter().flatten().collect()))
}

/// The median of k-nearest radii found at points of a surface, each weighed by the photon
/// density there (∝ 1/r²): the median a photon of those regions sees, as the median over the
/// map's photons was — photons crowd where the light is, and the first radius (hence each
/// estimate's cost and noise) was tuned on that median. `None` for no radii.
fn density_median(mut radii: Vec<f32>) -> Option<f32> {
    radii.retain(|r| *r > 0.0 && r.is_finite());
    radii.sort_unstable_by(f32::total_cmp);
    let weight = |r: f32| 1.0 / (f64::from(r) * f64::from(r));
    let half = 0.5 * radii.iter().map(|&r| weight(r)).sum::<f64>();
    let mut sum = 0.0;
    radii.into_iter().find(|&r| {
        sum += weight(r);
        sum >= half
    })
}

/// Each pixel's first radii: the radius a k-nearest-neighbour estimate would use at the first
/// non-specular point of the pixel's first camera sample (reached through mirrors and glass as
/// that sample's path goes) — the distance to the k-th nearest same-facing photon of `maps`,
/// or the maximum radius where fewer than k lie within it (`caustic_k` and the caustic map;
/// `k` and the global map without direct and caustic photons). `fallback`'s radii where the
/// path finds no such point. Global radii are found only where the camera reads the global
/// map (final gathering off).
#[must_use]
pub fn pixel_radii(
    scene: &Scene,
    rays: &CameraRays,
    job: &Job,
    maps: &PhotonMaps,
    fallback: &FixedRadii,
) -> PixelRadii {
    let settings = &job.settings;
    let ctx = Context::new(scene, maps, job);
    let want_global = ctx.effects.global_map.on && !ctx.effects.final_gather.on;
    let knn = |map: &PhotonMap, k: u32, r_max: f32, q: Lookup, scratch: &mut Nearest| {
        let found = map.nearest(settings.code_path, &Lookup { k: k as usize, r_max, ..q }, scratch);
        let r = found.iter().map(|c| c.0).fold(0.0, f32::max).sqrt();
        if found.len() == k as usize && r > 0.0 && r.is_finite() {
            r
        } else {
            r_max
        }
    };
    let miss = (fallback.global, fallback.caustic);
    let found = probe_first_surfaces(&ctx, job, rays, miss, |_, _, sp, d, scratch, _| {
        let (ng, _) = sp.frame.oriented(-d);
        let q = Lookup { p: sp.p, k: 0, r_max: 0.0, kernel: settings.kernel, filter: Filter::at(sp.p, ng, 0) };
        let caustic = knn(&maps.caustic, settings.caustic_k, ctx.caustic_radius, q, scratch);
        let global = if want_global {
            let q = Lookup { filter: Filter::at(sp.p, ng, flags::OWN_TERMS), ..q };
            knn(&maps.global, settings.k, ctx.global_radius, q, scratch)
        } else {
            fallback.global
        };
        (global, caustic)
    });
    let (global, caustic): (Vec<f32>, Vec<f32>) = found.into_iter().unzip();
    PixelRadii { global: if want_global { global } else { Vec::new() }, caustic }
}
