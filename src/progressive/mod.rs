//! Progressive photon mapping in Knaus & Zwicker's probabilistic form (2011): every pass is a
//! whole render with fresh photons, fresh camera samples and *fixed* density-estimation radii;
//! the image is the mean of the passes; and the radii shrink from pass to pass,
//!
//! ```text
//! r²ᵢ₊₁ = r²ᵢ · (i + α) / (i + 1)        (i = 1, 2, …; α ∈ (0, 1), 2/3 by default)
//! ```
//!
//! so that bias (∝ r²) and variance (∝ 1/(N·r²) per pass, averaged over N passes) both vanish:
//! the mean squared error falls as N^(−2/3) for α = 2/3 and the RMSE as N^(−1/3). No statistic is
//! carried between passes, so memory stays at one pass's photon maps. The caustic and the global
//! map each have their own radius sequence. The first radii come from a pilot photon pass with
//! its own seed ([`pilot_seed`], independent of every pass's photons): per map, the median
//! distance to the k-th nearest photon (`caustic_k`, `k`) over up to [`RADIUS_SAMPLES`] pilot
//! photons, so that `k` keeps its meaning as the blur of the first pass; and with
//! `per_pixel_radii` (the default) each pixel's own, the k-th-neighbour distance at the pixel's
//! first non-specular point ([`pixel_radii`]), scaled by the same sequence.
//!
//! Any set of passes can be rendered ([`crate::divided::pass_set::PassSet`]): pass i's seed and radii
//! follow from the user's seed and i alone, and the passes' sums are exact
//! ([`crate::divided::pass_sums`]), so passes split between machines or runs merge into the image of an
//! undivided render, bit for bit.
//!
//! The driver ([`render_passes`], [`drive`]) takes a closure that renders one pass of a [`Job`],
//! so it knows nothing of the engines; it owns the time budget ([`Budget`]).

mod budget;
mod driver;
mod radii;

pub use budget::{budget_warning, costs, Cost};
pub use driver::{default_set, drive, finish, render_passes, Drive, Ended};
pub use radii::{initial_radii, median_knn_radius, pass_seed, pilot_seed, pixel_radii, RADIUS_SAMPLES};

use crate::divided::pass_sums::{estimates_bias, PassSums};
use crate::error::Result;
use crate::film::Film;
use crate::job::{FixedRadii, Job, Pass};
use crate::scene::camera::CameraRays;
use crate::scene::Scene;
use crate::settings::Settings;
use crate::stats::RenderStats;
use std::time::{Duration, Instant};

pub use crate::divided::pass_sums::{radius2_scale, student_t975, BIAS_EVERY};

/// A time budget: stop starting passes so that the render ends near `start + limit`.
#[derive(Clone, Copy, Debug)]
pub struct Budget {
    /// The whole budget.
    pub limit: Duration,
    /// When the budget started counting (the CLI counts scene loading too).
    pub start: Instant,
}

pub use crate::settings::PerPass;
pub use crate::stats::{ImageError, ProgressiveStats};

/// 10th, 50th and 90th percentiles of `values` (none for an empty slice).
fn percentiles(values: &[f32]) -> Option<[f32; 3]> {
    if values.is_empty() {
        return None;
    }
    let mut v = values.to_vec();
    v.sort_by(f32::total_cmp);
    let at = |q: f32| v[((v.len() - 1) as f32 * q).round() as usize];
    Some([at(0.1), at(0.5), at(0.9)])
}

/// A progressive render in progress: call [`Progressive::step`] (or [`Progressive::step_pass`])
/// for each pass, read the mean with [`Progressive::image`].
pub struct Progressive {
    job: Job,
    first: FixedRadii,
    /// The passes' exact sums, and which passes they are.
    pub sums: PassSums,
    /// Stats of the passes so far (rays and phase times summed; the rest from the last pass).
    pub stats: RenderStats,
    /// What the passes did.
    pub progress: ProgressiveStats,
    /// The last pass's job.
    pub last: Option<Job>,
}

