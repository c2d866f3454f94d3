//! ESRI ASCII grids (`.asc`).
//!
//! Header lines `key value` (keys in any case), then `nrows` rows of `ncols` numbers, row 0 north:
//! `ncols`, `nrows`; `xllcorner` or `xllcenter`; `yllcorner` or `yllcenter`; `cellsize`, or GDAL's `dx` and `dy` for
//! non-square cells; optional `NODATA_value`. The `…corner` keys give the lower-left corner of the lower-left *cell*,
//! so its sample (cell centre) lies half a cell further in; the `…center` keys give that sample directly. The grid
//! origin is the centre of the north-west sample: `x = xll + dx/2`, `y = yll + dy/2 + (nrows − 1)·dy` for corners.
//! Samples equal to `NODATA_value` (and NaN) become voids. Errors name the line.

use std::path::Path;

use glam::DVec2;

use super::{DemOptions, finish, read_bytes};
use crate::error::{Result, TinError};
use crate::grid::Grid;

/// Reads an ESRI ASCII grid (see the module documentation).
pub fn read_asc(path: &Path, opts: &DemOptions) -> Result<Grid> {
    opts.check()?;
    let bytes = read_bytes(path)?;
    parse_asc(&bytes, path, opts)
}

#[derive(Default)]
struct Header {
    ncols: Option<usize>,
    nrows: Option<usize>,
    xll: Option<(f64, bool)>,
    yll: Option<(f64, bool)>,
    cellsize: Option<f64>,
    dx: Option<f64>,
    dy: Option<f64>,
    nodata: Option<f64>,
}

/// Parses an ESRI ASCII grid held in memory; `path` names it in errors.
pub fn parse_asc(bytes: &[u8], path: &Path, opts: &DemOptions) -> Result<Grid> {
    let err = |m: String| TinError::format(path, m);
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
        err(format!("line {line}: not text (a binary or foreign file?)"))
    })?;
    let mut h = Header::default();
    let mut lines = text.lines().enumerate().peekable();
    // Header: lines whose first word is not a number.
    while let Some(&(i, line)) = lines.peek() {
        let mut words = line.split_whitespace();
        let Some(key) = words.next() else {
            lines.next();
            continue;
        };
        if key.parse::<f64>().is_ok() {
            break;
        }
        lines.next();
        let n = i + 1;
        let value = words
            .next()
            .ok_or_else(|| err(format!("line {n}: header key {key:?} has no value")))?;
        if words.next().is_some() {
            return Err(err(format!("line {n}: header line {line:?} has more than one value")));
        }
        let number = || -> Result<f64> {
            value
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| err(format!("line {n}: {key} = {value:?} is not a finite number")))
        };
        let count = || -> Result<usize> {
            value
                .parse::<usize>()
                .ok()
                .filter(|&v| v > 0)
                .ok_or_else(|| err(format!("line {n}: {key} = {value:?} is not a positive integer")))
        };
        let slot_taken = |taken: bool| -> Result<()> {
            if taken {
                Err(err(format!("line {n}: {key} given twice")))
            } else {
                Ok(())
            }
        };
        match key.to_ascii_lowercase().as_str() {
            "ncols" => {
                slot_taken(h.ncols.is_some())?;
                h.ncols = Some(count()?);
            }
            "nrows" => {
                slot_taken(h.nrows.is_some())?;
                h.nrows = Some(count()?);
            }
            k @ ("xllcorner" | "xllcenter") => {
                slot_taken(h.xll.is_some())?;
                h.xll = Some((number()?, k == "xllcorner"));
            }
            k @ ("yllcorner" | "yllcenter") => {
                slot_taken(h.yll.is_some())?;
                h.yll = Some((number()?, k == "yllcorner"));
            }
            "cellsize" => {
                slot_taken(h.cellsize.is_some())?;
                h.cellsize = Some(number()?);
            }
            "dx" => {
                slot_taken(h.dx.is_some())?;
                h.dx = Some(number()?);
            }
            "dy" => {
                slot_taken(h.dy.is_some())?;
                h.dy = Some(number()?);
            }
            "nodata_value" => {
                slot_taken(h.nodata.is_some())?;
                h.nodata = Some(number()?);
            }
            _ => {
                return Err(err(format!(
                    "line {n}: unknown header key {key:?} (not an ESRI ASCII grid?)"
                )));
            }
        }
    }
    let missing = |key: &str| err(format!("the header has no {key} (not an ESRI ASCII grid?)"));
    let cols = h.ncols.ok_or_else(|| missing("ncols"))?;
    let rows = h.nrows.ok_or_else(|| missing("nrows"))?;
    let (xll, x_corner) = h.xll.ok_or_else(|| missing("xllcorner or xllcenter"))?;
    let (yll, y_corner) = h.yll.ok_or_else(|| missing("yllcorner or yllcenter"))?;
    let header_spacing = match (h.cellsize, h.dx, h.dy) {
        (Some(c), None, None) => (c, c),
        (None, Some(dx), Some(dy)) => (dx, dy),
        (None, None, None) => return Err(missing("cellsize (or dx and dy)")),
        _ => {
            return Err(err("the header must give either cellsize or both dx and dy".into()));
        }
    };
    if !(header_spacing.0 > 0.0 && header_spacing.1 > 0.0) {
        return Err(err(format!(
            "cell size must be positive, got {} x {}",
            header_spacing.0, header_spacing.1
        )));
    }
    let (dx, dy) = opts.spacing.unwrap_or(header_spacing);
    let expected = rows
        .checked_mul(cols)
        .filter(|&n| n <= (1 << 31))
        .ok_or_else(|| err(format!("{rows} x {cols} samples is too many")))?;
    // Every value takes at least two bytes: never reserve more than the file can hold (a lying header must not
    // allocate gigabytes).
    let mut z = Vec::with_capacity(expected.min(bytes.len() / 2 + 1));
    for (i, line) in lines {
        for word in line.split_whitespace() {
            if z.len() == expected {
                return Err(err(format!(
                    "line {}: more than the {expected} values that nrows x ncols = {rows} x {cols} announce",
                    i + 1
                )));
            }
            let v: f64 = word.parse().map_err(|_| {
                err(format!(
                    "line {}: {word:?} is not a number (row {}, column {})",
                    i + 1,
                    z.len() / cols,
                    z.len() % cols
                ))
            })?;
            z.push(if h.nodata == Some(v) { f64::NAN } else { v });
        }
    }
    if z.len() < expected {
        return Err(err(format!(
            "truncated: {} values, but nrows x ncols = {rows} x {cols} = {expected}",
            z.len()
        )));
    }
    let x0 = if x_corner { xll + 0.5 * dx } else { xll };
    let y_south = if y_corner { yll + 0.5 * dy } else { yll };
    let origin = DVec2::new(x0, y_south + (rows as f64 - 1.0) * dy);
    finish(path, rows, cols, (dx, dy), origin, z, opts)
}
