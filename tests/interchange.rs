//! Scenes from other tools: glTF 2.0 models, PLY meshes, and what the TOML scene file says of
//! meshes (transforms, built-in shapes, a material per mesh, conductors by η and k). The same
//! Cornell box as OBJ/MTL, glTF and PLY renders the same image; every feature loads with the
//! right transforms, cameras, lights and materials; bad files are errors naming file and element.

mod common;

use common::{assert_engines_agree, bundled, gallery_with, scratch_dir};
use glam::{Vec2, Vec3};
use photonwave::engine::{render, Engine};
use photonwave::formats::{load_scene, LoadedScene};
use photonwave::material::{AlphaMode, Bsdf};
use photonwave::microfacet::Alpha;
use photonwave::optics::conductor_f0;
use photonwave::progress::NoProgress;
use photonwave::scene::Light;
use photonwave::settings::Settings;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Gold's complex index: its normal-incidence reflectance red and green high, blue low.
fn is_gold(c: photonwave::optics::ComplexIor) -> bool {
    let f0 = conductor_f0(c.eta, c.k);
    f0.x > 0.9 && f0.z < 0.5
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn beauty(loaded: LoadedScene) -> Vec<Vec3> {
    let s = Settings {
        width: 24,
        height: 24,
        spp: 2,
        photons: 4000,
        caustic_photons: 1000,
        gather_rays: 4,
        threads: 2,
        ..Settings::default()
    };
    let rays = loaded.camera.unwrap().prepare(s.width, s.height).unwrap();
    render(&Arc::new(loaded.scene), &rays, &s, Engine::Wavefront, None, &NoProgress).unwrap().0.beauty()
}

/// The Cornell box as OBJ/MTL, as glTF (with its own camera) and as PLY meshes with TOML
/// materials: the readers give the same triangles in the same order, so the images are the same
/// bit for bit — stronger than "within noise", which would hide a reader that dropped a face.
#[test]
fn the_cornell_box_renders_the_same_from_obj_gltf_and_ply() {
    let obj = beauty(load_scene(&bundled("cornell-box.toml")).unwrap());
    let gltf = load_scene(&bundled("interchange/cornell-box.gltf")).unwrap();
    assert_eq!(gltf.cameras.len(), 1);
    assert!((gltf.camera.unwrap().fov_deg - 39.3).abs() < 1e-4);
    assert!(gltf.scene.warnings.is_empty(), "{:?}", gltf.scene.warnings);
    assert_eq!(beauty(gltf), obj, "glTF");
    assert_eq!(beauty(load_scene(&bundled("interchange/cornell-box-ply.toml")).unwrap()), obj, "PLY");
}

/// A glTF document of one triangle per node in `nodes` (each naming mesh 0), with `extra` merged
/// in at the top level; the buffer is a data URI.
fn gltf_doc(nodes: Value, material: Value, extra: Value) -> Value {
    let mut blob = Vec::new();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        p.iter().for_each(|x| blob.extend(x.to_le_bytes()));
    }
    for uv in [[0.0f32, 0.0], [1.0, 0.0], [0.0, 1.0]] {
        uv.iter().for_each(|x| blob.extend(x.to_le_bytes()));
    }
    use base64::Engine as _;
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&blob));
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": nodes,
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]}],
        "materials": [material],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}
        ],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
        "buffers": [{"byteLength": 60, "uri": uri}]
    });
    if let (Value::Object(d), Value::Object(e)) = (&mut doc, extra) {
        d.extend(e);
    }
    doc
}

/// Loads `doc` as a glTF file named by a scene file that adds a point light (so that models
/// without lights render).
fn load_doc(dir: &Path, doc: &Value) -> photonwave::error::Result<LoadedScene> {
    write(dir, "m.gltf", doc.to_string());
    let toml =
        "[[mesh]]\nfile = \"m.gltf\"\n[[light]]\ntype = \"point\"\nposition = [0, 0, 4]\nintensity = [1, 1, 1]\n";
    load_scene(&write(dir, "s.toml", toml))
}

/// Node transforms compose parent × child (translation, rotation, scale, matrix); the camera
/// sits on its node looking down −z; punctual lights are placed and converted from photometric
/// units (1/683 W per lm).
#[test]
fn gltf_hierarchy_cameras_and_lights() {
    let d = scratch_dir("gltf-hierarchy");
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let nodes = json!([
        {"translation": [10, 0, 0], "children": [1, 2, 3, 4, 5]},
        // Turned 90° about +z, scaled 2: (1, 0, 0) → (0, 2, 0).
        {"mesh": 0, "rotation": [0, 0, s, s], "scale": [2, 2, 2]},
        {"camera": 0, "name": "front", "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,5,1]},
        {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 3, 0]},
        {"extensions": {"KHR_lights_punctual": {"light": 1}}, "rotation": [-0.5, 0, 0, 0.8660254]},
        {"extensions": {"KHR_lights_punctual": {"light": 2}}}
    ]);
    let extra = json!({
        "extensionsUsed": ["KHR_lights_punctual"],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "intensity": 683, "color": [1, 0.5, 0]},
            {"type": "directional", "intensity": 1366},
            {"type": "spot", "intensity": 68.3, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.4}}
        ]}}
    });
    let loaded = load_doc(&d, &gltf_doc(nodes, json!({"pbrMetallicRoughness": {"metallicFactor": 0}}), extra)).unwrap();
    let (lo, hi) = loaded.scene.mesh_bounds();
    assert!((lo - Vec3::new(8.0, 0.0, 0.0)).abs().max_element() < 1e-5, "{lo}");
    assert!((hi - Vec3::new(10.0, 2.0, 0.0)).abs().max_element() < 1e-5, "{hi}");
    let (name, cam) = &loaded.cameras[0];
    assert_eq!(name, "front");
    assert_eq!(cam.eye, Vec3::new(10.0, 0.0, 5.0));
    assert!((cam.target - cam.eye - Vec3::NEG_Z).length() < 1e-6);
    assert!((cam.fov_deg - 0.5f32.to_degrees()).abs() < 1e-4);
    // The scene file's point light first, then the model's.
    let lights: Vec<&Light> = loaded.scene.lights.iter().filter(|l| !matches!(l, Light::Area { .. })).skip(1).collect();
    assert_eq!(lights.len(), 3, "{lights:?}");
    assert!(matches!(lights[0], Light::Point { position, intensity }
        if (*position - Vec3::new(10.0, 3.0, 0.0)).length() < 1e-6 && (*intensity - Vec3::new(1.0, 0.5, 0.0)).length() < 1e-6));
    // −60° about x turns −z toward −y: (0, −sin 60°, −cos 60°).
    assert!(matches!(lights[1], Light::Directional { direction, irradiance }
        if (*direction - Vec3::new(0.0, -0.8660254, -0.5)).length() < 1e-5 && (*irradiance - Vec3::splat(2.0)).length() < 1e-5));
    assert!(matches!(lights[2], Light::Spot { cos_inner, cos_outer, intensity, .. }
        if (*cos_inner - 0.2f32.cos()).abs() < 1e-6 && (*cos_outer - 0.4f32.cos()).abs() < 1e-6 && (intensity.x - 0.1).abs() < 1e-6));
}

