//! NumPy `.npy` arrays (format versions 1, 2 and 3) with a JSON sidecar.
//!
//! The header is parsed here (it is a small Python dict literal: `descr`, `fortran_order`, `shape`). Supported
//! element types: signed and unsigned 8/16/32/64-bit integers and 32/64-bit floats, either byte order. Both C order
//! and Fortran order are read (NumPy semantics: element `(r, c)` of a Fortran-ordered array is stored at
//! `c * rows + r`). The array must be 2-D; row 0 is the northern edge.
//!
//! Sidecar: `NAME.json` next to `NAME.npy`, as written for the project's data sets:
//! `spacing_x_m`, `spacing_y_m` (metres), optional `nodata` (null or a number: samples equal to it become voids),
//! optional `rows`/`cols` (checked against the array), optional `easting_min` and `northing_max` (or `northing_min`)
//! giving the world position of the western column and northern (southern) row of sample centres (both northings
//! must agree with the rows and the sidecar's y spacing, to 1% of a row). Other keys are ignored.
//! [`DemOptions::spacing`] wins over the sidecar's spacing; with neither, reading fails. Without an easting the western
//! column is at x = 0, without a northing the southern row at y = 0.

use std::path::{Path, PathBuf};

use glam::DVec2;

use super::{DemOptions, GridShape, check_window, file_len, finish, open, read_at, read_bytes};
use crate::error::{Result, TinError};
use crate::grid::Grid;

/// A 2-D array read from a `.npy` file, converted to f64 in row-major (C) order.
#[derive(Clone, Debug, PartialEq)]
pub struct NpyArray {
    /// Number of rows (first dimension).
    pub rows: usize,
    /// Number of columns (second dimension).
    pub cols: usize,
    /// The `descr` of the file, e.g. `<i2`.
    pub descr: String,
    /// Values, row-major.
    pub values: Vec<f64>,
}

/// What the JSON sidecar says.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sidecar {
    /// `spacing_x_m`, `spacing_y_m`.
    pub spacing: Option<(f64, f64)>,
    /// `nodata`.
    pub nodata: Option<f64>,
    /// `rows`.
    pub rows: Option<usize>,
    /// `cols`.
    pub cols: Option<usize>,
    /// `easting_min`.
    pub easting_min: Option<f64>,
    /// `northing_max`.
    pub northing_max: Option<f64>,
    /// `northing_min`.
    pub northing_min: Option<f64>,
}

/// Reads a `.npy` DEM and its sidecar (see the module documentation).
pub fn read_npy(path: &Path, opts: &DemOptions) -> Result<Grid> {
    opts.check_one_band(path, ".npy")?;
    let bytes = read_bytes(path)?;
    let array = parse_npy(&bytes, path)?;
    let (shape, nodata) = placement(path, array.rows, array.cols, opts)?;
    let mut z = array.values;
    void_nodata(&mut z, nodata, &array.descr);
    finish(
        path,
        shape.rows,
        shape.cols,
        (shape.dx, shape.dy),
        shape.origin,
        z,
        opts,
    )
}

/// The grid of a `.npy` DEM: its header and sidecar, without its samples (the file's length is checked against
/// the header).
pub fn read_npy_header(path: &Path, opts: &DemOptions) -> Result<GridShape> {
    opts.check_one_band(path, ".npy")?;
    let mut file = open(path)?;
    let layout = read_layout(&mut file, path)?;
    Ok(placement(path, layout.rows, layout.cols, opts)?.0)
}

