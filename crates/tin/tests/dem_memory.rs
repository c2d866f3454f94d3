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
    let _ = AT_LEAST.try_with(|a| {
        let (min, n) = a.get();
        if size >= min {
            a.set((min, n + 1));
        }
    });
}

thread_local! {
    /// A size, and how many allocations of at least that size this thread made.
    static AT_LEAST: Cell<(usize, usize)> = const { Cell::new((usize::MAX, 0)) };
}

/// How many allocations of at least `size` bytes `f` makes on this thread, with its result.
fn allocations_of_at_least<T>(size: usize, f: impl FnOnce() -> T) -> (usize, T) {
    AT_LEAST.with(|a| a.set((size, 0)));
    let out = f();
    let (_, n) = AT_LEAST.with(Cell::get);
    AT_LEAST.with(|a| a.set((usize::MAX, 0)));
    (n, out)
}

#[global_allocator]
static WATCH: Watch = Watch;

/// The largest allocation `f` makes on this thread, with its result.
fn largest_allocation<T>(f: impl FnOnce() -> T) -> (usize, T) {
    LARGEST.with(|l| l.set(0));
    let out = f();
    (LARGEST.with(Cell::get), out)
}

/// Runs a read of the file `name` that must be refused: returns the error's message, after checking that it is a
/// format error naming the file and that no allocation of `limit` bytes or more was made on the way.
fn refused_within<T>(what: &str, name: &str, limit: usize, read: impl FnOnce(&Path) -> tin::Result<T>) -> String {
    let (largest, result) = largest_allocation(|| read(Path::new(name)));
    let message = match result {
        Err(TinError::Format { path, message }) => {
            assert_eq!(path, Path::new(name), "{what}");
            message
        }
        Err(e) => panic!("{what}: expected a format error, got {e}"),
        Ok(_) => panic!("{what}: expected an error, the file was read"),
    };
    assert!(largest < limit, "{what}: an allocation of {largest} bytes ({message})");
    message
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
        // Far below the 1.6 GB of heights (and the 400 MB of its samples): what the file holds, and a strip's buffer.
        let message = refused_within(name, "claims.tif", 16 << 20, |p| parse_geotiff(&bytes, p, &plain()));
        assert!(message.contains("strip or tile 0"), "{name}: {message}");
    }
}

/// The same file with its rows intact reads (so the test above fails for the claim, not for the encoding), and a
/// claim beyond [`MAX_SAMPLES`] is refused at once, pointing to the tiled reading.
#[test]
fn the_claim_decides_and_beyond_the_limit_the_tiles_are_named() {
    let good = two_columns_claiming(10_000, 2, Compression::Uncompressed);
    let (grid, _) = parse_geotiff(&good, Path::new("good.tif"), &plain()).expect("reads");
    assert_eq!((grid.rows, grid.cols), (10_000, 2));

    let huge = two_columns_claiming(30_000, 10_000, Compression::Uncompressed);
    let message = refused_within("300M samples", "huge.tif", 16 << 20, |p| {
        parse_geotiff(&huge, p, &plain())
    });
    assert!(
        message.contains("10000 x 30000 samples") && message.contains("tiles plan"),
        "{message}"
    );
}

/// A 16-bit greyscale PNG of one row of `width` samples whose IHDR is then rewritten to claim `rows` rows (its CRC
/// recomputed, so only the missing rows give the file away).
fn png_claiming(width: u32, rows: u32) -> Vec<u8> {
    png_claiming_as(width, rows, false)
}

/// [`png_claiming`], the IHDR also saying that the image is interlaced (Adam7) when `interlaced`.
fn png_claiming_as(width: u32, rows: u32, interlaced: bool) -> Vec<u8> {
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
    bytes[28] = u8::from(interlaced);
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
    let message = refused_within("two rows", "claims.png", 16 << 20, |p| parse_png(&two, p, &plain()));
    assert!(message.contains("PNG"), "{message}");

    let huge = png_claiming(16_384, 16_384);
    assert!(huge.len() < 4096, "{} bytes", huge.len());
    let message = refused_within("16384 rows", "claims.png", 16 << 20, |p| parse_png(&huge, p, &plain()));
    assert!(message.contains("truncated"), "{message}");
}

/// Which strips or tiles of [`uint16_tiff`] have samples.
#[derive(Clone, Copy, PartialEq)]
enum Chunks {
    /// Every one (all the same samples).
    All,
    /// The first; the others point past the end of the file.
    First,
    /// None: every one points past the end of the file.
    None,
}

