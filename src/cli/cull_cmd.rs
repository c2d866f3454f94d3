//! `tincull cull`: the run-time culler on one or many viewpoints.

use super::output::count;
use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Args;
use cull::{AnyCuller, Camera, CullMethod, DrawList};
use serde_json::json;

use super::culling_args::{Eyes, SafeArgs};
use super::values::parse_point;
use super::{Output, OutputArgs};
use eval::evaluate::timed_cull;

/// Arguments of `tincull cull`.
#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("viewpoints").required(true).args(["eye", "eyes"])))]
pub struct CullArgs {
    /// The hierarchy file written by `tincull build`.
    pub hierarchy: PathBuf,
    /// Eye position `x,y,z` in world coordinates (m).
    #[arg(long, value_parser = parse_point, allow_hyphen_values = true)]
    pub eye: Option<[f64; 3]>,
    /// A file of viewpoints, one `x,y,z` per line (`#` starts a comment); prints one result per line (with `--json`,
    /// one JSON object per line: JSON Lines).
    #[arg(long)]
    pub eyes: Option<PathBuf>,
    /// Read each eye's z as a height above the terrain under its x,y (m) instead of a world z: `--eye x,y,2
    /// --above-ground` stands 2 m above the ground. An eye outside the terrain's footprint is an error.
    #[arg(long)]
    pub above_ground: bool,
    /// View direction in degrees, counter-clockwise from east (+x) [default: 0]; turns a --fov below 360 (refused
    /// at 360, where it changes nothing).
    #[arg(long, allow_hyphen_values = true)]
    pub yaw: Option<f64>,
    /// Horizontal field of view in degrees (360 = no frustum restriction).
    #[arg(long, default_value_t = 360.0)]
    pub fov: f64,
    /// Culling method: `safe` (never culls a visible triangle), `thesis` (the thesis' region test over a crystal
    /// hierarchy, not conservative), `stewart` (the same test over a quadtree hierarchy, Stewart 1997) or
    /// `lloyd-egbert` (Lloyd & Egbert 2002: cell edges as occluders, never culls a visible triangle; meant for a
    /// quadtree hierarchy).
    #[arg(long, default_value = "safe", value_parser = parse_method)]
    pub method: CullMethod,
    /// The horizon cullers' parameters.
    #[command(flatten)]
    pub safe: SafeArgs,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Parses a culling method name.
pub fn parse_method(s: &str) -> Result<CullMethod, String> {
    CullMethod::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = CullMethod::ALL.iter().map(|m| m.name()).collect();
        format!("unknown method {s:?}; expected one of {}", names.join(", "))
    })
}

/// Runs `tincull cull`.
pub fn run(args: &CullArgs, out: Output) -> Result<()> {
    out.require_a_result(false, "give --json")?;
    super::eval_cmd::check_fov(args.fov)?;
    let yaw = args.yaw.unwrap_or(0.0);
    if !yaw.is_finite() {
        bail!("--yaw must be finite, got {}", tin::compact_number(yaw));
    }
    if args.yaw.is_some() && args.fov == 360.0 {
        bail!("--yaw turns the field of view, and at --fov 360 (the default) there is none to turn: give --fov too");
    }
    args.safe.check_method(args.method)?;
    let h = super::mesh_input::load_hierarchy(&args.hierarchy)?;
    args.method
        .check(&h)
        .with_context(|| format!("{}: cannot cull with `{}`", args.hierarchy.display(), args.method))?;
    super::culling_args::warn_if_no_regions(&args.hierarchy, &h, args.method, out);
    let params = args.safe.params()?;
    let culler = AnyCuller::with_params(&h, args.method, params);
    let mut eyes = match (&args.eye, &args.eyes) {
        (Some(e), _) => Eyes::given(*e),
        (None, Some(path)) => Eyes::read(path)?,
        (None, None) => bail!("give --eye x,y,z or --eyes FILE"),
    };
    if args.above_ground {
        eyes.lift_above_ground(&h)?;
    } else {
        eyes.check_not_below_ground(&h, true)?;
    }
    let mut list = DrawList::default();
    for eye in eyes.points {
        let camera = Camera::from_degrees(eye, yaw, args.fov)?;
        let ns = timed_cull(&culler, &camera, &mut list);
        let s = list.stats;
        if out.json {
            out.json(&json!({
                "eye": eye,
                "method": args.method.name(),
                "ranges": list.ranges,
                "triangles_drawn": s.triangles_drawn,
                "triangles_culled": s.triangles_culled,
                "nodes_tested": s.nodes_tested,
                "nodes_skipped": s.nodes_skipped,
                "culled_by_occlusion": s.culled_by_occlusion,
                "culled_by_frustum": s.culled_by_frustum,
                "work": s.work,
                "occluder_edges": s.occluder_edges,
                "cull_ns": ns,
            }))?;
        } else {
            // The safe culler's work units against its budget: a user tuning --work-budget sees when it binds.
            let work = if args.method == CullMethod::Safe {
                let spent = if s.work as usize >= params.work_budget {
                    " (the budget: spent)"
                } else {
                    ""
                };
                format!(
                    "; {} work units of {}{spent}, {} written",
                    s.work,
                    params.work_budget,
                    count(s.occluder_edges as usize, "occluder edge")
                )
            } else {
                String::new()
            };
            out.say(format!(
                "eye {}: draw {} of {} in {}; {} tested, of which {} hidden and {} outside the view (culled \
                 with their descendants){work}; {:.2} µs",
                super::output::point(eye),
                s.triangles_drawn,
                count((s.triangles_drawn + s.triangles_culled) as usize, "triangle"),
                count(list.ranges.len(), "range"),
                count(s.nodes_tested as usize, "node"),
                s.culled_by_occlusion,
                s.culled_by_frustum,
                ns as f64 / 1000.0
            ));
        }
    }
    Ok(())
}
