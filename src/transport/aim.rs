//! Caustic photons aimed at what makes caustics (an importance scheme equivalent to Jensen's
//! projection maps): each light sends its caustic photons only toward the bounding spheres of
//! the scene's specular objects ([`crate::scene::targets`]), with power divided by the pdf of
//! the aimed sample, so the caustic map's estimate is unchanged in expectation — a direction
//! outside every sphere meets a diffuse surface first and could never start a caustic path.
//!
//! - From a point (area, point and spot lights): a sphere is picked with probability ∝ the solid
//!   angle Ω of its cone, then a direction uniformly in that cone; the pdf of a direction is
//!   (cones holding it)/ΣΩ. A light inside a sphere sees the whole sphere of directions.
//! - From a distant light (directional, sun, environment), for each direction: a sphere is
//!   picked ∝ r², then a point uniformly in its disk across the direction; the pdf of a point is
//!   (disks holding its line)/(π Σ r²).
//!
//! Power: area L·cos·A/pdf, point I/pdf, spot I·falloff/pdf, distant E/pdf (the sun and the
//! environment after their own direction sampling). A light whose own sampling is already
//! narrower than the targets' cones (a spot aimed at a lens, a light inside a glass ball) keeps
//! it (`Cones::cover`).

use crate::sampling::{concentric_disk, uniform_sphere, Frame};
use crate::scene::light::{spot_falloff, Emission, Light};
use crate::scene::targets::{Target, MAX_TARGETS};
use crate::scene::Scene;
use glam::Vec3;
use std::f32::consts::PI;

/// A target's cone seen from a point: its axis, 1 − cos and sin² of its half-angle (1 − cos = 2
/// for a point inside: the whole sphere) and its solid angle.
#[derive(Clone, Copy)]
struct Cone {
    axis: Vec3,
    one_minus_cos: f32,
    sin2: f32,
    solid_angle: f32,
}

impl Cone {
    /// Whether unit `d` lies in the cone (by the sine, which resolves the tiny cones of far
    /// targets that 1 − d·axis cannot).
    fn holds(&self, d: Vec3) -> bool {
        self.one_minus_cos >= 2.0 || (d.dot(self.axis) > 0.0 && d.cross(self.axis).length_squared() <= self.sin2)
    }
}

fn cone(x: Vec3, t: &Target) -> Cone {
    let d = t.centre - x;
    let dist2 = d.length_squared();
    if dist2 <= t.radius * t.radius {
        return Cone { axis: Vec3::Z, one_minus_cos: 2.0, sin2: 1.0, solid_angle: 4.0 * PI };
    }
    let sin2 = t.radius * t.radius / dist2;
    // 1 − cos = sin²/(1 + cos), exact for small cones.
    let one_minus_cos = sin2 / (1.0 + (1.0 - sin2).max(0.0).sqrt());
    Cone { axis: d / dist2.sqrt(), one_minus_cos, sin2, solid_angle: 2.0 * PI * one_minus_cos }
}

/// The targets' cones seen from one point, made once per photon (at most
/// [`MAX_TARGETS`], on the stack), and their summed solid angle (counted with overlaps): the
/// aimed pdf's normalisation.
struct Cones {
    list: [Cone; MAX_TARGETS],
    len: usize,
    total: f32,
}

impl Cones {
    fn from(x: Vec3, targets: &[Target]) -> Cones {
        let empty = Cone { axis: Vec3::Z, one_minus_cos: 0.0, sin2: 0.0, solid_angle: 0.0 };
        let mut c = Cones { list: [empty; MAX_TARGETS], len: 0, total: 0.0 };
        for t in targets.iter().take(MAX_TARGETS) {
            c.list[c.len] = cone(x, t);
            c.total += c.list[c.len].solid_angle;
            c.len += 1;
        }
        c
    }

    /// Where the cones cover what the light's own sampling covers (a hemisphere for an area
    /// light, the sphere for a point light, a spot's cone), aiming gains nothing and the light's
    /// own sampling is used: chosen by the emission point alone, so either way the estimate
    /// stays unbiased.
    fn cover(&self, own: f32) -> bool {
        self.total >= own
    }

    /// A direction toward the targets with three uniform numbers, and its pdf.
    fn aim(&self, u: [f32; 3]) -> Option<(Vec3, f32)> {
        let cones = &self.list[..self.len];
        if !(self.total > 0.0) {
            return None;
        }
        let mut pick = u[2] * self.total;
        let c = *cones.iter().find(|c| {
            pick -= c.solid_angle;
            pick < 0.0
        })?;
        let d = if c.one_minus_cos >= 2.0 {
            uniform_sphere([u[0], u[1]])
        } else {
            let omc = u[0] * c.one_minus_cos;
            let cos = 1.0 - omc;
            let sin = (omc * (2.0 - omc)).max(0.0).sqrt();
            let phi = 2.0 * PI * u[1];
            Frame::new(c.axis).to_world(Vec3::new(sin * phi.cos(), sin * phi.sin(), cos))
        };
        let holding = cones.iter().filter(|k| k.holds(d)).count();
        Some((d, holding.max(1) as f32 / self.total))
    }
}

