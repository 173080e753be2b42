//! Mitsuba's BSDFs as Mitsuba 3 itself evaluates them: `tests/data/mitsuba-bsdfs.tsv`, written by
//! `tests/data/mitsuba-bsdfs.py` through Mitsuba's Python API, holds f and the sampling pdf of
//! every BSDF photonwave renders as Mitsuba does, over a grid of parameters and direction pairs
//! (conductors by Mitsuba's named metals and by η, k with a `specular_reflectance`; for the
//! smooth `conductor`, the `thindielectric` and the smooth `plastic`'s coat, delta lobes, a sample's direction and weight and
//! the probability of its lobe); photonwave's must match.
//!
//! Tolerance, derived. The analytic BSDFs (diffuse, conductors, rough dielectric) are the
//! same formulas on both sides in f32: some 20 roundings of 6·10⁻⁸ each, so 2·10⁻⁶ relative; with
//! D and Λ computed from the sine² as x² + y² (not 1 − cos², which loses the peak of a narrow
//! lobe), near the peaks too. They are held to 10⁻⁵ (measured: 5.5·10⁻⁶). The rough plastic's
//! base reads tables that both sides integrate with the same Gauss–Legendre nodes but through
//! different maps from the unit square to visible normals (ours Heitz 2018's, Mitsuba's the
//! concentric-disk one), so the two quadratures differ by up to 10⁻⁴ in T and F_dr (measured):
//! f = coat + kd′·T·T/(πη²) with kd′ = kd/(1 − F_dr) moves by at most 3·10⁻⁴/(1 − F_dr) ≈
//! 7·10⁻⁴ relative (held to 10⁻³; measured 4.7·10⁻⁴); the pdf's choice between coat and base
//! weighs by 1 − T, which near normal incidence is 0.04, so 10⁻⁴ in T moves it by 0.25 % and the
//! pdf by up to 0.4 % (held to 5·10⁻³; measured 3.9·10⁻³). Below 10⁻⁶ absolute (a grazing
//! direction where G1 → 0, Mitsuba's cut-off of D·cos below 10⁻²⁰) values count as equal.
//!
//! Beckmann's masking: Mitsuba evaluates Walter et al.'s rational approximation of Smith's G1
//! (up to 0.31 % above it), photonwave Smith's own. Before comparing, the test puts Mitsuba's in
//! place of ours ([`mitsuba_masking`]: f carries G1(wo)·G1(wi), the pdf G1(wo), for the plastic
//! its coat's share), so the rest of the formulas is held to the tolerances above; the
//! difference itself is at most 0.31 % per G1 (`microfacet::distribution`'s doc).

use glam::Vec3;
use photonwave::material::{fresnel_dielectric, Bsdf, SurfaceFrame, Tint, Transport};
use photonwave::microfacet::{Alpha, Distribution};
use photonwave::optics::{named_metal, thin_slab_reflectance, ComplexIor};

/// One row: BSDF name, parameters, wo, wi, f (RGB), pdf.
struct Row {
    bsdf: String,
    params: String,
    wo: Vec3,
    wi: Vec3,
    f: Vec3,
    pdf: f32,
}

fn rows() -> Vec<Row> {
    let text = include_str!("data/mitsuba-bsdfs.tsv");
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("bsdf\t"))
        .map(|l| {
            let c: Vec<&str> = l.split('\t').collect();
            let x: Vec<f32> = c[2..].iter().map(|v| v.parse().expect("a number")).collect();
            Row {
                bsdf: c[0].to_string(),
                params: c[1].to_string(),
                wo: Vec3::new(x[0], x[1], x[2]),
                wi: Vec3::new(x[3], x[4], x[5]),
                f: Vec3::new(x[6], x[7], x[8]),
                pdf: x[9],
            }
        })
        .collect()
}

/// A parameter of a row (`name=value;…`) as text.
fn text<'a>(params: &'a str, name: &str) -> Option<&'a str> {
    params.split(';').find_map(|kv| kv.strip_prefix(name).and_then(|v| v.strip_prefix('=')))
}

/// A parameter of a row, as numbers.
fn param(params: &str, name: &str) -> Vec<f32> {
    text(params, name)
        .map(|v| {
            v.split(',')
                .map(|x| {
                    if x == "True" {
                        1.0
                    } else if x == "False" {
                        0.0
                    } else {
                        x.parse().unwrap()
                    }
                })
                .collect()
        })
        .unwrap_or_else(|| panic!("no {name} in {params}"))
}

