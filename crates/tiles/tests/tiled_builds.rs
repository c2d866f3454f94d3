//! Tiled builds against their oracles: the merged terrain reproduces every sample within the error bound (no crack
//! between tiles), halo and far field lie on or below it, the safe culler culls nothing visible on it (exact
//! checker), and builds are deterministic; a plan or a part file with any value replaced is refused (naming it) or run,
//! never a panic.

use std::path::{Path, PathBuf};

use cull::{AnyCuller, Camera, Hierarchy, SafeCuller, SafeParams};
use glam::{DVec2, DVec3};
use pipeline::BuildParams;
use proptest::prelude::*;
use tiles::{Plan, PlanOptions};
use tin::{DemOptions, Grid, SynthOptions, Tin};
use truth::visible::GroundTruth;

/// Writes `grid` as `.npy` + sidecar in `dir`, plans it (crystal grouping) and returns the plan and its path.
fn plan_grid(dir: &Path, grid: &Grid, tile: usize, halo: usize, max_error: f64) -> (Plan, PathBuf) {
    plan_grid_grouped(dir, grid, tile, halo, max_error, pipeline::Grouping::Crystal)
}

/// [`plan_grid`] with a given grouping.
fn plan_grid_grouped(
    dir: &Path,
    grid: &Grid,
    tile: usize,
    halo: usize,
    max_error: f64,
    grouping: pipeline::Grouping,
) -> (Plan, PathBuf) {
    let npy = dir.join("terrain.npy");
    let mut bytes = Vec::new();
    tin::dem::npy::write_npy_to(grid, &mut bytes).expect("npy");
    std::fs::write(&npy, bytes).expect("write npy");
    std::fs::write(tin::dem::npy::sidecar_path(&npy), tin::dem::npy::sidecar_json(grid)).expect("sidecar");
    let mut params = BuildParams {
        sectors: 8,
        subsectors: 2,
        grouping,
        ..BuildParams::default()
    };
    params.crystal.min_group = 4;
    let options = PlanOptions {
        tile,
        halo,
        far_block: 3,
        far_ratio: 2,
        max_error,
        params,
        no_regions: false,
    };
    write_plan(dir, &npy, options)
}

/// Plans the DEM `npy` in `dir` with `options`, writes the plan and its tiles' far-field files (a plan without
/// regions has none), and returns the plan and its path.
fn write_plan(dir: &Path, npy: &Path, options: PlanOptions) -> (Plan, PathBuf) {
    let (plan, field, _) =
        tiles::make_plan(npy, DemOptions::default(), options, Path::new("plan.tiles"), |_, _| {}).expect("plan");
    let path = dir.join("plan.json");
    std::fs::write(&path, plan.to_json().expect("json")).expect("write plan");
    std::fs::create_dir_all(dir.join("plan.tiles")).expect("tiles dir");
    for spec in &plan.tiles {
        assert_eq!(spec.far.is_none(), plan.options.no_regions, "tile {}", spec.index);
        if let Some(far) = &spec.far {
            let far = Plan::resolve(&path, far);
            std::fs::write(far, plan.far_file(&field, spec).expect("far field").0).expect("write far field");
        }
    }
    (Plan::load(&path).expect("load"), path)
}

/// Builds every tile and merges them.
/// Every tile of the plan, built here.
fn build_tiles(plan: &Plan, path: &Path) -> Vec<Hierarchy> {
    (0..plan.tiles.len())
        .map(|i| tiles::build_tile(plan, path, i, None).expect("tile").0)
        .collect()
}

fn build_all(plan: &Plan, path: &Path) -> Hierarchy {
    tiles::merge(plan, &build_tiles(plan, path)).expect("merge")
}

fn synth(samples: usize, seed: u64) -> Grid {
    tin::synth_grid(&SynthOptions::new(samples, seed)).expect("synth")
}

fn tin_of(h: &Hierarchy) -> Tin {
    Tin::from_parts(
        h.mesh.positions.iter().map(|p| DVec3::from_array(*p)).collect(),
        h.mesh.triangles.clone(),
    )
    .expect("merged mesh")
}

/// The largest |sample − merged terrain| over the valid samples; panics where a sample is outside the terrain.
fn max_sample_error(grid: &Grid, tin: &Tin) -> f64 {
    let loc = truth::locate::Locator::new(tin);
    let mut worst: f64 = 0.0;
    for r in 0..grid.rows {
        for c in 0..grid.cols {
            if let Some(p) = grid.sample(r, c) {
                let h = loc
                    .ground_height(tin, p.truncate())
                    .unwrap_or_else(|| panic!("sample ({r}, {c}) is outside the merged terrain"));
                worst = worst.max((h - p.z).abs());
            }
        }
    }
    worst
}

/// Regression (found by an audit): a tile whose only valid samples lie on a diagonal was planned (three samples over
/// two rows and two columns), and its job then failed, so the tiled build could not finish although the untiled one
/// does. Samples on one line, in any direction, now leave the tile out of the plan; every planned tile builds.
#[test]
fn a_tile_whose_samples_lie_on_a_diagonal_is_left_out() {
    let (rows, cols) = (9, 9);
    let mut z = vec![f64::NAN; rows * cols];
    for r in 0..rows {
        for c in 0..4 {
            z[r * cols + c] = (r * 7 + c * 3) as f64;
        }
    }
    // The tile of rows 0..=4 and columns 4..=8: only (0, 4), (1, 5), (2, 6) hold samples.
    for k in 0..3 {
        z[k * cols + 4 + k] = 10.0 + k as f64;
    }
    let grid = Grid::new(rows, cols, 10.0, 10.0, DVec2::new(1000.0, 2000.0), z).expect("grid");
    let dir = tempfile::tempdir().expect("tempdir");
    let npy = dir.path().join("terrain.npy");
    let mut bytes = Vec::new();
    tin::dem::npy::write_npy_to(&grid, &mut bytes).expect("npy");
    std::fs::write(&npy, bytes).expect("write npy");
    std::fs::write(tin::dem::npy::sidecar_path(&npy), tin::dem::npy::sidecar_json(&grid)).expect("sidecar");
    let options = PlanOptions {
        tile: 4,
        halo: 1,
        far_block: 2,
        far_ratio: 0,
        max_error: 0.5,
        params: BuildParams {
            sectors: 8,
            subsectors: 2,
            ..BuildParams::default()
        },
        no_regions: false,
    };
    let (_, _, left_out) = tiles::make_plan(
        &npy,
        DemOptions::default(),
        options.clone(),
        Path::new("plan.tiles"),
        |_, _| {},
    )
    .expect("plan");
    assert_eq!((left_out.void_tiles, left_out.line_tiles), (1, 1), "{left_out:?}");
    let (plan, path) = write_plan(dir.path(), &npy, options);
    for i in 0..plan.tiles.len() {
        tiles::build_tile(&plan, &path, i, None).unwrap_or_else(|e| panic!("tile {i}: {e}"));
    }
}

