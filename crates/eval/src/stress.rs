//! Stability suite: where the methods fail (the README's "Accuracy: how it is measured"; thesis 5.1.2 on undersampling,
//! 6.3 on sector counts and crystal seeds).
//!
//! Every case runs the whole pipeline ([`pipeline`]) on one terrain with one set of parameters, checks the
//! exported hierarchy's invariants, then scores the `hierarchy` culler against ground truth ([`truth::GroundTruth`])
//! from a set of viewpoints, always all around (360°). The cases:
//!
//! | category | cases |
//! | --- | --- |
//! | `baseline` | the input mesh with the default parameters (16 × 4 sectors) |
//! | `sectors` | too few sectors (4 × 1, 8 × 1); too thin sectors (64 × 4, 128 × 1), each with and without the undersampling fix at a radius of 2 × the mean edge length |
//! | `geometry` | slivers (few widely spaced rows of dense points, Delaunay), a one-vertex-wide knife-edge ridge, isolated spikes, a near-vertical cliff (0.01 m horizontal for 100 m of rise), the input mesh terraced (heights rounded down to 8 levels: plateaus of exactly level triangles), the input mesh's diagonals flipped (its vertices triangulated not Delaunay, as a mesh's own faces may be) |
//! | `flat` | a perfectly flat grid (all points cocircular in groups of four); Crater Lake simplified (a flat lake) when `../shared/dem/crater_lake.npy` exists |
//! | `coords` | the mesh offset by (5e5, 5e6, 0), (5e6, 5e6, 1000) and (1e7, 1e7, 0); the mesh and its eyes scaled uniformly by 1e-4 and 1e3 (the same views); vertical exaggeration × 0.01 and × 100; the terrain upside down (z × −1: every valley a ridge, every ridge a valley) |
//! | `viewpoints` | eyes exactly on a vertex, on an edge midpoint, at ground level, 10 m below the surface, far outside the footprint, 1e6 m up, and at sector-boundary azimuths from group centres |
//! | `seeds` | the crystal grouping with 20 random seeds (5 with `quick`): spread of groups, orphans, occlusion captured |
//!
//! Choices:
//!
//! - Viewpoints: the six classes of [`truth::viewpoints()`] with `viewpoints` eyes each, seed 1; the same eyes
//!   (translated) for the offset cases, so they compare drawn sets viewpoint by viewpoint with the baseline
//!   (`drawn_diff`: the number of (viewpoint, triangle) pairs whose drawn flag differs, triangles identified by
//!   their original index).
//! - A buried eye: ground truth sees nothing (`V = ∅`), so it can have no false cull; the culler has no notion of
//!   the ground and answers from the regions (an eye below the surface is inside most regions, so most groups are
//!   culled). Both are defined results and recorded as such.
//! - Failures of a build (an error, not a panic) are recorded as the case's outcome, never hidden; so are false
//!   culls.

use std::f64::consts::TAU;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use cull::{Camera, Culler, DrawList, Hierarchy, SafeCuller, SafeParams};
use glam::{DVec2, DVec3};
use horizon::{HorizonOptions, SectorConfig};
use occlusion::RegionTable;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use tin::{DedupePolicy, Tin};
use truth::{GroundTruth, ViewpointClass, view_metrics};

use pipeline::{BuildParams, build, export_hierarchy};

/// What the stability suite runs.
#[derive(Clone, Debug, Serialize)]
pub struct StressOptions {
    /// Viewpoints per class (six classes) for the ordinary cases, and per kind for the degenerate viewpoints.
    pub viewpoints: usize,
    /// Smaller synthetic terrains, fewer seeds and a smaller Crater Lake.
    pub quick: bool,
    /// Directory of the real DEMs (`crater_lake.npy`); the case is skipped when the file is missing.
    pub dem_dir: Option<PathBuf>,
}

impl Default for StressOptions {
    fn default() -> Self {
        StressOptions {
            viewpoints: 10,
            quick: false,
            dem_dir: None,
        }
    }
}

