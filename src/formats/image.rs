//! Image files into [`Texture`]s: PNG (through `png`), JPEG (through `zune-jpeg`) and OpenEXR
//! (through `exr`, its first RGB layer), told apart by their first bytes, not their names.
//!
//! 8- and 16-bit images are scaled to [0, 1] and, for colour maps, decoded from sRGB; EXR values
//! are linear already and taken as they are. Grey images fill all three channels; alpha is
//! dropped, except from an opacity ([`Encoding::Alpha`], [`Encoding::Opacity`]), which fills
//! every channel with the alpha channel (or, without one, with 1 or the grey level). A file that cannot be read, is not an image of these kinds, is truncated or damaged,
//! has no texels, or holds a non-finite or negative value, is an error naming the file.

use crate::error::{Error, Result};
use crate::files::{bytes, read_input, read_input_len};
use crate::texture::{luminance, srgb_to_linear, Encoding, Texture};
use glam::Vec3;
use std::path::Path;

/// The largest image file read: 1 GiB.
pub const MAX_IMAGE_FILE: u64 = 1 << 30;
/// The most texels an image may have (2²⁸: 3 GiB of linear RGB).
pub const MAX_TEXELS: u64 = 1 << 28;

/// The image formats read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Png,
    Jpeg,
    Exr,
}

/// The format of a file from its signature.
fn sniff(head: &[u8]) -> Option<Format> {
    if head.starts_with(b"\x89PNG\r\n\x1a\n") {
        Some(Format::Png)
    } else if head.starts_with(&[0xFF, 0xD8, 0xFF]) {
        Some(Format::Jpeg)
    } else if head.starts_with(&[0x76, 0x2F, 0x31, 0x01]) {
        Some(Format::Exr)
    } else {
        None
    }
}

thread_local! {
    /// Seconds this thread has spent in [`load_texture`].
    static TEXTURE_SECONDS: std::cell::Cell<f64> = const { std::cell::Cell::new(0.0) };
}

/// Seconds this thread has spent reading and decoding textures so far: a loader takes the
/// difference across its reading ([`crate::scene::LoadTimes::textures_s`]).
#[must_use]
pub fn texture_seconds() -> f64 {
    TEXTURE_SECONDS.with(std::cell::Cell::get)
}

/// Reads the image at `path` (`what` names its use in messages: "`map_Kd` texture").
pub fn load_texture(path: &Path, encoding: Encoding, what: &str) -> Result<Texture> {
    let clock = std::time::Instant::now();
    let texture = read_texture(path, encoding, what);
    TEXTURE_SECONDS.with(|t| t.set(t.get() + clock.elapsed().as_secs_f64()));
    texture
}

/// [`load_texture`], untimed.
fn read_texture(path: &Path, encoding: Encoding, what: &str) -> Result<Texture> {
    let len = read_input_len(path, what)?;
    if len > MAX_IMAGE_FILE {
        return Err(Error::io(
            path,
            format!("is {}, more than the {} accepted for {what}", bytes(len), bytes(MAX_IMAGE_FILE)),
        ));
    }
    let head = {
        use std::io::Read;
        let mut head = [0u8; 8];
        let mut f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        let n = f.read(&mut head).map_err(|e| Error::io(path, e))?;
        head[..n].to_vec()
    };
    let format = sniff(&head).ok_or_else(|| {
        Error::parse(path, 0, format!("{what}: not a PNG, JPEG or OpenEXR image (its first bytes are none of theirs)"))
    })?;
    let (width, height, texels) = match format {
        Format::Exr => {
            let image = crate::film::read_exr(path)?;
            let (_, pixels) = image.layers.into_iter().next().unwrap_or_default();
            // The first RGB layer has no alpha.
            let pixels = match encoding {
                Encoding::Alpha => vec![Vec3::ONE; pixels.len()],
                Encoding::Opacity => pixels.iter().map(|&p| Vec3::splat(luminance(p))).collect(),
                Encoding::Srgb | Encoding::Linear => pixels,
            };
            (image.width, image.height, pixels)
        }
        Format::Png | Format::Jpeg => {
            let data = read_input(path, what, MAX_IMAGE_FILE)?;
            return texture_from_bytes(path, &data, encoding, what);
        }
    };
    finish(path, width, height, texels, what)
}

/// Decodes a PNG or JPEG image held in memory (a glTF file's embedded image); `origin` names it
/// in messages and in the texture.
pub fn texture_from_bytes(origin: &Path, data: &[u8], encoding: Encoding, what: &str) -> Result<Texture> {
    let format = sniff(data).filter(|f| *f != Format::Exr).ok_or_else(|| {
        Error::parse(origin, 0, format!("{what}: not a PNG or JPEG image (its first bytes are neither's)"))
    })?;
    let decoded = std::panic::catch_unwind(|| match format {
        Format::Png => decode_png(data),
        _ => decode_jpeg(data),
    })
    .unwrap_or_else(|_| Err("the decoder failed on it".into()));
    let (w, h, channels, max, values) =
        decoded.map_err(|e| Error::parse(origin, 0, format!("{what}: damaged or unreadable image: {e}")))?;
    finish(origin, w, h, to_rgb(&values, channels, max, encoding), what)
}

