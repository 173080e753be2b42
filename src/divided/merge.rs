//! `merge`: reads partial films ([`crate::divided::partial`]) and writes the film and stats of all their
//! passes together. The sums are integers, so the result does not depend on the order of the
//! files or on how the passes were split: the merge of any split of passes 0..N is the film of
//! an undivided `render --passes N`, bit for bit. Files that are not parts of one render, or
//! that hold a pass twice, are refused by name.

use crate::divided::partial::Partial;
use crate::divided::pass_set::PassList;
use crate::divided::pass_sums::PassSums;
use crate::error::{Error, Result};
use crate::film::Film;
use crate::stats::RenderStats;

/// The merged render.
pub struct Merged {
    /// The passes' mean with its noise, bias and (when the render asked for them) diagnostic
    /// layers: what `render` writes.
    pub film: Film,
    /// The passes' stats together.
    pub stats: RenderStats,
    /// The merged sums (for writing a partial film of them).
    pub sums: PassSums,
    /// Passes below the largest that no file holds, as compact text.
    pub missing: Option<String>,
    /// Which render the parts belong to.
    pub identity: crate::divided::partial::Identity,
    /// Samples per pixel in each pass.
    pub spp: u32,
    /// What went into the film that its user should know (a missing diagnostic layer).
    pub warnings: Vec<String>,
}

/// What the merge keeps of a partial film once its sums are added: its passes and stats.
struct Part {
    path: std::path::PathBuf,
    done: PassList,
    stats: RenderStats,
    spp: u32,
}

/// Merges the partial films `parts` yields (at least one), checking that they are parts of one
/// render and hold disjoint passes. Each film's sums are added as it is read and then dropped,
/// so memory holds two films' sums at most, however many files there are.
pub fn merge(parts: impl IntoIterator<Item = Result<Partial>>) -> Result<Merged> {
    let mut parts = parts.into_iter();
    let first = parts.next().ok_or_else(|| Error::setting("PART", "give at least one partial film to merge"))??;
    let Partial { path: first_path, identity, sums: first_sums, spp, stats, diagnostics } = first;
    let alpha = first_sums.alpha();
    let PassSums { mut sums, done, .. } = first_sums;
    // The diagnostic layers of the film holding the last pass, as in an undivided render.
    let mut last: (Option<u32>, Option<crate::film::EstimateLayers>, usize) = (done.last(), diagnostics, 0);
    let mut kept = vec![Part { path: first_path.clone(), done, stats, spp }];
    for p in parts {
        let p = p?;
        let (a, b) = (first_path.display().to_string(), p.path.display().to_string());
        if let Some(why) = identity.difference(&a, &p.identity, &b) {
            return Err(Error::parse(&p.path, 0, format!("cannot be merged: {why}")));
        }
        if (sums.width, sums.height) != (p.sums.sums.width, p.sums.sums.height) || p.spp != spp {
            return Err(Error::parse(
                &p.path,
                0,
                format!("cannot be merged: its image size or samples per pass differ from {a}'s"),
            ));
        }
        sums.add(&p.sums.sums);
        if p.sums.done.last() > last.0 {
            last = (p.sums.done.last(), p.diagnostics, kept.len());
        }
        kept.push(Part { path: p.path, done: p.sums.done, stats: p.stats, spp: p.spp });
    }
    // Every pass once: sort (pass, file) pairs and look for neighbours with the same pass.
    let mut owners: Vec<(u32, usize)> =
        kept.iter().enumerate().flat_map(|(f, p)| p.done.indices().iter().map(move |&i| (i, f))).collect();
    owners.sort_unstable();
    if let Some(w) = owners.windows(2).find(|w| w[0].0 == w[1].0) {
        let (a, b) = (&kept[w[0].1], &kept[w[1].1]);
        return Err(Error::parse(
            &b.path,
            0,
            format!(
                "cannot be merged: it and {} both hold passes {} (a file given twice, or two workers with \
                 overlapping pass sets)",
                a.path.display(),
                a.done.overlap(&b.done).to_text()
            ),
        ));
    }
    if owners.is_empty() {
        let names: Vec<String> = kept.iter().map(|p| p.path.display().to_string()).collect();
        let verb = if kept.len() == 1 { "holds" } else { "hold" };
        return Err(Error::parse(
            &first_path,
            0,
            format!("{} {verb} no passes (stopped before the first ended): nothing to merge", names.join(", ")),
        ));
    }
    let done = PassList::new(owners.iter().map(|o| o.0).collect()).unwrap_or_default();
    let sums = PassSums::from_sums(sums, done, alpha);
    let mut film = sums.image();
    let mut warnings = Vec::new();
    if identity.image.get("diagnostics").and_then(serde_json::Value::as_bool) == Some(true) {
        film.diagnostics = last.1;
        if film.diagnostics.is_none() {
            warnings.push(format!(
                "no diagnostic layers: {}, which holds the last pass, has none (it was stopped or checkpointed before \
                 it finished)",
                kept[last.2].path.display()
            ));
        }
    }
    let stats = merged_stats(&kept, last.2, &sums, &film);
    let (count, text) = sums.done.gaps();
    let missing = (count > 0).then_some(text);
    Ok(Merged { film, stats, sums, missing, identity, spp, warnings })
}

/// The stats of the merged render: counts and phase times summed over the files, the rest
/// from `kept[last]`, the file holding the last pass.
fn merged_stats(kept: &[Part], last: usize, sums: &PassSums, film: &Film) -> RenderStats {
    let l = &kept[last];
    let mut stats = RenderStats { progressive: None, parallel: None, ..l.stats.clone() };
    let mut progressive = l.stats.progressive.clone().unwrap_or_default();
    let (mut pass_seconds, mut elapsed) = (Vec::new(), 0.0f64);
    for (k, p) in kept.iter().enumerate() {
        if k != last {
            stats.add_totals(&p.stats);
            stats.times.total_s += p.stats.times.total_s;
        }
        if let Some(pp) = &p.stats.progressive {
            pass_seconds.extend_from_slice(&pp.pass_seconds);
            elapsed = elapsed.max(pp.elapsed_s);
        }
    }
    progressive.passes = sums.passes();
    progressive.pass_seconds = pass_seconds;
    progressive.elapsed_s = elapsed;
    progressive.budget_s = None;
    progressive.error_95 = sums.error_95(std::thread::available_parallelism().map_or(1, |n| n.get()));
    stats.spp = l.spp.saturating_mul(sums.passes());
    stats.phases = vec![format!("{} progressive passes merged from {} partial films", sums.passes(), kept.len())];
    stats.mean_rgb = film.mean().to_array();
    stats.progressive = Some(progressive);
    stats
}
