//! The plan of a tiled build (`plan.json`): the DEM, its grid, the tiles, the far field and the build parameters.
//!
//! Tiles cut the grid's sample intervals evenly: with `k` tiles across `n` samples, tile `i` spans samples
//! `round(i·(n−1)/k) ..= round((i+1)·(n−1)/k)`, so neighbouring tiles share one row or column of samples, which both
//! simplify identically ([`crate::boundary`]). A tile whose own samples are voids (or too few to triangulate: under
//! three, or all on one line: a row, a column, a diagonal) holds no terrain and is left out of the plan; the others are numbered in
//! order. The far field's pyramid is computed here, once, and each tile's cut
//! through it goes to the tile's own file ([`crate::far_field`]), so the plan file stays small (a few hundred bytes
//! a tile) and a job reads only what it needs, however large the terrain.

use std::path::{Path, PathBuf};

use pipeline::BuildParams;
use serde::{Deserialize, Serialize};
use tin::{DemOptions, GridShape};

use crate::TilesError;
use crate::far_field::{FarField, FarPoint, far_from_bytes, far_to_bytes};

/// The plan format's version; a plan of another version is refused.
pub const PLAN_VERSION: u32 = 3;

/// The DEM's grid, as the plan saw it; every job checks that the file still has it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridInfo {
    /// Rows (north to south).
    pub rows: usize,
    /// Columns (west to east).
    pub cols: usize,
    /// Sample spacing east-west (m).
    pub dx: f64,
    /// Sample spacing north-south (m).
    pub dy: f64,
    /// World x,y of sample (0, 0), the north-west corner.
    pub origin: [f64; 2],
}

impl GridInfo {
    /// The grid description of a DEM of shape `shape`.
    pub fn of(shape: &GridShape) -> GridInfo {
        GridInfo {
            rows: shape.rows,
            cols: shape.cols,
            dx: shape.dx,
            dy: shape.dy,
            origin: shape.origin.to_array(),
        }
    }

    /// The world position of sample `(row, col)` at height `z`: the one formula every tile uses, so that shared
    /// samples get bit-identical positions in every tile.
    pub fn position(&self, row: usize, col: usize, z: f64) -> [f64; 3] {
        [
            self.origin[0] + col as f64 * self.dx,
            self.origin[1] - row as f64 * self.dy,
            z,
        ]
    }
}

/// One tile: a rectangle of samples (both ends inclusive) and where its job writes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TileSpec {
    /// Index in [`Plan::tiles`].
    pub index: usize,
    /// Row of the tile in the tile grid (north first).
    pub tile_row: usize,
    /// Column of the tile in the tile grid (west first).
    pub tile_col: usize,
    /// First and last sample row (a DEM's tile).
    #[serde(default)]
    pub rows: [usize; 2],
    /// First and last sample column (a DEM's tile).
    #[serde(default)]
    pub cols: [usize; 2],
    /// A mesh's tile: its part file ([`crate::part`]), relative to the plan's folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub part: Option<PathBuf>,
    /// A DEM's tile: its far-field file ([`crate::far_field::far_to_bytes`]), relative to the plan's folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub far: Option<PathBuf>,
    /// A DEM's tile: the CRC-32 of the samples of its halo window as the plan read them (row by row, each sample's
    /// f64 bits little-endian, every NaN as one NaN); its job refuses a DEM whose window now reads otherwise. `None`
    /// in a plan made before it was kept (not checked).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub window_digest: Option<u32>,
    /// A mesh's tile: what its part holds, which the merge checks each built tile against.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extent: Option<MeshExtent>,
    /// The [`file_digest`] of the tile's far-field or part file as the plan wrote it ([`Plan::seal`]); its job
    /// refuses a file that differs (another plan's, another tile's). `None` in a plan made before it was kept (not
    /// checked).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file_digest: Option<u32>,
    /// The tile's partial hierarchy, relative to the plan's folder.
    pub output: PathBuf,
}

/// What a mesh tile's part holds: its vertices' bounding box in x,y and its counts. A tile's hierarchy keeps the
/// part's vertices and triangles, so a built tile that differs is not this tile's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshExtent {
    /// Least x and y of the tile's vertices.
    pub min: [f64; 2],
    /// Largest x and y of the tile's vertices.
    pub max: [f64; 2],
    /// The tile's vertices.
    pub vertices: usize,
    /// The tile's triangles.
    pub triangles: usize,
}

