//! Image textures end to end: a textured floor's direct light and caustic-map estimate follow
//! the texture exactly, both engines agree on a textured scene, images decode (PNG, JPEG), and
//! bad texture input is refused by name.

mod common;

use common::*;
use glam::Vec3;
use photonwave::film::Film;
use photonwave::formats::image::load_texture;
use photonwave::formats::{load_scene, LoadedScene};
use photonwave::progress::NoProgress;
use photonwave::settings::Settings;
use photonwave::texture::{srgb_to_linear, Encoding};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The floor texture: 64×64 texels in four 32×32 quadrants of these sRGB colours (top left, top
/// right, bottom left, bottom right as the image is stored).
const QUADRANTS: [[u8; 3]; 4] = [[255, 255, 255], [128, 64, 32], [10, 200, 90], [60, 120, 250]];
const N: u32 = 64;

fn quadrant(col: u32, row: u32) -> usize {
    usize::from(col >= N / 2) + 2 * usize::from(row >= N / 2)
}

fn write_png(path: &Path, w: u32, h: u32, rgb: &[u8]) {
    let mut out = Vec::new();
    let mut e = png::Encoder::new(&mut out, w, h);
    e.set_color(png::ColorType::Rgb);
    e.set_depth(png::BitDepth::Eight);
    e.write_header().unwrap().write_image_data(rgb).unwrap();
    std::fs::write(path, out).unwrap();
}

/// A floor [-1, 1]² at y = 0 (u = x, v = −z, both mapped to [0, 1]), a small area light at
/// y = 1 facing down, a mirror wall at x = 1.2 facing the light (caustics on the floor) and a
/// white wall at z = −1.2 (light between it and the floor), both outside the view, seen from straight above with a field of view that frames the floor exactly: pixel (i, j)
/// sees texel (i, j). The floor is white, or textured with `map`.
fn floor_scene(dir: &Path, name: &str, map: Option<&str>) -> PathBuf {
    let obj = "mtllib m.mtl\n\
        v -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\n\
        vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
        usemtl floor\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n\
        v -0.1 1 -0.1\nv 0.1 1 -0.1\nv 0.1 1 0.1\nv -0.1 1 0.1\n\
        usemtl light\nf 5 6 7\nf 5 7 8\n\
        v 1.2 0 -1\nv 1.2 0 1\nv 1.2 1 1\nv 1.2 1 -1\n\
        usemtl mirror\nf 9 10 11\nf 9 11 12\n\
        v -1 0 -1.2\nv 1 0 -1.2\nv 1 1 -1.2\nv -1 1 -1.2\n\
        usemtl wall\nf 13 14 15\nf 13 15 16\n";
    let map = map.map(|m| format!("map_Kd {m}\n")).unwrap_or_default();
    let mtl = format!(
        "newmtl floor\nKd 1 1 1\n{map}\nnewmtl light\nKd 0 0 0\nKe 10 10 10\nnewmtl mirror\nillum 3\nKs 1 1 1\nnewmtl wall\nKd 0.8 0.8 0.8\n"
    );
    std::fs::write(dir.join(format!("{name}.obj")), obj.replace("m.mtl", &format!("{name}.mtl"))).unwrap();
    std::fs::write(dir.join(format!("{name}.mtl")), mtl).unwrap();
    // Eye 2 above the floor: a vertical field of view of 2·atan(1/2) frames [-1, 1].
    let fov = 2.0 * 0.5f64.atan().to_degrees();
    let toml = format!(
        "[[mesh]]\nfile = \"{name}.obj\"\n[camera]\neye = [0, 2, 0]\ntarget = [0, 0, 0]\nup = [0, 0, -1]\nfov = {fov}\n"
    );
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, toml).unwrap();
    path
}

