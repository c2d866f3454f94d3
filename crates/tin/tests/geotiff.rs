//! GeoTIFF reader: the three real files of `../shared/dem` against their `.npy` / `.hgt` twins and the README's
//! georeferencing (these fail, never skip, when the directory is missing), and GeoTIFFs written by the tests with the
//! `tiff` encoder (sample types, compression, predictors, transformation, bands, and the errors; and any bytes of a
//! small one damaged: read into a grid that simplifies, or refused, never a panic).
#![cfg(feature = "geotiff")]

mod common;

use std::io::Cursor;
use std::path::{Path, PathBuf};

use common::ifd_entry;
use glam::DVec2;
use tiff::encoder::{Compression, Predictor, TiffEncoder, colortype};
use tiff::tags::Tag;
use tin::dem::geotiff::{CrsKind, GeoTiffInfo, RasterType, parse_geotiff, read_geotiff_info};
use tin::dem::hgt::METRES_PER_DEGREE;
use tin::{DemOptions, Grid, SimplifyOptions, Tin, TinError, read_dem};

/// `../shared/dem`: required (CI has it); a missing directory fails the test.
fn shared_dem() -> PathBuf {
    let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/dem"));
    assert!(
        dir.is_dir(),
        "{} is missing: the GeoTIFF tests need the shared DEMs",
        dir.display()
    );
    dir
}

fn same_heights(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()))
}

fn range(g: &Grid) -> (f64, f64) {
    g.z.iter()
        .filter(|z| !z.is_nan())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &z| {
            (lo.min(z), hi.max(z))
        })
}

fn simplified(g: &Grid, n: usize) -> Tin {
    tin::simplify(
        g,
        &SimplifyOptions {
            max_vertices: Some(n),
            max_error: None,
        },
        None,
    )
    .expect("simplify")
    .0
}

/// Same grid bit for bit, and the same TIN from it.
fn assert_twins(tif: &Grid, twin: &Grid) {
    assert_eq!((tif.rows, tif.cols), (twin.rows, twin.cols));
    assert_eq!(
        (tif.dx.to_bits(), tif.dy.to_bits()),
        (twin.dx.to_bits(), twin.dy.to_bits()),
        "spacing {} x {} vs {} x {}",
        tif.dx,
        tif.dy,
        twin.dx,
        twin.dy
    );
    assert_eq!(tif.origin, twin.origin);
    assert!(same_heights(&tif.z, &twin.z));
    let (a, b) = (simplified(tif, 3000), simplified(twin, 3000));
    assert_eq!(a.positions(), b.positions());
    assert_eq!(a.triangles(), b.triangles());
}

