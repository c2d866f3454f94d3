//! Conservative precomputed regions (the README's "Safe culling": one construction of a conservative region), with
//! the proof.
//!
//! For a node `N` (a set of triangles), bounded in x,y by the circle `(m, r)` and in height by `z_max`, and for sector
//! `i` (centre direction `r_i`, half-width `w = π / s`), the camera directions from `N`'s points that fall in the
//! sector stay inside the wedge `W = disk(m, r) ⊕ {ρ (cos θ, sin θ) : ρ ≥ 0, θ ∈ sector i}`.
//!
//! **Barriers.** A barrier is a connected chain `Λ` of TIN edges, all beyond `N` (every end vertex at
//! `t > r_i · m + r`), joining a vertex outside `W` on its left to one outside `W` on its right (left and right of
//! `W`'s cross-section `|lateral| ≤ r / cos w + s tan w` at the distance `s` along `r_i` from `m`). Inside the
//! half-plane `t > r_i · m + r`, `W` is a half-strip whose bottom every sector ray from `N` crosses; a curve joining
//! its two sides without touching the bottom separates the bottom from infinity, so every such ray crosses `Λ`, at a
//! point `q` with `t_q ≤ T = ` the largest `t` of `Λ`'s vertices. On an edge the terrain is exactly the segment between
//! its end vertices.
//!
//! **Slope bound.** For `p ∈ N` (`|p − m| ≤ r`, `z_p ≤ z_max`) and `q` on an edge `e = uv` (heights lowered by the
//! margin `μ`): when `z_u, z_v ≥ z_max + μ`, `q ↦ f(p, q) = (z_q − z_p)/|q − p|` has a non-negative affine numerator
//! over a convex distance, so it is quasi-concave on the edge and `f ≥ min(f(p, u), f(p, v)) ≥ min_x (z_x − μ −
//! z_max) / (|x − m| + r)` over the two ends; otherwise `f ≥ (min(z_u, z_v) − μ − z_max) / (dist(e, m) − r)`
//! (a negative numerator over a distance bounded below). The barrier's slope `σ` is the least bound over its edges:
//! Kruskal's order (edges by decreasing bound, union–find, each component knowing whether it holds a left and a right
//! anchor and its largest `t`) finds, for a limit on `t`, the chain with the largest `σ` (a bottleneck path), and the
//! limits `r_i · m + r (1 + 2^k)` give barriers at several distances.
//!
//! **Region.** Let `σ' = σ_d` when `σ_d ≥ 0`, else `σ_d / cos w`. Every camera `c` with `t_c = r_i · c > T_d =
//! r_i · m + d` and `z_c < min_{v ∈ vertices(N)} (z_v + σ' (t_c − t_v))` is hidden from every point `p` of `N` whose
//! direction to `c` is in sector `i`. *Proof.* The right-hand side is affine in `p` over each triangle, so the
//! inequality holds for every `p ∈ N`: `z_c − z_p < σ' r_i · (c − p)`. With `φ` the angle between `c − p` and `r_i`
//! (`|φ| ≤ w`), `r_i · (c − p) = |c − p| cos φ`, so `σ' r_i · (c − p) ≤ σ_d |c − p|` in both signs of `σ_d`. The
//! segment from `p` (`t_p ≤ r_i · m + r < T_d`) to `c` (`t_c > T_d`) stays in `W` and crosses the line of `S_d` once,
//! at a point `q` of `S_d`, with `|q − p| < |c − p|`. There the sight line is at
//! `z_p + (z_c − z_p) |q − p| / |c − p| < z_p + σ_d |q − p| ≤ z_q`, at least `μ` below the terrain. ∎
//!
//! Every barrier `d` of a ladder `d_k = r · (1.25, 2, 3, 5, 8, 13, …)` (up to the footprint's size) gives one such
//! half-plane `{t > T_k, z < σ'_k t + b_k}`; the node's region in the sector is their union, stored as a polyline below
//! its upper envelope: on each interval between consecutive `T_k` one valid line (the highest at the interval's
//! middle), joined at each `T_k` through the lower of the two lines, so every point of the polyline lies under one of
//! the half-planes.
//!
//! **Rounding.** `μ = 1e-7 (1 + extent + max |z|)` m ([`height_margin`]): a sight line called blocked passes at least
//! `μ` below the terrain, which is at least ten times the exact checker's tolerance (`truth::walk`, growing with the
//! eye's distance and height) for every eye that `truth::MarginReach` covers with `μ` and the vertices' box. The
//! users of these regions judge only such eyes (`eval`'s `safe_regions` and `pvs`'s regions test call every node
//! visible from farther away, some hundred times the terrain's size); slopes are moved
//! towards smaller values by a relative `1e-9`, the offsets `b_k` down by `1e-9 (1 + |b_k| + |σ'| max |t|)`, the left
//! bounds `T_k` up by `1e-9 (1 + |T_k|)`; the f32 storage (`cull::StoredRegion::from_f64`) only shrinks regions; the
//! run-time test tests every sector that the directions from the node's bounding circle to the camera touch.

