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
//! The driver ([`render_passes`]) takes a closure that renders one pass of a [`Job`], so it
//! knows nothing of the engines; it owns the time budget ([`Budget`]).

use crate::code_path::CodePath;
use crate::error::Result;
use crate::film::{Film, Terms};
use crate::job::{FixedRadii, Job, Pass, PixelRadii};
use crate::photon_map::{flags, Filter, Kernel, Lookup, PhotonMap};
use crate::progress::Progress;
use crate::reference::build_job_maps;
use crate::scene::camera::CameraRays;
use crate::scene::Scene;
use crate::settings::Settings;
use crate::stats::RenderStats;
use crate::transport::camera::probe_first_surfaces;
use crate::transport::{Context, PhotonMaps};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A time budget: stop starting passes so that the render ends near `start + limit`.
#[derive(Clone, Copy, Debug)]
pub struct Budget {
    /// The whole budget.
    pub limit: Duration,
    /// When the budget started counting (the CLI counts scene loading too).
    pub start: Instant,
}

/// Photons sampled for the first radii.
pub const RADIUS_SAMPLES: usize = 1024;

/// Passes 0, 4, 8, … estimate their bias, and the image's bias is extrapolated from them: the
/// bias is ∝ r², so pass i's is sᵢ·b with sᵢ = r²ᵢ/r²₁, and the mean over all N passes is
/// (Σ sᵢ / N) · (Σ_S Bᵢ / Σ_S sᵢ) over the estimating passes S. The bias sum costs about a tenth
/// of a fixed-radius estimate (BENCHMARKS.md); the bias estimate's own noise is far below the
/// image's (0.2–0.3 % of a pixel against 2–10 %), so a quarter of the passes are enough.
pub const BIAS_EVERY: u32 = 4;

pub use crate::settings::PerPass;
pub use crate::stats::{ImageError, ProgressiveStats};

/// The seed of pass `i`: pass 0 keeps the user's seed; later ones are mixed from it.
#[must_use]
pub fn pass_seed(seed: u64, i: u32) -> u64 {
    if i == 0 {
        return seed;
    }
    crate::rng::mix64(seed ^ u64::from(i).wrapping_mul(0x9e37_79b9_7f4a_7c15))
}

/// r²ᵢ / r²₁ for pass `i` (1-based): ∏ⱼ₌₁^{i−1} (j + α)/(j + 1).
#[must_use]
pub fn radius2_scale(i: u32, alpha: f32) -> f64 {
    (1..i).map(|j| (f64::from(j) + f64::from(alpha)) / (f64::from(j) + 1.0)).product()
}

/// Median distance from a photon of `map` to its `k`-th nearest neighbour (same-facing photons,
/// within `r_max`), over up to [`RADIUS_SAMPLES`] photons spread through the map. `None` for an
/// empty map or when no sampled photon has k neighbours within `r_max`.
#[must_use]
pub fn median_knn_radius(map: &PhotonMap, k: u32, r_max: f32, code_path: CodePath) -> Option<f32> {
    if map.is_empty() {
        return None;
    }
    let step = map.len().div_ceil(RADIUS_SAMPLES).max(1);
    let mut scratch = Vec::new();
    let mut radii: Vec<f32> = (0..map.len())
        .step_by(step)
        .filter_map(|i| {
            let p = map.photon(i);
            let q = Lookup {
                p: p.position,
                k: k as usize,
                r_max,
                kernel: Kernel::Box,
                filter: Filter { n: p.normal, flags_mask: 0 },
            };
            map.nearest(code_path, &q, &mut scratch);
            (scratch.len() == k as usize).then(|| scratch.iter().map(|c| c.0).fold(0.0, f32::max).sqrt())
        })
        .collect();
    if radii.is_empty() {
        return None;
    }
    let mid = radii.len() / 2;
    Some(*radii.select_nth_unstable_by(mid, f32::total_cmp).1)
}

/// The pilot photon pass's seed: its photons are independent of every pass's.
#[must_use]
pub fn pilot_seed(seed: u64) -> u64 {
    pass_seed(seed, u32::MAX)
}

