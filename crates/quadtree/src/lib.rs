//! Stewart's hierarchical visibility as a baseline for the crystal hierarchy: A. J. Stewart, *Hierarchical
//! Visibility in Terrains*, Eurographics Rendering Workshop 1997, §5 (`shared/papers/000_…`).
//!
//! Stewart stores, for every quad of an implicit quadtree over a grid terrain, one occlusion region per sector, and
//! culls a quad with one test. The thesis generalises this to irregular, visibility-aware groups (crystals); this
//! crate builds the fixed quadtree over a TIN from the *same* per-vertex regions ([`occlusion::RegionTable`], from
//! the same [`horizon`](https://docs.rs/horizon) field), so that the two groupings can be compared with everything
//! else equal.
//!
//! ## What is built
//!
//! - **Cells (§5.3).** The root cell is the square `[min.x, min.x + side] × [min.y, min.y + side]` with `side` the
//!   longer side of the footprint's bounding box; a cell at depth `d` is one of the `4^d` equal squares. The finest
//!   depth `D` is a parameter (`depth`, or a cell size in metres). Only non-empty cells become nodes.
//! - **Triangles.** Every triangle is assigned to the finest cell containing its centroid (a centroid on the far
//!   border of the root goes to the last cell). Triangles are sorted by the Morton (Z-order) code of their centroid
//!   at 2^21 cells per axis, then by index; since a cell's Morton codes form one interval, every node is one
//!   contiguous range of that order, and a parent's range is its children's ranges side by side (children in Z
//!   order: SW, SE, NW, NE). Inside a leaf the order is the finer Morton order, a spatially coherent layout.
//! - **Regions (§5.3).** Stewart's quad region `R_Q(i)` is the intersection of the regions of all grid points the
//!   quad *covers*, including those on its border, which neighbouring quads share. Here a node's region is the
//!   intersection over the vertices of every triangle *assigned* to it (the node's drawn range), so vertices of
//!   triangles that stick out of the cell count, and triangles that merely overlap the cell but whose centroid lies
//!   in a neighbour do not. This is what the test needs: the culled set is exactly the node's range, and every vertex
//!   of it is inside the region. Leaves intersect their vertices' rows; an inner node intersects its children's
//!   rows (bottom-up, "in order of coarsening resolution"); intersection is associative, so this is the same region
//!   as the direct intersection over the node's vertices (up to the rounding of the boundary's crossing points).
//! - **Per-vertex regions (§5.1, §5.2).** Stewart's vertex region uses the minimum-elevation subsector horizon,
//!   projected on the sector plane, at the distance of the *farthest* horizon point (§5.1's correction); his
//!   subsector horizon is the highest point in the subsector *or immediately adjacent* (§5.2). Ours (the `horizon`
//!   crate's `sector` module, crate `occlusion`) keeps the same minimum over subsectors and the same farthest-distance
//!   correction, but the subsector horizon is the vertex of greatest *slope* seen from `p` in the subsector's closed
//!   wedge (not of greatest elevation), the distance is measured along the sector's centre direction, and no
//!   neighbouring points outside the wedge are taken; a subsector with no vertex leaves the sector's region empty.
//!   Stewart's default is 64 sectors.
//! - **Memory levels (§5.3, §6).** The finest levels are the most numerous; with a byte budget the finest levels are
//!   dropped (the nodes of the finest level kept become the leaves) until the visibility bytes fit. A dropped level
//!   draws like a cell with no stored regions (§5.4: visible), so dropping its nodes outright changes no verdict.
//!   [`Quadtree::levels`] reports the bytes of every level built, stored or not.
//!
//! The bytes counted are those of `cull::Hierarchy::visibility_bytes` for the exported nodes (24 bytes per node for
//! circle, range and level, 4 per child link and per root, and `2 + 4 + 8·points` per non-empty region); the export
//! rounds regions to f32 and may only drop boundary points (on the 100k-vertex Cascades mesh at 64 sectors about 3%
//! of the bytes), so the exported hierarchy never exceeds the count here.
//!
//! [`build_without_regions`] builds the same cells, order and nodes with every region empty, without the per-vertex
//! regions (no horizons): a spatial hierarchy for the run-time cullers, which read none.
//!
//! The run-time test (§5.3, §5.4) lives in the `cull` crate (`CullMethod::Stewart`).
#![warn(missing_docs)]