#[test]
fn merged_terrain_reproduces_every_sample_within_the_bound() {
    let dir = tempfile::tempdir().expect("tempdir");
    let grid = synth(45 * 45, 7);
    for e in [0.0, 0.5, 3.0] {
        let (plan, path) = plan_grid(dir.path(), &grid, 14, 3, e);
        assert_eq!(plan.tiles.len(), 16);
        let h = build_all(&plan, &path);
        let tin = tin_of(&h);
        let worst = max_sample_error(&grid, &tin);
        assert!(
            worst <= e + 1e-9,
            "error bound {e}: a sample is {worst} m off the merged terrain"
        );
        // The tiles cover the grid's rectangle exactly: no gap, no overlap.
        let area: f64 = (0..tin.num_triangles()).map(|t| tin.triangle_area_xy(t)).sum();
        let expected = (grid.cols - 1) as f64 * grid.dx * (grid.rows - 1) as f64 * grid.dy;
        assert!((area - expected).abs() <= 1e-9 * expected, "area {area} != {expected}");
        // A height field (no overlap, no crack, no duplicate x,y), which the safe culler's theorem is about.
        let report = tin::validate(&tin);
        assert!(report.is_height_field(), "error bound {e}: {:?}", report.warnings);
    }
}

#[test]
fn halo_and_far_field_lie_on_or_below_the_merged_terrain() {
    let dir = tempfile::tempdir().expect("tempdir");
    let grid = synth(40 * 40, 11);
    let e = 1.0;
    let (plan, path) = plan_grid(dir.path(), &grid, 12, 4, e);
    let tin = tin_of(&build_all(&plan, &path));
    let loc = truth::locate::Locator::new(&tin);
    // Every point of every level of the pyramid (what any tile may select), and what each tile's file holds.
    let field = tiles::far_field::FarField::new(&grid, 3, e);
    assert!(field.finest() > 0);
    let mut points: Vec<_> = field
        .pyramid
        .levels
        .iter()
        .flat_map(|l| l.points.iter().flatten().copied())
        .collect();
    for spec in &plan.tiles {
        let stored = plan.far_points(&path, spec).expect("far field");
        assert_eq!(stored, plan.far_cut(&field, spec), "tile {}", spec.index);
        points.extend(stored);
    }
    for p in points {
        let at = plan
            .grid
            .as_ref()
            .expect("a DEM plan")
            .position(p.row as usize, p.col as usize, p.z);
        let ground = loc.ground_height(&tin, DVec2::new(at[0], at[1])).expect("inside");
        assert!(
            at[2] <= ground + 1e-9,
            "far-field point {at:?} above the terrain ({ground})"
        );
    }
    for r in 0..grid.rows {
        for c in 0..grid.cols {
            let p = grid.sample(r, c).expect("no voids");
            let ground = loc.ground_height(&tin, p.truncate()).expect("inside");
            assert!(p.z - e <= ground + 1e-9, "halo sample ({r}, {c}) above the terrain");
        }
    }
}

/// Asserts that the safe culler culls no visible triangle of `h` (exact checker) from 40 seeded eyes 2, 20 and 200 m
/// above its terrain, and culls something.
fn assert_safe_culling(h: &Hierarchy) {
    assert_no_false_culls(h, &[AnyCuller::Safe(SafeCuller::new(h, SafeParams::default()))], &[]);
}

/// Asserts that each of `cullers` culls no visible triangle of `h` (exact checker) from 40 seeded eyes 2, 20 and
/// 200 m above its terrain and from `eyes`, and that each culls something.
fn assert_no_false_culls(h: &Hierarchy, cullers: &[AnyCuller], eyes: &[DVec3]) {
    let tin = tin_of(h);
    let truth = GroundTruth::new(&tin);
    let loc = truth.locator();
    let (lo, hi) = (tin.bbox().min, tin.bbox().max);
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut all = eyes.to_vec();
    while all.len() < eyes.len() + 40 {
        let xy = DVec2::new(lo.x + next() * (hi.x - lo.x), lo.y + next() * (hi.y - lo.y));
        let Some(ground) = loc.ground_height(&tin, xy) else {
            continue;
        };
        all.push(xy.extend(ground + [2.0, 20.0, 200.0][all.len() % 3]));
    }
    let mut culled = vec![0usize; cullers.len()];
    for eye in all {
        let visible = truth.visible_triangles(eye);
        for (culler, culled) in cullers.iter().zip(&mut culled) {
            let mask = culler
                .cull(&Camera::all_around(eye.to_array()))
                .mask(tin.num_triangles());
            for t in 0..tin.num_triangles() {
                assert!(
                    !visible[t] || mask[t],
                    "{}: false cull of triangle {t} from {eye:?}",
                    culler.method().name()
                );
            }
            *culled += mask.iter().filter(|&&m| !m).count();
        }
    }
    for (culler, culled) in cullers.iter().zip(culled) {
        assert!(
            culled > 0,
            "{} culled nothing on the merged terrain",
            culler.method().name()
        );
    }
}

#[test]
fn safe_culling_of_a_merged_terrain_never_culls_a_visible_triangle() {
    let dir = tempfile::tempdir().expect("tempdir");
    let grid = synth(48 * 48, 5);
    let (plan, path) = plan_grid(dir.path(), &grid, 12, 3, 0.5);
    assert_safe_culling(&build_all(&plan, &path));
}

