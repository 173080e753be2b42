//! OBJ and MTL input through tobj, and the MTL → material mapping (documented in README):
//!
//! | MTL | material |
//! |---|---|
//! | `Ke` ≠ 0 | area emitter with radiance `Ke` from the front (counter-clockwise) face, plus the scattering below |
//! | `illum` 3 or 5 | perfect mirror, reflectance `Ks` (1 if absent) |
//! | `illum` 4, 6 or 7 | smooth clear dielectric, IOR `Ni` (1.5 if absent), exact Fresnel |
//! | `illum` 2 with `Ks` > 0 | Lambertian `Kd` + normalised Phong lobe `Ks`, exponent `Ns`; scaled so Kd + Ks ≤ 1 |
//! | otherwise | Lambertian `Kd` (0.8 grey if absent) |

use super::validate::{check_mtl, check_obj};
use super::MeshInput;
use crate::error::{Error, Result};
use crate::material::{Bsdf, Material};
use glam::Vec3;
use std::collections::HashMap;
use std::path::Path;

/// Materials of all loaded files, by name (later files' materials of the same name win).
#[derive(Default, Debug)]
pub struct MaterialTable {
    /// The table.
    pub materials: Vec<Material>,
    /// Name → index.
    pub by_name: HashMap<String, u32>,
}

impl MaterialTable {
    /// Adds or replaces a material by name; returns its index.
    pub fn insert(&mut self, m: Material) -> u32 {
        if let Some(&i) = self.by_name.get(&m.name) {
            self.materials[i as usize] = m;
            i
        } else {
            let i = self.materials.len() as u32;
            self.by_name.insert(m.name.clone(), i);
            self.materials.push(m);
            i
        }
    }

    /// Index of the grey Lambertian used for faces without a material.
    pub fn default_material(&mut self) -> u32 {
        if let Some(&i) = self.by_name.get(DEFAULT_MATERIAL) {
            return i;
        }
        self.insert(Material {
            name: DEFAULT_MATERIAL.into(),
            bsdf: Bsdf::Lambert { kd: Vec3::splat(0.8) },
            emission: Vec3::ZERO,
        })
    }
}

/// Name of the material given to faces with no `usemtl` (or an unknown one).
pub const DEFAULT_MATERIAL: &str = "(default grey)";

fn rgb(v: Option<[f32; 3]>) -> Option<Vec3> {
    v.map(Vec3::from_array)
}

/// Maps one MTL material onto photonwave's materials; warnings go to `warnings`.
#[must_use]
pub fn material_from_mtl(m: &tobj::Material, warnings: &mut Vec<String>) -> Material {
    let kd = rgb(m.diffuse).unwrap_or(Vec3::splat(0.8));
    let ks = rgb(m.specular).unwrap_or(Vec3::ZERO);
    let emission = rgb(m.emissive).unwrap_or(Vec3::ZERO);
    let illum = m.illumination_model.unwrap_or(2);
    let bsdf = match illum {
        3 | 5 => Bsdf::Mirror { ks: rgb(m.specular).unwrap_or(Vec3::ONE).min(Vec3::ONE) },
        4 | 6 | 7 => Bsdf::Glass { ior: m.optical_density.unwrap_or(1.5) },
        2 if ks.max_element() > 0.0 => {
            let sum = (kd + ks).max_element();
            let scale = if sum > 1.0 {
                warnings.push(format!("material `{}`: Kd + Ks = {sum:.3} > 1, scaled down to conserve energy", m.name));
                1.0 / sum
            } else {
                1.0
            };
            Bsdf::Glossy { kd: kd * scale, ks: ks * scale, exponent: m.shininess.unwrap_or(10.0).max(0.0) }
        }
        _ => {
            if kd.max_element() > 1.0 {
                warnings.push(format!("material `{}`: Kd > 1 clamped to 1 to conserve energy", m.name));
            }
            Bsdf::Lambert { kd: kd.min(Vec3::ONE) }
        }
    };
    Material { name: m.name.clone(), bsdf, emission }
}

/// Loads an OBJ file (and the MTL files it names) into a mesh; materials go into `table`.
/// `transform` scales then translates every position.
pub fn load_obj(
    path: &Path,
    transform: (f32, Vec3),
    table: &mut MaterialTable,
    warnings: &mut Vec<String>,
) -> Result<MeshInput> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mtllibs = check_obj(path, &text)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    for lib in &mtllibs {
        let mtl_path = dir.join(lib);
        let mtl_text = std::fs::read_to_string(&mtl_path).map_err(|e| Error::io(&mtl_path, e))?;
        check_mtl(&mtl_path, &mtl_text)?;
    }
    let options = tobj::LoadOptions { single_index: true, triangulate: true, ..Default::default() };
    let (models, mtl) = tobj::load_obj(path, &options).map_err(|e| Error::parse(path, 0, format!("OBJ: {e}")))?;
    let mtl = match mtl {
        Ok(m) => m,
        // tobj reports "no material file" as an error; an OBJ without `mtllib` simply has none.
        Err(_) if mtllibs.is_empty() => Vec::new(),
        Err(e) => return Err(Error::parse(&dir.join(&mtllibs[0]), 0, format!("MTL: {e}"))),
    };
    let ids: Vec<u32> = mtl.iter().map(|m| table.insert(material_from_mtl(m, warnings))).collect();

    let (scale, translate) = transform;
    let mut mesh = MeshInput { source: path.display().to_string(), ..Default::default() };
    let mut any_normals = false;
    let mut missing_material = false;
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        let has_normals = !m.normals.is_empty() && m.normals.len() == m.positions.len();
        any_normals |= has_normals;
        for (k, p) in m.positions.chunks_exact(3).enumerate() {
            mesh.positions.push(Vec3::new(p[0], p[1], p[2]) * scale + translate);
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
        let material = match m.material_id {
            Some(i) if i < ids.len() => ids[i],
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
