//! Photon-map density estimates at a surface point: the caustic and global maps' reflected
//! radiance (k nearest photons, or every photon within a progressive pass's fixed radii,
//! optionally only the visible ones), and the radiance a final-gather ray reads where it lands
//! (precomputed irradiance where that applies). Each returns it [`Planned`]: the map's
//! [`Estimate`], or a fixed-radius lookup left to run alone ([`Planned::finish`]) or in a query
//! packet with its neighbours ([`run_packet`]). With fixed radii the estimate carries its bias
//! too (not with `visibility`, whose estimates are not boundary-corrected either).
//!
//! At a flat-shaded point the map's filter sets aside photons behind the point's plane
//! ([`Filter::plane`]): a parallel surface's — the sunlit ground 1 cm below a room's floor — or a
//! neighbouring face's across a convex crease. Each estimate that met some is completed with
//! those of them visible from the point ([`complete_off_plane`]): the ground's photons are
//! hidden by the floor, a crease's are in plain view. Where none is met (a flat room's own
//! walls, whose photons lie in their planes) no ray is traced.

use super::Context;
use crate::code_path::CodePath;
use crate::material::Bsdf;
use crate::photon_map::boundary::{presence_share, Cut, MAX_EXTRA_CUTS};
use crate::photon_map::query_packet::{RadiusQuery, PACKET};
use crate::photon_map::{
    flags, position_slack, Estimate, Filter, Kernel, Lookup, Nearest, PhotonMap, Reflectance, OFF_PLANE,
};
use crate::scene::{Scene, SurfacePoint};
use glam::Vec3;
use std::sync::atomic::Ordering;

/// A density estimate at a surface point, planned: computed already, or a fixed-radius lookup
/// with reflectance kd/π ([`FixedLookup`]) left to run — alone ([`Planned::finish`]) or with up
/// to 7 others in a query packet that shares one walk of the map ([`run_packet`]).
#[derive(Clone, Copy)]
pub enum Planned<'m> {
    /// The estimate.
    Done(Estimate),
    /// A lookup still to run.
    Fixed(FixedLookup<'m>),
}

/// A fixed-radius estimate (a progressive pass's) whose reflectance is kd/π above the surface
/// (Lambertian, or a glossy material's base), ready to run.
#[derive(Clone, Copy)]
pub struct FixedLookup<'m> {
    /// The map it reads.
    pub map: &'m PhotonMap,
    /// Point, filter, kernel; `r_max` is the fixed radius.
    pub lookup: Lookup,
    /// f for photons arriving above the surface (the filter's normal): kd/π.
    pub value: Vec3,
    /// The triangle the point lies on, whose region's open edges cut the disk.
    pub tri: u32,
    /// Whether the estimate is boundary-corrected ([`crate::settings::Settings::boundary_correction`]).
    pub corrected: bool,
}

impl Planned<'_> {
    /// The estimate: computed now if it was left to run.
    #[inline]
    #[must_use]
    pub fn finish(self, ctx: &Context) -> Estimate {
        match self {
            Planned::Done(e) => e,
            Planned::Fixed(q) => {
                let mut out = [Estimate::default()];
                run_packet(ctx, &[q], &mut out);
                out[0]
            }
        }
    }
}

