//! Scene assembly: meshes, materials and lights in, a validated [`Scene`] out — triangles
//! checked and stored as columns in BVH order, light triangles and their power distribution
//! (textured emitters by their texture's mean over each triangle), the environment, the BVH.
//!
//! Reads [`MeshInput`]s (from the readers of [`crate::formats`], or made in code),
//! [`Material`]s and [`Light`]s; writes the [`Scene`] the engines trace.

use super::light_tree::{LightTree, TreeLight};
use super::*;

/// Seconds since `clock`, which then restarts: one stage of [`LoadTimes`].
fn lap(clock: &mut std::time::Instant) -> f64 {
    let now = std::time::Instant::now();
    let seconds = now.duration_since(*clock).as_secs_f64();
    *clock = now;
    seconds
}

impl Scene {
    /// Assembles meshes, materials and extra lights; validates and builds the BVH.
    pub fn build(
        meshes: Vec<MeshInput>,
        materials: Vec<Material>,
        extra_lights: Vec<Light>,
        warnings: Vec<String>,
    ) -> Result<Scene> {
        Self::build_lit(meshes, materials, extra_lights, None, warnings)
    }

    /// [`Scene::build`] with an environment light.
    pub fn build_lit(
        mut meshes: Vec<MeshInput>,
        materials: Vec<Material>,
        mut extra_lights: Vec<Light>,
        environment: Option<Environment>,
        mut warnings: Vec<String>,
    ) -> Result<Scene> {
        let mut clock = std::time::Instant::now();
        for m in &meshes {
            // The readers name the line or the `[[mesh]]` entry; this catches meshes made in code.
            if let Some((k, p)) = super::first_out_of_range(&m.positions) {
                return Err(Error::scene(format!(
                    "{}, vertex {}: {}",
                    m.source,
                    k + 1,
                    super::out_of_range_message(p)
                )));
            }
        }
        let origin = move_to_frame(&mut meshes, &mut extra_lights);
        let environment = environment.map(|e| e.moved(origin));
        if environment.is_some() {
            extra_lights.push(Light::Environment);
        }
        let zero_normals = meshes.iter().map(|m| m.zero_normals).sum();
        let mut materials = materials;
        for m in &mut materials {
            // Thin sheets that can be passed in traversal are marked so.
            m.bsdf = m.bsdf.passing_thin_sheets();
            match &m.opacity {
                Some(o) if o.is_opaque() => m.opacity = None,
                Some(_) if m.emission != Vec3::ZERO => {
                    warnings.push(format!(
                        "material `{}`: its cut-out (opacity) is not rendered on an emitter: the light is opaque and \
                         emits everywhere, so that what light sampling sees and what rays hit agree",
                        m.name
                    ));
                    m.opacity = None;
                }
                _ => {}
            }
        }
        let t = Triangles::gather(&meshes, &materials, &mut warnings)?;
        if t.p0.is_empty() {
            let directional = extra_lights.iter().any(Light::is_distant);
            let why = if t.dropped > 0 {
                format!(" (all {} of its triangles have zero area)", t.dropped)
            } else if directional {
                ": a directional light needs geometry to light (add a [[mesh]])".into()
            } else {
                " to light (add a [[mesh]])".into()
            };
            return Err(Error::scene(format!("the scene has no triangles{why}")));
        }
        check_light_positions(&extra_lights)?;

        let (mut lo, mut hi) = bounds_of(t.p0.iter().chain(&t.p1).chain(&t.p2));
        let size = (hi - lo).length().max(f32::MIN_POSITIVE);
        if let Some(w) = checks::coincident_dielectrics(&t.p0, &t.p1, &t.p2, &t.mat, &materials, size) {
            warnings.push(w);
        }
        let mut load_times = LoadTimes { triangles_s: lap(&mut clock), ..LoadTimes::default() };
        let (bvh, order) = Bvh::build(&t.p0, &t.p1, &t.p2);
        load_times.bvh_s = lap(&mut clock);
        let pick = |v: &Vec<Vec3>| order.iter().map(|&i| v[i as usize]).collect::<Vec<_>>();
        let (p0, p1, p2) = (pick(&t.p0), pick(&t.p1), pick(&t.p2));
        let vn: Vec<[Vec3; 3]> = order.iter().map(|&i| t.vn[i as usize]).collect();
        let material: Vec<u32> = order.iter().map(|&i| t.mat[i as usize]).collect();
        let uv: Vec<[Vec2; 3]> = if t.textured { order.iter().map(|&i| t.uv[i as usize]).collect() } else { vec![] };
        let (ng, area): (Vec<Vec3>, Vec<f32>) = (0..p0.len()).map(|i| normal_and_area(p0[i], p1[i], p2[i])).unzip();

        let mut lights = area_lights(&material, &materials, &uv);
        for l in &extra_lights {
            if let Light::Point { position, .. } | Light::Spot { position, .. } = *l {
                lo = lo.min(position);
                hi = hi.max(position);
            }
        }
        lights.extend(extra_lights);
        if lights.is_empty() {
            return Err(Error::scene(
                "the scene has no light: give a material emission (`Ke` in an MTL file, `emissiveFactor` in a glTF \
                 file, `emission` in a [materials] table, an area `emitter` in a Mitsuba file), add a [[light]] to the scene file, or light it from the \
                 command line with `--light headlight` or `--light sun`",
            ));
        }
        let mut scene = Scene {
            p0,
            p1,
            p2,
            vn,
            uv,
            ng,
            area,
            material,
            materials,
            lights,
            environment,
            light_power: Distribution1D::default(),
            area_lights: vec![],
            area_power: None,
            light_tree: None,
            infinite_power: None,
            delta_lights: vec![],
            suns: vec![],
            bounds: (lo, hi),
            origin,
            dropped_degenerate: t.dropped,
            zero_normals,
            encloses_lights: false,
            warnings,
            bvh,
            kinds: (false, false, false, false, false, false, false),
            open_edges: open_edges::OpenEdges::default(),
            caustic_targets: Vec::new(),
            load_times,
            medium: None,
        };
        scene.find_kinds();
        // Placing the triangles in BVH order (and listing the emitting ones) counts with them.
        scene.load_times.triangles_s += lap(&mut clock);
        scene.distribute_lights()?;
        scene.load_times.lights_s = lap(&mut clock);
        let edges = scene.edge_uses();
        // Light may leave through a cut-out's holes and a window pane: a photon that escapes has
        // not leaked.
        scene.encloses_lights = !scene.kinds.5 && !scene.kinds.6 && scene.find_enclosure(&edges);
        scene.open_edges = scene.find_open_edges(scene.diagonal().max(f32::MIN_POSITIVE), &edges);
        scene.caustic_targets = scene.find_caustic_targets(&edges);
        scene.load_times.topology_s = lap(&mut clock);
        Ok(scene)
    }