/// Outcome of one case.
#[derive(Clone, Debug, Default, Serialize)]
pub struct CaseResult {
    /// Short name of the case.
    pub name: String,
    /// Category (see the module table).
    pub category: String,
    /// `ok`, `skipped` or `error` (the build failed with an error; the message is in `note`).
    pub status: String,
    /// What was done and what it shows.
    pub note: String,
    /// Vertices of the terrain.
    pub vertices: usize,
    /// Triangles of the terrain.
    pub triangles: usize,
    /// Sectors of the build.
    pub sectors: u32,
    /// Subsectors per sector of the build.
    pub subsectors: u32,
    /// Undersampling-fix radius used (m).
    pub undersampling: Option<f64>,
    /// Wall time of the build (s).
    pub build_seconds: f64,
    /// Leaf groups.
    pub groups: usize,
    /// Orphan (always-visible) triangles.
    pub orphans: usize,
    /// Whether [`Hierarchy::check_invariants`] passed (and the file round trip); `None` for a case that built nothing
    /// (`skipped` or `error`), whose build and score figures are 0.
    pub invariants_ok: Option<bool>,
    /// Viewpoints scored.
    pub viewpoints: usize,
    /// Mean false culls per viewpoint.
    pub false_culls_mean: f64,
    /// Largest false culls of one viewpoint.
    pub false_culls_max: usize,
    /// Viewpoints with at least one false cull.
    pub viewpoints_with_false_culls: usize,
    /// Largest falsely culled area of one viewpoint (m²).
    pub false_cull_area_max: f64,
    /// Mean occlusion captured over the viewpoints with something hidden (`None`: nothing hidden anywhere).
    pub occlusion_captured_mean: Option<f64>,
    /// Mean triangles culled per viewpoint.
    pub culled_mean: f64,
    /// Mean ground-truth visible triangles per viewpoint.
    pub visible_mean: f64,
    /// The safe culler (`cull::SafeCuller`) on the same hierarchy and viewpoints: largest false culls of one
    /// viewpoint (0 is its theorem).
    pub safe_false_culls_max: usize,
    /// The safe culler's mean occlusion captured (`None`: nothing hidden anywhere).
    pub safe_occlusion_captured_mean: Option<f64>,
    /// For cases compared with a reference (offsets): (viewpoint, triangle) pairs whose drawn flag differs.
    pub drawn_diff: Option<usize>,
    /// For cases compared with a reference: difference in leaf groups.
    pub groups_diff: Option<i64>,
}

/// Minimum, median and maximum of one figure over the seeds.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Spread {
    /// Smallest value.
    pub min: f64,
    /// Median (lower middle for an even count).
    pub median: f64,
    /// Largest value.
    pub max: f64,
}

impl Spread {
    fn of(values: &[f64]) -> Spread {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| !x.is_nan()).collect();
        if v.is_empty() {
            return Spread::default();
        }
        v.sort_by(f64::total_cmp);
        Spread {
            min: v[0],
            median: v[(v.len() - 1) / 2],
            max: v[v.len() - 1],
        }
    }
}

/// One crystal seed of the seed study.
#[derive(Clone, Debug, Serialize)]
pub struct SeedRow {
    /// The crystal `rng_seed`.
    pub rng_seed: u64,
    /// Leaf groups.
    pub groups: usize,
    /// Orphans.
    pub orphans: usize,
    /// Mean occlusion captured.
    pub occlusion_captured: Option<f64>,
    /// Largest false culls of one viewpoint.
    pub false_culls_max: usize,
}

/// The seed study: the same horizons and regions grouped with different random seeds.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SeedSpread {
    /// Per seed.
    pub seeds: Vec<SeedRow>,
    /// Spread of leaf groups.
    pub groups: Spread,
    /// Spread of orphans.
    pub orphans: Spread,
    /// Spread of the mean occlusion captured.
    pub occlusion_captured: Spread,
    /// Largest false culls of one viewpoint over all seeds.
    pub false_culls_max: usize,
}

/// The whole suite's result.
#[derive(Clone, Debug, Serialize)]
pub struct StressReport {
    /// The input mesh's name.
    pub mesh: String,
    /// Options used.
    pub options: StressOptions,
    /// Every case, in run order.
    pub cases: Vec<CaseResult>,
    /// The seed study.
    pub seeds: SeedSpread,
    /// Wall time of the whole suite (s).
    pub seconds: f64,
}

/// A labelled eye.
type Eye = (String, DVec3);

/// A finished build with what the scoring needs.
struct Built {
    hierarchy: Hierarchy,
    /// Original triangle index of each position in the hierarchy's triangle order.
    order: Vec<u32>,
    groups: usize,
    orphans: usize,
    seconds: f64,
    invariants: Result<(), String>,
}

/// Per-viewpoint scores plus the drawn masks (original triangle order).
struct Scores {
    metrics: Vec<truth::ViewMetrics>,
    masks: Vec<Vec<bool>>,
    /// The safe culler's metrics from the same viewpoints.
    safe: Vec<truth::ViewMetrics>,
}

fn build_case(tin: &Tin, params: &BuildParams) -> Result<Built> {
    let start = Instant::now();
    let b = build(tin, params, None)?;
    let seconds = start.elapsed().as_secs_f64();
    let invariants = check(&b.hierarchy);
    Ok(Built {
        groups: b.report.groups,
        orphans: b.report.orphans,
        order: b.order.clone(),
        hierarchy: b.hierarchy,
        seconds,
        invariants,
    })
}

/// Invariants, and the same after a round trip through the file format.
fn check(h: &Hierarchy) -> Result<(), String> {
    h.check_invariants().map_err(|e| e.to_string())?;
    let bytes = h.to_bytes().map_err(|e| e.to_string())?;
    let back = Hierarchy::from_bytes(&bytes).map_err(|e| e.to_string())?;
    if &back != h {
        return Err("the hierarchy changed in a file round trip".into());
    }
    Ok(())
}

