//! The film: per-pixel sums of each Jensen term, the beauty image as their sum, and output as a
//! multi-layer EXR and a tone-mapped PNG preview.

use crate::error::{Error as PwError, Result};
use glam::Vec3;
use std::path::Path;

/// The terms radiance is split into; their sum is the beauty image.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Terms {
    /// Emission seen directly by the camera.
    pub emitted: Vec3,
    /// Direct light at the first non-specular hit: light sampling, and with MIS the emission
    /// its gather and glossy rays hit straight away.
    pub direct: Vec3,
    /// Everything seen through mirrors and glass, and the glossy lobe's reflection.
    pub specular: Vec3,
    /// Caustic-map estimate at the first non-specular hit.
    pub caustic: Vec3,
    /// Indirect diffuse light (final gather or the global map) at the first non-specular hit.
    pub indirect: Vec3,
    /// Not a term and not in the beauty image: the estimated bias of the photon-map estimates
    /// within the terms above, weighted as they are (fixed radii only: progressive passes; zero
    /// otherwise). The part of [`Film::error`] that the spread between passes cannot show.
    pub bias: Vec3,
}

/// One of the five terms a film keeps apart, in EXR layer order. Every engine routes what it
/// finds to one of these; [`Terms`] holds one value per term.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Term {
    /// Emission seen directly by the camera.
    Emitted,
    /// Direct light at the first non-specular hit.
    Direct,
    /// Everything seen through mirrors and glass, and the glossy lobe's reflection.
    Specular,
    /// The caustic map's estimate at the first non-specular hit.
    Caustic,
    /// Indirect diffuse light at the first non-specular hit.
    Indirect,
}

impl Term {
    /// Every term, in EXR layer order.
    pub const ALL: [Term; 5] = [Term::Emitted, Term::Direct, Term::Specular, Term::Caustic, Term::Indirect];

    /// The term's EXR layer name.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Term::Emitted => "emitted",
            Term::Direct => "direct",
            Term::Specular => "specular",
            Term::Caustic => "caustic",
            Term::Indirect => "indirect",
        }
    }

    /// Where a camera path's findings of this term go: the term itself, or [`Term::Specular`]
    /// once the path has gone through a mirror or glass.
    #[must_use]
    pub fn seen(self, through_specular: bool) -> Term {
        if through_specular {
            Term::Specular
        } else {
            self
        }
    }
}

/// Layer names in EXR order (beauty is the unnamed default layer): [`Term::name`] of [`Term::ALL`].
pub const TERM_NAMES: [&str; 5] =
    [Term::Emitted.name(), Term::Direct.name(), Term::Specular.name(), Term::Caustic.name(), Term::Indirect.name()];

impl Terms {
    /// Sum of all terms.
    #[must_use]
    pub fn beauty(&self) -> Vec3 {
        self.emitted + self.direct + self.specular + self.caustic + self.indirect
    }
    /// The terms as an array, in [`Term::ALL`] order.
    #[inline]
    #[must_use]
    pub fn as_array(&self) -> [Vec3; 5] {
        [self.emitted, self.direct, self.specular, self.caustic, self.indirect]
    }
    /// The value of term `t`.
    #[inline]
    #[must_use]
    pub fn get(&self, t: Term) -> Vec3 {
        match t {
            Term::Emitted => self.emitted,
            Term::Direct => self.direct,
            Term::Specular => self.specular,
            Term::Caustic => self.caustic,
            Term::Indirect => self.indirect,
        }
    }
    /// Adds `v` to term `t`.
    #[inline]
    pub fn add(&mut self, t: Term, v: Vec3) {
        match t {
            Term::Emitted => self.emitted += v,
            Term::Direct => self.direct += v,
            Term::Specular => self.specular += v,
            Term::Caustic => self.caustic += v,
            Term::Indirect => self.indirect += v,
        }
    }
    /// True if every component is finite.
    #[inline]
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.as_array().iter().all(|v| v.is_finite()) && self.bias.is_finite()
    }
}

