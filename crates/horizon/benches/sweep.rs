//! Horizon sweep benchmarks on synthetic fractal terrain (random sample positions about 30 m apart, smooth
//! fractal heights; see `synthetic.rs`), standing in for the thesis' data sets:
//! - `sweep/10k_8x8`: the Ashby Gap / jacksboro size (thesis: 1.531 s on a 2004 dual 2.4 GHz PC);
//! - `sweep/100k_8x8`, `sweep/100k_16x4`: the Tiefort / N43W123 size (thesis: 34.4 s and 34.1 s);
//! - `ratio_20k/{sweep,oracle}_8x8`: the brute-force oracle against the sweep at 20,000 vertices.
//!
//! Run with `cargo bench -p horizon --bench sweep` (all), or e.g. `cargo bench -p horizon --bench sweep -- 10k`.
//! The oracle takes tens of seconds per iteration; criterion's minimum of 10 samples applies.

mod synthetic;

use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use horizon::{HorizonOptions, SectorConfig, brute_force, compute};

fn sweep(c: &mut Criterion) {
    let opts = HorizonOptions::default();
    let mut group = c.benchmark_group("sweep");
    group.sample_size(10).measurement_time(Duration::from_secs(20));
    let small = synthetic::fractal_tin(10_000, 1);
    let cfg = SectorConfig::new(8, 8).expect("valid");
    group.bench_function("10k_8x8", |b| b.iter(|| compute(&small, &cfg, &opts).expect("valid")));
    let large = synthetic::fractal_tin(100_000, 1);
    for (s, k) in [(8, 8), (16, 4)] {
        let cfg = SectorConfig::new(s, k).expect("valid");
        group.bench_function(format!("100k_{s}x{k}"), |b| {
            b.iter(|| compute(&large, &cfg, &opts).expect("valid"))
        });
    }
    group.finish();
}

fn ratio(c: &mut Criterion) {
    let opts = HorizonOptions::default();
    let tin = synthetic::fractal_tin(20_000, 2);
    let cfg = SectorConfig::new(8, 8).expect("valid");
    let mut group = c.benchmark_group("ratio_20k");
    group.sample_size(10).measurement_time(Duration::from_secs(30));
    group.bench_function("sweep_8x8", |b| b.iter(|| compute(&tin, &cfg, &opts).expect("valid")));
    group.bench_function("oracle_8x8", |b| {
        b.iter(|| brute_force(&tin, &cfg, &opts).expect("valid"))
    });
    group.finish();
}

criterion_group!(benches, sweep, ratio);
criterion_main!(benches);
