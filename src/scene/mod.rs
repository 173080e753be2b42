//! The scene model, in memory: triangles as columns in BVH order, materials, lights and their
//! power distributions, the environment, the camera, the BVH — and what is derived from them
//! once (open edges, caustic targets, checks). Built from [`MeshInput`]s by [`Scene::build`]
//! (`build.rs`); the file readers that make them are [`crate::formats`]'s.

mod build;
pub mod camera;
mod checks;
pub mod environment;
pub mod light;
mod light_choice;
pub mod light_tree;
pub mod open_edges;
pub mod portal;
pub mod targets;

use crate::error::{Error, Result};
use crate::geometry::bvh::TriangleColumns;
use crate::geometry::cut_out::{coverage_sample, CutOut};
use crate::geometry::offset::barycentric_error;
use crate::geometry::triangle::is_degenerate;
use crate::geometry::{in_range, normal_and_area, Bvh, Hit, MAX_COORDINATE};
use crate::material::{Bsdf, Material, NormalMap, Relief, SurfaceFrame};
use crate::optics::thin_pass_probability;
use crate::sampling::Distribution1D;
use crate::texture::luminance;
pub use camera::Camera;
pub use environment::Environment;
use glam::{Vec2, Vec3};
pub use light::{Light, LightPreset, TriangleGeom};
pub use light_tree::{LightSampler, Receiver, DEFENSIVE_SHARE};

/// Triangles of one mesh before the scene is assembled.
#[derive(Clone, Debug, Default)]
pub struct MeshInput {
    /// Where the mesh came from (for messages).
    pub source: String,
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Vertex normals (empty, or one per position; zero where a vertex has none, and then its
    /// face's geometric normal is used).
    pub normals: Vec<Vec3>,
    /// Vertex normals given in the file with zero length (counted, then treated as absent).
    pub zero_normals: u64,
    /// Texture coordinates (empty, or one per position; (0, 0) where a vertex has none).
    pub texcoords: Vec<Vec2>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// Material of each triangle (index into the scene's material table).
    pub material: Vec<u32>,
}

/// A point on a surface, everything shading needs.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// Position.
    pub p: Vec3,
    /// Bound on the rounding error of `p`, per axis.
    pub p_error: Vec3,
    /// Geometric and shading normals (unflipped).
    pub frame: SurfaceFrame,
    /// Material index.
    pub material: u32,
    /// Triangle index.
    pub tri: u32,
    /// Texture coordinates ((0, 0) in a scene without textures).
    pub uv: Vec2,
    /// The triangle is flat-shaded (its vertex normals are its geometric normal): its photons
    /// lie in its plane ([`crate::photon_map::Filter::plane`]).
    pub flat: bool,
}

/// The first of `positions` outside ±[`MAX_COORDINATE`], with its index.
#[must_use]
pub fn first_out_of_range(positions: &[Vec3]) -> Option<(usize, Vec3)> {
    positions.iter().position(|p| !in_range(*p)).map(|k| (k, positions[k]))
}

/// What every reader says of a vertex at `p` outside ±[`MAX_COORDINATE`] (after its mesh's
/// transform), after naming where it is.
#[must_use]
pub fn out_of_range_message(p: Vec3) -> String {
    format!(
        "the vertex lies at {p} (after the mesh's transform), outside ±{MAX_COORDINATE:e}, the range in which \
         photonwave's f32 geometry stays watertight; scale the scene down (`scale` in a scene file; \
         docs/src/bad-input.md, \"Limits\")"
    )
}

/// Where loading a scene spent its time (seconds, wall clock), by stage. The readers fill
/// `parse_s` and `textures_s`; [`Scene::build`] the rest.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct LoadTimes {
    /// Reading the scene and mesh files and their materials (textures not included).
    pub parse_s: f64,
    /// Reading and decoding texture images ([`crate::formats::image::load_texture`]).
    pub textures_s: f64,
    /// Gathering, checking and placing the triangles.
    pub triangles_s: f64,
    /// Building the BVH.
    pub bvh_s: f64,
    /// The lights' power distributions and the light tree.
    pub lights_s: f64,
    /// The meshes' edges: whether the lights are enclosed, open edges, caustic targets.
    pub topology_s: f64,
}