impl std::ops::AddAssign for Terms {
    fn add_assign(&mut self, o: Terms) {
        self.emitted += o.emitted;
        self.direct += o.direct;
        self.specular += o.specular;
        self.caustic += o.caustic;
        self.indirect += o.indirect;
        self.bias += o.bias;
    }
}

impl std::ops::Mul<f32> for Terms {
    type Output = Terms;
    fn mul(self, s: f32) -> Terms {
        Terms {
            emitted: self.emitted * s,
            direct: self.direct * s,
            specular: self.specular * s,
            caustic: self.caustic * s,
            indirect: self.indirect * s,
            bias: self.bias * s,
        }
    }
}

/// The mean of one pixel's samples, as both engines take it: NaN or infinite samples are dropped
/// and counted, and where the f32 sum of the rest overflows (samples near f32's largest value),
/// each sample is scaled by 1/spp before it is summed. Sums that do not overflow give the plain
/// mean, bit for bit.
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelMean {
    sum: Terms,
    scaled: Terms,
    dropped: u64,
}

impl PixelMean {
    /// Adds one sample; `inv` is 1/spp.
    #[inline]
    pub fn add(&mut self, t: Terms, inv: f32) {
        if t.is_finite() {
            self.sum += t;
            self.scaled += t * inv;
        } else {
            self.dropped += 1;
        }
    }

    /// The mean (`inv` is 1/spp), with the dropped samples and any overflow added to `numerics`.
    #[must_use]
    pub fn finish(self, inv: f32, numerics: &mut crate::stats::Numerics) -> Terms {
        numerics.camera_samples += self.dropped;
        let mean = self.sum * inv;
        if mean.is_finite() {
            mean
        } else {
            numerics.pixel_overflow += 1;
            self.scaled
        }
    }
}

/// A finished image: per-pixel mean of each term, row-major, y down.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Per-pixel terms.
    pub pixels: Vec<Terms>,
    /// Progressive renders: per pixel, the half-width of a 95 % confidence interval of the beauty
    /// image's grey value ((R+G+B)/3) from the spread between the passes — the noise. With the
    /// pixels' estimated bias ([`Terms::bias`]) it makes the error bound of [`Film::error`].
    /// `None` for a single render.
    pub noise: Option<Vec<f32>>,
    /// With `--diagnostics`: per pixel, the density estimates' radii and photon counts.
    pub diagnostics: Option<EstimateLayers>,
}

/// Per pixel, what the density estimates of one camera sample used (`crate::diagnostics`):
/// radius (scene units) and photons summed, of the caustic estimate at the first non-specular
/// point and of the global estimates where the render reads the global map (the mean over the
/// final-gather hits). Written as the EXR layers `radius.caustic`, `photons.caustic`,
/// `radius.global`, `photons.global` (R = G = B).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EstimateLayers {
    /// Caustic estimate's radius.
    pub caustic_radius: Vec<f32>,
    /// Photons in the caustic estimate.
    pub caustic_photons: Vec<f32>,
    /// Global estimates' mean radius.
    pub global_radius: Vec<f32>,
    /// Photons in the global estimates, on average.
    pub global_photons: Vec<f32>,
}

impl Film {
    /// A single render's film: its pixels, without noise or diagnostic layers.
    #[must_use]
    pub fn new(width: u32, height: u32, pixels: Vec<Terms>) -> Self {
        Film { width, height, pixels, noise: None, diagnostics: None }
    }

    /// Beauty image as RGB triples.
    #[must_use]
    pub fn beauty(&self) -> Vec<Vec3> {
        self.pixels.iter().map(Terms::beauty).collect()
    }

    /// Mean of the beauty image (summed in f64, so that bright images do not overflow).
    #[must_use]
    pub fn mean(&self) -> Vec3 {
        let sum: glam::DVec3 = self.pixels.iter().map(|t| t.beauty().as_dvec3()).sum();
        (sum / self.pixels.len().max(1) as f64).as_vec3()
    }

