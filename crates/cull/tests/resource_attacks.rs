//! Resource attacks on the run-time cullers: hierarchies that `Hierarchy::check_invariants` accepts (a `.tch` file may
//! hold any of them) built to make preparing a culler, or one cull, take time or memory out of proportion to the
//! input. Each test bounds the bytes allocated (a counting allocator, this binary only) generously, about ten times
//! what was measured, or checks that a deep hierarchy overflows no stack; the times are printed, not asserted (the
//! machines that run the tests are shared: speed goals live in benchmarks).

#[path = "common/resources.rs"]
mod resources;

use resources::{MB, Usage, chain, flat, grid_mesh, hierarchy, hierarchy_of, lock, measure, node, on_small_stack};

use cull::{
    AnyCuller, Camera, CullMethod, Culler, DrawList, Grouping, Hierarchy, LloydEgbertCuller, Mesh, Node, SafeCuller,
    SafeParams, StoredRegion,
};

fn cameras(n: u32) -> Vec<Camera> {
    let c = f64::from(n) * 0.5;
    vec![
        Camera::all_around([c, c, 5.0]),
        Camera::all_around([c * 0.3, c * 1.2, 2.0]),
        Camera::all_around([-f64::from(n), c, 1000.0]),
        Camera::all_around([c, c, 1e6]),
        Camera::from_degrees([c, c * 0.1, 3.0], 90.0, 60.0).expect("a camera"),
    ]
}

/// `mesh` with its triangles in a scrambled order (a fixed permutation).
fn scrambled(mut mesh: Mesh) -> Mesh {
    let n = mesh.triangles.len();
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for i in (1..n).rev() {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        mesh.triangles.swap(i, (state % (i as u64 + 1)) as usize);
    }
    mesh
}

/// A chain of 100,000 nodes of one child each (as deep as it has nodes) over a mesh of 128 triangles: decoding and
/// checking the file, preparing the safe culler (default, with a work budget of one unit, with coarse nodes) and the
/// thesis' culler, and culling from five cameras all run on a 256 KiB stack (nothing recurses over the depth), in
/// time and memory linear in the nodes (the search for the circles stops after 128 descendants).
#[test]
fn a_deep_chain_needs_no_deep_stack() {
    let _g = lock();
    let bytes = chain(grid_mesh(8), 100_000).to_bytes().expect("encodes");
    let file = bytes.len();
    let (_, Usage { took, peak, .. }) = measure(|| {
        on_small_stack(move || {
            let h = Hierarchy::from_bytes(&bytes).expect("a valid file");
            let d = SafeParams::default();
            let mut list = DrawList::default();
            for p in [
                d,
                SafeParams { work_budget: 1, ..d },
                SafeParams { coarse_columns: 8, ..d },
            ] {
                let c = SafeCuller::new(&h, p);
                for cam in cameras(8) {
                    c.cull_into(&cam, &mut list);
                    assert!(list.stats.nodes_tested >= 1);
                }
            }
            let c = AnyCuller::new(&h, CullMethod::Thesis);
            for cam in cameras(8) {
                c.cull_into(&cam, &mut list);
                // No region: every node is visible, the whole chain is walked (unless the view turns from it).
                if cam.frustum().is_none() {
                    assert_eq!(list.stats.nodes_tested, 100_001);
                }
            }
        })
    });
    eprintln!("deep chain: {took:?}, {} MB, file {file} bytes", peak / MB);
    // Measured (release, 2 shared cores): 44 MB for a file of 2.3 MB (the coarse culler's crests are computed once
    // for the chain's one range: see `crates/cull/src/safe.rs`).
    assert!(peak < 150 * MB, "{} MB for a file of {file} bytes", peak / MB);
}