impl MeshExtent {
    /// The extent of `part`.
    pub fn of(part: &crate::part::MeshPart) -> MeshExtent {
        let (mut min, mut max) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &part.positions {
            for k in 0..2 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
            }
        }
        MeshExtent {
            min,
            max,
            vertices: part.positions.len(),
            triangles: part.triangles.len(),
        }
    }
}

/// How to cut a terrain into tiles. Lengths are in samples for a DEM, in metres for a mesh.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanOptions {
    /// Largest tile side: sample intervals of a DEM (a tile has at most `tile + 1` samples a side), metres of a
    /// mesh.
    pub tile: usize,
    /// Width of the full-resolution halo around a tile (samples, or metres).
    pub halo: usize,
    /// Side of the far field's finest blocks (samples, or metres).
    pub far_block: usize,
    /// Far-field blocks grow with distance so that each spans at most about `1 / far_ratio` radian from the tile
    /// ([`crate::far_field`]); 0 keeps every block at `far_block`.
    pub far_ratio: usize,
    /// Vertical error bound of every tile's simplification (m); 0 keeps every sample that is not exactly
    /// interpolated.
    pub max_error: f64,
    /// The build parameters of every tile.
    pub params: BuildParams,
    /// Tiles compute no horizons and no regions ([`pipeline::build_without_regions`]), for the run-time cullers
    /// only: the quadtree grouping, no halo (`halo` 0), and no far field (a DEM's tiles get no far-field file, a
    /// mesh's parts carry no halo or far-field points).
    #[serde(default)]
    pub no_regions: bool,
}

impl PlanOptions {
    /// Checks the values.
    pub fn validate(&self) -> Result<(), TilesError> {
        let bad = |m: String| Err(TilesError::Parameter(m));
        // Each message names the `tiles plan` option that sets the value.
        if self.tile < 2 {
            return bad(format!(
                "--tile {}: the tile side must be at least 2 (sample intervals; metres for a mesh)",
                self.tile
            ));
        }
        if self.far_block < 1 {
            return bad("--far-block 0: the far field's blocks must be at least 1 (samples; metres for a mesh)".into());
        }
        // The halo and the far field are lowered by the bound: between 1 nm and 1,000 km, the lowered heights stay
        // heights every stage accepts (0 or 2^-100 ..= 2^100 in magnitude).
        if !(self.max_error == 0.0 || (1e-9..=1e9).contains(&self.max_error)) {
            return bad(format!(
                "--max-error {}: the error bound must be 0 or between 1e-9 and 1e9 m (the halo and far field are \
                 lowered by it)",
                tin::compact_number(self.max_error)
            ));
        }
        // The build parameters every tile job would refuse, refused before any job runs.
        self.params
            .validate()
            .map_err(|e| TilesError::Parameter(format!("{e:#}")))?;
        if self.no_regions {
            if !matches!(self.params.grouping, pipeline::Grouping::Quadtree(_)) {
                return bad(
                    "--no-regions needs --grouping quadtree: crystal groups grow from the occlusion regions".into(),
                );
            }
            if self.halo != 0 {
                return bad(format!(
                    "--halo {}: the tiles of a plan without regions (--no-regions) compute no horizons and read no \
                     halo",
                    self.halo
                ));
            }
        }
        Ok(())
    }
}

/// The digest of one far-field or part file, for [`Plan::seal`].
pub fn file_digest(bytes: &[u8]) -> u32 {
    let mut hasher = crc32fast::Hasher::new();
    hasher.update(&(bytes.len() as u64).to_le_bytes());
    hasher.update(bytes);
    hasher.finalize()
}

/// A tiled build's plan (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plan {
    /// [`PLAN_VERSION`].
    pub version: u32,
    /// The DEM or mesh, absolute or relative to the plan's folder (a mesh's tiles read only their parts).
    pub source: PathBuf,
    /// How to read a DEM.
    pub dem: DemOptions,
    /// A DEM's grid; `None` for a mesh.
    pub grid: Option<GridInfo>,
    /// How it was cut.
    pub options: PlanOptions,
    /// The tiles, row by row.
    pub tiles: Vec<TileSpec>,
    /// Where the tiles' outputs go, relative to the plan's folder.
    pub tiles_dir: PathBuf,
}

