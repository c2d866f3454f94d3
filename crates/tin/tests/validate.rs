//! Validation reports and mesh statistics on constructed meshes with known answers.

use glam::DVec3;
use tin::{DedupePolicy, Tin, triangulate, validate, validate_parts};

fn grid(w: usize, h: usize, spacing: f64, offset: DVec3) -> Tin {
    let points: Vec<DVec3> = (0..w * h)
        .map(|i| {
            offset
                + DVec3::new(
                    (i % w) as f64 * spacing,
                    (i / w) as f64 * spacing,
                    ((i * 31) % 17) as f64,
                )
        })
        .collect();
    triangulate(&points, DedupePolicy::Reject).expect("grid").0
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1.0)
}

#[test]
fn delaunay_grid_is_clean() {
    let tin = grid(20, 10, 5.0, DVec3::ZERO);
    let r = tin.validate();
    assert!(r.is_height_field(), "{:?}", r.warnings);
    assert_eq!(r.overlapping_pairs, 0);
    assert_eq!(r.slivers, 0);
    assert_eq!(
        r.degenerate_triangles + r.near_degenerate_triangles + r.unreferenced_vertices,
        0
    );
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    let s = tin.stats();
    assert_eq!(s.vertices, 200);
    assert_eq!(s.triangles, 2 * 19 * 9);
    assert_eq!(s.boundary_edges, 2 * (19 + 9));
    assert_eq!(s.area_xy_total, 95.0 * 45.0);
    assert_eq!(s.area_xy_min, 12.5);
    assert_eq!(s.area_xy_max, 12.5);
    assert_eq!(s.relief, 16.0);
    assert!(close(s.min_angle_deg, 45.0, 1e-12), "{}", s.min_angle_deg);
    assert!(close(s.max_aspect, 50.0 / 25.0, 1e-12), "{}", s.max_aspect);
    assert_eq!(s.edge_xy_min, 5.0);
    assert!(close(s.edge_xy_max, 50f64.sqrt(), 1e-12));
    // Both serialise.
    let json = serde_json::to_string(&(r, s)).expect("serialises");
    assert!(json.contains("\"overlapping_pairs\":0"));
}

#[test]
fn slivers_by_angle_and_by_aspect() {
    // 0: a flat sliver (angles 1.15°, 1.15°, 177.7°); 1: a needle (apex 4°, aspect 14.3, a sliver by angle only);
    // 2: a cap with base angles 5.5° (aspect 20.8, a sliver by aspect only); 3: equilateral.
    let t55 = 5.5f64.to_radians().tan();
    let t2 = 2f64.to_radians().tan();
    let positions = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(100.0, 0.0, 0.0),
        DVec3::new(50.0, 1.0, 0.0),
        DVec3::new(200.0, 0.0, 0.0),
        DVec3::new(300.0, -100.0 * t2, 0.0),
        DVec3::new(300.0, 100.0 * t2, 0.0),
        DVec3::new(400.0, 0.0, 0.0),
        DVec3::new(402.0, 0.0, 0.0),
        DVec3::new(401.0, t55, 0.0),
        DVec3::new(500.0, 0.0, 0.0),
        DVec3::new(502.0, 0.0, 0.0),
        DVec3::new(501.0, 3f64.sqrt(), 0.0),
    ];
    let tin = Tin::from_parts(positions, vec![[0, 1, 2], [3, 4, 5], [6, 7, 8], [9, 10, 11]]).expect("valid");
    let r = validate(&tin);
    assert_eq!(r.slivers, 3);
    assert_eq!(r.sliver_examples, vec![0, 1, 2]);
    assert_eq!(r.near_degenerate_triangles, 0);
    assert!(r.is_height_field());
    assert!(r.warnings.iter().any(|w| w.contains("3 sliver")), "{:?}", r.warnings);
    let s = tin.stats();
    assert_eq!(s.slivers, 3);
    assert!(
        close(s.min_angle_deg, (1.0f64 / 50.0).atan().to_degrees(), 1e-9),
        "{}",
        s.min_angle_deg
    );
    assert!(close(s.max_aspect, 100.0 * 100.0 / 100.0, 1e-9), "{}", s.max_aspect);
    let q = |t: usize| {
        let [a, b, c] = tin.corners(t).map(|p| p.truncate());
        tin::validate::triangle_quality(a, b, c)
    };
    assert!(close(q(1).min_angle_deg, 4.0, 1e-9) && q(1).aspect < 20.0, "{:?}", q(1));
    assert!(close(q(2).min_angle_deg, 5.5, 1e-9) && q(2).aspect > 20.0, "{:?}", q(2));
    assert!(close(q(3).min_angle_deg, 60.0, 1e-9) && close(q(3).aspect, 2.0 / 3f64.sqrt(), 1e-9));
    // A near-degenerate one: altitude 1e-7 of the base.
    let flat = Tin::from_parts(
        vec![DVec3::ZERO, DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.5, 1e-7, 0.0)],
        vec![[0, 1, 2]],
    )
    .expect("valid");
    assert_eq!(flat.validate().near_degenerate_triangles, 1);
}

