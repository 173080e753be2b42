//! Each wavefront stage on a tiny input: queue contents in, queue contents out.
//!
//! Lanes in the bundled `cornell-spheres` room (metres): the floor is y = 0, the light a
//! 0.13 × 0.105 quad at y = 0.5487 facing down, the mirror sphere centred (−0.12, 0.1, −0.1) and
//! the glass sphere (0.13, 0.1, 0.08), both of radius 0.1; the room is open toward +z.

mod common;

use bevy_ecs::prelude::*;
use bevy_ecs::system::RunSystemOnce;
use common::*;
use glam::Vec3;
use photonwave::film::{Term, Terms};
use photonwave::photon_map::flags;
use photonwave::reference::build_maps;
use photonwave::rng::{Domain, Sampler};
use photonwave::settings::Settings;
use photonwave::wavefront::queues::{Classified, HitColumns, PathKind, PathQueue, PhotonLane, Segment, ShadowQueue};
use photonwave::wavefront::*;
use std::sync::Arc;

/// Lanes: 0 floor, 1 mirror sphere, 2 glass sphere, 3 escapes, 4 light.
fn lanes() -> [(Vec3, Vec3); 5] {
    let down = Vec3::NEG_Y;
    [
        (Vec3::new(0.0, 0.3, 0.0), down),
        (Vec3::new(-0.12, 0.4, -0.1), down),
        (Vec3::new(0.13, 0.4, 0.08), down),
        (Vec3::new(0.0, 0.3, 0.0), Vec3::Z),
        (Vec3::new(0.0, 0.3, 0.0), Vec3::Y),
    ]
}

fn world(settings: Settings) -> World {
    let scene = Arc::new(load("cornell-spheres.toml").scene);
    let mut w = World::new();
    let job = job(&scene, &Settings { threads: 2, ..settings });
    w.insert_resource(Shared { scene, job });
    w.insert_resource(StageStats::default());
    w
}

fn photon_world(domain: Domain) -> World {
    let mut w = world(Settings::default());
    // Paths 100.. of a wave that starts there, each with its counts.
    let n = lanes().len();
    let mut work = PhotonWork { domain: Some(domain), first_path: 100, paths: 16_384, ..Default::default() };
    work.counts.resize(n, Default::default());
    for (i, (o, d)) in lanes().into_iter().enumerate() {
        work.queue.push(PhotonLane {
            origin: o,
            dir: d,
            path: 100 + i as u64,
            bounce: 0,
            power: Vec3::splat(2.0),
            emitted: 2.0,
            specular_only: true,
        });
    }
    w.insert_resource(work);
    w
}

#[test]
fn photon_stages_intersect_classify_deposit_scatter() {
    let mut w = photon_world(Domain::GlobalPhoton);
    w.run_system_once(photonwave::wavefront::intersect::intersect_photons).unwrap();
    let hits = w.resource::<PhotonWork>().queue.hits.clone();
    assert!((hits.t[0] - 0.3).abs() < 1e-5 && (hits.t[1] - 0.2).abs() < 1e-3 && (hits.t[2] - 0.2).abs() < 1e-3);
    assert_eq!(hits.tri[3], HitColumns::MISS);
    assert!((hits.t[4] - 0.2487).abs() < 1e-4);

    w.run_system_once(photonwave::wavefront::classify::classify_photons).unwrap();
    let c = w.resource::<PhotonWork>().classified.clone();
    assert_eq!(c, Classified { diffuse: vec![0, 4], mirror: vec![1], glass: vec![2], escaped: vec![3] });

    w.run_system_once(photonwave::wavefront::deposit::deposit_photons).unwrap();
    let work = w.resource::<PhotonWork>();
    assert_eq!(work.survivors, vec![0, 4]);
    let stored: Vec<(u64, u32)> = work.deposits.iter().map(|d| (d.0, d.1)).collect();
    assert_eq!(stored, vec![(100, 0), (104, 0)]);
    let floor = &work.deposits[0].2;
    assert_eq!(floor.flags, flags::DIRECT | flags::FLAT);
    assert!((floor.position - Vec3::ZERO).length() < 1e-5 && floor.normal == Vec3::Y && floor.wi == Vec3::Y);
    assert_eq!(floor.power, Vec3::splat(2.0));

    w.run_system_once(photonwave::wavefront::shade::scatter_photons).unwrap();
    w.run_system_once(photonwave::wavefront::shade::refract_photons).unwrap();
    let next = &w.resource::<PhotonWork>().next;
    assert!(next.bounce.iter().all(|&b| b == 1));
    assert!(next.specular_only.iter().zip(&next.path).all(|(&s, &p)| s == (p == 101 || p == 102)));
    for k in 0..next.len() {
        let d = next.rays.direction(k);
        match next.path[k] {
            // The mirror's top reflects straight up, Russian roulette at p = ks keeps power.
            101 => {
                assert!((d - Vec3::Y).length() < 1e-3 && (next.power[k] - Vec3::splat(2.0)).abs().max_element() < 1e-5)
            }
            // Glass: up (reflection) or down into the sphere (refraction), power unchanged.
            102 => assert!(d.y.abs() > 0.99 && next.power[k] == Vec3::splat(2.0)),
            100 | 104 => assert!(d.dot(if next.path[k] == 100 { Vec3::Y } else { Vec3::NEG_Y }) > 0.0),
            p => panic!("unexpected path {p}"),
        }
    }
}

