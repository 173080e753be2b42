//! The TOML scene file: meshes, camera, extra lights, material overrides and render settings.
//!
//! ```toml
//! [[mesh]]
//! file = "cornell-box.obj"      # relative to this file
//! scale = 1.0                   # optional, then
//! translate = [0, 0, 0]         # optional
//!
//! [camera]
//! eye = [0, 1, 3.4]
//! target = [0, 1, 0]
//! up = [0, 1, 0]                # optional
//! fov = 40                      # vertical, degrees; optional (40)
//!
//! [[light]]
//! type = "point"                # point | spot | directional
//! position = [0, 1.5, 0]
//! intensity = [5, 5, 5]         # W/sr
//!
//! [[light]]
//! type = "sun"                  # a distant disk: soft shadows
//! direction = [0.3, -1, -0.2]   # of travel
//! irradiance = [800, 780, 740]  # W/m² on a perpendicular plane
//! angle = 0.27                  # angular radius, degrees
//!
//! [environment]                 # radiance from every direction at infinity
//! radiance = [0.4, 0.5, 0.7]    # a constant, or
//! # map = "sky.exr"             # a lat-long (2:1) linear image, +y up
//! scale = 1.0
//! rotation = 0                  # degrees about +y
//!
//! [materials.sphere]            # replaces the MTL material `sphere`
//! type = "glass"                # lambert | glossy | mirror | glass | rough_conductor | rough_dielectric | rough_plastic
//! ior = 1.5
//! outside_ior = 1.0             # glass only: the medium the normal points into (nested dielectrics)
//!
//! [render]                      # any field of Settings
//! spp = 16
//! ```

use super::camera::{Camera, DEFAULT_FOV};
use super::environment::Environment;
use super::file_materials::{colour, finite3, MaterialEntry};
use super::file_meshes::{Brought, MeshEntry};
use super::image::load_texture;
use super::light::Light;
use super::mitsuba::load_mitsuba;
use super::obj::MaterialTable;
use super::{bounds_of, MeshInput, Scene};
use crate::error::{Error, Result};
use crate::files::{read_text, MAX_SCENE_FILE};
use crate::settings::Settings;
use crate::texture::Encoding;
use glam::Vec3;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    #[serde(default)]
    mesh: Vec<MeshEntry>,
    camera: Option<CameraEntry>,
    #[serde(default)]
    light: Vec<LightEntry>,
    #[serde(default)]
    materials: BTreeMap<String, MaterialEntry>,
    environment: Option<EnvironmentEntry>,
    #[serde(default)]
    render: Option<Settings>,
}

/// `[environment]`: a constant `radiance`, or a lat-long `map` (linear HDR, EXR or any image
/// format textures take), times `scale`, turned `rotation` degrees about +y.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct EnvironmentEntry {
    #[serde(default)]
    radiance: Option<[f32; 3]>,
    #[serde(default)]
    map: Option<PathBuf>,
    #[serde(default = "one")]
    scale: f32,
    #[serde(default)]
    rotation: f32,
}

fn sun_angle() -> f32 {
    0.27
}

fn one() -> f32 {
    1.0
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct CameraEntry {
    eye: [f32; 3],
    target: [f32; 3],
    #[serde(default = "y_up")]
    up: [f32; 3],
    #[serde(default = "default_fov")]
    fov: f32,
}

fn default_fov() -> f32 {
    DEFAULT_FOV
}

fn y_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Deserialize, Debug)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
enum LightEntry {
    Point {
        position: [f32; 3],
        intensity: [f32; 3],
    },
    Spot {
        position: [f32; 3],
        target: [f32; 3],
        intensity: [f32; 3],
        angle: f32,
        #[serde(default)]
        inner_angle: Option<f32>,
    },
    Directional {
        direction: [f32; 3],
        irradiance: [f32; 3],
    },
    Sun {
        direction: [f32; 3],
        irradiance: [f32; 3],
        /// Angular radius, degrees (the real sun's: 0.27).
        #[serde(default = "sun_angle")]
        angle: f32,
    },
}

