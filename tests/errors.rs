//! Bad input gets a clear error naming the file and line or the field — never a panic.

mod common;

use common::*;
use photonwave::formats::load_scene;
use std::path::Path;
use std::process::Command;

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const MTL: &str = "newmtl light\nKd 0.5 0.5 0.5\nKe 1 1 1\nnewmtl white\nKd 0.5 0.5 0.5\n";
const OBJ: &str = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nusemtl light\nf 1 3 2\nusemtl white\nf 1 2 4\n";

fn err(path: &Path) -> String {
    match load_scene(path) {
        Ok(_) => panic!("{} loaded, expected an error", path.display()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn good_input_loads() {
    let d = scratch_dir("good");
    write(&d, "m.mtl", MTL);
    let obj = write(&d, "a.obj", OBJ);
    let s = load_scene(&obj).unwrap().scene;
    assert_eq!(s.triangle_count(), 2);
}

#[test]
fn missing_files_are_named() {
    let d = scratch_dir("missing");
    assert!(err(&d.join("nope.toml")).contains("nope.toml"));
    let obj = write(&d, "a.obj", OBJ); // m.mtl not written
    let e = err(&obj);
    assert!(e.contains("m.mtl") && e.contains("cannot read"), "{e}");
    let toml = write(&d, "s.toml", "[[mesh]]\nfile = \"absent.obj\"\n");
    assert!(err(&toml).contains("absent.obj"));
}

#[test]
fn malformed_obj_names_the_line() {
    let d = scratch_dir("obj");
    write(&d, "m.mtl", MTL);
    let e = err(&write(&d, "a.obj", "v 0 0 0\nv 1 0 0\nf 1 2 7\n"));
    assert!(e.contains("a.obj:3:") && e.contains("vertex 7"), "{e}");
    let e = err(&write(&d, "b.obj", "v 0 0 0\nv 1 0 zero\n"));
    assert!(e.contains("b.obj:2:"), "{e}");
    let e = err(&write(&d, "c.obj", "v 0 0 0\nfoo bar\n"));
    assert!(e.contains("c.obj:2:") && e.contains("foo"), "{e}");
    let e = err(&write(&d, "d.obj", "v 0 0 0\n"));
    assert!(e.contains("no faces"), "{e}");
}

#[test]
fn non_finite_vertices_are_refused() {
    let d = scratch_dir("nan");
    write(&d, "m.mtl", MTL);
    for (i, bad) in ["nan", "inf", "-inf", "NaN"].iter().enumerate() {
        let e =
            err(&write(&d, &format!("n{i}.obj"), &format!("mtllib m.mtl\nv 0 0 0\nv 1 {bad} 0\nv 0 1 0\nf 1 2 3\n")));
        assert!(e.contains(":3:") && e.contains("not finite"), "{e}");
    }
}

#[test]
fn malformed_mtl_names_the_line() {
    let d = scratch_dir("mtl");
    write(&d, "m.mtl", "newmtl light\nKd 0.5 0.5\n");
    let e = err(&write(&d, "a.obj", OBJ));
    assert!(e.contains("m.mtl:2:") && e.contains("Kd"), "{e}");
    write(&d, "m.mtl", "newmtl light\nKe 1 -1 1\n");
    assert!(err(&d.join("a.obj")).contains("m.mtl:2:"));
    write(&d, "m.mtl", "Kd 1 1 1\n");
    assert!(err(&d.join("a.obj")).contains("before any `newmtl`"));
}

/// A `[camera]` without `fov` takes the default users expect (40°, as for a scene without a
/// camera) instead of an error (issue 53); `up` defaults to +y.
#[test]
fn a_camera_without_fov_takes_the_default() {
    let d = scratch_dir("fov");
    write(&d, "m.mtl", MTL);
    write(&d, "a.obj", OBJ);
    let s = write(&d, "s.toml", "[[mesh]]\nfile = \"a.obj\"\n[camera]\neye = [0, 0, 3]\ntarget = [0, 0, 0]\n");
    let camera = load_scene(&s).unwrap().camera.unwrap();
    assert_eq!(camera.fov_deg, photonwave::scene::camera::DEFAULT_FOV);
    assert_eq!(camera.fov_deg, 40.0);
    assert_eq!(camera.up, glam::Vec3::Y);
    let s =
        write(&d, "t.toml", "[[mesh]]\nfile = \"a.obj\"\n[camera]\neye = [0, 0, 3]\ntarget = [0, 0, 0]\nfov = 25\n");
    assert_eq!(load_scene(&s).unwrap().camera.unwrap().fov_deg, 25.0);
}

#[test]
fn malformed_scene_files_name_the_line_or_field() {
    let d = scratch_dir("toml");
    write(&d, "m.mtl", MTL);
    write(&d, "a.obj", OBJ);
    let e = err(&write(&d, "s1.toml", "[[mesh]]\nfile = \"a.obj\"\n[camera\n"));
    assert!(e.contains("s1.toml:3:"), "{e}");
    let e = err(&write(&d, "s2.toml", "[[mesh]]\nfile = \"a.obj\"\n\n[render]\nspp = 4\nspeed = 9\n"));
    assert!(e.contains("s2.toml:") && e.contains("speed"), "{e}");
    let e = err(&write(&d, "s3.toml", "[[mesh]]\nfile = \"a.obj\"\n[render]\nwidth = 0\n"));
    assert!(e.contains("`width`"), "{e}");
    let e = err(&write(&d, "s4.toml", "[[mesh]]\nfile = \"a.obj\"\n[materials.white]\ntype = \"glass\"\nior = -1\n"));
    assert!(e.contains("materials.white.ior"), "{e}");
    let toml = "[[mesh]]\nfile = \"a.obj\"\n[materials.white]\ntype = \"glass\"\nior = 1.33\noutside_ior = 0\n";
    let e = err(&write(&d, "s4b.toml", toml));
    assert!(e.contains("materials.white.outside_ior"), "{e}");
    let e = err(&write(&d, "s5.toml", "[[mesh]]\nfile = \"a.obj\"\n[materials.nosuch]\ntype = \"mirror\"\n"));
    assert!(e.contains("materials.nosuch"), "{e}");
    let e = err(&write(&d, "s6.toml", "[[mesh]]\nfile = \"a.obj\"\n[[light]]\ntype = \"spot\"\nposition = [0,0,0]\ntarget = [0,0,0]\nintensity = [1,1,1]\nangle = 30\n"));
    assert!(e.contains("light[0].target"), "{e}");
    let e = err(&write(
        &d,
        "s7.toml",
        "[[mesh]]\nfile = \"a.obj\"\n[materials.white]\ntype = \"lambert\"\nkd = [1.5, 0, 0]\n",
    ));
    assert!(e.contains("materials.white.kd"), "{e}");
}

#[test]
fn scenes_without_usable_light_are_refused() {
    let d = scratch_dir("light");
    write(&d, "dark.mtl", "newmtl white\nKd 0.5 0.5 0.5\n");
    let e = err(&write(&d, "dark.obj", "mtllib dark.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl white\nf 1 2 3\n"));
    assert!(e.contains("no light"), "{e}");
    // An emitter whose only triangle has zero area.
    write(&d, "m.mtl", MTL);
    let e = err(&write(
        &d,
        "zero.obj",
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nusemtl light\nf 1 2 3\nusemtl white\nf 1 2 4\n",
    ));
    assert!(e.contains("`light`") && e.contains("zero area"), "{e}");
}

fn cli(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_photonwave")).args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    (out.status.code().unwrap_or(-1), stderr)
}

#[test]
fn the_cli_reports_errors_with_a_nonzero_exit() {
    let d = scratch_dir("cli");
    let scene = bundled("cornell-box.toml");
    let scene = scene.to_str().unwrap();
    let out = d.join("x.exr");
    let out = out.to_str().unwrap();
    let (code, e) = cli(&["render", "/no/such/scene.toml", "-o", out]);
    assert!(code != 0 && e.contains("/no/such/scene.toml"), "{e}");
    let (code, e) = cli(&["render", scene, "--width", "0", "-o", out]);
    assert!(code != 0 && e.contains("`width`"), "{e}");
    let (code, e) = cli(&["render", scene, "--photons", "0", "-o", out]);
    assert!(code != 0 && e.contains("`photons`"), "{e}");
    let (code, e) = cli(&["render", scene, "--spp=-3", "-o", out]);
    assert!(code != 0 && e.contains("spp"), "{e}");
    let (code, e) = cli(&["render", scene, "--eye", "0,0.273,0", "--target", "0,0.273,0", "-o", out]);
    assert!(code != 0 && e.contains("camera.target"), "{e}");
    let (code, e) = cli(&["render", scene, "--k", "1", "-o", out]);
    assert!(code != 0 && e.contains("`k`"), "{e}");
    for bad in ["NaN", "-1", "1000"] {
        let flag = format!("--secondary-gather={bad}");
        let (code, e) = cli(&["render", scene, &flag, "-o", out]);
        assert!(code != 0 && e.contains("`secondary_gather`"), "{bad}: {e}");
    }
    let (code, e) = cli(&["render", scene, "-o", "x.png"]);
    assert!(code != 0 && e.contains("--output") && e.contains("x.png") && e.contains("--png"), "{e}");
    let (code, e) = cli(&["render", scene, "-o", out, "--png", "x.exr"]);
    assert!(code != 0 && e.contains("--png") && e.contains("x.exr"), "{e}");
    let (code, e) = cli(&["render", scene, "--width", "4", "--height", "4", "--spp", "1", "-o", "/no/such/dir/x.exr"]);
    assert!(code != 0 && e.contains("/no/such/dir/x.exr"), "{e}");
}

/// A scene far from the origin is rendered in its own frame (issue 53): the CLI says so, and
/// its `--eye` and `--target`, given in the file's coordinates, move with the scene — the same
/// camera given on the command line renders the file's camera's image, byte for byte.
#[test]
fn the_cli_places_a_far_scene_and_its_camera_in_its_frame() {
    let d = scratch_dir("cli-far");
    let obj = bundled("cornell-box.obj");
    let toml = format!(
        "[[mesh]]\nfile = {obj:?}\ntranslate = [30000, -20000, 10000]\n[camera]\neye = [30000, -19999.727, 10001.08]\n\
         target = [30000, -19999.727, 10000]\nfov = 39.3\n"
    );
    let scene = d.join("far.toml");
    std::fs::write(&scene, toml).unwrap();
    let render = |png: &str, extra: &[&str]| {
        let out = d.join(png);
        let mut args = vec!["render", scene.to_str().unwrap(), "-o"];
        let exr = d.join(format!("{png}.exr"));
        args.extend([exr.to_str().unwrap(), "--png", out.to_str().unwrap(), "--width", "16", "--height", "16"]);
        args.extend(["--spp", "1", "--photons", "2000", "--caustic-photons", "1000", "--threads", "1"]);
        args.extend(extra);
        let (code, e) = cli(&args);
        assert_eq!(code, 0, "{e}");
        (std::fs::read(out).unwrap(), e)
    };
    let (file_camera, said) = render("a.png", &[]);
    assert!(said.contains("frame: the scene lies") && said.contains("moved to its centre"), "{said}");
    let mut reader = png::Decoder::new(std::io::Cursor::new(&file_camera)).read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut pixels).unwrap();
    assert!(pixels.iter().filter(|&&b| b > 8).count() > pixels.len() / 4, "a dark image: the camera looks away");
    let (flags, _) = render("b.png", &["--eye", "30000,-19999.727,10001.08", "--target", "30000,-19999.727,10000"]);
    assert!(file_camera == flags, "the command line's camera renders another image");
    let (aside, _) = render("c.png", &["--eye", "30000.1,-19999.727,10001.08"]);
    assert!(file_camera != aside, "--eye was not read");
}

#[test]
fn the_cli_renders_and_writes_stats() {
    let d = scratch_dir("cli-ok");
    let scene = bundled("cornell-spheres.toml");
    let (exr, png, json) = (d.join("o.exr"), d.join("o.png"), d.join("s.json"));
    let (code, e) = cli(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        exr.to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
        "--stats",
        json.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "1",
        "--photons",
        "2000",
        "--caustic-photons",
        "2000",
        "--visibility",
    ]);
    assert_eq!(code, 0, "{e}");
    assert!(e.contains("caustic map   on") && e.contains("summary"), "{e}");
    let stats: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(stats["caustic_map"]["built"], true);
    assert!(stats["global_map"]["stored"].as_u64().unwrap() >= 2000);
    assert!(stats["rays"]["camera"].as_u64().unwrap() >= 256);
    assert!(std::fs::metadata(&png).unwrap().len() > 0);
}

#[test]
fn the_bench_command_checks_its_input_and_prints_one_json_object() {
    let (code, e) = cli(&["bench", "/no/such/scene.toml"]);
    assert!(code != 0 && e.contains("/no/such/scene.toml"), "{e}");
    let (code, e) = cli(&["bench", "--reps", "0"]);
    assert!(code != 0 && e.contains("--reps"), "{e}");
    let (code, e) = cli(&["bench", "--rings", "1"]);
    assert!(code != 0 && e.contains("--rings"), "{e}");
    // A small generated sphere, one repetition: the report's shape, not its speed.
    let v = bench_json(&["bench", "generated:sphere", "--rings", "8", "--reps", "1", "--json"]);
    assert!(v["target_cpu"].is_string() && v["threads"] == 1, "{v}");
    // Embree, when built in, is limited to the widest instruction set this build targets.
    #[cfg(feature = "embree")]
    {
        assert_eq!(v["embree_isa"], photonwave::bench::embree::isa(), "{v}");
        // The configured build (x86-64-v3, `.cargo/config.toml`) targets AVX2.
        if cfg!(target_feature = "avx2") {
            assert_eq!(v["embree_isa"], "avx2", "{v}");
        }
    }
    #[cfg(not(feature = "embree"))]
    assert!(v["embree_isa"].is_null(), "{v}");
    let traversal = v["traversal"].as_array().unwrap();
    assert_eq!(traversal.len(), 6, "three ray sets × closest/any");
    for row in traversal {
        assert!(row["count"].as_u64().unwrap() > 0 && row["ratio"].as_f64().unwrap() > 0.0, "{row}");
    }
    let density = v["density"].as_array().unwrap();
    assert_eq!(density.len(), 2, "knn and radius");
    for row in density {
        assert!(row["photons"].as_u64().unwrap() > 0 && row["ratio"].as_f64().unwrap() > 0.0, "{row}");
    }
}

/// Runs `photonwave ARGS` (a bench with `--json`), asserts success and returns its one JSON object.
fn bench_json(args: &[&str]) -> serde_json::Value {
    let out = Command::new(env!("CARGO_BIN_EXE_photonwave")).args(args).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).expect("one JSON object on stdout")
}