/// Spikes and a notched wall, one sample wide, on a plain at UTM-sized coordinates, cut into small tiles with a thin
/// halo (the wall runs along the side between two rows of tiles). The run-time cullers read the merged mesh and
/// hierarchy, not the tiles' horizons: neither the safe culler nor Lloyd & Egbert's may cull a visible triangle of the
/// merge, from random eyes and from eyes a millimetre and half a metre above the spike tips and the wall, and level
/// with the notch on either side of the wall.
#[test]
fn tiled_spikes_and_a_notched_wall_are_culled_safely() {
    let (rows, cols) = (48, 48);
    let mut z: Vec<f64> = (0..rows * cols)
        .map(|i| 3000.0 + 5.0 * ((i % cols) as f64 / 7.0).sin() * ((i / cols) as f64 / 5.0).cos())
        .collect();
    let mut tips = Vec::new();
    for (k, &(r, c)) in [
        (5, 5),
        (9, 30),
        (17, 13),
        (26, 41),
        (33, 7),
        (40, 22),
        (44, 45),
        (13, 24),
    ]
    .iter()
    .enumerate()
    {
        z[r * cols + c] += 60.0 + 45.0 * k as f64;
        tips.push((r, c));
    }
    // The wall across tile sides, with its notch in the middle.
    for c in 6..42 {
        z[24 * cols + c] += 150.0;
    }
    z[24 * cols + 23] -= 140.0;
    let (dx, dy) = (10.0, 10.0);
    let origin = DVec2::new(500_000.0, 4_800_000.0);
    let grid = Grid::new(rows, cols, dx, dy, origin, z).expect("grid");
    let dir = tempfile::tempdir().expect("tempdir");
    let (plan, path) = plan_grid(dir.path(), &grid, 12, 1, 0.0);
    assert_eq!(plan.tiles.len(), 16);
    let h = build_all(&plan, &path);
    let at = |r: usize, c: usize, up: f64| {
        let p = grid.sample(r, c).expect("no voids");
        DVec3::new(p.x, p.y, p.z + up)
    };
    let mut eyes = Vec::new();
    for &(r, c) in tips.iter().chain(&[(24, 10), (24, 23), (24, 35)]) {
        eyes.push(at(r, c, 1e-3));
        eyes.push(at(r, c, 0.5));
    }
    // Level with the bottom of the notch, 50 m to either side of the wall.
    let notch = at(24, 23, 0.5);
    eyes.push(DVec3::new(notch.x, notch.y - 5.0 * dy, notch.z));
    eyes.push(DVec3::new(notch.x, notch.y + 5.0 * dy, notch.z));
    let cullers = [
        AnyCuller::Safe(SafeCuller::new(&h, SafeParams::default())),
        AnyCuller::new(&h, cull::CullMethod::LloydEgbert),
    ];
    assert_no_false_culls(&h, &cullers, &eyes);
}

/// Tiles grouped by quadtree merge into a quadtree hierarchy: each tile's cells under its tile node, the file marked
/// quadtree (so `stewart` accepts it and `thesis` refuses it), as deterministic and as safe as crystal tiles.
#[test]
fn quadtree_tiles_merge_into_a_quadtree_hierarchy() {
    let dir = tempfile::tempdir().expect("tempdir");
    let grid = synth(48 * 48, 6);
    let depth = 3;
    let grouping = pipeline::Grouping::Quadtree(pipeline::QuadtreeParams {
        depth: Some(depth),
        ..Default::default()
    });
    let (plan, path) = plan_grid_grouped(dir.path(), &grid, 24, 3, 0.5, grouping);
    assert_eq!(plan.tiles.len(), 4);
    let h = build_all(&plan, &path);
    assert_eq!(
        h.to_bytes().expect("bytes"),
        build_all(&plan, &path).to_bytes().expect("bytes")
    );
    assert!(h.build.grouping.is_quadtree(), "{:?}", h.build.grouping);
    cull::CullMethod::Stewart
        .check(&h)
        .expect("stewart takes a tiled quadtree");
    assert!(cull::CullMethod::Thesis.check(&h).is_err());
    // One root over the 4 tile nodes, each over its tile's quadtree; every cell stores its regions.
    assert_eq!(h.roots.len(), 1);
    let root = &h.nodes[h.roots[0] as usize];
    assert_eq!(root.children.len(), 4);
    let leaves = h.nodes.iter().filter(|n| n.children.is_empty()).count();
    assert!(leaves >= 4 * 4usize.pow(depth - 1), "{leaves} leaves");
    assert_eq!(h.always_visible[0], h.always_visible[1], "a quadtree leaves no orphans");
    let stewart = AnyCuller::new(&h, cull::CullMethod::Stewart);
    let eye = h.mesh.positions[0];
    let list = stewart.cull(&Camera::all_around([eye[0], eye[1], eye[2] + 10.0]));
    assert!(list.stats.nodes_tested > 0);
    assert_safe_culling(&h);
}

/// A plan without regions builds the quadtree's cells alone: no far-field files, tiles that read no halo, and a
/// merged hierarchy that is the merge of the same plan with regions less its regions (the same mesh, nodes and
/// circles), which the safe culler culls exactly as that one, and safely. A mesh's plan without regions writes parts
/// with no halo and no far field, and merges into the same mesh.
#[test]
fn a_plan_without_regions_merges_into_the_quadtree_less_its_regions() {
    let grid = synth(48 * 48, 7);
    let grouping = pipeline::Grouping::Quadtree(pipeline::QuadtreeParams::default());
    let with_dir = tempfile::tempdir().expect("tempdir");
    let (plan, path) = plan_grid_grouped(with_dir.path(), &grid, 16, 3, 0.5, grouping.clone());
    let with = build_all(&plan, &path);
    assert!(with.has_regions());

    let dir = tempfile::tempdir().expect("tempdir");
    let npy = dir.path().join("terrain.npy");
    std::fs::copy(with_dir.path().join("terrain.npy"), &npy).expect("copy");
    std::fs::copy(
        tin::dem::npy::sidecar_path(&with_dir.path().join("terrain.npy")),
        tin::dem::npy::sidecar_path(&npy),
    )
    .expect("copy sidecar");
    let options = PlanOptions {
        halo: 0,
        no_regions: true,
        ..plan.options.clone()
    };
    let (bare_plan, bare_path) = write_plan(dir.path(), &npy, options);
    assert_eq!(bare_plan.tiles.len(), 9);
    let (bare, report) = tiles::build_tile(&bare_plan, &bare_path, 4, None).expect("tile 4");
    assert!(report.build.without_regions && report.halo_points == 0 && report.far_points == 0);
    assert!(!bare.has_regions());
    let bare = build_all(&bare_plan, &bare_path);
    assert!(!bare.has_regions());
    assert_eq!(bare.mesh, with.mesh);
    assert_eq!((&bare.roots, bare.always_visible), (&with.roots, with.always_visible));
    assert_eq!(bare.nodes.len(), with.nodes.len());
    for (i, (a, b)) in bare.nodes.iter().zip(&with.nodes).enumerate() {
        assert!(a.regions.is_empty(), "node {i} has regions");
        let mut b = b.clone();
        b.regions.clear();
        assert_eq!(*a, b, "node {i}");
    }
    let (safe_bare, safe_with) = (
        SafeCuller::new(&bare, SafeParams::default()),
        SafeCuller::new(&with, SafeParams::default()),
    );
    for (k, p) in bare.mesh.positions.iter().enumerate().step_by(97) {
        let camera = Camera::all_around([p[0], p[1], p[2] + [2.0, 20.0, 200.0][k % 3]]);
        assert_eq!(
            safe_bare.cull(&camera).ranges,
            safe_with.cull(&camera).ranges,
            "eye at vertex {k}"
        );
    }
    assert_safe_culling(&bare);

    // A mesh's plan without regions: parts with nothing beyond their tile.
    let tin = tin::synth_tin(&SynthOptions::new(2000, 3)).expect("synth");
    let side = tin.bbox().size().x;
    let options = PlanOptions {
        tile: (side / 2.5) as usize,
        halo: 0,
        far_block: 1,
        far_ratio: 0,
        max_error: 0.0,
        params: BuildParams {
            grouping,
            ..BuildParams::default()
        },
        no_regions: true,
    };
    let (plan, parts) =
        tiles::make_mesh_plan(&tin, Path::new("t.obj"), options, Path::new("plan.tiles")).expect("mesh plan");
    assert_eq!(plan.tiles.len(), 9);
    assert!(parts.iter().all(|p| p.halo.is_empty() && p.far.is_empty()));
    assert_eq!(
        parts.iter().map(|p| p.triangles.len()).sum::<usize>(),
        tin.num_triangles()
    );
}

