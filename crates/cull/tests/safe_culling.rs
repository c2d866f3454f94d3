//! The safe culler and the Lloyd & Egbert culler never cull a visible triangle: adversarial terrains and random TINs,
//! every cull checked against the exact segment-walk checker (`truth`), at several horizon resolutions, patch sizes
//! and occluder grids; and what a file stores of its nodes (circles, regions) changes nothing they draw.
//!
//! The checker's visible set is a lower bound of the true one (finite samples), so every triangle it calls visible
//! really is: a drawn set missing one of them is a false cull, always a bug.

use std::f64::consts::TAU;

mod common;

use common::{grid_tin, hierarchy_of, notch, random_tin, random_tin_at, splitmix};
use cull::{AnyCuller, Camera, Grouping, LloydEgbertCuller, SafeCuller, SafeParams};
use glam::DVec3;
use proptest::prelude::*;
use tin::{DedupePolicy, Tin, triangulate};
use truth::GroundTruth;

/// Occlusion captured over all eyes (culled hidden / hidden, 360° views, leaves of 8 triangles) by the safe culler
/// with its default parameters and by the Lloyd & Egbert culler on a grid of 8 × 8 cells and 256 columns.
#[derive(Clone, Copy, Debug)]
struct Captured {
    safe: f64,
    lloyd_egbert: f64,
}

/// Culls `tin` from every eye with several cullers and parameter sets and asserts that no triangle the exact checker
/// sees is culled.
fn assert_safe(name: &str, tin: &Tin, eyes: &[DVec3]) -> Captured {
    let truth = GroundTruth::new(tin);
    let mut captured = [(0usize, 0usize); 2];
    for (leaf, orphans) in [(8usize, 0usize), (40, 7)] {
        let (h, order) = hierarchy_of(tin, leaf, orphans);
        let mut cullers: Vec<(String, AnyCuller, Option<usize>)> = Vec::new();
        for params in [
            SafeParams::default(),
            SafeParams {
                columns_per_face: 8,
                patch: 1,
                occluder_budget: usize::MAX,
                work_budget: usize::MAX,
                coarse_columns: 0,
            },
            SafeParams {
                columns_per_face: 2048,
                patch: 4,
                occluder_budget: 50,
                work_budget: usize::MAX,
                coarse_columns: 0,
            },
            // Tiny work budgets: refining and writing stop almost at once (or midway), the rest is split and
            // tested against the horizon as it stands, with cell-edge occluders written, or drawn whole.
            SafeParams {
                work_budget: 1,
                ..SafeParams::default()
            },
            SafeParams {
                work_budget: 7,
                ..SafeParams::default()
            },
            SafeParams {
                work_budget: 120,
                ..SafeParams::default()
            },
            SafeParams {
                columns_per_face: 64,
                patch: 2,
                occluder_budget: usize::MAX,
                work_budget: 40,
                coarse_columns: 0,
            },
            // Coarse nodes: visible inner nodes drawn whole, their crests written as occluders (on these small
            // terrains only with many columns per node).
            SafeParams {
                coarse_columns: 64,
                ..SafeParams::default()
            },
            SafeParams {
                columns_per_face: 2048,
                patch: 2,
                occluder_budget: usize::MAX,
                work_budget: 300,
                coarse_columns: 300,
            },
        ] {
            let tally = (params == SafeParams::default() && leaf == 8).then_some(0);
            cullers.push((
                format!("{params:?}"),
                AnyCuller::Safe(SafeCuller::new(&h, params)),
                tally,
            ));
        }
        // Lloyd & Egbert over grids of 2 × 2 to 32 × 32 cells (the hierarchy's leaves are not these cells: its
        // verdicts must not depend on that), and over the crystal grid.
        for (depth, columns) in [(1u32, 8usize), (3, 256), (5, 2048)] {
            let mut q = h.clone();
            q.build.grouping = Grouping::Quadtree {
                built_depth: depth,
                stored_depth: depth,
            };
            let tally = (depth == 3 && leaf == 8).then_some(1);
            cullers.push((
                format!("lloyd-egbert, grid depth {depth}, {columns} columns"),
                AnyCuller::LloydEgbert(LloydEgbertCuller::new(&q, columns)),
                tally,
            ));
        }
        cullers.push((
            "lloyd-egbert, crystal grid".into(),
            AnyCuller::LloydEgbert(LloydEgbertCuller::new(&h, 64)),
            None,
        ));
        for (what, culler, tally) in &cullers {
            for &eye in eyes {
                let visible = truth.visible_triangles(eye);
                for camera in [
                    Camera::all_around(eye.to_array()),
                    Camera {
                        position: eye.to_array(),
                        yaw: 0.7,
                        hfov: 1.5,
                    },
                ] {
                    let list = culler.cull(&camera);
                    let mask = list.mask(order.len());
                    for (i, &t) in order.iter().enumerate() {
                        let t = t as usize;
                        if visible[t] && !mask[i] {
                            let in_view = camera.hfov >= TAU || {
                                let c = tin.corners(t);
                                c.iter().chain([&((c[0] + c[1] + c[2]) / 3.0)]).any(|p| {
                                    let d = *p - eye;
                                    let gap = (d.y.atan2(d.x) - camera.yaw + std::f64::consts::PI).rem_euclid(TAU)
                                        - std::f64::consts::PI;
                                    gap.abs() <= camera.hfov * 0.5
                                })
                            };
                            assert!(
                                !in_view,
                                "{name}: false cull of triangle {t} {:?} from eye {eye:?} (leaf {leaf}, {what}, \
                                 hfov {})",
                                tin.corners(t),
                                camera.hfov
                            );
                        }
                    }
                    if let (Some(k), true) = (tally, camera.hfov >= TAU) {
                        for (i, &t) in order.iter().enumerate() {
                            if !visible[t as usize] {
                                captured[*k].1 += 1;
                                captured[*k].0 += usize::from(!mask[i]);
                            }
                        }
                    }
                }
            }
        }
    }
    let ratio = |(c, h): (usize, usize)| c as f64 / h.max(1) as f64;
    Captured {
        safe: ratio(captured[0]),
        lloyd_egbert: ratio(captured[1]),
    }
}