/// The samples of a window of a `.npy` DEM (voids NaN, not scaled) and its whole grid: each row's slice of a
/// C-ordered array (each column's slice of a Fortran-ordered one) is read at its offset.
pub(super) fn read_npy_window(
    path: &Path,
    opts: &DemOptions,
    rows: [usize; 2],
    cols: [usize; 2],
) -> Result<(GridShape, Vec<f64>)> {
    let mut file = open(path)?;
    let layout = read_layout(&mut file, path)?;
    let (shape, nodata) = placement(path, layout.rows, layout.cols, opts)?;
    check_window(&shape, rows, cols, path)?;
    let (nr, nc) = (rows[1] - rows[0] + 1, cols[1] - cols[0] + 1);
    let size = layout.size;
    let mut z = vec![0.0; nr * nc];
    let offset = |k: usize| (layout.data_start + k * size) as u64;
    if layout.fortran {
        let mut buf = vec![0u8; nr * size];
        for c in 0..nc {
            read_at(&mut file, offset((cols[0] + c) * layout.rows + rows[0]), &mut buf, path)?;
            for (r, b) in buf.chunks_exact(size).enumerate() {
                z[r * nc + c] = layout.element(b);
            }
        }
    } else {
        let mut buf = vec![0u8; nc * size];
        for r in 0..nr {
            read_at(&mut file, offset((rows[0] + r) * layout.cols + cols[0]), &mut buf, path)?;
            for (h, b) in z[r * nc..(r + 1) * nc].iter_mut().zip(buf.chunks_exact(size)) {
                *h = layout.element(b);
            }
        }
    }
    void_nodata(&mut z, nodata, &layout.descr);
    Ok((shape, z))
}

/// Reads the header of an open `.npy` file and checks the file's length against it.
fn read_layout(file: &mut std::fs::File, path: &Path) -> Result<Layout> {
    let len = file_len(file, path)?;
    let mut prefix = vec![0u8; len.min(12) as usize];
    read_at(file, 0, &mut prefix, path)?;
    let start = if prefix.get(6).is_some_and(|&v| v >= 2) { 12 } else { 10 };
    let header_len = match prefix.len() {
        12 if start == 12 => u32::from_le_bytes([prefix[8], prefix[9], prefix[10], prefix[11]]) as u64,
        n if n >= 10 => u64::from(u16::from_le_bytes([prefix[8], prefix[9]])),
        _ => 0,
    };
    let want = (start + header_len).min(len);
    let mut head = vec![0u8; want as usize];
    read_at(file, 0, &mut head, path)?;
    let layout = parse_layout(&head, path)?;
    layout.check_data_len(len.saturating_sub(layout.data_start as u64), path)?;
    Ok(layout)
}

/// The whole grid's shape from the sidecar (when there is one) and the options, and the nodata value.
fn placement(path: &Path, rows: usize, cols: usize, opts: &DemOptions) -> Result<(GridShape, Option<f64>)> {
    let sidecar_path = sidecar_path(path);
    let sidecar = if sidecar_path.exists() {
        Some(read_sidecar(&sidecar_path)?)
    } else {
        None
    };
    let side = sidecar.clone().unwrap_or_default();
    if let Some(r) = side.rows
        && r != rows
    {
        return Err(TinError::format(
            &sidecar_path,
            format!("rows = {r}, but the array has {rows} rows"),
        ));
    }
    if let Some(c) = side.cols
        && c != cols
    {
        return Err(TinError::format(
            &sidecar_path,
            format!("cols = {c}, but the array has {cols} columns"),
        ));
    }
    let spacing = opts.spacing.or(side.spacing).ok_or_else(|| {
        TinError::format(
            path,
            if sidecar.is_some() {
                format!(
                    "no grid spacing: the sidecar {} has no spacing_x_m/spacing_y_m and none was given",
                    sidecar_path.display()
                )
            } else {
                format!(
                    "no grid spacing: put a JSON sidecar {} with spacing_x_m and spacing_y_m (metres) next to it, or give `--spacing dx,dy` (metres)",
                    sidecar_path.display()
                )
            },
        )
    })?;
    let span = (rows as f64 - 1.0) * spacing.1;
    // Both northings are checked against the sidecar's own spacing when it has one (a `--spacing` given to correct
    // it moves the southern row, not the northern one).
    let dy = side.spacing.map_or(spacing.1, |s| s.1);
    if let (Some(n), Some(s)) = (side.northing_max, side.northing_min)
        && (n - s - (rows as f64 - 1.0) * dy).abs() > 0.01 * dy + 1e-9 * (n.abs() + s.abs())
    {
        return Err(TinError::format(
            &sidecar_path,
            format!(
                "northing_max {n} and northing_min {s} are {} m apart, but {rows} rows at a spacing of {dy} m span {} m",
                n - s,
                (rows as f64 - 1.0) * dy
            ),
        ));
    }
    let north = side.northing_max.or_else(|| side.northing_min.map(|s| s + span));
    let origin = DVec2::new(side.easting_min.unwrap_or(0.0), north.unwrap_or(span));
    let shape = GridShape {
        rows,
        cols,
        dx: spacing.0,
        dy: spacing.1,
        origin,
    };
    Ok((shape, side.nodata))
}

