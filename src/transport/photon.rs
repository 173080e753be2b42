//! Photon transport, one vertex at a time: emission from the lights in proportion to power,
//! deposit at non-specular hits, scattering with Russian roulette at constant power, and the
//! tally that stops emission at exactly the photons a map asks for (and counts only the paths
//! it keeps).
//!
//! **Bounded power.** Every photon keeps the power its path was emitted with (Jensen's rule):
//! Russian roulette compares the power after a bounce with the path's emitted power (its
//! largest channel), kills the photon with the probability of the shortfall and scales the
//! survivor back up to it. Power grows only where a bounce's weight exceeds 1 — Veach's
//! shading-normal correction, a Phong lobe's (n+2)/(n+1) — and then decays again at the next
//! bounces that would take it below. Each factor of the correction is bounded by
//! [`CORRECTION_MAX`] and the power by [`POWER_GROWTH_MAX`] times the emitted power, so **every
//! stored photon's largest channel is at most `POWER_GROWTH_MAX · Φ_path / N`**, `Φ_path` the
//! path's emitted power (`Φ/N` of the whole scene for every unaimed photon of an area light of
//! uniform radiance; `Φ_light / (p_light · p_aim)` for an aimed caustic photon) and `N` the paths
//! emitted. Both bounds are biases, derived at [`CORRECTION_MAX`] and [`POWER_GROWTH_MAX`];
//! `--stats` counts the bounces the second one clamped (`numerics.photon_power_capped`).
//!
//! Global map: every non-specular hit (paths L{S|D}*D). Caustic map: photons whose every bounce
//! so far was specular (LS+D); their paths are discarded at the first hit when it is not
//! specular (a Jensen projection map reduced to rejection: unbiased, as the discarded paths still
//! count in the emitted total). Paths are emitted in fixed batches of [`BATCH`] until the map
//! holds its target, so the photon set is the same at any thread count and in every engine.
//! Stored power = Φ-weighted path power divided by the number of paths emitted.
//!
//! In a medium filling the scene (Jensen and Christensen 1998), every segment samples its first
//! interaction by free flight ([`super::specular::segment_flight`]); a photon that interacts
//! there scatters by the phase function and is stored as a volume photon
//! ([`deposit_in_medium`]), one that passes
//! reaches the surface with the free flight's weight. The volume photons travel in the same
//! list as the surface ones, flagged [`flags::VOLUME`], so the tally counts them toward the
//! map's target like any other; [`super::PhotonMaps::build`] sorts them into the volume maps.

use super::specular::{segment_flight, Flight};
pub use super::tally::{normalise_power, PathCounts, PathEnd, Tally, TracedPhotons, BATCH};
use crate::geometry::offset::{barycentric_error, offset_ray_origin};
use crate::job::Job;
use crate::material::{Bsdf, SurfaceFrame, Transport};
use crate::medium::Medium;
use crate::photon_map::{flags, Photon};
use crate::rng::{Domain, Sampler};
use crate::sampling::Distribution1D;
use crate::scene::{Scene, SurfacePoint};
use glam::Vec3;

/// The most each of the two factors of Veach's shading-normal correction may be (see
/// [`shading_normal_correction`]).
///
/// Unbounded, the arrival factor `|wo·ns| / |wo·ng|` grows without limit as a photon arrives
/// grazing the triangle's plane, and the departure factor `|wi·ng| / |wi·ns|` as it leaves
/// grazing the shading plane: both have a finite mean (arrivals are rare in proportion to
/// `|wo·ng|`, departures to `|wi·ns|`) but a logarithmically divergent variance, and a seed of
/// the white furnace (`scenes/hard/furnace-materials.toml --seed 11`) met a departure with
/// `wi·ns = −1.8·10⁻⁸`: one photon of 5·10⁶ times its path's power, an image mean of 13.2
/// where 2 is the most.
///
/// The bias of the bound, for shading normals θ from the geometric one and incident light of
/// equal radiance from every direction (a furnace; the worst case, grazing light being as
/// strong as any): the clamped arrival factor loses
/// `sin²θ · C / (2 cos θ (C² − cos²θ)) ≈ θ² / (2C)` of the reflected power (the energy in the
/// grazing bands `|wo·ng| < |wo·ns| / C` on both sides of the tilt), and the departure factor
/// the same to first order. At C = 4: 0.1 % at θ = 5°, 0.4 % at 10°, 1.6 % at 20° (a numerical
/// check over 4·10⁶ directions gave 0.10, 0.40 and 1.55 %); the bundled and public scenes'
/// smooth meshes have θ below 5°. Light that actually arrives grazing and leaves the same way
/// is rarer than in a furnace, so the loss in a lit room is smaller still.
pub const CORRECTION_MAX: f32 = 4.0;