/// Eyes around a terrain of side `size` (offset `o`): a ring at several heights, plus the given ones.
fn eyes_over(tin: &Tin, extra: &[DVec3]) -> Vec<DVec3> {
    let b = tin.bbox();
    let mut eyes = extra.to_vec();
    for (k, h) in [2.0, 10.0, 40.0].into_iter().enumerate() {
        for i in 0..6 {
            let a = TAU * (i as f64 + 0.37 * k as f64) / 6.0;
            let c = (b.min + b.max) * 0.5;
            let r = 0.35 * (b.max.x - b.min.x);
            let xy = glam::DVec2::new(c.x + r * a.cos(), c.y + r * a.sin());
            let z = truth::Locator::new(tin).ground_height(tin, xy).unwrap_or(0.0) + h;
            eyes.push(DVec3::new(xy.x, xy.y, z));
        }
    }
    eyes
}

#[test]
fn ridge_with_a_notch() {
    let tin = grid_tin(41, 200.0, DVec3::ZERO, notch);
    let eyes = eyes_over(
        &tin,
        &[
            DVec3::new(40.0, 100.0, 2.0),
            DVec3::new(40.0, 100.0, 5.0),
            DVec3::new(60.0, 97.0, 3.0),
            DVec3::new(10.0, 100.0, 5.0),
            DVec3::new(100.0, 100.0, 5.0 + 1e-9),
        ],
    );
    let captured = assert_safe("notch", &tin, &eyes).safe;
    assert!(
        captured > 0.3,
        "the ridge hides much of the far side: captured {captured}"
    );
}

#[test]
fn knife_edge_ridge() {
    let tin = grid_tin(
        41,
        200.0,
        DVec3::ZERO,
        |x, _| if (x - 100.0).abs() < 1.0 { 50.0 } else { 0.0 },
    );
    let eyes = eyes_over(&tin, &[DVec3::new(50.0, 80.0, 2.0), DVec3::new(100.0, 100.0, 50.0)]);
    let captured = assert_safe("knife edge", &tin, &eyes);
    assert!(captured.safe > 0.3, "captured {captured:?}");
    assert!(captured.lloyd_egbert > 0.3, "captured {captured:?}");
}

#[test]
fn plateau_edge() {
    let tin = grid_tin(31, 300.0, DVec3::ZERO, |x, _| if x < 150.0 { 20.0 } else { 0.0 });
    let eyes = eyes_over(
        &tin,
        &[
            DVec3::new(100.0, 150.0, 20.0),
            DVec3::new(140.0, 150.0, 20.0 + 1e-6),
            DVec3::new(200.0, 150.0, 2.0),
            DVec3::new(149.999, 150.0, 22.0),
        ],
    );
    assert_safe("plateau", &tin, &eyes);
}

/// Eyes whose sight lines graze a crest exactly, stand on it, or lie on the diagonals between the horizon's faces.
#[test]
fn grazing_eyes_and_eyes_on_crests_and_diagonals() {
    let tin = grid_tin(21, 200.0, DVec3::ZERO, |x, y| {
        10.0 * ((x / 40.0).sin() + (y / 55.0).cos())
    });
    let mut extra = Vec::new();
    for &v in &[60u32, 144, 200, 310] {
        let p = tin.position(v);
        extra.push(p); // on the vertex
        extra.push(p + DVec3::new(0.0, 0.0, 1e-9));
        extra.push(p + DVec3::new(0.0, 0.0, 2.0));
        extra.push(p + DVec3::new(10.0, 10.0, 2.0)); // vertices on exact diagonals (grid spacing 10)
        extra.push(p + DVec3::new(5.0, 0.0, 0.0)); // on an edge
    }
    // Grazing: the eye on the extension of the line through two crest points.
    let (a, b) = (tin.position(144), tin.position(165));
    extra.push(b + (b - a) * 3.0);
    extra.push(a + (a - b) * 2.0);
    let eyes = eyes_over(&tin, &extra);
    assert_safe("grazing", &tin, &eyes);
}

/// Regression: eyes a hair beside a vertex in x or y (1e-300 m, or one ulp), so that vertex lies almost exactly
/// beside the camera in a face's forward direction (`|u|` up to 1e302). Column indices of such spans once overflowed
/// (`horizon::floor`), which emptied the span checked in that face: a crash, or a patch called hidden there untested.
#[test]
fn eyes_a_hair_beside_a_vertex() {
    let tin = grid_tin(21, 200.0, DVec3::ZERO, |x, y| {
        10.0 * ((x / 40.0).sin() + (y / 55.0).cos())
    });
    let ulp = |x: f64| f64::from_bits(x.to_bits() + 1);
    let mut extra = Vec::new();
    for &(x, y) in &[
        (0.0, 35.0),
        (0.0, 100.0),
        (35.0, 0.0),
        (170.0, 0.0),
        (100.0, 100.0),
        (60.0, 140.0),
    ] {
        let z = 25.0;
        for eye in [
            DVec3::new(-1e-300, y, z),
            DVec3::new(1e-300, y, z),
            DVec3::new(x, -1e-300, z),
            DVec3::new(x, 1e-300, z),
            DVec3::new(ulp(x), y + 3.0, z),
            DVec3::new(x + 3.0, ulp(y), z),
            DVec3::new(-ulp(0.0), y + 3.0, 2.0),
        ] {
            extra.push(eye);
        }
    }
    let eyes = eyes_over(&tin, &extra);
    assert_safe("a hair beside a vertex", &tin, &eyes);
}