/// Runs up to [`PACKET`] fixed-radius lookups of one map as a query packet, each estimate into
/// `out` (each identical to the bit to the lookup run alone).
///
/// # Panics
/// If the lookups read different maps, there are more than [`PACKET`], or `out` is shorter.
pub fn run_packet(ctx: &Context, lookups: &[FixedLookup<'_>], out: &mut [Estimate]) {
    let Some(first) = lookups.first() else { return };
    assert!(lookups.iter().all(|q| std::ptr::eq(q.map, first.map)), "one packet, one map");
    let at = |j: usize| lookups.get(j).unwrap_or(first);
    // The cuts are written in place and the queries built from plain arrays: building them from
    // arrays of `Option<([Cut; 4], usize)>` moved each query's cuts twice and took 7 % of
    // `gather_global`'s samples, most of them loads stalled on the stores just made.
    let mut cuts = [[Cut::default(); MAX_EXTRA_CUTS]; PACKET];
    let mut lens = [None; PACKET];
    for (j, q) in lookups.iter().enumerate().filter(|(_, q)| q.corrected) {
        lens[j] = Some(open_edge_cuts(ctx.scene, q.tri, q.lookup.p, q.lookup.r_max, &mut cuts[j]));
    }
    let queries: [RadiusQuery<'_>; PACKET] = std::array::from_fn(|j| {
        let q = at(j);
        RadiusQuery {
            lookup: q.lookup,
            f: Reflectance::Hemisphere { value: q.value, ng: q.lookup.filter.n },
            edges: lens[j].map(|len| &cuts[j][..len]),
        }
    });
    let bias = ctx.fixed.is_some_and(|r| r.bias);
    let n = lookups.len();
    let set = ctx.settings.code_path;
    first.map.estimate_radius_packet(set, &queries[..n], bias, &mut out[..n]);
    for (j, q) in lookups.iter().enumerate() {
        if out[j].off_plane > 0 {
            let f = queries[j].f;
            let fixed = Lookup { k: 0, ..q.lookup };
            out[j] = complete_off_plane(ctx.scene, set, q.map, &fixed, f, out[j], &mut Nearest::default());
        }
    }
    if ctx.scene.has_cut_outs() {
        for (j, q) in lookups.iter().enumerate() {
            out[j] = on_cut_out(ctx.scene, q.tri, q.lookup.p, q.lookup.kernel, out[j]);
        }
    }
    let rejected: u64 = out[..n].iter().map(|e| u64::from(e.rejected)).sum();
    if rejected > 0 {
        ctx.filtered.fetch_add(rejected, Ordering::Relaxed);
    }
}

/// Radiance estimate from `map` at `sp` toward `wo` with `k` photons within `radius`, ignoring
/// photons with any `mask` flag: computed, or (a fixed radius, reflectance kd/π above the
/// surface, no visibility test) planned.
#[allow(clippy::too_many_arguments)]
#[inline]
fn plan_map<'m>(
    ctx: &Context,
    map: &'m PhotonMap,
    k: u32,
    radius: f32,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    mask: u8,
    fixed: Option<f32>,
    base: bool,
    scratch: &mut Nearest,
) -> Planned<'m> {
    if base && !bsdf.has_base() {
        return Planned::Done(Estimate::default());
    }
    let (ng, _) = sp.frame.oriented(wo);
    let lookup = Lookup {
        p: sp.p,
        k: k as usize,
        r_max: radius,
        kernel: ctx.settings.kernel,
        filter: Filter::at(sp.p, ng, mask).with_plane(if sp.flat && !ctx.settings.visibility {
            OFF_PLANE
        } else {
            0.0
        }),
    };
    let prepared = bsdf.prepare(&sp.frame, wo);
    let eval = |wi| if base { prepared.eval_base(wi) } else { prepared.eval(wi) };
    let f = match *bsdf {
        // Lambertian (or a glossy material's base): f = kd/π above the surface, 0 below — no
        // per-photon call.
        Bsdf::Lambert { kd } => Reflectance::Hemisphere { value: kd * std::f32::consts::FRAC_1_PI, ng },
        Bsdf::Glossy { kd, .. } if base => Reflectance::Hemisphere { value: kd * std::f32::consts::FRAC_1_PI, ng },
        _ => Reflectance::PerPhoton(&eval),
    };
    let set = ctx.settings.code_path;
    // Fixed radii (progressive passes) are corrected at edges and corners; k-nearest estimates
    // are not: on CornellBox-Original the correction moved the one-pass image from 0.3 % dark
    // to 0.2 % bright and its 16×16-block error from 1.2 % to 1.6 % (BENCHMARKS.md).
    let bias = ctx.fixed.is_some_and(|r| r.bias);
    let corrected = ctx.settings.boundary_correction;
    let e = match (fixed, ctx.settings.visibility, f) {
        (Some(r), false, Reflectance::Hemisphere { value, .. }) => {
            let lookup = Lookup { r_max: r, ..lookup };
            return Planned::Fixed(FixedLookup { map, lookup, value, tri: sp.tri, corrected });
        }
        (Some(r), false, _) => {
            let mut buf = [Cut::default(); MAX_EXTRA_CUTS];
            let edges = corrected.then(|| open_edge_cuts(ctx.scene, sp.tri, sp.p, r, &mut buf));
            let cuts = edges.map(|len| &buf[..len]);
            let lookup = Lookup { r_max: r, k: 0, ..lookup };
            let e = map.estimate_radius_with(set, &lookup, f, cuts, bias);
            complete_off_plane(ctx.scene, set, map, &lookup, f, e, scratch)
        }
        (None, false, _) => {
            let e = map.estimate(set, &lookup, f, scratch);
            complete_off_plane(ctx.scene, set, map, &lookup, f, e, scratch)
        }
        (fixed, true, _) => {
            let lookup = fixed.map_or(lookup, |r| Lookup { r_max: r, k: 0, ..lookup });
            let visible = photon_visibility(ctx.scene, sp.p, ng, lookup.r_max);
            map.estimate_visible(set, &lookup, f, scratch, &visible)
        }
    };
    if e.rejected > 0 {
        ctx.filtered.fetch_add(u64::from(e.rejected), Ordering::Relaxed);
    }
    if ctx.scene.has_cut_outs() {
        return Planned::Done(on_cut_out(ctx.scene, sp.tri, sp.p, lookup.kernel, e));
    }
    Planned::Done(e)
}

