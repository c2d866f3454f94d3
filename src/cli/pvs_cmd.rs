//! `tincull pvs`: from-region visibility. The potentially visible set (PVS) of one viewcell (`--cell`), of every
//! cell of a grid over the footprint (`--grid`), or a check of random cells against the exact checker (`--check`).

use super::output::count;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail, ensure};
use clap::Args;
use cull::{Hierarchy, SafeCuller};
use pvs::{CellPvs, CellRecord, Height, Method, Pvs, PvsFile, PvsParams, ViewCell, check_cell, sample_eyes};
use rand::{RngExt, SeedableRng};
use rayon::prelude::*;
use serde_json::{Value, json};

use super::culling_args::EVAL_REACH;
use super::files::Outputs;
use super::values::{parse_pair, parse_rect};
use super::{Output, OutputArgs};

/// Arguments of `tincull pvs`.
#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("mode").required(true).args(["cell", "grid", "check"])))]
pub struct PvsArgs {
    /// The hierarchy file written by `tincull build`.
    pub hierarchy: PathBuf,
    /// One viewcell: `x0,y0,x1,y1` in world coordinates (m).
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = parse_rect, allow_hyphen_values = true)]
    pub cell: Option<[f64; 4]>,
    /// Every cell of a grid of SIZE × SIZE metres over the footprint's bounding box (progress bar).
    #[arg(long, value_name = "SIZE")]
    pub grid: Option<f64>,
    /// Check N random cells (1 to 1000000) of `--cell-size` against the exact checker from 64 sample points each
    /// (corners, edges, interior, both heights): misses (target 0), PVS size against the union of the sampled visible
    /// sets and of the safe culler's drawn sets, seconds and bytes per cell; for `koltun` at every `--resolution`,
    /// `regions`, and `both` at the highest resolution. The heights must lie within 10,000 km of the terrain (the
    /// exact checker's reach, as for `eval`).
    #[arg(long, value_name = "N")]
    pub check: Option<usize>,
    /// Side of the random cells of `--check` (m) [default: 100].
    #[arg(long, value_name = "M")]
    pub cell_size: Option<f64>,
    /// Seed of the random cells of `--check` and of their interior sample points [default: 1].
    #[arg(long, value_name = "SEED")]
    pub view_seed: Option<u64>,
    /// Absolute height band of the cell: `z0,z1` (m).
    #[arg(long, value_name = "Z0,Z1", value_parser = parse_pair, allow_hyphen_values = true,
          conflicts_with = "above_ground")]
    pub height_band: Option<[f64; 2]>,
    /// Height band above the ground under each point of the cell: `h0,h1` (m) [default: 0,2].
    #[arg(long, value_name = "H0,H1", value_parser = parse_pair, allow_hyphen_values = true)]
    pub above_ground: Option<[f64; 2]>,
    /// Test that culls: `koltun` (Koltun et al. 2001 in the dual ray space), `regions` (the conservative precomputed
    /// regions) or `both` [default: both]. `--check` reports every method (and refuses this option).
    #[arg(long, value_parser = parse_method)]
    pub method: Option<Method>,
    /// Resolution R of the R × R ray-space bitmap, 1 to 256 [default: 64]; with `--check` a comma-separated list.
    /// Koltun's test only: refused with `--method regions`.
    #[arg(long, value_delimiter = ',', value_name = "R")]
    pub resolution: Vec<u32>,
    /// Largest patch (triangles) of the halving trees below the hierarchy's leaves, 1 to 64 [default: 16]: the PVS's
    /// unit below the leaves (smaller: a tighter PVS, more boxes to test), and the patch of the safe culler that
    /// `--check` compares with (its other parameters are its defaults). Refused with `--method regions`, whose
    /// regions are the hierarchy nodes' only.
    #[arg(long, value_name = "N")]
    pub patch: Option<usize>,
    /// Write the PVS of every cell here, in the compact binary form (`.pvs`); not with `--check`, which writes no PVS.
    #[arg(long, short = 'o', value_name = "FILE", conflicts_with = "check")]
    pub out: Option<PathBuf>,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Refuses, for `--check`, a band of heights whose sample points lie farther than [`EVAL_REACH`] above or below the