/// The halo window of `spec` in a grid of `shape` (rows, columns): its samples and `halo` more on every side, within
/// the grid (rows, then columns, both ends inclusive).
fn halo_window(halo: usize, shape: [usize; 2], spec: &TileSpec) -> ([usize; 2], [usize; 2]) {
    let [rows, cols] = shape;
    (
        [
            spec.rows[0].saturating_sub(halo),
            spec.rows[1].saturating_add(halo).min(rows.saturating_sub(1)),
        ],
        [
            spec.cols[0].saturating_sub(halo),
            spec.cols[1].saturating_add(halo).min(cols.saturating_sub(1)),
        ],
    )
}

/// Adds samples to a window's digest ([`TileSpec::window_digest`]): each sample's f64 bits, little-endian, every
/// NaN (a void) as the one canonical NaN.
pub(crate) fn digest_samples(hasher: &mut crc32fast::Hasher, z: &[f64]) {
    let mut bytes = Vec::with_capacity(8 * z.len());
    for v in z {
        let v = if v.is_nan() { f64::NAN } else { *v };
        bytes.extend_from_slice(&v.to_bits().to_le_bytes());
    }
    hasher.update(&bytes);
}

/// The digest of a window's samples in row-major order ([`TileSpec::window_digest`]).
pub(crate) fn window_digest(z: &[f64]) -> u32 {
    let mut hasher = crc32fast::Hasher::new();
    digest_samples(&mut hasher, z);
    hasher.finalize()
}

/// The tile grid (tile rows, tile columns) that cuts a grid of `shape` samples (rows, columns) into tiles of at most
/// `tile` sample intervals a side.
pub fn tile_grid(shape: [usize; 2], tile: usize) -> [usize; 2] {
    shape.map(|n| n.saturating_sub(1).div_ceil(tile).max(1))
}

/// What a tile's own samples hold: how many are not voids, and the rows and columns they span.
#[derive(Clone, Copy, Debug, Default)]
struct TileTerrain {
    samples: usize,
    /// The first valid sample and another one (grid column and row), while no sample has been seen off their line.
    first: Option<[i64; 2]>,
    second: Option<[i64; 2]>,
    /// Whether three of the samples are not on one line (exact: integer grid positions).
    spans_area: bool,
}

impl TileTerrain {
    /// Adds row `r`'s samples `z`, the first at column `c0`.
    fn add(&mut self, r: usize, c0: usize, z: &[f64]) {
        for (k, v) in z.iter().enumerate() {
            if v.is_nan() {
                continue;
            }
            self.samples += 1;
            let q = [(c0 + k) as i64, r as i64];
            match (self.first, self.second) {
                _ if self.spans_area => {}
                (None, _) => self.first = Some(q),
                (Some(_), None) => self.second = Some(q),
                (Some(a), Some(b)) => {
                    // Grid positions are below 2^31, so the cross product is exact in i64.
                    self.spans_area = (b[0] - a[0]) * (q[1] - a[1]) != (b[1] - a[1]) * (q[0] - a[0]);
                }
            }
        }
    }

    /// Whether the samples can be triangulated: three that are not on one line (a row, a column or a diagonal would
    /// leave the tile's job nothing to triangulate).
    fn can_triangulate(&self) -> bool {
        self.spans_area
    }
}

/// The first sample of each of `k` even spans over `n` samples, and the last sample.
fn cuts(n: usize, k: usize) -> Vec<usize> {
    (0..=k)
        .map(|i| ((i * (n - 1)) as f64 / k as f64).round() as usize)
        .collect()
}

/// The tiles of a DEM's tile grid that a plan leaves out ([`make_plan`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LeftOut {
    /// Tiles whose samples are all voids.
    pub void_tiles: usize,
    /// Tiles with samples too few or all on one line (a row, a column, a diagonal), which a tile job cannot
    /// triangulate alone.
    pub line_tiles: usize,
    /// The samples of those tiles (those on a side shared with a kept tile stay in the terrain, the others do not).
    pub line_samples: usize,
}

/// The most tiles a plan may have (2^20): each is a job of its own, and the plan lists them all before the DEM's
/// samples are read, so a header claiming a huge grid is refused here rather than allocated.
pub const MAX_TILES: usize = 1 << 20;

