//! Greedy-insertion simplification and synthetic terrain.
//!
//! Run with `cargo bench -p tin --bench simplify`. Inputs:
//! - `synthetic_1201/100k`: a 1201 x 1201 synthetic grid ([`tin::synth_grid`], seed 1) simplified to 100,000 vertices;
//! - `jacksboro_fault/10k`: `../shared/dem/jacksboro_fault.npy` (344 x 403, int16, 74.485 x 92.767 m) to 10,000
//!   vertices;
//! - `N43W123/100k`: `../shared/dem/N43W123.hgt` (SRTM3, 1201 x 1201) to 100,000 vertices;
//! - `synth_tin/{10k,1M}`: [`tin::synth_tin`] with 10,000 and 1,000,000 vertices.
//!
//! The real data sets are skipped with a notice when `../shared/dem` is missing. Each run also prints the
//! simplification report (vertices, max and RMS error) once per input.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec2;
use tin::{Grid, SimplifyOptions, SynthOptions, simplify, synth_grid, synth_tin};

const DEM_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/dem");

/// A little-endian int16 `.npy` of the given shape (bench-only reader).
fn read_npy_i16(path: &str, rows: usize, cols: usize, dx: f64, dy: f64) -> Option<Grid> {
    let bytes = std::fs::read(path).ok()?;
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return None;
    }
    let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(bytes.get(10..10 + header_len)?).ok()?;
    if !header.contains("'<i2'") || !header.contains(&format!("({rows}, {cols})")) {
        return None;
    }
    let z = bytes[10 + header_len..]
        .chunks_exact(2)
        .map(|b| f64::from(i16::from_le_bytes([b[0], b[1]])))
        .collect();
    Grid::new(rows, cols, dx, dy, DVec2::ZERO, z).ok()
}

/// An SRTM3 `.hgt` tile (1201 x 1201 big-endian int16, -32768 = void) at latitude `lat` (bench-only reader).
fn read_hgt(path: &str, lat: f64) -> Option<Grid> {
    let bytes = std::fs::read(path).ok()?;
    if bytes.len() != 1201 * 1201 * 2 {
        return None;
    }
    let z = bytes
        .chunks_exact(2)
        .map(|b| match i16::from_be_bytes([b[0], b[1]]) {
            -32768 => f64::NAN,
            h => f64::from(h),
        })
        .collect();
    let dy = 3.0 / 3600.0 * 111_320.0;
    let dx = dy * lat.to_radians().cos();
    Grid::new(1201, 1201, dx, dy, DVec2::ZERO, z).ok()
}

fn bench_grid(c: &mut Criterion, name: &str, grid: &Grid, vertices: usize) {
    let opts = SimplifyOptions::vertices(vertices);
    match simplify(grid, &opts, None) {
        Ok((_, r)) => eprintln!(
            "{name}: {} x {} samples ({} voids) -> {} vertices, {} triangles, max error {:.3} m at {:?}, \
             rms {:.3} m, {:.3} s",
            grid.rows,
            grid.cols,
            r.voids_skipped,
            r.vertices,
            r.triangles,
            r.max_error,
            r.max_error_at,
            r.rms_error,
            r.seconds
        ),
        Err(e) => {
            eprintln!("{name}: {e}");
            return;
        }
    }
    c.bench_function(name, |b| b.iter(|| simplify(black_box(grid), &opts, None)));
}

fn simplification(c: &mut Criterion) {
    let grid = match synth_grid(&SynthOptions::new(1201 * 1201, 1)) {
        Ok(g) => g,
        Err(e) => {
            eprintln!("synthetic grid: {e}");
            return;
        }
    };
    bench_grid(c, "simplify/synthetic_1201/100k", &grid, 100_000);
    match read_npy_i16(&format!("{DEM_DIR}/jacksboro_fault.npy"), 344, 403, 74.485, 92.767) {
        Some(g) => bench_grid(c, "simplify/jacksboro_fault/10k", &g, 10_000),
        None => eprintln!("skipping jacksboro_fault: {DEM_DIR}/jacksboro_fault.npy not found or not 344 x 403 int16"),
    }
    match read_hgt(&format!("{DEM_DIR}/N43W123.hgt"), 43.5) {
        Some(g) => bench_grid(c, "simplify/N43W123/100k", &g, 100_000),
        None => eprintln!("skipping N43W123: {DEM_DIR}/N43W123.hgt not found"),
    }
    match read_hgt(&format!("{DEM_DIR}/N50E008.hgt"), 50.5) {
        Some(g) => bench_grid(c, "simplify/N50E008/100k", &g, 100_000),
        None => eprintln!("skipping N50E008: {DEM_DIR}/N50E008.hgt not found"),
    }
}

fn synthetic_tins(c: &mut Criterion) {
    for (name, n) in [("synth_tin/10k", 10_000), ("synth_tin/1M", 1_000_000)] {
        let opts = SynthOptions::new(n, 1);
        c.bench_function(name, |b| b.iter(|| synth_tin(black_box(&opts))));
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10).measurement_time(Duration::from_secs(10));
    targets = simplification, synthetic_tins
}
criterion_main!(benches);
