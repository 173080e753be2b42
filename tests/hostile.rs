//! A hostile new user's inputs (issue 13): nothing of theirs is lost, nothing crashes or exhausts
//! memory, MTL and OBJ files are read as their spec and real exporters write them, and what is
//! not simulated is said. Each data-loss case checks that the earlier file is intact afterwards.

mod common;

use common::*;
use photonwave::formats::load_scene;
use photonwave::material::Material;
use std::path::{Path, PathBuf};
use std::process::Command;

fn write(dir: &Path, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn cli(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_photonwave")).args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    (out.status.code().unwrap_or(-1), stderr)
}

/// A copy of the bundled Cornell box in its own folder, with a previous render's outputs.
fn workspace(test: &str) -> PathBuf {
    let d = scratch_dir(test);
    for f in ["cornell-box.toml", "cornell-box.obj", "cornell-box.mtl"] {
        std::fs::copy(bundled(f), d.join(f)).unwrap();
    }
    for f in ["a.exr", "p.png", "s.json", "out.exr"] {
        write(&d, f, format!("previous {f}"));
    }
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const SMALL: [&str; 8] = ["--width", "4", "--height", "4", "--spp", "1", "--photons", "500"];

#[test]
fn outputs_never_overwrite_inputs_or_each_other() {
    let d = workspace("no-loss");
    let scene = d.join("cornell-box.toml");
    let before = std::fs::read(&scene).unwrap();
    let (a, p, obj) = (d.join("a.exr"), d.join("p.png"), d.join("cornell-box.obj"));
    // The right extension, but the scene file itself, reached through a link.
    let link = d.join("scene.json");
    #[cfg(unix)]
    std::os::unix::fs::symlink(&scene, &link).unwrap();
    let cases: [(&[&str], &str); 6] = [
        (&["--stats", s(&link)], "is an input"),
        (&["--stats", s(&scene)], "--stats"),
        (&["-o", s(&a), "--stats", s(&a)], "--stats"),
        (&["--png", s(&p), "--stats", s(&p)], "--stats"),
        (&["-o", s(&a), "--png", s(&a)], "--png"),
        (&["-o", s(&obj)], "--output"),
    ];
    #[cfg(not(unix))]
    let cases = &cases[1..];
    for &(extra, flag) in cases.iter() {
        let mut args = vec!["render", s(&scene), "-q"];
        args.extend_from_slice(&SMALL);
        args.extend_from_slice(extra);
        let (code, e) = cli(&args);
        assert!(code != 0 && e.contains(flag), "{extra:?}: {e}");
    }
    assert_eq!(std::fs::read(&scene).unwrap(), before, "the scene file was changed");
    for f in ["a.exr", "p.png", "s.json", "out.exr"] {
        assert_eq!(std::fs::read_to_string(d.join(f)).unwrap(), format!("previous {f}"), "{f} was changed");
    }
}

/// A missing folder for any output is found before the render, and the previous `-o` file is
/// left as it was (it used to be overwritten before `--stats` failed).
#[test]
fn a_missing_output_folder_fails_before_rendering() {
    let d = workspace("no-dir");
    let (scene, out) = (d.join("cornell-box.toml"), d.join("out.exr"));
    let missing = |name: &str| d.join("nodir").join(name).to_str().unwrap().to_string();
    for extra in [
        vec!["-o".to_string(), s(&out).into(), "--stats".into(), missing("s.json")],
        vec!["-o".to_string(), s(&out).into(), "--png".into(), missing("p.png")],
        vec!["-o".to_string(), missing("x.exr"), "--time".into(), "5s".into()],
    ] {
        let mut args = vec!["render", s(&scene), "-q"];
        args.extend_from_slice(&SMALL);
        args.extend(extra.iter().map(String::as_str));
        let t = std::time::Instant::now();
        let (code, e) = cli(&args);
        assert!(code != 0 && e.contains("nodir") && e.contains("does not exist"), "{extra:?}: {e}");
        // A five-second budget would have run out before the error; the check comes first.
        assert!(t.elapsed().as_secs_f64() < 4.0, "{extra:?} rendered before failing");
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "previous out.exr");
    }
}

#[test]
fn devices_are_not_read_as_meshes_or_materials() {
    let d = scratch_dir("devices");
    let obj = write(&d, "a.obj", "mtllib /dev/zero\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let e = load_scene(&obj).err().unwrap().to_string();
    assert!(e.contains("/dev/zero") && e.contains("not a regular file") && e.contains("a.obj:1"), "{e}");
    let toml = write(&d, "s.toml", "[[mesh]]\nfile = \"/dev/zero\"\n");
    let e = load_scene(&toml).err().unwrap().to_string();
    assert!(e.contains("/dev/zero") && e.contains("not a regular file"), "{e}");
}

/// 16384² pixels, from the CLI or the scene file's `[render]` table, are refused with the
/// estimate and the machine's memory before anything is allocated (they aborted allocating
/// 16 GB).
#[test]
fn huge_images_are_refused_with_the_estimate() {
    let d = workspace("huge");
    let scene = d.join("cornell-box.toml");
    let text = std::fs::read_to_string(&scene).unwrap();
    let big = write(&d, "big.toml", text.replace("width = 320\nheight = 320", "width = 16384\nheight = 16384"));
    let out = d.join("out.exr");
    // Where the machine's memory cannot be read (off Linux) nothing is refused; with 41 GiB
    // free these would render (this machine and CI's have 24 GiB).
    match photonwave::memory::machine() {
        Some((free, _)) if free < 41 << 30 => {}
        _ => return,
    }
    for args in [vec!["render", s(&scene), "--width", "16384", "--height", "16384"], vec!["render", s(&big)]] {
        let (code, e) = cli(&[&args[..], &["-o", s(&out)]].concat());
        assert!(code != 0 && e.contains("needs about 40.0 GiB") && e.contains("available of"), "{e}");
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "previous out.exr");
    }
}

/// `compare` on an EXR whose header claims 60000² pixels: refused from its length before any
/// allocation (it aborted allocating 14.4 GB).
#[test]
fn an_exr_header_cannot_claim_more_than_the_file_holds() {
    let d = scratch_dir("exr-header");
    let small = d.join("small.exr");
    photonwave::film::Film::new(8, 4, vec![Default::default(); 32]).write_exr(&small).unwrap();
    let mut bytes = std::fs::read(&small).unwrap();
    let key = b"dataWindow\0box2i\0";
    let at = bytes.windows(key.len()).position(|w| w == key).unwrap() + key.len() + 4;
    for (k, v) in [0i32, 0, 59_999, 59_999].iter().enumerate() {
        bytes[at + 4 * k..at + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
    }
    let huge = write(&d, "huge.exr", &bytes);
    let (code, e) = cli(&["compare", s(&huge), s(&small)]);
    assert!(code != 0 && e.contains("huge.exr") && e.contains("60000×60000"), "{e}");
    let (code, e) = cli(&["compare", "/dev/zero", s(&small)]);
    assert!(code != 0 && e.contains("not a regular file"), "{e}");
}

const MTL: &str = "newmtl light\nKd 0.5 0.5 0.5\nKe 1 1 1\nnewmtl white\nKd 0.5\n";
const OBJ: &str = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nusemtl light\nf 1 3 2\nusemtl white\nf 1 2 4\n";

fn material<'a>(materials: &'a [Material], name: &str) -> &'a Material {
    materials.iter().find(|m| m.name == name).unwrap_or_else(|| panic!("no material `{name}`"))
}