fn checker(dir: &Path) -> &'static str {
    let mut rgb = Vec::new();
    for row in 0..N {
        for col in 0..N {
            rgb.extend(QUADRANTS[quadrant(col, row)]);
        }
    }
    write_png(&dir.join("checker.png"), N, N, &rgb);
    "checker.png"
}

fn settings() -> Settings {
    Settings {
        width: N,
        height: N,
        spp: 1,
        photons: 20_000,
        caustic_photons: 20_000,
        gather_rays: 4,
        ..Default::default()
    }
}

fn reference(loaded: &LoadedScene, s: &Settings) -> Film {
    render(loaded, s)
}

#[test]
fn direct_light_and_caustic_estimate_follow_the_texture() {
    let dir = scratch_dir("textured-floor");
    let textured = load_scene(&floor_scene(&dir, "textured", Some(checker(&dir)))).unwrap();
    let white = load_scene(&floor_scene(&dir, "white", None)).unwrap();
    let s = settings();
    let (a, b) = (reference(&textured, &s), reference(&white, &s));
    // Same seed, same streams: the white floor (kd = 1) and the textured one see the same light
    // samples and the same caustic photons (stored at their first diffuse hit, never scattered
    // on), so per pixel each term differs by the factor kd(uv) alone — up to f32 rounding. One
    // sample per pixel; pixel (i, j) covers texels [i, i+1] × [j, j+1], and bilinear lookup is
    // constant at least half a texel inside a quadrant, so pixels 2 or more from a quadrant edge
    // read the quadrant's colour exactly.
    let (mut direct_checked, mut caustic_checked) = (0, 0);
    for j in 0..N {
        for i in 0..N {
            let inside = |k: u32| (2..N / 2 - 2).contains(&(k % (N / 2)));
            if !(inside(i) && inside(j)) {
                continue;
            }
            let kd = Vec3::from_array(QUADRANTS[quadrant(i, j)].map(|c| srgb_to_linear(f32::from(c) / 255.0)));
            let (pa, pb) = (a.pixels[(j * N + i) as usize], b.pixels[(j * N + i) as usize]);
            for (term, x, y, count) in [
                ("direct", pa.direct, pb.direct, &mut direct_checked),
                ("caustic", pa.caustic, pb.caustic, &mut caustic_checked),
            ] {
                if y == Vec3::ZERO {
                    continue; // the light's back, or no caustic photon near
                }
                let want = kd * y;
                assert!(
                    (x - want).abs().max_element() <= 1e-5 * want.max_element().max(1e-3),
                    "pixel ({i}, {j}) {term}: {x} against kd·white = {want}"
                );
                *count += 1;
            }
        }
    }
    // Most checked pixels see the floor lit; caustics land on the floor's right half.
    assert!(direct_checked > 1000, "{direct_checked} pixels checked for direct light");
    assert!(caustic_checked > 200, "{caustic_checked} pixels checked for caustics");
}

#[test]
fn engines_agree_on_a_textured_scene_at_any_thread_count() {
    let dir = scratch_dir("textured-engines");
    let path = floor_scene(&dir, "textured", Some(checker(&dir)));
    let s = Settings { spp: 2, ..settings() };
    let a = reference(&load_scene(&path).unwrap(), &s);
    let wavefront = |threads: u32| {
        let loaded = load_scene(&path).unwrap();
        let rays = loaded.camera.unwrap().prepare(s.width, s.height).unwrap();
        let s = Settings { threads, ..s.clone() };
        photonwave::wavefront::render(Arc::new(loaded.scene), &rays, &s, &NoProgress).unwrap().0
    };
    let (b1, b2) = (wavefront(1), wavefront(2));
    assert_eq!(b1.pixels, b2.pixels, "the wavefront engine is bit-identical across thread counts");
    // As in tests/wavefront.rs: 1e-6 relative per term and channel.
    assert_terms_agree(&a, &b1, 1e-6);
    assert!(a.pixels.iter().any(|p| p.indirect != Vec3::ZERO), "the textured floor reflects photons");
}

