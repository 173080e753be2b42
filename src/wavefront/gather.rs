//! Gather: photon-map density estimates where lanes reached a diffuse surface — the caustic map
//! for camera, glossy and near-landed gather rays, the global map for the other gather rays
//! (precomputed irradiance where it applies), and the global map without direct and caustic
//! photons for glossy rays and for camera rays when final gathering is off. Reads the diffuse
//! lane list, hits and maps; writes the wave's terms in lane order.

use super::queues::PathKind;
use super::{chunks, CameraWork, Maps, Shared, StageClock, StageStats, GATHER_CHUNK};
use crate::code_path::MortonGrid;
use crate::film::Term;
use crate::material::Bsdf;
use crate::photon_map::query_packet::PACKET;
use crate::photon_map::{Estimate, Nearest};
use crate::scene::SurfacePoint;
use crate::transport::estimate::{
    base_radiance, camera_indirect_estimate, caustic_estimate, indirect_estimate, map_radiance, run_packet,
    FixedLookup, Planned,
};
use crate::transport::Context;
use bevy_ecs::prelude::*;
use glam::Vec3;

/// Runs `estimate(ctx, point, bsdf, wo, kind, pixel, scratch)` at the diffuse hit of every lane
/// whose kind passes `wanted` (`pixel` is the lane's pixel for camera lanes, `None` for
/// others), in sorted units of lanes, and adds `beta × radiance` to the lane's sample in lane order (and
/// `beta × bias` to its bias). `own` is the term of camera lanes (routed to specular behind a
/// mirror or glass); gather and glossy lanes use the term they carry. Returns the number of
/// estimates.
///
/// Fixed-radius lookups the estimate leaves to run go in query packets of 8 neighbours
/// ([`run_packet`]; each estimate is the same as run alone, so grouping changes speed only):
/// gather rays that read the maps land anywhere, so theirs are sorted by the Morton code of their
/// points first; the other lanes' go as they come (neighbouring pixels, and gather rays that
/// landed near their origin, are consecutive lanes).
fn estimate_at_diffuse_hits(
    shared: &Shared,
    maps: &Maps,
    work: &mut CameraWork,
    wanted: impl Fn(PathKind) -> bool,
    own: Term,
    estimate: impl for<'a> Fn(&Context<'a>, &SurfacePoint, &Bsdf, Vec3, PathKind, Option<usize>, &mut Nearest) -> Planned<'a>
        + Sync,
) -> usize {
    let ctx = Context::new(&shared.scene, &maps.0, &shared.job);
    let spp = u64::from(shared.job.settings.spp);
    let w = &mut *work;
    let lanes: Vec<u32> = w.classified.diffuse.iter().copied().filter(|&l| wanted(w.paths.kind[l as usize])).collect();
    // Units large enough that a gather ray's point has close neighbours among the unit's
    // (16 384 points over a Cornell box lie ~1 cm apart), small enough to stay in cache: a
    // quarter of the wave's lanes within those bounds.
    let chunk = lanes.len().div_ceil(4).clamp(GATHER_CHUNK, SORTED_CHUNK);
    let mut scratch = Nearest::default();
    let (mut done, mut deferred) = (Vec::<Lane>::new(), Vec::<(u32, FixedLookup)>::new());
    for r in chunks(lanes.len(), chunk) {
        // The unit's lanes, and its lookups deferred to the sorted packets with the index of
        // their lane in `done`.
        done.clear();
        deferred.clear();
        let mut packet = Packet::default();
        for j in r {
            let i = lanes[j] as usize;
            let Some(hit) = w.paths.hits.get(i) else { continue };
            let sp = ctx.scene.surface(&hit);
            let bsdf = &ctx.scene.bsdf(&sp);
            let kind = w.paths.kind[i];
            let pixel =
                (kind == PathKind::Camera).then(|| ((w.first_sample + u64::from(w.paths.sample[i])) / spp) as usize);
            let planned = estimate(&ctx, &sp, bsdf, -w.paths.rays.direction(i), kind, pixel, &mut scratch);
            let term = match kind {
                PathKind::Camera => own.seen(w.paths.through_specular[i]),
                _ => w.paths.term[i],
            };
            let e = if let Planned::Done(e) = planned { e } else { Estimate::default() };
            done.push(Lane {
                sample: w.paths.sample[i],
                term,
                beta: w.paths.beta[i],
                radiance: e.radiance,
                bias: e.bias,
            });
            match planned {
                Planned::Done(_) => {}
                Planned::Fixed(q) if kind.reads_maps() => deferred.push((done.len() as u32 - 1, q)),
                Planned::Fixed(q) => packet.add(&ctx, q, done.len() - 1, &mut done),
            }
        }
        packet.run(&ctx, &mut done);
        // By Morton code, ties in lane order; the low half is the place in `deferred`. (A packet
        // holds lookups of one map: `Packet::add` runs it when the map changes.)
        let grid = MortonGrid::new(ctx.scene.bounds, 1024);
        let mut order: Vec<u64> =
            deferred.iter().enumerate().map(|(k, (_, q))| u64::from(grid.code(q.lookup.p)) << 32 | k as u64).collect();
        order.sort_unstable();
        for o in &order {
            let (slot, q) = deferred[(o & 0xffff_ffff) as usize];
            packet.add(&ctx, q, slot as usize, &mut done);
        }
        packet.run(&ctx, &mut done);
        for lane in &done {
            let t = &mut w.terms[lane.sample as usize];
            t.add(lane.term, lane.beta * lane.radiance);
            t.bias += lane.beta * lane.bias;
        }
    }
    w.numerics.photons_filtered += ctx.filtered();
    lanes.len()
}

