//! Resource attacks on [`pipeline::conservative_hierarchy`] (the audit's F3) and the glTF export: hierarchies that
//! `Hierarchy::check_invariants` accepts, built so that their conservative regions would cost far more time or memory
//! than the file's size. A chain of nodes with one child each over the same triangles once cost the product of its
//! depth and its triangles (each node's range scanned, its vertices sorted, its regions computed), and every node held
//! a slot per sector, region or not, all at once. Work is measured here as bytes allocated in all (each node's scan
//! collected its range), memory as the most bytes live at once: counts, not clocks.

#[path = "../../cull/tests/common/resources.rs"]
mod resources;

use resources::{MB, chain_over, flat, grid_mesh, lock, measure};

use cull::{Hierarchy, Node, StoredRegion};
use pipeline::{CONSERVATIVE_WORK_CONSTANT, CONSERVATIVE_WORK_PER_TRIANGLE, conservative_hierarchy};

/// The triangles of squares `i0..i1` of row `j` of [`grid_mesh`]`(n)`.
fn squares(n: u32, j: u32, i0: u32, i1: u32) -> [u32; 2] {
    [2 * (j * n + i0), 2 * (j * n + i1)]
}

/// Whether the stored circle of `n` in `h` holds every vertex of its triangles.
fn circle_holds_its_vertices(h: &Hierarchy, n: &Node) -> bool {
    let (cx, cy) = (
        h.origin[0] + f64::from(n.centre[0]),
        h.origin[1] + f64::from(n.centre[1]),
    );
    h.mesh.triangles[n.triangles[0] as usize..n.triangles[1] as usize]
        .iter()
        .flatten()
        .all(|&v| {
            let p = h.mesh.positions[v as usize];
            (p[0] - cx).hypot(p[1] - cy) <= f64::from(n.radius)
        })
}

/// The audit's F3.1: a chain of 1,600 nodes over 2,048 triangles (a file of about 71 KB) made every node scan,
/// collect and sort the whole terrain: about 200 MB allocated in all (0.3 s). Nodes over the same triangles with the
/// same circle are now computed once: about 0.7 MB.
#[test]
fn a_chain_over_the_same_triangles_is_computed_once() {
    let _guard = lock();
    let h = chain_over(grid_mesh(32), [0, 2048], 1600, 16);
    let file = h.to_bytes().expect("serialises").len();
    let (c, usage) = measure(|| conservative_hierarchy(&h));
    eprintln!("chain of 1,600 over 2,048 triangles, file {file} bytes: {usage:?}");
    assert!(usage.total < 3 * MB, "{usage:?} allocated for a file of {file} bytes");
    c.check_invariants().expect("a valid result");
    assert!(
        c.nodes
            .iter()
            .all(|n| n.regions == c.nodes[0].regions && circle_holds_its_vertices(&c, n))
    );
}

/// The audit's F3.2: 2,000 nodes at 1,024 sectors (a file of 40 KB) with no region made held a slot per sector per
/// node at once, 62.9 MB. Rows are now sparse and repeated nodes computed once: about 0.27 MB.
#[test]
fn a_chain_at_many_sectors_holds_only_the_regions_it_makes() {
    let _guard = lock();
    let h = chain_over(grid_mesh(2), [0, 8], 2000, 1024);
    let file = h.to_bytes().expect("serialises").len();
    let (c, usage) = measure(|| conservative_hierarchy(&h));
    eprintln!("chain of 2,000 at 1,024 sectors, file {file} bytes: {usage:?}");
    assert!(usage.peak < MB, "peak {usage:?} for a file of {file} bytes");
    assert!(
        c.nodes.iter().all(|n| n.regions.is_empty()),
        "a node over the whole terrain has nothing beyond it"
    );
}

/// Nodes with the same triangles and circle share one computation: the result is exactly what each node computed
/// alone (a hierarchy of that node only) gets, its circle included, whether its stored circle holds its vertices
/// (kept) or not (replaced), and the regions are not all empty.
#[test]
fn shared_regions_are_those_of_each_node_alone() {
    let _guard = lock();
    let mut h = chain_over(grid_mesh(16), squares(16, 8, 7, 9), 6, 16);
    // Every other node keeps a circle that holds its vertices (x 7 to 9, y 8 to 9): two shapes over the same range.
    for (i, n) in h.nodes.iter_mut().enumerate().take(7) {
        if i % 2 == 1 {
            (n.centre, n.radius) = ([8.0, 8.5], 1.5);
        }
    }
    let shared = conservative_hierarchy(&h);
    let made: Vec<usize> = shared.nodes.iter().map(|n| n.regions.len()).collect();
    eprintln!("regions per node: {made:?}");
    assert!(made[..7].iter().all(|&m| m > 0), "the chain has regions: {made:?}");
    assert_ne!(
        shared.nodes[0].regions, shared.nodes[1].regions,
        "two circles, two results"
    );
    for (i, (n, got)) in h.nodes.iter().zip(&shared.nodes).enumerate() {
        let alone = Hierarchy {
            nodes: vec![Node {
                children: vec![],
                level: 0,
                ..n.clone()
            }],
            roots: vec![0],
            ..h.clone()
        };
        let expected = &conservative_hierarchy(&alone).nodes[0];
        assert_eq!(got.regions, expected.regions, "node {i}'s regions");
        assert_eq!(
            (got.centre, got.radius),
            (expected.centre, expected.radius),
            "node {i}'s circle"
        );
    }
}

