//! Participating media: a homogeneous medium's coefficients (σ_a absorbs, σ_s scatters, per
//! unit length and per RGB channel), its transmittance exp(−σ_t·d) (Beer–Lambert), free-flight
//! sampling of where a ray first interacts with it, and the Henyey–Greenstein phase function
//! that says where scattered light goes (Henyey and Greenstein 1941; Jensen and Christensen
//! 1998 use the same model for their volume photon map).
//!
//! Free flight with RGB coefficients samples the distance from one channel's exponential, the
//! channel chosen uniformly, and weighs by the three channels' mean density (the single-sample
//! mixture, "spectral MIS"), so no channel's σ_t can be zero-weighted: a grey medium gets the
//! weights σ_s/σ_t (scatter) and 1 (pass) exactly.
//!
//! Reads coefficients and uniform numbers; writes distances, directions and weights. Used by
//! the path tracer (`crate::path`) through `crate::transport::media`.

use crate::sampling::Frame;
use glam::Vec3;
use std::f32::consts::PI;

/// A homogeneous participating medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Medium {
    /// Absorption coefficient σ_a per scene unit, RGB.
    pub sigma_a: Vec3,
    /// Scattering coefficient σ_s per scene unit, RGB.
    pub sigma_s: Vec3,
    /// Henyey–Greenstein asymmetry g in (−1, 1): > 0 scatters forward, 0 isotropically.
    pub g: f32,
}

/// Where free-flight sampling put a ray's first interaction with the medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FreeFlight {
    /// It scatters at `distance` along the ray; the path's throughput is multiplied by
    /// `weight` = σ_s·T(distance) / pdf(distance).
    Scatter {
        /// Distance from the ray's origin.
        distance: f32,
        /// Throughput factor.
        weight: Vec3,
    },
    /// It reaches the end of the segment; throughput × `weight` = T(length) / P(pass).
    Pass {
        /// Throughput factor.
        weight: Vec3,
    },
}

impl Medium {
    /// A medium from σ_a, σ_s and g, or what is wrong with them (a message naming the field).
    pub fn new(sigma_a: Vec3, sigma_s: Vec3, g: f32) -> Result<Self, String> {
        let ok = |v: Vec3| v.is_finite() && v.min_element() >= 0.0;
        if !ok(sigma_a) {
            return Err(format!("sigma_a must be finite and ≥ 0 in each channel, not {sigma_a}"));
        }
        if !ok(sigma_s) {
            return Err(format!("sigma_s must be finite and ≥ 0 in each channel, not {sigma_s}"));
        }
        if !(g.abs() < 1.0) {
            return Err(format!("g must lie in (−1, 1) (±1 would scatter along a single line), not {g}"));
        }
        Ok(Medium { sigma_a, sigma_s, g })
    }

    /// σ_t = σ_a + σ_s.
    #[must_use]
    pub fn sigma_t(&self) -> Vec3 {
        self.sigma_a + self.sigma_s
    }

    /// The single-scattering albedo σ_s/σ_t per channel (0 where σ_t is).
    #[must_use]
    pub fn albedo(&self) -> Vec3 {
        let t = self.sigma_t();
        Vec3::select(t.cmpgt(Vec3::ZERO), self.sigma_s / t, Vec3::ZERO)
    }

    /// True if the medium scatters light at all.
    #[must_use]
    pub fn scatters(&self) -> bool {
        self.sigma_s.max_element() > 0.0
    }

    /// The fraction of light that crosses `distance` without interacting: exp(−σ_t·d) per
    /// channel; an infinite distance keeps nothing where σ_t > 0 and everything where it is 0.
    #[must_use]
    pub fn transmittance(&self, distance: f32) -> Vec3 {
        let t = self.sigma_t();
        Vec3::from_array(t.to_array().map(|s| if s == 0.0 { 1.0 } else { (-s * distance).exp() }))
    }

