//! Progressive renders converge to the right answer, and their error estimate says how far off
//! they are: checked against path-traced references of two bundled scenes, committed small
//! (`tests/references/`, 32×32, made by `tests/references/make.sh`: photonwave's path tracer,
//! 65 536 samples per pixel).
//!
//! The references' own noise, measured once from two independent 4 096-spp renders (their
//! difference's spread, scaled by √(4 096/65 536)): on `cornell-box`, 0.21 % of a pixel's value
//! (median; 0.8 % at the 90th percentile), 0.07 % of an 8×8 block's mean, 0.007 % of the image
//! mean; on `cornell-spheres`, 0.8 % of a pixel (3 % at the 90th percentile, in the caustics)
//! for one file, half that for the four the test averages; on `interior`, in `INTERIOR_NOISE`.

mod common;

use common::load;
use glam::Vec3;
use photonwave::film::{read_exr_layer, Film};
use photonwave::job::Job;
use photonwave::progress::NoProgress;
use photonwave::progressive::Progressive;
use photonwave::settings::Settings;
use std::path::PathBuf;
use std::sync::Arc;

const SIZE: u32 = 32;

/// A layer of the committed reference of `scene` (grey values, row-major; `""` is beauty): the
/// mean of its files `SCENE-32-SEED.exr`, independent renders with the seeds in their names.
fn reference(scene: &str, layer: &str) -> Vec<f64> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/references");
    let prefix = format!("{scene}-32-");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "exr"))
        .filter(|p| p.file_name().unwrap().to_string_lossy().starts_with(&prefix))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no reference for {scene} in {}", dir.display());
    let mut sum = vec![0.0; (SIZE * SIZE) as usize];
    for path in &files {
        let (w, h, pixels) = read_exr_layer(path, layer).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((w, h), (SIZE, SIZE));
        for (s, &p) in sum.iter_mut().zip(&pixels) {
            *s += grey(p);
        }
    }
    sum.iter().map(|s| s / files.len() as f64).collect()
}

/// Reflected light: beauty less the emission the camera sees directly (exact in both renderers,
/// but at one sample per pixel per pass the light's edge pixels flip between the light's
/// radiance and the ceiling's, which made the passes' image means jump in steps of 9 %).
fn reflected(t: &photonwave::film::Terms) -> f64 {
    grey(t.beauty() - t.emitted)
}

/// Grey value of a beauty pixel.
fn grey(v: Vec3) -> f64 {
    f64::from(v.element_sum()) / 3.0
}

/// The bundled scene file of `scene`: its TOML file, or its Mitsuba file where it has no TOML.
fn file_of(scene: &str) -> String {
    let toml = format!("{scene}.toml");
    if common::bundled(&toml).exists() {
        toml
    } else {
        format!("{scene}.xml")
    }
}

/// `passes` progressive passes of the bundled `scene` at 32×32 with its own settings (per pass:
/// 1 spp and its photons spread as `render --passes` spreads them), seed `seed`: the image, and
/// each pass's 8×8-block means of reflected light ([`reflected`]).
fn passes(scene: &str, passes: u32, seed: u64) -> (Film, Vec<Vec<f64>>) {
    passes_with(scene, passes, seed, |_| {})
}

/// [`passes`] with the scene's settings changed by `change` first.
fn passes_with(scene: &str, passes: u32, seed: u64, change: impl Fn(&mut Settings)) -> (Film, Vec<Vec<f64>>) {
    let loaded = load(&file_of(scene));
    let mut file = Settings { width: SIZE, height: SIZE, seed, threads: 2, ..loaded.settings.clone() };
    change(&mut file);
    let settings = photonwave::progressive::per_pass(&file, Default::default());
    let rays = loaded.camera.unwrap().prepare(SIZE, SIZE).unwrap();
    let scene = Arc::new(loaded.scene);
    let job = common::job(&scene, &settings);
    let mut p = Progressive::new(&scene, &rays, &job);
    let blocks = std::cell::RefCell::new(Vec::new());
    let engine = |job: &Job| {
        let (film, stats) = photonwave::wavefront::render_job(scene.clone(), &rays, job, &NoProgress);
        blocks.borrow_mut().push(block_means(&film.pixels.iter().map(reflected).collect::<Vec<_>>()));
        Ok((film, stats))
    };
    for _ in 0..passes {
        p.step(&engine).unwrap();
    }
    (p.image(), blocks.into_inner())
}

/// The 16 8×8-block means of a 32×32 grey image.
fn block_means(grey: &[f64]) -> Vec<f64> {
    let n = SIZE as usize;
    (0..16)
        .map(|b| {
            let (bx, by) = (b % 4 * 8, b / 4 * 8);
            (0..64).map(|i| grey[(by + i / 8) * n + bx + i % 8]).sum::<f64>() / 64.0
        })
        .collect()
}