/// A row's microfacets: its `distribution` (GGX where the row names none), `alpha` or
/// `alpha_u` and `alpha_v`.
fn alpha(params: &str) -> Alpha {
    let distribution = match text(params, "distribution") {
        Some("beckmann") => Distribution::Beckmann,
        Some("ggx") | None => Distribution::Ggx,
        Some(other) => panic!("no distribution {other}"),
    };
    let a = Alpha::new(distribution, param(params, "alpha")[0]);
    match text(params, "alpha_u") {
        Some(_) => a.anisotropic(param(params, "alpha_u")[0], param(params, "alpha_v")[0]),
        None => a,
    }
}

/// photonwave's BSDF for a row's Mitsuba BSDF and parameters, as the Mitsuba reader makes it.
fn ours(bsdf: &str, params: &str) -> Bsdf {
    let v3 = |v: Vec<f32>| Vec3::new(v[0], v[1], v[2]);
    // A dielectric's `specular_reflectance` and `specular_transmittance` (1 where not given).
    let scale = |name: &str| if text(params, name).is_some() { v3(param(params, name)) } else { Vec3::ONE };
    let tint = Tint { reflect: scale("rt"), transmit: scale("tt") };
    match bsdf {
        "diffuse" => Bsdf::Lambert { kd: v3(param(params, "kd")) },
        "roughconductor" | "conductor" => {
            // As the Mitsuba reader maps them: a named metal's complex index, or η and k, times
            // `specular_reflectance`.
            let (ks, eta_k) = match text(params, "metal") {
                Some(metal) => (Vec3::ONE, named_metal(metal).expect("a metal Mitsuba names")),
                None => match text(params, "eta") {
                    Some(_) => (
                        v3(param(params, "ks")),
                        ComplexIor { eta: v3(param(params, "eta")), k: v3(param(params, "k")) },
                    ),
                    None => (Vec3::ONE, named_metal("none").unwrap()),
                },
            };
            if bsdf == "conductor" {
                Bsdf::Mirror { ks, eta_k: Some(eta_k) }
            } else {
                Bsdf::RoughConductor { ks, alpha: alpha(params), eta_k: Some(eta_k) }
            }
        }
        "roughdielectric" => Bsdf::RoughDielectric { ior: param(params, "ior")[0], alpha: alpha(params), tint },
        "roughplastic" => Bsdf::rough_plastic(v3(param(params, "kd")), param(params, "ior")[0], alpha(params))
            .with_nonlinear(param(params, "nonlinear")[0] == 1.0)
            .with_coat_scale(v3(param(params, "ks"))),
        "thindielectric" => Bsdf::ThinGlass { ior: param(params, "ior")[0], tint, passed: false },
        "dielectric" => Bsdf::Glass { ior: param(params, "ior")[0], tint },
        "plastic" | "plastic-coat" => Bsdf::Plastic {
            kd: v3(param(params, "kd")),
            ks: v3(param(params, "ks")),
            eta: param(params, "ior")[0],
            nonlinear: param(params, "nonlinear")[0] == 1.0,
        },
        other => panic!("no mapping for {other}"),
    }
}

/// Walter et al.'s rational approximation of Beckmann's G1, which Mitsuba evaluates in its
/// place, over Smith's exact G1 that photonwave uses (`microfacet::distribution`).
fn walter_over_smith(alpha: Alpha, w: Vec3) -> f32 {
    let w = Vec3::new(w.x, w.y, w.z.abs());
    let t = ((alpha.u * w.x).powi(2) + (alpha.v * w.y).powi(2)) / (w.z * w.z);
    if t == 0.0 {
        return 1.0;
    }
    let a = 1.0 / t.sqrt();
    let walter = if a >= 1.6 { 1.0 } else { (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a) };
    walter / alpha.g1(w)
}

