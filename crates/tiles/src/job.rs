//! One tile's job: its TIN, its vertices' horizons over the terrain around it, and its partial hierarchy.
//!
//! 1. **TIN.** The tile's samples are simplified by greedy insertion to the plan's error bound, with the samples
//!    [`crate::boundary::side_vertices`] keeps on each side fixed and the other side samples frozen, so neighbours
//!    share their side vertices exactly. Positions come from the plan's grid formula ([`GridInfo::position`]), so a
//!    shared vertex has bit-identical coordinates in both tiles.
//! 2. **Horizons.** Every vertex's horizons are swept over the tile's vertices, the halo (every valid sample within
//!    `halo` samples outside the tile, lowered by the error bound) and the far-field points outside the halo
//!    ([`crate::far_field`]). Halo and far field lie on or below the merged terrain, so a horizon vertex found among
//!    them is never higher than the terrain there (the regions built from them are not bounded by an untiled
//!    build's: see [`crate::far_field`]).
//! 3. **Hierarchy.** The grouping of the plan's parameters (crystals and their merge hierarchy, or a quadtree) over the
//!    tile's triangles, exactly as an untiled build ([`pipeline::build_from_regions`]).
//!
//! A plan without regions ([`crate::PlanOptions::no_regions`]) skips step 2: its tiles are the quadtree's cells alone
//! ([`pipeline::build_without_regions`]), for the run-time cullers, and read no halo and no far field.
//!
//! Memory: the job reads only the DEM's header and the tile's halo window ([`tin::dem::read_dem_window`]: the
//! window's slices of a `.npy` or `.hgt`, the strips or tiles of a GeoTIFF that meet it, a streamed `.asc`; a PNG is
//! decoded whole and cut), so it keeps the window of the grid (8 bytes a sample) and the tile's TIN stages (some
//! 1.6 kB a vertex), bounded by the tile and its halo, and its far field, read from the tile's own file and growing
//! with the logarithm of the terrain ([`crate::far_field`]); the plan file it reads holds a few hundred bytes a
//! tile.

use std::path::Path;
use std::time::Instant;

use glam::{DVec2, DVec3};
use horizon::{HorizonOptions, SectorConfig};
use occlusion::RegionTable;
use pipeline::{BuildProgress, BuildReport};
use serde::{Deserialize, Serialize};
use tin::{DedupePolicy, Grid, SimplifyOptions, Tin};

use crate::TilesError;
use crate::boundary::side_vertices;
use crate::part::MeshPart;
use crate::plan::{GridInfo, Plan, TileSpec};

/// What a tile job did, with the time of each stage.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TileReport {
    /// The tile's index.
    pub index: usize,
    /// Samples of the tile (a mesh's tile: its vertices).
    pub samples: usize,
    /// Vertices of the tile's TIN.
    pub vertices: usize,
    /// Triangles of the tile's TIN.
    pub triangles: usize,
    /// Halo samples its horizons saw.
    pub halo_points: usize,
    /// Far-field points its horizons saw.
    pub far_points: usize,
    /// Largest error of the tile's simplification over its non-side samples (m).
    pub max_error: f64,
    /// Reading the DEM's header and the tile's halo window (s).
    pub read_seconds: f64,
    /// Simplifying the tile (s).
    pub simplify_seconds: f64,
    /// Triangulating the tile with its halo and far field for the sweep (s).
    pub triangulate_seconds: f64,
    /// The build of the tile's hierarchy: horizons, regions, grouping.
    pub build: BuildReport,
}

