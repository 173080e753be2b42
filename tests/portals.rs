//! Light portals (`[[portal]]` in a TOML scene): direct light from the environment draws half its
//! samples through the portals instead of over the whole sky, and half its photons travel lines
//! through them. A room whose only opening is a portal renders the same direct light with and
//! without it, with several times less variance at equal samples, and its photons bring the
//! same light in, many more of them; a portal's corners are checked.

mod common;

use common::scratch_dir;
use photonwave::engine::{render, Engine};
use photonwave::formats::load_scene;
use photonwave::progress::NoProgress;
use photonwave::settings::Settings;
use std::path::Path;

/// A closed room x, z in [−1, 1], y in [0, 2] (Lambertian walls of albedo 0.7, zero thickness)
/// whose back wall (z = −1) has an open window x in [−0.3, 0.3], y in [0.8, 1.4], under a
/// constant sky of radiance 1; with `portal`, the window is marked as one. Written into `dir`.
fn room(dir: &Path, portal: bool) -> std::path::PathBuf {
    let quads: [[[f32; 3]; 4]; 9] = [
        [[-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [1.0, 0.0, 1.0], [-1.0, 0.0, 1.0]],
        [[-1.0, 2.0, -1.0], [-1.0, 2.0, 1.0], [1.0, 2.0, 1.0], [1.0, 2.0, -1.0]],
        [[-1.0, 0.0, -1.0], [-1.0, 0.0, 1.0], [-1.0, 2.0, 1.0], [-1.0, 2.0, -1.0]],
        [[1.0, 0.0, -1.0], [1.0, 2.0, -1.0], [1.0, 2.0, 1.0], [1.0, 0.0, 1.0]],
        [[-1.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 2.0, 1.0], [-1.0, 2.0, 1.0]],
        [[-1.0, 0.0, -1.0], [-1.0, 2.0, -1.0], [-0.3, 2.0, -1.0], [-0.3, 0.0, -1.0]],
        [[0.3, 0.0, -1.0], [0.3, 2.0, -1.0], [1.0, 2.0, -1.0], [1.0, 0.0, -1.0]],
        [[-0.3, 0.0, -1.0], [-0.3, 0.8, -1.0], [0.3, 0.8, -1.0], [0.3, 0.0, -1.0]],
        [[-0.3, 1.4, -1.0], [-0.3, 2.0, -1.0], [0.3, 2.0, -1.0], [0.3, 1.4, -1.0]],
    ];
    let mut obj = String::from("mtllib room.mtl\nusemtl wall\n");
    for q in &quads {
        for v in q {
            obj += &format!("v {} {} {}\n", v[0], v[1], v[2]);
        }
    }
    for k in 0..quads.len() {
        obj += &format!("f {} {} {} {}\n", 4 * k + 1, 4 * k + 2, 4 * k + 3, 4 * k + 4);
    }
    std::fs::write(dir.join("room.obj"), obj).unwrap();
    std::fs::write(dir.join("room.mtl"), "newmtl wall\nKd 0.7 0.7 0.7\n").unwrap();
    let mut toml = String::from(
        "[[mesh]]\nfile = \"room.obj\"\n\n[camera]\neye = [0.6, 1.3, 0.8]\ntarget = [-0.3, 0.5, -0.6]\nfov = 70\n\n\
         [environment]\nradiance = [1, 1, 1]\n",
    );
    if portal {
        toml += "\n[[portal]]\ncorners = [[-0.3, 0.8, -1], [0.3, 0.8, -1], [0.3, 1.4, -1], [-0.3, 1.4, -1]]\n";
    }
    let name = if portal { "portal.toml" } else { "open.toml" };
    std::fs::write(dir.join(name), toml).unwrap();
    dir.join(name)
}

#[test]
fn a_portal_keeps_the_mean_and_cuts_the_variance() {
    // The direct layer of the room, 24², 2 samples a pixel, at 12 seeds with and without the
    // portal (the reference engine; the engines agree per pixel elsewhere). Means: the seeds'
    // image means agree within 4 standard errors of their difference. Variance: each pixel's
    // variance over the seeds, averaged over the pixels (12 seeds: its relative spread is about
    // √(2/11)/√(pixels lit), 1–2 %), is at least 4 times lower with the portal.
    let d = scratch_dir("portals");
    let s = Settings {
        width: 24,
        height: 24,
        spp: 2,
        photons: 2000,
        caustic_photons: 1000,
        gather_rays: 2,
        threads: 2,
        ..Settings::default()
    };
    let direct = |path: &Path| {
        let loaded = load_scene(path).unwrap();
        let rays = loaded.camera.unwrap().prepare(s.width, s.height).unwrap();
        let scene = std::sync::Arc::new(loaded.scene);
        (1..=12u64)
            .map(|seed| {
                let settings = Settings { seed, ..s.clone() };
                let film = render(&scene, &rays, &settings, Engine::Reference, None, &NoProgress).unwrap().0;
                film.pixels.iter().map(|t| f64::from(t.direct.element_sum()) / 3.0).collect::<Vec<f64>>()
            })
            .collect::<Vec<_>>()
    };
    let (open, portal) = (direct(&room(&d, false)), direct(&room(&d, true)));
    let stats = |runs: &[Vec<f64>]| {
        let n = runs.len() as f64;
        let means: Vec<f64> = runs.iter().map(|r| r.iter().sum::<f64>() / r.len() as f64).collect();
        let mean = means.iter().sum::<f64>() / n;
        let se = (means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        let pixels = runs[0].len();
        let variance = (0..pixels)
            .map(|k| {
                let m = runs.iter().map(|r| r[k]).sum::<f64>() / n;
                runs.iter().map(|r| (r[k] - m).powi(2)).sum::<f64>() / (n - 1.0)
            })
            .sum::<f64>()
            / pixels as f64;
        (mean, se, variance)
    };
    let ((m0, s0, v0), (m1, s1, v1)) = (stats(&open), stats(&portal));
    println!("open: mean {m0:.5} ± {s0:.5}, variance {v0:.3e}; portal: mean {m1:.5} ± {s1:.5}, variance {v1:.3e}");
    assert!(m0 > 0.0 && (m0 - m1).abs() < 4.0 * (s0 * s0 + s1 * s1).sqrt(), "means {m0} and {m1}");
    assert!(v0 >= 4.0 * v1, "variance {v0:.3e} without the portal, {v1:.3e} with: {:.2}×", v0 / v1);
}

#[test]
fn photons_through_a_portal_bring_the_same_light_in() {
    // The room's global photons, 20 000 a seed at 8 seeds, with and without the portal. A
    // photon's first hit (direct) inside the room (a hair along its stored normal from it lies
    // in the box) is sky light that came through the window, whose flux is π·A·L = 0.36π W (the
    // whole sky outside it is open): the seeds' mean power must be that within 4 of its
    // standard errors, with the portal and without (the mixture's density keeps every line's
    // expectation), and the portal must bring at least 4 times as many photons in (13.5×
    // measured).
    use photonwave::photon_map::flags;
    use photonwave::reference::photons::trace_photons;
    use photonwave::rng::Domain;
    let d = scratch_dir("portal-photons");
    let inside = |p: glam::Vec3| p.x.abs() < 1.0 && p.z.abs() < 1.0 && p.y > 0.0 && p.y < 2.0;
    let run = |path: &Path| {
        let scene = load_scene(path).unwrap().scene;
        let per_seed: Vec<(f64, usize)> = (1..=8u64)
            .map(|seed| {
                let s = Settings { threads: 2, seed, ..Settings::default() };
                let pass = trace_photons(&scene, &common::job(&scene, &s), Domain::GlobalPhoton, 20_000, &NoProgress);
                let came_in: Vec<_> = pass
                    .photons
                    .iter()
                    .filter(|p| p.flags & flags::DIRECT != 0 && inside(p.position + p.normal * 1e-3))
                    .collect();
                (came_in.iter().map(|p| f64::from(p.power.x)).sum(), came_in.len())
            })
            .collect();
        let n = per_seed.len() as f64;
        let mean = per_seed.iter().map(|p| p.0).sum::<f64>() / n;
        let se = (per_seed.iter().map(|p| (p.0 - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        let count = per_seed.iter().map(|p| p.1).sum::<usize>();
        (mean, se, count)
    };
    let ((m0, s0, c0), (m1, s1, c1)) = (run(&room(&d, false)), run(&room(&d, true)));
    println!("open: {m0:.4} ± {s0:.4} W from {c0} photons; portal: {m1:.4} ± {s1:.4} W from {c1} photons");
    let flux = 0.36 * std::f64::consts::PI;
    assert!((m0 - flux).abs() < 4.0 * s0, "power in without the portal: {m0} ± {s0}, want {flux}");
    assert!((m1 - flux).abs() < 4.0 * s1, "power in with the portal: {m1} ± {s1}, want {flux}");
    assert!(c1 >= 4 * c0, "photons in: {c0} without the portal, {c1} with");
}

#[test]
fn portals_are_checked() {
    let d = scratch_dir("portals-bad");
    let path = room(&d, true);
    let text = std::fs::read_to_string(&path).unwrap();
    let write = |name: &str, t: String| {
        std::fs::write(d.join(name), t).unwrap();
        load_scene(&d.join(name)).err().expect("refused").to_string()
    };
    let skew = write("skew.toml", text.replace("[0.3, 1.4, -1]", "[0.6, 1.4, -1]"));
    assert!(skew.contains("portal[0].corners") && skew.contains("parallelogram"), "{skew}");
    let flat = write(
        "flat.toml",
        text.replace(
            "[[-0.3, 0.8, -1], [0.3, 0.8, -1], [0.3, 1.4, -1], [-0.3, 1.4, -1]]",
            "[[0, 1, -1], [0, 1, -1], [0, 1, -1], [0, 1, -1]]",
        ),
    );
    assert!(flat.contains("portal[0].corners") && flat.contains("zero area"), "{flat}");
    let dark = write(
        "dark.toml",
        text.replace(
            "[environment]\nradiance = [1, 1, 1]\n",
            "[[light]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = [1, 1, 1]\n",
        ),
    );
    assert!(dark.contains("portal[0]") && dark.contains("no [environment]"), "{dark}");
}

#[test]
fn engines_agree_in_the_daylight_room_at_any_thread_count() {
    // The bundled daylight room: a sky map and a sun through a glazed and an open window, both
    // portals (light samples and half the sky's photons through them), alpha-masked leaves and
    // a thin pane: the wavefront kernels and the reference engine agree per pixel.
    let loaded = common::load("daylight.toml");
    assert_eq!(loaded.scene.environment.as_ref().map(|e| e.portals().len()), Some(2));
    common::assert_engines_agree(loaded);
}
