//! The 8-wide photon lookups against their scalar twins, lookup by lookup, and whole renders
//! with the SIMD kernels against renders with the scalar twins.

mod common;

use common::*;
use glam::Vec3;
use photonwave::code_path::CodePath;
use photonwave::photon_map::{flags, Filter, Lookup, Nearest, Photon, PhotonMap, Reflectance};
use photonwave::rng::{Domain, Sampler};
use photonwave::sampling::uniform_sphere;
use photonwave::settings::{Kernel, Settings};

/// Photons on three faces of a corner (floor, wall, ceiling-facing), with random powers,
/// directions and flags, plus photons placed on exact lattice points.
fn corner_photons(n: u64) -> Vec<Photon> {
    let mut v: Vec<Photon> = (0..n)
        .map(|i| {
            let s = Sampler::new(3, Domain::GlobalPhoton, i);
            let (a, b) = (s.get(0, 0), s.get(0, 1));
            let (position, normal) = match i % 3 {
                0 => (Vec3::new(a, 0.0, b), Vec3::Y),
                1 => (Vec3::new(a, b, 0.0), Vec3::Z),
                _ => (Vec3::new(0.0, a, b), Vec3::X),
            };
            let mut wi = uniform_sphere([s.get(0, 2), s.get(0, 3)]);
            if wi.dot(normal) < 0.0 {
                wi = -wi;
            }
            let power = Vec3::new(s.get(0, 4), s.get(0, 5), s.get(0, 6)) * 1e-3;
            Photon { position, power, wi, normal, flags: (i % 4) as u8 & (flags::DIRECT | flags::CAUSTIC) }
        })
        .collect();
    // A lattice: many photons at exactly equal distances from lattice-aligned queries.
    for i in 0..20 {
        for j in 0..20 {
            let position = Vec3::new(0.5 + i as f32 * 0.01, 0.0, 0.5 + j as f32 * 0.01);
            v.push(Photon { position, power: Vec3::splat(1e-3), wi: Vec3::Y, normal: Vec3::Y, flags: 0 });
        }
    }
    v
}

fn queries() -> Vec<(Vec3, Vec3)> {
    let mut q: Vec<(Vec3, Vec3)> = (0..2000u64)
        .map(|i| {
            let s = Sampler::new(4, Domain::Camera, i);
            let (a, b) = (s.get(0, 0), s.get(0, 1));
            match i % 3 {
                0 => (Vec3::new(a, 0.0, b), Vec3::Y),
                1 => (Vec3::new(a, b, 0.0), Vec3::Z),
                _ => (Vec3::new(0.0, a, b), Vec3::X),
            }
        })
        .collect();
    // On the lattice, in the corner edge, and outside everything.
    q.extend([
        (Vec3::new(0.55, 0.0, 0.55), Vec3::Y),
        (Vec3::new(0.6, 0.0, 0.6), Vec3::Y),
        (Vec3::ZERO, Vec3::Y),
        (Vec3::new(0.5, 0.0, 0.0), Vec3::Z),
        (Vec3::splat(10.0), Vec3::Y),
    ]);
    q
}

fn sorted(mut v: Vec<(f32, u32)>) -> Vec<(f32, u32)> {
    v.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    v
}

/// |a − b| ≤ 1e-5·max(|a|, |b|) per channel: sums of the same terms in another order.
fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().cmple(a.abs().max(b.abs()) * 1e-5 + Vec3::splat(1e-30)).all()
}

