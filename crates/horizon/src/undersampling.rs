//! The opt-in undersampling fix (thesis 4.5.4): TIN edges that cross a subsector's wedge with neither endpoint
//! inside it become horizon candidates.
//!
//! The thesis proposes, "for each point p, \[to\] evaluate whether any of the edges of any point within a certain
//! distance cross one of its sectors. If an edge crosses a sector without either vertex being inside the sector,
//! then the edge is checked to see if it alters the horizon for p." Made precise here (choices marked *):
//!
//! For apex `p`, subsector `j` (wedge `W`, centre direction `r`) and radius `R`, the edge `{u, w}` yields a
//! candidate iff
//! 1. neither `u` nor `w` is `p`;
//! 2. `u` or `w` lies within `R` of `p` in x,y (* `dx² + dy² ≤ R²`, evaluated in f64);
//! 3. neither `u` nor `w` lies in the closed wedge `W` (the exact predicate of [`crate::sector::Wedge`]);
//! 4. the segment crosses the open centre ray `p + λr, λ > 0`: `u` and `w` lie strictly on opposite sides of the
//!    centre line and the crossing is ahead of `p` (exact predicates). With 3., this is the same as crossing the
//!    wedge: a segment entering the convex wedge through one boundary ray and leaving through the other crosses
//!    every ray strictly between them.
//! 5. (* the candidate point) it is the crossing with the centre ray, `c = u + s(w − u)` with
//!    `s = cross(r, u − p) / (cross(r, u − p) − cross(r, w − p))` and its height interpolated linearly along the
//!    edge, all in f64. It projects to `(t_c, z_c)` like a vertex (`t_c = r · (c − origin)`) and competes with
//!    the subsector's vertex horizon under the usual order (slope, then smaller `t`); on a full tie the vertex wins,
//!    and edge points rank among themselves by their endpoints. A crossing with `t_c ≤ t_p` after rounding is
//!    dropped, as for vertices.
//!
//! The crossing with the centre ray is where the thesis' linear projection places every member of the wedge, so
//! an edge that spans the wedge is sampled exactly where the subsector's horizon is meant to be measured.
//!
//! Two implementations of the same definition: `fast` gathers the edges of the vertices within `R` from a
//! uniform grid and tests only the subsectors whose centre ray lies inside the edge's angular span (found with
//! `atan2`, padded by one subsector on each side, every test exact); `straightforward` tests every edge near `p`
//! against every subsector. Tests check that they agree; [`crate::compute`] uses the first,
//! [`crate::brute_force`] the second.

use std::cmp::Ordering;

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use tin::{NO_NEIGHBOUR, Tin};

use crate::NO_HORIZON;
use crate::candidate::{Candidate, CandidateId, keep_best};
use crate::field::EdgeHorizon;
use crate::predicates::{orient2d, side};
use crate::sector::{SectorGeometry, Wedge};

/// Edge-point horizons that replace vertex horizons: `(slot, point)` with `slot = subsector · n + vertex`, sorted.
pub(crate) type Overrides = Vec<(u64, EdgeHorizon)>;

/// The undirected edges of a TIN (smaller index first) and, per vertex, the edges incident to it.
struct Edges {
    list: Vec<[u32; 2]>,
    offsets: Vec<u32>,
    incident: Vec<u32>,
}

