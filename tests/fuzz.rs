//! Fuzzing in the normal test run, bounded and with fixed seeds: the properties of
//! `photonwave::fuzzing` on mutated scene files and on rays through shared edges. The open-ended
//! twins are the cargo-fuzz targets in fuzz/ (docs/src/bad-input.md, "Fuzzing").

mod common;

use common::scratch_dir;
use glam::Vec3;
use photonwave::fuzzing;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

const OBJ: &str = "mtllib m.mtl\no floor\nusemtl half\nv -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\nvn 0 1 0\nvt 0 0\n\
f 1//1 2//1 3//1 4//1\no light\nusemtl light\nv -0.25 1 -0.25\nv 0.25 1 -0.25\nv 0.25 1 0.25\nv -0.25 1 0.25\n\
f 5 6 7 8\no ball\nusemtl glass\nv 0 0.2 0\nv 0.2 0.4 0\nv -0.2 0.4 0\nv 0 0.4 0.2\nf 9 10 11\nf 9 11 12\nf 9 12 10\nf 10 12 11\n";
const MTL: &str = "newmtl half\nillum 2\nKd 0.5 0.5 0.5\nKs 0.2 0.2 0.2\nNs 20\n\
newmtl light\nKd 0 0 0\nKe 4 4 4\nnewmtl glass\nillum 7\nNi 1.5\n";
const TOML: &str = "[[mesh]]\nfile = \"a.obj\"\nscale = 1.0\n\n[camera]\neye = [0, 0.5, 1.8]\ntarget = [0, 0.3, 0]\nfov = 50\n\n\
[[light]]\ntype = \"spot\"\nposition = [0, 0.9, 0]\ntarget = [0, 0, 0]\nintensity = [1, 1, 1]\nangle = 30\n\n\
[materials.half]\ntype = \"lambert\"\nkd = [0.5, 0.5, 0.5]\n\n[render]\nwidth = 4\nheight = 4\nspp = 1\nphotons = 300\ncaustic_photons = 300\ngather_rays = 2\n";

/// How many of [`TOKENS`] (its head) are numbers.
const NUMBERS: usize = 19;

/// Tokens a mutation may write: numbers at the edges of f32 (the first [`NUMBERS`]), then
/// non-numbers and keywords of all three formats.
const TOKENS: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "1e-45",
    "1e38",
    "3.5e38",
    "-3.5e38",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e400",
    "0.5",
    "7",
    "-7",
    "4294967296",
    "18446744073709551617",
    "2147483647",
    "",
    "/",
    "//",
    "1/2/3",
    "1//",
    "v",
    "vn",
    "vt",
    "f",
    "o",
    "usemtl",
    "mtllib",
    "newmtl",
    "Kd",
    "Ke",
    "Ks",
    "Ns",
    "Ni",
    "illum",
    "=",
    "[",
    "]",
    "\"",
    "[[mesh]]",
    "[camera]",
    "[render]",
    "[[light]]",
    "type",
    "\"glass\"",
    "\"mirror\"",
    "\"point\"",
    "\"directional\"",
    "[0, 0, 0]",
    "[nan, 1, 1]",
    "[1e39, 0, 0]",
    "fov",
    "width",
    "spp",
    "photons",
    "\u{fffd}",
    "é",
    "\0",
];

/// One edit of a text: (kind, word position, token). Positions are taken modulo the word count.
/// Kinds: replace a word, insert a word, remove one, double one, insert a line, cut the rest off,
/// and (twice as likely) replace a number by another.
type Edit = (u8, usize, usize);

