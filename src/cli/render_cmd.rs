//! `tincull render`: headless renders of a hierarchy or a mesh to PNG (map, orbit overview with a viewpoint's
//! culling, or the eye view with a culled-versus-unculled comparison).

use super::output::count;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use serde_json::json;
use viewer::{ColourMode, Gpu, RenderOptions, Terrain, ViewKind};

use super::files::Outputs;
use super::mesh_input::ImportArgs;
use super::values::parse_point;
use super::values::{parse_pair, parse_rect};
use super::{Output, OutputArgs};

/// Arguments of `tincull render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// A hierarchy (.tch), or a terrain mesh (.obj) or DEM grid (.npy, .asc, .hgt, .png, .tif/.tiff) simplified to
    /// --dem-vertices (both coloured by height, no culling).
    pub input: PathBuf,
    /// Culling method for a viewpoint: `safe` or `lloyd-egbert` (never cull a visible triangle), `thesis` or
    /// `stewart` (not conservative) [default: safe]. Refused, as the other culler flags are, by a render that culls
    /// nothing.
    #[arg(long, value_parser = super::cull_cmd::parse_method)]
    pub method: Option<cull::CullMethod>,
    /// The horizon cullers' parameters (`safe`, `lloyd-egbert`).
    #[command(flatten)]
    pub safe: super::culling_args::SafeArgs,
    /// The PNG to write.
    #[arg(short, long, value_name = "FILE")]
    pub out: PathBuf,
    /// The view: map (top-down), orbit (oblique overview) or eye (what a camera at --eye sees).
    #[arg(long, default_value = "map", value_parser = ["map", "orbit", "eye"])]
    pub view: String,
    /// Viewpoint `x,y,z` in world coordinates (m): the camera of the eye view, the culled viewpoint of the orbit.
    #[arg(long, value_parser = parse_point, allow_hyphen_values = true)]
    pub eye: Option<[f64; 3]>,
    /// How to import a mesh input.
    #[command(flatten)]
    pub import: ImportArgs,
    /// View direction in degrees, counter-clockwise from east [eye: 0, orbit: 45].
    #[arg(long, allow_hyphen_values = true)]
    pub yaw: Option<f64>,
    /// Pitch in degrees up from the horizontal, between -89 and 89 exclusive [eye: 0, orbit: -35].
    #[arg(long, allow_hyphen_values = true)]
    pub pitch: Option<f64>,
    /// Horizontal field of view of the eye view in degrees (drawn at most 150) [default: 90].
    #[arg(long)]
    pub fov: Option<f64>,
    /// Horizontal field of view the culler uses, in degrees (360 = occlusion only), turned by --yaw [default: 360].
    #[arg(long)]
    pub cull_fov: Option<f64>,
    /// Image size `WIDTHxHEIGHT` in pixels, each 1 to 8192.
    #[arg(long, default_value = "1024x768", value_parser = parse_size)]
    pub size: [u32; 2],
    /// Colouring: groups, level, visibility (drawn / culled for --eye) or height [default: groups for a hierarchy,
    /// height for a mesh].
    #[arg(long, value_parser = ["groups", "level", "visibility", "height"])]
    pub colour: Option<String>,
    /// Hierarchy level for `--colour level` [default: the top].
    #[arg(long)]
    pub level: Option<u32>,
    /// Eye view: also render without culling, write the difference image (IMG-diff.png) and count differing
    /// pixels (false culls on screen) and frame times.
    #[arg(long)]
    pub compare: bool,
    /// Paint a viewcell's PVS (`tincull pvs`, method `both`): `x0,y0,x1,y1`; the triangles it excludes are painted
    /// as culled (colour `visibility`), and the eye marker stands over the cell's centre unless --eye is given.
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = parse_rect, allow_hyphen_values = true)]
    pub pvs_cell: Option<[f64; 4]>,
    /// With --pvs-cell: the cell's absolute height band `z0,z1` (m).
    #[arg(long, value_name = "Z0,Z1", value_parser = parse_pair, allow_hyphen_values = true,
          requires = "pvs_cell", conflicts_with = "above_ground")]
    pub height_band: Option<[f64; 2]>,
    /// With --pvs-cell: the cell's band above the ground `h0,h1` (m) [default: 0,2].
    #[arg(long, value_name = "H0,H1", value_parser = parse_pair, allow_hyphen_values = true, requires = "pvs_cell")]
    pub above_ground: Option<[f64; 2]>,
    /// With --pvs-cell: resolution R of the PVS's R × R ray-space bitmap, 1 to 256.
    #[arg(long, default_value_t = 64, value_name = "R", requires = "pvs_cell",
          value_parser = clap::value_parser!(u32).range(1..=i64::from(pvs::MAX_RESOLUTION)))]
    pub resolution: u32,
    /// With --compare: timed repetitions of each frame (the median is reported).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..), requires = "compare")]
    pub runs: u32,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Parses `WIDTHxHEIGHT`.
