//! Progressive photon mapping: the radius sequence, convergence at the predicted rate, seeds and
//! threads, and time budgets.

mod common;

use common::load;
use photonwave::film::Film;
use photonwave::job::{FixedRadii, Job, Pass, PixelRadii};
use photonwave::progress::NoProgress;
use photonwave::progressive::{radius2_scale, Progressive};
use photonwave::scene::camera::CameraRays;
use photonwave::scene::Scene;
use photonwave::settings::Settings;
use std::sync::Arc;

/// Small, fast passes of the glass-sphere box: caustics without final gather.
fn small(seed: u64) -> Settings {
    Settings {
        width: 24,
        height: 24,
        spp: 1,
        photons: 1000,
        caustic_photons: 2000,
        final_gather: false,
        threads: 1,
        seed,
        ..Default::default()
    }
}

/// The bundled glass-sphere box, shared, with its camera at the small settings' size.
fn spheres() -> (Arc<Scene>, CameraRays) {
    let loaded = load("cornell-spheres.toml");
    let s = small(0);
    let cam = loaded.camera.unwrap().prepare(s.width, s.height).unwrap();
    (Arc::new(loaded.scene), cam)
}

/// Runs `passes` progressive passes with the wavefront engine, calling `at(n, image)` after each.
fn progressive(
    (scene, cam): &(Arc<Scene>, CameraRays),
    settings: &Settings,
    passes: u32,
    mut at: impl FnMut(u32, Film),
) {
    let mut p = Progressive::new(scene, cam, &common::job(scene, settings));
    let engine = |job: &Job| Ok(photonwave::wavefront::render_job(scene.clone(), cam, job, &NoProgress));
    for _ in 0..passes {
        p.step(&engine).unwrap();
        at(p.passes(), p.image());
    }
}

fn caustic_rms_difference(a: &Film, b: &Film) -> f64 {
    let se: f64 =
        a.pixels.iter().zip(&b.pixels).map(|(x, y)| f64::from((x.caustic - y.caustic).length_squared())).sum();
    (se / (3 * a.pixels.len()) as f64).sqrt()
}

