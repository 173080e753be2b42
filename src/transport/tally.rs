//! The tally of a map's photon pass: the photons stored as batches of paths come in, the
//! photons among them stored where the camera reads the map, and the stopping rule that ends
//! emission at exactly the photons a map asks for (counting only the paths it keeps).

use crate::photon_map::reach::ReadCells;
use crate::photon_map::Photon;
use crate::settings::{EMPTY_PATHS_PER_PHOTON, MAX_PATHS_PER_PHOTON, STEERED_PATHS};
use crate::stats::Numerics;

/// Paths per batch: emission runs batch by batch until a map reaches its target.
pub const BATCH: usize = 16_384;
/// A map's photons as batches of paths come in, and the stopping rule: emission stops at the
/// path that stores the target's last photon, so a map holds exactly the photons asked for and
/// its power is divided by the paths emitted up to that one. That path's later bounces are not
/// stored (as in Jensen 1996, where emission stops when the map is full): one path of thousands,
/// a bias far below the estimate's noise. Emission also stops after
/// [`MAX_PATHS_PER_PHOTON`] paths per wanted photon, for scenes that store almost nothing.
///
/// Steered by the cells where the camera reads the map ([`Tally::reading`]), the target counts only
/// the photons stored there: a sun outside a lit room does not fill the room's map with
/// photons on its roof. The photons stored elsewhere are kept (the cells come from a sample of
/// the camera's paths), and emission stops too at [`STEERED_PATHS`] times the paths that
/// stored the target in all photons; a map that has stored none where the camera reads after [`EMPTY_PATHS_PER_PHOTON`]
/// paths per photon asked stops as an empty one does.
///
/// The counts of [`PathCounts`] are summed over the kept paths only: the paths of the last
/// batch past the one that stores the last photon are traced but their rays and numerics are
/// not counted, so both engines count what the map holds, however a wave is cut.
#[derive(Debug, Default)]
pub struct Tally<'a> {
    target: u64,
    cap: u64,
    /// The paths emitted when the map first held its target in all photons.
    full_at: Option<u64>,
    cells: Option<&'a ReadCells>,
    steer: bool,
    photons: Vec<Photon>,
    read: u64,
    emitted: u64,
    rays: u64,
    numerics: Numerics,
}

impl<'a> Tally<'a> {
    /// An empty tally for a map of `target` photons, every stored photon counted.
    #[must_use]
    pub fn new(target: u32) -> Self {
        let target = u64::from(target);
        Tally {
            target,
            cap: (target * MAX_PATHS_PER_PHOTON).max(BATCH as u64),
            full_at: None,
            cells: None,
            steer: false,
            photons: Vec::new(),
            read: 0,
            emitted: 0,
            rays: 0,
            numerics: Numerics::default(),
        }
    }

    /// An empty tally that also counts the photons stored where `cells` says the camera reads:
    /// with `steer`, the target counts only those; without, every stored photon (as
    /// [`Tally::new`]), the others counted for the record.
    #[must_use]
    pub fn reading(target: u32, cells: Option<&'a ReadCells>, steer: bool) -> Self {
        Tally { cells, steer: steer && cells.is_some(), ..Tally::new(target) }
    }

    /// The count the target is met by: photons stored where the camera reads when steered, else
    /// every stored photon.
    #[must_use]
    pub fn counted(&self) -> u64 {
        if self.steer {
            self.read
        } else {
            self.stored()
        }
    }

    /// Whether another batch should be emitted: the map is short of its target, below the path
    /// and stored-photon caps, and not still empty (where the camera reads) after
    /// [`EMPTY_PATHS_PER_PHOTON`] paths per photon asked.
    #[must_use]
    pub fn wants_more(&self) -> bool {
        let empty = self.counted() == 0 && self.emitted >= self.target * EMPTY_PATHS_PER_PHOTON;
        self.counted() < self.target && !self.steered_out(self.emitted) && self.emitted < self.cap && !empty
    }

    /// Index of the next batch's first path (the paths emitted so far).
    #[must_use]
    pub fn emitted(&self) -> u64 {
        self.emitted
    }

    /// Photons stored so far.
    #[must_use]
    pub fn stored(&self) -> u64 {
        self.photons.len() as u64
    }

    /// Whether a steered tally has gone [`STEERED_PATHS`] times as many paths as it took to hold
    /// its target in all photons, by path `path`.
    fn steered_out(&self, path: u64) -> bool {
        self.steer && self.full_at.is_some_and(|full| path >= STEERED_PATHS * full)
    }

    /// Photons stored so far where the camera reads the map (all of them without cells).
    #[must_use]
    pub fn read(&self) -> u64 {
        self.read
    }

