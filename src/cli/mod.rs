//! Command-line interface: argument definitions and dispatch. Each subcommand lives in its own module.

mod build_cmd;
pub mod cull_cmd;
pub mod culling_args;
mod demo_cmd;
mod eval_cmd;
mod export_cmd;
mod failmap_cmd;
mod files;
mod horizon_cmd;

mod info;
mod mesh_input;
pub mod output;
pub mod pvs_cmd;
#[cfg(feature = "viewer")]
mod render_cmd;
mod stress_cmd;
mod sweep_cmd;
mod synth;
mod tiles_cmd;
mod tin_cmd;
pub mod values;
#[cfg(feature = "viewer")]
mod view_cmd;

use anyhow::Result;
use clap::{Parser, Subcommand};

pub use output::{Output, OutputArgs};

/// tincull: precomputed terrain self-occlusion culling for irregular triangulated terrains (TINs).
#[derive(Debug, Parser)]
#[command(name = "tincull", version, about, long_about = None)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
    /// Worker threads of the parallel stages (horizons, ground truth, tiles) [default: the `RAYON_NUM_THREADS`
    /// environment variable, else one per core]. Outputs are the same at any count. Accepted before or after the
    /// command (once).
    #[arg(long, global = true, value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    pub threads: Option<u16>,
}

impl Cli {
    /// Parses the process's arguments, exiting with clap's message on an error. A negative number is taken as the
    /// value of the option before it everywhere (`--max-error -1` is then refused by the option's own check, not
    /// taken for an unknown flag with the misleading tip to write `-- -1`).
    pub fn parse_args() -> Cli {
        use clap::{CommandFactory, FromArgMatches};
        fn negative_numbers(c: clap::Command) -> clap::Command {
            c.allow_negative_numbers(true).mut_subcommands(negative_numbers)
        }
        let matches = negative_numbers(Cli::command()).get_matches();
        // clap refuses `--threads` twice on one side of the command, but lets one after it silently override one
        // before it.
        let args: Vec<std::ffi::OsString> = std::env::args_os().skip(1).collect();
        if threads_flags(&args) > 1 {
            Cli::command()
                .error(
                    clap::error::ErrorKind::ArgumentConflict,
                    "--threads is given twice (before and after the command): give it once",
                )
                .exit();
        }
        Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit())
    }
}

/// The worker threads `RAYON_NUM_THREADS` asks for (0: one per core), or `None` when it is unset or empty. rayon
/// silently ignores a value it cannot read (spaces around a number included): such a value is refused here, as a bad
/// `--threads` is, and a readable one is applied by [`run`] rather than left to rayon.
fn env_threads() -> Result<Option<usize>> {
    let Some(value) = std::env::var_os("RAYON_NUM_THREADS") else {
        return Ok(None);
    };
    let text = value.to_string_lossy();
    let number = text.trim();
    if number.is_empty() {
        return Ok(None);
    }
    match number.parse::<u64>() {
        Ok(n) if n <= u64::from(u16::MAX) => Ok(Some(n as usize)),
        Ok(_) => anyhow::bail!(
            "RAYON_NUM_THREADS={text}: at most {} worker threads (as --threads; 0 for one per core)",
            u16::MAX
        ),
        Err(_) => anyhow::bail!(
            "RAYON_NUM_THREADS={text}: not a number of worker threads (a whole number, 0 for one per core; or leave \
             the variable unset)"
        ),
    }
}