#[test]
fn simd_lookups_find_the_same_photons_as_the_scalar_twins() {
    let map = PhotonMap::build(corner_photons(30_000));
    let (mut a, mut b) = (Nearest::default(), Nearest::default());
    let glossy = |wi: Vec3| Vec3::splat(wi.y.max(0.0).powi(8));
    for (qi, (p, n)) in queries().into_iter().enumerate() {
        for (k, r_max, flags_mask) in [(1, 0.05, 0), (16, 0.02, 0), (64, 0.1, flags::DIRECT), (200, 0.01, 0)] {
            for kernel in [Kernel::Box, Kernel::Cone, Kernel::Epanechnikov] {
                // Every other query allows a slack of a tenth of its radius (far larger than any
                // rounding: the filter's absolute term, exercised on both code paths).
                let slack = if qi % 2 == 1 { 0.1 * r_max } else { 0.0 };
                let q = Lookup { p, k, r_max, kernel, filter: Filter { n, flags_mask, plane: 0.0, slack } };
                let simd = map.nearest(CodePath::Simd, &q, &mut a).to_vec();
                let scalar = map.nearest(CodePath::Scalar, &q, &mut b).to_vec();
                assert_eq!(sorted(simd), sorted(scalar), "query {qi} {q:?}: different photons");
                let lambert = Reflectance::Hemisphere { value: Vec3::splat(0.3), ng: n };
                for f in [Reflectance::Constant(Vec3::ONE), lambert, Reflectance::PerPhoton(&glossy)] {
                    let es = map.estimate(CodePath::Simd, &q, f, &mut a);
                    let ek = map.estimate(CodePath::Scalar, &q, f, &mut b);
                    assert_eq!(es.count, ek.count, "query {qi}");
                    assert_eq!(es.radius, ek.radius, "query {qi}");
                    assert!(close(es.radiance, ek.radiance), "query {qi}: {:?} vs {:?}", es.radiance, ek.radiance);
                    let rs = map.estimate_radius(CodePath::Simd, &q, f);
                    let rk = map.estimate_radius(CodePath::Scalar, &q, f);
                    assert_eq!(rs.count, rk.count, "query {qi}: radius lookup counts");
                    assert!(close(rs.radiance, rk.radiance), "query {qi}: {:?} vs {:?}", rs.radiance, rk.radiance);
                }
            }
        }
    }
}

/// The tree prunes exactly: every photon a brute-force scan finds within the radius is found by
/// both code paths' fixed-radius lookups (those that walk every subtree: boundary-corrected),
/// summed or turned away, and none outside — with photons
/// at exactly the radius (lattice queries), NaN and infinite positions in the map, queries far
/// outside it, radii from a hundredth to the whole scene, and an empty map. The corner photons
/// have axis-aligned normals, stored exactly, so the normal filter's verdict is known: a photon
/// is summed when its surface is the query's, turned away otherwise (no flags masked).
#[test]
fn fixed_radius_lookups_find_what_a_brute_force_scan_finds() {
    let mut photons = corner_photons(6000);
    for (i, position) in [
        Vec3::splat(f32::NAN),
        Vec3::new(0.3, f32::NAN, 0.3),
        Vec3::new(f32::INFINITY, 0.0, 0.2),
        Vec3::new(0.2, 0.0, f32::NEG_INFINITY),
    ]
    .into_iter()
    .enumerate()
    {
        photons.insert(i * 1000, Photon { position, power: Vec3::ONE, wi: Vec3::Y, normal: Vec3::Y, flags: 0 });
    }
    let map = PhotonMap::build(photons);
    let f = Reflectance::Constant(Vec3::ONE);
    let mut checked = 0;
    for (qi, (p, n)) in queries().into_iter().enumerate().step_by(7) {
        for r in [0.01f32, 0.03, 0.1, 2.0] {
            let q = Lookup {
                p,
                k: 0,
                r_max: r,
                kernel: Kernel::Box,
                filter: Filter { n, flags_mask: 0, plane: 0.0, slack: 0.0 },
            };
            // The lookup's own distance arithmetic, photon by photon.
            let (mut summed, mut turned) = (0u32, 0u32);
            for i in 0..map.len() {
                let (x, y, z) = (map.position(i).x - p.x, map.position(i).y - p.y, map.position(i).z - p.z);
                if x * x + y * y + z * z < r * r {
                    if map.photon(i).normal.dot(n) > 0.9 {
                        summed += 1;
                    } else {
                        turned += 1;
                    }
                }
            }
            let mut tested_turned = 0;
            for set in [CodePath::Simd, CodePath::Scalar] {
                // A boundary-corrected lookup tests every photon within the radius; a plain one
                // skips the subtrees that face away (`photon_map::orientation`), the same photons
                // on both paths.
                let all = map.estimate_radius_on_surface(set, &q, f, &[]);
                assert_eq!((all.count, all.rejected), (summed, turned), "query {qi}, r {r}, {set:?}");
                let e = map.estimate_radius(set, &q, f);
                assert!(e.count == summed && e.rejected <= turned, "query {qi}, r {r}, {set:?}: {e:?}");
                assert!(e.radiance.is_finite() && all.radiance.is_finite(), "query {qi}, r {r}, {set:?}");
                tested_turned = e.rejected;
            }
            let tested = map.photons_tested(&q, &mut Nearest::default());
            assert!(tested >= u64::from(summed + tested_turned), "query {qi}, r {r}");
            checked += summed;
        }
    }
    assert!(checked > 10_000, "the queries found photons: {checked}");
    // An empty map finds nothing, on both paths, for any query.
    let empty = PhotonMap::build(vec![]);
    for set in [CodePath::Simd, CodePath::Scalar] {
        let q = Lookup {
            p: Vec3::ZERO,
            k: 0,
            r_max: 1.0,
            kernel: Kernel::Box,
            filter: Filter { n: Vec3::Y, flags_mask: 0, plane: 0.0, slack: 0.0 },
        };
        let e = empty.estimate_radius(set, &q, f);
        assert_eq!((e.count, e.rejected, e.radiance), (0, 0, Vec3::ZERO), "{set:?}");
        assert!(empty.nearest(set, &Lookup { k: 8, ..q }, &mut Nearest::default()).is_empty(), "{set:?}");
    }
}

