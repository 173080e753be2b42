//! Scenes generated in code, so that benchmarks need no download: a finely tessellated displaced
//! sphere inside a closed, lit box.

use super::LoadedScene;
use crate::error::Result;
use crate::material::{Bsdf, Material};
use crate::scene::{Camera, MeshInput, Scene};
use crate::settings::Settings;
use glam::Vec3;
use std::f32::consts::PI;

/// Name the CLI accepts for [`displaced_sphere`] (`photonwave bench generated:sphere`).
pub const SPHERE_NAME: &str = "generated:sphere";

/// A sphere of radius 0.3 at the centre of a closed unit box, its radius displaced by ±4 % in a
/// 12 × 12 bump pattern, tessellated into `2·rings·segments − 2·segments` triangles
/// (`super::shapes::sphere_grid`: rings × segments quads, the pole rows one triangle each), lit
/// by a square area light under the ceiling. `rings = 512, segments = 1024` gives 1 046 528
/// sphere triangles.
pub fn displaced_sphere(rings: u32, segments: u32) -> Result<LoadedScene> {
    let (rings, segments) = (rings.max(2), segments.max(3));
    let mut sphere = MeshInput { source: SPHERE_NAME.to_string(), ..Default::default() };
    let centre = Vec3::new(0.5, 0.4, 0.5);
    for i in 0..=rings {
        let theta = PI * i as f32 / rings as f32;
        for j in 0..=segments {
            let phi = 2.0 * PI * j as f32 / segments as f32;
            let dir = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            let r = 0.3 * (1.0 + 0.04 * (12.0 * theta).sin() * (12.0 * phi).sin());
            sphere.positions.push(centre + dir * r);
        }
    }
    // y up mirrors the grid's z-up parametrisation: each triangle reversed faces outward.
    sphere.triangles = super::shapes::sphere_grid(rings, segments).into_iter().map(|[a, b, c]| [a, c, b]).collect();
    sphere.material = vec![0; sphere.triangles.len()];

    // The box, faces pointing inward, and the light just under the ceiling.
    let mut room = MeshInput { source: format!("{SPHERE_NAME} room"), ..Default::default() };
    let corners: Vec<Vec3> =
        (0..8).map(|k| Vec3::new((k & 1) as f32, (k >> 1 & 1) as f32, (k >> 2 & 1) as f32)).collect();
    room.positions.extend(&corners);
    // Quads as (a, b, c, d) counter-clockwise seen from inside.
    for q in [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]] {
        room.triangles.push([q[0], q[1], q[2]]);
        room.triangles.push([q[0], q[2], q[3]]);
        room.material.extend([1, 1]);
    }
    let base = room.positions.len() as u32;
    let y = 0.999;
    room.positions.extend([
        Vec3::new(0.4, y, 0.4),
        Vec3::new(0.6, y, 0.4),
        Vec3::new(0.6, y, 0.6),
        Vec3::new(0.4, y, 0.6),
    ]);
    // Facing down.
    room.triangles.push([base, base + 1, base + 2]);
    room.triangles.push([base, base + 2, base + 3]);
    room.material.extend([2, 2]);

    let materials = vec![
        Material::new("sphere", Bsdf::Lambert { kd: Vec3::splat(0.7) }, Vec3::ZERO),
        Material::new("walls", Bsdf::Lambert { kd: Vec3::splat(0.6) }, Vec3::ZERO),
        Material::new("light", Bsdf::Lambert { kd: Vec3::ZERO }, Vec3::splat(20.0)),
    ];
    let scene = Scene::build(vec![sphere, room], materials, vec![], vec![])?;
    let camera = Camera { eye: Vec3::new(0.5, 0.5, 0.02), target: centre, up: Vec3::Y, fov_deg: 60.0 };
    Ok(LoadedScene {
        scene,
        camera: Some(camera),
        cameras: Vec::new(),
        settings: Settings::default(),
        inputs: Vec::new(),
    })
}