/// Regression (found by an audit of the proofs): an eye 8e-307 m west of x = 0 puts the vertex (0, 200) at
/// `f = 8e-307` in face +x, where its `u = 200 / f` overflowed to +∞ while its `v` stayed finite. The long edge to it
/// then had a NaN margin, `f64::max` dropped that edge from the bound of the triangle's top, and the triangle
/// (80, 30, 0), (40, 80, 0), (0, 200, 104), in plain view, was culled behind a low ridge. A face where a vertex's
/// `u` or `v` is not finite is now no face of that vertex, and an edge whose slope or margin is not finite makes its
/// triangle unusable (neither occluder nor hidden).
#[test]
fn an_eye_a_subnormal_beside_a_face_boundary() {
    let mut pts = vec![
        DVec3::new(80.0, 30.0, 0.0),
        DVec3::new(40.0, 80.0, 0.0),
        DVec3::new(0.0, 200.0, 104.0),
    ];
    // A low ridge at x = 10 (0.15 m below the eye) and a high wall along y = 14.
    pts.extend((0..11).map(|i| DVec3::new(10.0, 2.5 + 0.85 * i as f64, 1.85)));
    pts.extend([16.7, 15.0, 13.0, 11.0, 9.0, 7.0, 5.0, 3.0, 1.0, -1.4].map(|x| DVec3::new(x, 14.0, 16.0)));
    for (x, y) in [
        (-8.0, -8.0),
        (8.0, -8.0),
        (-8.0, 5.0),
        (4.0, 0.5),
        (-4.0, -1.0),
        (8.5, 1.5),
        (8.5, 5.0),
        (8.5, 9.0),
        (16.0, 0.0),
        (16.0, 12.5),
        (18.5, 14.0),
        (18.0, 16.0),
        (12.0, 12.5),
        (8.0, 12.5),
        (11.5, 8.0),
        (-6.0, 14.0),
        (5.0, 17.0),
        (-40.0, -40.0),
        (300.0, -90.0),
        (320.0, 520.0),
        (-40.0, 500.0),
        (40.0, 40.0),
        (40.0, 15.0),
        (25.0, 10.0),
        (25.0, 25.0),
    ] {
        pts.push(DVec3::new(x, y, 0.0));
    }
    let (tin, _) = triangulate(&pts, DedupePolicy::Reject).expect("a TIN");
    let eyes = [
        DVec3::new(-8e-307, 0.0, 2.0),
        DVec3::new(-1e-300, 0.0, 2.0),
        DVec3::new(0.0, 0.0, 2.0),
        DVec3::new(-f64::from_bits(1), 0.0, 2.0),
        DVec3::new(0.0, -8e-307, 2.0),
    ];
    // One triangle per leaf, as the audit's hierarchy had it, and the usual leaves.
    let truth = GroundTruth::new(&tin);
    let (h, order) = hierarchy_of(&tin, 1, 0);
    for culler in [
        AnyCuller::Safe(SafeCuller::new(&h, SafeParams::default())),
        AnyCuller::LloydEgbert(LloydEgbertCuller::new(&h, 256)),
    ] {
        for &eye in &eyes {
            let visible = truth.visible_triangles(eye);
            let mask = culler.cull(&Camera::all_around(eye.to_array())).mask(order.len());
            for (i, &t) in order.iter().enumerate() {
                assert!(
                    !visible[t as usize] || mask[i],
                    "false cull of triangle {t} {:?} from {eye:?}",
                    tin.corners(t as usize)
                );
            }
        }
    }
    assert_safe("a subnormal beside a face boundary", &tin, &eyes_over(&tin, &eyes));
}

#[test]
fn slivers() {
    // Rows 20 m apart, each doubled 5 cm away with the points staggered: the triangles between a row and its double
    // are slivers 10 m long and 5 cm wide.
    let mut pts = Vec::new();
    for j in 0..10 {
        for i in 0..30 {
            let z = 15.0 * ((i * 7 + j * 3) % 5) as f64;
            pts.push(DVec3::new(i as f64 * 10.0, j as f64 * 20.0, z));
            pts.push(DVec3::new(i as f64 * 10.0 + 5.0, j as f64 * 20.0 + 0.05, z + 7.0));
        }
    }
    let tin = triangulate(&pts, DedupePolicy::Reject).expect("valid").0;
    let eyes = eyes_over(&tin, &[DVec3::new(5.0, 1.0, 3.0), DVec3::new(150.0, 100.0, 80.0)]);
    assert_safe("slivers", &tin, &eyes);
}

/// Single-vertex spikes (needles, up to 15 times the grid spacing) on a gentle plain, and a row of them forming a
/// wall with a one-vertex notch, at UTM-sized coordinates 3 km up: the thinnest occluders a TIN has (every edge of a
/// needle is steep, its triangles are seen edge-on from most eyes). Eyes on the needles' tips, a hair above them,
/// beside them, and level with the notch.
#[test]
fn needles_and_a_notched_needle_wall() {
    let offset = DVec3::new(5e5, 4.8e6, 3000.0);
    let needle = |x: f64, y: f64| {
        let (i, j) = ((x / 10.0).round() as i64, (y / 10.0).round() as i64);
        let spike = if (i * 7 + j * 13) % 23 == 0 {
            40.0 + 5.0 * ((i + j) % 23) as f64
        } else {
            0.0
        };
        let wall = if j == 17 && (3..28).contains(&i) && i != 15 {
            120.0
        } else {
            0.0
        };
        2.0 * (x / 45.0).sin() * (y / 60.0).cos() + spike + wall
    };
    let tin = grid_tin(31, 300.0, offset, needle);
    let mut extra = Vec::new();
    for (i, j) in [(0i64, 0i64), (5, 4), (10, 8), (14, 17), (20, 10)] {
        let (x, y) = (10.0 * i as f64, 10.0 * j as f64);
        let tip = DVec3::new(x, y, needle(x, y)) + offset;
        extra.extend([
            tip,
            tip + DVec3::new(0.0, 0.0, 1e-9),
            tip + DVec3::new(0.0, 0.0, 2.0),
            tip + DVec3::new(3.0, 0.0, -20.0),
        ]);
    }
    // Level with the wall's notch (vertex 15 of row 17) and looking through it, from both sides.
    for (y, z) in [(100.0, 1.0), (60.0, 3.0), (260.0, 2.0)] {
        extra.push(DVec3::new(150.0, y, needle(150.0, y) + z) + offset);
    }
    let captured = assert_safe("needles", &tin, &eyes_over(&tin, &extra));
    assert!(
        captured.safe > 0.4,
        "the needle wall hides what lies behind it: {captured:?}"
    );
}

