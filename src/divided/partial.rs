//! Partial films: the passes of a divided or interrupted progressive render, as an EXR that
//! any viewer shows (the mean of its passes, with every layer a render writes) and that holds
//! what [`crate::divided::pass_sums`] needs to continue or merge it exactly — the per-pixel exact sums as
//! u32 channels (`sum.<value>.w0` … `w3`, the words of each i128, least significant first), the
//! per-pixel sample count (`samples`), and one header attribute, `photonwave`, a JSON record of
//! the passes, the seed, the engine, the version, hashes of the scene's files and of every
//! setting that changes the image, and the stats so far ([`Identity`], [`Partial`]).
//!
//! Reads partial films, checks that they belong to one render, and writes a partial film.

use crate::divided::exact::{ExactSums, NAMES, VALUES};
use crate::divided::pass_set::PassList;
use crate::divided::pass_sums::PassSums;
use crate::error::{Error, Result};
use crate::film::{EstimateLayers, Film};
use crate::settings::Settings;
use crate::stats::RenderStats;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The `format` every partial film written by this version carries.
pub const FORMAT: &str = "photonwave partial film 1";

/// The name of the header attribute holding the record.
pub const ATTRIBUTE: &str = "photonwave";

/// What makes two partial films parts of one render: same scene files, same image settings,
/// same seed, engine and version.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Identity {
    /// photonwave's version.
    pub version: String,
    /// The engine that rendered (`wavefront`, `reference`).
    pub engine: String,
    /// The user's seed.
    pub seed: u64,
    /// FNV-1a 64 of the scene's files, in the order they were read.
    pub scene_hash: String,
    /// Every setting that changes the image (counts and stopping rules aside), the camera and
    /// any added lights.
    pub image: serde_json::Map<String, serde_json::Value>,
    /// FNV-1a 64 of `image` as JSON.
    pub image_hash: String,
}

/// This build: the version, the source's git commit (when built from a git checkout) and the
/// compiler flags — builds that differ in any of them may render different bits.
#[must_use]
pub fn build() -> String {
    format!(
        "{} (commit {}, flags `{}`)",
        env!("CARGO_PKG_VERSION"),
        env!("PHOTONWAVE_COMMIT"),
        env!("PHOTONWAVE_RUSTFLAGS").trim()
    )
}

