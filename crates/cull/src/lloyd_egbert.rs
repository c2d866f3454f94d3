//! Lloyd & Egbert's horizon culling (2002) adapted to a TIN: the hierarchy traversed front to back, cell edges as
//! occluders, node bounding boxes as occludees, over the conservative 1-D horizon of [`crate::horizon`]; and the
//! argument why it never culls a visible triangle.
//!
//! ## What is built when the culler is prepared
//!
//! - **The grid.** The root square of the quadtree (`crates/quadtree`): lower-left corner the mesh's lowest x,y,
//!   side the larger extent; `n = 2^d` cells a side with `d` the hierarchy's stored depth (its leaves are these
//!   cells), at most [`MAX_GRID_DEPTH`]. Over a crystal hierarchy (no cells) `d` is the depth at which there are at
//!   least as many cells as leaf groups; `d` is at least 1 (2 × 2 cells) in both. The culler works on both, only the
//!   quadtree is Lloyd & Egbert's.
//! - **Occluders (§4.2).** For every cell edge (a segment of a grid line between two neighbouring grid corners,
//!   shared by the two cells it separates), the TIN's exact profile along it: the edge cuts every triangle it
//!   crosses in a chord on which the height is linear, so the profile is piecewise linear with breakpoints where the
//!   line crosses mesh edges and at the edge's ends. Over each stretch of the edge that the TIN covers, one straight
//!   line under the profile: the supporting line of the profile's lower convex hull at the stretch's middle (of all
//!   lines below the profile it has the largest mean height), lowered by its rounding bound (below). A 3-D segment
//!   on or below the terrain.
//! - **Occludees.** Every node's bounding box: the x,y box of the vertices of its triangles (which stick out of the
//!   cell: triangles are assigned by centroid) and their highest vertex `z_max`. Its top face (two triangles at
//!   `z_max`) is what is tested: a point of the box is below the top-face point above it, so on every sight line
//!   from the camera it is lower too.
//!
//! They are computed here, from the hierarchy's mesh, not stored in the `.tch`: a profile is exact and cheap
//! (`precompute_time`: a fraction of a second at 100k triangles, one pass over the triangles), the file stays what
//! every method reads, and the grid can follow the hierarchy.
//!
//! ## One cull (§4.1, §4.3–4.4)
//!
//! Nodes are taken nearest first, by the least horizontal distance `d_min` of their box from the camera (a child's
//! box lies in its parent's, so `d_min` never decreases along the traversal). For the four children of a quadtree
//! cell this is the order of the paper's Fig. 2: the child nearest the camera first, the farthest last, and a child
//! is never taken after one that lies entirely beyond it. Before a node is tested, every pending occluder whose
//! greatest distance `d_max` from the camera (an end point's) is below the node's `d_min` is written into the
//! horizon (conservative scan conversion: each column it spans gets a lower bound of its height there; see
//! [`crate::horizon`]). A node is then
//!
//! - *culled by the frustum* when its box's bounding circle lies outside the horizontal view (cameras have no
//!   pitch, so the view's azimuth range needs no widening);
//! - *visible* when the camera's x,y is inside its box;
//! - *hidden* when both triangles of its box's top face (raised by `μ`) are strictly below the horizon in every
//!   column they touch (tried first with the box's bounding disk at the face's height, which contains the face);
//!   a hidden node is not drawn and its descendants are not looked at;
//! - otherwise an inner node queues its children, and a leaf is drawn and the occluders on the edges of its cell
//!   become pending (over a crystal hierarchy: of the grid cells its box meets).
//!
//! The horizon has `4 w` columns (`w` per 90° face, the `columns` parameter): the cylindrical 360° buffer, used
//! whatever the field of view (a view of `φ` radians spans about `w φ / (π/2)` of them, its image width).
//!
//! ## Why a culled triangle is hidden
//!
//! Let node `N` be culled as hidden, `D` its `d_min`, and `t` one of its triangles. Every occluder written so far is
//! a segment `S` with (i) every point at or below the terrain surface at its x,y, and (ii) every point at a
//! horizontal distance from the camera below `D`, since `d_max(S) < D` and a segment's farthest point is an end.
//! Written with the height margin `μ` (points `μ` below `S`), the horizon's invariant holds for them (its proof asks
//! only that every occluder point lie on or below the terrain: the triangle case of [`crate::horizon`] applied to
//! the degenerate triangle `S, S`). Every point `p` of `t` has its x,y in `N`'s box and `p.z ≤ z_max`, so `p` is at
//! distance `≥ D` and lies below the point `p'` of the top face above it. The top face is at distance `≥ D` and
//! strictly below the horizon in each column it touches (tested with its heights raised by `μ`), so by the horizon's
//! theorem the sight line from `p'` passes below the terrain, more than `μ` below, at the x,y of an occluder point.
//! The sight line from `p` lies below that from `p'` at every distance (both end at the camera, `p.z ≤ p'.z`), so
//! it is blocked too. Nodes never tested lie below a hidden ancestor, whose box contains theirs. Nothing in this
//! argument depends on which nodes were drawn or in what order; the order only decides how much is culled.
//!
//! **(i) holds, rounding included.** The profile's breakpoints are computed, not exact: a crossing of grid line `x =
//! X` with mesh edge `AB` (the edge always taken from its lower vertex index, so both triangles at the edge compute
//! the same bits) is `s = (X − A.x) / (B.x − A.x)`, `t = A.y + s (B.y − A.y)`, `z = A.z + s (B.z − A.z)`: a few
//! roundings each, so `|t − t_true| ≤ δt = ERR (|A.y| + |B.y|)` and `|z − z_true| ≤ δz = ERR (|A.z| + |B.z|)` with
//! `ERR = 1e-14` (about 90 ε; the operations cost under 10 ε). Vertices on the line are taken exactly. A chord from
//! computed end `t_0` to `t_1` is cut at a grid corner `r` only when `t_0 + δt_0 < r < t_1 − δt_1`, so that the true
//! chord surely passes the corner (cutting a chord whose end lay within `δt` of the corner claimed a corner the TIN
//! might not reach, and two such stretches met exactly at it over a slit narrower than the rounding: regression test
//! `a_slit_through_a_grid_corner_is_not_closed_by_clipped_occluders`, `tests/lloyd_egbert_attacks.rs`); a chord not
//! cut keeps its ends and may reach a little into the next cell edge, still under the terrain. The end at the corner
//! is exact in `t` and interpolated on its chord, clamped between the computed ends' heights. With `δt`, `δz` the
//! larger of the ends' and `Δz` their height difference, its `δz` is `δz + min((Δz + 2 δz) δt / (t_1 − t_0), Δz) + ERR
//! (|z_0| + |z_1|)`: the line through the computed ends differs at `r` from the line through the computed `t`s and
//! true heights by at most `δz` (`r` lies between `t_0` and `t_1`: a convex combination), and that line differs from
//! the true chord by its slope, at most `(Δz + 2 δz) / (t_1 − t_0)`, times how far the ends' errors move the corner's
//! parameter, at most `δt` (`r` lies on the true chord, so that move is a convex combination of the ends' errors too);
//! and the clamped value and the true one both lie between the computed ends' heights `± δz`, so they differ by at
//! most `Δz + δz`. For the fitted line `ℓ(t) = a + b (t − t_m)` with `a` the least of `z_k − b (t_k − t_m)` over the
//! computed breakpoints: at a true breakpoint `ℓ(t_true) ≤ ℓ(t_k) + |b| δt ≤ z_k + |b| δt ≤ z_true + δz + |b| δt`, so
//! the line lowered by `M = max_k (δz_k + |b| δt_k) + ERR (|z_k| + |b| |t_k − t_m|)` (the last term covering the
//! rounding of `a`) is below the profile at every breakpoint, hence everywhere between (both linear there). Its end
//! heights are rounded once more and lowered by `ERR` of their own size; the segment between the two lowered ends is
//! below the line. A stretch of coverage is shrunk at each end by that end's `δt` (so it never reaches beyond the
//! TIN), and two chords are joined into one stretch only when they overlap by more than their ends' `δt`, or meet at
//! the same exactly computed point (one mesh vertex, one canonical mesh edge, one grid corner). Triangles without area
//! in x,y are skipped (a profile through the others is still under the surface). The segment's end points that are
//! grid corners carry the corner's id, so that two covers ending there join exactly in the horizon (same x,y: the same
//! projected `u`, bit for bit); the ids are grid ids (`PointId::grid`), never equal to a mesh vertex's, since the safe
//! culler writes these segments into the horizon of its patches' edges.
//!
//! **Bounded preparation.** A grid line meets each triangle it crosses in a chord, cut into one piece per cell edge
//! it spans: a chord's pieces are one plus the grid corners `r` with `t_0 < r ≤ t_1` (by the cell index of each end).
//! Over a height field the chords of a line overlap only at their ends, except that a mesh edge lying on the line is
//! the chord of both triangles at it: a corner lies inside at most two chords and is the upper end of at most two
//! more, so a line's pieces are at most its chords plus 4 per corner (chords that only touch the line at a vertex
//! span no corner). A line whose pieces pass its chords plus `PIECES_PER_CORNER` = 8 per corner (room for computed
//! ends within rounding of a corner) is not over a height field — its triangles overlap in x,y, as a `.tch` from
//! elsewhere may hold (the crate documentation) —, or its chords crowd within rounding of a corner: it is given up,
//! and its cell edges get no occluder. Fewer occluders cull less, never wrongly: (i) and (ii) are about each
//! occluder written. So a line keeps at most its chords plus 8 pieces per corner, and the work is linear in the
//! (triangle, grid line) pairs, where 64 copies of one triangle spanning a 256 × 256 grid (a 378-byte file) asked for
//! 8 million pieces, 430 MB. The lines of one axis are taken at a time (one pass over the triangles an axis), so that
//! the pieces held at once are an axis's. A cull is bounded too: it looks at each cell edge at most 9 times, queueing
//! every edge at once when the drawn nodes' boxes would make it look more (overlapping boxes each spanning the grid
//! did: 4.4 s a cull with 16,385 leaves); more occluders pending than the drawn nodes ask for cull no visible
//! triangle, by the same argument.
//!
//! **(ii) holds, rounding included.** `d_min` is multiplied by `1 − 1e-12` and `d_max` by `1 + 1e-12`, far beyond
//! the few-ulp errors of a square root of a sum of squares of correctly rounded differences.
//!
//! The height margin is the safe culler's ([`crate::safe`]): `μ = 1e-7 (1 + e + |c − o|₁ + |c.z| + h)` metres.

