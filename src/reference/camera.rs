//! The oracle's camera pass, one ray at a time: jittered camera rays; mirrors and glass by ray
//! tracing; at the first non-specular hit, Jensen's terms — direct light by light sampling,
//! caustics from the caustic map, indirect diffuse by final gather over the global map (with the
//! secondary gather where a gather ray lands near; or the global map read directly), and the
//! glossy lobe by one traced ray. In a medium filling the scene camera rays march each segment
//! and gather rays sample free flight; the volume maps and light sampling say what the medium
//! scatters (`transport::volume`). Every vertex is the transport core's; only the loops are here.
//!
//! Double counting is avoided by construction: emission that a final-gather or glossy ray hits
//! straight away belongs to the direct term, weighted by MIS against the light samples
//! (`transport::mis`; with `mis = false` it is left to light sampling); the rays read full map
//! estimates only at non-specular hits; a gather ray that ends on an emitter through mirrors is
//! an `LS+D` caustic, already in the caustic map.

use crate::film::{Film, Term, Terms};
use crate::job::Job;
use crate::material::Bsdf;
use crate::photon_map::Nearest;
use crate::progress::Progress;
use crate::rng::Sampler;
use crate::scene::camera::CameraRays;
use crate::scene::{Scene, SurfacePoint};
use crate::stats::{Numerics, RayCounts};
use crate::transport::camera::render_pixels;
use crate::transport::direct::{delta_light, direct_light, weighted_direct_light};
use crate::transport::estimate::{camera_indirect_estimate, caustic_estimate, indirect_estimate};
use crate::transport::gather::{glossy_density, glossy_ray, lands_near, trace_gather_rays};
use crate::transport::lobe::{gather_landing, lobe_escape, lobe_ray, Found};
use crate::transport::mis::{emission_found, receiver, sky_found, Strategies};
use crate::transport::specular::{continue_chain, emission_toward, follow_chain, Chain, ChainEnd};
use crate::transport::volume::{gather_in_medium, march_camera_segment};
use crate::transport::{streams, Context, PhotonMaps};
use glam::Vec3;

/// Renders every pixel; returns the film, rays traced and dropped non-finite samples.
pub fn render_image(
    scene: &Scene,
    maps: &PhotonMaps,
    camera: &CameraRays,
    job: &Job,
    progress: &dyn Progress,
) -> (Film, RayCounts, Numerics) {
    let ctx = Context::new(scene, maps, job);
    let (film, rays, mut numerics) = render_pixels(job, camera, progress, |pixel, o, d, s, rays, scratch| {
        trace_camera_path(&ctx, pixel, o, d, s, rays, scratch)
    });
    numerics.photons_filtered += ctx.filtered();
    numerics.camera_depth_cut += ctx.cuts();
    (film, rays, numerics)
}