/// Query packets (8 fixed-radius estimates sharing one walk) give each query exactly what its
/// own SIMD estimate gives — the same photons met in the same order with the same arithmetic, so
/// equal to the bit, bias and boundary correction included — and the scalar twin's photons (sums
/// to rounding). Packets mix radii (a hundredth to the whole scene, zero, ∞, NaN), filters,
/// reflectances, corrected and uncorrected queries, non-finite points, lattice points with
/// photons at exactly the radius, and both coherent (jittered about one point) and scattered
/// queries; the map holds NaN and infinite photons; an empty map answers every query with nothing.
#[test]
fn query_packets_match_single_estimates_to_the_bit() {
    use photonwave::photon_map::boundary::Cut;
    use photonwave::photon_map::query_packet::{RadiusQuery, PACKET};
    use photonwave::photon_map::Estimate;
    let mut photons = corner_photons(20_000);
    for (i, position) in [Vec3::splat(f32::NAN), Vec3::new(f32::INFINITY, 0.0, 0.2)].into_iter().enumerate() {
        photons.insert(i * 999, Photon { position, power: Vec3::ONE, wi: Vec3::Y, normal: Vec3::Y, flags: 0 });
    }
    let map = PhotonMap::build(photons);
    let glossy = |wi: Vec3| Vec3::splat(wi.y.max(0.0).powi(8));
    let cut = [Cut { point: Vec3::new(0.52, 0.0, 0.0), inward: -Vec3::X }];
    let radii = [0.02f32, 0.05, 0.01, 0.1, 0.03, 2.0];
    let query = |j: usize, p: Vec3, n: Vec3| {
        let f = match j % 3 {
            0 => Reflectance::Constant(Vec3::new(1.0, 0.5, 0.25)),
            1 => Reflectance::Hemisphere { value: Vec3::splat(0.3), ng: n },
            _ => Reflectance::PerPhoton(&glossy),
        };
        let flags_mask = if j % 4 == 3 { flags::OWN_TERMS } else { 0 };
        RadiusQuery {
            lookup: Lookup {
                p,
                k: 0,
                r_max: radii[j % radii.len()],
                kernel: Kernel::Epanechnikov,
                filter: Filter { n, flags_mask, plane: 0.0, slack: if j % 5 == 1 { 0.01 } else { 0.0 } },
            },
            f,
            edges: j.is_multiple_of(2).then_some(&cut[..]),
        }
    };
    let all = queries();
    let mut packets: Vec<Vec<RadiusQuery>> = vec![];
    // Coherent: 8 points jittered about each query, on its surface.
    for (i, &(p, n)) in all.iter().enumerate().step_by(23) {
        let len = 1 + i % PACKET;
        let t = if n.y != 0.0 { Vec3::X } else { Vec3::Y };
        let packet = (0..len).map(|j| query(i + j, p + t * (j as f32 * 0.004), n)).collect();
        packets.push(packet);
    }
    // Scattered: consecutive queries.
    for (c, chunk) in all.chunks(PACKET).enumerate().step_by(9) {
        packets.push(chunk.iter().enumerate().map(|(j, &(p, n))| query(c + j, p, n)).collect());
    }
    // Non-finite points and radii beside ordinary ones, and lattice points (photons at exactly r).
    let mut odd: Vec<RadiusQuery> =
        (0..PACKET).map(|j| query(j, Vec3::new(0.55, 0.0, 0.55 + j as f32 * 0.01), Vec3::Y)).collect();
    odd[1].lookup.p = Vec3::splat(f32::NAN);
    odd[3].lookup.r_max = 0.0;
    odd[4].lookup.r_max = f32::INFINITY;
    odd[5].lookup.r_max = f32::NAN;
    odd[6].lookup.p = Vec3::new(f32::INFINITY, 0.0, 0.5);
    packets.push(odd);
    let empty = PhotonMap::build(vec![]);
    let mut found = 0;
    for (m, map) in [&map, &empty].into_iter().enumerate() {
        for (pi, packet) in packets.iter().enumerate() {
            for bias in [false, true] {
                let mut got = [Estimate::default(); PACKET];
                let mut twin = [Estimate::default(); PACKET];
                map.estimate_radius_packet(CodePath::Simd, packet, bias, &mut got);
                map.estimate_radius_packet(CodePath::Scalar, packet, bias, &mut twin);
                for (j, q) in packet.iter().enumerate() {
                    let one = map.estimate_radius_with(CodePath::Simd, &q.lookup, q.f, q.edges, bias);
                    let (g, t) = (got[j], twin[j]);
                    let what = format!("map {m}, packet {pi}, query {j}, bias {bias}: {g:?} vs {one:?}");
                    assert_eq!(
                        (g.count, g.rejected, g.radius.to_bits()),
                        (one.count, one.rejected, one.radius.to_bits()),
                        "{what}"
                    );
                    assert_eq!(
                        g.radiance.to_array().map(f32::to_bits),
                        one.radiance.to_array().map(f32::to_bits),
                        "{what}"
                    );
                    assert_eq!(g.bias.to_array().map(f32::to_bits), one.bias.to_array().map(f32::to_bits), "{what}");
                    assert_eq!((t.count, t.rejected), (g.count, g.rejected), "{what}: the scalar twin");
                    assert!(close(t.radiance, g.radiance), "{what}: the scalar twin {:?}", t.radiance);
                    assert!(g.radiance.is_finite() && g.bias.is_finite(), "{what}");
                    found += g.count;
                }
            }
        }
    }
    assert!(found > 100_000, "the packets found photons: {found}");
}