#[test]
fn a_jpeg_decodes_to_its_colour() {
    // An 8×8 JPEG of the sRGB colour (200, 100, 50), written by Pillow at quality 95.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/references/texture-200-100-50.jpg");
    let t = load_texture(&path, Encoding::Srgb, "a `map_Kd` texture").unwrap();
    assert_eq!((t.width, t.height), (8, 8));
    let want = Vec3::new(200.0, 100.0, 50.0).map(|c| srgb_to_linear(c / 255.0));
    // JPEG's colour transform rounds: allow 2 of 255 codes, at the steepest part of the curve.
    let tolerance = srgb_to_linear(202.0 / 255.0) - srgb_to_linear(200.0 / 255.0);
    for texel in &t.texels {
        assert!((*texel - want).abs().max_element() <= tolerance, "{texel} against {want}");
    }
}

#[test]
fn bad_textures_are_refused_naming_the_mtl_line_and_the_image() {
    let dir = scratch_dir("textured-bad");
    let scene = floor_scene(&dir, "bad", Some("missing.png"));
    let e = load_scene(&scene).err().expect("a missing texture is an error").to_string();
    assert!(e.contains("missing.png") && e.contains("bad.mtl:3") && e.contains("map_Kd"), "{e}");

    // Truncated, not an image, and zero-sized (a PNG header claiming 0×4).
    let mut good = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut good, 4, 4);
        enc.set_color(png::ColorType::Rgb);
        enc.write_header().unwrap().write_image_data(&[7; 48]).unwrap();
    }
    std::fs::write(dir.join("missing.png"), &good[..good.len() - 16]).unwrap();
    let e = load_scene(&scene).err().expect("a truncated texture is an error").to_string();
    assert!(e.contains("missing.png") && e.contains("damaged") && e.contains("bad.mtl:3"), "{e}");
    std::fs::write(dir.join("missing.png"), "P3\n1 1\n255\n0 0 0\n").unwrap();
    let e = load_scene(&scene).err().expect("a text file is no texture").to_string();
    assert!(e.contains("missing.png") && e.contains("not a PNG, JPEG or OpenEXR"), "{e}");
    let mut zero = good.clone();
    zero[16..20].copy_from_slice(&0u32.to_be_bytes()); // IHDR width
    std::fs::write(dir.join("missing.png"), &zero).unwrap();
    let e = load_scene(&scene).err().expect("a zero-sized texture is an error").to_string();
    assert!(e.contains("missing.png") && e.contains("bad.mtl:3"), "{e}");
    // A directory where the image should be.
    std::fs::remove_file(dir.join("missing.png")).unwrap();
    std::fs::create_dir(dir.join("missing.png")).unwrap();
    let e = load_scene(&scene).err().expect("a directory is no texture").to_string();
    assert!(e.contains("missing.png") && e.contains("directory"), "{e}");
}

#[test]
fn a_mesh_without_texture_coordinates_is_warned_about() {
    let dir = scratch_dir("textured-no-vt");
    let path = floor_scene(&dir, "novt", Some(checker(&dir)));
    let obj = dir.join("novt.obj");
    let text = std::fs::read_to_string(&obj).unwrap();
    let text: String = text
        .lines()
        .filter(|l| !l.starts_with("vt"))
        .map(|l| l.replace("/1", "").replace("/2", "").replace("/3", "").replace("/4", "") + "\n")
        .collect();
    std::fs::write(&obj, text).unwrap();
    let loaded = load_scene(&path).unwrap();
    assert!(
        loaded.scene.warnings.iter().any(|w| w.contains("no texture coordinates") && w.contains("`floor`")),
        "{:?}",
        loaded.scene.warnings
    );
}

