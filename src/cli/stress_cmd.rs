//! `tincull stress`: the stability suite of [`eval::stress`] on one mesh: a table of cases and outcomes, or one
//! JSON object with `--json`.

use std::path::PathBuf;

use anyhow::{Context, Result};
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
    /// Viewpoints per class (six classes) for each case, and per kind for the degenerate viewpoints, 1 to 1000000.
    #[arg(long, default_value_t = 10)]
    pub viewpoints: usize,
    /// Smaller synthetic terrains, 5 crystal seeds instead of 20, a smaller Crater Lake.
    #[arg(long)]
    pub quick: bool,
    /// Directory holding `crater_lake.npy`, for the flat-lake case (run only when given; an error when the file
    /// is missing).
    #[arg(long, value_name = "DIR")]
    pub dem_dir: Option<PathBuf>,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Runs `tincull stress`.
pub fn run(args: &StressArgs, out: Output) -> Result<()> {
    super::eval_cmd::check_viewpoints(args.viewpoints)?;
    out.require_a_result(false, "give --json")?;
    let (tin, _) = args.mesh.load(out)?;
    if let Some(dir) = &args.dem_dir
        && !dir.is_dir()
    {
        let what = if dir.exists() { "not a folder" } else { "no such folder" };
        anyhow::bail!("{}: {what} (--dem-dir names the folder of the DEMs)", dir.display());
    }
    if let Some(dir) = &args.dem_dir
        && !dir.join("crater_lake.npy").exists()
    {
        anyhow::bail!(
            "{}: not found (given by --dem-dir)",
            dir.join("crater_lake.npy").display()
        );
    }
    let opts = StressOptions {
        viewpoints: args.viewpoints,
        quick: args.quick,
        dem_dir: args.dem_dir.clone(),
    };
    let spinner = out.spinner("stress");
    // The case under way, for an error: the suite moves and scales the mesh, which may break a mesh that builds.
    let case = std::cell::RefCell::new(String::new());
    let report = run_suite(&tin, &args.mesh.mesh.display().to_string(), &opts, &|name| {
        spinner.set_message(format!("case: {name}"));
        *case.borrow_mut() = name.to_string();
    })
    .with_context(|| format!("{}: stress case `{}`", args.mesh.mesh.display(), case.borrow()))?;
    spinner.finish_and_clear();
    out.say(report.table());
    out.say(format!("{:.1} s in all", report.seconds));
    out.json(&serde_json::to_value(&report)?)
}
