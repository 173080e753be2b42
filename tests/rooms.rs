//! Back-to-back surfaces: a closed room of zero-thickness walls lit inside by a ceiling panel
//! renders the same inside whether or not a sun lights the world outside — a ground far below
//! (scenes/hard/room-sunlit.toml) or a ground 1 cm under the room's floor, a floor thinner than
//! any search radius (room-on-ground.toml). Each is compared with its dark twin: the same file
//! without the sun, so that the geometry (and the radii, which follow the scene's size) is the
//! same and only the light outside differs.
//!
//! The sun takes most of the scene's power (88 %). The photon guide (`transport::guide`) keeps
//! the inside's photons the same: each map's target counts only the photons stored where the
//! camera reads it, and the lights emit in proportion to the power they bring there, so the
//! sunlit render stores as many photons inside as its twin, from the panel for the most part.
//! Before it, the sunlit render had to be given more photons by hand (the twin's paths over the
//! panel's share of the power), or the inside's estimates used wider radii: indirect light 1 %
//! darker inside in one pass at equal budgets.

mod common;

use glam::Vec3;
use photonwave::engine::{render, Engine};
use photonwave::formats::{load_scene, LoadedScene};
use photonwave::photon_map::{Filter, Kernel, Lookup, Nearest, OFF_PLANE};
use photonwave::progress::NoProgress;
use photonwave::scene::Scene;
use photonwave::settings::Settings;
use std::path::PathBuf;
use std::sync::Arc;

/// The sunlit scene and its dark twin (the same file without its `[[light]]`, the sun).
fn with_twin(name: &str) -> (LoadedScene, LoadedScene) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/hard");
    let path = dir.join(name);
    let text = std::fs::read_to_string(&path).unwrap();
    let start = text.find("[[light]]").expect("a sun");
    let end = text[start..].find("\n\n").map_or(text.len(), |e| start + e);
    let obj = dir.join(name.replace(".toml", ".obj"));
    let dark = (text[..start].to_string() + &text[end..]).replace(
        &format!("file = \"{}\"", name.replace(".toml", ".obj")),
        &format!("file = {:?}", obj.to_str().unwrap()),
    );
    // A folder per call: tests running at once write the same twin, and each scratch folder is
    // emptied when made (a shared one lost a twin to another test's call).
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let twin = common::scratch_dir(&format!("rooms-{call}")).join(name.replace(".toml", "-dark.toml"));
    std::fs::write(&twin, dark).unwrap();
    let load = |p: &std::path::Path| load_scene(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    (load(&path), load(&twin))
}

/// Inside the room: x, z in (−1, 1), y in (0, 1.2), and a point a hair along `normal` from it
/// too (a photon on a wall's inner face, not its outer one).
fn inside(p: Vec3, normal: Vec3) -> bool {
    let q = p + normal * 1e-3;
    [p, q].iter().all(|v| v.x.abs() < 1.0 + 1e-4 && v.z.abs() < 1.0 + 1e-4 && v.y > -1e-4 && v.y < 1.2 + 1e-4)
        && q.x.abs() < 1.0
        && q.z.abs() < 1.0
        && q.y > 0.0
        && q.y < 1.2
}