/// `e`, an estimate at `p` on triangle `tri`, divided by the kernel-weighted share of its disk
/// where the surface is present when the triangle's material is cut out
/// ([`presence_share`]): its photons landed only there, so the whole disk's area would dilute
/// the estimate beside holes (a checkerboard mask halved it). Unchanged on other surfaces. The
/// share is taken over the whole disk, apart from any boundary correction's cuts.
#[inline]
fn on_cut_out(scene: &Scene, tri: u32, p: Vec3, kernel: Kernel, e: Estimate) -> Estimate {
    let i = tri as usize;
    let Some(present) = scene.presence_on(i) else { return e };
    let share = presence_share(p, scene.ng[i], e.radius, kernel, present);
    Estimate { radiance: e.radiance / share, bias: e.bias / share, coverage: e.coverage * share, ..e }
}

/// The open edges of the flat region of triangle `tri` within `r` of the point `p` on it, as cuts
/// of the disk of an estimate at `p` written to the front of `cuts` (at most [`MAX_EXTRA_CUTS`]; a
/// region has few), and how many there are.
#[inline]
fn open_edge_cuts(scene: &Scene, tri: u32, p: Vec3, r: f32, cuts: &mut [Cut; MAX_EXTRA_CUTS]) -> usize {
    let mut len = 0;
    for e in scene.open_edges.of(tri) {
        // Distance from the point to the segment.
        let ab = e.b - e.a;
        let t = ((p - e.a).dot(ab) / ab.length_squared().max(f32::MIN_POSITIVE)).clamp(0.0, 1.0);
        if (e.a + ab * t).distance_squared(p) < r * r && len < MAX_EXTRA_CUTS {
            cuts[len] = Cut { point: e.a, inward: e.inward };
            len += 1;
        }
    }
    len
}

/// Completes an estimate `e` of `lookup` (a k-nearest one, or with `lookup.k == 0` a fixed-radius
/// one) that set photons aside off its flat plane ([`Estimate::off_plane`]) with those of them
/// visible from the point
/// ([`off_plane_visibility`]): a k-nearest estimate is made again over the photons on the plane
/// and the visible ones off it (so that the k nearest are counted among those); a fixed-radius
/// one adds the visible ones' kernel sum, divided by the part of the disk the estimate was
/// divided by (their share of the bias estimate is left out). Returns `e` when nothing was set
/// aside.
pub fn complete_off_plane(
    scene: &Scene,
    set: CodePath,
    map: &PhotonMap,
    lookup: &Lookup,
    f: Reflectance<'_>,
    e: Estimate,
    scratch: &mut Nearest,
) -> Estimate {
    if e.off_plane == 0 {
        return e;
    }
    let keep = off_plane_visibility(scene, lookup.p, &lookup.filter);
    if lookup.k > 0 {
        let open = Lookup { filter: Filter { plane: 0.0, ..lookup.filter }, ..*lookup };
        return map.estimate_visible(set, &open, f, scratch, &keep);
    }
    let mut seen = map.off_plane_photons(lookup);
    seen.retain(|&(_, i)| {
        let p = map.photon(i as usize);
        keep(p.position, p.normal)
    });
    let extra = map.estimate_photons(set, lookup, f, &seen);
    Estimate { radiance: e.radiance + extra.radiance / e.coverage, count: e.count + extra.count, off_plane: 0, ..e }
}

