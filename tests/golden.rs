//! Golden hashes of a handful of small renders: every bit of every pixel of every term, on both
//! photon-mapping engines and the path tracer, one-pass and progressive, at 1 and 2 threads.
//! A redesign that must not change images (issue 14) is checked against these.
//!
//! When an image changes on purpose (a new estimator, a fixed bug), the failure prints the new
//! hash: replace the old one in `GOLDEN` below and say in the commit why the images changed.
//! Hashes hold for this project's build flags (`.cargo/config.toml`: x86-64-v3) on x86-64 Linux;
//! elsewhere the test only checks that thread counts agree.

mod common;

use common::*;
use photonwave::engine::{render, Engine};
use photonwave::film::Film;
use photonwave::progress::NoProgress;
use photonwave::settings::Settings;
use std::sync::Arc;

/// (scene, engine, passes) → FNV-1a 64 of the film's f32 bits.
const GOLDEN: &[(&str, &str, u32, u64)] = &[
    ("cornell-box.toml", "wavefront", 1, 0x73564a7835fda6cf),
    ("cornell-box.toml", "reference", 1, 0x06479470161e4c11),
    ("cornell-box.toml", "path", 1, 0xb2e8d4765d127368),
    ("cornell-spheres.toml", "wavefront", 1, 0x452a5b76c2f225ef),
    ("cornell-spheres.toml", "reference", 1, 0x5e40e89365bc71fb),
    ("cornell-spheres.toml", "wavefront", 3, 0xc5f72ace8746ed0d),
    ("cornell-spheres.toml", "reference", 3, 0x55d571118c183f8e),
    ("hard/furnace-materials.toml", "wavefront", 1, 0xc3ebd9a5ae1d66b1),
    ("hard/furnace-materials.toml", "reference", 1, 0xb20cd7116331caa4),
    ("hard/nested.toml", "wavefront", 2, 0x5297a2f963c0a976),
];

/// FNV-1a over the bits of every term of every pixel, in film order.
fn hash(film: &Film) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for t in &film.pixels {
        for v in t.as_array() {
            for c in v.to_array() {
                for b in c.to_bits().to_le_bytes() {
                    h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
                }
            }
        }
    }
    h
}

fn engine(name: &str) -> Engine {
    match name {
        "wavefront" => Engine::Wavefront,
        "reference" => Engine::Reference,
        _ => Engine::Path,
    }
}

#[test]
fn renders_match_their_golden_hashes() {
    let exact = cfg!(all(target_arch = "x86_64", target_os = "linux", target_feature = "avx2", target_feature = "fma"));
    let mut wrong = Vec::new();
    for &(scene, name, passes, want) in GOLDEN {
        let loaded = load(scene);
        let settings = Settings {
            width: 12,
            height: 12,
            spp: 2,
            photons: 3000,
            caustic_photons: 3000,
            gather_rays: 4,
            passes,
            ..loaded.settings.clone()
        };
        let rays = loaded.camera.unwrap().prepare(settings.width, settings.height).unwrap();
        let scene_arc = Arc::new(loaded.scene);
        let hashes: Vec<u64> = [1, 2]
            .iter()
            .map(|&threads| {
                let s = Settings { threads, ..settings.clone() };
                hash(&render(&scene_arc, &rays, &s, engine(name), None, &NoProgress).unwrap().0)
            })
            .collect();
        assert_eq!(hashes[0], hashes[1], "{scene}, {name}, {passes} passes: 1 and 2 threads differ");
        if exact && hashes[0] != want {
            wrong.push(format!("    (\"{scene}\", \"{name}\", {passes}, {:#018x}),", hashes[0]));
        }
    }
    assert!(
        wrong.is_empty(),
        "images changed; if on purpose, put these lines in GOLDEN (tests/golden.rs) and say why in the commit:\n{}",
        wrong.join("\n")
    );
}
