//! The image of a set of progressive passes: reads each pass's film (or another set's sums) and
//! writes the mean film with its noise and bias layers and the image's error estimate. Sums are
//! exact ([`ExactSums`]) and the radius sequence's sums are folded over the pass indices in
//! increasing order, so the same passes give the same image bit for bit however they were
//! split between machines, threads or runs.

use crate::divided::exact::ExactSums;
use crate::divided::pass_set::PassList;
use crate::film::Film;
use crate::stats::ImageError;

/// Passes 0, 4, 8, … estimate their bias, and the image's bias is extrapolated from them: the
/// bias is ∝ r², so pass i's is sᵢ·b with sᵢ = r²ᵢ/r²₀, and the mean over all N passes is
/// (Σ sᵢ / N) · (Σ_S Bᵢ / Σ_S sᵢ) over the estimating passes S. The bias sum costs about a tenth
/// of a fixed-radius estimate (BENCHMARKS.md); the bias estimate's own noise is far below the
/// image's (0.2–0.3 % of a pixel against 2–10 %), so a quarter of the passes are enough.
pub const BIAS_EVERY: u32 = 4;

/// r²ᵢ / r²₁ for pass `i` (1-based): ∏ⱼ₌₁^{i−1} (j + α)/(j + 1).
#[must_use]
pub fn radius2_scale(i: u32, alpha: f32) -> f64 {
    RadiusSequence::new(alpha).scale2(i.saturating_sub(1))
}

/// The radius sequence walked forward: r² of pass index i (0-based) over pass 0's, the product
/// ∏ⱼ₌₁^i (j + α)/(j + 1), multiplied in index order so that every walk gives the same bits.
#[derive(Clone, Copy, Debug)]
pub struct RadiusSequence {
    alpha: f32,
    i: u32,
    scale2: f64,
}

impl RadiusSequence {
    /// The sequence for `alpha`, at pass 0.
    #[must_use]
    pub fn new(alpha: f32) -> Self {
        RadiusSequence { alpha, i: 0, scale2: 1.0 }
    }

    /// r²ᵢ/r²₀ for pass index `i` (walks forward; from 0 again for an earlier index).
    pub fn scale2(&mut self, i: u32) -> f64 {
        if i < self.i {
            *self = RadiusSequence::new(self.alpha);
        }
        while self.i < i {
            self.i += 1;
            let j = f64::from(self.i);
            self.scale2 *= (j + f64::from(self.alpha)) / (j + 1.0);
        }
        self.scale2
    }
}

/// Whether pass `i` estimates its bias ([`BIAS_EVERY`]).
#[must_use]
pub fn estimates_bias(i: u32) -> bool {
    i.is_multiple_of(BIAS_EVERY)
}

/// Student's t 97.5 % quantile for `dof` degrees of freedom: the table's values to 9, then the
/// Cornish–Fisher expansion about the normal's 1.96 (within 0.2 % from 10 on).
#[must_use]
pub fn student_t975(dof: u32) -> f64 {
    const Z: f64 = 1.959_964;
    match dof {
        0 => f64::INFINITY,
        1 => 12.706,
        2 => 4.303,
        3 => 3.182,
        4 => 2.776,
        5 => 2.571,
        6 => 2.447,
        7 => 2.365,
        8 => 2.306,
        9 => 2.262,
        _ => {
            let v = f64::from(dof);
            Z + (Z.powi(3) + Z) / (4.0 * v) + (5.0 * Z.powi(5) + 16.0 * Z.powi(3) + 3.0 * Z) / (96.0 * v * v)
        }
    }
}

/// The 95 % half-width t · s/√N of the mean of N = `nf` values whose sum is `s1` and sum of
/// squares `s2` (`t`: Student's quantile for N − 1 degrees of freedom).
fn half_width(s1: f64, s2: f64, nf: f64, t: f64) -> f64 {
    let mean = s1 / nf;
    let var = ((s2 - nf * mean * mean) / (nf - 1.0)).max(0.0);
    t * (var / nf).sqrt()
}

/// The exact sums of a set of passes and which passes they are.
#[derive(Clone, Debug)]
pub struct PassSums {
    /// Per-pixel sums.
    pub sums: ExactSums,
    /// The passes summed.
    pub done: PassList,
    alpha: f32,
    /// Walks the radius sequence as passes are added.
    sequence: RadiusSequence,
    /// Σ sᵢ over the passes, and over those that estimated their bias, added in index order.
    scale2_sums: [f64; 2],
}

impl PassSums {
    /// No passes yet, for a `width × height` image and radius reduction `alpha`.
    #[must_use]
    pub fn new(width: u32, height: u32, alpha: f32) -> Self {
        PassSums::from_sums(ExactSums::new(width, height), PassList::default(), alpha)
    }