/// The first pass's radii from a pilot photon pass (traced with [`pilot_seed`]): per map, the
/// median k-th-neighbour distance over the pilot's photons (the maximum radius where a map is
/// empty or too sparse); with `per_pixel_radii`, each pixel's own as well ([`pixel_radii`]).
/// `job` is the render's, whose pass (the user's seed, no radii) is the first.
#[must_use]
pub fn initial_radii(scene: &Scene, rays: &CameraRays, job: &Job) -> FixedRadii {
    let settings = &job.settings;
    let d = scene.diagonal();
    let (r_global, r_caustic) = (settings.global_radius * d, settings.caustic_radius * d);
    let pilot = Job {
        settings: Settings { precompute_irradiance: false, ..settings.clone() },
        pass: Pass { seed: pilot_seed(settings.seed), radii: None },
        ..job.clone()
    };
    let (maps, _, _) = build_job_maps(scene, &pilot);
    let uniform = FixedRadii::uniform(
        median_knn_radius(&maps.global, settings.k, r_global, settings.code_path).unwrap_or(r_global),
        median_knn_radius(&maps.caustic, settings.caustic_k, r_caustic, settings.code_path).unwrap_or(r_caustic),
    );
    // The pixels' first radii follow the first pass's camera samples: `job`'s own seed.
    let pixels = settings.per_pixel_radii.then(|| Arc::new(pixel_radii(scene, rays, job, &maps, &uniform)));
    FixedRadii { pixels, ..uniform }
}

/// Each pixel's first radii: the radius a k-nearest-neighbour estimate would use at the first
/// non-specular point of the pixel's first camera sample (reached through mirrors and glass as
/// that sample's path goes) — the distance to the k-th nearest same-facing photon of `maps`,
/// or the maximum radius where fewer than k lie within it (`caustic_k` and the caustic map;
/// `k` and the global map without direct and caustic photons). `fallback`'s radii where the
/// path finds no such point. Global radii are found only where the camera reads the global
/// map (final gathering off).
#[must_use]
pub fn pixel_radii(
    scene: &Scene,
    rays: &CameraRays,
    job: &Job,
    maps: &PhotonMaps,
    fallback: &FixedRadii,
) -> PixelRadii {
    let settings = &job.settings;
    let ctx = Context::new(scene, maps, job);
    let want_global = ctx.effects.global_map.on && !ctx.effects.final_gather.on;
    let knn = |map: &PhotonMap, k: u32, r_max: f32, q: Lookup, scratch: &mut Vec<(f32, u32)>| {
        map.nearest(settings.code_path, &Lookup { k: k as usize, r_max, ..q }, scratch);
        let r = scratch.iter().map(|c| c.0).fold(0.0, f32::max).sqrt();
        if scratch.len() == k as usize && r > 0.0 && r.is_finite() {
            r
        } else {
            r_max
        }
    };
    let miss = (fallback.global, fallback.caustic);
    let found = probe_first_surfaces(&ctx, job, rays, miss, |_, _, sp, d, scratch, _| {
        let (ng, _) = sp.frame.oriented(-d);
        let q = Lookup { p: sp.p, k: 0, r_max: 0.0, kernel: settings.kernel, filter: Filter { n: ng, flags_mask: 0 } };
        let caustic = knn(&maps.caustic, settings.caustic_k, ctx.caustic_radius, q, scratch);
        let global = if want_global {
            let q = Lookup { filter: Filter { n: ng, flags_mask: flags::OWN_TERMS }, ..q };
            knn(&maps.global, settings.k, ctx.global_radius, q, scratch)
        } else {
            fallback.global
        };
        (global, caustic)
    });
    let (global, caustic): (Vec<f32>, Vec<f32>) = found.into_iter().unzip();
    PixelRadii { global: if want_global { global } else { Vec::new() }, caustic }
}

