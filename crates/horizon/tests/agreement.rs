//! The sweep must return exactly the oracle's horizon for every vertex and subsector.

mod common;

use common::{CONFIGS, KINDS, Kind, assert_same, config, terrain};
use glam::DVec3;
use horizon::{HorizonOptions, brute_force, compute};
use proptest::prelude::*;
use tin::Tin;

fn check_all_configs(tin: &Tin, what: &str) {
    let opts = HorizonOptions::default();
    for (s, k) in CONFIGS {
        let cfg = config(s, k);
        let sweep = compute(tin, &cfg, &opts).expect("valid input");
        let oracle = brute_force(tin, &cfg, &opts).expect("valid input");
        assert_same(&sweep, &oracle, &format!("{what} at {s}x{k}"));
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn sweep_equals_oracle(kind in 0usize..KINDS.len(), n in 3usize..130, seed in any::<u64>()) {
        let kind = KINDS[kind];
        if let Some(tin) = terrain(kind, n, seed) {
            check_all_configs(&tin, &format!("{kind:?} n={n} seed={seed}"));
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// An exact translation (integer coordinates, integer offsets) gives the same horizons and sector summaries (equal
    /// to the last bit): projections are relative to the bounding-box corner, which moves with the terrain.
    #[test]
    fn exact_translation_gives_the_same_field(
        kind in prop_oneof![Just(Kind::IntegerGrid), Just(Kind::UtmGrid), Just(Kind::Spike), Just(Kind::CollinearRows)],
        n in 9usize..130,
        seed in any::<u64>(),
        dx in 0u32..1_000_000,
        dy in 0u32..5_000_000,
    ) {
        let Some(tin) = terrain(kind, n, seed) else { return Ok(()) };
        let off = DVec3::new(f64::from(dx), f64::from(dy), 0.0);
        let moved = Tin::from_parts(tin.positions().iter().map(|&p| p + off).collect(), tin.triangles().to_vec())
            .expect("valid mesh");
        prop_assert!(moved.positions().iter().zip(tin.positions()).all(|(m, p)| *m - off == *p), "exact");
        prop_assert_eq!(moved.bbox().min - off, tin.bbox().min);
        for (s, k) in [(8, 4), (16, 4)] {
            let cfg = config(s, k);
            let a = compute(&tin, &cfg, &HorizonOptions::default()).expect("valid input");
            let b = compute(&moved, &cfg, &HorizonOptions::default()).expect("valid input");
            prop_assert_eq!(b.origin() - off.truncate(), a.origin());
            for v in 0..tin.num_vertices() as u32 {
                for j in 0..s * k {
                    prop_assert_eq!(a.horizon(v, j), b.horizon(v, j), "vertex {} subsector {}", v, j);
                }
                for i in 0..s {
                    // Equal values (a height of −0.0 moved by +0.0 becomes +0.0, so a zero slope may change sign).
                    prop_assert_eq!(a.sector_summary(v, i), b.sector_summary(v, i), "vertex {} sector {}", v, i);
                }
            }
        }
    }
}

#[test]
fn every_kind_at_a_larger_size() {
    for (i, kind) in KINDS.into_iter().enumerate() {
        let tin = terrain(kind, 600, 1000 + i as u64).expect("not collinear");
        check_all_configs(&tin, &format!("{kind:?} n=600"));
    }
}

#[test]
fn results_do_not_depend_on_thread_count() {
    let tin = terrain(Kind::Uniform, 500, 7).expect("triangulates");
    let cfg = config(8, 8);
    let opts = HorizonOptions {
        undersampling_radius: Some(120.0),
        ..HorizonOptions::default()
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool")
        .install(|| compute(&tin, &cfg, &opts).expect("valid"));
    let three = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .expect("pool")
        .install(|| compute(&tin, &cfg, &opts).expect("valid"));
    assert!(one == three);
}

/// Vertices with identical x,y (an unreferenced duplicate) or closer than the rounding of `t`: such members have
/// `t_q ≤ t_p` and are no candidates; the sweep must notice and still match the oracle.
#[test]
fn coincident_and_nearly_coincident_vertices() {
    let mut positions: Vec<DVec3> = (0..25)
        .map(|i| {
            DVec3::new(
                500_000.0 + (i % 5) as f64,
                5_000_000.0 + (i / 5) as f64,
                ((i * 7) % 3) as f64,
            )
        })
        .collect();
    let mut triangles = Vec::new();
    for r in 0..4u32 {
        for c in 0..4u32 {
            let v = r * 5 + c;
            triangles.push([v, v + 1, v + 6]);
            triangles.push([v, v + 6, v + 5]);
        }
    }
    // Unreferenced duplicates of vertex 12 (higher) and a point 1e-11 m east of vertex 6.
    positions.push(DVec3::new(positions[12].x, positions[12].y, 9.0));
    positions.push(DVec3::new(positions[6].x + 1e-11, positions[6].y, 5.0));
    positions.push(DVec3::new(positions[6].x, positions[6].y + 1e-11, 4.0));
    let tin = Tin::from_parts(positions, triangles).expect("valid mesh");
    check_all_configs(&tin, "coincident");
}

#[test]
fn tiny_and_empty_inputs() {
    let tri = Tin::from_parts(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]]).expect("valid");
    check_all_configs(&tri, "one triangle");
    let cfg = config(4, 1);
    let field = compute(&tri, &cfg, &HorizonOptions::default()).expect("valid");
    // Vertex 0 sees vertex 1 (east, 0°) in subsector 0 (boundary 0°) and subsector 3 (boundary 360°),
    // and vertex 2 (north, 90°) in subsectors 0 and 1.
    assert_eq!(field.horizon(0, 3), Some(1));
    assert_eq!(field.horizon(0, 1), Some(2));
    assert_eq!(field.horizon(0, 2), None);
    // In subsector 0 both have slope 0 and t = 1/sqrt(2): the smaller index wins.
    assert_eq!(field.horizon(0, 0), Some(1));
    assert_eq!(field.horizon(99, 0), None);
    assert_eq!(field.horizon(0, 4), None);
    assert_eq!(field.sector_summary(0, 2), None);
    let s = field.sector_summary(0, 0).expect("sector 0 has a horizon");
    assert_eq!(s.slope, 0.0);
}

#[test]
fn rejects_bad_options_and_coordinates() {
    let tri = Tin::from_parts(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]]).expect("valid");
    let cfg = config(8, 1);
    for radius in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let opts = HorizonOptions {
            undersampling_radius: Some(radius),
            ..HorizonOptions::default()
        };
        assert!(matches!(
            compute(&tri, &cfg, &opts),
            Err(horizon::HorizonError::InvalidRadius { .. })
        ));
        assert!(matches!(
            brute_force(&tri, &cfg, &opts),
            Err(horizon::HorizonError::InvalidRadius { .. })
        ));
    }
    let huge =
        Tin::from_parts(vec![DVec3::ZERO, DVec3::new(1e40, 0.0, 0.0), DVec3::Y], vec![[0, 1, 2]]).expect("valid mesh");
    assert!(matches!(
        compute(&huge, &cfg, &HorizonOptions::default()),
        Err(horizon::HorizonError::CoordinateOutOfRange {
            vertex: 2,
            axis: "x",
            ..
        })
    ));
}

#[test]
fn progress_reports_every_subsector() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicUsize, Ordering};
    let tin = terrain(Kind::Uniform, 100, 3).expect("triangulates");
    let calls = Arc::new(AtomicUsize::new(0));
    let seen = calls.clone();
    let opts = HorizonOptions {
        undersampling_radius: None,
        progress: Some(Arc::new(move |_, total| {
            assert_eq!(total, 15);
            seen.fetch_add(1, Ordering::Relaxed);
        })),
    };
    compute(&tin, &config(5, 3), &opts).expect("valid");
    assert_eq!(calls.load(Ordering::Relaxed), 15);
}