/// The metallic–roughness mapping (docs/src/formats.md): each kind of material lands on the BSDF
/// the mapping names, emission is factor × strength, and a texture transform moves the texture
/// coordinates.
#[test]
fn gltf_materials_map_onto_the_bsdfs_they_name() {
    let d = scratch_dir("gltf-materials");
    let node = json!([{"mesh": 0}]);
    let extra = json!({"extensionsUsed": ["KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_emissive_strength", "KHR_materials_volume"]});
    let cases = [
        (
            json!({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.4, 0.3, 1], "metallicFactor": 0, "roughnessFactor": 1}}),
            Bsdf::Lambert { kd: Vec3::new(0.5, 0.4, 0.3) },
        ),
        (
            json!({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.4, 0.3, 1], "metallicFactor": 0, "roughnessFactor": 0.5}}),
            Bsdf::rough_plastic(Vec3::new(0.5, 0.4, 0.3), 1.5, Alpha::ggx(0.25)),
        ),
        (
            json!({"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.7, 0.3, 1], "metallicFactor": 1, "roughnessFactor": 0}}),
            Bsdf::Mirror { ks: Vec3::new(0.9, 0.7, 0.3), eta_k: None },
        ),
        (
            json!({"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.7, 0.3, 1], "metallicFactor": 1, "roughnessFactor": 0.4}}),
            Bsdf::RoughConductor { ks: Vec3::new(0.9, 0.7, 0.3), alpha: Alpha::ggx(0.16000001), eta_k: None },
        ),
        (
            json!({"pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0},
                "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}, "KHR_materials_ior": {"ior": 1.33},
                    "KHR_materials_volume": {"thicknessFactor": 0.2}}}),
            Bsdf::Glass { ior: 1.33, tint: photonwave::material::Tint::CLEAR },
        ),
        // Without a volume the spec makes it thin-walled: a sheet that does not bend light.
        (
            json!({"pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0},
                "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}, "KHR_materials_ior": {"ior": 1.33}}}),
            // Clear: the scene lets rays pass it in traversal (`Bsdf::thin_pass`).
            Bsdf::ThinGlass { ior: 1.33, tint: photonwave::material::Tint::CLEAR, passed: true },
        ),
    ];
    for (material, want) in cases {
        let loaded = load_doc(&d, &gltf_doc(node.clone(), material.clone(), extra.clone())).unwrap();
        assert_eq!(loaded.scene.materials[loaded.scene.material[0] as usize].bsdf, want, "{material}");
    }
    // A solid's volume attenuation: colour c left after distance d, σ_a = −ln(c)/d per channel
    // (a colour of 1 absorbs nothing); a thin-walled surface has no inside to absorb in.
    let tinted = |thickness: f32| {
        json!({"pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0},
            "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1},
                "KHR_materials_volume": {"thicknessFactor": thickness, "attenuationDistance": 2.0, "attenuationColor": [0.5, 1.0, 0.25]}}})
    };
    let loaded = load_doc(&d, &gltf_doc(node.clone(), tinted(0.1), extra.clone())).unwrap();
    let m = &loaded.scene.materials[loaded.scene.material[0] as usize];
    let want = Vec3::new(2f32.ln() / 2.0, 0.0, 4f32.ln() / 2.0);
    assert!(
        m.bsdf == Bsdf::Glass { ior: 1.5, tint: photonwave::material::Tint::CLEAR }
            && (m.interior - want).abs().max_element() < 1e-6,
        "{m:?}"
    );
    let loaded = load_doc(&d, &gltf_doc(node.clone(), tinted(0.0), extra.clone())).unwrap();
    assert_eq!(loaded.scene.materials[loaded.scene.material[0] as usize].interior, Vec3::ZERO);
    let glowing = json!({"emissiveFactor": [1, 0.5, 0.25], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 8}}});
    let loaded = load_doc(&d, &gltf_doc(node.clone(), glowing, extra.clone())).unwrap();
    assert_eq!(loaded.scene.materials[loaded.scene.material[0] as usize].emission, Vec3::new(8.0, 4.0, 2.0));
    assert!(loaded.scene.lights.iter().any(|l| matches!(l, Light::Area { .. })));
    // A 2×2 base-colour texture, embedded as a PNG data URI, offset by ½ in u: the
    // coordinates move (and v is flipped: glTF's runs down the image).
    let mut png_bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut png_bytes, 2, 2);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.write_header().unwrap().write_image_data(&[255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255]).unwrap();
    }
    use base64::Engine as _;
    let image = format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(&png_bytes));
    let textured = json!({"pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 1, "baseColorTexture": {
        "index": 0, "extensions": {"KHR_texture_transform": {"offset": [0.5, 0], "scale": [2, 1]}}}}});
    let extra =
        json!({"extensionsUsed": ["KHR_texture_transform"], "textures": [{"source": 0}], "images": [{"uri": image}]});
    let loaded = load_doc(&d, &gltf_doc(node.clone(), textured, extra.clone())).unwrap();
    let m = &loaded.scene.materials[loaded.scene.material[0] as usize];
    assert!(m.maps.kd.is_some());
    // The same image as a normal texture: read as data, its scale kept, glTF's handedness.
    let bumpy = json!({"normalTexture": {"index": 0, "scale": 0.5}, "pbrMetallicRoughness": {"metallicFactor": 0}});
    let bumped = load_doc(&d, &gltf_doc(node, bumpy, extra.clone())).unwrap();
    let map = bumped.scene.materials[bumped.scene.material[0] as usize].normal_map.clone().expect("a normal map");
    assert!(map.scale == 0.5 && map.handed && map.texture.texels[0] == Vec3::X, "{map:?}");
    // alphaMode: MASK cuts out below alphaCutoff, BLEND reads alpha as coverage; α is the base
    // colour factor's alpha times the texture's alpha channel (1 in this RGB image, so no
    // texture is kept); OPAQUE ignores alpha.
    let modes = [
        (json!({"alphaMode": "MASK", "alphaCutoff": 0.3}), Some(AlphaMode::Cutoff(0.3))),
        (json!({"alphaMode": "MASK"}), Some(AlphaMode::Cutoff(0.5))),
        (json!({"alphaMode": "BLEND"}), Some(AlphaMode::Coverage)),
        (json!({}), None),
    ];
    for (mode, want) in modes {
        let mut m = json!({"pbrMetallicRoughness": {"metallicFactor": 0, "baseColorFactor": [1, 1, 1, 0.2],
            "baseColorTexture": {"index": 0}}});
        if let (Value::Object(m), Value::Object(mode)) = (&mut m, mode) {
            m.extend(mode);
        }
        let loaded = load_doc(&d, &gltf_doc(json!([{"mesh": 0}]), m, extra.clone())).unwrap();
        let o = loaded.scene.materials[loaded.scene.material[0] as usize].opacity.clone();
        assert_eq!(o.as_ref().map(|o| o.mode), want);
        assert!(o.is_none_or(|o| o.factor == 0.2 && o.texture.is_none()));
    }
    // Corner (1, 0) in glTF coordinates: scaled to (2, 0), offset to (2.5, 0), v flipped to 1.
    let uvs: Vec<Vec2> = loaded.scene.uv[0].to_vec();
    assert!(uvs.iter().any(|uv| (*uv - Vec2::new(2.5, 1.0)).length() < 1e-6), "{uvs:?}");
}

