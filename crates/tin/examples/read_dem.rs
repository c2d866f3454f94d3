//! Reads DEM files with [`tin::read_dem`] and prints their size, voids, height range and read time:
//! `cargo run --release -p tin --example read_dem -- FILE...`.

use std::path::Path;
use std::time::Instant;

fn main() {
    let files: Vec<String> = std::env::args().skip(1).collect();
    if files.is_empty() {
        eprintln!("usage: read_dem FILE...");
        std::process::exit(2);
    }
    let mut failed = false;
    for arg in files {
        let path = Path::new(&arg);
        // Best of five reads (the first one also warms the page cache).
        let mut best = f64::INFINITY;
        let mut last = None;
        for _ in 0..5 {
            let t = Instant::now();
            let r = tin::read_dem(path, &tin::DemOptions::default());
            best = best.min(t.elapsed().as_secs_f64());
            last = Some(r);
        }
        match last {
            Some(Ok(g)) => {
                let (lo, hi) =
                    g.z.iter()
                        .filter(|z| !z.is_nan())
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &z| (a.min(z), b.max(z)));
                println!(
                    "{arg}: {} x {} samples, {} voids, heights {lo} .. {hi}, spacing {:.4} x {:.4} m, read in {:.2} ms",
                    g.rows,
                    g.cols,
                    g.voids(),
                    g.dx,
                    g.dy,
                    best * 1e3
                );
            }
            Some(Err(e)) => {
                // The message and its causes (an I/O error's message is the path, its cause the reason).
                let mut message = e.to_string();
                let mut cause = std::error::Error::source(&e);
                while let Some(c) = cause {
                    message += &format!(": {c}");
                    cause = c.source();
                }
                eprintln!("error: {message}");
                failed = true;
            }
            None => {}
        }
    }
    if failed {
        std::process::exit(1);
    }
}