/// Reads the header of the plan's DEM and checks that it still has the plan's grid; returns the DEM's path and the
/// plan's grid.
fn check_grid<'p>(plan: &'p Plan, plan_path: &Path) -> Result<(std::path::PathBuf, &'p GridInfo), TilesError> {
    let info = plan
        .grid
        .as_ref()
        .ok_or_else(|| TilesError::Parameter("the plan is a mesh's: its tiles read their parts".into()))?;
    let source = Plan::resolve(plan_path, &plan.source);
    let shape = tin::dem::read_dem_header(&source, &plan.dem)?;
    let found = GridInfo {
        rows: shape.rows,
        cols: shape.cols,
        dx: shape.dx,
        dy: shape.dy,
        origin: shape.origin.to_array(),
    };
    if &found != info {
        return Err(TilesError::Parameter(format!(
            "{} no longer has the plan's grid ({} x {} samples at {} x {} m): plan again",
            source.display(),
            info.rows,
            info.cols,
            info.dx,
            info.dy
        )));
    }
    Ok((source, info))
}

/// The samples in rows `r0..=r1`, columns `c0..=c1` of the whole grid `info`, as a grid of their own, cut from
/// `from`, a window of it whose north-west sample is `(at[0], at[1])`. The origin is computed from the whole grid's,
/// as cutting the whole grid would give it.
fn window(info: &GridInfo, from: &Grid, at: [usize; 2], r: [usize; 2], c: [usize; 2]) -> Result<Grid, TilesError> {
    let mut z = Vec::with_capacity((r[1] - r[0] + 1) * (c[1] - c[0] + 1));
    for row in r[0] - at[0]..=r[1] - at[0] {
        z.extend_from_slice(&from.z[row * from.cols + c[0] - at[1]..=row * from.cols + c[1] - at[1]]);
    }
    let origin = DVec2::from_array(info.origin) + DVec2::new(c[0] as f64 * info.dx, -(r[0] as f64) * info.dy);
    Ok(Grid::new(
        r[1] - r[0] + 1,
        c[1] - c[0] + 1,
        info.dx,
        info.dy,
        origin,
        z,
    )?)
}

/// Row-major indices (in the tile's own grid of `rows × cols`) of its four sides: north, south, west, east.
fn sides(rows: usize, cols: usize) -> [Vec<u32>; 4] {
    let at = |r: usize, c: usize| (r * cols + c) as u32;
    [
        (0..cols).map(|c| at(0, c)).collect(),
        (0..cols).map(|c| at(rows - 1, c)).collect(),
        (0..rows).map(|r| at(r, 0)).collect(),
        (0..rows).map(|r| at(r, cols - 1)).collect(),
    ]
}

/// The tile's TIN in world coordinates by the plan's formula, and its report's error.
fn tile_tin(plan: &Plan, info: &GridInfo, spec: &TileSpec, tile: &Grid) -> Result<(Tin, f64), TilesError> {
    let e = plan.options.max_error;
    let mut fixed = Vec::new();
    let mut frozen = Vec::new();
    let mut is_fixed = vec![false; tile.z.len()];
    for side in sides(tile.rows, tile.cols) {
        let z: Vec<f64> = side.iter().map(|&s| tile.z[s as usize]).collect();
        for k in side_vertices(&z, e) {
            if !std::mem::replace(&mut is_fixed[side[k] as usize], true) {
                fixed.push(side[k]);
            }
        }
        frozen.extend(side);
    }
    let (tin, report) = tin::simplify_constrained(tile, &fixed, &frozen, &SimplifyOptions::error(e), None)?;
    // Back to sample indices, then to the plan's positions.
    let (positions, triangles) = tin.into_parts();
    let world: Vec<DVec3> = positions
        .iter()
        .map(|p| {
            let col = ((p.x - tile.origin.x) / tile.dx).round() as usize;
            let row = ((tile.origin.y - p.y) / tile.dy).round() as usize;
            DVec3::from_array(info.position(spec.rows[0] + row, spec.cols[0] + col, p.z))
        })
        .collect();
    Ok((Tin::from_parts(world, triangles)?, report.max_error))
}

/// A tile's TIN and the points beyond it that its horizons see, with the figures of how they were made.
struct TileInput {
    tin: Tin,
    /// Halo points, then far-field points: all on or below the terrain.
    beyond: Vec<DVec3>,
    halo_points: usize,
    samples: usize,
    max_error: f64,
    read_seconds: f64,
    simplify_seconds: f64,
}

