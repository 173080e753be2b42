//! Image textures: a grid of linear RGB texels, looked up bilinearly with wrap at texture
//! coordinates (u, v) ∈ [0, 1)², v up as in OBJ (the image's first row is v = 1).
//!
//! Texel (i, j) — column i, row j from the top — has its centre at
//! u = (i + ½)/w, v = 1 − (j + ½)/h, where the lookup returns it exactly; between centres it
//! blends the four nearest texels, and coordinates outside [0, 1) wrap (repeat). Colour maps are
//! decoded from sRGB when loaded ([`srgb_to_linear`]); data maps (roughness, metalness) and HDR
//! images are stored as read.

use glam::{Vec2, Vec3};
use std::path::{Path, PathBuf};

/// How the numbers of an 8- or 16-bit image are turned into linear values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Encoding {
    /// A colour: the sRGB transfer curve is undone (`map_Kd`, `map_Ks`, `map_Ke`).
    Srgb,
    /// A number: taken as it is (`map_Pr`, `map_Pm`; every EXR).
    Linear,
    /// An alpha channel, taken as it is in every channel; 1 where the image has none (glTF's
    /// base colour alpha).
    Alpha,
    /// An opacity: the alpha channel where the image has one, else its grey level (the
    /// luminance of an RGB image), taken as it is (MTL `map_d`).
    Opacity,
}

/// An RGB image in linear values, ready for lookups.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// The file it was read from (for messages and the scene hash).
    pub path: PathBuf,
    /// Width in texels (≥ 1).
    pub width: u32,
    /// Height in texels (≥ 1).
    pub height: u32,
    /// Texels, rows from the top, `width` per row.
    pub texels: Vec<Vec3>,
}

/// The luminance (CIE Y) of linear RGB with Mitsuba 3's weights: what a grey reading of a
/// colour texture takes (a bump map's heights, an opacity mask, an RGB image's grey level).
#[must_use]
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.212_671, 0.715_160, 0.072_169))
}