/// The bundled diffuse box, 64 progressive passes: the image mean and every 8×8 block's mean lie
/// within a derived tolerance of the path-traced reference. The tolerance of each quantity is
/// t·√(s²/N + σ²_ref): s the spread of that quantity between the N passes (which are
/// independent), σ_ref the reference's measured noise (above), t Student's quantile for N − 1
/// degrees of freedom at a two-sided 0.1 % per quantity (17 of them: a false alarm in under 2 %
/// of seeds). So the test asserts what the issue asks: what is left of the bias is within the
/// noise. Before the edge correction, the bias at the ceiling's and floor's edges put blocks
/// outside (measured in BENCHMARKS.md).
#[test]
fn a_diffuse_box_converges_to_the_path_traced_image() {
    assert_converges("cornell-box", BOX_NOISE, passes("cornell-box", 64, 3));
}

/// The secondary gather changes where the maps are read, not which paths are summed: with every
/// gather ray that lands straight on a Lambertian surface taking it (100 radii: all of them in
/// this box), the diffuse box still converges to the path-traced image, to the same tolerances.
#[test]
fn the_secondary_gather_sums_the_same_paths() {
    assert_converges("cornell-box", BOX_NOISE, passes_with("cornell-box", 64, 5, |s| s.secondary_gather = 100.0));
}

/// The noise of a committed reference, as fractions of an 8×8 block's mean and of the image mean.
struct Noise {
    block: f64,
    mean: f64,
}

/// `cornell-box`'s reference (measured, above; rounded up).
const BOX_NOISE: Noise = Noise { block: 7e-4, mean: 7e-5 };

/// `interior`'s reference, the mean of its four files (measured from their spread: 0.074 % of
/// a block for one file at the median, 0.27 % at the worst block, so 0.14 % for the mean of four;
/// 0.009 % of the image mean; rounded up).
const INTERIOR_NOISE: Noise = Noise { block: 1.5e-3, mean: 1e-4 };

/// The bundled interior (`scenes/interior.xml`, issue 56: two rooms, thin treads, five small
/// lights, a near-mirror floor, absorbing glass), 64 progressive passes: converges to its
/// path-traced reference to the tolerances of [`a_diffuse_box_converges_to_the_path_traced_image`].
#[test]
fn the_interior_converges_to_the_path_traced_image() {
    assert_converges("interior", INTERIOR_NOISE, passes("interior", 64, 3));
}

/// One-pass renders of the bundled interior at its default settings (16 spp, 200 000 global and
/// 100 000 caustic photons), four seeds, against the path-traced reference. One pass is biased
/// (its k-NN density estimates blur; on this scene they read ~1 % dark, measured at six seeds:
/// 0.984–0.999 of the reference's mean, seed-averaged 8×8 blocks 0.98–1.01), so the check allows
/// a stated bias plus 4 standard errors of the seeds' spread: 2 % for the mean (the allowance
/// `tests/render.rs` gives the boxes) and 4 % for each block.
#[test]
fn one_pass_renders_of_the_interior_agree_with_the_path_tracer() {
    let loaded = load("interior.xml");
    let rays = loaded.camera.unwrap().prepare(SIZE, SIZE).unwrap();
    let scene = Arc::new(loaded.scene);
    let emitted = reference("interior", "emitted");
    let reference: Vec<f64> = reference("interior", "").iter().zip(&emitted).map(|(b, e)| b - e).collect();
    let renders: Vec<Vec<f64>> = (1..=4)
        .map(|seed| {
            let s = Settings { width: SIZE, height: SIZE, seed, threads: 2, ..loaded.settings.clone() };
            let (film, _) = photonwave::wavefront::render(scene.clone(), &rays, &s, &NoProgress).unwrap();
            block_means(&film.pixels.iter().map(reflected).collect::<Vec<_>>())
        })
        .collect();
    let n = renders.len() as f64;
    let mean_and_se = |values: Vec<f64>| {
        let mean = values.iter().sum::<f64>() / n;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, (var / n).sqrt())
    };
    let reference_blocks = block_means(&reference);
    for b in 0..16 {
        let (mean, se) = mean_and_se(renders.iter().map(|r| r[b]).collect());
        let tol = 4.0 * se + 0.04 * reference_blocks[b];
        println!(
            "block {b:2}: {:+.2} % (tolerance {:.2} %)",
            100.0 * (mean / reference_blocks[b] - 1.0),
            100.0 * tol / reference_blocks[b]
        );
        assert!(
            (mean - reference_blocks[b]).abs() <= tol,
            "block {b}: {mean} against {} (tolerance {tol})",
            reference_blocks[b]
        );
    }
    let (mean, se) = mean_and_se(renders.iter().map(|r| r.iter().sum::<f64>() / 16.0).collect());
    let reference_mean = reference_blocks.iter().sum::<f64>() / 16.0;
    let tol = 4.0 * se + 0.02 * reference_mean;
    println!("mean: {:+.2} % (tolerance {:.2} %)", 100.0 * (mean / reference_mean - 1.0), 100.0 * tol / reference_mean);
    assert!((mean - reference_mean).abs() <= tol, "mean {mean} against {reference_mean} (tolerance {tol})");
}

