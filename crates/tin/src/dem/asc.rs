//! ESRI ASCII grids (`.asc`).
//!
//! Header lines `key value` (keys in any case), then `nrows` rows of `ncols` numbers, row 0 north:
//! `ncols`, `nrows`; `xllcorner` or `xllcenter`; `yllcorner` or `yllcenter`; `cellsize`, or GDAL's `dx` and `dy` for
//! non-square cells; optional `NODATA_value`. The `…corner` keys give the lower-left corner of the lower-left *cell*,
//! so its sample (cell centre) lies half a cell further in; the `…center` keys give that sample directly. The grid
//! origin is the centre of the north-west sample: `x = xll + dx/2`, `y = yll + dy/2 + (nrows − 1)·dy` for corners.
//! Samples equal to `NODATA_value` (and NaN) become voids. Errors name the line. The values are a stream (a row may
//! wrap over lines), so a row with a value too many or too few shows only as too many or too few values in all; when
//! exactly one line holds a number of values other than `ncols`, that message names it too.
//!
//! The header has no CRS; a `.prj` beside the grid (same stem, as GDAL and ArcGIS write it) does. When its root is a
//! geographic CRS (WKT `GEOGCS[…]`, `GEOGCRS[…]`, `GEODCRS[…]`, or the old ESRI text form `Projection GEOGRAPHIC`),
//! the corners and cell sizes are degrees (or the WKT's angular unit) and are put into metres as GeoTIFFs in degrees
//! are (the frame of [`super::hgt`]). When its root is a projected CRS in feet ([`prj_linear_unit`]: WKT
//! `PROJCS[…]`, `PROJCRS[…]`, as US state-plane grids are, or the old ESRI text form's `Units FEET`), coordinates and
//! cell sizes are multiplied into metres. A compound CRS (`COMPD_CS[…]`, `COMPOUNDCRS[…]`) is read by its horizontal
//! part. Heights are multiplied by the unit the `.prj` states for them ([`prj_height_unit`]: a compound CRS's
//! vertical unit, the ESRI text form's `Zunits`); when it states none, they are taken to be in the coordinates' unit
//! (metres for degrees). Any other `.prj`, or none, means metres. An unreadable `.prj` is an error.
//!
//! A window ([`super::read_dem_window`]) is read by streaming the text: the values before it are counted, not
//! parsed, those of its rows outside its columns are skipped, and reading stops after its last row; so values
//! outside the window are not checked. Strips ([`super::read_dem_strips`]) stream the whole text once, every value
//! parsed and checked as [`read_asc`] does, holding one strip of values.

use std::io::BufRead;
use std::path::Path;

use glam::DVec2;

use super::{DemOptions, GridShape, check_window, degrees, file_len, finish, open, read_bytes};
use crate::error::{Result, TinError};
use crate::grid::Grid;

/// Reads an ESRI ASCII grid (see the module documentation).
pub fn read_asc(path: &Path, opts: &DemOptions) -> Result<Grid> {
    opts.check_one_band(path, ".asc")?;
    let bytes = read_bytes(path)?;
    parse_asc(&bytes, path, opts)
}

/// The grid of an ESRI ASCII grid from its header, without reading its values.
pub fn read_asc_header(path: &Path, opts: &DemOptions) -> Result<GridShape> {
    Ok(read_header(path, opts)?.shape(path, opts)?.0)
}

/// How the grid's coordinates (and heights) were put into metres: a sentence when a `.prj` beside it says they are
/// degrees or feet (see the module documentation), None when they are metres already.
pub fn read_asc_conversion(path: &Path, opts: &DemOptions) -> Result<Option<String>> {
    Ok(read_header(path, opts)?.grid(path, opts)?.2)
}

/// Metres per unit of an ESRI ASCII grid's heights, and whether that unit was assumed: the unit its `.prj` states for
/// heights ([`prj_height_unit`]), else the foot of a projected `.prj` in feet (assumed: taken to be the
/// coordinates'), else 1.
pub fn read_asc_height_unit(path: &Path, opts: &DemOptions) -> Result<(f64, bool)> {
    let values = read_header(path, opts)?.grid(path, opts)?.1;
    Ok((values.unit, values.unit_assumed))
}

