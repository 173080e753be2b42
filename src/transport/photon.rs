//! Photon transport, one vertex at a time: emission from the lights in proportion to power,
//! deposit at non-specular hits, scattering with Russian roulette at constant power, and the
//! tally that stops emission at exactly the photons a map asks for.
//!
//! Global map: every non-specular hit (paths L{S|D}*D). Caustic map: photons whose every bounce
//! so far was specular (LS+D); their paths are discarded at the first hit when it is not
//! specular (a Jensen projection map reduced to rejection: unbiased, as the discarded paths still
//! count in the emitted total). Paths are emitted in fixed batches of [`BATCH`] until the map
//! holds its target, so the photon set is the same at any thread count and in every engine.
//! Stored power = Φ-weighted path power divided by the number of paths emitted.

use crate::geometry::offset::{barycentric_error, offset_ray_origin};
use crate::material::{Bsdf, SurfaceFrame, Transport};
use crate::photon_map::{flags, Photon};
use crate::rng::{Domain, Sampler};
use crate::scene::{Scene, SurfacePoint};
use crate::settings::MAX_PATHS_PER_PHOTON;
use glam::Vec3;

/// Paths per batch: emission runs batch by batch until a map reaches its target.
pub const BATCH: usize = 16_384;

/// A map's photons as batches of paths come in, and the stopping rule: emission stops at the
/// path that stores the target's last photon, so a map holds exactly the photons asked for and
/// its power is divided by the paths emitted up to that one. That path's later bounces are not
/// stored (as in Jensen 1996, where emission stops when the map is full): one path of thousands,
/// a bias far below the estimate's noise. Emission also stops after
/// [`MAX_PATHS_PER_PHOTON`] paths per wanted photon, for scenes that store almost nothing.
#[derive(Debug, Default)]
pub struct Tally {
    target: u64,
    cap: u64,
    photons: Vec<Photon>,
    emitted: u64,
}

impl Tally {
    /// An empty tally for a map of `target` photons.
    #[must_use]
    pub fn new(target: u32) -> Self {
        let target = u64::from(target);
        Tally { target, cap: (target * MAX_PATHS_PER_PHOTON).max(BATCH as u64), photons: Vec::new(), emitted: 0 }
    }

    /// Whether another batch should be emitted.
    #[must_use]
    pub fn wants_more(&self) -> bool {
        (self.photons.len() as u64) < self.target && self.emitted < self.cap
    }

    /// Index of the next batch's first path (the paths emitted so far).
    #[must_use]
    pub fn emitted(&self) -> u64 {
        self.emitted
    }

    /// Photons stored so far.
    #[must_use]
    pub fn stored(&self) -> u64 {
        self.photons.len() as u64
    }

    /// Batches left before the path cap.
    #[must_use]
    pub fn batches_left(&self) -> usize {
        (self.cap - self.emitted.min(self.cap)).div_ceil(BATCH as u64) as usize
    }

    /// Adds the next batch, paths `emitted()..emitted() + BATCH`: the photons its paths stored,
    /// in path order (and bounce order within a path), each with its path index.
    pub fn add_batch(&mut self, stored: impl IntoIterator<Item = (u64, Photon)>) {
        let end = self.emitted + BATCH as u64;
        for (path, photon) in stored {
            debug_assert!((self.emitted..end).contains(&path), "path {path} is not in this batch");
            self.photons.push(photon);
            if self.photons.len() as u64 == self.target {
                self.emitted = path + 1;
                return;
            }
        }
        self.emitted = end;
    }

    /// The stored photons, each carrying its path's power over the paths emitted, and the paths
    /// emitted.
    #[must_use]
    pub fn finish(mut self) -> (Vec<Photon>, u64) {
        normalise_power(&mut self.photons, self.emitted);
        (self.photons, self.emitted)
    }
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

/// How a photon path starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Start {
    /// A photon leaves the light.
    Photon(PhotonRay),
    /// The sample carries no light: an aimed caustic photon behind its area light or outside
    /// its spot's cone. The path counts as emitted and stores nothing.
    Dark,
    /// The emission is not finite (dropped and counted).
    NonFinite,
}

