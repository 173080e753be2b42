//! Built-in shapes as triangle meshes in object space, with Mitsuba's conventions so that a
//! Mitsuba `shape` and a TOML `shape` mean the same thing: a `rectangle` is [−1, 1]² in the
//! z = 0 plane facing +z, a `disk` the unit disk there, a `cube` [−1, 1]³ facing out, a `sphere`
//! the unit sphere facing out (smooth normals). The scene's transform places them.
//!
//! Their texture coordinates are Mitsuba 3's (`SurfaceInteraction3f::uv` on its shapes, checked
//! point by point in tests/mitsuba_uv.rs) with v turned over, v → 1 − v: Mitsuba reads an
//! image's first row at v = 0, photonwave at v = 1 ([`crate::texture`]), so the same texel lands
//! on the same point. A rectangle is (x + 1)/2, (1 − y)/2; a disk (r, 1 − φ/2π), each fan
//! triangle with its own vertices so that neither the centre nor the seam at φ = 0 is shared; a
//! cube has Mitsuba's per-face layout; a sphere (φ/2π, 1 − θ/π).
//!
//! Writes [`MeshInput`]s; the front (emitting) face of each is the one its normal points out of.

use crate::error::{Error, Result};
use crate::scene::MeshInput;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Segments around a disk's rim and a sphere's equator.
pub const SEGMENTS: u32 = 96;
/// Rings from pole to pole of a sphere.
pub const RINGS: u32 = 48;

/// The names [`shape`] takes.
pub const NAMES: &str = "rectangle, disk, cube, sphere";

/// The built-in shape called `name`, made of material `material`; `source` names it in messages.
pub fn shape(name: &str, source: &str, material: u32) -> Result<MeshInput> {
    let mut mesh = match name {
        "rectangle" => rectangle(),
        "disk" => disk(SEGMENTS),
        "cube" => cube(),
        "sphere" => sphere(RINGS, SEGMENTS),
        other => {
            return Err(Error::setting(source, format!("unknown shape `{other}` (the built-in shapes are {NAMES})")))
        }
    };
    mesh.source = source.to_string();
    mesh.material = vec![material; mesh.triangles.len()];
    Ok(mesh)
}

/// [−1, 1]² at z = 0, facing +z, texture coordinates ((x + 1)/2, (1 − y)/2).
fn rectangle() -> MeshInput {
    let corners = [Vec2::new(-1.0, -1.0), Vec2::new(1.0, -1.0), Vec2::new(1.0, 1.0), Vec2::new(-1.0, 1.0)];
    MeshInput {
        positions: corners.iter().map(|c| c.extend(0.0)).collect(),
        texcoords: corners.iter().map(|c| Vec2::new(c.x + 1.0, 1.0 - c.y) * 0.5).collect(),
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        ..Default::default()
    }
}

/// The unit disk at z = 0 facing +z, a fan of `segments` triangles, texture coordinates
/// (r, 1 − φ/2π): each triangle has its own centre (at its middle φ) and rim vertices, the last
/// one's far rim at φ = 2π.
fn disk(segments: u32) -> MeshInput {
    let mut mesh = MeshInput::default();
    let rim = |j: u32| {
        let f = j as f32 / segments as f32;
        // The rim point of φ = 2π·f, exactly (1, 0) at both ends of the seam.
        let (s, c) = if j.is_multiple_of(segments) { (0.0, 1.0) } else { (2.0 * PI * f).sin_cos() };
        (Vec3::new(c, s, 0.0), Vec2::new(1.0, 1.0 - f))
    };
    for j in 0..segments {
        let base = mesh.positions.len() as u32;
        let ((p0, t0), (p1, t1)) = (rim(j), rim(j + 1));
        mesh.positions.extend([Vec3::ZERO, p0, p1]);
        mesh.texcoords.extend([Vec2::new(0.0, (t0.y + t1.y) * 0.5), t0, t1]);
        mesh.triangles.push([base, base + 1, base + 2]);
    }
    mesh
}

/// [−1, 1]³, each face facing out, two triangles per face (flat), with Mitsuba's texture layout
/// per face ([`cube_uv`]).
fn cube() -> MeshInput {
    let mut mesh = MeshInput::default();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::from_array(std::array::from_fn(|k| if k == axis { sign } else { 0.0 }));
            // Two tangents with u × v = n.
            let u = Vec3::from_array(std::array::from_fn(|k| if k == (axis + 1) % 3 { 1.0 } else { 0.0 }));
            let v = n.cross(u);
            let base = mesh.positions.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let p = n + u * a + v * b;
                mesh.positions.push(p);
                mesh.texcoords.push(cube_uv(axis, sign, p));
            }
            mesh.triangles.push([base, base + 1, base + 2]);
            mesh.triangles.push([base, base + 2, base + 3]);
        }
    }
    mesh
}

