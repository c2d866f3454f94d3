//! The far field: what a tile's horizons see of the terrain beyond its halo.
//!
//! ## Points on or below the terrain
//!
//! The grid is cut into blocks of `b × b` samples; each block keeps one point, its lowest valid sample (ties: the
//! first in row-major order) at that sample's position, lowered by the tiles' error bound `E`. Every tile's TIN
//! reproduces every sample within `E` (its simplification stops at `E`; its sides are simplified to `E`,
//! [`crate::boundary`]), so the merged terrain at that position is at least `z_min − E`: each far-field point lies on
//! or below the terrain. A horizon vertex found among points on or below the terrain is never higher than the
//! terrain at its position (a lower point subtends a smaller elevation angle from every eye). The halo's samples are
//! lowered by `E` for the same reason ([`crate::job`]). This bounds the horizons' elevation, not the regions built
//! from them: a region also depends on how far its horizon lies (its left bound), which a lower far field can bring
//! nearer, and with `--undersampling` the edges between these points are chords that can pass above the terrain. The
//! regions serve the thesis' test, which is not conservative in any case; the safe culler reads only the mesh.
//!
//! ## Coarser with distance: a min-pyramid
//!
//! Level 0 holds the blocks of `b` samples; a block of level `ℓ + 1` is the union of up to four blocks of level `ℓ`
//! (`b·2^(ℓ+1)` samples a side, fewer along the south and east edges) and keeps the lowest of their points (the same
//! tie rule, so it is the lowest valid sample of its samples), up to one block over the whole grid ([`FarField`],
//! computed once in the plan).
//!
//! A tile's far field is a cut through the pyramid ([`FarField::select`]), from the top block down: a block that
//! misses the tile's halo window is taken when its side is at most `1/ratio` of its distance from the tile (the
//! Chebyshev gap, in samples), else its children are looked at; a level-0 block is taken whole when it misses the
//! window, and otherwise gives its point only when that sample lies outside the window. Every sample outside the
//! window thus lies in exactly one block taken, or in a level-0 block that meets the window. A block taken at level
//! `ℓ > 0` subtends about `1/ratio` radian or less from the tile; and since its parent (twice as wide, at most one
//! block side nearer) was split, a block at a distance `d` is wider than `d / (2 ratio + 1)`. Once the distance
//! exceeds the tile's side, each doubling of it (a ring of area about `12 D²` at distance `D`) therefore adds at
//! most about `12 (2 ratio + 1)²` blocks: a tile sees `O(ratio² log n)` far points instead of the `n / b²` of level
//! 0, and a job's time and memory stay bounded by its tile as the terrain grows. With `ratio = 0` nothing is
//! coarsened: every level-0 point outside the window is taken.
//!
//! ## Stored per tile
//!
//! The plan computes the pyramid and every tile's cut once, and writes each cut to the tile's own far-field file
//! ([`far_to_bytes`]: checksummed, beside the plan), so a job reads only its own `O(ratio² log n)` points: neither
//! the plan file nor a job grows with the terrain's area.
//!
//! The same pyramid over squares of metres gives a mesh tile's far field ([`crate::part`]).

use std::path::Path;

use serde::{Deserialize, Serialize};
use tin::Grid;

use crate::TilesError;

/// Magic bytes of a tile's far-field file (framed like a `.tch`: [`cull::file::frame`]).
pub const FAR_MAGIC: &[u8; 8] = b"TCFAR\0\0\0";
/// Version of the far-field file format.
pub const FAR_VERSION: u32 = 1;

/// A tile's far-field points as a checksummed file.
pub fn far_to_bytes(points: &[FarPoint]) -> Result<Vec<u8>, TilesError> {
    crate::framed::encode(FAR_MAGIC, FAR_VERSION, &points, "a far field")
}

