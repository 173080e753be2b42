//! Divided renders (issue 16): pass sets rendered apart and merged equal the undivided render
//! bit for bit, on both engines, whatever the split and the thread counts; bad partial films are
//! refused by name; a render stopped by SIGTERM and resumed equals an uninterrupted one; an
//! interrupted checkpoint write leaves the previous checkpoint readable.

mod common;

use photonwave::divided::partial::{self, Identity};
use photonwave::divided::pass_sums::{radius2_scale, RadiusSequence};
use photonwave::engine::Engine;
use photonwave::film::Film;
use photonwave::job::Job;
use photonwave::progress::NoProgress;
use photonwave::progressive::Progressive;
use photonwave::scene::camera::CameraRays;
use photonwave::scene::Scene;
use photonwave::settings::Settings;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

/// A fresh scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("photonwave-divided-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Every bit of a film: its terms, bias and noise.
fn bits(f: &Film) -> Vec<u32> {
    let mut out: Vec<u32> = f
        .pixels
        .iter()
        .flat_map(|t| t.as_array().into_iter().chain([t.bias]))
        .flat_map(|v| v.to_array())
        .map(f32::to_bits)
        .collect();
    out.extend(f.noise.iter().flatten().map(|v| v.to_bits()));
    out
}

/// The small render the tests divide: the bundled glass-and-mirror box at 24×24, 1 spp and
/// 3 000 photons per map per pass, with `threads` workers.
fn setup(threads: u32) -> (Arc<Scene>, CameraRays, Settings) {
    let loaded = common::load("cornell-spheres.toml");
    let settings = Settings {
        width: 24,
        height: 24,
        spp: 1,
        photons: 3000,
        caustic_photons: 3000,
        gather_rays: 4,
        threads,
        seed: 7,
        ..loaded.settings.clone()
    };
    let rays = loaded.camera.unwrap().prepare(24, 24).unwrap();
    (Arc::new(loaded.scene), rays, settings)
}

/// Passes `indices` (increasing) of the small render with `engine` on `threads` workers.
fn render_passes(engine: Engine, indices: &[u32], threads: u32) -> Progressive {
    let (scene, rays, settings) = setup(threads);
    let job = common::job(&scene, &settings);
    let mut p = Progressive::new(&scene, &rays, &job);
    let run = |job: &Job| Ok(photonwave::engine::render_job(&scene, &rays, job, engine, &NoProgress));
    for &i in indices {
        p.step_pass(i, &run).unwrap();
    }
    p
}

/// The merge of every split of passes 0..6 — one part, two ranges, three strides of 3 — on both
/// engines, with parts on 1 thread and the undivided render on 2, through partial films written
/// and read back, is the undivided render's film bit for bit.
#[test]
fn merges_of_any_split_equal_the_undivided_render() {
    let dir = scratch("splits");
    for engine in [Engine::Wavefront, Engine::Reference] {
        let whole = render_passes(engine, &[0, 1, 2, 3, 4, 5], 2).image();
        let splits: [&[&[u32]]; 3] = [&[&[0, 1, 2, 3, 4, 5]], &[&[0, 1], &[2, 3, 4, 5]], &[&[0, 3], &[1, 4], &[2, 5]]];
        for split in splits {
            let mut parts = Vec::new();
            for (k, indices) in split.iter().enumerate() {
                let p = render_passes(engine, indices, 1);
                let (_, _, settings) = setup(1);
                let identity = Identity::new(&[], &p.job().settings, "camera", &[], &format!("{engine:?}")).unwrap();
                assert_eq!(settings.seed, identity.seed);
                let path = dir.join(format!("{engine:?}-{}-{k}.exr", split.len()));
                partial::write(&path, &identity, &p.sums, 1, &p.image(), &p.stats_now()).unwrap();
                parts.push(partial::read(&path).unwrap());
            }
            // Any order of the files.
            parts.reverse();
            let merged = photonwave::divided::merge::merge(parts.into_iter().map(Ok)).unwrap();
            assert!(merged.missing.is_none());
            assert_eq!(bits(&merged.film), bits(&whole), "{engine:?}, split {split:?}");
        }
    }
}

