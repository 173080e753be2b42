//! glTF 2.0 models (`.gltf` with its buffers and images, or `.glb`), through the `gltf` crate's
//! document model: the default scene's node hierarchy with its transforms, triangle meshes,
//! perspective cameras, `KHR_lights_punctual` lights and materials (`materials`).
//!
//! Reads the file, its buffers (the GLB's binary chunk, files beside it, or `data:` URIs) and
//! images; writes one [`MeshInput`] in world space, materials into the [`MaterialTable`], and the
//! lights and named cameras. Accessors are read here, bounds-checked, rather than by the crate's
//! reader (which asserts on strides shorter than an element): a damaged file is an error naming
//! the accessor, never a panic.
//!
//! Units: glTF lights are photometric (candela, lux); photonwave's are radiometric in the same
//! units as emitted radiance, so a candela is taken as 1/683 W/sr and a lux as 1/683 W/m² (the
//! luminous efficacy of 555 nm light), as Blender's importer does. Emissive materials are taken
//! as radiance as they are.

mod accessor;
mod materials;

use crate::error::{Error, Result};
use crate::files::{read_input, MAX_MESH_FILE};
use crate::formats::materials::MaterialTable;
use crate::formats::transform::Transform;
use crate::scene::camera::Camera;
use crate::scene::light::Light;
use crate::scene::MeshInput;
use crate::texture::{Encoding, Texture};
use accessor::{read_f32, read_indices};
use glam::{Affine3A, Mat4, Vec2, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The required extensions read (a file requiring any other is refused).
pub const REQUIRED_READ: [&str; 6] = [
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_texture_transform",
];

/// Nodes deeper than this are a cycle or a hostile file.
const MAX_DEPTH: usize = 256;

/// The most vertices a model may place (instances counted): 2²⁸, within the u32 indices.
const MAX_VERTICES: usize = 1 << 28;

/// 1 W at 555 nm is 683 lm: candela to W/sr, lux to W/m².
const LUMENS_PER_WATT: f32 = 683.0;

/// A loaded glTF model.
pub struct Model {
    /// Every triangle, in world space.
    pub mesh: MeshInput,
    /// Punctual lights, in world space.
    pub lights: Vec<Light>,
    /// Perspective cameras, with their names.
    pub cameras: Vec<(String, Camera)>,
}

/// The file's buffers and images, read once.
pub(super) struct Sources<'a> {
    pub path: &'a Path,
    doc: &'a gltf::Document,
    buffers: Vec<Vec<u8>>,
    images: HashMap<(usize, Encoding), Arc<Texture>>,
    inputs: &'a mut Vec<PathBuf>,
}

/// A GLB container's JSON and binary chunks, checked (the crate's own reader subtracts lengths
/// unchecked).
fn glb_chunks<'b>(path: &Path, data: &'b [u8]) -> Result<(&'b [u8], Option<&'b [u8]>)> {
    let err = |m: &str| Error::parse(path, 0, format!("GLB: {m}"));
    let word = |at: usize| data.get(at..at + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize);
    let (Some(version), Some(length)) = (word(4), word(8)) else { return Err(err("the header is cut short")) };
    if version != 2 {
        return Err(err(&format!("version {version} (glTF 2.0 is read)")));
    }
    let data = data.get(..length).ok_or_else(|| err("the file is shorter than its header says"))?;
    let mut chunks = Vec::new();
    let mut at = 12;
    while at + 8 <= data.len() {
        let (len, kind) = (word(at).unwrap_or(0), data[at + 4..at + 8].to_vec());
        let body = data.get(at + 8..at + 8 + len).ok_or_else(|| err("a chunk runs past the end of the file"))?;
        chunks.push((kind, body));
        at += 8 + len.div_ceil(4) * 4;
    }
    let json = chunks.first().filter(|(k, _)| k == b"JSON").ok_or_else(|| err("the first chunk is not JSON"))?.1;
    let bin = chunks.get(1).filter(|(k, _)| k == b"BIN\0").map(|c| c.1);
    Ok((json, bin))
}