/// Reads a tile's far-field file written by [`far_to_bytes`], checking that every point is a sample of a grid of
/// `grid` (rows, columns) with a finite height; `name` names the file in errors.
pub fn far_from_bytes(bytes: &[u8], grid: [usize; 2], name: &Path) -> Result<Vec<FarPoint>, TilesError> {
    let points: Vec<FarPoint> = crate::framed::decode(bytes, FAR_MAGIC, FAR_VERSION, name, "far field")?;
    if let Some((i, p)) = points
        .iter()
        .enumerate()
        .find(|(_, p)| p.row as usize >= grid[0] || p.col as usize >= grid[1] || !tin::coordinate_in_range(p.z))
    {
        return Err(TilesError::TileFile {
            path: name.to_path_buf(),
            what: "far field",
            reason: format!(
                "far-field point {} (row {}, column {}, 1-based; height {}) is not a sample of the {} x {} grid, or its \
                 height is not finite, or not 0 and outside 2^-100 ..= 2^100 in magnitude",
                i + 1,
                u64::from(p.row) + 1,
                u64::from(p.col) + 1,
                p.z,
                grid[0],
                grid[1]
            ),
        });
    }
    Ok(points)
}

/// One far-field point: a sample position and its lowered height.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FarPoint {
    /// Sample row.
    pub row: u32,
    /// Sample column.
    pub col: u32,
    /// The sample's height lowered by the error bound (m).
    pub z: f64,
}

/// One level of a [`MinPyramid`]: its blocks row by row, each with its lowest point (`None` where it has none).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Level<T> {
    /// Blocks down (north to south).
    pub rows: usize,
    /// Blocks across (west to east).
    pub cols: usize,
    /// The blocks' lowest points, row-major.
    pub points: Vec<Option<T>>,
}

/// A min-pyramid over a grid of blocks: level 0 as given, every further level keeping the lowest point of each 2 × 2
/// blocks of the level below, up to one block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MinPyramid<T> {
    /// Level 0 (the finest) first.
    pub levels: Vec<Level<T>>,
}

impl<T> Default for MinPyramid<T> {
    /// No level: selects nothing.
    fn default() -> Self {
        MinPyramid { levels: Vec::new() }
    }
}

/// What [`MinPyramid::select`] does with a block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Choice {
    /// Take its point.
    Take,
    /// Leave it and everything in it out.
    Skip,
    /// Look at its children instead (at level 0: leave it out).
    Split,
}

impl<T: Copy> MinPyramid<T> {
    /// The pyramid over level 0 (`rows × cols` blocks, row-major), `lower(a, b)` telling whether `a` is strictly
    /// lower than `b` (a total order: ties broken the same way wherever they meet).
    pub fn new(rows: usize, cols: usize, level0: Vec<Option<T>>, lower: impl Fn(&T, &T) -> bool) -> MinPyramid<T> {
        debug_assert_eq!(level0.len(), rows * cols);
        let mut levels = vec![Level {
            rows,
            cols,
            points: level0,
        }];
        while let Some(below) = levels.last().filter(|l| l.rows > 1 || l.cols > 1) {
            let (rows, cols) = (below.rows.div_ceil(2), below.cols.div_ceil(2));
            let mut points = vec![None; rows * cols];
            for (i, slot) in points.iter_mut().enumerate() {
                let (r, c) = (i / cols, i % cols);
                for rr in 2 * r..(2 * r + 2).min(below.rows) {
                    for cc in 2 * c..(2 * c + 2).min(below.cols) {
                        if let Some(p) = below.points[rr * below.cols + cc]
                            && slot.as_ref().is_none_or(|q| lower(&p, q))
                        {
                            *slot = Some(p);
                        }
                    }
                }
            }
            levels.push(Level { rows, cols, points });
        }
        MinPyramid { levels }
    }