/// How many times `--threads` is given in `args` (as `--threads N` or `--threads=N`), up to a `--`.
fn threads_flags(args: &[std::ffi::OsString]) -> usize {
    args.iter()
        .map(|a| a.to_string_lossy())
        .take_while(|a| a != "--")
        .filter(|a| a == "--threads" || a.starts_with("--threads="))
        .count()
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// The main job: build and evaluate the bundled default terrain, print a report and write out/.
    Demo(demo_cmd::DemoArgs),
    /// Describe a terrain mesh (counts, bounding box, relief, height-field check, triangle quality), a hierarchy
    /// (.tch: its mesh and the height-field check of it, nodes, visibility data and build parameters) or a PVS file
    /// (.pvs: its parameters and every viewcell's PVS).
    Info(info::InfoArgs),
    /// Turn a DEM grid (.npy, .asc, .hgt, .png, .tif) into a simplified TIN by greedy insertion, written as OBJ.
    Tin(tin_cmd::TinArgs),
    /// Write a seeded synthetic terrain (ridged fractal with valleys) as OBJ, or as a height grid (.npy).
    Synth(synth::SynthArgs),
    /// Compute the horizon of every vertex in every subsector (the covering-set sweep), optionally verified.
    Horizon(horizon_cmd::HorizonArgs),
    /// Build the occlusion hierarchy of a terrain: horizons, regions, crystal groups, merge hierarchy (.tch).
    Build(build_cmd::BuildArgs),
    /// Run the culler of a hierarchy for one or many viewpoints: triangles and ranges drawn, counts, timing (the
    /// median of 15 culls after a warm-up, each viewpoint); the ranges themselves with --json.
    Cull(cull_cmd::CullArgs),
    /// Evaluate every culling method against ground truth from seeded viewpoints: false culls, occlusion captured.
    ///
    /// Methods: `safe` and `lloyd-egbert` (which never cull a visible triangle), the regions test of the hierarchy
    /// (`thesis`, or `stewart` for a quadtree, and `per_triangle`, the same test triangle by triangle: neither is
    /// conservative), the conservative regions (`safe_regions`), and `frustum_only` and `none` as references.
    ///
    /// Per method and viewpoint class: false culls (visible triangles culled: mean, max, viewpoints with any),
    /// occlusion captured (hidden triangles culled / hidden triangles), leaf limit (what culling exactly the leaves
    /// with no visible triangle would capture: the most a culler of whole leaves can), the visible and drawn
    /// fractions of the mesh, overdraw and the median cull time.
    Eval(eval_cmd::EvalArgs),
    /// Export a hierarchy as JSON, as an OBJ with one group per leaf, or as glTF 2.0.
    Export(export_cmd::ExportArgs),
    /// Build and evaluate every combination of sectors, subsectors and seeds: one CSV line per combination, method
    /// and class (resumable).
    Sweep(sweep_cmd::SweepArgs),
    /// Stability suite: the pipeline over degenerate cases (sectors, slivers, flat, offsets, odd viewpoints, seeds).
    Stress(stress_cmd::StressArgs),
    /// Failure map: a raster of viewpoints over the footprint, false culls and occlusion captured per cell (PNG, CSV).
    Failmap(failmap_cmd::FailmapArgs),
    /// From-region visibility: the potentially visible set (PVS) of a viewcell or of a grid of cells (Koltun et al.
    /// 2001 over the TIN's walls, and the conservative regions), or a check of random cells against ground truth.
    Pvs(pvs_cmd::PvsArgs),
    /// Tiled builds of terrains too large for one build: plan a DEM's tiles, build each (here or on a cluster),
    /// merge them into one hierarchy.
    Tiles(tiles_cmd::TilesArgs),
    /// Render a hierarchy or mesh to PNG without a window: map, orbit overview with culling, or eye view.
    #[cfg(feature = "viewer")]
    Render(render_cmd::RenderArgs),
    /// Open the interactive viewer: fly/orbit camera, live culling, ground truth, rebuild and export.
    #[cfg(feature = "viewer")]
    View(view_cmd::ViewArgs),
    /// Render to PNG (not in this build: it was built without the `viewer` feature).
    #[cfg(not(feature = "viewer"))]
    Render(NoViewerArgs),
    /// The interactive viewer (not in this build: it was built without the `viewer` feature).
    #[cfg(not(feature = "viewer"))]
    View(NoViewerArgs),
}

/// Arguments of `render` and `view` in a build without the viewer: anything, refused with a clear error.
#[cfg(not(feature = "viewer"))]
#[derive(Debug, clap::Args)]
pub struct NoViewerArgs {
    /// Ignored.
    #[arg(trailing_var_arg = true, allow_hyphen_values = true, hide = true)]
    pub args: Vec<String>,
}

/// The error of a command that needs the viewer in a build without it.
#[cfg_attr(feature = "viewer", allow(dead_code))]
pub(crate) fn no_viewer(what: &str) -> anyhow::Error {
    anyhow::anyhow!(
        "{what}: this build of tincull lacks the viewer (it was built without the `viewer` feature); \
         rebuild with `cargo build --release --features viewer` (it is on by default)"
    )
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    // One command, then the process ends: a pipe given as an input may be looked at before it is read.
    infile::keep_pipes();
    let threads = match cli.threads {
        Some(n) => Some((usize::from(n), "--threads".to_string())),
        None => env_threads()?.map(|n| (n, format!("RAYON_NUM_THREADS={n}"))),
    };
    if let Some((n, given)) = threads.filter(|&(n, _)| n > 0) {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|e| anyhow::anyhow!("{given}: {e}"))?;
    }
    match cli.command {
        Command::Demo(args) => demo_cmd::run(&args, args.output.into()),
        Command::Info(args) => info::run(&args, args.output.into()),
        Command::Tin(args) => tin_cmd::run(&args, args.output.into()),
        Command::Synth(args) => synth::run(&args, args.output.into()),

        Command::Horizon(args) => horizon_cmd::run(&args, args.output.into()),
        Command::Build(args) => build_cmd::run(&args, args.output.into()),
        Command::Cull(args) => cull_cmd::run(&args, args.output.into()),
        Command::Eval(args) => eval_cmd::run(&args, args.output.into()),
        Command::Sweep(args) => sweep_cmd::run(&args, args.output.into()),
        Command::Export(args) => export_cmd::run(&args, args.output.into()),
        Command::Stress(args) => stress_cmd::run(&args, args.output.into()),
        Command::Failmap(args) => failmap_cmd::run(&args),
        Command::Pvs(args) => pvs_cmd::run(&args, args.output.into()),
        Command::Tiles(args) => tiles_cmd::run(&args),
        #[cfg(feature = "viewer")]
        Command::Render(args) => render_cmd::run(&args, args.output.into()),
        #[cfg(feature = "viewer")]
        Command::View(args) => view_cmd::run(
            &args,
            Output {
                json: false,
                quiet: args.quiet,
                quiet_text: false,
            },
        ),
        #[cfg(not(feature = "viewer"))]
        Command::Render(_) => Err(no_viewer("`tincull render`")),
        #[cfg(not(feature = "viewer"))]
        Command::View(_) => Err(no_viewer("`tincull view`")),
    }
}
