//! Normal and height maps (`Material::normal_map`: Mitsuba's `normalmap` and `bumpmap`, glTF's
//! `normalTexture`): a map that tilts a plane by θ scales its direct light from overhead by
//! cos θ in every engine, a height ramp tilts it by its gradient, and
//! the two photon-mapping engines agree per pixel with a normal-mapped wall in the gallery room at
//! any thread count. (glTF's `normalTexture` is read in tests/interchange.rs.)

mod common;

use common::{assert_engines_agree, gallery_with, scratch_dir};
use glam::Vec3;
use photonwave::engine::{render, Engine};
use photonwave::formats::load_scene;
use photonwave::progress::NoProgress;
use photonwave::settings::Settings;
use std::path::Path;
use std::sync::Arc;

/// Writes an 8-bit PNG of `width` × `height` texels of `colour` kind.
fn write_png(path: &Path, width: u32, height: u32, colour: png::ColorType, data: &[u8]) {
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, width, height);
        enc.set_color(colour);
        enc.set_depth(png::BitDepth::Eight);
        enc.write_header().unwrap().write_image_data(data).unwrap();
    }
    std::fs::write(path, bytes).unwrap();
}

/// Writes a 1×1 PNG of `rgb` and returns the normal it encodes, 2·rgb/255 − 1.
fn one_texel(path: &Path, rgb: [u8; 3]) -> Vec3 {
    write_png(path, 1, 1, png::ColorType::Rgb, &rgb);
    Vec3::from_array(rgb.map(|c| f32::from(c) / 255.0)) * 2.0 - Vec3::ONE
}

const DIFFUSE: &str = "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.5\"/></bsdf>";

/// A Mitsuba scene: a square at z = 0 facing +z (x and y from −2 to 2, u and v from 0 to 1),
/// grey Lambertian (0.5), in a `normalmap` of `map` when given, under sunlight straight down; the
/// camera looks straight at its middle.
fn plane(dir: &Path, name: &str, map: Option<&str>) -> photonwave::formats::LoadedScene {
    let bsdf = match map {
        Some(file) => format!(
            "<bsdf type=\"normalmap\"><texture name=\"normalmap\" type=\"bitmap\"><string name=\"filename\" value=\"{file}\"/>\
<boolean name=\"raw\" value=\"true\"/></texture>{DIFFUSE}</bsdf>"
        ),
        None => DIFFUSE.to_string(),
    };
    plane_of(dir, name, &bsdf)
}

/// [`plane`] with the BSDF `bsdf`.
fn plane_of(dir: &Path, name: &str, bsdf: &str) -> photonwave::formats::LoadedScene {
    let xml = format!(
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" value=\"20\"/>\
<transform name=\"to_world\"><lookat origin=\"0, 0, 3\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>\
<film type=\"hdrfilm\"><integer name=\"width\" value=\"8\"/><integer name=\"height\" value=\"8\"/></film></sensor>\n\
<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"2\"/></transform>{bsdf}</shape>\n\
<emitter type=\"directional\"><vector name=\"direction\" value=\"0, 0, -1\"/><rgb name=\"irradiance\" value=\"1\"/></emitter>\n</scene>\n"
    );
    let path = dir.join(name);
    std::fs::write(&path, xml).unwrap();
    load_scene(&path).unwrap()
}

/// The 8² beauty images of `mapped` and `flat` (the same camera) by each engine, in turn.
fn beauty_in_every_engine(
    mapped: photonwave::formats::LoadedScene,
    flat: photonwave::formats::LoadedScene,
) -> Vec<(Engine, Vec<Vec3>, Vec<Vec3>)> {
    let rays = flat.camera.unwrap().prepare(8, 8).unwrap();
    let (flat, mapped) = (Arc::new(flat.scene), Arc::new(mapped.scene));
    let s = Settings { width: 8, height: 8, spp: 2, photons: 500, caustic_photons: 500, ..Settings::default() };
    [Engine::Wavefront, Engine::Reference, Engine::Path]
        .into_iter()
        .map(|engine| {
            let beauty = |scene: &Arc<photonwave::scene::Scene>| {
                render(scene, &rays, &s, engine, None, &NoProgress).unwrap().0.beauty()
            };
            (engine, beauty(&mapped), beauty(&flat))
        })
        .collect()
}

