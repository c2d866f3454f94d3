//! Where the hierarchy culler fails over a terrain (the README's "Accuracy: how it is measured").
//!
//! The footprint's bounding box is cut into square cells of side `cell`; each cell whose centre lies on the
//! terrain is a viewpoint `eye_height` metres above the ground there, looking all around. For each, the hierarchy
//! culler's drawn set is scored against ground truth ([`truth::GroundTruth`]). [`FailureMap::to_rgba`] gives one
//! pixel per cell, north up: red for a viewpoint with false culls (brighter = more falsely culled triangles,
//! relative to the worst cell), otherwise green whose brightness is the occlusion captured (dark = little), grey
//! where nothing is hidden, transparent outside the footprint. [`FailureMap::to_csv`] has one line per viewpoint.
//! Cells are scored in parallel and collected in order, so the result does not depend on the thread count.

use std::sync::atomic::{AtomicU64, Ordering};

use anyhow::{Result, ensure};
use cull::{AnyCuller, Camera, CullMethod, DrawList, Hierarchy, SafeParams};
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use tin::Tin;
use truth::{GroundTruth, ViewMetrics, view_metrics};

/// Most cells a map may have.
pub const MAX_CELLS: u64 = 4_000_000;

/// The CSV header of [`FailureMap::to_csv`].
pub const CSV_HEADER: &str = "x,y,eye_z,false_culls,false_cull_area,occlusion_captured,triangles_drawn,visible";

/// One scored viewpoint.
#[derive(Clone, Debug)]
pub struct Cell {
    /// The eye: the cell centre, `eye_height` above the ground.
    pub eye: DVec3,
    /// The culler's drawn set scored against ground truth.
    pub metrics: ViewMetrics,
}

/// A failure map: `rows × cols` cells, row 0 at the northern edge; `None` where the cell centre is off the terrain.
#[derive(Clone, Debug)]
pub struct FailureMap {
    /// Columns (west to east).
    pub cols: usize,
    /// Rows (north to south).
    pub rows: usize,
    /// Cells in row-major order.
    pub cells: Vec<Option<Cell>>,
}

/// The number of cells (columns, rows) a map of `tin` with cells of side `cell` has; an error when `cell` is not a
/// positive length or the map would have more than [`MAX_CELLS`] cells.
pub fn grid_size(tin: &Tin, cell: f64) -> Result<(usize, usize)> {
    ensure!(
        cell.is_finite() && cell > 0.0,
        "--cell-size must be a positive length, got {}",
        tin::compact_number(cell)
    );
    let b = tin.bbox();
    let cols = ((b.max.x - b.min.x) / cell).ceil().max(1.0);
    let rows = ((b.max.y - b.min.y) / cell).ceil().max(1.0);
    ensure!(
        cols * rows <= MAX_CELLS as f64,
        "a {} m cell gives {} x {} cells, more than {MAX_CELLS}: use a larger --cell-size",
        tin::compact_number(cell),
        tin::compact_number(cols),
        tin::compact_number(rows)
    );
    Ok((cols as usize, rows as usize))
}

/// Scores the culler `method` (with the horizon cullers' run-time `params`) over `h` (whose mesh is `tin`) from every
/// cell. `progress` gets the number of cells done.
pub fn compute(
    h: &Hierarchy,
    method: CullMethod,
    params: SafeParams,
    tin: &Tin,
    eye_height: f64,
    cell: f64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<FailureMap> {
    ensure!(
        eye_height.is_finite(),
        "--eye-height must be finite, got {}",
        tin::compact_number(eye_height)
    );
    ensure!(tin.num_triangles() > 0, "the mesh has no triangles");
    let (cols, rows) = grid_size(tin, cell)?;
    let b = tin.bbox();
    let truth = GroundTruth::new(tin);
    let culler = AnyCuller::with_params(h, method, params);
    let n = tin.num_triangles();
    let done = AtomicU64::new(0);
    // Row 0 is the northern edge, as in the image.
    let cells: Vec<Option<Cell>> = (0..rows * cols)
        .into_par_iter()
        .map_init(DrawList::default, |list, i| {
            let (r, c) = (i / cols, i % cols);
            let p = DVec2::new(b.min.x + (c as f64 + 0.5) * cell, b.max.y - (r as f64 + 0.5) * cell);
            let scored = truth.locator().ground_height(tin, p).map(|g| {
                let eye = DVec3::new(p.x, p.y, g + eye_height);
                let visible = truth.visible_triangles(eye);
                culler.cull_into(&Camera::all_around(eye.to_array()), list);
                let drawn = list.mask(n);
                view_metrics(tin, &visible, &drawn).map(|metrics| Cell { eye, metrics })
            });
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            scored.transpose()
        })
        .collect::<truth::Result<Vec<_>>>()?;
    Ok(FailureMap { cols, rows, cells })
}

impl FailureMap {
    /// The cells on the terrain, in row-major order.
    pub fn scored(&self) -> impl Iterator<Item = &Cell> {
        self.cells.iter().flatten()
    }

    /// The most false culls of any cell.
    pub fn worst(&self) -> usize {
        self.scored().map(|c| c.metrics.false_culls).max().unwrap_or(0)
    }

    /// The image: 8-bit RGBA, `cols × rows`, row 0 north.
    pub fn to_rgba(&self) -> Vec<u8> {
        let worst = self.worst();
        let mut rgba = Vec::with_capacity(self.cells.len() * 4);
        for cell in &self.cells {
            rgba.extend_from_slice(&colour(cell.as_ref(), worst));
        }
        rgba
    }

    /// The CSV: [`CSV_HEADER`] and one line per cell on the terrain.
    pub fn to_csv(&self) -> String {
        let mut text = format!("{CSV_HEADER}\n");
        for c in self.scored() {
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
        text
    }
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
