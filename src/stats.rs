//! The render summary printed at the end and written by `--stats FILE.json`.

use serde::{Deserialize, Serialize};

/// Rays traced, by purpose.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, Eq)]
pub struct RayCounts {
    /// Primary rays and rays continuing camera paths through mirrors and glass.
    pub camera: u64,
    /// Shadow rays toward lights.
    pub shadow: u64,
    /// Final-gather and glossy rays.
    pub gather: u64,
    /// Photon path segments.
    pub photon: u64,
}

impl RayCounts {
    /// All rays.
    #[must_use]
    pub fn total(&self) -> u64 {
        self.camera + self.shadow + self.gather + self.photon
    }
}

impl std::ops::AddAssign for RayCounts {
    fn add_assign(&mut self, o: Self) {
        self.camera += o.camera;
        self.shadow += o.shadow;
        self.gather += o.gather;
        self.photon += o.photon;
    }
}

/// One photon map: whether it was built, why, and what it holds.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(default)]
pub struct MapStats {
    /// Whether the map was built.
    pub built: bool,
    /// Why it was (or was not) built.
    pub reason: String,
    /// Photon paths emitted for it.
    pub emitted: u64,
    /// Photons stored.
    pub stored: u64,
    /// Of those, the photons stored in the medium filling the scene (its volume map).
    pub volume: u64,
    /// Photons stored where the camera reads the map, by the pilot's cells
    /// ([`crate::photon_map::reach`]); all of them in maps built without a camera (no pilot).
    pub read: u64,
    /// Whether the target counted only the photons stored where the camera reads (the photon
    /// guide steered the pass), not every stored one.
    pub steered: bool,
    /// The largest stored photon's power over the median photon's (each photon's largest
    /// channel): 1 where every photon keeps its path's emitted power; a spike shows as a large
    /// ratio. The largest over the passes of a progressive render; 0 for an empty map.
    pub power_max_over_median: f64,
}

impl std::ops::AddAssign<&MapStats> for MapStats {
    /// Adds another pass's counts (progressive renders report totals over their passes, and
    /// the largest power ratio of any pass).
    fn add_assign(&mut self, o: &MapStats) {
        self.emitted += o.emitted;
        self.stored += o.stored;
        self.volume += o.volume;
        self.read += o.read;
        self.steered |= o.steered;
        self.power_max_over_median = self.power_max_over_median.max(o.power_max_over_median);
    }
}

impl MapStats {
    /// A warning when the map holds fewer photons than `asked` in all because its photon pass hit
    /// the cap of [`MAX_PATHS_PER_PHOTON`](crate::settings::MAX_PATHS_PER_PHOTON) paths per
    /// photon asked or stayed empty for
    /// [`EMPTY_PATHS_PER_PHOTON`](crate::settings::EMPTY_PATHS_PER_PHOTON): few light paths
    /// reach the surfaces it stores on, and its estimates are sparse (or, when it is empty,
    /// zero). A guided map that holds its photons in all but fewer where the camera reads (its
    /// steering bounded, [`STEERED_PATHS`](crate::settings::STEERED_PATHS)) is not warned of: it
    /// holds at least the photons there that an unguided one would; the summary gives the share.
    #[must_use]
    pub fn shortfall(&self, name: &str, asked: u64) -> Option<String> {
        use crate::settings::{EMPTY_PATHS_PER_PHOTON, MAX_PATHS_PER_PHOTON};
        // A steered map stops as an empty one when none of its photons lies where the camera reads.
        let empty = if self.steered { self.read == 0 } else { self.stored == 0 };
        (self.built && (self.stored < asked || empty)).then(|| {
            let cap = if empty { EMPTY_PATHS_PER_PHOTON } else { MAX_PATHS_PER_PHOTON };
            let (there, stays) = if self.steered {
                (format!(" ({} where the camera reads it)", self.read), " where the camera reads it")
            } else {
                (String::new(), "")
            };
            format!(
                "{name} map: {} of {asked} photons stored{there} from {} paths, the cap of {cap} per photon asked{} — \
                 few light paths reach the surfaces it stores on{}",
                self.stored,
                self.emitted,
                if empty { format!(" for a map that stays empty{stays}") } else { String::new() },
                match (empty, self.steered) {
                    (false, _) => "",
                    (true, false) => "; it is empty and adds nothing",
                    (true, true) => "; it adds nothing there",
                }
            )
        })
    }
}

