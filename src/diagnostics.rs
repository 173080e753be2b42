//! Diagnostic layers (`--diagnostics`): where a render's density estimates are starved (few
//! photons) or blurred (a wide radius). Reads a scene, its camera rays and the job of the
//! render's last pass; writes, per pixel, the radius and the photons summed of the caustic and
//! the global estimates ([`EstimateLayers`]).
//!
//! A probe, not a record kept by the engines: for each pixel, the pass's first camera sample is
//! followed through mirrors and glass to its first non-specular point, as the engines follow it.
//! There the caustic estimate is made as the camera's is; the global estimate is made where the
//! render reads the global map — at each final-gather ray's first non-specular hit (the mean over
//! the hits; the full map, as a gather ray reads it, even where the render reads precomputed
//! irradiance instead, whose points were estimated the same way), or at the point itself with
//! final gathering off. The pass's photon maps are traced again from its seed (the same photons
//! the engines traced, by the transport core's streams), which costs one pass's photon tracing: a
//! whole render's for a one-pass render, little for a progressive one.

use crate::film::{EstimateLayers, Film};
use crate::job::Job;
use crate::reference::build_job_maps;
use crate::scene::camera::CameraRays;
use crate::scene::Scene;
use crate::stats::RenderStats;
use crate::transport::camera::probe_first_surfaces;
use crate::transport::estimate::{caustic_estimate, global_estimate, indirect_estimate};
use crate::transport::gather::trace_gather_rays;
use crate::transport::specular::Chain;
use crate::transport::{streams, Context};

/// The diagnostic layers of `job`'s pass of `scene` seen through `rays` (see the module notes).
/// Pixels whose sample finds no non-specular point, and estimates of a map the plan skipped,
/// are 0.
#[must_use]
pub fn probe(scene: &Scene, rays: &CameraRays, job: &Job) -> EstimateLayers {
    let (maps, _, _) = build_job_maps(scene, job);
    let ctx = Context::new(scene, &maps, job);
    let settings = &job.settings;
    let (caustic_on, global_on) = (ctx.effects.caustic_map.on, ctx.effects.global_map.on);
    let gather_on = ctx.effects.final_gather.on;
    let found = probe_first_surfaces(&ctx, job, rays, [0.0; 4], |pixel, s, sp, d, scratch, counts| {
        let bsdf = &scene.bsdf(sp);
        let caustic = if caustic_on {
            let e = caustic_estimate(&ctx, sp, bsdf, -d, Some(pixel), scratch).finish(&ctx);
            [e.radius, e.count as f32]
        } else {
            [0.0; 2]
        };
        let global = if !global_on {
            [0.0; 2]
        } else if gather_on {
            let (mut sum, mut hits) = ([0.0f64; 2], 0u32);
            let gather = s.fork(streams::gather(0));
            trace_gather_rays(&ctx, sp, -d, settings.gather_rays, &gather, counts, |chain, _, _, _| {
                let Chain::Hit(end) = chain else { return };
                let bsdf = &scene.bsdf(&end.point);
                let e = global_estimate(&ctx, &end.point, bsdf, -end.dir, 0, None, scratch).finish(&ctx);
                sum[0] += f64::from(e.radius);
                sum[1] += f64::from(e.count);
                hits += 1;
            });
            let n = f64::from(hits.max(1));
            [(sum[0] / n) as f32, (sum[1] / n) as f32]
        } else {
            let e = indirect_estimate(&ctx, sp, bsdf, -d, Some(pixel), scratch).finish(&ctx);
            [e.radius, e.count as f32]
        };
        [caustic[0], caustic[1], global[0], global[1]]
    });
    let mut layers = EstimateLayers::default();
    for [cr, cn, gr, gn] in found {
        layers.caustic_radius.push(cr);
        layers.caustic_photons.push(cn);
        layers.global_radius.push(gr);
        layers.global_photons.push(gn);
    }
    layers
}

/// With `diagnostics` on, adds the diagnostic layers of `pass` (the render's last pass) to `film`
/// and their time to `stats`.
pub fn add_layers(scene: &Scene, rays: &CameraRays, pass: &Job, film: &mut Film, stats: &mut RenderStats) {
    if pass.settings.diagnostics {
        let t = std::time::Instant::now();
        film.diagnostics = Some(probe(scene, rays, pass));
        stats.times.diagnostics_s = t.elapsed().as_secs_f64();
        stats.times.total_s += stats.times.diagnostics_s;
    }
}
