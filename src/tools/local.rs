//! Local error of an image against a reference, where a whole-image mean hides it: the mean
//! luminance of each block of about B×B pixels against the reference's (a region too bright or
//! too dark), and the share of *speckled* pixels (isolated bright outliers, the fireflies and
//! splotches of a starved estimate). Also the box filter that brings a larger reference (a
//! published render at 4× the size) down to the image's size.
//!
//! Reads two images' beauty pixels; writes numbers. Used by `compare`.

use crate::texture::luminance;
use glam::Vec3;
use serde::Serialize;

/// Blocks whose reference mean luminance is below this fraction of the reference image's mean
/// are not measured: their relative error says nothing (a black corner) and they are counted in
/// [`BlockErrors::dark`].
pub const DARK_BLOCK: f64 = 0.01;

/// A speckled pixel's luminance is over this many times the median of its 8 neighbours' …
pub const SPECKLE_RATIO: f32 = 2.0;

/// … and over that median by more than this fraction of the image's mean luminance (so that
/// faint texture and noise in dark regions do not count).
pub const SPECKLE_FLOOR: f32 = 0.05;

/// The offsets of a pixel's 8 neighbours.
const NEIGHBOURS: [(i64, i64); 8] = [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)];

/// The block-mean errors of an image against its reference.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BlockErrors {
    /// The nominal block side in pixels (blocks are this size up to the rounding of the image
    /// into a whole number of them along each axis).
    pub size: u32,
    /// Blocks along x.
    pub columns: u32,
    /// Blocks along y.
    pub rows: u32,
    /// Blocks measured (not dark).
    pub measured: u32,
    /// Blocks skipped as dark ([`DARK_BLOCK`]).
    pub dark: u32,
    /// The largest |mean(a)/mean(b) − 1| over the measured blocks, signed; 0 when none was
    /// measured.
    pub worst: f64,
    /// The worst block's column and row.
    pub worst_at: (u32, u32),
    /// Root mean square of the measured blocks' relative errors.
    pub rms: f64,
    /// Measured blocks whose relative error exceeds 3 %.
    pub over_3_percent: u32,
}

/// Boundaries of `n` near-equal parts of `len` pixels: part `i` is `[b[i], b[i + 1])`.
fn splits(len: u32, n: u32) -> Vec<u32> {
    (0..=n).map(|i| (u64::from(i) * u64::from(len) / u64::from(n)) as u32).collect()
}

/// Mean luminance of `image` (row-major, `width` wide) over the rectangle `[x0, x1) × [y0, y1)`.
fn block_mean(image: &[Vec3], width: u32, (x0, x1): (u32, u32), (y0, y1): (u32, u32)) -> f64 {
    let mut sum = 0.0f64;
    for y in y0..y1 {
        let row = (y * width) as usize;
        sum += image[row + x0 as usize..row + x1 as usize].iter().map(|&p| f64::from(luminance(p))).sum::<f64>();
    }
    sum / f64::from((x1 - x0) * (y1 - y0)).max(1.0)
}

/// The block errors of `a` against the reference `b` (`width`×`height`, row-major). The image
/// is cut into round(width/size) × round(height/size) blocks (at least one each way) of
/// near-equal size, so that every pixel belongs to one block.
#[must_use]
pub fn block_errors(a: &[Vec3], b: &[Vec3], width: u32, height: u32, size: u32) -> BlockErrors {
    let size = size.max(1);
    let count = |len: u32| ((f64::from(len) / f64::from(size)).round() as u32).clamp(1, len.max(1));
    let (columns, rows) = (count(width), count(height));
    let (xs, ys) = (splits(width, columns), splits(height, rows));
    let image_mean = block_mean(b, width, (0, width), (0, height));
    let mut e = BlockErrors {
        size,
        columns,
        rows,
        measured: 0,
        dark: 0,
        worst: 0.0,
        worst_at: (0, 0),
        rms: 0.0,
        over_3_percent: 0,
    };
    let mut sum_sq = 0.0;
    for j in 0..rows {
        for i in 0..columns {
            let (xr, yr) = ((xs[i as usize], xs[i as usize + 1]), (ys[j as usize], ys[j as usize + 1]));
            let mb = block_mean(b, width, xr, yr);
            if !(mb > DARK_BLOCK * image_mean) {
                e.dark += 1;
                continue;
            }
            let r = block_mean(a, width, xr, yr) / mb - 1.0;
            e.measured += 1;
            sum_sq += r * r;
            e.over_3_percent += u32::from(r.abs() > 0.03);
            if r.abs() > e.worst.abs() {
                (e.worst, e.worst_at) = (r, (i, j));
            }
        }
    }
    e.rms = (sum_sq / f64::from(e.measured.max(1))).sqrt();
    e
}

/// The fraction of `image`'s pixels that are speckled: luminance over [`SPECKLE_RATIO`] times
/// the median of its 8 neighbours (the edge pixels repeated) and over it by more than
/// [`SPECKLE_FLOOR`] of the image's mean luminance.
#[must_use]
pub fn speckle_fraction(image: &[Vec3], width: u32, height: u32) -> f64 {
    let (w, h) = (width as i64, height as i64);
    if image.is_empty() || w == 0 || h == 0 {
        return 0.0;
    }
    let y: Vec<f32> = image.iter().map(|&p| luminance(p)).collect();
    let mean = (y.iter().map(|&v| f64::from(v)).sum::<f64>() / y.len() as f64) as f32;
    let at = |px: i64, py: i64| y[(py.clamp(0, h - 1) * w + px.clamp(0, w - 1)) as usize];
    let mut speckled = 0usize;
    let mut neighbours = [0.0f32; 8];
    for py in 0..h {
        for px in 0..w {
            for (slot, (dx, dy)) in neighbours.iter_mut().zip(NEIGHBOURS) {
                *slot = at(px + dx, py + dy);
            }
            neighbours.sort_unstable_by(f32::total_cmp);
            // The median of eight: the mean of the middle two.
            let median = 0.5 * (neighbours[3] + neighbours[4]);
            let v = at(px, py);
            speckled += usize::from(v > SPECKLE_RATIO * median && v - median > SPECKLE_FLOOR * mean);
        }
    }
    speckled as f64 / y.len() as f64
}

