//! The wavefront engine against the reference engine, determinism across thread counts, and
//! the effects plan gating its systems.

mod common;

use common::*;
use photonwave::film::Film;
use photonwave::formats::LoadedScene;
use photonwave::progress::NoProgress;
use photonwave::settings::Settings;
use photonwave::stats::RenderStats;
use std::sync::Arc;

fn wavefront(loaded: LoadedScene, settings: &Settings) -> (Film, RenderStats, Option<photonwave::scene::Camera>) {
    let cam = loaded.camera.unwrap();
    let rays = cam.prepare(settings.width, settings.height).unwrap();
    let (f, s) = photonwave::wavefront::render(Arc::new(loaded.scene), &rays, settings, &NoProgress).unwrap();
    (f, s, Some(cam))
}

fn small() -> Settings {
    Settings {
        width: 24,
        height: 24,
        spp: 4,
        photons: 20_000,
        caustic_photons: 10_000,
        gather_rays: 4,
        ..Default::default()
    }
}

/// Largest per-pixel, per-channel difference relative to max(1, |reference|), over the terms and
/// the estimated bias.
fn max_rel_diff(a: &Film, b: &Film) -> f32 {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(x, y)| x.as_array().into_iter().chain([x.bias]).zip(y.as_array().into_iter().chain([y.bias])))
        .map(|(x, y)| ((x - y).abs() / x.abs().max(glam::Vec3::ONE)).max_element())
        .fold(0.0, f32::max)
}

#[test]
fn wavefront_matches_reference_per_pixel_on_every_bundled_scene() {
    // Same photons (same streams, same order), same camera streams: the engines differ only in
    // the order floating-point contributions are added. Tolerance: 1e-6 relative per term and
    // channel, about 8 f32 ulps (measured: at most 9e-8).
    let glossy = glossy_spheres();
    let lights = delta_lights();
    let (smooth_rough, rough) = (rough_spheres(0.2), rough_spheres(0.6));
    // With a point light too: camera paths passing the frosted and smooth rough spheres take
    // the point light's direct light there.
    let lit_rough = {
        let p = rough_spheres(0.15);
        let text = std::fs::read_to_string(&p).unwrap()
            + "[[light]]\ntype = \"point\"\nposition = [0.1, 0.45, 0.3]\nintensity = [0.05, 0.05, 0.05]\n";
        let q = p.with_file_name("lit-rough.toml");
        std::fs::write(&q, text).unwrap();
        q
    };
    let scenes = [
        "cornell-box.toml",
        "cornell-spheres.toml",
        "furnace.toml",
        "interior.xml",
        glossy.to_str().unwrap(),
        lights.to_str().unwrap(),
        smooth_rough.to_str().unwrap(),
        rough.to_str().unwrap(),
        lit_rough.to_str().unwrap(),
    ];
    for scene in scenes {
        // The secondary gather at its default (many gather rays landing near: in one-pass
        // renders its unit is the maximum radius) and off.
        let on = photonwave::settings::SECONDARY_GATHER;
        for (final_gather, precompute_irradiance, secondary_gather) in
            [(true, true, on), (true, false, on), (false, true, on), (true, false, 0.0)]
        {
            let s = Settings { final_gather, precompute_irradiance, secondary_gather, ..small() };
            let loaded = || photonwave::formats::load_scene(&bundled(scene)).unwrap();
            let reference = render(&loaded(), &s);
            let (wave, _, _) = wavefront(loaded(), &s);
            let d = max_rel_diff(&reference, &wave);
            let case = format!("{scene} ({final_gather}, {precompute_irradiance}, {secondary_gather})");
            println!("{case}: max relative difference {d:e}");
            assert!(d < 1e-6, "{case}: max relative difference {d}");
        }
    }
}