/// The most a photon's power (its largest channel) may be, in multiples of its path's emitted
/// power: a bounce that would take it higher is clamped to it and counted
/// (`numerics.photon_power_capped`). Russian roulette returns a photon to its emitted power
/// whenever a bounce takes it below, so only a run of bounces each weighing more than 1 can
/// reach the bound: at most [`CORRECTION_MAX`]² = 16 for the shading normals times 2 for a
/// Phong lobe at exponent 0 (its (n+2)/(n+1)) in one bounce. None of the bundled or hard-case
/// scenes reaches it at any of the seeds `benches/photon-power.sh` tries; where a scene does,
/// the clamped power is a bias the count measures.
pub const POWER_GROWTH_MAX: f32 = 16.0;

/// A photon between bounces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonRay {
    /// Ray origin.
    pub origin: Vec3,
    /// Unit direction.
    pub dir: Vec3,
    /// Power (not yet divided by the paths emitted).
    pub power: Vec3,
    /// The largest channel of the power the path was emitted with: Russian roulette keeps the
    /// photon at it, and [`POWER_GROWTH_MAX`] bounds the power by a multiple of it.
    pub emitted: f32,
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

/// The lights' distribution that photons of `domain` leave from in `job`: its guide's
/// ([`super::guide`]) when it has one for that map, else the scene's, by power.
#[must_use]
pub fn photon_lights<'a>(scene: &'a Scene, job: &'a Job, domain: Domain) -> &'a Distribution1D {
    let guide = job.guide.get().map(|g| if domain == Domain::CausticPhoton { &g.caustic } else { &g.global });
    guide.and_then(|g| g.lights.as_ref()).unwrap_or(&scene.light_power)
}

/// The light that the photon path of `domain` with random stream `s` (its path's) leaves from
/// in `job`, and its probability.
#[must_use]
pub fn photon_light(scene: &Scene, job: &Job, domain: Domain, s: &Sampler) -> (usize, f32) {
    let lights = photon_lights(scene, job, domain);
    let li = lights.sample(s.get(0, 0));
    (li, lights.pmf(li) as f32)
}

