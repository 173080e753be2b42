//! The environment light: radiance arriving from every direction at infinity, a constant colour
//! or a lat-long (equirectangular) HDR map, importance-sampled by luminance for direct light and
//! emitting photons from a disk that covers the scene (as pbrt-v4 does for infinite lights).
//!
//! Lat-long convention (y up): texel column i, row j (from the top) covers azimuth
//! φ ∈ 2π·[i, i+1)/w and polar angle θ ∈ π·[j, j+1)/h from +y, direction
//! (sin θ cos φ, cos θ, sin θ sin φ), with φ turned by `rotation` about +y. The map is read
//! piecewise constant (each texel over its whole patch of sky), so the sampling pdf below is
//! exact: texel k is picked with probability ∝ luminance·sin θ of its centre, a point uniformly
//! inside it, and p(ω) = P(k)·w·h / (2π² sin θ) — mixed with a uniform share
//! ([`UNIFORM_SHARE`]) so that no direction the map lights is left to chance.

use super::portal::Portals;
use crate::sampling::{uniform_sphere, Distribution1D};
use crate::texture::Texture;
use glam::Vec3;
use std::f32::consts::PI;

/// Radiance at infinity in every direction.
#[derive(Clone, Debug)]
pub struct Environment {
    /// Radiance in every direction when there is no map (already scaled).
    constant: Vec3,
    /// The lat-long map and the texel distribution for sampling it.
    map: Option<(Texture, Distribution1D)>,
    /// Multiplies the map.
    scale: f32,
    /// Turn of the map about +y, radians.
    rotation: f32,
    /// ∫ L(ω) dω over the sphere.
    integral: Vec3,
    /// Where its light enters an interior: direct light draws half its samples through them
    /// instead of by the map ([`Environment::sampling_pdf`]).
    portals: Portals,
}

/// Rec. 709 luminance of linear RGB.
#[must_use]
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

impl Environment {
    /// The same radiance `l` from every direction.
    #[must_use]
    pub fn constant(l: Vec3) -> Environment {
        Environment {
            constant: l,
            map: None,
            scale: 1.0,
            rotation: 0.0,
            integral: l * 4.0 * PI,
            portals: Portals::default(),
        }
    }

    /// A lat-long map scaled by `scale` and turned by `rotation` radians about +y. `Err` says
    /// why the map cannot be one (its shape).
    pub fn from_map(map: Texture, scale: f32, rotation: f32) -> Result<Environment, String> {
        let (w, h) = (map.width as usize, map.height as usize);
        if w != 2 * h {
            return Err(format!(
                "a lat-long map is twice as wide as it is high (360° by 180°); {} is {w}×{h}",
                map.path.display()
            ));
        }
        let mut weights = Vec::with_capacity(w * h);
        let mut integral = glam::DVec3::ZERO;
        for j in 0..h {
            let theta = PI * (j as f32 + 0.5) / h as f32;
            // Solid angle of a texel of this row: (2π/w)·(cos θ0 − cos θ1).
            let (t0, t1) = (PI * j as f32 / h as f32, PI * (j + 1) as f32 / h as f32);
            let omega = f64::from(2.0 * PI / w as f32) * (f64::from(t0).cos() - f64::from(t1).cos());
            for i in 0..w {
                let l = map.texels[j * w + i];
                weights.push(f64::from(luminance(l) * theta.sin()));
                integral += l.as_dvec3() * omega;
            }
        }
        let distribution = Distribution1D::try_new(&weights).unwrap_or_default();
        let integral = integral.as_vec3() * scale;
        Ok(Environment {
            constant: Vec3::ZERO,
            map: Some((map, distribution)),
            scale,
            rotation,
            integral,
            portals: Portals::default(),
        })
    }

    /// This environment with its light entering through `portals` (in the scene files'
    /// coordinates until the scene moves them, [`Environment::moved`]).
    #[must_use]
    pub fn with_portals(self, portals: Portals) -> Environment {
        Environment { portals, ..self }
    }

    /// The same environment, its portals relative to `origin` (the scene's frame).
    #[must_use]
    pub fn moved(self, origin: Vec3) -> Environment {
        let portals = self.portals.moved(origin);
        Environment { portals, ..self }
    }

    /// Its portals (empty without).
    #[must_use]
    pub fn portals(&self) -> &Portals {
        &self.portals
    }

    /// A direction from `x` for direct light's second half of samples: through a portal when
    /// there are portals, else by the map ([`Environment::sample_direction`]).
    #[must_use]
    pub fn sample_from(&self, x: Vec3, u: [f32; 2]) -> Option<Vec3> {
        if self.portals.is_empty() {
            self.sample_direction(u)
        } else {
            self.portals.sample(x, u)
        }
    }

    /// The density of [`Environment::sample_from`] at `x` toward `wi`: the portals' when there
    /// are portals, else the map's, `map_pdf` (asked only then; a caller that read the
    /// radiance has it already, [`Environment::radiance_pdf`]).
    #[must_use]
    pub fn sampling_pdf(&self, x: Vec3, wi: Vec3, map_pdf: impl FnOnce() -> f32) -> f32 {
        if self.portals.is_empty() {
            map_pdf()
        } else {
            self.portals.pdf(x, wi)
        }
    }

