//! `tincull sweep`: build and evaluate every combination of sectors, subsectors, seeds and random seeds; one CSV
//! line per combination, method and class (see [`eval::sweep`]). Resumable: combinations already in the file are
//! skipped, and the file is rewritten atomically after each combination; a file written for another setup (mesh,
//! build options, evaluation) is refused ([`eval::sweep::setup_digest`]), and so is one with a malformed field or a
//! repeated line. A combination that lost lines (or a last line cut short) is reported and run again.

use super::output::count;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use serde_json::json;
use truth::ViewpointClass;

use super::build_cmd::{FixedParamArgs, ParamArgs};
use super::files::write_one;
use super::mesh_input::MeshArgs;
use super::{Output, OutputArgs};
use eval::evaluate::{EvalOptions, GroundTruthSet};
use eval::sweep::{SweepSpec, SweepTable, expected_rows, parse_list, run_combo, setup_digest};

/// Arguments of `tincull sweep`.
#[derive(Debug, Args)]
pub struct SweepArgs {
    /// The mesh and how to import it.
    #[command(flatten)]
    pub mesh: MeshArgs,
    /// Sector counts: comma-separated numbers or inclusive ranges `a..b`. A combination that no build takes (fewer
    /// than 4 sectors, no subsectors, too many subsectors in all) is skipped with a warning.
    #[arg(long, default_value = "4,8,16,32,64")]
    pub sectors: String,
    /// Subsectors per sector: comma-separated numbers or ranges.
    #[arg(long, default_value = "1,2,4,8")]
    pub subsectors: String,
    /// Crystal seeds of the first pass: numbers or ranges [default: one per 200 triangles].
    #[arg(long)]
    pub seeds: Option<String>,
    /// Seeds of the crystal's random generator: numbers or ranges (`1..5`, `1,2,3`); `--rng-seed` is the same
    /// [default: 1].
    #[arg(long, visible_alias = "rng-seed")]
    pub rng_seeds: Option<String>,
    /// Viewpoints per class, 1 to 1000000.
    #[arg(long, default_value_t = 10)]
    pub viewpoints: usize,
    /// Viewpoint classes, comma-separated, each once: ground, low, high, valley, ridge, sky.
    #[arg(long, value_delimiter = ',', default_value = "ground,low,high,valley,ridge,sky")]
    pub classes: Vec<ViewpointClass>,
    /// Seed of the viewpoint generator, and of each viewpoint's yaw below 360° (`--fov`), as for `eval`
    /// (`--rng-seed` seeds the grouping).
    #[arg(long, default_value_t = 1, value_name = "SEED")]
    pub view_seed: u64,
    /// Horizontal field of view in degrees (360 = all around).
    #[arg(long, default_value_t = 360.0)]
    pub fov: f64,
    /// The build parameters that are not swept, as `build` takes them (a quadtree's region test is reported as
    /// `stewart`).
    #[command(flatten)]
    pub fixed: FixedParamArgs,
    /// Read the build parameters that are not swept from this TOML file, as `build --config` does (the command line
    /// wins); the swept ones (`sectors`, `subsectors`, `seeds`, `rng_seed`) are refused there: give them as lists.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Skip the per-triangle method (its culler tests every triangle: by far the slowest part of scoring).
    #[arg(long)]
    pub no_per_triangle: bool,
    /// The CSV file of results; combinations already in it are skipped (it must have been written with the same mesh,
    /// build options, the grouping among them, and evaluation options, else it is refused; `--viewpoints` is part of
    /// each line's key, as the swept values are, so a run with another count adds its own lines beside the others).
    #[arg(short, long, value_name = "FILE")]
    pub out: PathBuf,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

fn u32_list(text: &str, what: &str) -> Result<Vec<u32>> {
    parse_list(text, what)?
        .into_iter()
        .map(|v| u32::try_from(v).with_context(|| format!("{what}: {v} is too large")))
        .collect()
}

/// Runs `tincull sweep`.
pub fn run(args: &SweepArgs, out: Output) -> Result<()> {
    if let Some(path) = &args.config {
        let file = ParamArgs::read(path)?;
        let swept = [
            ("sectors", file.sectors.is_some()),
            ("subsectors", file.subsectors.is_some()),
            ("seeds", file.seeds.is_some()),
            ("rng_seed", file.rng_seed.is_some()),
        ];
        if let Some((key, _)) = swept.iter().find(|(_, given)| *given) {
            anyhow::bail!(
                "{}: `{key}` is swept: give it as a list on the command line (--{}), not in --config",
                path.display(),
                key.replace('_', "-")
            );
        }
    }
    let base = ParamArgs {
        fixed: args.fixed.clone(),
        ..ParamArgs::default()
    }
    .resolve(args.config.as_deref())?;
    // The crystal's swept parameters mean nothing to a quadtree: refused rather than swept over identical builds.
    if matches!(base.grouping, pipeline::Grouping::Quadtree(_)) {
        let given = [
            ("--seeds", args.seeds.is_some()),
            ("--rng-seeds", args.rng_seeds.is_some()),
        ];
        if let Some((flag, _)) = given.iter().find(|(_, g)| *g) {
            anyhow::bail!("{flag} applies to the crystal grouping; a quadtree has no seeds (--grouping quadtree)");
        }
    }
    super::eval_cmd::check_viewpoints(args.viewpoints)?;
    let spec = SweepSpec {
        sectors: u32_list(&args.sectors, "--sectors")?,
        subsectors: u32_list(&args.subsectors, "--subsectors")?,
        seeds: match &args.seeds {
            Some(text) => parse_list(text, "--seeds")?
                .into_iter()
                .map(|v| {
                    usize::try_from(v)
                        .map(Some)
                        .with_context(|| format!("--seeds: {v} is too large"))
                })
                .collect::<Result<_>>()?,
            None => vec![None],
        },
        rng_seeds: match &args.rng_seeds {
            Some(text) => parse_list(text, "--rng-seeds")?,
            None => vec![1],
        },
        base,
        viewpoints: args.viewpoints,
    };
    let eval = EvalOptions {
        viewpoints: args.viewpoints,
        classes: args.classes.clone(),
        view_seed: args.view_seed,
        fov_deg: args.fov,
        per_triangle: !args.no_per_triangle,
        safe: cull::SafeParams::default(),
        safe_regions: false,
        eyes: None,
    };
    super::eval_cmd::check_fov(eval.fov_deg)?;
    anyhow::ensure!(!eval.classes.is_empty(), "--classes: no viewpoint classes");
    super::eval_cmd::check_classes(&eval.classes)?;
    // Which combinations are valid does not depend on the mesh (only their keys' seed counts do): refuse a sweep of
    // none before any work.
    let (valid, notes) = spec.combos(0)?;
    if valid.is_empty() {
        let reasons: Vec<String> = notes
            .iter()
            .map(|n| n.strip_prefix("skipped ").unwrap_or(n).to_string())
            .collect();
        anyhow::bail!(
            "no combination to sweep is valid: {}",
            first_of(&reasons, "combination", "").join("; ")
        );
    }

    // Refuse an output that cannot be written, or that is the mesh or the config, before any work (it is rewritten
    // after each combination).
    let mut check = outfile::Batch::new();
    check.input(&args.mesh.mesh)?;
    if let Some(config) = &args.config {
        check.input(config)?;
    }
    if args.out == std::path::Path::new("-") {
        anyhow::bail!(
            "-o -: sweep reads its CSV back and rewrites it after each combination (it is resumable), which standard \
             output cannot do; give a file name"
        );
    }
    check.check(&args.out)?;
    super::files::refuse_other_format(&args.out, "a CSV table (and resumes one)", "csv")?;
    let mut table = match std::fs::read_to_string(&args.out) {
        Ok(text) => SweepTable::parse(&text).with_context(|| format!("{}", args.out.display()))?,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => SweepTable::default(),
        Err(e) => return Err(e).with_context(|| format!("cannot read {}", args.out.display())),
    };

    let (tin, _) = args.mesh.load(out)?;
    table
        .adopt(&setup_digest(&tin, &spec.base, &eval))
        .with_context(|| args.out.display().to_string())?;
    let (combos, notes) = spec.combos(tin.num_triangles())?;
    for n in first_of(&notes, "skipped combination", " (--json lists them all)") {
        out.warn(n);
    }
    if let Some(line) = table.truncated_line() {
        out.warn(format!(
            "{}: line {line} is cut short (an interrupted write?): left out, its combination is incomplete",
            args.out.display()
        ));
    }
    // A combination that lost a line (or holds another evaluation's) is run again when this run's ranges hold it,
    // else kept as it is for a run that does.
    let expected = expected_rows(&spec.base, &eval);
    for (line, method, class) in table.unexpected(&expected) {
        out.warn(format!(
            "{}: line {line}: method {method:?} with class {class:?} is not a line this sweep writes (methods {}; \
             classes {}): its combination is incomplete",
            args.out.display(),
            names(expected.iter().map(|(m, _)| m)),
            names(expected.iter().map(|(_, c)| c))
        ));
    }
    for key in table.incomplete(&expected) {
        let name = format!(
            "{}: sectors {} x subsectors {} (seeds {}, rng seed {})",
            args.out.display(),
            key.sectors,
            key.subsectors,
            key.seeds,
            key.rng_seed
        );
        if combos.iter().any(|c| c.key == key) {
            table.remove(&key);
            out.warn(format!("{name}: its lines are incomplete: run again"));
        } else {
            out.warn(format!(
                "{name}: its lines are incomplete, and it is not in this run's ranges: kept as it is"
            ));
        }
    }
    let todo: Vec<_> = combos.iter().filter(|c| !table.contains(&c.key)).collect();
    let skipped = combos.len() - todo.len();
    out.say(format!(
        "{}: {} already in {}, {} to run",
        count(combos.len(), "combination"),
        skipped,
        args.out.display(),
        todo.len()
    ));

    let start = Instant::now();
    let mut truth_seconds = 0.0;
    if !todo.is_empty() {
        let total = eval.viewpoints * eval.classes.len();
        let bar = out.progress(total as u64, "ground truth");
        let t0 = Instant::now();
        let truth = GroundTruthSet::compute(&tin, &eval, &|done, _| bar.set_position(done as u64))?;
        truth_seconds = t0.elapsed().as_secs_f64();
        bar.finish_and_clear();
        out.say(format!(
            "ground truth: {} viewpoints in {:.1} s ({} triangles; a lower bound of the visible set)",
            truth.views.len(),
            truth_seconds,
            tin.num_triangles()
        ));
        let bar = out.progress(todo.len() as u64, "combinations");
        for combo in &todo {
            let k = &combo.key;
            bar.set_message(format!("s{} k{} r{}", k.sectors, k.subsectors, k.rng_seed));
            let r = run_combo(&tin, &truth, combo, !args.no_per_triangle, None)
                .with_context(|| format!("sectors {} x subsectors {}", k.sectors, k.subsectors))?;
            table.insert(combo.key, r.lines);
            let text = table.to_csv();
            write_one(&args.out, |w| w.write_all(text.as_bytes()))?;
            bar.inc(1);
            let h = r
                .evaluation
                .rows
                .iter()
                .find(|row| row.method == "safe" && row.class == "all");
            if let Some(h) = h {
                let rep = &r.report;
                let line = format!(
                    "s {:>3} k {:>2} seeds {:>4} rng {:>3}: prep {:>7.3} s, {:>4} groups, {:>5} orphans; safe: \
                     occlusion captured {}, false culls {:.2} ({} views), cull {:.1} µs",
                    k.sectors,
                    k.subsectors,
                    k.seeds,
                    k.rng_seed,
                    rep.horizon_seconds + rep.regions_seconds + rep.grouping_seconds,
                    rep.groups,
                    rep.orphans,
                    // Nothing hidden from any viewpoint: nothing to capture ("-", as eval says it).
                    h.summary
                        .occlusion_captured
                        .map_or("-".to_string(), |s| format!("{:.3}", s.mean)),
                    h.summary.false_culls.map_or(0.0, |s| s.mean),
                    h.summary.viewpoints_with_false_culls,
                    h.cull_ns as f64 / 1000.0
                );
                bar.suspend(|| out.say(line));
            }
        }
        bar.finish_and_clear();
    }
    out.say(format!(
        "{}: {}, {}",
        args.out.display(),
        count(table.combos(), "combination"),
        count(table.lines(), "line")
    ));
    out.json(&json!({
        "output": args.out,
        "combinations": combos.len(),
        "ran": todo.len(),
        "skipped": skipped,
        "notes": notes,
        "lines": table.lines(),
        "ground_truth_seconds": truth_seconds,
        "seconds": start.elapsed().as_secs_f64(),
    }))
}

/// Most notes said one by one; the rest are counted.
const NOTES_SHOWN: usize = 8;

/// The first [`NOTES_SHOWN`] of `notes`, and a line counting the others (`what`, in the singular, names one;
/// `where_all` says where they all are, if anywhere).
fn first_of(notes: &[String], what: &str, where_all: &str) -> Vec<String> {
    let mut shown: Vec<String> = notes.iter().take(NOTES_SHOWN).cloned().collect();
    if notes.len() > NOTES_SHOWN {
        shown.push(format!(
            "and {}{where_all}",
            count(notes.len() - NOTES_SHOWN, &format!("more {what}"))
        ));
    }
    shown
}

/// The distinct names of `items`, in their first order, joined by commas.
fn names<'a>(items: impl Iterator<Item = &'a String>) -> String {
    let mut seen: Vec<&str> = Vec::new();
    for i in items {
        if !seen.contains(&i.as_str()) {
            seen.push(i);
        }
    }
    seen.join(", ")
}
