//! `tincull tin`: a DEM grid simplified into a TIN by greedy insertion, written as OBJ.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use serde_json::json;
use tin::SimplifyOptions;

use super::files::Outputs;
use super::mesh_input::DemArgs;
use super::{Output, OutputArgs};

/// Arguments of `tincull tin`.
#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("budget").required(true).multiple(true).args(["vertices", "max_error", "keep_grid"])))]
pub struct TinArgs {
    /// The DEM: .npy (with its .json sidecar or --spacing), .asc, .hgt (SRTM), 8- or 16-bit greyscale .png or GeoTIFF
    /// (.tif, .tiff; geographic CRSs are converted to metres like .hgt).
    pub dem: PathBuf,
    /// Output OBJ file (`-` for standard output).
    #[arg(short, long, value_name = "FILE")]
    pub out: PathBuf,
    /// Stop at this many vertices (with --max-error: at whichever is reached first); at least 3, and at least the
    /// corners of the grid's convex hull, which are always kept.
    #[arg(long)]
    pub vertices: Option<usize>,
    /// Stop when the largest vertical error is at most this (m) (with --vertices: at whichever is reached first).
    #[arg(long, value_name = "M", value_parser = parse_max_error, allow_hyphen_values = true)]
    pub max_error: Option<f64>,
    /// Keep every valid sample: the full-resolution grid, Delaunay-triangulated, without simplification (unlike
    /// `--max-error 0`, which leaves out the samples that the triangles through their neighbours reproduce exactly).
    #[arg(long, conflicts_with_all = ["vertices", "max_error"])]
    pub keep_grid: bool,
    /// How to read the DEM.
    #[command(flatten)]
    pub read: DemArgs,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Runs `tincull tin`.
pub fn run(args: &TinArgs, mut out: Output) -> Result<()> {
    let mut files = Outputs::new();
    files.input(&args.dem)?;
    files.check_or_stdout(&args.out, "-o", &mut out)?;
    super::files::refuse_other_format(&args.out, "an OBJ mesh", "obj")?;
    let start = Instant::now();
    let dem_opts = args.read.options();
    let spinner = out.spinner("reading DEM");
    let grid = tin::read_dem(&args.dem, &dem_opts)?;
    spinner.finish_and_clear();
    super::mesh_input::warn_if_degrees(&grid, &args.dem, out);
    super::mesh_input::warn_about_dem_file(&args.dem, &dem_opts, out);
    if args.keep_grid {
        return keep_grid(args, &grid, files, start, out);
    }
    let opts = SimplifyOptions {
        max_vertices: args.vertices,
        max_error: args.max_error,
    };
    let target = args.vertices.unwrap_or(grid.rows * grid.cols - grid.voids());
    let bar = out.progress(target as u64, "simplifying");
    let progress = |v: usize| bar.set_position(v as u64);
    let (tin, report) = tin::simplify(&grid, &opts, Some(&progress)).with_context(|| args.dem.display().to_string())?;
    bar.finish_and_clear();
    files.add(&args.out, |w| tin::write_obj_to(&tin, w))?;
    files.commit()?;
    let seconds = start.elapsed().as_secs_f64();
    out.say(format!(
        "{} ({} x {} samples, {} voids) -> {}: {} vertices, {} triangles, max error {:.3} m, rms {:.3} m; \
         simplification {:.2} s, total {seconds:.2} s",
        args.dem.display(),
        grid.rows,
        grid.cols,
        grid.voids(),
        args.out.display(),
        report.vertices,
        report.triangles,
        report.max_error,
        report.rms_error,
        report.seconds
    ));
    out.json(&json!({
        "dem": args.dem,
        "output": args.out,
        "rows": grid.rows,
        "cols": grid.cols,
        "voids": grid.voids(),
        "vertices": report.vertices,
        "triangles": report.triangles,
        "max_error": report.max_error,
        "rms_error": report.rms_error,
        "stopped_by": report.stopped_by,
        "simplify_seconds": report.seconds,
        "seconds": seconds,
    }))
}

/// `tincull tin --keep-grid`: every valid sample, Delaunay-triangulated.
fn keep_grid(args: &TinArgs, grid: &tin::Grid, mut files: Outputs, start: Instant, out: Output) -> Result<()> {
    let spinner = out.spinner("triangulating");
    let (tin, _) =
        tin::triangulate(&grid.points(), tin::DedupePolicy::Reject).with_context(|| args.dem.display().to_string())?;
    spinner.finish_and_clear();
    files.add(&args.out, |w| tin::write_obj_to(&tin, w))?;
    files.commit()?;
    let seconds = start.elapsed().as_secs_f64();
    out.say(format!(
        "{} ({} x {} samples, {} voids) -> {}: the whole grid, {} vertices, {} triangles; total {seconds:.2} s",
        args.dem.display(),
        grid.rows,
        grid.cols,
        grid.voids(),
        args.out.display(),
        tin.num_vertices(),
        tin.num_triangles(),
    ));
    out.json(&json!({
        "dem": args.dem,
        "output": args.out,
        "rows": grid.rows,
        "cols": grid.cols,
        "voids": grid.voids(),
        "vertices": tin.num_vertices(),
        "triangles": tin.num_triangles(),
        "max_error": 0.0,
        "rms_error": 0.0,
        "stopped_by": "keep_grid",
        "simplify_seconds": null,
        "seconds": seconds,
    }))
}

/// `--max-error`: a finite, non-negative number of metres (refused by clap, which names the flag).
fn parse_max_error(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(e) if e.is_finite() && e >= 0.0 => Ok(e),
        Ok(_) => Err(format!("{s}: the error bound must be finite and non-negative (m)")),
        Err(_) => Err(format!("{s:?} is not a number")),
    }
}
