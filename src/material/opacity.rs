//! Alpha cut-outs: where a surface is there at all. Mitsuba's `mask` (opacity texture or
//! constant), glTF's `alphaMode` `MASK` (opaque where α ≥ `alphaCutoff`) and `BLEND` (α read as
//! coverage), MTL's `map_d` and `d`. Reads a material's opacity at texture coordinates; writes
//! whether a ray passes ([`Opacity::passes`], asked by every traversal kernel through
//! [`crate::geometry::cut_out`]).
//!
//! Coverage is stochastic: a texel of opacity α passes a ray with probability 1 − α, decided by
//! the ray's own hash ([`crate::geometry::cut_out::coverage_sample`]), so in expectation a
//! shadow ray sees 1 − α of the light behind (Mitsuba's `volpath` multiplies by the mask's null
//! transmission 1 − α; its plain `path` lets no shadow ray through) and a photon or camera ray
//! goes on with that probability, meeting the surface otherwise — the same expectation, without
//! a weight that could exceed one.

use crate::texture::Texture;
use glam::Vec2;
use std::sync::Arc;

/// How opacity becomes presence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// Opaque where the opacity is at least the cutoff, absent elsewhere (glTF `MASK`).
    Cutoff(f32),
    /// Present with probability equal to the opacity (Mitsuba's `mask`, glTF `BLEND`, MTL).
    Coverage,
}

/// A material's opacity: a constant, or a constant times a texture's first channel (readers put
/// the opacity in every channel).
#[derive(Clone, Debug, PartialEq)]
pub struct Opacity {
    /// Opacity texture (linear, in [0, 1]), or `None` for the constant alone.
    pub texture: Option<Arc<Texture>>,
    /// The constant, or the texture's factor.
    pub factor: f32,
    /// How it is applied.
    pub mode: AlphaMode,
}

impl Opacity {
    /// A constant opacity read as coverage.
    #[must_use]
    pub fn constant(alpha: f32) -> Opacity {
        Opacity { texture: None, factor: alpha, mode: AlphaMode::Coverage }
    }

    /// The opacity at texture coordinates `uv` (clamped to [0, 1]).
    #[must_use]
    pub fn alpha(&self, uv: Vec2) -> f32 {
        let t = self.texture.as_ref().map_or(1.0, |t| t.lookup(uv).x);
        (self.factor * t).clamp(0.0, 1.0)
    }

    /// Whether a ray passes the surface at `uv`; `sample` draws the ray's number in [0, 1) for
    /// partial coverage (called only there).
    #[must_use]
    pub fn passes(&self, uv: Vec2, sample: impl FnOnce() -> f32) -> bool {
        let alpha = self.alpha(uv);
        match self.mode {
            AlphaMode::Cutoff(c) => alpha < c,
            AlphaMode::Coverage => alpha < 1.0 && (alpha <= 0.0 || sample() >= alpha),
        }
    }

    /// The share of rays the surface stops at `uv`: the opacity under coverage, 0 or 1 under a
    /// cutoff (what a density estimate weighs the surface's presence by).
    #[must_use]
    pub fn presence(&self, uv: Vec2) -> f32 {
        let alpha = self.alpha(uv);
        match self.mode {
            AlphaMode::Cutoff(c) => f32::from(u8::from(alpha >= c)),
            AlphaMode::Coverage => alpha,
        }
    }

    /// True when it lets nothing through anywhere (a constant opacity of one, or a cutoff the
    /// constant meets without a texture): then it is dropped at load.
    #[must_use]
    pub fn is_opaque(&self) -> bool {
        self.texture.is_none()
            && match self.mode {
                AlphaMode::Cutoff(c) => self.factor >= c,
                AlphaMode::Coverage => self.factor >= 1.0,
            }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use std::path::Path;

    fn ramp() -> Arc<Texture> {
        // Two texels: opacity 0 on the left half, 1 on the right (texel centres at u = ¼, ¾).
        Arc::new(Texture::new(Path::new("a.png"), 2, 1, vec![Vec3::ZERO, Vec3::ONE]).unwrap())
    }

    #[test]
    fn a_cutoff_passes_below_it_and_stops_at_or_above() {
        let o = Opacity { texture: Some(ramp()), factor: 1.0, mode: AlphaMode::Cutoff(0.5) };
        let never = || panic!("a cutoff draws no sample");
        assert!(o.passes(Vec2::new(0.25, 0.5), never));
        assert!(!o.passes(Vec2::new(0.75, 0.5), never));
        // Halfway between the centres the bilinear opacity is ½: exactly the cutoff, opaque.
        assert!(!o.passes(Vec2::new(0.5, 0.5), never));
    }

    #[test]
    fn coverage_passes_when_the_sample_reaches_the_opacity() {
        let o = Opacity::constant(0.3);
        assert!(o.passes(Vec2::ZERO, || 0.3) && o.passes(Vec2::ZERO, || 0.9));
        assert!(!o.passes(Vec2::ZERO, || 0.29));
        let never = || panic!("no sample at α = 0 or 1");
        assert!(Opacity::constant(0.0).passes(Vec2::ZERO, never));
        assert!(!Opacity::constant(1.0).passes(Vec2::ZERO, never));
        assert!(Opacity::constant(1.0).is_opaque() && !Opacity::constant(0.99).is_opaque());
        let textured = Opacity { texture: Some(ramp()), factor: 1.0, mode: AlphaMode::Coverage };
        assert!(!textured.is_opaque());
    }
}