/// What is read but not rendered is warned of by name; an unknown required extension, a missing
/// buffer, a bad accessor index, a stride shorter than an element, an index past the vertices and
/// a cut GLB are errors naming the file and the element.
#[test]
fn gltf_bad_files_are_errors_naming_the_element() {
    let d = scratch_dir("gltf-bad");
    let node = json!([{"mesh": 0}]);
    let lambert = json!({"pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 1}});
    let images = json!({"extensionsUsed": ["KHR_materials_clearcoat"], "textures": [{"source": 0}],
                        "images": [{"uri": "data:image/png;base64,"}]});
    // What is not rendered is warned of; an empty image is an error naming what reads it, a
    // normal texture as a base colour.
    let occluded = json!({"occlusionTexture": {"index": 0}, "pbrMetallicRoughness": {"metallicFactor": 0}});
    let loaded = load_doc(&d, &gltf_doc(node.clone(), occluded, images.clone())).unwrap();
    let w = loaded.scene.warnings.join("\n");
    assert!(w.contains("KHR_materials_clearcoat") && w.contains("occlusion texture"), "{w}");
    let bumpy = json!({"normalTexture": {"index": 0}, "pbrMetallicRoughness": {"metallicFactor": 0}});
    let e = load_doc(&d, &gltf_doc(node.clone(), bumpy, images.clone())).err().unwrap().to_string();
    assert!(e.contains("the normal texture of material"), "{e}");
    let coloured = json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}});
    let e = load_doc(&d, &gltf_doc(node.clone(), coloured, images)).err().unwrap().to_string();
    assert!(e.contains("m.gltf") && e.contains("image 0"), "{e}");

    let mut doc =
        gltf_doc(node.clone(), lambert.clone(), json!({"extensionsRequired": ["KHR_draco_mesh_compression"]}));
    let e = load_doc(&d, &doc).err().unwrap().to_string();
    assert!(e.contains("m.gltf") && e.contains("KHR_draco_mesh_compression"), "{e}");

    doc = gltf_doc(node.clone(), lambert.clone(), json!({}));
    doc["buffers"][0]["uri"] = json!("missing.bin");
    let e = load_doc(&d, &doc).err().unwrap().to_string();
    assert!(e.contains("m.gltf") && e.contains("buffer 0") && e.contains("missing.bin"), "{e}");

    doc = gltf_doc(node.clone(), lambert.clone(), json!({}));
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(7);
    let e = load_doc(&d, &doc).err().unwrap().to_string();
    assert!(e.contains("m.gltf") && e.contains("POSITION"), "{e}");

    // glTF 1.0 is another schema: refused by name, whether or not its fields fit 2.0's (issue
    // 53: a 2.0 layout labelled "1.0" rendered silently).
    for (asset, want) in [
        (json!({"version": "1.0"}), "asset.version is \"1.0\""),
        (json!({"version": "2.0", "minVersion": "3.0"}), "asset.minVersion is \"3.0\""),
    ] {
        doc = gltf_doc(node.clone(), lambert.clone(), json!({}));
        doc["asset"] = asset;
        let e = load_doc(&d, &doc).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("m.gltf") && e.contains(want) && e.contains("glTF 2.0"), "{want}: {e}");
    }
    let v1 = json!({"asset": {"version": "1.0"}, "meshes": {"box": {"primitives": []}}, "scene": "main"});
    let e = load_doc(&d, &v1).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.contains("asset.version is \"1.0\""), "{e}");

    doc = gltf_doc(node.clone(), lambert.clone(), json!({}));
    doc["bufferViews"][0]["byteStride"] = json!(8);
    let e = load_doc(&d, &doc).err().unwrap().to_string();
    assert!(e.contains("accessor 0") && e.contains("stride 8"), "{e}");

    doc = gltf_doc(node.clone(), lambert.clone(), json!({}));
    doc["accessors"][0]["count"] = json!(4);
    let e = load_doc(&d, &doc).err().unwrap().to_string();
    assert!(e.contains("accessor 0") && e.contains("past the end"), "{e}");

    // What the crate's document model would unwrap or loop on (found in review): an image
    // without a source, a camera without its projection, a node reached twice.
    for (edit, want) in [
        (json!({"images": [{}], "textures": [{"source": 0}]}), "images[0]"),
        (
            json!({"cameras": [{"type": "perspective", "orthographic": {"xmag": 1, "ymag": 1, "zfar": 2, "znear": 1}}]}),
            "cameras[0]",
        ),
        (json!({"nodes": [{"children": [1, 1]}, {"mesh": 0}]}), "reached twice"),
    ] {
        let e = load_doc(&d, &gltf_doc(node.clone(), lambert.clone(), edit))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains("m.gltf") && e.contains(want), "{want}: {e}");
    }

    let e = load_scene(&write(&d, "cut.glb", b"glTF\x02\0\0\0\xff\0\0\0")).err().unwrap().to_string();
    assert!(e.contains("cut.glb") && e.contains("GLB"), "{e}");
}