    /// A cut through the pyramid, from the top block down: `decide(level, row, col)` says for each block reached
    /// whether to take its point, skip it, or look at its children. Points come out in a fixed order (depth first,
    /// children row by row).
    pub fn select(&self, mut decide: impl FnMut(usize, usize, usize) -> Choice) -> Vec<T> {
        let mut out = Vec::new();
        let Some(top) = self.levels.len().checked_sub(1) else {
            return out;
        };
        let mut stack = Vec::new();
        for r in (0..self.levels[top].rows).rev() {
            for c in (0..self.levels[top].cols).rev() {
                stack.push((top, r, c));
            }
        }
        while let Some((level, r, c)) = stack.pop() {
            let here = &self.levels[level];
            match decide(level, r, c) {
                Choice::Take => out.extend(here.points[r * here.cols + c]),
                Choice::Skip => {}
                Choice::Split if level > 0 => {
                    let below = &self.levels[level - 1];
                    for rr in (2 * r..(2 * r + 2).min(below.rows)).rev() {
                        for cc in (2 * c..(2 * c + 2).min(below.cols)).rev() {
                            stack.push((level - 1, rr, cc));
                        }
                    }
                }
                Choice::Split => {}
            }
        }
        out
    }
}

/// A grid's far field (see the module docs): the min-pyramid of its lowered samples over blocks of `block` samples.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FarField {
    /// Side of a level-0 block (samples).
    pub block: usize,
    /// The grid's rows and columns.
    pub grid: [usize; 2],
    /// The pyramid.
    pub pyramid: MinPyramid<FarPoint>,
}

/// Whether `a` is lower than `b`: the lower height first, then the first in row-major order (the rule of a level-0
/// block, over any union of blocks).
fn lower(a: &FarPoint, b: &FarPoint) -> bool {
    (a.z, a.row, a.col) < (b.z, b.row, b.col)
}

/// About how many samples [`FarField::read_each_strip`] reads at a time.
const STRIP_SAMPLES: usize = 1 << 22;

/// The most level-0 blocks a DEM's far field may have (2^26, 1.6 GB of blocks and 0.5 GB more for the levels above):
/// the blocks are allocated from the DEM's header, before its samples are read, so a header claiming a huge grid is
/// refused here, asking for larger blocks, rather than allocated (a 1° SRTM tile at 1" has 0.8M blocks of 4 x 4
/// samples; 10G samples of 1 m lidar, 100 km square, 39M blocks of 16 x 16).
pub const MAX_FAR_BLOCKS: usize = 1 << 26;

/// Folds the samples `z` of the rows from `first` on (row-major, `cols` columns; `first` a multiple of `block`) into
/// the level-0 blocks `level0` (row-major, `cols.div_ceil(block)` a row): each block keeps its lowest valid sample
/// (the first in row-major order on ties) lowered by `max_error`. A block's rows all lie in one call, so calls over
/// strips of whole block rows give what one call over the whole grid gives.
fn lowest_in_blocks(
    level0: &mut [Option<FarPoint>],
    block: usize,
    cols: usize,
    first: usize,
    z: &[f64],
    max_error: f64,
) {
    debug_assert!(first.is_multiple_of(block) && z.len().is_multiple_of(cols));
    let (rows, block_cols) = (z.len() / cols, cols.div_ceil(block));
    for r0 in (0..rows).step_by(block) {
        for c0 in (0..cols).step_by(block) {
            let mut low: Option<(f64, usize, usize)> = None;
            for r in r0..(r0 + block).min(rows) {
                for c in c0..(c0 + block).min(cols) {
                    let h = z[r * cols + c];
                    if !h.is_nan() && low.is_none_or(|(lz, _, _)| h < lz) {
                        low = Some((h, r, c));
                    }
                }
            }
            level0[(first + r0) / block * block_cols + c0 / block] = low.map(|(h, r, c)| FarPoint {
                row: (first + r) as u32,
                col: c as u32,
                z: h - max_error,
            });
        }
    }
}

/// Sample rectangles, both ends inclusive: `[first row, last row, first column, last column]`.
pub type Rect = [usize; 4];

