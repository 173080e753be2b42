//! An unbiased path tracer with next-event estimation, used only to validate the photon mapper's
//! energy: same scene, materials, light sampling and random streams, no photon maps.
//!
//! Emission is added when the camera sees an emitter directly or through mirrors and glass;
//! after a non-specular bounce an emissive triangle's is weighted by MIS against the light
//! sample taken at that bounce (`transport::mis`: the power heuristic, one BSDF sample against
//! `light_samples` light samples), and with `mis = false` left to light sampling. The
//! environment and the sun are left to light sampling after a non-specular bounce.
//! Terms, as the photon mapper defines them: `emitted` (seen directly), `direct` (light sampling
//! at a non-specular first hit), `specular` (everything seen when the first hit is a mirror or
//! glass), `indirect` (everything else; the photon mapper splits it into caustic, indirect and the
//! glossy lobe's share of specular).
//!
//! In a participating medium ([`crate::medium`]: one filling the scene, or a dielectric's
//! scattering interior, [`Scene::segment_medium`]) each segment samples its first interaction
//! by free flight: where it scatters, the medium point takes light by light
//! sampling through the phase function ([`crate::transport::media`], weighted by MIS against
//! the phase-function sample that continues the path); shadow rays carry the medium's
//! transmittance. Light scattered at the camera's first vertex counts as `direct`, later as
//! `indirect` (there is no `volume` layer yet).

use crate::error::Result;
use crate::film::{Film, Term, Terms};
use crate::job::Job;
use crate::medium::FreeFlight;
use crate::progress::Progress;
use crate::rng::Sampler;
use crate::scene::camera::CameraRays;
use crate::scene::{Receiver, Scene};
use crate::settings::Settings;
use crate::stats::{MapStats, Numerics, PhaseTimes, RayCounts, RenderStats};
use crate::transport::camera::render_pixels;
use crate::transport::direct::{attenuated_direct_light, weighted_direct_light};
use crate::transport::media::{in_scattered_light, medium_receiver};
use crate::transport::mis::{emission_found, receiver, sky_found, Strategies};
use crate::transport::specular::{continue_ray, emission_toward};
use crate::transport::{streams, Context, PhotonMaps};
use glam::Vec3;

/// Path depth after which Russian roulette starts.
const RR_DEPTH: u32 = 3;

