//! Mitsuba media on shapes: a `homogeneous` medium a shape names as its `interior` (a
//! `<medium name="interior">` inside it, or a `<ref name="interior" id="…"/>` to a top-level
//! one) makes the shape's dielectric enclose an absorbing interior: light crossing a length d of
//! it keeps exp(−σ_t·d) (Beer–Lambert, [`crate::material::Material::interior`]).
//!
//! σ_t is Mitsuba 3's `sigma_t` (1 by default) or 0.5's `sigmaT`, or `sigmaA` + `sigmaS`, times
//! `scale`. A medium that scatters (`albedo` or `sigmaS` above 0) is kept whole as well
//! ([`crate::material::Material::interior_scattering`], with its `hg` phase function's `g` or an
//! isotropic one): the path tracer scatters in it; the photon-mapping engines attenuate by the
//! whole σ_t and scatter nothing back in, warned of. Exterior media, other medium types, an interior behind a BSDF that is
//! not a solid dielectric and media no shape encloses are warned of by line and left out.
//!
//! Reads `<medium>` elements and `<ref>`s to them; writes the σ_t of a shape's interior.

use super::Ctx;
use crate::error::Result;
use crate::material::Bsdf;
use crate::medium::Medium;
use glam::Vec3;
use roxmltree::Node;

impl<'a> Ctx<'a> {
    /// The medium a shape's child `c` declares or references, and the name it gives it
    /// (`interior`, `exterior`); `None` if `c` is not a medium.
    fn medium_of(&self, c: Node<'a, 'a>) -> Result<Option<(Node<'a, 'a>, String)>> {
        let medium = match c.tag_name().name() {
            "medium" => c,
            "ref" => match self.referenced(c)? {
                m if m.tag_name().name() == "medium" => m,
                _ => return Ok(None),
            },
            _ => return Ok(None),
        };
        Ok(Some((medium, c.attribute("name").unwrap_or("").to_string())))
    }

    /// σ_t of the interior medium of `<shape>` element `shape` whose material is `bsdf`, with
    /// the whole medium when it scatters, or `None` (no interior medium, or one left out and
    /// warned of).
    pub(super) fn interior(&mut self, shape: Node<'a, 'a>, bsdf: &Bsdf) -> Result<Option<(Vec3, Option<Medium>)>> {
        let mut interior = None;
        for c in shape.children().filter(Node::is_element) {
            let Some((medium, name)) = self.medium_of(c)? else { continue };
            self.used_media.insert(medium.id());
            if name == "interior" {
                interior = Some(medium);
            } else {
                self.warn(c, format!("the `{name}` medium is not read (only a shape's `interior` is): it is left out"));
            }
        }
        let Some(medium) = interior else { return Ok(None) };
        let kind = medium.attribute("type").unwrap_or("");
        if kind != "homogeneous" {
            self.warn(medium, format!("medium `{kind}` is not read (only `homogeneous` is): the interior is clear"));
            return Ok(None);
        }
        if !matches!(bsdf, Bsdf::Glass { .. } | Bsdf::RoughDielectric { .. }) {
            self.warn(
                medium,
                "an interior medium is rendered only inside a solid dielectric (`dielectric`, `roughdielectric`); \
                 this shape's BSDF is not one: it is left out"
                    .to_string(),
            );
            return Ok(None);
        }
        if self.r.prop(medium, "material").is_some() {
            self.warn(medium, "a medium's named `material` is not read: give `sigma_t` and `albedo`".to_string());
        }
        let colour = |me: &Self, name: &str, default: Vec3| -> Result<Vec3> {
            me.r.prop(medium, name).map_or(Ok(default), |p| me.r.colour_of(p))
        };
        let (sigma_t, scattering) =
            if self.r.prop(medium, "sigma_a").is_some() || self.r.prop(medium, "sigma_s").is_some() {
                let (a, s) = (colour(self, "sigma_a", Vec3::ZERO)?, colour(self, "sigma_s", Vec3::ZERO)?);
                (a + s, s)
            } else {
                let t = colour(self, "sigma_t", Vec3::ONE)?;
                let albedo = colour(self, "albedo", Vec3::splat(0.75))?.min(Vec3::ONE);
                (t, t * albedo)
            };
        let scale = self.r.float(medium, "scale", 1.0)?;
        if !(scale >= 0.0 && scale.is_finite()) {
            return Err(self
                .r
                .error(medium, format!("the medium's `scale` is {scale}: it must be a finite number ≥ 0")));
        }
        if scattering.max_element() <= 0.0 {
            return Ok(Some((sigma_t * scale, None)));
        }
        self.warn(
            medium,
            format!(
                "the medium scatters (σ_s = {}): the path tracer (`--engine path`) scatters in it; the photon-mapping \
                 engines attenuate by the whole σ_t = {} and do not scatter light back in, so they render it darker",
                scattering * scale,
                sigma_t * scale
            ),
        );
        let g = match medium.children().find(|c| c.is_element() && c.tag_name().name() == "phase") {
            None => 0.0,
            Some(p) => match p.attribute("type").unwrap_or("") {
                "isotropic" => 0.0,
                "hg" => self.r.float(p, "g", 0.8)?,
                other => {
                    self.warn(
                        p,
                        format!("phase function `{other}` is not read (only `hg` and `isotropic`): isotropic"),
                    );
                    0.0
                }
            },
        };
        let whole = Medium::new((sigma_t - scattering) * scale, scattering * scale, g)
            .map_err(|e| self.r.error(medium, format!("the interior medium: {e}")))?;
        Ok(Some((sigma_t * scale, Some(whole))))
    }
}