/// A byte-order mark, CR-only and CR LF line ends, a one-number colour, and several MTL files
/// on one `mtllib` line all load as they mean.
#[test]
fn exporters_files_load_as_the_spec_writes_them() {
    let d = scratch_dir("spec");
    write(&d, "m.mtl", [&b"\xEF\xBB\xBF"[..], MTL.replace('\n', "\r").as_bytes()].concat());
    let obj = write(&d, "a.obj", [&b"\xEF\xBB\xBF"[..], OBJ.replace('\n', "\r\n").as_bytes()].concat());
    let scene = load_scene(&obj).unwrap().scene;
    assert_eq!(scene.triangle_count(), 2);
    let white = material(&scene.materials, "white");
    assert_eq!(white.bsdf, photonwave::material::Bsdf::Lambert { kd: glam::Vec3::splat(0.5) });
    let cr_only = write(&d, "cr.obj", OBJ.replace('\n', "\r"));
    assert_eq!(load_scene(&cr_only).unwrap().scene.triangle_count(), 2);
    // Two libraries on one line, the second defining what the first does not.
    write(&d, "lights.mtl", "newmtl light\nKe 1 1 1\n");
    write(&d, "walls.mtl", "newmtl white\nKd 0.25 0.25 0.25\n");
    let two = write(&d, "two.obj", OBJ.replace("mtllib m.mtl", "mtllib lights.mtl walls.mtl"));
    let scene = load_scene(&two).unwrap().scene;
    assert_eq!(
        material(&scene.materials, "white").bsdf,
        photonwave::material::Bsdf::Lambert { kd: glam::Vec3::splat(0.25) }
    );
    // A file name with a space, named whole.
    write(&d, "my walls.mtl", "newmtl white\nKd 0.125 0.125 0.125\nnewmtl light\nKe 2 2 2\n");
    let spaced = write(&d, "spaced.obj", OBJ.replace("mtllib m.mtl", "mtllib my walls.mtl"));
    let white = load_scene(&spaced).unwrap().scene;
    assert_eq!(
        material(&white.materials, "white").bsdf,
        photonwave::material::Bsdf::Lambert { kd: glam::Vec3::splat(0.125) }
    );
}

