//! The light-transport core: every piece of physics more than one engine uses, written once and
//! per vertex, so that the scalar oracle ([`crate::reference`]), the wavefront engine and the
//! path tracer compute the same thing from the same random numbers.
//!
//! - [`streams`]: which random stream and bounce each decision draws from;
//! - [`camera`]: camera samples and the pixel loop of the one-ray-at-a-time engines;
//! - [`specular`]: continuing a ray at a surface, and following mirrors and glass;
//! - [`photon`]: photon emission, deposit, scattering and the exact-count emission tally;
//! - [`direct`]: direct light by light sampling (shadow rays);
//! - [`mis`]: multiple importance sampling of emitters, light samples against BSDF samples;
//! - [`media`]: light in a scene-filling medium (shadow-ray transmittance, in-scattering);
//! - [`volume`]: the volume maps' estimate, and what camera-side rays find in the medium;
//! - [`gather`]: final-gather and glossy ray generation, and where the secondary gather applies;
//! - [`estimate`]: photon-map density estimates at a surface point;
//! - [`lobe`]: where gather and glossy rays land on a narrow lobe, its own ray;
//! - [`maps`]: the photon maps of a render and Christensen's precomputed irradiance.
//!
//! Each function handles one vertex, except two loops every one-ray engine shares: the pixel
//! loop ([`camera::render_pixels`]) and a ray's chain through mirrors and glass
//! ([`specular::first_non_specular`]). The loops over paths, bounces and queues belong to the
//! engines.

pub mod aim;
pub mod camera;
pub mod direct;
pub mod estimate;
pub mod gather;
pub mod guide;
pub mod lobe;
pub mod maps;
pub mod media;
pub mod mis;
pub mod photon;
pub mod specular;
pub mod streams;
pub mod tally;
pub mod volume;

pub use maps::PhotonMaps;

use crate::effects::Effects;
use crate::job::{FixedRadii, Job};
use crate::scene::Scene;
use crate::settings::Settings;
use std::sync::atomic::{AtomicU64, Ordering};

/// What the camera-side physics reads: the scene, the maps and the job, with the radii in scene
/// units.
pub struct Context<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The photon maps.
    pub maps: &'a PhotonMaps,
    /// The user's settings (the job's).
    pub settings: &'a Settings,
    /// What to simulate (the job's plan).
    pub effects: &'a Effects,
    /// A progressive pass's fixed radii: every photon within them, not the k nearest.
    pub fixed: Option<&'a FixedRadii>,
    /// Global-map maximum radius in scene units.
    pub global_radius: f32,
    /// Caustic-map maximum radius in scene units.
    pub caustic_radius: f32,
    /// Gather rays landing closer than this take the secondary gather
    /// ([`gather::secondary_gather_distance`]).
    pub secondary_gather: f32,
    /// Photons the normal filter tested and turned away in this context's estimates
    /// ([`Numerics::photons_filtered`](crate::stats::Numerics::photons_filtered)).
    pub filtered: AtomicU64,
    /// Chains through mirrors and glass cut at `max_depth` in this context
    /// ([`Numerics::camera_depth_cut`](crate::stats::Numerics::camera_depth_cut)).
    pub depth_cut: AtomicU64,
}

impl<'a> Context<'a> {
    /// The context of `job` on `scene` with `maps`.
    #[must_use]
    pub fn new(scene: &'a Scene, maps: &'a PhotonMaps, job: &'a Job) -> Self {
        let d = scene.diagonal();
        Context {
            scene,
            maps,
            settings: &job.settings,
            effects: &job.plan,
            fixed: job.pass.radii.as_ref(),
            global_radius: job.settings.global_radius * d,
            caustic_radius: job.settings.caustic_radius * d,
            secondary_gather: gather::secondary_gather_distance(scene, job),
            filtered: AtomicU64::new(0),
            depth_cut: AtomicU64::new(0),
        }
    }

    /// Counts a chain cut at `max_depth`.
    pub fn cut(&self) {
        self.depth_cut.fetch_add(1, Ordering::Relaxed);
    }

    /// Chains cut at `max_depth` in this context so far.
    #[must_use]
    pub fn cuts(&self) -> u64 {
        self.depth_cut.load(Ordering::Relaxed)
    }

    /// Photons the normal filter has tested and turned away in this context's estimates so far.
    #[must_use]
    pub fn filtered(&self) -> u64 {
        self.filtered.load(Ordering::Relaxed)
    }
}