// Comparisons are written so that a NaN anywhere answers "not hidden" (`!(a < b)`), on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::time::{Duration, Instant};

use crate::culler::{Camera, CullStats, DrawList};
use crate::hierarchy::{Grouping, Hierarchy};
use crate::horizon::{Horizon, NO_GRID_POINT, PointId, Projected, Scale, project};
use crate::sector::circle_outside_view;

/// The finest grid of occluders: `2^8 = 256` cells a side (about 130 000 cell edges).
pub const MAX_GRID_DEPTH: u32 = 8;

/// Pieces each cell edge's occluder segment is written in (see [`LloydEgbertCuller`]'s traversal).
pub const PIECES: usize = 1;

/// Relative rounding bound of the profile computations (see the module documentation).
const ERR: f64 = 1e-14;

/// Times the grid's cell edges that one cull may look at before it queues them all ([`CellEdges::queue_cells`]).
const LOOKS_PER_EDGE: usize = 8;

/// Chord pieces allowed per grid corner on a grid line beyond one per chord, before the line is given up (see the
/// module documentation, "Bounded preparation").
const PIECES_PER_CORNER: usize = 8;

/// A node's box and links.
#[derive(Clone, Copy, Debug)]
struct BoxNode {
    lo: [f64; 2],
    hi: [f64; 2],
    zmax: f64,
    triangles: [u32; 2],
    kids: [u32; 2],
    /// Over a quadtree: the grid cell of the node's first triangle's centroid (the leaf's own cell).
    cell: Option<[usize; 2]>,
}

/// One occluder: a 3-D segment on or below the terrain, with the grid-corner ids of its ends ([`NO_GRID_POINT`] for an
/// end that is not a corner).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Occluder {
    a: [f64; 3],
    b: [f64; 3],
    ida: u32,
    idb: u32,
}

/// The grid of cell edges.
#[derive(Clone, Copy, Debug)]
struct Grid {
    min: [f64; 2],
    cell: f64,
    n: usize,
}

impl Grid {
    /// Coordinate of grid line `i` along `axis` (0: x, 1: y).
    #[inline]
    fn line(&self, axis: usize, i: usize) -> f64 {
        self.min[axis] + self.cell * i as f64
    }

    /// Edge id: on line `i` of `axis` (the coordinate held fixed), segment `j` along the other axis.
    #[inline]
    fn edge(&self, axis: usize, i: usize, j: usize) -> usize {
        axis * self.n * (self.n + 1) + i * self.n + j
    }

    fn edges(&self) -> usize {
        2 * self.n * (self.n + 1)
    }

    /// Id of grid corner (`ix`, `iy`).
    #[inline]
    fn corner(&self, ix: usize, iy: usize) -> u32 {
        (iy * (self.n + 1) + ix) as u32
    }

    /// The cells (inclusive index range) that `[lo, hi]` meets along `axis`, clamped to the grid.
    fn cells(&self, axis: usize, lo: f64, hi: f64) -> (usize, usize) {
        let last = self.n as f64 - 1.0;
        let f = |v: f64| ((v - self.min[axis]) / self.cell).floor().clamp(0.0, last) as usize;
        (f(lo), f(hi))
    }
}

/// A profile breakpoint `(t, z)` with its error bounds `δt`, `δz`.
#[derive(Clone, Copy, Debug)]
struct Break {
    t: f64,
    z: f64,
    dt: f64,
    dz: f64,
}