/// Scores the hierarchy culler of `b` against ground truth on `tin` (original order) from `eyes`.
fn score(tin: &Tin, truth: &GroundTruth, b: &Built, eyes: &[Eye]) -> Result<Scores> {
    let culler = Culler::new(&b.hierarchy);
    let safe = SafeCuller::new(&b.hierarchy, SafeParams::default());
    let n = tin.num_triangles();
    let mut metrics = Vec::with_capacity(eyes.len());
    let mut safe_metrics = Vec::with_capacity(eyes.len());
    let mut masks = Vec::with_capacity(eyes.len());
    let mut list = DrawList::default();
    // The culler's mask in the TIN's original triangle order.
    let in_tin_order = |in_order: Vec<bool>| {
        let mut drawn = vec![false; n];
        for (pos, &t) in b.order.iter().enumerate() {
            if let (Some(d), Some(&m)) = (drawn.get_mut(t as usize), in_order.get(pos)) {
                *d = m;
            }
        }
        drawn
    };
    for (_, eye) in eyes {
        let visible = truth.visible_triangles(*eye);
        let camera = Camera::all_around(eye.to_array());
        let drawn = in_tin_order(culler.cull(&camera).mask(n));
        metrics.push(view_metrics(tin, &visible, &drawn)?);
        masks.push(drawn);
        safe.cull_into(&camera, &mut list);
        safe_metrics.push(view_metrics(tin, &visible, &in_tin_order(list.mask(n)))?);
    }
    Ok(Scores {
        metrics,
        masks,
        safe: safe_metrics,
    })
}

fn fill(case: &mut CaseResult, tin: &Tin, params: &BuildParams, b: &Built, s: &Scores) {
    case.vertices = tin.num_vertices();
    case.triangles = tin.num_triangles();
    (case.sectors, case.subsectors) = (params.sectors, params.subsectors);
    case.undersampling = params.undersampling;
    case.build_seconds = b.seconds;
    case.groups = b.groups;
    case.orphans = b.orphans;
    case.invariants_ok = Some(b.invariants.is_ok());
    if let Err(e) = &b.invariants {
        case.note = format!("INVARIANTS BROKEN: {e}; {}", case.note);
    }
    let m = &s.metrics;
    case.viewpoints = m.len();
    let k = m.len().max(1) as f64;
    case.false_culls_mean = m.iter().map(|v| v.false_culls as f64).sum::<f64>() / k;
    case.false_culls_max = m.iter().map(|v| v.false_culls).max().unwrap_or(0);
    case.viewpoints_with_false_culls = m.iter().filter(|v| v.false_culls > 0).count();
    case.false_cull_area_max = m.iter().map(|v| v.false_cull_area).fold(0.0, f64::max);
    let occ: Vec<f64> = m.iter().filter_map(|v| v.occlusion_captured).collect();
    case.occlusion_captured_mean = (!occ.is_empty()).then(|| occ.iter().sum::<f64>() / occ.len() as f64);
    case.culled_mean = m.iter().map(|v| v.culled as f64).sum::<f64>() / k;
    case.visible_mean = m.iter().map(|v| v.visible as f64).sum::<f64>() / k;
    case.safe_false_culls_max = s.safe.iter().map(|v| v.false_culls).max().unwrap_or(0);
    let occ: Vec<f64> = s.safe.iter().filter_map(|v| v.occlusion_captured).collect();
    case.safe_occlusion_captured_mean = (!occ.is_empty()).then(|| occ.iter().sum::<f64>() / occ.len() as f64);
    case.status = "ok".into();
}

/// Runs one case from scratch: build, check, score. A failed build is recorded, not returned.
fn run_case(
    name: &str,
    category: &str,
    note: &str,
    tin: &Tin,
    params: &BuildParams,
    eyes: &[Eye],
) -> (CaseResult, Option<Scores>) {
    let mut case = CaseResult {
        name: name.into(),
        category: category.into(),
        note: note.into(),
        vertices: tin.num_vertices(),
        triangles: tin.num_triangles(),
        sectors: params.sectors,
        subsectors: params.subsectors,
        undersampling: params.undersampling,
        ..CaseResult::default()
    };
    let outcome = build_case(tin, params).and_then(|b| {
        let truth = GroundTruth::new(tin);
        let s = score(tin, &truth, &b, eyes)?;
        Ok((b, s))
    });
    match outcome {
        Ok((b, s)) => {
            fill(&mut case, tin, params, &b, &s);
            (case, Some(s))
        }
        Err(e) => {
            case.status = "error".into();
            case.note = format!("build failed: {e:#}");
            (case, None)
        }
    }
}

/// The six classes' viewpoints, `n` each.
pub fn standard_eyes(tin: &Tin, n: usize) -> Vec<(String, DVec3)> {
    ViewpointClass::ALL
        .iter()
        .enumerate()
        .flat_map(|(i, &c)| {
            truth::viewpoints(tin, c, n, 1 + i as u64)
                .into_iter()
                .map(move |p| (c.name().to_string(), p))
        })
        .collect()
}