fn apply(text: &str, edits: &[Edit]) -> String {
    let mut words: Vec<String> = text.split_inclusive([' ', '\n']).map(str::to_string).collect();
    for &(kind, pos, tok) in edits {
        if words.is_empty() {
            words.push(String::new());
        }
        let i = pos % words.len();
        let token = TOKENS[tok % TOKENS.len()];
        let tail = ["\n", " "].into_iter().find(|t| words[i].ends_with(t)).unwrap_or("");
        match kind % 8 {
            // A number (the first at or after i) becomes another: the file keeps its shape, so
            // these edits reach the renderer.
            6 | 7 => {
                let number = |w: &String| w.trim().parse::<f64>().is_ok();
                if let Some(j) = (i..words.len()).find(|&j| number(&words[j])) {
                    let tail = ["\n", " "].into_iter().find(|t| words[j].ends_with(t)).unwrap_or("");
                    words[j] = format!("{}{tail}", TOKENS[tok % NUMBERS]);
                }
            }
            0 => words[i] = format!("{token}{tail}"),
            1 => words.insert(i, format!("{token} ")),
            2 => drop(words.remove(i)),
            3 => words.insert(i, words[i].clone()),
            4 => words.insert(i, format!("{token}\n")),
            _ => words.truncate(i),
        }
    }
    words.concat()
}

/// No edit with weight `keep`, else 1–5 edits with weight `edit`.
fn edits(keep: u32, edit: u32) -> impl Strategy<Value = Vec<Edit>> {
    prop_oneof![keep => Just(vec![]), edit => prop::collection::vec((any::<u8>(), any::<usize>(), any::<usize>()), 1..6)]
}

fn runner(cases: u32, seed: u8) -> TestRunner {
    let config = Config { cases, failure_persistence: None, ..Config::default() };
    TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &[seed; 32]))
}

/// 500 mutated scenes (the TOML left alone in three cases of four, the OBJ and MTL in one of
/// three, else edited 1–5 times, see [`Edit`]): each loads, or fails with a short message, and a
/// scene that loads renders on both engines to a finite image or an error.
#[test]
fn mutated_scene_files_load_or_fail_cleanly() {
    let dir = scratch_dir("fuzz-scenes");
    runner(500, 7)
        .run(&(edits(3, 1), edits(1, 2), edits(1, 2)), |(toml, obj, mtl)| {
            let (toml, obj, mtl) = (apply(TOML, &toml), apply(OBJ, &obj), apply(MTL, &mtl));
            let result = fuzzing::scene_files(&dir, toml.as_bytes(), obj.as_bytes(), mtl.as_bytes());
            prop_assert!(result.is_ok(), "{result:?}\n--- s.toml\n{toml}\n--- a.obj\n{obj}\n--- m.mtl\n{mtl}");
            Ok(())
        })
        .unwrap();
}

/// 400 mutated models: the ASCII PLY quad, the bundled glTF Cornell box and a Mitsuba scene of
/// built-in shapes, edited 1–5 times as text (see [`Edit`]), and the binary PLY and GLB boxes
/// with 1–8 bytes overwritten: each loads,
/// or fails with a short message, and a model that loads renders to a finite image or an error.
#[test]
fn mutated_models_load_or_fail_cleanly() {
    let dir = scratch_dir("fuzz-models");
    let ascii = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
property float nx\nproperty float ny\nproperty float nz\nelement face 1\nproperty list uchar int vertex_indices\n\
end_header\n0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n4 0 1 2 3\n";
    let scenes = common::bundled("interchange");
    let gltf = std::fs::read_to_string(scenes.join("cornell-box.gltf")).unwrap();
    let (ply, glb) =
        (std::fs::read(scenes.join("white.ply")).unwrap(), std::fs::read(scenes.join("cornell-box.glb")).unwrap());
    let bytes = prop::collection::vec((any::<usize>(), any::<u8>()), 1..9);
    let xml = "<scene version=\"2.0.0\">\n<default name=\"a\" value=\"0.3\"/>\n<sensor type=\"perspective\">\n\
<float name=\"fov\" value=\"45\"/>\n<transform name=\"to_world\"><lookat origin=\"0, 0, 4\" target=\"0, 0, 0\" up=\"0, 1, 0\"/>\n\
</transform>\n<film type=\"hdrfilm\"><integer name=\"width\" value=\"4\"/><integer name=\"height\" value=\"4\"/></film>\n</sensor>\n\
<bsdf type=\"roughconductor\" id=\"m\"><float name=\"alpha\" value=\"$a\"/></bsdf>\n\
<shape type=\"sphere\"><float name=\"radius\" value=\"0.5\"/><ref id=\"m\"/></shape>\n\
<shape type=\"rectangle\"><transform name=\"to_world\"><rotate x=\"1\" angle=\"90\"/><scale value=\"3\"/>\n\
<translate y=\"2\"/></transform><bsdf type=\"dielectric\"/><emitter type=\"area\"><rgb name=\"radiance\" value=\"2\"/></emitter></shape>\n\
<emitter type=\"spot\"><float name=\"cutoff_angle\" value=\"40\"/></emitter>\n</scene>\n";
    runner(400, 13)
        .run(&(0u8..5, edits(0, 1), bytes), |(kind, edits, bytes)| {
            let overwrite = |mut data: Vec<u8>| {
                let n = data.len();
                bytes.iter().for_each(|&(at, b)| data[at % n] = b);
                data
            };
            let (name, data) = match kind {
                0 => ("m.ply", apply(ascii, &edits).into_bytes()),
                1 => ("m.gltf", apply(&gltf, &edits).into_bytes()),
                2 => ("m.ply", overwrite(ply.clone())),
                3 => ("m.glb", overwrite(glb.clone())),
                _ => ("m.xml", apply(xml, &edits).into_bytes()),
            };
            let result = fuzzing::mesh_file(&dir, name, &data);
            prop_assert!(result.is_ok(), "{result:?}\n--- {name}\n{}", String::from_utf8_lossy(&data));
            Ok(())
        })
        .unwrap();
}

