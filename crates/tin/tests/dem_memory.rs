//! A compressed DEM's header may claim far more samples than its data holds: the GeoTIFF and PNG readers must refuse
//! such a file without allocating the image it claims (found by `scripts/fuzz`: a 298-byte GeoTIFF made the reader
//! allocate 4 GB of heights before its first strip failed to decode). The allocations of the reading thread are
//! watched by a global allocator that records the largest one.
#![cfg(all(feature = "png", feature = "geotiff"))]

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::io::Cursor;
use std::path::Path;

use common::ifd_entry;
use tiff::encoder::{Compression, TiffEncoder, colortype};
use tin::dem::MAX_SAMPLES;
use tin::dem::geotiff::parse_geotiff;
use tin::dem::png::parse_png;
use tin::{DemOptions, TinError};

/// The system allocator, recording per thread the largest allocation asked for.
struct Watch;

thread_local! {
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: every call is forwarded to `System` unchanged; the thread-local is a const-initialised `Cell` without a
// destructor, so recording a size neither allocates nor re-enters the allocator.
unsafe impl GlobalAlloc for Watch {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        record(layout.size());
        // SAFETY: the caller's contract, passed on.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        record(layout.size());
        // SAFETY: as above.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        record(new_size);
        // SAFETY: as above.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as above.
        unsafe { System.dealloc(ptr, layout) }
    }
}

fn record(size: usize) {
    let _ = LARGEST.try_with(|l| l.set(l.get().max(size)));
}

#[global_allocator]
static WATCH: Watch = Watch;

/// The largest allocation `f` makes on this thread, with its result.
fn largest_allocation<T>(f: impl FnOnce() -> T) -> (usize, T) {
    LARGEST.with(|l| l.set(0));
    let out = f();
    (LARGEST.with(Cell::get), out)
}

/// Options for a plain TIFF (no georeference): a spacing of 10 m.
fn plain() -> DemOptions {
    DemOptions {
        spacing: Some((10.0, 10.0)),
        ..DemOptions::default()
    }
}

/// A valid little-endian TIFF of `rows` rows of two uint16 samples each, one row per strip (4 bytes of samples a
/// strip, compressed with `compression`), whose ImageWidth tag is then rewritten to `width`: every strip now claims
/// `width` samples and holds two.
fn two_columns_claiming(rows: u32, width: u16, compression: Compression) -> Vec<u8> {
    let mut buf = Cursor::new(Vec::new());
    {
        let mut enc = TiffEncoder::new(&mut buf)
            .expect("encoder")
            .with_compression(compression);
        let mut img = enc.new_image::<colortype::Gray16>(2, rows).expect("image");
        img.rows_per_strip(1).expect("strips");
        let data: Vec<u16> = (0..2 * rows).map(|i| (i % 1000) as u16).collect();
        img.write_data(&data).expect("data");
    }
    let mut bytes = buf.into_inner();
    let e = ifd_entry(&bytes, 256).expect("an ImageWidth tag");
    let kind = u16::from_le_bytes([bytes[e + 2], bytes[e + 3]]);
    match kind {
        3 => bytes[e + 8..e + 10].copy_from_slice(&width.to_le_bytes()),
        4 => bytes[e + 8..e + 12].copy_from_slice(&u32::from(width).to_le_bytes()),
        _ => panic!("ImageWidth of type {kind}"),
    }
    bytes
}

/// 10,000 strips of two samples each, claiming 20,000 samples a row: 200M samples, within [`MAX_SAMPLES`], whose
/// heights would take 1.6 GB. The first strip cannot give its 20,000 samples (uncompressed, its byte count is too
/// small for them, and they were read from the bytes after it; compressed, its stream ends); the file is refused, and
/// nothing near that size may be allocated first.
#[test]
fn a_small_geotiff_claiming_a_huge_image_is_refused_without_allocating_it() {
    let (rows, width) = (10_000u32, 20_000u16);
    assert!(u64::from(rows) * u64::from(width) <= MAX_SAMPLES);
    let compressions = [
        ("none", Compression::Uncompressed),
        ("deflate", Compression::Deflate(Default::default())),
        ("lzw", Compression::Lzw),
        ("packbits", Compression::Packbits),
    ];
    for (name, compression) in compressions {
        let bytes = two_columns_claiming(rows, width, compression);
        assert!(bytes.len() < 1 << 20, "{name}: {} bytes", bytes.len());
        let (largest, result) = largest_allocation(|| parse_geotiff(&bytes, Path::new("claims.tif"), &plain()));
        match result {
            Err(TinError::Format { path, message }) => {
                assert_eq!(path, Path::new("claims.tif"));
                assert!(message.contains("strip or tile 0"), "{name}: {message}");
            }
            Err(e) => panic!("{name}: expected a format error, got {e}"),
            Ok((g, _)) => panic!("{name}: expected an error, got a {} x {} grid", g.rows, g.cols),
        }
        // Far below the 1.6 GB of heights (and the 400 MB of its samples): what the file holds, and a strip's buffer.
        assert!(
            largest < 16 << 20,
            "{name}: an allocation of {largest} bytes for a file of {} bytes",
            bytes.len()
        );
    }
}

