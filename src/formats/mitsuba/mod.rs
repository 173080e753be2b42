//! Mitsuba scene files (`.xml`, versions 0.5 to 3.x, the subset research scenes use), read with
//! `roxmltree`: `<default>` and `$param` substitution, `<ref>` and ids, the `perspective`
//! (or `thinlens`) sensor and its film's size, shapes (`obj`, `ply`, `rectangle`, `disk`,
//! `cube`, `sphere`) with their `to_world` transforms, BSDFs (`bsdfs`), area emitters on
//! shapes, and `point`, `spot`, `directional`, `envmap` and `constant` emitters.
//!
//! Writes the meshes, materials (into the [`MaterialTable`]), lights, environment, camera and
//! image size of a [`crate::formats::LoadedScene`]. Everything not understood is warned of with its
//! line (`integrator`, `sampler`, media that are no shape's interior, `sun`, …); a shape's
//! interior `homogeneous` medium absorbs inside its dielectric (`media`); what cannot be rendered honestly (a
//! metal without data, a shape file that cannot be read) is an error naming file and line.
//!
//! Mitsuba's camera looks down its local +z with +y up; its lat-long maps put u = atan2(x, −z)/2π
//! (photonwave's: atan2(z, x)/2π, a quarter turn apart), which `Ctx::envmap` turns into
//! photonwave's convention.

mod bsdfs;
mod media;
mod props;

use crate::error::{Error, Result};
use crate::files::{read_text, MAX_SCENE_FILE};
use crate::formats::materials::MaterialTable;
use crate::formats::obj::{load_obj, ObjMaterials};
use crate::formats::ply::load_ply;
use crate::formats::shapes::shape;
use crate::formats::transform::Transform;
use crate::scene::camera::Camera;
use crate::scene::environment::Environment;
use crate::scene::light::Light;
use crate::scene::MeshInput;
use crate::settings::MAX_IMAGE_SIDE;
use crate::texture::{Encoding, Texture};
use bsdfs::UvMap;
use glam::{Affine3A, Vec2, Vec3};
use props::Reader;
use roxmltree::{Node, NodeId};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A Mitsuba scene, read.
pub struct MitsubaScene {
    /// The shapes, in world space.
    pub meshes: Vec<MeshInput>,
    /// The point, spot and directional emitters.
    pub lights: Vec<Light>,
    /// An `envmap` or `constant` emitter.
    pub environment: Option<Environment>,
    /// The sensor.
    pub camera: Option<Camera>,
    /// The film's width and height.
    pub size: Option<(u32, u32)>,
}

/// What reading the scene carries along.
pub(super) struct Ctx<'a> {
    r: Reader<'a>,
    /// The major version (0 for 0.5, 3 for 3.x).
    version: u32,
    ids: HashMap<String, Node<'a, 'a>>,
    table: &'a mut MaterialTable,
    warnings: &'a mut Vec<String>,
    inputs: &'a mut Vec<PathBuf>,
    materials: HashMap<NodeId, (u32, Option<UvMap>)>,
    /// The `<medium>` elements shapes named (the others are warned of).
    used_media: std::collections::HashSet<NodeId>,
    /// How deep the BSDF being read is nested in wrappers.
    depth: usize,
}

impl<'a> Ctx<'a> {
    fn warn(&mut self, node: Node, message: String) {
        let line = self.r.line(node);
        self.warnings.push(format!("{}:{line}: {message}", self.r.path.display()));
    }

    /// The element a `<ref id>` names.
    fn referenced(&self, node: Node<'a, 'a>) -> Result<Node<'a, 'a>> {
        let id = self.r.attr(node, "id")?.unwrap_or_default();
        self.ids.get(&id).copied().ok_or_else(|| self.r.error(node, format!("<ref id=\"{id}\"> names no element")))
    }

    /// A file the scene names, relative to it.
    fn file(&self, name: &str) -> PathBuf {
        self.r.path.parent().unwrap_or(Path::new(".")).join(name)
    }

    /// The image `file` (read once per encoding), named by `node` in errors.
    fn image(&mut self, node: Node, file: &str, encoding: Encoding) -> Result<Arc<Texture>> {
        let what = format!("the texture at {}:{}", self.r.path.display(), self.r.line(node));
        self.table.texture(&self.file(file), encoding, &what, self.inputs)
    }

