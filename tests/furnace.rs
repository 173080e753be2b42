//! Energy in the white furnace, at every seed (scenes/hard/furnace-*.toml, nested.toml).
//!
//! A closed sphere emitting Le = 1 and reflecting 0.5 holds objects of every material. Where
//! every surface is lossless, radiance is Le/(1 − 0.5) = 2; lossy lobes (a Phong lobe below the
//! horizon, the microfacets' shadowing) make an object and what sees it darker, and nothing may
//! be brighter. A photon of runaway power breaks that at one seed and not at another (seed 11
//! once rendered a mean of 13.2 for 1.94 at seeds 1–4), so every claim here is checked at each
//! of [`common::SEEDS`] and the worst seed asserted.
//!
//! Per object (pixels whose 3 × 3 neighbourhood sees only it), at each seed, a small render
//! (24², 2 spp, 10 000 photons per map, 4 gather rays; the engines alternate by seed, as they
//! agree per pixel: tests/wavefront.rs) gives a mean `v_s`. Its spread over the seeds, σ, is
//! estimated robustly (1.4826 × the median absolute deviation, which one runaway seed cannot
//! inflate), must stay within 1.25 times the value recorded in [`SIGMA`], and the claims take σ
//! from that record, so that a noisier renderer cannot widen its own tolerance. The claims, with
//! σ and the path tracer's truth T ± se (24², 512 spp, 64 bounces):
//! - no seed gains energy: `v_s ≤ 2 · 1.01 + 6σ` — 1 % for the density estimates' bias (their
//!   kernel and boundary: measured at most 0.6 % above T over the seeds' mean), and 6σ, whose
//!   chance excess for a normal spread is 2·10⁻⁹ a seed;
//! - no seed strays: `|v_s − median| ≤ 6σ + 0.5 %` (the 0.5 % a floor for objects whose σ is tiny);
//! - the seeds' mean agrees with the path tracer: `|v̄ − T| ≤ 4·√(σ²/n + se²) + 1.5 % · T`, the
//!   1.5 % the density estimates' bias, as in the one-seed test this replaces.
//!
//! Variants of the materials scene: smooth-shaded as written, flat-shaded (vertex normals set to
//! the geometric ones), every normal perturbed by one ulp, and geometric normals computed in f64;
//! and furnace-rough.toml (rough plastic, a rough conductor whose photons are stored, frosted
//! glass, a grey Lambertian).

mod common;

use glam::{DVec3, Vec3};
use photonwave::engine::{render, Engine};
use photonwave::formats::load_scene;
use photonwave::progress::NoProgress;
use photonwave::scene::Scene;
use photonwave::settings::Settings;
use std::path::PathBuf;
use std::sync::Arc;

const SIZE: usize = 24;

fn hard(name: &str) -> photonwave::formats::LoadedScene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/hard").join(name);
    load_scene(&path).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Each object's pixels: those whose centre sees it and whose 3 × 3 neighbourhood sees only it
/// (at least 9 of them).
fn regions(scene: &Scene, rays: &photonwave::scene::camera::CameraRays) -> Vec<(String, Vec<usize>)> {
    let seen: Vec<Option<u32>> = (0..SIZE * SIZE)
        .map(|i| {
            let (o, d) = rays.ray((i % SIZE) as f32 + 0.5, (i / SIZE) as f32 + 0.5);
            scene.intersect(o, d, f32::INFINITY).map(|hit| scene.surface(&hit).material)
        })
        .collect();
    let interior = |i: usize| {
        let (x, y) = ((i % SIZE) as i64, (i / SIZE) as i64);
        (-1..=1).all(|dy| {
            (-1..=1).all(|dx| {
                let (u, v) = (x + dx, y + dy);
                let n = SIZE as i64;
                (0..n).contains(&u) && (0..n).contains(&v) && seen[(v * n + u) as usize] == seen[i]
            })
        })
    };
    scene
        .materials
        .iter()
        .enumerate()
        .map(|(m, mat)| {
            (mat.name.clone(), (0..SIZE * SIZE).filter(|&i| seen[i] == Some(m as u32) && interior(i)).collect())
        })
        .filter(|(_, px): &(String, Vec<usize>)| px.len() >= 9)
        .collect()
}

