//! `photonwave sweep`: renders a scene over a grid of settings, times each render and measures
//! its error against a reference; writes the CSV and the error-against-time plots.

use super::bars::Bars;
use super::parse_duration;
use photonwave::engine::Engine;
use photonwave::error::{Error, Result};
use photonwave::files::{check_outputs, Output};
use photonwave::formats::load_scene;
use photonwave::job::Job;
use photonwave::scene::camera::fitted_camera;
use photonwave::settings::{Overrides, Preset};
use std::path::PathBuf;

/// Flags of `sweep`.
#[derive(clap::Args)]
pub struct SweepArgs {
    /// Scene file (.toml) or model (.obj with its .mtl, .ply, .gltf or .glb).
    pub scene: PathBuf,
    /// The reference image (.exr), e.g. from `render --preset reference`; the sweep renders at
    /// its size.
    #[arg(long)]
    pub reference: PathBuf,
    /// A knob and its values, NAME=V1,V2,… (repeatable; the grid is every combination). Any
    /// setting but width, height and force: spp, photons, caustic_photons, k, caustic_k,
    /// global_radius, caustic_radius, kernel, gather_rays, final_gather, precompute_irradiance,
    /// secondary_gather, per_pixel_radii, passes, alpha, max_depth, light_samples, mis, seed, threads, code_path.
    #[arg(long = "knob", required = true)]
    pub knobs: Vec<photonwave::tools::sweep::Knob>,
    /// Equal-time mode: time budgets, e.g. `1s,4s,16s`; every configuration renders progressive
    /// passes for each budget, and the error it reaches is recorded.
    #[arg(long, value_delimiter = ',', value_parser = parse_duration)]
    pub time: Vec<std::time::Duration>,
    /// Output directory (created if missing).
    #[arg(short, long)]
    pub output: PathBuf,
    /// The layer whose RMSE the plots show: beauty, emitted, direct, specular, caustic or
    /// indirect (the CSV has them all).
    #[arg(long, default_value = "beauty")]
    pub layer: String,
    /// The error the plots show: `rmse`, or `relmse` ((a−b)²/(b²+0.01), which weighs dark
    /// regions as much as bright ones).
    #[arg(long, default_value = "rmse")]
    pub metric: photonwave::tools::sweep::Metric,
    /// Amounts of work the knobs start from (as `render --preset`) [the scene file's settings].
    #[arg(long)]
    pub preset: Option<Preset>,
    /// Engine for every render: wavefront, reference or path.
    #[arg(long, default_value = "wavefront")]
    pub engine: Engine,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Runs `sweep`.
pub fn run(args: SweepArgs) -> Result<()> {
    use photonwave::tools::sweep::Sweep;
    let reference = photonwave::tools::compare::read_finite_exr(&args.reference)?;
    let layer_key = if args.layer == "beauty" { "" } else { args.layer.as_str() };
    if !reference.layers.iter().any(|(n, _)| n == layer_key) {
        let names: Vec<&str> =
            reference.layers.iter().map(|(n, _)| if n.is_empty() { "beauty" } else { n.as_str() }).collect();
        return Err(Error::setting(
            "--layer",
            format!(
                "the reference {} has no layer `{}` (it has {})",
                args.reference.display(),
                args.layer,
                names.join(", ")
            ),
        ));
    }
    let loaded = load_scene(&args.scene)?;
    let mut inputs = loaded.inputs;
    inputs.push(args.reference.clone());
    let scene = std::sync::Arc::new(loaded.scene);
    // The reference fixes the size.
    let size = Overrides { width: Some(reference.width), height: Some(reference.height), ..Default::default() };
    let (base, given) = size.layer(loaded.settings, args.preset);
    let job = Job::new(&scene, &base)?;
    let sweep = Sweep::new(&base, given, args.knobs, args.time, args.engine)?;
    // The input is checked; the output folder now, before any render.
    std::fs::create_dir_all(&args.output).map_err(|e| Error::output(&args.output, e))?;
    let csv = args.output.join("sweep.csv");
    check_outputs(&[Output { flag: "--output", path: &csv, ext: "csv" }], &inputs)?;
    let camera = loaded.camera.unwrap_or_else(|| {
        fitted_camera(&scene, photonwave::scene::camera::DEFAULT_FOV, base.width as f32 / base.height as f32)
    });
    let rays = camera.prepare(base.width, base.height)?;

    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    eprint!("{}", job.plan.describe());
    let runs = sweep.configs.len() * sweep.budgets.len().max(1);
    eprintln!(
        "sweep: {} configuration(s){} = {runs} render(s) at {}×{}, {:?} engine, against {}",
        sweep.configs.len(),
        if sweep.budgets.is_empty() { String::new() } else { format!(" × {} budget(s)", sweep.budgets.len()) },
        base.width,
        base.height,
        args.engine,
        args.reference.display()
    );
    let bars = Bars::new(args.quiet);
    let rows = sweep.run(&scene, &rays, &reference, &bars)?;

    let metric = format!("{} {}", args.layer, args.metric.name());
    eprintln!("{:>4} {:<40} {:>9} {:>7} {:>10} {metric:>14}", "#", "configuration", "budget s", "passes", "seconds");
    for r in &rows {
        let err = r.errors.iter().find(|e| e.layer == args.layer).map_or(f64::NAN, |e| args.metric.of(e));
        eprintln!(
            "{:>4} {:<40} {:>9} {:>7} {:>10.3} {:>14.4e}",
            r.config,
            photonwave::tools::sweep::describe(&sweep.knobs, &r.values),
            r.budget_s.map_or("-".into(), |b| format!("{b:.2}")),
            r.passes,
            r.seconds,
            err
        );
    }
    photonwave::tools::sweep::write_csv(&csv, &sweep.knobs, &rows)?;
    eprintln!("wrote {}", csv.display());
    let name = args.scene.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    for (knob, fig) in sweep.figures(&rows, &args.layer, args.metric, &name) {
        for ext in ["svg", "png"] {
            let path = args.output.join(format!("{knob}.{ext}"));
            if ext == "svg" {
                photonwave::tools::plot::write_svg(&fig, &path)?;
            } else {
                photonwave::tools::plot::write_png(&fig, &path)?;
            }
            eprintln!("wrote {}", path.display());
        }
    }
    Ok(())
}
