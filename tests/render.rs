//! Whole renders: layers sum to the beauty image, determinism across runs and thread counts,
//! energy against an unbiased path tracer, and which maps each scene builds.

mod common;

use common::*;
use photonwave::effects::Effects;
use photonwave::film::{read_exr_layer, TERM_NAMES};
use photonwave::settings::Settings;

fn small() -> Settings {
    Settings { width: 24, height: 24, spp: 4, photons: 20_000, caustic_photons: 10_000, ..Default::default() }
}

#[test]
fn layers_sum_to_the_beauty_image_in_the_exr() {
    let loaded = load("cornell-spheres.toml");
    let film = render(&loaded, &small());
    let path = scratch_dir("layers").join("out.exr");
    film.write_exr(&path).unwrap();
    let (w, h, beauty) = read_exr_layer(&path, "").unwrap();
    assert_eq!((w, h), (24, 24));
    let layers: Vec<_> = TERM_NAMES.iter().map(|n| read_exr_layer(&path, n).unwrap().2).collect();
    let mut nonzero = [false; 5];
    for i in 0..beauty.len() {
        let sum: glam::Vec3 = layers.iter().map(|l| l[i]).sum();
        // Same five f32 values added in the same order, up to the order of addition.
        assert!((sum - beauty[i]).abs().max_element() <= 1e-5 * beauty[i].max_element().max(1.0), "pixel {i}");
        for (k, l) in layers.iter().enumerate() {
            nonzero[k] |= l[i].max_element() > 0.0;
        }
    }
    // Every term is present in this scene: light, walls, spheres, caustic, indirect.
    assert_eq!(nonzero, [true; 5], "{TERM_NAMES:?}");
}

#[test]
fn same_seed_same_image_at_any_thread_count() {
    let loaded = load("cornell-spheres.toml");
    let one = render(&loaded, &Settings { threads: 1, ..small() });
    let two = render(&loaded, &Settings { threads: 2, ..small() });
    let again = render(&loaded, &Settings { threads: 2, ..small() });
    assert!(one == two, "1 and 2 threads differ");
    assert!(two == again, "two runs differ");
    let other = render(&loaded, &Settings { seed: 2, ..small() });
    assert!(other != one, "a different seed must give a different image");
}

#[test]
fn photon_mapping_energy_matches_path_tracing() {
    // Mean of the image over the same pixels. The path tracer is unbiased: its standard error
    // comes from its pixels. Photon mapping is consistent but biased by its density estimates
    // (blur near edges and corners, ~1 % here); the tolerance is 4 standard errors plus 2 %.
    for scene in ["cornell-box.toml", "cornell-spheres.toml"] {
        let loaded = load(scene);
        let s =
            Settings { width: 24, height: 24, spp: 16, photons: 60_000, caustic_photons: 30_000, ..Default::default() };
        let pm = grey(&render(&loaded, &s));
        let pt = grey(&render_path(&loaded, &Settings { spp: 256, ..s.clone() }));
        let (m_pm, _) = mean_and_se(&pm);
        let (m_pt, se) = mean_and_se(&pt);
        let tol = 4.0 * se + 0.02 * m_pt;
        assert!((m_pm - m_pt).abs() < tol, "{scene}: photon map {m_pm} vs path traced {m_pt} ± {tol}");
    }
}

