//! A scene-filling participating medium (`[medium]`) in the path tracer, against analytic
//! answers: an absorbing medium keeps exp(−σ_a·d) of an emitter's light; a furnace (a closed
//! box whose walls all emit Le and reflect ρ) filled with a medium of albedo 1 stays at
//! Le/(1 − ρ) everywhere, with MIS and without; single scattering from a point light equals its
//! integral along the camera ray by quadrature; a glass cube of index 1 holding a white
//! scattering interior keeps the furnace at Le/(1 − ρ) too. The reference photon mapper's volume
//! photons carry the power an infinite medium scatters, its furnace stays at Le/(1 − ρ), and its
//! fog-filled Cornell box agrees with the path tracer, in one pass and progressively. Bad media are
//! errors naming the field; the wavefront engine refuses a scene-filling medium; Mitsuba's
//! scattering interior media are read whole.

mod common;

use common::{mean_and_se, scratch_dir};
use glam::Vec3;
use photonwave::engine::{render, Engine};
use photonwave::formats::{load_scene, LoadedScene};
use photonwave::progress::NoProgress;
use photonwave::settings::Settings;
use std::path::Path;
use std::sync::Arc;

/// Writes `name`.toml in `dir` with `body` and the OBJ/MTL files in `files`, and loads it.
fn scene(dir: &Path, name: &str, body: &str, files: &[(&str, &str)]) -> photonwave::error::Result<LoadedScene> {
    for (file, text) in files {
        std::fs::write(dir.join(file), text).unwrap();
    }
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, body).unwrap();
    load_scene(&path)
}

/// Path-traces `loaded` at `settings`' size.
fn path_traced(loaded: &LoadedScene, settings: &Settings) -> photonwave::film::Film {
    let rays = loaded.camera.unwrap().prepare(settings.width, settings.height).unwrap();
    photonwave::path::render_path_traced(&loaded.scene, &rays, settings, &NoProgress).unwrap().0
}

/// A 40×40 emitter of radiance 1 at z = −2 facing +z.
const EMITTER_OBJ: &str = "mtllib e.mtl\nv -20 -20 -2\nv 20 -20 -2\nv 20 20 -2\nv -20 20 -2\nusemtl light\nf 1 2 3 4\n";
const EMITTER_MTL: &str = "newmtl light\nKd 0 0 0\nKe 1 1 1\n";

#[test]
fn an_absorbing_medium_keeps_exp_minus_sigma_d() {
    // The camera at z = 2 looks at the emitter 4 away through a 2° field: every pixel ray's
    // length L is 4·sec θ ≤ 4 × 1.0003. With σ_s = 0 nothing scatters, and every ray passes
    // with exactly its transmittance exp(−σ_a·L) — in the path tracer and in the reference
    // photon mapper alike. Tolerance: the sec θ spread, σ_a·4·0.0003 ≤ 0.12 % of the value at
    // σ_a = 1, and float rounding; every pixel of every seed is checked.
    let d = scratch_dir("media-absorbing");
    let sigma = Vec3::new(0.25, 0.5, 1.0);
    let body = "[[mesh]]\nfile = \"e.obj\"\n[camera]\neye = [0, 0, 2]\ntarget = [0, 0, -2]\nfov = 2\n\
[medium]\nsigma_a = [0.25, 0.5, 1.0]\n";
    let loaded = scene(&d, "absorbing", body, &[("e.obj", EMITTER_OBJ), ("e.mtl", EMITTER_MTL)]).unwrap();
    let expected = (-sigma * 4.0).exp();
    let rays = loaded.camera.unwrap().prepare(8, 8).unwrap();
    let shared = Arc::new(loaded.scene);
    for seed in 1..4 {
        let settings = Settings { width: 8, height: 8, spp: 4, seed, ..Settings::default() };
        let path = photonwave::path::render_path_traced(&shared, &rays, &settings, &NoProgress).unwrap().0;
        let photons = render(&shared, &rays, &settings, Engine::Reference, None, &NoProgress).unwrap().0;
        for (engine, film) in [("path", &path), ("reference", &photons)] {
            for p in film.beauty() {
                let err = (p / expected - 1.0).abs().max_element();
                assert!(err < 1.5e-3, "{engine}, seed {seed}: {p} against exp(−σ_a·4) = {expected}");
            }
        }
    }
}

