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
//! - every node knows the last visit whose query path passes through it; insertions into a node that no one
//!   will query again are skipped (for narrow wedges the `A` and `B` orders nearly coincide, so
//!   whole subtrees are finished early);
//! - the sorts compare the f64 approximations of `A` and `B` and re-sort only runs of near-ties exactly;
//! - consecutive subsectors share a boundary direction (`b` of one is `a` of the next): a sweep hands its leaf
//!   order on, and the next derives its visiting order from it instead of sorting (`DirectionOrder`);
//! - everything the main loop reads is laid out in visiting order, and prefetched a few visits ahead;
//! - each node keeps bounds (smallest and largest `t`, largest `z`) of the points inserted into its covering set;
//!   a node whose bounding box is strictly less steep than the best candidate so far cannot hold the horizon
//!   and is not queried (an exact test, `cannot_beat`).
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
use tin::prefetch;

use crate::NO_HORIZON;
use crate::candidate::{Candidate, CandidateId, keep_best};
use crate::hull::{HullRef, HullSet};
use crate::oracle::best_in_wedge;
use crate::predicates::{LineKey, cmp_slope};
use crate::sector::Wedge;

/// Leaves of the tree are buckets of this many consecutive leaf positions, scanned directly.
const BUCKET: usize = 8;

/// The vertices sorted by their exact key across a boundary direction `e` (`cross(e, x)`, increasing; ties by
/// index): the leaf order of the subsector whose wedge has `b = e`, and, reversed with its runs of equal keys
/// re-sorted, the visiting order of the next subsector (`a = e`). Handing it on saves one of the two sorts of a
/// sweep.
pub(crate) struct DirectionOrder {
    direction: DVec2,
    order: Vec<u32>,
}

/// Computes, for every vertex, its horizon vertex in the subsector with wedge `wedge` (or [`NO_HORIZON`]), into
/// `out` (one entry per vertex). `origin` is the local origin of the projection ([`Wedge::project`]). `previous` is
/// what the sweep of the previous subsector returned, if it ran just before (used when its direction is this
/// wedge's `a`); the result is the same with or without it. `scratch` is working memory, kept from one sweep to the
/// next; the result does not depend on what it holds.
pub(crate) fn sweep_subsector(
    positions: &[DVec3],
    origin: DVec2,
    wedge: &Wedge,
    out: &mut [u32],
    previous: Option<DirectionOrder>,
    scratch: &mut Scratch,
) -> DirectionOrder {
    sweep_with(
        positions,
        origin,
        wedge,
        out,
        BUCKET,
        HullSet::DEFAULT_SMALL_LIMIT,
        previous,
        scratch,
    )
}

/// The working memory of a sweep, reused by the next one: a sweep of a million vertices fills some 250 MB, and
/// allocating it afresh every time made the system fault in and zero every page of it again (about 4% of a
/// million-vertex build's horizon time). Every buffer is cleared and refilled before it is read, so what a scratch
/// holds never changes a result.
#[derive(Default)]
pub(crate) struct Scratch {
    ka: Vec<LineKey>,
    kb: Vec<LineKey>,
    t: Vec<f64>,
    keyed: Vec<(f64, u32)>,
    /// A leaf or visiting order no longer in use, whose memory the next sort fills.
    spare: Vec<u32>,
    leaf_of: Vec<u32>,
    hi: Vec<u32>,
    visits: Vec<Visit>,
    members: Vec<Member>,
    visited: Vec<bool>,
    slots: Vec<Slot>,
    hulls: HullSet,
}

/// One visit of the main loop, laid out in visiting order: everything it reads of its vertex.
struct Visit {
    t: f64,
    z: f64,
    vertex: u32,
    /// Leaf position of the vertex.
    pos: u32,
    /// Last leaf position with the same B.
    hi: u32,
    /// First leaf position of the bucket of `hi`.
    first: u32,
    /// Tree nodes of the buckets of `hi` (query path) and `pos` (insertion path).
    query_leaf: u32,
    insert_leaf: u32,
}