fn info(path: &Path) -> (Grid, GeoTiffInfo) {
    read_geotiff_info(path, &DemOptions::default()).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn crater_lake_utm_matches_its_npy_twin() {
    let dir = shared_dem();
    let (tif, i) = info(&dir.join("crater_lake_utm.tif"));
    let npy = read_dem(dir.join("crater_lake.npy"), &DemOptions::default()).expect("npy");
    assert_twins(&tif, &npy);
    // README: 513 x 513 float32, 20.182 x 27.305 m, UTM 10N (EPSG:26910), 1524 - 2478 m, pixel-is-area, tiles,
    // Deflate with the floating-point predictor, nodata -9999 unused. Sidecar: easting_min 561133.125, northing_max
    // 4760971.5 (sample centres).
    assert_eq!((tif.rows, tif.cols), (513, 513));
    assert_eq!((tif.dx, tif.dy), (20.182, 27.305));
    assert_eq!(tif.origin, DVec2::new(561133.125, 4760971.5));
    assert_eq!(range(&tif), (1524.0, 2478.0));
    assert_eq!(tif.voids(), 0);
    assert_eq!(i.crs_kind, CrsKind::Projected);
    assert_eq!(i.epsg, Some(26910));
    assert!(i.crs.contains("EPSG:26910"), "{}", i.crs);
    assert_eq!(i.raster_type, RasterType::PixelIsArea);
    assert_eq!(i.nodata, Some(-9999.0));
    assert_eq!(i.sample_type, "float32");
    assert_eq!(i.layout, "tiles");
    assert_eq!(i.compression, "deflate, predictor floating-point");
    let [w, s, e, n] = i.native_bbox;
    assert_eq!((w, n), (561133.125, 4760971.5));
    assert!((e - (561133.125 + 512.0 * 20.182)).abs() < 1e-6);
    assert!((s - (4760971.5 - 512.0 * 27.305)).abs() < 1e-6);
}

#[test]
fn n50e008_deflate_matches_its_hgt_twin() {
    let dir = shared_dem();
    let (tif, i) = info(&dir.join("N50E008_deflate.tif"));
    let hgt = read_dem(dir.join("N50E008.hgt"), &DemOptions::default()).expect("hgt");
    assert_twins(&tif, &hgt);
    // README: 1201 x 1201 int16, 3", EPSG:4326, 62 - 885 m, 50 voids, pixel-is-point with the tie point 8E 51N at
    // sample (0, 0), strips of 16 rows, Deflate with the horizontal predictor.
    assert_eq!((tif.rows, tif.cols), (1201, 1201));
    assert_eq!(tif.voids(), 50);
    assert_eq!(range(&tif), (62.0, 885.0));
    assert_eq!(i.crs_kind, CrsKind::Geographic);
    assert_eq!(i.epsg, Some(4326));
    assert_eq!(i.raster_type, RasterType::PixelIsPoint);
    assert_eq!(i.nodata, Some(-32768.0));
    assert_eq!(i.sample_type, "int16");
    assert_eq!(i.layout, "strips");
    assert_eq!(i.compression, "deflate, predictor horizontal");
    assert_eq!(i.native_bbox, [8.0, 50.0, 9.0, 51.0]);
    // Metres: the .hgt frame, x from the western column, y = latitude * 111320.
    assert_eq!(tif.origin, DVec2::new(0.0, 51.0 * METRES_PER_DEGREE));
    assert!((tif.dy - METRES_PER_DEGREE / 1200.0).abs() < 1e-12);
    assert!((tif.dx - METRES_PER_DEGREE / 1200.0 * 50.5f64.to_radians().cos()).abs() < 1e-12);
    let south = tif.origin.y - 1200.0 * tif.dy;
    assert!((south - 50.0 * METRES_PER_DEGREE).abs() < 1e-6);
}

#[test]
fn dfw_srtm_georeference_is_exact() {
    let dir = shared_dem();
    let (g, i) = info(&dir.join("dfw_srtm.tif"));
    // README: 359 x 367 int16, 3 arc-seconds, EPSG:4326, 147 - 298 m (nodata -32768), 16x16 tiles, uncompressed,
    // pixel-is-area. The tie point is the north-west corner of the first pixel: 97.485W, 32.82166666666536N.
    assert_eq!((g.rows, g.cols), (359, 367));
    assert_eq!(range(&g), (147.0, 298.0));
    assert_eq!(i.crs_kind, CrsKind::Geographic);
    assert_eq!(i.epsg, Some(4326));
    assert!(i.crs.contains("WGS 84"), "{}", i.crs);
    assert_eq!(i.raster_type, RasterType::PixelIsArea);
    assert_eq!(i.nodata, Some(-32768.0));
    assert_eq!(i.layout, "tiles");
    assert_eq!(i.compression, "none, predictor none");
    let step = 0.0008333333333333;
    let (west, north) = (-97.4849999999961, 32.82166666666536);
    let [w, s, e, n] = i.native_bbox;
    let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
    assert!(close(w, west + step / 2.0), "{w}");
    assert!(close(n, north - step / 2.0), "{n}");
    assert!(close(e, west + 366.5 * step), "{e}");
    assert!(close(s, north - 358.5 * step), "{s}");
    // Metres: 3" = 111320 / 1200 m north-south, times cos(mid-latitude) east-west; y = latitude * 111320.
    let mid = 0.5 * (n + (n - 358.0 / 1200.0));
    assert!((g.dy - METRES_PER_DEGREE / 1200.0).abs() < 1e-12);
    assert!((g.dx - METRES_PER_DEGREE / 1200.0 * mid.to_radians().cos()).abs() < 1e-9);
    assert!((g.origin.y - n * METRES_PER_DEGREE).abs() < 1e-6);
    assert_eq!(g.origin.x, 0.0);
    assert!(i.conversion.contains("111320"), "{}", i.conversion);
}

/// The real tiled file, its 529 tiles recompressed by ZSTD: the same grid.
#[test]
fn dfw_srtm_recompressed_with_zstd_reads_the_same() {
    let path = shared_dem().join("dfw_srtm.tif");
    let bytes = std::fs::read(&path).expect("dfw_srtm.tif");
    let opts = DemOptions::default();
    let (plain, _) = parse_geotiff(&bytes, &path, &opts).expect("the original");
    let zstd = zstd_chunks(bytes);
    let (packed, i) = parse_geotiff(&zstd, &path, &opts).expect("recompressed");
    assert_eq!(
        (i.layout.as_str(), i.compression.as_str()),
        ("tiles", "zstd, predictor none")
    );
    assert_eq!(packed, plain);
    // From a file, as the commands read it (tile by tile).
    let dir = tempfile::tempdir().expect("temporary directory");
    let file = dir.path().join("dfw_zstd.tif");
    std::fs::write(&file, &zstd).expect("write");
    assert_eq!(read_dem(&file, &opts).expect("read_dem"), plain);
}

#[test]
fn missing_file_names_it() {
    let p = Path::new("/nonexistent/dem.tif");
    let e = read_dem(p, &DemOptions::default()).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/dem.tif"), "{e}");
}

/// `tests/data/lzw_tiles_70x50.tif`: 70 x 50 int16 samples `⌊100 + row + column / 2⌋`, LZW in 16 x 16 tiles (which do
/// not divide the image: GDAL's default tiling of a DEM does the same), EPSG:32633, 10 x 20 m, written by Python's
/// `tifffile`. The `tiff` crate's own `read_image` and `read_chunk` fail on its right-edge tiles ("no lzw end code
/// found"); the reader decodes every tile at its padded width.
#[test]
fn lzw_tiles_at_the_right_edge_decode() {
    let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/lzw_tiles_70x50.tif"));
    let expected = |r: usize, c: usize| (100.0 + r as f64 + 0.5 * c as f64).floor();
    let (g, i) = info(&path);
    assert_eq!((g.rows, g.cols, i.layout.as_str()), (50, 70, "tiles"));
    assert!(i.compression.starts_with("lzw"), "{}", i.compression);
    for r in 0..50 {
        for c in 0..70 {
            assert_eq!(g.z[r * 70 + c], expected(r, c), "row {r}, column {c}");
        }
    }
    // A window across the right-edge tiles, as a tile job reads it.
    let (rows, cols) = ([10, 40], [60, 69]);
    let (_, z) = tin::dem::read_dem_window_heights(&path, &DemOptions::default(), rows, cols).expect("window");
    for (k, &v) in z.iter().enumerate() {
        let (r, c) = (rows[0] + k / 10, cols[0] + k % 10);
        assert_eq!(v, expected(r, c), "window row {r}, column {c}");
    }
}

/// A GeoTIFF cut short (a partial download) is named as such, with the strip that runs past its end.
#[test]
fn a_truncated_geotiff_is_named_truncated() {
    let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/lzw_tiles_70x50.tif"));
    let bytes = std::fs::read(&path).expect("fixture");
    let cut = &bytes[..bytes.len() / 2];
    let msg = message(parse_geotiff(cut, Path::new("test.tif"), &DemOptions::default()));
    assert!(msg.contains("truncated") && msg.contains("strip or tile"), "{msg}");
}

// ---------------------------------------------------------------- written by the tests

/// GeoKeys of a projected CRS in metres (EPSG:32633), pixel-is-area.
const KEYS_UTM: [u16; 16] = [1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, 32633];

/// How to write a test GeoTIFF.
struct Spec<'a> {
    keys: Option<&'a [u16]>,
    scale: Option<[f64; 3]>,
    tie: Option<Vec<f64>>,
    transform: Option<[f64; 16]>,
    nodata: Option<&'a str>,
    /// GDAL's metadata XML (tag 42112).
    metadata: Option<&'a str>,
    compression: Compression,
    predictor: Predictor,
}

impl Default for Spec<'_> {
    fn default() -> Self {
        Spec {
            keys: Some(&KEYS_UTM),
            scale: Some([10.0, 20.0, 0.0]),
            tie: Some(vec![0.0, 0.0, 0.0, 500_000.0, 4_000_000.0, 0.0]),
            transform: None,
            nodata: None,
            metadata: None,
            compression: Compression::Uncompressed,
            predictor: Predictor::None,
        }
    }
}

