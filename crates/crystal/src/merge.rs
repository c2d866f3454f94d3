//! The merge hierarchy over crystal groups (thesis 5.2.3, last part; the README's "What it does").
//!
//! Leaves are the groups. Level by level, each node still in play finds the partner it collided with most and, when
//! both are still free at this level, the two merge into a parent whose collision record is the sum of theirs without
//! their mutual collisions and whose occlusion region, per sector, is the intersection of theirs. A node with no
//! collisions left is top-level. The collision graph is a [`petgraph::graphmap::UnGraphMap`] whose edge weights are
//! the counts.
//!
//! Choices made where the thesis is vague:
//! - **Order and ties**: at each level nodes are visited in increasing id (leaves first, then parents in creation
//!   order); the most-collided partner is the one with the largest count, ties to the smaller id. A node whose best
//!   partner is already taken at this level waits for the next level, where the taken partner is replaced by its
//!   parent; it does not fall back to a less-collided partner.
//! - **Circles**: a node's circumscribed circle encloses all vertices of its triangles. It is Ritter's circle
//!   ([`tin::bounding_circle_of_points`], grown to be exact) of the convex hull of those vertices; a parent's hull is
//!   the hull of its children's hulls, so a merge costs the hulls' size, not the node's.
//! - **Expanse limit**: when the parent's circle's area `π r²` would exceed
//!   `max_expanse × terrain area` (the sum of all triangles' areas in x,y), the merge is not made: the pair's edge is
//!   removed from the collision graph (their mutual collisions are forgotten, so neither tries the other again, and
//!   their future parents inherit nothing of that pair), and the node tries its next partner at the same level. A node
//!   left without partners becomes top-level at the start of the next level.
//! - **Records between levels**: merges are decided on the records as they stood at the start of the level. After the
//!   level every edge is redirected to the new parents and counts are summed; edges inside a parent vanish.
//! - **Stop**: when a level makes no merge and removes no edge, every node still in play becomes top-level. (At every
//!   level the first node with a partner either merges or loses an edge, so this only happens once no edges remain.)
//! - **Levels**: leaves are level 0, a parent is one more than the higher of its two children. Roots are listed in
//!   increasing id.
//! - **Group regions** ([`group_regions`]) are the intersection of the group's triangles' regions. A triangle's region
//!   is the intersection of its three vertices' regions, so that is the intersection of the regions of the group's
//!   distinct vertices, computed from the vertex table as a lower envelope of lines (see there) without any
//!   per-triangle table; parents intersect their two children's regions with [`Region::intersect`].

use std::f64::consts::PI;
use std::ops::Range;

use glam::DVec2;
use occlusion::{Region, RegionTable};
use petgraph::graphmap::UnGraphMap;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use tin::{Circle, Tin, bounding_circle_of_points};

use crate::growth::best_partner;

/// One node of the hierarchy: a leaf (one group) or the merge of two nodes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Node {
    /// Child node ids (empty for a leaf, two for a parent), smaller id first.
    pub children: Vec<u32>,
    /// The parent node, `None` for a top-level node.
    pub parent: Option<u32>,
    /// 0 for leaves; a parent is one more than its higher child.
    pub level: u32,
    /// A circle in x,y enclosing every vertex of the node's triangles.
    pub circle: Circle,
    /// The node's triangles: positions `range` of [`crate::Crystal::order`].
    pub range: Range<u32>,
    /// The node's occlusion region in each sector (`None`: never hidden there): for a leaf the intersection of its
    /// triangles' regions (equivalently of its vertices'), for a parent the intersection of its children's. Plane
    /// coordinates are those of the vertex region table ([`crate::Crystal::region_origin`]).
    pub regions: Vec<Option<Region>>,
    /// The collision record when the node was made: `(partner node, count)`, by partner id. Partners are the nodes in
    /// play at that time (for a leaf, other leaves).
    pub collisions: Vec<(u32, u64)>,
}

