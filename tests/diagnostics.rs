//! The diagnostic layers (`--diagnostics`): each pixel's estimate radii and photon counts, as the
//! settings prescribe them, without changing the image.

mod common;

use common::load;
use photonwave::engine::{render, Engine};
use photonwave::film::{EstimateLayers, Film};
use photonwave::progress::NoProgress;
use photonwave::settings::Settings;
use photonwave::stats::RenderStats;
use std::sync::Arc;

/// Small renders of the glass-sphere box (caustics and the global map).
fn spheres(settings: &Settings, engine: Engine) -> (Film, RenderStats) {
    let loaded = load("cornell-spheres.toml");
    let rays = loaded.camera.unwrap().prepare(settings.width, settings.height).unwrap();
    render(&Arc::new(loaded.scene), &rays, settings, engine, None, &NoProgress).unwrap()
}

fn small() -> Settings {
    Settings { width: 24, height: 24, spp: 2, photons: 4000, caustic_photons: 8000, threads: 1, ..Default::default() }
}

/// Every layer has a value per pixel, and some pixels found photons in each map.
fn check_shape(d: &EstimateLayers, pixels: usize) {
    for layer in [&d.caustic_radius, &d.caustic_photons, &d.global_radius, &d.global_photons] {
        assert_eq!(layer.len(), pixels);
        assert!(layer.iter().all(|v| v.is_finite() && *v >= 0.0));
    }
    assert!(d.caustic_photons.iter().any(|&c| c > 0.0) && d.global_photons.iter().any(|&c| c > 0.0));
}

/// One k-nearest render: an estimate sums at most k − 1 photons (the (k−1)/(πr²) form), and one
/// that found fewer used the maximum radius; k-NN radii never exceed it. The image is the same
/// with and without the layers, and the EXR carries them.
#[test]
fn knn_layers_follow_k_and_the_maximum_radius() {
    let s = Settings { diagnostics: true, ..small() };
    let (film, stats) = spheres(&s, Engine::Wavefront);
    let (plain, _) = spheres(&Settings { diagnostics: false, ..s.clone() }, Engine::Wavefront);
    assert_eq!(film.pixels, plain.pixels, "the diagnostics changed the image");
    assert!(plain.diagnostics.is_none() && stats.times.diagnostics_s > 0.0);
    let d = film.diagnostics.as_ref().expect("diagnostics asked for");
    check_shape(d, 24 * 24);
    let diagonal = load("cornell-spheres.toml").scene.diagonal();
    let r_max = s.caustic_radius * diagonal;
    for (&r, &n) in d.caustic_radius.iter().zip(&d.caustic_photons) {
        assert!(n <= (s.caustic_k - 1) as f32, "{n} caustic photons with k = {}", s.caustic_k);
        assert!(r <= r_max * (1.0 + 1e-6), "radius {r} above the maximum {r_max}");
        if n > 0.0 && n < (s.caustic_k - 1) as f32 {
            assert!((r / r_max - 1.0).abs() < 1e-6, "{n} photons but radius {r}, not the maximum {r_max}");
        }
    }
    // Final gathering: the global layers are means over the gather hits.
    assert!(d.global_photons.iter().all(|&n| n <= (s.k - 1) as f32 + 1e-3));
    let dir = common::scratch_dir("diagnostics");
    let path = dir.join("d.exr");
    film.write_exr(&path).unwrap();
    let names: Vec<String> = photonwave::film::read_exr(&path).unwrap().layers.into_iter().map(|l| l.0).collect();
    for layer in ["radius.caustic", "photons.caustic", "radius.global", "photons.global"] {
        assert!(names.iter().any(|n| n == layer), "{layer} not in {names:?}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Progressive passes with one radius per map (no per-pixel radii): every estimate of the last
/// pass used that pass's radii, so the radius layers hold exactly those (or 0 where a pixel found
/// no surface); both engines give the same layers, as the probe is theirs in common.
#[test]
fn progressive_layers_hold_the_last_pass_radii() {
    let s = Settings { diagnostics: true, passes: 3, per_pixel_radii: false, ..small() };
    let (film, stats) = spheres(&s, Engine::Wavefront);
    let d = film.diagnostics.as_ref().unwrap();
    check_shape(d, 24 * 24);
    let [global, caustic] = stats.progressive.unwrap().final_radii;
    assert!(d.caustic_radius.iter().all(|&r| r == 0.0 || r == caustic), "caustic radii {:?}", &d.caustic_radius[..8]);
    assert!(d.global_radius.iter().all(|&r| r == 0.0 || (r / global - 1.0).abs() < 1e-5));
    let (reference, _) = spheres(&s, Engine::Reference);
    assert_eq!(reference.diagnostics.as_ref(), Some(d));
}

/// The path tracer makes no density estimates: asking it for their layers is an error naming
/// the flag.
#[test]
fn the_path_tracer_refuses_diagnostics() {
    let loaded = load("cornell-spheres.toml");
    let s = Settings { diagnostics: true, ..small() };
    let rays = loaded.camera.unwrap().prepare(s.width, s.height).unwrap();
    let err = render(&Arc::new(loaded.scene), &rays, &s, Engine::Path, None, &NoProgress).unwrap_err();
    assert!(err.to_string().contains("--diagnostics"), "{err}");
}