/// The bundled spheres lit also by a point, a spot and a directional light (delta lights in
/// direct lighting and photon emission).
fn delta_lights() -> std::path::PathBuf {
    let dir = scratch_dir("delta-lights");
    let obj = bundled("cornell-spheres.obj");
    let toml = format!(
        "[[mesh]]\nfile = {:?}\n[camera]\neye = [0.0, 0.273, 1.0796]\ntarget = [0.0, 0.273, 0.0]\nfov = 39.3\n\
         [[light]]\ntype = \"point\"\nposition = [0.1, 0.45, 0.1]\nintensity = [0.05, 0.05, 0.05]\n\
         [[light]]\ntype = \"spot\"\nposition = [-0.2, 0.5, 0.2]\ntarget = [0.13, 0.0, 0.08]\nintensity = [0.2, 0.1, 0.05]\nangle = 25\ninner_angle = 15\n\
         [[light]]\ntype = \"directional\"\ndirection = [0.2, -1.0, -0.3]\nirradiance = [0.3, 0.3, 0.3]\n",
        obj.to_str().unwrap()
    );
    let path = dir.join("delta-lights.toml");
    std::fs::write(&path, toml).unwrap();
    path
}

/// The bundled spheres with the mirror sphere made glossy (exercises glossy rays).
fn glossy_spheres() -> std::path::PathBuf {
    let dir = scratch_dir("glossy-spheres");
    let obj = bundled("cornell-spheres.obj");
    let toml = format!(
        "[[mesh]]\nfile = {:?}\n[camera]\neye = [0.0, 0.273, 1.0796]\ntarget = [0.0, 0.273, 0.0]\nfov = 39.3\n\
         [materials.mirror]\ntype = \"glossy\"\nkd = [0.3, 0.3, 0.3]\nks = [0.6, 0.6, 0.6]\nexponent = 30\n",
        obj.to_str().unwrap()
    );
    let path = dir.join("glossy-spheres.toml");
    std::fs::write(&path, toml).unwrap();
    path
}

/// The bundled spheres with a rough metal sphere of roughness `r` (below 0.3 photons pass it on
/// as specular, above they are stored on it), a frosted glass sphere (photons always pass) and a
/// red wall of rough plastic (final-gather rays weighted one by one).
fn rough_spheres(r: f32) -> std::path::PathBuf {
    let dir = scratch_dir(&format!("rough-spheres-{r}"));
    let obj = bundled("cornell-spheres.obj");
    let toml = format!(
        "[[mesh]]\nfile = {:?}\n[camera]\neye = [0.0, 0.273, 1.0796]\ntarget = [0.0, 0.273, 0.0]\nfov = 39.3\n\
         [materials.mirror]\ntype = \"rough_conductor\"\nks = [0.95, 0.7, 0.4]\nroughness = {r}\n\
         [materials.glass]\ntype = \"rough_dielectric\"\nior = 1.5\nroughness = 0.25\n\
         [materials.red]\ntype = \"rough_plastic\"\nkd = [0.63, 0.06, 0.05]\nroughness = 0.4\n",
        obj.to_str().unwrap()
    );
    let path = dir.join("rough-spheres.toml");
    std::fs::write(&path, toml).unwrap();
    path
}

#[test]
fn wavefront_is_bit_identical_at_one_and_two_threads() {
    // The interior (issue 56): narrow lobes, absorbing glass, a light tree of ten triangles.
    for scene in ["cornell-spheres.toml", "interior.xml"] {
        let one = wavefront(load(scene), &Settings { threads: 1, ..small() }).0;
        let two = wavefront(load(scene), &Settings { threads: 2, ..small() }).0;
        assert!(one == two, "{scene}: 1 and 2 threads differ");
    }
}