    /// The image as named RGB layers, as [`Film::write_exr`] writes and [`read_exr`] reads them:
    /// `""` (beauty) first, then each term in [`TERM_NAMES`] order.
    #[must_use]
    pub fn layers(&self) -> Vec<(String, Vec<Vec3>)> {
        let mut layers = vec![(String::new(), self.beauty())];
        for term in Term::ALL {
            layers.push((term.name().to_string(), self.pixels.iter().map(|t| t.get(term)).collect()));
        }
        if let Some(error) = self.error() {
            layers.push(("error".to_string(), error.into_iter().map(Vec3::splat).collect()));
            let noise = self.noise.iter().flatten();
            layers.push(("error.noise".to_string(), noise.map(|&v| Vec3::splat(v)).collect()));
            layers.push(("error.bias".to_string(), self.pixels.iter().map(|t| t.bias).collect()));
        }
        if let Some(d) = &self.diagnostics {
            for (name, values) in [
                ("radius.caustic", &d.caustic_radius),
                ("photons.caustic", &d.caustic_photons),
                ("radius.global", &d.global_radius),
                ("photons.global", &d.global_photons),
            ] {
                layers.push((name.to_string(), values.iter().map(|&v| Vec3::splat(v)).collect()));
            }
        }
        layers
    }

    /// Progressive renders: per pixel, a bound on the error of the beauty grey value
    /// ((R+G+B)/3) — the noise's 95 % half-width ([`Film::noise`]) plus the size of the estimated
    /// bias (the grey value of [`Terms::bias`]), after Hachisuka, Jarosz and Jensen (2010). The
    /// EXR layer `error`, beside `error.noise` and the signed RGB `error.bias`. `None` for a
    /// single render.
    #[must_use]
    pub fn error(&self) -> Option<Vec<f32>> {
        let noise = self.noise.as_ref()?;
        Some(noise.iter().zip(&self.pixels).map(|(&n, t)| n + (t.bias.element_sum() / 3.0).abs()).collect())
    }

    /// Writes the EXR: default layer R, G, B = beauty; one layer per term (`direct.R`, …).
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        self.write_exr_with(path, Vec::new(), &[])
    }

    /// [`Film::write_exr`] with `extra` u32 channels (name, one value per pixel) and `text`
    /// header attributes (name, value; characters beyond U+00FF are not allowed by EXR and
    /// must be escaped by the caller).
    pub fn write_exr_with(&self, path: &Path, extra: Vec<(String, Vec<u32>)>, text: &[(&str, String)]) -> Result<()> {
        use exr::prelude::*;
        let size = Vec2(self.width as usize, self.height as usize);
        let mut channels: Vec<AnyChannel<FlatSamples>> = Vec::new();
        for (name, pixels) in self.layers() {
            for (c, suffix) in ["R", "G", "B"].iter().enumerate() {
                let data: Vec<f32> = pixels.iter().map(|p| p[c]).collect();
                let full = if name.is_empty() { suffix.to_string() } else { format!("{name}.{suffix}") };
                channels.push(AnyChannel::new(full.as_str(), FlatSamples::F32(data)));
            }
        }
        for (name, data) in extra {
            channels.push(AnyChannel::new(name.as_str(), FlatSamples::U32(data)));
        }
        let mut attributes = LayerAttributes::default();
        for (name, value) in text {
            let text = Text::new_or_none(value)
                .ok_or_else(|| PwError::output(path, format!("attribute `{name}` has characters EXR cannot hold")))?;
            attributes.other.insert(Text::new_or_panic(name), AttributeValue::Text(text));
        }
        // Blocks in increasing order: with the default (unspecified) order the encoder writes
        // blocks as its threads finish them, and two renders of the same image gave files that
        // differed byte for byte.
        let encoding = Encoding { line_order: LineOrder::Increasing, ..Encoding::FAST_LOSSLESS };
        let layer = Layer::new(size, attributes, encoding, AnyChannels::sort(channels.into()));
        let image = Image::from_layer(layer);
        crate::files::replace(path, |tmp| image.write().to_file(tmp).map_err(|e| PwError::output(path, e)))
    }

    /// Writes a tone-mapped 8-bit sRGB PNG of the beauty image (exposure 1, clamped).
    pub fn write_png(&self, path: &Path) -> Result<()> {
        let bytes: Vec<u8> = self.beauty().iter().flat_map(|c| c.to_array().map(srgb8)).collect();
        crate::files::write_png(path, self.width, self.height, &bytes)
    }
}