/// The header of an ESRI ASCII grid, read up to its first line of values.
fn read_header(path: &Path, opts: &DemOptions) -> Result<Header> {
    opts.check_one_band(path, ".asc")?;
    let mut lines = Lines::open(path)?;
    let mut h = Header::default();
    while let Some((n, line)) = lines.next()? {
        if !h.line(n, line, path)? {
            break;
        }
    }
    Ok(h)
}

/// The samples of a window of an ESRI ASCII grid (voids NaN, not scaled) and its whole grid, streaming the text
/// (see the module documentation).
pub(super) fn read_asc_window(
    path: &Path,
    opts: &DemOptions,
    rows: [usize; 2],
    cols: [usize; 2],
) -> Result<(GridShape, Vec<f64>)> {
    let err = |m: String| TinError::format(path, m);
    let mut lines = Lines::open(path)?;
    let file_len = lines.len;
    let mut h = Header::default();
    let mut window: Option<(GridShape, Values)> = None;
    // Checked against the grid below, once the header is read: never underflows before that.
    let nc = cols[1].saturating_sub(cols[0]).saturating_add(1);
    let mut z = Vec::new();
    // Index of the next value in the whole grid (row-major).
    let mut k = 0usize;
    let mut counts = LineCounts::default();
    'lines: while let Some((n, line)) = lines.next()? {
        if window.is_none() {
            if h.line(n, line, path)? {
                continue;
            }
            let (shape, nodata) = std::mem::take(&mut h).shape(path, opts)?;
            check_window(&shape, rows, cols, path)?;
            // Every value takes at least two bytes: never reserve more than the file can hold.
            z.reserve_exact(((rows[1] - rows[0] + 1) * nc).min(file_len / 2 + 1));
            window = Some((shape, nodata));
        }
        let Some((shape, nodata)) = window else { break };
        let before = k;
        for word in line.split_whitespace() {
            let (r, c) = (k / shape.cols, k % shape.cols);
            if r > rows[1] {
                break 'lines;
            }
            if r >= rows[0] && (cols[0]..=cols[1]).contains(&c) {
                z.push(sample(word, n, k, shape.cols, nodata, path)?);
            }
            k += 1;
        }
        counts.add(n, k - before, shape.cols);
    }
    let (shape, _) = match window {
        Some(w) => w,
        None => {
            // No values at all: the header's own errors, or the window's, or truncation.
            let (shape, nodata) = h.shape(path, opts)?;
            check_window(&shape, rows, cols, path)?;
            (shape, nodata)
        }
    };
    if z.len() < (rows[1] - rows[0] + 1) * nc {
        return Err(err(format!(
            "truncated: {k} values, but nrows x ncols = {} x {} = {}{}",
            shape.rows,
            shape.cols,
            shape.rows * shape.cols,
            counts.hint(shape.cols, false)
        )));
    }
    Ok((shape, z))
}

/// Values per line of a grid's body, for the messages about too many or too few values: the format is a stream of
/// values (a row may wrap over lines), but most files write one row per line, and when exactly one line of several
/// holds a number other than `ncols`, that line is where a row went wrong.
#[derive(Debug, Default)]
struct LineCounts {
    /// Lines with values.
    lines: usize,
    /// Lines whose number of values is not `ncols`, and the first of them: (line, values).
    odd_lines: usize,
    first_odd: Option<(usize, usize)>,
}

impl LineCounts {
    /// Counts line `n`, which held `values` values (lines without any are not counted).
    fn add(&mut self, n: usize, values: usize, cols: usize) {
        if values == 0 {
            return;
        }
        self.lines += 1;
        if values != cols {
            self.odd_lines += 1;
            self.first_odd.get_or_insert((n, values));
        }
    }

    /// `"; line L has V values where every other line has ncols = C"` when one line alone of those counted is odd,
    /// and there is another line (counted, or the line being read when `reading` holds), else nothing.
    fn hint(&self, cols: usize, reading: bool) -> String {
        match self.first_odd {
            Some((n, v)) if self.odd_lines == 1 && self.lines + usize::from(reading) > 1 => {
                format!("; line {n} has {v} values where every other line has ncols = {cols}")
            }
            _ => String::new(),
        }
    }
}

