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
//! 2. Leaves of a static complete binary tree (heap layout, `L` = next power of two ≥ n leaves) hold the vertices
//!    by increasing `B` (ties by index). For `p`, `hi(p)` is the last leaf whose `B` equals `B(p)`, so
//!    `B(q) ≤ B(p)` ⇔ `leaf(q) ≤ hi(p)`.
//! 3. A visited vertex `q` is inserted into the covering set (upper hull, [`crate::hull`]) of its own leaf and of
//!    the right sibling of every left child on its leaf-to-root path. The thesis, with mirrored orders, inserts
//!    into the left children; here `p` then queries every node on the path of leaf `hi(p)`. A node on that path
//!    holds `q` iff it is `q`'s leaf (`leaf(q) = hi(p)`) or the right child of the lowest common ancestor of the
//!    two leaves while `q` lies in its left child (`leaf(q) < hi(p)`): every candidate is seen exactly once.
//! 4. Each node answers the leftmost steepest hull vertex seen from `p̂`; the best of those by the candidate order
//!    ([`crate::candidate`]) is the horizon.
//!
//! Degenerate input: a member `q` with `t_q ≤ t_p` (identical positions, or points closer than the rounding of
//! `t`) is no candidate by definition, and it would break the tangent search, which needs the apex left of every
//! hull point. A node's leftmost hull vertex has the smallest `t` of every point inserted into it, so the sweep
//! notices such a member on the query path and answers that vertex by the brute-force scan of
//! [`crate::oracle::best_in_wedge`] instead. On valid TINs this never happens.
//!
//! Cost per subsector: two O(n log n) sorts, then for each vertex O(log n) nodes with an O(log h) tangent query
//! or amortised O(log h) insertion each: O(n log² n) time; at most O(n log n) hull vertices alive.

use glam::{DVec2, DVec3};

use crate::NO_HORIZON;
use crate::candidate::{Candidate, CandidateId, keep_best};
use crate::hull::{Hull, HullArena};
use crate::oracle::best_in_wedge;
use crate::predicates::LineKey;
use crate::sector::Wedge;

/// Computes, for every vertex, its horizon vertex in the subsector with wedge `wedge` (or [`NO_HORIZON`]), into
/// `out` (one entry per vertex). `origin` is the local origin of the projection ([`Wedge::project`]).
pub(crate) fn sweep_subsector(positions: &[DVec3], origin: DVec2, wedge: &Wedge, out: &mut [u32]) {
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

    // Visiting order: A descending, then B ascending, then index.
    let mut order_a: Vec<u32> = (0..n as u32).collect();
    order_a.sort_unstable_by(|&x, &y| {
        ka[y as usize]
            .cmp_exact(&ka[x as usize], wedge.a, xy(y), xy(x))
            .then_with(|| cmp_b(x, y))
            .then(x.cmp(&y))
    });
    // Leaves: B ascending, then index; hi = last leaf of each group of equal B.
    let mut order_b: Vec<u32> = (0..n as u32).collect();
    order_b.sort_unstable_by(|&x, &y| cmp_b(x, y).then(x.cmp(&y)));
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

    let leaves = n.next_power_of_two();
    let mut hulls = vec![Hull::EMPTY; 2 * leaves];
    let mut arena = HullArena::with_capacity(2 * n);
    for &p in &order_a {
        let pu = p as usize;
        let apex = DVec2::new(t[pu], positions[pu].z);
        let mut best: Option<Candidate> = None;
        let mut degenerate = false;
        let mut node = leaves + hi[leaf_of[pu] as usize] as usize;
        loop {
            let hull = &hulls[node];
            if let Some(min_t) = arena.min_t(hull) {
                if min_t <= apex.x {
                    degenerate = true;
                    break;
                }
                if let Some(c) = arena.tangent(hull, apex) {
                    keep_best(&mut best, c, apex);
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
        out[pu] = match best {
            Some(Candidate {
                id: CandidateId::Vertex(q),
                ..
            }) => q,
            _ => NO_HORIZON,
        };

        // Insert p into its own leaf and into the right siblings of the left children on its path, skipping
        // siblings whose subtree holds no vertex.
        let mut node = leaves + leaf_of[pu] as usize;
        arena.insert(&mut hulls[node], apex.x, apex.y, p);
        let mut level = 0;
        while node > 1 {
            if node & 1 == 0 && ((node + 1) << level) - leaves < n {
                arena.insert(&mut hulls[node + 1], apex.x, apex.y, p);
            }
            node >>= 1;
            level += 1;
        }
    }
}