/// Least-squares slope of log y against log x.
fn log_slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (xs, ys): (Vec<f64>, Vec<f64>) = points.iter().map(|&(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

#[test]
fn radii_shrink_as_knaus_and_zwicker_prescribe() {
    let alpha = 2.0 / 3.0;
    assert_eq!(radius2_scale(1, alpha), 1.0);
    assert!((radius2_scale(2, alpha) - (1.0 + 2.0 / 3.0) / 2.0).abs() < 1e-7);
    // r²ᵢ ∝ i^(α−1) asymptotically: the ratio over a doubling of i tends to 2^(−1/3).
    let ratio = radius2_scale(20_000, alpha) / radius2_scale(10_000, alpha);
    assert!((ratio - 2f64.powf(alpha as f64 - 1.0)).abs() < 1e-4, "{ratio}");
    for i in 1..100 {
        assert!(radius2_scale(i + 1, alpha) < radius2_scale(i, alpha));
    }
}

/// The caustic layer's error falls as passes grow, at the rate the radius sequence predicts.
///
/// Two independent runs (different seeds) differ by √2 × each one's noise, with the bias
/// cancelled, so their RMS difference measures the variance part of the error without a
/// converged reference. For a fixed photon count per pass the variance of pass i ∝ 1/r²ᵢ, so the
/// mean of N passes has variance ∝ Σᵢ 1/r²ᵢ / N² — predicted slope −0.394 over N = 1…16 for
/// α = 2/3 (−1/3 asymptotically; camera jitter at 1 spp, whose variance falls as 1/N, pulls the
/// measured slope toward −1/2). Squared differences are pooled over 4 seed pairs. Tolerance:
/// single pairs' slopes spread with a standard deviation of 0.27 (6 pairs measured, 24² pixels,
/// dominated by a few bright caustic pixels), so the pooled slope's standard error is ≈ 0.14;
/// ±0.3 is ≈ 2.2 of them, and a render that did not converge (slope ≥ 0) fails by ≥ 2.7.
/// The same runs are also measured against a converged reference (below).
#[test]
fn progressive_error_falls_at_the_predicted_rate() {
    let shared = spheres();
    let mut reference = None;
    progressive(&shared, &small(1000), 64, |n, f| {
        if n == 64 {
            reference = Some(f);
        }
    });
    let reference = reference.unwrap();
    let marks = [1u32, 2, 4, 8, 16];
    let mut mse = [0.0f64; 5];
    let mut against = [0.0f64; 2];
    for pair in 0..4u64 {
        let mut runs = [Vec::new(), Vec::new()];
        for (k, run) in runs.iter_mut().enumerate() {
            progressive(&shared, &small(100 + 2 * pair + k as u64), 16, |n, f| {
                if marks.contains(&n) {
                    run.push(f);
                }
            });
        }
        for (m, (a, b)) in mse.iter_mut().zip(runs[0].iter().zip(&runs[1])) {
            *m += caustic_rms_difference(a, b).powi(2) / 4.0;
        }
        against[0] += caustic_rms_difference(&runs[0][0], &reference).powi(2) / 4.0;
        against[1] += caustic_rms_difference(&runs[0][4], &reference).powi(2) / 4.0;
    }
    let points: Vec<(f64, f64)> = marks.iter().zip(&mse).map(|(&n, &m)| (f64::from(n), m.sqrt())).collect();
    let alpha = small(0).alpha;
    let predicted: Vec<(f64, f64)> = marks
        .iter()
        .map(|&n| {
            (f64::from(n), ((1..=n).map(|i| 1.0 / radius2_scale(i, alpha)).sum::<f64>() / f64::from(n * n)).sqrt())
        })
        .collect();
    let (measured, expected) = (log_slope(&points), log_slope(&predicted));
    assert!((expected + 0.394).abs() < 0.005, "{expected}");

    // Against a converged reference (64 passes, another seed) the error includes the bias and
    // the reference's own error (≈ 64^(−1/3) = 0.25 of one pass's): from the rates above one
    // expects error(16) ≈ √(0.42² + 0.25²) ≈ 0.5 × error(1). The pooled slope's standard error
    // (0.14) spreads its logarithm by ±0.14·ln 16 ≈ ±0.39 per standard error, so
    // "error(16) < error(1)" holds with ln 2 / 0.39 ≈ 1.8 of them to spare (fixed seeds: the
    // outcome is deterministic; measured 0.0276 → 0.0066, 0.24×); a render that does not
    // converge toward the reference fails it.
    let against = against.map(f64::sqrt);
    println!("caustic RMSE against a 64-pass reference: {:.4} after 1 pass, {:.4} after 16", against[0], against[1]);
    assert!(against[1] < against[0], "{against:?}");
    assert!(points[4].1 < 0.5 * points[0].1, "error did not fall: {points:?}");
    println!("caustic RMS difference {points:?}: slope {measured:.3}, predicted {expected:.3}");
    assert!((measured - expected).abs() < 0.3, "slope {measured:.3}, predicted {expected:.3}: {points:?}");
}

/// The same seed gives the same progressive image at 1 and 2 threads.
#[test]
fn same_seed_same_image_at_any_thread_count() {
    let shared = spheres();
    let mut images = Vec::new();
    for threads in [1, 2] {
        let mut last = None;
        progressive(&shared, &Settings { threads, ..small(7) }, 3, |_, f| last = Some(f));
        images.push(last.unwrap());
    }
    assert_eq!(images[0], images[1]);
}

/// `--time` ends within 5 % of the budget, counted by the process's wall clock (scene loading
/// and writing the EXR included), with short passes: one sample per pixel and 4 gather rays, so
/// that a pass is mostly its two photon batches (at 16 samples and 16 gather rays a pass took
/// ~100 ms on a 2.5 GHz Xeon and ~400 ms with other tests sharing its two cores, too few passes
/// for the test's premise; now ~70–90 ms alone there).
#[test]
fn time_budget_is_met_within_five_percent() {
    let d = common::scratch_dir("time-budget");
    let (out, stats) = (d.join("t.exr"), d.join("t.json"));
    let budget = 2.0;
    let t = std::time::Instant::now();
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_photonwave"))
        .args(["render", common::bundled("cornell-spheres.toml").to_str().unwrap()])
        .args(["--width", "32", "--height", "32", "--spp", "1", "--gather-rays", "4"])
        .args(["--photons", "1000", "--caustic-photons", "2000"])
        .args(["--time", "2s", "--threads", "1", "-q", "-o", out.to_str().unwrap(), "--stats", stats.to_str().unwrap()])
        .output()
        .unwrap();
    let wall = t.elapsed().as_secs_f64();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let s: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    // Passes of 20–90 ms alone (by machine), slower when other tests share the two cores; at
    // least 8 keeps one pass under 5 % of the budget (the render ends within half a pass of it).
    let passes = s["progressive"]["passes"].as_u64().unwrap();
    assert!(passes >= 8, "{passes} passes");
    assert!(
        (wall - budget).abs() <= 0.05 * budget,
        "finished after {wall:.3} s for a {budget} s budget ({passes} passes)"
    );
}

/// Presets set only the amounts of work, leave the scene's other settings alone, and say which
/// amounts are per pass.
#[test]
fn presets_set_only_amounts_of_work() {
    use photonwave::progressive::PerPass;
    use photonwave::settings::Preset;
    let scene_file =
        Settings { width: 50, k: 20, caustic_radius: 0.01, max_depth: 3, seed: 5, spp: 9, ..Default::default() };
    let amounts = |s: &Settings| (s.passes, s.spp, s.photons, s.caustic_photons, s.gather_rays);
    let rest = |s: &Settings| (s.width, s.k, s.caustic_radius, s.max_depth, s.seed);
    let all = PerPass { spp: true, photons: true, caustic_photons: true };
    let d = Settings::default();
    for (preset, expect, per_pass) in [
        (Preset::Reference, (512, 4, 100_000, 100_000, 16), all),
        (Preset::Preview, (1, 4, 50_000, 25_000, 8), PerPass::default()),
        (Preset::Default, amounts(&d), PerPass::default()),
    ] {
        let mut s = scene_file.clone();
        assert_eq!(preset.apply(&mut s), per_pass, "{preset:?}");
        assert_eq!(amounts(&s), expect, "{preset:?}");
        assert_eq!(rest(&s), rest(&scene_file), "{preset:?}");
        s.validate().unwrap();
    }
}

/// Spreading a one-pass render over passes: 1 spp and photons / spp a pass (the caustic map's
/// too), but at least one global photon per pixel (`GLOBAL_PHOTONS_PER_PIXEL`) — not when the
/// photons are given per pass.
#[test]
fn passes_trace_at_least_a_global_photon_per_pixel() {
    use photonwave::progressive::{per_pass, PerPass, GLOBAL_PHOTONS_PER_PIXEL};
    assert_eq!(GLOBAL_PHOTONS_PER_PIXEL, 1);
    let file = |w: u32| Settings {
        width: w,
        height: w,
        spp: 16,
        photons: 200_000,
        caustic_photons: 100_000,
        ..Default::default()
    };
    let amounts = |s: &Settings| (s.spp, s.photons, s.caustic_photons);
    assert_eq!(amounts(&per_pass(&file(64), PerPass::default())), (1, 12_500, 6_250));
    assert_eq!(amounts(&per_pass(&file(256), PerPass::default())), (1, 65_536, 6_250));
    let given = PerPass { photons: true, ..PerPass::default() };
    assert_eq!(amounts(&per_pass(&file(256), given)), (1, 200_000, 6_250));
}

/// `render --preset reference`: the preset's amounts are per pass, flags override them, and
/// without a preset `--passes` spreads the default amounts over the passes.
#[test]
fn cli_preset_reference_renders_progressive_passes() {
    let d = common::scratch_dir("preset");
    let scene = common::bundled("cornell-spheres.toml");
    let render = |extra: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_photonwave"))
            .args(["render", scene.to_str().unwrap(), "--width", "8", "--height", "8"])
            .args(["-o", d.join("p.exr").to_str().unwrap(), "--stats", d.join("p.json").to_str().unwrap()])
            .args(extra)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{err}");
        let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("p.json")).unwrap()).unwrap();
        (err, stats)
    };
    let (err, stats) = render(&[
        "--preset",
        "reference",
        "--passes",
        "2",
        "--spp",
        "1",
        "--photons",
        "3000",
        "--caustic-photons",
        "3000",
    ]);
    assert!(err.contains("progressive: 2 passes, each 1 spp, 3000 global photons + 3000 caustic photons"), "{err}");
    assert_eq!(stats["progressive"]["passes"], 2);
    assert_eq!(stats["spp"], 2);
    let (err, _) = render(&["--passes", "2"]);
    assert!(err.contains("progressive: 2 passes, each 1 spp, 12500 global photons + 6250 caustic photons"), "{err}");
}