/// photonwave's f and pdf of a Beckmann material with Mitsuba's masking put in place of its
/// own: the microfacet lobes' f carries G1(wo)·G1(wi), their pdf G1(wo) (for the plastic, the
/// coat's share of each); unchanged for other materials.
fn mitsuba_masking(b: &Bsdf, wo: Vec3, wi: Vec3, f: Vec3, pdf: f32) -> (Vec3, f32) {
    let (Bsdf::RoughConductor { alpha, .. } | Bsdf::RoughDielectric { alpha, .. } | Bsdf::RoughPlastic { alpha, .. }) =
        *b
    else {
        return (f, pdf);
    };
    if alpha.distribution != Distribution::Beckmann {
        return (f, pdf);
    }
    let (ro, ri) = (walter_over_smith(alpha, wo), walter_over_smith(alpha, wi));
    match b.plastic() {
        Some(p) => {
            let frame = SurfaceFrame { ng: Vec3::Z, ns: Vec3::Z };
            let coat = b.eval_lobe(&frame, wo, wi);
            let coat_pdf = p.coat_probability(wo) * b.glossy_pdf(&frame, wo, wi);
            (f + coat * (ro * ri - 1.0), pdf + coat_pdf * (ro - 1.0))
        }
        None => (f * (ro * ri), pdf * ro),
    }
}

#[test]
fn every_bsdf_evaluates_as_mitsuba_3_does() {
    let frame = SurfaceFrame { ng: Vec3::Z, ns: Vec3::Z };
    let abs = 1e-6f32;
    let close = |a: f32, b: f32, rel: f32| (a - b).abs() <= rel * a.abs().max(b.abs()) + abs;
    let mut worst: std::collections::BTreeMap<String, (f32, f32)> = Default::default();
    let mut failures = vec![];
    let all = rows();
    assert!(all.len() > 1000, "the table has {} rows", all.len());
    for r in &all {
        let b = ours(&r.bsdf, &r.params);
        let (f, pdf) = if r.bsdf == "plastic-coat" {
            // The smooth plastic's coat: its sample (u = 0 picks it), weight F·ks over its
            // probability, and that probability.
            let s = b.sample(&frame, r.wo, [0.5, 0.5, 0.0], Transport::Radiance).expect("the coat reflects");
            assert!(s.delta && (s.wi - r.wi).length() < 1e-6, "{}: {:?} against {:?}", r.params, s.wi, r.wi);
            (s.weight, b.smooth_plastic().expect("a smooth plastic").coat_probability(r.wo))
        } else if b.is_delta() {
            // A delta lobe: the sample's direction and weight, and the chosen lobe's probability
            // (the sheet's reflectance R′ or 1 − R′; 1 for the mirror).
            let reflects = r.wi.z * r.wo.z > 0.0;
            let u = if reflects { 0.0 } else { 0.99999 };
            let s = b.sample(&frame, r.wo, [u, 0.5, 0.5], Transport::Radiance).expect("a delta lobe scatters");
            assert!((s.wi - r.wi).length() < 1e-6, "{} {}: {:?} against {:?}", r.bsdf, r.params, s.wi, r.wi);
            let p = match b {
                Bsdf::ThinGlass { ior, .. } => thin_slab_reflectance(r.wo.z, ior),
                // Fresnel from wo's side (its index ratio inverted from inside).
                Bsdf::Glass { ior, .. } => fresnel_dielectric(r.wo.z.abs(), if r.wo.z > 0.0 { ior } else { 1.0 / ior }),
                _ => 1.0,
            };
            (s.weight, if reflects { p } else { 1.0 - p })
        } else {
            mitsuba_masking(&b, r.wo, r.wi, b.eval(&frame, r.wo, r.wi), b.pdf(&frame, r.wo, r.wi))
        };
        let (rel_f, rel_pdf) = if r.bsdf == "roughplastic" { (1e-3, 5e-3) } else { (1e-5, 1e-5) };
        let e = |a: f32, b: f32| (a - b).abs() / (a.abs().max(b.abs()) + 1e3 * abs);
        let w = worst.entry(format!("{} {}", r.bsdf, r.params)).or_default();
        w.0 = w.0.max((0..3).map(|c| e(f[c], r.f[c])).fold(0.0, f32::max));
        w.1 = w.1.max(e(pdf, r.pdf));
        if !(0..3).all(|c| close(f[c], r.f[c], rel_f)) || !close(pdf, r.pdf, rel_pdf) {
            failures.push(format!(
                "{} {} wo {:?} wi {:?}: f {f:?} against {:?}, pdf {pdf} against {}",
                r.bsdf, r.params, r.wo, r.wi, r.f, r.pdf
            ));
        }
    }
    for (k, (ef, ep)) in &worst {
        println!("{k}: worst relative error f {ef:.2e}, pdf {ep:.2e}");
    }
    assert!(
        failures.is_empty(),
        "{} of {} rows differ:\n{}",
        failures.len(),
        all.len(),
        failures[..failures.len().min(20)].join("\n")
    );
}
