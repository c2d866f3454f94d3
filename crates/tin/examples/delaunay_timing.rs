//! Times Delaunay construction of uniformly random points.
//!
//! `cargo run --release -p tin --example delaunay_timing -- [POINTS] [REPEAT]` (default 1,000,000 points, at least 3,
//! and 3 runs, at least 1);
//! prints the best wall time of [`tin::triangulate`] (spade, Morton-ordered insertion, adjacency included).

use std::time::Instant;

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    // A whole number of at least `min`, or the usage and exit status 2.
    let arg = |i: usize, default: usize, min: usize| match args.get(i).map(|a| a.parse::<usize>()) {
        None => default,
        Some(Ok(v)) if v >= min => v,
        _ => {
            eprintln!("usage: delaunay_timing [POINTS (at least 3)] [REPEAT (at least 1)]");
            std::process::exit(2)
        }
    };
    if args.len() > 2 {
        eprintln!("usage: delaunay_timing [POINTS (at least 3)] [REPEAT (at least 1)]");
        std::process::exit(2);
    }
    let (n, repeat) = (arg(0, 1_000_000, 3), arg(1, 3, 1));
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
    for _ in 0..repeat {
        let start = Instant::now();
        let (tin, _) = tin::triangulate(&points, tin::DedupePolicy::KeepHighest).expect("random points triangulate");
        best = best.min(start.elapsed().as_secs_f64());
        assert_eq!(tin.num_vertices(), n);
    }
    println!("{n} points: best of {repeat}: {best:.3} s");
}
