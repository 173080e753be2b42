//! Packet traversal against its scalar twin, lane by lane: random rays on the bundled scenes and
//! the edge cases where slab tests and triangle tests usually disagree.

mod common;

use common::*;
use glam::Vec3;
use photonwave::geometry::bvh::TriangleColumns;
use photonwave::geometry::packet::{closest_packets, occluded_packets};
use photonwave::geometry::traverse::{closest_rays, occluded_rays};
use photonwave::geometry::{wide_packet, wide_traverse};
use photonwave::geometry::{Bvh, Hit, RayQuery};
use photonwave::rng::{Domain, Sampler};
use photonwave::sampling::uniform_sphere;

/// Runs both twins on `rays` and asserts identical results lane by lane; returns the hits.
fn agree(bvh: &Bvh, tris: TriangleColumns<'_>, rays: &[RayQuery]) -> Vec<Option<Hit>> {
    let mut a = vec![None; rays.len()];
    let mut b = vec![None; rays.len()];
    closest_rays(bvh, tris, rays, &mut a);
    closest_packets(bvh, tris, rays, &mut b);
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        assert_eq!(x, y, "closest hit differs for ray {i}: {:?}", rays[i]);
    }
    // The 8-wide BVH, with its 8-wide child and triangle tests and with the child test's
    // scalar twin.
    for (label, simd) in [("8-wide", true), ("8-wide scalar", false)] {
        let mut w = vec![None; rays.len()];
        if simd {
            wide_traverse::closest_rays::<true>(bvh.wide(tris), tris.cut, rays, &mut w);
        } else {
            wide_traverse::closest_rays::<false>(bvh.wide(tris), tris.cut, rays, &mut w);
        }
        for (i, (x, y)) in a.iter().zip(&w).enumerate() {
            assert_eq!(x, y, "{label}: closest hit differs for ray {i}: {:?}", rays[i]);
        }
    }
    // Packets of 8 through the 8-wide BVH: never handing lanes over to single rays, at the
    // default, and handing over at every node (each lane walks alone from the root).
    let mut ops = vec![];
    for thin in [0, wide_packet::THIN_LANES, 8] {
        let mut wp = vec![None; rays.len()];
        wide_packet::closest_packets8(bvh.wide(tris), tris, rays, &mut wp, thin);
        for (i, (x, y)) in a.iter().zip(&wp).enumerate() {
            assert_eq!(x, y, "8-wide packets (thin {thin}): closest hit differs for ray {i}: {:?}", rays[i]);
        }
        let mut op = vec![false; rays.len()];
        wide_packet::occluded_packets8(bvh.wide(tris), tris, rays, &mut op, thin);
        ops.push((thin, op));
    }
    let mut oa = vec![false; rays.len()];
    let mut ob = vec![false; rays.len()];
    let mut ow = vec![false; rays.len()];
    let mut os = vec![false; rays.len()];
    occluded_rays(bvh, tris, rays, &mut oa);
    occluded_packets(bvh, tris, rays, &mut ob);
    wide_traverse::occluded_rays::<true>(bvh.wide(tris), tris.cut, rays, &mut ow);
    wide_traverse::occluded_rays::<false>(bvh.wide(tris), tris.cut, rays, &mut os);
    for (i, x) in oa.iter().enumerate() {
        assert_eq!(*x, ob[i], "packet: any hit differs for ray {i}: {:?}", rays[i]);
        assert_eq!(*x, ow[i], "8-wide: any hit differs for ray {i}: {:?}", rays[i]);
        assert_eq!(*x, os[i], "8-wide scalar: any hit differs for ray {i}: {:?}", rays[i]);
        for (thin, op) in &ops {
            assert_eq!(*x, op[i], "8-wide packets (thin {thin}): any hit differs for ray {i}: {:?}", rays[i]);
        }
        // Any hit and closest hit agree on whether something is in (0, t_max).
        assert_eq!(*x, a[i].is_some(), "any vs closest for ray {i}");
    }
    a
}

