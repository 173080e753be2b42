//! MTL files as the spec (Wavefront's, with the PBR extension's keys) and real exporters write
//! them, and their mapping onto photonwave's materials (documented in docs/src/scenes.md):
//!
//! | MTL | material |
//! |---|---|
//! | `Ke` ≠ 0 | area emitter with radiance `Ke` from the front (counter-clockwise) face, plus the scattering below |
//! | `illum` 3, 5 or 8 | perfect mirror, reflectance `Ks` (1 if absent); with `Pr` > 0 a GGX rough conductor of α = `Pr`² |
//! | `illum` 4, 6, 7 or 9 | smooth clear dielectric, IOR `Ni` (1.5 if absent), exact Fresnel; with `Pr` > 0 rough (frosted) |
//! | `Pm` ≥ 0.5 (PBR metal) | mirror of colour `Kd`; with `Pr` > 0 a rough conductor |
//! | `Pr` > 0 otherwise | rough plastic: a GGX coat of IOR `Ni` (1.5) over the Lambertian base `Kd` |
//! | `illum` 2 with `Ks` > 0 | Lambertian `Kd` + normalised Phong lobe `Ks`, exponent `Ns`; scaled so Kd + Ks ≤ 1 |
//! | otherwise (`illum` 0, 1, 10, or 2 without `Ks`) | Lambertian `Kd` (0.8 grey if absent) |
//!
//! Colours take three numbers, one (grey), or `xyz X [Y Z]` (CIE XYZ, converted to linear sRGB).
//! `map_Kd` and `map_Ks` name textures that replace `Kd` and `Ks` ([`MapStatement`]; read by
//! [`super`]). Statements the spec defines but photonwave does not simulate (the other
//! texture maps, texture options, `d`/`Tr` transparency, a coloured `Tf`, `sharpness`, `Km`, the
//! PBR keys, spectral colours) are read, checked where they hold numbers, and reported in one warning per
//! material (`Ka` is read and not reported: ambient light has no place in global illumination). Anything else is
//! an error naming the file and line.

use super::validate::number;
use crate::error::{Error, Result};
use crate::material::{Bsdf, Material, Tint};
use crate::microfacet::{alpha_of, Alpha};
use glam::Vec3;
use std::path::Path;

/// One `newmtl` block as read from the file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MtlMaterial {
    /// Its name.
    pub name: String,
    /// The line of its `newmtl`.
    pub line: usize,
    /// `Kd`.
    pub kd: Option<Vec3>,
    /// `Ks`.
    pub ks: Option<Vec3>,
    /// `Ke`.
    pub ke: Option<Vec3>,
    /// `Ns`.
    pub ns: Option<f32>,
    /// `Ni`.
    pub ni: Option<f32>,
    /// `illum`.
    pub illum: Option<u8>,
    /// `Pr` (PBR roughness, 0–1).
    pub pr: Option<f32>,
    /// `Pm` (PBR metallic, 0–1).
    pub pm: Option<f32>,
    /// `d`, the dissolve (1: opaque).
    pub d: Option<f32>,
    /// `Tr`, the transparency (the spec's 1 − `d`).
    pub tr: Option<f32>,
    /// The texture maps simulated (`map_Kd`, `map_Ks`, `map_Pr`, `map_Ke`, `map_Pm`, `map_d`,
    /// `bump`), in file order.
    pub maps: Vec<MapStatement>,
    /// Statements read but not simulated, in order of first appearance (`map_Ke`, `d`, …).
    pub ignored: Vec<String>,
}

/// A texture statement photonwave simulates.
#[derive(Clone, Debug, PartialEq)]
pub struct MapStatement {
    /// Its keyword (`map_Kd` or `map_Ks`).
    pub key: String,
    /// The image file as written (relative to the MTL file's folder).
    pub file: String,
    /// Its line.
    pub line: usize,
    /// The bump multiplier (`-bm` of a `bump` map; 1 elsewhere).
    pub scale: f32,
}

impl MtlMaterial {
    /// The file of the texture statement `key` (the last one given), if any.
    #[must_use]
    pub fn map(&self, key: &str) -> Option<&MapStatement> {
        self.maps.iter().rev().find(|m| m.key == key)
    }

