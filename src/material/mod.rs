//! Materials and their BSDFs: Lambertian, glossy (Lambertian + normalised Phong lobe), perfect
//! mirror (constant or a conductor's exact Fresnel), smooth dielectric, thin dielectric sheet,
//! and the microfacet rough ones (GGX or Beckmann); their evaluate, pdf and sample are in `bsdf`.
//!
//! Directions are world-space unit vectors pointing away from the surface: `wo` toward the viewer
//! (or where the photon came from), `wi` toward the next vertex. Opaque materials are two-sided:
//! the frame is flipped to the side of `wo`. The dielectric uses the unflipped normal to know
//! whether the ray enters or leaves.

use crate::microfacet;
pub use crate::optics::{fresnel_dielectric, reflect, refract};
use crate::texture::Texture;
use glam::{Vec2, Vec3};
use std::sync::Arc;

mod bsdf;
mod opacity;
mod plastic;
mod prepared;
pub use opacity::{AlphaMode, Opacity};
pub use plastic::{fresnel_diffuse_reflectance, PlasticSample, SmoothPlastic};
pub use prepared::Prepared;

/// What flows along the path: radiance (camera paths) or power (photons). Refraction scales
/// radiance by (η_wo / η_wi)², never power.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    /// Camera paths carry radiance.
    Radiance,
    /// Photon paths carry power.
    Power,
}

/// The scattering part of a material.
#[derive(Clone, Copy, Debug, PartialEq)]
// Each variant's doc names and explains its fields.
#[allow(missing_docs)]
pub enum Bsdf {
    /// Lambertian reflection with albedo `kd`.
    Lambert { kd: Vec3 },
    /// Lambertian `kd` plus a normalised modified-Phong lobe `ks·(n+2)/(2π)·cos^n α` around the mirror
    /// direction (Lafortune & Willems 1994); kd + ks ≤ 1 per channel, so it never gains energy.
    Glossy { kd: Vec3, ks: Vec3, exponent: f32 },
    /// Perfect mirror: reflectance `ks` at every angle, or with the complex index `eta_k` its
    /// exact Fresnel times `ks` (Mitsuba's `conductor`).
    Mirror { ks: Vec3, eta_k: Option<crate::optics::ComplexIor> },
    /// Smooth dielectric with index of refraction `ior` (relative to the outside, the side the
    /// geometric normal points to), exact Fresnel, its reflection and transmission scaled by
    /// `tint` (clear: 1).
    Glass { ior: f32, tint: Tint },
    /// A thin dielectric sheet of index `ior` (Mitsuba's `thindielectric`, a window pane): light
    /// passes straight through, unbent, or is reflected, with the slab's reflectance
    /// ([`crate::optics::thin_slab_reflectance`]: the two faces and every bounce between them).
    /// `passed`: rays pass the sheet in traversal with its transmittance, as through a cut-out
    /// ([`Bsdf::thin_pass`]), so a hit is a reflection (set by the scene for a sheet whose
    /// transmission tint is grey; `false` as read).
    ThinGlass { ior: f32, tint: Tint, passed: bool },
    /// Rough conductor ([`crate::microfacet`]): microfacets `alpha` (GGX or Beckmann), Schlick's
    /// Fresnel from the normal-incidence reflectance `ks`, or with the complex index `eta_k` its
    /// exact Fresnel times `ks` ([`crate::optics::conductor_reflectance`]).
    RoughConductor { ks: Vec3, alpha: microfacet::Alpha, eta_k: Option<crate::optics::ComplexIor> },
    /// Rough (frosted) dielectric: microfacets `alpha`, exact Fresnel, reflection and refraction
    /// through the microfacets; `ior` and `tint` as for [`Bsdf::Glass`].
    RoughDielectric { ior: f32, alpha: microfacet::Alpha, tint: Tint },
    /// Rough plastic, Mitsuba 3's `roughplastic` ([`microfacet::Plastic`]): a dielectric coat
    /// of microfacets `alpha` over a Lambertian base `kd`, the coat's reflection scaled by `ks`
    /// (Mitsuba's `specular_reflectance`, 1 elsewhere); `coat` holds its index ratio and its
    /// transmittance tables ([`Bsdf::rough_plastic`] builds it); `nonlinear` lets the base's
    /// bounces under the coat tint by kd.
    RoughPlastic { kd: Vec3, ks: Vec3, alpha: microfacet::Alpha, nonlinear: bool, coat: microfacet::CoatAt },
    /// Smooth plastic, Mitsuba 3's `plastic` ([`SmoothPlastic`]): a smooth dielectric coat of
    /// index ratio `eta` whose mirror reflection is scaled by `ks`, over a Lambertian base `kd`;
    /// `nonlinear` as for [`Bsdf::RoughPlastic`]. Its coat is a delta lobe beside a diffuse
    /// base: camera paths follow it with their glossy ray, photons are stored on it.
    Plastic { kd: Vec3, ks: Vec3, eta: f32, nonlinear: bool },
}

