//! Throughput of each wavefront stage on `cornell-spheres` (one run of the system over a full
//! queue), and the queue layout the design card asked us to measure: SoA columns in a resource
//! (what the engine uses) against one entity per ray with its fields as components.
//! Run: `cargo bench --bench stages`.

use bevy_ecs::prelude::*;
use bevy_ecs::system::RunSystemOnce;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use photonwave::formats::load_scene;
use photonwave::reference::build_maps;
use photonwave::rng::Domain;
use photonwave::scene::Scene;
use photonwave::settings::Settings;
use photonwave::wavefront::queues::{Classified, PathQueue, ShadowQueue};
use photonwave::wavefront::*;
use std::path::PathBuf;
use std::sync::Arc;

fn setup(threads: usize) -> World {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-spheres.toml");
    let loaded = load_scene(&path).expect("bundled scene");
    let settings = Settings {
        width: 128,
        height: 128,
        spp: 2,
        photons: 100_000,
        caustic_photons: 50_000,
        threads: threads as u32,
        ..Default::default()
    };
    let camera = loaded.camera.unwrap().prepare(settings.width, settings.height).unwrap();
    let scene = Arc::new(loaded.scene);
    let (maps, _, _) = build_maps(&scene, &settings).unwrap();
    let mut w = World::new();
    let job = photonwave::job::Job::new(&scene, &settings).expect("valid bench settings");
    w.insert_resource(Shared { scene, job });
    w.insert_resource(StageStats::default());
    w.insert_resource(Maps(Arc::new(maps)));
    w.insert_resource(PhotonWork { domain: Some(Domain::GlobalPhoton), ..Default::default() });
    w.insert_resource(CameraWork {
        camera,
        first_sample: 0,
        count: 32_768,
        paths: PathQueue::default(),
        next: PathQueue::default(),
        classified: Classified::default(),
        shadows: ShadowQueue::default(),
        terms: Vec::new(),
        receivers: Vec::new(),
        lobe_receivers: Vec::new(),
        narrow_hits: Vec::new(),
        film: Vec::new(),
        open: Default::default(),
        rays: Default::default(),
        numerics: Default::default(),
    });
    w
}

fn photon_stages(c: &mut Criterion) {
    let mut w = setup(1);
    let mut g = c.benchmark_group("photon_stages");
    g.throughput(Throughput::Elements(photonwave::transport::photon::BATCH as u64));
    g.bench_function("emit_photons", |b| b.iter(|| w.run_system_once(emit::emit_photons).unwrap()));
    w.run_system_once(emit::emit_photons).unwrap();
    g.bench_function("intersect_photons", |b| b.iter(|| w.run_system_once(intersect::intersect_photons).unwrap()));
    g.bench_function("classify_photons", |b| b.iter(|| w.run_system_once(classify::classify_photons).unwrap()));
    g.bench_function("deposit_photons", |b| {
        b.iter(|| {
            w.resource_mut::<PhotonWork>().deposits.clear();
            w.run_system_once(deposit::deposit_photons).unwrap()
        })
    });
    g.bench_function("scatter_photons", |b| {
        b.iter(|| {
            w.resource_mut::<PhotonWork>().next.clear();
            w.run_system_once(shade::scatter_photons).unwrap()
        })
    });
    g.finish();
}