#[test]
fn lookups_honour_the_radius_and_the_filters_exactly() {
    // Photons at exactly the search radius are outside (the interval is open), on both twins;
    // photons on the perpendicular wall or with a masked flag are never found.
    let r = 0.25f32;
    let mut photons = vec![];
    for (i, d) in [Vec3::X, Vec3::Z, -Vec3::X, -Vec3::Z].into_iter().enumerate() {
        photons.push(Photon { position: d * r, power: Vec3::ONE, wi: Vec3::Y, normal: Vec3::Y, flags: 0 });
        photons.push(Photon { position: d * r * 0.5, power: Vec3::ONE, wi: Vec3::Y, normal: Vec3::Y, flags: 0 });
        // A wall photon right at the query, and a masked one.
        photons.push(Photon { position: d * 0.01, power: Vec3::ONE, wi: Vec3::X, normal: Vec3::X, flags: 0 });
        let flags = if i % 2 == 0 { flags::CAUSTIC } else { flags::DIRECT };
        photons.push(Photon { position: d * 0.02, power: Vec3::ONE, wi: Vec3::Y, normal: Vec3::Y, flags });
    }
    let map = PhotonMap::build(photons);
    for set in [CodePath::Simd, CodePath::Scalar] {
        let q = Lookup {
            p: Vec3::ZERO,
            k: 100,
            r_max: r,
            kernel: Kernel::Box,
            filter: Filter { n: Vec3::Y, flags_mask: flags::DIRECT | flags::CAUSTIC, plane: 0.0, slack: 0.0 },
        };
        let mut out = Nearest::default();
        assert_eq!(map.nearest(set, &q, &mut out).len(), 4, "{set:?}: only the four at half the radius");
        let e = map.estimate_radius(set, &q, Reflectance::Constant(Vec3::ONE));
        assert_eq!(e.count, 4, "{set:?}");
        // Box kernel: 4 photons of unit power over πr².
        let want = 4.0 / (std::f32::consts::PI * r * r);
        assert!((e.radiance.x - want).abs() < 1e-5 * want, "{set:?}: {} vs {want}", e.radiance.x);
        // Non-finite queries find nothing and stay finite.
        for p in [Vec3::splat(f32::NAN), Vec3::splat(f32::INFINITY), Vec3::new(f32::NEG_INFINITY, 0.0, 0.0)] {
            let q = Lookup { p, ..q };
            assert!(map.nearest(set, &q, &mut out).is_empty(), "{set:?}: {p:?} found photons");
            let e = map.estimate(set, &q, Reflectance::Constant(Vec3::ONE), &mut out);
            assert!(e.radiance.is_finite() && e.count == 0, "{set:?}: {p:?}");
        }
    }
}