/// PLY: ASCII with normals, texture coordinates and a quad (fanned); big-endian binary; errors
/// with the header line, the element and index, or the ASCII line.
#[test]
fn ply_meshes_in_every_encoding() {
    let d = scratch_dir("ply");
    let header = |format: &str, extra: &str| {
        format!("ply\nformat {format} 1.0\ncomment a quad\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n{extra}element face 1\nproperty list uchar int vertex_indices\nend_header\n")
    };
    let ascii = header(
        "ascii",
        "property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n",
    ) + "0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n0 1 0 0 0 1 0 1\n4 0 1 2 3\n";
    // The columns themselves, as read: texture coordinates and normals that differ per vertex
    // (normals all equal to the face's would not show a dropped column).
    let columns = header(
        "ascii",
        "property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n",
    )
        + "0 0 0 0 0 1 0.25 0.5\n1 0 0 0 0.6 0.8 0.75 0\n1 1 0 0.6 0 0.8 1 1\n0 1 0 0 0 2 0 0.125\n4 0 1 2 3\n";
    let mesh = photonwave::formats::ply::load_ply(&write(&d, "c.ply", &columns), 0, &mut vec![], &mut vec![]).unwrap();
    let uv = [[0.25, 0.5], [0.75, 0.0], [1.0, 1.0], [0.0, 0.125]].map(Vec2::from_array);
    assert_eq!(mesh.texcoords, uv);
    let normals = [[0.0, 0.0, 1.0], [0.0, 0.6, 0.8], [0.6, 0.0, 0.8], [0.0, 0.0, 2.0]].map(Vec3::from_array);
    assert_eq!(mesh.normals, normals);
    assert_eq!(mesh.triangles, [[0, 1, 2], [0, 2, 3]]);
    // A second vertex element without the columns the first had: its vertices get zeros, not
    // their x as both u and v (found in review, issue 53).
    let lacking = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n\
property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n\
element vertex 1\nproperty float x\nproperty float y\nproperty float z\n\
element face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0 0 0 1 0.5 0.5\n1 0 0 0 0 1 0.25 0.25\n0.75 1 0\n3 0 1 2\n";
    let mesh = photonwave::formats::ply::load_ply(&write(&d, "l.ply", lacking), 0, &mut vec![], &mut vec![]).unwrap();
    assert_eq!(mesh.texcoords, [Vec2::splat(0.5), Vec2::splat(0.25), Vec2::ZERO]);
    assert_eq!(mesh.normals, [Vec3::Z, Vec3::Z, Vec3::ZERO]);
    let toml = "[[mesh]]\nfile = \"q.ply\"\nmaterial = \"grey\"\n[materials.grey]\ntype = \"lambert\"\nkd = [0.5, 0.5, 0.5]\n[[light]]\ntype = \"point\"\nposition = [0, 0, 1]\nintensity = [1, 1, 1]\n";
    write(&d, "q.ply", &ascii);
    let s = write(&d, "s.toml", toml);
    let loaded = load_scene(&s).unwrap();
    assert_eq!(loaded.scene.p0.len(), 2);
    assert!(loaded.scene.uv.is_empty() || loaded.scene.uv.len() == 2);
    assert!(loaded.scene.warnings.is_empty(), "{:?}", loaded.scene.warnings);
    let mut big = header("binary_big_endian", "").into_bytes();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]] {
        p.iter().for_each(|x| big.extend(x.to_be_bytes()));
    }
    big.push(4);
    [0i32, 1, 2, 3].iter().for_each(|i| big.extend(i.to_be_bytes()));
    write(&d, "q.ply", &big);
    let (lo, hi) = load_scene(&s).unwrap().scene.mesh_bounds();
    assert_eq!((lo, hi), (Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
    // Two vertex elements, only the second with normals: the column is padded (found in review).
    let split = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n\
element vertex 2\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n";
    write(&d, "q.ply", split);
    assert_eq!(load_scene(&s).unwrap().scene.p0.len(), 1);
    for (bad, want) in [
        (ascii.replace("property float u\n", "property float128 u\n"), "q.ply:11:"),
        (ascii.replace("4 0 1 2 3", "4 0 1 2 9"), "vertex index 9"),
        (ascii.replace("0 1 0 0 0 1 0 1\n4 0 1 2 3\n", "0 1 0 0 0 1 0 1\n4 0 1"), "ends early"),
        (ascii.replace("1 1 0 0 0 1 1 1", "1 nan 0 0 0 1 1 1"), "not finite"),
        (ascii.replace("1 1 0 0 0 1 1 1", "1 x 0 0 0 1 1 1"), "q.ply:18:"),
        (ascii.replace("end_header\n", ""), "end_header"),
    ] {
        write(&d, "q.ply", &bad);
        let e = load_scene(&s).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("q.ply") && e.contains(want), "{want}: {e}");
    }
}