    /// Samples the first interaction along a segment of `length` (∞ for a ray that leaves the
    /// scene) with two uniform numbers: `u_channel` picks the channel whose σ_t draws the
    /// distance, `u` the distance.
    #[must_use]
    pub fn free_flight(&self, length: f32, u_channel: f32, u: f32) -> FreeFlight {
        if !self.scatters() {
            // Nothing would scatter where a distance fell: every ray passes with exactly its
            // transmittance, no noise.
            return FreeFlight::Pass { weight: self.transmittance(length) };
        }
        let sigma_t = self.sigma_t();
        let channel = ((u_channel * 3.0) as usize).min(2);
        let s = sigma_t[channel];
        let distance = if s > 0.0 { -(1.0 - u).ln() / s } else { f32::INFINITY };
        if distance < length {
            let tr = self.transmittance(distance);
            // The mixture's density: the mean of the channels' σ_t·T(d).
            let pdf = (sigma_t * tr).element_sum() / 3.0;
            let weight = if pdf > 0.0 { self.sigma_s * tr / pdf } else { Vec3::ZERO };
            FreeFlight::Scatter { distance, weight }
        } else {
            let tr = self.transmittance(length);
            // The probability of passing: the mean of the channels' T(length).
            let p = tr.element_sum() / 3.0;
            FreeFlight::Pass { weight: if p > 0.0 { tr / p } else { Vec3::ZERO } }
        }
    }

    /// The medium's phase function.
    #[must_use]
    pub fn phase(&self) -> HenyeyGreenstein {
        HenyeyGreenstein { g: self.g }
    }
}

/// The Henyey–Greenstein phase function: p(cos θ) = (1 − g²) / (4π (1 + g² − 2g cos θ)^{3/2}),
/// θ the angle between the direction light travelled before scattering and after (so g > 0
/// keeps it going forward). It integrates to 1 over the sphere and its mean cosine is g.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HenyeyGreenstein {
    /// Asymmetry, the mean cosine.
    pub g: f32,
}

impl HenyeyGreenstein {
    /// p for the cosine between the travel directions before and after.
    #[must_use]
    pub fn eval_cos(&self, cos: f32) -> f32 {
        let g = self.g;
        let denom = (1.0 + g * g - 2.0 * g * cos).max(1e-12);
        (1.0 - g * g) / (4.0 * PI * denom * denom.sqrt())
    }

    /// p for light travelling along unit `before`, scattered into unit `after`: also the
    /// density per steradian with which [`Self::sample`] draws `after`.
    #[must_use]
    pub fn eval(&self, before: Vec3, after: Vec3) -> f32 {
        self.eval_cos(before.dot(after))
    }

