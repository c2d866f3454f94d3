//! Horizon candidates and the total order that picks the horizon among them (the `sector` module).
//!
//! Seen from the apex `p̂ = (t_p, z_p)`, a candidate `q̂ = (t_q, z_q)` with `t_q > t_p` is better than another when
//! its slope `(z_q − z_p)/(t_q − t_p)` is greater; on equal slopes the smaller `t_q` (smaller `t_q − t_p`) wins,
//! then the smaller vertex index. Edge points of the undersampling fix rank after every vertex on a full tie, and
//! among themselves by their edge's endpoints. Slopes are compared exactly ([`crate::predicates::cmp_slope`]).

use std::cmp::Ordering;

use glam::DVec2;

use crate::predicates::cmp_slope;

/// Who a candidate is: a vertex, or the crossing point of an edge (its endpoints, smaller first).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum CandidateId {
    /// A TIN vertex.
    Vertex(u32),
    /// A point on the edge between two vertices (smaller index first).
    Edge(u32, u32),
}

/// A candidate's projected point `(t, z)` and identity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Candidate {
    /// `(t, z)` in the subsector's projection plane.
    pub point: DVec2,
    /// Identity for tie-breaking.
    pub id: CandidateId,
}

impl Candidate {
    /// A vertex candidate.
    #[inline]
    pub fn vertex(t: f64, z: f64, index: u32) -> Candidate {
        Candidate {
            point: DVec2::new(t, z),
            id: CandidateId::Vertex(index),
        }
    }

    /// Compares two candidates seen from `apex`: `Greater` when `self` is the better horizon.
    /// Both must lie strictly right of the apex (`t > t_p`).
    #[inline]
    pub fn rank(&self, other: &Candidate, apex: DVec2) -> Ordering {
        // Numeric comparison of t (−0.0 equals 0.0, as in the hulls), never NaN.
        cmp_slope(apex, self.point, other.point)
            .then_with(|| other.point.x.partial_cmp(&self.point.x).unwrap_or(Ordering::Equal))
            .then_with(|| other.id.cmp(&self.id))
    }
}

/// Keeps the better of `best` and `c` (seen from `apex`).
#[inline]
pub(crate) fn keep_best(best: &mut Option<Candidate>, c: Candidate, apex: DVec2) {
    match best {
        Some(b) if b.rank(&c, apex).is_ge() => {}
        _ => *best = Some(c),
    }
}