/// Mean 3-D length of the TIN's edges (each shared edge counted twice).
pub fn mean_edge_length(tin: &Tin) -> f64 {
    let mut sum = 0.0;
    let mut count = 0usize;
    for t in 0..tin.num_triangles() {
        let c = tin.corners(t);
        for i in 0..3 {
            sum += (c[i] - c[(i + 1) % 3]).length();
            count += 1;
        }
    }
    sum / count.max(1) as f64
}

/// The TIN with every position mapped by `f` (same triangles).
pub fn map_tin(tin: &Tin, f: impl Fn(DVec3) -> DVec3) -> Result<Tin> {
    let positions = tin.positions().iter().map(|&p| f(p)).collect();
    Ok(Tin::from_parts(positions, tin.triangles().to_vec())?)
}

fn delaunay(points: Vec<DVec3>) -> Result<Tin> {
    Ok(tin::triangulate(&points, DedupePolicy::Reject)?.0)
}

/// A TIN of slivers: `rows` rows 300 m apart, each of `cols` points 3 m apart, over a rolling surface.
pub fn sliver_tin(rows: usize, cols: usize) -> Result<Tin> {
    let mut pts = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            let (x, y) = (3.0 * c as f64, 300.0 * r as f64);
            let z = 40.0 * (x / 40.0).sin() * (1.0 + 0.5 * (y / 500.0).cos()) + 20.0 * r as f64;
            pts.push(DVec3::new(x, y, z));
        }
    }
    delaunay(pts)
}

/// An `n × n` grid 10 m apart with heights `z(col, row)`.
pub fn grid_tin(n: usize, z: impl Fn(usize, usize) -> f64) -> Result<Tin> {
    let mut pts = Vec::with_capacity(n * n);
    for r in 0..n {
        for c in 0..n {
            pts.push(DVec3::new(10.0 * c as f64, 10.0 * r as f64, z(c, r)));
        }
    }
    delaunay(pts)
}

/// A flat plain with a ridge one vertex wide (the middle column, 80 m high).
pub fn knife_edge_tin(n: usize) -> Result<Tin> {
    grid_tin(n, |c, _| if c == n / 2 { 80.0 } else { 0.0 })
}

/// A gently rolling plain with five isolated one-vertex spikes 150 m high.
pub fn spikes_tin(n: usize) -> Result<Tin> {
    let spikes = [
        (n / 4, n / 4),
        (3 * n / 4, n / 4),
        (n / 2, n / 2),
        (n / 4, 3 * n / 4),
        (3 * n / 4, 3 * n / 4),
    ];
    grid_tin(n, |c, r| {
        let base = 3.0 * (c as f64 * 0.4).sin() * (r as f64 * 0.3).cos();
        if spikes.contains(&(c, r)) { base + 150.0 } else { base }
    })
}

/// A step: a low plain, then a wall rising 100 m over 0.01 m horizontally, then a high plain.
pub fn cliff_tin(n: usize) -> Result<Tin> {
    let mut pts = Vec::new();
    let wall = 10.0 * (n / 2) as f64;
    for r in 0..n {
        for c in 0..n {
            let x = 10.0 * c as f64;
            let y = 10.0 * r as f64;
            let undulate = 2.0 * (y / 37.0).sin();
            pts.push(DVec3::new(x, y, if x <= wall { undulate } else { 100.0 + undulate }));
        }
        pts.push(DVec3::new(
            wall + 0.01,
            10.0 * r as f64,
            100.0 + 2.0 * (10.0 * r as f64 / 37.0).sin(),
        ));
    }
    delaunay(pts)
}

/// A perfectly flat grid (z = 0).
pub fn flat_tin(n: usize) -> Result<Tin> {
    grid_tin(n, |_, _| 0.0)
}

/// `tin` terraced: every height rounded down to one of `levels` levels spread evenly over its range, on the same
/// triangulation, so the plateaus are exactly level triangles and the steps between them steep ones (a flat mesh stays
/// as it is).
pub fn terraces_tin(tin: &Tin, levels: u32) -> Result<Tin> {
    let (lo, hi) = tin
        .positions()
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.z), hi.max(p.z))
        });
    let step = (hi - lo) / f64::from(levels.max(1));
    if step.is_nan() || step <= 0.0 {
        return map_tin(tin, |p| p);
    }
    map_tin(tin, |p| {
        DVec3::new(
            p.x,
            p.y,
            lo + ((p.z - lo) / step).floor().min(f64::from(levels - 1)) * step,
        )
    })
}

