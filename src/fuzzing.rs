//! The properties that fuzzing checks, shared by the bounded proptest suite (`tests/fuzz.rs`) and
//! the open-ended cargo-fuzz targets (`fuzz/`). Each returns `Err` with a description when the
//! property fails; bad input that is refused with an error is not a failure.

use crate::engine::{render, Engine};
use crate::formats::load_scene;
use crate::geometry::bvh::TriangleColumns;
use crate::geometry::packet::closest_packets;
use crate::geometry::traverse::closest_rays;
use crate::geometry::{in_range, Bvh, RayQuery};
use crate::progress::NoProgress;
use crate::settings::Settings;
use glam::Vec3;
use std::path::Path;
use std::sync::Arc;

/// Most work a fuzzed scene may ask for before it is only loaded, not rendered.
const MAX_PIXELS: u32 = 64;
const MAX_PHOTONS: u32 = 5_000;

/// The cargo-fuzz target `scene_files`'s input: TOML, OBJ and MTL text separated by 0xFF bytes,
/// checked by [`scene_files`] in `dir`.
pub fn scene_files_input(dir: &Path, data: &[u8]) -> Result<(), String> {
    let mut parts = data.split(|&b| b == 0xff);
    let mut next = || parts.next().unwrap_or_default();
    let (toml, obj, mtl) = (next(), next(), next());
    scene_files(dir, toml, obj, mtl)
}

/// The cargo-fuzz target `mesh_files`'s input: the first byte picks the format (0: PLY, 1: glTF,
/// 2: GLB, 3: Mitsuba XML, by its value mod 4), the rest is the file, checked by [`mesh_file`]
/// in `dir`.
pub fn mesh_files_input(dir: &Path, data: &[u8]) -> Result<(), String> {
    let (kind, body) = data.split_first().unwrap_or((&0, &[]));
    mesh_file(dir, ["m.ply", "m.gltf", "m.glb", "m.xml"][usize::from(*kind) % 4], body)
}

/// Writes `bytes` as `dir/name` (a PLY, glTF, GLB or Mitsuba file) and loads it alone, lit by a headlight
/// (so that a model without lights still renders). An error must be a short, non-empty message;
/// a model that loads must render a 4×4 image on both engines, finite or an error.
pub fn mesh_file(dir: &Path, name: &str, bytes: &[u8]) -> Result<(), String> {
    let path = dir.join(name);
    std::fs::write(&path, bytes).map_err(|e| format!("cannot write the input: {e}"))?;
    let headlight = |_: (Vec3, Vec3), _: Option<crate::scene::Camera>| {
        vec![crate::scene::Light::Point { position: Vec3::new(0.0, 0.0, 10.0), intensity: Vec3::ONE }]
    };
    let loaded = match crate::formats::load_scene_lit(&path, &headlight) {
        Err(e) => {
            let msg = e.to_string();
            return if msg.is_empty() || msg.len() > 2000 { Err(format!("unhelpful error: {msg:?}")) } else { Ok(()) };
        }
        Ok(loaded) => loaded,
    };
    let s = Settings {
        threads: 1,
        width: 4,
        height: 4,
        spp: 1,
        photons: 300,
        caustic_photons: 300,
        gather_rays: 2,
        ..loaded.settings
    };
    let camera = loaded
        .camera
        .unwrap_or_else(|| crate::scene::camera::fitted_camera(&loaded.scene, crate::scene::camera::DEFAULT_FOV, 1.0));
    let Ok(rays) = camera.prepare(s.width, s.height) else { return Ok(()) };
    renders_finite(loaded.scene, &rays, &s).map_err(|e| format!("{name}, {e}"))
}

