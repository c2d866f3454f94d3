//! `tincull info`: what a terrain mesh holds and whether it is a sound height field; what a hierarchy or a PVS file
//! holds.

use super::output::count;
use anyhow::{Context, Result};
use clap::Args;
use serde_json::json;

use super::mesh_input::MeshArgs;
use super::{Output, OutputArgs};

/// Arguments of `tincull info`.
#[derive(Debug, Args)]
#[command(mut_arg("mesh", |a| a.help(
    "The terrain mesh (OBJ), a DEM grid (.npy, .asc, .hgt, .png, .tif/.tiff) simplified to --dem-vertices, a \
     hierarchy (.tch) or a PVS file (.pvs, written by `tincull pvs -o`)"
)))]
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
    // What the file holds decides, by content first (a PVS file named .tch is still described), then by name (then
    // the reader says what is wrong with it: empty, truncated, another format).
    let is_pvs = super::mesh_input::file_kind(&args.mesh.mesh) == super::mesh_input::FileKind::Pvs;
    if !is_pvs && super::mesh_input::is_hierarchy(&args.mesh.mesh) {
        args.mesh.refuse_for_hierarchy()?;
        return hierarchy(&args.mesh.mesh, out);
    }
    let named_pvs = args
        .mesh
        .mesh
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pvs"));
    if is_pvs || named_pvs {
        args.mesh.refuse_import_flags("a PVS file (.pvs) holds no mesh")?;
        return pvs_file(&args.mesh.mesh, out);
    }
    let (tin, import, dem) = args.mesh.load_with_source(out)?;
    let stats = tin::mesh_stats(&tin);
    let check = tin::validate(&tin);
    let b = stats.bbox;
    out.say(format!("{}", args.mesh.mesh.display()));
    if let Some(d) = &dem {
        out.say(format!(
            "  DEM grid      {} x {} samples ({} voids), spacing {:.4} x {:.4} m, north-west sample at ({:.3}, {:.3})",
            d.rows, d.cols, d.voids, d.spacing.0, d.spacing.1, d.origin[0], d.origin[1]
        ));
        if let Some(c) = &d.to_metres {
            out.say(format!("  to metres     {c}"));
        }
        if let Some(g) = &d.geotiff {
            out.say(format!("  CRS           {}", g.crs));
            let [w, s, e, n] = g.native_bbox;
            out.say(format!(
                "  native bbox   x {w} .. {e}, y {s} .. {n} (sample centres, {:?})",
                g.raster_type
            ));
            out.say(format!(
                "  GeoTIFF       {} {}, {}, band {} of {}, nodata {}",
                g.sample_type,
                g.layout,
                g.compression,
                g.bands.1,
                g.bands.0,
                g.nodata.map_or("none".to_string(), |v| v.to_string())
            ));
            if let Some((scale, offset)) = g.scale_offset {
                out.say(format!(
                    "  heights       sample x {scale} + {offset} (GDAL scale and offset)"
                ));
            }
            if let Some(mask) = &g.nodata_mask {
                out.say(format!("  nodata mask   {mask}"));
            }
        }
        out.say(format!(
            "  simplified    to {} vertices (max error {:.3} m; --dem-vertices)",
            tin.num_vertices(),
            d.max_error
        ));
    }
    if dem.is_none() {
        out.say(format!(
            "  vertices      {} (file: {}, {}{})",
            stats.vertices,
            count(import.vertices_read, "vertex"),
            count(import.faces_read, "face"),
            if import.kept_faces {
                ", faces kept"
            } else {
                ", re-triangulated (Delaunay)"
            }
        ));
    } else {
        out.say(format!("  vertices      {}", stats.vertices));
    }
    out.say(format!("  triangles     {}", stats.triangles));
    out.say(bbox_line(b.min.to_array(), b.max.to_array()));
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
        "dem": dem,
    }))
}