/// FNV-1a 64 of `bytes`, continuing from `h`.
fn fnv1a(mut h: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// FNV-1a's starting value.
const FNV_START: u64 = 0xcbf2_9ce4_8422_2325;

impl Identity {
    /// The identity of a render of the scene read from `inputs` with per-pass `settings`, seen
    /// by `camera` (its text), with the `--light` presets `lights` (their names), by `engine`.
    pub fn new(inputs: &[PathBuf], settings: &Settings, camera: &str, lights: &[String], engine: &str) -> Result<Self> {
        let mut h = FNV_START;
        for path in inputs {
            let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
            h = fnv1a(h, &(bytes.len() as u64).to_le_bytes());
            h = fnv1a(h, &bytes);
        }
        let mut image = match serde_json::to_value(settings) {
            Ok(serde_json::Value::Object(m)) => m,
            _ => serde_json::Map::new(),
        };
        // How many passes, when to stop and how many threads do not change a pass's image.
        for key in ["passes", "target_error", "threads"] {
            image.remove(key);
        }
        image.insert("camera".into(), camera.into());
        image.insert("lights".into(), lights.to_vec().into());
        let text = serde_json::to_string(&image).unwrap_or_default();
        Ok(Identity {
            version: build(),
            engine: engine.to_string(),
            seed: settings.seed,
            scene_hash: format!("{:016x}", fnv1a(FNV_START, &(h.to_le_bytes()))),
            image_hash: format!("{:016x}", fnv1a(FNV_START, text.as_bytes())),
            image,
        })
    }

    /// Why `o` (named `b`, e.g. its file) is not part of the same render as `self` (named `a`),
    /// naming the first difference; `None` when it is.
    #[must_use]
    pub fn difference(&self, a: &str, o: &Identity, b: &str) -> Option<String> {
        if self.version != o.version {
            return Some(format!("{a} is of photonwave {}, {b} of photonwave {}", self.version, o.version));
        }
        if self.engine != o.engine {
            return Some(format!("{a} was rendered by the {} engine, {b} by the {}", self.engine, o.engine));
        }
        if self.seed != o.seed {
            return Some(format!("{a} has seed {}, {b} seed {}", self.seed, o.seed));
        }
        if self.scene_hash != o.scene_hash {
            return Some(format!(
                "{a} and {b} are renders of different scene files (or of a file changed between them)"
            ));
        }
        if self.image_hash != o.image_hash {
            let keys: std::collections::BTreeSet<&String> = self.image.keys().chain(o.image.keys()).collect();
            let null = serde_json::Value::Null;
            for k in keys {
                let (x, y) = (self.image.get(k).unwrap_or(&null), o.image.get(k).unwrap_or(&null));
                if x != y {
                    return Some(format!("{a} and {b} differ in setting `{k}`: {x} against {y}"));
                }
            }
            return Some(format!("{a} and {b} differ in their image settings"));
        }
        None
    }
}

/// The record in a partial film's `photonwave` attribute.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Record {
    format: String,
    identity: Identity,
    /// The passes summed ([`PassList::to_text`]).
    passes: String,
    /// Samples per pixel in each pass.
    spp: u32,
    /// The stats of the passes summed.
    stats: RenderStats,
}

/// A partial film read back.
#[derive(Clone, Debug)]
pub struct Partial {
    /// Where it was read from.
    pub path: PathBuf,
    /// Which render it belongs to.
    pub identity: Identity,
    /// Its passes' exact sums.
    pub sums: PassSums,
    /// Samples per pixel in each pass.
    pub spp: u32,
    /// The stats of its passes.
    pub stats: RenderStats,
    /// Its diagnostic layers (of its last pass), if it has them.
    pub diagnostics: Option<EstimateLayers>,
}

/// JSON with every character beyond ASCII escaped (`\uXXXX`), as an EXR attribute holds bytes.
fn ascii_json(value: &impl Serialize) -> String {
    let text = serde_json::to_string(value).unwrap_or_default();
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_ascii() {
            out.push(c);
        } else {
            let mut units = [0u16; 2];
            for u in c.encode_utf16(&mut units) {
                out.push_str(&format!("\\u{u:04x}"));
            }
        }
    }
    out
}

/// Writes the partial film of `sums` to `path` (atomically: a temporary file renamed over it,
/// so an interrupted write leaves the previous file whole): `film` as the viewable layers (the
/// passes' mean, from `sums.image()`, with diagnostic layers if it has them), then the sums, the
/// sample counts and the record.
pub fn write(
    path: &Path,
    identity: &Identity,
    sums: &PassSums,
    spp: u32,
    film: &Film,
    stats: &RenderStats,
) -> Result<()> {
    let s = &sums.sums;
    let mut extra = Vec::with_capacity(VALUES * 4 + 1);
    for (k, name) in NAMES.iter().enumerate() {
        for w in 0..4 {
            extra.push((format!("sum.{name}.w{w}"), s.words(k, w)));
        }
    }
    let samples = sums.passes().saturating_mul(spp);
    extra.push(("samples".to_string(), vec![samples; s.len()]));
    let record = Record {
        format: FORMAT.to_string(),
        identity: identity.clone(),
        passes: sums.done.to_text(),
        spp,
        stats: stats.clone(),
    };
    film.write_exr_with(path, extra, &[(ATTRIBUTE, ascii_json(&record))])
}

