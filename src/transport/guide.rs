//! The photon guide's pilot, run once before a render's first photon pass. It reads the scene,
//! the camera and the job, and writes the job's [`PhotonGuide`], which the photon passes read:
//! their tally's target ([`super::tally`]) and the lights photons leave from
//! ([`super::photon::photon_lights`]).
//!
//! **Where the camera reads.** A sample of the camera's paths, followed through mirrors and
//! glass to their first non-specular points, marks the cells ([`ReadCells`]) where each map is
//! read: the caustic map there, the global map there and where a few final-gather rays from
//! there land. A cell is the map's largest radius wide.
//!
//! **Which lights.** A photon is worth its power only where the camera reads its map. A sun
//! outside a lit room, picked by power, takes most photons and stores them on the roof while
//! the room's estimates starve; their bias grows as their photons thin out (issue 58 measured
//! the room 1.5–6.8 % darker for it). A pilot of [`PILOT_PATHS`] global photon paths, lights
//! picked by power, measures the power `R_g` each light source `g` brings to the marked cells.
//! The global photons then pick a source with probability `(1 − s)·R_g/ΣR + s·Φ_g/ΣΦ`, `s` =
//! [`BY_POWER_SHARE`], and a light within it by power. In proportion to `R_g`, the photons
//! stored where the camera reads carry about equal power, which is what a fixed number of them
//! spends best. The defensive share by power (Hesterberg 1995) keeps a source the pilot saw
//! bring nothing emitting: a photon's power is divided by its light's probability, so every
//! light keeps its expectation whatever the pilot found, and no estimate depends on the cells.
//!
//! The pilot has a seed of its own, mixed from the user's, so it is the same in every pass, at
//! any thread count and on every machine of a divided render.

use super::gather::trace_gather_rays;
use super::photon::{photon_light, trace_path};
use super::specular::{first_non_specular, Chain};
use super::streams::{self, CAMERA_CHAIN_BOUNCE, JITTER_BOUNCE};
use super::tally::Tally;
use super::{Context, PhotonMaps};
use crate::job::{Job, Pass};
use crate::parallel::map_chunks;
use crate::photon_map::reach::{MapGuide, PhotonGuide, ReadCells};
use crate::rng::{mix64, Domain, Sampler};
use crate::sampling::Distribution1D;
use crate::scene::camera::CameraRays;
use crate::scene::{Light, Scene};
use crate::stats::RayCounts;
use crate::texture::luminance;
use glam::Vec3;
use std::sync::Arc;
use std::time::Instant;

/// Camera paths the pilot follows (spread evenly over the image).
pub const PILOT_PIXELS: usize = 16_384;

/// Final-gather rays the pilot traces from each of them.
pub const PILOT_GATHER_RAYS: u32 = 4;

/// Global photon paths the pilot traces.
pub const PILOT_PATHS: usize = 16_384;

/// The share of photon paths whose light stays picked by power.
pub const BY_POWER_SHARE: f64 = 0.2;

/// Mixed into the user's seed for the pilot's streams.
const PILOT_SALT: u64 = 0x5049_4c4f_545f_4755;

/// The cells of `job`'s guide for `domain`'s map (`None` before the pilot or without one).
#[must_use]
pub fn cells(job: &Job, domain: Domain) -> Option<&ReadCells> {
    let g = job.guide.get()?;
    Some(if domain == Domain::CausticPhoton { &g.caustic.cells } else { &g.global.cells })
}

/// Whether `domain`'s map counts only the photons stored where the camera reads it toward its
/// target: the global map's, when the job guides photons and has a guide. The caustic map's
/// photons are aimed at the specular objects already; it counts every stored photon and its
/// lights stay picked by power ([`steers_lights`]).
#[must_use]
pub fn steers(job: &Job, domain: Domain) -> bool {
    steers_lights(job, domain) && cells(job, domain).is_some()
}

/// Whether `domain`'s photons leave the lights by the power they bring where the camera reads:
/// the global map's, when the job guides photons. Not the caustic map's: in the daylight room
/// (window panes reflecting the sun onto the ground outside, 1.5 % of its photons read) the
/// guided choice (the sky's share from 60 to 92 %) stored fewer caustic photons per path, and with
/// its count steered too its pass became 3.4 times dearer; the 60-second render's relMSE rose
/// from 1.81e-3 to 2.79e-3 with both, 2.10e-3 with the choice alone (BENCHMARKS.md). A
/// cost-aware choice (power brought per path traced) would be the next step.
#[must_use]
pub fn steers_lights(job: &Job, domain: Domain) -> bool {
    job.settings.guide_photons && domain == Domain::GlobalPhoton
}

