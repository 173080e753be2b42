//! The effects plan: which of Jensen's terms a scene needs and which machinery they need,
//! decided once from the scene and settings before any work, with a reason for each part.
//! Both engines follow it; the wavefront engine gates its systems on it.

use crate::scene::Scene;
use crate::settings::Settings;

pub use crate::plan::{Effects, Part};
pub use crate::settings::PART_NAMES;

impl Effects {
    /// Plans from the scene's materials and lights and the settings (`force` turns parts on).
    #[must_use]
    pub fn plan(scene: &Scene, settings: &Settings) -> Self {
        let delta = scene.has_delta_surfaces();
        let diffuse = scene.has_diffuse_surfaces();
        let glass = scene.has_glass();
        let forced = |name: &str| settings.force.iter().any(|f| f == name);
        // A medium filling the scene that scatters holds photons as diffuse surfaces do (its
        // volume maps come from the same passes).
        let fog = scene.medium.as_ref().is_some_and(crate::medium::Medium::scatters);
        let into_fog = if fog { "; and into the scattering medium (volumetric caustics)" } else { "" };
        let caustic_map = match (delta, diffuse) {
            (true, false) if fog => Part::new(
                true,
                "mirror or glass surfaces can focus light into the scattering medium (volumetric caustics)",
            ),
            (true, true) => {
                let aimed = match scene.caustic_targets.len() {
                    n if settings.aim_caustics && n > 0 => {
                        format!("; its photons are aimed at {n} specular object{}", if n == 1 { "" } else { "s" })
                    }
                    _ => String::new(),
                };
                Part::new(
                    true,
                    format!(
                        "mirror or glass surfaces (or frosted glass, or metal with roughness below 0.3, which pass \
                         photons on as specular) can focus light onto diffuse surfaces{into_fog}{aimed}"
                    ),
                )
            }
            _ if forced("caustic_map") => Part::new(true, "forced on by the `force` setting"),
            (false, _) => Part::new(false, "no mirror or glass in the scene"),
            (true, false) => Part::new(false, "no diffuse surface to receive caustics"),
        };
        let global_map = if diffuse && fog {
            Part::new(true, "diffuse surfaces reflect indirect light, and the medium scatters it (its volume map)")
        } else if diffuse {
            Part::new(true, "diffuse surfaces reflect indirect light")
        } else if fog {
            Part::new(true, "the medium filling the scene scatters light (its volume map)")
        } else if forced("global_map") {
            Part::new(true, "forced on by the `force` setting")
        } else {
            Part::new(false, "no diffuse or glossy surface in the scene")
        };
        let final_gather = if !global_map.on {
            Part::new(false, "no global map to gather from")
        } else if settings.final_gather {
            let rays = format!("{} cosine-weighted rays per sample read the global map", settings.gather_rays);
            if settings.secondary_gather > 0.0 {
                let near = format!("those landing within {} radii bounce once more", settings.secondary_gather);
                Part::new(true, format!("{rays}; {near} (secondary gather)"))
            } else {
                Part::new(true, rays)
            }
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
        let absorption = if scene.has_absorbing_interiors() {
            Part::new(true, "a dielectric encloses an absorbing interior (Beer–Lambert along the rays inside it)")
        } else {
            Part::new(false, "no dielectric with an absorbing interior")
        };
        let cut_outs = match scene.cut_out_materials() {
            0 => Part::new(false, "no material has an opacity mask"),
            n => Part::new(
                true,
                format!(
                    "{n} material{} cut out by opacity (mask, alphaMode, map_d): every ray passes their transparent texels",
                    if n == 1 { "" } else { "s" }
                ),
            ),
        };
        let thin_glass = thin_glass_part(scene);
        let media = media_part(scene);
        Effects {
            caustic_map,
            global_map,
            final_gather,
            refraction,
            shadow_rays,
            absorption,
            cut_outs,
            thin_glass,
            media,
        }
    }
}

/// The plan's line on thin glass: the sheets every ray passes with their transmittance, and
/// those that stay surfaces (a coloured transmission tint).
fn thin_glass_part(scene: &Scene) -> Part {
    let (passed, tinted) = scene.thin_sheets();
    let plural = |n: usize| if n == 1 { "" } else { "s" };
    let stay = if tinted > 0 {
        format!(
            "; {tinted} with a coloured transmission stay{} surfaces that rays sample, the light through them a caustic",
            if tinted == 1 { "s" } else { "" }
        )
    } else {
        String::new()
    };
    match passed {
        0 if tinted == 0 => Part::new(false, "no thin glass (window panes, thindielectric)"),
        0 => Part::new(false, format!("no clear thin glass{stay}")),
        n => Part::new(
            true,
            format!(
                "{n} thin glass material{} (window panes) let shadow rays, photons and every other ray straight \
                 through with their transmittance: light through them is direct light, not a caustic{stay}",
                plural(n)
            ),
        ),
    }
}

/// The plan's `media` line: on for a scene-filling medium or a dielectric's scattering interior,
/// saying what each engine does with it.
fn media_part(scene: &Scene) -> Part {
    let interiors = scene.materials.iter().filter(|m| m.interior_scattering.is_some()).count();
    let inside = match interiors {
        0 => String::new(),
        n => format!(
            "{n} dielectric{} enclose{} a scattering medium: the path tracer scatters in it, the photon-mapping \
             engines only attenuate by its σ_t",
            if n == 1 { "" } else { "s" },
            if n == 1 { "s" } else { "" }
        ),
    };
    let filling = match &scene.medium {
        None => None,
        Some(m) if !m.scatters() => Some(
            "the scene is filled with a purely absorbing medium: every ray and photon keeps exp(−σ_a·d), no volume \
             map (path tracer and reference engine)"
                .into(),
        ),
        Some(m) => {
            let a = m.albedo();
            Some(format!(
                "the scene is filled with a scattering medium (albedo {:.2}/{:.2}/{:.2}, g {}): free-flight sampling on \
                 every segment; the path tracer scatters by light sampling and the phase function, the reference \
                 engine stores photons that scatter in volume maps and takes single scattering by light sampling, \
                 multiple scattering and volumetric caustics from the maps (not the wavefront engine yet)",
                a.x, a.y, a.z, m.g
            ))
        }
    };
    match (filling, interiors) {
        (None, 0) => Part::new(false, "no participating medium"),
        (None, _) => Part::new(true, inside),
        (Some(f), 0) => Part::new(true, f),
        (Some(f), _) => Part::new(true, format!("{f}; {inside}")),
    }
}