/// `tin` with its diagonals flipped: in triangle order, every interior edge whose two triangles are both still as
/// they were and form a strictly convex quadrilateral is replaced by the quadrilateral's other diagonal. The same
/// vertices on a triangulation that is not Delaunay (a flipped edge breaks the empty-circle property unless its four
/// points are cocircular), as a mesh's own faces read with `--keep-faces` may be: thinner triangles, edges across
/// valleys and ridges.
pub fn flipped_tin(tin: &Tin) -> Result<Tin> {
    let pos = tin.positions();
    let xy = |v: u32| pos[v as usize].truncate();
    let neighbours = tin.neighbours();
    let mut tris = tin.triangles().to_vec();
    let mut touched = vec![false; tris.len()];
    for t in 0..tris.len() {
        for k in 0..3 {
            let u = neighbours[t][k];
            if touched[t] || u == tin::NO_NEIGHBOUR || touched[u as usize] {
                continue;
            }
            // `t` is (p, q, r) counter-clockwise with the shared edge p → q; its neighbour holds q, p and s, so the
            // quadrilateral is p, s, q, r counter-clockwise, convex at p and q when both new triangles are.
            let (p, q, r) = (tris[t][k], tris[t][(k + 1) % 3], tris[t][(k + 2) % 3]);
            let Some(&s) = tris[u as usize].iter().find(|&&v| v != p && v != q) else {
                continue;
            };
            if tin::orient2d(xy(p), xy(s), xy(r)) > 0.0 && tin::orient2d(xy(s), xy(q), xy(r)) > 0.0 {
                tris[t] = [p, s, r];
                tris[u as usize] = [s, q, r];
                touched[t] = true;
                touched[u as usize] = true;
            }
        }
    }
    Ok(Tin::from_parts(pos.to_vec(), tris)?)
}

/// Crater Lake simplified to `vertices` vertices, or `None` when the DEM is missing.
pub fn crater_lake_tin(dem_dir: &Path, vertices: usize) -> Result<Option<Tin>> {
    let path = dem_dir.join("crater_lake.npy");
    if !path.exists() {
        return Ok(None);
    }
    let grid = tin::read_dem(&path, &tin::DemOptions::default())?;
    let (t, _) = tin::simplify(&grid, &tin::SimplifyOptions::vertices(vertices), None)?;
    Ok(Some(t))
}

/// Interior vertices (not on the hull): vertices all of whose triangles have three neighbours.
fn interior_vertices(tin: &Tin) -> Vec<u32> {
    let vt = tin.vertex_triangles();
    (0..tin.num_vertices() as u32)
        .filter(|&v| {
            let ts = vt.of(v);
            !ts.is_empty()
                && ts.iter().all(|&t| {
                    let tri = tin.triangles()[t as usize];
                    let nb = tin.neighbours()[t as usize];
                    (0..3).all(|i| {
                        // The edge opposite corner i touches v unless corner i is v.
                        tri[i] == v || nb[i] != tin::NO_NEIGHBOUR
                    })
                })
        })
        .collect()
}

/// The degenerate viewpoint sets over `tin` with the baseline hierarchy `h`: (case name, note, eyes).
fn degenerate_eyes(tin: &Tin, h: &Hierarchy, n: usize) -> Vec<(&'static str, &'static str, Vec<Eye>)> {
    let truth = GroundTruth::new(tin);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let b = tin.bbox();
    let extent = (b.max.x - b.min.x).max(b.max.y - b.min.y);
    let centre = (b.min + b.max) * 0.5;
    let inner = interior_vertices(tin);
    let pick = |rng: &mut ChaCha8Rng, len: usize| rng.random_range(0..len.max(1));
    let label = |s: &str| s.to_string();

    let on_vertex: Vec<Eye> = (0..n)
        .filter_map(|_| inner.get(pick(&mut rng, inner.len())))
        .map(|&v| (label("vertex"), tin.position(v)))
        .collect();
    let on_edge: Vec<Eye> = (0..n)
        .filter_map(|_| {
            let t = pick(&mut rng, tin.num_triangles());
            let c = tin.corners(t);
            (tin.num_triangles() > 0).then(|| (label("edge"), (c[0] + c[1]) * 0.5))
        })
        .collect();
    let ground = truth::viewpoints(tin, ViewpointClass::Ground, n, 11);
    let at_ground: Vec<Eye> = ground.iter().map(|p| (label("ground"), *p - DVec3::Z * 2.0)).collect();
    let buried: Vec<Eye> = ground.iter().map(|p| (label("buried"), *p - DVec3::Z * 12.0)).collect();
    let far: Vec<Eye> = (0..n)
        .map(|i| {
            let a = TAU * i as f64 / n as f64 + 0.1;
            let z = if i % 2 == 0 { b.max.z + 2.0 } else { b.min.z };
            let p = centre + DVec3::new(a.cos(), a.sin(), 0.0) * (10.0 * extent);
            (label("far"), DVec3::new(p.x, p.y, z))
        })
        .collect();
    let high: Vec<Eye> = ground
        .iter()
        .map(|p| (label("high"), DVec3::new(p.x, p.y, b.max.z + 1e6)))
        .collect();
    let mut boundary = Vec::new();
    let leaves: Vec<&cull::Node> = h.nodes.iter().filter(|nd| nd.children.is_empty()).collect();
    for i in 0..n {
        let Some(nd) = leaves.get(pick(&mut rng, leaves.len())) else {
            break;
        };
        let k = rng.random_range(0..h.sectors);
        let a = TAU * f64::from(k) / f64::from(h.sectors);
        let c = DVec2::new(
            h.origin[0] + f64::from(nd.centre[0]),
            h.origin[1] + f64::from(nd.centre[1]),
        );
        let d = f64::from(nd.radius) * (1.5 + i as f64 % 3.0);
        let p = c + DVec2::new(a.cos(), a.sin()) * d;
        let z = truth.locator().ground_height(tin, p).map_or(b.max.z + 2.0, |g| g + 2.0);
        boundary.push((label("boundary"), DVec3::new(p.x, p.y, z)));
    }
    vec![
        (
            "eye on a vertex",
            "eye exactly at an interior vertex's position",
            on_vertex,
        ),
        ("eye on an edge", "eye exactly at an edge midpoint", on_edge),
        ("eye at ground level", "eye on the surface (z = ground)", at_ground),
        (
            "eye below surface",
            "10 m below ground: truth sees nothing (V empty), so no false cull is possible; the culler answers from the regions",
            buried,
        ),
        (
            "eye far outside",
            "10 x the extent from the centre, at max z + 2 or min z",
            far,
        ),
        ("eye very high", "1e6 m above the highest vertex", high),
        (
            "eye at sector boundary",
            "from a leaf centre along a sector-boundary azimuth, 1.5-3.5 radii out, 2 m above ground",
            boundary,
        ),
    ]
}

