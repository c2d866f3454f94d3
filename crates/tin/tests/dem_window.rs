//! Windowed DEM reading: `read_dem_header` and `read_dem_window` against `read_dem` and cutting the window out, bit
//! for bit, for every format (`.npy` in several element types and both orders, `.hgt`, `.asc`, PNG, GeoTIFF), for
//! fixed windows (corners, single samples, strips, the whole grid) and random ones; `read_dem_strips` over every
//! strip height; and their errors.

mod common;

use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use glam::DVec2;
use proptest::prelude::*;
use tin::dem::{GridShape, read_dem_header, read_dem_strips, read_dem_window, read_dem_window_heights};
use tin::{DemOptions, Grid, TinError, read_dem};

const R: usize = 23;
const C: usize = 17;

/// An integer value in 0..97 for sample (r, c); 13, 0 and 50 occur (used as nodata values).
fn ival(r: usize, c: usize) -> i64 {
    ((r * 31 + c * 17) % 97) as i64
}

/// A float value with voids at a few samples.
fn fval(r: usize, c: usize) -> f64 {
    if (r * C + c) % 11 == 3 {
        f64::NAN
    } else {
        ival(r, c) as f64 * 1.375 - 40.1 + r as f64 * 1e-3
    }
}

/// Writes a `.npy` file of `R` x `C` elements, each encoded by `enc`.
fn write_npy(path: &Path, version: u8, descr: &str, fortran: bool, enc: impl Fn(usize, usize) -> Vec<u8>) {
    let mut data = Vec::new();
    if fortran {
        for c in 0..C {
            for r in 0..R {
                data.extend(enc(r, c));
            }
        }
    } else {
        for r in 0..R {
            for c in 0..C {
                data.extend(enc(r, c));
            }
        }
    }
    common::write_npy(path, version, descr, fortran, &format!("({R}, {C})"), &data);
}

fn write_sidecar(npy: &Path, json: &str) {
    std::fs::write(npy.with_extension("json"), json).expect("write sidecar");
}

/// A DEM written for the tests, and what `read_dem` reads from it.
struct Fixture {
    name: &'static str,
    path: PathBuf,
    opts: DemOptions,
    whole: Grid,
}

fn hgt_value(r: usize, c: usize) -> i16 {
    if (r * 7 + c * 3) % 101 == 5 {
        -32768
    } else {
        (r as i16) * 3 - (c as i16) * 2
    }
}