/// A closed cube [−1, 1]³ whose six walls face inward, reflect 0.5 and emit 1.
fn furnace_files() -> [(&'static str, &'static str); 2] {
    const OBJ: &str =
        "mtllib f.mtl\nv -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n\
usemtl wall\nf 1 2 3 4\nf 5 8 7 6\nf 1 5 6 2\nf 4 3 7 8\nf 1 4 8 5\nf 2 6 7 3\n";
    const MTL: &str = "newmtl wall\nKd 0.5 0.5 0.5\nKe 1 1 1\n";
    [("f.obj", OBJ), ("f.mtl", MTL)]
}

#[test]
fn a_furnace_filled_with_a_white_medium_stays_at_le_over_one_minus_rho() {
    // Every wall emits Le = 1 and reflects ρ = 0.5 inward, so without a medium the radiance is
    // Le/(1 − ρ) = 2 everywhere; a medium that only scatters (albedo 1) moves light between
    // directions and keeps it at 2 (the radiative transfer equation's uniform solution). A
    // forward-scattering phase function (g = 0.6) and σ_s = 1 (mean free path half the box)
    // give several medium vertices per path. Tolerance: 4 standard errors over the 8×8 pixels,
    // at each of 6 seeds, with MIS of lights against the phase function and BSDF and without.
    // The cap of 64 vertices (roulette ends paths before it) drops under 0.5^20 of the light.
    let d = scratch_dir("media-furnace");
    let body = "[[mesh]]\nfile = \"f.obj\"\n[camera]\neye = [0, 0, 0.5]\ntarget = [0, 0, -1]\nfov = 70\n\
[medium]\nalbedo = [1, 1, 1]\ndensity = 1.0\ng = 0.6\n";
    let loaded = scene(&d, "furnace", body, &furnace_files()).unwrap();
    assert!(loaded.scene.medium.is_some());
    for mis in [true, false] {
        for seed in 1..7 {
            let settings = Settings { width: 8, height: 8, spp: 256, seed, mis, ..Settings::default() };
            let film = path_traced(&loaded, &settings);
            let values = common::grey(&film);
            let (mean, se) = mean_and_se(&values);
            eprintln!("furnace mis {mis} seed {seed}: {mean:.4} ± {se:.4}");
            assert!((mean - 2.0).abs() <= 4.0 * se, "mis {mis} seed {seed}: {mean} ± {se}, want 2");
            assert!(se < 0.03, "mis {mis} seed {seed}: the test has no power (SE {se})");
        }
    }
}

/// An OBJ box [−w, w]² × [−h, h] along z of material `m` (from `c.mtl`), its faces outward.
fn box_obj(w: f32, h: f32, m: &str) -> String {
    let v: String = (0..8)
        .map(|i| {
            let (x, y, z) = ([-w, w, w, -w][i % 4], [-w, -w, w, w][i % 4], if i < 4 { -h } else { h });
            format!("v {x} {y} {z}\n")
        })
        .collect();
    format!("mtllib c.mtl\n{v}usemtl {m}\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n")
}