/// `bench --light` lights a bare mesh (which would not load without a light) and sends every
/// shadow ray to the point; `--only` measures one half; the Embree columns are filled exactly
/// when the `embree` feature is on.
#[test]
fn bench_lights_a_bare_mesh_and_measures_one_half() {
    let (code, e) = cli(&["bench", "--only", "photons"]);
    assert!(code != 0 && e.contains("--only"), "{e}");
    let d = scratch_dir("bench-light");
    let obj = d.join("quad.obj");
    std::fs::write(&obj, "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\n").unwrap();
    let (code, e) = cli(&["bench", obj.to_str().unwrap(), "--reps", "1"]);
    assert!(code != 0 && e.contains("no light"), "{e}");
    let v = bench_json(&[
        "bench",
        obj.to_str().unwrap(),
        "--light",
        "0,0,3",
        "--only",
        "traversal",
        "--reps",
        "1",
        "--json",
    ]);
    assert!(v["density"].as_array().unwrap().is_empty(), "{v}");
    let traversal = v["traversal"].as_array().unwrap();
    assert_eq!(traversal.len(), 6, "three ray sets × closest/any: {v}");
    let shadow: Vec<_> = traversal.iter().filter(|r| r["rays"] == "shadow").collect();
    assert_eq!(shadow.len(), 2, "{v}");
    for row in &shadow {
        assert!(row["count"].as_u64().unwrap() > 0, "{row}");
    }
    for row in traversal {
        for field in ["embree1_mrays", "embree_robust1_mrays", "renderer_vs_embree_robust", "embree_extra_hits_by_call"]
        {
            assert_eq!(row[field].is_null(), !cfg!(feature = "embree"), "{field}: {row}");
        }
        if cfg!(feature = "embree") {
            // Four calls, the first of them the one `embree_extra_hits` reports.
            let by_call = row["embree_extra_hits_by_call"].as_array().unwrap();
            assert_eq!(by_call.len(), 4, "{row}");
            assert_eq!(by_call[0], row["embree_extra_hits"], "{row}");
        }
    }
    // The other half alone.
    let v =
        bench_json(&["bench", obj.to_str().unwrap(), "--light", "0,0,3", "--only", "density", "--reps", "1", "--json"]);
    assert!(v["traversal"].as_array().unwrap().is_empty(), "{v}");
    assert_eq!(v["density"].as_array().unwrap().len(), 2, "knn and radius: {v}");
}

