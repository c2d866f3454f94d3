//! The a/b-ordered covering-set sweep for one subsector (thesis 4.5.3, after Stewart's O(n log² n) horizon
//! algorithm).
//!
//! With `A(x) = cross(a, x)` and `B(x) = cross(b, x)` (`a`, `b` the wedge's boundary directions), a vertex `q ≠ p`
//! is in the closed wedge of `p` iff `A(q) ≥ A(p)` and `B(q) ≤ B(p)`: it lies on or left of the ray `a` and on or
//! right of the ray `b`. Both comparisons are exact ([`crate::predicates::LineKey`]).
//!
//! 1. Visit the vertices by decreasing `A`; on equal `A` by increasing `B`; then by index. When `p` is visited,
//!    the vertices visited before it are exactly those with `A(q) > A(p)`, or `A(q) = A(p)` and `B(q) < B(p)`,
//!    (or an identical position with a smaller index): together with `B(q) ≤ B(p)` these are exactly the wedge's
//!    members (ties on a boundary ray included, as the closed wedge demands).
//! 2. Leaf positions `0..n` hold the vertices by increasing `B` (ties by index). For `p`, `hi(p)` is the last
//!    position whose `B` equals `B(p)`, so `B(q) ≤ B(p)` ⇔ `pos(q) ≤ hi(p)`. Positions are grouped into buckets
//!    of `BUCKET` (8) consecutive positions, the leaves of a static complete binary tree (heap layout).
//! 3. A visited vertex `q` is marked in its bucket and inserted into the covering set (upper hull,
//!    [`crate::hull`]) of the right sibling of every left child on its bucket's leaf-to-root path. The thesis,
//!    with mirrored orders and single-vertex leaves, inserts into the left children. Here `p` scans the visited
//!    members of its query bucket `bucket(hi(p))` up to `hi(p)`, then queries every node on that bucket's path. A
//!    node on the path holds `q` iff it is the right child of the lowest common ancestor of the two buckets while
//!    `q` lies in its left child (`bucket(q) < bucket(hi(p))`): every candidate is seen exactly once, in the scan
//!    or in one covering set.
//! 4. Each node answers the leftmost steepest hull vertex seen from `p̂`; the best of those and of the scanned
//!    members by the candidate order ([`crate::candidate`]) is the horizon.
//!
//! Choices beyond the thesis, for speed (none changes the result; the tests run several bucket sizes, including
//! the thesis' single leaves, against the oracle):
//! - buckets of a few positions at the bottom of the tree replace its lowest levels by a scan of one cache line;
//! - every node counts the vertices still to be visited whose query path passes through it; insertions into a
//!   node that no one will query again are skipped (for narrow wedges the `A` and `B` orders nearly coincide, so
//!   whole subtrees are finished early);
//! - the sorts compare the f64 approximations of `A` and `B` and re-sort only runs of near-ties exactly;
//! - everything the main loop reads is laid out in visiting order.
//!
//! Degenerate input: a member `q` with `t_q ≤ t_p` (identical positions, or points closer than the rounding of
//! `t`) is no candidate by definition, and it would break the tangent search, which needs the apex left of every
//! hull point. A node's leftmost hull vertex has the smallest `t` of every point inserted into it, so the sweep
//! notices such a member on the query path and answers that vertex by the brute-force scan of
//! `oracle::best_in_wedge` instead. On valid TINs this never happens.
//!
//! Cost per subsector: two O(n log n) sorts, then for each vertex a scan of one bucket and O(log n) nodes with an
//! O(log h) tangent query or amortised O(log h) insertion each: O(n log² n) time; at most O(n log n) hull
//! vertices alive.

use std::cmp::Ordering;

use glam::{DVec2, DVec3};

use crate::NO_HORIZON;
use crate::candidate::{Candidate, CandidateId, keep_best};
use crate::hull::{HullRef, HullSet};
use crate::oracle::best_in_wedge;
use crate::predicates::LineKey;
use crate::sector::Wedge;

/// Leaves of the tree are buckets of this many consecutive leaf positions, scanned directly.
const BUCKET: usize = 8;

/// Computes, for every vertex, its horizon vertex in the subsector with wedge `wedge` (or [`NO_HORIZON`]), into
/// `out` (one entry per vertex). `origin` is the local origin of the projection ([`Wedge::project`]).
pub(crate) fn sweep_subsector(positions: &[DVec3], origin: DVec2, wedge: &Wedge, out: &mut [u32]) {
    sweep_with(positions, origin, wedge, out, BUCKET, HullSet::DEFAULT_SMALL_LIMIT);
}