#[test]
fn huge_offsets_are_an_f32_risk() {
    // UTM-like coordinates with 1 m cells: absolute f32 loses half a metre, local coordinates are fine.
    let tin = grid(10, 10, 1.0, DVec3::new(500_000.0, 5_000_000.0, 100.0));
    let r = tin.validate();
    assert!(r.is_height_field());
    let p = &r.precision;
    assert_eq!(p.origin, DVec3::new(500_000.0, 5_000_000.0, 0.0));
    assert_eq!(p.max_abs_coordinate, 5_000_009.0);
    assert_eq!(p.f32_step_absolute, 0.5);
    assert!(p.absolute_f32_unsafe);
    assert!(!p.local_f32_unsafe);
    assert_eq!(p.min_edge_xy, 1.0);
    // Local coordinates reach the heights (up to 116 m) and 9 m in x,y.
    assert_eq!(p.max_local_coordinate, 116.0);
    assert!(
        r.warnings.iter().any(|w| w.contains("absolute coordinates")),
        "{:?}",
        r.warnings
    );
    // A TIN spanning 20,000 km with a 1 mm triangle: even local f32 coordinates are too coarse.
    let tiny = Tin::from_parts(
        vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2e7, 0.0, 0.0),
            DVec3::new(0.0, 2e7, 0.0),
            DVec3::new(5e6, 5e6, 0.0),
            DVec3::new(5e6 + 0.001, 5e6, 0.0),
            DVec3::new(5e6, 5e6 + 0.001, 0.0),
        ],
        vec![[0, 1, 2], [3, 4, 5]],
    )
    .expect("valid parts");
    let r = tiny.validate();
    assert!(r.precision.local_f32_unsafe);
    assert!(close(r.precision.min_edge_xy, 0.001, 1e-6));
    // The 1 mm triangle lies inside the big one.
    assert_eq!(r.overlapping_pairs, 1);
    assert_eq!(r.overlap_examples, vec![[0, 1]]);
    // Small coordinates raise nothing.
    let small = grid(5, 5, 1.0, DVec3::ZERO).validate();
    assert!(!small.precision.absolute_f32_unsafe && !small.precision.local_f32_unsafe);
}

#[test]
fn overlapping_triangles_are_found() {
    // Tin::from_parts does not check overlap: build a fold where a third triangle covers part of the first.
    let positions = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(4.0, 0.0, 0.0),
        DVec3::new(0.0, 4.0, 0.0),
        DVec3::new(4.0, 4.0, 0.0),
        DVec3::new(1.0, 1.0, 5.0),
        DVec3::new(3.0, 1.0, 5.0),
    ];
    let tin = Tin::from_parts(positions, vec![[0, 1, 2], [1, 3, 2], [4, 5, 2]]).expect("manifold and CCW");
    let r = tin.validate();
    assert!(!r.is_height_field());
    assert_eq!(r.overlapping_pairs, 1);
    assert_eq!(r.overlap_examples, vec![[0, 2]]);
    assert!(r.warnings.iter().any(|w| w.contains("overlapping")), "{:?}", r.warnings);
}

#[test]
fn raw_parts_report_every_problem() {
    let positions = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(f64::NAN, 0.0, 0.0),
        DVec3::new(1.0, 1.0, 3.0), // same x,y as 3
        DVec3::new(7.0, 7.0, 0.0), // unreferenced
        DVec3::new(2.0, 0.0, 0.0),
    ];
    let triangles = vec![
        [0, 1, 2],  // fine
        [1, 3, 2],  // fine
        [0, 2, 1],  // clockwise, overlaps 0, reuses edges 0-2 / 2-1 / 1-0 in directions already used
        [0, 1, 7],  // degenerate (collinear)
        [0, 1, 99], // bad index
        [4, 1, 2],  // non-finite corner
        [3, 5, 1],  // degenerate (3 and 5 share x,y)
    ];
    let r = validate_parts(&positions, &triangles);
    assert_eq!(r.non_finite_vertices, 1);
    assert_eq!(r.non_finite_examples, vec![4]);
    assert_eq!(r.bad_index_triangles, 1);
    assert_eq!(r.duplicate_xy_vertices, 1);
    assert_eq!(r.unreferenced_vertices, 1);
    assert_eq!(r.degenerate_triangles, 2);
    assert_eq!(r.degenerate_examples, vec![3, 6]);
    assert_eq!(r.clockwise_triangles, 1);
    assert_eq!(r.overlapping_pairs, 1);
    assert_eq!(r.overlap_examples, vec![[0, 2]]);
    // 0->1 (triangles 0 and 3), 1->2 (0 and 5), 1->3 (1 and 6) are each used twice in one direction; 0-2 is used
    // once each way, which is fine.
    assert_eq!(r.non_manifold_edges, 3);
    assert!(!r.is_height_field());
    assert!(r.warnings.len() >= 8, "{:?}", r.warnings);
}

