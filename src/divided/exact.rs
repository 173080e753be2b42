//! Exact sums of progressive passes: reads each pass's film and writes, per pixel, integer sums
//! of its terms (and of the beauty grey value and its square, for the noise estimate) in fixed
//! point. Integer addition does not depend on order, so passes summed on one machine, on many,
//! or resumed from a checkpoint give the same bits — what lets `merge` equal an undivided
//! render exactly. Floating-point sums would not: `(a + b) + c ≠ a + (b + c)`.
//!
//! Each value `x` is stored as `round(x · 2⁶⁴)` in an `i128` (its square as `round(x² · 2⁴⁸)`):
//! resolution 5·10⁻²⁰ (squares 4·10⁻¹⁵); one value saturates at ±2¹²⁶ units (±4.6·10¹⁸), and
//! sums add in two's complement (wrapping), which keeps them independent of order even past
//! ±9·10¹⁸ (squares ±6·10²³), where they would wrap — far beyond any radiance an f32 film holds
//! usefully. The conversion is IEEE arithmetic only (a power-of-two product, floor, round, integer
//! casts), the same on every machine.

use crate::film::{Film, Terms};
use glam::Vec3;

/// Values summed per pixel: five terms and the bias, RGB each, then grey and grey².
pub const VALUES: usize = 20;

/// The values' names, as partial films name their channels (`sum.direct.R.w0`, …).
pub const NAMES: [&str; VALUES] = [
    "emitted.R",
    "emitted.G",
    "emitted.B",
    "direct.R",
    "direct.G",
    "direct.B",
    "specular.R",
    "specular.G",
    "specular.B",
    "caustic.R",
    "caustic.G",
    "caustic.B",
    "indirect.R",
    "indirect.G",
    "indirect.B",
    "bias.R",
    "bias.G",
    "bias.B",
    "grey",
    "grey2",
];

/// Fixed-point scale of values (2⁶⁴).
const VALUE_SCALE: f64 = TWO64;
/// Fixed-point scale of squared grey values (2⁴⁸).
const SQUARE_SCALE: f64 = 281_474_976_710_656.0;
/// Index of the grey value; the square follows.
const GREY: usize = 18;

/// 2⁶⁴, for splitting a fixed-point value into 64-bit halves.
const TWO64: f64 = 18_446_744_073_709_551_616.0;
/// 2¹²⁶: beyond it a value saturates.
const LIMIT: f64 = 85_070_591_730_234_615_865_843_651_857_942_052_864.0;

/// `x` in fixed point: `round(x · scale)` (ties away from zero), saturating at ±2¹²⁶; NaN counts
/// as 0 (films hold none: engines drop non-finite samples). Computed on the magnitude in two
/// 64-bit halves — `a = |x| · scale` is exact, and so are `h = ⌊a / 2⁶⁴⌋` and `a − h · 2⁶⁴` (the
/// remainder of a non-negative value keeps a subset of its bits) — because a direct f64 → i128
/// conversion is a library call several times slower (BENCHMARKS.md, "Divided renders").
fn quantise(x: f64, scale: f64) -> i128 {
    let y = x * scale;
    if y.is_nan() {
        return 0;
    }
    if !(y.abs() < LIMIT) {
        return if y > 0.0 { LIMIT as i128 } else { -(LIMIT as i128) };
    }
    let a = y.abs();
    let hi = (a / TWO64).floor();
    let lo = (a - hi * TWO64).round();
    let (hi, lo) = if lo >= TWO64 { (hi as u64 + 1, 0) } else { (hi as u64, lo as u64) };
    let q = (i128::from(hi) << 64) + i128::from(lo);
    if y < 0.0 {
        -q
    } else {
        q
    }
}

/// Adds `pixels`' values to their `sums`.
fn add_pixels(sums: &mut [[i128; VALUES]], pixels: &[Terms]) {
    for (s, p) in sums.iter_mut().zip(pixels) {
        let v = [p.emitted, p.direct, p.specular, p.caustic, p.indirect, p.bias];
        for (k, c) in v.iter().flat_map(|c| c.to_array()).enumerate() {
            s[k] = s[k].wrapping_add(quantise(f64::from(c), VALUE_SCALE));
        }
        let grey = f64::from(p.beauty().element_sum()) / 3.0;
        s[GREY] = s[GREY].wrapping_add(quantise(grey, VALUE_SCALE));
        s[GREY + 1] = s[GREY + 1].wrapping_add(quantise(grey * grey, SQUARE_SCALE));
    }
}

/// Per-pixel exact sums of passes' films.
#[derive(Clone, Debug, PartialEq)]
pub struct ExactSums {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    sums: Vec<[i128; VALUES]>,
}

impl ExactSums {
    /// Zero sums for a `width × height` image.
    #[must_use]
    pub fn new(width: u32, height: u32) -> Self {
        ExactSums { width, height, sums: vec![[0; VALUES]; width as usize * height as usize] }
    }

    /// Pixels.
    #[must_use]
    pub fn len(&self) -> usize {
        self.sums.len()
    }

