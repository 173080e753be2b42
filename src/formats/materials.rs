//! The material table every reader fills: materials of all loaded files, kept apart per source
//! file (two MTL files may each define `floor`), with the textures read so far. Reads materials
//! as the readers make them; writes the scene's material list.

use super::image::load_texture;
use crate::error::Result;
use crate::material::{Bsdf, Material};
use crate::texture::{Encoding, Texture};
use glam::Vec3;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Name of the material given to faces with no `usemtl` (or an unknown one).
pub const DEFAULT_MATERIAL: &str = "(default grey)";

/// Materials of all loaded files, kept apart per MTL file.
#[derive(Default, Debug)]
pub struct MaterialTable {
    /// The table.
    pub materials: Vec<Material>,
    /// (MTL file, name) → index.
    by_key: HashMap<(PathBuf, String), u32>,
    /// Textures read so far, by file and encoding (a file named twice is read once).
    textures: HashMap<(PathBuf, Encoding), Arc<Texture>>,
}

impl MaterialTable {
    /// Adds the material `m` of the file `source`, or replaces the one of that name from that
    /// file; returns its index. When another file defines a different material of the same
    /// name, `warnings` says that each mesh keeps its own file's.
    pub fn insert(&mut self, source: &Path, m: Material, warnings: &mut Vec<String>) -> u32 {
        let key = (source.to_path_buf(), m.name.clone());
        if let Some(&i) = self.by_key.get(&key) {
            self.materials[i as usize] = m;
            return i;
        }
        let clash = self
            .by_key
            .iter()
            .find(|((file, name), &i)| name == &m.name && file != source && self.materials[i as usize] != m);
        if let Some(((file, _), _)) = clash {
            warnings.push(format!(
                "material `{}` is defined differently in {} and {}: each mesh uses its own MTL file's                  (a [materials.{}] override in the scene file replaces both)",
                m.name,
                file.display(),
                source.display(),
                m.name
            ));
        }
        let i = self.materials.len() as u32;
        self.by_key.insert(key, i);
        self.materials.push(m);
        i
    }

    /// Replaces every material called `name`, from any file, by `m`; returns how many there were.
    pub fn replace_named(&mut self, name: &str, m: &Material) -> usize {
        let mut n = 0;
        for slot in self.materials.iter_mut().filter(|x| x.name == name) {
            *slot = m.clone();
            n += 1;
        }
        n
    }

    /// The image at `path` decoded with `encoding`, read once per scene (`what` names its use in
    /// messages); the file is added to `inputs` when read.
    pub fn texture(
        &mut self,
        path: &Path,
        encoding: Encoding,
        what: &str,
        inputs: &mut Vec<PathBuf>,
    ) -> Result<Arc<Texture>> {
        let key = (path.to_path_buf(), encoding);
        if let Some(t) = self.textures.get(&key) {
            return Ok(t.clone());
        }
        let texture = Arc::new(load_texture(path, encoding, what)?);
        inputs.push(path.to_path_buf());
        self.textures.insert(key, texture.clone());
        Ok(texture)
    }

    /// Index of the grey Lambertian used for faces without a material.
    pub fn default_material(&mut self) -> u32 {
        let grey = Material::new(DEFAULT_MATERIAL, Bsdf::Lambert { kd: Vec3::splat(0.8) }, Vec3::ZERO);
        match self.by_key.get(&(PathBuf::new(), DEFAULT_MATERIAL.to_string())) {
            Some(&i) => i,
            None => self.insert(Path::new(""), grey, &mut Vec::new()),
        }
    }
}
