//! The quadtree on the bundled `jacksboro-2k` terrain: its invariants, regions against a brute-force intersection,
//! the byte budget of the memory levels, and determinism.

use std::path::Path;

use horizon::{HorizonOptions, SectorConfig};
use occlusion::{RegionTable, region::intersect_all};
use quadtree::{QuadtreeError, QuadtreeParams, build};

fn setup(sectors: u32) -> (tin::Tin, RegionTable) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../meshes/jacksboro-2k.obj");
    let tin = tin::read_obj(&path, &tin::ObjImportOptions::default())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .0;
    let config = SectorConfig::new(sectors, 2).expect("config");
    let field = horizon::compute(&tin, &config, &HorizonOptions::default()).expect("horizons");
    let regions = RegionTable::from_field(tin.positions(), &field);
    (tin, regions)
}

fn params(depth: u32) -> QuadtreeParams {
    QuadtreeParams {
        depth: Some(depth),
        ..QuadtreeParams::default()
    }
}

#[test]
fn invariants_hold_at_every_depth() {
    let (tin, regions) = setup(8);
    for depth in 0..=5 {
        let q = build(&tin, &regions, &params(depth)).expect("build");
        q.check_invariants(&tin)
            .unwrap_or_else(|e| panic!("depth {depth}: {e}"));
        assert_eq!(q.stored_depth, depth);
        assert_eq!(q.levels.len(), depth as usize + 1);
        let nodes: usize = q.levels.iter().map(|l| l.nodes).sum();
        assert_eq!(nodes, q.nodes.len());
    }
}

#[test]
fn regions_equal_the_brute_force_intersection() {
    let (tin, regions) = setup(8);
    let q = build(&tin, &regions, &params(3)).expect("build");
    let non_empty = q.nodes.iter().flat_map(|n| n.regions.iter().flatten()).count();
    assert!(non_empty > q.nodes.len(), "too few regions to test: {non_empty}");
    for (i, node) in q.nodes.iter().enumerate() {
        let mut vertices: Vec<u32> = q.order[node.range.start as usize..node.range.end as usize]
            .iter()
            .flat_map(|&t| tin.triangles()[t as usize])
            .collect();
        vertices.sort_unstable();
        vertices.dedup();
        for s in 0..q.sectors {
            let direct = intersect_all(vertices.iter().map(|&v| regions.get(v, s)));
            let built = node.regions[s as usize].as_ref();
            match (direct, built) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    assert!(
                        (a.t0() - b.t0()).abs() <= 1e-9 * (1.0 + a.t0().abs()),
                        "node {i} sector {s}: t0"
                    );
                    for k in 0..40 {
                        let t = a.t0() + f64::from(k) * 25.0;
                        let (za, zb) = (a.height_at(t), b.height_at(t));
                        assert!(
                            (za - zb).abs() <= 1e-6 * (1.0 + za.abs()),
                            "node {i} sector {s} at t={t}: {za} vs {zb}"
                        );
                    }
                }
                (a, b) => panic!(
                    "node {i} sector {s}: direct {:?} vs built {:?}",
                    a.is_some(),
                    b.is_some()
                ),
            }
        }
    }
}

#[test]
fn memory_levels_fit_the_budget() {
    let (tin, regions) = setup(8);
    let full = build(&tin, &regions, &params(4)).expect("build");
    let total = full.stored_bytes();
    let without_finest = total - full.levels[4].bytes;
    for (budget, depth) in [(total, 4), (total - 1, 3), (without_finest, 3), (without_finest - 1, 2)] {
        let p = QuadtreeParams {
            max_bytes: Some(budget),
            ..params(4)
        };
        let q = build(&tin, &regions, &p).expect("build");
        q.check_invariants(&tin).expect("invariants");
        assert_eq!(q.stored_depth, depth, "budget {budget}");
        assert!(q.stored_bytes() <= budget);
        assert_eq!(q.levels.iter().filter(|l| l.stored).count(), depth as usize + 1);
        // The stored nodes keep the regions of the full tree.
        let kept: Vec<_> = full
            .nodes
            .iter()
            .filter(|n| n.depth <= depth)
            .map(|n| (&n.range, &n.regions))
            .collect();
        let got: Vec<_> = q.nodes.iter().map(|n| (&n.range, &n.regions)).collect();
        assert_eq!(kept, got);
    }
    let p = QuadtreeParams {
        max_bytes: Some(10),
        ..params(4)
    };
    assert!(matches!(build(&tin, &regions, &p), Err(QuadtreeError::Budget { .. })));
}

#[test]
fn depth_from_cell_size_and_default() {
    let (tin, regions) = setup(4);
    let q = build(&tin, &regions, &QuadtreeParams::default()).expect("build");
    // About 128 triangles per leaf cell on average over the root square.
    let per_cell = tin.num_triangles() as f64 / 4f64.powi(q.built_depth as i32);
    assert!((32.0..=512.0).contains(&per_cell), "{per_cell}");
    let cell = q.root_side / 8.0;
    let p = QuadtreeParams {
        cell: Some(cell * 1.01),
        ..QuadtreeParams::default()
    };
    assert_eq!(build(&tin, &regions, &p).expect("build").built_depth, 3);
    for bad in [
        QuadtreeParams {
            cell: Some(-1.0),
            ..QuadtreeParams::default()
        },
        QuadtreeParams {
            depth: Some(99),
            ..QuadtreeParams::default()
        },
        QuadtreeParams {
            depth: Some(2),
            cell: Some(10.0),
            ..QuadtreeParams::default()
        },
    ] {
        assert!(matches!(build(&tin, &regions, &bad), Err(QuadtreeError::Params(_))));
    }
}

#[test]
fn deterministic() {
    let (tin, regions) = setup(4);
    let a = build(&tin, &regions, &params(4)).expect("build");
    let b = build(&tin, &regions, &params(4)).expect("build");
    assert_eq!(a.order, b.order);
    assert_eq!(a.nodes, b.nodes);
    assert_eq!(a.levels, b.levels);
}
