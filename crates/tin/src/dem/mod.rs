//! Reading regular elevation grids (DEMs) into a [`Grid`].
//!
//! The thesis builds its TINs from gridded DEMs (Edmondson 2004, section 6.1); this module reads the formats the
//! project's data comes in: NumPy `.npy` arrays with a JSON sidecar ([`npy`]), ESRI ASCII grids ([`asc`]), SRTM
//! `.hgt` tiles ([`hgt`]), 8/16-bit grayscale PNG height maps ([`png`]) and GeoTIFF rasters ([`geotiff`]).
//! [`read_dem`] picks the reader from the file extension.
//!
//! Conventions shared by all readers:
//! - [`Grid::origin`] is the **centre of the north-west sample**; row 0 is north, column 0 west.
//! - Heights are `value * z_scale` ([`DemOptions::z_scale`], default 1; it may be negative, e.g. to turn depths into
//!   heights, but not zero). Voids (nodata values, SRTM's -32768, NaN in float arrays) become NaN in the grid, never
//!   a height, and are not scaled.
//! - [`DemOptions::spacing`], when given, overrides whatever spacing the file or its sidecar states.
//! - Formats without a georeference (PNG, `.npy` whose sidecar has no easting/northing) put the **south-west sample at
//!   (0, 0)**, so all coordinates are non-negative.
//!
//! Windows: [`read_dem_header`] gives a DEM's [`GridShape`] without reading its samples, and [`read_dem_window`]
//! reads a rectangle of samples, exactly (bit for bit) what [`read_dem`] and cutting the rectangle out give, with
//! memory bounded by the window where the format allows it:
//! - `.npy` (C or Fortran order) and `.hgt`: the window's slice of each row (column) is read at its offset;
//! - `.asc`: the text is streamed, only the window's values are parsed and reading stops after its last row (values
//!   outside the window are not checked);
//! - GeoTIFF: only the strips or tiles that meet the window are decoded;
//! - PNG: one compressed stream, so the whole image is read and the window cut from it.
//!
//! [`read_dem_strips`] reads a whole DEM in strips of rows (windows where they are cheap), for work that needs every
//! sample once but not all at once (the far field of a tiled plan).

pub mod asc;
mod degrees;
#[cfg(feature = "geotiff")]
pub mod geotiff;
pub mod hgt;
pub mod npy;
#[cfg(feature = "png")]
pub mod png;
#[cfg(feature = "geotiff")]
pub mod tiff_mask;

use std::path::{Path, PathBuf};

use glam::DVec2;

use crate::error::{Result, TinError};
use crate::grid::Grid;

/// The most samples a compressed DEM (PNG, GeoTIFF) read whole, or a window of one, may have: 16384 x 16384, 2 GiB of
/// heights in f64. Its samples are decoded from data that may be far smaller than they are, so the count its header
/// claims is checked before the heights are allocated; larger DEMs are read in windows (`tincull tiles plan`).
pub const MAX_SAMPLES: u64 = 1 << 28;

/// Makes room in `z` for `more` values, growing its capacity with the values it holds (to twice as many, or what
/// `more` needs) but never past `total`: heights decoded from a compressed file take memory as the file's data gives
/// them, not as its header claims.
#[cfg(any(feature = "png", feature = "geotiff"))]
pub(crate) fn grow_with_data(z: &mut Vec<f64>, more: usize, total: usize) {
    if z.len() + more > z.capacity() {
        let room = (2 * z.len()).max(z.len() + more).min(total.max(z.len() + more));
        z.reserve_exact(room - z.len());
    }
}

/// How to read a DEM.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DemOptions {
    /// Sample spacing (east-west, north-south) in metres; overrides the file's or sidecar's spacing. Required for
    /// PNG, and for `.npy` without a sidecar.
    pub spacing: Option<(f64, f64)>,
    /// Factor applied to every stored value to get heights in metres (default 1).
    pub z_scale: f64,
    /// The elevation band (1-based) of a multi-band GeoTIFF; single-band files need none. Other formats have one band
    /// and refuse it.
    #[serde(default)]
    pub band: Option<u16>,
}

