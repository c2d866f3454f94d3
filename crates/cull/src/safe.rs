//! The safe run-time culler: a front-to-back traversal of the hierarchy against a conservative horizon
//! ([`crate::horizon`]), whose verdict "hidden" is a theorem (the README's "Safe culling").
//!
//! ## The tree
//!
//! Built once from a [`Hierarchy`] and its mesh, nothing more stored in the file: the hierarchy's nodes, then below
//! every leaf group (and below the always-visible set, which this culler may cull too) a binary tree obtained by
//! halving the triangle range (`[s, e)` splits at `s + (e − s) / 2`) until a range has at most `patch` triangles.
//! The build lays out every group and the always-visible set in a spatial order in which halving is a spatial split
//! (`crystal`'s `spatial_order`), so these ranges are compact patches. Every tree node gets, in f64 from the mesh
//! itself, a bounding circle in x,y (grown to cover rounding) and the largest height of its vertices.
//!
//! ## One cull
//!
//! Nodes are taken nearest first (by the least horizontal distance `d_min` of their circle from the camera). Before
//! a node is tested, every drawn patch whose greatest distance `d_max` is below the node's `d_min` becomes
//! *eligible*: its edges (TIN edges, lowered by `μ`) may be written into the horizon as occluders. Only the edges
//! that can bound the patch's image from above are written: its boundary edges with the patch's triangle below them
//! in the image, and its silhouette edges (one triangle facing the camera, the other not); an inner edge with its two
//! triangles on either side of it in the image is covered above by one of them, so it would add little. Which edges
//! are written decides only how much is culled: every TIN edge lies on the terrain, so any of them is an occluder
//! (an orientation computed wrongly by rounding writes an edge too many or too few, nothing worse).
//!
//! The edges written of one patch that are connected to each other (*chains*, found by a union-find over the patch's
//! vertices) are also written as one flat cover each ([`crate::horizon`]'s chains: the least lowered `v` of the chain's
//! vertices over the `u` its vertices span): far away, where a TIN edge is shorter than a column, edge by edge a chain
//! covers no column it crosses, as a whole it does. Only patches small on screen (spanning fewer than 4 columns) write
//! chains: nearer ones have edges long enough to cover columns by themselves.
//!
//! They are written lazily: each eligible patch raises a per-column bound `P` of what it could write (its highest
//! lowered vertex over the columns its vertices span), and the eligible patches are written only when a test would
//! pass against `max(H, P)` but not against `H` alone. Writing fewer occluders only makes the horizon lower, so this
//! changes how much is culled, never whether a verdict is right. A node is then
//!
//! - *visible* if the camera's x,y is inside its circle;
//! - *hidden* if its bounding cylinder (circle, height up to its highest vertex plus `μ`) is below the horizon in
//!   every column it touches ([`crate::horizon`]'s theorem with `D = d_min`: every occluder written so far lies
//!   nearer than `d_min`). A hidden node is not drawn and none of its descendants is looked at;
//! - for a patch that passes the cylinder test: visible at once if one of its vertices (raised by `μ`) is not below
//!   the horizon in its column (its triangles' tests would fail there; no proof needed for "visible"); hidden if its
//!   vertices bound all its triangles below the horizon ([`crate::horizon`]'s vertex bound for a set of triangles:
//!   the camera is outside the patch's circle, hence outside each of its triangles); else hidden if each of its
//!   triangles (raised by `μ`) is below the horizon in every column it touches (the same theorem, triangle by
//!   triangle);
//! - otherwise visible: an inner node queues its children, a patch is drawn and queued as an occluder.
//!
//! *Why every occluder lies nearer than the node tested.* A child's circle need not lie inside its parent's, so a
//! child's key can be below its parent's and below keys popped before it: "nodes are taken nearest first" holds for
//! their points, not for their keys. Let node `A` be popped with key `d_A`. Every node `B` tested after it is a
//! descendant of `A` or of a node that was in the queue when `A` was popped (whose key was `≥ d_A`), and its points are
//! points of that ancestor, inside the ancestor's circle: every point of `B` lies at a horizontal distance `≥ d_A`. A
//! patch made eligible at `A` has `d_max < d_A`, so whenever it is written (lazily, maybe while `B` is tested) it lies
//! nearer than every point of `B`, which is what the theorem needs with `D = d_A`. The keys are computed in f64 as
//! `|m − c| − r` from circles grown by a relative 1e-12 (and an absolute 1e-9 m). A computed key may exceed the exact
//! `|m − c| − r` by the rounding of the distance and of the subtraction, at most `3ε (|m − c| − r + r)` with
//! `ε = 2⁻⁵³` (an eye 10⁸ m from a 1 m circle: 6e-9 m); that does not matter for the order, which the argument above
//! takes from the keys as computed. What is compared with an occluder's `d_max` is not the key but
//! `d_min = (|m − c| − r)(1 − 1e-12)`: the 1e-12 taken off it, with the 1e-12 `r` of the circle's growth, is more than
//! `3ε` times each term, so `d_min` never exceeds the true least distance of the node's points.
//!
//! ## Coarse nodes
//!
//! With [`SafeParams::coarse_columns`] `n > 0`, a visible inner node (not containing the camera) whose circle is small
//! on screen (`radius · w < n · distance`, `w` the columns per face: about `n` columns) is drawn whole instead of
//! refined, and queued as an occluder like a drawn patch (from its greatest distance `d_max`). Its occluders are its
//! *crests*, computed once when the culler is prepared (for nodes of at most 2,048 triangles, once a range, within a
//! bound on the triangles scanned past which a node gets none and writes nothing: `CREST_SCANS_PER_TRIANGLE`): for x
//! and for y, the bottleneck path of its TIN edges between its vertices in the first and the last quarter of its
//! extent, stored as the path's two end vertices `a`, `b` and the least height `z*` of its vertices (edges taken by
//! decreasing lower end into a union-find until one component holds a vertex of each quarter). The path is a connected
//! set of TIN edges at heights `≥ z*` inside the node's circle; lowered by `μ`, it is a chain in the sense of
//! [`crate::horizon`] in every face `k` whose half-plane `f > 0` holds the whole circle (`m_f − r > 0`, `m` the
//! circle's centre less the camera): its `u` fill `[u_a, u_b]`, and each of its points has `f` in `[m_f − r, m_f + r]`
//! and height `≥ z* − μ`, so `v ≥ (z* − μ − c.z) / (m_f + r)` when that numerator is `≥ 0`, else `≥ (z* − μ − c.z) /
//! (m_f − r)`; this bound (the radius grown for the rounding of `m`, `f` moved outward and the quotient lowered by
//! `REL`, as for disks) is written as a flat cover over `[u_a, u_b]`. Drawing a node whole draws a superset of what
//! refining it would; the crests only raise the horizon by what the theorem allows.
//!
//! ## The work budget
//!
//! Refining costs what the view sees: every visible patch is projected, tested and written. [`SafeParams::work_budget`]
//! bounds it by a count (not a time: culls stay byte-identical across runs and machines) of *work units*: one per node
//! tested while refining, one per occluder edge written, one per chain or crest written. Each unit is checked before it
//! is spent, so a cull spends at most `B` of them. Once they are spent:
//!
//! - no node is refined any more, and no patch edge, chain or crest is written. Every node still queued (and each
//!   descendant taken below) is at least as far as every node tested so far (its points are at least at its queue key
//!   `d_min`, the keys of its queued ancestors, and the queue pops keys in order), so every occluder in the horizon
//!   lies nearer than every one of its points, as when that occluder was written: the theorem applies to them against
//!   the horizon as it stands;
//! - the queued nodes are taken largest first (by triangles): each is culled if its cylinder is hidden (the same test
//!   as above, `H` only), else split into its children while fewer than `⌈B / 8⌉` nodes were split this way, else kept
//!   to be drawn whole. Drawing a node whole draws a superset of what refining it would have drawn. The splits get an
//!   eighth of the budget: in a view that sees most of the terrain (the views that spend it) few of them cull anything,
//!   and with as many splits as units they cost as much again as the refining;
//! - the kept nodes are then taken nearest first, sorted by the computed `d_min` of their own circles (the same
//!   `(|m − c| − r)(1 − 1e-12)` as while refining, at most the least distance of their points), and tested once more:
//!   before node `X` is tested, every pending *cell-edge occluder* whose greatest distance `d_max` is below `X`'s
//!   `d_min` is written (lowered by `μ`); `X` is culled if its cylinder is now hidden, else drawn whole, and the
//!   cell-edge occluders around it become pending: those of [`crate::lloyd_egbert`] (its grid over this hierarchy),
//!   one segment under the TIN's profile along each edge of the grid cells that the square around `X`'s circle meets
//!   (each edge once a cull, at most `⌈B / 8⌉` segments in all, within [`SafeParams::occluder_budget`]). Each segment
//!   lies on or below the terrain, rounding included (that module's (i)), and its `d_max`, the larger of its ends'
//!   horizontal distances from the camera (a segment's farthest point from a point is an end) grown by a relative
//!   1e-12, is at least its true greatest distance (that module's (ii)). A segment written before `X` is tested has
//!   `d_max < d_min(X) ≤ d_min(Y)` for every node `Y` tested after `X` (sorted), so it lies nearer than every point of
//!   `X` and of every later `Y`: an occluder in the theorem's sense for each of them, as a drawn patch's edge is for
//!   the nodes tested after it. The earlier occluders stay valid for the kept nodes (first item). The horizon only
//!   rises, so this pass culls a subset of what was kept and draws no more than the largest-first pass alone: the
//!   terrain drawn whole hides what lies behind it at the cost of one test per kept node and at most `⌈B / 8⌉`
//!   segments.
//!
//! Hence at most `B` refining tests (each pushing at most `c` children, `c` the most children of a node: 2 in a crystal
//! hierarchy and its halving trees), at most `⌈B / 8⌉` splits pushing `c` each, and every pushed node tested once: at
//! most `(1 + c) B + c ⌈B / 8⌉ + r` nodes tested (`r` roots; `3.25 B + 2 + r` with `c = 2`), each kept one once more,
//! at most `B` edges and chains written while refining and `⌈B / 8⌉` cell-edge segments after. The verdicts "hidden"
//! are the same theorem's. A budget never reached changes nothing; a spent one draws more than the cull without a
//! budget where it stopped refining, and may draw less behind the cell edges (a horizon built without a budget holds
//! none), so neither draw list need hold the other. The grid's occluders are computed when the culler is prepared
//! (one pass over the triangles), and only if some cull could spend the budget: every node is tested at most once,
//! every patch edge and crest written at most once, and a patch has no more chains than edges, so when the nodes, twice
//! the patch edges and the crests number fewer than `B` in all, no cull can.

