//! Cell-to-box visibility after Koltun, Chrysanthou & Cohen-Or (2001), adapted to TIN terrain, with the proof.
//!
//! The question: can any point of the viewcell box `A` see any point of a node's box `B` (both axis-parallel in x,y;
//! only their tops matter)? A verdict "hidden" must be a theorem: every segment from a point of `A` to a point of `B`
//! passes strictly below the terrain somewhere (design.md, "Safe culling"; touching is visible).
//!
//! **Occluders (2.5-D walls).** For every TIN edge `uv`, the wall `{(x, y, z) : (x, y) ∈ uv, z < ẑ(x, y)}` where `ẑ`
//! interpolates the end heights lowered by `μ`. On an edge the terrain is exactly the segment between its end vertices,
//! so a sight line passing under a wall's top at a point passes at least `μ` below the terrain there: blocked in the
//! exact checker's sense for every eye that `truth::MarginReach` covers with `μ` (ten times its tolerance;
//! [`crate::Pvs`] judges only cells it covers and calls every node visible from the others). The walls lie *below* the
//! terrain, so anything they block the terrain blocks: dropping walls (or parts of them) only makes the answer more
//! "visible".
//!
//! **Reduction to the plane (§4, Observation 1).** Take an axis `k` (x or y) and a sign along which `A` and `B` are
//! separated: `along = ±p_k`, `A` in `along ≤ X1`, `B` in `along ≥ X2 > X1`; `lat` is the other coordinate. Let `T`
//! be a plane `z = T(along)` above both boxes' tops (the bridge of their tops in the `(along, z)` plane, raised by a
//! rounding margin). A sight segment `pq` (`p ∈ A`, `q ∈ B`) lifted vertically onto `T` (`p' = (p.xy, T)`,
//! `q' = (q.xy, T)`) lies pointwise above `pq` and has the same x,y projection: if `p'q'` passes under a wall at some
//! x,y point, so does `pq`. `p'q'` crosses the slab `X1 < along < X2` along one segment, from a point of
//! `s1 = hull(A ∪ B) ∩ {along = X1}` to a point of `s2 = hull(A ∪ B) ∩ {along = X2}` (the x,y hull is convex and
//! contains `p, q`); we use supersets `[a_lo, a_hi]`, `[b_lo, b_hi]` of these lateral intervals. In the slab, a wall
//! cut by the plane `T` leaves a *piece*: the part of the edge where `ẑ − T ≥ δ`; the lifted line passes under it.
//!
//! **Dual ray space (§5).** Ray `(x, y) ∈ [0, 1]²` is the line from `(X1, a_lo + x (a_hi − a_lo))` to
//! `(X2, b_lo + y (b_hi − b_lo))`. For a point `P` of the slab let `g_P(x, y)` be the line's lateral position at
//! `along = P.along` minus `P.lat`, affine in `(x, y)`; its sign says on which side of the line `P` lies. Koltun marks
//! the rays crossing each occluder segment (a trapeze or double triangle: `g_{P0} g_{P1} ≤ 0`). Terrain occluders are
//! short edges, and a pixel cut by the boundary between two neighbouring edges' trapezes is fully covered by neither;
//! so we use **connected pieces** instead of segments: pieces that share a vertex (both reaching it) form a connected
//! set `K` inside the open slab, and if two points of `K` lie strictly on opposite sides of a ray's line, a path in
//! `K` between them crosses the line (intermediate values) inside the slab, where the line *is* the ray's segment.
//! So ray `(x, y)` is blocked when `max_{P ∈ E} g_P > 0` and `min_{P ∈ E} g_P < 0` for any subset `E` of `K`
//! (we take the pieces' end points extreme in eight directions). This is Koltun's trapeze test over every chord of
//! `K` at once, with the same union for a single segment.
//!
//! **Conservative rasterisation (§5.2).** At resolution `R`, pixel `(i, j)` is `[i/R, (i+1)/R] × [j/R, (j+1)/R]`
//! (corners computed as `i as f64 / R as f64`, so neighbouring pixels share them exactly and the pixels cover the
//! square without gaps). A pixel counts as covered only if, for one component, some `P ∈ E` has `min_pixel g_P > τ`
//! and some `P ∈ E` has `max_pixel g_P < −τ`: the extremes of an affine function over a box are at its corners, taken
//! directly (Koltun's "shrunk trapezes", without the √2 slack). Every ray of a covered pixel is blocked. `B` is hidden
//! when every pixel is covered, for one separating axis (two are tried).
//!
//! **What is only speed.** Walls are gathered from a grid over the quadrilateral between `s1` and `s2` (plus a margin
//! for connectivity), skipping grid cells whose edges all stay under the plane; a ray that no component blocks answers
//! "visible" at once (its pixel can never be covered); resolution 16 is tried first when it divides `R` (a pixel
//! covered at 16 has every sub-pixel covered at `R`). Dropping walls and answering "visible" are always safe, so none
//! of this can make a verdict wrong.
//!
//! **Rounding.** All geometry is in world f64 coordinates (no shift: the inputs are exact). `W = 1 + max |x|, |y|`
//! over the mesh and the boxes; `S = (lateral extent) / (X2 − X1)` bounds the lines' slopes in the slab.
//! - `μ = 1e-7 (1 + extent + max |z|)`: walls' tops; ten times the checker's tolerance at least, from the cells that
//!   `truth::MarginReach` covers (the checker's tolerance grows with the eye's distance and height: a cell some
//!   hundred times the terrain's size away is not judged).
//! - Pieces stay `τ_a = 1e-12 W` inside the slab; an edge's pieces end where the computed `ẑ − T` reaches `2δ`, and
//!   both end points are re-checked directly (`ẑ − T ≥ δ` and inside the slab), else the edge is dropped; `ẑ − T` is
//!   affine along the edge, so the checks at the ends hold on the whole piece. `δ = μ / 2 + 1e-12 (W |T'| + max |z|)`
//!   bounds the rounding of `T` and `ẑ` (relative error below 1e-15 of those magnitudes).
//! - `τ = 1e-12 W (1 + S)`: the error of `g_P` (a few operations on lateral coordinates ≤ W, plus the displacement of
//!   a computed piece end by ≤ 1e-15 W along, times the slope) is far below it.
//! - `T` is raised by `1e-12 (1 + |z_A| + |z_B|)` so that the rounded slope cannot make it dip below a box top;
//!   `s1`, `s2` are widened by `τ_a`.
//! - Edges steeper than 1e6 (|Δz| / |Δxy|) are dropped, so that displacements of 1e-15 W in x,y move heights by far
//!   less than `δ`.