/// Refuses a model whose `asset.version` (or `minVersion`) is not 2.x, before the typed reader
/// sees it: glTF 1.0 is another schema (objects keyed by name, techniques and shaders), which
/// would either be refused with an unrelated message or, where its fields happen to fit, render
/// as something else. A JSON the check cannot read, or one without a version, is left to the
/// typed reader's message.
fn asset_version(path: &Path, json: &[u8]) -> Result<()> {
    let Ok(root) = serde_json::from_slice::<serde_json::Value>(json) else { return Ok(()) };
    let asset = root.get("asset");
    for field in ["version", "minVersion"] {
        let Some(v) = asset.and_then(|a| a.get(field)) else { continue };
        let text = v.as_str().map_or_else(|| v.to_string(), str::to_owned);
        if text.split('.').next() != Some("2") {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "asset.{field} is \"{}\": photonwave reads glTF 2.0 (glTF 1.0 is another schema; \
                     convert the model to 2.0 first, e.g. with Khronos' glTF converters or Blender)",
                    text.chars().take(40).collect::<String>()
                ),
            ));
        }
    }
    Ok(())
}

/// The bytes a `data:` URI holds (base64 only).
fn data_uri(uri: &str) -> Option<Vec<u8>> {
    use base64::Engine;
    let (head, body) = uri.strip_prefix("data:")?.split_once(',')?;
    head.ends_with(";base64").then(|| base64::engine::general_purpose::STANDARD.decode(body).ok())?
}

/// A relative URI's path beside `path` (percent escapes decoded).
fn beside(path: &Path, uri: &str) -> PathBuf {
    let mut bytes = Vec::new();
    let mut it = uri.bytes();
    while let Some(b) = it.next() {
        if b == b'%' {
            let hex: Vec<u8> = it.by_ref().take(2).collect();
            if let Some(v) = std::str::from_utf8(&hex).ok().and_then(|h| u8::from_str_radix(h, 16).ok()) {
                bytes.push(v);
                continue;
            }
            bytes.push(b'%');
            bytes.extend(hex);
        } else {
            bytes.push(b);
        }
    }
    path.parent().unwrap_or(Path::new(".")).join(String::from_utf8_lossy(&bytes).as_ref())
}

impl Sources<'_> {
    /// The bytes at a URI of the file: a `data:` URI's or a file's beside it (`what` names it).
    fn uri(&mut self, uri: &str, what: &str) -> Result<Vec<u8>> {
        if uri.starts_with("data:") {
            return data_uri(uri)
                .ok_or_else(|| Error::parse(self.path, 0, format!("{what}: a `data:` URI that is not valid base64")));
        }
        let file = beside(self.path, uri);
        let bytes = read_input(&file, what, MAX_MESH_FILE)
            .map_err(|e| Error::parse(self.path, 0, format!("{what} cannot be read: {e}")))?;
        self.inputs.push(file);
        Ok(bytes)
    }

    /// Image `index` decoded with `encoding` (read once per encoding); `what` names its use.
    pub fn image(&mut self, index: usize, encoding: Encoding, what: &str) -> Result<Arc<Texture>> {
        if let Some(t) = self.images.get(&(index, encoding)) {
            return Ok(t.clone());
        }
        let doc = self.doc;
        let image =
            doc.images().nth(index).ok_or_else(|| Error::parse(self.path, 0, format!("{what}: no image {index}")))?;
        let label = format!("{what} (image {index})");
        let (bytes, origin) = match image.source() {
            gltf::image::Source::Uri { uri, .. } => {
                let origin = if uri.starts_with("data:") { self.path.to_path_buf() } else { beside(self.path, uri) };
                (self.uri(uri, &label)?, origin)
            }
            gltf::image::Source::View { view, .. } => {
                let buffer = &self.buffers[view.buffer().index()];
                let end = view.offset().checked_add(view.length()).filter(|e| *e <= buffer.len());
                let bytes = end.map(|e| buffer[view.offset()..e].to_vec()).ok_or_else(|| {
                    Error::parse(self.path, 0, format!("{label}: buffer view {} runs past its buffer", view.index()))
                })?;
                (bytes, self.path.to_path_buf())
            }
        };
        let texture = Arc::new(crate::formats::image::texture_from_bytes(&origin, &bytes, encoding, &label)?);
        self.images.insert((index, encoding), texture.clone());
        Ok(texture)
    }
}

