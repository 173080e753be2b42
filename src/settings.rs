//! Every knob of a render in one struct, with documented defaults. The scene file's `[render]`
//! table and the CLI flags both map onto it.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

pub use crate::photon_map::Kernel;
pub use crate::scene::LightSampler;

/// Names of the effects plan's parts, as `force` accepts them.
pub const PART_NAMES: [&str; 5] = ["caustic_map", "global_map", "final_gather", "refraction", "shadow_rays"];

/// At most this many photon paths per stored photon asked for (caps scenes where few paths
/// reach a surface the map stores on).
pub const MAX_PATHS_PER_PHOTON: u64 = 256;

/// A map that has stored nothing after this many paths per photon asked stops emitting: its
/// light paths are rarer than one in 16 per photon asked (1.6 million paths for 10⁵ photons),
/// so the rest of [`MAX_PATHS_PER_PHOTON`]'s allowance would store a handful at most, at 15
/// times the cost. A caustic map whose only specular surfaces are window panes that reflect
/// the sun out of the scene spent 5.3 s of a 23.5 s render storing nothing before this.
pub const EMPTY_PATHS_PER_PHOTON: u64 = 16;

/// With the camera's cells ([`Settings::guide_photons`]), a map's target counts only photons
/// stored where the camera reads it, and emission goes on past the path at which the map held
/// its target in all photons for at most this many times as many paths: the map then costs at
/// most twice its unguided paths where the camera reads little of what it stores (the window's
/// global map: 37 % read, the bound reached with 148 000 of 200 000 read; BENCHMARKS.md).
pub const STEERED_PATHS: u64 = 2;

/// Passes a `target_error` render runs before it trusts the spread between passes.
pub const MIN_PASSES_FOR_TARGET: u32 = 4;

/// Default [`Settings::secondary_gather`], in global-map radii (chosen by measurement:
/// BENCHMARKS.md, "Secondary gather").
pub const SECONDARY_GATHER: f32 = 3.0;

/// Which per-pass amounts were given explicitly (by a flag, a sweep knob or a preset); those are
/// used as they are in every pass instead of being spread over the passes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PerPass {
    /// `spp` is per pass.
    pub spp: bool,
    /// `photons` is per pass.
    pub photons: bool,
    /// `caustic_photons` is per pass.
    pub caustic_photons: bool,
}

impl std::ops::BitOr for PerPass {
    type Output = PerPass;
    fn bitor(self, o: PerPass) -> PerPass {
        PerPass {
            spp: self.spp || o.spp,
            photons: self.photons || o.photons,
            caustic_photons: self.caustic_photons || o.caustic_photons,
        }
    }
}

/// The default [`Settings::max_depth`]: high enough that the paths it cuts are a negligible
/// share (counted in `--stats`), where Russian roulette has not ended them.
pub const DEFAULT_MAX_DEPTH: u32 = 64;

