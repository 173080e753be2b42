//! Light sources: emissive triangles (area lights from MTL `Ke`) and the point, spot and
//! directional lights of the scene file; their power, emission sampling (photons) and
//! illumination sampling (direct light).

use crate::geometry::offset::barycentric_error;
use crate::sampling::{concentric_disk, uniform_cone, uniform_sphere, uniform_triangle, Frame};
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
                let (b1, b2) = uniform_triangle(u);
                let b = [1.0 - b1 - b2, b1, b2];
                let q = t.p[0] * b[0] + t.p[1] * b[1] + t.p[2] * b[2];
                let d = q - p;
                let dist2 = d.length_squared();
                let dist = dist2.sqrt();
                let wi = d / dist;
                let cos_l = -wi.dot(t.n);
                if !(cos_l > 0.0) || !(dist2 > 0.0) || !wi.is_finite() {
                    return None;
                }
                // Area measure → solid angle: Le·cos_l·A/d².
                Some(Incident {
                    wi,
                    value: radiance * (cos_l * t.area / dist2),
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
                    distance: dist,
                    point: Some((position, Vec3::ZERO)),
                    point_error: Vec3::ZERO,
                })
            }
            Light::Directional { direction, irradiance } => Some(Incident {
                wi: -direction,
                value: irradiance,
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
                Some(Incident { wi, value, distance: f32::INFINITY, point: None, point_error: Vec3::ZERO })
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
