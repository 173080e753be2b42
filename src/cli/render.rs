//! `photonwave render SCENE`: loads a scene, layers the settings (scene file, preset, flags),
//! renders once or progressively, and writes the EXR, the PNG preview and the JSON stats.

use super::bars::Bars;
use super::passes::{PassFlags, Setup};
use super::{parse_duration, parse_vec3, significant, Say};
use glam::Vec3;
use photonwave::divided::partial::Identity;
use photonwave::engine::{Budget, Engine};
use photonwave::error::{Error, Result};
use photonwave::files::{check_outputs, Output};
use photonwave::formats::load_scene_lit;
use photonwave::job::Job;
use photonwave::scene::camera::fitted_camera_to;
use photonwave::scene::{Camera, Light, LightPreset};
use photonwave::settings::{Kernel, Overrides, Preset};
use std::path::PathBuf;
use std::time::Instant;

/// Flags of `render`.
#[derive(clap::Args)]
pub struct RenderArgs {
    /// Scene file (.toml) or model (.obj with its .mtl, .ply, .gltf or .glb).
    pub scene: PathBuf,
    /// Output EXR (beauty as the default layer, one layer per term).
    #[arg(short, long, default_value = "out.exr")]
    pub output: PathBuf,
    /// Image width in pixels [scene file, else 320].
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels [scene file, else 320].
    #[arg(long)]
    pub height: Option<u32>,
    /// Camera position X,Y,Z [scene file, else fitted to the scene bounds].
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub eye: Option<Vec3>,
    /// Point the camera looks at X,Y,Z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub target: Option<Vec3>,
    /// Camera up direction X,Y,Z [0,1,0].
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub up: Option<Vec3>,
    /// Vertical field of view in degrees [scene file, else 40].
    #[arg(long)]
    pub fov: Option<f32>,
    /// Jittered samples per pixel [16].
    #[arg(long)]
    pub spp: Option<u32>,
    /// Photons to store in the global map [200000].
    #[arg(long)]
    pub photons: Option<u32>,
    /// Photons to store in the caustic map [100000].
    #[arg(long)]
    pub caustic_photons: Option<u32>,
    /// Nearest photons per estimate, both maps [global 64, caustic 48].
    #[arg(long)]
    pub k: Option<u32>,
    /// Density-estimation kernel: box, cone, epanechnikov [cone].
    #[arg(long)]
    pub kernel: Option<Kernel>,
    /// BVH traversal and photon lookups: `simd` (8-wide packets) or `scalar` (their scalar twins,
    /// for checking) [simd]. `--kernels` is the old name.
    #[arg(long, alias = "kernels")]
    pub code_path: Option<photonwave::code_path::CodePath>,
    /// Final-gather rays per camera sample [16].
    #[arg(long)]
    pub gather_rays: Option<u32>,
    /// Read the global map directly at the first diffuse hit instead of final gathering.
    #[arg(long)]
    pub no_final_gather: bool,
    /// Secondary gather: a gather ray landing closer than this many global-map radii takes one
    /// more diffuse bounce instead of reading the map there (dark corners stay dark); 0 = off [3].
    #[arg(long, value_name = "RADII")]
    pub secondary_gather: Option<f32>,
    /// Count only photons visible from each estimate's point (no light through thin walls; one
    /// short occlusion ray per candidate photon) [off, or the scene file's `visibility`].
    #[arg(long)]
    pub visibility: bool,
    /// Plain density estimates, without dividing by the part of the kernel's disk on the
    /// surface (edges and corners then come out darker; for comparison) [on].
    #[arg(long)]
    pub no_boundary_correction: bool,
    /// Emit caustic photons in every direction, as global photons are, instead of aiming them at
    /// the mirrors, glass and smooth rough metal that make caustics (for comparison) [aimed].
    #[arg(long)]
    pub no_aim_caustics: bool,
    /// Emit photons from the lights by power and count every stored photon toward a map's
    /// target, instead of guiding both by a pilot of the camera's paths (where the camera reads
    /// each map) (for comparison) [guided].
    #[arg(long)]
    pub no_photon_guide: bool,
    /// Leave emitters to light sampling alone instead of weighing light samples against the
    /// final-gather and glossy rays (the path tracer: its next bounce) by multiple importance
    /// sampling (for comparison) [MIS on].
    #[arg(long)]
    pub no_mis: bool,
    /// How each area-light sample of direct light picks its light: `tree`, by a light tree's
    /// bound of each emitter's contribution at the shading point (near lights more often than
    /// far ones of equal power, none behind the surface), or `power`, by emitted power alone
    /// (for comparison); suns and environments are picked by power beside the tree [tree].
    #[arg(long, value_enum)]
    pub light_sampler: Option<photonwave::settings::LightSampler>,
    /// Add diagnostic EXR layers: per pixel, the radius and photon count of the caustic and the
    /// global density estimates (`radius.caustic`, `photons.caustic`, `radius.global`,
    /// `photons.global`), probed at one camera sample of the last pass; costs one pass's photon
    /// tracing [off, or the scene file's `diagnostics`].
    #[arg(long)]
    pub diagnostics: bool,
    /// Force a part of the effects plan on even where the scene does not need it (repeatable):
    /// caustic_map, global_map, final_gather, refraction, shadow_rays.
    #[arg(long)]
    pub force: Vec<String>,
    /// Progressive passes: each traces fresh photons and estimates with fixed radii that shrink
    /// pass by pass (α); the image is their mean [1 = one k-nearest-neighbour render]. A range
    /// `A..B` renders passes A to B−1 only, a part of a divided render: the output is then a
    /// partial film for `photonwave merge`.
    #[arg(long, value_name = "N|A..B", value_parser = super::passes::parse_passes)]
    pub passes: Option<super::passes::PassesArg>,
    /// Render worker K's share of a divided render of N workers: passes K, K+N, K+2N, … (below
    /// `--passes`, or until `--time` or `--target-error` stops it). The output is a partial film
    /// for `photonwave merge`, whose merge of all N equals the undivided render bit for bit.
    #[arg(long, value_name = "K/N")]
    pub pass_set: Option<String>,
    /// Write the output as a partial film (viewable, plus the exact sums `merge` and `--resume`
    /// read) even for an undivided progressive render.
    #[arg(long)]
    pub partial: bool,
    /// Write the passes so far to this partial film every `--checkpoint-every`, and when the
    /// render ends; written atomically, so a crash mid-write keeps the previous one.
    #[arg(long, value_name = "FILE.exr")]
    pub checkpoint: Option<PathBuf>,
    /// How often to write `--checkpoint`, e.g. `60s`, `10m` [60s].
    #[arg(long, value_parser = parse_duration, default_value = "60s", requires = "checkpoint")]
    pub checkpoint_every: std::time::Duration,
    /// Continue the render whose passes this partial film or checkpoint holds (the same scene and
    /// flags); passes it holds are not rendered again.
    #[arg(long, value_name = "PART.exr")]
    pub resume: Option<PathBuf>,
    /// Progressive passes until the image's estimated error (the `error` layer's mean — 95 %
    /// noise half-width plus estimated bias — over the image mean) is at most E, a fraction
    /// (0.01 = 1 %); with
    /// `--time` or `--passes` as a cap (without either it runs until the target is met) [off].
    #[arg(long, value_name = "E")]
    pub target_error: Option<f32>,
    /// Time budget, e.g. `30s`, `500ms`, `2m`: progressive passes until it is spent, ending
    /// within 5 % of it (counted from the start, scene loading included).
    #[arg(long, value_parser = parse_duration)]
    pub time: Option<std::time::Duration>,
    /// Radius reduction of progressive passes, r²ᵢ₊₁ = r²ᵢ·(i+α)/(i+1) [0.6667].
    #[arg(long)]
    pub alpha: Option<f32>,
    /// Longest photon path / specular chain, a safety cap: Russian roulette ends paths before
    /// it, and `--stats` counts what it cuts [64].
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Seed of all random streams [1].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Worker threads, 0 = all cores [0].
    #[arg(long)]
    pub threads: Option<u32>,
    /// Write the summary as JSON to this file.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Write a tone-mapped PNG preview to this file.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Engine: `wavefront` (bevy_ecs stages over SoA queues), `reference` (scalar photon mapper)
    /// or `path` (unbiased path tracer, for validation) [wavefront; reference for a scene filled
    /// with a participating medium, which the wavefront engine does not render yet].
    #[arg(long)]
    pub engine: Option<Engine>,
    /// Amounts of work (spp, photons, gather rays, passes) from a named preset, over the scene
    /// file's settings and under these flags: `preview`, `default`, or `reference` (a long
    /// progressive run to measure other renders against).
    #[arg(long)]
    pub preset: Option<Preset>,
    /// A camera of the scene's glTF model by name, instead of the first (or the scene file's).
    #[arg(long)]
    pub camera: Option<String>,
    /// Add a light to the scene, placed from the camera (repeatable): `headlight` (a point light
    /// at the eye) or `sun` (a directional light from above and behind the camera). For meshes
    /// that bring no light, such as a bare OBJ from a model library.
    #[arg(long, value_enum)]
    pub light: Vec<LightPreset>,
    /// Print errors only: no plan, warnings, progress bars or summary.
    #[arg(long, short, conflicts_with = "verbose")]
    pub quiet: bool,
    /// Also print per-system runs, lanes and times (wavefront engine).
    #[arg(long, short)]
    pub verbose: bool,
}

