//! Cell-to-box visibility after Koltun, Chrysanthou & Cohen-Or (2001), adapted to TIN terrain, with the proof.
//!
//! The question: can any point of the viewcell box `A` see any point of a node's box `B` (both axis-parallel in x,y;
//! only their tops matter)? A verdict "hidden" must be a theorem: every segment from a point of `A` to a point of `B`
//! passes strictly below the terrain somewhere (the README's "Safe culling"; touching is visible).
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
//! **The grid.** The walls are found through a uniform grid of `cols × rows` square cells of side `cell` from the
//! mesh's lower corner `lo`. The index of a coordinate `v` along axis `a` is `I_a(v) = clamp(⌊fl(fl(v − lo_a) /
//! cell)⌋, 0, n_a − 1)`, where `fl` is f64 rounding (to nearest, unit `u = 2^-53`) and `n_a` the cells along `a`.
//! `I_a` is non-decreasing in `v` (each rounded operation is monotone, `cell > 0`, and `b` below stays finite: a
//! valid mesh's coordinates are below 2^100 and `cell > 1e-155`). The query above takes index ranges
//! by `I_a` of its region's bounds, so it looks at the cell `(I_0(x), I_1(y))` of every point `(x, y)` of its region.
//! Each edge `pq` is registered in a superset of `G = {(I_0(x), I_1(y)) : (x, y) ∈ pq}` (real points of the
//! segment), so a query finds every edge that meets its region. (Which walls are found is only speed and tightness,
//! as above: the superset keeps every wall that the query means to look at.) Which cells:
//! - By monotonicity `G` lies in the edge's index box `[c0, c1] × [r0, r1]`, the indices of its ends' min and max.
//!   A box of `nc × nr ≤ 2 (nc + nr)` cells is registered whole: at most `2 (nc + nr)` cells, and exactly as before
//!   this walk existed, so ordinary meshes, whose edges span a cell or two, get the same grid.
//! - Otherwise the edge is walked in bands: `m` is the axis with more cells in the box (rows on a tie), `n` the other,
//!   `[i0, i1]` the box's range along `m`, `[j0, j1]` along `n`, `ε = 1e-14 w` with `w = 1 + max |x|, |y|` over the
//!   mesh. Band `i` takes `J_i = [v_lo, v_hi]`: `v_lo` is the edge's least `m` coordinate when `i = i0`, else the
//!   larger of it and `fl(fl(lo_m + fl(cell · i)) − ε)`; `v_hi` is the edge's greatest `m` coordinate when `i = i1`,
//!   else the smaller of it and `fl(fl(lo_m + fl(cell · (i + 1))) + ε)` (min and max are exact).
//!   1. Every point of the edge with `I_m = i` has its `m` coordinate `v` in `J_i`. Nothing to show at `i = i0`
//!      (below) and `i = i1` (above). Write `b = fl(fl(v − lo_m) / cell)`. Below, `i > i0 ≥ 0`: `I_m(v) = i ≥ 1`
//!      gives `b ≥ i` (the clamp only lowers indices above `n_m − 1`), so `v − lo_m ≥ i · cell / (1 + u)^2 ≥
//!      i · cell (1 − 2u)`. The same at the edge's greatest `m` coordinate (index `i1 ≥ i`, at most `w − 1` from 0,
//!      like `lo_m`) gives `i · cell ≤ 2w (1 + 3u)`; so `v ≥ lo_m + i · cell − 4.1 u w`. The computed bound is at
//!      most `lo_m + i · cell − ε + 8.1 u w` (the product errs by `≤ 2.1 u w`, the sum and the difference each by
//!      `≤ u · 3.1 w`), below `v` because `ε ≥ 0.99e-14 w > 89 u w > 12.2 u w`. Above, `i < i1 ≤ n_m − 1`: `I_m(v) = i`
//!      gives `b < i + 1` (the clamp only raises indices below 0, to `i = 0`). If `v ≤ lo_m` the bound, at least
//!      `lo_m`, holds; else `v − lo_m ≤ (i + 1) cell / (1 − u)^2`, with `(i + 1) cell ≤ 2w (1 + 3u)` as before
//!      (`i + 1 ≤ i1`), so `v ≤ lo_m + (i + 1) cell + 4.1 u w`, and the computed bound is at least `lo_m + (i + 1)
//!      cell + ε − 8.1 u w`.
//!   2. The edge's `n` coordinate at `v ∈ J_i` is `x_n(v) = p_n + (v − p_m) Δn / Δm` (`Δ = q − p`, `Δm ≠ 0` since
//!      the box spans three cells or more along `m`), computed as `fl(p_n + fl(fl(v − p_m) · s))`, `s = fl(fl(Δn) /
//!      fl(Δm))`. `s` errs by a factor within `1 ± 3.1u`, the product by `1 ± 5.1u` of an exact value of magnitude
//!      at most `|Δn| ≤ 2w` (`v` lies between `p_m` and `q_m`), the sum by `u · 3.1 w`: the error is at most
//!      `13.3 u w` (underflow adds less than `2^-1000`, and `w ≥ 1`). A result that is not finite (an overflowing
//!      `s`) gives the band the whole range `[j0, j1]`.
//!   3. Band `i` is registered in the cells `(i, j)` for `j` from `max(j0, I_n(fl(min − ε)))` to `min(j1,
//!      I_n(fl(max + ε)))`, `min` and `max` of the two computed `x_n(v_lo)`, `x_n(v_hi)`. `x_n` is affine, so by 1.
//!      every point of the edge in band `i` has its `n` coordinate between `x_n(v_lo)` and `x_n(v_hi)`, within
//!      `13.3 u w` of the computed values; `fl(min − ε) ≤ min − ε + 1.1 u w` (`|min| ≤ w`) is below it, `fl(max + ε)`
//!      above it. `I_n` is monotone and every point of the edge has its index in `[j0, j1]`: each point's cell is
//!      registered.
//!
//! Size: along `m` the bands' `J_i` overlap by `2ε` at most, `|Δn / Δm| ≤ 4` (the box has at least as many cells
//! along `m`, three or more; rounding aside), so an edge takes about `(nc + nr)(3 + 10 ε / cell)` cells:
//! O(length / cell + 1), where a whole box would take `nc · nr` (a long diagonal sliver: a quarter of the grid). On
//! top, the grid is coarsened (`cell` doubled) while the registrations would exceed `32` per edge plus `4096`, so the
//! grid never holds more: memory linear in the mesh whatever its shape (no ordinary mesh comes near; a coarser grid
//! only finds more walls per query, none fewer).
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

