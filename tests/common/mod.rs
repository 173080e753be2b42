//! Shared helpers for the integration tests.
#![allow(dead_code)]

use glam::Vec3;
use photonwave::film::Film;
use photonwave::formats::{load_scene, LoadedScene};
use photonwave::progress::NoProgress;
use photonwave::reference;
use photonwave::settings::Settings;
use std::path::PathBuf;

/// The seeds a statistical test runs over: its claim must hold at every one of them (the worst
/// seed is asserted), not at one lucky stream.
pub const SEEDS: std::ops::Range<u64> = 1..33;

/// Path of a bundled scene file.
pub fn bundled(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

/// Loads a bundled scene.
pub fn load(name: &str) -> LoadedScene {
    load_scene(&bundled(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The job of a single render of `scene` with `settings` (which must be valid).
pub fn job(scene: &photonwave::scene::Scene, settings: &Settings) -> photonwave::job::Job {
    photonwave::job::Job::new(scene, settings).unwrap_or_else(|e| panic!("{e}"))
}

/// Renders a loaded scene with the reference engine.
pub fn render(loaded: &LoadedScene, settings: &Settings) -> Film {
    let cam = loaded.camera.expect("bundled scenes have cameras").prepare(settings.width, settings.height).unwrap();
    reference::render(&loaded.scene, &cam, settings, &NoProgress).unwrap().0
}

/// Renders with the path tracer.
pub fn render_path(loaded: &LoadedScene, settings: &Settings) -> Film {
    let cam = loaded.camera.unwrap().prepare(settings.width, settings.height).unwrap();
    photonwave::path::render_path_traced(&loaded.scene, &cam, settings, &NoProgress).unwrap().0
}

/// Mean and standard error of the mean of a per-pixel scalar.
pub fn mean_and_se(values: &[f32]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().map(|&v| v as f64).sum::<f64>() / n;
    let var = values.iter().map(|&v| (v as f64 - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Per-pixel luminance-free average of RGB.
pub fn grey(film: &Film) -> Vec<f32> {
    film.beauty().iter().map(|c: &Vec3| c.element_sum() / 3.0).collect()
}

/// A unique scratch directory for a test.
pub fn scratch_dir(test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("photonwave-{}-{test}", std::process::id()));
    // Emptied first: an earlier run whose process had the same id leaves its files there (a
    // link that test made again failed with "File exists" on a machine with 7 000 such
    // folders).
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Asserts that two films of the same scene agree per pixel in every term: relative difference
/// (over max(1, |a|)) at most `tol`, naming the first pixel that does not. The engines'
/// tolerance is 1e-6 (tests/wavefront.rs).
pub fn assert_terms_agree(a: &Film, b: &Film, tol: f32) {
    for (k, (x, y)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        for (u, v) in x.as_array().into_iter().zip(y.as_array()) {
            let d = ((u - v).abs() / u.abs().max(Vec3::ONE)).max_element();
            assert!(d <= tol, "pixel {k}: {u} against {v}");
        }
    }
}

/// The bundled Mitsuba gallery room (`scenes/interchange/cornell-shapes.xml`, copied with its
/// PLY meshes into `dir`) with the shapes `extra` added, loaded.
pub fn gallery_with(dir: &std::path::Path, extra: &str) -> LoadedScene {
    let src = std::fs::read_to_string(bundled("interchange/cornell-shapes.xml")).unwrap();
    for ply in ["white-room.ply", "red.ply", "green.ply"] {
        std::fs::copy(bundled(&format!("interchange/{ply}")), dir.join(ply)).unwrap();
    }
    let path = dir.join("shapes.xml");
    std::fs::write(&path, src.replace("</scene>", &format!("{extra}\n</scene>"))).unwrap();
    load_scene(&path).unwrap()
}

/// Renders `loaded` (20², 2 spp, 4 gather rays, small maps) with the reference engine and with
/// the wavefront engine at one and two threads; asserts that the wavefront engine is
/// bit-identical across thread counts and that the engines agree per pixel in every term
/// (1e-6, as tests/wavefront.rs holds them). Returns the reference engine's film.
pub fn assert_engines_agree(loaded: LoadedScene) -> Film {
    use photonwave::engine::{render, Engine};
    let s = Settings {
        width: 20,
        height: 20,
        spp: 2,
        photons: 4000,
        caustic_photons: 2000,
        gather_rays: 4,
        ..Settings::default()
    };
    let rays = loaded.camera.unwrap().prepare(s.width, s.height).unwrap();
    let scene = std::sync::Arc::new(loaded.scene);
    let film = |engine, threads| {
        render(&scene, &rays, &Settings { threads, ..s.clone() }, engine, None, &NoProgress).unwrap().0
    };
    let (a, b1, b2) = (film(Engine::Reference, 2), film(Engine::Wavefront, 1), film(Engine::Wavefront, 2));
    assert_eq!(b1.pixels, b2.pixels, "the wavefront engine is bit-identical across thread counts");
    assert_terms_agree(&a, &b1, 1e-6);
    a
}

/// A point of a floor facing +y at `p` (material and triangle 0).
pub fn floor_point(p: Vec3) -> photonwave::scene::SurfacePoint {
    photonwave::scene::SurfacePoint {
        p,
        p_error: Vec3::ZERO,
        frame: photonwave::material::SurfaceFrame { ng: Vec3::Y, ns: Vec3::Y },
        material: 0,
        tri: 0,
        uv: glam::Vec2::ZERO,
        flat: true,
    }
}

/// Irradiance at `p` (normal `n`) from a uniform Lambertian polygon of radiance `le`:
/// E = le/2 · Σ θ_i (n · unit(v_i × v_{i+1})) (Lambert's formula), in f64: in f32 the arccosine
/// of a far polygon's edges (cos θ within 10⁻⁵ of 1) is off by 4 % an edge.
pub fn polygon_irradiance(p: Vec3, n: Vec3, corners: &[Vec3], le: f32) -> f32 {
    let v: Vec<glam::DVec3> = corners.iter().map(|c| (c.as_dvec3() - p.as_dvec3()).normalize()).collect();
    let mut sum = 0.0;
    for i in 0..v.len() {
        let (a, b) = (v[i], v[(i + 1) % v.len()]);
        let g = a.cross(b);
        sum += g.length().atan2(a.dot(b)) * n.as_dvec3().dot(g.normalize());
    }
    (0.5 * f64::from(le) * sum.abs()) as f32
}