/// A TIFF of `$ct` samples written by the `tiff` encoder (`TiffEncoder::new`, or the constructor given first, e.g.
/// `TiffEncoder::new_big` for a BigTIFF) with the tags of `$spec`.
macro_rules! write_tif {
    ($ct:ty, $w:expr, $h:expr, $data:expr, $spec:expr) => {
        write_tif!(TiffEncoder::new, $ct, $w, $h, $data, $spec)
    };
    ($new:path, $ct:ty, $w:expr, $h:expr, $data:expr, $spec:expr) => {{
        let spec: &Spec = $spec;
        let mut buf = Cursor::new(Vec::new());
        {
            let mut enc = $new(&mut buf)
                .expect("encoder")
                .with_compression(spec.compression)
                .with_predictor(spec.predictor);
            let mut img = enc.new_image::<$ct>($w, $h).expect("image");
            img.rows_per_strip(2).expect("strips");
            let d = img.encoder();
            if let Some(k) = spec.keys {
                d.write_tag(Tag::GeoKeyDirectoryTag, k).expect("tag");
            }
            if let Some(s) = spec.scale {
                d.write_tag(Tag::ModelPixelScaleTag, &s[..]).expect("tag");
            }
            if let Some(t) = &spec.tie {
                d.write_tag(Tag::ModelTiepointTag, &t[..]).expect("tag");
            }
            if let Some(m) = spec.transform {
                d.write_tag(Tag::ModelTransformationTag, &m[..]).expect("tag");
            }
            if let Some(n) = spec.nodata {
                d.write_tag(Tag::Unknown(42113), n).expect("tag");
            }
            if let Some(m) = spec.metadata {
                d.write_tag(Tag::Unknown(42112), m).expect("tag");
            }
            img.write_data($data).expect("data");
        }
        buf.into_inner()
    }};
}

fn parse(bytes: &[u8]) -> tin::Result<(Grid, GeoTiffInfo)> {
    parse_geotiff(bytes, Path::new("test.tif"), &DemOptions::default())
}

fn message(r: tin::Result<(Grid, GeoTiffInfo)>) -> String {
    match r {
        Err(TinError::Format { path, message }) => {
            assert_eq!(path, Path::new("test.tif"));
            message
        }
        Err(e) => panic!("expected a format error, got {e}"),
        Ok((g, _)) => panic!("expected an error, got a {} x {} grid", g.rows, g.cols),
    }
}

#[test]
fn sample_types_compressions_and_predictors() {
    let (w, h) = (5u32, 4u32);
    let vals: Vec<f64> = (0..w * h).map(|i| f64::from(i) * 3.0 + 100.0).collect();
    let check = |bytes: Vec<u8>, ty: &str| {
        let (g, i) = parse(&bytes).unwrap_or_else(|e| panic!("{ty}: {e}"));
        assert_eq!(i.sample_type, ty);
        assert_eq!((g.rows, g.cols), (4, 5));
        assert_eq!((g.dx, g.dy), (10.0, 20.0));
        assert_eq!(g.origin, DVec2::new(500_005.0, 3_999_990.0));
        assert!(same_heights(&g.z, &vals), "{ty}: {:?}", g.z);
    };
    for (c, p) in [
        (Compression::Uncompressed, Predictor::None),
        (Compression::Lzw, Predictor::None),
        (Compression::Lzw, Predictor::Horizontal),
        (Compression::Deflate(Default::default()), Predictor::Horizontal),
    ] {
        let spec = Spec {
            compression: c,
            predictor: p,
            ..Spec::default()
        };
        let i16s: Vec<i16> = vals.iter().map(|&v| v as i16).collect();
        check(write_tif!(colortype::GrayI16, w, h, &i16s, &spec), "int16");
        let i32s: Vec<i32> = vals.iter().map(|&v| v as i32).collect();
        check(write_tif!(colortype::GrayI32, w, h, &i32s, &spec), "int32");
        let u16s: Vec<u16> = vals.iter().map(|&v| v as u16).collect();
        check(write_tif!(colortype::Gray16, w, h, &u16s, &spec), "uint16");
        if p == Predictor::None {
            let f32s: Vec<f32> = vals.iter().map(|&v| v as f32).collect();
            check(write_tif!(colortype::Gray32Float, w, h, &f32s, &spec), "float32");
            check(write_tif!(colortype::Gray64Float, w, h, &vals, &spec), "float64");
        }
    }
}

/// A BigTIFF (64-bit offsets, as GDAL writes files over 4 GB or with `BIGTIFF=YES`) reads as the classic TIFF of the
/// same samples and tags does, from bytes and from a file; its magic number is recognised in a file without a DEM
/// extension.
#[test]
fn a_bigtiff_reads_like_a_classic_tiff() {
    let (w, h) = (6u32, 5u32);
    let vals: Vec<f32> = (0..w * h).map(|i| (i * 29 % 17) as f32 * 2.5 + 80.0).collect();
    let spec = Spec {
        compression: Compression::Deflate(Default::default()),
        ..Spec::default()
    };
    let classic = write_tif!(colortype::Gray32Float, w, h, &vals, &spec);
    let big = write_tif!(TiffEncoder::new_big, colortype::Gray32Float, w, h, &vals, &spec);
    assert_eq!(&big[..4], b"II+\0", "a BigTIFF");
    let (g, i) = parse(&big).expect("the BigTIFF");
    assert_eq!(i.compression, "deflate, predictor none");
    assert_eq!(g, parse(&classic).expect("the classic TIFF").0);
    let dir = tempfile::tempdir().expect("temporary directory");
    let file = dir.path().join("big.tif");
    std::fs::write(&file, &big).expect("write");
    assert_eq!(read_dem(&file, &DemOptions::default()).expect("read_dem"), g);
    let unnamed = dir.path().join("big");
    std::fs::write(&unnamed, &big).expect("write");
    let e = read_dem(&unnamed, &DemOptions::default())
        .expect_err("no extension")
        .to_string();
    assert!(e.contains("it starts like a TIFF"), "{e}");
}

/// `bytes` (a little-endian TIFF with uncompressed strips or tiles, as `write_tif!` writes them) with every strip or
/// tile compressed by ZSTD (compression 50000, as GDAL's `COMPRESS=ZSTD` writes it): the chunks are appended
/// compressed and the compression, offsets and byte counts rewritten in the IFD.
fn zstd_chunks(mut bytes: Vec<u8>) -> Vec<u8> {
    let u32_at = |b: &[u8], at: usize| u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"));
    let entry = |b: &[u8], tag: u16| ifd_entry(b, tag).unwrap_or_else(|| panic!("no tag {tag}"));
    // The values of a LONG array entry: inline when there is one, else at its offset.
    let longs = |b: &[u8], e: usize| {
        assert_eq!(u16::from_le_bytes([b[e + 2], b[e + 3]]), 4, "LONG values");
        let n = u32_at(b, e + 4) as usize;
        let at = if n == 1 { e + 8 } else { u32_at(b, e + 8) as usize };
        (0..n).map(|i| at + 4 * i).collect::<Vec<usize>>()
    };
    set_compression(&mut bytes, 50000);
    // StripOffsets and StripByteCounts, or TileOffsets and TileByteCounts.
    let [offsets, counts] = match ifd_entry(&bytes, 273) {
        Some(strips) => [strips, entry(&bytes, 279)],
        None => [entry(&bytes, 324), entry(&bytes, 325)],
    }
    .map(|e| longs(&bytes, e));
    for (&o, &c) in offsets.iter().zip(&counts) {
        let (start, len) = (u32_at(&bytes, o) as usize, u32_at(&bytes, c) as usize);
        let packed = zstd::encode_all(&bytes[start..start + len], 3).expect("zstd");
        let at = u32::try_from(bytes.len()).expect("small");
        bytes.extend_from_slice(&packed);
        bytes[o..o + 4].copy_from_slice(&at.to_le_bytes());
        bytes[c..c + 4].copy_from_slice(&u32::try_from(packed.len()).expect("small").to_le_bytes());
    }
    bytes
}

