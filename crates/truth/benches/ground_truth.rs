//! Ground-truth cost per viewpoint on synthetic terrains.
//!
//! Inputs: random points (seeded) over a 10 km square with a smooth hilly height field, Delaunay-triangulated to
//! 10,000 and 100,000 vertices; one `ground` viewpoint and one `high` viewpoint (seed 1). Run with
//! `cargo bench -p truth --bench ground_truth`.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use tin::{DedupePolicy, Tin, triangulate};
use truth::{GroundTruth, ViewpointClass, viewpoints};

fn terrain(n: usize) -> Tin {
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let pts: Vec<DVec3> = (0..n)
        .map(|_| {
            let (x, y) = (rng.random::<f64>() * 10_000.0, rng.random::<f64>() * 10_000.0);
            let z = 300.0 * (x / 1300.0).sin() * (y / 1700.0).cos()
                + 120.0 * ((x + 2.0 * y) / 600.0).sin()
                + 40.0 * ((3.0 * x - y) / 250.0).cos();
            DVec3::new(x, y, z)
        })
        .collect();
    triangulate(&pts, DedupePolicy::KeepHighest).expect("terrain").0
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("visible_triangles");
    group.sample_size(10);
    for n in [10_000, 100_000] {
        let tin = terrain(n);
        let gt = GroundTruth::new(&tin);
        for class in [ViewpointClass::Ground, ViewpointClass::High] {
            let eye = viewpoints(&tin, class, 1, 1)[0];
            group.bench_function(format!("{n}_vertices_{class}"), |b| {
                b.iter(|| black_box(gt.visible_triangles(black_box(eye))))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