/// A chord's end: the breakpoint and the exact point it was computed from (for joining chords).
#[derive(Clone, Copy, Debug)]
struct ChordEnd {
    b: Break,
    /// 0: mesh vertex `v`; 1: canonical mesh edge; 2: grid corner; the key is unique within its kind.
    source: (u8, u64),
}

/// Per-call working memory of [`LloydEgbertCuller`], kept in the [`DrawList`] between calls.
#[derive(Clone, Debug, Default)]
pub struct LeScratch {
    horizon: Option<Horizon>,
    queue: BinaryHeap<Reverse<(u64, u32)>>,
    edges: EdgeQueue,
    drawn: Vec<[u32; 2]>,
}

/// The pending cell-edge occluders of one cull, nearest first by their greatest distance `d_max` from the camera, and
/// which cell edges were queued already (each once a cull).
#[derive(Clone, Debug, Default)]
pub(crate) struct EdgeQueue {
    pending: BinaryHeap<Reverse<(u64, u32)>>,
    stamp: Vec<u32>,
    round: u32,
    /// Cell edges looked at this cull, queued before or not (see [`CellEdges::queue_cells`]).
    looked_at: usize,
    /// Whether every cell edge was queued this cull.
    all: bool,
}

impl EdgeQueue {
    /// Starts a cull over the occluders of `cells`: nothing pending, no edge queued.
    pub(crate) fn begin(&mut self, cells: &CellEdges) {
        self.pending.clear();
        if self.stamp.len() != cells.grid.edges() || self.round == u32::MAX {
            self.stamp = vec![0; cells.grid.edges()];
            self.round = 0;
        }
        self.round += 1;
        self.looked_at = 0;
        self.all = false;
    }
}

/// The occluders of a hierarchy's grid of cells (see the module documentation: the grid, the occluders and (i)): one
/// segment on or below the terrain per stretch of a cell edge that the TIN covers. Shared by
/// [`LloydEgbertCuller`] and the safe culler's work budget ([`crate::safe`]).
#[derive(Clone, Debug)]
pub(crate) struct CellEdges {
    grid: Grid,
    occluders: Vec<Occluder>,
    /// Occluders of edge `e`: `occluders[edge_start[e]..edge_start[e + 1]]`.
    edge_start: Vec<u32>,
}

impl CellEdges {
    /// The grid of `h` (its quadtree's stored depth, or else the least depth with at least as many cells as leaf
    /// groups; 1 to [`MAX_GRID_DEPTH`]) over the square of side the larger extent of `scale`'s box, and its occluders.
    pub(crate) fn new(h: &Hierarchy, scale: &Scale) -> CellEdges {
        let (lo, hi) = (scale.lo, scale.hi);
        let leaves = h.nodes.iter().filter(|n| n.children.is_empty()).count().max(1);
        let depth = match h.build.grouping {
            Grouping::Quadtree { stored_depth, .. } => stored_depth,
            Grouping::Crystal => {
                let mut d = 0;
                while (1usize << (2 * d)) < leaves && d < MAX_GRID_DEPTH {
                    d += 1;
                }
                d
            }
        }
        .clamp(1, MAX_GRID_DEPTH);
        let side = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let n = 1usize << depth;
        let grid = Grid {
            min: if h.mesh.positions.is_empty() {
                [0.0; 2]
            } else {
                [lo[0], lo[1]]
            },
            cell: if side.is_finite() && side > 0.0 {
                side / n as f64
            } else {
                1.0
            },
            n,
        };
        let (occluders, edge_start) = occluders(h, &grid);
        CellEdges {
            grid,
            occluders,
            edge_start,
        }
    }

    /// Makes the occluders on the edges of the cells `x.0 ..= x.1` by `y.0 ..= y.1` pending (each edge once a cull),
    /// at most `room` of them (decreased by those queued).
    ///
    /// The edges of a block are looked at one by one, those queued before included, so drawn nodes whose boxes
    /// overlap would look at the same edges again and again (16,385 leaves whose boxes each span a 256 × 256 grid: 2
    /// billion looks, 4.4 s a cull). Once the looks of a cull would exceed [`LOOKS_PER_EDGE`] times the grid's edges,
    /// every edge is queued at once instead (at most `room`), and later calls of the cull return at once: a cull
    /// looks at most `LOOKS_PER_EDGE + 1` times at each edge. Queueing more occluders than the drawn nodes ask for
    /// culls no visible triangle: the proof (module documentation) asks only that an occluder lie on or below the
    /// terrain and be nearer than the node it hides, whichever node made it pending.
    fn queue_cells(&self, x: (usize, usize), y: (usize, usize), eye: [f64; 3], q: &mut EdgeQueue, room: &mut usize) {
        if *room == 0 || q.all {
            return;
        }
        let g = &self.grid;
        let (w, h) = (x.1 - x.0 + 1, y.1 - y.0 + 1);
        let looks = (w + 1) * h + (h + 1) * w;
        let every = q.looked_at + looks > LOOKS_PER_EDGE * g.edges();
        q.looked_at += if every { g.edges() } else { looks };
        q.all = every;
        // Whether there is room left after queueing edge `e`'s occluders.
        let mut visit = |e: usize| {
            if q.stamp[e] != q.round {
                q.stamp[e] = q.round;
                for o in self.edge_start[e]..self.edge_start[e + 1] {
                    if *room == 0 {
                        return false;
                    }
                    *room -= 1;
                    let occ = &self.occluders[o as usize];
                    let d = |p: [f64; 3]| (p[0] - eye[0]).hypot(p[1] - eye[1]);
                    let dmax = d(occ.a).max(d(occ.b)) * (1.0 + 1e-12);
                    q.pending.push(Reverse((key(dmax), o)));
                }
            }
            *room > 0
        };
        if every {
            for e in 0..g.edges() {
                if !visit(e) {
                    return;
                }
            }
            return;
        }
        // Vertical lines x = X_i (axis 0) with segments j along y; horizontal lines y = Y_j (axis 1).
        for i in x.0..=x.1 + 1 {
            for j in y.0..=y.1 {
                if !visit(g.edge(0, i, j)) {
                    return;
                }
            }
        }
        for j in y.0..=y.1 + 1 {
            for i in x.0..=x.1 {
                if !visit(g.edge(1, j, i)) {
                    return;
                }
            }
        }
    }

    /// Makes the occluders on the edges of the grid cells that the box `lo`..`hi` meets pending, at most `room`.
    pub(crate) fn queue_box(&self, lo: [f64; 2], hi: [f64; 2], eye: [f64; 3], q: &mut EdgeQueue, room: &mut usize) {
        let g = &self.grid;
        self.queue_cells(g.cells(0, lo[0], hi[0]), g.cells(1, lo[1], hi[1]), eye, q, room);
    }