/// Turns samples equal to the nodata value into voids; in a float32 array (`descr` `f4`), also samples equal to the
/// nodata value rounded to float32 (a sidecar's `0.1` is the float32 sample `0.1f32`), as for GeoTIFFs.
fn void_nodata(z: &mut [f64], nodata: Option<f64>, descr: &str) {
    if let Some(nodata) = nodata {
        let single = if descr.ends_with("f4") {
            f64::from(nodata as f32)
        } else {
            nodata
        };
        for h in z {
            if *h == nodata || *h == single {
                *h = f64::NAN;
            }
        }
    }
}

/// Writes `grid` as a `.npy` of little-endian f64 heights in row-major order (voids as NaN), format version 1.0.
pub fn write_npy_to(grid: &Grid, w: &mut dyn std::io::Write) -> std::io::Result<()> {
    let dict = format!(
        "{{'descr': '<f8', 'fortran_order': False, 'shape': ({}, {}), }}",
        grid.rows, grid.cols
    );
    // Magic (6) + version (2) + length (2) + header, padded with spaces to a multiple of 64 and ending in '\n'.
    let len = (10 + dict.len() + 1).div_ceil(64) * 64 - 10;
    let mut header = dict.into_bytes();
    header.resize(len - 1, b' ');
    header.push(b'\n');
    w.write_all(b"\x93NUMPY\x01\x00")?;
    w.write_all(&(len as u16).to_le_bytes())?;
    w.write_all(&header)?;
    let mut buf = Vec::with_capacity(8 * grid.cols);
    for row in grid.z.chunks(grid.cols.max(1)) {
        buf.clear();
        for z in row {
            buf.extend_from_slice(&z.to_le_bytes());
        }
        w.write_all(&buf)?;
    }
    Ok(())
}

/// The JSON sidecar that places `grid` when read back with [`read_npy`]: spacing, size and the north-west corner.
pub fn sidecar_json(grid: &Grid) -> String {
    serde_json::json!({
        "spacing_x_m": grid.dx,
        "spacing_y_m": grid.dy,
        "rows": grid.rows,
        "cols": grid.cols,
        "easting_min": grid.origin.x,
        "northing_max": grid.origin.y,
    })
    .to_string()
}