/// The vertex at a leaf position, as a bucket scan reads it.
#[derive(Clone, Copy)]
struct Member {
    t: f64,
    z: f64,
    vertex: u32,
}

impl Member {
    const UNSET: Member = Member {
        t: 0.0,
        z: 0.0,
        vertex: 0,
    };
}

/// Per tree node: its covering set, the index of the last visit whose query path contains the node (a hull that no
/// later vertex will query needs no insertions), and bounds of every point inserted into the hull (its smallest `t`
/// answers the degeneracy check without touching the hull; with the largest `t` and `z` they bound the slope of
/// every hull vertex, see `cannot_beat`). Kept together for cache locality: 32 bytes, aligned, so one slot never
/// straddles two cache lines. The largest `t` is rounded up to f32 (only ever used as an upper bound).
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct Slot {
    hull: HullRef,
    last: u32,
    max_t: f32,
    min_t: f64,
    max_z: f64,
}

impl Slot {
    const EMPTY: Slot = Slot {
        hull: HullRef::EMPTY,
        last: 0,
        max_t: f32::NEG_INFINITY,
        min_t: f64::INFINITY,
        max_z: f64::NEG_INFINITY,
    };
}

/// Clears `v` and fills it with `n` copies of `value`, keeping its memory.
fn refill<T: Clone>(v: &mut Vec<T>, n: usize, value: T) {
    v.clear();
    v.resize(n, value);
}

