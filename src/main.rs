//! The photonwave command line: `photonwave render SCENE [flags]`.

use clap::{Parser, Subcommand};
use glam::Vec3;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use photonwave::effects::Effects;
use photonwave::engine::{Budget, Engine};
use photonwave::error::{Error, Result};
use photonwave::files::{check_outputs, Output};
use photonwave::progress::Progress;
use photonwave::progressive::PerPass;
use photonwave::scene::file::{fitted_camera, fitted_camera_to, load_scene, load_scene_lit};
use photonwave::scene::{Camera, Light, LightPreset};
use photonwave::settings::{Kernel, Preset};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Mutex;
use std::time::Instant;

#[derive(Parser)]
#[command(name = "photonwave", version, about = "A photon-mapping renderer (Jensen 1996)")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene (.toml scene file or bare .obj) to a multi-layer EXR.
    Render(Box<RenderArgs>),
    /// Throughput of the SIMD kernels against their baselines on identical rays and queries:
    /// packet vs obvhs single-ray traversal, SIMD vs scalar density estimates.
    Bench(BenchArgs),
    /// Error of an image against a reference (both EXRs written by `render`): RMSE, relMSE
    /// ((a−b)²/(b²+0.01)) and mean ratio for the beauty image and each term layer in both.
    Compare(CompareArgs),
    /// What accuracy costs in time: render a scene over a grid of settings, time each render and
    /// measure its error against a reference; writes DIR/sweep.csv and a log-log
    /// error-against-time plot per knob (DIR/KNOB.svg and .png).
    Sweep(Box<SweepArgs>),
}

#[derive(clap::Args)]
struct SweepArgs {
    /// Scene file (.toml) or mesh (.obj with its .mtl).
    scene: PathBuf,
    /// The reference image (.exr), e.g. from `render --preset reference`; the sweep renders at
    /// its size.
    #[arg(long)]
    reference: PathBuf,
    /// A knob and its values, NAME=V1,V2,… (repeatable; the grid is every combination). Any
    /// setting but width, height and force: spp, photons, caustic_photons, k, caustic_k,
    /// global_radius, caustic_radius, kernel, gather_rays, final_gather, precompute_irradiance,
    /// per_pixel_radii, passes, alpha, max_depth, light_samples, seed, threads, kernels.
    #[arg(long = "knob", required = true)]
    knobs: Vec<photonwave::sweep::Knob>,
    /// Equal-time mode: time budgets, e.g. `1s,4s,16s`; every configuration renders progressive
    /// passes for each budget, and the error it reaches is recorded.
    #[arg(long, value_delimiter = ',', value_parser = parse_duration)]
    time: Vec<std::time::Duration>,
    /// Output directory (created if missing).
    #[arg(short, long)]
    output: PathBuf,
    /// The layer whose RMSE the plots show: beauty, emitted, direct, specular, caustic or
    /// indirect (the CSV has them all).
    #[arg(long, default_value = "beauty")]
    layer: String,
    /// The error the plots show: `rmse`, or `relmse` ((a−b)²/(b²+0.01), which weighs dark
    /// regions as much as bright ones).
    #[arg(long, default_value = "rmse")]
    metric: photonwave::sweep::Metric,
    /// Amounts of work the knobs start from (as `render --preset`) [the scene file's settings].
    #[arg(long)]
    preset: Option<Preset>,
    /// Engine for every render: wavefront, reference or path.
    #[arg(long, default_value = "wavefront")]
    engine: Engine,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(clap::Args)]
struct CompareArgs {
    /// The image to measure (.exr).
    image: PathBuf,
    /// The reference image (.exr), e.g. a long progressive render.
    reference: PathBuf,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
}

#[derive(clap::Args)]
struct BenchArgs {
    /// Scenes (.toml or .obj), or `generated:sphere` for the built-in displaced sphere
    /// (~1 M triangles). Default: the bundled Cornell boxes and the generated sphere.
    scenes: Vec<String>,
    /// Print one JSON object instead of tables.
    #[arg(long)]
    json: bool,
    /// Worker threads for every kernel, 0 = all cores [1].
    #[arg(long, default_value_t = 1)]
    threads: u32,
    /// Timed repetitions of each kernel (alternating with its baseline; medians reported).
    #[arg(long, default_value_t = 5)]
    reps: u32,
    /// Camera position X,Y,Z for scenes without a camera [fitted to the scene bounds].
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    eye: Option<Vec3>,
    /// Camera target X,Y,Z for scenes without a camera.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    target: Option<Vec3>,
    /// Vertical field of view in degrees for scenes without a camera [40].
    #[arg(long)]
    fov: Option<f32>,
    /// Also time packet traversal at each single-ray hand-over threshold (0–4 lanes).
    #[arg(long)]
    thin_sweep: bool,
    /// Sphere rings of `generated:sphere` (2·rings·2·rings triangles) [512].
    #[arg(long, default_value_t = 512)]
    rings: u32,
}