#[test]
fn maps_are_built_only_where_the_scene_needs_them() {
    let s = Settings::default();
    let diffuse = Effects::plan(&load("cornell-box.toml").scene, &s);
    assert!(diffuse.global_map.on && !diffuse.caustic_map.on && !diffuse.refraction.on, "{diffuse:?}");
    assert!(diffuse.caustic_map.reason.contains("no mirror or glass"));
    let forced =
        Effects::plan(&load("cornell-box.toml").scene, &Settings { force: vec!["caustic_map".into()], ..s.clone() });
    assert!(forced.caustic_map.on && forced.caustic_map.reason.contains("forced"));
    let spheres = Effects::plan(&load("cornell-spheres.toml").scene, &s);
    assert!(spheres.global_map.on && spheres.caustic_map.on && spheres.refraction.on, "{spheres:?}");
    let cam = load("cornell-box.toml");
    let c = cam.camera.unwrap().prepare(8, 8).unwrap();
    let s = Settings { width: 8, height: 8, spp: 1, photons: 5_000, ..Default::default() };
    let (_, stats) = photonwave::reference::render(&cam.scene, &c, &s, &photonwave::progress::NoProgress).unwrap();
    assert!(!stats.caustic_map.built && stats.caustic_map.stored == 0 && stats.caustic_map.emitted == 0);
    assert!(stats.global_map.stored >= 5_000);
}

#[test]
fn a_caustic_appears_under_the_glass_sphere() {
    // The glass sphere (centre x = 0.13, z = 0.08, r = 0.1) focuses light onto the floor below it:
    // the caustic layer there must be far brighter than on the open floor.
    let loaded = load("cornell-spheres.toml");
    let s = Settings { width: 64, height: 64, spp: 1, photons: 20_000, caustic_photons: 40_000, ..Default::default() };
    let film = render(&loaded, &s);
    let total_caustic: f32 = film.pixels.iter().map(|t| t.caustic.element_sum()).sum();
    let brightest = film.pixels.iter().map(|t| t.caustic.element_sum()).fold(0.0f32, f32::max);
    assert!(total_caustic > 0.0);
    // A focused caustic: the brightest pixel carries ≥ 20× the mean caustic of a pixel.
    assert!(brightest > 20.0 * total_caustic / film.pixels.len() as f32);
}

#[test]
fn more_threads_than_work_give_the_same_image_and_utilisation_is_a_share() {
    // A 4×4 image: every stage holds fewer chunks than 16 threads. Both photon-mapping engines,
    // one pass and three progressive passes, at 1, 2, 3, 7 and 16 threads.
    use photonwave::engine::{render, Engine};
    use photonwave::progress::NoProgress;
    let loaded = load("cornell-spheres.toml");
    let cam = loaded.camera.unwrap().prepare(4, 4).unwrap();
    let scene = std::sync::Arc::new(loaded.scene);
    for engine in [Engine::Wavefront, Engine::Reference] {
        for passes in [1, 3] {
            let s = Settings { width: 4, height: 4, spp: 2, photons: 4_000, caustic_photons: 2_000, passes, ..small() };
            let run = |threads: u32| {
                render(&scene, &cam, &Settings { threads, ..s.clone() }, engine, None, &NoProgress).unwrap()
            };
            let (first, first_stats) = run(1);
            for threads in [1, 2, 3, 7, 16] {
                let (film, stats) = run(threads);
                let what = format!("{engine:?}, {passes} passes, {threads} threads");
                assert!(film == first, "{what}: the image differs from one thread's");
                let p = stats.parallel.unwrap_or_else(|| panic!("{what}: no parallel stats"));
                assert_eq!(p.threads, threads as usize, "{what}");
                for (name, v) in [("utilisation", p.utilisation), ("region_utilisation", p.region_utilisation)] {
                    assert!((0.0..=1.0).contains(&v), "{what}: {name} {v}");
                }
                assert!(p.busy_s > 0.0 && p.outside_regions_s >= 0.0 && p.in_regions_s <= p.wall_s, "{what}: {p:?}");
                // The work is cut into the same regions whatever the thread count.
                assert_eq!(p.regions, first_stats.parallel.unwrap().regions, "{what}");
                for (name, st) in stats.stages.iter().flat_map(|s| s.0.iter()) {
                    let most = f64::from(threads) * st.seconds * 1.01 + 1e-4;
                    assert!((0.0..=most).contains(&st.busy_seconds), "{what}: {name} busy {st:?}");
                }
            }
        }
    }
}
