//! SIGINT and SIGTERM during a progressive render (Ctrl-C, a scheduler's time limit): reads the
//! signals and the render's state, writes the partial film of the passes finished. The first
//! signal asks the render to stop after the pass in progress; if that pass has not ended
//! [`GRACE`] later, or at a second signal (one more than a second after the first: a scheduler
//! may deliver the same SIGTERM to the job's shell, which forwards it, and to the renderer), the
//! pass is abandoned and the passes finished so far are written at once. Either way the partial
//! film is written and the process exits with 128 + the signal's number (130, 143), so that
//! nothing rendered is lost. Once the render has finished its passes and writes its own output, a
//! signal waits for that output and then ends the process as the signal's default action does.

use photonwave::error::Result;
use photonwave::progressive::Progressive;
use signal_hook::consts::{SIGINT, SIGTERM};
use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// How long the pass in progress may take to end after the first signal before it is abandoned.
/// Schedulers wait about 30 s between SIGTERM and SIGKILL (Slurm's KillWait default).
pub const GRACE: Duration = Duration::from_secs(10);

/// Writes the render's partial film (the passes finished so far).
pub type WritePartial = dyn Fn(&Progressive) -> Result<()> + Send + Sync;

/// The signal watch of one render.
pub struct Interrupt {
    /// The first signal's number, 0 before any.
    signal: Arc<AtomicI32>,
    /// Set by the render, under the render's lock, once it writes its own output: the watch then
    /// leaves the writing to it.
    finished: Arc<AtomicBool>,
}

impl Interrupt {
    /// Starts watching for SIGINT and SIGTERM. `state` is the render; `write` writes its partial
    /// film when a pass is abandoned.
    pub fn watch(state: Arc<Mutex<Progressive>>, write: Arc<WritePartial>) -> std::io::Result<Self> {
        let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM])?;
        let signal = Arc::new(AtomicI32::new(0));
        let finished = Arc::new(AtomicBool::new(false));
        let (sig, fin) = (signal.clone(), finished.clone());
        std::thread::spawn(move || {
            let mut first: Option<std::time::Instant> = None;
            for s in signals.forever() {
                if fin.load(Ordering::SeqCst) {
                    // The render writes its output under the lock: let it end, then die.
                    drop(state.lock().unwrap_or_else(std::sync::PoisonError::into_inner));
                    let _ = signal_hook::low_level::emulate_default_handler(s);
                    std::process::exit(128 + s);
                }
                match first {
                    // The same signal delivered twice at once (shell and process): one request.
                    Some(t) if t.elapsed() < Duration::from_secs(1) => {}
                    Some(_) => abandon(&state, &*write, &fin, sig.load(Ordering::SeqCst)),
                    None => {
                        first = Some(std::time::Instant::now());
                        sig.store(s, Ordering::SeqCst);
                        eprintln!(
                            "\n{}: stopping after the pass in progress (at most {} s more; signal again to stop now)",
                            name(s),
                            GRACE.as_secs()
                        );
                        let (state, write, fin) = (state.clone(), write.clone(), fin.clone());
                        std::thread::spawn(move || {
                            std::thread::sleep(GRACE);
                            abandon(&state, &*write, &fin, s);
                        });
                    }
                }
            }
        });
        Ok(Interrupt { signal, finished })
    }

    /// Whether a signal asked the render to stop.
    #[must_use]
    pub fn stopping(&self) -> bool {
        self.signal.load(Ordering::SeqCst) != 0
    }

    /// The first signal's number, if any came.
    #[must_use]
    pub fn signal(&self) -> Option<i32> {
        Some(self.signal.load(Ordering::SeqCst)).filter(|&s| s != 0)
    }

    /// Marks the render as writing its own output (call with the render's lock held): from here
    /// on a signal waits for the lock to be released, then ends the process.
    pub fn finish(&self) {
        self.finished.store(true, Ordering::SeqCst);
    }
}

/// The signal's name.
fn name(s: i32) -> &'static str {
    if s == SIGINT {
        "SIGINT"
    } else {
        "SIGTERM"
    }
}

/// Abandons the pass in progress: writes the passes finished so far and exits with 128 + `s`,
/// unless the render has already finished and writes its output itself.
fn abandon(state: &Mutex<Progressive>, write: &WritePartial, finished: &AtomicBool, s: i32) {
    let p = state.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    if finished.load(Ordering::SeqCst) {
        return;
    }
    eprintln!("{}: abandoning the pass in progress; writing the {} passes finished", name(s), p.passes());
    match write(&p) {
        Ok(()) => std::process::exit(128 + s),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1)
        }
    }
}