/// Values that could not be used, per stage of the pipeline where they were caught. Nothing
/// counted here reaches the film or a photon map.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(default)]
pub struct Numerics {
    /// Load: vertex normals given with zero length, replaced by their face's geometric normal
    /// (non-finite ones are refused with an error naming the line).
    pub load_normals: u64,
    /// Photon emission: paths whose emitted power or direction was not finite, dropped.
    pub photon_emission: u64,
    /// Photon scattering: paths whose power stopped being finite at a bounce, dropped there.
    pub photon_scatter: u64,
    /// Photon scattering: paths whose BSDF sample had zero pdf (a glossy lobe too narrow for
    /// f32), dropped there.
    pub photon_zero_pdf: u64,
    /// Camera: samples with a NaN or infinite term, dropped before the film.
    pub camera_samples: u64,
    /// Film: pixels whose sum of samples overflowed f32, averaged sample by sample instead.
    pub pixel_overflow: u64,
    /// Photon tracing: rays that hit nothing although the geometry is closed around every light
    /// (a leak; counted only in such scenes, where missing everything is impossible).
    pub photon_escaped: u64,
    /// Density estimates: photons within the search radius that the normal filter turned away
    /// (another surface's photons, around a corner or across a thin wall), at shading points;
    /// only those the lookups tested (they skip subtrees whose photons all face away,
    /// `photon_map::orientation`).
    pub photons_filtered: u64,
    /// Photon scattering: bounces whose power would have exceeded the stated bound
    /// ([`POWER_GROWTH_MAX`](crate::transport::photon::POWER_GROWTH_MAX) times the path's
    /// emitted power) and were clamped to it.
    pub photon_power_capped: u64,
    /// Photon paths still going after `max_depth` bounces, cut there (Russian roulette ends
    /// the others; the cut is a safety cap, and what it cuts is a bias this counts).
    pub photon_depth_cut: u64,
    /// Camera-side chains through mirrors and glass (camera, gather and glossy rays) still going
    /// after `max_depth` bounces, cut there.
    pub camera_depth_cut: u64,
}

impl std::ops::AddAssign for Numerics {
    fn add_assign(&mut self, o: Numerics) {
        self.load_normals += o.load_normals;
        self.photon_emission += o.photon_emission;
        self.photon_scatter += o.photon_scatter;
        self.photon_zero_pdf += o.photon_zero_pdf;
        self.camera_samples += o.camera_samples;
        self.pixel_overflow += o.pixel_overflow;
        self.photon_escaped += o.photon_escaped;
        self.photons_filtered += o.photons_filtered;
        self.photon_power_capped += o.photon_power_capped;
        self.photon_depth_cut += o.photon_depth_cut;
        self.camera_depth_cut += o.camera_depth_cut;
    }
}

/// The stages of a load for the summary (` (parse 0.91 s, textures …)`), or nothing where they
/// were not measured.
fn load_stages(l: &crate::scene::LoadTimes) -> String {
    let parts = [
        ("parse", l.parse_s),
        ("textures", l.textures_s),
        ("triangles", l.triangles_s),
        ("BVH", l.bvh_s),
        ("lights", l.lights_s),
        ("edges", l.topology_s),
    ];
    if parts.iter().all(|p| p.1 == 0.0) {
        return String::new();
    }
    let parts: Vec<String> = parts.iter().map(|(name, s)| format!("{name} {s:.2} s")).collect();
    format!(" ({})", parts.join(", "))
}

/// Wall time per phase, seconds.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct PhaseTimes {
    /// Loading and BVH build.
    pub load_s: f64,
    /// Loading by stage (a render from a scene file; zero otherwise, and in summaries written
    /// before it).
    #[serde(default)]
    pub load: crate::scene::LoadTimes,
    /// Global photon pass.
    pub global_photons_s: f64,
    /// Caustic photon pass.
    pub caustic_photons_s: f64,
    /// Building the photon trees.
    pub map_build_s: f64,
    /// Camera pass.
    pub camera_s: f64,
    /// The diagnostic layers' probe (`--diagnostics`), photon tracing included.
    pub diagnostics_s: f64,
    /// Everything.
    pub total_s: f64,
}

