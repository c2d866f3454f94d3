//! `tincull failmap`: where the hierarchy culler fails over a terrain; the computation is [`eval::failmap`], this
//! module parses the arguments and writes the PNG and the CSV.

use std::path::PathBuf;

use anyhow::{Context, Result, ensure};
use clap::Args;
use eval::failmap;

use super::files::Outputs;
use super::{Output, OutputArgs};

/// Arguments of `tincull failmap`.
#[derive(Debug, Args)]
pub struct FailmapArgs {
    /// The hierarchy file written by `tincull build`.
    pub hierarchy: PathBuf,
    /// Culling method to map: `safe` or `lloyd-egbert` (never cull a visible triangle), `thesis` or `stewart` (where
    /// their false culls are).
    #[arg(long, default_value = "safe", value_parser = super::cull_cmd::parse_method)]
    pub method: cull::CullMethod,
    /// The horizon cullers' parameters (`safe`, `lloyd-egbert`).
    #[command(flatten)]
    pub safe: super::culling_args::SafeArgs,
    /// Eye height above the ground at each cell centre (m, 0 to 10,000 km: the exact checker's reach, as for `eval`).
    #[arg(long, default_value_t = 2.0)]
    pub eye_height: f64,
    /// Side of the map's square cells (m; `--cell` is an older name).
    #[arg(long, value_name = "M", alias = "cell")]
    pub cell_size: f64,
    /// The PNG image to write: one pixel per cell, north up.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// The CSV to write, one line per cell on the terrain: x, y, eye_z, false_culls, false_cull_area,
    /// occlusion_captured, triangles_drawn, visible (triangles the exact checker sees); `-` for standard output,
    /// instead of the summary.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Runs `tincull failmap`.
pub fn run(args: &FailmapArgs) -> Result<()> {
    let mut out: Output = args.output.into();
    args.safe.check_method(args.method)?;
    let params = args.safe.params()?;
    ensure!(
        args.cell_size.is_finite() && args.cell_size > 0.0,
        "--cell-size must be a positive length, got {}",
        tin::compact_number(args.cell_size)
    );
    ensure!(
        args.eye_height.is_finite() && args.eye_height >= 0.0,
        "--eye-height must be a finite height above the ground (0 or more; an eye below the ground sees none of the \
         terrain), got {}",
        tin::compact_number(args.eye_height)
    );
    ensure!(
        args.eye_height <= super::culling_args::EVAL_REACH,
        "--eye-height {}: failmap scores eyes within {} m of the terrain (its exact checker works to 1e-9 of the \
         distance)",
        tin::compact_number(args.eye_height),
        tin::compact_number(super::culling_args::EVAL_REACH)
    );
    // Without -o or --csv the summary alone is the result (as for `pvs`); quietened as well, nothing would be.
    out.require_a_result(
        args.out.is_some() || args.csv.is_some(),
        "give -o MAP.png, --csv MAP.csv or --json",
    )?;
    let mut files = Outputs::new();
    files.input(&args.hierarchy)?;
    if let Some(path) = &args.out {
        files.check_file(path, "-o", "the map is a PNG image (binary)")?;
        super::files::require_png(path, "-o")?;
    }
    if let Some(path) = &args.csv {
        files.check_or_stdout(path, "--csv", &mut out)?;
        super::files::refuse_other_format(path, "the map as CSV", "csv")?;
    }
    let h = super::mesh_input::load_hierarchy(&args.hierarchy)?;
    args.method
        .check(&h)
        .with_context(|| format!("{}: --method {}", args.hierarchy.display(), args.method))?;
    super::culling_args::warn_if_no_regions(&args.hierarchy, &h, args.method, out);
    let tin = super::mesh_input::hierarchy_tin_of(&h, &args.hierarchy)?;
    ensure!(
        tin.num_triangles() > 0,
        "{}: the mesh has no triangles",
        args.hierarchy.display()
    );
    let (cols, rows) = failmap::grid_size(&tin, args.cell_size)?;
    let bar = out.progress((cols * rows) as u64, "cells");
    let advance = Output::monotone(&bar);
    let map = failmap::compute(&h, args.method, params, &tin, args.eye_height, args.cell_size, &advance)?;
    bar.finish_and_clear();
    ensure!(
        map.scored().next().is_some(),
        "--cell-size {}: the centre of none of the {} x {} cells lies on the terrain of {}; give a smaller --cell-size",
        tin::compact_number(args.cell_size),
        map.cols,
        map.rows,
        args.hierarchy.display()
    );
    let worst = map.worst();
    if let Some(path) = &args.out {
        let rgba = map.to_rgba();
        let mut png_bytes = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut png_bytes, map.cols as u32, map.rows as u32);
            enc.set_color(png::ColorType::Rgba);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc.write_header()?;
            w.write_image_data(&rgba)?;
            w.finish()?;
        }
        files.add_bytes(path, &png_bytes)?;
    }
    if let Some(path) = &args.csv {
        files.add_bytes(path, map.to_csv().as_bytes())?;
    }
    files.commit()?;
    let scored: Vec<&failmap::Cell> = map.scored().collect();
    let with_fc = scored.iter().filter(|c| c.metrics.false_culls > 0).count();
    let occ: Vec<f64> = scored.iter().filter_map(|c| c.metrics.occlusion_captured).collect();
    // No cell with anything hidden (e.g. eyes far above the terrain): no mean, not the empty sum's −0.
    let captured = (!occ.is_empty()).then(|| occ.iter().sum::<f64>() / occ.len() as f64);
    out.say(format!(
        "{} x {} cells, {} on the terrain: {with_fc} with false culls (worst {worst}), occlusion captured {}",
        map.cols,
        map.rows,
        scored.len(),
        captured.map_or("none (no cell hides any triangle)".to_string(), |c| format!(
            "{c:.3} on average"
        )),
    ));
    out.json(&serde_json::json!({
        "hierarchy": args.hierarchy,
        "output": args.out,
        "csv": args.csv,
        "method": args.method.name(),
        "cols": map.cols,
        "rows": map.rows,
        "cells_on_terrain": scored.len(),
        "cells_with_false_culls": with_fc,
        "worst_false_culls": worst,
        "occlusion_captured_mean": captured,
    }))
}
