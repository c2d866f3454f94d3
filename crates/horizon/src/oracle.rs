//! The O(n²) brute-force oracle: the horizon definition of the `sector` module, evaluated literally.
//!
//! For every vertex `p` and every other vertex `q`, find the subsectors whose closed wedge at `p` contains `q`
//! (one, or two when `q` is on a shared boundary ray), and keep in each the best candidate: greatest slope
//! `(z_q − z_p)/(t_q − t_p)`, then smaller `t_q`, then smaller index ([`crate::candidate`]). A member with
//! `t_q ≤ t_p` has no slope and is not a candidate; for valid TINs this never happens (see [`crate::sector`]).
//!
//! The oracle shares only the predicates with the sweep: wedge membership ([`Wedge::contains_keyed`]), the
//! projection ([`Wedge::project`]) and the candidate order. An `atan2` estimate of the direction only picks which
//! three subsectors to test; membership itself is decided exactly.

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use crate::NO_HORIZON;
use crate::candidate::{Candidate, CandidateId, keep_best};
use crate::predicates::LineKey;
use crate::sector::{SectorGeometry, Wedge};

/// The best candidate for `p` in one wedge by scanning every vertex, with precomputed keys and projections of
/// all vertices for that wedge (the sweep's fallback for degenerate input).
pub(crate) fn best_in_wedge(
    positions: &[DVec3],
    wedge: &Wedge,
    p: u32,
    ka: &[LineKey],
    kb: &[LineKey],
    t: &[f64],
) -> Option<Candidate> {
    let pu = p as usize;
    let pxy = positions[pu].truncate();
    let apex = DVec2::new(t[pu], positions[pu].z);
    let mut best = None;
    for (q, pos) in positions.iter().enumerate() {
        if q == pu || t[q] <= apex.x {
            continue;
        }
        if wedge.contains_keyed(pxy, ka[pu], kb[pu], pos.truncate(), ka[q], kb[q]) {
            keep_best(&mut best, Candidate::vertex(t[q], pos.z, q as u32), apex);
        }
    }
    best
}

/// Horizon vertices of every vertex in every subsector, subsector-major (`[j * n + v]`), by brute force.
pub(crate) fn vertex_horizons(positions: &[DVec3], origin: DVec2, geometry: &SectorGeometry) -> Vec<u32> {
    let n = positions.len();
    let total = geometry.total();
    let wedges: Vec<Wedge> = (0..total).map(|j| geometry.wedge(j)).collect();
    let per_vertex: Vec<Vec<u32>> = (0..n)
        .into_par_iter()
        .map(|p| {
            let pxy = positions[p].truncate();
            let zp = positions[p].z;
            let apexes: Vec<DVec2> = wedges.iter().map(|w| DVec2::new(w.project(origin, pxy), zp)).collect();
            let mut best: Vec<Option<Candidate>> = vec![None; total];
            for (q, pos) in positions.iter().enumerate() {
                if q == p {
                    continue;
                }
                let qxy = pos.truncate();
                for &j in geometry.subsectors_containing(pxy, qxy).as_slice() {
                    let j = j as usize;
                    let tq = wedges[j].project(origin, qxy);
                    if tq > apexes[j].x {
                        keep_best(&mut best[j], Candidate::vertex(tq, pos.z, q as u32), apexes[j]);
                    }
                }
            }
            best.iter()
                .map(|b| match b {
                    Some(Candidate {
                        id: CandidateId::Vertex(q),
                        ..
                    }) => *q,
                    _ => NO_HORIZON,
                })
                .collect()
        })
        .collect();
    let mut out = vec![NO_HORIZON; n * total];
    for (p, row) in per_vertex.iter().enumerate() {
        for (j, &h) in row.iter().enumerate() {
            out[j * n + p] = h;
        }
    }
    out
}
