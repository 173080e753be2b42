//! Known answers: the white furnace, flux conservation, kernel normalisation, k-NN bias, and
//! irradiance from an area light against Lambert's polygon formula, by light sampling and by
//! light samples weighed against BSDF samples (MIS).

mod common;

use common::*;
use glam::Vec3;
use photonwave::code_path::CodePath;
use photonwave::material::{Bsdf, Material};
use photonwave::microfacet::Alpha;
use photonwave::photon_map::{Filter, Lookup, Nearest, Photon, PhotonMap, Reflectance};
use photonwave::progress::NoProgress;
use photonwave::reference::photons::trace_photons;
use photonwave::rng::{Domain, Sampler};
use photonwave::scene::{Light, MeshInput, Scene, SurfacePoint};
use photonwave::settings::{Kernel, Settings};
use photonwave::transport::direct::{direct_light, weighted_direct_light};
use photonwave::transport::gather::{gather_rays, glossy_ray};
use photonwave::transport::mis::{emission_found, receiver, Strategies};
use photonwave::transport::photon::first_hit_power;
use photonwave::transport::{Context, PhotonMaps};

/// Furnace: Le = 1, albedo a = 0.5 (scenes/furnace.toml).
const LE: f64 = 1.0;
const A: f64 = 0.5;

fn furnace_expected(bounces: u32) -> f64 {
    // Emission plus `bounces` orders of reflection: Le·(1 − a^(n+1))/(1 − a).
    LE * (1.0 - A.powi(bounces as i32 + 1)) / (1.0 - A)
}

#[test]
fn white_furnace_through_light_sampling() {
    let loaded = load("furnace.toml");
    for depth in [1u32, 3] {
        let s = Settings { width: 16, height: 16, spp: 16, max_depth: depth, ..Default::default() };
        let film = render_path(&loaded, &s);
        let (mean, se) = mean_and_se(&grey(&film));
        // Pixels are independent path-traced estimates: 4 standard errors, plus 1e-4 for f32 sums.
        let tol = 4.0 * se + 1e-4;
        let want = furnace_expected(depth);
        assert!((mean - want).abs() < tol, "depth {depth}: {mean} vs {want} ± {tol}");
    }
}

#[test]
fn white_furnace_through_the_photon_map() {
    let loaded = load("furnace.toml");
    let depth = 3;
    let base = Settings { width: 16, height: 16, spp: 4, photons: 60_000, max_depth: depth, ..Default::default() };
    // Read at the first hit: emission + direct (light sampling) + global photons that bounced at
    // least once, which carry orders 2..=depth.
    let direct_read = render(&loaded, &Settings { final_gather: false, ..base.clone() });
    // Final gather: emission + direct + a × (global map at the gather hit: orders 1..=depth),
    // i.e. orders up to depth + 1.
    let gathered = render(&loaded, &base);
    // The same through full density estimates at the gather hits instead of precomputed irradiance.
    let gathered_full = render(&loaded, &Settings { precompute_irradiance: false, ..base.clone() });
    // The photon-map part (≈ 0.44) is a k-NN estimate with relative σ ≈ 1/√(k−2) ≈ 0.13 per
    // lookup; ~60 000·3 photons / 64 per lookup ≈ 2 800 independent neighbourhoods → σ ≈ 0.0025·0.44.
    // Tolerance 1 %: more than 4σ of that, plus the tessellation's tiny non-uniformity.
    let cases = [
        (direct_read, furnace_expected(depth)),
        (gathered, furnace_expected(depth + 1)),
        (gathered_full, furnace_expected(depth + 1)),
    ];
    for (film, want) in cases {
        let (mean, _) = mean_and_se(&grey(&film));
        assert!((mean - want).abs() < 0.01 * want, "{mean} vs {want}");
    }
}

#[test]
fn first_hit_photon_power_sums_to_light_power() {
    // In a closed sphere every emitted photon lands; each carries Φ/N, so the first hits sum to Φ.
    let loaded = load("furnace.toml");
    let s = Settings::default();
    let pass = trace_photons(
        &loaded.scene,
        &job(&loaded.scene, &Settings { threads: 1, ..s.clone() }),
        Domain::GlobalPhoton,
        20_000,
        &NoProgress,
    );
    let got = first_hit_power(&pass.photons);
    let want = loaded.scene.total_power();
    assert!(((got - want) / want).abs().max_element() < 1e-4, "{got} vs {want}");
}