/// Student's t 97.5 % quantile for `dof` degrees of freedom: the table's values to 9, then the
/// Cornish–Fisher expansion about the normal's 1.96 (within 0.2 % from 10 on).
#[must_use]
pub fn student_t975(dof: u32) -> f64 {
    const Z: f64 = 1.959_964;
    match dof {
        0 => f64::INFINITY,
        1 => 12.706,
        2 => 4.303,
        3 => 3.182,
        4 => 2.776,
        5 => 2.571,
        6 => 2.447,
        7 => 2.365,
        8 => 2.306,
        9 => 2.262,
        _ => {
            let v = f64::from(dof);
            Z + (Z.powi(3) + Z) / (4.0 * v) + (5.0 * Z.powi(5) + 16.0 * Z.powi(3) + 3.0 * Z) / (96.0 * v * v)
        }
    }
}

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

/// A progressive render in progress: call [`Progressive::step`] for each pass, read the mean
/// with [`Progressive::image`].
pub struct Progressive {
    job: Job,
    first: FixedRadii,
    /// r² of the next pass over r² of the first ([`radius2_scale`], kept as a running product).
    scale2: f64,
    /// Σ sᵢ (sᵢ = r²ᵢ/r²₁) over all passes so far, and over those that estimated their bias.
    scale2_sums: [f64; 2],
    sum: Vec<Terms>,
    /// Per pixel, the sums of the passes' beauty grey value and of its square (f64: the
    /// variance is a small difference of large sums).
    grey: Vec<(f64, f64)>,
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
            scale2: 1.0,
            scale2_sums: [0.0; 2],
            sum: vec![Terms::default(); settings.width as usize * settings.height as usize],
            grey: vec![(0.0, 0.0); settings.width as usize * settings.height as usize],
            stats: RenderStats::default(),
            progress,
            last: None,
        }
    }

    /// The radii of the next pass.
    #[must_use]
    pub fn next_radii(&self) -> FixedRadii {
        let s = self.scale2.sqrt() as f32;
        FixedRadii {
            global: self.first.global * s,
            caustic: self.first.caustic * s,
            pixels: self.first.pixels.clone(),
            scale: s,
            bias: self.progress.passes.is_multiple_of(BIAS_EVERY),
        }
    }

    /// What turns the summed per-pixel bias of the estimating passes into the image's:
    /// (Σ sᵢ / N) / Σ_S sᵢ ([`BIAS_EVERY`]).
    fn bias_scale(&self) -> f32 {
        let n = f64::from(self.progress.passes.max(1));
        if self.scale2_sums[1] > 0.0 {
            (self.scale2_sums[0] / n / self.scale2_sums[1]) as f32
        } else {
            0.0
        }
    }

    /// Passes so far.
    #[must_use]
    pub fn passes(&self) -> u32 {
        self.progress.passes
    }

    /// Renders the next pass with `engine` (given the pass's job) and adds it to the mean.
    pub fn step(&mut self, engine: &dyn Fn(&Job) -> Result<(Film, RenderStats)>) -> Result<()> {
        let t = Instant::now();
        let i = self.progress.passes;
        let radii = self.next_radii();
        let final_radii = [radii.global, radii.caustic];
        self.scale2_sums[0] += self.scale2;
        if radii.bias {
            self.scale2_sums[1] += self.scale2;
        }
        let pass = self.job.with_pass(Pass { seed: pass_seed(self.job.settings.seed, i), radii: Some(radii) })?;
        let (film, stats) = engine(&pass)?;
        self.last = Some(pass);
        for ((s, g), p) in self.sum.iter_mut().zip(&mut self.grey).zip(&film.pixels) {
            *s += *p;
            let v = f64::from(p.beauty().element_sum()) / 3.0;
            *g = (g.0 + v, g.1 + v * v);
        }
        // This pass's stats, with the counts and phase times of the earlier passes added.
        let mut stats = stats;
        let old = &self.stats;
        stats.rays += old.rays;
        // The load's count is the scene's, the same in every pass.
        let load_normals = stats.numerics.load_normals;
        stats.numerics += old.numerics;
        stats.numerics.load_normals = load_normals;
        stats.times.global_photons_s += old.times.global_photons_s;
        stats.times.caustic_photons_s += old.times.caustic_photons_s;
        stats.times.map_build_s += old.times.map_build_s;
        stats.times.camera_s += old.times.camera_s;
        // Photon counts and per-system work are totals over the passes, like the rays.
        stats.global_map += &old.global_map;
        stats.caustic_map += &old.caustic_map;
        if let (Some(s), Some(o)) = (stats.stages.as_mut(), old.stages.as_ref()) {
            *s += o;
        }
        self.stats = stats;
        self.progress.passes += 1;
        // Pass i + 1 (1-based) done: r²ᵢ₊₂ = r²ᵢ₊₁ · (i + 1 + α)/(i + 2).
        let j = f64::from(self.progress.passes);
        self.scale2 *= (j + f64::from(self.job.settings.alpha)) / (j + 1.0);
        self.progress.final_radii = final_radii;
        self.progress.pass_seconds.push(t.elapsed().as_secs_f64());
        Ok(())
    }

    /// The mean of the passes so far, with its noise ([`Progressive::noise`]) and, in its
    /// pixels, its estimated bias.
    #[must_use]
    pub fn image(&self) -> Film {
        let n = self.progress.passes.max(1) as f32;
        let bias = self.bias_scale();
        Film {
            width: self.job.settings.width,
            height: self.job.settings.height,
            pixels: self.sum.iter().map(|t| Terms { bias: t.bias * bias, ..*t * (1.0 / n) }).collect(),
            noise: self.noise(),
            diagnostics: None,
        }
    }

    /// The image's error estimate ([`ImageError`], `target_error`'s metric): the means over
    /// pixels of [`Film::error`]'s bound and of its two parts, each over the image's mean grey
    /// value. `None` before two passes.
    #[must_use]
    pub fn error_95(&self) -> Option<ImageError> {
        let pixels = self.grey.len().max(1) as f64;
        let n = f64::from(self.progress.passes);
        let noise = self.half_widths()?.sum::<f64>() / pixels;
        let scale = f64::from(self.bias_scale());
        let bias = self.sum.iter().map(|t| (f64::from(t.bias.element_sum()) / 3.0 * scale).abs()).sum::<f64>() / pixels;
        let mean_grey = (self.grey.iter().map(|g| g.0).sum::<f64>() / n / pixels).max(f64::MIN_POSITIVE);
        Some(ImageError { error: (noise + bias) / mean_grey, noise: noise / mean_grey, bias: bias / mean_grey })
    }

    /// Per pixel, the half-width of a 95 % confidence interval of the mean beauty grey value,
    /// from the spread between the passes: t · s/√N, with s the passes' sample standard deviation
    /// and t Student's 97.5 % quantile for N − 1 degrees of freedom. The noise only, not the bias
    /// (which the pixels carry: [`Terms::bias`]); and approximate, as later passes' smaller radii
    /// make them a little noisier than earlier ones. `None` before two passes.
    #[must_use]
    pub fn noise(&self) -> Option<Vec<f32>> {
        Some(self.half_widths()?.map(|h| h as f32).collect())
    }

    /// [`Progressive::noise`]'s half-widths, pixel by pixel, in f64.
    fn half_widths(&self) -> Option<impl Iterator<Item = f64> + '_> {
        let n = self.progress.passes;
        if n < 2 {
            return None;
        }
        let (nf, t) = (f64::from(n), student_t975(n - 1));
        Some(self.grey.iter().map(move |&(s1, s2)| {
            let mean = s1 / nf;
            let var = ((s2 - nf * mean * mean) / (nf - 1.0)).max(0.0);
            t * (var / nf).sqrt()
        }))
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
}

