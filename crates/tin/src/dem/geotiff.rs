//! GeoTIFF elevation rasters (`.tif`, `.tiff`), read with the `tiff` crate (no GDAL; ZSTD through the `zstd` crate,
//! which builds its own libzstd).
//!
//! What is read:
//! - one image (the first IFD) of a classic TIFF or a BigTIFF; samples int8/16/32/64, uint8/16/32/64, float32 or
//!   float64, in strips or tiles, uncompressed, LZW, Deflate, PackBits or ZSTD (GDAL's `COMPRESS=ZSTD`), with no
//!   predictor, the horizontal predictor (2) or the floating-point predictor (3): whatever the `tiff` crate decodes.
//!   Strips and tiles are decoded one by one at their full padded width (see `decode_window`); a whole-file read
//!   decodes at most [`MAX_DECODED_BYTES`] and [`MAX_SAMPLES`] samples, a file that ends before the data its tags
//!   point at is named as truncated, an uncompressed strip or tile whose byte count is too small for its samples is
//!   refused, and the heights grow with the strips and tiles decoded (a small file whose tags claim a huge image is
//!   refused without allocating it);
//! - one band: a single-band image, or band [`DemOptions::band`] (1-based, like GDAL) of an interleaved multi-band
//!   image; a multi-band image without a chosen band is an error;
//! - `GDAL_NODATA` (tag 42113): samples equal to it become voids, as do NaN samples; for float32 samples, also those
//!   equal to it rounded to float32 (a value within 1e-5 of the largest float32, like `-3.40282e+38`, being that
//!   largest float32);
//! - GDAL's band scale and offset (`GDAL_METADATA`, tag 42112: the `<Item>`s of roles `scale` and `offset` of the
//!   band read): heights are `sample · scale + offset` (voids are judged on the raw sample, as GDAL does);
//! - the georeference: ModelPixelScale (33550) + one ModelTiepoint (33922), or a ModelTransformation (34264) without
//!   rotation or shear; north-up only (row 0 north). `GTRasterTypeGeoKey` says whether the tie point is the corner
//!   of a pixel (pixel-is-area, the default) or its centre (pixel-is-point); the grid origin is always the centre of
//!   the north-west sample.
//!
//! Coordinate reference systems (`GeoKeyDirectory`, tag 34735):
//! - **Projected** (`GTModelTypeGeoKey` = 1) in metres (`ProjLinearUnitsGeoKey` = 9001, or absent with a UTM
//!   `ProjectedCSTypeGeoKey`: EPSG 326xx/327xx, 269xx, 267xx, 258xx, 322xx/323xx): coordinates are used as they are.
//!   In international feet (9002, 0.3048 m) or US survey feet (9003, 1200/3937 m), as US state-plane rasters are:
//!   coordinates and spacing are multiplied into metres. Other linear units are an error.
//! - Heights are in the unit of `VerticalUnitsGeoKey` (4099: metres, international or US survey feet; others are an
//!   error) and put into metres; without it, in metres, except under a projected CRS in feet, where they are taken
//!   to be in the same feet ([`GeoTiffInfo::heights_unit_assumed`]; `--z-scale` corrects them).
//! - **Geographic** (`GTModelTypeGeoKey` = 2; EPSG:4326 and any datum) in degrees (`GeogAngularUnitsGeoKey` 9102 or
//!   9122, or absent), arc-minutes (9103) or arc-seconds (9104): converted to metres in the same local frame as
//!   SRTM `.hgt` tiles ([`super::hgt`]): 1° of latitude is 111,320 m, 1° of longitude is `111,320 · cos(φc)` m with
//!   φc the latitude midway between the northern and southern sample rows; x is metres east of the western sample
//!   column (column 0 at x = 0), y is `latitude · 111,320` (the southern row at `south · 111,320`). A spacing within
//!   10⁻⁹ (relative) of 1/n degree for a whole n is taken as exactly 1/n degree, because writers store 3″ as
//!   0.000833…; so a GeoTIFF written from an `.hgt` tile reads to exactly the tile's grid.
//! - No GeoKeyDirectory but a pixel scale and tie point (or a transformation): georeferenced in metres, no CRS, and
//!   pixel-is-area (as GDAL reads it).
//! - No GeoKeyDirectory and no georeference (a plain TIFF): read like a 16-bit PNG height map ([`super::png`]) when
//!   [`DemOptions::spacing`] is given (metres, the south-western sample at (0, 0)), an error otherwise.
//! - A geocentric or user-defined model, radians or grads, a rotated or sheared transformation,
//!   several tie points, or a south-up raster are errors naming the file and the tag.
//!
//! [`DemOptions::spacing`] overrides the spacing (the origin stays where the georeference puts it). GDAL's nodata
//! masks (an internal mask image, or a `.msk` file) are applied, whole and in windows: a sample they mark invalid is
//! a void ([`super::tiff_mask`]).
//! [`read_geotiff_info`] also returns what was found ([`GeoTiffInfo`]: the CRS, units, raster type, the native
//! bounding box), which `tincull info` prints.

use std::io::{Cursor, Read, Seek};
use std::path::Path;

use glam::DVec2;
use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::Tag;

use super::{
    DemOptions, GridShape, MAX_SAMPLES, check_window, finish, grow_with_data, open, open_with_len, read_bytes,
};
use super::{degrees, tiff_mask};
use crate::error::{Result, TinError};
use crate::grid::Grid;

/// GeoKey ids used here (GeoTIFF 1.1, section 7).
mod key {
    pub const MODEL_TYPE: u16 = 1024;
    pub const RASTER_TYPE: u16 = 1025;
    pub const CITATION: u16 = 1026;
    pub const GEOGRAPHIC_TYPE: u16 = 2048;
    pub const GEOG_CITATION: u16 = 2049;
    pub const GEOG_ANGULAR_UNITS: u16 = 2054;
    pub const PROJECTED_CS_TYPE: u16 = 3072;
    pub const PCS_CITATION: u16 = 3073;
    pub const PROJ_LINEAR_UNITS: u16 = 3076;
    pub const VERTICAL_UNITS: u16 = 4099;
}

/// The most decoded sample bytes a GeoTIFF may have (1 GiB); larger images are refused, not read.
pub const MAX_DECODED_BYTES: usize = 1 << 30;

/// The most bytes one strip or tile may decode to, its padding included, when that is more than the whole image
/// (64 MiB: a tile of 4096 x 4096 float32 samples): a tile larger than its image is padding, and a file whose
/// padding would take more is refused rather than decoded.
const MAX_CHUNK_PADDING: u64 = 64 << 20;

/// The tag of GDAL's nodata value.
const GDAL_NODATA: u16 = 42113;
/// The tag of GDAL's metadata (XML), which holds a band's scale and offset.
const GDAL_METADATA: u16 = 42112;
/// The GeoTIFF tag holding GeoKey ASCII parameters.
const GEO_ASCII_PARAMS: u16 = 34737;