#[test]
fn photon_packing_stays_within_its_stated_error_bounds() {
    // 20 bytes a photon: power per channel within 2⁻⁷ of the largest channel (dithered), incoming direction
    // within 1°, normal within 4° (photon_map/mod.rs module notes).
    assert_eq!(PhotonMap::bytes_per_photon(), 20);
    let photons: Vec<Photon> = (0..5000u64)
        .map(|i| {
            let s = Sampler::new(5, Domain::GlobalPhoton, i);
            let wi = uniform_sphere([s.get(0, 0), s.get(0, 1)]);
            let normal = uniform_sphere([s.get(0, 2), s.get(0, 3)]);
            let scale = 10f32.powf(s.get(0, 4) * 12.0 - 6.0);
            let power = Vec3::new(s.get(0, 5), s.get(0, 6), s.get(0, 7)) * scale;
            Photon { position: Vec3::new(i as f32, 0.0, 0.0), power, wi, normal, flags: (i % 4) as u8 }
        })
        .collect();
    let map = PhotonMap::build(photons.clone());
    for i in 0..map.len() {
        let got = map.photon(i);
        let want = photons[got.position.x as usize];
        let max = want.power.max_element();
        assert!(
            (got.power - want.power).abs().max_element() <= max / 128.0,
            "{i}: {:?} vs {:?}",
            got.power,
            want.power
        );
        assert!(got.wi.dot(want.wi) >= 1f32.to_radians().cos(), "{i}: wi {:?} vs {:?}", got.wi, want.wi);
        assert!(got.normal.dot(want.normal) >= 4f32.to_radians().cos(), "{i}: n {:?} vs {:?}", got.normal, want.normal);
        assert_eq!(got.flags, want.flags);
    }
}

#[test]
fn renders_with_simd_kernels_match_renders_with_scalar_twins() {
    // Traversal is bit-identical and lookups find the same photons; only the order in which
    // photon contributions are summed differs. Tolerance 1e-5 relative per pixel and channel.
    for scene in ["cornell-box.toml", "cornell-spheres.toml"] {
        let loaded = load(scene);
        let base = Settings {
            width: 24,
            height: 24,
            spp: 2,
            photons: 20_000,
            caustic_photons: 10_000,
            gather_rays: 4,
            ..Default::default()
        };
        let simd = render(&loaded, &Settings { code_path: CodePath::Simd, ..base.clone() });
        let scalar = render(&loaded, &Settings { code_path: CodePath::Scalar, ..base });
        for (a, b) in simd.beauty().iter().zip(scalar.beauty()) {
            assert!(close(*a, b), "{scene}: {a:?} vs {b:?}");
        }
    }
}

/// Packets, single rays and 8-wide packets find the same hits, so the per-queue choice between
/// them changes speed only: renders with every queue on each kernel, and with the timed trials
/// (on two threads, so that trials run concurrently) are identical to the bit, and the trials
/// report a choice for each queue that ran one, with a speed for each kernel it tried.
#[test]
fn the_traversal_choice_never_changes_an_image() {
    use photonwave::traversal_choice::{Kernel, TraversalChoice};
    use std::sync::Arc;
    let loaded = load("cornell-spheres.toml");
    let settings = Settings {
        width: 64,
        height: 64,
        spp: 2,
        photons: 20_000,
        caustic_photons: 10_000,
        gather_rays: 4,
        threads: 2,
        ..Default::default()
    };
    let cam = loaded.camera.unwrap().prepare(settings.width, settings.height).unwrap();
    let scene = Arc::new(loaded.scene);
    let render = |traversal: TraversalChoice| {
        let job = photonwave::job::Job { traversal: Arc::new(traversal), ..job(&scene, &settings) };
        photonwave::wavefront::render_job(scene.clone(), &cam, &job, &photonwave::progress::NoProgress)
    };
    let (packets, _) = render(TraversalChoice::fixed(Kernel::Packets));
    let (single, _) = render(TraversalChoice::fixed(Kernel::Single));
    let (wide_packets, _) = render(TraversalChoice::fixed(Kernel::WidePackets));
    let (chosen, stats) = render(TraversalChoice::timed());
    assert!(packets == single, "single rays changed the image");
    assert!(packets == wide_packets, "8-wide packets changed the image");
    assert!(packets == chosen, "the trials changed the image");
    let queues: Vec<&str> = stats.traversal.iter().map(|c| c.queue.as_str()).collect();
    for q in ["camera", "emitted", "photon", "secondary", "shadow"] {
        assert!(queues.contains(&q), "{q} not in {queues:?}");
    }
    let speed = |v: Option<f64>| v.is_some_and(|v| v.is_finite() && v > 0.0);
    for c in &stats.traversal {
        assert!(speed(c.packets_mrays) && speed(c.wide_packets_mrays), "{c:?}");
        // Camera rays never try single rays.
        assert_eq!(speed(c.single_mrays), c.queue != "camera", "{c:?}");
    }
}