/// [`sweep_subsector`] with a given bucket size and small-hull limit (tests vary both).
#[allow(clippy::too_many_arguments)]
fn sweep_with(
    positions: &[DVec3],
    origin: DVec2,
    wedge: &Wedge,
    out: &mut [u32],
    bucket: usize,
    small_limit: usize,
    previous: Option<DirectionOrder>,
    scratch: &mut Scratch,
) -> DirectionOrder {
    let n = positions.len();
    debug_assert_eq!(out.len(), n);
    if n == 0 {
        return DirectionOrder {
            direction: wedge.b,
            order: Vec::new(),
        };
    }
    let xy = |v: u32| positions[v as usize].truncate();
    let Scratch {
        ka,
        kb,
        t,
        keyed,
        spare,
        leaf_of,
        hi,
        visits,
        members,
        visited,
        slots,
        hulls,
    } = scratch;
    ka.clear();
    ka.extend(positions.iter().map(|p| LineKey::new(wedge.a, p.truncate())));
    kb.clear();
    kb.extend(positions.iter().map(|p| LineKey::new(wedge.b, p.truncate())));
    t.clear();
    t.extend(positions.iter().map(|p| wedge.project(origin, p.truncate())));
    let (ka, kb, t) = (&ka[..], &kb[..], &t[..]);
    let cmp_b = |x: u32, y: u32| kb[x as usize].cmp_exact(&kb[y as usize], wedge.b, xy(x), xy(y));
    let gap = |keys: &[LineKey]| LineKey::certain_gap(keys.iter().map(LineKey::magnitude).fold(0.0, f64::max));

    // Visiting order: A descending, then B ascending, then index. From the previous subsector's leaf order (A
    // ascending, then index) when there is one: reversed, with each run of equal A re-sorted by B and index. Both
    // are sorted by the same total order, hence identical.
    let same_direction = |d: DVec2| d.to_array().map(f64::to_bits) == wedge.a.to_array().map(f64::to_bits);
    let order_a = match previous {
        Some(DirectionOrder { direction, mut order }) if same_direction(direction) && order.len() == n => {
            order.reverse();
            let mut start = 0;
            while start < n {
                let (first, mut end) = (order[start], start + 1);
                while end < n
                    && ka[order[end] as usize]
                        .cmp_exact(&ka[first as usize], wedge.a, xy(order[end]), xy(first))
                        .is_eq()
                {
                    end += 1;
                }
                if end - start > 1 {
                    order[start..end].sort_unstable_by(|&x, &y| cmp_b(x, y).then(x.cmp(&y)));
                }
                start = end;
            }
            order
        }
        _ => {
            let mut order = std::mem::take(spare);
            sort_exact(
                n,
                |v| -ka[v as usize].value(),
                gap(ka),
                |x, y| {
                    ka[y as usize]
                        .cmp_exact(&ka[x as usize], wedge.a, xy(y), xy(x))
                        .then_with(|| cmp_b(x, y))
                        .then(x.cmp(&y))
                },
                keyed,
                &mut order,
            );
            order
        }
    };
    // Leaves: B ascending, then index; hi = last leaf of each group of equal B.
    let mut order_b = std::mem::take(spare);
    sort_exact(
        n,
        |v| kb[v as usize].value(),
        gap(kb),
        |x, y| cmp_b(x, y).then(x.cmp(&y)),
        keyed,
        &mut order_b,
    );
    refill(leaf_of, n, 0);
    for (pos, &v) in order_b.iter().enumerate() {
        leaf_of[v as usize] = pos as u32;
    }
    refill(hi, n, 0);
    hi[n - 1] = (n - 1) as u32;
    for pos in (0..n - 1).rev() {
        hi[pos] = if cmp_b(order_b[pos], order_b[pos + 1]).is_eq() {
            hi[pos + 1]
        } else {
            pos as u32
        };
    }

    // Everything the main loop reads, laid out in visiting order; the bucket members in leaf (B) order.
    let buckets = n.div_ceil(bucket);
    let tree_leaves = buckets.next_power_of_two();
    let tree_leaf = |pos: u32| (tree_leaves + pos as usize / bucket) as u32;
    visits.clear();
    visits.extend(order_a.iter().map(|&v| {
        let pos = leaf_of[v as usize];
        let hi = hi[pos as usize];
        Visit {
            t: t[v as usize],
            z: positions[v as usize].z,
            vertex: v,
            pos,
            hi,
            first: (hi as usize / bucket * bucket) as u32,
            query_leaf: tree_leaf(hi),
            insert_leaf: tree_leaf(pos),
        }
    }));
    refill(members, n, Member::UNSET);
    for visit in visits.iter() {
        members[visit.pos as usize] = Member {
            t: visit.t,
            z: visit.z,
            vertex: visit.vertex,
        };
    }
    // Whether the member at each leaf position has been visited: one byte per position, apart from the members,
    // so that the scan of a bucket touches the members only where it needs them.
    refill(visited, n, false);
    *spare = order_a;

    refill(slots, 2 * tree_leaves, Slot::EMPTY);
    for (i, visit) in visits.iter().enumerate() {
        let mut node = visit.query_leaf as usize;
        while node >= 1 {
            slots[node].last = i as u32;
            node >>= 1;
        }
    }
    hulls.clear(small_limit, 4 * n);
    for (i, visit) in visits.iter().enumerate() {
        // The main loop is bound by memory latency: fetch what later visits will read (their bucket, the bottom
        // of their query path, and the hulls there) ahead of time. No effect on the result.
        if let Some(ahead) = visits.get(i + PREFETCH_AHEAD) {
            prefetch(&visited[ahead.first as usize]);
            prefetch(&members[ahead.first as usize]);
            prefetch(&out[ahead.vertex as usize]);
            let (query, insert) = (ahead.query_leaf as usize, ahead.insert_leaf as usize);
            for level in 0..PREFETCH_LEVELS {
                prefetch(&slots[query >> level]);
                prefetch(&slots[(insert >> level) | 1]);
            }
        }
        if let Some(ahead) = visits.get(i + PREFETCH_AHEAD / 2) {
            // The hulls it will query, and those it will insert into (right siblings on the path of its own leaf).
            let (query, insert) = (ahead.query_leaf as usize, ahead.insert_leaf as usize);
            for level in 0..PREFETCH_LEVELS {
                hulls.prefetch(&slots[query >> level].hull);
                hulls.prefetch(&slots[(insert >> level) | 1].hull);
            }
        }
        let p = visit.vertex;
        let apex = DVec2::new(visit.t, visit.z);
        let mut best: Option<Candidate> = None;
        let mut degenerate = false;
        // Visited members of the query bucket up to hi.
        let first = visit.first as usize;
        for (m, &seen) in members[first..=visit.hi as usize]
            .iter()
            .zip(&visited[first..=visit.hi as usize])
        {
            if seen {
                if m.t <= apex.x {
                    degenerate = true;
                } else {
                    keep_best(&mut best, Candidate::vertex(m.t, m.z, m.vertex), apex);
                }
            }
        }
        // Covering sets on the path of the query bucket.
        let mut node = visit.query_leaf as usize;
        loop {
            let slot = &slots[node];
            if !degenerate && !slot.hull.is_empty() {
                if slot.min_t <= apex.x {
                    degenerate = true;
                } else if !best
                    .is_some_and(|b| cannot_beat(apex, slot.min_t, f64::from(slot.max_t), slot.max_z, b.point))
                    && let Some(c) = hulls.tangent(&slot.hull, apex)
                {
                    keep_best(&mut best, c, apex);
                }
            }
            if node == 1 {
                break;
            }
            node >>= 1;
        }
        if degenerate {
            best = best_in_wedge(positions, wedge, p, ka, kb, t);
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
        visited[visit.pos as usize] = true;
        let mut node = visit.insert_leaf as usize;
        while node > 1 {
            if node & 1 == 0 && slots[node + 1].last > i as u32 {
                let slot = &mut slots[node + 1];
                hulls.insert(&mut slot.hull, apex.x, apex.y, p);
                slot.min_t = slot.min_t.min(apex.x);
                slot.max_t = slot.max_t.max(f32_at_least(apex.x));
                slot.max_z = slot.max_z.max(apex.y);
            }
            node >>= 1;
        }
    }
    DirectionOrder {
        direction: wedge.b,
        order: order_b,
    }
}

/// How many visits ahead the main loop prefetches.
const PREFETCH_AHEAD: usize = 16;

/// How many levels of a later visit's paths (from the bottom) the main loop prefetches; the levels above are few
/// nodes, which stay in cache.
const PREFETCH_LEVELS: usize = 6;

/// The smallest f32 not below `x` (infinite beyond the f32 range).
#[inline]
fn f32_at_least(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) < x { y.next_up() } else { y }
}