/// Reads the DEM at `source` (with `dem`) in strips of rows, computing its far field ([`FarField::read_each_strip`];
/// memory bounded by a strip and the far field's blocks, not the grid; `progress(rows read, rows)`) and every tile's
/// window digest, and cuts it into tiles, leaving out those with no terrain to triangulate ([`LeftOut`]). `tiles_dir`
/// is where the jobs will write, relative to the plan's folder. Each tile's far-field file ([`TileSpec::far`]) is to be
/// written beside the plan with [`Plan::far_file`].
pub fn make_plan(
    source: &Path,
    dem: DemOptions,
    options: PlanOptions,
    tiles_dir: &Path,
    progress: impl FnMut(usize, usize),
) -> Result<(Plan, FarField, LeftOut), TilesError> {
    options.validate()?;
    let header = tin::read_dem_header(source, &dem)?;
    let [kr, kc] = tile_grid([header.rows, header.cols], options.tile);
    if kr.saturating_mul(kc) > MAX_TILES {
        return Err(TilesError::Parameter(format!(
            "{}: {} x {} samples in tiles of {} x {} intervals are {kr} x {kc} tiles, more than the {MAX_TILES} a plan \
             holds: give a larger --tile",
            source.display(),
            header.cols,
            header.rows,
            options.tile,
            options.tile
        )));
    }
    let (rc, cc) = (cuts(header.rows, kr), cuts(header.cols, kc));
    let mut tiles = Vec::with_capacity(kr * kc);
    for tr in 0..kr {
        for tc in 0..kc {
            let index = tiles.len();
            tiles.push(TileSpec {
                index,
                tile_row: tr,
                tile_col: tc,
                rows: [rc[tr], rc[tr + 1]],
                cols: [cc[tc], cc[tc + 1]],
                part: None,
                far: far_name(&options, tiles_dir, index),
                window_digest: None,
                file_digest: None,
                extent: None,
                output: tiles_dir.join(format!("tile-{index:05}.tch")),
            });
        }
    }
    // Each tile's window digest, fed row by row as the strips come (windows of a tile row share their rows).
    let windows: Vec<_> = tiles
        .iter()
        .map(|t| halo_window(options.halo, [header.rows, header.cols], t))
        .collect();
    let row_windows: Vec<[usize; 2]> = (0..kr).map(|tr| windows[tr * kc].0).collect();
    let mut digests = vec![crc32fast::Hasher::new(); tiles.len()];
    let mut terrain = vec![TileTerrain::default(); tiles.len()];
    let mut progress = progress;
    let (field, grid) = FarField::read_each_strip(source, &dem, options.far_block, options.max_error, |first, z| {
        let cols = header.cols;
        for (k, row) in z.chunks_exact(cols).enumerate() {
            let r = first + k;
            // Tile rows whose windows hold row `r`: from the first whose window ends at or after it.
            let from = row_windows.partition_point(|w| w[1] < r);
            for tr in (from..kr).take_while(|&tr| row_windows[tr][0] <= r) {
                for i in tr * kc..(tr + 1) * kc {
                    let c = windows[i].1;
                    digest_samples(&mut digests[i], &row[c[0]..=c[1]]);
                    if (tiles[i].rows[0]..=tiles[i].rows[1]).contains(&r) {
                        let cols = tiles[i].cols;
                        terrain[i].add(r, cols[0], &row[cols[0]..=cols[1]]);
                    }
                }
            }
        }
        progress(first + z.len() / cols, header.rows);
    })?;
    if [grid.rows, grid.cols] != [header.rows, header.cols] {
        return Err(TilesError::Parameter(format!(
            "{}: read {} x {} samples, its header says {} x {}",
            source.display(),
            grid.rows,
            grid.cols,
            header.rows,
            header.cols
        )));
    }
    for (t, d) in tiles.iter_mut().zip(digests) {
        t.window_digest = Some(d.finalize());
    }
    // Tiles whose samples are voids, or too few to triangulate, hold no terrain: left out (their neighbours' halos
    // and the far field still see what lies around them), the others numbered anew.
    let mut left_out = LeftOut::default();
    for t in terrain.iter().filter(|t| !t.can_triangulate()) {
        if t.samples == 0 {
            left_out.void_tiles += 1;
        } else {
            left_out.line_tiles += 1;
            left_out.line_samples += t.samples;
        }
    }
    let mut kept: Vec<TileSpec> = tiles
        .into_iter()
        .zip(&terrain)
        .filter(|(_, t)| t.can_triangulate())
        .map(|(t, _)| t)
        .collect();
    if kept.is_empty() {
        return Err(TilesError::Parameter(format!(
            "{}: no tile has samples to triangulate (at least 3, not all on one line): the DEM is voids",
            source.display()
        )));
    }
    for (index, t) in kept.iter_mut().enumerate() {
        t.index = index;
        t.far = far_name(&options, tiles_dir, index);
        t.output = tiles_dir.join(format!("tile-{index:05}.tch"));
    }
    let tiles = kept;
    let plan = Plan {
        version: PLAN_VERSION,
        source: source.to_path_buf(),
        dem,
        grid: Some(GridInfo::of(&grid)),
        options,
        tiles,
        tiles_dir: tiles_dir.to_path_buf(),
    };
    Ok((plan, field, left_out))
}

