//! From-region visibility on TIN terrains: the potentially visible set (PVS) of a viewcell, after Koltun,
//! Chrysanthou & Cohen-Or (2001), "Hardware-accelerated from-region visibility using a dual ray space".
//!
//! A viewcell is an axis-parallel box over x,y with a height band (absolute, or above the ground). Its PVS is the
//! set of triangle ranges (in the hierarchy's triangle order, the order of `tincull export --obj`) that may be visible
//! from some point of the cell: a superset of the truly visible set, never missing a visible triangle.
//!
//! | test | module | verdict "hidden" for a node |
//! | --- | --- | --- |
//! | `koltun` | [`koltun`] | the node's box is hidden from the cell's box in the dual ray space of the plane over their upper rims (§4, §5.2), with 2.5-D wall occluders under the TIN's edges |
//! | `regions` | [`regions`] | the cell box lies in the node's conservative precomputed region in every sector the cell–node directions touch |
//! | `both` | | either of the two |
//!
//! The traversal ([`Pvs::compute`]) is top-down over a hierarchy of boxes: the `.tch` hierarchy's nodes (their
//! triangles' x,y bounding boxes and highest vertex, computed in f64 from the mesh), and below each leaf and below the
//! always-visible set a binary tree obtained by halving the triangle range down to `patch` triangles (the build lays
//! these ranges out in a spatial order). A hidden node's subtree is skipped; a visible patch joins the PVS. Each
//! verdict is one of the theorems above, so the PVS contains every visible triangle.
//!
//! Departures from the paper: occluders are walls derived from the TIN, not given boxes; the ray space is covered by
//! connected wall pieces rather than single segments (see [`koltun`]); the rasterisation is in software (exact
//! per-pixel extremes, no GPU); the exact analytic union of §5.1 is not implemented.
#![warn(missing_docs)]

pub mod check;
pub mod format;
pub mod koltun;
pub mod regions;

use std::sync::Arc;
use std::time::Instant;

use cull::Hierarchy;
use serde::{Deserialize, Serialize};

pub use check::{CellCheck, check_cell, sample_eyes};
pub use format::{CellRecord, FORMAT_VERSION, MAGIC, PvsFile};
pub use koltun::{Box3, MAX_RESOLUTION};

/// Errors of this crate.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PvsError {
    /// A viewcell or height band that is empty, inverted or not finite.
    #[error("invalid viewcell: {0}")]
    BadCell(String),
    /// A resolution outside 1..=256.
    #[error("the resolution must be from 1 to {MAX_RESOLUTION}, got {0}")]
    BadResolution(u32),
    /// A `.pvs` file that cannot be read.
    #[error("not a readable PVS file: {0}")]
    BadFile(String),
}

/// Most cells of a [`Pvs::grid`]: a million PVSs take hours on a large terrain, and the file grows with them.
pub const MAX_GRID_CELLS: usize = 1_000_000;

/// How the viewcell's height is given (in JSON `{"band": [z0, z1]}` or `{"above_ground": [h0, h1]}`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Height {
    /// Absolute heights `[z0, z1]` (m).
    Band([f64; 2]),
    /// Heights above the ground under each point of the cell `[h0, h1]` (m).
    AboveGround([f64; 2]),
}

impl std::fmt::Display for Height {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Height::Band([z0, z1]) => write!(f, "heights {z0} to {z1} m"),
            Height::AboveGround([h0, h1]) => write!(f, "{h0} to {h1} m above the ground"),
        }
    }
}

/// Which from-region test decides that a node is hidden.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Method {
    /// Koltun et al.'s test in the dual ray space ([`koltun`]).
    Koltun,
    /// The conservative precomputed regions ([`regions`]).
    Regions,
    /// Hidden if either says so.
    Both,
}

impl Method {
    /// All methods, in the order of reports.
    pub const ALL: [Method; 3] = [Method::Koltun, Method::Regions, Method::Both];

    /// The name in reports and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Method::Koltun => "koltun",
            Method::Regions => "regions",
            Method::Both => "both",
        }
    }

    /// The method of a name.
    pub fn from_name(s: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == s)
    }
}

