//! Alpha cut-outs (`Material::opacity`: Mitsuba's `mask`, glTF's `alphaMode`, MTL's `map_d` and
//! `d`): a checkerboard mask passes half the shadow rays and half the photons, as coverage
//! (Mitsuba, MTL) and as a cutoff (glTF `MASK`), at each of 32 seeds; the photon-mapping
//! engines agree per pixel with a cut-out panel in the gallery room at any thread count; the
//! readers read what they name. (Every traversal kernel's agreement with cut-outs is in
//! tests/packet.rs.)

mod common;

use common::{assert_engines_agree, gallery_with, job, scratch_dir, SEEDS};
use glam::Vec3;
use photonwave::formats::load_scene;
use photonwave::material::AlphaMode;
use photonwave::progress::NoProgress;
use photonwave::reference::photons::trace_photons;
use photonwave::rng::{Domain, Sampler};
use photonwave::scene::Scene;
use photonwave::settings::Settings;
use photonwave::transport::estimate::global_estimate;
use photonwave::transport::{Context, PhotonMaps};
use std::path::Path;

/// Writes an 8×8 grey PNG checkerboard of 0 and 255.
fn write_checker(path: &Path) {
    write_checker_of(path, 8);
}

/// Writes an `n`×`n` grey PNG checkerboard of 0 and 255.
fn write_checker_of(path: &Path, n: u32) {
    let texels: Vec<u8> = (0..n * n).map(|k| if (k % n + k / n).is_multiple_of(2) { 255 } else { 0 }).collect();
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, n, n);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Eight);
        enc.write_header().unwrap().write_image_data(&texels).unwrap();
    }
    std::fs::write(path, bytes).unwrap();
}

const BLACK: &str = "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf>";

/// A Mitsuba scene in `dir`: a black square at z = 0 (x, y in [−2, 2]) in a `mask` whose opacity
/// is the checkerboard `checker.png`, over a black floor of the same size at z = −1, under
/// sunlight straight down. With `mode`, the mask is read as that instead (glTF's `MASK`).
fn masked_square(dir: &Path, mode: Option<AlphaMode>) -> Scene {
    write_checker(&dir.join("checker.png"));
    square_under_the_sun(
        dir,
        &format!(
            "<bsdf type=\"mask\"><texture name=\"opacity\" type=\"bitmap\">\
<string name=\"filename\" value=\"checker.png\"/></texture>{BLACK}</bsdf>"
        ),
        mode,
    )
}

/// [`masked_square`] with the square's BSDF `bsdf`.
fn square_under_the_sun(dir: &Path, bsdf: &str, mode: Option<AlphaMode>) -> Scene {
    let xml = format!(
        "<scene version=\"3.0.0\">\n\
<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"2\"/></transform>{bsdf}</shape>\n\
<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"2\"/><translate z=\"-1\"/></transform>{BLACK}</shape>\n\
<emitter type=\"directional\"><vector name=\"direction\" value=\"0, 0, -1\"/><rgb name=\"irradiance\" value=\"1\"/></emitter>\n</scene>\n"
    );
    let path = dir.join("masked.xml");
    std::fs::write(&path, xml).unwrap();
    let mut scene = load_scene(&path).unwrap().scene;
    let masks = scene.materials.iter_mut().filter_map(|m| m.opacity.as_mut()).collect::<Vec<_>>();
    if let Some(mode) = mode {
        for m in masks {
            m.mode = mode;
        }
    }
    scene
}

/// Whether the shadow ray from the floor point below (x, y) toward the sun is blocked.
fn blocked(scene: &Scene, x: f32, y: f32) -> bool {
    scene.occluded(Vec3::new(x, y, -0.999), Vec3::Z, f32::INFINITY)
}