/// Settings for each pass when a one-pass render's `spp` samples and photon counts are spread
/// over passes: 1 sample per pixel and photons / spp per map (at least 1 000), except for the
/// amounts `given` per pass.
#[must_use]
pub fn per_pass(settings: &Settings, given: PerPass) -> Settings {
    let mut s = settings.clone();
    let spread = settings.spp.max(1);
    if !given.spp {
        s.spp = 1;
    }
    if !given.photons && settings.photons > 0 {
        s.photons = (settings.photons / spread).max(1000);
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

/// A warning when one pass takes more than 5 % of the budget (the render cannot end within 5 %
/// of it then).
#[must_use]
pub fn budget_warning(p: &ProgressiveStats) -> Option<String> {
    let (b, first) = (p.budget_s?, *p.pass_seconds.first()?);
    (first > 0.05 * b).then(|| {
        format!(
            "one pass takes {first:.2} s, more than 5 % of the {b:.2} s budget; lower --spp or --photons per pass to end closer to it"
        )
    })
}

/// Progressive passes of `job` (its settings per pass), each rendered by `run` given the pass's
/// job, until `settings.passes` or, with a budget, until the budget is spent
/// ([`Progressive::another_fits`]). `progress` gets one bar: passes, or the budget's
/// milliseconds, with the pass number and time left as its message.
pub fn render_passes(
    scene: &Arc<Scene>,
    rays: &CameraRays,
    job: &Job,
    run: &dyn Fn(&Job) -> Result<(Film, RenderStats)>,
    budget: Option<Budget>,
    progress: &dyn Progress,
) -> Result<(Film, RenderStats)> {
    let settings = &job.settings;
    let t = Instant::now();
    let start = budget.map_or(t, |b| b.start);
    let mut p = Progressive::new(scene, rays, job);
    let target = f64::from(settings.target_error);
    // A target with no pass count runs until it is met (or the budget is spent).
    let pass_cap = if target > 0.0 && settings.passes == 1 { u32::MAX } else { settings.passes };
    let (unit, total) = match budget {
        Some(b) => ("ms of budget", b.limit.as_millis() as u64),
        // With shrinking radii the error falls about as N^(−1/3) (BENCHMARKS.md fits −0.31 to the
        // noise), so about (target / error)³ of the passes needed are done.
        None if pass_cap == u32::MAX => ("% to target", 100),
        None => ("passes", u64::from(settings.passes)),
    };
    progress.start(unit, total);
    let mut shown = 0u64;
    // The image's error after the last pass (computed once a pass: it reads every pixel).
    let mut error_now: Option<ImageError> = None;
    loop {
        let reached = target > 0.0
            && p.passes() >= crate::settings::MIN_PASSES_FOR_TARGET
            && error_now.is_some_and(|e| e.error <= target);
        let go_on = !reached
            && match budget {
                Some(b) => p.another_fits(start.elapsed(), b.limit),
                None => p.passes() < pass_cap,
            };
        if !go_on {
            break;
        }
        p.step(run)?;
        let elapsed = start.elapsed();
        error_now = p.error_95();
        let error = error_now.map_or(String::new(), |e| format!(", error ±{:.2} %", 100.0 * e.error));
        let done = match budget {
            Some(b) => {
                let left = (b.limit.as_secs_f64() - elapsed.as_secs_f64()).max(0.0);
                progress.message(&format!("pass {}{error}, {left:.1} s left", p.passes()));
                (elapsed.as_millis() as u64).min(total)
            }
            None if pass_cap == u32::MAX => {
                progress.message(&format!("pass {}{error}, target ±{:.2} %", p.passes(), 100.0 * target));
                // Not 100 % before the minimum of passes has run.
                let cap = if p.passes() < crate::settings::MIN_PASSES_FOR_TARGET { 99.0 } else { 100.0 };
                error_now.map_or(0, |e| (100.0 * (target / e.error).powi(3)).min(cap) as u64)
            }
            None => {
                progress.message(&format!("pass {} of {}{error}", p.passes(), settings.passes));
                u64::from(p.passes())
            }
        };
        progress.advance(done - shown.min(done));
        shown = shown.max(done);
    }
    progress.finish();
    let mut film = p.image();
    if let Some(last) = &p.last {
        crate::diagnostics::add_layers(scene, rays, last, &mut film, &mut p.stats);
    }
    let error_95 = error_now.or_else(|| p.error_95());
    let mut stats = p.stats;
    let mut prog = p.progress;
    prog.budget_s = budget.map(|b| b.limit.as_secs_f64());
    prog.elapsed_s = start.elapsed().as_secs_f64();
    prog.error_95 = error_95;
    prog.target_error = (target > 0.0).then_some(settings.target_error);
    stats.phases.push(format!("{} progressive passes", prog.passes));
    stats.spp = settings.spp * prog.passes;
    stats.progressive = Some(prog);
    stats.times.total_s = t.elapsed().as_secs_f64();
    stats.mean_rgb = film.mean().to_array();
    Ok((film, stats))
}