/// A little-endian uncompressed uint16 TIFF of `width` x `height` samples, in strips of one row or in tiles of
/// `tile` x `tile`, whose strips or tiles hold samples (all 7) as `present` says.
fn uint16_tiff(width: u32, height: u32, tile: Option<u32>, present: Chunks) -> Vec<u8> {
    let (cw, ch) = tile.map_or((width, 1), |t| (t, t));
    let chunks = width.div_ceil(cw) * height.div_ceil(ch);
    let chunk_bytes = cw * ch * 2;
    // Header, the IFD (a count, its entries, the next IFD's offset), the offsets, the byte counts, the first chunk.
    let ifd = 8u32;
    let offsets = ifd + 2 + if tile.is_some() { 11 } else { 10 } * 12 + 4;
    let counts = offsets + 4 * chunks;
    let data = counts + 4 * chunks;
    let (offsets_tag, counts_tag) = if tile.is_some() { (324, 325) } else { (273, 279) };
    let past_end = data + chunk_bytes + 1_000_000;
    let has_data = |i: u32| present == Chunks::All || (i == 0 && present == Chunks::First);
    // One offset and one count are held in their entries; more in the tables the entries point at.
    let (offsets_value, counts_value) = match chunks {
        1 => (if has_data(0) { data } else { past_end }, chunk_bytes),
        _ => (offsets, counts),
    };
    let mut entries: Vec<(u16, u16, u32, u32)> = vec![
        (256, 4, 1, width),
        (257, 4, 1, height),
        (258, 3, 1, 16),
        (259, 3, 1, 1),
        (262, 3, 1, 1),
        (277, 3, 1, 1),
        (339, 3, 1, 1),
        (offsets_tag, 4, chunks, offsets_value),
        (counts_tag, 4, chunks, counts_value),
    ];
    entries.extend(match tile {
        Some(t) => vec![(322, 4, 1, t), (323, 4, 1, t)],
        None => vec![(278, 4, 1, 1)],
    });
    entries.sort();
    let mut b = b"II*\0".to_vec();
    b.extend(ifd.to_le_bytes());
    b.extend((entries.len() as u16).to_le_bytes());
    for &(tag, kind, count, value) in &entries {
        b.extend(tag.to_le_bytes());
        b.extend(kind.to_le_bytes());
        b.extend(count.to_le_bytes());
        match kind {
            3 => b.extend((value as u16).to_le_bytes().into_iter().chain([0, 0])),
            _ => b.extend(value.to_le_bytes()),
        }
    }
    b.extend(0u32.to_le_bytes());
    assert_eq!(b.len(), offsets as usize);
    b.extend((0..chunks).flat_map(|i| if has_data(i) { data } else { past_end }.to_le_bytes()));
    b.extend((0..chunks).flat_map(|_| chunk_bytes.to_le_bytes()));
    assert_eq!(b.len(), data as usize);
    if present != Chunks::None {
        b.extend((0..cw * ch).flat_map(|_| 7u16.to_le_bytes()));
    }
    b
}

/// A GeoTIFF whose first strip or tile decodes but whose next one is missing: 200M samples claimed (1.6 GB of
/// heights), first in strips of one row of 20,000 samples, then in tiles of 256 x 256. The heights grow with the bands
/// of strips or tiles decoded, so the file is refused at its second chunk with nothing near the claim allocated (the
/// whole image's heights used to be allocated once the first chunk had decoded).
#[test]
fn a_geotiff_missing_all_but_its_first_chunk_is_refused_without_allocating_the_image() {
    for (name, width, height, tile) in [("strips", 20_000, 10_000, None), ("tiles", 16_384, 12_288, Some(256))] {
        assert!(u64::from(width) * u64::from(height) <= MAX_SAMPLES);
        let bytes = uint16_tiff(width, height, tile, Chunks::First);
        let message = refused_within(name, "first.tif", 16 << 20, |p| parse_geotiff(&bytes, p, &plain()));
        assert!(
            message.contains("strip or tile 1") && message.contains("truncated"),
            "{name}: {message}"
        );
    }
    // With every chunk present the same layouts read (so the test above fails for the missing chunk): strips, and
    // tiles that overhang the image on the right and at the bottom.
    for (width, height, tile) in [(20, 3_000, None), (40, 37, Some(16))] {
        let bytes = uint16_tiff(width, height, tile, Chunks::All);
        let (grid, _) = parse_geotiff(&bytes, Path::new("all.tif"), &plain()).expect("reads");
        assert_eq!((grid.cols, grid.rows), (width as usize, height as usize));
        assert!(grid.z.iter().all(|&z| z == 7.0), "{tile:?}");
    }
}