    /// Which kinds of material the scene's triangles use: (any passed as specular by photons,
    /// any glass, any non-delta, any absorbing interior, any normal map, any cut-out, any thin
    /// sheet passed in traversal: marked so at the start of [`Scene::build_lit`],
    /// [`Bsdf::passing_thin_sheets`]).
    fn find_kinds(&mut self) {
        let used = self.used_materials();
        for (m, _) in self.materials.iter().zip(&used).filter(|(_, u)| **u) {
            self.kinds.6 |= m.bsdf.thin_pass().is_some();
            self.kinds.0 |= m.bsdf.photon_specular();
            self.kinds.1 |= matches!(m.bsdf, Bsdf::Glass { .. } | Bsdf::ThinGlass { .. });
            self.kinds.2 |= !m.bsdf.is_delta();
            self.kinds.3 |= m.interior != Vec3::ZERO;
            self.kinds.4 |= m.normal_map.is_some();
            self.kinds.5 |= m.opacity.is_some();
        }
    }

    /// The lights' power distributions: every light by power (photons), the area lights, sun and
    /// environment by power (direct light), the delta lights and suns listed. A light whose
    /// power overflows f32, or a scene whose every light is dark, is an error.
    fn distribute_lights(&mut self) -> Result<()> {
        let powers: Vec<f64> = self.lights.iter().map(|l| self.light_power_of(l).element_sum() as f64 / 3.0).collect();
        if let Some(i) = powers.iter().position(|p| !p.is_finite()) {
            let what = match &self.lights[i] {
                Light::Area { tri, .. } => {
                    format!("emitter material `{}`", self.materials[self.material[*tri as usize] as usize].name)
                }
                _ => {
                    let k = self.lights[..i].iter().filter(|l| !matches!(l, Light::Area { .. })).count();
                    format!("setting `light[{k}]`")
                }
            };
            return Err(Error::scene(format!(
                "{what}: its power overflows f32 (emission times area or intensity times solid angle is above 3.4e38 W); scale it down"
            )));
        }
        self.light_power = Distribution1D::try_new(&powers)
            .ok_or_else(|| Error::scene("every light has zero power: check `Ke` and light intensities"))?;
        let lights = 0..self.lights.len() as u32;
        self.area_lights = lights.clone().filter(|&i| !self.lights[i as usize].is_delta()).collect();
        self.delta_lights = lights.clone().filter(|&i| self.lights[i as usize].is_delta()).collect();
        self.suns = lights.filter(|&i| matches!(self.lights[i as usize], Light::Sun { .. })).collect();
        let area_w: Vec<f64> = self.area_lights.iter().map(|&i| powers[i as usize]).collect();
        self.area_power = Distribution1D::try_new(&area_w);
        // The emissive triangles in a light tree, beside the suns and the environment.
        let emitters: Vec<TreeLight> = (0..self.lights.len())
            .filter_map(|i| match self.lights[i] {
                Light::Area { tri, .. } => {
                    let t = self.triangle(tri);
                    Some(TreeLight { light: i as u32, p: t.p, n: t.n, power: powers[i] as f32 })
                }
                _ => None,
            })
            .collect();
        let infinite: Vec<u32> = self
            .area_lights
            .iter()
            .copied()
            .filter(|&i| !matches!(self.lights[i as usize], Light::Area { .. }))
            .collect();
        let tree_power: f64 = emitters.iter().map(|l| powers[l.light as usize]).sum();
        let share = tree_power / self.area_power.as_ref().map_or(1.0, Distribution1D::total);
        self.light_tree = LightTree::build(&emitters, self.lights.len()).map(|t| (t, share));
        let infinite_w: Vec<f64> = infinite.iter().map(|&i| powers[i as usize]).collect();
        self.infinite_power = Distribution1D::try_new(&infinite_w).map(|d| (infinite, d));
        Ok(())
    }
}

