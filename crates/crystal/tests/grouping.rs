//! Crystal grouping on random, flat, tiny and ridge terrains with brute-force horizons.

mod common;

use common::{jittered_grid, random_terrain, recheck_group_regions, recheck_growth, recheck_passes, tables};
use crystal::{Crystal, CrystalError, CrystalParams, NO_GROUP, build};
use glam::DVec2;
use occlusion::RegionTable;
use proptest::prelude::*;
use tin::Tin;

fn group(tin: &Tin, sectors: u32, subsectors: u32, params: &CrystalParams) -> (Crystal, RegionTable, RegionTable) {
    let (v, t) = tables(tin, sectors, subsectors);
    let c = build(tin, &v, params).expect("valid input");
    c.check_invariants(tin).expect("invariants hold");
    recheck_growth(tin, &v, &c);
    recheck_group_regions(&c, &t);
    recheck_passes(tin, &c);
    (c, v, t)
}

#[test]
fn random_terrain_groups_satisfy_every_invariant() {
    let tin = jittered_grid(30, 30, 10.0, 3.0, 7, common::fractal(7, 40.0, 90.0));
    let params = CrystalParams {
        seeds: Some(30),
        min_group: 10,
        ..Default::default()
    };
    let (c, _, _) = group(&tin, 16, 4, &params);
    let s = &c.stats;
    eprintln!("{s:?}");
    assert!(
        s.groups >= 2,
        "a rough terrain of {} triangles forms several groups",
        tin.num_triangles()
    );
    assert!(s.orphans < tin.num_triangles(), "not everything is orphaned");
    assert_eq!(s.passes[0].seeds, 30);
    assert!(
        s.orphan_passes >= 1,
        "a rough terrain leaves orphans for an orphan pass"
    );
    // Orphan passes cast proportionally fewer seeds.
    for p in &s.passes[1..] {
        assert!(p.seeds >= 1 && p.seeds < 30);
    }
    assert!(s.nodes > s.groups, "groups that collided merge into parents");
}

#[test]
fn flat_terrain_is_visible_everywhere_and_forms_few_big_groups() {
    let tin = jittered_grid(30, 30, 10.0, 3.0, 3, |_| 0.0);
    let params = CrystalParams {
        seeds: Some(6),
        max_expanse: f64::INFINITY,
        ..Default::default()
    };
    let (c, v, _) = group(&tin, 8, 2, &params);
    // Nothing is hidden on a flat terrain: every triangle is reachable from every seed.
    let p = tin.positions();
    for a in (0..tin.num_vertices() as u32).step_by(37) {
        for b in (0..tin.num_vertices() as u32).step_by(11) {
            assert!(!v.vertex_hidden_from(a, p[a as usize], p[b as usize]));
        }
    }
    assert_eq!(c.stats.orphans, 0, "{:?}", c.stats);
    assert_eq!(c.stats.passes.len(), 1, "no orphans, no orphan pass");
    assert_eq!(c.stats.groups, 6, "each seed grows one big group");
    assert!(c.groups.iter().all(|g| g.len() > 60));
    // Without an expanse limit, groups that all see each other merge into one tree.
    assert_eq!(c.hierarchy.roots.len(), 1, "all groups collide and merge into one tree");
    assert_eq!(c.stats.nodes, 11);
    // With no horizons at all (empty regions everywhere) growth sees exactly the same: identical groups.
    let empty = RegionTable::from_rows(8, DVec2::ZERO, vec![None; tin.num_vertices() * 8]);
    let bare = build(&tin, &empty, &params).expect("valid");
    bare.check_invariants(&tin).expect("invariants");
    assert_eq!(bare.groups, c.groups);
    assert!(
        bare.hierarchy
            .nodes
            .iter()
            .all(|n| n.regions.iter().all(Option::is_none))
    );
}