/// `[[mesh]]` transforms: scale, rotate and translate equal the matrix they make; a shape takes a
/// material; a conductor is given by η and k or by name; mistakes are errors naming the field.
#[test]
fn toml_transforms_shapes_and_conductors() {
    let d = scratch_dir("toml-meshes");
    let load = |body: &str| {
        load_scene(&write(
            &d,
            "s.toml",
            format!("{body}\n[[light]]\ntype = \"point\"\nposition = [0, 5, 0]\nintensity = [1, 1, 1]\n"),
        ))
    };
    let gold = "[materials.gold]\ntype = \"conductor\"\nmetal = \"Au\"\nroughness = 0.3\n";
    let a = load(&format!("[[mesh]]\nshape = \"cube\"\nmaterial = \"gold\"\nscale = [1, 2, 3]\nrotate = [0, 0, 1, 90]\ntranslate = [5, 0, 0]\n{gold}")).unwrap();
    let b = load(&format!("[[mesh]]\nshape = \"cube\"\nmaterial = \"gold\"\nmatrix = [0, -2, 0, 5,  1, 0, 0, 0,  0, 0, 3, 0,  0, 0, 0, 1]\n{gold}")).unwrap();
    let (lo, hi) = a.scene.mesh_bounds();
    assert!(
        (lo - Vec3::new(3.0, -1.0, -3.0)).abs().max_element() < 1e-5
            && (hi - Vec3::new(7.0, 1.0, 3.0)).abs().max_element() < 1e-5,
        "{lo} {hi}"
    );
    // The same triangles (the BVH may order them differently by a rounding).
    let corners = |s: &photonwave::scene::Scene| {
        let mut v: Vec<[i64; 9]> = (0..s.p0.len())
            .map(|i| {
                let c = [s.p0[i], s.p1[i], s.p2[i]].map(|p| (p * 1e4).round().as_i64vec3().to_array());
                std::array::from_fn(|k| c[k / 3][k % 3])
            })
            .collect();
        v.sort();
        v
    };
    assert_eq!(corners(&a.scene), corners(&b.scene));
    let m = &a.scene.materials[a.scene.material[0] as usize];
    assert!(
        matches!(m.bsdf, Bsdf::RoughConductor { ks, alpha, eta_k: Some(c) } if ks == Vec3::ONE && is_gold(c) && alpha == Alpha::ggx(0.09)),
        "{m:?}"
    );
    let c = load("[[mesh]]\nshape = \"sphere\"\nmaterial = \"m\"\n[materials.m]\ntype = \"conductor\"\neta = [1.5, 1.5, 1.5]\nk = [0, 0, 0]\n").unwrap();
    assert!(
        matches!(c.scene.materials[c.scene.material[0] as usize].bsdf, Bsdf::Mirror { eta_k: Some(c), .. } if (conductor_f0(c.eta, c.k).x - 0.04).abs() < 1e-6)
    );
    // A mirroring matrix keeps the front face in front: the rectangle still faces where its
    // normal is sent.
    let r = load("[[mesh]]\nshape = \"rectangle\"\nmaterial = \"m\"\nmatrix = [1, 0, 0, 0,  0, 1, 0, 0,  0, 0, -1, 0,  0, 0, 0, 1]\n[materials.m]\ntype = \"lambert\"\nkd = [0.5, 0.5, 0.5]\n").unwrap();
    assert!(r.scene.ng.iter().all(|n| (*n - Vec3::NEG_Z).length() < 1e-6), "{:?}", r.scene.ng);
    let grey = load("[[mesh]]\nshape = \"disk\"\n").unwrap();
    assert!(grey.scene.warnings.iter().any(|w| w.contains("mesh[0] (a disk) names no `material`")));
    for (body, want) in [
        ("[[mesh]]\nshape = \"torus\"\n", "unknown shape `torus`"),
        ("[[mesh]]\nshape = \"cube\"\nmatrix = [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]\nscale = 2\n", "mesh[0].matrix"),
        ("[[mesh]]\nshape = \"cube\"\nscale = [1, 0, 1]\n", "mesh[0].scale"),
        ("[[mesh]]\nshape = \"cube\"\nmaterial = \"nope\"\n", "no [materials.nope]"),
        (
            "[[mesh]]\nshape = \"cube\"\nmaterial = \"m\"\n[materials.m]\ntype = \"conductor\"\nmetal = \"Xx\"\n",
            "unknown metal `Xx`",
        ),
        ("[[mesh]]\nfile = \"a.stl\"\n", "mesh[0].file"),
        ("[[mesh]]\nshape = \"cube\"\nfile = \"a.obj\"\n", "not both"),
    ] {
        let e = load(body).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains(want), "{want}: {e}");
    }
}

/// The Mitsuba 0.6 Cornell box over the PLY meshes: the same image as the OBJ box, and its
/// integrator and sampler are warned of with their lines.
#[test]
fn the_mitsuba_cornell_box_renders_the_same() {
    let obj = beauty(load_scene(&bundled("cornell-box.toml")).unwrap());
    let xml = load_scene(&bundled("interchange/cornell-box.xml")).unwrap();
    assert_eq!((xml.settings.width, xml.settings.height), (320, 320));
    let w = xml.scene.warnings.join("\n");
    assert!(w.contains("cornell-box.xml:5: integrator `path`") && w.contains("cornell-box.xml:12: the sampler"), "{w}");
    assert_eq!(beauty(xml), obj, "Mitsuba");
}