/// A valid face of area 0.5 m² at UTM-sized coordinates, whose naive orientation rounds to zero: accepted, because
/// `Tin::from_parts` decides orientation with the one exact predicate.
#[test]
fn from_parts_accepts_a_small_face_that_naive_orientation_calls_degenerate() {
    let k = 134_217_728.0; // 2^27: (k + 1)(k - 1) rounds to k² in f64
    let a = DVec3::new(500_000.0, 5_000_000.0, 10.0);
    // Counter-clockwise: (b - a) x (c - a) = k·k - (k + 1)(k - 1) = 1.
    let b = a + DVec3::new(k, k - 1.0, 1.0);
    let c = a + DVec3::new(k + 1.0, k, 0.0);
    let (ab, ac) = ((b - a).truncate(), (c - a).truncate());
    assert_eq!(ab.perp_dot(ac), 0.0, "the naive formula rounds this face to zero area");
    assert_eq!(tin::orient2d(a.truncate(), b.truncate(), c.truncate()), 1.0);
    let tin = Tin::from_parts(vec![a, b, c], vec![[0, 1, 2]]).expect("a valid counter-clockwise face");
    assert_eq!(tin.triangle_area_xy(0), 0.5);
}

/// A terrain a few millimetres across is warned about (its tolerances are not small against it); one of a metre is not.
#[test]
fn a_terrain_under_a_metre_across_is_warned_about() {
    let tiny = grid(20, 10, 1e-4, DVec3::ZERO).validate();
    assert!(tiny.is_height_field());
    assert!(
        tiny.warnings
            .iter()
            .any(|w| w.contains("the terrain spans only 1.900e-3 m across")),
        "{:?}",
        tiny.warnings
    );
    let metre = grid(11, 11, 0.1, DVec3::ZERO).validate();
    assert!(metre.warnings.is_empty(), "{:?}", metre.warnings);
}

/// A crack: a vertex on an edge of a triangle that does not use it (a T-junction) at another height than the edge
/// there. The triangles only touch, so no overlap is found, but the surface has two heights (0 and 50) at the vertex's
/// x,y. At the edge's own height, or split at the vertex, it is a height field.
#[test]
fn a_crack_is_not_a_height_field() {
    let p = DVec3::new;
    let mut positions = vec![
        p(0.0, 0.0, 0.0),
        p(10.0, 0.0, 0.0),
        p(5.0, 10.0, 0.0),
        p(5.0, -10.0, 0.0),
        p(5.0, 0.0, 50.0),
    ];
    let t_junction = [[0, 1, 2], [0, 3, 4], [4, 3, 1]];
    let r = validate_parts(&positions, &t_junction);
    assert_eq!(
        (r.overlapping_pairs, r.cracks, r.crack_examples.clone()),
        (0, 1, vec![[4, 0]])
    );
    assert!(!r.is_height_field());
    assert!(
        r.warnings.iter().any(|w| w.contains("cracks in the surface")),
        "{:?}",
        r.warnings
    );
    let split = validate_parts(&positions, &[[0, 4, 2], [4, 1, 2], [0, 3, 4], [4, 3, 1]]);
    assert!(split.is_height_field() && split.cracks == 0, "{:?}", split.warnings);
    // The same T-junction at the edge's height (and within rounding of it) leaves the surface whole.
    for z in [0.0, 1e-12] {
        positions[4].z = z;
        let r = validate_parts(&positions, &t_junction);
        assert!(r.is_height_field() && r.cracks == 0, "z {z}: {:?}", r.warnings);
    }
}

