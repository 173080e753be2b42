//! Absorbing interiors (Beer–Lambert inside dielectrics, `Material::interior`): a slab of
//! thickness d keeps exp(−σ·d) of what the clear slab passes, for camera paths in every engine
//! and for photons; the two photon-mapping engines agree per pixel with an absorbing block in a
//! room, at any thread count; and the readers turn Mitsuba's interior media and TOML's
//! `absorption` into it, warning of what they leave out.

mod common;

use common::{assert_engines_agree, gallery_with, job, scratch_dir};
use glam::Vec3;
use photonwave::engine::{render, Engine};
use photonwave::formats::load_scene;
use photonwave::material::Bsdf;
use photonwave::progress::NoProgress;
use photonwave::reference::photons::trace_photons;
use photonwave::rng::Domain;
use photonwave::settings::Settings;
use std::path::PathBuf;
use std::sync::Arc;

/// The interior of the test slabs: σ_t of Bitterli's Modern Hall balustrade glass, albedo 0.
const MEDIUM: &str = "<medium name=\"interior\" type=\"homogeneous\"><rgb name=\"sigma_t\" value=\"0.5, 0.2, 0.4\"/>\
<float name=\"albedo\" value=\"0\"/></medium>";
const SIGMA: Vec3 = Vec3::new(0.5, 0.2, 0.4);

/// A Mitsuba scene `name` in `dir`: a glass slab 1 thick (z in [−0.5, 0.5], 6 wide) with
/// `interior` inside its shape, and `rest`.
fn slab_scene(dir: &std::path::Path, name: &str, interior: &str, rest: &str) -> PathBuf {
    let xml = format!(
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" value=\"10\"/>\
<transform name=\"to_world\"><lookat origin=\"0, 0, 4\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>\
<film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer name=\"height\" value=\"16\"/></film></sensor>\n\
<shape type=\"cube\"><transform name=\"to_world\"><scale x=\"3\" y=\"3\" z=\"0.5\"/></transform>\
<bsdf type=\"dielectric\"/>{interior}</shape>\n{rest}</scene>\n"
    );
    let path = dir.join(name);
    std::fs::write(&path, xml).unwrap();
    path
}

#[test]
fn a_slab_keeps_exp_minus_sigma_d_of_what_the_clear_slab_passes() {
    // The camera sees an emitter of radiance 1 through the slab. Both renders draw the same
    // random numbers and glass makes the same choices (the chains' roulette weighs the bounce's
    // weight, not the throughput), so each path through the absorbing slab keeps exp(−σ·L) of its
    // clear twin, L its length inside: d·sec θt for the straight paths, θt ≤ 4.7° here (pixel
    // rays within 7° of the axis, refracted by 1.5) so sec θt ≤ 1.0034. Paths that reflect
    // inside (2k more crossings) make at most R²/(1 − R²) = 0.16 % of the clear image (R ≤ 0.04
    // at these angles); the path tracer's roulette (from its third bounce) may treat them
    // differently in the two renders, so they move the ratio by at most twice that: 0.33 %.
    let d = scratch_dir("absorbing-slab");
    let emitter = "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"4\"/><translate z=\"-2\"/></transform>\
<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>\n";
    let clear = load_scene(&slab_scene(&d, "clear.xml", "", emitter)).unwrap();
    let tinted = load_scene(&slab_scene(&d, "tinted.xml", MEDIUM, emitter)).unwrap();
    assert!(tinted.scene.materials.iter().any(|m| m.interior == SIGMA), "the interior is read");
    let rays = clear.camera.unwrap().prepare(16, 16).unwrap();
    let (clear, tinted) = (Arc::new(clear.scene), Arc::new(tinted.scene));
    let share = 2.0 * 0.04f32.powi(2) / (1.0 - 0.04f32.powi(2));
    let (high, low) = ((-SIGMA).exp() * (1.0 + share), (-SIGMA * 1.0034).exp() * (1.0 - share));
    for engine in [Engine::Wavefront, Engine::Reference, Engine::Path] {
        for seed in 1..=3 {
            let s = Settings {
                width: 16,
                height: 16,
                spp: 8,
                photons: 1000,
                caustic_photons: 1000,
                seed,
                ..Settings::default()
            };
            let mean = |scene: &Arc<photonwave::scene::Scene>| {
                render(scene, &rays, &s, engine, None, &NoProgress).unwrap().0.mean()
            };
            let (a, b) = (mean(&tinted), mean(&clear));
            assert!(b.min_element() > 0.8, "{engine:?}: the clear slab passes most light: {b}");
            let ratio = a / b;
            assert!(
                ratio.cmple(high).all() && ratio.cmpge(low).all(),
                "{engine:?} seed {seed}: kept {ratio}, exp(−σd) = {} (allowed {low} to {high})",
                (-SIGMA).exp()
            );
        }
    }
}