/// A tile may be wider and taller than its image (padding), but a file whose one tile's padding would take far more
/// than the image (found by an audit: a 1 MB GeoTIFF of 2 x 16,384 samples in a tile 65,536 wide had 1 GiB decoded,
/// then 8 GiB asked for its conversion to f64) is refused before the tile is decoded; one within bounds is read
/// without converting its padding.
#[test]
fn a_tile_far_larger_than_its_image_is_refused_and_padding_is_never_converted() {
    let padded = uint16_tiff(16, 8192, Some(8192), Chunks::None);
    let message = refused_within("8192 tile", "padded.tif", 1 << 20, |p| {
        parse_geotiff(&padded, p, &plain())
    });
    assert!(
        message.contains("strip or tile 0") && message.contains("padding"),
        "{message}"
    );

    // A tile of 4096 x 4096 (32 MiB of samples) over 20 x 4096: read with nothing near the 128 MiB its f64 would
    // take.
    let big = uint16_tiff(20, 4096, Some(4096), Chunks::All);
    let (largest, read) = largest_allocation(|| parse_geotiff(&big, Path::new("big.tif"), &plain()));
    let (grid, _) = read.expect("reads");
    assert_eq!((grid.cols, grid.rows), (20, 4096));
    assert!(grid.z.iter().all(|&z| z == 7.0));
    assert!(largest <= 33 << 20, "an allocation of {largest} bytes");
}

/// An interlaced PNG is decoded whole (its rows come in seven passes), so its header is checked against what its
/// bytes can hold: no Deflate stream inflates to more than 1032 bytes a byte. One claiming 16,384 x 16,384 samples
/// is refused before any decoding, saying so, with nothing near its 512 MiB of samples allocated (whole and
/// non-interlaced alike).
#[test]
fn a_png_claiming_more_than_its_bytes_can_inflate_to_is_refused_at_once() {
    for interlaced in [true, false] {
        let huge = png_claiming_as(16_384, 16_384, interlaced);
        let what = format!("interlaced {interlaced}");
        let message = refused_within(&what, "claims.png", 1 << 20, |p| parse_png(&huge, p, &plain()));
        assert!(
            message.contains("inflates to at most") && message.contains("truncated"),
            "{message}"
        );
    }
}

/// The bound is a theorem, not a guess: the best compression the encoder has, of the most compressible image (one
/// height everywhere), stays within it and reads.
#[test]
fn a_png_compressed_as_well_as_it_can_be_reads() {
    let (width, rows) = (2_048u32, 2_048u32);
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, width, rows);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Sixteen);
        enc.set_compression(png::Compression::High);
        let mut w = enc.write_header().expect("header");
        w.write_image_data(&vec![0u8; 2 * (width * rows) as usize])
            .expect("data");
    }
    let ratio = (2 * width * rows) as f64 / bytes.len() as f64;
    assert!(ratio > 100.0, "{} bytes, a ratio of {ratio}", bytes.len());
    let grid = parse_png(&bytes, Path::new("flat.png"), &plain()).expect("reads");
    assert_eq!((grid.rows, grid.cols), (rows as usize, width as usize));
}

/// A GeoTIFF in one strip (as many writers store a small image) read in strips of rows, as `tiles plan` reads a DEM:
/// the file's strip is decoded once, not once for every strip of rows (a 16,384² file in one strip took 179 s and
/// 2.4 GB instead of 10 s, found by an audit), and the strips hold what a whole read gives.
#[test]
fn a_geotiff_in_one_strip_is_decoded_once_when_read_in_strips_of_rows() {
    let (width, height) = (1_000u32, 2_000u32);
    let mut buf = Cursor::new(Vec::new());
    {
        let mut enc = TiffEncoder::new(&mut buf).expect("encoder");
        let mut img = enc.new_image::<colortype::Gray16>(width, height).expect("image");
        img.rows_per_strip(height).expect("one strip");
        let data: Vec<u16> = (0..width * height).map(|i| (i % 4099) as u16).collect();
        img.write_data(&data).expect("data");
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("one-strip.tif");
    std::fs::write(&path, buf.into_inner()).expect("write");
    let whole = tin::read_dem(&path, &plain()).expect("reads whole");
    let chunk = (width * height * 2) as usize;
    let (decodes, strips) = allocations_of_at_least(chunk, || {
        let mut strips = Vec::new();
        tin::read_dem_strips(&path, &plain(), 100, |first, z| {
            strips.push((first, z.to_vec()));
            Ok(())
        })
        .map(|_| strips)
    });
    let strips = strips.expect("reads in strips");
    assert_eq!(strips.len(), 20);
    assert_eq!(
        strips.iter().flat_map(|(_, z)| z.iter().copied()).collect::<Vec<_>>(),
        whole.z
    );
    assert_eq!(decodes, 1, "the strip of {chunk} bytes decoded {decodes} times");
}