//! Every "hidden" is thus an instance of the theorem, whatever the order, the tree or the parameters; the order and
//! the parameters only decide how much is culled. With a horizontal field of view below 360°, a node entirely
//! outside it is culled by the same azimuth test as [`crate::Culler`]'s (a node outside the view cannot be seen).
//! A non-finite camera draws everything.
//!
//! The height margin is `μ = 1e-7 (1 + e + |c − o|₁ + |c.z| + h)` metres with `e` the mesh's extent, `o` the
//! centre of its box (computed from the vertices, not read from the file's origin field) and `h` its largest `|z|`
//! ([`crate::horizon`]'s `Scale`): more than 100 times the exact checker's tolerance (`truth::walk`), so a
//! sight line called blocked here is blocked there, and far above every rounding error of the arithmetic.

// Comparisons are written so that a NaN anywhere answers "not hidden" (`!(a < b)`), on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};

use crate::culler::{Camera, CullStats, DrawList};
use crate::hierarchy::Hierarchy;
use crate::horizon::{FACES, Horizon, PointId, Projected, REL, Reach, Scale, face_coords, project};
use crate::lloyd_egbert::{CellEdges, EdgeQueue};
use crate::sector::circle_outside_view;

/// The default [`SafeParams::work_budget`]: far above what any view of the bundled 10k-vertex meshes needs (at most
/// about 20,000 units) and above what the measured sky views of a 100k-vertex mesh and high views of a 1M-vertex one
/// need (means of about 120,000 and 70,000 units); it caps the sky views of a 1M-vertex mesh (over 1,000,000).
pub const DEFAULT_WORK_BUDGET: usize = 200_000;

/// Parameters of the safe culler (run time only; nothing of them is stored in the `.tch`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SafeParams {
    /// Horizon columns per 90° face: rounded up to a power of two, and clamped to 2 ..= 65,536.
    pub columns_per_face: usize,
    /// Largest patch (triangles) below the hierarchy's leaves: clamped to 1 ..= 64.
    pub patch: usize,
    /// Most occluder edges written into the horizon per cull, nearest first (fewer occluders only cull less, never
    /// wrongly); the cell-edge segments written after a spent work budget count too. It bounds the writing, not the
    /// cost: with few occluders every visible node is refined and tested ([`SafeParams::work_budget`] bounds the cost).
    /// `usize::MAX`: unlimited (`null` when serialized, which JSON readers hold exactly).
    #[serde(with = "unlimited")]
    pub occluder_budget: usize,
    /// Most work units per cull: nodes tested while refining, occluder edges and chains written. Once spent, the
    /// culler stops refining and writing edges: every node still queued is tested against the horizon as it stands
    /// (split at most `⌈B / 8⌉` times in all), and those left are tested once more, nearest first, with the cell-edge
    /// occluders around the ones drawn before them (at most `⌈B / 8⌉` segments), and drawn whole unless hidden. A
    /// count, not a time, so culls are reproducible; see the module documentation.
    pub work_budget: usize,
    /// A visible inner node whose circle spans fewer than this many columns (about `radius · columns / distance`)
    /// is drawn whole instead of refined, and writes its crests as occluders; 0 refines every visible node. Only inner
    /// nodes of at most 2048 triangles have crests and can be drawn so; larger ones and patches are refined as usual.
    pub coarse_columns: usize,
}

/// `usize::MAX` (no limit) serialized as `null`, and read back from `null` or a number.
mod unlimited {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(n: &usize, s: S) -> Result<S::Ok, S::Error> {
        (*n != usize::MAX).then_some(*n).serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<usize, D::Error> {
        Ok(Option::<usize>::deserialize(d)?.unwrap_or(usize::MAX))
    }
}

/// The most horizon columns per face ([`SafeParams::columns_per_face`]) a front end accepts.
pub const MAX_COLUMNS_PER_FACE: usize = 1 << 16;

/// The largest patch ([`SafeParams::patch`]) a front end accepts.
pub const MAX_PATCH: usize = 64;

/// A [`SafeParams`] value outside what a front end should accept ([`SafeParams::check`]); the culler itself rounds and
/// clamps such values instead.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum SafeParamsError {
    /// [`SafeParams::columns_per_face`] is not a power of two from 2 to [`MAX_COLUMNS_PER_FACE`].
    Columns(usize),
    /// [`SafeParams::patch`] is not from 1 to [`MAX_PATCH`].
    Patch(usize),
}

impl std::fmt::Display for SafeParamsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SafeParamsError::Columns(n) => write!(
                f,
                "the columns per face must be a power of two from 2 to {MAX_COLUMNS_PER_FACE}, got {n}"
            ),
            SafeParamsError::Patch(n) => write!(f, "the patch must be from 1 to {MAX_PATCH} triangles, got {n}"),
        }
    }
}

impl std::error::Error for SafeParamsError {}

impl SafeParams {
    /// Whether every value is one a front end should accept as given: the columns per face a power of two from 2 to
    /// [`MAX_COLUMNS_PER_FACE`], the patch from 1 to [`MAX_PATCH`] (the budgets and the coarse columns take any
    /// value). [`SafeCuller::new`] rounds and clamps the others rather than refusing them.
    pub fn check(&self) -> Result<(), SafeParamsError> {
        let c = self.columns_per_face;
        if !(c.is_power_of_two() && (2..=MAX_COLUMNS_PER_FACE).contains(&c)) {
            return Err(SafeParamsError::Columns(c));
        }
        if !(1..=MAX_PATCH).contains(&self.patch) {
            return Err(SafeParamsError::Patch(self.patch));
        }
        Ok(())
    }
}

impl Default for SafeParams {
    fn default() -> Self {
        SafeParams {
            columns_per_face: 256,
            patch: 16,
            occluder_budget: usize::MAX,
            work_budget: DEFAULT_WORK_BUDGET,
            coarse_columns: 0,
        }
    }
}

/// One node of the culling tree.
#[derive(Clone, Copy, Debug)]
struct TreeNode {
    centre: [f64; 2],
    radius: f64,
    zmax: f64,
    triangles: [u32; 2],
    /// Children in `children[kids[0]..kids[1]]`; empty for a patch.
    kids: [u32; 2],
    /// For a patch: its vertices in `verts[v[0]..v[1]]` and triangles in `tris[t[0]..t[1]]` (local indices).
    verts: [u32; 2],
    tris: [u32; 2],
    /// For a patch: its edges in `edges[e[0]..e[1]]`.
    edges: [u32; 2],
    /// For an inner node with [`SafeParams::coarse_columns`]: its crests in `crests[c[0]..c[1]]`.
    crests: [u32; 2],
}

/// A crest of a node: two of its vertices joined by a path of its TIN edges whose vertices all lie at height `z` or
/// higher (the highest such `z`: a bottleneck path), one near each end of the node along x or along y.
#[derive(Clone, Copy, Debug)]
struct Crest {
    a: [f64; 3],
    b: [f64; 3],
    ids: [u32; 2],
    z: f64,
}

