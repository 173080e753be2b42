//! Scene assembly: meshes, materials and lights in, a validated [`Scene`] out — triangles
//! checked and stored as columns in BVH order, light triangles and their power distribution
//! (textured emitters by their texture's mean over each triangle), the environment, the BVH.
//!
//! Reads [`MeshInput`]s (from the readers of [`crate::formats`], or made in code),
//! [`Material`]s and [`Light`]s; writes the [`Scene`] the engines trace.

use super::*;

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
        let origin = frame_origin(&meshes);
        if origin != Vec3::ZERO {
            for p in meshes.iter_mut().flat_map(|m| m.positions.iter_mut()) {
                *p = relative_to(*p, origin);
            }
            for l in &mut extra_lights {
                if let Light::Point { position, .. } | Light::Spot { position, .. } = l {
                    *position = relative_to(*position, origin);
                }
            }
        }
        if environment.is_some() {
            extra_lights.push(Light::Environment);
        }
        let (mut p0, mut p1, mut p2, mut vn, mut mat) = (vec![], vec![], vec![], vec![], vec![]);
        let textured = materials.iter().any(|m| !m.maps.is_empty());
        let mut uv: Vec<[Vec2; 3]> = vec![];
        let mut untextured_uses: Vec<String> = vec![];
        // Degenerate triangles skipped, per mesh (named in the warning).
        let mut dropped_in: Vec<(&str, usize)> = vec![];
        let zero_normals = meshes.iter().map(|m| m.zero_normals).sum();
        // Emissive area per material, to refuse lights whose every triangle is degenerate.
        let mut emitter_area = vec![0.0f64; materials.len()];
        let mut emitter_seen = vec![false; materials.len()];
        for m in &meshes {
            for (t, tri) in m.triangles.iter().enumerate() {
                let v = tri.map(|i| m.positions[i as usize]);
                let material = m.material[t];
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
                p0.push(v[0]);
                p1.push(v[1]);
                p2.push(v[2]);
                vn.push(if m.normals.is_empty() {
                    [gn; 3]
                } else {
                    tri.map(|i| m.normals[i as usize].try_normalize().unwrap_or(gn))
                });
                mat.push(material);
                if textured {
                    if m.texcoords.is_empty() {
                        let name = &materials[material as usize];
                        if !name.maps.is_empty() && !untextured_uses.iter().any(|u| u.starts_with(&m.source)) {
                            untextured_uses.push(format!(
                                "{}: material `{}` has a texture but the mesh has no texture coordinates (`vt`); it \
                                 reads the texture at (0, 0) everywhere",
                                m.source, name.name
                            ));
                        }
                        uv.push([Vec2::ZERO; 3]);
                    } else {
                        uv.push(tri.map(|i| m.texcoords[i as usize]));
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
        let dropped: usize = dropped_in.iter().map(|(_, n)| n).sum();
        for (source, n) in &dropped_in {
            warnings.push(format!("{source}: {n} degenerate (zero-area) triangles were skipped"));
        }
        if p0.is_empty() {
            let directional = extra_lights.iter().any(Light::is_distant);
            let why = if dropped > 0 {
                format!(" (all {dropped} of its triangles have zero area)")
            } else if directional {
                ": a directional light needs geometry to light (add a [[mesh]])".into()
            } else {
                " to light (add a [[mesh]])".into()
            };
            return Err(Error::scene(format!("the scene has no triangles{why}")));
        }
        for (i, l) in extra_lights.iter().enumerate() {
            if let Light::Point { position, .. } | Light::Spot { position, .. } = *l {
                if !in_range(position) {
                    return Err(Error::setting(
                        format!("light[{i}].position"),
                        format!("{position} is outside ±{MAX_COORDINATE:e}, the range photonwave supports"),
                    ));
                }
            }
        }

        let (mut lo, mut hi) = bounds_of(p0.iter().chain(&p1).chain(&p2));
        let size = (hi - lo).length().max(f32::MIN_POSITIVE);
        if let Some(w) = checks::coincident_dielectrics(&p0, &p1, &p2, &mat, &materials, size) {
            warnings.push(w);
        }
        let (bvh, order) = Bvh::build(&p0, &p1, &p2);
        let pick = |v: &Vec<Vec3>| order.iter().map(|&i| v[i as usize]).collect::<Vec<_>>();
        let (p0, p1, p2) = (pick(&p0), pick(&p1), pick(&p2));
        let vn: Vec<[Vec3; 3]> = order.iter().map(|&i| vn[i as usize]).collect();
        let material: Vec<u32> = order.iter().map(|&i| mat[i as usize]).collect();
        let uv: Vec<[Vec2; 3]> = if textured { order.iter().map(|&i| uv[i as usize]).collect() } else { vec![] };
        let (ng, area): (Vec<Vec3>, Vec<f32>) = (0..p0.len()).map(|i| normal_and_area(p0[i], p1[i], p2[i])).unzip();

        let mut lights: Vec<Light> = (0..p0.len())
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
            .collect();
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
            delta_lights: vec![],
            suns: vec![],
            bounds: (lo, hi),
            origin,
            dropped_degenerate: dropped,
            zero_normals,
            encloses_lights: false,
            warnings,
            bvh,
            kinds: (false, false, false),
            open_edges: open_edges::OpenEdges::default(),
            caustic_targets: Vec::new(),
        };
        let mut used = vec![false; scene.materials.len()];
        for &m in &scene.material {
            used[m as usize] = true;
        }
        for (m, _) in scene.materials.iter().zip(&used).filter(|(_, u)| **u) {
            scene.kinds.0 |= m.bsdf.photon_specular();
            scene.kinds.1 |= matches!(m.bsdf, Bsdf::Glass { .. });
            scene.kinds.2 |= !m.bsdf.is_delta();
        }
        let powers: Vec<f64> =
            scene.lights.iter().map(|l| scene.light_power_of(l).element_sum() as f64 / 3.0).collect();
        if let Some(i) = powers.iter().position(|p| !p.is_finite()) {
            let what = match &scene.lights[i] {
                Light::Area { tri, .. } => {
                    format!("emitter material `{}`", scene.materials[scene.material[*tri as usize] as usize].name)
                }
                _ => {
                    let k = scene.lights[..i].iter().filter(|l| !matches!(l, Light::Area { .. })).count();
                    format!("setting `light[{k}]`")
                }
            };
            return Err(Error::scene(format!(
                "{what}: its power overflows f32 (emission times area or intensity times solid angle is above 3.4e38 W); scale it down"
            )));
        }
        scene.light_power = Distribution1D::try_new(&powers)
            .ok_or_else(|| Error::scene("every light has zero power: check `Ke` and light intensities"))?;
        scene.area_lights = (0..scene.lights.len() as u32).filter(|&i| !scene.lights[i as usize].is_delta()).collect();
        scene.delta_lights = (0..scene.lights.len() as u32).filter(|&i| scene.lights[i as usize].is_delta()).collect();
        scene.suns =
            (0..scene.lights.len() as u32).filter(|&i| matches!(scene.lights[i as usize], Light::Sun { .. })).collect();
        let area_w: Vec<f64> = scene.area_lights.iter().map(|&i| powers[i as usize]).collect();
        scene.area_power = Distribution1D::try_new(&area_w);
        let edges = scene.edge_uses();
        scene.encloses_lights = scene.find_enclosure(&edges);
        scene.open_edges = scene.find_open_edges(scene.diagonal().max(f32::MIN_POSITIVE), &edges);
        scene.caustic_targets = scene.find_caustic_targets(&edges);
        Ok(scene)
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
