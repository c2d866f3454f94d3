//! Crystal growth, orphan passes and small-group merging (thesis 5.2.3 "The Crystal Method" and 6.3.1).
//!
//! Seeds are cast on random unassigned triangles; every crystal grows breadth-first over edge-adjacent triangles,
//! all of them at once, until none can grow; triangles no crystal could reach (orphans) get a proportionally smaller
//! number of seeds in further passes; finally groups that are too small are merged with a small group they collided
//! with, or freed into the always-visible set.
//!
//! Choices made where the thesis is vague (each one is tested):
//! - **Visibility rule** (6.3.1): a triangle may join a crystal only if none of its three vertices is hidden from the
//!   crystal's *current* lowest vertex (lowest z, ties to the smaller vertex index): `!vertex_hidden_from(v, v, low)`
//!   for each vertex `v` (see [`occlusion::RegionTable::vertex_hidden_from`]: the region's definition evaluated
//!   relative to `v`, so that a lowest vertex on the left bound of `v`'s region, typically the horizon vertex that set
//!   it, is decided as the strict rule says and not by rounding); a vertex never hides from itself. The lowest
//!   vertex is updated as soon as a triangle with a lower vertex joins, so later tests of the same crystal use it.
//! - **Seeds** are drawn without replacement, uniformly from the unassigned triangles (partial Fisher-Yates over them
//!   in index order, `ChaCha8Rng::seed_from_u64(rng_seed)`, one generator for all passes). A drawn triangle that fails
//!   the visibility rule from the lowest of its own vertices is skipped (it stays unassigned) and drawing goes on, so
//!   every member of every crystal, its seed included, satisfies the rule.
//! - **Simultaneous growth** is round-robin: in each round every crystal that can still grow, in id order, takes one
//!   step. A step pops the crystal's oldest unexpanded member (its member list in join order is its BFS queue) and
//!   looks across that member's three edges in edge order (see [`tin::Tin::neighbours`]).
//! - **Collisions**: looking across an edge at a triangle owned by another crystal counts one collision for the pair
//!   when that triangle passes the visibility rule from the looking crystal's current lowest vertex, i.e. when the
//!   crystal would have grown there had the triangle been free. Adjacent crystals that cannot see into each other
//!   therefore never collide, as the thesis notes. Each member expands once, so an edge between two crystals counts
//!   at most twice (once from each side). Crystals of later passes collide with older ones by the same rule; older
//!   crystals do not grow again.
//! - **Orphan passes**: pass `k ≥ 1` casts `max(1, ⌊seeds × orphans / triangles⌋)` seeds over the triangles still
//!   unassigned. Passes stop after `orphan_passes` of them, when nothing is unassigned or no seed could be placed, or
//!   when the largest crystal started in an orphan pass is smaller than `min_group` (the size rule is not applied to
//!   the first pass, whose seeds were not cast over orphans).
//! - **Small groups**: sweeping groups in id order, a group under `min_group` merges with the small group (also under
//!   `min_group`) it collided with most (ties to the smaller id); the merged group keeps the smaller id, the sum of
//!   both collision records without their mutual collisions, and the members of the kept group followed by the other's.
//!   A group keeps merging while it is small and has a small partner; sweeps repeat until nothing merges. Groups still
//!   small are freed into the always-visible set and their collisions forgotten. Merged groups stay edge-connected,
//!   because collisions only happen across edges.
//!
//! Speed: growth needs no allocation per step. The visibility test reads the vertex table's sector summaries in place
//! (it is [`occlusion::RegionTable::vertex_hidden_from`] itself), and each vertex remembers its answer for the last
//! camera vertex it was tested against; reading the table at random is most of growth's time.

use glam::DVec3;
use occlusion::RegionTable;
use petgraph::graphmap::UnGraphMap;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use tin::{NO_NEIGHBOUR, Tin, prefetch};

use crate::error::CrystalError;
use crate::params::CrystalParams;

/// Marks a triangle that belongs to no crystal.
pub(crate) const UNASSIGNED: u32 = u32::MAX;