/// Everything the summary reports.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(default)]
pub struct RenderStats {
    /// Engine that rendered.
    pub engine: String,
    /// Scene file.
    pub scene: String,
    /// Triangles after dropping degenerate ones.
    pub triangles: usize,
    /// Light sources: each emissive material once, however many triangles it covers
    /// ([`crate::scene::Scene::light_sources`]), and every other light.
    pub lights: usize,
    /// Emissive triangles (each sampled as a light; absent from summaries written before it).
    #[serde(default)]
    pub emissive_triangles: usize,
    /// Image size and sampling.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Worker threads.
    pub threads: usize,
    /// Code path of traversal and photon lookups: simd or scalar.
    pub code_path: String,
    /// Seed.
    pub seed: u64,
    /// The effects plan: each part with whether it ran and why (photon-mapping engines only;
    /// absent from the JSON for the path tracer).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub effects: Option<crate::plan::Effects>,
    /// Global photon map.
    pub global_map: MapStats,
    /// Caustic photon map.
    pub caustic_map: MapStats,
    /// Points with precomputed irradiance (0 when not used).
    pub irradiance_points: u64,
    /// The photon guide's pilot ([`crate::transport::guide`]): what it found, in a line;
    /// absent without one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub guide: Option<String>,
    /// Phases that ran: photon passes, final gather or direct global-map reading, progressive
    /// passes (their count is `progressive.passes`).
    pub phases: Vec<String>,
    /// Rays traced.
    pub rays: RayCounts,
    /// Values caught and dropped (or replaced), per stage.
    pub numerics: Numerics,
    /// Phase times.
    pub times: PhaseTimes,
    /// Per-system runs, lanes and time (wavefront engine).
    pub stages: Option<StageStats>,
    /// How the render used its threads (absent in a merge and where the render was not
    /// metered).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parallel: Option<ParallelStats>,
    /// Traversal kernel per ray queue, chosen by timing the candidates (wavefront engine, SIMD
    /// code path).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub traversal: Vec<crate::traversal_choice::QueueChoice>,
    /// Mean of the beauty image (RGB).
    pub mean_rgb: [f32; 3],
    /// Progressive passes, radii and budget (progressive renders only).
    pub progressive: Option<ProgressiveStats>,
}

impl RenderStats {
    /// Adds `o`'s totals — rays, values caught, photon-pass, map and camera times, photons, and
    /// per-system work — to these (another pass's, or another worker's passes'). The load's count
    /// of replaced normals is the scene's, the same in every pass, and is kept.
    pub fn add_totals(&mut self, o: &RenderStats) {
        self.rays += o.rays;
        let load_normals = self.numerics.load_normals;
        self.numerics += o.numerics;
        self.numerics.load_normals = load_normals;
        self.times.global_photons_s += o.times.global_photons_s;
        self.times.caustic_photons_s += o.times.caustic_photons_s;
        self.times.map_build_s += o.times.map_build_s;
        self.times.camera_s += o.times.camera_s;
        self.global_map += &o.global_map;
        self.caustic_map += &o.caustic_map;
        if let (Some(s), Some(os)) = (self.stages.as_mut(), o.stages.as_ref()) {
            *s += os;
        }
        if self.traversal.is_empty() {
            self.traversal.clone_from(&o.traversal);
        }
    }

    /// The stats of a render about to start: engine, scene size, image and sampling settings.
    #[must_use]
    pub fn new(
        engine: &str,
        scene: &crate::scene::Scene,
        settings: &crate::settings::Settings,
        threads: usize,
    ) -> Self {
        let (lights, emissive_triangles) = scene.light_sources();
        RenderStats {
            engine: engine.into(),
            triangles: scene.triangle_count(),
            lights,
            emissive_triangles,
            width: settings.width,
            height: settings.height,
            spp: settings.spp,
            threads,
            code_path: format!("{:?}", settings.code_path).to_lowercase(),
            seed: settings.seed,
            numerics: Numerics { load_normals: scene.zero_normals, ..Default::default() },
            ..Default::default()
        }
    }