fn camera_stages(c: &mut Criterion) {
    let mut w = setup(1);
    w.run_system_once(emit::emit_camera_rays).unwrap();
    let mut g = c.benchmark_group("camera_stages");
    g.throughput(Throughput::Elements(32_768));
    g.bench_function("emit_camera_rays", |b| b.iter(|| w.run_system_once(emit::emit_camera_rays).unwrap()));
    g.bench_function("intersect_paths", |b| b.iter(|| w.run_system_once(intersect::intersect_paths).unwrap()));
    g.bench_function("classify_paths", |b| b.iter(|| w.run_system_once(classify::classify_paths).unwrap()));
    g.bench_function("deposit_emission", |b| b.iter(|| w.run_system_once(deposit::deposit_emission).unwrap()));
    g.bench_function("gather_caustics", |b| b.iter(|| w.run_system_once(gather::gather_caustics).unwrap()));
    g.bench_function("shade_direct", |b| {
        b.iter(|| {
            w.resource_mut::<CameraWork>().shadows.clear();
            w.run_system_once(shade::shade_direct).unwrap()
        })
    });
    w.resource_mut::<CameraWork>().shadows.clear();
    w.run_system_once(shade::shade_direct).unwrap();
    let shadows = w.resource::<CameraWork>().shadows.clone();
    g.bench_function("trace_shadow_rays", |b| {
        b.iter(|| {
            w.resource_mut::<CameraWork>().shadows = shadows.clone();
            w.run_system_once(intersect::trace_shadow_rays).unwrap()
        })
    });
    g.bench_function("spawn_gather_rays", |b| {
        b.iter(|| {
            w.resource_mut::<CameraWork>().next.clear();
            w.run_system_once(shade::spawn_gather_rays).unwrap()
        })
    });
    // The gather rays' own hits: global-map reads (precomputed irradiance where it applies).
    w.resource_mut::<CameraWork>().next.clear();
    w.run_system_once(shade::spawn_gather_rays).unwrap();
    {
        let mut work = w.resource_mut::<CameraWork>();
        let work = &mut *work;
        std::mem::swap(&mut work.paths, &mut work.next);
    }
    w.run_system_once(intersect::intersect_paths).unwrap();
    w.run_system_once(classify::classify_paths).unwrap();
    let n = w.resource::<CameraWork>().paths.len() as u64;
    g.throughput(Throughput::Elements(n));
    g.bench_function("gather_global", |b| b.iter(|| w.run_system_once(gather::gather_global).unwrap()));
    g.finish();
}

/// One ray per entity, its fields as components (the alternative layout).
#[derive(Component)]
struct RayOrigin(Vec3);
#[derive(Component)]
struct RayDir(Vec3);
#[derive(Component, Default)]
struct RayHit(Option<photonwave::geometry::Hit>);

#[derive(Resource)]
struct SceneRes(Arc<Scene>);

fn intersect_entities(scene: Res<SceneRes>, mut q: Query<(&RayOrigin, &RayDir, &mut RayHit)>) {
    for (o, d, mut h) in &mut q {
        h.0 = scene.0.intersect(o.0, d.0, f32::INFINITY);
    }
}

/// The entity layout's classify: material kind of each hit into a per-entity component.
#[derive(Component, Default)]
struct RayClass(u8);

fn classify_entities(scene: Res<SceneRes>, mut q: Query<(&RayHit, &mut RayClass)>) {
    let s = &scene.0;
    for (h, mut c) in &mut q {
        c.0 = match h.0 {
            None => 3,
            Some(h) => match s.materials[s.material[h.tri as usize] as usize].bsdf {
                photonwave::material::Bsdf::Mirror { .. } => 1,
                photonwave::material::Bsdf::Glass { .. } => 2,
                _ => 0,
            },
        };
    }
}

fn layout(c: &mut Criterion) {
    let mut w = setup(1);
    w.run_system_once(emit::emit_camera_rays).unwrap();
    let scene = w.resource::<Shared>().scene.clone();
    let rays = w.resource::<CameraWork>().paths.rays.clone();
    let mut ew = World::new();
    ew.insert_resource(SceneRes(scene));
    for i in 0..rays.len() {
        ew.spawn((RayOrigin(rays.origin(i)), RayDir(rays.direction(i)), RayHit::default(), RayClass::default()));
    }
    w.run_system_once(intersect::intersect_paths).unwrap();
    ew.run_system_once(intersect_entities).unwrap();
    let mut g = c.benchmark_group("layout");
    g.throughput(Throughput::Elements(rays.len() as u64));
    g.bench_function(BenchmarkId::new("intersect", "soa_resource"), |b| {
        b.iter(|| w.run_system_once(intersect::intersect_paths).unwrap())
    });
    g.bench_function(BenchmarkId::new("intersect", "entity_per_ray"), |b| {
        b.iter(|| ew.run_system_once(intersect_entities).unwrap())
    });
    g.bench_function(BenchmarkId::new("classify", "soa_resource"), |b| {
        b.iter(|| w.run_system_once(classify::classify_paths).unwrap())
    });
    g.bench_function(BenchmarkId::new("classify", "entity_per_ray"), |b| {
        b.iter(|| ew.run_system_once(classify_entities).unwrap())
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10).measurement_time(std::time::Duration::from_secs(3));
    targets = photon_stages, camera_stages, layout
}
criterion_main!(benches);