/// What the crate would refuse late or unwrap, checked first: required extensions photonwave
/// does not read; an image needs a `uri` or a `bufferView` with a `mimeType`; a camera the
/// projection its `type` names; a POSITION attribute an accessor that exists (gltf-json's
/// validator indexes it unchecked).
fn check_root(path: &Path, root: &gltf::json::Root) -> Result<()> {
    for ext in &root.extensions_required {
        if !REQUIRED_READ.contains(&ext.as_str()) {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "the model requires the extension {ext}, which photonwave does not read (it reads {})",
                    REQUIRED_READ.join(", ")
                ),
            ));
        }
    }
    // What the crate's document model would unwrap, checked here first: an image has a `uri` or a
    // `bufferView` (with a `mimeType`), and a camera has the projection its `type` names.
    for (i, image) in root.images.iter().enumerate() {
        if image.uri.is_some() == image.buffer_view.is_some()
            || (image.buffer_view.is_some() && image.mime_type.is_none())
        {
            return Err(Error::parse(
                path,
                0,
                format!("images[{i}] needs a `uri`, or a `bufferView` and a `mimeType`"),
            ));
        }
    }
    for (i, camera) in root.cameras.iter().enumerate() {
        use gltf::json::camera::Type;
        let ok = match camera.type_ {
            gltf::json::validation::Checked::Valid(Type::Perspective) => camera.perspective.is_some(),
            gltf::json::validation::Checked::Valid(Type::Orthographic) => camera.orthographic.is_some(),
            _ => true,
        };
        if !ok {
            return Err(Error::parse(path, 0, format!("cameras[{i}] lacks the projection its `type` names")));
        }
    }
    // gltf-json's validator indexes the POSITION accessor unchecked: checked here first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let position = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(i) = prim.attributes.get(&position).filter(|i| i.value() >= root.accessors.len()) {
                return Err(Error::parse(
                    path,
                    0,
                    format!(
                        "meshes[{m}].primitives[{p}]: POSITION names accessor {}, but there are {}",
                        i.value(),
                        root.accessors.len()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Reads every buffer of `src`'s document into `src.buffers`: the GLB's binary chunk `bin` or
/// the file or data URI it names; a buffer shorter than declared is an error.
fn read_buffers(src: &mut Sources, bin: Option<&[u8]>) -> Result<()> {
    let (path, doc) = (src.path, src.doc);
    for buffer in doc.buffers() {
        let what = format!("buffer {}", buffer.index());
        let bytes = match buffer.source() {
            gltf::buffer::Source::Bin => bin
                .ok_or_else(|| {
                    Error::parse(path, 0, format!("{what} is the GLB's binary chunk, which the file lacks"))
                })?
                .to_vec(),
            gltf::buffer::Source::Uri(uri) => src.uri(uri, &what)?,
        };
        if bytes.len() < buffer.length() {
            return Err(Error::parse(
                path,
                0,
                format!("{what} holds {} bytes, fewer than the {} declared", bytes.len(), buffer.length()),
            ));
        }
        src.buffers.push(bytes);
    }
    Ok(())
}

/// The pinhole camera `camera` of `node`, placed by `world`, with its name (the camera's, else
/// the node's); an orthographic one is warned of and skipped.
fn node_camera(
    node: &gltf::Node,
    camera: &gltf::Camera,
    world: &Affine3A,
    label: &str,
    path: &Path,
    warnings: &mut Vec<String>,
) -> Option<(String, Camera)> {
    match camera.projection() {
        gltf::camera::Projection::Perspective(p) => {
            let name =
                camera.name().or(node.name()).map_or_else(|| format!("camera {}", camera.index()), str::to_string);
            let eye = world.transform_point3(Vec3::ZERO);
            let forward = world.transform_vector3(-Vec3::Z);
            let up = world.transform_vector3(Vec3::Y);
            Some((name, Camera { eye, target: eye + forward, up, fov_deg: p.yfov().to_degrees() }))
        }
        gltf::camera::Projection::Orthographic(_) => {
            warnings
                .push(format!("{}: {label}'s orthographic camera is not read (pinhole cameras only)", path.display()));
            None
        }
    }
}

/// Loads the glTF or GLB file at `path`, placed by `transform`; its materials go into `table`,
/// every file read into `inputs`.
pub fn load_gltf(
    path: &Path,
    transform: &Transform,
    table: &mut MaterialTable,
    warnings: &mut Vec<String>,
    inputs: &mut Vec<PathBuf>,
) -> Result<Model> {
    let data = read_input(path, "a glTF model", MAX_MESH_FILE)?;
    inputs.push(path.to_path_buf());
    let (json, bin) = if data.starts_with(b"glTF") { glb_chunks(path, &data)? } else { (&data[..], None) };
    asset_version(path, json)?;
    let root: gltf::json::Root =
        gltf::json::deserialize::from_slice(json).map_err(|e| Error::parse(path, e.line(), format!("glTF: {e}")))?;
    check_root(path, &root)?;
    let doc = gltf::Document::from_json(root).map_err(|e| Error::parse(path, 0, format!("glTF: {e}")))?;
    let ignored: Vec<&str> = doc.extensions_used().filter(|e| !REQUIRED_READ.contains(e)).collect();
    if !ignored.is_empty() {
        warnings.push(format!(
            "{}: the extensions {} are not read; the model renders without them",
            path.display(),
            ignored.join(", ")
        ));
    }
    let mut src = Sources { path, doc: &doc, buffers: Vec::new(), images: HashMap::new(), inputs };
    read_buffers(&mut src, bin)?;
    let mut ids = Vec::new();
    let mut names = std::collections::HashSet::new();
    for m in doc.materials() {
        let index = m.index().unwrap_or(0);
        let mut name = m.name().map_or_else(|| format!("material {index}"), str::to_string);
        // Names need not be unique in glTF; in the material table they must.
        if !names.insert(name.clone()) {
            name = format!("{name} (material {index})");
            names.insert(name.clone());
        }
        ids.push((materials::convert(&m, &name, &mut src, warnings)?, None));
    }
    let mut model = Model {
        mesh: MeshInput { source: path.display().to_string(), ..Default::default() },
        lights: Vec::new(),
        cameras: Vec::new(),
    };
    let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let children: std::collections::HashSet<usize> =
                doc.nodes().flat_map(|n| n.children().map(|c| c.index())).collect();
            doc.nodes().filter(|n| !children.contains(&n.index())).collect()
        }
    };
    let mut stack: Vec<(gltf::Node, Affine3A, usize)> = roots.into_iter().rev().map(|n| (n, transform.0, 0)).collect();
    let mut missing_material = false;
    // The nodes form a forest (glTF 2.0, 5.25): a node reached twice is a cycle or a shared
    // child, either of which could multiply the work without bound.
    let mut reached = vec![false; doc.nodes().len()];
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > MAX_DEPTH || std::mem::replace(&mut reached[node.index()], true) {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "node {} is reached twice or lies {MAX_DEPTH} levels deep: the hierarchy must be a forest",
                    node.index()
                ),
            ));
        }
        let local = Affine3A::from_mat4(Mat4::from_cols_array_2d(&node.transform().matrix()));
        let world = parent * local;
        // Children in document order (the stack pops the last pushed first).
        let children: Vec<gltf::Node> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world, depth + 1)));
        let label = node.name().map_or_else(|| format!("node {}", node.index()), |n| format!("node `{n}`"));
        if let Some(camera) = node.camera() {
            model.cameras.extend(node_camera(&node, &camera, &world, &label, path, warnings));
        }
        if let Some(light) = node.light() {
            model.lights.extend(punctual(&light, &world, &label, path, warnings));
        }
        let Some(mesh) = node.mesh() else { continue };
        let Ok(place) = Transform::checked(&label, world) else {
            warnings.push(format!(
                "{}: {label} is scaled to nothing (a singular transform); its mesh is skipped",
                path.display()
            ));
            continue;
        };
        for prim in mesh.primitives() {
            let what = format!("{label}, mesh {} primitive {}", mesh.index(), prim.index());
            let material = match prim.material().index() {
                Some(i) => {
                    let (converted, id) = &mut ids[i];
                    *id.get_or_insert_with(|| table.insert(path, converted.material.clone(), warnings))
                }
                None => {
                    missing_material = true;
                    table.default_material()
                }
            };
            let uv = prim.material().index().and_then(|i| ids[i].0.uv);
            if let Some(mut part) = primitive(&prim, &src, &what, material, uv, warnings)? {
                if model.mesh.positions.len() + part.positions.len() > MAX_VERTICES {
                    return Err(Error::parse(
                        path,
                        0,
                        format!("{what}: the model's meshes, as its nodes place them, exceed 2²⁸ vertices"),
                    ));
                }
                place.apply(&mut part);
                append(&mut model.mesh, part);
            }
        }
    }
    if missing_material {
        warnings.push(format!("{}: primitives without a material are grey Lambertian (Kd 0.8)", path.display()));
    }
    if model.mesh.triangles.is_empty() && model.lights.is_empty() {
        return Err(Error::parse(path, 0, "the model's scene has no triangles and no lights"));
    }
    Ok(model)
}