/// box of `h`'s vertices: the exact checker that scores them works to `1e-9` of the distance, as for `eval`.
fn band_within_reach(h: &Hierarchy, height: Height) -> Result<()> {
    let (lo, hi) = h
        .mesh
        .positions
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p[2]), hi.max(p[2]))
        });
    let (flag, far) = match height {
        // An eye at most `top` above the ground is at most `top` above the box.
        Height::AboveGround([_, top]) => ("--above-ground", top),
        Height::Band([bottom, top]) => ("--height-band", (lo - bottom).max(top - hi)),
    };
    ensure!(
        far <= EVAL_REACH,
        "{flag}: --check scores sample points within {} m of the terrain's box (its exact checker works to 1e-9 of the \
         distance), and this band reaches {} m beyond it",
        tin::compact_number(EVAL_REACH),
        tin::compact_number(far)
    );
    Ok(())
}

/// Refuses an absolute band that lies wholly below the terrain's lowest vertex: every eye of every cell would be
/// under the ground (`--cell` checks its own cell against the ground under it; a grid's or a check's cells cover the
/// footprint's box, whose corners may hold no terrain, so they are checked against the whole mesh).
fn band_over_lowest_ground(h: &Hierarchy, height: Height) -> Result<()> {
    if let Height::Band([_, top]) = height {
        let lowest = h.mesh.positions.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
        ensure!(
            top >= lowest,
            "--height-band: the band up to {} m lies below the whole terrain (its lowest vertex is at {} m): an eye \
             below the ground sees none of the terrain",
            tin::compact_number(top),
            tin::compact_number(lowest)
        );
    }
    Ok(())
}

fn parse_method(s: &str) -> Result<Method, String> {
    Method::from_name(s).ok_or_else(|| format!("unknown method {s:?}; expected one of koltun, regions, both"))
}

