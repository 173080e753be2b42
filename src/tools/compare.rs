//! How far an image is from a reference: RMSE, relative MSE and the ratio of means, for the
//! beauty image and for each Jensen term layer present in both files; for the beauty image also
//! the error of its blocks' means and its share of speckled pixels ([`super::local`]).

use crate::error::{Error, Result};
use crate::film::{read_exr, ExrLayers};
use crate::tools::local::{block_errors, box_reduce, speckle_fraction, BlockErrors};
use glam::Vec3;
use serde::Serialize;
use std::path::Path;

/// The relMSE denominator's offset: (a − b)² / (b² + ε), so that black reference pixels do not
/// dominate.
pub const REL_EPSILON: f64 = 0.01;

/// Error of one layer against its reference, over every pixel and channel.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LayerError {
    /// Layer name: `beauty`, or a term (`direct`, `caustic`, …).
    pub layer: String,
    /// √(mean (a − b)²).
    pub rmse: f64,
    /// mean (a − b)² / (b² + [`REL_EPSILON`]).
    pub rel_mse: f64,
    /// mean(a) / mean(b); `None` when the reference's mean is 0.
    pub mean_ratio: Option<f64>,
    /// mean(a).
    pub mean: f64,
    /// mean(b), the reference's.
    pub reference_mean: f64,
}

/// `a` against the reference `b` (same length, finite values).
#[must_use]
pub fn layer_error(layer: &str, a: &[Vec3], b: &[Vec3]) -> LayerError {
    let (mut se, mut rel, mut sa, mut sb) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (x, y) in a.iter().zip(b) {
        for c in 0..3 {
            let (x, y) = (f64::from(x[c]), f64::from(y[c]));
            let d2 = (x - y) * (x - y);
            se += d2;
            rel += d2 / (y * y + REL_EPSILON);
            sa += x;
            sb += y;
        }
    }
    let n = (3 * a.len().min(b.len())).max(1) as f64;
    LayerError {
        layer: layer.to_string(),
        rmse: (se / n).sqrt(),
        rel_mse: rel / n,
        mean_ratio: (sb != 0.0).then(|| sa / sb),
        mean: sa / n,
        reference_mean: sb / n,
    }
}

/// The error of each layer of `image` that `reference` also has, in `image`'s order; `""` is
/// reported as `beauty`. Layers of equal length are assumed.
#[must_use]
pub fn layer_errors(image: &[(String, Vec<Vec3>)], reference: &[(String, Vec<Vec3>)]) -> Vec<LayerError> {
    image
        .iter()
        // The image layers only: not diagnostics such as a progressive render's `error`.
        .filter(|(name, _)| name.is_empty() || crate::film::TERM_NAMES.contains(&name.as_str()))
        .filter_map(|(name, pa)| {
            let (_, pb) = reference.iter().find(|(n, _)| n == name)?;
            Some(layer_error(if name.is_empty() { "beauty" } else { name }, pa, pb))
        })
        .collect()
}

/// The comparison of two EXR files.
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    /// The image compared.
    pub image: String,
    /// The reference.
    pub reference: String,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The reference was this many times larger in both axes and was box-filtered down to the
    /// image's size (1: same size).
    pub reference_reduced: u32,
    /// Beauty first, then each term layer present in both files.
    pub layers: Vec<LayerError>,
    /// The beauty image's block-mean errors.
    pub blocks: BlockErrors,
    /// The share of the beauty image's pixels that are speckled ([`speckle_fraction`]).
    pub speckle: f64,
    /// The same share in the reference (at the image's size): the floor its own noise sets.
    pub reference_speckle: f64,
}

/// The default block side of `compare`'s block errors, in pixels.
pub const BLOCK: u32 = 32;

/// Reads every RGB layer of the EXR at `path`, refusing NaN or infinite pixels with the layer's
/// name and count.
pub fn read_finite_exr(path: &Path) -> Result<ExrLayers> {
    let img = read_exr(path)?;
    for (name, pixels) in &img.layers {
        let bad = pixels.iter().filter(|p| !p.is_finite()).count();
        if bad > 0 {
            let name = if name.is_empty() { "beauty" } else { name.as_str() };
            return Err(Error::parse(
                path,
                0,
                format!("layer `{name}`: {bad} of {} pixels are NaN or infinite", pixels.len()),
            ));
        }
    }
    Ok(img)
}

