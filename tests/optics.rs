//! Hard cases with an optical answer (scenes/hard/): the cosine law, light through glass, a ball
//! lens, a light pipe, a watertight cube — each at every one of [`common::SEEDS`], the worst seed
//! asserted. The photon maps alternate between the engines by seed (even: the oracle, odd: the
//! wavefront engine; they hold the same photons, tests/wavefront.rs). Each claim about a
//! proportion of photons is checked twice: every seed within 5 of its own standard errors (a
//! normal excess of 5σ has chance 6·10⁻⁷, so over the 32 seeds of a test a chance failure is
//! below 10⁻⁴), and the seeds pooled within 5 of the pooled standard error — √32 times tighter.

mod common;

use glam::Vec3;
use photonwave::engine::{render, Engine};
use photonwave::formats::{load_scene, LoadedScene};
use photonwave::progress::NoProgress;
use photonwave::settings::Settings;
use photonwave::transport::PhotonMaps;
use std::path::PathBuf;
use std::sync::Arc;

fn hard(name: &str) -> LoadedScene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/hard").join(name);
    load_scene(&path).unwrap_or_else(|e| panic!("{name}: {e}"))
}

const ENGINES: [Engine; 2] = [Engine::Wavefront, Engine::Reference];

/// The photon maps of `s` at `seed`, from the engine whose turn it is; with its name.
fn maps_at(scene: &Arc<photonwave::scene::Scene>, s: &Settings, seed: u64) -> (&'static str, PhotonMaps) {
    let s = Settings { seed, threads: 1, ..s.clone() };
    if seed.is_multiple_of(2) {
        ("reference", photonwave::reference::build_maps(scene, &s).unwrap().0)
    } else {
        ("wavefront", photonwave::wavefront::build_maps(scene.clone(), &s).unwrap().0)
    }
}

/// A ratio that should be 1, measured at each seed with a relative standard error: asserts each
/// seed within 5 of its errors plus `allowance`, and the seeds' mean (weighted equally) within 5
/// pooled errors plus `allowance`. Returns the seeds' mean.
fn ratio_at_every_seed(what: &str, per_seed: &[(u64, f64, f64)], allowance: f64) -> f64 {
    let n = per_seed.len() as f64;
    let mean = per_seed.iter().map(|r| r.1).sum::<f64>() / n;
    let pooled = (per_seed.iter().map(|r| r.2 * r.2).sum::<f64>()).sqrt() / n;
    let worst = per_seed.iter().max_by(|a, b| ((a.1 - 1.0) / a.2).abs().total_cmp(&((b.1 - 1.0) / b.2).abs())).unwrap();
    println!(
        "{what}: seeds' mean {mean:.4} ± {pooled:.4}; worst seed {} at {:.4} ± {:.4} ({:+.1} errors)",
        worst.0,
        worst.1,
        worst.2,
        (worst.1 - 1.0) / worst.2
    );
    for &(seed, r, se) in per_seed {
        assert!((r - 1.0).abs() <= 5.0 * se + allowance, "{what}, seed {seed}: {r} ± {se}");
    }
    assert!((mean - 1.0).abs() <= 5.0 * pooled + allowance, "{what}: seeds' mean {mean} ± {pooled}");
    mean
}

/// Case 5: a directional light θ from a plane's normal gives irradiance E⊥·cos θ (catches a
/// doubled or missing cosine), at θ = 0°, 60°, 85° and 89°:
/// - light sampling, both engines, one seed: every pixel's direct term is kd/π · cos θ (a delta
///   light — one unblocked shadow ray per sample — so only rounding separates them: 1e-5
///   relative, at any seed);
/// - photons, at every seed: a box-kernel estimate of radius 0.8 at the plane's centre. Its
///   photons have equal power, so its relative standard error is 1/√count (count ≈ 10 000 ·
///   π·0.8²/4 ≈ 5 000).
#[test]
fn grazing_light_follows_the_cosine_law() {
    use photonwave::code_path::CodePath;
    use photonwave::photon_map::{Filter, Lookup, Reflectance};
    use photonwave::settings::Kernel;
    for deg in [0u32, 60, 85, 89] {
        let loaded = hard(&format!("grazing-{deg}.toml"));
        let cos = (deg as f32).to_radians().cos();
        let scene = Arc::new(loaded.scene);
        let rays = loaded.camera.unwrap().prepare(16, 16).unwrap();
        let s = Settings { width: 16, height: 16, spp: 1, photons: 10_000, final_gather: false, ..Default::default() };
        let expected = 0.5 * cos / std::f32::consts::PI;
        for engine in ENGINES {
            let film = render(&scene, &rays, &s, engine, None, &NoProgress).unwrap().0;
            for (i, t) in film.pixels.iter().enumerate() {
                let err = (t.direct - Vec3::splat(expected)).abs().max_element();
                assert!(err <= 1e-5 * expected, "{deg}°, {engine:?}, pixel {i}: direct {} for {expected}", t.direct);
                // A lone plane reflects nothing back onto itself.
                assert_eq!(t.indirect + t.caustic + t.specular, Vec3::ZERO, "{deg}°, {engine:?}, pixel {i}");
            }
        }
        let per_seed: Vec<(u64, f64, f64)> = common::SEEDS
            .map(|seed| {
                let (_, maps) = maps_at(&scene, &s, seed);
                let q = Lookup {
                    p: Vec3::ZERO,
                    k: 0,
                    r_max: 0.8,
                    kernel: Kernel::Box,
                    filter: Filter { n: Vec3::Y, flags_mask: 0, plane: 0.0, slack: 0.0 },
                };
                let e = maps.global.estimate_radius(CodePath::Simd, &q, Reflectance::Constant(Vec3::ONE));
                (seed, f64::from(e.radiance.x / cos), 1.0 / f64::from(e.count).sqrt())
            })
            .collect();
        ratio_at_every_seed(&format!("{deg}°, photon irradiance / cos θ"), &per_seed, 0.0);
    }
}