impl Edges {
    fn of(tin: &Tin) -> Edges {
        let mut list = Vec::with_capacity(tin.num_triangles() * 3 / 2 + 3);
        for (tri, nb) in tin.triangles().iter().zip(tin.neighbours()) {
            for i in 0..3 {
                let (a, b) = (tri[i], tri[(i + 1) % 3]);
                // Each interior edge appears in two triangles with opposite directions: keep one.
                if nb[i] == NO_NEIGHBOUR || a < b {
                    list.push([a.min(b), a.max(b)]);
                }
            }
        }
        list.sort_unstable();
        list.dedup();
        let n = tin.num_vertices();
        let mut offsets = vec![0u32; n + 1];
        for e in &list {
            offsets[e[0] as usize + 1] += 1;
            offsets[e[1] as usize + 1] += 1;
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut incident = vec![0u32; list.len() * 2];
        for (id, e) in list.iter().enumerate() {
            for &v in e {
                incident[fill[v as usize] as usize] = id as u32;
                fill[v as usize] += 1;
            }
        }
        Edges {
            list,
            offsets,
            incident,
        }
    }

    fn incident(&self, v: u32) -> &[u32] {
        &self.incident[self.offsets[v as usize] as usize..self.offsets[v as usize + 1] as usize]
    }
}

/// An edge's candidate with its 3-D point.
type EdgeCandidate = (Candidate, DVec3);

/// Clause 2 of the definition.
#[inline]
fn within(p: DVec2, x: DVec2, r2: f64) -> bool {
    let d = x - p;
    d.x * d.x + d.y * d.y <= r2
}

/// The candidate of edge `edge` for apex `p` in the subsector with wedge `wedge`, with its 3-D point, or `None`
/// (the definition in the module documentation, clauses 1–5).
fn edge_candidate(
    positions: &[DVec3],
    origin: DVec2,
    wedge: &Wedge,
    p: u32,
    edge: [u32; 2],
    r2: f64,
) -> Option<EdgeCandidate> {
    let [u, w] = edge;
    if u == p || w == p {
        return None;
    }
    let (p3, u3, w3) = (positions[p as usize], positions[u as usize], positions[w as usize]);
    let (pxy, uxy, wxy) = (p3.truncate(), u3.truncate(), w3.truncate());
    if !within(pxy, uxy, r2) && !within(pxy, wxy, r2) {
        return None;
    }
    if wedge.contains(pxy, uxy) || wedge.contains(pxy, wxy) {
        return None;
    }
    let (su, sw) = (side(wedge.r, pxy, uxy), side(wedge.r, pxy, wxy));
    let ahead = match (su, sw) {
        (Ordering::Less, Ordering::Greater) => orient2d(uxy, wxy, pxy) == Ordering::Greater,
        (Ordering::Greater, Ordering::Less) => orient2d(uxy, wxy, pxy) == Ordering::Less,
        _ => false,
    };
    if !ahead {
        return None;
    }
    let fu = wedge.r.perp_dot(uxy - pxy);
    let fw = wedge.r.perp_dot(wxy - pxy);
    let s = (fu / (fu - fw)).clamp(0.0, 1.0);
    let c = u3 + (w3 - u3) * s;
    let tc = wedge.project(origin, c.truncate());
    if tc <= wedge.project(origin, pxy) {
        return None;
    }
    Some((
        Candidate {
            point: DVec2::new(tc, c.z),
            id: CandidateId::Edge(u, w),
        },
        c,
    ))
}

/// Compares the best edge candidate of each subsector with `p`'s vertex horizon there and records the winners.
#[allow(clippy::too_many_arguments)]
fn resolve(
    positions: &[DVec3],
    origin: DVec2,
    wedges: &[Wedge],
    horizons: &[u32],
    p: u32,
    best_edges: &[Option<EdgeCandidate>],
    out: &mut Vec<(u64, EdgeHorizon)>,
) {
    let n = positions.len();
    let pxy = positions[p as usize].truncate();
    for (j, best) in best_edges.iter().enumerate() {
        let Some((edge, point)) = best else { continue };
        let apex = DVec2::new(wedges[j].project(origin, pxy), positions[p as usize].z);
        let slot = j * n + p as usize;
        let h = horizons[slot];
        let wins = h == NO_HORIZON || {
            let q = positions[h as usize];
            let vertex = Candidate::vertex(wedges[j].project(origin, q.truncate()), q.z, h);
            edge.rank(&vertex, apex).is_gt()
        };
        if wins && let CandidateId::Edge(a, b) = edge.id {
            out.push((
                slot as u64,
                EdgeHorizon {
                    edge: [a, b],
                    point: *point,
                },
            ));
        }
    }
}

fn finish(per_vertex: Vec<Vec<(u64, EdgeHorizon)>>) -> Overrides {
    let mut all: Overrides = per_vertex.into_iter().flatten().collect();
    all.sort_unstable_by_key(|&(slot, _)| slot);
    all
}

/// The reference implementation: every edge with an endpoint within `radius` of `p`, against every subsector.
pub(crate) fn straightforward(
    tin: &Tin,
    geometry: &SectorGeometry,
    origin: DVec2,
    radius: f64,
    horizons: &[u32],
) -> Overrides {
    let positions = tin.positions();
    let edges = Edges::of(tin);
    let wedges: Vec<Wedge> = (0..geometry.total()).map(|j| geometry.wedge(j)).collect();
    let r2 = radius * radius;
    let per_vertex: Vec<Vec<(u64, EdgeHorizon)>> = (0..positions.len() as u32)
        .into_par_iter()
        .map(|p| {
            let pxy = positions[p as usize].truncate();
            let mut best: Vec<Option<EdgeCandidate>> = vec![None; wedges.len()];
            for &e in &edges.list {
                if !within(pxy, positions[e[0] as usize].truncate(), r2)
                    && !within(pxy, positions[e[1] as usize].truncate(), r2)
                {
                    continue;
                }
                for (j, wedge) in wedges.iter().enumerate() {
                    if let Some(c) = edge_candidate(positions, origin, wedge, p, e, r2) {
                        keep_best_pair(&mut best[j], c, wedge.project(origin, pxy), positions[p as usize].z);
                    }
                }
            }
            let mut out = Vec::new();
            resolve(positions, origin, &wedges, horizons, p, &best, &mut out);
            out
        })
        .collect();
    finish(per_vertex)
}

fn keep_best_pair(best: &mut Option<EdgeCandidate>, c: (Candidate, DVec3), tp: f64, zp: f64) {
    let apex = DVec2::new(tp, zp);
    let mut b = best.map(|(cand, _)| cand);
    keep_best(&mut b, c.0, apex);
    if b == Some(c.0) {
        *best = Some(c);
    }
}

/// A uniform grid over the vertices' x,y.
struct PointGrid {
    min: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    offsets: Vec<u32>,
    items: Vec<u32>,
}

impl PointGrid {
    fn new(positions: &[DVec3], radius: f64) -> PointGrid {
        let (mut min, mut max) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for p in positions {
            min = min.min(p.truncate());
            max = max.max(p.truncate());
        }
        let extent = (max - min).max_element().max(0.0);
        // At most about 4·sqrt(n) cells per axis.
        let cell = radius
            .max(extent / (4.0 * (positions.len() as f64).sqrt()).max(1.0))
            .max(f64::MIN_POSITIVE);
        let nx = (((max.x - min.x) / cell) as usize).saturating_add(1).min(1 << 20);
        let ny = (((max.y - min.y) / cell) as usize).saturating_add(1).min(1 << 20);
        let mut grid = PointGrid {
            min,
            cell,
            nx,
            ny,
            offsets: vec![0; nx * ny + 1],
            items: vec![0; positions.len()],
        };
        let cells: Vec<usize> = positions.iter().map(|p| grid.cell_index(p.truncate())).collect();
        for &c in &cells {
            grid.offsets[c + 1] += 1;
        }
        for i in 0..nx * ny {
            grid.offsets[i + 1] += grid.offsets[i];
        }
        let mut fill = grid.offsets.clone();
        for (v, &c) in cells.iter().enumerate() {
            grid.items[fill[c] as usize] = v as u32;
            fill[c] += 1;
        }
        grid
    }