/// Compares the EXR at `image` with the reference EXR at `reference` in blocks of [`BLOCK`]
/// pixels ([`compare_files_in_blocks`]).
pub fn compare_files(image: &Path, reference: &Path) -> Result<Comparison> {
    compare_files_in_blocks(image, reference, BLOCK)
}

/// Compares the EXR at `image` with the reference EXR at `reference`: both must be finite and of
/// the same size, or the reference an integer multiple of the image's size in both axes (then
/// box-filtered down to it); layers present in only one file are skipped. Block errors are over
/// blocks of about `block`×`block` pixels.
pub fn compare_files_in_blocks(image: &Path, reference: &Path, block: u32) -> Result<Comparison> {
    let a = read_finite_exr(image)?;
    let mut b = read_finite_exr(reference)?;
    let k = b.width.checked_div(a.width).unwrap_or(0);
    let reduced = k >= 1 && b.width == k * a.width && b.height == k * a.height;
    if !reduced {
        return Err(Error::parse(
            image,
            0,
            format!(
                "is {}×{} but the reference {} is {}×{} (it must be the same size or a whole multiple of it)",
                a.width,
                a.height,
                reference.display(),
                b.width,
                b.height
            ),
        ));
    }
    if k > 1 {
        for (_, pixels) in &mut b.layers {
            *pixels = box_reduce(pixels, b.width, b.height, k).expect("sides divide by k");
        }
    }
    let layers = layer_errors(&a.layers, &b.layers);
    if layers.is_empty() {
        return Err(Error::parse(image, 0, format!("shares no RGB layer with {}", reference.display())));
    }
    fn beauty(l: &ExrLayers) -> Option<&[Vec3]> {
        l.layers.iter().find(|(n, _)| n.is_empty()).map(|(_, p)| p.as_slice())
    }
    let (pa, pb) = match (beauty(&a), beauty(&b)) {
        (Some(pa), Some(pb)) => (pa, pb),
        _ => {
            return Err(Error::parse(image, 0, format!("it or {} has no beauty image (R, G, B)", reference.display())))
        }
    };
    Ok(Comparison {
        image: image.display().to_string(),
        reference: reference.display().to_string(),
        width: a.width,
        height: a.height,
        reference_reduced: k,
        layers,
        blocks: block_errors(pa, pb, a.width, a.height, block),
        speckle: speckle_fraction(pa, a.width, a.height),
        reference_speckle: speckle_fraction(pb, a.width, a.height),
    })
}

/// `x` in scientific notation with four decimals (`1.2346e-3`), and an exact zero as `0`.
#[must_use]
pub fn sci(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else {
        format!("{x:.4e}")
    }
}

impl Comparison {
    /// A text table, one row per layer.
    #[must_use]
    pub fn table(&self) -> String {
        let mut s = format!(
            "{} against {} ({}×{})\n{:<10} {:>12} {:>12} {:>10} {:>12} {:>12}\n",
            self.image,
            self.reference,
            self.width,
            self.height,
            "layer",
            "RMSE",
            "relMSE",
            "mean ratio",
            "mean",
            "ref mean"
        );
        for l in &self.layers {
            let ratio = l.mean_ratio.map_or("-".to_string(), |r| format!("{r:.5}"));
            s += &format!(
                "{:<10} {:>12} {:>12} {:>10} {:>12} {:>12}\n",
                l.layer,
                sci(l.rmse),
                sci(l.rel_mse),
                ratio,
                sci(l.mean),
                sci(l.reference_mean)
            );
        }
        if self.reference_reduced > 1 {
            s += &format!("the reference box-filtered down {}× to the image's size\n", self.reference_reduced);
        }
        let b = &self.blocks;
        s += &format!(
            "blocks of ~{0}×{0} ({1}×{2}): {3} measured, {4} dark; worst {5:+.2} % at ({6}, {7}), RMS {8:.2} %, {9} over 3 %\n",
            b.size,
            b.columns,
            b.rows,
            b.measured,
            b.dark,
            100.0 * b.worst,
            b.worst_at.0,
            b.worst_at.1,
            100.0 * b.rms,
            b.over_3_percent
        );
        s += &format!(
            "speckled pixels: {:.2} % (the reference: {:.2} %)\n",
            100.0 * self.speckle,
            100.0 * self.reference_speckle
        );
        s
    }
}
