//! `tincull eval`: every culling method against ground truth from seeded viewpoint sets.

use std::path::PathBuf;

use anyhow::{Result, ensure};
use clap::Args;
use truth::ViewpointClass;

use super::culling_args::{Eyes, SafeArgs};
use super::files::Outputs;
use super::{Output, OutputArgs};
use eval::evaluate::{EvalOptions, Evaluation, MAX_VIEWPOINTS, evaluate};

/// Arguments of `tincull eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// The hierarchy file written by `tincull build`.
    pub hierarchy: PathBuf,
    /// Viewpoints per class, 1 to 1000000 (not with --eyes).
    #[arg(long, default_value_t = 20)]
    pub viewpoints: usize,
    /// Viewpoint classes, comma-separated, each once: ground, low, high, valley, ridge, sky (not with --eyes).
    #[arg(long, value_delimiter = ',', default_value = "ground,low,high,valley,ridge,sky")]
    pub classes: Vec<ViewpointClass>,
    /// Seed of the viewpoint generator, and of each viewpoint's yaw below 360° (`--view-seed` everywhere;
    /// `--rng-seed` seeds the grouping) [default: 1]. With --eyes only the yaws are seeded: not at 360°.
    #[arg(long, value_name = "SEED")]
    pub view_seed: Option<u64>,
    /// Horizontal field of view in degrees (360 = all around); below 360 each viewpoint gets a seeded yaw.
    #[arg(long, default_value_t = 360.0)]
    pub fov: f64,
    /// Skip the per-triangle method (it recomputes the horizons of the mesh).
    #[arg(long)]
    pub no_per_triangle: bool,
    /// Skip the conservative precomputed regions (method `safe_regions`; computing them takes a few seconds).
    #[arg(long)]
    pub no_safe_regions: bool,
    /// Score your own camera path: a file of eye positions, one `x,y,z` per line, `#` starting a comment (class
    /// `path`, instead of the seeded viewpoints: not with --classes or --viewpoints).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["classes", "viewpoints"])]
    pub eyes: Option<PathBuf>,
    /// With --eyes: read each eye's z as a height above the terrain under its x,y (m) instead of a world z, as
    /// `cull --above-ground` does. An eye outside the terrain's footprint is an error.
    #[arg(long, requires = "eyes")]
    pub above_ground: bool,
    /// The horizon cullers' parameters (`safe`, `lloyd-egbert`).
    #[command(flatten)]
    pub safe: SafeArgs,
    /// Write the whole evaluation (rows and every viewpoint) as JSON here (`-` for standard output, instead of the
    /// table).
    #[arg(long, value_name = "FILE")]
    pub export_json: Option<PathBuf>,
    /// Write one CSV line per method and class here (`-` for standard output, instead of the table).
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Refuses a viewpoint class given twice in `--classes` (its rows would be counted twice in `all`), naming it.
pub fn check_classes(classes: &[ViewpointClass]) -> Result<()> {
    for (i, c) in classes.iter().enumerate() {
        ensure!(
            !classes[..i].contains(c),
            "--classes: `{}` is given twice; give each class once",
            c.name()
        );
    }
    Ok(())
}

/// Checks the evaluation's outputs (before the work). One of them may be `-` (standard output): the table is then not
/// printed, and `--json` is refused.
pub fn check_outputs(
    files: &mut Outputs,
    json: Option<&std::path::Path>,
    csv: Option<&std::path::Path>,
    out: &mut Output,
) -> Result<()> {
    for (path, flag, what, own) in json
        .map(|p| (p, "--export-json", "the evaluation as JSON", "json"))
        .into_iter()
        .chain(csv.map(|p| (p, "--csv", "the evaluation as CSV", "csv")))
    {
        files.check_or_stdout(path, flag, out)?;
        super::files::refuse_other_format(path, what, own)?;
    }
    Ok(())
}

/// Adds an evaluation's JSON and CSV files where asked.
pub fn add_outputs(
    files: &mut Outputs,
    e: &Evaluation,
    json: Option<&std::path::Path>,
    csv: Option<&std::path::Path>,
) -> Result<()> {
    if let Some(path) = json {
        files.add_bytes(path, serde_json::to_string_pretty(e)?.as_bytes())?;
    }
    if let Some(path) = csv {
        files.add_bytes(path, e.to_csv().as_bytes())?;
    }
    Ok(())
}

/// Checks `--viewpoints` (of `eval`, `sweep` and `demo`): at least 1, at most [`MAX_VIEWPOINTS`].
/// Refuses a field of view (`--fov`, degrees) outside (0, 360], naming the flag (`cull`, `eval` and `sweep`).
pub(crate) fn check_fov(fov: f64) -> Result<()> {
    ensure!(
        fov > 0.0 && fov <= 360.0,
        "--fov {}: the field of view must be in (0, 360] degrees",
        tin::compact_number(fov)
    );
    Ok(())
}

