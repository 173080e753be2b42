//! `photonwave sweep`: what accuracy costs in time. Renders one scene over a grid of settings
//! (every combination of the knobs' values — at each time budget, in equal-time mode), times
//! each render, measures the error of every layer against a reference image, and writes
//! `sweep.csv` and one log-log error-against-time plot per knob ([`crate::tools::plot`]).
//!
//! A knob is any field of [`Settings`] but the image size (the reference fixes it) and `force`;
//! its values are parsed as the field's own type, so `kernel=box,cone` and `final_gather=true,false`
//! work as `k=16,64` does. Every configuration renders with the same seed (unless `seed` is a
//! knob), so rows differ by their settings and not by their random numbers, and each is what
//! `photonwave render` gives with the same settings and flags.

use crate::engine::{Budget, Engine};
use crate::error::{Error, Result};
use crate::film::ExrLayers;
use crate::progress::{NoProgress, Progress};
use crate::progressive::{per_pass, PerPass};
use crate::scene::camera::CameraRays;
use crate::scene::Scene;
use crate::settings::Settings;
use crate::tools::compare::{layer_errors, LayerError};
use crate::tools::plot::{Figure, Line, PointGroup};
use serde::Deserialize;
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Settings fields a sweep cannot vary: the size is the reference's, `force` is a list.
pub const FIXED_FIELDS: [&str; 3] = ["width", "height", "force"];

/// Renders in one sweep at the most (configurations × budgets).
pub const MAX_RUNS: usize = 10_000;

/// One knob and the values it takes: `NAME=V1,V2,…` on the command line.
#[derive(Clone, Debug, PartialEq)]
pub struct Knob {
    /// A [`Settings`] field.
    pub name: String,
    /// Its values, as written (parsed when the grid is built).
    pub values: Vec<String>,
}

impl std::str::FromStr for Knob {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let (name, values) =
            s.split_once('=').ok_or_else(|| format!("`{s}`: a knob is NAME=V1,V2,… (e.g. k=16,32,64)"))?;
        let name = name.trim().to_string();
        let values: Vec<String> = values.split(',').map(|v| v.trim().to_string()).collect();
        if name.is_empty() || values.iter().any(String::is_empty) {
            return Err(format!("`{s}`: a knob is NAME=V1,V2,… with no empty name or value"));
        }
        Ok(Knob { name, values })
    }
}

/// The settings as a TOML table (every field, by its name in scene files).
fn table(settings: &Settings) -> Result<toml::Table> {
    // Only a value TOML cannot hold (a seed above 2⁶³ − 1) fails here.
    toml::Table::try_from(settings).map_err(|e| Error::setting("seed", e.to_string()))
}

/// The names of every knob a sweep can vary, sorted.
#[must_use]
pub fn knob_names() -> Vec<String> {
    table(&Settings::default())
        .map(|t| t.keys().filter(|k| !FIXED_FIELDS.contains(&k.as_str())).cloned().collect())
        .unwrap_or_default()
}

/// `settings` with knob `name` set to `value`, parsed as that field's type.
pub fn set_knob(settings: &Settings, name: &str, value: &str) -> Result<Settings> {
    if FIXED_FIELDS.contains(&name) {
        return Err(Error::setting(
            name,
            "cannot be swept: the image size is the reference's, and `force` is a list (set it in the scene file)",
        ));
    }
    let mut t = table(settings)?;
    let bad = |what: &str| Error::setting(name, format!("`{value}` is not {what}"));
    let parsed = match t.get(name) {
        None => {
            return Err(Error::setting(name, format!("no such knob (one of {})", knob_names().join(", "))));
        }
        Some(toml::Value::Integer(_)) => toml::Value::Integer(value.parse().map_err(|_| bad("a whole number"))?),
        Some(toml::Value::Float(_)) => toml::Value::Float(value.parse().map_err(|_| bad("a number"))?),
        Some(toml::Value::Boolean(_)) => toml::Value::Boolean(value.parse().map_err(|_| bad("true or false"))?),
        Some(_) => toml::Value::String(value.to_string()),
    };
    t.insert(name.to_string(), parsed);
    let s = Settings::deserialize(toml::Value::Table(t)).map_err(|e| Error::setting(name, e.message().to_string()))?;
    s.validate()?;
    Ok(s)
}