fn closed_cube(half: f32) -> MeshInput {
    // Six inward-facing faces of a cube, two triangles each.
    let mut m = MeshInput { source: "cube".into(), ..Default::default() };
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::from_array(std::array::from_fn(|i| if i == axis { sign } else { 0.0 }));
            let u = Vec3::from_array(std::array::from_fn(|i| if i == (axis + 1) % 3 { half } else { 0.0 }));
            let v = n.cross(u).normalize() * half;
            let c = n * half;
            let base = m.positions.len() as u32;
            m.positions.extend([c - u - v, c + u - v, c + u + v, c - u + v]);
            // Wind so the front face looks inward (−n).
            let tri = |a: u32, b: u32, cc: u32| [base + a, base + cc, base + b];
            m.triangles.push(tri(0, 1, 2));
            m.triangles.push(tri(0, 2, 3));
            m.material.extend([0, 0]);
        }
    }
    m
}

#[test]
fn spot_light_flux_is_conserved_in_a_closed_box() {
    // A spot light's photons carry unequal power (falloff / pdf); their sum estimates Φ.
    let mat = Material::new("grey", Bsdf::Lambert { kd: Vec3::splat(0.5) }, Vec3::ZERO);
    let spot = Light::Spot {
        position: Vec3::ZERO,
        direction: Vec3::new(0.3, -1.0, 0.2).normalize(),
        intensity: Vec3::new(2.0, 1.0, 0.5),
        cos_inner: 20f32.to_radians().cos(),
        cos_outer: 40f32.to_radians().cos(),
    };
    let scene = Scene::build(vec![closed_cube(1.0)], vec![mat], vec![spot], vec![]).unwrap();
    let pass = trace_photons(
        &scene,
        &job(&scene, &Settings { threads: 1, ..Settings::default().clone() }),
        Domain::GlobalPhoton,
        16_384,
        &NoProgress,
    );
    let got = first_hit_power(&pass.photons);
    let want = scene.total_power();
    // Per-photon weight w = falloff/E[falloff]: w ∈ [0, 1/E], E[falloff] = 0.51 here, so the
    // relative σ of the mean over N = 16 384 paths is ≤ √(1/0.51 − 1)/√N ≈ 0.8 %; 4σ = 3.1 %.
    assert!(((got - want) / want).abs().max_element() < 0.031, "{got} vs {want}");
}

#[test]
fn every_kernel_returns_a_uniform_density() {
    // A square lattice of spacing h with unit power: density 1/h². Lattice points in a disk of
    // radius r = 50h deviate from πr²/h² by O((r/h)^(2/3)) ≈ 14 of 7 854: tolerance 0.5 %.
    let h = 0.001f32;
    let mut photons = Vec::new();
    for i in -80..=80 {
        for j in -80..=80 {
            let position = Vec3::new(i as f32 * h + 0.000_31, 0.0, j as f32 * h + 0.000_17);
            photons.push(Photon { position, power: Vec3::ONE, wi: Vec3::Y, normal: Vec3::Y, flags: 0 });
        }
    }
    let map = PhotonMap::build(photons);
    let mut scratch = Nearest::default();
    for kernel in [Kernel::Box, Kernel::Cone, Kernel::Epanechnikov] {
        let q = Lookup {
            p: Vec3::ZERO,
            k: 100_000,
            r_max: 50.0 * h,
            kernel,
            filter: Filter { n: Vec3::Y, flags_mask: 0, plane: 0.0, slack: 0.0 },
        };
        let e = map.estimate(CodePath::Simd, &q, Reflectance::Constant(Vec3::ONE), &mut scratch);
        let rel = e.radiance.x * h * h;
        assert!((rel - 1.0).abs() < 0.005, "{kernel:?}: {rel}");
    }
}

