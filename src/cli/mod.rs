//! The command line's pieces: one module per command ([`render`] with its progressive path
//! [`passes`] and signal watch [`interrupt`], [`merge`], [`bench`], [`compare`], [`sweep`]),
//! the progress bars ([`bars`]), and the parsers and printing they share.

pub mod bars;
pub mod bench;
pub mod compare;
pub mod interrupt;
pub mod merge;
pub mod passes;
pub mod render;
pub mod sweep;

use glam::Vec3;

/// Parses a duration such as `30s`, `500ms`, `2m` or `1h` (a bare number is seconds).
pub fn parse_duration(s: &str) -> std::result::Result<std::time::Duration, String> {
    let t = s.trim();
    // The unit is the trailing run of letters, so that `1e9s` reads as 1e9 seconds.
    let at = t.trim_end_matches(|c: char| c.is_ascii_alphabetic()).len();
    let (num, unit) = if at == t.len() { (t, "s") } else { t.split_at(at) };
    let scale = match unit {
        "ms" => 1e-3,
        "s" => 1.0,
        "m" | "min" => 60.0,
        "h" => 3600.0,
        _ => return Err(format!("unknown unit `{unit}` in `{s}` (ms, s, m, h)")),
    };
    let v: f64 = num.trim().parse().map_err(|_| format!("`{s}` is not a duration such as 30s, 500ms or 2m"))?;
    let secs = v * scale;
    if !(secs > 0.0 && secs <= 1e7) {
        return Err(format!(
            "`{s}`: a budget must be positive and at most 10 000 000 s (about 115 days), the largest accepted"
        ));
    }
    Ok(std::time::Duration::from_secs_f64(secs))
}

/// Parses `X,Y,Z` (finite numbers).
pub fn parse_vec3(s: &str) -> std::result::Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(format!("expected X,Y,Z, got `{s}`"));
    }
    let mut v = [0.0f32; 3];
    for (i, p) in parts.iter().enumerate() {
        v[i] = p.trim().parse().map_err(|_| format!("`{p}` is not a number"))?;
        if !v[i].is_finite() {
            return Err(format!("`{p}` is not finite"));
        }
    }
    Ok(Vec3::from_array(v))
}

/// `x` with three decimals, or in scientific notation outside [10⁻³, 10⁵) (scenes modelled
/// in micrometres or kilometres have light powers of any size).
pub fn significant(x: f32) -> String {
    if x == 0.0 || (1e-3..1e5).contains(&x.abs()) {
        format!("{x:.3}")
    } else {
        format!("{x:.3e}")
    }
}

/// What the CLI prints besides errors: nothing (`-q`), the plan, warnings and summary (the
/// default), or also the per-system table (`-v`).
#[derive(Clone, Copy)]
pub struct Say {
    /// `-q`: errors only.
    pub quiet: bool,
    /// `-v`: the per-system table too.
    pub verbose: bool,
}

impl Say {
    /// Prints `text` unless quiet.
    pub fn info(self, text: impl std::fmt::Display) {
        if !self.quiet {
            eprint!("{text}");
        }
    }
    /// Prints `text` as a warning unless quiet.
    pub fn warn(self, text: impl std::fmt::Display) {
        self.info(format!("warning: {text}\n"));
    }
}