// Comparisons are written so that a NaN anywhere answers "visible" (`!(a > b)`), on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

/// An axis-parallel box over x,y whose top is `ztop` (the bottom never matters: Observation 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Box3 {
    /// Lower corner (x, y), world coordinates.
    pub lo: [f64; 2],
    /// Upper corner (x, y), world coordinates.
    pub hi: [f64; 2],
    /// Highest z of the box.
    pub ztop: f64,
}

/// The wall occluders of a mesh: every TIN edge, its end heights lowered by `μ`, in a uniform grid.
pub(crate) struct Walls {
    pos: Vec<[f64; 3]>,
    edges: Vec<[u32; 2]>,
    lo: [f64; 2],
    cell: f64,
    cols: usize,
    rows: usize,
    start: Vec<u32>,
    items: Vec<u32>,
    /// Per grid cell, the highest lowered end height of its edges (pruning only).
    cell_top: Vec<f64>,
    /// `1 + max |x|, |y|` of the mesh.
    pub w: f64,
    /// `max |z|` of the mesh.
    pub zabs: f64,
    /// The walls' lowering.
    pub mu: f64,
    /// The eyes for which `mu` is far above the exact checker's tolerance (module docs): [`crate::Pvs`] applies the
    /// test to a cell only when this covers it.
    pub reach: truth::MarginReach,
}