fn write_fixtures(dir: &Path) -> Vec<Fixture> {
    let mut out: Vec<(&'static str, PathBuf, DemOptions)> = Vec::new();
    let opts = DemOptions::default();
    let sidecar = |nodata: &str| {
        format!(
            "{{\"spacing_x_m\": 30.0, \"spacing_y_m\": 12.5, \"easting_min\": 500123.25, \"northing_max\": 4000321.75, \
             \"nodata\": {nodata}, \"rows\": {R}, \"cols\": {C}}}"
        )
    };

    // .npy: little-endian f8 with NaN voids.
    let p = dir.join("f8.npy");
    write_npy(&p, 1, "<f8", false, |r, c| fval(r, c).to_le_bytes().to_vec());
    write_sidecar(&p, &sidecar("null"));
    out.push(("npy <f8", p, opts));
    // Big-endian f4 with NaN voids, a z scale and the northing of the southern row.
    let p = dir.join("f4be.npy");
    write_npy(&p, 1, ">f4", false, |r, c| (fval(r, c) as f32).to_be_bytes().to_vec());
    write_sidecar(
        &p,
        "{\"spacing_x_m\": 2.5, \"spacing_y_m\": 2.5, \"easting_min\": 10.0, \"northing_min\": 20.0}",
    );
    out.push(("npy >f4", p, DemOptions { z_scale: -0.3, ..opts }));
    // i2 with a nodata value in the sidecar.
    let p = dir.join("i2.npy");
    write_npy(&p, 1, "<i2", false, |r, c| {
        ((ival(r, c) - 40) as i16).to_le_bytes().to_vec()
    });
    write_sidecar(&p, &sidecar("-27"));
    out.push(("npy <i2 nodata", p, opts));
    // u1, nodata 0.
    let p = dir.join("u1.npy");
    write_npy(&p, 1, "|u1", false, |r, c| vec![ival(r, c) as u8]);
    write_sidecar(&p, &sidecar("0"));
    out.push(("npy |u1 nodata", p, opts));
    // Big-endian i8 in Fortran order, nodata 50, header version 2.
    let p = dir.join("i8f.npy");
    write_npy(&p, 2, ">i8", true, |r, c| (ival(r, c) - 1000).to_be_bytes().to_vec());
    write_sidecar(&p, &sidecar("-950"));
    out.push(("npy >i8 fortran", p, opts));
    // u4 in Fortran order, f8 in Fortran order with voids.
    let p = dir.join("u4f.npy");
    write_npy(&p, 3, "<u4", true, |r, c| {
        (ival(r, c) as u32 * 100_000).to_le_bytes().to_vec()
    });
    write_sidecar(&p, &sidecar("1300000"));
    out.push(("npy <u4 fortran", p, opts));
    let p = dir.join("f8f.npy");
    write_npy(&p, 1, "<f8", true, |r, c| fval(r, c).to_le_bytes().to_vec());
    write_sidecar(&p, &sidecar("null"));
    out.push(("npy <f8 fortran", p, opts));
    // i1 without a sidecar: the spacing from the options, the south-west sample at (0, 0).
    let p = dir.join("i1.npy");
    write_npy(&p, 1, "<i1", false, |r, c| vec![(ival(r, c) - 48) as i8 as u8]);
    out.push((
        "npy <i1 no sidecar",
        p,
        DemOptions {
            spacing: Some((3.0, 4.0)),
            z_scale: 2.5,
            band: None,
        },
    ));

    // .hgt: 1201 x 1201 with voids.
    let p = dir.join("N43W123.hgt");
    let bytes: Vec<u8> = (0..1201 * 1201)
        .flat_map(|i| hgt_value(i / 1201, i % 1201).to_be_bytes())
        .collect();
    std::fs::write(&p, bytes).expect("write hgt");
    out.push(("hgt", p, opts));

    // .asc with NODATA, 5 values a line (rows run across lines), CRLF line ends, a blank line in the header.
    let p = dir.join("grid.asc");
    let mut text = format!(
        "ncols {C}\r\nnrows {R}\r\n\r\nxllcorner 1000.5\r\nyllcorner 2000.25\r\ncellsize 7.5\r\nNODATA_value -9999\r\n"
    );
    for k in 0..R * C {
        let (r, c) = (k / C, k % C);
        let v = fval(r, c);
        if v.is_nan() {
            text.push_str("-9999");
        } else {
            text.push_str(&format!("{v}"));
        }
        text.push_str(if k % 5 == 4 { "\r\n" } else { "  " });
    }
    std::fs::write(&p, text).expect("write asc");
    out.push(("asc", p, opts));

    // PNG: 16-bit grayscale.
    let p = dir.join("map.png");
    {
        let file = std::fs::File::create(&p).expect("create");
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), C as u32, R as u32);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Sixteen);
        let mut w = enc.write_header().expect("header");
        let data: Vec<u8> = (0..R * C)
            .flat_map(|k| ((ival(k / C, k % C) * 600) as u16).to_be_bytes())
            .collect();
        w.write_image_data(&data).expect("data");
    }
    out.push((
        "png",
        p,
        DemOptions {
            spacing: Some((5.0, 6.0)),
            ..opts
        },
    ));

    // GeoTIFF: float32 with GDAL_NODATA and NaN in LZW strips of 3 rows; int16 with the horizontal predictor in
    // Deflate strips of 2 rows.
    let f32s: Vec<f32> = (0..R * C)
        .map(|k| {
            let v = fval(k / C, k % C) as f32;
            if k % 13 == 6 { -9999.0 } else { v }
        })
        .collect();
    let p = dir.join("f32.tif");
    std::fs::write(&p, write_tif_f32(&f32s, 3)).expect("write tif");
    out.push(("geotiff float32", p, opts));
    let i16s: Vec<i16> = (0..R * C).map(|k| (ival(k / C, k % C) - 40) as i16).collect();
    let p = dir.join("i16.tif");
    std::fs::write(&p, write_tif_i16(&i16s, 2)).expect("write tif");
    out.push(("geotiff int16", p, opts));

    out.into_iter()
        .map(|(name, path, opts)| {
            let whole = read_dem(&path, &opts).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!((whole.rows > 2, whole.cols > 2), (true, true));
            Fixture {
                name,
                path,
                opts,
                whole,
            }
        })
        .collect()
}