/// The kind of coordinate reference system of a GeoTIFF.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CrsKind {
    /// A projected CRS in metres: coordinates used as they are.
    Projected,
    /// A geographic CRS (latitude/longitude): converted to metres like `.hgt` tiles.
    Geographic,
}

/// Whether the tie point names a pixel's corner or its centre (`GTRasterTypeGeoKey`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RasterType {
    /// Pixel-is-area (1, the default): raster coordinate (0, 0) is the north-west corner of the first pixel.
    PixelIsArea,
    /// Pixel-is-point (2): raster coordinate (0, 0) is the centre of the first pixel.
    PixelIsPoint,
}

/// What a GeoTIFF says about itself, beyond the grid.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GeoTiffInfo {
    /// Projected (metres) or geographic (degrees, converted).
    pub crs_kind: CrsKind,
    /// The EPSG code of the projected or geographic CRS, when the file gives one.
    pub epsg: Option<u16>,
    /// The CRS in words, e.g. `EPSG:26910 (projected, metres)`, with the file's citation when it has one.
    pub crs: String,
    /// How the native coordinates and heights became metres (empty when they were metres).
    pub conversion: String,
    /// Whether the heights were taken to be in the projected CRS's feet without the file saying so (no
    /// `VerticalUnitsGeoKey`): `--z-scale` corrects them when they are not.
    #[serde(default)]
    pub heights_unit_assumed: bool,
    /// Metres per unit of the file's heights (1 unless they are feet).
    #[serde(default = "one")]
    pub height_unit_m: f64,
    /// Pixel-is-area or pixel-is-point.
    pub raster_type: RasterType,
    /// Native bounding box of the sample centres: (west, south, east, north), in the CRS's units (degrees for
    /// geographic CRSs).
    pub native_bbox: [f64; 4],
    /// Native sample spacing (x, y) in the CRS's units.
    pub native_spacing: (f64, f64),
    /// The `GDAL_NODATA` value, if any.
    pub nodata: Option<f64>,
    /// The sample type, e.g. `int16`, `float32`.
    pub sample_type: String,
    /// The TIFF compression (`none`, `lzw`, `deflate`, …) and predictor (`none`, `horizontal`, `floating-point`).
    pub compression: String,
    /// `strips` or `tiles`.
    pub layout: String,
    /// Number of bands (samples per pixel), and the one read (1-based).
    pub bands: (u16, u16),
    /// GDAL's scale and offset of the band read (`GDAL_METADATA` items of roles `scale` and `offset`): heights are
    /// `sample · scale + offset`. `None` when the file gives neither.
    #[serde(default)]
    pub scale_offset: Option<(f64, f64)>,
    /// GDAL's nodata mask applied to the samples ([`super::tiff_mask`]), in words with the number of samples it
    /// voided; `None` when the file has none. Filled by a whole read ([`read_geotiff_info`]).
    #[serde(default)]
    pub nodata_mask: Option<String>,
}

/// 1, the default of [`GeoTiffInfo::height_unit_m`] in files written before it.
fn one() -> f64 {
    1.0
}

/// Reads a GeoTIFF DEM (see the module documentation), checked as [`read_geotiff_info`] checks it.
pub fn read_geotiff(path: &Path, opts: &DemOptions) -> Result<Grid> {
    read_geotiff_info(path, opts).map(|(g, _)| g)
}

/// Reads a GeoTIFF DEM and what its tags say ([`GeoTiffInfo`]); the grid's coordinates, spacing and heights are
/// checked as [`crate::read_dem`] checks them.
pub fn read_geotiff_info(path: &Path, opts: &DemOptions) -> Result<(Grid, GeoTiffInfo)> {
    let (grid, info) = read_geotiff_unchecked(path, opts)?;
    super::check_range(&grid, path, opts.z_scale)?;
    Ok((grid, info))
}

/// [`read_geotiff_info`] without the checks of the grid's coordinates, spacing and heights ([`crate::read_dem`] makes
/// them).
pub(crate) fn read_geotiff_unchecked(path: &Path, opts: &DemOptions) -> Result<(Grid, GeoTiffInfo)> {
    opts.check()?;
    let bytes = read_bytes(path)?;
    parse_geotiff(&bytes, path, opts)
}

/// Parses the bytes of a GeoTIFF; `path` names it in errors. The grid's coordinates, spacing and heights are not
/// checked ([`read_geotiff_info`] and [`crate::read_dem`] check them).
pub fn parse_geotiff(bytes: &[u8], path: &Path, opts: &DemOptions) -> Result<(Grid, GeoTiffInfo)> {
    opts.check()?;
    let err = |m: String| TinError::format(path, m);
    let (mut dec, meta) = open_tiff(Cursor::new(bytes), path, opts)?;
    let (rows, cols) = (meta.shape.rows, meta.shape.cols);
    let decoded = rows
        .checked_mul(cols)
        .and_then(|n| n.checked_mul(meta.stride))
        .and_then(|n| n.checked_mul(meta.sample_bytes.max(1)));
    if decoded.is_none_or(|b| b > MAX_DECODED_BYTES) {
        return Err(err(format!(
            "{cols} x {rows} samples of {} bytes are more than the {} MiB a whole-file read decodes; \
             `tincull tiles plan` reads a DEM this large in windows",
            meta.sample_bytes.max(1) * meta.stride,
            MAX_DECODED_BYTES >> 20
        )));
    }
    if (rows as u64).saturating_mul(cols as u64) > MAX_SAMPLES {
        return Err(err(format!(
            "{cols} x {rows} samples are more than the {MAX_SAMPLES} a whole-file read holds; \
             `tincull tiles plan` reads a DEM this large in windows"
        )));
    }
    if rows == 0 || cols == 0 {
        return Err(err(format!("the image has {cols} x {rows} samples")));
    }
    let whole = [[0, rows - 1], [0, cols - 1]];
    let (sample_type, mut z) = decode_window(
        &mut dec,
        &meta,
        whole[0],
        whole[1],
        bytes.len() as u64,
        path,
        &mut Band::default(),
    )?;
    let nodata_mask = match tiff_mask::find_mask(path, Cursor::new(bytes)) {
        Some(mask) => {
            let shape = (rows, cols);
            let voided = tiff_mask::apply_mask(
                &mask,
                || Ok(Cursor::new(bytes)),
                path,
                shape,
                [0, rows - 1],
                [0, cols - 1],
                &mut z,
            )?;
            Some(format!("{}: {voided} samples voided", mask.describe()))
        }
        None => None,
    };
    let info = GeoTiffInfo {
        sample_type: sample_type.to_string(),
        nodata_mask,
        ..meta.info
    };
    let s = meta.shape;
    let grid = finish(path, rows, cols, (s.dx, s.dy), s.origin, z, opts)?;
    Ok((grid, info))
}

