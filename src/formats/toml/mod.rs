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
//! [medium]                      # a participating medium filling the scene (path tracer only)
//! sigma_a = [0.01, 0.01, 0.01]  # absorption per scene unit, and
//! sigma_s = [0.1, 0.1, 0.1]     # scattering per scene unit; or albedo = [..] and density = ..
//! g = 0.0                       # Henyey–Greenstein asymmetry in (−1, 1)
//!
//! [[portal]]                    # where the environment's light enters (a window); optional
//! corners = [[-1, 1, -2], [1, 1, -2], [1, 2, -2], [-1, 2, -2]]   # in order around it
//!
//! [materials.sphere]            # replaces the MTL material `sphere`
//! type = "glass"                # lambert | glossy | mirror | glass | rough_conductor | rough_dielectric | rough_plastic
//! ior = 1.5
//! outside_ior = 1.0             # glass only: the medium the normal points into (nested dielectrics)
//!
//! [render]                      # any field of Settings
//! spp = 16
//! ```

pub mod materials;
pub mod meshes;

use super::image::load_texture;
use super::materials::MaterialTable;
use super::{AddedLights, LoadedScene};
use crate::error::{Error, Result};
use crate::files::{read_text, MAX_SCENE_FILE};
use crate::scene::camera::{Camera, DEFAULT_FOV};
use crate::scene::environment::Environment;
use crate::scene::light::Light;
use crate::scene::portal::{Portal, Portals};
use crate::scene::{bounds_of, MeshInput, Scene};
use crate::settings::Settings;
use crate::texture::Encoding;
use glam::Vec3;
use materials::{colour, finite3, MaterialEntry};
use meshes::{Brought, MeshEntry};
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
    portal: Vec<PortalEntry>,
    medium: Option<MediumEntry>,
    #[serde(default)]
    render: Option<Settings>,
}

/// `[medium]`: a homogeneous medium filling the scene, by its coefficients (`sigma_a`,
/// `sigma_s`) or by `albedo` and `density` (σ_s = albedo·density, σ_a = density − σ_s), with
/// the Henyey–Greenstein `g`.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct MediumEntry {
    sigma_a: Option<[f32; 3]>,
    sigma_s: Option<[f32; 3]>,
    albedo: Option<[f32; 3]>,
    density: Option<f32>,
    #[serde(default)]
    g: f32,
}

impl MediumEntry {
    fn to_medium(&self) -> Result<crate::medium::Medium> {
        let (sigma_a, sigma_s) = match (self.sigma_a, self.sigma_s, self.albedo, self.density) {
            (a, s, None, None) if a.is_some() || s.is_some() => {
                (colour("medium.sigma_a", a.unwrap_or([0.0; 3]))?, colour("medium.sigma_s", s.unwrap_or([0.0; 3]))?)
            }
            (None, None, Some(albedo), Some(density)) => {
                let albedo = colour("medium.albedo", albedo)?;
                if albedo.max_element() > 1.0 {
                    return Err(Error::setting("medium.albedo", "must lie in [0, 1] in each channel"));
                }
                if !(density >= 0.0 && density.is_finite()) {
                    return Err(Error::setting("medium.density", "must be a finite number ≥ 0 (σ_t per scene unit)"));
                }
                (Vec3::splat(density) * (Vec3::ONE - albedo), Vec3::splat(density) * albedo)
            }
            _ => {
                return Err(Error::setting(
                    "medium",
                    "give `sigma_a` and/or `sigma_s` (per scene unit), or `albedo` and `density`, not a mix",
                ))
            }
        };
        // σ_a and σ_s are checked above: what is left to refuse is g.
        crate::medium::Medium::new(sigma_a, sigma_s, self.g).map_err(|e| Error::setting("medium.g", e))
    }
}

/// `[[portal]]`: a parallelogram (a window, a door) where the environment's light enters, its
/// four `corners` in order around it.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct PortalEntry {
    corners: [[f32; 3]; 4],
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

/// Loads the TOML scene file at `path`, with the lights `added` gives it besides its own.
pub fn load(path: &Path, added: AddedLights) -> Result<LoadedScene> {
    let bounds = |meshes: &[MeshInput]| bounds_of(meshes.iter().flat_map(|m| m.positions.iter()));
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
    let mut environment = file.environment.as_ref().map(|e| e.to_environment(dir, &mut inputs)).transpose()?;
    if !file.portal.is_empty() {
        let Some(env) = environment.take() else {
            return Err(Error::setting(
                "portal[0]",
                "a portal marks where the [environment]'s light enters, but the scene has no [environment]",
            ));
        };
        let portals = file
            .portal
            .iter()
            .enumerate()
            .map(|(k, p)| {
                Portal::new(p.corners.map(Vec3::from_array))
                    .map_err(|e| Error::setting(format!("portal[{k}].corners"), e))
            })
            .collect::<Result<Vec<_>>>()?;
        environment = Some(env.with_portals(Portals::new(portals)));
    }
    let medium = file.medium.as_ref().map(MediumEntry::to_medium).transpose()?;
    let mut scene = Scene::build_lit(meshes, table.materials, lights, environment, warnings)?;
    if let Some(m) = medium {
        let distant = scene.lights.iter().any(|l| matches!(l, Light::Sun { .. } | Light::Directional { .. }));
        if scene.environment.is_some() || distant {
            scene.warnings.push(
                "the [medium] fills all space, so the light of the environment, suns and directional lights, which \
                 comes from infinitely far, is extinguished in every channel whose σ_t is above 0"
                    .to_string(),
            );
        }
        scene.medium = Some(m);
    }
    Ok(LoadedScene::framed(scene, camera, brought.cameras, settings, inputs))
}
