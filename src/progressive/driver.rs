//! The progressive driver: runs the passes of a [`PassSet`] with an engine's one-pass closure,
//! under a pass count, a time budget, an error target and a stop request, and turns the sums
//! into the finished film and stats.

use super::{Budget, Progressive};
use crate::divided::pass_set::PassSet;
use crate::error::Result;
use crate::film::Film;
use crate::job::Job;
use crate::progress::Progress;
use crate::scene::camera::CameraRays;
use crate::scene::Scene;
use crate::stats::{ImageError, RenderStats};
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// How [`drive`] runs the passes.
pub struct Drive<'a> {
    /// The passes it may render (those already summed are skipped: a resumed render).
    pub set: PassSet,
    /// A time budget.
    pub budget: Option<Budget>,
    /// Asked between passes: stop now (a signal came).
    pub stop: &'a dyn Fn() -> bool,
    /// Called after each pass with the render so far (periodic checkpoints).
    pub after_pass: &'a mut dyn FnMut(&Progressive) -> Result<()>,
}

/// Why [`drive`] returned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ended {
    /// The set, the budget or the error target is done.
    Done,
    /// `stop` asked for it.
    Stopped,
}

/// Locks the render (a panic elsewhere leaves the sums whole: they change only under the lock).
fn lock(state: &Mutex<Progressive>) -> std::sync::MutexGuard<'_, Progressive> {
    state.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Runs the passes `d.set` holds after the last one summed in `state`, each rendered by `run`
/// given the pass's job, until the set ends, the budget is spent
/// ([`Progressive::another_fits`]), the error target is met or `d.stop` says so. The lock is
/// not held while a pass renders (only to prepare it, and to add it, estimate the error and
/// call `after_pass`), so that another thread can write the sums meanwhile. `progress` gets one bar: passes, or the budget's milliseconds, with the pass
/// number and time left as its message.
pub fn drive(
    state: &Mutex<Progressive>,
    run: &dyn Fn(&Job) -> Result<(Film, RenderStats)>,
    d: Drive,
    progress: &dyn Progress,
) -> Result<Ended> {
    let target = f64::from(lock(state).job().settings.target_error);
    let start = d.budget.map_or_else(Instant::now, |b| b.start);
    let mut next = d.set.next_after(lock(state).sums.done.last());
    let to_do = d.set.count().map(|n| n.saturating_sub(lock(state).passes()));
    let (unit, total) = match (d.budget, to_do) {
        (Some(b), _) => ("ms of budget", b.limit.as_millis() as u64),
        // With shrinking radii the error falls about as N^(−1/3) (BENCHMARKS.md fits −0.31 to the
        // noise), so about (target / error)³ of the passes needed are done.
        (None, None) => ("% to target", 100),
        (None, Some(n)) => ("passes", u64::from(n)),
    };
    progress.start(unit, total);
    let mut shown = 0u64;
    let mut rendered = 0u32;
    // The image's error after the last pass (computed once a pass: it reads every pixel).
    let mut error_now: Option<ImageError> = lock(state).error_95();
    let ended = loop {
        let passes = lock(state).passes();
        let reached = target > 0.0
            && passes >= crate::settings::MIN_PASSES_FOR_TARGET
            && error_now.is_some_and(|e| e.error <= target);
        let fits = d.budget.is_none_or(|b| lock(state).another_fits(start.elapsed(), b.limit));
        let Some(i) = next.filter(|_| !reached && fits) else { break Ended::Done };
        // After the check for the end: a signal during the last pass still finishes the render.
        if (d.stop)() {
            break Ended::Stopped;
        }
        let t = Instant::now();
        let pass = lock(state).pass_job(i)?;
        let (film, stats) = run(&pass)?;
        let mut p = lock(state);
        p.add(i, pass, &film, stats, t.elapsed().as_secs_f64());
        error_now = p.error_95();
        (d.after_pass)(&p)?;
        drop(p);
        rendered += 1;
        next = d.set.next_after(Some(i));
        let elapsed = start.elapsed();
        let error = error_now.map_or(String::new(), |e| format!(", error ±{:.2} %", 100.0 * e.error));
        let done = match (d.budget, to_do) {
            (Some(b), _) => {
                let left = (b.limit.as_secs_f64() - elapsed.as_secs_f64()).max(0.0);
                progress.message(&format!("pass {}{error}, {left:.1} s left", i + 1));
                (elapsed.as_millis() as u64).min(total)
            }
            (None, None) => {
                progress.message(&format!("pass {}{error}, target ±{:.2} %", i + 1, 100.0 * target));
                // Not 100 % before the minimum of passes has run.
                let cap = if passes + 1 < crate::settings::MIN_PASSES_FOR_TARGET { 99.0 } else { 100.0 };
                error_now.map_or(0, |e| (100.0 * (target / e.error).powi(3)).min(cap) as u64)
            }
            (None, Some(n)) => {
                progress.message(&format!("pass {} ({rendered} of {n}){error}", i + 1));
                u64::from(rendered)
            }
        };
        progress.advance(done - shown.min(done));
        shown = shown.max(done);
    };
    progress.finish();
    Ok(ended)
}

