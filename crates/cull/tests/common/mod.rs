//! Test terrains and hierarchies shared by the safe-culling tests of this crate and the PVS tests (`crates/pvs`,
//! which includes this file by path).

// Each test binary uses its own subset of these.
#![allow(dead_code)]

use cull::{BuildInfo, Hierarchy, Mesh, Node};
use glam::DVec3;
use tin::{DedupePolicy, Tin, triangulate};

/// `tin`'s triangles in the spatial order of their centroids ([`spatial`]).
pub fn spatial_order(tin: &Tin) -> Vec<u32> {
    let centroids: Vec<[f64; 2]> = (0..tin.num_triangles())
        .map(|t| {
            let c = tin.corners(t);
            [(c[0].x + c[1].x + c[2].x) / 3.0, (c[0].y + c[1].y + c[2].y) / 3.0]
        })
        .collect();
    let mut order: Vec<u32> = (0..tin.num_triangles() as u32).collect();
    spatial(&mut order, &centroids);
    order
}

/// Orders triangles so that halving is a spatial split (the build's layout, written independently here).
pub fn spatial(tris: &mut [u32], c: &[[f64; 2]]) {
    if tris.len() <= 2 {
        tris.sort_unstable();
        return;
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for &t in tris.iter() {
        for k in 0..2 {
            lo[k] = lo[k].min(c[t as usize][k]);
            hi[k] = hi[k].max(c[t as usize][k]);
        }
    }
    let axis = usize::from(hi[1] - lo[1] > hi[0] - lo[0]);
    let mid = tris.len() / 2;
    tris.select_nth_unstable_by(mid, |&a, &b| {
        c[a as usize][axis].total_cmp(&c[b as usize][axis]).then(a.cmp(&b))
    });
    let (l, r) = tris.split_at_mut(mid);
    spatial(l, c);
    spatial(r, c);
}

/// A hierarchy over `tin` without regions (the safe culler reads none): triangles in spatial order, leaves of `leaf`
/// triangles, parents over pairs of leaves, and the last `orphans` triangles always visible. Returns it with the
/// order (`order[i]` is the TIN triangle drawn `i`-th).
pub fn hierarchy_of(tin: &Tin, leaf: usize, orphans: usize) -> (Hierarchy, Vec<u32>) {
    let nt = tin.num_triangles();
    let order = spatial_order(tin);
    let orphans = orphans.min(nt);
    let grouped = (nt - orphans) as u32;
    let origin = tin.origin().to_array();
    let circle = |range: [u32; 2]| {
        let pts: Vec<glam::DVec2> = order[range[0] as usize..range[1] as usize]
            .iter()
            .flat_map(|&t| tin.corners(t as usize).map(|p| p.truncate()))
            .collect();
        let c = tin::bounding_circle_of_points(&pts).expect("a non-empty node");
        let centre = [(c.centre.x - origin[0]) as f32, (c.centre.y - origin[1]) as f32];
        let shift =
            (f64::from(centre[0]) + origin[0] - c.centre.x).hypot(f64::from(centre[1]) + origin[1] - c.centre.y);
        (centre, ((c.radius + shift) * (1.0 + 1e-6) + 1e-3) as f32)
    };
    let mut nodes = Vec::new();
    let mut leaves = Vec::new();
    let mut s = 0u32;
    while s < grouped {
        let e = (s + leaf as u32).min(grouped);
        let (centre, radius) = circle([s, e]);
        leaves.push(nodes.len() as u32);
        nodes.push(Node {
            centre,
            radius,
            children: vec![],
            triangles: [s, e],
            level: 0,
            regions: vec![],
        });
        s = e;
    }
    let mut roots = Vec::new();
    for pair in leaves.chunks(2) {
        if pair.len() == 1 {
            roots.push(pair[0]);
            continue;
        }
        let range = [
            nodes[pair[0] as usize].triangles[0],
            nodes[pair[1] as usize].triangles[1],
        ];
        let (centre, radius) = circle(range);
        roots.push(nodes.len() as u32);
        nodes.push(Node {
            centre,
            radius,
            children: pair.to_vec(),
            triangles: range,
            level: 1,
            regions: vec![],
        });
    }
    let h = Hierarchy {
        sectors: 16,
        origin,
        nodes,
        roots,
        always_visible: [grouped, nt as u32],
        mesh: Mesh {
            positions: tin.positions().iter().map(|p| p.to_array()).collect(),
            triangles: order.iter().map(|&t| tin.triangles()[t as usize]).collect(),
        },
        build: BuildInfo::default(),
    };
    h.check_invariants().expect("a valid test hierarchy");
    (h, order)
}

pub fn grid_tin(n: usize, size: f64, offset: DVec3, height: impl Fn(f64, f64) -> f64) -> Tin {
    let mut pts = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (size * i as f64 / (n - 1) as f64, size * j as f64 / (n - 1) as f64);
            pts.push(DVec3::new(x, y, height(x, y)) + offset);
        }
    }
    triangulate(&pts, DedupePolicy::Reject).expect("a valid grid").0
}

/// A ridge at x = 100 (30 m) with a V notch down to 5 m at y = 100: triangles behind the notch are seen through it
/// while their vertices are hidden — the case that defeats vertex regions.
pub fn notch(x: f64, y: f64) -> f64 {
    let ridge = (30.0 - 3.0 * (x - 100.0).abs()).max(0.0);
    let notch = (5.0 + 1.5 * (y - 100.0).abs()).min(30.0);
    ridge.min(notch.max(if (x - 100.0).abs() < 10.0 { 0.0 } else { 30.0 }))
}

/// A seeded generator of uniform numbers in [0, 1) (splitmix64): portable, so test cases do not change across
/// platforms.
pub fn splitmix(seed: u64) -> impl FnMut() -> f64 {
    let mut g = seed;
    move || {
        g = g.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = g;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A random TIN of `n` points over 500 m × 500 m: rolling hills plus `rough` × 15 m of noise; `None` when the points
/// do not triangulate.
pub fn random_tin(next: &mut impl FnMut() -> f64, n: usize, rough: f64) -> Option<Tin> {
    random_tin_at(next, n, rough, DVec3::ZERO)
}

/// [`random_tin`] moved by `offset` (the points are generated first, then moved, so the same draws give the same
/// terrain at another place).
pub fn random_tin_at(next: &mut impl FnMut() -> f64, n: usize, rough: f64, offset: DVec3) -> Option<Tin> {
    let pts: Vec<DVec3> = (0..n)
        .map(|_| {
            let (x, y) = (next() * 500.0, next() * 500.0);
            DVec3::new(x, y, 20.0 * (x / 60.0).sin() * (y / 80.0).cos() + rough * 15.0 * next()) + offset
        })
        .collect();
    triangulate(&pts, DedupePolicy::Reject).ok().map(|(tin, _)| tin)
}
