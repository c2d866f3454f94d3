//! Grayscale PNG height maps.
//!
//! 16-bit grayscale (the usual height-map format) or 8-bit grayscale; height = stored value · `z_scale`. A PNG has
//! no georeference, so [`DemOptions::spacing`] is required, and the south-west sample is put at (0, 0). Every value
//! is a height (PNG has no nodata convention). Row 0 (the top of the image) is north. Other colour types and bit
//! depths are rejected.
//!
//! A window ([`super::read_dem_window`]) is cut from the whole image: PNG is one compressed stream, so the whole
//! image is decoded. [`read_png_header`] reads the header only. Strips ([`super::read_dem_strips`]) decode the rows
//! once, in order, holding one strip (an interlaced image, whose rows come in passes, is decoded whole first). A whole
//! read decodes the rows in order too, its heights growing with the rows decoded, so a small file whose header claims
//! a huge image is refused, at its first missing row, without allocating that image.

use std::io::Cursor;
use std::path::Path;

use glam::DVec2;

use super::{DemOptions, GridShape, MAX_SAMPLES, finish, grow_with_data, open_with_len, read_bytes};
use crate::error::{Result, TinError};
use crate::grid::Grid;

/// Reads a PNG height map (see the module documentation).
pub fn read_png(path: &Path, opts: &DemOptions) -> Result<Grid> {
    opts.check_one_band(path, "PNG")?;
    let bytes = read_bytes(path)?;
    parse_png(&bytes, path, opts)
}

/// The grid of a PNG height map from its header, without decoding its samples.
pub fn read_png_header(path: &Path, opts: &DemOptions) -> Result<GridShape> {
    opts.check_one_band(path, "PNG")?;
    let spacing = spacing(path, opts)?;
    let (file, len) = open_with_len(path)?;
    let file = std::io::BufReader::new(file);
    let mut decoder = png::Decoder::new_with_limits(file, png::Limits { bytes: 1 << 31 });
    decoder.set_transformations(png::Transformations::IDENTITY);
    let reader = decoder
        .read_info()
        .map_err(|e| TinError::format(path, format!("not a readable PNG: {e}")))?;
    let info = reader.info();
    check_info(info, path, len)?;
    let (cols, rows) = (info.width as usize, info.height as usize);
    Ok(GridShape {
        rows,
        cols,
        dx: spacing.0,
        dy: spacing.1,
        origin: DVec2::new(0.0, (rows as f64 - 1.0) * spacing.1),
    })
}

/// The spacing, which a PNG needs from the options.
fn spacing(path: &Path, opts: &DemOptions) -> Result<(f64, f64)> {
    opts.spacing.ok_or_else(|| {
        TinError::InvalidParameter(format!(
            "{}: a PNG height map has no georeference: the sample spacing must be given (`--spacing dx,dy`)",
            path.display()
        ))
    })
}

/// The most bytes a Deflate stream (RFC 1951), which holds a PNG's image data, inflates to per byte of the stream.
///
/// A stream is blocks of symbols. A stored block gives one byte per byte it holds. In a Huffman-coded block every
/// symbol takes at least one bit (a code of a used symbol is at least one bit long, even when it is the only one of
/// its tree), a literal gives one byte, and a match takes a length symbol and a distance symbol, at least two bits,
/// for at most 258 bytes. So no bit gives more than 129 bytes, and no byte of the stream more than 8 · 129 = 1032;
/// block headers, the zlib header and checksum and the PNG's other bytes only lower the ratio. A file of `n` bytes
/// therefore holds at most 1032 `n` bytes of image data, whatever its header claims.
const DEFLATE_MAX_RATIO: u64 = 1032;

/// Refuses images too large, other than 8- or 16-bit grayscale, or larger than a file of `file_len` bytes can hold
/// ([`DEFLATE_MAX_RATIO`]).
fn check_info(info: &png::Info, path: &Path, file_len: u64) -> Result<()> {
    let err = |m: String| TinError::format(path, m);
    let (color, depth) = (info.color_type, info.bit_depth);
    if u64::from(info.width) * u64::from(info.height) > MAX_SAMPLES {
        return Err(err(format!(
            "{} x {} samples is more than the {MAX_SAMPLES} supported",
            info.width, info.height
        )));
    }
    if color != png::ColorType::Grayscale || !matches!(depth, png::BitDepth::Eight | png::BitDepth::Sixteen) {
        let colour = match color {
            png::ColorType::Grayscale => "a greyscale",
            png::ColorType::Rgb => "an RGB",
            png::ColorType::Indexed => "an indexed (palette)",
            png::ColorType::GrayscaleAlpha => "a greyscale-with-alpha",
            png::ColorType::Rgba => "an RGBA",
        };
        return Err(err(format!(
            "{colour} image with {} bits per sample: only 8- or 16-bit greyscale height maps are supported",
            depth as u8
        )));
    }
    let sample_bytes = if depth == png::BitDepth::Sixteen { 2 } else { 1 };
    let needed = u64::from(info.width) * u64::from(info.height) * sample_bytes;
    let most = file_len.saturating_mul(DEFLATE_MAX_RATIO);
    if needed > most {
        return Err(err(format!(
            "{} x {} samples of {sample_bytes} bytes take {needed} bytes, but a PNG of {file_len} bytes inflates to at \
             most {most}: a truncated file, or a header that claims more than the file holds",
            info.width, info.height
        )));
    }
    Ok(())
}