/// Streams a whole ESRI ASCII grid once, handing its values out in strips of `strip_rows` rows (voids NaN, not
/// scaled): `each(first_row, values)`. Every value is parsed, and too few or too many are errors, as in
/// [`parse_asc`]; `shape` is the grid its header describes ([`read_asc_header`]).
pub(super) fn read_asc_strips(
    path: &Path,
    shape: &GridShape,
    opts: &DemOptions,
    strip_rows: usize,
    each: &mut dyn FnMut(usize, &mut Vec<f64>) -> Result<()>,
) -> Result<()> {
    let err = |m: String| TinError::format(path, m);
    let mut lines = Lines::open(path)?;
    let mut h = Header::default();
    let mut values = Values::default();
    let mut in_header = true;
    let (rows, cols) = (shape.rows, shape.cols);
    let expected = rows * cols;
    let strip = strip_rows.max(1) * cols;
    let mut z = Vec::with_capacity(strip.min(lines.len / 2 + 1));
    // Values read so far, and the first row of the strip being filled.
    let (mut k, mut first) = (0usize, 0usize);
    let mut counts = LineCounts::default();
    while let Some((n, line)) = lines.next()? {
        if in_header {
            if h.line(n, line, path)? {
                continue;
            }
            in_header = false;
            values = std::mem::take(&mut h).shape(path, opts)?.1;
        }
        let before = k;
        for word in line.split_whitespace() {
            if k == expected {
                return Err(err(format!(
                    "line {n}: more than the {expected} values that nrows x ncols = {rows} x {cols} announce{}",
                    counts.hint(cols, true)
                )));
            }
            z.push(sample(word, n, k, cols, values, path)?);
            k += 1;
            if z.len() == strip {
                each(first, &mut z)?;
                first += strip_rows.max(1);
                z.clear();
            }
        }
        counts.add(n, k - before, cols);
    }
    if k < expected {
        return Err(err(format!(
            "truncated: {k} values, but nrows x ncols = {rows} x {cols} = {expected}{}",
            counts.hint(cols, false)
        )));
    }
    if !z.is_empty() {
        each(first, &mut z)?;
    }
    Ok(())
}

/// The lines of a text file, read one at a time (1-based numbers), naming the file and line in errors.
/// How a grid's values become heights: its nodata value, and metres per unit of the values (1, or the unit its `.prj`
/// states for heights, or else the foot of a projected `.prj` in feet).
#[derive(Clone, Copy, Debug)]
struct Values {
    nodata: Option<f64>,
    unit: f64,
    /// Whether `unit` was taken from the coordinates' because the `.prj` does not state the heights'.
    unit_assumed: bool,
}

impl Default for Values {
    fn default() -> Self {
        Values {
            nodata: None,
            unit: 1.0,
            unit_assumed: false,
        }
    }
}

/// The height of the value `word` at index `k` of the grid (row-major, `cols` wide) on line `n`, in metres: NaN for a
/// void (the nodata value, or NaN); an error naming the line and the 1-based row and column for anything else that is
/// not a finite number.
fn sample(word: &str, n: usize, k: usize, cols: usize, values: Values, path: &Path) -> Result<f64> {
    match word.parse::<f64>() {
        Ok(v) if values.nodata == Some(v) || v.is_nan() => Ok(f64::NAN),
        Ok(v) if v.is_finite() => Ok(v * values.unit),
        _ => Err(TinError::format(
            path,
            format!(
                "line {n}: {} is not a finite number (row {}, column {})",
                quote(word),
                k / cols + 1,
                k % cols + 1
            ),
        )),
    }
}

/// `s` quoted for a message, cut after 60 characters (a file without line endings is one long line).
fn quote(s: &str) -> String {
    match s.char_indices().nth(60) {
        Some((at, _)) => format!("{:?}…", &s[..at]),
        None => format!("{s:?}"),
    }
}

struct Lines<'p> {
    reader: std::io::BufReader<std::fs::File>,
    buf: Vec<u8>,
    n: usize,
    path: &'p Path,
    /// The file's length in bytes.
    len: usize,
}

