//! The safe run-time culler: a front-to-back traversal of the hierarchy against a conservative horizon
//! ([`crate::horizon`]), whose verdict "hidden" is a theorem (design.md, "Safe culling").
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
//! Every "hidden" is thus an instance of the theorem, whatever the order, the tree or the parameters; the order and
//! the parameters only decide how much is culled. With a horizontal field of view below 360°, a node entirely
//! outside it is culled by the same azimuth test as [`crate::Culler`]'s (a node outside the view cannot be seen).
//! A non-finite camera draws everything.
//!
//! The height margin is `μ = 1e-7 (1 + e + |c − o|₁ + |c.z| + h)` metres with `e` the mesh's extent, `o` its
//! lowest corner and `h` its largest `|z|`: more than 100 times the exact checker's tolerance (`truth::walk`), so a
//! sight line called blocked here is blocked there, and far above every rounding error of the arithmetic.

// Comparisons are written so that a NaN anywhere answers "not hidden" (`!(a < b)`), on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::f64::consts::TAU;

use crate::culler::{Camera, CullStats, DrawList};
use crate::hierarchy::Hierarchy;
use crate::horizon::{Horizon, Projected, Reach, project};
use crate::sector::circle_outside_view;

/// Parameters of the safe culler (run time only; nothing of them is stored in the `.tch`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SafeParams {
    /// Horizon columns per 90° face (rounded up to a power of two).
    pub columns_per_face: usize,
    /// Largest patch (triangles) below the hierarchy's leaves, at most 64.
    pub patch: usize,
    /// Most occluder edges written into the horizon per cull, nearest first: bounds the cost of views that
    /// see much of the terrain (fewer occluders only cull less, never wrongly).
    pub occluder_budget: usize,
}