/// Median of `v` (not empty).
fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

/// The seeds' spread σ of each object's mean, per variant, as measured once multiple importance
/// sampling weighed the furnace's light samples (issue 53, item 2; robust:
/// 1.4826 × the median absolute deviation over the 32 seeds; the smooth, one-ulp and f64-normal
/// variants measure alike). The claims below take their σ from here, not from the run, so a
/// noisier renderer cannot widen its own tolerance: a run whose measured σ exceeds 1.25 times
/// this fails (the MAD estimate over 32 seeds has a sampling error of about 20 % of σ, so a
/// change of renderer that keeps the noise may move it that far; each seed's render is
/// deterministic, so the figure moves only when the renderer does, and is then looked at and
/// recorded again). Every object listed must be found in the image, and every object found
/// must be listed. Before MIS, white and glossy were 6.5 and 10 times noisier (σ 0.1756 and
/// 0.4067, smooth): their direct light came from light samples alone, and one across a crease
/// of the tessellated sphere or in the glossy lobe's peak weighed tens of times the mean.
/// Recorded again when the light tree and solid-angle sampling came (issue 56): every object
/// within 0.82–1.16 of its figure before, but the flat-shaded glossy sphere 1.32 (0.0400 →
/// 0.0527; with power's picks it measured 0.0363): inside an emitting sphere, picking by power
/// is already ideal (uniform area on a sphere is uniform in cos·cos/d²), and the tree's bound,
/// which prefers lights toward the normal, lights a glossy lobe less well (1.45 times power's
/// σ with a quarter of the picks left to power).
const SIGMA: &[(&str, &[(&str, f64)])] = &[
    ("smooth", &[("furnace", 0.0076), ("white", 0.0294), ("mirror", 0.0162), ("glass", 0.0234), ("glossy", 0.0420)]),
    ("flat", &[("furnace", 0.0071), ("white", 0.0198), ("mirror", 0.0130), ("glass", 0.0213), ("glossy", 0.0527)]),
    ("one ulp", &[("furnace", 0.0076), ("white", 0.0294), ("mirror", 0.0159), ("glass", 0.0234), ("glossy", 0.0420)]),
    (
        "f64 normals",
        &[("furnace", 0.0076), ("white", 0.0290), ("mirror", 0.0162), ("glass", 0.0234), ("glossy", 0.0420)],
    ),
    ("rough", &[("furnace", 0.0101), ("white", 0.0267), ("mirror", 0.0901), ("glass", 0.0672), ("glossy", 0.0101)]),
    ("nested", &[("furnace", 0.0275), ("glass", 0.0238), ("water", 0.0046)]),
];