/// 3 000 triangle pairs sharing an edge, at scales 10⁻⁴, 1 and 10⁵, and rays toward a point of
/// the edge (its middle half) from inside their wedge, from as far as the edge is long or 10³ and
/// 10⁶ times that (where a triangle is tiny beside its distance and f32 alone cannot prove t > 0),
/// with unit or unnormalised directions: one triangle is hit at t > 0, packet and scalar alike.
/// Cases reaching beyond ±`MAX_COORDINATE` (the farthest rays at scale 10⁵) are left out: the
/// loader refuses such scenes.
#[test]
fn rays_through_a_shared_edge_hit_one_side() {
    let point = || prop::array::uniform3(-1.0f32..1.0).prop_map(Vec3::from);
    let scale = prop_oneof![Just(1e-4f32), Just(1.0), Just(1e5)];
    let far = prop_oneof![Just(1.0f32), Just(1e3), Just(1e6)];
    let mix = (prop_oneof![Just(0.5f32), 0.25f32..0.75], 0.2f32..0.8, 0.2f32..0.8, far);
    let strategy = (point(), point(), point(), point(), mix, scale, any::<bool>());
    runner(3000, 11)
        .run(&strategy, |(a, b, u1, u2, (s, w, h, far), scale, normalise)| {
            let e = b - a;
            // Unit wing directions: u1, u2 without their components along the edge.
            let unit = |u: Vec3| (u - e * (u.dot(e) / e.length_squared())).normalize_or_zero();
            let (n1, n2) = (unit(u1), unit(u2));
            prop_assume!(e.length() > 1e-2 && n1 != Vec3::ZERO && n2 != Vec3::ZERO);
            let m = a + e * 0.5;
            let (c1, c2) = (m + n1 * e.length(), m + n2 * e.length());
            // From inside the wedge, `far` edge lengths away.
            let o = m + (n1 * w + n2 * (1.0 - w)) * (h * far * e.length()) + e * (0.3 - 0.6 * w);
            let target = a + e * s;
            // Beyond ±MAX_COORDINATE (10⁶ edge lengths at scale 10⁵) scenes are refused at load.
            let reach = (o.abs().max_element() + 2.0) * scale;
            prop_assume!(reach <= photonwave::geometry::MAX_COORDINATE);
            let result =
                fuzzing::edge_ray(a * scale, b * scale, c1 * scale, c2 * scale, o * scale, target * scale, normalise);
            prop_assert!(result.is_ok(), "{result:?}");
            Ok(())
        })
        .unwrap();
}

