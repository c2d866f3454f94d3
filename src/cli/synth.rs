//! `tincull synth`: a seeded synthetic terrain written as OBJ (or as a height grid, `.npy`).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::Args;
use serde_json::json;
use tin::SynthOptions;

use super::files::Outputs;
use super::{Output, OutputArgs};

/// Arguments of `tincull synth`.
#[derive(Debug, Args)]
pub struct SynthArgs {
    /// Output file: an OBJ mesh (`-`: to standard output), or with `.npy` the terrain's height grid (f64, a JSON
    /// sidecar with its spacing and position beside it), e.g. the input of `tiles plan`.
    #[arg(short, long, value_name = "FILE")]
    pub out: PathBuf,
    /// Number of vertices, 4 to 2^31 (exact; for a `.npy` grid, the nearest square number of samples).
    #[arg(long, default_value_t = 10_000, value_parser = parse_vertices)]
    pub vertices: usize,
    /// Seed of the random generator: the same seed gives the same terrain.
    #[arg(long, default_value_t = 1)]
    pub rng_seed: u64,
    /// Side of the square footprint in metres (default: 30 m per vertex spacing, 30·√vertices); below 1e12 m, and at
    /// least 1 mm per vertex spacing (1 mm·√vertices).
    #[arg(long)]
    pub extent: Option<f64>,
    /// Relief in metres (default: a tenth of the extent): 0 (flat), or from 1 µm to below 1e12 m.
    #[arg(long)]
    pub relief: Option<f64>,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Runs `tincull synth`.
pub fn run(args: &SynthArgs, out: Output) -> Result<()> {
    let mut out = out;
    let stdout = args.out == std::path::Path::new("-");
    let ext = args
        .out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    anyhow::ensure!(
        stdout || matches!(ext.as_deref(), Some("obj" | "npy")),
        "{}: synth writes an OBJ mesh (.obj, or `-` for standard output) or a height grid (.npy); name the output so",
        args.out.display()
    );
    let mut files = Outputs::new();
    files.check_or_stdout(&args.out, "-o", &mut out)?;
    let grid_out = args.out.extension().is_some_and(|e| e.eq_ignore_ascii_case("npy"));
    let sidecar = tin::dem::npy::sidecar_path(&args.out);
    if grid_out {
        files.check(&sidecar)?;
        // The sidecar is named after the grid, not by the user: an existing file there is replaced only when it is
        // a grid's sidecar (it says a spacing), never another JSON (a tile plan, a report) that happens to share it.
        if sidecar.exists() {
            let is_sidecar = tin::dem::npy::read_sidecar(&sidecar).is_ok_and(|c| c.spacing.is_some());
            anyhow::ensure!(
                is_sidecar,
                "{}: a grid's sidecar goes here, and this file is not one (no spacing_x_m/spacing_y_m); move it, or \
                 name the grid otherwise",
                sidecar.display()
            );
        }
    }
    let start = Instant::now();
    let mut opts = SynthOptions::new(args.vertices, args.rng_seed);
    if let Some(e) = args.extent {
        opts.extent = e;
        opts.relief = e / 10.0;
    }
    if let Some(r) = args.relief {
        opts.relief = r;
    }
    let spinner = out.spinner("synthesising");
    if grid_out {
        let grid = tin::synth_grid(&opts)?;
        spinner.set_message("writing");
        files.add(&args.out, |w| tin::dem::npy::write_npy_to(&grid, w))?;
        files.add_bytes(&sidecar, tin::dem::npy::sidecar_json(&grid).as_bytes())?;
        files.commit()?;
        spinner.finish_and_clear();
        let seconds = start.elapsed().as_secs_f64();
        out.say(format!(
            "wrote {} and {}: {} x {} samples, {:.0} m square, {:.0} m relief ({seconds:.2} s)",
            args.out.display(),
            sidecar.display(),
            grid.rows,
            grid.cols,
            opts.extent,
            opts.relief
        ));
        return out.json(&json!({
            "output": args.out,
            "sidecar": sidecar,
            "rows": grid.rows,
            "cols": grid.cols,
            "extent": opts.extent,
            "relief": opts.relief,
            "rng_seed": args.rng_seed,
            "seconds": seconds,
        }));
    }
    let tin = tin::synth_tin(&opts)?;
    spinner.set_message("writing");
    files.add(&args.out, |w| tin::write_obj_to(&tin, w))?;
    files.commit()?;
    spinner.finish_and_clear();
    let seconds = start.elapsed().as_secs_f64();
    out.say(format!(
        "wrote {}: {} vertices, {} triangles, {:.0} m square, {:.0} m relief ({seconds:.2} s)",
        args.out.display(),
        tin.num_vertices(),
        tin.num_triangles(),
        opts.extent,
        opts.relief
    ));
    out.json(&json!({
        "output": args.out,
        "vertices": tin.num_vertices(),
        "triangles": tin.num_triangles(),
        "extent": opts.extent,
        "relief": opts.relief,
        "rng_seed": args.rng_seed,
        "seconds": seconds,
    }))
}

/// `--vertices`: 4 to 2^31 (refused by clap, which names the flag).
fn parse_vertices(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if (4..=1 << 31).contains(&n) => Ok(n),
        Ok(_) => Err(format!("{s:?}: a synthetic terrain has 4 to 2^31 vertices")),
        Err(_) => Err(format!(
            "{s:?} is not a whole number (a synthetic terrain has 4 to 2^31 vertices)"
        )),
    }
}