    /// The table index of the material of `<bsdf>` element `node` (converted once).
    fn material(&mut self, node: Node<'a, 'a>) -> Result<(u32, Option<UvMap>)> {
        let node = if node.tag_name().name() == "ref" { self.referenced(node)? } else { node };
        if let Some(m) = self.materials.get(&node.id()) {
            return Ok(*m);
        }
        let pos = self.r.doc.text_pos_at(node.range().start);
        let name = node
            .attribute("id")
            .map_or_else(|| format!("bsdf at line {}, column {}", pos.row, pos.col), str::to_string);
        let (material, uv) = self.bsdf(node, &name)?;
        let id = self.table.insert(self.r.path, material, self.warnings);
        self.materials.insert(node.id(), (id, uv));
        Ok((id, uv))
    }

    /// The mesh of `<shape>` element `node` (its area emitter makes its material emit).
    fn shape(&mut self, node: Node<'a, 'a>) -> Result<Option<MeshInput>> {
        let kind = node.attribute("type").unwrap_or("");
        let to_world = Transform::checked(
            &format!("{}:{}", self.r.path.display(), self.r.line(node)),
            self.r.transform(node, "to_world")?,
        )?;
        let mut bsdf = None;
        for c in node.children().filter(Node::is_element) {
            match c.tag_name().name() {
                "bsdf" => bsdf = Some(c),
                "ref" if self.referenced(c)?.tag_name().name() == "bsdf" => bsdf = Some(c),
                _ => {}
            }
        }
        let (mut material, uv) = match bsdf {
            Some(b) => self.material(b)?,
            None => {
                // Mitsuba's default BSDF: diffuse, reflectance 0.5.
                let grey = crate::material::Material::new(
                    "(Mitsuba default diffuse)",
                    crate::material::Bsdf::Lambert { kd: Vec3::splat(0.5) },
                    Vec3::ZERO,
                );
                (self.table.insert(Path::new(""), grey, &mut Vec::new()), None)
            }
        };
        let bsdf_kind = self.table.materials[material as usize].bsdf;
        if let Some((sigma, scattering)) = self.interior(node, &bsdf_kind)? {
            let mut inside = self.table.materials[material as usize].clone();
            inside.name = format!("{} (interior medium of the shape at line {})", inside.name, self.r.line(node));
            inside.interior = sigma;
            inside.interior_scattering = scattering;
            material = self.table.insert(self.r.path, inside, self.warnings);
        }
        if let Some(e) = node.children().find(|c| c.is_element() && c.tag_name().name() == "emitter") {
            if e.attribute("type") != Some("area") {
                self.warn(
                    e,
                    format!(
                        "a `{}` emitter inside a shape is not read (only `area`)",
                        e.attribute("type").unwrap_or("")
                    ),
                );
            } else {
                let radiance =
                    self.r.prop(e, "radiance").map_or(Ok(Vec3::ONE), |p| self.r.colour_of(p))?.max(Vec3::ZERO);
                let mut lit = self.table.materials[material as usize].clone();
                let pos = self.r.doc.text_pos_at(e.range().start);
                lit.name = format!("{} (area light at line {}, column {})", lit.name, pos.row, pos.col);
                lit.emission = radiance;
                material = self.table.insert(self.r.path, lit, self.warnings);
            }
        }
        let source = format!("{}:{} (shape `{kind}`)", self.r.path.display(), self.r.line(node));
        let mut mesh = match kind {
            "obj" | "ply" => {
                let file = self
                    .r
                    .string(node, "filename")?
                    .ok_or_else(|| self.r.error(node, format!("a `{kind}` shape needs a `filename`")))?;
                let path = self.file(&file);
                let mut mesh = if kind == "obj" {
                    let all = ObjMaterials::All(material);
                    load_obj(&path, &Transform::default(), all, self.table, self.warnings, self.inputs)?
                } else {
                    load_ply(&path, material, self.warnings, self.inputs)?
                };
                if self.r.boolean(node, "face_normals", false)? {
                    mesh.normals.clear();
                }
                // Mitsuba turns an OBJ's v over by default and a PLY's not; it reads an image's
                // first row at v = 0, photonwave at v = 1 (as the OBJ files' v means): a file
                // whose v Mitsuba keeps is turned over here.
                if !self.r.boolean(node, "flip_tex_coords", kind == "obj")? {
                    mesh.texcoords.iter_mut().for_each(|t| t.y = 1.0 - t.y);
                }
                mesh
            }
            "rectangle" | "disk" | "cube" => shape(kind, &source, material)?,
            "sphere" => {
                let mut mesh = shape("sphere", &source, material)?;
                let (c, r) = (self.r.point(node, "center")?.unwrap_or(Vec3::ZERO), self.r.float(node, "radius", 1.0)?);
                Transform(Affine3A::from_scale_rotation_translation(
                    Vec3::splat(r.abs().max(1e-30)),
                    glam::Quat::IDENTITY,
                    c,
                ))
                .apply(&mut mesh);
                mesh
            }
            other => {
                self.warn(
                    node,
                    format!(
                        "shape `{other}` is not read (obj, ply, rectangle, disk, cube and sphere are); it is left out"
                    ),
                );
                return Ok(None);
            }
        };
        if self.r.boolean(node, "flip_normals", false)? {
            mesh.triangles.iter_mut().for_each(|t| t.swap(1, 2));
            mesh.normals.iter_mut().for_each(|n| *n = -*n);
        }
        if let Some(m) = uv {
            // The texture transform acts on Mitsuba's coordinates, v the other way up.
            let turn = |t: Vec2| Vec2::new(t.x, 1.0 - t.y);
            mesh.texcoords.iter_mut().for_each(|t| *t = turn(turn(*t) * m.scale + m.offset));
        }
        to_world.apply(&mut mesh);
        mesh.source = source;
        Ok(Some(mesh))
    }