/// A dielectric's scales on what it reflects and what it transmits (Mitsuba's
/// `specular_reflectance` and `specular_transmittance`; glTF's base colour on transmission). The
/// sampling probabilities stay Fresnel's: only the sample weights and values are scaled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tint {
    /// Scale on reflection.
    pub reflect: Vec3,
    /// Scale on transmission.
    pub transmit: Vec3,
}

impl Tint {
    /// No scale.
    pub const CLEAR: Tint = Tint { reflect: Vec3::ONE, transmit: Vec3::ONE };

    /// The scale of a lobe: reflection where `wo` and `wi` lie on one side of the geometric
    /// normal `ng`, transmission otherwise.
    #[inline]
    #[must_use]
    pub fn of(&self, ng: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        if (wo.dot(ng) > 0.0) == (wi.dot(ng) > 0.0) {
            self.reflect
        } else {
            self.transmit
        }
    }
}

impl Bsdf {
    /// A rough plastic of base `kd`, coat index ratio `ior` and width `alpha`, Mitsuba's default
    /// (linear) internal bounces.
    #[must_use]
    pub fn rough_plastic(kd: Vec3, ior: f32, alpha: microfacet::Alpha) -> Bsdf {
        Bsdf::RoughPlastic { kd, ks: Vec3::ONE, alpha, nonlinear: false, coat: microfacet::CoatAt::new(ior, alpha) }
    }

    /// A plastic (rough or smooth) whose base's bounces under the coat tint by kd (`nonlinear`,
    /// Mitsuba's flag of that name); other materials unchanged.
    #[must_use]
    pub fn with_nonlinear(self, nonlinear: bool) -> Bsdf {
        match self {
            Bsdf::RoughPlastic { kd, ks, alpha, coat, .. } => Bsdf::RoughPlastic { kd, ks, alpha, nonlinear, coat },
            Bsdf::Plastic { kd, ks, eta, .. } => Bsdf::Plastic { kd, ks, eta, nonlinear },
            other => other,
        }
    }

    /// A plastic (rough or smooth) whose coat's reflection is scaled by `ks` (Mitsuba's
    /// `specular_reflectance`); other materials unchanged.
    #[must_use]
    pub fn with_coat_scale(self, ks: Vec3) -> Bsdf {
        match self {
            Bsdf::RoughPlastic { kd, alpha, nonlinear, coat, .. } => {
                Bsdf::RoughPlastic { kd, ks, alpha, nonlinear, coat }
            }
            Bsdf::Plastic { kd, eta, nonlinear, .. } => Bsdf::Plastic { kd, ks, eta, nonlinear },
            other => other,
        }
    }
}

/// The α (the larger width) below which a rough conductor acts as a mirror for photons (roughness 0.3): its
/// photons pass on as specular, so its caustics go into the caustic map, instead of being
/// stored on it. Rough dielectrics always pass photons on (a photon stored on frosted glass
/// could never light what lies behind it). The effects plan says which surfaces are which.
pub const PHOTON_SPECULAR_ALPHA: f32 = 0.09;