/// The cargo-fuzz target `edge_rays`'s input: 18 floats — the edge's ends `a`, `b`, the wings
/// `c1`, `c2`, the ray origin (3 each), where on the edge the ray aims (in [0, 1]), a scale for
/// every point, and whether the direction is normalised (> 0) — checked by [`edge_ray`].
/// Inputs that are not finite, aim off the edge or have no positive scale are skipped.
pub fn edge_rays_input(data: [f32; 18]) -> Result<(), String> {
    let v = |i: usize| Vec3::new(data[i], data[i + 1], data[i + 2]);
    let (a, b, c1, c2, o) = (v(0), v(3), v(6), v(9), v(12));
    let (s, scale, normalise) = (data[15], data[16], data[17] > 0.0);
    if !data.iter().all(|x| x.is_finite()) || !(0.0..=1.0).contains(&s) || !(scale > 0.0) {
        return Ok(());
    }
    let target = (a + (b - a) * s) * scale;
    edge_ray(a * scale, b * scale, c1 * scale, c2 * scale, o * scale, target, normalise)
}

/// Writes `s.toml`, `a.obj` and `m.mtl` into `dir` and loads `s.toml`. An error must be a short,
/// non-empty message; a scene that loads (with a camera and a modest amount of work) must render
/// on both engines to a finite image or to an error. Panics are the caller's to catch (the
/// fuzzer and the test harness both report them).
pub fn scene_files(dir: &Path, toml: &[u8], obj: &[u8], mtl: &[u8]) -> Result<(), String> {
    for (name, text) in [("s.toml", toml), ("a.obj", obj), ("m.mtl", mtl)] {
        std::fs::write(dir.join(name), text).map_err(|e| format!("cannot write the input: {e}"))?;
    }
    let loaded = match load_scene(&dir.join("s.toml")) {
        Err(e) => {
            let msg = e.to_string();
            return if msg.is_empty() || msg.len() > 2000 { Err(format!("unhelpful error: {msg:?}")) } else { Ok(()) };
        }
        Ok(loaded) => loaded,
    };
    let Some(camera) = loaded.camera else { return Ok(()) };
    let s = Settings { threads: 1, ..loaded.settings };
    let small = s.width.saturating_mul(s.height) <= MAX_PIXELS
        && s.spp <= 4
        && s.passes <= 2
        && s.photons <= MAX_PHOTONS
        && s.caustic_photons <= MAX_PHOTONS;
    if s.validate().is_err() || !small {
        return Ok(());
    }
    let Ok(rays) = camera.prepare(s.width, s.height) else { return Ok(()) };
    renders_finite(loaded.scene, &rays, &s)
}

/// Renders `scene` on both engines: each gives a finite image or an error.
fn renders_finite(
    scene: crate::scene::Scene,
    rays: &crate::scene::camera::CameraRays,
    s: &Settings,
) -> Result<(), String> {
    let scene = Arc::new(scene);
    for engine in [Engine::Wavefront, Engine::Reference] {
        if let Ok((film, _)) = render(&scene, rays, s, engine, None, &NoProgress) {
            if let Some(i) = film.pixels.iter().position(|t| !t.is_finite()) {
                return Err(format!("{engine:?}: pixel {i} is {:?}", film.pixels[i]));
            }
        }
    }
    Ok(())
}

