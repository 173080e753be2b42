//! Aimed caustic photons (`transport::aim`) carry the same caustic light as photons emitted in
//! every direction — in total and where it lands — from far fewer emitted paths, for every kind
//! of light.

mod common;

use common::*;
use glam::Vec3;
use photonwave::formats::load_scene;
use photonwave::photon_map::Photon;
use photonwave::progress::NoProgress;
use photonwave::reference::photons::trace_photons;
use photonwave::rng::Domain;
use photonwave::scene::Scene;
use photonwave::settings::Settings;

/// A scene's caustic photons, aimed or not: (photons, paths emitted).
fn caustics(scene: &Scene, aim: bool, n: u32) -> (Vec<Photon>, u64) {
    let s = Settings { aim_caustics: aim, threads: 2, ..Default::default() };
    let t = trace_photons(scene, &job(scene, &s), Domain::CausticPhoton, n, &NoProgress);
    (t.photons, t.emitted)
}

/// Caustic flux in each cell of a 4 × 4 × 4 grid over the scene's box, with its variance.
/// A caustic path stores at most one photon, so the paths are independent samples of
/// (power·N or 0): the variance of the flux Σ p is Σ p² − (Σ p)²/N per channel.
fn flux_grid(scene: &Scene, photons: &[Photon], emitted: u64) -> Vec<(Vec3, Vec3)> {
    let (lo, hi) = scene.bounds;
    let mut cells = vec![(Vec3::ZERO, Vec3::ZERO); 64];
    for p in photons {
        let t = ((p.position - lo) / (hi - lo).max(Vec3::splat(1e-6)) * 4.0).clamp(Vec3::ZERO, Vec3::splat(3.0));
        let k = t.x as usize + 4 * t.y as usize + 16 * t.z as usize;
        cells[k].0 += p.power;
        cells[k].1 += p.power * p.power;
    }
    cells.into_iter().map(|(sum, sq)| (sum, (sq - sum * sum / emitted as f32).max(Vec3::ZERO))).collect()
}

/// Aimed and unaimed caustic flux agree in total and in every cell, within 4.5 standard errors
/// of their difference (64 cells × 3 channels: a right pair fails somewhere about 0.1 % of the
/// time); returns stored per emitted path, aimed over unaimed.
fn agree(name: &str, scene: &Scene, n: u32) -> f64 {
    let (a, na) = caustics(scene, true, n);
    let (u, nu) = caustics(scene, false, n);
    assert!(!a.is_empty() && !u.is_empty(), "{name}: no caustic photons");
    let (ga, gu) = (flux_grid(scene, &a, na), flux_grid(scene, &u, nu));
    let total = |g: &[(Vec3, Vec3)]| g.iter().fold((Vec3::ZERO, Vec3::ZERO), |s, c| (s.0 + c.0, s.1 + c.1));
    let (ta, tu) = (total(&ga), total(&gu));
    for (what, (fa, va), (fu, vu)) in
        std::iter::once(("total", ta, tu)).chain(ga.iter().zip(&gu).map(|(x, y)| ("cell", *x, *y)))
    {
        let tol = 4.5 * (va + vu).powf(0.5) + Vec3::splat(1e-9);
        assert!(
            ((fa - fu).abs() - tol).max_element() <= 0.0,
            "{name} {what}: aimed flux {fa} against unaimed {fu} (4.5σ = {tol})"
        );
    }
    (a.len() as f64 / na as f64) / (u.len() as f64 / nu as f64)
}

#[test]
fn aimed_caustics_carry_the_same_light_from_fewer_paths() {
    // The glass-sphere box, lit by its ceiling light: measured 12.0× more stored per emitted
    // path (BENCHMARKS.md); the test asks for 8×.
    let spheres = load("cornell-spheres.toml").scene;
    let gain = agree("cornell-spheres", &spheres, 40_000);
    assert!(gain > 8.0, "stored per emitted path rose only {gain:.2}×");
}

#[test]
fn every_kind_of_light_aims_without_bias() {
    let dir = scratch_dir("aim-lights");
    let obj = bundled("cornell-spheres.obj");
    // Point, spot and directional lights with the box's own light.
    let delta = format!(
        "[[mesh]]\nfile = {:?}\n\
         [[light]]\ntype = \"point\"\nposition = [0.1, 0.45, 0.1]\nintensity = [0.05, 0.05, 0.05]\n\
         [[light]]\ntype = \"spot\"\nposition = [-0.2, 0.5, 0.2]\ntarget = [0.13, 0.0, 0.08]\nintensity = [0.2, 0.1, 0.05]\nangle = 25\ninner_angle = 15\n\
         [[light]]\ntype = \"directional\"\ndirection = [0.2, -1.0, -0.3]\nirradiance = [0.3, 0.3, 0.3]\n",
        obj.to_str().unwrap()
    );
    std::fs::write(dir.join("delta.toml"), delta).unwrap();
    agree("point, spot, directional", &load_scene(&dir.join("delta.toml")).unwrap().scene, 40_000);
    // A glass ball on a floor under a sun (5°) and a constant sky: distant lights only.
    let mut obj =
        String::from("mtllib s.mtl\nusemtl floor\nv -3 0 -3\nv 3 0 -3\nv 3 0 3\nv -3 0 3\nf 1 4 3 2\nusemtl glass\n");
    let (nu, nv) = (24, 12);
    for j in 0..=nv {
        for i in 0..nu {
            let (th, ph) =
                (std::f32::consts::PI * j as f32 / nv as f32, 2.0 * std::f32::consts::PI * i as f32 / nu as f32);
            obj += &format!("v {} {} {}\n", 0.5 * th.sin() * ph.cos(), 0.6 + 0.5 * th.cos(), 0.5 * th.sin() * ph.sin());
        }
    }
    let v = |i: usize, j: usize| 5 + j * nu + i % nu;
    for j in 0..nv {
        for i in 0..nu {
            obj += &format!("f {} {} {} {}\n", v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
        }
    }
    std::fs::write(dir.join("s.obj"), obj).unwrap();
    std::fs::write(dir.join("s.mtl"), "newmtl floor\nKd 0.8 0.8 0.8\nnewmtl glass\nillum 7\nNi 1.5\n").unwrap();
    let sky = "[[mesh]]\nfile = \"s.obj\"\n\
               [[light]]\ntype = \"sun\"\ndirection = [0.3, -1.0, 0.2]\nirradiance = [3, 3, 3]\nangle = 5\n\
               [environment]\nradiance = [0.3, 0.4, 0.6]\n";
    std::fs::write(dir.join("sky.toml"), sky).unwrap();
    agree("sun and sky", &load_scene(&dir.join("sky.toml")).unwrap().scene, 40_000);
}