fn random_rays(scene: &photonwave::scene::Scene, n: u64, seed: u64) -> Vec<RayQuery> {
    let c = scene.centre();
    let r = scene.radius();
    (0..n)
        .map(|i| {
            let s = Sampler::new(seed, Domain::Camera, i);
            let o = c + uniform_sphere([s.get(0, 0), s.get(0, 1)]) * r * s.get(0, 2) * 1.5;
            let d = uniform_sphere([s.get(0, 3), s.get(0, 4)]);
            let t_max = if i % 3 == 0 { f32::INFINITY } else { r * s.get(0, 5) * 2.0 };
            RayQuery::new(o, d, t_max)
        })
        .collect()
}

#[test]
fn packets_match_scalar_on_random_rays() {
    for name in ["cornell-box.toml", "cornell-spheres.toml", "furnace.toml"] {
        let loaded = load(name);
        let s = &loaded.scene;
        let rays = random_rays(s, 4000, 7);
        let hits = agree(s.bvh(), s.columns(), &rays);
        assert!(hits.iter().filter(|h| h.is_some()).count() > 1000, "{name}: too few hits to mean anything");
    }
}

#[test]
fn packets_match_scalar_on_coherent_camera_rays() {
    let loaded = load("cornell-spheres.toml");
    let s = &loaded.scene;
    let cam = loaded.camera.unwrap().prepare(64, 64).unwrap();
    let rays: Vec<RayQuery> = (0..64 * 64)
        .map(|i| {
            let (o, d) = cam.ray((i % 64) as f32 + 0.5, (i / 64) as f32 + 0.5);
            RayQuery::new(o, d, f32::INFINITY)
        })
        .collect();
    let hits = agree(s.bvh(), s.columns(), &rays);
    for (h, r) in hits.iter().zip(&rays) {
        let o = s.bvh().closest_obvhs(s.columns(), r.origin, r.direction, r.t_max);
        assert_eq!(h.map(|h| h.tri), o.map(|h| h.tri), "{r:?} vs obvhs");
    }
    // The box is open toward the camera; the corner pixels see past its front edges.
    assert!(hits.iter().filter(|h| h.is_some()).count() > 64 * 60, "most camera rays hit the box");
}

#[test]
fn packets_match_scalar_on_edges_vertices_and_slab_planes() {
    let loaded = load("cornell-box.toml");
    let s = &loaded.scene;
    let c = s.centre();
    let mut rays = vec![];
    for t in 0..s.triangle_count() {
        let (p0, p1, p2) = (s.p0[t], s.p1[t], s.p2[t]);
        // Exactly at vertices and edge midpoints, from the centre and from outside along axes.
        for target in [p0, p1, p2, (p0 + p1) * 0.5, (p1 + p2) * 0.5, (p2 + p0) * 0.5] {
            rays.push(RayQuery::new(c, target - c, f32::INFINITY));
            // Axis-aligned rays whose other two direction components are exactly zero and whose
            // origin lies on the slab planes of the boxes that hold the target.
            for axis in 0..3 {
                let mut o = target;
                o[axis] = c[axis];
                let mut d = Vec3::ZERO;
                d[axis] = if target[axis] >= c[axis] { 1.0 } else { -1.0 };
                rays.push(RayQuery::new(o, d, f32::INFINITY));
            }
        }
        // Grazing: in the triangle's plane, along an edge.
        rays.push(RayQuery::new(p0 - (p1 - p0), p1 - p0, f32::INFINITY));
        // Hit distance exactly t_max (must not count: the interval is open).
        let h = s.intersect(c, (p0 + p1 + p2) / 3.0 - c, f32::INFINITY);
        if let Some(h) = h {
            rays.push(RayQuery::new(c, (p0 + p1 + p2) / 3.0 - c, h.t));
        }
    }
    // Invalid input: NaN, ±inf, zero direction, zero and negative t_max.
    let bad = [
        RayQuery::new(Vec3::splat(f32::NAN), Vec3::X, f32::INFINITY),
        RayQuery::new(c, Vec3::new(f32::NAN, 0.0, 1.0), f32::INFINITY),
        RayQuery::new(c, Vec3::new(f32::INFINITY, 0.0, 0.0), f32::INFINITY),
        RayQuery::new(Vec3::splat(f32::NEG_INFINITY), Vec3::X, f32::INFINITY),
        RayQuery::new(c, Vec3::ZERO, f32::INFINITY),
        RayQuery::new(c, Vec3::X, 0.0),
        RayQuery::new(c, Vec3::X, -1.0),
        RayQuery::new(c, Vec3::X, f32::NAN),
    ];
    rays.extend(bad);
    let hits = agree(s.bvh(), s.columns(), &rays);
    for h in &hits[hits.len() - bad.len()..] {
        assert!(h.is_none(), "invalid rays hit nothing");
    }
    // Each invalid ray in a packet with seven valid ones that hit (a packet traces a stand-in ray
    // in an invalid lane; it must never report that ray's hits).
    let valid: Vec<RayQuery> =
        rays.iter().zip(&hits).filter(|(r, h)| r.is_valid() && h.is_some()).map(|(r, _)| *r).collect();
    assert!(valid.len() >= 7);
    for (slot, b) in bad.iter().enumerate() {
        let mut mixed = valid[..7].to_vec();
        mixed.insert(slot % 8, *b);
        let got = agree(s.bvh(), s.columns(), &mixed);
        assert!(got[slot % 8].is_none(), "invalid ray {b:?} in lane {} hit something", slot % 8);
    }
    // Vertex- and edge-aimed rays from inside the closed box never slip through.
    let from_centre = hits.iter().zip(&rays).filter(|(_, r)| r.origin == c && r.t_max.is_infinite() && r.is_valid());
    for (h, r) in from_centre {
        assert!(h.is_some(), "ray {r:?} slipped through an edge or vertex");
    }
}