    /// The dissolve the material states: `d`, else 1 − `Tr`. A lone `Tr 1`, which would make the
    /// surface vanish, is taken as the exporters' inverted convention (1 = opaque) and ignored
    /// (the material's warning says so).
    #[must_use]
    pub fn dissolve(&self) -> Option<f32> {
        self.d.or(self.tr.filter(|t| *t < 1.0).map(|t| 1.0 - t))
    }

    /// Notes the statement `what` as read but not simulated (once).
    fn ignore(&mut self, what: &str) {
        if !self.ignored.iter().any(|s| s == what) {
            self.ignored.push(what.to_string());
        }
    }
}

/// A colour statement's value: `r g b`, `r` (grey), or `xyz X [Y Z]`. `None` for `spectral`.
fn colour(path: &Path, line: usize, kw: &str, words: &[&str]) -> Result<Option<Vec3>> {
    let nums = |ws: &[&str]| ws.iter().map(|w| number(path, line, kw, w)).collect::<Result<Vec<f32>>>();
    let v = match words.first().copied() {
        Some("spectral") => return Ok(None),
        Some("xyz") => {
            let xyz = nums(&words[1..])?;
            let xyz = match xyz.len() {
                1 => Vec3::splat(xyz[0]),
                3 => Vec3::from_slice(&xyz),
                n => return Err(Error::parse(path, line, format!("`{kw} xyz` needs 1 or 3 numbers, found {n}"))),
            };
            // CIE XYZ (D65 white) to linear sRGB; out-of-gamut negatives clip to 0.
            Vec3::new(
                3.240_97 * xyz.x - 1.537_38 * xyz.y - 0.498_61 * xyz.z,
                -0.969_24 * xyz.x + 1.875_97 * xyz.y + 0.041_56 * xyz.z,
                0.055_63 * xyz.x - 0.203_98 * xyz.y + 1.056_97 * xyz.z,
            )
            .max(Vec3::ZERO)
        }
        _ => {
            let v = nums(words)?;
            match v.len() {
                1 => Vec3::splat(v[0]),
                3 => Vec3::from_slice(&v),
                n => {
                    return Err(Error::parse(path, line, format!("`{kw}` needs 3 numbers (or 1 for grey), found {n}")))
                }
            }
        }
    };
    if v.min_element() < 0.0 {
        return Err(Error::parse(path, line, format!("`{kw}` must not be negative")));
    }
    Ok(Some(v))
}

/// The image file of a texture statement's words: the spec's options (`-o 1 1 1`, `-bm 0.5`,
/// `-clamp on`, …) with their arguments come first, the file name (which may hold spaces) last.
/// The `-bm` multiplier among a map statement's `words` (1 without one); an error naming the
/// line when it is not a finite number.
fn bump_multiplier(path: &Path, line: usize, words: &[&str]) -> Result<f32> {
    let Some(i) = words.iter().position(|w| *w == "-bm") else { return Ok(1.0) };
    match words.get(i + 1).and_then(|w| w.parse::<f32>().ok()).filter(|v| v.is_finite()) {
        Some(v) => Ok(v),
        None => Err(Error::parse(path, line, "`-bm` needs a finite number (the bump multiplier)")),
    }
}

fn texture_file(words: &[&str]) -> Option<String> {
    let mut i = 0;
    while let Some(opt) = words.get(i).filter(|w| w.starts_with('-')) {
        i += 1;
        let (min, max) = match *opt {
            "-o" | "-s" | "-t" => (1, 3),
            "-mm" => (2, 2),
            _ => (1, 1), // -blendu -blendv -bm -boost -cc -clamp -imfchan -texres -type
        };
        let mut taken = 0;
        while taken < max && i < words.len() && (taken < min || words[i].parse::<f32>().is_ok()) {
            i += 1;
            taken += 1;
        }
    }
    (i < words.len()).then(|| words[i..].join(" "))
}

