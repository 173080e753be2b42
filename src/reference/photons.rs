//! The oracle's photon pass: batches of photon paths, each traced one bounce at a time with
//! the transport core's emission, deposit and scattering, until the map holds its target
//! ([`Tally`]).

use crate::job::Job;
use crate::parallel::map_chunks;
use crate::photon_map::Photon;
use crate::progress::Progress;
use crate::rng::{Domain, Sampler};
use crate::scene::Scene;
use crate::stats::Numerics;
use crate::transport::photon::{deposit_photon, scatter_photon, start_photon, Scattered, Start, Tally, BATCH};

/// Paths per work chunk inside a batch.
const CHUNK: usize = 1024;

/// What the oracle's photon pass produced for one map.
pub struct TracedPhotons {
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
pub fn trace_photons(scene: &Scene, job: &Job, domain: Domain, target: u32, progress: &dyn Progress) -> TracedPhotons {
    let name = if domain == Domain::CausticPhoton { "caustic photons" } else { "global photons" };
    progress.start(name, u64::from(target));
    let mut tally = Tally::new(target);
    let (mut rays, mut numerics) = (0u64, Numerics::default());
    let mut reported = 0u64;
    while tally.wants_more() {
        let first = tally.emitted();
        let chunks = map_chunks(
            BATCH,
            CHUNK,
            job.threads,
            |range| {
                let (mut out, mut tagged) = (Vec::new(), Vec::new());
                let (mut r, mut nf) = (0u64, Numerics::default());
                for i in range {
                    let path = first + i as u64;
                    trace_path(scene, job, domain, path, &mut out, &mut r, &mut nf);
                    tagged.extend(out.drain(..).map(|p| (path, p)));
                }
                (tagged, r, nf)
            },
            |_| {},
        );
        let mut batch = Vec::new();
        for (tagged, r, nf) in chunks {
            batch.extend(tagged);
            rays += r;
            numerics += nf;
        }
        tally.add_batch(batch);
        let now = tally.stored().min(u64::from(target));
        progress.advance(now - reported);
        reported = now;
    }
    progress.finish();
    let (photons, emitted) = tally.finish();
    TracedPhotons { photons, emitted, rays, numerics }
}

/// Traces photon path `index` of `domain`, appending stored photons (un-normalised power) to `out`.
pub fn trace_path(
    scene: &Scene,
    job: &Job,
    domain: Domain,
    index: u64,
    out: &mut Vec<Photon>,
    rays: &mut u64,
    numerics: &mut Numerics,
) {
    let mut photon = match start_photon(scene, job.pass.seed, domain, index, job.settings.aim_caustics) {
        Start::Photon(p) => p,
        Start::Dark => return,
        Start::NonFinite => {
            numerics.photon_emission += 1;
            return;
        }
    };
    let s = Sampler::new(job.pass.seed, domain, index);
    for bounce in 0..job.settings.max_depth {
        *rays += 1;
        let Some(hit) = scene.intersect(photon.origin, photon.dir, f32::INFINITY) else {
            numerics.photon_escaped += u64::from(scene.encloses_lights);
            break;
        };
        let sp = scene.surface(&hit);
        let bsdf = scene.bsdf(&sp);
        if !bsdf.is_delta() && !deposit_photon(domain, &sp, &bsdf, &photon, bounce, out) {
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
