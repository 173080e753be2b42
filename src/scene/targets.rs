//! Caustic targets: a bounding sphere around each object that photons pass on as specular
//! (mirrors, glass, frosted glass, smooth rough metal; `Bsdf::photon_specular`). Caustic
//! photons are aimed at them (`transport::aim`): a direction outside every sphere's cone can
//! only meet a diffuse surface first, so it can never start a caustic path.
//!
//! Objects are the pieces of photon-specular triangles joined by shared edges (matched by the
//! exact bits of their ends, as for the open edges). Each sphere holds its piece's bounding box
//! with a margin of 10⁻⁴ of its radius for rounding. More than [`MAX_TARGETS`] pieces (a
//! scattered mosaic of mirror tiles) become one sphere around all of them.

use super::open_edges::EdgeUses;
use super::Scene;
use glam::Vec3;
use std::collections::HashMap;

/// The most spheres kept; beyond it one sphere bounds every specular triangle.
pub const MAX_TARGETS: usize = 64;

/// A sphere around one specular object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target {
    /// Centre.
    pub centre: Vec3,
    /// Radius.
    pub radius: f32,
}

impl Target {
    /// The sphere around the points `ps` (the centre of their box; the farthest one's distance,
    /// with the margin).
    fn around<'a>(ps: impl Iterator<Item = &'a Vec3> + Clone) -> Target {
        let (lo, hi) = super::bounds_of(ps.clone());
        let centre = 0.5 * (lo + hi);
        let r = ps.map(|p| p.distance(centre)).fold(0.0f32, f32::max);
        Target { centre, radius: r * (1.0 + 1e-4) + f32::MIN_POSITIVE }
    }
}

impl Scene {
    /// The caustic targets of the scene (empty without photon-specular surfaces).
    pub(super) fn find_caustic_targets(&self, uses: &EdgeUses) -> Vec<Target> {
        let specular: Vec<usize> =
            (0..self.p0.len()).filter(|&i| self.materials[self.material[i] as usize].bsdf.photon_specular()).collect();
        if specular.is_empty() {
            return Vec::new();
        }
        let index: HashMap<usize, usize> = specular.iter().enumerate().map(|(k, &i)| (i, k)).collect();
        let mut parent: Vec<usize> = (0..specular.len()).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        for (k, &i) in specular.iter().enumerate() {
            for key in self.edge_keys(i) {
                // The edge's first triangle; joined only when it is specular too.
                let Some(&(first, _, _)) = uses.get(&key) else { continue };
                if let Some(&j) = index.get(&(first as usize)) {
                    let (a, b) = (root(&mut parent, j), root(&mut parent, k));
                    parent[a] = b;
                }
            }
        }
        let mut pieces: HashMap<usize, Vec<Vec3>> = HashMap::new();
        for (k, &i) in specular.iter().enumerate() {
            let r = root(&mut parent, k);
            pieces.entry(r).or_default().extend([self.p0[i], self.p1[i], self.p2[i]]);
        }
        // Same order on every run: by the piece's first triangle.
        let mut roots: Vec<usize> = pieces.keys().copied().collect();
        roots.sort_unstable();
        if roots.len() > MAX_TARGETS {
            let all: Vec<Vec3> = pieces.values().flatten().copied().collect();
            return vec![Target::around(all.iter())];
        }
        roots.iter().map(|r| Target::around(pieces[r].iter())).collect()
    }
}