/// Per-thread working memory of the planar test.
#[derive(Default)]
pub(crate) struct Scratch {
    stamp: Vec<u32>,
    epoch: u32,
    vstamp: Vec<u32>,
    vpiece: Vec<u32>,
    pieces: Vec<[[f64; 2]; 2]>,
    parent: Vec<u32>,
    cover: Vec<[u64; 4]>,
}

/// A connected set of wall pieces: its root, its number of pieces, and its extreme end points (score, point) in
/// eight directions.
type Component = (u32, usize, [(f64, [f64; 2]); 8]);

/// Largest resolution of the ray-space bitmap.
pub const MAX_RESOLUTION: u32 = 256;

impl Walls {
    /// Walls of the mesh `positions` / `triangles` (world coordinates).
    pub fn new(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Walls {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if positions.is_empty() {
            lo = [0.0; 3];
            hi = [0.0; 3];
        }
        let extent = (hi[0] - lo[0]) + (hi[1] - lo[1]);
        let zabs = lo[2].abs().max(hi[2].abs());
        let mu = 1e-7 * (1.0 + extent + zabs);
        let w = 1.0 + lo[0].abs().max(hi[0].abs()).max(lo[1].abs()).max(hi[1].abs());
        let mut edges: Vec<[u32; 2]> = triangles
            .iter()
            .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        edges.sort_unstable();
        edges.dedup();
        // Drop edges steeper than 1e6 (module docs, rounding).
        edges.retain(|&[a, b]| {
            let (p, q) = (positions[a as usize], positions[b as usize]);
            (q[2] - p[2]).abs() <= 1e6 * (q[0] - p[0]).hypot(q[1] - p[1])
        });
        let pos: Vec<[f64; 3]> = positions.iter().map(|p| [p[0], p[1], p[2] - mu]).collect();
        let area = ((hi[0] - lo[0]) * (hi[1] - lo[1])).max(1e-300);
        let cell = (area / edges.len().max(1) as f64).sqrt() * 2.0;
        let cell = if cell.is_finite() && cell > 0.0 { cell } else { 1.0 };
        let cols = (((hi[0] - lo[0]) / cell) as usize + 1).clamp(1, 4096);
        let rows = (((hi[1] - lo[1]) / cell) as usize + 1).clamp(1, 4096);
        let mut walls = Walls {
            pos,
            edges,
            lo: [lo[0], lo[1]],
            cell,
            cols,
            rows,
            start: vec![0; cols * rows + 1],
            items: Vec::new(),
            cell_top: vec![f64::NEG_INFINITY; cols * rows],
            w,
            zabs,
            mu,
            reach: truth::MarginReach::new(mu, lo, hi),
        };
        let spans: Vec<[usize; 4]> = walls
            .edges
            .iter()
            .map(|&[a, b]| {
                let (p, q) = (walls.pos[a as usize], walls.pos[b as usize]);
                let (c0, r0) = walls.cell_of([p[0].min(q[0]), p[1].min(q[1])]);
                let (c1, r1) = walls.cell_of([p[0].max(q[0]), p[1].max(q[1])]);
                [c0, r0, c1, r1]
            })
            .collect();
        for s in &spans {
            for r in s[1]..=s[3] {
                for c in s[0]..=s[2] {
                    walls.start[r * cols + c + 1] += 1;
                }
            }
        }
        for i in 0..cols * rows {
            walls.start[i + 1] += walls.start[i];
        }
        let mut fill = walls.start.clone();
        walls.items = vec![0; walls.start[cols * rows] as usize];
        for (e, s) in spans.iter().enumerate() {
            for r in s[1]..=s[3] {
                for c in s[0]..=s[2] {
                    let k = r * cols + c;
                    walls.items[fill[k] as usize] = e as u32;
                    fill[k] += 1;
                    let [a, b] = walls.edges[e];
                    let top = walls.pos[a as usize][2].max(walls.pos[b as usize][2]);
                    walls.cell_top[k] = walls.cell_top[k].max(top);
                }
            }
        }
        walls
    }

    fn cell_of(&self, p: [f64; 2]) -> (usize, usize) {
        let c = ((p[0] - self.lo[0]) / self.cell).floor();
        let r = ((p[1] - self.lo[1]) / self.cell).floor();
        let c = if c.is_finite() {
            c.clamp(0.0, (self.cols - 1) as f64)
        } else {
            0.0
        };
        let r = if r.is_finite() {
            r.clamp(0.0, (self.rows - 1) as f64)
        } else {
            0.0
        };
        (c as usize, r as usize)
    }

    /// A fresh scratch for this mesh.
    pub fn scratch(&self) -> Scratch {
        Scratch {
            stamp: vec![0; self.edges.len()],
            vstamp: vec![0; self.pos.len()],
            vpiece: vec![0; self.pos.len()],
            ..Scratch::default()
        }
    }

    /// Whether `b` is hidden from every point of `a` (a theorem when `true`; see the module documentation), at ray
    /// space resolution `res` (1..=256).
    pub fn hidden(&self, a: &Box3, b: &Box3, res: u32, scratch: &mut Scratch) -> bool {
        // Separating axes, widest gap first.
        let mut axes: Vec<(f64, usize, f64)> = Vec::with_capacity(2);
        for k in 0..2 {
            if a.hi[k] < b.lo[k] {
                axes.push((b.lo[k] - a.hi[k], k, 1.0));
            } else if b.hi[k] < a.lo[k] {
                axes.push((a.lo[k] - b.hi[k], k, -1.0));
            }
        }
        axes.sort_by(|x, y| y.0.total_cmp(&x.0));
        axes.into_iter()
            .any(|(_, k, sign)| self.planar_hidden(a, b, k, sign, res.clamp(1, MAX_RESOLUTION), scratch))
    }

    fn planar_hidden(&self, a: &Box3, b: &Box3, k: usize, sign: f64, res: u32, sc: &mut Scratch) -> bool {
        let l = 1 - k;
        let along_range = |bx: &Box3| {
            if sign > 0.0 {
                (bx.lo[k], bx.hi[k])
            } else {
                (-bx.hi[k], -bx.lo[k])
            }
        };
        let ((a0, x1), (x2, b1)) = (along_range(a), along_range(b));
        if !(x2 > x1) || !a.ztop.is_finite() || !b.ztop.is_finite() {
            return false;
        }
        let w = self
            .w
            .max(1.0 + a.lo[0].abs().max(a.hi[0].abs()).max(a.lo[1].abs()).max(a.hi[1].abs()));
        let tau_a = 1e-12 * w;
        // Lateral intervals s1, s2 of the hull of A ∪ B at X1 and X2 (over all corner pairs), widened.
        let ca = [(a0, a.lo[l]), (a0, a.hi[l]), (x1, a.lo[l]), (x1, a.hi[l])];
        let cb = [(x2, b.lo[l]), (x2, b.hi[l]), (b1, b.lo[l]), (b1, b.hi[l])];
        let (mut s1, mut s2) = ([f64::INFINITY, f64::NEG_INFINITY], [f64::INFINITY, f64::NEG_INFINITY]);
        for u in ca {
            for v in cb {
                for (x, s) in [(x1, &mut s1), (x2, &mut s2)] {
                    let lat = u.1 + (x - u.0) / (v.0 - u.0) * (v.1 - u.1);
                    s[0] = s[0].min(lat);
                    s[1] = s[1].max(lat);
                }
            }
        }
        let (a_lo, a_hi, b_lo, b_hi) = (s1[0] - tau_a, s1[1] + tau_a, s2[0] - tau_a, s2[1] + tau_a);
        let lat_lo = a.lo[l].min(b.lo[l]);
        let lat_hi = a.hi[l].max(b.hi[l]);
        let slope_bound = (lat_hi - lat_lo) / (x2 - x1);
        let tau = 1e-12 * w * (1.0 + slope_bound);
        if !(tau.is_finite() && slope_bound < 1e9) {
            return false;
        }
        // The plane T(along) = tz + tslope (along − tal): the bridge of the two tops, raised.
        let (za, zb) = (a.ztop, b.ztop);
        let raise = 1e-12 * (1.0 + za.abs() + zb.abs());
        let (tal, tslope) = if zb >= za {
            (a0, (zb - za) / (x2 - a0))
        } else {
            (x1, (zb - za) / (b1 - x1))
        };
        let tz = za + raise;
        if !tslope.is_finite() {
            return false;
        }
        let plane = |al: f64| tz + tslope * (al - tal);
        let delta = 0.5 * self.mu + 1e-12 * (w * tslope.abs() + self.zabs + za.abs() + zb.abs());
        // Pieces of walls in the slab.
        let (lo_a, hi_a) = (x1 + tau_a, x2 - tau_a);
        if !(hi_a > lo_a) {
            return false;
        }
        let (q_al0, q_al1) = if sign > 0.0 { (lo_a, hi_a) } else { (-hi_a, -lo_a) };
        sc.epoch = sc.epoch.wrapping_add(1);
        if sc.epoch == 0 {
            sc.stamp.iter_mut().for_each(|s| *s = 0);
            sc.vstamp.iter_mut().for_each(|s| *s = 0);
            sc.epoch = 1;
        }
        let epoch = sc.epoch;
        sc.pieces.clear();
        sc.parent.clear();
        // Grid cells over the quadrilateral between s1 and s2 (plus a quarter of its width and one grid cell on each
        // side, so that pieces connect around it), column by column along the axis. Which walls are looked at only
        // decides how much is hidden: dropping walls is always safe.
        let (lines_along, lines_lat) = if k == 0 {
            (self.cols, self.rows)
        } else {
            (self.rows, self.cols)
        };
        let grid_index = |v: f64, axis: usize, n: usize| {
            let i = ((v - self.lo[axis]) / self.cell).floor();
            if i.is_finite() {
                i.clamp(0.0, (n - 1) as f64) as usize
            } else {
                0
            }
        };
        let (g0, g1) = (grid_index(q_al0, k, lines_along), grid_index(q_al1, k, lines_along));
        for gi in g0..=g1 {
            let wa = [
                self.lo[k] + self.cell * gi as f64,
                self.lo[k] + self.cell * (gi + 1) as f64,
            ];
            let (mut lat0, mut lat1) = (f64::INFINITY, f64::NEG_INFINITY);
            for wv in wa {
                let lam = ((sign * wv - x1) / (x2 - x1)).clamp(0.0, 1.0);
                lat0 = lat0.min(a_lo + lam * (b_lo - a_lo));
                lat1 = lat1.max(a_hi + lam * (b_hi - a_hi));
            }
            let margin = 0.25 * (lat1 - lat0) + self.cell;
            let (h0, h1) = (
                grid_index(lat0 - margin, l, lines_lat),
                grid_index(lat1 + margin, l, lines_lat),
            );
            for gj in h0..=h1 {
                let (c, r) = if k == 0 { (gi, gj) } else { (gj, gi) };
                let cell = r * self.cols + c;
                // Skip a grid cell whose edges all stay under the plane over the cell (a heuristic: dropping walls
                // is always safe).
                let gx = [
                    self.lo[0] + self.cell * c as f64,
                    self.lo[0] + self.cell * (c + 1) as f64,
                ];
                let gy = [
                    self.lo[1] + self.cell * r as f64,
                    self.lo[1] + self.cell * (r + 1) as f64,
                ];
                let g = if k == 0 { gx } else { gy };
                let (ga, gb) = (sign * g[0], sign * g[1]);
                let t_min = plane(ga.min(gb).clamp(lo_a, hi_a)).min(plane(ga.max(gb).clamp(lo_a, hi_a)));
                if self.cell_top[cell] < t_min + 2.0 * delta - 1e-9 * (1.0 + t_min.abs()) {
                    continue;
                }
                for &e in &self.items[self.start[cell] as usize..self.start[cell + 1] as usize] {
                    if sc.stamp[e as usize] == epoch {
                        continue;
                    }
                    sc.stamp[e as usize] = epoch;
                    let [u, v] = self.edges[e as usize];
                    let (pu, pv) = (self.pos[u as usize], self.pos[v as usize]);
                    let (au, av) = (sign * pu[k], sign * pv[k]);
                    // Quick rejection: both ends on one side of the slab, or both tops under the plane.
                    if (au <= lo_a && av <= lo_a) || (au >= hi_a && av >= hi_a) {
                        continue;
                    }
                    let (du, dv) = (pu[2] - plane(au), pv[2] - plane(av));
                    if !(du >= 2.0 * delta || dv >= 2.0 * delta) {
                        continue;
                    }
                    // Slab interval in s.
                    let (mut s0, mut s1) = (0.0f64, 1.0f64);
                    if au != av {
                        let (sa, sb) = ((lo_a - au) / (av - au), (hi_a - au) / (av - au));
                        s0 = s0.max(sa.min(sb));
                        s1 = s1.min(sa.max(sb));
                    }
                    // Poking interval: ẑ − T ≥ 2δ.
                    if !(du >= 2.0 * delta && dv >= 2.0 * delta) {
                        let st = (2.0 * delta - du) / (dv - du);
                        if du >= 2.0 * delta {
                            s1 = s1.min(st);
                        } else {
                            s0 = s0.max(st);
                        }
                    }
                    if !(s0 <= s1) {
                        continue;
                    }
                    let point = |s: f64| -> ([f64; 2], f64) {
                        if s == 0.0 {
                            return ([au, pu[l]], pu[2]);
                        }
                        if s == 1.0 {
                            return ([av, pv[l]], pv[2]);
                        }
                        let x = pu[k] + (pv[k] - pu[k]) * s;
                        ([sign * x, pu[l] + (pv[l] - pu[l]) * s], pu[2] + (pv[2] - pu[2]) * s)
                    };
                    let (p0, z0) = point(s0);
                    let (p1, z1) = point(s1);
                    let ok = |p: [f64; 2], z: f64| p[0] > lo_a && p[0] < hi_a && z - plane(p[0]) >= delta;
                    if !(ok(p0, z0) && ok(p1, z1)) {
                        continue;
                    }
                    let id = sc.pieces.len() as u32;
                    sc.pieces.push([p0, p1]);
                    sc.parent.push(id);
                    for (touch, vert) in [(s0 == 0.0, u), (s1 == 1.0, v)] {
                        if !touch {
                            continue;
                        }
                        let vi = vert as usize;
                        if sc.vstamp[vi] == epoch {
                            let other = sc.vpiece[vi];
                            union(&mut sc.parent, id, other);
                        } else {
                            sc.vstamp[vi] = epoch;
                            sc.vpiece[vi] = id;
                        }
                    }
                }
            }
        }
        if sc.pieces.is_empty() {
            return false;
        }
        // Components: extreme end points in eight directions.
        const DIRS: [[f64; 2]; 8] = [
            [0.0, 1.0],
            [0.0, -1.0],
            [1.0, 0.0],
            [-1.0, 0.0],
            [1.0, 1.0],
            [1.0, -1.0],
            [-1.0, 1.0],
            [-1.0, -1.0],
        ];
        let n = sc.pieces.len();
        let mut comps: Vec<Component> = Vec::new();
        let mut slot = vec![u32::MAX; n];
        for i in 0..n {
            let root = find(&mut sc.parent, i as u32);
            if slot[root as usize] == u32::MAX {
                slot[root as usize] = comps.len() as u32;
                comps.push((root, 0, [(f64::NEG_INFINITY, [0.0; 2]); 8]));
            }
            let comp = &mut comps[slot[root as usize] as usize];
            comp.1 += 1;
            for p in sc.pieces[i] {
                for (d, best) in DIRS.iter().zip(comp.2.iter_mut()) {
                    let score = d[0] * p[0] + d[1] * p[1];
                    if score > best.0 {
                        *best = (score, p);
                    }
                }
            }
        }
        comps.sort_by(|x, y| y.1.cmp(&x.1).then(x.0.cmp(&y.0)));
        // Each component's end points as affine functions g_P(x, y) = α + β x + γ y.
        let sets: Vec<Vec<[f64; 3]>> = comps
            .iter()
            .filter_map(|comp| {
                let mut pts: Vec<[f64; 2]> = comp.2.iter().map(|b| b.1).collect();
                pts.sort_by(|p, q| p[0].total_cmp(&q[0]).then(p[1].total_cmp(&q[1])));
                pts.dedup();
                (pts.len() >= 2).then(|| {
                    pts.iter()
                        .map(|p| {
                            let lam = (p[0] - x1) / (x2 - x1);
                            let alpha = (1.0 - lam) * a_lo + lam * b_lo - p[1];
                            [alpha, (1.0 - lam) * (a_hi - a_lo), lam * (b_hi - b_lo)]
                        })
                        .collect()
                })
            })
            .collect();
        // A ray that no component blocks lies in a pixel never covered at any resolution: visible. (A shortcut:
        // answering "visible" is always safe.)
        for i in 0..4 {
            for j in 0..4 {
                let (x, y) = ((f64::from(i) + 0.5) / 4.0, (f64::from(j) + 0.5) / 4.0);
                let blocked = sets.iter().any(|set| {
                    let (mut hi, mut lo) = (f64::NEG_INFINITY, f64::INFINITY);
                    for &[al, be, ga] in set {
                        let g = al + be * x + ga * y;
                        hi = hi.max(g);
                        lo = lo.min(g);
                    }
                    hi > tau && lo < -tau
                });
                if !blocked {
                    return false;
                }
            }
        }
        // Coarse to fine: a pixel covered at resolution 16 has all its sub-pixels covered at any multiple of it (the
        // extremes over a sub-pixel are within those over the pixel), so "hidden" at 16 is "hidden" at R.
        if res > 16 && res.is_multiple_of(16) && rasterise(&sets, 16, tau, &mut sc.cover) {
            return true;
        }
        rasterise(&sets, res, tau, &mut sc.cover)
    }
}

/// Whether every pixel of the `res` × `res` bitmap is covered by one of the component `sets` (module documentation).
fn rasterise(sets: &[Vec<[f64; 3]>], res: u32, tau: f64, cover: &mut Vec<[u64; 4]>) -> bool {
    let r = res as usize;
    let full = full_mask(r);
    cover.clear();
    cover.resize(r, [0u64; 4]);
    let rf = f64::from(res);
    let edge = |i: usize| i as f64 / rf;
    for lines in sets {
        let mut all = true;
        for (i, col) in cover.iter_mut().enumerate() {
            if *col == full {
                continue;
            }
            let (xl, xh) = (edge(i), edge(i + 1));
            // Union over lines of rows where min g > τ, and where max g < −τ: each a half-line of rows.
            let mut pos = [0u64; 4];
            let mut neg = [0u64; 4];
            for &[al, be, ga] in lines {
                let (xmin, xmax) = if be >= 0.0 { (xl, xh) } else { (xh, xl) };
                let (cmin, cmax) = (al + be * xmin, al + be * xmax);
                // Row j: y in [edge(j), edge(j+1)].
                let gmin = |j: usize| {
                    let y = if ga >= 0.0 { edge(j) } else { edge(j + 1) };
                    cmin + ga * y
                };
                let gmax = |j: usize| {
                    let y = if ga >= 0.0 { edge(j + 1) } else { edge(j) };
                    cmax + ga * y
                };
                // Both are monotone in j: non-decreasing when γ ≥ 0, else non-increasing.
                let up = ga >= 0.0;
                or_mask(&mut pos, &half_line(r, up, |j| gmin(j) > tau));
                or_mask(&mut neg, &half_line(r, !up, |j| gmax(j) < -tau));
            }
            for w in 0..4 {
                col[w] |= pos[w] & neg[w];
            }
            all &= *col == full;
        }
        if all {
            return true;
        }
    }
    false
}

fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let p = parent[x as usize];
        parent[x as usize] = parent[p as usize];
        x = p;
    }
    x
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        parent[hi as usize] = lo;
    }
}