/// A loaded scene with what its file said about the camera and settings.
pub struct LoadedScene {
    /// The assembled scene.
    pub scene: Scene,
    /// Camera from the file, if it had one: the TOML `[camera]`, else the first a glTF file
    /// brings; in the scene's frame ([`Scene::to_frame`]).
    pub camera: Option<Camera>,
    /// The named cameras mesh files bring (glTF), for `--camera NAME`; in the scene's frame.
    pub cameras: Vec<(String, Camera)>,
    /// Settings from the file's `[render]` table (defaults otherwise).
    pub settings: Settings,
    /// Every file read: the scene file, its OBJ and MTL files (outputs must not overwrite them).
    pub inputs: Vec<PathBuf>,
}

impl LoadedScene {
    /// The loaded scene with its file's cameras (given in the file's coordinates) moved into the
    /// scene's frame.
    fn framed(
        scene: Scene,
        camera: Option<Camera>,
        cameras: Vec<(String, Camera)>,
        settings: Settings,
        inputs: Vec<PathBuf>,
    ) -> LoadedScene {
        let camera = camera.map(|c| scene.camera_to_frame(c));
        let cameras = cameras.into_iter().map(|(name, c)| (name, scene.camera_to_frame(c))).collect();
        LoadedScene { scene, camera, cameras, settings, inputs }
    }
}

impl LightEntry {
    fn to_light(&self, i: usize) -> Result<Light> {
        let f = |name: &str| format!("light[{i}].{name}");
        Ok(match *self {
            LightEntry::Point { position, intensity } => Light::Point {
                position: finite3(&f("position"), position)?,
                intensity: colour(&f("intensity"), intensity)?,
            },
            LightEntry::Spot { position, target, intensity, angle, inner_angle } => {
                let position = finite3(&f("position"), position)?;
                let direction = (finite3(&f("target"), target)? - position)
                    .try_normalize()
                    .ok_or_else(|| Error::setting(f("target"), "must differ from position"))?;
                if !(angle > 0.0 && angle < 180.0) {
                    return Err(Error::setting(f("angle"), "half-angle of the cone must be in (0, 180) degrees"));
                }
                let inner = inner_angle.unwrap_or(angle);
                if !(inner > 0.0 && inner <= angle) {
                    return Err(Error::setting(f("inner_angle"), "must be in (0, angle]"));
                }
                Light::Spot {
                    position,
                    direction,
                    intensity: colour(&f("intensity"), intensity)?,
                    cos_inner: inner.to_radians().cos(),
                    cos_outer: angle.to_radians().cos(),
                }
            }
            LightEntry::Directional { direction, irradiance } => Light::Directional {
                direction: finite3(&f("direction"), direction)?
                    .try_normalize()
                    .ok_or_else(|| Error::setting(f("direction"), "must not be zero"))?,
                irradiance: colour(&f("irradiance"), irradiance)?,
            },
            LightEntry::Sun { direction, irradiance, angle } => {
                if !(0.05..=45.0).contains(&angle) {
                    return Err(Error::setting(
                        f("angle"),
                        "the sun's angular radius must be in [0.05, 45] degrees (the real sun's is 0.27; for a \
                         point-like sun use type = \"directional\")",
                    ));
                }
                let half = (angle * 0.5).to_radians().sin();
                Light::Sun {
                    direction: finite3(&f("direction"), direction)?
                        .try_normalize()
                        .ok_or_else(|| Error::setting(f("direction"), "must not be zero"))?,
                    irradiance: colour(&f("irradiance"), irradiance)?,
                    one_minus_cos: 2.0 * half * half,
                }
            }
        })
    }
}