/// The tally of `domain`'s photon pass in `job` for `target` photons: reading the guide's cells,
/// steered by them where [`steers`] says so.
#[must_use]
pub fn tally(job: &Job, domain: Domain, target: u32) -> Tally<'_> {
    Tally::reading(target, cells(job, domain), steers(job, domain))
}

/// Runs the pilot of `job` with camera `rays` once (the passes of a progressive render share
/// it); nothing for a job without photon maps. Returns the guide.
pub fn ensure<'a>(scene: &Scene, rays: &CameraRays, job: &'a Job) -> Option<&'a PhotonGuide> {
    (job.plan.global_map.on || job.plan.caustic_map.on).then(|| job.guide.get_or_init(|| pilot(scene, rays, job)))
}

/// The pilot: cells from the camera's paths, then, when the settings guide photons, the global
/// photons' lights ([`steers_lights`]).
fn pilot(scene: &Scene, rays: &CameraRays, job: &Job) -> PhotonGuide {
    let start = Instant::now();
    let pilot = Job {
        pass: Pass { seed: mix64(job.settings.seed ^ PILOT_SALT), radii: None },
        guide: Arc::default(),
        ..job.clone()
    };
    let (global, caustic) = camera_cells(scene, rays, &pilot);
    let mut guide = PhotonGuide {
        global: MapGuide { cells: global, lights: None },
        caustic: MapGuide { cells: caustic, lights: None },
        summary: String::new(),
    };
    let mut said = Vec::new();
    for (domain, on, name) in [
        (Domain::GlobalPhoton, job.plan.global_map.on, "global"),
        (Domain::CausticPhoton, job.plan.caustic_map.on, "caustic"),
    ] {
        if !on {
            continue;
        }
        let map = if domain == Domain::CausticPhoton { &mut guide.caustic } else { &mut guide.global };
        said.push(format!("{name} map read in {} cells", map.cells.len()));
        if !steers_lights(job, domain) {
            continue;
        }
        if let Some((lights, shares)) = light_choice(scene, &pilot, domain, &map.cells) {
            map.lights = Some(lights);
            said.push(format!("{name} photons from {shares}"));
        }
    }
    guide.summary = format!("{} ({:.2} s)", said.join("; "), start.elapsed().as_secs_f64());
    guide
}

/// The cells where the global and the caustic map are read, from [`PILOT_PIXELS`] camera paths.
fn camera_cells(scene: &Scene, rays: &CameraRays, pilot: &Job) -> (ReadCells, ReadCells) {
    let settings = &pilot.settings;
    let (lo, _) = scene.bounds;
    let diagonal = scene.diagonal();
    // The grid's corner is a non-round number of cells below the scene's, so that walls on the
    // scene's bounds (and the planes a round step from them) lie inside cells, not on their
    // borders, where rounding would mark a cell at one scale and its neighbour at another.
    let cell = |fraction: f32| {
        let width = (fraction * diagonal).max(diagonal * 1e-5).max(f32::MIN_POSITIVE);
        ReadCells::new(lo - Vec3::splat(2.381_966 * width), width)
    };
    let (mut global, mut caustic) = (cell(settings.global_radius), cell(settings.caustic_radius));
    let maps = PhotonMaps::default();
    let ctx = Context::new(scene, &maps, pilot);
    let gather = pilot.plan.final_gather.on;
    // Columns and rows of the pilot's grid over the image, and a grid cell's size in pixels.
    let (width, height) = (settings.width as f32, settings.height as f32);
    let columns = ((PILOT_PIXELS as f32 * width / height).sqrt().ceil() as usize).clamp(1, PILOT_PIXELS);
    let rows = PILOT_PIXELS.div_ceil(columns);
    let cell = (width / columns as f32, height / rows as f32);
    let found = map_chunks(
        PILOT_PIXELS,
        256,
        pilot.threads,
        |range| {
            let mut counts = RayCounts::default();
            range
                .map(|i| {
                    // Stratified over the image whatever its size: a grid of about square cells,
                    // one jittered point in each (a small image gets several per pixel).
                    let s = Sampler::new(pilot.pass.seed, Domain::Camera, i as u64);
                    let (jx, jy) = (s.get(JITTER_BOUNCE, 0), s.get(JITTER_BOUNCE, 1));
                    let (cx, cy) = ((i % columns) as f32, (i / columns) as f32);
                    let (o, d) = rays.ray((cx + jx) * cell.0, (cy + jy) * cell.1);
                    let Some(end) = first_non_specular(&ctx, o, d, &s, CAMERA_CHAIN_BOUNCE, &mut counts) else {
                        return (None, Vec::new());
                    };
                    let (n, _) = end.point.frame.oriented(-end.dir);
                    let mut landed = Vec::new();
                    if gather {
                        let g = s.fork(streams::gather(0));
                        trace_gather_rays(
                            &ctx,
                            &end.point,
                            -end.dir,
                            PILOT_GATHER_RAYS,
                            &g,
                            &mut counts,
                            |chain, _, _, _| {
                                if let Chain::Hit(e) = chain {
                                    landed.push((e.point.p, e.point.frame.oriented(-e.dir).0));
                                }
                            },
                        );
                    }
                    (Some((end.point.p, n)), landed)
                })
                .collect::<Vec<_>>()
        },
        |_| {},
    );
    let (global_on, caustic_on) = (pilot.plan.global_map.on, pilot.plan.caustic_map.on);
    for (first, landed) in found.into_iter().flatten() {
        if let Some((p, n)) = first {
            if caustic_on {
                caustic.mark(p, n);
            }
            if global_on {
                global.mark(p, n);
            }
        }
        for (p, n) in landed.into_iter().filter(|_| global_on) {
            global.mark(p, n);
        }
    }
    (global, caustic)
}