/// A Mitsuba 3 scene (snake_case names) of built-in shapes with transforms, `$param` defaults,
/// named metals and indices, and every emitter kind read; what is not read is warned of with its
/// line, and mistakes are errors naming file and line.
#[test]
fn mitsuba_shapes_materials_emitters_and_errors() {
    let d = scratch_dir("mitsuba");
    let scene = |body: &str| {
        format!("<scene version=\"3.0.0\">\n<default name=\"r\" value=\"0.25\"/>\n<sensor type=\"perspective\">\n\
<float name=\"fov\" value=\"60\"/>\n<transform name=\"to_world\"><lookat origin=\"0, 0, 5\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>\n\
<film type=\"hdrfilm\"><integer name=\"width\" value=\"40\"/><integer name=\"height\" value=\"20\"/></film>\n</sensor>\n{body}</scene>\n")
    };
    let body = "<bsdf type=\"roughconductor\" id=\"gold\"><string name=\"material\" value=\"Au\"/><float name=\"alpha\" value=\"$r\"/>\
<string name=\"distribution\" value=\"ggx\"/></bsdf>\n\
<shape type=\"sphere\"><point name=\"center\" x=\"1\" y=\"2\" z=\"3\"/><float name=\"radius\" value=\"0.5\"/><ref id=\"gold\"/></shape>\n\
<shape type=\"rectangle\"><transform name=\"to_world\"><scale x=\"2\" y=\"3\"/><rotate x=\"1\" angle=\"-90\"/><translate y=\"-1\"/></transform>\
<bsdf type=\"twosided\"><bsdf type=\"roughplastic\"><rgb name=\"diffuse_reflectance\" value=\"0.2, 0.3, 0.4\"/><boolean name=\"nonlinear\" value=\"true\"/><boolean name=\"sample_visible\" value=\"false\"/></bsdf></bsdf></shape>\n\
<shape type=\"cube\"><bsdf type=\"dielectric\"><string name=\"int_ior\" value=\"water\"/></bsdf>\
<emitter type=\"area\"><rgb name=\"radiance\" value=\"1, 2, 3\"/></emitter></shape>\n\
<shape type=\"disk\"><bsdf type=\"hanrahan_krueger\"/></shape>\n\
<emitter type=\"point\"><point name=\"position\" value=\"0, 4, 0\"/><rgb name=\"intensity\" value=\"5\"/></emitter>\n\
<emitter type=\"spot\"><transform name=\"to_world\"><lookat origin=\"0, 4, 0\" target=\"0, 0, 0\" up=\"0, 0, 1\"/></transform>\
<float name=\"cutoff_angle\" value=\"30\"/></emitter>\n\
<emitter type=\"directional\"><vector name=\"direction\" value=\"0, -1, 0\"/><rgb name=\"irradiance\" value=\"2\"/></emitter>\n\
<emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.1\"/></emitter>\n\
<medium type=\"homogeneous\"/>\n";
    let loaded = load_scene(&write(&d, "s.xml", scene(body))).unwrap();
    assert_eq!((loaded.settings.width, loaded.settings.height), (40, 20));
    // fov_axis x: a 60° horizontal field of a 2:1 image is 2·atan(tan 30° / 2) vertically.
    let cam = loaded.camera.unwrap();
    assert!((cam.fov_deg - 2.0 * (30f32.to_radians().tan() / 2.0).atan().to_degrees()).abs() < 1e-4);
    assert_eq!(cam.eye, Vec3::new(0.0, 0.0, 5.0));
    let s = &loaded.scene;
    let kinds: Vec<String> = s.materials.iter().map(|m| format!("{:?}", m.bsdf)).collect();
    assert!(
        s.materials.iter().any(
            |m| matches!(m.bsdf, Bsdf::RoughConductor { alpha, eta_k: Some(c), .. } if is_gold(c) && alpha == Alpha::ggx(0.25))
        ),
        "{kinds:?}"
    );
    assert!(
        s.materials.iter().any(|m| m.bsdf
            == Bsdf::rough_plastic(Vec3::new(0.2, 0.3, 0.4), 1.49 / 1.000277, Alpha::beckmann(0.1))
                .with_nonlinear(true)),
        "{kinds:?}"
    );
    assert!(
        s.materials
            .iter()
            .any(|m| m.bsdf == Bsdf::Glass { ior: 1.333 / 1.000277, tint: photonwave::material::Tint::CLEAR }
                && m.emission == Vec3::new(1.0, 2.0, 3.0)),
        "{kinds:?}"
    );
    // The sphere: centre (1, 2, 3), radius 0.5. The rectangle: 4 × 6, turned flat at y = −1
    // (x in [−2, 2], z in [−3, 3]).
    let (lo, hi) = s.mesh_bounds();
    assert!((hi - Vec3::new(2.0, 2.5, 3.5)).abs().max_element() < 1e-4, "{hi}");
    assert!((lo - Vec3::new(-2.0, -1.0, -3.0)).abs().max_element() < 1e-4, "{lo}");
    let delta: Vec<&Light> =
        s.lights.iter().filter(|l| !matches!(l, Light::Area { .. } | Light::Environment)).collect();
    assert!(
        matches!(delta[0], Light::Point { position, intensity } if *position == Vec3::new(0.0, 4.0, 0.0) && *intensity == Vec3::splat(5.0))
    );
    assert!(
        matches!(delta[1], Light::Spot { direction, cos_outer, .. } if (*direction + Vec3::Y).length() < 1e-6 && (*cos_outer - 30f32.to_radians().cos()).abs() < 1e-6)
    );
    assert!(matches!(delta[2], Light::Directional { irradiance, .. } if *irradiance == Vec3::splat(2.0)));
    assert!(s.environment.is_some());
    let w = s.warnings.join("\n");
    // `nonlinear` is read (the base's bounces tint by kd); whether Mitsuba samples visible
    // normals is not (photonwave always does).
    assert!(!w.contains("`nonlinear`"), "{w}");
    assert!(w.contains("s.xml:10: `sample_visible` of <bsdf type=\"roughplastic\"> is not read"), "{w}");
    assert!(
        w.contains("s.xml:12: bsdf `hanrahan_krueger` is not read")
            && w.contains("s.xml:17: this <medium> is no shape's interior"),
        "{w}"
    );
    for (body, want) in [
        ("<shape type=\"cube\"><bsdf type=\"conductor\"><string name=\"material\" value=\"Unobtainium\"/></bsdf></shape>\n", "s.xml:8: metal `Unobtainium`"),
        ("<shape type=\"cube\"><ref id=\"nothing\"/></shape>\n", "names no element"),
        ("<shape type=\"cube\"><bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"$nope\"/></bsdf></shape>\n", "`$nope` has no value"),
        ("<shape type=\"ply\"><string name=\"filename\" value=\"missing.ply\"/></shape>\n", "missing.ply"),
        ("<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"0\"/></transform></shape>\n", "s.xml:8"),
        ("<shape type=\"cube\">\n", "XML"),
        // Found in review: a wrapper that names itself, a negative colour.
        ("<bsdf type=\"twosided\" id=\"w\"><ref id=\"w\"/></bsdf><shape type=\"cube\"><ref id=\"w\"/></shape>\n", "nest more than 16"),
        ("<shape type=\"cube\"><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"-1\"/></bsdf></shape>\n", "not negative"),
        ("<shape type=\"cube\"><bsdf type=\"roughconductor\"><string name=\"distribution\" value=\"gxx\"/></bsdf></shape>\n", "s.xml:8: roughconductor: unknown microfacet distribution `gxx`"),
    ] {
        let e = load_scene(&write(&d, "s.xml", scene(body))).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains(want), "{want}: {e}");
    }
    // A film the settings would refuse is refused at its own line, naming the file (issue 53:
    // 4 000 000 000² was "setting `width`: must be between 1 and 16384", naming neither).
    for (film, want) in [
        ("<integer name=\"width\" value=\"4000000000\"/>", "s.xml:6: the film's `width` is 4000000000"),
        ("<integer name=\"height\" value=\"0\"/>", "s.xml:6: the film's `height` is 0"),
        ("<float name=\"width\" value=\"12.5\"/>", "s.xml:6: the film's `width` is 12.5"),
    ] {
        let xml =
            scene("").replace("<integer name=\"width\" value=\"40\"/><integer name=\"height\" value=\"20\"/>", film);
        let e = load_scene(&write(&d, "s.xml", xml)).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains(want) && e.contains("16384"), "{want}: {e}");
    }
}