#[test]
fn a_scattering_interior_keeps_the_furnace_at_le_over_one_minus_rho() {
    // The furnace above without a scene-filling medium, holding a cube [−0.5, 0.5]³ of glass of
    // index 1 (no reflection, no bending) whose interior scatters (σ_s = 2, g = −0.3): paths
    // cross its faces as delta bounces and scatter inside; the radiance stays 2. Same
    // tolerances as above.
    let d = scratch_dir("media-interior");
    let cube = box_obj(0.5, 0.5, "clear");
    let [(fo, fobj), (fm, fmtl)] = furnace_files();
    let files = [(fo, fobj), (fm, fmtl), ("c.obj", cube.as_str()), ("c.mtl", "newmtl clear\nKd 0 0 0\n")];
    let body = "[[mesh]]\nfile = \"f.obj\"\n[[mesh]]\nfile = \"c.obj\"\n[camera]\neye = [0, 0, 0.9]\ntarget = [0, 0, -1]\nfov = 70\n\
[materials.clear]\ntype = \"glass\"\nior = 1.0\nscattering = [2, 2, 2]\ng = -0.3\n";
    let loaded = scene(&d, "interior", body, &files).unwrap();
    let inside = loaded.scene.materials.iter().find_map(|m| m.interior_scattering).expect("the interior is read");
    assert_eq!((inside.sigma_s, inside.g), (Vec3::splat(2.0), -0.3));
    for seed in 1..7 {
        let settings = Settings { width: 8, height: 8, spp: 256, seed, ..Settings::default() };
        let values = common::grey(&path_traced(&loaded, &settings));
        let (mean, se) = mean_and_se(&values);
        eprintln!("furnace with a scattering cube, seed {seed}: {mean:.4} ± {se:.4}");
        assert!((mean - 2.0).abs() <= 4.0 * se, "seed {seed}: {mean} ± {se}, want 2");
        assert!(se < 0.03, "seed {seed}: the test has no power (SE {se})");
    }
}

#[test]
fn a_scattering_interior_attenuates_once() {
    // The emitter seen through a cube of index-1 glass 1 thick whose interior absorbs σ_a = 1
    // and barely scatters (σ_s = 0.001): a pixel sees exp(−1.001) of the emitter's light, plus
    // light scattered into the ray, at most albedo × Le ≈ 0.001 (added to the tolerance with
    // 4 standard errors over the 8×8 pixels, at each of 4 seeds). Attenuating by free flight and
    // again by Beer–Lambert at the back face would give exp(−2).
    let d = scratch_dir("media-interior-once");
    let cube = box_obj(3.0, 0.5, "murky");
    let files = [
        ("e.obj", EMITTER_OBJ),
        ("e.mtl", EMITTER_MTL),
        ("c.obj", cube.as_str()),
        ("c.mtl", "newmtl murky\nKd 0 0 0\n"),
    ];
    let body = "[[mesh]]\nfile = \"e.obj\"\n[[mesh]]\nfile = \"c.obj\"\n[camera]\neye = [0, 0, 2]\ntarget = [0, 0, -2]\nfov = 2\n\
[materials.murky]\ntype = \"glass\"\nior = 1.0\nabsorption = [1, 1, 1]\nscattering = [0.001, 0.001, 0.001]\n";
    let loaded = scene(&d, "murky", body, &files).unwrap();
    let want = (-1.001f64).exp();
    for seed in 1..5 {
        let settings = Settings { width: 8, height: 8, spp: 64, seed, ..Settings::default() };
        let (mean, se) = mean_and_se(&common::grey(&path_traced(&loaded, &settings)));
        assert!((mean - want).abs() <= 4.0 * se + 0.001, "seed {seed}: {mean} ± {se}, exp(−σ_t·d) = {want}");
        assert!(se < 0.02, "seed {seed}: the test has no power (SE {se})");
    }
}