/// Runs `tincull pvs`.
pub fn run(args: &PvsArgs, out: Output) -> Result<()> {
    let height = match (args.height_band, args.above_ground) {
        (Some(z), _) => Height::Band(z),
        (None, Some(h)) => Height::AboveGround(h),
        (None, None) => Height::AboveGround([0.0, 2.0]),
    };
    // Before the hierarchy is read and prepared (seconds on a large one).
    height.validate().context(if args.height_band.is_some() {
        "--height-band"
    } else {
        "--above-ground"
    })?;
    // A check's result is its report: `-o` does not go with `--check`.
    let hint = if args.check.is_some() {
        "give --json"
    } else {
        "give -o FILE.pvs or --json"
    };
    out.require_a_result(args.out.is_some(), hint)?;
    if args.method == Some(Method::Regions) {
        for (flag, given) in [
            ("--resolution", !args.resolution.is_empty()),
            ("--patch", args.patch.is_some()),
        ] {
            ensure!(
                !given,
                "{flag} does not apply to --method regions: the conservative regions are the hierarchy nodes' own, \
                 with no ray-space bitmap and nothing below the leaves"
            );
        }
    }
    let resolutions = if args.resolution.is_empty() {
        vec![64]
    } else {
        args.resolution.clone()
    };
    let patch = args.patch.unwrap_or(cull::SafeParams::default().patch);
    for (i, &r) in resolutions.iter().enumerate() {
        ensure!(
            (1..=pvs::MAX_RESOLUTION).contains(&r),
            "--resolution must be from 1 to {}, got {r}",
            pvs::MAX_RESOLUTION
        );
        ensure!(!resolutions[..i].contains(&r), "--resolution: {r} is given twice");
    }
    ensure!(
        args.check.is_some() || resolutions.len() == 1,
        "--resolution takes a list only with --check"
    );
    ensure!(
        (1..=cull::MAX_PATCH).contains(&patch),
        "--patch must be from 1 to {}, got {patch}",
        cull::MAX_PATCH
    );
    let safe_params = cull::SafeParams {
        patch,
        ..cull::SafeParams::default()
    };
    let mut files = Outputs::new();
    if let Some(n) = args.check {
        ensure!(
            args.method.is_none(),
            "--method: --check reports every method (koltun, regions and both), each at every --resolution"
        );
        ensure!(n >= 1, "--check must be at least 1 cell");
        ensure!(
            n <= pvs::MAX_GRID_CELLS,
            "--check {n}: at most {} cells (as --grid; each is checked from 64 sample points)",
            pvs::MAX_GRID_CELLS
        );
    }
    if args.check.is_none() {
        for (flag, given) in [
            ("--cell-size", args.cell_size.is_some()),
            ("--view-seed", args.view_seed.is_some()),
        ] {
            anyhow::ensure!(
                !given,
                "{flag} is for --check (the random cells it tests); --cell and --grid give theirs"
            );
        }
    }
    files.input(&args.hierarchy)?;
    if let Some(path) = &args.out {
        files.check_file(
            path,
            "-o",
            "a .pvs file is binary, and standard output carries pvs's report",
        )?;
        super::files::refuse_other_format(path, "a PVS file", "pvs")?;
    }
    let h = super::mesh_input::load_hierarchy(&args.hierarchy)?;
    if args.cell.is_none() {
        band_over_lowest_ground(&h, height)?;
    }
    if let Some(n) = args.check {
        band_within_reach(&h, height)?;
        return check(args, &h, height, n, &resolutions, safe_params, out);
    }
    if args.method == Some(Method::Regions) && !h.has_regions() {
        out.warn(format!(
            "{} holds no regions (built with --no-regions, or the terrain hid nothing from its vertices in the \
             build): --method regions keeps every triangle in the PVS",
            args.hierarchy.display()
        ));
    }
    let params = PvsParams {
        method: args.method.unwrap_or(Method::Both),
        resolution: resolutions[0],
        patch: safe_params.patch as u32,
    };
    // The cells are checked first, by a computer without the conservative regions (which take seconds to minutes).
    let cells = {
        let probe = Pvs::with_regions(&h, params, None)?;
        match (args.cell, args.grid) {
            (Some(rect), _) => {
                let cell = ViewCell { rect, height };
                probe.check_over_terrain(&cell).context("--cell")?;
                vec![cell]
            }
            (None, Some(size)) => probe.grid(size, height).context("--grid")?,
            (None, None) => bail!("give --cell, --grid or --check"),
        }
    };
    for c in &cells {
        c.validate().with_context(|| format!("--cell {:?}", c.rect))?;
    }
    let spinner = out.spinner("preparing (walls, boxes and, for regions, the conservative regions)");
    let prep = Instant::now();
    let pvs = Pvs::new(&h, params)?;
    let prep_s = prep.elapsed().as_secs_f64();
    spinner.finish_and_clear();
    let bar = if args.grid.is_some() {
        out.progress(cells.len() as u64, "cells")
    } else {
        indicatif::ProgressBar::hidden()
    };
    let start = Instant::now();
    let results: Vec<CellPvs> = cells
        .par_iter()
        .map(|c| {
            let r = pvs.compute(c);
            bar.inc(1);
            r
        })
        .collect::<Result<_, _>>()?;
    bar.finish_and_clear();
    let total_s = start.elapsed().as_secs_f64();
    let records: Vec<CellRecord> = cells
        .iter()
        .zip(&results)
        .map(|(c, r)| CellRecord::new(*c, r))
        .collect();
    let file = PvsFile {
        triangles: h.num_triangles() as u32,
        nodes: h.nodes.len() as u32,
        params,
        cells: records,
    };
    let bytes = file.to_bytes()?;
    if let Some(path) = &args.out {
        files.add_bytes(path, &bytes)?;
        files.commit()?;
    }
    let nt = h.num_triangles() as u64;
    let sizes: Vec<u64> = results.iter().map(CellPvs::triangles).collect();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let mean_size = mean(&sizes.iter().map(|&s| s as f64).collect::<Vec<_>>());
    let mean_s = mean(&results.iter().map(|r| r.seconds).collect::<Vec<_>>());
    if out.json {
        let cells_json: Vec<Value> = cells
            .iter()
            .zip(&results)
            .zip(&file.cells)
            .map(|((c, r), rec)| {
                json!({
                    "cell": c.rect,
                    "ztop": r.ztop,
                    "nodes": r.nodes,
                    "ranges": r.ranges,
                    "pvs_triangles": r.triangles(),
                    "boxes_tested": r.tests,
                    "seconds": r.seconds,
                    "bytes": rec.encoded_len(),
                })
            })
            .collect();
        out.json(&json!({
            "hierarchy": args.hierarchy,
            "method": params.method.name(),
            "resolution": params.resolution,
            "patch": params.patch,
            "height": height,
            "triangles": nt,
            "cells": cells_json,
            "mean_pvs_triangles": mean_size,
            "mean_seconds_per_cell": mean_s,
            "prepare_seconds": prep_s,
            "seconds": total_s,
            "file_bytes": args.out.as_ref().map(|_| bytes.len()),
        }))?;
    } else {
        for (c, r) in cells.iter().zip(&results).take(20) {
            out.say(format!(
                "cell {:?}: PVS {} of {} ({:.1}%) in {}, {}; {:.3} s",
                c.rect,
                r.triangles(),
                count(nt as usize, "triangle"),
                100.0 * r.triangles() as f64 / nt.max(1) as f64,
                count(r.ranges.len(), "range"),
                count(r.nodes.len(), "node"),
                r.seconds
            ));
        }
        if cells.len() > 20 {
            out.say(format!("… and {} more cells", cells.len() - 20));
        }
        out.say(format!(
            "{}, method {}{}, mean PVS {:.0} of {} triangles, {:.3} s per cell, {:.2} s in all \
             (+{:.2} s preparation), {} bytes{}",
            count(cells.len(), "cell"),
            params.method.name(),
            // The conservative regions have no ray-space bitmap.
            if params.method == Method::Regions {
                String::new()
            } else {
                format!(" at {}²", params.resolution)
            },
            mean_size,
            nt,
            mean_s,
            total_s,
            prep_s,
            bytes.len(),
            args.out
                .as_ref()
                .map_or(" as a .pvs file (give -o to write it)".to_string(), |p| format!(
                    " written to {}",
                    p.display()
                ))
        ));
    }
    Ok(())
}