/// The grid of a GeoTIFF from its tags, without decoding its samples.
pub fn read_geotiff_header(path: &Path, opts: &DemOptions) -> Result<GridShape> {
    opts.check()?;
    let file = std::io::BufReader::new(open(path)?);
    Ok(open_tiff(file, path, opts)?.1.shape)
}

/// What the tags of a GeoTIFF say ([`GeoTiffInfo`], without the sample type), without decoding its samples.
pub fn read_geotiff_tags(path: &Path, opts: &DemOptions) -> Result<GeoTiffInfo> {
    opts.check()?;
    let file = std::io::BufReader::new(open(path)?);
    Ok(open_tiff(file, path, opts)?.1.info)
}

/// The samples of a window of a GeoTIFF (voids NaN, not scaled) and its whole grid: only the strips or tiles
/// (of the first plane) that meet the window are decoded.
pub(super) fn read_geotiff_window(
    path: &Path,
    opts: &DemOptions,
    rows: [usize; 2],
    cols: [usize; 2],
) -> Result<(GridShape, Vec<f64>)> {
    let mut reader = WindowReader::open(path, opts)?;
    let z = reader.read(rows, cols)?;
    Ok((reader.meta.shape, z))
}

/// A GeoTIFF opened once for many windows (a DEM read strip by strip): its decoder, its tags, its nodata mask and
/// the band of strips or tiles decoded last, so that windows that share a band (strips of rows narrower than the
/// file's strips or tiles) decode it once, not once a window.
pub(super) struct WindowReader<'p> {
    path: &'p Path,
    dec: Decoder<std::io::BufReader<std::fs::File>>,
    meta: Meta,
    len: u64,
    mask: Option<tiff_mask::MaskSource>,
    band: Band,
}