/// Renders `scene` at every seed and checks the claims of the module notes per object; returns
/// (object, seeds' mean) for the caller's own claims.
fn furnace_at_every_seed(name: &str, scene: Scene, camera: photonwave::scene::Camera) -> Vec<(String, f64)> {
    let scene = Arc::new(scene);
    let rays = camera.prepare(SIZE as u32, SIZE as u32).unwrap();
    let objects = regions(&scene, &rays);
    let recorded = SIGMA.iter().find(|(v, _)| *v == name).unwrap_or_else(|| panic!("{name}: no recorded σ")).1;
    let found: Vec<&str> = objects.iter().map(|(o, _)| o.as_str()).collect();
    let listed: Vec<&str> = recorded.iter().map(|(o, _)| *o).collect();
    assert_eq!(found, listed, "{name}: the objects in view");
    let base = Settings {
        width: SIZE as u32,
        height: SIZE as u32,
        spp: 2,
        photons: 10_000,
        caustic_photons: 10_000,
        gather_rays: 4,
        threads: 1,
        ..Default::default()
    };
    let means = |film: &photonwave::film::Film| -> Vec<(f64, f64)> {
        let grey = common::grey(film);
        objects.iter().map(|(_, px)| common::mean_and_se(&px.iter().map(|&i| grey[i]).collect::<Vec<f32>>())).collect()
    };
    let path = Settings { spp: 512, max_depth: 64, ..base.clone() };
    let truth = means(&photonwave::path::render_path_traced(&scene, &rays, &path, &NoProgress).unwrap().0);
    let per_seed: Vec<Vec<f64>> = common::SEEDS
        .map(|seed| {
            let engine = if seed.is_multiple_of(2) { Engine::Wavefront } else { Engine::Reference };
            let s = Settings { seed, ..base.clone() };
            let film = render(&scene, &rays, &s, engine, None, &NoProgress).unwrap().0;
            assert!(film.pixels.iter().all(|t| t.is_finite()), "{name}, seed {seed}: a non-finite pixel");
            means(&film).into_iter().map(|(m, _)| m).collect()
        })
        .collect();
    let n = per_seed.len() as f64;
    let mut out = Vec::new();
    for (k, (object, _)) in objects.iter().enumerate() {
        let v: Vec<f64> = per_seed.iter().map(|m| m[k]).collect();
        let (t, se) = truth[k];
        let mid = median(&v);
        let measured = 1.4826 * median(&v.iter().map(|x| (x - mid).abs()).collect::<Vec<f64>>());
        let sigma = recorded[k].1;
        assert!(
            measured <= 1.25 * sigma,
            "{name}, {object}: the seeds' spread σ {measured:.4} exceeds 1.25 × the recorded {sigma}"
        );
        let mean = v.iter().sum::<f64>() / n;
        let (worst_seed, worst) = common::SEEDS
            .zip(&v)
            .max_by(|a, b| (a.1 - mid).abs().total_cmp(&(b.1 - mid).abs()))
            .map(|(s, x)| (s, *x))
            .unwrap();
        let brightest = v.iter().copied().fold(f64::MIN, f64::max);
        println!(
            "{name}, {object}: path tracer {t:.4} ± {se:.4}; seeds' mean {mean:.4}, median {mid:.4}, σ {measured:.4} \
             (recorded {sigma}), brightest {brightest:.4}, worst seed {worst_seed} at {worst:.4} ({:+.1}σ)",
            (worst - mid) / sigma.max(1e-12)
        );
        assert!(t <= 2.0 + 4.0 * se + 0.01, "{name}, path tracer, {object}: {t} > 2");
        for (seed, x) in common::SEEDS.zip(&v) {
            assert!(*x <= 2.0 * 1.01 + 6.0 * sigma, "{name}, {object}, seed {seed}: {x} > 2 (σ {sigma})");
            assert!(
                (x - mid).abs() <= 6.0 * sigma + 0.005 * mid,
                "{name}, {object}, seed {seed}: {x} strays from the seeds' median {mid} (σ {sigma})"
            );
        }
        let tol = 4.0 * (sigma * sigma / n + se * se).sqrt() + 0.015 * t;
        assert!((mean - t).abs() <= tol, "{name}, {object}: seeds' mean {mean} against the path tracer's {t} ± {tol}");
        out.push((object.clone(), mean));
    }
    out
}

#[test]
fn a_smooth_shaded_furnace_never_gains_energy_at_any_seed() {
    let loaded = hard("furnace-materials.toml");
    furnace_at_every_seed("smooth", loaded.scene, loaded.camera.unwrap());
}

/// The same spheres flat-shaded: every vertex normal is its triangle's geometric normal, so
/// Veach's correction is 1 and photons carry their emitted power exactly.
#[test]
fn a_flat_shaded_furnace_never_gains_energy_at_any_seed() {
    let loaded = hard("furnace-materials.toml");
    let mut scene = loaded.scene;
    for (vn, ng) in scene.vn.iter_mut().zip(&scene.ng) {
        *vn = [*ng; 3];
    }
    furnace_at_every_seed("flat", scene, loaded.camera.unwrap());
}

