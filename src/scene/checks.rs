//! Checks on a built scene: whether its geometry closes around every light (so that escaping
//! photons count as a leak), and overlapping faces of a dielectric and another material (a
//! modelling mistake worth a warning).

use super::{Light, Scene};
use crate::geometry::offset::offset_ray_origin;
use crate::material::{Bsdf, Material};
use glam::Vec3;

/// A warning when faces of two different materials, at least one a dielectric, overlap in one
/// plane: which of them a ray meets is arbitrary, and the ratio of indices across the boundary
/// is lost. Nested dielectrics are modelled with one face per boundary instead. Faces are grouped
/// by plane (normal up to sign and offset, rounded to 10⁻⁵ of the scene's size `size`); within a plane
/// that holds a dielectric and another material, a face overlaps another when one of four points
/// inside either lies inside the other.
pub(super) fn coincident_dielectrics(
    p0: &[Vec3],
    p1: &[Vec3],
    p2: &[Vec3],
    mat: &[u32],
    materials: &[Material],
    size: f32,
) -> Option<String> {
    let glass = |m: u32| matches!(materials[m as usize].bsdf, Bsdf::Glass { .. });
    if !mat.iter().any(|&m| glass(m)) {
        return None;
    }
    let mut planes: std::collections::HashMap<[i64; 4], Vec<usize>> = std::collections::HashMap::new();
    for i in 0..p0.len() {
        let n = (p1[i] - p0[i]).cross(p2[i] - p0[i]).normalize_or_zero();
        let first = n.to_array().into_iter().find(|c| c.abs() > 1e-6).unwrap_or(1.0);
        let n = if first < 0.0 { -n } else { n };
        let q = |x: f32| (f64::from(x) * 1e5).round() as i64;
        planes.entry([q(n.x), q(n.y), q(n.z), q(n.dot(p0[i]) / size)]).or_default().push(i);
    }
    let inside = |p: Vec3, i: usize| {
        let n = (p1[i] - p0[i]).cross(p2[i] - p0[i]);
        let edge = |a: Vec3, b: Vec3| (b - a).cross(p - a).dot(n) > 0.0;
        edge(p0[i], p1[i]) && edge(p1[i], p2[i]) && edge(p2[i], p0[i])
    };
    let mut pairs = std::collections::BTreeMap::<(String, String), usize>::new();
    for faces in planes.values() {
        if !faces.iter().any(|&i| glass(mat[i])) || faces.iter().all(|&i| mat[i] == mat[faces[0]]) {
            continue;
        }
        // Each dielectric face against every face of another material in its plane (not all
        // pairs: a large floor sharing the plane of one glass face stays linear). Planes that
        // would take more than 10⁷ tests are left unchecked.
        let dielectric = faces.iter().filter(|&&i| glass(mat[i])).count();
        if dielectric * faces.len() > 10_000_000 {
            continue;
        }
        for &i in faces.iter().filter(|&&i| glass(mat[i])) {
            for &j in faces {
                let (a, b) = (&materials[mat[i] as usize], &materials[mat[j] as usize]);
                if a.name == b.name || (glass(mat[j]) && j < i) {
                    continue;
                }
                // The centroid and three points toward the corners (a centroid alone can sit on
                // the other face's edge, as when a quad is split along its other diagonal).
                let points = |t: usize| {
                    let (a, b, c) = (p0[t], p1[t], p2[t]);
                    [(a + b + c) / 3.0, a * 0.6 + (b + c) * 0.2, b * 0.6 + (a + c) * 0.2, c * 0.6 + (a + b) * 0.2]
                };
                if points(i).iter().any(|&p| inside(p, j)) || points(j).iter().any(|&p| inside(p, i)) {
                    let (x, y) = if a.name < b.name { (a, b) } else { (b, a) };
                    *pairs.entry((x.name.clone(), y.name.clone())).or_default() += 1;
                }
            }
        }
    }
    let list: Vec<String> = pairs.iter().map(|((a, b), n)| format!("{n} triangle pairs of `{a}` and `{b}`")).collect();
    (!list.is_empty()).then(|| {
        format!(
            "overlapping faces of different materials in one plane ({}): which one a ray meets is \
             arbitrary and the ratio of indices across them is lost; model each boundary between two \
             dielectrics as one face whose glass material has `ior` and `outside_ior` (docs/src/hard-cases.md, \
             \"Nested dielectrics\")",
            list.join(", ")
        )
    })
}

impl Scene {
    /// [`Scene::encloses_lights`]: closed (no edge borders one triangle alone), then each light tested for being inside
    /// one of the closed pieces (connected by shared edges) by the parity of a ray's crossings of
    /// that piece — per piece, so that a light inside a glass ball inside a room counts.
    pub(super) fn find_enclosure(&self, uses: &super::open_edges::EdgeUses) -> bool {
        if self.p0.is_empty() || self.lights.iter().any(Light::is_distant) {
            return false;
        }
        let n = self.p0.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn root(parent: &mut [u32], mut i: u32) -> u32 {
            while parent[i as usize] != i {
                parent[i as usize] = parent[parent[i as usize] as usize];
                i = parent[i as usize];
            }
            i
        }
        // Closed: no edge borders a single triangle (three faces may meet at an edge, as at the
        // rim of a boundary between two dielectrics).
        if uses.values().any(|&(_, _, count)| count < 2) {
            return false;
        }
        // Triangles sharing an edge belong to one piece.
        for i in 0..n {
            for key in self.edge_keys(i) {
                let first = uses.get(&key).map_or(i as u32, |e| e.0);
                let (x, y) = (root(&mut parent, first), root(&mut parent, i as u32));
                parent[x as usize] = y;
            }
        }
        let piece: Vec<u32> = (0..n as u32).map(|i| root(&mut parent, i)).collect();
        let diagonal = self.diagonal();
        self.lights.iter().all(|l| match *l {
            Light::Point { position, .. } | Light::Spot { position, .. } => self.inside(position, &piece),
            Light::Area { tri, .. } => {
                let i = tri as usize;
                let c = (self.p0[i] + self.p1[i] + self.p2[i]) / 3.0;
                let lift = c.abs().max_element().max(diagonal) * 1e-5;
                self.inside(c + self.ng[i] * lift, &piece)
            }
            Light::Directional { .. } | Light::Sun { .. } | Light::Environment => false,
        })
    }

    /// Whether `p` is inside one of the closed pieces (`piece[triangle]`): an odd number of that
    /// piece's surfaces along a ray from `p`.
    fn inside(&self, p: Vec3, piece: &[u32]) -> bool {
        // A direction unlikely to graze an edge or lie in a face of modelled geometry.
        let d = Vec3::new(0.536_2, 0.612_7, 0.580_5).normalize();
        let mut crossings = std::collections::HashMap::<u32, u32>::new();
        let mut o = p;
        for _ in 0..100_000 {
            let Some(hit) = self.intersect(o, d, f32::INFINITY) else {
                return crossings.values().any(|c| c % 2 == 1);
            };
            *crossings.entry(piece[hit.tri as usize]).or_default() += 1;
            let sp = self.surface(&hit);
            o = offset_ray_origin(sp.p, sp.p_error, sp.frame.ng, d);
        }
        false
    }
}