    /// Records which maps the plan builds and why.
    pub fn record_plan(&mut self, plan: &crate::plan::Effects) {
        self.global_map.built = plan.global_map.on;
        self.global_map.reason = plan.global_map.reason.clone();
        self.caustic_map.built = plan.caustic_map.on;
        self.caustic_map.reason = plan.caustic_map.reason.clone();
    }

    /// A human-readable summary (without the per-system table: [`RenderStats::stage_summary`]).
    #[must_use]
    pub fn summary(&self) -> String {
        let t = &self.times;
        let over = self.progressive.as_ref().map_or(String::new(), |p| format!(" in all {} passes", p.passes));
        let map = |name: &str, m: &MapStats| {
            if m.built {
                let per = if m.emitted > 0 { m.stored as f64 / m.emitted as f64 } else { 0.0 };
                let read = match (&self.guide, m.stored) {
                    (Some(_), n) if n > 0 => {
                        format!(", {:.1} % where the camera reads it", 100.0 * m.read as f64 / n as f64)
                    }
                    _ => String::new(),
                };
                let volume = if m.volume > 0 {
                    format!(" ({} of them in the medium, the volume map)", m.volume)
                } else {
                    String::new()
                };
                format!(
                    "  {name:<8} map: {} photons stored{volume} from {} emitted paths{over} ({per:.3} per path){read}\n",
                    m.stored, m.emitted
                )
            } else {
                format!("  {name:<8} map: not built — {}\n", m.reason)
            }
        };
        format!(
            "summary ({} engine, {} code path, {} threads)\n{}{}  rays: {} total ({} camera, {} shadow, {} gather, {} photon)\n  \
             time: load {:.2} s{}, global photons {:.2} s, caustic photons {:.2} s, maps {:.2} s, camera {:.2} s{}, total {:.2} s\n  \
             non-finite values dropped: {} photon emissions, {} photon bounces ({} more with a zero pdf), \
             {} camera samples; \
             {} pixel sums overflowed; {} vertex normals replaced at load; {} photon rays escaped a \
             closed scene; \
             {} photons tested and turned away by the normal filter\n",
            self.engine,
            self.code_path,
            self.threads,
            map("global", &self.global_map),
            map("caustic", &self.caustic_map),
            self.rays.total(),
            self.rays.camera,
            self.rays.shadow,
            self.rays.gather,
            self.rays.photon,
            t.load_s,
            load_stages(&t.load),
            t.global_photons_s,
            t.caustic_photons_s,
            t.map_build_s,
            t.camera_s,
            if t.diagnostics_s > 0.0 { format!(", diagnostics {:.2} s", t.diagnostics_s) } else { String::new() },
            t.total_s,
            self.numerics.photon_emission,
            self.numerics.photon_scatter,
            self.numerics.photon_zero_pdf,
            self.numerics.camera_samples,
            self.numerics.pixel_overflow,
            self.numerics.load_normals,
            self.numerics.photon_escaped,
            self.numerics.photons_filtered,
        ) + &self.guide.as_ref().map_or(String::new(), |g| format!("  photon guide: {g}\n"))
            + &self.progressive_summary()
            + &self.parallel.map_or(String::new(), |p| p.summary() + "\n")
    }