impl<'p> Lines<'p> {
    fn open(path: &'p Path) -> Result<Self> {
        let file = open(path)?;
        let len = file_len(&file, path)?;
        Ok(Lines {
            reader: std::io::BufReader::with_capacity(1 << 16, file),
            buf: Vec::new(),
            n: 0,
            path,
            len: usize::try_from(len).unwrap_or(usize::MAX),
        })
    }

    /// The next line without its line ending (as [`str::lines`] gives it), or None at the end.
    fn next(&mut self) -> Result<Option<(usize, &str)>> {
        self.buf.clear();
        let read = self
            .reader
            .read_until(b'\n', &mut self.buf)
            .map_err(|e| TinError::io(self.path, e))?;
        if read == 0 {
            return Ok(None);
        }
        self.n += 1;
        let mut line = &self.buf[..];
        if let Some(l) = line.strip_suffix(b"\n") {
            line = l.strip_suffix(b"\r").unwrap_or(l);
        }
        let text = std::str::from_utf8(line).map_err(|_| {
            TinError::format(
                self.path,
                format!("line {}: not text (a binary or foreign file?)", self.n),
            )
        })?;
        Ok(Some((self.n, text)))
    }
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

impl Header {
    /// Takes line `n` (1-based) of the header: false when it is not a header line but the first line of values
    /// (its first word is a number). Blank lines are header lines.
    fn line(&mut self, n: usize, line: &str, path: &Path) -> Result<bool> {
        let err = |m: String| TinError::format(path, m);
        // A byte-order mark (as Notepad's "UTF-8 with BOM" writes) is not part of the first key.
        let line = if n == 1 {
            line.strip_prefix('\u{feff}').unwrap_or(line)
        } else {
            line
        };
        let mut words = line.split_whitespace();
        let Some(key) = words.next() else {
            return Ok(true);
        };
        if key.parse::<f64>().is_ok() {
            return Ok(false);
        }
        let value = words
            .next()
            .ok_or_else(|| err(format!("line {n}: header key {} has no value", quote(key))))?;
        if words.next().is_some() {
            return Err(err(format!(
                "line {n}: header line {} has more than one value",
                quote(line)
            )));
        }
        let number = || -> Result<f64> {
            value
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| err(format!("line {n}: {key} = {} is not a finite number", quote(value))))
        };
        let count = || -> Result<usize> {
            value
                .parse::<usize>()
                .ok()
                .filter(|&v| v > 0)
                .ok_or_else(|| err(format!("line {n}: {key} = {} is not a positive integer", quote(value))))
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
                slot_taken(self.ncols.is_some())?;
                self.ncols = Some(count()?);
            }
            "nrows" => {
                slot_taken(self.nrows.is_some())?;
                self.nrows = Some(count()?);
            }
            k @ ("xllcorner" | "xllcenter") => {
                slot_taken(self.xll.is_some())?;
                self.xll = Some((number()?, k == "xllcorner"));
            }
            k @ ("yllcorner" | "yllcenter") => {
                slot_taken(self.yll.is_some())?;
                self.yll = Some((number()?, k == "yllcorner"));
            }
            "cellsize" => {
                slot_taken(self.cellsize.is_some())?;
                self.cellsize = Some(number()?);
            }
            "dx" => {
                slot_taken(self.dx.is_some())?;
                self.dx = Some(number()?);
            }
            "dy" => {
                slot_taken(self.dy.is_some())?;
                self.dy = Some(number()?);
            }
            "nodata_value" => {
                slot_taken(self.nodata.is_some())?;
                // GDAL writes `nan` for a float grid whose voids are NaN (which are voids anyway).
                self.nodata = Some(
                    if value.eq_ignore_ascii_case("nan") || value.eq_ignore_ascii_case("-nan") {
                        f64::NAN
                    } else {
                        number()?
                    },
                );
            }
            _ => {
                return Err(err(format!(
                    "line {n}: unknown header key {} (not an ESRI ASCII grid?)",
                    quote(key)
                )));
            }
        }
        Ok(true)
    }

    /// The grid the header describes (with [`DemOptions::spacing`] applied) and how its values become heights.
    fn shape(self, path: &Path, opts: &DemOptions) -> Result<(GridShape, Values)> {
        self.grid(path, opts).map(|(shape, values, _)| (shape, values))
    }

    /// [`Header::shape`], and how the coordinates (and heights) were put into metres when the `.prj` says geographic
    /// or feet.
    fn grid(self, path: &Path, opts: &DemOptions) -> Result<(GridShape, Values, Option<String>)> {
        let err = |m: String| TinError::format(path, m);
        let h = self;
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
        rows.checked_mul(cols)
            .filter(|&n| n <= (1 << 31))
            .ok_or_else(|| err(format!("{rows} x {cols} samples is too many")))?;
        let prj = read_prj(path)?;
        // The heights' unit when the `.prj` states it; else the coordinates' (metres for degrees).
        let heights = prj.as_ref().and_then(|(text, _)| prj_height_unit(text));
        let heights_note = |xy: &str| match &heights {
            Some((m, name)) if *m != 1.0 => format!("{xy}heights in {name} times {m} m"),
            _ => xy.trim_end_matches([',', ' ']).to_string(),
        };
        let (shape, values, conversion) = if let Some((deg, prj)) = prj
            .as_ref()
            .and_then(|(text, prj)| prj_geographic_unit(text).map(|deg| (deg, prj)))
        {
            // The header's numbers are angles: the sample (0, 0) and spacing in degrees, then metres.
            let (dx, dy) = (header_spacing.0 * deg, header_spacing.1 * deg);
            let west = xll * deg + if x_corner { 0.5 * dx } else { 0.0 };
            let south = yll * deg + if y_corner { 0.5 * dy } else { 0.0 };
            let north = south + (rows as f64 - 1.0) * dy;
            let (shape, conversion) = degrees::grid_in_metres(rows, cols, west, north, (dx, dy), opts)
                .map_err(|m| err(format!("{} says geographic, but {m}", prj.display())))?;
            let values = Values {
                nodata: h.nodata,
                unit: heights.as_ref().map_or(1.0, |u| u.0),
                unit_assumed: false,
            };
            let conversion = heights_note(&format!("{conversion}, "));
            (
                shape,
                values,
                Some(format!("{conversion} (CRS from {})", prj.display())),
            )
        } else {
            // A projected CRS in feet: every coordinate is multiplied into metres, and every height too unless the
            // `.prj` states the heights' unit.
            let feet = prj
                .as_ref()
                .and_then(|(text, prj)| prj_linear_unit(text).map(|u| (u, prj)));
            let m = feet.as_ref().map_or(1.0, |((m, _), _)| *m);
            let values = Values {
                nodata: h.nodata,
                unit: heights.as_ref().map_or(m, |u| u.0),
                unit_assumed: heights.is_none() && m != 1.0,
            };
            let (dx, dy) = opts.spacing.unwrap_or((header_spacing.0 * m, header_spacing.1 * m));
            let (xll, yll) = (xll * m, yll * m);
            let x0 = if x_corner { xll + 0.5 * dx } else { xll };
            let y_south = if y_corner { yll + 0.5 * dy } else { yll };
            let origin = DVec2::new(x0, y_south + (rows as f64 - 1.0) * dy);
            let shape = GridShape {
                rows,
                cols,
                dx,
                dy,
                origin,
            };
            let conversion = match (&feet, &heights, &prj) {
                (Some(((m, name), prj)), None, _) => Some(format!(
                    "x, y and heights in {name} times {m} m (CRS from {}; heights assumed in the same unit: the .prj \
                     does not say theirs)",
                    prj.display()
                )),
                (Some(((m, name), prj)), Some(_), _) => Some(format!(
                    "{} (CRS from {})",
                    heights_note(&format!("x, y in {name} times {m} m, ")),
                    prj.display()
                )),
                (None, Some((hm, _)), Some((_, prj))) if *hm != 1.0 => {
                    Some(format!("{} (CRS from {})", heights_note(""), prj.display()))
                }
                _ => None,
            };
            (shape, values, conversion)
        };
        Ok((shape, values, conversion))
    }
}