/// Renders the scene by path tracing (`max_depth` bounces) with `settings` (validated here).
pub fn render_path_traced(
    scene: &Scene,
    camera: &CameraRays,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<(Film, RayCounts, Numerics)> {
    Ok(trace_image(scene, camera, &Job::new(scene, settings)?, progress))
}

/// The path-traced image of `job`, the rays traced and the numerics.
fn trace_image(scene: &Scene, camera: &CameraRays, job: &Job, progress: &dyn Progress) -> (Film, RayCounts, Numerics) {
    let empty = PhotonMaps::default();
    let ctx = Context::new(scene, &empty, job);
    let media = scene.has_media();
    render_pixels(job, camera, progress, |_, o, d, s, rays, _| trace_path(&ctx, media, o, d, s, rays))
}

/// Renders `job` by path tracing, with the CLI's summary.
#[must_use]
pub fn render_job(scene: &Scene, camera: &CameraRays, job: &Job, progress: &dyn Progress) -> (Film, RenderStats) {
    let t = std::time::Instant::now();
    let (film, rays, numerics) = trace_image(scene, camera, job, progress);
    let none = |name: &str| MapStats {
        reason: format!("the path tracer builds no {name} map: it samples every path from the camera"),
        ..Default::default()
    };
    let stats = RenderStats {
        phases: vec!["path tracing with next-event estimation".into()],
        global_map: none("global"),
        caustic_map: none("caustic"),
        rays,
        numerics: Numerics { load_normals: scene.zero_normals, ..numerics },
        times: PhaseTimes {
            camera_s: t.elapsed().as_secs_f64(),
            total_s: t.elapsed().as_secs_f64(),
            ..Default::default()
        },
        mean_rgb: film.mean().to_array(),
        ..RenderStats::new("path", scene, &job.settings, job.threads)
    };
    (film, stats)
}

/// The term light found at `depth` goes to: `first` (emitted or direct) at the camera's first
/// hit, `specular` on a path whose first hit was a mirror or glass, `indirect` otherwise.
fn path_term(first: Term, depth: u32, via_specular: bool) -> Term {
    match (depth, via_specular) {
        (_, true) => Term::Specular,
        (0, false) => first,
        _ => Term::Indirect,
    }
}

/// Radiance along one camera ray, split into the path tracer's terms.
/// `media`: the scene has a participating medium somewhere ([`Scene::has_media`]).
fn trace_path(ctx: &Context, media: bool, mut o: Vec3, mut d: Vec3, s: &Sampler, rays: &mut RayCounts) -> Terms {
    let scene = ctx.scene;
    let mut terms = Terms::default();
    let mut beta = Vec3::ONE;
    // The camera's first hit was a mirror or glass: everything found later is `specular`, as in
    // the photon mapper's layers.
    let mut via_specular = false;
    // The previous vertex was the camera or a delta bounce.
    let mut last_delta = true;
    // The density with which the last non-delta bounce picked this ray's direction (0: MIS off).
    let mut bsdf_density = 0.0;
    // The point that bounce left from, for the light-sampling density of what it finds.
    let mut from = Receiver::default();
    let mis = if ctx.settings.mis { Strategies::Whole } else { Strategies::LightOnly };
    for depth in 0..=ctx.settings.max_depth {
        rays.camera += 1;
        let found = scene.intersect(o, d, f32::INFINITY);
        // The medium this segment travels in.
        let arrived = if media { scene.segment_medium(found.as_ref(), d) } else { None };
        if let Some(medium) = arrived {
            // Free flight along this segment: bounce `depth`, dims 4–5.
            let length = found.map_or(f32::INFINITY, |h| h.t * d.length());
            match medium.free_flight(length, s.get(depth, 4), s.get(depth, 5)) {
                FreeFlight::Pass { weight } => beta *= weight,
                FreeFlight::Scatter { distance, weight } => {
                    beta *= weight;
                    let dir = d.normalize();
                    let p = o + dir * distance;
                    if depth == ctx.settings.max_depth || beta == Vec3::ZERO {
                        break;
                    }
                    let light_stream = s.fork(streams::path_light(depth));
                    let l = in_scattered_light(ctx, medium, p, dir, &light_stream, ctx.settings.mis, rays);
                    terms.add(path_term(Term::Direct, depth, via_specular), beta * l);
                    // The phase-function sample continues the path: bounce depth + 1, dims 0–1.
                    let phase = medium.phase();
                    let next = phase.sample(dir, [s.get(depth + 1, 0), s.get(depth + 1, 1)]);
                    last_delta = false;
                    if ctx.settings.mis {
                        bsdf_density = phase.eval(dir, next);
                        from = medium_receiver(p, dir);
                    }
                    if depth >= RR_DEPTH {
                        let q = beta.max_element().min(0.95);
                        if !(q > 0.0) || s.get(depth + 1, 3) >= q {
                            break;
                        }
                        beta /= q;
                    }
                    (o, d) = (p, next);
                    continue;
                }
            }
        }
        let Some(hit) = found else {
            // The environment and the suns, counted where light sampling does not (as emitters);
            // after a BSDF sample, the environment weighed against light sampling.
            if last_delta && scene.has_background() {
                terms.add(path_term(Term::Emitted, depth, via_specular), beta * scene.background(d));
            } else if bsdf_density > 0.0 {
                let found = sky_found(ctx, &from, d, bsdf_density);
                terms.add(path_term(Term::Direct, depth - 1, via_specular), beta * found);
            }
            break;
        };
        if scene.scattering_interior(&hit, d).is_none() {
            beta *= scene.interior_transmittance(&hit, d);
        }
        let sp = scene.surface(&hit);
        let bsdf = scene.bsdf(&sp);
        let wo = -d;
        let e = emission_toward(scene, &hit, wo);
        if e != Vec3::ZERO {
            if last_delta {
                terms.add(path_term(Term::Emitted, depth, via_specular), beta * e);
            } else {
                // Found by the previous bounce's BSDF sample: light sampling's partner there.
                let found = emission_found(ctx, &from, &hit, d, bsdf_density);
                terms.add(path_term(Term::Direct, depth - 1, via_specular), beta * found);
            }
        }
        if depth == ctx.settings.max_depth {
            break;
        }
        if !bsdf.is_delta() {
            let light_stream = s.fork(streams::path_light(depth));
            let l = if media {
                // Each shadow ray in the medium on its side of the surface.
                let toward = |dir: Vec3| scene.medium_on_side(hit.tri, dir);
                attenuated_direct_light(ctx, toward, &sp, &bsdf, wo, &light_stream, false, &mis, rays)
            } else {
                weighted_direct_light(ctx, &sp, &bsdf, wo, &light_stream, &mis, rays)
            };
            terms.add(path_term(Term::Direct, depth, via_specular), beta * l);
        }
        let Some(bs) = continue_ray(&sp, &bsdf, wo, s, streams::CAMERA_CHAIN_BOUNCE + depth) else { break };
        beta *= bs.weight;
        last_delta = bs.delta;
        if ctx.settings.mis && !bs.delta {
            bsdf_density = bsdf.pdf(&sp.frame, wo, bs.dir);
            from = receiver(&sp, &bsdf, wo);
        }
        if depth == 0 && bs.delta {
            via_specular = true;
        }
        if depth >= RR_DEPTH {
            let q = beta.max_element().min(0.95);
            if !(q > 0.0) || s.get(depth + 1, 3) >= q {
                break;
            }
            beta /= q;
        }
        (o, d) = (bs.origin, bs.dir);
    }
    terms
}
