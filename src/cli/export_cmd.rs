//! `tincull export`: a `.tch` hierarchy as JSON or as a grouped OBJ.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use cull::Hierarchy;

use super::{Output, OutputArgs};
use pipeline::export::to_json;

use super::files::Outputs;

/// Arguments of `tincull export`.
#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("format").required(true).multiple(true).args(["export_json", "export_obj"])))]
pub struct ExportArgs {
    /// The hierarchy file written by `tincull build`.
    pub hierarchy: PathBuf,
    /// Write the hierarchy's JSON form here (`-` for standard output).
    #[arg(long, value_name = "FILE")]
    pub export_json: Option<PathBuf>,
    /// Write the mesh as OBJ with one group per leaf and the orphans (and a .mtl beside it).
    #[arg(long, value_name = "FILE")]
    pub export_obj: Option<PathBuf>,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Runs `tincull export`.
pub fn run(args: &ExportArgs, out: Output) -> Result<()> {
    let mut out = out;
    let mut files = Outputs::new();
    if let Some(path) = &args.export_json {
        files.check_or_stdout(path, &mut out)?;
    }
    if let Some(path) = &args.export_obj {
        files.check_grouped_obj(path)?;
    }
    let h = Hierarchy::load(&args.hierarchy)?;
    if let Some(path) = &args.export_json {
        files.add_bytes(path, to_json(&h)?.as_bytes())?;
    }
    if let Some(path) = &args.export_obj {
        files.add_grouped_obj(&h, path)?;
    }
    files.commit()?;
    if let Some(path) = &args.export_json {
        out.say(format!("wrote {}", path.display()));
    }
    if let Some(path) = &args.export_obj {
        out.say(format!("wrote {} and its .mtl", path.display()));
    }
    out.json(&serde_json::json!({
        "hierarchy": args.hierarchy,
        "json": args.export_json,
        "obj": args.export_obj,
    }))
}
