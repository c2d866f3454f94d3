//! `tincull failmap`: where the hierarchy culler fails over a terrain (design.md "Measuring accuracy").
//!
//! The footprint's bounding box is cut into square cells of side `--cell`; each cell whose centre lies on the
//! terrain is a viewpoint `--eye-height` metres above the ground there, looking all around. For each, the
//! hierarchy culler's drawn set is scored against ground truth ([`truth::GroundTruth`]). The PNG has one pixel per
//! cell, north up: red for a viewpoint with false culls (brighter = more falsely culled triangles, relative to the
//! worst cell), otherwise green whose brightness is the occlusion captured (dark = little), grey where nothing is
//! hidden, transparent outside the footprint. The CSV has one line per viewpoint. Cells are scored in parallel and
//! collected in order, so the output does not depend on the thread count.

use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};

use anyhow::{Result, ensure};
use clap::Args;
use cull::{Camera, Culler, DrawList, Hierarchy};
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use truth::{GroundTruth, ViewMetrics, view_metrics};

use super::Output;
use crate::evaluate::hierarchy_tin;

/// Arguments of `tincull failmap`.
#[derive(Debug, Args)]
pub struct FailmapArgs {
    /// The hierarchy file written by `tincull build`.
    pub hierarchy: PathBuf,
    /// Eye height above the ground at each cell centre (m).
    #[arg(long, default_value_t = 2.0)]
    pub eye_height: f64,
    /// Cell side (m).
    #[arg(long)]
    pub cell: f64,
    /// The PNG image to write.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// The CSV to write: x, y, eye_z, false_culls, false_cull_area, occlusion_captured, triangles_drawn.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// No progress bar and no summary.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Most cells a map may have.
const MAX_CELLS: u64 = 4_000_000;

struct Cell {
    eye: DVec3,
    metrics: ViewMetrics,
}

/// Runs `tincull failmap`.
pub fn run(args: &FailmapArgs) -> Result<()> {
    let out = Output {
        json: false,
        quiet: args.quiet,
    };
    ensure!(
        args.cell.is_finite() && args.cell > 0.0,
        "--cell must be a positive length, got {}",
        args.cell
    );
    ensure!(
        args.eye_height.is_finite(),
        "--eye-height must be finite, got {}",
        args.eye_height
    );
    ensure!(
        args.output.is_some() || args.csv.is_some(),
        "nothing to write: give -o MAP.png and/or --csv MAP.csv"
    );
    let h = Hierarchy::load(&args.hierarchy)?;
    let tin = hierarchy_tin(&h)?;
    ensure!(
        tin.num_triangles() > 0,
        "{}: the mesh has no triangles",
        args.hierarchy.display()
    );
    let b = tin.bbox();
    let cols = ((b.max.x - b.min.x) / args.cell).ceil().max(1.0);
    let rows = ((b.max.y - b.min.y) / args.cell).ceil().max(1.0);
    ensure!(
        cols * rows <= MAX_CELLS as f64,
        "a {} m cell gives {cols} x {rows} cells, more than {MAX_CELLS}: use a larger --cell",
        args.cell
    );
    let (cols, rows) = (cols as usize, rows as usize);
    let truth = GroundTruth::new(&tin);
    let culler = Culler::new(&h);
    let n = tin.num_triangles();
    let bar = out.progress((cols * rows) as u64, "cells");
    let done = AtomicU64::new(0);
    // Row 0 is the northern edge, as in the image.
    let cells: Vec<Option<Cell>> = (0..rows * cols)
        .into_par_iter()
        .map_init(DrawList::default, |list, i| {
            let (r, c) = (i / cols, i % cols);
            let p = DVec2::new(
                b.min.x + (c as f64 + 0.5) * args.cell,
                b.max.y - (r as f64 + 0.5) * args.cell,
            );
            let cell = truth.locator().ground_height(&tin, p).map(|g| {
                let eye = DVec3::new(p.x, p.y, g + args.eye_height);
                let visible = truth.visible_triangles(eye);
                culler.cull_into(&Camera::all_around(eye.to_array()), list);
                let drawn = list.mask(n);
                view_metrics(&tin, &visible, &drawn).map(|metrics| Cell { eye, metrics })
            });
            bar.set_position(done.fetch_add(1, Ordering::Relaxed) + 1);
            cell.transpose()
        })
        .collect::<truth::Result<Vec<_>>>()?;
    bar.finish_and_clear();

    let scored: Vec<&Cell> = cells.iter().flatten().collect();
    let worst = scored.iter().map(|c| c.metrics.false_culls).max().unwrap_or(0);
    if let Some(path) = &args.output {
        let mut rgba = Vec::with_capacity(cells.len() * 4);
        for cell in &cells {
            rgba.extend_from_slice(&colour(cell.as_ref(), worst));
        }
        let mut png_bytes = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut png_bytes, cols as u32, rows as u32);
            enc.set_color(png::ColorType::Rgba);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc.write_header()?;
            w.write_image_data(&rgba)?;
            w.finish()?;
        }
        tin::write_atomic(path, |w| w.write_all(&png_bytes))?;
    }
    if let Some(path) = &args.csv {
        let mut text =
            String::from("x,y,eye_z,false_culls,false_cull_area,occlusion_captured,triangles_drawn,visible\n");
        for c in &scored {
            let m = &c.metrics;
            text += &format!(
                "{},{},{},{},{},{},{},{}\n",
                c.eye.x,
                c.eye.y,
                c.eye.z,
                m.false_culls,
                m.false_cull_area,
                m.occlusion_captured.map_or(String::new(), |x| x.to_string()),
                m.triangles_drawn,
                m.visible
            );
        }
        tin::write_atomic(path, |w| w.write_all(text.as_bytes()))?;
    }
    let with_fc = scored.iter().filter(|c| c.metrics.false_culls > 0).count();
    let occ: Vec<f64> = scored.iter().filter_map(|c| c.metrics.occlusion_captured).collect();
    out.say(format!(
        "{cols} x {rows} cells, {} on the terrain: {with_fc} with false culls (worst {worst}), occlusion captured {:.3} on average",
        scored.len(),
        occ.iter().sum::<f64>() / occ.len().max(1) as f64
    ));
    Ok(())
}

/// The pixel of one cell.
fn colour(cell: Option<&Cell>, worst: usize) -> [u8; 4] {
    let Some(c) = cell else {
        return [0, 0, 0, 0];
    };
    let m = &c.metrics;
    if m.false_culls > 0 {
        let f = m.false_culls as f64 / worst.max(1) as f64;
        return [(110.0 + 145.0 * f).round() as u8, 0, 0, 255];
    }
    match m.occlusion_captured {
        Some(o) => [0, (30.0 + 225.0 * o.clamp(0.0, 1.0)).round() as u8, 0, 255],
        None => [128, 128, 128, 255],
    }
}