/// One point of the grid: a value per knob and the settings they make.
#[derive(Clone, Debug)]
pub struct Config {
    /// One value per knob, in knob order.
    pub values: Vec<String>,
    /// The base settings with those values set (per pass, for progressive renders).
    pub settings: Settings,
}

/// Every combination of the knobs' values over `base` (the first knob varies slowest). Each
/// configuration is validated; a progressive one gets per-pass amounts as `render --passes`
/// would, with the amounts in `given` (e.g. a preset's) and the knobs among `spp`, `photons`
/// and `caustic_photons` taken per pass.
pub fn grid(base: &Settings, given: PerPass, knobs: &[Knob], budgets: &[Duration]) -> Result<Vec<Config>> {
    for (i, k) in knobs.iter().enumerate() {
        if knobs[..i].iter().any(|o| o.name == k.name) {
            return Err(Error::setting(&k.name, "given twice: list all its values in one --knob"));
        }
        if !budgets.is_empty() && k.name == "passes" {
            return Err(Error::setting("passes", "cannot be a knob with --time: the budget decides the passes"));
        }
    }
    let runs = knobs.iter().try_fold(budgets.len().max(1), |n, k| n.checked_mul(k.values.len()));
    if runs.is_none_or(|n| n > MAX_RUNS) {
        return Err(Error::setting("--knob", format!("the grid has more than {MAX_RUNS} renders")));
    }
    let given = given
        | PerPass {
            spp: knobs.iter().any(|k| k.name == "spp"),
            photons: knobs.iter().any(|k| k.name == "photons"),
            caustic_photons: knobs.iter().any(|k| k.name == "caustic_photons"),
        };
    let mut configs = vec![Config { values: Vec::new(), settings: base.clone() }];
    for k in knobs {
        let mut next = Vec::with_capacity(configs.len() * k.values.len());
        for c in &configs {
            for v in &k.values {
                let mut values = c.values.clone();
                values.push(v.clone());
                next.push(Config { values, settings: set_knob(&c.settings, &k.name, v)? });
            }
        }
        configs = next;
    }
    for c in &mut configs {
        if c.settings.passes > 1 || c.settings.target_error > 0.0 || !budgets.is_empty() {
            c.settings = per_pass(&c.settings, given);
        }
    }
    Ok(configs)
}

/// The error a plot shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Metric {
    /// √(mean (a − b)²): absolute, dominated by bright pixels.
    #[default]
    Rmse,
    /// mean (a − b)² / (b² + 0.01): relative, so dark regions count as much as bright ones.
    Relmse,
}

impl Metric {
    /// The metric's value in `e`.
    #[must_use]
    pub fn of(self, e: &LayerError) -> f64 {
        match self {
            Metric::Rmse => e.rmse,
            Metric::Relmse => e.rel_mse,
        }
    }
    /// Its name in plots.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Metric::Rmse => "RMSE",
            Metric::Relmse => "relMSE",
        }
    }
}

/// One render of the sweep.
#[derive(Clone, Debug)]
pub struct Row {
    /// Index into the grid.
    pub config: usize,
    /// The knobs' values.
    pub values: Vec<String>,
    /// The time budget, in equal-time mode.
    pub budget_s: Option<f64>,
    /// Passes rendered.
    pub passes: u32,
    /// Samples per pixel over all passes.
    pub spp: u32,
    /// Wall time of the render (photon passes, maps and camera pass; the scene is loaded once
    /// before the sweep).
    pub seconds: f64,
    /// Error of each layer against the reference: beauty first, then the terms.
    pub errors: Vec<LayerError>,
}

