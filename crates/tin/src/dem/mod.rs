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

pub mod asc;
#[cfg(feature = "geotiff")]
pub mod geotiff;
pub mod hgt;
pub mod npy;
#[cfg(feature = "png")]
pub mod png;

use std::path::Path;

use glam::DVec2;

use crate::error::{Result, TinError};
use crate::grid::Grid;

/// How to read a DEM.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DemOptions {
    /// Sample spacing (east-west, north-south) in metres; overrides the file's or sidecar's spacing. Required for
    /// PNG, and for `.npy` without a sidecar.
    pub spacing: Option<(f64, f64)>,
    /// Factor applied to every stored value to get heights in metres (default 1).
    pub z_scale: f64,
    /// The elevation band (1-based) of a multi-band GeoTIFF; single-band files need none. Other formats ignore it.
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
                self.z_scale
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
}

/// Reads a DEM, choosing the reader from the extension (`.npy`, `.asc`, `.hgt`, `.png`, `.tif`/`.tiff`, any case).
pub fn read_dem(path: &Path, opts: &DemOptions) -> Result<Grid> {
    let grid = read_dem_unchecked(path, opts)?;
    check_range(&grid, path)?;
    Ok(grid)
}

/// Refuses a grid with a sample whose coordinates no stage can handle ([`crate::COORDINATE_LIMIT`]), naming the
/// file and the 1-based row and column (row 1 is the northern edge).
fn check_range(g: &Grid, path: &Path) -> Result<()> {
    let corners = [(0, 0), (g.rows.saturating_sub(1), g.cols.saturating_sub(1))];
    for (r, c) in corners {
        let (x, y) = (g.origin.x + c as f64 * g.dx, g.origin.y - r as f64 * g.dy);
        for (axis, v) in [("x", x), ("y", y)] {
            if !crate::predicates::coordinate_in_range(v) {
                return Err(TinError::format(
                    path,
                    format!(
                        "row {}, column {}: {axis} = {v:e} is outside the coordinates every stage accepts (0 or 2^-100 \
                         to 2^100 in magnitude)",
                        r + 1,
                        c + 1
                    ),
                ));
            }
        }
    }
    for (i, &z) in g.z.iter().enumerate() {
        if !z.is_nan() && !crate::predicates::coordinate_in_range(z) {
            return Err(TinError::format(
                path,
                format!(
                    "row {}, column {}: height {z:e} is outside the coordinates every stage accepts (0 or 2^-100 to \
                     2^100 in magnitude)",
                    i / g.cols.max(1) + 1,
                    i % g.cols.max(1) + 1
                ),
            ));
        }
    }
    Ok(())
}

fn read_dem_unchecked(path: &Path, opts: &DemOptions) -> Result<Grid> {
    opts.check()?;
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
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
        "tif" | "tiff" => geotiff::read_geotiff(path, opts),
        #[cfg(not(feature = "geotiff"))]
        "tif" | "tiff" => Err(TinError::format(
            path,
            "GeoTIFF rasters need the `geotiff` feature of the tin crate, which this build lacks",
        )),
        _ => Err(TinError::format(
            path,
            format!("unsupported DEM extension {ext:?}: expected .npy, .asc, .hgt, .png, .tif or .tiff"),
        )),
    }
}

/// Reads a whole file, naming it in the error.
fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| TinError::io(path, e))
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
    if opts.z_scale != 1.0 {
        for h in &mut z {
            *h *= opts.z_scale;
        }
    }
    Grid::new(rows, cols, dx, dy, origin, z).map_err(|e| match e {
        TinError::InvalidParameter(m) => TinError::format(path, m),
        e => e,
    })
}