/// Radiance along one camera ray of `pixel`, split into terms.
pub fn trace_camera_path(
    ctx: &Context,
    pixel: usize,
    mut o: Vec3,
    mut d: Vec3,
    s: &Sampler,
    rays: &mut RayCounts,
    scratch: &mut Nearest,
) -> Terms {
    let scene = ctx.scene;
    let mut terms = Terms::default();
    let mut beta = Vec3::ONE;
    let mut through_specular = false;
    for depth in 0..=ctx.settings.max_depth {
        rays.camera += 1;
        let hit = scene.intersect(o, d, f32::INFINITY);
        // In a medium filling the scene: the light the medium scatters toward the camera along
        // the segment, by term, and the transmittance to what lies beyond (`transport::volume`).
        if let Some(medium) = scene.filling_medium(hit.as_ref(), d) {
            let length = hit.map_or(f32::INFINITY, |h| h.t);
            let light = s.fork(streams::light(depth));
            let stream = (s, streams::segment(depth));
            let l = march_camera_segment(ctx, medium, o, d, length, stream, &light, rays, scratch);
            terms.add(Term::Direct.seen(through_specular), beta * l.direct);
            terms.add(Term::Caustic.seen(through_specular), beta * l.caustic);
            terms.add(Term::Indirect.seen(through_specular), beta * l.indirect);
            beta *= medium.transmittance(length);
            if beta == Vec3::ZERO {
                break;
            }
        }
        let Some(hit) = hit else {
            // Leaving the scene: the environment and the sun, seen directly or through mirrors.
            if scene.has_background() {
                terms.add(Term::Emitted.seen(through_specular), beta * scene.background(d));
            }
            break;
        };
        beta *= scene.interior_transmittance(&hit, d);
        let sp = scene.surface(&hit);
        let bsdf = scene.bsdf(&sp);
        let wo = -d;
        let e = emission_toward(scene, &hit, wo);
        if e != Vec3::ZERO {
            terms.add(Term::Emitted.seen(through_specular), beta * e);
        }
        // Mirrors and glass, and what photons pass as specular (frosted glass, smooth rough
        // metal): the path goes on by sampling, so the lights and sky seen through them are
        // found as emission, as their photons' caustics are found in the caustic map.
        if bsdf.is_delta() || bsdf.photon_specular() {
            if !bsdf.is_delta() && !scene.delta_lights.is_empty() {
                let d = delta_light(ctx, &sp, &bsdf, wo, &s.fork(streams::light(depth)), rays);
                terms.add(Term::Direct.seen(through_specular), beta * d);
            }
            if depth == ctx.settings.max_depth {
                ctx.cut();
                break;
            }
            let Some(next) = continue_chain(&sp, &bsdf, wo, s, streams::CAMERA_CHAIN_BOUNCE + depth, depth) else {
                break;
            };
            beta *= next.weight;
            through_specular = true;
            (o, d) = (next.origin, next.dir);
            continue;
        }
        let mis = Strategies::at_camera_hit(ctx, &bsdf);
        let lit = weighted_direct_light(ctx, &sp, &bsdf, wo, &s.fork(streams::light(depth)), &mis, rays);
        let caustic = caustic_estimate(ctx, &sp, &bsdf, wo, Some(pixel), scratch).finish(ctx);
        let indirect = if ctx.effects.final_gather.on {
            final_gather(ctx, &sp, &bsdf, wo, &s.fork(streams::gather(depth)), &mis, rays, scratch)
        } else {
            camera_indirect_estimate(ctx, &sp, &bsdf, wo, Some(pixel), scratch).finish(ctx).into()
        };
        let glossy = glossy_reflection(ctx, &sp, &bsdf, wo, &s.fork(streams::glossy(depth)), &mis, rays, scratch);
        // Light sampling's share of the emitters' light, then what the gather and glossy rays
        // found of it.
        let direct = beta * lit + beta * indirect.emission + beta * glossy.emission;
        let (caustic_l, indirect_l, glossy_l) =
            (beta * caustic.radiance, beta * indirect.radiance, beta * glossy.radiance);
        if through_specular {
            terms.specular += direct + caustic_l + indirect_l + glossy_l;
        } else {
            terms.direct += direct;
            terms.caustic += caustic_l;
            terms.indirect += indirect_l;
            terms.specular += glossy_l;
        }
        terms.bias += beta * (caustic.bias + indirect.bias + glossy.bias);
        break;
    }
    terms
}

/// Radiance found by photon-map estimates, with their estimated bias weighted the same way,
/// and the emission the rays that made them hit straight away (MIS-weighted: the direct term's).
#[derive(Clone, Copy, Debug, Default)]
pub struct Estimated {
    /// Radiance.
    pub radiance: Vec3,
    /// Its bias ([`crate::photon_map::Estimate::bias`]).
    pub bias: Vec3,
    /// Emission found by the rays, weighted against light sampling ([`emission_found`]).
    pub emission: Vec3,
}

impl From<crate::photon_map::Estimate> for Estimated {
    fn from(e: crate::photon_map::Estimate) -> Self {
        Estimated { radiance: e.radiance, bias: e.bias, emission: Vec3::ZERO }
    }
}

