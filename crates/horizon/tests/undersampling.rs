//! The undersampling fix: the fast implementation (used by `compute`) against the straightforward one (used by
//! `brute_force`), and a configuration with a known answer.

mod common;

use common::{CONFIGS, KINDS, assert_same, config, terrain};
use glam::DVec3;
use horizon::{HorizonOptions, HorizonPoint, SectorGeometry, brute_force, compute};
use proptest::prelude::*;
use tin::{DedupePolicy, triangulate};

fn with_radius(radius: f64) -> HorizonOptions {
    HorizonOptions {
        undersampling_radius: Some(radius),
        ..HorizonOptions::default()
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    #[test]
    fn fast_equals_straightforward(kind in 0usize..KINDS.len(), n in 3usize..90, seed in any::<u64>(),
                                   radius_factor in 0.2f64..3.0, cfg in 0usize..CONFIGS.len()) {
        let kind = KINDS[kind];
        if let Some(tin) = terrain(kind, n, seed) {
            let (s, k) = CONFIGS[cfg];
            let cfg = config(s, k);
            let extent = tin.bbox().size().truncate().max_element().max(1.0);
            let radius = extent * radius_factor / (n as f64).sqrt();
            let opts = with_radius(radius);
            let fast = compute(&tin, &cfg, &opts).expect("valid");
            let reference = brute_force(&tin, &cfg, &opts).expect("valid");
            assert_same(&fast, &reference, &format!("{kind:?} n={n} seed={seed} {s}x{k} radius {radius}"));
        }
    }
}

#[test]
fn edge_points_appear_on_sparse_terrain_and_only_raise_slopes() {
    let mut total = 0;
    for (i, kind) in KINDS.into_iter().enumerate() {
        let tin = terrain(kind, 400, 77 + i as u64).expect("triangulates");
        for (s, k) in [(16u32, 4u32), (64, 1)] {
            let cfg = config(s, k);
            let g = SectorGeometry::new(&cfg);
            let extent = tin.bbox().size().truncate().max_element();
            let opts = with_radius(extent / 10.0);
            let fixed = compute(&tin, &cfg, &opts).expect("valid");
            let plain = compute(&tin, &cfg, &HorizonOptions::default()).expect("valid");
            assert_same(
                &fixed,
                &brute_force(&tin, &cfg, &opts).expect("valid"),
                &format!("{kind:?} {s}x{k}"),
            );
            total += fixed.edge_horizon_count();
            let o = tin.origin().truncate();
            for v in 0..tin.num_vertices() as u32 {
                for j in 0..g.total() as u32 {
                    // The vertex horizon is kept; an edge point replaces it only when strictly better.
                    assert_eq!(fixed.horizon(v, j), plain.horizon(v, j));
                    if let Some(HorizonPoint::Edge(e)) = fixed.horizon_point(v, j) {
                        let w = g.wedge(j as usize);
                        let p = tin.position(v);
                        let slope = |q: DVec3| (q.z - p.z) / (w.project(o, q.truncate()) - w.project(o, p.truncate()));
                        if let Some(h) = plain.horizon(v, j) {
                            assert!(slope(e.point) >= slope(tin.position(h)) - 1e-9);
                        }
                        // The point lies on its edge, on the centre ray of the subsector.
                        let (a, b) = (tin.position(e.edge[0]), tin.position(e.edge[1]));
                        let along = (e.point - a).truncate().perp_dot((b - a).truncate()).abs();
                        assert!(along <= 1e-6 * (b - a).length() * (e.point - a).length().max(1.0));
                        assert!(w.r.perp_dot((e.point - p).truncate()).abs() < 1e-6 * (e.point - p).length());
                    }
                }
            }
        }
    }
    assert!(total > 0, "sparse random terrains should have some edge horizons");
}

#[test]
fn tiny_radius_changes_nothing() {
    let tin = terrain(common::Kind::Uniform, 300, 5).expect("triangulates");
    let cfg = config(8, 8);
    let fixed = compute(&tin, &cfg, &with_radius(1e-3)).expect("valid");
    assert_eq!(fixed.edge_horizon_count(), 0);
    assert_eq!(
        fixed.mismatches(&compute(&tin, &cfg, &HorizonOptions::default()).expect("valid")),
        0
    );
}

/// A high edge from (10, −30) to (10, 30) in front of vertex 0 at the origin spans the subsectors around east;
/// only a far, low vertex lies in them. With the fix, the horizon there is where the edge crosses the centre ray.
#[test]
fn a_spanning_edge_becomes_the_horizon() {
    let pts = [
        DVec3::new(0.0, 0.0, 0.0),     // 0: p
        DVec3::new(10.0, -30.0, 50.0), // 1: u
        DVec3::new(10.0, 30.0, 50.0),  // 2: w
        DVec3::new(-10.0, 0.0, 0.0),   // 3
        DVec3::new(200.0, 0.0, 0.0),   // 4: far and low, due east
    ];
    let (tin, _) = triangulate(&pts, DedupePolicy::Reject).expect("triangulates");
    let has_edge = tin
        .triangles()
        .iter()
        .any(|t| t.contains(&1) && t.contains(&2) && t.contains(&0));
    assert!(has_edge, "the test needs the edge 1-2 next to vertex 0");
    let cfg = config(16, 1);
    let g = SectorGeometry::new(&cfg);
    let fixed = compute(&tin, &cfg, &with_radius(35.0)).expect("valid");
    let plain = compute(&tin, &cfg, &HorizonOptions::default()).expect("valid");
    assert_same(
        &fixed,
        &brute_force(&tin, &cfg, &with_radius(35.0)).expect("valid"),
        "spanning edge",
    );
    // Subsectors 0 and 15 contain vertex 4 (due east, on their shared boundary); 3 and 12 contain 2 and 1.
    assert_eq!(plain.horizon(0, 0), Some(4));
    assert_eq!(plain.horizon(0, 15), Some(4));
    assert_eq!(plain.horizon(0, 1), None);
    assert_eq!(fixed.horizon(0, 3), Some(2));
    assert_eq!(fixed.horizon(0, 12), Some(1));
    for j in [0u32, 1, 2, 13, 14, 15] {
        let r = g.wedge(j as usize).r;
        match fixed.horizon_point(0, j) {
            Some(HorizonPoint::Edge(e)) => {
                assert_eq!(e.edge, [1, 2]);
                let expect = r * (10.0 / r.x);
                assert!(
                    (e.point.truncate() - expect).length() < 1e-9,
                    "subsector {j}: {e:?} expected {expect}"
                );
                assert!((e.point.z - 50.0).abs() < 1e-9);
            }
            other => panic!("subsector {j}: expected an edge point, got {other:?}"),
        }
    }
    // The sector summary of sector 0 (subsector 0 alone) now uses the edge point: slope 50 / (10 / cos 11.25°).
    let sum = fixed.sector_summary(0, 0).expect("horizon");
    let r0 = g.wedge(0).r;
    assert!((sum.slope - 50.0 * r0.x / 10.0).abs() < 1e-9, "slope {}", sum.slope);
    assert!((sum.distance - 10.0 / r0.x).abs() < 1e-9);
    // A radius that reaches neither endpoint disables the fix for that edge.
    let short = compute(&tin, &cfg, &with_radius(31.0)).expect("valid");
    assert_eq!(short.horizon_point(0, 1), None);
}

#[test]
fn all_configs_agree_on_a_utm_grid() {
    let tin = terrain(common::Kind::UtmGrid, 225, 9).expect("triangulates");
    for (s, k) in CONFIGS {
        let cfg = config(s, k);
        let opts = with_radius(2.5);
        assert_same(
            &compute(&tin, &cfg, &opts).expect("valid"),
            &brute_force(&tin, &cfg, &opts).expect("valid"),
            &format!("utm grid {s}x{k}"),
        );
    }
}