/// The far-field file of a DEM's tile `index` in `tiles_dir`; none in a plan without regions.
fn far_name(options: &PlanOptions, tiles_dir: &Path, index: usize) -> Option<PathBuf> {
    (!options.no_regions).then(|| tiles_dir.join(format!("far-{index:05}.bin")))
}

/// Most squares a mesh's plan cuts its footprint into, for its tiles or for its far field's blocks.
pub const MAX_MESH_SQUARES: usize = 1 << 24;

/// Cuts a mesh into tiles of `options.tile` metres (see [`crate::part`]); returns the plan and each tile's part,
/// to be written to the tile's [`TileSpec::part`] beside the plan.
pub fn make_mesh_plan(
    tin: &tin::Tin,
    source: &Path,
    options: PlanOptions,
    tiles_dir: &Path,
) -> Result<(Plan, Vec<crate::part::MeshPart>), TilesError> {
    options.validate()?;
    // Both cuts keep a list per square in memory, the empty ones too: refused before they are made when too many
    // (a plan without regions makes no far field).
    let size = tin.bbox().size();
    let cuts = [
        ("tile side", "--tile", options.tile),
        ("far-field block", "--far-block", options.far_block),
    ];
    for &(what, flag, side) in &cuts[..if options.no_regions { 1 } else { 2 }] {
        let squares = (size.x / side as f64).ceil().max(1.0) * (size.y / side as f64).ceil().max(1.0);
        if squares > MAX_MESH_SQUARES as f64 {
            return Err(TilesError::Parameter(format!(
                "a {what} of {side} m cuts the mesh's {:.0} x {:.0} m into {squares} squares, more than \
                 {MAX_MESH_SQUARES}: give a larger {flag}",
                size.x, size.y
            )));
        }
    }
    let beyond = (!options.no_regions).then_some(crate::part::Beyond {
        halo: options.halo as f64,
        far_block: options.far_block as f64,
        far_ratio: options.far_ratio,
    });
    let parts = crate::part::mesh_parts(tin, options.tile as f64, beyond);
    let mut tiles = Vec::with_capacity(parts.len());
    let mut out = Vec::with_capacity(parts.len());
    for (index, (tile_row, tile_col, part)) in parts.into_iter().enumerate() {
        tiles.push(TileSpec {
            index,
            tile_row,
            tile_col,
            rows: [0, 0],
            cols: [0, 0],
            part: Some(tiles_dir.join(format!("part-{index:05}.bin"))),
            far: None,
            window_digest: None,
            file_digest: None,
            extent: Some(MeshExtent::of(&part)),
            output: tiles_dir.join(format!("tile-{index:05}.tch")),
        });
        out.push(part);
    }
    let plan = Plan {
        version: PLAN_VERSION,
        source: source.to_path_buf(),
        dem: DemOptions::default(),
        grid: None,
        options,
        tiles,
        tiles_dir: tiles_dir.to_path_buf(),
    };
    Ok((plan, out))
}

impl Plan {
    /// Reads and checks a plan file.
    pub fn load(path: &Path) -> Result<Plan, TilesError> {
        Plan::parse(crate::framed::read(path)?, path)
    }