/// A viewcell: its x,y rectangle (world coordinates) and its height specification.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewCell {
    /// `[x0, y0, x1, y1]`, `x0 < x1`, `y0 < y1`.
    pub rect: [f64; 4],
    /// The height band.
    pub height: Height,
}

/// A rectangle `x0,y0,x1,y1` for messages, each number as short as it reads exactly (`1e300`, not 301 digits).
fn rect_text(rect: [f64; 4]) -> String {
    rect.map(tin::compact_number).join(",")
}

impl ViewCell {
    /// Checks the rectangle and the band (finite, non-empty, ordered).
    pub fn validate(&self) -> Result<(), PvsError> {
        let [x0, y0, x1, y1] = self.rect;
        if !(self.rect.iter().all(|v| v.is_finite()) && x0 < x1 && y0 < y1) {
            return Err(PvsError::BadCell(format!(
                "the rectangle {} must be finite with x0 < x1 and y0 < y1",
                rect_text(self.rect)
            )));
        }
        self.height.validate()
    }
}

impl Height {
    /// Checks the band: two finite values, the lower first.
    pub fn validate(&self) -> Result<(), PvsError> {
        let ([a, b], what) = match *self {
            Height::Band(z) => (z, "height band"),
            Height::AboveGround(h) => (h, "height above ground"),
        };
        if !(a.is_finite() && b.is_finite() && a <= b) {
            return Err(PvsError::BadCell(format!(
                "the {what} {a},{b} must be two finite values, the lower first"
            )));
        }
        if matches!(self, Height::AboveGround(_)) && a < 0.0 {
            return Err(PvsError::BadCell(format!(
                "the {what} {a},{b} must be 0 or more: an eye below the ground sees none of the terrain"
            )));
        }
        Ok(())
    }
}

/// Parameters of the PVS computation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PvsParams {
    /// Which test culls.
    pub method: Method,
    /// Resolution `R` of the ray-space bitmap (`R × R`, 1..=256).
    pub resolution: u32,
    /// Largest patch (triangles) of the halving trees below the hierarchy's leaves.
    pub patch: u32,
}

impl Default for PvsParams {
    fn default() -> Self {
        PvsParams {
            method: Method::Both,
            resolution: 64,
            patch: 16,
        }
    }
}

/// The PVS of one viewcell.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CellPvs {
    /// Hierarchy nodes not proven hidden (each may hold visible triangles), increasing.
    pub nodes: Vec<u32>,
    /// Triangle ranges `[start, end)` that may be visible, increasing and merged, in the hierarchy's triangle order.
    pub ranges: Vec<[u32; 2]>,
    /// The cell box's top used (m).
    pub ztop: f64,
    /// Boxes tested.
    pub tests: u64,
    /// Seconds of the computation.
    pub seconds: f64,
}

impl CellPvs {
    /// Number of triangles in the PVS.
    pub fn triangles(&self) -> u64 {
        self.ranges.iter().map(|r| u64::from(r[1] - r[0])).sum()
    }

    /// A per-triangle mask of the PVS over `n` triangles.
    pub fn mask(&self, n: usize) -> Vec<bool> {
        let mut m = vec![false; n];
        for r in &self.ranges {
            let (a, b) = ((r[0] as usize).min(n), (r[1] as usize).min(n));
            m[a..b.max(a)].iter_mut().for_each(|x| *x = true);
        }
        m
    }
}

/// `h` with conservative regions (`pipeline::conservative_hierarchy`), as the regions test needs them: seconds at
/// 10k vertices, minutes at 100k.
pub fn conservative_regions(h: &Hierarchy) -> Hierarchy {
    pipeline::conservative_hierarchy(h)
}

/// One node of the box tree.
#[derive(Clone, Copy, Debug)]
struct TreeNode {
    bounds: Box3,
    range: [u32; 2],
    kids: [u32; 2],
    /// The hierarchy node, or `u32::MAX` below the leaves.
    hier: u32,
}

/// The box of no triangle: the identity of [`union`].
const EMPTY_BOX: Box3 = Box3 {
    lo: [f64::INFINITY; 2],
    hi: [f64::NEG_INFINITY; 2],
    ztop: f64::NEG_INFINITY,
};