impl<'p> WindowReader<'p> {
    /// Opens the GeoTIFF at `path` and reads its tags.
    pub(super) fn open(path: &'p Path, opts: &DemOptions) -> Result<WindowReader<'p>> {
        let (file, len) = open_with_len(path)?;
        let (dec, meta) = open_tiff(std::io::BufReader::new(file), path, opts)?;
        let mask = tiff_mask::find_mask(path, std::io::BufReader::new(open(path)?));
        Ok(WindowReader {
            path,
            dec,
            meta,
            len,
            mask,
            band: Band::default(),
        })
    }

    /// The samples of rows `rows[0]..=rows[1]` and columns `cols[0]..=cols[1]` (voids NaN, not scaled).
    pub(super) fn read(&mut self, rows: [usize; 2], cols: [usize; 2]) -> Result<Vec<f64>> {
        let (path, shape) = (self.path, self.meta.shape);
        check_window(&shape, rows, cols, path)?;
        let (_, mut z) = decode_window(&mut self.dec, &self.meta, rows, cols, self.len, path, &mut self.band)?;
        if let Some(mask) = &self.mask {
            let reopen = || open(path).map(std::io::BufReader::new);
            tiff_mask::apply_mask(mask, reopen, path, (shape.rows, shape.cols), rows, cols, &mut z)?;
        }
        Ok(z)
    }
}

/// The strips or tiles of one band (a row of them across the image) decoded last: its index and, per chunk, its
/// index, samples and row stride.
#[derive(Default)]
struct Band {
    index: Option<usize>,
    chunks: Vec<(u32, Samples, usize)>,
}

/// Decodes the samples of rows `rows[0]..=rows[1]` and columns `cols[0]..=cols[1]` (a window inside the image) of
/// the band `meta` names, strip by strip or tile by tile, as heights (voids NaN, not scaled), with the sample type's
/// name. Only the strips or tiles (of the first plane) that meet the window are decoded. `file_len` (bytes) names a
/// truncated file as such.
///
/// Memory follows the data, not the header: a window of more than [`MAX_SAMPLES`] is refused, and the window's heights
/// grow band by band (a row of strips or tiles across the window) as the bands decode, to at most twice the samples
/// decoded, so a small file whose tags claim a huge image made of data it does not hold is refused, at the first strip
/// or tile that is missing, without allocating the image.
///
/// A strip or tile is decoded with its full padded width as the row stride: the `tiff` crate (0.11) fails on an LZW
/// tile at the right edge of an image that its tiles do not divide when asked for the unpadded width (it skips the
/// padding of the last row past the end of the LZW stream), and GDAL writes such files by default.
fn decode_window<R: Read + Seek>(
    dec: &mut Decoder<R>,
    meta: &Meta,
    rows: [usize; 2],
    cols: [usize; 2],
    file_len: u64,
    path: &Path,
    band: &mut Band,
) -> Result<(&'static str, Vec<f64>)> {
    let err = |m: String| TinError::format(path, m);
    let shape = meta.shape;
    let (cw, ch) = dec.chunk_dimensions();
    let (cw, ch) = (cw as usize, ch as usize);
    if cw == 0 || ch == 0 {
        return Err(err(format!("chunks of {cw} x {ch} samples")));
    }
    let across = shape.cols.div_ceil(cw);
    let nc = cols[1] - cols[0] + 1;
    let samples = (rows[1] - rows[0] + 1) as u64 * nc as u64;
    if samples > MAX_SAMPLES {
        return Err(err(format!(
            "a window of {nc} x {} samples is more than the {MAX_SAMPLES} read at once",
            rows[1] - rows[0] + 1
        )));
    }
    let mut z = Vec::new();
    let mut sample_type = "";
    let stride = meta.stride;
    for ty in rows[0] / ch..=rows[1] / ch {
        // The band of strips or tiles across the window: each one's samples inside the window, kept compactly until
        // the band is decoded, then appended to the heights row by row.
        let mut pieces: Vec<(usize, Vec<f64>)> = Vec::new();
        let mut band_rows = 0;
        if band.index != Some(ty) {
            *band = Band {
                index: Some(ty),
                chunks: Vec::new(),
            };
        }
        for tx in cols[0] / cw..=cols[1] / cw {
            let index = u32::try_from(ty * across + tx).map_err(|_| err("too many strips or tiles".into()))?;
            let (dw, dh) = dec.chunk_data_dimensions(index);
            let (dw, dh) = (dw as usize, dh as usize);
            if dw == 0 || dh == 0 {
                return Err(err(format!("strip or tile {index} has {dw} x {dh} samples")));
            }
            let cached = match band.chunks.iter().position(|c| c.0 == index) {
                Some(i) => i,
                None => {
                    let (values, row) = decode_chunk(dec, meta, index, [cw, ch], [dw, dh], file_len, path)?;
                    band.chunks.push((index, values, row));
                    band.chunks.len() - 1
                }
            };
            let (_, values, row) = &band.chunks[cached];
            let row = *row;
            sample_type = values
                .kind()
                .ok_or_else(|| err("float16 samples are not supported".into()))?;
            // The chunk's samples inside the window, in whole-grid rows and columns.
            let (y0, x0) = (ty * ch, tx * cw);
            let (r0, r1) = (rows[0].max(y0), rows[1].min(y0 + dh - 1));
            let (c0, c1) = (cols[0].max(x0), cols[1].min(x0 + dw - 1));
            if r1 < r0 || c1 < c0 || (!pieces.is_empty() && r1 - r0 + 1 != band_rows) {
                return Err(err(format!(
                    "strip or tile {index} ({dw} x {dh} samples) does not cover its part of rows {}..={} and \
                     columns {}..={}",
                    rows[0], rows[1], cols[0], cols[1]
                )));
            }
            band_rows = r1 - r0 + 1;
            let mut piece = Vec::with_capacity(band_rows * (c1 - c0 + 1));
            for r in r0..=r1 {
                let at = |c: usize| ((r - y0) * row + (c - x0)) * stride + meta.band - 1;
                piece.extend((c0..=c1).map(|c| meta.height(values.get(at(c)), sample_type)));
            }
            pieces.push((c1 - c0 + 1, piece));
        }
        // Memory follows the data: the heights grow with the bands decoded (see `grow_with_data`).
        grow_with_data(&mut z, band_rows * nc, samples as usize);
        for r in 0..band_rows {
            for (width, piece) in &pieces {
                z.extend_from_slice(&piece[r * width..(r + 1) * width]);
            }
        }
    }
    if z.len() != samples as usize {
        return Err(err(format!(
            "strips or tiles gave {} of the {samples} samples of rows {}..={} and columns {}..={}",
            z.len(),
            rows[0],
            rows[1],
            cols[0],
            cols[1]
        )));
    }
    Ok((sample_type, z))
}

/// Decodes strip or tile `index` (chunks of `cw` x `ch` samples, this one `dw` x `dh` of them data), refusing what
/// no real file holds first (see [`decode_window`]): its samples and their row stride.
#[allow(clippy::too_many_arguments)]
fn decode_chunk<R: Read + Seek>(
    dec: &mut Decoder<R>,
    meta: &Meta,
    index: u32,
    [cw, ch]: [usize; 2],
    [dw, dh]: [usize; 2],
    file_len: u64,
    path: &Path,
) -> Result<(Samples, usize)> {
    let err = |m: String| TinError::format(path, m);
    let (shape, stride) = (meta.shape, meta.stride);
    // Uncompressed samples are read from the chunk's offset on, whatever its byte count says: a count too small
    // for its rows is refused, or the samples would be read from the bytes that follow it.
    if let (Some(row_bytes), Some(&(_, count))) = (meta.uncompressed_row_bytes, meta.chunks.get(index as usize)) {
        let needed = row_bytes.saturating_mul(dh as u64);
        if count < needed {
            return Err(err(format!(
                "strip or tile {index} holds {count} bytes, but its {dw} x {dh} uncompressed samples \
                 take {needed}"
            )));
        }
    }
    // A tile may be wider than the image (it is padded), but one whose padding alone would take more than
    // the whole image, and more than `MAX_CHUNK_PADDING`, is no real file's: refused before it is decoded.
    let bytes = meta.sample_bytes.max(1) * stride;
    let padded = (if meta.sample_bytes > 0 { cw } else { dw } as u64) * dh as u64 * bytes as u64;
    let image = shape.rows as u64 * shape.cols as u64 * bytes as u64;
    if padded > image.max(MAX_CHUNK_PADDING) {
        return Err(err(format!(
            "strip or tile {index} of {cw} x {ch} samples decodes to {padded} bytes with its padding, more \
             than the whole {} x {} image's {image}",
            shape.cols, shape.rows
        )));
    }
    // Whole bytes per sample: decoded at the padded width (see above); else as the crate lays it out.
    let (chunk, row) = if meta.sample_bytes > 0 {
        let mut chunk = DecodingResult::U8(Vec::new());
        let row_bytes = cw * stride * meta.sample_bytes;
        dec.read_chunk_to_buffer(&mut chunk, index, row_bytes)
            .map(|()| (chunk, cw))
    } else {
        dec.read_chunk(index).map(|chunk| (chunk, dw))
    }
    .map_err(|e| chunk_error(meta, index, file_len, e, path))?;
    let values = Samples(chunk);
    let needed = ((dh - 1) * row + dw) * stride;
    if values.len() < needed {
        return Err(err(format!(
            "strip or tile {index}: decoded {} samples, expected {needed} ({dw} x {dh} x {stride})",
            values.len(),
        )));
    }
    Ok((values, row))
}

/// The error of a strip or tile that cannot be decoded: a file that ends before the data its tags point at is
/// named as truncated.
fn chunk_error(meta: &Meta, index: u32, file_len: u64, e: tiff::TiffError, path: &Path) -> TinError {
    let what = format!("cannot decode strip or tile {index} ({})", meta.info.compression);
    let short = matches!(&e, tiff::TiffError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof);
    let end = meta
        .chunks
        .get(index as usize)
        .map(|&(offset, count)| offset.saturating_add(count));
    match end {
        Some(end) if short && end > file_len => TinError::format(
            path,
            format!("{what}: its data runs to byte {end}, but the file has {file_len} bytes (a truncated file?)"),
        ),
        _ => TinError::format(path, format!("{what}: {e}")),
    }
}

/// What the tags of a GeoTIFF say: its grid, the band to read and how voids are marked.
struct Meta {
    shape: GridShape,
    /// The band read (1-based) and the samples per pixel of a decoded chunk or image.
    band: usize,
    stride: usize,
    /// Bytes per sample (0 when samples are not whole bytes).
    sample_bytes: usize,
    /// Per strip or tile, its offset in the file and its byte count, where the tags say.
    chunks: Vec<(u64, u64)>,
    /// Bytes of one stored row of a strip or tile (of one plane) when the samples are not compressed.
    uncompressed_row_bytes: Option<u64>,
    /// GDAL's scale and offset of the band read.
    scale_offset: Option<(f64, f64)>,
    /// Metres per unit of the heights (1 unless the file's units are feet).
    height_unit: f64,
    nodata: Option<f64>,
    /// What the tags say, but the sample type (known once samples are decoded).
    info: GeoTiffInfo,
}

impl Meta {
    /// The height of a decoded sample: NaN for voids (NaN, the nodata value, or for float32 samples the nodata
    /// value rounded to float32; a nodata value within 1e-5 (relative) of the largest float32, such as the short form
    /// `-3.40282e+38`, stands for that largest float32, as GDAL reads it).
    fn height(&self, v: f64, sample_type: &str) -> f64 {
        let single = |nd: f64| {
            if nd.is_finite() && nd.abs() >= f64::from(f32::MAX) * (1.0 - 1e-5) {
                f32::MAX.copysign(nd as f32)
            } else {
                nd as f32
            }
        };
        let void = v.is_nan()
            || self.nodata.is_some_and(|nd| v == nd)
            || (sample_type == "float32" && self.nodata.is_some_and(|nd| v as f32 == single(nd)));
        match (void, self.scale_offset) {
            (true, _) => f64::NAN,
            (false, Some((scale, offset))) => (v * scale + offset) * self.height_unit,
            (false, None) => v * self.height_unit,
        }
    }
}

/// The scale and offset of band `band` (1-based) in GDAL's metadata XML: its `<Item>`s of `role="scale"` and
/// `role="offset"` with `sample="band − 1"` (a missing one is 1 or 0). `None` when neither is there; an error naming
/// the item when a value is not a finite number (a zero scale included).
fn gdal_scale_offset(xml: &str, band: usize, path: &Path) -> Result<Option<(f64, f64)>> {
    let sample = format!("sample=\"{}\"", band - 1);
    let mut found = (None, None);
    for item in xml.split("<Item").skip(1) {
        let Some((attributes, rest)) = item.split_once('>') else {
            continue;
        };
        if !attributes.contains(&sample) {
            continue;
        }
        let slot = if attributes.contains("role=\"scale\"") {
            &mut found.0
        } else if attributes.contains("role=\"offset\"") {
            &mut found.1
        } else {
            continue;
        };
        let text = rest.split('<').next().unwrap_or("").trim();
        let value = text.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| {
            TinError::format(
                path,
                format!("tag GDAL_METADATA (42112): the item <Item{attributes}> holds {text:?}, not a finite number"),
            )
        })?;
        *slot = Some(value);
    }
    if found.0 == Some(0.0) {
        return Err(TinError::format(path, "tag GDAL_METADATA (42112): band scale 0"));
    }
    Ok(match found {
        (None, None) => None,
        (scale, offset) => Some((scale.unwrap_or(1.0), offset.unwrap_or(0.0))),
    })
}