use std::ops::Range;

use glam::DVec2;
use occlusion::{Region, RegionTable};
use serde::{Deserialize, Serialize};
use tin::{Circle, Tin};

/// Bits per axis of the Morton code used to order triangles (the finest depth allowed is one less).
const KEY_BITS: u32 = 21;
/// The largest finest depth.
pub const MAX_DEPTH: u32 = 16;
/// Triangles per leaf aimed at by the default depth: Stewart's finest tested quads are 8 × 8 grid cells (§6), 128
/// triangles.
pub const DEFAULT_LEAF_TRIANGLES: f64 = 128.0;

/// Bytes of one exported node without its regions and child links (centre, radius, range, level).
pub const NODE_BYTES: usize = 12 + 8 + 4;
/// Bytes of one child link or root index.
pub const LINK_BYTES: usize = 4;

/// Bytes of one exported region with `points` boundary vertices (sector, tail slope, points).
pub fn region_bytes(points: usize) -> usize {
    2 + 4 + 8 * points
}

/// Errors of [`build`] and [`build_without_regions`].
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum QuadtreeError {
    /// The terrain has no triangle.
    #[error("the terrain has no triangles")]
    Empty,
    /// The footprint has no extent, or is not finite.
    #[error("the terrain's footprint has no extent in x,y")]
    Footprint,
    /// An invalid parameter.
    #[error("invalid quadtree parameter: {0}")]
    Params(String),
    /// The region table does not belong to the terrain.
    #[error("the region table has {rows} rows but the terrain has {vertices} vertices")]
    Regions {
        /// Rows of the table.
        rows: usize,
        /// Vertices of the terrain.
        vertices: usize,
    },
    /// Not even the coarsest level fits the byte budget.
    #[error("the byte budget {budget} is below the {needed} bytes of the root cell alone")]
    Budget {
        /// The budget.
        budget: u64,
        /// Bytes of the root level.
        needed: u64,
    },
}

/// How to build the quadtree.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct QuadtreeParams {
    /// Finest depth `D` (the root is depth 0; leaves are `4^-D` of the root square). Default: the depth whose cells
    /// hold about [`DEFAULT_LEAF_TRIANGLES`] triangles on average, from the triangle count.
    pub depth: Option<u32>,
    /// Finest cell side in metres instead of `depth`: the smallest depth whose cells are at most this wide.
    pub cell: Option<f64>,
    /// Byte budget of the visibility data: the finest levels are dropped until it fits.
    pub max_bytes: Option<u64>,
}

impl QuadtreeParams {
    /// Checks the parameters on their own.
    pub fn validate(&self) -> Result<(), QuadtreeError> {
        if self.depth.is_some() && self.cell.is_some() {
            return Err(QuadtreeError::Params("give either depth or cell, not both".into()));
        }
        if let Some(d) = self.depth
            && d > MAX_DEPTH
        {
            return Err(QuadtreeError::Params(format!("depth {d} is above {MAX_DEPTH}")));
        }
        if let Some(c) = self.cell
            && !(c.is_finite() && c > 0.0)
        {
            return Err(QuadtreeError::Params(format!(
                "cell size {c} must be a positive number of metres"
            )));
        }
        Ok(())
    }