/// Most lanes in one chunk of [`estimate_at_diffuse_hits`], whose gather lookups are sorted and
/// packed together.
const SORTED_CHUNK: usize = 16_384;

/// A lane's sample, term, path weight and estimate (radiance and bias: 44 bytes, where the whole
/// [`Estimate`] made 60; the records of a bounce's ~10⁶ lanes are written once and read once).
#[derive(Clone, Copy)]
struct Lane {
    sample: u32,
    term: Term,
    beta: Vec3,
    radiance: Vec3,
    bias: Vec3,
}

/// Fixed-radius lookups waiting for their query packet, with the lanes their estimates go to.
#[derive(Default)]
struct Packet<'m> {
    lookups: Vec<FixedLookup<'m>>,
    slots: Vec<usize>,
}

impl<'m> Packet<'m> {
    /// Adds `q`, whose estimate goes to `done[slot]`: the packet runs first if `q` reads another
    /// map, and runs once full.
    fn add(&mut self, ctx: &Context, q: FixedLookup<'m>, slot: usize, done: &mut [Lane]) {
        if self.lookups.first().is_some_and(|first| !std::ptr::eq(first.map, q.map)) {
            self.run(ctx, done);
        }
        self.lookups.push(q);
        self.slots.push(slot);
        if self.lookups.len() == PACKET {
            self.run(ctx, done);
        }
    }

    /// Runs the waiting lookups and writes their estimates to their lanes.
    fn run(&mut self, ctx: &Context, done: &mut [Lane]) {
        let mut out = [Estimate::default(); PACKET];
        run_packet(ctx, &self.lookups, &mut out);
        for (&slot, &e) in self.slots.iter().zip(&out) {
            (done[slot].radiance, done[slot].bias) = (e.radiance, e.bias);
        }
        self.lookups.clear();
        self.slots.clear();
    }
}

/// Caustic-map estimates at the diffuse hits of camera, glossy and near-landed gather rays.
pub fn gather_caustics(
    shared: Res<Shared>,
    maps: Res<Maps>,
    mut work: ResMut<CameraWork>,
    mut stats: ResMut<StageStats>,
) {
    let t = StageClock::start();
    let n = estimate_at_diffuse_hits(
        &shared,
        &maps,
        &mut work,
        |kind| !kind.reads_maps(),
        Term::Caustic,
        |ctx, sp, bsdf, wo, _, pixel, scratch| caustic_estimate(ctx, sp, bsdf, wo, pixel, scratch),
    );
    stats.record("gather_caustics", n, t);
}

/// Global-map estimates at diffuse hits: gather rays read the maps' radiance (not those that
/// landed near, whose secondary gather reads them a bounce later); glossy rays, and camera rays
/// when final gathering is off, read the global map without direct and caustic photons (those
/// terms are computed separately). Where gather and glossy rays land on a narrow lobe they read
/// its base, and the lobe's ray reads the maps' radiance where it lands (`transport::lobe`).
pub fn gather_global(
    shared: Res<Shared>,
    maps: Res<Maps>,
    mut work: ResMut<CameraWork>,
    mut stats: ResMut<StageStats>,
) {
    let t = StageClock::start();
    let gather_on = shared.job.plan.final_gather.on;
    let n = estimate_at_diffuse_hits(
        &shared,
        &maps,
        &mut work,
        |kind| match kind {
            PathKind::Camera => !gather_on,
            PathKind::NearGather => false,
            _ => true,
        },
        Term::Indirect,
        |ctx, sp, bsdf, wo, kind, pixel, scratch| {
            // On a narrow lobe gather and glossy rays read the base; the lobe's own ray
            // (`PathKind::Lobe`) reads the rest.
            let narrow = kind != PathKind::Lobe && bsdf.narrow_lobe();
            if kind.reads_maps() && narrow {
                base_radiance(ctx, sp, bsdf, wo, scratch)
            } else if kind.reads_maps() {
                map_radiance(ctx, sp, bsdf, wo, scratch)
            } else if kind == PathKind::Camera || narrow {
                camera_indirect_estimate(ctx, sp, bsdf, wo, pixel, scratch)
            } else {
                indirect_estimate(ctx, sp, bsdf, wo, pixel, scratch)
            }
        },
    );
    stats.record("gather_global", n, t);
}
