//! `photonwave compare IMAGE REFERENCE`: the error of an image against a reference, per layer.

use photonwave::error::{Error, Result};
use std::path::PathBuf;

/// Flags of `compare`.
#[derive(clap::Args)]
pub struct CompareArgs {
    /// The image to measure (.exr).
    pub image: PathBuf,
    /// The reference image (.exr), e.g. a long progressive render.
    pub reference: PathBuf,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Runs `compare`.
pub fn run(args: &CompareArgs) -> Result<()> {
    let c = photonwave::tools::compare::compare_files(&args.image, &args.reference)?;
    if args.json {
        println!("{}", serde_json::to_string(&c).map_err(|e| Error::output(std::path::Path::new("stdout"), e))?);
    } else {
        print!("{}", c.table());
    }
    Ok(())
}
