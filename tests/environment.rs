//! Environment and sun light against their known answers: a white Lambertian surface that sees
//! only the sky returns albedo·L by light sampling and by the photon map, a sun puts E⊥·cos θ on
//! a plane, escaped camera rays see the sky, both engines agree, and bad `[environment]` and sun
//! settings are refused by name.

mod common;

use common::*;
use glam::Vec3;
use photonwave::code_path::CodePath;
use photonwave::formats::load_scene;
use photonwave::material::{Bsdf, Material};
use photonwave::photon_map::{Filter, Lookup, Nearest, PhotonMap, Reflectance};
use photonwave::progress::NoProgress;
use photonwave::reference::photons::trace_photons;
use photonwave::rng::{Domain, Sampler};
use photonwave::scene::{Environment, Light, MeshInput, Scene};
use photonwave::settings::{Kernel, Settings};
use photonwave::transport::direct::direct_light;
use photonwave::transport::{Context, PhotonMaps};
use std::sync::Arc;

const KD: f32 = 0.8;

/// A floor [-10, 10]² at y = 0: two-sided, so its top sees exactly the upper hemisphere.
fn floor() -> MeshInput {
    let half = 10.0;
    MeshInput {
        source: "floor".into(),
        positions: vec![
            Vec3::new(-half, 0.0, -half),
            Vec3::new(half, 0.0, -half),
            Vec3::new(half, 0.0, half),
            Vec3::new(-half, 0.0, half),
        ],
        triangles: vec![[0, 2, 1], [0, 3, 2]],
        material: vec![0, 0],
        ..Default::default()
    }
}

fn white() -> Material {
    Material::new("white", Bsdf::Lambert { kd: Vec3::splat(KD) }, Vec3::ZERO)
}

/// Light sampling at the floor's centre, `n` independent estimates of the red channel: (mean,
/// standard error).
fn sampled_direct(scene: &Scene, n: u64) -> (f64, f64) {
    let settings = Settings::default();
    let job = job(scene, &settings);
    let maps = PhotonMaps::default();
    let ctx = Context::new(scene, &maps, &job);
    let values: Vec<f32> = (0..n)
        .map(|i| {
            let s = Sampler::new(7, Domain::Camera, i);
            direct_light(&ctx, &floor_point(Vec3::ZERO), &white().bsdf, Vec3::Y, &s, &mut Default::default()).x
        })
        .collect();
    mean_and_se(&values)
}

/// The global map's estimate (direct photons included, box kernel, k = 400) averaged over 64
/// points of the floor's middle: relative σ ≈ 1/√398 = 5 % per lookup, 0.6 % over the 64.
fn photon_estimate(scene: &Scene) -> f32 {
    let settings = Settings { photons: 400_000, max_depth: 1, ..Default::default() };
    let photons = trace_photons(
        scene,
        &job(scene, &Settings { threads: 2, ..settings.clone() }),
        Domain::GlobalPhoton,
        400_000,
        &NoProgress,
    )
    .photons;
    let maps = PhotonMaps { global: PhotonMap::build(photons), ..Default::default() };
    let mut scratch = Nearest::default();
    let mut sum = 0.0;
    for i in 0..8 {
        for j in 0..8 {
            let sp = floor_point(Vec3::new(-4.0 + i as f32, 0.0, -4.0 + j as f32));
            let q = Lookup {
                p: sp.p,
                k: 400,
                r_max: 1.0,
                kernel: Kernel::Box,
                filter: Filter { n: Vec3::Y, flags_mask: 0, plane: 0.0, slack: 0.0 },
            };
            let eval = |wi| white().bsdf.eval(&sp.frame, Vec3::Y, wi);
            sum += maps.global.estimate(CodePath::Simd, &q, Reflectance::PerPhoton(&eval), &mut scratch).radiance.x;
        }
    }
    sum / 64.0
}

