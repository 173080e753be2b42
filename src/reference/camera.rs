//! The camera pass: jittered camera rays; mirrors and glass by ray tracing; at the first
//! non-specular hit, Jensen's terms — direct light by light sampling, caustics from the caustic
//! map, indirect diffuse by final gather over the global map (or the global map read directly),
//! and the glossy lobe by one traced ray.
//!
//! Double counting is avoided by construction: final-gather and glossy rays never add emission
//! (that is the direct term) and read full map estimates only at non-specular hits; a gather ray
//! that ends on an emitter through mirrors is an `LS+D` caustic, already in the caustic map.

use super::parallel::map_chunks;
use super::{PhotonMaps, Progress};
use crate::effects::Effects;
use crate::film::{Film, PixelMean, Terms};
use crate::geometry::offset::offset_ray_origin;
use crate::material::{Bsdf, Transport};
use crate::photon_map::{flags, Filter, Lookup, PhotonMap, Reflectance};
use crate::rng::{Domain, Sampler};
use crate::sampling::{cosine_hemisphere, Frame};
use crate::scene::camera::CameraRays;
use crate::scene::{Scene, SurfacePoint};
use crate::settings::Settings;
use crate::stats::{Numerics, RayCounts};
use glam::Vec3;

/// Shadow rays stop this fraction short of the light point (relative, so scale-free).
const SHADOW_SHORTEN: f32 = 1e-4;
/// Sub-stream tags.
pub const TAG_GATHER: u64 = 1 << 32;
pub const TAG_GLOSSY: u64 = 2 << 32;
pub const TAG_LIGHT: u64 = 3 << 32;

/// Everything a camera path needs.
pub struct Context<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The photon maps.
    pub maps: &'a PhotonMaps,
    /// The settings.
    pub settings: &'a Settings,
    /// Global-map radius in scene units.
    pub global_radius: f32,
    /// Caustic-map radius in scene units.
    pub caustic_radius: f32,
    /// Progressive pass: every photon within these radii, not the k nearest.
    pub fixed: Option<crate::settings::FixedRadii>,
    /// What to simulate.
    pub effects: Effects,
    /// Photons the normal filter turned away in this context's estimates
    /// ([`Numerics::photons_filtered`](crate::stats::Numerics::photons_filtered)).
    pub filtered: std::sync::atomic::AtomicU64,
}

impl<'a> Context<'a> {
    /// Prepares radii from the scene size.
    #[must_use]
    pub fn new(scene: &'a Scene, maps: &'a PhotonMaps, settings: &'a Settings) -> Self {
        let d = scene.diagonal();
        Context {
            scene,
            maps,
            settings,
            global_radius: settings.global_radius * d,
            caustic_radius: settings.caustic_radius * d,
            fixed: settings.fixed_radii.clone(),
            effects: Effects::plan(scene, settings),
            filtered: std::sync::atomic::AtomicU64::new(0),
        }
    }

    /// Photons the normal filter has turned away in this context's estimates so far.
    #[must_use]
    pub fn filtered(&self) -> u64 {
        self.filtered.load(std::sync::atomic::Ordering::Relaxed)
    }
}

/// Renders every pixel; returns the film, rays traced and dropped non-finite samples.
pub fn render_image(
    scene: &Scene,
    maps: &PhotonMaps,
    camera: &CameraRays,
    settings: &Settings,
    threads: usize,
    progress: &dyn Progress,
) -> (Film, RayCounts, Numerics) {
    let ctx = Context::new(scene, maps, settings);
    let (film, rays, mut numerics) =
        render_pixels(settings, camera, threads, progress, |pixel, o, d, s, rays, scratch| {
            trace_camera_path(&ctx, pixel, o, d, s, rays, scratch)
        });
    numerics.photons_filtered += ctx.filtered();
    (film, rays, numerics)
}