    /// Sums read back (from a partial film or several merged): the radius sequence's sums are
    /// folded over `done` in increasing order, as adding the passes one by one does.
    #[must_use]
    pub fn from_sums(sums: ExactSums, done: PassList, alpha: f32) -> Self {
        let mut out = PassSums {
            sums,
            done: PassList::default(),
            alpha,
            sequence: RadiusSequence::new(alpha),
            scale2_sums: [0.0; 2],
        };
        for &i in done.indices() {
            out.count(i);
        }
        out
    }

    /// r²ᵢ/r²₀ of pass `i`.
    pub fn scale2(&mut self, i: u32) -> f64 {
        self.sequence.scale2(i)
    }

    /// Records pass `i` (larger than every pass so far) in the list and the radius sums.
    fn count(&mut self, i: u32) {
        let s = self.sequence.scale2(i);
        self.scale2_sums[0] += s;
        if estimates_bias(i) {
            self.scale2_sums[1] += s;
        }
        self.done.push(i);
    }

    /// Adds pass `i`'s film on `threads` threads; `i` must be larger than every pass so far.
    pub fn add_pass(&mut self, i: u32, film: &Film, threads: usize) {
        self.count(i);
        self.sums.add_film(film, threads);
    }

    /// Passes summed.
    #[must_use]
    pub fn passes(&self) -> u32 {
        self.done.len() as u32
    }

    /// What turns the summed per-pixel bias of the estimating passes into the image's:
    /// (Σ sᵢ / N) / Σ_S sᵢ ([`BIAS_EVERY`]).
    fn bias_scale(&self) -> f64 {
        let n = f64::from(self.passes().max(1));
        if self.scale2_sums[1] > 0.0 {
            self.scale2_sums[0] / n / self.scale2_sums[1]
        } else {
            0.0
        }
    }

    /// The mean of the passes, with its noise ([`PassSums::noise`]) and, in its pixels, its
    /// estimated bias. No diagnostic layers.
    #[must_use]
    pub fn image(&self) -> Film {
        let n = f64::from(self.passes().max(1));
        let bias = self.bias_scale();
        let pixels = (0..self.sums.len()).map(|i| self.sums.mean(i, n, bias)).collect();
        Film { noise: self.noise(), ..Film::new(self.sums.width, self.sums.height, pixels) }
    }

    /// The image's error estimate ([`ImageError`], `target_error`'s metric): the means over
    /// pixels of [`Film::error`]'s bound and of its two parts, each over the image's mean grey
    /// value. `None` before two passes. Summed in fixed chunks of pixels on `threads` threads and
    /// the chunks' sums added in order, so the thread count does not change it.
    #[must_use]
    pub fn error_95(&self, threads: usize) -> Option<ImageError> {
        const CHUNK: usize = 16_384;
        let n = self.passes();
        if n < 2 {
            return None;
        }
        let (nf, t) = (f64::from(n), student_t975(n - 1));
        let scale = self.bias_scale();
        let chunks = crate::parallel::map_chunks(
            self.sums.len(),
            CHUNK,
            threads,
            |range| {
                let mut sum = [0.0f64; 3];
                for i in range {
                    let (s1, s2) = self.sums.grey_at(i);
                    sum[0] += half_width(s1, s2, nf, t);
                    sum[1] += (self.sums.bias_grey(i) * scale).abs();
                    sum[2] += s1;
                }
                sum
            },
            |_| {},
        );
        let [noise, bias, grey] = chunks.iter().fold([0.0; 3], |a, c| [a[0] + c[0], a[1] + c[1], a[2] + c[2]]);
        let pixels = self.sums.len().max(1) as f64;
        let (noise, bias) = (noise / pixels, bias / pixels);
        let mean_grey = (grey / nf / pixels).max(f64::MIN_POSITIVE);
        Some(ImageError { error: (noise + bias) / mean_grey, noise: noise / mean_grey, bias: bias / mean_grey })
    }

    /// Per pixel, the half-width of a 95 % confidence interval of the mean beauty grey value,
    /// from the spread between the passes: t · s/√N, with s the passes' sample standard deviation
    /// and t Student's 97.5 % quantile for N − 1 degrees of freedom. The noise only, not the bias
    /// (which the pixels carry: `Terms::bias`); and approximate, as later passes' smaller radii
    /// make them a little noisier than earlier ones. `None` before two passes.
    #[must_use]
    pub fn noise(&self) -> Option<Vec<f32>> {
        Some(self.half_widths()?.map(|h| h as f32).collect())
    }

    /// [`PassSums::noise`]'s half-widths, pixel by pixel, in f64.
    fn half_widths(&self) -> Option<impl Iterator<Item = f64> + '_> {
        let n = self.passes();
        if n < 2 {
            return None;
        }
        let (nf, t) = (f64::from(n), student_t975(n - 1));
        Some(self.sums.grey().map(move |(s1, s2)| half_width(s1, s2, nf, t)))
    }

    /// The radius reduction the passes used.
    #[must_use]
    pub fn alpha(&self) -> f32 {
        self.alpha
    }
}