#[test]
fn shadow_rays_into_a_dielectric_leave_the_fog_outside() {
    // A point light inside a clear rough-glass cube [−0.5, 0.5]³, seen from 3 away through a fog
    // that only absorbs (σ_a = 0.5) and without it. Light sampling at the cube's faces reaches
    // the light through the glass without crossing the fog, so the foggy image is the clear one
    // times the camera segment's transmittance exp(−σ_a·t), t from 2.5 to 2.5 × 1.008 over the
    // 10° field (so within 1 % of exp(−1.25)). Both renders draw the same light and BSDF
    // samples; the fog only ends camera paths (free flight at bounce 0, dims 4–5). Tolerance on
    // the ratio of the image means: 4 standard errors over 6 seeds, plus that 1 %; shadow rays
    // attenuated by the fog inside the cube too (by up to exp(−0.43)) make it about 22 % low.
    let d = scratch_dir("media-globe");
    let cube = box_obj(0.5, 0.5, "globe");
    let files = [("c.obj", cube.as_str()), ("c.mtl", "newmtl globe\nKd 0 0 0\n")];
    let body = |fog: &str| {
        format!(
            "[[mesh]]\nfile = \"c.obj\"\n[camera]\neye = [0, 0, 3]\ntarget = [0, 0, 0]\nfov = 10\n\
[[light]]\ntype = \"point\"\nposition = [0, 0, 0]\nintensity = [1, 1, 1]\n\
[materials.globe]\ntype = \"rough_dielectric\"\nior = 1.5\nroughness = 0.4\n{fog}"
        )
    };
    let clear = scene(&d, "clear", &body(""), &files).unwrap();
    let foggy = scene(&d, "foggy", &body("[medium]\nsigma_a = [0.5, 0.5, 0.5]\n"), &files).unwrap();
    let t = (-1.25f64).exp();
    let ratios: Vec<f32> = (1..7)
        .map(|seed| {
            let settings = Settings { width: 16, height: 16, spp: 512, seed, ..Settings::default() };
            let (a, b) = (path_traced(&foggy, &settings).mean(), path_traced(&clear, &settings).mean());
            a.element_sum() / b.element_sum()
        })
        .collect();
    let (ratio, se) = mean_and_se(&ratios);
    eprintln!("globe: foggy ÷ clear = {ratio:.5} ± {se:.5}, exp(−1.25) = {t:.5}");
    assert!((ratio / t - 1.0).abs() <= 4.0 * se / t + 0.01, "foggy ÷ clear = {ratio} ± {se}, want {t}");
    assert!(se < 0.02 * t, "the test has no power (SE {se} against {t})");
}

#[test]
fn mitsuba_scattering_interiors_are_read_whole() {
    let d = scratch_dir("media-mitsuba");
    let xml = "<scene version=\"3.0.0\">\n<shape type=\"cube\"><bsdf type=\"dielectric\"/>\n\
<medium name=\"interior\" type=\"homogeneous\"><rgb name=\"sigma_t\" value=\"2, 2, 2\"/>\
<rgb name=\"albedo\" value=\"0.5, 0.75, 1\"/><phase type=\"hg\"><float name=\"g\" value=\"0.4\"/></phase></medium>\n\
</shape>\n<emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"3\" z=\"0\"/></emitter>\n</scene>\n";
    let path = d.join("milk.xml");
    std::fs::write(&path, xml).unwrap();
    let loaded = load_scene(&path).unwrap();
    let m = loaded.scene.materials.iter().find_map(|m| m.interior_scattering).expect("the scattering interior is kept");
    assert!((m.sigma_s - Vec3::new(1.0, 1.5, 2.0)).abs().max_element() < 1e-6, "{m:?}");
    assert!((m.sigma_a - Vec3::new(1.0, 0.5, 0.0)).abs().max_element() < 1e-6 && m.g == 0.4, "{m:?}");
    assert!(
        loaded.scene.warnings.iter().any(|w| w.contains("photon-mapping engines attenuate")),
        "{:?}",
        loaded.scene.warnings
    );
}

