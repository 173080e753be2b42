//! One render job: the settings, validated once; the effects plan, made once; the worker count;
//! and the state of the pass being rendered — its seed and, in a progressive pass, its fixed
//! radii. Every engine and the transport core read these from the job, so nothing per pass
//! hides in [`Settings`] and nothing is planned or validated twice.

use crate::effects::Effects;
use crate::error::{Error, Result};
use crate::photon_map::reach::PhotonGuide;
use crate::scene::Scene;
use crate::settings::Settings;
use crate::traversal_choice::TraversalChoice;
use std::sync::{Arc, OnceLock};

/// What changes from pass to pass of a progressive render.
#[derive(Clone, Debug, PartialEq)]
pub struct Pass {
    /// Seed of every random stream of the pass: the user's seed in a single render and in the
    /// first progressive pass, mixed from it in later ones.
    pub seed: u64,
    /// A progressive pass estimates every photon within these radii instead of the k nearest.
    /// `None`: a single k-nearest-neighbour render.
    pub radii: Option<FixedRadii>,
}

/// Everything a render reads besides the scene and the camera.
#[derive(Clone, Debug)]
pub struct Job {
    /// The user's settings, validated.
    pub settings: Settings,
    /// Which terms and machinery the scene needs, planned from the scene and the settings.
    pub plan: Effects,
    /// Worker threads ([`Settings::thread_count`]).
    pub threads: usize,
    /// The pass being rendered.
    pub pass: Pass,
    /// The traversal kernel per ray queue (BVH2 packets, single rays or 8-wide packets), chosen
    /// in the first pass and kept by the others.
    pub traversal: Arc<TraversalChoice>,
    /// Where the camera reads the photon maps and which lights photons come from, found once by
    /// a pilot before the first photon pass ([`crate::transport::guide`]) and shared by every
    /// pass. Empty (photons by power, every stored photon counted) in a job whose maps are built
    /// without a camera; with `--no-photon-guide` it holds the cells (for the record) and no
    /// light distribution, and does not steer.
    pub guide: Arc<OnceLock<PhotonGuide>>,
}

impl Job {
    /// Validates `settings` and plans the render of `scene`: the job of a single render.
    pub fn new(scene: &Scene, settings: &Settings) -> Result<Job> {
        settings.validate()?;
        let plan = Effects::plan(scene, settings);
        Ok(Job {
            settings: settings.clone(),
            plan,
            threads: settings.thread_count(),
            pass: Pass { seed: settings.seed, radii: None },
            traversal: Arc::new(TraversalChoice::timed()),
            guide: Arc::default(),
        })
    }

    /// [`Job::new`] for a photon-mapping engine: also refuses settings that leave a map the plan
    /// needs empty.
    pub fn photon_mapping(scene: &Scene, settings: &Settings) -> Result<Job> {
        let job = Job::new(scene, settings)?;
        job.plan.check(settings)?;
        Ok(job)
    }

    /// The same job rendering `pass` (a progressive pass).
    pub fn with_pass(&self, pass: Pass) -> Result<Job> {
        if let Some(r) = &pass.radii {
            let ok = |v: f32| v > 0.0 && v.is_finite();
            if !(ok(r.global) && ok(r.caustic) && ok(r.scale)) {
                return Err(Error::setting("radii", "progressive radii must be positive and finite"));
            }
        }
        Ok(Job { pass, ..self.clone() })
    }
}

/// Fixed density-estimation radii of one progressive pass, in scene units.
#[derive(Clone, Debug, PartialEq)]
pub struct FixedRadii {
    /// Global map (and the irradiance precomputed from it).
    pub global: f32,
    /// Caustic map.
    pub caustic: f32,
    /// Per-pixel radii for the estimates at camera paths' first non-specular hits: each pixel's
    /// first radius, times `scale`. `None`: `global` and `caustic` everywhere.
    pub pixels: Option<std::sync::Arc<PixelRadii>>,
    /// This pass's radius over the first pass's (√ of ∏ (j+α)/(j+1)).
    pub scale: f32,
    /// The estimates also estimate their bias ([`crate::photon_map::Estimate::bias`]); a
    /// progressive render asks for it in some passes only (`progressive::BIAS_EVERY`).
    pub bias: bool,
    /// The volume maps' radii (global, caustic) in a medium filling the scene. They shrink by
    /// the 3-D sequence, r³ᵢ₊₁ = r³ᵢ·(i + α)/(i + 1) (Knaus and Zwicker 2011), so each is its
    /// first radius times `scale`^(2/3).
    pub volume: (f32, f32),
}

/// The first progressive pass's radii per pixel (row-major), in scene units.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PixelRadii {
    /// Global-map radius per pixel (used where the global map is read at the first hit, i.e.
    /// with final gathering off; empty otherwise).
    pub global: Vec<f32>,
    /// Caustic-map radius per pixel.
    pub caustic: Vec<f32>,
}

impl FixedRadii {
    /// The same radius everywhere.
    #[must_use]
    pub fn uniform(global: f32, caustic: f32) -> Self {
        FixedRadii { global, caustic, pixels: None, scale: 1.0, bias: true, volume: (global, caustic) }
    }

    /// The caustic radius at `pixel`'s camera paths (`None`: anywhere else).
    #[must_use]
    pub fn caustic_at(&self, pixel: Option<usize>) -> f32 {
        match (&self.pixels, pixel) {
            (Some(p), Some(i)) if i < p.caustic.len() => p.caustic[i] * self.scale,
            _ => self.caustic,
        }
    }

    /// The global radius at `pixel`'s camera paths (`None`: anywhere else).
    #[must_use]
    pub fn global_at(&self, pixel: Option<usize>) -> f32 {
        match (&self.pixels, pixel) {
            (Some(p), Some(i)) if i < p.global.len() => p.global[i] * self.scale,
            _ => self.global,
        }
    }
}
