//! `sweep`: knobs parse as their fields' types, the grid is every combination, each row is
//! exactly what `render` + `compare` give for its settings, the CSV and plots are written, and
//! bad input is named.

mod common;

use common::{bundled, load, scratch_dir};
use photonwave::engine::{self, Engine};
use photonwave::film::Film;
use photonwave::progress::NoProgress;
use photonwave::progressive::PerPass;
use photonwave::settings::{Kernel, Settings};
use photonwave::tools::compare::layer_errors;
use photonwave::tools::sweep::{grid, set_knob, Knob, Metric, Sweep};
use std::process::Command;
use std::sync::Arc;
use std::time::Duration;

/// Tiny renders of the glass-sphere box.
fn tiny() -> Settings {
    Settings {
        width: 12,
        height: 12,
        spp: 1,
        photons: 2000,
        caustic_photons: 2000,
        gather_rays: 2,
        threads: 1,
        ..Default::default()
    }
}

fn knob(s: &str) -> Knob {
    s.parse().unwrap()
}

/// A reference for [`tiny`]: four progressive passes with another seed.
fn reference_film() -> Film {
    let loaded = load("cornell-spheres.toml");
    let s = tiny();
    let rays = loaded.camera.unwrap().prepare(s.width, s.height).unwrap();
    let settings = Settings { passes: 4, seed: 99, ..s };
    engine::render(&Arc::new(loaded.scene), &rays, &settings, Engine::Wavefront, None, &NoProgress).unwrap().0
}

#[test]
fn knobs_take_their_fields_types_and_bad_ones_are_named() {
    let base = tiny();
    assert_eq!(set_knob(&base, "k", "16").unwrap().k, 16);
    assert_eq!(set_knob(&base, "global_radius", "0.02").unwrap().global_radius, 0.02);
    assert_eq!(set_knob(&base, "kernel", "box").unwrap().kernel, Kernel::Box);
    assert!(!set_knob(&base, "final_gather", "false").unwrap().final_gather);
    assert_eq!(set_knob(&base, "alpha", "0.5").unwrap().alpha, 0.5);

    let err = |name: &str, value: &str| set_knob(&base, name, value).unwrap_err().to_string();
    let e = err("photon", "5");
    assert!(e.contains("`photon`") && e.contains("no such knob") && e.contains("photons"), "{e}");
    let e = err("k", "many");
    assert!(e.contains("`k`") && e.contains("`many`") && e.contains("whole number"), "{e}");
    let e = err("k", "1");
    assert!(e.contains("`k`") && e.contains("between 2"), "{e}");
    let e = err("kernel", "gaussian");
    assert!(e.contains("`kernel`") && e.contains("gaussian"), "{e}");
    let e = err("width", "64");
    assert!(e.contains("`width`") && e.contains("reference"), "{e}");
    let e = err("final_gather", "yes");
    assert!(e.contains("true or false"), "{e}");

    for bad in ["k", "k=", "=1,2", "k=1,,2"] {
        assert!(bad.parse::<Knob>().is_err(), "{bad}");
    }
    assert_eq!(knob(" k = 8, 16 "), Knob { name: "k".into(), values: vec!["8".into(), "16".into()] });
}

#[test]
fn the_grid_is_every_combination_first_knob_slowest() {
    let configs =
        grid(&tiny(), PerPass::default(), &[knob("k=8,16"), knob("kernel=box,cone,epanechnikov")], &[]).unwrap();
    let seen: Vec<(u32, Kernel)> = configs.iter().map(|c| (c.settings.k, c.settings.kernel)).collect();
    use Kernel::*;
    assert_eq!(seen, [(8, Box), (8, Cone), (8, Epanechnikov), (16, Box), (16, Cone), (16, Epanechnikov)]);
    assert_eq!(configs[4].values, ["16", "cone"]);

    // Progressive configurations spread the base's samples and photons over passes, as
    // `render --passes` does, unless a knob sets them (then they are per pass).
    let base = Settings { spp: 16, photons: 160_000, ..tiny() };
    let spread = grid(&base, PerPass::default(), &[knob("passes=1,8")], &[]).unwrap();
    assert_eq!((spread[0].settings.spp, spread[0].settings.photons), (16, 160_000));
    assert_eq!((spread[1].settings.spp, spread[1].settings.photons), (1, 10_000));
    // spp given per pass: photons are still spread over the spp (`per_pass`'s rule).
    let given = grid(&base, PerPass::default(), &[knob("passes=8"), knob("spp=2")], &[]).unwrap();
    assert_eq!((given[0].settings.spp, given[0].settings.photons), (2, 80_000));
    let given = grid(&base, PerPass::default(), &[knob("passes=8"), knob("photons=5000")], &[]).unwrap();
    assert_eq!((given[0].settings.spp, given[0].settings.photons), (1, 5000));
    // Amounts a preset gives per pass stay as they are.
    let all = PerPass { spp: true, photons: true, caustic_photons: true };
    let preset = grid(&base, all, &[knob("passes=8")], &[]).unwrap();
    assert_eq!((preset[0].settings.spp, preset[0].settings.photons), (16, 160_000));

    let e = grid(&tiny(), PerPass::default(), &[knob("k=8"), knob("k=16")], &[]).unwrap_err().to_string();
    assert!(e.contains("`k`") && e.contains("twice"), "{e}");
    let e =
        grid(&tiny(), PerPass::default(), &[knob("passes=1,2")], &[Duration::from_secs(1)]).unwrap_err().to_string();
    assert!(e.contains("`passes`") && e.contains("budget"), "{e}");
    let many: Vec<Knob> = ["k", "caustic_k", "gather_rays"]
        .iter()
        .map(|n| knob(&format!("{n}={}", (2..30).map(|v| v.to_string()).collect::<Vec<_>>().join(","))))
        .collect();
    let e = grid(&tiny(), PerPass::default(), &many, &[]).unwrap_err().to_string();
    assert!(e.contains("more than"), "{e}");
}