    /// The finest depth for a terrain of `triangles` triangles whose root square has side `side`.
    pub fn resolve_depth(&self, triangles: usize, side: f64) -> Result<u32, QuadtreeError> {
        self.validate()?;
        let depth = match (self.depth, self.cell) {
            (Some(d), _) => d,
            (None, Some(c)) => {
                let mut d = 0;
                while side / f64::from(1u32 << d) > c {
                    d += 1;
                    if d > MAX_DEPTH {
                        return Err(QuadtreeError::Params(format!(
                            "cell size {c} m needs more than {MAX_DEPTH} levels over a {side} m square"
                        )));
                    }
                }
                d
            }
            (None, None) => {
                let cells = (triangles as f64 / DEFAULT_LEAF_TRIANGLES).max(1.0);
                (cells.log(4.0).round() as u32).min(MAX_DEPTH)
            }
        };
        Ok(depth)
    }
}

/// One node of the quadtree: a non-empty cell.
#[derive(Clone, Debug, PartialEq)]
pub struct QuadNode {
    /// Depth of the cell (0 for the root).
    pub depth: u32,
    /// Cell coordinates `[ix, iy]` among the `2^depth × 2^depth` cells of its depth.
    pub cell: [u32; 2],
    /// Child nodes (non-empty sub-cells) in Z order; empty for a leaf.
    pub children: Vec<u32>,
    /// The node's triangles: positions in [`Quadtree::order`].
    pub range: Range<u32>,
    /// A circle enclosing every vertex of the node's triangles.
    pub circle: Circle,
    /// Per sector, the intersection of the regions of every vertex of the node's triangles (`None`: empty).
    pub regions: Vec<Option<Region>>,
}

/// Figures of one depth of the quadtree.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LevelStats {
    /// Depth (0 for the root).
    pub depth: u32,
    /// Side of its cells (m).
    pub cell_side: f64,
    /// Non-empty cells.
    pub nodes: usize,
    /// Mean triangles per node.
    pub mean_triangles: f64,
    /// Non-empty regions.
    pub regions: usize,
    /// Boundary points of those regions.
    pub region_points: usize,
    /// Visibility bytes of the level when it is stored: nodes, their regions, and the links from their parents (the
    /// root level also counts the root index).
    pub bytes: u64,
    /// Whether the level is kept (not dropped by the byte budget).
    pub stored: bool,
}

/// The quadtree, its regions and the triangle order.
#[derive(Clone, Debug)]
pub struct Quadtree {
    /// Sectors of the regions.
    pub sectors: u32,
    /// The origin of the regions' plane coordinates (that of the vertex region table).
    pub region_origin: DVec2,
    /// Lower-left corner of the root square.
    pub root_min: DVec2,
    /// Side of the root square (m).
    pub root_side: f64,
    /// The finest depth built.
    pub built_depth: u32,
    /// The finest depth kept (after the byte budget); its nodes are the leaves.
    pub stored_depth: u32,
    /// Nodes in depth-first pre-order; node 0 is the root.
    pub nodes: Vec<QuadNode>,
    /// `order[k]`: the original index of the triangle drawn `k`-th.
    pub order: Vec<u32>,
    /// Every depth built, root first.
    pub levels: Vec<LevelStats>,
}

impl Quadtree {
    /// The hierarchy level of a node: 0 for the leaves (depth [`Quadtree::stored_depth`]), the root highest.
    pub fn level(&self, node: &QuadNode) -> u32 {
        self.stored_depth - node.depth
    }

    /// Visibility bytes of the stored levels.
    pub fn stored_bytes(&self) -> u64 {
        self.levels.iter().filter(|l| l.stored).map(|l| l.bytes).sum()
    }