/// GeoKeys of a projected CRS in metres (EPSG:32633), pixel-is-area.
const KEYS_UTM: [u16; 16] = [1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, 32633];

macro_rules! write_tif {
    ($ct:ty, $data:expr, $rows_per_strip:expr, $compression:expr, $predictor:expr, $nodata:expr) => {{
        use tiff::encoder::TiffEncoder;
        use tiff::tags::Tag;
        let mut buf = Cursor::new(Vec::new());
        {
            let mut enc = TiffEncoder::new(&mut buf)
                .expect("encoder")
                .with_compression($compression)
                .with_predictor($predictor);
            let mut img = enc.new_image::<$ct>(C as u32, R as u32).expect("image");
            img.rows_per_strip($rows_per_strip).expect("strips");
            let d = img.encoder();
            d.write_tag(Tag::GeoKeyDirectoryTag, &KEYS_UTM[..]).expect("tag");
            d.write_tag(Tag::ModelPixelScaleTag, &[10.0, 20.0, 0.0][..])
                .expect("tag");
            d.write_tag(Tag::ModelTiepointTag, &[0.0, 0.0, 0.0, 500_000.0, 4_000_000.0, 0.0][..])
                .expect("tag");
            if let Some(n) = $nodata {
                d.write_tag(Tag::Unknown(42113), n).expect("tag");
            }
            img.write_data($data).expect("data");
        }
        buf.into_inner()
    }};
}

fn write_tif_f32(data: &[f32], rows_per_strip: u32) -> Vec<u8> {
    use tiff::encoder::{Compression, Predictor, colortype};
    write_tif!(
        colortype::Gray32Float,
        data,
        rows_per_strip,
        Compression::Lzw,
        Predictor::None,
        Some("-9999")
    )
}

fn write_tif_i16(data: &[i16], rows_per_strip: u32) -> Vec<u8> {
    use tiff::encoder::{Compression, Predictor, colortype};
    write_tif!(
        colortype::GrayI16,
        data,
        rows_per_strip,
        Compression::Deflate(Default::default()),
        Predictor::Horizontal,
        None::<&str>
    )
}

/// The fixtures, written once into the test's own directory under the target directory.
fn fixtures() -> &'static [Fixture] {
    static FIXTURES: OnceLock<Vec<Fixture>> = OnceLock::new();
    FIXTURES.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("dem_window_{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("fixture directory");
        write_fixtures(&dir)
    })
}

/// Rows `r`, columns `c` of `g`, cut from the whole grid.
fn cut(g: &Grid, r: [usize; 2], c: [usize; 2]) -> Vec<f64> {
    (r[0]..=r[1])
        .flat_map(|row| g.z[row * g.cols + c[0]..=row * g.cols + c[1]].to_vec())
        .collect()
}

fn bits(z: &[f64]) -> Vec<u64> {
    z.iter().map(|h| h.to_bits()).collect()
}