/// The texture of `width × height` `texels`, refused when empty, too large or holding a value that
/// is not finite or is negative.
fn finish(path: &Path, width: u32, height: u32, texels: Vec<Vec3>, what: &str) -> Result<Texture> {
    if width == 0 || height == 0 {
        return Err(Error::parse(path, 0, format!("{what}: the image has no texels ({width}×{height})")));
    }
    if u64::from(width) * u64::from(height) > MAX_TEXELS {
        return Err(Error::parse(path, 0, format!("{what}: {width}×{height} texels is more than the 2²⁸ accepted")));
    }
    if let Some(k) = texels.iter().position(|t| !t.is_finite() || t.min_element() < 0.0) {
        let (x, y) = (k as u32 % width, k as u32 / width);
        return Err(Error::parse(
            path,
            0,
            format!("{what}: texel ({x}, {y}) is {}, but textures must be finite and not negative", texels[k]),
        ));
    }
    Texture::new(path, width, height, texels)
        .ok_or_else(|| Error::parse(path, 0, format!("{what}: the image's size does not match its data")))
}

/// Decoded samples: (width, height, channels, the largest sample value, samples row by row).
type Samples = (u32, u32, usize, f32, Vec<u16>);

/// A PNG's samples, palettes expanded.
fn decode_png(data: &[u8]) -> std::result::Result<Samples, String> {
    // At most MAX_TEXELS of 4 channels of 16 bits: 2 GiB.
    let limits = png::Limits { bytes: (MAX_TEXELS * 8) as usize };
    let mut decoder = png::Decoder::new_with_limits(std::io::Cursor::new(data), limits);
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(|e| e.to_string())?;
    let (w, h) = (reader.info().width, reader.info().height);
    check_size(w, h)?;
    let size = reader.output_buffer_size().ok_or("the image is too large")?;
    let mut buf = vec![0u8; size];
    let info = reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
    let channels = info.color_type.samples();
    let (w, h) = (info.width, info.height);
    buf.truncate(info.buffer_size());
    Ok(match info.bit_depth {
        png::BitDepth::Sixteen => {
            let values = buf.chunks_exact(2).map(|b| u16::from_be_bytes([b[0], b[1]])).collect();
            (w, h, channels, 65535.0, values)
        }
        _ => (w, h, channels, 255.0, buf.into_iter().map(u16::from).collect()),
    })
}

/// A JPEG's samples, as RGB or grey.
fn decode_jpeg(data: &[u8]) -> std::result::Result<Samples, String> {
    use zune_jpeg::zune_core::colorspace::ColorSpace;
    use zune_jpeg::zune_core::options::DecoderOptions;
    let options = DecoderOptions::default()
        .set_max_width(1 << 16)
        .set_max_height(1 << 16)
        .jpeg_set_out_colorspace(ColorSpace::RGB);
    let mut decoder = zune_jpeg::JpegDecoder::new_with_options(std::io::Cursor::new(data), options);
    decoder.decode_headers().map_err(|e| e.to_string())?;
    let header = decoder.info().ok_or("no image header")?;
    check_size(u32::from(header.width), u32::from(header.height))?;
    let pixels = decoder.decode().map_err(|e| e.to_string())?;
    let info = decoder.info().ok_or("no image header")?;
    let channels = decoder.output_colorspace().map_or(3, |c| c.num_components());
    let (w, h) = (u32::from(info.width), u32::from(info.height));
    Ok((w, h, channels, 255.0, pixels.into_iter().map(u16::from).collect()))
}

/// Refuses an image header of more than [`MAX_TEXELS`] texels before anything is decoded (a
/// small file can claim a huge image).
fn check_size(w: u32, h: u32) -> std::result::Result<(), String> {
    if u64::from(w) * u64::from(h) > MAX_TEXELS {
        Err(format!("{w}×{h} texels is more than the 2²⁸ accepted"))
    } else {
        Ok(())
    }
}

