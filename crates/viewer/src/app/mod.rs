//! The interactive viewer (eframe + egui on wgpu): the terrain drawn with the culler's ranges from a viewpoint, in a
//! first-person (eye) or orbit view, with the groups, orphans and culled groups on screen, live culling statistics,
//! ground truth on demand, exports, and a rebuild with new parameters in a background thread. A toggle shows the
//! viewcell around the eye on the map and paints what its PVS (crate `pvs`) excludes.
//!
//! The 3-D view is rendered by [`crate::render::Renderer`] into its own texture (depth-tested, reversed Z) on the
//! window's wgpu device and shown with egui's `register_native_texture`. Rebuilds run the `pipeline` crate
//! ([`pipeline::build`], or [`pipeline::build_without_regions`] for a quadtree without regions; a test may pass a
//! stand-in, [`RebuildFn`]); the exports use `cull` (`.tch`) and [`pipeline::export`] (JSON, grouped OBJ).
//!
//! Controls: drag in the view to look around (eye) or rotate (orbit); W/S/A/D move the viewpoint, R/F raise and
//! lower it; the scroll wheel zooms the orbit or moves the eye forward; click on the map to place the viewpoint.
//! The field of view (up to 360°) is the culler's; the eye view draws at most 150° of it.

use std::path::PathBuf;
use std::sync::mpsc::{Receiver, channel};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use cull::{AnyCuller, Camera, CullMethod, CullStats, DrawList, Hierarchy};
use eframe::egui;
use eframe::egui_wgpu;
use glam::{DVec2, DVec3, Vec3};
use tin::Tin;
use truth::Locator;

mod jobs;
mod panel;

use jobs::{RebuildJob, Truth, TruthJob};

use crate::camera::{EyeCamera, MAX_RENDER_HFOV_DEG, MapView, Orbit, culling_hfov_deg};
use crate::error::{Result, ViewerError};
use crate::gpu::Gpu;
use crate::headless::split_items;
use crate::render::{DrawItem, DrawStyle, Frame, Marker, Renderer, RgbaImage};
use crate::scene::{ColourMode, GpuScene, Terrain, paint_false_culls};

pub use pipeline::BuildParams;

/// Errors of a [`RebuildFn`].
pub type DynError = Box<dyn std::error::Error + Send + Sync>;
/// Progress of a rebuild: `(stage, done, total)`.
pub type Progress = pipeline::BuildProgress;
/// Builds a hierarchy for a terrain with the given parameters, reporting progress: [`pipeline_rebuild`] or a
/// stand-in (tests use a slow fake to check that the window stays responsive).
pub type RebuildFn =
    Arc<dyn Fn(&Tin, &RebuildParams, Progress) -> std::result::Result<Hierarchy, DynError> + Send + Sync>;

/// What the side panel's Rebuild builds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RebuildParams {
    /// The pipeline's parameters: grouping, sectors, subsectors and the crystal grouping's.
    pub build: BuildParams,
    /// Whether to build without horizons and regions (`tincull build --no-regions`): only a quadtree can be built so
    /// ([`pipeline::build_without_regions`]), for the run-time cullers.
    pub without_regions: bool,
}

/// The rebuild of the side panel: the whole pipeline ([`pipeline::build`]) with the panel's parameters, or the
/// quadtree's cells alone ([`pipeline::build_without_regions`]) when they ask for no regions.
pub fn pipeline_rebuild() -> RebuildFn {
    Arc::new(|tin, params, progress| {
        let build = if params.without_regions {
            pipeline::build_without_regions(tin, &params.build, Some(progress))?
        } else {
            pipeline::build(tin, &params.build, Some(progress))?
        };
        Ok(build.hierarchy)
    })
}

/// What the viewer shows first.
#[derive(Clone, Debug)]
pub enum Source {
    /// A plain mesh: coloured by height until rebuilt.
    Mesh(Tin),
    /// A hierarchy and its mesh.
    Hierarchy(Hierarchy),
}

/// Take a screenshot of the window after some frames, write it as PNG and close.
#[derive(Clone, Debug, PartialEq)]
pub struct ScreenshotRequest {
    /// The PNG to write.
    pub path: PathBuf,
    /// Frames to draw first.
    pub after_frames: u32,
}

/// Actions the viewer takes by itself once the window is up, for tests and demonstrations: first the rebuild
/// (with the panel's parameters), then the ground truth for the viewpoint. A screenshot waits for both.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Startup {
    /// Press Rebuild at the first frame (with the pipeline, or the stand-in of [`ViewerOptions::rebuild`]).
    pub rebuild: bool,
    /// Press "Ground truth here" once the hierarchy is ready.
    pub ground_truth: bool,
    /// Turn the viewcell PVS on, with cells of this side (m).
    pub pvs_cell_size: Option<f64>,
}

/// What happened during a [`run`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RunSummary {
    /// Frames drawn.
    pub frames: u64,
    /// Frames drawn while a rebuild was running (the window stayed responsive).
    pub frames_during_rebuild: u64,
    /// Rebuilds completed and shown.
    pub rebuilds: u32,
    /// Triangles of the hierarchy shown last.
    pub triangles: usize,
    /// Leaf groups of the hierarchy shown last.
    pub groups: usize,
    /// Whether the hierarchy shown last has regions (none for a quadtree built without them; `false` for a plain
    /// mesh).
    pub regions: bool,
    /// The last ground truth: `(visible triangles, false culls)`.
    pub truth: Option<(usize, usize)>,
    /// The screenshot asked for: `None` when none was taken (the window closed first), else whether it was written
    /// (or why not).
    pub screenshot: Option<std::result::Result<PathBuf, String>>,
}