    /// Checks every invariant against `tin`: ranges nested and contiguous (a parent's range is its children's side
    /// by side), every triangle in exactly one leaf, every triangle's centroid in its leaf's cell, circles enclosing
    /// every vertex of their node's triangles, one region per sector.
    pub fn check_invariants(&self, tin: &Tin) -> Result<(), String> {
        let n = tin.num_triangles();
        let mut seen = vec![false; n];
        for &t in &self.order {
            let slot = seen
                .get_mut(t as usize)
                .ok_or(format!("order holds triangle {t} beyond {n}"))?;
            if std::mem::replace(slot, true) {
                return Err(format!("triangle {t} appears twice in the order"));
            }
        }
        if self.order.len() != n {
            return Err(format!("order holds {} of {n} triangles", self.order.len()));
        }
        let root = self.nodes.first().ok_or("no root")?;
        if root.range != (0..n as u32) || root.depth != 0 {
            return Err("the root does not cover every triangle".into());
        }
        let mut leaf_cover = 0usize;
        let mut parents = vec![0u32; self.nodes.len()];
        for (i, node) in self.nodes.iter().enumerate() {
            if node.regions.len() != self.sectors as usize {
                return Err(format!("node {i} has {} sectors of regions", node.regions.len()));
            }
            if node.range.is_empty() {
                return Err(format!("node {i} is empty"));
            }
            if node.children.is_empty() {
                if node.depth != self.stored_depth {
                    return Err(format!("leaf {i} is at depth {} not {}", node.depth, self.stored_depth));
                }
                leaf_cover += node.range.len();
            } else {
                let mut at = node.range.start;
                for &c in &node.children {
                    let child = self
                        .nodes
                        .get(c as usize)
                        .ok_or(format!("node {i} has a bad child {c}"))?;
                    parents[c as usize] += 1;
                    if child.range.start != at || child.depth != node.depth + 1 || c as usize <= i {
                        return Err(format!(
                            "children of node {i} are not contiguous, ordered and one deeper"
                        ));
                    }
                    if child.cell[0] >> 1 != node.cell[0] || child.cell[1] >> 1 != node.cell[1] {
                        return Err(format!("child {c} is not a sub-cell of node {i}"));
                    }
                    at = child.range.end;
                }
                if at != node.range.end {
                    return Err(format!("children of node {i} do not cover its range"));
                }
            }
            let positions = tin.positions();
            for k in node.range.clone() {
                let tri = tin.triangles()[self.order[k as usize] as usize];
                let c = centroid(tin, self.order[k as usize]);
                let cell = cell_of(c, self.root_min, self.root_side, node.depth);
                if cell != node.cell {
                    return Err(format!(
                        "triangle {} lies outside the cell of node {i}",
                        self.order[k as usize]
                    ));
                }
                for v in tri {
                    let p = positions[v as usize].truncate();
                    if p.distance(node.circle.centre) > node.circle.radius {
                        return Err(format!("the circle of node {i} misses vertex {v}"));
                    }
                }
            }
        }
        if parents.iter().skip(1).any(|&p| p != 1) || parents[0] != 0 {
            return Err("the nodes are not a tree rooted at node 0".into());
        }
        if leaf_cover != n {
            return Err(format!("the leaves cover {leaf_cover} of {n} triangles"));
        }
        Ok(())
    }
}

/// Centroid of triangle `t` in x,y.
fn centroid(tin: &Tin, t: u32) -> DVec2 {
    let p = tin.positions();
    let [a, b, c] = tin.triangles()[t as usize];
    (p[a as usize].truncate() + p[b as usize].truncate() + p[c as usize].truncate()) / 3.0
}

/// The cell `[ix, iy]` of `p` at `depth` (points on or beyond the far border go to the last cell).
fn cell_of(p: DVec2, min: DVec2, side: f64, depth: u32) -> [u32; 2] {
    let cells = f64::from(1u32 << depth);
    let last = (1u32 << depth) - 1;
    let f = |x: f64, m: f64| (((x - m) / side * cells).floor().max(0.0) as u32).min(last);
    [f(p.x, min.x), f(p.y, min.y)]
}