fn spread_study(tin: &Tin, params: &BuildParams, eyes: &[Eye], seeds: u64) -> Result<SeedSpread> {
    let config = SectorConfig::new(params.sectors, params.subsectors)?;
    let field = horizon::compute(
        tin,
        &config,
        &HorizonOptions {
            undersampling_radius: params.undersampling,
            progress: None,
        },
    )?;
    let vertex_regions = RegionTable::from_field(tin.positions(), &field);
    let truth = GroundTruth::new(tin);
    let mut rows = Vec::new();
    for seed in 1..=seeds {
        let mut p = params.clone();
        p.crystal.rng_seed = seed;
        let start = Instant::now();
        let c = crystal::build(tin, &vertex_regions, &p.crystal)?;
        let h = export_hierarchy(tin, &c, &p);
        let b = Built {
            invariants: check(&h),
            hierarchy: h,
            order: c.order.clone(),
            groups: c.stats.groups,
            orphans: c.stats.orphans,
            seconds: start.elapsed().as_secs_f64(),
        };
        if let Err(e) = &b.invariants {
            anyhow::bail!("seed {seed}: invariants broken: {e}");
        }
        let s = score(tin, &truth, &b, eyes)?;
        let occ: Vec<f64> = s.metrics.iter().filter_map(|m| m.occlusion_captured).collect();
        rows.push(SeedRow {
            rng_seed: seed,
            groups: b.groups,
            orphans: b.orphans,
            occlusion_captured: (!occ.is_empty()).then(|| occ.iter().sum::<f64>() / occ.len() as f64),
            false_culls_max: s.metrics.iter().map(|m| m.false_culls).max().unwrap_or(0),
        });
    }
    let col = |f: &dyn Fn(&SeedRow) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    Ok(SeedSpread {
        groups: Spread::of(&col(&|r| r.groups as f64)),
        orphans: Spread::of(&col(&|r| r.orphans as f64)),
        occlusion_captured: Spread::of(&col(&|r| r.occlusion_captured.unwrap_or(f64::NAN))),
        false_culls_max: rows.iter().map(|r| r.false_culls_max).max().unwrap_or(0),
        seeds: rows,
    })
}

/// Number of (viewpoint, triangle) pairs where two sets of drawn masks differ.
fn mask_diff(a: &Scores, b: &Scores) -> usize {
    a.masks
        .iter()
        .zip(&b.masks)
        .map(|(x, y)| x.iter().zip(y).filter(|(p, q)| p != q).count())
        .sum()
}