/// The same file with its rows intact reads (so the test above fails for the claim, not for the encoding), and a
/// claim beyond [`MAX_SAMPLES`] is refused at once, pointing to the tiled reading.
#[test]
fn the_claim_decides_and_beyond_the_limit_the_tiles_are_named() {
    let good = two_columns_claiming(10_000, 2, Compression::Uncompressed);
    let (grid, _) = parse_geotiff(&good, Path::new("good.tif"), &plain()).expect("reads");
    assert_eq!((grid.rows, grid.cols), (10_000, 2));

    let (largest, result) = largest_allocation(|| {
        let huge = two_columns_claiming(30_000, 10_000, Compression::Uncompressed);
        parse_geotiff(&huge, Path::new("huge.tif"), &plain())
    });
    let message = match result {
        Err(TinError::Format { message, .. }) => message,
        Err(e) => panic!("expected a format error, got {e}"),
        Ok(_) => panic!("300M samples read whole"),
    };
    assert!(
        message.contains("10000 x 30000 samples") && message.contains("tiles plan"),
        "{message}"
    );
    assert!(largest < 16 << 20, "an allocation of {largest} bytes");
}

/// A 16-bit greyscale PNG of one row of `width` samples whose IHDR is then rewritten to claim `rows` rows (its CRC
/// recomputed, so only the missing rows give the file away).
fn png_claiming(width: u32, rows: u32) -> Vec<u8> {
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, width, 1);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Sixteen);
        let mut w = enc.write_header().expect("header");
        w.write_image_data(&vec![7u8; 2 * width as usize]).expect("data");
    }
    // Signature (8), then the IHDR chunk: length (4), type (4), width (4), height (4), 5 more bytes, CRC (4).
    assert_eq!(&bytes[12..16], b"IHDR");
    bytes[20..24].copy_from_slice(&rows.to_be_bytes());
    let crc = crc32(&bytes[12..29]);
    bytes[29..33].copy_from_slice(&crc.to_be_bytes());
    bytes
}

/// CRC-32 (ISO-HDLC, as PNG chunks use), bit by bit.
fn crc32(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// A PNG of one row claiming 16,384 x 16,384 samples (the most read, 2 GiB of heights and 512 MiB of 16-bit samples)
/// is refused, naming the missing rows, without allocating either; the same file claiming its one row reads.
#[test]
fn a_small_png_claiming_a_huge_image_is_refused_without_allocating_it() {
    let good = png_claiming(16_384, 1);
    let grid = parse_png(&good, Path::new("row.png"), &plain());
    assert!(
        matches!(&grid, Err(TinError::Format { message, .. }) if message.contains("at least 2 x 2")),
        "one row is no grid: {grid:?}"
    );
    let two = png_claiming(16_384, 2);
    let (largest, result) = largest_allocation(|| parse_png(&two, Path::new("claims.png"), &plain()));
    match result {
        Err(TinError::Format { path, message }) => {
            assert_eq!(path, Path::new("claims.png"));
            assert!(message.contains("PNG"), "{message}");
        }
        Err(e) => panic!("expected a format error, got {e}"),
        Ok(g) => panic!("expected an error, got a {} x {} grid", g.rows, g.cols),
    }
    assert!(largest < 16 << 20, "an allocation of {largest} bytes");

    let huge = png_claiming(16_384, 16_384);
    assert!(huge.len() < 4096, "{} bytes", huge.len());
    let (largest, result) = largest_allocation(|| parse_png(&huge, Path::new("claims.png"), &plain()));
    match result {
        Err(TinError::Format { message, .. }) => assert!(message.contains("truncated"), "{message}"),
        Err(e) => panic!("expected a format error, got {e}"),
        Ok(g) => panic!("expected an error, got a {} x {} grid", g.rows, g.cols),
    }
    assert!(
        largest < 16 << 20,
        "an allocation of {largest} bytes for a file of {} bytes",
        huge.len()
    );
}