/// Moves the meshes and the point and spot lights into the scene's frame ([`frame_origin`]);
/// returns its origin (zero: nothing moved).
fn move_to_frame(meshes: &mut [MeshInput], lights: &mut [Light]) -> Vec3 {
    let origin = frame_origin(meshes);
    if origin != Vec3::ZERO {
        for p in meshes.iter_mut().flat_map(|m| m.positions.iter_mut()) {
            *p = relative_to(*p, origin);
        }
        for l in lights {
            if let Light::Point { position, .. } | Light::Spot { position, .. } = l {
                *position = relative_to(*position, origin);
            }
        }
    }
    origin
}

/// Point and spot lights must lie within ±[`MAX_COORDINATE`].
fn check_light_positions(lights: &[Light]) -> Result<()> {
    for (i, l) in lights.iter().enumerate() {
        if let Light::Point { position, .. } | Light::Spot { position, .. } = *l {
            if !in_range(position) {
                return Err(Error::setting(
                    format!("light[{i}].position"),
                    format!("{position} is outside ±{MAX_COORDINATE:e}, the range photonwave supports"),
                ));
            }
        }
    }
    Ok(())
}

/// One area light per emissive triangle (`material` per triangle, in BVH order), in triangle
/// order: the scene's first lights.
fn area_lights(material: &[u32], materials: &[Material], uv: &[[Vec2; 3]]) -> Vec<Light> {
    (0..material.len())
        .filter(|&i| materials[material[i] as usize].emission != Vec3::ZERO)
        .map(|i| {
            let m = &materials[material[i] as usize];
            // A textured emitter's radiance here only weighs its pick (its power): the
            // samples read the texture where they land (`Scene::sample_incident`, …).
            let radiance = match (&m.maps.ke, uv.get(i)) {
                (Some(t), Some(tri_uv)) => m.emission * textured_mean(t, tri_uv),
                _ => m.emission,
            };
            Light::Area { tri: i as u32, radiance }
        })
        .collect()
}

/// The meshes' triangles as columns in input order, degenerate ones skipped: vertices, vertex
/// normals, materials and (with any textured material) texture coordinates.
struct Triangles {
    p0: Vec<Vec3>,
    p1: Vec<Vec3>,
    p2: Vec<Vec3>,
    vn: Vec<[Vec3; 3]>,
    mat: Vec<u32>,
    uv: Vec<[Vec2; 3]>,
    /// Whether any material has a texture or a normal map (then `uv` has a row per triangle).
    textured: bool,
    /// Degenerate triangles skipped.
    dropped: usize,
}