/// Rewrites the Compression tag (a SHORT held in its entry) of a little-endian classic TIFF.
fn set_compression(b: &mut [u8], code: u16) {
    let e = ifd_entry(b, 259).expect("a Compression tag");
    b[e + 8..e + 10].copy_from_slice(&code.to_le_bytes());
}

/// Compressions the `tiff` crate does not decode (those GDAL writes named) are refused before any sample is read,
/// saying which are read and how to convert the file.
#[test]
fn compressions_not_read_are_named() {
    let data: Vec<i16> = (0..20).collect();
    for (code, name) in [
        (34887u16, "compression 34887 (LERC)"),
        (7, "compression 7 (JPEG)"),
        (9, "compression 9 "),
    ] {
        let mut b = write_tif!(colortype::GrayI16, 5, 4, &data, &Spec::default());
        set_compression(&mut b, code);
        let m = message(parse(&b));
        assert!(
            m.starts_with(name) && m.contains("ZSTD are") && m.contains("gdal_translate"),
            "{m}"
        );
    }
}

/// ZSTD strips (GDAL's `COMPRESS=ZSTD`), with and without the horizontal predictor, decode to the same heights.
#[test]
fn zstd_compressed_strips_decode() {
    let (w, h) = (7u32, 5u32);
    let vals: Vec<f64> = (0..w * h).map(|i| f64::from(i * 37 % 23) * 4.0 + 250.0).collect();
    for p in [Predictor::None, Predictor::Horizontal] {
        let spec = Spec {
            predictor: p,
            ..Spec::default()
        };
        let i16s: Vec<i16> = vals.iter().map(|&v| v as i16).collect();
        let u16s: Vec<u16> = vals.iter().map(|&v| v as u16).collect();
        let f32s: Vec<f32> = vals.iter().map(|&v| v as f32).collect();
        let mut files = vec![
            ("int16", write_tif!(colortype::GrayI16, w, h, &i16s, &spec)),
            ("uint16", write_tif!(colortype::Gray16, w, h, &u16s, &spec)),
        ];
        if p == Predictor::None {
            files.push(("float32", write_tif!(colortype::Gray32Float, w, h, &f32s, &spec)));
        }
        for (ty, plain) in files {
            let packed = zstd_chunks(plain.clone());
            let (g, i) = parse(&packed).unwrap_or_else(|e| panic!("{ty}, {p:?}: {e}"));
            assert_eq!(i.sample_type, ty);
            let predictor = if p == Predictor::None { "none" } else { "horizontal" };
            assert_eq!(i.compression, format!("zstd, predictor {predictor}"));
            assert_eq!((g.rows, g.cols), (5, 7));
            assert!(same_heights(&g.z, &vals), "{ty}, {p:?}: {:?}", g.z);
            assert_eq!(g, parse(&plain).expect("the uncompressed file").0, "{ty}, {p:?}");
            // Cut short inside the last strip's compressed bytes: named as truncated; a strip that is not ZSTD
            // data (its frame's magic number broken): named with its compression. Never a panic.
            let m = message(parse(&packed[..packed.len() - 3]));
            assert!(
                m.contains("(zstd, predictor") && m.contains("a truncated file?"),
                "{ty}, {p:?}: {m}"
            );
            let mut broken = packed.clone();
            broken[plain.len()] ^= 0xff;
            let m = message(parse(&broken));
            assert!(
                m.starts_with("cannot decode strip or tile 0 (zstd, predictor"),
                "{ty}, {p:?}: {m}"
            );
        }
    }
}

