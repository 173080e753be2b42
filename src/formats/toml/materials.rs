//! The TOML scene file's `[materials.NAME]` tables: each becomes a [`Material`] replacing the
//! MTL material of that name, or one a `[[mesh]]` names with `material = "NAME"`.
//!
//! A `conductor` given by its complex index η + ik (or a named metal, [`METALS`]) is rendered
//! as a mirror (roughness 0) or a GGX rough conductor whose Schlick Fresnel starts from the
//! exact normal-incidence reflectance ((η − 1)² + k²) / ((η + 1)² + k²): the colour is exact
//! head-on, the rise toward grazing angles Schlick's (within a few per cent for metals).

use crate::error::{Error, Result};
use crate::material::{Bsdf, Material, Tint};
use crate::optics::{named_metal, ComplexIor, METALS};
use glam::Vec3;
use serde::Deserialize;

#[derive(Deserialize, Debug)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub(super) enum MaterialEntry {
    Lambert {
        kd: [f32; 3],
        #[serde(default)]
        emission: Option<[f32; 3]>,
    },
    Glossy {
        kd: [f32; 3],
        ks: [f32; 3],
        exponent: f32,
        #[serde(default)]
        emission: Option<[f32; 3]>,
    },
    Mirror {
        #[serde(default = "ones")]
        ks: [f32; 3],
        #[serde(default)]
        emission: Option<[f32; 3]>,
    },
    #[serde(rename = "rough_conductor")]
    RoughConductor {
        #[serde(default = "ones")]
        ks: [f32; 3],
        roughness: f32,
        #[serde(default)]
        emission: Option<[f32; 3]>,
    },
    #[serde(rename = "rough_plastic")]
    RoughPlastic {
        kd: [f32; 3],
        #[serde(default = "ior_default")]
        ior: f32,
        roughness: f32,
        #[serde(default)]
        emission: Option<[f32; 3]>,
    },
    #[serde(rename = "rough_dielectric")]
    RoughDielectric {
        #[serde(default = "ior_default")]
        ior: f32,
        #[serde(default = "one")]
        outside_ior: f32,
        roughness: f32,
        /// σ_a of the interior, per scene unit (Beer–Lambert; clear when absent).
        #[serde(default)]
        absorption: Option<[f32; 3]>,
        /// σ_s of the interior, per scene unit: it scatters (the path tracer).
        #[serde(default)]
        scattering: Option<[f32; 3]>,
        /// Henyey–Greenstein g of the interior's scattering.
        #[serde(default)]
        g: Option<f32>,
        #[serde(default)]
        emission: Option<[f32; 3]>,
    },
    /// A metal given by its complex index (`eta`, `k`) or by name (`metal`), smooth (a mirror)
    /// or rough.
    Conductor {
        #[serde(default)]
        eta: Option<[f32; 3]>,
        #[serde(default)]
        k: Option<[f32; 3]>,
        #[serde(default)]
        metal: Option<String>,
        #[serde(default)]
        roughness: f32,
        #[serde(default)]
        emission: Option<[f32; 3]>,
    },
    Glass {
        #[serde(default = "ior_default")]
        ior: f32,
        /// Index of the medium on the side the face's normal points to (1, air, by default):
        /// one face with `ior` and `outside_ior` is the boundary between two dielectrics.
        #[serde(default = "one")]
        outside_ior: f32,
        /// σ_a of the interior (the side the normal points away from), per scene unit
        /// (Beer–Lambert; clear when absent).
        #[serde(default)]
        absorption: Option<[f32; 3]>,
        /// σ_s of the interior, per scene unit: it scatters (the path tracer).
        #[serde(default)]
        scattering: Option<[f32; 3]>,
        /// Henyey–Greenstein g of the interior's scattering.
        #[serde(default)]
        g: Option<f32>,
        #[serde(default)]
        emission: Option<[f32; 3]>,
    },
    /// A thin sheet (a window pane, Mitsuba's `thindielectric`): straight through or reflected.
    #[serde(rename = "thin_glass")]
    ThinGlass {
        #[serde(default = "ior_default")]
        ior: f32,
        /// Scale on what it transmits (Mitsuba's `specular_transmittance`); a grey one lets
        /// every ray pass in traversal.
        #[serde(default = "ones")]
        transmittance: [f32; 3],
        #[serde(default)]
        emission: Option<[f32; 3]>,
    },
}

