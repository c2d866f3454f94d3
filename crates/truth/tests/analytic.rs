//! Ground truth on terrains whose visible sets are known analytically: a ridge between two valleys, a convex
//! pyramid (a 36-sided cone) on a plain, tilted planes, and a U-shaped (non-convex) footprint.

mod common;

use common::{Verdict, centroid, grid_tin, oracle};
use glam::DVec3;
use tin::Tin;
use truth::GroundTruth;

/// Valley floor (z = 0) for x <= 60, slope up to a ridge of 50 m at x = 100, down to the far floor at x = 140,
/// flat to x = 200. Constant in y over 0..100. Grid spacing 10 m, so every break of slope is a grid line.
fn ridge_z(x: f64) -> f64 {
    if x <= 60.0 {
        0.0
    } else if x <= 100.0 {
        (x - 60.0) * 1.25
    } else if x <= 140.0 {
        (140.0 - x) * 1.25
    } else {
        0.0
    }
}

fn ridge() -> Tin {
    grid_tin(21, 11, 10.0, |x, _| ridge_z(x))
}

#[test]
fn ridge_hides_the_far_valley() {
    let tin = ridge();
    let gt = GroundTruth::new(&tin);
    let eye = DVec3::new(30.0, 50.0, 2.0); // 2 m above a grid vertex of the near floor
    let vis = gt.visible_triangles(eye);
    for (t, &v) in vis.iter().enumerate() {
        let c = centroid(&tin, t);
        // Near floor and near slope visible; far slope (back-facing) and far floor (behind the ridge) hidden.
        assert_eq!(v, c.x < 100.0, "triangle {t} at {c}");
    }
    // From 1 km up, the far slope faces the eye too and both slopes show over the ridge: everything is visible.
    let vis = gt.visible_triangles(DVec3::new(30.0, 50.0, 1000.0));
    assert!(vis.iter().all(|&v| v));
}

#[test]
fn ridge_points_along_grid_lines() {
    let tin = ridge();
    let gt = GroundTruth::new(&tin);
    let eye = DVec3::new(30.0, 50.0, 2.0);
    let on = |x: f64, y: f64| DVec3::new(x, y, ridge_z(x));
    // Along y = 50 the segment runs exactly along grid edges and through vertices.
    assert!(
        gt.point_visible(eye, on(100.0, 50.0)),
        "ridge crest vertex, grazing the near slope: visible"
    );
    assert!(gt.point_visible(eye, on(80.0, 50.0)));
    assert!(!gt.point_visible(eye, on(150.0, 50.0)), "far floor");
    assert!(!gt.point_visible(eye, on(120.0, 50.0)), "far slope");
    // Eye on a grid edge, not a vertex.
    assert!(!gt.point_visible(DVec3::new(35.0, 50.0, 2.0), on(150.0, 50.0)));
    assert!(gt.point_visible(DVec3::new(35.0, 50.0, 2.0), on(95.0, 55.0)));
    // Far above: the far floor shows over the ridge.
    assert!(gt.point_visible(DVec3::new(30.0, 50.0, 1000.0), on(150.0, 50.0)));
    // Eye outside the footprint, west of it.
    assert!(gt.point_visible(DVec3::new(-100.0, 50.0, 60.0), on(80.0, 50.0)));
    assert!(!gt.point_visible(DVec3::new(-100.0, 50.0, 60.0), on(150.0, 50.0)));
    // Eye below the floor: sees nothing, not even the floor right above it.
    let buried = DVec3::new(30.0, 50.0, -1.0);
    assert!(!gt.point_visible(buried, on(30.0, 60.0)));
    assert!(!gt.point_visible(buried, on(30.0, 50.0)), "vertical segment, eye below");
    assert!(gt.visible_triangles(buried).iter().all(|&v| !v));
    // Vertical segment, eye above.
    assert!(gt.point_visible(DVec3::new(80.0, 50.0, 26.0), on(80.0, 50.0)));
    // Every case agrees with the brute-force oracle.
    for (e, p) in [
        (eye, on(100.0, 50.0)),
        (eye, on(150.0, 50.0)),
        (DVec3::new(-100.0, 50.0, 60.0), on(80.0, 50.0)),
        (DVec3::new(30.0, 50.0, 1000.0), on(150.0, 50.0)),
    ] {
        let expected = oracle(&tin, e, p);
        assert_ne!(expected, Verdict::Unclear);
        assert_eq!(
            gt.point_visible(e, p),
            expected == Verdict::Visible,
            "eye {e} target {p}"
        );
    }
}

