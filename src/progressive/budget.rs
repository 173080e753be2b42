//! Where a time-budgeted render's passes spent their time, and the warning that names it when one
//! pass is too long for the budget. Reads a render's [`RenderStats`] (its phase times, summed over
//! the passes, and the wavefront engine's per-system times); writes nothing.

use crate::stats::RenderStats;

/// The wavefront systems whose work is density estimates (photon-map lookups): the camera
/// pass's reads of the global and caustic maps.
const LOOKUP_SYSTEMS: [&str; 2] = ["gather_global", "gather_caustics"];

/// A share of the passes' time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cost {
    /// Density estimates: reading the photon maps at camera hits and where gather rays land.
    Lookups,
    /// The rest of the camera pass: tracing and shading camera, gather, glossy and shadow rays.
    CameraRays,
    /// The camera pass whole, where it is not split by system (the reference engine).
    CameraPass,
    /// Tracing photons from the lights.
    Photons,
    /// Building the photon trees.
    MapBuilds,
}

impl Cost {
    /// What it is, for a warning.
    fn name(self) -> &'static str {
        match self {
            Cost::Lookups => "photon-map lookups (gather_global, gather_caustics)",
            Cost::CameraRays => "tracing and shading camera, gather and shadow rays",
            Cost::CameraPass => "the camera pass (its photon-map lookups included)",
            Cost::Photons => "tracing photons",
            Cost::MapBuilds => "building the photon maps",
        }
    }

    /// The settings that make it smaller in each pass.
    fn remedy(self) -> &'static str {
        match self {
            Cost::Lookups => {
                "fewer --gather-rays or --spp per pass make fewer lookups, and fewer --photons per pass make each one cheaper"
            }
            Cost::CameraRays | Cost::CameraPass => "lower --spp or --gather-rays per pass",
            Cost::Photons | Cost::MapBuilds => "lower --photons or --caustic-photons per pass",
        }
    }
}

/// The passes' time split into [`Cost`]s (seconds, summed over the passes), largest first. The
/// camera pass is split by its systems' times (summed over the threads that ran them) in
/// proportion, when the engine reports them.
#[must_use]
pub fn costs(stats: &RenderStats) -> Vec<(Cost, f64)> {
    let t = &stats.times;
    let mut out = vec![(Cost::Photons, t.global_photons_s + t.caustic_photons_s), (Cost::MapBuilds, t.map_build_s)];
    let camera = stats.stages.as_ref().map(|s| {
        let camera_systems = s.0.iter().filter(|(name, _)| !name.ends_with("_photons"));
        let lookups = camera_systems.clone().filter(|(name, _)| LOOKUP_SYSTEMS.contains(&name.as_str()));
        (lookups.map(|(_, st)| st.seconds).sum::<f64>(), camera_systems.map(|(_, st)| st.seconds).sum::<f64>())
    });
    match camera {
        Some((lookups, all)) if all > 0.0 => {
            let share = lookups / all;
            out.push((Cost::Lookups, t.camera_s * share));
            out.push((Cost::CameraRays, t.camera_s * (1.0 - share)));
        }
        _ => out.push((Cost::CameraPass, t.camera_s)),
    }
    out.sort_by(|a, b| b.1.total_cmp(&a.1));
    out
}

/// A warning when one pass takes more than 5 % of the budget (the render cannot end within 5 %
/// of it then), naming where the passes' time went and the settings that shorten a pass.
#[must_use]
pub fn budget_warning(stats: &RenderStats) -> Option<String> {
    let p = stats.progressive.as_ref()?;
    let (b, first) = (p.budget_s?, *p.pass_seconds.first()?);
    if first <= 0.05 * b {
        return None;
    }
    let costs = costs(stats);
    let total: f64 = costs.iter().map(|c| c.1).sum();
    let mut message =
        format!("one pass takes {first:.2} s, more than 5 % of the {b:.2} s budget, so the render may end up to half a pass past it");
    if let Some(&(largest, seconds)) = costs.first().filter(|_| total > 0.0) {
        let rest: Vec<String> = costs[1..]
            .iter()
            .filter(|c| c.1 > 0.0)
            .map(|&(c, s)| format!("{} {:.0} %", c.name(), 100.0 * s / total))
            .collect();
        message += &format!(
            "; {:.0} % of the passes' time went to {} ({}): {}",
            100.0 * seconds / total,
            largest.name(),
            rest.join(", "),
            largest.remedy()
        );
    }
    Some(message)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::{PhaseTimes, ProgressiveStats, StageStat, StageStats};

    /// Phase times: global and caustic photons, map builds, camera pass.
    fn phases(global_photons_s: f64, caustic_photons_s: f64, map_build_s: f64, camera_s: f64) -> PhaseTimes {
        PhaseTimes { global_photons_s, caustic_photons_s, map_build_s, camera_s, ..Default::default() }
    }

    fn stats(first_pass: f64, times: PhaseTimes, stages: &[(&str, f64)]) -> RenderStats {
        let stages = (!stages.is_empty()).then(|| {
            StageStats(
                stages
                    .iter()
                    .map(|&(name, seconds)| (name.to_string(), StageStat { seconds, runs: 1, ..Default::default() }))
                    .collect(),
            )
        });
        RenderStats {
            times,
            stages,
            progressive: Some(ProgressiveStats {
                budget_s: Some(10.0),
                pass_seconds: vec![first_pass],
                ..Default::default()
            }),
            ..Default::default()
        }
    }

    /// The hall's split (issue 57: `gather_global` 78 % of the busy time): the warning names the
    /// lookups and the settings that make fewer or cheaper ones, not photons alone.
    #[test]
    fn a_pass_spent_in_lookups_is_named_so() {
        let times = phases(0.2, 0.1, 0.1, 9.6);
        let s = stats(
            1.0,
            times,
            &[("gather_global", 14.0), ("gather_caustics", 1.0), ("intersect_paths", 5.0), ("emit_photons", 3.0)],
        );
        let c = costs(&s);
        assert_eq!(c[0].0, Cost::Lookups);
        // 15 of the camera systems' 20 s: three quarters of the 9.6 s camera pass.
        assert!((c[0].1 - 7.2).abs() < 1e-9, "{c:?}");
        let w = budget_warning(&s).expect("a pass of 10 % of the budget");
        assert!(w.contains("72 % of the passes' time went to photon-map lookups"), "{w}");
        assert!(w.contains("--gather-rays") && w.contains("cheaper"), "{w}");
    }

    /// Photon tracing as the largest cost names the photon counts; a pass within 5 % of the
    /// budget is not warned of.
    #[test]
    fn a_pass_spent_in_photons_names_the_photon_counts() {
        let times = phases(6.0, 2.0, 0.5, 1.5);
        let s = stats(0.8, times.clone(), &[("gather_global", 1.0), ("intersect_paths", 2.0)]);
        let w = budget_warning(&s).unwrap();
        assert!(w.contains("80 % of the passes' time went to tracing photons"), "{w}");
        assert!(w.contains("--caustic-photons"), "{w}");
        assert_eq!(budget_warning(&stats(0.5, times, &[])), None);
    }

    /// Without per-system times (the reference engine) the camera pass is one cost.
    #[test]
    fn an_engine_without_system_times_reports_the_camera_pass_whole() {
        let times = PhaseTimes { global_photons_s: 1.0, camera_s: 3.0, ..Default::default() };
        let c = costs(&stats(1.0, times, &[]));
        assert_eq!(c[0], (Cost::CameraPass, 3.0));
        assert_eq!(c.iter().map(|c| c.1).sum::<f64>(), 4.0);
    }
}