#[test]
fn knn_estimate_is_unbiased_on_a_uniform_plane() {
    // N uniform photons in the unit square; k = 16; estimates at a grid of queries 0.01 apart
    // (neighbourhoods of radius ≈ 0.0023 do not overlap). (k−1)/(πr²) has mean ρ and relative
    // variance 1/(k−2); over Q ≈ 6 400 queries σ ≈ 0.0033, tolerance 4σ = 1.3 %. The biased
    // k/(πr²) would read 16/15 = +6.7 %.
    let n = 1_000_000u32;
    let s = Sampler::new(99, Domain::GlobalPhoton, 0);
    let photons: Vec<Photon> = (0..n)
        .map(|i| Photon {
            position: Vec3::new(s.get(i, 0), 0.0, s.get(i, 1)),
            power: Vec3::ONE,
            wi: Vec3::Y,
            normal: Vec3::Y,
            flags: 0,
        })
        .collect();
    let map = PhotonMap::build(photons);
    let mut scratch = Nearest::default();
    let (mut sum, mut q) = (0.0f64, 0);
    for i in 0..80 {
        for j in 0..80 {
            let p = Vec3::new(0.1 + i as f32 * 0.01, 0.0, 0.1 + j as f32 * 0.01);
            let look = Lookup {
                p,
                k: 16,
                r_max: 0.1,
                kernel: Kernel::Box,
                filter: Filter { n: Vec3::Y, flags_mask: 0, plane: 0.0, slack: 0.0 },
            };
            let e = map.estimate(CodePath::Simd, &look, Reflectance::Constant(Vec3::ONE), &mut scratch);
            sum += e.radiance.x as f64 / n as f64;
            q += 1;
        }
    }
    let mean = sum / q as f64;
    assert!((mean - 1.0).abs() < 0.013, "mean density ratio {mean}");
}

/// The quad light of radiance `le` the next two tests sit under: 1 × 1 at height 1, facing down
/// (wound (c0, c1, c2) and (c0, c2, c3)); returns the scene and its corners.
fn quad_light(le: f32) -> (Scene, [Vec3; 4]) {
    let corners =
        [Vec3::new(-0.5, 1.0, -0.5), Vec3::new(0.5, 1.0, -0.5), Vec3::new(0.5, 1.0, 0.5), Vec3::new(-0.5, 1.0, 0.5)];
    let mesh = MeshInput {
        source: "quad".into(),
        positions: corners.to_vec(),
        normals: vec![],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        material: vec![0, 0],
        ..Default::default()
    };
    let light = Material::new("light", Bsdf::Lambert { kd: Vec3::ZERO }, Vec3::splat(le));
    (Scene::build(vec![mesh], vec![light], vec![], vec![]).unwrap(), corners)
}

#[test]
fn quad_light_irradiance_matches_lamberts_formula() {
    let le = 3.0f32;
    let (scene, corners) = quad_light(le);
    let settings = Settings { light_samples: 256, ..Default::default() };
    let maps = PhotonMaps::default();
    let job = job(&scene, &settings);
    let ctx = Context::new(&scene, &maps, &job);
    let white = Bsdf::Lambert { kd: Vec3::ONE };
    for p in [Vec3::ZERO, Vec3::new(0.7, 0.0, 0.3), Vec3::new(2.0, 0.3, -1.0)] {
        let sp = floor_point(p);
        let mut rays = Default::default();
        // E = π·L_reflected for a white Lambertian; each call averages 256 light samples.
        let values: Vec<f32> = (0..256)
            .map(|i| {
                let s = Sampler::new(5, Domain::Camera, i);
                std::f32::consts::PI * direct_light(&ctx, &sp, &white, Vec3::Y, &s, &mut rays).x
            })
            .collect();
        let (mean, se) = mean_and_se(&values);
        let want = common::polygon_irradiance(p, Vec3::Y, &corners, le) as f64;
        assert!((mean - want).abs() < 4.0 * se + 1e-5 * want, "at {p}: {mean} vs {want} (se {se})");
    }
}

