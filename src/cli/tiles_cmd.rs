//! `tincull tiles plan|build|merge`: tiled builds of terrains too large for one build (crate `tiles`).

use super::output::count;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use rayon::prelude::*;
use serde_json::json;
use tiles::{Plan, PlanOptions, TileReport, TilesError};

use super::build_cmd::{ParamArgs, peak_memory_bytes, stage_progress};
use super::files::Outputs;
use super::mesh_input::{DedupeArg, DemArgs, ImportArgs, MeshArgs, UpArg, is_dem};
use super::{Output, OutputArgs};

/// Arguments of `tincull tiles`.
#[derive(Debug, Args)]
pub struct TilesArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: TilesCommand,
}

/// The steps of a tiled build.
#[derive(Debug, Subcommand)]
pub enum TilesCommand {
    /// Cut a DEM grid (or a mesh) into tiles and write the plan (JSON: tiles, halo, build parameters) and each
    /// tile's far field (a DEM, read in strips of rows) or part (a mesh) beside it.
    Plan(Box<PlanArgs>),
    /// Build one tile of a plan (`--tile I`: one job, as a cluster runs it) or every tile here (`--all`).
    Build(TileBuildArgs),
    /// Join the tiles' hierarchies into one `.tch`.
    Merge(MergeArgs),
}

/// Default tile side of a DEM's plan, in sample intervals (a mesh's: in mean vertex spacings).
const DEFAULT_TILE: usize = 512;
/// Default halo of a DEM's plan, in samples (a mesh's: in mean vertex spacings).
const DEFAULT_HALO: usize = 16;
/// Default far-field block of a DEM's plan, in samples (a mesh's: in mean vertex spacings).
const DEFAULT_FAR_BLOCK: usize = 16;
/// Default growth of the far field's blocks with distance (see `--far-ratio`).
const DEFAULT_FAR_RATIO: usize = 16;
/// Default vertical error bound of a DEM's tiles (m); a mesh's plan records it too, unused.
const DEFAULT_MAX_ERROR: f64 = 1.0;