/// The Phong exponent as narrow as a GGX lobe of [`PHOTON_SPECULAR_ALPHA`]: 2/α² − 2, the usual
/// match of the two lobes' widths (Walter et al. 2007); above it a Phong lobe is
/// [`Bsdf::narrow_lobe`].
pub const NARROW_PHONG_EXPONENT: f32 = 2.0 / (PHOTON_SPECULAR_ALPHA * PHOTON_SPECULAR_ALPHA) - 2.0;

/// A named material: scattering plus emitted radiance from the front face.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name as in the MTL file or scene file.
    pub name: String,
    /// Scattering.
    pub bsdf: Bsdf,
    /// Emitted radiance from the front (counter-clockwise) face; zero for non-emitters.
    pub emission: Vec3,
    /// Image textures that replace the constant colours where the surface has them.
    pub maps: Maps,
    /// The absorption coefficient σ_a (per scene unit, per channel) of what a dielectric
    /// encloses, the side its geometric normal points away from: light crossing a length d of
    /// it keeps exp(−σ_a·d) (Beer–Lambert; Mitsuba's interior `homogeneous` medium, glTF's
    /// `KHR_materials_volume` attenuation). Zero for a clear interior and for every material
    /// that is not a dielectric.
    pub interior: Vec3,
    /// The whole medium of that interior when it also scatters (σ_a, σ_s, g; σ_a + σ_s is
    /// `interior`): the path tracer samples free flight in it and scatters light back in; the
    /// photon-mapping engines attenuate by `interior` alone. `None` for a clear or purely
    /// absorbing interior.
    pub interior_scattering: Option<crate::medium::Medium>,
    /// A tangent-space normal map that bends the shading normal ([`NormalMap`]).
    pub normal_map: Option<NormalMap>,
    /// An alpha cut-out: where the surface is absent ([`Opacity`]); `None`: opaque everywhere.
    pub opacity: Option<Opacity>,
}

/// A texture that bends the shading normal ([`crate::scene::Scene::surface`]):
/// - normals ([`Relief::Normals`]; Mitsuba's `normalmap`, glTF's `normalTexture`): each texel's
///   RGB is a normal m = 2·rgb − 1 in the frame of the interpolated normal n, the texture's u
///   direction s (dp/du made orthogonal to n) and t = n × s; the shading normal becomes
///   s·m.x + t·m.y + n·m.z;
/// - heights ([`Relief::Heights`]; Mitsuba's `bumpmap`): the texel's luminance h is a height
///   along n, so the surface's tangents become dp/du + n·(scale·∂h/∂u − n·dp/du) and the same in
///   v (Mitsuba's form), and the shading normal their cross product, on the geometric normal's
///   side.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalMap {
    /// The map (linear data, not colour).
    pub texture: Arc<Texture>,
    /// What its texels are.
    pub relief: Relief,
    /// Scale of m.x and m.y (glTF's `normalTexture.scale`; 1 elsewhere), or of the height
    /// gradient (Mitsuba's `bumpmap` `scale`).
    pub scale: f32,
    /// Turn t where the texture coordinates are mirrored (glTF's bitangent, which follows the
    /// handedness of (dp/du, dp/dv)); Mitsuba's frame does not.
    pub handed: bool,
}

/// What a [`NormalMap`]'s texels hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Relief {
    /// Tangent-space normals, 2·rgb − 1.
    Normals,
    /// Heights (the texel's luminance).
    Heights,
}

/// A material's image textures: each, when present, replaces its constant colour at every
/// point by the texture's value at the point's texture coordinates.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Maps {
    /// Diffuse albedo (MTL `map_Kd`): replaces `kd`.
    pub kd: Option<Arc<Texture>>,
    /// Specular reflectance (MTL `map_Ks`): replaces `ks` of glossy and mirror materials.
    pub ks: Option<Arc<Texture>>,
    /// Roughness (MTL `map_Pr`, a linear data map read from its red channel): replaces the rough
    /// materials' roughness, within the material's photon class ([`Material::bsdf_at`]).
    pub roughness: Option<Arc<Texture>>,
    /// Emitted radiance (MTL `map_Ke`): multiplies the emission of an emitter.
    pub ke: Option<Arc<Texture>>,
    /// Metalness (MTL `map_Pm`, data, red channel): where it is at least ½ a rough material is a
    /// rough conductor of the base colour, elsewhere a rough plastic of it ([`Material::bsdf_at`]).
    pub metallic: Option<Arc<Texture>>,
}

