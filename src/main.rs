//! The photonwave command line: `photonwave render SCENE [flags]`, `merge`, `bench`, `compare`
//! and `sweep`, one module each under `cli/`.

mod cli;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "photonwave", version, about = "A photon-mapping renderer (Jensen 1996)")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene (.toml scene file or bare .obj) to a multi-layer EXR.
    Render(Box<cli::render::RenderArgs>),
    /// Merge partial films (from `render --pass-set K/N`, `--passes A..B`, checkpoints) into the
    /// image of all their passes: bit for bit what an undivided render of them writes.
    Merge(cli::merge::MergeArgs),
    /// Throughput of the SIMD kernels against their baselines on identical rays and queries:
    /// packet vs obvhs single-ray traversal, SIMD vs scalar density estimates.
    Bench(cli::bench::BenchArgs),
    /// Error of an image against a reference (both EXRs written by `render`): RMSE, relMSE
    /// ((a−b)²/(b²+0.01)) and mean ratio for the beauty image and each term layer in both.
    Compare(cli::compare::CompareArgs),
    /// What accuracy costs in time: render a scene over a grid of settings, time each render and
    /// measure its error against a reference; writes DIR/sweep.csv and a log-log
    /// error-against-time plot per knob (DIR/KNOB.svg and .png).
    Sweep(Box<cli::sweep::SweepArgs>),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => cli::render::run(*args),
        Command::Merge(args) => cli::merge::run(&args),
        Command::Bench(args) => cli::bench::run(args),
        Command::Compare(args) => cli::compare::run(&args),
        Command::Sweep(args) => cli::sweep::run(*args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