/// Everything [`run`] needs.
pub struct ViewerOptions {
    /// Window title.
    pub title: String,
    /// The terrain.
    pub source: Source,
    /// Initial build parameters (shown in the side panel; the undersampling radius is kept as given).
    pub params: RebuildParams,
    /// A stand-in for the pipeline; `None` rebuilds with [`pipeline_rebuild`].
    pub rebuild: Option<RebuildFn>,
    /// Path stem of exports (`STEM.tch`, `STEM.json`, `STEM.obj`).
    pub export_stem: PathBuf,
    /// Files the exports never write over (the terrain shown, and the files its reader read beside it:
    /// [`tin::dem::companion_files`]): an export to one of them is refused.
    pub inputs: Vec<PathBuf>,
    /// Initial viewpoint (world); default: the terrain's centre, 20 m above the ground.
    pub eye: Option<[f64; 3]>,
    /// Screenshot-and-exit, for tests and documentation.
    pub screenshot: Option<ScreenshotRequest>,
    /// Window size in points.
    pub window_size: [f32; 2],
    /// Actions to take by itself.
    pub startup: Startup,
    /// The culling method (the safe culler by default; switchable in the side panel).
    pub method: CullMethod,
    /// The safe culler's run-time parameters (also `--columns` of `lloyd-egbert`).
    pub safe: cull::SafeParams,
}

impl std::fmt::Debug for ViewerOptions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ViewerOptions")
            .field("title", &self.title)
            .field("params", &self.params)
            .field("rebuild", &self.rebuild.is_some())
            .field("export_stem", &self.export_stem)
            .field("eye", &self.eye)
            .field("screenshot", &self.screenshot)
            .finish_non_exhaustive()
    }
}

/// The terrain, its TIN (same triangle order, for ground truth and rebuilds), the TIN's point locator (the ground
/// under the eye, queried every frame the eye moves, and ground truth) and the culler.
struct Model {
    tin: Arc<Tin>,
    locator: Arc<Locator>,
    terrain: Terrain,
    culler: Option<AnyCuller>,
    /// The culling method (kept across rebuilds).
    method: CullMethod,
    /// The horizon cullers' parameters (kept across rebuilds).
    safe: cull::SafeParams,
}

impl Model {
    fn new(source: Source, method: CullMethod, safe: cull::SafeParams) -> Result<Model> {
        match source {
            Source::Mesh(tin) => Ok(Model {
                terrain: Terrain::from_tin(&tin)?,
                locator: Arc::new(Locator::new(&tin)),
                tin: Arc::new(tin),
                culler: None,
                method,
                safe,
            }),
            Source::Hierarchy(h) => Model::from_hierarchy(h, method, safe),
        }
    }

    fn from_hierarchy(h: Hierarchy, method: CullMethod, safe: cull::SafeParams) -> Result<Model> {
        let positions = h.mesh.positions.iter().map(|p| DVec3::from_array(*p)).collect();
        let tin = Tin::from_parts(positions, h.mesh.triangles.clone())?;
        // A rebuild may change the grouping: a region method becomes the one meant for the new one.
        let method = if method.check(&h).is_ok() {
            method
        } else {
            CullMethod::regions_for(&h)
        };
        // Preparing the culler and the locator take about as long on a large mesh (0.7 and 0.6 s at 1M vertices).
        let (culler, locator) = std::thread::scope(|s| {
            let locator = s.spawn(|| Locator::new(&tin));
            let culler = AnyCuller::with_params(&h, method, safe);
            // A panic there (none is known) goes on here, as if the locator had been built on this thread.
            (culler, locator.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
        });
        Ok(Model {
            tin: Arc::new(tin),
            locator: Arc::new(locator),
            terrain: Terrain::from_hierarchy(h)?,
            culler: Some(culler),
            method,
            safe,
        })
    }

    /// The terrain's height under world `(x, y)`, or `None` outside the mesh.
    fn ground(&self, x: f64, y: f64) -> Option<f64> {
        self.locator.ground_height(&self.tin, DVec2::new(x, y))
    }

    /// Switches the culling method, keeping the parameters.
    fn set_method(&mut self, method: CullMethod) {
        self.method = method;
        self.prepare();
    }

    /// Takes the horizon cullers' parameters `safe`, keeping the method.
    fn set_safe(&mut self, safe: cull::SafeParams) {
        self.safe = safe;
        self.prepare();
    }

    /// Prepares the culler of the hierarchy (if any) again, with the method and parameters as they are.
    fn prepare(&mut self) {
        if let Some(h) = &self.terrain.hierarchy {
            self.culler = Some(AnyCuller::with_params(h, self.method, self.safe));
        }
    }
}

/// Opens the viewer window and runs until it is closed.
pub fn run(options: ViewerOptions) -> Result<RunSummary> {
    let ViewerOptions {
        title,
        source,
        params,
        rebuild,
        export_stem,
        inputs,
        eye,
        screenshot,
        window_size,
        startup,
        method,
        safe,
    } = options;
    let rebuild = rebuild.unwrap_or_else(pipeline_rebuild);
    let summary = Arc::new(Mutex::new(RunSummary::default()));
    let model = Model::new(source, method, safe)?;
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title(title.clone())
            .with_inner_size(window_size),
        ..Default::default()
    };
    let setup = Setup {
        model,
        params,
        rebuild,
        export_stem,
        inputs,
        eye,
        screenshot,
        startup,
        summary: Arc::clone(&summary),
    };
    eframe::run_native(
        &title,
        native,
        Box::new(move |cc| {
            let app = ViewerApp::new(cc, setup).map_err(|e| Box::new(e) as DynError)?;
            Ok(Box::new(app) as Box<dyn eframe::App>)
        }),
    )
    .map_err(|e| match e {
        // No adapter could draw into the window: the same hint as a render without one.
        eframe::Error::Wgpu(
            w @ (eframe::egui_wgpu::WgpuError::RequestAdapterError(_)
            | eframe::egui_wgpu::WgpuError::CreateSurfaceError(_)),
        ) => ViewerError::NoAdapter(format!("for the viewer window: {w}")),
        e => ViewerError::Window(e.to_string()),
    })?;
    let result = summary.lock().map(|s| s.clone()).unwrap_or_default();
    Ok(result)
}

