//! `render`'s progressive path: which passes this run renders (all, a range, or worker K of N),
//! resuming from a partial film, periodic checkpoints, stopping on a signal, and writing the
//! output — the image, or for a part of a divided render the partial film `merge` reads.

use super::interrupt::{Interrupt, WritePartial};
use super::Say;
use photonwave::divided::partial::{self, Identity};
use photonwave::divided::pass_set::PassSet;
use photonwave::engine::{Budget, Engine};
use photonwave::error::{Error, Result};
use photonwave::film::Film;
use photonwave::job::Job;
use photonwave::parallel::{metered, Meter};
use photonwave::progress::Progress;
use photonwave::progressive::{self, Drive, Ended, Progressive};
use photonwave::scene::camera::CameraRays;
use photonwave::scene::Scene;
use photonwave::stats::{ParallelStats, RenderStats};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// `--passes`: a count, or a range of pass indices.
#[derive(Clone, Copy, Debug)]
pub enum PassesArg {
    /// `--passes N`: passes 0..N.
    Count(u32),
    /// `--passes A..B`: passes A..B (a part of a divided render).
    Range(PassSet),
}

impl PassesArg {
    /// The pass count this gives the settings: N, or B for a range.
    #[must_use]
    pub fn total(self) -> u32 {
        match self {
            PassesArg::Count(n) => n,
            PassesArg::Range(r) => r.end,
        }
    }
}

/// Parses `--passes N` or `--passes A..B`.
pub fn parse_passes(s: &str) -> std::result::Result<PassesArg, String> {
    match PassSet::parse_range(s)? {
        Some(r) => Ok(PassesArg::Range(r)),
        None => s
            .trim()
            .parse()
            .map(PassesArg::Count)
            .map_err(|_| format!("`{s}`: expected a number of passes N or a range A..B, such as 64 or 32..64")),
    }
}

/// What the progressive path needs from `render`'s flags.
pub struct PassFlags<'a> {
    /// `--passes`.
    pub passes: Option<PassesArg>,
    /// `--pass-set K/N`.
    pub pass_set: Option<&'a str>,
    /// `--partial`.
    pub partial: bool,
    /// `--checkpoint FILE`.
    pub checkpoint: Option<&'a Path>,
    /// `--checkpoint-every`.
    pub checkpoint_every: Duration,
    /// `--resume FILE`.
    pub resume: Option<&'a Path>,
    /// `-o`.
    pub output: &'a Path,
}

impl PassFlags<'_> {
    /// Whether these flags ask for a part of a render (a partial film as the output).
    #[must_use]
    pub fn divided(&self) -> bool {
        self.pass_set.is_some() || matches!(self.passes, Some(PassesArg::Range(_)))
    }

    /// Whether these flags need the progressive path even without a pass count.
    #[must_use]
    pub fn any(&self) -> bool {
        self.divided() || self.partial || self.checkpoint.is_some() || self.resume.is_some()
    }

    /// The passes this run renders, for `settings` (a count from the scene file or a preset
    /// caps a pass set too) and a `budget`.
    pub fn set(&self, settings: &photonwave::settings::Settings, budget: Option<Budget>) -> Result<PassSet> {
        let open = budget.is_some() || settings.target_error > 0.0;
        match (self.passes, self.pass_set) {
            (Some(PassesArg::Range(_)), Some(_)) => Err(Error::setting(
                "--pass-set",
                "give either --pass-set K/N (with --passes N as a cap) or a range --passes A..B, not both",
            )),
            (Some(PassesArg::Range(r)), None) => Ok(r),
            (given, Some(s)) => {
                let end = if given.is_some() || (!open && settings.passes > 1) {
                    settings.passes
                } else if open {
                    u32::MAX
                } else {
                    return Err(Error::setting(
                        "--pass-set",
                        "a pass set needs an end: --passes N (the whole render's count), --time or --target-error",
                    ));
                };
                PassSet::parse_stride(s, end).map_err(|m| Error::setting("--pass-set", m))
            }
            (_, None) if self.any() && !open && settings.passes <= 1 => Err(Error::setting(
                if self.resume.is_some() {
                    "--resume"
                } else if self.checkpoint.is_some() {
                    "--checkpoint"
                } else {
                    "--partial"
                },
                "checkpoints, partial films and resuming are for progressive renders: add --passes N, --time or \
                 --target-error",
            )),
            (_, None) => Ok(progressive::default_set(settings, budget)),
        }
    }
}

/// What the progressive path gives back to `render`.
pub struct Rendered {
    /// The film written to `-o` (the mean of the passes).
    pub film: Film,
    /// The render's stats.
    pub stats: RenderStats,
    /// The signal that stopped the render early, if one did.
    pub signal: Option<i32>,
}

/// A render's inputs, as `render` prepared them.
pub struct Setup<'a> {
    /// The scene.
    pub scene: &'a Arc<Scene>,
    /// Its camera rays.
    pub rays: &'a CameraRays,
    /// The job, with per-pass settings.
    pub job: &'a Job,
    /// The engine.
    pub engine: Engine,
    /// The time budget.
    pub budget: Option<Budget>,
    /// When the command started.
    pub t0: Instant,
    /// Which render this is, for partial films.
    pub identity: Identity,
}