#[test]
fn caustic_photons_are_kept_only_after_a_specular_bounce() {
    let mut w = photon_world(Domain::CausticPhoton);
    w.run_system_once(photonwave::wavefront::intersect::intersect_photons).unwrap();
    w.run_system_once(photonwave::wavefront::classify::classify_photons).unwrap();
    w.run_system_once(photonwave::wavefront::deposit::deposit_photons).unwrap();
    let work = w.resource::<PhotonWork>();
    assert!(work.deposits.is_empty() && work.survivors.is_empty());
}

#[test]
fn emit_photons_starts_a_batch_like_the_reference() {
    let mut w = world(Settings::default());
    w.insert_resource(PhotonWork {
        domain: Some(Domain::GlobalPhoton),
        first_path: 5 * 16_384,
        paths: 16_384,
        ..Default::default()
    });
    w.run_system_once(photonwave::wavefront::emit::emit_photons).unwrap();
    let shared = w.resource::<Shared>();
    let q = &w.resource::<PhotonWork>().queue;
    assert_eq!(q.len(), photonwave::transport::photon::BATCH);
    for k in [0usize, 777, 16_383] {
        let photonwave::transport::photon::Start::Photon(p) =
            photonwave::transport::photon::start_photon(&shared.scene, &shared.job, Domain::GlobalPhoton, q.path[k])
        else {
            panic!("path {k} starts no photon")
        };
        assert_eq!((q.rays.origin(k), q.rays.direction(k), q.power[k]), (p.origin, p.dir, p.power));
        assert_eq!(q.path[k], 5 * 16_384 + k as u64);
    }
}

fn camera_world(segments: &[(usize, PathKind)]) -> World {
    let settings = Settings {
        width: 2,
        height: 1,
        spp: 4,
        photons: 20_000,
        caustic_photons: 5_000,
        gather_rays: 3,
        ..Default::default()
    };
    let mut w = world(settings.clone());
    let scene = w.resource::<Shared>().scene.clone();
    let (maps, _, _) = build_maps(&scene, &settings).unwrap();
    w.insert_resource(Maps(Arc::new(maps)));
    let camera = load("cornell-spheres.toml").camera.unwrap().prepare(2, 1).unwrap();
    let mut paths = PathQueue::default();
    let all = lanes();
    for (sample, &(lane, kind)) in segments.iter().enumerate() {
        let (o, d) = all[lane];
        paths.push(Segment {
            origin: o,
            dir: d,
            sample: sample as u32,
            kind,
            key: Sampler::new(1, Domain::Camera, sample as u64).key(),
            base: if kind == PathKind::Gather { 0 } else { 1 },
            depth: 0,
            beta: Vec3::ONE,
            term: Term::Indirect,
            through_specular: false,
            mis: 0.0,
        });
    }
    w.insert_resource(CameraWork {
        camera,
        first_sample: 0,
        count: 8,
        paths,
        next: PathQueue::default(),
        classified: Classified::default(),
        shadows: ShadowQueue::default(),
        terms: vec![Terms::default(); 8],
        receivers: vec![Default::default(); 8],
        lobe_receivers: vec![Default::default(); 8],
        narrow_hits: vec![false; 8],
        film: Vec::new(),
        open: Default::default(),
        rays: Default::default(),
        numerics: Default::default(),
    });
    w
}

fn intersect_and_classify(w: &mut World) {
    w.run_system_once(photonwave::wavefront::intersect::intersect_paths).unwrap();
    w.run_system_once(photonwave::wavefront::classify::classify_paths).unwrap();
}

#[test]
fn emission_is_added_for_camera_rays_only() {
    let mut w = camera_world(&[(4, PathKind::Camera), (4, PathKind::Gather), (0, PathKind::Camera)]);
    intersect_and_classify(&mut w);
    w.run_system_once(photonwave::wavefront::deposit::deposit_emission).unwrap();
    let t = &w.resource::<CameraWork>().terms;
    assert_eq!(t[0].emitted, Vec3::new(15.0, 11.0, 6.0));
    assert_eq!(t[1], Terms::default());
    assert_eq!(t[2], Terms::default());
}