impl Node {
    /// Whether the node is a leaf (a group).
    pub fn is_leaf(&self) -> bool {
        self.children.is_empty()
    }
}

/// The forest of merges over the groups.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Hierarchy {
    /// All nodes: leaves `0..groups` (node `g` is group `g`), then parents in creation order (a parent's id is larger
    /// than its children's).
    pub nodes: Vec<Node>,
    /// Top-level nodes, in increasing id.
    pub roots: Vec<u32>,
}

impl Hierarchy {
    /// Number of levels (highest level + 1); 0 without nodes.
    pub fn levels(&self) -> u32 {
        self.nodes.iter().map(|n| n.level + 1).max().unwrap_or(0)
    }

    /// The hierarchy as a petgraph forest with an edge from each parent to each child (node index = node id).
    pub fn forest(&self) -> petgraph::graph::DiGraph<u32, ()> {
        let mut g = petgraph::graph::DiGraph::with_capacity(self.nodes.len(), self.nodes.len());
        for id in 0..self.nodes.len() as u32 {
            g.add_node(id);
        }
        for (id, node) in self.nodes.iter().enumerate() {
            for &c in &node.children {
                g.add_edge((id as u32).into(), c.into(), ());
            }
        }
        g
    }
}

/// The convex hull of `points` (counter-clockwise, Andrew's monotone chain), kept on the safe side of rounding: a point
/// is dropped only when it lies clearly inside (a right turn larger than `1e-9 × |a−o| × |b−o|`), so every input point
/// is inside the hull polygon and hence inside any circle that encloses the hull's vertices.
pub(crate) fn hull_of(mut points: Vec<DVec2>) -> Vec<DVec2> {
    points.sort_unstable_by(|p, q| p.x.total_cmp(&q.x).then(p.y.total_cmp(&q.y)));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    // Whether `a` lies clearly to the right of `o → b`, i.e. inside a counter-clockwise chain.
    let inside = |o: DVec2, a: DVec2, b: DVec2| {
        let (u, v) = (a - o, b - o);
        u.perp_dot(v) < -1e-9 * u.length() * v.length()
    };
    let chain = |iter: &mut dyn Iterator<Item = DVec2>| {
        let mut h: Vec<DVec2> = Vec::new();
        for p in iter {
            while h.len() >= 2 && inside(h[h.len() - 2], h[h.len() - 1], p) {
                h.pop();
            }
            h.push(p);
        }
        h.pop(); // The other chain starts with it.
        h
    };
    let mut hull = chain(&mut points.iter().copied());
    hull.extend(chain(&mut points.iter().rev().copied()));
    hull
}

/// The circle enclosing a hull's points (a zero circle for none).
fn circle_of_hull(hull: &[DVec2]) -> Circle {
    bounding_circle_of_points(hull).unwrap_or(Circle {
        centre: DVec2::ZERO,
        radius: 0.0,
    })
}

/// The distinct vertices of each group of triangles, in increasing index.
pub(crate) fn group_vertices(tin: &Tin, groups: &[Vec<u32>]) -> Vec<Vec<u32>> {
    let tris = tin.triangles();
    groups
        .par_iter()
        .map(|members| {
            let mut vertices: Vec<u32> = members.iter().flat_map(|&t| tris[t as usize]).collect();
            vertices.sort_unstable();
            vertices.dedup();
            vertices
        })
        .collect()
}

/// Per-sector intersection of two nodes' regions.
pub(crate) fn intersect_regions(a: &[Option<Region>], b: &[Option<Region>]) -> Vec<Option<Region>> {
    a.iter()
        .zip(b)
        .map(|(x, y)| match (x, y) {
            (Some(x), Some(y)) => Some(x.intersect(y)),
            _ => None,
        })
        .collect()
}