    /// The progressive line: passes, radii, budget.
    #[must_use]
    pub fn progressive_summary(&self) -> String {
        let Some(p) = &self.progressive else { return String::new() };
        let budget =
            p.budget_s.map_or(String::new(), |b| format!(", budget {b:.2} s, finished at {:.2} s", p.elapsed_s));
        let shrink = if p.initial_radii[1] > 0.0 { p.final_radii[1] / p.initial_radii[1] } else { 1.0 };
        let per_pixel = |name: &str, r: Option<[f32; 3]>| {
            r.map_or(String::new(), |[a, b, c]| {
                format!(
                    "\n    per-pixel {name} radii: 10/50/90 % {a:.4} / {b:.4} / {c:.4} → {:.4} / {:.4} / {:.4}",
                    a * shrink,
                    b * shrink,
                    c * shrink
                )
            })
        };
        format!(
            "  progressive: {} passes (α = {:.3}), pilot {:.2} s, radii global {:.4} → {:.4}, caustic {:.4} → {:.4}{budget}{}{}\n{}",
            p.passes,
            p.alpha,
            p.pilot_seconds,
            p.initial_radii[0],
            p.final_radii[0],
            p.initial_radii[1],
            p.final_radii[1],
            per_pixel("caustic", p.pixel_caustic_radii),
            per_pixel("global", p.pixel_global_radii),
            p.error_95.map_or(String::new(), |e| format!(
                "  error: ±{:.2} % of the image mean = noise ±{:.2} % (95 % intervals from the spread between passes) \
                 + bias {:.2} % (estimated from the photons); per pixel in the EXR's `error` layer\n",
                100.0 * e.error,
                100.0 * e.noise,
                100.0 * e.bias
            ))
        )
    }

    /// Per-system lines (wavefront engine): runs, lanes, time and lanes per second.
    #[must_use]
    pub fn stage_summary(&self) -> String {
        let Some(stages) = &self.stages else { return String::new() };
        let mut out = String::from("  stages (runs, lanes, seconds, lanes/s):\n");
        for (name, s) in &stages.0 {
            let rate = if s.seconds > 0.0 { s.items as f64 / s.seconds } else { 0.0 };
            out += &format!("    {name:<18} {:>7} {:>11} {:>8.3} {:>12.0}\n", s.runs, s.items, s.seconds, rate);
        }
        if !self.traversal.is_empty() {
            out += "  traversal per ray queue (chosen by timing the kernels, Mrays/s):\n";
            for c in &self.traversal {
                let speeds: Vec<String> = [
                    ("packets", c.packets_mrays),
                    ("single rays", c.single_mrays),
                    ("8-wide packets", c.wide_packets_mrays),
                ]
                .iter()
                .filter_map(|(name, v)| v.map(|v| format!("{name} {v:.2}")))
                .collect();
                out += &format!("    {:<16} {:<14} ({})\n", c.queue, c.kernel.name(), speeds.join(", "));
            }
        }
        out
    }
}

/// Work done by one system.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct StageStat {
    /// Times the system ran.
    pub runs: u64,
    /// Lanes it processed.
    pub items: u64,
    /// The most lanes one run processed: for the camera pass's stages, the most one worker's
    /// queues held at once (what bounds its memory).
    #[serde(default)]
    pub max_items: u64,
    /// Wall time inside it, summed over the workers that ran it where it runs inside each
    /// worker's own tiles (the camera pass's stages).
    pub seconds: f64,
    /// Its workers' busy time: for a stage that shares its lanes among the threads (the photon
    /// pass's), the chunks' durations summed over threads, over `seconds` × threads its parallel
    /// utilisation; for one run inside a worker's tile (the camera pass's), its `seconds`.
    #[serde(default)]
    pub busy_seconds: f64,
}

/// Per-system counts and times.
#[derive(bevy_ecs::resource::Resource, Default, Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct StageStats(pub std::collections::BTreeMap<String, StageStat>);

impl std::ops::AddAssign<&StageStats> for StageStats {
    /// Adds another render's runs, lanes and times, system by system.
    fn add_assign(&mut self, o: &StageStats) {
        for (name, s) in &o.0 {
            let e = self.0.entry(name.clone()).or_default();
            e.runs += s.runs;
            e.items += s.items;
            e.max_items = e.max_items.max(s.max_items);
            e.seconds += s.seconds;
            e.busy_seconds += s.busy_seconds;
        }
    }
}

/// When a system started: its wall clock and its render's busy time so far
/// ([`crate::parallel::busy_seconds`]).
#[derive(Clone, Copy, Debug)]
pub struct StageClock {
    start: std::time::Instant,
    /// The meter's busy time at the start; `None` on a thread without one (a worker's own
    /// tile, or an unmetered render), where the stage's own wall time is its busy time.
    busy_s: Option<f64>,
}

