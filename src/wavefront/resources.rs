//! The resources the wavefront systems share: what every system reads ([`Shared`], [`Maps`])
//! and the state of the photon pass and of a camera wave, with their queues.

use super::queues::{Classified, PathQueue, PhotonQueue, ShadowQueue};
use crate::film::{PixelMean, Terms};
use crate::job::Job;
use crate::photon_map::Photon;
use crate::rng::Domain;
use crate::scene::camera::CameraRays;
use crate::scene::Receiver;
use crate::scene::Scene;
use crate::stats::{Numerics, RayCounts};
use crate::transport::photon::PathCounts;
use crate::transport::PhotonMaps;
use bevy_ecs::prelude::*;
use std::sync::Arc;

/// What every system reads.
#[derive(Resource)]
pub struct Shared {
    /// The scene.
    pub scene: Arc<Scene>,
    /// The render job: settings, plan, worker threads and the pass.
    pub job: Job,
}

/// The photon maps (empty until the photon passes are done).
#[derive(Resource, Default)]
pub struct Maps(pub Arc<PhotonMaps>);

/// Photon-pass state of one worker: its piece of a wave.
#[derive(Resource, Default)]
pub struct PhotonWork {
    /// Which map this pass fills.
    pub domain: Option<Domain>,
    /// Path index of the piece's first photon.
    pub first_path: u64,
    /// Paths in this piece of a wave.
    pub paths: usize,
    /// Photons to trace this bounce.
    pub queue: PhotonQueue,
    /// Photons for the next bounce.
    pub next: PhotonQueue,
    /// The queue's lanes by outcome.
    pub classified: Classified,
    /// Diffuse lanes whose path goes on after deposit.
    pub survivors: Vec<u32>,
    /// Stored photons keyed by (path, bounce), the reference engine's order.
    pub deposits: Vec<(u64, u32, Photon)>,
    /// What each path of the piece counted (rays, clamped bounces, how it ended), indexed by
    /// path − `first_path`: the tally sums the kept paths' only.
    pub counts: Vec<PathCounts>,
}

/// Camera-pass state of one worker: the wave of samples in flight (its tile's, or part of them)
/// and the counts of every tile it has rendered.
#[derive(Resource)]
pub struct CameraWork {
    /// Primary-ray generator.
    pub camera: CameraRays,
    /// Global index of the wave's first sample.
    pub first_sample: u64,
    /// Samples in the wave.
    pub count: usize,
    /// Segments to trace this bounce.
    pub paths: PathQueue,
    /// Segments for the next bounce.
    pub next: PathQueue,
    /// `paths` lanes by outcome.
    pub classified: Classified,
    /// Shadow rays waiting for the next intersect stage.
    pub shadows: ShadowQueue,
    /// Per-sample terms of the wave.
    pub terms: Vec<Terms>,
    /// Per sample, the receiver its camera path's non-specular hit sampled light for: the
    /// gather and glossy rays that leave it weigh the emission they find for that point
    /// (`transport::mis::emission_found`). A camera path has at most one such hit.
    pub receivers: Vec<Receiver>,
    /// Per sample, the receiver where its glossy ray landed on a narrow lobe: that lobe's ray
    /// weighs the emission it finds for it (`transport::lobe`). A sample has at most one.
    pub lobe_receivers: Vec<Receiver>,
    /// Per sample, whether its camera path's non-specular hit is a narrow lobe: its glossy ray
    /// then also counts what it finds through mirrors and glass and leaving the scene
    /// (`transport::lobe`).
    pub narrow_hits: Vec<bool>,
    /// The tile's pixels, resolved after each wave's bounce loop (a tile of one pixel with more
    /// samples than a wave holds takes several waves: [`super::camera_pass::camera_pass`]).
    pub film: Vec<Terms>,
    /// The running mean of a pixel whose samples the wave so far has not finished (its next
    /// wave goes on adding to it).
    pub open: PixelMean,
    /// Rays traced, over the worker's tiles.
    pub rays: RayCounts,
    /// Samples dropped as non-finite, and pixel sums that overflowed, over the worker's tiles.
    pub numerics: Numerics,
}