/// Largest node (triangles) given crests: larger ones are never small enough on screen to be drawn whole.
const CREST_MAX: u32 = 2048;

/// Triangles scanned for crests, per triangle of the mesh, beyond which nodes get no crests. Nodes of one range share
/// theirs, and the hierarchies `tincull build` makes scan 5 to 7 (crystal and quadtree, 10k to 200k triangles), but a
/// file may nest ranges that differ by a triangle, each scanned whole: a chain of 5,000 nodes over 2,048 triangles
/// (143 KB) took 2.4 s to prepare. A node without crests draws whole as before and writes no occluder: it culls
/// less, never wrongly.
const CREST_SCANS_PER_TRIANGLE: u64 = 32;

/// The most descendants of a hierarchy node looked at for its bounding circle (see
/// [`SafeCuller::bounds_from_descendants`]): the crystal hierarchies of 10k and 100k vertices need at most 15.
const MAX_DESCENDANT_STEPS: usize = 128;

/// No crest entry: a pending patch's offset in `projected` never takes this value.
const CRESTS: u32 = u32::MAX;

/// Per-call working memory of [`SafeCuller`], kept in the [`DrawList`] between calls.
#[derive(Clone, Debug, Default)]
pub struct SafeScratch {
    horizon: Option<Horizon>,
    queue: BinaryHeap<Reverse<(u64, u32)>>,
    pending: BinaryHeap<Reverse<(u64, u32, u32)>>,
    projected: Vec<Projected>,
    drawn: Vec<[u32; 2]>,
    /// Drawn patches nearer than the node under test, not written yet: `(patch, offset in projected, what it can
    /// write)`.
    eligible: Vec<(u32, u32, Reach)>,
    /// Nodes left when the work budget is spent, largest first: `(triangles, node)`.
    by_size: BinaryHeap<(u32, u32)>,
    /// Nodes left to be drawn whole once the work budget is spent: `(key of d_min, node)`.
    whole: Vec<(u64, u32)>,
    /// Cell-edge occluders pending once the work budget is spent.
    cell_edges: EdgeQueue,
}

impl PartialEq for SafeScratch {
    /// Working memory carries no result: any two are equal.
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// The safe culler over a [`Hierarchy`]: see the module documentation.
#[derive(Clone, Debug)]
pub struct SafeCuller {
    params: SafeParams,
    nodes: Vec<TreeNode>,
    children: Vec<u32>,
    roots: Vec<u32>,
    verts: Vec<[f64; 3]>,
    /// Mesh vertex index of every entry of `verts`.
    vids: Vec<u32>,
    tris: Vec<[u8; 3]>,
    crests: Vec<Crest>,
    /// Patch edges `[a, b, t1, t2]` (local vertices and triangles): `a → b` runs along the winding of triangle `t1`,
    /// `t2` is the patch's other triangle on the edge ([`NO_TRIANGLE`] on the patch boundary).
    edges: Vec<[u8; 4]>,
    /// Normal `(b − a) × (c − a)` of every entry of `tris`.
    normals: Vec<[f64; 3]>,
    triangles: u32,
    scale: Scale,
    /// The cell-edge occluders written once the work budget is spent; `None` when no cull can spend it (fewer work
    /// units in the whole tree than the budget).
    cells: Option<CellEdges>,
}

/// The work of one cull, in the units of [`SafeParams::work_budget`].
#[derive(Clone, Copy, Debug, Default)]
struct Count {
    /// Nodes tested while refining.
    tests: usize,
    /// Occluder edges written.
    edges: usize,
    /// Flat covers (chains) written.
    flats: usize,
    /// Nodes split after the budget was spent.
    splits: usize,
    /// Cell-edge occluders written after the budget was spent.
    cell_edges: usize,
}

impl Count {
    /// Work units spent.
    #[inline]
    fn work(&self) -> usize {
        self.tests + self.edges + self.flats
    }

    /// Whether an occluder may still be written: the occluder budget and the work budget both left.
    #[inline]
    fn can_write(&self, params: &SafeParams) -> bool {
        self.edges < params.occluder_budget && self.work() < params.work_budget
    }
}

/// A connected set of written edges of one patch (a chain), summed up per face for a flat cover: the faces in front
/// of all its vertices, their least and greatest `u` (with the vertices there) and least lowered `v`.
#[derive(Clone, Copy, Debug)]
struct Chain {
    mask: u8,
    lo: [(f64, PointId); FACES],
    hi: [(f64, PointId); FACES],
    bound: [f64; FACES],
}

impl Default for Chain {
    fn default() -> Self {
        Chain {
            mask: 0b1111,
            lo: [(f64::INFINITY, PointId::NONE); FACES],
            hi: [(f64::NEG_INFINITY, PointId::NONE); FACES],
            bound: [f64::INFINITY; FACES],
        }
    }
}

impl Chain {
    fn add(&mut self, p: &Projected) {
        self.mask &= p.mask;
        for k in 0..FACES {
            let q = p.face[k];
            if q.u < self.lo[k].0 {
                self.lo[k] = (q.u, p.id);
            }
            if q.u > self.hi[k].0 {
                self.hi[k] = (q.u, p.id);
            }
            // A NaN makes the bound NaN for good, which writes nothing.
            self.bound[k] = if q.u.is_nan() || q.lo.is_nan() || self.bound[k].is_nan() {
                f64::NAN
            } else {
                self.bound[k].min(q.lo)
            };
        }
    }

    /// Writes the chain as a flat cover into every face in front of all its vertices.
    fn write(&self, horizon: &mut Horizon) {
        for k in 0..FACES {
            if self.mask & (1 << k) != 0 {
                horizon.write_flat(k, self.lo[k], self.hi[k], self.bound[k]);
            }
        }
    }
}

/// The root of `v` in a patch's union-find (path halving).
#[inline]
fn find(parent: &mut [u8], mut v: u8) -> u8 {
    while parent[v as usize] != v {
        let up = parent[parent[v as usize] as usize];
        parent[v as usize] = up;
        v = up;
    }
    v
}

/// Patches spanning fewer columns than this (about `radius · columns / distance`) also write their chains.
const CHAIN_COLUMNS: f64 = 4.0;

/// No triangle on this side of a patch edge.
const NO_TRIANGLE: u8 = u8::MAX;

/// Orders non-negative distances as integers (their bit patterns are monotone).
#[inline]
fn key(d: f64) -> u64 {
    d.max(0.0).to_bits()
}

/// The x,y box and the highest vertex of a set of triangles: min and max are exact, so the extent of a union is the
/// union of the extents.
#[derive(Clone, Copy, Debug)]
struct Extent {
    lo: [f64; 2],
    hi: [f64; 2],
    zmax: f64,
}

impl Extent {
    /// The extent of no vertex.
    const EMPTY: Extent = Extent {
        lo: [f64::INFINITY; 2],
        hi: [f64::NEG_INFINITY; 2],
        zmax: f64::NEG_INFINITY,
    };

    /// The extent of the vertices of the triangles `range`.
    fn of(h: &Hierarchy, range: [u32; 2]) -> Extent {
        let mut e = Extent::EMPTY;
        for t in &h.mesh.triangles[range[0] as usize..range[1] as usize] {
            for &v in t {
                let p = h.mesh.positions[v as usize];
                e.lo = [e.lo[0].min(p[0]), e.lo[1].min(p[1])];
                e.hi = [e.hi[0].max(p[0]), e.hi[1].max(p[1])];
                e.zmax = e.zmax.max(p[2]);
            }
        }
        e
    }

    /// The extent of both.
    fn union(&self, other: &Extent) -> Extent {
        Extent {
            lo: [self.lo[0].min(other.lo[0]), self.lo[1].min(other.lo[1])],
            hi: [self.hi[0].max(other.hi[0]), self.hi[1].max(other.hi[1])],
            zmax: self.zmax.max(other.zmax),
        }
    }