/// Linear value → 8-bit sRGB.
fn srgb8(v: f32) -> u8 {
    let v = if v.is_finite() { v.clamp(0.0, 1.0) } else { 0.0 };
    let s = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// An RGB image read from an EXR: its size and every layer that has R, G and B channels, the
/// default (unnamed) layer first as `""`, then the term layers in [`TERM_NAMES`] order, then any
/// others by name.
pub struct ExrLayers {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// (layer name, pixels) — `""` is the beauty image in files written by [`Film::write_exr`].
    pub layers: Vec<(String, Vec<Vec3>)>,
}

/// The most decoded bytes an EXR may claim per byte of file. No OpenEXR compression that the
/// `exr` crate reads packs more: RLE stores at most 128 bytes in 2, deflate (ZIP, PXR24) at
/// most about 1 032 in 1, B44 32 in 14; PIZ's run-length Huffman codes stay below 4 096.
pub const MAX_EXR_RATIO: u64 = 4096;

/// Refuses, before anything is decoded, an EXR whose header claims more pixels than its length
/// could hold at any compression ([`MAX_EXR_RATIO`]) or than the machine's memory could hold
/// while decoding (the samples, then the RGB layers built from them: about 3 times the samples).
fn check_exr_size(path: &Path) -> Result<()> {
    let len = crate::files::read_input_len(path, "an image (EXR)")?;
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| PwError::parse(path, 0, e.to_string()))?;
    let (mut pixels, mut samples) = (0u64, 0u64);
    for h in &meta.headers {
        let px = h.layer_size.0 as u64 * h.layer_size.1 as u64;
        pixels = pixels.max(px);
        samples = samples.saturating_add(px.saturating_mul(h.channels.list.len() as u64));
    }
    let decoded = samples.saturating_mul(4);
    let first = &meta.headers[0].layer_size;
    if decoded > len.saturating_mul(MAX_EXR_RATIO) {
        return Err(PwError::parse(
            path,
            0,
            format!(
                "damaged EXR: its header claims {}×{} pixels ({} of samples), more than its {} could hold \
                 at any compression",
                first.0,
                first.1,
                crate::files::bytes(decoded),
                crate::files::bytes(len)
            ),
        ));
    }
    if let Some((available, total)) = crate::memory::machine() {
        if decoded.saturating_mul(3) > available {
            return Err(PwError::parse(
                path,
                0,
                format!(
                    "its {}×{} pixels need about {} to read, but the machine has {} available of {}",
                    first.0,
                    first.1,
                    crate::files::bytes(decoded.saturating_mul(3)),
                    crate::files::bytes(available),
                    crate::files::bytes(total)
                ),
            ));
        }
    }
    Ok(())
}

/// An EXR decoded whole: every channel of every layer, as stored.
pub type DecodedExr = exr::image::FlatImage;

/// Decodes the EXR at `path` whole. A damaged file is an error naming it, never a crash: sizes
/// are checked before decoding (`check_exr_size`), and a panic inside the decoder is caught
/// and reported as damage.
pub fn decode_exr(path: &Path) -> Result<DecodedExr> {
    check_exr_size(path)?;
    std::panic::catch_unwind(|| exr::prelude::read_all_flat_layers_from_file(path))
        .map_err(|_| PwError::parse(path, 0, "damaged EXR: the decoder failed on it"))?
        .map_err(|e| PwError::parse(path, 0, format!("not a readable EXR: {e}")))
}

