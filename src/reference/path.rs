//! An unbiased path tracer with next-event estimation, used only to validate the photon mapper's
//! energy: same scene, materials, light sampling and random streams, no photon maps.
//!
//! Emission is added when the camera sees an emitter directly or through mirrors and glass;
//! after a non-specular bounce it is left to light sampling (no double counting, no MIS).
//! Terms, as the photon mapper defines them: `emitted` (seen directly), `direct` (light sampling
//! at a non-specular first hit), `specular` (everything seen when the first hit is a mirror or
//! glass), `indirect` (everything else; the photon mapper splits it into caustic, indirect and the
//! glossy lobe's share of specular).

use super::camera::{direct_light, render_pixels};
use super::Progress;
use crate::film::{Film, Terms};
use crate::geometry::offset::offset_ray_origin;
use crate::material::Transport;
use crate::rng::Sampler;
use crate::scene::camera::CameraRays;
use crate::scene::Scene;
use crate::settings::Settings;
use crate::stats::RayCounts;
use glam::Vec3;

/// Path depth after which Russian roulette starts.
const RR_DEPTH: u32 = 3;

/// Renders the scene by path tracing (`max_depth` bounces).
pub fn render_path_traced(
    scene: &Scene,
    camera: &CameraRays,
    settings: &Settings,
    progress: &dyn Progress,
) -> (Film, RayCounts, crate::stats::Numerics) {
    let empty = super::PhotonMaps::default();
    let ctx = super::camera::Context::new(scene, &empty, settings);
    render_pixels(settings, camera, settings.thread_count(), progress, |_, o, d, s, rays, _| {
        trace_path(&ctx, o, d, s, rays)
    })
}

/// [`render_path_traced`] with the CLI's summary.
pub fn render_path_traced_with_stats(
    scene: &Scene,
    camera: &CameraRays,
    settings: &Settings,
    progress: &dyn Progress,
) -> crate::Result<(Film, crate::stats::RenderStats)> {
    settings.validate()?;
    let t = std::time::Instant::now();
    let (film, rays, numerics) = render_path_traced(scene, camera, settings, progress);
    let none = |name: &str| crate::stats::MapStats {
        reason: format!("the path tracer builds no {name} map: it samples every path from the camera"),
        ..Default::default()
    };
    let stats = crate::stats::RenderStats {
        phases: vec!["path tracing with next-event estimation".into()],
        global_map: none("global"),
        caustic_map: none("caustic"),
        rays,
        numerics: crate::stats::Numerics { load_normals: scene.zero_normals, ..numerics },
        times: crate::stats::PhaseTimes {
            camera_s: t.elapsed().as_secs_f64(),
            total_s: t.elapsed().as_secs_f64(),
            ..Default::default()
        },
        mean_rgb: film.mean().to_array(),
        ..crate::stats::RenderStats::new("path", scene, settings, settings.thread_count())
    };
    Ok((film, stats))
}

fn trace_path(ctx: &super::camera::Context, mut o: Vec3, mut d: Vec3, s: &Sampler, rays: &mut RayCounts) -> Terms {
    let scene = ctx.scene;
    let mut terms = Terms::default();
    let mut beta = Vec3::ONE;
    // The camera's first hit was a mirror or glass: everything found later is `specular`, as in
    // the photon mapper's layers.
    let mut via_specular = false;
    let mut last_delta = true; // previous vertex was the camera or a delta bounce
    for depth in 0..=ctx.settings.max_depth {
        rays.camera += 1;
        let Some(hit) = scene.intersect(o, d, f32::INFINITY) else { break };
        let sp = scene.surface(&hit);
        let mat = &scene.materials[sp.material as usize];
        let wo = -d;
        if last_delta && mat.emission != Vec3::ZERO && wo.dot(sp.frame.ng) > 0.0 {
            let e = beta * mat.emission;
            match (depth, via_specular) {
                (0, _) => terms.emitted += e,
                (_, true) => terms.specular += e,
                _ => terms.indirect += e,
            }
        }
        if depth == ctx.settings.max_depth {
            break;
        }
        if !mat.bsdf.is_delta() {
            let l = beta * direct_light(ctx, &sp, &mat.bsdf, wo, &s.fork(((depth as u64) << 32) | 0xd1), rays);
            match (depth, via_specular) {
                (_, true) => terms.specular += l,
                (0, _) => terms.direct += l,
                _ => terms.indirect += l,
            }
        }
        let u = [s.get(depth + 1, 0), s.get(depth + 1, 1), s.get(depth + 1, 2)];
        let Some(bs) = mat.bsdf.sample(&sp.frame, wo, u, Transport::Radiance) else { break };
        beta *= bs.weight;
        last_delta = bs.delta;
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
        o = offset_ray_origin(sp.p, sp.p_error, sp.frame.ng, bs.wi);
        d = bs.wi;
    }
    terms
}