    /// Checks and parses the content of a plan file; `path` names it in errors.
    pub fn parse(bytes: Vec<u8>, path: &Path) -> Result<Plan, TilesError> {
        let bad = |reason: String| TilesError::Plan {
            path: path.to_path_buf(),
            reason,
        };
        // A binary file (a hierarchy, a tile's far field, an image): said as such, not as bytes that are not UTF-8.
        let text = String::from_utf8(bytes)
            .map_err(|_| bad("a binary file, not the JSON text that `tincull tiles plan` writes".into()))?;
        // The version first: a plan of another version may not parse as this one.
        #[derive(Deserialize)]
        struct Versioned {
            version: u32,
            /// A plan's own keys (every version has one of them): another JSON with a version is not a plan.
            tiles: Option<serde::de::IgnoredAny>,
            far_field: Option<serde::de::IgnoredAny>,
        }
        let versioned: Versioned = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
        if versioned.version != PLAN_VERSION {
            if versioned.tiles.is_none() && versioned.far_field.is_none() {
                return Err(bad(format!(
                    "version {}, and neither tiles nor a far field",
                    versioned.version
                )));
            }
            // A tile plan all the same, of another version: not "not a tile plan".
            return Err(TilesError::Parameter(format!(
                "{}: a tile plan of version {}, made by another tincull; this one reads version {PLAN_VERSION}: plan \
                 again",
                path.display(),
                versioned.version
            )));
        }
        let plan: Plan = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
        plan.options.validate().map_err(|e| bad(e.to_string()))?;
        if plan.tiles.is_empty() {
            return Err(bad("it has no tiles".into()));
        }
        // A tile's place in the tile grid (the merge builds its quadtree of tiles over them): one tile a place, within
        // the 2^32 x 2^32 places of the merge's Morton order.
        let mut places = std::collections::HashSet::new();
        for (i, t) in plan.tiles.iter().enumerate() {
            if u32::try_from(t.tile_row).is_err() || u32::try_from(t.tile_col).is_err() {
                return Err(bad(format!(
                    "tile {i} is at row {}, column {} of the tile grid, beyond the 2^32 a side a plan can have",
                    t.tile_row, t.tile_col
                )));
            }
            if !places.insert((t.tile_row, t.tile_col)) {
                return Err(bad(format!(
                    "tile {i} is at row {}, column {} of the tile grid, as an earlier tile is",
                    t.tile_row, t.tile_col
                )));
            }
            let problem = if t.index != i {
                Some(format!("its index is {}", t.index))
            } else {
                match &plan.grid {
                    Some(_) if t.part.is_some() || t.far.is_none() != plan.options.no_regions => Some(
                        if plan.options.no_regions {
                            "a DEM's tile of a plan without regions has no far-field file and no part"
                        } else {
                            "a DEM's tile needs a far-field file and no part"
                        }
                        .to_string(),
                    ),
                    Some(_) if !(t.rows[0] < t.rows[1] && t.cols[0] < t.cols[1]) => Some(format!(
                        "its rows {:?} and columns {:?} are not increasing ranges",
                        t.rows, t.cols
                    )),
                    Some(g) if !(t.rows[1] < g.rows && t.cols[1] < g.cols) => Some(format!(
                        "its rows {:?} and columns {:?} reach beyond the grid of {} x {} samples",
                        t.rows, t.cols, g.rows, g.cols
                    )),
                    None if t.part.is_none() || t.far.is_some() => {
                        Some("a mesh's tile needs a part file and no far field".to_string())
                    }
                    _ => None,
                }
            };
            if let Some(problem) = problem {
                return Err(bad(format!("tile {i} is malformed: {problem}")));
            }
        }
        if !plan.seal_holds()? {
            return Err(TilesError::Parameter(format!(
                "{}: the plan's content does not match the names `tincull tiles plan` gave its tiles (edited since?), \
                 so tiles built under other options could be merged: plan again rather than editing a plan",
                path.display()
            )));
        }
        Ok(plan)
    }

    /// The plan as pretty JSON.
    pub fn to_json(&self) -> Result<String, TilesError> {
        serde_json::to_string_pretty(self).map_err(|e| TilesError::Parameter(format!("cannot write the plan: {e}")))
    }

    /// Names every tile's output after a digest (CRC-32) of the plan and of the far-field or part files written
    /// beside it (`files`: each one's [`file_digest`], in tile order): `tile-00007-1a2b3c4d.tch`. A tile built from an
    /// earlier plan written to the same place (another terrain, other options) then has another name, so
    /// [`crate::merge()`] never takes it for a tile of this plan: it says the tile has not been built. Deterministic:
    /// the same plan and files give the same names. (A DEM changed in place under the same name, with the same grid
    /// and far field, is not seen.)
    ///
    /// Each tile keeps its file's digest ([`TileSpec::file_digest`], when `files` has one a tile), so that
    /// [`Plan::parse`] can check the seal: a plan edited after it was made (its options, its tiles) no longer matches
    /// its names and is refused, rather than merging tiles built under two sets of options.
    pub fn seal(&mut self, files: &[u32]) -> Result<(), TilesError> {
        if files.len() == self.tiles.len() {
            for (t, &f) in self.tiles.iter_mut().zip(files) {
                t.file_digest = Some(f);
            }
        }
        let digest = self.seal_digest(files)?;
        for t in &mut self.tiles {
            t.output = self.tiles_dir.join(format!("tile-{:05}-{digest:08x}.tch", t.index));
        }
        Ok(())
    }