/// The window read alone is what reading the whole grid and cutting it gives, bit for bit.
fn check(f: &Fixture, r: [usize; 2], c: [usize; 2]) {
    let g = &f.whole;
    let what = format!("{}: rows {r:?}, columns {c:?}", f.name);
    let header = read_dem_header(&f.path, &f.opts).unwrap_or_else(|e| panic!("{what}: header: {e}"));
    assert_eq!(header, GridShape::of(g), "{what}");
    let (shape, z) = read_dem_window_heights(&f.path, &f.opts, r, c).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert_eq!(shape, GridShape::of(g), "{what}");
    let expected = cut(g, r, c);
    assert_eq!(bits(&z), bits(&expected), "{what}");
    let window = read_dem_window(&f.path, &f.opts, r, c);
    if r[1] > r[0] && c[1] > c[0] {
        let w = window.unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!((w.rows, w.cols), (r[1] - r[0] + 1, c[1] - c[0] + 1), "{what}");
        assert_eq!(
            (w.dx.to_bits(), w.dy.to_bits()),
            (g.dx.to_bits(), g.dy.to_bits()),
            "{what}"
        );
        let origin = g.origin + DVec2::new(c[0] as f64 * g.dx, -(r[0] as f64) * g.dy);
        assert_eq!(
            (w.origin.x.to_bits(), w.origin.y.to_bits()),
            (origin.x.to_bits(), origin.y.to_bits()),
            "{what}"
        );
        assert_eq!(bits(&w.z), bits(&expected), "{what}");
    } else {
        // A grid needs 2 x 2 samples; thinner windows are only heights.
        assert!(window.is_err(), "{what}: a window thinner than 2 x 2 is not a grid");
    }
}

#[test]
fn fixtures_have_voids_and_nodata() {
    for f in fixtures() {
        let voids = f.whole.voids();
        match f.name {
            "png" | "geotiff int16" | "npy <i1 no sidecar" => assert_eq!(voids, 0, "{}", f.name),
            _ => assert!(voids > 0, "{}: the fixture should have voids", f.name),
        }
    }
}

#[test]
fn fixed_windows_equal_the_cut_whole_grid() {
    for f in fixtures() {
        let (rows, cols) = (f.whole.rows, f.whole.cols);
        let (lr, lc) = (rows - 1, cols - 1);
        let windows = [
            // The whole grid.
            ([0, lr], [0, lc]),
            // 2 x 2 corners.
            ([0, 1], [0, 1]),
            ([0, 1], [lc - 1, lc]),
            ([lr - 1, lr], [0, 1]),
            ([lr - 1, lr], [lc - 1, lc]),
            // Single samples: the corners and the middle.
            ([0, 0], [0, 0]),
            ([0, 0], [lc, lc]),
            ([lr, lr], [0, 0]),
            ([lr, lr], [lc, lc]),
            ([rows / 2, rows / 2], [cols / 2, cols / 2]),
            // Full-width rows and full-height columns, one sample thick.
            ([0, 0], [0, lc]),
            ([lr, lr], [0, lc]),
            ([0, lr], [3, 3]),
            // Interior, and touching each side.
            ([2, rows - 3], [1, cols - 2]),
            ([0, rows / 2], [cols / 3, lc]),
            ([rows / 3, lr], [0, cols / 2]),
        ];
        for (r, c) in windows {
            check(f, r, c);
        }
    }
}