impl Triangles {
    /// Gathers the triangles of `meshes`, warning per mesh of the degenerate ones skipped and of
    /// textured materials on meshes without texture coordinates; an emitter material whose every
    /// triangle is degenerate is an error.
    fn gather(meshes: &[MeshInput], materials: &[Material], warnings: &mut Vec<String>) -> Result<Triangles> {
        let textured = materials.iter().any(Material::reads_texture_coordinates);
        let mut t =
            Triangles { p0: vec![], p1: vec![], p2: vec![], vn: vec![], mat: vec![], uv: vec![], textured, dropped: 0 };
        let mut untextured_uses: Vec<String> = vec![];
        // Degenerate triangles skipped, per mesh (named in the warning).
        let mut dropped_in: Vec<(&str, usize)> = vec![];
        // Emissive area per material, to refuse lights whose every triangle is degenerate.
        let mut emitter_area = vec![0.0f64; materials.len()];
        let mut emitter_seen = vec![false; materials.len()];
        for m in meshes {
            for (k, tri) in m.triangles.iter().enumerate() {
                let v = tri.map(|i| m.positions[i as usize]);
                let material = m.material[k];
                let emissive = materials[material as usize].emission != Vec3::ZERO;
                let (gn, area) = normal_and_area(v[0], v[1], v[2]);
                if emissive {
                    emitter_seen[material as usize] = true;
                }
                // Also what the intersection test takes as degenerate (its f32 cross product
                // underflows): such a triangle could never be hit, nor lit if it emitted.
                if !(area > 0.0) || is_degenerate(v[0], v[1], v[2]) {
                    match dropped_in.last_mut() {
                        Some((source, n)) if *source == m.source.as_str() => *n += 1,
                        _ => dropped_in.push((&m.source, 1)),
                    }
                    continue;
                }
                if emissive {
                    emitter_area[material as usize] += f64::from(area);
                }
                t.p0.push(v[0]);
                t.p1.push(v[1]);
                t.p2.push(v[2]);
                t.vn.push(if m.normals.is_empty() {
                    [gn; 3]
                } else {
                    tri.map(|i| m.normals[i as usize].try_normalize().unwrap_or(gn))
                });
                t.mat.push(material);
                if textured {
                    if m.texcoords.is_empty() {
                        let name = &materials[material as usize];
                        if name.reads_texture_coordinates() && !untextured_uses.iter().any(|u| u.starts_with(&m.source))
                        {
                            untextured_uses.push(format!(
                                "{}: material `{}` has a texture but the mesh has no texture coordinates (`vt`); it \
                                 reads the texture at (0, 0) everywhere",
                                m.source, name.name
                            ));
                        }
                        t.uv.push([Vec2::ZERO; 3]);
                    } else {
                        t.uv.push(tri.map(|i| m.texcoords[i as usize]));
                    }
                }
            }
        }
        warnings.extend(untextured_uses);
        for (i, seen) in emitter_seen.iter().enumerate() {
            if *seen && emitter_area[i] <= 0.0 {
                return Err(Error::scene(format!(
                    "emitter material `{}` has zero area: every triangle using it is degenerate",
                    materials[i].name
                )));
            }
        }
        t.dropped = dropped_in.iter().map(|(_, n)| n).sum();
        for (source, n) in &dropped_in {
            warnings.push(format!("{source}: {n} degenerate (zero-area) triangles were skipped"));
        }
        Ok(t)
    }
}

/// The mean of texture `t` over a triangle with texture coordinates `uv` (16 stratified points),
/// or over the whole texture where that is black (a pick weight must be positive where the
/// texture lights anything).
fn textured_mean(t: &crate::texture::Texture, uv: &[Vec2; 3]) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for k in 0..16 {
        let (b1, b2) = crate::sampling::uniform_triangle([(k % 4) as f32 / 4.0 + 0.125, (k / 4) as f32 / 4.0 + 0.125]);
        sum += t.lookup(uv[0] * (1.0 - b1 - b2) + uv[1] * b1 + uv[2] * b2);
    }
    if sum == Vec3::ZERO {
        t.mean()
    } else {
        sum / 16.0
    }
}

/// How many of its own diagonals a scene's centre must lie from the origin for the scene to be
/// moved to it ([`frame_origin`]): 8, where its coordinates have lost 3 bits or more to their
/// magnitude. Nearer, the scene keeps the coordinates of its files (and its images their bits).
const FAR: f64 = 8.0;

/// Where the scene's own frame puts its origin, in the coordinates of its files: the centre of
/// its meshes' bounds where that lies further than [`FAR`] diagonals from the origin, else the
/// origin itself (no move). f32 resolves a coordinate to 2⁻²⁴ of its magnitude, so a
/// Cornell box 30 000 units out is drawn on a grid of 2 mm: rays leaving a wall's top edge
/// started above the ceiling, error bounds and ray offsets grew to centimetres, and the image
/// came out 2.7 % dark. Moved to its own centre (each position's difference taken in f64 and
/// rounded once, so equal positions stay equal bit for bit), the scene renders as it would at
/// the origin; cameras and lights move with it ([`Scene::to_frame`]). Positions are rounded to
/// f32 as the files are read, so what the far placement already lost (vertices on the 2 mm grid)
/// stays lost.
fn frame_origin(meshes: &[MeshInput]) -> Vec3 {
    let (lo, hi) = bounds_of(meshes.iter().flat_map(|m| m.positions.iter()));
    if !(lo.is_finite() && hi.is_finite()) {
        return Vec3::ZERO;
    }
    let centre = 0.5 * (lo.as_dvec3() + hi.as_dvec3());
    if centre.length() <= FAR * (hi.as_dvec3() - lo.as_dvec3()).length() {
        return Vec3::ZERO;
    }
    centre.as_vec3()
}