impl Default for SafeParams {
    fn default() -> Self {
        SafeParams {
            columns_per_face: 256,
            patch: 16,
            occluder_budget: usize::MAX,
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
}

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
    /// Patch edges `[a, b, t1, t2]` (local vertices and triangles): `a → b` runs along the winding of triangle `t1`,
    /// `t2` is the patch's other triangle on the edge ([`NO_TRIANGLE`] on the patch boundary).
    edges: Vec<[u8; 4]>,
    /// Normal `(b − a) × (c − a)` of every entry of `tris`.
    normals: Vec<[f64; 3]>,
    triangles: u32,
    origin: [f64; 3],
    extent: f64,
    zabs: f64,
}

/// No triangle on this side of a patch edge.
const NO_TRIANGLE: u8 = u8::MAX;

/// Orders non-negative distances as integers (their bit patterns are monotone).
#[inline]
fn key(d: f64) -> u64 {
    d.max(0.0).to_bits()
}

impl SafeCuller {
    /// Prepares the safe culler for `h` (which must satisfy [`Hierarchy::check_invariants`], as every loaded file
    /// does).
    pub fn new(h: &Hierarchy, params: SafeParams) -> SafeCuller {
        let params = SafeParams {
            columns_per_face: params.columns_per_face.clamp(2, 1 << 16).next_power_of_two(),
            patch: params.patch.clamp(1, 64),
            occluder_budget: params.occluder_budget,
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
            edges: Vec::new(),
            normals: Vec::new(),
            triangles: h.mesh.triangles.len() as u32,
            origin: h.origin,
            extent: 0.0,
            zabs: 0.0,
        };
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in pos {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if !pos.is_empty() {
            c.extent = (hi[0] - lo[0]) + (hi[1] - lo[1]) + (hi[2] - lo[2]);
            c.zabs = lo[2].abs().max(hi[2].abs());
        }
        // Hierarchy nodes first (same ids), then the halving trees.
        let n = h.nodes.len();
        c.nodes.reserve(n);
        for node in &h.nodes {
            c.nodes.push(c.bounds(h, node.triangles));
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
        c
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
        let id = self.nodes.len() as u32;
        self.nodes.push(self.bounds(h, range));
        let [s, e] = range;
        if (e - s) as usize <= self.params.patch {
            self.make_patch(h, id);
        } else {
            let mid = s + (e - s) / 2;
            let a = self.halving_tree(h, [s, mid]);
            let b = self.halving_tree(h, [mid, e]);
            let start = self.children.len() as u32;
            self.children.extend([a, b]);
            self.nodes[id as usize].kids = [start, start + 2];
        }
        id
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

    /// The bounds of the triangles `range` (f64, from the mesh): circle around the x,y box's centre through the
    /// farthest vertex, grown by a relative 1e-12 and 1e-9 m; the highest vertex.
    fn bounds(&self, h: &Hierarchy, range: [u32; 2]) -> TreeNode {
        let tris = &h.mesh.triangles[range[0] as usize..range[1] as usize];
        let pos = &h.mesh.positions;
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let mut zmax = f64::NEG_INFINITY;
        for t in tris {
            for &v in t {
                let p = pos[v as usize];
                lo = [lo[0].min(p[0]), lo[1].min(p[1])];
                hi = [hi[0].max(p[0]), hi[1].max(p[1])];
                zmax = zmax.max(p[2]);
            }
        }
        let centre = if tris.is_empty() {
            [0.0; 2]
        } else {
            [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])]
        };
        let mut r2: f64 = 0.0;
        for t in tris {
            for &v in t {
                let p = pos[v as usize];
                let (dx, dy) = (p[0] - centre[0], p[1] - centre[1]);
                r2 = r2.max(dx * dx + dy * dy);
            }
        }
        let scale = centre[0].abs() + centre[1].abs();
        TreeNode {
            centre,
            radius: r2.sqrt() * (1.0 + 1e-12) + 1e-12 * scale + 1e-9,
            zmax,
            triangles: range,
            kids: [0, 0],
            verts: [0, 0],
            tris: [0, 0],
            edges: [0, 0],
        }
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
        written: &mut usize,
    ) {
        let mut facing = [0.0f64; 64];
        for (patch, at, reach) in eligible.iter() {
            // Nothing of a patch that cannot raise any column needs looking at.
            if !horizon.can_raise(reach) {
                continue;
            }
            let p = &self.nodes[*patch as usize];
            let base = *at as usize;
            let verts = &self.verts[p.verts[0] as usize..p.verts[1] as usize];
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
            for e in &self.edges[p.edges[0] as usize..p.edges[1] as usize] {
                if *written >= self.params.occluder_budget {
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
                *written += 1;
                horizon.write_segment([&projected[base + e[0] as usize], &projected[base + e[1] as usize]]);
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
        let mu = 1e-7
            * (1.0
                + self.extent
                + (eye[0] - self.origin[0]).abs()
                + (eye[1] - self.origin[1]).abs()
                + eye[2].abs()
                + self.zabs);
        let frustum = (camera.hfov < TAU).then_some((camera.yaw, camera.hfov * 0.5));
        let distance = |n: &TreeNode| {
            let (dx, dy) = (n.centre[0] - eye[0], n.centre[1] - eye[1]);
            (dx * dx + dy * dy).sqrt()
        };
        for &r in &self.roots {
            let n = &self.nodes[r as usize];
            scratch.queue.push(Reverse((key(distance(n) - n.radius), r)));
        }
        let mut tested = 0u32;
        let mut written = 0usize;
        while let Some(Reverse((dmin_key, id))) = scratch.queue.pop() {
            let node = &self.nodes[id as usize];
            let dist = distance(node);
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
                let mut hidden = horizon.disk_hidden(m, node.radius, dz, false);
                if !hidden && !scratch.eligible.is_empty() && horizon.disk_hidden(m, node.radius, dz, true) {
                    self.flush(horizon, &mut scratch.eligible, &scratch.projected, eye, &mut written);
                    hidden = horizon.disk_hidden(m, node.radius, dz, false);
                }
                if hidden {
                    out.stats.culled_by_occlusion += 1;
                    continue;
                }
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
                scratch
                    .projected
                    .push(project([p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]], mu, v));
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
                self.flush(horizon, &mut scratch.eligible, &scratch.projected, eye, &mut written);
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
        scratch.drawn.sort_unstable();
        for &r in &scratch.drawn {
            out.push(r);
        }
        out.stats.nodes_tested = tested;
        out.stats.nodes_skipped = self.nodes.len() as u32 - tested;
        out.stats.triangles_culled = self.triangles - out.stats.triangles_drawn;
        scratch.horizon = Some(owned);
        out.scratch = scratch;
    }
}

/// Whether every direction from the eye to the node's circle misses the horizontal view `yaw ± half_fov`.
fn outside_view(node: &TreeNode, eye: [f64; 3], yaw: f64, half_fov: f64) -> bool {
    let centre = [node.centre[0] - eye[0], node.centre[1] - eye[1]];
    circle_outside_view(centre, node.radius, yaw, half_fov)
}
