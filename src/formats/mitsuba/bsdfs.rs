//! Mitsuba BSDFs and textures onto photonwave's materials.
//!
//! | Mitsuba | photonwave |
//! |---|---|
//! | `diffuse` | Lambertian (`reflectance`, a colour or a texture) |
//! | `twosided` | its inner BSDF (photonwave's opaque materials are two-sided already) |
//! | `dielectric` | smooth glass of index `int_ior` / `ext_ior` (numbers or Mitsuba's names) |
//! | `thindielectric` | a thin sheet: straight through or reflected with the slab's reflectance |
//! | `roughdielectric` | rough dielectric of `distribution` (Beckmann unless `ggx`) and `alpha` |
//! | the three dielectrics' `specular_reflectance`, `specular_transmittance` | scales on what they reflect and transmit ([`Tint`]; a texture as its mean, warned of) |
//! | `conductor`, `roughconductor` | mirror or rough conductor (Beckmann unless `ggx`), the exact Fresnel of `eta`, `k` or the named `material` ([`crate::optics::METALS`]), times `specular_reflectance` |
//! | `plastic`, `roughplastic` | Mitsuba's smooth (a mirror coat) or rough plastic over `diffuse_reflectance`, with `nonlinear` and `specular_reflectance` (a texture as its mean, warned of) |
//! | `phong` | normalised Phong (`diffuse_reflectance`, `specular_reflectance`, `exponent`) |
//! | `normalmap` | its inner BSDF, its texture bending the shading normal ([`NormalMap`], Mitsuba's frame) |
//! | `bumpmap` | its inner BSDF, its `bitmap` (in any `scale` textures) a height field that bends the shading normal ([`Relief::Heights`]) |
//! | `mask` | its inner BSDF, cut out where its `opacity` (0.5 by default; a bitmap's luminance) says: present with probability equal to the opacity ([`Opacity`], coverage) |
//! | `coating`, `roughcoating`, `blendbsdf`, `mixturebsdf` | the (first) inner BSDF, warned of by name |
//! | anything else | grey Lambertian (0.5), warned of with its line |
//!
//! `diffuse`, `roughconductor`, `roughdielectric`, `roughplastic` (GGX and Beckmann) and
//! `plastic` (its base's f and pdf; its coat's sample weight and probability) evaluate as
//! Mitsuba 3 does: `tests/mitsuba_bsdfs.rs` holds them to a table written through Mitsuba's own
//! Python API (`tests/data/mitsuba-bsdfs.py`). Not in it: `phong` (Mitsuba 3 has none), the
//! smooth `dielectric` (delta lobes, no eval or pdf; its Fresnel is the same function;
//! `conductor`'s and `thindielectric`'s directions and weights are in the table as samples).
//!
//! Mitsuba 0.5's Phong and Ashikhmin–Shirley microfacet distributions are rendered as Beckmann
//! of the same α, anisotropic `alpha_u`/`alpha_v` as their mean (hits carry no texture-space
//! tangent to orient them); each is warned of. Textures: `bitmap` (`filename`, sRGB for
//! colours) and `checkerboard` (`color0`, `color1`, drawn into a 256² image), with `uvscale`,
//! `uoffset`, `voffset` (0.5) or a `to_uv` scale and translation (3.x), applied to the shape's
//! texture coordinates.

use super::Ctx;
use crate::error::Result;
use crate::material::{AlphaMode, Bsdf, Maps, Material, NormalMap, Opacity, Relief, Tint};
use crate::microfacet::{Alpha, Distribution, MIN_ALPHA};
use crate::optics::{named_metal, ComplexIor};
use crate::texture::{luminance, Encoding, Texture};
use glam::{Vec2, Vec3};
use roxmltree::Node;
use std::sync::Arc;

/// A texture coordinate scale and offset: uv·scale + offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvMap {
    pub scale: Vec2,
    pub offset: Vec2,
}

/// How deep wrappers (`twosided`, `mask`, …) may nest.
const MAX_NESTING: usize = 16;

/// Mitsuba's named indices of refraction.
const IORS: [(&str, f32); 22] = [
    ("vacuum", 1.0),
    ("helium", 1.00004),
    ("hydrogen", 1.00013),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.333),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("diamond", 2.419),
];

/// A colour property, or a texture in its place, of a BSDF.
pub(super) struct Coloured {
    pub value: Vec3,
    pub map: Option<Arc<Texture>>,
    pub uv: Option<UvMap>,
}