// Comparisons are written so that a NaN answers "no region" (`!(a > b)`), on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::{DVec2, DVec3};

/// A node for [`conservative_regions`]: its triangles and a circle enclosing their vertices.
#[derive(Clone, Debug)]
pub struct NodeShape<'a> {
    /// Indices into the mesh's triangles.
    pub triangles: &'a [u32],
    /// Circle centre (x, y), world coordinates.
    pub centre: DVec2,
    /// Circle radius.
    pub radius: f64,
}

/// One sector's conservative region in the absolute plane frame (`t = r_i · xy`): boundary vertices `[t, z]` with
/// strictly increasing `t` (the first on the left bound) and the slope beyond the last.
pub type Polyline = (Vec<[f64; 2]>, f64);

/// Vertex neighbours (CSR) and a grid of vertices, shared by all nodes.
struct Topology {
    start: Vec<u32>,
    adj: Vec<u32>,
    lo: DVec2,
    cell: f64,
    cols: usize,
    rows: usize,
    cell_start: Vec<u32>,
    cell_items: Vec<u32>,
}

impl Topology {
    fn new(pos: &[DVec3], tris: &[[u32; 3]]) -> Topology {
        let n = pos.len();
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for p in pos {
            lo = lo.min(p.truncate());
            hi = hi.max(p.truncate());
        }
        let area = ((hi.x - lo.x) * (hi.y - lo.y)).max(1e-300);
        let cell = (area / n.max(1) as f64).sqrt() * 2.0;
        let cell = if cell.is_finite() && cell > 0.0 { cell } else { 1.0 };
        let cols = (((hi.x - lo.x) / cell) as usize + 1).clamp(1, 4096);
        let rows = (((hi.y - lo.y) / cell) as usize + 1).clamp(1, 4096);
        let cell_of = |p: DVec2| {
            let c = ((p.x - lo.x) / cell).floor().clamp(0.0, (cols - 1) as f64) as usize;
            let r = ((p.y - lo.y) / cell).floor().clamp(0.0, (rows - 1) as f64) as usize;
            (c, r)
        };
        let mut edges: Vec<(u32, u32)> = tris
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .flat_map(|(a, b)| [(a, b), (b, a)])
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let mut start = vec![0u32; n + 1];
        for &(a, _) in &edges {
            start[a as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let adj = edges.iter().map(|e| e.1).collect();
        let mut cell_start = vec![0u32; cols * rows + 1];
        let cells: Vec<usize> = pos
            .iter()
            .map(|p| {
                let (c, r) = cell_of(p.truncate());
                r * cols + c
            })
            .collect();
        for &c in &cells {
            cell_start[c + 1] += 1;
        }
        for i in 0..cols * rows {
            cell_start[i + 1] += cell_start[i];
        }
        let mut fill = cell_start.clone();
        let mut cell_items = vec![0u32; n];
        for (v, &c) in cells.iter().enumerate() {
            cell_items[fill[c] as usize] = v as u32;
            fill[c] += 1;
        }
        Topology {
            start,
            adj,
            lo,
            cell,
            cols,
            rows,
            cell_start,
            cell_items,
        }
    }

    fn neighbours(&self, v: u32) -> &[u32] {
        &self.adj[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }

    /// Vertices in the cells meeting the box `[a, b]`.
    fn vertices_in(&self, a: DVec2, b: DVec2, out: &mut Vec<u32>) {
        let cell = |p: DVec2| {
            let c = ((p.x - self.lo.x) / self.cell)
                .floor()
                .clamp(0.0, (self.cols - 1) as f64) as usize;
            let r = ((p.y - self.lo.y) / self.cell)
                .floor()
                .clamp(0.0, (self.rows - 1) as f64) as usize;
            (c, r)
        };
        let ((c0, r0), (c1, r1)) = (cell(a), cell(b));
        for r in r0..=r1 {
            for c in c0..=c1 {
                let k = r * self.cols + c;
                out.extend_from_slice(&self.cell_items[self.cell_start[k] as usize..self.cell_start[k + 1] as usize]);
            }
        }
    }
}

/// The height margin `μ = 1e-7 (1 + extent + max |z|)` m of the regions over the mesh `positions` (`extent` the
/// diagonal of their box in x,y; 0 without positions).
pub fn height_margin(positions: &[DVec3]) -> f64 {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for p in positions {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    if positions.is_empty() {
        return 1e-7;
    }
    let extent = (hi.x - lo.x).hypot(hi.y - lo.y);
    1e-7 * (1.0 + extent + lo.z.abs().max(hi.z.abs()))
}

/// Conservative regions of `nodes` over the mesh `positions`/`triangles`, for `sectors` sectors: per node, the sectors
/// in which it has a region, in increasing order, each with the region's boundary (see the module documentation); a
/// sector left out is one in which the node is never hidden.
///
/// A node's regions depend only on its vertex set (the vertices of its triangles), its circle and the mesh, so nodes
/// alike in these have the same regions: callers with repeated nodes should pass each once. The work for a node is
/// about its triangles times `log` plus `sectors` searches near it, and the result holds only the regions made.
pub fn conservative_regions(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    nodes: &[NodeShape],
    sectors: u32,
) -> Vec<Vec<(u32, Polyline)>> {
    use rayon::prelude::*;
    let topo = Topology::new(positions, triangles);
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for p in positions {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let extent = (hi.x - lo.x).hypot(hi.y - lo.y);
    let mu = height_margin(positions);
    let w = std::f64::consts::PI / f64::from(sectors);
    nodes
        .par_iter()
        .map(|node| {
            let mut verts: Vec<u32> = node.triangles.iter().flat_map(|&t| triangles[t as usize]).collect();
            verts.sort_unstable();
            verts.dedup();
            let z_max = verts
                .iter()
                .map(|&v| positions[v as usize].z)
                .fold(f64::NEG_INFINITY, f64::max);
            let ctx = Context {
                positions,
                topo: &topo,
                node,
                verts: &verts,
                z_max,
                w,
                mu,
                extent,
            };
            // Only the sectors with a region: memory follows the regions made, not nodes × sectors.
            (0..sectors)
                .filter_map(|i| ctx.sector_region(sectors, i).map(|r| (i, r)))
                .collect()
        })
        .collect()
}

/// What one node's regions are computed from.
struct Context<'a> {
    positions: &'a [DVec3],
    topo: &'a Topology,
    node: &'a NodeShape<'a>,
    verts: &'a [u32],
    z_max: f64,
    w: f64,
    mu: f64,
    extent: f64,
}

/// Union–find with per-component anchors and largest `t`.
struct Components {
    parent: Vec<u32>,
    left: Vec<bool>,
    right: Vec<bool>,
    t_max: Vec<f64>,
}

impl Components {
    fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[x as usize];
            self.parent[x as usize] = self.parent[p as usize];
            x = p;
        }
        x
    }

    /// Joins the components of `a` and `b`; returns the joined root.
    fn union(&mut self, a: u32, b: u32) -> u32 {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return ra;
        }
        self.parent[rb as usize] = ra;
        let (i, j) = (ra as usize, rb as usize);
        self.left[i] |= self.left[j];
        self.right[i] |= self.right[j];
        self.t_max[i] = self.t_max[i].max(self.t_max[j]);
        ra
    }
}

impl Context<'_> {
    fn sector_region(&self, sectors: u32, sector: u32) -> Option<Polyline> {
        let [rx, ry] = cull::sector_direction(sectors, sector);
        let dir = DVec2::new(rx, ry);
        let across = dir.perp();
        let (m, r) = (self.node.centre, self.node.radius.max(1e-9));
        let t_m = dir.dot(m);
        let (cos_w, tan_w) = (self.w.cos(), self.w.tan());
        let half = |s: f64| (r / cos_w + s * tan_w) * (1.0 + 1e-9) + 1e-9;
        // Candidate vertices: beyond the node, within reach of the largest limit, inside the wedge or just beside it.
        let reach = (16.0 * r).min(2.0 * self.extent + r) + r;
        let box_pts = [
            m,
            m + dir * (reach + r),
            m + dir * (reach + r) + across * half(reach + r) * 1.5,
            m + dir * (reach + r) - across * half(reach + r) * 1.5,
            m + across * half(0.0) * 1.5,
            m - across * half(0.0) * 1.5,
        ];
        let (mut a, mut b) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for p in box_pts {
            a = a.min(p);
            b = b.max(p);
        }
        let mut cand = Vec::new();
        self.topo.vertices_in(a, b, &mut cand);
        // Per candidate: (vertex, t, side: −1 left, 0 inside, +1 right).
        let mut info: Vec<(u32, f64, i8)> = Vec::new();
        let margin_cells = 2.0 * self.topo.cell;
        for &v in &cand {
            let p = self.positions[v as usize].truncate();
            let s = dir.dot(p - m);
            if !(s > r * (1.0 + 1e-9) + 1e-9) || s > reach + r {
                continue;
            }
            let l = across.dot(p - m);
            let h = half(s);
            if l.abs() > h + margin_cells {
                continue;
            }
            let side = if l > h {
                1
            } else if l < -h {
                -1
            } else {
                0
            };
            info.push((v, t_m + s, side));
        }
        if info.is_empty() {
            return None;
        }
        info.sort_unstable_by_key(|x| x.0);
        let index_of = |v: u32| info.binary_search_by_key(&v, |x| x.0).ok();
        // Edges among candidates with their slope bounds.
        let z_of = |v: u32| self.positions[v as usize].z - self.mu;
        let dist_m = |v: u32| (self.positions[v as usize].truncate() - m).length();
        let mut edges: Vec<(f64, u32, u32)> = Vec::new();
        for (i, &(u, _, _)) in info.iter().enumerate() {
            for &v in self.topo.neighbours(u) {
                if v <= u {
                    continue;
                }
                let Some(j) = index_of(v) else { continue };
                let (zu, zv) = (z_of(u), z_of(v));
                let sigma = if zu.min(zv) >= self.z_max {
                    ((zu - self.z_max) / (dist_m(u) * (1.0 + 1e-12) + r))
                        .min((zv - self.z_max) / (dist_m(v) * (1.0 + 1e-12) + r))
                } else {
                    let (pu, pv) = (
                        self.positions[u as usize].truncate(),
                        self.positions[v as usize].truncate(),
                    );
                    let d = segment_distance(m, pu, pv) * (1.0 - 1e-12) - r;
                    if !(d > 0.0) {
                        continue;
                    }
                    (zu.min(zv) - self.z_max) / d
                };
                if sigma.is_finite() {
                    edges.push((sigma, i as u32, j as u32));
                }
            }
        }
        edges.sort_unstable_by(|x, y| y.0.total_cmp(&x.0));
        // Kruskal per limit on t.
        let mut lines: Vec<(f64, f64, f64)> = Vec::new();
        let mut limit_factor = 2.0;
        while limit_factor <= 16.0 && r * limit_factor <= 2.0 * self.extent + r {
            let limit = t_m + r + r * limit_factor;
            limit_factor *= 2.0;
            let mut comp = Components {
                parent: (0..info.len() as u32).collect(),
                left: info.iter().map(|x| x.2 < 0).collect(),
                right: info.iter().map(|x| x.2 > 0).collect(),
                t_max: info.iter().map(|x| x.1).collect(),
            };
            let mut found = None;
            for &(sigma, i, j) in &edges {
                if info[i as usize].1 > limit || info[j as usize].1 > limit {
                    continue;
                }
                let root = comp.union(i, j) as usize;
                if comp.left[root] && comp.right[root] {
                    found = Some((sigma, comp.t_max[root]));
                    break;
                }
            }
            let Some((sigma, t_top)) = found else { continue };
            if lines.last().is_some_and(|l: &(f64, f64, f64)| l.0 >= t_top) {
                continue;
            }
            let sigma = if sigma >= 0.0 {
                sigma * (1.0 - 1e-9)
            } else {
                sigma * (1.0 + 1e-9) / cos_w
            };
            let mut b_k = f64::INFINITY;
            let mut t_abs: f64 = 0.0;
            for &v in self.verts {
                let p = self.positions[v as usize];
                let t_v = dir.dot(p.truncate());
                t_abs = t_abs.max(t_v.abs());
                b_k = b_k.min(p.z - sigma * t_v);
            }
            let b_k = b_k - 1e-9 * (1.0 + b_k.abs() + sigma.abs() * t_abs);
            lines.push((t_top + 1e-9 * (1.0 + t_top.abs()), sigma, b_k));
        }
        lines.sort_by(|x, y| x.0.total_cmp(&y.0));
        envelope(&lines)
    }
}

