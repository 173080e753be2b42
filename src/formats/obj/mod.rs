//! OBJ input through tobj, with materials from the MTL files it names ([`mtl`]).
//!
//! The text is read by [`crate::files::read_text`] (regular files only, bounded size, no
//! byte-order mark, any line ends), checked line by line ([`check_obj`]) and handed to tobj.
//! `mtllib` may name several files on one line, as the spec allows (a name with spaces is taken
//! whole when such a file exists). Materials are kept per MTL file: two files may each define
//! `floor`, and each mesh gets its own file's.

pub mod mtl;
pub mod validate;

use crate::error::{Error, Result};
use crate::files::{read_text, MAX_MATERIAL_FILE, MAX_MESH_FILE};
use crate::formats::materials::MaterialTable;
use crate::formats::transform::Transform;
use crate::geometry::in_range;
use crate::material::{AlphaMode, Bsdf, Maps, NormalMap, Opacity, Relief};
use crate::scene::{first_out_of_range, out_of_range_message, MeshInput};
use crate::texture::{Encoding, Texture};
use glam::{Vec2, Vec3};
use mtl::{material_from_mtl, parse_mtl, MtlMaterial};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use validate::{check_obj, MtlLib};

impl MaterialTable {
    /// The textures the MTL material `m` of the file `mtl_path` names, read (or taken from those
    /// read before); each file read is added to `inputs`. An image that cannot be read is an
    /// error naming it and the MTL statement.
    pub fn load_maps(&mut self, mtl_path: &Path, m: &MtlMaterial, inputs: &mut Vec<PathBuf>) -> Result<Maps> {
        let mut load = |key: &str, encoding: Encoding| {
            self.load_statement(mtl_path, m, key, encoding, &format!("a `{key}` texture"), inputs)
        };
        Ok(Maps {
            kd: load("map_Kd", Encoding::Srgb)?,
            ks: load("map_Ks", Encoding::Srgb)?,
            roughness: load("map_Pr", Encoding::Linear)?,
            ke: load("map_Ke", Encoding::Srgb)?,
            metallic: load("map_Pm", Encoding::Linear)?,
        })
    }

    /// The height field of a material's `bump` (or `map_Bump`) statement, its `-bm` as the
    /// scale ([`Relief::Heights`]); an image that cannot be read is an error naming it and the
    /// statement.
    pub fn load_bump(
        &mut self,
        mtl_path: &Path,
        m: &MtlMaterial,
        inputs: &mut Vec<PathBuf>,
    ) -> Result<Option<NormalMap>> {
        let Some(scale) = m.map("bump").map(|st| st.scale) else { return Ok(None) };
        let texture = self.load_statement(mtl_path, m, "bump", Encoding::Linear, "a `bump` height map", inputs)?;
        Ok(texture.map(|texture| NormalMap { texture, relief: Relief::Heights, scale, handed: false }))
    }

    /// The cut-out of a material's dissolve: `d` (or 1 − `Tr`) times its `map_d` (the image's
    /// alpha channel, or its grey level without one), read as coverage ([`Opacity`]); `None`
    /// where it is opaque everywhere.
    pub fn load_opacity(
        &mut self,
        mtl_path: &Path,
        m: &MtlMaterial,
        inputs: &mut Vec<PathBuf>,
    ) -> Result<Option<Opacity>> {
        let texture = self.load_statement(mtl_path, m, "map_d", Encoding::Opacity, "a `map_d` opacity", inputs)?;
        let opacity = Opacity { texture, factor: m.dissolve().unwrap_or(1.0), mode: AlphaMode::Coverage };
        Ok((!opacity.is_opaque()).then_some(opacity))
    }

    /// The image of material `m`'s map statement `key` (`None` without one), read as `what` in
    /// `encoding`; an image that cannot be read is an error naming it and the statement.
    fn load_statement(
        &mut self,
        mtl_path: &Path,
        m: &MtlMaterial,
        key: &str,
        encoding: Encoding,
        what: &str,
        inputs: &mut Vec<PathBuf>,
    ) -> Result<Option<Arc<Texture>>> {
        let Some(st) = m.map(key) else { return Ok(None) };
        let dir = mtl_path.parent().unwrap_or(Path::new("."));
        let texture = self.texture(&dir.join(&st.file), encoding, what, inputs).map_err(|e| {
            named_by_statement(e, &format!("`{key}` of material `{}` at {}:{}", m.name, mtl_path.display(), st.line))
        })?;
        Ok(Some(texture))
    }
}

