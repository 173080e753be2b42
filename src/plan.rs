//! The effects plan as a plain record: each part of the machinery, on or off, with the reason.
//! [`crate::effects`] decides it from a scene; `--stats` and the CLI report it.

use crate::error::{Error, Result};
use crate::settings::Settings;
use serde::{Deserialize, Serialize};

/// One part of the plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Part {
    /// Whether it runs.
    pub on: bool,
    /// Why (or why not).
    pub reason: String,
}

impl Part {
    /// A part that is on or off, and why.
    pub(crate) fn new(on: bool, reason: impl Into<String>) -> Self {
        Part { on, reason: reason.into() }
    }

    /// An off part that a plan written by an older photonwave did not record.
    fn not_recorded() -> Self {
        Part::new(false, "not recorded in this plan")
    }
}

/// What to simulate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
    /// Beer–Lambert absorption inside dielectrics with an absorbing interior (absent from plans
    /// written before it existed: read as off).
    #[serde(default = "Part::not_recorded")]
    pub absorption: Part,
    /// Alpha cut-outs: every traversal asks whether a ray passes the hits on cut-out materials
    /// (absent from plans written before it existed: read as off).
    #[serde(default = "Part::not_recorded")]
    pub cut_outs: Part,
    /// Thin glass sheets (window panes) passed in traversal with their transmittance: shadow
    /// rays and photons go straight through (absent from plans written before it existed: read
    /// as off).
    #[serde(default = "Part::not_recorded")]
    pub thin_glass: Part,
    /// A participating medium: free-flight sampling, in-scattering by light sampling and the
    /// phase function (absent from plans written before it existed: read as off).
    #[serde(default = "Part::not_recorded")]
    pub media: Part,
}

impl Effects {
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
            line("absorption", &self.absorption),
            line("cut-outs", &self.cut_outs),
            line("thin glass", &self.thin_glass),
            line("media", &self.media),
        ]
        .concat()
    }
}