/// Render settings. Radii are fractions of the scene's bounding-box diagonal, so that a scene
/// renders the same at any unit scale.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Jittered samples per pixel.
    pub spp: u32,
    /// Photons stored in the global map: exactly this many (emission stops at the path that
    /// stores the last one), unless the cap of paths per photon is reached first.
    pub photons: u32,
    /// Photons stored in the caustic map, exactly as `photons`.
    pub caustic_photons: u32,
    /// Nearest photons per global-map estimate.
    pub k: u32,
    /// Nearest photons per caustic-map estimate.
    pub caustic_k: u32,
    /// Maximum search radius of the global map, as a fraction of the scene diagonal.
    pub global_radius: f32,
    /// Maximum search radius of the caustic map, as a fraction of the scene diagonal.
    pub caustic_radius: f32,
    /// Density-estimation kernel for both maps.
    pub kernel: Kernel,
    /// The code path of BVH traversal and photon lookups: the SIMD kernels (`simd`, the
    /// default) or their scalar twins (`scalar`); the images agree (tests/simd.rs). Named
    /// `kernels` before issue 14; that key is still read.
    #[serde(alias = "kernels")]
    pub code_path: crate::code_path::CodePath,
    /// Final-gather rays per camera sample.
    pub gather_rays: u32,
    /// Final gather (true) or read the global map directly at the first diffuse hit (false).
    pub final_gather: bool,
    /// Final-gather rays that end on a Lambertian surface read irradiance precomputed at every
    /// 4th global photon (Christensen 1999) instead of a full density estimate: one
    /// nearest-neighbour search instead of k. Slightly blurrier, several times faster. Not used
    /// by progressive passes, where it would be biased (see `transport::maps::precompute_irradiance`).
    pub precompute_irradiance: bool,
    /// Jensen's secondary gather: a final-gather ray that lands on a Lambertian surface closer
    /// to its origin than this many global-map radii (the pass's fixed radius in progressive
    /// passes, `global_radius` otherwise), straight from its origin, does not read the global
    /// map there. It takes direct light and the caustic map at that point and continues with one
    /// cosine-weighted bounce that reads the maps where it lands (`transport::gather`). A read
    /// that close averages the light of its disk into the corner the gather leaves, which
    /// brightens dark corners. 0 turns it off.
    pub secondary_gather: f32,
    /// Longest photon path and longest specular chain of a camera path (bounces): a safety cap.
    /// Russian roulette ends paths that lose light (photons at every bounce, camera-side chains
    /// from [`CHAIN_ROULETTE_DEPTH`](crate::transport::specular::CHAIN_ROULETTE_DEPTH) on), so
    /// the default cuts almost nothing, and what it cuts is counted
    /// (`numerics.photon_depth_cut`, `camera_depth_cut`): light trapped between glass and water
    /// (CornellBox-Water) took more than the 10 bounces that were once the default.
    pub max_depth: u32,
    /// Area-light samples per shading point.
    pub light_samples: u32,
    /// Multiple importance sampling of emissive triangles (`transport::mis`): light samples are
    /// weighted by the power heuristic against the final-gather and glossy rays (the path
    /// tracer: its next bounce), which add the emission they hit, weighted likewise. On by
    /// default; `false` leaves emitters to light sampling alone, for comparison.
    pub mis: bool,
    /// How direct light picks each area-light sample's light: by the light tree's bound of its
    /// contribution at the shading point (`tree`, the default) or by power alone (`power`).
    pub light_sampler: LightSampler,
    /// The user's seed: a single render and the first progressive pass draw every random
    /// stream from it; later passes and the pilot pass mix their own from it.
    pub seed: u64,
    /// Worker threads (0 = all cores).
    pub threads: u32,
    /// Parts of the effects plan to force on even where the scene does not need them (for
    /// comparison): any of `caustic_map`, `global_map`, `final_gather`, `refraction`, `shadow_rays`.
    pub force: Vec<String>,
    /// Progressive passes (1 = a single k-nearest-neighbour render). With more, every pass
    /// traces fresh photons and estimates with fixed radii that shrink pass by pass (Knaus &
    /// Zwicker 2011), and the image is the mean of the passes.
    pub passes: u32,
    /// Progressive passes until the image's estimated error — the mean of the pixels' error
    /// bounds (95 % noise half-width plus estimated bias: the `error` layer) over the image mean —
    /// is at most this
    /// (a fraction: 0.01 = 1 %), after at least [`MIN_PASSES_FOR_TARGET`] passes. 0 = off. With
    /// `passes` > 1 the passes cap it; with a time budget, the budget does.
    pub target_error: f32,
    /// Radius reduction of progressive passes: r²ᵢ₊₁ = r²ᵢ·(i + α)/(i + 1). Smaller α shrinks
    /// faster (less bias, more noise).
    pub alpha: f32,
    /// Progressive passes give each pixel its own radius sequence (SPPM's adaptive radii in
    /// Knaus & Zwicker's form): the first radius is the distance to the k-th nearest photon of a
    /// pilot map at the pixel's first non-specular point, so dense caustics stay sharp and
    /// sparse regions smooth. Used for the caustic estimate seen from the camera, and the global
    /// estimate there when final gathering is off; gather and glossy rays use the map's radius.
    /// `false`: one radius per map and pass everywhere.
    pub per_pixel_radii: bool,
    /// Density estimates count only the photons visible from the query point (one short
    /// occlusion ray per candidate photon, both lifted off their surfaces), and a precomputed
    /// irradiance point is read only where visible. No light then reaches through a wall
    /// thinner than the search radius (scenes/hard/thin-wall.toml), at a cost measured in
    /// BENCHMARKS.md. Off by default.
    pub visibility: bool,
    /// Progressive passes' fixed-radius estimates are divided by the part of the kernel's disk
    /// that lies on the query's surface, found from the other surfaces' photons the normal
    /// filter turns away (`photon_map::boundary`) and from the open edges of its flat region
    /// (`scene::open_edges`): edges and corners are not darkened (not with `visibility`, whose
    /// estimates stay plain). On by default; `false` gives the plain estimate, for comparison.
    /// One-pass (k-nearest) estimates are not corrected (measured: no better, BENCHMARKS.md).
    pub boundary_correction: bool,
    /// Adds the diagnostic layers `radius.caustic`, `photons.caustic`, `radius.global` and
    /// `photons.global` to the EXR (`crate::diagnostics`): where the estimates are starved or
    /// blurred. Costs one pass's photon tracing again. Off by default.
    pub diagnostics: bool,
    /// Caustic photons are emitted only toward the bounding spheres of the objects that make
    /// caustics (mirrors, glass, frosted glass, smooth rough metal), their power divided by the
    /// aimed pdf (`transport::aim`): the same caustic map in expectation from far fewer emitted
    /// paths. `false` emits them as the global photons are, for comparison.
    pub aim_caustics: bool,
    /// Before the first photon pass a pilot follows a sample of the camera's paths and of the
    /// global map's photon paths (`transport::guide`): the global map's target then counts only
    /// photons stored where the camera reads it, and its photons leave the lights in proportion
    /// to the power they bring there (a fifth of the choices stay by power), so a sun outside a
    /// lit room does not take its photons. `false`: lights by power, every stored photon counted
    /// (for comparison). The caustic map is never steered.
    pub guide_photons: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            width: 320,
            height: 320,
            spp: 16,
            photons: 200_000,
            caustic_photons: 100_000,
            k: 64,
            caustic_k: 48,
            global_radius: 0.05,
            caustic_radius: 0.015,
            kernel: Kernel::Cone,
            code_path: crate::code_path::CodePath::Simd,
            gather_rays: 16,
            final_gather: true,
            precompute_irradiance: true,
            secondary_gather: SECONDARY_GATHER,
            max_depth: DEFAULT_MAX_DEPTH,
            light_samples: 1,
            mis: true,
            light_sampler: LightSampler::Tree,
            seed: 1,
            threads: 0,
            force: Vec::new(),
            passes: 1,
            target_error: 0.0,
            alpha: 2.0 / 3.0,
            per_pixel_radii: true,
            visibility: false,
            boundary_correction: true,
            diagnostics: false,
            aim_caustics: true,
            guide_photons: true,
        }
    }
}