/// The Chebyshev gap between two rectangles of samples (0 when they meet).
fn gap(a: Rect, b: Rect) -> usize {
    let rows = b[0].saturating_sub(a[1]).max(a[0].saturating_sub(b[1]));
    let cols = b[2].saturating_sub(a[3]).max(a[2].saturating_sub(b[3]));
    rows.max(cols)
}

/// Whether two rectangles of samples share a sample.
fn meet(a: Rect, b: Rect) -> bool {
    a[0] <= b[1] && b[0] <= a[1] && a[2] <= b[3] && b[2] <= a[3]
}

impl FarField {
    /// The far field of `grid` with level-0 blocks of `block` samples, lowered by `max_error` (blocks with no valid
    /// sample have no point).
    pub fn new(grid: &Grid, block: usize, max_error: f64) -> FarField {
        let block = block.max(1);
        let mut level0 = vec![None; grid.rows.div_ceil(block) * grid.cols.div_ceil(block)];
        lowest_in_blocks(&mut level0, block, grid.cols, 0, &grid.z, max_error);
        FarField::of_level0([grid.rows, grid.cols], block, level0)
    }

    /// The far field of the DEM at `path` (read with `opts`), as [`FarField::new`] computes it from the whole grid,
    /// reading the DEM in strips of rows ([`tin::read_dem_strips`]): memory is the level-0 blocks (a `block²`-th of
    /// the samples) and one strip, which is handed to `each_strip(first row, samples of whole rows)` as it is read.
    /// Returns the grid's shape too.
    pub fn read_each_strip(
        path: &Path,
        opts: &tin::DemOptions,
        block: usize,
        max_error: f64,
        each_strip: impl FnMut(usize, &[f64]),
    ) -> Result<(FarField, tin::GridShape), TilesError> {
        FarField::read_in_strips(path, opts, block, max_error, STRIP_SAMPLES, each_strip)
    }

    /// [`FarField::read_each_strip`] in strips of about `strip_samples` samples (tests vary it).
    fn read_in_strips(
        path: &Path,
        opts: &tin::DemOptions,
        block: usize,
        max_error: f64,
        strip_samples: usize,
        mut each_strip: impl FnMut(usize, &[f64]),
    ) -> Result<(FarField, tin::GridShape), TilesError> {
        let block = block.max(1);
        let shape = tin::read_dem_header(path, opts)?;
        let blocks = (shape.rows.div_ceil(block)).saturating_mul(shape.cols.div_ceil(block));
        if blocks > MAX_FAR_BLOCKS {
            return Err(TilesError::Parameter(format!(
                "{}: {} x {} samples in far-field blocks of {block} x {block} samples are {blocks} blocks, more than the \
                 {MAX_FAR_BLOCKS} a far field holds: give a larger --far-block",
                path.display(),
                shape.cols,
                shape.rows
            )));
        }
        let mut level0 = vec![None; blocks];
        // Strips of whole block rows, of about `strip_samples` samples.
        let strip = block * (strip_samples / (block * shape.cols).max(1)).max(1);
        let shape = tin::read_dem_strips(path, opts, strip, |first, z| {
            lowest_in_blocks(&mut level0, block, shape.cols, first, z, max_error);
            each_strip(first, z);
            Ok(())
        })?;
        Ok((FarField::of_level0([shape.rows, shape.cols], block, level0), shape))
    }

    /// The pyramid over the level-0 points of a grid of `grid` (rows, columns) samples.
    fn of_level0(grid: [usize; 2], block: usize, level0: Vec<Option<FarPoint>>) -> FarField {
        let (rows, cols) = (grid[0].div_ceil(block), grid[1].div_ceil(block));
        FarField {
            block,
            grid,
            pyramid: MinPyramid::new(rows, cols, level0, lower),
        }
    }