#[test]
fn photons_through_an_absorbing_slab_keep_exp_minus_sigma_d() {
    // Sunlight straight down (−z) through the slab onto a black floor, where each photon that
    // passes is stored once. Photon roulette weighs the photon's power, so the absorbing run's
    // photons leaving the slab survive with q = max exp(−σd) = 0.82 and carry 1/q: the stored
    // power per channel is exp(−σ_c d)/q × (survivors / clear passes), unbiased with relative
    // σ = √((1 − q)/(q·n)) for n photons passed; held to 4σ plus the internal reflections' 0.16 %
    // at each of the 32 seeds.
    let d = scratch_dir("absorbing-photons");
    let rest = "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/><translate z=\"-2\"/></transform>\
<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf></shape>\n\
<emitter type=\"directional\"><vector name=\"direction\" value=\"0, 0, -1\"/><rgb name=\"irradiance\" value=\"1\"/></emitter>\n";
    let n = 20_000;
    let (tinted, clear) = (
        load_scene(&slab_scene(&d, "tinted.xml", MEDIUM, rest)).unwrap(),
        load_scene(&slab_scene(&d, "clear.xml", "", rest)).unwrap(),
    );
    let stored = |scene: &photonwave::scene::Scene, seed: u64| {
        let s = Settings { threads: 1, seed, ..Settings::default() };
        let pass = trace_photons(scene, &job(scene, &s), Domain::GlobalPhoton, n, &NoProgress);
        let power: Vec3 = pass.photons.iter().map(|p| p.power).sum();
        (power, pass.photons.len())
    };
    let want = (-SIGMA).exp();
    let q = want.max_element();
    let mut worst = 0.0f32;
    for seed in common::SEEDS {
        let ((a, _), (b, passed)) = (stored(&tinted.scene, seed), stored(&clear.scene, seed));
        assert!(passed > n as usize / 10, "photons reach the floor: {passed}");
        let sigma = ((1.0 - q) / (q * passed as f32)).sqrt();
        let got = a / b;
        let tol = want * (4.0 * sigma + 0.0016);
        worst = worst.max(((got - want).abs() / (want * sigma)).max_element());
        assert!((got - want).abs().cmple(tol).all(), "seed {seed}: kept {got}, exp(−σd) = {want} ± {tol}");
    }
    println!("worst deviation {worst:.2} σ");
}

#[test]
fn engines_agree_with_an_absorbing_block_at_any_thread_count() {
    // The Mitsuba gallery room with a block of the hall's tinted glass in view: camera, gather
    // and glossy rays and photons cross it; the wavefront engine's absorb stage and the
    // reference's per-hit transmittance agree per pixel in every term (1e-6), and the wavefront
    // engine is bit-identical at one and two threads.
    let block = format!(
        "<shape type=\"cube\"><transform name=\"to_world\"><scale x=\"0.1\" y=\"0.12\" z=\"0.05\"/>\
<translate x=\"0.05\" y=\"0.2\" z=\"0.15\"/></transform><bsdf type=\"dielectric\"/>{MEDIUM}</shape>"
    );
    let loaded = gallery_with(&scratch_dir("absorbing-engines"), &block);
    assert!(loaded.scene.materials.iter().any(|m| m.interior == SIGMA && matches!(m.bsdf, Bsdf::Glass { .. })));
    let a = assert_engines_agree(loaded);
    assert!(a.pixels.iter().filter(|p| p.specular != Vec3::ZERO).count() > 10, "the block is in view");
}