/// Runs the whole suite on `tin` (named `mesh`). `progress` is called with each case's name before it runs.
pub fn run(tin: &Tin, mesh: &str, opts: &StressOptions, progress: &dyn Fn(&str)) -> Result<StressReport> {
    let start = Instant::now();
    anyhow::ensure!(opts.viewpoints > 0, "at least one viewpoint per class is needed");
    let n = opts.viewpoints;
    let eyes = standard_eyes(tin, n);
    let default = BuildParams::default();
    let mut cases = Vec::new();

    progress("baseline");
    let (base_case, base_scores) = run_case("baseline", "baseline", "default parameters", tin, &default, &eyes);
    cases.push(base_case);

    // Sectors.
    let fix = 2.0 * mean_edge_length(tin);
    let sector_cases: [(u32, u32, Option<f64>); 6] = [
        (4, 1, None),
        (8, 1, None),
        (64, 4, None),
        (64, 4, Some(fix)),
        (128, 1, None),
        (128, 1, Some(fix)),
    ];
    for (s, k, u) in sector_cases {
        let name = match u {
            Some(_) => format!("{s}x{k} sectors + fix"),
            None => format!("{s}x{k} sectors"),
        };
        progress(&name);
        let note = match (s, u) {
            (..=8, _) => "too few sectors: wide sectors, conservative regions".to_string(),
            (_, None) => "thin sectors: horizons undersampled between vertices".to_string(),
            (_, Some(r)) => format!("thin sectors with the undersampling fix, radius {r:.1} m (2 x mean edge)"),
        };
        let p = BuildParams {
            sectors: s,
            subsectors: k,
            undersampling: u,
            ..default.clone()
        };
        cases.push(run_case(&name, "sectors", &note, tin, &p, &eyes).0);
    }

    // Geometry.
    let g = if opts.quick { 21 } else { 41 };
    let geometry: Vec<(&str, &str, Result<Tin>)> = vec![
        (
            "slivers",
            "rows 300 m apart, points 3 m apart along them (aspect ~100)",
            sliver_tin(if opts.quick { 4 } else { 6 }, if opts.quick { 80 } else { 200 }),
        ),
        (
            "knife-edge ridge",
            "one-vertex-wide ridge 80 m high on a flat plain",
            knife_edge_tin(g),
        ),
        (
            "isolated spikes",
            "five one-vertex spikes 150 m high on a rolling plain",
            spikes_tin(g),
        ),
        (
            "near-vertical cliff",
            "100 m rise over 0.01 m horizontally",
            cliff_tin(g),
        ),
        ("flat terrain", "perfectly flat grid, cocircular points", flat_tin(g)),
        (
            "terraces",
            "the input mesh's heights rounded down to 8 levels: level plateaus, steep steps",
            terraces_tin(tin, 8),
        ),
        (
            "flipped diagonals",
            "the input mesh's vertices, triangulated not Delaunay: every convex quadrilateral's diagonal flipped",
            flipped_tin(tin),
        ),
    ];
    for (name, note, t) in geometry {
        progress(name);
        let category = if name == "flat terrain" { "flat" } else { "geometry" };
        match t {
            Ok(t) => {
                let e = standard_eyes(&t, n);
                cases.push(run_case(name, category, note, &t, &default, &e).0);
            }
            Err(e) => cases.push(CaseResult {
                name: name.into(),
                category: category.into(),
                status: "error".into(),
                note: format!("construction failed: {e:#}"),
                ..CaseResult::default()
            }),
        }
    }

    progress("crater lake");
    let lake_vertices = if opts.quick { 1500 } else { 5000 };
    match opts.dem_dir.as_deref().map(|d| crater_lake_tin(d, lake_vertices)) {
        Some(Ok(Some(t))) => {
            let e = standard_eyes(&t, n);
            let note =
                format!("Crater Lake simplified to {lake_vertices} vertices: flat lake, steep rim, UTM coordinates");
            cases.push(run_case("crater lake", "flat", &note, &t, &default, &e).0);
        }
        Some(Err(e)) => cases.push(CaseResult {
            name: "crater lake".into(),
            category: "flat".into(),
            status: "error".into(),
            note: format!("reading or simplifying the DEM failed: {e:#}"),
            ..CaseResult::default()
        }),
        Some(Ok(None)) | None => cases.push(CaseResult {
            name: "crater lake".into(),
            category: "flat".into(),
            status: "skipped".into(),
            note: match opts.dem_dir.as_deref() {
                Some(d) => format!("{} not found", d.join("crater_lake.npy").display()),
                None => "runs with --dem-dir DIR (a folder holding crater_lake.npy)".into(),
            },
            ..CaseResult::default()
        }),
    }

    // Coordinates.
    for off in [
        DVec3::new(5e5, 5e6, 0.0),
        DVec3::new(5e6, 5e6, 1000.0),
        DVec3::new(1e7, 1e7, 0.0),
    ] {
        let name = format!("offset {:.0e},{:.0e},{}", off.x, off.y, off.z);
        progress(&name);
        let t = map_tin(tin, |p| p + off)?;
        let e: Vec<Eye> = eyes.iter().map(|(l, p)| (l.clone(), *p + off)).collect();
        let (mut case, s) = run_case(&name, "coords", "same mesh and eyes, translated", &t, &default, &e);
        if let (Some(a), Some(b)) = (&base_scores, &s) {
            case.drawn_diff = Some(mask_diff(a, b));
            case.groups_diff = Some(case.groups as i64 - cases[0].groups as i64);
        }
        cases.push(case);
    }
    // Scaled uniformly about the origin, eyes with it: the same views (visibility does not depend on the unit), with
    // every coordinate rounded anew, and the margins, tolerances and distances of the proofs at another size.
    for scale in [1e-4, 1e3] {
        let name = format!("scale x {scale:e}");
        progress(&name);
        let t = map_tin(tin, |p| p * scale)?;
        let e: Vec<Eye> = eyes.iter().map(|(l, p)| (l.clone(), *p * scale)).collect();
        let note = "same mesh and eyes, scaled uniformly (the same views)";
        let (mut case, s) = run_case(&name, "coords", note, &t, &default, &e);
        if let (Some(a), Some(b)) = (&base_scores, &s) {
            case.drawn_diff = Some(mask_diff(a, b));
            case.groups_diff = Some(case.groups as i64 - cases[0].groups as i64);
        }
        cases.push(case);
    }
    for (scale, note) in [
        (0.01, "vertical exaggeration"),
        (100.0, "vertical exaggeration"),
        (-1.0, "upside down: every valley a ridge"),
    ] {
        let name = format!("z x {scale}");
        progress(&name);
        let t = map_tin(tin, |p| DVec3::new(p.x, p.y, p.z * scale))?;
        let e = standard_eyes(&t, n);
        cases.push(run_case(&name, "coords", note, &t, &default, &e).0);
    }

    // Degenerate viewpoints, scored on the baseline build.
    match build_case(tin, &default) {
        Ok(b) => {
            let truth = GroundTruth::new(tin);
            for (name, note, e) in degenerate_eyes(tin, &b.hierarchy, n) {
                progress(name);
                let mut case = CaseResult {
                    name: name.into(),
                    category: "viewpoints".into(),
                    note: note.into(),
                    ..CaseResult::default()
                };
                let s = score(tin, &truth, &b, &e)?;
                fill(&mut case, tin, &default, &b, &s);
                cases.push(case);
            }
        }
        Err(e) => cases.push(CaseResult {
            name: "degenerate viewpoints".into(),
            category: "viewpoints".into(),
            status: "error".into(),
            note: format!("baseline build failed: {e:#}"),
            ..CaseResult::default()
        }),
    }

    progress("seeds");
    let seeds =
        spread_study(tin, &default, &eyes, if opts.quick { 5 } else { 20 }).with_context(|| "the seed study failed")?;

    Ok(StressReport {
        mesh: mesh.to_string(),
        options: opts.clone(),
        cases,
        seeds,
        seconds: start.elapsed().as_secs_f64(),
    })
}

