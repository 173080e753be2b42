//! Smooth-interface optics both the smooth and the rough materials use: mirror reflection,
//! Snell's refraction and the unpolarised Fresnel reflectance of a dielectric boundary.
//! Directions point away from the surface.

use glam::Vec3;

/// Unpolarised Fresnel reflectance of a smooth dielectric boundary, `cos_i` = |cos| of the incident
/// angle, `eta` = η_transmitted / η_incident. Exactly 1 past the critical angle; clamped to [0, 1].
#[must_use]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (0.5 * (r_parl * r_parl + r_perp * r_perp)).clamp(0.0, 1.0)
}

/// Mirror reflection of `wo` about `n`.
#[inline]
#[must_use]
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    2.0 * wo.dot(n) * n - wo
}

/// Refraction of `wo` through a boundary with normal `n` on the side of `wo`, `eta` = η_t / η_i.
/// `None` on total internal reflection.
#[must_use]
pub fn refract(wo: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = wo.dot(n);
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-wo / eta + (cos_i / eta - cos_t) * n).normalize())
}