/// Every component of every vertex normal and geometric normal moved by one ulp (up and down in
/// turn). The random numbers are the same, so most paths are too; but a spike such as the
/// furnace's (a departure a rounding away from the shading plane) appears or hides with such
/// changes, so the claims must hold for them as for the normals as written.
#[test]
fn normals_one_ulp_off_change_nothing_at_any_seed() {
    let loaded = hard("furnace-materials.toml");
    let mut scene = loaded.scene;
    let nudge = |v: Vec3, up: bool| {
        let f = |c: f32| if up { c.next_up() } else { c.next_down() };
        Vec3::new(f(v.x), f(v.y), f(v.z))
    };
    for (i, vn) in scene.vn.iter_mut().enumerate() {
        *vn = vn.map(|n| nudge(n, i % 2 == 0));
    }
    for (i, ng) in scene.ng.iter_mut().enumerate() {
        *ng = nudge(*ng, i % 2 == 1);
    }
    furnace_at_every_seed("one ulp", scene, loaded.camera.unwrap());
}

/// Geometric normals computed in f64 from the vertices (rounded once), as a loader might: they
/// differ from the f32 cross product in the last bits of many triangles. With them one global
/// photon once carried 1 352 W against a median of 0.0012 W.
#[test]
fn f64_geometric_normals_change_nothing_at_any_seed() {
    let loaded = hard("furnace-materials.toml");
    let mut scene = loaded.scene;
    let mut changed = 0;
    for i in 0..scene.ng.len() {
        let (a, b, c) = (scene.p0[i].as_dvec3(), scene.p1[i].as_dvec3(), scene.p2[i].as_dvec3());
        let n: DVec3 = (b - a).cross(c - a).normalize();
        assert!(n.dot(scene.ng[i].as_dvec3()) > 0.99, "triangle {i}");
        changed += usize::from(scene.ng[i] != n.as_vec3());
        scene.ng[i] = n.as_vec3();
    }
    println!("f64 normals: {changed} of {} triangles' normals changed", scene.ng.len());
    assert!(changed > scene.ng.len() / 10, "{changed}");
    furnace_at_every_seed("f64 normals", scene, loaded.camera.unwrap());
}

/// Rough plastic, a rough conductor whose photons are stored on it, frosted glass and a grey
/// Lambertian.
#[test]
fn a_rough_furnace_never_gains_energy_at_any_seed() {
    let loaded = hard("furnace-rough.toml");
    furnace_at_every_seed("rough", loaded.scene, loaded.camera.unwrap());
}

/// A glass slab under water in the white furnace, the boundary between them one face with `ior`
/// 1.33 and `outside_ior` 1.5 (the documented model: one face per boundary, indices on both
/// sides). Every surface is lossless, so radiance is 2 wherever the camera looks, through any
/// number of interfaces: the seeds' mean of water and glass is 2 within 2 %. The same slabs
/// closed each on its own put coincident faces of glass and water at the boundary, which the
/// loader reports.
#[test]
fn nested_dielectrics_conserve_energy_at_every_seed() {
    assert!(hard("nested.toml").scene.warnings.is_empty());
    let coincident = hard("nested-coincident.toml").scene.warnings;
    assert!(coincident.iter().any(|w| w.contains("triangle pairs of `glass` and `water`")), "{coincident:?}");
    let loaded = hard("nested.toml");
    let objects = furnace_at_every_seed("nested", loaded.scene, loaded.camera.unwrap());
    for (object, mean) in objects {
        assert!(mean > 2.0 * 0.98, "{object}: {mean}, not 2");
    }
}