/// The camera a render uses: the scene file's, else one fitted to `bounds` for an image of
/// `aspect`, with the CLI's `--eye`, `--target`, `--up` and `--fov` over either (`--eye` and
/// `--target` are in the files' coordinates: `frame` moves them where `file` and `bounds` are).
fn view(
    args: &RenderArgs,
    file: Option<Camera>,
    bounds: (Vec3, Vec3),
    aspect: f32,
    frame: &dyn Fn(Vec3) -> Vec3,
) -> Camera {
    let fov = args.fov.or(file.map(|c| c.fov_deg)).unwrap_or(photonwave::scene::camera::DEFAULT_FOV);
    let mut camera = file.unwrap_or_else(|| fitted_camera_to(bounds, fov, aspect));
    camera.fov_deg = fov;
    camera.eye = args.eye.map_or(camera.eye, frame);
    camera.target = args.target.map_or(camera.target, frame);
    camera.up = args.up.unwrap_or(camera.up);
    camera
}

/// The flags that override the scene file's settings.
fn overrides(args: &RenderArgs) -> Overrides {
    Overrides {
        width: args.width,
        height: args.height,
        spp: args.spp,
        photons: args.photons,
        caustic_photons: args.caustic_photons,
        k: args.k,
        kernel: args.kernel,
        code_path: args.code_path,
        gather_rays: args.gather_rays,
        no_final_gather: args.no_final_gather,
        no_aim_caustics: args.no_aim_caustics,
        no_photon_guide: args.no_photon_guide,
        no_mis: args.no_mis,
        light_sampler: args.light_sampler,
        secondary_gather: args.secondary_gather,
        visibility: args.visibility,
        no_boundary_correction: args.no_boundary_correction,
        diagnostics: args.diagnostics,
        force: args.force.clone(),
        passes: args.passes.map(super::passes::PassesArg::total),
        target_error: args.target_error,
        alpha: args.alpha,
        max_depth: args.max_depth,
        seed: args.seed,
        threads: args.threads,
    }
}

