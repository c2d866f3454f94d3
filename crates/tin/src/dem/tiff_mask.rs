//! GDAL's nodata masks of a GeoTIFF, applied: a sample that the mask marks invalid is a void.
//!
//! GDAL keeps a mask beside the samples in one of two places: an image of the same file whose `NewSubfileType` has
//! bit 2 (a transparency mask) and not bit 0 (a reduced-resolution image: the masks of overviews), as
//! `GDAL_TIFF_INTERNAL_MASK` writes it; else the first image of a `.msk` file beside the GeoTIFF (`dem.tif.msk`). Its
//! samples are 1-bit (as GDAL writes them) or 8-bit gray, 0 meaning nodata and anything else a valid sample; it has
//! the image's size. The first 64 images of the file are searched for it.
//!
//! The `tiff` crate (0.11) refuses to decode an image whose `PhotometricInterpretation` is 4 (transparency mask),
//! although its samples are plain gray: the mask is decoded through a reader that reads that one tag of that one
//! image as 1 (`BlackIsZero`), every other byte of the file as it is.

use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use tiff::ColorType;
use tiff::decoder::{Decoder, DecodingResult};
use tiff::tags::Tag;

use super::open;
use crate::error::{Result, TinError};

/// Images of the file searched for an internal mask.
const MAX_IMAGES: usize = 64;

/// Where a GeoTIFF's nodata mask is kept.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MaskSource {
    /// Image `index` (0-based) of the GeoTIFF itself.
    Internal(usize),
    /// The first image of this `.msk` file.
    External(PathBuf),
}

impl MaskSource {
    /// The mask in words, for messages.
    pub fn describe(&self) -> String {
        match self {
            MaskSource::Internal(i) => format!("an internal nodata mask (image {} of the file)", i + 1),
            MaskSource::External(p) => format!("the nodata mask file {}", p.display()),
        }
    }
}

/// The nodata mask of the GeoTIFF at `path`, whose bytes `reader` reads: the first full-resolution mask image among
/// its first 64, else a `.msk` file beside it (GDAL's order). None when there is neither; a file whose images cannot
/// be listed is looked at no further (the reader of its samples names that error).
pub fn find_mask<R: Read + Seek>(path: &Path, reader: R) -> Option<MaskSource> {
    if let Ok(mut dec) = Decoder::new(reader) {
        for image in 1..MAX_IMAGES {
            if !dec.more_images() || dec.next_image().is_err() {
                break;
            }
            let kind = dec.find_tag_unsigned::<u32>(Tag::NewSubfileType).ok().flatten();
            if kind.is_some_and(|t| t & 4 != 0 && t & 1 == 0) {
                return Some(MaskSource::Internal(image));
            }
        }
    }
    let msk = super::gdal_mask_path(path);
    msk.is_file().then_some(MaskSource::External(msk))
}

/// A reader of a TIFF file that reads the two bytes at `at` as `value` (the inline value of one
/// `PhotometricInterpretation` entry, so that it says 1) and every other byte as the file holds it.
struct Patched<R> {
    inner: R,
    pos: u64,
    at: u64,
    value: [u8; 2],
}

impl<R: Read> Read for Patched<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        for (k, &b) in self.value.iter().enumerate() {
            let p = self.at + k as u64;
            if p >= self.pos && p < self.pos + n as u64 {
                buf[(p - self.pos) as usize] = b;
            }
        }
        self.pos += n as u64;
        Ok(n)
    }
}

impl<R: Seek> Seek for Patched<R> {
    fn seek(&mut self, to: SeekFrom) -> std::io::Result<u64> {
        self.pos = self.inner.seek(to)?;
        Ok(self.pos)
    }
}

/// Where the inline value of the `PhotometricInterpretation` entry (tag 262, one SHORT) of the IFD at `ifd` lies in
/// the file, and the bytes of the value 1 in the file's byte order; None when the IFD has no such entry.
fn photometric_value<R: Read + Seek>(r: &mut R, ifd: u64) -> std::io::Result<Option<(u64, [u8; 2])>> {
    let mut header = [0u8; 4];
    r.seek(SeekFrom::Start(0))?;
    r.read_exact(&mut header)?;
    let little = &header[..2] == b"II";
    let u16_of = |b: [u8; 2]| {
        if little {
            u16::from_le_bytes(b)
        } else {
            u16::from_be_bytes(b)
        }
    };
    let big = u16_of([header[2], header[3]]) == 43;
    r.seek(SeekFrom::Start(ifd))?;
    let count = if big {
        let mut b = [0u8; 8];
        r.read_exact(&mut b)?;
        if little {
            u64::from_le_bytes(b)
        } else {
            u64::from_be_bytes(b)
        }
    } else {
        let mut b = [0u8; 2];
        r.read_exact(&mut b)?;
        u64::from(u16_of(b))
    };
    let (first, size, value_at) = if big { (ifd + 8, 20, 12) } else { (ifd + 2, 12, 8) };
    for i in 0..count.min(4096) {
        let entry = first + i * size;
        let mut tag = [0u8; 2];
        r.seek(SeekFrom::Start(entry))?;
        r.read_exact(&mut tag)?;
        if u16_of(tag) == 262 {
            let one = if little { [1, 0] } else { [0, 1] };
            return Ok(Some((entry + value_at, one)));
        }
    }
    Ok(None)
}