/// Multiple importance sampling (`transport::mis`) under the quad light of the test above: one
/// light sample weighed against 16 gather rays, plus the emission those rays hit weighed
/// likewise, is again Lambert's formula for a white Lambertian (within 4 standard errors of 512
/// estimates; weights that did not sum to one, such as a density missing its sample count, would
/// be off by far more). On a Phong surface whose lobe points at the light, the light sample
/// weighed against the gather rays and the glossy ray, plus both kinds' emission, agrees with the
/// light sample alone (4 096 estimates each, 4 standard errors of the difference), and on the
/// narrow lobes (Phong, rough plastic) is the less noisy of the two (measured: standard error
/// 0.0095 against 0.0216, 0.0019 against 0.0049): the one shadow ray is the same, the gather
/// and glossy rays are those the camera hit sends anyway.
#[test]
fn light_samples_weighed_against_gather_and_glossy_rays_keep_the_direct_light() {
    let le = 3.0f32;
    let (scene, corners) = quad_light(le);
    let settings = Settings::default();
    let maps = PhotonMaps::default();
    let job = job(&scene, &settings);
    let ctx = Context::new(&scene, &maps, &job);
    let point = floor_point;
    let n = 16;
    // One camera sample's direct light at `sp` on `bsdf` seen from `wo` with MIS: the weighed light
    // sample, the gather rays' emission (each weighted by its gather weight over n: kd/n, or the
    // rough plastic's base seen through its coat) and the glossy ray's.
    let mis_sample = |sp: &SurfacePoint, bsdf: &Bsdf, wo: Vec3, i: u64| {
        let s = Sampler::new(9, Domain::Camera, i);
        let mis = Strategies::Split { gather: n, glossy: bsdf.has_glossy_lobe() };
        let mut value = weighted_direct_light(&ctx, sp, bsdf, wo, &s.fork(1), &mis, &mut Default::default()).x;
        let r = receiver(sp, bsdf, wo);
        gather_rays(sp, wo, n, &s.fork(2), |_, o, d| {
            if let Some(hit) = scene.intersect(o, d, f32::INFINITY) {
                let e = emission_found(&ctx, &r, &hit, d, mis.gather_density(sp, wo, d));
                let w = if bsdf.gather_varies() { bsdf.gather_weight(&sp.frame, wo, d) } else { bsdf.diffuse() };
                value += w.x / n as f32 * e.x;
            }
        });
        if let Some(ray) = glossy_ray(sp, bsdf, wo, &s.fork(3)) {
            if let Some(hit) = scene.intersect(ray.origin, ray.dir, f32::INFINITY) {
                value +=
                    ray.weight.x * emission_found(&ctx, &r, &hit, ray.dir, mis.glossy_density(sp, bsdf, wo, ray.dir)).x;
            }
        }
        value
    };
    let white = Bsdf::Lambert { kd: Vec3::ONE };
    for p in [Vec3::ZERO, Vec3::new(0.7, 0.0, 0.3), Vec3::new(2.0, 0.3, -1.0)] {
        let values: Vec<f32> =
            (0..512).map(|i| std::f32::consts::PI * mis_sample(&point(p), &white, Vec3::Y, i)).collect();
        let (mean, se) = mean_and_se(&values);
        let want = common::polygon_irradiance(p, Vec3::Y, &corners, le) as f64;
        assert!((mean - want).abs() < 4.0 * se + 1e-5 * want, "at {p}: {mean} vs {want} (se {se})");
    }
    // The glossy point: its mirror direction toward the light's centre.
    let sp = point(Vec3::new(0.6, 0.0, 0.2));
    let to_light = (Vec3::new(0.0, 1.0, 0.0) - sp.p).normalize();
    let wo = Vec3::new(-to_light.x, to_light.y, -to_light.z);
    for (name, bsdf) in [
        ("phong", Bsdf::Glossy { kd: Vec3::splat(0.3), ks: Vec3::splat(0.7), exponent: 30.0 }),
        ("rough plastic", Bsdf::rough_plastic(Vec3::splat(0.5), 1.5, Alpha::ggx(0.05))),
        ("rough conductor", Bsdf::RoughConductor { ks: Vec3::splat(0.9), alpha: Alpha::beckmann(0.4), eta_k: None }),
    ] {
        let with: Vec<f32> = (0..4096).map(|i| mis_sample(&sp, &bsdf, wo, i)).collect();
        let without: Vec<f32> = (0..4096)
            .map(|i| {
                let s = Sampler::new(9, Domain::Camera, i);
                direct_light(&ctx, &sp, &bsdf, wo, &s.fork(1), &mut Default::default()).x
            })
            .collect();
        let (a, sa) = mean_and_se(&with);
        let (b, sb) = mean_and_se(&without);
        println!("{name}: MIS {a:.4} ± {sa:.4}, light samples alone {b:.4} ± {sb:.4}");
        assert!((a - b).abs() < 4.0 * (sa * sa + sb * sb).sqrt(), "{name}: MIS {a} ± {sa} against {b} ± {sb}");
        // The narrow lobes are where light sampling alone draws badly. Under this light of
        // about 0.7 sr, sampled by its solid angle, the wide conductor lobe (α 0.4) is lit well
        // by light samples alone, and the power heuristic, which hands part of the weight to the
        // glossy ray, measured 17 % noisier there (0.0022 against 0.0019): not a claim to make.
        if name != "rough conductor" {
            assert!(sa < sb, "{name}: MIS is noisier ({sa}) than light samples alone ({sb})");
        }
    }
}

