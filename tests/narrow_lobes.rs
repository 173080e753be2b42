//! Narrow lobes where gather and glossy rays land (issue 56, item 3; `transport::lobe`): a
//! near-mirror coat (GGX α 0.01 over a black base, η 1.5) under a large emitting ceiling, seen
//! at 45°. Its reflected radiance is Le·R, R the coat's directional albedo, measured here as
//! the mean weight of 65 536 samples of the lobe (every reflected direction meets the ceiling).
//!
//! - A gather ray's landing (nothing sampled the lights there) reads the base and sends the
//!   lobe's ray, which counts the emission it finds whole.
//! - A glossy ray's landing samples the lights and sends the lobe's ray; the two are weighed by
//!   MIS, so their sum is Le·R in expectation — under the ceiling, and under a constant sky of
//!   the same radiance, whose light samples are weighed against the lobe's ray as emitters'
//!   are (light sampling alone reached 700·Le·R there), and under a sun in its mirror
//!   direction, whose reference is the lobe's own samples' mean.
//!
//! Tolerances: each mean within 4 standard errors of its 4 096 estimates plus 10⁻³ relative (the
//! f32 sums and R's own sampling error, ~10⁻⁴); and every single estimate at most 3·Le·R. Light
//! sampling alone, as the landings had it before, has the same mean, but a light sample in the
//! coat's peak (f ≈ 3 000 per steradian) is worth hundreds of times Le·R (675 times among these
//! 4 096); under MIS a light sample is worth at most half the lobe ray's weight, and the lobe
//! ray's weight is the Fresnel factor, within a few per cent of R.
//! The engines agree per pixel with such a floor in the gallery room.

mod common;

use glam::Vec3;

use photonwave::material::{Bsdf, Material};
use photonwave::microfacet::Alpha;
use photonwave::rng::{Domain, Sampler};
use photonwave::scene::light::Light;
use photonwave::scene::{Environment, MeshInput, Scene, SurfacePoint};
use photonwave::settings::Settings;
use photonwave::transport::direct::weighted_direct_light;
use photonwave::transport::lobe::{gather_landing, lobe_ray};
use photonwave::transport::mis::Strategies;
use photonwave::transport::specular::ChainEnd;
use photonwave::transport::{streams, Context, PhotonMaps};

const LE: f32 = 1.0;

/// A 20 × 20 near-mirror floor at y = 0 and a 40 × 40 emitting ceiling at y = 1 facing down.
fn coat_under_ceiling() -> Scene {
    let quad = |h: f32, s: f32, down: bool, material: u32| {
        let positions = vec![Vec3::new(-s, h, -s), Vec3::new(s, h, -s), Vec3::new(s, h, s), Vec3::new(-s, h, s)];
        let triangles = if down { vec![[0, 1, 2], [0, 2, 3]] } else { vec![[0, 2, 1], [0, 3, 2]] };
        MeshInput {
            source: format!("quad{material}"),
            positions,
            normals: vec![],
            triangles,
            material: vec![material; 2],
            ..Default::default()
        }
    };
    let coat = Material::new("coat", Bsdf::rough_plastic(Vec3::ZERO, 1.5, Alpha::ggx(0.01)), Vec3::ZERO);
    let lamp = Material::new("lamp", Bsdf::Lambert { kd: Vec3::ZERO }, Vec3::splat(LE));
    Scene::build(vec![quad(0.0, 10.0, false, 0), quad(1.0, 20.0, true, 1)], vec![coat, lamp], vec![], vec![]).unwrap()
}

/// The near-mirror floor alone (20 × 20 at y = 0) and its coat, for other lights.
fn coat_alone() -> (MeshInput, Material) {
    let mesh = MeshInput {
        source: "floor".into(),
        positions: vec![
            Vec3::new(-10.0, 0.0, -10.0),
            Vec3::new(10.0, 0.0, -10.0),
            Vec3::new(10.0, 0.0, 10.0),
            Vec3::new(-10.0, 0.0, 10.0),
        ],
        triangles: vec![[0, 2, 1], [0, 3, 2]],
        material: vec![0, 0],
        ..Default::default()
    };
    (mesh, Material::new("coat", Bsdf::rough_plastic(Vec3::ZERO, 1.5, Alpha::ggx(0.01)), Vec3::ZERO))
}

/// The landing point at the floor's centre and the direction back along the arriving ray.
fn landing(scene: &Scene) -> (SurfacePoint, Vec3) {
    let hit = scene.intersect(Vec3::new(1.0, 0.5, 0.0), Vec3::new(-1.0, -1.0, 0.0).normalize(), f32::INFINITY);
    let hit = hit.expect("the ray meets the floor");
    (scene.surface(&hit), Vec3::new(1.0, 1.0, 0.0).normalize())
}