    /// Writes (lowered by `mu`) every pending occluder whose greatest distance from the camera is below `dmin`,
    /// nearest first; returns how many.
    pub(crate) fn write_nearer(
        &self,
        dmin: f64,
        eye: [f64; 3],
        mu: f64,
        horizon: &mut Horizon,
        q: &mut EdgeQueue,
    ) -> usize {
        let mut written = 0;
        while let Some(&Reverse((dmax_key, o))) = q.pending.peek() {
            if !(f64::from_bits(dmax_key) < dmin) {
                break;
            }
            q.pending.pop();
            let o = &self.occluders[o as usize];
            // Grid ids, never taken for mesh vertices' ([`PointId`]): the safe culler writes these segments into a
            // horizon that holds the covers of its patches' edges.
            let pa = project(sub(o.a, eye), mu, PointId::grid(o.ida));
            let pb = project(sub(o.b, eye), mu, PointId::grid(o.idb));
            horizon.write_segment([&pa, &pb]);
            written += 1;
        }
        written
    }

    /// Occluder segments in all.
    pub(crate) fn len(&self) -> usize {
        self.occluders.len()
    }
}

impl PartialEq for LeScratch {
    /// Working memory carries no result: any two are equal.
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// Lloyd & Egbert's horizon culler over a [`Hierarchy`]: see the module documentation.
#[derive(Clone, Debug)]
pub struct LloydEgbertCuller {
    columns_per_face: usize,
    nodes: Vec<BoxNode>,
    children: Vec<u32>,
    roots: Vec<u32>,
    always_visible: [u32; 2],
    triangles: u32,
    cells: CellEdges,
    scale: Scale,
    precompute: Duration,
}

/// Orders non-negative distances as integers (their bit patterns are monotone).
#[inline]
fn key(d: f64) -> u64 {
    d.max(0.0).to_bits()
}

impl LloydEgbertCuller {
    /// Prepares the culler for `h` (which must satisfy [`Hierarchy::check_invariants`], as every loaded file does)
    /// with `columns_per_face` horizon columns per 90° face (rounded up to a power of two, 2 to 65536).
    ///
    /// # Panics
    ///
    /// A hierarchy that breaks those invariants (built or changed in code: its fields are public) may make it panic,
    /// exhaust memory or never return; [`crate::AnyCuller::checked`] checks one first.
    pub fn new(h: &Hierarchy, columns_per_face: usize) -> LloydEgbertCuller {
        let start = Instant::now();
        let pos = &h.mesh.positions;
        let scale = Scale::of(pos);
        let cells = CellEdges::new(h, &scale);
        let grid = cells.grid;
        let nodes = h
            .nodes
            .iter()
            .map(|node| {
                let [s, e] = node.triangles;
                let (mut lo, mut hi, mut zmax) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2], f64::NEG_INFINITY);
                for t in &h.mesh.triangles[s as usize..e as usize] {
                    for &v in t {
                        let p = pos[v as usize];
                        lo = [lo[0].min(p[0]), lo[1].min(p[1])];
                        hi = [hi[0].max(p[0]), hi[1].max(p[1])];
                        zmax = zmax.max(p[2]);
                    }
                }
                let cell = match (h.build.grouping, h.mesh.triangles.get(s as usize)) {
                    (Grouping::Quadtree { .. }, Some(t)) if s < e => {
                        let [a, b, c] = t.map(|v| pos[v as usize]);
                        let centroid = |k: usize| (a[k] + b[k] + c[k]) / 3.0;
                        Some([
                            grid.cells(0, centroid(0), centroid(0)).0,
                            grid.cells(1, centroid(1), centroid(1)).0,
                        ])
                    }
                    _ => None,
                };
                BoxNode {
                    lo,
                    hi,
                    zmax,
                    triangles: node.triangles,
                    kids: [0, 0],
                    cell,
                }
            })
            .collect::<Vec<_>>();
        let mut c = LloydEgbertCuller {
            columns_per_face: columns_per_face.clamp(2, 1 << 16).next_power_of_two(),
            nodes,
            children: Vec::new(),
            roots: Vec::new(),
            always_visible: h.always_visible,
            triangles: h.mesh.triangles.len() as u32,
            cells,
            scale,
            precompute: Duration::ZERO,
        };
        for (i, node) in h.nodes.iter().enumerate() {
            let start = c.children.len() as u32;
            c.children.extend(&node.children);
            c.nodes[i].kids = [start, c.children.len() as u32];
        }
        c.roots = h.roots.clone();
        c.roots.sort_by_key(|&r| h.nodes[r as usize].triangles[0]);
        c.precompute = start.elapsed();
        c
    }

    /// Horizon columns per 90° face.
    pub fn columns_per_face(&self) -> usize {
        self.columns_per_face
    }

    /// Cells a side of the occluder grid.
    pub fn grid_cells(&self) -> usize {
        self.cells.grid.n
    }

    /// Occluder segments (a cell edge has one per stretch the TIN covers).
    pub fn occluder_count(&self) -> usize {
        self.cells.len()
    }

    /// Wall-clock time spent preparing the culler (boxes, profiles and occluder lines).
    pub fn precompute_time(&self) -> Duration {
        self.precompute
    }

    /// Nodes of the hierarchy it traverses.
    pub fn tree_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Culls for `camera`, returning a new draw list.
    pub fn cull(&self, camera: &Camera) -> DrawList {
        let mut out = DrawList::default();
        self.cull_into(camera, &mut out);
        out
    }

    /// The horizon after a cull for `camera` (every column of the four faces; for overlays and tests).
    pub fn horizon_after(&self, camera: &Camera) -> Horizon {
        let mut out = DrawList::default();
        self.cull_into(camera, &mut out);
        out.le_scratch
            .horizon
            .take()
            .unwrap_or_else(|| Horizon::new(self.columns_per_face))
    }

    /// Culls for `camera` into `out` (cleared first); reuses `out`'s working memory.
    pub fn cull_into(&self, camera: &Camera, out: &mut DrawList) {
        out.ranges.clear();
        out.stats = CullStats::default();
        let mut s = std::mem::take(&mut out.le_scratch);
        let eye = camera.position;
        if !eye.iter().all(|c| c.is_finite()) {
            out.push([0, self.triangles]);
            out.stats.nodes_skipped = self.nodes.len() as u32;
            out.le_scratch = s;
            return;
        }
        let mut horizon = match s.horizon.take() {
            Some(h) if h.columns_per_face() == self.columns_per_face => h,
            _ => Horizon::new(self.columns_per_face),
        };
        horizon.clear();
        s.queue.clear();
        s.drawn.clear();
        s.edges.begin(&self.cells);
        let mu = self.scale.margin(eye);
        let frustum = camera.frustum();
        let dmin_of = |n: &BoxNode| {
            let dx = (n.lo[0] - eye[0]).max(eye[0] - n.hi[0]).max(0.0);
            let dy = (n.lo[1] - eye[1]).max(eye[1] - n.hi[1]).max(0.0);
            (dx * dx + dy * dy).sqrt()
        };
        for &r in &self.roots {
            s.queue.push(Reverse((key(dmin_of(&self.nodes[r as usize])), r)));
        }
        let mut tested = 0u32;
        while let Some(Reverse((_, id))) = s.queue.pop() {
            let node = &self.nodes[id as usize];
            let dist = dmin_of(node);
            let dmin = dist * (1.0 - 1e-12);
            self.cells.write_nearer(dmin, eye, mu, &mut horizon, &mut s.edges);
            tested += 1;
            if let Some((yaw, half_fov)) = frustum {
                let centre = [
                    0.5 * (node.lo[0] + node.hi[0]) - eye[0],
                    0.5 * (node.lo[1] + node.hi[1]) - eye[1],
                ];
                let radius = 0.5 * (node.hi[0] - node.lo[0]).hypot(node.hi[1] - node.lo[1]);
                // Grown by more than the rounding of the box's centre and of its offset from the eye (a few ulps of
                // the world coordinates: the offset's magnitude plus the eye's bounds them).
                let world = centre[0].abs() + centre[1].abs() + eye[0].abs() + eye[1].abs();
                let radius = radius * (1.0 + 1e-12) + 1e-12 * world + 1e-9;
                if circle_outside_view(centre, radius, yaw, half_fov) {
                    out.stats.culled_by_frustum += 1;
                    continue;
                }
            }
            if dist > 0.0 && box_top_hidden(&horizon, node, eye, mu) {
                out.stats.culled_by_occlusion += 1;
                continue;
            }
            if node.kids[0] < node.kids[1] {
                for &c in &self.children[node.kids[0] as usize..node.kids[1] as usize] {
                    s.queue.push(Reverse((key(dmin_of(&self.nodes[c as usize])), c)));
                }
                continue;
            }
            s.drawn.push(node.triangles);
            self.queue_edges(node, eye, &mut s);
        }
        s.drawn.push(self.always_visible);
        s.drawn.sort_unstable();
        for &r in &s.drawn {
            out.push(r);
        }
        out.stats.nodes_tested = tested;
        out.stats.nodes_skipped = self.nodes.len() as u32 - tested;
        out.stats.triangles_culled = self.triangles - out.stats.triangles_drawn;
        s.horizon = Some(horizon);
        out.le_scratch = s;
    }

    /// Makes the occluders on the edges of the leaf's own cell (over a quadtree), or else of the grid cells that its
    /// box meets, pending (each edge once a cull).
    fn queue_edges(&self, node: &BoxNode, eye: [f64; 3], s: &mut LeScratch) {
        let mut room = usize::MAX;
        match node.cell {
            Some([ix, iy]) => self.cells.queue_cells((ix, ix), (iy, iy), eye, &mut s.edges, &mut room),
            None => self.cells.queue_box(node.lo, node.hi, eye, &mut s.edges, &mut room),
        }
    }
}