/// An origin for light travelling along `dir` that then crosses the targets' disks, with three
/// uniform numbers; and the area pdf of the crossing point. The origin is moved back along
/// `dir` outside the scene's bounding sphere.
fn aim_along(scene: &Scene, dir: Vec3, targets: &[Target], u: [f32; 3]) -> Option<(Vec3, f32)> {
    let total: f32 = targets.iter().map(|t| t.radius * t.radius).sum();
    if !(total > 0.0) {
        return None;
    }
    let mut pick = u[2] * total;
    let t = targets.iter().find(|t| {
        pick -= t.radius * t.radius;
        pick < 0.0
    })?;
    let f = Frame::new(dir);
    let (dx, dy) = concentric_disk([u[0], u[1]]);
    let p = t.centre + (f.s * dx + f.t * dy) * t.radius;
    let holding = targets
        .iter()
        .filter(|k| {
            let v = k.centre - p;
            (v - dir * v.dot(dir)).length_squared() <= k.radius * k.radius
        })
        .count();
    let (centre, radius) = (scene.centre(), scene.radius());
    let origin = p - dir * ((p - centre).dot(dir) + 2.0 * radius);
    Some((origin, holding.max(1) as f32 / (PI * total)))
}

/// A caustic photon leaving `light` aimed at the scene's targets, with five uniform numbers;
/// power divided by the aimed sample's pdfs (not yet by the light's pick). `None` when the
/// sample carries no light (a direction behind an area light, outside a spot's cone).
#[must_use]
pub fn aimed_emission(scene: &Scene, light: &Light, u: [f32; 5]) -> Option<Emission> {
    let targets = &scene.caustic_targets;
    let em = match *light {
        Light::Area { radiance, tri } => {
            let t = scene.triangle(tri);
            let (b1, b2) = crate::sampling::uniform_triangle([u[0], u[1]]);
            let x = t.p[0] * (1.0 - b1 - b2) + t.p[1] * b1 + t.p[2] * b2;
            let cones = Cones::from(x, targets);
            if cones.cover(2.0 * PI) {
                // The targets fill the emitter's hemisphere or more: cosine sampling is better.
                return Some(scene.sample_emission(light, [u[0], u[1], u[2], u[3]]));
            }
            let (d, pdf) = cones.aim([u[2], u[3], u[4]])?;
            let cos = d.dot(t.n);
            if !(cos > 0.0) {
                return None;
            }
            let radiance =
                if scene.textured_emitter(tri) { scene.emitted_at(tri, [1.0 - b1 - b2, b1, b2]) } else { radiance };
            Emission { origin: x, direction: d, power: radiance * (cos * t.area / pdf), normal: Some(t.n) }
        }
        Light::Point { position, intensity } => {
            let cones = Cones::from(position, targets);
            if cones.cover(4.0 * PI) {
                return Some(scene.sample_emission(light, [u[0], u[1], u[2], u[3]]));
            }
            let (d, pdf) = cones.aim([u[2], u[3], u[4]])?;
            Emission { origin: position, direction: d, power: intensity / pdf, normal: None }
        }
        Light::Spot { position, direction, intensity, cos_inner, cos_outer } => {
            let cones = Cones::from(position, targets);
            if cones.cover(2.0 * PI * (1.0 - cos_outer)) {
                // The spot's own cone is the narrower: sample it as unaimed photons do.
                return Some(scene.sample_emission(light, [u[0], u[1], u[2], u[3]]));
            }
            let (d, pdf) = cones.aim([u[2], u[3], u[4]])?;
            let fall = spot_falloff(d.dot(direction), cos_inner, cos_outer);
            if !(fall > 0.0) {
                return None;
            }
            Emission { origin: position, direction: d, power: intensity * (fall / pdf), normal: None }
        }
        Light::Directional { direction, irradiance } => {
            let (origin, pdf) = aim_along(scene, direction, targets, [u[0], u[1], u[4]])?;
            Emission { origin, direction, power: irradiance / pdf, normal: None }
        }
        Light::Sun { direction, irradiance, .. } => {
            // The sun's own direction sampling (pdf L·cos θ/E⊥ about its axis), then aimed
            // across that direction: power L/(pdf·q) = E⊥/(cos θ·q).
            let d = light.sample_emission(None, (scene.centre(), scene.radius()), [0.5, 0.5, u[2], u[3]]).direction;
            let (origin, pdf) = aim_along(scene, d, targets, [u[0], u[1], u[4]])?;
            Emission { origin, direction: d, power: irradiance / (pdf * d.dot(direction)), normal: None }
        }
        Light::Environment => {
            let env = scene.environment.as_ref()?;
            let (wi, pdf_dir, radiance) = env.sample([u[2], u[3]])?;
            let (origin, pdf) = aim_along(scene, -wi, targets, [u[0], u[1], u[4]])?;
            Emission { origin, direction: -wi, power: radiance / (pdf_dir * pdf), normal: None }
        }
    };
    Some(em)
}