struct Setup {
    model: Model,
    params: RebuildParams,
    rebuild: RebuildFn,
    export_stem: PathBuf,
    inputs: Vec<PathBuf>,
    eye: Option<[f64; 3]>,
    screenshot: Option<ScreenshotRequest>,
    startup: Startup,
    summary: Arc<Mutex<RunSummary>>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ViewMode {
    Eye,
    Orbit,
}

/// A texture rendered by our renderer and shown by egui.
struct View {
    renderer: Renderer,
    texture: egui::TextureId,
}

impl View {
    fn new(gpu: &Gpu, egui_renderer: &Arc<egui::mutex::RwLock<egui_wgpu::Renderer>>, size: [u32; 2]) -> Result<View> {
        let renderer = Renderer::new(gpu, size[0], size[1])?;
        let texture = egui_renderer.write().register_native_texture(
            &gpu.device,
            renderer.texture_view(),
            wgpu::FilterMode::Linear,
        );
        Ok(View { renderer, texture })
    }

    fn resize(
        &mut self,
        gpu: &Gpu,
        egui_renderer: &Arc<egui::mutex::RwLock<egui_wgpu::Renderer>>,
        size: [u32; 2],
    ) -> Result<()> {
        if self.renderer.size() != size {
            self.renderer.resize(gpu, size[0], size[1])?;
            egui_renderer.write().update_egui_texture_from_wgpu_texture(
                &gpu.device,
                self.renderer.texture_view(),
                wgpu::FilterMode::Linear,
                self.texture,
            );
        }
        Ok(())
    }
}

/// Exponential moving average for live figures.
#[derive(Clone, Copy, Debug, Default)]
struct Smoothed(Option<f64>);

impl Smoothed {
    fn add(&mut self, v: f64) {
        self.0 = Some(self.0.map_or(v, |old| old * 0.8 + v * 0.2));
    }
}

struct ViewerApp {
    gpu: Gpu,
    egui_renderer: Arc<egui::mutex::RwLock<egui_wgpu::Renderer>>,
    model: Model,
    scene: GpuScene,
    main: View,
    map: View,
    map_view: MapView,
    params: RebuildParams,
    rebuild: RebuildFn,
    export_stem: String,
    /// Files the exports never write over.
    inputs: Vec<PathBuf>,
    // Camera.
    mode: ViewMode,
    eye: [f64; 3],
    eye_height: f64,
    yaw_deg: f64,
    pitch_deg: f64,
    fov_deg: f64,
    orbit: Orbit,
    // Toggles.
    colour: ColourMode,
    level: u32,
    culling: bool,
    show_orphans: bool,
    culled_wire: bool,
    /// Plot the Lloyd & Egbert culler's horizon buffer in the side panel.
    show_horizon: bool,
    /// The horizon cullers' parameters as the side panel's controls hold them (taken by the culler when a control
    /// is let go).
    safe_edit: cull::SafeParams,
    /// Paint a viewcell's PVS around the eye instead of the culler's verdicts.
    pvs_on: bool,
    /// Side of the viewcells (m): a grid over world coordinates, the eye's cell is shown.
    pvs_size: f64,
    // State.
    pvs: Option<PvsView>,
    list: DrawList,
    /// The fingerprint of `list`'s ranges after the last cull (0 with no culler).
    drawn_fingerprint: u64,
    /// The camera of the last cull: the eye view is culled again before it is drawn when the camera has changed since
    /// (the controls move it after the frame's cull).
    culled_for: Option<Camera>,
    /// Width over height of the eye view as last drawn, for the culler's field ([`culling_hfov_deg`]).
    view_aspect: f64,
    colours_key: Option<(ColourMode, u32, u64)>,
    map_dirty: bool,
    cull_us: Smoothed,
    ms_culled: Smoothed,
    ms_all: Smoothed,
    frame_count: u64,
    rebuild_job: Option<RebuildJob>,
    truth_job: Option<TruthJob>,
    truth: Option<Truth>,
    status: String,
    screenshot: Option<ScreenshotRequest>,
    screenshot_rx: Option<Receiver<Arc<egui::ColorImage>>>,
    startup: Startup,
    summary: Arc<Mutex<RunSummary>>,
}

const MAP_SIDE: u32 = 280;

/// The PVS of the viewcell around the eye (crate `pvs`, Koltun's test at 64 × 64): the cell of a `pvs_size` grid over
/// world coordinates that holds the eye, from the ground up to the eye's height above it.
struct PvsView {
    rect: [f64; 4],
    band: [f64; 2],
    mask: Vec<bool>,
    triangles: u64,
    seconds: f64,
}

impl ViewerApp {
    fn new(cc: &eframe::CreationContext<'_>, setup: Setup) -> Result<ViewerApp> {
        let rs = cc
            .wgpu_render_state
            .as_ref()
            .ok_or_else(|| ViewerError::Window("eframe did not start its wgpu renderer".into()))?;
        let gpu = Gpu::from_parts(rs.device.clone(), rs.queue.clone(), rs.adapter.get_info());
        let egui_renderer = rs.renderer.clone();
        let Setup {
            model,
            params,
            rebuild,
            export_stem,
            inputs,
            eye,
            screenshot,
            startup,
            summary,
        } = setup;
        let t = &model.terrain;
        let colour = if t.hierarchy.is_some() {
            ColourMode::Groups
        } else {
            ColourMode::Height
        };
        let colours = t.colours(colour, None, None)?;
        let scene = GpuScene::new(&gpu, t, &colours)?;
        let aspect = (t.max[0] - t.min[0]).max(1e-3) / (t.max[1] - t.min[1]).max(1e-3);
        let map_size = map_size(aspect);
        let main = View::new(&gpu, &egui_renderer, [640, 480])?;
        let map = View::new(&gpu, &egui_renderer, map_size)?;
        let eye = eye.unwrap_or_else(|| {
            let c = t.to_world([(t.min[0] + t.max[0]) * 0.5, (t.min[1] + t.max[1]) * 0.5, 0.0]);
            let ground = model.ground(c[0], c[1]).unwrap_or(c[2]);
            [c[0], c[1], ground + 20.0]
        });
        let eye_height = model.ground(eye[0], eye[1]).map_or(20.0, |g| (eye[2] - g).max(0.5));
        let safe_edit = model.safe;
        Ok(ViewerApp {
            map_view: MapView::fit(t.min, t.max, map_size[0] as f32 / map_size[1] as f32),
            orbit: Orbit::overview(t.min, t.max, 1.4, None, None),
            level: t.max_level(),
            gpu,
            egui_renderer,
            scene,
            main,
            map,
            params,
            rebuild,
            export_stem: export_stem.display().to_string(),
            inputs,
            mode: ViewMode::Eye,
            eye,
            eye_height,
            yaw_deg: 0.0,
            pitch_deg: -5.0,
            fov_deg: 90.0,
            colour,
            culling: true,
            show_orphans: true,
            culled_wire: true,
            show_horizon: false,
            safe_edit,
            pvs_on: startup.pvs_cell_size.is_some(),
            pvs_size: startup.pvs_cell_size.unwrap_or(100.0).max(1.0),
            pvs: None,
            list: DrawList::default(),
            drawn_fingerprint: 0,
            culled_for: None,
            view_aspect: 1.0,
            colours_key: Some((colour, 0, 0)),
            map_dirty: true,
            cull_us: Smoothed::default(),
            ms_culled: Smoothed::default(),
            ms_all: Smoothed::default(),
            frame_count: 0,
            rebuild_job: None,
            truth_job: None,
            truth: None,
            status: String::new(),
            screenshot,
            screenshot_rx: None,
            startup,
            summary,
            model,
        })
    }