    /// The light of a top-level `<emitter>`, or the environment it is.
    fn emitter(&mut self, node: Node<'a, 'a>, scene: &mut MitsubaScene) -> Result<()> {
        let kind = node.attribute("type").unwrap_or("");
        let to_world = self.r.transform(node, "to_world")?;
        let colour = |me: &Self, name: &str| {
            me.r.prop(node, name).map_or(Ok(Vec3::ONE), |p| me.r.colour_of(p)).map(|c| c.max(Vec3::ZERO))
        };
        let scale = self.r.float(node, "scale", 1.0)?;
        if scale < 0.0 {
            return Err(self.r.error(node, "an emitter's `scale` must not be negative"));
        }
        match kind {
            "point" => {
                let position = self.r.point(node, "position")?.unwrap_or(to_world.transform_point3(Vec3::ZERO));
                scene.lights.push(Light::Point { position, intensity: colour(self, "intensity")? * scale });
            }
            "spot" => {
                let cutoff = self.r.float(node, "cutoff_angle", 20.0)?.clamp(0.01, 90.0);
                let beam = self.r.float(node, "beam_width", cutoff * 0.75)?.clamp(0.0, cutoff);
                let direction = to_world.transform_vector3(Vec3::Z).try_normalize().ok_or_else(|| self.r.error(node, "the spot's to_world flattens its direction"))?;
                let intensity = colour(self, "intensity")? * scale;
                let position = to_world.transform_point3(Vec3::ZERO);
                scene.lights.push(Light::Spot { position, direction, intensity, cos_inner: beam.to_radians().cos(), cos_outer: cutoff.to_radians().cos() });
            }
            "directional" => {
                let d = self.r.point(node, "direction")?.unwrap_or(to_world.transform_vector3(Vec3::Z));
                let direction = d.try_normalize().ok_or_else(|| self.r.error(node, "a directional emitter needs a direction"))?;
                scene.lights.push(Light::Directional { direction, irradiance: colour(self, "irradiance")? * scale });
            }
            "constant" => scene.environment = Some(Environment::constant(colour(self, "radiance")? * scale)),
            "envmap" => scene.environment = Some(self.envmap(node, to_world, scale)?),
            other => self.warn(node, format!("emitter `{other}` is not read (point, spot, directional, envmap, constant and area are); it is left out")),
        }
        Ok(())
    }

