//! The preprocessing pipeline of tincull, as a library: horizons → vertex regions → grouping (crystals, or the
//! quadtree of Stewart's baseline, [`Grouping`]; nodes' regions intersected from their vertices' regions) → the
//! exported [`cull::Hierarchy`] (regions rounded to f32 so that they only shrink). Per-triangle regions are only made
//! for the per-triangle evaluation method ([`triangle_regions`]).
//!
//! Where it sits: the data of a build flows `tin → horizon → occlusion → crystal → cull::Hierarchy`, and this crate
//! drives that flow. Crate dependencies point one way, down: this crate uses `tin`, `horizon`, `occlusion`,
//! `crystal` and `cull` (the run-time format and sector geometry, which `occlusion` and `crystal` share so that
//! precomputation and run time agree); `eval`, `viewer` and the `tincull` command line use it, never the other way
//! round. It writes no files (see [`export`]) and compiles no GPU or GUI code (`cargo tree -e normal -p pipeline`
//! shows what it does compile).
//!
//! [`build_without_regions`] stops before the horizons: the quadtree's cells alone, for the run-time cullers, which
//! read no region.
//!
//! Besides [`build`] it owns the content for people and other tools ([`export`]: the grouped OBJ + MTL and the
//! hierarchy's JSON form) and the group palette they share with the viewer ([`palette`]).
//!
//! The crates whose types a build and a cull take and return are re-exported, so that a library user needs only this
//! one dependency: `pipeline::tin` (the terrain, its readers of OBJ, `.hgt`, `.asc`, `.npy`, and with this crate's
//! default features `png` and `geotiff` also of PNG height maps and GeoTIFFs) and `pipeline::cull` (the hierarchy,
//! cameras, cullers). A DEM grid becomes a TIN as `tincull` makes it (`--dem-vertices`, 10,000 by default) with
//! `let grid = tin::read_dem(path, &tin::DemOptions::default())?;` then
//! `let (tin, _report) = tin::simplify(&grid, &tin::SimplifyOptions::vertices(10_000), None)?;`.
//!
//! Errors: [`build`], [`build_from_regions`], [`build_without_regions`] and [`BuildParams::validate`] return a
//! [`BuildError`], whose variant says which stage refused (the horizon sweep, crystal grouping, the quadtree, regions
//! that do not fit the terrain, or crystals asked for without regions) and holds that stage's own error; the
//! file-format helpers ([`export`], [`gltf`]) return an [`ExportError`], whose messages name the path or the element
//! at fault.
//!
//! From a mesh to a `.tch` file and a cull, as `tincull build` and `tincull cull` do it (the file's bytes are
//! [`cull::Hierarchy::to_bytes`]; [`cull::Hierarchy::load`] reads them back):
//!
//! ```
//! use pipeline::cull::{AnyCuller, Camera, CullMethod, DrawList, Hierarchy};
//! use pipeline::tin::{self, ObjImportOptions};
//! use pipeline::{BuildParams, build};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! # let mesh = concat!(env!("CARGO_MANIFEST_DIR"), "/../../meshes/jacksboro-2k.obj");
//! let (tin, _report) = tin::read_obj(mesh, &ObjImportOptions::default())?;
//! let built = build(&tin, &BuildParams::default(), None)?; // 16 sectors × 4 subsectors, crystal groups
//! let bytes = built.hierarchy.to_bytes()?; // what a `.tch` file holds: write it with any atomic file writer
//! let h = Hierarchy::from_bytes(&bytes)?;
//! assert_eq!(h, built.hierarchy);
//!
//! // Culling: the safe culler by default; one draw list reused frame after frame.
//! let culler = AnyCuller::new(&h, CullMethod::default());
//! let mut list = DrawList::default();
//! let (lo, hi) = (tin.bbox().min, tin.bbox().max);
//! let eye = [0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), hi.z + 100.0];
//! culler.cull_into(&Camera::from_degrees(eye, 30.0, 90.0)?, &mut list);
//! let drawn: u32 = list.ranges.iter().map(|[start, end]| end - start).sum();
//! assert_eq!(drawn, list.stats.triangles_drawn);
//! // Draw triangles `start..end` of `h.mesh.triangles` for each range (the order of `tincull export --export-obj`).
//! # Ok(())
//! # }
//! ```
#![warn(missing_docs)]