/// Single scattering along the ray from the origin down −z, from a point light of intensity
/// `i` at `light`, in a medium (σ_s, σ_t, g): ∫ σ_s T(t) p(cos θ) I T(r)/r² dt by Simpson's
/// rule over [0, 80] (T(80) = e^{−32}) in 400 000 steps.
fn single_scattering(i: f64, light: [f64; 3], sigma_s: f64, sigma_t: f64, g: f64) -> f64 {
    let n = 400_000;
    let (a, b) = (0.0, 80.0);
    let h = (b - a) / n as f64;
    let f = |t: f64| {
        let v = [light[0], light[1], light[2] + t];
        let r2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        let r = r2.sqrt();
        // The cosine between the camera ray's direction (0, 0, −1) and the way to the light.
        let cos = -v[2] / r;
        let p = (1.0 - g * g) / (4.0 * std::f64::consts::PI * (1.0 + g * g - 2.0 * g * cos).powf(1.5));
        sigma_s * (-sigma_t * t).exp() * p * i * (-sigma_t * r).exp() / r2
    };
    let mut sum = f(a) + f(b);
    for k in 1..n {
        sum += f(a + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    sum * h / 3.0
}

#[test]
fn single_scattering_from_a_point_light_matches_quadrature() {
    // max_depth = 1 keeps the light scattered once: the camera segment's medium vertex takes
    // the point light through the phase function; the next segment's vertex is past the cap.
    // One small black triangle far behind the camera is the scene's only geometry. The pixel
    // is 0.05° wide, so its rays leave within 0.0004 rad of −z; the integral changes by far
    // less than the tolerance over that. Tolerance: 4 standard errors of the mean of 16
    // seeds' pixels (each 4 096 samples), per channel. The medium differs by channel (σ_s
    // 0.3/0.2/0.1, σ_t 0.4/0.25/0.4), so the free flight's mixture weights are not the albedo.
    let d = scratch_dir("media-single");
    let obj = "mtllib b.mtl\nv -0.1 0 50\nv 0.1 0 50\nv 0 0.1 50\nusemtl black\nf 1 2 3\n";
    let mtl = "newmtl black\nKd 0 0 0\n";
    let body = "[[mesh]]\nfile = \"b.obj\"\n[camera]\neye = [0, 0, 0]\ntarget = [0, 0, -1]\nfov = 0.05\n\
[[light]]\ntype = \"point\"\nposition = [0, 1, -2]\nintensity = [10, 10, 10]\n\
[medium]\nsigma_a = [0.1, 0.05, 0.3]\nsigma_s = [0.3, 0.2, 0.1]\ng = 0.5\n";
    let loaded = scene(&d, "single", body, &[("b.obj", obj), ("b.mtl", mtl)]).unwrap();
    let pixels: Vec<Vec3> = (1..17)
        .map(|seed| {
            let settings = Settings { width: 1, height: 1, spp: 4096, max_depth: 1, seed, ..Settings::default() };
            path_traced(&loaded, &settings).beauty()[0]
        })
        .collect();
    for (c, (sigma_s, sigma_t)) in [(0.3, 0.4), (0.2, 0.25), (0.1, 0.4)].into_iter().enumerate() {
        let expected = single_scattering(10.0, [0.0, 1.0, -2.0], sigma_s, sigma_t, 0.5);
        let values: Vec<f32> = pixels.iter().map(|p| p[c]).collect();
        let (mean, se) = mean_and_se(&values);
        eprintln!("single scattering, channel {c}: {mean:.6} ± {se:.6}, quadrature {expected:.6}");
        assert!((mean - expected).abs() <= 4.0 * se, "channel {c}: {mean} ± {se}, quadrature {expected}");
        assert!(se < 0.02 * expected, "channel {c}: the test has no power (SE {se} against {expected})");
    }
}

#[test]
fn bad_media_are_named_and_engines_refuse_what_they_cannot_render() {
    let d = scratch_dir("media-bad");
    let files = [("e.obj", EMITTER_OBJ), ("e.mtl", EMITTER_MTL)];
    let head = "[[mesh]]\nfile = \"e.obj\"\n[camera]\neye = [0, 0, 2]\ntarget = [0, 0, -2]\n";
    for (medium, field) in [
        ("sigma_a = [-1, 0, 0]", "medium.sigma_a"),
        ("sigma_s = [0, 1e40, 0]", "medium.sigma_s"),
        ("sigma_s = [1, 1, 1]\ng = 1.0", "medium.g"),
        ("albedo = [1.2, 1, 1]\ndensity = 1", "medium.albedo"),
        ("albedo = [1, 1, 1]\ndensity = -2", "medium.density"),
        ("albedo = [1, 1, 1]\nsigma_s = [1, 1, 1]", "medium"),
        ("g = 0.3", "medium"),
    ] {
        let e = scene(&d, "bad", &format!("{head}[medium]\n{medium}\n"), &files).err().unwrap().to_string();
        assert!(e.contains(field), "`{medium}`: {e}");
    }
    let loaded = scene(&d, "fog", &format!("{head}[medium]\nsigma_s = [0.1, 0.1, 0.1]\n"), &files).unwrap();
    let rays = loaded.camera.unwrap().prepare(4, 4).unwrap();
    let settings = Settings { width: 4, height: 4, ..Settings::default() };
    let scene = Arc::new(loaded.scene);
    let e = render(&scene, &rays, &settings, Engine::Wavefront, None, &NoProgress).err().unwrap().to_string();
    assert!(e.contains("--engine") && e.contains("medium") && e.contains("--engine reference"), "{e}");
    assert!(render(&scene, &rays, &settings, Engine::Reference, None, &NoProgress).is_ok());
    // The CLI without --engine renders a medium with the reference engine, and says so.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_photonwave"))
        .args([
            "render",
            "--width",
            "4",
            "--height",
            "4",
            "--spp",
            "1",
            "--photons",
            "2000",
            "--caustic-photons",
            "1000",
        ])
        .arg(d.join("fog.toml"))
        .arg("-o")
        .arg(d.join("fog.exr"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && stderr.contains("engine: reference"), "{stderr}");
    assert!(d.join("fog.exr").exists());
    let job = common::job(&scene, &settings);
    assert!(job.plan.media.on && job.plan.media.reason.contains("scattering medium"), "{:?}", job.plan.media);
}

#[test]
fn volume_photons_carry_what_an_infinite_medium_scatters() {
    // A point light of intensity I = 10 (power Φ = 4π·I) in an infinite grey medium of
    // albedo a (σ_t = 1; the scene's one triangle lies 50 mean free paths away). Every photon
    // path interacts, and each event stores the power that scatters there: Φ·a at the first
    // (flagged direct), and after Russian roulette at the emitted power a path goes on with
    // probability a. So the direct photons carry Φ·a in all, and all of them Φ·a/(1 − a) (the
    // number of events is geometric with mean 1/(1 − a)). Tolerances: the direct total is
    // exact but for the RGBE rounding (dithered, < 0.1 % over 10⁵ photons); a path's total is
    // Φ·a·K with K's relative spread √a, and N photons come from N·(1 − a) paths, so the
    // total's relative SE is √a/√(N·(1 − a)): 0.32 % at a = 0.5, 0.63 % at a = 0.8; 4 of those.
    let d = scratch_dir("media-photons");
    let obj = "mtllib b.mtl\nv -0.1 0 50\nv 0.1 0 50\nv 0 0.1 50\nusemtl black\nf 1 2 3\n";
    let files = [("b.obj", obj), ("b.mtl", "newmtl black\nKd 0 0 0\n")];
    let phi = 4.0 * std::f64::consts::PI * 10.0;
    for (seed, a) in [(1, 0.5), (2, 0.8)] {
        let body = format!(
            "[[mesh]]\nfile = \"b.obj\"\n[camera]\neye = [0, 0, 0]\ntarget = [0, 0, -1]\n\
[[light]]\ntype = \"point\"\nposition = [0, 0, 0]\nintensity = [10, 10, 10]\n\
[medium]\nalbedo = [{a}, {a}, {a}]\ndensity = 1\ng = 0.4\n"
        );
        let loaded = scene(&d, "infinite", &body, &files).unwrap();
        let settings = Settings { photons: 100_000, seed, ..Settings::default() };
        let (maps, global, _) = photonwave::reference::build_maps(&loaded.scene, &settings).unwrap();
        assert_eq!((global.volume, maps.global.len()), (100_000, 0), "every photon lies in the medium");
        let (mut direct, mut all) = (0.0, 0.0);
        for i in 0..maps.volume.len() {
            let p = maps.volume.photon(i);
            let power = f64::from(p.power.x);
            all += power;
            if p.flags & photonwave::photon_map::flags::DIRECT != 0 {
                direct += power;
            }
        }
        let (want_direct, want_all) = (phi * a, phi * a / (1.0 - a));
        eprintln!("albedo {a}: direct {direct:.3} (Φa {want_direct:.3}), all {all:.3} (Φa/(1−a) {want_all:.3})");
        assert!((direct / want_direct - 1.0).abs() < 1e-3, "albedo {a}: direct {direct}, want {want_direct}");
        let se = (a / (100_000.0 * (1.0 - a))).sqrt();
        assert!((all / want_all - 1.0).abs() < 4.0 * se, "albedo {a}: all {all}, want {want_all} (SE {se})");
    }
}

#[test]
fn the_reference_engine_keeps_the_white_furnace() {
    // The white-medium furnace above (walls Le 1, ρ 0.5, albedo 1, g 0.6) in the reference
    // photon mapper: camera rays march the medium and take single scattering by light sampling
    // and the rest from the volume map; final-gather rays that stop there by free flight read
    // the whole volume map. The radiance is 2 everywhere, so the density estimates have no
    // gradient to blur; near a wall they divide by the part of their sphere inside the box.
    // Each seed's photon maps are shared by its pixels, so the seeds, not the pixels, are the
    // independent samples: the mean of 8 seeds within 4 of their standard errors of 2, and that
    // standard error below 0.5 %.
    let d = scratch_dir("media-furnace-photons");
    let body = "[[mesh]]\nfile = \"f.obj\"\n[camera]\neye = [0, 0, 0.5]\ntarget = [0, 0, -1]\nfov = 70\n\
[medium]\nalbedo = [1, 1, 1]\ndensity = 1.0\ng = 0.6\n";
    let loaded = scene(&d, "furnace", body, &furnace_files()).unwrap();
    let rays = loaded.camera.unwrap().prepare(16, 16).unwrap();
    let shared = Arc::new(loaded.scene);
    let means: Vec<f32> = (1..9)
        .map(|seed| {
            let settings = Settings { width: 16, height: 16, spp: 16, photons: 400_000, seed, ..Settings::default() };
            let film = render(&shared, &rays, &settings, Engine::Reference, None, &NoProgress).unwrap().0;
            let (mean, _) = mean_and_se(&common::grey(&film));
            mean as f32
        })
        .collect();
    let (mean, se) = mean_and_se(&means);
    eprintln!("reference furnace: {mean:.4} ± {se:.4} over seeds {means:?}");
    assert!((mean - 2.0).abs() <= 4.0 * se, "{mean} ± {se}, want 2");
    assert!(se < 0.01, "the test has no power (SE {se})");
}

/// Each pixel's grey value without the emitted layer (the light scattered toward the camera).
fn scattered(film: &photonwave::film::Film) -> Vec<f32> {
    let layers = film.layers();
    let emitted = &layers.iter().find(|(name, _)| name == "emitted").expect("an emitted layer").1;
    film.beauty().iter().zip(emitted).map(|(b, e)| (*b - *e).element_sum() / 3.0).collect()
}

#[test]
fn the_reference_engine_agrees_with_the_path_tracer_in_a_fog_box() {
    // The bundled Cornell box filled with fog (albedo 0.9, σ_t 1.5 per metre, g 0.3), seen from
    // inside at 24×24 pixels, the light scattered toward the camera compared (the image without
    // its emitted layer: the lamp seen straight on is the same in both and the noisiest part of
    // a small image's mean). The path tracer (4 seeds of 128 spp) is unbiased. The photon
    // mapper's volume estimates divide by the part of their sphere in the fog (`Walls`): at
    // 10⁵ photons r ≈ 4 cm, and a third of the box's volume lies within that of a wall. Measured
    // at 32² over 4 seeds against 4 096 spp (camera rays by free flight then): direct layer
    // 0.998 of the path tracer's, indirect 1.001 (0.970 with every sphere taken as whole). Each seed's maps are shared by its
    // pixels, so each side's mean is taken over its seeds with their spread as its standard
    // error; tolerance 4 standard errors of the difference plus 1 % for the estimates' blur of
    // the lamp's gradients. It catches gross errors (a volume estimate off by a factor, light
    // counted twice or lost); percent-level ones (the walls' correction, 3 % of the indirect
    // layer) are the unit tests' and BENCHMARKS.md's.
    let d = scratch_dir("media-fog-box");
    let obj = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.obj");
    let body = format!(
        "[[mesh]]\nfile = {obj:?}\n[camera]\neye = [0.0, 0.273, 0.27]\ntarget = [0.0, 0.273, -0.3]\nfov = 70\n\
[medium]\nalbedo = [0.9, 0.9, 0.9]\ndensity = 1.5\ng = 0.3\n"
    );
    let loaded = scene(&d, "fog-box", &body, &[]).unwrap();
    let rays = loaded.camera.unwrap().prepare(24, 24).unwrap();
    let shared = Arc::new(loaded.scene);
    let photon_means: Vec<f32> = (1..7)
        .map(|seed| {
            let settings = Settings { width: 24, height: 24, spp: 16, photons: 100_000, seed, ..Settings::default() };
            let film = render(&shared, &rays, &settings, Engine::Reference, None, &NoProgress).unwrap().0;
            mean_and_se(&scattered(&film)).0 as f32
        })
        .collect();
    let path_means: Vec<f32> = (1..5)
        .map(|seed| {
            let settings = Settings { width: 24, height: 24, spp: 128, seed, ..Settings::default() };
            let film = photonwave::path::render_path_traced(&shared, &rays, &settings, &NoProgress).unwrap().0;
            mean_and_se(&scattered(&film)).0 as f32
        })
        .collect();
    let ((photon, se_photon), (path, se_path)) = (mean_and_se(&photon_means), mean_and_se(&path_means));
    let se = (se_photon * se_photon + se_path * se_path).sqrt();
    eprintln!("fog box: photon mapping {photon:.5} ± {se_photon:.5} {photon_means:?}, path tracing {path:.5} ± {se_path:.5} {path_means:?}");
    assert!((photon - path).abs() <= 4.0 * se + 0.01 * path, "{photon} ± {se_photon} against {path} ± {se_path}");
    assert!(se < 0.015 * path, "the test has no power (SE {se} against {path})");
    // Progressive passes: fresh maps each pass, the volume radii shrinking by the 3-D sequence
    // (r³ by (i + α)/(i + 1)), fixed-radius estimates. 6 seeds of 8 passes (2·10⁴ photons and
    // 2 spp each); same tolerance. Measured at 32² against 4 096 spp (4 spp a pass, camera rays
    // by free flight then): beauty 0.993, 0.994 and 0.997 of the path tracer's after 4, 16 and
    // 64 passes, relMSE 1.2·10⁻², 3.5·10⁻³, 1.2·10⁻³.
    let progressive_means: Vec<f32> = (1..7)
        .map(|seed| {
            let settings =
                Settings { width: 24, height: 24, spp: 2, photons: 20_000, passes: 8, seed, ..Settings::default() };
            let film = render(&shared, &rays, &settings, Engine::Reference, None, &NoProgress).unwrap().0;
            mean_and_se(&scattered(&film)).0 as f32
        })
        .collect();
    let (progressive, se_progressive) = mean_and_se(&progressive_means);
    let se = (se_progressive * se_progressive + se_path * se_path).sqrt();
    eprintln!("fog box, 8 passes: {progressive:.5} ± {se_progressive:.5} {progressive_means:?}");
    assert!((progressive - path).abs() <= 4.0 * se + 0.01 * path, "{progressive} ± {se_progressive} against {path}");
    assert!(se < 0.015 * path, "the test has no power (SE {se} against {path})");
}

#[test]
fn media_render_the_same_at_any_thread_count() {
    // The fog box with a glass ball focusing a lamp (scenes/fog-lens.toml) in the reference
    // photon mapper, one pass and progressive: photon passes cut into batches, camera pixels into
    // chunks, and the volume maps built on every thread give the same bits on 1 and 2 threads.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fog-lens.toml");
    let loaded = load_scene(&path).unwrap();
    let rays = loaded.camera.unwrap().prepare(16, 16).unwrap();
    let scene = Arc::new(loaded.scene);
    for passes in [1, 3] {
        let image = |threads| {
            let settings = Settings {
                width: 16,
                height: 16,
                spp: 2,
                photons: 20_000,
                caustic_photons: 10_000,
                passes,
                threads,
                ..Settings::default()
            };
            let film = render(&scene, &rays, &settings, Engine::Reference, None, &NoProgress).unwrap().0;
            film.beauty().iter().map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>()
        };
        assert_eq!(image(1), image(2), "{passes} pass(es)");
    }
}
