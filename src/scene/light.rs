//! Light sources: emissive triangles (area lights from MTL `Ke`) and the point, spot and
//! directional lights of the scene file; their power, emission sampling (photons) and
//! illumination sampling (direct light).

use super::light_tree::near;
use crate::geometry::offset::barycentric_error;
use crate::sampling::{
    concentric_disk, uniform_cone, uniform_sphere, uniform_triangle, Frame, SphericalTriangle, SPHERICAL_SAMPLING,
};
use glam::Vec3;
use std::f32::consts::PI;

/// A light source.
#[derive(Clone, Copy, Debug, PartialEq)]
// Each variant's doc names and explains its fields.
#[allow(missing_docs)]
pub enum Light {
    /// Emissive triangle `tri` (scene BVH order) with radiance `radiance` from its front face.
    Area { tri: u32, radiance: Vec3 },
    /// Isotropic point light at `position` with radiant intensity `intensity` (W/sr).
    Point { position: Vec3, intensity: Vec3 },
    /// Spot light at `position` aimed along unit `direction`: intensity `intensity` inside
    /// `cos_inner`, falling linearly in cos θ to zero at `cos_outer`.
    Spot { position: Vec3, direction: Vec3, intensity: Vec3, cos_inner: f32, cos_outer: f32 },
    /// Distant light travelling along `direction` with irradiance `irradiance` on a perpendicular plane.
    Directional { direction: Vec3, irradiance: Vec3 },
    /// A sun: a distant disk of uniform radiance seen under angular radius θ, its centre's light
    /// travelling along `direction`, putting `irradiance` on a perpendicular plane.
    /// `one_minus_cos` = 1 − cos θ (kept apart for precision: 4.4e-6 for the real sun's 0.27°).
    Sun { direction: Vec3, irradiance: Vec3, one_minus_cos: f32 },
    /// The scene's environment ([`super::environment::Environment`]): sampled by the scene, which
    /// holds its map.
    Environment,
}

/// A photon leaving a light: origin, direction and power before division by the photon count.
#[derive(Clone, Copy, Debug)]
pub struct Emission {
    /// Where it starts.
    pub origin: Vec3,
    /// Unit direction.
    pub direction: Vec3,
    /// Power carried, already divided by the pdfs of the sample (sums to Φ in expectation).
    pub power: Vec3,
    /// Surface normal at the origin (area lights), used to offset the first ray.
    pub normal: Option<Vec3>,
}

/// A sample of incident light at a shading point (direct lighting).
#[derive(Clone, Copy, Debug)]
pub struct Incident {
    /// Unit direction from the shading point toward the light.
    pub wi: Vec3,
    /// Radiance or irradiance-like contribution divided by the sample pdf (f·cos not applied).
    pub value: Vec3,
    /// The sample's density per steradian (an emissive triangle's: [`area_light_pdf`]; the
    /// environment's mixture); 0 for delta lights and the sun (never weighed by MIS).
    pub pdf: f32,
    /// Distance to the light sample (infinite for directional lights).
    pub distance: f32,
    /// The light-side point and its geometric normal, for shadow rays (None for distant lights).
    pub point: Option<(Vec3, Vec3)>,
    /// The rounding error bound of that point, per axis (zero for point and spot lights, whose
    /// position is given): a shadow ray stops short of it by as much, or the emitter's own
    /// triangle, which a sample computed a rounding behind it lies beyond, blocks the ray (the
    /// Cornell box 30 000 units out lost 3 % of its direct light so).
    pub point_error: Vec3,
}

/// Triangle geometry an area light needs.
#[derive(Clone, Copy, Debug)]
pub struct TriangleGeom {
    /// Vertices.
    pub p: [Vec3; 3],
    /// Unit geometric normal (front face).
    pub n: Vec3,
    /// Area.
    pub area: f32,
}

/// Falloff of a spot light at `cos_theta`.
#[must_use]
pub fn spot_falloff(cos_theta: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    if cos_theta >= cos_inner {
        1.0
    } else if cos_theta <= cos_outer {
        0.0
    } else {
        (cos_theta - cos_outer) / (cos_inner - cos_outer)
    }
}