#[test]
fn diffuse_camera_hits_queue_shadow_rays_gather_rays_and_estimates() {
    let mut w = camera_world(&[(0, PathKind::Camera), (0, PathKind::Gather)]);
    intersect_and_classify(&mut w);
    w.run_system_once(photonwave::wavefront::gather::gather_global).unwrap();
    // The gather lane read the maps at the floor; the camera lane waits for its gather rays.
    let t = w.resource::<CameraWork>().terms.clone();
    assert!(t[1].indirect.min_element() > 0.0 && t[0] == Terms::default());

    w.run_system_once(photonwave::wavefront::shade::shade_direct).unwrap();
    let shadows = w.resource::<CameraWork>().shadows.clone();
    assert_eq!(shadows.len(), 1, "one area-light sample for the camera lane");
    assert_eq!((shadows.sample[0], shadows.term[0]), (0, Term::Direct));
    w.run_system_once(photonwave::wavefront::intersect::trace_shadow_rays).unwrap();
    let work = w.resource::<CameraWork>();
    assert!(work.shadows.is_empty());
    assert!(work.terms[0].direct.min_element() > 0.0, "the floor under the light is lit");

    w.run_system_once(photonwave::wavefront::shade::spawn_gather_rays).unwrap();
    let next = &w.resource::<CameraWork>().next;
    assert_eq!(next.len(), 3);
    let kd = Vec3::splat(0.73);
    for k in 0..3 {
        assert_eq!(
            (next.kind[k], next.sample[k], next.term[k], next.depth[k]),
            (PathKind::Gather, 0, Term::Indirect, 0)
        );
        assert!((next.beta[k] - kd / 3.0).abs().max_element() < 1e-6 && next.rays.direction(k).y > 0.0);
    }
}

#[test]
fn mirror_hits_continue_through_specular() {
    let mut w = camera_world(&[(1, PathKind::Camera)]);
    intersect_and_classify(&mut w);
    w.run_system_once(photonwave::wavefront::shade::reflect_paths).unwrap();
    let next = &w.resource::<CameraWork>().next;
    assert_eq!(next.len(), 1);
    assert_eq!((next.depth[0], next.through_specular[0], next.kind[0]), (1, true, PathKind::Camera));
    assert!((next.beta[0] - Vec3::splat(0.95)).abs().max_element() < 1e-6);
    assert!((next.rays.direction(0) - Vec3::Y).length() < 1e-3);
}

#[test]
fn resolve_averages_each_pixels_samples_and_drops_non_finite_ones() {
    let mut w = camera_world(&[]);
    {
        let mut work = w.resource_mut::<CameraWork>();
        for (i, t) in work.terms.iter_mut().enumerate() {
            t.direct = Vec3::splat(i as f32);
        }
        work.terms[5].caustic = Vec3::splat(f32::NAN);
        // Four finite samples whose f32 sum overflows: averaged sample by sample.
        for t in &mut work.terms[..4] {
            t.emitted = Vec3::splat(3e38);
        }
    }
    w.run_system_once(photonwave::wavefront::shade::resolve_wave).unwrap();
    let work = w.resource::<CameraWork>();
    assert_eq!(work.film[0].direct, Vec3::splat((0.0 + 1.0 + 2.0 + 3.0) / 4.0));
    assert_eq!(work.film[0].emitted, Vec3::splat(3e38));
    assert_eq!(work.film[1].direct, Vec3::splat((4.0 + 6.0 + 7.0) / 4.0));
    assert_eq!(work.numerics.camera_samples, 1);
    assert_eq!(work.numerics.pixel_overflow, 1);
}

#[test]
fn emit_camera_rays_fills_the_wave() {
    let mut w = camera_world(&[]);
    w.run_system_once(photonwave::wavefront::emit::emit_camera_rays).unwrap();
    let work = w.resource::<CameraWork>();
    assert_eq!(work.paths.len(), 8);
    for k in 0..8 {
        assert_eq!(work.paths.key[k], Sampler::new(1, Domain::Camera, k as u64).key());
        assert_eq!((work.paths.kind[k], work.paths.sample[k], work.paths.base[k]), (PathKind::Camera, k as u32, 1));
    }
    // Samples 0..4 belong to pixel 0 (left half), 4..8 to pixel 1.
    assert!(work.paths.rays.direction(0).x < 0.0 && work.paths.rays.direction(7).x > 0.0);
}