impl Default for DemOptions {
    fn default() -> Self {
        DemOptions {
            spacing: None,
            z_scale: 1.0,
            band: None,
        }
    }
}

impl DemOptions {
    fn check(&self) -> Result<()> {
        if !self.z_scale.is_finite() || self.z_scale == 0.0 {
            return Err(TinError::InvalidParameter(format!(
                "z scale must be finite and non-zero, got {}",
                crate::compact_number(self.z_scale)
            )));
        }
        if let Some((dx, dy)) = self.spacing
            && !(dx.is_finite() && dy.is_finite() && dx > 0.0 && dy > 0.0)
        {
            return Err(TinError::InvalidParameter(format!(
                "spacing must be positive and finite, got {dx} x {dy}"
            )));
        }
        Ok(())
    }

    /// [`DemOptions::check`] for a reader of a single-band format (`format`, as `.npy`), which refuses a band rather
    /// than ignoring it, naming the file.
    pub(crate) fn check_one_band(&self, path: &Path, format: &str) -> Result<()> {
        self.check()?;
        if let Some(b) = self.band {
            return Err(TinError::format(
                path,
                format!("--band {b}: a {format} grid has one band; a band is chosen in a multi-band GeoTIFF only"),
            ));
        }
        Ok(())
    }
}

/// Reads a DEM, choosing the reader from the extension (`.npy`, `.asc`, `.hgt`, `.png`, `.tif`/`.tiff`, any case).
pub fn read_dem(path: impl AsRef<Path>, opts: &DemOptions) -> Result<Grid> {
    let path = path.as_ref();
    let grid = read_dem_unchecked(path, opts)?;
    check_range(&grid, path, opts.z_scale)?;
    Ok(grid)
}

/// The size and placement of a DEM's grid, read without its samples ([`read_dem_header`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridShape {
    /// Number of rows (north to south).
    pub rows: usize,
    /// Number of columns (west to east).
    pub cols: usize,
    /// Sample spacing east-west (m).
    pub dx: f64,
    /// Sample spacing north-south (m).
    pub dy: f64,
    /// World x,y of sample (0, 0), the north-west corner: [`Grid::origin`] of the whole grid.
    pub origin: DVec2,
}

impl GridShape {
    /// The shape of `grid`.
    pub fn of(grid: &Grid) -> GridShape {
        GridShape {
            rows: grid.rows,
            cols: grid.cols,
            dx: grid.dx,
            dy: grid.dy,
            origin: grid.origin,
        }
    }

    /// The world x,y of sample `(row, col)` of the whole grid.
    fn at(&self, row: usize, col: usize) -> DVec2 {
        DVec2::new(
            self.origin.x + col as f64 * self.dx,
            self.origin.y - row as f64 * self.dy,
        )
    }

    /// The origin of the window whose north-west sample is `(row, col)`: the formula cutting a window out of a
    /// whole [`Grid`] uses, so a window read alone has the same origin bit for bit.
    pub fn window_origin(&self, row: usize, col: usize) -> DVec2 {
        self.origin + DVec2::new(col as f64 * self.dx, -(row as f64) * self.dy)
    }

    /// What [`Grid::new`] checks of the shape (at least 2 x 2 samples, positive finite spacing, finite origin),
    /// naming the file.
    fn check(&self, path: &Path) -> Result<()> {
        let (dx, dy, origin) = (self.dx, self.dy, self.origin);
        let problem = if self.rows < 2 || self.cols < 2 {
            format!("a grid needs at least 2 x 2 samples, got {} x {}", self.rows, self.cols)
        } else if !(dx.is_finite() && dy.is_finite() && dx > 0.0 && dy > 0.0) {
            format!("grid spacing must be positive and finite, got {dx}, {dy}")
        } else if !origin.is_finite() {
            format!("grid origin must be finite, got {origin}")
        } else {
            return Ok(());
        };
        Err(TinError::format(path, problem))
    }
}