/// The error for a TIFF compression that is not read, naming the ones GDAL writes and how to convert the file.
fn unread_compression(code: u64) -> String {
    let name = match code {
        6 | 7 => " (JPEG)",
        34712 => " (JPEG 2000)",
        34887 => " (LERC)",
        34925 => " (LZMA)",
        50001 => " (WebP)",
        50002 => " (JPEG XL)",
        _ => "",
    };
    format!(
        "compression {code}{name} is not read (none, LZW, Deflate, PackBits and ZSTD are): convert the file first, \
         e.g. `gdal_translate -co COMPRESS=DEFLATE IN.tif OUT.tif`"
    )
}

/// Opens a TIFF, reads its tags and georeference ([`Meta`]).
fn open_tiff<R: Read + Seek>(reader: R, path: &Path, opts: &DemOptions) -> Result<(Decoder<R>, Meta)> {
    let err = |m: String| TinError::format(path, m);
    let tiff_err = |what: &str, e: tiff::TiffError| TinError::format(path, format!("{what}: {e}"));
    let mut dec = Decoder::new(reader).map_err(|e| tiff_err("not a readable TIFF", e))?;
    // Bounded memory on hostile headers: at most 1 GiB of decoded samples (a 16k x 16k float32 DEM) and 256 MiB
    // per compressed strip or tile.
    let mut limits = Limits::default();
    limits.decoding_buffer_size = MAX_DECODED_BYTES;
    limits.intermediate_buffer_size = 1 << 28;
    dec = dec.with_limits(limits);
    let (width, height) = dec
        .dimensions()
        .map_err(|e| tiff_err("image size (ImageWidth/ImageLength)", e))?;
    let (cols, rows) = (width as usize, height as usize);

    // Tags, read before the samples.
    let spp: u16 = find_u64(&mut dec, Tag::SamplesPerPixel, path)?
        .unwrap_or(1)
        .try_into()
        .unwrap_or(u16::MAX);
    let planar = find_u64(&mut dec, Tag::PlanarConfiguration, path)?.unwrap_or(1);
    let compression = match find_u64(&mut dec, Tag::Compression, path)?.unwrap_or(1) {
        1 => "none".to_string(),
        5 => "lzw".to_string(),
        8 | 32946 => "deflate".to_string(),
        32773 => "packbits".to_string(),
        50000 => "zstd".to_string(),
        c => return Err(err(unread_compression(c))),
    };
    let predictor = match find_u64(&mut dec, Tag::Predictor, path)?.unwrap_or(1) {
        1 => "none".to_string(),
        2 => "horizontal".to_string(),
        3 => "floating-point".to_string(),
        p => format!("predictor {p}"),
    };
    let layout = if dec.find_tag(Tag::TileWidth).ok().flatten().is_some() {
        "tiles"
    } else {
        "strips"
    };
    let nodata = match dec.find_tag(Tag::Unknown(GDAL_NODATA)) {
        Ok(Some(v)) => {
            let s = v
                .into_string()
                .map_err(|e| tiff_err("tag GDAL_NODATA (42113) is not text", e))?;
            let t = s.trim_matches(|c: char| c == '\0' || c.is_whitespace());
            Some(parse_nodata(t).ok_or_else(|| err(format!("tag GDAL_NODATA (42113): {t:?} is not a number")))?)
        }
        Ok(None) => None,
        Err(e) => return Err(tiff_err("tag GDAL_NODATA (42113)", e)),
    };
    let georef = read_georef(&mut dec, path, opts.spacing, rows)?;

    let band = match (spp, opts.band) {
        (1, None | Some(1)) => 1,
        (_, Some(0)) => return Err(err("band 0 requested: bands are numbered from 1".into())),
        (1, Some(b)) => {
            return Err(err(format!(
                "band {b} requested, but the image has 1 band (SamplesPerPixel)"
            )));
        }
        (n, None) => {
            return Err(err(format!(
                "the image has {n} bands (SamplesPerPixel = {n}): choose the elevation band (1..{n}) with `--band B`"
            )));
        }
        (n, Some(b)) if b == 0 || b > n => {
            return Err(err(format!(
                "band {b} requested, but the image has bands 1..{n} (SamplesPerPixel)"
            )));
        }
        (_, Some(b)) if planar == 2 && b != 1 => {
            return Err(err(format!(
                "band {b} of a planar (PlanarConfiguration = 2) multi-band image: only band 1 can be read"
            )));
        }
        (_, Some(b)) => b,
    };

    let stride = if planar == 2 { 1 } else { usize::from(spp) };
    let scale_offset = match dec.find_tag(Tag::Unknown(GDAL_METADATA)) {
        Ok(Some(v)) => match v.into_string() {
            Ok(xml) => gdal_scale_offset(&xml, usize::from(band), path)?,
            Err(e) => return Err(tiff_err("tag GDAL_METADATA (42112) is not text", e)),
        },
        Ok(None) => None,
        Err(e) => return Err(tiff_err("tag GDAL_METADATA (42112)", e)),
    };
    let bits = dec
        .get_tag_u64_vec(Tag::BitsPerSample)
        .ok()
        .and_then(|b| b.first().copied())
        .unwrap_or(1);
    let sample_bytes = if bits % 8 == 0 { (bits / 8) as usize } else { 0 };
    let (offsets, counts) = if layout == "tiles" {
        (Tag::TileOffsets, Tag::TileByteCounts)
    } else {
        (Tag::StripOffsets, Tag::StripByteCounts)
    };
    let chunks = match (dec.get_tag_u64_vec(offsets), dec.get_tag_u64_vec(counts)) {
        (Ok(o), Ok(c)) => o.into_iter().zip(c).collect(),
        _ => Vec::new(),
    };
    let uncompressed_row_bytes = (compression == "none").then(|| {
        let cw = u64::from(dec.chunk_dimensions().0);
        (cw.saturating_mul(stride as u64).saturating_mul(bits)).div_ceil(8)
    });
    // The georeference: native coordinates of the centre of sample (0, 0) and the native spacing.
    let c = match georef.raster_type {
        RasterType::PixelIsArea => 0.5,
        RasterType::PixelIsPoint => 0.0,
    };
    let (sx, sy) = georef.scale;
    let x0 = georef.tie_world.0 + (c - georef.tie_raster.0) * sx;
    let y0 = georef.tie_world.1 - (c - georef.tie_raster.1) * sy;
    let (x1, y1) = (x0 + (cols as f64 - 1.0) * sx, y0 - (rows as f64 - 1.0) * sy);
    let native_bbox = [x0, y1, x1, y0];
    if !native_bbox.iter().all(|v| v.is_finite()) {
        return Err(err(format!(
            "the georeference gives a non-finite bounding box {native_bbox:?}"
        )));
    }

    // Heights: in the unit `VerticalUnitsGeoKey` gives; without it, in the projected CRS's linear unit (metres for
    // every other CRS).
    let (height_unit, height_note) = match georef.height_unit {
        Some(u) => (u, "VerticalUnitsGeoKey"),
        None => (
            georef.linear_unit,
            "assumed: no VerticalUnitsGeoKey; --z-scale corrects them",
        ),
    };
    let (shape, mut conversion) = match georef.kind {
        CrsKind::Projected => {
            let m = georef.linear_unit.0;
            let (dx, dy) = opts.spacing.unwrap_or((sx * m, sy * m));
            let origin = DVec2::new(x0 * m, y0 * m);
            let conversion = if m == 1.0 {
                String::new()
            } else {
                format!("x, y in {} times {m} m", georef.linear_unit.1)
            };
            (
                GridShape {
                    rows,
                    cols,
                    dx,
                    dy,
                    origin,
                },
                conversion,
            )
        }
        CrsKind::Geographic => {
            let deg = georef.angular_unit_deg;
            degrees::grid_in_metres(rows, cols, x0 * deg, y0 * deg, (sx * deg, sy * deg), opts)
                .map_err(|m| err(format!("the GeoKeys say geographic, but {m}")))?
        }
    };
    if height_unit.0 != 1.0 {
        let sep = if conversion.is_empty() { "" } else { "; " };
        conversion = format!(
            "{conversion}{sep}heights in {} times {} m ({height_note})",
            height_unit.1, height_unit.0
        );
    }
    let info = GeoTiffInfo {
        crs_kind: georef.kind,
        epsg: georef.epsg,
        crs: georef.description,
        conversion,
        heights_unit_assumed: georef.height_unit.is_none() && height_unit.0 != 1.0,
        height_unit_m: height_unit.0,
        raster_type: georef.raster_type,
        native_bbox,
        native_spacing: (sx, sy),
        nodata,
        sample_type: String::new(),
        compression: format!("{compression}, predictor {predictor}"),
        layout: layout.to_string(),
        bands: (spp, band),
        scale_offset,
        nodata_mask: None,
    };
    let meta = Meta {
        shape,
        band: usize::from(band),
        stride,
        sample_bytes,
        chunks,
        uncompressed_row_bytes,
        scale_offset,
        height_unit: height_unit.0,
        nodata,
        info,
    };
    Ok((dec, meta))
}