/// Strips of every height, in order, put together are the whole grid, bit for bit, and report its shape.
#[test]
fn strips_of_every_height_make_the_whole_grid() {
    for f in fixtures() {
        let g = &f.whole;
        for strip in [1, 2, 5, g.rows - 1, g.rows, g.rows + 3] {
            let mut z = Vec::new();
            let shape = read_dem_strips(&f.path, &f.opts, strip, |first, heights| {
                assert_eq!(first * g.cols, z.len(), "{}: strips in order", f.name);
                assert!(heights.len() <= strip * g.cols && heights.len() % g.cols == 0);
                z.extend_from_slice(heights);
                Ok(())
            })
            .expect("strips");
            assert_eq!(bits(&z), bits(&g.z), "{}: strips of {strip} rows", f.name);
            assert_eq!(shape, GridShape::of(g), "{}", f.name);
        }
        // An error from the callback stops the reading and comes back.
        let e = read_dem_strips(&f.path, &f.opts, 4, |_, _| {
            Err(TinError::InvalidParameter("stop".into()))
        });
        assert!(e.is_err_and(|e| e.to_string().contains("stop")), "{}", f.name);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    #[test]
    fn random_windows_equal_the_cut_whole_grid(a in 0.0..1.0f64, b in 0.0..1.0f64, x in 0.0..1.0f64, y in 0.0..1.0f64) {
        for f in fixtures() {
            let pick = |u: f64, n: usize| ((u * n as f64) as usize).min(n - 1);
            let (r0, r1) = (pick(a, f.whole.rows), pick(b, f.whole.rows));
            let (c0, c1) = (pick(x, f.whole.cols), pick(y, f.whole.cols));
            check(f, [r0.min(r1), r0.max(r1)], [c0.min(c1), c0.max(c1)]);
        }
    }
}

/// The message of an error, checking that it names the file.
fn names_file(e: TinError, path: &Path) -> String {
    let text = e.to_string();
    let name = path.file_name().expect("name").to_string_lossy().into_owned();
    assert!(text.contains(&name), "{text:?} should name {name}");
    text
}

#[test]
fn windows_outside_the_grid_are_refused() {
    for f in fixtures() {
        let (rows, cols) = (f.whole.rows, f.whole.cols);
        for (r, c) in [
            ([0, rows], [0, 1]),
            ([0, 1], [0, cols]),
            ([rows, rows + 3], [0, 1]),
            ([3, 2], [0, 1]),
            ([0, 1], [5, 4]),
        ] {
            let e = read_dem_window(&f.path, &f.opts, r, c).expect_err("outside");
            assert!(matches!(e, TinError::InvalidParameter(_)), "{}: {e}", f.name);
            let text = names_file(e, &f.path);
            assert!(text.contains("not inside its grid"), "{text}");
            assert!(read_dem_window_heights(&f.path, &f.opts, r, c).is_err());
        }
    }
}

#[test]
fn truncated_files_are_errors_naming_them() {
    let dir = tempfile::tempdir().expect("tempdir");
    let opts = DemOptions::default();
    // .npy cut short in its data, and in its header.
    let full = dir.path().join("full.npy");
    write_npy(&full, 1, "<f8", false, |r, c| fval(r, c).to_le_bytes().to_vec());
    let bytes = std::fs::read(&full).expect("read");
    for (name, len) in [
        ("data.npy", bytes.len() - 5),
        ("head.npy", 40),
        ("magic.npy", 4),
        ("empty.npy", 0),
    ] {
        let p = dir.path().join(name);
        std::fs::write(&p, &bytes[..len]).expect("write");
        write_sidecar(&p, "{\"spacing_x_m\": 1.0, \"spacing_y_m\": 1.0}");
        let e = read_dem_header(&p, &opts).expect_err("truncated");
        names_file(e, &p);
        let e = read_dem_window(&p, &opts, [0, 1], [0, 1]).expect_err("truncated");
        let text = names_file(e, &p);
        if name == "data.npy" {
            assert!(text.contains("truncated"), "{text}");
        }
    }
    // .hgt cut short.
    let p = dir.path().join("N10E010.hgt");
    let hgt: Vec<u8> = (0..1201 * 1201)
        .flat_map(|i| hgt_value(i / 1201, i % 1201).to_be_bytes())
        .collect();
    std::fs::write(&p, &hgt[..hgt.len() - 1201]).expect("write");
    let e = read_dem_header(&p, &opts).expect_err("truncated");
    assert!(names_file(e, &p).contains("is not an SRTM tile"));
    let e = read_dem_window(&p, &opts, [1190, 1200], [0, 1200]).expect_err("truncated");
    names_file(e, &p);
    // .asc cut short: a window reaching the missing values fails, one before them reads.
    let p = dir.path().join("cut.asc");
    let mut text = format!("ncols {C}\nnrows {R}\nxllcenter 0\nyllcenter 0\ncellsize 1\n");
    for k in 0..R * C - 7 {
        text.push_str(&format!("{} ", ival(k / C, k % C)));
    }
    std::fs::write(&p, &text).expect("write");
    let e = read_dem_window(&p, &opts, [R - 2, R - 1], [0, C - 1]).expect_err("truncated");
    assert!(names_file(e, &p).contains("truncated"));
    let w = read_dem_window(&p, &opts, [0, 3], [0, 3]).expect("values before the cut");
    assert_eq!(w.z[5], ival(1, 1) as f64);
    assert!(read_dem(&p, &opts).is_err());
    let strips = |p: &Path| read_dem_strips(p, &opts, 3, |_, _| Ok(()));
    assert!(names_file(strips(&p).expect_err("truncated"), &p).contains("truncated"));
    // .asc with a value too many, or a word that is not a finite number: strips read every value, as read_dem does.
    let p = dir.path().join("long.asc");
    std::fs::write(&p, format!("{text}{} 1 2 3 4 5 6 7 8", ival(0, 0))).expect("write");
    assert!(read_dem(&p, &opts).is_err());
    assert!(names_file(strips(&p).expect_err("too many"), &p).contains("more than the"));
    // One row per line with one value too many in the first row: the whole read and the strips name that line.
    let p = dir.path().join("row.asc");
    let rows: Vec<String> = (0..3)
        .map(|r| {
            let extra = if r == 0 { " 7" } else { "" };
            format!(
                "{}{extra}",
                (0..4).map(|c| ival(r, c).to_string()).collect::<Vec<_>>().join(" ")
            )
        })
        .collect();
    std::fs::write(
        &p,
        format!(
            "ncols 4\nnrows 3\nxllcenter 0\nyllcenter 0\ncellsize 1\n{}\n",
            rows.join("\n")
        ),
    )
    .expect("write");
    let hint = "line 6 has 5 values where every other line has ncols = 4";
    assert!(names_file(read_dem(&p, &opts).expect_err("too many"), &p).contains(hint));
    assert!(names_file(strips(&p).expect_err("too many"), &p).contains(hint));
    let p = dir.path().join("word.asc");
    std::fs::write(&p, format!("{text}1 2 3 4 5 6 x")).expect("write");
    assert!(read_dem(&p, &opts).is_err());
    assert!(names_file(strips(&p).expect_err("a word"), &p).contains("\"x\" is not a finite number"));
    // A PNG cut short: its strips are refused, naming the file.
    let png = fixtures().iter().find(|f| f.name == "png").expect("the PNG fixture");
    let bytes = std::fs::read(&png.path).expect("read");
    let p = dir.path().join("cut.png");
    std::fs::write(&p, &bytes[..bytes.len() / 2]).expect("write");
    let e = read_dem_strips(&p, &png.opts, 3, |_, _| Ok(())).expect_err("truncated");
    names_file(e, &p);
    // A header without values.
    let p = dir.path().join("bare.asc");
    std::fs::write(
        &p,
        format!("ncols {C}\nnrows {R}\nxllcenter 0\nyllcenter 0\ncellsize 1\n"),
    )
    .expect("write");
    assert_eq!(read_dem_header(&p, &opts).expect("header").rows, R);
    let e = read_dem_window(&p, &opts, [0, 1], [0, 1]).expect_err("no values");
    assert!(names_file(e, &p).contains("truncated"));
    // A missing file.
    let p = dir.path().join("missing.npy");
    names_file(read_dem_header(&p, &opts).expect_err("missing"), &p);
    names_file(read_dem_window(&p, &opts, [0, 1], [0, 1]).expect_err("missing"), &p);
}

#[test]
fn heights_out_of_range_name_the_whole_files_row_and_column() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = dir.path().join("huge.npy");
    write_npy(&p, 1, "<f8", false, |r, c| {
        let v = if (r, c) == (5, 7) { 1e200 } else { ival(r, c) as f64 };
        v.to_le_bytes().to_vec()
    });
    write_sidecar(&p, "{\"spacing_x_m\": 1.0, \"spacing_y_m\": 1.0}");
    let opts = DemOptions::default();
    let e = read_dem_window(&p, &opts, [4, 6], [6, 8]).expect_err("out of range");
    assert!(matches!(e, TinError::Format { .. }), "{e}");
    let text = names_file(e, &p);
    assert!(
        text.contains("row 6, column 8 (1-based, row 1 north): height 1e200"),
        "{text}"
    );
    let text = names_file(read_dem(&p, &opts).expect_err("whole"), &p);
    assert!(
        text.contains("row 6, column 8 (1-based, row 1 north): height 1e200"),
        "{text}"
    );
    let strips = |p: &Path| read_dem_strips(p, &opts, 2, |_, _| Ok(())).expect_err("out of range");
    let text = names_file(strips(&p), &p);
    assert!(
        text.contains("row 6, column 8 (1-based, row 1 north): height 1e200"),
        "{text}"
    );
    // The same in a streamed `.asc`: the strip's first row is counted in.
    let asc = dir.path().join("huge.asc");
    let mut body = format!("ncols {C}\nnrows {R}\nxllcenter 0\nyllcenter 0\ncellsize 1\n");
    for k in 0..R * C {
        let (r, c) = (k / C, k % C);
        body.push_str(&if (r, c) == (5, 7) {
            "1e200 ".to_string()
        } else {
            format!("{} ", ival(r, c))
        });
    }
    std::fs::write(&asc, body).expect("write");
    let text = names_file(strips(&asc), &asc);
    assert!(
        text.contains("row 6, column 8 (1-based, row 1 north): height 1e200"),
        "{text}"
    );
    // A window without the sample reads.
    let w = read_dem_window(&p, &opts, [0, 3], [0, 16]).expect("reads");
    assert_eq!(w.z[17 + 2], ival(1, 2) as f64);
    // Coordinates out of range: the header is refused, naming the corner.
    let p = dir.path().join("far.npy");
    write_npy(&p, 1, "<f8", false, |r, c| (ival(r, c) as f64).to_le_bytes().to_vec());
    write_sidecar(
        &p,
        "{\"spacing_x_m\": 1.0, \"spacing_y_m\": 1.0, \"easting_min\": 1e200, \"northing_max\": 10.0}",
    );
    let text = names_file(read_dem_header(&p, &opts).expect_err("far"), &p);
    assert!(
        text.contains("row 1, column 1 (1-based, row 1 north): x = 1e200"),
        "{text}"
    );
    let text = names_file(read_dem_window(&p, &opts, [3, 5], [4, 6]).expect_err("far"), &p);
    assert!(
        text.contains("row 4, column 5 (1-based, row 1 north): x = 1e200"),
        "{text}"
    );
}

