//! Replays the checked-in fuzz corpus (`fuzz/corpus/<target>/`) through the fuzz targets' own code
//! (`fuzz/src/targets.rs`) on the stable toolchain: every file must go through without a panic.

use std::path::{Path, PathBuf};

#[path = "../fuzz/src/targets.rs"]
mod targets;

fn corpus(target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus").join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
}

fn replay(target: &str, run: fn(&[u8])) -> usize {
    let files = corpus(target);
    assert!(
        files.len() >= 3,
        "{target}: the corpus needs a few seeds, found {}",
        files.len()
    );
    for f in &files {
        let bytes = std::fs::read(f).expect("corpus file");
        assert!(
            bytes.len() < 100 * 1024,
            "{}: corpus files stay under 100 KB",
            f.display()
        );
        let outcome = std::panic::catch_unwind(|| run(&bytes));
        assert!(outcome.is_ok(), "{target} panicked on {}", f.display());
    }
    files.len()
}

#[test]
fn obj_import_corpus_never_panics() {
    replay("obj_import", targets::obj_import);
}

#[test]
fn dem_readers_corpus_never_panics() {
    replay("dem_readers", targets::dem_readers);
}

#[test]
fn geotiff_corpus_never_panics() {
    replay("geotiff", targets::geotiff);
}

#[test]
fn tch_load_corpus_never_panics() {
    replay("tch_load", targets::tch_load);
}

#[test]
fn tile_files_corpus_never_panics() {
    replay("tile_files", targets::tile_files);
}

/// The tile files' seeds are valid (a plan of each kind, a part, a far field), so the fuzzer starts from the deep code.
#[test]
fn valid_tile_file_seeds_parse() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/tile_files");
    let read = |name: &str| std::fs::read(dir.join(name)).expect("seed");
    for (name, mesh) in [("mesh_plan.json", true), ("dem_plan.json", false)] {
        let plan = tiles::Plan::parse(read(name), Path::new(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(plan.grid.is_none(), mesh, "{name}");
    }
    let part = tiles::part::MeshPart::from_bytes(&read("mesh_part.bin"), Path::new("mesh_part.bin")).expect("part");
    assert!(!part.triangles.is_empty() && !part.halo.is_empty() && !part.far.is_empty());
    let far = tiles::far_field::far_from_bytes(&read("dem_far_field.bin"), [80, 80], Path::new("far")).expect("far");
    assert!(!far.is_empty());
    let e = tiles::part::MeshPart::from_bytes(&read("truncated_part.bin"), Path::new("truncated_part.bin"))
        .expect_err("a truncated part");
    assert!(e.to_string().contains("truncated_part.bin"), "{e}");
}

/// The valid seeds really are valid: they load (so the fuzzer starts from files that reach the deep code).
#[test]
fn valid_seeds_load() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus");
    for name in ["jacksboro-2k-3seeds.tch", "synth-60.tch"] {
        let bytes = std::fs::read(dir.join("tch_load").join(name)).expect("seed");
        let h = cull::Hierarchy::from_bytes(&bytes).expect("a valid seed loads");
        assert!(h.num_triangles() > 0);
        assert_eq!(
            targets::reseal(&bytes).as_deref(),
            Some(&bytes[..]),
            "resealing a valid file changes nothing"
        );
    }
    let opts = tin::ObjImportOptions {
        keep_faces: true,
        ..Default::default()
    };
    let obj = std::fs::read(dir.join("obj_import/grid5.obj")).expect("seed");
    let (t, _) = tin::parse_obj(&obj, "grid5.obj", &opts).expect("a valid seed loads");
    assert_eq!(t.num_triangles(), 32);
    let npy = std::fs::read(dir.join("dem_readers/i2_3x4.npy")).expect("seed");
    tin::dem::npy::parse_npy(&npy, Path::new("i2_3x4.npy")).expect("a valid .npy seed parses");
    let png = std::fs::read(dir.join("dem_readers/gray16_4x3.png")).expect("seed");
    let opts = tin::DemOptions {
        spacing: Some((10.0, 10.0)),
        z_scale: 1.0,
        band: None,
    };
    let g = tin::dem::png::parse_png(&png, Path::new("gray16_4x3.png"), &opts).expect("a valid .png seed parses");
    assert_eq!(g.points().len(), 12);
    let asc = std::fs::read(dir.join("dem_readers/grid.asc")).expect("seed");
    let g = tin::dem::asc::parse_asc(&asc, Path::new("grid.asc"), &tin::DemOptions::default()).expect("asc parses");
    assert_eq!(g.points().len(), 11, "12 samples, one of them nodata");
    for (name, points) in [
        ("utm_int16_4x3.tif", 12),
        ("geo_float32_point_nodata.tif", 11),
        ("utm_float64_transform.tif", 12),
        ("utm_uint16_tiled.tif", 256),
    ] {
        let tif = std::fs::read(dir.join("geotiff").join(name)).expect("seed");
        let (g, _) = tin::dem::geotiff::parse_geotiff(&tif, Path::new(name), &tin::DemOptions::default())
            .unwrap_or_else(|e| panic!("a valid GeoTIFF seed parses: {e}"));
        assert_eq!(g.points().len(), points, "{name}");
    }
}