/// Two OBJ files whose MTL files both define `floor`: each mesh gets its own file's (the second
/// used to get the first's, a grey floor rendering red), and a warning says so.
#[test]
fn materials_are_kept_apart_per_file() {
    let d = scratch_dir("namespace");
    write(&d, "red.mtl", "newmtl floor\nKd 0.8 0 0\nnewmtl light\nKe 1 1 1\n");
    write(&d, "grey.mtl", "newmtl floor\nKd 0.5 0.5 0.5\n");
    write(&d, "red.obj", "mtllib red.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl floor\nf 1 2 3\nusemtl light\nf 1 3 2\n");
    write(&d, "grey.obj", "mtllib grey.mtl\nv 0 0 1\nv 1 0 1\nv 0 1 1\nusemtl floor\nf 1 2 3\n");
    let toml = write(&d, "s.toml", "[[mesh]]\nfile = \"red.obj\"\n[[mesh]]\nfile = \"grey.obj\"\n");
    let loaded = load_scene(&toml).unwrap();
    let scene = &loaded.scene;
    let floors: Vec<_> = scene.materials.iter().filter(|m| m.name == "floor").collect();
    assert_eq!(floors.len(), 2);
    let kd_at_z = |z: f32| {
        let t = (0..scene.triangle_count()).find(|&t| scene.p0[t].z == z && scene.ng[t].z > 0.0).unwrap();
        scene.materials[scene.material[t] as usize].bsdf
    };
    assert_eq!(kd_at_z(0.0), photonwave::material::Bsdf::Lambert { kd: glam::Vec3::new(0.8, 0.0, 0.0) });
    assert_eq!(kd_at_z(1.0), photonwave::material::Bsdf::Lambert { kd: glam::Vec3::splat(0.5) });
    assert!(scene.warnings.iter().any(|w| w.contains("`floor` is defined differently")), "{:?}", scene.warnings);
    assert_eq!(loaded.inputs.len(), 5, "scene, two OBJ and two MTL files: {:?}", loaded.inputs);
}

