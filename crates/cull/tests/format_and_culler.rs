//! The `.tch` container (round trip, corruption) and the culler against an independent re-check of its rule.

use std::f64::consts::TAU;

use cull::{Camera, Culler, Hierarchy, HierarchyError, Mesh, Node, StoredRegion, sector_direction, sector_of_azimuth};
use proptest::prelude::*;

/// A region hiding everything below `z < height` beyond `t > t0`, flat.
fn flat(sector: u16, t0: f32, height: f32) -> StoredRegion {
    StoredRegion {
        sector,
        points: vec![[t0, height]],
        tail_slope: 0.0,
    }
}

fn leaf(centre: [f32; 2], radius: f32, triangles: [u32; 2], regions: Vec<StoredRegion>) -> Node {
    Node {
        centre,
        radius,
        children: vec![],
        triangles,
        level: 0,
        regions,
    }
}

/// Two leaves under one parent and one orphan triangle; 4 sectors. Leaf 0 is hidden from low cameras in every
/// sector; leaf 1 only in sector 0.
fn tiny() -> Hierarchy {
    let positions: Vec<[f64; 3]> = (0..8)
        .map(|i| [f64::from(i % 4) * 10.0, f64::from(i / 4) * 10.0, 0.0])
        .collect();
    let triangles = vec![[0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5], [2, 3, 7]];
    let all: Vec<StoredRegion> = (0..4).map(|s| flat(s, -1000.0, 50.0)).collect();
    Hierarchy {
        sectors: 4,
        origin: [0.0, 0.0, 0.0],
        nodes: vec![
            leaf([5.0, 5.0], 8.0, [0, 2], all.clone()),
            leaf([15.0, 5.0], 8.0, [2, 4], vec![flat(0, -1000.0, 50.0)]),
            Node {
                centre: [10.0, 5.0],
                radius: 13.0,
                children: vec![0, 1],
                triangles: [0, 4],
                level: 1,
                regions: vec![flat(0, -1000.0, 50.0)],
            },
        ],
        roots: vec![2],
        always_visible: [4, 5],
        mesh: Mesh { positions, triangles },
        build: Default::default(),
    }
}

#[test]
fn round_trip_is_identity() {
    let h = tiny();
    h.check_invariants().expect("valid");
    let bytes = h.to_bytes().expect("encodes");
    assert_eq!(Hierarchy::from_bytes(&bytes).expect("decodes"), h);
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("tiny.tch");
    std::fs::write(&path, h.to_bytes().expect("encodes")).expect("writes");
    assert_eq!(Hierarchy::load(&path).expect("loads"), h);
}

#[test]
fn corruption_is_a_clear_error() {
    let bytes = tiny().to_bytes().expect("encodes");
    assert!(matches!(
        Hierarchy::from_bytes(b"P3\n1 1\n"),
        Err(HierarchyError::BadMagic)
    ));
    // Empty: said as such, not as a wrong magic number.
    let empty = Hierarchy::from_bytes(&[]).expect_err("empty");
    assert!(matches!(empty, HierarchyError::Truncated { found: 0, .. }), "{empty:?}");
    assert_eq!(empty.to_string(), "empty hierarchy file (0 bytes)");
    for cut in [10, 24, bytes.len() / 2, bytes.len() - 1] {
        assert!(
            matches!(
                Hierarchy::from_bytes(&bytes[..cut]),
                Err(HierarchyError::Truncated { .. })
            ),
            "cut at {cut}"
        );
    }
    let mut v = bytes.clone();
    v[8] = 3;
    assert!(matches!(
        Hierarchy::from_bytes(&v),
        Err(HierarchyError::UnsupportedVersion { found: 3, supported: 2 })
    ));
    for at in [24, 30, bytes.len() - 1] {
        let mut v = bytes.clone();
        v[at] ^= 0x10;
        assert!(
            matches!(Hierarchy::from_bytes(&v), Err(HierarchyError::Checksum { .. })),
            "flip at {at}"
        );
    }
    let mut v = bytes.clone();
    v.push(0);
    assert!(matches!(Hierarchy::from_bytes(&v), Err(HierarchyError::Invalid(_))));
    let dir = tempfile::tempdir().expect("tempdir");
    assert!(matches!(
        Hierarchy::load(dir.path().join("missing.tch")),
        Err(HierarchyError::Io { .. })
    ));
}