#[inline]
fn sub(p: [f64; 3], eye: [f64; 3]) -> [f64; 3] {
    [p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]]
}

/// Whether both triangles of the top face of `node`'s box (raised by `mu`) are strictly below the horizon. First the
/// cheaper test of the box's bounding disk at the same height ([`Horizon`]'s disk test: one comparison per column):
/// the top face lies inside it, so if every point of the disk is below the horizon in its columns, so is every point
/// of the face (the face keeps its own distance `≥ d_min`, which is what the theorem asks of the occludee).
fn box_top_hidden(horizon: &Horizon, node: &BoxNode, eye: [f64; 3], mu: f64) -> bool {
    let dz = node.zmax - eye[2];
    let m = [
        0.5 * (node.lo[0] + node.hi[0]) - eye[0],
        0.5 * (node.lo[1] + node.hi[1]) - eye[1],
    ];
    // Half the diagonal, grown past the rounding of the centre and of the square root.
    let r = 0.5 * (node.hi[0] - node.lo[0]).hypot(node.hi[1] - node.lo[1]);
    let r = r * (1.0 + 1e-12) + 1e-12 * (node.lo[0].abs() + node.hi[0].abs() + node.lo[1].abs() + node.hi[1].abs());
    if horizon.disk_hidden(m, r, dz + mu, false) {
        return true;
    }
    let corner = |x: f64, y: f64| -> Projected { project([x - eye[0], y - eye[1], dz], mu, PointId::NONE) };
    let c = [
        corner(node.lo[0], node.lo[1]),
        corner(node.hi[0], node.lo[1]),
        corner(node.hi[0], node.hi[1]),
        corner(node.lo[0], node.hi[1]),
    ];
    horizon.triangle_hidden([&c[0], &c[1], &c[2]], false) && horizon.triangle_hidden([&c[0], &c[2], &c[3]], false)
}