/// Starts photon path `index` of `domain` with the random streams of `job`'s pass: picks a
/// light ([`photon_light`]) and samples its emission; the caustic pass aims at the scene's
/// specular objects ([`super::aim`]) unless the settings say not to.
#[must_use]
pub fn start_photon(scene: &Scene, job: &Job, domain: Domain, index: u64) -> Start {
    let s = Sampler::new(job.pass.seed, domain, index);
    let (li, pmf) = photon_light(scene, job, domain, &s);
    let aim = job.settings.aim_caustics;
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
    Start::Photon(PhotonRay { origin, dir: em.direction, power, emitted: power.max_element(), specular_only: true })
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
    let mut f = if sp.flat { flags::FLAT } else { 0 };
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

/// At a scattering event at `p` in the medium filling the scene, `photon.power` already
/// weighted by the free flight (the power that scatters there): stores a volume photon
/// ([`flags::VOLUME`]) where its map wants it; returns whether the path goes on. The global
/// pass stores every one, flagged [`flags::DIRECT`] at the path's first vertex and
/// [`flags::CAUSTIC`] when every surface before was specular (a volumetric caustic, `LS+V`);
/// the caustic pass stores only those and ends its path at the event.
pub fn deposit_in_medium(domain: Domain, p: Vec3, photon: &PhotonRay, bounce: u32, out: &mut Vec<Photon>) -> bool {
    if photon.power == Vec3::ZERO {
        // A channel-mixture flight that scattered where σ_s is 0 in every channel it carries.
        return false;
    }
    let caustic = photon.specular_only && bounce > 0;
    let mut f = flags::VOLUME;
    if bounce == 0 {
        f |= flags::DIRECT;
    }
    if caustic {
        f |= flags::CAUSTIC;
    }
    if domain != Domain::CausticPhoton || caustic {
        out.push(Photon { position: p, power: photon.power, wi: -photon.dir, normal: flags::VOLUME_NORMAL, flags: f });
    }
    domain != Domain::CausticPhoton
}

/// Scatters a photon at medium point `p` by the phase function of `medium` (sampled exactly,
/// so the power is unchanged) with the numbers of bounce `bounce + 1` (dims 0–1), then Russian
/// roulette at the path's emitted power (dim 3), as at a surface.
#[must_use]
pub fn scatter_in_medium(s: &Sampler, medium: &Medium, p: Vec3, photon: &PhotonRay, bounce: u32) -> Scattered {
    let dir = medium.phase().sample(photon.dir, [s.get(bounce + 1, 0), s.get(bounce + 1, 1)]);
    if !photon.power.is_finite() {
        return Scattered::NonFinite;
    }
    let next = |power| PhotonRay { origin: p, dir, power, emitted: photon.emitted, specular_only: false };
    match roulette(photon.power, photon.emitted, s.get(bounce + 1, 3)) {
        Roulette::Absorbed => Scattered::Absorbed,
        Roulette::Survives(q) => Scattered::Continue(next(q)),
        Roulette::Capped(q) => Scattered::Capped(next(q)),
    }
}

/// What scattering did to a photon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scattered {
    /// It goes on.
    Continue(PhotonRay),
    /// It goes on, its power clamped to [`POWER_GROWTH_MAX`] times its emitted power (counted).
    Capped(PhotonRay),
    /// Absorbed (Russian roulette or no valid direction).
    Absorbed,
    /// Its power stopped being finite; dropped and counted.
    NonFinite,
    /// The BSDF's sample had zero pdf; dropped and counted.
    ZeroPdf,
}

/// Scatters a photon at `sp` (BSDF sample, bounded shading-normal correction, Russian roulette
/// at the path's emitted power, the power bound) with the random numbers of bounce
/// `bounce + 1`.
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
    // symmetric, and Veach's correction makes photon transport agree with camera paths (Veach
    // 1997 §5.3; pbrt-v3 CorrectShadingNormal), each factor bounded by CORRECTION_MAX.
    let power = photon.power * (bs.weight * shading_normal_correction(&sp.frame, wo, bs.wi));
    if !power.is_finite() {
        return Scattered::NonFinite;
    }
    let next = |power| PhotonRay {
        origin: offset_ray_origin(sp.p, sp.p_error, sp.frame.ng, bs.wi),
        dir: bs.wi,
        power,
        emitted: photon.emitted,
        // A smooth plastic's coat reflects as a mirror but is no caustic maker: its photons go on
        // as indirect light (for the global map and the final gather), as a rough coat's do.
        specular_only: photon.specular_only && ((bs.delta && bsdf.is_delta()) || bsdf.photon_specular()),
    };
    match roulette(power, photon.emitted, s.get(bounce + 1, 3)) {
        Roulette::Absorbed => Scattered::Absorbed,
        Roulette::Survives(p) => Scattered::Continue(next(p)),
        Roulette::Capped(p) => Scattered::Capped(next(p)),
    }
}

/// What Russian roulette did to a photon's power.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Roulette {
    /// Absorbed.
    Absorbed,
    /// It goes on with this power.
    Survives(Vec3),
    /// It goes on with this power, clamped to the bound.
    Capped(Vec3),
}

