//! Resource attacks on the PVS computer ([`pvs::Pvs`]) and the exports it shares the `pipeline` crate with:
//! hierarchies that `Hierarchy::check_invariants` accepts, built to make preparing a PVS computer or one PVS take time,
//! memory or stack out of proportion to the input. Two problems the audit found in this crate are fixed and tested
//! here: a chain of nodes over the same triangles made the preparation quadratic (each node's box scanned its whole
//! range), and long edges made the walls' grid quadratic in memory (each edge registered in every cell of its box).
//! Memory is bounded with a counting allocator (this binary only); times are printed, not asserted (the machines that
//! run the tests are shared: speed goals live in benchmarks).

#[path = "../../cull/tests/common/resources.rs"]
mod resources;

use resources::{MB, Usage, chain, flat, grid_mesh, lock, measure, on_small_stack};

use cull::Mesh;
use pvs::{Height, Method, Pvs, PvsParams, ViewCell};

/// A chain of 100,000 nodes of one child each (as deep as it has nodes) over a mesh of 8 triangles: preparing the PVS
/// computer for Koltun's test, one PVS from inside the terrain and one from beside it, and the JSON export and its
/// reader run on a 256 KiB stack (nothing recurses over the depth), in time and memory linear in the nodes.
#[test]
fn a_deep_chain_needs_no_deep_stack() {
    let _g = lock();
    let h = chain(grid_mesh(2), 100_000);
    let file = h.to_bytes().expect("encodes").len();
    let (_, Usage { took, peak, .. }) = measure(|| {
        on_small_stack(move || {
            let params = PvsParams {
                method: Method::Koltun,
                ..PvsParams::default()
            };
            let p = Pvs::new(&h, params).expect("a PVS computer");
            for x in [0.5, -3.0] {
                let cell = ViewCell {
                    rect: [x, 0.5, x + 1.0, 1.5],
                    height: Height::Band([0.0, 5.0]),
                };
                assert!(p.compute(&cell).expect("a PVS").tests >= 1);
            }
            let json = pipeline::export::to_json(&h).expect("JSON");
            assert_eq!(pipeline::export::from_json(&json).expect("read back"), h);
        })
    });
    eprintln!("deep chain: {took:?}, {} MB, file {file} bytes", peak / MB);
    // Measured (release, 2 shared cores): about 0.12 s and 33 MB for a file of 2.2 MB.
    assert!(peak < 120 * MB, "{} MB for a file of {file} bytes", peak / MB);
}

/// A chain of 10,000 nodes over a mesh of 8 triangles, with the methods that need the conservative regions (computed
/// by `pipeline`, once for the chain's one range) and the glTF export and its reader: all on a 256 KiB stack. (The
/// glTF document takes some 4 KB a node.)
#[test]
fn regions_and_gltf_of_a_deep_chain_need_no_deep_stack() {
    let _g = lock();
    let h = chain(grid_mesh(2), 10_000);
    let (_, Usage { took, .. }) = measure(|| {
        on_small_stack(move || {
            let p = Pvs::new(&h, PvsParams::default()).expect("a PVS computer");
            let cell = ViewCell {
                rect: [-3.0, 0.5, -2.0, 1.5],
                height: Height::Band([0.0, 5.0]),
            };
            assert!(p.compute(&cell).expect("a PVS").tests >= 1);
            let (doc, bin) = pipeline::gltf::to_gltf(&h, None).expect("glTF");
            let doc = serde_json::to_value(&doc).expect("a JSON value");
            let back = pipeline::gltf::hierarchy_from_gltf_json(&doc, &bin).expect("read back");
            assert_eq!(back.nodes.len(), h.nodes.len());
        })
    });
    eprintln!("regions and glTF: {took:?}");
    // Measured: about 0.15 s.
}

/// The audit's F2: a chain of 20,000 nodes of one child each over 8,192 triangles (a file of 1.1 MB). Preparing the
/// PVS computer computed every node's box by scanning its whole range: 20,000 × 8,192 triangles, about 1.3 s (255 ms
/// at 4,000 nodes). Bottom-up it scans each triangle once (counted by the unit test
/// `node_boxes_scan_each_triangle_once_on_a_chain`); here the time is printed and the memory bounded.
#[test]
fn preparing_a_chain_over_many_triangles_is_linear() {
    let _g = lock();
    let h = chain(grid_mesh(64), 20_000);
    let file = h.to_bytes().expect("encodes").len();
    let params = PvsParams {
        method: Method::Koltun,
        ..PvsParams::default()
    };
    let (p, Usage { took, peak, .. }) = measure(|| Pvs::new(&h, params).expect("a PVS computer"));
    let cell = ViewCell {
        rect: [10.5, 10.5, 11.5, 11.5],
        height: Height::Band([0.0, 40.0]),
    };
    assert!(p.compute(&cell).expect("a PVS").tests >= 1);
    eprintln!(
        "chain of 20,000 over 8,192 triangles: {took:?}, {} MB, file {file} bytes",
        peak / MB
    );
    // Measured (release, 2 shared cores): 4 to 10 ms and 3 MB; before the fix 1.3 to 2.5 s (and 3 MB: the problem was
    // time).
    assert!(peak < 16 * MB, "{} MB for a file of {file} bytes", peak / MB);
}

/// `n` parallel diagonal slivers across `[0, n] × [0, 2n]`: a valid height field whose `2n` long edges each cross the
/// whole terrain diagonally (the audit's F4 mesh).
fn slivers(n: u32) -> Mesh {
    let l = f64::from(n);
    let mut positions = Vec::new();
    for k in 0..=n {
        let d = f64::from(k);
        positions.push([0.0, d, 0.1 * (d * 0.3).sin()]);
        positions.push([l, l + d, 0.1 * (d * 0.7).cos()]);
    }
    let triangles = (0..n)
        .flat_map(|k| [[2 * k, 2 * k + 1, 2 * k + 3], [2 * k, 2 * k + 3, 2 * k + 2]])
        .collect();
    Mesh { positions, triangles }
}

/// The audit's F4: 8,000 diagonal slivers (a file of 500 KB). Every edge was registered in every grid cell of its
/// x,y box: 252.9 MB and 0.61 s to prepare Koltun's test. Registered only in the cells it crosses (and the grid
/// capped at 32 registrations an edge), the walls take a few MB; and a PVS on it is still computed.
#[test]
fn walls_of_long_diagonal_slivers_take_linear_memory() {
    let _g = lock();
    let h = flat(slivers(8_000), 16);
    let file = h.to_bytes().expect("encodes").len();
    let params = PvsParams {
        method: Method::Koltun,
        ..PvsParams::default()
    };
    let (p, Usage { took, peak, .. }) = measure(|| Pvs::new(&h, params).expect("a PVS computer"));
    let cell = ViewCell {
        rect: [100.0, 4_000.0, 200.0, 4_100.0],
        height: Height::AboveGround([0.0, 2.0]),
    };
    let (pvs, Usage { took: took_cell, .. }) = measure(|| p.compute(&cell).expect("a PVS"));
    assert!(pvs.tests >= 1);
    eprintln!(
        "8,000 slivers: {took:?}, {} MB, file {file} bytes; one PVS {took_cell:?}",
        peak / MB
    );
    // Measured (release, 2 shared cores): 45 to 150 ms and 3 MB; before the fix 0.6 s and 252 MB.
    assert!(peak < 16 * MB, "{} MB for a file of {file} bytes", peak / MB);
}