#[test]
fn invalid_structure_is_rejected() {
    let mut h = tiny();
    h.nodes[2].children = vec![1, 0];
    assert!(h.check_invariants().is_err(), "children out of order");
    let mut h = tiny();
    h.roots = vec![2, 0];
    assert!(h.check_invariants().is_err(), "a child listed as a root");
    let mut h = tiny();
    h.mesh.triangles[0][0] = 99;
    assert!(h.check_invariants().is_err(), "vertex out of range");
    let mut h = tiny();
    h.nodes[0].regions.swap(0, 1);
    assert!(h.check_invariants().is_err(), "regions out of sector order");
    let mut h = tiny();
    h.always_visible = [4, 4];
    assert!(
        h.check_invariants().is_err(),
        "always-visible range must end the triangles"
    );
}

/// A hierarchy built or changed in code (its fields are public) is checked by `AnyCuller::checked` before any culler
/// is prepared: a node that is its own child made the thesis' culler exhaust memory and Lloyd & Egbert's loop, an
/// index out of range made them panic or draw ranges beyond the mesh.
#[test]
fn a_culler_of_a_broken_hierarchy_is_refused() {
    type Break = fn(&mut Hierarchy);
    let broken: [(&str, Break); 5] = [
        ("a node its own child", |h| h.nodes[2].children.push(2)),
        ("a child beyond the nodes", |h| h.nodes[2].children[0] = 9999),
        ("a root beyond the nodes", |h| h.roots.push(9999)),
        ("a range beyond the triangles", |h| {
            h.nodes[0].triangles = [0, 1_000_000]
        }),
        ("no sectors", |h| h.sectors = 0),
    ];
    for (what, break_it) in broken {
        let mut h = tiny();
        break_it(&mut h);
        for method in cull::CullMethod::ALL {
            let e = cull::AnyCuller::checked(&h, method).expect_err(what);
            assert!(matches!(e, HierarchyError::Invalid(_)), "{what}, {method}: {e:?}");
        }
    }
    // `stewart` is for quadtrees: refused over these crystal groups, by the method's own check.
    for method in [
        cull::CullMethod::Safe,
        cull::CullMethod::Thesis,
        cull::CullMethod::LloydEgbert,
    ] {
        cull::AnyCuller::checked(&tiny(), method).expect("a sound hierarchy");
    }
}

/// Regression (found by an audit of the proofs): a file whose roots and always-visible range leave a triangle out
/// passed the checks, and every culler then never drew that triangle, in plain view or not. Every triangle must be
/// in a root's range or always visible.
#[test]
fn a_triangle_in_no_node_is_rejected() {
    // Leaf 1 ([2, 4)) made a root of its own range only, its parent gone: triangles [0, 2) are in no node.
    let mut h = tiny();
    h.nodes = vec![h.nodes[1].clone()];
    h.roots = vec![0];
    let e = h.check_invariants().expect_err("a gap").to_string();
    assert!(e.contains("[0, 2) are in no node"), "{e}");
    // A gap between the roots and the always-visible range.
    let mut h = tiny();
    h.mesh.triangles.push([3, 7, 6]);
    h.always_visible = [5, 6];
    let e = h.check_invariants().expect_err("a gap").to_string();
    assert!(e.contains("[4, 5) are in no node"), "{e}");
    // Through the file too.
    let bytes = h.to_bytes().expect("encodes");
    assert!(Hierarchy::from_bytes(&bytes).is_err());
}