/// Where a `.prj` beside `grid` may be: same stem, extension `prj` in lower or upper case.
pub(crate) fn prj_candidates(grid: &Path) -> [std::path::PathBuf; 2] {
    ["prj", "PRJ"].map(|e| grid.with_extension(e))
}

/// The `.prj` beside `grid` ([`prj_candidates`]), if there is one.
fn prj_of(grid: &Path) -> Option<std::path::PathBuf> {
    prj_candidates(grid).into_iter().find(|p| p.is_file())
}

/// The root keyword of a CRS text, in upper case (`PROJCS`, `GEOGCRS`, `COMPD_CS`, `PROJECTION`, …), and the text
/// with any byte-order mark and leading space removed.
fn crs_root(text: &str) -> (String, &str) {
    let t = text.trim_start_matches('\u{feff}').trim_start();
    let root = t
        .chars()
        .take_while(|c| c.is_ascii_alphabetic() || *c == '_')
        .collect::<String>()
        .to_ascii_uppercase();
    (root, t)
}

/// Whether `root` is the keyword of a compound CRS (WKT 1 `COMPD_CS`, WKT 2 `COMPOUNDCRS`): a horizontal CRS, then a
/// vertical one.
fn is_compound(root: &str) -> bool {
    matches!(root, "COMPD_CS" | "COMPOUNDCRS")
}