/// No estimate inside the room reads a photon from outside, at any seed, in either sunlit
/// scene: at 216 points on the floor, walls and ceiling (facing in), every photon the map's
/// filter accepts for a k-nearest (k = 64) or fixed-radius (0.3) lookup at a flat point lies
/// inside, and every photon it sets aside off the point's plane that lies outside (the ground
/// under the floor, the outer faces) is invisible from the point, so the estimate's completion
/// does not add it either (`transport::estimate::complete_off_plane`).
#[test]
fn no_estimate_inside_reads_a_photon_from_outside() {
    use photonwave::transport::estimate::off_plane_visibility;
    let faces: [(Vec3, Vec3, Vec3, Vec3); 6] = [
        (Vec3::new(0.0, 0.0, 0.0), Vec3::Y, Vec3::X, Vec3::Z),
        (Vec3::new(0.0, 1.2, 0.0), -Vec3::Y, Vec3::X, Vec3::Z),
        (Vec3::new(-1.0, 0.6, 0.0), Vec3::X, Vec3::Y * 0.6, Vec3::Z),
        (Vec3::new(1.0, 0.6, 0.0), -Vec3::X, Vec3::Y * 0.6, Vec3::Z),
        (Vec3::new(0.0, 0.6, -1.0), Vec3::Z, Vec3::X, Vec3::Y * 0.6),
        (Vec3::new(0.0, 0.6, 1.0), -Vec3::Z, Vec3::X, Vec3::Y * 0.6),
    ];
    for name in ["room-sunlit.toml", "room-on-ground.toml"] {
        let (sunlit, _) = with_twin(name);
        let scene = Arc::new(sunlit.scene);
        let (mut checked, mut set_aside) = (0usize, 0usize);
        for seed in common::SEEDS {
            let s = Settings { photons: 10_000, seed, threads: 1, ..Default::default() };
            let maps = if seed.is_multiple_of(2) {
                photonwave::reference::build_maps(&scene, &s).unwrap().0
            } else {
                photonwave::wavefront::build_maps(scene.clone(), &s).unwrap().0
            };
            let map = &maps.global;
            let mut scratch = Nearest::default();
            for (centre, n, u, v) in faces {
                for a in 0..6 {
                    for b in 0..6 {
                        // A grid from the face's edges in, 0.98 of its half-widths.
                        let (fa, fb) = (-0.98 + 1.96 * a as f32 / 5.0, -0.98 + 1.96 * b as f32 / 5.0);
                        let p = centre + u * fa + v * fb;
                        let filter = Filter::at(p, n, 0).with_plane(OFF_PLANE);
                        for (k, r_max) in [(64usize, 0.5f32), (usize::MAX, 0.3)] {
                            let q = Lookup { p, k, r_max, kernel: Kernel::Box, filter };
                            for &(_, i) in map.nearest(photonwave::code_path::CodePath::Simd, &q, &mut scratch) {
                                let ph = map.photon(i as usize);
                                assert!(
                                    inside(ph.position, ph.normal),
                                    "{name}, seed {seed}: the estimate at {p} (normal {n}) accepts a photon at {} (normal {})",
                                    ph.position,
                                    ph.normal
                                );
                                checked += 1;
                            }
                        }
                        let visible = off_plane_visibility(&scene, p, &filter);
                        let q = Lookup { p, k: 0, r_max: 0.3, kernel: Kernel::Box, filter };
                        for (_, i) in map.off_plane_photons(&q) {
                            let ph = map.photon(i as usize);
                            set_aside += 1;
                            assert!(
                                inside(ph.position, ph.normal) || !visible(ph.position, ph.normal),
                                "{name}, seed {seed}: at {p} (normal {n}), a visible photon from outside at {} (normal {})",
                                ph.position,
                                ph.normal
                            );
                        }
                    }
                }
            }
        }
        println!("{name}: {checked} accepted photons inside, {set_aside} set aside off the plane");
        assert!(checked > 50_000, "{name}: {checked}");
    }
}

/// The inside's mean over `region` of each layer that lights it: (direct, indirect).
fn inside_means(film: &photonwave::film::Film) -> (f64, f64) {
    let n = film.pixels.len() as f64;
    let grey = |v: Vec3| f64::from(v.element_sum()) / 3.0;
    let direct = film.pixels.iter().map(|t| grey(t.direct)).sum::<f64>() / n;
    let indirect = film.pixels.iter().map(|t| grey(t.indirect + t.caustic)).sum::<f64>() / n;
    (direct, indirect)
}