/// Reads the size and placement of a DEM's grid ([`GridShape`]) without its samples: headers and sidecars only
/// (a PNG's header; a GeoTIFF's tags). The same conventions and [`DemOptions`] as [`read_dem`]; the coordinates of
/// the grid's corners are checked as [`read_dem`] checks them, its heights are not.
pub fn read_dem_header(path: &Path, opts: &DemOptions) -> Result<GridShape> {
    let shape = read_header_unchecked(path, opts)?;
    shape.check(path)?;
    check_corners(&shape, [0, shape.rows - 1], [0, shape.cols - 1], path)?;
    Ok(shape)
}

/// Reads the samples of rows `rows[0]..=rows[1]` and columns `cols[0]..=cols[1]` (0-based, inclusive; row 0 north)
/// of a DEM as a grid of their own, whose origin is the centre of the window's north-west sample
/// ([`GridShape::window_origin`]). The result is bit for bit what [`read_dem`] and cutting the window out give
/// (voids as NaN, [`DemOptions::z_scale`] applied alike), but only the window is read where the format allows it
/// (see the module documentation). The window's corners and heights are checked as [`read_dem`] checks a whole
/// grid, errors naming the 1-based row and column in the whole file; a window outside the grid, or of fewer than
/// 2 x 2 samples (see [`read_dem_window_heights`]), is refused.
pub fn read_dem_window(path: &Path, opts: &DemOptions, rows: [usize; 2], cols: [usize; 2]) -> Result<Grid> {
    let (shape, z) = read_dem_window_heights(path, opts, rows, cols)?;
    finish(
        path,
        rows[1] - rows[0] + 1,
        cols[1] - cols[0] + 1,
        (shape.dx, shape.dy),
        shape.window_origin(rows[0], cols[0]),
        z,
        &DemOptions { z_scale: 1.0, ..*opts },
    )
}

/// Like [`read_dem_window`], for any window of at least one sample: the whole grid's [`GridShape`] and the
/// window's heights in row-major order (voids as NaN, scaled by [`DemOptions::z_scale`]).
pub fn read_dem_window_heights(
    path: &Path,
    opts: &DemOptions,
    rows: [usize; 2],
    cols: [usize; 2],
) -> Result<(GridShape, Vec<f64>)> {
    opts.check()?;
    let (shape, mut z) = read_window_unchecked(path, opts, rows, cols)?;
    finish_window(&shape, rows, cols, &mut z, path, opts)?;
    Ok((shape, z))
}

/// Scales a window's heights read unchecked and checks its corners and heights, as [`read_dem`] checks a grid.
fn finish_window(
    shape: &GridShape,
    rows: [usize; 2],
    cols: [usize; 2],
    z: &mut [f64],
    path: &Path,
    opts: &DemOptions,
) -> Result<()> {
    scale(z, opts);
    check_corners(shape, rows, cols, path)?;
    check_heights(z, rows[0], cols, path, opts.z_scale)
}