impl Maps {
    /// True when the material has no texture.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.kd.is_none()
            && self.ks.is_none()
            && self.roughness.is_none()
            && self.ke.is_none()
            && self.metallic.is_none()
    }
}

impl Material {
    /// A material without textures.
    #[must_use]
    pub fn new(name: impl Into<String>, bsdf: Bsdf, emission: Vec3) -> Material {
        Material {
            name: name.into(),
            bsdf,
            emission,
            maps: Maps::default(),
            interior: Vec3::ZERO,
            interior_scattering: None,
            normal_map: None,
            opacity: None,
        }
    }

    /// True when some texture of the material is read at texture coordinates (colour maps, a
    /// normal map, an opacity map): its triangles need theirs.
    #[must_use]
    pub fn reads_texture_coordinates(&self) -> bool {
        !self.maps.is_empty() || self.normal_map.is_some() || self.opacity.as_ref().is_some_and(|o| o.texture.is_some())
    }

    /// The radiance emitted at texture coordinates `uv` from the front face: the constant
    /// emission times the emission texture's value there (an 8-bit texture holds colours up to 1;
    /// `Ke` scales them, as the MTL spec multiplies a map by its constant).
    #[inline]
    #[must_use]
    pub fn emission_at(&self, uv: Vec2) -> Vec3 {
        match &self.maps.ke {
            Some(t) => self.emission * t.lookup(uv),
            None => self.emission,
        }
    }

    /// Whether some point of the material may have a narrow lobe ([`Bsdf::narrow_lobe`]): its
    /// constant BSDF has one, or a roughness or metallic map may give one (a cheap test before
    /// the point's own BSDF is built).
    #[inline]
    #[must_use]
    pub fn may_have_narrow_lobe(&self) -> bool {
        self.bsdf.narrow_lobe() || self.maps.roughness.is_some() || self.maps.metallic.is_some()
    }

