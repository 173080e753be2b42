//! What a render will need in memory, estimated before any work, and what the machine has.
//!
//! The costs were measured with `/usr/bin/time -f %M` (peak resident set) on the bundled
//! Cornell box, every engine (BENCHMARKS.md, "Memory"): about 147 bytes per pixel (film terms,
//! per-pixel sums and radii, camera queues and the EXR's channels while it is written) and
//! about 81 bytes per stored photon (the map's columns, the kd-tree and the deposits sorted
//! before they are stored; the tree's nodes added about 3.4 B in issue 18: 84 B), over a base
//! of about 12 MiB. The estimate rounds each up.

use crate::error::{Error, Result};
use crate::files::bytes;

/// Bytes per pixel of the image (measured 147).
pub const BYTES_PER_PIXEL: u64 = 160;
/// Bytes per stored photon (measured 81, then 84 with the tree's nodes).
pub const BYTES_PER_PHOTON: u64 = 96;
/// Bytes per pixel a progressive render adds (measured 390 at 800², peak resident set of
/// `--passes 2` against one pass, BENCHMARKS.md "Divided renders"): its passes' exact sums
/// (`crate::divided::exact`, 20 values of 16 bytes), the pass's film beside them and the mean's.
pub const PROGRESSIVE_BYTES_PER_PIXEL: u64 = 400;

/// Bytes per pixel of a render, progressive or not.
#[must_use]
pub fn bytes_per_pixel(progressive: bool) -> u64 {
    BYTES_PER_PIXEL + if progressive { PROGRESSIVE_BYTES_PER_PIXEL } else { 0 }
}

/// Bytes of everything else (measured 12 MiB; the scene itself is already loaded).
pub const BASE_BYTES: u64 = 16 << 20;

/// Bytes per triangle of the 8-wide BVH the SIMD traversal builds for single rays and 8-wide
/// packets (measured 91–93 on the bunny, the ogre and the 1 M-triangle sphere, BENCHMARKS.md
/// issue 18): built during the render, so it counts against the machine's memory.
pub const WIDE_BVH_BYTES_PER_TRIANGLE: u64 = 96;

/// A render's estimated peak memory, in bytes: a `width × height` image at `per_pixel` bytes a
/// pixel ([`bytes_per_pixel`]), `photons` stored in all its maps together, and `scene_bytes` of
/// structures built over the scene during the render (the 8-wide BVH).
#[must_use]
pub fn estimate(width: u32, height: u32, per_pixel: u64, photons: u64, scene_bytes: u64) -> u64 {
    BASE_BYTES + u64::from(width) * u64::from(height) * per_pixel + photons * BYTES_PER_PHOTON + scene_bytes
}

/// The machine's memory available to a new allocation and in all (Linux `/proc/meminfo`'s
/// `MemAvailable` and `MemTotal`), in bytes; `None` where it cannot be read.
#[must_use]
pub fn machine() -> Option<(u64, u64)> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let field = |name: &str| -> Option<u64> {
        let line = text.lines().find(|l| l.starts_with(name))?;
        let kib: u64 = line[name.len()..].trim().trim_end_matches("kB").trim().parse().ok()?;
        Some(kib * 1024)
    };
    Some((field("MemAvailable:")?, field("MemTotal:")?))
}

/// Refuses a render whose estimate exceeds `available` bytes (of `total`), saying what it would
/// need, what the machine has, and what to lower.
pub fn check(
    width: u32,
    height: u32,
    per_pixel: u64,
    photons: u64,
    scene_bytes: u64,
    available: u64,
    total: u64,
) -> Result<()> {
    let need = estimate(width, height, per_pixel, photons, scene_bytes);
    if need <= available {
        return Ok(());
    }
    let pixels = u64::from(width) * u64::from(height);
    Err(Error::setting(
        if pixels * per_pixel >= photons * BYTES_PER_PHOTON { "width" } else { "photons" },
        format!(
            "this render needs about {} ({width}×{height} pixels at ~{per_pixel} B, {photons} photons at \
             ~{BYTES_PER_PHOTON} B, {} for the scene's 8-wide BVH), but the machine has {} available of \
             {}; lower the image size or the photon counts (docs/src/bad-input.md, \"Limits\")",
            bytes(need),
            bytes(scene_bytes),
            bytes(available),
            bytes(total)
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_huge_image_is_refused_with_the_estimate_and_the_machine() {
        let e = check(16384, 16384, BYTES_PER_PIXEL, 200_000, 0, 20 << 30, 24 << 30).unwrap_err().to_string();
        assert!(
            e.starts_with("setting `width`") && e.contains("40.0 GiB") && e.contains("20.0 GiB available of 24.0 GiB"),
            "{e}"
        );
        check(320, 320, BYTES_PER_PIXEL, 300_000, 0, 1 << 30, 1 << 30).unwrap();
        let e = check(320, 320, BYTES_PER_PIXEL, 200_000_000, 0, 8 << 30, 8 << 30).unwrap_err().to_string();
        assert!(e.starts_with("setting `photons`") && e.contains("200000000 photons"), "{e}");
        // A scene of 10 M triangles: its 8-wide BVH (~0.9 GiB) tips a render that fits without it.
        let wide = 10_000_000 * WIDE_BVH_BYTES_PER_TRIANGLE;
        let without = estimate(320, 320, BYTES_PER_PIXEL, 300_000, 0);
        check(320, 320, BYTES_PER_PIXEL, 300_000, 0, without + (1 << 20), 8 << 30).unwrap();
        let e = check(320, 320, BYTES_PER_PIXEL, 300_000, wide, without + (1 << 20), 8 << 30).unwrap_err().to_string();
        assert!(e.contains("915.5 MiB for the scene's 8-wide BVH"), "{e}");
    }

    #[test]
    fn this_machine_reports_its_memory() {
        if let Some((available, total)) = machine() {
            assert!(available > 0 && available <= total, "{available} of {total}");
        }
    }
}
