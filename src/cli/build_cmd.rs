//! `tincull build`: horizons, regions, crystal grouping and the merge hierarchy, written as a `.tch` file.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result};
use clap::Args;
use serde::Deserialize;
use serde_json::json;

use super::mesh_input::MeshArgs;
use super::{Output, OutputArgs};
use pipeline::export::to_json;

use super::files::Outputs;
use pipeline::{BuildParams, BuildReport, build};

/// Parameters that may also come from a TOML file (`--config`); the command line wins.
#[derive(Debug, Default, Clone, Args, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamArgs {
    /// Number of sectors [default: 16].
    #[arg(long)]
    pub sectors: Option<u32>,
    /// Subsectors per sector [default: 4].
    #[arg(long)]
    pub subsectors: Option<u32>,
    /// Crystal seeds of the first pass [default: one per 200 triangles].
    #[arg(long)]
    pub seeds: Option<usize>,
    /// Orphan passes after the first [default: 10].
    #[arg(long)]
    pub orphan_passes: Option<u32>,
    /// Groups smaller than this many triangles are merged or freed to the always-visible set [default: 30].
    #[arg(long)]
    pub min_group: Option<usize>,
    /// A merge whose bounding circle covers more than this fraction of the terrain's area is not made [default: 0.25].
    #[arg(long)]
    pub max_expanse: Option<f64>,
    /// Seed of the random generator [default: 1].
    #[arg(long)]
    pub rng_seed: Option<u64>,
    /// Radius (m) of the horizon undersampling fix [default: off].
    #[arg(long, value_name = "RADIUS")]
    pub undersampling: Option<f64>,
}

impl ParamArgs {
    /// Command-line values over those of `file` over the defaults.
    pub fn resolve(&self, file: Option<&Path>) -> Result<BuildParams> {
        let from_file: ParamArgs = match file {
            Some(path) => {
                let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
                toml::from_str(&text).with_context(|| format!("{}: invalid parameters", path.display()))?
            }
            None => ParamArgs::default(),
        };
        let d = BuildParams::default();
        let mut p = d.clone();
        p.sectors = self.sectors.or(from_file.sectors).unwrap_or(d.sectors);
        p.subsectors = self.subsectors.or(from_file.subsectors).unwrap_or(d.subsectors);
        p.undersampling = self.undersampling.or(from_file.undersampling);
        p.crystal.seeds = self.seeds.or(from_file.seeds);
        p.crystal.orphan_passes = self
            .orphan_passes
            .or(from_file.orphan_passes)
            .unwrap_or(d.crystal.orphan_passes);
        p.crystal.min_group = self.min_group.or(from_file.min_group).unwrap_or(d.crystal.min_group);
        p.crystal.max_expanse = self
            .max_expanse
            .or(from_file.max_expanse)
            .unwrap_or(d.crystal.max_expanse);
        p.crystal.rng_seed = self.rng_seed.or(from_file.rng_seed).unwrap_or(d.crystal.rng_seed);
        if let Some(r) = p.undersampling
            && !(r.is_finite() && r > 0.0)
        {
            anyhow::bail!("the undersampling radius must be positive and finite, got {r}");
        }
        Ok(p)
    }
}

/// Arguments of `tincull build`.
#[derive(Debug, Args)]
pub struct BuildArgs {
    /// The mesh and how to import it.
    #[command(flatten)]
    pub mesh: MeshArgs,
    /// Output hierarchy file (.tch).
    #[arg(short, long)]
    pub out: PathBuf,
    /// Build parameters.
    #[command(flatten)]
    pub params: ParamArgs,
    /// Read parameters from this TOML file (keys as the long options, with underscores).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Also write the hierarchy's JSON form here.
    #[arg(long, value_name = "FILE")]
    pub export_json: Option<PathBuf>,
    /// Also write the mesh as OBJ with one group per leaf and the orphans, with a .mtl beside it.
    #[arg(long, value_name = "FILE")]
    pub export_obj: Option<PathBuf>,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// A progress bar per pipeline stage.
pub fn stage_progress(out: Output) -> pipeline::BuildProgress {
    let bar = out.progress(1, "horizons");
    // Threads report out of order: within a stage the bar only moves forward.
    let high = std::sync::Mutex::new(0u64);
    Arc::new(move |stage: &str, done: u64, total: u64| {
        let Ok(mut high) = high.lock() else { return };
        if bar.message() != stage {
            bar.set_message(stage.to_string());
            bar.reset();
            *high = 0;
        } else if done < *high {
            return;
        }
        *high = done;
        bar.set_length(total);
        bar.set_position(done);
    })
}

/// Prints the thesis-style table of a build.
pub fn print_report(r: &BuildReport, out: Output) {
    out.say(format!(
        "{} vertices, {} triangles; {} sectors x {} subsectors, {} seeds",
        r.vertices, r.triangles, r.sectors, r.subsectors, r.seeds
    ));
    out.say(format!(
        "  horizons {:.3} s, regions {:.3} s, grouping {:.3} s",
        r.horizon_seconds, r.regions_seconds, r.grouping_seconds
    ));
    out.say(format!(
        "  orphan passes {}, orphans {}, groups {}, nodes {}, levels {}, top-level {}",
        r.orphan_passes, r.orphans, r.groups, r.nodes, r.levels, r.top_level
    ));
    out.say(format!(
        "  visibility data {} bytes ({:.1} bytes per triangle)",
        r.visibility_bytes, r.visibility_bytes_per_triangle
    ));
}

/// Runs `tincull build`.
pub fn run(args: &BuildArgs, out: Output) -> Result<()> {
    let mut out = out;
    let params = args.params.resolve(args.config.as_deref())?;
    let mut files = Outputs::new();
    files.check_or_stdout(&args.out, &mut out)?;
    if let Some(path) = &args.export_json {
        files.check(path)?;
    }
    if let Some(path) = &args.export_obj {
        files.check_grouped_obj(path)?;
    }
    let (tin, _) = args.mesh.load(out)?;
    let result = build(&tin, &params, Some(stage_progress(out)))?;
    files.add_bytes(&args.out, &result.hierarchy.to_bytes()?)?;
    if let Some(path) = &args.export_json {
        files.add_bytes(path, to_json(&result.hierarchy)?.as_bytes())?;
    }
    if let Some(path) = &args.export_obj {
        files.add_grouped_obj(&result.hierarchy, path)?;
    }
    files.commit()?;
    print_report(&result.report, out);
    let peak = peak_memory_bytes();
    if let Some(bytes) = peak {
        out.say(format!(
            "  peak memory {:.1} MB (the whole process so far)",
            bytes as f64 / 1e6
        ));
    }
    out.say(format!("wrote {}", args.out.display()));
    if let Some(path) = &args.export_json {
        out.say(format!("wrote {}", path.display()));
    }
    if let Some(path) = &args.export_obj {
        out.say(format!("wrote {} and its .mtl", path.display()));
    }
    let mut j = serde_json::to_value(&result.report)?;
    j["output"] = json!(args.out);
    j["params"] = serde_json::to_value(&params)?;
    j["peak_memory_bytes"] = json!(peak);
    out.json(&j)
}

/// The process's peak resident memory (`VmHWM` of `/proc/self/status`), where the system reports it (Linux).
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line
        .trim_start_matches("VmHWM:")
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kib * 1024)
}
