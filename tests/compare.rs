//! `compare`: known differences give the known numbers; bad inputs are named.

mod common;

use common::scratch_dir;
use glam::Vec3;
use photonwave::film::{Film, Terms};
use photonwave::tools::compare::compare_files;
use std::process::Command;

/// A 2×1 film whose only non-zero terms are `direct` and `caustic`.
fn film(direct: [Vec3; 2], caustic: [Vec3; 2]) -> Film {
    Film::new(2, 1, (0..2).map(|i| Terms { direct: direct[i], caustic: caustic[i], ..Default::default() }).collect())
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * b.abs().max(1e-12)
}

#[test]
fn known_differences_give_known_numbers() {
    let d = scratch_dir("compare-known");
    let (a, b) = (d.join("a.exr"), d.join("b.exr"));
    // Reference: direct 0.5 grey and 1.0 grey; caustic 0 and 0.2 grey.
    film([Vec3::splat(0.5), Vec3::ONE], [Vec3::ZERO, Vec3::splat(0.2)]).write_exr(&b).unwrap();
    // Image: direct off by (+0.1, 0, −0.1) in the first pixel, exact in the second; caustic
    // doubled in the second pixel.
    film([Vec3::new(0.6, 0.5, 0.4), Vec3::ONE], [Vec3::ZERO, Vec3::splat(0.4)]).write_exr(&a).unwrap();
    let c = compare_files(&a, &b).unwrap();
    let names: Vec<&str> = c.layers.iter().map(|l| l.layer.as_str()).collect();
    assert_eq!(names, ["beauty", "emitted", "direct", "specular", "caustic", "indirect"]);
    let layer = |n: &str| c.layers.iter().find(|l| l.layer == n).unwrap();

    // direct: squared errors 0.01, 0, 0.01 in pixel 0, none in pixel 1; six values.
    let direct = layer("direct");
    assert!(close(direct.rmse, (0.02f64 / 6.0).sqrt()), "{direct:?}");
    // relMSE: 0.01 / (0.25 + 0.01) twice, over six values.
    assert!(close(direct.rel_mse, 2.0 * 0.01 / 0.26 / 6.0), "{direct:?}");
    assert!(close(direct.mean_ratio.unwrap(), 1.0), "{direct:?}");

    // caustic: error 0.2 in the three channels of pixel 1; relMSE 0.04 / (0.04 + 0.01) each.
    let caustic = layer("caustic");
    assert!(close(caustic.rmse, (3.0 * 0.04f64 / 6.0).sqrt()), "{caustic:?}");
    assert!(close(caustic.rel_mse, 3.0 * 0.04 / 0.05 / 6.0), "{caustic:?}");
    assert!(close(caustic.mean_ratio.unwrap(), 2.0), "{caustic:?}");

    // beauty = direct + caustic: pixel 0 as direct; pixel 1 (1.4 against 1.2) in three channels.
    let beauty = layer("beauty");
    assert!(close(beauty.rmse, ((0.02 + 3.0 * 0.04f64) / 6.0).sqrt()), "{beauty:?}");
    assert!(close(beauty.rel_mse, (2.0 * 0.01 / 0.26 + 3.0 * 0.04 / (1.44 + 0.01)) / 6.0), "{beauty:?}");
    assert!(close(beauty.mean_ratio.unwrap(), (1.5 + 4.2) / (1.5 + 3.6)), "{beauty:?}");

    // A term that is black in both: no error, no ratio.
    let emitted = layer("emitted");
    assert_eq!((emitted.rmse, emitted.rel_mse, emitted.mean_ratio), (0.0, 0.0, None));

    // An image against itself.
    assert!(compare_files(&a, &a).unwrap().layers.iter().all(|l| l.rmse == 0.0 && l.rel_mse == 0.0));
}

#[test]
fn cli_prints_json_and_names_bad_inputs() {
    let d = scratch_dir("compare-cli");
    let (a, b, small) = (d.join("a.exr"), d.join("b.exr"), d.join("small.exr"));
    film([Vec3::splat(0.5); 2], [Vec3::ZERO; 2]).write_exr(&a).unwrap();
    film([Vec3::splat(0.25); 2], [Vec3::ZERO; 2]).write_exr(&b).unwrap();
    Film::new(1, 1, vec![Terms::default()]).write_exr(&small).unwrap();
    let run = |args: &[&std::path::Path], json: bool| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_photonwave"));
        cmd.arg("compare").args(args);
        if json {
            cmd.arg("--json");
        }
        cmd.output().unwrap()
    };
    let out = run(&[&a, &b], true);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let direct = v["layers"].as_array().unwrap().iter().find(|l| l["layer"] == "direct").unwrap();
    assert!(close(direct["mean_ratio"].as_f64().unwrap(), 2.0));
    assert!(close(direct["rmse"].as_f64().unwrap(), 0.25));

    let out = run(&[&a, &small], false);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("a.exr") && err.contains("2×1") && err.contains("1×1"), "{err}");

    let missing = d.join("missing.exr");
    let out = run(&[&a, &missing], false);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("missing.exr"), "{err}");

    let text = d.join("text.exr");
    std::fs::write(&text, "not an exr").unwrap();
    let out = run(&[&text, &a], false);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("text.exr") && !err.contains("panicked"), "{err}");
}

#[test]
fn non_finite_pixels_are_refused_with_their_layer() {
    let d = scratch_dir("compare-nan");
    let (a, b) = (d.join("a.exr"), d.join("b.exr"));
    film([Vec3::splat(0.5); 2], [Vec3::new(f32::NAN, 0.0, 0.0), Vec3::ZERO]).write_exr(&a).unwrap();
    film([Vec3::splat(0.5); 2], [Vec3::ZERO; 2]).write_exr(&b).unwrap();
    let e = compare_files(&a, &b).unwrap_err().to_string();
    assert!(e.contains("a.exr") && e.contains("`beauty`") && e.contains("1 of 2 pixels"), "{e}");
}

#[test]
fn a_larger_reference_is_box_filtered_and_blocks_and_speckle_are_reported() {
    let d = scratch_dir("compare-reduced");
    let (a, b, odd) = (d.join("a.exr"), d.join("b.exr"), d.join("odd.exr"));
    // Reference 4×2; each 2×2 square averages to the image's pixel (0.5 and 1.0 grey).
    let grey = |v: f32| Terms { direct: Vec3::splat(v), ..Default::default() };
    let reference = [0.4, 0.6, 0.9, 1.1, 0.6, 0.4, 1.1, 0.9].map(grey);
    Film::new(4, 2, reference.to_vec()).write_exr(&b).unwrap();
    film([Vec3::splat(0.5), Vec3::ONE], [Vec3::ZERO; 2]).write_exr(&a).unwrap();
    let c = compare_files(&a, &b).unwrap();
    assert_eq!(c.reference_reduced, 2);
    assert!(c.layers.iter().all(|l| l.rmse < 1e-6), "{:?}", c.layers);
    // One block (the image is smaller than 32 pixels), exact; no speckle in either.
    assert_eq!((c.blocks.columns, c.blocks.rows, c.blocks.measured), (1, 1, 1));
    assert!(c.blocks.worst.abs() < 1e-6 && c.speckle == 0.0 && c.reference_speckle == 0.0, "{c:?}");
    // 3×2 is not a whole multiple of 2×1: refused, naming both sizes.
    Film::new(3, 2, vec![Terms::default(); 6]).write_exr(&odd).unwrap();
    let e = compare_files(&a, &odd).unwrap_err().to_string();
    assert!(e.contains("2×1") && e.contains("3×2") && e.contains("multiple"), "{e}");
}