/// The finished film and stats of `p`: the mean image, the diagnostic layers of its last pass
/// (when asked for and `diagnostics` is true), and the progressive stats; `start` is when the
/// budget (or the render) started counting. The caller sets `times.total_s`.
#[must_use]
pub fn finish(
    p: &Progressive,
    scene: &Arc<Scene>,
    rays: &CameraRays,
    budget: Option<Budget>,
    start: Instant,
    diagnostics: bool,
) -> (Film, RenderStats) {
    let mut film = p.image();
    let mut stats = p.stats.clone();
    if let (Some(last), true) = (&p.last, diagnostics) {
        crate::diagnostics::add_layers(scene, rays, last, &mut film, &mut stats);
    }
    let settings = &p.job().settings;
    let target = settings.target_error;
    let spp = settings.spp;
    let error_95 = p.error_95();
    let mut prog = p.progress.clone();
    prog.budget_s = budget.map(|b| b.limit.as_secs_f64());
    prog.elapsed_s = start.elapsed().as_secs_f64();
    prog.error_95 = error_95;
    prog.target_error = (target > 0.0).then_some(target);
    stats.phases.push(format!("{} progressive passes", prog.passes));
    stats.spp = spp * prog.passes;
    stats.progressive = Some(prog);
    stats.mean_rgb = film.mean().to_array();
    (film, stats)
}

/// Progressive passes of `job` (its settings per pass), each rendered by `run` given the pass's
/// job: `settings.passes` of them, or with a budget until it is spent, or with an error target
/// until it is met ([`drive`] over [`default_set`]).
pub fn render_passes(
    scene: &Arc<Scene>,
    rays: &CameraRays,
    job: &Job,
    run: &dyn Fn(&Job) -> Result<(Film, RenderStats)>,
    budget: Option<Budget>,
    progress: &dyn Progress,
) -> Result<(Film, RenderStats)> {
    let t = Instant::now();
    let state = Mutex::new(Progressive::new(scene, rays, job));
    let d = Drive { set: default_set(&job.settings, budget), budget, stop: &|| false, after_pass: &mut |_| Ok(()) };
    drive(&state, run, d, progress)?;
    let p = state.into_inner().unwrap_or_else(std::sync::PoisonError::into_inner);
    let (film, mut stats) = finish(&p, scene, rays, budget, budget.map_or(t, |b| b.start), true);
    stats.times.total_s = t.elapsed().as_secs_f64();
    Ok((film, stats))
}

/// The passes an undivided render runs: `settings.passes` of them, or — with a time budget, or
/// an error target and no pass count — as many as it takes.
#[must_use]
pub fn default_set(settings: &crate::settings::Settings, budget: Option<Budget>) -> PassSet {
    if budget.is_some() || (settings.target_error > 0.0 && settings.passes == 1) {
        PassSet::unbounded()
    } else {
        PassSet::first(settings.passes)
    }
}
