//! Times the horizon sweep (and optionally the oracle) on a synthetic fractal TIN.
//!
//! `cargo run --release -p horizon --example horizon_timing -- VERTICES SECTORS SUBSECTORS [--oracle]
//! [--undersampling R] [--repeat N]`
//!
//! With `--repeat N` the sweep runs N times and the fastest wall time is reported (useful on a busy machine).

#[path = "../benches/synthetic.rs"]
mod synthetic;

use std::time::Instant;

use horizon::{HorizonOptions, SectorConfig, brute_force, compute};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let num = |i: usize, default: u64| args.get(i).and_then(|a| a.parse().ok()).unwrap_or(default);
    let (n, s, k) = (num(0, 10_000) as usize, num(1, 8) as u32, num(2, 8) as u32);
    let oracle = args.iter().any(|a| a == "--oracle");
    let radius = args
        .iter()
        .position(|a| a == "--undersampling")
        .and_then(|i| args.get(i + 1))
        .and_then(|r| r.parse().ok());
    let repeat: usize = args
        .iter()
        .position(|a| a == "--repeat")
        .and_then(|i| args.get(i + 1))
        .and_then(|r| r.parse().ok())
        .unwrap_or(1);
    let cfg = SectorConfig::new(s, k)?;
    let started = Instant::now();
    let tin = synthetic::fractal_tin(n, 1);
    println!(
        "tin: {} vertices, {} triangles in {:.2} s",
        tin.num_vertices(),
        tin.num_triangles(),
        started.elapsed().as_secs_f64()
    );
    let opts = HorizonOptions {
        undersampling_radius: radius,
        ..HorizonOptions::default()
    };
    let mut sweep_s = f64::INFINITY;
    let mut field = None;
    for _ in 0..repeat.max(1) {
        let started = Instant::now();
        field = Some(compute(&tin, &cfg, &opts)?);
        sweep_s = sweep_s.min(started.elapsed().as_secs_f64());
    }
    let field = field.ok_or("no run")?;
    println!(
        "sweep {s}x{k}: {sweep_s:.3} s (best of {repeat}, {} threads), {} empty, {} edge horizons",
        rayon::current_num_threads(),
        field.empty_count(),
        field.edge_horizon_count()
    );
    if oracle {
        let started = Instant::now();
        let reference = brute_force(&tin, &cfg, &opts)?;
        let oracle_s = started.elapsed().as_secs_f64();
        println!(
            "oracle: {oracle_s:.3} s, ratio oracle/sweep {:.1}, mismatches {}",
            oracle_s / sweep_s,
            field.mismatches(&reference)
        );
    }
    Ok(())
}