/// Every (vertex, triangle) pair of the crack test, by brute force over all pairs with the same exact predicate.
fn cracks_brute(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let used: std::collections::BTreeSet<u32> = triangles.iter().flatten().copied().collect();
    let mut out = Vec::new();
    for &v in &used {
        let q = positions[v as usize];
        for (t, tri) in triangles.iter().enumerate() {
            let c = tri.map(|i| positions[i as usize].truncate());
            let o = tin::orient2d(c[0], c[1], c[2]);
            if o == 0.0 || tri.contains(&v) || c.contains(&q.truncate()) {
                continue;
            }
            let sides = [0, 1, 2].map(|k| o.signum() * tin::orient2d(c[k], c[(k + 1) % 3], q.truncate()));
            let Some(k) = sides.iter().position(|&s| s == 0.0) else {
                continue;
            };
            if sides.iter().any(|&s| s < 0.0) {
                continue;
            }
            let (a, b) = (positions[tri[k] as usize], positions[tri[(k + 1) % 3] as usize]);
            let d = b - a;
            let s = if d.x.abs() >= d.y.abs() {
                (q.x - a.x) / d.x
            } else {
                (q.y - a.y) / d.y
            };
            if (q.z - (a.z + s * d.z)).abs() > 1e-9 * (1.0 + a.z.abs() + b.z.abs() + q.z.abs()) {
                out.push([v, t as u32]);
            }
        }
    }
    out
}

proptest::proptest! {
    /// The gridded search finds exactly the pairs that brute force finds, on random triangle soups over a small
    /// integer lattice (so that vertices often fall on edges, at corners and on edge lines outside the edge, at the
    /// edge's height or not).
    #[test]
    fn cracks_match_brute_force(
        points in proptest::collection::vec((0i32..6, 0i32..6, 0i32..3), 3..14),
        tris in proptest::collection::vec((0usize..14, 0usize..14, 0usize..14), 1..10),
    ) {
        let positions: Vec<DVec3> =
            points.iter().map(|&(x, y, z)| DVec3::new(f64::from(x), f64::from(y), f64::from(z))).collect();
        let n = positions.len();
        let triangles: Vec<[u32; 3]> =
            tris.iter().map(|&(a, b, c)| [(a % n) as u32, (b % n) as u32, (c % n) as u32]).collect();
        let found = tin::find_cracks(&positions, &triangles, usize::MAX);
        let mut want = cracks_brute(&positions, &triangles);
        want.sort_unstable();
        proptest::prop_assert_eq!(found.count, want.len());
        proptest::prop_assert_eq!(found.first, want);
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(100))]

    /// The same on fans: spokes from a centre to lattice points (long thin triangles over many cells), with vertices
    /// at the spokes' midpoints at the spoke's height or not, used by small triangles beside them, and vertices
    /// placed exactly on the grid's cell edges by the lattice.
    #[test]
    fn cracks_match_brute_force_on_fans(
        rim in proptest::collection::vec((-12i32..=12, -12i32..=12, 0i32..4), 3..40),
        lifts in proptest::collection::vec(0i32..3, 40),
    ) {
        let mut rim: Vec<(i32, i32, i32)> = rim.into_iter().filter(|&(x, y, _)| (x, y) != (0, 0)).collect();
        rim.sort_by(|a, b| f64::from(a.1).atan2(f64::from(a.0)).total_cmp(&f64::from(b.1).atan2(f64::from(b.0))));
        rim.dedup_by_key(|p| (p.0, p.1));
        let mut positions = vec![DVec3::ZERO];
        positions.extend(rim.iter().map(|&(x, y, z)| DVec3::new(f64::from(x), f64::from(y), f64::from(z))));
        let k = rim.len() as u32;
        let mut triangles: Vec<[u32; 3]> = (0..k).map(|i| [0, i + 1, (i + 1) % k + 1]).collect();
        // A midpoint of each even spoke, a little triangle on it: on the spoke's line at its height (lift 1) or not.
        for (i, &(x, y, z)) in rim.iter().enumerate() {
            if x % 2 == 0 && y % 2 == 0 {
                let lift = f64::from(lifts[i % lifts.len()]) - 1.0;
                let m = positions.len() as u32;
                positions.push(DVec3::new(f64::from(x / 2), f64::from(y / 2), 0.5 * f64::from(z) + lift));
                positions.push(DVec3::new(f64::from(x / 2) + 0.25, f64::from(y / 2) + 0.5, 0.0));
                triangles.push([m, m + 1, i as u32 + 1]);
            }
        }
        let found = tin::find_cracks(&positions, &triangles, usize::MAX);
        let mut want = cracks_brute(&positions, &triangles);
        want.sort_unstable();
        proptest::prop_assert_eq!(found.count, want.len());
        proptest::prop_assert_eq!(found.first, want);
    }
}