/// The regions of each group of triangles of `tin`: per sector, the intersection of its triangles' regions (empty
/// when any triangle's is), computed from `vertex_regions` (one row per vertex of `tin`).
///
/// A triangle's region is the intersection of its three vertices' regions, so a group's is the intersection of the
/// regions of its distinct vertices (about half as many as its triangles, and each a single wedge): no per-triangle
/// table is needed. A region's upper boundary is concave (it is the lower envelope of its vertices' horizon lines),
/// so it is the minimum of the lines through its chain segments and its tail. The intersection of many regions is
/// then the lower envelope of all their lines to the right of the largest left bound, built in `O(L log L)` for `L`
/// lines with the classic convex-hull sweep, instead of `O(m × chain length)` for a running intersection of `m`
/// regions. It is the same region as [`occlusion::intersect_all`] over the members' triangle regions, up to rounding
/// in the crossing points. A vertex region whose chain is not concave (possible for hand-made tables) makes the sector
/// fall back to pairwise intersection in a balanced tree.
pub fn group_regions(tin: &Tin, vertex_regions: &RegionTable, groups: &[Vec<u32>]) -> Vec<Vec<Option<Region>>> {
    vertex_set_regions(vertex_regions, &group_vertices(tin, groups))
}

/// Per vertex set and sector, the intersection of the sets' vertices' regions (see [`group_regions`]).
pub(crate) fn vertex_set_regions(vertex_regions: &RegionTable, sets: &[Vec<u32>]) -> Vec<Vec<Option<Region>>> {
    let sectors = vertex_regions.sectors();
    sets.par_iter()
        .map_init(
            || (Vec::new(), Vec::new()),
            |(regions, lines), vertices| {
                (0..sectors)
                    .map(|s| {
                        regions.clear();
                        for &v in vertices.iter() {
                            regions.push(vertex_regions.get(v, s)?);
                        }
                        envelope(regions, lines).or_else(|| intersect_balanced(regions))
                    })
                    .collect()
            },
        )
        .collect()
}

/// A line `z = a + m·s` with `s = t − T0` measured from the group's left bound `T0`.
#[derive(Clone, Copy, Debug)]
struct Line {
    m: f64,
    a: f64,
}

/// The intersection of concave regions as the lower envelope of their lines; `None` for no regions or when a chain is
/// not concave. `lines` is scratch space.
fn envelope(regions: &[&Region], lines: &mut Vec<Line>) -> Option<Region> {
    let t0 = regions.iter().map(|r| r.t0()).reduce(f64::max)?;
    lines.clear();
    for r in regions {
        let pts = r.points();
        let mut previous = f64::INFINITY;
        for (k, p) in pts.iter().enumerate() {
            let m = match pts.get(k + 1) {
                Some(q) => (q.y - p.y) / (q.x - p.x),
                None => r.tail_slope(),
            };
            if m > previous + 1e-9 * previous.abs().max(m.abs()).max(1.0) {
                return None; // Not concave.
            }
            previous = m;
            // Segments that end at or before T0 cannot bound the intersection.
            if pts.get(k + 1).is_some_and(|q| q.x <= t0) {
                continue;
            }
            lines.push(Line {
                m,
                a: p.y + m * (t0 - p.x),
            });
        }
    }
    prune(lines);
    // Decreasing slope, ties by increasing value at T0 (only the lowest of parallel lines matters).
    lines.sort_unstable_by(|x, y| y.m.total_cmp(&x.m).then(x.a.total_cmp(&y.a)));
    lines.dedup_by(|later, kept| later.m == kept.m);
    // Lower envelope over all s: with decreasing slopes, lines take over from left to right. `b` is dropped when the
    // crossing of `a` and `c` is not to the right of the crossing of `a` and `b`.
    let mut hull: Vec<Line> = Vec::with_capacity(lines.len());
    for &c in lines.iter() {
        while hull.len() >= 2 {
            let (a, b) = (hull[hull.len() - 2], hull[hull.len() - 1]);
            if (c.a - a.a) * (a.m - b.m) <= (b.a - a.a) * (a.m - c.m) {
                hull.pop();
            } else {
                break;
            }
        }
        hull.push(c);
    }
    // Walk the envelope from s = 0.
    let cross = |x: Line, y: Line| (y.a - x.a) / (x.m - y.m);
    let mut i = 0;
    while i + 1 < hull.len() && cross(hull[i], hull[i + 1]) <= 0.0 {
        i += 1;
    }
    let mut points = vec![DVec2::new(t0, hull[i].a)];
    while i + 1 < hull.len() {
        let s = cross(hull[i], hull[i + 1]);
        let t = t0 + s;
        if t > points.last().map_or(t0, |p| p.x) {
            let z = (hull[i].a + hull[i].m * s).min(hull[i + 1].a + hull[i + 1].m * s);
            points.push(DVec2::new(t, z));
        }
        i += 1;
    }
    Region::from_chain(points, hull[i].m)
}

