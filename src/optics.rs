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

/// Normal-incidence reflectance of a conductor of complex index η + ik (per channel):
/// ((η − 1)² + k²) / ((η + 1)² + k²), the exact Fresnel reflectance at cos θ = 1.
#[must_use]
pub fn conductor_f0(eta: Vec3, k: Vec3) -> Vec3 {
    let k2 = k * k;
    ((eta - 1.0) * (eta - 1.0) + k2) / ((eta + 1.0) * (eta + 1.0) + k2)
}

/// Complex indices (η, k) of named metals near the red, green and blue primaries (about 650,
/// 550 and 450 nm): measured optical constants rounded to two decimals, with the chemical
/// symbols Mitsuba uses for them. Their normal-incidence reflectances are within a few hundredths
/// of the usual RGB tables (gold ≈ (0.95, 0.78, 0.41)); a spectral renderer would differ by more
/// than that. `none` is a perfect reflector.
pub const METALS: [(&str, [f32; 3], [f32; 3]); 9] = [
    ("Ag", [0.14, 0.12, 0.14], [4.15, 3.34, 2.46]),
    ("Al", [1.47, 0.96, 0.62], [7.79, 6.69, 5.47]),
    ("Au", [0.16, 0.42, 1.47], [3.45, 2.35, 1.95]),
    ("Cr", [3.18, 3.18, 2.35], [3.33, 3.33, 3.03]),
    ("Cu", [0.27, 1.03, 1.22], [3.41, 2.59, 2.36]),
    ("Fe", [2.91, 2.95, 2.58], [3.08, 2.93, 2.78]),
    ("Ni", [2.01, 1.85, 1.61], [3.80, 3.43, 2.94]),
    ("Ti", [2.74, 2.54, 2.15], [3.81, 3.43, 2.97]),
    ("W", [3.63, 3.48, 3.35], [2.81, 2.81, 2.72]),
];

/// The normal-incidence reflectance of the metal called `name` (as [`METALS`] names them, or
/// `none` for a perfect reflector); `None` for a name not known.
#[must_use]
pub fn named_metal_f0(name: &str) -> Option<Vec3> {
    if name == "none" {
        return Some(Vec3::ONE);
    }
    METALS
        .iter()
        .find(|(n, _, _)| n.eq_ignore_ascii_case(name))
        .map(|(_, eta, k)| conductor_f0(Vec3::from_array(*eta), Vec3::from_array(*k)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metals_reflect_as_measured() {
        // Gold: red and green high, blue low; silver and aluminium above 0.85 everywhere.
        let au = named_metal_f0("Au").unwrap();
        assert!(au.x > 0.9 && au.y > 0.6 && au.z < 0.5, "{au}");
        assert!(named_metal_f0("Ag").unwrap().min_element() > 0.85);
        assert!(named_metal_f0("al").unwrap().min_element() > 0.85);
        assert_eq!(named_metal_f0("none"), Some(Vec3::ONE));
        assert_eq!(named_metal_f0("unobtainium"), None);
        // A dielectric (k = 0) of η = 1.5 reflects 4 %.
        assert!((conductor_f0(Vec3::splat(1.5), Vec3::ZERO).x - 0.04).abs() < 1e-6);
        for (_, eta, k) in METALS {
            let f0 = conductor_f0(Vec3::from_array(eta), Vec3::from_array(k));
            assert!(f0.min_element() > 0.4 && f0.max_element() < 1.0);
        }
    }
}