fn ones() -> [f32; 3] {
    [1.0; 3]
}
fn ior_default() -> f32 {
    1.5
}

pub(super) fn finite3(field: &str, v: [f32; 3]) -> Result<Vec3> {
    let v = Vec3::from_array(v);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::setting(field, "must be finite"))
    }
}

pub(super) fn colour(field: &str, v: [f32; 3]) -> Result<Vec3> {
    let v = finite3(field, v)?;
    if v.min_element() < 0.0 {
        Err(Error::setting(field, "must not be negative"))
    } else {
        Ok(v)
    }
}

/// GGX of α = `roughness`² for a roughness in (0, 1] (0 is the smooth `mirror` or `glass`).
fn roughness_alpha(field: &str, roughness: f32) -> Result<crate::microfacet::Alpha> {
    if roughness > 0.0 && roughness <= 1.0 {
        Ok(crate::microfacet::Alpha::ggx(crate::microfacet::alpha_of(roughness)))
    } else {
        Err(Error::setting(
            field,
            format!("must be in (0, 1], found {roughness} (a smooth surface is `mirror` or `glass`)"),
        ))
    }
}

fn albedo(field: &str, v: [f32; 3]) -> Result<Vec3> {
    let v = colour(field, v)?;
    if v.max_element() > 1.0 {
        Err(Error::setting(field, "must not exceed 1 (it would create energy)"))
    } else {
        Ok(v)
    }
}

