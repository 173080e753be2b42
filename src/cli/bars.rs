//! Progress bars on stderr for the library's [`Progress`] hooks.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use photonwave::progress::Progress;
use std::sync::Mutex;

/// indicatif progress bars on stderr, one per phase.
pub struct Bars {
    bar: Mutex<Option<ProgressBar>>,
    quiet: bool,
}

impl Bars {
    /// Bars on stderr; none when `quiet` or when stderr is not a terminal.
    pub fn new(quiet: bool) -> Self {
        Bars { bar: Mutex::new(None), quiet: quiet || !std::io::IsTerminal::is_terminal(&std::io::stderr()) }
    }
}

impl Progress for Bars {
    fn start(&self, phase: &str, total: u64) {
        if self.quiet {
            return;
        }
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
        bar.set_style(
            ProgressStyle::with_template("{prefix:>16} [{bar:40}] {pos}/{len} ({elapsed}, eta {eta}) {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        bar.set_prefix(phase.to_string());
        *self.bar.lock().unwrap_or_else(|e| e.into_inner()) = Some(bar);
    }
    fn advance(&self, n: u64) {
        if let Some(b) = &*self.bar.lock().unwrap_or_else(|e| e.into_inner()) {
            b.inc(n);
        }
    }
    fn message(&self, text: &str) {
        if let Some(b) = &*self.bar.lock().unwrap_or_else(|e| e.into_inner()) {
            b.set_message(text.to_string());
        }
    }
    fn finish(&self) {
        if let Some(b) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).take() {
            b.finish();
        }
    }
}
