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

/// The reflectance of a thin slab of relative index `eta` at incidence cos θ = `cos_i`: each face
/// reflects R = F(cos θ, η), and light bouncing between the faces adds T·R·T/(1 − R²) (T = 1 − R,
/// no absorption), so R′ = R + (1 − R)²R/(1 − R²) = 2R/(1 + R); the slab transmits 1 − R′ straight
/// through. Mitsuba's `thindielectric` takes this reflectance.
#[must_use]
pub fn thin_slab_reflectance(cos_i: f32, eta: f32) -> f32 {
    let r = fresnel_dielectric(cos_i.abs(), eta);
    2.0 * r / (1.0 + r)
}

/// The chance that a ray at cos θ = `cos` to a thin sheet's normal passes it when the sheet
/// (index `ior`, grey transmission scale `t`) is passed in traversal
/// ([`crate::material::Bsdf::thin_pass`]): its transmittance t·(1 − R′), R′ the slab's
/// reflectance ([`thin_slab_reflectance`]).
#[must_use]
pub fn thin_pass_probability(cos: f32, ior: f32, t: f32) -> f32 {
    t * (1.0 - thin_slab_reflectance(cos, ior))
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

/// A conductor's complex index of refraction η + ik, per colour channel, relative to the outside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ComplexIor {
    /// Real part η.
    pub eta: Vec3,
    /// Extinction k.
    pub k: Vec3,
}

/// The exact Fresnel reflectance of a conductor of complex index `ior` at incidence cos θ = `cos_i`
/// (unpolarised light, per channel): with sin² = 1 − cos², a² + b² = |(η + ik)² − sin²| and
/// a² = ½(a² + b² + η² − k² − sin²), R_s = (a² + b² − 2a cos + cos²) / (a² + b² + 2a cos + cos²),
/// R_p = R_s·(cos²(a² + b²) − 2a cos sin² + sin⁴) / (cos²(a² + b²) + 2a cos sin² + sin⁴),
/// F = (R_s + R_p)/2. Mitsuba's `conductor` and `roughconductor` take this Fresnel.
#[must_use]
pub fn fresnel_conductor(cos_i: f32, ior: ComplexIor) -> Vec3 {
    let c = cos_i.clamp(0.0, 1.0);
    let (c2, s2) = (c * c, 1.0 - c * c);
    let (eta2, k2) = (ior.eta * ior.eta, ior.k * ior.k);
    let t0 = eta2 - k2 - Vec3::splat(s2);
    let ab2 = (t0 * t0 + 4.0 * eta2 * k2).map(f32::sqrt);
    let a = (0.5 * (ab2 + t0)).max(Vec3::ZERO).map(f32::sqrt);
    let t1 = ab2 + Vec3::splat(c2);
    let t2 = 2.0 * c * a;
    let rs = (t1 - t2) / (t1 + t2).max(Vec3::splat(f32::MIN_POSITIVE));
    let t3 = c2 * ab2 + Vec3::splat(s2 * s2);
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / (t3 + t4).max(Vec3::splat(f32::MIN_POSITIVE));
    (0.5 * (rs + rp)).clamp(Vec3::ZERO, Vec3::ONE)
}

/// A conductor's reflectance at cos θ = `cos`: `ks` times the exact Fresnel of `ior` when the
/// complex index is known (Mitsuba's metals: `ks` its `specular_reflectance`), Schlick's
/// approximation from the normal-incidence reflectance `ks` otherwise (MTL, glTF, TOML colours).
#[must_use]
pub fn conductor_reflectance(ks: Vec3, ior: Option<ComplexIor>, cos: f32) -> Vec3 {
    match ior {
        Some(ior) => ks * fresnel_conductor(cos, ior),
        None => {
            let c = (1.0 - cos.clamp(0.0, 1.0)).powi(5);
            ks + (Vec3::ONE - ks) * c
        }
    }
}

