//! The merge hierarchy over crystal groups (thesis 5.2.3, last part; design.md "Crystal grouping").
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
//! - **Expanse limit**: the parent's circumscribed circle is the bounding circle of all vertices of its triangles
//!   ([`tin::bounding_circle_of_points`], Ritter's circle made exact). When its area `π r²` would exceed
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
    /// triangles' regions, for a parent the intersection of its children's.
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

/// The circle enclosing all vertices of `triangles` (the triangles of one or more groups).
pub(crate) fn circle_of<'a>(tin: &Tin, groups: impl IntoIterator<Item = &'a [u32]>, buffer: &mut Vec<DVec2>) -> Circle {
    buffer.clear();
    let (tris, pos) = (tin.triangles(), tin.positions());
    for group in groups {
        for &t in group {
            buffer.extend(tris[t as usize].iter().map(|&v| pos[v as usize].truncate()));
        }
    }
    bounding_circle_of_points(buffer).unwrap_or(Circle {
        centre: DVec2::ZERO,
        radius: 0.0,
    })
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

/// What building the hierarchy did, besides the hierarchy itself.
pub(crate) struct MergeReport {
    /// Merges refused by the expanse limit.
    pub expanse_rejections: usize,
}

/// Builds the hierarchy over `groups` (see the module documentation). Node ranges are left empty; see
/// [`crate::order`].
pub(crate) fn build_hierarchy(
    tin: &Tin,
    groups: &[Vec<u32>],
    group_regions: &RegionTable,
    collisions: &[(u32, u32, u64)],
    max_expanse: f64,
    terrain_area: f64,
) -> (Hierarchy, MergeReport) {
    let count = groups.len();
    let limit = max_expanse * terrain_area;
    let mut buffer = Vec::new();
    let mut graph: UnGraphMap<u32, u64> = UnGraphMap::with_capacity(count, collisions.len());
    for g in 0..count as u32 {
        graph.add_node(g);
    }
    for &(a, b, w) in collisions {
        graph.add_edge(a, b, w);
    }
    let mut nodes: Vec<Node> = (0..count)
        .map(|g| Node {
            children: Vec::new(),
            parent: None,
            level: 0,
            circle: circle_of(tin, [groups[g].as_slice()], &mut buffer),
            range: 0..0,
            regions: group_regions.row(g as u32).to_vec(),
            collisions: record(&graph, g as u32),
        })
        .collect();
    // The groups under each node in play.
    let mut leaves_of: Vec<Vec<u32>> = (0..count as u32).map(|g| vec![g]).collect();
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
        let mut merges: Vec<(u32, u32, Circle)> = Vec::new();
        let mut rejected_here = 0;
        for &g in &active {
            if taken[g as usize] {
                continue;
            }
            while let Some(p) = best_partner(&graph, g, |_| true) {
                if taken[p as usize] {
                    break;
                }
                let under = leaves_of[g as usize].iter().chain(&leaves_of[p as usize]);
                let circle = circle_of(tin, under.map(|&l| groups[l as usize].as_slice()), &mut buffer);
                if PI * circle.radius * circle.radius > limit {
                    graph.remove_edge(g, p);
                    rejected_here += 1;
                    continue;
                }
                taken[g as usize] = true;
                taken[p as usize] = true;
                merges.push((g.min(p), g.max(p), circle));
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
            .map(|&(a, b, _)| intersect_regions(&nodes[a as usize].regions, &nodes[b as usize].regions))
            .collect();
        let mut map: Vec<u32> = (0..nodes.len() as u32).collect();
        let mut parents = Vec::with_capacity(merges.len());
        for ((a, b, circle), regions) in merges.into_iter().zip(regions) {
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
            let mut under = std::mem::take(&mut leaves_of[a as usize]);
            under.append(&mut leaves_of[b as usize]);
            leaves_of.push(under);
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
