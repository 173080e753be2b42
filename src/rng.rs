//! Counter-based random numbers.
//!
//! A sample is a pure function of (seed, domain, index, bounce, dimension): no state is carried
//! between pixels or photons, so the image does not depend on thread count or scheduling, and
//! the wavefront engine can reproduce the reference engine's streams exactly.

/// What a stream is used for; keeps camera, photon and light streams independent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum Domain {
    /// Camera paths, indexed by pixel sample.
    Camera = 1,
    /// Global-map photon paths, indexed by photon path.
    GlobalPhoton = 2,
    /// Caustic-map photon paths, indexed by photon path.
    CausticPhoton = 3,
}

/// SplitMix64's finaliser: a bijective 64-bit mixer with full avalanche.
#[inline]
#[must_use]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A stream of uniform numbers for one path: keyed by seed, domain and index; each call names
/// the bounce and the dimension it consumes.
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    key: u64,
}

impl Sampler {
    /// The stream of path `index` in `domain` for `seed`.
    #[must_use]
    pub fn new(seed: u64, domain: Domain, index: u64) -> Self {
        let k = mix64(seed ^ 0x9e37_79b9_7f4a_7c15);
        let k = mix64(k ^ (domain as u64).wrapping_mul(0xd1b5_4a32_d192_ed03));
        Sampler { key: mix64(k ^ index) }
    }

    /// The stream's key, for storing a stream in a queue column.
    #[must_use]
    pub fn key(&self) -> u64 {
        self.key
    }

    /// The stream with a stored key.
    #[must_use]
    pub fn from_key(key: u64) -> Self {
        Sampler { key }
    }

    /// A uniform f32 in [0, 1) for (`bounce`, `dim`).
    #[inline]
    #[must_use]
    pub fn get(&self, bounce: u32, dim: u32) -> f32 {
        let h = mix64(self.key ^ ((bounce as u64) << 32 | dim as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
        // 24 high bits → exactly representable, strictly below 1.
        (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// Two uniform numbers for (`bounce`, `dim`), (`bounce`, `dim + 1`).
    #[inline]
    #[must_use]
    pub fn get2(&self, bounce: u32, dim: u32) -> [f32; 2] {
        [self.get(bounce, dim), self.get(bounce, dim + 1)]
    }

    /// A sub-stream for a sub-path (a final-gather ray, a light sample), independent of this one.
    #[must_use]
    pub fn fork(&self, tag: u64) -> Self {
        Sampler { key: mix64(self.key ^ mix64(tag.wrapping_add(0x632b_e59b_d9b4_e019))) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_mean_and_range() {
        let s = Sampler::new(7, Domain::Camera, 3);
        let n = 100_000;
        let mut sum = 0.0f64;
        for i in 0..n {
            let u = s.get(i / 16, i % 16);
            assert!((0.0..1.0).contains(&u));
            sum += u as f64;
        }
        // Mean of U(0,1) has σ = sqrt(1/12/n) ≈ 0.0009; 5σ tolerance.
        assert!((sum / n as f64 - 0.5).abs() < 0.0046);
    }

    #[test]
    fn streams_are_pure_functions() {
        let a = Sampler::new(1, Domain::GlobalPhoton, 42);
        let b = Sampler::new(1, Domain::GlobalPhoton, 42);
        assert_eq!(a.get(3, 5), b.get(3, 5));
        assert_ne!(a.get(3, 5), Sampler::new(2, Domain::GlobalPhoton, 42).get(3, 5));
        assert_ne!(a.get(3, 5), Sampler::new(1, Domain::CausticPhoton, 42).get(3, 5));
    }
}