/// A DEM tile: its simplified TIN, the lowered halo and the far field outside the halo.
fn dem_input(plan: &Plan, plan_path: &Path, spec: &TileSpec) -> Result<TileInput, TilesError> {
    let start = Instant::now();
    let (source, info) = check_grid(plan, plan_path)?;
    let (win_r, win_c) = plan.halo_window(spec);
    let halo = tin::dem::read_dem_window(&source, &plan.dem, win_r, win_c)?;
    if let Some(planned) = spec.window_digest
        && crate::plan::window_digest(&halo.z) != planned
    {
        return Err(TilesError::Parameter(format!(
            "{}: the samples of tile {}'s window (rows {} to {}, columns {} to {}) changed since the plan was made: \
             plan again",
            source.display(),
            spec.index,
            win_r[0],
            win_r[1],
            win_c[0],
            win_c[1]
        )));
    }
    let tile = window(info, &halo, [win_r[0], win_c[0]], spec.rows, spec.cols)?;
    let read_seconds = start.elapsed().as_secs_f64();

    let start = Instant::now();
    let (tin, max_error) = tile_tin(plan, info, spec, &tile)?;
    let simplify_seconds = start.elapsed().as_secs_f64();

    let e = plan.options.max_error;
    let inside = |r: usize, c: usize, rr: [usize; 2], cc: [usize; 2]| {
        (rr[0]..=rr[1]).contains(&r) && (cc[0]..=cc[1]).contains(&c)
    };
    let mut beyond = Vec::new();
    for r in win_r[0]..=win_r[1] {
        for c in win_c[0]..=win_c[1] {
            let z = halo.z[(r - win_r[0]) * halo.cols + (c - win_c[0])];
            if !z.is_nan() && !inside(r, c, spec.rows, spec.cols) {
                beyond.push(DVec3::from_array(info.position(r, c, z - e)));
            }
        }
    }
    let halo_points = beyond.len();
    if !plan.options.no_regions {
        for p in plan.far_points(plan_path, spec)? {
            beyond.push(DVec3::from_array(info.position(p.row as usize, p.col as usize, p.z)));
        }
    }
    Ok(TileInput {
        tin,
        beyond,
        halo_points,
        samples: tile.z.len(),
        max_error,
        read_seconds,
        simplify_seconds,
    })
}

/// A mesh tile: its part, as the plan cut it.
fn mesh_input(plan: &Plan, plan_path: &Path, spec: &TileSpec, part: &Path) -> Result<TileInput, TilesError> {
    let start = Instant::now();
    let path = Plan::resolve(plan_path, part);
    let bytes = crate::framed::read(&path)?;
    let part = MeshPart::from_bytes(&bytes, &path)?;
    plan.check_tile_file(spec, &path, &bytes)?;
    // Every point joins the sweep's: coordinates every stage accepts.
    for (what, points) in [
        ("vertex", &part.positions),
        ("halo point", &part.halo),
        ("far-field point", &part.far),
    ] {
        if let Some((i, p)) = points
            .iter()
            .enumerate()
            .find(|(_, p)| !p.iter().all(|&c| tin::coordinate_in_range(c)))
        {
            return Err(TilesError::TileFile {
                path,
                what: "part",
                reason: format!(
                    "{what} {} at {p:?} has a coordinate that is not finite, or not 0 and outside 2^-100 ..= 2^100 in \
                     magnitude",
                    i + 1
                ),
            });
        }
    }
    let tin = Tin::from_parts(
        part.positions.iter().map(|p| DVec3::from_array(*p)).collect(),
        part.triangles,
    )
    .map_err(|e| TilesError::Parameter(format!("{}: not a valid mesh part: {e}", path.display())))?;
    let halo_points = part.halo.len();
    let beyond = part
        .halo
        .iter()
        .chain(&part.far)
        .map(|p| DVec3::from_array(*p))
        .collect();
    Ok(TileInput {
        samples: tin.num_vertices(),
        tin,
        beyond,
        halo_points,
        max_error: 0.0,
        read_seconds: start.elapsed().as_secs_f64(),
        simplify_seconds: 0.0,
    })
}