/// The first element nested in the WKT element `t` starts with (the horizontal CRS of a compound CRS), through its
/// closing bracket; None when there is none or it is not closed.
fn first_component(t: &str) -> Option<&str> {
    let open = t.find(['[', '('])?;
    let (mut quoted, mut start, mut depth) = (false, open + 1, 0usize);
    for (i, c) in t.char_indices().skip_while(|&(i, _)| i <= open) {
        match c {
            '"' => quoted = !quoted,
            _ if quoted => {}
            '[' | '(' => depth += 1,
            ']' | ')' if depth == 0 => return None,
            ']' | ')' => {
                depth -= 1;
                if depth == 0 {
                    return Some(t[start..=i].trim_start());
                }
            }
            ',' if depth == 0 => start = i + 1,
            _ => {}
        }
    }
    None
}

/// How `.asc` coordinates are to be read, from the text of a `.prj`: `Some(degrees per unit)` when its root is a
/// geographic CRS, or a compound CRS whose horizontal part is one (see the module documentation), None for anything
/// else.
pub fn prj_geographic_unit(text: &str) -> Option<f64> {
    let (root, t) = crs_root(text);
    if is_compound(&root) {
        return first_component(t).and_then(prj_geographic_unit);
    }
    let wkt_geographic = matches!(root.as_str(), "GEOGCS" | "GEOGCRS" | "GEODCRS" | "GEOGRAPHICCRS")
        && t[root.len()..].trim_start().starts_with(['[', '(']);
    if wkt_geographic {
        // The angular unit: `ANGLEUNIT[name, radians]`, or a plain `UNIT[…]` (WKT 1's only unit in a GEOGCS), never
        // an ellipsoid's `LENGTHUNIT[…]`.
        let upper = t.to_ascii_uppercase();
        let unit_at = upper.match_indices("UNIT[").map(|(at, _)| at).find(|&at| {
            let before = &upper[..at];
            before.ends_with("ANGLE") || !before.ends_with(|c: char| c.is_ascii_alphabetic())
        });
        let radians = unit_at
            .and_then(|at| t[at + "UNIT[".len()..].split([',', ']']).nth(1))
            .and_then(|v| v.trim().parse::<f64>().ok())
            .filter(|r| r.is_finite() && *r > 0.0);
        // A degree written to 15 digits (`0.0174532925199433`) is a degree.
        let deg = radians.map_or(1.0, f64::to_degrees);
        return Some(if (deg - 1.0).abs() < 1e-9 { 1.0 } else { deg });
    }
    // The ESRI text form: `Projection GEOGRAPHIC`, with `Units DD` (decimal degrees) or none.
    (esri_text_field(t, "projection").as_deref() == Some("GEOGRAPHIC")).then_some(1.0)
}

/// The text and path of the `.prj` beside `grid`; None when there is none.
fn read_prj(grid: &Path) -> Result<Option<(String, std::path::PathBuf)>> {
    let Some(prj) = prj_of(grid) else {
        return Ok(None);
    };
    let bytes = read_bytes(&prj)?;
    let text = String::from_utf8(bytes)
        .map_err(|_| TinError::format(&prj, String::from("not text: a .prj holds a CRS in WKT")))?;
    Ok(Some((text, prj)))
}