/// `tincull info FILE.tch`: what a hierarchy holds (its mesh, its nodes, its visibility data, how it was built).
fn hierarchy(path: &std::path::Path, out: Output) -> Result<()> {
    let h = super::mesh_input::load_hierarchy(path)?;
    let file_bytes = infile::size(path).with_context(|| path.display().to_string())?;
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in &h.mesh.positions {
        for k in 0..3 {
            (lo[k], hi[k]) = (lo[k].min(p[k]), hi[k].max(p[k]));
        }
    }
    let leaves = h.nodes.iter().filter(|n| n.children.is_empty()).count();
    let depth = h.nodes.iter().map(|n| n.level).max().unwrap_or(0);
    let regions: usize = h.nodes.iter().map(|n| n.regions.len()).sum();
    let triangles = h.num_triangles();
    let bytes = h.visibility_bytes();
    let per_triangle = bytes as f64 / triangles.max(1) as f64;
    let [a, b] = h.always_visible;
    let b_info = &h.build;
    // The mesh checked as a height field, as `info MESH` checks one: a `.tch` from anything but `tincull` may hold
    // one that is not (its structure is checked on load, not this).
    let check = eval::evaluate::hierarchy_tin(&h).map(|tin| tin::validate(&tin));
    out.say(format!("{} (a tincull hierarchy, {file_bytes} bytes)", path.display()));
    out.say(format!(
        "  mesh          {} vertices, {} triangles",
        h.mesh.positions.len(),
        triangles
    ));
    if lo[0] <= hi[0] {
        out.say(bbox_line(lo, hi));
    }
    out.say(format!(
        "  hierarchy     {}: {} ({}, {}, depth {depth}), {} always visible",
        b_info.grouping.name(),
        count(h.nodes.len(), "node"),
        count(leaves, "leaf"),
        count(h.roots.len(), "root"),
        count((b - a) as usize, "triangle")
    ));
    if h.has_regions() {
        out.say(format!(
            "  regions       {regions} in {} sectors x {} subsectors; visibility data {bytes} bytes ({per_triangle:.2} \
             per triangle)",
            h.sectors, b_info.subsectors
        ));
    } else {
        out.say(format!(
            "  regions       none (built with --no-regions, or a --max-bytes budget that no level fits, or the terrain \
             hides nothing); visibility data {bytes} bytes ({per_triangle:.2} per triangle)"
        ));
    }
    out.say(format!(
        "  height field  {}",
        match &check {
            Ok(c) if c.is_height_field() => "yes".to_string(),
            Ok(_) => "NO (see --json for the violations)".to_string(),
            Err(e) => format!("NO ({e:#})"),
        }
    ));
    if let Ok(c) = &check {
        for w in &c.warnings {
            out.warn(w);
        }
    }
    let undersampling = b_info
        .undersampling
        .map_or(String::new(), |u| format!(", undersampling {u} m"));
    out.say(match b_info.grouping {
        cull::Grouping::Crystal => format!(
            "  built with    seeds {}, orphan passes {}, min group {}, max expanse {}, rng seed {}{undersampling}",
            b_info.seeds, b_info.orphan_passes, b_info.min_group, b_info.max_expanse, b_info.rng_seed,
        ),
        cull::Grouping::Quadtree {
            built_depth,
            stored_depth,
        } => format!("  built with    quadtree depth {built_depth}, depth {stored_depth} stored{undersampling}"),
    });
    out.json(&json!({
        "hierarchy": path,
        "file_bytes": file_bytes,
        "vertices": h.mesh.positions.len(),
        "triangles": triangles,
        "bbox": { "min": lo, "max": hi },
        "grouping": b_info.grouping,
        "nodes": h.nodes.len(),
        "leaves": leaves,
        "roots": h.roots.len(),
        "depth": depth,
        "always_visible": h.always_visible,
        "sectors": h.sectors,
        "regions": regions,
        "visibility_bytes": bytes,
        "visibility_bytes_per_triangle": per_triangle,
        "height_field": check.as_ref().is_ok_and(|c| c.is_height_field()),
        "validation": check.as_ref().ok(),
        "build": b_info,
    }))
}