#[test]
fn tiny_mesh_below_min_group_is_all_orphans() {
    let tin = random_terrain(4, 4, 2); // 18 triangles
    assert!(tin.num_triangles() < 30);
    let (c, _, _) = group(&tin, 8, 2, &CrystalParams::default());
    assert_eq!(c.stats.groups, 0);
    assert_eq!(c.orphans.len(), tin.num_triangles());
    assert!(c.group_of.iter().all(|&g| g == NO_GROUP));
    assert!(c.hierarchy.nodes.is_empty() && c.hierarchy.roots.is_empty());
    assert_eq!(c.orphan_range, 0..tin.num_triangles() as u32);
    assert_eq!(c.stats.levels, 0);
}

/// A straight north-south ridge at x = 100 with convex flanks (every flank point is visible from the flank's foot;
/// everything beyond the crest is hidden from it). The crest is sampled every `crest_step` metres, the flanks every
/// 10 m; the flank rows are jittered in y.
fn ridge(crest_step: f64) -> Tin {
    let (nx, ny, step) = (21, 16, 10.0);
    let height = |x: f64| {
        let u = (x - 100.0).abs() / 100.0;
        60.0 * (1.0 - u) * (1.0 - u)
    };
    let mut points = Vec::new();
    let mut rng_state = 12345u64;
    for j in 0..ny {
        for i in (0..nx).filter(|&i| i != 10) {
            rng_state = rng_state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let jitter = ((rng_state >> 33) as f64 / (1u64 << 31) as f64 - 0.5) * 4.0;
            let x = i as f64 * step;
            // Straight first and last rows, so that no hull triangle bridges the crest column.
            let y = j as f64 * step + if j == 0 || j == ny - 1 { 0.0 } else { jitter };
            points.push(glam::DVec3::new(x, y, height(x)));
        }
    }
    // The crest runs 50 m beyond the flanks at both ends, so that every sector of a flank vertex that looks across
    // the ridge finds crest vertices in all its subsectors (a sector reaching past the mesh has no horizon and hides
    // nothing).
    let crest = ((ny - 1) as f64 * step + 100.0) / crest_step;
    for k in 0..=crest.round() as usize {
        points.push(glam::DVec3::new(100.0, k as f64 * crest_step - 50.0, height(100.0)));
    }
    tin::triangulate(&points, tin::DedupePolicy::Reject).expect("valid").0
}

/// Groups of `c` with triangles on both flanks of the ridge (a triangle is west when it has a vertex west of the crest
/// column, east otherwise).
fn crossing_groups(tin: &Tin, c: &Crystal) -> Vec<usize> {
    let side = |t: u32| {
        let xs = tin.corners(t as usize).map(|p| p.x);
        let west = xs.iter().any(|&x| x < 99.0);
        assert!(
            !(west && xs.iter().any(|&x| x > 101.0)),
            "triangle {t} straddles the crest column"
        );
        west
    };
    (0..c.groups.len())
        .filter(|&g| c.groups[g].iter().any(|&t| side(t) != side(c.groups[g][0])))
        .collect()
}

#[test]
fn groups_do_not_cross_a_ridge_crest() {
    // The crest is sampled every 0.5 m: from a flank vertex 10 m away, every subsector (at most 5.6° wide) then holds a
    // crest vertex, so the regions see the ridge.
    let tin = ridge(0.5);
    let params = CrystalParams {
        seeds: Some(10),
        min_group: 10,
        ..Default::default()
    };
    for (sectors, subsectors) in [(16, 4), (8, 2)] {
        let (v, _) = tables(&tin, sectors, subsectors);
        for rng_seed in 1..=3 {
            let c = build(
                &tin,
                &v,
                &CrystalParams {
                    rng_seed,
                    ..params.clone()
                },
            )
            .expect("valid");
            c.check_invariants(&tin).expect("invariants");
            recheck_growth(&tin, &v, &c);
            let label = format!("{sectors}/{subsectors} sectors, seed {rng_seed}");
            assert_eq!(
                crossing_groups(&tin, &c),
                Vec::<usize>::new(),
                "{label}: groups cross the crest"
            );
            let west = |g: &Vec<u32>| tin.corners(g[0] as usize).iter().any(|p| p.x < 99.0);
            assert!(
                c.groups.iter().any(west) && !c.groups.iter().all(west),
                "{label}: both flanks form groups"
            );
            assert!(
                c.orphans.len() * 10 < tin.num_triangles(),
                "{label}: smooth flanks are grouped"
            );
            // The flanks cannot see into each other, so their groups never collide either.
            for g in 0..c.groups.len() {
                for &(h, _) in &c.hierarchy.nodes[g].collisions {
                    assert_eq!(
                        west(&c.groups[g]),
                        west(&c.groups[h as usize]),
                        "{label}: {g} and {h} collided"
                    );
                }
            }
        }
    }
}