mod error;
pub mod export;
pub mod gltf;
pub mod palette;

pub use error::{BuildError, ExportError};
/// The errors of the stages, which [`BuildError`] holds.
pub use {crystal::CrystalError, horizon::HorizonError, quadtree::QuadtreeError};

pub use cull;
pub use tin;
/// The crates whose types a [`Build`] holds beyond the hierarchy (its groups, quadtree and regions), and glam, whose
/// vectors [`tin::Tin`] and the regions use: re-exported so that they can be named without depending on them.
pub use {crystal, glam, occlusion, quadtree};

use std::sync::Arc;
use std::time::Instant;

use crystal::Crystal;
pub use crystal::CrystalParams;
use cull::{BuildInfo, Hierarchy, Mesh, Node, StoredRegion};
use horizon::{HorizonOptions, SectorConfig};
use occlusion::{Region, RegionTable, plane_t};
pub use quadtree::QuadtreeParams;
use quadtree::{LevelStats, Quadtree};
use serde::{Deserialize, Serialize};
use tin::{Circle, Tin};

/// Everything that controls a build.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BuildParams {
    /// Number of sectors `s`: at least 4 ([`horizon::SectorConfig::new`]).
    pub sectors: u32,
    /// Subsectors per sector `k`: at least 1, with `s · k` at most [`horizon::MAX_TOTAL_SUBSECTORS`].
    pub subsectors: u32,
    /// Radius of the horizon undersampling fix (m), off when `None`.
    pub undersampling: Option<f64>,
    /// Crystal grouping parameters (used when `grouping` is [`Grouping::Crystal`]).
    pub crystal: CrystalParams,
    /// How triangles are grouped into hierarchy nodes.
    #[serde(default)]
    pub grouping: Grouping,
}

/// The grouping of a build.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Grouping {
    /// Crystal groups and their merge hierarchy (the thesis), with [`BuildParams::crystal`].
    #[default]
    Crystal,
    /// Stewart's quadtree over the footprint (crate `quadtree`) with its parameters.
    Quadtree(QuadtreeParams),
}

impl Grouping {
    /// The grouping's name (`crystal`, `quadtree`).
    pub fn name(&self) -> &'static str {
        match self {
            Grouping::Crystal => "crystal",
            Grouping::Quadtree(_) => "quadtree",
        }
    }
}

impl Default for BuildParams {
    fn default() -> Self {
        BuildParams {
            sectors: 16,
            subsectors: 4,
            undersampling: None,
            crystal: CrystalParams::default(),
            grouping: Grouping::Crystal,
        }
    }
}

impl BuildParams {
    /// Checks the values (the sectors and subsectors, the undersampling radius, the grouping's parameters), as
    /// [`build`] does before any work: a tile plan checks them before its jobs run.
    pub fn validate(&self) -> Result<(), BuildError> {
        SectorConfig::new(self.sectors, self.subsectors)?;
        horizon::check_undersampling_radius(self.undersampling)?;
        match &self.grouping {
            Grouping::Crystal => self.crystal.validate()?,
            Grouping::Quadtree(q) => q.validate()?,
        }
        Ok(())
    }
}

/// The figures of a build (the thesis' Tables 2 and 3, plus storage).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BuildReport {
    /// Vertices of the terrain.
    pub vertices: usize,
    /// Triangles of the terrain.
    pub triangles: usize,
    /// Sectors.
    pub sectors: u32,
    /// Subsectors per sector.
    pub subsectors: u32,
    /// Seeds asked for in the first crystal pass.
    pub seeds: usize,
    /// Crystals started by the first pass: fewer than `seeds` when fewer triangles than that are free to seed or
    /// pass the visibility rule.
    pub first_pass_crystals: usize,
    /// Wall time of the horizon sweep (s).
    pub horizon_seconds: f64,
    /// Wall time of the vertex regions (s).
    pub regions_seconds: f64,
    /// Wall time of crystal growth and the merge hierarchy (s).
    pub grouping_seconds: f64,
    /// Orphan passes run after the first pass (at most the limit `params.crystal.orphan_passes`).
    pub orphan_passes_run: u32,
    /// Triangles in the always-visible set.
    pub orphans: usize,
    /// Leaf groups.
    pub groups: usize,
    /// Hierarchy nodes (leaves included).
    pub nodes: usize,
    /// Levels of the hierarchy.
    pub levels: u32,
    /// Top-level nodes.
    pub top_level: usize,
    /// Bytes of visibility data in the exported hierarchy.
    pub visibility_bytes: usize,
    /// Visibility bytes per triangle.
    pub visibility_bytes_per_triangle: f64,
    /// The grouping (`crystal` or `quadtree`).
    #[serde(default)]
    pub grouping: String,
    /// For a quadtree: every depth built, root first, with its bytes and whether it is stored (memory levels).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub quadtree_levels: Vec<LevelStats>,
    /// Built by [`build_without_regions`]: no horizons, no regions.
    #[serde(default)]
    pub without_regions: bool,
}