/// How a triangle joined its crystal during growth.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Join {
    /// The crystal it joined, numbered in seeding order over all passes (not the final group id: small-group merging
    /// and freeing come later).
    pub crystal: u32,
    /// The pass (0 = first pass, then orphan passes) in which it joined.
    pub pass: u32,
    /// Global join order: triangles joined in increasing `seq`.
    pub seq: u32,
    /// The crystal's lowest vertex when the triangle joined (for a seed, the lowest of its own vertices); none of the
    /// triangle's vertices was hidden from it.
    pub lowest: u32,
}

/// What one pass of seeding and growth did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct PassStats {
    /// Seeds asked for.
    pub seeds: usize,
    /// Crystals started (fewer than `seeds` when not enough unassigned triangles pass the visibility rule).
    pub new_groups: usize,
    /// Triangles in the largest crystal started in this pass (0 when none started).
    pub largest_new_group: usize,
}

/// The outcome of seeding and growth over all passes, before small-group merging (see [`grow`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Growth {
    /// Members of each crystal in join order.
    pub crystals: Vec<Vec<u32>>,
    /// Per triangle, how it joined (`None`: never joined a crystal).
    pub joins: Vec<Option<Join>>,
    /// Collision counts `(a, b, count)` with `a < b`, sorted by pair.
    pub collisions: Vec<(u32, u32, u64)>,
    /// One entry per pass, the first pass included.
    pub passes: Vec<PassStats>,
}

/// The vertex-from-point test of growth: [`RegionTable::vertex_hidden_from`] with the vertex's own position, read in
/// place from the vertex region table (no copy of the table is made).
pub(crate) struct Sight<'a> {
    regions: &'a RegionTable,
    positions: &'a [DVec3],
}

impl<'a> Sight<'a> {
    pub(crate) fn new(regions: &'a RegionTable, positions: &'a [DVec3]) -> Sight<'a> {
        Sight { regions, positions }
    }

    /// Whether vertex `v` is hidden from `camera`.
    #[inline]
    fn hidden(&self, v: u32, camera: DVec3) -> bool {
        self.regions.vertex_hidden_from(v, self.positions[v as usize], camera)
    }
}

/// Remembers, per vertex, the last camera vertex it was tested against and the answer: a crystal tests the same
/// vertices from the same lowest vertex several times (each vertex lies in about six triangles, each looked at from up
/// to three sides).
struct Memo {
    /// Per vertex: the last camera vertex and whether the vertex was hidden from it (side by side, so that a lookup
    /// touches one cache line).
    last: Vec<(u32, bool)>,
}

impl Memo {
    fn new(vertices: usize) -> Memo {
        Memo {
            last: vec![(u32::MAX, false); vertices],
        }
    }

    /// Whether no vertex of `tri` is hidden from vertex `low`.
    #[inline]
    fn sees(&mut self, sight: &Sight, tri: [u32; 3], low: u32) -> bool {
        let camera = sight.positions[low as usize];
        tri.iter().all(|&v| {
            if v == low {
                return true;
            }
            let entry = &mut self.last[v as usize];
            if entry.0 != low {
                *entry = (low, sight.hidden(v, camera));
            }
            !entry.1
        })
    }
}

/// Whether vertex `a` is lower than vertex `b` (z, then index).
#[inline]
fn lower(positions: &[DVec3], a: u32, b: u32) -> bool {
    let (za, zb) = (positions[a as usize].z, positions[b as usize].z);
    za < zb || (za == zb && a < b)
}

/// The lowest vertex of a triangle.
fn lowest_of(positions: &[DVec3], tri: [u32; 3]) -> u32 {
    tri.into_iter()
        .reduce(|a, b| if lower(positions, b, a) { b } else { a })
        .unwrap_or(tri[0])
}

/// Levels of data [`Grower::prefetch_step`] requests ahead of a step.
const PREFETCH_STAGES: usize = 5;
/// Steps between two prefetch stages of the same crystal.
const PREFETCH_DISTANCE: usize = 4;

struct Grower<'a> {
    triangles: &'a [[u32; 3]],
    neighbours: &'a [[u32; 3]],
    positions: &'a [DVec3],
    sight: Sight<'a>,
    memo: Memo,
    owner: Vec<u32>,
    crystals: Vec<Vec<u32>>,
    heads: Vec<usize>,
    lowest: Vec<u32>,
    joins: Vec<Option<Join>>,
    seq: u32,
    /// One entry per collision: the pair packed as `min << 32 | max`.
    events: Vec<u64>,
}