/// The coat's directional albedo toward `wo`: the mean weight of its lobe's samples.
fn albedo(scene: &Scene, sp: &SurfacePoint, wo: Vec3) -> f64 {
    let bsdf = scene.bsdf(sp);
    let n = 65_536;
    let sum: f64 = (0..n)
        .filter_map(|i| {
            let s = Sampler::new(9, Domain::Camera, i);
            bsdf.sample_glossy(&sp.frame, wo, [s.get(0, 0), s.get(0, 1), s.get(0, 2)])
        })
        .map(|b| f64::from(b.weight.x))
        .sum();
    sum / n as f64
}

/// Asserts the estimates' mean is Le·R and that none exceeds 3·Le·R.
fn assert_bounded_around(what: &str, values: &[f32], want: f64) {
    let (mean, se) = common::mean_and_se(values);
    assert!((mean - want).abs() < 4.0 * se + 1e-3 * want, "{what}: mean {mean} against Le·R {want} (se {se})");
    let max = values.iter().copied().fold(0.0f32, f32::max);
    assert!(f64::from(max) <= 3.0 * want, "{what}: an estimate of {max} against Le·R {want}");
}

/// What a glossy ray's landing at `sp` (seen from `wo`) returns in 4 096 estimates of seed
/// `seed`: its MIS-weighted light samples plus its lobe's ray.
fn glossy_landing(scene: &Scene, sp: &SurfacePoint, wo: Vec3, seed: u64) -> Vec<f32> {
    let bsdf = scene.bsdf(sp);
    let maps = PhotonMaps::default();
    let job = common::job(scene, &Settings::default());
    let ctx = Context::new(scene, &maps, &job);
    let lit = Strategies::at_landing(&ctx, &bsdf);
    assert_eq!(lit, Strategies::Split { gather: 0, glossy: true });
    (0..4096)
        .map(|i| {
            let s = Sampler::new(seed, Domain::Camera, i);
            let (mut rays, mut scratch) = (Default::default(), Default::default());
            let light = weighted_direct_light(&ctx, sp, &bsdf, wo, &s.fork(streams::GLOSSY_HIT_LIGHT), &lit, &mut rays);
            let lobe =
                lobe_ray(&ctx, sp, &bsdf, wo, &s.fork(streams::LANDING_LOBE), Some(&lit), &mut rays, &mut scratch);
            light.x + lobe.radiance.x
        })
        .collect()
}

#[test]
fn a_gather_rays_landing_on_a_near_mirror_reads_its_lobe_by_a_ray() {
    let scene = coat_under_ceiling();
    let (sp, wo) = landing(&scene);
    assert!(scene.bsdf(&sp).narrow_lobe());
    let want = f64::from(LE) * albedo(&scene, &sp, wo);
    assert!((0.04..0.07).contains(&want), "Fresnel at 45° for η 1.5 is about 0.05: {want}");
    let maps = PhotonMaps::default();
    let job = common::job(&scene, &Settings::default());
    let ctx = Context::new(&scene, &maps, &job);
    let hit = scene.intersect(sp.p + wo, -wo, f32::INFINITY).unwrap();
    let end = ChainEnd { point: sp, dir: -wo, beta: Vec3::ONE, hit, bounces: 0 };
    let values: Vec<f32> = (0..4096)
        .map(|i| {
            let s = Sampler::new(5, Domain::Camera, i);
            gather_landing(&ctx, &end, &s, &mut Default::default(), &mut Default::default()).radiance.x
        })
        .collect();
    assert_bounded_around("gather landing", &values, want);
}

#[test]
fn a_glossy_rays_landing_weighs_its_light_samples_against_the_lobes_ray() {
    let scene = coat_under_ceiling();
    let (sp, wo) = landing(&scene);
    let want = f64::from(LE) * albedo(&scene, &sp, wo);
    assert_bounded_around("glossy landing", &glossy_landing(&scene, &sp, wo, 6), want);
}

#[test]
fn a_glossy_rays_landing_under_the_sky_weighs_its_sky_samples_against_the_lobes_ray() {
    // The coat alone under a constant sky of radiance 1: Le·R as under the ceiling, where the
    // lobe's ray now leaves the scene and its light samples pick the environment.
    let floor = coat_under_ceiling();
    let (sp, wo) = landing(&floor);
    let want = f64::from(LE) * albedo(&floor, &sp, wo);
    let (mesh, coat) = coat_alone();
    let sky = Some(Environment::constant(Vec3::splat(LE)));
    let scene = Scene::build_lit(vec![mesh], vec![coat], vec![], sky, vec![]).unwrap();
    let (sp, wo) = landing(&scene);
    assert_bounded_around("glossy landing under the sky", &glossy_landing(&scene, &sp, wo, 7), want);
}