/// Reads the text of an MTL file. Non-fatal findings (a material defined twice, statements that
/// are not simulated) go to `warnings`, once per material.
pub fn parse_mtl(path: &Path, text: &str, warnings: &mut Vec<String>) -> Result<Vec<MtlMaterial>> {
    let mut out: Vec<MtlMaterial> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let stmt = raw.split('#').next().unwrap_or("").trim();
        let mut it = stmt.split_whitespace();
        let Some(kw) = it.next() else { continue };
        let words: Vec<&str> = it.collect();
        if kw == "newmtl" {
            let name = stmt["newmtl".len()..].trim();
            if name.is_empty() {
                return Err(Error::parse(path, line, "`newmtl` needs a name"));
            }
            if let Some(k) = out.iter().position(|m| m.name == name) {
                warnings.push(format!(
                    "{}:{line}: material `{name}` is defined again (first at line {}); this later definition is used",
                    path.display(),
                    out[k].line
                ));
                out.remove(k);
            }
            out.push(MtlMaterial { name: name.to_string(), line, ..Default::default() });
            continue;
        }
        let Some(m) = out.last_mut() else {
            return Err(Error::parse(path, line, format!("`{kw}` before any `newmtl`")));
        };
        statement(path, line, kw, &words, m)?;
    }
    for m in &mut out {
        drop_unusable_maps(m);
    }
    for m in &out {
        warn_ignored(path, m, warnings);
    }
    Ok(out)
}

/// Maps one MTL material (read from `file`) onto photonwave's materials; warnings, each naming
/// the file and the material's `newmtl` line, go to `warnings`.
#[must_use]
pub fn material_from_mtl(m: &MtlMaterial, file: &Path, warnings: &mut Vec<String>) -> Material {
    let kd = m.kd.unwrap_or(Vec3::splat(0.8));
    // A `map_Ks` gives a specular colour even without `Ks`; its texels replace `ks` (and are kept
    // within kd + ks ≤ 1 where they are read, `Material::bsdf_at`).
    let ks_map = m.map("map_Ks").is_some();
    let ks = m.ks.unwrap_or(if ks_map { Vec3::ONE } else { Vec3::ZERO });
    // A `map_Ke` makes an emitter even without `Ke`; its texels replace the emission.
    let emission = m.ke.unwrap_or(if m.map("map_Ke").is_some() { Vec3::ONE } else { Vec3::ZERO });
    let rough = m.pr.filter(|&r| r > 0.0).map(|r| Alpha::ggx(alpha_of(r)));
    let metal = m.pm.is_some_and(|p| p >= 0.5);
    let bsdf = match (m.illum.unwrap_or(2), rough) {
        (3 | 5 | 8, None) => Bsdf::Mirror { ks: m.ks.unwrap_or(Vec3::ONE).min(Vec3::ONE), eta_k: None },
        (3 | 5 | 8, Some(alpha)) => {
            Bsdf::RoughConductor { ks: m.ks.unwrap_or(Vec3::ONE).min(Vec3::ONE), alpha, eta_k: None }
        }
        (4 | 6 | 7 | 9, None) => Bsdf::Glass { ior: m.ni.unwrap_or(1.5), tint: Tint::CLEAR },
        (4 | 6 | 7 | 9, Some(alpha)) => Bsdf::RoughDielectric { ior: m.ni.unwrap_or(1.5), alpha, tint: Tint::CLEAR },
        // The PBR extension's metals take their colour from `Kd` (the base colour).
        (_, None) if metal => Bsdf::Mirror { ks: kd.min(Vec3::ONE), eta_k: None },
        (_, Some(alpha)) if metal => Bsdf::RoughConductor { ks: kd.min(Vec3::ONE), alpha, eta_k: None },
        // A rough non-metal: the PBR extension's dielectric, a coat over the base colour.
        (_, Some(alpha)) => Bsdf::rough_plastic(kd.min(Vec3::ONE), m.ni.unwrap_or(1.5), alpha),
        (2, _) if ks.max_element() > 0.0 => {
            let sum = (kd + ks).max_element();
            let scale = if sum > 1.0 && !ks_map && m.map("map_Kd").is_none() {
                warnings.push(format!(
                    "{}:{}: material `{}`: Kd + Ks = {sum:.3} > 1, scaled down to conserve energy",
                    file.display(),
                    m.line,
                    m.name
                ));
                1.0 / sum
            } else {
                1.0
            };
            Bsdf::Glossy { kd: kd * scale, ks: ks * scale, exponent: m.ns.unwrap_or(10.0) }
        }
        _ => {
            if kd.max_element() > 1.0 {
                warnings.push(format!(
                    "{}:{}: material `{}`: Kd > 1 clamped to 1 to conserve energy",
                    file.display(),
                    m.line,
                    m.name
                ));
            }
            Bsdf::Lambert { kd: kd.min(Vec3::ONE) }
        }
    };
    Material::new(m.name.clone(), bsdf, emission)
}