/// A plan without regions needs the quadtree grouping and no halo; the plan file says which tiles have far fields.
#[test]
fn a_plan_without_regions_is_refused_with_crystals_or_a_halo() {
    let quadtree = pipeline::Grouping::Quadtree(pipeline::QuadtreeParams::default());
    let options = |halo: usize, grouping: pipeline::Grouping| PlanOptions {
        tile: 16,
        halo,
        far_block: 3,
        far_ratio: 2,
        max_error: 0.5,
        params: BuildParams {
            grouping,
            ..BuildParams::default()
        },
        no_regions: true,
    };
    options(0, quadtree.clone()).validate().expect("valid");
    let e = options(0, pipeline::Grouping::Crystal)
        .validate()
        .expect_err("crystals")
        .to_string();
    assert!(e.contains("--no-regions needs --grouping quadtree"), "{e}");
    let e = options(3, quadtree).validate().expect_err("a halo").to_string();
    assert!(e.contains("--halo 3") && e.contains("without regions"), "{e}");

    // A plan with regions edited to say it has none (or the reverse) is malformed: its tiles' far fields disagree.
    let dir = tempfile::tempdir().expect("tempdir");
    let (plan, path) = plan_grid(dir.path(), &synth(24 * 24, 2), 12, 0, 0.5);
    let mut doc: serde_json::Value = serde_json::from_str(&plan.to_json().expect("json")).expect("parse");
    doc["options"]["no_regions"] = serde_json::Value::Bool(true);
    doc["options"]["params"]["grouping"] =
        serde_json::json!({"quadtree": {"depth": null, "cell": null, "max_bytes": null}});
    std::fs::write(&path, doc.to_string()).expect("write");
    let e = Plan::load(&path)
        .expect_err("far fields in a plan without regions")
        .to_string();
    assert!(e.contains("without regions has no far-field file"), "{e}");
}

#[test]
fn tiled_builds_are_deterministic_and_tiles_are_nodes_near_the_top() {
    let dir = tempfile::tempdir().expect("tempdir");
    let grid = synth(33 * 33, 2);
    let (plan, path) = plan_grid(dir.path(), &grid, 10, 2, 0.5);
    let a = build_all(&plan, &path).to_bytes().expect("bytes");
    let h = build_all(&plan, &path);
    assert_eq!(a, h.to_bytes().expect("bytes"));
    // 4 x 4 tiles: one root over 4 quadrant nodes over the 16 tile nodes (none of them stores a region).
    assert_eq!(h.roots.len(), 1);
    let root = &h.nodes[h.roots[0] as usize];
    assert_eq!(root.children.len(), 4);
    assert!(root.regions.is_empty());
    for &q in &root.children {
        let quad = &h.nodes[q as usize];
        assert_eq!(quad.children.len(), 4);
        assert!(quad.regions.is_empty());
    }
}

/// The streaming merge reads each tile once, in Morton order of the tile grid, and gives what the merge of tiles held
/// in memory gives; a tile that cannot be read stops it with that tile's error.
#[test]
fn the_merge_reads_one_tile_at_a_time() {
    let dir = tempfile::tempdir().expect("tempdir");
    let grid = synth(33 * 33, 3);
    let (plan, path) = plan_grid(dir.path(), &grid, 10, 2, 0.5);
    let tiles = build_tiles(&plan, &path);
    let mut read = Vec::new();
    let streamed = tiles::merge::merge_with(&plan, |i| {
        read.push((plan.tiles[i].tile_row, plan.tiles[i].tile_col));
        Ok(tiles[i].clone())
    })
    .expect("merge");
    assert_eq!(
        streamed.to_bytes().expect("bytes"),
        tiles::merge(&plan, &tiles).expect("merge").to_bytes().expect("bytes")
    );
    assert_eq!(read.len(), 16);
    assert_eq!(&read[..5], &[(0, 0), (0, 1), (1, 0), (1, 1), (0, 2)], "Morton order");
    let mut calls = 0;
    let e = tiles::merge::merge_with(&plan, |i| {
        calls += 1;
        if calls == 3 {
            return Err(tiles::TilesError::Parameter(format!("tile {i} is unreadable")));
        }
        Ok(tiles[i].clone())
    })
    .expect_err("an unreadable tile");
    assert!(e.to_string().contains("is unreadable"), "{e}");
    assert_eq!(calls, 3, "no tile is read after the one that failed");
}

/// A tile's file replaced by another tile's (copied over it) is refused by the merge, naming the tile, its file and a
/// vertex outside its samples; before, the joined mesh was reported as not manifold, naming neither.
#[test]
fn another_tiles_file_in_a_tiles_place_is_named() {
    let dir = tempfile::tempdir().expect("tempdir");
    let grid = synth(33 * 33, 3);
    let (plan, path) = plan_grid(dir.path(), &grid, 10, 2, 0.5);
    let tiles = build_tiles(&plan, &path);
    for (i, t) in tiles.iter().enumerate() {
        plan.check_built_tile(i, t).expect("every tile lies within its samples");
    }
    let mut swapped = tiles.clone();
    swapped[5] = tiles[6].clone();
    let e = tiles::merge(&plan, &swapped)
        .expect_err("tile 6 in tile 5's place")
        .to_string();
    let file = plan.tiles[5].output.display().to_string();
    assert!(
        e.contains("tile 5 (")
            && e.contains(&file)
            && e.contains("outside the tile's samples")
            && e.contains("--tile 5"),
        "{e}"
    );
}

