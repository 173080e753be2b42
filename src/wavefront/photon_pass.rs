//! The wavefront photon pass: for each map the plan wants, waves of photon paths run through
//! the photon schedule, and the transport core's [`Tally`] applied batch by batch, so the maps
//! hold exactly the photons of the oracle's pass; then the maps are built.

use super::resources::PhotonWork;
use super::schedule::PhotonPass;
use crate::job::Job;
use crate::photon_map::Photon;
use crate::progress::Progress;
use crate::rng::Domain;
use crate::scene::Scene;
use crate::stats::RenderStats;
use crate::transport::photon::{power_max_over_median, Tally, BATCH};
use crate::transport::PhotonMaps;
use bevy_ecs::prelude::*;
use std::time::Instant;

/// At most this many batches per photon wave.
pub const MAX_BATCHES_PER_WAVE: usize = 8;

/// The photon pass of both maps the plan wants, run through the photon schedule of `world`,
/// and the maps built from it; counts and times go into `stats`.
pub fn photon_pass(
    world: &mut World,
    scene: &Scene,
    job: &Job,
    stats: &mut RenderStats,
    progress: &dyn Progress,
) -> PhotonMaps {
    let (plan, settings) = (&job.plan, &job.settings);
    let mut maps_photons: [Vec<Photon>; 2] = [Vec::new(), Vec::new()];
    for (k, (domain, on, target)) in [
        (Domain::GlobalPhoton, plan.global_map.on, settings.photons),
        (Domain::CausticPhoton, plan.caustic_map.on, settings.caustic_photons),
    ]
    .into_iter()
    .enumerate()
    {
        if !on {
            continue;
        }
        let t = Instant::now();
        let name = if domain == Domain::CausticPhoton { "caustic photons" } else { "global photons" };
        progress.start(name, u64::from(target));
        let mut tally = Tally::new(target);
        let mut reported = 0u64;
        *world.resource_mut::<PhotonWork>() = PhotonWork { domain: Some(domain), ..Default::default() };
        // A wave holds several batches — large queues keep both cores busy in the deep bounces —
        // sized from the photons per batch seen so far. The tally is then fed batch by batch, so
        // the photons are the oracle's; paths traced past the stopping batch are discarded.
        let mut per_batch = 0.0f64;
        while tally.wants_more() {
            let wanted = if per_batch > 0.0 {
                ((f64::from(target) - tally.stored() as f64) / per_batch).ceil() as usize
            } else {
                1
            };
            let batches = wanted.clamp(1, MAX_BATCHES_PER_WAVE).min(tally.batches_left());
            {
                let mut w = world.resource_mut::<PhotonWork>();
                w.first_path = tally.emitted();
                w.batches = batches;
            }
            world.run_schedule(PhotonPass);
            let mut w = world.resource_mut::<PhotonWork>();
            let mut deposits = std::mem::take(&mut w.deposits);
            deposits.sort_by_key(|(path, bounce, _)| (*path, *bounce));
            let mut rest = deposits.as_slice();
            for counts in w.counts.chunks(BATCH) {
                if !tally.wants_more() {
                    break;
                }
                let end = tally.emitted() + BATCH as u64;
                let n = rest.partition_point(|(path, _, _)| *path < end);
                tally.add_batch(rest[..n].iter().map(|(path, _, p)| (*path, *p)), counts);
                rest = &rest[n..];
            }
            per_batch = tally.stored() as f64 / (tally.emitted() / BATCH as u64) as f64;
            let now = tally.stored().min(u64::from(target));
            progress.advance(now - reported);
            reported = now;
        }
        progress.finish();
        let traced = tally.finish();
        stats.rays.photon += traced.rays;
        stats.numerics += traced.numerics;
        let (photons, emitted) = (traced.photons, traced.emitted);
        let (map, time) = if k == 0 {
            (&mut stats.global_map, &mut stats.times.global_photons_s)
        } else {
            (&mut stats.caustic_map, &mut stats.times.caustic_photons_s)
        };
        map.emitted = emitted;
        map.stored = photons.len() as u64;
        map.power_max_over_median = power_max_over_median(&photons);
        *time = t.elapsed().as_secs_f64();
        stats.phases.push(format!("{name} (wavefront)"));
        maps_photons[k] = photons;
    }
    stats.record_plan(plan);

    let t = Instant::now();
    let [global, caustic] = maps_photons;
    let maps = PhotonMaps::build(scene, job, global, caustic);
    stats.irradiance_points = maps.irradiance.len() as u64;
    stats.times.map_build_s = t.elapsed().as_secs_f64();
    maps
}
