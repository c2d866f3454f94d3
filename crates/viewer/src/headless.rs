//! Headless renders of a terrain or hierarchy, without a window: the map, the orbit overview with the culling of a
//! viewpoint, and the eye view with its culled-versus-unculled comparison.
//!
//! The comparison renders the same view twice, once with the culler's ranges and once with every triangle, and
//! compares the images pixel by pixel. A triangle that the culler skipped but that covers a pixel in the full
//! render makes the images differ there, so every differing pixel is a false cull seen on screen. The culler runs
//! all around (360°) by default, so that only occlusion culling is judged; a narrower culling field of view also
//! culls by the frustum, whose horizontal test ignores pitch, and may then show frustum misses as well.

use glam::Vec3;

use cull::{AnyCuller, Camera, CullMethod, CullStats};

use crate::camera::{EyeCamera, MapView, Orbit};
use crate::error::{Result, ViewerError};
use crate::gpu::Gpu;
use crate::render::{DrawItem, DrawStyle, Frame, FrameStats, Marker, Renderer, RgbaImage};
use crate::scene::{ColourMode, GpuScene, Terrain};

/// Which view to render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewKind {
    /// Top-down orthographic map of the whole terrain.
    Map,
    /// Oblique perspective overview; with an eye, its marker, drawn groups solid and culled ones as wireframe.
    Orbit,
    /// What a camera at the eye sees.
    Eye,
}

impl std::str::FromStr for ViewKind {
    type Err = ViewerError;

    fn from_str(s: &str) -> Result<ViewKind> {
        match s {
            "map" => Ok(ViewKind::Map),
            "orbit" => Ok(ViewKind::Orbit),
            "eye" => Ok(ViewKind::Eye),
            _ => Err(ViewerError::Invalid(format!(
                "unknown view {s:?}: expected map, orbit or eye"
            ))),
        }
    }
}

/// Everything a headless render needs besides the terrain.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// The view.
    pub view: ViewKind,
    /// Viewpoint in world coordinates (required for `eye`, optional for `orbit`).
    pub eye: Option<[f64; 3]>,
    /// View azimuth in degrees, counter-clockwise from east (eye: default 0; orbit: default 45).
    pub yaw_deg: Option<f64>,
    /// View pitch in degrees up from the horizontal (eye: default 0; orbit: default −35).
    pub pitch_deg: Option<f64>,
    /// Horizontal field of view of the eye view, degrees (drawn at most 150°).
    pub fov_deg: f64,
    /// Horizontal field of view the culler uses, degrees; 360 culls by occlusion only.
    pub cull_fov_deg: f64,
    /// Image size in pixels.
    pub size: [u32; 2],
    /// Colouring; `None` picks groups for a hierarchy and height for a plain mesh.
    pub colour: Option<ColourMode>,
    /// Level of [`ColourMode::Level`]; `None` is the top level.
    pub level: Option<u32>,
    /// Eye view only: also render without culling and compare.
    pub compare: bool,
    /// Repetitions of each timed render when comparing (the median is reported).
    pub timing_runs: u32,
    /// The culling method (default: the safe culler).
    pub method: CullMethod,
    /// The safe culler's run-time parameters (also `--columns` of `lloyd-egbert`).
    pub safe: cull::SafeParams,
    /// A viewcell's PVS as a per-triangle mask (hierarchy order; crate `pvs`): it replaces the viewpoint's culling
    /// (nothing is culled for `eye`): `ColourMode::Visibility` paints what it excludes as culled, and the eye view
    /// draws only its triangles.
    pub pvs: Option<Vec<bool>>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            view: ViewKind::Map,
            eye: None,
            yaw_deg: None,
            pitch_deg: None,
            fov_deg: 90.0,
            cull_fov_deg: 360.0,
            size: [1024, 768],
            colour: None,
            level: None,
            compare: false,
            timing_runs: 5,
            method: CullMethod::Safe,
            safe: cull::SafeParams::default(),
            pvs: None,
        }
    }
}