    /// The far field of a flat grid of `grid` (rows, columns) samples at height 0, every block's point at its first
    /// sample, built without the grid: what a tile's far field would count on a grid too large to hold.
    pub fn flat(grid: [usize; 2], block: usize) -> FarField {
        let block = block.max(1);
        let cols = grid[1].div_ceil(block);
        let level0 = (0..grid[0].div_ceil(block) * cols)
            .map(|i| {
                Some(FarPoint {
                    row: ((i / cols) * block) as u32,
                    col: ((i % cols) * block) as u32,
                    z: 0.0,
                })
            })
            .collect();
        FarField::of_level0(grid, block, level0)
    }

    /// Points of level 0 (what `ratio = 0` can take).
    pub fn finest(&self) -> usize {
        self.pyramid
            .levels
            .first()
            .map_or(0, |l| l.points.iter().flatten().count())
    }

    /// The far field of the tile `tile` whose halo window is `window` (see the module docs).
    pub fn select(&self, tile: Rect, window: Rect, ratio: usize) -> Vec<FarPoint> {
        let [rows, cols] = self.grid;
        self.pyramid.select(|level, r, c| {
            let side = self.block << level;
            let block = [
                r * side,
                ((r + 1) * side).min(rows) - 1,
                c * side,
                ((c + 1) * side).min(cols) - 1,
            ];
            if meet(block, window) {
                if level > 0 {
                    return Choice::Split;
                }
                let l = &self.pyramid.levels[0];
                return match l.points[r * l.cols + c] {
                    Some(p) if !meet([p.row as usize, p.row as usize, p.col as usize, p.col as usize], window) => {
                        Choice::Take
                    }
                    _ => Choice::Skip,
                };
            }
            if level == 0 || (ratio > 0 && side.saturating_mul(ratio) <= gap(block, tile)) {
                Choice::Take
            } else {
                Choice::Split
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;
    use proptest::prelude::*;

    fn grid(rows: usize, cols: usize, seed: u64) -> Grid {
        let z: Vec<f64> = (0..rows * cols)
            .map(|i| {
                let h = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15 ^ seed) >> 40;
                if h.is_multiple_of(11) {
                    f64::NAN
                } else {
                    (h % 97) as f64
                }
            })
            .collect();
        Grid::new(rows, cols, 1.0, 1.0, DVec2::ZERO, z).expect("grid")
    }

    /// The lowest valid sample of a rectangle, by the pyramid's rule, lowered.
    fn lowest(g: &Grid, r: Rect, e: f64) -> Option<FarPoint> {
        let mut best: Option<FarPoint> = None;
        for row in r[0]..=r[1] {
            for col in r[2]..=r[3] {
                let z = g.z[row * g.cols + col];
                if !z.is_nan() && best.is_none_or(|b| z - e < b.z) {
                    best = Some(FarPoint {
                        row: row as u32,
                        col: col as u32,
                        z: z - e,
                    });
                }
            }
        }
        best
    }

    #[test]
    fn a_far_field_file_round_trips_and_rejects_points_off_the_grid() {
        let name = std::path::Path::new("far-00003.bin");
        let points = vec![
            FarPoint {
                row: 0,
                col: 4,
                z: -1.5,
            },
            FarPoint { row: 9, col: 0, z: 2.0 },
        ];
        let bytes = far_to_bytes(&points).expect("encode");
        assert_eq!(far_from_bytes(&bytes, [10, 5], name).expect("decode"), points);
        let e = far_from_bytes(&bytes, [9, 5], name)
            .expect_err("row 9 of 9 rows")
            .to_string();
        assert!(
            e.contains("far-00003.bin") && e.contains("point 2 (row 10, column 1, 1-based"),
            "{e}"
        );
        let nan = far_to_bytes(&[FarPoint {
            row: 0,
            col: 0,
            z: f64::NAN,
        }])
        .expect("encode");
        assert!(far_from_bytes(&nan, [1, 1], name).is_err());
        let e = far_from_bytes(&bytes[..bytes.len() - 1], [10, 5], name)
            .expect_err("truncated")
            .to_string();
        assert!(e.contains("far-00003.bin"), "{e}");
        let part = crate::part::MeshPart::default().to_bytes().expect("a part");
        assert!(
            far_from_bytes(&part, [10, 5], name).is_err(),
            "a part is not a far field"
        );
    }

    #[test]
    fn one_lowest_sample_per_block_lowered() {
        let z: Vec<f64> = (0..16)
            .map(|i| f64::from(i) * if i % 5 == 0 { -1.0 } else { 1.0 })
            .collect();
        let g = Grid::new(4, 4, 1.0, 1.0, DVec2::ZERO, z).expect("grid");
        let f = FarField::new(&g, 2, 0.5);
        let l0 = &f.pyramid.levels[0];
        assert_eq!((l0.rows, l0.cols, f.finest()), (2, 2, 4));
        // Block (0,0) holds samples 0, 1, 4, 5: the lowest is 5 (height -5).
        assert_eq!(
            l0.points[0],
            Some(FarPoint {
                row: 1,
                col: 1,
                z: -5.5
            })
        );
        // The top: the lowest of all (sample 15, height -15).
        assert_eq!(f.pyramid.levels.len(), 2);
        assert_eq!(f.pyramid.levels[1].points[0].map(|p| (p.row, p.col)), Some((3, 3)));
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 40, ..ProptestConfig::default() })]

        /// Reading a DEM file in strips of rows (windows of a `.npy`, a whole `.asc` handed out in strips) gives the
        /// far field of the whole grid, bit for bit, and reports every row.
        #[test]
        fn strips_of_a_file_give_the_whole_grids_far_field(rows in 1usize..30, cols in 1usize..30, seed in 0u64..1000,
                                                           block in 1usize..6, strip in 1usize..200) {
            let g = grid(rows.max(2), cols.max(2), seed);
            let dir = tempfile::tempdir().expect("tempdir");
            let npy = dir.path().join("g.npy");
            let mut bytes = Vec::new();
            tin::dem::npy::write_npy_to(&g, &mut bytes).expect("npy");
            std::fs::write(&npy, bytes).expect("write");
            std::fs::write(tin::dem::npy::sidecar_path(&npy), tin::dem::npy::sidecar_json(&g)).expect("sidecar");
            let mut last = 0;
            let (f, shape) = FarField::read_in_strips(&npy, &tin::DemOptions::default(), block, 0.25, strip, |first, z| {
                let done = first + z.len() / g.cols;
                assert!(first == last && done > last && z.len() % g.cols == 0);
                last = done;
            }).expect("read");
            prop_assert_eq!(last, g.rows);
            prop_assert_eq!((shape.rows, shape.cols), (g.rows, g.cols));
            prop_assert_eq!(f, FarField::new(&g, block, 0.25));
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// Every block of every level holds the lowest valid sample of its samples, lowered.
        #[test]
        fn every_level_keeps_the_lowest_sample(rows in 2usize..40, cols in 2usize..40, block in 1usize..6, seed in any::<u64>()) {
            let g = grid(rows, cols, seed);
            let f = FarField::new(&g, block, 0.25);
            prop_assert_eq!(f.pyramid.levels.last().map(|l| (l.rows, l.cols)), Some((1, 1)));
            for (level, l) in f.pyramid.levels.iter().enumerate() {
                let side = block << level;
                for r in 0..l.rows {
                    for c in 0..l.cols {
                        let rect = [r * side, ((r + 1) * side).min(rows) - 1, c * side, ((c + 1) * side).min(cols) - 1];
                        prop_assert_eq!(l.points[r * l.cols + c], lowest(&g, rect, 0.25));
                    }
                }
            }
        }

        /// The blocks a tile takes cover every sample outside its halo window exactly once and none inside; each
        /// point taken is the lowest sample of its block; `ratio = 0` takes exactly the level-0 points outside the
        /// window, and a positive ratio never more.
        #[test]
        fn a_cut_covers_the_outside_once(rows in 2usize..60, cols in 2usize..60, block in 1usize..5, seed in any::<u64>(),
                                         t in (0usize..60, 0usize..60, 0usize..60, 0usize..60), halo in 0usize..6,
                                         ratio in 0usize..6) {
            let g = grid(rows, cols, seed);
            let f = FarField::new(&g, block, 0.0);
            let (r0, r1) = ((t.0 % rows).min(t.1 % rows), (t.0 % rows).max(t.1 % rows));
            let (c0, c1) = ((t.2 % cols).min(t.3 % cols), (t.2 % cols).max(t.3 % cols));
            let tile = [r0, r1, c0, c1];
            let window = [r0.saturating_sub(halo), (r1 + halo).min(rows - 1), c0.saturating_sub(halo), (c1 + halo).min(cols - 1)];
            let mut covered = vec![0u8; rows * cols];
            let taken = f.pyramid.select(|level, r, c| {
                let side = block << level;
                let rect = [r * side, ((r + 1) * side).min(rows) - 1, c * side, ((c + 1) * side).min(cols) - 1];
                let choice = if meet(rect, window) { Choice::Split } else if level == 0 || (ratio > 0 && side * ratio <= gap(rect, tile)) { Choice::Take } else { Choice::Split };
                if choice == Choice::Take {
                    for row in rect[0]..=rect[1] {
                        for col in rect[2]..=rect[3] {
                            covered[row * cols + col] += 1;
                        }
                    }
                }
                choice
            });
            let _ = taken;
            for row in 0..rows {
                for col in 0..cols {
                    let (br, bc) = (row / block * block, col / block * block);
                    let block0 = [br, (br + block).min(rows) - 1, bc, (bc + block).min(cols) - 1];
                    let expected = u8::from(!meet(block0, window));
                    prop_assert_eq!(covered[row * cols + col], expected, "sample {} {}", row, col);
                }
            }
            let points = f.select(tile, window, ratio);
            for p in &points {
                prop_assert!(!meet([p.row as usize, p.row as usize, p.col as usize, p.col as usize], window));
                prop_assert!(p.z <= g.z[p.row as usize * cols + p.col as usize]);
            }
            let mut finest: Vec<(u32, u32)> = f.pyramid.levels[0].points.iter().flatten()
                .filter(|p| !meet([p.row as usize, p.row as usize, p.col as usize, p.col as usize], window))
                .map(|p| (p.row, p.col)).collect();
            finest.sort_unstable();
            let mut all: Vec<(u32, u32)> = f.select(tile, window, 0).iter().map(|p| (p.row, p.col)).collect();
            all.sort_unstable();
            prop_assert_eq!(&all, &finest);
            prop_assert!(points.len() <= finest.len());
        }
    }

    /// On a large grid a tile's far field stays within the module docs' bound (the near region at level 0, then at
    /// most `12 (2 ratio + 1)²` blocks per doubling of the distance), far below the level-0 count.
    #[test]
    fn a_tile_sees_few_far_points_on_a_large_grid() {
        let (n, block, ratio, side) = (1usize << 14, 16usize, 16usize, 256usize);
        let f = FarField::flat([n, n], block);
        let tile = [0, side - 1, 0, side - 1];
        let window = [0, side + 15, 0, side + 15];
        let points = f.select(tile, window, ratio).len();
        // Within one tile side of the tile: at most its area at level 0; beyond, log2(n / side) doublings.
        let near = (2 * side + block) * (2 * side + block) / (block * block);
        let doublings = (n / side).ilog2() as usize;
        let bound = near + doublings * 12 * (2 * ratio + 1) * (2 * ratio + 1);
        assert!(points <= bound, "{points} far points, bound {bound}");
        assert!(points * 10 < f.finest(), "{points} far points of {}", f.finest());
        assert_eq!(
            f.select(tile, window, 0).len(),
            f.finest() - (side + 16) * (side + 16) / (block * block)
        );
    }
}