#[test]
fn interior_media_are_read_or_warned_of() {
    let d = scratch_dir("absorbing-readers");
    let light = "<emitter type=\"point\"><point name=\"position\" value=\"0, 0, 3\"/><rgb name=\"intensity\" value=\"1\"/></emitter>\n";
    // A medium defined at the top and referenced, with σ_a + σ_s and a scale; it scatters, so the
    // whole σ_t is taken and the scattering warned of.
    let rest = format!(
        "<medium type=\"homogeneous\" id=\"smoke\"><rgb name=\"sigma_a\" value=\"0.1, 0.2, 0.3\"/>\
<float name=\"sigma_s\" value=\"0.5\"/><float name=\"scale\" value=\"2\"/></medium>\n\
<shape type=\"sphere\"><bsdf type=\"roughdielectric\"/><ref name=\"interior\" id=\"smoke\"/></shape>\n\
<shape type=\"sphere\"><bsdf type=\"diffuse\"/>{MEDIUM}</shape>\n\
<shape type=\"disk\"><bsdf type=\"dielectric\"/><medium name=\"exterior\" type=\"homogeneous\"/></shape>\n\
<medium type=\"heterogeneous\" id=\"cloud\"/>\n{light}"
    );
    let loaded = load_scene(&slab_scene(&d, "media.xml", MEDIUM, &rest)).unwrap();
    let interiors: Vec<Vec3> = loaded.scene.materials.iter().map(|m| m.interior).filter(|i| *i != Vec3::ZERO).collect();
    assert!(interiors.contains(&SIGMA), "the slab's inline medium: {interiors:?}");
    assert!(interiors.contains(&Vec3::new(1.2, 1.4, 1.6)), "(σ_a + σ_s)·scale: {interiors:?}");
    assert_eq!(interiors.len(), 2, "a diffuse shape's interior is left out: {interiors:?}");
    let w = loaded.scene.warnings.join("\n");
    for want in [
        "the medium scatters (σ_s = [1, 1, 1])",
        "an interior medium is rendered only inside a solid dielectric",
        "the `exterior` medium is not read",
        "media.xml:8: this <medium> is no shape's interior",
    ] {
        assert!(w.contains(want), "{want}: {w}");
    }
    assert!(!w.contains("`interior` of"), "a read interior is not warned of as an unread property: {w}");
    // A negative σ is an error at its line.
    let bad = "<medium name=\"interior\" type=\"homogeneous\"><rgb name=\"sigma_t\" value=\"-1\"/></medium>";
    let e = load_scene(&slab_scene(&d, "bad.xml", bad, light)).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.contains("bad.xml:3") && e.contains("not negative"), "{e}");
    // TOML: `absorption` on glass; on an opaque material it is an unknown field.
    let toml = |material: &str| {
        let text = format!(
            "[[mesh]]\nshape = \"cube\"\nmaterial = \"m\"\n[materials.m]\n{material}\n\
[[light]]\ntype = \"point\"\nposition = [0, 5, 0]\nintensity = [1, 1, 1]\n"
        );
        let path = d.join("s.toml");
        std::fs::write(&path, text).unwrap();
        load_scene(&path)
    };
    let glass = toml("type = \"glass\"\nabsorption = [0.5, 0.2, 0.4]").unwrap();
    assert!(glass.scene.materials.iter().any(|m| m.interior == SIGMA));
    let e = toml("type = \"lambert\"\nkd = [0.5, 0.5, 0.5]\nabsorption = [1, 1, 1]").err().unwrap().to_string();
    assert!(e.contains("absorption"), "{e}");
    let e = toml("type = \"glass\"\nabsorption = [-1, 0, 0]").err().unwrap().to_string();
    assert!(e.contains("materials.m.absorption"), "{e}");
}