/// The notch terrain at UTM-sized coordinates: the same proofs hold with large offsets.
#[test]
fn utm_offsets() {
    for offset in [DVec3::new(5e5, 5e6, 0.0), DVec3::new(5e6, 5e6, 1000.0)] {
        let tin = grid_tin(31, 200.0, offset, notch);
        let eyes: Vec<DVec3> = [DVec3::new(40.0, 100.0, 2.0), DVec3::new(60.0, 97.0, 3.0)]
            .iter()
            .map(|&e| e + offset)
            .collect();
        let eyes = eyes_over(&tin, &eyes);
        assert_safe("utm", &tin, &eyes);
    }
}

/// A 400 m square of 10 m cells, bumps of ±2 m, and a wall 60 m high and 30 m thick across it at x = 200 m.
fn wall() -> Tin {
    grid_tin(41, 400.0, DVec3::ZERO, |x, y| {
        if (x - 200.0).abs() < 15.0 {
            60.0
        } else {
            2.0 * ((x + y) / 37.0).sin()
        }
    })
}

/// A tall wall hides the far side almost entirely from a ground-level eye: the culler must capture most of it.
#[test]
fn a_wall_hides_the_far_side() {
    let tin = wall();
    let eye = DVec3::new(100.0, 200.0, 4.0);
    let captured = assert_safe("wall", &tin, &[eye]).safe;
    assert!(captured > 0.6, "captured {captured}");
    // Lloyd & Egbert's cell edges along the wall's crest hide it too, from an eye whose sight lines to the grid
    // corners do not fall exactly on horizon column boundaries (covers ending exactly on one are dropped).
    let captured = assert_safe("wall", &tin, &[DVec3::new(100.37, 203.1, 4.0)]).lloyd_egbert;
    assert!(captured > 0.6, "captured {captured}");
}

/// A fan: every triangle shares one vertex placed near the rim of a convex polygon (a mesh's own faces, the least
/// Delaunay triangulation there is: slivers up to 2 km long, every node's circle reaching the hub), over a ring of
/// hills. Eyes on the hub, a hair above it, on the rim, between the hills and above them. Little of a fan can be
/// hidden (every triangle reaches the hub); what is attacked here is the bounds of long thin nodes seen from within
/// their circles.
#[test]
fn a_fan_of_slivers_around_one_vertex() {
    let n = 90u32;
    let mut pts = vec![DVec3::new(-950.0, 20.0, 5.0)];
    for i in 0..n {
        let a = TAU * f64::from(i) / f64::from(n);
        let z = 40.0 * (7.0 * a).sin().max(0.0) + if i % 11 == 0 { 90.0 } else { 0.0 };
        pts.push(DVec3::new(1000.0 * a.cos(), 1000.0 * a.sin(), z));
    }
    let tris: Vec<[u32; 3]> = (0..n).map(|i| [0, 1 + i, 1 + (i + 1) % n]).collect();
    let tin = Tin::from_parts(pts.clone(), tris).expect("a fan over a convex polygon");
    assert!(tin.validate().is_height_field());
    let loc = truth::Locator::new(&tin);
    let above = |x: f64, y: f64, h: f64| {
        let ground = loc.ground_height(&tin, glam::DVec2::new(x, y)).expect("inside the fan");
        DVec3::new(x, y, ground + h)
    };
    let hub = pts[0];
    let eyes = [
        hub,
        hub + DVec3::new(0.0, 0.0, 1e-9),
        above(-947.0, 20.0, 2.0),
        above(999.0, 0.0, 0.5),
        pts[23],
        above(400.0, -300.0, 2.0),
        above(0.0, 0.0, 150.0),
        DVec3::new(1500.0, 0.0, 20.0),
    ];
    assert_safe("fan", &tin, &eyes);
}

/// Footprints that are not one convex piece (a mesh's own faces): a grid with a hole in the middle and cut into two
/// islands by a gap, ridges running across both. Sight lines over the hole and the gap meet no terrain there (the
/// exact checker sees through them), so nothing beyond may be hidden by what is not there. Eyes on the hole's rim,
/// above the hole (no ground below), on both shores of the gap, level with the ridges, and outside.
#[test]
fn a_footprint_with_a_hole_and_two_islands() {
    let (n, d) = (26usize, 40.0);
    let height = |i: usize, j: usize| {
        let (x, y) = (i as f64 * d, j as f64 * d);
        30.0 * (x / 150.0).sin() * (y / 120.0).cos() + if i % 7 == 3 { 60.0 } else { 0.0 }
    };
    let kept = |i: usize, j: usize| {
        let hole = (10..15).contains(&i) && (9..15).contains(&j);
        let gap = i == 19;
        !hole && !gap
    };
    let pts: Vec<DVec3> = (0..n * n)
        .map(|k| DVec3::new((k % n) as f64 * d, (k / n) as f64 * d, height(k % n, k / n)))
        .collect();
    let mut tris = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            if kept(i, j) {
                let a = (j * n + i) as u32;
                let (b, c, e) = (a + 1, a + n as u32, a + n as u32 + 1);
                tris.extend([[a, b, e], [a, e, c]]);
            }
        }
    }
    // Drop the vertices no triangle uses (those inside the hole).
    let mut new_index = vec![u32::MAX; pts.len()];
    let mut used = Vec::new();
    for t in &mut tris {
        for v in t.iter_mut() {
            if new_index[*v as usize] == u32::MAX {
                new_index[*v as usize] = used.len() as u32;
                used.push(pts[*v as usize]);
            }
            *v = new_index[*v as usize];
        }
    }
    let tin = Tin::from_parts(used, tris).expect("a grid with a hole and a gap");
    assert!(tin.validate().is_height_field());
    let at = |i: usize, j: usize, above: f64| DVec3::new(i as f64 * d, j as f64 * d, height(i, j) + above);
    let eyes = [
        at(10, 12, 0.0),
        at(10, 12, 1e-9),
        at(15, 9, 2.0),
        DVec3::new(12.5 * d, 12.0 * d, 5.0),
        DVec3::new(12.5 * d, 12.0 * d, -40.0),
        at(19, 5, 2.0),
        at(20, 5, 0.5),
        at(17, 20, 60.0),
        at(3, 3, 2.0),
        DVec3::new(-200.0, 500.0, 90.0),
    ];
    assert_safe("hole and islands", &tin, &eyes);
}