/// A file whose coordinates no mesh reader accepts (here 1e300, beyond f32: an export would write `null`) is refused
/// on load, naming the vertex; the limit is the mesh readers' own.
#[test]
fn coordinates_beyond_the_readers_limit_are_rejected() {
    assert_eq!(cull::hierarchy::COORDINATE_LIMIT, tin::COORDINATE_LIMIT);
    for bad in [1e300, -9e42, 1e-300, f64::NAN, f64::INFINITY] {
        let mut h = tiny();
        h.mesh.positions[1][0] = bad;
        let e = h.check_invariants().expect_err("refused").to_string();
        assert!(e.contains("vertex 1") && e.contains("2^100"), "{e}");
        let mut h = tiny();
        h.origin[2] = bad;
        if bad.abs() > 1.0 || bad.is_nan() {
            assert!(h.check_invariants().is_err(), "origin {bad}");
        }
    }
    let mut h = tiny();
    h.mesh.positions[1] = [0.0, -tin::COORDINATE_LIMIT, 1.0 / tin::COORDINATE_LIMIT];
    h.check_invariants().expect("the limits themselves are accepted");
    // Through the file: the same refusal, naming the file.
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("huge.tch");
    let mut h = tiny();
    h.mesh.positions[0][1] = 1e300;
    std::fs::write(&path, h.to_bytes().expect("encoded")).expect("written");
    let e = Hierarchy::load(&path).expect_err("refused").to_string();
    assert!(e.contains("huge.tch") && e.contains("vertex 0"), "{e}");
}

#[test]
fn culls_what_the_regions_say() {
    let h = tiny();
    let culler = Culler::new(&h);
    // Far to the east-north-east and low: the parent's sector-0 region hides everything.
    let low = culler.cull(&Camera::all_around([500.0, 100.0, 10.0]));
    assert_eq!(low.ranges, vec![[4, 5]]);
    assert_eq!(low.stats.culled_by_occlusion, 1);
    assert_eq!(low.stats.nodes_tested + low.stats.nodes_skipped, 3);
    assert_eq!(low.stats.triangles_drawn + low.stats.triangles_culled, 5);
    // High up: all visible, ranges merged.
    let high = culler.cull(&Camera::all_around([500.0, 100.0, 100.0]));
    assert_eq!(high.ranges, vec![[0, 5]]);
    // To the west (sector 2): the parent is visible, leaf 0 hidden, leaf 1 visible.
    let west = culler.cull(&Camera::all_around([-500.0, 40.0, 10.0]));
    assert_eq!(west.ranges, vec![[2, 5]]);
    // Inside a bounding circle: visible whatever the regions say.
    let inside = culler.cull(&Camera::all_around([5.0, 5.0, -100.0]));
    assert_eq!(inside.ranges, vec![[0, 5]]);
    // Looking away (east camera looking east): frustum culls the groups.
    let away = culler.cull(&Camera {
        position: [500.0, 5.0, 100.0],
        yaw: 0.0,
        hfov: 60f64.to_radians(),
    });
    assert_eq!(away.ranges, vec![[4, 5]]);
    assert_eq!(away.stats.culled_by_frustum, 1);
}