/// How an emissive triangle is sampled from `p`: by the solid angle Ω it subtends there
/// (`Some`: the triangle as seen from `p`, and Ω) where it is near ([`near`]: closer than 5
/// bounding radii, where area sampling's 1/d² would vary more than 2.25× over it) and Ω lies
/// within [`SPHERICAL_SAMPLING`]; `None` by area (uniform in area is nearly uniform in solid
/// angle for a far triangle, and much cheaper). Light sampling and MIS's density
/// ([`area_light_pdf`]) decide alike, so their weights sum to one.
#[must_use]
pub fn area_light_sampling(t: &TriangleGeom, p: Vec3) -> Option<(SphericalTriangle, f64)> {
    if !near(&t.p, p) {
        return None;
    }
    let seen = SphericalTriangle::new(t.p, p);
    let omega = seen.solid_angle();
    SPHERICAL_SAMPLING.contains(&omega).then_some((seen, omega))
}

/// The density per steradian with which light sampling from `p` picks the direction `wi`
/// toward a point of triangle `t` at `distance`: 1/Ω where it samples the solid angle,
/// d²/(A·cos θ_light) where it samples the area ([`area_light_sampling`]).
#[must_use]
pub fn area_light_pdf(t: &TriangleGeom, p: Vec3, wi: Vec3, distance: f32) -> f32 {
    match area_light_sampling(t, p) {
        Some((_, omega)) => (1.0 / omega) as f32,
        None => distance * distance / (t.area * wi.dot(t.n).abs()),
    }
}

/// Barycentrics of the point where the ray from `p` along `w` crosses triangle `t`'s plane,
/// moved onto the triangle where rounding put it just outside (f64: a far or thin triangle's
/// edge products cancel in f32). `None` for a ray along the plane.
fn crossing(t: &TriangleGeom, p: Vec3, w: Vec3) -> Option<[f32; 3]> {
    let [a, b, c] = t.p.map(|q| q.as_dvec3() - p.as_dvec3());
    let w = w.as_dvec3();
    let (e1, e2) = (b - a, c - a);
    let pv = w.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let b1 = ((-a).dot(pv) / det).max(0.0);
    let b2 = (w.dot((-a).cross(e1)) / det).max(0.0);
    let s = (b1 + b2).max(1.0);
    let (b1, b2) = (b1 / s, b2 / s);
    Some([(1.0 - b1 - b2) as f32, b1 as f32, b2 as f32])
}

impl Light {
    /// True for lights of one direction at each point (point, spot, directional): sampled once
    /// per shading point. Area lights, the sun and the environment are sampled `light_samples`
    /// times.
    #[must_use]
    pub fn is_delta(&self) -> bool {
        !matches!(self, Light::Area { .. } | Light::Sun { .. } | Light::Environment)
    }

    /// True for lights at infinity (directional, sun, environment): they light the whole scene
    /// and photons from them can leave it.
    #[must_use]
    pub fn is_distant(&self) -> bool {
        matches!(self, Light::Directional { .. } | Light::Sun { .. } | Light::Environment)
    }

    /// The sun's radiance: E / (π sin² θ), so that its disk puts `irradiance` on a perpendicular
    /// plane (∫ L cos dω over the disk = L·π sin² θ).
    #[must_use]
    pub fn sun_radiance(irradiance: Vec3, one_minus_cos: f32) -> Vec3 {
        irradiance / (PI * one_minus_cos * (2.0 - one_minus_cos))
    }

    /// Emitted power (W) per channel. `scene_radius` bounds the scene (directional lights).
    #[must_use]
    pub fn power(&self, tri: Option<&TriangleGeom>, scene_radius: f32) -> Vec3 {
        match *self {
            Light::Area { radiance, .. } => radiance * PI * tri.map_or(0.0, |t| t.area),
            Light::Point { intensity, .. } => intensity * 4.0 * PI,
            Light::Spot { intensity, cos_inner, cos_outer, .. } => {
                intensity * 2.0 * PI * ((1.0 - cos_inner) + 0.5 * (cos_inner - cos_outer))
            }
            Light::Directional { irradiance, .. } | Light::Sun { irradiance, .. } => {
                irradiance * PI * scene_radius * scene_radius
            }
            // Computed by the scene, which holds the map (`Scene::light_power_of`).
            Light::Environment => Vec3::ZERO,
        }
    }