#[test]
fn nodata_pixel_is_point_and_transformation() {
    let data: Vec<f32> = vec![1.0, -9999.0, 3.0, f32::NAN, 5.0, 6.0];
    let keys: [u16; 16] = [1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 2, 3076, 0, 1, 9001];
    let spec = Spec {
        keys: Some(&keys),
        nodata: Some("-9999"),
        ..Spec::default()
    };
    let (g, i) = parse(&write_tif!(colortype::Gray32Float, 3, 2, &data, &spec)).expect("point");
    assert_eq!(i.raster_type, RasterType::PixelIsPoint);
    assert_eq!(g.voids(), 2);
    // GDAL's scale and offset (as `gdal_translate -a_scale 0.1 -a_offset -1000` writes them) give the heights; the
    // nodata value is a raw sample.
    let raw: Vec<u16> = vec![21000, 21835, 0, 21010, 21020, 21030];
    let xml = r#"<GDALMetadata>
  <Item name="OFFSET" sample="0" role="offset">-1000</Item>
  <Item name="SCALE" sample="0" role="scale">0.1</Item>
</GDALMetadata>"#;
    let spec = Spec {
        keys: Some(&keys),
        nodata: Some("0"),
        metadata: Some(xml),
        ..Spec::default()
    };
    let (sc, si) = parse(&write_tif!(colortype::Gray16, 3, 2, &raw, &spec)).expect("scaled");
    assert_eq!(si.scale_offset, Some((0.1, -1000.0)));
    assert_eq!(sc.voids(), 1);
    assert!(
        (sc.z[0] - 1100.0).abs() < 1e-9 && (sc.z[1] - 1183.5).abs() < 1e-9,
        "{:?}",
        sc.z
    );
    let spec = Spec {
        keys: Some(&keys),
        metadata: Some(r#"<GDALMetadata><Item name="SCALE" sample="0" role="scale">x</Item></GDALMetadata>"#),
        ..Spec::default()
    };
    let msg = message(parse(&write_tif!(colortype::Gray16, 3, 2, &raw, &spec)));
    assert!(msg.contains("GDAL_METADATA") && msg.contains("\"x\""), "{msg}");
    // The largest float32 as nodata, written in its short form: those samples are voids.
    let fill: Vec<f32> = vec![-f32::MAX, 2.0, 3.0, 4.0, -f32::MAX, 6.0];
    for text in ["-3.40282e+38", "-3.4028234663852886e+38", "-3.40282346638528859812e+38"] {
        let spec = Spec {
            keys: Some(&keys),
            nodata: Some(text),
            ..Spec::default()
        };
        let (f, _) = parse(&write_tif!(colortype::Gray32Float, 3, 2, &fill, &spec)).expect(text);
        assert_eq!(f.voids(), 2, "{text}");
    }
    assert_eq!(g.origin, DVec2::new(500_000.0, 4_000_000.0));
    assert_eq!(i.epsg, None);
    // The same georeference as a ModelTransformation (pixel-is-point): x = 10 i + 500000, y = -20 j + 4000000.
    let mut m = [0.0; 16];
    (m[0], m[3], m[5], m[7], m[15]) = (10.0, 500_000.0, -20.0, 4_000_000.0, 1.0);
    let spec = Spec {
        keys: Some(&keys),
        scale: None,
        tie: None,
        transform: Some(m),
        ..Spec::default()
    };
    let (t, _) = parse(&write_tif!(colortype::Gray32Float, 3, 2, &data, &spec)).expect("transformation");
    assert_eq!((t.dx, t.dy, t.origin), (10.0, 20.0, g.origin));
    // Rotated: an error naming the tag.
    m[1] = 0.5;
    let spec = Spec {
        keys: Some(&keys),
        scale: None,
        tie: None,
        transform: Some(m),
        ..Spec::default()
    };
    let msg = message(parse(&write_tif!(colortype::Gray32Float, 3, 2, &data, &spec)));
    assert!(msg.contains("ModelTransformation") && msg.contains("rotates"), "{msg}");
}

#[test]
fn geographic_arc_seconds_snap_to_whole_fractions() {
    // EPSG:4326, pixel-is-area, 1" cells stored as rounded decimals.
    let keys: [u16; 16] = [1, 1, 0, 3, 1024, 0, 1, 2, 1025, 0, 1, 1, 2048, 0, 1, 4326];
    let step = 0.000277777777777778;
    let spec = Spec {
        keys: Some(&keys),
        scale: Some([step, step, 0.0]),
        tie: Some(vec![0.0, 0.0, 0.0, 10.0 - step / 2.0, 46.0 + step / 2.0, 0.0]),
        ..Spec::default()
    };
    let data = vec![1i16; 12];
    let (g, i) = parse(&write_tif!(colortype::GrayI16, 4, 3, &data, &spec)).expect("geographic");
    assert_eq!(i.crs_kind, CrsKind::Geographic);
    assert_eq!(g.dy, METRES_PER_DEGREE / 3600.0);
    assert!((g.origin.y - 46.0 * METRES_PER_DEGREE).abs() < 1e-6);
    // Not degrees after all: latitudes out of range.
    let spec = Spec {
        keys: Some(&keys),
        ..Spec::default()
    };
    let msg = message(parse(&write_tif!(colortype::GrayI16, 4, 3, &data, &spec)));
    assert!(msg.contains("-90..90"), "{msg}");
}

/// A projected CRS in feet (as US state-plane rasters are) is put into metres: x, y by the CRS's foot, heights by
/// `VerticalUnitsGeoKey`'s unit, or without one by the CRS's foot too (said in the conversion); a vertical unit in
/// feet on a metric CRS converts the heights alone.
#[test]
fn feet_are_put_into_metres() {
    let data: Vec<f32> = vec![100.0, 200.0, 300.0, 400.0, 500.0, -9999.0];
    let survey = 1200.0 / 3937.0;
    let tie = Some(vec![0.0, 0.0, 0.0, 2_000_000.0, 500_000.0, 0.0]);
    let read = |keys: &[u16]| {
        let spec = Spec {
            keys: Some(keys),
            scale: Some([10.0, 20.0, 0.0]),
            tie: tie.clone(),
            nodata: Some("-9999"),
            ..Spec::default()
        };
        parse(&write_tif!(colortype::Gray32Float, 3, 2, &data, &spec)).expect("reads")
    };
    // US survey feet, heights unstated: both in US survey feet.
    let (g, i) = read(&[1, 1, 0, 2, 1024, 0, 1, 1, 3076, 0, 1, 9003]);
    assert_eq!((g.dx, g.dy), (10.0 * survey, 20.0 * survey));
    assert_eq!(g.origin, DVec2::new(2_000_005.0 * survey, 499_990.0 * survey));
    assert_eq!(
        g.z[..5],
        [
            100.0 * survey,
            200.0 * survey,
            300.0 * survey,
            400.0 * survey,
            500.0 * survey
        ]
    );
    assert!(g.z[5].is_nan(), "nodata is judged on the raw sample");
    assert!(i.crs.contains("US survey feet"), "{}", i.crs);
    assert!(
        i.conversion.contains("x, y in US survey feet") && i.conversion.contains("assumed"),
        "{}",
        i.conversion
    );
    assert_eq!(i.native_spacing, (10.0, 20.0));
    assert!(i.heights_unit_assumed && i.height_unit_m == survey);
    // International feet across, heights said to be metres.
    let (g, i) = read(&[1, 1, 0, 3, 1024, 0, 1, 1, 3076, 0, 1, 9002, 4099, 0, 1, 9001]);
    assert_eq!((g.dx, g.dy), (10.0 * 0.3048, 20.0 * 0.3048));
    assert_eq!(g.z[..5], [100.0, 200.0, 300.0, 400.0, 500.0]);
    assert!(
        i.conversion.contains("international feet") && !i.conversion.contains("heights"),
        "{}",
        i.conversion
    );
    // Metres across, heights in international feet.
    let (g, i) = read(&[1, 1, 0, 3, 1024, 0, 1, 1, 3076, 0, 1, 9001, 4099, 0, 1, 9002]);
    assert_eq!((g.dx, g.dy), (10.0, 20.0));
    assert_eq!(g.origin, DVec2::new(2_000_005.0, 499_990.0));
    assert_eq!(g.z[0], 100.0 * 0.3048);
    assert_eq!(
        i.conversion,
        "heights in international feet times 0.3048 m (VerticalUnitsGeoKey)"
    );
    assert!(!i.heights_unit_assumed && i.height_unit_m == 0.3048);
    // Metres throughout: nothing converted.
    let (g, i) = read(&[1, 1, 0, 2, 1024, 0, 1, 1, 3076, 0, 1, 9001]);
    assert_eq!((g.dx, g.z[0]), (10.0, 100.0));
    assert!(i.conversion.is_empty());
}

/// Appends to the little-endian classic TIFF `tiff` an uncompressed 1-bit image of `w` × `h` samples as GDAL writes
/// a nodata mask (`PhotometricInterpretation` 4, `NewSubfileType` `subfile`), rows of whole bytes, most significant
/// bit first: one strip, or with `tile` one tile of that side (rows of `tile / 8` bytes); the last image's next-IFD
/// pointer is set to it.
fn append_bit_mask(tiff: &mut Vec<u8>, w: u32, h: u32, rows: &[u8], subfile: u32, tile: Option<u32>) {
    let u16_at = |b: &[u8], o: usize| usize::from(u16::from_le_bytes([b[o], b[o + 1]]));
    let u32_at = |b: &[u8], o: usize| u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]) as usize;
    let mut ifd = u32_at(tiff, 4);
    let next_at = loop {
        let next_at = ifd + 2 + 12 * u16_at(tiff, ifd);
        match u32_at(tiff, next_at) {
            0 => break next_at,
            next => ifd = next,
        }
    };
    let data_at = tiff.len() as u32;
    tiff.extend_from_slice(rows);
    if tiff.len() % 2 == 1 {
        tiff.push(0);
    }
    let ifd_at = tiff.len() as u32;
    tiff[next_at..next_at + 4].copy_from_slice(&ifd_at.to_le_bytes());
    let (short, long) = (3u16, 4u16);
    let mut entries: Vec<(u16, u16, u32)> = vec![
        (254, long, subfile),
        (256, short, w),
        (257, short, h),
        (258, short, 1),
        (259, short, 1),
        (262, short, 4),
        (277, short, 1),
        (284, short, 1),
    ];
    let n = rows.len() as u32;
    match tile {
        None => entries.extend([(273, long, data_at), (278, short, h), (279, long, n)]),
        Some(t) => entries.extend([(322, short, t), (323, short, t), (324, long, data_at), (325, long, n)]),
    }
    entries.sort_unstable();
    tiff.extend_from_slice(&(entries.len() as u16).to_le_bytes());
    for (tag, ty, value) in entries {
        tiff.extend_from_slice(&tag.to_le_bytes());
        tiff.extend_from_slice(&ty.to_le_bytes());
        tiff.extend_from_slice(&1u32.to_le_bytes());
        // A SHORT is left-justified in the value field: its little-endian bytes, then zeros, as a LONG's.
        tiff.extend_from_slice(&value.to_le_bytes());
    }
    tiff.extend_from_slice(&0u32.to_le_bytes());
}