    /// The centre of the box of the triangles `range` (the origin when there are none).
    fn centre(&self, range: [u32; 2]) -> [f64; 2] {
        if range[0] == range[1] {
            [0.0; 2]
        } else {
            [0.5 * (self.lo[0] + self.hi[0]), 0.5 * (self.lo[1] + self.hi[1])]
        }
    }
}

/// The largest squared x,y distance from `centre` of the vertices of the triangles `range`.
fn farthest(h: &Hierarchy, range: [u32; 2], centre: [f64; 2]) -> f64 {
    let mut r2: f64 = 0.0;
    for t in &h.mesh.triangles[range[0] as usize..range[1] as usize] {
        for &v in t {
            let p = h.mesh.positions[v as usize];
            let (dx, dy) = (p[0] - centre[0], p[1] - centre[1]);
            r2 = r2.max(dx * dx + dy * dy);
        }
    }
    r2
}

/// A tree node over the triangles `range` (no children yet): the circle around `centre` of squared radius `r2`,
/// grown by a relative 1e-12 and 1e-9 m (and more far from the origin), and the highest vertex of `extent`.
fn node_of(range: [u32; 2], extent: &Extent, centre: [f64; 2], r2: f64) -> TreeNode {
    let scale = centre[0].abs() + centre[1].abs();
    TreeNode {
        centre,
        radius: r2.sqrt() * (1.0 + 1e-12) + 1e-12 * scale + 1e-9,
        zmax: extent.zmax,
        triangles: range,
        kids: [0, 0],
        verts: [0, 0],
        tris: [0, 0],
        edges: [0, 0],
        crests: [0, 0],
    }
}

impl SafeCuller {
    /// Prepares the safe culler for `h` (which must satisfy [`Hierarchy::check_invariants`], as every loaded file
    /// does).
    ///
    /// # Panics
    ///
    /// A hierarchy that breaks those invariants (built or changed in code: its fields are public) may make it panic,
    /// exhaust memory or never return; [`crate::AnyCuller::checked`] checks one first.
    pub fn new(h: &Hierarchy, params: SafeParams) -> SafeCuller {
        let params = SafeParams {
            columns_per_face: params
                .columns_per_face
                .clamp(2, MAX_COLUMNS_PER_FACE)
                .next_power_of_two(),
            patch: params.patch.clamp(1, MAX_PATCH),
            occluder_budget: params.occluder_budget,
            work_budget: params.work_budget,
            coarse_columns: params.coarse_columns,
        };
        let pos = &h.mesh.positions;
        let mut c = SafeCuller {
            params,
            nodes: Vec::new(),
            children: Vec::new(),
            roots: Vec::new(),
            verts: Vec::new(),
            vids: Vec::new(),
            tris: Vec::new(),
            crests: Vec::new(),
            edges: Vec::new(),
            normals: Vec::new(),
            triangles: h.mesh.triangles.len() as u32,
            scale: Scale::of(pos),
            cells: None,
        };
        // Hierarchy nodes first (same ids), then the halving trees. A hierarchy node's extent is its children's
        // together (they partition its range): computed bottom-up, by increasing level.
        let n = h.nodes.len();
        let mut extents = vec![Extent::EMPTY; n];
        let mut by_level: Vec<usize> = (0..n).collect();
        by_level.sort_by_key(|&i| h.nodes[i].level);
        c.nodes = vec![node_of([0, 0], &Extent::EMPTY, [0.0; 2], 0.0); n];
        for i in by_level {
            let node = &h.nodes[i];
            c.nodes[i] = if node.children.is_empty() {
                extents[i] = Extent::of(h, node.triangles);
                c.bounds(h, node.triangles, &extents[i])
            } else {
                extents[i] = node
                    .children
                    .iter()
                    .fold(Extent::EMPTY, |e, &k| e.union(&extents[k as usize]));
                c.bounds_from_descendants(h, i, &extents[i])
            };
        }
        let mut kids: Vec<Vec<u32>> = h.nodes.iter().map(|n| n.children.clone()).collect();
        for (i, node) in h.nodes.iter().enumerate() {
            if node.children.is_empty() {
                kids[i] = c.halve_below(h, i as u32, &mut Vec::new());
            }
        }
        for (i, k) in kids.into_iter().enumerate() {
            let start = c.children.len() as u32;
            c.children.extend(k);
            c.nodes[i].kids = [start, c.children.len() as u32];
        }
        let mut roots: Vec<u32> = h.roots.clone();
        roots.sort_by_key(|&r| h.nodes[r as usize].triangles[0]);
        let [a, b] = h.always_visible;
        if a < b {
            roots.push(c.halving_tree(h, [a, b]));
        }
        c.roots = roots;
        if c.params.coarse_columns > 0 {
            // Crests are a function of the triangle range: nodes of one range share them. The triangles scanned are
            // bounded (see `CREST_SCANS_PER_TRIANGLE`); nodes past the bound get none.
            let mut by_range: HashMap<[u32; 2], [u32; 2]> = HashMap::new();
            let mut room = CREST_SCANS_PER_TRIANGLE * h.mesh.triangles.len() as u64 + u64::from(CREST_MAX);
            for id in 0..c.nodes.len() {
                let node = c.nodes[id];
                let [s, e] = node.triangles;
                if !(node.kids[0] < node.kids[1] && e - s <= CREST_MAX) {
                    continue;
                }
                if let Some(&crests) = by_range.get(&[s, e]) {
                    c.nodes[id].crests = crests;
                    continue;
                }
                let Some(left) = room.checked_sub(u64::from(e - s)) else {
                    continue;
                };
                room = left;
                let start = c.crests.len() as u32;
                crests_of(
                    &h.mesh.triangles[s as usize..e as usize],
                    &h.mesh.positions,
                    &mut c.crests,
                );
                c.nodes[id].crests = [start, c.crests.len() as u32];
                by_range.insert([s, e], c.nodes[id].crests);
            }
        }
        // Every node is tested at most once, every patch edge and every crest written at most once, and a patch has
        // no more chains than edges: a budget above their sum is never spent.
        let most_work = c.nodes.len() + 2 * c.edges.len() + c.crests.len();
        if most_work >= c.params.work_budget {
            c.cells = Some(CellEdges::new(h, &c.scale));
        }
        c
    }

    /// Writes the crests of node `id` into the horizon as flat covers, in every face whose half-plane `f > 0` holds
    /// the node's whole circle (see the module documentation).
    fn write_crests(&self, horizon: &mut Horizon, id: u32, eye: [f64; 3], mu: f64, count: &mut Count) {
        let node = &self.nodes[id as usize];
        let m = [node.centre[0] - eye[0], node.centre[1] - eye[1]];
        let dist = (m[0] * m[0] + m[1] * m[1]).sqrt();
        // The offset carries a rounding error below ε |m|: grow the circle by more.
        let r = node.radius + 1e-15 * dist;
        for crest in &self.crests[node.crests[0] as usize..node.crests[1] as usize] {
            if !count.can_write(&self.params) {
                return;
            }
            count.flats += 1;
            let off = |p: [f64; 3]| [p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]];
            let pa = project(off(crest.a), mu, PointId::vertex(crest.ids[0]));
            let pb = project(off(crest.b), mu, PointId::vertex(crest.ids[1]));
            let num = crest.z - eye[2] - mu;
            for k in 0..FACES {
                let (mf, _) = face_coords(k, m[0], m[1]);
                if !(mf - r > 0.0) || pa.mask & pb.mask & (1 << k) == 0 {
                    continue;
                }
                // Every point of the node has f in [mf − r, mf + r].
                let (f_lo, f_hi) = ((mf - r) * (1.0 - REL), (mf + r) * (1.0 + REL));
                let v = if num >= 0.0 { num / f_hi } else { num / f_lo };
                let v = v - REL * v.abs();
                horizon.write_flat(k, (pa.face[k].u, pa.id), (pb.face[k].u, pb.id), v);
            }
        }
    }

    /// The children of hierarchy leaf `i` in its halving tree (empty when the leaf is small enough to be a patch,
    /// which then becomes one).
    fn halve_below(&mut self, h: &Hierarchy, i: u32, _: &mut Vec<u32>) -> Vec<u32> {
        let [s, e] = self.nodes[i as usize].triangles;
        if (e - s) as usize <= self.params.patch {
            self.make_patch(h, i);
            return Vec::new();
        }
        let mid = s + (e - s) / 2;
        vec![self.halving_tree(h, [s, mid]), self.halving_tree(h, [mid, e])]
    }

    /// A halving tree over `range`; returns its root.
    fn halving_tree(&mut self, h: &Hierarchy, range: [u32; 2]) -> u32 {
        self.halving_subtree(h, range).0
    }

    /// [`SafeCuller::halving_tree`], also returning the extent of `range` (its halves' together, bottom-up). A node's
    /// id comes before its children's.
    fn halving_subtree(&mut self, h: &Hierarchy, range: [u32; 2]) -> (u32, Extent) {
        let id = self.nodes.len() as u32;
        let [s, e] = range;
        if (e - s) as usize <= self.params.patch {
            let extent = Extent::of(h, range);
            self.nodes.push(self.bounds(h, range, &extent));
            self.make_patch(h, id);
            return (id, extent);
        }
        // Its place first; its bounds once its halves are done.
        self.nodes.push(node_of([s, s], &Extent::EMPTY, [0.0; 2], 0.0));
        let mid = s + (e - s) / 2;
        let (a, ea) = self.halving_subtree(h, [s, mid]);
        let (b, eb) = self.halving_subtree(h, [mid, e]);
        let extent = ea.union(&eb);
        let start = self.children.len() as u32;
        self.children.extend([a, b]);
        self.nodes[id as usize] = TreeNode {
            kids: [start, start + 2],
            ..self.bounds(h, range, &extent)
        };
        (id, extent)
    }