/// Whether a photon (position, normal) near the flat point `q` (normal `n`) belongs in its
/// estimate: one in the point's plane (to `plane` of its distance, [`Filter::plane`]) or in
/// front of it always, as the filter keeps them; one behind it only if the segment between them,
/// both lifted off their surfaces, meets nothing. (Tracing the photons in front too — a corner's
/// other wall — cost the modern hall's gather a third of its time and kept fewer of them than
/// the filter does wherever no photon was behind.)
/// The lift is ¾ of the photon's height above the plane (at least 10⁻³ of its distance, and at
/// least the filter's [`Filter::slack`], the points' rounding): enough to clear a convex crease
/// or a curved neighbour between them (a chord dips below a sphere by a quarter of that height),
/// not enough to lift a photon under a floor above it. `filter` is the query's, with its plane.
pub fn off_plane_visibility<'s>(scene: &'s Scene, q: Vec3, filter: &Filter) -> impl Fn(Vec3, Vec3) -> bool + 's {
    let (n, plane, slack) = (filter.n, filter.plane, filter.slack);
    move |p, m| {
        let d = p - q;
        let (h, d2) = (d.dot(n), d.length_squared());
        if h >= 0.0 || h * h <= plane * plane * d2 + slack * slack {
            return true;
        }
        let lift = (0.75 * h.abs()).max(1e-3 * d2.sqrt()).max(slack);
        let from = q + n * lift;
        !scene.occluded(from, p + m * lift - from, 1.0)
    }
}

/// Whether a photon (position, normal) is visible from the point `q` (normal `n`, on the side
/// the estimate looks from), for [`crate::settings::Settings::visibility`]: the segment between them, both lifted
/// off their surfaces by 10⁻³ of the search radius `r` (far below any wall worth stopping light)
/// or by the points' rounding ([`position_slack`]: far from the origin 10⁻³ of a radius can be
/// less than an ulp of a coordinate, and the segment would start inside its own surface),
/// whichever is more, meets nothing.
pub fn photon_visibility(scene: &Scene, q: Vec3, n: Vec3, r: f32) -> impl Fn(Vec3, Vec3) -> bool + '_ {
    let lift = (1e-3 * r).max(position_slack(q, n));
    let from = q + n * lift;
    move |p, m| !scene.occluded(from, p + m * lift - from, 1.0)
}

/// Caustic-map radiance estimate at `sp` toward `wo`; `pixel` when `sp` is a camera path's first
/// non-specular hit (progressive passes may give each pixel its own radius). On a narrow lobe
/// ([`Bsdf::narrow_lobe`]) photons are weighed by the base alone: the lobe's own ray (the
/// camera hit's glossy ray, a landing's lobe ray, `super::lobe`) finds the light that mirrors
/// and glass bring into it.
#[inline]
pub fn caustic_estimate<'a>(
    ctx: &Context<'a>,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    pixel: Option<usize>,
    scratch: &mut Nearest,
) -> Planned<'a> {
    let fixed = ctx.fixed.map(|r| r.caustic_at(pixel));
    let map: &'a PhotonMap = &ctx.maps.caustic;
    let base = bsdf.narrow_lobe();
    plan_map(ctx, map, ctx.settings.caustic_k, ctx.caustic_radius, sp, bsdf, wo, 0, fixed, base, scratch)
}

/// Global-map radiance estimate at `sp` toward `wo`, ignoring photons with any `mask` flag;
/// `pixel` as for [`caustic_estimate`].
#[inline]
pub fn global_estimate<'a>(
    ctx: &Context<'a>,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    mask: u8,
    pixel: Option<usize>,
    scratch: &mut Nearest,
) -> Planned<'a> {
    global_part(ctx, sp, bsdf, wo, mask, pixel, false, scratch)
}