#[test]
fn a_checkerboard_mask_passes_half_the_shadow_rays() {
    // Shadow rays rise from uniform points of the floor. The bilinear opacity of a 0/1
    // checkerboard averages ½ over the square (its texels' mean), and so does the share below
    // the cutoff ½ (the pattern shifted by one cell is its complement): either way a ray passes
    // with probability ½, so the share passed of n = 4096 rays is ½ within 4σ, σ = √(¼/n), at
    // each of 32 seeds.
    let d = scratch_dir("cut-out-shadows");
    let n = 4096u32;
    let sigma = (0.25 / f64::from(n)).sqrt();
    for (label, mode) in [("coverage", None), ("cutoff", Some(AlphaMode::Cutoff(0.5)))] {
        let scene = masked_square(&d, mode);
        assert_eq!(scene.cut_out_materials(), 1, "the mask is read");
        let mut worst = 0.0f64;
        for seed in SEEDS {
            let passed = (0..n)
                .filter(|&i| {
                    let s = Sampler::new(seed, Domain::Camera, u64::from(i));
                    !blocked(&scene, 4.0 * s.get(0, 0) - 2.0, 4.0 * s.get(0, 1) - 2.0)
                })
                .count();
            let share = passed as f64 / f64::from(n);
            worst = worst.max((share - 0.5).abs() / sigma);
            assert!((share - 0.5).abs() < 4.0 * sigma, "{label} seed {seed}: {share} of the shadow rays passed");
        }
        println!("{label}: worst deviation {worst:.2} σ");
    }
    // Under the cutoff the texel centres decide alone: opaque and clear alternate like the
    // texels, half of them each.
    let scene = masked_square(&d, Some(AlphaMode::Cutoff(0.5)));
    let centre = |i: i32| -2.0 + (i as f32 + 0.5) * 0.5;
    let grid: Vec<Vec<bool>> =
        (0..8).map(|i| (0..8).map(|j| blocked(&scene, centre(i), centre(j))).collect()).collect();
    for i in 0..8 {
        for j in 0..8 {
            if i < 7 {
                assert_ne!(grid[i][j], grid[i + 1][j], "cells ({i}, {j}) and ({}, {j})", i + 1);
            }
            if j < 7 {
                assert_ne!(grid[i][j], grid[i][j + 1], "cells ({i}, {j}) and ({i}, {})", j + 1);
            }
        }
    }
    assert_eq!(grid.iter().flatten().filter(|b| **b).count(), 32);
}

#[test]
fn a_checkerboard_mask_passes_half_the_photons() {
    // Sunlight straight down: every photon that reaches the square lands either on it (stopped
    // by an opaque texel) or on the floor below (passed), each stored once on the black surface.
    // Passing has probability ½ (see the shadow-ray test), so the floor's share of the n stored
    // photons is ½ within 4σ, σ = √(¼/n), at each of 32 seeds.
    let d = scratch_dir("cut-out-photons");
    for (label, mode) in [("coverage", None), ("cutoff", Some(AlphaMode::Cutoff(0.5)))] {
        let scene = masked_square(&d, mode);
        let mut worst = 0.0f64;
        for seed in SEEDS {
            let s = Settings { threads: 1, seed, ..Settings::default() };
            let pass = trace_photons(&scene, &job(&scene, &s), Domain::GlobalPhoton, 4000, &NoProgress);
            let stored = pass.photons.len();
            assert!(stored > 1000, "{label}: photons reach the square: {stored}");
            let floor = pass.photons.iter().filter(|p| p.position.z < -0.5).count();
            let share = floor as f64 / stored as f64;
            let sigma = (0.25 / stored as f64).sqrt();
            worst = worst.max((share - 0.5).abs() / sigma);
            assert!((share - 0.5).abs() < 4.0 * sigma, "{label} seed {seed}: {floor} of {stored} photons passed");
        }
        println!("{label}: worst deviation {worst:.2} σ");
    }
}