/// Every input a cargo-fuzz target ever failed on, kept in `fuzz/regressions/TARGET/`
/// (docs/src/bad-input.md, "Fuzzing"), passes its property now.
#[test]
fn inputs_the_fuzzers_found_stay_fixed() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/regressions");
    let dir = scratch_dir("fuzz-regressions");
    let mut count = 0;
    for target in ["edge_rays", "scene_files", "mesh_files"] {
        let Ok(entries) = std::fs::read_dir(root.join(target)) else { continue };
        for entry in entries {
            let path = entry.unwrap().path();
            let data = std::fs::read(&path).unwrap();
            let result = if target == "edge_rays" {
                let floats: Vec<f32> =
                    data.chunks_exact(4).take(18).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
                fuzzing::edge_rays_input(floats.try_into().expect("an edge_rays input has 72 bytes"))
            } else if target == "mesh_files" {
                fuzzing::mesh_files_input(&dir, &data)
            } else {
                fuzzing::scene_files_input(&dir, &data)
            };
            assert!(result.is_ok(), "{}: {result:?}", path.display());
            count += 1;
        }
    }
    assert!(count > 0, "no regression inputs found under {}", root.display());
}

/// 20 000 BSDF samples and evaluations of every material kind, with extreme parameters (Phong
/// exponents 0 to 10³⁰, albedos at their edges, indices of refraction 0.01 to 100), grazing and
/// exactly tangent directions, and shading normals that are zero, NaN, opposite to or
/// perpendicular to the geometric normal: a sample is absent (a zero pdf, absorption) or has a
/// finite direction and a finite, non-negative weight; evaluations are finite and non-negative.
/// Nothing non-finite can leave a BSDF for the film or a photon map.
#[test]
fn bsdf_samples_are_finite_or_absent() {
    use photonwave::material::{Bsdf, SurfaceFrame, Transport};
    let unit = || prop::array::uniform3(-1.0f32..1.0).prop_map(|v| Vec3::from(v).normalize_or(Vec3::Y));
    let exponent = prop_oneof![Just(0.0f32), Just(1.0), Just(1e4), Just(1e30), 0.0f32..1000.0];
    let albedo = || prop_oneof![Just(0.0f32), Just(1.0), 0.0f32..1.0];
    let ior = prop_oneof![Just(1.0f32), Just(1.5), Just(0.01), Just(100.0), 0.5f32..3.0];
    let bsdf = (0u8..4, albedo(), albedo(), exponent, ior).prop_map(|(kind, a, b, exponent, ior)| match kind {
        0 => Bsdf::Lambert { kd: Vec3::splat(a) },
        1 => Bsdf::Glossy { kd: Vec3::splat(a * (1.0 - b)), ks: Vec3::splat(b), exponent },
        2 => Bsdf::Mirror { ks: Vec3::splat(a), eta_k: None },
        _ => Bsdf::Glass { ior, tint: photonwave::material::Tint::CLEAR },
    });
    let shading = prop_oneof![
        Just(Vec3::ZERO),
        Just(Vec3::NAN),
        unit(),
        Just(Vec3::X), // perpendicular to ng = Y
        Just(-Vec3::Y),
    ];
    let wo = prop_oneof![unit(), Just(Vec3::X), Just(Vec3::new(1.0, 1e-7, 0.0).normalize())];
    let u = prop::array::uniform3(prop_oneof![Just(0.0f32), Just(1.0 - f32::EPSILON), 0.0f32..1.0]);
    runner(20_000, 13)
        .run(&(bsdf, shading, wo, u, any::<bool>()), |(bsdf, ns, wo, u, power)| {
            let frame = SurfaceFrame { ng: Vec3::Y, ns };
            let transport = if power { Transport::Power } else { Transport::Radiance };
            if let Some(s) = bsdf.sample(&frame, wo, u, transport) {
                prop_assert!(s.wi.is_finite() && (s.wi.length() - 1.0).abs() < 1e-3, "{bsdf:?}: direction {}", s.wi);
                prop_assert!(s.weight.is_finite() && s.weight.min_element() >= 0.0, "{bsdf:?}: weight {}", s.weight);
                let f = bsdf.eval(&frame, wo, s.wi);
                prop_assert!(f.is_finite() && f.min_element() >= 0.0, "{bsdf:?}: f {f}");
            }
            Ok(())
        })
        .unwrap();
}