/// Regression (found by a user's test): a tile built from a plan with another `--max-error`, copied into its place,
/// lies within its samples but keeps other side vertices than its neighbours: T-junctions at other heights than the
/// neighbours' edges, a crack. The merge exited 0 and the safe culler culled hundreds of visible triangles through
/// the cracks; it must refuse.
#[test]
fn a_tile_from_another_max_error_is_refused_as_a_crack() {
    let dir = tempfile::tempdir().expect("tempdir");
    let other = tempfile::tempdir().expect("tempdir");
    let grid = synth(33 * 33, 3);
    let (plan, path) = plan_grid(dir.path(), &grid, 10, 2, 0.5);
    let (plan_b, path_b) = plan_grid(other.path(), &grid, 10, 2, 3.0);
    let mut tiles = build_tiles(&plan, &path);
    let foreign = (0..plan.tiles.len())
        .find_map(|i| {
            let t = tiles::build_tile(&plan_b, &path_b, i, None).expect("tile").0;
            (plan.check_built_tile(i, &t).is_ok() && t.mesh.positions != tiles[i].mesh.positions).then_some((i, t))
        })
        .expect("a tile that differs between the two plans");
    let i = foreign.0;
    tiles[i] = foreign.1;
    let e = tiles::merge(&plan, &tiles).expect_err("a crack").to_string();
    assert!(
        e.contains("(a crack)") && e.contains("plan and build them again"),
        "{e}"
    );
    // Every crack is between the foreign tile and a neighbour: the message names it (the vertex's or the
    // triangle's tile) and its file, to be built again.
    let named = format!("tile {i}, {}", plan.tiles[i].output.display());
    assert!(e.contains(&named), "{e}");
}

/// Writes `grid` over the plan's DEM (`terrain.npy` beside `path`).
fn rewrite_dem(path: &Path, grid: &Grid) {
    let mut bytes = Vec::new();
    tin::dem::npy::write_npy_to(grid, &mut bytes).expect("npy");
    std::fs::write(path.with_file_name("terrain.npy"), bytes).expect("rewrite the DEM");
}

#[test]
fn a_dem_changed_after_planning_is_refused_by_the_job_and_the_merge() {
    let dir = tempfile::tempdir().expect("tempdir");
    let grid = synth(33 * 33, 5);
    let (plan, path) = plan_grid(dir.path(), &grid, 16, 2, 0.0);
    assert_eq!(plan.tiles.len(), 4);
    let tiles = build_tiles(&plan, &path);
    // A sample on the side that tiles 0 and 1 share (column 16): both tiles keep a vertex there.
    let (r, c) = (5, plan.tiles[0].cols[1]);
    assert_eq!(plan.tiles[1].cols[0], c);
    let at = grid.sample(r, c).expect("a valid sample");
    let has = |h: &Hierarchy| h.mesh.positions.iter().any(|p| p[0] == at.x && p[1] == at.y);
    assert!(
        has(&tiles[0]) && has(&tiles[1]),
        "the tiles keep the changed sample as a vertex"
    );
    let mut changed = grid.clone();
    changed.z[r * grid.cols + c] -= 150.0;
    rewrite_dem(&path, &changed);
    // The job reads its window and refuses it: every tile whose window holds the sample, no other.
    for (i, spec) in plan.tiles.iter().enumerate() {
        let (wr, wc) = plan.halo_window(spec);
        let holds = (wr[0]..=wr[1]).contains(&r) && (wc[0]..=wc[1]).contains(&c);
        match tiles::build_tile(&plan, &path, i, None) {
            Ok(_) => assert!(!holds, "tile {i} was built from a changed window"),
            Err(e) => {
                let e = e.to_string();
                assert!(
                    holds && e.contains("terrain.npy") && e.contains("changed since the plan"),
                    "{e}"
                );
            }
        }
    }
    // A plan without window digests (made before they were kept) builds tile 0 from the changed DEM; the merge
    // refuses the crack between it and tile 1, built before the change.
    let mut old = plan.clone();
    for t in &mut old.tiles {
        t.window_digest = None;
    }
    let mut mixed = tiles.clone();
    mixed[0] = tiles::build_tile(&old, &path, 0, None).expect("tile 0, unchecked").0;
    let e = tiles::merge(&old, &mixed).expect_err("a crack").to_string();
    assert!(
        e.contains("tiles 0 and 1")
            && e.contains("disagree on the terrain's height")
            && e.contains(&format!("y {}", at.y)),
        "{e}"
    );
    // Back to the planned DEM, every tile builds again, identical to the first time.
    rewrite_dem(&path, &grid);
    assert_eq!(build_tiles(&plan, &path), tiles);
}

#[test]
fn voids_across_tile_sides_still_join() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut grid = synth(36 * 36, 4);
    for r in 8..20 {
        for c in 5..16 {
            grid.z[r * grid.cols + c] = f64::NAN;
        }
    }
    let (plan, path) = plan_grid(dir.path(), &grid, 10, 2, 0.5);
    let h = build_all(&plan, &path);
    let tin = tin_of(&h);
    assert!(max_sample_error(&grid, &tin) <= 0.5 + 1e-9);
    let report = tin::validate(&tin);
    assert!(report.is_height_field(), "{:?}", report.warnings);
}

#[test]
fn a_missing_or_foreign_dem_is_a_clear_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    let grid = synth(20 * 20, 1);
    let (plan, path) = plan_grid(dir.path(), &grid, 8, 2, 0.5);
    let other = synth(21 * 21, 1);
    let mut bytes = Vec::new();
    tin::dem::npy::write_npy_to(&other, &mut bytes).expect("npy");
    std::fs::write(dir.path().join("terrain.npy"), bytes).expect("replace");
    std::fs::write(dir.path().join("terrain.json"), tin::dem::npy::sidecar_json(&other)).expect("sidecar");
    let err = tiles::build_tile(&plan, &path, 0, None)
        .expect_err("changed DEM")
        .to_string();
    assert!(err.contains("no longer has the plan's grid"), "{err}");
    let err = tiles::build_tile(&plan, &path, 99, None)
        .expect_err("no such tile")
        .to_string();
    assert!(err.contains("tile 99 does not exist"), "{err}");
    std::fs::write(&path, "{\"version\": 1}").expect("bad plan");
    let err = Plan::load(&path).expect_err("bad plan").to_string();
    assert!(err.contains("not a tincull tile plan"), "{err}");
}