/// One fixed-radius pass of the small spheres scene with the given radii.
fn fixed_pass(scene: &Scene, radii: FixedRadii) -> Job {
    let job = common::job(scene, &Settings { final_gather: false, ..small(11) });
    job.with_pass(Pass { seed: job.settings.seed, radii: Some(radii) }).unwrap()
}

/// Per-pixel radii reach the estimates pixel by pixel, in both engines: radii equal to the
/// uniform ones give the same image bit for bit; a larger radius in one pixel changes that
/// pixel's caustic and (final gathering off) indirect terms and no other pixel.
#[test]
fn per_pixel_radii_apply_to_their_own_pixel_only() {
    use photonwave::engine::{render_job, Engine};
    let (scene, cam) = spheres();
    let n = 24 * 24;
    let uniform = FixedRadii { scale: 0.8, ..FixedRadii::uniform(0.03, 0.01) };
    let with = |global: Vec<f32>, caustic: Vec<f32>| FixedRadii {
        pixels: Some(Arc::new(PixelRadii { global, caustic })),
        ..uniform.clone()
    };
    // Pixel radii are scaled by `scale`; the uniform ones are already this pass's.
    let same = with(vec![0.03 / 0.8; n], vec![0.01 / 0.8; n]);
    for engine in [Engine::Wavefront, Engine::Reference] {
        let image = |r: FixedRadii| render_job(&scene, &cam, &fixed_pass(&scene, r), engine, &NoProgress).0;
        let base = image(uniform.clone());
        // The pixel that sees the brightest caustic directly (on the floor under the glass).
        let pixel = (0..n).max_by(|&a, &b| base.pixels[a].caustic.x.total_cmp(&base.pixels[b].caustic.x)).unwrap();
        let mut bigger = (vec![0.03 / 0.8; n], vec![0.01 / 0.8; n]);
        bigger.0[pixel] *= 2.0;
        bigger.1[pixel] *= 2.0;
        let bigger = with(bigger.0, bigger.1);
        assert_eq!(base, image(same.clone()), "{engine:?}");
        let changed = image(bigger.clone());
        for (i, (a, b)) in base.pixels.iter().zip(&changed.pixels).enumerate() {
            if i == pixel {
                assert!(a.caustic != b.caustic && a.indirect != b.indirect, "{engine:?}: {a:?}");
                assert_eq!((a.direct, a.emitted), (b.direct, b.emitted), "{engine:?}");
            } else {
                assert_eq!(a, b, "{engine:?}: pixel {i} changed");
            }
        }
    }
}