#[test]
fn point_light_irradiance_is_inverse_square_cosine() {
    let mesh = closed_cube(10.0);
    let mat = Material::new("grey", Bsdf::Lambert { kd: Vec3::splat(0.5) }, Vec3::ZERO);
    let light = Light::Point { position: Vec3::new(0.0, 2.0, 0.0), intensity: Vec3::splat(4.0) };
    let scene = Scene::build(vec![mesh], vec![mat], vec![light], vec![]).unwrap();
    let settings = Settings::default();
    let maps = PhotonMaps::default();
    let job = job(&scene, &settings);
    let ctx = Context::new(&scene, &maps, &job);
    let p = Vec3::new(1.5, 0.0, 0.0);
    let sp = floor_point(p);
    let l = direct_light(
        &ctx,
        &sp,
        &Bsdf::Lambert { kd: Vec3::ONE },
        Vec3::Y,
        &Sampler::new(1, Domain::Camera, 0),
        &mut Default::default(),
    );
    let d2 = 1.5f32 * 1.5 + 4.0;
    let want = 4.0 * (2.0 / d2.sqrt()) / d2; // I·cos θ / d²
    assert!((std::f32::consts::PI * l.x - want).abs() < 1e-5 * want);
}

#[test]
fn directional_light_irradiance_is_cosine_weighted_by_both_methods() {
    // A white Lambertian floor lit by a directional light at θ from its normal: E = E⊥·cos θ, so
    // reflected radiance is kd·E⊥·cos θ/π. Light sampling is exact; the photon estimate (direct
    // photons, box kernel, k = 400 → relative σ ≈ 1/√398 = 5 % per lookup, averaged over 64
    // disjoint lookups → 0.6 %) gets 3 %.
    let kd = 0.8f32;
    let e_perp = 2.0f32;
    for deg in [0.0f32, 60.0] {
        let half = 10.0;
        let floor = MeshInput {
            source: "floor".into(),
            positions: vec![
                Vec3::new(-half, 0.0, -half),
                Vec3::new(half, 0.0, -half),
                Vec3::new(half, 0.0, half),
                Vec3::new(-half, 0.0, half),
            ],
            normals: vec![],
            triangles: vec![[0, 2, 1], [0, 3, 2]],
            material: vec![0, 0],
            ..Default::default()
        };
        let mat = Material::new("white", Bsdf::Lambert { kd: Vec3::splat(kd) }, Vec3::ZERO);
        let th = deg.to_radians();
        let light =
            Light::Directional { direction: Vec3::new(th.sin(), -th.cos(), 0.0), irradiance: Vec3::splat(e_perp) };
        let scene = Scene::build(vec![floor], vec![mat.clone()], vec![light], vec![]).unwrap();
        let want = kd * e_perp * th.cos() / std::f32::consts::PI;
        let settings = Settings { photons: 400_000, max_depth: 1, ..Default::default() };
        let maps = PhotonMaps {
            global: PhotonMap::build(
                trace_photons(
                    &scene,
                    &job(&scene, &Settings { threads: 2, ..settings.clone() }),
                    Domain::GlobalPhoton,
                    400_000,
                    &NoProgress,
                )
                .photons,
            ),
            ..Default::default()
        };
        let job = job(&scene, &settings);
        let ctx = Context::new(&scene, &maps, &job);
        let mut scratch = Nearest::default();
        let mut photon_sum = 0.0;
        for i in 0..8 {
            for j in 0..8 {
                let p = Vec3::new(-4.0 + i as f32, 0.0, -4.0 + j as f32);
                let sp = floor_point(p);
                let direct = direct_light(
                    &ctx,
                    &sp,
                    &mat.bsdf,
                    Vec3::Y,
                    &Sampler::new(1, Domain::Camera, 0),
                    &mut Default::default(),
                );
                assert!(
                    (direct.x - want).abs() < 1e-5 * want.max(1.0),
                    "θ={deg}: light sampling {} vs {want}",
                    direct.x
                );
                let q = Lookup {
                    p,
                    k: 400,
                    r_max: 1.0,
                    kernel: Kernel::Box,
                    filter: Filter { n: Vec3::Y, flags_mask: 0, plane: 0.0, slack: 0.0 },
                };
                let eval = |wi| mat.bsdf.eval(&sp.frame, Vec3::Y, wi);
                let e = maps.global.estimate(CodePath::Simd, &q, Reflectance::PerPhoton(&eval), &mut scratch);
                photon_sum += e.radiance.x;
            }
        }
        let photon = photon_sum / 64.0;
        assert!((photon - want).abs() < 0.03 * want, "θ={deg}: photons {photon} vs {want}");
    }
}