/// Renders the passes `flags` ask for, writes `-o` (and checkpoints), and returns the film.
pub fn render(s: &Setup, flags: &PassFlags, progress: &dyn Progress, say: Say) -> Result<Rendered> {
    let t = Instant::now();
    let settings = &s.job.settings;
    let set = flags.set(settings, s.budget)?;
    let mut state = Progressive::new(s.scene, s.rays, s.job);
    if let Some(path) = flags.resume {
        let part = partial::read(path)?;
        let file = path.display().to_string();
        if let Some(why) = s.identity.difference("this render", &part.identity, &file) {
            return Err(Error::setting("--resume", format!("cannot resume: {why}")));
        }
        // The file's passes must be the first of this run's set, so that continuing the set
        // renders the rest of it.
        let mut expect = None;
        for &i in part.sums.done.indices() {
            expect = set.next_after(expect);
            if expect != Some(i) {
                return Err(Error::setting(
                    "--resume",
                    format!(
                        "{} holds passes {}, which are not the first passes of this render's {}; resume with the \
                         flags that started it",
                        path.display(),
                        part.sums.done.to_text(),
                        set.describe()
                    ),
                ));
            }
        }
        say.info(format!("resuming from {}: {} passes done\n", path.display(), part.sums.passes()));
        state.resume(part.sums, part.stats)?;
    }
    let divided = flags.divided() || flags.partial;
    if flags.divided() {
        say.info(format!(
            "rendering {} (a part: {} is a partial film for `photonwave merge`)\n",
            set.describe(),
            flags.output.display()
        ));
    }
    let state = Arc::new(Mutex::new(state));
    let identity = Arc::new(s.identity.clone());
    let spp = settings.spp;
    // Where a stopped render writes its passes: the checkpoint, else the output.
    let stop_path: PathBuf = flags.checkpoint.unwrap_or(flags.output).to_path_buf();
    let write_partial = {
        let (identity, path) = (identity.clone(), stop_path.clone());
        Arc::new(move |p: &Progressive| partial::write(&path, &identity, &p.sums, spp, &p.image(), &p.stats_now()))
    };
    let interrupt = Interrupt::watch(state.clone(), write_partial.clone() as Arc<WritePartial>)
        .map_err(|e| Error::setting("signals", format!("cannot watch SIGINT and SIGTERM: {e}")))?;
    let mut last_checkpoint = Instant::now();
    let mut after_pass = |p: &Progressive| -> Result<()> {
        if let Some(path) = flags.checkpoint {
            if last_checkpoint.elapsed() >= flags.checkpoint_every {
                // A failed checkpoint (a full disk) keeps the previous one and the render going.
                if let Err(e) = partial::write(path, &identity, &p.sums, spp, &p.image(), &p.stats_now()) {
                    say.warn(format!("checkpoint not written, the render goes on: {e}"));
                }
                last_checkpoint = Instant::now();
            }
        }
        Ok(())
    };
    let run = |pass: &Job| {
        Ok(photonwave::engine::render_job(s.scene, s.rays, pass, s.engine, &photonwave::progress::NoProgress))
    };
    let d = Drive { set, budget: s.budget, stop: &|| interrupt.stopping(), after_pass: &mut after_pass };
    // This run's use of its threads (a resumed render's earlier runs are not in it).
    let (meter, metered_from) = (Arc::new(Meter::default()), Instant::now());
    let parallel =
        |threads: usize| Some(ParallelStats::new(meter.reading(), threads, metered_from.elapsed().as_secs_f64()));
    let ended = metered(&meter, || progressive::drive(&state, &run, d, progress))?;
    let guard = state.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    interrupt.finish();
    if ended == Ended::Stopped {
        let sig = interrupt.signal().unwrap_or(signal_hook::consts::SIGTERM);
        let (film, mut stats) = (guard.image(), guard.stats_now());
        stats.times.total_s = t.elapsed().as_secs_f64();
        stats.parallel = parallel(s.job.threads);
        partial::write(&stop_path, &identity, &guard.sums, spp, &film, &stats)?;
        say.info(format!(
            "stopped: {} passes written to {} (continue with --resume)\n",
            guard.passes(),
            stop_path.display()
        ));
        return Ok(Rendered { film, stats, signal: Some(sig) });
    }
    // Every pass is done: with diagnostic layers still to make (a photon pass), save the passes
    // first, so that a signal or a kill meanwhile loses nothing.
    if settings.diagnostics && (divided || flags.checkpoint.is_some()) {
        write_partial(&guard)?;
    }
    let start = s.budget.map_or(s.t0, |b| b.start);
    let (film, mut stats) = metered(&meter, || progressive::finish(&guard, s.scene, s.rays, s.budget, start, true));
    stats.times.total_s = t.elapsed().as_secs_f64();
    stats.parallel = parallel(s.job.threads);
    if let Some(path) = flags.checkpoint {
        partial::write(path, &identity, &guard.sums, spp, &film, &stats)?;
    }
    if divided {
        partial::write(flags.output, &identity, &guard.sums, spp, &film, &stats)?;
    } else {
        film.write_exr(flags.output)?;
    }
    Ok(Rendered { film, stats, signal: None })
}
