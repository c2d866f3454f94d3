//! Times the horizon sweep on an OBJ terrain and prints a hash of the whole field (byte-identity checks).
//!
//! `cargo run --release -p horizon --example horizon_obj -- MESH.obj [SECTORS SUBSECTORS] [--repeat N]`

use std::hash::Hasher;
use std::time::Instant;

use horizon::{HorizonOptions, SectorConfig, compute};

/// FNV-1a over 64-bit words.
struct Fnv(u64);

impl Hasher for Fnv {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 ^= u64::from(*b);
            self.0 = self.0.wrapping_mul(0x100_0000_01b3);
        }
    }
}

/// The error's message and its causes, as `error: …` on standard error; exit status 1.
fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            let mut message = e.to_string();
            let mut cause = e.source();
            while let Some(c) = cause {
                message += &format!(": {c}");
                cause = c.source();
            }
            eprintln!("error: {message}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    const USAGE: &str = "usage: horizon_obj MESH.obj [SECTORS SUBSECTORS] [--repeat N]";
    let whole = |what: &str, a: &str| {
        a.parse::<u32>()
            .map_err(|_| format!("{what} {a:?}: not a whole number"))
    };
    let (mut positional, mut repeat) = (Vec::new(), 1);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--repeat" {
            repeat = whole("--repeat", &args.next().ok_or(USAGE)?)?.max(1);
        } else {
            positional.push(a);
        }
    }
    let (path, s, k) = match positional.as_slice() {
        [path] => (path, 16, 4),
        [path, s, k] => (path, whole("SECTORS", s)?, whole("SUBSECTORS", k)?),
        _ => return Err(USAGE.into()),
    };
    let (tin, _) = tin::read_obj(std::path::Path::new(path), &tin::ObjImportOptions::default())?;
    let cfg = SectorConfig::new(s, k)?;
    let mut best = f64::INFINITY;
    let mut field = None;
    for _ in 0..repeat {
        let started = Instant::now();
        field = Some(compute(&tin, &cfg, &HorizonOptions::default())?);
        best = best.min(started.elapsed().as_secs_f64());
    }
    let field = field.ok_or("no run")?;
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    for j in 0..cfg.total_subsectors() {
        for v in 0..field.num_vertices() as u32 {
            h.write_u32(field.horizon(v, j).unwrap_or(u32::MAX));
        }
    }
    for v in 0..field.num_vertices() as u32 {
        for i in 0..cfg.sectors() {
            if let Some(sum) = field.sector_summary(v, i) {
                h.write_u64(sum.slope.to_bits());
                h.write_u64(sum.distance.to_bits());
            }
        }
    }
    println!(
        "{} vertices, {s}x{k}: {best:.3} s wall (best of {repeat}, {} threads), hash {:016x}",
        field.num_vertices(),
        rayon::current_num_threads(),
        h.finish()
    );
    Ok(())
}