/// Two triangles sharing the edge (a, b), wound as in a closed mesh — (a, b, c1) and (b, a, c2) —
/// and a ray from `o` toward `target`, a point of the edge, with direction `target − o`
/// (unnormalised, as shadow rays have) or its unit vector. Packet and scalar traversal must
/// return the same hit. When the case is well conditioned — `target` in the middle half of the
/// edge, both wings at least half as long as the edge, `o` inside their wedge and clear of both
/// faces' planes — watertight intersection must also hit one of them at t > 0. (Two triangles
/// alone do not close the space: near a vertex, or beside a face seen edge-on that is thinner
/// than f32 resolves, a ray may rightly pass where a closed mesh has its other faces.)
///
/// Points outside ±[`MAX_COORDINATE`](crate::geometry::MAX_COORDINATE) are skipped: the loader refuses such scenes, because the
/// f32 test's products overflow there.
pub fn edge_ray(a: Vec3, b: Vec3, c1: Vec3, c2: Vec3, o: Vec3, target: Vec3, normalise: bool) -> Result<(), String> {
    if ![a, b, c1, c2, o, target].into_iter().all(in_range) {
        return Ok(());
    }
    let d = if normalise { (target - o).normalize_or_zero() } else { target - o };
    let (p0, p1, p2) = ([a, b], [b, a], [c1, c2]);
    let (bvh, order) = Bvh::build(&p0, &p1, &p2);
    let pick = |v: &[Vec3; 2]| order.iter().map(|&i| v[i as usize]).collect::<Vec<_>>();
    let (q0, q1, q2) = (pick(&p0), pick(&p1), pick(&p2));
    let cols = TriangleColumns::new(&q0, &q1, &q2);
    let rays = [RayQuery::new(o, d, f32::INFINITY)];
    let (mut scalar, mut packet) = ([None], [None]);
    closest_rays(&bvh, cols, &rays, &mut scalar);
    closest_packets(&bvh, cols, &rays, &mut packet);
    if scalar != packet {
        return Err(format!("{:?}: scalar {:?}, packet {:?}", rays[0], scalar[0], packet[0]));
    }
    let mut wide = [None];
    crate::geometry::wide_traverse::closest_rays::<true>(bvh.wide(cols), cols.cut, &rays, &mut wide);
    if scalar != wide {
        return Err(format!("{:?}: scalar {:?}, 8-wide {:?}", rays[0], scalar[0], wide[0]));
    }
    if well_conditioned(a, b, c1, c2, o, target) && !scalar[0].is_some_and(|h| h.t > 0.0) {
        return Err(format!("{:?} slipped through the edge {a}–{b} (wings {c1}, {c2})", rays[0]));
    }
    Ok(())
}

/// The conditions of [`edge_ray`]'s hit property: `target` in the middle half of the edge, both
/// wings at least half the edge's length from its line, and `o` inside the wedge they bound (an
/// open dihedral angle below 180°), with both wing directions weighing at least a tenth in it.
fn well_conditioned(a: Vec3, b: Vec3, c1: Vec3, c2: Vec3, o: Vec3, target: Vec3) -> bool {
    let edge = b - a;
    let (len, e) = (edge.length(), edge.normalize_or_zero());
    let s = (target - a).dot(e) / len;
    let perp = |p: Vec3| (p - a) - e * (p - a).dot(e);
    if !(0.25..=0.75).contains(&s) || perp(c1).length() < 0.5 * len || perp(c2).length() < 0.5 * len {
        return false;
    }
    let (u1, u2, v) = (perp(c1).normalize_or_zero(), perp(c2).normalize_or_zero(), perp(o));
    if u1 == Vec3::ZERO || u2 == Vec3::ZERO || v.length() == 0.0 || u1.dot(u2).abs() > 0.95 {
        return false;
    }
    // The ray must cross the edge, not run along it (sine of their angle ≥ 0.1), and the edge
    // must be long against the f32 rounding of the ray's aim (a quarter of it, the least margin to
    // the segment's ends, ≥ 64 ε of the coordinates): otherwise the ray may rightly pass beside the
    // segment, where a closed mesh has its other faces. (Found by the fuzzer: a ray along an edge
    // 6.5e-12 long from 9.4e-4 away, passing 2e-9 from it.)
    let dist = (o - target).length();
    if v.length() < 0.1 * dist || len < 256.0 * f32::EPSILON * (o.length() + dist) {
        return false;
    }
    // v, like u1 and u2, is perpendicular to the edge: v = α u1 + β u2 with α, β clearly positive.
    let g = u1.dot(u2);
    let (x, y) = (v.dot(u1), v.dot(u2));
    let det = 1.0 - g * g;
    let (alpha, beta) = ((x - g * y) / det, (y - g * x) / det);
    let margin = 0.1 * v.length();
    alpha > margin && beta > margin
}