/// An assembled, validated scene.
pub struct Scene {
    /// First vertices (BVH order).
    pub p0: Vec<Vec3>,
    /// Second vertices.
    pub p1: Vec<Vec3>,
    /// Third vertices.
    pub p2: Vec<Vec3>,
    /// Vertex normals per triangle (the geometric normal where the mesh has none).
    pub vn: Vec<[Vec3; 3]>,
    /// Texture coordinates per triangle; empty when no material has a texture.
    pub uv: Vec<[Vec2; 3]>,
    /// Unit geometric normals.
    pub ng: Vec<Vec3>,
    /// Triangle areas.
    pub area: Vec<f32>,
    /// Material per triangle.
    pub material: Vec<u32>,
    /// Material table.
    pub materials: Vec<Material>,
    /// Lights (area lights first, one per emissive triangle; then the scene file's, and
    /// [`Light::Environment`] last when there is an environment).
    pub lights: Vec<Light>,
    /// The environment: radiance at infinity (a constant or a lat-long map).
    pub environment: Option<Environment>,
    /// Lights by power (photon emission).
    pub light_power: Distribution1D,
    /// Indices of area lights in `lights`, and their distribution by power (direct lighting).
    pub area_lights: Vec<u32>,
    /// Distribution over `area_lights` by power.
    pub area_power: Option<Distribution1D>,
    /// The light tree over the emissive triangles ([`light_tree::LightTree`]), and the share of
    /// `area_lights`' power they hold: direct light picks the tree with that probability, else
    /// a sun or the environment by power.
    pub light_tree: Option<(light_tree::LightTree, f64)>,
    /// The suns and the environment among `area_lights`, by power.
    infinite_power: Option<(Vec<u32>, Distribution1D)>,
    /// Indices of delta lights in `lights`.
    pub delta_lights: Vec<u32>,
    /// Indices of suns in `lights` (seen by rays that leave the scene).
    suns: Vec<u32>,
    /// Bounding box of all triangles and lights.
    pub bounds: (Vec3, Vec3),
    /// Where the scene's frame has its origin in the coordinates its files use: every position
    /// in the scene is relative to it (zero for a scene near the origin; a scene far from it is
    /// moved to its centre as it is built, for precision). [`Scene::to_frame`] moves a point or
    /// camera given in the files' coordinates (the command line's `--eye`) into the scene.
    pub origin: Vec3,
    /// Degenerate (zero-area) triangles dropped at load.
    pub dropped_degenerate: usize,
    /// Vertex normals given with zero length (their faces use the geometric normal there).
    pub zero_normals: u64,
    /// Whether the geometry is closed (no edge borders a single triangle) with
    /// every light inside it (point and spot lights, and the front of every emitter) and no
    /// directional light: a photon ray that then hits nothing has leaked through the geometry.
    pub encloses_lights: bool,
    /// Non-fatal observations made while loading.
    pub warnings: Vec<String>,
    /// Edges bordering one triangle, listed per triangle of their flat region.
    pub open_edges: open_edges::OpenEdges,
    /// Bounding spheres of the objects photons pass on as specular: where caustic photons are
    /// aimed.
    pub caustic_targets: Vec<targets::Target>,
    /// Where loading it spent its time.
    pub load_times: LoadTimes,
    /// A participating medium filling the whole scene (the TOML file's `[medium]`), or none:
    /// rendered by the path tracer only so far ([`crate::medium`]).
    pub medium: Option<crate::medium::Medium>,
    bvh: Bvh,
    /// (any passed on as specular by photons, any glass, any non-delta, any absorbing interior,
    /// any normal map, any cut-out, any thin sheet passed in traversal) material on a triangle,
    /// computed once.
    kinds: (bool, bool, bool, bool, bool, bool, bool),
}

impl Scene {
    /// Point `p`, given in the coordinates of the scene's files, in the scene's frame
    /// ([`Scene::origin`]).
    #[must_use]
    pub fn to_frame(&self, p: Vec3) -> Vec3 {
        if self.origin == Vec3::ZERO {
            return p;
        }
        relative_to(p, self.origin)
    }

    /// Camera `c`, placed in the coordinates of the scene's files, in the scene's frame.
    #[must_use]
    pub fn camera_to_frame(&self, c: Camera) -> Camera {
        Camera { eye: self.to_frame(c.eye), target: self.to_frame(c.target), ..c }
    }
}

/// `p` relative to `origin`: the exact difference (in f64), rounded once, so equal points stay
/// equal bit for bit.
fn relative_to(p: Vec3, origin: Vec3) -> Vec3 {
    (p.as_dvec3() - origin.as_dvec3()).as_vec3()
}

/// The bounding box (lo, hi) of `points`; (+∞, −∞) for none.
#[must_use]
pub fn bounds_of<'a>(points: impl Iterator<Item = &'a Vec3>) -> (Vec3, Vec3) {
    points.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)))
}

