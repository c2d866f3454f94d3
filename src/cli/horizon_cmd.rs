//! `tincull horizon`: horizons of every vertex in every subsector, optionally checked against the brute-force oracle.

use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use horizon::{HorizonField, HorizonOptions, HorizonPoint, SectorConfig};
use serde_json::json;
use tin::Tin;

use super::files::Outputs;
use super::mesh_input::MeshArgs;
use super::{Output, OutputArgs};

/// Arguments of `tincull horizon`.
#[derive(Debug, Args)]
pub struct HorizonArgs {
    /// The mesh and how to import it.
    #[command(flatten)]
    pub mesh: MeshArgs,
    /// Number of sectors `s` (at least 4).
    #[arg(long, default_value_t = 16)]
    pub sectors: u32,
    /// Subsectors per sector `k` (s·k at most 1024).
    #[arg(long, default_value_t = 4)]
    pub subsectors: u32,
    /// Enable the undersampling fix: TIN edges within this radius (m) that cross a subsector with neither endpoint
    /// inside contribute their crossing point as a horizon candidate.
    #[arg(long, value_name = "RADIUS")]
    pub undersampling: Option<f64>,
    /// Also run the O(n²) brute-force oracle and report mismatches (0 is the only acceptable value).
    #[arg(long)]
    pub verify: bool,
    /// Write every vertex's horizon per subsector and its sector summaries as JSON (`-`: standard output).
    #[arg(long, value_name = "FILE")]
    pub export_json: Option<PathBuf>,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Computes horizons with a progress bar over subsector sweeps.
pub fn compute_with_progress(
    tin: &Tin,
    config: &SectorConfig,
    undersampling: Option<f64>,
    out: Output,
) -> Result<(HorizonField, f64)> {
    let bar = out.progress(u64::from(config.total_subsectors()), "horizons");
    let advance = Output::monotone(&bar);
    let opts = HorizonOptions {
        undersampling_radius: undersampling,
        progress: Some(Arc::new(move |done, _| advance(done as u64))),
    };
    let start = Instant::now();
    let field = horizon::compute(tin, config, &opts)?;
    let seconds = start.elapsed().as_secs_f64();
    bar.finish_and_clear();
    Ok((field, seconds))
}

/// Runs `tincull horizon`.
pub fn run(args: &HorizonArgs, out: Output) -> Result<()> {
    let config = SectorConfig::new(args.sectors, args.subsectors)
        .map_err(|e| anyhow::anyhow!("{}: {e}", super::build_cmd::horizon_flag(&e)))?;
    horizon::check_undersampling_radius(args.undersampling).context("--undersampling")?;
    // With --verify the exit status is a result (non-zero on a mismatch).
    out.require_a_result(
        args.export_json.is_some() || args.verify,
        "give --export-json FILE, --verify or --json",
    )?;
    let mut files = Outputs::new();
    let mut out = out;
    files.input(&args.mesh.mesh)?;
    if let Some(path) = &args.export_json {
        files.check_or_stdout(path, "--export-json", &mut out)?;
        super::files::refuse_other_format(path, "horizons as JSON", "json")?;
    }
    let (tin, _) = args.mesh.load(out)?;
    let (field, seconds) = compute_with_progress(&tin, &config, args.undersampling, out)?;
    let n = tin.num_vertices();
    let pairs = n as f64 * f64::from(config.total_subsectors());
    let mut report = json!({
        "mesh": args.mesh.mesh,
        "vertices": n,
        "sectors": config.sectors(),
        "subsectors": config.subsectors(),
        "total_subsectors": config.total_subsectors(),
        "undersampling": args.undersampling,
        "seconds": seconds,
        "vertex_subsectors_per_second": pairs / seconds.max(1e-9),
        "empty_pairs": field.empty_count(),
        "edge_horizons": field.edge_horizon_count(),
    });
    out.say(format!(
        "{} vertices x {} subsectors ({} sectors x {}): {seconds:.3} s, {:.2} M vertex-subsectors/s; {} pairs without horizon",
        n,
        config.total_subsectors(),
        config.sectors(),
        config.subsectors(),
        pairs / seconds.max(1e-9) / 1e6,
        field.empty_count()
    ));
    if args.verify {
        let spinner = out.spinner("brute-force oracle");
        let opts = HorizonOptions {
            undersampling_radius: args.undersampling,
            progress: None,
        };
        let start = Instant::now();
        let oracle = horizon::brute_force(&tin, &config, &opts)?;
        let oracle_seconds = start.elapsed().as_secs_f64();
        spinner.finish_and_clear();
        let mismatches = field.mismatches(&oracle);
        report["mismatches"] = json!(mismatches);
        report["oracle_seconds"] = json!(oracle_seconds);
        out.say(format!(
            "oracle: {oracle_seconds:.3} s ({:.1}x the sweep), {mismatches} mismatches",
            oracle_seconds / seconds.max(1e-9)
        ));
        if mismatches > 0 {
            let first = field.first_mismatch(&oracle);
            out.json(&report)?;
            anyhow::bail!(
                "the sweep disagrees with the oracle on {mismatches} vertex-subsector pairs (first: {first:?})"
            );
        }
    }
    if let Some(path) = &args.export_json {
        export_json(&tin, &field, path, &mut files)?;
        files.commit()?;
        out.say(format!("wrote {}", path.display()));
    }
    out.json(&report)
}

/// Writes per vertex: the horizon per subsector (vertex index, an edge point, or null) and the sector summaries.
fn export_json(tin: &Tin, field: &HorizonField, path: &std::path::Path, files: &mut Outputs) -> Result<()> {
    let config = *field.config();
    let write = |w: &mut dyn Write| -> std::io::Result<()> {
        write!(
            w,
            "{{\"sectors\":{},\"subsectors\":{},\"undersampling\":{},\"vertices\":[",
            config.sectors(),
            config.subsectors(),
            json!(field.undersampling_radius())
        )?;
        for v in 0..tin.num_vertices() as u32 {
            let horizons: Vec<serde_json::Value> = (0..config.total_subsectors())
                .map(|j| match field.horizon_point(v, j) {
                    None => serde_json::Value::Null,
                    Some(HorizonPoint::Vertex(q)) => json!(q),
                    Some(HorizonPoint::Edge(e)) => json!({ "edge": e.edge, "point": e.point.to_array() }),
                })
                .collect();
            let sectors: Vec<serde_json::Value> = (0..config.sectors())
                .map(|i| match field.sector_summary(v, i) {
                    None => serde_json::Value::Null,
                    Some(s) => json!({ "slope": s.slope, "distance": s.distance }),
                })
                .collect();
            if v > 0 {
                w.write_all(b",")?;
            }
            serde_json::to_writer(&mut *w, &json!({ "horizons": horizons, "sectors": sectors }))?;
        }
        w.write_all(b"]}\n")
    };
    files.add(path, write)
}
