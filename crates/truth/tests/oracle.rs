//! The segment walk and triangle visibility against the brute-force oracle (segment against every triangle's
//! prism), on random TINs (convex and with holes cut out) and on integer grids where segments pass exactly through
//! vertices and along edges.

mod common;

use common::{Verdict, oracle, point_in};
use glam::DVec3;
use proptest::prelude::*;
use tin::{DedupePolicy, Tin, triangulate};
use truth::{GroundTruth, Locator, point_visible};

/// Delaunay TIN of random points; when `hole` is given, triangles whose centroid lies within the disk
/// (centre x, centre y, radius) are removed (unless that removes all), giving non-convex footprints and holes.
fn random_tin(pts: &[(f64, f64, f64)], hole: Option<(f64, f64, f64)>) -> Option<Tin> {
    let points: Vec<DVec3> = pts.iter().map(|&(x, y, z)| DVec3::new(x, y, z)).collect();
    let (tin, _) = triangulate(&points, DedupePolicy::KeepHighest).ok()?;
    let Some((cx, cy, r)) = hole else { return Some(tin) };
    let keep: Vec<[u32; 3]> = (0..tin.num_triangles())
        .filter(|&t| common::centroid(&tin, t).truncate().distance(glam::DVec2::new(cx, cy)) > r)
        .map(|t| tin.triangles()[t])
        .collect();
    if keep.is_empty() {
        return Some(tin);
    }
    let (positions, _) = tin.into_parts();
    Some(Tin::from_parts(positions, keep).expect("a subset of a valid TIN is valid"))
}

/// Targets on the terrain: a random interior point, a vertex, and a point on an edge, of random triangles.
fn targets(tin: &Tin, picks: &[(prop::sample::Index, f64, f64)]) -> Vec<DVec3> {
    let mut out = Vec::new();
    for (i, (idx, u, v)) in picks.iter().enumerate() {
        let t = idx.index(tin.num_triangles());
        out.push(match i % 3 {
            0 => point_in(tin, t, *u, *v),
            1 => tin.corners(t)[(u * 3.0) as usize % 3],
            _ => point_in(tin, t, *u, 0.0),
        });
    }
    out
}

fn check(tin: &Tin, loc: &Locator, eye: DVec3, target: DVec3, decided: &mut usize) -> Result<(), TestCaseError> {
    let got = point_visible(tin, loc, eye, target);
    match oracle(tin, eye, target) {
        Verdict::Visible => {
            prop_assert!(got, "oracle: visible; walk: hidden (eye {eye}, target {target})");
            *decided += 1;
        }
        Verdict::Hidden => {
            prop_assert!(!got, "oracle: hidden; walk: visible (eye {eye}, target {target})");
            *decided += 1;
        }
        Verdict::Unclear => {}
    }
    Ok(())
}