/// Drops lines that lie above the lower envelope for every `s ≥ 0`, in linear time, so that only the few lines near
/// the envelope are sorted.
///
/// Let `low` be the line lowest at `s = 0` and `flat` the one of smallest slope; the envelope runs from `low` to
/// `flat`, and `min(low, flat)` is concave with one kink, at their crossing `s* ≥ 0`. A line `ℓ` that reaches the
/// envelope somewhere reaches `min(low, flat)` there, and `min(low, flat) − ℓ` is concave, at most 0 at `s = 0`
/// (unless `ℓ` ties `low` there) and non-increasing beyond `s*`: its maximum is at `s*`. So `ℓ` is kept when it ties
/// `low` at `s = 0` or is not above `min(low, flat)` at `s*`, with a small tolerance that only ever keeps more lines
/// (extra lines are removed by the hull sweep).
fn prune(lines: &mut Vec<Line>) {
    let by_value = |x: &&Line, y: &&Line| x.a.total_cmp(&y.a).then(x.m.total_cmp(&y.m));
    let by_slope = |x: &&Line, y: &&Line| x.m.total_cmp(&y.m).then(x.a.total_cmp(&y.a));
    let (Some(&low), Some(&flat)) = (lines.iter().min_by(by_value), lines.iter().min_by(by_slope)) else {
        return;
    };
    let kink = if low.m > flat.m {
        ((flat.a - low.a) / (low.m - flat.m)).max(0.0)
    } else {
        0.0
    };
    let floor = (low.a + low.m * kink).min(flat.a + flat.m * kink);
    if !(kink.is_finite() && floor.is_finite()) {
        return;
    }
    lines.retain(|l| {
        let v = l.a + l.m * kink;
        l.a <= low.a || v <= floor + 1e-9 * (1.0 + floor.abs() + (l.m * kink).abs())
    });
}

/// Intersects regions pairwise in a balanced tree; `None` for no regions.
fn intersect_balanced(regions: &[&Region]) -> Option<Region> {
    let mut level: Vec<Region> = regions
        .chunks(2)
        .map(|c| match c {
            [a, b] => a.intersect(b),
            _ => c[0].clone(),
        })
        .collect();
    while level.len() > 1 {
        let mut next = Vec::with_capacity(level.len().div_ceil(2));
        let mut it = level.into_iter();
        while let Some(a) = it.next() {
            next.push(match it.next() {
                Some(b) => a.intersect(&b),
                None => a,
            });
        }
        level = next;
    }
    level.pop()
}

/// What building the hierarchy did, besides the hierarchy itself.
pub(crate) struct MergeReport {
    /// Merges refused by the expanse limit.
    pub expanse_rejections: usize,
}