#[test]
fn packets_match_scalar_on_a_flat_mesh_with_slivers_and_degenerate_triangles() {
    // A unit grid in z = 0 (boxes flat in z), plus zero-area and sliver triangles.
    let n = 16;
    let (mut p0, mut p1, mut p2) = (vec![], vec![], vec![]);
    for i in 0..n {
        for j in 0..n {
            let q = |a: usize, b: usize| Vec3::new(a as f32 / n as f32, b as f32 / n as f32, 0.0);
            p0.extend([q(i, j), q(i, j)]);
            p1.extend([q(i + 1, j), q(i + 1, j + 1)]);
            p2.extend([q(i + 1, j + 1), q(i, j + 1)]);
        }
    }
    p0.extend([Vec3::new(0.5, 0.5, 0.5), Vec3::new(0.0, 0.0, 0.25)]);
    p1.extend([Vec3::new(0.5, 0.5, 0.5), Vec3::new(1.0, 1.0, 0.25)]);
    p2.extend([Vec3::new(0.6, 0.5, 0.5), Vec3::new(1.0, 1.0 + 1e-6, 0.25)]);
    let (bvh, order) = Bvh::build(&p0, &p1, &p2);
    let pick = |v: &Vec<Vec3>| order.iter().map(|&i| v[i as usize]).collect::<Vec<_>>();
    let (q0, q1, q2) = (pick(&p0), pick(&p1), pick(&p2));
    let cols = TriangleColumns::new(&q0, &q1, &q2);
    let mut rays = vec![];
    for i in 0..=4 * n {
        for j in 0..=4 * n {
            // Straight down onto grid lines and vertices (x, y multiples of 1/4n), direction
            // components exactly zero, origins on the boxes' x/y slab planes.
            let (x, y) = (i as f32 / (4 * n) as f32, j as f32 / (4 * n) as f32);
            rays.push(RayQuery::new(Vec3::new(x, y, 1.0), Vec3::new(0.0, 0.0, -1.0), f32::INFINITY));
            // Grazing: nearly in the plane.
            rays.push(RayQuery::new(Vec3::new(x, -0.5, 1e-7), Vec3::new(0.0, 1.0, -1e-7), f32::INFINITY));
        }
    }
    let hits = agree(&bvh, cols, &rays);
    for (h, r) in hits.iter().zip(&rays).step_by(2) {
        let o = bvh.closest_obvhs(cols, r.origin, r.direction, r.t_max);
        assert_eq!(h.is_some(), o.is_some(), "{r:?} vs obvhs");
    }
    let down = hits.iter().step_by(2).filter(|h| h.is_some()).count();
    assert_eq!(down, (4 * n + 1) * (4 * n + 1), "every ray straight down onto the closed grid hits");
}