/// The radius sequence walked forward, backward or in strides gives the bits of the product.
#[test]
fn the_radius_sequence_walks_to_the_same_bits() {
    let alpha = 2.0 / 3.0;
    let mut s = RadiusSequence::new(alpha);
    for i in [0, 5, 3, 19, 35, 2, 100] {
        assert_eq!(s.scale2(i).to_bits(), radius2_scale(i + 1, alpha).to_bits(), "pass {i}");
    }
}

/// The photonwave binary.
fn photonwave() -> Command {
    Command::new(env!("CARGO_BIN_EXE_photonwave"))
}

/// `render` of a bundled scene at 24×24, 1 spp, 2 000 photons per map, quiet, with `extra`.
fn render_cli(scene: &str, out: &Path, extra: &[&str]) -> std::process::Output {
    let scene = common::bundled(scene);
    let mut c = photonwave();
    c.args(["render", scene.to_str().unwrap(), "-q", "--width", "24", "--height", "24", "--spp", "1"]);
    c.args(["--photons", "2000", "--caustic-photons", "2000", "--gather-rays", "4", "-o", out.to_str().unwrap()]);
    c.args(extra).output().unwrap()
}

/// Runs `render_cli` and insists it succeeds.
fn render_ok(scene: &str, out: &Path, extra: &[&str]) {
    let o = render_cli(scene, out, extra);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// `merge` of `parts` into `out`.
fn merge_cli(parts: &[&Path], out: &Path) -> std::process::Output {
    let mut c = photonwave();
    c.arg("merge").args(parts).args(["-q", "-o", out.to_str().unwrap()]);
    c.output().unwrap()
}

/// Through the command line: workers 0/2 and 1/2 merged give the undivided render's EXR byte
/// for byte, diagnostic layers (of the last pass) included, and a worker's file alone is a
/// viewable partial film.
#[test]
fn the_command_line_merge_writes_the_undivided_file() {
    let dir = scratch("cli");
    let whole = dir.join("whole.exr");
    render_ok("cornell-spheres.toml", &whole, &["--passes", "4", "--diagnostics"]);
    let (p0, p1, merged) = (dir.join("p0.exr"), dir.join("p1.exr"), dir.join("merged.exr"));
    render_ok("cornell-spheres.toml", &p0, &["--passes", "4", "--pass-set", "0/2", "--threads", "1", "--diagnostics"]);
    render_ok("cornell-spheres.toml", &p1, &["--passes", "4", "--pass-set", "1/2", "--diagnostics"]);
    let o = merge_cli(&[&p1, &p0], &merged);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::read(&merged).unwrap(), std::fs::read(&whole).unwrap());
    let (_, _, beauty) = photonwave::film::read_exr_layer(&p0, "").unwrap();
    assert!(beauty.iter().any(|v| v.x > 0.0));
}

/// A part of a divided render says so, when it starts and where it names its output: a range
/// from pass 0 (`--passes 0..2`) as much as any other part; a whole progressive render does not.
#[test]
fn a_part_says_it_is_a_partial_film() {
    let dir = scratch("notice");
    for (extra, part) in [(&["--passes", "0..2"][..], true), (&["--passes", "1..2"], true), (&["--passes", "2"], false)]
    {
        let out = dir.join("out.exr");
        let scene = common::bundled("cornell-box.toml");
        let o = photonwave()
            .args(["render", scene.to_str().unwrap(), "--width", "8", "--height", "8", "--photons", "1000"])
            .args(["-o", out.to_str().unwrap()])
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let said = String::from_utf8_lossy(&o.stderr).to_string() + &String::from_utf8_lossy(&o.stdout);
        let starts = said.contains("(a part: ") && said.contains("is a partial film for `photonwave merge`)");
        let ends = said.contains("(a partial film: merge the parts with `photonwave merge`)");
        assert_eq!((starts, ends), (part, part), "{extra:?}: {said}");
    }
}