/// A GeoTIFF of 3 × 2 int16 samples, with an 8-bit image after them when `mask` is given (its `NewSubfileType`; 0 at
/// sample 1, 255 elsewhere).
fn samples_3x2(mask: Option<u32>) -> Vec<u8> {
    let mut buf = Cursor::new(Vec::new());
    {
        let mut enc = TiffEncoder::new(&mut buf).expect("encoder");
        let mut img = enc.new_image::<colortype::GrayI16>(3, 2).expect("image");
        img.encoder()
            .write_tag(Tag::GeoKeyDirectoryTag, &KEYS_UTM[..])
            .expect("tag");
        img.encoder()
            .write_tag(Tag::ModelPixelScaleTag, &[10.0f64, 10.0, 0.0][..])
            .expect("tag");
        img.encoder()
            .write_tag(Tag::ModelTiepointTag, &[0.0f64, 0.0, 0.0, 5e5, 4e6, 0.0][..])
            .expect("tag");
        img.write_data(&[1i16, 2, 3, 4, 5, 6]).expect("data");
        if let Some(kind) = mask {
            let mut second = enc.new_image::<colortype::Gray8>(3, 2).expect("image");
            second.encoder().write_tag(Tag::NewSubfileType, kind).expect("tag");
            second.write_data(&[255u8, 0, 255, 255, 255, 255]).expect("data");
        }
    }
    buf.into_inner()
}

/// GDAL's nodata masks are applied, whole and in windows: an 8-bit mask image, a 1-bit transparency mask as GDAL
/// writes it (which the `tiff` crate alone refuses to decode), and a `.msk` file beside the GeoTIFF; an overview's
/// mask is not the image's; a `.msk` of another size is an error naming it.
#[test]
fn nodata_masks_are_applied() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("m.tif");
    let opts = DemOptions::default();
    let heights = |path: &Path| {
        let (g, info) = read_geotiff_info(path, &opts).expect("reads");
        let (_, w) = tin::dem::read_dem_window_heights(path, &opts, [1, 1], [1, 2]).expect("window");
        // The window (row 1, columns 1 and 2) as the whole read has it.
        assert!(
            w.iter()
                .zip(&g.z[4..6])
                .all(|(a, b)| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())),
            "{w:?} {:?}",
            g.z
        );
        (g.z.iter().map(|z| z.is_nan()).collect::<Vec<_>>(), info.nodata_mask)
    };
    std::fs::write(&path, samples_3x2(None)).expect("write");
    assert_eq!(heights(&path), (vec![false; 6], None));
    // An image that is not a mask, and an overview's mask (NewSubfileType 5), are not applied.
    for kind in [0, 5] {
        std::fs::write(&path, samples_3x2(Some(kind))).expect("write");
        assert_eq!(heights(&path).0, vec![false; 6], "NewSubfileType {kind}");
    }
    // The 8-bit mask: the grid's north-west sample is row 0, so sample 1 of the file is grid sample 1.
    std::fs::write(&path, samples_3x2(Some(4))).expect("write");
    let (voids, said) = heights(&path);
    assert_eq!(voids, [false, true, false, false, false, false]);
    let said = said.expect("described");
    assert!(
        said.contains("image 2 of the file") && said.contains("1 samples voided"),
        "{said}"
    );
    // A 1-bit transparency mask as GDAL writes it: rows 101 and 110.
    let bits = masked_geotiff();
    std::fs::write(&path, &bits).expect("write");
    assert_eq!(heights(&path).0, [false, true, false, false, false, true]);
    // The same mask in one 16 × 16 tile (GDAL tiles the mask of a tiled GeoTIFF): the samples right of and below the
    // image are padding.
    let mut tiled = samples_3x2(None);
    let mut tile = vec![0xffu8; 32];
    tile[..4].copy_from_slice(&[0b1010_0000, 0xff, 0b1100_0000, 0xff]);
    append_bit_mask(&mut tiled, 3, 2, &tile, 4, Some(16));
    std::fs::write(&path, &tiled).expect("write");
    assert_eq!(heights(&path).0, [false, true, false, false, false, true]);
    // The same bytes in memory.
    let (g, _) = parse_geotiff(&bits, &path, &opts).expect("parses");
    assert!(g.z[1].is_nan() && g.z[5].is_nan() && g.z[0] == 1.0);
    // A `.msk` file beside the GeoTIFF: its first image is the mask (the 8-bit one here).
    std::fs::write(&path, samples_3x2(None)).expect("write");
    let msk = dir.path().join("m.tif.msk");
    let mut mask_file = Cursor::new(Vec::new());
    {
        let mut enc = TiffEncoder::new(&mut mask_file).expect("encoder");
        enc.write_image::<colortype::Gray8>(3, 2, &[0, 255, 255, 255, 255, 0])
            .expect("mask");
    }
    std::fs::write(&msk, mask_file.into_inner()).expect("write");
    let (voids, said) = heights(&path);
    assert_eq!(voids, [true, false, false, false, false, true]);
    assert!(said.expect("described").contains("m.tif.msk"));
    // An internal mask is used before a `.msk` file (GDAL's order).
    std::fs::write(&path, samples_3x2(Some(4))).expect("write");
    assert_eq!(heights(&path).0, [false, true, false, false, false, false]);
    std::fs::write(&path, samples_3x2(None)).expect("write");
    // A `.msk` of another size, or not a TIFF: an error naming it.
    let mut wrong = Cursor::new(Vec::new());
    {
        let mut enc = TiffEncoder::new(&mut wrong).expect("encoder");
        enc.write_image::<colortype::Gray8>(2, 2, &[255; 4]).expect("mask");
    }
    std::fs::write(&msk, wrong.into_inner()).expect("write");
    let e = read_geotiff_info(&path, &opts).expect_err("wrong size").to_string();
    assert!(e.contains("m.tif.msk") && e.contains("2 x 2 samples"), "{e}");
    std::fs::write(&msk, b"II*\0").expect("write");
    let e = read_geotiff_info(&path, &opts).expect_err("not a TIFF").to_string();
    assert!(e.contains("m.tif.msk"), "{e}");
}