#[test]
fn packets_match_scalar_on_rays_along_box_edges_and_faces() {
    // Rays that run exactly along the edges of BVH node boxes and inside their faces — where a
    // slab test's near and far distances coincide or a direction component is zero.
    for name in ["cornell-box.toml", "cornell-spheres.toml"] {
        let loaded = load(name);
        let s = &loaded.scene;
        let mut rays = vec![];
        for (k, node) in s.bvh().nodes().iter().enumerate() {
            let (lo, hi) = (Vec3::from(node.aabb.min), Vec3::from(node.aabb.max));
            let ext = hi - lo;
            for axis in 0..3 {
                // Along an edge: start before the box on the edge line.
                let mut o = lo;
                o[axis] -= ext[axis].max(1e-3);
                let mut d = Vec3::ZERO;
                d[axis] = 1.0;
                rays.push(RayQuery::new(o, d, f32::INFINITY));
                // Inside a face, diagonally across it (two non-zero components, one zero).
                let mut o2 = lo;
                let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
                o2[a] -= ext[a].max(1e-3);
                o2[b] -= ext[b].max(1e-3);
                let mut d2 = Vec3::ZERO;
                d2[a] = ext[a].max(1e-3) * 2.0 + ext[a];
                d2[b] = ext[b].max(1e-3) * 2.0 + ext[b];
                rays.push(RayQuery::new(o2, d2, if k % 2 == 0 { f32::INFINITY } else { 1.0 }));
            }
            // Through opposite corners.
            rays.push(RayQuery::new(lo - ext, ext, f32::INFINITY));
        }
        let hits = agree(s.bvh(), s.columns(), &rays);
        let n = hits.iter().filter(|h| h.is_some()).count();
        assert!(n > rays.len() / 10, "{name}: only {n} of {} edge rays hit anything", rays.len());
    }
}

/// Hard cases 9 and 13 (scenes/hard/watertight.toml): a closed cube whose faces are grids with a
/// strip of 1e-6-wide slivers, lying on the planes x, y, z = 0 and ±1 where rays have zero
/// direction components. From origins at the centre, on those planes, near a face and near a
/// corner, rays aimed exactly at every vertex and edge midpoint, and axis-aligned rays along the
/// grid lines: packet and scalar traversal agree lane by lane, and none slips out.
#[test]
fn watertight_mesh_edges_and_vertices_never_leak() {
    let loaded = load("hard/watertight.toml");
    let s = &loaded.scene;
    assert!(s.warnings.iter().any(|w| w.contains("6 degenerate")), "{:?}", s.warnings);
    let origins = [Vec3::ZERO, Vec3::new(0.0, 0.3, -0.2), Vec3::new(0.999_999, 0.0, 0.0), Vec3::new(-0.9, -0.9, 0.9)];
    let mut rays = vec![];
    for o in origins {
        for t in 0..s.triangle_count() {
            let (p0, p1, p2) = (s.p0[t], s.p1[t], s.p2[t]);
            for target in [p0, p1, p2, (p0 + p1) * 0.5, (p1 + p2) * 0.5, (p2 + p0) * 0.5] {
                if target != o {
                    rays.push(RayQuery::new(o, target - o, f32::INFINITY));
                }
            }
        }
        for g in [-0.5f32, -1e-6, 0.0, 0.5] {
            for axis in 0..3 {
                for sign in [-1.0f32, 1.0] {
                    // Along a grid line: the other components zero, the origin on its planes.
                    let mut origin = Vec3::splat(g);
                    origin[axis] = o[axis];
                    let mut d = Vec3::ZERO;
                    d[axis] = sign;
                    rays.push(RayQuery::new(origin, d, f32::INFINITY));
                }
            }
        }
    }
    let hits = agree(s.bvh(), s.columns(), &rays);
    for (h, r) in hits.iter().zip(&rays) {
        assert!(h.is_some(), "{r:?} slipped out of the closed cube");
    }
}