/// The smallest box holding `a` and `b` (exact: min and max), with the higher top.
fn union(a: Box3, b: Box3) -> Box3 {
    Box3 {
        lo: [a.lo[0].min(b.lo[0]), a.lo[1].min(b.lo[1])],
        hi: [a.hi[0].max(b.hi[0]), a.hi[1].max(b.hi[1])],
        ztop: a.ztop.max(b.ztop),
    }
}

/// [`Pvs::node_boxes`] over `nodes`, with `scan` giving the box of a triangle range.
fn node_boxes(nodes: &[cull::Node], mut scan: impl FnMut([u32; 2]) -> Box3) -> Vec<Box3> {
    let mut order: Vec<usize> = (0..nodes.len()).collect();
    order.sort_by_key(|&i| nodes[i].level);
    let mut boxes: Vec<Option<Box3>> = vec![None; nodes.len()];
    for i in order {
        let node = &nodes[i];
        let [s, e] = node.triangles;
        let mut at = s;
        let mut joined = (!node.children.is_empty()).then_some(EMPTY_BOX);
        for &c in &node.children {
            let c = c as usize;
            match (nodes.get(c), boxes.get(c).copied().flatten(), joined) {
                (Some(child), Some(b), Some(u)) if child.triangles[0] == at => {
                    at = child.triangles[1];
                    joined = Some(union(u, b));
                }
                _ => joined = None,
            }
        }
        boxes[i] = Some(match joined {
            Some(u) if at == e => u,
            _ => scan(node.triangles),
        });
    }
    boxes.into_iter().map(|b| b.unwrap_or(EMPTY_BOX)).collect()
}

/// The PVS computer of one hierarchy: its box tree, its walls and (for the regions test) its conservative regions.
pub struct Pvs<'a> {
    h: &'a Hierarchy,
    params: PvsParams,
    nodes: Vec<TreeNode>,
    children: Vec<u32>,
    roots: Vec<u32>,
    walls: koltun::Walls,
    conservative: Option<Arc<Hierarchy>>,
    /// The eyes for which the conservative regions' margin is far above the checker's tolerance.
    regions_reach: truth::MarginReach,
    /// The mesh's lowest height (the ground under a cell given above the ground lies above it).
    zmin: f64,
}