/// Starts photon path `index` of `domain` with the random streams of `seed`: picks a light by
/// power and samples its emission; with `aim` the caustic pass aims at the scene's specular
/// objects ([`super::aim`]).
#[must_use]
pub fn start_photon(scene: &Scene, seed: u64, domain: Domain, index: u64, aim: bool) -> Start {
    let s = Sampler::new(seed, domain, index);
    let li = scene.light_power.sample(s.get(0, 0));
    let pmf = scene.light_power.pmf(li) as f32;
    let light = &scene.lights[li];
    let tri = scene.light_triangle(light);
    let u = [s.get(0, 1), s.get(0, 2), s.get(0, 3), s.get(0, 4)];
    let em = if aim && domain == Domain::CausticPhoton && !scene.caustic_targets.is_empty() {
        match super::aim::aimed_emission(scene, light, [u[0], u[1], u[2], u[3], s.get(0, 5)]) {
            Some(em) => em,
            None => return Start::Dark,
        }
    } else {
        scene.sample_emission(light, u)
    };
    let power = em.power / pmf;
    if !power.is_finite() || !em.direction.is_finite() {
        return Start::NonFinite;
    }
    if power == Vec3::ZERO {
        // A black texel of an emission texture, or an environment sample of no light.
        return Start::Dark;
    }
    let origin = match (em.normal, tri) {
        (Some(n), Some(t)) => {
            // The emission point's rounding error is bounded like any barycentric point.
            let err = barycentric_error([1.0, 1.0, 1.0], t.p[0], t.p[1], t.p[2]);
            offset_ray_origin(em.origin, err, n, em.direction)
        }
        _ => em.origin,
    };
    Start::Photon(PhotonRay { origin, dir: em.direction, power, specular_only: true })
}

/// At a non-specular hit: stores the photon where its map wants it; returns whether the path
/// goes on. A surface that passes photons on as specular ([`Bsdf::photon_specular`]) stores none. The caustic pass keeps only paths whose first hit is specular and ends each at its
/// first non-specular hit.
pub fn deposit_photon(
    domain: Domain,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    photon: &PhotonRay,
    bounce: u32,
    out: &mut Vec<Photon>,
) -> bool {
    // Smooth rough surfaces and frosted glass pass photons on as specular: nothing stored.
    if bsdf.photon_specular() {
        return true;
    }
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
        specular_only: photon.specular_only && (bs.delta || bsdf.photon_specular()),
    })
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
    use super::*;

    /// Emission stops at the path that stores the target's last photon: paths storing nothing
    /// are passed over, a path whose photons straddle the count is the one emission stops at,
    /// and a batch that falls short counts whole.
    #[test]
    fn emission_stops_at_the_path_that_stores_the_last_photon() {
        let p = Photon { position: Vec3::ZERO, power: Vec3::ONE, wi: Vec3::Z, normal: Vec3::Z, flags: 0 };
        // Paths 0..5 store 0, 2, 0, 3 and 1 photons.
        let batch: Vec<(u64, Photon)> = [1u64, 1, 3, 3, 3, 4].iter().map(|&path| (path, p)).collect();
        let cuts: Vec<u64> = (1..=6)
            .map(|need| {
                let mut t = Tally::new(need);
                t.add_batch(batch.iter().copied());
                assert_eq!(t.stored(), u64::from(need));
                t.emitted()
            })
            .collect();
        assert_eq!(cuts, [2, 2, 4, 4, 4, 5]);
        let mut short = Tally::new(100_000);
        short.add_batch(batch.iter().copied());
        assert_eq!((short.stored(), short.emitted(), short.wants_more()), (6, BATCH as u64, true));
        // A map of 10 photons may emit one batch at most (the path cap is at least a batch).
        let mut capped = Tally::new(10);
        capped.add_batch(batch.iter().copied());
        assert!(!capped.wants_more());
        let (photons, emitted) = short.finish();
        assert_eq!((photons[0].power, emitted), (Vec3::splat(1.0 / BATCH as f32), BATCH as u64));
    }
}