impl Grower<'_> {
    fn join(&mut self, t: u32, crystal: u32, pass: u32, lowest: u32) {
        self.owner[t as usize] = crystal;
        self.crystals[crystal as usize].push(t);
        self.joins[t as usize] = Some(Join {
            crystal,
            pass,
            seq: self.seq,
            lowest,
        });
        self.seq += 1;
    }

    /// Starts a crystal on `t` if `t` passes the visibility rule from its own lowest vertex.
    fn try_seed(&mut self, t: u32, pass: u32) -> bool {
        let tri = self.triangles[t as usize];
        let low = lowest_of(self.positions, tri);
        if !self.memo.sees(&self.sight, tri, low) {
            return false;
        }
        let id = self.crystals.len() as u32;
        self.crystals.push(Vec::new());
        self.heads.push(0);
        self.lowest.push(low);
        self.join(t, id, pass, low);
        true
    }

    /// Casts up to `want` seeds on distinct random unassigned triangles; returns how many crystals started.
    fn seed(&mut self, rng: &mut ChaCha8Rng, want: usize, pass: u32) -> usize {
        let mut free: Vec<u32> = (0..self.owner.len() as u32)
            .filter(|&t| self.owner[t as usize] == UNASSIGNED)
            .collect();
        let (mut placed, mut i) = (0, 0);
        while placed < want && i < free.len() {
            let j = rng.random_range(i as u32..free.len() as u32) as usize;
            free.swap(i, j);
            if self.try_seed(free[i], pass) {
                placed += 1;
            }
            i += 1;
        }
        placed
    }

    /// Hints the processor to load what crystal `g`'s next step reads ([`Grower::step`]), one level per `stage`:
    /// 0 its next member's entry, 1 that member's neighbours, 2 their owners and corners, 3 the corners' positions and
    /// memo entries, 4 the sector summaries of the corners the memo will not answer for. Each stage reads only what
    /// the previous one requested (a few steps earlier). No effect on any result: the data read here is what the
    /// step will read, since no other crystal's step changes `g`'s members, head or the mesh; owners may change in
    /// between, which only makes a hint useless.
    #[inline(always)]
    fn prefetch_step(&self, g: u32, stage: usize) {
        let gi = g as usize;
        let Some(t) = self.crystals[gi].get(self.heads[gi]) else {
            return;
        };
        if stage == 0 {
            prefetch(t);
            return;
        }
        let neighbours = &self.neighbours[*t as usize];
        if stage == 1 {
            prefetch(neighbours);
            return;
        }
        for &n in neighbours {
            if n == NO_NEIGHBOUR {
                continue;
            }
            if stage == 2 {
                prefetch(&self.owner[n as usize]);
                prefetch(&self.triangles[n as usize]);
                continue;
            }
            let low = self.lowest[gi];
            for v in self.triangles[n as usize] {
                if stage == 3 {
                    prefetch(&self.memo.last[v as usize]);
                    prefetch(&self.positions[v as usize]);
                } else if v != low && self.memo.last[v as usize].0 != low {
                    // The test that the memo will not answer.
                    let (position, camera) = (self.positions[v as usize], self.positions[low as usize]);
                    self.sight.regions.prefetch_vertex_test(v, position, camera);
                }
            }
        }
    }

    /// One growth step of crystal `g`; returns whether it may still grow.
    fn step(&mut self, g: u32, pass: u32) -> bool {
        let gi = g as usize;
        let Some(&t) = self.crystals[gi].get(self.heads[gi]) else {
            return false;
        };
        self.heads[gi] += 1;
        for n in self.neighbours[t as usize] {
            if n == NO_NEIGHBOUR {
                continue;
            }
            let owner = self.owner[n as usize];
            if owner == g {
                continue;
            }
            let tri = self.triangles[n as usize];
            let low = self.lowest[gi];
            if !self.memo.sees(&self.sight, tri, low) {
                continue;
            }
            if owner == UNASSIGNED {
                self.join(n, g, pass, low);
                let candidate = lowest_of(self.positions, tri);
                if lower(self.positions, candidate, low) {
                    self.lowest[gi] = candidate;
                }
            } else {
                let (a, b) = (g.min(owner), g.max(owner));
                self.events.push(u64::from(a) << 32 | u64::from(b));
            }
        }
        self.heads[gi] < self.crystals[gi].len()
    }

    /// Grows crystals `first..` round-robin until none can grow.
    fn grow(&mut self, first: usize, pass: u32) {
        let mut active: Vec<u32> = (first as u32..self.crystals.len() as u32).collect();
        while !active.is_empty() {
            let mut kept = 0;
            for i in 0..active.len() {
                // Consecutive steps are far apart on the mesh (one per crystal), so each step's reads miss the
                // cache; the steps of the next crystals are known, so their data is requested in stages ahead.
                for stage in 0..PREFETCH_STAGES {
                    if let Some(&ahead) = active.get(i + (PREFETCH_STAGES - stage) * PREFETCH_DISTANCE) {
                        self.prefetch_step(ahead, stage);
                    }
                }
                let g = active[i];
                if self.step(g, pass) {
                    active[kept] = g;
                    kept += 1;
                }
            }
            active.truncate(kept);
        }
    }
}