impl Scene {
    /// Vertex columns for intersection.
    #[must_use]
    pub fn columns(&self) -> TriangleColumns<'_> {
        let cut: Option<&dyn CutOut> = if self.kinds.5 || self.kinds.6 { Some(self) } else { None };
        TriangleColumns { cut, ..TriangleColumns::new(&self.p0, &self.p1, &self.p2) }
    }

    /// The light sources as a user counts them, and the emissive triangles among them: an
    /// emissive material is one source however many triangles it covers (a Mitsuba shape's
    /// emitter gets a material of its own, so each shape is one), every other light one.
    #[must_use]
    pub fn light_sources(&self) -> (usize, usize) {
        let sources = self.light_source_of().into_iter().max().map_or(0, |s| s + 1);
        let triangles = self.lights.iter().filter(|l| matches!(l, Light::Area { .. })).count();
        (sources, triangles)
    }

    /// Each light's source ([`Scene::light_sources`]), numbered in the order of the lights: the
    /// emissive triangles of one material share theirs.
    #[must_use]
    pub fn light_source_of(&self) -> Vec<usize> {
        let mut of_material = std::collections::HashMap::new();
        let mut sources = 0;
        self.lights
            .iter()
            .map(|l| {
                let mut next = || {
                    sources += 1;
                    sources - 1
                };
                match l {
                    Light::Area { tri, .. } => *of_material.entry(self.material[*tri as usize]).or_insert_with(next),
                    _ => next(),
                }
            })
            .collect()
    }

    /// Whether any material the triangles use has an alpha cut-out.
    #[must_use]
    pub fn has_cut_outs(&self) -> bool {
        self.kinds.5
    }

    /// How many materials the triangles use are thin glass sheets: (passed in traversal with
    /// their transmittance, [`Bsdf::thin_pass`]: window panes through which shadow rays and
    /// photons go straight, so light through them is direct light, not a caustic; sampled as
    /// surfaces, for a coloured transmission).
    #[must_use]
    pub fn thin_sheets(&self) -> (usize, usize) {
        if !self.kinds.1 {
            return (0, 0);
        }
        let used = self.materials.iter().zip(self.used_materials()).filter(|(_, u)| *u).map(|(m, _)| m.bsdf);
        used.fold((0, 0), |(p, s), b| match b {
            Bsdf::ThinGlass { passed: true, .. } => (p + 1, s),
            Bsdf::ThinGlass { passed: false, .. } => (p, s + 1),
            _ => (p, s),
        })
    }

    /// How many materials the triangles use have an alpha cut-out ([`crate::material::Opacity`]).
    #[must_use]
    pub fn cut_out_materials(&self) -> usize {
        if !self.kinds.5 {
            return 0;
        }
        self.materials.iter().zip(self.used_materials()).filter(|(m, u)| *u && m.opacity.is_some()).count()
    }

    /// Whether each material is used by some triangle.
    fn used_materials(&self) -> Vec<bool> {
        let mut used = vec![false; self.materials.len()];
        for &m in &self.material {
            used[m as usize] = true;
        }
        used
    }

    /// Closest hit along `o + t·d`, 0 < t < `t_max`.
    #[must_use]
    pub fn intersect(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<Hit> {
        self.bvh.closest(self.columns(), o, d, t_max)
    }

    /// True if anything blocks `o + t·d`, 0 < t < `t_max`.
    #[must_use]
    pub fn occluded(&self, o: Vec3, d: Vec3, t_max: f32) -> bool {
        self.bvh.occluded(self.columns(), o, d, t_max)
    }

    /// The BVH.
    #[must_use]
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// Texture coordinates of triangle `i` at barycentrics `b` ((0, 0) in a scene without
    /// textures).
    #[inline]
    fn uv_at(&self, i: usize, b: [f32; 3]) -> Vec2 {
        match self.uv.get(i) {
            None => Vec2::ZERO,
            Some(t) => t[0] * b[0] + t[1] * b[1] + t[2] * b[2],
        }
    }

    /// How much of triangle `i`'s cut-out surface is present
    /// ([`crate::material::Opacity::presence`]) at a point of its plane, its texture coordinates
    /// extended across the plane affinely (exact on a flat region textured by one affine map,
    /// such as a quad): the triangle's map prepared once, for the many points of a quadrature;
    /// `None` when the triangle's material has no cut-out.
    #[must_use]
    pub fn presence_on(&self, i: usize) -> Option<impl Fn(Vec3) -> f32 + '_> {
        let opacity = self.materials[self.material[i] as usize].opacity.as_ref()?;
        // Without texture coordinates (a constant opacity) every point reads (0, 0).
        let t = self.uv.get(i).copied().unwrap_or([Vec2::ZERO; 3]);
        let (p0, e1, e2) = (self.p0[i], self.p1[i] - self.p0[i], self.p2[i] - self.p0[i]);
        let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let det = d00 * d11 - d01 * d01;
        Some(move |q: Vec3| {
            if !(det.abs() > 0.0) {
                return opacity.presence(t[0]);
            }
            let d = q - p0;
            let (d20, d21) = (d.dot(e1), d.dot(e2));
            let (s, v) = ((d11 * d20 - d01 * d21) / det, (d00 * d21 - d01 * d20) / det);
            opacity.presence(t[0] + (t[1] - t[0]) * s + (t[2] - t[0]) * v)
        })
    }

    /// The surface point of a hit.
    #[must_use]
    pub fn surface(&self, hit: &Hit) -> SurfacePoint {
        let i = hit.tri as usize;
        let b = hit.b;
        let (a, bb, c) = (self.p0[i], self.p1[i], self.p2[i]);
        let p = a * b[0] + bb * b[1] + c * b[2];
        let n = self.vn[i];
        let mut ns = (n[0] * b[0] + n[1] * b[1] + n[2] * b[2]).try_normalize().unwrap_or(self.ng[i]);
        let uv = self.uv_at(i, b);
        if self.kinds.4 && !self.uv.is_empty() {
            if let Some(map) = &self.materials[self.material[i] as usize].normal_map {
                ns = self.mapped_normal(i, ns, uv, map);
            }
        }
        SurfacePoint {
            p,
            p_error: barycentric_error(b, a, bb, c),
            frame: SurfaceFrame { ng: self.ng[i], ns },
            material: self.material[i],
            tri: hit.tri,
            uv,
            flat: n == [self.ng[i]; 3],
        }
    }

    /// The shading normal of triangle `i` at texture coordinates `uv` under normal map `map`
    /// ([`NormalMap`]), `n` the interpolated normal. Unchanged where the triangle's texture
    /// coordinates are degenerate (no u direction) or the map's normal points into the surface.
    #[cold]
    #[inline(never)]
    fn mapped_normal(&self, i: usize, n: Vec3, uv: Vec2, map: &NormalMap) -> Vec3 {
        let t = self.uv[i];
        let (e1, e2) = (self.p1[i] - self.p0[i], self.p2[i] - self.p0[i]);
        let (d1, d2) = (t[1] - t[0], t[2] - t[0]);
        let det = d1.x * d2.y - d1.y * d2.x;
        if det == 0.0 || !det.is_finite() {
            return n;
        }
        let dpdu = (e1 * d2.y - e2 * d1.y) / det;
        let dpdv = (e2 * d1.x - e1 * d2.x) / det;
        if map.relief == Relief::Heights {
            let (gu, gv) = map.texture.gradient(uv);
            let du = dpdu + n * (map.scale * luminance(gu) - n.dot(dpdu));
            let dv = dpdv + n * (map.scale * luminance(gv) - n.dot(dpdv));
            let Some(bumped) = du.cross(dv).try_normalize() else { return n };
            return if bumped.dot(self.ng[i]) < 0.0 { -bumped } else { bumped };
        }
        let Some(s) = (dpdu - n * n.dot(dpdu)).try_normalize() else { return n };
        let mut tangent_v = n.cross(s);
        if map.handed && dpdu.cross(dpdv).dot(n) < 0.0 {
            tangent_v = -tangent_v;
        }
        let m = map.texture.lookup(uv) * 2.0 - Vec3::ONE;
        if !(m.z > 0.0) {
            return n;
        }
        (s * (m.x * map.scale) + tangent_v * (m.y * map.scale) + n * m.z).try_normalize().unwrap_or(n)
    }

    /// The scattering at a surface point: its material's BSDF with any textures read at the
    /// point ([`Material::bsdf_at`]). Both engines, the photons and the path tracer read it here.
    #[inline]
    #[must_use]
    pub fn bsdf(&self, sp: &SurfacePoint) -> Bsdf {
        let m = &self.materials[sp.material as usize];
        if self.uv.is_empty() {
            m.bsdf
        } else {
            m.bsdf_at(sp.uv)
        }
    }

    /// Geometry of triangle `i` for area lights.
    #[must_use]
    pub fn triangle(&self, i: u32) -> TriangleGeom {
        let i = i as usize;
        TriangleGeom { p: [self.p0[i], self.p1[i], self.p2[i]], n: self.ng[i], area: self.area[i] }
    }

    /// The triangle geometry a light needs (area lights only).
    #[must_use]
    pub fn light_triangle(&self, light: &Light) -> Option<TriangleGeom> {
        match light {
            Light::Area { tri, .. } => Some(self.triangle(*tri)),
            _ => None,
        }
    }

    /// The light of emissive triangle `tri`: its index in `lights`, which is also its index in
    /// `area_lights` and `area_power` (area lights come first, in triangle order). `None` for a
    /// triangle that emits nothing.
    #[must_use]
    pub fn area_light_of(&self, tri: u32) -> Option<usize> {
        let k = self.lights.partition_point(|l| matches!(l, Light::Area { tri: t, .. } if *t < tri));
        matches!(self.lights.get(k), Some(Light::Area { tri: t, .. }) if *t == tri).then_some(k)
    }

    /// Length of the bounding-box diagonal.
    #[must_use]
    pub fn diagonal(&self) -> f32 {
        (self.bounds.1 - self.bounds.0).length().max(f32::MIN_POSITIVE)
    }

    /// Centre of the bounding box.
    #[must_use]
    pub fn centre(&self) -> Vec3 {
        0.5 * (self.bounds.0 + self.bounds.1)
    }

    /// Bounding box of the triangles alone (without the lights of `bounds`): what a fitted camera
    /// frames.
    #[must_use]
    pub fn mesh_bounds(&self) -> (Vec3, Vec3) {
        bounds_of(self.p0.iter().chain(&self.p1).chain(&self.p2))
    }

    /// Radius of the bounding sphere around the box centre.
    #[must_use]
    pub fn radius(&self) -> f32 {
        0.5 * self.diagonal()
    }

    /// Total emitted power per channel.
    #[must_use]
    pub fn total_power(&self) -> Vec3 {
        self.lights.iter().map(|l| self.light_power_of(l)).sum()
    }

    /// The power light `l` emits into the scene (W per channel).
    #[must_use]
    pub fn light_power_of(&self, l: &Light) -> Vec3 {
        match (l, &self.environment) {
            (Light::Environment, Some(env)) => env.power(self.radius()),
            _ => l.power(self.light_triangle(l).as_ref(), self.radius()),
        }
    }

    /// Samples light `l` arriving at `p`, a surface point with unit normal `n` (on the side light
    /// is wanted from), with two uniform numbers ([`Light::sample_incident`]). The environment is
    /// sampled half by its map ([`Environment::sample`]) and half cosine-weighted about `n`, with
    /// the pdf of the mixture (the balance heuristic of the two): a face that does not see a
    /// bright sun in the map still gets half of its samples where its own sky is.
    #[must_use]
    pub fn sample_incident(&self, l: &Light, p: Vec3, n: Vec3, u: [f32; 2]) -> Option<light::Incident> {
        match (l, &self.environment) {
            (Light::Environment, Some(env)) => {
                let wi = if u[0] < 0.5 {
                    let local = crate::sampling::cosine_hemisphere([(2.0 * u[0]).min(1.0), u[1]]);
                    crate::sampling::Frame::new(n).to_world(local)
                } else {
                    env.sample_from(p, [(2.0 * u[0] - 1.0).min(crate::sampling::ONE_BELOW), u[1]])?
                };
                let (radiance, map_pdf) = env.radiance_pdf(wi);
                let env_pdf = env.sampling_pdf(p, wi, || map_pdf);
                let pdf = 0.5 * wi.dot(n).max(0.0) * std::f32::consts::FRAC_1_PI + 0.5 * env_pdf;
                (pdf > 0.0 && wi.is_finite()).then(|| light::Incident {
                    wi,
                    value: radiance / pdf,
                    pdf,
                    distance: f32::INFINITY,
                    point: None,
                    point_error: Vec3::ZERO,
                })
            }
            (Light::Area { tri, .. }, _) if self.textured_emitter(*tri) => {
                // The sample's point and density as for a constant emitter, its radiance read
                // from the texture where it lands: L(q)/pdf.
                let t = self.triangle(*tri);
                let mut inc = l.sample_incident(Some(&t), p, u)?;
                let (q, _) = inc.point?;
                inc.value = self.emitted_at(*tri, self.barycentrics(*tri, q)) / inc.pdf;
                Some(inc)
            }
            _ => l.sample_incident(self.light_triangle(l).as_ref(), p, u),
        }
    }

    /// Samples a photon leaving light `l` with four uniform numbers ([`Light::sample_emission`];
    /// the environment's from a disk of the scene's radius across a direction picked by the
    /// map's importance: power L·π r²/pdf; with portals, through them for
    /// [`PORTAL_PHOTON_SHARE`] of its photons, along lines [`portal::Portals::sample_line`] draws).
    #[must_use]
    pub fn sample_emission(&self, l: &Light, u: [f32; 4]) -> light::Emission {
        let (centre, radius) = (self.centre(), self.radius());
        match (l, &self.environment) {
            (Light::Environment, Some(env)) if !env.portals().is_empty() => self.portal_photon(env, u),
            (Light::Environment, Some(env)) => {
                let Some((wi, pdf, radiance)) = env.sample([u[0], u[1]]) else {
                    return light::Emission { origin: centre, direction: Vec3::Y, power: Vec3::ZERO, normal: None };
                };
                let power = radiance * (std::f32::consts::PI * radius * radius) / pdf;
                light::Emission { origin: self.disk_origin(wi, [u[2], u[3]]), direction: -wi, power, normal: None }
            }
            (Light::Area { tri, .. }, _) if self.textured_emitter(*tri) => {
                let t = self.triangle(*tri);
                let mut em = l.sample_emission(Some(&t), (centre, radius), u);
                em.power = self.emitted_at(*tri, self.barycentrics(*tri, em.origin)) * (std::f32::consts::PI * t.area);
                em
            }
            _ => l.sample_emission(self.light_triangle(l).as_ref(), (centre, radius), u),
        }
    }

    /// Where a photon of light from direction `wi` (unit, away from the scene) starts: a point
    /// uniform on the disk of the scene's radius across `wi` (two uniform numbers), moved 2 r
    /// out along `wi`, outside the scene.
    fn disk_origin(&self, wi: Vec3, u: [f32; 2]) -> Vec3 {
        let (dx, dy) = crate::sampling::concentric_disk(u);
        let f = crate::sampling::Frame::new(wi);
        let radius = self.radius();
        self.centre() + (f.s * dx + f.t * dy) * radius + wi * (2.0 * radius)
    }

    /// An environment photon in a scene with portals: with probability [`PORTAL_PHOTON_SHARE`]
    /// (from `u[2]`, remapped) its line is drawn through a portal
    /// ([`portal::Portals::sample_line`]),
    /// otherwise across the scene's disk as without portals; either way it starts outside the
    /// scene, on the disk's plane, and carries L(−ω) over the mixture's density at its line per
    /// steradian and unit area across it: share·(portal lines' density) + (1 − share)·(map pdf
    /// of −ω)/(π r²) (the disk's, for a line within r of the centre). Unbiased for every line,
    /// through a portal or not.
    fn portal_photon(&self, env: &Environment, u: [f32; 4]) -> light::Emission {
        use std::f32::consts::PI;
        let (centre, radius) = (self.centre(), self.radius());
        let dark = light::Emission { origin: centre, direction: Vec3::Y, power: Vec3::ZERO, normal: None };
        let share = PORTAL_PHOTON_SHARE;
        let (origin, dir) = if u[2] < share {
            let Some((y, w)) = env.portals().sample_line([u[0], u[1], u[2] / share, u[3]]) else { return dark };
            (y - w * ((y - centre).dot(w) + 2.0 * radius), w)
        } else {
            let u2 = ((u[2] - share) / (1.0 - share)).min(crate::sampling::ONE_BELOW);
            let Some(wi) = env.sample_direction([u[0], u[1]]) else { return dark };
            (self.disk_origin(wi, [u2, u[3]]), -wi)
        };
        let (radiance, map_pdf) = env.radiance_pdf(-dir);
        let across = (centre - origin).reject_from_normalized(dir).length();
        let disk = if across <= radius * (1.0 + 1e-5) { map_pdf / (PI * radius * radius) } else { 0.0 };
        let density = share * env.portals().line_density(origin, dir) + (1.0 - share) * disk;
        if !(density > 0.0) || !dir.is_finite() {
            return dark;
        }
        light::Emission { origin, direction: dir, power: radiance / density, normal: None }
    }

    /// Radiance emitted from the front of triangle `tri` at barycentrics `b` (the emission
    /// texture read there, or the constant emission).
    #[must_use]
    pub fn emitted_at(&self, tri: u32, b: [f32; 3]) -> Vec3 {
        let i = tri as usize;
        let m = &self.materials[self.material[i] as usize];
        match self.uv.get(i) {
            Some(t) if m.maps.ke.is_some() => m.emission_at(t[0] * b[0] + t[1] * b[1] + t[2] * b[2]),
            _ => m.emission,
        }
    }

    /// Whether triangle `tri`'s emission comes from a texture.
    #[must_use]
    pub fn textured_emitter(&self, tri: u32) -> bool {
        !self.uv.is_empty() && self.materials[self.material[tri as usize] as usize].maps.ke.is_some()
    }

    /// The barycentrics of point `q` of triangle `tri`.
    fn barycentrics(&self, tri: u32, q: Vec3) -> [f32; 3] {
        // In f64: |n|² of a large or thin triangle overflows or underflows f32.
        let i = tri as usize;
        let (a, b, c, q) = (self.p0[i].as_dvec3(), self.p1[i].as_dvec3(), self.p2[i].as_dvec3(), q.as_dvec3());
        let n = (b - a).cross(c - a);
        let n2 = n.length_squared();
        if !(n2 > 0.0) {
            return [1.0 / 3.0; 3];
        }
        let b1 = (q - a).cross(c - a).dot(n) / n2;
        let b2 = (b - a).cross(q - a).dot(n) / n2;
        [(1.0 - b1 - b2) as f32, b1 as f32, b2 as f32]
    }

    /// Radiance reaching a ray that leaves the scene in direction `d`: the environment's and
    /// the sun's. Zero in a scene lit by neither.
    #[must_use]
    pub fn background(&self, d: Vec3) -> Vec3 {
        let d = d.normalize_or(Vec3::Y);
        let env = self.environment.as_ref().map_or(Vec3::ZERO, |e| e.radiance(d));
        self.suns.iter().map(|&i| self.lights[i as usize].radiance_at_infinity(d)).sum::<Vec3>() + env
    }

    /// Indices in `lights` of the suns.
    #[must_use]
    pub fn suns(&self) -> &[u32] {
        &self.suns
    }

    /// Whether any ray leaving the scene sees light ([`Scene::background`]).
    #[must_use]
    pub fn has_background(&self) -> bool {
        self.environment.is_some() || !self.suns.is_empty()
    }

    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.p0.len()
    }

    /// True if any triangle has a material photons pass on as specular (mirror, glass, frosted
    /// glass, a smooth rough metal: [`Bsdf::photon_specular`]): caustics are possible.
    #[must_use]
    pub fn has_delta_surfaces(&self) -> bool {
        self.kinds.0
    }

    /// True if any triangle is glass.
    #[must_use]
    pub fn has_glass(&self) -> bool {
        self.kinds.1
    }

    /// True if any triangle has a non-delta (diffuse or glossy) material.
    #[must_use]
    pub fn has_diffuse_surfaces(&self) -> bool {
        self.kinds.2
    }

    /// The scattering medium a ray along `d` crossed to reach `hit`: the interior of the
    /// dielectric whose back face it hit, if that interior scatters
    /// ([`Material::interior_scattering`]).
    #[must_use]
    pub fn scattering_interior(&self, hit: &Hit, d: Vec3) -> Option<&crate::medium::Medium> {
        let tri = hit.tri as usize;
        if d.dot(self.ng[tri]) <= 0.0 {
            return None;
        }
        self.materials[self.material[tri] as usize].interior_scattering.as_ref()
    }

    /// The medium on the side of triangle `tri` that `v` points to: a solid dielectric's
    /// interior behind its face (its scattering medium, or none for clear or Beer–Lambert
    /// absorbing glass); the medium filling the scene, if any, everywhere else. Interiors are
    /// not nested. A shadow ray leaving the surface along `v` travels in it; a ray that reached
    /// the surface along `d` travelled in the one on the side of −d.
    #[must_use]
    pub fn medium_on_side(&self, tri: u32, v: Vec3) -> Option<&crate::medium::Medium> {
        if self.behind_dielectric(tri, v) {
            self.materials[self.material[tri as usize] as usize].interior_scattering.as_ref()
        } else {
            self.medium.as_ref()
        }
    }

    /// Whether `v` points from triangle `tri` into a solid dielectric's interior (behind the
    /// face of glass or a rough dielectric).
    #[must_use]
    #[inline]
    pub fn behind_dielectric(&self, tri: u32, v: Vec3) -> bool {
        let m = &self.materials[self.material[tri as usize] as usize];
        v.dot(self.ng[tri as usize]) < 0.0 && matches!(m.bsdf, Bsdf::Glass { .. } | Bsdf::RoughDielectric { .. })
    }

    /// The photon-mapping engines' rule: the medium filling the scene on the side of triangle
    /// `tri` that `v` points to, none inside a solid dielectric (whose interior they only
    /// attenuate, [`Self::interior_transmittance`]).
    #[must_use]
    #[inline]
    pub fn filling_medium_toward(&self, tri: u32, v: Vec3) -> Option<&crate::medium::Medium> {
        self.medium.as_ref().filter(|_| !self.behind_dielectric(tri, v))
    }

    /// The medium filling the scene that a ray along `d` crosses before `hit` (or to infinity),
    /// for the photon-mapping engines ([`Self::filling_medium_toward`] of the side it came
    /// from).
    #[must_use]
    #[inline]
    pub fn filling_medium(&self, hit: Option<&Hit>, d: Vec3) -> Option<&crate::medium::Medium> {
        match hit {
            Some(h) => self.filling_medium_toward(h.tri, -d),
            None => self.medium.as_ref(),
        }
    }

    /// True if the scene has a participating medium anywhere: one filling it or a scattering
    /// interior.
    #[must_use]
    pub fn has_media(&self) -> bool {
        self.medium.is_some() || self.materials.iter().any(|m| m.interior_scattering.is_some())
    }

    /// The medium a ray along `d` travels in before `hit` (`None`: it leaves the scene): the
    /// one on the side of `hit`'s triangle it came from ([`Self::medium_on_side`]), or the
    /// medium filling the scene when it hits nothing.
    #[must_use]
    pub fn segment_medium(&self, hit: Option<&Hit>, d: Vec3) -> Option<&crate::medium::Medium> {
        match hit {
            Some(h) => self.medium_on_side(h.tri, -d),
            None => self.medium.as_ref(),
        }
    }

    /// True if any triangle's dielectric encloses an absorbing interior ([`Material::interior`]).
    #[must_use]
    pub fn has_absorbing_interiors(&self) -> bool {
        self.kinds.3
    }

    /// The share of light a ray along `d` keeps on its way to `hit` when it reaches a
    /// dielectric's back face, having crossed its absorbing interior: exp(−σ_a·distance)
    /// (Beer–Lambert, [`Material::interior`]); 1 at a front face or a clear interior. Every
    /// engine's camera, gather, glossy and photon rays take it at each hit.
    #[must_use]
    #[inline]
    pub fn interior_transmittance(&self, hit: &Hit, d: Vec3) -> Vec3 {
        if !self.kinds.3 {
            return Vec3::ONE;
        }
        let tri = hit.tri as usize;
        let sigma = self.materials[self.material[tri] as usize].interior;
        if sigma == Vec3::ZERO || d.dot(self.ng[tri]) <= 0.0 {
            return Vec3::ONE;
        }
        (-sigma * (hit.t * d.length())).exp()
    }
}