    fn axis(&self, x: f64, min: f64, n: usize) -> usize {
        let i = ((x - min) / self.cell).floor();
        if i.is_nan() || i < 0.0 {
            0
        } else {
            (i as usize).min(n - 1)
        }
    }

    fn cell_index(&self, p: DVec2) -> usize {
        self.axis(p.y, self.min.y, self.ny) * self.nx + self.axis(p.x, self.min.x, self.nx)
    }

    /// Every vertex in the cells overlapping the square of half-side `r` around `p`.
    fn around(&self, p: DVec2, r: f64, mut f: impl FnMut(u32)) {
        let (x0, x1) = (
            self.axis(p.x - r, self.min.x, self.nx),
            self.axis(p.x + r, self.min.x, self.nx),
        );
        let (y0, y1) = (
            self.axis(p.y - r, self.min.y, self.ny),
            self.axis(p.y + r, self.min.y, self.ny),
        );
        for y in y0..=y1 {
            let row = y * self.nx;
            let (a, b) = (self.offsets[row + x0] as usize, self.offsets[row + x1 + 1] as usize);
            for &v in &self.items[a..b] {
                f(v);
            }
        }
    }
}

/// The subsectors whose centre ray may cross the segment `u w` seen from `p`: the centre azimuths inside the
/// segment's angular span, padded by one on each side; every subsector when the span is near a half turn.
fn crossed_subsectors(p: DVec2, u: DVec2, w: DVec2, total: usize, out: &mut Vec<usize>) {
    out.clear();
    let nf = total as f64;
    // Position in units of subsectors, centre of subsector j at j.
    let pos = |d: DVec2| (d.y.atan2(d.x) / std::f64::consts::TAU * nf - 0.5).rem_euclid(nf);
    let (xu, xw) = (pos(u - p), pos(w - p));
    let diff = (xw - xu).rem_euclid(nf);
    let (start, len) = if diff <= nf / 2.0 { (xu, diff) } else { (xw, nf - diff) };
    if len.is_nan() || len > nf / 2.0 - 2.0 {
        out.extend(0..total);
        return;
    }
    let first = start.floor() as isize - 1;
    let last = (start + len).floor() as isize + 1;
    for j in first..=last {
        out.push(j.rem_euclid(total as isize) as usize);
    }
}

/// The fast implementation: edges of the vertices within `radius` (uniform grid), tested only against the
/// subsectors their angular span covers.
pub(crate) fn fast(tin: &Tin, geometry: &SectorGeometry, origin: DVec2, radius: f64, horizons: &[u32]) -> Overrides {
    let positions = tin.positions();
    let edges = Edges::of(tin);
    let grid = PointGrid::new(positions, radius);
    let wedges: Vec<Wedge> = (0..geometry.total()).map(|j| geometry.wedge(j)).collect();
    let r2 = radius * radius;
    let search = radius * (1.0 + 1e-9);
    let per_vertex: Vec<Vec<(u64, EdgeHorizon)>> = (0..positions.len() as u32)
        .into_par_iter()
        .map_init(
            || (vec![None; wedges.len()], Vec::new()),
            |(best, subsectors): &mut (Vec<Option<EdgeCandidate>>, Vec<usize>), p| {
                best.iter_mut().for_each(|b| *b = None);
                let pxy = positions[p as usize].truncate();
                let zp = positions[p as usize].z;
                grid.around(pxy, search, |u| {
                    if u == p || !within(pxy, positions[u as usize].truncate(), r2) {
                        return;
                    }
                    for &e in edges.incident(u) {
                        let edge = edges.list[e as usize];
                        let w = if edge[0] == u { edge[1] } else { edge[0] };
                        // Gather each edge once: from its smaller endpoint when both are within the radius.
                        if w == p || (w < u && within(pxy, positions[w as usize].truncate(), r2)) {
                            continue;
                        }
                        let (uxy, wxy) = (positions[u as usize].truncate(), positions[w as usize].truncate());
                        crossed_subsectors(pxy, uxy, wxy, wedges.len(), subsectors);
                        for &j in subsectors.iter() {
                            if let Some(c) = edge_candidate(positions, origin, &wedges[j], p, edge, r2) {
                                keep_best_pair(&mut best[j], c, wedges[j].project(origin, pxy), zp);
                            }
                        }
                    }
                });
                let mut out = Vec::new();
                resolve(positions, origin, &wedges, horizons, p, best, &mut out);
                out
            },
        )
        .collect();
    finish(per_vertex)
}