/// Named amounts of work for a render: samples, photons, gather rays and passes. A preset is
/// applied over the scene file's `[render]` table and under the CLI's flags, and sets only those
/// five knobs (radii, kernel, depth, size, seed and the rest stay as the scene file says).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Preset {
    /// A quick look, several times faster than the defaults: 4 spp, 50 000 global and 25 000
    /// caustic photons, 8 final-gather rays, one pass.
    Preview,
    /// The documented defaults: 16 spp, 200 000 + 100 000 photons, 16 gather rays, one pass.
    Default,
    /// A converged image to measure other renders against (`compare`, `sweep`): 512
    /// progressive passes, each of 4 spp with 100 000 global and 100 000 caustic photons and 16
    /// gather rays — 128 times the default render's camera samples and 256 times its global
    /// photons. `--passes` or `--time` shorten or lengthen it.
    Reference,
}

impl Preset {
    /// Sets the preset's knobs on `settings`; returns the per-pass amounts it fixed (see
    /// `progressive::per_pass`).
    pub fn apply(self, s: &mut Settings) -> PerPass {
        let (spp, photons, caustic_photons, gather_rays, passes) = match self {
            Preset::Preview => (4, 50_000, 25_000, 8, 1),
            Preset::Default => {
                let d = Settings::default();
                (d.spp, d.photons, d.caustic_photons, d.gather_rays, d.passes)
            }
            Preset::Reference => (4, 100_000, 100_000, 16, 512),
        };
        (s.spp, s.photons, s.caustic_photons, s.gather_rays, s.passes) =
            (spp, photons, caustic_photons, gather_rays, passes);
        let per_pass = passes > 1;
        PerPass { spp: per_pass, photons: per_pass, caustic_photons: per_pass }
    }
}

