//! `photonwave merge PART.exr… -o OUT.exr`: reads partial films, merges them exactly
//! (`photonwave::divided::merge`), and writes the EXR, PNG and JSON stats an undivided render writes.

use super::Say;
use photonwave::error::{Error, Result};
use photonwave::files::{check_outputs, Output};
use std::path::PathBuf;
use std::time::Instant;

/// Flags of `merge`.
#[derive(clap::Args)]
pub struct MergeArgs {
    /// Partial films written by `render --pass-set`, `--passes A..B`, `--partial` or
    /// `--checkpoint` (in any order).
    #[arg(required = true, value_name = "PART.exr")]
    pub parts: Vec<PathBuf>,
    /// Output EXR: the image an undivided render of the same passes writes, bit for bit.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write a tone-mapped PNG preview to this file.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Write the merged render's summary as JSON to this file.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Write the output as a partial film again (to merge it further, or to `--resume` it).
    #[arg(long)]
    pub partial: bool,
    /// Refuse to write an image that lacks passes below the largest one held (a worker that
    /// failed), instead of warning.
    #[arg(long)]
    pub complete: bool,
    /// Print errors only.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Runs `merge`.
pub fn run(args: &MergeArgs) -> Result<()> {
    let t = Instant::now();
    let say = Say { quiet: args.quiet, verbose: false };
    let mut outputs = vec![Output { flag: "--output", path: &args.output, ext: "exr" }];
    outputs.extend(args.png.as_deref().map(|path| Output { flag: "--png", path, ext: "png" }));
    outputs.extend(args.stats.as_deref().map(|path| Output { flag: "--stats", path, ext: "json" }));
    check_outputs(&outputs, &args.parts)?;
    let merged = photonwave::divided::merge::merge(args.parts.iter().map(|p| photonwave::divided::partial::read(p)))?;
    if let Some(missing) = &merged.missing {
        let text = format!(
            "passes {missing} are missing (below the largest, {}; `a..b` is a to b−1): the image is the mean of \
             the {} passes held",
            merged.sums.done.last().unwrap_or(0),
            merged.sums.passes()
        );
        if args.complete {
            return Err(Error::setting("--complete", text));
        }
        say.warn(text);
    }
    for w in &merged.warnings {
        say.warn(w);
    }
    if args.partial {
        let m = &merged;
        photonwave::divided::partial::write(&args.output, &m.identity, &m.sums, m.spp, &m.film, &m.stats)?;
    } else {
        merged.film.write_exr(&args.output)?;
    }
    say.info(format!(
        "merged {} passes from {} files in {:.2} s; wrote {}\n",
        merged.sums.passes(),
        args.parts.len(),
        t.elapsed().as_secs_f64(),
        args.output.display()
    ));
    if let Some(p) = &args.png {
        merged.film.write_png(p)?;
        say.info(format!("wrote {}\n", p.display()));
    }
    say.info(merged.stats.summary());
    if let Some(p) = &args.stats {
        let json = serde_json::to_string_pretty(&merged.stats).map_err(|e| Error::output(p, e))?;
        photonwave::files::write_bytes(p, json.as_bytes())?;
        say.info(format!("wrote {}\n", p.display()));
    }
    Ok(())
}