    /// Batches left before the path cap.
    #[must_use]
    pub fn batches_left(&self) -> usize {
        let end = match (self.steer, self.full_at) {
            (true, Some(full)) => self.cap.min(STEERED_PATHS * full),
            _ => self.cap,
        };
        (end - self.emitted.min(end)).div_ceil(BATCH as u64) as usize
    }

    /// Adds the next batch, paths `emitted()..emitted() + BATCH`: the photons its paths stored,
    /// in path order (and bounce order within a path), each with its path index, and what each
    /// path of the batch counted (`counts[j]` for path `emitted() + j`; only the kept paths'
    /// are summed).
    pub fn add_batch(&mut self, stored: impl IntoIterator<Item = (u64, Photon)>, counts: &[PathCounts]) {
        let start = self.emitted;
        let end = start + BATCH as u64;
        self.emitted = end;
        for (path, photon) in stored {
            debug_assert!((start..end).contains(&path), "path {path} is not in this batch");
            if self.steered_out(path) {
                // Steered past its bound: ended below, at the bound.
                break;
            }
            self.photons.push(photon);
            // The pilot's cells are surfaces': a volume photon (in a medium filling the scene)
            // counts as read wherever it lies.
            let volume = photon.flags & crate::photon_map::flags::VOLUME != 0;
            if volume || self.cells.is_none_or(|c| c.reads(photon.position, photon.normal)) {
                self.read += 1;
            }
            if self.full_at.is_none() && self.stored() == self.target {
                self.full_at = Some(path + 1);
            }
            if self.counted() == self.target {
                self.emitted = path + 1;
                break;
            }
        }
        if let (true, Some(full)) = (self.steered_out(self.emitted), self.full_at) {
            // The paths past the bound stored nothing: the map's paths end at it.
            self.emitted = self.emitted.min(STEERED_PATHS * full).max(start);
        }
        let kept = ((self.emitted - start) as usize).min(counts.len());
        for c in &counts[..kept] {
            self.rays += u64::from(c.rays);
            c.add_to(&mut self.numerics);
        }
    }

    /// The stored photons, each carrying its path's power over the paths emitted, with the
    /// paths emitted and what they counted.
    #[must_use]
    pub fn finish(mut self) -> TracedPhotons {
        normalise_power(&mut self.photons, self.emitted);
        TracedPhotons {
            photons: self.photons,
            read: self.read,
            emitted: self.emitted,
            rays: self.rays,
            numerics: self.numerics,
        }
    }
}

/// What a photon pass produced for one map.
#[derive(Debug)]
pub struct TracedPhotons {
    /// Stored photons, power already divided by `emitted`.
    pub photons: Vec<Photon>,
    /// How many of them lie where the camera reads the map (all without a guide).
    pub read: u64,
    /// Paths emitted.
    pub emitted: u64,
    /// Ray segments traced by those paths.
    pub rays: u64,
    /// Those paths' photon counters (the photon fields of [`Numerics`]).
    pub numerics: Numerics,
}

/// What one photon path counted, kept per path until the tally knows whether the path is kept.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PathCounts {
    /// Ray segments traced.
    pub rays: u16,
    /// Bounces whose power the photon power bound (`photon::POWER_GROWTH_MAX`) clamped.
    pub capped: u16,
    /// How the path ended, where that is counted.
    pub end: PathEnd,
}

/// How a photon path ended, for the counters of [`Numerics`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PathEnd {
    /// Absorbed, stored its last photon, or still going: nothing counted.
    #[default]
    Quiet,
    /// Its emission was not finite (`photon_emission`).
    EmissionNonFinite,
    /// Its power stopped being finite at a bounce (`photon_scatter`).
    ScatterNonFinite,
    /// A BSDF sample of zero pdf (`photon_zero_pdf`).
    ZeroPdf,
    /// It left a scene closed around its lights (`photon_escaped`).
    Escaped,
    /// Still going after `max_depth` bounces (`photon_depth_cut`).
    DepthCut,
}

impl PathCounts {
    /// One more ray segment.
    pub fn ray(&mut self) {
        self.rays = self.rays.saturating_add(1);
    }

    /// Adds this path's counts to `n`.
    pub fn add_to(&self, n: &mut Numerics) {
        n.photon_power_capped += u64::from(self.capped);
        match self.end {
            PathEnd::Quiet => {}
            PathEnd::EmissionNonFinite => n.photon_emission += 1,
            PathEnd::ScatterNonFinite => n.photon_scatter += 1,
            PathEnd::ZeroPdf => n.photon_zero_pdf += 1,
            PathEnd::Escaped => n.photon_escaped += 1,
            PathEnd::DepthCut => n.photon_depth_cut += 1,
        }
    }
}