/// The Mitsuba paths the first test leaves out (issue 53): every `fov_axis`, `phong`, the
/// Beckmann default and anisotropic `alpha_u`/`alpha_v` (each rendered as GGX of the mean α and
/// warned of), `bitmap` and `checkerboard` textures, and the `envmap` emitter's quarter turn:
/// Mitsuba's lat-long u is atan2(x, −z)/2π, so the texel it shows at direction (sin φ, 0, −cos φ)
/// is column φ/2π of its file; photonwave must return that texel there.
#[test]
fn mitsuba_textures_envmaps_phong_and_every_fov_axis() {
    let d = scratch_dir("mitsuba-more");
    let png = |name: &str, w: u32, h: u32, rgb: &[u8]| {
        let mut bytes = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut bytes, w, h);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            enc.write_header().unwrap().write_image_data(rgb).unwrap();
        }
        write(&d, name, bytes);
    };
    // An 8 × 4 sky: column c has red 30·c, green 200 and blue 0 in every row.
    let sky: Vec<u8> = (0..4).flat_map(|_| (0..8u8).flat_map(|c| [30 * c, 200, 0])).collect();
    png("sky.png", 8, 4, &sky);
    png("wood.png", 2, 1, &[255, 0, 0, 0, 0, 255]);
    let scene = |axis: &str, body: &str| {
        format!(
            "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><string name=\"fov_axis\" value=\"{axis}\"/>\
<float name=\"fov\" value=\"50\"/><transform name=\"to_world\"><lookat origin=\"0, 0, 5\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>\
<film type=\"hdrfilm\"><integer name=\"width\" value=\"40\"/><integer name=\"height\" value=\"20\"/></film></sensor>\n{body}</scene>\n"
        )
    };
    // Every fov_axis of a 40 × 20 film: the vertical half-angle's tangent.
    let t = 25f32.to_radians().tan();
    for (axis, want) in [
        ("x", t * 0.5),
        ("y", t),
        ("diagonal", t * 20.0 / (40f32 * 40.0 + 20.0 * 20.0).sqrt()),
        ("smaller", t),
        ("larger", t * 0.5),
    ] {
        let loaded =
            load_scene(&write(&d, "a.xml", scene(axis, "<shape type=\"cube\"/><emitter type=\"constant\"/>\n")))
                .unwrap();
        let fov = loaded.camera.unwrap().fov_deg;
        assert!((fov - 2.0 * want.atan().to_degrees()).abs() < 1e-4, "fov_axis {axis}: {fov}°");
    }
    let body = "<shape type=\"cube\"><bsdf type=\"phong\"><rgb name=\"diffuse_reflectance\" value=\"0.6\"/>\
<rgb name=\"specular_reflectance\" value=\"0.8\"/><float name=\"exponent\" value=\"40\"/></bsdf></shape>\n\
<shape type=\"sphere\"><bsdf type=\"roughconductor\"><string name=\"material\" value=\"Ag\"/>\
<float name=\"alpha_u\" value=\"0.1\"/><float name=\"alpha_v\" value=\"0.3\"/></bsdf></shape>\n\
<shape type=\"disk\"><bsdf type=\"diffuse\"><texture type=\"bitmap\" name=\"reflectance\">\
<string name=\"filename\" value=\"wood.png\"/><float name=\"uvscale\" value=\"2\"/></texture></bsdf></shape>\n\
<shape type=\"rectangle\"><bsdf type=\"diffuse\"><texture type=\"checkerboard\" name=\"reflectance\">\
<rgb name=\"color0\" value=\"0.1, 0.2, 0.3\"/><rgb name=\"color1\" value=\"0.7\"/></texture></bsdf></shape>\n\
<emitter type=\"envmap\"><string name=\"filename\" value=\"sky.png\"/><float name=\"scale\" value=\"2\"/></emitter>\n";
    let loaded = load_scene(&write(&d, "b.xml", scene("x", body))).unwrap();
    let s = &loaded.scene;
    let kinds: Vec<String> = s.materials.iter().map(|m| format!("{:?}", m.bsdf)).collect();
    // Phong: kd + ks = 1.4 > 1, both scaled by 1/1.4 (energy), exponent as written.
    assert!(
        s.materials.iter().any(|m| matches!(m.bsdf, Bsdf::Glossy { kd, ks, exponent }
            if (kd - Vec3::splat(0.6 / 1.4)).abs().max_element() < 1e-6
                && (ks - Vec3::splat(0.8 / 1.4)).abs().max_element() < 1e-6 && exponent == 40.0)),
        "{kinds:?}"
    );
    // Anisotropic Beckmann (the default distribution): Beckmann of the mean α, 0.2, warned of.
    assert!(s
        .materials
        .iter()
        .any(|m| matches!(m.bsdf, Bsdf::RoughConductor { alpha, .. } if alpha == Alpha::beckmann(0.2))));
    let w = s.warnings.join("\n");
    assert!(w.contains("anisotropic roughness (0.1, 0.3)") && !w.contains("distribution"), "{w}");
    // The bitmap: sRGB decoded, its uvscale kept.
    let wood = s.materials.iter().find_map(|m| m.maps.kd.as_ref().filter(|t| t.width == 2)).expect("the bitmap");
    assert_eq!((wood.texels[0], wood.texels[1]), (Vec3::X, Vec3::Z));
    // The checkerboard: color0 in the first quarter, color1 beside it (linear colours).
    let board = s.materials.iter().find_map(|m| m.maps.kd.as_ref().filter(|t| t.width == 256)).expect("the board");
    assert_eq!((board.texels[0], board.texels[200]), (Vec3::new(0.1, 0.2, 0.3), Vec3::splat(0.7)));
    assert_eq!(board.texels[200 * 256], Vec3::splat(0.7));
    // The envmap: at azimuth φ from −z toward +x, Mitsuba shows column φ/2π of its file.
    let env = s.environment.as_ref().expect("the envmap");
    // An envmap is radiance: its 8-bit texels are read as linear values.
    let linear = |b: u8| f32::from(b) / 255.0;
    for column in 0..8u8 {
        let phi = (f32::from(column) + 0.5) / 8.0 * std::f32::consts::TAU;
        let up = Vec3::new(phi.sin(), 0.5, -phi.cos()).normalize();
        let want = 2.0 * Vec3::new(linear(30 * column), linear(200), 0.0);
        let got = env.radiance(up);
        assert!((got - want).abs().max_element() < 1e-5, "column {column}: {got} against {want}");
    }
}