/// Reads a whole DEM strip by strip, north to south, calling `each(first_row, heights)` with the row-major samples of
/// `strip_rows` (at least 1) consecutive rows (fewer in the last strip), all columns, exactly as [`read_dem`] reads
/// them (voids NaN, [`DemOptions::z_scale`] applied, every height checked); returns the grid's shape. Memory: one
/// strip for `.npy` and `.hgt` (each strip a window, [`read_dem_window_heights`]), `.asc` (the text streamed once)
/// and PNG (the rows decoded once, in order; an interlaced PNG is decoded whole); for GeoTIFF, a strip and the band of
/// the file's strips or tiles that it meets, each decoded once however many strips of rows it holds.
pub fn read_dem_strips(
    path: &Path,
    opts: &DemOptions,
    strip_rows: usize,
    mut each: impl FnMut(usize, &[f64]) -> Result<()>,
) -> Result<GridShape> {
    let strip_rows = strip_rows.max(1);
    match extension(path)?.as_str() {
        ext @ ("png" | "asc") => {
            let shape = read_dem_header(path, opts)?;
            let mut checked = |first: usize, z: &mut Vec<f64>| {
                scale(z, opts);
                check_heights(z, first, [0, shape.cols - 1], path, opts.z_scale)?;
                each(first, z)
            };
            match ext {
                #[cfg(feature = "png")]
                "png" => png::read_png_strips(path, opts, strip_rows, &mut checked)?,
                _ => asc::read_asc_strips(path, &shape, opts, strip_rows, &mut checked)?,
            }
            Ok(shape)
        }
        #[cfg(feature = "geotiff")]
        "tif" | "tiff" => {
            // Opened once: a strip or tile taller than a strip of rows is decoded once, not once a strip.
            opts.check()?;
            let shape = read_dem_header(path, opts)?;
            let mut reader = geotiff::WindowReader::open(path, opts)?;
            for first in (0..shape.rows).step_by(strip_rows) {
                let (rows, cols) = ([first, (first + strip_rows).min(shape.rows) - 1], [0, shape.cols - 1]);
                let mut z = reader.read(rows, cols)?;
                finish_window(&shape, rows, cols, &mut z, path, opts)?;
                each(first, &z)?;
            }
            Ok(shape)
        }
        _ => {
            let shape = read_dem_header(path, opts)?;
            for first in (0..shape.rows).step_by(strip_rows) {
                let last = (first + strip_rows).min(shape.rows) - 1;
                let (_, z) = read_dem_window_heights(path, opts, [first, last], [0, shape.cols - 1])?;
                each(first, &z)?;
            }
            Ok(shape)
        }
    }
}

/// Refuses a window that is empty or not inside the grid of `shape`, naming the file.
fn check_window(shape: &GridShape, rows: [usize; 2], cols: [usize; 2], path: &Path) -> Result<()> {
    shape.check(path)?;
    if rows[0] > rows[1] || cols[0] > cols[1] || rows[1] >= shape.rows || cols[1] >= shape.cols {
        return Err(TinError::InvalidParameter(format!(
            "{}: the window of rows {}..={} and columns {}..={} (0-based) is not inside its grid of {} x {} samples",
            path.display(),
            rows[0],
            rows[1],
            cols[0],
            cols[1],
            shape.rows,
            shape.cols
        )));
    }
    Ok(())
}

/// The header of a DEM, not yet checked.
fn read_header_unchecked(path: &Path, opts: &DemOptions) -> Result<GridShape> {
    opts.check()?;
    match extension(path)?.as_str() {
        "npy" => npy::read_npy_header(path, opts),
        "asc" => asc::read_asc_header(path, opts),
        "hgt" => hgt::read_hgt_header(path, opts),
        #[cfg(feature = "png")]
        "png" => png::read_png_header(path, opts),
        #[cfg(feature = "geotiff")]
        "tif" | "tiff" => geotiff::read_geotiff_header(path, opts),
        _ => read_dem_unchecked(path, opts).map(|g| GridShape::of(&g)),
    }
}