    /// Stores the local vertices and triangles of node `id`, which becomes a patch.
    fn make_patch(&mut self, h: &Hierarchy, id: u32) {
        let [s, e] = self.nodes[id as usize].triangles;
        let v0 = self.verts.len() as u32;
        let t0 = self.tris.len() as u32;
        let mut local: Vec<(u32, u8)> = Vec::new();
        for t in &h.mesh.triangles[s as usize..e as usize] {
            let mut tri = [0u8; 3];
            for (k, &v) in t.iter().enumerate() {
                let at = match local.iter().find(|(g, _)| *g == v) {
                    Some(&(_, l)) => l,
                    None => {
                        let l = local.len() as u8;
                        local.push((v, l));
                        self.verts.push(h.mesh.positions[v as usize]);
                        self.vids.push(v);
                        l
                    }
                };
                tri[k] = at;
            }
            let [a, b, c] = t.map(|v| h.mesh.positions[v as usize]);
            let (u, w) = (
                [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
                [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
            );
            self.normals.push([
                u[1] * w[2] - u[2] * w[1],
                u[2] * w[0] - u[0] * w[2],
                u[0] * w[1] - u[1] * w[0],
            ]);
            self.tris.push(tri);
        }
        // The patch's edges, each once, with the triangles on both sides.
        let e0 = self.edges.len();
        for (i, t) in self.tris[t0 as usize..].iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                match self.edges[e0..]
                    .iter_mut()
                    .find(|e| e[0] == b && e[1] == a && e[3] == NO_TRIANGLE)
                {
                    Some(e) => e[3] = i as u8,
                    None => self.edges.push([a, b, i as u8, NO_TRIANGLE]),
                }
            }
        }
        let node = &mut self.nodes[id as usize];
        node.verts = [v0, self.verts.len() as u32];
        node.tris = [t0, self.tris.len() as u32];
        node.edges = [e0 as u32, self.edges.len() as u32];
    }

    /// The bounds of the triangles `range`, whose box and highest vertex are `extent` (f64, from the mesh): circle
    /// around the x,y box's centre through the farthest vertex, grown by a relative 1e-12 and 1e-9 m; the highest
    /// vertex.
    fn bounds(&self, h: &Hierarchy, range: [u32; 2], extent: &Extent) -> TreeNode {
        let centre = extent.centre(range);
        node_of(range, extent, centre, farthest(h, range, centre))
    }

    /// The bounds of hierarchy node `i` (as [`SafeCuller::bounds`] computes them) from its extent and the bounds
    /// already computed of its descendants in the hierarchy: the farthest vertex is sought only in descendants whose
    /// circle may hold a vertex at least as far as the farthest found so far.
    ///
    /// Exactness: a vertex `p` of a descendant `k` (circle `c_k`, `r_k`, which holds every vertex of `k`) has
    /// `|p − c| ≤ |c_k − c| + r_k`; the computed `d ≥ |c_k − c| (1 − 4ε)`, and the computed square of `p`'s distance
    /// (the same arithmetic as in [`farthest`]) is at most `|p − c|² (1 + 6ε)`. So when
    /// `((d + r_k)(1 + 1e-9))²`, computed, is below the largest square found so far, every vertex of `k` computes
    /// below it too, and the maximum (hence the radius) is the one a scan of every vertex gives, bit for bit.
    ///
    /// At most [`MAX_DESCENDANT_STEPS`] descendants are taken. When more remain, the square of the farthest reach
    /// `b` among them also bounds the radius: `b ≥ (d + r_k)(1 + 1e-9)(1 − 3ε)` for the descendant `k` it belongs
    /// to and every one left in the queue (the queue's largest), hence `b > |p − c| (1 + 1e-10)` for each of their
    /// vertices `p`, and the square root of the computed `b²` (at least `b (1 − ε)`) still exceeds `|p − c|`. The
    /// circle then holds every vertex and may be a little wider than the farthest one needs, which only culls less.
    /// Each leaf is scanned by at most its `MAX_DESCENDANT_STEPS` nearest ancestors (an ancestor reaches a
    /// descendant only after taking every node between them), so preparing a hierarchy costs
    /// `O(MAX_DESCENDANT_STEPS · (nodes + triangles))`, however deep it is (a chain of 80,000 nodes took 51 s
    /// without the limit).
    fn bounds_from_descendants(&self, h: &Hierarchy, i: usize, extent: &Extent) -> TreeNode {
        let range = h.nodes[i].triangles;
        let centre = extent.centre(range);
        let reach = |k: u32| {
            let n = &self.nodes[k as usize];
            let (dx, dy) = (n.centre[0] - centre[0], n.centre[1] - centre[1]);
            ((dx * dx + dy * dy).sqrt() + n.radius) * (1.0 + 1e-9)
        };
        // Farthest-reaching descendants first (non-negative f64 bits order as the values).
        let mut queue: BinaryHeap<(u64, u32)> = h.nodes[i].children.iter().map(|&k| (reach(k).to_bits(), k)).collect();
        let mut r2: f64 = 0.0;
        let mut steps = 0;
        while let Some((bound, k)) = queue.pop() {
            let bound = f64::from_bits(bound);
            if bound * bound < r2 {
                break;
            }
            if steps == MAX_DESCENDANT_STEPS {
                r2 = bound * bound;
                break;
            }
            steps += 1;
            let node = &h.nodes[k as usize];
            if node.children.is_empty() {
                r2 = r2.max(farthest(h, node.triangles, centre));
            } else {
                queue.extend(node.children.iter().map(|&j| (reach(j).to_bits(), j)));
            }
        }
        node_of(range, extent, centre, r2)
    }

    /// Writes every eligible occluder patch into the horizon (within the budget) and forgets them.
    ///
    /// A patch is written as those of its edges that can bound its image from above: seen from the camera, an edge
    /// with a patch triangle on each side of it in the image (both facing the camera, or both facing away) is
    /// covered above by one of them, so only the patch's boundary and silhouette edges with the patch below them
    /// are written. Which edges are written only decides how much is culled (every TIN edge lies on the terrain).
    /// A patch whose highest lowered vertex is at most `H` in every column it spans is skipped: it could raise none.
    fn flush(
        &self,
        horizon: &mut Horizon,
        eligible: &mut Vec<(u32, u32, Reach)>,
        projected: &[Projected],
        eye: [f64; 3],
        count: &mut Count,
    ) {
        let mut facing = [0.0f64; 64];
        // Union-find over a patch's local vertices (at most 3 · 64), joined by the edges written.
        let mut parent = [0u8; 192];
        let mut touched = [false; 192];
        for (patch, at, reach) in eligible.iter() {
            if !count.can_write(&self.params) {
                break;
            }
            // Nothing of a patch that cannot raise any column needs looking at.
            if !horizon.can_raise(reach) {
                continue;
            }
            let p = &self.nodes[*patch as usize];
            let base = *at as usize;
            let verts = &self.verts[p.verts[0] as usize..p.verts[1] as usize];
            let nv = verts.len();
            let off = |i: u8| {
                let v = verts[i as usize];
                [v[0] - eye[0], v[1] - eye[1], v[2] - eye[2]]
            };
            let tris = p.tris[0] as usize..p.tris[1] as usize;
            for ((f, t), n) in facing.iter_mut().zip(&self.tris[tris.clone()]).zip(&self.normals[tris]) {
                // Negative when the camera sees the upper side of the (counter-clockwise) triangle.
                let a = off(t[0]);
                *f = a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
            }
            // Chains (below) only where the patch is small on screen: its circle spans fewer than `CHAIN_COLUMNS`
            // columns, so its edges are about a column long or shorter; nearer, its edges cover the columns by
            // themselves.
            let (dx, dy) = (p.centre[0] - eye[0], p.centre[1] - eye[1]);
            let w = self.params.columns_per_face as f64;
            let chains = p.radius * w < CHAIN_COLUMNS * (dx * dx + dy * dy).sqrt();
            if chains {
                for (i, (q, t)) in parent.iter_mut().zip(touched.iter_mut()).take(nv).enumerate() {
                    *q = i as u8;
                    *t = false;
                }
            }
            let mut joined = false;
            for e in &self.edges[p.edges[0] as usize..p.edges[1] as usize] {
                if !count.can_write(&self.params) {
                    break;
                }
                let (a, b) = (off(e[0]), off(e[1]));
                // Positive when a → b turns counter-clockwise around the camera (u grows).
                let dir = a[0] * b[1] - a[1] * b[0];
                // Triangle t (with a → b along its winding when `s` is 1) lies below the edge in the image.
                let below = |t: u8, s: f64| facing[t as usize] * dir * s < 0.0;
                let top = below(e[2], 1.0) && (e[3] == NO_TRIANGLE || below(e[3], -1.0));
                let flat = facing[e[2] as usize] == 0.0 || dir == 0.0;
                if !(top || flat) {
                    continue;
                }
                count.edges += 1;
                horizon.write_segment([&projected[base + e[0] as usize], &projected[base + e[1] as usize]]);
                if chains {
                    let (ra, rb) = (find(&mut parent, e[0]), find(&mut parent, e[1]));
                    joined |= touched[e[0] as usize] || touched[e[1] as usize];
                    touched[e[0] as usize] = true;
                    touched[e[1] as usize] = true;
                    if ra != rb {
                        parent[ra as usize] = rb;
                    }
                }
            }
            // Chains of two edges or more, also as flat covers: a chain crossing a column in several short edges covers
            // it, which edge by edge only the partial covers of its first and last edge could (and cannot pair).
            if !joined {
                continue;
            }
            // The touched vertices grouped by their root, then one chain per group of three vertices or more.
            let mut members = [(0u8, 0u8); 192];
            let mut n = 0;
            for v in 0..nv as u8 {
                if touched[v as usize] {
                    members[n] = (find(&mut parent, v), v);
                    n += 1;
                }
            }
            let members = &mut members[..n];
            members.sort_unstable();
            for group in members.chunk_by(|a, b| a.0 == b.0) {
                if group.len() < 3 {
                    continue;
                }
                if !count.can_write(&self.params) {
                    break;
                }
                let mut chain = Chain::default();
                for &(_, v) in group {
                    chain.add(&projected[base + v as usize]);
                }
                count.flats += 1;
                chain.write(horizon);
            }
        }
        eligible.clear();
    }

