//! Test terrains: random and degenerate point sets triangulated into TINs.

#![allow(dead_code)]

use glam::DVec3;
use horizon::{HorizonField, SectorConfig};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tin::{DedupePolicy, Tin, triangulate};

/// The configurations every agreement test runs.
pub const CONFIGS: [(u32, u32); 6] = [(4, 1), (8, 1), (8, 8), (16, 4), (64, 1), (5, 3)];

pub fn config(s: u32, k: u32) -> SectorConfig {
    SectorConfig::new(s, k).expect("valid config")
}

/// Kinds of point sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Uniform x, y, z.
    Uniform,
    /// A few tight clusters.
    Clustered,
    /// Integer grid around the origin with heights in {±0, 1, 2} (many exact boundary directions and slope ties).
    IntegerGrid,
    /// Integer grid at UTM-sized coordinates, small integer heights.
    UtmGrid,
    /// Everything at one height (every slope ties at 0).
    Flat,
    /// Flat grid with one high vertex.
    Spike,
    /// Points on a few horizontal rows (collinear runs), integer coordinates.
    CollinearRows,
}

pub const KINDS: [Kind; 7] = [
    Kind::Uniform,
    Kind::Clustered,
    Kind::IntegerGrid,
    Kind::UtmGrid,
    Kind::Flat,
    Kind::Spike,
    Kind::CollinearRows,
];

/// About `n` points of the given kind.
pub fn points(kind: Kind, n: usize, seed: u64) -> Vec<DVec3> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = n.max(4);
    let side = (n as f64).sqrt().ceil() as usize;
    let grid = |rng: &mut ChaCha8Rng, offset: (f64, f64), heights: u32| -> Vec<DVec3> {
        (0..side * side)
            .map(|i| {
                DVec3::new(
                    offset.0 + (i % side) as f64,
                    offset.1 + (i / side) as f64,
                    rng.random_range(0..heights) as f64,
                )
            })
            .collect()
    };
    match kind {
        Kind::Uniform => (0..n)
            .map(|_| {
                DVec3::new(
                    rng.random_range(0.0..1000.0),
                    rng.random_range(0.0..1000.0),
                    rng.random_range(0.0..100.0),
                )
            })
            .collect(),
        Kind::Clustered => {
            let centres: Vec<(f64, f64)> = (0..3)
                .map(|_| (rng.random_range(0.0..1000.0), rng.random_range(0.0..1000.0)))
                .collect();
            (0..n)
                .map(|i| {
                    let (cx, cy) = centres[i % 3];
                    let spread = if i % 7 == 0 { 300.0 } else { 5.0 };
                    DVec3::new(
                        cx + rng.random_range(-spread..spread),
                        cy + rng.random_range(-spread..spread),
                        rng.random_range(0.0..30.0),
                    )
                })
                .collect()
        }
        Kind::IntegerGrid => {
            // Centred on the origin, with zero heights of both signs: −0.0 must behave like 0.0.
            let half = (side / 2) as f64;
            grid(&mut rng, (-half, -half), 3)
                .into_iter()
                .enumerate()
                .map(|(i, p)| DVec3::new(p.x, p.y, if p.z == 0.0 && i % 2 == 1 { -0.0 } else { p.z }))
                .collect()
        }
        Kind::UtmGrid => grid(&mut rng, (500_000.0, 5_000_000.0), 4),
        Kind::Flat => {
            if seed.is_multiple_of(2) {
                grid(&mut rng, (0.0, 0.0), 1)
                    .into_iter()
                    .map(|p| DVec3::new(p.x, p.y, 7.0))
                    .collect()
            } else {
                (0..n)
                    .map(|_| DVec3::new(rng.random_range(0.0..100.0), rng.random_range(0.0..100.0), 7.0))
                    .collect()
            }
        }
        Kind::Spike => {
            let mut pts = grid(&mut rng, (0.0, 0.0), 1);
            let k = rng.random_range(0..pts.len());
            pts[k].z = 50.0;
            pts
        }
        Kind::CollinearRows => {
            let rows = 2 + n / 12;
            (0..n)
                .map(|i| {
                    DVec3::new(
                        rng.random_range(0..40) as f64,
                        (i % rows) as f64 * 3.0,
                        rng.random_range(0..3) as f64,
                    )
                })
                .collect()
        }
    }
}

/// A TIN of the given kind, or `None` when the points happen to be collinear.
pub fn terrain(kind: Kind, n: usize, seed: u64) -> Option<Tin> {
    triangulate(&points(kind, n, seed), DedupePolicy::KeepHighest)
        .ok()
        .map(|(tin, _)| tin)
}

/// Panics with a readable message unless the two fields agree everywhere.
pub fn assert_same(sweep: &HorizonField, oracle: &HorizonField, what: &str) {
    sweep
        .check_invariants()
        .unwrap_or_else(|e| panic!("{what}: sweep field invalid: {e}"));
    oracle
        .check_invariants()
        .unwrap_or_else(|e| panic!("{what}: oracle field invalid: {e}"));
    let mismatches = sweep.mismatches(oracle);
    assert_eq!(
        mismatches,
        0,
        "{what}: {mismatches} mismatches, first at (vertex, subsector) {:?}: sweep {:?}, oracle {:?}",
        sweep.first_mismatch(oracle),
        sweep.first_mismatch(oracle).map(|(v, j)| sweep.horizon_point(v, j)),
        sweep.first_mismatch(oracle).map(|(v, j)| oracle.horizon_point(v, j)),
    );
    assert!(sweep == oracle, "{what}: horizons agree but summaries differ");
}