/// Each light's source ([`Scene::light_source_of`]) and the sources' names.
fn light_sources(scene: &Scene) -> (Vec<usize>, Vec<String>) {
    let of_light = scene.light_source_of();
    let mut names = Vec::new();
    for (light, &source) in scene.lights.iter().zip(&of_light) {
        if source < names.len() {
            continue;
        }
        names.push(match light {
            Light::Area { tri, .. } => {
                format!("emitter '{}'", scene.materials[scene.material[*tri as usize] as usize].name)
            }
            Light::Point { .. } => "point light".into(),
            Light::Spot { .. } => "spot light".into(),
            Light::Directional { .. } => "directional light".into(),
            Light::Sun { .. } => "sun".into(),
            Light::Environment => "environment".into(),
        });
    }
    (of_light, names)
}

/// The lights' distribution for `domain`'s photons from [`PILOT_PATHS`] pilot paths, and a
/// line naming each source's share by power and guided; `None` (by power) with one source or
/// when no pilot photon lands in `cells`.
fn light_choice(scene: &Scene, pilot: &Job, domain: Domain, cells: &ReadCells) -> Option<(Distribution1D, String)> {
    let (of_light, names) = light_sources(scene);
    if names.len() < 2 {
        return None;
    }
    let brought = map_chunks(
        PILOT_PATHS,
        1024,
        pilot.threads,
        |range| {
            let mut out = Vec::new();
            range
                .map(|i| {
                    out.clear();
                    trace_path(scene, pilot, domain, i as u64, &mut out);
                    let light = photon_light(scene, pilot, domain, &Sampler::new(pilot.pass.seed, domain, i as u64)).0;
                    let read = out.iter().filter(|p| cells.reads(p.position, p.normal));
                    (light, read.map(|p| f64::from(luminance(p.power))).sum())
                })
                .collect::<Vec<(usize, f64)>>()
        },
        |_| {},
    );
    let mut read = vec![0.0f64; names.len()];
    for (light, power) in brought.into_iter().flatten() {
        read[of_light[light]] += power;
    }
    let mut by_power = vec![0.0f64; names.len()];
    for (light, &source) in of_light.iter().enumerate() {
        by_power[source] += scene.light_power.pmf(light);
    }
    let total: f64 = read.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    let share: Vec<f64> =
        read.iter().zip(&by_power).map(|(r, q)| (1.0 - BY_POWER_SHARE) * r / total + BY_POWER_SHARE * q).collect();
    let weights: Vec<f64> = (0..of_light.len())
        .map(|light| {
            let source = of_light[light];
            let q = by_power[source];
            if q > 0.0 {
                scene.light_power.pmf(light) / q * share[source]
            } else {
                0.0
            }
        })
        .collect();
    let mut order: Vec<usize> = (0..names.len()).collect();
    order.sort_by(|&a, &b| share[b].total_cmp(&share[a]));
    let listed: Vec<String> = order
        .iter()
        .take(4)
        .map(|&g| format!("{} {:.1} % (by power {:.1} %)", names[g], 100.0 * share[g], 100.0 * by_power[g]))
        .collect();
    let more = if names.len() > 4 { format!(" and {} more", names.len() - 4) } else { String::new() };
    Distribution1D::try_new(&weights).map(|d| (d, listed.join(", ") + &more))
}