/// Reads every RGB layer of the first part of the EXR at `path` ([`decode_exr`], [`rgb_layers`]).
pub fn read_exr(path: &Path) -> Result<ExrLayers> {
    rgb_layers(path, &decode_exr(path)?)
}

/// Every RGB layer of the first part of `image`, decoded from `path`.
pub fn rgb_layers(path: &Path, image: &DecodedExr) -> Result<ExrLayers> {
    let l = image.layer_data.first().ok_or_else(|| PwError::parse(path, 0, "EXR has no layer"))?;
    let (w, h) = (l.size.0, l.size.1);
    let channel = |name: &str| {
        l.channel_data
            .list
            .iter()
            .find(|ch| ch.name.eq(name))
            .map(|ch| ch.sample_data.values_as_f32().collect::<Vec<f32>>())
    };
    // Layer names: the part of `layer.R` before the last dot, "" for a bare `R`.
    let mut names: Vec<String> = l
        .channel_data
        .list
        .iter()
        .filter_map(|ch| {
            let full = ch.name.to_string();
            match full.rsplit_once('.') {
                Some((layer, "R")) => Some(layer.to_string()),
                None if full == "R" => Some(String::new()),
                _ => None,
            }
        })
        .collect();
    // Beauty, then the terms in film order, then anything else by name.
    names.sort_by_key(|n| {
        (!n.is_empty(), TERM_NAMES.iter().position(|t| t == n).unwrap_or(TERM_NAMES.len()), n.clone())
    });
    names.dedup();
    let mut layers = Vec::new();
    for name in names {
        let full = |c: &str| if name.is_empty() { c.to_string() } else { format!("{name}.{c}") };
        if let (Some(r), Some(g), Some(b)) = (channel(&full("R")), channel(&full("G")), channel(&full("B"))) {
            layers.push((name, (0..w * h).map(|i| Vec3::new(r[i], g[i], b[i])).collect()));
        }
    }
    if layers.is_empty() {
        return Err(PwError::parse(path, 0, "EXR has no layer with R, G and B channels"));
    }
    Ok(ExrLayers { width: w as u32, height: h as u32, layers })
}

/// Reads the named layer (`""` for beauty) of an EXR written by [`Film::write_exr`] as RGB.
pub fn read_exr_layer(path: &Path, layer: &str) -> Result<(u32, u32, Vec<Vec3>)> {
    let image = read_exr(path)?;
    let pixels = image
        .layers
        .into_iter()
        .find(|(n, _)| n == layer)
        .map(|(_, p)| p)
        .ok_or_else(|| PwError::parse(path, 0, format!("EXR has no RGB channels for layer `{layer}`")))?;
    Ok((image.width, image.height, pixels))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same film written twice gives the same bytes: blocks are written in increasing order,
    /// not as the encoder's threads finish them (which made 320² renders differ file to file).
    #[test]
    fn the_same_film_writes_the_same_bytes() {
        let (w, h) = (320u32, 320u32);
        let pixels = (0..w * h)
            .map(|i| {
                let v = Vec3::new((i % 97) as f32, (i % 31) as f32, (i % 7) as f32) * 0.01;
                Terms {
                    emitted: v,
                    direct: v * 0.5,
                    specular: Vec3::ZERO,
                    caustic: v * v,
                    indirect: Vec3::new(v.y, v.z, v.x),
                    bias: Vec3::ZERO,
                }
            })
            .collect();
        let film = Film::new(w, h, pixels);
        let dir = std::env::temp_dir().join(format!("photonwave-film-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bytes = |name: &str| {
            let path = dir.join(name);
            film.write_exr(&path).unwrap();
            std::fs::read(&path).unwrap()
        };
        let first = bytes("a.exr");
        for k in 0..4 {
            assert!(first == bytes(&format!("b{k}.exr")), "write {k} differs");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
