//! Synthetic terrain for benches and timing examples: uniformly random sample positions (about 30 m apart, like
//! a 1-arc-second DEM) with smooth fractal heights (a sum of sine octaves in random directions), Delaunay
//! triangulated. Seeded, so every run measures the same TIN.

use glam::{DVec2, DVec3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tin::{DedupePolicy, Tin, triangulate};

/// A synthetic TIN with `n` vertices.
pub fn fractal_tin(n: usize, seed: u64) -> Tin {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let side = (n as f64).sqrt() * 30.0;
    let mut waves = Vec::new();
    let (mut freq, mut amp) = (std::f64::consts::TAU / side, side / 20.0);
    for _ in 0..10 {
        for _ in 0..3 {
            let a: f64 = rng.random_range(0.0..std::f64::consts::TAU);
            waves.push((
                DVec2::new(a.cos(), a.sin()) * freq,
                amp,
                rng.random_range(0.0..std::f64::consts::TAU),
            ));
        }
        freq *= 2.0;
        amp *= 0.45;
    }
    let points: Vec<DVec3> = (0..n)
        .map(|_| {
            let xy = DVec2::new(rng.random_range(0.0..side), rng.random_range(0.0..side));
            let z: f64 = waves.iter().map(|(k, a, ph)| a * (k.dot(xy) + ph).sin()).sum();
            // A UTM-like offset, as real data sets have.
            DVec3::new(xy.x + 500_000.0, xy.y + 4_000_000.0, z + 300.0)
        })
        .collect();
    triangulate(&points, DedupePolicy::KeepHighest)
        .expect("random points triangulate")
        .0
}