/// [`samples_3x2`] with a 1-bit nodata mask as GDAL writes it (rows 101 and 110).
fn masked_geotiff() -> Vec<u8> {
    let mut bytes = samples_3x2(None);
    append_bit_mask(&mut bytes, 3, 2, &[0b1010_0000, 0b1100_0000], 4, None);
    bytes
}

proptest::proptest! {
    /// A masked GeoTIFF with any few bytes changed (the mask's tags and data included) is read or refused with an
    /// error, never a panic.
    #[test]
    fn mutated_masked_geotiffs_never_panic(
        edits in proptest::collection::vec((proptest::num::usize::ANY, proptest::num::u8::ANY), 1..4),
    ) {
        let mut bytes = masked_geotiff();
        let n = bytes.len();
        for (at, b) in edits {
            bytes[at % n] = b;
        }
        let _ = parse_geotiff(&bytes, Path::new("mutated.tif"), &DemOptions::default());
    }
}

#[test]
fn clear_errors() {
    let data = vec![1i16; 6];
    // A plain TIFF: no GeoKeys, no scale and tie point, no spacing given.
    let no_keys = Spec {
        keys: None,
        scale: None,
        tie: None,
        ..Spec::default()
    };
    let msg = message(parse(&write_tif!(colortype::GrayI16, 3, 2, &data, &no_keys)));
    assert!(msg.contains("GeoKeyDirectory") && msg.contains("--spacing"), "{msg}");
    let yards: [u16; 12] = [1, 1, 0, 2, 1024, 0, 1, 1, 3076, 0, 1, 9096];
    let spec = Spec {
        keys: Some(&yards),
        ..Spec::default()
    };
    let msg = message(parse(&write_tif!(colortype::GrayI16, 3, 2, &data, &spec)));
    assert!(
        msg.contains("ProjLinearUnitsGeoKey (3076) = 9096") && msg.contains("US survey feet"),
        "{msg}"
    );
    let fathoms: [u16; 16] = [1, 1, 0, 3, 1024, 0, 1, 1, 3076, 0, 1, 9001, 4099, 0, 1, 9014];
    let spec = Spec {
        keys: Some(&fathoms),
        ..Spec::default()
    };
    let msg = message(parse(&write_tif!(colortype::GrayI16, 3, 2, &data, &spec)));
    assert!(msg.contains("VerticalUnitsGeoKey (4099) = 9014"), "{msg}");
    let unknown: [u16; 8] = [1, 1, 0, 1, 1024, 0, 1, 1];
    let spec = Spec {
        keys: Some(&unknown),
        ..Spec::default()
    };
    let msg = message(parse(&write_tif!(colortype::GrayI16, 3, 2, &data, &spec)));
    assert!(msg.contains("unknown units"), "{msg}");
    let radians: [u16; 12] = [1, 1, 0, 2, 1024, 0, 1, 2, 2054, 0, 1, 9101];
    let spec = Spec {
        keys: Some(&radians),
        ..Spec::default()
    };
    let msg = message(parse(&write_tif!(colortype::GrayI16, 3, 2, &data, &spec)));
    assert!(msg.contains("GeogAngularUnitsGeoKey"), "{msg}");
    let no_geo = Spec {
        scale: None,
        tie: None,
        ..Spec::default()
    };
    let msg = message(parse(&write_tif!(colortype::GrayI16, 3, 2, &data, &no_geo)));
    assert!(msg.contains("ModelPixelScale"), "{msg}");
    let two_ties = Spec {
        tie: Some(vec![0.0; 12]),
        ..Spec::default()
    };
    let msg = message(parse(&write_tif!(colortype::GrayI16, 3, 2, &data, &two_ties)));
    assert!(msg.contains("ModelTiepoint"), "{msg}");
    // Multi-band: an error without a chosen band, the band with one.
    let rgb: Vec<u16> = (0..18).collect();
    let bytes = write_tif!(colortype::RGB16, 3, 2, &rgb, &Spec::default());
    let msg = message(parse(&bytes));
    assert!(msg.contains("3 bands") && msg.contains("SamplesPerPixel"), "{msg}");
    let opts = DemOptions {
        band: Some(2),
        ..DemOptions::default()
    };
    let (g, i) = parse_geotiff(&bytes, Path::new("test.tif"), &opts).expect("band 2");
    assert_eq!(g.z, vec![1.0, 4.0, 7.0, 10.0, 13.0, 16.0]);
    assert_eq!(i.bands, (3, 2));
    // Garbage and truncation.
    let msg = message(parse(b"II*\0garbage"));
    assert!(!msg.is_empty());
    let good = write_tif!(colortype::GrayI16, 3, 2, &data, &Spec::default());
    for cut in [8, good.len() / 2, good.len() - 1] {
        assert!(parse(&good[..cut]).is_err(), "cut at {cut}");
    }
}

