//! Benchmarks of TIN import, export and validation on a 100,000-triangle TIN.
//!
//! Input: 50,000 uniformly random points in a 10 km square (seed 1), Delaunay-triangulated (≈ 100,000 triangles).
//! Run with `cargo bench -p tin --bench tinio`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tin::{DedupePolicy, ObjImportOptions, find_overlaps, parse_obj, triangulate, validate, write_obj_to};

fn bench(c: &mut Criterion) {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let points: Vec<DVec3> = (0..50_000)
        .map(|_| {
            DVec3::new(
                500_000.0 + rng.random_range(0.0..10_000.0),
                4_800_000.0 + rng.random_range(0.0..10_000.0),
                rng.random_range(0.0..1000.0),
            )
        })
        .collect();
    let (tin, _) = triangulate(&points, DedupePolicy::Reject).expect("random points triangulate");
    let mut text = Vec::new();
    write_obj_to(&tin, &mut text).expect("in memory");
    eprintln!(
        "{} vertices, {} triangles, {} bytes of OBJ",
        tin.num_vertices(),
        tin.num_triangles(),
        text.len()
    );

    let mut g = c.benchmark_group("tinio");
    g.sample_size(10);
    g.bench_function("find_overlaps_100k", |b| {
        b.iter(|| black_box(find_overlaps(tin.positions(), tin.triangles(), 1)))
    });
    g.bench_function("validate_100k", |b| b.iter(|| black_box(validate(&tin))));
    g.bench_function("write_obj_100k", |b| {
        b.iter(|| {
            let mut out = Vec::with_capacity(text.len());
            write_obj_to(&tin, &mut out).expect("in memory");
            black_box(out)
        })
    });
    let keep = ObjImportOptions {
        keep_faces: true,
        dedupe: DedupePolicy::Reject,
        ..ObjImportOptions::default()
    };
    g.bench_function("parse_obj_keep_faces_100k", |b| {
        b.iter(|| black_box(parse_obj(&text, "bench.obj", &keep).expect("valid")))
    });
    g.bench_function("parse_obj_delaunay_100k", |b| {
        b.iter(|| black_box(parse_obj(&text, "bench.obj", &ObjImportOptions::default()).expect("valid")))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
