//! `photonwave bench`: throughput of the SIMD kernels against their baselines on identical rays
//! and queries.

use super::parse_vec3;
use glam::Vec3;
use photonwave::error::{Error, Result};
use photonwave::formats::load_scene_lit;
use photonwave::scene::camera::fitted_camera;
use photonwave::scene::Light;
use std::path::PathBuf;

/// Flags of `bench`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Scenes (.toml, .obj, .ply, .gltf or .glb), or `generated:sphere` for the built-in displaced sphere
    /// (~1 M triangles). Default: the bundled Cornell boxes and the generated sphere.
    pub scenes: Vec<String>,
    /// Print one JSON object instead of tables.
    #[arg(long)]
    pub json: bool,
    /// Worker threads for every kernel, 0 = all cores [1].
    #[arg(long, default_value_t = 1)]
    pub threads: u32,
    /// Timed repetitions of each kernel (alternating with its baseline; medians reported).
    #[arg(long, default_value_t = 5)]
    pub reps: u32,
    /// Camera position X,Y,Z for scenes without a camera [fitted to the scene bounds].
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub eye: Option<Vec3>,
    /// Camera target X,Y,Z for scenes without a camera.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub target: Option<Vec3>,
    /// Vertical field of view in degrees for scenes without a camera [40].
    #[arg(long)]
    pub fov: Option<f32>,
    /// A point light at X,Y,Z: every shadow ray goes to it, and meshes without lights of their
    /// own (a bare OBJ) can be measured at all.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub light: Option<Vec3>,
    /// Also time packet traversal at each single-ray hand-over threshold (0–4 lanes; part of the
    /// traversal half, so not with `--only density`).
    #[arg(long)]
    pub thin_sweep: bool,
    /// Measure only `traversal` or only `density` [both].
    #[arg(long, value_parser = ["traversal", "density"])]
    pub only: Option<String>,
    /// Sphere rings of `generated:sphere` (2·rings × 2·rings quads, less the poles: 4·rings² − 4·rings triangles) [512].
    #[arg(long, default_value_t = 512)]
    pub rings: u32,
}

/// Runs `bench`.
pub fn run(args: BenchArgs) -> Result<()> {
    use photonwave::bench;
    use photonwave::formats::generated;
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
        #[cfg(feature = "embree")]
        eprintln!("Embree limited to max_isa={} (this build's widest)", bench::embree::isa());
    }
    let mut report = bench::Report::new(threads);
    let options = bench::Options {
        light: args.light,
        threads,
        reps: args.reps as usize,
        traversal: args.only.as_deref() != Some("density"),
        density: args.only.as_deref() != Some("traversal"),
    };
    for name in &names {
        let loaded = if name == generated::SPHERE_NAME {
            generated::displaced_sphere(args.rings, 2 * args.rings)?
        } else {
            // `--light`: a point light there, so that bare meshes load, photons have a source
            // and every shadow ray goes to it.
            let added = |_: (Vec3, Vec3), _: Option<photonwave::scene::camera::Camera>| {
                args.light.map(|p| Light::Point { position: p, intensity: Vec3::ONE }).into_iter().collect()
            };
            load_scene_lit(std::path::Path::new(name), &added)?
        };
        let label = std::path::Path::new(name).file_stem().map_or(name.clone(), |s| s.to_string_lossy().into_owned());
        let camera = loaded.camera.unwrap_or_else(|| {
            let mut c = fitted_camera(&loaded.scene, args.fov.unwrap_or(photonwave::scene::camera::DEFAULT_FOV), 1.0);
            if let Some(e) = args.eye {
                c.eye = loaded.scene.to_frame(e);
            }
            if let Some(t) = args.target {
                c.target = loaded.scene.to_frame(t);
            }
            c
        });
        let cam = camera.prepare(bench::SIDE, bench::SIDE)?;
        if !args.json {
            eprintln!("{label}: {} triangles", loaded.scene.triangle_count());
        }
        // `--light` is in the file's coordinates; the shadow rays aim at it in the scene's frame.
        let options = bench::Options { light: args.light.map(|p| loaded.scene.to_frame(p)), ..options.clone() };
        if args.thin_sweep && options.traversal {
            let sets = bench::RaySets::with_light(&loaded.scene, &cam, options.light);
            for (rays, query, thin, mrays) in
                bench::thin_sweep(&loaded.scene, &sets, &[0, 1, 2, 3, 4], args.reps as usize)
            {
                eprintln!("  hand-over at ≤{thin} lanes: {rays:<8} {query:<8} {mrays:>7.2} Mrays/s");
            }
        }
        let rows = bench::run_scene(&label, &loaded.scene, &cam, &options)?;
        for r in &rows.0 {
            // Embree's calls may differ from ours by a ray or two on edges (its default mode is not
            // watertight); more means rays it did not trace as given.
            if let Some(extra) = r.embree_extra_hits_by_call {
                if extra.iter().any(|e| e.unsigned_abs() as usize > 4.max(r.count / 10_000)) {
                    eprintln!(
                        "warning: {label} {} {}: Embree's hits differ from ours by {extra:?} of {} rays \
                         (default single, default packets, robust single, robust packets)",
                        r.rays, r.query, r.count
                    );
                }
            }
        }
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
