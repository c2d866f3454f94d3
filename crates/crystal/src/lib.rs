//! Crystal grouping of TIN triangles by visibility (thesis 5.2.3 "The Crystal Method" and 6.3; the README's "What it
//! does").
//!
//! [`build`] groups the triangles of a [`Tin`] into edge-connected crystals that do not grow out of sight of their
//! lowest vertex ([`growth`]), orphans what no crystal could take, merges the groups into a hierarchy by their
//! collision records ([`merge`]), and reorders the triangles so that every hierarchy node is one contiguous range.
//! [`Crystal::check_invariants`] checks everything the result promises.
#![warn(missing_docs)]

pub mod error;
pub mod growth;
pub mod merge;
mod order;
pub mod params;

use std::ops::Range;

use glam::DVec2;
use occlusion::RegionTable;
use serde::{Deserialize, Serialize};
use tin::{NO_NEIGHBOUR, Tin};

pub use error::CrystalError;
pub use growth::{Join, PassStats};
pub use merge::{Hierarchy, Node};
pub use params::CrystalParams;

/// Marks a triangle in no group (an always-visible orphan) in [`Crystal::group_of`].
pub const NO_GROUP: u32 = u32::MAX;

/// Counts describing a grouping.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CrystalStats {
    /// Orphan passes run after the first pass.
    pub orphan_passes: u32,
    /// Triangles in the always-visible set.
    pub orphans: usize,
    /// Groups (hierarchy leaves).
    pub groups: usize,
    /// Hierarchy nodes, leaves included.
    pub nodes: usize,
    /// Hierarchy levels (highest level + 1).
    pub levels: u32,
    /// Top-level nodes.
    pub top_level: usize,
    /// Seeds asked for, crystals started and the largest new crystal, per pass (the first pass first).
    pub passes: Vec<PassStats>,
    /// Crystals grown over all passes.
    pub crystals: usize,
    /// Merges of two small groups.
    pub small_merges: usize,
    /// Small groups freed into the always-visible set.
    pub freed_groups: usize,
    /// Triangles of those freed groups.
    pub freed_triangles: usize,
    /// Hierarchy merges refused by the expanse limit.
    pub expanse_rejections: usize,
}

/// The result of crystal grouping.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Crystal {
    /// The parameters used.
    pub params: CrystalParams,
    /// Sectors of the regions.
    pub sectors: u32,
    /// The origin `o` of the regions' plane coordinates `t = r_i · (xy − o)` (that of the vertex region table).
    pub region_origin: DVec2,
    /// Triangles of each group (original indices, in join order); group `g` is hierarchy node `g`.
    pub groups: Vec<Vec<u32>>,
    /// The always-visible triangles (original indices, increasing).
    pub orphans: Vec<u32>,
    /// Per triangle, its group, or [`NO_GROUP`] for an orphan.
    pub group_of: Vec<u32>,
    /// Per triangle, how it joined a crystal during growth; `None` for triangles no crystal reached. Triangles of
    /// freed small groups keep their record.
    pub joins: Vec<Option<Join>>,
    /// The merge hierarchy over the groups.
    pub hierarchy: Hierarchy,
    /// The new triangle order: `order[k]` is the original index of the triangle drawn `k`-th.
    pub order: Vec<u32>,
    /// Positions of the always-visible set in `order` (the tail).
    pub orphan_range: Range<u32>,
    /// Sum of the triangles' areas in x,y (m²), the base of the expanse limit.
    pub terrain_area: f64,
    /// Counts.
    pub stats: CrystalStats,
}

/// Groups the triangles of `tin` (see the crate documentation and [`growth`], [`merge`]).
///
/// `vertex_regions` has one row per vertex: the growth's visibility rule reads it, and a group's regions are the
/// intersection of its vertices' regions (the same as that of its triangles' regions, since a triangle's region is the
/// intersection of its three vertices').
pub fn build(tin: &Tin, vertex_regions: &RegionTable, params: &CrystalParams) -> Result<Crystal, CrystalError> {
    params.validate()?;
    let nt = tin.num_triangles();
    let grown = growth::grow(tin, vertex_regions, params)?;
    let crystals = grown.crystals.len();
    let settled = growth::settle_small(grown.crystals, &grown.collisions, params.min_group);
    let groups = settled.groups;
    let mut group_of = vec![NO_GROUP; nt];
    for (g, members) in groups.iter().enumerate() {
        for &t in members {
            group_of[t as usize] = g as u32;
        }
    }
    let orphans: Vec<u32> = (0..nt as u32).filter(|&t| group_of[t as usize] == NO_GROUP).collect();
    let group_vertices = merge::group_vertices(tin, &groups);
    let group_regions = merge::vertex_set_regions(vertex_regions, &group_vertices);
    let terrain_area: f64 = (0..nt).map(|t| tin.triangle_area_xy(t)).sum();
    let (mut hierarchy, report) = merge::build_hierarchy(
        tin,
        &group_vertices,
        group_regions,
        &settled.collisions,
        params.max_expanse,
        terrain_area,
    );
    let centroids: Vec<[f64; 2]> = (0..nt)
        .map(|t| {
            let c = tin.corners(t);
            [(c[0].x + c[1].x + c[2].x) / 3.0, (c[0].y + c[1].y + c[2].y) / 3.0]
        })
        .collect();
    let (order, orphan_range) = order::lay_out(&mut hierarchy, &groups, &orphans, &centroids);
    let stats = CrystalStats {
        orphan_passes: grown.passes.len().saturating_sub(1) as u32,
        orphans: orphans.len(),
        groups: groups.len(),
        nodes: hierarchy.nodes.len(),
        levels: hierarchy.levels(),
        top_level: hierarchy.roots.len(),
        passes: grown.passes,
        crystals,
        small_merges: settled.merges,
        freed_groups: settled.freed_groups,
        freed_triangles: settled.freed.len(),
        expanse_rejections: report.expanse_rejections,
    };
    Ok(Crystal {
        params: params.clone(),
        sectors: vertex_regions.sectors(),
        region_origin: vertex_regions.origin(),
        groups,
        orphans,
        group_of,
        joins: grown.joins,
        hierarchy,
        order,
        orphan_range,
        terrain_area,
        stats,
    })
}

