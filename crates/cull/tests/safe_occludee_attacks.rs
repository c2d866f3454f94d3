//! Attacks on the safe culler's occludee side and traversal (`crates/cull/src/safe.rs`): adversarial terrains, trees
//! in any triangle order, extreme parameters and eyes on the culler's own circles, every cull checked against the
//! exact checker (`truth`).

use std::f64::consts::TAU;

mod common;

use common::{grid_tin, notch, random_tin_at, spatial_order, splitmix};
use cull::{BuildInfo, Camera, Hierarchy, Mesh, Node, SafeCuller, SafeParams};
use glam::DVec3;
use tin::Tin;
use truth::GroundTruth;

/// A hierarchy over `tin` whose triangle order is `order` (any order: not necessarily spatial), cut into leaves of
/// `leaf` triangles, merged pairwise in the given pattern into a random binary forest (`merge_seed`), with the last
/// `orphans` triangles always visible. Stored circles are left at zero (the safe culler reads none).
fn hierarchy_with_order(tin: &Tin, order: &[u32], leaf: usize, orphans: usize, merge_seed: u64) -> Hierarchy {
    let nt = order.len();
    let orphans = orphans.min(nt);
    let grouped = (nt - orphans) as u32;
    let mut nodes: Vec<Node> = Vec::new();
    // Current top-level nodes, in triangle order.
    let mut tops: Vec<u32> = Vec::new();
    let mut s = 0u32;
    while s < grouped {
        let e = (s + leaf as u32).min(grouped);
        tops.push(nodes.len() as u32);
        nodes.push(Node {
            centre: [0.0; 2],
            radius: 0.0,
            children: vec![],
            triangles: [s, e],
            level: 0,
            regions: vec![],
        });
        s = e;
    }
    let mut next = splitmix(merge_seed);
    // Random merges of adjacent tops, sometimes of three, sometimes a node with one child.
    let rounds = (next() * 6.0) as usize + 1;
    for _ in 0..rounds {
        if tops.len() < 2 {
            break;
        }
        let mut new_tops = Vec::new();
        let mut i = 0;
        while i < tops.len() {
            let take = if next() < 0.15 {
                1
            } else if next() < 0.2 {
                3
            } else {
                2
            };
            let take = take.min(tops.len() - i);
            if take == 1 && next() < 0.5 {
                new_tops.push(tops[i]);
                i += 1;
                continue;
            }
            let kids: Vec<u32> = tops[i..i + take].to_vec();
            let level = kids.iter().map(|&k| nodes[k as usize].level).max().unwrap() + 1;
            let range = [
                nodes[kids[0] as usize].triangles[0],
                nodes[*kids.last().unwrap() as usize].triangles[1],
            ];
            new_tops.push(nodes.len() as u32);
            nodes.push(Node {
                centre: [0.0; 2],
                radius: 0.0,
                children: kids,
                triangles: range,
                level,
                regions: vec![],
            });
            i += take;
        }
        tops = new_tops;
    }
    let h = Hierarchy {
        sectors: 16,
        origin: [0.0; 3],
        nodes,
        roots: tops,
        always_visible: [grouped, nt as u32],
        mesh: Mesh {
            positions: tin.positions().iter().map(|p| p.to_array()).collect(),
            triangles: order.iter().map(|&t| tin.triangles()[t as usize]).collect(),
        },
        build: BuildInfo::default(),
    };
    h.check_invariants().expect("a valid test hierarchy");
    h
}

/// A shuffled order (patches become scattered: circles overlap, children's circles leave their parents').
fn shuffled_order(n: usize, seed: u64) -> Vec<u32> {
    let mut next = splitmix(seed);
    let mut order: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        let j = (next() * (i + 1) as f64) as usize;
        order.swap(i, j.min(i));
    }
    order
}