/// The pixel loop shared by the photon mapper and the path tracer: rows in parallel, each pixel
/// the mean of its jittered samples (stratified when spp is a square), non-finite samples
/// dropped and counted. `radiance(pixel, o, d, sampler, rays, scratch)` traces one camera ray of
/// `pixel` (row-major index).
pub fn render_pixels(
    settings: &Settings,
    camera: &CameraRays,
    threads: usize,
    progress: &dyn Progress,
    radiance: impl Fn(usize, Vec3, Vec3, &Sampler, &mut RayCounts, &mut Vec<(f32, u32)>) -> Terms + Sync,
) -> (Film, RayCounts, Numerics) {
    let (w, h) = (settings.width as usize, settings.height as usize);
    let spp = settings.spp;
    progress.start("camera", h as u64);
    let rows = map_chunks(
        h,
        1,
        threads,
        |range| {
            let mut rays = RayCounts::default();
            let mut numerics = Numerics::default();
            let mut scratch = Vec::new();
            let mut row = Vec::with_capacity(w * range.len());
            for y in range {
                for x in 0..w {
                    let mut mean = PixelMean::default();
                    for s in 0..spp {
                        let index = ((y * w + x) as u64) * spp as u64 + s as u64;
                        let (sampler, (fx, fy)) = camera_sample(settings, index);
                        let (o, d) = camera.ray(x as f32 + fx, y as f32 + fy);
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
    (Film { width: settings.width, height: settings.height, pixels }, rays, numerics)
}

/// Camera sample `index` (sample `index % spp` of pixel `index / spp`): its random stream and its
/// position inside the pixel, jittered within its stratum when spp is a square.
#[must_use]
pub fn camera_sample(settings: &Settings, index: u64) -> (Sampler, (f32, f32)) {
    let spp = settings.spp;
    let s = (index % spp as u64) as u32;
    let strata = (spp as f32).sqrt() as u32;
    let sampler = Sampler::new(settings.seed, Domain::Camera, index);
    let (jx, jy) = (sampler.get(0, 0), sampler.get(0, 1));
    let offset = if strata * strata == spp {
        (((s % strata) as f32 + jx) / strata as f32, ((s / strata) as f32 + jy) / strata as f32)
    } else {
        (jx, jy)
    };
    (sampler, offset)
}

/// Radiance along one camera ray of `pixel`, split into terms.
pub fn trace_camera_path(
    ctx: &Context,
    pixel: usize,
    mut o: Vec3,
    mut d: Vec3,
    s: &Sampler,
    rays: &mut RayCounts,
    scratch: &mut Vec<(f32, u32)>,
) -> Terms {
    let scene = ctx.scene;
    let mut terms = Terms::default();
    let mut beta = Vec3::ONE;
    let mut through_specular = false;
    for depth in 0..=ctx.settings.max_depth {
        rays.camera += 1;
        let Some(hit) = scene.intersect(o, d, f32::INFINITY) else { break };
        let sp = scene.surface(&hit);
        let mat = &scene.materials[sp.material as usize];
        let wo = -d;
        if mat.emission != Vec3::ZERO && wo.dot(sp.frame.ng) > 0.0 {
            let e = beta * mat.emission;
            if through_specular {
                terms.specular += e;
            } else {
                terms.emitted += e;
            }
        }
        if mat.bsdf.is_delta() {
            if depth == ctx.settings.max_depth {
                break;
            }
            let u = [s.get(depth + 1, 0), s.get(depth + 1, 1), s.get(depth + 1, 2)];
            let Some(bs) = mat.bsdf.sample(&sp.frame, wo, u, Transport::Radiance) else { break };
            beta *= bs.weight;
            through_specular = true;
            o = offset_ray_origin(sp.p, sp.p_error, sp.frame.ng, bs.wi);
            d = bs.wi;
            continue;
        }
        let ls = s.fork(TAG_LIGHT + depth as u64);
        let direct = beta * direct_light(ctx, &sp, &mat.bsdf, wo, &ls, rays);
        let caustic = beta * caustic_estimate(ctx, &sp, &mat.bsdf, wo, Some(pixel), scratch);
        let indirect = beta
            * if ctx.effects.final_gather.on {
                final_gather(ctx, &sp, &mat.bsdf, wo, &s.fork(TAG_GATHER + depth as u64), rays, scratch)
            } else {
                global_estimate(ctx, &sp, &mat.bsdf, wo, flags::DIRECT | flags::CAUSTIC, Some(pixel), scratch)
            };
        let glossy =
            beta * glossy_reflection(ctx, &sp, &mat.bsdf, wo, &s.fork(TAG_GLOSSY + depth as u64), rays, scratch);
        if through_specular {
            terms.specular += direct + caustic + indirect + glossy;
        } else {
            terms.direct += direct;
            terms.caustic += caustic;
            terms.indirect += indirect;
            terms.specular += glossy;
        }
        break;
    }
    terms
}

/// A shadow ray and what it carries if nothing blocks it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowRay {
    /// Origin (offset off the surface).
    pub origin: Vec3,
    /// Direction; not unit for rays to a point (the point is at t = 1).
    pub direction: Vec3,
    /// Blocked by hits with t below this.
    pub t_max: f32,
    /// Reflected radiance it adds when unblocked: f·L·|cos|/pdf.
    pub contribution: Vec3,
}

/// The shadow rays of direct light at `sp` toward `wo`: every delta light once, then
/// `light_samples` area-light samples chosen by power. Lights that cannot contribute (behind
/// the surface, back faces, outside a spot cone) get no ray.
pub fn direct_light_rays(
    ctx: &Context,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    s: &Sampler,
    mut emit: impl FnMut(ShadowRay),
) {
    let scene = ctx.scene;
    let (_, ns) = sp.frame.oriented(wo);
    let mut add = |light_index: u32, u: [f32; 2], weight: f32| {
        let light = &scene.lights[light_index as usize];
        let tri = scene.light_triangle(light);
        let Some(inc) = light.sample_incident(tri.as_ref(), sp.p, u) else { return };
        let f = bsdf.eval(&sp.frame, wo, inc.wi);
        let cos = inc.wi.dot(ns).abs();
        if f == Vec3::ZERO || cos == 0.0 {
            return;
        }
        let origin = offset_ray_origin(sp.p, sp.p_error, sp.frame.ng, inc.wi);
        let (direction, t_max) = match inc.point {
            Some((q, _)) => (q - origin, 1.0 - SHADOW_SHORTEN),
            None => (inc.wi, f32::INFINITY),
        };
        emit(ShadowRay { origin, direction, t_max, contribution: f * inc.value * (cos * weight) });
    };
    for &li in &scene.delta_lights {
        add(li, [0.5, 0.5], 1.0);
    }
    if let Some(dist) = &scene.area_power {
        let n = ctx.settings.light_samples;
        for j in 0..n {
            let pick = dist.sample(s.get(j, 0));
            let pmf = dist.pmf(pick) as f32;
            add(scene.area_lights[pick], [s.get(j, 1), s.get(j, 2)], 1.0 / (pmf * n as f32));
        }
    }
}

/// Direct light at `sp` toward `wo`: the unblocked shadow rays' contributions summed.
pub fn direct_light(
    ctx: &Context,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    s: &Sampler,
    rays: &mut RayCounts,
) -> Vec3 {
    let mut sum = Vec3::ZERO;
    direct_light_rays(ctx, sp, bsdf, wo, s, |r| {
        rays.shadow += 1;
        if !ctx.scene.occluded(r.origin, r.direction, r.t_max) {
            sum += r.contribution;
        }
    });
    sum
}

/// Radiance estimate from `map` at `sp` toward `wo` with `k` photons within `radius`, ignoring
/// photons with any `mask` flag.
#[allow(clippy::too_many_arguments)]
fn map_estimate(
    ctx: &Context,
    map: &PhotonMap,
    k: u32,
    radius: f32,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    mask: u8,
    fixed: Option<f32>,
    scratch: &mut Vec<(f32, u32)>,
) -> Vec3 {
    let (ng, _) = sp.frame.oriented(wo);
    let lookup = Lookup {
        p: sp.p,
        k: k as usize,
        r_max: radius,
        kernel: ctx.settings.kernel,
        filter: Filter { n: ng, flags_mask: mask },
    };
    let eval = |wi| bsdf.eval(&sp.frame, wo, wi);
    let f = match *bsdf {
        // Lambertian: f = kd/π above the surface, 0 below — no per-photon call.
        Bsdf::Lambert { kd } => Reflectance::Hemisphere { value: kd * std::f32::consts::FRAC_1_PI, ng },
        _ => Reflectance::PerPhoton(&eval),
    };
    let set = ctx.settings.kernels;
    let e = match (fixed, ctx.settings.visibility) {
        (Some(r), false) => map.estimate_radius(set, &Lookup { r_max: r, ..lookup }, f),
        (None, false) => map.estimate(set, &lookup, f, scratch),
        (fixed, true) => {
            let lookup = fixed.map_or(lookup, |r| Lookup { r_max: r, k: 0, ..lookup });
            let visible = photon_visibility(ctx.scene, sp.p, ng, lookup.r_max);
            map.estimate_visible(set, &lookup, f, scratch, &visible)
        }
    };
    if e.rejected > 0 {
        ctx.filtered.fetch_add(u64::from(e.rejected), std::sync::atomic::Ordering::Relaxed);
    }
    e.radiance
}

/// Whether a photon (position, normal) is visible from the point `q` (normal `n`, on the side
/// the estimate looks from), for [`Settings::visibility`]: the segment between them, both lifted
/// off their surfaces by 10⁻³ of the search radius `r` (far above rounding, far below any wall
/// worth stopping light), meets nothing.
pub fn photon_visibility(scene: &Scene, q: Vec3, n: Vec3, r: f32) -> impl Fn(Vec3, Vec3) -> bool + '_ {
    let lift = 1e-3 * r;
    let from = q + n * lift;
    move |p, m| !scene.occluded(from, p + m * lift - from, 1.0)
}

/// Caustic-map radiance estimate at `sp` toward `wo`; `pixel` when `sp` is a camera path's first
/// non-specular hit (progressive passes may give each pixel its own radius).
pub fn caustic_estimate(
    ctx: &Context,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    pixel: Option<usize>,
    scratch: &mut Vec<(f32, u32)>,
) -> Vec3 {
    let fixed = ctx.fixed.as_ref().map(|r| r.caustic_at(pixel));
    map_estimate(ctx, &ctx.maps.caustic, ctx.settings.caustic_k, ctx.caustic_radius, sp, bsdf, wo, 0, fixed, scratch)
}

/// Global-map radiance estimate at `sp` toward `wo`, ignoring photons with any `mask` flag;
/// `pixel` as for [`caustic_estimate`].
pub fn global_estimate(
    ctx: &Context,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    mask: u8,
    pixel: Option<usize>,
    scratch: &mut Vec<(f32, u32)>,
) -> Vec3 {
    let fixed = ctx.fixed.as_ref().map(|r| r.global_at(pixel));
    map_estimate(ctx, &ctx.maps.global, ctx.settings.k, ctx.global_radius, sp, bsdf, wo, mask, fixed, scratch)
}

/// Final gather: `kd/N · Σ L(x, ωi)` over N cosine-weighted rays, L read from the global map at
/// the first non-specular hit (following mirrors and glass, adding no emission).
pub fn final_gather(
    ctx: &Context,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    s: &Sampler,
    rays: &mut RayCounts,
    scratch: &mut Vec<(f32, u32)>,
) -> Vec3 {
    let kd = bsdf.diffuse();
    if kd == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let (ng, ns) = sp.frame.oriented(wo);
    let frame = Frame::new(ns);
    let n = ctx.settings.gather_rays;
    let mut sum = Vec3::ZERO;
    for g in 0..n {
        let wi = frame.to_world(cosine_hemisphere([s.get(g, 0), s.get(g, 1)]));
        if wi.dot(ng) <= 0.0 {
            continue;
        }
        let o = offset_ray_origin(sp.p, sp.p_error, sp.frame.ng, wi);
        sum += incoming_from_map(ctx, o, wi, &s.fork(g as u64), rays, scratch);
    }
    kd * sum / n as f32
}

/// Follows a ray through mirrors and glass (at most `max_depth` bounces, sampling each with `s`
/// at bounce `first_bounce + depth`) to its first non-specular hit: that point, the incoming
/// direction and the throughput of the specular chain. `None` if it escapes or is absorbed.
pub fn first_non_specular(
    ctx: &Context,
    mut o: Vec3,
    mut d: Vec3,
    s: &Sampler,
    first_bounce: u32,
    rays: &mut RayCounts,
) -> Option<(SurfacePoint, Vec3, Vec3)> {
    let scene = ctx.scene;
    let mut beta = Vec3::ONE;
    for depth in 0..=ctx.settings.max_depth {
        rays.gather += 1;
        let hit = scene.intersect(o, d, f32::INFINITY)?;
        let sp = scene.surface(&hit);
        let bsdf = &scene.materials[sp.material as usize].bsdf;
        if !bsdf.is_delta() {
            return Some((sp, d, beta));
        }
        let b = first_bounce + depth;
        let bs = bsdf.sample(&sp.frame, -d, [s.get(b, 0), s.get(b, 1), s.get(b, 2)], Transport::Radiance)?;
        beta *= bs.weight;
        o = offset_ray_origin(sp.p, sp.p_error, sp.frame.ng, bs.wi);
        d = bs.wi;
    }
    None
}

/// Radiance arriving at `o` from direction `-d`, as the global map sees it at the first
/// non-specular hit (through mirrors and glass; no emission).
fn incoming_from_map(
    ctx: &Context,
    o: Vec3,
    d: Vec3,
    s: &Sampler,
    rays: &mut RayCounts,
    scratch: &mut Vec<(f32, u32)>,
) -> Vec3 {
    let Some((y, d, beta)) = first_non_specular(ctx, o, d, s, 0, rays) else { return Vec3::ZERO };
    let bsdf = &ctx.scene.materials[y.material as usize].bsdf;
    beta * map_radiance(ctx, &y, bsdf, -d, scratch)
}

/// Radiance leaving a non-specular point toward `wo` as the photon maps see it: kd/π × the
/// nearest precomputed irradiance for Lambertian surfaces when that is available (and a point
/// with a similar normal lies within the global radius), the full global-map estimate otherwise.
pub fn map_radiance(ctx: &Context, sp: &SurfacePoint, bsdf: &Bsdf, wo: Vec3, scratch: &mut Vec<(f32, u32)>) -> Vec3 {
    let irr = &ctx.maps.irradiance;
    if let (Bsdf::Lambert { kd }, false) = (bsdf, irr.is_empty()) {
        let (ng, _) = sp.frame.oriented(wo);
        let lookup = Lookup {
            p: sp.p,
            k: 1,
            r_max: ctx.global_radius,
            kernel: ctx.settings.kernel,
            filter: Filter { n: ng, flags_mask: 0 },
        };
        irr.nearest(ctx.settings.kernels, &lookup, scratch);
        if let Some(&(_, i)) = scratch.first() {
            // With visibility on, a point behind a wall is not read: the full estimate below is.
            let p = irr.photon(i as usize);
            if !ctx.settings.visibility || photon_visibility(ctx.scene, sp.p, ng, lookup.r_max)(p.position, p.normal) {
                return *kd * std::f32::consts::FRAC_1_PI * irr.power(i as usize);
            }
        }
    }
    global_estimate(ctx, sp, bsdf, wo, 0, None, scratch)
}

/// The glossy lobe's reflection: one ray sampled from the lobe; at its first non-specular hit,
/// direct light, caustics and the global map without direct and caustic photons (so each path
/// is counted once: emission reached by this ray is already in the direct term).
pub fn glossy_reflection(
    ctx: &Context,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    s: &Sampler,
    rays: &mut RayCounts,
    scratch: &mut Vec<(f32, u32)>,
) -> Vec3 {
    let Some(bs) = bsdf.sample_glossy(&sp.frame, wo, [s.get(0, 0), s.get(0, 1)]) else { return Vec3::ZERO };
    let o = offset_ray_origin(sp.p, sp.p_error, sp.frame.ng, bs.wi);
    let Some((y, d, beta)) = first_non_specular(ctx, o, bs.wi, s, 1, rays) else { return Vec3::ZERO };
    let b = &ctx.scene.materials[y.material as usize].bsdf;
    let direct = direct_light(ctx, &y, b, -d, &s.fork(7), rays);
    let caustic = caustic_estimate(ctx, &y, b, -d, None, scratch);
    let rest = global_estimate(ctx, &y, b, -d, flags::DIRECT | flags::CAUSTIC, None, scratch);
    bs.weight * beta * (direct + caustic + rest)
}