#[test]
fn a_sparsely_sampled_crest_lets_groups_cross() {
    // Thesis Figure 18: with 16 sectors of 4 subsectors, a crest sampled every 10 m falls between the subsectors of
    // nearby flank vertices, their regions miss the ridge, and crystals grow over it. This pins down that the
    // crossing test above can fail.
    let tin = ridge(10.0);
    let (v, _) = tables(&tin, 16, 4);
    let c = build(
        &tin,
        &v,
        &CrystalParams {
            seeds: Some(10),
            min_group: 10,
            ..Default::default()
        },
    )
    .expect("valid");
    c.check_invariants(&tin).expect("invariants");
    assert!(!crossing_groups(&tin, &c).is_empty());
}

#[test]
fn same_seed_same_result_different_seed_different_groups() {
    let tin = random_terrain(20, 20, 11);
    let (v, _) = tables(&tin, 8, 4);
    let params = CrystalParams {
        seeds: Some(6),
        min_group: 10,
        ..Default::default()
    };
    let a = build(&tin, &v, &params).expect("valid");
    let b = build(&tin, &v, &params).expect("valid");
    assert_eq!(a, b);
    let other = build(&tin, &v, &CrystalParams { rng_seed: 2, ..params }).expect("valid");
    other.check_invariants(&tin).expect("invariants");
    assert_ne!(a.groups, other.groups);
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let tin = random_terrain(24, 20, 5);
    let params = CrystalParams {
        seeds: Some(7),
        min_group: 10,
        ..Default::default()
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| {
                let (v, _) = tables(&tin, 8, 4);
                build(&tin, &v, &params).expect("valid")
            })
    };
    let one = run(1);
    assert_eq!(one, run(2));
    assert_eq!(one, run(3));
}

#[test]
fn collision_records_are_symmetric_and_sum_in_parents() {
    let tin = random_terrain(24, 24, 9);
    let params = CrystalParams {
        seeds: Some(12),
        min_group: 8,
        max_expanse: f64::INFINITY,
        ..Default::default()
    };
    let (c, _, _) = group(&tin, 8, 4, &params);
    let nodes = &c.hierarchy.nodes;
    let mut pairs = 0;
    for (g, n) in nodes.iter().enumerate().take(c.groups.len()) {
        for &(h, count) in &n.collisions {
            pairs += 1;
            assert!(nodes[h as usize].collisions.contains(&(g as u32, count)));
        }
    }
    assert!(pairs > 0, "neighbouring groups collide");
    // A parent's record is its children's summed, without their mutual collisions (which exist: they merged because
    // they collided). Without the expanse limit no edge is ever dropped, so the totals add up exactly.
    let total = |x: u32| nodes[x as usize].collisions.iter().map(|e| e.1).sum::<u64>();
    let mut leaf_pairs = 0;
    for (id, n) in nodes.iter().enumerate() {
        if let [a, b] = n.children[..] {
            let (ta, tb, tp) = (total(a), total(b), total(id as u32));
            assert!(
                tp < ta + tb && (ta + tb - tp) % 2 == 0,
                "node {id}: {ta} + {tb} -> {tp}"
            );
            if n.level == 1 {
                leaf_pairs += 1;
                let mutual = nodes[a as usize]
                    .collisions
                    .iter()
                    .find(|e| e.0 == b)
                    .map_or(0, |e| e.1);
                assert!(mutual > 0, "node {id}: leaves {a} and {b} merged without colliding");
                assert_eq!(tp, ta + tb - 2 * mutual, "node {id}");
                // The merged pair was the most-collided partner of at least one of them (ties to the smaller id).
                let best = |x: u32| {
                    nodes[x as usize]
                        .collisions
                        .iter()
                        .max_by(|p, q| p.1.cmp(&q.1).then(q.0.cmp(&p.0)))
                        .map(|e| e.0)
                };
                assert!(best(a) == Some(b) || best(b) == Some(a), "node {id}");
            }
        }
    }
    assert!(leaf_pairs > 0);
    assert_eq!(c.stats.expanse_rejections, 0);
    // With every collision kept, merging ends only when no root has collisions left.
    for &r in &c.hierarchy.roots {
        assert!(nodes[r as usize].parent.is_none());
    }
}

