//! Light portals (`[[portal]]` in a TOML scene): direct light from the environment draws half its
//! samples through the portals instead of over the whole sky. A room whose only opening is a
//! portal renders the same direct light with and without it, with several times less variance
//! at equal samples; a portal's corners are checked.

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