    /// The scattering at texture coordinates `uv`: the constant BSDF with its textured colours
    /// replaced. Albedos are kept within energy conservation as the MTL mapping keeps the
    /// constants: a Lambertian or mirror colour at most 1, a glossy `kd + ks` at most 1 per
    /// channel (both scaled down together). A roughness map sets α = roughness² but keeps a rough
    /// conductor on its constant roughness's side of [`PHOTON_SPECULAR_ALPHA`]: whether photons
    /// pass a material is decided per material, so both engines route it alike.
    #[inline]
    #[must_use]
    pub fn bsdf_at(&self, uv: Vec2) -> Bsdf {
        if self.maps.is_empty() {
            return self.bsdf;
        }
        let kd_at = |kd: Vec3| self.maps.kd.as_ref().map_or(kd, |t| t.lookup(uv));
        let ks_at = |ks: Vec3| self.maps.ks.as_ref().map_or(ks, |t| t.lookup(uv));
        let alpha_at = |alpha: microfacet::Alpha| {
            self.maps
                .roughness
                .as_ref()
                .map_or(alpha, |t| alpha.with_width(microfacet::alpha_of(t.lookup(uv).x.clamp(0.0, 1.0))))
        };
        if let Some(m) = &self.maps.metallic {
            // The PBR extension's metallic workflow, per point: the base colour makes a metal's
            // reflectance or a plastic's base. Metal parts store photons (α at least
            // PHOTON_SPECULAR_ALPHA), as plastic does, so the material's photon class is one.
            let (base, ks, coat, nonlinear, alpha) = match self.bsdf {
                Bsdf::RoughPlastic { kd, ks, alpha, nonlinear, coat } => {
                    (kd_at(kd), ks, coat, nonlinear, alpha_at(alpha))
                }
                Bsdf::RoughConductor { ks, alpha, .. } => {
                    (ks_at(ks), Vec3::ONE, metal_map_coat(), false, alpha_at(alpha))
                }
                other => return other,
            };
            let base = base.min(Vec3::ONE);
            return if m.lookup(uv).x >= 0.5 {
                Bsdf::RoughConductor {
                    ks: base,
                    alpha: alpha.with_width(alpha.width().max(PHOTON_SPECULAR_ALPHA)),
                    eta_k: None,
                }
            } else {
                plastic_at(base, ks, coat, nonlinear, alpha)
            };
        }
        match self.bsdf {
            Bsdf::Lambert { kd } => Bsdf::Lambert { kd: kd_at(kd).min(Vec3::ONE) },
            Bsdf::Glossy { kd, ks, exponent } => {
                let (kd, ks) = (kd_at(kd), ks_at(ks));
                let sum = (kd + ks).max_element();
                let scale = if sum > 1.0 { 1.0 / sum } else { 1.0 };
                Bsdf::Glossy { kd: kd * scale, ks: ks * scale, exponent }
            }
            Bsdf::Mirror { ks, eta_k } => Bsdf::Mirror { ks: ks_at(ks).min(Vec3::ONE), eta_k },
            Bsdf::RoughConductor { ks, alpha, eta_k } => {
                let a = alpha_at(alpha);
                // The same photon class as the constant roughness.
                let a = if alpha.width() < PHOTON_SPECULAR_ALPHA {
                    a.with_width(a.width().min(PHOTON_SPECULAR_ALPHA * (1.0 - f32::EPSILON)))
                } else {
                    a.with_width(a.width().max(PHOTON_SPECULAR_ALPHA))
                };
                Bsdf::RoughConductor { ks: ks_at(ks).min(Vec3::ONE), alpha: a, eta_k }
            }
            Bsdf::RoughPlastic { kd, ks, alpha, nonlinear, coat } => {
                let kd = kd_at(kd).min(Vec3::ONE);
                match &self.maps.roughness {
                    Some(_) => plastic_at(kd, ks, coat, nonlinear, alpha_at(alpha)),
                    None => Bsdf::RoughPlastic { kd, ks, alpha, nonlinear, coat },
                }
            }
            Bsdf::RoughDielectric { ior, alpha, tint } => Bsdf::RoughDielectric { ior, alpha: alpha_at(alpha), tint },
            Bsdf::Plastic { kd, ks, eta, nonlinear } => {
                Bsdf::Plastic { kd: kd_at(kd).min(Vec3::ONE), ks, eta, nonlinear }
            }
            b @ (Bsdf::Glass { .. } | Bsdf::ThinGlass { .. }) => b,
        }
    }
}

/// A textured rough plastic at one point: its own α shapes the coat's lobe, the roughness
/// levels of its coat's η around it give the coat's tables ([`microfacet::CoatAt::at`]).
fn plastic_at(kd: Vec3, ks: Vec3, coat: microfacet::CoatAt, nonlinear: bool, alpha: microfacet::Alpha) -> Bsdf {
    Bsdf::RoughPlastic { kd, ks, alpha, nonlinear, coat: coat.at(alpha.width()) }
}

/// The coat (index 1.5) of the plastic parts a metallic map makes of a rough conductor.
fn metal_map_coat() -> microfacet::CoatAt {
    static COAT: std::sync::OnceLock<microfacet::CoatAt> = std::sync::OnceLock::new();
    *COAT.get_or_init(|| microfacet::CoatAt::new(1.5, microfacet::Alpha::ggx(microfacet::MIN_ALPHA)))
}

/// A BSDF sample whose pdf came out zero (see [`Bsdf::sample_checked`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ZeroPdf;

/// A sampled direction and its weight `f·|cos θi| / pdf` (for delta lobes, the lobe's weight).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// Sampled incident direction (unit).
    pub wi: Vec3,
    /// Throughput multiplier.
    pub weight: Vec3,
    /// True for mirror reflection and dielectric reflection/refraction.
    pub delta: bool,
}

/// Geometry the BSDF needs at a point: geometric and shading normals (unit, unflipped).
#[derive(Clone, Copy, Debug)]
pub struct SurfaceFrame {
    /// Geometric normal, as wound (front face).
    pub ng: Vec3,
    /// Shading normal (interpolated vertex normal, or `ng`).
    pub ns: Vec3,
}