/// A `KHR_lights_punctual` light at the node placed by `world`.
fn punctual(
    light: &gltf::khr_lights_punctual::Light,
    world: &Affine3A,
    label: &str,
    path: &Path,
    warnings: &mut Vec<String>,
) -> Option<Light> {
    use gltf::khr_lights_punctual::Kind;
    let power = Vec3::from_array(light.color()).max(Vec3::ZERO) * light.intensity().max(0.0) / LUMENS_PER_WATT;
    if !power.is_finite() {
        warnings.push(format!("{}: {label}'s light has a non-finite intensity; it is skipped", path.display()));
        return None;
    }
    if light.range().is_some() {
        warnings.push(format!(
            "{}: {label}'s light range is ignored (light falls off as 1/r² without a cutoff)",
            path.display()
        ));
    }
    let position = world.transform_point3(Vec3::ZERO);
    let mut direction = || {
        let d = world.transform_vector3(-Vec3::Z).try_normalize();
        if d.is_none() {
            warnings.push(format!("{}: {label}'s light is scaled to no direction; it is skipped", path.display()));
        }
        d
    };
    Some(match light.kind() {
        Kind::Point => Light::Point { position, intensity: power },
        Kind::Directional => Light::Directional { direction: direction()?, irradiance: power },
        Kind::Spot { inner_cone_angle, outer_cone_angle } => {
            let direction = direction()?;
            let outer = outer_cone_angle.clamp(1e-3, std::f32::consts::FRAC_PI_2);
            let inner = inner_cone_angle.clamp(0.0, outer);
            Light::Spot { position, direction, intensity: power, cos_inner: inner.cos(), cos_outer: outer.cos() }
        }
    })
}

