//! The oracle's photon pass: batches of photon paths, each traced one bounce at a time with
//! the transport core's emission, deposit and scattering, until the map holds its target
//! ([`Tally`](crate::transport::tally::Tally)).

use crate::job::Job;
use crate::parallel::map_chunks;
use crate::progress::Progress;
use crate::rng::Domain;
use crate::scene::Scene;
pub use crate::transport::photon::trace_path;
pub use crate::transport::photon::TracedPhotons;
use crate::transport::photon::BATCH;

/// Paths per work chunk inside a batch.
const CHUNK: usize = 1024;

/// Emits batches of paths until `target` photons are stored where the camera reads the map (any
/// stored photon without the job's guide), or a cap is reached
/// ([`Tally`](crate::transport::tally::Tally)).
pub fn trace_photons(scene: &Scene, job: &Job, domain: Domain, target: u32, progress: &dyn Progress) -> TracedPhotons {
    let name = if domain == Domain::CausticPhoton { "caustic photons" } else { "global photons" };
    progress.start(name, u64::from(target));
    let mut tally = crate::transport::guide::tally(job, domain, target);
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
        let now = tally.counted().min(u64::from(target));
        progress.advance(now - reported);
        reported = now;
    }
    progress.finish();
    tally.finish()
}