#[test]
fn expanse_limit_keeps_parents_small() {
    let tin = random_terrain(26, 26, 4);
    let (v, _) = tables(&tin, 8, 2);
    let base = CrystalParams {
        seeds: Some(16),
        min_group: 6,
        ..Default::default()
    };
    let loose = build(
        &tin,
        &v,
        &CrystalParams {
            max_expanse: f64::INFINITY,
            ..base.clone()
        },
    )
    .expect("valid");
    let tight = build(
        &tin,
        &v,
        &CrystalParams {
            max_expanse: 0.08,
            ..base
        },
    )
    .expect("valid");
    loose.check_invariants(&tin).expect("loose invariants");
    tight.check_invariants(&tin).expect("tight invariants");
    assert_eq!(loose.groups, tight.groups, "the limit only affects the hierarchy");
    assert_eq!(loose.stats.expanse_rejections, 0);
    assert!(tight.stats.expanse_rejections > 0);
    assert!(tight.stats.top_level > loose.stats.top_level);
    let limit = 0.08 * tight.terrain_area;
    for n in &tight.hierarchy.nodes {
        if !n.children.is_empty() {
            assert!(std::f64::consts::PI * n.circle.radius.powi(2) <= limit);
        }
    }
}

#[test]
fn bad_input_is_rejected_with_the_offending_part_named() {
    let tin = random_terrain(6, 6, 1);
    let (v, t) = tables(&tin, 8, 1);
    let err = build(&tin, &t, &CrystalParams::default()).expect_err("triangle table as vertex table");
    assert!(
        matches!(err, CrystalError::TableSize { table: "vertex", expected, found } if expected == tin.num_vertices() && found == tin.num_triangles()),
        "{err}"
    );
    let err = build(
        &tin,
        &v,
        &CrystalParams {
            min_group: 0,
            ..Default::default()
        },
    )
    .expect_err("bad params");
    assert!(err.to_string().contains("min_group"), "{err}");
}

#[test]
fn invariant_checker_catches_broken_groupings() {
    let tin = random_terrain(16, 16, 3);
    let params = CrystalParams {
        seeds: Some(5),
        min_group: 10,
        ..Default::default()
    };
    let (c, _, _) = group(&tin, 8, 2, &params);
    assert!(c.stats.groups >= 2);
    let mut broken = c.clone();
    let last = broken.order.len() - 1;
    broken.order.swap(0, last);
    assert!(broken.check_invariants(&tin).is_err(), "a shuffled order");
    let mut broken = c.clone();
    let t = broken.groups[0].pop().expect("non-empty");
    broken.orphans.push(t);
    assert!(
        broken.check_invariants(&tin).is_err(),
        "a triangle moved without its bookkeeping"
    );
    let nodes = &c.hierarchy.nodes;
    let parent = nodes.iter().position(|n| {
        n.children.len() == 2
            && n.children
                .iter()
                .all(|&x| nodes[x as usize].regions.iter().any(Option::is_some))
    });
    if let Some(p) = parent {
        let mut broken = c.clone();
        let s = nodes[p].regions.iter().position(Option::is_some);
        let sector = s.unwrap_or(0);
        let a = nodes[p].children[0] as usize;
        broken.hierarchy.nodes[p].regions[sector] = nodes[a].regions[sector].clone();
        if broken.hierarchy.nodes[p].regions != nodes[p].regions {
            assert!(
                broken.check_invariants(&tin).is_err(),
                "a parent region that is not the intersection"
            );
        }
    }
    let mut broken = c;
    broken.stats.groups += 1;
    assert!(broken.check_invariants(&tin).is_err(), "wrong stats");
}