    fn camera(&self) -> Camera {
        // The culler keeps every azimuth the pitched eye view shows, which is more than its field once it is pitched.
        let fov = culling_hfov_deg(self.fov_deg, self.pitch_deg, self.view_aspect);
        // The slider keeps the field of view in (0, 360] and the eye is finite; anything else looks all around.
        Camera::from_degrees(self.eye, self.yaw_deg, fov).unwrap_or(Camera::all_around(self.eye))
    }

    fn terrain(&self) -> &Terrain {
        &self.model.terrain
    }

    /// Runs the culler for the current viewpoint (timed) and returns the drawn mask's fingerprint.
    fn cull(&mut self) -> u64 {
        let camera = self.camera();
        self.culled_for = Some(camera);
        let Some(culler) = &self.model.culler else {
            self.list.ranges.clear();
            self.list.ranges.push([0, self.terrain().num_triangles() as u32]);
            self.list.stats = CullStats::default();
            self.drawn_fingerprint = 0;
            return 0;
        };
        let start = Instant::now();
        culler.cull_into(&camera, &mut self.list);
        self.cull_us.add(start.elapsed().as_secs_f64() * 1e6);
        // A cheap fingerprint of the ranges, to know when visibility colours must change.
        self.drawn_fingerprint = self.list.ranges.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, r| {
            (h ^ (u64::from(r[0]) << 32 | u64::from(r[1]))).wrapping_mul(0x0100_0000_01b3)
        });
        self.drawn_fingerprint
    }

