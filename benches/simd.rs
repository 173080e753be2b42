//! The SIMD kernels beside their baselines on identical input (criterion's view of what
//! `photonwave bench` reports): packet traversal against obvhs single-ray traversal on
//! `cornell-spheres` camera and diffuse-bounce rays (the bench command's ray sets), and the 8-wide
//! photon lookups against their scalar twins on the Cornell box (k-NN with k = 64 under the
//! default maximum radius; fixed-radius lookups at a quarter of it).
//! Run: `cargo bench --bench simd` (flags from .cargo/config.toml: target-cpu=x86-64-v3).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use photonwave::bench::RaySets;
use photonwave::code_path::CodePath;
use photonwave::formats::load_scene;
use photonwave::geometry::packet::{closest_packets, occluded_packets};
use photonwave::photon_map::{Filter, Lookup, Nearest, Reflectance};
use photonwave::reference::build_maps;
use photonwave::settings::Settings;
use std::hint::black_box;
use std::path::PathBuf;

fn scene_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

fn traversal(c: &mut Criterion) {
    let loaded = load_scene(&scene_path("cornell-spheres.toml")).expect("bundled scene");
    let s = &loaded.scene;
    let cam = loaded.camera.unwrap().prepare(photonwave::bench::SIDE, photonwave::bench::SIDE).unwrap();
    let sets = RaySets::new(s, &cam);
    let mut g = c.benchmark_group("simd_traversal");
    for (label, rays) in [("camera", &sets.camera), ("diffuse", &sets.diffuse)] {
        // 65 536 rays of each set keep a sample short.
        let rays = &rays[..rays.len().min(65_536)];
        g.throughput(Throughput::Elements(rays.len() as u64));
        let mut hits = vec![None; rays.len()];
        let mut blocked = vec![false; rays.len()];
        g.bench_function(BenchmarkId::new("closest_packet", label), |b| {
            b.iter(|| closest_packets(s.bvh(), s.columns(), rays, &mut hits))
        });
        g.bench_function(BenchmarkId::new("closest_obvhs", label), |b| {
            b.iter(|| {
                rays.iter()
                    .filter(|r| s.bvh().closest_obvhs(s.columns(), r.origin, r.direction, r.t_max).is_some())
                    .count()
            })
        });
        g.bench_function(BenchmarkId::new("any_packet", label), |b| {
            b.iter(|| occluded_packets(s.bvh(), s.columns(), rays, &mut blocked))
        });
        g.bench_function(BenchmarkId::new("any_obvhs", label), |b| {
            b.iter(|| {
                rays.iter().filter(|r| s.bvh().occluded_obvhs(s.columns(), r.origin, r.direction, r.t_max)).count()
            })
        });
    }
    g.finish();
}

fn density(c: &mut Criterion) {
    let loaded = load_scene(&scene_path("cornell-box.toml")).expect("bundled scene");
    let s = &loaded.scene;
    let cam = loaded.camera.unwrap().prepare(photonwave::bench::SIDE, photonwave::bench::SIDE).unwrap();
    let sets = RaySets::new(s, &cam);
    let settings = Settings { photons: 200_000, ..Default::default() };
    let (maps, _, _) = build_maps(s, &settings).unwrap();
    let queries: Vec<(Vec3, Vec3)> = sets.hits.iter().step_by(16).copied().collect();
    let r = settings.global_radius * s.diagonal();
    let mut g = c.benchmark_group("simd_density");
    g.throughput(Throughput::Elements(queries.len() as u64));
    for set in [CodePath::Simd, CodePath::Scalar] {
        let name = format!("{set:?}").to_lowercase();
        let lookup = |p, n, k, r_max| Lookup {
            p,
            k,
            r_max,
            kernel: settings.kernel,
            filter: Filter { n, flags_mask: 0, plane: 0.0, slack: 0.0 },
        };
        let f = |n| Reflectance::Hemisphere { value: Vec3::splat(0.2), ng: n };
        g.bench_function(BenchmarkId::new("knn", &name), |b| {
            let mut scratch = Nearest::default();
            b.iter(|| {
                let mut sum = Vec3::ZERO;
                for &(p, n) in &queries {
                    sum += maps.global.estimate(set, &lookup(p, n, 64, r), f(n), &mut scratch).radiance;
                }
                black_box(sum)
            })
        });
        g.bench_function(BenchmarkId::new("radius", &name), |b| {
            b.iter(|| {
                let mut sum = Vec3::ZERO;
                for &(p, n) in &queries {
                    sum += maps.global.estimate_radius(set, &lookup(p, n, 0, r * 0.25), f(n)).radiance;
                }
                black_box(sum)
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(3));
    targets = traversal, density
}
criterion_main!(benches);