/// With a light point given, every shadow ray of the bench's sets ends at that point (origin +
/// direction is the point, t_max just short of it), whatever lights the scene has.
#[test]
fn bench_shadow_rays_go_to_the_light_point() {
    let loaded = load("cornell-box.toml");
    let side = photonwave::bench::SIDE;
    let cam = loaded.camera.unwrap().prepare(side, side).unwrap();
    let light = glam::Vec3::new(0.1, 0.5, 0.2);
    let sets = photonwave::bench::RaySets::with_light(&loaded.scene, &cam, Some(light));
    assert!(sets.shadow.len() > 1000, "{}", sets.shadow.len());
    for r in &sets.shadow {
        let end = r.origin + r.direction;
        assert!((end - light).length() <= 1e-6, "{r:?} ends at {end}");
        assert!(r.t_max < 1.0, "{r:?}");
    }
}

/// A map that the photon-path cap leaves short of its count is reported: here no photon can
/// reach the only diffuse surface (scenes/hard/tir-slab.toml), so both maps stay empty.
#[test]
fn the_cli_warns_when_a_map_falls_short() {
    let d = scratch_dir("cli-short");
    let scene = bundled("hard/tir-slab.toml");
    let out = d.join("o.exr");
    let args = ["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--spp", "1", "--width", "8"];
    let (code, e) = cli(&[&args[..], &["--height", "8", "--photons", "50", "--caustic-photons", "50"]].concat());
    assert_eq!(code, 0, "{e}");
    assert!(e.contains("warning: global map: 0 of 50 photons stored") && e.contains("it is empty"), "{e}");
    assert!(e.contains("warning: caustic map: 0 of 50 photons stored"), "{e}");
}

/// An emission whose power overflows f32 is refused, naming the material (an infinite `Ke` is
/// already refused by the MTL check, naming its line), and so is a light whose intensity does.
#[test]
fn overflowing_light_power_is_refused() {
    let d = scratch_dir("overflow");
    write(&d, "m.mtl", &MTL.replace("Ke 1 1 1", "Ke 3e38 3e38 3e38"));
    let obj = write(&d, "a.obj", OBJ);
    let e = err(&obj);
    assert!(e.contains("`light`") && e.contains("overflows"), "{e}");
    write(&d, "m.mtl", &MTL.replace("Ke 1 1 1", "Ke inf 1 1"));
    let e = err(&obj);
    assert!(e.contains("m.mtl:3") && e.contains("not finite"), "{e}");
    write(&d, "m.mtl", MTL);
    let toml = "[[mesh]]\nfile = \"a.obj\"\n[[light]]\ntype = \"point\"\nposition = [0.2, 0.2, 0.2]\nintensity = [3e38, 3e38, 3e38]\n";
    let e = err(&write(&d, "s.toml", toml));
    assert!(e.contains("light[0]") && e.contains("overflows"), "{e}");
}