/// Parses a PNG height map held in memory; `path` names it in errors.
pub fn parse_png(bytes: &[u8], path: &Path, opts: &DemOptions) -> Result<Grid> {
    let spacing = spacing(path, opts)?;
    let err = |m: String| TinError::format(path, m);
    let mut decoder = png::Decoder::new_with_limits(Cursor::new(bytes), png::Limits { bytes: 1 << 31 });
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder
        .read_info()
        .map_err(|e| err(format!("not a readable PNG: {e}")))?;
    let info = reader.info();
    check_info(info, path, bytes.len() as u64)?;
    let (cols, rows, depth) = (info.width as usize, info.height as usize, info.bit_depth);
    let mut z = Vec::new();
    if info.interlaced {
        // Seven passes over the image: decoded whole.
        let size = reader
            .output_buffer_size()
            .ok_or_else(|| err("image too large".into()))?;
        let mut buf = vec![0u8; size];
        let frame = reader
            .next_frame(&mut buf)
            .map_err(|e| err(format!("truncated or corrupt PNG: {e}")))?;
        z.reserve_exact(rows * cols);
        for r in 0..rows {
            push_row(&mut z, &buf[r * frame.line_size..], cols, depth);
        }
    } else {
        // Row by row, with room for at most twice the rows decoded so far (and never more than the image): memory
        // grows with the data the file holds, so a small file whose header claims a huge image is refused without
        // allocating it.
        each_row(&mut reader, path, |_, row| {
            grow_with_data(&mut z, row.len(), rows * cols);
            z.append(row);
            Ok(())
        })?;
    }
    let origin = DVec2::new(0.0, (rows as f64 - 1.0) * spacing.1);
    finish(path, rows, cols, spacing, origin, z, opts)
}

/// Appends the `cols` values of one decoded row of samples of `depth` bits.
fn push_row(z: &mut Vec<f64>, line: &[u8], cols: usize, depth: png::BitDepth) {
    for c in 0..cols {
        z.push(match depth {
            png::BitDepth::Sixteen => f64::from(u16::from_be_bytes([line[2 * c], line[2 * c + 1]])),
            _ => f64::from(line[c]),
        });
    }
}

/// Decodes a PNG height map's rows once, in order, handing its values out in strips of `strip_rows` rows (not
/// scaled): `each(first_row, values)`. An interlaced image is decoded whole first.
pub(super) fn read_png_strips(
    path: &Path,
    opts: &DemOptions,
    strip_rows: usize,
    each: &mut dyn FnMut(usize, &mut Vec<f64>) -> Result<()>,
) -> Result<()> {
    let err = |m: String| TinError::format(path, m);
    let strip_rows = strip_rows.max(1);
    let (file, len) = open_with_len(path)?;
    let file = std::io::BufReader::new(file);
    let mut decoder = png::Decoder::new_with_limits(file, png::Limits { bytes: 1 << 31 });
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder
        .read_info()
        .map_err(|e| err(format!("not a readable PNG: {e}")))?;
    let info = reader.info();
    check_info(info, path, len)?;
    if info.interlaced {
        let grid = read_png(path, &DemOptions { z_scale: 1.0, ..*opts })?;
        for (i, strip) in grid.z.chunks(strip_rows * grid.cols).enumerate() {
            each(i * strip_rows, &mut strip.to_vec())?;
        }
        return Ok(());
    }
    let (cols, rows) = (info.width as usize, info.height as usize);
    let mut z = Vec::with_capacity(strip_rows.min(rows) * cols);
    let mut first = 0;
    each_row(&mut reader, path, |r, row| {
        z.append(row);
        if z.len() == strip_rows * cols || r + 1 == rows {
            each(first, &mut z)?;
            first += strip_rows;
            z.clear();
        }
        Ok(())
    })
}

/// Decodes the rows of a non-interlaced PNG in order, handing each one's values (not scaled) to `f(row, values)`,
/// which may take them.
fn each_row<R: std::io::BufRead + std::io::Seek>(
    reader: &mut png::Reader<R>,
    path: &Path,
    mut f: impl FnMut(usize, &mut Vec<f64>) -> Result<()>,
) -> Result<()> {
    let info = reader.info();
    let (cols, rows, depth) = (info.width as usize, info.height as usize, info.bit_depth);
    let mut values = Vec::with_capacity(cols);
    for r in 0..rows {
        let row = reader
            .next_row()
            .map_err(|e| TinError::format(path, format!("truncated or corrupt PNG: {e}")))?
            .ok_or_else(|| TinError::format(path, format!("truncated PNG: {r} of its {rows} rows")))?;
        values.clear();
        push_row(&mut values, row.data(), cols, depth);
        f(r, &mut values)?;
    }
    Ok(())
}