/// Every row's errors equal those of a separate render with the row's settings measured against
/// the same reference (renders are deterministic), and each knob with two values gets a figure.
#[test]
fn rows_are_what_render_and_compare_give() {
    let loaded = load("cornell-spheres.toml");
    let scene = Arc::new(loaded.scene);
    let rays = loaded.camera.unwrap().prepare(12, 12).unwrap();
    let reference_film = reference_film();
    let reference = photonwave::film::ExrLayers { width: 12, height: 12, layers: reference_film.layers() };
    let sweep = Sweep::new(
        &tiny(),
        PerPass::default(),
        vec![knob("gather_rays=1,4"), knob("passes=1,3")],
        Vec::new(),
        Engine::Wavefront,
    )
    .unwrap();
    let rows = sweep.run(&scene, &rays, &reference, &NoProgress).unwrap();
    assert_eq!(rows.len(), 4);
    for (row, config) in rows.iter().zip(&sweep.configs) {
        let (film, _) = engine::render(&scene, &rays, &config.settings, Engine::Wavefront, None, &NoProgress).unwrap();
        assert_eq!(row.errors, layer_errors(&film.layers(), &reference.layers), "{:?}", row.values);
        assert_eq!(row.errors[0].layer, "beauty");
        assert_eq!(row.errors.len(), 6);
        assert!(row.errors.iter().all(|e| e.rmse.is_finite() && e.rmse > 0.0 || e.layer == "emitted"));
        assert_eq!(row.passes, config.settings.passes);
        assert!(row.seconds > 0.0 && row.budget_s.is_none());
    }
    let figures = sweep.figures(&rows, "caustic", Metric::Rmse, "spheres");
    let names: Vec<&str> = figures.iter().map(|f| f.0.as_str()).collect();
    assert_eq!(names, ["gather_rays", "passes"]);
    // By gather rays: two lines (one per passes value), each through both gather-ray values.
    let by_rays = &figures[0].1;
    assert_eq!(by_rays.lines.len(), 2);
    assert!(by_rays.lines.iter().all(|l| l.points.len() == 2 && l.colour.is_none()));
    assert_eq!(by_rays.groups.iter().map(|g| g.points.len()).collect::<Vec<_>>(), [2, 2]);
    assert_eq!(by_rays.groups[1].label, "gather_rays = 4");
    let caustic = |r: &photonwave::tools::sweep::Row| r.errors.iter().find(|e| e.layer == "caustic").unwrap().rmse;
    assert_eq!(by_rays.groups[0].points[0], (rows[0].seconds, caustic(&rows[0])));

    let csv = photonwave::tools::sweep::csv(&sweep.knobs, &rows);
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 5);
    assert!(
        lines[0].starts_with("config,gather_rays,passes,budget_s,passes_rendered,spp_rendered,seconds,beauty_rmse,")
    );
    assert!(lines[0].ends_with(",indirect_rmse,indirect_relmse,indirect_mean_ratio"));
    let fields: Vec<&str> = lines[4].split(',').collect();
    assert_eq!(&fields[..6], ["3", "4", "3", "", "3", "3"]);
    assert_eq!(fields.len(), lines[0].split(',').count());
    let rmse: f64 = fields[7].parse().unwrap();
    assert!((rmse / rows[3].errors[0].rmse - 1.0).abs() < 1e-5);
}