/// [`sweep_subsector`] with a given bucket size and small-hull limit (tests vary both).
fn sweep_with(positions: &[DVec3], origin: DVec2, wedge: &Wedge, out: &mut [u32], bucket: usize, small_limit: usize) {
    let n = positions.len();
    debug_assert_eq!(out.len(), n);
    if n == 0 {
        return;
    }
    let xy = |v: u32| positions[v as usize].truncate();
    let ka: Vec<LineKey> = positions.iter().map(|p| LineKey::new(wedge.a, p.truncate())).collect();
    let kb: Vec<LineKey> = positions.iter().map(|p| LineKey::new(wedge.b, p.truncate())).collect();
    let t: Vec<f64> = positions.iter().map(|p| wedge.project(origin, p.truncate())).collect();
    let cmp_b = |x: u32, y: u32| kb[x as usize].cmp_exact(&kb[y as usize], wedge.b, xy(x), xy(y));
    let gap = |keys: &[LineKey]| LineKey::certain_gap(keys.iter().map(LineKey::magnitude).fold(0.0, f64::max));

    // Visiting order: A descending, then B ascending, then index.
    let order_a = sort_exact(
        n,
        |v| -ka[v as usize].value(),
        gap(&ka),
        |x, y| {
            ka[y as usize]
                .cmp_exact(&ka[x as usize], wedge.a, xy(y), xy(x))
                .then_with(|| cmp_b(x, y))
                .then(x.cmp(&y))
        },
    );
    // Leaves: B ascending, then index; hi = last leaf of each group of equal B.
    let order_b = sort_exact(
        n,
        |v| kb[v as usize].value(),
        gap(&kb),
        |x, y| cmp_b(x, y).then(x.cmp(&y)),
    );
    let mut leaf_of = vec![0u32; n];
    for (pos, &v) in order_b.iter().enumerate() {
        leaf_of[v as usize] = pos as u32;
    }
    let mut hi = vec![0u32; n];
    hi[n - 1] = (n - 1) as u32;
    for pos in (0..n - 1).rev() {
        hi[pos] = if cmp_b(order_b[pos], order_b[pos + 1]).is_eq() {
            hi[pos + 1]
        } else {
            pos as u32
        };
    }
    drop(order_b);

    // Everything the main loop reads, laid out in visiting order; the bucket members in leaf (B) order.
    let buckets = n.div_ceil(bucket);
    let tree_leaves = buckets.next_power_of_two();
    struct Visit {
        t: f64,
        z: f64,
        vertex: u32,
        /// Leaf position of the vertex.
        pos: u32,
        /// Last leaf position with the same B.
        hi: u32,
    }
    let visits: Vec<Visit> = order_a
        .iter()
        .map(|&v| {
            let pos = leaf_of[v as usize];
            Visit {
                t: t[v as usize],
                z: positions[v as usize].z,
                vertex: v,
                pos,
                hi: hi[pos as usize],
            }
        })
        .collect();
    #[derive(Clone, Copy)]
    struct Member {
        t: f64,
        z: f64,
        vertex: u32,
        visited: bool,
    }
    let mut members = vec![
        Member {
            t: 0.0,
            z: 0.0,
            vertex: 0,
            visited: false
        };
        n
    ];
    for visit in &visits {
        members[visit.pos as usize] = Member {
            t: visit.t,
            z: visit.z,
            vertex: visit.vertex,
            visited: false,
        };
    }
    drop((order_a, leaf_of, hi));
    let tree_leaf = |pos: u32| tree_leaves + pos as usize / bucket;

    // Per tree node: its covering set, and the number of vertices not yet visited whose query path contains the
    // node (a hull that no later vertex will query needs no insertions). Kept together for cache locality.
    #[derive(Clone, Copy)]
    struct Slot {
        hull: HullRef,
        pending: u32,
    }
    let mut slots = vec![
        Slot {
            hull: HullRef::EMPTY,
            pending: 0
        };
        2 * tree_leaves
    ];
    for visit in &visits {
        let mut node = tree_leaf(visit.hi);
        while node >= 1 {
            slots[node].pending += 1;
            node >>= 1;
        }
    }
    let mut hulls = HullSet::new(small_limit, 4 * n);
    for visit in &visits {
        let p = visit.vertex;
        let apex = DVec2::new(visit.t, visit.z);
        let mut best: Option<Candidate> = None;
        let mut degenerate = false;
        // Visited members of the query bucket up to hi.
        let first = visit.hi as usize / bucket * bucket;
        for m in &members[first..=visit.hi as usize] {
            if m.visited {
                if m.t <= apex.x {
                    degenerate = true;
                } else {
                    keep_best(&mut best, Candidate::vertex(m.t, m.z, m.vertex), apex);
                }
            }
        }
        // Covering sets on the path of the query bucket.
        let mut node = tree_leaf(visit.hi);
        loop {
            let slot = &mut slots[node];
            slot.pending -= 1;
            if !degenerate && !slot.hull.is_empty() {
                match hulls.min_t(&slot.hull) {
                    Some(min_t) if min_t <= apex.x => degenerate = true,
                    _ => {
                        if let Some(c) = hulls.tangent(&slot.hull, apex) {
                            keep_best(&mut best, c, apex);
                        }
                    }
                }
            }
            if node == 1 {
                break;
            }
            node >>= 1;
        }
        if degenerate {
            best = best_in_wedge(positions, wedge, p, &ka, &kb, &t);
        }
        out[p as usize] = match best {
            Some(Candidate {
                id: CandidateId::Vertex(q),
                ..
            }) => q,
            _ => NO_HORIZON,
        };

        // Mark p in its bucket and insert it into the right siblings of the left children on its bucket's path,
        // skipping nodes that no vertex still to be visited will query.
        members[visit.pos as usize].visited = true;
        let mut node = tree_leaf(visit.pos);
        while node > 1 {
            if node & 1 == 0 && slots[node + 1].pending > 0 {
                hulls.insert(&mut slots[node + 1].hull, apex.x, apex.y, p);
            }
            node >>= 1;
        }
    }
}

