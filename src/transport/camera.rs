//! Camera samples, and the pixel loop of the engines that trace one camera ray at a time (the
//! scalar oracle and the path tracer): rows in parallel, each pixel the mean of its jittered
//! samples. The wavefront engine makes the same samples in its emit stage.

use crate::film::{Film, PixelMean, Terms};
use crate::job::Job;
use crate::parallel::map_chunks;
use crate::photon_map::Nearest;
use crate::progress::Progress;
use crate::rng::{Domain, Sampler};
use crate::scene::camera::CameraRays;
use crate::stats::{Numerics, RayCounts};
use glam::Vec3;

use super::specular::first_non_specular;
use super::streams::{CAMERA_CHAIN_BOUNCE, JITTER_BOUNCE};
use super::Context;
use crate::scene::SurfacePoint;

/// Camera sample `index` (sample `index % spp` of pixel `index / spp`) of `job`'s pass: its
/// random stream and its position inside the pixel, jittered within its stratum when spp is a
/// square.
#[must_use]
pub fn camera_sample(job: &Job, index: u64) -> (Sampler, (f32, f32)) {
    let spp = job.settings.spp;
    let s = (index % u64::from(spp)) as u32;
    let strata = (spp as f32).sqrt() as u32;
    let sampler = Sampler::new(job.pass.seed, Domain::Camera, index);
    let (jx, jy) = (sampler.get(JITTER_BOUNCE, 0), sampler.get(JITTER_BOUNCE, 1));
    let offset = if strata * strata == spp {
        (((s % strata) as f32 + jx) / strata as f32, ((s / strata) as f32 + jy) / strata as f32)
    } else {
        (jx, jy)
    };
    (sampler, offset)
}

/// Camera sample `index` of `job`'s pass as a ray: [`camera_sample`]'s random stream, and the
/// origin and direction of the ray through its jittered position in pixel `index / spp`
/// (row-major). Every engine makes its camera rays here.
#[must_use]
pub fn camera_ray(job: &Job, camera: &CameraRays, index: u64) -> (Sampler, Vec3, Vec3) {
    let pixel = index / u64::from(job.settings.spp);
    let width = u64::from(job.settings.width);
    let (sampler, (fx, fy)) = camera_sample(job, index);
    let (o, d) = camera.ray((pixel % width) as f32 + fx, (pixel / width) as f32 + fy);
    (sampler, o, d)
}

/// Per-pixel probes (the pixel radii, the diagnostic layers): each pixel's first camera sample
/// of `job`'s pass, followed through mirrors and glass to its first non-specular point as camera
/// paths go ([`first_non_specular`]), is handed to `probe(pixel, sampler, point, direction that
/// reached it, scratch, rays)`; a pixel whose path escapes or ends on mirrors and glass gets
/// `miss`. Pixels in parallel; the results row-major.
pub fn probe_first_surfaces<T: Send + Sync + Clone>(
    ctx: &Context,
    job: &Job,
    rays: &CameraRays,
    miss: T,
    probe: impl Fn(usize, &Sampler, &SurfacePoint, Vec3, &mut Nearest, &mut RayCounts) -> T + Sync,
) -> Vec<T> {
    let pixels = job.settings.width as usize * job.settings.height as usize;
    let chunks = map_chunks(
        pixels,
        256,
        job.threads,
        |range| {
            let (mut scratch, mut counts) = (Nearest::default(), RayCounts::default());
            range
                .map(|pixel| {
                    let (s, o, d) = camera_ray(job, rays, pixel as u64 * u64::from(job.settings.spp));
                    match first_non_specular(ctx, o, d, &s, CAMERA_CHAIN_BOUNCE, &mut counts) {
                        Some(end) => probe(pixel, &s, &end.point, end.dir, &mut scratch, &mut counts),
                        None => miss.clone(),
                    }
                })
                .collect::<Vec<_>>()
        },
        |_| {},
    );
    chunks.into_iter().flatten().collect()
}

/// Renders every pixel with `radiance(pixel, o, d, sampler, rays, scratch)`, which traces one
/// camera ray of `pixel` (row-major index): rows in parallel, each pixel the mean of its `spp`
/// jittered samples (stratified when spp is a square), non-finite samples dropped and counted.
/// Returns the film, the rays traced and the numerics.
pub fn render_pixels(
    job: &Job,
    camera: &CameraRays,
    progress: &dyn Progress,
    radiance: impl Fn(usize, Vec3, Vec3, &Sampler, &mut RayCounts, &mut Nearest) -> Terms + Sync,
) -> (Film, RayCounts, Numerics) {
    let (w, h) = (job.settings.width as usize, job.settings.height as usize);
    let spp = job.settings.spp;
    progress.start("camera", h as u64);
    let rows = map_chunks(
        h,
        1,
        job.threads,
        |range| {
            let mut rays = RayCounts::default();
            let mut numerics = Numerics::default();
            let mut scratch = Nearest::default();
            let mut row = Vec::with_capacity(w * range.len());
            for y in range {
                for x in 0..w {
                    let mut mean = PixelMean::default();
                    for s in 0..spp {
                        let index = ((y * w + x) as u64) * u64::from(spp) + u64::from(s);
                        let (sampler, o, d) = camera_ray(job, camera, index);
                        let t = radiance(y * w + x, o, d, &sampler, &mut rays, &mut scratch);
                        mean.add(t, 1.0 / spp as f32);
                    }
                    row.push(mean.finish(1.0 / spp as f32, &mut numerics));
                }
            }
            (row, rays, numerics)
        },
        |n| progress.advance(n as u64),
    );
    progress.finish();
    let mut pixels = Vec::with_capacity(w * h);
    let mut rays = RayCounts::default();
    let mut numerics = Numerics::default();
    for (row, r, n) in rows {
        pixels.extend(row);
        rays += r;
        numerics += n;
    }
    (Film::new(job.settings.width, job.settings.height, pixels), rays, numerics)
}