/// Reads a sidecar (see the module documentation).
pub fn read_sidecar(path: &Path) -> Result<Sidecar> {
    let bytes = read_bytes(path)?;
    let value: serde_json::Value = serde_json::from_slice(&bytes).map_err(|e| {
        // Python's `json.dump` writes a NaN or infinite float as the bare word `NaN` or `Infinity`.
        let text = String::from_utf8_lossy(&bytes);
        let hint = if text.contains("NaN") || text.contains("Infinity") {
            " (JSON has no NaN or Infinity, which Python's json.dump writes for float('nan'): write null for \
                 `nodata`)"
        } else {
            ""
        };
        TinError::format(path, format!("not valid JSON: {e}{hint}"))
    })?;
    let obj = value
        .as_object()
        .ok_or_else(|| TinError::format(path, "expected a JSON object"))?;
    let number = |key: &str| -> Result<Option<f64>> {
        match obj.get(key) {
            None | Some(serde_json::Value::Null) => Ok(None),
            Some(v) => v
                .as_f64()
                .filter(|x| x.is_finite())
                .map(Some)
                .ok_or_else(|| TinError::format(path, format!("{key} must be a number, found {v}"))),
        }
    };
    let count = |key: &str| -> Result<Option<usize>> {
        match obj.get(key) {
            None | Some(serde_json::Value::Null) => Ok(None),
            Some(v) => v
                .as_u64()
                .map(|x| Some(x as usize))
                .ok_or_else(|| TinError::format(path, format!("{key} must be a non-negative integer, found {v}"))),
        }
    };
    let (dx, dy) = (number("spacing_x_m")?, number("spacing_y_m")?);
    for (key, v) in [("spacing_x_m", dx), ("spacing_y_m", dy)] {
        if let Some(v) = v
            && v <= 0.0
        {
            return Err(TinError::format(path, format!("{key} is {v}, must be positive")));
        }
    }
    let spacing = match (dx, dy) {
        (Some(dx), Some(dy)) => Some((dx, dy)),
        (None, None) => None,
        (Some(_), None) => return Err(TinError::format(path, "spacing_x_m is given without spacing_y_m")),
        (None, Some(_)) => return Err(TinError::format(path, "spacing_y_m is given without spacing_x_m")),
    };
    Ok(Sidecar {
        spacing,
        nodata: number("nodata")?,
        rows: count("rows")?,
        cols: count("cols")?,
        easting_min: number("easting_min")?,
        northing_max: number("northing_max")?,
        northing_min: number("northing_min")?,
    })
}

/// Element type of an array.
#[derive(Clone, Copy, Debug)]
enum Kind {
    Int,
    Uint,
    Float,
}

/// What a `.npy` header says: the array's size, element type and order, and where its data starts.
#[derive(Clone, Debug)]
struct Layout {
    rows: usize,
    cols: usize,
    descr: String,
    fortran: bool,
    little: bool,
    kind: Kind,
    size: usize,
    data_start: usize,
}

impl Layout {
    /// Refuses data of `len` bytes that is not exactly the array's.
    fn check_data_len(&self, len: u64, path: &Path) -> Result<()> {
        let (rows, cols, size) = (self.rows, self.cols, self.size);
        let expected = rows
            .checked_mul(cols)
            .and_then(|n| n.checked_mul(size))
            .ok_or_else(|| TinError::format(path, format!("array of {rows} x {cols} is too large")))?
            as u64;
        if len < expected {
            return Err(TinError::format(
                path,
                format!("truncated: {len} data bytes, expected {expected} ({rows} x {cols} x {size} bytes)"),
            ));
        }
        if len > expected {
            return Err(TinError::format(
                path,
                format!(
                    "{} bytes of unexpected data after the {rows} x {cols} array",
                    len - expected
                ),
            ));
        }
        Ok(())
    }

    /// The value of one element's `size` bytes.
    fn element(&self, b: &[u8]) -> f64 {
        let size = self.size;
        let mut buf = [0u8; 8];
        buf[..size].copy_from_slice(&b[..size]);
        if !self.little {
            buf[..size].reverse();
        }
        // buf now holds the value in little-endian order, zero-padded.
        match (self.kind, size) {
            (Kind::Float, 4) => f64::from(f32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]])),
            (Kind::Float, _) => f64::from_le_bytes(buf),
            (Kind::Uint, _) => u64::from_le_bytes(buf) as f64,
            (Kind::Int, _) => {
                // Sign-extend from `size` bytes.
                let shift = 64 - 8 * size as u32;
                ((u64::from_le_bytes(buf) << shift) as i64 >> shift) as f64
            }
        }
    }
}