/// A triangle as its three positions' bits, rotated to start at the smallest: the same triangle in any mesh.
fn canonical(tin_positions: &[[f64; 3]], t: [u32; 3]) -> [[u64; 3]; 3] {
    let mut k = t.map(|v| tin_positions[v as usize].map(f64::to_bits));
    let m = (0..3).min_by_key(|&i| k[i]).unwrap_or(0);
    k.rotate_left(m);
    k
}

/// Plans `tin` in `dir` in tiles of `1 / per_side` of its width (crystal grouping), writes the plan and its parts
/// (each with a halo and a far field), and returns the plan, its path and the parts.
fn plan_mesh(dir: &Path, tin: &Tin, per_side: f64) -> (Plan, PathBuf, Vec<tiles::part::MeshPart>) {
    plan_mesh_with(dir, tin, per_side, false)
}

/// [`plan_mesh`], or without regions (quadtree grouping, parts with no halo and no far field).
fn plan_mesh_with(
    dir: &Path,
    tin: &Tin,
    per_side: f64,
    no_regions: bool,
) -> (Plan, PathBuf, Vec<tiles::part::MeshPart>) {
    let mut params = BuildParams {
        sectors: 8,
        subsectors: 2,
        ..BuildParams::default()
    };
    params.crystal.min_group = 4;
    if no_regions {
        params = BuildParams {
            grouping: pipeline::Grouping::Quadtree(pipeline::QuadtreeParams::default()),
            ..BuildParams::default()
        };
    }
    let side = tin.bbox().size().x;
    let options = PlanOptions {
        tile: (side / per_side) as usize,
        halo: if no_regions { 0 } else { (side / 20.0) as usize },
        far_block: (side / 30.0) as usize,
        far_ratio: 2,
        max_error: 0.0,
        params,
        no_regions,
    };
    let (plan, parts) =
        tiles::make_mesh_plan(tin, Path::new("t.obj"), options, Path::new("plan.tiles")).expect("mesh plan");
    std::fs::create_dir_all(dir.join("plan.tiles")).expect("dir");
    for (t, part) in plan.tiles.iter().zip(&parts) {
        let path = dir.join(t.part.as_ref().expect("part"));
        std::fs::write(path, part.to_bytes().expect("bytes")).expect("write part");
        assert_eq!(part.halo.is_empty() && part.far.is_empty(), no_regions);
    }
    let path = dir.join("plan.json");
    std::fs::write(&path, plan.to_json().expect("json")).expect("plan");
    (Plan::load(&path).expect("load"), path, parts)
}

#[test]
fn a_mesh_cut_into_tiles_merges_back_into_the_same_mesh() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tin = tin::synth_tin(&SynthOptions::new(3000, 9)).expect("synth");
    let (plan, path, parts) = plan_mesh(dir.path(), &tin, 3.5);
    assert_eq!(plan.tiles.len(), 16);
    let h = build_all(&plan, &path);
    assert_eq!(h.mesh.positions.len(), tin.num_vertices());
    let original: Vec<[f64; 3]> = tin.positions().iter().map(|p| p.to_array()).collect();
    let mut a: Vec<_> = tin.triangles().iter().map(|&t| canonical(&original, t)).collect();
    let mut b: Vec<_> = h
        .mesh
        .triangles
        .iter()
        .map(|&t| canonical(&h.mesh.positions, t))
        .collect();
    a.sort_unstable();
    b.sort_unstable();
    assert!(a == b, "the merged mesh differs from the mesh that was cut");
    // Another tile's file in a tile's place is refused, naming the tile and its file.
    let mut tiles = build_tiles(&plan, &path);
    for (i, t) in tiles.iter().enumerate() {
        plan.check_built_tile(i, t).expect("every tile is its part's");
    }
    tiles[5] = tiles[6].clone();
    let e = tiles::merge(&plan, &tiles)
        .expect_err("tile 6 in tile 5's place")
        .to_string();
    let file = plan.tiles[5].output.display().to_string();
    assert!(
        e.contains("tile 5 (") && e.contains(&file) && e.contains("--tile 5"),
        "{e}"
    );
    // Even one whose counts match is refused by its bounding box.
    let mut moved = tiles[6].clone();
    let extent = plan.tiles[5].extent.clone().expect("a mesh tile's extent");
    (moved.mesh.positions, moved.mesh.triangles) = (parts[5].positions.clone(), parts[5].triangles.clone());
    moved.mesh.positions[0][0] = extent.max[0] + 1.0;
    let e = plan
        .check_built_tile(5, &moved)
        .expect_err("a vertex outside")
        .to_string();
    assert!(e.contains("vertex 0") && e.contains("outside the tile's part"), "{e}");
    // A part whose triangles are invalid is refused with its name.
    let p1 = dir.path().join(plan.tiles[1].part.as_ref().expect("part"));
    let mut bad = parts[1].clone();
    bad.triangles[0][0] = bad.positions.len() as u32;
    std::fs::write(&p1, bad.to_bytes().expect("bytes")).expect("write");
    let err = tiles::build_tile(&plan, &path, 1, None)
        .expect_err("bad part")
        .to_string();
    assert!(
        err.contains("part-00001.bin") && err.contains("not a valid mesh part"),
        "{err}"
    );
    // A damaged part is refused with its name.
    let p0 = dir.path().join(plan.tiles[0].part.as_ref().expect("part"));
    let mut bytes = std::fs::read(&p0).expect("read");
    let last = bytes.len() - 1;
    bytes[last] ^= 1;
    std::fs::write(&p0, bytes).expect("damage");
    let err = tiles::build_tile(&plan, &path, 0, None)
        .expect_err("damaged")
        .to_string();
    assert!(err.contains("part-00000.bin") && err.contains("checksum"), "{err}");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// Random grids (rough, with flat runs), tile sizes and bounds: the tiles always join into a terrain within the
    /// bound of every sample.
    #[test]
    fn random_grids_join_within_the_bound(
        rows in 5usize..24,
        cols in 5usize..24,
        tile in 3usize..9,
        e in prop_oneof![Just(0.0), Just(0.5), Just(4.0)],
        seed in 0u64..1000,
    ) {
        let mut s = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
        let z: Vec<f64> = (0..rows * cols)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                let v = (s % 1000) as f64 / 50.0;
                if s % 5 == 0 { 3.0 } else { v }
            })
            .collect();
        let grid = Grid::new(rows, cols, 10.0, 12.5, DVec2::new(300_000.0, 5_000_000.0), z).expect("grid");
        let dir = tempfile::tempdir().expect("tempdir");
        let (plan, path) = plan_grid(dir.path(), &grid, tile, 2, e);
        let h = build_all(&plan, &path);
        let tin = tin_of(&h);
        prop_assert!(max_sample_error(&grid, &tin) <= e + 1e-9);
    }
}