/// Runs `render`.
pub fn run(args: RenderArgs) -> Result<()> {
    let t0 = Instant::now();
    let say = Say { quiet: args.quiet, verbose: args.verbose };
    let mut outputs = vec![Output { flag: "--output", path: &args.output, ext: "exr" }];
    outputs.extend(args.png.as_deref().map(|path| Output { flag: "--png", path, ext: "png" }));
    outputs.extend(args.stats.as_deref().map(|path| Output { flag: "--stats", path, ext: "json" }));
    outputs.extend(args.checkpoint.as_deref().map(|path| Output { flag: "--checkpoint", path, ext: "exr" }));
    // Every output is checked before any work, and again against every file the scene read.
    check_outputs(&outputs, std::slice::from_ref(&args.scene))?;
    // `--light` presets are placed from the camera, which may be fitted to the meshes' bounds
    // for the image's aspect ratio (as the flags or the defaults give it: a scene file that sets
    // a size has a camera too).
    let default = photonwave::settings::Settings::default();
    let cli_aspect = args.width.unwrap_or(default.width) as f32 / args.height.unwrap_or(default.height).max(1) as f32;
    let added = |bounds: (Vec3, Vec3), file: Option<Camera>| -> Vec<Light> {
        let c = view(&args, file, bounds, cli_aspect, &|p| p);
        args.light.iter().map(|preset| preset.light(c.eye, c.target, c.up)).collect()
    };
    let loaded = load_scene_lit(&args.scene, &added)?;
    check_outputs(&outputs, &loaded.inputs)?;
    let scene = std::sync::Arc::new(loaded.scene);
    let (settings, per_pass) = overrides(&args).layer(loaded.settings, args.preset);
    // Validated and planned once, for the whole render.
    let job = Job::new(&scene, &settings)?;
    let settings = &job.settings;
    let file_camera = named_camera(&args, loaded.camera, &loaded.cameras)?;
    let aspect = settings.width as f32 / settings.height as f32;
    let camera = view(&args, file_camera, scene.mesh_bounds(), aspect, &|p| scene.to_frame(p));
    let rays = camera.prepare(settings.width, settings.height)?;
    let load_s = t0.elapsed().as_secs_f64();

    let engine = args.engine.unwrap_or_else(|| {
        if scene.medium.is_some() {
            say.info(
                "engine: reference — the scene is filled with a participating medium, which the wavefront engine \
                 does not render yet\n"
                    .to_string(),
            );
            Engine::Reference
        } else {
            Engine::Wavefront
        }
    });
    describe(say, &scene, &job, engine);
    let bars = Bars::new(args.quiet);
    let budget = args.time.map(|limit| Budget { limit, start: t0 });
    let flags = PassFlags {
        passes: args.passes,
        pass_set: args.pass_set.as_deref(),
        partial: args.partial,
        checkpoint: args.checkpoint.as_deref(),
        checkpoint_every: args.checkpoint_every,
        resume: args.resume.as_deref(),
        output: &args.output,
    };
    let progressive = photonwave::engine::is_progressive(settings, budget) || flags.any();
    let job = if progressive {
        if engine == Engine::Path {
            return Err(Error::setting(
                "--engine",
                "progressive passes (--passes, --time, --pass-set) need a photon-mapping engine",
            ));
        }
        let pass = Job { settings: photonwave::progressive::per_pass(settings, per_pass), ..job.clone() };
        say.info(photonwave::progressive::describe(&pass.plan, &pass.settings, args.time));
        pass
    } else {
        job
    };
    let settings = &job.settings;
    let (film, mut stats, signal) = if progressive {
        photonwave::engine::check_planned(&job, &scene, engine, true)?;
        let lights: Vec<String> = args.light.iter().map(|l| format!("{l:?}")).collect();
        let identity = Identity::new(
            &loaded.inputs,
            settings,
            &format!("{camera:?}"),
            &lights,
            &format!("{engine:?}").to_lowercase(),
        )?;
        let setup = Setup { scene: &scene, rays: &rays, job: &job, engine, budget, t0, identity };
        let r = super::passes::render(&setup, &flags, &bars, say)?;
        (r.film, r.stats, r.signal)
    } else {
        let (film, stats) = photonwave::engine::render_planned(&scene, &rays, &job, engine, budget, &bars)?;
        film.write_exr(&args.output)?;
        (film, stats, None)
    };
    if let Some(w) = photonwave::progressive::budget_warning(&stats) {
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
    stats.times.load = scene.load_times;
    stats.times.total_s += load_s;

    if signal.is_none() {
        // A part of a divided render (`--passes A..B` from 0 too, `--pass-set`, `--partial`) is
        // not an image to look at: say so again where the output is named.
        let part = if progressive && (flags.divided() || flags.partial) {
            " (a partial film: merge the parts with `photonwave merge`)"
        } else {
            ""
        };
        say.info(format!("wrote {}{part}\n", args.output.display()));
    }
    write_png_and_stats(&args, &film, &stats, say)?;
    if let Some(sig) = signal {
        std::process::exit(128 + sig);
    }
    Ok(())
}

/// The camera `--camera NAME` picks from the scene's named cameras, or the file's own.
fn named_camera(args: &RenderArgs, file: Option<Camera>, cameras: &[(String, Camera)]) -> Result<Option<Camera>> {
    let Some(name) = &args.camera else { return Ok(file) };
    let found = cameras.iter().find(|c| &c.0 == name).map(|c| c.1);
    Ok(Some(found.ok_or_else(|| {
        let names: Vec<&str> = cameras.iter().map(|c| c.0.as_str()).collect();
        photonwave::error::Error::setting(
            "--camera",
            if names.is_empty() {
                format!("`{name}`: the scene's models name no cameras")
            } else {
                format!("`{name}` is not a camera of the scene (its cameras: {})", names.join(", "))
            },
        )
    })?))
}

/// What the render is about to do, before it does it: the scene's warnings, too many threads,
/// the scene in numbers, its frame when it was moved, and the plan.
fn describe(say: Say, scene: &photonwave::scene::Scene, job: &Job, engine: Engine) {
    for w in &scene.warnings {
        say.warn(w);
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if job.threads > 2 * cores {
        say.warn(format!(
            "{} threads on {cores} cores: threads beyond the cores only add switching (measured 20× slower \
             at 1024 on 2 cores); 0 uses every core",
            job.threads
        ));
    }
    let (sources, emissive) = scene.light_sources();
    say.info(format!(
        "scene: {} triangles, {} materials, lights: {sources} ({emissive} emissive triangles), total power {} W\n",
        scene.triangle_count(),
        scene.materials.len(),
        significant(scene.total_power().element_sum() / 3.0)
    ));
    if scene.origin != Vec3::ZERO {
        let o = scene.origin;
        say.info(format!(
            "frame: the scene lies {} units from the origin, far for its size; it is rendered moved to its centre \
             ({}, {}, {}), where f32 holds its detail (the camera and lights move with it)\n",
            significant(o.length()),
            significant(o.x),
            significant(o.y),
            significant(o.z)
        ));
    }
    if engine == Engine::Path {
        say.info(
            "plan: path tracing with next-event estimation — every term sampled from the camera; no photon maps\n",
        );
    } else {
        say.info(job.plan.describe());
    }
}

/// Writes the `--png` preview and the `--stats` JSON, and prints the summary.
fn write_png_and_stats(
    args: &RenderArgs,
    film: &photonwave::film::Film,
    stats: &photonwave::stats::RenderStats,
    say: Say,
) -> Result<()> {
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
