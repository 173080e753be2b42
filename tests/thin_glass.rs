//! Thin glass (window panes: Mitsuba's `thindielectric`, glTF's thin-walled transmission, TOML's
//! `thin_glass`) passed in traversal with its transmittance T = 1 − R′ (`Bsdf::thin_pass`): shadow
//! rays pass a pane with probability T at its angle; photons that pass are direct light (first
//! hits, never caustics); direct light under a pane is T times the open sky's, in both engines;
//! the engines agree per pixel on the bundled window room at any thread count.

mod common;

use common::{assert_engines_agree, job, load, mean_and_se, scratch_dir, SEEDS};
use glam::Vec3;
use photonwave::engine::{render, Engine};
use photonwave::formats::{load_scene, LoadedScene};
use photonwave::optics::thin_slab_reflectance;
use photonwave::photon_map::flags;
use photonwave::progress::NoProgress;
use photonwave::reference::photons::trace_photons;
use photonwave::rng::{Domain, Sampler};
use photonwave::settings::Settings;
use std::path::Path;

/// The transmittance of a clear pane of index 1.5 at cos θ = `cos`: 1 − R′.
fn transmittance(cos: f32) -> f64 {
    1.0 - f64::from(thin_slab_reflectance(cos, 1.5))
}

/// A Mitsuba scene in `dir`: a floor (diffuse `kd`) at z = −1 and, with `pane`, a thin glass
/// pane of index 1.5 at z = 0 (both 4 × 4, centred on the axis), under a directional light of
/// irradiance 1 travelling along `toward`; a camera at z = −0.5 looking down at the floor (it
/// sees the floor only).
fn under_a_pane(dir: &Path, name: &str, pane: bool, kd: f32, toward: Vec3) -> LoadedScene {
    let glass = "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"2\"/></transform>\
<bsdf type=\"thindielectric\"><float name=\"int_ior\" value=\"1.5\"/></bsdf></shape>";
    let xml = format!(
        "<scene version=\"3.0.0\">\n\
<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/><transform name=\"to_world\">\
<lookat origin=\"0, 0, -0.5\" target=\"0, 0, -1\" up=\"0, 1, 0\"/></transform></sensor>\n{}\n\
<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"2\"/><translate z=\"-1\"/></transform>\
<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"{kd}\"/></bsdf></shape>\n\
<emitter type=\"directional\"><vector name=\"direction\" value=\"{}, {}, {}\"/><rgb name=\"irradiance\" value=\"1\"/></emitter>\n</scene>\n",
        if pane { glass } else { "" },
        toward.x,
        toward.y,
        toward.z
    );
    let path = dir.join(name);
    std::fs::write(&path, xml).unwrap();
    load_scene(&path).unwrap()
}

#[test]
fn a_pane_passes_its_transmittance_of_the_shadow_rays() {
    // Shadow rays rise from uniform points of the floor's middle (x, y in [−1, 1]) toward the
    // light, head-on and at 45° (every one meets the pane). Each passes with probability T, so
    // the share passed of n = 4096 rays is T within 4σ, σ = √(T(1 − T)/n), at each of 32 seeds.
    let d = scratch_dir("thin-shadows");
    let loaded = under_a_pane(&d, "pane.xml", true, 0.0, Vec3::NEG_Z);
    let scene = &loaded.scene;
    assert_eq!(scene.thin_sheets(), (1, 0), "the pane is passed in traversal");
    let n = 4096u32;
    for (label, up) in [("head-on", Vec3::Z), ("45°", Vec3::new(1.0, 0.0, 1.0).normalize())] {
        let t = transmittance(up.z);
        let sigma = (t * (1.0 - t) / f64::from(n)).sqrt();
        let mut worst = 0.0f64;
        for seed in SEEDS {
            let passed = (0..n)
                .filter(|&i| {
                    let s = Sampler::new(seed, Domain::Camera, u64::from(i));
                    let p = Vec3::new(2.0 * s.get(0, 0) - 1.0, 2.0 * s.get(0, 1) - 1.0, -0.999);
                    !scene.occluded(p, up, f32::INFINITY)
                })
                .count();
            let share = passed as f64 / f64::from(n);
            worst = worst.max((share - t).abs() / sigma);
            assert!((share - t).abs() < 4.0 * sigma, "{label} seed {seed}: {share} passed, T = {t}");
        }
        println!("{label}: T = {t:.4}, worst deviation {worst:.2} σ");
    }
}

#[test]
fn light_through_a_pane_is_direct_light_not_a_caustic() {
    // Sunlight straight down through the pane onto a black floor of the same size: a photon
    // passes (probability T) and lands on the floor, its first hit, or is reflected up out of
    // the scene. So every stored photon is on the floor, flagged direct, none caustic, and the
    // caustic map stays empty. Their power is T·E·A = 16·T: the map stops at n = 20 000 photons,
    // so the sum n·Φ/N (N paths emitted) has a relative spread of √((1 − p)/n), p the share of
    // paths that store (0.57); asserted within 4 of those at each of 32 seeds.
    let d = scratch_dir("thin-photons");
    let loaded = under_a_pane(&d, "pane.xml", true, 0.0, Vec3::NEG_Z);
    let scene = &loaded.scene;
    let want = 16.0 * transmittance(1.0);
    let n = 20_000u32;
    let mut worst = 0.0f64;
    for seed in SEEDS {
        let s = Settings { threads: 1, seed, ..Settings::default() };
        let pass = trace_photons(scene, &job(scene, &s), Domain::GlobalPhoton, n, &NoProgress);
        assert_eq!(pass.photons.len(), n as usize);
        for p in &pass.photons {
            assert!(p.position.z < -0.99, "seed {seed}: a photon stored off the floor at {}", p.position);
            assert_eq!(p.flags & flags::OWN_TERMS, flags::DIRECT, "seed {seed}: the floor's photons are direct light");
        }
        let power: f64 = pass.photons.iter().map(|p| f64::from(p.power.x)).sum();
        let p = f64::from(n) / pass.emitted as f64;
        let sigma = ((1.0 - p) / f64::from(n)).sqrt() * want;
        worst = worst.max((power - want).abs() / sigma);
        assert!((power - want).abs() < 4.0 * sigma, "seed {seed}: {power} through the pane, want {want}");
        let caustic = trace_photons(scene, &job(scene, &s), Domain::CausticPhoton, 1000, &NoProgress);
        assert!(caustic.photons.is_empty(), "seed {seed}: {} caustic photons", caustic.photons.len());
    }
    println!("worst deviation {worst:.2} σ");
}