/// The result of [`build`]: the exported hierarchy, the figures, and the intermediate data that evaluation reuses.
#[derive(Clone, Debug)]
pub struct Build {
    /// The exported hierarchy (mesh reordered).
    pub hierarchy: Hierarchy,
    /// Figures.
    pub report: BuildReport,
    /// Per-vertex regions (the grouping's input); [`triangle_regions`] derives the per-triangle ones from them. Empty
    /// (no rows) from [`build_without_regions`].
    pub vertex_regions: RegionTable,
    /// The new triangle order: `order[k]` is the original index of the hierarchy's triangle `k`.
    pub order: Vec<u32>,
    /// The crystal grouping, for [`Grouping::Crystal`].
    pub crystal: Option<Crystal>,
    /// The quadtree, for [`Grouping::Quadtree`].
    pub quadtree: Option<Quadtree>,
}

/// Progress callback of [`build`]: `(stage name, done, total)`.
pub type BuildProgress = Arc<dyn Fn(&str, u64, u64) + Send + Sync>;

/// Runs the whole pipeline on `tin`, which must be a height field (no two triangles overlapping in x,y): every TIN
/// the readers and `tin::triangulate` make is one; one made with `Tin::from_parts` is checked by `tin::validate`.
pub fn build(tin: &Tin, params: &BuildParams, progress: Option<BuildProgress>) -> Result<Build, BuildError> {
    params.validate()?;
    let config = SectorConfig::new(params.sectors, params.subsectors)?;
    let report_progress = progress.clone();
    let opts = HorizonOptions {
        undersampling_radius: params.undersampling,
        progress: report_progress
            .map(|p| Arc::new(move |done: usize, total: usize| p("horizons", done as u64, total as u64)) as _),
    };
    let start = Instant::now();
    let field = horizon::compute(tin, &config, &opts)?;
    let horizon_seconds = start.elapsed().as_secs_f64();

    if let Some(p) = &progress {
        p("regions", 0, 1);
    }
    let start = Instant::now();
    let vertex_regions = RegionTable::from_field_owned(tin.positions(), field);
    let regions_seconds = start.elapsed().as_secs_f64();
    if let Some(p) = &progress {
        p("regions", 1, 1);
    }
    build_from_regions(
        tin,
        vertex_regions,
        params,
        [horizon_seconds, regions_seconds],
        progress,
    )
}

/// A quadtree hierarchy without the thesis' visibility data: no horizons, no regions (every node's region empty),
/// for the run-time cullers (`safe`, the default, and `lloyd-egbert`), which read only the mesh and the nodes. The
/// same cells, triangle order and nodes as [`build`] with the same quadtree parameters, in a fraction of its time
/// (the horizon sweep is most of a build); the region tests (`stewart`, `thesis`) cull nothing in it. `params` must
/// name [`Grouping::Quadtree`] (crystal groups grow from the regions); its sectors and subsectors are recorded only.
/// [`Build::vertex_regions`] is empty.
pub fn build_without_regions(
    tin: &Tin,
    params: &BuildParams,
    progress: Option<BuildProgress>,
) -> Result<Build, BuildError> {
    params.validate()?;
    let Grouping::Quadtree(qp) = &params.grouping else {
        return Err(BuildError::RegionsNeeded);
    };
    if let Some(p) = &progress {
        p("grouping", 0, 1);
    }
    let start = Instant::now();
    let quadtree = quadtree::build_without_regions(tin, params.sectors, qp)?;
    let seconds = [0.0, 0.0, start.elapsed().as_secs_f64()];
    let empty = RegionTable::from_rows(params.sectors, glam::DVec2::ZERO, Vec::new());
    let mut b = quadtree_build(tin, quadtree, empty, params, seconds);
    b.report.without_regions = true;
    if let Some(p) = &progress {
        p("grouping", 1, 1);
    }
    Ok(b)
}

