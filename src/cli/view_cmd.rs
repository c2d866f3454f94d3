//! `tincull view`: the interactive viewer on a hierarchy or a mesh (its rebuilds and exports use the `pipeline`
//! crate directly).

use super::output::count;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use viewer::app::{RebuildParams, ScreenshotRequest, Source, Startup, ViewerOptions};

use super::Output;
use super::build_cmd::ParamArgs;
use super::values::parse_point;

/// Frames drawn before a screenshot, by default.
const DEFAULT_SCREENSHOT_AFTER: u32 = 10;

/// Arguments of `tincull view`.
#[derive(Debug, Args)]
pub struct ViewArgs {
    /// A hierarchy (.tch), or a terrain mesh (.obj) or DEM grid (.npy, .asc, .hgt, .png, .tif/.tiff) simplified to
    /// --dem-vertices.
    pub input: PathBuf,
    /// Culling method at start (switchable in the side panel): `safe`, `thesis`, `stewart` or `lloyd-egbert`. The
    /// horizon cullers' flags (--columns …) are taken with any method: they apply whenever the panel switches to
    /// `safe` or `lloyd-egbert`.
    #[arg(long, default_value = "safe", value_parser = super::cull_cmd::parse_method)]
    pub method: cull::CullMethod,
    /// The horizon cullers' parameters (`safe`, `lloyd-egbert`).
    #[command(flatten)]
    pub safe: super::culling_args::SafeArgs,
    /// Initial viewpoint `x,y,z` in world coordinates (m) [default: the centre, 20 m above the ground].
    #[arg(long, value_parser = parse_point, allow_hyphen_values = true)]
    pub eye: Option<[f64; 3]>,
    /// How to import a mesh input.
    #[command(flatten)]
    pub import: super::mesh_input::ImportArgs,
    /// Initial build parameters of the side panel (the hierarchy's own, when it records them: its grouping too,
    /// unless --grouping is given).
    #[command(flatten)]
    pub params: ParamArgs,
    /// With a quadtree (--grouping quadtree, or a quadtree hierarchy): Rebuild computes no horizons and no regions,
    /// as `build --no-regions` does (the cells alone, for the `safe` and `lloyd-egbert` cullers). A hierarchy without
    /// regions is rebuilt so without it; the side panel switches it too.
    #[arg(long)]
    pub no_regions: bool,
    /// Build the hierarchy with the panel's parameters right away, in the background (as the Rebuild button does).
    #[arg(long)]
    pub rebuild: bool,
    /// Compute the ground truth for the initial viewpoint right away (after --rebuild), showing false culls in red.
    #[arg(long)]
    pub truth: bool,
    /// Turn the viewcell PVS on at start, with cells of this side (m): the cell around the eye is outlined on the map
    /// and what its PVS excludes is painted as culled (also a toggle in the side panel).
    #[arg(long, value_name = "M")]
    pub pvs_cell_size: Option<f64>,
    /// Write a screenshot of the window to this PNG after a few frames (and after --rebuild and --truth), then
    /// close.
    #[arg(long, value_name = "PNG")]
    pub screenshot: Option<PathBuf>,
    /// Frames drawn before the screenshot.
    #[arg(long, default_value_t = DEFAULT_SCREENSHOT_AFTER)]
    pub screenshot_after: u32,
    /// Window size `WIDTHxHEIGHT` in points, each 1 to 8192 (a window larger than the screen may be made smaller by
    /// the window manager; the screenshot is the window as drawn).
    #[arg(long, default_value = "1280x800", value_parser = super::render_cmd::parse_size)]
    pub size: [u32; 2],
    /// No progress bars or human-readable text (errors and warnings are still printed), as in every command.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Runs `tincull view`.
pub fn run(args: &ViewArgs, out: Output) -> Result<()> {
    let is_tch = super::mesh_input::is_hierarchy(&args.input);
    // The screenshot's path is checked before the window opens, as every output is.
    if let Some(shot) = &args.screenshot {
        let mut files = super::files::Outputs::new();
        files.input(&args.input)?;
        files.check(shot)?;
        super::files::require_png(shot, "--screenshot")?;
    } else if args.screenshot_after != DEFAULT_SCREENSHOT_AFTER {
        anyhow::bail!("--screenshot-after {} applies to --screenshot", args.screenshot_after);
    }
    anyhow::ensure!(
        !args.truth || is_tch || args.rebuild,
        "--truth compares the culler with the ground truth, and a mesh has no culler until it is built: add --rebuild"
    );
    if let Some(m) = args.pvs_cell_size {
        anyhow::ensure!(
            m.is_finite() && m >= 1.0,
            "--pvs-cell-size {m}: the cells' side must be at least 1 m"
        );
    }
    let mut params = args.params.resolve(None)?;
    let mut without_regions = args.no_regions;
    let source = if is_tch {
        args.import.mesh(&args.input).refuse_for_hierarchy()?;
        let h = super::mesh_input::load_hierarchy(&args.input)?;
        args.method
            .check(&h)
            .with_context(|| format!("{}", args.input.display()))?;
        super::culling_args::warn_if_no_regions(&args.input, &h, args.method, out);
        if let Some(eye) = args.eye {
            super::culling_args::Eyes::given(eye).check_not_below_ground(&h, false)?;
        }
        let b = &h.build;
        let p = &args.params;
        params.sectors = p.sectors.unwrap_or(h.sectors);
        if b.subsectors > 0 {
            let c = &mut params.crystal;
            params.subsectors = p.subsectors.unwrap_or(b.subsectors);
            c.seeds = p.seeds.or(Some(b.seeds as usize).filter(|&s| s > 0));
            c.orphan_passes = p.fixed.orphan_passes.unwrap_or(b.orphan_passes);
            c.min_group = p.fixed.min_group.unwrap_or(b.min_group as usize);
            c.max_expanse = p.fixed.max_expanse.unwrap_or(b.max_expanse);
            c.rng_seed = p.rng_seed.unwrap_or(b.rng_seed);
            params.undersampling = p.fixed.undersampling.or(b.undersampling);
        }
        if p.fixed.grouping.is_none() {
            // Rebuilt as it was built: a quadtree at its depth (a byte budget it was built with is not recorded),
            // without regions if it has none.
            if let cull::Grouping::Quadtree { built_depth, .. } = b.grouping {
                params.grouping = pipeline::Grouping::Quadtree(pipeline::QuadtreeParams {
                    depth: Some(built_depth),
                    ..Default::default()
                });
                without_regions |= !h.has_regions();
            }
        }
        check_no_regions(args, &params.grouping)?;
        Source::Hierarchy(h)
    } else {
        // The hierarchy comes from the panel's parameters (Rebuild): the method must fit their grouping.
        let grouping = match params.grouping {
            pipeline::Grouping::Crystal => cull::Grouping::Crystal,
            pipeline::Grouping::Quadtree(_) => cull::Grouping::Quadtree {
                built_depth: 0,
                stored_depth: 0,
            },
        };
        args.method
            .check_grouping(grouping)
            .with_context(|| format!("{}", args.input.display()))?;
        check_no_regions(args, &params.grouping)?;
        let (tin, _) = args.import.mesh(&args.input).load(out)?;
        if let Some(eye) = args.eye {
            super::culling_args::Eyes::given(eye).check_not_below_mesh(&tin, false)?;
        }
        Source::Mesh(tin)
    };
    // The panel starts from these values: refused as `build` refuses them, before the window opens (the panel
    // would clamp them, and a rebuild with them would fail only inside the window).
    params
        .validate()
        .context("the side panel's build parameters (from the command line and the hierarchy)")?;
    let title = format!(
        "tincull — {}",
        args.input
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    let safe = args.safe.params()?;
    no_display_is_an_error()?;
    let summary = viewer::app::run(ViewerOptions {
        title,
        source,
        params: RebuildParams {
            build: params,
            without_regions,
        },
        rebuild: None,
        // Exports go beside the input under another name (`NAME-view.tch`): never over the terrain shown.
        export_stem: args.input.with_file_name(format!(
            "{}-view",
            args.input.file_stem().map(|s| s.to_string_lossy()).unwrap_or_default()
        )),
        inputs: std::iter::once(args.input.clone())
            .chain(tin::dem::companion_files(&args.input))
            .collect(),
        eye: args.eye,
        screenshot: args.screenshot.as_ref().map(|path| ScreenshotRequest {
            path: path.clone(),
            after_frames: args.screenshot_after,
        }),
        window_size: [args.size[0] as f32, args.size[1] as f32],
        method: args.method,
        safe,
        startup: Startup {
            rebuild: args.rebuild,
            ground_truth: args.truth,
            pvs_cell_size: args.pvs_cell_size,
        },
    })?;
    if let Some(path) = &args.screenshot {
        match &summary.screenshot {
            Some(Ok(_)) => out.say(format!("wrote {}", path.display())),
            Some(Err(e)) => anyhow::bail!("cannot write the screenshot: {e}"),
            None => anyhow::bail!("{}: no screenshot was taken (the window closed first)", path.display()),
        }
    }
    if summary.rebuilds > 0 {
        out.say(format!(
            "built the hierarchy {}; the last has {}{}",
            count(summary.rebuilds as usize, "time"),
            count(summary.groups, "group"),
            if summary.regions { "" } else { ", without regions" }
        ));
    }
    if let Some((visible, false_culls)) = summary.truth {
        out.say(format!(
            "ground truth: {visible} visible triangles, {false_culls} false culls"
        ));
    }
    Ok(())
}

/// Refuses `--no-regions` where `build --no-regions` would ([`super::build_cmd::check_no_regions`]): with `grouping`
/// (the one the side panel starts with: given, or the hierarchy's) and the options given on the command line, not
/// the values read from a hierarchy.
fn check_no_regions(args: &ViewArgs, grouping: &pipeline::Grouping) -> Result<()> {
    if args.no_regions {
        let mut given = args.params.resolve(None)?;
        given.grouping = grouping.clone();
        super::build_cmd::check_no_regions(&given)?;
    }
    Ok(())
}

/// Without a display the window cannot open: said plainly (the windowing library's own error names its source file),
/// after every argument is checked.
fn no_display_is_an_error() -> Result<()> {
    #[cfg(all(unix, not(target_os = "macos")))]
    {
        let set = |name: &str| std::env::var_os(name).is_some_and(|v| !v.is_empty());
        anyhow::ensure!(
            set("DISPLAY") || set("WAYLAND_DISPLAY"),
            "no display to open the viewer's window on (neither DISPLAY nor WAYLAND_DISPLAY is set): run it in a \
             desktop session or under `xvfb-run`; `tincull render` draws pictures without a window"
        );
    }
    Ok(())
}