/// A window of a DEM (unscaled heights, voids NaN) and the whole grid's shape, the window checked against it.
fn read_window_unchecked(
    path: &Path,
    opts: &DemOptions,
    rows: [usize; 2],
    cols: [usize; 2],
) -> Result<(GridShape, Vec<f64>)> {
    let ext = extension(path)?;
    let whole = |grid: Grid| -> Result<(GridShape, Vec<f64>)> {
        let shape = GridShape::of(&grid);
        check_window(&shape, rows, cols, path)?;
        Ok((shape, cut(&grid.z, grid.cols, rows, cols)))
    };
    let unscaled = DemOptions { z_scale: 1.0, ..*opts };
    match ext.as_str() {
        "npy" => npy::read_npy_window(path, opts, rows, cols),
        "asc" => asc::read_asc_window(path, opts, rows, cols),
        "hgt" => hgt::read_hgt_window(path, opts, rows, cols),
        #[cfg(feature = "geotiff")]
        "tif" | "tiff" => geotiff::read_geotiff_window(path, opts, rows, cols),
        _ => whole(read_dem_unchecked(path, &unscaled)?),
    }
}

/// The row-major samples of rows `rows[0]..=rows[1]`, columns `cols[0]..=cols[1]` of a row-major array of `width`
/// columns.
fn cut(z: &[f64], width: usize, rows: [usize; 2], cols: [usize; 2]) -> Vec<f64> {
    let mut out = Vec::with_capacity((rows[1] - rows[0] + 1) * (cols[1] - cols[0] + 1));
    for r in rows[0]..=rows[1] {
        out.extend_from_slice(&z[r * width + cols[0]..=r * width + cols[1]]);
    }
    out
}

/// The files beside the DEM `path` that its reader may read too (whether or not they exist): a `.npy` grid's JSON
/// sidecar, an `.asc` grid's `.prj` (either case), a GeoTIFF's GDAL mask (`.tif.msk`). A command that reads the DEM
/// must not write over them.
pub fn companion_files(path: &Path) -> Vec<PathBuf> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "npy" => vec![npy::sidecar_path(path)],
        "asc" => asc::prj_candidates(path).to_vec(),
        "tif" | "tiff" => vec![gdal_mask_path(path)],
        _ => Vec::new(),
    }
}

/// The external nodata mask file GDAL would read beside the GeoTIFF `path` (`dem.tif.msk`).
pub(crate) fn gdal_mask_path(path: &Path) -> PathBuf {
    PathBuf::from(format!("{}.msk", path.display()))
}

/// The lower-case extension of `path`, or the error for a file without one the readers know.
fn extension(path: &Path) -> Result<String> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "npy" | "asc" | "hgt" | "png" | "tif" | "tiff" => Ok(ext),
        _ => Err(unsupported(path, &ext)),
    }
}

/// The error for a DEM named with an extension no reader takes, saying what its first bytes look like when they tell
/// (a pipe such as `<(cat x.tif)` has no extension).
fn unsupported(path: &Path, ext: &str) -> TinError {
    let hint = crate::sniff::head_of(path)
        .and_then(|head| crate::sniff::sniff(&head))
        .map(|f| format!("; {}", f.as_dem_hint()))
        .unwrap_or_default();
    TinError::format(
        path,
        format!("unsupported DEM extension {ext:?}: expected .npy, .asc, .hgt, .png, .tif or .tiff{hint}"),
    )
}