/// The triangles of a primitive in its mesh's space, or `None` (with a warning) for points and
/// lines.
fn primitive(
    prim: &gltf::Primitive,
    src: &Sources,
    what: &str,
    material: u32,
    uv: Option<materials::UvTransform>,
    warnings: &mut Vec<String>,
) -> Result<Option<MeshInput>> {
    use gltf::mesh::{Mode, Semantic};
    let path = src.path;
    let positions =
        prim.get(&Semantic::Positions).ok_or_else(|| Error::parse(path, 0, format!("{what} has no POSITION")))?;
    let positions: Vec<Vec3> =
        read_f32::<3>(&positions, &src.buffers, path, what)?.into_iter().map(Vec3::from_array).collect();
    if let Some(k) = positions.iter().position(|p| !p.is_finite()) {
        return Err(Error::parse(path, 0, format!("{what}: vertex {k} is {}, not finite", positions[k])));
    }
    let n = positions.len();
    let order: Vec<u32> = match prim.indices() {
        Some(a) => read_indices(&a, &src.buffers, path, what, n)?,
        None => (0..n as u32).collect(),
    };
    let triangles: Vec<[u32; 3]> = match prim.mode() {
        Mode::Triangles => order.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
        Mode::TriangleStrip => (2..order.len())
            .map(|i| {
                if i % 2 == 0 {
                    [order[i - 2], order[i - 1], order[i]]
                } else {
                    [order[i - 1], order[i - 2], order[i]]
                }
            })
            .collect(),
        Mode::TriangleFan => (2..order.len()).map(|i| [order[0], order[i - 1], order[i]]).collect(),
        other => {
            warnings.push(format!("{}: {what} is drawn as {other:?}, not triangles; it is skipped", path.display()));
            return Ok(None);
        }
    };
    let mut mesh = MeshInput { positions, material: vec![material; triangles.len()], triangles, ..Default::default() };
    if let Some(a) = prim.get(&Semantic::Normals) {
        mesh.normals = read_f32::<3>(&a, &src.buffers, path, what)?.into_iter().map(Vec3::from_array).collect();
        for v in &mut mesh.normals {
            if !v.is_finite() || v.try_normalize().is_none() {
                mesh.zero_normals += 1;
                *v = Vec3::ZERO;
            }
        }
    }
    if let Some(a) = prim.get(&Semantic::TexCoords(0)) {
        // glTF's v runs down the image; photonwave's up (the image's first row is v = 1).
        let t = uv.unwrap_or(materials::UvTransform { offset: Vec2::ZERO, rotation: 0.0, scale: Vec2::ONE });
        mesh.texcoords = read_f32::<2>(&a, &src.buffers, path, what)?
            .into_iter()
            .map(|c| {
                let c = t.apply(Vec2::from_array(c));
                let c = Vec2::new(c.x, 1.0 - c.y);
                if c.is_finite() {
                    c
                } else {
                    Vec2::ZERO
                }
            })
            .collect();
    }
    for (name, len) in [("NORMAL", mesh.normals.len()), ("TEXCOORD_0", mesh.texcoords.len())] {
        if len != 0 && len != n {
            return Err(Error::parse(path, 0, format!("{what}: {name} has {len} entries for {n} positions")));
        }
    }
    Ok(Some(mesh))
}

/// Appends `part` to `mesh`, filling absent normals and texture coordinates with zeros (none).
fn append(mesh: &mut MeshInput, part: MeshInput) {
    let (base, n) = (mesh.positions.len(), part.positions.len());
    column(&mut mesh.normals, &part.normals, base, n);
    column(&mut mesh.texcoords, &part.texcoords, base, n);
    mesh.zero_normals += part.zero_normals;
    mesh.positions.extend(part.positions);
    mesh.triangles.extend(part.triangles.iter().map(|t| t.map(|i| i + base as u32)));
    mesh.material.extend(part.material);
}

/// Appends a per-vertex column: `theirs` (or zeros for `n` vertices when it is empty) after the
/// `base` entries `ours` should have; both empty stay empty.
fn column<T: Copy + Default>(ours: &mut Vec<T>, theirs: &[T], base: usize, n: usize) {
    if theirs.is_empty() && ours.is_empty() {
        return;
    }
    ours.resize(base, T::default());
    if theirs.is_empty() {
        ours.resize(base + n, T::default());
    } else {
        ours.extend_from_slice(theirs);
    }
}