/// Arguments of `tincull tiles plan`.
#[derive(Debug, Args)]
pub struct PlanArgs {
    /// The DEM: .npy (with its .json sidecar or --spacing), .asc, .hgt (SRTM), 8- or 16-bit greyscale .png or GeoTIFF;
    /// or a mesh (OBJ), read whole once and cut into squares (then --tile, --halo and --far-block are metres).
    pub dem: PathBuf,
    /// For a mesh: use the file's own triangles (checked to form a height field) instead of re-triangulating.
    #[arg(long)]
    pub keep_faces: bool,
    /// For a mesh: what to do with vertices that share x,y but differ in z (as every command that reads a mesh)
    /// [default: reject].
    #[arg(long, value_enum)]
    pub dedupe: Option<DedupeArg>,
    /// For a mesh: its up axis (y for a y-up OBJ, rotated to z up; as every command that reads a mesh) [default: z].
    #[arg(long, value_enum)]
    pub up: Option<UpArg>,
    /// The plan to write (JSON); tiles write their hierarchies to `<plan stem>.tiles/` beside it.
    #[arg(short, long, value_name = "FILE")]
    pub out: PathBuf,
    /// Largest tile side, in sample intervals (a mesh: whole metres) [default: 512 samples; a mesh: 512 times its
    /// mean vertex spacing, the side of a square of its area over its vertices]
    #[arg(long, value_name = "N", value_parser = parse_whole)]
    pub tile: Option<usize>,
    /// Width of the full-resolution halo around each tile whose samples its horizons see, in samples (a mesh:
    /// whole metres, its vertices) [default: 16 samples; a mesh: 16 mean vertex spacings]
    #[arg(long, value_name = "N", value_parser = parse_whole)]
    pub halo: Option<usize>,
    /// Side of the far field's blocks in samples: each contributes its lowest sample, lowered by --max-error (a
    /// mesh: whole metres, its lowest vertex) [default: 16 samples; a mesh: 16 mean vertex spacings]
    #[arg(long, value_name = "N", value_parser = parse_whole)]
    pub far_block: Option<usize>,
    /// Far-field blocks double in size with distance, keeping each within about 1/R radian seen from the tile, so
    /// a tile's far field grows with the logarithm of the terrain, not its area; 0 keeps every block at
    /// --far-block [default: 16].
    #[arg(long, value_name = "R")]
    pub far_ratio: Option<usize>,
    /// With --grouping quadtree: the tiles compute no horizons and no regions, and need no halo and no far field,
    /// as `build --no-regions` does: the quadtree's cells alone, for the run-time cullers (`safe`, the default, and
    /// `lloyd-egbert`); the region tests (`stewart`, `thesis`) cull nothing in the merged file.
    #[arg(long)]
    pub no_regions: bool,
    /// Vertical error bound of every tile's TIN (m); 0 keeps every sample that is not exactly interpolated (a DEM
    /// only: a mesh keeps its triangles) [default: 1].
    #[arg(long, value_name = "M")]
    pub max_error: Option<f64>,
    /// How to read the DEM.
    #[command(flatten)]
    pub read: DemArgs,
    /// Build parameters of every tile.
    #[command(flatten)]
    pub params: ParamArgs,
    /// Read the build parameters (`--sectors`, `--seeds`, …) from this TOML file, keys as their long options with
    /// underscores; the plan's own options (`--tile`, `--halo`, `--max-error`, …) are given on the command line.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Arguments of `tincull tiles build`.
#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("which").required(true).args(["tile", "all"])))]
pub struct TileBuildArgs {
    /// The plan (from `tiles plan`).
    pub plan: PathBuf,
    /// Build this tile (0-based); repeat for several (each is built once, in index order).
    #[arg(long)]
    pub tile: Vec<usize>,
    /// Build every tile of the plan.
    #[arg(long)]
    pub all: bool,
    /// Threads [default: --threads, else `RAYON_NUM_THREADS`, else one per core]: a single tile's build uses them (up
    /// to the machine's cores); several tiles are built at once on them, at most one thread per tile, with a warning
    /// above the machine's cores (each running tile holds its own memory).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Arguments of `tincull tiles merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// The plan whose tiles were built.
    pub plan: PathBuf,
    /// The merged hierarchy (.tch; `-` for standard output, instead of the report, when it is not a terminal).
    #[arg(short, long, value_name = "FILE")]
    pub out: PathBuf,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Runs `tincull tiles`.
pub fn run(args: &TilesArgs) -> Result<()> {
    match &args.command {
        TilesCommand::Plan(a) => plan(a, a.output.into()),
        TilesCommand::Build(a) => build(a, a.output.into()),
        TilesCommand::Merge(a) => merge(a, a.output.into()),
    }
}

fn plan(args: &PlanArgs, out: Output) -> Result<()> {
    let mut files = Outputs::new();
    files.input(&args.dem)?;
    if let Some(config) = &args.config {
        files.input(config)?;
    }
    files.check(&args.out)?;
    super::files::refuse_other_format(&args.out, "a tiling plan (JSON)", "json")?;
    if args.out.extension().is_some_and(|e| e == "tiles") {
        bail!(
            "{}: the plan's tiles go into the folder `<plan name without extension>.tiles` beside it, which would be \
             this very path; name the plan otherwise (such as plan.json)",
            args.out.display()
        );
    }
    let params = args.params.resolve(args.config.as_deref())?;
    if args.no_regions {
        super::build_cmd::check_no_regions(&params)?;
        let given = [
            ("--halo", args.halo.is_some()),
            ("--far-block", args.far_block.is_some()),
            ("--far-ratio", args.far_ratio.is_some()),
        ];
        if let Some((flag, _)) = given.iter().find(|(_, g)| *g) {
            bail!(
                "{flag}: a plan without regions (--no-regions) computes no horizons, so its tiles read no halo or \
                 far field"
            );
        }
    }
    // In samples for a DEM; a mesh's plan scales them by its vertex spacing (`plan_mesh`).
    let options = PlanOptions {
        tile: args.tile.unwrap_or(DEFAULT_TILE),
        halo: if args.no_regions {
            0
        } else {
            args.halo.unwrap_or(DEFAULT_HALO)
        },
        far_block: args.far_block.unwrap_or(DEFAULT_FAR_BLOCK),
        far_ratio: args.far_ratio.unwrap_or(DEFAULT_FAR_RATIO),
        max_error: args.max_error.unwrap_or(DEFAULT_MAX_ERROR),
        params,
        no_regions: args.no_regions,
    };
    let stem = args
        .out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tiles_dir = PathBuf::from(format!("{stem}.tiles"));
    // The tiles' folder is made after the work: something else in its place is refused before it.
    let dir = Plan::resolve(&args.out, &tiles_dir);
    if dir.exists() && !dir.is_dir() {
        bail!(
            "{}: the plan's tiles go into this folder, and something that is not a folder is there; move it, or name \
             the plan otherwise (-o)",
            dir.display()
        );
    }
    let source = std::path::absolute(&args.dem).with_context(|| format!("cannot resolve {}", args.dem.display()))?;
    if !is_dem(&args.dem) {
        super::mesh_input::refuse_dem_flags_for_mesh(&args.dem, &args.read, None)?;
        if let Some(m) = args.max_error {
            bail!(
                "{}: --max-error {} applies to a DEM's tiles (each simplified to it); a mesh's tiles keep its triangles",
                args.dem.display(),
                tin::compact_number(m),
            );
        }
        return plan_mesh(args, out, files, options, &source, &tiles_dir);
    }
    super::mesh_input::refuse_mesh_flags_for_dem(&args.dem, args.keep_faces, args.dedupe, args.up)?;
    let dem = args.read.options();
    super::mesh_input::warn_about_dem_file(&args.dem, &dem, out);
    let bar = out.progress(0, "reading DEM rows");
    let (mut plan, field, left) = tiles::make_plan(&source, dem, options.clone(), &tiles_dir, |done, rows| {
        bar.set_length(rows as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    let grid = plan.grid.clone().context("a DEM's plan has its grid")?;
    let dir = Plan::resolve(&args.out, &plan.tiles_dir);
    let far_points = in_new_dir(&dir, || {
        let mut far_points = 0;
        let mut digests = Vec::with_capacity(plan.tiles.len());
        for spec in &plan.tiles {
            if let Some(far) = &spec.far {
                let (bytes, count) = plan.far_file(&field, spec)?;
                files.add_bytes(&Plan::resolve(&args.out, far), &bytes)?;
                digests.push(tiles::plan::file_digest(&bytes));
                far_points = far_points.max(count);
            }
        }
        plan.seal(&digests)?;
        files.add_bytes(&args.out, plan.to_json()?.as_bytes())?;
        files.commit()?;
        Ok(far_points)
    })?;
    warn_of_earlier_files(&plan, &args.out, &dir, out);
    let [rows, cols] = tiles::plan::tile_grid([grid.rows, grid.cols], options.tile);
    let left_out = if left.void_tiles > 0 {
        format!(", {} of voids left out", count(left.void_tiles, "tile"))
    } else {
        String::new()
    };
    if left.line_tiles > 0 {
        out.warn(format!(
            "{} left out: their {} lie on one line (a row, a column, a diagonal) or are fewer than 3, which a tile \
             cannot triangulate alone; those on a side shared with another tile stay, the others are not in the \
             tiled terrain (the untiled `tin` and `build` keep them; a larger --tile may too)",
            count(left.line_tiles, "tile"),
            count(left.line_samples, "sample")
        ));
    }
    let far_blocks = if options.no_regions { 0 } else { field.finest() };
    let beyond = if options.no_regions {
        "no regions (no halo, no far field)".to_string()
    } else {
        format!(
            "halo {} samples, far field {far_blocks} blocks (at most {far_points} points per tile)",
            options.halo
        )
    };
    out.say(format!(
        "{} ({} x {} samples) -> {}: {} ({rows} x {cols}{left_out}) of at most {} intervals, {beyond}; tiles write to \
         {}",
        args.dem.display(),
        grid.rows,
        grid.cols,
        args.out.display(),
        count(plan.tiles.len(), "tile"),
        options.tile,
        dir.display()
    ));
    out.json(&json!({
        "output": args.out,
        "tiles": plan.tiles.len(),
        "tile_rows": rows,
        "tile_cols": cols,
        "void_tiles": left.void_tiles,
        "line_tiles": left.line_tiles,
        "line_samples": left.line_samples,
        "far_blocks": far_blocks,
        "far_points_max": far_points,
        "tiles_dir": dir,
    }))
}

/// Warns of the files of an earlier plan left in the tiles' folder `dir` (far fields, parts and tiles named as a plan
/// names them, that `plan` does not name): the new plan never reads them, and they are the user's to remove (tiles
/// may have taken hours to build, so nothing is deleted).
fn warn_of_earlier_files(plan: &Plan, plan_path: &Path, dir: &Path, out: Output) {
    let ours: std::collections::HashSet<PathBuf> = plan
        .tiles
        .iter()
        .flat_map(|t| t.far.iter().chain(&t.part).chain(std::iter::once(&t.output)))
        .filter_map(|p| Plan::resolve(plan_path, p).file_name().map(PathBuf::from))
        .collect();
    let planned_name = |name: &str| {
        let digits = |s: &str, n: usize| s.len() == n && s.bytes().all(|b| b.is_ascii_digit());
        let hex = |s: &str| s.len() == 8 && s.bytes().all(|b| b.is_ascii_hexdigit());
        let stem = |prefix: &str, ext: &str| name.strip_prefix(prefix).and_then(|r| r.strip_suffix(ext));
        stem("far-", ".bin").is_some_and(|n| digits(n, 5))
            || stem("part-", ".bin").is_some_and(|n| digits(n, 5))
            || stem("tile-", ".tch")
                .is_some_and(|n| digits(n, 5) || n.split_once('-').is_some_and(|(i, d)| digits(i, 5) && hex(d)))
    };
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut earlier: Vec<String> = entries
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| planned_name(n) && !ours.contains(Path::new(n)))
        .collect();
    earlier.sort();
    if let Some(first) = earlier.first() {
        let (files, remain) = match earlier.len() {
            1 => ("1 file".to_string(), "remains"),
            n => (count(n, "file"), "remain"),
        };
        out.warn(format!(
            "{}: {files} of an earlier plan {remain} (first {first}); this plan does not read them: remove them once \
             their tiles are not needed",
            dir.display(),
        ));
    }
}

/// Parses a length of a plan: a whole number of samples (a DEM) or metres (a mesh).
fn parse_whole(s: &str) -> Result<usize, String> {
    s.trim()
        .parse::<usize>()
        .map_err(|_| format!("{s:?} is not a whole number (0 or more): samples of a DEM, or whole metres of a mesh"))
}

/// Creates the folder `dir` of a plan's tile files, then runs `work`, which writes into it: when `work` fails or is
/// interrupted (Ctrl-C) and the folder was new, it is removed again (it is then empty, the files being all or
/// nothing), so a failed plan leaves nothing behind.
fn in_new_dir<T>(dir: &Path, work: impl FnOnce() -> Result<T>) -> Result<T> {
    let new = outfile::NewDir::create(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let result = work()?;
    if let Some(new) = new {
        new.keep();
    }
    Ok(result)
}

/// `tiles plan MESH`: the whole mesh is read once and cut; each tile's part is written beside the plan.
fn plan_mesh(
    args: &PlanArgs,
    out: Output,
    mut files: Outputs,
    options: PlanOptions,
    source: &Path,
    tiles_dir: &Path,
) -> Result<()> {
    let mesh = MeshArgs {
        mesh: args.dem.clone(),
        import: ImportArgs {
            keep_faces: args.keep_faces,
            dedupe: args.dedupe,
            up: args.up,
            ..ImportArgs::default()
        },
    };
    let (tin, _) = mesh.load(out)?;
    // Unset sizes as a DEM's in samples, a sample being the mesh's mean vertex spacing: the side of a square of its
    // footprint's area over its vertices (whole metres, at least 1).
    let size = tin.bbox().size();
    let spacing = (size.x * size.y / tin.num_vertices().max(1) as f64)
        .sqrt()
        .ceil()
        .max(1.0);
    let scaled = |given: Option<usize>, samples: usize| given.unwrap_or((samples as f64 * spacing) as usize);
    let options = PlanOptions {
        tile: scaled(args.tile, DEFAULT_TILE),
        halo: if args.no_regions {
            0
        } else {
            scaled(args.halo, DEFAULT_HALO)
        },
        far_block: scaled(args.far_block, DEFAULT_FAR_BLOCK),
        ..options
    };
    let (mut plan, parts) = tiles::make_mesh_plan(&tin, source, options.clone(), tiles_dir)?;
    let dir = Plan::resolve(&args.out, tiles_dir);
    in_new_dir(&dir, || {
        let paths: Vec<PathBuf> = plan
            .tiles
            .iter()
            .filter_map(|t| t.part.as_ref().map(|p| Plan::resolve(&args.out, p)))
            .collect();
        for p in &paths {
            files.check(p)?;
        }
        let mut digests = Vec::with_capacity(parts.len());
        for (p, part) in paths.iter().zip(&parts) {
            let bytes = part.to_bytes()?;
            files.add_bytes(p, &bytes)?;
            digests.push(tiles::plan::file_digest(&bytes));
        }
        plan.seal(&digests)?;
        files.add_bytes(&args.out, plan.to_json()?.as_bytes())?;
        files.commit()
    })?;
    warn_of_earlier_files(&plan, &args.out, &dir, out);
    let (rows, cols) = plan
        .tiles
        .iter()
        .fold((0, 0), |(r, c), t| (r.max(t.tile_row + 1), c.max(t.tile_col + 1)));
    let beyond = if options.no_regions {
        "no regions (no halo, no far field)".to_string()
    } else {
        format!("halo {} m, far field blocks of {} m", options.halo, options.far_block)
    };
    out.say(format!(
        "{} ({} vertices, {} triangles) -> {}: {} (of a {rows} x {cols} grid of {} m squares), {beyond}; parts and \
         tiles in {}",
        args.dem.display(),
        tin.num_vertices(),
        tin.num_triangles(),
        args.out.display(),
        count(plan.tiles.len(), "tile"),
        options.tile,
        dir.display()
    ));
    out.json(&json!({
        "output": args.out,
        "tiles": plan.tiles.len(),
        "tile_rows": rows,
        "tile_cols": cols,
        "far_points_max": parts.iter().map(|p| p.far.len()).max().unwrap_or(0),
        "tiles_dir": dir,
    }))
}

/// Checks what tile `index`'s job reads and writes, before any work: the files the plan wrote for it are there, and
/// its output can be written and is none of its inputs (an output whose folder is missing is checked once the folder
/// is made, with `made`). Returns the output and its check.
fn check_tile(plan: &Plan, plan_path: &Path, index: usize, made: bool) -> Result<(PathBuf, Outputs)> {
    let spec = plan.tile(index)?;
    let target = Plan::resolve(plan_path, &spec.output);
    // The files the plan wrote for this job first: when they are gone (the tiles' folder deleted), nothing is made.
    for read in spec.far.iter().chain(&spec.part) {
        let path = Plan::resolve(plan_path, read);
        if !path.exists() {
            bail!(
                "tile {index}: {} is missing (the plan writes it beside itself): plan again with `tincull tiles plan`",
                path.display()
            );
        }
    }
    let dir = output_dir(&target);
    // What the job reads is never its output (a plan edited by hand could name the DEM or a far-field file).
    let mut files = Outputs::new();
    files.input(plan_path)?;
    files.input(&Plan::resolve(plan_path, &plan.source))?;
    for read in spec.far.iter().chain(&spec.part) {
        files.input(&Plan::resolve(plan_path, read))?;
    }
    if made || dir.is_none_or(Path::exists) {
        files
            .check(&target)
            .with_context(|| format!("tile {index}: its output"))?;
    }
    Ok((target, files))
}

/// The folder of a tile's output, when its path names one.
fn output_dir(target: &Path) -> Option<&Path> {
    target.parent().filter(|d| !d.as_os_str().is_empty())
}

/// Builds one tile and writes its hierarchy (its output's folder made).
fn build_one(plan: &Plan, plan_path: &Path, index: usize, out: Output, bars: bool) -> Result<TileReport> {
    let (target, mut files) = check_tile(plan, plan_path, index, true)?;
    let progress = bars.then(|| stage_progress(out));
    let (h, report) = tiles::build_tile(plan, plan_path, index, progress).with_context(|| format!("tile {index}"))?;
    files.add_bytes(&target, &h.to_bytes()?)?;
    files.commit()?;
    Ok(report)
}

fn build(args: &TileBuildArgs, out: Output) -> Result<()> {
    let plan = Plan::load(&args.plan)?;
    let indices: Vec<usize> = if args.all {
        (0..plan.tiles.len()).collect()
    } else {
        // A tile given twice is built once (twice at once, both jobs would write the same file).
        let mut given = args.tile.clone();
        given.sort_unstable();
        given.dedup();
        given
    };
    // Every tile's inputs and output checked before the first is built; then the outputs' missing folders are made,
    // removed again (with the folders above them that were made) when no tile was written into them.
    let mut dirs = Vec::new();
    for &i in &indices {
        let (target, _) = check_tile(&plan, &args.plan, i, false)?;
        dirs.extend(output_dir(&target).map(Path::to_path_buf));
    }
    dirs.sort_unstable();
    dirs.dedup();
    // Deepest first: a folder inside another is made with it, and both are removed in that order.
    let mut made = Vec::new();
    for dir in dirs.iter().rev() {
        made.push(outfile::NewDir::create_all(dir).with_context(|| format!("cannot create {}", dir.display()))?);
    }
    let start = Instant::now();
    // Without --jobs, as many threads as the global pool (--threads, `RAYON_NUM_THREADS` or the cores).
    let mut builder = rayon::ThreadPoolBuilder::new().num_threads(rayon::current_num_threads());
    if let Some(j) = args.jobs {
        if j == 0 {
            bail!("--jobs must be at least 1");
        }
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        if j > cores && indices.len() == 1 {
            out.warn(format!(
                "--jobs {j} is more than the {cores} cores of this machine: the tile's build uses {cores}"
            ));
        } else if j > cores {
            out.warn(format!(
                "--jobs {j} is more than the {cores} cores of this machine: the tiles built at once share them, and \
                 each holds its own memory"
            ));
        }
        // One tile uses the threads in its own build, up to the cores (more would only wait); several take one
        // thread each at most, so that no more tiles than threads are held in memory at once.
        builder = builder.num_threads(if indices.len() == 1 {
            j.min(cores)
        } else {
            j.min(indices.len())
        });
    }
    let pool = builder.build()?;
    let reports: Vec<TileReport> = if indices.len() == 1 {
        pool.install(|| build_one(&plan, &args.plan, indices[0], out, true))
            .map(|r| vec![r])?
    } else {
        let bar = out.progress(indices.len() as u64, "tiles");
        let r = pool.install(|| {
            indices
                .par_iter()
                .map(|&i| {
                    let r = build_one(&plan, &args.plan, i, out, false);
                    bar.inc(1);
                    r
                })
                .collect::<Result<Vec<_>>>()
        })?;
        bar.finish_and_clear();
        r
    };
    made.into_iter().for_each(outfile::NewDirs::keep);
    let seconds = start.elapsed().as_secs_f64();
    for r in &reports {
        // A DEM's tile is simplified from its samples; a mesh's tile keeps its part's vertices as they are.
        let (tin, simplify) = if plan.grid.is_some() {
            (
                format!(
                    "{} samples -> {} vertices, {} triangles (max error {:.3} m)",
                    r.samples, r.vertices, r.triangles, r.max_error
                ),
                format!(", simplify {:.2} s", r.simplify_seconds),
            )
        } else {
            (
                format!("{} vertices, {} triangles", r.vertices, r.triangles),
                String::new(),
            )
        };
        if r.build.without_regions {
            out.say(format!(
                "tile {}: {tin}; no regions; read {:.2} s{simplify}, quadtree {:.2} s",
                r.index, r.read_seconds, r.build.grouping_seconds
            ));
            continue;
        }
        out.say(format!(
            "tile {}: {tin}; halo {} and far field {} points; read {:.2} s{simplify}, triangulate {:.2} s, horizons \
             {:.2} s, grouping {:.2} s",
            r.index,
            r.halo_points,
            r.far_points,
            r.read_seconds,
            r.triangulate_seconds,
            r.build.horizon_seconds,
            r.build.grouping_seconds
        ));
    }
    let peak = peak_memory_bytes();
    out.say(format!(
        "{} in {seconds:.2} s{}",
        count(reports.len(), "tile"),
        peak.map(|b| format!(", peak memory {:.1} MB", b as f64 / 1e6))
            .unwrap_or_default()
    ));
    out.json(&json!({
        "tiles": reports,
        "seconds": seconds,
        "threads": pool.current_num_threads(),
        "peak_memory_bytes": peak,
    }))
}

fn merge(args: &MergeArgs, out: Output) -> Result<()> {
    let mut out = out;
    let plan = Plan::load(&args.plan)?;
    let mut files = Outputs::new();
    files.input(&args.plan)?;
    for t in &plan.tiles {
        files.input(&Plan::resolve(&args.plan, &t.output))?;
    }
    files.check_binary_or_stdout(&args.out, "-o", &mut out)?;
    super::files::refuse_other_format(&args.out, "a hierarchy", "tch")?;
    let start = Instant::now();
    // Every tile must be built before any is read; every missing one is named (the first 20 by number).
    let missing: Vec<usize> = plan
        .tiles
        .iter()
        .filter(|t| !Plan::resolve(&args.plan, &t.output).exists())
        .map(|t| t.index)
        .collect();
    if let Some(&first) = missing.first() {
        let shown: Vec<String> = missing.iter().take(20).map(usize::to_string).collect();
        let more = match missing.len() {
            1 => String::new(),
            2 => format!(", nor tile {}", shown[1]),
            n if n <= 20 => format!(", nor tiles {}", shown[1..].join(", ")),
            n => format!(", nor {} more tiles ({}, ...)", n - 1, shown[1..].join(", ")),
        };
        // The command that builds them: every tile (`--all`) when none is built, else the missing ones by number.
        let build = if missing.len() == plan.tiles.len() && missing.len() > 1 {
            format!("`tincull tiles build {} --all`", args.plan.display())
        } else {
            format!(
                "`tincull tiles build {} --tile {}`{}",
                args.plan.display(),
                shown.join(" --tile "),
                if missing.len() > 20 { " and the others" } else { "" }
            )
        };
        bail!(
            "tile {first} has not been built ({} is missing){more}: run {build}",
            Plan::resolve(&args.plan, &plan.tiles[first].output).display(),
        );
    }
    let bar = out.progress(plan.tiles.len() as u64, "merging");
    let h = tiles::merge::merge_with(&plan, |i| {
        let path = Plan::resolve(&args.plan, &plan.tiles[i].output);
        let h = cull::Hierarchy::load(&path)
            .map_err(|e| TilesError::Parameter(format!("tile {i}: {:#}", anyhow::Error::from(e))))?;
        bar.inc(1);
        Ok(h)
    })?;
    bar.finish_and_clear();
    files.add_bytes(&args.out, &h.to_bytes()?)?;
    files.commit()?;
    let seconds = start.elapsed().as_secs_f64();
    let peak = peak_memory_bytes();
    out.say(format!(
        "{} -> {}: {} vertices, {} triangles, {}, {} always visible; {seconds:.2} s{}",
        count(plan.tiles.len(), "tile"),
        args.out.display(),
        h.mesh.positions.len(),
        h.num_triangles(),
        count(h.nodes.len(), "node"),
        h.always_visible[1] - h.always_visible[0],
        peak.map(|b| format!(", peak memory {:.1} MB", b as f64 / 1e6))
            .unwrap_or_default()
    ));
    out.json(&json!({
        "output": args.out,
        "tiles": plan.tiles.len(),
        "vertices": h.mesh.positions.len(),
        "triangles": h.num_triangles(),
        "nodes": h.nodes.len(),
        "orphans": h.always_visible[1] - h.always_visible[0],
        "seconds": seconds,
        "peak_memory_bytes": peak,
    }))
}

#[cfg(test)]
mod tests {
    use super::in_new_dir;

    #[test]
    fn a_failed_plan_removes_the_folder_it_created_and_keeps_one_that_was_there() {
        let root = tempfile::tempdir().expect("tempdir");
        let new = root.path().join("p.tiles");
        let failed: anyhow::Result<()> = in_new_dir(&new, || anyhow::bail!("the work failed"));
        assert!(failed.is_err());
        assert!(!new.exists(), "a folder the failed plan created is removed");
        let done = in_new_dir(&new, || Ok(7)).expect("the work succeeds");
        assert_eq!(done, 7);
        assert!(new.is_dir(), "a successful plan keeps its folder");
        let failed: anyhow::Result<()> = in_new_dir(&new, || anyhow::bail!("the work failed"));
        assert!(failed.is_err());
        assert!(new.is_dir(), "a folder that was there before is left as it was");
    }
}