    /// Recomputes the viewcell PVS when the eye has left its cell or the band changed (when the PVS is on).
    fn update_pvs(&mut self) {
        let Some(h) = self.model.terrain.hierarchy.as_ref().filter(|_| self.pvs_on) else {
            self.pvs = None;
            return;
        };
        let size = self.pvs_size.max(1.0);
        let (x0, y0) = ((self.eye[0] / size).floor() * size, (self.eye[1] / size).floor() * size);
        let rect = [x0, y0, x0 + size, y0 + size];
        let band = [0.0, self.eye_height];
        if self.pvs.as_ref().is_some_and(|p| p.rect == rect && p.band == band) {
            return;
        }
        let params = pvs::PvsParams {
            method: pvs::Method::Koltun,
            ..pvs::PvsParams::default()
        };
        let cell = pvs::ViewCell {
            rect,
            height: pvs::Height::AboveGround(band),
        };
        match pvs::Pvs::new(h, params).and_then(|p| p.compute(&cell)) {
            Ok(r) => {
                self.pvs = Some(PvsView {
                    rect,
                    band,
                    mask: r.mask(h.num_triangles()),
                    triangles: r.triangles(),
                    seconds: r.seconds,
                });
            }
            Err(e) => {
                self.status = format!("PVS: {e}");
                self.pvs_on = false;
                self.pvs = None;
            }
        }
    }

    fn update_colours(&mut self, fingerprint: u64) {
        if let Some(p) = &self.pvs {
            let fp = p
                .rect
                .iter()
                .chain(&p.band)
                .fold(0u64, |h, v| h.rotate_left(13) ^ v.to_bits());
            let key = (ColourMode::Visibility, u32::MAX, fp);
            if self.colours_key == Some(key) {
                return;
            }
            match self.terrain().colours(ColourMode::Visibility, None, Some(&p.mask)) {
                Ok(colours) => {
                    if let Err(e) = self.scene.set_colours(&self.gpu, &colours) {
                        self.status = e.to_string();
                    }
                    self.colours_key = Some(key);
                    self.map_dirty = true;
                }
                Err(e) => self.status = e.to_string(),
            }
            return;
        }
        let visibility_key = if self.colour == ColourMode::Visibility {
            fingerprint
        } else {
            0
        };
        let truth_key = self.truth.as_ref().map_or(0, |t| t.count as u64 + 1);
        let key = (self.colour, self.level, visibility_key ^ truth_key.rotate_left(17));
        if self.colours_key == Some(key) {
            return;
        }
        let n = self.terrain().num_triangles();
        let mask = self.list.mask(n);
        let colours = self.terrain().colours(self.colour, Some(self.level), Some(&mask));
        match colours {
            Ok(mut colours) => {
                if let Some(t) = &self.truth {
                    paint_false_culls(&mut colours, &t.false_culls);
                }
                if let Err(e) = self.scene.set_colours(&self.gpu, &colours) {
                    self.status = e.to_string();
                }
                self.colours_key = Some(key);
                self.map_dirty = true;
            }
            Err(e) => {
                self.status = e.to_string();
                self.colour = ColourMode::Height;
            }
        }
    }

    /// The draw items for the main view.
    fn items(&self) -> Vec<DrawItem> {
        let n = self.terrain().num_triangles() as u32;
        let limit = match (&self.terrain().hierarchy, self.show_orphans) {
            (Some(h), false) => h.always_visible[0],
            _ => n,
        };
        let clip = |items: Vec<DrawItem>| -> Vec<DrawItem> {
            items
                .into_iter()
                .filter_map(|mut i| {
                    i.range[1] = i.range[1].min(limit);
                    (i.range[0] < i.range[1]).then_some(i)
                })
                .collect()
        };
        if !self.culling || self.model.culler.is_none() {
            return clip(vec![DrawItem {
                range: [0, n],
                style: DrawStyle::Solid,
            }]);
        }
        // With a ground truth, culled triangles are drawn solid so that the false culls (painted red) show.
        let truth = self.truth.is_some();
        let items = split_items(&self.list.ranges, n);
        clip(
            items
                .into_iter()
                .filter(|i| i.style == DrawStyle::Solid || self.culled_wire || truth)
                .map(|mut i| {
                    if truth {
                        i.style = DrawStyle::Solid;
                    }
                    i
                })
                .collect(),
        )
    }

    fn marker(&self) -> Marker {
        let t = self.terrain();
        let extent = Vec3::from(t.max) - Vec3::from(t.min);
        let p = Vec3::from(t.to_local(self.eye));
        let diagonal = extent.truncate().length();
        Marker {
            position: p,
            size: diagonal * 0.008,
            height: diagonal * 0.05,
        }
    }

    fn place_eye(&mut self, x: f64, y: f64) {
        if let Some(z) = self.model.ground(x, y) {
            self.eye = [x, y, z + self.eye_height];
            self.map_dirty = true;
        }
    }