/// Partial films of another scene, other settings, another seed, overlapping passes, a
/// truncated file and an EXR that is no partial film are refused, naming the files, and no
/// output is written.
#[test]
fn bad_partial_films_are_refused_by_name() {
    let dir = scratch("bad");
    let part = |name: &str, scene: &str, extra: &[&str]| {
        let p = dir.join(name);
        render_ok(scene, &p, extra);
        p
    };
    let a = part("a.exr", "cornell-spheres.toml", &["--passes", "0..2"]);
    let other_scene = part("scene.exr", "cornell-box.toml", &["--passes", "2..4"]);
    let other_settings = part("k.exr", "cornell-spheres.toml", &["--passes", "2..4", "--k", "16"]);
    let other_seed = part("seed.exr", "cornell-spheres.toml", &["--passes", "2..4", "--seed", "9"]);
    let overlap = part("overlap.exr", "cornell-spheres.toml", &["--passes", "1..3"]);
    let plain = part("plain.exr", "cornell-spheres.toml", &["--passes", "2"]);
    let truncated = dir.join("truncated.exr");
    let bytes = std::fs::read(&a).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let out = dir.join("out.exr");
    for (bad, says) in [
        (&other_scene, "different scene files"),
        (&other_settings, "differ in setting `caustic_k`: 48 against 16"),
        (&other_seed, "seed"),
        (&overlap, "both hold passes 1"),
        (&plain, "not a photonwave partial film"),
        (&truncated, "truncated.exr"),
    ] {
        let o = merge_cli(&[&a, bad], &out);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(says), "{}: {err}", bad.display());
        assert!(err.contains(bad.file_name().unwrap().to_str().unwrap()), "{err}");
        assert!(!out.exists());
    }
}

/// Passes in a partial film read back from its text.
fn passes_in(path: &Path) -> usize {
    partial::read(path).unwrap().sums.passes() as usize
}

/// A render stopped by SIGTERM after some of its passes writes them to its checkpoint and exits
/// with 143; resumed, it writes the uninterrupted render's file byte for byte.
#[test]
fn a_render_stopped_by_sigterm_and_resumed_equals_an_uninterrupted_one() {
    let dir = scratch("resume");
    let (ck, out, whole) = (dir.join("ck.exr"), dir.join("resumed.exr"), dir.join("whole.exr"));
    let scene = common::bundled("cornell-spheres.toml");
    let mut child = photonwave()
        .args(["render", scene.to_str().unwrap(), "-q", "--width", "24", "--height", "24", "--spp", "1"])
        .args(["--photons", "2000", "--caustic-photons", "2000", "--gather-rays", "4", "--passes", "120"])
        .args(["--checkpoint", ck.to_str().unwrap(), "--checkpoint-every", "1ms", "-o", out.to_str().unwrap()])
        .spawn()
        .unwrap();
    // Wait for the first checkpoint (after the first pass), then stop the render.
    let t = std::time::Instant::now();
    while !ck.exists() {
        assert!(t.elapsed().as_secs() < 60, "no checkpoint after 60 s");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let killed = Command::new("kill").args(["-TERM", &child.id().to_string()]).status().unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(143), "the render was stopped by SIGTERM");
    let done = passes_in(&ck);
    assert!((1..120).contains(&done), "{done} passes in the checkpoint");
    assert!(!out.exists(), "a stopped render writes its checkpoint, not the image");
    let ck = ck.to_str().unwrap();
    render_ok("cornell-spheres.toml", &out, &["--passes", "120", "--resume", ck, "--checkpoint", ck]);
    render_ok("cornell-spheres.toml", &whole, &["--passes", "120"]);
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&whole).unwrap());
    // The checkpoint was rewritten at the end with every pass.
    assert_eq!(passes_in(Path::new(ck)), 120);
}

/// A checkpoint write that fails half-way (a crash, a full disk) leaves the previous checkpoint
/// whole and readable: partial films are written beside and renamed over.
#[test]
fn an_interrupted_checkpoint_write_keeps_the_previous_one() {
    let dir = scratch("checkpoint");
    let p = render_passes(Engine::Wavefront, &[0, 1], 1);
    let identity = Identity::new(&[], &p.job().settings, "camera", &[], "wavefront").unwrap();
    let path = dir.join("ck.exr");
    partial::write(&path, &identity, &p.sums, 1, &p.image(), &p.stats_now()).unwrap();
    let good = std::fs::read(&path).unwrap();
    let failed = photonwave::files::replace(&path, |tmp| {
        std::fs::write(tmp, &good[..good.len() / 3]).unwrap();
        Err(photonwave::error::Error::output(&path, "killed mid-write"))
    });
    assert!(failed.is_err());
    assert_eq!(std::fs::read(&path).unwrap(), good);
    assert_eq!(passes_in(&path), 2);
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "no temporary left beside it");
}