/// Keywords of the elements of a projected CRS whose units are not those of its coordinates: the base geographic
/// CRS (its datum, ellipsoid and angular unit) and the map projection's parameters (WKT 2's `CONVERSION`).
const NOT_COORDINATES: [&str; 10] = [
    "GEOGCS",
    "BASEGEOGCRS",
    "BASEGEODCRS",
    "GEOGCRS",
    "GEODCRS",
    "DATUM",
    "SPHEROID",
    "ELLIPSOID",
    "CONVERSION",
    "PARAMETER",
];

/// Keywords of the vertical CRS of a compound CRS (WKT 1 and 2).
const VERTICAL: [&str; 3] = ["VERT_CS", "VERTCRS", "VERTICALCRS"];

/// Keywords of a vertical datum, whose units (if any) are not the heights'.
const VERTICAL_DATUM: [&str; 4] = ["VERT_DATUM", "VDATUM", "VERTICALDATUM", "VRF"];

/// The first `UNIT[name, factor]` or `LENGTHUNIT[…]` of a WKT text for which `wanted` holds of the keywords of the
/// elements open around it (outermost first): its factor (None when it is not a positive finite number) and name.
/// None when no unit is wanted.
fn first_wkt_unit(t: &str, wanted: impl Fn(&[&str]) -> bool) -> Option<(Option<f64>, String)> {
    let upper = t.to_ascii_uppercase();
    let mut open: Vec<&str> = Vec::new();
    let mut word_start = 0;
    let mut quoted = false;
    for (i, c) in upper.char_indices() {
        match c {
            '"' => quoted = !quoted,
            _ if quoted => {}
            '[' | '(' => {
                let word = upper[word_start..i].trim();
                if matches!(word, "UNIT" | "LENGTHUNIT") && wanted(&open) {
                    // `upper` and `t` have the same bytes at the same places but for the case of ASCII letters.
                    let mut parts = t[i + 1..].split([',', ']', ')']);
                    let name = parts.next().unwrap_or_default().trim().trim_matches('"').to_string();
                    let factor = parts
                        .next()
                        .and_then(|f| f.trim().parse::<f64>().ok())
                        .filter(|f| f.is_finite() && *f > 0.0);
                    return Some((factor, name));
                }
                open.push(word);
                word_start = i + 1;
            }
            ']' | ')' => {
                open.pop();
                word_start = i + 1;
            }
            ',' => word_start = i + 1,
            _ => {}
        }
    }
    None
}

/// The linear unit of a projected CRS in WKT (root `PROJCS`, `PROJCRS` or `PROJECTEDCRS`, or a compound CRS whose
/// horizontal part is one) when it is not the metre: metres per unit and the unit's name, from the first
/// `UNIT[name, factor]` or `LENGTHUNIT[…]` that is neither inside the base geographic CRS (its datum, ellipsoid or
/// angular unit), nor a parameter's of the map projection (WKT 2's `CONVERSION`), nor the vertical CRS's: the unit of
/// the coordinates. The old ESRI text form (`Projection …` then `Units FEET`) is read too. None for metres, for any
/// other CRS, and for a unit without a positive factor.
pub fn prj_linear_unit(text: &str) -> Option<(f64, String)> {
    let (root, t) = crs_root(text);
    if root == "PROJECTION" {
        return esri_text_linear_unit(t);
    }
    if !matches!(root.as_str(), "PROJCS" | "PROJCRS" | "PROJECTEDCRS") && !is_compound(&root) {
        return None;
    }
    let (factor, name) = first_wkt_unit(t, |open| {
        !open.is_empty() && !open.iter().any(|w| NOT_COORDINATES.contains(w) || VERTICAL.contains(w))
    })?;
    let factor = factor?;
    ((factor - 1.0).abs() > 1e-12).then_some((factor, name))
}