/// How many scalars (numbers, strings, booleans, nulls) `v` holds.
fn scalars(v: &serde_json::Value) -> usize {
    match v {
        serde_json::Value::Array(items) => items.iter().map(scalars).sum(),
        serde_json::Value::Object(fields) => fields.values().map(scalars).sum(),
        _ => 1,
    }
}

/// Replaces the `n`-th scalar (in document order, counting from 0) of `v` by `with`; returns its JSON pointer, or
/// `None` (and `n` less the scalars passed) when `v` holds fewer.
fn replace_scalar(v: &mut serde_json::Value, n: &mut usize, with: &serde_json::Value) -> Option<String> {
    use serde_json::Value;
    let children: Vec<(String, &mut Value)> = match v {
        Value::Array(items) => items.iter_mut().enumerate().map(|(i, x)| (i.to_string(), x)).collect(),
        Value::Object(fields) => fields.iter_mut().map(|(k, x)| (k.clone(), x)).collect(),
        _ if *n == 0 => {
            *v = with.clone();
            return Some(String::new());
        }
        _ => {
            *n -= 1;
            return None;
        }
    };
    children
        .into_iter()
        .find_map(|(key, child)| replace_scalar(child, n, with).map(|at| format!("/{key}{at}")))
}

/// A plan of a small DEM or mesh, with regions or without, planned and written once: the plan's JSON and the
/// directory of its files.
fn damageable_plan(mesh: bool) -> &'static (serde_json::Value, tempfile::TempDir) {
    damageable(mesh, false)
}

/// [`damageable_plan`], or without regions.
fn damageable(mesh: bool, no_regions: bool) -> &'static (serde_json::Value, tempfile::TempDir) {
    static PLANS: [std::sync::OnceLock<(serde_json::Value, tempfile::TempDir)>; 4] = [
        std::sync::OnceLock::new(),
        std::sync::OnceLock::new(),
        std::sync::OnceLock::new(),
        std::sync::OnceLock::new(),
    ];
    PLANS[usize::from(mesh) + 2 * usize::from(no_regions)].get_or_init(|| {
        let dir = tempfile::tempdir().expect("tempdir");
        let plan = if mesh {
            plan_mesh_with(
                dir.path(),
                &tin::synth_tin(&SynthOptions::new(400, 3)).expect("synth"),
                1.9,
                no_regions,
            )
            .0
        } else if no_regions {
            let quadtree = pipeline::Grouping::Quadtree(pipeline::QuadtreeParams::default());
            let (plan, _) = plan_grid_grouped(dir.path(), &synth(33 * 33, 5), 16, 0, 0.5, quadtree);
            let options = PlanOptions {
                no_regions: true,
                ..plan.options
            };
            write_plan(dir.path(), &dir.path().join("terrain.npy"), options).0
        } else {
            plan_grid(dir.path(), &synth(33 * 33, 5), 16, 4, 0.5).0
        };
        assert_eq!(plan.tiles.len(), 4);
        let doc = serde_json::from_str(&plan.to_json().expect("json")).expect("the plan's JSON");
        (doc, dir)
    })
}

/// Writes the plan `doc` to `path`, loads it, builds every tile and merges them; removes the plan file.
fn run_plan(doc: &serde_json::Value, path: &Path) -> Result<Hierarchy, tiles::TilesError> {
    std::fs::write(path, serde_json::to_string(doc).expect("JSON")).expect("write the plan");
    let result = Plan::load(path).and_then(|plan| {
        let built = (0..plan.tiles.len())
            .map(|i| tiles::build_tile(&plan, path, i, None).map(|b| b.0))
            .collect::<Result<Vec<_>, _>>()?;
        tiles::merge(&plan, &built)
    });
    std::fs::remove_file(path).expect("remove the plan");
    result
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// A plan (of a DEM or of a mesh, with regions or without) with any one value replaced, as a hand edit or a damaged
    /// copy may leave it, is refused when loaded, or its tiles are built and merged or refused with an error; never a
    /// panic. (Its JSON is not checksummed: the files it names are, and a window of the DEM by its digest.)
    #[test]
    fn a_plan_with_any_value_replaced_is_run_or_refused(
        mesh in any::<bool>(),
        no_regions in any::<bool>(),
        which in 0usize..1_000_000,
        value in prop_oneof![
            any::<i64>().prop_map(serde_json::Value::from),
            any::<u64>().prop_map(serde_json::Value::from),
            proptest::num::f64::NORMAL.prop_map(serde_json::Value::from),
            (0u32..100).prop_map(serde_json::Value::from),
            (0u32..100_000).prop_map(serde_json::Value::from),
            Just(serde_json::Value::Null),
            "[a-z./]{0,6}".prop_map(serde_json::Value::from),
            Just(serde_json::json!([1, 2])),
            any::<bool>().prop_map(serde_json::Value::from),
        ],
    ) {
        let (doc, dir) = damageable(mesh, no_regions);
        let mut damaged = doc.clone();
        let at = replace_scalar(&mut damaged, &mut (which % scalars(doc)), &value).expect("a scalar");
        // Each case its own plan file beside the shared tile files.
        let result = run_plan(&damaged, &dir.path().join(format!("plan-{which}.json")));
        if let Ok(h) = result {
            prop_assert!(h.check_invariants().is_ok(), "{at} = {value}: the merge is not a valid hierarchy");
        }
    }
}