/// A Mitsuba `thindielectric` pane between the camera and a black-backed emitter (Le = 1): every
/// camera ray passes straight through with probability 1 − R′(θ), R′ the slab's reflectance
/// 2R/(1 + R), and what it reflects leaves the scene. So each engine's image mean is the mean
/// over pixels of 1 − R′ (≈ 0.923 at η = 1.5 near normal incidence), a solid glass interface's
/// would be (1 − R)/η² ≈ 0.43. Tolerance: a sample is 1 or 0, so the image mean of N samples has
/// σ = √(R′(1 − R′)/N) (0.0026 at N = 16²·40); held to 4σ at each of four seeds per engine.
#[test]
fn a_thin_sheet_passes_one_minus_its_reflectance_straight_through() {
    let d = scratch_dir("thin-sheet");
    let xml = "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" value=\"10\"/>\
<transform name=\"to_world\"><lookat origin=\"0, 0, 3\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>\
<film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer name=\"height\" value=\"16\"/></film></sensor>\n\
<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"4\"/><translate z=\"-1\"/></transform>\
<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>\n\
<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"4\"/></transform><bsdf type=\"thindielectric\"/></shape>\n</scene>\n";
    let path = d.join("pane.xml");
    std::fs::write(&path, xml).unwrap();
    let loaded = load_scene(&path).unwrap();
    let cam = loaded.camera.unwrap();
    let rays = cam.prepare(16, 16).unwrap();
    let eta = 1.5 / 1.000277;
    // The expected mean: 1 − R′ at each pixel centre's angle to the pane's normal.
    let dirs = (0..16 * 16).map(|i| {
        let (x, y) = ((i % 16) as f32 + 0.5, (i / 16) as f32 + 0.5);
        let t = (5f32.to_radians()).tan();
        Vec3::new((x / 8.0 - 1.0) * t, (1.0 - y / 8.0) * t, -1.0).normalize()
    });
    let expected: f64 =
        dirs.map(|w| 1.0 - f64::from(photonwave::optics::thin_slab_reflectance(-w.z, eta))).sum::<f64>() / 256.0;
    let n = 16.0 * 16.0 * 40.0;
    let sigma = (expected * (1.0 - expected) / n).sqrt();
    let scene = Arc::new(loaded.scene);
    for engine in [Engine::Wavefront, Engine::Reference, Engine::Path] {
        for seed in 1..=4 {
            let s = Settings {
                width: 16,
                height: 16,
                spp: 40,
                photons: 2000,
                caustic_photons: 2000,
                seed,
                ..Settings::default()
            };
            let film = render(&scene, &rays, &s, engine, None, &NoProgress).unwrap().0;
            let mean = f64::from(film.mean().element_sum() / 3.0);
            assert!(
                (mean - expected).abs() < 4.0 * sigma,
                "{engine:?} seed {seed}: mean {mean} against 1 − R′ = {expected} (σ {sigma})"
            );
        }
    }
}

/// The Mitsuba gallery scene — Mitsuba's rough plastic (its coat tables), a copper rough
/// conductor by its complex index — with a thin sheet across the room and a smooth plastic ball
/// (its coat a delta lobe beside a diffuse base): the two photon-mapping engines agree per pixel
/// in every term (1e-6, as tests/wavefront.rs holds them), and the wavefront engine is
/// bit-identical at one and two threads.
#[test]
fn engines_agree_on_mitsuba_plastics_conductors_and_a_thin_sheet() {
    let pane = "<shape type=\"rectangle\"><transform name=\"to_world\"><scale x=\"0.12\" y=\"0.1\"/><translate x=\"0.08\" y=\"0.25\" z=\"0.12\"/></transform>\
<bsdf type=\"thindielectric\"/></shape>\n<shape type=\"sphere\"><point name=\"center\" x=\"-0.16\" y=\"0.32\" z=\"0.02\"/>\
<float name=\"radius\" value=\"0.07\"/><bsdf type=\"plastic\"><rgb name=\"diffuse_reflectance\" value=\"0.7, 0.6, 0.15\"/></bsdf></shape>";
    let loaded = gallery_with(&scratch_dir("mitsuba-engines"), pane);
    let kinds = |f: fn(&Bsdf) -> bool| loaded.scene.materials.iter().any(|m| f(&m.bsdf));
    assert!(kinds(|b| matches!(b, Bsdf::RoughPlastic { .. })) && kinds(|b| matches!(b, Bsdf::ThinGlass { .. })));
    assert!(kinds(|b| matches!(b, Bsdf::Plastic { .. })));
    assert!(kinds(|b| matches!(b, Bsdf::RoughConductor { eta_k: Some(_), .. })));
    let a = assert_engines_agree(loaded);
    // The camera sees the room through the sheet (the only delta surface): a specular term.
    assert!(a.pixels.iter().filter(|p| p.specular != Vec3::ZERO).count() > 10, "the sheet is in view");
}

/// An emitter is one light source however many triangles it has: two Mitsuba rectangles that
/// emit (two triangles each) and a point light are three sources of four emissive triangles, in
/// the scene and in the render summary.
#[test]
fn an_emitting_shape_is_one_light_source() {
    let d = scratch_dir("light-sources");
    let lamp = |x: f32| {
        format!(
            "<shape type=\"rectangle\"><transform name=\"to_world\"><translate x=\"{x}\" z=\"2\"/></transform>\
<emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>"
        )
    };
    let xml = format!(
        "<scene version=\"3.0.0\">\n<shape type=\"rectangle\"/>\n{}\n{}\n\
<emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"0\" z=\"1\"/></emitter>\n</scene>\n",
        lamp(-3.0),
        lamp(3.0)
    );
    let loaded = load_doc_xml(&d, &xml);
    assert_eq!(loaded.scene.light_sources(), (3, 4));
    let stats = photonwave::stats::RenderStats::new("path", &loaded.scene, &Settings::default(), 1);
    assert_eq!((stats.lights, stats.emissive_triangles), (3, 4));
}

/// Loads Mitsuba XML text written into `dir`.
fn load_doc_xml(dir: &Path, xml: &str) -> LoadedScene {
    load_scene(&write(dir, "s.xml", xml)).unwrap()
}