impl EnvironmentEntry {
    /// The environment this entry describes; a map is read relative to `dir` and added to
    /// `inputs`.
    fn to_environment(&self, dir: &Path, inputs: &mut Vec<PathBuf>) -> Result<Environment> {
        if !(self.scale >= 0.0 && self.scale.is_finite()) {
            return Err(Error::setting("environment.scale", "must be a finite number ≥ 0"));
        }
        if !self.rotation.is_finite() {
            return Err(Error::setting("environment.rotation", "must be a finite number of degrees"));
        }
        match (&self.radiance, &self.map) {
            (Some(_), Some(_)) => {
                Err(Error::setting("environment", "give `radiance` (a constant) or `map` (a lat-long image), not both"))
            }
            (None, None) => Err(Error::setting("environment", "needs `radiance = [r, g, b]` or `map = \"sky.exr\"`")),
            (Some(l), None) => Ok(Environment::constant(colour("environment.radiance", *l)? * self.scale)),
            (None, Some(file)) => {
                let path = dir.join(file);
                let map = load_texture(&path, Encoding::Linear, "an environment map").map_err(|e| match e {
                    Error::Io { path, message } => {
                        Error::Io { path, message: format!("{message} (named by `environment.map`)") }
                    }
                    Error::Parse { path, line, message } => {
                        Error::Parse { path, line, message: format!("{message} (named by `environment.map`)") }
                    }
                    other => other,
                })?;
                inputs.push(path);
                Environment::from_map(map, self.scale, self.rotation.to_radians())
                    .map_err(|e| Error::setting("environment.map", e))
            }
        }
    }
}

/// The extensions of mesh files that load as scenes by themselves.
const MESH_FORMATS: [&str; 4] = ["obj", "ply", "gltf", "glb"];

/// Loads a scene: a `.toml` scene file, a Mitsuba scene file (`.xml`), or a bare mesh file (OBJ
/// with its MTL files, PLY, glTF or GLB).
pub fn load_scene(path: &Path) -> Result<LoadedScene> {
    load_scene_lit(path, &|_, _| Vec::new())
}

/// Lights added to a scene once its meshes' bounds and its file's camera are known (the CLI's
/// `--light` presets, for meshes that bring no light of their own).
pub type AddedLights<'a> = &'a dyn Fn((Vec3, Vec3), Option<Camera>) -> Vec<Light>;

