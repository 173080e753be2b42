//! Throughput of the reference engine's hot kernels on a bundled scene: closest-hit and shadow
//! traversal (obvhs BVH2 + watertight triangles) and the photon-map radiance estimate.
//! Run: `cargo bench --bench reference` (flags from .cargo/config.toml: target-cpu=x86-64-v3).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use photonwave::code_path::CodePath;
use photonwave::formats::load_scene;
use photonwave::photon_map::{Filter, Lookup, Nearest, Reflectance};
use photonwave::reference::build_maps;
use photonwave::rng::{Domain, Sampler};
use photonwave::sampling::uniform_sphere;
use photonwave::settings::Settings;
use std::hint::black_box;
use std::path::PathBuf;

fn scene_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

fn traversal(c: &mut Criterion) {
    let loaded = load_scene(&scene_path("cornell-spheres.toml")).expect("bundled scene");
    let scene = &loaded.scene;
    let cam = loaded.camera.unwrap().prepare(256, 256).unwrap();
    let camera_rays: Vec<(Vec3, Vec3)> =
        (0..65_536u32).map(|i| cam.ray((i % 256) as f32 + 0.5, (i / 256) as f32 + 0.5)).collect();
    let centre = scene.centre();
    let diffuse_rays: Vec<(Vec3, Vec3)> = (0..65_536u64)
        .map(|i| {
            let s = Sampler::new(1, Domain::Camera, i);
            (centre, uniform_sphere([s.get(0, 0), s.get(0, 1)]))
        })
        .collect();
    let mut g = c.benchmark_group("traversal");
    g.throughput(Throughput::Elements(65_536));
    g.bench_function(BenchmarkId::new("closest", "camera"), |b| {
        b.iter(|| camera_rays.iter().filter(|(o, d)| scene.intersect(*o, *d, f32::INFINITY).is_some()).count())
    });
    g.bench_function(BenchmarkId::new("closest", "incoherent"), |b| {
        b.iter(|| diffuse_rays.iter().filter(|(o, d)| scene.intersect(*o, *d, f32::INFINITY).is_some()).count())
    });
    g.bench_function(BenchmarkId::new("any", "incoherent"), |b| {
        b.iter(|| diffuse_rays.iter().filter(|(o, d)| scene.occluded(*o, *d, 0.3)).count())
    });
    g.finish();
}

fn density(c: &mut Criterion) {
    let loaded = load_scene(&scene_path("cornell-box.toml")).expect("bundled scene");
    let scene = &loaded.scene;
    let settings = Settings { photons: 200_000, ..Default::default() };
    let (maps, _, _) = build_maps(scene, &settings).unwrap();
    // Queries at stored photon positions (on surfaces), in a scattered order.
    let queries: Vec<(Vec3, Vec3)> = (0..16_384usize)
        .map(|i| {
            let p = maps.global.photon((i * 7919) % maps.global.len());
            (p.position, p.normal)
        })
        .collect();
    let r = settings.global_radius * scene.diagonal();
    let mut g = c.benchmark_group("density");
    g.throughput(Throughput::Elements(queries.len() as u64));
    g.bench_function(BenchmarkId::new("knn", settings.k), |b| {
        let mut scratch = Nearest::default();
        b.iter(|| {
            let mut sum = Vec3::ZERO;
            for (p, n) in &queries {
                let q = Lookup {
                    p: *p,
                    k: settings.k as usize,
                    r_max: r,
                    kernel: settings.kernel,
                    filter: Filter { n: *n, flags_mask: 0, plane: 0.0, slack: 0.0 },
                };
                sum +=
                    maps.global.estimate(CodePath::Simd, &q, Reflectance::Constant(Vec3::ONE), &mut scratch).radiance;
            }
            black_box(sum)
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(4));
    targets = traversal, density
}
criterion_main!(benches);