/// The files an `mtllib` statement names: its whole text when a file of that name exists
/// (names with spaces), else each word.
fn mtllib_files(dir: &Path, lib: &MtlLib) -> Vec<PathBuf> {
    if dir.join(&lib.names).is_file() {
        vec![PathBuf::from(&lib.names)]
    } else {
        lib.names.split_whitespace().map(PathBuf::from).collect()
    }
}

/// `e` with "(named by STATEMENT)" added, for an image file that cannot be read.
fn named_by_statement(e: Error, statement: &str) -> Error {
    match e {
        Error::Io { path, message } => Error::Io { path, message: format!("{message} (named by {statement})") },
        Error::Parse { path, line, message } => {
            Error::Parse { path, line, message: format!("{message} (named by {statement})") }
        }
        other => other,
    }
}

/// `e` with "(named by OBJ:LINE)" added, for an MTL file that cannot be read.
fn named_by(e: Error, obj: &Path, line: usize) -> Error {
    match e {
        Error::Io { path, message } => {
            Error::Io { path, message: format!("{message} (named by `mtllib` at {}:{line})", obj.display()) }
        }
        other => other,
    }
}

/// The error for the first `v` statement of `text` that lies outside ±[`crate::geometry::MAX_COORDINATE`] once
/// transformed (tobj reorders vertices, so the file is read again for its line).
fn out_of_range(path: &Path, text: &str, transform: &Transform) -> Error {
    let first = text.lines().enumerate().find_map(|(i, line)| {
        let mut words = line.split_whitespace();
        if words.next() != Some("v") {
            return None;
        }
        let xyz: Vec<f32> = words.take(3).filter_map(|w| w.parse().ok()).collect();
        let p = transform.point(Vec3::from_slice(&xyz));
        (!in_range(p)).then_some((i + 1, p))
    });
    let (line, p) = first.unwrap_or((0, Vec3::splat(f32::INFINITY)));
    Error::parse(path, line, out_of_range_message(p))
}

/// The name tobj is given for the one material library photonwave hands it (all of the OBJ's
/// MTL files, already read and checked).
const ALL_MATERIALS: &str = "\u{1}photonwave-materials";

/// Where an OBJ mesh's materials come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ObjMaterials {
    /// From the MTL files its `mtllib` statements name, by `usemtl`.
    Mtl,
    /// Every face is this material of the table (a scene file's `material = "NAME"`, a Mitsuba
    /// shape's BSDF): the MTL files are not read.
    All(u32),
}