/// Refuses a window (or a whole grid) whose corner samples have coordinates no stage can handle, naming the file
/// and the corner's 1-based row and column in the whole grid; and one whose spacing is too fine for the magnitude of
/// its coordinates, where neighbouring samples could get the same coordinate in f64.
///
/// *The spacing bound.* A sample's x is computed as `fl(x₀ + fl(c · dx))` (`x₀` the grid's origin), within
/// `ε (|c · dx| + |x₀ + c · dx|)` of the exact `x₀ + c · dx` (`ε = 2⁻⁵²`, two roundings of at most `ε/2` each, the
/// second of a sum at most `|x₀| + |c · dx|` in magnitude). With `|c · dx| ≤ |x₀| + |x|` (`x` the exact coordinate, at
/// most the larger of the window's corners' in magnitude, up to the same rounding), the error is below
/// `2 ε (|x₀| + M)` where `M` bounds the corners' magnitudes; neighbouring samples, `dx` apart exactly, keep distinct
/// and ordered coordinates when `dx` exceeds twice that, `4 ε (|x₀| + M)`. The check asks for
/// `8 ε (|x₀| + |x_a| + |x_b|)` (`x_a`, `x_b` the corners), twice as much: below a nanometre for coordinates of 10⁶ m.
fn check_corners(shape: &GridShape, rows: [usize; 2], cols: [usize; 2], path: &Path) -> Result<()> {
    for (r, c) in [(rows[0], cols[0]), (rows[1], cols[1])] {
        let p = shape.at(r, c);
        for (axis, v) in [("x", p.x), ("y", p.y)] {
            if !crate::predicates::coordinate_in_range(v) {
                return Err(TinError::format(
                    path,
                    format!(
                        "row {}, column {} (1-based, row 1 north): {axis} = {v:e} is outside the coordinates every stage \
                         accepts (0 or 2^-100 to 2^100 in magnitude)",
                        r + 1,
                        c + 1
                    ),
                ));
            }
        }
    }
    let (a, b) = (shape.at(rows[0], cols[0]), shape.at(rows[1], cols[1]));
    for (axis, step, at) in [
        ("x", shape.dx, [shape.origin.x, a.x, b.x]),
        ("y", shape.dy, [shape.origin.y, a.y, b.y]),
    ] {
        // All finite: the corners were checked above, the spacing and the origin by the shape's own check.
        let magnitude: f64 = at.iter().map(|v| v.abs()).sum();
        if step <= 8.0 * f64::EPSILON * magnitude {
            return Err(TinError::format(
                path,
                format!(
                    "the {axis} spacing {step:e} m is too fine for coordinates near {:e} m: neighbouring samples could \
                     get the same {axis} in f64 (the spacing must exceed 2^-49 times the summed magnitudes of the \
                     origin's and the corners' coordinates)",
                    at.iter().fold(0.0f64, |m, v| m.max(v.abs()))
                ),
            ));
        }
    }
    Ok(())
}

/// Refuses heights no stage can handle in the window whose north-west sample is in row `row0` and whose columns
/// are `cols` of the whole grid, naming the file and the 1-based row and column in the whole grid.
fn check_heights(z: &[f64], row0: usize, cols: [usize; 2], path: &Path, z_scale: f64) -> Result<()> {
    let width = cols[1] - cols[0] + 1;
    for (i, &h) in z.iter().enumerate() {
        if !h.is_nan() && !crate::predicates::coordinate_in_range(h) {
            return Err(TinError::format(
                path,
                format!(
                    "row {}, column {} (1-based, row 1 north): height {h:e}{} is outside the coordinates every stage \
                     accepts (0 or 2^-100 to 2^100 in magnitude)",
                    row0 + i / width + 1,
                    cols[0] + i % width + 1,
                    scaled_note(z_scale)
                ),
            ));
        }
    }
    Ok(())
}

/// Refuses a grid with a sample whose coordinates no stage can handle ([`crate::COORDINATE_LIMIT`]), naming the
/// file and the 1-based row and column (row 1 is the northern edge).
pub(crate) fn check_range(g: &Grid, path: &Path, z_scale: f64) -> Result<()> {
    let (rows, cols) = ([0, g.rows.saturating_sub(1)], [0, g.cols.saturating_sub(1)]);
    check_corners(&GridShape::of(g), rows, cols, path)?;
    check_heights(&g.z, 0, cols, path, z_scale)
}