/// A sweep: the grid, the budgets and the engine.
#[derive(Clone, Debug)]
pub struct Sweep {
    /// The knobs, in the order given.
    pub knobs: Vec<Knob>,
    /// Every combination of their values ([`grid`]).
    pub configs: Vec<Config>,
    /// Time budgets (equal-time mode); empty for one render per configuration.
    pub budgets: Vec<Duration>,
    /// The engine every configuration renders with.
    pub engine: Engine,
}

impl Sweep {
    /// The sweep of `knobs` over `base` (with the per-pass amounts `given`, see [`grid`]),
    /// validated before anything renders.
    pub fn new(
        base: &Settings,
        given: PerPass,
        knobs: Vec<Knob>,
        budgets: Vec<Duration>,
        engine: Engine,
    ) -> Result<Self> {
        let configs = grid(base, given, &knobs, &budgets)?;
        if engine == Engine::Path
            && (!budgets.is_empty() || configs.iter().any(|c| c.settings.passes > 1 || c.settings.target_error > 0.0))
        {
            return Err(Error::setting(
                "--engine",
                "progressive passes (--time, passes, target_error) need a photon-mapping engine",
            ));
        }
        Ok(Sweep { knobs, configs, budgets, engine })
    }

    /// Renders every configuration (at every budget, when there are budgets) and measures it
    /// against `reference`, which must be the size of `rays`. `progress` sees one bar over the
    /// renders, with the configuration as its message.
    pub fn run(
        &self,
        scene: &Arc<Scene>,
        rays: &CameraRays,
        reference: &ExrLayers,
        progress: &dyn Progress,
    ) -> Result<Vec<Row>> {
        let limits: Vec<Option<Duration>> =
            if self.budgets.is_empty() { vec![None] } else { self.budgets.iter().copied().map(Some).collect() };
        progress.start("sweep", (limits.len() * self.configs.len()) as u64);
        let mut rows = Vec::with_capacity(limits.len() * self.configs.len());
        for limit in &limits {
            for (i, c) in self.configs.iter().enumerate() {
                let label = describe(&self.knobs, &c.values);
                progress.message(&match limit {
                    Some(l) => format!("{label} for {:.2} s", l.as_secs_f64()),
                    None => label,
                });
                let start = Instant::now();
                let budget = limit.map(|limit| Budget { limit, start });
                let (film, stats) = crate::engine::render(scene, rays, &c.settings, self.engine, budget, &NoProgress)?;
                let seconds = start.elapsed().as_secs_f64();
                rows.push(Row {
                    config: i,
                    values: c.values.clone(),
                    budget_s: limit.map(|l| l.as_secs_f64()),
                    passes: stats.progressive.as_ref().map_or(1, |p| p.passes),
                    spp: stats.spp,
                    seconds,
                    errors: layer_errors(&film.layers(), &reference.layers),
                });
                progress.advance(1);
            }
        }
        progress.finish();
        Ok(rows)
    }