/// Beyond the work bound nodes get no regions (which only culls less: both cullers call a node without regions
/// visible), smallest range first, and a circle that still holds their vertices; within it they get the regions of
/// their range as before.
#[test]
fn nodes_beyond_the_work_bound_get_no_regions_and_a_circle_that_holds_them() {
    let _guard = lock();
    let mesh = grid_mesh(16); // 512 triangles: a bound of 64 · 512 + 65,536 = 98,304
    let nt = mesh.triangles.len() as u64;
    let bound = CONSERVATIVE_WORK_PER_TRIANGLE * nt + CONSERVATIVE_WORK_CONSTANT;
    let depth = 25_000; // 25,001 nodes over 4 triangles: 5 each, 125,005 in all
    let h = chain_over(mesh, squares(16, 8, 7, 9), depth, 16);
    let (c, usage) = measure(|| conservative_hierarchy(&h));
    eprintln!("chain of 25,000 over 4 of 512 triangles: {usage:?}");
    let with: Vec<bool> = c.nodes.iter().map(|n| !n.regions.is_empty()).collect();
    // The chain's nodes first (cost 5 each) in index order, then the two other roots (larger).
    let within = (bound / 5) as usize;
    assert!(within <= depth as usize, "the bound binds within the chain");
    assert!(
        with[..within].iter().all(|&w| w),
        "the first nodes by index get regions"
    );
    assert!(!with[within..].iter().any(|&w| w), "the rest get none");
    assert!(c.nodes[..within].iter().all(|n| n.regions == c.nodes[0].regions));
    assert!(
        c.nodes.iter().all(|n| circle_holds_its_vertices(&c, n)),
        "circles hold their vertices"
    );
    c.check_invariants().expect("a valid result");
}

/// The bound never binds on what `tincull build` makes: summed ranges (plus one a node) are a few times the triangles
/// on a crystal build and on a deep quadtree, far within the bound, and every node of a real build keeps its regions.
#[test]
fn the_work_bound_is_far_from_real_builds() {
    let _guard = lock();
    let tin = tin::synth_tin(&tin::SynthOptions::new(600, 3)).expect("synthetic terrain");
    let quadtree = pipeline::BuildParams {
        grouping: pipeline::Grouping::Quadtree(pipeline::QuadtreeParams {
            depth: Some(8),
            ..Default::default()
        }),
        ..pipeline::BuildParams::default()
    };
    for params in [pipeline::BuildParams::default(), quadtree] {
        let h = pipeline::build(&tin, &params, None).expect("builds").hierarchy;
        let nt = h.mesh.triangles.len() as u64;
        let work: u64 = h
            .nodes
            .iter()
            .map(|n| u64::from(n.triangles[1] - n.triangles[0]) + 1)
            .sum();
        eprintln!(
            "{} nodes, work {:.2} × {nt} triangles",
            h.nodes.len(),
            work as f64 / nt as f64
        );
        assert!(
            4 * work <= CONSERVATIVE_WORK_PER_TRIANGLE * nt,
            "work {work} over {nt} triangles"
        );
    }
}

/// The glTF export built a JSON value tree of the whole document before writing it, every f32 of a region a value of
/// its own: the 16,384 leaves of 16 regions below held 774 MB at once (1.2 GB allocated) for a 48 MB `.glb`. The
/// document is now serialised straight from the hierarchy, into a buffer of its exact size (counted first): the most
/// it holds at once is what it writes and, for a `.glb`, the binary buffer once more.
#[test]
fn the_gltf_export_holds_little_more_than_what_it_writes() {
    let _guard = lock();
    let mut h = flat(grid_mesh(128), 2);
    for (i, n) in h.nodes.iter_mut().enumerate() {
        n.regions = (0..16u16)
            .map(|sector| StoredRegion {
                sector,
                points: (0..4).map(|k| [k as f32 + 0.25, i as f32 * 0.001 - k as f32]).collect(),
                tail_slope: -0.125,
            })
            .collect();
    }
    h.check_invariants().expect("a valid hierarchy");
    for name in ["x.glb", "x.gltf"] {
        let (files, usage) = measure(|| pipeline::gltf::gltf_files(&h, std::path::Path::new(name)).expect("glTF"));
        let written: usize = files.iter().map(|(_, bytes)| bytes.len()).sum();
        eprintln!("{} nodes as {name}: {written} bytes written, {usage:?}", h.nodes.len());
        assert!(
            usage.peak < written * 3 / 2,
            "{name}: peak {usage:?} for {written} bytes written"
        );
    }
}