/// Final gather: `kd/N · Σ L(x, ωi)` over the N gather rays, L read from the photon maps at
/// each ray's first non-specular hit (following mirrors and glass), or by the secondary gather
/// where that hit is near (`gather_hit`); and the emission the rays hit straight away,
/// weighted against light sampling by `mis`.
#[allow(clippy::too_many_arguments)]
pub fn final_gather(
    ctx: &Context,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    s: &Sampler,
    mis: &Strategies,
    rays: &mut RayCounts,
    scratch: &mut Nearest,
) -> Estimated {
    let kd = bsdf.diffuse();
    if kd == Vec3::ZERO {
        return Estimated::default();
    }
    let n = ctx.settings.gather_rays;
    let (mut sum, mut bias, mut emission) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
    // A rough plastic weighs each ray by its base's share seen through the coat; for the others
    // the weight is kd for every ray, applied once at the end.
    let varies = bsdf.gather_varies();
    let r = receiver(sp, bsdf, wo);
    trace_gather_rays(ctx, sp, wo, n, s, rays, |chain, wi, stream, rays| match chain {
        Chain::Hit(end) => {
            let e = gather_hit(ctx, end, stream, rays, scratch);
            let w = if varies { bsdf.gather_weight(&sp.frame, wo, wi) * end.beta } else { end.beta };
            sum += w * e.radiance;
            bias += w * e.bias;
            if end.bounces == 0 {
                emission += w * emission_found(ctx, &r, &end.hit, end.dir, mis.gather_density(sp, wo, wi));
            }
        }
        // Stopped in the medium filling the scene: the global volume map there.
        Chain::Medium(end) => {
            let w = if varies { bsdf.gather_weight(&sp.frame, wo, wi) } else { Vec3::ONE };
            sum += w * gather_in_medium(ctx, end, rays, scratch);
        }
        // Leaving the scene straight away: the environment, weighed against its light samples.
        Chain::Escaped { dir, bounces: 0, .. } => {
            let w = if varies { bsdf.gather_weight(&sp.frame, wo, wi) } else { Vec3::ONE };
            emission += w * sky_found(ctx, &r, *dir, mis.gather_density(sp, wo, wi));
        }
        _ => {}
    });
    let scale = if varies { Vec3::ONE } else { kd };
    Estimated { radiance: scale * sum / n as f32, bias: scale * bias / n as f32, emission: scale * emission / n as f32 }
}

/// Radiance a gather ray (stream `chain`) finds where it ends: the photon maps' there, or, where
/// it lands near its origin, the secondary gather's — direct light, the caustic map and one more
/// gather ray that reads the maps (`transport::gather`).
fn gather_hit(
    ctx: &Context,
    end: &ChainEnd,
    chain: &Sampler,
    rays: &mut RayCounts,
    scratch: &mut Nearest,
) -> Estimated {
    let (y, wo) = (&end.point, -end.dir);
    let bsdf = &ctx.scene.bsdf(y);
    if !lands_near(end.hit.t, end.bounces, bsdf, ctx.secondary_gather) {
        let e = gather_landing(ctx, end, chain, rays, scratch);
        return Estimated { radiance: e.radiance, bias: e.bias, emission: Vec3::ZERO };
    }
    let direct = direct_light(ctx, y, bsdf, wo, &chain.fork(streams::SECONDARY_LIGHT), rays);
    let caustic = caustic_estimate(ctx, y, bsdf, wo, None, scratch).finish(ctx);
    let kd = bsdf.diffuse();
    let mut far = Estimated::default();
    // A black surface sends no gather ray (as in `final_gather` and the wavefront engine).
    if kd != Vec3::ZERO {
        trace_gather_rays(ctx, y, wo, 1, &chain.fork(streams::SECONDARY_GATHER), rays, |z, _, stream, rays| match z {
            Chain::Hit(z) => {
                let e = gather_landing(ctx, z, stream, rays, scratch);
                far = Estimated { radiance: z.beta * e.radiance, bias: z.beta * e.bias, emission: Vec3::ZERO };
            }
            Chain::Medium(z) => {
                far = Estimated { radiance: gather_in_medium(ctx, z, rays, scratch), ..Default::default() }
            }
            _ => {}
        });
    }
    Estimated {
        radiance: direct + caustic.radiance + kd * far.radiance,
        bias: caustic.bias + kd * far.bias,
        emission: Vec3::ZERO,
    }
}