/// A node of 100,352 leaves (one triangle each) under a chain of 200 nodes: each of the 128 chain nodes nearest the
/// wide node pushes its 100,352 children while searching for its circle's farthest vertex, which the 128-step limit
/// bounds (`O(128 (nodes + triangles))`); without the chain the same preparation takes about a fifth of the time.
#[test]
fn a_wide_node_under_a_chain_stays_within_the_descendant_limit() {
    let _g = lock();
    let n = 224;
    let mesh = grid_mesh(n);
    let nt = mesh.triangles.len() as u32;
    let mut nodes: Vec<Node> = (0..nt).map(|t| node(vec![], [t, t + 1], 0)).collect();
    nodes.push(node((0..nt).collect(), [0, nt], 1));
    for k in 0..200 {
        nodes.push(node(vec![nodes.len() as u32 - 1], [0, nt], 2 + k));
    }
    let root = nodes.len() as u32 - 1;
    let h = hierarchy(mesh, nodes, vec![root]);
    let file = h.to_bytes().expect("encodes").len();
    // An unlimited budget: no cell-edge occluders (Lloyd & Egbert's grid, out of this test's scope).
    let p = SafeParams {
        work_budget: usize::MAX,
        ..SafeParams::default()
    };
    let (c, Usage { took, peak, .. }) = measure(|| SafeCuller::new(&h, p));
    eprintln!("wide node: {took:?}, {} MB, file {file} bytes", peak / MB);
    // Measured: about 100 ms and 33 MB for a file of 4.4 MB.
    assert!(peak < 100 * MB, "{} MB for a file of {file} bytes", peak / MB);
    let mut list = DrawList::default();
    for cam in cameras(n) {
        let (_, Usage { took, .. }) = measure(|| c.cull_into(&cam, &mut list));
        eprintln!("wide node cull: {took:?}");
        // Measured: at most about 110 ms (a view of every leaf).
    }
}

/// Triangles in a scrambled order (the build's spatial order is not checked on load): every patch of the halving
/// trees is spread over the whole terrain, so every circle is as large as the terrain and every patch's vertices are
/// its own. A cull stays within the work budget; its working memory holds one projected vertex (112 bytes) per
/// vertex of every drawn patch, about four times what the same terrain in its spatial order needs (a linear cost,
/// noted in the audit).
#[test]
fn a_scrambled_triangle_order_keeps_a_cull_bounded() {
    let _g = lock();
    let n = 200;
    let h = flat(scrambled(grid_mesh(n)), 64);
    let c = SafeCuller::new(&h, SafeParams::default());
    let mut list = DrawList::default();
    for cam in cameras(n) {
        let (_, Usage { took, peak, .. }) = measure(|| c.cull_into(&cam, &mut list));
        assert!(list.stats.work as usize <= SafeParams::default().work_budget);
        eprintln!("scrambled cull: {took:?}, {} MB", peak / MB);
        // Measured: at most about 26 ms and 28 MB (80,000 triangles).
        assert!(peak < 150 * MB, "{} MB", peak / MB);
    }
}

/// 1,024 sectors and leaves with regions in every eighth one (a slot per sector in the thesis' culler): the culler
/// holds less than the documented eight times what the file stores, and a cull takes milliseconds.
#[test]
fn a_thousand_sectors_stay_within_eight_slots_per_region() {
    let _g = lock();
    let mesh = grid_mesh(30);
    let nt = mesh.triangles.len() as u32;
    let region = |sector: u16| StoredRegion {
        sector,
        points: vec![[-1e4, 1e4]],
        tail_slope: 0.0,
    };
    let nodes: Vec<Node> = (0..nt)
        .map(|t| Node {
            regions: (0..128).map(|s| region(s * 8)).collect(),
            ..node(vec![], [t, t + 1], 0)
        })
        .collect();
    let h = hierarchy_of(mesh, nodes, (0..nt).collect(), 1024);
    let file = h.to_bytes().expect("encodes").len();
    let (c, Usage { peak, .. }) = measure(|| Culler::new(&h));
    eprintln!("1024 sectors: {peak} bytes, file {file}");
    // Measured: 5.5 times the file.
    assert!(peak < 8 * file, "{peak} bytes for a file of {file}");
    let mut list = DrawList::default();
    for cam in cameras(30) {
        let (_, Usage { took, .. }) = measure(|| c.cull_into(&cam, &mut list));
        eprintln!("1024 sectors cull: {took:?}");
    }
}