/// Parses the header of a `.npy` file (`bytes` holds at least the header); `path` names it in errors.
fn parse_layout(bytes: &[u8], path: &Path) -> Result<Layout> {
    let err = |m: String| TinError::format(path, m);
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(err("not a NumPy .npy file (bad magic bytes)".into()));
    }
    let (major, minor) = (bytes[6], bytes[7]);
    let (header_len, start) = match major {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 => {
            if bytes.len() < 12 {
                return Err(err("truncated .npy header".into()));
            }
            (
                u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
                12,
            )
        }
        _ => return Err(err(format!("unsupported .npy format version {major}.{minor}"))),
    };
    let data_start = start + header_len;
    if bytes.len() < data_start {
        return Err(err(format!(
            "truncated .npy header: {header_len} header bytes announced, {} present",
            bytes.len() - start
        )));
    }
    let header =
        std::str::from_utf8(&bytes[start..data_start]).map_err(|_| err("the .npy header is not text".into()))?;
    let dict = parse_header(header).map_err(|m| err(format!("bad .npy header {:?}: {m}", header.trim())))?;
    let descr = dict.descr.ok_or_else(|| err("the .npy header has no 'descr'".into()))?;
    let fortran = dict
        .fortran_order
        .ok_or_else(|| err("the .npy header has no 'fortran_order'".into()))?;
    let shape = dict.shape.ok_or_else(|| err("the .npy header has no 'shape'".into()))?;
    let [rows, cols] = shape[..] else {
        return Err(err(format!(
            "expected a 2-D array (rows, cols), the shape is {shape:?}"
        )));
    };
    let (little, kind, size) = parse_descr(&descr).ok_or_else(|| {
        err(format!(
            "unsupported element type {descr:?}: expected integers (i1..i8, u1..u8) or floats (f4, f8)"
        ))
    })?;
    Ok(Layout {
        rows,
        cols,
        descr,
        fortran,
        little,
        kind,
        size,
        data_start,
    })
}

/// Parses the bytes of a `.npy` file holding a 2-D numeric array; `path` names it in errors.
pub fn parse_npy(bytes: &[u8], path: &Path) -> Result<NpyArray> {
    let layout = parse_layout(bytes, path)?;
    let data = &bytes[layout.data_start..];
    layout.check_data_len(data.len() as u64, path)?;
    let (rows, cols, size) = (layout.rows, layout.cols, layout.size);
    let element = |k: usize| layout.element(&data[k * size..(k + 1) * size]);
    let values = if layout.fortran {
        let mut v = vec![0.0; rows * cols];
        for c in 0..cols {
            for r in 0..rows {
                v[r * cols + c] = element(c * rows + r);
            }
        }
        v
    } else {
        (0..rows * cols).map(element).collect()
    };
    Ok(NpyArray {
        rows,
        cols,
        descr: layout.descr,
        values,
    })
}

/// Byte order (true = little), kind and size of a `descr` such as `<i2`.
fn parse_descr(descr: &str) -> Option<(bool, Kind, usize)> {
    let mut chars = descr.chars();
    let order = chars.next()?;
    let kind = match chars.next()? {
        'i' => Kind::Int,
        'u' => Kind::Uint,
        'f' => Kind::Float,
        _ => return None,
    };
    let size: usize = chars.as_str().parse().ok()?;
    let valid = match kind {
        Kind::Float => size == 4 || size == 8,
        _ => matches!(size, 1 | 2 | 4 | 8),
    };
    let little = match order {
        '<' => true,
        '>' => false,
        '|' if size == 1 => true,
        '=' => cfg!(target_endian = "little"),
        _ => return None,
    };
    valid.then_some((little, kind, size))
}

#[derive(Debug, Default)]
struct Header {
    descr: Option<String>,
    fortran_order: Option<bool>,
    shape: Option<Vec<usize>>,
}

