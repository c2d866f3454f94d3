//! `tincull export`: a `.tch` hierarchy as JSON, as a grouped OBJ, or as glTF 2.0 (`.glb`, or `.gltf` + `.bin`).

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use cull::Hierarchy;

use super::Output;
use pipeline::export::{write_grouped_obj, write_json};
use pipeline::gltf::write_gltf;

/// Arguments of `tincull export`.
#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("format").required(true).multiple(true).args(["json", "obj", "gltf"])))]
pub struct ExportArgs {
    /// The hierarchy file written by `tincull build`.
    pub hierarchy: PathBuf,
    /// Write the hierarchy's JSON form here.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Write the mesh as OBJ with one group per leaf and the orphans (and a .mtl beside it).
    #[arg(long, value_name = "FILE")]
    pub obj: Option<PathBuf>,
    /// Write the mesh as glTF 2.0: one primitive per leaf group and one for the always-visible set, nodes mirroring
    /// the hierarchy, regions and ranges in `extras.tincull`; `.glb` for binary, else `.gltf` with a `.bin` beside it.
    #[arg(long, value_name = "FILE")]
    pub gltf: Option<PathBuf>,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Runs `tincull export`.
pub fn run(args: &ExportArgs, out: Output) -> Result<()> {
    let h = Hierarchy::load(&args.hierarchy)?;
    if let Some(path) = &args.json {
        write_json(&h, path)?;
        out.say(format!("wrote {}", path.display()));
    }
    if let Some(path) = &args.obj {
        write_grouped_obj(&h, path)?;
        out.say(format!("wrote {} and its .mtl", path.display()));
    }
    if let Some(path) = &args.gltf {
        let written = write_gltf(&h, path)?;
        let names: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
        out.say(format!("wrote {}", names.join(" and ")));
    }
    Ok(())
}