/// A closed box of half-size 1 whose ceiling holds a 0.5 × 0.5 light, its MTL `light` material
/// given by `light_mtl`; texture coordinates span the light once.
fn lit_box(dir: &Path, name: &str, light_mtl: &str) -> PathBuf {
    let obj = "mtllib b.mtl\n\
        v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n\
        usemtl wall\nf 1 2 3 4\nf 5 8 7 6\nf 1 5 6 2\nf 4 3 7 8\nf 1 4 8 5\nf 2 6 7 3\n\
        v -0.25 0.999 -0.25\nv 0.25 0.999 -0.25\nv 0.25 0.999 0.25\nv -0.25 0.999 0.25\n\
        vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
        usemtl light\nf 9/1 10/2 11/3 12/4\n";
    std::fs::write(dir.join(format!("{name}.obj")), obj.replace("b.mtl", &format!("{name}.mtl"))).unwrap();
    std::fs::write(
        dir.join(format!("{name}.mtl")),
        format!("newmtl wall\nKd 0.5 0.5 0.5\nnewmtl light\nKd 0 0 0\n{light_mtl}\n"),
    )
    .unwrap();
    let toml =
        format!("[[mesh]]\nfile = \"{name}.obj\"\n[camera]\neye = [0, -0.6, 0.95]\ntarget = [0, 0.99, 0]\nfov = 50\n");
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, toml).unwrap();
    path
}

#[test]
fn a_one_colour_emission_texture_renders_as_the_constant_emission() {
    // The same samples and, per sample, the same radiance (the texel, sRGB-decoded, equals the
    // constant): the images agree to f32 rounding in every term, in both engines.
    let dir = scratch_dir("textured-light-uniform");
    write_png(&dir.join("glow.png"), 1, 1, &[255, 200, 120]);
    let ke = Vec3::new(255.0, 200.0, 120.0).map(|c| srgb_to_linear(c / 255.0));
    let textured = lit_box(&dir, "textured", "Ke 1 1 1\nmap_Ke glow.png");
    let constant = lit_box(&dir, "constant", &format!("Ke {} {} {}", ke.x, ke.y, ke.z));
    let s = Settings { spp: 2, ..settings() };
    let (a, b) = (reference(&load_scene(&textured).unwrap(), &s), reference(&load_scene(&constant).unwrap(), &s));
    for (k, (x, y)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        for (u, v) in x.as_array().into_iter().zip(y.as_array()) {
            assert!(
                ((u - v).abs() / v.abs().max(Vec3::splat(1e-3))).max_element() < 1e-4,
                "pixel {k}: {u} against {v}"
            );
        }
    }
    let loaded = load_scene(&textured).unwrap();
    let rays = loaded.camera.unwrap().prepare(s.width, s.height).unwrap();
    let w = photonwave::wavefront::render(Arc::new(loaded.scene), &rays, &s, &NoProgress).unwrap().0;
    assert_terms_agree(&a, &w, 1e-6);
}

#[test]
fn a_textured_light_emits_its_mean_texel_and_shows_its_texture() {
    // Bilinear lookup with wrap averages, over one period, to the texels' mean, so the light's
    // power is π·A·mean. In a closed box every photon's first hit lands somewhere: the
    // first-hit photons' power sums to it (relative spread of the sum ≈ 1/√N for 200 000).
    let dir = scratch_dir("textured-light-power");
    let texels: [[u8; 3]; 4] = [[255, 255, 255], [0, 0, 0], [255, 128, 0], [40, 40, 40]];
    write_png(&dir.join("sign.png"), 4, 1, &texels.concat());
    let path = lit_box(&dir, "sign", "Ke 1 1 1\nmap_Ke sign.png");
    let scene = load_scene(&path).unwrap().scene;
    let mean =
        texels.iter().map(|t| Vec3::from_array(t.map(|c| srgb_to_linear(f32::from(c) / 255.0)))).sum::<Vec3>() / 4.0;
    let want = mean * std::f32::consts::PI * 0.25;
    let s = Settings { photons: 200_000, threads: 2, ..Default::default() };
    let t = photonwave::reference::photons::trace_photons(
        &scene,
        &common::job(&scene, &s),
        photonwave::rng::Domain::GlobalPhoton,
        200_000,
        &NoProgress,
    );
    let got = photonwave::transport::photon::first_hit_power(&t.photons);
    assert!(
        ((got - want).abs() / want.max(Vec3::splat(1e-6))).max_element() < 0.02,
        "first-hit power {got} against π·A·mean = {want}"
    );
    // The camera sees the texture: the light's emitted pixels span the texels' range.
    let loaded = load_scene(&path).unwrap();
    let film = reference(&loaded, &Settings { width: 32, height: 32, spp: 1, ..settings() });
    let lit: Vec<f32> = film.pixels.iter().map(|p| p.emitted.x).filter(|&e| e > 0.0).collect();
    let (lo, hi) = lit.iter().fold((f32::MAX, 0f32), |(a, b), &e| (a.min(e), b.max(e)));
    assert!(lit.len() > 20 && hi > 0.9 && lo < 0.1, "{} emitting pixels, {lo}..{hi}", lit.len());
}