    /// The parameters in use.
    pub fn params(&self) -> SafeParams {
        self.params
    }

    /// Nodes of the culling tree (hierarchy nodes and the halving trees below them).
    pub fn tree_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Roots of the culling tree (the hierarchy's roots, and the always-visible set's halving tree).
    pub fn roots(&self) -> usize {
        self.roots.len()
    }

    /// Culls for `camera`, returning a new draw list.
    pub fn cull(&self, camera: &Camera) -> DrawList {
        let mut out = DrawList::default();
        self.cull_into(camera, &mut out);
        out
    }

    /// Culls for `camera` into `out` (cleared first); reuses `out`'s working memory.
    pub fn cull_into(&self, camera: &Camera, out: &mut DrawList) {
        out.ranges.clear();
        out.stats = CullStats::default();
        let mut scratch = std::mem::take(&mut out.scratch);
        let eye = camera.position;
        if !eye.iter().all(|c| c.is_finite()) {
            out.push([0, self.triangles]);
            out.stats.nodes_skipped = self.nodes.len() as u32;
            out.scratch = scratch;
            return;
        }
        let mut owned = match scratch.horizon.take() {
            Some(h) if h.columns_per_face() == self.params.columns_per_face => h,
            _ => Horizon::new(self.params.columns_per_face),
        };
        let horizon = &mut owned;
        horizon.clear();
        scratch.queue.clear();
        scratch.pending.clear();
        scratch.projected.clear();
        scratch.drawn.clear();
        scratch.eligible.clear();
        let mu = self.scale.margin(eye);
        let frustum = camera.frustum();
        let distance = |n: &TreeNode| {
            let (dx, dy) = (n.centre[0] - eye[0], n.centre[1] - eye[1]);
            (dx * dx + dy * dy).sqrt()
        };
        for &r in &self.roots {
            let n = &self.nodes[r as usize];
            scratch.queue.push(Reverse((key(distance(n) - n.radius), r)));
        }
        let mut tested = 0u32;
        let mut count = Count::default();
        while let Some(Reverse((dmin_key, id))) = scratch.queue.pop() {
            let node = &self.nodes[id as usize];
            let dist = distance(node);
            if count.work() >= self.params.work_budget {
                // The budget is spent: stop refining and writing (below).
                scratch.queue.push(Reverse((dmin_key, id)));
                break;
            }
            count.tests += 1;
            // Occluders strictly nearer than every point of this node (rounding: the distances carry relative
            // errors below 1e-15, so compare with a relative gap far larger).
            let dmin = (dist - node.radius) * (1.0 - 1e-12);
            // Drawn patches entirely nearer than this node become eligible occluders; they are written only when
            // a test could use them (below), which saves most of the work in views that see much terrain.
            while let Some(&Reverse((dmax_key, patch, at))) = scratch.pending.peek() {
                if !(f64::from_bits(dmax_key) < dmin) {
                    break;
                }
                scratch.pending.pop();
                if at == CRESTS {
                    self.write_crests(horizon, patch, eye, mu, &mut count);
                    continue;
                }
                let p = &self.nodes[patch as usize];
                let n = (p.verts[1] - p.verts[0]) as usize;
                let reach = horizon.raise_potential_reach(&scratch.projected[at as usize..at as usize + n]);
                scratch.eligible.push((patch, at, reach));
            }
            let _ = dmin_key;
            tested += 1;
            if let Some((yaw, half_fov)) = frustum
                && outside_view(node, eye, yaw, half_fov)
            {
                out.stats.culled_by_frustum += 1;
                continue;
            }
            let inside = dist <= node.radius;
            if !inside {
                let m = [node.centre[0] - eye[0], node.centre[1] - eye[1]];
                let dz = node.zmax - eye[2] + mu;
                // The disk's columns and bound once, then tested against the horizon, and against its potential.
                let span = horizon.disk_span(m, node.radius, dz);
                let test = |horizon: &Horizon, with_potential| {
                    span.is_some_and(|span| horizon.span_hidden(&span, with_potential))
                };
                let mut hidden = test(horizon, false);
                if !hidden && !scratch.eligible.is_empty() && test(horizon, true) {
                    self.flush(horizon, &mut scratch.eligible, &scratch.projected, eye, &mut count);
                    hidden = test(horizon, false);
                }
                if hidden {
                    out.stats.culled_by_occlusion += 1;
                    continue;
                }
            }
            // Small on screen (angular radius times columns per radian, near enough): drawn whole, its crests queued
            // as occluders.
            let columns = (self.params.columns_per_face as f64, self.params.coarse_columns as f64);
            if node.kids[0] < node.kids[1]
                && !inside
                && node.crests[0] < node.crests[1]
                && node.radius * columns.0 < columns.1 * dist
            {
                scratch.drawn.push(node.triangles);
                let dmax = (dist + node.radius) * (1.0 + 1e-12);
                scratch.pending.push(Reverse((key(dmax), id, CRESTS)));
                continue;
            }
            if node.kids[0] < node.kids[1] {
                for &c in &self.children[node.kids[0] as usize..node.kids[1] as usize] {
                    let n = &self.nodes[c as usize];
                    scratch.queue.push(Reverse((key(distance(n) - n.radius), c)));
                }
                continue;
            }
            // A patch: project its vertices, test its triangles one by one.
            let at = scratch.projected.len();
            let range = node.verts[0] as usize..node.verts[1] as usize;
            for (p, &v) in self.verts[range.clone()].iter().zip(&self.vids[range]) {
                scratch.projected.push(project(
                    [p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]],
                    mu,
                    PointId::vertex(v),
                ));
            }
            let tris = &self.tris[node.tris[0] as usize..node.tris[1] as usize];
            let nv = node.verts[1] as usize - node.verts[0] as usize;
            let all_hidden = |horizon: &Horizon, projected: &[Projected], with_potential: bool| {
                // The patch's vertices first (cheap, and enough for most hidden patches), then triangle by triangle.
                let verts = &projected[at..at + nv];
                !horizon.vertex_above(verts, with_potential)
                    && (horizon.vertices_hidden(verts, with_potential)
                        || tris.iter().all(|t| {
                            horizon.triangle_hidden(
                                [
                                    &projected[at + t[0] as usize],
                                    &projected[at + t[1] as usize],
                                    &projected[at + t[2] as usize],
                                ],
                                with_potential,
                            )
                        }))
            };
            let mut hidden = !inside && all_hidden(horizon, &scratch.projected, false);
            if !inside && !hidden && !scratch.eligible.is_empty() && all_hidden(horizon, &scratch.projected, true) {
                self.flush(horizon, &mut scratch.eligible, &scratch.projected, eye, &mut count);
                hidden = all_hidden(horizon, &scratch.projected, false);
            }
            let all_hidden = hidden;
            if all_hidden {
                scratch.projected.truncate(at);
                out.stats.culled_by_occlusion += 1;
                continue;
            }
            scratch.drawn.push(node.triangles);
            let dmax = (dist + node.radius) * (1.0 + 1e-12);
            scratch.pending.push(Reverse((key(dmax), id, at as u32)));
        }
        if !scratch.queue.is_empty() {
            // The budget is spent. Every occluder in the horizon is nearer than every point of every node still
            // queued (as when it was written), so the horizon stays valid for them and their descendants. The
            // largest nodes first: each is tested once by its cylinder and culled if hidden, else split while fewer
            // than `⌈B / 8⌉` were, else kept to be drawn whole.
            scratch.by_size.clear();
            scratch.whole.clear();
            for Reverse((_, id)) in scratch.queue.drain() {
                let [s, e] = self.nodes[id as usize].triangles;
                scratch.by_size.push((e - s, id));
            }
            let cap = self.params.work_budget.div_ceil(8);
            let mut splits = 0usize;
            while let Some((_, id)) = scratch.by_size.pop() {
                let node = &self.nodes[id as usize];
                tested += 1;
                if let Some((yaw, half_fov)) = frustum
                    && outside_view(node, eye, yaw, half_fov)
                {
                    out.stats.culled_by_frustum += 1;
                    continue;
                }
                let dist = distance(node);
                if !(dist <= node.radius) {
                    let m = [node.centre[0] - eye[0], node.centre[1] - eye[1]];
                    if horizon.disk_hidden(m, node.radius, node.zmax - eye[2] + mu, false) {
                        out.stats.culled_by_occlusion += 1;
                        continue;
                    }
                }
                if node.kids[0] < node.kids[1] && splits < cap {
                    splits += 1;
                    for &c in &self.children[node.kids[0] as usize..node.kids[1] as usize] {
                        let [s, e] = self.nodes[c as usize].triangles;
                        scratch.by_size.push((e - s, c));
                    }
                    continue;
                }
                scratch.whole.push((key(dist - node.radius), id));
            }
            count.splits = splits;
            // The nodes kept, nearest first (by the least distance of their own circles), tested once more against
            // the horizon and the cell-edge occluders around the nodes drawn before them (at most `⌈B / 8⌉`
            // segments, within the occluder budget), each written once it is nearer than the node under test.
            scratch.whole.sort_unstable();
            let mut room = cap.min(self.params.occluder_budget.saturating_sub(count.edges));
            if let Some(cells) = &self.cells {
                scratch.cell_edges.begin(cells);
            }
            for &(_, id) in &scratch.whole {
                let node = &self.nodes[id as usize];
                if let Some(cells) = &self.cells {
                    let dist = distance(node);
                    let dmin = (dist - node.radius) * (1.0 - 1e-12);
                    count.cell_edges += cells.write_nearer(dmin, eye, mu, horizon, &mut scratch.cell_edges);
                    let m = [node.centre[0] - eye[0], node.centre[1] - eye[1]];
                    if !(dist <= node.radius)
                        && count.cell_edges > 0
                        && horizon.disk_hidden(m, node.radius, node.zmax - eye[2] + mu, false)
                    {
                        out.stats.culled_by_occlusion += 1;
                        continue;
                    }
                    let r = node.radius;
                    let (lo, hi) = (
                        [node.centre[0] - r, node.centre[1] - r],
                        [node.centre[0] + r, node.centre[1] + r],
                    );
                    cells.queue_box(lo, hi, eye, &mut scratch.cell_edges, &mut room);
                }
                scratch.drawn.push(node.triangles);
            }
        }
        scratch.drawn.sort_unstable();
        for &r in &scratch.drawn {
            out.push(r);
        }
        out.stats.nodes_tested = tested;
        out.stats.work = count.work() as u32;
        out.stats.occluder_edges = (count.edges + count.cell_edges) as u32;
        out.stats.nodes_skipped = self.nodes.len() as u32 - tested;
        out.stats.triangles_culled = self.triangles - out.stats.triangles_drawn;
        scratch.horizon = Some(owned);
        out.scratch = scratch;
    }
}