fn random_hierarchy() -> impl Strategy<Value = Hierarchy> {
    let region = (
        0u16..8,
        -300.0f32..300.0,
        prop::collection::vec((1.0f32..100.0, -50.0f32..50.0), 0..3),
        -1.0f32..1.0,
    );
    let leaf_s = (
        (-200.0f32..200.0, -200.0f32..200.0),
        1.0f32..80.0,
        prop::collection::vec(region, 0..8),
    );
    prop::collection::vec(leaf_s, 1..12).prop_map(|leaves| {
        let mut nodes = Vec::new();
        for (i, ((x, y), r, regs)) in leaves.into_iter().enumerate() {
            let mut regions: Vec<StoredRegion> = Vec::new();
            let mut regs = regs;
            regs.sort_by_key(|r| r.0);
            regs.dedup_by_key(|r| r.0);
            for (sector, t0, steps, tail) in regs {
                let mut pts = vec![[t0, 0.0f32]];
                for (dt, dz) in steps {
                    let last = *pts.last().unwrap_or(&[t0, 0.0]);
                    pts.push([last[0] + dt, last[1] + dz]);
                }
                regions.push(StoredRegion {
                    sector,
                    points: pts,
                    tail_slope: tail,
                });
            }
            nodes.push(leaf([x, y], r, [i as u32, i as u32 + 1], regions));
        }
        let n = nodes.len() as u32;
        let positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        Hierarchy {
            sectors: 8,
            origin: [0.0; 3],
            roots: (0..n).collect(),
            nodes,
            always_visible: [n, n],
            mesh: Mesh {
                positions,
                triangles: vec![[0, 1, 2]; n as usize],
            },
            build: Default::default(),
        }
    })
}

proptest! {
    /// A leaf is culled only if, for every direction from a point of its circle to the camera, the camera lies inside
    /// the region of that direction's sector: re-checked by sampling directions densely, independently of the
    /// culler's interval arithmetic.
    #[test]
    fn never_culls_without_the_regions(h in random_hierarchy(), eye in (-400.0f64..400.0, -400.0f64..400.0, -60.0f64..60.0)) {
        h.check_invariants().expect("valid");
        let eye = [eye.0, eye.1, eye.2];
        let drawn = Culler::new(&h).cull(&Camera::all_around(eye)).mask(h.num_triangles());
        for (i, node) in h.nodes.iter().enumerate() {
            if drawn[i] {
                continue;
            }
            let (cx, cy, r) = (f64::from(node.centre[0]), f64::from(node.centre[1]), f64::from(node.radius));
            let d = (eye[0] - cx).hypot(eye[1] - cy);
            prop_assert!(d > r, "node {} culled with the camera inside its circle", i);
            // Directions from points of the circle's boundary to the eye.
            for k in 0..720 {
                let a = TAU * f64::from(k) / 720.0;
                let (px, py) = (cx + r * a.cos(), cy + r * a.sin());
                let sector = sector_of_azimuth(8, (eye[1] - py).atan2(eye[0] - px));
                let region = node.regions.iter().find(|reg| u32::from(reg.sector) == sector);
                let [rx, ry] = sector_direction(8, sector);
                prop_assert!(region.is_some_and(|reg| reg.contains(rx * eye[0] + ry * eye[1], eye[2])),
                    "node {} culled but sector {} does not hide the camera", i, sector);
            }
        }
    }

    #[test]
    fn frustum_draws_a_subset(h in random_hierarchy(), eye in (-400.0f64..400.0, -400.0f64..400.0, -60.0f64..60.0),
                              yaw in 0.0f64..TAU, fov in 0.1f64..6.0) {
        let culler = Culler::new(&h);
        let all = culler.cull(&Camera::all_around([eye.0, eye.1, eye.2])).mask(h.num_triangles());
        let restricted = culler.cull(&Camera { position: [eye.0, eye.1, eye.2], yaw, hfov: fov });
        let sub = restricted.mask(h.num_triangles());
        prop_assert!(sub.iter().zip(&all).all(|(s, a)| !s || *a));
        prop_assert_eq!(restricted.stats.nodes_tested + restricted.stats.nodes_skipped, h.nodes.len() as u32);
        prop_assert_eq!(restricted.stats.triangles_drawn + restricted.stats.triangles_culled, h.num_triangles() as u32);
    }

    #[test]
    fn stored_regions_only_shrink(t0 in -1e6f64..1e6, steps in prop::collection::vec((0.01f64..500.0, -3.0f64..0.0), 0..5),
                                  z0 in -1000.0f64..3000.0, origin_t in -5e6f64..5e6, samples in prop::collection::vec((0.0f64..3000.0, -1.0f64..1.0), 50)) {
        // A concave chain: slopes decreasing.
        let mut pts = vec![[t0, z0]];
        let mut slope = 2.0;
        for (dt, ds) in steps {
            slope += ds;
            let last = pts[pts.len() - 1];
            pts.push([last[0] + dt, last[1] + slope * dt]);
        }
        let tail = slope - 0.5;
        let stored = StoredRegion::from_f64(0, &pts, tail, origin_t, 100.0).expect("finite");
        let exact = |t: f64| {
            let i = pts.partition_point(|p| p[0] <= t).saturating_sub(1);
            match pts.get(i + 1) { Some(b) => pts[i][1] + (b[1] - pts[i][1]) * (t - pts[i][0]) / (b[0] - pts[i][0]),
                                   None => pts[i][1] + tail * (t - pts[i][0]) }
        };
        for (dt, dz) in samples {
            let t = t0 + dt;
            let z = exact(t) + dz * 1e-3 * (1.0 + exact(t).abs());
            if stored.contains(t - origin_t, z - 100.0) {
                prop_assert!(t > t0 && z < exact(t) + 1e-9 * (1.0 + z.abs()), "stored region grew at t={}", t);
            }
        }
    }
}