/// Seeds and grows crystals over all passes (see the module documentation). This is the first phase of
/// [`crate::build`], public for measurement and inspection.
pub fn grow(tin: &Tin, vertex_regions: &RegionTable, params: &CrystalParams) -> Result<Growth, CrystalError> {
    params.validate()?;
    if vertex_regions.len() != tin.num_vertices() {
        return Err(CrystalError::TableSize {
            table: "vertex",
            expected: tin.num_vertices(),
            found: vertex_regions.len(),
        });
    }
    let n = tin.num_triangles();
    let sight = Sight::new(vertex_regions, tin.positions());
    let mut g = Grower {
        triangles: tin.triangles(),
        neighbours: tin.neighbours(),
        positions: tin.positions(),
        sight,
        memo: Memo::new(tin.num_vertices()),
        owner: vec![UNASSIGNED; n],
        crystals: Vec::new(),
        heads: Vec::new(),
        lowest: Vec::new(),
        joins: vec![None; n],
        seq: 0,
        events: Vec::new(),
    };
    let mut rng = ChaCha8Rng::seed_from_u64(params.rng_seed);
    let first_seeds = params.first_seeds(n);
    let mut passes = Vec::new();
    let mut assigned = 0usize;
    for pass in 0..=params.orphan_passes {
        let unassigned = n - assigned;
        if unassigned == 0 {
            break;
        }
        let want = if pass == 0 {
            first_seeds
        } else {
            ((first_seeds as u128 * unassigned as u128 / n as u128) as usize).max(1)
        };
        let first = g.crystals.len();
        let new_groups = g.seed(&mut rng, want, pass);
        g.grow(first, pass);
        let largest = g.crystals[first..].iter().map(Vec::len).max().unwrap_or(0);
        assigned += g.crystals[first..].iter().map(Vec::len).sum::<usize>();
        passes.push(PassStats {
            seeds: want,
            new_groups,
            largest_new_group: largest,
        });
        if new_groups == 0 || (pass > 0 && largest < params.min_group) {
            break;
        }
    }
    let mut events = std::mem::take(&mut g.events);
    events.sort_unstable();
    let mut collisions: Vec<(u32, u32, u64)> = Vec::new();
    for key in events {
        let (a, b) = ((key >> 32) as u32, key as u32);
        match collisions.last_mut() {
            Some(last) if (last.0, last.1) == (a, b) => last.2 += 1,
            _ => collisions.push((a, b, 1)),
        }
    }
    Ok(Growth {
        crystals: g.crystals,
        joins: g.joins,
        collisions,
        passes,
    })
}

/// Groups after small-group merging.
#[derive(Clone, Debug)]
pub(crate) struct Settled {
    /// The groups kept (each at least `min_group` triangles), in order of their smallest crystal id.
    pub groups: Vec<Vec<u32>>,
    /// Collision counts `(a, b, count)` between kept groups, `a < b`, sorted.
    pub collisions: Vec<(u32, u32, u64)>,
    /// Triangles of the groups freed for being small.
    pub freed: Vec<u32>,
    /// Merges of two small groups made.
    pub merges: usize,
    /// Groups freed into the always-visible set.
    pub freed_groups: usize,
}