/// A plain TIFF (no georeference) reads like a PNG height map once a spacing is given: metres, the south-western
/// sample at (0, 0), row 0 north.
#[test]
fn a_plain_tiff_reads_with_a_given_spacing() {
    let data: Vec<f32> = (0..12).map(|i| i as f32 * 1.5).collect();
    let no_keys = Spec {
        keys: None,
        scale: None,
        tie: None,
        ..Spec::default()
    };
    let bytes = write_tif!(colortype::Gray32Float, 4, 3, &data, &no_keys);
    let opts = DemOptions {
        spacing: Some((10.0, 20.0)),
        ..DemOptions::default()
    };
    let (g, info) = parse_geotiff(&bytes, Path::new("plain.tif"), &opts).expect("reads with a spacing");
    assert_eq!((g.rows, g.cols, g.dx, g.dy), (3, 4, 10.0, 20.0));
    assert_eq!(
        g.origin,
        DVec2::new(0.0, 40.0),
        "north-west sample centre; south-west at (0, 0)"
    );
    assert_eq!(g.z, data.iter().map(|&v| f64::from(v)).collect::<Vec<_>>());
    assert!(info.crs.contains("plain TIFF"), "{}", info.crs);
}

/// A TIFF with a pixel scale and tie point but no GeoKeys (a world file turned into tags, say) keeps its place:
/// the tie point, taken as metres (no CRS, as GDAL reads it), pixel-is-area; `--spacing` overrides the spacing only.
#[test]
fn a_georeference_without_geokeys_is_kept_as_metres() {
    let data: Vec<f32> = (0..12).map(|i| i as f32).collect();
    let no_keys = Spec {
        keys: None,
        ..Spec::default()
    };
    let bytes = write_tif!(colortype::Gray32Float, 4, 3, &data, &no_keys);
    let (g, info) = parse(&bytes).expect("reads without a spacing");
    assert_eq!((g.rows, g.cols, g.dx, g.dy), (3, 4, 10.0, 20.0));
    // Pixel-is-area: the tie point (500000, 4000000) is the corner of sample (0, 0), its centre half a cell in.
    assert_eq!(g.origin, DVec2::new(500_005.0, 3_999_990.0));
    assert!(info.crs.contains("no GeoKeyDirectory"), "{}", info.crs);
    let opts = DemOptions {
        spacing: Some((1.0, 2.0)),
        ..DemOptions::default()
    };
    let (g, _) = parse_geotiff(&bytes, Path::new("test.tif"), &opts).expect("reads with a spacing");
    assert_eq!((g.dx, g.dy), (1.0, 2.0));
    assert_eq!(g.origin, DVec2::new(500_005.0, 3_999_990.0), "the tie point stays");
    // A transformation instead of a scale and tie point.
    let transform = Spec {
        keys: None,
        scale: None,
        tie: None,
        transform: Some([
            10.0, 0.0, 0.0, 300.0, 0.0, -20.0, 0.0, 900.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ]),
        ..Spec::default()
    };
    let bytes = write_tif!(colortype::Gray32Float, 4, 3, &data, &transform);
    let (g, _) = parse(&bytes).expect("reads");
    assert_eq!((g.dx, g.dy, g.origin), (10.0, 20.0, DVec2::new(305.0, 890.0)));
}

/// Regression: `read_geotiff_info` (what `tincull tin` and `build` call for a `.tif`, for its CRS and units) returned
/// the grid without the checks `read_dem` makes, so coordinates out of range, or a spacing too fine for them, reached
/// the simplification, which failed on a degenerate triangle naming neither the file nor the cause.
#[test]
fn read_geotiff_info_checks_the_grid_as_read_dem_does() {
    let dir = tempfile::tempdir().expect("tempdir");
    let data: Vec<f32> = (0..12).map(|i| i as f32).collect();
    let cases = [
        (
            Some([1e-12, 1e-12, 0.0]),
            "the x spacing 1e-12 m is too fine for coordinates near 5e5 m",
        ),
        (
            Some([1e35, 10.0, 0.0]),
            "row 1, column 1 (1-based, row 1 north): x = 5e34 is outside the coordinates every stage accepts",
        ),
    ];
    for (scale, expected) in cases {
        let spec = Spec {
            scale,
            ..Spec::default()
        };
        let path = dir.path().join("bad.tif");
        std::fs::write(&path, write_tif!(colortype::Gray32Float, 4, 3, &data[..], &spec)).expect("write");
        for e in [
            tin::dem::geotiff::read_geotiff_info(&path, &DemOptions::default())
                .map(|(g, _)| g)
                .expect_err("refused"),
            read_dem(&path, &DemOptions::default()).expect_err("refused"),
        ] {
            assert!(
                matches!(&e, TinError::Format { path: p, message } if p == &path && message.contains(expected)),
                "{e}"
            );
        }
    }
}

mod damaged_bytes {
    use super::*;
    use proptest::prelude::*;

    /// Six small GeoTIFFs, made once.
    fn originals() -> &'static Vec<Vec<u8>> {
        static O: std::sync::OnceLock<Vec<Vec<u8>>> = std::sync::OnceLock::new();
        O.get_or_init(|| {
            let data: Vec<f32> = (0..48).map(|i| (i as f32) * 1.5 - 3.0).collect();
            let ints: Vec<i16> = (0..48).map(|i| i as i16 * 7 - 20).collect();
            let mut out = Vec::new();
            for (c, p) in [
                (Compression::Uncompressed, Predictor::None),
                (Compression::Lzw, Predictor::Horizontal),
                (Compression::Deflate(Default::default()), Predictor::Horizontal),
            ] {
                let spec = Spec {
                    compression: c,
                    predictor: Predictor::None,
                    nodata: Some("-3"),
                    ..Spec::default()
                };
                out.push(write_tif!(colortype::Gray32Float, 8, 6, &data[..], &spec));
                let spec = Spec {
                    compression: c,
                    predictor: p,
                    nodata: Some("-3"),
                    ..Spec::default()
                };
                out.push(write_tif!(colortype::GrayI16, 8, 6, &ints[..], &spec));
            }
            out
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        /// A small GeoTIFF (float32 and int16; uncompressed, LZW, Deflate; with and without a predictor) with bytes
        /// replaced and maybe cut short is read into a grid that simplifies into a TIN, or refused with an error;
        /// never a panic (in this crate or in `tiff`).
        #[test]
        fn a_geotiff_with_bytes_damaged_is_read_or_refused(
            which in 0usize..6,
            damages in prop::collection::vec((any::<usize>(), any::<u8>()), 1..4),
            cut in prop_oneof![3 => Just(None), 1 => any::<usize>().prop_map(Some)],
        ) {
            let mut bytes = originals()[which].clone();
            for (at, b) in damages {
                let n = bytes.len();
                bytes[at % n] = b;
            }
            if let Some(c) = cut {
                let n = bytes.len();
                bytes.truncate(c % n);
            }
            let dir = tempfile::tempdir().expect("tempdir");
            let path = dir.path().join("damaged.tif");
            std::fs::write(&path, &bytes).expect("write");
            if let Ok(g) = read_dem(&path, &DemOptions::default()) {
                let simplified = tin::simplify(&g, &tin::SimplifyOptions::vertices(8), None);
                prop_assert!(simplified.is_ok(), "{:?}", simplified.err());
            }
        }
    }
}
