//! `tincull stress`: the stability suite of [`eval::stress`] on one mesh: a table of cases and outcomes, or one
//! JSON object with `--json`.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use super::mesh_input::MeshArgs;
use super::{Output, OutputArgs};
use eval::stress::{StressOptions, run as run_suite};

/// Arguments of `tincull stress`.
#[derive(Debug, Args)]
pub struct StressArgs {
    /// The terrain mesh and how to import it.
    #[command(flatten)]
    pub mesh: MeshArgs,
    /// Viewpoints per class (six classes) for each case, and per kind for the degenerate viewpoints.
    #[arg(long, default_value_t = 10)]
    pub viewpoints: usize,
    /// Smaller synthetic terrains, 5 crystal seeds instead of 20, a smaller Crater Lake.
    #[arg(long)]
    pub quick: bool,
    /// Directory holding `crater_lake.npy` (the flat-lake case is skipped with a notice when it is missing).
    #[arg(long, value_name = "DIR", default_value = "../shared/dem")]
    pub dem_dir: PathBuf,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Runs `tincull stress`.
pub fn run(args: &StressArgs, out: Output) -> Result<()> {
    let (tin, _) = args.mesh.load(out)?;
    if !args.dem_dir.join("crater_lake.npy").exists() {
        out.warn(format!(
            "{} not found: the Crater Lake case is skipped",
            args.dem_dir.join("crater_lake.npy").display()
        ));
    }
    let opts = StressOptions {
        viewpoints: args.viewpoints,
        quick: args.quick,
        dem_dir: Some(args.dem_dir.clone()),
    };
    let spinner = out.spinner("stress");
    let report = run_suite(&tin, &args.mesh.mesh.display().to_string(), &opts, &|name| {
        spinner.set_message(format!("case: {name}"));
    })?;
    spinner.finish_and_clear();
    out.say(report.table());
    out.say(format!("{:.1} s in all", report.seconds));
    out.json(&serde_json::to_value(&report)?)
}