/// The work budget bounds a cull whatever the view: at most `B` work units (nodes tested while refining, occluder
/// edges and chains written: no slack, each unit is checked before it is spent), at most `⌈B / 8⌉` cell-edge occluders
/// written after it is spent (`occluder_edges` counts both), and at most `3 B + 2 ⌈B / 8⌉ + r` nodes tested in all
/// (`r` roots; every node has at most two children: `B` refining tests push at most `2 B` nodes, the splits after the
/// budget, at most `⌈B / 8⌉`, push `2 ⌈B / 8⌉` more). Culls are deterministic, culls nothing the exact checker sees,
/// and a budget never reached changes nothing.
#[test]
fn the_work_budget_bounds_every_cull() {
    let tin = grid_tin(61, 600.0, DVec3::ZERO, |x, y| {
        25.0 * ((x / 50.0).sin() * (y / 70.0).cos()) + 0.05 * x
    });
    let (h, order) = hierarchy_of(&tin, 8, 5);
    let truth = GroundTruth::new(&tin);
    let unlimited = SafeCuller::new(&h, SafeParams::default());
    let eyes = eyes_over(&tin, &[DVec3::new(300.0, 300.0, 400.0), DVec3::new(10.0, 10.0, 3.0)]);
    for &eye in &eyes {
        let camera = Camera::all_around(eye.to_array());
        let full = unlimited.cull(&camera);
        let visible = truth.visible_triangles(eye);
        for budget in [1usize, 3, 10, 50, 200, 1000, 100_000] {
            let culler = SafeCuller::new(
                &h,
                SafeParams {
                    work_budget: budget,
                    ..SafeParams::default()
                },
            );
            let list = culler.cull(&camera);
            let s = list.stats;
            assert!(
                s.work as usize <= budget,
                "eye {eye}: work {} over budget {budget}",
                s.work
            );
            assert!(
                s.occluder_edges as usize <= budget + budget.div_ceil(8),
                "eye {eye}, budget {budget}: {} occluder edges",
                s.occluder_edges
            );
            assert!(
                s.nodes_tested as usize <= 3 * budget + 2 * budget.div_ceil(8) + culler.roots(),
                "eye {eye}, budget {budget}: {} nodes tested",
                s.nodes_tested
            );
            assert_eq!(list, culler.cull(&camera), "deterministic");
            let mask = list.mask(order.len());
            assert!(
                order.iter().enumerate().all(|(i, &t)| mask[i] || !visible[t as usize]),
                "eye {eye}, budget {budget}: a visible triangle culled"
            );
            if (full.stats.work as usize) < budget {
                assert_eq!(
                    list.ranges, full.ranges,
                    "eye {eye}: a budget never reached changes nothing"
                );
            }
        }
    }
}

/// Once the work budget is spent, the nodes left to be drawn whole are tested once more, nearest first, against the
/// horizon and the cell-edge occluders around the nodes drawn before them: a wall beyond the refined terrain still
/// hides much of the far side. Two eyes 2–3 m above bumpy ground, 110 and 180 m before a 60 m wall, a budget of 600
/// units (about a third of what the unlimited culls spend): 1,220 of the 2,880 triangles hidden behind the wall are
/// culled (without the cell edges, with the horizon of what was refined alone, 50), and nothing visible.
#[test]
fn a_spent_budget_still_culls_behind_a_wall() {
    let tin = wall();
    let (h, order) = hierarchy_of(&tin, 40, 0);
    let truth = GroundTruth::new(&tin);
    let culler = SafeCuller::new(
        &h,
        SafeParams {
            work_budget: 600,
            ..SafeParams::default()
        },
    );
    let (mut hidden, mut culled) = (0usize, 0usize);
    for eye in [DVec3::new(90.37, 143.1, 3.0), DVec3::new(20.0, 300.0, 2.0)] {
        let list = culler.cull(&Camera::all_around(eye.to_array()));
        assert_eq!(list.stats.work, 600, "eye {eye}: the budget is spent");
        let visible = truth.visible_triangles(eye);
        let mask = list.mask(order.len());
        for (i, &t) in order.iter().enumerate() {
            assert!(
                mask[i] || !visible[t as usize],
                "eye {eye}: visible triangle {t} culled"
            );
            if !visible[t as usize] && tin.corners(t as usize).iter().all(|p| p.x > 215.0) {
                hidden += 1;
                culled += usize::from(!mask[i]);
            }
        }
    }
    assert!(
        culled * 3 > hidden,
        "behind the wall: {culled} of {hidden} hidden triangles culled"
    );
}