impl Crystal {
    /// The original indices of the triangles of node `id`, in drawing order.
    pub fn node_triangles(&self, id: u32) -> &[u32] {
        let r = &self.hierarchy.nodes[id as usize].range;
        &self.order[r.start as usize..r.end as usize]
    }

    /// Checks every promise of the grouping against `tin`, naming the first broken one:
    /// every triangle is in exactly one group or in the always-visible set; groups have at least `min_group`
    /// triangles and are edge-connected; the order is a permutation with every node one contiguous range, a parent's
    /// range its children's side by side, the roots' ranges tiling everything before the always-visible tail; the
    /// hierarchy is a forest whose leaves are exactly the groups, parents have two children and a larger id, levels
    /// are one more than the higher child; each parent's regions are the per-sector intersection of its children's;
    /// every node's circle encloses its vertices and no parent exceeds the expanse limit; the groups' collision
    /// records are symmetric and only join groups that share an edge; the counts in [`CrystalStats`] match.
    pub fn check_invariants(&self, tin: &Tin) -> Result<(), CrystalError> {
        let fail = |msg: String| Err(CrystalError::Invariant(msg));
        let nt = tin.num_triangles();
        let groups = self.groups.len();
        let nodes = &self.hierarchy.nodes;

        // Partition of the triangles.
        if self.group_of.len() != nt || self.joins.len() != nt {
            return fail(format!("per-triangle tables do not have {nt} entries"));
        }
        let mut seen = vec![false; nt];
        for (g, members) in self.groups.iter().enumerate() {
            if members.len() < self.params.min_group {
                return fail(format!(
                    "group {g} has {} triangles, below min_group {}",
                    members.len(),
                    self.params.min_group
                ));
            }
            for &t in members {
                if t as usize >= nt || std::mem::replace(&mut seen[t as usize], true) {
                    return fail(format!("triangle {t} of group {g} is out of range or in two groups"));
                }
                if self.group_of[t as usize] != g as u32 {
                    return fail(format!("group_of[{t}] is not {g}"));
                }
            }
        }
        if !self.orphans.windows(2).all(|w| w[0] < w[1]) {
            return fail("the always-visible set is not strictly increasing".into());
        }
        for &t in &self.orphans {
            if t as usize >= nt || std::mem::replace(&mut seen[t as usize], true) {
                return fail(format!("orphan {t} is out of range or also in a group"));
            }
            if self.group_of[t as usize] != NO_GROUP {
                return fail(format!("group_of[{t}] of an orphan is not NO_GROUP"));
            }
        }
        if let Some(t) = seen.iter().position(|&s| !s) {
            return fail(format!("triangle {t} is in no group and not an orphan"));
        }

        // Groups are edge-connected.
        let neighbours = tin.neighbours();
        let mut reached = vec![false; nt];
        for (g, members) in self.groups.iter().enumerate() {
            let mut queue = vec![members[0]];
            reached[members[0] as usize] = true;
            let mut count = 0;
            while let Some(t) = queue.pop() {
                count += 1;
                for n in neighbours[t as usize] {
                    if n != NO_NEIGHBOUR && self.group_of[n as usize] == g as u32 && !reached[n as usize] {
                        reached[n as usize] = true;
                        queue.push(n);
                    }
                }
            }
            if count != members.len() {
                return fail(format!(
                    "group {g} is not edge-connected ({count} of {} triangles reachable)",
                    members.len()
                ));
            }
        }

        // The order is a permutation.
        if self.order.len() != nt {
            return fail(format!("order has {} entries, not {nt}", self.order.len()));
        }
        let mut placed = vec![false; nt];
        for &t in &self.order {
            if t as usize >= nt || std::mem::replace(&mut placed[t as usize], true) {
                return fail(format!("order repeats or overruns triangle {t}"));
            }
        }
        let tail = (nt - self.orphans.len()) as u32..nt as u32;
        let mut tail_triangles = self.order[tail.start as usize..].to_vec();
        tail_triangles.sort_unstable();
        if self.orphan_range != tail || tail_triangles != self.orphans {
            return fail("the always-visible set is not the tail of the order".into());
        }

        // Forest structure, levels, ranges, regions, circles.
        if nodes.len() < groups {
            return fail(format!("{} nodes for {groups} groups", nodes.len()));
        }
        let forest = self.hierarchy.forest();
        if petgraph::algo::is_cyclic_directed(&forest) {
            return fail("the hierarchy has a cycle".into());
        }
        let limit = self.params.max_expanse * self.terrain_area;
        let (tris, pos) = (tin.triangles(), tin.positions());
        for (id, node) in nodes.iter().enumerate() {
            let id = id as u32;
            let is_group = (id as usize) < groups;
            if node.is_leaf() != is_group {
                return fail(format!("node {id}: leaves must be exactly the groups 0..{groups}"));
            }
            if node.regions.len() != self.sectors as usize {
                return fail(format!("node {id} has {} sector regions", node.regions.len()));
            }
            let r = node.range.clone();
            if r.start > r.end || r.end > self.orphan_range.start {
                return fail(format!("node {id} has range {r:?} outside the grouped part"));
            }
            match node.parent {
                None => {
                    if self.hierarchy.roots.binary_search(&id).is_err() {
                        return fail(format!("node {id} has no parent but is not a root"));
                    }
                }
                Some(p) => {
                    if p <= id || !nodes.get(p as usize).is_some_and(|pn| pn.children.contains(&id)) {
                        return fail(format!("node {id}'s parent {p} does not list it"));
                    }
                }
            }
            if is_group {
                if node.level != 0 {
                    return fail(format!("leaf {id} has level {}", node.level));
                }
                let mut got = self.node_triangles(id).to_vec();
                let mut want = self.groups[id as usize].clone();
                got.sort_unstable();
                want.sort_unstable();
                if got != want {
                    return fail(format!("leaf {id}'s range {r:?} does not hold exactly its group"));
                }
            } else {
                let c = &node.children;
                if c.len() != 2 || c[0] >= c[1] || c[1] >= id {
                    return fail(format!("node {id} has children {c:?}"));
                }
                let (a, b) = (&nodes[c[0] as usize], &nodes[c[1] as usize]);
                if a.parent != Some(id) || b.parent != Some(id) {
                    return fail(format!("node {id}'s children do not name it as parent"));
                }
                if node.level != a.level.max(b.level) + 1 {
                    return fail(format!("node {id} has level {}", node.level));
                }
                if a.range.start != r.start || a.range.end != b.range.start || b.range.end != r.end {
                    return fail(format!(
                        "node {id}'s range {r:?} is not its children's {:?} and {:?}",
                        a.range, b.range
                    ));
                }
                if node.regions != merge::intersect_regions(&a.regions, &b.regions) {
                    return fail(format!(
                        "node {id}'s regions are not the intersection of its children's"
                    ));
                }
                let area = std::f64::consts::PI * node.circle.radius * node.circle.radius;
                if area > limit {
                    return fail(format!(
                        "node {id}'s circle covers {area} m², over the limit {limit} m²"
                    ));
                }
            }
            for &t in self.node_triangles(id) {
                for &v in &tris[t as usize] {
                    if pos[v as usize].truncate().distance(node.circle.centre) > node.circle.radius {
                        return fail(format!("vertex {v} of triangle {t} lies outside node {id}'s circle"));
                    }
                }
            }
        }
        let mut start = 0;
        for &root in &self.hierarchy.roots {
            let Some(node) = nodes.get(root as usize) else {
                return fail(format!("root {root} does not exist"));
            };
            if node.parent.is_some() || node.range.start != start {
                return fail(format!("root {root} has a parent or does not follow the previous root"));
            }
            start = node.range.end;
        }
        if start != self.orphan_range.start {
            return fail("the roots' ranges do not tile the grouped part of the order".into());
        }

        // Collision records of the groups.
        for g in 0..groups {
            for &(h, count) in &nodes[g].collisions {
                if h as usize >= groups || h as usize == g || count == 0 {
                    return fail(format!("group {g} has a bad collision entry ({h}, {count})"));
                }
                if nodes[h as usize].collisions.binary_search(&(g as u32, count)).is_err() {
                    return fail(format!("collisions of groups {g} and {h} are not symmetric"));
                }
                let shared = self.groups[g]
                    .iter()
                    .flat_map(|&t| neighbours[t as usize])
                    .filter(|&n| n != NO_NEIGHBOUR && self.group_of[n as usize] == h)
                    .count() as u64;
                if count > 2 * shared {
                    return fail(format!(
                        "groups {g} and {h} share {shared} edges but record {count} collisions"
                    ));
                }
            }
        }

        // Counts.
        let s = &self.stats;
        let expected = (
            self.orphans.len(),
            groups,
            nodes.len(),
            self.hierarchy.levels(),
            self.hierarchy.roots.len(),
        );
        if (s.orphans, s.groups, s.nodes, s.levels, s.top_level) != expected {
            return fail(format!("stats {s:?} do not match the grouping {expected:?}"));
        }
        Ok(())
    }
}
