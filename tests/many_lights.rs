//! Many lights (issue 56, item 2): a row of 64 small square emitters of equal power, 0.5 apart
//! and 0.4 above a floor, each 0.06 across. Direct light at points of the floor, one light
//! sample an estimate, must be the sum of every light's irradiance (Lambert's formula per square)
//! whichever way the light is picked — by the light tree (the default) or by power — and the
//! tree's estimates must be at least 4 times less variable: power picks each light 1 time in 64,
//! wherever the point, and the few lights above it carry almost all of its light.
//!
//! Tolerances: each mean within 4 standard errors of its 8 192 estimates (plus 10⁻⁴ relative,
//! the f32 sums) of the exact sum; the variance ratio measured 23–89 at these points (asserted
//! ≥ 4, the goal, so only a tree that had lost its advantage fails).

mod common;

use glam::Vec3;

use photonwave::material::{Bsdf, Material};
use photonwave::rng::{Domain, Sampler};
use photonwave::scene::{LightSampler, MeshInput, Scene};
use photonwave::settings::Settings;
use photonwave::transport::direct::direct_light;
use photonwave::transport::{Context, PhotonMaps};

const LE: f32 = 20.0;

/// The row of lights, facing down; returns the scene and each square's corners.
fn row() -> (Scene, Vec<[Vec3; 4]>) {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut squares = Vec::new();
    for i in 0..64 {
        let x = -15.75 + 0.5 * i as f32;
        let h = 0.03;
        let c =
            [Vec3::new(x - h, 0.4, -h), Vec3::new(x + h, 0.4, -h), Vec3::new(x + h, 0.4, h), Vec3::new(x - h, 0.4, h)];
        let k = positions.len() as u32;
        positions.extend(c);
        // Wound so that the normal points down (−y).
        triangles.extend([[k, k + 1, k + 2], [k, k + 2, k + 3]]);
        squares.push(c);
    }
    let n = triangles.len();
    let mesh = MeshInput {
        source: "row".into(),
        positions,
        normals: vec![],
        triangles,
        material: vec![0; n],
        ..Default::default()
    };
    let light = Material::new("lamp", Bsdf::Lambert { kd: Vec3::ZERO }, Vec3::splat(LE));
    (Scene::build(vec![mesh], vec![light], vec![], vec![]).unwrap(), squares)
}

#[test]
fn the_light_tree_sums_every_light_with_a_quarter_of_powers_variance() {
    let (scene, squares) = row();
    assert!(scene.light_tree.is_some(), "128 emissive triangles make a tree");
    let maps = PhotonMaps::default();
    let white = Bsdf::Lambert { kd: Vec3::ONE };
    for p in [Vec3::new(0.0, 0.0, 0.0), Vec3::new(-7.3, 0.0, 0.4), Vec3::new(15.6, 0.0, -0.2)] {
        let want: f64 = squares.iter().map(|c| common::polygon_irradiance(p, Vec3::Y, c, LE) as f64).sum();
        let mut variances = Vec::new();
        for how in [LightSampler::Tree, LightSampler::Power] {
            let settings = Settings { light_sampler: how, light_samples: 1, ..Default::default() };
            let job = common::job(&scene, &settings);
            let ctx = Context::new(&scene, &maps, &job);
            let sp = common::floor_point(p);
            // E = π·L_reflected for a white Lambertian.
            let values: Vec<f32> = (0..8192)
                .map(|i| {
                    let s = Sampler::new(3, Domain::Camera, i);
                    std::f32::consts::PI * direct_light(&ctx, &sp, &white, Vec3::Y, &s, &mut Default::default()).x
                })
                .collect();
            let (mean, se) = common::mean_and_se(&values);
            assert!(
                (mean - want).abs() < 4.0 * se + 1e-4 * want,
                "{how:?} at {p}: {mean} against the sum of every light {want} (se {se})"
            );
            variances.push(se * se);
        }
        let ratio = variances[1] / variances[0];
        println!("at {p}: variance by power / by the tree = {ratio:.1}");
        assert!(ratio >= 4.0, "at {p}: the tree's estimates are only {ratio:.2} times less variable than power's");
    }
}
