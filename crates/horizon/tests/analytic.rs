//! Terrains whose horizons are known in closed form, checked against the sweep (and the oracle).

mod common;

use common::{CONFIGS, Kind, config, points, terrain};
use glam::{DVec2, DVec3};
use horizon::{HorizonOptions, SectorGeometry, Wedge, brute_force, compute};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tin::{DedupePolicy, Tin, triangulate};

fn tin_of(points: &[DVec3]) -> Tin {
    triangulate(points, DedupePolicy::Reject).expect("triangulates").0
}

/// A centre vertex with two rings of vertices on the subsector centre rays; heights `f(ρ)`.
fn rings(geometry: &SectorGeometry, f: impl Fn(f64) -> f64) -> Tin {
    let mut pts = vec![DVec3::new(0.0, 0.0, f(0.0))];
    for j in 0..geometry.total() {
        let r = geometry.wedge(j).r;
        for rho in [10.0, 20.0] {
            pts.push((r * rho).extend(f(rho)));
        }
    }
    tin_of(&pts)
}

#[test]
fn bowl_and_dome_rings() {
    for (s, k) in CONFIGS {
        let cfg = config(s, k);
        let g = SectorGeometry::new(&cfg);
        let opts = HorizonOptions::default();
        // Bowl z = ρ²/100: the outer ring is steeper (0.2 against 0.1).
        let bowl = rings(&g, |rho| rho * rho / 100.0);
        let field = compute(&bowl, &cfg, &opts).expect("valid");
        // Dome z = −ρ²/100: the inner ring is less steep downwards (−0.1 against −0.2).
        let dome = rings(&g, |rho| -rho * rho / 100.0);
        let dome_field = compute(&dome, &cfg, &opts).expect("valid");
        for j in 0..g.total() as u32 {
            assert_eq!(field.horizon(0, j), Some(2 + 2 * j), "bowl {s}x{k} subsector {j}");
            assert_eq!(dome_field.horizon(0, j), Some(1 + 2 * j), "dome {s}x{k} subsector {j}");
        }
        // Sector summaries: slope 0.2; farthest distance along the sector centre is 20·cos of the smallest angle
        // between the sector centre and a subsector centre (0 for odd k, half a subsector for even k).
        let min_offset = if k % 2 == 1 {
            0.0
        } else {
            std::f64::consts::PI / g.total() as f64
        };
        for i in 0..s {
            let sum = field.sector_summary(0, i).expect("every subsector has a horizon");
            assert!(
                (sum.slope - 0.2).abs() < 1e-12,
                "{s}x{k} sector {i}: slope {}",
                sum.slope
            );
            assert!(
                (sum.distance - 20.0 * min_offset.cos()).abs() < 1e-9,
                "{s}x{k}: distance {}",
                sum.distance
            );
            let dome_sum = dome_field.sector_summary(0, i).expect("horizons everywhere");
            assert!((dome_sum.slope + 0.1).abs() < 1e-12);
        }
        assert_eq!(field.mismatches(&brute_force(&bowl, &cfg, &opts).expect("valid")), 0);
    }
}