    /// An `envmap` emitter: its lat-long image turned into photonwave's convention (a quarter
    /// turn in u), with a `to_world` rotation about +y.
    fn envmap(&mut self, node: Node<'a, 'a>, to_world: Affine3A, scale: f32) -> Result<Environment> {
        let file =
            self.r.string(node, "filename")?.ok_or_else(|| self.r.error(node, "an envmap needs a `filename`"))?;
        let t = self.image(node, &file, Encoding::Linear)?;
        let (w, h) = (t.width as usize, t.height as usize);
        let shift = w / 4;
        let texels = (0..w * h).map(|k| t.texels[(k / w) * w + (k % w + shift) % w]).collect();
        let map = Texture::new(&t.path, t.width, t.height, texels).expect("the same size");
        // A rotation about +y: where to_world sends +x, measured about y.
        let x = to_world.transform_vector3(Vec3::X);
        if (to_world.transform_vector3(Vec3::Y).normalize() - Vec3::Y).length() > 1e-3 {
            self.warn(node, "the envmap's to_world tilts +y; only its turn about +y is rendered".to_string());
        }
        // Mitsuba turns directions by β about +y (φ → φ − β, where to_world·x = (cos β, 0, −sin β));
        // photonwave's `rotation` adds to φ.
        let angle = x.z.atan2(x.x);
        Environment::from_map(map, scale.max(0.0), angle).map_err(|e| self.r.error(node, e))
    }

    /// The film's `width` or `height` (`default` where it has none): a whole number of pixels
    /// within [`MAX_IMAGE_SIDE`], refused at its own line otherwise (a film the size of a
    /// planet would be refused later by the settings, naming neither the file nor the line).
    fn film_side(&self, film: Node<'a, 'a>, name: &str, default: u32) -> Result<u32> {
        let Some(p) = self.r.prop(film, name) else { return Ok(default) };
        let v = self.r.float(film, name, default as f32)?;
        if v.fract() != 0.0 || !(1.0..=MAX_IMAGE_SIDE as f32).contains(&v) {
            return Err(self.r.error(
                p,
                format!("the film's `{name}` is {v}: it must be a whole number of pixels from 1 to {MAX_IMAGE_SIDE}"),
            ));
        }
        Ok(v as u32)
    }

    /// The camera and film of a `<sensor>`.
    fn sensor(&mut self, node: Node<'a, 'a>, scene: &mut MitsubaScene) -> Result<()> {
        let kind = node.attribute("type").unwrap_or("");
        match kind {
            "perspective" => {}
            "thinlens" => {
                self.warn(node, "thinlens: depth of field is not rendered (a pinhole camera is used)".to_string())
            }
            other => {
                return Err(self
                    .r
                    .error(node, format!("sensor `{other}` cannot be rendered (perspective and thinlens can)")))
            }
        }
        let (mut w, mut h) = (768u32, 576u32);
        if let Some(film) = node.children().find(|c| c.is_element() && c.tag_name().name() == "film") {
            w = self.film_side(film, "width", w)?;
            h = self.film_side(film, "height", h)?;
        }
        scene.size = Some((w, h));
        if let Some(s) = node.children().find(|c| c.is_element() && c.tag_name().name() == "sampler") {
            self.warn(s, "the sampler is not read: photonwave's `spp` and photon counts set the work".to_string());
        }
        let t = self.r.transform(node, "to_world")?;
        let eye = t.transform_point3(Vec3::ZERO);
        let forward = t
            .transform_vector3(Vec3::Z)
            .try_normalize()
            .ok_or_else(|| self.r.error(node, "the sensor's to_world flattens its view"))?;
        let up = t.transform_vector3(Vec3::Y);
        // Mitsuba's image x runs along the camera's −x (its lookat puts +x to the left); a
        // to_world that mirrors x gives a mirrored image, which a pinhole cannot.
        if t.transform_vector3(Vec3::X).dot(up.cross(forward)) < 0.0 {
            self.warn(node, "the sensor's to_world mirrors the image; it is rendered unmirrored".to_string());
        }
        let fov = self.r.float(node, "fov", 0.0)?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(self
                .r
                .error(node, "the sensor needs a `fov` in (0, 180) degrees (`focal_length` is not read)"));
        }
        let half = (fov.to_radians() * 0.5).tan();
        let (fw, fh) = (w as f32, h as f32);
        let axis = self.r.string(node, "fov_axis")?.unwrap_or_else(|| "x".into());
        let vertical = match axis.as_str() {
            "x" => half * fh / fw,
            "y" => half,
            "diagonal" => half * fh / (fw * fw + fh * fh).sqrt(),
            "smaller" => {
                if fw < fh {
                    half * fh / fw
                } else {
                    half
                }
            }
            "larger" => {
                if fw > fh {
                    half * fh / fw
                } else {
                    half
                }
            }
            other => {
                return Err(self
                    .r
                    .error(node, format!("fov_axis `{other}` is not one of x, y, diagonal, smaller, larger")))
            }
        };
        scene.camera = Some(Camera { eye, target: eye + forward, up, fov_deg: 2.0 * vertical.atan().to_degrees() });
        Ok(())
    }
}