/// Russian roulette at the path's emitted power `emitted` (a largest channel) with the uniform
/// number `u`: a photon whose largest channel `m` fell below it survives with probability
/// `m / emitted` and is scaled back up to it (unbiased: the expected power is unchanged); one at
/// or above it goes on as it is, up to [`POWER_GROWTH_MAX`]` · emitted`, where it is clamped.
/// Zero power is absorbed.
#[must_use]
pub fn roulette(power: Vec3, emitted: f32, u: f32) -> Roulette {
    let m = power.max_element();
    if !(m > 0.0) {
        Roulette::Absorbed
    } else if m < emitted {
        let survive = m / emitted;
        if u < survive {
            Roulette::Survives(power * (emitted / m))
        } else {
            Roulette::Absorbed
        }
    } else if m > POWER_GROWTH_MAX * emitted {
        Roulette::Capped(power * (POWER_GROWTH_MAX * emitted / m))
    } else {
        Roulette::Survives(power)
    }
}

/// Traces photon path `index` of `domain` one bounce at a time (the scalar oracle's photon path,
/// and the guide's pilot), appending stored photons (un-normalised power) to
/// `out`; returns what the path counted.
pub fn trace_path(scene: &Scene, job: &Job, domain: Domain, index: u64, out: &mut Vec<Photon>) -> PathCounts {
    let mut counts = PathCounts::default();
    let mut photon = match start_photon(scene, job, domain, index) {
        Start::Photon(p) => p,
        Start::Dark => return counts,
        Start::NonFinite => {
            counts.end = PathEnd::EmissionNonFinite;
            return counts;
        }
    };
    let s = Sampler::new(job.pass.seed, domain, index);
    for bounce in 0..job.settings.max_depth {
        counts.ray();
        let hit = scene.intersect(photon.origin, photon.dir, f32::INFINITY);
        // The segment to vertex `bounce` draws its free flight at bounce + 1 (dims 4–5), which
        // that vertex's scattering leaves free.
        let scattered = match segment_flight(scene, photon.origin, photon.dir, hit.as_ref(), &s, bounce + 1) {
            Flight::Scatter { medium, p, weight } => {
                photon.power *= weight;
                if !deposit_in_medium(domain, p, &photon, bounce, out) {
                    return counts;
                }
                scatter_in_medium(&s, &medium, p, &photon, bounce)
            }
            Flight::Pass(weight) => {
                photon.power *= weight;
                let Some(hit) = hit else {
                    if scene.encloses_lights {
                        counts.end = PathEnd::Escaped;
                    }
                    return counts;
                };
                photon.power *= scene.interior_transmittance(&hit, photon.dir);
                let sp = scene.surface(&hit);
                let bsdf = scene.bsdf(&sp);
                if !bsdf.is_delta() && !deposit_photon(domain, &sp, &bsdf, &photon, bounce, out) {
                    return counts;
                }
                scatter_photon(&s, &sp, &bsdf, &photon, bounce)
            }
        };
        match scattered {
            Scattered::Continue(next) => photon = next,
            Scattered::Capped(next) => {
                counts.capped += 1;
                photon = next;
            }
            Scattered::Absorbed => return counts,
            Scattered::NonFinite => {
                counts.end = PathEnd::ScatterNonFinite;
                return counts;
            }
            Scattered::ZeroPdf => {
                counts.end = PathEnd::ZeroPdf;
                return counts;
            }
        }
    }
    // Russian roulette did not end it within max_depth bounces: the safety cap does.
    counts.end = PathEnd::DepthCut;
    counts
}

/// Veach's adjoint correction for shading normals, `|wo·ns||wi·ng| / (|wo·ng||wi·ns|)`, as the
/// arrival factor `|wo·ns| / |wo·ng|` times the departure factor `|wi·ng| / |wi·ns|`, each at
/// most [`CORRECTION_MAX`] (whose bias is derived there); 1 where the shading normal is the
/// geometric one. A vanishing denominator gives the bound, a vanishing numerator 0.
#[must_use]
pub fn shading_normal_correction(frame: &SurfaceFrame, wo: Vec3, wi: Vec3) -> f32 {
    let (ng, ns) = frame.oriented(wo);
    if ns == ng {
        return 1.0;
    }
    bounded_ratio(wo.dot(ns).abs(), wo.dot(ng).abs()) * bounded_ratio(wi.dot(ng).abs(), wi.dot(ns).abs())
}