/// The texture coordinates of point `p` on the cube's face along `axis` (0, 1, 2: x, y, z) on
/// the `sign` side: Mitsuba 3's (u, v) there, v turned over.
fn cube_uv(axis: usize, sign: f32, p: Vec3) -> Vec2 {
    let (x, y, z) = (p.x, p.y, p.z);
    let mitsuba = match (axis, sign > 0.0) {
        (0, true) => Vec2::new(y + 1.0, 1.0 - z),
        (0, false) => Vec2::new(y + 1.0, z + 1.0),
        (1, true) => Vec2::new(1.0 - x, 1.0 - z),
        (1, false) => Vec2::new(z + 1.0, x + 1.0),
        (_, true) => Vec2::new(y + 1.0, x + 1.0),
        (_, false) => Vec2::new(1.0 - y, x + 1.0),
    } * 0.5;
    Vec2::new(mitsuba.x, 1.0 - mitsuba.y)
}

/// The unit sphere, `rings` × `segments` quads (the pole rows as single triangles), with its
/// normals and (φ/2π, 1 − θ/π) texture coordinates.
fn sphere(rings: u32, segments: u32) -> MeshInput {
    let mut mesh = MeshInput::default();
    for i in 0..=rings {
        let theta = PI * i as f32 / rings as f32;
        for j in 0..=segments {
            let phi = 2.0 * PI * j as f32 / segments as f32;
            let d = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
            mesh.positions.push(d);
            mesh.normals.push(d);
            mesh.texcoords.push(Vec2::new(j as f32 / segments as f32, 1.0 - i as f32 / rings as f32));
        }
    }
    mesh.triangles = sphere_grid(rings, segments);
    mesh
}

/// The triangles of a sphere's `(rings + 1) × (segments + 1)` vertex grid (row `i` at
/// θ = π·i/rings from the pole, column `j` at φ = 2π·j/segments): each quad split along the
/// diagonal from (i, j + 1) to (i + 1, j), the pole rows keeping only the triangle with area, so
/// `2·rings·segments − 2·segments` triangles. Counter-clockwise seen from outside when the
/// directions are (sin θ cos φ, sin θ sin φ, cos θ); reversed for a mirrored parametrisation.
pub(crate) fn sphere_grid(rings: u32, segments: u32) -> Vec<[u32; 3]> {
    let mut triangles = Vec::with_capacity(2 * (rings as usize) * (segments as usize));
    let row = segments + 1;
    for i in 0..rings {
        for j in 0..segments {
            let (a, b) = (i * row + j, i * row + j + 1);
            let (c, d) = (a + row, b + row);
            // Going down from the +z pole with φ increasing is counter-clockwise seen from
            // outside for (a, c, d).
            if i != 0 {
                triangles.push([a, c, b]);
            }
            if i + 1 != rings {
                triangles.push([b, c, d]);
            }
        }
    }
    triangles
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Area and the mean outward orientation: Σ area · (n_geometric · outward direction).
    fn area_and_outwardness(m: &MeshInput, outward: impl Fn(Vec3) -> Vec3) -> (f32, f32) {
        let (mut area, mut out) = (0.0, 0.0);
        for t in &m.triangles {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let cross = (b - a).cross(c - a);
            area += 0.5 * cross.length();
            out += 0.5 * cross.length() * cross.normalize().dot(outward((a + b + c) / 3.0));
        }
        (area, out / area)
    }

    #[test]
    fn shapes_have_their_areas_and_face_out() {
        let (a, o) = area_and_outwardness(&shape("rectangle", "r", 0).unwrap(), |_| Vec3::Z);
        assert!((a - 4.0).abs() < 1e-5 && o > 0.999);
        let (a, o) = area_and_outwardness(&shape("disk", "d", 0).unwrap(), |_| Vec3::Z);
        // An inscribed polygon of n sides: (n/2)·sin(2π/n).
        let n = SEGMENTS as f32;
        assert!((a - 0.5 * n * (2.0 * PI / n).sin()).abs() < 1e-4 && o > 0.999);
        let (a, o) = area_and_outwardness(&shape("cube", "c", 0).unwrap(), |p| {
            let k = p.abs().max_position();
            Vec3::from_array(std::array::from_fn(|i| if i == k { p[i].signum() } else { 0.0 }))
        });
        assert!((a - 24.0).abs() < 1e-4 && o > 0.999);
        let s = shape("sphere", "s", 0).unwrap();
        let (a, o) = area_and_outwardness(&s, |p| p.normalize());
        assert!((a - 4.0 * PI).abs() < 0.01 * 4.0 * PI && o > 0.99, "area {a}, outwardness {o}");
        assert!(s.material.len() == s.triangles.len());
        assert!(shape("torus", "t", 0).is_err());
    }
}