/// Boundary correction (issue 15): on a uniformly lit floor that meets a wall, and in a corner
/// where it meets two, a fixed-radius estimate divided by the part of its disk on the floor
/// equals the interior value; the plain estimate falls to ½ at the edge and ¼ in the corner.
/// Photons lie on a regular grid (spacing h = r/40, so ~5 000 in a disk): no noise, and the
/// count in a disk is off by far less than 1 %. The tolerance, 2 %, covers that and the polar
/// quadrature of the disk's cut part (exact by symmetry at the edge and corner, ~1 % between).
/// Both code paths find the same photons and agree to 1e-5.
#[test]
fn boundary_corrected_estimates_do_not_darken_edges_and_corners() {
    let (r, h) = (0.2f32, 0.005f32);
    let photon = |position: Vec3, normal: Vec3| Photon { position, power: Vec3::ONE, wi: normal, normal, flags: 0 };
    // Floor y = 0 over x < 0 (and z < 0 in the corner case), walls rising at x = 0 and z = 0.
    let room = |corner: bool| {
        let n = (1.0 / h) as i32;
        let at = |i: i32| (i as f32 + 0.5) * h;
        let mut photons = Vec::new();
        for i in 0..n {
            for j in -n..n {
                // Floor.
                if !corner || j < 0 {
                    photons.push(photon(Vec3::new(-at(i), 0.0, at(j)), Vec3::Y));
                }
                // Walls, sparser (their density does not matter, only where they are): x = 0
                // facing −x, and in the corner z = 0 facing −z.
                if i % 2 == 0 && j % 2 == 0 {
                    if !corner || j < 0 {
                        photons.push(photon(Vec3::new(0.0, at(i), at(j)), Vec3::NEG_X));
                    }
                    if corner && j < 0 {
                        photons.push(photon(Vec3::new(at(j), at(i), 0.0), Vec3::NEG_Z));
                    }
                }
            }
        }
        PhotonMap::build(photons)
    };
    for kernel in [Kernel::Box, Kernel::Cone] {
        for (corner, edge_share) in [(false, 0.5f32), (true, 0.25)] {
            let map = room(corner);
            let q = |p: Vec3| Lookup {
                p,
                k: 0,
                r_max: r,
                kernel,
                filter: Filter { n: Vec3::Y, flags_mask: 0, plane: 0.0, slack: 0.0 },
            };
            let f = Reflectance::Constant(Vec3::ONE);
            let inner = Vec3::new(-0.5, 0.0, -0.5);
            let interior = map.estimate_radius(CodePath::Scalar, &q(inner), f).radiance.x;
            for p in [Vec3::ZERO, Vec3::new(-0.1, 0.0, if corner { -0.1 } else { 0.3 })] {
                let plain = map.estimate_radius(CodePath::Scalar, &q(p), f).radiance.x;
                let fixed = map.estimate_radius_on_surface(CodePath::Scalar, &q(p), f, &[]).radiance.x;
                let simd = map.estimate_radius_on_surface(CodePath::Simd, &q(p), f, &[]).radiance.x;
                let what = format!("{kernel:?}, corner {corner}, at {p}");
                assert!((fixed / interior - 1.0).abs() < 0.02, "{what}: {fixed} vs interior {interior}");
                assert!((simd - fixed).abs() <= 1e-5 * fixed, "{what}: SIMD {simd} vs scalar {fixed}");
                if p == Vec3::ZERO {
                    assert!((plain / interior - edge_share).abs() < 0.02, "{what}: plain {plain} vs {interior}");
                }
            }
        }
    }
}