/// The vertices `0..n` sorted by `exact`, a total order that agrees with the approximate keys `approx` whenever
/// they differ by more than `gap`: sort by the approximations, then re-sort each run of approximations closer
/// than `gap` with the exact comparison.
fn sort_exact(n: usize, approx: impl Fn(u32) -> f64, gap: f64, exact: impl Fn(u32, u32) -> Ordering) -> Vec<u32> {
    let mut keyed: Vec<(f64, u32)> = (0..n as u32).map(|v| (approx(v), v)).collect();
    keyed.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut start = 0;
    while start < n {
        let mut end = start + 1;
        while end < n && keyed[end].0 - keyed[end - 1].0 <= gap {
            end += 1;
        }
        if end - start > 1 {
            keyed[start..end].sort_unstable_by(|a, b| exact(a.1, b.1));
        }
        start = end;
    }
    keyed.into_iter().map(|(_, v)| v).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::oracle::vertex_horizons;
    use crate::sector::{SectorConfig, SectorGeometry};
    use proptest::prelude::*;

    fn grid_or_random(n: usize, grid: bool, heights: &[i32]) -> Vec<DVec3> {
        (0..n)
            .map(|i| {
                let z = heights[i % heights.len()] as f64;
                if grid {
                    DVec3::new((i % 7) as f64, (i / 7) as f64, z)
                } else {
                    DVec3::new(
                        ((i * 7919) % 1013) as f64 * 0.37,
                        ((i * 104_729) % 997) as f64 * 0.41,
                        z,
                    )
                }
            })
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 150, ..ProptestConfig::default() })]

        /// Every bucket size (1 = the thesis' tree down to single leaves) and a tiny small-hull limit (treaps
        /// inside the sweep) give the oracle's answer.
        #[test]
        fn any_bucket_and_hull_limit_matches_the_oracle(n in 1usize..90, grid in any::<bool>(),
                                                        heights in prop::collection::vec(-2i32..3, 1..20),
                                                        bucket in 1usize..6, limit in 1usize..4, cfg in 0usize..3) {
            let positions = grid_or_random(n, grid, &heights);
            let (s, k) = [(4, 1), (8, 8), (5, 3)][cfg];
            let g = SectorGeometry::new(&SectorConfig::new(s, k).expect("valid"));
            let origin = DVec2::new(1.0, 2.0);
            let expect = vertex_horizons(&positions, origin, &g);
            for j in 0..g.total() {
                let mut out = vec![0; n];
                sweep_with(&positions, origin, &g.wedge(j), &mut out, bucket, limit);
                prop_assert_eq!(&out[..], &expect[j * n..(j + 1) * n], "subsector {}", j);
            }
        }
    }
}