#[test]
fn a_scene_without_mirror_or_glass_runs_no_caustic_or_refraction_system() {
    let (plain, stats, _) = wavefront(load("cornell-box.toml"), &small());
    let stages = stats.stages.unwrap().0;
    for system in ["gather_caustics", "refract_paths", "refract_photons"] {
        assert_eq!(stages.get(system).map_or(0, |s| s.runs), 0, "{system} ran");
    }
    assert!(stages["intersect_paths"].runs > 0 && stages["deposit_photons"].runs > 0);
    assert!(!stats.caustic_map.built && stats.caustic_map.emitted == 0);
    let effects = stats.effects.unwrap();
    assert!(!effects.caustic_map.on && !effects.refraction.on && effects.global_map.on && effects.final_gather.on);
    // Forced on, the caustic pass runs and finds no specular surface to focus light: its map
    // is empty and the image is the same.
    let forced = Settings { force: vec!["caustic_map".into()], caustic_photons: 100, ..small() };
    let (with_caustics, fstats, _) = wavefront(load("cornell-box.toml"), &forced);
    let fstages = fstats.stages.unwrap().0;
    assert!(fstages["gather_caustics"].runs > 0);
    assert!(fstats.caustic_map.built && fstats.caustic_map.stored == 0 && fstats.caustic_map.emitted > 0);
    assert!(plain == with_caustics, "forcing an empty caustic map changed the image");
}

#[test]
fn glass_scenes_run_refraction_and_caustics() {
    let (_, stats, _) = wavefront(load("cornell-spheres.toml"), &small());
    let stages = stats.stages.unwrap().0;
    for system in ["gather_caustics", "refract_paths", "refract_photons", "reflect_paths"] {
        assert!(stages[system].runs > 0 && stages[system].items > 0, "{system}: {:?}", stages[system]);
    }
}

#[test]
fn both_engines_emit_and_store_the_same_photons() {
    // The wavefront engine traces several reference batches per wave but applies the
    // reference's stopping rule batch by batch.
    let s = Settings { photons: 50_000, caustic_photons: 30_000, ..small() };
    let loaded = load("cornell-spheres.toml");
    let cam = loaded.camera.unwrap().prepare(s.width, s.height).unwrap();
    let (_, r) = photonwave::reference::render(&loaded.scene, &cam, &s, &NoProgress).unwrap();
    let (_, w, _) = wavefront(load("cornell-spheres.toml"), &s);
    assert_eq!((r.global_map.emitted, r.global_map.stored), (w.global_map.emitted, w.global_map.stored));
    assert_eq!((r.caustic_map.emitted, r.caustic_map.stored), (w.caustic_map.emitted, w.caustic_map.stored));
    assert_eq!(r.irradiance_points, w.irradiance_points);
    // Photon by photon: same positions, powers, directions and flags, in the same order.
    let scene = Arc::new(load("cornell-spheres.toml").scene);
    let (rm, _, _) = photonwave::reference::build_maps(&scene, &s).unwrap();
    let (wm, _) = photonwave::wavefront::build_maps(scene, &s).unwrap();
    for (a, b) in [(&rm.global, &wm.global), (&rm.caustic, &wm.caustic), (&rm.irradiance, &wm.irradiance)] {
        assert_eq!(a.len(), b.len());
        assert!((0..a.len()).all(|i| a.photon(i) == b.photon(i)));
    }
}

/// Progressive passes with per-pixel radii: the engines still agree per pixel (same tolerance
/// as one-pass renders), terms and estimated bias, with final gathering on and off.
#[test]
fn wavefront_matches_reference_with_per_pixel_radii() {
    use photonwave::engine::{render as render_with, Engine};
    let loaded = load("cornell-spheres.toml");
    let rays = loaded.camera.unwrap().prepare(24, 24).unwrap();
    let scene = Arc::new(loaded.scene);
    for final_gather in [true, false] {
        let s = Settings { passes: 2, spp: 1, final_gather, ..small() };
        let image = |e| render_with(&scene, &rays, &s, e, None, &NoProgress).unwrap();
        let ((reference, rs), (wave, _)) = (image(Engine::Reference), image(Engine::Wavefront));
        assert!(rs.progressive.unwrap().pixel_caustic_radii.is_some());
        assert!(reference.pixels.iter().any(|t| t.bias != glam::Vec3::ZERO), "no bias estimated");
        let d = max_rel_diff(&reference, &wave);
        assert!(d < 1e-6, "final gather {final_gather}: max relative difference {d}");
    }
}