#[test]
fn direct_light_under_a_pane_is_t_times_the_open_skys() {
    // The floor (kd 0.5) seen from under the pane, the light straight down: its direct layer is
    // kd/π·E open (every shadow ray passes; asserted to 1e-5), and under the pane each sample's
    // one shadow ray passes with probability T, so the image mean is T times it within 4σ,
    // σ = √(T(1 − T)/n) over n = 24·24·4 samples, at each of 8 seeds and in both engines (which
    // agree per pixel).
    let d = scratch_dir("thin-direct");
    let open = under_a_pane(&d, "open.xml", false, 0.5, Vec3::NEG_Z);
    let pane = under_a_pane(&d, "pane.xml", true, 0.5, Vec3::NEG_Z);
    let s = Settings {
        width: 24,
        height: 24,
        spp: 4,
        photons: 2000,
        caustic_photons: 1000,
        gather_rays: 2,
        ..Settings::default()
    };
    let prepared = |loaded: LoadedScene| {
        let rays = loaded.camera.unwrap().prepare(s.width, s.height).unwrap();
        (std::sync::Arc::new(loaded.scene), rays)
    };
    let (open, pane) = (prepared(open), prepared(pane));
    let direct_mean = |(scene, rays): &(std::sync::Arc<photonwave::scene::Scene>, _), engine, seed| {
        let settings = Settings { seed, threads: 2, ..s.clone() };
        let film = render(scene, rays, &settings, engine, None, &NoProgress).unwrap().0;
        let direct: Vec<f32> = film.pixels.iter().map(|t| t.direct.x).collect();
        (mean_and_se(&direct).0, film)
    };
    let lit = 0.5 / std::f64::consts::PI;
    let (open_mean, _) = direct_mean(&open, Engine::Wavefront, 1);
    assert!((open_mean / lit - 1.0).abs() < 1e-5, "open: {open_mean}, want {lit}");
    let t = transmittance(1.0);
    let sigma = (t * (1.0 - t) / f64::from(s.width * s.height * s.spp)).sqrt();
    let mut worst = 0.0f64;
    for seed in 1..=8 {
        let (wavefront, a) = direct_mean(&pane, Engine::Wavefront, seed);
        let (reference, b) = direct_mean(&pane, Engine::Reference, seed);
        common::assert_terms_agree(&a, &b, 1e-6);
        assert_eq!(wavefront, reference);
        let ratio = wavefront / lit;
        worst = worst.max((ratio - t).abs() / sigma);
        assert!((ratio - t).abs() < 4.0 * sigma, "seed {seed}: under the pane {ratio} of the open sky's, T = {t}");
    }
    println!("T = {t:.4}, worst deviation {worst:.2} σ");
}

#[test]
fn engines_agree_in_the_window_room_at_any_thread_count() {
    // The bundled room lit by sun and sky through its one pane: camera, shadow, gather and
    // glossy rays and photons pass the pane or reflect off it, the same in the wavefront kernels
    // and the reference engine's single rays.
    let loaded = load("window.toml");
    assert_eq!(loaded.scene.thin_sheets(), (1, 0));
    assert!(!loaded.scene.encloses_lights, "light leaves through the pane");
    assert_engines_agree(loaded);
}

#[test]
fn a_coloured_pane_stays_a_surface() {
    // A coloured transmission would need a weight to pass in traversal: such a sheet is sampled
    // at its hits as before, and the plan says so.
    let d = scratch_dir("thin-tinted");
    let xml = "<scene version=\"3.0.0\">\n<shape type=\"rectangle\"><bsdf type=\"thindielectric\">\
<rgb name=\"specular_transmittance\" value=\"0.9, 0.5, 0.5\"/></bsdf></shape>\n\
<shape type=\"rectangle\"><translate z=\"-1\"/><bsdf type=\"diffuse\"/></shape>\n\
<emitter type=\"directional\"><vector name=\"direction\" value=\"0, 0, -1\"/></emitter>\n</scene>\n";
    std::fs::write(d.join("tinted.xml"), xml).unwrap();
    let scene = load_scene(&d.join("tinted.xml")).unwrap().scene;
    assert_eq!(scene.thin_sheets(), (0, 1));
    let plan = photonwave::effects::Effects::plan(&scene, &Settings::default());
    assert!(!plan.thin_glass.on && plan.thin_glass.reason.contains("coloured"), "{:?}", plan.thin_glass);
    // Nothing passes it in traversal: a ray straight up from the floor is blocked.
    assert!(scene.occluded(Vec3::new(0.1, 0.2, -0.999), Vec3::Z, f32::INFINITY));
}
