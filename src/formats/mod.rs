//! Scene files in, a [`LoadedScene`] out: one entry point ([`load_scene`]) and one table of
//! formats by extension ([`Format`]) over the readers — the TOML scene file ([`toml`]), Mitsuba
//! XML ([`mitsuba`]), and the mesh files a scene names or that load by themselves: OBJ with its
//! MTL files ([`obj`]), PLY ([`ply`]), glTF and GLB ([`gltf`]); with the built-in shapes
//! ([`shapes`]), the placement every reader applies ([`transform`]), image files ([`image`]), the
//! material table every reader fills ([`materials`]) and scenes generated in code
//! ([`generated`]). Every reader produces the same [`MeshInput`]s, [`Material`]s and lights, so
//! the scene model ([`crate::scene`]) never knows which format a scene came from.
//!
//! [`Material`]: crate::material::Material

pub mod generated;
pub mod gltf;
pub mod image;
pub mod materials;
pub mod mitsuba;
pub mod obj;
pub mod ply;
pub mod shapes;
pub mod toml;
pub mod transform;

use crate::error::Result;
use crate::scene::camera::Camera;
use crate::scene::light::Light;
use crate::scene::{bounds_of, MeshInput, Scene};
use crate::settings::Settings;
use glam::Vec3;
use materials::MaterialTable;
use mitsuba::load_mitsuba;
use std::path::{Path, PathBuf};
use toml::meshes::{Brought, MeshEntry};

/// The formats photonwave reads, by file extension (case-insensitive): the one table every
/// reader is chosen from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// A TOML scene file (`.toml`; any extension not listed here is read as one).
    Toml,
    /// A Mitsuba scene file (`.xml`).
    Mitsuba,
    /// Wavefront OBJ (`.obj`), with its MTL files; a `[[mesh]]` file without an extension too.
    Obj,
    /// PLY, ASCII or binary (`.ply`).
    Ply,
    /// glTF 2.0, JSON or binary (`.gltf`, `.glb`).
    Gltf,
}

impl Format {
    /// The mesh formats, as messages list them.
    pub const MESH_NAMES: &'static str = "`.obj`, `.ply`, `.gltf` or `.glb`";

    /// The format of `path` by its extension; `None` for one not in the table (a scene file
    /// treats it as TOML, a `[[mesh]]` entry refuses it).
    #[must_use]
    pub fn of(path: &Path) -> Option<Format> {
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        Some(match ext.as_str() {
            "toml" => Format::Toml,
            "xml" => Format::Mitsuba,
            "obj" => Format::Obj,
            "ply" => Format::Ply,
            "gltf" | "glb" => Format::Gltf,
            _ => return None,
        })
    }

    /// Whether this is a mesh format (one that a `[[mesh]]` entry names, or that loads as a
    /// scene by itself).
    #[must_use]
    pub fn is_mesh(self) -> bool {
        matches!(self, Format::Obj | Format::Ply | Format::Gltf)
    }
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
    let (clock, textures) = (std::time::Instant::now(), image::texture_seconds());
    let mut loaded = read_scene(path, added)?;
    // Whatever the scene's build did not count was reading the files (textures apart).
    let t = &mut loaded.scene.load_times;
    t.textures_s = image::texture_seconds() - textures;
    let built = t.triangles_s + t.bvh_s + t.lights_s + t.topology_s;
    t.parse_s = (clock.elapsed().as_secs_f64() - built - t.textures_s).max(0.0);
    Ok(loaded)
}

/// [`load_scene_lit`] without its load times' reading parts.
fn read_scene(path: &Path, added: AddedLights) -> Result<LoadedScene> {
    let bounds = |meshes: &[MeshInput]| bounds_of(meshes.iter().flat_map(|m| m.positions.iter()));
    let format = Format::of(path);
    if format == Some(Format::Mitsuba) {
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
    if format.is_some_and(Format::is_mesh) {
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
    toml::load(path, added)
}