/// Samples of 1–4 channels as linear RGB (grey repeated, alpha dropped), or as an opacity in
/// every channel ([`Encoding::Alpha`], [`Encoding::Opacity`]).
fn to_rgb(values: &[u16], channels: usize, max: f32, encoding: Encoding) -> Vec<Vec3> {
    let decode = |v: u16| {
        let x = f32::from(v) / max;
        match encoding {
            Encoding::Srgb => srgb_to_linear(x),
            Encoding::Linear | Encoding::Alpha | Encoding::Opacity => x,
        }
    };
    if channels == 0 {
        return Vec::new();
    }
    if matches!(encoding, Encoding::Alpha | Encoding::Opacity) {
        // Grey + alpha and RGBA end with alpha.
        let has_alpha = channels == 2 || channels == 4;
        return values
            .chunks_exact(channels)
            .map(|p| {
                Vec3::splat(match (has_alpha, encoding) {
                    (true, _) => decode(p[channels - 1]),
                    (false, Encoding::Alpha) => 1.0,
                    (false, _) if channels >= 3 => luminance(Vec3::new(decode(p[0]), decode(p[1]), decode(p[2]))),
                    (false, _) => decode(p[0]),
                })
            })
            .collect();
    }
    values
        .chunks_exact(channels)
        .map(|p| {
            if channels >= 3 {
                Vec3::new(decode(p[0]), decode(p[1]), decode(p[2]))
            } else {
                Vec3::splat(decode(p[0]))
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str, bytes: &[u8]) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("pw-image-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    fn png_bytes(w: u32, h: u32, colour: png::ColorType, data: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        let mut e = png::Encoder::new(&mut out, w, h);
        e.set_color(colour);
        e.set_depth(png::BitDepth::Eight);
        e.write_header().unwrap().write_image_data(data).unwrap();
        out
    }

    #[test]
    fn png_colour_is_decoded_from_srgb_and_data_is_not() {
        let p = temp("rgb.png", &png_bytes(2, 1, png::ColorType::Rgb, &[255, 128, 0, 10, 20, 30]));
        let t = load_texture(&p, Encoding::Srgb, "`map_Kd` texture").unwrap();
        assert_eq!((t.width, t.height), (2, 1));
        assert!((t.texels[0] - Vec3::new(1.0, 0.215_861, 0.0)).abs().max_element() < 1e-5, "{}", t.texels[0]);
        let t = load_texture(&p, Encoding::Linear, "`map_Pr` texture").unwrap();
        assert!((t.texels[0].y - 128.0 / 255.0).abs() < 1e-6);
        let g = temp("grey.png", &png_bytes(1, 1, png::ColorType::GrayscaleAlpha, &[255, 7]));
        assert_eq!(load_texture(&g, Encoding::Srgb, "t").unwrap().texels, [Vec3::ONE]);
    }

    /// An opacity is the alpha channel where there is one; without one, 1 for glTF's alpha and
    /// the grey level (RGB: its luminance) for MTL's `map_d`. Never decoded from sRGB.
    #[test]
    fn opacities_read_alpha_or_grey() {
        let rgba = temp("rgba.png", &png_bytes(1, 1, png::ColorType::Rgba, &[255, 255, 255, 51]));
        for e in [Encoding::Alpha, Encoding::Opacity] {
            assert_eq!(load_texture(&rgba, e, "t").unwrap().texels, [Vec3::splat(0.2)]);
        }
        let grey = temp("grey-a.png", &png_bytes(1, 1, png::ColorType::Grayscale, &[51]));
        assert_eq!(load_texture(&grey, Encoding::Alpha, "t").unwrap().texels, [Vec3::ONE]);
        assert_eq!(load_texture(&grey, Encoding::Opacity, "t").unwrap().texels, [Vec3::splat(0.2)]);
        let rgb = temp("rgb-a.png", &png_bytes(1, 1, png::ColorType::Rgb, &[0, 255, 0]));
        let t = load_texture(&rgb, Encoding::Opacity, "t").unwrap();
        assert!((t.texels[0].x - 0.715_16).abs() < 1e-6, "{}", t.texels[0]);
    }

    #[test]
    fn bad_images_are_named() {
        let good = png_bytes(4, 4, png::ColorType::Rgb, &[9; 48]);
        let cut = temp("cut.png", &good[..good.len() - 20]);
        let e = load_texture(&cut, Encoding::Srgb, "`map_Kd` texture").unwrap_err().to_string();
        assert!(e.contains("cut.png") && e.contains("damaged"), "{e}");
        let text = temp("text.png", b"not an image at all");
        let e = load_texture(&text, Encoding::Srgb, "`map_Kd` texture").unwrap_err().to_string();
        assert!(e.contains("text.png") && e.contains("not a PNG, JPEG or OpenEXR"), "{e}");
        let jpeg = temp("cut.jpg", &[0xFF, 0xD8, 0xFF, 0xE0, 0, 16, b'J', b'F']);
        let e = load_texture(&jpeg, Encoding::Srgb, "`map_Kd` texture").unwrap_err().to_string();
        assert!(e.contains("cut.jpg") && e.contains("damaged"), "{e}");
        let e = load_texture(Path::new("/nonexistent/t.png"), Encoding::Srgb, "t").unwrap_err().to_string();
        assert!(e.contains("/nonexistent/t.png"), "{e}");
    }
}
