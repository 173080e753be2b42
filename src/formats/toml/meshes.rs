//! The TOML scene file's `[[mesh]]` entries: a mesh file (OBJ with its MTL files, PLY, glTF) or a
//! built-in shape ([`crate::formats::shapes`]), placed by a transform (a `matrix`, or `scale`, `rotate`
//! and `translate` applied in that order) and optionally made of one material of the file's
//! `[materials]` (`material = "NAME"`, replacing whatever the mesh file says).
//!
//! Reads the entry; writes [`MeshInput`]s into the scene's list and materials into its
//! [`MaterialTable`], and the lights and cameras a glTF file brings into `Brought`.

use super::materials::finite3;
use crate::error::{Error, Result};
use crate::formats::gltf::load_gltf;
use crate::formats::materials::MaterialTable;
use crate::formats::obj::{load_obj, ObjMaterials};
use crate::formats::ply::load_ply;
use crate::formats::shapes::shape;
use crate::formats::transform::Transform;
use crate::formats::Format;
use crate::scene::camera::Camera;
use crate::scene::light::Light;
use crate::scene::MeshInput;
use glam::{Affine3A, Quat, Vec3};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A `[[mesh]]` table.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(in crate::formats) struct MeshEntry {
    /// An OBJ, PLY, glTF or GLB file, relative to the scene file.
    #[serde(default)]
    file: Option<PathBuf>,
    /// A built-in shape instead of a file.
    #[serde(default)]
    shape: Option<String>,
    /// A `[materials.NAME]` every face of the mesh is made of.
    #[serde(default)]
    pub(in crate::formats) material: Option<String>,
    /// A number (uniform) or three (per axis).
    #[serde(default)]
    scale: Option<Scale>,
    /// An axis and an angle in degrees: `[x, y, z, degrees]`.
    #[serde(default)]
    rotate: Option<[f32; 4]>,
    #[serde(default)]
    translate: Option<[f32; 3]>,
    /// A 4×4 affine matrix, row by row (instead of scale, rotate and translate).
    #[serde(default)]
    matrix: Option<[f32; 16]>,
}

#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(untagged)]
enum Scale {
    Uniform(f32),
    Axes([f32; 3]),
}

/// What mesh files bring besides their triangles: a glTF file's lights and cameras.
#[derive(Default)]
pub(in crate::formats) struct Brought {
    /// Lights, in world space.
    pub lights: Vec<Light>,
    /// Cameras with their names, in world space.
    pub cameras: Vec<(String, Camera)>,
}

impl MeshEntry {
    /// An entry for the file `file` alone, untransformed.
    pub(in crate::formats) fn of_file(file: PathBuf) -> MeshEntry {
        MeshEntry {
            file: Some(file),
            shape: None,
            material: None,
            scale: None,
            rotate: None,
            translate: None,
            matrix: None,
        }
    }

    /// The transform this entry gives its mesh; `i` is its index in the file.
    pub(in crate::formats) fn transform(&self, i: usize) -> Result<Transform> {
        let field = |name: &str| format!("mesh[{i}].{name}");
        if let Some(rows) = &self.matrix {
            if self.scale.is_some() || self.rotate.is_some() || self.translate.is_some() {
                return Err(Error::setting(
                    field("matrix"),
                    "give a `matrix` or `scale`, `rotate` and `translate`, not both",
                ));
            }
            return Transform::from_rows(&field("matrix"), rows);
        }
        let scale = match self.scale {
            None => Vec3::ONE,
            Some(Scale::Uniform(s)) => Vec3::splat(s),
            Some(Scale::Axes(s)) => Vec3::from_array(s),
        };
        if !(scale.is_finite() && scale.min_element() > 0.0) {
            return Err(Error::setting(field("scale"), "must be positive numbers (mirror with a `matrix`)"));
        }
        let rotation = match self.rotate {
            None => Quat::IDENTITY,
            Some([x, y, z, degrees]) => {
                let axis = Vec3::new(x, y, z).try_normalize().filter(|_| degrees.is_finite()).ok_or_else(|| {
                    Error::setting(field("rotate"), "is [x, y, z, degrees]: a non-zero axis and a finite angle")
                })?;
                Quat::from_axis_angle(axis, degrees.to_radians())
            }
        };
        let translate = finite3(&field("translate"), self.translate.unwrap_or_default())?;
        if self.scale.is_none() && self.rotate.is_none() {
            // Exactly the positions the original scale-then-translate gave (no rounding change).
            return Ok(Transform::scale_translate(1.0, translate));
        }
        let named = if self.rotate.is_some() { "rotate" } else { "scale" };
        Transform::checked(&field(named), Affine3A::from_scale_rotation_translation(scale, rotation, translate))
    }