pub fn parse_size(s: &str) -> Result<[u32; 2], String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, got {s:?}"))?;
    let parse = |t: &str| {
        t.trim()
            .parse::<u32>()
            .ok()
            .filter(|&v| (1..=8192).contains(&v))
            .ok_or_else(|| format!("{t:?} is not a size in 1..=8192"))
    };
    Ok([parse(w)?, parse(h)?])
}

/// Loads a `.tch` hierarchy or an OBJ mesh as a [`Terrain`], refusing an `eye` below its ground.
pub fn load_terrain(path: &Path, import: &ImportArgs, eye: Option<[f64; 3]>, out: Output) -> Result<Terrain> {
    let eyes = eye.map(super::culling_args::Eyes::given);
    if super::mesh_input::is_hierarchy(path) {
        import.mesh(path).refuse_for_hierarchy()?;
        let h = super::mesh_input::load_hierarchy(path)?;
        if let Some(e) = &eyes {
            e.check_not_below_ground(&h, false)?;
        }
        Ok(Terrain::from_hierarchy(h)?)
    } else {
        let (tin, _) = import.mesh(path).load(out)?;
        if let Some(e) = &eyes {
            e.check_not_below_mesh(&tin, false)?;
        }
        Ok(Terrain::from_tin(&tin)?)
    }
}

/// The difference image's path: `IMG-diff.png` beside `IMG.png`.
pub fn diff_path(out: &Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    out.with_file_name(format!("{stem}-diff.png"))
}