pub(crate) fn check_viewpoints(n: usize) -> Result<()> {
    ensure!(n > 0, "--viewpoints must be at least 1");
    ensure!(
        n <= MAX_VIEWPOINTS,
        "--viewpoints {n}: at most {MAX_VIEWPOINTS} per class (each viewpoint's ground truth takes milliseconds or more)"
    );
    Ok(())
}

/// Runs `tincull eval`.
pub fn run(args: &EvalArgs, out: Output) -> Result<()> {
    let mut out = out;
    check_viewpoints(args.viewpoints)?;
    check_fov(args.fov)?;
    check_classes(&args.classes)?;
    let safe = args.safe.params()?;
    ensure!(
        !(args.eyes.is_some() && args.fov >= 360.0 && args.view_seed.is_some()),
        "--view-seed: with --eyes it seeds only the yaws of a view narrower than 360° (--fov); at 360° it has \
         nothing to seed"
    );
    anyhow::ensure!(
        !args.above_ground || args.eyes.is_some(),
        "--above-ground reads the z of --eyes FILE as heights above the terrain; without --eyes the viewpoint classes \
         set their own heights"
    );
    out.require_a_result(
        args.csv.is_some() || args.export_json.is_some(),
        "give --csv FILE, --export-json FILE or --json",
    )?;
    let mut eyes = args.eyes.as_deref().map(Eyes::read).transpose()?;
    let mut files = Outputs::new();
    files.input(&args.hierarchy)?;
    if let Some(eyes) = &args.eyes {
        files.input(eyes)?;
    }
    check_outputs(&mut files, args.export_json.as_deref(), args.csv.as_deref(), &mut out)?;
    let h = super::mesh_input::load_hierarchy(&args.hierarchy)?;
    if let Some(eyes) = &mut eyes {
        if args.above_ground {
            eyes.lift_above_ground(&h)?;
        } else {
            eyes.check_not_below_ground(&h, true)?;
        }
        eyes.check_within_reach(&h)?;
    }
    let tin = super::mesh_input::hierarchy_tin_of(&h, &args.hierarchy)?;
    if let Some(w) = tin::validate::small_terrain_warning(tin.positions()) {
        out.warn(format!("{}: {w}", args.hierarchy.display()));
    }
    // The region test scored is the grouping's own: `stewart` over a quadtree, `thesis` over crystals.
    let region_test = if h.build.grouping.is_quadtree() {
        cull::CullMethod::Stewart
    } else {
        cull::CullMethod::Thesis
    };
    super::culling_args::warn_if_no_regions(&args.hierarchy, &h, region_test, out);
    let opts = EvalOptions {
        viewpoints: args.viewpoints,
        classes: args.classes.clone(),
        view_seed: args.view_seed.unwrap_or(1),
        fov_deg: args.fov,
        per_triangle: !args.no_per_triangle,
        safe,
        safe_regions: !args.no_safe_regions,
        eyes: eyes.map(|e| e.points),
    };
    let total = opts
        .eyes
        .as_ref()
        .map_or(opts.viewpoints * opts.classes.len(), Vec::len);
    // The bar names the stage: the per-triangle regions (their horizons) before the ground truth, the culls and the
    // conservative regions of `safe_regions` after it; it ticks by itself through them.
    let bar = out.progress(total as u64, "viewpoints");
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    if opts.per_triangle {
        bar.set_message("per-triangle regions");
    }
    let e = evaluate(&h, &tin, &opts, &|done, total| {
        bar.set_message(if done < total {
            "viewpoints"
        } else if opts.safe_regions {
            "scoring (and safe_regions' conservative regions)"
        } else {
            "scoring"
        });
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    out.say(e.table());
    out.say(format!(
        "ground truth: {:.3} s per viewpoint ({} triangles; a lower bound of the visible set)",
        e.ground_truth_seconds_per_viewpoint, e.triangles
    ));
    add_outputs(&mut files, &e, args.export_json.as_deref(), args.csv.as_deref())?;
    files.commit()?;
    // The evaluation as `--export-json` writes it, less its viewpoints.
    out.json(&serde_json::json!({
        "hierarchy": args.hierarchy,
        "options": e.options,
        "triangles": e.triangles,
        "ground_truth_seconds_per_viewpoint": e.ground_truth_seconds_per_viewpoint,
        "per_triangle_setup_seconds": e.per_triangle_setup_seconds,
        "safe_regions_setup_seconds": e.safe_regions_setup_seconds,
        "rows": e.rows,
    }))
}
