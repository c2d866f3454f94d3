//! Command-line interface: argument definitions and dispatch. Each subcommand lives in its own module.

mod horizon_cmd;
mod info;
mod mesh_input;
pub mod output;
mod synth;
mod tin_cmd;

use anyhow::Result;
use clap::{Parser, Subcommand};

pub use output::Output;

/// tincull: precomputed terrain self-occlusion culling for irregular triangulated terrains (TINs).
#[derive(Debug, Parser)]
#[command(name = "tincull", version, about, long_about = None)]
pub struct Cli {
    /// Print one JSON object on stdout instead of text.
    #[arg(long, global = true)]
    pub json: bool,
    /// No progress bars or human-readable text (errors are still printed).
    #[arg(long, short, global = true)]
    pub quiet: bool,
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Describe a terrain mesh: counts, bounding box, relief, height-field check, triangle quality.
    Info(info::InfoArgs),
    /// Turn a DEM grid (.npy, .asc, .hgt, .png) into a simplified TIN by greedy insertion, written as OBJ.
    Tin(tin_cmd::TinArgs),
    /// Write a seeded synthetic terrain (ridged fractal with valleys) as OBJ.
    Synth(synth::SynthArgs),
    /// Compute the horizon of every vertex in every subsector (the covering-set sweep).
    Horizon(horizon_cmd::HorizonArgs),
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    let out = Output {
        json: cli.json,
        quiet: cli.quiet,
    };
    match cli.command {
        Command::Info(args) => info::run(&args, out),
        Command::Tin(args) => tin_cmd::run(&args, out),
        Command::Synth(args) => synth::run(&args, out),
        Command::Horizon(args) => horizon_cmd::run(&args, out),
    }
}