/// Builds the hierarchy over the groups, given by their distinct vertices (see the module documentation). Node ranges
/// are left empty; see [`crate::order`].
pub(crate) fn build_hierarchy(
    tin: &Tin,
    group_vertices: &[Vec<u32>],
    group_regions: Vec<Vec<Option<Region>>>,
    collisions: &[(u32, u32, u64)],
    max_expanse: f64,
    terrain_area: f64,
) -> (Hierarchy, MergeReport) {
    let count = group_vertices.len();
    let limit = max_expanse * terrain_area;
    // The convex hull of each node's vertices: a parent's circle is computed from its children's hulls.
    let pos = tin.positions();
    let mut hulls: Vec<Vec<DVec2>> = group_vertices
        .par_iter()
        .map(|vs| hull_of(vs.iter().map(|&v| pos[v as usize].truncate()).collect()))
        .collect();
    let mut graph: UnGraphMap<u32, u64> = UnGraphMap::with_capacity(count, collisions.len());
    for g in 0..count as u32 {
        graph.add_node(g);
    }
    for &(a, b, w) in collisions {
        graph.add_edge(a, b, w);
    }
    let mut nodes: Vec<Node> = group_regions
        .into_iter()
        .enumerate()
        .map(|(g, regions)| Node {
            children: Vec::new(),
            parent: None,
            level: 0,
            circle: circle_of_hull(&hulls[g]),
            range: 0..0,
            regions,
            collisions: record(&graph, g as u32),
        })
        .collect();
    let mut active: Vec<u32> = (0..count as u32).collect();
    let mut roots = Vec::new();
    let mut expanse_rejections = 0;
    loop {
        active.retain(|&g| {
            let done = graph.neighbors(g).next().is_none();
            if done {
                roots.push(g);
                graph.remove_node(g);
            }
            !done
        });
        if active.is_empty() {
            break;
        }
        let mut taken = vec![false; nodes.len()];
        let mut merges: Vec<(u32, u32, Circle, Vec<DVec2>)> = Vec::new();
        let mut rejected_here = 0;
        for &g in &active {
            if taken[g as usize] {
                continue;
            }
            while let Some(p) = best_partner(&graph, g, |_| true) {
                if taken[p as usize] {
                    break;
                }
                let hull = hull_of([&hulls[g as usize][..], &hulls[p as usize][..]].concat());
                let circle = circle_of_hull(&hull);
                if PI * circle.radius * circle.radius > limit {
                    graph.remove_edge(g, p);
                    rejected_here += 1;
                    continue;
                }
                taken[g as usize] = true;
                taken[p as usize] = true;
                merges.push((g.min(p), g.max(p), circle, hull));
                break;
            }
        }
        expanse_rejections += rejected_here;
        if merges.is_empty() {
            if rejected_here == 0 {
                roots.append(&mut active);
                break;
            }
            continue;
        }
        // Make the parents.
        let regions: Vec<Vec<Option<Region>>> = merges
            .par_iter()
            .map(|&(a, b, _, _)| intersect_regions(&nodes[a as usize].regions, &nodes[b as usize].regions))
            .collect();
        let mut map: Vec<u32> = (0..nodes.len() as u32).collect();
        let mut parents = Vec::with_capacity(merges.len());
        for ((a, b, circle, hull), regions) in merges.into_iter().zip(regions) {
            let id = nodes.len() as u32;
            map[a as usize] = id;
            map[b as usize] = id;
            nodes[a as usize].parent = Some(id);
            nodes[b as usize].parent = Some(id);
            let level = nodes[a as usize].level.max(nodes[b as usize].level) + 1;
            nodes.push(Node {
                children: vec![a, b],
                parent: None,
                level,
                circle,
                range: 0..0,
                regions,
                collisions: Vec::new(),
            });
            hulls.push(hull);
            parents.push(id);
        }
        // Redirect the collision graph to the parents.
        let carried: Vec<u32> = active.iter().copied().filter(|&g| !taken[g as usize]).collect();
        let mut next: UnGraphMap<u32, u64> =
            UnGraphMap::with_capacity(carried.len() + parents.len(), graph.edge_count());
        for &g in carried.iter().chain(&parents) {
            next.add_node(g);
        }
        for (a, b, &w) in graph.all_edges() {
            let (a, b) = (map[a as usize], map[b as usize]);
            if a == b {
                continue;
            }
            match next.edge_weight_mut(a, b) {
                Some(e) => *e += w,
                None => {
                    next.add_edge(a, b, w);
                }
            }
        }
        graph = next;
        for &p in &parents {
            nodes[p as usize].collisions = record(&graph, p);
        }
        active = carried;
        active.extend(parents);
    }
    roots.sort_unstable();
    (Hierarchy { nodes, roots }, MergeReport { expanse_rejections })
}