/// Case 2: a point light (I = 1 W/sr) at the centre of a glass sphere in a closed room. Rays leave
/// the sphere along radii, unbent, so direct light is exactly 0 everywhere (shadow rays meet the
/// glass) and the caustic map carries it all: irradiance I·cos θ/D² on the walls. Over a disk of
/// radius r centred on a wall at distance 1 that averages (2/r²)·(1 − 1/√(1 + r²)) = 0.7917 for
/// r = 0.6. The box-kernel estimate counts photons of equal power (Fresnel choices are sampled,
/// not weighted), so its relative standard error is 1/√count; the allowance of 1 % is for the
/// tessellated sphere's shading normals bending rays slightly.
#[test]
fn light_inside_glass_reaches_the_walls_only_as_caustics() {
    use photonwave::code_path::CodePath;
    use photonwave::photon_map::{Filter, Lookup, Reflectance};
    use photonwave::settings::Kernel;
    let loaded = hard("light-in-glass.toml");
    let scene = Arc::new(loaded.scene);
    let rays = loaded.camera.unwrap().prepare(16, 16).unwrap();
    let s = Settings {
        width: 16,
        height: 16,
        spp: 1,
        photons: 5_000,
        caustic_photons: 40_000,
        gather_rays: 4,
        ..Default::default()
    };
    for engine in ENGINES {
        let film = render(&scene, &rays, &s, engine, None, &NoProgress).unwrap().0;
        assert!(film.pixels.iter().all(|t| t.direct == Vec3::ZERO), "{engine:?}: direct light through glass");
        assert!(film.pixels.iter().filter(|t| t.caustic.min_element() > 0.0).count() > 200, "{engine:?}");
    }
    let r = 0.6f32;
    let expected = 2.0 / (r * r) * (1.0 - 1.0 / (1.0 + r * r).sqrt());
    for (wall, p, n) in [("back", -Vec3::Z, Vec3::Z), ("floor", -Vec3::Y, Vec3::Y)] {
        let per_seed: Vec<(u64, f64, f64)> = common::SEEDS
            .map(|seed| {
                let (_, maps) = maps_at(&scene, &s, seed);
                let q = Lookup {
                    p,
                    k: 0,
                    r_max: r,
                    kernel: Kernel::Box,
                    filter: Filter { n, flags_mask: 0, plane: 0.0, slack: 0.0 },
                };
                let e = maps.caustic.estimate_radius(CodePath::Simd, &q, Reflectance::Constant(Vec3::ONE));
                (seed, f64::from(e.radiance.x / expected), 1.0 / f64::from(e.count).sqrt())
            })
            .collect();
        ratio_at_every_seed(&format!("{wall} wall, caustic irradiance / I·cos θ/D²"), &per_seed, 0.01);
    }
}

/// Case 7: a collimated beam (a directional light through a 0.2 × 0.2 hole) through a glass ball
/// (n = 1.5, R = 1) focuses on the axis at nR/(2(n − 1)) = 1.5 from the centre. The screen lies in
/// the plane y = 0 along the axis, so each ray of the beam lands on it where it crosses that
/// plane — at its focus. The median landing depth must be 1.5 within 2 % at every seed. Rays at
/// height h focus short of the paraxial focus (spherical aberration: 0.28 % at h = 0.1, 0.55 % at
/// the hole's corners, from an exact trace), so the median sits a little short of 1.5.
#[test]
fn a_ball_lens_focuses_at_n_r_over_2_n_minus_1() {
    let loaded = hard("ball-lens.toml");
    let scene = Arc::new(loaded.scene);
    let s = Settings { photons: 1_000, caustic_photons: 4_000, ..Default::default() };
    let mut worst = (0, 1.5f32);
    for seed in common::SEEDS {
        let (name, maps) = maps_at(&scene, &s, seed);
        let map = &maps.caustic;
        let mut depth: Vec<f32> = (0..map.len())
            .map(|i| map.photon(i).position)
            .filter(|p| p.y.abs() < 1e-6 && p.z < -1.0)
            .map(|p| -p.z)
            .collect();
        depth.sort_by(f32::total_cmp);
        let n = depth.len();
        assert!(n > 1_000, "{name}, seed {seed}: {n} photons on the screen");
        let median = depth[n / 2];
        if (median / 1.5 - 1.0).abs() > (worst.1 / 1.5 - 1.0).abs() {
            worst = (seed, median);
        }
        assert!((median / 1.5 - 1.0).abs() < 0.02, "{name}, seed {seed}: the beam focuses at {median}, not 1.5");
    }
    println!("the median landing depth farthest from 1.5: {} at seed {}", worst.1, worst.0);
}