/// Statement `kw` with arguments `words` at `line` of `path`, applied to the material `m` it
/// belongs to (a statement photonwave reads but does not simulate is noted in `m.ignored`).
fn statement(path: &Path, line: usize, kw: &str, words: &[&str], m: &mut MtlMaterial) -> Result<()> {
    let one = |what: &str| -> Result<f32> {
        match words {
            [w] => number(path, line, what, w),
            _ => Err(Error::parse(path, line, format!("`{what}` needs 1 number, found {}", words.len()))),
        }
    };
    if words.first() == Some(&"spectral") {
        m.ignore(&format!("{kw} spectral"));
    }
    match kw {
        "Kd" => m.kd = colour(path, line, kw, words)?.or(m.kd),
        "Ks" => m.ks = colour(path, line, kw, words)?.or(m.ks),
        "Ke" => m.ke = colour(path, line, kw, words)?.or(m.ke),
        "Ka" => {
            colour(path, line, kw, words)?;
        }
        "Tf" => {
            // The transmission filter: clear (1 1 1) is what photonwave's glass does.
            if colour(path, line, kw, words)?.is_some_and(|c| c != Vec3::ONE) {
                m.ignore(kw);
            }
        }
        "Ns" => {
            let v = one(kw)?;
            if v < 0.0 {
                return Err(Error::parse(path, line, "`Ns` (Phong exponent) must not be negative"));
            }
            m.ns = Some(v);
        }
        "Ni" => {
            let v = one(kw)?;
            if v <= 0.0 {
                return Err(Error::parse(path, line, "`Ni` (index of refraction) must be positive"));
            }
            m.ni = Some(v);
        }
        "illum" => match words {
            [w] if w.parse::<u8>().is_ok_and(|v| v <= 10) => m.illum = w.parse().ok(),
            _ => return Err(Error::parse(path, line, "`illum` needs one integer 0–10 (the MTL spec's models)")),
        },
        "d" | "Tr" => {
            // `d -halo 0.5` is the spec's other form (dissolve by viewing angle: not simulated).
            let (v, halo) = match words {
                ["-halo", w] => (number(path, line, kw, w)?, true),
                _ => (one(kw)?, false),
            };
            if !(0.0..=1.0).contains(&v) {
                return Err(Error::parse(path, line, format!("`{kw}` must be in [0, 1]")));
            }
            if halo {
                let d = if kw == "d" { v } else { 1.0 - v };
                if d < 1.0 {
                    m.ignore("d -halo");
                }
            } else if kw == "d" {
                m.d = Some(v);
            } else {
                m.tr = Some(v);
            }
        }
        "Pr" | "Pm" => {
            let v = one(kw)?;
            if !(0.0..=1.0).contains(&v) {
                let what = if kw == "Pr" { "roughness" } else { "metallic" };
                return Err(Error::parse(path, line, format!("`{kw}` ({what}) must be in [0, 1], found {v}")));
            }
            if kw == "Pr" {
                m.pr = Some(v);
            } else {
                m.pm = Some(v);
            }
        }
        "sharpness" | "Ps" | "Pc" | "Pcr" | "aniso" | "anisor" => {
            one(kw)?;
            m.ignore(kw);
        }
        "Km" => {
            colour(path, line, kw, words)?;
            m.ignore(kw);
        }
        _ if kw.starts_with("map_") || matches!(kw, "bump" | "disp" | "decal" | "refl" | "norm") => {
            let Some(file) = texture_file(words) else {
                return Err(Error::parse(path, line, format!("`{kw}` names no image file")));
            };
            if matches!(kw, "map_Kd" | "map_Ks" | "map_Pr" | "map_Ke" | "map_Pm" | "map_d") {
                if words.first().is_some_and(|w| w.starts_with('-')) {
                    m.ignore(&format!("{kw} options"));
                }
                m.maps.push(MapStatement { key: kw.to_string(), file, line, scale: 1.0 });
            } else if matches!(kw, "bump" | "map_Bump" | "map_bump") {
                // A height field: `-bm` scales the heights, other options are not simulated.
                let scale = bump_multiplier(path, line, words)?;
                if words.iter().any(|w| w.starts_with('-') && *w != "-bm") {
                    m.ignore("bump options");
                }
                m.maps.push(MapStatement { key: "bump".to_string(), file, line, scale });
            } else {
                m.ignore(kw);
            }
        }
        other => return Err(Error::parse(path, line, format!("unknown MTL statement `{other}`"))),
    }
    Ok(())
}

