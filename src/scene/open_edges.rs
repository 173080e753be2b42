//! Open edges: mesh edges that border one triangle alone, such as the front edges of a Cornell
//! box with no front wall. A density estimate near one has part of its disk beyond the surface,
//! with no other surface there whose photons could say so (`photon_map::boundary` finds cuts
//! from such photons); these edges are the cuts it cannot find. Each triangle lists the open
//! edges of its flat region (the triangles in its plane), so an estimate reads a short list.

use super::Scene;
use glam::Vec3;
use std::collections::HashMap;

/// A flat region's open edges listed per triangle at most this many (a region with more is left
/// uncorrected at its edges rather than read slowly).
pub const MAX_EDGES_PER_TRIANGLE: usize = 16;

/// An edge bordering one triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OpenEdge {
    /// One end.
    pub a: Vec3,
    /// The other end.
    pub b: Vec3,
    /// Unit direction in the triangle's plane, across the edge, into the triangle.
    pub inward: Vec3,
}

/// The open edges of a scene and, per triangle, which of them bound its flat region.
#[derive(Clone, Debug, Default)]
pub struct OpenEdges {
    /// Every open edge.
    pub edges: Vec<OpenEdge>,
    /// Per triangle, its range in `list`.
    ranges: Vec<(u32, u32)>,
    /// Edge indices, triangle by triangle.
    list: Vec<u32>,
}

impl OpenEdges {
    /// The open edges bounding triangle `tri`'s flat region.
    pub fn of(&self, tri: u32) -> impl Iterator<Item = &OpenEdge> {
        let (start, len) = self.ranges.get(tri as usize).copied().unwrap_or((0, 0));
        self.list[start as usize..(start + len) as usize].iter().map(|&e| &self.edges[e as usize])
    }
}

/// An edge by the bit patterns of its two ends, in order.
pub(super) type EdgeKey = ([u32; 3], [u32; 3]);

/// Per edge: the first triangle using it, which of that triangle's edges it is, and how many
/// triangles use it.
pub(super) type EdgeUses = HashMap<EdgeKey, (u32, u8, u32)>;

impl Scene {
    /// The keys of triangle `i`'s three edges (edge k runs from corner k to corner k + 1).
    pub(super) fn edge_keys(&self, i: usize) -> [EdgeKey; 3] {
        let v = [self.p0[i], self.p1[i], self.p2[i]].map(|p| p.to_array().map(f32::to_bits));
        [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])].map(|(a, b)| if a < b { (a, b) } else { (b, a) })
    }

    /// Every edge of the mesh with its uses, matched by the exact bits of its ends (once per
    /// scene: the closed-scene test and the open edges both read it).
    pub(super) fn edge_uses(&self) -> EdgeUses {
        let mut uses = EdgeUses::new();
        for i in 0..self.p0.len() {
            for (k, key) in self.edge_keys(i).into_iter().enumerate() {
                uses.entry(key).or_insert((i as u32, k as u8, 0)).2 += 1;
            }
        }
        uses
    }

    /// Finds the open edges among `uses` and lists them per triangle of their flat region
    /// (triangles whose normal and plane offset agree to 10⁻⁵, the offset relative to the
    /// scene's size `size`).
    pub(super) fn find_open_edges(&self, size: f32, uses: &EdgeUses) -> OpenEdges {
        let n = self.p0.len();
        let corners = |i: usize| [self.p0[i], self.p1[i], self.p2[i]];
        let q = |x: f32| (f64::from(x) * 1e5).round() as i64;
        let plane = |i: usize| {
            let nn = self.ng[i];
            [q(nn.x), q(nn.y), q(nn.z), q(nn.dot(self.p0[i]) / size)]
        };
        let mut edges = Vec::new();
        let mut by_plane: HashMap<[i64; 4], Vec<u32>> = HashMap::new();
        let mut plane_triangles: HashMap<[i64; 4], Vec<u32>> = HashMap::new();
        for i in 0..n {
            plane_triangles.entry(plane(i)).or_default().push(i as u32);
        }
        // Whether a point of triangle `i`'s plane lies inside triangle `j` (same plane).
        let inside = |j: usize, q: Vec3| {
            let c = corners(j);
            let edge = |a: Vec3, b: Vec3| (b - a).cross(q - a).dot(self.ng[j]) >= 0.0;
            edge(c[0], c[1]) && edge(c[1], c[2]) && edge(c[2], c[0])
        };
        let mut open: Vec<(u32, usize)> = uses.values().filter(|e| e.2 == 1).map(|e| (e.0, e.1 as usize)).collect();
        // Deterministic order (the map's is not).
        open.sort_unstable();
        for (tri, k) in open {
            let c = corners(tri as usize);
            let (a, b, other) = (c[k], c[(k + 1) % 3], c[(k + 2) % 3]);
            let across = self.ng[tri as usize].cross(b - a).normalize_or_zero();
            let inward = if across.dot(other - a) >= 0.0 { across } else { -across };
            if inward == Vec3::ZERO {
                continue;
            }
            // An edge that only looks open — a seam between coplanar pieces whose vertices are
            // not shared, or a T-junction — has a triangle of the same plane just past it.
            let past = (a + b) * 0.5 - inward * (1e-4 * (b - a).length().max(1e-6 * size));
            let key = plane(tri as usize);
            if plane_triangles[&key].iter().any(|&j| j != tri && inside(j as usize, past)) {
                continue;
            }
            by_plane.entry(plane(tri as usize)).or_default().push(edges.len() as u32);
            edges.push(OpenEdge { a, b, inward });
        }
        let mut ranges = vec![(0u32, 0u32); n];
        let mut list = Vec::new();
        if !edges.is_empty() {
            for (i, range) in ranges.iter_mut().enumerate() {
                if let Some(mine) = by_plane.get(&plane(i)).filter(|m| m.len() <= MAX_EDGES_PER_TRIANGLE) {
                    *range = (list.len() as u32, mine.len() as u32);
                    list.extend_from_slice(mine);
                }
            }
        }
        OpenEdges { edges, ranges, list }
    }
}