    fn handle_input(&mut self, ui: &egui::Ui, response: &egui::Response) {
        let ctx = ui.ctx();
        let drag = response.drag_delta();
        let t = &self.model.terrain;
        let extent = (Vec3::from(t.max) - Vec3::from(t.min)).truncate().length().max(1.0);
        match self.mode {
            ViewMode::Eye => {
                if response.dragged() {
                    self.yaw_deg = wrap_degrees(self.yaw_deg - f64::from(drag.x) * 0.25);
                    self.pitch_deg = (self.pitch_deg + f64::from(drag.y) * 0.25).clamp(-89.0, 89.0);
                    self.map_dirty = true;
                }
            }
            ViewMode::Orbit => {
                if response.dragged() {
                    self.orbit.yaw -= drag.x * 0.005;
                    self.orbit.pitch = (self.orbit.pitch + drag.y * 0.005).clamp(-1.5, 0.3);
                }
            }
        }
        let (scroll, dt, keys) = ctx.input(|i| {
            let k = |key| i.key_down(key);
            (
                i.smooth_scroll_delta.y,
                i.stable_dt.min(0.1),
                [
                    k(egui::Key::W),
                    k(egui::Key::S),
                    k(egui::Key::A),
                    k(egui::Key::D),
                    k(egui::Key::R),
                    k(egui::Key::F),
                ],
            )
        });
        if response.hovered() && scroll != 0.0 {
            match self.mode {
                ViewMode::Orbit => self.orbit.distance = (self.orbit.distance * (-scroll * 0.002).exp()).max(1.0),
                ViewMode::Eye => self.move_eye(f64::from(scroll) * f64::from(extent) * 2e-4, 0.0, 0.0),
            }
        }
        if !ctx.egui_wants_keyboard_input() {
            let speed = f64::from(extent) * 0.1 * f64::from(dt);
            let axis = |plus: bool, minus: bool| f64::from(i8::from(plus) - i8::from(minus));
            let forward = axis(keys[0], keys[1]);
            let right = axis(keys[3], keys[2]);
            let up = axis(keys[4], keys[5]);
            if forward != 0.0 || right != 0.0 || up != 0.0 {
                self.move_eye(forward * speed, right * speed, up * speed * 0.25);
                ctx.request_repaint();
            }
        }
    }

    fn move_eye(&mut self, forward: f64, right: f64, up: f64) {
        let model = &self.model;
        (self.eye, self.eye_height) =
            moved_eye(self.eye, self.eye_height, self.yaw_deg, [forward, right, up], |x, y| {
                model.ground(x, y)
            });
        self.map_dirty = true;
    }

    fn render_views(&mut self, size: [u32; 2]) -> Result<()> {
        self.main.resize(&self.gpu, &self.egui_renderer, size)?;
        let aspect = size[0] as f32 / size[1].max(1) as f32;
        // What is drawn is culled for this very camera and image (the input handled after the frame's cull may have
        // moved, turned or pitched it, and the window may have changed shape).
        self.view_aspect = f64::from(aspect);
        if self.culled_for != Some(self.camera()) {
            let fingerprint = self.cull();
            self.update_colours(fingerprint);
        }
        let t = &self.model.terrain;
        let (view_proj, marker) = match self.mode {
            ViewMode::Eye => {
                let cam = EyeCamera {
                    position: Vec3::from(t.to_local(self.eye)),
                    yaw: (self.yaw_deg as f32).to_radians(),
                    pitch: (self.pitch_deg as f32).to_radians(),
                    hfov: (self.fov_deg.min(f64::from(MAX_RENDER_HFOV_DEG)) as f32).to_radians(),
                };
                (cam.view_proj(aspect), None)
            }
            ViewMode::Orbit => (self.orbit.view_proj(aspect), Some(self.marker())),
        };
        let n = t.num_triangles() as u32;
        let all = [DrawItem {
            range: [0, n],
            style: DrawStyle::Solid,
        }];
        let items = self.items();
        // Every 20th frame, time a frame that draws everything for comparison.
        if self.frame_count.is_multiple_of(20) {
            let frame = Frame {
                scene: &self.scene,
                view_proj,
                items: &all,
                marker,
                count_primitives: false,
            };
            let stats = self.main.renderer.render(&self.gpu, &frame)?;
            self.ms_all.add(stats.ms);
        }
        let frame = Frame {
            scene: &self.scene,
            view_proj,
            items: &items,
            marker,
            count_primitives: false,
        };
        let stats = self.main.renderer.render(&self.gpu, &frame)?;
        self.ms_culled.add(stats.ms + self.cull_us.0.unwrap_or(0.0) * 1e-3);
        if self.map_dirty {
            let frame = Frame {
                scene: &self.scene,
                view_proj: self.map_view.view_proj(),
                items: &all,
                marker: None,
                count_primitives: false,
            };
            self.map.renderer.render(&self.gpu, &frame)?;
            self.map_dirty = false;
        }
        Ok(())
    }