#[test]
fn a_white_surface_under_a_constant_sky_returns_albedo_times_its_radiance() {
    // E = ∫ L cos dω over the upper hemisphere = πL, so L_out = kd·L: by light sampling (each
    // sample 4·kd·L·cos⁺ with pdf 1/4π; the mean of 20 000 within 4 standard errors) and by the
    // photon map (photons from a disk covering the scene, 3 % as for the directional light).
    let l = 1.25f32;
    let scene =
        Scene::build_lit(vec![floor()], vec![white()], vec![], Some(Environment::constant(Vec3::splat(l))), vec![])
            .unwrap();
    let want = f64::from(KD * l);
    let (m, se) = sampled_direct(&scene, 20_000);
    assert!((m - want).abs() <= 4.0 * se, "light sampling {m} ± {se} against kd·L = {want}");
    let photon = f64::from(photon_estimate(&scene));
    assert!((photon - want).abs() < 0.03 * want, "photons {photon} against kd·L = {want}");
}

#[test]
fn a_sun_puts_its_irradiance_times_cosine_on_a_plane() {
    // A disk of angular radius 5° whose axis is 60° from the normal lies wholly above the
    // horizon: E = E⊥·cos 60° exactly (the cosine averages over the disk to its axis's), so
    // L_out = kd·E⊥·cos 60°/π by light sampling (4 standard errors) and by photons (3 %).
    let e_perp = 3.0f32;
    let th = 60f32.to_radians();
    let half = (2.5f32).to_radians().sin();
    let sun = Light::Sun {
        direction: Vec3::new(th.sin(), -th.cos(), 0.0),
        irradiance: Vec3::splat(e_perp),
        one_minus_cos: 2.0 * half * half,
    };
    let scene = Scene::build(vec![floor()], vec![white()], vec![sun], vec![]).unwrap();
    let want = f64::from(KD * e_perp * th.cos() / std::f32::consts::PI);
    let (m, se) = sampled_direct(&scene, 4_000);
    assert!((m - want).abs() <= 4.0 * se.max(1e-6 * want), "light sampling {m} ± {se} against {want}");
    let photon = f64::from(photon_estimate(&scene));
    assert!((photon - want).abs() < 0.03 * want, "photons {photon} against {want}");
}

/// A unit cube (convex, white) under a constant sky of radiance `SKY`, seen from a corner.
const SKY: [f32; 3] = [1.0, 0.5, 0.25];

fn cube_scene(dir: &std::path::Path) -> std::path::PathBuf {
    let obj = "mtllib c.mtl\nusemtl white\n\
        v -0.5 -0.5 -0.5\nv 0.5 -0.5 -0.5\nv 0.5 0.5 -0.5\nv -0.5 0.5 -0.5\n\
        v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0.5 0.5 0.5\nv -0.5 0.5 0.5\n\
        f 1 4 3 2\nf 5 6 7 8\nf 1 5 8 4\nf 2 3 7 6\nf 4 8 7 3\nf 1 2 6 5\n";
    std::fs::write(dir.join("c.obj"), obj).unwrap();
    std::fs::write(dir.join("c.mtl"), format!("newmtl white\nKd {KD} {KD} {KD}\n")).unwrap();
    let toml = format!(
        "[[mesh]]\nfile = \"c.obj\"\n[camera]\neye = [2, 1.6, 2.4]\ntarget = [0, 0, 0]\nfov = 40\n\
         [environment]\nradiance = [{}, {}, {}]\n",
        SKY[0], SKY[1], SKY[2]
    );
    let path = dir.join("cube.toml");
    std::fs::write(&path, toml).unwrap();
    path
}