/// Settings given on the command line, each over the scene file's value (`None`: not given).
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    /// `--width`.
    pub width: Option<u32>,
    /// `--height`.
    pub height: Option<u32>,
    /// `--spp`.
    pub spp: Option<u32>,
    /// `--photons`.
    pub photons: Option<u32>,
    /// `--caustic-photons`.
    pub caustic_photons: Option<u32>,
    /// `--k`: both maps' k.
    pub k: Option<u32>,
    /// `--kernel`.
    pub kernel: Option<Kernel>,
    /// `--code-path`.
    pub code_path: Option<crate::code_path::CodePath>,
    /// `--gather-rays`.
    pub gather_rays: Option<u32>,
    /// `--no-final-gather`.
    pub no_final_gather: bool,
    /// `--secondary-gather`.
    pub secondary_gather: Option<f32>,
    /// `--visibility` (turns it on; the scene file may too).
    pub visibility: bool,
    /// `--no-boundary-correction`.
    pub no_boundary_correction: bool,
    /// `--no-aim-caustics`.
    pub no_aim_caustics: bool,
    /// `--no-photon-guide`.
    pub no_photon_guide: bool,
    /// `--no-mis`.
    pub no_mis: bool,
    /// `--light-sampler`.
    pub light_sampler: Option<LightSampler>,
    /// `--diagnostics` (turns them on; the scene file may too).
    pub diagnostics: bool,
    /// `--force`, added to the scene file's.
    pub force: Vec<String>,
    /// `--passes`.
    pub passes: Option<u32>,
    /// `--target-error`.
    pub target_error: Option<f32>,
    /// `--alpha`.
    pub alpha: Option<f32>,
    /// `--max-depth`.
    pub max_depth: Option<u32>,
    /// `--seed`.
    pub seed: Option<u64>,
    /// `--threads`.
    pub threads: Option<u32>,
}

impl Overrides {
    /// The settings of a render, layered: the scene file's `file`, then `preset`'s amounts of
    /// work, then these flags. Not validated: [`crate::job::Job::new`] does that once. Also
    /// returns which amounts are per progressive pass (the preset's and those the flags give).
    #[must_use]
    pub fn layer(&self, file: Settings, preset: Option<Preset>) -> (Settings, PerPass) {
        let mut s = file;
        let from_preset = preset.map(|p| p.apply(&mut s)).unwrap_or_default();
        macro_rules! set {
            ($($f:ident),*) => { $( if let Some(v) = self.$f { s.$f = v; } )* };
        }
        set!(width, height, spp, photons, caustic_photons, gather_rays, max_depth, seed, threads, kernel, code_path);
        set!(passes, alpha, target_error, secondary_gather, light_sampler);
        if let Some(k) = self.k {
            s.k = k;
            s.caustic_k = k;
        }
        s.force.extend(self.force.iter().cloned());
        if self.no_final_gather {
            s.final_gather = false;
        }
        s.visibility |= self.visibility;
        s.diagnostics |= self.diagnostics;
        if self.no_boundary_correction {
            s.boundary_correction = false;
        }
        if self.no_aim_caustics {
            s.aim_caustics = false;
        }
        if self.no_photon_guide {
            s.guide_photons = false;
        }
        if self.no_mis {
            s.mis = false;
        }
        let given = PerPass {
            spp: self.spp.is_some(),
            photons: self.photons.is_some(),
            caustic_photons: self.caustic_photons.is_some(),
        };
        (s, from_preset | given)
    }
}

/// The largest image width or height a render takes, in pixels.
pub const MAX_IMAGE_SIDE: u32 = 16384;