    fn screenshot_step(&mut self, ctx: &egui::Context, ready: bool) {
        let Some(req) = &self.screenshot else { return };
        ctx.request_repaint();
        if !ready {
            return;
        }
        if let Some(rx) = &self.screenshot_rx {
            if let Ok(image) = rx.try_recv() {
                let [w, h] = image.size;
                let pixels = image.pixels.iter().flat_map(|c| c.to_array()).collect();
                let img = RgbaImage {
                    width: w as u32,
                    height: h as u32,
                    pixels,
                };
                let written = crate::png_out::write_png(&req.path, &img)
                    .map(|()| req.path.clone())
                    .map_err(|e| e.to_string());
                if let Ok(mut s) = self.summary.lock() {
                    s.screenshot = Some(written);
                }
                self.screenshot = None;
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
        } else if self.frame_count >= u64::from(req.after_frames) {
            let (tx, rx) = channel();
            ctx.request_screenshot(move |image| {
                let _ = tx.send(image);
            });
            self.screenshot_rx = Some(rx);
        }
    }
}

impl eframe::App for ViewerApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.poll_jobs();
        let fingerprint = self.cull();
        let camera = self.camera();
        if self.truth.as_ref().is_some_and(|t| !t.holds_for(&camera, fingerprint)) {
            self.truth = None;
        }
        self.update_pvs();
        self.update_colours(fingerprint);
        egui::Panel::left("controls").default_size(330.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| self.side_panel(ui));
        });
        egui::CentralPanel::default().show(ui, |ui| {
            let avail = ui.available_size();
            let (rect, response) = ui.allocate_exact_size(avail, egui::Sense::click_and_drag());
            self.handle_input(ui, &response);
            let ppp = ctx.pixels_per_point();
            let size = [
                ((rect.width() * ppp).round() as u32).clamp(1, crate::render::MAX_SIDE),
                ((rect.height() * ppp).round() as u32).clamp(1, crate::render::MAX_SIDE),
            ];
            if let Err(e) = self.render_views(size) {
                self.status = format!("render failed: {e}");
            }
            ui.painter().image(
                self.main.texture,
                rect,
                egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
                egui::Color32::WHITE,
            );
        });
        if self.rebuild_job.is_some() || self.truth_job.is_some() {
            ctx.request_repaint_after(std::time::Duration::from_millis(100));
        }
        self.frame_count += 1;
        if let Ok(mut s) = self.summary.lock() {
            s.frames += 1;
            s.frames_during_rebuild += u64::from(self.rebuild_job.is_some());
            s.triangles = self.model.terrain.num_triangles();
            s.groups = self.model.terrain.groups;
            s.regions = self
                .model
                .terrain
                .hierarchy
                .as_ref()
                .is_some_and(Hierarchy::has_regions);
        }
        let ready = self.startup_step(&ctx);
        self.screenshot_step(&ctx, ready);
    }
}

fn map_size(aspect: f32) -> [u32; 2] {
    if aspect >= 1.0 {
        [MAP_SIDE, ((MAP_SIDE as f32 / aspect).round() as u32).max(16)]
    } else {
        [((MAP_SIDE as f32 * aspect).round() as u32).max(16), MAP_SIDE]
    }
}

fn wrap_degrees(d: f64) -> f64 {
    (d + 180.0).rem_euclid(360.0) - 180.0
}

/// The eye moved by `[forward, right, up]` (m) at the view azimuth `yaw_deg`: over the terrain it keeps its height
/// above the ground (changed by `up`, at least 0.5 m), returned with it; off the terrain (`ground` is `None` there)
/// it moves at its own height and keeps `eye_height` for when it comes back.
fn moved_eye(
    eye: [f64; 3],
    eye_height: f64,
    yaw_deg: f64,
    [forward, right, up]: [f64; 3],
    ground: impl Fn(f64, f64) -> Option<f64>,
) -> ([f64; 3], f64) {
    let a = yaw_deg.to_radians();
    let (f, r) = ([a.cos(), a.sin()], [a.sin(), -a.cos()]);
    let x = eye[0] + f[0] * forward + r[0] * right;
    let y = eye[1] + f[1] * forward + r[1] * right;
    match ground(x, y) {
        Some(g) => {
            let h = (eye[2] + up - g).max(0.5);
            ([x, y, g + h], h)
        }
        None => ([x, y, eye[2] + up], eye_height),
    }
}

#[cfg(test)]
mod tests {
    use super::{Model, moved_eye};
    use cull::{AnyCuller, Camera, CullMethod, SafeParams};

    /// The bundled 2,000-vertex terrain and its default build.
    fn bundled() -> (tin::Tin, cull::Hierarchy) {
        let obj = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../meshes/jacksboro-2k.obj");
        let (tin, _) = tin::read_obj(&obj, &Default::default()).expect("the bundled mesh");
        let h = pipeline::build(&tin, &pipeline::BuildParams::default(), None)
            .expect("build")
            .hierarchy;
        (tin, h)
    }

    /// Parameters set from the side panel prepare the culler again, as `AnyCuller::with_params` prepares it, and
    /// stay when the method changes (and the method when they change).
    #[test]
    fn new_culler_parameters_and_methods_prepare_the_culler_again() {
        let (_, h) = bundled();
        let mut model = Model::from_hierarchy(h.clone(), CullMethod::Safe, SafeParams::default()).expect("model");
        let eyes: Vec<Camera> = h
            .mesh
            .positions
            .iter()
            .step_by(97)
            .map(|p| Camera::all_around([p[0], p[1], p[2] + 2.0]))
            .collect();
        let ranges = |c: &AnyCuller| eyes.iter().map(|e| c.cull(e).ranges).collect::<Vec<_>>();
        let tight = SafeParams {
            columns_per_face: 16,
            patch: 4,
            work_budget: 300,
            ..SafeParams::default()
        };
        let before = ranges(model.culler.as_ref().expect("a culler"));
        model.set_safe(tight);
        let after = ranges(model.culler.as_ref().expect("a culler"));
        assert_eq!(after, ranges(&AnyCuller::with_params(&h, CullMethod::Safe, tight)));
        assert_ne!(after, before, "the parameters changed nothing: the test tests nothing");
        model.set_method(CullMethod::LloydEgbert);
        assert_eq!(model.safe, tight);
        assert_eq!(
            ranges(model.culler.as_ref().expect("a culler")),
            ranges(&AnyCuller::with_params(&h, CullMethod::LloydEgbert, tight))
        );
        model.set_safe(SafeParams::default());
        assert_eq!(model.method, CullMethod::LloydEgbert);
    }