fn read_dem_unchecked(path: &Path, opts: &DemOptions) -> Result<Grid> {
    opts.check()?;
    match extension(path)?.as_str() {
        "npy" => npy::read_npy(path, opts),
        "asc" => asc::read_asc(path, opts),
        "hgt" => hgt::read_hgt(path, opts),
        #[cfg(feature = "png")]
        "png" => png::read_png(path, opts),
        #[cfg(not(feature = "png"))]
        "png" => Err(TinError::format(
            path,
            "PNG height maps need the `png` feature of the tin crate, which this build lacks",
        )),
        #[cfg(feature = "geotiff")]
        "tif" | "tiff" => geotiff::read_geotiff_unchecked(path, opts).map(|(grid, _)| grid),
        #[cfg(not(feature = "geotiff"))]
        "tif" | "tiff" => Err(TinError::format(
            path,
            "GeoTIFF rasters need the `geotiff` feature of the tin crate, which this build lacks",
        )),
        ext => Err(unsupported(path, ext)),
    }
}

/// Reads a whole file, naming it in the error.
fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    infile::read(path).map_err(|e| TinError::io(path, e))
}

/// Scales the heights (voids stay NaN) and builds the grid, naming the file in any error.
fn finish(
    path: &Path,
    rows: usize,
    cols: usize,
    (dx, dy): (f64, f64),
    origin: DVec2,
    mut z: Vec<f64>,
    opts: &DemOptions,
) -> Result<Grid> {
    scale(&mut z, opts);
    Grid::new(rows, cols, dx, dy, origin, z).map_err(|e| match e {
        TinError::InvalidParameter(m) if m.ends_with("the height is infinite") => {
            TinError::format(path, format!("{m}{}", scaled_note(opts.z_scale)))
        }
        TinError::InvalidParameter(m) => TinError::format(path, m),
        e => e,
    })
}

/// What a height error adds when the heights were scaled: that the height is the stored value times the z scale
/// (a large scale can carry a stored value out of range).
fn scaled_note(z_scale: f64) -> String {
    if z_scale == 1.0 {
        String::new()
    } else {
        format!(
            " (the stored value times the z scale {})",
            crate::compact_number(z_scale)
        )
    }
}

/// Multiplies the heights by [`DemOptions::z_scale`] (voids stay NaN).
fn scale(z: &mut [f64], opts: &DemOptions) {
    if opts.z_scale != 1.0 {
        for h in z {
            *h *= opts.z_scale;
        }
    }
}

/// [`open`] (a regular file), with its length in bytes.
#[cfg(any(feature = "png", feature = "geotiff"))]
fn open_with_len(path: &Path) -> Result<(std::fs::File, u64)> {
    let file = open(path)?;
    let len = file.metadata().map_err(|e| TinError::io(path, e))?.len();
    Ok((file, len))
}

/// Opens a file, naming it in the error. The readers that open a DEM (headers, windows, strips) read it at offsets,
/// so a pipe is refused here with an error saying so, rather than read as an empty file or waited on (a named pipe
/// read whole is read by [`infile::read`] instead, where a whole grid is wanted).
fn open(path: &Path) -> Result<std::fs::File> {
    let file = infile::open(path).map_err(|e| TinError::io(path, e))?;
    let kind = file.metadata().map_err(|e| TinError::io(path, e))?.file_type();
    match infile::non_regular(&kind) {
        None => Ok(file),
        Some(what) => Err(TinError::io(
            path,
            std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!("{what}: this DEM reader reads at offsets, from a regular file"),
            ),
        )),
    }
}

/// The length of an open file, naming it in the error.
fn file_len(file: &std::fs::File, path: &Path) -> Result<u64> {
    Ok(file.metadata().map_err(|e| TinError::io(path, e))?.len())
}

/// Reads `buf.len()` bytes at `offset`, naming the file in the error (a file cut short is an error, not a panic).
fn read_at(file: &mut std::fs::File, offset: u64, buf: &mut [u8], path: &Path) -> Result<()> {
    use std::io::{Read, Seek, SeekFrom};
    file.seek(SeekFrom::Start(offset))
        .and_then(|_| file.read_exact(buf))
        .map_err(|e| {
            TinError::format(
                path,
                format!("cannot read {} bytes at byte {offset} (truncated?): {e}", buf.len()),
            )
        })
}