impl StressReport {
    /// A readable table: one line per case, then the seed spread.
    pub fn table(&self) -> String {
        let mut s = format!(
            "{:<24} {:<10} {:>6} {:>6} {:>8} {:>6} {:>6} {:>4} {:>5} {:>8} {:>6} {:>6} {:>9} {:>8} {:>7} {:>9}  note\n",
            "case",
            "category",
            "V",
            "T",
            "build_s",
            "groups",
            "orph",
            "inv",
            "views",
            "fc_mean",
            "fc_max",
            "fc_vw",
            "occl_capt",
            "culled",
            "safe_fc",
            "safe_occl"
        );
        for c in &self.cases {
            if c.status != "ok" {
                s += &format!(
                    "{:<24} {:<10} {}: {}\n",
                    c.name,
                    c.category,
                    c.status.to_uppercase(),
                    c.note
                );
                continue;
            }
            let mut note = c.note.clone();
            if let Some(d) = c.drawn_diff {
                note = format!(
                    "drawn differs from baseline in {d} (view, triangle) pairs, groups {:+}; {note}",
                    c.groups_diff.unwrap_or(0)
                );
            }
            s += &format!(
                "{:<24} {:<10} {:>6} {:>6} {:>8.2} {:>6} {:>6} {:>4} {:>5} {:>8.2} {:>6} {:>6} {:>9} {:>8.1} {:>7} {:>9}  {}\n",
                c.name,
                c.category,
                c.vertices,
                c.triangles,
                c.build_seconds,
                c.groups,
                c.orphans,
                match c.invariants_ok {
                    Some(true) => "ok",
                    Some(false) => "BAD",
                    None => "-",
                },
                c.viewpoints,
                c.false_culls_mean,
                c.false_culls_max,
                c.viewpoints_with_false_culls,
                c.occlusion_captured_mean.map_or("-".into(), |x| format!("{x:.3}")),
                c.culled_mean,
                c.safe_false_culls_max,
                c.safe_occlusion_captured_mean.map_or("-".into(), |x| format!("{x:.3}")),
                note
            );
        }
        let sp = &self.seeds;
        s += &format!(
            "seeds ({}): groups {:.0}/{:.0}/{:.0}, orphans {:.0}/{:.0}/{:.0}, occlusion captured {:.3}/{:.3}/{:.3} (min/median/max); max false culls {}\n",
            sp.seeds.len(),
            sp.groups.min,
            sp.groups.median,
            sp.groups.max,
            sp.orphans.min,
            sp.orphans.median,
            sp.orphans.max,
            sp.occlusion_captured.min,
            sp.occlusion_captured.median,
            sp.occlusion_captured.max,
            sp.false_culls_max
        );
        s
    }

    /// The case named `name`.
    pub fn case(&self, name: &str) -> Option<&CaseResult> {
        self.cases.iter().find(|c| c.name == name)
    }
}