    /// ∫ L(ω) dω over the sphere.
    #[must_use]
    pub fn integral(&self) -> Vec3 {
        self.integral
    }

    /// Power entering a scene of bounding radius `radius`: π r² ∫ L dω (the flux through a disk
    /// of that radius from every direction).
    #[must_use]
    pub fn power(&self, radius: f32) -> Vec3 {
        self.integral * (PI * radius * radius)
    }

    /// Radiance arriving from direction `wi` (unit, pointing away from the scene).
    #[must_use]
    pub fn radiance(&self, wi: Vec3) -> Vec3 {
        self.radiance_pdf(wi).0
    }

    /// The pdf of [`Environment::sample`] for direction `wi`, per steradian.
    #[must_use]
    pub fn pdf(&self, wi: Vec3) -> f32 {
        self.radiance_pdf(wi).1
    }

    /// Radiance from `wi` and the pdf of sampling it, from one texel lookup.
    #[must_use]
    pub fn radiance_pdf(&self, wi: Vec3) -> (Vec3, f32) {
        let Some((map, dist)) = &self.map else { return (self.constant, 1.0 / (4.0 * PI)) };
        let (i, j, sin_theta) = self.texel_of(map, wi);
        let k = j * map.width as usize + i;
        let radiance = map.texels[k] * self.scale;
        if dist.total() <= 0.0 {
            return (radiance, 0.0);
        }
        let p_map = if sin_theta > 0.0 {
            let (w, h) = (map.width as f32, map.height as f32);
            dist.pmf(k) as f32 * w * h / (2.0 * PI * PI * sin_theta)
        } else {
            0.0
        };
        (radiance, UNIFORM_SHARE / (4.0 * PI) + (1.0 - UNIFORM_SHARE) * p_map)
    }

    /// A direction toward the environment with two uniform numbers, as [`Environment::sample`]
    /// draws it (without its radiance and pdf). `None` for a black environment.
    ///
    /// A map is sampled defensively: with probability [`UNIFORM_SHARE`] uniformly over the
    /// sphere, otherwise by the map's luminance, and the pdf is the mixture's. A sky whose sun
    /// holds most of the power would otherwise leave the faces that do not see the sun lit by
    /// a handful of samples.
    #[must_use]
    pub fn sample_direction(&self, u: [f32; 2]) -> Option<Vec3> {
        let Some((map, dist)) = &self.map else {
            return (self.constant != Vec3::ZERO).then(|| uniform_sphere(u));
        };
        if dist.total() <= 0.0 {
            return None;
        }
        if u[0] < UNIFORM_SHARE {
            return Some(uniform_sphere([u[0] / UNIFORM_SHARE, u[1]]));
        }
        let u0 = ((u[0] - UNIFORM_SHARE) / (1.0 - UNIFORM_SHARE)).min(crate::sampling::ONE_BELOW);
        let (k, ux) = dist.sample_remapped(u0);
        let (w, h) = (map.width as usize, map.height as usize);
        let (i, j) = (k % w, k / w);
        let theta = PI * (j as f32 + u[1]) / h as f32;
        let phi = 2.0 * PI * (i as f32 + ux) / w as f32 + self.rotation;
        let sin_theta = theta.sin();
        Some(Vec3::new(sin_theta * phi.cos(), theta.cos(), sin_theta * phi.sin()))
    }

    /// A direction toward the environment with two uniform numbers: (direction, pdf per
    /// steradian, radiance). `None` for a black map or a sample at a pole (sin θ = 0).
    #[must_use]
    pub fn sample(&self, u: [f32; 2]) -> Option<(Vec3, f32, Vec3)> {
        let wi = self.sample_direction(u)?;
        let (radiance, pdf) = self.radiance_pdf(wi);
        (pdf > 0.0 && wi.is_finite()).then_some((wi, pdf, radiance))
    }

    /// The texel (column, row) a direction falls in, and sin θ.
    fn texel_of(&self, map: &Texture, wi: Vec3) -> (usize, usize, f32) {
        let theta = wi.y.clamp(-1.0, 1.0).acos();
        let phi = (wi.z.atan2(wi.x) - self.rotation).rem_euclid(2.0 * PI);
        let i = ((phi / (2.0 * PI) * map.width as f32) as usize).min(map.width as usize - 1);
        let j = ((theta / PI * map.height as f32) as usize).min(map.height as usize - 1);
        (i, j, theta.sin())
    }
}