/// Loads a scene as [`load_scene`] does, with the lights `added` gives it besides its own.
pub fn load_scene_lit(path: &Path, added: AddedLights) -> Result<LoadedScene> {
    let bounds = |meshes: &[MeshInput]| bounds_of(meshes.iter().flat_map(|m| m.positions.iter()));
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    if ext == "xml" {
        let (mut table, mut warnings, mut inputs) = (MaterialTable::default(), Vec::new(), Vec::new());
        let m = load_mitsuba(path, &mut table, &mut warnings, &mut inputs)?;
        let mut lights = m.lights;
        lights.extend(added(bounds(&m.meshes), m.camera));
        let scene = Scene::build_lit(m.meshes, table.materials, lights, m.environment, warnings)?;
        let mut settings = Settings::default();
        if let Some((width, height)) = m.size {
            (settings.width, settings.height) = (width, height);
        }
        return Ok(LoadedScene::framed(scene, m.camera, Vec::new(), settings, inputs));
    }
    if MESH_FORMATS.contains(&ext.as_str()) {
        // A bare mesh file: its own camera and lights if it brings them, `added` besides.
        let (mut table, mut warnings, mut inputs, mut brought) =
            (MaterialTable::default(), Vec::new(), Vec::new(), Brought::default());
        let dir = path.parent().unwrap_or(Path::new("."));
        let name = PathBuf::from(path.file_name().unwrap_or_default());
        let meshes =
            vec![MeshEntry::of_file(name).load(0, dir, None, &mut table, &mut warnings, &mut inputs, &mut brought)?];
        let camera = brought.cameras.first().map(|c| c.1);
        let mut lights = brought.lights;
        lights.extend(added(bounds(&meshes), camera));
        let scene = Scene::build(meshes, table.materials, lights, warnings)?;
        let (settings, cameras) = (Settings::default(), brought.cameras);
        return Ok(LoadedScene::framed(scene, camera, cameras, settings, inputs));
    }
    let text = read_text(path, "a scene file", MAX_SCENE_FILE)?;
    let mut inputs = vec![path.to_path_buf()];
    let file: SceneFile = toml::from_str(&text).map_err(|e| {
        let line = e.span().map_or(0, |s| text[..s.start.min(text.len())].lines().count().max(1));
        Error::parse(path, line, e.message().to_string())
    })?;
    if file.mesh.is_empty() && file.light.is_empty() && file.environment.is_none() {
        return Err(Error::parse(path, 0, "the scene file names no [[mesh]] and no [[light]]"));
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut table = MaterialTable::default();
    let mut warnings = Vec::new();
    let mut meshes: Vec<MeshInput> = Vec::new();
    let mut brought = Brought::default();
    // Materials `[[mesh]]` entries name, each added to the table once.
    let mut named: BTreeMap<&str, u32> = BTreeMap::new();
    for (i, m) in file.mesh.iter().enumerate() {
        let material = match m.material.as_deref() {
            None => None,
            Some(name) => Some(match named.get(name) {
                Some(&id) => id,
                None => {
                    let entry = file.materials.get(name).ok_or_else(|| {
                        Error::setting(
                            format!("mesh[{i}].material"),
                            format!("names `{name}`, but there is no [materials.{name}]"),
                        )
                    })?;
                    let id = table.insert(path, entry.to_material(name)?, &mut Vec::new());
                    named.insert(name, id);
                    id
                }
            }),
        };
        meshes.push(m.load(i, dir, material, &mut table, &mut warnings, &mut inputs, &mut brought)?);
    }
    for (name, entry) in &file.materials {
        if table.replace_named(name, &entry.to_material(name)?) == 0 {
            return Err(Error::setting(format!("materials.{name}"), "no mesh uses a material of that name"));
        }
    }
    let mut lights = file.light.iter().enumerate().map(|(i, l)| l.to_light(i)).collect::<Result<Vec<_>>>()?;
    lights.extend(brought.lights);
    let camera = file
        .camera
        .map(|c| Camera {
            eye: Vec3::from_array(c.eye),
            target: Vec3::from_array(c.target),
            up: Vec3::from_array(c.up),
            fov_deg: c.fov,
        })
        .or_else(|| brought.cameras.first().map(|c| c.1));
    if !meshes.is_empty() {
        lights.extend(added(bounds(&meshes), camera));
    }
    let settings = file.render.unwrap_or_default();
    settings.validate()?;
    let environment = file.environment.as_ref().map(|e| e.to_environment(dir, &mut inputs)).transpose()?;
    let scene = Scene::build_lit(meshes, table.materials, lights, environment, warnings)?;
    Ok(LoadedScene::framed(scene, camera, brought.cameras, settings, inputs))
}

/// A camera that frames the bounding sphere of the scene's triangles from +z, looking down −z, for an image of
/// `aspect` = width / height: the sphere fits the narrower of the two fields of view.
#[must_use]
pub fn fitted_camera(scene: &Scene, fov_deg: f32, aspect: f32) -> Camera {
    fitted_camera_to(scene.mesh_bounds(), fov_deg, aspect)
}

/// [`fitted_camera`] for a bounding box (lo, hi).
#[must_use]
pub fn fitted_camera_to((lo, hi): (Vec3, Vec3), fov_deg: f32, aspect: f32) -> Camera {
    let c = (lo + hi) * 0.5;
    let r = ((hi - lo) * 0.5).length().max(f32::MIN_POSITIVE);
    let half_v = fov_deg.to_radians() * 0.5;
    let half = if aspect >= 1.0 { half_v } else { (half_v.tan() * aspect).atan() };
    let dist = r / half.sin() * 1.05;
    Camera { eye: c + Vec3::Z * dist, target: c, up: Vec3::Y, fov_deg }
}