/// Reads the partial film at `path`. A file that is not one (no record, no sums, another
/// format), a damaged one or a truncated one is an error naming it.
pub fn read(path: &Path) -> Result<Partial> {
    use exr::prelude::{AttributeValue, FlatSamples, Text};
    let bad = |m: String| Error::parse(path, 0, m);
    let image = crate::film::decode_exr(path)?;
    let layer = image.layer_data.first().ok_or_else(|| bad("EXR has no layer".into()))?;
    let text = match layer.attributes.other.get(&Text::new_or_panic(ATTRIBUTE)) {
        Some(AttributeValue::Text(t)) => t.to_string(),
        _ => {
            return Err(bad("not a photonwave partial film (no `photonwave` attribute): only `render --pass-set`, \
                 `--passes A..B`, `--partial`, `--checkpoint` and an interrupted render write one"
                .into()))
        }
    };
    let damaged = |e: serde_json::Error| bad(format!("its `photonwave` attribute is damaged: {e}"));
    // The format first, so that a film of another format says so rather than fail to read.
    let value: serde_json::Value = serde_json::from_str(&text).map_err(damaged)?;
    let format = value.get("format").and_then(serde_json::Value::as_str).unwrap_or("none");
    if format != FORMAT {
        return Err(bad(format!("a partial film of format `{format}`; this photonwave reads `{FORMAT}`")));
    }
    let record: Record = serde_json::from_value(value).map_err(damaged)?;
    let done = PassList::parse(&record.passes).map_err(|m| bad(format!("its passes: {m}")))?;
    // α as the settings hold it: an f32 whose f64 value JSON keeps exactly.
    let alpha = record.identity.image.get("alpha").and_then(serde_json::Value::as_f64).map(|a| a as f32);
    let Some(alpha) = alpha.filter(|a| *a > 0.0 && *a < 1.0) else {
        return Err(bad("its settings have no valid `alpha` (in (0, 1)): damaged".into()));
    };
    let (w, h) = (layer.size.0 as u32, layer.size.1 as u32);
    let channel = |k: usize, word: usize| -> Option<&[u32]> {
        let name = format!("sum.{}.w{word}", NAMES[k]);
        match layer.channel_data.list.iter().find(|c| c.name.eq(name.as_str())).map(|c| &c.sample_data) {
            Some(FlatSamples::U32(v)) if v.len() == w as usize * h as usize => Some(v),
            _ => None,
        }
    };
    let missing = NAMES
        .iter()
        .enumerate()
        .flat_map(|(k, name)| (0..4).map(move |word| (k, word, name)))
        .find(|&(k, word, _)| channel(k, word).is_none())
        .map(|(_, word, name)| format!("sum.{name}.w{word}"));
    let words = |k: usize, word: usize| channel(k, word).unwrap_or_default();
    if let Some(name) = missing {
        return Err(bad(format!(
            "partial film without its u32 channel `{name}`: damaged, or not written by photonwave"
        )));
    }
    let sums = ExactSums::from_words(w, h, &words);
    // The diagnostic layers hold R = G = B: their R channels.
    let layer_of = |name: &str| {
        let name = format!("{name}.R");
        let c = layer.channel_data.list.iter().find(|c| c.name.eq(name.as_str()))?;
        Some(c.sample_data.values_as_f32().collect::<Vec<f32>>())
    };
    let diagnostics = match (
        layer_of("radius.caustic"),
        layer_of("photons.caustic"),
        layer_of("radius.global"),
        layer_of("photons.global"),
    ) {
        (Some(caustic_radius), Some(caustic_photons), Some(global_radius), Some(global_photons)) => {
            Some(EstimateLayers { caustic_radius, caustic_photons, global_radius, global_photons })
        }
        _ => None,
    };
    Ok(Partial {
        path: path.to_path_buf(),
        identity: record.identity,
        sums: PassSums::from_sums(sums, done, alpha),
        spp: record.spp,
        stats: record.stats,
        diagnostics,
    })
}