#[test]
fn engines_agree_with_a_cut_out_panel_at_any_thread_count() {
    // A checkerboard-masked panel in the gallery room, lit by its ceiling light: camera, shadow,
    // gather and glossy rays and photons all pass its clear texels and stop at its opaque ones,
    // in the wavefront kernels and in the reference engine's single rays alike.
    let d = scratch_dir("cut-out-engines");
    write_checker(&d.join("checker.png"));
    let panel = "<shape type=\"rectangle\"><transform name=\"to_world\"><scale x=\"0.15\" y=\"0.12\"/>\
<translate x=\"0.02\" y=\"0.28\" z=\"-0.1\"/></transform><bsdf type=\"mask\"><texture name=\"opacity\" type=\"bitmap\">\
<string name=\"filename\" value=\"checker.png\"/></texture><bsdf type=\"twosided\"><bsdf type=\"diffuse\">\
<rgb name=\"reflectance\" value=\"0.7, 0.6, 0.2\"/></bsdf></bsdf></bsdf></shape>";
    let loaded = gallery_with(&d, panel);
    assert_eq!(loaded.scene.cut_out_materials(), 1);
    assert!(!loaded.scene.encloses_lights, "light may leave through a cut-out's holes");
    assert_engines_agree(loaded);
}

#[test]
fn cut_outs_are_read_from_mitsuba_and_mtl() {
    let d = scratch_dir("cut-out-readers");
    // Mitsuba: the mask's default opacity is ½; a constant of 1 is no cut-out at all; an
    // emitter's mask is dropped with a warning (light sampling would disagree with its hits).
    let mitsuba = |name: &str, mask: &str, emitter: &str| {
        let xml = format!(
            "<scene version=\"3.0.0\">\n<shape type=\"rectangle\"><bsdf type=\"mask\">{mask}{BLACK}</bsdf>{emitter}</shape>\n\
<shape type=\"rectangle\"><translate z=\"-1\"/><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>\n</scene>\n"
        );
        std::fs::write(d.join(name), xml).unwrap();
        load_scene(&d.join(name)).unwrap().scene
    };
    let half = mitsuba("half.xml", "", "");
    let o = half.materials.iter().find_map(|m| m.opacity.clone()).expect("the default opacity");
    assert!(o.factor == 0.5 && o.texture.is_none() && o.mode == AlphaMode::Coverage, "{o:?}");
    let opaque = mitsuba("opaque.xml", "<float name=\"opacity\" value=\"1\"/>", "");
    assert_eq!(opaque.cut_out_materials(), 0);
    let lit = mitsuba("lit.xml", "", "<emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter>");
    assert_eq!(lit.cut_out_materials(), 0);
    assert!(lit.warnings.iter().any(|w| w.contains("not rendered on an emitter")), "{:?}", lit.warnings);
    // MTL: `d` (or 1 − `Tr`) times `map_d` (alpha, or grey without it) as coverage; a glass's
    // dissolve is its own transparency and is not read as a cut-out.
    write_checker(&d.join("checker.png"));
    let mtl = "newmtl leaf\nKd 0.2 0.6 0.1\nd 0.8\nmap_d checker.png\nnewmtl veil\nKd 0.5 0.5 0.5\nTr 0.25\n\
newmtl glass\nillum 7\nNi 1.5\nd 0.1\nnewmtl light\nKe 1 1 1\n";
    std::fs::write(d.join("m.mtl"), mtl).unwrap();
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 -1\nv 1 0 -1\nv 0 1 -1\nvt 0 0\nvt 1 0\nvt 0 1\n\
usemtl leaf\nf 1/1 2/2 3/3\nusemtl veil\nf 1/1 3/3 2/2\nusemtl glass\nf 4/1 5/2 6/3\nusemtl light\nf 4/1 6/3 5/2\n";
    std::fs::write(d.join("m.obj"), obj).unwrap();
    std::fs::write(d.join("m.toml"), "[[mesh]]\nfile = \"m.obj\"\n").unwrap();
    let loaded = load_scene(&d.join("m.toml")).unwrap();
    let named = |n: &str| loaded.scene.materials.iter().find(|m| m.name == n).unwrap().opacity.clone();
    let leaf = named("leaf").expect("map_d is read");
    assert!(leaf.factor == 0.8 && leaf.mode == AlphaMode::Coverage, "{leaf:?}");
    let texels = &leaf.texture.as_ref().expect("the map_d texture").texels;
    assert!(texels.iter().all(|t| *t == Vec3::ONE || *t == Vec3::ZERO) && texels.contains(&Vec3::ZERO));
    assert_eq!(named("veil").map(|o| o.factor), Some(0.75));
    assert!(named("glass").is_none());
    let w = loaded.scene.warnings.join("\n");
    assert!(w.contains("d or map_d on a glass"), "{w}");
    assert_eq!(loaded.scene.cut_out_materials(), 2);
}