/// The [`Build`] of a quadtree: its hierarchy and figures; `seconds` are the horizon, region and grouping times.
fn quadtree_build(
    tin: &Tin,
    quadtree: Quadtree,
    vertex_regions: RegionTable,
    params: &BuildParams,
    seconds: [f64; 3],
) -> Build {
    let [horizon_seconds, regions_seconds, grouping_seconds] = seconds;
    let hierarchy = export_quadtree(tin, &quadtree, params);
    let visibility_bytes = hierarchy.visibility_bytes();
    let leaves = hierarchy.nodes.iter().filter(|n| n.children.is_empty()).count();
    let report = BuildReport {
        vertices: tin.num_vertices(),
        triangles: tin.num_triangles(),
        sectors: params.sectors,
        subsectors: params.subsectors,
        seeds: 0,
        first_pass_crystals: 0,
        horizon_seconds,
        regions_seconds,
        grouping_seconds,
        orphan_passes_run: 0,
        orphans: 0,
        groups: leaves,
        nodes: hierarchy.nodes.len(),
        levels: quadtree.stored_depth + 1,
        top_level: hierarchy.roots.len(),
        visibility_bytes,
        visibility_bytes_per_triangle: visibility_bytes as f64 / tin.num_triangles().max(1) as f64,
        grouping: "quadtree".into(),
        quadtree_levels: quadtree.levels.clone(),
        without_regions: false,
    };
    Build {
        hierarchy,
        report,
        vertex_regions,
        order: quadtree.order.clone(),
        crystal: None,
        quadtree: Some(quadtree),
    }
}

/// The grouping and export stages of [`build`], from per-vertex regions computed elsewhere (a tile job computes
/// them with terrain from outside its tile: crate `tiles`). `seconds` are the horizon and region times to report.
pub fn build_from_regions(
    tin: &Tin,
    vertex_regions: RegionTable,
    params: &BuildParams,
    seconds: [f64; 2],
    progress: Option<BuildProgress>,
) -> Result<Build, BuildError> {
    let [horizon_seconds, regions_seconds] = seconds;
    params.validate()?;
    if vertex_regions.len() != tin.num_vertices() || vertex_regions.sectors() != params.sectors {
        return Err(BuildError::RegionsMismatch {
            rows: vertex_regions.len(),
            sectors: vertex_regions.sectors(),
            vertices: tin.num_vertices(),
            expected_sectors: params.sectors,
        });
    }
    if let Some(p) = &progress {
        p("grouping", 0, 1);
    }
    let start = Instant::now();
    if let Grouping::Quadtree(qp) = &params.grouping {
        let quadtree = quadtree::build(tin, &vertex_regions, qp)?;
        let seconds = [horizon_seconds, regions_seconds, start.elapsed().as_secs_f64()];
        return Ok(quadtree_build(tin, quadtree, vertex_regions, params, seconds));
    }
    let crystal = crystal::build(tin, &vertex_regions, &params.crystal)?;
    let grouping_seconds = start.elapsed().as_secs_f64();
    if let Some(p) = &progress {
        p("grouping", 1, 1);
    }

    let hierarchy = export_hierarchy(tin, &crystal, params);
    let s = &crystal.stats;
    let visibility_bytes = hierarchy.visibility_bytes();
    let report = BuildReport {
        vertices: tin.num_vertices(),
        triangles: tin.num_triangles(),
        sectors: params.sectors,
        subsectors: params.subsectors,
        seeds: params.crystal.first_seeds(tin.num_triangles()),
        first_pass_crystals: s.passes.first().map_or(0, |p| p.new_groups),
        horizon_seconds,
        regions_seconds,
        grouping_seconds,
        orphan_passes_run: s.orphan_passes,
        orphans: s.orphans,
        groups: s.groups,
        nodes: s.nodes,
        levels: s.levels,
        top_level: s.top_level,
        visibility_bytes,
        visibility_bytes_per_triangle: visibility_bytes as f64 / tin.num_triangles().max(1) as f64,
        grouping: "crystal".into(),
        quadtree_levels: Vec::new(),
        without_regions: false,
    };
    Ok(Build {
        hierarchy,
        report,
        vertex_regions,
        order: crystal.order.clone(),
        crystal: Some(crystal),
        quadtree: None,
    })
}