/// One row of the check: a method at a resolution.
#[derive(Default)]
struct Row {
    misses: u64,
    max_misses: u64,
    pvs: Vec<f64>,
    over_visible: Vec<f64>,
    over_safe: Vec<f64>,
    seconds: Vec<f64>,
    bytes: Vec<f64>,
}

/// `--check N`: random cells against the exact checker.
fn check(
    args: &PvsArgs,
    h: &Hierarchy,
    height: Height,
    n: usize,
    resolutions: &[u32],
    safe_params: cull::SafeParams,
    out: Output,
) -> Result<()> {
    let cell_size = args.cell_size.unwrap_or(100.0);
    let view_seed = args.view_seed.unwrap_or(1);
    ensure!(
        cell_size.is_finite() && cell_size > 0.0,
        "--cell-size must be positive, got {}",
        tin::compact_number(cell_size)
    );
    let tin = super::mesh_input::hierarchy_tin_of(h, &args.hierarchy)?;
    let truth = truth::GroundTruth::new(&tin);
    let safe = SafeCuller::new(h, safe_params);
    let patch = safe_params.patch as u32;
    // Configurations: koltun at every resolution, regions, both at the highest resolution.
    let mut configs: Vec<PvsParams> = resolutions
        .iter()
        .map(|&resolution| PvsParams {
            method: Method::Koltun,
            resolution,
            patch,
        })
        .collect();
    configs.push(PvsParams {
        method: Method::Regions,
        resolution: 1,
        patch,
    });
    configs.extend(resolutions.iter().max().map(|&resolution| PvsParams {
        method: Method::Both,
        resolution,
        patch,
    }));
    let spinner = out.spinner("preparing (the conservative regions, walls and boxes)");
    let prep = Instant::now();
    let regions = std::sync::Arc::new(pvs::conservative_regions(h));
    let computers: Vec<Pvs> = configs
        .iter()
        .map(|&p| Pvs::with_regions(h, p, (p.method != Method::Koltun).then(|| regions.clone())))
        .collect::<Result<_, _>>()?;
    let prep_s = prep.elapsed().as_secs_f64();
    spinner.finish_and_clear();
    // Random cells whose centre lies on the terrain.
    let b = tin.bbox();
    let s = cell_size;
    ensure!(
        b.max.x - b.min.x > s && b.max.y - b.min.y > s,
        "--cell-size {s} does not fit in the footprint"
    );
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(view_seed);
    let mut cells = Vec::with_capacity(n);
    let mut tries = 0;
    while cells.len() < n {
        tries += 1;
        ensure!(
            tries < 1000 * (n + 1),
            "could not place {n} cells of {s} m on the terrain"
        );
        let x0 = rng.random_range(b.min.x..b.max.x - s);
        let y0 = rng.random_range(b.min.y..b.max.y - s);
        let centre = glam::DVec2::new(x0 + 0.5 * s, y0 + 0.5 * s);
        if truth.locator().ground_height(&tin, centre).is_some() {
            let cell = ViewCell {
                rect: [x0, y0, x0 + s, y0 + s],
                height,
            };
            // A side too small to widen the cell at its coordinates is named here, not in a viewcell's error.
            cell.validate()
                .with_context(|| format!("--cell-size {}", tin::compact_number(s)))?;
            cells.push(cell);
        }
    }
    let nt = tin.num_triangles();
    let mut rows: Vec<Row> = configs.iter().map(|_| Row::default()).collect();
    let mut unions = (Vec::new(), Vec::new(), 0usize, 0.0f64);
    let bar = out.progress(n as u64, "cells");
    for (i, cell) in cells.iter().enumerate() {
        let t = Instant::now();
        let eyes = sample_eyes(&truth, cell, 7, view_seed.wrapping_add(i as u64));
        let seen = check_cell(&truth, &safe, &eyes);
        unions.3 += t.elapsed().as_secs_f64();
        let (v, sd) = (seen.visible_count() as f64, seen.safe_count() as f64);
        unions.0.push(v);
        unions.1.push(sd);
        unions.2 += eyes.len();
        for (pvs, row) in computers.iter().zip(&mut rows) {
            let r = pvs.compute(cell)?;
            let misses = seen.misses(&r.mask(nt)).len() as u64;
            row.misses += misses;
            row.max_misses = row.max_misses.max(misses);
            let size = r.triangles() as f64;
            row.pvs.push(size);
            row.over_visible.push(size / v.max(1.0));
            row.over_safe.push(size / sd.max(1.0));
            row.seconds.push(r.seconds);
            row.bytes.push(CellRecord::new(*cell, &r).encoded_len() as f64);
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    // A PVS over a union of no triangle (no sample point saw any) has no ratio.
    let ratio = |pvs: f64, union: f64| (union > 0.0).then(|| pvs / union.max(1.0));
    let rows_json: Vec<Value> = configs
        .iter()
        .zip(&rows)
        .map(|(p, r)| {
            json!({
                "method": p.method.name(),
                "resolution": if p.method == Method::Regions { Value::Null } else { json!(p.resolution) },
                "misses": r.misses,
                "max_misses_per_cell": r.max_misses,
                "mean_pvs_triangles": mean(&r.pvs),
                "mean_pvs_fraction": mean(&r.pvs) / nt.max(1) as f64,
                "mean_pvs_over_visible": mean(&r.over_visible),
                "mean_pvs_over_safe": mean(&r.over_safe),
                "pvs_over_visible": ratio(mean(&r.pvs), mean(&unions.0)),
                "pvs_over_safe": ratio(mean(&r.pvs), mean(&unions.1)),
                "mean_seconds_per_cell": mean(&r.seconds),
                "mean_bytes_per_cell": mean(&r.bytes),
            })
        })
        .collect();
    if out.json {
        out.json(&json!({
            "hierarchy": args.hierarchy,
            "cells": n,
            "cell_size": s,
            "height": height,
            "view_seed": view_seed,
            "triangles": nt,
            "sample_points": unions.2,
            "mean_union_visible": mean(&unions.0),
            "mean_union_safe_drawn": mean(&unions.1),
            "truth_seconds": unions.3,
            "prepare_seconds": prep_s,
            "rows": rows_json,
        }))?;
    } else {
        out.say(format!(
            "{} of {s} m ({height}), {} sample points; per cell (means): union of visible sets {:.0}, of safe \
             drawn sets {:.0} of {nt} triangles; PVS/visible and PVS/safe are ratios of these means",
            super::output::count(n, "cell"),
            unions.2,
            mean(&unions.0),
            mean(&unions.1)
        ));
        out.say("method   R    misses  PVS (tri)  PVS/visible  PVS/safe  s/cell   bytes/cell");
        for (p, r) in configs.iter().zip(&rows) {
            out.say(format!(
                "{:<8} {:>4} {:>7} {:>10.0} {:>12} {:>9} {:>7.3} {:>11.0}",
                p.method.name(),
                if p.method == Method::Regions {
                    "-".to_string()
                } else {
                    p.resolution.to_string()
                },
                r.misses,
                mean(&r.pvs),
                ratio(mean(&r.pvs), mean(&unions.0)).map_or("-".into(), |x| format!("{x:.2}")),
                ratio(mean(&r.pvs), mean(&unions.1)).map_or("-".into(), |x| format!("{x:.2}")),
                mean(&r.seconds),
                mean(&r.bytes)
            ));
        }
    }
    Ok(())
}