/// The scene's alpha cut-outs and passed thin sheets, for every traversal ([`Scene::columns`]
/// hands them over when some material has one): a hit passes where its material's
/// [`crate::material::Opacity`] lets the ray through at the hit's texture coordinates, and,
/// where it is present, a thin sheet passed in traversal ([`Bsdf::thin_pass`]) lets it through
/// with its transmittance at the ray's angle to the triangle, drawn from the ray's hash with
/// the triangle's number salted (independent of the mask's draw).
impl CutOut for Scene {
    fn passes(&self, tri: u32, b: [f32; 3], o: Vec3, d: Vec3) -> bool {
        let i = tri as usize;
        let m = &self.materials[self.material[i] as usize];
        if let Some(opacity) = &m.opacity {
            if opacity.passes(self.uv_at(i, b), || coverage_sample(tri, o, d)) {
                return true;
            }
        }
        match m.bsdf.thin_pass() {
            None => false,
            Some((ior, t)) => {
                let cos = d.dot(self.ng[i]).abs() / d.length();
                coverage_sample(tri ^ SHEET_SALT, o, d) < thin_pass_probability(cos, ior, t)
            }
        }
    }
}

/// The share of an environment's photons whose lines are drawn through its portals
/// ([`Scene::sample_emission`]); the rest cross the whole scene, for the light that reaches
/// what lies outside the portals (the ground outside a window, which a gather ray can see).
pub const PORTAL_PHOTON_SHARE: f32 = 0.5;

/// Flips a triangle's number for a thin sheet's draw, so that a sheet with a mask draws its
/// two decisions from unrelated hashes.
const SHEET_SALT: u32 = 0x8000_0000;