/// Runs `tincull render`.
pub fn run(args: &RenderArgs, out: Output) -> Result<()> {
    let view: ViewKind = args.view.parse()?;
    let colour: Option<ColourMode> = args.colour.as_deref().map(str::parse).transpose()?;
    if args.compare && view != ViewKind::Eye {
        bail!("--compare works with --view eye");
    }
    // The outputs are checked before the terrain is read and its PVS computed.
    let mut files = Outputs::new();
    files.input(&args.input)?;
    files.check(&args.out)?;
    super::files::require_png(&args.out, "render")?;
    if args.compare {
        files.check(&diff_path(&args.out))?;
    }
    let terrain = load_terrain(&args.input, &args.import, args.eye, out)?;
    // Every flag is checked before the PVS is computed (seconds, or minutes on a large hierarchy).
    let with_pvs = args.pvs_cell.is_some();
    let colour = if with_pvs {
        // The PVS is painted with the visibility colours (the eye view also draws only its triangles).
        if colour.is_some_and(|c| c != ColourMode::Visibility) {
            bail!(
                "--colour {}: --pvs-cell paints what the cell's PVS excludes with --colour visibility",
                args.colour.as_deref().unwrap_or_default()
            );
        }
        Some(ColourMode::Visibility)
    } else {
        colour
    };
    // Checked first with a stand-in for the eye that a PVS's cell gives (its height is known once it is computed).
    let mut options = RenderOptions {
        view,
        eye: args.eye.or(args.pvs_cell.map(|_| [0.0; 3])),
        yaw_deg: args.yaw,
        pitch_deg: args.pitch,
        fov_deg: args.fov.unwrap_or(90.0),
        cull_fov_deg: args.cull_fov.unwrap_or(360.0),
        size: args.size,
        colour,
        level: args.level,
        compare: args.compare,
        timing_runs: args.runs,
        method: args.method.unwrap_or(cull::CullMethod::Safe),
        safe: args.safe.params()?,
        pvs: None,
    };
    viewer::validate(&terrain, &options)?;
    // A culling parameter that this render does not use is an error, as for `cull`, rather than ignored.
    // A PVS replaces the culling of a viewpoint.
    let culls = !with_pvs
        && terrain.hierarchy.is_some()
        && (args.eye.is_some() && view != ViewKind::Map || colour == Some(ColourMode::Visibility));
    // So is a view flag that changes nothing in this image.
    let view_name = &args.view;
    let unused = [
        (
            args.pitch.is_some() && view == ViewKind::Map,
            "--pitch: the map view looks straight down; --pitch tilts the orbit and eye cameras",
        ),
        (
            args.yaw.is_some() && view == ViewKind::Map && !(culls && args.cull_fov.is_some()),
            "--yaw: the map view looks straight down; --yaw turns the orbit and eye cameras (and the culler's field \
             of view, --cull-fov)",
        ),
        (
            args.fov.is_some() && view != ViewKind::Eye,
            "--fov is the eye view's field of view, and this render is not one (--view eye); the culler's is \
             --cull-fov",
        ),
        (
            args.level.is_some() && colour != Some(ColourMode::Level),
            "--level is the level that --colour level paints",
        ),
    ];
    if let Some((_, why)) = unused.iter().find(|(given, _)| *given) {
        bail!("{why} (this render: --view {view_name})");
    }
    // A perspective picture is drawn at most `MAX_RENDER_HFOV_DEG` wide: a wider --fov is drawn at that, and said.
    let widest = f64::from(viewer::camera::MAX_RENDER_HFOV_DEG);
    if let Some(fov) = args.fov.filter(|&f| f > widest) {
        out.warn(format!(
            "--fov {}: an eye picture is drawn at most {} degrees wide; this one is drawn at {}",
            tin::compact_number(fov),
            tin::compact_number(widest),
            tin::compact_number(widest)
        ));
    }
    if culls {
        args.safe.check_method(options.method)?;
        if let Some(h) = &terrain.hierarchy {
            super::culling_args::warn_if_no_regions(&args.input, h, options.method, out);
        }
        // `--cull-fov` is the culler's field as given; an eye picture that reaches further round (pitched, its
        // corners do) loses terrain at its edges: said, not changed (a narrow field may be what is being looked at).
        if let (Some(field), ViewKind::Eye) = (args.cull_fov, view) {
            let [w, h] = args.size;
            let needed = viewer::camera::culling_hfov_deg(
                options.fov_deg,
                args.pitch.unwrap_or(0.0),
                f64::from(w) / f64::from(h),
            );
            if field < needed {
                let reach = tin::compact_number((needed * 10.0).ceil() / 10.0);
                out.warn(format!(
                    "--cull-fov {}: this picture (--fov {}, --pitch {}, {w}x{h}) reaches {reach} degrees of azimuth \
                     round the yaw; the culler hides terrain at its edges (--cull-fov {reach} or more culls nothing it \
                     shows)",
                    tin::compact_number(field),
                    tin::compact_number(options.fov_deg),
                    tin::compact_number(args.pitch.unwrap_or(0.0)),
                ));
            }
        }
    } else if args.cull_fov.is_some() {
        bail!(
            "--cull-fov: this render culls nothing (culling needs a hierarchy, and --eye with --view eye or orbit, or \
             --colour visibility)"
        );
    } else {
        let method = args.method.map(|m| format!("--method {}", m.name()));
        if let Some(flag) = method.or_else(|| args.safe.first_given()) {
            if with_pvs {
                bail!("{flag}: with --pvs-cell the render shows the cell's PVS, and culls nothing from a point");
            }
            bail!(
                "{flag}: this render culls nothing (culling needs a hierarchy, and --eye with --view eye or orbit, or \
                 --colour visibility)"
            );
        }
    }
    let (pvs_mask, pvs_eye, pvs_json) = match args.pvs_cell {
        Some(rect) => {
            let h = terrain
                .hierarchy
                .as_ref()
                .context("--pvs-cell needs a hierarchy (.tch), not a plain mesh")?;
            let height = match (args.height_band, args.above_ground) {
                (Some(z), _) => pvs::Height::Band(z),
                (None, Some(a)) => pvs::Height::AboveGround(a),
                (None, None) => pvs::Height::AboveGround([0.0, 2.0]),
            };
            let params = pvs::PvsParams {
                method: pvs::Method::Both,
                resolution: args.resolution,
                patch: pvs::PvsParams::default().patch,
            };
            let cell = pvs::ViewCell { rect, height };
            let pvs = pvs::Pvs::new(h, params)?;
            pvs.check_over_terrain(&cell).context("--pvs-cell")?;
            let result = pvs.compute(&cell).with_context(|| format!("--pvs-cell {rect:?}"))?;
            out.say(format!(
                "PVS of cell {rect:?}: {} of {} triangles ({:.3} s)",
                result.triangles(),
                h.num_triangles(),
                result.seconds
            ));
            let centre = [0.5 * (rect[0] + rect[2]), 0.5 * (rect[1] + rect[3]), result.ztop];
            let summary = json!({ "cell": rect, "pvs_triangles": result.triangles(), "seconds": result.seconds });
            (Some(result.mask(h.num_triangles())), Some(centre), Some(summary))
        }
        None => (None, None, None),
    };
    // The PVS's cell gives the eye when --eye does not.
    options.eye = args.eye.or(pvs_eye);
    options.pvs = pvs_mask;
    viewer::validate(&terrain, &options)?;
    let gpu = Gpu::headless()?;
    let result = viewer::render(&gpu, &terrain, &options)?;
    let png = |image: &viewer::RgbaImage| {
        viewer::png_out::encode_png(image).map_err(|e| anyhow::anyhow!("{}: {e}", args.out.display()))
    };
    files.add_bytes(&args.out, &png(&result.image)?)?;
    if let Some(c) = &result.compare {
        files.add_bytes(&diff_path(&args.out), &png(&c.difference)?)?;
    }
    files.commit()?;
    out.say(format!(
        "wrote {} ({}x{}, {} of {}, on {})",
        args.out.display(),
        result.image.width,
        result.image.height,
        count(result.frame.draws as usize, "draw"),
        count(result.frame.triangles as usize, "triangle"),
        gpu.describe()
    ));
    if let Some(s) = &result.cull {
        out.say(format!(
            "culled for eye {}: draw {} of {}; {} tested, {} culled by occlusion, {} by frustum",
            super::output::point(options.eye.unwrap_or_default()),
            s.triangles_drawn,
            count((s.triangles_drawn + s.triangles_culled) as usize, "triangle"),
            count(s.nodes_tested as usize, "node"),
            s.culled_by_occlusion,
            s.culled_by_frustum
        ));
    }
    let mut j = json!({
        "output": args.out,
        "width": result.image.width,
        "height": result.image.height,
        "view": args.view,
        "adapter": gpu.describe(),
        "draws": result.frame.draws,
        "triangles_submitted": result.frame.triangles,
        "gpu_primitives": result.frame.gpu_primitives,
        "cull": result.cull,
    });
    if let Some(p) = pvs_json {
        // What the image paints: the cell's PVS (the `cull` counters are the culling eye's).
        j["pvs"] = p;
    }
    if let Some(c) = &result.compare {
        let diff = diff_path(&args.out);
        out.say(format!(
            "{} differing pixels (false culls on screen); wrote {}",
            c.differing_pixels,
            diff.display()
        ));
        out.say(format!(
            "frame {:.2} ms culled (cull {:.1} µs) vs {:.2} ms everything ({} vs {} triangles)",
            c.ms_culled, c.cull_us, c.ms_unculled, c.culled_frame.triangles, c.unculled_frame.triangles
        ));
        j["differing_pixels"] = json!(c.differing_pixels);
        j["difference_image"] = json!(diff);
        j["frame_ms_culled"] = json!(c.ms_culled);
        j["frame_ms_unculled"] = json!(c.ms_unculled);
        j["cull_us"] = json!(c.cull_us);
        j["triangles_unculled"] = json!(c.unculled_frame.triangles);
    }
    out.json(&j)
}