    /// Samples a photon leaving the light with four uniform numbers; `scene` = (centre, radius).
    #[must_use]
    pub fn sample_emission(&self, tri: Option<&TriangleGeom>, scene: (Vec3, f32), u: [f32; 4]) -> Emission {
        match *self {
            Light::Area { radiance, .. } => {
                let t = tri.expect("area light without its triangle");
                let (b1, b2) = uniform_triangle([u[0], u[1]]);
                let origin = t.p[0] * (1.0 - b1 - b2) + t.p[1] * b1 + t.p[2] * b2;
                let local = crate::sampling::cosine_hemisphere([u[2], u[3]]);
                // pdf = (1/A)·(cos/π); Le·cos/pdf = π·A·Le.
                Emission {
                    origin,
                    direction: Frame::new(t.n).to_world(local),
                    power: radiance * PI * t.area,
                    normal: Some(t.n),
                }
            }
            Light::Point { position, intensity } => Emission {
                origin: position,
                direction: uniform_sphere([u[0], u[1]]),
                power: intensity * 4.0 * PI,
                normal: None,
            },
            Light::Spot { position, direction, intensity, cos_inner, cos_outer } => {
                let local = uniform_cone([u[0], u[1]], cos_outer);
                let pdf = 1.0 / (2.0 * PI * (1.0 - cos_outer));
                Emission {
                    origin: position,
                    direction: Frame::new(direction).to_world(local),
                    power: intensity * spot_falloff(local.z, cos_inner, cos_outer) / pdf,
                    normal: None,
                }
            }
            Light::Directional { direction, irradiance } => {
                let (centre, radius) = scene;
                let (dx, dy) = concentric_disk([u[0], u[1]]);
                let f = Frame::new(direction);
                let origin = centre + (f.s * dx + f.t * dy) * radius - direction * (2.0 * radius);
                Emission { origin, direction, power: irradiance * PI * radius * radius, normal: None }
            }
            Light::Sun { direction, irradiance, one_minus_cos } => {
                // Directions ∝ L·cos about the axis: uniform on the disk of radius sin θ.
                let (centre, radius) = scene;
                let sin_max = (one_minus_cos * (2.0 - one_minus_cos)).sqrt();
                let (x, y) = concentric_disk([u[2], u[3]]);
                let (x, y) = (x * sin_max, y * sin_max);
                let f = Frame::new(direction);
                let dir = f.to_world(Vec3::new(x, y, (1.0 - x * x - y * y).max(0.0).sqrt()));
                // The disk across each direction (not the axis): every ray through the scene's
                // bounding sphere crosses it. Power L/(pdf·q) with pdf = L·cos θ/E⊥ about the axis.
                let g = Frame::new(dir);
                let (dx, dy) = concentric_disk([u[0], u[1]]);
                let origin = centre + (g.s * dx + g.t * dy) * radius - dir * (2.0 * radius);
                let cos = dir.dot(direction);
                Emission { origin, direction: dir, power: irradiance * (PI * radius * radius / cos), normal: None }
            }
            // Sampled by the scene (`Scene::sample_emission`); never reached.
            Light::Environment => Emission { origin: Vec3::ZERO, direction: Vec3::Y, power: Vec3::ZERO, normal: None },
        }
    }