/// Appends the crests of the triangles `tris` (indices into `pos`) to `out`: for x and for y, the vertices within
/// the first and the last quarter of their extent, and the bottleneck path between the two sets over their TIN edges
/// (edges taken by decreasing lower end, union-find, until one component holds a vertex of each set; every vertex of
/// the path joining them is at least as high as the last edge's lower end).
fn crests_of(tris: &[[u32; 3]], pos: &[[f64; 3]], out: &mut Vec<Crest>) {
    let mut vs: Vec<u32> = tris.iter().flatten().copied().collect();
    vs.sort_unstable();
    vs.dedup();
    let local = |v: u32| vs.binary_search(&v).ok();
    let mut edges: Vec<(f64, u32, u32)> = Vec::with_capacity(3 * tris.len());
    for t in tris {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if let (Some(la), Some(lb)) = (local(a), local(b)) {
                let z = pos[a as usize][2].min(pos[b as usize][2]);
                edges.push((z, la.min(lb) as u32, la.max(lb) as u32));
            }
        }
    }
    edges.sort_unstable_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
    edges.dedup_by(|x, y| x.1 == y.1 && x.2 == y.2);
    const NONE: u32 = u32::MAX;
    for axis in 0..2 {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for &v in &vs {
            lo = lo.min(pos[v as usize][axis]);
            hi = hi.max(pos[v as usize][axis]);
        }
        let quarter = 0.25 * (hi - lo);
        if !(quarter > 0.0) {
            continue;
        }
        let mut parent: Vec<u32> = (0..vs.len() as u32).collect();
        let mut reps: Vec<[u32; 2]> = vs
            .iter()
            .enumerate()
            .map(|(i, &v)| {
                let x = pos[v as usize][axis];
                [
                    if x <= lo + quarter { i as u32 } else { NONE },
                    if x >= hi - quarter { i as u32 } else { NONE },
                ]
            })
            .collect();
        fn root(parent: &mut [u32], mut v: u32) -> u32 {
            while parent[v as usize] != v {
                let up = parent[parent[v as usize] as usize];
                parent[v as usize] = up;
                v = up;
            }
            v
        }
        for &(z, a, b) in &edges {
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            if ra == rb {
                continue;
            }
            parent[ra as usize] = rb;
            let merged = [
                if reps[rb as usize][0] == NONE {
                    reps[ra as usize][0]
                } else {
                    reps[rb as usize][0]
                },
                if reps[rb as usize][1] == NONE {
                    reps[ra as usize][1]
                } else {
                    reps[rb as usize][1]
                },
            ];
            reps[rb as usize] = merged;
            if merged[0] != NONE && merged[1] != NONE {
                let (va, vb) = (vs[merged[0] as usize], vs[merged[1] as usize]);
                out.push(Crest {
                    a: pos[va as usize],
                    b: pos[vb as usize],
                    ids: [va, vb],
                    z,
                });
                break;
            }
        }
    }
}