/// The sRGB transfer curve undone (IEC 61966-2-1): an encoded value in [0, 1] to linear.
#[must_use]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl Texture {
    /// A texture of `width × height` texels (rows from the top). `None` when the sizes do not
    /// match or either is zero.
    #[must_use]
    pub fn new(path: &Path, width: u32, height: u32, texels: Vec<Vec3>) -> Option<Texture> {
        let n = (width as usize).checked_mul(height as usize)?;
        (n > 0 && texels.len() == n).then(|| Texture { path: path.to_path_buf(), width, height, texels })
    }

    /// The texel in column `i`, row `j` (from the top), both wrapped.
    #[inline]
    fn texel(&self, i: i64, j: i64) -> Vec3 {
        let i = i.rem_euclid(i64::from(self.width)) as usize;
        let j = j.rem_euclid(i64::from(self.height)) as usize;
        self.texels[j * self.width as usize + i]
    }

    /// The cell of texel centres around `uv` (wrapping outside [0, 1)): its first texel's column
    /// and row and the fractions across it; `None` at a non-finite coordinate.
    #[inline]
    fn cell(&self, uv: Vec2) -> Option<(i64, i64, f32, f32)> {
        // Continuous texel coordinates whose integers are texel centres.
        let x = uv.x.fract() * self.width as f32 - 0.5;
        let y = (1.0 - uv.y.fract()) * self.height as f32 - 0.5;
        if !(x.is_finite() && y.is_finite()) {
            return None;
        }
        let (x0, y0) = (x.floor(), y.floor());
        Some((x0 as i64, y0 as i64, x - x0, y - y0))
    }

    /// The bilinear value at `uv`, wrapping outside [0, 1). A non-finite coordinate reads
    /// texel (0, 0) rather than NaN.
    #[must_use]
    pub fn lookup(&self, uv: Vec2) -> Vec3 {
        let Some((i, j, fx, fy)) = self.cell(uv) else { return self.texels[0] };
        let top = self.texel(i, j) * (1.0 - fx) + self.texel(i + 1, j) * fx;
        let bottom = self.texel(i, j + 1) * (1.0 - fx) + self.texel(i + 1, j + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The derivatives (∂/∂u, ∂/∂v) at `uv` of the bilinear value [`Texture::lookup`] returns:
    /// constant across each cell between four texel centres (zero at a non-finite coordinate).
    /// Rows run down the image as v falls, so ∂/∂v is the row difference times −height.
    #[must_use]
    pub fn gradient(&self, uv: Vec2) -> (Vec3, Vec3) {
        let Some((i, j, fx, fy)) = self.cell(uv) else { return (Vec3::ZERO, Vec3::ZERO) };
        let (a, b, c, d) = (self.texel(i, j), self.texel(i + 1, j), self.texel(i, j + 1), self.texel(i + 1, j + 1));
        let dx = (b - a) * (1.0 - fy) + (d - c) * fy;
        let dy = (c - a) * (1.0 - fx) + (d - b) * fx;
        (dx * self.width as f32, dy * -(self.height as f32))
    }

    /// The mean of every texel: what the texture reflects on average.
    #[must_use]
    pub fn mean(&self) -> Vec3 {
        let sum: glam::DVec3 = self.texels.iter().map(|t| t.as_dvec3()).sum();
        (sum / self.texels.len() as f64).as_vec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4×2 texture whose texel (i, j) is (i, j, 1).
    fn ramp() -> Texture {
        let texels = (0..2).flat_map(|j| (0..4).map(move |i| Vec3::new(i as f32, j as f32, 1.0))).collect();
        Texture::new(Path::new("t.png"), 4, 2, texels).unwrap()
    }

    fn centre(t: &Texture, i: u32, j: u32) -> Vec2 {
        Vec2::new((i as f32 + 0.5) / t.width as f32, 1.0 - (j as f32 + 0.5) / t.height as f32)
    }

    #[test]
    fn the_gradient_is_the_bilinear_lookups_slope() {
        // Central differences of `lookup` inside a cell against `gradient` (the ramp rises by 1
        // per texel in x, so by 4 per unit of u; by 1 per row down, so by −2 per unit of v).
        let t = ramp();
        for uv in [Vec2::new(0.3, 0.4), Vec2::new(0.55, 0.35), Vec2::new(0.2, 0.6)] {
            let (du, dv) = t.gradient(uv);
            let h = 1e-3;
            let cu = (t.lookup(uv + Vec2::new(h, 0.0)) - t.lookup(uv - Vec2::new(h, 0.0))) / (2.0 * h);
            let cv = (t.lookup(uv + Vec2::new(0.0, h)) - t.lookup(uv - Vec2::new(0.0, h))) / (2.0 * h);
            assert!(
                (du - cu).abs().max_element() < 1e-2 && (dv - cv).abs().max_element() < 1e-2,
                "{uv}: {du} {dv} against {cu} {cv}"
            );
        }
        let (du, dv) = t.gradient(Vec2::new(0.3, 0.4));
        assert!((du.x - 4.0).abs() < 1e-4 && (dv.y + 2.0).abs() < 1e-4, "{du} {dv}");
    }

    #[test]
    fn texel_centres_are_exact() {
        let t = ramp();
        for j in 0..2 {
            for i in 0..4 {
                assert_eq!(t.lookup(centre(&t, i, j)), Vec3::new(i as f32, j as f32, 1.0), "texel ({i}, {j})");
            }
        }
    }

    #[test]
    fn between_centres_is_bilinear_and_wraps() {
        let t = ramp();
        // Halfway between texels 1 and 2 of row 0: the mean of the two.
        let uv = Vec2::new(0.5, 0.75);
        assert_eq!(t.lookup(uv), Vec3::new(1.5, 0.0, 1.0));
        // A quarter of the way from (1, 0) to (2, 1) in both directions.
        let uv = Vec2::new((1.5 + 0.25) / 4.0, 1.0 - (0.5 + 0.25) / 2.0);
        let v = t.lookup(uv);
        assert!((v - Vec3::new(1.25, 0.25, 1.0)).abs().max_element() < 1e-6, "{v}");
        // u = 0 lies halfway between the last column and the first: wrap.
        assert_eq!(t.lookup(Vec2::new(0.0, 0.75)), Vec3::new(1.5, 0.0, 1.0));
        // Coordinates outside [0, 1) repeat.
        assert_eq!(t.lookup(Vec2::new(2.0 + 0.5, 0.75 - 3.0)), t.lookup(Vec2::new(0.5, 0.75)));
        assert_eq!(t.lookup(Vec2::new(-0.875, 0.75)), t.lookup(Vec2::new(0.125, 0.75)));
        assert_eq!(t.lookup(Vec2::new(f32::NAN, 0.5)), Vec3::new(0.0, 0.0, 1.0));
    }

    #[test]
    fn srgb_known_values() {
        // IEC 61966-2-1: 0 and 1 are fixed; 128/255 is 0.21586; below the knee the curve is linear.
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(128.0 / 255.0) - 0.215_861).abs() < 1e-5);
        assert!((srgb_to_linear(10.0 / 255.0) - 0.003_035).abs() < 1e-6);
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
    }

    #[test]
    fn sizes_must_match() {
        assert!(Texture::new(Path::new("t"), 0, 4, vec![]).is_none());
        assert!(Texture::new(Path::new("t"), 2, 2, vec![Vec3::ZERO; 3]).is_none());
    }
}