/// Rounds a circle to f32 relative to `origin` so that it still encloses the original one.
pub fn stored_circle(c: &Circle, origin: [f64; 3]) -> ([f32; 2], f32) {
    let rel = [c.centre.x - origin[0], c.centre.y - origin[1]];
    let centre = [rel[0] as f32, rel[1] as f32];
    let shift = (f64::from(centre[0]) - rel[0]).hypot(f64::from(centre[1]) - rel[1]);
    let r = c.radius + shift;
    let mut radius = r as f32;
    if f64::from(radius) < r {
        radius = radius.next_up();
    }
    (centre, radius)
}

/// The per-triangle regions of `tin`: each triangle's row is the intersection of its three vertices' rows of
/// `vertex_regions`, in the terrain's original triangle order. Only the per-triangle method
/// ([`per_triangle_hierarchy`]) needs them; [`build`] does not make them.
///
/// # Panics
/// When `vertex_regions` has fewer rows than `tin` has vertices (a table of another terrain).
pub fn triangle_regions(tin: &Tin, vertex_regions: &RegionTable) -> RegionTable {
    let triangles = tin.triangles();
    vertex_regions.intersect_rows(triangles.len(), |t| triangles[t])
}

/// Rounds per-sector regions to the stored f32 form, relative to `origin`; empty sectors are left out. The regions'
/// plane coordinates are relative to `frame` (`t = r_i · (xy − frame)`, see [`RegionTable::origin`]); the stored ones
/// are relative to `origin` (`t = r_i · (xy − origin)`, `z − origin.z`), as the exported format defines.
pub fn stored_regions(
    regions: &[Option<Region>],
    sectors: u32,
    frame: glam::DVec2,
    origin: [f64; 3],
) -> Vec<StoredRegion> {
    // Both are near the terrain, so this difference is small (and exact when both are large and close).
    let shift = glam::DVec2::new(origin[0], origin[1]) - frame;
    regions
        .iter()
        .enumerate()
        .filter_map(|(i, r)| {
            let r = r.as_ref()?;
            let i = i as u32;
            let points: Vec<[f64; 2]> = r.points().iter().map(|p| [p.x, p.y]).collect();
            let origin_t = plane_t(sectors, i, shift);
            StoredRegion::from_f64(i as u16, &points, r.tail_slope(), origin_t, origin[2])
        })
        .collect()
}

/// The exported hierarchy of a grouping: nodes with f32 circles and regions, the mesh in the grouping's triangle
/// order.
pub fn export_hierarchy(tin: &Tin, crystal: &Crystal, params: &BuildParams) -> Hierarchy {
    let origin = tin.origin().to_array();
    let sectors = crystal.sectors;
    let nodes = crystal
        .hierarchy
        .nodes
        .iter()
        .map(|n| {
            let (centre, radius) = stored_circle(&n.circle, origin);
            Node {
                centre,
                radius,
                children: n.children.clone(),
                triangles: [n.range.start, n.range.end],
                level: n.level,
                regions: stored_regions(&n.regions, sectors, crystal.region_origin, origin),
            }
        })
        .collect();
    let triangles = crystal.order.iter().map(|&t| tin.triangles()[t as usize]).collect();
    Hierarchy {
        sectors,
        origin,
        nodes,
        roots: crystal.hierarchy.roots.clone(),
        always_visible: [crystal.orphan_range.start, crystal.orphan_range.end],
        mesh: Mesh {
            positions: tin.positions().iter().map(|p| p.to_array()).collect(),
            triangles,
        },
        build: BuildInfo {
            subsectors: params.subsectors,
            seeds: saturated(params.crystal.first_seeds(tin.num_triangles())),
            orphan_passes: params.crystal.orphan_passes,
            min_group: saturated(params.crystal.min_group),
            max_expanse: params.crystal.max_expanse,
            rng_seed: params.crystal.rng_seed,
            undersampling: params.undersampling,
            grouping: cull::Grouping::Crystal,
        },
    }
}