/// Warnings name their file: skipped degenerate triangles the mesh they were in (one warning per
/// mesh), energy-conserving material fixes the MTL file and line of the material.
#[test]
fn warnings_name_their_file() {
    let d = scratch_dir("warnings-name-files");
    write(
        &d,
        "m.mtl",
        "newmtl white\nKd 0.5 0.5 0.5\nnewmtl hot\nKd 1.5 0.2 0.2\nnewmtl shiny\nKd 0.7 0.7 0.7\nKs 0.6 0.6 0.6\n",
    );
    // Two faces each; in a.obj one of them has zero area, in b.obj both are fine.
    write(&d, "a.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nusemtl hot\nf 1 2 3\nf 1 2 4\n");
    write(&d, "b.obj", "mtllib m.mtl\nv 0 0 1\nv 1 0 1\nv 0 1 1\nusemtl shiny\nf 1 2 3\n");
    let toml = write(
        &d,
        "s.toml",
        "[[mesh]]\nfile = \"a.obj\"\n[[mesh]]\nfile = \"b.obj\"\n[[light]]\ntype = \"point\"\nposition = [0.2, 0.2, 2]\nintensity = [1, 1, 1]\n",
    );
    let w = load_scene(&toml).unwrap().scene.warnings;
    let skipped: Vec<_> = w.iter().filter(|w| w.contains("degenerate")).collect();
    assert_eq!(skipped.len(), 1, "{w:?}");
    assert!(skipped[0].contains("a.obj") && skipped[0].contains(": 1 degenerate"), "{w:?}");
    assert!(w.iter().any(|w| w.contains("m.mtl:3: material `hot`: Kd > 1")), "{w:?}");
    assert!(w.iter().any(|w| w.contains("m.mtl:5: material `shiny`: Kd + Ks")), "{w:?}");
}

/// Texture options not simulated (`map_d`'s, a bump map's other than `-bm`) are read and said to
/// be ignored, once per material; `map_d` and `d` make a cut-out, a `bump` map is read with its
/// `-bm`, and one with a `-bm` that is no number is an error; `Ns -5`, `illum 99` and a file
/// that is not UTF-8 are errors with their line.
#[test]
fn what_is_not_simulated_is_said() {
    let d = scratch_dir("said");
    let mut png_bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut png_bytes, 1, 1);
        enc.set_color(png::ColorType::Grayscale);
        enc.write_header().unwrap().write_image_data(&[128]).unwrap();
    }
    write(&d, "wood-bump.png", &png_bytes);
    write(&d, "alpha.png", png_bytes);
    write(
        &d,
        "m.mtl",
        format!("{MTL}map_d -s 2 2 2 alpha.png\nbump -bm 0.3 -clamp on wood-bump.png\nd 0.4\nsharpness 60\n"),
    );
    let scene = load_scene(&write(&d, "a.obj", OBJ)).unwrap().scene;
    let w: Vec<_> = scene.warnings.iter().filter(|w| w.contains("not simulated")).collect();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("m.mtl:4: material `white`") && w[0].contains("`map_d options`, `bump options`, `sharpness`"),
        "{w:?}"
    );
    let cut = scene.materials.iter().find_map(|m| m.opacity.as_ref()).expect("the cut-out");
    assert!(cut.factor == 0.4 && cut.texture.is_some(), "{cut:?}");
    let bump = scene.materials.iter().find_map(|m| m.normal_map.as_ref()).expect("the bump map");
    assert!(bump.scale == 0.3 && bump.relief == photonwave::material::Relief::Heights, "{bump:?}");
    write(&d, "m.mtl", format!("{MTL}bump -bm x wood-bump.png\n"));
    let e = load_scene(&d.join("a.obj")).err().unwrap().to_string();
    assert!(e.contains("m.mtl:6:") && e.contains("-bm"), "{e}");
    for (bad, what) in [("Ns -5", "negative"), ("illum 99", "0–10")] {
        write(&d, "m.mtl", format!("{MTL}{bad}\n"));
        let e = load_scene(&d.join("a.obj")).err().unwrap().to_string();
        assert!(e.contains("m.mtl:6:") && e.contains(what), "{e}");
    }
    write(&d, "m.mtl", [MTL.as_bytes(), b"Kd \xFF\n"].concat());
    let e = load_scene(&d.join("a.obj")).err().unwrap().to_string();
    assert!(e.contains("m.mtl:6:") && e.contains("UTF-8"), "{e}");
}