/// Runs tile `index` of `plan` (read from `plan_path`) and returns its hierarchy and report; writes nothing.
pub fn build_tile(
    plan: &Plan,
    plan_path: &Path,
    index: usize,
    progress: Option<BuildProgress>,
) -> Result<(cull::Hierarchy, TileReport), TilesError> {
    let spec = plan.tile(index)?;
    let input = match &spec.part {
        Some(part) => mesh_input(plan, plan_path, spec, part)?,
        None => dem_input(plan, plan_path, spec)?,
    };
    let tin = &input.tin;
    let params = &plan.options.params;
    let far_points = input.beyond.len() - input.halo_points;
    let (build, triangulate_seconds) = if plan.options.no_regions {
        let build = pipeline::build_without_regions(tin, params, progress);
        (build.map_err(|e| TilesError::Parameter(format!("{e:#}")))?, 0.0)
    } else {
        build_with_regions(plan_path, index, &input, params, progress)?
    };
    let report = TileReport {
        index,
        samples: input.samples,
        vertices: tin.num_vertices(),
        triangles: tin.num_triangles(),
        halo_points: input.halo_points,
        far_points,
        max_error: input.max_error,
        read_seconds: input.read_seconds,
        simplify_seconds: input.simplify_seconds,
        triangulate_seconds,
        build: build.report,
    };
    Ok((build.hierarchy, report))
}

/// The tile's hierarchy with its regions: its vertices' horizons swept over the tile, the halo and the far field
/// (triangulated together first), its regions, and the grouping over them. Returns the build and the seconds the
/// triangulation took.
fn build_with_regions(
    plan_path: &Path,
    index: usize,
    input: &TileInput,
    params: &pipeline::BuildParams,
    progress: Option<BuildProgress>,
) -> Result<(pipeline::Build, f64), TilesError> {
    let tin = &input.tin;
    // The sweep's points: the tile's vertices first, then the halo and the far field, all on or below the terrain.
    let start = Instant::now();
    let mut points: Vec<DVec3> = tin.positions().to_vec();
    points.extend_from_slice(&input.beyond);
    let far_points = input.beyond.len() - input.halo_points;
    let (ext, _) = tin::triangulate(&points, DedupePolicy::Reject).map_err(|e| {
        TilesError::Parameter(format!(
            "tile {index} of {}: the horizon sweep's points (the tile's {} vertices, then {} halo and {} far-field \
             points, numbered from 0 in that order) do not triangulate: {e}",
            plan_path.display(),
            tin.num_vertices(),
            input.halo_points,
            far_points
        ))
    })?;
    if ext.num_vertices() != points.len() {
        return Err(TilesError::Parameter(format!(
            "tile {index} of {}: {} of the horizon sweep's points coincide",
            plan_path.display(),
            points.len() - ext.num_vertices()
        )));
    }
    drop(points);
    let triangulate_seconds = start.elapsed().as_secs_f64();

    let config = SectorConfig::new(params.sectors, params.subsectors)?;
    let opts = HorizonOptions {
        undersampling_radius: params.undersampling,
        progress: progress
            .clone()
            .map(|p| std::sync::Arc::new(move |d: usize, t: usize| p("horizons", d as u64, t as u64)) as _),
    };
    let start = Instant::now();
    let field = horizon::compute(&ext, &config, &opts)?;
    let horizon_seconds = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let n = tin.num_vertices();
    let regions = RegionTable::from_field_owned(&ext.positions()[..n], field);
    drop(ext);
    let regions_seconds = start.elapsed().as_secs_f64();
    let build = pipeline::build_from_regions(tin, regions, params, [horizon_seconds, regions_seconds], progress)
        .map_err(|e| TilesError::Parameter(format!("{e:#}")))?;
    Ok((build, triangulate_seconds))
}