/// Parses the header dict, e.g. `{'descr': '<i2', 'fortran_order': False, 'shape': (344, 403), }`.
fn parse_header(text: &str) -> std::result::Result<Header, String> {
    let mut p = Lexer {
        s: text.as_bytes(),
        i: 0,
    };
    let mut h = Header::default();
    p.expect(b'{')?;
    loop {
        p.skip_ws();
        if p.eat(b'}') {
            break;
        }
        let key = p.string()?;
        p.expect(b':')?;
        p.skip_ws();
        match key.as_str() {
            "descr" => h.descr = Some(p.string()?),
            "fortran_order" => h.fortran_order = Some(p.boolean()?),
            "shape" => h.shape = Some(p.tuple()?),
            other => return Err(format!("unexpected key {other:?}")),
        }
        p.skip_ws();
        if !p.eat(b',') {
            p.expect(b'}')?;
            break;
        }
    }
    Ok(h)
}

struct Lexer<'a> {
    s: &'a [u8],
    i: usize,
}

impl Lexer<'_> {
    fn skip_ws(&mut self) {
        while self.i < self.s.len() && self.s[self.i].is_ascii_whitespace() {
            self.i += 1;
        }
    }

    fn eat(&mut self, c: u8) -> bool {
        self.skip_ws();
        if self.s.get(self.i) == Some(&c) {
            self.i += 1;
            true
        } else {
            false
        }
    }

    fn expect(&mut self, c: u8) -> std::result::Result<(), String> {
        if self.eat(c) {
            Ok(())
        } else {
            Err(format!("expected '{}' at byte {}", c as char, self.i))
        }
    }

    fn string(&mut self) -> std::result::Result<String, String> {
        self.skip_ws();
        let quote = match self.s.get(self.i) {
            Some(&q @ (b'\'' | b'"')) => q,
            _ => return Err(format!("expected a string at byte {}", self.i)),
        };
        let start = self.i + 1;
        let len = self.s[start..]
            .iter()
            .position(|&b| b == quote)
            .ok_or_else(|| "unterminated string".to_string())?;
        self.i = start + len + 1;
        Ok(String::from_utf8_lossy(&self.s[start..start + len]).into_owned())
    }

    fn boolean(&mut self) -> std::result::Result<bool, String> {
        self.skip_ws();
        for (word, value) in [("True", true), ("False", false)] {
            if self.s[self.i..].starts_with(word.as_bytes()) {
                self.i += word.len();
                return Ok(value);
            }
        }
        Err(format!("expected True or False at byte {}", self.i))
    }

    fn tuple(&mut self) -> std::result::Result<Vec<usize>, String> {
        self.expect(b'(')?;
        let mut v = Vec::new();
        loop {
            self.skip_ws();
            if self.eat(b')') {
                return Ok(v);
            }
            let start = self.i;
            while self.i < self.s.len() && self.s[self.i].is_ascii_digit() {
                self.i += 1;
            }
            let digits = std::str::from_utf8(&self.s[start..self.i]).unwrap_or("");
            v.push(
                digits
                    .parse()
                    .map_err(|_| format!("expected a dimension at byte {start}"))?,
            );
            if !self.eat(b',') {
                self.expect(b')')?;
                return Ok(v);
            }
        }
    }
}

/// The path of the sidecar of a `.npy` file.
pub fn sidecar_path(npy: &Path) -> PathBuf {
    npy.with_extension("json")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_grids_read_back_exactly() {
        let z = vec![1.5, f64::NAN, -3.25, 1e-300, 8848.0, 0.0];
        let g = Grid::new(2, 3, 30.0, 20.0, DVec2::new(500_000.0, 4_000_000.0), z).expect("grid");
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("g.npy");
        let mut bytes = Vec::new();
        write_npy_to(&g, &mut bytes).expect("write");
        assert_eq!((bytes.len() - 48) % 8, 0);
        std::fs::write(&path, &bytes).expect("npy");
        std::fs::write(sidecar_path(&path), sidecar_json(&g)).expect("sidecar");
        let back = read_npy(&path, &DemOptions::default()).expect("read");
        assert_eq!(
            (back.rows, back.cols, back.dx, back.dy, back.origin),
            (2, 3, 30.0, 20.0, g.origin)
        );
        assert!(back.z.iter().zip(&g.z).all(|(a, b)| a.to_bits() == b.to_bits()));
    }
}
