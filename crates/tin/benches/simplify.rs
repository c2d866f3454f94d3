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
use tin::{DemOptions, Grid, SimplifyOptions, SynthOptions, simplify, synth_grid, synth_tin};

const DEM_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/dem");

/// A DEM of `../shared/dem` through the crate's own readers (`.npy` with its sidecar, SRTM `.hgt`).
fn read(name: &str) -> tin::Result<Grid> {
    tin::read_dem(std::path::Path::new(DEM_DIR).join(name), &DemOptions::default())
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
    for (file, name, vertices) in [
        ("jacksboro_fault.npy", "simplify/jacksboro_fault/10k", 10_000),
        ("N43W123.hgt", "simplify/N43W123/100k", 100_000),
        ("N50E008.hgt", "simplify/N50E008/100k", 100_000),
    ] {
        match read(file) {
            Ok(g) => bench_grid(c, name, &g, vertices),
            Err(e) => eprintln!("skipping {name}: {e}"),
        }
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
