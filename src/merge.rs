//! `merge`: reads partial films ([`crate::partial`]) and writes the film and stats of all their
//! passes together. The sums are integers, so the result does not depend on the order of the
//! files or on how the passes were split: the merge of any split of passes 0..N is the film of
//! an undivided `render --passes N`, bit for bit. Files that are not parts of one render, or
//! that hold a pass twice, are refused by name.

use crate::error::{Error, Result};
use crate::film::Film;
use crate::partial::Partial;
use crate::pass_set::PassList;
use crate::pass_sums::PassSums;
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
    /// Passes below the largest that no file holds.
    pub missing: PassList,
    /// What went into the film that its user should know (a missing diagnostic layer).
    pub warnings: Vec<String>,
}

/// Merges `parts` (at least one), checking that they are parts of one render and hold
/// disjoint passes.
pub fn merge(parts: &[Partial]) -> Result<Merged> {
    let first = parts.first().ok_or_else(|| Error::setting("PART", "give at least one partial film to merge"))?;
    for p in &parts[1..] {
        if let Some(why) = first.identity.difference(&first.path, &p.identity, &p.path) {
            return Err(Error::parse(&p.path, 0, format!("cannot be merged: {why}")));
        }
        let (a, b) = (&first.sums.sums, &p.sums.sums);
        if (a.width, a.height) != (b.width, b.height) || first.spp != p.spp {
            return Err(Error::parse(
                &p.path,
                0,
                format!("cannot be merged: it and {} differ in image size or samples per pass", first.path.display()),
            ));
        }
    }
    // Every pass once: sort (pass, file) pairs and look for neighbours with the same pass.
    let mut owners: Vec<(u32, usize)> =
        parts.iter().enumerate().flat_map(|(f, p)| p.sums.done.indices().iter().map(move |&i| (i, f))).collect();
    owners.sort_unstable();
    if let Some(w) = owners.windows(2).find(|w| w[0].0 == w[1].0) {
        let (a, b) = (&parts[w[0].1].path, &parts[w[1].1].path);
        let both = parts[w[0].1].sums.done.overlap(&parts[w[1].1].sums.done);
        return Err(Error::parse(
            b,
            0,
            format!(
                "cannot be merged: it and {} both hold passes {} (a file given twice, or two workers with \
                 overlapping pass sets)",
                a.display(),
                both.to_text()
            ),
        ));
    }
    if owners.is_empty() {
        let names: Vec<String> = parts.iter().map(|p| p.path.display().to_string()).collect();
        return Err(Error::parse(
            &first.path,
            0,
            format!("{} hold no passes (stopped before the first ended): nothing to merge", names.join(", ")),
        ));
    }
    let done = PassList::new(owners.iter().map(|o| o.0).collect()).unwrap_or_default();
    let mut sums = first.sums.sums.clone();
    for p in &parts[1..] {
        sums.add(&p.sums.sums);
    }
    let sums = PassSums::from_sums(sums, done, first.sums.alpha());
    let missing = sums.done.gaps();
    let mut film = sums.image();
    // The diagnostic layers are those of the last pass, as in an undivided render.
    let last = parts.iter().max_by_key(|p| p.sums.done.last()).unwrap_or(first);
    let mut warnings = Vec::new();
    let wanted = first.identity.image.get("diagnostics").and_then(serde_json::Value::as_bool) == Some(true);
    if wanted {
        film.diagnostics.clone_from(&last.diagnostics);
        if last.diagnostics.is_none() {
            warnings.push(format!(
                "no diagnostic layers: {}, which holds the last pass, has none (it was interrupted or checkpointed \
                 before it finished)",
                last.path.display()
            ));
        }
    }
    let stats = merged_stats(parts, last, &sums, &film);
    Ok(Merged { film, stats, sums, missing, warnings })
}

/// The stats of the merged render: counts and phase times summed over the files, the rest
/// from the file holding the last pass.
fn merged_stats(parts: &[Partial], last: &Partial, sums: &PassSums, film: &Film) -> RenderStats {
    let mut stats = RenderStats { progressive: None, ..last.stats.clone() };
    let mut progressive = last.stats.progressive.clone().unwrap_or_default();
    let (mut pass_seconds, mut elapsed) = (Vec::new(), 0.0f64);
    for p in parts.iter().filter(|p| !std::ptr::eq(*p, last)) {
        stats.add_totals(&p.stats);
        stats.times.total_s += p.stats.times.total_s;
    }
    for p in parts {
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
    stats.spp = last.spp.saturating_mul(sums.passes());
    stats.phases = vec![format!("{} progressive passes merged from {} partial films", sums.passes(), parts.len())];
    stats.mean_rgb = film.mean().to_array();
    stats.progressive = Some(progressive);
    stats
}
