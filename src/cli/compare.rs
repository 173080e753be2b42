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
    /// Block side in pixels for the block-mean errors (the image is cut into a whole number of
    /// blocks of about this size).
    #[arg(long, default_value_t = photonwave::tools::compare::BLOCK, value_parser = clap::value_parser!(u32).range(1..))]
    pub block: u32,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Runs `compare`.
pub fn run(args: &CompareArgs) -> Result<()> {
    let c = photonwave::tools::compare::compare_files_in_blocks(&args.image, &args.reference, args.block)?;
    if args.json {
        println!("{}", serde_json::to_string(&c).map_err(|e| Error::output(std::path::Path::new("stdout"), e))?);
    } else {
        print!("{}", c.table());
    }
    Ok(())
}