/// Triangles culled in all (to see that an attack is not vacuous).
static CULLED: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// The first false cull of `culler` from `camera`, if any: `(triangle in the TIN, its corners)`.
fn false_cull(
    tin: &Tin,
    order: &[u32],
    visible: &[bool],
    culler: &SafeCuller,
    camera: &Camera,
) -> Option<(usize, [DVec3; 3])> {
    let list = culler.cull(camera);
    CULLED.fetch_add(
        list.stats.triangles_culled as usize,
        std::sync::atomic::Ordering::Relaxed,
    );
    let mask = list.mask(order.len());
    let eye = DVec3::from_array(camera.position);
    for (i, &t) in order.iter().enumerate() {
        let t = t as usize;
        if visible[t] && !mask[i] {
            let in_view = camera.hfov >= TAU || camera.hfov <= 0.0 || {
                let c = tin.corners(t);
                // Any of the corners, the centroid, or points along the edges inside the view.
                let mut pts: Vec<DVec3> = c.to_vec();
                for k in 0..3 {
                    for s in 1..16 {
                        let a = s as f64 / 16.0;
                        pts.push(c[k] * (1.0 - a) + c[(k + 1) % 3] * a);
                    }
                }
                pts.push((c[0] + c[1] + c[2]) / 3.0);
                pts.iter().any(|p| {
                    let d = *p - eye;
                    let gap =
                        (d.y.atan2(d.x) - camera.yaw + std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI;
                    gap.abs() <= camera.hfov * 0.5
                })
            };
            if in_view {
                return Some((t, tin.corners(t)));
            }
        }
    }
    None
}

/// Parameter sets at the extremes of every range.
fn extreme_params() -> Vec<SafeParams> {
    let d = SafeParams::default();
    let mut out = vec![d];
    out.push(SafeParams {
        columns_per_face: 65536,
        patch: 1,
        ..d
    });
    for columns in [2usize, 8, 4096] {
        for patch in [1usize, 64] {
            out.push(SafeParams {
                columns_per_face: columns,
                patch,
                ..d
            });
        }
    }
    for work_budget in [1usize, 3, 9, 33, 200] {
        out.push(SafeParams {
            work_budget,
            patch: 2,
            ..d
        });
        out.push(SafeParams {
            work_budget,
            columns_per_face: 4096,
            patch: 1,
            coarse_columns: 64,
            ..d
        });
    }
    for coarse_columns in [1usize, 16, 1 << 20, usize::MAX] {
        for columns in [2usize, 1024] {
            out.push(SafeParams {
                columns_per_face: columns,
                patch: 1,
                coarse_columns,
                ..d
            });
        }
    }
    for occluder_budget in [1usize, 5] {
        out.push(SafeParams {
            occluder_budget,
            patch: 1,
            ..d
        });
    }
    out
}

/// Runs every parameter set of `params` over `h` (in `order`) from every eye, all around and in two narrow views,
/// and panics on the first false cull.
fn attack(name: &str, tin: &Tin, h: &Hierarchy, order: &[u32], params: &[SafeParams], eyes: &[DVec3]) -> usize {
    let truth = GroundTruth::new(tin);
    let cullers: Vec<SafeCuller> = params.iter().map(|&p| SafeCuller::new(h, p)).collect();
    let before = CULLED.load(std::sync::atomic::Ordering::Relaxed);
    for &eye in eyes {
        let visible = truth.visible_triangles(eye);
        for (culler, p) in cullers.iter().zip(params) {
            for camera in [
                Camera::all_around(eye.to_array()),
                Camera {
                    position: eye.to_array(),
                    yaw: 2.1,
                    hfov: 0.3,
                },
                Camera {
                    position: eye.to_array(),
                    yaw: -40.0,
                    hfov: 6.2,
                },
            ] {
                if let Some((t, c)) = false_cull(tin, order, &visible, culler, &camera) {
                    panic!(
                        "{name}: false cull of triangle {t} {c:?} from eye {eye:?} (yaw {}, hfov {}), params {p:?}",
                        camera.yaw, camera.hfov
                    );
                }
            }
        }
    }
    CULLED.load(std::sync::atomic::Ordering::Relaxed) - before
}

/// Eyes on every vertex at its height, a hair above, 1e-7 above and on edge midpoints, plus `extra`.
fn eyes_on_vertices(tin: &Tin, every: usize, extra: &[DVec3]) -> Vec<DVec3> {
    let mut eyes = extra.to_vec();
    for (i, p) in tin.positions().iter().enumerate() {
        if i % every != 0 {
            continue;
        }
        eyes.push(*p);
        eyes.push(DVec3::new(p.x, p.y, p.z + p.z.abs().max(1.0) * 1e-12));
        eyes.push(DVec3::new(p.x, p.y, p.z + 0.5));
    }
    eyes
}

/// the notched ridge with patch 1, extreme columns, tiny budgets and large coarse columns, eyes
/// on vertices (on crests and in the notch) and beside the ridge.
#[test]
fn notch_extreme_parameters() {
    let tin = grid_tin(17, 200.0, DVec3::ZERO, notch);
    let order = spatial_order(&tin);
    let extra = [
        DVec3::new(40.0, 100.0, 2.0),
        DVec3::new(100.0, 100.0, 5.0),
        DVec3::new(100.0, 100.0, 30.0),
        DVec3::new(-5000.0, 100.0, 30.0),
        DVec3::new(-1e6, 100.0, 29.99),
        DVec3::new(100.0, -3e5, 1e5),
    ];
    let eyes = eyes_on_vertices(&tin, 11, &extra);
    let mut culled = 0;
    for (leaf, orphans, seed) in [(1usize, 0usize, 1u64), (5, 3, 2), (300, 11, 4)] {
        let h = hierarchy_with_order(&tin, &order, leaf, orphans, seed);
        culled += attack("notch", &tin, &h, &order, &extreme_params(), &eyes);
    }
    assert!(culled > 0);
}

/// Eyes on (and a hair either side of) the circles the safe culler computes for the hierarchy's leaves and for the
/// halves of their ranges (box centre, farthest vertex), at ground level + `dz`.
fn eyes_on_circles(tin: &Tin, h: &Hierarchy, dz: f64) -> Vec<DVec3> {
    let loc = truth::Locator::new(tin);
    let mut ranges: Vec<[u32; 2]> = h.nodes.iter().map(|n| n.triangles).collect();
    for n in &h.nodes {
        let [s, e] = n.triangles;
        if e - s >= 2 {
            let m = s + (e - s) / 2;
            ranges.push([s, m]);
            ranges.push([m, e]);
        }
    }
    let mut eyes = Vec::new();
    for (i, [s, e]) in ranges.into_iter().enumerate() {
        if s == e || i % 3 != 0 {
            continue;
        }
        let ps: Vec<[f64; 3]> = h.mesh.triangles[s as usize..e as usize]
            .iter()
            .flatten()
            .map(|&v| h.mesh.positions[v as usize])
            .collect();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &ps {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let c = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
        let (far, r2) = ps
            .iter()
            .map(|p| (p, (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2)))
            .fold((ps[0], -1.0), |a, b| if b.1 > a.1 { (*b.0, b.1) } else { a });
        let r = r2.sqrt();
        let scale = c[0].abs() + c[1].abs();
        let grown = r * (1.0 + 1e-12) + 1e-12 * scale + 1e-9;
        // Along the direction of the farthest vertex (the eye then sits at or beside that vertex), and across.
        let dir = [(far[0] - c[0]) / r.max(1e-300), (far[1] - c[1]) / r.max(1e-300)];
        for d in [dir, [-dir[1], dir[0]], [-dir[0], -dir[1]]] {
            for rad in [r, grown, grown * (1.0 + 1e-15) + 1e-12, grown + 1e-7, r * 1.001 + 1e-3] {
                let xy = glam::DVec2::new(c[0] + rad * d[0], c[1] + rad * d[1]);
                if let Some(z) = loc.ground_height(tin, xy) {
                    eyes.push(DVec3::new(xy.x, xy.y, z + dz));
                }
            }
        }
    }
    eyes
}

/// scattered (shuffled) triangle orders under random trees: patches are not compact, children's
/// circles reach outside their parents', keys are not monotone along the queue. Random rough TINs, some at UTM
/// coordinates, eyes on the tree's circles, on vertices, and far away.
#[test]
fn scattered_orders_and_eyes_on_circles() {
    let mut culled = 0;
    for seed in 0..6u64 {
        let mut next = splitmix(seed);
        let offset = if seed % 2 == 1 {
            DVec3::new(512_345.25, 5_123_456.5, 1500.0)
        } else {
            DVec3::ZERO
        };
        let Some(tin) = random_tin_at(&mut next, 60 + 20 * seed as usize, 1.5, offset) else {
            continue;
        };
        let order = if seed % 3 == 0 {
            spatial_order(&tin)
        } else {
            shuffled_order(tin.num_triangles(), seed)
        };
        let h = hierarchy_with_order(
            &tin,
            &order,
            1 + (seed as usize * 7) % 23,
            (seed as usize * 5) % 9,
            seed,
        );
        let mut eyes: Vec<DVec3> = eyes_on_circles(&tin, &h, 1e-3).into_iter().step_by(5).collect();
        eyes.extend(eyes_on_circles(&tin, &h, 2.0).into_iter().step_by(17));
        let b = tin.bbox();
        let mid = (b.min + b.max) * 0.5;
        eyes.extend(eyes_on_vertices(
            &tin,
            9,
            &[
                mid + DVec3::new(-3e4, 0.0, 0.0),
                DVec3::new(mid.x + 2e7, mid.y + 1e7, b.max.z),
                DVec3::new(mid.x, mid.y - 800.0, b.max.z + 1e-6),
                DVec3::new(mid.x, mid.y, b.max.z + 5e4),
            ],
        ));
        let params = [
            SafeParams::default(),
            SafeParams {
                patch: 1,
                columns_per_face: 65536,
                ..SafeParams::default()
            },
            SafeParams {
                patch: 1,
                columns_per_face: 2,
                ..SafeParams::default()
            },
            SafeParams {
                patch: 3,
                work_budget: 4,
                ..SafeParams::default()
            },
            SafeParams {
                patch: 2,
                work_budget: 25,
                coarse_columns: usize::MAX,
                ..SafeParams::default()
            },
            SafeParams {
                patch: 1,
                columns_per_face: 4096,
                coarse_columns: 1 << 20,
                ..SafeParams::default()
            },
            SafeParams {
                patch: 64,
                columns_per_face: 16,
                coarse_columns: 3,
                ..SafeParams::default()
            },
        ];
        culled += attack(&format!("scattered seed {seed}"), &tin, &h, &order, &params, &eyes);
    }
    assert!(culled > 0);
}

/// one `DrawList` reused across cameras, cullers over two hierarchies of the same mesh and several
/// parameter sets (its scratch: horizon, queues, pending patches, cell-edge stamps), with empty nodes in the tree
/// (ranges `[s, s)`, whose circles the culler puts at the origin), and after a round trip through the `.tch` bytes:
/// every cull equals a fresh one and culls nothing visible.
#[test]
fn reused_scratch_empty_nodes_and_file_round_trip() {
    let tin = grid_tin(13, 120.0, DVec3::new(3000.0, -2000.0, 100.0), |x, y| {
        40.0 * (-((x - 60.0).powi(2)) / 200.0).exp() + 3.0 * (y / 17.0).sin()
    });
    let order = spatial_order(&tin);
    let mut h = hierarchy_with_order(&tin, &order, 6, 4, 9);
    // Empty leaves: an empty leaf before each leaf's range, under a new parent with that leaf.
    let leaves: Vec<usize> = (0..h.nodes.len()).filter(|&i| h.nodes[i].children.is_empty()).collect();
    for (n, &leaf) in leaves.iter().enumerate() {
        if n % 2 == 1 {
            continue;
        }
        let s = h.nodes[leaf].triangles[0];
        let empty = h.nodes.len() as u32;
        h.nodes.push(Node {
            centre: [0.0; 2],
            radius: 0.0,
            children: vec![],
            triangles: [s, s],
            level: 0,
            regions: vec![],
        });
        // The leaf becomes an inner node over [empty, copy of the leaf].
        let copy = h.nodes.len() as u32;
        let mut c = h.nodes[leaf].clone();
        c.level = 0;
        h.nodes.push(c);
        h.nodes[leaf].children = vec![empty, copy];
        h.nodes[leaf].level = 1;
    }
    // Levels must increase strictly towards the roots: recompute bottom-up.
    fn level(h: &mut Hierarchy, i: usize) -> u32 {
        let kids = h.nodes[i].children.clone();
        let l = kids.iter().map(|&k| level(h, k as usize) + 1).max().unwrap_or(0);
        h.nodes[i].level = l;
        l
    }
    for r in h.roots.clone() {
        level(&mut h, r as usize);
    }
    h.check_invariants().expect("valid");
    let h = Hierarchy::from_bytes(&h.to_bytes().expect("bytes")).expect("loads");
    let h2 = hierarchy_with_order(&tin, &order, 2, 0, 10);
    let truth = GroundTruth::new(&tin);
    let params = [
        SafeParams::default(),
        SafeParams {
            work_budget: 5,
            patch: 1,
            ..SafeParams::default()
        },
        SafeParams {
            work_budget: 40,
            coarse_columns: 1 << 30,
            columns_per_face: 1024,
            ..SafeParams::default()
        },
    ];
    let cullers: Vec<SafeCuller> = params
        .iter()
        .flat_map(|&p| [SafeCuller::new(&h, p), SafeCuller::new(&h2, p)])
        .collect();
    let mut list = cull::DrawList::default();
    let eyes = eyes_on_vertices(
        &tin,
        5,
        &[DVec3::new(2900.0, -1940.0, 120.0), DVec3::new(3200.0, -1940.0, 120.0)],
    );
    let mut culled = 0;
    for (i, &eye) in eyes.iter().enumerate() {
        let visible = truth.visible_triangles(eye);
        for culler in cullers.iter().cycle().skip(i).take(cullers.len()) {
            let camera = Camera::all_around(eye.to_array());
            culler.cull_into(&camera, &mut list);
            let fresh = culler.cull(&camera);
            assert_eq!(
                list.ranges, fresh.ranges,
                "a reused scratch changed the cull from {eye:?}"
            );
            if let Some((t, c)) = false_cull(&tin, &order, &visible, culler, &camera) {
                panic!("false cull of {t} {c:?} from {eye:?}, {:?}", culler.params());
            }
            culled += fresh.stats.triangles_culled;
        }
    }
    assert!(culled > 0);
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 64, ..Default::default() })]

    /// random small rough TINs (spikes and pits), random triangle orders and trees, random
    /// parameters at their extremes, random eyes (on vertices, a hair above, grazing the highest vertex, far).
    #[test]
    fn random_small_tins_random_trees_random_parameters(
        seed in proptest::prelude::any::<u64>(),
        n in 8usize..50,
        utm in proptest::prelude::any::<bool>(),
        shuffle in proptest::prelude::any::<bool>(),
        leaf in 1usize..12,
        orphans in 0usize..6,
        columns in 1u32..17,
        patch in 1usize..65,
        budget in proptest::prelude::prop_oneof![1usize..40, proptest::prelude::Just(usize::MAX)],
        coarse in proptest::prelude::prop_oneof![
            proptest::prelude::Just(0usize),
            1usize..100_000,
            proptest::prelude::Just(usize::MAX),
        ],
        occluders in proptest::prelude::prop_oneof![proptest::prelude::Just(usize::MAX), 0usize..20],
        yaw in -7.0f64..7.0,
        hfov in 0.01f64..7.0,
    ) {
        let mut next = splitmix(seed);
        let offset = if utm { DVec3::new(654_321.125, 4_987_654.75, -50.0) } else { DVec3::ZERO };
        let pts: Vec<DVec3> = (0..n)
            .map(|_| {
                let (x, y) = (next() * 100.0, next() * 100.0);
                let spike = if next() < 0.2 { 40.0 * next() } else { 0.0 };
                DVec3::new(x, y, 10.0 * (x / 20.0).sin() + spike + 3.0 * next()) + offset
            })
            .collect();
        let Ok((tin, _)) = tin::triangulate(&pts, tin::DedupePolicy::Reject) else { return Ok(()); };
        let order = if shuffle { shuffled_order(tin.num_triangles(), seed ^ 7) } else { spatial_order(&tin) };
        let h = hierarchy_with_order(&tin, &order, leaf, orphans, seed ^ 3);
        let params = SafeParams {
            columns_per_face: 1 << columns,
            patch,
            occluder_budget: occluders,
            work_budget: budget,
            coarse_columns: coarse,
        };
        let culler = SafeCuller::new(&h, params);
        let truth = GroundTruth::new(&tin);
        let b = tin.bbox();
        let top = tin.positions().iter().copied().max_by(|a, b| a.z.total_cmp(&b.z)).unwrap();
        let v = tin.positions()[(next() * tin.num_vertices() as f64) as usize % tin.num_vertices()];
        let eyes = [
            v,
            v + DVec3::new(0.0, 0.0, 1e-9),
            v + DVec3::new(0.0, 0.0, 3.0),
            DVec3::new(b.min.x - 50.0, top.y, top.z),
            DVec3::new(top.x + 1e5, top.y + 1.0, top.z + 1e-7),
            DVec3::new(b.min.x + next() * 100.0, b.min.y + next() * 100.0, b.min.z + next() * 30.0),
        ];
        for eye in eyes {
            let visible = truth.visible_triangles(eye);
            for camera in [Camera::all_around(eye.to_array()), Camera { position: eye.to_array(), yaw, hfov }] {
                if let Some((t, c)) = false_cull(&tin, &order, &visible, &culler, &camera) {
                    panic!("false cull of {t} {c:?} from {eye:?} yaw {yaw} hfov {hfov}, {params:?}");
                }
            }
        }
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 96, ..Default::default() })]

    /// knife edges, plateau edges and a notched wall on a jittered grid, scaled from millimetres
    /// to kilometres and moved to UTM coordinates, heights up to 9 km; eyes exactly on crest vertices and plateau
    /// edges (grazing), level with the crest far away, and a hair above; tiny patches and extreme columns.
    #[test]
    fn scaled_knife_edges_and_plateaus(
        seed in proptest::prelude::any::<u64>(),
        scale_exp in -3i32..4,
        z0 in proptest::prelude::prop_oneof![proptest::prelude::Just(0.0f64), -400.0f64..9000.0],
        utm in proptest::prelude::any::<bool>(),
        shuffle in proptest::prelude::any::<bool>(),
        leaf in 1usize..9,
        columns in 1u32..17,
        patch in 1usize..5,
        budget in proptest::prelude::prop_oneof![1usize..30, proptest::prelude::Just(usize::MAX)],
        coarse in proptest::prelude::prop_oneof![proptest::prelude::Just(0usize), proptest::prelude::Just(usize::MAX)],
        kind in 0u32..3,
    ) {
        let s = 10f64.powi(scale_exp);
        let mut next = splitmix(seed);
        let offset = if utm { DVec3::new(500_000.0 + 0.37, 5_000_000.0 + 0.61, z0) } else { DVec3::new(0.0, 0.0, z0) };
        let n = 9usize;
        let mut pts = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let (mut x, mut y) = (i as f64 * 10.0, j as f64 * 10.0);
                if i > 0 && j > 0 && i < n - 1 && j < n - 1 {
                    x += (next() - 0.5) * 2.0;
                    y += (next() - 0.5) * 2.0;
                }
                let z = match kind {
                    // A knife edge along x = 40 (one vertex row high).
                    0 => if i == 4 { 30.0 } else { 0.0 },
                    // A plateau with a sharp edge.
                    1 => if i >= 4 { 20.0 } else { 0.0 },
                    // A wall at i = 4 with a one-vertex notch at j = 4.
                    _ => if i == 4 && j != 4 { 25.0 } else if i == 4 { 5.0 } else { 0.0 },
                };
                pts.push(DVec3::new(x * s, y * s, z * s) + offset);
            }
        }
        let Ok((tin, _)) = tin::triangulate(&pts, tin::DedupePolicy::Reject) else { return Ok(()); };
        let order = if shuffle { shuffled_order(tin.num_triangles(), seed ^ 5) } else { spatial_order(&tin) };
        let h = hierarchy_with_order(&tin, &order, leaf, 0, seed);
        let params = SafeParams {
            columns_per_face: 1 << columns,
            patch,
            occluder_budget: usize::MAX,
            work_budget: budget,
            coarse_columns: coarse,
        };
        let culler = SafeCuller::new(&h, params);
        let truth = GroundTruth::new(&tin);
        let crest = pts[4 + n * ((next() * n as f64) as usize % n)];
        let low = pts[(next() * (n * n) as f64) as usize % (n * n)];
        let eyes = [
            crest,
            crest + DVec3::new(0.0, 0.0, 1e-9 * s),
            low,
            low + DVec3::new(0.0, 0.0, 1.0 * s),
            DVec3::new(crest.x - 300.0 * s, crest.y, crest.z),
            DVec3::new(crest.x - 300.0 * s, crest.y, crest.z + 1e-6 * s),
            DVec3::new(crest.x - 7e4 * s, crest.y + 3.0 * s, crest.z),
            pts[4 + n * 4] + DVec3::new(-25.0 * s, 0.0, -5.0 * s + 6.0 * s),
        ];
        for eye in eyes {
            let visible = truth.visible_triangles(eye);
            let camera = Camera::all_around(eye.to_array());
            if let Some((t, c)) = false_cull(&tin, &order, &visible, &culler, &camera) {
                panic!("false cull of {t} {c:?} from {eye:?}, {params:?}");
            }
        }
    }
}