/// Cells listed one by one by `info FILE.pvs` (all of them with `--json`).
const PVS_CELLS_LISTED: usize = 20;

/// Describes a `.pvs` file: the hierarchy it refers to, its parameters and every viewcell's PVS.
fn pvs_file(path: &std::path::Path, out: Output) -> Result<()> {
    let bytes = infile::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let file = pvs::PvsFile::from_bytes(&bytes).with_context(|| format!("{}", path.display()))?;
    let nt = u64::from(file.triangles);
    let sizes: Vec<u64> = file
        .cells
        .iter()
        .map(|c| c.ranges().iter().map(|r| u64::from(r[1] - r[0])).sum())
        .collect();
    let percent = |s: u64| 100.0 * s as f64 / nt.max(1) as f64;
    let mean = sizes.iter().sum::<u64>() as f64 / sizes.len().max(1) as f64;
    let p = file.params;
    out.say(format!(
        "{} (a tincull PVS file, {} bytes)",
        path.display(),
        bytes.len()
    ));
    out.say(format!(
        "  hierarchy     {} and {} (of the .tch it was computed for)",
        count(nt as usize, "triangle"),
        count(file.nodes as usize, "node")
    ));
    out.say(format!(
        "  computed with method {}, resolution {}, patch {}",
        p.method.name(),
        p.resolution,
        p.patch
    ));
    out.say(format!(
        "  cells         {}, mean PVS {mean:.0} triangles ({:.1}%)",
        file.cells.len(),
        percent(mean.round() as u64)
    ));
    for (i, (c, &s)) in file.cells.iter().zip(&sizes).enumerate().take(PVS_CELLS_LISTED) {
        let [x0, y0, x1, y1] = c.cell.rect;
        out.say(format!(
            "  cell {i:<8} x {x0} .. {x1}, y {y0} .. {y1}, {} (top {:.3} m): PVS {s} triangles ({:.1}%) in {}, {}; {} \
             bytes",
            c.cell.height,
            c.ztop,
            percent(s),
            count(c.ranges().len(), "range"),
            count(c.nodes().len(), "node"),
            c.encoded_len()
        ));
    }
    if file.cells.len() > PVS_CELLS_LISTED {
        out.say(format!(
            "  … and {} more cells (--json lists them all)",
            file.cells.len() - PVS_CELLS_LISTED
        ));
    }
    let cells: Vec<serde_json::Value> = file
        .cells
        .iter()
        .zip(&sizes)
        .map(|(c, &s)| {
            json!({
                "cell": c.cell.rect,
                "height": c.cell.height,
                "ztop": c.ztop,
                "nodes": c.nodes(),
                "ranges": c.ranges(),
                "pvs_triangles": s,
                "bytes": c.encoded_len(),
            })
        })
        .collect();
    out.json(&json!({
        "pvs": path,
        "file_bytes": bytes.len(),
        "triangles": nt,
        "nodes": file.nodes,
        "method": p.method.name(),
        "resolution": p.resolution,
        "patch": p.patch,
        "mean_pvs_triangles": mean,
        "cells": cells,
    }))
}

/// The bounding box line of `info`, in millimetres, without a negative zero (a y-up file's `-0` heights).
fn bbox_line(lo: [f64; 3], hi: [f64; 3]) -> String {
    let mm = |v: f64| {
        let text = format!("{v:.3}");
        match text.strip_prefix('-') {
            Some(rest) if rest.bytes().all(|c| c == b'0' || c == b'.') => rest.to_string(),
            _ => text,
        }
    };
    format!(
        "  bbox          x {} .. {}, y {} .. {}, z {} .. {}",
        mm(lo[0]),
        mm(hi[0]),
        mm(lo[1]),
        mm(hi[1]),
        mm(lo[2]),
        mm(hi[2])
    )
}