/// `num / den` for non-negative operands, at most [`CORRECTION_MAX`] (also where `den` is 0).
fn bounded_ratio(num: f32, den: f32) -> f32 {
    if !(num > 0.0) {
        0.0
    } else if num < CORRECTION_MAX * den {
        num / den
    } else {
        CORRECTION_MAX
    }
}

/// The largest photon power over the median one (each photon's largest channel), for the
/// stats: how far the heaviest photon stands above a typical one. 0 for no photons.
#[must_use]
pub fn power_max_over_median(photons: &[Photon]) -> f64 {
    let mut power: Vec<f32> = photons.iter().map(|p| p.power.max_element()).collect();
    if power.is_empty() {
        return 0.0;
    }
    let mid = power.len() / 2;
    let (_, &mut median, _) = power.select_nth_unstable_by(mid, f32::total_cmp);
    let max = power.iter().copied().fold(median, f32::max);
    // A median of zero (most photons black) would divide by zero: the ratio to the smallest
    // positive float instead, finite in the JSON.
    f64::from(max) / f64::from(median.max(f32::MIN_POSITIVE))
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

    /// Russian roulette at the emitted power: below it a photon survives with probability
    /// m / emitted at exactly the emitted power (so the expected power is unchanged), at or
    /// above it goes on unchanged, above the bound is clamped; zero power is absorbed.
    #[test]
    fn roulette_keeps_the_emitted_power() {
        let p = Vec3::new(0.2, 0.5, 0.1);
        assert_eq!(roulette(p, 1.0, 0.49), Roulette::Survives(p * 2.0));
        assert_eq!(roulette(p, 1.0, 0.5), Roulette::Absorbed);
        // The expected power over the uniform numbers is the power.
        let n = 1000;
        let mean: Vec3 = (0..n)
            .map(|i| match roulette(p, 1.0, (i as f32 + 0.5) / n as f32) {
                Roulette::Survives(q) => q,
                _ => Vec3::ZERO,
            })
            .sum::<Vec3>()
            / n as f32;
        assert!((mean - p).abs().max_element() < 1e-6, "{mean}");
        assert_eq!(roulette(p * 3.0, 1.0, 0.99), Roulette::Survives(p * 3.0));
        let Roulette::Capped(q) = roulette(p * 100.0, 1.0, 0.0) else { panic!() };
        assert!((q.max_element() - POWER_GROWTH_MAX).abs() < 1e-5, "{q}");
        assert_eq!(roulette(Vec3::ZERO, 1.0, 0.0), Roulette::Absorbed);
        assert_eq!(roulette(Vec3::splat(f32::NAN), 1.0, 0.0), Roulette::Absorbed);
    }

    /// The correction's factors are each at most CORRECTION_MAX: a departure grazing the shading
    /// plane (the furnace's spike: wi·ns = −1.8e-8) gives the bound, not 5·10⁶; with equal
    /// normals it is exactly 1, and it is the unbounded ratio where both factors are moderate.
    #[test]
    fn the_shading_normal_correction_is_bounded() {
        let ng = Vec3::Z;
        let ns = Vec3::new(0.2, 0.0, 1.0).normalize();
        let frame = SurfaceFrame { ng, ns };
        let wo = Vec3::new(0.3, 0.4, 0.8).normalize();
        let grazing = Vec3::new(-ns.z, 0.3, ns.x).normalize();
        assert!(grazing.dot(ns).abs() < 1e-6 && grazing.dot(ng) > 0.1);
        let c = shading_normal_correction(&frame, wo, grazing);
        let arrival = wo.dot(ns) / wo.dot(ng);
        assert!((c - arrival * CORRECTION_MAX).abs() < 1e-5, "{c}");
        let wi = Vec3::new(-0.5, 0.1, 0.8).normalize();
        let full = wo.dot(ns) * wi.dot(ng) / (wo.dot(ng) * wi.dot(ns));
        assert!((shading_normal_correction(&frame, wo, wi) - full).abs() < 1e-6);
        assert_eq!(shading_normal_correction(&SurfaceFrame { ng, ns: ng }, wo, grazing), 1.0);
        let along = Vec3::new(1.0, 0.0, 0.0);
        assert!(shading_normal_correction(&frame, along, wi) <= CORRECTION_MAX * CORRECTION_MAX);
    }
}