/// The assertions of [`a_diffuse_box_converges_to_the_path_traced_image`] on `n` passes of the
/// bundled `scene` whose reference has the noise `noise`: the image and each pass's block means.
fn assert_converges(scene: &str, noise: Noise, (image, per_pass): (Film, Vec<Vec<f64>>)) {
    let n = per_pass.len() as u32;
    assert_eq!(n, 64, "t below is Student's for 63 degrees of freedom");
    let emitted = reference(scene, "emitted");
    let reference: Vec<f64> = reference(scene, "").iter().zip(&emitted).map(|(b, e)| b - e).collect();
    let grey: Vec<f64> = image.pixels.iter().map(reflected).collect();
    let nf = f64::from(n);
    // t for 63 degrees of freedom at two-sided 0.1 %: 3.39 (tables); the normal's is 3.29.
    let t = 3.39;
    let spread = |values: &[f64]| {
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (values.len() - 1) as f64).sqrt()
    };
    let reference_blocks = block_means(&reference);
    let blocks = block_means(&grey);
    for b in 0..16 {
        let s = spread(&per_pass.iter().map(|p| p[b]).collect::<Vec<_>>());
        let tol = t * (s * s / nf + (noise.block * reference_blocks[b]).powi(2)).sqrt();
        let d = blocks[b] - reference_blocks[b];
        println!(
            "block {b:2}: {:+.4} % (tolerance {:.4} %)",
            100.0 * d / reference_blocks[b],
            100.0 * tol / reference_blocks[b]
        );
        assert!(d.abs() <= tol, "block {b}: {} against {} (tolerance {tol})", blocks[b], reference_blocks[b]);
    }
    let means: Vec<f64> = per_pass.iter().map(|p| p.iter().sum::<f64>() / 16.0).collect();
    let (mean, reference_mean) =
        (grey.iter().sum::<f64>() / grey.len() as f64, reference.iter().sum::<f64>() / grey.len() as f64);
    let tol = t * (spread(&means).powi(2) / nf + (noise.mean * reference_mean).powi(2)).sqrt();
    println!("mean: {:+.4} % (tolerance {:.4} %)", 100.0 * (mean / reference_mean - 1.0), 100.0 * tol / reference_mean);
    assert!((mean - reference_mean).abs() <= tol, "mean {mean} against {reference_mean} (tolerance {tol})");
}

/// The error layer is calibrated: on the bundled diffuse box, glass-sphere box and interior
/// after 32 passes, the share of pixels whose actual error (against the reference) lies within the
/// `error` bound is at least its stated 95 %, less a binomial tolerance: 3 standard deviations of
/// a share over n pixels, 3·√(0.95·0.05/n) = 2.0 % for the 1 024 pixels. (Pixels are not quite
/// independent — the passes' photons are shared by all of them — so this is the tolerance the
/// issue asks for, not an exact one.) Measured: 96.6 %, 94.9 % and 96.9 % (the noise alone 94.2 %,
/// 92.3 % and 94.9 %; the boxes read 96.1 % and 95.0 % when this test was written). The reference's own noise widens the actual error a little and is not allowed for;
/// with one 65 536-spp reference instead of four the glass-sphere box fell to 92.9 % here and
/// 90.8 % after 128 passes (95.4 % with four).
#[test]
fn the_error_bound_holds_for_95_percent_of_pixels() {
    for scene in ["cornell-box", "cornell-spheres", "interior"] {
        let reference = reference(scene, "");
        let (image, _) = passes(scene, 32, 5);
        let error = image.error().expect("progressive passes have an error layer");
        let noise = image.noise.as_ref().unwrap();
        let lit: Vec<usize> = (0..reference.len()).filter(|&i| reference[i] > 1e-3).collect();
        let share = |bound: &[f32]| {
            let error = |i: usize| (grey(image.pixels[i].beauty()) - reference[i]).abs();
            lit.iter().filter(|&&i| error(i) <= f64::from(bound[i])).count() as f64 / lit.len() as f64
        };
        let (inside, noise_only) = (share(&error), share(noise));
        let tol = 3.0 * (0.95 * 0.05 / lit.len() as f64).sqrt();
        println!(
            "{scene}: {:.1} % of {} pixels within the bound (noise alone {:.1} %), need ≥ {:.1} %",
            100.0 * inside,
            lit.len(),
            100.0 * noise_only,
            100.0 * (0.95 - tol)
        );
        assert!(inside >= 0.95 - tol, "{scene}: {inside} of pixels within their bound");
    }
}
