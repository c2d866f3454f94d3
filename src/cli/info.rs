//! `tincull info`: what a terrain mesh holds and whether it is a sound height field.

use anyhow::Result;
use clap::Args;
use serde_json::json;

use super::mesh_input::MeshArgs;
use super::{Output, OutputArgs};

/// Arguments of `tincull info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The mesh and how to import it.
    #[command(flatten)]
    pub mesh: MeshArgs,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Runs `tincull info`.
pub fn run(args: &InfoArgs, out: Output) -> Result<()> {
    let (tin, import) = args.mesh.load(out)?;
    let stats = tin::mesh_stats(&tin);
    let check = tin::validate(&tin);
    let b = stats.bbox;
    out.say(format!("{}", args.mesh.mesh.display()));
    out.say(format!(
        "  vertices      {} (file: {} vertices, {} faces{})",
        stats.vertices,
        import.vertices_read,
        import.faces_read,
        if import.kept_faces {
            ", faces kept"
        } else {
            ", re-triangulated (Delaunay)"
        }
    ));
    out.say(format!("  triangles     {}", stats.triangles));
    out.say(format!(
        "  bbox          x {:.3} .. {:.3}, y {:.3} .. {:.3}, z {:.3} .. {:.3}",
        b.min.x, b.max.x, b.min.y, b.max.y, b.min.z, b.max.z
    ));
    out.say(format!(
        "  extent        {:.1} m x {:.1} m, relief {:.1} m",
        b.size().x,
        b.size().y,
        stats.relief
    ));
    out.say(format!(
        "  triangle area {:.3} .. {:.3} m² (mean {:.3}), min angle {:.2}°, slivers {}",
        stats.area_xy_min, stats.area_xy_max, stats.area_xy_mean, stats.min_angle_deg, stats.slivers
    ));
    out.say(format!(
        "  height field  {}",
        if check.is_height_field() {
            "yes"
        } else {
            "NO (see --json for the violations)"
        }
    ));
    for w in &check.warnings {
        out.warn(w);
    }
    out.json(&json!({
        "mesh": args.mesh.mesh,
        "vertices": stats.vertices,
        "triangles": stats.triangles,
        "bbox": { "min": b.min.to_array(), "max": b.max.to_array() },
        "relief": stats.relief,
        "height_field": check.is_height_field(),
        "slivers": stats.slivers,
        "stats": stats,
        "validation": check,
        "import": import,
    }))
}