/// The walls' grid holds at most this many registrations per edge, plus [`GRID_ITEMS_SPARE`]: a grid that would hold
/// more is coarsened (module docs, "The grid").
const GRID_ITEMS_PER_EDGE: usize = 32;

/// See [`GRID_ITEMS_PER_EDGE`].
const GRID_ITEMS_SPARE: usize = 4096;

/// The rounding margin of an edge's walk through the grid, relative to [`Walls::w`] (module docs, "The grid").
const WALK_MARGIN: f64 = 1e-14;

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
        let mut walls = Walls {
            pos,
            edges,
            lo: [lo[0], lo[1]],
            cell,
            cols: 1,
            rows: 1,
            start: Vec::new(),
            items: Vec::new(),
            cell_top: Vec::new(),
            w,
            zabs,
            mu,
            reach: truth::MarginReach::new(mu, lo, hi),
        };
        // The grid's size, coarsened while the registrations would exceed the budget (module docs, "The grid").
        let budget = GRID_ITEMS_PER_EDGE * walls.edges.len() + GRID_ITEMS_SPARE;
        loop {
            walls.cols = (((hi[0] - lo[0]) / walls.cell) as usize + 1).clamp(1, 4096);
            walls.rows = (((hi[1] - lo[1]) / walls.cell) as usize + 1).clamp(1, 4096);
            if walls.cols * walls.rows == 1 || walls.registrations(budget) <= budget {
                break;
            }
            walls.cell *= 2.0;
        }
        let (cols, rows) = (walls.cols, walls.rows);
        let mut start = vec![0u32; cols * rows + 1];
        for e in 0..walls.edges.len() {
            walls.edge_cells(e, |first, n, stride| {
                for i in 0..n {
                    start[first + i * stride + 1] += 1;
                }
            });
        }
        for i in 0..cols * rows {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut items = vec![0; start[cols * rows] as usize];
        let mut cell_top = vec![f64::NEG_INFINITY; cols * rows];
        for e in 0..walls.edges.len() {
            let [a, b] = walls.edges[e];
            let top = walls.pos[a as usize][2].max(walls.pos[b as usize][2]);
            walls.edge_cells(e, |first, n, stride| {
                for i in 0..n {
                    let k = first + i * stride;
                    items[fill[k] as usize] = e as u32;
                    fill[k] += 1;
                    cell_top[k] = cell_top[k].max(top);
                }
            });
        }
        walls.start = start;
        walls.items = items;
        walls.cell_top = cell_top;
        walls
    }

    /// The grid index along `axis` (0: column, 1: row) of the coordinate `v`: `⌊(v − lo) / cell⌋` computed in f64,
    /// clamped to the grid (`NaN`: 0). Non-decreasing in `v`; [`Walls::planar_hidden`] indexes its cells alike.
    fn index(&self, v: f64, axis: usize) -> usize {
        let n = if axis == 0 { self.cols } else { self.rows };
        let i = ((v - self.lo[axis]) / self.cell).floor();
        if i.is_finite() {
            i.clamp(0.0, (n - 1) as f64) as usize
        } else {
            0
        }
    }

    /// The grid cells edge `e` is registered in, as runs `f(first, n, stride)`: cells `first + i · stride` for
    /// `i < n` (module docs, "The grid", for why they hold every cell of a point of the edge).
    fn edge_cells(&self, e: usize, mut f: impl FnMut(usize, usize, usize)) {
        let [a, b] = self.edges[e];
        let (p, q) = (self.pos[a as usize], self.pos[b as usize]);
        let lo = [p[0].min(q[0]), p[1].min(q[1])];
        let hi = [p[0].max(q[0]), p[1].max(q[1])];
        let (c0, c1) = (self.index(lo[0], 0), self.index(hi[0], 0));
        let (r0, r1) = (self.index(lo[1], 1), self.index(hi[1], 1));
        let (nc, nr) = (c1 - c0 + 1, r1 - r0 + 1);
        let cols = self.cols;
        if nc * nr <= 2 * (nc + nr) || !lo.iter().chain(&hi).all(|v| v.is_finite()) {
            // The whole box: a few cells (or coordinates no valid mesh has).
            for r in r0..=r1 {
                f(r * cols + c0, nc, 1);
            }
            return;
        }
        // Bands across axis `m` (the one of more cells), each with the range of indices along `n` of the edge's
        // points in it.
        let m = usize::from(nr >= nc);
        let n = 1 - m;
        let (i0, i1, j0, j1) = if m == 1 { (r0, r1, c0, c1) } else { (c0, c1, r0, r1) };
        let slope = (q[n] - p[n]) / (q[m] - p[m]);
        let eps = WALK_MARGIN * self.w;
        let across = |v: f64| p[n] + (v - p[m]) * slope;
        for i in i0..=i1 {
            let vlo = if i == i0 {
                lo[m]
            } else {
                (self.lo[m] + self.cell * i as f64 - eps).max(lo[m])
            };
            let vhi = if i == i1 {
                hi[m]
            } else {
                (self.lo[m] + self.cell * (i + 1) as f64 + eps).min(hi[m])
            };
            let (ua, ub) = (across(vlo), across(vhi));
            let (ja, jb) = if ua.is_finite() && ub.is_finite() {
                (
                    self.index(ua.min(ub) - eps, n).max(j0),
                    self.index(ua.max(ub) + eps, n).min(j1),
                )
            } else {
                (j0, j1)
            };
            if ja <= jb {
                if m == 1 {
                    f(i * cols + ja, jb - ja + 1, 1);
                } else {
                    f(ja * cols + i, jb - ja + 1, cols);
                }
            }
        }
    }

    /// The number of registrations of all edges in the current grid, or a number above `limit` once they exceed it.
    fn registrations(&self, limit: usize) -> usize {
        let mut total = 0usize;
        for e in 0..self.edges.len() {
            self.edge_cells(e, |_, n, _| total += n);
            if total > limit {
                break;
            }
        }
        total
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
        let (g0, g1) = (self.index(q_al0, k), self.index(q_al1, k));
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
            let (h0, h1) = (self.index(lat0 - margin, l), self.index(lat1 + margin, l));
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

    /// `n` parallel diagonal slivers from `x = 0` to `x = l` (`l = n`), rising by `rise · l` (the audit's F4 mesh at
    /// `rise = 1`), moved by `offset`.
    fn slivers(n: u32, rise: f64, offset: [f64; 2]) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let l = f64::from(n);
        let mut pos = Vec::new();
        for k in 0..=n {
            let d = f64::from(k);
            pos.push([offset[0], offset[1] + d, 0.1 * (d * 0.3).sin()]);
            pos.push([offset[0] + l, offset[1] + rise * l + d, 0.1 * (d * 0.7).cos()]);
        }
        let tris = (0..n)
            .flat_map(|k| [[2 * k, 2 * k + 1, 2 * k + 3], [2 * k, 2 * k + 3, 2 * k + 2]])
            .collect();
        (pos, tris)
    }

    /// Per edge, the sorted cells it is registered in.
    fn registered(walls: &Walls) -> Vec<Vec<usize>> {
        let mut cells = vec![Vec::new(); walls.edges.len()];
        for c in 0..walls.cols * walls.rows {
            for &e in &walls.items[walls.start[c] as usize..walls.start[c + 1] as usize] {
                cells[e as usize].push(c);
            }
        }
        cells
    }

    /// Checks that every sampled point of every edge lies in a cell the edge is registered in: 257 evenly spaced
    /// points, and at every grid line the edge crosses the crossing point and its neighbours one and two ulps away
    /// in the parameter (each point computed in f64, so within an ulp or so of the segment). Returns the number of
    /// edges registered in fewer cells than their index box (walked).
    fn assert_registration_covers(walls: &Walls) -> usize {
        let cells = registered(walls);
        let mut walked = 0;
        for (e, &[a, b]) in walls.edges.iter().enumerate() {
            let (p, q) = (walls.pos[a as usize], walls.pos[b as usize]);
            let mut ts: Vec<f64> = (0..=256).map(|i| f64::from(i) / 256.0).collect();
            for axis in 0..2 {
                let n = if axis == 0 { walls.cols } else { walls.rows };
                for g in 0..=n {
                    let line = walls.lo[axis] + walls.cell * g as f64;
                    let t = (line - p[axis]) / (q[axis] - p[axis]);
                    if (0.0..=1.0).contains(&t) {
                        ts.extend([
                            t,
                            t.next_up(),
                            t.next_down(),
                            t.next_up().next_up(),
                            t.next_down().next_down(),
                        ]);
                    }
                }
            }
            for t in ts.into_iter().filter(|t| (0.0..=1.0).contains(t)) {
                let x = p[0] + (q[0] - p[0]) * t;
                let y = p[1] + (q[1] - p[1]) * t;
                let c = walls.index(y, 1) * walls.cols + walls.index(x, 0);
                assert!(
                    cells[e].binary_search(&c).is_ok(),
                    "edge {e} {p:?}-{q:?}: point at t = {t} ({x}, {y}) in cell {c} not registered ({:?})",
                    cells[e]
                );
            }
            let box_cells = (walls.index(p[0].max(q[0]), 0) - walls.index(p[0].min(q[0]), 0) + 1)
                * (walls.index(p[1].max(q[1]), 1) - walls.index(p[1].min(q[1]), 1) + 1);
            if cells[e].len() < box_cells {
                walked += 1;
            }
        }
        walked
    }

    /// The grid registration holds every cell of every point of an edge (module docs, "The grid"), on slivers of
    /// several slopes and places (UTM-like offsets, where rounding is coarser than the cells' fine structure), and on
    /// random long triangles; and it walks the long edges instead of registering their whole boxes.
    #[test]
    fn every_point_of_an_edge_lies_in_a_registered_cell() {
        for (rise, offset) in [
            (1.0, [0.0, 0.0]),
            (0.13, [0.0, 0.0]),
            (7.5, [-300.0, 20.0]),
            (-0.6, [0.0, 0.0]),
            (1.0, [5e5, 5e6]),
            (0.31, [-4e6, 3e7]),
        ] {
            let (pos, tris) = slivers(300, rise, offset);
            let walls = Walls::new(&pos, &tris);
            let walked = assert_registration_covers(&walls);
            assert!(walked >= 300, "rise {rise}: {walked} edges walked");
        }
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            seed = seed.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = seed;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        for round in 0..20 {
            let scale = [1.0, 1e-3, 1e4, 3.7][round % 4];
            let offset = [0.0, 6e5, -2.5e6][round % 3];
            let pos: Vec<[f64; 3]> = (0..300)
                .map(|_| {
                    [
                        offset + scale * 1000.0 * next(),
                        offset + scale * 1000.0 * next(),
                        next(),
                    ]
                })
                .collect();
            // Mostly short triangles, and some spanning the whole terrain.
            let tris: Vec<[u32; 3]> = (0..200u32)
                .map(|i| {
                    let a = (next() * 300.0) as u32 % 300;
                    let b = if i % 5 == 0 {
                        (next() * 300.0) as u32 % 300
                    } else {
                        (a + 1) % 300
                    };
                    [a, b, (a + 2) % 300]
                })
                .collect();
            let walls = Walls::new(&pos, &tris);
            assert_registration_covers(&walls);
        }
    }

    /// The audit's sliver mesh (8,000 diagonal slivers, a valid height field of 500 KB as a file) registered each edge
    /// in every cell of its box: about 64 million registrations (253 MB). Walking the edges, the grid holds
    /// O(length / cell) per edge, and never more than 32 per edge plus 4,096 (here about 525,000).
    #[test]
    fn long_slivers_take_few_registrations() {
        let (pos, tris) = slivers(8_000, 1.0, [0.0, 0.0]);
        let walls = Walls::new(&pos, &tris);
        let (edges, items) = (walls.edges.len(), walls.items.len());
        eprintln!(
            "slivers: {edges} edges, {items} registrations, grid {} x {}",
            walls.cols, walls.rows
        );
        assert!(items <= GRID_ITEMS_PER_EDGE * edges + GRID_ITEMS_SPARE);
        assert!(items < 1_000_000, "{items} registrations for {edges} edges");
    }
}