#[test]
fn both_engines_see_the_sky_and_agree_per_pixel() {
    let dir = scratch_dir("sky-cube");
    let path = cube_scene(&dir);
    let s = Settings { width: 32, height: 32, spp: 4, photons: 20_000, gather_rays: 4, ..Default::default() };
    let loaded = load_scene(&path).unwrap();
    let a = render(&loaded, &s);
    let rays = loaded.camera.unwrap().prepare(s.width, s.height).unwrap();
    let wavefront = |threads: u32| {
        let scene = load_scene(&path).unwrap().scene;
        photonwave::wavefront::render(Arc::new(scene), &rays, &Settings { threads, ..s.clone() }, &NoProgress)
            .unwrap()
            .0
    };
    let (b1, b2) = (wavefront(1), wavefront(2));
    assert_eq!(b1.pixels, b2.pixels, "the wavefront engine is bit-identical across thread counts");
    assert_terms_agree(&a, &b1, 1e-6);
    // Camera rays that leave the scene see the sky exactly, so a pixel's `emitted` is k/4 of it
    // for the k of its 4 samples that miss the cube. The cube's pixels (convex: no
    // interreflection, no caustics) return kd·L on average, within 4 standard errors of their
    // spread.
    let sky = Vec3::from_array(SKY);
    let (mut background, mut cube) = (0, Vec::new());
    for p in &a.pixels {
        let k = (p.emitted.x / sky.x * 4.0).round();
        assert!((p.emitted - sky * k / 4.0).abs().max_element() < 1e-6, "emitted {} is not k/4 of the sky", p.emitted);
        if k == 4.0 {
            assert_eq!(p.direct + p.indirect, Vec3::ZERO);
            background += 1;
        } else if k == 0.0 {
            assert_eq!(p.caustic, Vec3::ZERO);
            cube.push((p.direct + p.indirect).x / sky.x);
        }
    }
    assert!(background > 300 && cube.len() > 200, "{background} background and {} cube pixels", cube.len());
    let (m, se) = mean_and_se(&cube);
    assert!((m - f64::from(KD)).abs() <= 4.0 * se, "cube {m} ± {se} against kd = {KD}");
    // The path tracer weighs its sky samples against its next bounce (MIS): the cube's pixels
    // return kd·L too, with and without MIS.
    for mis in [true, false] {
        let pt = render_path(&loaded, &Settings { mis, ..s.clone() });
        let cube: Vec<f32> = pt
            .pixels
            .iter()
            .zip(&a.pixels)
            .filter(|(_, p)| p.emitted == Vec3::ZERO)
            .map(|(t, _)| (t.beauty() - t.emitted).x / sky.x)
            .collect();
        let (m, se) = mean_and_se(&cube);
        assert!((m - f64::from(KD)).abs() <= 4.0 * se, "path tracer (mis {mis}): cube {m} ± {se} against kd = {KD}");
    }
}

#[test]
fn bad_environment_and_sun_settings_are_refused_by_name() {
    let dir = scratch_dir("sky-bad");
    let path = cube_scene(&dir);
    let text = std::fs::read_to_string(&path).unwrap();
    let sky = text.lines().last().unwrap().to_string();
    let try_with = |replacement: &str| {
        std::fs::write(&path, text.replace(&sky, replacement)).unwrap();
        load_scene(&path).err().map(|e| e.to_string()).unwrap_or_default()
    };
    let e = try_with("radiance = [1, 1, 1]\nmap = \"sky.exr\"");
    assert!(e.contains("`environment`") && e.contains("not both"), "{e}");
    let e = try_with("map = \"sky.exr\"");
    assert!(e.contains("sky.exr") && e.contains("environment.map"), "{e}");
    let e = try_with("radiance = [1, 1, 1]\nscale = -2");
    assert!(e.contains("environment.scale"), "{e}");
    // A square map is not lat-long.
    let mut square = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut square, 4, 4);
        enc.set_color(png::ColorType::Rgb);
        enc.write_header().unwrap().write_image_data(&[100; 48]).unwrap();
    }
    std::fs::write(dir.join("square.png"), square).unwrap();
    let e = try_with("map = \"square.png\"");
    assert!(e.contains("environment.map") && e.contains("square.png") && e.contains("4×4"), "{e}");
    let e = try_with(
        "radiance = [1, 1, 1]\n[[light]]\ntype = \"sun\"\ndirection = [0, -1, 0]\nirradiance = [1, 1, 1]\nangle = 0",
    );
    assert!(e.contains("light[0].angle"), "{e}");
}