/// Drops the maps a material cannot use: `map_Pr` and `map_Pm` without `Pr` > 0 (a smooth
/// material has no roughness for them to vary), `map_Pm` on a mirror or glass (illum 3–9: no
/// plastic to mix with), and a glass's dissolve (`d`, `Tr`, `map_d` under illum 4, 6, 7 or 9:
/// there the spec's transparency is the glass's own, which the dielectric renders).
fn drop_unusable_maps(m: &mut MtlMaterial) {
    if m.d.is_none() && m.tr == Some(1.0) {
        m.ignore("Tr 1 (read as opaque: exporters write it for d 1)");
    }
    if matches!(m.illum, Some(4 | 6 | 7 | 9)) && (m.dissolve().is_some_and(|d| d < 1.0) || m.map("map_d").is_some()) {
        m.d = None;
        m.tr = None;
        m.maps.retain(|s| s.key != "map_d");
        m.ignored.push("d or map_d on a glass".into());
    }
    for key in ["map_Pr", "map_Pm"] {
        if !m.pr.is_some_and(|r| r > 0.0) && m.map(key).is_some() {
            m.maps.retain(|s| s.key != key);
            m.ignored.push(format!("{key} without Pr > 0"));
        }
    }
    if matches!(m.illum, Some(3..=9)) && m.map("map_Pm").is_some() {
        m.maps.retain(|s| s.key != "map_Pm");
        m.ignored.push("map_Pm on a mirror or glass".into());
    }
}