/// Interleaves the bits of `ix` (even bits) and `iy` (odd bits).
fn morton([ix, iy]: [u32; 2]) -> u64 {
    let spread = |v: u32| {
        let mut x = u64::from(v);
        x = (x | (x << 16)) & 0x0000_ffff_0000_ffff;
        x = (x | (x << 8)) & 0x00ff_00ff_00ff_00ff;
        x = (x | (x << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
        x = (x | (x << 2)) & 0x3333_3333_3333_3333;
        x = (x | (x << 1)) & 0x5555_5555_5555_5555;
        x
    };
    spread(ix) | (spread(iy) << 1)
}

/// A node of one depth while building: its Morton prefix, range, and children's positions in the next depth.
struct Pending {
    prefix: u64,
    range: Range<u32>,
    children: Range<u32>,
}

/// Builds the quadtree of `tin` over the per-vertex regions `vertex_regions` (one row per vertex; see the crate
/// documentation).
pub fn build(tin: &Tin, vertex_regions: &RegionTable, params: &QuadtreeParams) -> Result<Quadtree, QuadtreeError> {
    if vertex_regions.len() != tin.num_vertices() {
        return Err(QuadtreeError::Regions {
            rows: vertex_regions.len(),
            vertices: tin.num_vertices(),
        });
    }
    build_cells(tin, Some(vertex_regions), vertex_regions.sectors(), params)
}

/// The same cells, triangle order and nodes as [`build`], without regions (every node's region empty in each of
/// `sectors` sectors): a spatial hierarchy for the run-time cullers, which read none, built without the horizons.
pub fn build_without_regions(tin: &Tin, sectors: u32, params: &QuadtreeParams) -> Result<Quadtree, QuadtreeError> {
    if sectors == 0 {
        return Err(QuadtreeError::Params("a quadtree needs at least one sector".into()));
    }
    build_cells(tin, None, sectors, params)
}

/// [`build`] over `vertex_regions`, or [`build_without_regions`] when there are none.
fn build_cells(
    tin: &Tin,
    vertex_regions: Option<&RegionTable>,
    sectors: u32,
    params: &QuadtreeParams,
) -> Result<Quadtree, QuadtreeError> {
    params.validate()?;
    let n = tin.num_triangles();
    if n == 0 {
        return Err(QuadtreeError::Empty);
    }
    let bbox = tin.bbox();
    let root_min = bbox.min.truncate();
    let root_side = (bbox.max.x - bbox.min.x).max(bbox.max.y - bbox.min.y);
    if !(root_side.is_finite() && root_side > 0.0) {
        return Err(QuadtreeError::Footprint);
    }
    let depth = params.resolve_depth(n, root_side)?;

    // Triangles by Morton code of the centroid at full resolution, then by index.
    let mut keyed: Vec<(u64, u32)> = (0..n as u32)
        .map(|t| (morton(cell_of(centroid(tin, t), root_min, root_side, KEY_BITS)), t))
        .collect();
    keyed.sort_unstable();
    let order: Vec<u32> = keyed.iter().map(|&(_, t)| t).collect();

    // Depths bottom-up: runs of equal prefix.
    let shift = |d: u32| 2 * (KEY_BITS - d);
    let mut depths: Vec<Vec<Pending>> = Vec::new();
    let mut finest: Vec<Pending> = Vec::new();
    for (k, &(key, _)) in keyed.iter().enumerate() {
        let prefix = key >> shift(depth);
        match finest.last_mut() {
            Some(p) if p.prefix == prefix => p.range.end = k as u32 + 1,
            _ => finest.push(Pending {
                prefix,
                range: k as u32..k as u32 + 1,
                children: 0..0,
            }),
        }
    }
    depths.push(finest);
    for _ in 0..depth {
        let below = depths.last().map_or(&[][..], Vec::as_slice);
        let mut level: Vec<Pending> = Vec::new();
        for (c, child) in below.iter().enumerate() {
            let prefix = child.prefix >> 2;
            match level.last_mut() {
                Some(p) if p.prefix == prefix => {
                    p.range.end = child.range.end;
                    p.children.end = c as u32 + 1;
                }
                _ => level.push(Pending {
                    prefix,
                    range: child.range.clone(),
                    children: c as u32..c as u32 + 1,
                }),
            }
        }
        depths.push(level);
    }
    depths.reverse(); // depths[d] is depth d.

    // Regions bottom-up: leaves from their vertices, inner nodes from their children.
    let leaves = &depths[depth as usize];
    let mut below = match vertex_regions {
        Some(v) => {
            let triangles = tin.triangles();
            let leaf_vertices: Vec<Vec<u32>> = leaves
                .iter()
                .map(|p| {
                    let mut v: Vec<u32> = order[p.range.start as usize..p.range.end as usize]
                        .iter()
                        .flat_map(|&t| triangles[t as usize])
                        .collect();
                    v.sort_unstable();
                    v.dedup();
                    v
                })
                .collect();
            v.intersect_rows(leaf_vertices.len(), |l| leaf_vertices[l].iter().copied())
        }
        None => RegionTable::from_rows(sectors, DVec2::ZERO, vec![None; leaves.len() * sectors as usize]),
    };
    let mut tables: Vec<RegionTable> = Vec::with_capacity(depth as usize + 1);
    for d in (0..depth as usize).rev() {
        let level = &depths[d];
        let table = below.intersect_rows(level.len(), |e| level[e].children.clone());
        tables.push(std::mem::replace(&mut below, table));
    }
    tables.push(below);
    tables.reverse();

    // Level figures and the byte budget.
    let mut levels: Vec<LevelStats> = depths
        .iter()
        .enumerate()
        .map(|(d, level)| {
            let table = &tables[d];
            let (mut regions, mut points, mut region_bytes_sum) = (0usize, 0usize, 0usize);
            for e in 0..level.len() as u32 {
                for r in table.row(e).iter().flatten() {
                    regions += 1;
                    points += r.points().len();
                    region_bytes_sum += region_bytes(r.points().len());
                }
            }
            let links = LINK_BYTES * level.len(); // from the parents, or the root index
            LevelStats {
                depth: d as u32,
                cell_side: root_side / f64::from(1u32 << d),
                nodes: level.len(),
                mean_triangles: n as f64 / level.len() as f64,
                regions,
                region_points: points,
                bytes: (NODE_BYTES * level.len() + links + region_bytes_sum) as u64,
                stored: true,
            }
        })
        .collect();
    let mut stored_depth = depth;
    if let Some(budget) = params.max_bytes {
        let root = levels[0].bytes;
        if root > budget {
            return Err(QuadtreeError::Budget { budget, needed: root });
        }
        while levels.iter().filter(|l| l.stored).map(|l| l.bytes).sum::<u64>() > budget {
            levels[stored_depth as usize].stored = false;
            stored_depth -= 1;
        }
    }

    // Nodes in depth-first pre-order down to the stored depth.
    let mut nodes: Vec<QuadNode> = Vec::new();
    let mut stack: Vec<(u32, u32, Option<usize>)> = vec![(0, 0, None)];
    while let Some((d, e, parent)) = stack.pop() {
        let p = &depths[d as usize][e as usize];
        let id = nodes.len();
        if let Some(parent) = parent {
            nodes[parent].children.push(id as u32);
        }
        let tri_range = p.range.start as usize..p.range.end as usize;
        let circle = tin
            .bounding_circle(order[tri_range].iter().copied())
            .ok_or(QuadtreeError::Empty)?;
        let prefix = p.prefix;
        let (mut ix, mut iy) = (0u32, 0u32);
        for b in 0..d {
            ix |= (((prefix >> (2 * b)) & 1) as u32) << b;
            iy |= (((prefix >> (2 * b + 1)) & 1) as u32) << b;
        }
        nodes.push(QuadNode {
            depth: d,
            cell: [ix, iy],
            children: Vec::new(),
            range: p.range.clone(),
            circle,
            regions: tables[d as usize].row(e).to_vec(),
        });
        if d < stored_depth {
            for c in p.children.clone().rev() {
                stack.push((d + 1, c, Some(id)));
            }
        }
    }
    Ok(Quadtree {
        sectors,
        region_origin: vertex_regions.map_or(DVec2::ZERO, RegionTable::origin),
        root_min,
        root_side,
        built_depth: depth,
        stored_depth,
        nodes,
        order,
        levels,
    })
}