/// Each pixel's first radius is a k-NN radius capped at the maximum radius: small in the glass
/// sphere's focused caustic, the maximum where the caustic is sparse; global radii only where
/// the camera reads the global map. Measured (issue 53): 46 of the 576 pixels find their 48
/// photons within the maximum radius and 43 within half of it (the spot under the sphere, about
/// 7 pixels across); at least 10 of each are asserted — a caustic lost, or blurred to the
/// maximum radius, leaves none. (Commit 25a6eb9 had relaxed it from 3 to 1 focused pixel.)
#[test]
fn pixel_radii_follow_the_photon_density() {
    use photonwave::progressive::{initial_radii, pixel_radii};
    let (scene, cam) = spheres();
    let s = Settings { caustic_photons: 20_000, ..small(5) };
    let d = scene.diagonal();
    let r_max = s.caustic_radius * d;
    let first = initial_radii(&scene, &cam, &common::job(&scene, &s));
    let pixels = first.pixels.as_deref().expect("per-pixel radii are on by default");
    assert_eq!((pixels.caustic.len(), pixels.global.len()), (24 * 24, 24 * 24));
    assert!(pixels.caustic.iter().all(|&r| r > 0.0 && r <= r_max));
    let focused = pixels.caustic.iter().filter(|&&r| r < 0.5 * r_max).count();
    let mut sorted = pixels.caustic.clone();
    sorted.sort_by(f32::total_cmp);
    let dense = pixels.caustic.iter().filter(|&&r| r < r_max).count();
    println!("{dense} pixels with a dense caustic, {focused} focused: {:?}", &sorted[..10]);
    assert!(
        dense >= 10 && focused >= 10,
        "{dense} pixels with a dense caustic, {focused} focused: {:?}",
        &sorted[..10]
    );
    assert!(pixels.caustic.iter().filter(|&&r| r == r_max).count() > 24 * 24 / 2);
    assert!(pixels.global.iter().all(|&r| r > 0.0 && r <= s.global_radius * d));

    // Final gathering reads the global map at gather hits only: no global radii per pixel.
    let gather = Settings { final_gather: true, ..s.clone() };
    let (maps, _, _) = photonwave::reference::build_maps(&scene, &gather).unwrap();
    let uniform = FixedRadii::uniform(0.1, 0.1);
    assert!(pixel_radii(&scene, &cam, &common::job(&scene, &gather), &maps, &uniform).global.is_empty());
    let uniform_only = common::job(&scene, &Settings { per_pixel_radii: false, ..s });
    assert!(initial_radii(&scene, &cam, &uniform_only).pixels.is_none());
}