/// Bits `0..r` set.
fn full_mask(r: usize) -> [u64; 4] {
    range_mask(0, r)
}

/// Bits `lo..hi` set (`hi ≤ 256`).
fn range_mask(lo: usize, hi: usize) -> [u64; 4] {
    let mut m = [0u64; 4];
    for (w, word) in m.iter_mut().enumerate() {
        let (a, b) = (lo.max(64 * w), hi.min(64 * w + 64));
        if a < b {
            let n = b - a;
            let bits = if n == 64 {
                u64::MAX
            } else {
                ((1u64 << n) - 1) << (a - 64 * w)
            };
            *word |= bits;
        }
    }
    m
}

fn or_mask(a: &mut [u64; 4], b: &[u64; 4]) {
    for w in 0..4 {
        a[w] |= b[w];
    }
}

/// The rows `0..r` where the monotone predicate `p` holds: `up` means it holds on an upper half-line (`p(j)` implies
/// `p(j + 1)`), otherwise on a lower one. Found by bisection on direct evaluations, so the mask is exactly the rows
/// where `p` holds.
fn half_line(r: usize, up: bool, p: impl Fn(usize) -> bool) -> [u64; 4] {
    if up {
        // Smallest j with p(j).
        let (mut lo, mut hi) = (0usize, r);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if p(mid) {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        range_mask(lo, r)
    } else {
        // Number of leading rows with p.
        let (mut lo, mut hi) = (0usize, r);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if p(mid) {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        range_mask(0, lo)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masks() {
        assert_eq!(range_mask(0, 256), [u64::MAX; 4]);
        assert_eq!(range_mask(3, 5), [0b11000, 0, 0, 0]);
        assert_eq!(range_mask(60, 70)[1], 0b111111);
        assert_eq!(half_line(16, true, |j| j >= 5), range_mask(5, 16));
        assert_eq!(half_line(16, false, |j| j <= 5), range_mask(0, 6));
        assert_eq!(half_line(16, false, |_| false), [0; 4]);
    }

    /// A wall across the whole terrain hides what lies behind it from a low cell, and nothing hides a box in the
    /// open.
    #[test]
    fn a_long_wall_hides_and_open_ground_does_not() {
        // Grid 0..=20 x 0..=20 (10 m spacing), a ridge 50 m high at x = 100.
        let mut pos = Vec::new();
        for j in 0..=20 {
            for i in 0..=20 {
                let x = 10.0 * f64::from(i);
                let z = if i == 10 { 50.0 } else { 0.0 };
                pos.push([x, 10.0 * f64::from(j), z]);
            }
        }
        let mut tris = Vec::new();
        for j in 0..20u32 {
            for i in 0..20u32 {
                let v = j * 21 + i;
                tris.push([v, v + 1, v + 22]);
                tris.push([v, v + 22, v + 21]);
            }
        }
        let walls = Walls::new(&pos, &tris);
        let mut sc = walls.scratch();
        let cell = Box3 {
            lo: [20.0, 80.0],
            hi: [40.0, 120.0],
            ztop: 2.0,
        };
        let behind = Box3 {
            lo: [150.0, 90.0],
            hi: [170.0, 110.0],
            ztop: 0.0,
        };
        for res in [16, 64, 256] {
            assert!(walls.hidden(&cell, &behind, res, &mut sc), "res {res}");
        }
        let open = Box3 {
            lo: [60.0, 90.0],
            hi: [80.0, 110.0],
            ztop: 0.0,
        };
        assert!(!walls.hidden(&cell, &open, 64, &mut sc));
        let high_cell = Box3 { ztop: 200.0, ..cell };
        assert!(!walls.hidden(&high_cell, &behind, 64, &mut sc));
    }
}
