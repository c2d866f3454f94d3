//! Times Delaunay construction of uniformly random points.
//!
//! `cargo run --release -p tin --example delaunay_timing -- [POINTS] [REPEAT]` (default 1,000,000 points, 3 runs);
//! prints the best wall time of [`tin::triangulate`] (spade, Morton-ordered insertion, adjacency included).

use std::time::Instant;

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(1_000_000);
    let repeat: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(3);
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let side = (n as f64).sqrt() * 30.0;
    let points: Vec<DVec3> = (0..n)
        .map(|_| {
            DVec3::new(
                rng.random_range(0.0..side),
                rng.random_range(0.0..side),
                rng.random_range(0.0..100.0),
            )
        })
        .collect();
    let mut best = f64::INFINITY;
    for _ in 0..repeat.max(1) {
        let start = Instant::now();
        let (tin, _) = tin::triangulate(&points, tin::DedupePolicy::KeepHighest).expect("random points triangulate");
        best = best.min(start.elapsed().as_secs_f64());
        assert_eq!(tin.num_vertices(), n);
    }
    println!("{n} points: best of {repeat}: {best:.3} s");
}
