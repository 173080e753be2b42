//! The photon pass: emit photons from lights in proportion to power, trace them with Russian
//! roulette at constant power, and store them at non-specular hits.
//!
//! Global map: every non-specular hit (paths L{S|D}*D). Caustic map: photons whose every bounce
//! so far was specular (LS+D); their paths are discarded at the first hit when it is not
//! specular (a Jensen projection map reduced to rejection: unbiased, as the discarded paths still
//! count in the emitted total). Paths are emitted in fixed batches until the map holds its target,
//! so the photon set is the same at any thread count; the map keeps exactly the photons asked for,
//! up to the path that stores the last of them ([`stop_path`]). Stored power = Φ-weighted path
//! power divided by the number of paths emitted up to that one.

use super::parallel::map_chunks;
use super::Progress;
use crate::geometry::offset::{barycentric_error, offset_ray_origin};
use crate::material::{Bsdf, SurfaceFrame, Transport};
use crate::photon_map::{flags, Photon};
use crate::rng::{Domain, Sampler};
use crate::scene::{Scene, SurfacePoint};
use crate::settings::Settings;
use crate::stats::Numerics;
use glam::Vec3;

/// Paths per batch: emission runs batch by batch until a map reaches its target.
pub const BATCH: usize = 16_384;
/// Paths per work chunk inside a batch.
const CHUNK: usize = 1024;
pub use crate::settings::MAX_PATHS_PER_PHOTON;

/// What a photon pass produced.
pub struct PhotonPass {
    /// Stored photons, power already divided by `emitted`.
    pub photons: Vec<Photon>,
    /// Paths emitted.
    pub emitted: u64,
    /// Ray segments traced.
    pub rays: u64,
    /// Paths dropped for non-finite power, at emission and at a bounce (the photon fields of
    /// [`Numerics`]).
    pub numerics: Numerics,
}

/// Emits batches of paths until `target` photons are stored (or the path cap is reached).
pub fn trace_photons(
    scene: &Scene,
    settings: &Settings,
    domain: Domain,
    target: u32,
    threads: usize,
    progress: &dyn Progress,
) -> PhotonPass {
    let name = if domain == Domain::CausticPhoton { "caustic photons" } else { "global photons" };
    progress.start(name, target as u64);
    let mut photons = Vec::new();
    let (mut emitted, mut rays, mut numerics) = (0u64, 0u64, Numerics::default());
    let cap = (target as u64 * MAX_PATHS_PER_PHOTON).max(BATCH as u64);
    let mut reported = 0u64;
    while (photons.len() as u64) < target as u64 && emitted < cap {
        let first = emitted;
        let chunks = map_chunks(
            BATCH,
            CHUNK,
            threads,
            |range| {
                let mut out = Vec::new();
                let mut stored = Vec::with_capacity(range.len());
                let (mut r, mut nf) = (0u64, Numerics::default());
                for i in range {
                    let n = out.len();
                    trace_path(scene, settings, domain, first + i as u64, &mut out, &mut r, &mut nf);
                    stored.push((out.len() - n) as u32);
                }
                (out, r, nf, stored)
            },
            |_| {},
        );
        let before = photons.len() as u64;
        let mut per_path = Vec::with_capacity(BATCH);
        for (out, r, nf, stored) in chunks {
            photons.extend(out);
            per_path.extend(stored);
            rays += r;
            numerics += nf;
        }
        emitted += BATCH as u64;
        if photons.len() as u64 >= target as u64 {
            emitted = first + stop_path(&per_path, target as u64 - before) + 1;
            photons.truncate(target as usize);
        }
        let now = (photons.len() as u64).min(target as u64);
        progress.advance(now - reported);
        reported = now;
    }
    progress.finish();
    normalise_power(&mut photons, emitted);
    PhotonPass { photons, emitted, rays, numerics }
}

