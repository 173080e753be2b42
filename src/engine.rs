//! Which renderer turns a scene into a film, and the one call that runs it — a single render or
//! progressive passes under a pass count or a time budget. `photonwave render` and
//! `photonwave sweep` both go through [`render`], so a sweep row is what `render` gives with the
//! same settings.

use crate::error::{Error, Result};
use crate::film::Film;
use crate::job::Job;
use crate::parallel::{metered, Meter};
use crate::progress::{NoProgress, Progress};
use crate::scene::camera::CameraRays;
use crate::scene::Scene;
use crate::settings::Settings;
use crate::stats::{ParallelStats, RenderStats};
use std::sync::Arc;
use std::time::Instant;

/// A rendering engine.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Engine {
    /// The wavefront photon mapper: bevy_ecs systems over structure-of-arrays queues.
    #[default]
    Wavefront,
    /// The scalar reference photon mapper.
    Reference,
    /// An unbiased path tracer with next-event estimation (slow; for checking energy).
    Path,
}

pub use crate::progressive::Budget;

/// Whether `settings` (and an optional budget) make a progressive render.
#[must_use]
pub fn is_progressive(settings: &Settings, budget: Option<Budget>) -> bool {
    settings.passes > 1 || budget.is_some() || settings.target_error > 0.0
}

/// One pass of `job` rendered by `engine`: a whole render with the job's seed and, in a
/// progressive pass, its fixed radii.
#[must_use]
pub fn render_job(
    scene: &Arc<Scene>,
    rays: &CameraRays,
    job: &Job,
    engine: Engine,
    progress: &dyn Progress,
) -> (Film, RenderStats) {
    match engine {
        Engine::Wavefront => crate::wavefront::render_job(scene.clone(), rays, job, progress),
        Engine::Reference => crate::reference::render_job(scene, rays, job, progress),
        Engine::Path => crate::path::render_job(scene, rays, job, progress),
    }
}

/// Renders `scene` with `settings` (validated and planned here, once): see [`render_planned`].
pub fn render(
    scene: &Arc<Scene>,
    rays: &CameraRays,
    settings: &Settings,
    engine: Engine,
    budget: Option<Budget>,
    progress: &dyn Progress,
) -> Result<(Film, RenderStats)> {
    render_planned(scene, rays, &Job::new(scene, settings)?, engine, budget, progress)
}

/// Refuses what `job` cannot render with `engine` (progressively or not): a map the plan needs
/// left empty, more memory than the machine has (before any of it is allocated), diagnostics
/// from the path tracer, a medium filling the scene in the wavefront engine.
pub fn check_planned(job: &Job, scene: &Scene, engine: Engine, progressive: bool) -> Result<()> {
    let settings = &job.settings;
    if engine != Engine::Path {
        job.plan.check(settings)?;
        if scene.medium.is_some() && engine == Engine::Wavefront {
            return Err(Error::setting(
                "--engine",
                "the scene has a participating medium ([medium]): the wavefront engine does not render media yet; \
                 render it with `--engine reference` (photon mapping with a volume photon map) or `--engine path`",
            ));
        }
    }
    // Refuse what would exhaust memory before any of it is allocated.
    if let Some((available, total)) = crate::memory::machine() {
        let photons = if engine == Engine::Path {
            0
        } else {
            u64::from(settings.photons) * u64::from(job.plan.global_map.on)
                + u64::from(settings.caustic_photons) * u64::from(job.plan.caustic_map.on)
        };
        let per_pixel = crate::memory::bytes_per_pixel(progressive);
        // The wavefront engine's SIMD traversal builds the 8-wide BVH for single rays and 8-wide
        // packets.
        let wide_bvh = if engine == Engine::Wavefront && settings.code_path == crate::code_path::CodePath::Simd {
            scene.triangle_count() as u64 * crate::memory::WIDE_BVH_BYTES_PER_TRIANGLE
        } else {
            0
        };
        crate::memory::check(settings.width, settings.height, per_pixel, photons, wide_bvh, available, total)?;
    }
    if engine == Engine::Path && settings.diagnostics {
        return Err(Error::setting(
            "--diagnostics",
            "the diagnostic layers show photon-map estimates; the path tracer makes none",
        ));
    }
    Ok(())
}

/// Renders `scene` as `job` says: once, or — when `settings.passes > 1` or a budget is given —
/// progressive passes with the job's settings as each pass's (see
/// [`crate::progressive::per_pass`]). `progress` sees one phase per pass in a single render, or
/// one bar over the passes (or the budget's milliseconds) in a progressive one.
pub fn render_planned(
    scene: &Arc<Scene>,
    rays: &CameraRays,
    job: &Job,
    engine: Engine,
    budget: Option<Budget>,
    progress: &dyn Progress,
) -> Result<(Film, RenderStats)> {
    check_planned(job, scene, engine, is_progressive(&job.settings, budget))?;
    let settings = &job.settings;
    if engine == Engine::Path && is_progressive(settings, budget) {
        return Err(Error::setting("--engine", "progressive passes (--passes, --time) need a photon-mapping engine"));
    }
    let (meter, start) = (Arc::new(Meter::default()), Instant::now());
    let (film, mut stats) = metered(&meter, || {
        if !is_progressive(settings, budget) {
            let (mut film, mut stats) = render_job(scene, rays, job, engine, progress);
            crate::diagnostics::add_layers(scene, rays, job, &mut film, &mut stats);
            return Ok((film, stats));
        }
        let run = |pass: &Job| Ok(render_job(scene, rays, pass, engine, &NoProgress));
        crate::progressive::render_passes(scene, rays, job, &run, budget, progress)
    })?;
    stats.parallel = Some(ParallelStats::new(meter.reading(), job.threads, start.elapsed().as_secs_f64()));
    Ok((film, stats))
}