/// An open edge (a floor that simply ends, as at the front of CornellBox-Original) has no
/// photons beyond it to show the cut; the scene's open edges give it instead
/// (`scene::open_edges`). With that cut the estimate at the edge equals the interior value (the
/// same 2 % as above); without it, it is half.
#[test]
fn open_edges_cut_the_disk_where_no_photons_show_it() {
    use photonwave::photon_map::boundary::Cut;
    let (r, h) = (0.2f32, 0.005f32);
    let n = (1.0 / h) as i32;
    let at = |i: i32| (i as f32 + 0.5) * h;
    let photons = (0..n)
        .flat_map(|i| (-n..n).map(move |j| (i, j)))
        .map(|(i, j)| Photon {
            position: Vec3::new(-at(i), 0.0, at(j)),
            power: Vec3::ONE,
            wi: Vec3::Y,
            normal: Vec3::Y,
            flags: 0,
        })
        .collect();
    let map = PhotonMap::build(photons);
    let q = |p: Vec3| Lookup {
        p,
        k: 0,
        r_max: r,
        kernel: Kernel::Cone,
        filter: Filter { n: Vec3::Y, flags_mask: 0, plane: 0.0, slack: 0.0 },
    };
    let f = Reflectance::Constant(Vec3::ONE);
    let interior = map.estimate_radius(CodePath::Scalar, &q(Vec3::new(-0.5, 0.0, 0.0)), f).radiance.x;
    let edge = [Cut { point: Vec3::ZERO, inward: Vec3::NEG_X }];
    let cut = map.estimate_radius_on_surface(CodePath::Simd, &q(Vec3::ZERO), f, &edge).radiance.x;
    let uncut = map.estimate_radius_on_surface(CodePath::Simd, &q(Vec3::ZERO), f, &[]).radiance.x;
    assert!((cut / interior - 1.0).abs() < 0.02, "{cut} vs interior {interior}");
    assert!((uncut / interior - 0.5).abs() < 0.02, "{uncut} vs interior {interior}");
}