impl Ctx<'_> {
    /// An index of refraction property: a number or one of Mitsuba's names.
    /// `int_ior` / `ext_ior` of `node`, refused unless a finite positive ratio.
    fn ior_ratio(&self, node: Node, int_default: f32) -> Result<f32> {
        let ratio = self.ior(node, "int_ior", int_default)? / self.ior(node, "ext_ior", 1.000277)?;
        if ratio.is_finite() && ratio > 0.0 {
            Ok(ratio)
        } else {
            Err(self.r.error(node, format!("int_ior / ext_ior = {ratio} is not a finite positive ratio")))
        }
    }

    fn ior(&self, node: Node, name: &str, default: f32) -> Result<f32> {
        let Some(p) = self.r.prop(node, name) else { return Ok(default) };
        let v = self.r.attr(p, "value")?.unwrap_or_default();
        if let Ok(x) = v.trim().parse::<f32>() {
            return if x.is_finite() && x > 0.0 {
                Ok(x)
            } else {
                Err(self.r.error(p, format!("`{name}` must be positive")))
            };
        }
        IORS.iter().find(|(n, _)| n.eq_ignore_ascii_case(v.trim())).map(|(_, x)| *x).ok_or_else(|| {
            self.r.error(
                p,
                format!(
                    "`{v}` is not an index of refraction Mitsuba names (e.g. {})",
                    IORS.map(|x| x.0)[..6].join(", ")
                ),
            )
        })
    }

    /// The `raw` flag of the texture property `name` of `node` (inline or by `<ref>`), `default`
    /// where it says nothing or there is no texture.
    fn raw(&mut self, node: Node, name: &str, default: bool) -> Result<bool> {
        let Some(t) = self.r.prop(node, name) else { return Ok(default) };
        let t = if t.tag_name().name() == "ref" { self.referenced(t)? } else { t };
        self.r.boolean(t, "raw", default)
    }

    /// A BSDF's scale `name` (`specular_reflectance`, `specular_transmittance`; 1 by default), a
    /// texture read as its mean (warned of), at most 1 per channel.
    fn scale_colour(&mut self, node: Node, kind: &str, name: &str) -> Result<Vec3> {
        let s = self.coloured(node, name, Vec3::ONE, Encoding::Srgb)?;
        Ok(match &s.map {
            Some(t) => {
                self.warn(node, format!("{kind}: a textured `{name}` is rendered as its mean"));
                t.mean().min(Vec3::ONE)
            }
            None => s.value.min(Vec3::ONE),
        })
    }

    /// A colour property of `node` (a colour element, a nested texture or a `ref` to one), or
    /// `default`.
    pub(super) fn coloured(&mut self, node: Node, name: &str, default: Vec3, encoding: Encoding) -> Result<Coloured> {
        let plain = |value| Coloured { value, map: None, uv: None };
        let Some(p) = self.r.prop(node, name) else { return Ok(plain(default)) };
        let p = match p.tag_name().name() {
            "ref" => self.referenced(p)?,
            _ => p,
        };
        if p.tag_name().name() != "texture" {
            return Ok(plain(self.r.colour_of(p)?));
        }
        let uv = self.uv_map(p)?;
        let kind = p.attribute("type").unwrap_or("");
        let map = match kind {
            "bitmap" => {
                let file =
                    self.r.string(p, "filename")?.ok_or_else(|| self.r.error(p, "a bitmap needs a `filename`"))?;
                self.image(p, &file, encoding)?
            }
            "checkerboard" => {
                let (c0, c1) = (self.r.prop(p, "color0"), self.r.prop(p, "color1"));
                let c0 = c0.map_or(Ok(Vec3::splat(0.4)), |c| self.r.colour_of(c))?;
                let c1 = c1.map_or(Ok(Vec3::splat(0.2)), |c| self.r.colour_of(c))?;
                const N: u32 = 256;
                let texels = (0..N * N).map(|k| if ((k % N) < N / 2) == ((k / N) < N / 2) { c0 } else { c1 }).collect();
                Arc::new(Texture::new(self.r.path, N, N, texels).expect("a 256² checkerboard"))
            }
            other => {
                self.warn(p, format!("texture `{other}` is not read: its mean colour 0.5 is used"));
                return Ok(plain(Vec3::splat(0.5)));
            }
        };
        Ok(Coloured { value: Vec3::ONE, map: Some(map), uv })
    }

    /// A texture's coordinate scale and offset, `None` for the identity.
    fn uv_map(&self, t: Node) -> Result<Option<UvMap>> {
        let us = self.r.float(t, "uscale", 1.0)? * self.r.float(t, "uvscale", 1.0)?;
        let vs = self.r.float(t, "vscale", 1.0)? * self.r.float(t, "uvscale", 1.0)?;
        let offset = Vec2::new(self.r.float(t, "uoffset", 0.0)?, self.r.float(t, "voffset", 0.0)?);
        let to_uv = self.r.transform(t, "to_uv")?;
        let scale = Vec2::new(us * to_uv.matrix3.x_axis.x, vs * to_uv.matrix3.y_axis.y);
        let offset = offset + Vec2::new(to_uv.translation.x, to_uv.translation.y);
        let map = UvMap { scale, offset };
        Ok((map != UvMap { scale: Vec2::ONE, offset: Vec2::ZERO }).then_some(map))
    }

    /// The microfacets of `distribution` (Beckmann when absent, as in Mitsuba) and `alpha` (or
    /// `alpha_u`/`alpha_v`, rendered as their mean and warned of); Mitsuba 0.5's `phong` and `as`
    /// are rendered as Beckmann and warned of, any other name is an error.
    fn alpha(&mut self, node: Node, what: &str) -> Result<Alpha> {
        let dist = self.r.string(node, "distribution")?.unwrap_or_else(|| "beckmann".into());
        let distribution = match dist.as_str() {
            "ggx" => Distribution::Ggx,
            "beckmann" => Distribution::Beckmann,
            "phong" | "as" => {
                self.warn(node, format!("{what}: the {dist} distribution is rendered as Beckmann of the same α"));
                Distribution::Beckmann
            }
            other => {
                return Err(self
                    .r
                    .error(node, format!("{what}: unknown microfacet distribution `{other}` (known: beckmann, ggx)")))
            }
        };
        let a = if self.r.prop(node, "alpha_u").is_some() {
            let (u, v) = (self.r.float(node, "alpha_u", 0.1)?, self.r.float(node, "alpha_v", 0.1)?);
            if u != v {
                self.warn(
                    node,
                    format!("{what}: anisotropic roughness ({u}, {v}) is rendered isotropic, α = {}", 0.5 * (u + v)),
                );
            }
            0.5 * (u + v)
        } else {
            self.r.float(node, "alpha", 0.1)?
        };
        Ok(Alpha::new(distribution, a.clamp(MIN_ALPHA, 1.0)))
    }

    /// A `bumpmap`'s height field and gradient scale: its `scale` times those of any `scale`
    /// textures (Mitsuba 0.5's way) around a `bitmap`, read as data; `None` (warned of) for
    /// another texture.
    fn height_map(&mut self, node: Node) -> Result<Option<(Arc<Texture>, f32)>> {
        let mut scale = self.r.float(node, "scale", 1.0)?;
        let doc = self.r.doc;
        let mut t = self.first_texture(node)?;
        for _ in 0..MAX_NESTING {
            let Some(tex) = t.and_then(|id| doc.get_node(id)) else { return Ok(None) };
            match tex.attribute("type").unwrap_or("") {
                "scale" => {
                    scale *= self.r.float(tex, "scale", 1.0)?;
                    t = self.first_texture(tex)?;
                }
                "bitmap" => {
                    self.r.boolean(tex, "raw", true)?;
                    let file = self
                        .r
                        .string(tex, "filename")?
                        .ok_or_else(|| self.r.error(tex, "a bitmap needs a `filename`"))?;
                    return Ok(Some((self.image(tex, &file, Encoding::Linear)?, scale)));
                }
                other => {
                    self.warn(tex, format!("a `{other}` height field is not read (a `bitmap` is)"));
                    return Ok(None);
                }
            }
        }
        Ok(None)
    }

    /// The first `<texture>` child of `node`, or the texture its first `<ref>` to one names.
    fn first_texture(&self, node: Node) -> Result<Option<roxmltree::NodeId>> {
        for c in node.children().filter(Node::is_element) {
            match c.tag_name().name() {
                "texture" => return Ok(Some(c.id())),
                "ref" => {
                    let r = self.referenced(c)?;
                    if r.tag_name().name() == "texture" {
                        return Ok(Some(r.id()));
                    }
                }
                _ => {}
            }
        }
        Ok(None)
    }

    /// The material of `<bsdf>` element `node`, called `name`, and the texture coordinate map its
    /// textures want.
    pub(super) fn bsdf(&mut self, node: Node, name: &str) -> Result<(Material, Option<UvMap>)> {
        let kind = node.attribute("type").unwrap_or("");
        if self.depth > MAX_NESTING {
            return Err(self.r.error(
                node,
                format!("BSDFs nest more than {MAX_NESTING} deep (a <ref> that names its own wrapper?)"),
            ));
        }
        let inner = node.children().find(|c| c.is_element() && matches!(c.tag_name().name(), "bsdf" | "ref"));
        let wrapper = |me: &mut Self, note: Option<&str>| -> Result<(Material, Option<UvMap>)> {
            if let Some(note) = note {
                me.warn(node, format!("bsdf `{kind}`: {note}"));
            }
            match inner {
                Some(i) => {
                    let i = if i.tag_name().name() == "ref" { me.referenced(i)? } else { i };
                    me.depth += 1;
                    let inner = me.bsdf(i, name);
                    me.depth -= 1;
                    inner
                }
                None => Err(me.r.error(node, format!("bsdf `{kind}` has no inner <bsdf>"))),
            }
        };
        let (bsdf, maps, uv) = match kind {
            "twosided" => return wrapper(self, None),
            "bumpmap" => {
                let heights = self.height_map(node)?;
                let (mut material, uv) = wrapper(self, None)?;
                match heights {
                    Some((texture, scale)) => {
                        material.normal_map =
                            Some(NormalMap { texture, relief: Relief::Heights, scale, handed: false });
                    }
                    None => self.warn(node, "bsdf `bumpmap` without a bitmap: the shape's normals are used".into()),
                }
                return Ok((material, uv));
            }
            "normalmap" => {
                // Its texture is data (Mitsuba reads it `raw`), a normal in the shading frame.
                self.raw(node, "normalmap", true)?;
                let map = self.coloured(node, "normalmap", Vec3::new(0.5, 0.5, 1.0), Encoding::Linear)?;
                let (mut material, uv) = wrapper(self, None)?;
                match map.map {
                    Some(texture) => {
                        material.normal_map =
                            Some(NormalMap { texture, relief: Relief::Normals, scale: 1.0, handed: false })
                    }
                    None => self.warn(node, "bsdf `normalmap` without a texture: the shape's normals are used".into()),
                }
                if uv.is_some() && map.uv.is_some() && uv != map.uv {
                    self.warn(
                        node,
                        "the normal map's texture transform differs from its BSDF's: the BSDF's is used".into(),
                    );
                }
                return Ok((material, uv.or(map.uv)));
            }
            "mask" => {
                // A scalar texture (Mitsuba's default 0.5): a bitmap's luminance, decoded from
                // sRGB unless `raw`, as Mitsuba's `eval_1` reads it.
                let encoding = if self.raw(node, "opacity", false)? { Encoding::Linear } else { Encoding::Srgb };
                let c = self.coloured(node, "opacity", Vec3::splat(0.5), encoding)?;
                let (mut material, uv) = wrapper(self, None)?;
                let texture = c.map.map(|t| {
                    let texels = t.texels.iter().map(|&x| Vec3::splat(luminance(x))).collect();
                    Arc::new(Texture { texels, ..(*t).clone() })
                });
                let opacity = Opacity { texture, factor: luminance(c.value), mode: AlphaMode::Coverage };
                material.opacity = (!opacity.is_opaque()).then_some(opacity);
                if uv.is_some() && c.uv.is_some() && uv != c.uv {
                    self.warn(
                        node,
                        "the opacity's texture transform differs from its BSDF's: the BSDF's is used".into(),
                    );
                }
                return Ok((material, uv.or(c.uv)));
            }
            "coating" | "roughcoating" => return wrapper(self, Some("the coating is not rendered: its base alone is")),
            "blendbsdf" | "mixturebsdf" => {
                return wrapper(self, Some("only the first of the blended BSDFs is rendered"))
            }
            "diffuse" => {
                let c = self.coloured(node, "reflectance", Vec3::splat(0.5), Encoding::Srgb)?;
                (Bsdf::Lambert { kd: c.value.min(Vec3::ONE) }, Maps { kd: c.map, ..Maps::default() }, c.uv)
            }
            "dielectric" | "thindielectric" | "roughdielectric" => {
                let ior = self.ior_ratio(node, 1.5046)?;
                let tint = Tint {
                    reflect: self.scale_colour(node, kind, "specular_reflectance")?,
                    transmit: self.scale_colour(node, kind, "specular_transmittance")?,
                };
                let bsdf = match kind {
                    "roughdielectric" => Bsdf::RoughDielectric { ior, alpha: self.alpha(node, kind)?, tint },
                    "thindielectric" => Bsdf::ThinGlass { ior, tint, passed: false },
                    _ => Bsdf::Glass { ior, tint },
                };
                (bsdf, Maps::default(), None)
            }
            "conductor" | "roughconductor" => {
                let metal = self.r.string(node, "material")?.unwrap_or_else(|| {
                    if self.version < 2 {
                        "Cu".into()
                    } else {
                        "none".into()
                    }
                });
                let eta_k = match (self.r.prop(node, "eta"), self.r.prop(node, "k")) {
                    (Some(e), Some(k)) => ComplexIor { eta: self.r.colour_of(e)?, k: self.r.colour_of(k)? },
                    _ => named_metal(&metal).ok_or_else(|| {
                        let known: Vec<&str> = crate::optics::METALS.iter().map(|m| m.0).collect();
                        self.r.error(node, format!("metal `{metal}` is not known (known: {}, none)", known.join(", ")))
                    })?,
                };
                let s = self.coloured(node, "specular_reflectance", Vec3::ONE, Encoding::Srgb)?;
                // Mitsuba's exact conductor Fresnel, scaled by `specular_reflectance`.
                let (ks, eta_k) = (s.value.min(Vec3::ONE), Some(eta_k));
                let maps = Maps { ks: s.map, ..Maps::default() };
                let bsdf = if kind == "conductor" {
                    Bsdf::Mirror { ks, eta_k }
                } else {
                    Bsdf::RoughConductor { ks, alpha: self.alpha(node, kind)?, eta_k }
                };
                (bsdf, maps, s.uv)
            }
            "plastic" | "roughplastic" => {
                let ior = self.ior_ratio(node, 1.49)?;
                let c = self.coloured(node, "diffuse_reflectance", Vec3::splat(0.5), Encoding::Srgb)?;
                let alpha = if kind == "plastic" { None } else { Some(self.alpha(node, kind)?) };
                let nonlinear = self.r.boolean(node, "nonlinear", false)?;
                let ks = self.scale_colour(node, kind, "specular_reflectance")?;
                let kd = c.value.min(Vec3::ONE);
                let bsdf = match alpha {
                    Some(alpha) => Bsdf::rough_plastic(kd, ior, alpha),
                    None => Bsdf::Plastic { kd, ks: Vec3::ONE, eta: ior, nonlinear },
                }
                .with_nonlinear(nonlinear)
                .with_coat_scale(ks.min(Vec3::ONE));
                (bsdf, Maps { kd: c.map, ..Maps::default() }, c.uv)
            }
            "phong" => {
                let kd = self.coloured(node, "diffuse_reflectance", Vec3::splat(0.5), Encoding::Srgb)?;
                let ks = self.coloured(node, "specular_reflectance", Vec3::splat(0.2), Encoding::Srgb)?;
                let exponent = self.r.float(node, "exponent", 30.0)?.max(0.0);
                let sum = (kd.value + ks.value).max_element().max(1.0);
                let bsdf = Bsdf::Glossy { kd: kd.value / sum, ks: ks.value / sum, exponent };
                (bsdf, Maps { kd: kd.map, ks: ks.map, ..Maps::default() }, kd.uv.or(ks.uv))
            }
            other => {
                self.warn(node, format!("bsdf `{other}` is not read: it is rendered grey Lambertian (0.5)"));
                (Bsdf::Lambert { kd: Vec3::splat(0.5) }, Maps::default(), None)
            }
        };
        Ok((
            Material {
                name: name.to_string(),
                bsdf,
                emission: Vec3::ZERO,
                maps,
                interior: Vec3::ZERO,
                interior_scattering: None,
                normal_map: None,
                opacity: None,
            },
            uv,
        ))
    }
}
