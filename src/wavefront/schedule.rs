//! The recipe: the four schedules (a photon piece and its bounce, a camera wave and its bounce),
//! the order of their systems, their run conditions from the effects plan, and the loops that
//! run a bounce schedule until its queues are empty.

use super::resources::{CameraWork, PhotonWork, Shared};
use super::{absorb, classify, deposit, emit, gather, intersect, shade, Stage};
use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{ExecutorKind, ScheduleLabel};

/// One piece of a photon wave (consecutive paths, [`super::photon_pass`](mod@super::photon_pass)): emit, then the
/// bounce loop.
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
pub struct PhotonPass;
/// One photon bounce.
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
pub struct PhotonBounce;
/// The camera pass for one wave of samples: emit, the bounce loop, resolve.
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
pub struct CameraPass;
/// One camera-pass bounce.
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
pub struct CameraBounce;

// Run conditions from the plan.
fn caustics_on(s: Res<Shared>) -> bool {
    s.job.plan.caustic_map.on
}
fn global_on(s: Res<Shared>) -> bool {
    s.job.plan.global_map.on
}
fn final_gather_on(s: Res<Shared>) -> bool {
    s.job.plan.final_gather.on
}
fn refraction_on(s: Res<Shared>) -> bool {
    s.job.plan.refraction.on
}
fn absorption_on(s: Res<Shared>) -> bool {
    s.job.plan.absorption.on
}
fn shadow_rays_on(s: Res<Shared>) -> bool {
    s.job.plan.shadow_rays.on
}

/// Runs [`PhotonBounce`] until no photon is in flight.
fn run_photon_bounces(world: &mut World) {
    while !world.resource::<PhotonWork>().queue.is_empty() {
        world.run_schedule(PhotonBounce);
        let mut w = world.resource_mut::<PhotonWork>();
        let w = &mut *w;
        std::mem::swap(&mut w.queue, &mut w.next);
        w.next.clear();
    }
}

/// Runs [`CameraBounce`] until no ray and no shadow ray is in flight.
fn run_camera_bounces(world: &mut World) {
    loop {
        let w = world.resource::<CameraWork>();
        if w.paths.is_empty() && w.shadows.is_empty() {
            break;
        }
        world.run_schedule(CameraBounce);
        let mut w = world.resource_mut::<CameraWork>();
        let w = &mut *w;
        std::mem::swap(&mut w.paths, &mut w.next);
        w.next.clear();
    }
}

/// The stages of a bounce, in order.
const STAGES: (Stage, Stage, Stage, Stage, Stage) =
    (Stage::Intersect, Stage::Classify, Stage::Deposit, Stage::Gather, Stage::Shade);

/// The systems of a schedule run one after another in the recipe's order, on the worker's
/// thread (the workers are the parallelism: [`super::IdleWorlds::run_units`]).
fn single_threaded<const N: usize>(mut schedules: [Schedule; N]) -> [Schedule; N] {
    for s in &mut schedules {
        s.set_executor_kind(ExecutorKind::SingleThreaded);
    }
    schedules
}

/// The photon pass's recipe, [`PhotonPass`] and [`PhotonBounce`]: the order of their systems,
/// top to bottom.
#[must_use]
pub fn photon_schedules() -> [Schedule; 2] {
    let mut photon_pass = Schedule::new(PhotonPass);
    photon_pass.add_systems((emit::emit_photons, run_photon_bounces).chain());

    let mut photon_bounce = Schedule::new(PhotonBounce);
    photon_bounce.configure_sets(STAGES.chain());
    photon_bounce.add_systems((
        intersect::intersect_photons.in_set(Stage::Intersect),
        (classify::classify_photons, absorb::absorb_photons.run_if(absorption_on)).chain().in_set(Stage::Classify),
        deposit::deposit_photons.in_set(Stage::Deposit),
        (shade::scatter_photons, shade::refract_photons.run_if(refraction_on)).chain().in_set(Stage::Shade),
    ));
    single_threaded([photon_pass, photon_bounce])
}

/// The camera pass's recipe, [`CameraPass`] and [`CameraBounce`]: the order of their systems,
/// top to bottom.
#[must_use]
pub fn camera_schedules() -> [Schedule; 2] {
    let mut camera_pass = Schedule::new(CameraPass);
    camera_pass.add_systems((emit::emit_camera_rays, run_camera_bounces, shade::resolve_wave).chain());

    let mut camera_bounce = Schedule::new(CameraBounce);
    camera_bounce.configure_sets(STAGES.chain());
    camera_bounce.add_systems((
        (intersect::trace_shadow_rays, intersect::intersect_paths).chain().in_set(Stage::Intersect),
        (
            classify::classify_paths,
            classify::mark_near_gathers.run_if(final_gather_on),
            absorb::absorb_paths.run_if(absorption_on),
        )
            .chain()
            .in_set(Stage::Classify),
        deposit::deposit_emission.in_set(Stage::Deposit),
        (gather::gather_caustics.run_if(caustics_on), gather::gather_global.run_if(global_on))
            .chain()
            .in_set(Stage::Gather),
        (
            shade::shade_direct.run_if(shadow_rays_on),
            shade::spawn_gather_rays.run_if(final_gather_on),
            shade::spawn_glossy_rays,
            shade::spawn_lobe_rays,
            shade::reflect_paths,
            shade::refract_paths.run_if(refraction_on),
        )
            .chain()
            .in_set(Stage::Shade),
    ));

    single_threaded([camera_pass, camera_bounce])
}