/// Progressive passes converge to the path tracer's indirect light (caustics included; the path
/// tracer files them under `indirect`), and never read irradiance precomputed at photons: under
/// small fixed radii that was biased low, 3.6 % after 64 passes and 5.2 % after 512 on this
/// scene (src/transport/maps.rs, `precompute_irradiance`).
///
/// Tolerance: 3 standard errors of the mean per-pixel difference (structure cancels; measured
/// 0.8 % of the mean) plus 2 % for the fixed radii's remaining blur at edges and corners
/// (measured 0.04 % at 64², 2 % here). That catches gross biases, not the 3.6 % one; the exact
/// check below does.
#[test]
fn progressive_indirect_light_matches_the_path_tracer() {
    let loaded = load("cornell-spheres.toml");
    let base = Settings { width: 32, height: 32, ..Default::default() };
    let cam = loaded.camera.unwrap().prepare(32, 32).unwrap();
    let scene = Arc::new(loaded.scene);
    let pass = photonwave::progressive::per_pass(&Settings { passes: 64, ..base.clone() }, Default::default());
    let (pm, stats) =
        photonwave::engine::render(&scene, &cam, &pass, photonwave::engine::Engine::Wavefront, None, &NoProgress)
            .unwrap();
    assert_eq!(stats.irradiance_points, 0, "progressive passes must not precompute irradiance");
    let pt =
        photonwave::path::render_path_traced(&scene, &cam, &Settings { spp: 2048, ..base }, &NoProgress).unwrap().0;
    let grey = |v: glam::Vec3| v.element_sum() / 3.0;
    let pm: Vec<f32> = pm.pixels.iter().map(|t| grey(t.caustic + t.indirect)).collect();
    let pt: Vec<f32> = pt.pixels.iter().map(|t| grey(t.indirect)).collect();
    let diff: Vec<f32> = pm.iter().zip(&pt).map(|(a, b)| a - b).collect();
    let (m_pm, m_pt, se) = (common::mean_and_se(&pm).0, common::mean_and_se(&pt).0, common::mean_and_se(&diff).1);
    println!("caustic + indirect: progressive {m_pm:.6}, path traced {m_pt:.6} (ratio {:.4}, se {se:.6})", m_pm / m_pt);
    assert!((m_pm - m_pt).abs() < 3.0 * se + 0.02 * m_pt, "progressive {m_pm} vs path traced {m_pt} (se {se})");
}