/// Loads the Mitsuba scene file at `path`; its materials go into `table`, every file read into
/// `inputs`.
pub fn load_mitsuba(
    path: &Path,
    table: &mut MaterialTable,
    warnings: &mut Vec<String>,
    inputs: &mut Vec<PathBuf>,
) -> Result<MitsubaScene> {
    let text = read_text(path, "a Mitsuba scene file", MAX_SCENE_FILE)?;
    inputs.push(path.to_path_buf());
    // No DTD: entity expansion would let a small file grow without bound, and Mitsuba scenes
    // have none.
    let options = roxmltree::ParsingOptions { allow_dtd: false, ..Default::default() };
    let doc = roxmltree::Document::parse_with_options(&text, options)
        .map_err(|e| Error::parse(path, e.pos().row as usize, format!("XML: {e}")))?;
    let root = doc.root_element();
    if root.tag_name().name() != "scene" {
        return Err(Error::parse(path, 1, format!("the root element is <{}>, not <scene>", root.tag_name().name())));
    }
    let version = root.attribute("version").and_then(|v| v.split('.').next()?.parse().ok()).unwrap_or(0);
    let mut params = HashMap::new();
    for d in root.children().filter(|c| c.tag_name().name() == "default") {
        if let (Some(n), Some(v)) = (d.attribute("name"), d.attribute("value")) {
            params.insert(n.to_string(), v.to_string());
        }
    }
    // Every element with an id, except the <ref id> elements that name them.
    let ids = doc
        .descendants()
        .filter(|n| n.is_element() && n.tag_name().name() != "ref")
        .filter_map(|n| n.attribute("id").map(|id| (id.to_string(), n)))
        .collect();
    let r = Reader { path, doc: &doc, params, read: Default::default(), visited: Default::default() };
    let mut cx = Ctx {
        r,
        version,
        ids,
        table,
        warnings,
        inputs,
        materials: HashMap::new(),
        used_media: Default::default(),
        depth: 0,
    };
    let mut scene =
        MitsubaScene { meshes: Vec::new(), lights: Vec::new(), environment: None, camera: None, size: None };
    for node in root.children().filter(Node::is_element) {
        match node.tag_name().name() {
            "default" | "bsdf" | "texture" | "medium" => {}
            "integrator" => cx.warn(
                node,
                format!("integrator `{}` is replaced by photon mapping", node.attribute("type").unwrap_or("")),
            ),
            "sensor" | "camera" => cx.sensor(node, &mut scene)?,
            "shape" => scene.meshes.extend(cx.shape(node)?),
            "emitter" => cx.emitter(node, &mut scene)?,
            other => cx.warn(node, format!("<{other}> is not read; it is left out")),
        }
    }
    let unused: Vec<Node> =
        root.descendants().filter(|n| n.tag_name().name() == "medium" && !cx.used_media.contains(&n.id())).collect();
    for m in unused {
        cx.warn(m, "this <medium> is no shape's interior: it is not read (participating media are issue 59's)".into());
    }
    for (line, name, element) in cx.r.unread() {
        cx.warnings.push(format!("{}:{line}: `{name}` of {element} is not read", path.display()));
    }
    if scene.meshes.is_empty() && scene.lights.is_empty() && scene.environment.is_none() {
        return Err(Error::parse(path, 0, "the scene has no shape and no emitter photonwave reads"));
    }
    Ok(scene)
}