/// Each misleading message now says what is wrong: coordinates beyond the supported range (they
/// were reported as a camera fault or a zero-area emitter), a directional light with nothing to
/// light (reported as an overflowing power), and an over-long budget (an "unknown unit `e9s`").
#[test]
fn messages_say_what_is_actually_wrong() {
    let d = scratch_dir("messages");
    write(&d, "m.mtl", MTL);
    let far = write(&d, "far.obj", OBJ.replace("v 1 0 0", "v 3e38 0 0").replace("v 0 1 0", "v 0 -3e38 0"));
    let e = load_scene(&far).err().unwrap().to_string();
    assert!(e.contains("far.obj:3:") && e.contains("outside ±1e10"), "{e}");
    let big = write(&d, "big.obj", OBJ.replace("v 1 0 0", "v 3e19 0 0"));
    let e = load_scene(&big).err().unwrap().to_string();
    assert!(e.contains("big.obj:3:") && e.contains("[30000000000000000000, 0, 0]"), "{e}");
    write(&d, "a.obj", OBJ);
    let scaled = write(&d, "scaled.toml", "[[mesh]]\nfile = \"a.obj\"\nscale = 1e30\n");
    let e = load_scene(&scaled).err().unwrap().to_string();
    assert!(e.contains("a.obj:3:") && e.contains("after the mesh's transform"), "{e}");
    let sun =
        write(&d, "sun.toml", "[[light]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = [1, 1, 1]\n");
    let e = load_scene(&sun).err().unwrap().to_string();
    assert!(e.contains("a directional light needs geometry to light"), "{e}");
    // Triangles a billion units across keep their area (the f32 cross product's squared
    // length overflowed, and they were dropped as degenerate).
    let huge = write(&d, "huge.obj", OBJ.replace("v 1 0 0", "v 5e9 0 0").replace("v 0 1 0", "v 0 5e9 0"));
    let scene = load_scene(&huge).unwrap().scene;
    assert_eq!(scene.triangle_count(), 2);
    assert!((scene.area.iter().sum::<f32>() / 1.25e19 - 1.0).abs() < 1e-5, "{:?}", scene.area);
    let scene = bundled("cornell-box.toml");
    let (code, e) = cli(&["render", s(&scene), "--time", "1e9s"]);
    assert!(code != 0 && e.contains("at most 10 000 000 s") && !e.contains("unknown unit"), "{e}");
    let (code, e) = cli(&["render", s(&scene), "--time", "10 fortnights"]);
    assert!(code != 0 && e.contains("unknown unit `fortnights`"), "{e}");
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// `-q` prints nothing but errors, the per-system table needs `-v`, and the path engine's output
/// has no empty fields and no photon-mapping plan.
#[test]
fn the_cli_prints_what_is_asked() {
    let d = scratch_dir("verbosity");
    let (scene, out, stats) = (bundled("cornell-box.toml"), d.join("o.exr"), d.join("s.json"));
    let base = ["render", s(&scene), "-o", s(&out), "--stats", s(&stats)];
    let run = |extra: &[&str]| cli(&[&base[..], &SMALL[..], extra].concat());
    let (code, e) = run(&["-q"]);
    assert!(code == 0 && e.is_empty(), "-q printed: {e}");
    let (_, e) = run(&[]);
    assert!(e.contains("summary") && !e.contains("stages (runs"), "{e}");
    let (_, e) = run(&["-v"]);
    assert!(e.contains("stages (runs") && e.contains("gather_global"), "{e}");
    let (code, e) = run(&["--engine", "path"]);
    assert_eq!(code, 0, "{e}");
    assert!(e.contains("plan: path tracing") && !e.contains("global map    on"), "{e}");
    assert!(e.contains("(path engine, simd code path") && !e.contains("not built — \n"), "{e}");
    let v = json(&stats);
    assert_eq!(v["code_path"], "simd");
    assert!(v.get("effects").is_none(), "{v}");
    assert!(v["global_map"]["reason"].as_str().unwrap().contains("path tracer"));
}

/// `--photons N` stores exactly N photons, on both engines alike (20 000 stored 29 999 and 1
/// stored about 26 600: whole batches of paths) — in the global map, N where the camera reads it
/// (the photon guide's count); progressive stats total the passes.
#[test]
fn a_map_holds_the_photons_asked_for() {
    let d = scratch_dir("exact-photons");
    let (scene, out, stats) = (bundled("cornell-spheres.toml"), d.join("o.exr"), d.join("s.json"));
    for n in ["1", "20000"] {
        let mut emitted = Vec::new();
        for engine in ["wavefront", "reference"] {
            let args =
                ["render", s(&scene), "-q", "-o", s(&out), "--stats", s(&stats), "--width", "4", "--height", "4"];
            let (code, e) =
                cli(&[&args[..], &["--spp", "1", "--engine", engine, "--photons", n, "--caustic-photons", n]].concat());
            assert_eq!(code, 0, "{e}");
            let v = json(&stats);
            for (map, count) in [("global_map", "read"), ("caustic_map", "stored")] {
                assert_eq!(v[map][count].to_string(), n, "{engine} {map}: {}", v[map]);
            }
            emitted.push((v["global_map"]["emitted"].clone(), v["caustic_map"]["emitted"].clone()));
        }
        assert_eq!(emitted[0], emitted[1], "the engines cut at the same path");
    }
    let args = ["render", s(&scene), "-q", "-o", s(&out), "--stats", s(&stats), "--width", "4", "--height", "4"];
    let (code, e) = cli(&[&args[..], &["--passes", "3", "--photons", "3000", "--caustic-photons", "2000"]].concat());
    assert_eq!(code, 0, "{e}");
    let v = json(&stats);
    assert_eq!(v["progressive"]["passes"], 3);
    assert_eq!(v["global_map"]["read"], 9000, "totals over the passes");
    assert_eq!(v["caustic_map"]["stored"], 6000);
    assert!(v["phases"].as_array().unwrap().iter().any(|p| p == "3 progressive passes"), "{}", v["phases"]);
}

/// A bare mesh with no light is lit from the command line, and its fitted camera frames it at
/// any aspect ratio.
#[test]
fn bare_meshes_can_be_lit_and_framed() {
    let d = scratch_dir("bare");
    write(&d, "m.mtl", "newmtl white\nKd 0.8 0.8 0.8\n");
    let obj = write(&d, "a.obj", "mtllib m.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nusemtl white\nf 1 2 3 4\n");
    let (out, stats) = (d.join("o.exr"), d.join("s.json"));
    let base = ["render", s(&obj), "-o", s(&out), "--stats", s(&stats), "--spp", "1", "--photons", "500"];
    let (code, e) = cli(&[&base[..], &["--width", "4", "--height", "4"]].concat());
    assert!(code != 0 && e.contains("--light headlight"), "{e}");
    for light in ["headlight", "sun"] {
        let (code, e) = cli(&[&base[..], &["--width", "4", "--height", "8", "--light", light]].concat());
        assert_eq!(code, 0, "{e}");
        let mean = json(&stats)["mean_rgb"][0].as_f64().unwrap();
        assert!(mean > 0.05, "{light}: mean {mean}");
    }
    // A quarter as wide as high: the bounding sphere fits the horizontal field of view.
    let c = photonwave::scene::camera::fitted_camera_to((glam::Vec3::splat(-1.0), glam::Vec3::ONE), 40.0, 0.25);
    let half_h = ((20f32).to_radians().tan() * 0.25).atan();
    let r = 3f32.sqrt();
    assert!(r / (c.eye - c.target).length() <= half_h.sin() + 1e-6, "{c:?}");
}

/// More threads than cores is warned of; `compare` prints an exact zero as 0.
#[test]
fn small_things_a_user_noticed() {
    let d = scratch_dir("small");
    let (scene, out) = (bundled("cornell-box.toml"), d.join("o.exr"));
    let (code, e) = cli(&[&["render", s(&scene), "-o", s(&out), "--threads", "64"][..], &SMALL[..]].concat());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    assert_eq!(code, 0, "{e}");
    assert_eq!(e.contains("warning: 64 threads on"), 64 > 2 * cores, "{e}");
    let o = Command::new(env!("CARGO_BIN_EXE_photonwave")).args(["compare", s(&out), s(&out)]).output().unwrap();
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success() && table.contains(" 0 ") && !table.contains("0.0000e0"), "{table}");
}
