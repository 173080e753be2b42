//! Density-estimation kernels: the weight of a photon at a distance from the query, its 8-wide
//! twin with the same operations, and the normalisation that returns a uniform density exactly.

use serde::{Deserialize, Serialize};
use std::f32::consts::PI;
use wide::f32x8;

/// Density-estimation kernel, each normalised so that a uniform photon density is returned exactly.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Kernel {
    /// Constant weight: ∑Φ / (πr²).
    Box,
    /// Jensen's cone filter, weight 1 − d/r, normalised by 3/(πr²).
    Cone,
    /// Epanechnikov, weight 1 − d²/r², normalised by 2/(πr²).
    Epanechnikov,
}

impl std::str::FromStr for Kernel {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "box" => Ok(Kernel::Box),
            "cone" => Ok(Kernel::Cone),
            "epanechnikov" => Ok(Kernel::Epanechnikov),
            _ => Err(format!("unknown kernel `{s}` (box, cone, epanechnikov)")),
        }
    }
}

impl Kernel {
    /// Weight of a photon at squared distance `d2` from the query, radius² `r2`.
    #[inline]
    #[must_use]
    pub fn weight(self, d2: f32, r2: f32) -> f32 {
        match self {
            Kernel::Box => 1.0,
            Kernel::Cone => 1.0 - (d2 / r2).sqrt(),
            Kernel::Epanechnikov => 1.0 - d2 / r2,
        }
    }
    /// [`Kernel::weight`] for 8 photons, the same operations.
    #[inline]
    pub(super) fn weight8(self, d2: f32x8, r2: f32x8) -> f32x8 {
        match self {
            Kernel::Box => f32x8::ONE,
            Kernel::Cone => f32x8::ONE - (d2 / r2).sqrt(),
            Kernel::Epanechnikov => f32x8::ONE - d2 / r2,
        }
    }
    /// 1 / ∫ weight dA over the disk of radius² `r2`: the normalisation that returns a uniform
    /// density exactly.
    #[inline]
    #[must_use]
    pub fn normalisation(self, r2: f32) -> f32 {
        match self {
            Kernel::Box => 1.0 / (PI * r2),
            Kernel::Cone => 3.0 / (PI * r2),
            Kernel::Epanechnikov => 2.0 / (PI * r2),
        }
    }

    /// The weight of a photon at squared distance `d2` in the estimate of this kernel's bias
    /// ([`Kernel::bias_normalisation`]): 2·d²/r² − 1, the Laplacian of the biweight kernel
    /// (1 − d²/r²)² up to its constant, whose gradient vanishes at the rim, so the Laplacian
    /// estimate has no ring term. Its sum over a uniform density is zero.
    #[inline]
    #[must_use]
    pub fn bias_weight(d2: f32, r2: f32) -> f32 {
        // d²/r² as the kernels' weights compute it, so that the two share the division.
        2.0 * (d2 / r2) - 1.0
    }

    /// [`Kernel::bias_weight`] for 8 photons, the same operations.
    #[inline]
    pub(super) fn bias_weight8(d2: f32x8, r2: f32x8) -> f32x8 {
        f32x8::splat(2.0) * (d2 / r2) - f32x8::ONE
    }

    /// The normalisation of the bias sum Σ f·Φ·[`Kernel::bias_weight`] that makes it an estimate
    /// of this kernel's leading bias, E[L̂] − L ≈ ½·μ₂·r²·ΔL (Hachisuka, Jarosz and Jensen 2010;
    /// ΔL the surface Laplacian of the reflected radiance, μ₂·r² = ∫K·x² dA: r²/4 box, 3r²/20
    /// cone, r²/6 Epanechnikov). ΔL is estimated with the biweight kernel's Laplacian,
    /// Δ[(3/πr²)(1 − s)²] = 24(2s − 1)/(πr⁴) with s = d²/r², so the normalisation is
    /// 12·μ₂/(πr²): 3/(πr²), 9/(5πr²), 2/(πr²). Exact for radiance that is quadratic over the disk
    /// (tested).
    #[inline]
    #[must_use]
    pub fn bias_normalisation(self, r2: f32) -> f32 {
        match self {
            Kernel::Box => 3.0 / (PI * r2),
            Kernel::Cone => 9.0 / (5.0 * PI * r2),
            Kernel::Epanechnikov => 2.0 / (PI * r2),
        }
    }
}