/// Parses GDAL's nodata text (a decimal number, `nan`, `inf`, `-inf`).
fn parse_nodata(t: &str) -> Option<f64> {
    match t.to_ascii_lowercase().as_str() {
        "nan" | "-nan" => Some(f64::NAN),
        "inf" | "+inf" => Some(f64::INFINITY),
        "-inf" => Some(f64::NEG_INFINITY),
        s => s.parse().ok(),
    }
}

/// The samples of a decoded strip or tile, read one at a time as f64 (only those inside the window are: a chunk
/// is never copied whole into f64, which takes up to eight times its bytes).
struct Samples(DecodingResult);

impl Samples {
    /// The sample type's name, `None` for float16 (not read).
    fn kind(&self) -> Option<&'static str> {
        match self.0 {
            DecodingResult::U8(_) => Some("uint8"),
            DecodingResult::U16(_) => Some("uint16"),
            DecodingResult::U32(_) => Some("uint32"),
            DecodingResult::U64(_) => Some("uint64"),
            DecodingResult::I8(_) => Some("int8"),
            DecodingResult::I16(_) => Some("int16"),
            DecodingResult::I32(_) => Some("int32"),
            DecodingResult::I64(_) => Some("int64"),
            DecodingResult::F32(_) => Some("float32"),
            DecodingResult::F64(_) => Some("float64"),
            DecodingResult::F16(_) => None,
        }
    }

    /// How many samples were decoded.
    fn len(&self) -> usize {
        match &self.0 {
            DecodingResult::U8(v) => v.len(),
            DecodingResult::U16(v) => v.len(),
            DecodingResult::U32(v) => v.len(),
            DecodingResult::U64(v) => v.len(),
            DecodingResult::I8(v) => v.len(),
            DecodingResult::I16(v) => v.len(),
            DecodingResult::I32(v) => v.len(),
            DecodingResult::I64(v) => v.len(),
            DecodingResult::F32(v) => v.len(),
            DecodingResult::F64(v) => v.len(),
            DecodingResult::F16(v) => v.len(),
        }
    }

    /// Sample `i` (below [`Samples::len`]; NaN for float16, which [`Samples::kind`] refuses first).
    fn get(&self, i: usize) -> f64 {
        match &self.0 {
            DecodingResult::U8(v) => f64::from(v[i]),
            DecodingResult::U16(v) => f64::from(v[i]),
            DecodingResult::U32(v) => f64::from(v[i]),
            DecodingResult::U64(v) => v[i] as f64,
            DecodingResult::I8(v) => f64::from(v[i]),
            DecodingResult::I16(v) => f64::from(v[i]),
            DecodingResult::I32(v) => f64::from(v[i]),
            DecodingResult::I64(v) => v[i] as f64,
            DecodingResult::F32(v) => f64::from(v[i]),
            DecodingResult::F64(v) => v[i],
            DecodingResult::F16(_) => f64::NAN,
        }
    }
}