impl<'a> Pvs<'a> {
    /// Prepares the PVS computation over `h` (which must satisfy [`Hierarchy::check_invariants`], as every loaded
    /// file does). With the regions test, computes the conservative regions first (seconds on 100k vertices).
    pub fn new(h: &'a Hierarchy, params: PvsParams) -> Result<Pvs<'a>, PvsError> {
        // The parameters before the regions' seconds of work.
        if !(1..=MAX_RESOLUTION).contains(&params.resolution) {
            return Err(PvsError::BadResolution(params.resolution));
        }
        let needs = matches!(params.method, Method::Regions | Method::Both);
        Pvs::with_regions(h, params, needs.then(|| Arc::new(conservative_regions(h))))
    }

    /// [`Pvs::new`] with the conservative regions already computed ([`conservative_regions`] of `h`), so that
    /// several computers share them; without them the regions test hides nothing.
    pub fn with_regions(
        h: &'a Hierarchy,
        params: PvsParams,
        conservative: Option<Arc<Hierarchy>>,
    ) -> Result<Pvs<'a>, PvsError> {
        if !(1..=MAX_RESOLUTION).contains(&params.resolution) {
            return Err(PvsError::BadResolution(params.resolution));
        }
        let params = PvsParams {
            patch: params.patch.max(1),
            ..params
        };
        let mut pvs = Pvs {
            h,
            params,
            nodes: Vec::with_capacity(h.nodes.len()),
            children: Vec::new(),
            roots: Vec::new(),
            walls: koltun::Walls::new(&h.mesh.positions, &h.mesh.triangles),
            conservative,
            regions_reach: {
                let (mu, lo, hi) = pipeline::conservative_margin(h);
                truth::MarginReach::new(mu, lo, hi)
            },
            zmin: h.mesh.positions.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min),
        };
        for (i, (node, bounds)) in h.nodes.iter().zip(pvs.node_boxes()).enumerate() {
            pvs.nodes.push(TreeNode {
                bounds,
                range: node.triangles,
                kids: [0, 0],
                hier: i as u32,
            });
        }
        let mut kids: Vec<Vec<u32>> = h.nodes.iter().map(|n| n.children.clone()).collect();
        for (i, node) in h.nodes.iter().enumerate() {
            if node.children.is_empty() {
                kids[i] = pvs.halve(node.triangles);
            }
        }
        for (i, k) in kids.into_iter().enumerate() {
            let start = pvs.children.len() as u32;
            pvs.children.extend(k);
            pvs.nodes[i].kids = [start, pvs.children.len() as u32];
        }
        let mut roots = h.roots.clone();
        roots.sort_by_key(|&r| h.nodes[r as usize].triangles[0]);
        let [a, b] = h.always_visible;
        if a < b {
            roots.push(pvs.subtree([a, b]));
        }
        pvs.roots = roots;
        Ok(pvs)
    }

    /// The parameters in use.
    pub fn params(&self) -> PvsParams {
        self.params
    }

    /// The halving children of range `r` (none when it is a patch).
    fn halve(&mut self, r: [u32; 2]) -> Vec<u32> {
        if r[1] - r[0] <= self.params.patch {
            return Vec::new();
        }
        let mid = r[0] + (r[1] - r[0]) / 2;
        vec![self.subtree([r[0], mid]), self.subtree([mid, r[1]])]
    }

    /// A halving subtree over `r`; returns its root.
    fn subtree(&mut self, r: [u32; 2]) -> u32 {
        let kids = self.halve(r);
        let start = self.children.len() as u32;
        self.children.extend(kids);
        let id = self.nodes.len() as u32;
        // The two halves tile `r`, so their union is the scan of `r` (min and max are exact): O(r) in all, not
        // O(r log r).
        let bounds = match self.children[start as usize..] {
            [a, b] => union(self.nodes[a as usize].bounds, self.nodes[b as usize].bounds),
            _ => self.bounds(r),
        };
        self.nodes.push(TreeNode {
            bounds,
            range: r,
            kids: [start, self.children.len() as u32],
            hier: u32::MAX,
        });
        id
    }

    /// The box of every hierarchy node ([`Pvs::bounds`] of its range), bottom-up: a leaf's from its triangles, an
    /// inner node's as the union of its children's boxes. On a hierarchy that satisfies
    /// [`Hierarchy::check_invariants`], children have lower levels than their parent and tile its range in order, so
    /// taking nodes by increasing level finds every child's box ready, and the union is the scan of the parent's
    /// range regrouped (min and max of the same f64 values: the same numbers). Each triangle is then scanned once, for
    /// its leaf, and the whole costs O(nodes log nodes + triangles), where a scan per node would cost the sum of the
    /// ranges: quadratic on a chain of nodes of one child each over the same triangles. A node whose children are not
    /// ready or do not tile its range (only in a hierarchy that breaks the invariants) is scanned as before.
    fn node_boxes(&self) -> Vec<Box3> {
        node_boxes(&self.h.nodes, |r| self.bounds(r))
    }

    /// The x,y box and highest vertex of triangles `r` (exact: min and max of f64 values).
    fn bounds(&self, r: [u32; 2]) -> Box3 {
        let mut b = EMPTY_BOX;
        for t in &self.h.mesh.triangles[r[0] as usize..r[1] as usize] {
            for &v in t {
                let p = self.h.mesh.positions[v as usize];
                b.lo = [b.lo[0].min(p[0]), b.lo[1].min(p[1])];
                b.hi = [b.hi[0].max(p[0]), b.hi[1].max(p[1])];
                b.ztop = b.ztop.max(p[2]);
            }
        }
        b
    }

    /// The lowest and the highest vertex of the triangles whose x,y boxes meet the rectangle `[x0, y0, x1, y1]`
    /// (every ground height under it lies between them), and the highest vertex of the whole mesh; `None` for the
    /// first when no triangle's box meets the rectangle.
    fn ground_under(&self, [x0, y0, x1, y1]: [f64; 4]) -> (Option<[f64; 2]>, f64) {
        let pos = &self.h.mesh.positions;
        let (mut lo, mut hi, mut all) = (f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
        for t in &self.h.mesh.triangles {
            let c = t.map(|v| pos[v as usize]);
            let tz = c[0][2].max(c[1][2]).max(c[2][2]);
            all = all.max(tz);
            let (lx, hx) = (c[0][0].min(c[1][0]).min(c[2][0]), c[0][0].max(c[1][0]).max(c[2][0]));
            let (ly, hy) = (c[0][1].min(c[1][1]).min(c[2][1]), c[0][1].max(c[1][1]).max(c[2][1]));
            if lx <= x1 && hx >= x0 && ly <= y1 && hy >= y0 {
                hi = hi.max(tz);
                lo = lo.min(c[0][2].min(c[1][2]).min(c[2][2]));
            }
        }
        ((lo <= hi).then_some([lo, hi]), all)
    }

    /// Checks that a viewcell a person gave lies where its heights make sense: a cell given in heights above the
    /// ground must meet the terrain's footprint (there is no ground elsewhere), and a cell given as an absolute band
    /// must not lie wholly below the terrain under it (an eye below the ground sees none of the terrain). A grid's
    /// cells are not checked: they cover the footprint's bounding box, whose corners may hold no terrain.
    pub fn check_over_terrain(&self, cell: &ViewCell) -> Result<(), PvsError> {
        cell.validate()?;
        let (ground, _) = self.ground_under(cell.rect);
        match (cell.height, ground) {
            (Height::AboveGround(_), None) => Err(PvsError::BadCell(format!(
                "the cell {} lies off the terrain: heights above the ground need ground under the cell (give an \
                 absolute band for a cell beside the terrain)",
                rect_text(cell.rect)
            ))),
            (Height::Band([_, z1]), Some([lo, _])) if z1 < lo => Err(PvsError::BadCell(format!(
                "the height band up to {z1} m lies below the terrain under the cell {} (its lowest vertex there is \
                 at {lo} m): an eye below the ground sees none of the terrain",
                rect_text(cell.rect)
            ))),
            _ => Ok(()),
        }
    }

    /// The box of `cell`: its rectangle, and the top of its band (for heights above ground: the highest vertex of
    /// the triangles whose boxes meet the rectangle, or of the whole mesh when none does, plus `h1`; rounded up).
    pub fn cell_box(&self, cell: &ViewCell) -> Result<Box3, PvsError> {
        cell.validate()?;
        let [x0, y0, x1, y1] = cell.rect;
        let ztop = match cell.height {
            Height::Band([_, z1]) => z1,
            Height::AboveGround([_, h1]) => {
                let (ground, all) = self.ground_under(cell.rect);
                (ground.map_or(all, |[_, hi]| hi) + h1).next_up()
            }
        };
        if !ztop.is_finite() {
            return Err(PvsError::BadCell("the cell's top is not finite (empty mesh?)".into()));
        }
        Ok(Box3 {
            lo: [x0, y0],
            hi: [x1, y1],
            ztop,
        })
    }

    /// The PVS of `cell`.
    pub fn compute(&self, cell: &ViewCell) -> Result<CellPvs, PvsError> {
        let start = Instant::now();
        let a = self.cell_box(cell)?;
        // The cell's eyes as a box: its rectangle, from its lowest possible eye to its top. Each test judges the cell
        // only when its margin is far above the exact checker's tolerance from all of them (`truth::MarginReach`);
        // from a cell farther away, every node is visible.
        let zlo = match cell.height {
            Height::Band([z0, _]) => z0.min(self.zmin),
            Height::AboveGround([h0, _]) => self.zmin + h0.min(0.0),
        };
        let eyes = ([a.lo[0], a.lo[1], zlo], [a.hi[0], a.hi[1], a.ztop]);
        let judged = [
            self.walls.reach.covers(eyes.0, eyes.1),
            self.regions_reach.covers(eyes.0, eyes.1),
        ];
        let mut scratch = self.walls.scratch();
        let mut out = CellPvs {
            ztop: a.ztop,
            ..CellPvs::default()
        };
        let mut stack: Vec<u32> = self.roots.iter().rev().copied().collect();
        while let Some(id) = stack.pop() {
            let node = &self.nodes[id as usize];
            if node.range[0] == node.range[1] {
                continue;
            }
            out.tests += 1;
            if self.hidden(id, &a, judged, &mut scratch) {
                continue;
            }
            if node.hier != u32::MAX {
                out.nodes.push(node.hier);
            }
            let kids = &self.children[node.kids[0] as usize..node.kids[1] as usize];
            if kids.is_empty() {
                match out.ranges.last_mut() {
                    Some(last) if last[1] == node.range[0] => last[1] = node.range[1],
                    _ => out.ranges.push(node.range),
                }
            } else {
                stack.extend(kids.iter().rev());
            }
        }
        out.nodes.sort_unstable();
        out.ranges.sort_unstable();
        let mut merged: Vec<[u32; 2]> = Vec::with_capacity(out.ranges.len());
        for r in out.ranges.drain(..) {
            match merged.last_mut() {
                Some(last) if last[1] >= r[0] => last[1] = last[1].max(r[1]),
                _ => merged.push(r),
            }
        }
        out.ranges = merged;
        out.seconds = start.elapsed().as_secs_f64();
        Ok(out)
    }

    /// Whether node `id` is hidden from the cell `a`, by the tests that `judged` (Koltun's, the regions') allows.
    fn hidden(&self, id: u32, a: &Box3, judged: [bool; 2], scratch: &mut koltun::Scratch) -> bool {
        let node = &self.nodes[id as usize];
        let by_regions = |_: ()| {
            judged[1]
                && node.hier != u32::MAX
                && self
                    .conservative
                    .as_ref()
                    .is_some_and(|c| regions::hidden_by_regions(c, node.hier as usize, a))
        };
        let by_koltun = |scratch: &mut koltun::Scratch| {
            judged[0] && self.walls.hidden(a, &node.bounds, self.params.resolution, scratch)
        };
        match self.params.method {
            Method::Koltun => by_koltun(scratch),
            Method::Regions => by_regions(()),
            Method::Both => by_regions(()) || by_koltun(scratch),
        }
    }

    /// The cells of a grid of `size` × `size` over the footprint's bounding box (row by row from the lowest corner;
    /// the last row and column are cut at the footprint).
    pub fn grid(&self, size: f64, height: Height) -> Result<Vec<ViewCell>, PvsError> {
        if !(size.is_finite() && size > 0.0) {
            return Err(PvsError::BadCell(format!(
                "grid size {size} must be finite and positive"
            )));
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &self.h.mesh.positions {
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
        if !(lo[0] < hi[0] && lo[1] < hi[1]) {
            return Err(PvsError::BadCell("the mesh has an empty footprint".into()));
        }
        let nx = ((hi[0] - lo[0]) / size).ceil().max(1.0);
        let ny = ((hi[1] - lo[1]) / size).ceil().max(1.0);
        if nx * ny > MAX_GRID_CELLS as f64 {
            return Err(PvsError::BadCell(format!(
                "a grid of {} m gives {} x {} cells, more than {MAX_GRID_CELLS} (each cell's PVS takes \
                 milliseconds or more); give a larger size",
                tin::compact_number(size),
                tin::compact_number(nx),
                tin::compact_number(ny)
            )));
        }
        let mut cells = Vec::new();
        for j in 0..ny as usize {
            for i in 0..nx as usize {
                let x0 = lo[0] + size * i as f64;
                let y0 = lo[1] + size * j as f64;
                let rect = [x0, y0, (x0 + size).min(hi[0]), (y0 + size).min(hi[1])];
                if rect[0] < rect[2] && rect[1] < rect[3] {
                    cells.push(ViewCell { rect, height });
                }
            }
        }
        Ok(cells)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cull::Node;

    fn node(children: Vec<u32>, triangles: [u32; 2], level: u32) -> Node {
        Node {
            centre: [0.0; 2],
            radius: 0.0,
            children,
            triangles,
            level,
            regions: vec![],
        }
    }

    /// Triangle `t`'s box: an arbitrary, irregular function of `t`.
    fn triangle_box(t: u32) -> Box3 {
        let f = f64::from(t);
        Box3 {
            lo: [(f * 0.37).sin() * 100.0, (f * 0.11).cos() * 50.0],
            hi: [
                (f * 0.37).sin() * 100.0 + 1.0 + (f * 0.5).cos(),
                (f * 0.11).cos() * 50.0 + 2.0,
            ],
            ztop: (f * 0.23).sin() * 10.0,
        }
    }

    /// The box of range `r` by scanning it, counting the triangles scanned.
    fn scan(r: [u32; 2], count: &mut u64) -> Box3 {
        *count += u64::from(r[1] - r[0]);
        (r[0]..r[1]).map(triangle_box).fold(EMPTY_BOX, union)
    }

    fn bits(b: &Box3) -> [u64; 5] {
        [b.lo[0], b.lo[1], b.hi[0], b.hi[1], b.ztop].map(f64::to_bits)
    }

    /// On a chain of 10,000 nodes of one child each over 1,000 triangles, the boxes are built bottom-up: the
    /// triangles are scanned once (for the leaf), not once per node (the audit's F2: O(nodes × triangles)), and every
    /// box is bit for bit the scan of its node's range.
    #[test]
    fn node_boxes_scan_each_triangle_once_on_a_chain() {
        let (depth, nt) = (10_000u32, 1_000u32);
        let mut nodes = vec![node(vec![], [0, nt], 0)];
        for k in 1..=depth {
            nodes.push(node(vec![k - 1], [0, nt], k));
        }
        let mut scanned = 0u64;
        let boxes = node_boxes(&nodes, |r| scan(r, &mut scanned));
        assert_eq!(scanned, u64::from(nt), "each triangle scanned once");
        let mut dummy = 0;
        let whole = bits(&scan([0, nt], &mut dummy));
        assert!(boxes.iter().all(|b| bits(b) == whole));
    }

    /// A bushier hierarchy, nodes listed in a scrambled order, with empty ranges and a chain inside: every box equals
    /// the direct scan bit for bit, with each triangle scanned once; a node whose children break the invariants is
    /// scanned directly.
    #[test]
    fn node_boxes_equal_direct_scans() {
        // Leaves [0,10) [10,10) [10,25) [25,40); inner 4 = {0, 1}, 5 = {4, 2}, chain 6 = {5}, 7 = {6, 3}.
        let nodes = vec![
            node(vec![], [0, 10], 0),
            node(vec![], [10, 10], 0),
            node(vec![], [10, 25], 0),
            node(vec![], [25, 40], 0),
            node(vec![0, 1], [0, 10], 1),
            node(vec![4, 2], [0, 25], 2),
            node(vec![5], [0, 25], 3),
            node(vec![6, 3], [0, 40], 4),
        ];
        // A scrambled order of the same nodes (children renumbered).
        let perm = [5usize, 2, 7, 0, 3, 6, 1, 4];
        let mut inv = [0u32; 8];
        for (new, &old) in perm.iter().enumerate() {
            inv[old] = new as u32;
        }
        let scrambled: Vec<Node> = perm
            .iter()
            .map(|&old| {
                let n = &nodes[old];
                node(
                    n.children.iter().map(|&c| inv[c as usize]).collect(),
                    n.triangles,
                    n.level,
                )
            })
            .collect();
        for list in [&nodes, &scrambled] {
            let mut scanned = 0u64;
            let boxes = node_boxes(list, |r| scan(r, &mut scanned));
            assert_eq!(scanned, 40);
            for (n, b) in list.iter().zip(&boxes) {
                let mut dummy = 0;
                assert_eq!(bits(b), bits(&scan(n.triangles, &mut dummy)), "{:?}", n.triangles);
            }
        }
        // Children that do not tile the range: the node is scanned.
        let broken = vec![node(vec![], [0, 10], 0), node(vec![0], [0, 20], 1)];
        let mut scanned = 0u64;
        let boxes = node_boxes(&broken, |r| scan(r, &mut scanned));
        let mut dummy = 0;
        assert_eq!(bits(&boxes[1]), bits(&scan([0, 20], &mut dummy)));
        assert_eq!(scanned, 30);
    }
}