    /// Samples light arriving at `p` with two uniform numbers. `None` when no light arrives
    /// (back face of an area light, outside a spot cone, degenerate geometry).
    #[must_use]
    pub fn sample_incident(&self, tri: Option<&TriangleGeom>, p: Vec3, u: [f32; 2]) -> Option<Incident> {
        match *self {
            Light::Area { radiance, .. } => {
                let t = tri?;
                let spherical = area_light_sampling(t, p);
                let b = match &spherical {
                    // Uniform in the solid angle it subtends: the point where the sampled
                    // direction crosses the triangle.
                    Some((seen, _)) => crossing(t, p, seen.sample(u)?)?,
                    None => {
                        let (b1, b2) = uniform_triangle(u);
                        [1.0 - b1 - b2, b1, b2]
                    }
                };
                let q = t.p[0] * b[0] + t.p[1] * b[1] + t.p[2] * b[2];
                let d = q - p;
                let dist2 = d.length_squared();
                let dist = dist2.sqrt();
                let wi = d / dist;
                let cos_l = -wi.dot(t.n);
                if !(cos_l > 0.0) || !(dist2 > 0.0) || !wi.is_finite() {
                    return None;
                }
                // Area measure → solid angle: d²/(A·cos θ_light).
                let pdf = spherical.map_or(dist2 / (t.area * cos_l), |(_, o)| (1.0 / o) as f32);
                (pdf > 0.0 && pdf.is_finite()).then(|| Incident {
                    wi,
                    value: radiance / pdf,
                    pdf,
                    distance: dist,
                    point: Some((q, t.n)),
                    point_error: barycentric_error(b, t.p[0], t.p[1], t.p[2]),
                })
            }
            Light::Point { position, intensity } => {
                let d = position - p;
                let dist2 = d.length_squared();
                let dist = dist2.sqrt();
                (dist2 > 0.0).then(|| Incident {
                    wi: d / dist,
                    value: intensity / dist2,
                    pdf: 0.0,
                    distance: dist,
                    point: Some((position, Vec3::ZERO)),
                    point_error: Vec3::ZERO,
                })
            }
            Light::Spot { position, direction, intensity, cos_inner, cos_outer } => {
                let d = position - p;
                let dist2 = d.length_squared();
                let dist = dist2.sqrt();
                if !(dist2 > 0.0) {
                    return None;
                }
                let wi = d / dist;
                let fall = spot_falloff((-wi).dot(direction), cos_inner, cos_outer);
                (fall > 0.0).then(|| Incident {
                    wi,
                    value: intensity * fall / dist2,
                    pdf: 0.0,
                    distance: dist,
                    point: Some((position, Vec3::ZERO)),
                    point_error: Vec3::ZERO,
                })
            }
            Light::Directional { direction, irradiance } => Some(Incident {
                wi: -direction,
                value: irradiance,
                pdf: 0.0,
                distance: f32::INFINITY,
                point: None,
                point_error: Vec3::ZERO,
            }),
            Light::Sun { direction, irradiance, one_minus_cos } => {
                // Uniform in the cone: pdf 1/(2π(1 − cos θ)).
                let cos = 1.0 - u[0] * one_minus_cos;
                let sin = (u[0] * one_minus_cos * (2.0 - u[0] * one_minus_cos)).max(0.0).sqrt();
                let phi = 2.0 * PI * u[1];
                let wi = Frame::new(-direction).to_world(Vec3::new(sin * phi.cos(), sin * phi.sin(), cos));
                let value = Self::sun_radiance(irradiance, one_minus_cos) * (2.0 * PI * one_minus_cos);
                Some(Incident { wi, value, pdf: 0.0, distance: f32::INFINITY, point: None, point_error: Vec3::ZERO })
            }
            // Sampled by the scene (`Scene::sample_incident`).
            Light::Environment => None,
        }
    }

    /// Radiance this light sends along a ray that leaves the scene in direction `d` (the sun
    /// when `d` points into its disk; the environment is the scene's).
    #[must_use]
    pub fn radiance_at_infinity(&self, d: Vec3) -> Vec3 {
        match *self {
            // Inside the disk: toward the sun, and sin of the angle to its axis within sin θ (the
            // cross product resolves angles a dot product near −1 cannot).
            Light::Sun { direction, irradiance, one_minus_cos }
                if d.dot(direction) < 0.0
                    && d.cross(direction).length_squared() <= one_minus_cos * (2.0 - one_minus_cos) =>
            {
                Self::sun_radiance(irradiance, one_minus_cos)
            }
            _ => Vec3::ZERO,
        }
    }
}

/// Lights the command line can give a scene that brings none of its own (`--light`), such as a
/// bare OBJ from a model library. Both put an irradiance of π on a surface square to them, so
/// that a white Lambertian surface facing them has radiance equal to its albedo.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum LightPreset {
    /// A point light at the camera: everything seen is lit, as with a camera's flash.
    Headlight,
    /// A directional light from above the camera, behind and to its left: shading and shadows
    /// that show the shape.
    Sun,
}

impl LightPreset {
    /// The light for a view from `eye` toward `target` with `up`.
    #[must_use]
    pub fn light(self, eye: Vec3, target: Vec3, up: Vec3) -> Light {
        let forward = (target - eye).normalize_or(Vec3::NEG_Z);
        let right = forward.cross(up).normalize_or(Vec3::X);
        let up = right.cross(forward);
        match self {
            LightPreset::Headlight => {
                let d2 = (target - eye).length_squared().max(f32::MIN_POSITIVE);
                Light::Point { position: eye, intensity: Vec3::splat(PI * d2) }
            }
            LightPreset::Sun => Light::Directional {
                direction: (forward - up * 1.5 + right * 0.5).normalize(),
                irradiance: Vec3::splat(PI),
            },
        }
    }
}