/// An optional unsigned tag, naming the file and tag on error.
fn find_u64<R: Read + Seek>(dec: &mut Decoder<R>, tag: Tag, path: &Path) -> Result<Option<u64>> {
    match dec.find_tag(tag) {
        Ok(None) => Ok(None),
        Ok(Some(v)) => v
            .into_u64()
            .map(Some)
            .map_err(|e| TinError::format(path, format!("tag {tag:?} ({}): {e}", tag.to_u16()))),
        Err(e) => Err(TinError::format(path, format!("tag {tag:?} ({}): {e}", tag.to_u16()))),
    }
}

/// An optional tag of doubles.
fn find_f64s<R: Read + Seek>(dec: &mut Decoder<R>, tag: Tag, name: &str, path: &Path) -> Result<Option<Vec<f64>>> {
    let e = |m: String| TinError::format(path, format!("tag {name} ({}): {m}", tag.to_u16()));
    match dec.find_tag(tag) {
        Ok(None) => Ok(None),
        Ok(Some(v)) => v.into_f64_vec().map(Some).map_err(|x| e(x.to_string())),
        Err(x) => Err(e(x.to_string())),
    }
}

/// The pixel scale and tie point, or the transformation: native spacing (x east, y south), the tie point's raster
/// (column, row) and native (x, y) coordinates; None when the file has neither.
type ModelTransform = ((f64, f64), (f64, f64), (f64, f64));

/// Reads [`ModelTransform`] from the tags ModelPixelScale and ModelTiepoint, or ModelTransformation (no rotation).
fn model_transform<R: Read + Seek>(dec: &mut Decoder<R>, path: &Path) -> Result<Option<ModelTransform>> {
    let err = |m: String| TinError::format(path, m);
    let scale = find_f64s(dec, Tag::ModelPixelScaleTag, "ModelPixelScale", path)?;
    let tie = find_f64s(dec, Tag::ModelTiepointTag, "ModelTiepoint", path)?;
    let transform = find_f64s(dec, Tag::ModelTransformationTag, "ModelTransformation", path)?;
    let georef = match (scale, tie, transform) {
        (Some(s), Some(t), _) => {
            if s.len() < 2 {
                return Err(err(format!(
                    "tag ModelPixelScale (33550) has {} values, expected 3",
                    s.len()
                )));
            }
            if t.len() != 6 {
                return Err(err(format!(
                    "tag ModelTiepoint (33922) has {} values: exactly one tie point (6 values) is supported, \
                     several tie points (a warped raster) are not",
                    t.len()
                )));
            }
            if !(s[0].is_finite() && s[1].is_finite() && s[0] > 0.0) || s[1] == 0.0 {
                return Err(err(format!(
                    "tag ModelPixelScale (33550) = {:?}: the scales must be positive and finite",
                    &s[..2]
                )));
            }
            if s[1] < 0.0 {
                return Err(err(format!(
                    "tag ModelPixelScale (33550) has a negative y scale {}: south-up rasters are not supported",
                    s[1]
                )));
            }
            ((s[0], s[1]), (t[0], t[1]), (t[3], t[4]))
        }
        (_, _, Some(m)) => {
            if m.len() != 16 {
                return Err(err(format!(
                    "tag ModelTransformation (34264) has {} values, expected 16",
                    m.len()
                )));
            }
            let (a, b, d, e, f, h) = (m[0], m[1], m[3], m[4], m[5], m[7]);
            if b != 0.0 || e != 0.0 {
                return Err(err(format!(
                    "tag ModelTransformation (34264) rotates or shears the raster (terms {b}, {e}): not supported"
                )));
            }
            if !(a > 0.0 && a.is_finite() && f.is_finite() && f != 0.0) {
                return Err(err(format!(
                    "tag ModelTransformation (34264): pixel sizes {a} x {f} must be finite, x positive"
                )));
            }
            if f > 0.0 {
                return Err(err(format!(
                    "tag ModelTransformation (34264) has a positive y term {f}: south-up rasters are not supported"
                )));
            }
            ((a, -f), (0.0, 0.0), (d, h))
        }
        (None, _, None) => return Ok(None),
        (Some(_), None, None) => {
            return Err(err("ModelPixelScale (33550) without a ModelTiepoint (33922)".into()));
        }
    };
    Ok(Some(georef))
}