impl Settings {
    /// Rejects values that make no sense, naming the field.
    pub fn validate(&self) -> Result<()> {
        let err = |f: &str, m: &str| Err(Error::setting(f, m));
        if !(1..=MAX_IMAGE_SIDE).contains(&self.width) {
            return err("width", &format!("must be between 1 and {MAX_IMAGE_SIDE}"));
        }
        if !(1..=MAX_IMAGE_SIDE).contains(&self.height) {
            return err("height", &format!("must be between 1 and {MAX_IMAGE_SIDE}"));
        }
        if !(1..=65536).contains(&self.spp) {
            return err("spp", "must be between 1 and 65536");
        }
        if self.photons > 100_000_000 {
            return err("photons", "at most 100 000 000");
        }
        if self.caustic_photons > 100_000_000 {
            return err("caustic_photons", "at most 100 000 000");
        }
        if !(2..=10_000).contains(&self.k) {
            return err("k", "must be between 2 and 10000 (the estimator uses k − 1 photons)");
        }
        if !(2..=10_000).contains(&self.caustic_k) {
            return err("caustic_k", "must be between 2 and 10000");
        }
        if !(self.global_radius > 0.0 && self.global_radius <= 1.0) {
            return err("global_radius", "must be in (0, 1] (fraction of the scene diagonal)");
        }
        if !(self.caustic_radius > 0.0 && self.caustic_radius <= 1.0) {
            return err("caustic_radius", "must be in (0, 1] (fraction of the scene diagonal)");
        }
        if !(0.0..=100.0).contains(&self.secondary_gather) {
            return err("secondary_gather", "must be between 0 (off) and 100 global-map radii");
        }
        if self.final_gather && !(1..=4096).contains(&self.gather_rays) {
            return err("gather_rays", "must be between 1 and 4096 with final gather on");
        }
        if !(1..=1000).contains(&self.max_depth) {
            return err("max_depth", "must be between 1 and 1000");
        }
        if !(1..=1024).contains(&self.light_samples) {
            return err("light_samples", "must be between 1 and 1024");
        }
        if !(1..=10_000_000).contains(&self.passes) {
            return err("passes", "must be between 1 and 10000000");
        }
        if !(self.target_error == 0.0 || (1e-4..1.0).contains(&self.target_error)) {
            return err("target_error", "must be 0 (off) or in [0.0001, 1) (a fraction of the image mean: 0.01 = 1 %)");
        }
        if !(self.alpha > 0.0 && self.alpha < 1.0) {
            return err("alpha", "must be in (0, 1) (2/3 is the usual choice)");
        }
        if self.threads > 1024 {
            return err("threads", "at most 1024");
        }
        if let Some(bad) = self.force.iter().find(|f| !PART_NAMES.contains(&f.as_str())) {
            return Err(Error::setting("force", format!("unknown part `{bad}` (one of {})", PART_NAMES.join(", "))));
        }
        Ok(())
    }

    /// Worker threads to use.
    #[must_use]
    pub fn thread_count(&self) -> usize {
        if self.threads == 0 {
            std::thread::available_parallelism().map_or(1, |n| n.get())
        } else {
            self.threads as usize
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Layering: the scene file's values, then the preset's amounts, then the flags; the amounts
    /// per progressive pass are the preset's (when it is progressive) and those the flags give.
    #[test]
    fn flags_override_the_preset_which_overrides_the_file() {
        let file = Settings { spp: 3, photons: 7_000, seed: 9, k: 20, ..Settings::default() };
        let flags = Overrides { spp: Some(5), k: Some(30), no_final_gather: true, ..Default::default() };
        let (s, given) = flags.layer(file.clone(), Some(Preset::Preview));
        assert_eq!((s.spp, s.photons, s.gather_rays, s.seed), (5, 50_000, 8, 9));
        assert_eq!((s.k, s.caustic_k, s.final_gather), (30, 30, false));
        assert_eq!(given, PerPass { spp: true, photons: false, caustic_photons: false });
        let (s, given) = Overrides::default().layer(file.clone(), Some(Preset::Reference));
        assert_eq!((s.passes, given), (512, PerPass { spp: true, photons: true, caustic_photons: true }));
        assert_eq!(Overrides::default().layer(file.clone(), None).0, file);
    }

    /// The code path's old key still reads.
    #[test]
    fn the_old_kernels_key_still_sets_the_code_path() {
        let s: Settings = toml::from_str("kernels = \"scalar\"").unwrap();
        assert_eq!(s.code_path, crate::code_path::CodePath::Scalar);
        let s: Settings = toml::from_str("code_path = \"scalar\"").unwrap();
        assert_eq!(s.code_path, crate::code_path::CodePath::Scalar);
    }
}