/// The unit of the heights when a `.prj` states it: metres per unit (1 for metres) and how the `.prj` names it. A
/// compound CRS states it as its vertical CRS's unit (WKT 1 `VERT_CS[…, UNIT[…]]`, WKT 2 `VERTCRS[…, LENGTHUNIT[…]]`),
/// the old ESRI text form as its `Zunits` line (`METERS`, `FEET` for the US survey foot, a unit naming both "INT" and
/// "FEET" for the international foot, or a positive number of metres per unit). None when the `.prj` does not say
/// (`Zunits NO`, a CRS without a vertical part, a unit without a positive factor, or a `Zunits` it does not know):
/// the heights are then taken to be in the coordinates' unit.
pub fn prj_height_unit(text: &str) -> Option<(f64, String)> {
    let (root, t) = crs_root(text);
    if root == "PROJECTION" {
        let z = esri_text_field(t, "zunits")?;
        return if z.starts_with("MET") {
            Some((1.0, format!("metres (Zunits {z})")))
        } else if z.contains("FEET") || z.contains("FOOT") {
            Some(feet(&z, "Zunits"))
        } else {
            let m = z.parse::<f64>().ok().filter(|m| m.is_finite() && *m > 0.0)?;
            Some((m, format!("units of {m} m (Zunits {z})")))
        };
    }
    if !is_compound(&root) {
        return None;
    }
    let (factor, name) = first_wkt_unit(t, |open| {
        open.iter().any(|w| VERTICAL.contains(w)) && !open.iter().any(|w| VERTICAL_DATUM.contains(w))
    })?;
    Some((factor?, name))
}

/// The value of the line `key value…` of the old ESRI text form of a `.prj` (the key in any case), its words joined by
/// `_`, in upper case; None when there is no such line.
fn esri_text_field(t: &str, key: &str) -> Option<String> {
    t.lines().find_map(|l| {
        let mut w = l.split_whitespace();
        (w.next()?.eq_ignore_ascii_case(key)).then(|| w.collect::<Vec<_>>().join("_").to_ascii_uppercase())
    })
}

/// Metres per unit and a description of the foot that the ESRI text form's `unit` names on its line `key`: the US
/// survey foot, as ArcInfo and GDAL read `FEET`, or the international foot for a unit naming both "INT" and "FEET".
fn feet(unit: &str, key: &str) -> (f64, String) {
    if unit.contains("INT") {
        (0.3048, format!("international feet ({key} {unit})"))
    } else {
        (1200.0 / 3937.0, format!("US survey feet ({key} {unit})"))
    }
}

/// The linear unit of the old ESRI text form of a `.prj` (`Projection UTM`, `Units FEET`, …) when it is not the
/// metre (see [`feet`]). None for `Projection GEOGRAPHIC`, for metres and for a unit it does not know.
fn esri_text_linear_unit(t: &str) -> Option<(f64, String)> {
    if esri_text_field(t, "projection")? == "GEOGRAPHIC" {
        return None;
    }
    let units = esri_text_field(t, "units")?;
    (units.contains("FEET") || units.contains("FOOT")).then(|| feet(&units, "Units"))
}

/// Parses an ESRI ASCII grid held in memory; `path` names it in errors and locates its `.prj` (if any).
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
        if !h.line(i + 1, line, path)? {
            break;
        }
        lines.next();
    }
    let (shape, nodata) = h.shape(path, opts)?;
    let (rows, cols) = (shape.rows, shape.cols);
    let expected = rows * cols;
    // Every value takes at least two bytes: never reserve more than the file can hold (a lying header must not
    // allocate gigabytes).
    let mut z = Vec::with_capacity(expected.min(bytes.len() / 2 + 1));
    let mut counts = LineCounts::default();
    for (i, line) in lines {
        let before = z.len();
        for word in line.split_whitespace() {
            if z.len() == expected {
                return Err(err(format!(
                    "line {}: more than the {expected} values that nrows x ncols = {rows} x {cols} announce{}",
                    i + 1,
                    counts.hint(cols, true)
                )));
            }
            z.push(sample(word, i + 1, z.len(), cols, nodata, path)?);
        }
        counts.add(i + 1, z.len() - before, cols);
    }
    if z.len() < expected {
        return Err(err(format!(
            "truncated: {} values, but nrows x ncols = {rows} x {cols} = {expected}{}",
            z.len(),
            counts.hint(cols, false)
        )));
    }
    finish(path, rows, cols, (shape.dx, shape.dy), shape.origin, z, opts)
}
