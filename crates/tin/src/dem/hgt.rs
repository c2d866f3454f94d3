//! SRTM `.hgt` tiles.
//!
//! A tile is a square of big-endian i16 heights (metres), 1201 x 1201 samples for 3 arc-seconds (SRTM3) or
//! 3601 x 3601 for 1 arc-second (SRTM1), row 0 north, column 0 west; neighbouring tiles share their edge rows and
//! columns. -32768 marks a void. The file name gives the south-west corner: `N43W123.hgt` covers 43°N–44°N,
//! 123°W–122°W. Any other file size is rejected, and so is a tile that reads as terrain only with its bytes swapped
//! (written little-endian).
//!
//! Metric frame (a local, tile-based choice, not a map projection):
//! - 1° of latitude is 111,320 m ([`METRES_PER_DEGREE`]), so `dy = 111320 / (n − 1)` m.
//! - 1° of longitude is `111,320 · cos(φc)` m with φc the latitude of the **tile centre** (south edge + 0.5°): the
//!   east-west spacing is exact at mid-tile and off by at most about ±0.9% (at 45°) at the northern and southern
//!   edges.
//! - x is metres east of the tile's **west edge** (column 0 at x = 0); y is metres north of the equator,
//!   `latitude · 111320` (the southern row at `south · 111320`). So y looks like a UTM northing (large coordinates,
//!   as real data sets have) while adjacent tiles do not share an x frame.
//!
//! [`DemOptions::spacing`] overrides both spacings; the southern row stays at `south · 111320`.

use std::path::Path;

use glam::DVec2;

use super::{DemOptions, GridShape, check_window, file_len, finish, open, read_at, read_bytes};
use crate::error::{Result, TinError};
use crate::grid::Grid;

/// Metres per degree of latitude (and of longitude at the equator).
pub const METRES_PER_DEGREE: f64 = 111_320.0;
/// The SRTM void value.
pub const VOID: i16 = -32768;

/// Position of a tile: its south-west corner in whole degrees (north and east positive).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileName {
    /// Latitude of the southern edge.
    pub lat: i32,
    /// Longitude of the western edge.
    pub lon: i32,
}

/// Parses a tile name such as `N43W123` (the first seven characters of the file name, any case).
pub fn parse_tile_name(file_name: &str) -> Option<TileName> {
    let s = file_name.as_bytes();
    if s.len() < 7 || !s[..7].is_ascii() {
        return None;
    }
    let digits = |b: &[u8]| -> Option<i32> {
        b.iter()
            .all(u8::is_ascii_digit)
            .then(|| std::str::from_utf8(b).ok()?.parse().ok())?
    };
    let lat = digits(&s[1..3])?;
    let lon = digits(&s[4..7])?;
    let lat = match s[0].to_ascii_uppercase() {
        b'N' => lat,
        b'S' => -lat,
        _ => return None,
    };
    let lon = match s[3].to_ascii_uppercase() {
        b'E' => lon,
        b'W' => -lon,
        _ => return None,
    };
    ((-90..90).contains(&lat) && (-180..180).contains(&lon)).then_some(TileName { lat, lon })
}

/// Reads an SRTM tile (see the module documentation).
pub fn read_hgt(path: &Path, opts: &DemOptions) -> Result<Grid> {
    opts.check_one_band(path, ".hgt")?;
    // A missing file is named as missing before its name is read for the tile.
    let bytes = read_bytes(path)?;
    let tile = tile_of(path)?;
    parse_hgt(&bytes, tile, path, opts)
}

/// The grid of an SRTM tile from its name and size, without reading its samples.
pub fn read_hgt_header(path: &Path, opts: &DemOptions) -> Result<GridShape> {
    opts.check_one_band(path, ".hgt")?;
    let file = open(path)?;
    let tile = tile_of(path)?;
    let len = file_len(&file, path)?;
    Ok(shape(side(len, path)?, tile, opts))
}

/// The samples of a window of an SRTM tile (voids NaN, not scaled) and its whole grid: each row's slice is read at
/// its offset.
pub(super) fn read_hgt_window(
    path: &Path,
    opts: &DemOptions,
    rows: [usize; 2],
    cols: [usize; 2],
) -> Result<(GridShape, Vec<f64>)> {
    let mut file = open(path)?;
    let tile = tile_of(path)?;
    let n = side(file_len(&file, path)?, path)?;
    let shape = shape(n, tile, opts);
    check_window(&shape, rows, cols, path)?;
    let nc = cols[1] - cols[0] + 1;
    let mut buf = vec![0u8; 2 * nc];
    let mut z = Vec::with_capacity((rows[1] - rows[0] + 1) * nc);
    for r in rows[0]..=rows[1] {
        read_at(&mut file, 2 * (r * n + cols[0]) as u64, &mut buf, path)?;
        z.extend(buf.chunks_exact(2).map(height));
    }
    check_byte_order(&z, nc, [rows[0], cols[0]], path)?;
    Ok((shape, z))
}