/// The share of an environment map's samples spread uniformly over the sphere
/// ([`Environment::sample`]).
pub const UNIFORM_SHARE: f32 = 0.1;

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// A 32×16 sky: a dim blue gradient with one bright texel (a small sun).
    fn sky() -> Environment {
        let (w, h) = (32u32, 16u32);
        let mut texels = Vec::new();
        for j in 0..h {
            for i in 0..w {
                let g = 0.2 + 0.8 * (1.0 - j as f32 / h as f32);
                texels.push(
                    Vec3::new(0.3 * g, 0.5 * g, g) + if (i, j) == (5, 3) { Vec3::splat(400.0) } else { Vec3::ZERO },
                );
            }
        }
        Environment::from_map(Texture::new(Path::new("sky.exr"), w, h, texels).unwrap(), 1.5, 0.4).unwrap()
    }

    /// Mean and standard error of `n` values of `f(k)`.
    fn mean_se(n: usize, f: impl Fn(usize) -> f64) -> (f64, f64) {
        let v: Vec<f64> = (0..n).map(f).collect();
        let m = v.iter().sum::<f64>() / n as f64;
        let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1) as f64;
        (m, (var / n as f64).sqrt())
    }

    /// Uniform numbers from a fixed-seed generator (splitmix64).
    fn uniforms(k: usize) -> [f32; 2] {
        let mix = |mut z: u64| {
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
            ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
        };
        let z = (k as u64 + 1).wrapping_mul(0x9e3779b97f4a7c15);
        [mix(z), mix(z ^ 0x5555)]
    }

    #[test]
    fn importance_sampling_agrees_with_uniform_sampling() {
        // Irradiance on a surface facing n: E = ∫ L(ω) max(0, ω·n) dω, estimated with the map's
        // importance sampling and with uniform sphere sampling (pdf 1/4π). Both are unbiased; the
        // test allows 4 standard errors of their difference.
        let env = sky();
        for n in [Vec3::Y, Vec3::new(0.5, 0.2, -0.8).normalize(), -Vec3::Y] {
            let n_samples = 200_000;
            let (a, sa) = mean_se(n_samples, |k| match env.sample(uniforms(k)) {
                Some((wi, pdf, l)) => f64::from(luminance(l) * wi.dot(n).max(0.0) / pdf),
                None => 0.0,
            });
            let (b, sb) = mean_se(n_samples, |k| {
                let wi = uniform_sphere(uniforms(k + 7_000_000));
                f64::from(luminance(env.radiance(wi)) * wi.dot(n).max(0.0) * 4.0 * PI)
            });
            let tol = 4.0 * (sa * sa + sb * sb).sqrt();
            assert!((a - b).abs() <= tol, "n = {n}: importance {a} ± {sa} against uniform {b} ± {sb}");
        }
    }

    #[test]
    fn samples_follow_the_pdf() {
        let env = sky();
        // The pdf integrates to 1 over the sphere (uniform estimate, 4 standard errors).
        let (m, se) = mean_se(200_000, |k| f64::from(env.pdf(uniform_sphere(uniforms(k))) * 4.0 * PI));
        assert!((m - 1.0).abs() <= 4.0 * se, "∫ pdf = {m} ± {se}");
        // χ² of the samples' texels against each texel's probability, ∫ pdf dω over it =
        // share/4π·Ω + (1 − share)·P(texel). Texels expected fewer than 5 times are pooled. The
        // statistic of a right sampler has mean dof and σ √(2 dof); 5σ over the mean fails.
        let (w, h) = (32usize, 16usize);
        let n = 400_000usize;
        let mut counts = vec![0f64; w * h];
        for k in 0..n {
            let (wi, _, _) = env.sample(uniforms(k)).unwrap();
            let Some((map, _)) = &env.map else { unreachable!() };
            let (i, j, _) = env.texel_of(map, wi);
            counts[j * w + i] += 1.0;
        }
        let Some((_, dist)) = &env.map else { unreachable!() };
        let (mut chi2, mut dof, mut pooled) = (0.0, 0usize, (0.0, 0.0));
        for j in 0..h {
            let omega = 2.0 * std::f64::consts::PI / w as f64
                * ((std::f64::consts::PI * j as f64 / h as f64).cos()
                    - (std::f64::consts::PI * (j + 1) as f64 / h as f64).cos());
            for i in 0..w {
                let share = f64::from(UNIFORM_SHARE);
                let expected =
                    n as f64 * (share * omega / (4.0 * std::f64::consts::PI) + (1.0 - share) * dist.pmf(j * w + i));
                if expected < 5.0 {
                    pooled = (pooled.0 + counts[j * w + i], pooled.1 + expected);
                } else {
                    chi2 += (counts[j * w + i] - expected).powi(2) / expected;
                    dof += 1;
                }
            }
        }
        if pooled.1 > 0.0 {
            chi2 += (pooled.0 - pooled.1).powi(2) / pooled.1;
            dof += 1;
        }
        let dof = (dof - 1) as f64;
        assert!(chi2 < dof + 5.0 * (2.0 * dof).sqrt(), "χ² = {chi2} for {dof} degrees of freedom");
        // A constant environment's integral is 4π L.
        assert!((Environment::constant(Vec3::ONE).integral() - Vec3::splat(4.0 * PI)).length() < 1e-5);
    }

    #[test]
    fn maps_must_be_twice_as_wide_as_high() {
        let t = Texture::new(Path::new("square.exr"), 4, 4, vec![Vec3::ONE; 16]).unwrap();
        let e = Environment::from_map(t, 1.0, 0.0).unwrap_err();
        assert!(e.contains("square.exr") && e.contains("4×4"), "{e}");
    }
}