/// The path (counted from a batch's first) that stores the `need`-th photon of the batch, given
/// how many each path stored: emission stops there, so a map holds exactly the photons asked
/// for and its power is divided by the paths emitted up to that one. Its later bounces are not
/// stored (as in Jensen 1996, where emission stops when the map is full): one path of the
/// thousands, a bias far below the estimates' noise.
#[must_use]
pub fn stop_path(stored_per_path: &[u32], need: u64) -> u64 {
    let mut sum = 0u64;
    let j = stored_per_path.iter().position(|&n| {
        sum += u64::from(n);
        sum >= need
    });
    debug_assert!(j.is_some(), "the batch stored fewer than the {need} photons it is cut at");
    j.unwrap_or(stored_per_path.len().saturating_sub(1)) as u64
}

/// Divides stored photons' power by the number of paths emitted: each then carries Φ/N.
pub fn normalise_power(photons: &mut [Photon], emitted: u64) {
    let scale = 1.0 / emitted as f32;
    for p in photons {
        p.power *= scale;
    }
}

/// A photon between bounces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonRay {
    /// Ray origin.
    pub origin: Vec3,
    /// Unit direction.
    pub dir: Vec3,
    /// Power (not yet divided by the paths emitted).
    pub power: Vec3,
    /// True while every bounce so far was specular.
    pub specular_only: bool,
}

/// Starts photon path `index` of `domain`: picks a light by power and samples its emission.
/// `None` if the emission is not finite.
#[must_use]
pub fn start_photon(scene: &Scene, settings: &Settings, domain: Domain, index: u64) -> Option<PhotonRay> {
    let s = Sampler::new(settings.seed, domain, index);
    let li = scene.light_power.sample(s.get(0, 0));
    let pmf = scene.light_power.pmf(li) as f32;
    let light = &scene.lights[li];
    let tri = scene.light_triangle(light);
    let em = light.sample_emission(
        tri.as_ref(),
        (scene.centre(), scene.radius()),
        [s.get(0, 1), s.get(0, 2), s.get(0, 3), s.get(0, 4)],
    );
    let power = em.power / pmf;
    if !power.is_finite() || !em.direction.is_finite() {
        return None;
    }
    let origin = match (em.normal, tri) {
        (Some(n), Some(t)) => {
            // The emission point's rounding error is bounded like any barycentric point.
            let err = barycentric_error([1.0, 1.0, 1.0], t.p[0], t.p[1], t.p[2]);
            offset_ray_origin(em.origin, err, n, em.direction)
        }
        _ => em.origin,
    };
    Some(PhotonRay { origin, dir: em.direction, power, specular_only: true })
}

/// At a non-specular hit: stores the photon where its map wants it; returns whether the path
/// goes on. The caustic pass keeps only paths whose first hit is specular and ends each at its
/// first non-specular hit.
pub fn deposit_photon(
    domain: Domain,
    sp: &SurfacePoint,
    photon: &PhotonRay,
    bounce: u32,
    out: &mut Vec<Photon>,
) -> bool {
    let caustic = domain == Domain::CausticPhoton;
    if caustic && bounce == 0 {
        return false;
    }
    let wo = -photon.dir;
    let (ng, _) = sp.frame.oriented(wo);
    let mut f = 0;
    if bounce == 0 {
        f |= flags::DIRECT;
    }
    if photon.specular_only && bounce > 0 {
        f |= flags::CAUSTIC;
    }
    if !caustic || f & flags::CAUSTIC != 0 {
        out.push(Photon { position: sp.p, power: photon.power, wi: wo, normal: ng, flags: f });
    }
    !caustic
}

/// What scattering did to a photon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scattered {
    /// It goes on.
    Continue(PhotonRay),
    /// Absorbed (Russian roulette or no valid direction).
    Absorbed,
    /// Its power stopped being finite; dropped and counted.
    NonFinite,
    /// The BSDF's sample had zero pdf; dropped and counted.
    ZeroPdf,
}