/// `image` (`width`×`height`) box-filtered down by the integer factor `k` in both axes: each
/// output pixel is the mean of a k×k square. `None` unless both sides divide by `k`.
#[must_use]
pub fn box_reduce(image: &[Vec3], width: u32, height: u32, k: u32) -> Option<Vec<Vec3>> {
    if k == 0 || !width.is_multiple_of(k) || !height.is_multiple_of(k) || image.len() != (width * height) as usize {
        return None;
    }
    let (ow, oh) = (width / k, height / k);
    let scale = 1.0 / (k * k) as f32;
    let mut out = vec![Vec3::ZERO; (ow * oh) as usize];
    for y in 0..height {
        for x in 0..width {
            out[((y / k) * ow + x / k) as usize] += image[(y * width + x) as usize];
        }
    }
    out.iter_mut().for_each(|p| *p *= scale);
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_cover_every_pixel() {
        assert_eq!(splits(320, 10), (0..=10).map(|i| 32 * i).collect::<Vec<_>>());
        let s = splits(180, 6);
        assert_eq!((s[0], s[6]), (0, 180));
        assert!(s.windows(2).all(|p| p[1] - p[0] == 30));
    }

    #[test]
    fn one_bright_block_is_the_worst() {
        let (w, h) = (64, 40);
        let b = vec![Vec3::splat(0.5); (w * h) as usize];
        let mut a = b.clone();
        // 64×40 in blocks of 32: 2 columns, round(1.25) = 1 row of 40. Brighten the right
        // block's top 20 rows by 10 %: its mean is 5 % over.
        for y in 0..20 {
            for x in 32..64 {
                a[(y * w + x) as usize] *= 1.1;
            }
        }
        let e = block_errors(&a, &b, w, h, 32);
        assert_eq!((e.columns, e.rows, e.measured, e.dark), (2, 1, 2, 0));
        assert!((e.worst - 0.05).abs() < 1e-6 && e.worst_at == (1, 0), "{e:?}");
        assert!((e.rms - (0.05f64 * 0.05 / 2.0).sqrt()).abs() < 1e-6 && e.over_3_percent == 1, "{e:?}");
    }

    #[test]
    fn dark_blocks_are_skipped() {
        let (w, h) = (64, 32);
        let mut b = vec![Vec3::ONE; (w * h) as usize];
        for y in 0..h {
            for x in 0..32 {
                b[(y * w + x) as usize] = Vec3::ZERO;
            }
        }
        let a = vec![Vec3::ONE; (w * h) as usize];
        let e = block_errors(&a, &b, w, h, 32);
        assert_eq!((e.measured, e.dark, e.worst), (1, 1, 0.0), "{e:?}");
    }

    #[test]
    fn speckles_are_isolated_bright_pixels() {
        let (w, h) = (10, 10);
        let mut img = vec![Vec3::splat(0.5); 100];
        img[33] = Vec3::splat(1.2); // over twice its neighbours: speckled
        img[66] = Vec3::splat(0.9); // 1.8× its neighbours: not
        assert!((speckle_fraction(&img, w, h) - 0.01).abs() < 1e-12);
        // A 2×2 bright patch: each pixel has three bright neighbours among eight, so the
        // median stays at the background and all four count.
        let mut patch = vec![Vec3::splat(0.5); 100];
        for i in [44, 45, 54, 55] {
            patch[i] = Vec3::splat(2.0);
        }
        assert!((speckle_fraction(&patch, w, h) - 0.04).abs() < 1e-12);
        // A bright half: an edge, not speckle.
        let half: Vec<Vec3> = (0..100).map(|i| Vec3::splat(if i % 10 < 5 { 0.1 } else { 1.0 })).collect();
        assert_eq!(speckle_fraction(&half, w, h), 0.0);
        // In a dark half (0.001 beside 1.0), a pixel 10× its neighbours but only 0.009 over
        // them, under the floor of 5 % of the image mean (about 0.025): not speckled; at 0.1 it is.
        let mut dim: Vec<Vec3> = (0..100).map(|i| Vec3::splat(if i % 10 < 5 { 1.0 } else { 0.001 })).collect();
        dim[58] = Vec3::splat(0.01);
        assert_eq!(speckle_fraction(&dim, w, h), 0.0);
        dim[58] = Vec3::splat(0.1);
        assert!((speckle_fraction(&dim, w, h) - 0.01).abs() < 1e-12);
    }

    #[test]
    fn box_reduce_averages_squares() {
        let img: Vec<Vec3> = (0..16).map(|i| Vec3::splat(i as f32)).collect();
        let r = box_reduce(&img, 4, 4, 2).unwrap();
        assert_eq!(r, vec![Vec3::splat(2.5), Vec3::splat(4.5), Vec3::splat(10.5), Vec3::splat(12.5)]);
        assert!(box_reduce(&img, 4, 4, 3).is_none());
    }
}
