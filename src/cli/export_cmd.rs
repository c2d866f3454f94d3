//! `tincull export`: a `.tch` hierarchy as JSON, as a grouped OBJ, or as glTF 2.0 (`.glb`, or `.gltf` + `.bin`).

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use super::{Output, OutputArgs};
use pipeline::export::to_json;

use super::files::{Outputs, refuse_other_format};

/// Arguments of `tincull export`.
#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("format").required(true).multiple(true).args(["export_json", "export_obj", "export_gltf"])))]
pub struct ExportArgs {
    /// The hierarchy file written by `tincull build`.
    pub hierarchy: PathBuf,
    /// Write the hierarchy's JSON form here (`-` for standard output).
    #[arg(long, value_name = "FILE")]
    pub export_json: Option<PathBuf>,
    /// Write the mesh as OBJ with one group per leaf and the orphans (and a .mtl beside it). Groups are numbered
    /// in triangle order (`group_0` holds the first leaf's range), not by node id as the JSON and `.pvs` nodes are.
    #[arg(long, value_name = "FILE")]
    pub export_obj: Option<PathBuf>,
    /// Write the mesh as glTF 2.0: one primitive per leaf group and one for the always-visible set, nodes mirroring
    /// the hierarchy, regions and ranges in `extras.tincull`; `.glb` for binary, else `.gltf` with a `.bin` beside it.
    #[arg(long, visible_alias = "gltf", value_name = "FILE")]
    pub export_gltf: Option<PathBuf>,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Runs `tincull export`.
pub fn run(args: &ExportArgs, out: Output) -> Result<()> {
    let mut out = out;
    let mut files = Outputs::new();
    files.input(&args.hierarchy)?;
    if let Some(path) = &args.export_json {
        files.check_or_stdout(path, "--export-json", &mut out)?;
        refuse_other_format(path, "a hierarchy's JSON", "json")?;
    }
    if let Some(path) = &args.export_obj {
        files.check_grouped_obj(path, "--export-obj")?;
    }
    if let Some(path) = &args.export_gltf {
        files.check_gltf(path, "--export-gltf")?;
    }
    let h = super::mesh_input::load_hierarchy(&args.hierarchy)?;
    if let Some(path) = &args.export_json {
        files.add_bytes(path, to_json(&h)?.as_bytes())?;
    }
    if let Some(path) = &args.export_obj {
        files.add_grouped_obj(&h, path)?;
    }
    let mut gltf_written = Vec::new();
    if let Some(path) = &args.export_gltf {
        gltf_written = files.add_gltf(&h, path)?;
    }
    files.commit()?;
    // In the order of the flags' help: JSON, OBJ, glTF.
    if let Some(path) = &args.export_json {
        out.say(format!("wrote {}", path.display()));
    }
    if let Some(path) = &args.export_obj {
        out.say(format!("wrote {} and its .mtl", path.display()));
    }
    if !gltf_written.is_empty() {
        let names: Vec<String> = gltf_written.iter().map(|p| p.display().to_string()).collect();
        out.say(format!("wrote {}", names.join(" and ")));
    }
    // Every format is `null` when not asked for; the OBJ's `.mtl` and the glTF's `.bin` are named beside it.
    out.json(&serde_json::json!({
        "hierarchy": args.hierarchy,
        "json": args.export_json,
        "obj": args.export_obj,
        "mtl": args.export_obj.as_deref().map(pipeline::export::mtl_path).transpose()?.map(|(mtl, _)| mtl),
        "gltf": args.export_gltf.as_ref().map(|_| gltf_written),
    }))
}