/// Marks as voids (NaN) the samples of `z` (rows `rows[0]..=rows[1]`, columns `cols[0]..=cols[1]` of an image of
/// `shape_rows` × `shape_cols` samples) that the mask `source` marks invalid. `reader` opens the GeoTIFF's bytes
/// again (the mask of an internal source is read from them); `path` names the GeoTIFF in errors. Returns how many
/// samples of the window the mask voided.
pub fn apply_mask<R: Read + Seek>(
    source: &MaskSource,
    reader: impl FnOnce() -> Result<R>,
    path: &Path,
    shape: (usize, usize),
    rows: [usize; 2],
    cols: [usize; 2],
    z: &mut [f64],
) -> Result<usize> {
    match source {
        MaskSource::Internal(image) => decode(reader()?, *image, path, path, shape, rows, cols, z),
        MaskSource::External(msk) => decode(open(msk)?, 0, msk, path, shape, rows, cols, z),
    }
}

/// [`apply_mask`] from image `image` of the TIFF that `reader` reads (`file` names it in errors).
#[allow(clippy::too_many_arguments)]
fn decode<R: Read + Seek>(
    mut reader: R,
    image: usize,
    file: &Path,
    path: &Path,
    (shape_rows, shape_cols): (usize, usize),
    rows: [usize; 2],
    cols: [usize; 2],
    z: &mut [f64],
) -> Result<usize> {
    let err = |m: String| TinError::format(file, format!("nodata mask (image {}): {m}", image + 1));
    let tiff_err = |e: tiff::TiffError| err(e.to_string());
    // Where the mask's IFD lies, from a first pass over the file as it is.
    let ifd = {
        let mut dec = Decoder::new(&mut reader).map_err(tiff_err)?;
        dec.seek_to_image(image).map_err(tiff_err)?;
        dec.ifd_pointer().ok_or_else(|| err("no such image".into()))?.0
    };
    let patch = photometric_value(&mut reader, ifd).map_err(|e| err(format!("cannot read its tags: {e}")))?;
    reader.seek(SeekFrom::Start(0)).map_err(|e| err(e.to_string()))?;
    let (at, value) = patch.unwrap_or((u64::MAX - 2, [0, 0]));
    let mut dec = Decoder::new(Patched {
        inner: reader,
        pos: 0,
        at,
        value,
    })
    .map_err(tiff_err)?;
    dec.seek_to_image(image).map_err(tiff_err)?;
    let (w, h) = dec.dimensions().map_err(tiff_err)?;
    if (w as usize, h as usize) != (shape_cols, shape_rows) {
        return Err(err(format!(
            "{w} x {h} samples, but {} has {shape_cols} x {shape_rows}",
            path.display()
        )));
    }
    let bits = match dec.colortype().map_err(tiff_err)? {
        ColorType::Gray(b @ (1 | 8)) => usize::from(b),
        other => return Err(err(format!("{other:?} samples; a mask has 1-bit or 8-bit gray ones"))),
    };
    let (cw, ch) = dec.chunk_dimensions();
    let (cw, ch) = (cw as usize, ch as usize);
    if cw == 0 || ch == 0 {
        return Err(err(format!("chunks of {cw} x {ch} samples")));
    }
    let across = shape_cols.div_ceil(cw);
    let nc = cols[1] - cols[0] + 1;
    let mut voided = 0;
    for ty in rows[0] / ch..=rows[1] / ch {
        for tx in cols[0] / cw..=cols[1] / cw {
            let index = u32::try_from(ty * across + tx).map_err(|_| err("too many strips or tiles".into()))?;
            let (dw, dh) = dec.chunk_data_dimensions(index);
            let (dw, dh) = (dw as usize, dh as usize);
            // Decoded at the padded chunk width, as the samples are (see `geotiff`'s `decode_window`): rows of whole
            // bytes, 1-bit rows padded to a byte.
            let row = (cw * bits).div_ceil(8);
            let mut chunk = DecodingResult::U8(Vec::new());
            dec.read_chunk_to_buffer(&mut chunk, index, row).map_err(tiff_err)?;
            let DecodingResult::U8(bytes) = chunk else {
                return Err(err(format!("strip or tile {index} is not decoded as bytes")));
            };
            if dh == 0 || dw > cw || bytes.len() < (dh - 1) * row + (dw * bits).div_ceil(8) {
                return Err(err(format!(
                    "strip or tile {index}: {} bytes for {dw} x {dh} samples",
                    bytes.len()
                )));
            }
            let (y0, x0) = (ty * ch, tx * cw);
            for r in rows[0].max(y0)..=rows[1].min(y0 + dh - 1) {
                let line = &bytes[(r - y0) * row..];
                for c in cols[0].max(x0)..=cols[1].min(x0 + dw - 1) {
                    let k = c - x0;
                    let valid = if bits == 1 {
                        line[k / 8] & (0x80 >> (k % 8)) != 0
                    } else {
                        line[k] != 0
                    };
                    let v = &mut z[(r - rows[0]) * nc + (c - cols[0])];
                    if !valid && !v.is_nan() {
                        *v = f64::NAN;
                        voided += 1;
                    }
                }
            }
        }
    }
    Ok(voided)
}