/// Whether every direction from the eye to the node's circle misses the horizontal view `yaw ± half_fov`.
fn outside_view(node: &TreeNode, eye: [f64; 3], yaw: f64, half_fov: f64) -> bool {
    let centre = [node.centre[0] - eye[0], node.centre[1] - eye[1]];
    circle_outside_view(centre, node.radius, yaw, half_fov)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The values a front end accepts: the default, powers of two from 2 to 65,536 columns, patches of 1 to 64
    /// triangles, any budget; and the first value refused on either side of each range.
    #[test]
    fn parameters_are_checked_at_the_ends_of_their_ranges() {
        let d = SafeParams::default();
        assert_eq!(d.check(), Ok(()));
        for columns in [2, 4, 256, 1 << 16] {
            assert_eq!(
                SafeParams {
                    columns_per_face: columns,
                    ..d
                }
                .check(),
                Ok(())
            );
        }
        for columns in [0, 1, 3, 96, (1 << 16) + 1, 1 << 17] {
            assert_eq!(
                SafeParams {
                    columns_per_face: columns,
                    ..d
                }
                .check(),
                Err(SafeParamsError::Columns(columns))
            );
        }
        for patch in [1, 64] {
            assert_eq!(SafeParams { patch, ..d }.check(), Ok(()));
        }
        for patch in [0, 65] {
            assert_eq!(SafeParams { patch, ..d }.check(), Err(SafeParamsError::Patch(patch)));
        }
        let any = SafeParams {
            occluder_budget: 0,
            work_budget: 0,
            coarse_columns: usize::MAX,
            ..d
        };
        assert_eq!(any.check(), Ok(()));
        assert_eq!(
            SafeParamsError::Columns(3).to_string(),
            "the columns per face must be a power of two from 2 to 65536, got 3"
        );
    }

    /// A hierarchy as deep as it has nodes: a caterpillar, each node a leaf of one triangle beside the node over the
    /// rest, under a chain of `chain` nodes of one child each. The `leaves` triangles make a fan whose vertices all
    /// lie on one circle.
    fn caterpillar(leaves: u32, chain: u32) -> Hierarchy {
        use crate::hierarchy::{Mesh, Node};
        let angle = |i: u32| f64::from(i) * std::f64::consts::TAU / f64::from(leaves + 1);
        let mut positions: Vec<[f64; 3]> = (0..=leaves)
            .map(|i| [3.0 + 100.0 * angle(i).cos(), -2.0 + 100.0 * angle(i).sin(), 1.0])
            .collect();
        positions.push([3.0, -2.0, 0.0]);
        let triangles: Vec<[u32; 3]> = (0..leaves).map(|i| [i, i + 1, leaves + 1]).collect();
        let node = |children: Vec<u32>, triangles: [u32; 2], level: u32| Node {
            centre: [0.0; 2],
            radius: 0.0,
            children,
            triangles,
            level,
            regions: vec![],
        };
        // Leaf t is node t; the caterpillar node over [t, leaves) is node leaves + t (t < leaves - 1), the last
        // leaf standing for itself; the chain's nodes follow, the top one the root.
        let mut nodes: Vec<Node> = (0..leaves).map(|t| node(vec![], [t, t + 1], 0)).collect();
        let over = |t: u32| if t + 1 == leaves { t } else { leaves + t };
        for t in 0..leaves - 1 {
            nodes.push(node(vec![t, over(t + 1)], [t, leaves], leaves - 1 - t));
        }
        for k in 0..chain {
            let below = if k == 0 { over(0) } else { nodes.len() as u32 - 1 };
            nodes.push(node(vec![below], [0, leaves], leaves + k));
        }
        let h = Hierarchy {
            sectors: 16,
            origin: [0.0; 3],
            roots: vec![nodes.len() as u32 - 1],
            nodes,
            always_visible: [leaves, leaves],
            mesh: Mesh { positions, triangles },
            build: Default::default(),
        };
        h.check_invariants().expect("a valid hierarchy");
        h
    }

    /// A hierarchy as deep as it has nodes (the chain of a crafted file, which made preparing it quadratic: 80,000
    /// nodes took 51 s): the [`caterpillar`] of 600 leaves under a chain of 400 nodes. Every vertex lies on one
    /// circle, so the search for the farthest vertex prunes nothing. Every node's circle still holds each of its
    /// vertices, and a node whose subtree the search takes whole has the circle of a scan of every vertex, bit for
    /// bit.
    #[test]
    fn circles_of_deep_hierarchies_hold_every_vertex() {
        let leaves = 600u32;
        let h = caterpillar(leaves, 400);
        let c = SafeCuller::new(&h, SafeParams::default());
        let mut exact = 0;
        for (i, n) in h.nodes.iter().enumerate() {
            let got = &c.nodes[i];
            for t in &h.mesh.triangles[n.triangles[0] as usize..n.triangles[1] as usize] {
                for &v in t {
                    let p = h.mesh.positions[v as usize];
                    let d = (p[0] - got.centre[0]).hypot(p[1] - got.centre[1]);
                    assert!(
                        d <= got.radius,
                        "node {i}: vertex {v} at {d} outside the circle of radius {}",
                        got.radius
                    );
                }
            }
            let scan = c.bounds(&h, n.triangles, &Extent::of(&h, n.triangles));
            assert_eq!(got.centre, scan.centre, "node {i}");
            assert!(got.radius >= scan.radius, "node {i}");
            // A caterpillar node of `k` leaves has `2k - 1` descendants, taken whole within the limit.
            if (leaves..2 * leaves - 1).contains(&(i as u32)) && i as u32 - leaves + 64 >= leaves {
                assert_eq!(got.radius, scan.radius, "node {i}");
                exact += 1;
            }
        }
        assert_eq!(exact, 63);
        // The root's search stopped at the limit (one without it takes every node below every node: quadratic).
        let root = h.roots[0] as usize;
        assert!(c.nodes[root].radius > c.bounds(&h, [0, leaves], &Extent::of(&h, [0, leaves])).radius);
    }

    /// Crests on the [`caterpillar`] of 600 leaves under a chain of 400 nodes (a crafted file; a chain of 5,000 nodes
    /// over 2,048 triangles took 2.4 s to prepare with coarse nodes, each node scanning its range anew): nodes of one
    /// range share one computation, and the ranges scanned stay within `CREST_SCANS_PER_TRIANGLE` per triangle (the
    /// caterpillar's nested ranges alone would scan 180,000 triangles).
    #[test]
    fn crests_are_computed_once_a_range_and_within_their_bound() {
        let leaves = 600u32;
        let h = caterpillar(leaves, 400);
        let c = SafeCuller::new(
            &h,
            SafeParams {
                coarse_columns: 8,
                ..SafeParams::default()
            },
        );
        let top = &c.nodes[(2 * leaves - 1) as usize];
        assert!(top.crests[0] < top.crests[1], "the node over every leaf has crests");
        for k in 0..400 {
            assert_eq!(
                c.nodes[(2 * leaves - 1 + k) as usize].crests,
                top.crests,
                "chain node {k}"
            );
        }
        let mut computed: HashMap<[u32; 2], u32> = HashMap::new();
        for n in &c.nodes {
            if n.crests[0] < n.crests[1] {
                computed.insert(n.crests, n.triangles[1] - n.triangles[0]);
            }
        }
        let scanned: u64 = computed.values().map(|&t| u64::from(t)).sum();
        let bound = CREST_SCANS_PER_TRIANGLE * u64::from(leaves) + u64::from(CREST_MAX);
        assert!(scanned <= bound, "{scanned} triangles scanned, more than {bound}");
        assert!(
            computed.len() > 10,
            "nodes within the bound have crests: {}",
            computed.len()
        );
    }

    /// Whether the first and the last quarter of the extent along `axis` of the vertices `tris` use are joined by a
    /// path of the triangles' edges whose vertices all lie at height `z` or above (from `from` to `to` when given).
    /// A graph search, independent of the union-find of [`crests_of`].
    fn joined(tris: &[[u32; 3]], pos: &[[f64; 3]], axis: usize, z: f64, ends: Option<[u32; 2]>) -> bool {
        let used: Vec<u32> = tris.iter().flatten().copied().collect();
        let (lo, hi) = used.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(pos[v as usize][axis]), hi.max(pos[v as usize][axis]))
        });
        let q = 0.25 * (hi - lo);
        if !(q > 0.0) {
            return false;
        }
        let first = |v: u32| pos[v as usize][axis] <= lo + q;
        let last = |v: u32| pos[v as usize][axis] >= hi - q;
        let high = |v: u32| pos[v as usize][2] >= z;
        let mut stack: Vec<u32> = match ends {
            Some([a, b]) if first(a) && last(b) && high(a) => vec![a],
            Some(_) => return false,
            None => used.iter().copied().filter(|&v| first(v) && high(v)).collect(),
        };
        let mut seen = vec![false; pos.len()];
        for &v in &stack {
            seen[v as usize] = true;
        }
        while let Some(v) = stack.pop() {
            if ends.map_or(last(v), |[_, b]| v == b) {
                return true;
            }
            for t in tris {
                for k in 0..3 {
                    let (p, q) = (t[k], t[(k + 1) % 3]);
                    for (from, to) in [(p, q), (q, p)] {
                        if from == v && !seen[to as usize] && high(to) {
                            seen[to as usize] = true;
                            stack.push(to);
                        }
                    }
                }
            }
        }
        false
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 500, ..ProptestConfig::default() })]

        /// Every crest is what coarse nodes write it as, by a graph search: its ends lie in the first and the last
        /// quarter of the extent along an axis and are joined by a path of the triangles' edges whose vertices all
        /// lie at the crest's height or above, and no greater height joins those quarters (the bottleneck); an axis
        /// whose quarters are joined at all has a crest. Random triangles over few vertices, repeated heights.
        #[test]
        fn crests_are_bottleneck_paths_between_the_quarters(
            pos in proptest::collection::vec((0.0f64..10.0, 0.0f64..10.0, 0i32..6), 3..24),
            tris in proptest::collection::vec((0usize..24, 0usize..24, 0usize..24), 1..40),
        ) {
            let pos: Vec<[f64; 3]> = pos.iter().map(|&(x, y, z)| [x, y, f64::from(z)]).collect();
            let n = pos.len();
            let tris: Vec<[u32; 3]> =
                tris.iter().map(|&(a, b, c)| [(a % n) as u32, (b % n) as u32, (c % n) as u32]).collect();
            let mut crests = Vec::new();
            crests_of(&tris, &pos, &mut crests);
            let heights: Vec<f64> = pos.iter().map(|p| p[2]).collect();
            let bottleneck = |axis: usize| {
                heights.iter().copied().filter(|&z| joined(&tris, &pos, axis, z, None)).reduce(f64::max)
            };
            let mut axes = (0..2).filter(|&axis| bottleneck(axis).is_some());
            prop_assert_eq!(crests.len(), axes.clone().count());
            for c in &crests {
                let axis = axes.next().expect("one crest per joined axis");
                prop_assert_eq!(c.a, pos[c.ids[0] as usize]);
                prop_assert_eq!(c.b, pos[c.ids[1] as usize]);
                prop_assert!(
                    joined(&tris, &pos, axis, c.z, Some(c.ids)),
                    "crest {:?} along axis {}: its ends are not joined at height {} or above", c, axis, c.z
                );
                prop_assert_eq!(Some(c.z), bottleneck(axis), "crest {:?} along axis {}", c, axis);
            }
        }
    }
}
