//! Times the horizon sweep (and optionally the oracle) on a synthetic fractal TIN.
//!
//! `cargo run --release -p horizon --example horizon_timing -- [VERTICES [SECTORS [SUBSECTORS]]] [--oracle]
//! [--undersampling R] [--repeat N]` (10,000 vertices, at least 3, and 8 × 8 when not given)
//!
//! With `--repeat N` the sweep runs N times and the fastest wall time is reported (useful on a busy machine).

#[path = "../benches/synthetic.rs"]
mod synthetic;

use std::time::Instant;

use horizon::{HorizonOptions, SectorConfig, brute_force, compute};

/// Errors as `error: …` on standard error (their message, not their debug form); exit status 1.
fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    const USAGE: &str = "usage: horizon_timing [VERTICES [SECTORS [SUBSECTORS]]] [--oracle] [--undersampling R] \
                         [--repeat N]";
    let whole = |what: &str, a: &str| {
        a.parse::<u32>()
            .map_err(|_| format!("{what} {a:?}: not a whole number"))
    };
    let (mut positional, mut oracle, mut radius, mut repeat) = (Vec::new(), false, None, 1);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--oracle" => oracle = true,
            "--repeat" => repeat = whole("--repeat", &args.next().ok_or(USAGE)?)?.max(1),
            "--undersampling" => {
                let r = args.next().ok_or(USAGE)?;
                radius = Some(
                    r.parse::<f64>()
                        .map_err(|_| format!("--undersampling {r:?}: not a number"))?,
                );
            }
            _ if a.starts_with("--") => return Err(format!("unknown flag {a}; {USAGE}").into()),
            _ => positional.push(a),
        }
    }
    if positional.len() > 3 {
        return Err(USAGE.into());
    }
    let names = ["VERTICES", "SECTORS", "SUBSECTORS"];
    let mut values = [10_000, 8, 8];
    for ((value, name), text) in values.iter_mut().zip(names).zip(&positional) {
        *value = whole(name, text)?;
    }
    let [n, s, k] = values;
    let n = n as usize;
    if n < 3 {
        return Err(format!("VERTICES {n}: a terrain needs at least 3").into());
    }
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
    for _ in 0..repeat {
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