/// Whether no point in the box `t ∈ [min_t, max_t]`, `z ≤ max_z` (`min_t` strictly right of `apex`; `max_t` may
/// exceed the largest `t`) can be a better
/// horizon than the candidate at `best`: true when the box's steepest corner is strictly less steep than `best`.
/// Exact. The steepest corner is `(min_t, max_z)` when `max_z ≥ z_p` (every point of the box with `z ≥ z_p` rises
/// at most as steeply, the others fall); otherwise every point falls, at least as steeply as `(max_t, max_z)`. A
/// strictly less steep point never wins, whatever the tie-breaks ([`crate::candidate`]).
#[inline]
fn cannot_beat(apex: DVec2, min_t: f64, max_t: f64, max_z: f64, best: DVec2) -> bool {
    let corner = if max_z >= apex.y {
        DVec2::new(min_t, max_z)
    } else {
        DVec2::new(max_t, max_z)
    };
    cmp_slope(apex, corner, best) == Ordering::Less
}

/// Writes into `out` the vertices `0..n` sorted by `exact`, a total order that agrees with the approximate keys
/// `approx` whenever they differ by more than `gap`: sort by the approximations, then re-sort each run of
/// approximations closer than `gap` with the exact comparison. `keyed` is working memory.
fn sort_exact(
    n: usize,
    approx: impl Fn(u32) -> f64,
    gap: f64,
    exact: impl Fn(u32, u32) -> Ordering,
    keyed: &mut Vec<(f64, u32)>,
    out: &mut Vec<u32>,
) {
    keyed.clear();
    keyed.extend((0..n as u32).map(|v| (approx(v), v)));
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
    out.clear();
    out.extend(keyed.iter().map(|&(_, v)| v));
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
        #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

        /// Whenever `cannot_beat` prunes a box, every point in it is strictly less steep than the best candidate
        /// (with the largest `t` rounded up as the sweep stores it).
        #[test]
        fn cannot_beat_is_a_sound_bound(points in prop::collection::vec((1i32..40, -10i32..10), 1..20),
                                        apex_z in -10i32..10, best in (1i32..40, -10i32..10)) {
            let apex = DVec2::new(0.3, apex_z as f64 / 3.0);
            let pts: Vec<DVec2> = points.iter().map(|&(t, z)| DVec2::new(t as f64 / 7.0 + 0.3, z as f64 / 3.0)).collect();
            let min_t = pts.iter().map(|p| p.x).fold(f64::INFINITY, f64::min);
            let max_t = pts.iter().map(|p| p.x).fold(f64::NEG_INFINITY, f64::max);
            let max_z = pts.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max);
            let best = DVec2::new(best.0 as f64 / 7.0 + 0.3, best.1 as f64 / 3.0);
            if cannot_beat(apex, min_t, f64::from(f32_at_least(max_t)), max_z, best) {
                for p in &pts {
                    prop_assert_eq!(cmp_slope(apex, *p, best), Ordering::Less, "{} beats {}", p, best);
                }
            }
        }
    }

    #[test]
    fn f32_at_least_rounds_up() {
        for x in [0.1, 1.0 / 3.0, 5_000_000.123, -2.7, 0.0, 1e30] {
            assert!(f64::from(f32_at_least(x)) >= x, "{x}");
        }
        assert_eq!(f32_at_least(0.5), 0.5);
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 150, ..ProptestConfig::default() })]

        /// Every bucket size (1 = the thesis' tree down to single leaves) and a tiny small-hull limit (treaps
        /// inside the sweep) give the oracle's answer, with a fresh scratch and with one used before.
        #[test]
        fn any_bucket_and_hull_limit_matches_the_oracle(n in 1usize..90, grid in any::<bool>(),
                                                        heights in prop::collection::vec(-2i32..3, 1..20),
                                                        bucket in 1usize..6, limit in 1usize..4, cfg in 0usize..3) {
            let positions = grid_or_random(n, grid, &heights);
            let (s, k) = [(4, 1), (8, 8), (5, 3)][cfg];
            let g = SectorGeometry::new(&SectorConfig::new(s, k).expect("valid"));
            let origin = DVec2::new(1.0, 2.0);
            let expect = vertex_horizons(&positions, origin, &g);
            // One scratch kept through every sweep, as a run of subsectors keeps it, begun by a sweep of another
            // mesh that leaves it holding more than this one needs.
            let mut kept = Scratch::default();
            let other = grid_or_random(2 * n + 7, !grid, &[3, -1, 4, 1, -5]);
            sweep_with(&other, origin, &g.wedge(0), &mut vec![0; other.len()], bucket, limit + 1, None, &mut kept);
            let mut previous = None;
            for j in 0..g.total() {
                let mut out = vec![0; n];
                sweep_with(&positions, origin, &g.wedge(j), &mut out, bucket, limit, None, &mut Scratch::default());
                prop_assert_eq!(&out[..], &expect[j * n..(j + 1) * n], "subsector {}", j);
                // Handing on the previous subsector's leaf order, with the kept scratch, gives the same.
                let mut out = vec![0; n];
                previous = Some(sweep_with(&positions, origin, &g.wedge(j), &mut out, bucket, limit, previous, &mut kept));
                prop_assert_eq!(&out[..], &expect[j * n..(j + 1) * n], "subsector {} after {}", j, j.max(1) - 1);
            }
        }
    }
}