/// Divides stored photons' power by the number of paths emitted: each then carries Φ/N.
pub fn normalise_power(photons: &mut [Photon], emitted: u64) {
    let scale = 1.0 / emitted as f32;
    for p in photons {
        p.power *= scale;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Emission stops at the path that stores the target's last photon: paths storing nothing
    /// are passed over, a path whose photons straddle the count is the one emission stops at,
    /// and a batch that falls short counts whole.
    #[test]
    fn emission_stops_at_the_path_that_stores_the_last_photon() {
        let p = Photon { position: Vec3::ZERO, power: Vec3::ONE, wi: Vec3::Z, normal: Vec3::Z, flags: 0 };
        // Paths 0..5 store 0, 2, 0, 3 and 1 photons.
        let batch: Vec<(u64, Photon)> = [1u64, 1, 3, 3, 3, 4].iter().map(|&path| (path, p)).collect();
        let cuts: Vec<u64> = (1..=6)
            .map(|need| {
                let mut t = Tally::new(need);
                t.add_batch(batch.iter().copied(), &[]);
                assert_eq!(t.stored(), u64::from(need));
                t.emitted()
            })
            .collect();
        assert_eq!(cuts, [2, 2, 4, 4, 4, 5]);
        let mut short = Tally::new(100_000);
        short.add_batch(batch.iter().copied(), &[]);
        assert_eq!((short.stored(), short.emitted(), short.wants_more()), (6, BATCH as u64, true));
        // A map of 10 photons may emit one batch at most (the path cap is at least a batch).
        let mut capped = Tally::new(10);
        capped.add_batch(batch.iter().copied(), &[]);
        assert!(!capped.wants_more());
        let traced = short.finish();
        assert_eq!((traced.photons[0].power, traced.emitted), (Vec3::splat(1.0 / BATCH as f32), BATCH as u64));
    }

    /// Only the kept paths' counts are summed: with 3 photons wanted the tally stops at path 3
    /// (paths 0..4 kept), so path 4's rays and its escape are not counted.
    #[test]
    fn only_kept_paths_are_counted() {
        let p = Photon { position: Vec3::ZERO, power: Vec3::ONE, wi: Vec3::Z, normal: Vec3::Z, flags: 0 };
        let batch: Vec<(u64, Photon)> = [1u64, 1, 3, 3, 3, 4].iter().map(|&path| (path, p)).collect();
        let mut counts = vec![PathCounts { rays: 2, ..Default::default() }; BATCH];
        counts[1].end = PathEnd::ScatterNonFinite;
        counts[2].capped = 3;
        counts[4].end = PathEnd::Escaped;
        let mut t = Tally::new(3);
        t.add_batch(batch.iter().copied(), &counts);
        let traced = t.finish();
        assert_eq!((traced.emitted, traced.rays), (4, 8));
        assert_eq!(
            (traced.numerics.photon_scatter, traced.numerics.photon_power_capped, traced.numerics.photon_escaped),
            (1, 3, 0)
        );
    }

    /// Steered by cells, the target counts only the photons stored where the camera reads (the
    /// marked cell; photons at x = 5 lie outside it). Paths 0..4 storing a read, an unread, a
    /// read and a read photon: 2 read stop emission at path 2, holding the unread one too.
    /// Paths 0..5 storing 2 unread, 1 read, 0, 2 (one read) and 1 read: the map held 2 photons
    /// after path 0, so emission ends at 2 · 1 paths, with 1 read (path 2 stored nothing, path
    /// 3's photons are not taken). Unsteered, the same cells only count: 2 stored photons stop
    /// at path 0.
    #[test]
    fn a_steered_target_counts_only_the_photons_read() {
        let at = |x: f32, path: u64| {
            (
                path,
                Photon { position: Vec3::new(x, 0.5, 0.5), power: Vec3::ONE, wi: Vec3::Y, normal: Vec3::Y, flags: 0 },
            )
        };
        let mut cells = ReadCells::new(Vec3::ZERO, 1.0);
        cells.mark(Vec3::splat(0.5), Vec3::Y);
        let tally = |batch: &[(u64, Photon)], steer: bool| {
            let mut t = Tally::reading(2, Some(&cells), steer);
            t.add_batch(batch.iter().copied(), &[]);
            (t.read(), t.stored(), t.emitted(), t.wants_more())
        };
        let reached = [at(0.5, 0), at(5.0, 1), at(0.5, 2), at(0.5, 3)];
        assert_eq!(tally(&reached, true), (2, 3, 3, false));
        let bounded = [at(5.0, 0), at(5.0, 0), at(0.5, 1), at(5.0, 3), at(0.5, 3), at(0.5, 4)];
        assert_eq!(tally(&bounded, true), (1, 3, 2, false));
        assert_eq!(tally(&bounded, false), (0, 2, 1, false));
    }
}