/// Warns, naming the material's `newmtl` line, of what `m` states that is not simulated.
fn warn_ignored(path: &Path, m: &MtlMaterial, warnings: &mut Vec<String>) {
    if m.ignored.is_empty() {
        return;
    }
    warnings.push(format!(
        "{}:{}: material `{}`: {} not simulated yet (of the texture maps only `map_Kd`, `map_Ks`, \
         `map_Ke`, `map_Pr`, `map_Pm`, `map_d` and `bump` are, without options; the PBR keys are ignored); it renders with its constant \
         colours there",
        path.display(),
        m.line,
        m.name,
        m.ignored.iter().map(|s| format!("`{s}`")).collect::<Vec<_>>().join(", ")
    ));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> (Result<Vec<MtlMaterial>>, Vec<String>) {
        let mut w = Vec::new();
        (parse_mtl(Path::new("m.mtl"), text, &mut w), w)
    }

    #[test]
    fn colours_take_one_three_or_xyz_numbers() {
        let (m, _) = parse("newmtl a\nKd 0.5\nKs 0.1 0.2 0.3\nKe xyz 0.9505 1 1.089\n");
        let m = &m.unwrap()[0];
        assert_eq!(m.kd, Some(Vec3::splat(0.5)));
        assert_eq!(m.ks, Some(Vec3::new(0.1, 0.2, 0.3)));
        assert!((m.ke.unwrap() - Vec3::ONE).abs().max_element() < 2e-3, "D65 white is (1, 1, 1): {:?}", m.ke);
        let e = parse("newmtl a\nKd 0.5 0.5\n").0.unwrap_err().to_string();
        assert!(e.starts_with("m.mtl:2:") && e.contains("3 numbers (or 1"), "{e}");
    }

    #[test]
    fn spec_statements_are_accepted_and_reported_once_per_material() {
        let text = "newmtl a\nKd 1 0 0\nsharpness 60\nKm 0.5\nmap_Kd -o 1 1 1 -s 2 2 2 tex.png\nbump -bm 0.5 b.png\n\
                    d 0.5\nd -halo 0.5\nmap_Ks spec.png\nnewmtl b\nd 1\nTr 0\n";
        let (m, w) = parse(text);
        let m = m.unwrap();
        // `d` is the dissolve read as coverage; its angle-dependent `-halo` form is not.
        assert_eq!(m[0].ignored, ["sharpness", "Km", "map_Kd options", "d -halo"]);
        assert_eq!(m[0].d, Some(0.5));
        assert_eq!(
            m[0].maps.iter().map(|s| (s.key.as_str(), s.file.as_str(), s.line, s.scale)).collect::<Vec<_>>(),
            [("map_Kd", "tex.png", 5, 1.0), ("bump", "b.png", 6, 0.5), ("map_Ks", "spec.png", 9, 1.0)]
        );
        assert!(m[1].ignored.is_empty() && m[1].d == Some(1.0), "opaque `d 1` and `Tr 0` change nothing");
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].starts_with("m.mtl:1: material `a`") && w[0].contains("`map_Kd options`"), "{w:?}");
    }

    /// `d` is the dissolve, `Tr` its complement where `d` is absent; a lone `Tr 1` (exporters'
    /// inverted opaque) is said to be ignored rather than making the surface vanish.
    #[test]
    fn dissolve_reads_d_then_tr() {
        let (m, w) = parse("newmtl a\nTr 0.25\nnewmtl b\nTr 1\nd 0.5\nnewmtl c\nTr 1\n");
        let m = m.unwrap();
        assert_eq!([m[0].dissolve(), m[1].dissolve(), m[2].dissolve()], [Some(0.75), Some(0.5), None]);
        assert!(m[2].ignored.iter().any(|s| s.starts_with("Tr 1")), "{:?}", m[2].ignored);
        assert!(w.len() == 1 && w[0].contains("material `c`"), "{w:?}");
    }

    #[test]
    fn pbr_roughness_and_metallic_make_rough_materials() {
        let text =
            "newmtl metal\nKd 0.9 0.6 0.3\nPm 1\nmap_Pr r.png\nPr 0.4\nnewmtl frosted\nillum 7\nNi 1.4\nPr 0.5\n\
                    newmtl chrome\nKd 0.8 0.8 0.8\nPm 1\nPr 0\nnewmtl plastic\nKd 0.5 0.5 0.5\nPr 0.3\n";
        let (m, w) = parse(text);
        let m = m.unwrap();
        let mut w2 = Vec::new();
        let b: Vec<Bsdf> = m.iter().map(|x| material_from_mtl(x, Path::new("t.mtl"), &mut w2).bsdf).collect();
        assert_eq!(
            b[0],
            Bsdf::RoughConductor { ks: Vec3::new(0.9, 0.6, 0.3), alpha: Alpha::ggx(alpha_of(0.4)), eta_k: None }
        );
        assert!(m[0].map("map_Pr").is_some(), "map_Pr before Pr is kept");
        assert_eq!(b[1], Bsdf::RoughDielectric { ior: 1.4, alpha: Alpha::ggx(alpha_of(0.5)), tint: Tint::CLEAR });
        assert_eq!(b[2], Bsdf::Mirror { ks: Vec3::splat(0.8), eta_k: None });
        assert_eq!(b[3], Bsdf::rough_plastic(Vec3::splat(0.5), 1.5, Alpha::ggx(alpha_of(0.3))));
        assert!(w.is_empty(), "{w:?}");
        for bad in ["Pr 1.5", "Pr -0.1", "Pm 2"] {
            let e = parse(&format!("newmtl a\n{bad}\n")).0.unwrap_err().to_string();
            assert!(e.starts_with("m.mtl:2:") && e.contains("must be in [0, 1]"), "{bad}: {e}");
        }
    }

    #[test]
    fn silent_mistakes_are_errors_or_warnings() {
        let e = parse("newmtl a\nNs -5\n").0.unwrap_err().to_string();
        assert!(e.starts_with("m.mtl:2:") && e.contains("negative"), "{e}");
        let e = parse("newmtl a\nillum 99\n").0.unwrap_err().to_string();
        assert!(e.starts_with("m.mtl:2:") && e.contains("0–10"), "{e}");
        let e = parse("newmtl a\nmap_Kd -clamp on\n").0.unwrap_err().to_string();
        assert!(e.contains("no image file"), "{e}");
        let (m, w) = parse("newmtl a\nKd 1 0 0\nnewmtl b\nnewmtl a\nKd 0 1 0\n");
        let m = m.unwrap();
        assert_eq!(m.iter().map(|m| m.name.as_str()).collect::<Vec<_>>(), ["b", "a"]);
        assert_eq!(m[1].kd, Some(Vec3::Y));
        assert!(w[0].starts_with("m.mtl:4: material `a` is defined again (first at line 1)"), "{w:?}");
    }
}