/// The culled-versus-unculled comparison of an eye view.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    /// The view drawn with every triangle.
    pub unculled: RgbaImage,
    /// Differing pixels red, the rest a dimmed grey copy of the culled view.
    pub difference: RgbaImage,
    /// Pixels that differ: false culls on screen.
    pub differing_pixels: u64,
    /// Median frame time with culling (ms), including the cull itself.
    pub ms_culled: f64,
    /// Median frame time drawing everything (ms).
    pub ms_unculled: f64,
    /// Median time of the cull alone (µs).
    pub cull_us: f64,
    /// Stats of one culled frame.
    pub culled_frame: FrameStats,
    /// Stats of one unculled frame.
    pub unculled_frame: FrameStats,
}

/// The result of [`render`].
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOutput {
    /// The rendered view.
    pub image: RgbaImage,
    /// Stats of the render.
    pub frame: FrameStats,
    /// The culler's counters, when a viewpoint was culled.
    pub cull: Option<CullStats>,
    /// The culler's draw ranges, when a viewpoint was culled.
    pub ranges: Option<Vec<[u32; 2]>>,
    /// The comparison, when asked for.
    pub compare: Option<Comparison>,
}

/// Checks options against the terrain, naming the offending option ([`render`] does this too; call it first to
/// reject bad options before opening a GPU device).
pub fn validate(terrain: &Terrain, o: &RenderOptions) -> Result<()> {
    let bad = |m: String| Err(ViewerError::Invalid(m));
    if !(o.fov_deg > 0.0 && o.fov_deg <= 360.0) {
        return bad(format!(
            "--fov must be in (0, 360], got {}",
            tin::compact_number(o.fov_deg)
        ));
    }
    if !(o.cull_fov_deg > 0.0 && o.cull_fov_deg <= 360.0) {
        return bad(format!(
            "--cull-fov must be in (0, 360], got {}",
            tin::compact_number(o.cull_fov_deg)
        ));
    }
    for (name, v) in [("--yaw", o.yaw_deg), ("--pitch", o.pitch_deg)] {
        if v.is_some_and(|v| !v.is_finite()) {
            return bad(format!("{name} must be finite"));
        }
    }
    if let Some(p) = o.pitch_deg
        && p.abs() >= 89.0
    {
        return bad(format!(
            "--pitch must be between -89° and 89° (exclusive: the camera never looks straight up or down), got {}",
            tin::compact_number(p)
        ));
    }
    if let (Some(level), Some(h)) = (o.level, &terrain.hierarchy) {
        let top = h.nodes.iter().map(|n| n.level).max().unwrap_or(0);
        if level > top {
            return bad(format!("--level {level}: the hierarchy's levels are 0 to {top}"));
        }
    }
    if let Some(h) = &terrain.hierarchy {
        // The region methods refuse the other grouping, as `cull` does.
        o.method.check(h).map_err(|e| ViewerError::Invalid(e.to_string()))?;
    }
    if o.level.is_some() && terrain.hierarchy.is_none() {
        return bad("--level needs a hierarchy (.tch), not a plain mesh".into());
    }
    if o.eye.is_some_and(|e| !e.iter().all(|c| c.is_finite())) {
        return bad("--eye must be finite".into());
    }
    if let Some(m) = &o.pvs
        && m.len() != terrain.num_triangles()
    {
        return bad(format!(
            "the PVS mask has {} entries for {} triangles",
            m.len(),
            terrain.num_triangles()
        ));
    }
    if o.view == ViewKind::Eye && o.eye.is_none() {
        return bad("--view eye needs --eye x,y,z".into());
    }
    if o.compare && o.view != ViewKind::Eye {
        return bad("--compare works with --view eye".into());
    }
    let culls = o.eye.is_some() && o.view != ViewKind::Map || o.colour == Some(ColourMode::Visibility);
    if culls && terrain.hierarchy.is_none() && (o.compare || o.view == ViewKind::Orbit) {
        return bad("culling a viewpoint needs a hierarchy (.tch), not a plain mesh".into());
    }
    Ok(())
}