impl Progressive {
    /// Prepares a progressive render of `scene` seen through `rays` as `job` says (its settings
    /// hold spp and photon counts per pass): finds the first radii.
    #[must_use]
    pub fn new(scene: &Scene, rays: &CameraRays, job: &Job) -> Self {
        let settings = &job.settings;
        let t = Instant::now();
        let first = initial_radii(scene, rays, job);
        let pixel = first.pixels.as_deref();
        let progress = ProgressiveStats {
            alpha: settings.alpha,
            initial_radii: [first.global, first.caustic],
            pixel_caustic_radii: pixel.and_then(|p| percentiles(&p.caustic)),
            pixel_global_radii: pixel.and_then(|p| percentiles(&p.global)),
            pilot_seconds: t.elapsed().as_secs_f64(),
            ..Default::default()
        };
        Progressive {
            job: job.clone(),
            first,
            sums: PassSums::new(settings.width, settings.height, settings.alpha),
            stats: RenderStats::default(),
            progress,
            last: None,
        }
    }

    /// Continues from passes rendered before (a checkpoint or partial film): their sums and the
    /// stats they had. The last of them becomes the last pass (whose diagnostic layers a
    /// finished render adds).
    pub fn resume(&mut self, sums: PassSums, stats: RenderStats) -> Result<()> {
        self.progress.passes = sums.passes();
        if let Some(p) = &stats.progressive {
            self.progress.pass_seconds.clone_from(&p.pass_seconds);
            self.progress.final_radii = p.final_radii;
        }
        let last = sums.done.last();
        self.sums = sums;
        self.stats = RenderStats { progressive: None, ..stats };
        self.last = last.map(|i| self.pass_job(i)).transpose()?;
        Ok(())
    }

    /// The radii of pass `i`.
    pub fn radii(&mut self, i: u32) -> FixedRadii {
        let s = self.sums.scale2(i).sqrt() as f32;
        // Volume radii shrink as the cube root of the product whose square root the surfaces' do.
        let v = s.powf(2.0 / 3.0);
        FixedRadii {
            global: self.first.global * s,
            caustic: self.first.caustic * s,
            pixels: self.first.pixels.clone(),
            scale: s,
            bias: estimates_bias(i),
            volume: (self.first.volume.0 * v, self.first.volume.1 * v),
        }
    }

    /// Passes so far.
    #[must_use]
    pub fn passes(&self) -> u32 {
        self.sums.passes()
    }

    /// The job of pass `i`: its seed and radii.
    pub fn pass_job(&mut self, i: u32) -> Result<Job> {
        let radii = self.radii(i);
        self.job.with_pass(Pass { seed: pass_seed(self.job.settings.seed, i), radii: Some(radii) })
    }

    /// Renders the pass after the last one so far (pass 0 first) with `engine` (given the pass's
    /// job) and adds it to the sums.
    pub fn step(&mut self, engine: &dyn Fn(&Job) -> Result<(Film, RenderStats)>) -> Result<()> {
        let i = self.sums.done.last().map_or(0, |l| l + 1);
        self.step_pass(i, engine)
    }

    /// Renders pass `i` (larger than every pass so far) with `engine` and adds it.
    pub fn step_pass(&mut self, i: u32, engine: &dyn Fn(&Job) -> Result<(Film, RenderStats)>) -> Result<()> {
        let t = Instant::now();
        let pass = self.pass_job(i)?;
        let (film, stats) = engine(&pass)?;
        self.add(i, pass, &film, stats, t.elapsed().as_secs_f64());
        Ok(())
    }

    /// Adds pass `i`, rendered as `pass` says, to the sums: its film, its stats and the
    /// `seconds` it took.
    pub fn add(&mut self, i: u32, pass: Job, film: &Film, stats: RenderStats, seconds: f64) {
        let radii = pass.pass.radii.as_ref().map_or([0.0; 2], |r| [r.global, r.caustic]);
        self.sums.add_pass(i, film, self.job.threads);
        self.last = Some(pass);
        // This pass's stats, with the counts and phase times of the earlier passes added.
        let mut stats = stats;
        stats.add_totals(&self.stats);
        self.stats = stats;
        self.progress.passes = self.sums.passes();
        self.progress.final_radii = radii;
        self.progress.pass_seconds.push(seconds);
    }

    /// The mean of the passes so far, with its noise and, in its pixels, its estimated bias.
    #[must_use]
    pub fn image(&self) -> Film {
        self.sums.image()
    }

    /// The image's error estimate ([`PassSums::error_95`]). `None` before two passes.
    #[must_use]
    pub fn error_95(&self) -> Option<ImageError> {
        self.sums.error_95(self.job.threads)
    }