fn small_params() -> impl Strategy<Value = CrystalParams> {
    (
        1usize..8,
        0u32..4,
        1usize..16,
        prop_oneof![Just(0.02), Just(0.25), Just(f64::INFINITY)],
        any::<u64>(),
    )
        .prop_map(
            |(seeds, orphan_passes, min_group, max_expanse, rng_seed)| CrystalParams {
                seeds: Some(seeds),
                orphan_passes,
                min_group,
                max_expanse,
                rng_seed,
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn invariants_hold_on_random_meshes(
        nx in 3usize..13,
        ny in 3usize..13,
        terrain in any::<u64>(),
        sectors in prop_oneof![Just(4u32), Just(8), Just(16)],
        subsectors in 1u32..3,
        params in small_params(),
    ) {
        let tin = random_terrain(nx, ny, terrain);
        let (c, _, _) = group(&tin, sectors, subsectors, &params);
        prop_assert_eq!(c.groups.iter().map(Vec::len).sum::<usize>() + c.orphans.len(), tin.num_triangles());
    }

    #[test]
    fn invariants_hold_on_degenerate_meshes(
        n in 3usize..40,
        terrain in any::<u64>(),
        kind in 0u8..3,
        params in small_params(),
    ) {
        // A thin strip, a spiky terrain, or a steep plane.
        let tin = match kind {
            0 => jittered_grid(n, 2, 10.0, 2.0, terrain, common::fractal(terrain, 20.0, 40.0)),
            1 => jittered_grid(6, 6, 10.0, 4.0, terrain, {
                let f = common::fractal(terrain, 200.0, 15.0);
                move |p: DVec2| f(p)
            }),
            _ => jittered_grid(7, 5, 10.0, 3.0, terrain, move |p: DVec2| 3.0 * p.x + (n as f64) * 0.01 * p.y),
        };
        let (c, _, _) = group(&tin, 8, 2, &params);
        prop_assert!(c.groups.iter().all(|g| g.len() >= params.min_group));
    }

    #[test]
    fn invariants_hold_with_arbitrary_horizons(
        nx in 3usize..14,
        ny in 3usize..14,
        terrain in any::<u64>(),
        horizons in prop::collection::vec(prop::option::weighted(0.8, (-1.5f64..1.5, 0.0f64..60.0)), 8 * 196),
        params in small_params(),
    ) {
        // Hand-made horizons unrelated to the terrain: visibility is erratic, which exercises seeds that fail the
        // rule, freed groups and small merges.
        let tin = random_terrain(nx, ny, terrain);
        let v = RegionTable::of_vertices(tin.positions(), DVec2::ZERO, 8, |vx, s| {
            horizons[(vx * 8 + s) as usize].map(|(slope, distance)| occlusion::SectorHorizon { slope, distance })
        });
        let tris = tin.triangles();
        let t = v.intersect_rows(tin.num_triangles(), |i| tris[i]);
        let c = build(&tin, &v, &params).expect("valid input");
        c.check_invariants(&tin).expect("invariants hold");
        recheck_growth(&tin, &v, &c);
        recheck_group_regions(&c, &t);
        recheck_passes(&tin, &c);
    }
}