/// Renders of a sunlit scene and its dark twin agree inside, at 32 seeds (the engines in turn),
/// at the same budget: one pass, and 3 progressive passes with and without the edge correction.
/// Per seed the difference of the inside's mean direct and indirect light; over the seeds, its
/// mean must be 0 within 5 of its standard errors plus 1 % of the layer. Both renders hold the
/// same photons where the camera reads (asserted), but their photons are not the same ones, and
/// the sun's light samples are chosen by power, so the sunlit direct layer is noisier but not
/// biased. Measured: one pass +1.3 % and +1.5 % ± 0.8 % of indirect light, 3 passes +0.4 % ±
/// 0.4 %; the one-pass rows, 2 standard errors, are not explained. Before issue 44, at equal
/// budgets: indirect light +6.9 % (progressive, corrected) and −6.4 % (uncorrected), the first
/// radius set by the sunlit ground's photons.
fn renders_the_same_with_light_outside(name: &str) {
    let (sunlit, dark) = with_twin(name);
    let (sunlit_scene, dark_scene) = (Arc::new(sunlit.scene), Arc::new(dark.scene));
    let share = dark_scene.total_power().element_sum() / sunlit_scene.total_power().element_sum();
    assert!(share < 0.2, "{name}: the panel's share of the power is {share}");
    let rays = sunlit.camera.unwrap().prepare(16, 16).unwrap();
    let base =
        Settings { width: 16, height: 16, spp: 1, photons: 3_000, gather_rays: 4, threads: 1, ..Default::default() };
    for (mode, passes, corrected) in [("one pass", 1, true), ("3 passes", 3, true), ("3 passes, uncorrected", 3, false)]
    {
        let mut diffs: Vec<(f64, f64)> = Vec::new();
        let mut level = (0.0, 0.0);
        for seed in common::SEEDS {
            let engine = if seed.is_multiple_of(2) { Engine::Reference } else { Engine::Wavefront };
            let s = Settings { seed, passes, boundary_correction: corrected, ..base.clone() };
            let image = |scene: &Arc<Scene>, s: &Settings| render(scene, &rays, s, engine, None, &NoProgress).unwrap();
            let ((film, dark_stats), (sunlit_film, sunlit_stats)) = (image(&dark_scene, &s), image(&sunlit_scene, &s));
            for stats in [&dark_stats, &sunlit_stats] {
                assert_eq!(stats.global_map.read, u64::from(s.photons * passes), "{name}: {:?}", stats.global_map);
            }
            let (a, b) = (inside_means(&sunlit_film), inside_means(&film));
            diffs.push((a.0 - b.0, a.1 - b.1));
            level = (level.0 + b.0, level.1 + b.1);
        }
        let n = diffs.len() as f64;
        level = (level.0 / n, level.1 / n);
        for (layer, pick, mean_level) in [("direct", 0usize, level.0), ("indirect", 1, level.1)] {
            let d: Vec<f64> = diffs.iter().map(|t| if pick == 0 { t.0 } else { t.1 }).collect();
            let mean = d.iter().sum::<f64>() / n;
            let se = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
            println!(
                "{name}, {mode}, {layer}: sunlit − dark = {:+.2} % ± {:.2} % of {mean_level:.4}",
                100.0 * mean / mean_level,
                100.0 * se / mean_level
            );
            assert!(
                mean.abs() <= 5.0 * se + 0.01 * mean_level,
                "{name}, {mode}, {layer}: the inside changes by {mean} ± {se} of {mean_level} with the sun outside"
            );
        }
    }
}

/// Zero-thickness walls, a sunlit ground far below.
#[test]
fn a_room_of_zero_thickness_walls_renders_the_same_with_light_outside() {
    renders_the_same_with_light_outside("room-sunlit.toml");
}

/// A floor 1 cm above a sunlit ground.
#[test]
fn a_room_on_a_sunlit_ground_renders_the_same_with_light_outside() {
    renders_the_same_with_light_outside("room-on-ground.toml");
}