#[test]
fn engines_agree_on_a_metallic_and_roughness_mapped_floor() {
    // The checker as data: its white and brown quadrants (red ≥ ½) are metal, the others
    // plastic; the same checker as roughness. Both engines read the same per-point BSDF.
    let dir = scratch_dir("textured-metallic");
    let path = floor_scene(&dir, "pbr", Some(checker(&dir)));
    let mtl = dir.join("pbr.mtl");
    let text = std::fs::read_to_string(&mtl).unwrap();
    std::fs::write(
        &mtl,
        text.replace(
            "newmtl floor\nKd 1 1 1\n",
            "newmtl floor\nKd 0.8 0.6 0.3\nPr 0.5\nmap_Pm checker.png\nmap_Pr checker.png\n",
        ),
    )
    .unwrap();
    let loaded = load_scene(&path).unwrap();
    assert!(loaded.scene.warnings.iter().all(|w| !w.contains("not simulated")), "{:?}", loaded.scene.warnings);
    let s = Settings { spp: 2, ..settings() };
    let a = reference(&loaded, &s);
    let rays = loaded.camera.unwrap().prepare(s.width, s.height).unwrap();
    let w =
        photonwave::wavefront::render(Arc::new(load_scene(&path).unwrap().scene), &rays, &s, &NoProgress).unwrap().0;
    assert_terms_agree(&a, &w, 1e-6);
    // Metal quadrants reflect the light's highlight through the glossy ray (the specular layer);
    // plastic ones have a diffuse base too: both are lit.
    assert!(a.pixels.iter().any(|p| p.specular != Vec3::ZERO) && a.pixels.iter().any(|p| p.direct != Vec3::ZERO));
}

/// Loading counts its stages (issue 57, `--stats` `times.load`): the textured table spends time
/// decoding `wood.png`, the untextured box none; both spend some on their BVH and lights; the
/// stages never add up to more than the load took.
#[test]
fn a_load_says_where_its_time_went() {
    for (scene, textured) in [("table.toml", true), ("cornell-box.toml", false)] {
        let clock = std::time::Instant::now();
        let loaded = load_scene(&bundled(scene)).unwrap();
        let whole = clock.elapsed().as_secs_f64();
        let t = loaded.scene.load_times;
        println!("{scene}: {t:?} of {whole:.4} s");
        assert_eq!(t.textures_s > 0.0, textured, "{scene}: {t:?}");
        assert!(t.bvh_s > 0.0 && t.lights_s > 0.0 && t.triangles_s > 0.0 && t.parse_s > 0.0, "{scene}: {t:?}");
        let sum = t.parse_s + t.textures_s + t.triangles_s + t.bvh_s + t.lights_s + t.topology_s;
        assert!(sum <= whole, "{scene}: stages {sum} s of a {whole} s load");
    }
}