impl StageClock {
    /// Now.
    #[must_use]
    pub fn start() -> StageClock {
        StageClock { start: std::time::Instant::now(), busy_s: crate::parallel::busy_seconds() }
    }
}

impl StageStats {
    /// Records one run of `system` over `items` lanes since `start`.
    pub fn record(&mut self, system: &str, items: usize, start: StageClock) {
        let e = self.0.entry(system.to_string()).or_default();
        e.runs += 1;
        e.items += items as u64;
        e.max_items = e.max_items.max(items as u64);
        let seconds = start.start.elapsed().as_secs_f64();
        e.seconds += seconds;
        e.busy_seconds += match (start.busy_s, crate::parallel::busy_seconds()) {
            (Some(before), Some(now)) => now - before,
            _ => seconds,
        };
    }
}

/// What a progressive render did (in `--stats` and the summary).
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct ProgressiveStats {
    /// Passes rendered.
    pub passes: u32,
    /// Radius reduction α.
    pub alpha: f32,
    /// First global and caustic radii (scene units).
    pub initial_radii: [f32; 2],
    /// Last pass's global and caustic radii.
    pub final_radii: [f32; 2],
    /// First caustic radii per pixel (10th, 50th, 90th percentile), with per-pixel radii.
    pub pixel_caustic_radii: Option<[f32; 3]>,
    /// First global radii per pixel (10th, 50th, 90th percentile), with per-pixel radii and
    /// final gathering off.
    pub pixel_global_radii: Option<[f32; 3]>,
    /// The error the passes ran until (`target_error`), if one was given.
    pub target_error: Option<f32>,
    /// Time budget in seconds, if one was given.
    pub budget_s: Option<f64>,
    /// Seconds from the caller's start to the last pass's end.
    pub elapsed_s: f64,
    /// Wall time of each pass.
    pub pass_seconds: Vec<f64>,
    /// Wall time of the pilot photon pass and the per-pixel radii.
    pub pilot_seconds: f64,
    /// The image's error estimate after the last pass. `None` before two passes.
    pub error_95: Option<ImageError>,
}

/// A progressive image's error estimate, each part a mean over pixels over the image's mean
/// beauty grey value: `error` = `noise` + `bias`, the mean of the EXR's `error` layer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ImageError {
    /// The error bound: noise plus the bias's size.
    pub error: f64,
    /// The half-width of each pixel's 95 % interval from the spread between passes.
    pub noise: f64,
    /// The size of each pixel's estimated bias (Hachisuka, Jarosz and Jensen 2010).
    pub bias: f64,
}

/// How a render used its threads: the parallel regions' busy time against what its threads
/// could have done (from a [`crate::parallel::Meter`]).
///
/// Read as Amdahl's law: the render's work is `busy_s` on one thread plus `outside_regions_s`
/// that no thread count shortens, so on n threads it takes at least
/// `outside_regions_s + busy_s / n` ([`ParallelStats::amdahl_speedup`]) — a bound, which load
/// imbalance, regions with fewer chunks than threads and memory bandwidth keep it from.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct ParallelStats {
    /// Worker threads the render was given.
    pub threads: usize,
    /// Wall time of the metered render (s): its photon passes, maps and camera pass.
    pub wall_s: f64,
    /// The workers' busy time (s): every chunk's duration, summed over the threads.
    pub busy_s: f64,
    /// Wall time inside parallel regions (s).
    pub in_regions_s: f64,
    /// Wall time outside any parallel region (s): serial work, on one thread whatever the
    /// thread count.
    pub outside_regions_s: f64,
    /// Parallel regions (each a fork and a join where the threads are more than one).
    pub regions: u64,
    /// `busy_s / (threads × wall_s)`, in [0, 1] when the meter is right (not clamped): the
    /// share of the threads' time spent working.
    pub utilisation: f64,
    /// `busy_s / Σ threads × region wall`, in [0, 1] likewise: the same inside the parallel regions only
    /// (what barriers, idle workers and too few chunks cost).
    pub region_utilisation: f64,
}