/// Loads an OBJ file (and the MTL files it names, unless `materials` says otherwise) into a
/// mesh; materials go into `table`. `transform` places it ([`Transform::apply`]). Every file
/// read is added to `inputs`.
pub fn load_obj(
    path: &Path,
    transform: &Transform,
    materials: ObjMaterials,
    table: &mut MaterialTable,
    warnings: &mut Vec<String>,
    inputs: &mut Vec<PathBuf>,
) -> Result<MeshInput> {
    let text = read_text(path, "a mesh (OBJ)", MAX_MESH_FILE)?;
    inputs.push(path.to_path_buf());
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut mtl: Vec<(PathBuf, MtlMaterial)> = Vec::new();
    let libs = check_obj(path, &text)?;
    for lib in libs.iter().filter(|_| materials == ObjMaterials::Mtl) {
        for file in mtllib_files(dir, lib) {
            let mtl_path = dir.join(file);
            let mtl_text = read_text(&mtl_path, "a material file (MTL)", MAX_MATERIAL_FILE)
                .map_err(|e| named_by(e, path, lib.line))?;
            inputs.push(mtl_path.clone());
            mtl.extend(parse_mtl(&mtl_path, &mtl_text, warnings)?.into_iter().map(|m| (mtl_path.clone(), m)));
        }
    }
    // tobj is given the checked text and one material library holding every MTL file's
    // materials in order (a later file's material of the same name wins, as in tobj).
    let names: Vec<tobj::Material> =
        mtl.iter().map(|(_, m)| tobj::Material { name: m.name.clone(), ..Default::default() }).collect();
    let index: HashMap<String, usize> = mtl.iter().enumerate().map(|(i, (_, m))| (m.name.clone(), i)).collect();
    let options = tobj::LoadOptions { single_index: true, triangulate: true, ..Default::default() };
    let header = format!("mtllib {ALL_MATERIALS}\n");
    let mut reader = std::io::Read::chain(header.as_bytes(), text.as_bytes());
    let (models, _) = tobj::load_obj_buf(&mut reader, &options, |lib| {
        if lib == Path::new(ALL_MATERIALS) {
            Ok((names.clone(), index.clone()))
        } else {
            Ok((Vec::new(), HashMap::new()))
        }
    })
    .map_err(|e| Error::parse(path, 0, format!("OBJ: {e}")))?;
    let mut ids = Vec::with_capacity(mtl.len());
    for (file, m) in &mtl {
        let mut material = material_from_mtl(m, file, warnings);
        material.maps = table.load_maps(file, m, inputs)?;
        material.normal_map = table.load_bump(file, m, inputs)?;
        material.opacity = table.load_opacity(file, m, inputs)?;
        // A PBR metal's colour is its `Kd`: so is its texture's.
        if m.pm.is_some_and(|p| p >= 0.5) && material.maps.ks.is_none() {
            material.maps.ks = material.maps.kd.take();
        }
        // With a metallic map the material stores photons everywhere (its metal parts at least at
        // the photon threshold's roughness): one photon class per material.
        if material.maps.metallic.is_some() {
            if let Bsdf::RoughConductor { alpha, .. } = &mut material.bsdf {
                *alpha = alpha.with_width(alpha.width().max(crate::material::PHOTON_SPECULAR_ALPHA));
            }
        }
        ids.push(table.insert(file, material, warnings));
    }

    let mut mesh = MeshInput { source: path.display().to_string(), ..Default::default() };
    let mut any_normals = false;
    let mut any_texcoords = false;
    let mut missing_material = false;
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        let has_normals = !m.normals.is_empty() && m.normals.len() == m.positions.len();
        any_normals |= has_normals;
        let has_texcoords = !m.texcoords.is_empty() && m.texcoords.len() / 2 == m.positions.len() / 3;
        any_texcoords |= has_texcoords;
        mesh.texcoords.extend((0..m.positions.len() / 3).map(|k| {
            if has_texcoords {
                Vec2::new(m.texcoords[2 * k], m.texcoords[2 * k + 1])
            } else {
                Vec2::ZERO
            }
        }));
        for (k, p) in m.positions.chunks_exact(3).enumerate() {
            mesh.positions.push(Vec3::new(p[0], p[1], p[2]));
            mesh.normals.push(if has_normals {
                let n = Vec3::new(m.normals[3 * k], m.normals[3 * k + 1], m.normals[3 * k + 2]);
                if n.try_normalize().is_none() {
                    mesh.zero_normals += 1;
                    Vec3::ZERO
                } else {
                    n
                }
            } else {
                Vec3::ZERO
            });
        }
        let material = match (materials, m.material_id) {
            (ObjMaterials::All(id), _) => id,
            (_, Some(i)) if i < ids.len() => ids[i],
            _ => {
                missing_material = true;
                table.default_material()
            }
        };
        for t in m.indices.chunks_exact(3) {
            mesh.triangles.push([base + t[0], base + t[1], base + t[2]]);
            mesh.material.push(material);
        }
    }
    if !any_normals {
        mesh.normals.clear();
    }
    if !any_texcoords {
        mesh.texcoords.clear();
    }
    transform.apply(&mut mesh);
    if first_out_of_range(&mesh.positions).is_some() {
        return Err(out_of_range(path, &text, transform));
    }
    if mesh.zero_normals > 0 {
        warnings.push(format!(
            "{}: {} vertex normals have zero length; faces shade with their geometric normal there",
            path.display(),
            mesh.zero_normals
        ));
    }
    if missing_material {
        warnings.push(format!("{}: faces without a known material are grey Lambertian (Kd 0.8)", path.display()));
    }
    if mesh.triangles.is_empty() {
        return Err(Error::parse(path, 0, "the file has no triangles"));
    }
    Ok(mesh)
}