/// Distance from `m` to the segment `a b`.
fn segment_distance(m: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let len2 = d.length_squared();
    let s = if len2 > 0.0 {
        ((m - a).dot(d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + d * s - m).length()
}

/// A polyline below the upper envelope of the half-planes `{t > T_k, z < σ_k t + b_k}` (sorted by `T_k`).
fn envelope(lines: &[(f64, f64, f64)]) -> Option<Polyline> {
    if lines.is_empty() {
        return None;
    }
    let at = |k: usize, t: f64| lines[k].1 * t + lines[k].2;
    // On each interval [T_k, T_{k+1}] the valid line highest at its middle; the last interval is open.
    let mut points: Vec<[f64; 2]> = Vec::new();
    let mut chosen = 0usize;
    for k in 0..lines.len() {
        let t0 = lines[k].0;
        let t1 = lines.get(k + 1).map_or(t0 + 1.0, |l| l.0);
        let mid = 0.5 * (t0 + t1);
        let best = (0..=k).max_by(|&a, &b| at(a, mid).total_cmp(&at(b, mid))).unwrap_or(k);
        if k == 0 {
            points.push([t0, at(best, t0)]);
            chosen = best;
        } else if best != chosen {
            // Join through the lower of the two lines just past the bound (under a half-plane everywhere).
            // Far enough past the bound to survive the f32 storage.
            let t = t0 + 1e-6 * (1.0 + t0.abs()) + 1e-3 * (t0 - lines[0].0);
            let prev = points.last().map_or(f64::NEG_INFINITY, |p| p[0]);
            if t0 > prev && t > t0 {
                points.push([t0, at(chosen, t0)]);
                points.push([t, at(chosen, t).min(at(best, t))]);
                chosen = best;
            }
        }
    }
    let tail = lines[chosen].1;
    (points.iter().all(|p| p[0].is_finite() && p[1].is_finite()) && tail.is_finite()).then_some((points, tail))
}