#[test]
fn a_normal_map_tilting_a_plane_scales_its_direct_light_by_the_cosine() {
    // Sunlight along the plane's normal: a Lambertian's radiance is kd/π·E·cos θ, θ between the
    // shading normal and the light. The map's one texel encodes m = 2·rgb/255 − 1 in the
    // (u, v, n) frame, so cos θ = m.z/|m|: the mapped plane is that times the flat one, per pixel,
    // in every engine (no other surface: direct light alone; f32 rounding, 1e-5).
    let d = scratch_dir("normal-map-tilt");
    for (k, rgb) in [[218u8, 128, 218], [128, 40, 230], [30, 200, 150]].into_iter().enumerate() {
        let file = format!("tilt{k}.png");
        let m = one_texel(&d.join(&file), rgb);
        let cos = m.z / m.length();
        let (flat, mapped) = (plane(&d, "flat.xml", None), plane(&d, &format!("tilt{k}.xml"), Some(&file)));
        assert!(mapped.scene.materials.iter().any(|m| m.normal_map.is_some()), "the map is read");
        for (engine, a, b) in beauty_in_every_engine(mapped, flat) {
            for (x, y) in a.iter().zip(&b) {
                assert!((y.x - 0.5 / std::f32::consts::PI).abs() < 1e-5, "{engine:?}: the flat plane is kd/π: {y}");
                assert!((*x - *y * cos).abs().max_element() < 1e-5, "{engine:?} texel {rgb:?}: {x} against {y}·{cos}");
            }
        }
    }
}

#[test]
fn a_height_map_sloping_along_u_tilts_the_plane_by_its_gradient() {
    // A 64×1 grey ramp, texel i of height i/255, under a `bumpmap` of scale 8: between texel
    // centres h rises by 64/255 per unit of u, so the tangents are dp/du = (4, 0, 8·64/255) and
    // dp/dv = (0, 4, 0) and the normal leans by cos θ = 1/√(1 + (8·64/255/4)²) = 0.894 — the
    // direct light from overhead scales by that, in every engine (f32 rounding, 1e-5; the
    // camera sees u in 0.37–0.63, far from the ramp's wrap-around cells).
    let d = scratch_dir("bump-map-ramp");
    write_png(&d.join("ramp.png"), 64, 1, png::ColorType::Grayscale, &(0..64u8).collect::<Vec<_>>());
    let bump = format!(
        "<bsdf type=\"bumpmap\"><texture type=\"bitmap\"><string name=\"filename\" value=\"ramp.png\"/>\
<boolean name=\"raw\" value=\"true\"/></texture><float name=\"scale\" value=\"8\"/>{DIFFUSE}</bsdf>"
    );
    let (flat, bumped) = (plane_of(&d, "flat.xml", DIFFUSE), plane_of(&d, "bumped.xml", &bump));
    assert!(bumped.scene.materials.iter().any(|m| m.normal_map.is_some()), "the height map is read");
    let g = 8.0 * 64.0 / 255.0 / 4.0f32;
    let cos = 1.0 / (1.0 + g * g).sqrt();
    for (engine, a, b) in beauty_in_every_engine(bumped, flat) {
        for (x, y) in a.iter().zip(&b) {
            assert!((*x - *y * cos).abs().max_element() < 1e-5, "{engine:?}: {x} against {y}·{cos}");
        }
    }
}

#[test]
fn engines_agree_with_a_normal_mapped_wall_at_any_thread_count() {
    // A 4×4 map of bumps on a panel in the gallery room, lit by its ceiling light: shading
    // normals vary across it, and camera, gather and glossy rays and photons all meet them.
    let d = scratch_dir("normal-map-engines");
    let texels: Vec<u8> =
        (0..16).flat_map(|i| [[200u8, 128, 200], [60, 128, 220], [128, 200, 200], [128, 60, 220]][i % 4]).collect();
    write_png(&d.join("bumps.png"), 4, 4, png::ColorType::Rgb, &texels);
    let panel = "<shape type=\"rectangle\"><transform name=\"to_world\"><scale x=\"0.15\" y=\"0.12\"/>\
<translate x=\"0.02\" y=\"0.28\" z=\"-0.2\"/></transform><bsdf type=\"normalmap\"><texture name=\"normalmap\" type=\"bitmap\">\
<string name=\"filename\" value=\"bumps.png\"/><boolean name=\"raw\" value=\"true\"/></texture>\
<bsdf type=\"roughplastic\"><rgb name=\"diffuse_reflectance\" value=\"0.6, 0.5, 0.4\"/></bsdf></bsdf></shape>";
    let loaded = gallery_with(&d, panel);
    assert!(loaded.scene.materials.iter().any(|m| m.normal_map.is_some()));
    assert!(!loaded.scene.warnings.iter().any(|w| w.contains("raw")), "{:?}", loaded.scene.warnings);
    assert_engines_agree(loaded);
}