impl SurfaceFrame {
    /// Normals flipped to the side of `wo`: (geometric, shading). The shading normal falls back to
    /// the geometric one when they disagree about the side.
    #[must_use]
    pub fn oriented(&self, wo: Vec3) -> (Vec3, Vec3) {
        let ng = if wo.dot(self.ng) < 0.0 { -self.ng } else { self.ng };
        let ns = if self.ns.dot(ng) < 0.0 { -self.ns } else { self.ns };
        let ns = if ns.dot(ng) > 0.0 && ns.is_finite() { ns } else { ng };
        (ng, ns)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::microfacet::Alpha;

    #[test]
    fn a_roughness_map_sets_alpha_within_the_photon_class() {
        let grey =
            |v: f32| Some(Arc::new(Texture::new(std::path::Path::new("r.png"), 1, 1, vec![Vec3::splat(v)]).unwrap()));
        let rough = |bsdf: Bsdf, v: f32| Material {
            maps: Maps { roughness: grey(v), ..Maps::default() },
            ..Material::new("m", bsdf, Vec3::ZERO)
        };
        let uv = Vec2::splat(0.5);
        let Bsdf::RoughPlastic { alpha, .. } =
            rough(Bsdf::rough_plastic(Vec3::ONE, 1.5, Alpha::beckmann(0.5)), 0.6).bsdf_at(uv)
        else {
            panic!()
        };
        // The texture sets the width, the distribution stays.
        assert_eq!(alpha, Alpha::beckmann(0.36));
        // A conductor whose photons are stored (α ≥ 0.09) stays there, and one whose photons pass stays below.
        let stored =
            rough(Bsdf::RoughConductor { ks: Vec3::ONE, alpha: Alpha::ggx(0.25), eta_k: None }, 0.1).bsdf_at(uv);
        assert_eq!(
            stored,
            Bsdf::RoughConductor { ks: Vec3::ONE, alpha: Alpha::ggx(PHOTON_SPECULAR_ALPHA), eta_k: None }
        );
        let passed =
            rough(Bsdf::RoughConductor { ks: Vec3::ONE, alpha: Alpha::ggx(0.01), eta_k: None }, 0.9).bsdf_at(uv);
        assert!(passed.photon_specular(), "{passed:?}");
        let Bsdf::RoughConductor { alpha, .. } =
            rough(Bsdf::RoughConductor { ks: Vec3::ONE, alpha: Alpha::ggx(0.01), eta_k: None }, 0.2).bsdf_at(uv)
        else {
            panic!()
        };
        assert!((alpha.u - 0.04).abs() < 1e-6 && alpha.u == alpha.v);
    }

    #[test]
    fn a_metallic_map_picks_conductor_or_plastic_per_point() {
        let two =
            Some(Arc::new(Texture::new(std::path::Path::new("m.png"), 2, 1, vec![Vec3::ZERO, Vec3::ONE]).unwrap()));
        let m = Material {
            maps: Maps { metallic: two, ..Maps::default() },
            ..Material::new("m", Bsdf::rough_plastic(Vec3::new(0.9, 0.5, 0.1), 1.4, Alpha::ggx(0.04)), Vec3::ZERO)
        };
        let Bsdf::RoughPlastic { kd, alpha, coat, .. } = m.bsdf_at(Vec2::new(0.25, 0.5)) else { panic!() };
        assert_eq!((kd, alpha, coat.eta), (Vec3::new(0.9, 0.5, 0.1), Alpha::ggx(0.04), 1.4));
        let metal = m.bsdf_at(Vec2::new(0.75, 0.5));
        assert_eq!(
            metal,
            Bsdf::RoughConductor {
                ks: Vec3::new(0.9, 0.5, 0.1),
                alpha: Alpha::ggx(PHOTON_SPECULAR_ALPHA),
                eta_k: None
            }
        );
        assert!(!metal.photon_specular(), "metal parts store photons, as the plastic does");
    }

    #[test]
    fn fresnel_known_values() {
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        let c45 = std::f32::consts::FRAC_1_SQRT_2;
        assert!((fresnel_dielectric(c45, 1.5) - 0.0502).abs() < 1e-4, "{}", fresnel_dielectric(c45, 1.5));
        // Glass → air: critical angle asin(1/1.5) = 41.81°.
        let crit = (1.0f32 / 1.5).asin();
        assert_eq!(fresnel_dielectric((crit + 1e-3).cos(), 1.0 / 1.5), 1.0);
        assert!(fresnel_dielectric((crit - 1e-3).cos(), 1.0 / 1.5) < 1.0);
    }

    #[test]
    fn reflectance_plus_transmittance_is_one() {
        // Energy through the boundary: T = 1 − R, and T computed from the Fresnel amplitudes agrees.
        for i in 0..90 {
            let th = (i as f32).to_radians();
            let (ci, eta) = (th.cos(), 1.5f32);
            let r = fresnel_dielectric(ci, eta);
            let st2 = (1.0 - ci * ci) / (eta * eta);
            let ct = (1.0 - st2).sqrt();
            let ts = 2.0 * ci / (ci + eta * ct);
            let tp = 2.0 * ci / (eta * ci + ct);
            let t = eta * ct / ci * 0.5 * (ts * ts + tp * tp);
            assert!((r + t - 1.0).abs() < 1e-4, "θ={i}: R={r} T={t}");
        }
    }

    #[test]
    fn total_internal_reflection_is_exact() {
        let frame = SurfaceFrame { ng: Vec3::Z, ns: Vec3::Z };
        // Inside the glass (wo below the surface), 60° from the normal: past 41.8°.
        let wo = Vec3::new(60f32.to_radians().sin(), 0.0, -60f32.to_radians().cos());
        for k in 0..100 {
            let s = Bsdf::Glass { ior: 1.5, tint: Tint::CLEAR }
                .sample(&frame, wo, [k as f32 / 100.0, 0.5, 0.5], Transport::Power)
                .unwrap();
            assert_eq!(s.weight, Vec3::ONE);
            assert!(s.wi.z < 0.0, "must stay inside");
        }
    }

    #[test]
    fn lambert_sample_weight_is_kd_exactly() {
        let kd = Vec3::new(0.7, 0.3, 0.05);
        let frame = SurfaceFrame { ng: Vec3::Y, ns: Vec3::Y };
        for i in 0..64 {
            let u = [(i % 8) as f32 / 8.0 + 0.03, (i / 8) as f32 / 8.0 + 0.05, 0.5];
            let s = Bsdf::Lambert { kd }.sample(&frame, Vec3::Y, u, Transport::Radiance).unwrap();
            assert_eq!(s.weight, kd);
            assert!(s.wi.dot(Vec3::Y) > 0.0);
        }
    }

    #[test]
    fn glossy_never_reflects_more_than_it_receives() {
        // Monte Carlo albedo (mean of sample weights) at several incidence angles, per channel ≤ 1.
        let b = Bsdf::Glossy { kd: Vec3::splat(0.5), ks: Vec3::splat(0.5), exponent: 20.0 };
        let frame = SurfaceFrame { ng: Vec3::Z, ns: Vec3::Z };
        for deg in [0.0f32, 30.0, 60.0, 85.0] {
            let wo = Vec3::new(deg.to_radians().sin(), 0.0, deg.to_radians().cos());
            let n = 64;
            let mut sum = Vec3::ZERO;
            for i in 0..n * n {
                let u = [
                    ((i % n) as f32 + 0.5) / n as f32,
                    ((i / n) as f32 + 0.5) / n as f32,
                    ((i * 7919) % 1000) as f32 / 1000.0,
                ];
                if let Some(s) = b.sample(&frame, wo, u, Transport::Radiance) {
                    sum += s.weight;
                }
            }
            let albedo = sum / (n * n) as f32;
            // Stratified estimate; 2 % slack for its error.
            assert!(albedo.max_element() <= 1.02, "θ={deg}: albedo {albedo}");
        }
    }
}
