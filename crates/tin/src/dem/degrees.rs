//! Rasters in degrees of latitude and longitude (a geographic CRS), put into metres the way `.hgt` tiles are
//! ([`super::hgt`]): a local frame, not a map projection.
//!
//! - 1° of latitude is [`METRES_PER_DEGREE`] m; 1° of longitude is that times `cos φc`, `φc` the latitude midway
//!   between the northern and southern sample rows (exact at mid-raster, off by under 1% within a few degrees of it).
//! - x is metres east of the western sample column (x = 0 there); y is `latitude · 111320`.
//! - A spacing given in degrees within 1e-9 (relative) of `1/n` is taken as exactly `1/n` (a GDAL-written
//!   `0.000833333333` is 3 arc-seconds), so neighbouring tiles land on one another's rows.
//!
//! [`DemOptions::spacing`] overrides both spacings; the southern row stays at `south · 111320`.

use glam::DVec2;

use super::hgt::METRES_PER_DEGREE;
use super::{DemOptions, GridShape};

/// Samples per degree for a spacing of `s` degrees: a whole number n when `s` is within 1e-9 (relative) of 1/n.
fn per_degree(s: f64) -> f64 {
    let n = (1.0 / s).round();
    if n >= 1.0 && ((1.0 / s) - n).abs() <= 1e-9 * n {
        n
    } else {
        1.0 / s
    }
}

/// The grid in metres of `rows` x `cols` samples whose north-west sample lies at `north`, `west` (degrees) with
/// spacings `spacing` (degrees east-west, north-south), and a sentence saying how degrees became metres; an error
/// message when the latitudes are not degrees or the raster reaches a pole.
pub(super) fn grid_in_metres(
    rows: usize,
    cols: usize,
    west: f64,
    north: f64,
    spacing: (f64, f64),
    opts: &DemOptions,
) -> Result<(GridShape, String), String> {
    let (per_deg_x, per_deg_y) = (per_degree(spacing.0), per_degree(spacing.1));
    let south = north - (rows as f64 - 1.0) / per_deg_y;
    if !(-90.0..=90.0).contains(&south) || !(-90.0..=90.0).contains(&north) {
        return Err(format!(
            "latitudes {south}..{north} are outside -90..90: the coordinates are not degrees"
        ));
    }
    let centre = 0.5 * (north + south);
    let dx = METRES_PER_DEGREE / per_deg_x * centre.to_radians().cos();
    if dx.is_nan() || dx <= 0.0 {
        return Err(format!("the raster reaches a pole (mid-latitude {centre})"));
    }
    let (dx, dy) = opts.spacing.unwrap_or((dx, METRES_PER_DEGREE / per_deg_y));
    let conversion = format!(
        "degrees to metres like .hgt: 1° latitude = 111320 m, 1° longitude = 111320·cos({centre:.6}°) = \
         {:.3} m; x from the western sample column ({west:.9}°), y = latitude·111320",
        METRES_PER_DEGREE * centre.to_radians().cos()
    );
    let origin = DVec2::new(0.0, south * METRES_PER_DEGREE + (rows as f64 - 1.0) * dy);
    Ok((
        GridShape {
            rows,
            cols,
            dx,
            dy,
            origin,
        },
        conversion,
    ))
}