/// The occluders of every cell edge of `grid` over `h`'s mesh, and each edge's range of them.
fn occluders(h: &Hierarchy, grid: &Grid) -> (Vec<Occluder>, Vec<u32>) {
    let pos = &h.mesh.positions;
    let n = grid.n;
    // The chord pieces of each cell edge of one axis's grid lines (edge `e` in `chords[e - axis n (n + 1)]`), the lists
    // reused for the other axis: one pass over the triangles an axis, and the pieces held at once are an axis's (lists
    // for every cell edge held 65 MB for two triangles at the finest grid, 40 MB now; blocks of 64 lines, each reading
    // only the triangles listed for it, held less but took three times as long over 2 million triangles, whose
    // vertices are read again at every pass).
    let lines = 2 * (n + 1);
    let mut chords: Vec<Vec<(ChordEnd, ChordEnd)>> = vec![Vec::new(); (n + 1) * n];
    let mut points: Vec<ChordEnd> = Vec::with_capacity(6);
    // Per grid line (`axis * (n + 1) + i`): chords met and pieces made so far, and whether it was given up.
    let mut met = vec![0usize; lines];
    let mut pieces = vec![0usize; lines];
    let mut given_up = vec![false; lines];
    let mut out = Vec::new();
    let mut edge_start = Vec::with_capacity(grid.edges() + 1);
    let mut next_id = grid.corner(n, n);
    for axis in 0..2 {
        let axis_lines = axis * (n + 1)..(axis + 1) * (n + 1);
        chords.iter_mut().for_each(Vec::clear);
        for tri in &h.mesh.triangles {
            let p = tri.map(|v| pos[v as usize]);
            let area = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
            if !(area != 0.0 && area.is_finite()) {
                continue;
            }
            let o = 1 - axis;
            let lo = p[0][axis].min(p[1][axis]).min(p[2][axis]);
            let hi = p[0][axis].max(p[1][axis]).max(p[2][axis]);
            let first = (((lo - grid.min[axis]) / grid.cell).floor().max(0.0) as usize).saturating_sub(1);
            let last = ((((hi - grid.min[axis]) / grid.cell).ceil().max(0.0) as usize).saturating_add(1)).min(n);
            for i in first..=last {
                let x = grid.line(axis, i);
                let line = axis * (n + 1) + i;
                if !(lo <= x && x <= hi) || given_up[line] {
                    continue;
                }
                points.clear();
                for (k, m) in [(0usize, 1usize), (1, 2), (2, 0)] {
                    let (mut va, mut vb) = (tri[k], tri[m]);
                    if va > vb {
                        std::mem::swap(&mut va, &mut vb);
                    }
                    let (a, b) = (pos[va as usize], pos[vb as usize]);
                    let (da, db) = (a[axis] - x, b[axis] - x);
                    if da == 0.0 {
                        points.push(ChordEnd {
                            b: Break {
                                t: a[o],
                                z: a[2],
                                dt: 0.0,
                                dz: 0.0,
                            },
                            source: (0, u64::from(va)),
                        });
                    }
                    if db == 0.0 {
                        points.push(ChordEnd {
                            b: Break {
                                t: b[o],
                                z: b[2],
                                dt: 0.0,
                                dz: 0.0,
                            },
                            source: (0, u64::from(vb)),
                        });
                    }
                    if (da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0) {
                        let s = (x - a[axis]) / (b[axis] - a[axis]);
                        points.push(ChordEnd {
                            b: Break {
                                t: a[o] + s * (b[o] - a[o]),
                                z: a[2] + s * (b[2] - a[2]),
                                dt: ERR * (a[o].abs() + b[o].abs()),
                                dz: ERR * (a[2].abs() + b[2].abs()),
                            },
                            source: (1, (u64::from(va) << 32) | u64::from(vb)),
                        });
                    }
                }
                let (Some(&c0), Some(&c1)) = (
                    points.iter().min_by(|a, b| a.b.t.total_cmp(&b.b.t)),
                    points.iter().max_by(|a, b| a.b.t.total_cmp(&b.b.t)),
                ) else {
                    continue;
                };
                if !(c0.b.t.is_finite() && c1.b.t.is_finite() && c0.b.z.is_finite() && c1.b.z.is_finite()) {
                    continue;
                }
                let (j0, j1) = grid.cells(o, c0.b.t, c1.b.t);
                // The pieces of a line stay within its chords plus `PIECES_PER_CORNER` per grid corner on it, as
                // they do over a height field (module documentation); a line past that bound is given up,
                // occluders and all, so that the work and memory stay linear in the chords.
                met[line] += 1;
                pieces[line] += j1 - j0 + 1;
                if pieces[line] > met[line] + PIECES_PER_CORNER * (n + 1) {
                    given_up[line] = true;
                    let at = (line - axis_lines.start) * n;
                    chords[at..at + n].iter_mut().for_each(Vec::clear);
                    continue;
                }
                for j in j0..=j1 {
                    let (r0, r1) = (grid.line(o, j), grid.line(o, j + 1));
                    let clip = |r: f64, end: ChordEnd, ix: usize, iy: usize| -> Option<ChordEnd> {
                        if c0.b.t == c1.b.t {
                            return (r == c0.b.t).then_some(end);
                        }
                        let (lo_z, hi_z) = (c0.b.z.min(c1.b.z), c0.b.z.max(c1.b.z));
                        let k = (c1.b.z - c0.b.z) / (c1.b.t - c0.b.t);
                        let z = (c0.b.z + (r - c0.b.t) * k).clamp(lo_z, hi_z);
                        let dtm = c0.b.dt.max(c1.b.dt);
                        let dzm = c0.b.dz.max(c1.b.dz);
                        let dz = dzm
                            + ((hi_z - lo_z + 2.0 * dzm) * dtm / (c1.b.t - c0.b.t)).min(hi_z - lo_z)
                            + ERR * (c0.b.z.abs() + c1.b.z.abs());
                        Some(ChordEnd {
                            b: Break { t: r, z, dt: 0.0, dz },
                            source: (2, u64::from(grid.corner(ix, iy))),
                        })
                    };
                    // Corner indices of a point at `t = line(o, jj)` on line `i` of `axis`.
                    let corner = |jj: usize| if axis == 0 { (i, jj) } else { (jj, i) };
                    // A chord is cut at a grid corner only when its computed ends lie on either side of the corner
                    // by more than their `δt`, so that the true chord surely passes it (module documentation, (i)).
                    let passes = |r: f64| c0.b.t + c0.b.dt < r && r < c1.b.t - c1.b.dt;
                    let start = if !passes(r0) {
                        Some(c0)
                    } else {
                        let (ix, iy) = corner(j);
                        clip(r0, c0, ix, iy)
                    };
                    let end = if !passes(r1) {
                        Some(c1)
                    } else {
                        let (ix, iy) = corner(j + 1);
                        clip(r1, c1, ix, iy)
                    };
                    let (Some(start), Some(end)) = (start, end) else {
                        continue;
                    };
                    if start.b.t > end.b.t {
                        continue;
                    }
                    chords[grid.edge(axis, i, j) - axis_lines.start * n].push((start, end));
                }
            }
        }
        for e in axis_lines.start * n..axis_lines.end * n {
            edge_start.push(out.len() as u32);
            let list = &mut chords[e - axis_lines.start * n];
            if list.is_empty() || given_up[e / n] {
                continue;
            }
            // By start, then end (a stable sort: then in the order made).
            list.sort_by(|a, b| a.0.b.t.total_cmp(&b.0.b.t).then(a.1.b.t.total_cmp(&b.1.b.t)));
            let axis = usize::from(e >= n * (n + 1));
            let i = (e - axis * n * (n + 1)) / n;
            let x = grid.line(axis, i);
            let j = e - axis * n * (n + 1) - i * n;
            let corner = |jj: usize| {
                let (ix, iy) = if axis == 0 { (i, jj) } else { (jj, i) };
                (grid.line(1 - axis, jj), grid.corner(ix, iy))
            };
            let corners = [corner(j), corner(j + 1)];
            let mut run: Vec<Break> = Vec::new();
            let mut run_start: Option<ChordEnd> = None;
            let mut run_end: Option<ChordEnd> = None;
            for &(s, t) in list.iter() {
                let joins = match run_end {
                    None => false,
                    Some(re) => {
                        (s.b.t == re.b.t && s.source == re.source)
                            || s.b.t + s.b.dt < re.b.t - re.b.dt
                            || (s.b.dt == 0.0 && re.b.dt == 0.0 && s.b.t <= re.b.t)
                    }
                };
                if !joins {
                    if let (Some(a), Some(b)) = (run_start, run_end) {
                        fit(&run, (a, b), (axis, x), corners, &mut out, &mut next_id);
                    }
                    run.clear();
                    run_start = Some(s);
                    run_end = Some(t);
                } else if run_end.is_some_and(|re| t.b.t > re.b.t) {
                    run_end = Some(t);
                }
                run.push(s.b);
                run.push(t.b);
            }
            if let (Some(a), Some(b)) = (run_start, run_end) {
                fit(&run, (a, b), (axis, x), corners, &mut out, &mut next_id);
            }
        }
    }
    edge_start.push(out.len() as u32);
    (out, edge_start)
}