/// Regions of 2,000 vertices each in every sector of every node: the thesis' culler copies them once (about twice
/// the file), and a cull walks each region it tests at most twice (the fast test, then the reference where it cannot
/// decide), so it costs at most about the regions' size.
#[test]
fn long_regions_cost_one_pass_per_cull() {
    let _g = lock();
    let mesh = grid_mesh(4);
    let nt = mesh.triangles.len() as u32;
    let region = |sector: u16| StoredRegion {
        sector,
        points: (0..2000).map(|i| [i as f32 - 1e3, 1e4]).collect(),
        tail_slope: 0.0,
    };
    let nodes: Vec<Node> = (0..nt)
        .map(|t| Node {
            regions: (0..16).map(region).collect(),
            ..node(vec![], [t, t + 1], 0)
        })
        .collect();
    let h = hierarchy(mesh, nodes, (0..nt).collect());
    let file = h.to_bytes().expect("encodes").len();
    let (c, Usage { peak, .. }) = measure(|| Culler::new(&h));
    eprintln!("long regions: {peak} bytes, file {file}");
    assert!(peak < 3 * file, "{peak} bytes for a file of {file}");
    let mut list = DrawList::default();
    for cam in cameras(4) {
        let (_, Usage { took, .. }) = measure(|| c.cull_into(&cam, &mut list));
        eprintln!("long regions cull: {took:?}");
        // Measured: well under a millisecond (8 MB of regions).
    }
}

/// Regression: 64 copies of one triangle over a 1 km square, a quadtree of stored depth 8 (a file of a few hundred
/// bytes, no height field): Lloyd & Egbert's preparation cut every grid line's 64 chords at each of the up to 256 grid
/// corners they pass, 8 million pieces, 430 MB (16 copies: 107 MB). A line is now given up once its pieces pass its
/// chords plus 8 a corner, so the pieces stay within about a million at this grid, whatever the file: a few times
/// what two triangles covering the same square take (the grid's 131,584 cell edges each cut once).
#[test]
fn lloyd_egbert_prepares_overlapping_copies_in_bounded_memory() {
    let _g = lock();
    let square = |triangles: Vec<[u32; 3]>| {
        let mesh = Mesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1000.0, 0.0, 10.0],
                [0.0, 1000.0, 20.0],
                [1000.0, 1000.0, 5.0],
            ],
            triangles,
        };
        let nt = mesh.triangles.len() as u32;
        let mut h = hierarchy(mesh, vec![node(vec![], [0, nt], 0)], vec![0]);
        h.build.grouping = Grouping::Quadtree {
            built_depth: 8,
            stored_depth: 8,
        };
        h
    };
    let (two, copies) = (square(vec![[0, 1, 2], [1, 3, 2]]), square(vec![[0, 1, 2]; 64]));
    let (c, Usage { took, peak: legit, .. }) = measure(|| LloydEgbertCuller::new(&two, 256));
    eprintln!("two triangles: {took:?}, {} MB", legit / MB);
    assert_eq!(c.occluder_count(), 2 * 256 * 257);
    let file = copies.to_bytes().expect("encodes").len();
    let (c, Usage { took, peak, .. }) = measure(|| LloydEgbertCuller::new(&copies, 256));
    eprintln!("64 copies: {took:?}, {} MB, file {file} bytes", peak / MB);
    assert_eq!(c.grid_cells(), 256);
    // Measured: 40 MB for two triangles, 62 MB for the copies.
    assert!(
        peak < 4 * legit,
        "{} MB for a file of {file} bytes, {} MB for two triangles",
        peak / MB,
        legit / MB
    );
}