/// [`global_estimate`] weighing photons by the whole BSDF, or (`base`) by the part its glossy
/// ray does not sample.
#[allow(clippy::too_many_arguments)]
#[inline]
fn global_part<'a>(
    ctx: &Context<'a>,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    mask: u8,
    pixel: Option<usize>,
    base: bool,
    scratch: &mut Nearest,
) -> Planned<'a> {
    let fixed = ctx.fixed.map(|r| r.global_at(pixel));
    let map: &'a PhotonMap = &ctx.maps.global;
    plan_map(ctx, map, ctx.settings.k, ctx.global_radius, sp, bsdf, wo, mask, fixed, base, scratch)
}

/// Indirect light at `sp` toward `wo` from the global map alone: its estimate without direct and
/// caustic photons ([`flags::OWN_TERMS`]), whose light other terms compute; `pixel` as for
/// [`caustic_estimate`].
#[inline]
pub fn indirect_estimate<'a>(
    ctx: &Context<'a>,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    pixel: Option<usize>,
    scratch: &mut Nearest,
) -> Planned<'a> {
    global_part(ctx, sp, bsdf, wo, flags::OWN_TERMS, pixel, false, scratch)
}

/// [`indirect_estimate`] at a vertex whose glossy lobe is followed by its own ray (a camera
/// path's, [`crate::transport::gather::glossy_ray`], or a glossy ray's landing on a narrow
/// lobe, `super::lobe`): photons are weighed by the part of the BSDF that ray does not sample (a
/// Phong material's kd/π, a rough plastic's base; nothing for a rough conductor or dielectric),
/// so no path is counted twice.
#[inline]
pub fn camera_indirect_estimate<'a>(
    ctx: &Context<'a>,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    pixel: Option<usize>,
    scratch: &mut Nearest,
) -> Planned<'a> {
    global_part(ctx, sp, bsdf, wo, flags::OWN_TERMS, pixel, true, scratch)
}

/// The global map's whole estimate at `sp` toward `wo` with photons weighed by the base alone:
/// where a gather ray lands on a narrow lobe, whose own ray reads the rest (`super::lobe`).
#[inline]
pub fn base_radiance<'a>(
    ctx: &Context<'a>,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    scratch: &mut Nearest,
) -> Planned<'a> {
    global_part(ctx, sp, bsdf, wo, 0, None, true, scratch)
}

/// Radiance leaving a non-specular point toward `wo` as the photon maps see it: kd/π × the
/// nearest precomputed irradiance for Lambertian surfaces when that is available (and a point
/// with a similar normal lies within the global radius), the full global-map estimate otherwise.
#[inline]
pub fn map_radiance<'a>(
    ctx: &Context<'a>,
    sp: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    scratch: &mut Nearest,
) -> Planned<'a> {
    let irr = &ctx.maps.irradiance;
    // A cut-out surface's points would need the presence around each: its full estimate is read
    // and corrected instead.
    let cut_out = ctx.scene.has_cut_outs() && ctx.scene.materials[sp.material as usize].opacity.is_some();
    if let (Bsdf::Lambert { kd }, false, false) = (bsdf, irr.is_empty(), cut_out) {
        let (ng, _) = sp.frame.oriented(wo);
        let lookup = Lookup {
            p: sp.p,
            k: 1,
            r_max: ctx.global_radius,
            kernel: ctx.settings.kernel,
            // At a flat point, a point off its plane (under a thin floor) is never the nearest.
            filter: Filter::at(sp.p, ng, 0).with_plane(if sp.flat { OFF_PLANE } else { 0.0 }),
        };
        if let Some(&(_, i)) = irr.nearest(ctx.settings.code_path, &lookup, scratch).first() {
            // With visibility on, a point behind a wall is not read: the full estimate below is.
            // (The point's record is decoded only then: decoding it for every gather ray cost 4 %
            // of a one-thread default render.)
            let visible = || {
                let p = irr.photon(i as usize);
                photon_visibility(ctx.scene, sp.p, ng, lookup.r_max)(p.position, p.normal)
            };
            if !ctx.settings.visibility || visible() {
                let radiance = *kd * std::f32::consts::FRAC_1_PI * irr.power(i as usize);
                return Planned::Done(Estimate { radiance, radius: lookup.r_max, ..Default::default() });
            }
        }
    }
    global_part(ctx, sp, bsdf, wo, 0, None, false, scratch)
}