/// Coarse nodes take effect on a terrain of this size: some visible inner nodes are drawn whole (more is drawn than
/// when refining), culling goes on behind them, and nothing visible is culled.
#[test]
fn coarse_nodes_are_drawn_whole_safely() {
    let tin = grid_tin(41, 400.0, DVec3::ZERO, |x, _| {
        if (x - 200.0).abs() < 15.0 {
            60.0
        } else {
            2.0 * (x / 37.0).sin()
        }
    });
    let (h, order) = hierarchy_of(&tin, 8, 0);
    let truth = GroundTruth::new(&tin);
    let fine = SafeCuller::new(&h, SafeParams::default());
    let coarse = SafeCuller::new(
        &h,
        SafeParams {
            coarse_columns: 64,
            ..SafeParams::default()
        },
    );
    let (mut more, mut culled) = (0, 0);
    for eye in [
        DVec3::new(100.0, 200.0, 4.0),
        DVec3::new(20.0, 30.0, 10.0),
        DVec3::new(150.0, 380.0, 3.0),
    ] {
        let camera = Camera::all_around(eye.to_array());
        let (a, b) = (fine.cull(&camera), coarse.cull(&camera));
        more += usize::from(b.stats.triangles_drawn > a.stats.triangles_drawn);
        culled += usize::from(b.stats.triangles_culled > 0);
        let visible = truth.visible_triangles(eye);
        let mask = b.mask(order.len());
        assert!(order.iter().enumerate().all(|(i, &t)| mask[i] || !visible[t as usize]));
    }
    assert!(more > 0, "no node was drawn whole");
    assert!(culled > 0, "nothing culled");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// `SafeParams::check` accepts exactly the parameters the safe culler uses as they are given: what it accepts,
    /// `SafeCuller::new` keeps; what it refuses, the culler rounds or clamps to something else (so a front end that
    /// checks never has a value changed behind its back, and refuses none the culler would take).
    #[test]
    fn checked_parameters_are_the_ones_the_culler_uses(
        columns in prop_oneof![0usize..70_000, (0u32..20).prop_map(|k| 1usize << k)],
        patch in 0usize..80,
        budgets in (any::<usize>(), any::<usize>()),
        coarse in any::<usize>(),
    ) {
        let tin = grid_tin(4, 100.0, DVec3::ZERO, |x, y| 0.01 * x * y);
        let (h, _) = hierarchy_of(&tin, 4, 0);
        let given = SafeParams {
            columns_per_face: columns,
            patch,
            occluder_budget: budgets.0,
            work_budget: budgets.1,
            coarse_columns: coarse,
        };
        let used = SafeCuller::new(&h, given).params();
        prop_assert_eq!(given.check().is_ok(), used == given, "given {:?}, used {:?}", given, used);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Random TINs (random points, rough random heights) and random eyes inside and outside the footprint.
    #[test]
    fn random_tins_have_no_false_culls(seed in any::<u64>(), n in 20usize..160, rough in 0.0f64..3.0) {
        let mut next = splitmix(seed);
        let Some(tin) = random_tin(&mut next, n, rough) else { return Ok(()) };
        let loc = truth::Locator::new(&tin);
        let mut eyes = Vec::new();
        for k in 0..6 {
            let xy = glam::DVec2::new(next() * 600.0 - 50.0, next() * 600.0 - 50.0);
            let ground = loc.ground_height(&tin, xy).unwrap_or(0.0);
            eyes.push(DVec3::new(xy.x, xy.y, ground + [0.0, 0.5, 2.0, 10.0, 60.0, -3.0][k]));
        }
        assert_safe("random", &tin, &eyes);
    }

    /// The same random TINs at UTM-sized coordinates (up to 900 km east, 10,000 km north) and altitudes from below sea
    /// level to 8,000 m, where a coordinate's rounding is a nanometre and the margins must still cover it; eyes as in
    /// `random_tins_have_no_false_culls`, relative to the moved terrain.
    #[test]
    fn random_tins_far_from_the_origin_have_no_false_culls(
        seed in any::<u64>(),
        n in 20usize..120,
        rough in 0.0f64..3.0,
        east in 1.0e5f64..9.0e5,
        north in 1.0e6f64..1.0e7,
        up in prop_oneof![Just(-430.0f64), Just(2_500.0), Just(8_000.0)],
    ) {
        let mut next = splitmix(seed);
        let offset = DVec3::new(east, north, up);
        let Some(tin) = random_tin_at(&mut next, n, rough, offset) else { return Ok(()) };
        let loc = truth::Locator::new(&tin);
        let mut eyes = Vec::new();
        for k in 0..6 {
            let xy = glam::DVec2::new(east + next() * 600.0 - 50.0, north + next() * 600.0 - 50.0);
            let ground = loc.ground_height(&tin, xy).unwrap_or(up);
            eyes.push(DVec3::new(xy.x, xy.y, ground + [0.0, 0.5, 2.0, 10.0, 60.0, -3.0][k]));
        }
        assert_safe("random, far from the origin", &tin, &eyes);
    }

    /// Eyes far beyond the footprint (a camera flying towards a tile, or culling a neighbouring one): from 1.5 to
    /// 2,000 times the 500 m footprint away, at heights from below the lowest vertex to far above the highest, and
    /// level with the highest vertex, where every sight line grazes the crests.
    #[test]
    fn eyes_far_outside_the_footprint_have_no_false_culls(
        seed in any::<u64>(),
        n in 20usize..120,
        rough in 0.0f64..3.0,
    ) {
        let mut next = splitmix(seed);
        let Some(tin) = random_tin(&mut next, n, rough) else { return Ok(()) };
        let b = tin.bbox();
        let c = (b.min + b.max) * 0.5;
        let mut eyes = Vec::new();
        for (k, dist) in [750.0, 1_500.0, 5_000.0, 50_000.0, 1.0e6].into_iter().enumerate() {
            let a = TAU * next();
            let z = [b.max.z, b.min.z - 5.0, b.max.z + 1.0, b.max.z + 0.25 * dist, (b.min.z + b.max.z) * 0.5][k];
            eyes.push(DVec3::new(c.x + dist * a.cos(), c.y + dist * a.sin(), z));
        }
        assert_safe("far eyes", &tin, &eyes);
    }

    /// Degenerate terrains: an exact grid (every cell's four corners co-circular, so the Delaunay diagonals are
    /// ties) with heights on a few terraces (plateaus, and one-cell steps between them), some samples missing; eyes
    /// on vertices at their exact height (on a plateau, so sight lines graze it), just above, and off the terrain.
    #[test]
    fn terraced_grids_have_no_false_culls(
        seed in any::<u64>(),
        side in 5usize..13,
        levels in 1u32..5,
        holes in 0.0f64..0.3,
    ) {
        let mut next = splitmix(seed);
        let step = 25.0;
        // Contiguous terraces: a smooth random field cut into `levels + 1` flat steps 10 m apart.
        let (a, b, phase) = (40.0 + 80.0 * next(), 40.0 + 80.0 * next(), TAU * next());
        let mut pts = Vec::new();
        for i in 0..side {
            for j in 0..side {
                let corner = (i == 0 || i == side - 1) && (j == 0 || j == side - 1);
                if !corner && next() < holes {
                    continue;
                }
                let (x, y) = (i as f64 * step, j as f64 * step);
                let field = 0.5 + 0.5 * (x / a + phase).sin() * (y / b - phase).cos();
                let z = 10.0 * (field * f64::from(levels) + 0.5).floor();
                pts.push(DVec3::new(x, y, z));
            }
        }
        let Ok((tin, _)) = triangulate(&pts, DedupePolicy::Reject) else { return Ok(()) };
        let loc = truth::Locator::new(&tin);
        let mut eyes = Vec::new();
        for k in 0..6 {
            let p = pts[(next() * pts.len() as f64) as usize % pts.len()];
            let above = [0.0, 1e-9, 0.5, 10.0, 30.0, 2.0][k];
            eyes.push(DVec3::new(p.x, p.y, p.z + above));
        }
        let xy = glam::DVec2::new(next() * side as f64 * step, next() * side as f64 * step);
        eyes.push(DVec3::new(xy.x, xy.y, loc.ground_height(&tin, xy).unwrap_or(0.0) + 1.0));
        eyes.push(DVec3::new(-40.0, xy.y, 10.0 * f64::from(levels)));
        assert_safe("terraced grid", &tin, &eyes);
    }

    /// Triangulations that are not Delaunay (a mesh's own faces, as `--keep-faces` reads them): a grid stretched up
    /// to 100 times along one axis (triangles up to 100 times longer than wide), inner vertices jittered by a tenth
    /// of a cell, each cell cut along a random diagonal; rolling heights, noise and random spikes. Eyes on vertices (at
    /// their height and a hair above), on edge midpoints (on the terrain), above random points and off the terrain.
    #[test]
    fn non_delaunay_grids_have_no_false_culls(
        seed in any::<u64>(),
        nx in 3usize..16,
        ny in 3usize..16,
        stretch in -2.0f64..2.0,
        rough in 0.0f64..3.0,
    ) {
        let mut next = splitmix(seed);
        let (dx, dy) = (40.0 * 10f64.powf(stretch / 2.0), 40.0 / 10f64.powf(stretch / 2.0));
        let (w, h) = (dx * (nx - 1) as f64, dy * (ny - 1) as f64);
        let mut pts = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let inner = |k: usize, n: usize| if k == 0 || k == n - 1 { 0.0 } else { 1.0 };
                let x = dx * (i as f64 + inner(i, nx) * 0.2 * (next() - 0.5));
                let y = dy * (j as f64 + inner(j, ny) * 0.2 * (next() - 0.5));
                let spike = if next() < 0.1 { 60.0 } else { 0.0 };
                let z = 40.0 * (9.0 * x / w).sin() * (6.0 * y / h).cos() + rough * 15.0 * next() + spike;
                pts.push(DVec3::new(x, y, z));
            }
        }
        let mut tris = Vec::new();
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let a = (j * nx + i) as u32;
                let (b, c, d) = (a + 1, a + nx as u32, a + nx as u32 + 1);
                if next() < 0.5 {
                    tris.extend([[a, b, d], [a, d, c]]);
                } else {
                    tris.extend([[a, b, c], [b, d, c]]);
                }
            }
        }
        let tin = Tin::from_parts(pts.clone(), tris.clone()).expect("a grid jittered by a tenth of a cell");
        prop_assert!(tin.validate().is_height_field());
        let loc = truth::Locator::new(&tin);
        let mut eyes = Vec::new();
        for above in [0.0, 1e-9, 0.5] {
            eyes.push(pts[(next() * pts.len() as f64) as usize % pts.len()] + DVec3::new(0.0, 0.0, above));
        }
        for above in [1e-9, 2.0] {
            let t = tris[(next() * tris.len() as f64) as usize % tris.len()];
            let (p, q) = (pts[t[0] as usize], pts[t[1] as usize]);
            eyes.push((p + q) * 0.5 + DVec3::new(0.0, 0.0, above));
        }
        let xy = glam::DVec2::new(next() * w, next() * h);
        eyes.push(DVec3::new(xy.x, xy.y, loc.ground_height(&tin, xy).unwrap_or(0.0) + 10.0));
        eyes.push(DVec3::new(-0.3 * w, 0.5 * h, 30.0));
        assert_safe("non-Delaunay grid", &tin, &eyes);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// The run-time cullers whose verdicts are theorems read only the mesh and the tree's structure from a file: any
    /// stored circle (moved, shrunk to nothing, grown to 1e30 m) and any stored region (dropped, or one in every
    /// sector holding every camera) changes nothing they draw, from any eye: a file cannot make them cull wrongly by
    /// what it says of its nodes.
    #[test]
    fn stored_circles_and_regions_change_nothing_the_run_time_cullers_draw(
        seed in any::<u64>(),
        n in 20usize..120,
        circles in prop::collection::vec(
            (-1e30f32..1e30, -1e30f32..1e30, prop_oneof![Just(0.0f32), 0.0f32..1e30]),
            1..64,
        ),
        claim_everything in any::<bool>(),
    ) {
        let mut next = splitmix(seed);
        let Some(tin) = random_tin(&mut next, n, 1.0) else { return Ok(()) };
        let (h, _) = hierarchy_of(&tin, 8, 3);
        let mut damaged = h.clone();
        for (i, node) in damaged.nodes.iter_mut().enumerate() {
            let (x, y, r) = circles[i % circles.len()];
            node.centre = [x, y];
            node.radius = r;
            node.regions = if claim_everything {
                // A region in every sector that holds every camera below 1e30 m: "always hidden".
                (0..h.sectors as u16)
                    .map(|sector| cull::StoredRegion {
                        sector,
                        points: vec![[-1e30, 1e30]],
                        tail_slope: 0.0,
                    })
                    .collect()
            } else {
                Vec::new()
            };
        }
        prop_assert!(damaged.check_invariants().is_ok());
        let params = [
            SafeParams::default(),
            SafeParams { coarse_columns: 64, work_budget: 40, ..SafeParams::default() },
        ];
        for p in params {
            let (a, b) = (SafeCuller::new(&h, p), SafeCuller::new(&damaged, p));
            let (c, d) = (
                LloydEgbertCuller::new(&h, p.columns_per_face),
                LloydEgbertCuller::new(&damaged, p.columns_per_face),
            );
            for _ in 0..4 {
                let eye = [next() * 700.0 - 100.0, next() * 700.0 - 100.0, next() * 80.0 - 20.0];
                for camera in [Camera::all_around(eye), Camera { position: eye, yaw: 6.0 * next(), hfov: 1.2 }] {
                    prop_assert_eq!(a.cull(&camera), b.cull(&camera));
                    prop_assert_eq!(c.cull(&camera), d.cull(&camera));
                }
            }
        }
    }
}