#[test]
fn density_estimates_on_a_cut_out_count_only_its_present_part() {
    // A grey square (kd 0.5) under the sun, cut out by a 64×64 checkerboard (cells of 6 cm), is
    // read by the global map's k-nearest estimate at 256 points on its opaque cells: each disk
    // (r ≈ 0.15) spans many cells, half of whose area is absent, so an estimate dividing by the
    // whole disk reads half (0.505 measured). Divided by the present share it reads what the same
    // square without a mask reads: the mean ratio is 1 within 6 % at each of 8 seeds, as coverage
    // and as a cutoff. The ratio's spread over the seeds is 1.0–1.6 % (the photon counts' noise,
    // shared by every point; its mean over them 0.997–1.003), so 6 % is at least 3.7σ.
    let d = scratch_dir("cut-out-density");
    write_checker_of(&d.join("fine.png"), 64);
    let grey = "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.5\"/></bsdf>";
    let masked = format!(
        "<bsdf type=\"mask\"><texture name=\"opacity\" type=\"bitmap\"><string name=\"filename\" value=\"fine.png\"/>\
</texture>{grey}</bsdf>"
    );
    let mean_estimate = |scene: &Scene, seed: u64| {
        let s = Settings { threads: 1, seed, photons: 40_000, ..Settings::default() };
        let job = job(scene, &s);
        let global = trace_photons(scene, &job, Domain::GlobalPhoton, s.photons, &NoProgress).photons;
        let maps = PhotonMaps::build(scene, &job, global, vec![]);
        let ctx = Context::new(scene, &maps, &job);
        let mut scratch = Default::default();
        let mut sum = 0.0f64;
        let mut n = 0;
        for i in 0..4096u64 {
            let sampler = Sampler::new(seed, Domain::Camera, i);
            let (x, y) = (3.0 * sampler.get(0, 0) - 1.5, 3.0 * sampler.get(0, 1) - 1.5);
            let Some(hit) = scene.intersect(Vec3::new(x, y, 1.0), Vec3::NEG_Z, 1.5) else { continue };
            let sp = scene.surface(&hit);
            let e = global_estimate(&ctx, &sp, &scene.bsdf(&sp), Vec3::Z, 0, None, &mut scratch).finish(&ctx);
            sum += f64::from(e.radiance.x);
            n += 1;
            if n == 256 {
                break;
            }
        }
        assert_eq!(n, 256, "points on the square");
        sum / f64::from(n)
    };
    let plain = square_under_the_sun(&d, grey, None);
    for (label, mode) in [("coverage", None), ("cutoff", Some(AlphaMode::Cutoff(0.5)))] {
        let cut = square_under_the_sun(&d, &masked, mode);
        assert_eq!(cut.cut_out_materials(), 1);
        for seed in 1..=8 {
            let ratio = mean_estimate(&cut, seed) / mean_estimate(&plain, seed);
            assert!((ratio - 1.0).abs() < 0.06, "{label} seed {seed}: the cut-out reads {ratio} of the whole square");
        }
    }
}