fn pick() -> impl Strategy<Value = (prop::sample::Index, f64, f64)> {
    (any::<prop::sample::Index>(), 0.0f64..1.0, 0.0f64..1.0)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: common::cases(192), ..ProptestConfig::default() })]

    #[test]
    fn walk_matches_oracle_on_random_tins(
        pts in prop::collection::vec((0.0f64..100.0, 0.0f64..100.0, 0.0f64..30.0), 4..40),
        hole in prop::option::of((0.0f64..100.0, 0.0f64..100.0, 5.0f64..45.0)),
        eyes in prop::collection::vec((-30.0f64..130.0, -30.0f64..130.0, -10.0f64..60.0), 1..4),
        picks in prop::collection::vec(pick(), 6),
    ) {
        let Some(tin) = random_tin(&pts, hole) else { return Ok(()) };
        let loc = Locator::new(&tin);
        let mut decided = 0;
        for &(x, y, z) in &eyes {
            let eye = DVec3::new(x, y, z);
            for target in targets(&tin, &picks) {
                check(&tin, &loc, eye, target, &mut decided)?;
            }
            // Eye exactly above a vertex and above a point on an edge.
            let above_vertex = tin.corners(picks[0].0.index(tin.num_triangles()))[0] + DVec3::Z * z.abs();
            let above_edge = point_in(&tin, picks[1].0.index(tin.num_triangles()), x / 130.0, 0.0) + DVec3::Z * 3.0;
            for target in targets(&tin, &picks) {
                check(&tin, &loc, above_vertex, target, &mut decided)?;
                check(&tin, &loc, above_edge, target, &mut decided)?;
            }
        }
        prop_assert!(decided > 0);
    }

    #[test]
    fn walk_matches_oracle_on_integer_grids(
        w in 2usize..8, h in 2usize..8,
        z in prop::collection::vec(0i32..6, 64),
        eyes in prop::collection::vec((-4i32..18, -4i32..18, -2i32..16), 4),
        targets in prop::collection::vec((0i32..16, 0i32..16), 8),
        hole in prop::option::of((0i32..8, 0i32..8, 1i32..3)),
    ) {
        // Heights on a grid of spacing 2, so that eyes and targets at odd coordinates sit on edge midpoints and
        // cell centres: segments pass exactly through vertices and along edges.
        let pts: Vec<(f64, f64, f64)> = (0..w * h)
            .map(|i| ((2 * (i % w)) as f64, (2 * (i / w)) as f64, f64::from(z[i])))
            .collect();
        let hole = hole.map(|(x, y, r)| (2.0 * f64::from(x) + 1.0, 2.0 * f64::from(y) + 1.0, f64::from(r)));
        let Some(tin) = random_tin(&pts, hole) else { return Ok(()) };
        let loc = Locator::new(&tin);
        let mut decided = 0;
        for &(ex, ey, ez) in &eyes {
            let eye = DVec3::new(f64::from(ex) * 0.5, f64::from(ey) * 0.5, f64::from(ez) * 0.5);
            for &(tx, ty) in &targets {
                let xy = glam::DVec2::new(f64::from(tx % (2 * w as i32 - 1)), f64::from(ty % (2 * h as i32 - 1)));
                let Some(ground) = loc.ground_height(&tin, xy) else { continue };
                let target = xy.extend(ground);
                check(&tin, &loc, eye, target, &mut decided)?;
            }
        }
    }

    #[test]
    fn triangle_visibility_matches_oracle(
        pts in prop::collection::vec((0.0f64..100.0, 0.0f64..100.0, 0.0f64..30.0), 4..25),
        hole in prop::option::of((0.0f64..100.0, 0.0f64..100.0, 5.0f64..45.0)),
        eye in (-30.0f64..130.0, -30.0f64..130.0, 0.0f64..80.0),
    ) {
        let Some(tin) = random_tin(&pts, hole) else { return Ok(()) };
        let gt = GroundTruth::new(&tin);
        let eye = DVec3::new(eye.0, eye.1, eye.2);
        let vis = gt.visible_triangles(eye);
        prop_assert_eq!(vis.len(), tin.num_triangles());
        for (t, &v) in vis.iter().enumerate() {
            // Height of the eye above the triangle's plane, from the 3-D normal.
            let [a, b, c] = tin.corners(t);
            let n = (b - a).cross(c - a);
            let h_rel = n.dot(eye - a) / n.z;
            let verdicts: Vec<Verdict> = gt.samples(eye, t).iter().map(|&s| oracle(&tin, eye, s)).collect();
            if v {
                prop_assert!(h_rel > -1e-5, "triangle {} facing away (by {}) but visible", t, h_rel);
                prop_assert!(verdicts.iter().any(|&x| x != Verdict::Hidden), "triangle {} visible, all samples hidden", t);
            } else if h_rel > 1e-5 {
                prop_assert!(verdicts.iter().all(|&x| x != Verdict::Visible), "triangle {} hidden, a sample visible", t);
            }
        }
    }
}

#[test]
fn triangle_visibility_does_not_depend_on_threads() {
    let tin = common::grid_tin(30, 30, 10.0, |x, y| {
        20.0 * (x / 40.0).sin() * (y / 55.0).cos() + 0.1 * x
    });
    let gt = GroundTruth::new(&tin);
    let eye = DVec3::new(37.0, 141.0, 12.0);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool")
        .install(|| gt.visible_triangles(eye));
    let many = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()
        .expect("pool")
        .install(|| gt.visible_triangles(eye));
    assert_eq!(one, many);
    let visible = one.iter().filter(|&&v| v).count();
    assert!(
        visible > 0 && visible < tin.num_triangles(),
        "{visible} visible: a non-trivial case"
    );
}

/// `visible_triangles` (back faces skipped, blocking edges reused between samples) against the definition applied
/// directly: not back-facing and some sample visible by an independent walk from the located sample.
#[test]
fn triangle_visibility_is_the_sample_definition() {
    let tin = common::grid_tin(25, 25, 10.0, |x, y| {
        15.0 * (x / 30.0).sin() * (y / 45.0).cos() + 8.0 * ((x + y) / 17.0).sin() + 0.05 * x
    });
    let gt = GroundTruth::new(&tin);
    let mut visible_total = 0;
    for eye in [
        DVec3::new(120.0, 120.0, 30.0),
        DVec3::new(13.0, 201.0, 25.0),
        DVec3::new(-40.0, 80.0, 35.0),
        DVec3::new(200.0, 3.0, 80.0),
    ] {
        let vis = gt.visible_triangles(eye);
        for (t, &v) in vis.iter().enumerate() {
            let expected = !gt.back_facing(eye, t) && gt.samples(eye, t).iter().any(|&s| gt.point_visible(eye, s));
            assert_eq!(v, expected, "triangle {t} from {eye}");
        }
        visible_total += vis.iter().filter(|&&v| v).count();
    }
    assert!(visible_total > 100 && visible_total < 4 * tin.num_triangles() - 100);
}
