//! `tincull view`: the interactive viewer on a hierarchy or a mesh, with the pipeline injected for rebuilds and the
//! grouped OBJ writer for exports.

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{Context, Result};
use clap::Args;
use viewer::app::{Progress, ScreenshotRequest, Source, ViewerOptions, ViewerParams};

use super::Output;
use super::build_cmd::ParamArgs;
use super::cull_cmd::parse_point;
use super::render_cmd::mesh_args;
use crate::export::write_grouped_obj;
use crate::pipeline::{BuildParams, build};

/// Arguments of `tincull view`.
#[derive(Debug, Args)]
pub struct ViewArgs {
    /// A hierarchy (.tch) or a terrain mesh (.obj).
    pub input: PathBuf,
    /// Initial viewpoint `x,y,z` in world coordinates (m) [default: the centre, 20 m above the ground].
    #[arg(long, value_parser = parse_point, allow_hyphen_values = true)]
    pub eye: Option<[f64; 3]>,
    /// Initial build parameters of the side panel (the hierarchy's own, when it records them).
    #[command(flatten)]
    pub params: ParamArgs,
    /// Write a screenshot of the window to this PNG after a few frames, then close.
    #[arg(long, value_name = "PNG")]
    pub screenshot: Option<PathBuf>,
    /// Frames drawn before the screenshot.
    #[arg(long, default_value_t = 10)]
    pub screenshot_after: u32,
    /// Window size `WIDTHxHEIGHT` in points.
    #[arg(long, default_value = "1280x800", value_parser = super::render_cmd::parse_size)]
    pub size: [u32; 2],
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

fn to_build_params(p: &ViewerParams, undersampling: Option<f64>) -> BuildParams {
    let mut b = BuildParams {
        sectors: p.sectors,
        subsectors: p.subsectors,
        undersampling,
        ..BuildParams::default()
    };
    b.crystal.seeds = p.seeds;
    b.crystal.orphan_passes = p.orphan_passes;
    b.crystal.min_group = p.min_group;
    b.crystal.max_expanse = p.max_expanse;
    b.crystal.rng_seed = p.rng_seed;
    b
}

/// Runs `tincull view`.
pub fn run(args: &ViewArgs, out: Output) -> Result<()> {
    let is_tch = args
        .input
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("tch"));
    let defaults = args.params.resolve(None)?;
    let mut params = ViewerParams {
        sectors: defaults.sectors,
        subsectors: defaults.subsectors,
        seeds: defaults.crystal.seeds,
        orphan_passes: defaults.crystal.orphan_passes,
        min_group: defaults.crystal.min_group,
        max_expanse: defaults.crystal.max_expanse,
        rng_seed: defaults.crystal.rng_seed,
    };
    let mut undersampling = defaults.undersampling;
    let source = if is_tch {
        let h = cull::Hierarchy::load(&args.input).with_context(|| format!("cannot load {}", args.input.display()))?;
        let b = &h.build;
        let p = &args.params;
        params.sectors = p.sectors.unwrap_or(h.sectors);
        if b.subsectors > 0 {
            params.subsectors = p.subsectors.unwrap_or(b.subsectors);
            params.seeds = p.seeds.or(Some(b.seeds as usize).filter(|&s| s > 0));
            params.orphan_passes = p.orphan_passes.unwrap_or(b.orphan_passes);
            params.min_group = p.min_group.unwrap_or(b.min_group as usize);
            params.max_expanse = p.max_expanse.unwrap_or(b.max_expanse);
            params.rng_seed = p.rng_seed.unwrap_or(b.rng_seed);
            undersampling = p.undersampling.or(b.undersampling);
        }
        Source::Hierarchy(h)
    } else {
        let (tin, _) = mesh_args(&args.input).load(out)?;
        Source::Mesh(tin)
    };
    let rebuild: viewer::app::RebuildFn = Arc::new(move |tin, p, progress: Progress| {
        let built = build(tin, &to_build_params(p, undersampling), Some(progress))?;
        Ok(built.hierarchy)
    });
    let export_obj: viewer::app::ExportObjFn = Arc::new(|h, path| Ok(write_grouped_obj(h, path)?));
    let title = format!(
        "tincull — {}",
        args.input
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    viewer::app::run(ViewerOptions {
        title,
        source,
        params,
        rebuild: Some(rebuild),
        export_obj: Some(export_obj),
        export_stem: args.input.with_extension(""),
        eye: args.eye,
        screenshot: args.screenshot.as_ref().map(|path| ScreenshotRequest {
            path: path.clone(),
            after_frames: args.screenshot_after,
        }),
        window_size: [args.size[0] as f32, args.size[1] as f32],
        startup: Default::default(),
    })?;
    if let Some(path) = &args.screenshot {
        out.say(format!("wrote {}", path.display()));
    }
    Ok(())
}