    /// A direction light travelling along unit `before` scatters into, drawn with density
    /// [`Self::eval`] from two uniform numbers (the inverse of the cosine's distribution).
    #[must_use]
    pub fn sample(&self, before: Vec3, u: [f32; 2]) -> Vec3 {
        let g = self.g;
        let cos = if g.abs() < 1e-3 {
            1.0 - 2.0 * u[0]
        } else {
            let k = (1.0 - g * g) / (1.0 - g + 2.0 * g * u[0]);
            ((1.0 + g * g - k * k) / (2.0 * g)).clamp(-1.0, 1.0)
        };
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = 2.0 * PI * u[1];
        Frame::new(before).to_world(Vec3::new(sin * phi.cos(), sin * phi.sin(), cos))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_coefficients_are_named() {
        assert!(Medium::new(Vec3::splat(-0.1), Vec3::ONE, 0.0).unwrap_err().contains("sigma_a"));
        assert!(Medium::new(Vec3::ONE, Vec3::new(1.0, f32::NAN, 1.0), 0.0).unwrap_err().contains("sigma_s"));
        assert!(Medium::new(Vec3::ONE, Vec3::ONE, 1.0).unwrap_err().contains('g'));
        assert!(Medium::new(Vec3::ONE, Vec3::ONE, -0.99).is_ok());
    }

    #[test]
    fn transmittance_is_beer_lambert() {
        let m = Medium::new(Vec3::new(0.5, 0.0, 1.0), Vec3::new(0.5, 0.0, 0.0), 0.0).unwrap();
        let t = m.transmittance(2.0);
        assert!((t - Vec3::new((-2.0f32).exp(), 1.0, (-2.0f32).exp())).abs().max_element() < 1e-6);
        assert_eq!(m.transmittance(f32::INFINITY), Vec3::new(0.0, 1.0, 0.0));
    }

    /// The phase function integrates to 1 over the sphere and has mean cosine g (midpoint rule
    /// in cos θ, 20 000 steps: its error is far below the 1e-3 asked).
    #[test]
    fn henyey_greenstein_is_normalised_with_mean_cosine_g() {
        for g in [-0.9, -0.3, 0.0, 0.5, 0.9] {
            let p = HenyeyGreenstein { g };
            let n = 20_000;
            let (mut total, mut mean) = (0.0f64, 0.0f64);
            for i in 0..n {
                let c = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                let w = f64::from(p.eval_cos(c as f32)) * 2.0 * std::f64::consts::PI * 2.0 / n as f64;
                total += w;
                mean += w * c;
            }
            assert!((total - 1.0).abs() < 1e-3, "g {g}: integral {total}");
            assert!((mean - f64::from(g)).abs() < 1e-3, "g {g}: mean cosine {mean}");
        }
    }

    /// Sampled directions have the mean cosine g: 40 000 stratified samples, whose mean
    /// cosine's error is far below the 0.01 asked (the cosine's spread is at most 1).
    #[test]
    fn henyey_greenstein_samples_follow_it() {
        let before = Vec3::new(0.3, -0.4, 0.866).normalize();
        for g in [-0.7, 0.0, 0.4, 0.95] {
            let p = HenyeyGreenstein { g };
            let n = 200;
            let mut mean = 0.0f64;
            for i in 0..n {
                for j in 0..n {
                    let u = [(i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32];
                    let d = p.sample(before, u);
                    assert!((d.length() - 1.0).abs() < 1e-4);
                    mean += f64::from(d.dot(before));
                }
            }
            mean /= f64::from(n * n);
            assert!((mean - f64::from(g)).abs() < 0.01, "g {g}: sampled mean cosine {mean}");
        }
    }

    /// Free flight is unbiased for the transmittance: the mean of the pass weights over all
    /// draws (0 for a scatter) is T(length) per channel, within 4 standard errors of 20 000
    /// stratified draws; with a grey medium the scatter weight is the albedo exactly.
    #[test]
    fn free_flight_estimates_transmittance() {
        let m = Medium::new(Vec3::new(0.2, 0.5, 1.5), Vec3::new(0.3, 0.5, 0.5), 0.0).unwrap();
        let length = 1.3;
        let n = 20_000;
        let (mut sum, mut sum2) = (Vec3::ZERO, Vec3::ZERO);
        for i in 0..n {
            let u = (i as f32 + 0.5) / n as f32;
            let uc = ((i * 7919) % n) as f32 / n as f32;
            let w = match m.free_flight(length, uc, u) {
                FreeFlight::Pass { weight } => weight,
                FreeFlight::Scatter { .. } => Vec3::ZERO,
            };
            sum += w;
            sum2 += w * w;
        }
        let mean = sum / n as f32;
        let se = ((sum2 / n as f32 - mean * mean) / n as f32).max(Vec3::ZERO).sqrt();
        let expected = m.transmittance(length);
        assert!(((mean - expected).abs() - 4.0 * se).max_element() <= 1e-6, "{mean} vs {expected} ± {se}");
        let grey = Medium::new(Vec3::splat(0.25), Vec3::splat(0.75), 0.0).unwrap();
        match grey.free_flight(10.0, 0.5, 0.5) {
            FreeFlight::Scatter { weight, .. } => assert!((weight - Vec3::splat(0.75)).abs().max_element() < 1e-6),
            FreeFlight::Pass { .. } => panic!("a median draw in σ_t = 1 scatters before 10"),
        }
    }
}
