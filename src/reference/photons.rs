//! The oracle's photon pass: batches of photon paths, each traced one bounce at a time with
//! the transport core's emission, deposit and scattering, until the map holds its target
//! ([`Tally`]).

use crate::job::Job;
use crate::parallel::map_chunks;
use crate::photon_map::Photon;
use crate::progress::Progress;
use crate::rng::{Domain, Sampler};
use crate::scene::Scene;
pub use crate::transport::photon::TracedPhotons;
use crate::transport::photon::{
    deposit_photon, scatter_photon, start_photon, PathCounts, PathEnd, Scattered, Start, Tally, BATCH,
};

/// Paths per work chunk inside a batch.
const CHUNK: usize = 1024;

/// Emits batches of paths until `target` photons are stored (or the path cap is reached).
pub fn trace_photons(scene: &Scene, job: &Job, domain: Domain, target: u32, progress: &dyn Progress) -> TracedPhotons {
    let name = if domain == Domain::CausticPhoton { "caustic photons" } else { "global photons" };
    progress.start(name, u64::from(target));
    let mut tally = Tally::new(target);
    let mut reported = 0u64;
    while tally.wants_more() {
        let first = tally.emitted();
        let chunks = map_chunks(
            BATCH,
            CHUNK,
            job.threads,
            |range| {
                let (mut out, mut tagged, mut counts) = (Vec::new(), Vec::new(), Vec::with_capacity(range.len()));
                for i in range {
                    let path = first + i as u64;
                    counts.push(trace_path(scene, job, domain, path, &mut out));
                    tagged.extend(out.drain(..).map(|p| (path, p)));
                }
                (tagged, counts)
            },
            |_| {},
        );
        let (mut batch, mut counts) = (Vec::new(), Vec::with_capacity(BATCH));
        for (tagged, c) in chunks {
            batch.extend(tagged);
            counts.extend(c);
        }
        tally.add_batch(batch, &counts);
        let now = tally.stored().min(u64::from(target));
        progress.advance(now - reported);
        reported = now;
    }
    progress.finish();
    tally.finish()
}

/// Traces photon path `index` of `domain`, appending stored photons (un-normalised power) to
/// `out`; returns what the path counted.
pub fn trace_path(scene: &Scene, job: &Job, domain: Domain, index: u64, out: &mut Vec<Photon>) -> PathCounts {
    let mut counts = PathCounts::default();
    let mut photon = match start_photon(scene, job.pass.seed, domain, index, job.settings.aim_caustics) {
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
        let Some(hit) = scene.intersect(photon.origin, photon.dir, f32::INFINITY) else {
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
        match scatter_photon(&s, &sp, &bsdf, &photon, bounce) {
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