/// Equal-time mode renders every configuration at every budget, progressively.
#[test]
fn equal_time_mode_renders_each_configuration_per_budget() {
    let loaded = load("cornell-spheres.toml");
    let scene = Arc::new(loaded.scene);
    let rays = loaded.camera.unwrap().prepare(12, 12).unwrap();
    let reference = photonwave::film::ExrLayers { width: 12, height: 12, layers: reference_film().layers() };
    let budgets = vec![Duration::from_millis(150), Duration::from_millis(450)];
    let sweep =
        Sweep::new(&tiny(), PerPass::default(), vec![knob("kernel=box,cone")], budgets, Engine::Wavefront).unwrap();
    let rows = sweep.run(&scene, &rays, &reference, &NoProgress).unwrap();
    let got: Vec<(usize, Option<f64>)> = rows.iter().map(|r| (r.config, r.budget_s)).collect();
    assert_eq!(got, [(0, Some(0.15)), (1, Some(0.15)), (0, Some(0.45)), (1, Some(0.45))]);
    // Passes of a few ms: the longer budget fits more of them.
    for c in 0..2 {
        assert!(rows[c + 2].passes > rows[c].passes, "{:?}", (rows[c].passes, rows[c + 2].passes));
    }
    let figures = sweep.figures(&rows, "beauty", Metric::Relmse, "spheres");
    assert_eq!(figures.len(), 1);
    // One coloured line per configuration, across the budgets.
    let lines: Vec<(Option<usize>, usize)> = figures[0].1.lines.iter().map(|l| (l.colour, l.points.len())).collect();
    assert_eq!(lines, [(Some(0), 2), (Some(1), 2)]);
    assert!(figures[0].1.y_label.contains("relMSE"));
}

fn run(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_photonwave")).args(args).output().unwrap()
}

#[test]
fn cli_writes_the_csv_and_a_plot_per_knob() {
    let d = scratch_dir("sweep-cli");
    let reference = d.join("ref.exr");
    reference_film().write_exr(&reference).unwrap();
    let out = d.join("out");
    let scene = bundled("cornell-spheres.toml");
    let o = run(&[
        "sweep",
        scene.to_str().unwrap(),
        "--reference",
        reference.to_str().unwrap(),
        "--knob",
        "k=8,16",
        "--knob",
        "spp=1",
        "--knob",
        "photons=2000",
        "--knob",
        "caustic_photons=2000",
        "--knob",
        "gather_rays=2",
        "-o",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("2 configuration(s) = 2 render(s) at 12×12"), "{err}");
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 3, "{csv}");
    assert!(lines[0].starts_with("config,k,spp,photons,caustic_photons,gather_rays,budget_s,"), "{}", lines[0]);
    assert!(lines[1].starts_with("0,8,1,2000,2000,2,,1,1,") && lines[2].starts_with("1,16,1,2000,2000,2,,1,1,"));
    // One plot per knob that varies, in both formats; none for the single-valued ones.
    let svg = std::fs::read_to_string(out.join("k.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("k = 16") && svg.contains("render time (s)"), "{svg}");
    let png = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(out.join("k.png")).unwrap()));
    let info = png.read_info().unwrap().info().clone();
    assert_eq!((info.width, info.height), photonwave::tools::plot::SIZE);
    assert!(!out.join("spp.svg").exists() && !out.join("photons.png").exists());
}

#[test]
fn cli_names_bad_input() {
    let d = scratch_dir("sweep-errors");
    let reference = d.join("ref.exr");
    reference_film().write_exr(&reference).unwrap();
    let scene = bundled("cornell-spheres.toml");
    let (scene, reference, out) = (scene.to_str().unwrap(), reference.to_str().unwrap(), d.join("o"));
    let out = out.to_str().unwrap();
    let fails = |extra: &[&str], expect: &[&str]| {
        let mut args = vec!["sweep", scene, "-o", out];
        args.extend_from_slice(extra);
        let o = run(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(!err.contains("panicked"), "{err}");
        for e in expect {
            assert!(err.contains(e), "{args:?}: `{e}` not in {err}");
        }
    };
    fails(&["--reference", "missing.exr", "--knob", "k=8"], &["missing.exr"]);
    fails(&["--reference", reference, "--knob", "kk=8"], &["`kk`", "no such knob"]);
    fails(&["--reference", reference, "--knob", "k=8,x"], &["`k`", "`x`"]);
    fails(&["--reference", reference, "--knob", "height=8"], &["`height`"]);
    fails(&["--reference", reference, "--knob", "passes=1,2", "--time", "1s"], &["`passes`", "budget"]);
    fails(&["--reference", reference, "--knob", "k=8", "--time", "1x"], &["1x"]);
    fails(&["--reference", reference, "--knob", "k=8", "--layer", "glossy"], &["glossy", "caustic"]);
    fails(&["--reference", reference], &["--knob"]);
    fails(&["--reference", reference, "--knob", "k=8", "--engine", "path", "--time", "1s"], &["--engine"]);
    fails(&["--reference", reference, "--knob", "passes=1,2", "--engine", "path"], &["--engine"]);
    assert!(!d.join("o").exists(), "nothing is written before the input is checked");
}