impl MaterialEntry {
    /// The material this entry describes, called `name`.
    pub(super) fn to_material(&self, name: &str) -> Result<Material> {
        let f = |field: &str| format!("materials.{name}.{field}");
        let (bsdf, emission) = match *self {
            MaterialEntry::Lambert { kd, emission } => (Bsdf::Lambert { kd: albedo(&f("kd"), kd)? }, emission),
            MaterialEntry::Glossy { kd, ks, exponent, emission } => {
                let (kd, ks) = (albedo(&f("kd"), kd)?, albedo(&f("ks"), ks)?);
                if (kd + ks).max_element() > 1.0 {
                    return Err(Error::setting(f("ks"), "kd + ks must not exceed 1 in any channel"));
                }
                if !(exponent >= 0.0 && exponent.is_finite()) {
                    return Err(Error::setting(f("exponent"), "must be a finite number ≥ 0"));
                }
                (Bsdf::Glossy { kd, ks, exponent }, emission)
            }
            MaterialEntry::Mirror { ks, emission } => {
                (Bsdf::Mirror { ks: albedo(&f("ks"), ks)?, eta_k: None }, emission)
            }
            MaterialEntry::RoughConductor { ks, roughness, emission } => {
                let alpha = roughness_alpha(&f("roughness"), roughness)?;
                (Bsdf::RoughConductor { ks: albedo(&f("ks"), ks)?, alpha, eta_k: None }, emission)
            }
            MaterialEntry::RoughPlastic { kd, ior, roughness, emission } => {
                let alpha = roughness_alpha(&f("roughness"), roughness)?;
                if !(ior > 0.0 && ior.is_finite()) {
                    return Err(Error::setting(f("ior"), "must be a positive number"));
                }
                (Bsdf::rough_plastic(albedo(&f("kd"), kd)?, ior, alpha), emission)
            }
            MaterialEntry::RoughDielectric { ior, outside_ior, roughness, emission, .. } => {
                let alpha = roughness_alpha(&f("roughness"), roughness)?;
                if !(ior > 0.0 && ior.is_finite() && outside_ior > 0.0 && outside_ior.is_finite()) {
                    return Err(Error::setting(f("ior"), "`ior` and `outside_ior` must be positive numbers"));
                }
                (
                    Bsdf::RoughDielectric {
                        ior: finite_ratio(&f("ior"), ior / outside_ior)?,
                        alpha,
                        tint: Tint::CLEAR,
                    },
                    emission,
                )
            }
            MaterialEntry::Conductor { eta, k, ref metal, roughness, emission } => {
                let eta_k = match (eta, k, metal) {
                    (None, None, Some(name)) => named_metal(name).ok_or_else(|| {
                        let known: Vec<&str> = METALS.iter().map(|m| m.0).collect();
                        Error::setting(
                            f("metal"),
                            format!("unknown metal `{name}` (known: {}, none)", known.join(", ")),
                        )
                    })?,
                    (Some(eta), Some(k), None) => {
                        let (eta, k) = (colour(&f("eta"), eta)?, colour(&f("k"), k)?);
                        if eta.min_element() <= 0.0 {
                            return Err(Error::setting(f("eta"), "must be positive"));
                        }
                        ComplexIor { eta, k }
                    }
                    _ => return Err(Error::setting(f("type"), "a conductor takes `eta` and `k`, or `metal`")),
                };
                // The exact Fresnel of the complex index (`ks` is its scale).
                let (ks, eta_k) = (Vec3::ONE, Some(eta_k));
                if roughness == 0.0 {
                    (Bsdf::Mirror { ks, eta_k }, emission)
                } else {
                    let alpha = roughness_alpha(&f("roughness"), roughness)?;
                    (Bsdf::RoughConductor { ks, alpha, eta_k }, emission)
                }
            }
            MaterialEntry::Glass { ior, outside_ior, emission, .. } => {
                if !(ior > 0.0 && ior.is_finite()) {
                    return Err(Error::setting(f("ior"), "must be a positive number"));
                }
                if !(outside_ior > 0.0 && outside_ior.is_finite()) {
                    return Err(Error::setting(f("outside_ior"), "must be a positive number"));
                }
                (Bsdf::Glass { ior: finite_ratio(&f("ior"), ior / outside_ior)?, tint: Tint::CLEAR }, emission)
            }
            MaterialEntry::ThinGlass { ior, transmittance, emission } => {
                if !(ior > 0.0 && ior.is_finite()) {
                    return Err(Error::setting(f("ior"), "must be a positive number"));
                }
                let tint = Tint { reflect: Vec3::ONE, transmit: albedo(&f("transmittance"), transmittance)? };
                (Bsdf::ThinGlass { ior, tint, passed: false }, emission)
            }
        };
        let emission = match emission {
            Some(e) => colour(&f("emission"), e)?,
            None => Vec3::ZERO,
        };
        let (absorption, scattering, g) = match *self {
            MaterialEntry::Glass { absorption, scattering, g, .. }
            | MaterialEntry::RoughDielectric { absorption, scattering, g, .. } => (absorption, scattering, g),
            _ => (None, None, None),
        };
        let sigma_a = absorption.map_or(Ok(Vec3::ZERO), |a| colour(&f("absorption"), a))?;
        let sigma_s = scattering.map_or(Ok(Vec3::ZERO), |a| colour(&f("scattering"), a))?;
        if g.is_some() && sigma_s == Vec3::ZERO {
            return Err(Error::setting(f("g"), "is the interior's phase function: give `scattering` too"));
        }
        let interior_scattering = if sigma_s == Vec3::ZERO {
            None
        } else {
            Some(
                crate::medium::Medium::new(sigma_a, sigma_s, g.unwrap_or(0.0))
                    .map_err(|e| Error::setting(f("g"), e))?,
            )
        };
        Ok(Material { interior: sigma_a + sigma_s, interior_scattering, ..Material::new(name, bsdf, emission) })
    }
}

fn one() -> f32 {
    1.0
}

/// `ior / outside_ior`, refused unless finite and positive (1e30 / 1e-30 is not).
fn finite_ratio(field: &str, ratio: f32) -> Result<f32> {
    if ratio.is_finite() && ratio > 0.0 {
        Ok(ratio)
    } else {
        Err(Error::setting(field, format!("ior / outside_ior = {ratio} must be a finite positive ratio")))
    }
}