/// `../shared/dem`: required (CI has it); a missing directory fails the test.
fn shared_dem() -> PathBuf {
    let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/dem"));
    assert!(
        dir.is_dir(),
        "{} is missing: the real-file window tests need the shared DEMs",
        dir.display()
    );
    dir
}

#[test]
fn real_files_windows_equal_the_cut_whole_grid() {
    let dir = shared_dem();
    for name in [
        "N50E008_deflate.tif",
        "crater_lake_utm.tif",
        "dfw_srtm.tif",
        "N43W123.hgt",
        "crater_lake.npy",
        "jacksboro_fault.asc",
        "jacksboro_fault.npy",
    ] {
        let path = dir.join(name);
        let opts = DemOptions::default();
        let whole = read_dem(&path, &opts).unwrap_or_else(|e| panic!("{name}: {e}"));
        let f = Fixture {
            name: "real",
            path,
            opts,
            whole,
        };
        let (lr, lc) = (f.whole.rows - 1, f.whole.cols - 1);
        for (r, c) in [
            ([0, lr], [0, lc]),
            ([0, 1], [0, 1]),
            ([lr - 1, lr], [lc - 1, lc]),
            ([lr / 3, lr / 2], [lc / 4, 3 * lc / 4]),
            ([lr / 2 - 70, lr / 2 + 70], [lc / 2 - 90, lc / 2 + 90]),
        ] {
            check(&f, r, c);
        }
    }
}