/// Renders `terrain` as `options` say.
pub fn render(gpu: &Gpu, terrain: &Terrain, options: &RenderOptions) -> Result<RenderOutput> {
    validate(terrain, options)?;
    let [width, height] = options.size;
    let aspect = width as f32 / height.max(1) as f32;
    let n = terrain.num_triangles() as u32;

    // Cull for the viewpoint when there is one and a hierarchy to cull with (a PVS replaces it: see `pvs`).
    let culled = match (&terrain.hierarchy, options.eye) {
        (Some(h), Some(eye))
            if options.pvs.is_none()
                && (options.view != ViewKind::Map || options.colour == Some(ColourMode::Visibility)) =>
        {
            let culler = AnyCuller::with_params(h, options.method, options.safe);
            let camera = culling_camera(eye, options)?;
            Some((culler.cull(&camera), culler, camera))
        }
        _ => None,
    };
    let mode = options.colour.unwrap_or(if terrain.hierarchy.is_some() {
        ColourMode::Groups
    } else {
        ColourMode::Height
    });
    let mask = match &options.pvs {
        Some(m) => Some(m.clone()),
        None => culled.as_ref().map(|(list, _, _)| list.mask(n as usize)),
    };
    if mode == ColourMode::Visibility && mask.is_none() {
        return Err(ViewerError::Invalid(
            "--colour visibility needs --eye and a hierarchy".into(),
        ));
    }
    let colours = terrain.colours(mode, options.level, mask.as_deref())?;
    let scene = GpuScene::new(gpu, terrain, &colours)?;
    let mut renderer = Renderer::new(gpu, width, height)?;
    let all = [DrawItem {
        range: [0, n],
        style: DrawStyle::Solid,
    }];
    let marker = options.eye.map(|e| {
        let p = Vec3::from(terrain.to_local(e));
        let extent = Vec3::from(terrain.max) - Vec3::from(terrain.min);
        let diagonal = extent.truncate().length();
        Marker {
            position: p,
            size: diagonal * 0.012,
            height: diagonal * 0.07,
        }
    });
    let (view_proj, items, marker) = match options.view {
        ViewKind::Map => {
            let mut map = MapView::fit(terrain.min, terrain.max, aspect);
            // The camera above the pin's head, which stands high over the terrain (it was clipped away).
            if let Some(m) = &marker {
                map.z_range[1] = map.z_range[1].max(m.position.z + m.height + m.size);
            }
            (map.view_proj(), all.to_vec(), marker)
        }
        ViewKind::Orbit => {
            let orbit = Orbit::overview(
                terrain.min,
                terrain.max,
                aspect,
                options.yaw_deg.map(|d| (d as f32).to_radians()),
                options.pitch_deg.map(|d| (d as f32).to_radians()),
            );
            let items = match (&culled, mode) {
                (Some((list, _, _)), m) if m != ColourMode::Visibility => split_items(&list.ranges, n),
                _ => all.to_vec(),
            };
            (orbit.view_proj(aspect), items, marker)
        }
        ViewKind::Eye => {
            let eye = eye_camera(terrain, options);
            let items = match (&culled, &options.pvs) {
                (Some((list, _, _)), _) => solid(&list.ranges),
                // The eye view of a PVS draws its triangles only.
                (None, Some(pvs)) => solid(&mask_ranges(pvs)),
                (None, None) => all.to_vec(),
            };
            (eye.view_proj(aspect), items, None)
        }
    };
    let frame = Frame {
        scene: &scene,
        view_proj,
        items: &items,
        marker,
        count_primitives: true,
    };
    let stats = renderer.render(gpu, &frame)?;
    let image = renderer.read_image(gpu)?;
    let compare = if options.compare {
        let (list, culler, camera) = culled
            .as_ref()
            .ok_or_else(|| ViewerError::Invalid("--compare needs --eye and a hierarchy".into()))?;
        let full = Frame { items: &all, ..frame };
        let unculled_frame = renderer.render(gpu, &full)?;
        let unculled = renderer.read_image(gpu)?;
        let (difference, differing_pixels) = image
            .difference(&unculled)
            .ok_or_else(|| ViewerError::Gpu("the two renders differ in size".into()))?;
        let runs = options.timing_runs.max(1);
        let mut list2 = list.clone();
        let mut cull_times = Vec::new();
        let mut culled_times = Vec::new();
        let mut unculled_times = Vec::new();
        for _ in 0..runs {
            let start = std::time::Instant::now();
            culler.cull_into(camera, &mut list2);
            let cull_ms = start.elapsed().as_secs_f64() * 1e3;
            cull_times.push(cull_ms * 1e3);
            let items = solid(&list2.ranges);
            let f = Frame {
                items: &items,
                count_primitives: false,
                ..frame
            };
            culled_times.push(cull_ms + renderer.render(gpu, &f)?.ms);
            let f = Frame {
                items: &all,
                count_primitives: false,
                ..frame
            };
            unculled_times.push(renderer.render(gpu, &f)?.ms);
        }
        Some(Comparison {
            unculled,
            difference,
            differing_pixels,
            ms_culled: median(&mut culled_times),
            ms_unculled: median(&mut unculled_times),
            cull_us: median(&mut cull_times),
            culled_frame: stats,
            unculled_frame,
        })
    } else {
        None
    };
    Ok(RenderOutput {
        image,
        frame: stats,
        cull: culled.as_ref().map(|(l, _, _)| l.stats),
        ranges: culled.map(|(l, _, _)| l.ranges),
        compare,
    })
}