#[test]
fn tiles_of_any_size_at_any_thread_count_give_the_same_image() {
    // The camera pass cuts the image into tiles, each rendered by one worker on its own queues:
    // a sample's terms are added in the order of its own lanes whoever shares its tile, so the
    // film is the same for one-pixel tiles, uneven ones, the default and one tile for the whole
    // image, at 1, 2, 3 and 7 threads. cornell-spheres: mirror and glass chains, caustics.
    use photonwave::wavefront::camera_pass::{camera_pass, TILE};
    let loaded = load("cornell-spheres.toml");
    let s = Settings { width: 20, height: 14, spp: 4, ..small() };
    let rays = loaded.camera.unwrap().prepare(s.width, s.height).unwrap();
    let scene = Arc::new(loaded.scene);
    let (maps, _) = photonwave::wavefront::build_maps(scene.clone(), &s).unwrap();
    let maps = Arc::new(maps);
    let samples = (s.width * s.height * s.spp) as usize;
    let mut first: Option<Vec<photonwave::film::Terms>> = None;
    for tile in [1, 4, 4 * 7 + 2, 4 * 63, TILE, samples] {
        for threads in [1, 2, 3, 7] {
            let job = photonwave::job::Job::photon_mapping(&scene, &Settings { threads, ..s.clone() }).unwrap();
            let out = camera_pass(&scene, &rays, &job, &maps, tile, &NoProgress);
            assert_eq!(out.film.len(), (s.width * s.height) as usize, "tile {tile}, {threads} threads");
            assert!(out.film.iter().any(|t| t.beauty() != glam::Vec3::ZERO), "tile {tile}: a black image");
            match &first {
                None => first = Some(out.film),
                Some(f) => assert!(*f == out.film, "tile {tile} samples, {threads} threads: the image differs"),
            }
        }
    }
}

/// Memory at any spp (issue 53): a camera tile is whole pixels, so a pixel of 65 536 samples
/// once made one wave of 65 536 samples and their gather rays on every worker, whatever the
/// in-flight bound. Now such a pixel runs as waves of the tile's size: at 16 threads no stage
/// of the camera pass holds more than `tile_for`'s 512 samples and their gather rays, and the
/// pixel is the reference engine's to 10⁻⁶ (its mean carried from wave to wave in sample
/// order).
#[test]
fn a_pixel_of_65536_samples_keeps_the_in_flight_bound() {
    use photonwave::engine::{render, Engine};
    use photonwave::wavefront::camera_pass::tile_for;
    let loaded = load("cornell-spheres.toml");
    let s = Settings {
        width: 1,
        height: 1,
        spp: 65_536,
        photons: 2_000,
        caustic_photons: 1_000,
        gather_rays: 2,
        threads: 16,
        ..Default::default()
    };
    let rays = loaded.camera.unwrap().prepare(1, 1).unwrap();
    let scene = Arc::new(loaded.scene);
    let (wave, stats) = render(&scene, &rays, &s, Engine::Wavefront, None, &NoProgress).unwrap();
    let tile = tile_for(65_536, 16) as u64;
    assert_eq!(tile, 512);
    let stages = &stats.stages.expect("the wavefront engine's stages").0;
    let most = |name: &str| stages.get(name).map_or(0, |st| st.max_items);
    assert_eq!(most("emit_camera_rays"), tile);
    assert_eq!(stages["emit_camera_rays"].items, 65_536);
    assert_eq!(most("resolve_wave"), tile);
    // A bounce's queue holds the wave's paths and, from the second bounce, their gather rays.
    let lanes = tile * (1 + u64::from(s.gather_rays));
    for name in ["intersect_paths", "classify_paths", "shade_direct", "spawn_gather_rays", "gather_global"] {
        assert!((1..=lanes).contains(&most(name)), "{name}: {} lanes in one run (at most {lanes})", most(name));
    }
    let reference =
        render(&scene, &rays, &Settings { threads: 2, ..s.clone() }, Engine::Reference, None, &NoProgress).unwrap().0;
    let d = max_rel_diff(&reference, &wave);
    assert!(d < 1e-6, "max relative difference {d}");
}