#[cfg(test)]
mod tests {
    use crate::material::{Bsdf, Material};
    use crate::scene::{Light, MeshInput, Scene};
    use glam::Vec3;

    fn scene(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Scene {
        let material = vec![0; triangles.len()];
        let mesh = MeshInput { source: "test".into(), positions, triangles, material, ..Default::default() };
        let grey = Material::new("grey", Bsdf::Lambert { kd: Vec3::splat(0.5) }, Vec3::ZERO);
        let light = Light::Point { position: Vec3::new(0.0, 1.0, 0.0), intensity: Vec3::ONE };
        Scene::build(vec![mesh], vec![grey], vec![light], vec![]).unwrap()
    }

    /// A lone quad has four open edges, each pointing into the quad and listed for both of its
    /// triangles; its diagonal is not open. A closed tetrahedron has none. A T-junction (one quad
    /// meeting two along a seam whose vertices they do not all share) leaves the seam closed.
    #[test]
    fn a_quad_has_four_open_edges_and_a_closed_mesh_none() {
        let quad = scene(
            vec![
                Vec3::new(-1.0, 0.0, -1.0),
                Vec3::new(1.0, 0.0, -1.0),
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(-1.0, 0.0, 1.0),
            ],
            vec![[0, 2, 1], [0, 3, 2]],
        );
        assert_eq!(quad.open_edges.edges.len(), 4);
        for e in &quad.open_edges.edges {
            let mid = (e.a + e.b) * 0.5;
            assert!((mid + e.inward * 0.1).abs().max_element() < 1.0, "{e:?} points out of the quad");
            assert!(e.inward.y.abs() < 1e-6 && (e.inward.length() - 1.0).abs() < 1e-6);
        }
        assert_eq!(quad.open_edges.of(0).count(), 4);
        assert_eq!(quad.open_edges.of(1).count(), 4);
        let tetra =
            scene(vec![Vec3::ZERO, Vec3::X, Vec3::Z, Vec3::Y], vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]]);
        assert!(tetra.open_edges.edges.is_empty());
        // A T-junction: one quad on the left, two on the right meeting it along x = 0.
        let seam = scene(
            vec![
                Vec3::new(-1.0, 0.0, -1.0),
                Vec3::new(0.0, 0.0, -1.0),
                Vec3::new(0.0, 0.0, 1.0),
                Vec3::new(-1.0, 0.0, 1.0),
                Vec3::new(1.0, 0.0, -1.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 1.0),
            ],
            vec![[0, 2, 1], [0, 3, 2], [1, 6, 5], [1, 5, 4], [6, 2, 7], [6, 7, 5]],
        );
        // Outer edges only: 3 of the left quad, 2 of each right one (none along the seam).
        assert_eq!(seam.open_edges.edges.len(), 7, "{:?}", seam.open_edges.edges);
    }
}