/// The georeference of the image.
struct Georef {
    kind: CrsKind,
    epsg: Option<u16>,
    description: String,
    raster_type: RasterType,
    /// Degrees per native angular unit (geographic only).
    angular_unit_deg: f64,
    /// Metres per native linear unit (projected only; 1 for metres) and its name.
    linear_unit: (f64, &'static str),
    /// Metres per unit of the heights, when `VerticalUnitsGeoKey` gives it, and its name.
    height_unit: Option<(f64, &'static str)>,
    /// Native spacing (x east, y south), both positive.
    scale: (f64, f64),
    /// Raster coordinates (column, row) of the tie point.
    tie_raster: (f64, f64),
    /// Native coordinates (x, y) of the tie point.
    tie_world: (f64, f64),
}

/// The metre, as a linear unit: metres per unit and the unit's name.
const METRE: (f64, &str) = (1.0, "metres");

/// The linear unit of EPSG unit code `code` (GeoTIFF's `ProjLinearUnitsGeoKey` and `VerticalUnitsGeoKey`): metres
/// per unit and its name, for the metre (9001), the international foot (9002, 0.3048 m) and the US survey foot (9003,
/// 1200/3937 m); None for any other.
fn linear_unit_of(code: u16) -> Option<(f64, &'static str)> {
    match code {
        9001 => Some(METRE),
        9002 => Some((0.3048, "international feet")),
        9003 => Some((1200.0 / 3937.0, "US survey feet")),
        _ => None,
    }
}

/// Reads the GeoKeys, the pixel scale and tie point (or the transformation). Without a GeoKeyDirectory, a pixel scale
/// and tie point (or transformation) are taken as metres (no CRS, as GDAL reads such a file); a plain TIFF (neither)
/// is read like a PNG height map when a spacing is given: metres, the south-western sample at (0, 0).
fn read_georef<R: Read + Seek>(
    dec: &mut Decoder<R>,
    path: &Path,
    spacing: Option<(f64, f64)>,
    rows: usize,
) -> Result<Georef> {
    let err = |m: String| TinError::format(path, m);
    let dir = match dec.find_tag(Tag::GeoKeyDirectoryTag) {
        Ok(Some(v)) => v
            .into_u16_vec()
            .map_err(|e| err(format!("tag GeoKeyDirectory (34735): {e}")))?,
        Ok(None) => {
            if let Some((scale, tie_raster, tie_world)) = model_transform(dec, path)? {
                // GDAL reads such a file with its transform and no CRS: so do we, taking the units for metres.
                return Ok(Georef {
                    kind: CrsKind::Projected,
                    epsg: None,
                    description: "unknown (no GeoKeyDirectory, tag 34735): the pixel scale and tie point taken as \
                                  metres"
                        .into(),
                    raster_type: RasterType::PixelIsArea,
                    angular_unit_deg: 1.0,
                    linear_unit: METRE,
                    height_unit: None,
                    scale,
                    tie_raster,
                    tie_world,
                });
            }
            let Some((dx, dy)) = spacing else {
                return Err(err(
                    "no GeoKeyDirectory tag (34735): a plain TIFF has no georeference; give the \
                     sample spacing (`--spacing dx,dy`, in metres) or write it as a GeoTIFF"
                        .into(),
                ));
            };
            return Ok(Georef {
                kind: CrsKind::Projected,
                epsg: None,
                description: "none (a plain TIFF: the given spacing, the south-western sample at (0, 0))".into(),
                raster_type: RasterType::PixelIsPoint,
                angular_unit_deg: 1.0,
                linear_unit: METRE,
                height_unit: None,
                scale: (dx, dy),
                tie_raster: (0.0, 0.0),
                tie_world: (0.0, rows.saturating_sub(1) as f64 * dy),
            });
        }
        Err(e) => return Err(err(format!("tag GeoKeyDirectory (34735): {e}"))),
    };
    let ascii = match dec.find_tag(Tag::Unknown(GEO_ASCII_PARAMS)) {
        Ok(Some(v)) => v.into_string().unwrap_or_default(),
        _ => String::new(),
    };
    if dir.len() < 4 || dir.len() < 4 + 4 * usize::from(dir[3]) {
        return Err(err(format!(
            "tag GeoKeyDirectory (34735): {} values cannot hold the header and {} keys",
            dir.len(),
            dir.get(3).copied().unwrap_or(0)
        )));
    }
    let entries: Vec<&[u16]> = dir[4..4 + 4 * usize::from(dir[3])].chunks_exact(4).collect();
    let short = |id: u16| -> Option<u16> { entries.iter().find(|e| e[0] == id && e[1] == 0).map(|e| e[3]) };
    let text = |id: u16| -> Option<String> {
        let e = entries.iter().find(|e| e[0] == id && e[1] == GEO_ASCII_PARAMS)?;
        let (start, len) = (usize::from(e[3]), usize::from(e[2]));
        let s = ascii.get(start..start.checked_add(len)?)?;
        let s = s.trim_end_matches(['|', '\0']).trim();
        (!s.is_empty()).then(|| s.to_string())
    };

    let raster_type = match short(key::RASTER_TYPE) {
        None | Some(1) => RasterType::PixelIsArea,
        Some(2) => RasterType::PixelIsPoint,
        Some(v) => {
            return Err(err(format!(
                "GeoKey GTRasterTypeGeoKey (1025) = {v}: expected 1 (pixel-is-area) or 2 (pixel-is-point)"
            )));
        }
    };
    let citation = text(key::CITATION)
        .or_else(|| text(key::PCS_CITATION))
        .or_else(|| text(key::GEOG_CITATION));
    let cite = |s: String| match &citation {
        Some(c) => format!("{s}, \"{c}\""),
        None => s,
    };
    let (kind, epsg, description, angular_unit_deg, linear_unit) = match short(key::MODEL_TYPE) {
        Some(1) => {
            let pcs = short(key::PROJECTED_CS_TYPE).filter(|&c| c != 32767 && c != 0);
            let metric_pcs = pcs.is_some_and(|c| {
                (32601..=32660).contains(&c)
                    || (32701..=32760).contains(&c)
                    || (26901..=26923).contains(&c)
                    || (26701..=26722).contains(&c)
                    || (25828..=25838).contains(&c)
                    || (32201..=32260).contains(&c)
                    || (32301..=32360).contains(&c)
            });
            let linear_unit = match short(key::PROJ_LINEAR_UNITS).map(|u| (u, linear_unit_of(u))) {
                Some((_, Some(unit))) => unit,
                None if metric_pcs => METRE,
                None => {
                    return Err(err(format!(
                        "GeoKey ProjLinearUnitsGeoKey (3076) is missing and the projected CRS {} is not one known \
                         to be in metres: unknown units",
                        pcs.map_or("(user-defined)".to_string(), |c| format!("EPSG:{c}"))
                    )));
                }
                Some((u, None)) => {
                    return Err(err(format!(
                        "GeoKey ProjLinearUnitsGeoKey (3076) = {u}: only metres (9001), international feet (9002) \
                         and US survey feet (9003) are supported"
                    )));
                }
            };
            let d = cite(match pcs {
                Some(c) => format!("EPSG:{c} (projected, {})", linear_unit.1),
                None => format!("user-defined projected CRS ({})", linear_unit.1),
            });
            (CrsKind::Projected, pcs, d, 1.0, linear_unit)
        }
        Some(2) => {
            let gcs = short(key::GEOGRAPHIC_TYPE).filter(|&c| c != 32767 && c != 0);
            let (unit, unit_name) = match short(key::GEOG_ANGULAR_UNITS) {
                None | Some(9102) | Some(9122) => (1.0, "degrees"),
                Some(9103) => (1.0 / 60.0, "arc-minutes"),
                Some(9104) => (1.0 / 3600.0, "arc-seconds"),
                Some(u) => {
                    return Err(err(format!(
                        "GeoKey GeogAngularUnitsGeoKey (2054) = {u}: only degrees (9102), arc-minutes (9103) and \
                         arc-seconds (9104) are supported"
                    )));
                }
            };
            let d = cite(match gcs {
                Some(c) => format!("EPSG:{c} (geographic, {unit_name})"),
                None => format!("user-defined geographic CRS ({unit_name})"),
            });
            (CrsKind::Geographic, gcs, d, unit, METRE)
        }
        Some(3) => {
            return Err(err(
                "GeoKey GTModelTypeGeoKey (1024) = 3: geocentric coordinates are not a height field".into(),
            ));
        }
        Some(v) => {
            return Err(err(format!(
                "GeoKey GTModelTypeGeoKey (1024) = {v}: expected 1 (projected) or 2 (geographic)"
            )));
        }
        None => {
            return Err(err(
                "GeoKey GTModelTypeGeoKey (1024) is missing: cannot tell projected from geographic".into(),
            ));
        }
    };

    let Some((scale, tie_raster, tie_world)) = model_transform(dec, path)? else {
        return Err(err(
            "no ModelPixelScale (33550) and no ModelTransformation (34264): the raster has no georeference".into(),
        ));
    };
    let height_unit = match short(key::VERTICAL_UNITS) {
        None => None,
        Some(u) => Some(linear_unit_of(u).ok_or_else(|| {
            err(format!(
                "GeoKey VerticalUnitsGeoKey (4099) = {u}: only metres (9001), international feet (9002) and US survey \
                 feet (9003) are supported"
            ))
        })?),
    };
    Ok(Georef {
        kind,
        epsg,
        description,
        raster_type,
        angular_unit_deg,
        linear_unit,
        height_unit,
        scale,
        tie_raster,
        tie_world,
    })
}
