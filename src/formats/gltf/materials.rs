//! glTF 2.0 materials onto photonwave's BSDFs, with their textures.
//!
//! The metallic–roughness model mapped (base colour b, metallic m, roughness r, all factors times
//! their textures):
//! - transmission ≥ ½ (`KHR_materials_transmission`), index `KHR_materials_ior` (1.5 by
//!   default): with `KHR_materials_volume` of a non-zero thickness the boundary of a solid —
//!   smooth glass (r < 0.05) or a GGX rough dielectric of α = r²; without it thin-walled, as the
//!   spec has it — a thin sheet (light passes unbent) when smooth, a rough dielectric (warned of)
//!   when rough; a solid's volume attenuation absorbs inside it (σ_a = −ln(colour)/distance,
//!   Beer–Lambert), and the base colour tints what is transmitted (a texture by its mean, warned of);
//! - m ≥ ½: a mirror of reflectance b (r < 0.05) or a GGX rough conductor (Schlick from b);
//! - otherwise a rough plastic (GGX coat of index 1.5 over a Lambertian base b), or Lambertian b
//!   where r ≥ 0.95 (the 4 % coat at that roughness scatters nearly diffusely itself);
//! - a metallic–roughness texture makes the choice per point (metal where m ≥ ½).
//!
//! Emission is `emissiveFactor` × `KHR_materials_emissive_strength` (radiance, taken as
//! photonwave's units, as Blender imports it) times the emissive texture, from the front face.
//! The normal texture bends the shading normal ([`NormalMap`], glTF's handedness). `alphaMode`
//! cuts the surface out ([`Opacity`]; α = the base colour factor's alpha times the base colour
//! texture's alpha channel): `MASK` where α < `alphaCutoff` (0.5 by default), `BLEND` as coverage
//! (present with probability α); occlusion textures are warned of by name.

use super::Sources;
use crate::error::Result;
use crate::material::{AlphaMode, Bsdf, Maps, Material, NormalMap, Opacity, Relief, Tint, PHOTON_SPECULAR_ALPHA};
use crate::microfacet::{alpha_of, Alpha};
use crate::texture::{Encoding, Texture};
use glam::{Vec2, Vec3};
use std::sync::Arc;

/// Below this roughness a surface is taken as smooth (mirror, glass).
const SMOOTH: f32 = 0.05;
/// At or above this roughness a dielectric base is Lambertian.
const DIFFUSE: f32 = 0.95;

/// A glTF texture reference's transform (`KHR_texture_transform`) and coordinate set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct UvTransform {
    pub offset: Vec2,
    pub rotation: f32,
    pub scale: Vec2,
}

impl UvTransform {
    /// Where glTF texture coordinates `uv` go.
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let (s, c) = self.rotation.sin_cos();
        let p = uv * self.scale;
        Vec2::new(c * p.x + s * p.y, -s * p.x + c * p.y) + self.offset
    }
}

/// A converted material and the coordinate transform its textures want.
pub(super) struct Converted {
    pub material: Material,
    pub uv: Option<UvTransform>,
}

/// `t`'s texels times `factor`, per channel (`channel` picks one to fill all three: 1 = green,
/// 2 = blue, as glTF stores roughness and metalness).
fn derived(t: &Texture, factor: Vec3, channel: Option<usize>) -> Arc<Texture> {
    let texels = t
        .texels
        .iter()
        .map(|x| match channel {
            Some(c) => Vec3::splat(x[c] * factor.x),
            None => *x * factor,
        })
        .collect();
    Arc::new(Texture { path: t.path.clone(), width: t.width, height: t.height, texels })
}