    /// Whether the image has no pixels.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.sums.is_empty()
    }

    /// Adds one pass's film (the same size), its pixels split among `threads` threads (each
    /// pixel's sums are its own, so the split changes nothing).
    pub fn add_film(&mut self, film: &Film, threads: usize) {
        debug_assert_eq!(film.pixels.len(), self.sums.len());
        let per = self.sums.len().div_ceil(threads.max(1)).max(1);
        std::thread::scope(|scope| {
            for (sums, pixels) in self.sums.chunks_mut(per).zip(film.pixels.chunks(per)) {
                scope.spawn(move || add_pixels(sums, pixels));
            }
        });
    }

    /// Adds another set of sums (the same size): the sums of both sets of passes (wrapping, so
    /// that any order gives the same bits).
    pub fn add(&mut self, o: &ExactSums) {
        for (s, t) in self.sums.iter_mut().zip(&o.sums) {
            for k in 0..VALUES {
                s[k] = s[k].wrapping_add(t[k]);
            }
        }
    }

    /// Pixel `i`'s terms divided by `n` passes, its bias multiplied by `bias_scale` instead.
    #[must_use]
    pub fn mean(&self, i: usize, n: f64, bias_scale: f64) -> Terms {
        let s = &self.sums[i];
        let v = |k: usize, f: f64| {
            Vec3::new(
                (s[k] as f64 / VALUE_SCALE * f) as f32,
                (s[k + 1] as f64 / VALUE_SCALE * f) as f32,
                (s[k + 2] as f64 / VALUE_SCALE * f) as f32,
            )
        };
        let inv = 1.0 / n;
        Terms {
            emitted: v(0, inv),
            direct: v(3, inv),
            specular: v(6, inv),
            caustic: v(9, inv),
            indirect: v(12, inv),
            bias: v(15, bias_scale),
        }
    }

    /// Pixel `i`'s summed bias, grey (R+G+B)/3.
    #[must_use]
    pub fn bias_grey(&self, i: usize) -> f64 {
        let s = &self.sums[i];
        (s[15] as f64 + s[16] as f64 + s[17] as f64) / VALUE_SCALE / 3.0
    }

    /// Per pixel, the sums of the passes' beauty grey value and of its square.
    pub fn grey(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        (0..self.sums.len()).map(|i| self.grey_at(i))
    }

    /// Pixel `i`'s sums of the passes' beauty grey value and of its square.
    #[must_use]
    pub fn grey_at(&self, i: usize) -> (f64, f64) {
        let s = &self.sums[i];
        (s[GREY] as f64 / VALUE_SCALE, s[GREY + 1] as f64 / SQUARE_SCALE)
    }

    /// Word `w` (0 = least significant) of value `k` of every pixel, as partial films store the
    /// sums: four u32 channels per value, two's complement.
    #[must_use]
    pub fn words(&self, k: usize, w: usize) -> Vec<u32> {
        self.sums.iter().map(|s| ((s[k] as u128) >> (32 * w)) as u32).collect()
    }

    /// Sums from [`ExactSums::words`]' channels: `words(k, w)` gives value k's word w.
    #[must_use]
    pub fn from_words<'a>(width: u32, height: u32, words: &dyn Fn(usize, usize) -> &'a [u32]) -> Self {
        let mut out = ExactSums::new(width, height);
        for k in 0..VALUES {
            for w in 0..4 {
                for (s, &word) in out.sums.iter_mut().zip(words(k, w)) {
                    s[k] = (s[k] as u128 | (u128::from(word) << (32 * w))) as i128;
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn film(values: &[f32]) -> Film {
        let pixels = values
            .iter()
            .map(|&v| Terms { direct: Vec3::new(v, 2.0 * v, 0.5), bias: Vec3::splat(-v), ..Terms::default() })
            .collect();
        Film::new(values.len() as u32, 1, pixels)
    }

    /// The split conversion gives the direct one's integer (round half away from zero) and
    /// saturates.
    #[test]
    fn quantising_in_halves_rounds_to_the_nearest_unit() {
        let mut state = 0x1234_5678_9abc_def0_u64;
        for _ in 0..100_000 {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            let mantissa = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            let x = mantissa * 2f64.powi((state % 120) as i32 - 70);
            let direct = (x * VALUE_SCALE).round() as i128;
            assert_eq!(quantise(x, VALUE_SCALE), direct, "{x:e}");
        }
        assert_eq!(quantise(1e30, VALUE_SCALE), LIMIT as i128);
        assert_eq!(quantise(-1e30, VALUE_SCALE), -(LIMIT as i128));
        assert_eq!(quantise(f64::NAN, VALUE_SCALE), 0);
        assert_eq!((quantise(-0.625, 4.0), quantise(0.625, 4.0)), (-3, 3));
    }

    /// Any grouping of the same passes gives the same sums, and the words read back.
    #[test]
    fn sums_do_not_depend_on_order_or_grouping() {
        let passes = [film(&[1e-9, 3.0, 1e7]), film(&[0.1, 7e-3, 2.5]), film(&[1e3, 0.0, 1e-20])];
        let mut a = ExactSums::new(3, 1);
        for p in &passes {
            a.add_film(p, 2);
        }
        let (mut b, mut c) = (ExactSums::new(3, 1), ExactSums::new(3, 1));
        b.add_film(&passes[2], 1);
        c.add_film(&passes[1], 3);
        c.add_film(&passes[0], 1);
        b.add(&c);
        assert_eq!(a, b);
        let words: Vec<Vec<Vec<u32>>> = (0..VALUES).map(|k| (0..4).map(|w| a.words(k, w)).collect()).collect();
        let back = ExactSums::from_words(3, 1, &|k, w| &words[k][w]);
        assert_eq!(back, a);
        // Means are the exact sums' (to f32 rounding), and the bias is signed.
        let m = a.mean(0, 3.0, 1.0);
        assert!((m.direct.x - (1e-9 + 0.1 + 1e3) / 3.0).abs() < 1e-4);
        assert!(m.bias.x < 0.0);
    }
}