/// A node's collision record from the graph, by partner id.
fn record(graph: &UnGraphMap<u32, u64>, g: u32) -> Vec<(u32, u64)> {
    let mut r: Vec<(u32, u64)> = graph.edges(g).map(|(_, x, &w)| (x, w)).collect();
    r.sort_unstable();
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use proptest::prelude::*;

    /// Upper boundaries within rounding at the chain vertices of both, between them and beyond; equal left bounds.
    fn close(a: &Region, b: &Region) -> bool {
        let mut ts: Vec<f64> = a.points().iter().chain(b.points()).map(|p| p.x).collect();
        ts.sort_by(f64::total_cmp);
        let mids: Vec<f64> = ts.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
        let last = ts[ts.len() - 1];
        ts.extend(mids);
        ts.extend([last + 1.0, last + 1000.0]);
        a.t0() == b.t0()
            && ts
                .iter()
                .filter(|&&t| t >= a.t0())
                .all(|&t| (a.height_at(t) - b.height_at(t)).abs() <= 1e-9 * (1.0 + a.height_at(t).abs() + t.abs()))
    }

    fn wedge() -> impl Strategy<Value = Region> {
        (-100.0f64..100.0, -50.0f64..50.0, -2.0f64..2.0, 0.0f64..60.0)
            .prop_map(|(t, z, m, d)| Region::of_vertex(t, z, m, d))
    }

    /// A triangle-like region: the intersection of three vertex wedges.
    fn triangle_region() -> impl Strategy<Value = Region> {
        (wedge(), wedge(), wedge()).prop_map(|(a, b, c)| a.intersect(&b).intersect(&c))
    }

    proptest! {
        #[test]
        fn envelope_is_the_running_intersection(regions in prop::collection::vec(triangle_region(), 1..40)) {
            let refs: Vec<&Region> = regions.iter().collect();
            let want = occlusion::intersect_all(refs.iter().map(|r| Some(*r))).expect("non-empty");
            let got = envelope(&refs, &mut Vec::new()).expect("concave input");
            prop_assert!(close(&got, &want), "{got:?} vs {want:?}");
            let balanced = intersect_balanced(&refs).expect("non-empty");
            prop_assert!(close(&balanced, &want), "{balanced:?} vs {want:?}");
        }

        /// The oracle for [`group_regions`]: per-triangle regions (the running intersection of each triangle's three
        /// vertex regions), then the running intersection over the group's triangles. Groups are arbitrary sets of
        /// triangles (repeats included); some vertex regions are empty.
        #[test]
        fn group_regions_from_vertices_equal_group_regions_from_triangles(
            points in prop::collection::vec((0.0f64..100.0, 0.0f64..100.0, -20.0f64..20.0), 4..30),
            horizons in prop::collection::vec(prop::option::weighted(0.9, (-1.0f64..1.0, 0.0f64..50.0)), 30 * 4),
            picks in prop::collection::vec(prop::collection::vec(any::<prop::sample::Index>(), 1..12), 1..5),
            offset in prop_oneof![Just(DVec2::ZERO), Just(DVec2::new(5e5, 5e6))],
        ) {
            let pts: Vec<DVec3> = points.iter().map(|&(x, y, z)| DVec3::new(x + offset.x, y + offset.y, z)).collect();
            let triangulated = tin::triangulate(&pts, tin::DedupePolicy::Reject);
            prop_assume!(triangulated.is_ok());
            let tin = triangulated.expect("checked").0;
            let sectors = 4;
            let vertices = RegionTable::of_vertices(tin.positions(), tin.bbox().min.truncate(), sectors, |v, s| {
                horizons[(v * sectors + s) as usize].map(|(slope, distance)| occlusion::SectorHorizon { slope, distance })
            });
            let tris = tin.triangles();
            let triangles = vertices.intersect_rows(tin.num_triangles(), |t| tris[t]);
            let groups: Vec<Vec<u32>> = picks
                .iter()
                .map(|g| g.iter().map(|i| i.index(tin.num_triangles()) as u32).collect())
                .collect();
            let got = group_regions(&tin, &vertices, &groups);
            for (g, members) in groups.iter().enumerate() {
                for s in 0..sectors {
                    let want = occlusion::intersect_all(members.iter().map(|&t| triangles.get(t, s)));
                    let have = got[g][s as usize].as_ref();
                    match (have, want.as_ref()) {
                        (None, None) => {}
                        (Some(a), Some(b)) => prop_assert!(close(a, b), "group {g} sector {s}: {a:?} vs {b:?}"),
                        (a, b) => prop_assert!(false, "group {g} sector {s}: {a:?} vs {b:?}"),
                    }
                }
            }
        }

        #[test]
        fn hull_circle_encloses_every_point(
            points in prop::collection::vec((-1e3f64..1e3, -1e3f64..1e3), 1..80),
            offset in prop_oneof![Just(0.0), Just(5e5), Just(5e6)],
        ) {
            let pts: Vec<DVec2> = points.iter().map(|&(x, y)| DVec2::new(x + offset, y + offset)).collect();
            let hull = hull_of(pts.clone());
            prop_assert!(hull.len() <= pts.len());
            let circle = circle_of_hull(&hull);
            for p in &pts {
                prop_assert!(p.distance(circle.centre) <= circle.radius, "{p} outside {circle:?}");
            }
        }
    }

    #[test]
    fn non_concave_chains_fall_back_to_pairwise_intersection() {
        // A convex kink: slope 0 then slope 1.
        let kinked = Region::from_chain(vec![DVec2::new(0.0, 0.0), DVec2::new(10.0, 0.0)], 1.0).expect("valid chain");
        let other = Region::of_vertex(-5.0, 3.0, -0.1, 7.0);
        let third = Region::of_vertex(1.0, 4.0, 0.2, 2.0);
        assert!(envelope(&[&kinked, &other], &mut Vec::new()).is_none());
        let table = RegionTable::from_rows(
            1,
            DVec2::ZERO,
            vec![Some(kinked.clone()), Some(other.clone()), Some(third.clone())],
        );
        let tin = Tin::from_parts(
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2]],
        )
        .expect("one triangle");
        let regions = group_regions(&tin, &table, &[vec![0]]);
        assert_eq!(regions[0][0], Some(kinked.intersect(&other).intersect(&third)));
    }

    #[test]
    fn hull_of_a_square_with_inner_and_edge_points() {
        let mut pts = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(4.0, 0.0),
            DVec2::new(4.0, 4.0),
            DVec2::new(0.0, 4.0),
            DVec2::new(2.0, 2.0),
            DVec2::new(1.0, 3.0),
        ];
        pts.push(DVec2::new(2.0, 0.0)); // On an edge: kept (collinear points are never dropped).
        let hull = hull_of(pts);
        assert_eq!(
            hull,
            vec![
                DVec2::new(0.0, 0.0),
                DVec2::new(2.0, 0.0),
                DVec2::new(4.0, 0.0),
                DVec2::new(4.0, 4.0),
                DVec2::new(0.0, 4.0)
            ]
        );
    }
}