/// A convex 36-sided pyramid (apex 100 m at the origin, base radius 100 m) on a flat plain out to radius 200 m,
/// built ring by ring along 36 generators so that every face is planar.
fn cone() -> Tin {
    let m = 36usize;
    let radii = [
        10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0, 120.0, 140.0, 170.0, 200.0,
    ];
    let z = |r: f64| (100.0 - r).max(0.0);
    let mut pos = vec![DVec3::new(0.0, 0.0, 100.0)];
    for &r in &radii {
        for k in 0..m {
            let a = std::f64::consts::TAU * k as f64 / m as f64;
            pos.push(DVec3::new(r * a.cos(), r * a.sin(), z(r)));
        }
    }
    let ring = |i: usize, k: usize| (1 + i * m + k % m) as u32;
    let mut tris = Vec::new();
    for k in 0..m {
        tris.push([0, ring(0, k), ring(0, k + 1)]);
    }
    for i in 0..radii.len() - 1 {
        for k in 0..m {
            tris.push([ring(i, k), ring(i + 1, k), ring(i + 1, k + 1)]);
            tris.push([ring(i, k), ring(i + 1, k + 1), ring(i, k + 1)]);
        }
    }
    Tin::from_parts(pos, tris).expect("valid cone")
}

#[test]
fn cone_hides_its_far_side_and_its_shadow() {
    let tin = cone();
    let gt = GroundTruth::new(&tin);
    assert!(gt.locator().footprint_is_convex());
    let eye = DVec3::new(-150.0, 0.0, 2.0);
    let vis = gt.visible_triangles(eye);
    let (mut checked_hidden, mut checked_visible) = (0, 0);
    for (t, &v) in vis.iter().enumerate() {
        let corners = tin.corners(t);
        let c = centroid(&tin, t);
        let on_cone = corners.iter().all(|p| p.truncate().length() <= 100.0 + 1e-9);
        let azimuth = c.y.atan2(c.x).to_degrees().abs();
        if on_cone && azimuth < 110.0 {
            assert!(!v, "far face {t} at azimuth {azimuth}");
            checked_hidden += 1;
        }
        if on_cone && azimuth > 150.0 {
            assert!(v, "near face {t} at azimuth {azimuth}");
            checked_visible += 1;
        }
        let ground = corners.iter().all(|p| p.z == 0.0);
        if ground && corners.iter().all(|p| p.x > 100.0 && p.y.abs() < 50.0) {
            assert!(!v, "ground {t} in the cone's shadow");
            checked_hidden += 1;
        }
        if ground && corners.iter().all(|p| p.x < -100.0) {
            assert!(v, "ground {t} around the eye");
            checked_visible += 1;
        }
    }
    assert!(
        checked_hidden > 100 && checked_visible > 50,
        "{checked_hidden} / {checked_visible}"
    );
    // From far above the apex everything is visible.
    assert!(gt.visible_triangles(DVec3::new(0.0, 0.0, 5000.0)).iter().all(|&v| v));
}