/// `n` as a `u32` count of [`BuildInfo`], `u32::MAX` when larger.
fn saturated(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

/// The exported hierarchy of a quadtree (Stewart's baseline): one root, nodes with f32 circles and regions, the
/// mesh in the quadtree's triangle order, nothing always visible, [`cull::Grouping::Quadtree`] recorded.
pub fn export_quadtree(tin: &Tin, q: &Quadtree, params: &BuildParams) -> Hierarchy {
    let origin = tin.origin().to_array();
    let nodes = q
        .nodes
        .iter()
        .map(|n| {
            let (centre, radius) = stored_circle(&n.circle, origin);
            Node {
                centre,
                radius,
                children: n.children.clone(),
                triangles: [n.range.start, n.range.end],
                level: q.level(n),
                regions: stored_regions(&n.regions, q.sectors, q.region_origin, origin),
            }
        })
        .collect();
    let triangles: Vec<[u32; 3]> = q.order.iter().map(|&t| tin.triangles()[t as usize]).collect();
    let n = triangles.len() as u32;
    Hierarchy {
        sectors: q.sectors,
        origin,
        nodes,
        roots: vec![0],
        always_visible: [n, n],
        mesh: Mesh {
            positions: tin.positions().iter().map(|p| p.to_array()).collect(),
            triangles,
        },
        build: BuildInfo {
            subsectors: params.subsectors,
            undersampling: params.undersampling,
            grouping: cull::Grouping::Quadtree {
                built_depth: q.built_depth,
                stored_depth: q.stored_depth,
            },
            ..BuildInfo::default()
        },
    }
}

/// The thesis' per-triangle mode (5.1.1) as a flat hierarchy: every triangle is its own top-level leaf with its own
/// regions and bounding circle, in the original triangle order, and nothing is always visible.
pub fn per_triangle_hierarchy(tin: &Tin, triangle_regions: &RegionTable) -> Hierarchy {
    let origin = tin.origin().to_array();
    let sectors = triangle_regions.sectors();
    let nodes: Vec<Node> = (0..tin.num_triangles() as u32)
        .map(|t| {
            let circle = tin.bounding_circle([t]).unwrap_or(Circle {
                centre: glam::DVec2::ZERO,
                radius: 0.0,
            });
            let (centre, radius) = stored_circle(&circle, origin);
            Node {
                centre,
                radius,
                children: vec![],
                triangles: [t, t + 1],
                level: 0,
                regions: stored_regions(triangle_regions.row(t), sectors, triangle_regions.origin(), origin),
            }
        })
        .collect();
    let n = nodes.len() as u32;
    Hierarchy {
        sectors,
        origin,
        nodes,
        roots: (0..n).collect(),
        always_visible: [n, n],
        mesh: Mesh {
            positions: tin.positions().iter().map(|p| p.to_array()).collect(),
            triangles: tin.triangles().to_vec(),
        },
        build: BuildInfo::default(),
    }
}

/// The height margin `μ` of [`conservative_hierarchy`]'s regions over `h`'s mesh ([`occlusion::conservative`]), and
/// the lowest and highest corners of the mesh's box: what `truth::MarginReach` needs to tell the eyes from which
/// those regions may be judged.
pub fn conservative_margin(h: &Hierarchy) -> (f64, [f64; 3], [f64; 3]) {
    let positions: Vec<glam::DVec3> = h.mesh.positions.iter().map(|&p| glam::DVec3::from_array(p)).collect();
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in &h.mesh.positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (occlusion::conservative::height_margin(&positions), lo, hi)
}

/// The work bound of [`conservative_hierarchy`], per triangle of the mesh: nodes get regions, smallest range first,
/// while the sum over them of their range's length plus one stays within this many times the mesh's triangles plus
/// [`CONSERVATIVE_WORK_CONSTANT`]. Every level of a hierarchy covers the triangles at most once, so the sum is about
/// the depth times the triangles: measured 4.09 on the hierarchy of `meshes/jacksboro-10k.obj`, 7.86 on a crater
/// lake TIN of 100,000 vertices (10 levels), 26.9 for a quadtree of the deepest depth (16) over jacksboro-10k (at
/// most 2 × 17 for any quadtree, whose nodes hold at least one triangle each). A file can hold far more (a chain of
/// nodes with one child each over the same triangles), and without a bound the work would be their product.
pub const CONSERVATIVE_WORK_PER_TRIANGLE: u64 = 64;

/// The constant part of [`conservative_hierarchy`]'s work bound (see [`CONSERVATIVE_WORK_PER_TRIANGLE`]).
pub const CONSERVATIVE_WORK_CONSTANT: u64 = 1 << 16;

/// `h` with every node's regions replaced by conservative ones ([`occlusion::conservative`]): the thesis' run-time
/// test over them never culls a visible triangle. Computed from the hierarchy's own mesh and circles (widened to
/// cover their f32 storage), so it applies to any hierarchy, crystal or not. The proof needs every point of a node
/// inside its circle, which a file does not promise (its circles are data): a circle that misses a vertex of its
/// node is replaced, here and in the result, by one computed from the vertices. With fewer than 3 sectors a sector's
/// wedge is not convex (the proof's barrier needs `cos w > 0`), so no region is made.
///
/// Nodes with the same triangle range and circle are computed once and share the result (a node's regions depend
/// only on its vertices, its circle and the mesh). The work is bounded ([`CONSERVATIVE_WORK_PER_TRIANGLE`]): nodes
/// beyond the bound, which no hierarchy that `tincull build` makes reaches, get no regions, so that both cullers
/// (`cull`'s thesis test and `pvs`'s regions test) always call them visible, and their circle is not checked but
/// replaced, unless it holds the whole mesh's box, by one around that box, so that it still holds their vertices.
pub fn conservative_hierarchy(h: &Hierarchy) -> Hierarchy {
    use std::collections::HashMap;
    let positions: Vec<glam::DVec3> = h.mesh.positions.iter().map(|&p| glam::DVec3::from_array(p)).collect();
    let order: Vec<u32> = (0..h.mesh.triangles.len() as u32).collect();
    let [ox, oy, oz] = h.origin;
    let mut out = h.clone();
    let within = within_work_bound(h);
    // The whole mesh's box, for the circles of the nodes beyond the bound.
    let (mut lo, mut hi) = (glam::DVec2::splat(f64::INFINITY), glam::DVec2::splat(f64::NEG_INFINITY));
    for p in &positions {
        lo = lo.min(p.truncate());
        hi = hi.max(p.truncate());
    }
    let corners = [lo, glam::DVec2::new(hi.x, lo.y), glam::DVec2::new(lo.x, hi.y), hi];
    let mesh_circle = tin::bounding_circle_of_points(&corners).map(|c| Circle {
        centre: c.centre,
        radius: c.radius * (1.0 + 1e-9) + 1e-12 * (c.centre.x.abs() + c.centre.y.abs()) + 1e-9,
    });
    // The circle each node's regions are computed for (`None` beyond the bound), checked once per range and stored
    // circle (its bits): that circle, and the one to store where the stored one misses a vertex.
    type Checked = (glam::DVec2, f64, Option<([f32; 2], f32)>);
    let mut checked: HashMap<([u32; 2], [u32; 3]), Checked> = HashMap::new();
    let mut circles: Vec<Option<(glam::DVec2, f64)>> = Vec::with_capacity(h.nodes.len());
    for ((n, stored), &inside) in h.nodes.iter().zip(out.nodes.iter_mut()).zip(&within) {
        let centre = glam::DVec2::new(ox + f64::from(n.centre[0]), oy + f64::from(n.centre[1]));
        // The world centre is rounded once (relative error ε): grow the radius by far more.
        let slack = 1e-12 * (centre.x.abs() + centre.y.abs()) + 1e-9;
        let radius = f64::from(n.radius) + slack;
        if !inside {
            let holds_mesh = corners.iter().all(|p| p.distance(centre) * (1.0 + 1e-12) <= radius);
            if !holds_mesh && let Some(c) = &mesh_circle {
                (stored.centre, stored.radius) = stored_circle(c, h.origin);
            }
            circles.push(None);
            continue;
        }
        let key = (
            n.triangles,
            [n.centre[0].to_bits(), n.centre[1].to_bits(), n.radius.to_bits()],
        );
        let &mut (centre, radius, replaced) = checked.entry(key).or_insert_with(|| {
            let range = &h.mesh.triangles[n.triangles[0] as usize..n.triangles[1] as usize];
            let points = || range.iter().flatten().map(|&v| positions[v as usize].truncate());
            // Inside, the computed distance grown for its own rounding (a built file's circles pass: their slack
            // above is far more).
            if points().all(|p| p.distance(centre) * (1.0 + 1e-15) <= radius) {
                return (centre, radius, None);
            }
            match tin::bounding_circle_of_points(&points().collect::<Vec<_>>()) {
                Some(c) => {
                    let slack = 1e-12 * (c.centre.x.abs() + c.centre.y.abs()) + 1e-9;
                    (
                        c.centre,
                        c.radius * (1.0 + 1e-12) + slack,
                        Some(stored_circle(&c, h.origin)),
                    )
                }
                None => (centre, radius, None),
            }
        });
        if let Some(c) = replaced {
            (stored.centre, stored.radius) = c;
        }
        circles.push(Some((centre, radius)));
    }
    for node in &mut out.nodes {
        node.regions.clear();
    }
    if h.sectors < 3 {
        return out;
    }
    // One shape per range and circle; `of_node[i]` is node `i`'s shape.
    let mut shape_of: HashMap<([u32; 2], [u64; 3]), usize> = HashMap::new();
    let mut shapes: Vec<occlusion::NodeShape> = Vec::new();
    let of_node: Vec<Option<usize>> = h
        .nodes
        .iter()
        .zip(&circles)
        .map(|(n, circle)| {
            let &(centre, radius) = circle.as_ref()?;
            let key = (n.triangles, [centre.x.to_bits(), centre.y.to_bits(), radius.to_bits()]);
            Some(*shape_of.entry(key).or_insert_with(|| {
                shapes.push(occlusion::NodeShape {
                    triangles: &order[n.triangles[0] as usize..n.triangles[1] as usize],
                    centre,
                    radius,
                });
                shapes.len() - 1
            }))
        })
        .collect();
    let stored: Vec<Vec<StoredRegion>> =
        occlusion::conservative_regions(&positions, &h.mesh.triangles, &shapes, h.sectors)
            .into_iter()
            .map(|row| {
                row.into_iter()
                    .filter_map(|(i, (points, tail))| {
                        let origin_t = occlusion::plane_t(h.sectors, i, glam::DVec2::new(ox, oy));
                        StoredRegion::from_f64(i as u16, &points, tail, origin_t, oz)
                    })
                    .collect()
            })
            .collect();
    for (node, shape) in out.nodes.iter_mut().zip(of_node) {
        if let Some(k) = shape {
            node.regions = stored[k].clone();
        }
    }
    out
}

/// Which nodes of `h` [`conservative_hierarchy`] gives regions: smallest range first (then by index), while the sum
/// of their ranges' lengths plus one stays within the bound of [`CONSERVATIVE_WORK_PER_TRIANGLE`].
fn within_work_bound(h: &Hierarchy) -> Vec<bool> {
    let cost = |i: usize| u64::from(h.nodes[i].triangles[1].saturating_sub(h.nodes[i].triangles[0])) + 1;
    let bound = CONSERVATIVE_WORK_PER_TRIANGLE * h.mesh.triangles.len() as u64 + CONSERVATIVE_WORK_CONSTANT;
    let mut by_cost: Vec<usize> = (0..h.nodes.len()).collect();
    by_cost.sort_by_key(|&i| (cost(i), i));
    let mut within = vec![false; h.nodes.len()];
    let mut spent = 0u64;
    for i in by_cost {
        spent += cost(i);
        if spent > bound {
            break;
        }
        within[i] = true;
    }
    within
}
