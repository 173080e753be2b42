//! The wavefront photon pass: for each map the plan wants, waves of photon paths run through
//! the photon schedule, and the transport core's tally
//! ([`Tally`](crate::transport::tally::Tally)) applied batch by batch, so the maps hold exactly
//! the photons of the oracle's pass; then the maps are built.
//!
//! A wave's batches are cut into pieces of up to [`PIECE`] paths, and each worker traces the pieces it
//! takes through the whole photon schedule on its own world, one thread per piece, as the
//! camera pass does with its tiles (a wave shared by all threads met them at every stage of
//! every bounce, and its deep bounces held too few photons to split: on 16 cores the global
//! photons scaled 2.5×, issue 46). A piece's photons are keyed by (path, bounce) and the
//! pieces hold consecutive paths, so their deposits concatenated in piece order are the
//! reference engine's order, whoever traced which piece.

use super::resources::PhotonWork;
use super::schedule::{photon_schedules, PhotonPass};
use super::{new_world, IdleWorlds, StageStats};
use crate::job::Job;
use crate::photon_map::Photon;
use crate::progress::Progress;
use crate::rng::Domain;
use crate::scene::Scene;
use crate::stats::RenderStats;
use crate::transport::photon::{power_max_over_median, PathCounts, BATCH};
use crate::transport::PhotonMaps;
use std::sync::Arc;
use std::time::Instant;

/// At most this many batches per photon wave.
pub const MAX_BATCHES_PER_WAVE: usize = 8;
/// Photon paths per piece of work at most: a batch makes 8, and a piece's first bounces still
/// fill SIMD packets.
pub const PIECE: usize = BATCH / 8;
/// Photon paths per piece at least, where a small wave on many workers cuts finer.
pub const MIN_PIECE: usize = 256;
/// Pieces per worker wanted in a wave, so that the last pieces even out the workers' loads.
const PIECES_PER_WORKER: usize = 4;

/// The piece size for a wave of `paths` paths on `threads` workers: [`PIECE`], or less where
/// that would leave fewer than `PIECES_PER_WORKER` pieces per worker (a progressive pass's one
/// batch is 8 pieces of 2 048: half of 16 workers would wait), but not below [`MIN_PIECE`].
/// Only the speed depends on it, never the photons.
#[must_use]
pub fn piece_for(paths: usize, threads: usize) -> usize {
    PIECE.min(paths.div_ceil(threads.max(1) * PIECES_PER_WORKER)).max(MIN_PIECE)
}

/// Traces paths `first..first + paths` of `domain`'s photons in pieces on `job.threads`
/// workers (their worlds taken from and put back into `idle`), and returns their deposits in
/// (path, bounce) order and their counts in path order.
fn trace_wave(
    scene: &Arc<Scene>,
    job: &Job,
    idle: &IdleWorlds,
    domain: Domain,
    first: u64,
    paths: usize,
) -> (Vec<(u64, u32, Photon)>, Vec<PathCounts>) {
    let worker_job = Job { threads: 1, ..job.clone() };
    let piece = piece_for(paths, job.threads);
    let pieces = idle.run_units(
        paths.div_ceil(piece),
        job.threads,
        || {
            let mut world = new_world(scene, &worker_job, photon_schedules());
            world.insert_resource(PhotonWork::default());
            world
        },
        |k, world| {
            let start = k * piece;
            {
                // The queues keep their allocations from piece to piece (emit clears them).
                let mut w = world.resource_mut::<PhotonWork>();
                w.domain = Some(domain);
                w.first_path = first + start as u64;
                w.paths = piece.min(paths - start);
                w.deposits.clear();
            }
            world.run_schedule(PhotonPass);
            let mut w = world.resource_mut::<PhotonWork>();
            let mut deposits = std::mem::take(&mut w.deposits);
            deposits.sort_by_key(|(path, bounce, _)| (*path, *bounce));
            (deposits, std::mem::take(&mut w.counts))
        },
    );
    let mut deposits = Vec::with_capacity(pieces.iter().map(|p| p.0.len()).sum());
    let mut counts = Vec::with_capacity(paths);
    for (mut d, mut c) in pieces {
        deposits.append(&mut d);
        counts.append(&mut c);
    }
    (deposits, counts)
}