#[test]
/// The 8-wide BVH over a grid of small triangles: every triangle lands in exactly one leaf lane,
/// once, inside its child box.
fn collapse_keeps_every_triangle_once() {
    let mut p = [vec![], vec![], vec![]];
    for i in 0..40 {
        for j in 0..25 {
            let o = Vec3::new(i as f32, j as f32, (i * j % 7) as f32 * 0.1);
            p[0].push(o);
            p[1].push(o + Vec3::X * 0.9);
            p[2].push(o + Vec3::Y * 0.9);
        }
    }
    let (bvh, order) = Bvh::build(&p[0], &p[1], &p[2]);
    let cols: Vec<Vec<Vec3>> = p.iter().map(|c| order.iter().map(|&i| c[i as usize]).collect()).collect();
    let tris = TriangleColumns::new(&cols[0], &cols[1], &cols[2]);
    let wide = bvh.wide(tris);
    let mut seen = vec![0u32; order.len()];
    for b in wide.blocks() {
        for l in 0..8 {
            if b.live >> l & 1 == 1 {
                let id = b.ids[l as usize] as usize;
                seen[id] += 1;
                assert_eq!(b.triangle(l as usize), [tris.p0[id], tris.p1[id], tris.p2[id]]);
            }
        }
    }
    assert!(
        seen.iter().all(|&n| n == 1),
        "{} triangles not in exactly one leaf",
        seen.iter().filter(|&&n| n != 1).count()
    );
    for node in wide.nodes() {
        for slot in 0..8 {
            if node.valid >> slot & 1 == 0 || node.count[slot] == 0 {
                continue;
            }
            let (lo, hi) = node.child_box(slot);
            let first = node.child[slot] as usize;
            for b in &wide.blocks()[first..first + (node.count[slot] as usize).div_ceil(8)] {
                for l in 0..8 {
                    if b.live >> l & 1 == 1 {
                        for v in b.triangle(l) {
                            assert!(
                                lo.cmple(v.into()).all() && glam::Vec3A::from(v).cmple(hi).all(),
                                "{v} outside its box"
                            );
                        }
                    }
                }
            }
        }
    }
}

/// A cut-out for the kernels alone: triangles with an odd index pass rays where the first
/// barycentric is below ½ (a hard edge across each triangle), and triangles whose index is a
/// multiple of 3 pass half the rays by the ray's own hash (partial coverage).
struct TestCut;

impl photonwave::geometry::cut_out::CutOut for TestCut {
    fn passes(&self, tri: u32, b: [f32; 3], o: Vec3, d: Vec3) -> bool {
        let hard = tri % 2 == 1 && b[0] < 0.5;
        let soft = tri.is_multiple_of(3) && photonwave::geometry::cut_out::coverage_sample(tri, o, d) >= 0.5;
        hard || soft
    }
}

#[test]
fn every_kernel_passes_the_same_cut_outs() {
    // With cut-outs every kernel (BVH2 packets, 8-wide single rays with either child test,
    // 8-wide packets at every hand-over threshold, their scalar twin) keeps the same hits —
    // none of them on a passed texel — and any-hit agrees with closest-hit. The cut changes
    // many hits, so the test sees the filter at work.
    let cut = TestCut;
    for name in ["cornell-box.toml", "cornell-spheres.toml"] {
        let loaded = load(name);
        let s = &loaded.scene;
        let plain = s.columns();
        let tris = TriangleColumns { cut: Some(&cut), ..plain };
        let rays = random_rays(s, 4000, 11);
        let cut_hits = agree(s.bvh(), tris, &rays);
        let plain_hits = agree(s.bvh(), plain, &rays);
        let changed = cut_hits.iter().zip(&plain_hits).filter(|(a, b)| a != b).count();
        assert!(changed > 400, "{name}: the cut-outs changed only {changed} of 4000 hits");
        for (h, r) in cut_hits.iter().zip(&rays) {
            if let Some(h) = h {
                let passes = photonwave::geometry::cut_out::CutOut::passes(&cut, h.tri, h.b, r.origin, r.direction);
                assert!(!passes, "{name}: a kept hit lies on a passed texel: {h:?}");
            }
        }
        // A ray never hits farther with the cut than without it, and where the plain hit is kept
        // the two agree.
        for (a, b) in cut_hits.iter().zip(&plain_hits) {
            if let (Some(a), Some(b)) = (a, b) {
                assert!(a.t >= b.t, "{name}: a cut-out brought a hit nearer: {a:?} against {b:?}");
            }
        }
    }
}