/// Scatters a photon at `sp` (BSDF sample, shading-normal correction, Russian roulette) with the
/// random numbers of bounce `bounce + 1`.
#[must_use]
pub fn scatter_photon(s: &Sampler, sp: &SurfacePoint, bsdf: &Bsdf, photon: &PhotonRay, bounce: u32) -> Scattered {
    let wo = -photon.dir;
    let u = [s.get(bounce + 1, 0), s.get(bounce + 1, 1), s.get(bounce + 1, 2)];
    let bs = match bsdf.sample_checked(&sp.frame, wo, u, Transport::Power) {
        Ok(Some(bs)) => bs,
        Ok(None) => return Scattered::Absorbed,
        Err(_) => return Scattered::ZeroPdf,
    };
    // Photons carry power, the adjoint of radiance: with shading normals the BSDF is not
    // symmetric, and Veach's correction |wo·ns||wi·ng| / (|wo·ng||wi·ns|) makes photon
    // transport agree with camera paths (Veach 1997 §5.3; pbrt-v4 CorrectShadingNormal).
    let weight = bs.weight * shading_normal_correction(&sp.frame, wo, bs.wi);
    // Russian roulette keeps the largest channel's power constant: never gains energy.
    let p_survive = weight.max_element().min(1.0);
    if !(p_survive > 0.0) || s.get(bounce + 1, 3) >= p_survive {
        return Scattered::Absorbed;
    }
    let power = photon.power * weight / p_survive;
    if !power.is_finite() {
        return Scattered::NonFinite;
    }
    Scattered::Continue(PhotonRay {
        origin: offset_ray_origin(sp.p, sp.p_error, sp.frame.ng, bs.wi),
        dir: bs.wi,
        power,
        specular_only: photon.specular_only && bs.delta,
    })
}

/// Traces photon path `index` of `domain`, appending stored photons (un-normalised power) to `out`.
pub fn trace_path(
    scene: &Scene,
    settings: &Settings,
    domain: Domain,
    index: u64,
    out: &mut Vec<Photon>,
    rays: &mut u64,
    numerics: &mut Numerics,
) {
    let Some(mut photon) = start_photon(scene, settings, domain, index) else {
        numerics.photon_emission += 1;
        return;
    };
    let s = Sampler::new(settings.seed, domain, index);
    for bounce in 0..settings.max_depth {
        *rays += 1;
        let Some(hit) = scene.intersect(photon.origin, photon.dir, f32::INFINITY) else {
            numerics.photon_escaped += u64::from(scene.encloses_lights);
            break;
        };
        let sp = scene.surface(&hit);
        let bsdf = scene.materials[sp.material as usize].bsdf;
        if !bsdf.is_delta() && !deposit_photon(domain, &sp, &photon, bounce, out) {
            break;
        }
        match scatter_photon(&s, &sp, &bsdf, &photon, bounce) {
            Scattered::Continue(next) => photon = next,
            Scattered::Absorbed => break,
            Scattered::NonFinite => {
                numerics.photon_scatter += 1;
                break;
            }
            Scattered::ZeroPdf => {
                numerics.photon_zero_pdf += 1;
                break;
            }
        }
    }
}

/// Veach's adjoint correction for shading normals, `|wo·ns||wi·ng| / (|wo·ng||wi·ns|)`; 1 where
/// the shading normal is the geometric one, 0 where a denominator vanishes.
#[must_use]
pub fn shading_normal_correction(frame: &SurfaceFrame, wo: Vec3, wi: Vec3) -> f32 {
    let (ng, ns) = frame.oriented(wo);
    if ns == ng {
        return 1.0;
    }
    let num = wo.dot(ns).abs() * wi.dot(ng).abs();
    let den = wo.dot(ng).abs() * wi.dot(ns).abs();
    if den > 0.0 {
        num / den
    } else {
        0.0
    }
}

/// Powers of the first-hit photons of a global pass, for flux checks: their sum should be the
/// lights' power (every emitted photon lands somewhere in a closed scene).
#[must_use]
pub fn first_hit_power(photons: &[Photon]) -> Vec3 {
    photons.iter().filter(|p| p.flags & flags::DIRECT != 0).map(|p| p.power).sum()
}

#[cfg(test)]
mod tests {
    use super::stop_path;

    /// The path that stores the `need`-th photon of a batch: paths storing nothing are passed
    /// over, and a path whose photons straddle the count is the one emission stops at.
    #[test]
    fn emission_stops_at_the_path_that_stores_the_last_photon() {
        let stored = [0, 2, 0, 3, 1];
        let cuts: Vec<u64> = (1..=6).map(|need| stop_path(&stored, need)).collect();
        assert_eq!(cuts, [1, 1, 3, 3, 3, 4]);
    }
}
