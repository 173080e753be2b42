//! The effects plan: which of Jensen's terms a scene needs and which machinery they need,
//! decided once from the scene and settings before any work, with a reason for each part.
//! Both engines follow it; the wavefront engine gates its systems on it.

use crate::error::{Error, Result};
use crate::scene::Scene;
use crate::settings::Settings;
use serde::Serialize;

/// One part of the plan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Part {
    /// Whether it runs.
    pub on: bool,
    /// Why (or why not).
    pub reason: String,
}

impl Part {
    fn new(on: bool, reason: impl Into<String>) -> Self {
        Part { on, reason: reason.into() }
    }
}

/// Names accepted by `Settings::force`.
pub const PART_NAMES: [&str; 5] = ["caustic_map", "global_map", "final_gather", "refraction", "shadow_rays"];

/// What to simulate.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Effects {
    /// Caustic photon pass, caustic map and caustic estimates.
    pub caustic_map: Part,
    /// Global photon pass and global map.
    pub global_map: Part,
    /// Final-gather rays (otherwise the global map is read at the first hit).
    pub final_gather: Part,
    /// Refraction through glass.
    pub refraction: Part,
    /// Shadow rays toward lights (direct light).
    pub shadow_rays: Part,
}

impl Effects {
    /// Plans from the scene's materials and lights and the settings (`force` turns parts on).
    #[must_use]
    pub fn plan(scene: &Scene, settings: &Settings) -> Self {
        let delta = scene.has_delta_surfaces();
        let diffuse = scene.has_diffuse_surfaces();
        let glass = scene.has_glass();
        let forced = |name: &str| settings.force.iter().any(|f| f == name);
        let caustic_map = match (delta, diffuse) {
            (true, true) => Part::new(true, "mirror or glass surfaces can focus light onto diffuse surfaces"),
            _ if forced("caustic_map") => Part::new(true, "forced on by the `force` setting"),
            (false, _) => Part::new(false, "no mirror or glass in the scene"),
            (true, false) => Part::new(false, "no diffuse surface to receive caustics"),
        };
        let global_map = if diffuse {
            Part::new(true, "diffuse surfaces reflect indirect light")
        } else if forced("global_map") {
            Part::new(true, "forced on by the `force` setting")
        } else {
            Part::new(false, "no diffuse or glossy surface in the scene")
        };
        let final_gather = if !global_map.on {
            Part::new(false, "no global map to gather from")
        } else if settings.final_gather {
            Part::new(true, format!("{} cosine-weighted rays per sample read the global map", settings.gather_rays))
        } else if forced("final_gather") {
            Part::new(true, "forced on by the `force` setting")
        } else {
            Part::new(false, "final_gather = false: the global map is read at the first hit")
        };
        let refraction = if glass {
            Part::new(true, "the scene has glass")
        } else if forced("refraction") {
            Part::new(true, "forced on by the `force` setting")
        } else {
            Part::new(false, "no glass in the scene")
        };
        let shadow_rays = if diffuse {
            Part::new(
                true,
                format!(
                    "{} light{} can light diffuse surfaces",
                    scene.lights.len(),
                    if scene.lights.len() == 1 { "" } else { "s" }
                ),
            )
        } else if forced("shadow_rays") {
            Part::new(true, "forced on by the `force` setting")
        } else {
            Part::new(false, "no diffuse or glossy surface to light directly")
        };
        Effects { caustic_map, global_map, final_gather, refraction, shadow_rays }
    }

    /// Refuses settings that leave a needed map empty.
    pub fn check(&self, settings: &Settings) -> Result<()> {
        if self.global_map.on && settings.photons == 0 {
            return Err(Error::setting(
                "photons",
                format!("must be > 0: the scene needs a global map ({})", self.global_map.reason),
            ));
        }
        if self.caustic_map.on && settings.caustic_photons == 0 {
            return Err(Error::setting(
                "caustic_photons",
                format!("must be > 0: the scene needs a caustic map ({})", self.caustic_map.reason),
            ));
        }
        Ok(())
    }

    /// The plan as lines for the CLI.
    #[must_use]
    pub fn describe(&self) -> String {
        let line =
            |name: &str, p: &Part| format!("plan: {name:<13} {} — {}\n", if p.on { "on " } else { "off" }, p.reason);
        [
            line("global map", &self.global_map),
            line("caustic map", &self.caustic_map),
            line("final gather", &self.final_gather),
            line("refraction", &self.refraction),
            line("shadow rays", &self.shadow_rays),
        ]
        .concat()
    }
}