/// The noise is the half-width of a 95 % Student-t interval of each pixel's mean over the
/// passes: with passes whose beauty grey value alternates a ± d in every pixel (exactly
/// representable values), it must equal t(N−1)·s/√N, s the passes' sample standard deviation,
/// to 1e-6 relative; and the `error` bound adds the size of the passes' mean bias's grey value,
/// extrapolated from the passes that estimate it (`BIAS_EVERY`) as ∝ r².
/// One pass has neither. The t quantile itself is checked against tables (0.5 %).
#[test]
fn the_error_layer_is_the_passes_spread_plus_the_bias() {
    use photonwave::progressive::student_t975;
    for (dof, table) in [(1u32, 12.706f64), (4, 2.776), (10, 2.228), (30, 2.042), (100, 1.984)] {
        assert!((student_t975(dof) / table - 1.0).abs() < 0.005, "t({dof}) = {}", student_t975(dof));
    }
    let (scene, cam) = spheres();
    let settings = small(3);
    let mut p = Progressive::new(&scene, &cam, &common::job(&scene, &settings));
    let (a, d, bias) = (0.5f32, 0.125f32, 0.01f32);
    let n = (settings.width * settings.height) as usize;
    // Pass k gives a + d for even k and a − d for odd k.
    let calls = std::cell::Cell::new(0u32);
    // A pass that estimates its bias reports one ∝ r² (the model the extrapolation assumes).
    let fake = |job: &Job| -> photonwave::Result<(Film, photonwave::stats::RenderStats)> {
        let v = if calls.get().is_multiple_of(2) { a + d } else { a - d };
        calls.set(calls.get() + 1);
        let radii = job.pass.radii.as_ref().unwrap();
        let s = if radii.bias { radii.scale * radii.scale } else { 0.0 };
        let t = photonwave::film::Terms {
            direct: glam::Vec3::splat(v),
            bias: glam::Vec3::new(-3.0, 1.0, 0.5) * bias * s,
            ..Default::default()
        };
        let film = Film::new(settings.width, settings.height, vec![t; n]);
        Ok((film, photonwave::stats::RenderStats::default()))
    };
    p.step(&fake).unwrap();
    assert!(p.image().noise.is_none() && p.image().error().is_none());
    for _ in 0..7 {
        p.step(&fake).unwrap();
    }
    let image = p.image();
    let values: Vec<f64> = (0..8u32).map(|k| f64::from(if k.is_multiple_of(2) { a + d } else { a - d })).collect();
    let nf = values.len() as f64;
    let mean = values.iter().sum::<f64>() / nf;
    let s = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (nf - 1.0)).sqrt();
    let want = student_t975(7) * s / nf.sqrt();
    let noise = image.noise.as_ref().expect("eight passes have a noise estimate");
    assert!(want > 0.0, "the passes must differ for this test to mean anything");
    assert!(noise.iter().all(|&e| (f64::from(e) / want - 1.0).abs() < 1e-6), "{} vs {want}", noise[0]);
    // The bound adds the size of the bias's grey value, |(−3 + 1 + 0.5)/3 · bias| = bias / 2, times
    // the passes' mean r²/r²₁: estimated in passes 0 and 4 only, extrapolated to all eight.
    let error = image.error().expect("and an error bound");
    let mean_s = (1..=8).map(|i| radius2_scale(i, settings.alpha)).sum::<f64>() / 8.0;
    let want = want + f64::from(bias) / 2.0 * mean_s;
    assert!(error.iter().all(|&e| (f64::from(e) / want - 1.0).abs() < 1e-6), "{} vs {want}", error[0]);
}

/// `target_error` stops at the first pass whose image noise (mean `error` half-width over the
/// image mean) is at most the target, after at least 4 passes: the same render with one pass
/// fewer is still above it. The noise it reports is the noise of the image it wrote: recomputed
/// from the film's error layer and pixels, to 1e-4 relative (f32 layer against f64 sums).
#[test]
fn target_error_stops_at_the_error_it_reports() {
    use photonwave::engine::{render, Engine};
    let (scene, cam) = spheres();
    let target = 0.25f32;
    let s = Settings { target_error: target, ..small(4) };
    let (film, stats) = render(&scene, &cam, &s, Engine::Wavefront, None, &NoProgress).unwrap();
    let p = stats.progressive.expect("a target makes a progressive render");
    let error = p.error_95.expect("at least two passes").error;
    assert!(p.passes >= 4 && error <= f64::from(target), "{} passes, error {error}", p.passes);
    assert_eq!(p.target_error, Some(target));
    let layer = film.error().unwrap();
    let mean_error = layer.iter().map(|&v| f64::from(v)).sum::<f64>() / layer.len() as f64;
    let mean = film.pixels.iter().map(|t| f64::from(t.beauty().element_sum()) / 3.0).sum::<f64>() / layer.len() as f64;
    assert!((mean_error / mean / error - 1.0).abs() < 1e-4, "{} vs {error}", mean_error / mean);
    // The target is far enough that the minimum of 4 passes is not what stopped it.
    assert!(p.passes > 4, "{} passes", p.passes);
    let fewer = Settings { target_error: 0.0, passes: p.passes - 1, ..s };
    let (_, before) = render(&scene, &cam, &fewer, Engine::Wavefront, None, &NoProgress).unwrap();
    let before = before.progressive.unwrap().error_95.unwrap().error;
    assert!(before > f64::from(target), "one pass fewer already had error {before}");
}