/// Complex indices (η, k) of named metals, per linear sRGB channel, with the chemical symbols
/// Mitsuba uses for them. Ag, Al, Au, Cr, Cu and W are the values Mitsuba 3 itself derives from
/// its measured spectra in its RGB modes (read through its Python API), so that a Mitsuba file's
/// named metal renders as Mitsuba renders it; Fe, Ni and Ti (not Mitsuba names) are measured
/// constants near 650, 550 and 450 nm rounded to two decimals. `none` is a perfect reflector
/// (η = 0, k = 1: F = 1 at every angle).
pub const METALS: [(&str, [f32; 3], [f32; 3]); 9] = [
    ("Ag", [0.155276, 0.116728, 0.138388], [4.82835, 3.12222, 2.1469]),
    ("Al", [1.6575, 0.880405, 0.521244], [9.22381, 6.2695, 4.837]),
    ("Au", [0.143036, 0.375307, 1.44205], [3.983, 2.38556, 1.60336]),
    ("Cr", [4.36967, 2.91651, 1.6549], [5.20655, 4.23131, 3.7547]),
    ("Cu", [0.201005, 0.92375, 1.10222], [3.91326, 2.45305, 2.14209]),
    ("Fe", [2.91, 2.95, 2.58], [3.08, 2.93, 2.78]),
    ("Ni", [2.01, 1.85, 1.61], [3.80, 3.43, 2.94]),
    ("Ti", [2.74, 2.54, 2.15], [3.81, 3.43, 2.97]),
    ("W", [4.37082, 3.30025, 2.99841], [3.50064, 2.60487, 2.27323]),
];

/// The complex index of the metal called `name` (as [`METALS`] names them, or `none` for a
/// perfect reflector); `None` for a name not known.
#[must_use]
pub fn named_metal(name: &str) -> Option<ComplexIor> {
    if name == "none" {
        return Some(ComplexIor { eta: Vec3::ZERO, k: Vec3::ONE });
    }
    METALS
        .iter()
        .find(|(n, _, _)| n.eq_ignore_ascii_case(name))
        .map(|(_, eta, k)| ComplexIor { eta: Vec3::from_array(*eta), k: Vec3::from_array(*k) })
}

/// The normal-incidence reflectance of the metal called `name` ([`named_metal`]).
#[must_use]
pub fn named_metal_f0(name: &str) -> Option<Vec3> {
    named_metal(name).map(|c| conductor_f0(c.eta, c.k))
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
        // The exact Fresnel: at normal incidence f0, at grazing 1, a perfect reflector 1 always.
        for (_, eta, k) in METALS {
            let ior = ComplexIor { eta: Vec3::from_array(eta), k: Vec3::from_array(k) };
            let f0 = conductor_f0(ior.eta, ior.k);
            assert!((fresnel_conductor(1.0, ior) - f0).abs().max_element() < 1e-5);
            assert!((fresnel_conductor(0.0, ior) - Vec3::ONE).abs().max_element() < 1e-5);
        }
        let none = named_metal("none").unwrap();
        for c in [0.0, 0.3, 0.7, 1.0] {
            assert!((fresnel_conductor(c, none) - Vec3::ONE).abs().max_element() < 1e-6);
        }
        // k = 0: the dielectric Fresnel.
        let glass = ComplexIor { eta: Vec3::splat(1.5), k: Vec3::ZERO };
        for c in [0.2f32, 0.5, 0.9] {
            assert!((fresnel_conductor(c, glass).x - fresnel_dielectric(c, 1.5)).abs() < 1e-5, "{c}");
        }
        // A dielectric (k = 0) of η = 1.5 reflects 4 %.
        assert!((conductor_f0(Vec3::splat(1.5), Vec3::ZERO).x - 0.04).abs() < 1e-6);
        // Every metal reflects most light head-on but none all of it; gold's blue is the lowest
        // (0.33 from Mitsuba's indices, 0.41 in the usual RGB tables).
        for (name, eta, k) in METALS {
            let f0 = conductor_f0(Vec3::from_array(eta), Vec3::from_array(k));
            assert!(f0.min_element() > 0.3 && f0.max_element() < 1.0, "{name}: {f0}");
        }
    }
}