/// The bias estimate (Hachisuka, Jarosz and Jensen 2010) of a fixed-radius estimate: for
/// radiance quadratic over the disk, L(y) = 1 + c·|y|², the estimate's bias is exactly
/// ½·μ₂·r²·ΔL = 2c·μ₂·r² (μ₂·r² = r²/4 box, 3r²/20 cone, r²/6 Epanechnikov), and the bias
/// estimate must return it: photons on a grid (spacing r/40, ~5 000 in the disk) carrying
/// L·h², so the sums are quadratures of the integrals, off by far less than 1 %; the tolerance
/// is 2 % of the bias. The plain estimate minus L(q) is the same bias (the same 2 %). On a
/// uniform floor near a wall's foot, the boundary-corrected bias estimate is ~0: under 2 % of
/// the radiance (measured ≤ 1.5 % box, ≤ 0.8 % cone: the 8 × 32 polar quadrature of a thin cut
/// segment), where without the correction the cut disk reads as curvature of 8–15 %; without the
/// bias sum (passes that skip it) the radiance is the same to the bit and the bias 0. Both code
/// paths agree to 1e-5.
#[test]
fn bias_estimates_return_the_kernel_bias_of_quadratic_radiance() {
    let (r, h, c) = (0.2f32, 0.005f32, 25.0f32);
    let n = (0.3 / h) as i32;
    let at = |i: i32| (i as f32 + 0.5) * h;
    let radiance = |x: f32, z: f32| 1.0 + c * (x * x + z * z);
    let photon = |position: Vec3, power: f32, normal: Vec3| Photon {
        position,
        power: Vec3::splat(power),
        wi: normal,
        normal,
        flags: 0,
    };
    let mut photons = Vec::new();
    for i in -n..n {
        for j in -n..n {
            let (x, z) = (at(i), at(j));
            photons.push(photon(Vec3::new(x, 0.0, z), radiance(x, z) * h * h, Vec3::Y));
        }
    }
    let map = PhotonMap::build(photons);
    let f = Reflectance::Constant(Vec3::ONE);
    for (kernel, mu2) in [(Kernel::Box, 0.25f32), (Kernel::Cone, 0.15), (Kernel::Epanechnikov, 1.0 / 6.0)] {
        let want = 2.0 * c * mu2 * r * r;
        for p in [Vec3::ZERO, Vec3::new(0.03, 0.0, -0.05)] {
            let q = Lookup {
                p,
                k: 0,
                r_max: r,
                kernel,
                filter: Filter { n: Vec3::Y, flags_mask: 0, plane: 0.0, slack: 0.0 },
            };
            let scalar = map.estimate_radius(CodePath::Scalar, &q, f);
            let simd = map.estimate_radius(CodePath::Simd, &q, f);
            let what = format!("{kernel:?} at {p}");
            assert!((scalar.bias.x / want - 1.0).abs() < 0.02, "{what}: bias {} vs {want}", scalar.bias.x);
            let actual = scalar.radiance.x - radiance(p.x, p.z);
            assert!((actual / want - 1.0).abs() < 0.02, "{what}: actual bias {actual} vs {want}");
            assert!(
                (simd.bias.x - scalar.bias.x).abs() <= 1e-5 * want,
                "{what}: SIMD {} vs {}",
                simd.bias.x,
                scalar.bias.x
            );
        }
    }
    // A uniform floor (x < 0) at the foot of a wall (x = 0, facing −x).
    let mut photons = Vec::new();
    for i in 0..2 * n {
        for j in -n..n {
            photons.push(photon(Vec3::new(-at(i), 0.0, at(j)), h * h, Vec3::Y));
            if i % 2 == 0 && j % 2 == 0 {
                photons.push(photon(Vec3::new(0.0, at(i), at(j)), h * h, Vec3::NEG_X));
            }
        }
    }
    let map = PhotonMap::build(photons);
    for kernel in [Kernel::Box, Kernel::Cone] {
        for p in [Vec3::ZERO, Vec3::new(-0.05, 0.0, 0.0), Vec3::new(-0.15, 0.0, 0.0)] {
            let q = Lookup {
                p,
                k: 0,
                r_max: r,
                kernel,
                filter: Filter { n: Vec3::Y, flags_mask: 0, plane: 0.0, slack: 0.0 },
            };
            for set in [CodePath::Scalar, CodePath::Simd] {
                let e = map.estimate_radius_on_surface(set, &q, f, &[]);
                let what = format!("{kernel:?} at {p}, {set:?}");
                assert!(e.bias.x.abs() < 0.02 * e.radiance.x, "{what}: bias {} of {}", e.bias.x, e.radiance.x);
                // Without the bias sum: the same radiance to the bit, and no bias at all.
                let plain_sum = map.estimate_radius_with(set, &q, f, Some(&[]), false);
                assert_eq!((plain_sum.radiance, plain_sum.bias), (e.radiance, Vec3::ZERO), "{what}");
                // Uncorrected, the missing outer part of the disk reads as strong curvature.
                if p != Vec3::ZERO {
                    let plain = map.estimate_radius(set, &q, f);
                    assert!(plain.bias.x < -0.05 * e.radiance.x, "{what}: uncorrected bias {}", plain.bias.x);
                }
            }
        }
    }
}