    /// Per pixel, the noise's 95 % half-width ([`PassSums::noise`]). `None` before two passes.
    #[must_use]
    pub fn noise(&self) -> Option<Vec<f32>> {
        self.sums.noise()
    }

    /// Whether another pass should start, `elapsed` after the caller's start, to end closest to
    /// `budget`: yes while the expected end (elapsed + the median pass time) is nearer the budget
    /// than stopping now, i.e. while elapsed + median/2 < budget. At least one pass always runs.
    #[must_use]
    pub fn another_fits(&self, elapsed: Duration, budget: Duration) -> bool {
        let mut times = self.progress.pass_seconds.clone();
        if times.is_empty() {
            return true;
        }
        let mid = times.len() / 2;
        let median = *times.select_nth_unstable_by(mid, f64::total_cmp).1;
        elapsed.as_secs_f64() + median / 2.0 < budget.as_secs_f64()
    }

    /// The stats so far, with the progressive stats in them (what a checkpoint records).
    #[must_use]
    pub fn stats_now(&self) -> RenderStats {
        RenderStats { progressive: Some(self.progress.clone()), ..self.stats.clone() }
    }

    /// The job the passes are rendered with (each pass's seed and radii aside).
    #[must_use]
    pub fn job(&self) -> &Job {
        &self.job
    }
}
/// The fewest global photons a pass spread from a one-pass render's settings ([`per_pass`])
/// traces for each pixel of its image: one, as pbrt-v4's SPPM traces as many photons per
/// iteration as the film has pixels by default. Spread as photons / spp alone, the Modern Hall's
/// 256² passes spent 1 % of their time on photons (12 500 a pass) and their radii stayed wide:
/// at 30 s the image was 3.4 % bright and its relMSE 0.0175; at 65 536 a pass, 1.3 % and 0.0121
/// (BENCHMARKS.md). The caustic map keeps its share: its photons are aimed, and dearer.
pub const GLOBAL_PHOTONS_PER_PIXEL: u32 = 1;

/// Settings for each pass when a one-pass render's `spp` samples and photon counts are spread
/// over passes: 1 sample per pixel and photons / spp per map (at least 1 000), except for the
/// amounts `given` per pass; and at least [`GLOBAL_PHOTONS_PER_PIXEL`] global photon per pixel.
#[must_use]
pub fn per_pass(settings: &Settings, given: PerPass) -> Settings {
    let mut s = settings.clone();
    let spread = settings.spp.max(1);
    if !given.spp {
        s.spp = 1;
    }
    if !given.photons && settings.photons > 0 {
        let pixels = u64::from(settings.width) * u64::from(settings.height) * u64::from(GLOBAL_PHOTONS_PER_PIXEL);
        s.photons = (settings.photons / spread).max(1000).max(pixels.min(u64::from(u32::MAX)) as u32);
    }
    if !given.caustic_photons && settings.caustic_photons > 0 {
        s.caustic_photons = (settings.caustic_photons / spread).max(1000);
    }
    s
}

/// The line the CLI prints before a progressive render: passes or budget, and each pass's work.
#[must_use]
pub fn describe(plan: &crate::effects::Effects, settings: &Settings, budget: Option<Duration>) -> String {
    let maps: Vec<String> =
        [(plan.global_map.on, settings.photons, "global"), (plan.caustic_map.on, settings.caustic_photons, "caustic")]
            .iter()
            .filter(|m| m.0)
            .map(|m| format!("{} {} photons", m.1, m.2))
            .collect();
    format!(
        "progressive: {} each {} spp{}{}, α = {:.3}\n",
        match (budget, settings.target_error > 0.0) {
            (Some(b), false) => format!("passes for {:.2} s,", b.as_secs_f64()),
            (Some(b), true) =>
                format!("passes until noise ±{:.2} % or {:.2} s,", 100.0 * settings.target_error, b.as_secs_f64()),
            (None, true) if settings.passes > 1 => {
                format!("passes until noise ±{:.2} %, at most {},", 100.0 * settings.target_error, settings.passes)
            }
            (None, true) => format!("passes until noise ±{:.2} %,", 100.0 * settings.target_error),
            (None, false) => format!("{} passes,", settings.passes),
        },
        settings.spp,
        if maps.is_empty() { "" } else { ", " },
        maps.join(" + "),
        settings.alpha
    )
}