/// The material `m` of the glTF file, called `name`.
pub(super) fn convert(
    m: &gltf::Material,
    name: &str,
    src: &mut Sources,
    warnings: &mut Vec<String>,
) -> Result<Converted> {
    let file = src.path.display().to_string();
    let mut warn = |what: String| warnings.push(format!("{file}: material `{name}`: {what}"));
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, base_alpha] = pbr.base_color_factor();
    let base = Vec3::new(r, g, b).clamp(Vec3::ZERO, Vec3::ONE);
    let (metallic, roughness) = (pbr.metallic_factor().clamp(0.0, 1.0), pbr.roughness_factor().clamp(0.0, 1.0));
    let mut uv = None;
    let mut transforms = Vec::new();
    let mut texture = |info: Option<gltf::texture::Info>,
                       enc: Encoding,
                       what: &str,
                       src: &mut Sources|
     -> Result<Option<Arc<Texture>>> {
        let Some(info) = info else { return Ok(None) };
        if info.tex_coord() != 0 {
            transforms.push(format!(
                "{what} reads TEXCOORD_{} (only TEXCOORD_0 is read; it is used instead)",
                info.tex_coord()
            ));
        }
        let t = info.texture_transform().map(|t| UvTransform {
            offset: Vec2::from_array(t.offset()),
            rotation: t.rotation(),
            scale: Vec2::from_array(t.scale()),
        });
        if uv.is_some() && uv != Some(t) {
            transforms.push(format!("{what} has its own KHR_texture_transform (the first texture's is used)"));
        } else {
            uv = Some(t);
        }
        let image = info.texture().source();
        src.image(image.index(), enc, &format!("the {what} of material `{name}`")).map(Some)
    };
    let base_map = texture(pbr.base_color_texture(), Encoding::Srgb, "base colour texture", src)?;
    let mr_map = texture(pbr.metallic_roughness_texture(), Encoding::Linear, "metallic-roughness texture", src)?;
    let ke_map = texture(m.emissive_texture(), Encoding::Srgb, "emissive texture", src)?;
    let cut = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => None,
        gltf::material::AlphaMode::Mask => Some(AlphaMode::Cutoff(m.alpha_cutoff().unwrap_or(0.5))),
        gltf::material::AlphaMode::Blend => Some(AlphaMode::Coverage),
    };
    let alpha_map = match cut {
        Some(_) => texture(pbr.base_color_texture(), Encoding::Alpha, "base colour texture's alpha", src)?,
        None => None,
    };
    for w in transforms {
        warn(w);
    }
    let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor());
    let ior = m.ior().filter(|i| i.is_finite() && *i >= 1.0).unwrap_or(1.5);
    let alpha = Alpha::ggx(alpha_of(roughness));
    let mut maps = Maps::default();
    let mut interior = Vec3::ZERO;
    let bsdf = if transmission >= 0.5 {
        // The spec tints what is transmitted by the base colour (a texture by its mean here).
        let tint = Tint {
            reflect: Vec3::ONE,
            transmit: match &base_map {
                Some(t) => {
                    warn("its base colour texture tints the transmission by its mean".into());
                    base * t.mean().min(Vec3::ONE)
                }
                None => base,
            },
        };
        // The spec's rule: without KHR_materials_volume (or with a zero thickness) the surface
        // is thin-walled — light passes through unbent — and with it the boundary of a solid,
        // whose attenuation colour c is what remains after `attenuationDistance` d inside:
        // σ_a = −ln(c)/d per channel.
        let solid = m.volume().is_some_and(|v| v.thickness_factor() > 0.0);
        if let Some(v) = m.volume().filter(|v| solid && v.attenuation_distance().is_finite()) {
            let (c, d) = (Vec3::from_array(v.attenuation_color()), v.attenuation_distance());
            if d > 0.0 && c.is_finite() {
                interior = -c.clamp(Vec3::splat(1e-6), Vec3::ONE).ln() / d;
            } else {
                warn(format!(
                    "KHR_materials_volume attenuation (distance {d}, colour {c}) is not valid: the glass is clear"
                ));
            }
        }
        match (roughness < SMOOTH, solid) {
            (true, true) => Bsdf::Glass { ior, tint },
            (true, false) => Bsdf::ThinGlass { ior, tint, passed: false },
            (false, solid) => {
                if !solid {
                    warn("rough thin-walled transmission is rendered as a solid rough dielectric".into());
                }
                Bsdf::RoughDielectric { ior, alpha, tint }
            }
        }
    } else {
        if transmission > 0.0 {
            warn(format!("transmission {transmission} (below ½) is rendered opaque"));
        }
        if let Some(t) = &mr_map {
            maps.roughness = Some(derived(t, Vec3::splat(roughness), Some(1)));
            maps.metallic = Some(derived(t, Vec3::splat(metallic), Some(2)));
            maps.kd = base_map.as_ref().map(|t| derived(t, base, None));
            // One photon class for the material (metal parts at least PHOTON_SPECULAR_ALPHA).
            Bsdf::rough_plastic(base, 1.5, alpha.with_width(alpha.width().max(PHOTON_SPECULAR_ALPHA)))
        } else if metallic >= 0.5 {
            maps.ks = base_map.as_ref().map(|t| derived(t, base, None));
            if roughness < SMOOTH {
                Bsdf::Mirror { ks: base, eta_k: None }
            } else {
                Bsdf::RoughConductor { ks: base, alpha, eta_k: None }
            }
        } else {
            if metallic > 0.0 {
                warn(format!("metallic {metallic} (below ½) is rendered as a dielectric"));
            }
            maps.kd = base_map.as_ref().map(|t| derived(t, base, None));
            if roughness >= DIFFUSE {
                Bsdf::Lambert { kd: base }
            } else {
                Bsdf::rough_plastic(base, 1.5, alpha)
            }
        }
    };
    let emission =
        Vec3::from_array(m.emissive_factor()).max(Vec3::ZERO) * m.emissive_strength().unwrap_or(1.0).max(0.0);
    if emission.max_element() > 0.0 {
        maps.ke = ke_map;
    }
    // The normal texture, in the frame of the mesh's normal and its texture's u direction
    // (with the handedness of its texture coordinates, as glTF's bitangent has it); read with
    // TEXCOORD_0 and the first texture's transform, as the others.
    let normal_map = match m.normal_texture() {
        Some(nt) => {
            if nt.tex_coord() != 0 {
                warn(format!(
                    "its normal texture reads TEXCOORD_{} (only TEXCOORD_0 is read; it is used instead)",
                    nt.tex_coord()
                ));
            }
            let what = format!("the normal texture of material `{name}`");
            let texture = src.image(nt.texture().source().index(), Encoding::Linear, &what)?;
            Some(NormalMap { texture, relief: Relief::Normals, scale: nt.scale(), handed: true })
        }
        None => None,
    };
    if m.occlusion_texture().is_some() {
        warn("its occlusion texture is ignored (a renderer computes occlusion; it is for rasterisers)".into());
    }
    // An image without alpha is opaque: no texture to look up.
    let alpha_map = alpha_map.filter(|t| t.texels.iter().any(|a| a.x < 1.0));
    let opacity = cut
        .map(|mode| Opacity { texture: alpha_map, factor: base_alpha.clamp(0.0, 1.0), mode })
        .filter(|o| !o.is_opaque());
    let emission = if emission.is_finite() { emission } else { Vec3::ZERO };
    Ok(Converted {
        material: Material {
            name: name.to_string(),
            bsdf,
            emission,
            maps,
            interior,
            interior_scattering: None,
            normal_map,
            opacity,
        },
        uv: uv.flatten(),
    })
}