    /// The digest [`Plan::seal`] names the tiles after: of the plan with unsealed names, then of `files`.
    fn seal_digest(&self, files: &[u32]) -> Result<u32, TilesError> {
        let mut unsealed = self.clone();
        for t in &mut unsealed.tiles {
            t.output = unsealed.tiles_dir.join(format!("tile-{:05}.tch", t.index));
        }
        let mut hasher = crc32fast::Hasher::new();
        hasher.update(unsealed.to_json()?.as_bytes());
        for f in files {
            hasher.update(&f.to_le_bytes());
        }
        Ok(hasher.finalize())
    }

    /// Whether the tiles' names are still those [`Plan::seal`] gave this plan (checked when every tile keeps its
    /// file's digest; a plan made before they were kept passes).
    fn seal_holds(&self) -> Result<bool, TilesError> {
        let Some(files) = self.tiles.iter().map(|t| t.file_digest).collect::<Option<Vec<u32>>>() else {
            return Ok(true);
        };
        let digest = self.seal_digest(&files)?;
        Ok(self
            .tiles
            .iter()
            .all(|t| t.output == self.tiles_dir.join(format!("tile-{:05}-{digest:08x}.tch", t.index))))
    }

    /// Refuses tile `spec`'s far-field or part file `path` (its whole `bytes`, already decoded: a file cut short or
    /// damaged is named as such first) when its digest is not the plan's: another plan's or another tile's file in
    /// its place.
    pub(crate) fn check_tile_file(&self, spec: &TileSpec, path: &Path, bytes: &[u8]) -> Result<(), TilesError> {
        match spec.file_digest {
            Some(expected) if file_digest(bytes) != expected => Err(TilesError::Parameter(format!(
                "{}: not tile {}'s file as the plan wrote it (its digest differs: another plan's or another tile's \
                 file in its place?); plan again with `tincull tiles plan`",
                path.display(),
                spec.index
            ))),
            _ => Ok(()),
        }
    }