impl ParallelStats {
    /// The stats of a render that took `wall_s` on `threads` threads, its meter read at the end.
    #[must_use]
    pub fn new(m: crate::parallel::MeterReading, threads: usize, wall_s: f64) -> ParallelStats {
        // Not clamped: a metering fault (busy time above the capacity, regions longer than the
        // render) must show in the figures, and the tests assert they stay in range.
        let threads = threads.max(1);
        let share = |num: f64, den: f64| if den > 0.0 { num / den } else { 0.0 };
        ParallelStats {
            threads,
            wall_s,
            busy_s: m.busy_s,
            in_regions_s: m.in_regions_s,
            outside_regions_s: wall_s - m.in_regions_s,
            regions: m.regions,
            utilisation: share(m.busy_s, threads as f64 * wall_s),
            region_utilisation: share(m.busy_s, m.capacity_s),
        }
    }

    /// Amdahl's bound on the speed-up on `n` threads over one: (serial + work) / (serial +
    /// work / n), the work being the busy time and the serial part the time outside regions.
    #[must_use]
    pub fn amdahl_speedup(&self, n: usize) -> f64 {
        let one = self.outside_regions_s + self.busy_s;
        let many = self.outside_regions_s + self.busy_s / n.max(1) as f64;
        if many > 0.0 {
            one / many
        } else {
            1.0
        }
    }

    /// The summary's line: utilisation, where the time went, and the bound at 16 threads.
    #[must_use]
    pub fn summary(&self) -> String {
        format!(
            "parallel: {} thread{} {:.0} % busy ({:.0} % inside parallel regions; {:.2} s of {:.2} s outside \
             them, {} regions); Amdahl's bound: {:.1}x on 16 threads",
            self.threads,
            if self.threads == 1 { "" } else { "s" },
            100.0 * self.utilisation,
            100.0 * self.region_utilisation,
            self.outside_regions_s,
            self.wall_s,
            self.regions,
            self.amdahl_speedup(16)
        )
    }
}

#[cfg(test)]
mod meter_tests {
    use crate::parallel::{map_chunks, metered, Meter};
    use std::sync::Arc;
    use std::time::{Duration, Instant};

    /// The meter on a workload of known busy time, read raw (no clamp between it and the test):
    /// 4 chunks of a 20 ms sleep on 4 threads, the first of which also starts a nested region
    /// of 8 such chunks on 4 threads (sleeping takes no core, so 4 threads run at once even on 2
    /// cores). The nested region is part of its chunk's time and is neither counted again nor
    /// counted as a region: busy is at least the sleeps' 4 × 20 ms + 2 rounds of the nested 8
    /// on 4 threads (120 ms), it is one region, and busy never exceeds the capacity (4 × the
    /// region's wall) — which counting the nested chunks again (160 ms more, 280 ms against a
    /// capacity of about 4 × 60 ms) would break, as would busy time taken from the wrong clock.
    #[test]
    fn the_meter_counts_known_busy_time_once() {
        let sleep = || std::thread::sleep(Duration::from_millis(20));
        let meter = Arc::new(Meter::default());
        let start = Instant::now();
        let sizes = metered(&meter, || {
            map_chunks(
                4,
                1,
                4,
                |r| {
                    sleep();
                    if r.start == 0 {
                        map_chunks(8, 1, 4, |_| sleep(), |_| {}).len()
                    } else {
                        0
                    }
                },
                |_| {},
            )
        });
        let wall = start.elapsed().as_secs_f64();
        assert_eq!(sizes, [8, 0, 0, 0]);
        let m = meter.reading();
        assert_eq!(m.regions, 1, "{m:?}");
        assert!(m.busy_s >= 0.120, "{m:?}");
        assert!(m.busy_s <= m.capacity_s, "busy above capacity: {m:?}");
        assert!((m.capacity_s - 4.0 * m.in_regions_s).abs() <= 1e-6, "{m:?}");
        assert!(m.in_regions_s <= wall, "{m:?} in {wall} s");
        let p = super::ParallelStats::new(m, 4, wall);
        assert!(p.utilisation > 0.0 && p.utilisation <= 1.0 && p.region_utilisation <= 1.0, "{p:?}");
        assert!(p.outside_regions_s >= 0.0 && (p.in_regions_s + p.outside_regions_s - wall).abs() < 1e-9, "{p:?}");
    }
}