/// Fits the line under the profile breakpoints `run` over the stretch from `start` to `end` on grid line
/// `axis = x`, and pushes the occluder (see the module documentation for the margins).
fn fit(
    run: &[Break],
    (start, end): (ChordEnd, ChordEnd),
    (axis, x): (usize, f64),
    corners: [(f64, u32); 2],
    out: &mut Vec<Occluder>,
    next_id: &mut u32,
) {
    let (t0, t1) = (start.b.t + start.b.dt, end.b.t - end.b.dt);
    if !(t0 < t1) {
        return;
    }
    // Lower convex hull of the breakpoints (monotone chain).
    let mut pts: Vec<(f64, f64)> = run.iter().map(|b| (b.t, b.z)).collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    pts.dedup_by(|b, a| a.0 == b.0);
    let mut hull: Vec<(f64, f64)> = Vec::new();
    for &p in &pts {
        while hull.len() >= 2 {
            let (a, b) = (hull[hull.len() - 2], hull[hull.len() - 1]);
            if (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0) <= 0.0 {
                hull.pop();
            } else {
                break;
            }
        }
        hull.push(p);
    }
    let tm = 0.5 * (t0 + t1);
    let slope = match hull.windows(2).find(|w| w[1].0 >= tm) {
        Some(w) => (w[1].1 - w[0].1) / (w[1].0 - w[0].0),
        None => 0.0,
    };
    let b = if slope.is_finite() { slope } else { 0.0 };
    let mut a = f64::INFINITY;
    let mut margin: f64 = 0.0;
    for k in run {
        let rel = k.t - tm;
        a = a.min(k.z - b * rel);
        margin = margin.max(k.dz + b.abs() * k.dt + ERR * (k.z.abs() + b.abs() * rel.abs()));
    }
    let a = a - margin;
    let z_at = |t: f64| {
        let r = t - tm;
        let z = a + b * r;
        z - ERR * (a.abs() + b.abs() * (r.abs() + t.abs()) + 1.0)
    };
    let (za, zb) = (z_at(t0), z_at(t1));
    if !(za.is_finite() && zb.is_finite()) {
        return;
    }
    let point = |t: f64, z: f64| if axis == 0 { [x, t, z] } else { [t, x, z] };
    // An end exactly at one of the edge's grid corners is that corner (whatever it was computed from).
    let id = |t: f64| {
        if t == corners[0].0 {
            corners[0].1
        } else if t == corners[1].0 {
            corners[1].1
        } else {
            NO_GRID_POINT
        }
    };
    // The segment in `PIECES` pieces (each between two points of the lowered line, so below it), that become
    // eligible one by one as the traversal moves away from the camera; inner piece ends get fresh ids.
    let mut prev = (t0, za, id(t0));
    for k in 1..=PIECES {
        let next = if k == PIECES {
            (t1, zb, id(t1))
        } else {
            let t = t0 + (t1 - t0) * (k as f64 / PIECES as f64);
            *next_id += 1;
            (t, z_at(t), *next_id)
        };
        if !next.1.is_finite() || !(prev.0 < next.0) {
            return;
        }
        out.push(Occluder {
            a: point(prev.0, prev.1),
            b: point(next.0, next.1),
            ida: prev.2,
            idb: next.2,
        });
        prev = next;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hierarchy::{BuildInfo, Mesh, Node};

    /// A 5 × 5 grid of vertices (spacing 10 m) with heights `z(x, y)`, one leaf, over a quadtree grid of depth 2.
    fn hierarchy(z: impl Fn(f64, f64) -> f64) -> Hierarchy {
        let mut positions = Vec::new();
        for j in 0..5 {
            for i in 0..5 {
                let (x, y) = (10.0 * i as f64, 10.0 * j as f64);
                positions.push([x, y, z(x, y)]);
            }
        }
        let mut triangles = Vec::new();
        for j in 0..4u32 {
            for i in 0..4u32 {
                let v = j * 5 + i;
                // Alternate diagonals, so that grid lines cross mesh edges as well as run along them.
                if (i + j) % 2 == 0 {
                    triangles.push([v, v + 1, v + 6]);
                    triangles.push([v, v + 6, v + 5]);
                } else {
                    triangles.push([v, v + 1, v + 5]);
                    triangles.push([v + 1, v + 6, v + 5]);
                }
            }
        }
        let nt = triangles.len() as u32;
        Hierarchy {
            sectors: 16,
            origin: [0.0; 3],
            nodes: vec![Node {
                centre: [20.0, 20.0],
                radius: 30.0,
                children: vec![],
                triangles: [0, nt],
                level: 0,
                regions: vec![],
            }],
            roots: vec![0],
            always_visible: [nt, nt],
            mesh: Mesh { positions, triangles },
            build: BuildInfo {
                grouping: Grouping::Quadtree {
                    built_depth: 3,
                    stored_depth: 3,
                },
                ..BuildInfo::default()
            },
        }
    }

    /// The terrain height at `(x, y)` by brute force over the triangles (the lowest plane through a triangle that
    /// contains the point).
    fn ground(h: &Hierarchy, x: f64, y: f64) -> Option<f64> {
        let p = &h.mesh.positions;
        let mut best: Option<f64> = None;
        for t in &h.mesh.triangles {
            let [a, b, c] = t.map(|v| p[v as usize]);
            let d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            let l1 = ((b[0] - x) * (c[1] - y) - (b[1] - y) * (c[0] - x)) / d;
            let l2 = ((c[0] - x) * (a[1] - y) - (c[1] - y) * (a[0] - x)) / d;
            let l3 = 1.0 - l1 - l2;
            if l1 >= -1e-12 && l2 >= -1e-12 && l3 >= -1e-12 {
                let z = l1 * a[2] + l2 * b[2] + l3 * c[2];
                best = Some(best.map_or(z, |m: f64| m.min(z)));
            }
        }
        best
    }

    #[test]
    fn occluders_lie_under_the_profile_and_follow_it() {
        let h = hierarchy(|x, y| 3.0 * (x * 0.37).sin() + 0.2 * y + if x > 25.0 { 8.0 } else { 0.0 });
        let c = LloydEgbertCuller::new(&h, 64);
        assert_eq!(c.grid_cells(), 8);
        // 2 · 8 · 9 cell edges, each covered by the terrain once, in `PIECES` pieces.
        assert_eq!(c.occluder_count(), 2 * 8 * 9 * PIECES);
        let mut gap: f64 = 0.0;
        for o in &c.cells.occluders {
            for k in 0..=20 {
                let s = k as f64 / 20.0;
                let p: Vec<f64> = (0..3).map(|i| o.a[i] + s * (o.b[i] - o.a[i])).collect();
                let g = ground(&h, p[0], p[1]).expect("the occluder lies over the TIN");
                // `ground` rounds too (products of coordinates up to 80 m): allow 1e-12 m, far below the culler's
                // height margin μ (1e-7 m and more).
                assert!(p[2] <= g + 1e-12, "occluder {o:?} above the terrain at {p:?} ({g})");
                gap = gap.max(g - p[2]);
            }
        }
        // Cell edges are 5 m long: the line under a profile of that length stays within a few metres of it.
        assert!(gap < 6.0, "largest gap {gap}");
    }

    #[test]
    fn corners_join_and_the_outside_has_no_occluder() {
        // A terrain wider than deep: the grid's upper rows lie beyond the TIN and get no occluders.
        let mut h = hierarchy(|x, _| x * 0.1);
        for p in &mut h.mesh.positions {
            p[0] *= 2.0;
        }
        let c = LloydEgbertCuller::new(&h, 64);
        for o in &c.cells.occluders {
            assert!(o.a[1] <= 40.0 && o.b[1] <= 40.0, "{o:?}");
        }
        // Ends at grid corners carry ids, equal at the same corner.
        let at = |p: [f64; 3]| ((p[0] * 1e6) as i64, (p[1] * 1e6) as i64);
        let mut ids = std::collections::HashMap::new();
        for o in &c.cells.occluders {
            for (p, id) in [(o.a, o.ida), (o.b, o.idb)] {
                if id != NO_GRID_POINT {
                    assert_eq!(*ids.entry(id).or_insert(at(p)), at(p));
                }
            }
        }
        assert!(!ids.is_empty());
    }

    /// Over a height field no grid line is given up, at the finest grid too (mesh edges on every 64th grid line,
    /// vertices at grid corners): every cell edge has its occluder. Over 16 copies of each half of the square (a mesh
    /// that is no height field; 16 copies of one triangle in a 234-byte `.tch` asked for 107 MB of chord pieces) every
    /// grid line meets 32 chords of 258 pieces together, past the bound of 32 + 8 per corner: every line is given up
    /// and nothing is kept.
    #[test]
    fn lines_are_given_up_only_where_triangles_overlap() {
        let mut h = hierarchy(|x, y| 0.3 * x + (y * 0.2).sin());
        h.build.grouping = Grouping::Quadtree {
            built_depth: 8,
            stored_depth: 8,
        };
        let c = LloydEgbertCuller::new(&h, 64);
        assert_eq!(c.grid_cells(), 256);
        assert_eq!(c.occluder_count(), 2 * 256 * 257 * PIECES);
        // Corners 0, 4, 24 and 20 of the 5 × 5 grid of vertices: (0, 0), (40, 0), (40, 40), (0, 40).
        h.mesh.triangles = [[0, 4, 24], [0, 24, 20]].repeat(16);
        h.nodes[0].triangles = [0, 32];
        h.always_visible = [32, 32];
        h.check_invariants().expect("a valid structure");
        let c = LloydEgbertCuller::new(&h, 64);
        assert_eq!(c.occluder_count(), 0);
    }

    /// Drawn leaves whose boxes each span the grid (every leaf holds two triangles at opposite ends of the terrain):
    /// a cull looks at each cell edge at most `LOOKS_PER_EDGE + 1` times, having queued every edge once the looks
    /// passed the limit (they were 2,000 a leaf, a million a cull here; 2 billion with 16,385 leaves over a 256 × 256
    /// grid), and culls no triangle that the exact checker sees.
    #[test]
    fn leaves_spanning_the_grid_look_at_each_cell_edge_a_bounded_number_of_times() {
        use glam::DVec3;
        let n = 33;
        let mut pts = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let (x, y) = (20.0 * i as f64, 20.0 * j as f64);
                let z = 25.0 * (x / 70.0).sin() * (y / 90.0).cos() + 0.02 * x;
                pts.push(DVec3::new(x + 500_000.0, y + 4_000_000.0, z + 300.0));
            }
        }
        let (tin, _) = tin::triangulate(&pts, tin::DedupePolicy::Reject).expect("a grid");
        let nt = tin.num_triangles();
        // Triangles by the sum of their centroid's coordinates; leaf k holds the k-th and the k-th from the end.
        let sum = |t: usize| tin.corners(t).iter().map(|p| p.x + p.y).sum::<f64>();
        let mut by_sum: Vec<usize> = (0..nt).collect();
        by_sum.sort_by(|&a, &b| sum(a).total_cmp(&sum(b)).then(a.cmp(&b)));
        let order: Vec<usize> = (0..nt / 2).flat_map(|k| [by_sum[k], by_sum[nt - 1 - k]]).collect();
        let nodes: Vec<Node> = (0..nt / 2)
            .map(|k| Node {
                // The culler takes the box of the node's vertices, not its circle.
                centre: [0.0; 2],
                radius: 1.0,
                children: vec![],
                triangles: [2 * k as u32, 2 * k as u32 + 2],
                level: 0,
                regions: vec![],
            })
            .collect();
        let grouped = 2 * (nt / 2) as u32;
        let h = Hierarchy {
            sectors: 16,
            origin: [0.0; 3],
            roots: (0..nodes.len() as u32).collect(),
            nodes,
            always_visible: [grouped, nt as u32],
            mesh: Mesh {
                positions: tin.positions().iter().map(|p| p.to_array()).collect(),
                triangles: order
                    .iter()
                    .chain(&by_sum[grouped as usize..])
                    .map(|&t| tin.triangles()[t])
                    .collect(),
            },
            build: BuildInfo::default(),
        };
        h.check_invariants().expect("a valid hierarchy");
        let culler = LloydEgbertCuller::new(&h, 256);
        let edges = culler.cells.grid.edges();
        assert_eq!(culler.grid_cells(), 32, "1,024 leaves: a 32 × 32 grid");
        let truth = truth::GroundTruth::new(&tin);
        let mut list = DrawList::default();
        let mut culled = 0;
        for (k, [x, y]) in [[30.0, 30.0], [330.0, 310.0], [610.0, 50.0], [150.0, 600.0]]
            .into_iter()
            .enumerate()
        {
            let at = glam::DVec2::new(x + 500_000.0, y + 4_000_000.0);
            let ground = truth::ground_heights(&h.mesh.positions, &h.mesh.triangles, &[at])[0]
                .expect("the eye is over the terrain");
            let eye = at.extend(ground + 2.0);
            culler.cull_into(&Camera::all_around(eye.to_array()), &mut list);
            let q = &list.le_scratch.edges;
            assert!(
                q.all,
                "eye {k}: the drawn leaves' boxes ask for every edge many times over"
            );
            assert!(
                q.looked_at <= (LOOKS_PER_EDGE + 1) * edges,
                "eye {k}: {} looks",
                q.looked_at
            );
            let seen = truth.visible_triangles(eye);
            let mut drawn = vec![false; nt];
            for &[s, e] in &list.ranges {
                drawn[s as usize..e as usize].iter_mut().for_each(|d| *d = true);
            }
            for (i, &t) in order.iter().chain(&by_sum[grouped as usize..]).enumerate() {
                assert!(drawn[i] || !seen[t], "eye {k}: triangle {t} is visible but culled");
                culled += usize::from(!drawn[i]);
            }
        }
        assert!(culled > 0, "the leaves hidden from the valleys are culled");
    }
}