/// Regression (found by an audit of the proofs): once the work budget is spent, the safe culler writes the cell-edge
/// segments of `lloyd_egbert`, whose ends carry the ids of grid points, into a horizon holding the partial covers of
/// its patches' edges, whose ends carry mesh vertex ids. Both were `u32` numbers, so grid corner (20, 0) of this
/// 4 × 4 grid (id 12) was taken for mesh vertex 12, at another `u`: a left-anchored cover ending at the corner and a
/// right-anchored one starting at the vertex were paired as if they met, and the column was raised over a gap that
/// no occluder covers. Triangle X, seen through that gap, was culled at every budget from 7 on. The ids now live in
/// disjoint ranges (`horizon::PointId`).
#[test]
fn a_grid_corner_numbered_like_a_mesh_vertex_is_not_that_vertex() {
    use cull::{BuildInfo, Hierarchy, Mesh, Node};
    let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let positions = vec![
        p(10.0, -10.0, -20.0), // 0..2: F1, the grid's lower-left corner
        p(10.3, -9.9, -20.0),
        p(10.2, -9.6, -20.0),
        p(10.0, -0.2, 0.0), // 3: R, with P and Q the occluder A
        p(19.5, 0.0, 10.0), // 4: W's fourth corner
        p(14.0, 1.9, 7.0),  // 5: Q
        p(16.8, 2.3, 0.0),  // 6..8: T, which makes the culler write A's edges
        p(17.2, 2.3, 0.0),
        p(17.0, 2.7, 0.0),
        p(19.5, -4.0, 10.0), // 9..11 and 4: W, a slab across grid line x = 20 up to the corner (20, 0)
        p(20.5, -4.0, 10.0),
        p(20.5, 0.0, 10.0),
        p(14.0, 0.08, 7.0), // 12: P, numbered like grid corner (2, 2) = (20, 0)
        p(27.5, 1.8, -5.0), // 13..15: X, seen through the gap between the corner's u and P's
        p(28.5, 1.8, -5.0),
        p(28.0, 2.6, -5.0),
        p(30.0, 10.0, -20.0), // 16..18: F2, the grid's upper-right corner
        p(29.7, 9.9, -20.0),
        p(29.8, 9.6, -20.0),
    ];
    let triangles = vec![
        [0, 1, 2],
        [3, 12, 5],
        [6, 7, 8],
        [9, 10, 11],
        [9, 11, 4],
        [13, 14, 15],
        [16, 17, 18],
    ];
    let tin = Tin::from_parts(positions, triangles).expect("a TIN");
    // Each group its own root leaf; the last triangle is the always-visible set.
    let nodes: Vec<Node> = [[0u32, 1], [1, 2], [2, 3], [3, 5], [5, 6], [6, 7]]
        .iter()
        .map(|&triangles| Node {
            centre: [0.0; 2],
            radius: 0.0,
            children: vec![],
            triangles,
            level: 0,
            regions: vec![],
        })
        .collect();
    let h = Hierarchy {
        sectors: 16,
        origin: [0.0; 3],
        roots: (0..nodes.len() as u32).collect(),
        nodes,
        always_visible: [7, 7],
        mesh: Mesh {
            positions: tin.positions().iter().map(|p| p.to_array()).collect(),
            triangles: tin.triangles().to_vec(),
        },
        build: BuildInfo::default(),
    };
    h.check_invariants().expect("valid");
    let eye = DVec3::new(0.0, -3.0, 0.0);
    let visible = GroundTruth::new(&tin).visible_triangles(eye);
    assert!(visible[5], "X is visible to the exact checker");
    let mut false_culls = Vec::new();
    for budget in 1..=20 {
        let params = SafeParams {
            columns_per_face: 8,
            patch: 2,
            occluder_budget: usize::MAX,
            work_budget: budget,
            coarse_columns: 0,
        };
        let mask = SafeCuller::new(&h, params)
            .cull(&Camera::all_around(eye.to_array()))
            .mask(7);
        false_culls.extend((0..7).filter(|&t| visible[t] && !mask[t]).map(|t| (budget, t)));
    }
    assert!(
        false_culls.is_empty(),
        "false culls (budget, triangle): {false_culls:?}"
    );
}
