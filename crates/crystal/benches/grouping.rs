//! Crystal grouping speed on a synthetic terrain of about 100,000 vertices (about 200,000 triangles).
//!
//! Input: a 317 × 317 jittered grid (10 m spacing, ±3 m jitter, `ChaCha8Rng::seed_from_u64(1)`) with fractal heights
//! (five octaves of sine products, 300 m relief at 2 km wavelength). Horizons are not computed from the mesh (that is
//! the horizon crate's job): for each vertex and sector the analytic height function is sampled along the sector's
//! centre direction at geometrically growing distances, and the steepest sample gives the slope and distance (no
//! horizon when the first sample falls outside the terrain). 16 sectors, default parameters.
//!
//! Run: `cargo bench -p crystal --bench grouping`. Measures the growth phase alone (seeds, growth, orphan passes) and
//! the whole of `crystal::build` (plus small-group merging, group regions from the vertex regions, hierarchy,
//! reordering).

use std::f64::consts::TAU;

use criterion::{Criterion, criterion_group, criterion_main};
use crystal::CrystalParams;
use glam::{DVec2, DVec3};
use occlusion::{RegionTable, SectorHorizon};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use tin::{DedupePolicy, Tin};

const SIDE: usize = 317;
const STEP: f64 = 10.0;
const SECTORS: u32 = 16;

fn height(p: DVec2) -> f64 {
    (0..5)
        .map(|o| {
            let f = TAU / 2000.0 * 2f64.powi(o);
            let a = 150.0 / 2f64.powi(o);
            let angle = 0.7 * f64::from(o) + 0.3;
            let (s, c) = f64::sin_cos(angle);
            let (u, v) = (c * p.x + s * p.y, -s * p.x + c * p.y);
            a * (f * u + 1.3 * f64::from(o)).sin() * (0.8 * f * v + 0.5).cos()
        })
        .sum()
}

fn terrain() -> Tin {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut points = Vec::with_capacity(SIDE * SIDE);
    for j in 0..SIDE {
        for i in 0..SIDE {
            let xy = DVec2::new(
                i as f64 * STEP + rng.random_range(-3.0..=3.0),
                j as f64 * STEP + rng.random_range(-3.0..=3.0),
            );
            points.push(xy.extend(height(xy)));
        }
    }
    tin::triangulate(&points, DedupePolicy::Reject).expect("valid grid").0
}

/// Horizons from the analytic terrain along each sector's centre direction.
fn horizons(positions: &[DVec3]) -> Vec<Option<SectorHorizon>> {
    let extent = (SIDE - 1) as f64 * STEP;
    let inside = |p: DVec2| p.x >= 0.0 && p.y >= 0.0 && p.x <= extent && p.y <= extent;
    positions
        .par_iter()
        .flat_map_iter(|p| {
            (0..SECTORS).map(move |s| {
                let [x, y] = cull::sector_direction(SECTORS, s);
                let r = DVec2::new(x, y);
                let mut best: Option<SectorHorizon> = None;
                let mut d = STEP;
                while d < extent * 1.5 {
                    let q = p.truncate() + r * d;
                    if !inside(q) {
                        break;
                    }
                    let slope = (height(q) - p.z) / d;
                    if best.is_none_or(|b| slope > b.slope) {
                        best = Some(SectorHorizon { slope, distance: d });
                    }
                    d *= 1.2;
                }
                best
            })
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let tin = terrain();
    let h = horizons(tin.positions());
    let origin = tin.bbox().min.truncate();
    let vertices = RegionTable::of_vertices(tin.positions(), origin, SECTORS, |v, s| h[(v * SECTORS + s) as usize]);
    let params = CrystalParams::default();
    let result = crystal::build(&tin, &vertices, &params).expect("valid input");
    result.check_invariants(&tin).expect("invariants");
    eprintln!(
        "{} vertices, {} triangles, {} sectors: {:?}",
        tin.num_vertices(),
        tin.num_triangles(),
        SECTORS,
        result.stats
    );
    let mut group = c.benchmark_group("grouping");
    group.sample_size(10);
    group.bench_function("growth_200k", |b| {
        b.iter(|| crystal::growth::grow(&tin, &vertices, &params).expect("valid input"))
    });
    group.bench_function("build_200k", |b| {
        b.iter(|| crystal::build(&tin, &vertices, &params).expect("valid input"))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