    /// A path of the plan (the source, a tile's output) resolved against the plan file's folder.
    pub fn resolve(plan_path: &Path, p: &Path) -> PathBuf {
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            plan_path.parent().unwrap_or(Path::new(".")).join(p)
        }
    }

    /// The halo window of a DEM's tile: its samples and `halo` more on every side, within the grid (rows, then
    /// columns, both ends inclusive).
    pub fn halo_window(&self, spec: &TileSpec) -> ([usize; 2], [usize; 2]) {
        let shape = self.grid.as_ref().map_or([0, 0], |g| [g.rows, g.cols]);
        halo_window(self.options.halo, shape, spec)
    }

    /// The far-field points of a DEM's tile: `field`'s cut outside its halo window ([`FarField::select`]).
    pub fn far_cut(&self, field: &FarField, spec: &TileSpec) -> Vec<FarPoint> {
        let (r, c) = self.halo_window(spec);
        let tile = [spec.rows[0], spec.rows[1], spec.cols[0], spec.cols[1]];
        field.select(tile, [r[0], r[1], c[0], c[1]], self.options.far_ratio)
    }

    /// The content of a DEM tile's far-field file ([`TileSpec::far`]): its [`Plan::far_cut`] of `field`, and how
    /// many points that is.
    pub fn far_file(&self, field: &FarField, spec: &TileSpec) -> Result<(Vec<u8>, usize), TilesError> {
        let points = self.far_cut(field, spec);
        Ok((far_to_bytes(&points)?, points.len()))
    }

    /// Reads a DEM tile's far-field points from its file (the plan at `plan_path` wrote it), checking that they are
    /// samples of the plan's grid.
    pub fn far_points(&self, plan_path: &Path, spec: &TileSpec) -> Result<Vec<FarPoint>, TilesError> {
        let (Some(grid), Some(far)) = (&self.grid, &spec.far) else {
            return Err(TilesError::Parameter(format!(
                "tile {} has no far-field file",
                spec.index
            )));
        };
        let path = Plan::resolve(plan_path, far);
        let bytes = crate::framed::read(&path)?;
        let points = far_from_bytes(&bytes, [grid.rows, grid.cols], &path)?;
        self.check_tile_file(spec, &path, &bytes)?;
        Ok(points)
    }

    /// Checks that a built hierarchy can be tile `index` of this plan, so that a file of another tile copied over
    /// this tile's output is refused, naming both:
    /// - for a DEM's plan, every vertex lies within the tile's samples (the corners by [`GridInfo::position`], the
    ///   formula every tile uses, so its own vertices are never outside);
    /// - for a mesh's plan, the tile has its part's counts of vertices and triangles, and every vertex lies within
    ///   the part's bounding box ([`TileSpec::extent`]; a plan without it is not checked).
    pub fn check_built_tile(&self, index: usize, built: &cull::Hierarchy) -> Result<(), TilesError> {
        let spec = self.tile(index)?;
        let not_this_tile = |what: String| {
            Err(TilesError::Parameter(format!(
                "tile {index} ({}): {what}: the file is not this tile's (another tile's copied over it?); build it \
                 again with `tincull tiles build PLAN --tile {index}`",
                spec.output.display(),
            )))
        };
        let (lo, hi, within) = match (&self.grid, &spec.extent) {
            (Some(grid), _) => {
                let nw = grid.position(spec.rows[0], spec.cols[0], 0.0);
                let se = grid.position(spec.rows[1], spec.cols[1], 0.0);
                let within = format!(
                    "the tile's samples (rows {} to {}, columns {} to {})",
                    spec.rows[0], spec.rows[1], spec.cols[0], spec.cols[1]
                );
                (
                    [nw[0].min(se[0]), nw[1].min(se[1])],
                    [nw[0].max(se[0]), nw[1].max(se[1])],
                    within,
                )
            }
            (None, Some(extent)) => {
                let (v, t) = (built.mesh.positions.len(), built.mesh.triangles.len());
                if (v, t) != (extent.vertices, extent.triangles) {
                    return not_this_tile(format!(
                        "it has {v} vertices and {t} triangles, its part {} and {}",
                        extent.vertices, extent.triangles
                    ));
                }
                let within = format!(
                    "the tile's part (x {} to {}, y {} to {})",
                    extent.min[0], extent.max[0], extent.min[1], extent.max[1]
                );
                (extent.min, extent.max, within)
            }
            (None, None) => return Ok(()),
        };
        let outside = built
            .mesh
            .positions
            .iter()
            .position(|p| !(p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] && p[1] <= hi[1]));
        match outside {
            None => Ok(()),
            Some(v) => {
                let p = built.mesh.positions[v];
                not_this_tile(format!("vertex {v} at x {}, y {} lies outside {within}", p[0], p[1]))
            }
        }
    }

    /// Tile `index`, or an error naming the range.
    pub fn tile(&self, index: usize) -> Result<&TileSpec, TilesError> {
        self.tiles.get(index).ok_or_else(|| {
            TilesError::Parameter(format!(
                "tile {index} does not exist: the plan has tiles 0 to {}",
                self.tiles.len().saturating_sub(1)
            ))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plan_of_another_version_asks_to_plan_again() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("plan.json");
        std::fs::write(
            &path,
            r#"{"version": 1, "far_field": [{"row": 0, "col": 0, "z": 1.0}]}"#,
        )
        .expect("write");
        let e = Plan::load(&path).expect_err("version 1").to_string();
        assert!(
            e.contains("a tile plan of version 1") && e.contains("reads version 3") && e.contains("plan again"),
            "{e}"
        );
        assert!(!e.contains("not a tincull tile plan"), "{e}");
        assert!(e.contains("plan.json"), "{e}");
        std::fs::write(&path, "[1, 2]").expect("write");
        assert!(Plan::load(&path).is_err());
    }

    #[test]
    fn cuts_share_their_ends_and_cover_the_grid() {
        assert_eq!(cuts(11, 2), vec![0, 5, 10]);
        assert_eq!(cuts(1201, 3), vec![0, 400, 800, 1200]);
        let c = cuts(1000, 7);
        assert_eq!((c[0], c[7]), (0, 999));
        assert!(c.windows(2).all(|w| w[1] > w[0] && w[1] - w[0] <= 143));
    }
}