fn parse_duration(s: &str) -> std::result::Result<std::time::Duration, String> {
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

fn parse_vec3(s: &str) -> std::result::Result<Vec3, String> {
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

#[derive(clap::Args)]
struct RenderArgs {
    /// Scene file (.toml) or mesh (.obj with its .mtl).
    scene: PathBuf,
    /// Output EXR (beauty as the default layer, one layer per term).
    #[arg(short, long, default_value = "out.exr")]
    output: PathBuf,
    /// Image width in pixels [scene file, else 320].
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels [scene file, else 320].
    #[arg(long)]
    height: Option<u32>,
    /// Camera position X,Y,Z [scene file, else fitted to the scene bounds].
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    eye: Option<Vec3>,
    /// Point the camera looks at X,Y,Z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    target: Option<Vec3>,
    /// Camera up direction X,Y,Z [0,1,0].
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    up: Option<Vec3>,
    /// Vertical field of view in degrees [scene file, else 40].
    #[arg(long)]
    fov: Option<f32>,
    /// Jittered samples per pixel [16].
    #[arg(long)]
    spp: Option<u32>,
    /// Photons to store in the global map [200000].
    #[arg(long)]
    photons: Option<u32>,
    /// Photons to store in the caustic map [100000].
    #[arg(long)]
    caustic_photons: Option<u32>,
    /// Nearest photons per estimate, both maps [global 64, caustic 48].
    #[arg(long)]
    k: Option<u32>,
    /// Density-estimation kernel: box, cone, epanechnikov [cone].
    #[arg(long)]
    kernel: Option<Kernel>,
    /// BVH traversal and photon lookups: `simd` (8-wide packets) or `scalar` (their scalar twins,
    /// for checking) [simd].
    #[arg(long)]
    kernels: Option<photonwave::kernels::KernelSet>,
    /// Final-gather rays per camera sample [16].
    #[arg(long)]
    gather_rays: Option<u32>,
    /// Read the global map directly at the first diffuse hit instead of final gathering.
    #[arg(long)]
    no_final_gather: bool,
    /// Count only photons visible from each estimate's point (no light through thin walls; one
    /// short occlusion ray per candidate photon) [off, or the scene file's `visibility`].
    #[arg(long)]
    visibility: bool,
    /// Force a part of the effects plan on even where the scene does not need it (repeatable):
    /// caustic_map, global_map, final_gather, refraction, shadow_rays.
    #[arg(long)]
    force: Vec<String>,
    /// Progressive passes: each traces fresh photons and estimates with fixed radii that shrink
    /// pass by pass (α); the image is their mean [1 = one k-nearest-neighbour render].
    #[arg(long)]
    passes: Option<u32>,
    /// Time budget, e.g. `30s`, `500ms`, `2m`: progressive passes until it is spent, ending
    /// within 5 % of it (counted from the start, scene loading included).
    #[arg(long, value_parser = parse_duration)]
    time: Option<std::time::Duration>,
    /// Radius reduction of progressive passes, r²ᵢ₊₁ = r²ᵢ·(i+α)/(i+1) [0.6667].
    #[arg(long)]
    alpha: Option<f32>,
    /// Longest photon path / specular chain [10].
    #[arg(long)]
    max_depth: Option<u32>,
    /// Seed of all random streams [1].
    #[arg(long)]
    seed: Option<u64>,
    /// Worker threads, 0 = all cores [0].
    #[arg(long)]
    threads: Option<u32>,
    /// Write the summary as JSON to this file.
    #[arg(long)]
    stats: Option<PathBuf>,
    /// Write a tone-mapped PNG preview to this file.
    #[arg(long)]
    png: Option<PathBuf>,
    /// Engine: `wavefront` (bevy_ecs stages over SoA queues), `reference` (scalar photon mapper)
    /// or `path` (unbiased path tracer, for validation).
    #[arg(long, default_value = "wavefront")]
    engine: Engine,
    /// Amounts of work (spp, photons, gather rays, passes) from a named preset, over the scene
    /// file's settings and under these flags: `preview`, `default`, or `reference` (a long
    /// progressive run to measure other renders against).
    #[arg(long)]
    preset: Option<Preset>,
    /// Add a light to the scene, placed from the camera (repeatable): `headlight` (a point light
    /// at the eye) or `sun` (a directional light from above and behind the camera). For meshes
    /// that bring no light, such as a bare OBJ from a model library.
    #[arg(long, value_enum)]
    light: Vec<LightPreset>,
    /// Print errors only: no plan, warnings, progress bars or summary.
    #[arg(long, short, conflicts_with = "verbose")]
    quiet: bool,
    /// Also print per-system runs, lanes and times (wavefront engine).
    #[arg(long, short)]
    verbose: bool,
}

/// indicatif progress bars on stderr, one per phase.
struct Bars {
    bar: Mutex<Option<ProgressBar>>,
    quiet: bool,
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

/// `x` with three decimals, or in scientific notation outside [10⁻³, 10⁵) (scenes modelled
/// in micrometres or kilometres have light powers of any size).
fn significant(x: f32) -> String {
    if x == 0.0 || (1e-3..1e5).contains(&x.abs()) {
        format!("{x:.3}")
    } else {
        format!("{x:.3e}")
    }
}

/// The camera a render uses: the scene file's, else one fitted to `bounds` for an image of
/// `aspect`, with the CLI's `--eye`, `--target`, `--up` and `--fov` over either.
fn view(args: &RenderArgs, file: Option<Camera>, bounds: (Vec3, Vec3), aspect: f32) -> Camera {
    let fov = args.fov.or(file.map(|c| c.fov_deg)).unwrap_or(40.0);
    let mut camera = file.unwrap_or_else(|| fitted_camera_to(bounds, fov, aspect));
    camera.fov_deg = fov;
    camera.eye = args.eye.unwrap_or(camera.eye);
    camera.target = args.target.unwrap_or(camera.target);
    camera.up = args.up.unwrap_or(camera.up);
    camera
}

/// What the CLI prints besides errors: nothing (`-q`), the plan, warnings and summary (the
/// default), or also the per-system table (`-v`).
#[derive(Clone, Copy)]
struct Say {
    quiet: bool,
    verbose: bool,
}

impl Say {
    fn info(self, text: impl std::fmt::Display) {
        if !self.quiet {
            eprint!("{text}");
        }
    }
    fn warn(self, text: impl std::fmt::Display) {
        self.info(format!("warning: {text}\n"));
    }
}

fn render(args: RenderArgs) -> Result<()> {
    let t0 = Instant::now();
    let say = Say { quiet: args.quiet, verbose: args.verbose };
    let mut outputs = vec![Output { flag: "--output", path: &args.output, ext: "exr" }];
    outputs.extend(args.png.as_deref().map(|path| Output { flag: "--png", path, ext: "png" }));
    outputs.extend(args.stats.as_deref().map(|path| Output { flag: "--stats", path, ext: "json" }));
    // Every output is checked before any work, and again against every file the scene read.
    check_outputs(&outputs, std::slice::from_ref(&args.scene))?;
    // `--light` presets are placed from the camera, which may be fitted to the meshes' bounds
    // for the image's aspect ratio (as the flags or the defaults give it: a scene file that sets
    // a size has a camera too).
    let default = photonwave::settings::Settings::default();
    let cli_aspect = args.width.unwrap_or(default.width) as f32 / args.height.unwrap_or(default.height).max(1) as f32;
    let added = |bounds: (Vec3, Vec3), file: Option<Camera>| -> Vec<Light> {
        let c = view(&args, file, bounds, cli_aspect);
        args.light.iter().map(|preset| preset.light(c.eye, c.target, c.up)).collect()
    };
    let loaded = load_scene_lit(&args.scene, &added)?;
    check_outputs(&outputs, &loaded.inputs)?;
    let scene = std::sync::Arc::new(loaded.scene);
    let mut settings = loaded.settings;
    let preset_per_pass = args.preset.map(|p| p.apply(&mut settings)).unwrap_or_default();
    macro_rules! set {
        ($($f:ident),*) => { $( if let Some(v) = args.$f { settings.$f = v; } )* };
    }
    set!(width, height, spp, photons, caustic_photons, gather_rays, max_depth, seed, threads, kernel, kernels);
    set!(passes, alpha);
    if let Some(k) = args.k {
        settings.k = k;
        settings.caustic_k = k;
    }
    settings.force.extend(args.force.iter().cloned());
    if args.no_final_gather {
        settings.final_gather = false;
    }
    settings.visibility |= args.visibility;
    settings.validate()?;
    let camera = view(&args, loaded.camera, scene.mesh_bounds(), settings.width as f32 / settings.height as f32);
    let rays = camera.prepare(settings.width, settings.height)?;
    let load_s = t0.elapsed().as_secs_f64();

    for w in &scene.warnings {
        say.warn(w);
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if settings.thread_count() > 2 * cores {
        say.warn(format!(
            "{} threads on {cores} cores: threads beyond the cores only add switching (measured 20× slower \
             at 1024 on 2 cores); 0 uses every core",
            settings.thread_count()
        ));
    }
    say.info(format!(
        "scene: {} triangles, {} materials, lights: {} ({} emissive triangles), total power {} W\n",
        scene.triangle_count(),
        scene.materials.len(),
        scene.lights.len(),
        scene.area_lights.len(),
        significant(scene.total_power().element_sum() / 3.0)
    ));
    if args.engine == Engine::Path {
        say.info(
            "plan: path tracing with next-event estimation — every term sampled from the camera; no photon maps\n",
        );
    } else {
        say.info(Effects::plan(&scene, &settings).describe());
    }
    let quiet = args.quiet || !std::io::IsTerminal::is_terminal(&std::io::stderr());
    let bars = Bars { bar: Mutex::new(None), quiet };
    let budget = args.time.map(|limit| Budget { limit, start: t0 });
    let settings = if photonwave::engine::is_progressive(&settings, budget) {
        let given = PerPass {
            spp: args.spp.is_some(),
            photons: args.photons.is_some(),
            caustic_photons: args.caustic_photons.is_some(),
        };
        let pass = photonwave::progressive::per_pass(&settings, given | preset_per_pass);
        if args.engine != Engine::Path {
            say.info(photonwave::progressive::describe(&scene, &pass, args.time));
        }
        pass
    } else {
        settings
    };
    let (film, mut stats) = photonwave::engine::render(&scene, &rays, &settings, args.engine, budget, &bars)?;
    if let Some(w) = stats.progressive.as_ref().and_then(photonwave::progressive::budget_warning) {
        say.warn(w);
    }
    if stats.progressive.is_none() {
        let short = [
            stats.global_map.shortfall("global", settings.photons.into()),
            stats.caustic_map.shortfall("caustic", settings.caustic_photons.into()),
        ];
        for w in short.into_iter().flatten() {
            say.warn(w);
        }
    }
    stats.scene = args.scene.display().to_string();
    stats.times.load_s = load_s;
    stats.times.total_s += load_s;

    film.write_exr(&args.output)?;
    say.info(format!("wrote {}\n", args.output.display()));
    if let Some(p) = &args.png {
        film.write_png(p)?;
        say.info(format!("wrote {}\n", p.display()));
    }
    say.info(stats.summary());
    if say.verbose {
        say.info(stats.stage_summary());
    }
    if let Some(p) = &args.stats {
        let json = serde_json::to_string_pretty(&stats).map_err(|e| Error::output(p, e))?;
        photonwave::files::write_bytes(p, json.as_bytes())?;
        say.info(format!("wrote {}\n", p.display()));
    }
    Ok(())
}

fn bench(args: BenchArgs) -> Result<()> {
    use photonwave::bench;
    use photonwave::scene::generated;
    if args.reps == 0 || args.reps > 1000 {
        return Err(Error::Setting { field: "--reps".into(), message: format!("{} is not in 1..=1000", args.reps) });
    }
    if !(2..=4096).contains(&args.rings) {
        return Err(Error::Setting { field: "--rings".into(), message: format!("{} is not in 2..=4096", args.rings) });
    }
    let threads = if args.threads == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    } else {
        args.threads as usize
    };
    let names = if args.scenes.is_empty() {
        let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes");
        vec![
            dir.join("cornell-box.toml").display().to_string(),
            dir.join("cornell-spheres.toml").display().to_string(),
            generated::SPHERE_NAME.to_string(),
        ]
    } else {
        args.scenes.clone()
    };
    let (cpu, flags, features) = bench::build_flags();
    if !args.json {
        eprintln!("build: target-cpu {cpu}; SIMD features {features:?}; RUSTFLAGS `{flags}`; {threads} thread(s)");
    }
    let mut report = bench::Report::new(threads);
    for name in &names {
        let loaded = if name == generated::SPHERE_NAME {
            generated::displaced_sphere(args.rings, 2 * args.rings)?
        } else {
            load_scene(std::path::Path::new(name))?
        };
        let label = std::path::Path::new(name).file_stem().map_or(name.clone(), |s| s.to_string_lossy().into_owned());
        let camera = loaded.camera.unwrap_or_else(|| {
            let mut c = fitted_camera(&loaded.scene, args.fov.unwrap_or(40.0), 1.0);
            if let Some(e) = args.eye {
                c.eye = e;
            }
            if let Some(t) = args.target {
                c.target = t;
            }
            c
        });
        let cam = camera.prepare(bench::SIDE, bench::SIDE)?;
        if !args.json {
            eprintln!("{label}: {} triangles", loaded.scene.triangle_count());
        }
        if args.thin_sweep {
            let sets = bench::RaySets::new(&loaded.scene, &cam);
            for (rays, query, thin, mrays) in
                bench::thin_sweep(&loaded.scene, &sets, &[0, 1, 2, 3, 4], args.reps as usize)
            {
                eprintln!("  hand-over at ≤{thin} lanes: {rays:<8} {query:<8} {mrays:>7.2} Mrays/s");
            }
        }
        let rows = bench::run_scene(&label, &loaded.scene, &cam, threads, args.reps as usize);
        if !args.json {
            eprint!("{}", bench::table(&rows.0, &rows.1));
        }
        report.add(rows);
    }
    if args.json {
        println!("{}", serde_json::to_string(&report).map_err(|e| Error::output(std::path::Path::new("stdout"), e))?);
    }
    Ok(())
}

fn compare(args: &CompareArgs) -> Result<()> {
    let c = photonwave::compare::compare_files(&args.image, &args.reference)?;
    if args.json {
        println!("{}", serde_json::to_string(&c).map_err(|e| Error::output(std::path::Path::new("stdout"), e))?);
    } else {
        print!("{}", c.table());
    }
    Ok(())
}

fn sweep(args: SweepArgs) -> Result<()> {
    use photonwave::sweep::Sweep;
    let reference = photonwave::compare::read_finite_exr(&args.reference)?;
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
    let mut base = loaded.settings;
    let given = args.preset.map(|p| p.apply(&mut base)).unwrap_or_default();
    (base.width, base.height) = (reference.width, reference.height);
    base.validate()?;
    let sweep = Sweep::new(&base, given, args.knobs, args.time, args.engine)?;
    // The input is checked; the output folder now, before any render.
    std::fs::create_dir_all(&args.output).map_err(|e| Error::output(&args.output, e))?;
    let csv = args.output.join("sweep.csv");
    check_outputs(&[Output { flag: "--output", path: &csv, ext: "csv" }], &inputs)?;
    let camera = loaded.camera.unwrap_or_else(|| fitted_camera(&scene, 40.0, base.width as f32 / base.height as f32));
    let rays = camera.prepare(base.width, base.height)?;

    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    eprint!("{}", Effects::plan(&scene, &base).describe());
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
    let quiet = args.quiet || !std::io::IsTerminal::is_terminal(&std::io::stderr());
    let bars = Bars { bar: Mutex::new(None), quiet };
    let rows = sweep.run(&scene, &rays, &reference, &bars)?;

    let metric = format!("{} {}", args.layer, args.metric.name());
    eprintln!("{:>4} {:<40} {:>9} {:>7} {:>10} {metric:>14}", "#", "configuration", "budget s", "passes", "seconds");
    for r in &rows {
        let err = r.errors.iter().find(|e| e.layer == args.layer).map_or(f64::NAN, |e| args.metric.of(e));
        eprintln!(
            "{:>4} {:<40} {:>9} {:>7} {:>10.3} {:>14.4e}",
            r.config,
            photonwave::sweep::describe(&sweep.knobs, &r.values),
            r.budget_s.map_or("-".into(), |b| format!("{b:.2}")),
            r.passes,
            r.seconds,
            err
        );
    }
    photonwave::sweep::write_csv(&csv, &sweep.knobs, &rows)?;
    eprintln!("wrote {}", csv.display());
    let name = args.scene.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    for (knob, fig) in sweep.figures(&rows, &args.layer, args.metric, &name) {
        for ext in ["svg", "png"] {
            let path = args.output.join(format!("{knob}.{ext}"));
            if ext == "svg" {
                photonwave::plot::write_svg(&fig, &path)?;
            } else {
                photonwave::plot::write_png(&fig, &path)?;
            }
            eprintln!("wrote {}", path.display());
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render(*args),
        Command::Bench(args) => bench(args),
        Command::Compare(args) => compare(&args),
        Command::Sweep(args) => sweep(*args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