/// Re-frames `h`'s payload as a version-1 file: the version-2 payload without its last byte (`Grouping::Crystal`).
fn as_version_1(h: &Hierarchy) -> Vec<u8> {
    let bytes = h.to_bytes().expect("encode");
    let payload = &bytes[24..bytes.len() - 1];
    let mut out = cull::MAGIC.to_vec();
    out.extend_from_slice(&1u32.to_le_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&crc32fast::hash(payload).to_le_bytes());
    out.extend_from_slice(payload);
    out
}

#[test]
fn version_1_files_read_as_crystal_grouped() {
    let h = tiny();
    assert_eq!(h.build.grouping, cull::Grouping::Crystal);
    let back = Hierarchy::from_bytes(&as_version_1(&h)).expect("version 1 reads");
    assert_eq!(back, h);
    let mut q = tiny();
    q.build.grouping = cull::Grouping::Quadtree {
        built_depth: 3,
        stored_depth: 2,
    };
    let bytes = q.to_bytes().expect("encode");
    assert_eq!(bytes[8], 2);
    assert_eq!(Hierarchy::from_bytes(&bytes).expect("decode"), q);
}

#[test]
fn region_methods_refuse_the_other_grouping() {
    use cull::{AnyCuller, CullMethod};
    let crystal = tiny();
    let mut quad = tiny();
    quad.build.grouping = cull::Grouping::Quadtree {
        built_depth: 1,
        stored_depth: 1,
    };
    assert!(CullMethod::Thesis.check(&crystal).is_ok());
    assert!(CullMethod::Safe.check(&quad).is_ok());
    let err = CullMethod::Stewart.check(&crystal).expect_err("stewart on crystals");
    assert!(err.to_string().contains("--grouping quadtree"), "{err}");
    // A valid file the method does not apply to: not an "invalid hierarchy".
    assert!(matches!(err, HierarchyError::MethodMismatch(_)), "{err:?}");
    assert!(!err.to_string().contains("invalid"), "{err}");
    let err = CullMethod::Thesis.check(&quad).expect_err("thesis on a quadtree");
    assert!(err.to_string().contains("method `stewart`"), "{err}");
    assert_eq!(CullMethod::regions_for(&quad), CullMethod::Stewart);
    assert_eq!(CullMethod::from_name("stewart"), Some(CullMethod::Stewart));
    // The same test as the thesis' culler.
    let eye = Camera::all_around([5.0, 100.0, 1.0]);
    let a = AnyCuller::checked(&quad, CullMethod::Stewart)
        .expect("quadtree")
        .cull(&eye);
    let b = AnyCuller::new(&crystal, CullMethod::Thesis).cull(&eye);
    assert_eq!(a.ranges, b.ranges);
}