/// Case 6, light pipe: a narrow spot (2°) lights the near end of a glass rod 30° off its axis.
/// Inside, the beam meets the side faces at 70.5°, past the critical angle (41.8°), so they
/// reflect all of it; the far end lets out T(30°) of what reaches it, and what it reflects comes
/// back after another reflection at the near end: flux out / flux in = T²/(1 − R²), R the
/// unpolarised Fresnel reflectance at 30° (T = 1 − R). Every caustic photon carries Φ/N, so the
/// screen's share is a binomial proportion; the allowance of 0.2 % is for the spread of angles
/// within the cone. Without total reflection most light would leave the sides.
#[test]
fn a_light_pipe_loses_only_the_fresnel_reflections_at_its_ends() {
    use photonwave::material::fresnel_dielectric;
    let loaded = hard("light-pipe.toml");
    let scene = Arc::new(loaded.scene);
    let s = Settings { photons: 1_000, caustic_photons: 10_000, ..Default::default() };
    let r = fresnel_dielectric(30f32.to_radians().cos(), 1.5);
    let expected = f64::from((1.0 - r) * (1.0 - r) / (1.0 - r * r));
    let flux = scene.total_power();
    let per_seed: Vec<(u64, f64, f64)> = common::SEEDS
        .map(|seed| {
            let (_, maps) = maps_at(&scene, &s, seed);
            let map = &maps.caustic;
            let on_screen: Vec<usize> =
                (0..map.len()).filter(|&i| (map.photon(i).position.z + 2.0).abs() < 1e-4).collect();
            let out: Vec3 = on_screen.iter().map(|&i| map.power(i)).sum();
            let ratio = f64::from(out.x / flux.x);
            let emitted = (on_screen.len() as f64 / ratio).round();
            let se = (expected * (1.0 - expected) / emitted).sqrt();
            (seed, ratio / expected, se / expected)
        })
        .collect();
    ratio_at_every_seed(&format!("flux out / in over T²/(1 − R²) = {expected:.5}"), &per_seed, 0.002);
}

/// Case 9 (the ray-level half is in tests/packet.rs): a point light inside the closed cube of
/// grid-triangulated faces with sliver strips and zero-area triangles. Every photon path lands
/// inside, so at every seed the first-hit photons carry the light's whole power (each Φ/N; only
/// the dithered power packing, 2⁻⁸/√N relative, separates the sum from Φ: 5 of those), and both
/// engines' images are finite and lit.
#[test]
fn no_photon_leaves_a_watertight_mesh() {
    use photonwave::photon_map::flags;
    let loaded = hard("watertight.toml");
    let scene = Arc::new(loaded.scene);
    let s = Settings { width: 16, height: 16, spp: 2, photons: 10_000, gather_rays: 4, ..Default::default() };
    let phi = scene.total_power();
    let mut worst = 0.0f32;
    for seed in common::SEEDS {
        let (name, maps) = maps_at(&scene, &s, seed);
        let map = &maps.global;
        let first: Vec<usize> = (0..map.len()).filter(|&i| map.photon(i).flags & flags::DIRECT != 0).collect();
        let sum: Vec3 = first.iter().map(|&i| map.power(i)).sum();
        let tol = 5.0 * 2f32.powi(-8) / (first.len() as f32).sqrt();
        let off = (sum / phi - Vec3::ONE).abs().max_element();
        worst = worst.max(off / tol);
        assert!(off < tol, "{name}, seed {seed}: {} of the light's power landed (± {tol})", sum / phi);
    }
    println!("first-hit power / Φ: the worst seed {worst:.2} of the tolerance away");
    let rays = loaded.camera.unwrap().prepare(16, 16).unwrap();
    for engine in ENGINES {
        let film = render(&scene, &rays, &s, engine, None, &NoProgress).unwrap().0;
        assert!(film.pixels.iter().all(|t| t.is_finite() && t.beauty().min_element() > 0.0), "{engine:?}");
    }
}