/// A straight ridge across subsector `j`'s centre direction: `z = 100 − 2·|r·x|`. Seen from the near side, the
/// rising flank has slope exactly 2 in the projection, so the horizon slope is 2 whenever a flank vertex is in
/// the wedge, and below 2 otherwise; seen from the far side every slope is −2.
#[test]
fn straight_ridge_has_the_flank_slope() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for (s, k, j) in [(8u32, 1u32, 1usize), (16, 4, 37), (5, 3, 7), (64, 1, 20)] {
        let cfg = config(s, k);
        let g = SectorGeometry::new(&cfg);
        let w: Wedge = g.wedge(j);
        let height = |xy: DVec2| 100.0 - 2.0 * w.r.dot(xy).abs();
        let pts: Vec<DVec3> = (0..1500)
            .map(|_| {
                let xy = DVec2::new(rng.random_range(-500.0..500.0), rng.random_range(-500.0..500.0));
                xy.extend(height(xy))
            })
            .collect();
        let tin = tin_of(&pts);
        let field = compute(&tin, &cfg, &HorizonOptions::default()).expect("valid");
        let pos = tin.positions();
        let mut near_checked = 0;
        for (p, &pp) in pos.iter().enumerate() {
            let members: Vec<usize> = (0..pos.len())
                .filter(|&q| q != p && w.contains(pp.truncate(), pos[q].truncate()))
                .collect();
            let h = field.horizon(p as u32, j as u32);
            assert_eq!(h.is_some(), !members.is_empty());
            let Some(h) = h else { continue };
            let q = pos[h as usize];
            let slope = (q.z - pp.z) / w.r.dot(q.truncate() - pp.truncate());
            let tp = w.r.dot(pp.truncate());
            if tp < -1e-9 {
                let flank_member = members.iter().any(|&q| w.r.dot(pos[q].truncate()) <= 0.0);
                if flank_member {
                    assert!((slope - 2.0).abs() < 1e-6, "{s}x{k}: vertex {p} slope {slope}");
                    near_checked += 1;
                } else {
                    assert!(slope < 2.0 + 1e-6);
                }
            } else if tp > 1e-9 {
                assert!((slope + 2.0).abs() < 1e-6, "{s}x{k}: far-side vertex {p} slope {slope}");
            }
        }
        assert!(near_checked > 100, "only {near_checked} near-side vertices checked");
    }
}

/// The definition's tie-break alone: the wedge members with the smallest `t`, then smallest index.
fn nearest_member(g: &SectorGeometry, tin: &Tin, p: usize, j: usize, prefer_far: bool) -> Option<u32> {
    let w = g.wedge(j);
    let o = tin.origin().truncate();
    let pos = tin.positions();
    let mut best: Option<(f64, usize)> = None;
    for q in 0..pos.len() {
        if q == p || !w.contains(pos[p].truncate(), pos[q].truncate()) {
            continue;
        }
        let t = w.project(o, pos[q].truncate());
        let key = if prefer_far { -t } else { t };
        if best.is_none_or(|(bt, _)| key < bt) {
            best = Some((key, q));
        }
    }
    best.map(|(_, q)| q as u32)
}

/// Flat lake: every slope is exactly 0, so the horizon is the nearest member by `t`, then the smallest index.
#[test]
fn flat_lake_picks_the_nearest_member() {
    for seed in [2u64, 3] {
        let tin = terrain(Kind::Flat, 150, seed).expect("triangulates");
        for (s, k) in CONFIGS {
            let cfg = config(s, k);
            let g = SectorGeometry::new(&cfg);
            let field = compute(&tin, &cfg, &HorizonOptions::default()).expect("valid");
            for p in 0..tin.num_vertices() {
                for j in 0..g.total() {
                    assert_eq!(
                        field.horizon(p as u32, j as u32),
                        nearest_member(&g, &tin, p, j, false),
                        "seed {seed} {s}x{k} vertex {p} subsector {j}"
                    );
                }
            }
        }
    }
}

/// One spike on a flat grid: every vertex that has the spike in its wedge sees it; the others see the nearest
/// member; the spike itself looks down and sees the farthest member (least negative slope).
#[test]
fn spike_on_a_flat_grid() {
    let mut pts = points(Kind::Flat, 144, 0); // 12×12 integer grid at height 7
    let spike = 53;
    pts[spike].z = 40.0;
    let tin = tin_of(&pts);
    for (s, k) in CONFIGS {
        let cfg = config(s, k);
        let g = SectorGeometry::new(&cfg);
        let field = compute(&tin, &cfg, &HorizonOptions::default()).expect("valid");
        let pos = tin.positions();
        for p in 0..pos.len() {
            for j in 0..g.total() {
                let expect = if p == spike {
                    nearest_member(&g, &tin, p, j, true)
                } else if g.wedge(j).contains(pos[p].truncate(), pos[spike].truncate()) {
                    Some(spike as u32)
                } else {
                    nearest_member(&g, &tin, p, j, false)
                };
                assert_eq!(
                    field.horizon(p as u32, j as u32),
                    expect,
                    "{s}x{k} vertex {p} subsector {j}"
                );
            }
        }
    }
}