#[test]
fn tilted_plane() {
    let plane = |x: f64, y: f64| 0.1 * x + 0.05 * y;
    let tin = grid_tin(11, 11, 10.0, plane);
    let gt = GroundTruth::new(&tin);
    let n = tin.num_triangles();
    let count = |eye: DVec3| gt.visible_triangles(eye).iter().filter(|&&v| v).count();
    assert_eq!(count(DVec3::new(43.0, 57.0, plane(43.0, 57.0) + 20.0)), n, "eye above");
    assert_eq!(
        count(DVec3::new(43.0, 57.0, plane(43.0, 57.0) + 1e5)),
        n,
        "eye far above"
    );
    assert_eq!(
        count(DVec3::new(43.0, 57.0, plane(43.0, 57.0) - 1.0)),
        0,
        "eye below the surface"
    );
    // Eye exactly in the surface: every segment lies in it, grazing all the way, so everything is visible.
    assert_eq!(
        count(DVec3::new(40.0, 50.0, plane(40.0, 50.0))),
        n,
        "eye in the surface"
    );
    // Outside the footprint: above the plane's extension everything shows, below it nothing does.
    assert_eq!(count(DVec3::new(-50.0, 50.0, 0.0)), n);
    assert_eq!(count(DVec3::new(-50.0, 50.0, -10.0)), 0);
    assert_eq!(count(DVec3::new(f64::NAN, 50.0, 10.0)), 0);
}

/// A U-shaped footprint of 10 m cells: bottom row x 0..30, left arm x 0..10 and right arm x 20..30 up to y = 30.
/// `wall` is the height of the two vertices (20, 20) and (20, 30) at the inner side of the right arm.
fn u_shape(wall: f64) -> Tin {
    let mut pos = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            let (x, y) = (10.0 * i as f64, 10.0 * j as f64);
            let z = if i == 2 && j >= 2 { wall } else { 0.0 };
            pos.push(DVec3::new(x, y, z));
        }
    }
    let v = |i: u32, j: u32| j * 4 + i;
    let mut tris = Vec::new();
    for (i, j) in [(0, 0), (1, 0), (2, 0), (0, 1), (0, 2), (2, 1), (2, 2)] {
        tris.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
        tris.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
    }
    Tin::from_parts(pos, tris).expect("valid U")
}

#[test]
fn segment_leaves_and_re_enters_a_non_convex_footprint() {
    // The eye is 2 m above the right arm, where the terrain is z = 30 - x; the target is on the left arm's floor.
    let target = DVec3::new(5.0, 25.0, 0.0);
    let eye = DVec3::new(28.0, 25.0, 4.0);
    let flat = u_shape(0.0);
    let gt = GroundTruth::new(&flat);
    assert!(!gt.locator().footprint_is_convex());
    assert!(gt.point_visible(eye, target));
    let walled = u_shape(10.0);
    let gt = GroundTruth::new(&walled);
    assert!(!gt.point_visible(eye, target), "the wall across the gap blocks");
    assert_eq!(oracle(&walled, eye, target), Verdict::Hidden);
    // Over the wall.
    assert!(gt.point_visible(DVec3::new(25.0, 25.0, 30.0), target));
    // From the right arm's outer edge across the gap: the segment from (30, 25, 0) to (5, 25, 25) lies in the wall's
    // slope z = 30 - x over x in 20..30 (grazing all along: visible); slightly lower, it is under the slope.
    let graze = DVec3::new(30.0, 25.0, 0.0);
    assert!(gt.point_visible(DVec3::new(5.0, 25.0, 25.0), graze));
    assert!(!gt.point_visible(DVec3::new(5.0, 25.0, 24.99), graze));
    // Re-entering exactly through a boundary vertex: from the left arm through (20, 20) at the wall's height.
    let through_vertex_target = DVec3::new(10.0, 10.0, 0.0);
    assert!(!gt.point_visible(DVec3::new(30.0, 30.0, 19.0), through_vertex_target));
    assert!(gt.point_visible(DVec3::new(30.0, 30.0, 30.0), through_vertex_target));
}