/// The tile's position from the file name.
fn tile_of(path: &Path) -> Result<TileName> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    parse_tile_name(&name).ok_or_else(|| {
        TinError::format(
            path,
            format!("cannot tell the tile's position from the name {name:?}: expected e.g. N43W123.hgt"),
        )
    })
}

/// The side (1201 or 3601 samples) of a tile of `len` bytes.
fn side(len: u64, path: &Path) -> Result<usize> {
    match len {
        2_884_802 => Ok(1201),
        25_934_402 => Ok(3601),
        len => Err(TinError::format(
            path,
            format!(
                "{len} bytes is not an SRTM tile: expected 2884802 (1201 x 1201, 3 arc-seconds) or 25934402 \
                 (3601 x 3601, 1 arc-second)"
            ),
        )),
    }
}

/// The grid of a tile of `n` x `n` samples at `tile` (see the module documentation).
fn shape(n: usize, tile: TileName, opts: &DemOptions) -> GridShape {
    let dy = METRES_PER_DEGREE / (n as f64 - 1.0);
    let centre_lat = (f64::from(tile.lat) + 0.5).to_radians();
    let spacing = opts.spacing.unwrap_or((dy * centre_lat.cos(), dy));
    let south = f64::from(tile.lat) * METRES_PER_DEGREE;
    let origin = DVec2::new(0.0, south + (n as f64 - 1.0) * spacing.1);
    GridShape {
        rows: n,
        cols: n,
        dx: spacing.0,
        dy: spacing.1,
        origin,
    }
}

/// The height of one big-endian sample (NaN for a void).
fn height(b: &[u8]) -> f64 {
    match i16::from_be_bytes([b[0], b[1]]) {
        VOID => f64::NAN,
        h => f64::from(h),
    }
}

/// Heights an SRTM sample can take (m): below the Dead Sea shore and above Everest there is no terrain on Earth.
const PLAUSIBLE: std::ops::RangeInclusive<f64> = -1000.0..=9000.0;

/// Refuses samples `z` (read big-endian, `cols` per row, the first at `row0`, `col0` of the tile) that look written
/// little-endian: more than 1% of the heights outside [`PLAUSIBLE`], but under 1% once their bytes are swapped. A tile
/// of real terrain read with the wrong byte order is mostly thousands of metres off, so this never refuses a sound
/// tile.
fn check_byte_order(z: &[f64], cols: usize, [row0, col0]: [usize; 2], path: &Path) -> Result<()> {
    let (mut valid, mut bad, mut bad_swapped, mut first_bad) = (0usize, 0usize, 0usize, None);
    for (k, &h) in z.iter().enumerate() {
        if h.is_nan() {
            continue;
        }
        valid += 1;
        if !PLAUSIBLE.contains(&h) {
            bad += 1;
            first_bad.get_or_insert((k, h));
        }
        // Every non-void sample is a whole i16.
        if !PLAUSIBLE.contains(&f64::from((h as i16).swap_bytes())) {
            bad_swapped += 1;
        }
    }
    match first_bad {
        Some((k, h)) if bad * 100 > valid && bad_swapped * 100 < valid => Err(TinError::format(
            path,
            format!(
                "{bad} of {valid} samples lie outside -1000..9000 m read big-endian, as SRTM tiles are written (row \
                 {}, column {}: {h} m); with their bytes swapped all but {bad_swapped} lie within: the file seems \
                 written little-endian (swap its byte pairs, e.g. `dd conv=swab`)",
                row0 + k / cols + 1,
                col0 + k % cols + 1
            ),
        )),
        _ => Ok(()),
    }
}

/// Parses the bytes of a tile at `tile`; `path` names it in errors.
pub fn parse_hgt(bytes: &[u8], tile: TileName, path: &Path, opts: &DemOptions) -> Result<Grid> {
    let n = side(bytes.len() as u64, path)?;
    let z: Vec<f64> = bytes.chunks_exact(2).map(height).collect();
    check_byte_order(&z, n, [0, 0], path)?;
    let s = shape(n, tile, opts);
    finish(path, n, n, (s.dx, s.dy), s.origin, z, opts)
}