/// The most one camera sample's direct light can be at a non-specular hit on `bsdf` under
/// emission `le`, by construction of multiple importance sampling (`transport::mis`, the power
/// heuristic): a light sample of density x weighed against a BSDF kind of density g carries
/// f·L·cos·x/(x² + g²) ≤ f·L·cos/(2g), and a BSDF ray that hits the emitter carries at most its
/// own weight times L. With `nl` light samples and `ng` gather rays: for the Lambertian base
/// g = ng·cos/π, so the light samples carry at most nl·kd·L/(2·ng) and the gather rays kd·L
/// together; for Phong's lobe g is the glossy ray's pdf and f·cos/g = ks·(n+2)/(n+1)·cos, so the
/// light samples carry at most nl/2 and the glossy ray once that times L.
fn direct_bound(bsdf: &photonwave::material::Bsdf, le: f64, nl: f64, ng: f64) -> f64 {
    use photonwave::material::Bsdf;
    let base = |kd: Vec3| f64::from(kd.max_element()) * (1.0 + nl / (2.0 * ng));
    le * match *bsdf {
        Bsdf::Lambert { kd } => base(kd),
        Bsdf::Glossy { kd, ks, exponent } => {
            let n = f64::from(exponent);
            base(kd) + f64::from(ks.max_element()) * (n + 2.0) / (n + 1.0) * (1.0 + nl / 2.0)
        }
        // Mirrors and glass: the camera path goes on, its direct light is the next hit's.
        _ => 0.0,
    }
}

/// Issue 53: `furnace-materials.toml` at seed 11 had a pixel of 10.6 where the image's bound is 2,
/// its direct layer 8.9 — light samples of the furnace's own surface across a crease of the
/// tessellated sphere (d² near zero), and in the glossy sphere's lobe peak. With MIS every camera
/// sample's direct light is bounded ([`direct_bound`]: 1.39 here, the glossy sphere's), so no
/// pixel of the direct layer may pass it, at any seed; without MIS (`mis = false`) the same seeds
/// pass it (3.6 to 8.9 when this was written), which shows the test can fail. Few photons: the
/// direct layer does not read the maps.
#[test]
fn direct_light_stays_within_its_bound_in_every_pixel_at_every_seed() {
    let loaded = hard("furnace-materials.toml");
    let base = Settings { photons: 2_000, caustic_photons: 2_000, threads: 1, ..loaded.settings.clone() };
    let scene = Arc::new(loaded.scene);
    let rays = loaded.camera.unwrap().prepare(base.width, base.height).unwrap();
    let le = scene.materials.iter().map(|m| f64::from(m.emission.max_element())).fold(0.0, f64::max);
    let (nl, ng) = (f64::from(base.light_samples), f64::from(base.gather_rays));
    let bound = scene.materials.iter().map(|m| direct_bound(&m.bsdf, le, nl, ng)).fold(0.0, f64::max);
    // The bound is the glossy sphere's: 0.3·(1 + 1/32) + 0.7·32/31·1.5 under Le = 1.
    assert!((bound - 1.3931).abs() < 1e-3, "bound {bound}");
    let mut beyond_without_mis = 0;
    for seed in [1, 2, 3, 11] {
        let brightest = |mis: bool| {
            let engine = if seed % 2 == 0 { Engine::Wavefront } else { Engine::Reference };
            let s = Settings { seed, mis, ..base.clone() };
            let film = render(&scene, &rays, &s, engine, None, &NoProgress).unwrap().0;
            film.pixels.iter().map(|t| f64::from(t.direct.max_element())).fold(0.0, f64::max)
        };
        let (with, without) = (brightest(true), brightest(false));
        println!("seed {seed}: brightest direct pixel {with:.3} with MIS, {without:.3} without (bound {bound:.3})");
        assert!(with <= bound * (1.0 + 1e-5), "seed {seed}: a direct pixel of {with} above the bound {bound}");
        beyond_without_mis += usize::from(without > bound);
    }
    assert!(beyond_without_mis >= 1, "without MIS no seed passed the bound: the test shows nothing");
}