/// The culler's camera for the options: at the eye, looking along yaw, with the culling field of view.
pub fn culling_camera(eye: [f64; 3], options: &RenderOptions) -> Result<Camera> {
    Camera::from_degrees(eye, options.yaw_deg.unwrap_or(0.0), options.cull_fov_deg)
        .map_err(|e| ViewerError::Invalid(format!("cannot cull from there: {e}")))
}

fn eye_camera(terrain: &Terrain, options: &RenderOptions) -> EyeCamera {
    let eye = options.eye.unwrap_or([0.0; 3]);
    EyeCamera {
        position: Vec3::from(terrain.to_local(eye)),
        yaw: (options.yaw_deg.unwrap_or(0.0) as f32).to_radians(),
        pitch: (options.pitch_deg.unwrap_or(0.0) as f32).to_radians(),
        hfov: (options.fov_deg as f32).to_radians(),
    }
}

/// Solid draws of `ranges`.
pub fn solid(ranges: &[[u32; 2]]) -> Vec<DrawItem> {
    ranges
        .iter()
        .map(|&range| DrawItem {
            range,
            style: DrawStyle::Solid,
        })
        .collect()
}

/// `ranges` solid and their complement in `[0, n)` as wireframe.
pub fn split_items(ranges: &[[u32; 2]], n: u32) -> Vec<DrawItem> {
    let mut items = solid(ranges);
    let mut at = 0;
    for &[s, e] in ranges {
        if s > at {
            items.push(DrawItem {
                range: [at, s],
                style: DrawStyle::Wire,
            });
        }
        at = at.max(e);
    }
    if at < n {
        items.push(DrawItem {
            range: [at, n],
            style: DrawStyle::Wire,
        });
    }
    items
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The runs of `true` in `mask` as triangle ranges.
fn mask_ranges(mask: &[bool]) -> Vec<[u32; 2]> {
    let mut ranges: Vec<[u32; 2]> = Vec::new();
    for (t, _) in mask.iter().enumerate().filter(|(_, m)| **m) {
        let t = t as u32;
        match ranges.last_mut() {
            Some(r) if r[1] == t => r[1] = t + 1,
            _ => ranges.push([t, t + 1]),
        }
    }
    ranges
}