/// The partner of `g` with the most collisions among those `eligible`, ties to the smaller id.
pub(crate) fn best_partner(graph: &UnGraphMap<u32, u64>, g: u32, eligible: impl Fn(u32) -> bool) -> Option<u32> {
    graph
        .edges(g)
        .filter(|&(_, x, _)| eligible(x))
        .max_by(|a, b| a.2.cmp(b.2).then(b.1.cmp(&a.1)))
        .map(|(_, x, _)| x)
}

/// Merges `gone` into `keep` in a collision graph: `keep`'s edges gain `gone`'s, their mutual edge disappears.
pub(crate) fn contract(graph: &mut UnGraphMap<u32, u64>, keep: u32, gone: u32) {
    let edges: Vec<(u32, u64)> = graph
        .edges(gone)
        .filter(|&(_, x, _)| x != keep)
        .map(|(_, x, &w)| (x, w))
        .collect();
    graph.remove_node(gone);
    for (x, w) in edges {
        match graph.edge_weight_mut(keep, x) {
            Some(e) => *e += w,
            None => {
                graph.add_edge(keep, x, w);
            }
        }
    }
}

/// Merges small groups with small groups they collided with and frees what stays small (see the module docs).
pub(crate) fn settle_small(crystals: Vec<Vec<u32>>, collisions: &[(u32, u32, u64)], min_group: usize) -> Settled {
    let count = crystals.len();
    let mut graph: UnGraphMap<u32, u64> = UnGraphMap::with_capacity(count, collisions.len());
    for g in 0..count as u32 {
        graph.add_node(g);
    }
    for &(a, b, w) in collisions {
        graph.add_edge(a, b, w);
    }
    let mut members = crystals;
    let mut alive = vec![true; count];
    let mut merges = 0;
    loop {
        let mut changed = false;
        for g in 0..count as u32 {
            while alive[g as usize] && members[g as usize].len() < min_group {
                let Some(p) = best_partner(&graph, g, |x| members[x as usize].len() < min_group) else {
                    break;
                };
                let (keep, gone) = (g.min(p), g.max(p));
                let moved = std::mem::take(&mut members[gone as usize]);
                members[keep as usize].extend(moved);
                contract(&mut graph, keep, gone);
                alive[gone as usize] = false;
                merges += 1;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    let mut id = vec![UNASSIGNED; count];
    let mut groups = Vec::new();
    let mut freed = Vec::new();
    let mut freed_groups = 0;
    for (g, m) in members.into_iter().enumerate() {
        if !alive[g] {
            continue;
        }
        if m.len() < min_group {
            freed.extend(m);
            freed_groups += 1;
        } else {
            id[g] = groups.len() as u32;
            groups.push(m);
        }
    }
    let mut kept: Vec<(u32, u32, u64)> = graph
        .all_edges()
        .filter_map(|(a, b, &w)| {
            let (a, b) = (id[a as usize], id[b as usize]);
            (a != UNASSIGNED && b != UNASSIGNED).then_some((a.min(b), a.max(b), w))
        })
        .collect();
    kept.sort_unstable();
    Settled {
        groups,
        collisions: kept,
        freed,
        merges,
        freed_groups,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;
    use proptest::prelude::*;

    proptest! {
        /// Growth's visibility test against the wedge definition (crate `occlusion`'s `region` module), relative to the
        /// vertex: in the sector towards the camera, hidden when the camera is strictly beyond `t_p + d` and strictly
        /// below the line through the vertex with the sector's slope. Cases within rounding of a boundary are skipped.
        #[test]
        fn sight_follows_the_wedge_definition(
            vertices in prop::collection::vec((-50.0f64..50.0, -50.0f64..50.0, -10.0f64..10.0), 2..12),
            horizons in prop::collection::vec(prop::option::weighted(0.8, (-1.0f64..1.0, 0.0f64..40.0)), 12 * 8),
            cameras in prop::collection::vec((-80.0f64..80.0, -80.0f64..80.0, -30.0f64..30.0), 1..20),
            origin in (-100.0f64..100.0, -100.0f64..100.0),
        ) {
            let positions: Vec<DVec3> = vertices.iter().map(|&(x, y, z)| DVec3::new(x, y, z)).collect();
            let origin = DVec2::new(origin.0, origin.1);
            let table = RegionTable::of_vertices(&positions, origin, 8, |v, s| {
                horizons[(v * 8 + s) as usize].map(|(slope, distance)| occlusion::SectorHorizon { slope, distance })
            });
            let sight = Sight::new(&table, &positions);
            for &(x, y, z) in cameras.iter().chain(vertices.iter()) {
                let camera = DVec3::new(x, y, z);
                for (v, p) in positions.iter().enumerate() {
                    let d = camera.truncate() - p.truncate();
                    let want = if d == DVec2::ZERO {
                        false
                    } else {
                        let sector = cull::sector_of_azimuth(8, cull::azimuth(d.x, d.y));
                        match horizons[v * 8 + sector as usize] {
                            None => false,
                            Some((slope, distance)) => {
                                let [rx, ry] = cull::sector_direction(8, sector);
                                let ahead = rx * d.x + ry * d.y;
                                let (beyond, below) = (ahead - distance, p.z + slope * ahead - camera.z);
                                if beyond.abs() < 1e-9 || below.abs() < 1e-9 {
                                    continue;
                                }
                                beyond > 0.0 && below > 0.0
                            }
                        }
                    };
                    prop_assert_eq!(sight.hidden(v as u32, camera), want, "vertex {} camera {}", v, camera);
                }
            }
        }
    }

    #[test]
    fn small_groups_merge_with_their_most_collided_small_partner() {
        // Sizes 10, 10, 10, 50 with min 25: 0 collided most with 2 (and with big 3), 1 only with 3.
        let crystals = vec![
            (0..10).collect(),
            (10..20).collect(),
            (20..30).collect(),
            (30..80).collect::<Vec<u32>>(),
        ];
        let s = settle_small(crystals, &[(0, 1, 1), (0, 2, 4), (0, 3, 9), (1, 3, 2), (2, 3, 1)], 25);
        // 0 and 2 merge (20 triangles, still small); then 0+2 merges with 1 (its only small partner): 30 ≥ 25.
        assert_eq!(s.merges, 2);
        assert_eq!(s.groups.len(), 2);
        assert_eq!(s.groups[0].len(), 30);
        assert_eq!(&s.groups[0][..10], &(0..10).collect::<Vec<u32>>()[..]);
        assert_eq!(&s.groups[0][10..20], &(20..30).collect::<Vec<u32>>()[..]);
        assert!(s.freed.is_empty());
        // 0+1+2 vs 3: 9 + 2 + 1 collisions.
        assert_eq!(s.collisions, vec![(0, 1, 12)]);
    }

    #[test]
    fn small_groups_without_small_partners_are_freed() {
        let crystals = vec![(0..5).collect(), (5..40).collect::<Vec<u32>>(), (40..44).collect()];
        let s = settle_small(crystals, &[(0, 1, 3), (1, 2, 1)], 30);
        assert_eq!(s.merges, 0);
        assert_eq!(s.groups, vec![(5..40).collect::<Vec<u32>>()]);
        assert_eq!(s.freed, vec![0, 1, 2, 3, 4, 40, 41, 42, 43]);
        assert_eq!(s.freed_groups, 2);
        assert!(s.collisions.is_empty());
    }

    #[test]
    fn ties_go_to_the_smaller_id() {
        let mut graph = UnGraphMap::new();
        graph.add_edge(5u32, 9, 3u64);
        graph.add_edge(5, 2, 3);
        graph.add_edge(5, 7, 1);
        assert_eq!(best_partner(&graph, 5, |_| true), Some(2));
        assert_eq!(best_partner(&graph, 5, |x| x != 2), Some(9));
        contract(&mut graph, 2, 5);
        assert_eq!(graph.edge_weight(2, 9), Some(&3));
        assert_eq!(graph.edge_weight(2, 7), Some(&1));
        assert!(!graph.contains_node(5));
    }
}