    /// Loads this entry's mesh (relative to `dir`), of material `material` when the entry names
    /// one; materials read go into `table`, every file read into `inputs`.
    #[allow(clippy::too_many_arguments)]
    pub(in crate::formats) fn load(
        &self,
        i: usize,
        dir: &Path,
        material: Option<u32>,
        table: &mut MaterialTable,
        warnings: &mut Vec<String>,
        inputs: &mut Vec<PathBuf>,
        brought: &mut Brought,
    ) -> Result<MeshInput> {
        let transform = self.transform(i)?;
        let fallback = |what: &str, table: &mut MaterialTable, warnings: &mut Vec<String>| {
            material.unwrap_or_else(|| {
                warnings.push(format!(
                    "mesh[{i}] ({what}) names no `material`: it is grey Lambertian (Kd 0.8); add `material = \"NAME\"` and \
                     a [materials.NAME] table"
                ));
                table.default_material()
            })
        };
        let mut mesh = match (&self.file, &self.shape) {
            (Some(_), Some(_)) => {
                return Err(Error::setting(format!("mesh[{i}]"), "give a `file` or a `shape`, not both"));
            }
            (None, None) => return Err(Error::setting(format!("mesh[{i}]"), "needs a `file` or a `shape`")),
            (None, Some(name)) => {
                let m = fallback(&format!("a {name}"), table, warnings);
                let mut mesh = shape(name, &format!("mesh[{i}].shape"), m)?;
                transform.apply(&mut mesh);
                mesh
            }
            (Some(file), None) => {
                let path = dir.join(file);
                // A file without an extension is read as OBJ, as before other formats.
                let format = if path.extension().is_none() { Some(Format::Obj) } else { Format::of(&path) };
                match format {
                    Some(Format::Obj) => {
                        let from = material.map_or(ObjMaterials::Mtl, ObjMaterials::All);
                        load_obj(&path, &transform, from, table, warnings, inputs)?
                    }
                    Some(Format::Ply) => {
                        let what = format!("{}, a PLY file, which has no materials", file.display());
                        let m = fallback(&what, table, warnings);
                        let mut mesh = load_ply(&path, m, warnings, inputs)?;
                        transform.apply(&mut mesh);
                        mesh
                    }
                    Some(Format::Gltf) => {
                        let model = load_gltf(&path, &transform, table, warnings, inputs)?;
                        brought.lights.extend(model.lights);
                        brought.cameras.extend(model.cameras);
                        model.mesh
                    }
                    _ => {
                        return Err(Error::setting(
                            format!("mesh[{i}].file"),
                            format!("{}: not a mesh format photonwave reads ({})", file.display(), Format::MESH_NAMES),
                        ))
                    }
                }
            }
        };
        if let Some(m) = material {
            mesh.material.fill(m);
        }
        if let Some((k, p)) = crate::scene::first_out_of_range(&mesh.positions) {
            let at = format!("mesh[{i}] ({}, vertex {})", mesh.source, k + 1);
            return Err(Error::setting(at, crate::scene::out_of_range_message(p)));
        }
        Ok(mesh)
    }
}