/// The glossy lobe's reflection: one ray sampled from the lobe; at its first non-specular hit,
/// direct light, caustics and the global map without direct and caustic photons (so each path
/// is counted once) — on a narrow lobe there, the base's and the lobe's own ray
/// (`transport::lobe`) — and the emission it hits straight away, weighted against light
/// sampling by `mis` (the direct term's). The bias is that of the estimates.
#[allow(clippy::too_many_arguments)]
pub fn glossy_reflection(
    ctx: &Context,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    s: &Sampler,
    mis: &Strategies,
    rays: &mut RayCounts,
    scratch: &mut Nearest,
) -> Estimated {
    let Some(ray) = glossy_ray(sp, bsdf, wo, s) else { return Estimated::default() };
    let density = glossy_density(&ray, mis, sp, bsdf, wo);
    // From a narrow lobe, whose caustic estimate reads its base alone, the ray also counts what
    // it finds through mirrors and glass, and the sky where nothing else finds it
    // (`transport::lobe`).
    let narrow = bsdf.narrow_lobe();
    let (y, d, beta, hit, bounces) = match follow_chain(ctx, ray.origin, ray.dir, s, streams::GLOSSY_CHAIN_BOUNCE, rays)
    {
        Chain::Hit(ChainEnd { point, dir, beta, hit, bounces }) => (point, dir, beta, hit, bounces),
        // Leaving the scene: the environment straight away, weighed against its light samples
        // (the direct term's, as emitters are); from a narrow lobe, the sky through mirrors and
        // glass too.
        Chain::Escaped { dir, beta, bounces } if bounces == 0 || narrow => {
            let sky = ray.weight * beta * lobe_escape(ctx, &receiver(sp, bsdf, wo), dir, bounces, density);
            return if bounces == 0 {
                Estimated { emission: sky, ..Default::default() }
            } else {
                Estimated { radiance: sky, ..Default::default() }
            };
        }
        // Stopped in the medium filling the scene: the global volume map there.
        Chain::Medium(end) => {
            return Estimated {
                radiance: ray.weight * gather_in_medium(ctx, &end, rays, scratch),
                ..Default::default()
            };
        }
        _ => return Estimated::default(),
    };
    let b = &ctx.scene.bsdf(&y);
    // On a narrow lobe the maps read the base and the lobe sends its own ray (`transport::lobe`),
    // against which the light samples there are weighed.
    let lit = Strategies::at_landing(ctx, b);
    let direct = weighted_direct_light(ctx, &y, b, -d, &s.fork(streams::GLOSSY_HIT_LIGHT), &lit, rays);
    let caustic = caustic_estimate(ctx, &y, b, -d, None, scratch).finish(ctx);
    let (rest, lobe) = if b.narrow_lobe() {
        (
            camera_indirect_estimate(ctx, &y, b, -d, None, scratch).finish(ctx),
            lobe_ray(ctx, &y, b, -d, &s.fork(streams::LANDING_LOBE), Some(&lit), rays, scratch),
        )
    } else {
        (indirect_estimate(ctx, &y, b, -d, None, scratch).finish(ctx), Found::default())
    };
    let w = ray.weight * beta;
    let (emission, through) = if bounces == 0 {
        (w * emission_found(ctx, &receiver(sp, bsdf, wo), &hit, d, density), Vec3::ZERO)
    } else if narrow {
        (Vec3::ZERO, emission_toward(ctx.scene, &hit, -d))
    } else {
        (Vec3::ZERO, Vec3::ZERO)
    };
    Estimated {
        radiance: w * (direct + caustic.radiance + rest.radiance + lobe.radiance + through),
        bias: w * (caustic.bias + rest.bias + lobe.bias),
        emission,
    }
}