/// The photon pass of both maps the plan wants, run through the photon schedule on the workers'
/// worlds, and the maps built from it; counts and times go into `stats`, and the stages' into
/// `stages`.
pub fn photon_pass(
    scene: &Arc<Scene>,
    job: &Job,
    stats: &mut RenderStats,
    stages: &mut StageStats,
    progress: &dyn Progress,
) -> PhotonMaps {
    let (plan, settings) = (&job.plan, &job.settings);
    let mut maps_photons: [Vec<Photon>; 2] = [Vec::new(), Vec::new()];
    let idle = IdleWorlds::default();
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
        let mut tally = crate::transport::guide::tally(job, domain, target);
        let mut reported = 0u64;
        // A wave holds several batches — enough pieces to keep every worker busy — sized from
        // the photons per batch seen so far. The tally is then fed batch by batch, so the
        // photons are the oracle's; paths traced past the stopping batch are discarded.
        let mut per_batch = 0.0f64;
        while tally.wants_more() {
            let wanted = if per_batch > 0.0 {
                ((f64::from(target) - tally.counted() as f64) / per_batch).ceil() as usize
            } else {
                1
            };
            let batches = wanted.clamp(1, MAX_BATCHES_PER_WAVE).min(tally.batches_left());
            let (deposits, counts) = trace_wave(scene, job, &idle, domain, tally.emitted(), batches * BATCH);
            let mut rest = deposits.as_slice();
            for counts in counts.chunks(BATCH) {
                if !tally.wants_more() {
                    break;
                }
                let end = tally.emitted() + BATCH as u64;
                let n = rest.partition_point(|(path, _, _)| *path < end);
                tally.add_batch(rest[..n].iter().map(|(path, _, p)| (*path, *p)), counts);
                rest = &rest[n..];
            }
            per_batch = tally.counted() as f64 / (tally.emitted() / BATCH as u64) as f64;
            let now = tally.counted().min(u64::from(target));
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
        map.read = traced.read;
        map.steered = crate::transport::guide::steers(job, domain);
        map.power_max_over_median = power_max_over_median(&photons);
        *time = t.elapsed().as_secs_f64();
        stats.phases.push(format!("{name} (wavefront)"));
        maps_photons[k] = photons;
    }
    stats.record_plan(plan);
    // The workers' stage counts and times join the render's.
    *stages += &idle.finish().1;

    let t = Instant::now();
    let [global, caustic] = maps_photons;
    let maps = PhotonMaps::build(scene, job, global, caustic);
    stats.irradiance_points = maps.irradiance.len() as u64;
    stats.times.map_build_s = t.elapsed().as_secs_f64();
    maps
}

#[cfg(test)]
mod tests {
    use super::{piece_for, BATCH, MIN_PIECE, PIECE, PIECES_PER_WORKER};

    #[test]
    fn pieces_are_cut_finer_only_where_workers_would_wait() {
        // One batch on 1 or 2 threads: 8 pieces of 2 048.
        assert_eq!(piece_for(BATCH, 1), PIECE);
        assert_eq!(piece_for(BATCH, 2), PIECE);
        // One batch on 16 threads: 4 pieces per worker.
        assert_eq!(BATCH.div_ceil(piece_for(BATCH, 16)), 16 * PIECES_PER_WORKER);
        // Never below MIN_PIECE, never above PIECE.
        for threads in [0, 1, 3, 64, 1000] {
            for paths in [1, BATCH, 8 * BATCH] {
                let p = piece_for(paths, threads);
                assert!((MIN_PIECE..=PIECE).contains(&p), "{paths} paths, {threads} threads: {p}");
            }
        }
    }
}