    /// The ground under the eye comes from the model's point locator: the height of the plane of a triangle that holds
    /// the point, as the independent pass over all triangles (`truth::ground_heights`) finds it, for a plain mesh and
    /// a hierarchy alike; none outside the footprint.
    #[test]
    fn the_ground_under_the_eye_is_the_terrain_s() {
        let (tin, h) = bundled();
        let (lo, hi) = (tin.bbox().min, tin.bbox().max);
        let points: Vec<glam::DVec2> = (0..=40)
            .flat_map(|i| (0..=40).map(move |j| (i, j)))
            .map(|(i, j)| {
                // A lattice over the box and a margin beyond it, so that some points miss the footprint.
                let f = |k: i32| (f64::from(k) - 2.0) / 36.0;
                glam::DVec2::new(lo.x + f(i) * (hi.x - lo.x), lo.y + f(j) * (hi.y - lo.y))
            })
            .collect();
        let positions: Vec<[f64; 3]> = tin.positions().iter().map(|p| p.to_array()).collect();
        let expected = truth::ground_heights(&positions, tin.triangles(), &points);
        assert!(expected.iter().any(Option::is_none) && expected.iter().any(Option::is_some));
        let plain = Model::new(super::Source::Mesh(tin), CullMethod::Safe, SafeParams::default()).expect("model");
        let built = Model::from_hierarchy(h, CullMethod::Safe, SafeParams::default()).expect("model");
        for model in [plain, built] {
            for (p, want) in points.iter().zip(&expected) {
                let got = model.ground(p.x, p.y);
                match (got, want) {
                    (Some(g), Some(w)) => assert!((g - w).abs() <= 1e-9 * w.abs().max(1.0), "{p}: {g} against {w}"),
                    _ => assert_eq!(got.is_some(), want.is_some(), "{p}: {got:?} against {want:?}"),
                }
            }
        }
    }

    /// The panel's rebuild runs the pipeline the parameters name: with regions (`pipeline::build`), or for a quadtree
    /// without them the cells alone (`pipeline::build_without_regions`), the same hierarchy either way but its
    /// regions; a crystal grouping without regions is an error, not a build with them.
    #[test]
    fn the_rebuild_builds_with_or_without_regions_as_asked() {
        let (tin, _) = bundled();
        let rebuild = super::pipeline_rebuild();
        let progress: super::Progress = std::sync::Arc::new(|_: &str, _, _| {});
        let quadtree = pipeline::BuildParams {
            grouping: pipeline::Grouping::Quadtree(pipeline::QuadtreeParams {
                depth: Some(3),
                ..Default::default()
            }),
            ..Default::default()
        };
        let rebuilt = |build: &pipeline::BuildParams, without_regions| {
            let params = super::RebuildParams {
                build: build.clone(),
                without_regions,
            };
            rebuild(&tin, &params, progress.clone())
        };
        let with = rebuilt(&quadtree, false).expect("with regions");
        let without = rebuilt(&quadtree, true).expect("without regions");
        assert!(with.has_regions() && !without.has_regions());
        assert_eq!(
            without,
            pipeline::build_without_regions(&tin, &quadtree, None)
                .expect("build")
                .hierarchy
        );
        assert_eq!(with.mesh, without.mesh);
        assert_eq!(with.nodes.len(), without.nodes.len());
        let crystal = pipeline::BuildParams::default();
        assert!(rebuilt(&crystal, false).expect("crystal").has_regions());
        assert!(rebuilt(&crystal, true).is_err());
    }

    /// Ground at height 100 on x in [0, 10], none beyond.
    fn ground(x: f64, _: f64) -> Option<f64> {
        (0.0..=10.0).contains(&x).then_some(100.0)
    }

    #[test]
    fn the_eye_follows_the_ground_and_moves_freely_off_it() {
        // Over the terrain: the height above the ground changes by `up`, never below 0.5 m.
        let (eye, h) = moved_eye([5.0, 0.0, 120.0], 20.0, 0.0, [1.0, 0.0, 5.0], ground);
        assert_eq!((eye, h), ([6.0, 0.0, 125.0], 25.0));
        let (eye, h) = moved_eye(eye, h, 0.0, [0.0, 0.0, -100.0], ground);
        assert_eq!((eye, h), ([6.0, 0.0, 100.5], 0.5));
        // Off the terrain (an eye given outside it, or walking off its edge): it moves, at its own height.
        let (eye, h) = moved_eye([5.0, 0.0, 120.0], 20.0, 180.0, [10.0, 0.0, 3.0], ground);
        assert!(
            (eye[0] + 5.0).abs() < 1e-9 && eye[2] == 123.0 && h == 20.0,
            "{eye:?} {h}"
        );
        let (eye, h) = moved_eye([-50.0, 0.0, 300.0], 20.0, 0.0, [-10.0, 0.0, 0.0], ground);
        assert_eq!((eye, h), ([-60.0, 0.0, 300.0], 20.0));
        // Back onto it: its height above the ground is what it is there.
        let (eye, h) = moved_eye([-1.0, 0.0, 130.0], 20.0, 0.0, [2.0, 0.0, 0.0], ground);
        assert_eq!((eye, h), ([1.0, 0.0, 130.0], 30.0));
    }
}