    /// One figure per knob with two or more values (per knob in equal-time mode): `layer`'s error against wall time, log-log,
    /// points coloured by the knob's value. Without budgets, lines join the renders that differ
    /// only in this knob; in equal-time mode, each configuration's renders across the budgets.
    /// Rows whose error or time is not positive cannot be drawn on log axes and are left out.
    #[must_use]
    pub fn figures(&self, rows: &[Row], layer: &str, metric: Metric, scene: &str) -> Vec<(String, Figure)> {
        let mut figures = Vec::new();
        for (j, knob) in self.knobs.iter().enumerate() {
            if knob.values.len() < 2 && self.budgets.is_empty() {
                continue;
            }
            let point = |r: &Row| {
                let e = metric.of(r.errors.iter().find(|e| e.layer == layer)?);
                (e > 0.0 && r.seconds > 0.0).then_some((r.seconds, e))
            };
            let colour_of = |r: &Row| knob.values.iter().position(|v| *v == r.values[j]).unwrap_or(0);
            // Lines: rows that share everything but this knob (one render each), or one
            // configuration's rows across budgets.
            let mut groups: Vec<(Vec<String>, Vec<&Row>)> = Vec::new();
            for r in rows {
                let key: Vec<String> = if self.budgets.is_empty() {
                    r.values.iter().enumerate().filter(|&(i, _)| i != j).map(|(_, v)| v.clone()).collect()
                } else {
                    vec![r.config.to_string()]
                };
                match groups.iter_mut().find(|g| g.0 == key) {
                    Some(g) => g.1.push(r),
                    None => groups.push((key, vec![r])),
                }
            }
            let mut lines = Vec::new();
            for (_, mut members) in groups {
                if self.budgets.is_empty() {
                    members.sort_by_key(|r| colour_of(r));
                } else {
                    members.sort_by(|a, b| a.seconds.total_cmp(&b.seconds));
                }
                let colour = (!self.budgets.is_empty()).then(|| colour_of(members[0]));
                let points: Vec<(f64, f64)> = members.iter().filter_map(|r| point(r)).collect();
                if points.len() > 1 {
                    lines.push(Line { colour, points });
                }
            }
            let groups: Vec<PointGroup> = knob
                .values
                .iter()
                .enumerate()
                .map(|(c, v)| PointGroup {
                    label: format!("{} = {v}", knob.name),
                    colour: c,
                    points: rows.iter().filter(|r| colour_of(r) == c).filter_map(&point).collect(),
                })
                .collect();
            if groups.iter().all(|g| g.points.is_empty()) {
                continue;
            }
            let what = if self.budgets.is_empty() { "error against time" } else { "error at equal time" };
            figures.push((
                knob.name.clone(),
                Figure {
                    title: format!("{scene}: {layer} {what}, by {}", knob.name),
                    x_label: "render time (s)".into(),
                    y_label: format!("{layer} {} against the reference", metric.name()),
                    lines,
                    groups,
                },
            ));
        }
        figures
    }
}

/// `k=32 kernel=box`.
#[must_use]
pub fn describe(knobs: &[Knob], values: &[String]) -> String {
    knobs.iter().zip(values).map(|(k, v)| format!("{}={v}", k.name)).collect::<Vec<_>>().join(" ")
}

/// Quotes a CSV field if it needs it.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The CSV text: one row per render — configuration index, each knob's value, budget (empty
/// without one), passes and samples per pixel rendered, wall seconds, then RMSE, relMSE and
/// mean ratio per layer.
#[must_use]
pub fn csv(knobs: &[Knob], rows: &[Row]) -> String {
    let layers: Vec<&str> = rows.first().map_or(Vec::new(), |r| r.errors.iter().map(|e| e.layer.as_str()).collect());
    let mut head: Vec<String> = vec!["config".into()];
    head.extend(knobs.iter().map(|k| csv_field(&k.name)));
    head.extend(["budget_s", "passes_rendered", "spp_rendered", "seconds"].map(String::from));
    for l in &layers {
        head.extend([format!("{l}_rmse"), format!("{l}_relmse"), format!("{l}_mean_ratio")]);
    }
    let mut out = head.join(",") + "\n";
    for r in rows {
        let mut f: Vec<String> = vec![r.config.to_string()];
        f.extend(r.values.iter().map(|v| csv_field(v)));
        f.push(r.budget_s.map_or(String::new(), |b| format!("{b}")));
        f.extend([r.passes.to_string(), r.spp.to_string(), format!("{:.6}", r.seconds)]);
        for e in &r.errors {
            f.extend([
                format!("{:.6e}", e.rmse),
                format!("{:.6e}", e.rel_mse),
                e.mean_ratio.map_or(String::new(), |m| format!("{m:.6}")),
            ]);
        }
        out += &(f.join(",") + "\n");
    }
    out
}

/// Writes [`csv`] to `path`.
pub fn write_csv(path: &Path, knobs: &[Knob], rows: &[Row]) -> Result<()> {
    crate::files::write_bytes(path, csv(knobs, rows).as_bytes())
}