#[test]
fn a_glossy_rays_landing_under_a_sun_weighs_its_sun_samples_against_the_lobes_ray() {
    // The coat alone under a sun of angular radius 5° in its mirror direction, E⊥ = 1: the lobe
    // (about 1° wide) sees the disk's radiance, so the reference is the lobe's own estimate,
    // its samples' weight times the sun's radiance where they point into the disk (65 536).
    let (mesh, coat) = coat_alone();
    let half = 5f32.to_radians();
    let sun = Light::Sun {
        direction: Vec3::new(1.0, -1.0, 0.0).normalize(),
        irradiance: Vec3::ONE,
        one_minus_cos: 1.0 - half.cos(),
    };
    let scene = Scene::build(vec![mesh], vec![coat], vec![sun], vec![]).unwrap();
    let (sp, wo) = landing(&scene);
    let bsdf = scene.bsdf(&sp);
    let n = 65_536;
    let want = (0..n)
        .filter_map(|i| {
            let s = Sampler::new(9, Domain::Camera, i);
            bsdf.sample_glossy(&sp.frame, wo, [s.get(0, 0), s.get(0, 1), s.get(0, 2)])
        })
        .map(|b| f64::from(b.weight.x * sun.radiance_at_infinity(b.wi).x))
        .sum::<f64>()
        / n as f64;
    assert!(want > 0.0);
    assert_bounded_around("glossy landing under a sun", &glossy_landing(&scene, &sp, wo, 8), want);
}

#[test]
fn engines_agree_with_a_near_mirror_floor_at_any_thread_count() {
    let dir = common::scratch_dir("narrow_lobe_floor");
    // A near-mirror tile across the floor, under the gallery's rough-plastic and plastic shapes.
    let extra = "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"0.25\"/>\
        <rotate x=\"1\" angle=\"-90\"/><translate y=\"0.002\"/></transform>\
        <bsdf type=\"roughplastic\"><rgb name=\"diffuse_reflectance\" value=\"0.3, 0.25, 0.2\"/>\
        <float name=\"alpha\" value=\"0.01\"/></bsdf></shape>\n\
        <shape type=\"sphere\"><point name=\"center\" x=\"-0.15\" y=\"0.07\" z=\"0.12\"/>\
        <float name=\"radius\" value=\"0.07\"/><bsdf type=\"plastic\"/></shape>";
    let film = common::assert_engines_agree(common::gallery_with(&dir, extra));
    assert!(film.pixels.iter().all(|t| t.beauty().is_finite()), "finite everywhere");
}

#[test]
fn engines_agree_on_near_mirrors_under_the_sky_beside_glass_at_any_thread_count() {
    // Glossy and gather rays from the rough-plastic ball land on the near-mirror floor; the
    // floor's and the smooth plastic ball's lobe rays pass the glass ball, reach the lamp and
    // leave the scene for the sky.
    let dir = common::scratch_dir("narrow_lobe_sky");
    let xml = r#"<scene version="3.0.0">
<sensor type="perspective"><float name="fov" value="45"/>
<transform name="to_world"><lookat origin="0, 1.2, 2.5" target="0, 0.2, 0" up="0, 1, 0"/></transform></sensor>
<emitter type="constant"><rgb name="radiance" value="1.0, 0.8, 0.6"/></emitter>
<shape type="rectangle"><transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform>
<bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.3, 0.25, 0.2"/><float name="alpha" value="0.01"/></bsdf></shape>
<shape type="sphere"><point name="center" x="-0.5" y="0.3" z="0"/><float name="radius" value="0.3"/><bsdf type="dielectric"/></shape>
<shape type="sphere"><point name="center" x="0.5" y="0.3" z="0"/><float name="radius" value="0.3"/><bsdf type="plastic"/></shape>
<shape type="sphere"><point name="center" x="0" y="0.3" z="-0.6"/><float name="radius" value="0.3"/>
<bsdf type="roughplastic"><float name="alpha" value="0.3"/></bsdf></shape>
<shape type="rectangle"><transform name="to_world"><scale value="0.2"/><rotate x="1" angle="90"/><translate y="1.5"/></transform>
<bsdf type="diffuse"/><emitter type="area"><rgb name="radiance" value="20, 20, 20"/></emitter></shape>
</scene>"#;
    let path = dir.join("sky.xml");
    std::fs::write(&path, xml).unwrap();
    let film = common::assert_engines_agree(photonwave::formats::load_scene(&path).unwrap());
    assert!(film.pixels.iter().all(|t| t.beauty().is_finite()), "finite everywhere");
}