/// Regression (found by `a_plan_with_any_value_replaced_is_run_or_refused`): the merge summed the tiles' seed counts
/// in a `u32` and overflowed (a panic in a debug build) when a plan asked for more seeds than that holds; a build
/// records such counts as `u32::MAX`, and the merge's sum saturates there too.
#[test]
fn seed_counts_beyond_u32_saturate_in_the_merge() {
    let (doc, dir) = damageable_plan(false);
    let mut many = doc.clone();
    *many.pointer_mut("/options/params/crystal/seeds").expect("the seeds") = serde_json::json!(1u64 << 40);
    let path = dir.path().join("plan-many-seeds.json");
    std::fs::write(&path, serde_json::to_string(&many).expect("JSON")).expect("write the plan");
    let plan = Plan::load(&path).expect("a valid plan");
    let tiles = build_tiles(&plan, &path);
    std::fs::remove_file(&path).expect("remove the plan");
    assert!(tiles.iter().all(|t| t.build.seeds == u32::MAX));
    assert_eq!(tiles::merge(&plan, &tiles).expect("merge").build.seeds, u32::MAX);
}

mod damaged_part {
    use super::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// A mesh tile's part file (framed and checksummed anew, as a faulty planner would write it) with one value
        /// replaced (a coordinate of a vertex, a halo or far-field point, or a triangle's vertex) is built and merged
        /// into a valid hierarchy, or refused with an error naming the part file or the tile; never a panic.
        #[test]
        fn a_part_with_any_value_replaced_is_built_or_refused(
            tile in 0usize..4,
            field in 0usize..4,
            index in any::<usize>(),
            coordinate in 0usize..3,
            value in prop_oneof![
                Just(f64::NAN), Just(f64::INFINITY), Just(1e30), Just(-1e30), Just(0.0), Just(1e-300),
                -1000.0f64..1000.0, proptest::num::f64::ANY,
            ],
            vertex in prop_oneof![0u32..200, Just(u32::MAX), any::<u32>()],
        ) {
            let (doc, dir) = damageable_plan(true);
            let mut plan_doc = doc.clone();
            let part_path = dir.path().join(plan_doc["tiles"][tile]["part"].as_str().expect("a part"));
            let bytes = std::fs::read(&part_path).expect("read");
            let mut part = tiles::part::MeshPart::from_bytes(&bytes, &part_path).expect("part");
            match field {
                0 => { let n = part.positions.len(); part.positions[index % n][coordinate] = value; }
                1 => { let n = part.triangles.len(); part.triangles[index % n][coordinate] = vertex; }
                2 => { let n = part.halo.len(); part.halo[index % n][coordinate] = value; }
                _ => { let n = part.far.len(); part.far[index % n][coordinate] = value; }
            }
            let name = format!("plan.tiles/damaged-{tile}-{field}-{index}-{coordinate}.bin");
            std::fs::write(dir.path().join(&name), part.to_bytes().expect("bytes")).expect("write");
            plan_doc["tiles"][tile]["part"] = serde_json::json!(name);
            let plan_path = dir.path().join(format!("plan-part-{tile}-{field}-{index}-{coordinate}.json"));
            let result = run_plan(&plan_doc, &plan_path);
            std::fs::remove_file(dir.path().join(&name)).expect("remove the part");
            match result {
                Ok(h) => prop_assert!(h.check_invariants().is_ok()),
                Err(e) => {
                    let m = e.to_string();
                    let named = m.contains(&name) || m.contains("tile ") || m.contains("tiles ");
                    prop_assert!(named, "the error names neither file nor tile: {m}");
                }
            }
        }
    }
}

/// Regression (found by `a_part_with_any_value_replaced_is_built_or_refused`): a part's halo or far-field point, or
/// vertex, with a coordinate out of range (1e-300, NaN) reached the horizon sweep's triangulation, whose error named
/// a point of the sweep by its index, not the part file; it is refused as the part's now.
#[test]
fn a_part_with_a_point_out_of_range_is_named() {
    let (doc, dir) = damageable_plan(true);
    let source = dir.path().join(doc["tiles"][1]["part"].as_str().expect("a part"));
    let original = tiles::part::MeshPart::from_bytes(&std::fs::read(&source).expect("read"), &source).expect("part");
    for (field, expected) in [(0, "vertex 3 at"), (1, "halo point 3 at"), (2, "far-field point 3 at")] {
        let mut part = original.clone();
        let points = match field {
            0 => &mut part.positions,
            1 => &mut part.halo,
            _ => &mut part.far,
        };
        points[2][0] = 1e-300;
        let name = format!("plan.tiles/out-of-range-{field}.bin");
        std::fs::write(dir.path().join(&name), part.to_bytes().expect("bytes")).expect("write");
        let mut plan = doc.clone();
        plan["tiles"][1]["part"] = serde_json::json!(name);
        let path = dir.path().join(format!("plan-out-of-range-{field}.json"));
        std::fs::write(&path, serde_json::to_string(&plan).expect("JSON")).expect("write the plan");
        let e = tiles::build_tile(&Plan::load(&path).expect("a plan"), &path, 1, None)
            .expect_err("refused")
            .to_string();
        assert!(
            e.contains(&name) && e.contains(expected) && e.contains("not finite, or not 0 and outside"),
            "{e}"
        );
    }
}

/// A plan lists its tiles and allocates its far field's blocks from the DEM's header, before any sample is read: a
/// header claiming a huge grid (found by an audit: a 65-byte `.asc` header claiming 46,340 x 46,340 samples, planned
/// with `--tile 2` or `--far-block 1`, asked for 107 GB and 51 GB) is refused, naming the file and the option to raise,
/// not allocated.
#[test]
fn a_header_claiming_a_huge_grid_is_refused_before_the_plan_allocates_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    let asc = dir.path().join("claims.asc");
    std::fs::write(
        &asc,
        "ncols 46340\nnrows 46340\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n",
    )
    .expect("asc");
    let options = PlanOptions {
        tile: 2,
        halo: 0,
        far_block: 64,
        far_ratio: 2,
        max_error: 0.0,
        params: BuildParams::default(),
        no_regions: false,
    };
    let message = |options: PlanOptions| match tiles::make_plan(
        &asc,
        DemOptions::default(),
        options,
        Path::new("p.tiles"),
        |_, _| {},
    ) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("a 6-sample file planned as 46,340 x 46,340 samples"),
    };
    let tiles = message(options.clone());
    assert!(
        tiles.contains("claims.asc") && tiles.contains("23170 x 23170 tiles") && tiles.contains("--tile"),
        "{tiles}"
    );
    let far = message(PlanOptions {
        tile: 512,
        far_block: 1,
        ..options.clone()
    });
    assert!(far.contains("claims.asc") && far.contains("--far-block"), "{far}");
    // Within both limits the plan reads the samples, and finds them missing.
    let read = message(PlanOptions { tile: 512, ..options });
    assert!(
        read.contains("claims.asc") && !read.contains("--tile") && !read.contains("--far-block"),
        "{read}"
    );
}
