//! The conservative 1-D horizon around a camera (Lloyd & Egbert 2002, §4.3; Downs, Möller & Séquin 2001), on four
//! vertical image planes, and its proof.
//!
//! ## Geometry
//!
//! Seen from the camera `c`, a point `p` has the offset `d = p − c`. The plane x,y around `c` is cut into four
//! closed 90° wedges, the *faces* `k = 0..4`, centred on +x, +y, −x and −y. In face `k` a point has a *forward*
//! coordinate `f` and a *lateral* coordinate `l` (face 0: `f = dx, l = dy`; face 1: `f = dy, l = −dx`; face 2:
//! `f = −dx, l = −dy`; face 3: `f = −dy, l = dx`), and, where `f > 0`, the image coordinates `u = l / f` (the face
//! covers `u ∈ [−1, 1]`) and `v = dz / f`. This is a perspective projection onto the plane `f = 1`, so
//!
//! - (P1) a 3-D segment or triangle whose points all have `f > 0` projects to the segment or triangle spanned by its
//!   projected vertices (perspective maps lines to lines);
//! - (P2) along one vertical half-plane from `c` (fixed `u`), `v = s / cos φ` with `s = dz / |d.xy|` the elevation
//!   slope and `φ` the fixed angle between the half-plane and the face axis, so comparing `v` at equal `u` is
//!   comparing slopes `s`.
//!
//! Each face has `w` columns (a power of two); column `j` covers `u ∈ [a_j, a_{j+1}]` with `a_j = −1 + 2j / w`,
//! computed exactly. The buffer holds one value `H` per column.
//!
//! ## What the buffer promises
//!
//! **Invariant.** After occluders `O_1 … O_m` (pieces of terrain, or of surfaces lying on or below the terrain, each
//! lowered by a height margin `μ`) were written, for every column `j` and every `u` in it there is a point `q` of
//! some `O_i` on the vertical half-plane `u` with `v(q) ≥ H_j`.
//!
//! **Theorem.** Let every point of the occluders written so far be at a horizontal distance from `c` strictly below
//! `D`, and let `N` be a set of terrain points at horizontal distances `≥ D`. If for every column `j` that `N`
//! touches, every point `p` of `N` in column `j` has `v(p) < H_j`, then every segment `pc` passes strictly below the
//! terrain (by more than `μ`): `N` is hidden.
//!
//! *Proof.* Take `p` in `N` at `u`, column `j`. By the invariant there is `q` on the same half-plane with
//! `v(q) ≥ H_j > v(p)`; by (P2), `s(q) > s(p)`, and `|q − c| < D ≤ |p − c|` (horizontal), so `q` lies between `c` and
//! `p` in x,y. The segment `pc` at `q`'s distance `ρ_q` is at height `c.z + s(p) ρ_q < c.z + s(q) ρ_q = q.z`, and `q.z`
//! is at least `μ` below the terrain there. ∎
//!
//! ## Why the invariant holds: writing an occluder
//!
//! An occluder is a triangle of the TIN with its three vertices lowered by `μ` (a parallel copy `μ` below the
//! terrain; every point of it is `μ` below the terrain at its x,y). It is written into face `k` only when all three
//! vertices have `f > 0`; by (P1) its image is the triangle of the projected vertices. For a fixed `u` inside the
//! image's span `[u_A, u_C]`, the image's vertical section has the top value `top(u)`, the larger value at `u` of
//! the two image edges that span `u` (the long edge `AC` and `AB` or `BC`); it is a point of the occluder. `top` is
//! concave on `[u_A, u_C]` (the upper boundary of a triangle), so its minimum over an interval is at one of the
//! interval's ends.
//!
//! A TIN edge lowered by `μ` is an occluder too (the terrain along an edge is exactly the segment between its end
//! vertices): a degenerate triangle `A C` whose image is the segment of its projected ends, with `top` that segment
//! (linear, so concave) and no middle vertex (`Horizon::write_segment`). Everything below holds for it unchanged.
//!
//! A *chain* of lowered TIN edges is an occluder too, taken as a whole (`Horizon::write_flat`): a set `C` of edges
//! that is connected (as a graph over their end vertices) and whose vertices all have `f > 0` in face `k`. Every point
//! of `C` then has `f > 0` (the half-space is convex), `u` is continuous on `C`, and `C` is connected, so the `u` of
//! its points fill the interval `[u_min, u_max]` spanned by its vertices; and every point of an edge has, by (P1), a
//! `v` at least the lower of its two ends'. Hence every `u` in `[u_min, u_max]` has a point `q` of `C` on its
//! half-plane with `v(q) ≥ b`, `b` the least lowered `v` of `C`'s vertices: the chain is written as the constant
//! `top(u) = b` over `[u_min, u_max]` (a segment of slope 0 from the vertex at `u_min` to the vertex at `u_max`, which
//! also names the end vertices of its partial covers). Edge by edge, a chain crossing a column in several edges shorter
//! than the column covers it nowhere (only its first and last edge reach a column boundary, and their covers end at
//! different vertices); as a whole it covers it at `b`.
//!
//! - *Full columns*: for a column with `[a_j, a_{j+1}] ⊆ [u_A, u_C]`, `H_j ← max(H_j, min(top(a_j), top(a_{j+1})))`.
//! - *Partial columns*: the column containing `u_A` is covered by the occluder on `[u_A, a_{j+1}]` with the lower
//!   bound `min(top(u_A), top(a_{j+1}))`, and the column containing `u_C` on `[a_j, u_C]`. Such a right-anchored
//!   cover `[x, a_{j+1}]` and a left-anchored cover `[a_j, y]` with `y ≥ x` (from any occluders written so far)
//!   together cover the whole column, so `H_j ← max(H_j, min(bound₁, bound₂))` keeps the invariant. Each column
//!   keeps two candidates per side (the highest bound, and the widest cover). `y ≥ x` is known when both covers end
//!   at the same point (their `u` are then one value computed from the same offset) or when `y` exceeds `x` by more
//!   than their rounding; the point is told by its id (`PointId`), a mesh vertex or a point of the cell-edge
//!   occluders' grid, in disjoint ranges: equal numbers of the two kinds name different points.
//!
//! ## Testing an occludee
//!
//! A triangle of the TIN (raised by `μ`, which only adds points above the terrain) projected into face `k` when its
//! three vertices have `f > 0`: it touches the columns that meet `[u_A, u_C]` and its largest `v` in column `j` is the
//! largest of `top` at the two ends of `[max(a_j, u_A), min(a_{j+1}, u_C)]` and at the middle vertex's `u` when
//! inside (the only corner of the concave `top`). A triangle that touches a face in which it cannot be projected
//! is not hidden.
//!
//! *Vertex bound.* Every point of the image is a convex combination of the projected vertices (P1), so its `u` lies in
//! `[min u, max u]` of the vertices and its `v` is at most their largest `v`. Hence the triangle is hidden in face `k`
//! if that largest `v` is below `H_j` in every column `j` meeting `[min u, max u]`; this is tried first (no division),
//! and when the vertices lie in one column it is all that `top` could tell, so the triangle is then left visible. For
//! a set of triangles at once (a patch, `Horizon::vertices_hidden`) take the range and the maximum over all their
//! vertices: if the union of the vertices' wedges is one face or two adjacent ones and every vertex has `f > 0` in
//! each of them, every triangle of the set meets the conditions above with its own (smaller) range and maximum, so
//! the set is hidden when the bound over all vertices is below the horizon in every column of each face. A vertex
//! with a NaN `u` or `v` makes the answer "not hidden".
//!
//! A disk of radius `r` around `m` (x,y) with every point at most at height `z_max` (a node's bounding cylinder) whose
//! distance `δ = |m − c|` exceeds `r`: in face `k`, its points inside the face's wedge have `f ≥ f_lo =
//! max(m_f − r, (δ − r)/√2)` (inside a 90° wedge `f ≥ |d.xy| / √2`) and `f ≤ f_hi = min(m_f + r, δ + r)`, so their
//! `v ≤ (z_max − c.z) / f_lo` when that numerator is `≥ 0`, else `≤ (z_max − c.z) / f_hi`; the columns touched are
//! those between the tangent directions `u± = (m_f m_l ± r √(m_f² + m_l² − r²)) / (m_f² − r²)` when `m_f > r`, else
//! the whole face if the disk meets the wedge.
//!
//! ## Rounding
//!
//! All arithmetic is f64 on offsets `p − c`, each one correctly rounded subtraction of world coordinates (relative
//! error `ε = 2⁻⁵³`). Every derived quantity is moved in the safe direction by more than its rounding error:
//!
//! - heights: the margin `μ` (chosen by the caller as `1e-7 (1 + scene size + |camera|)` metres, over 100 times the
//!   ground truth's own tolerance of `1e-9 (1 + distance + |z|)`, so a sight line that we call blocked is blocked for
//!   the exact checker too) is subtracted from occluder and added to occludee heights before dividing;
//! - values `v = (dz ∓ μ) · (1 / f)` and `u = l · (1 / f)`: one subtraction, one division and one product, relative
//!   error below `4ε`; `v` is moved by `REL = 1e-12` relative (down for occluders, up for occludees);
//! - a line's value between its end points `P, Q`, `P.v + (u − P.u)·κ` with `κ = (Q.v − P.v)/(Q.u − P.u)`: its error,
//!   from the operands' errors and its own four operations, is below `8ε (|P.v| + |Q.v| + |κ| (|P.u| + |Q.u| + 2))`
//!   for `u` within `[−1, 1]` and the edge; it is moved by `REL` times that sum;
//! - column indices: `u` values carry a relative error below `3ε`; full and partial covers are shrunk and occludee
//!   spans (of a triangle, or of a set of vertices for the vertex bound) widened by `REL (1 + |u|)` before they are
//!   turned into columns; column boundaries `a_j` are exact dyadic numbers; a span's ends are turned into column
//!   indices by a floor or ceiling that saturates (a vertex almost beside the camera, `f` near 0, has `|u|` up to
//!   `1e300`: a larger `|u|` or `|v|` leaves that face out of the vertex's, see below) and then clamped to the
//!   face, so a span always covers every column its `u` interval meets; the partial column left of a cover's first full
//!   column is found by a saturating subtraction too (it is then outside the face, never wrapped into it), so no index
//!   arithmetic can overflow;
//! - the vertex bound compares the vertices' raised values `hi` themselves (each above the exact `v` of the raised
//!   vertex, see above) with `H_j`: no further arithmetic;
//! - values beyond f64: a vertex gets face `k` only when its `|u|`, `|lo|` and `|hi|` there are at most `1e300`
//!   (`f` subnormal beside a large `l` or `dz` would overflow them); then differences of `u` and `v` stay finite,
//!   so no edge value is NaN. An edge whose slope or margin is not finite makes its triangle or segment unusable
//!   (neither written nor called hidden), and an occludee's bound is NaN, hence "not hidden", when any of its terms
//!   is (`f64::max` alone would drop the NaN term and keep a bound of the other edge only);
//! - disks: `f_lo` is decreased and `f_hi` increased by `REL` relative; the tangent values `u±` are computed from a
//!   square root and a division, each correctly rounded, and moved outward by `1e-9 (1 + |u|)` (also covering the
//!   cancellation in `m_f² − r²`, which is why a disk with `m_f < (1 + 1e-6) r` takes the whole face).

// Comparisons are written so that a NaN anywhere answers "not hidden" (`!(a < b)`), on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

/// Relative margin applied to every rounded quantity (see the module documentation).
pub(crate) const REL: f64 = 1e-12;

/// Number of faces (90° wedges) around the camera.
pub const FACES: usize = 4;

/// Forward and lateral coordinates of the offset `(dx, dy)` in face `k` (exact: only negations).
#[inline(always)]
pub(crate) fn face_coords(k: usize, dx: f64, dy: f64) -> (f64, f64) {
    match k {
        0 => (dx, dy),
        1 => (dy, -dx),
        2 => (-dx, -dy),
        _ => (-dy, dx),
    }
}

/// A vertex projected into one face: `u`, and `v` lowered (`lo`, for occluders) and raised (`hi`, for occludees) by
/// the height margin and the rounding margin.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Proj {
    pub u: f64,
    pub lo: f64,
    pub hi: f64,
}

/// A vertex projected into every face where its forward coordinate is positive (`mask` bit `k`), with the point it
/// stands for (partial covers that end and start at the same point meet exactly).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Projected {
    pub mask: u8,
    /// [`wedge_of`] this vertex.
    pub wedge: u8,
    pub id: PointId,
    pub face: [Proj; FACES],
}

/// What writing the triangles or edges over a set of projected vertices can reach, per face: the columns their `u`
/// span (`[1, 0]` for none) and their highest lowered `v`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Reach {
    columns: [[u32; 2]; FACES],
    v: [f64; FACES],
}

/// The point of the x,y plane that a projected vertex stands for, by which two partial covers are known to meet
/// exactly: a mesh vertex, or a point of the cell-edge occluders' grid ([`crate::lloyd_egbert`]: a grid corner or the
/// end of a piece), in two disjoint ranges of ids. Equal ids name one point, so the two `u` are one computed value;
/// a grid point never shares an id with a mesh vertex, even where their numbers are equal (the safe culler writes
/// both kinds into one horizon once its work budget is spent).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct PointId(u64);

impl PointId {
    /// No point: a cover that ends here meets another one only by the rounding margin.
    pub(crate) const NONE: PointId = PointId(u64::MAX);

    /// Mesh vertex `v`.
    #[inline(always)]
    pub(crate) fn vertex(v: u32) -> PointId {
        PointId(u64::from(v))
    }

    /// Point `g` of the cell-edge occluders' grid, or [`PointId::NONE`] for [`NO_GRID_POINT`].
    #[inline(always)]
    pub(crate) fn grid(g: u32) -> PointId {
        if g == NO_GRID_POINT {
            PointId::NONE
        } else {
            PointId(1 << 32 | u64::from(g))
        }
    }
}

impl Default for PointId {
    fn default() -> PointId {
        PointId::NONE
    }
}

/// A segment end of the cell-edge occluders that is no grid point ([`PointId::grid`] makes it [`PointId::NONE`]).
pub(crate) const NO_GRID_POINT: u32 = u32::MAX;

/// What a culler's height margin `μ` depends on, computed from the mesh's positions (not from a file's origin
/// field, which a file may set anywhere): the lowest and highest corners of the box of the vertices, the extent `e`
/// (sum of the box's sides) and the largest `|z|` (`h`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Scale {
    /// Lowest corner of the vertices' box (`+∞` for no vertex).
    pub lo: [f64; 3],
    /// Highest corner of the vertices' box (`−∞` for no vertex).
    pub hi: [f64; 3],
    extent: f64,
    zabs: f64,
}

impl Scale {
    /// The scale of `positions`.
    pub(crate) fn of(positions: &[[f64; 3]]) -> Scale {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let (extent, zabs) = if positions.is_empty() {
            (0.0, 0.0)
        } else {
            (
                (hi[0] - lo[0]) + (hi[1] - lo[1]) + (hi[2] - lo[2]),
                lo[2].abs().max(hi[2].abs()),
            )
        };
        Scale { lo, hi, extent, zabs }
    }

    /// The height margin `μ = 1e-7 (1 + e + |c − o|₁ + |c.z| + h)` metres for a camera at `eye`, `o` the centre of
    /// the vertices' box in x,y: every vertex lies within `e / 2` of `o` (1-norm), so `μ` exceeds
    /// `1e-7 (1 + |p − c| + |p.z|)` for every vertex `p`, over 100 times the exact checker's tolerance of
    /// `1e-9 (1 + distance + |z|)` (`truth::walk`).
    pub(crate) fn margin(&self, eye: [f64; 3]) -> f64 {
        // No vertex: no box (and nothing to cull).
        let o = if self.lo[0].is_finite() {
            [0.5 * (self.lo[0] + self.hi[0]), 0.5 * (self.lo[1] + self.hi[1])]
        } else {
            [0.0; 2]
        };
        1e-7 * (1.0 + self.extent + (eye[0] - o[0]).abs() + (eye[1] - o[1]).abs() + eye[2].abs() + self.zabs)
    }
}

/// Largest `|u|` or `|v|` of a projection (see [`project`]).
const PROJ_MAX: f64 = 1e300;

/// Projects the offset `d = p − c` of the point `id` into every face where `f > 0`, with the height margin `mu`.
#[inline]
pub(crate) fn project(d: [f64; 3], mu: f64, id: PointId) -> Projected {
    let mut out = Projected {
        id,
        ..Projected::default()
    };
    let (dz_lo, dz_hi) = (d[2] - mu, d[2] + mu);
    for k in 0..FACES {
        let (f, l) = face_coords(k, d[0], d[1]);
        if f > 0.0 {
            // One division and two products: relative error below 3ε each.
            let inv = 1.0 / f;
            let lo = dz_lo * inv;
            let hi = dz_hi * inv;
            let p = Proj {
                u: l * inv,
                lo: lo - REL * lo.abs(),
                hi: hi + REL * hi.abs(),
            };
            // A `u` or `v` beyond `PROJ_MAX` (`f` tiny beside `l` or `dz`: coordinates near 0 with subnormal
            // differences) is no projection: the face is not one of this vertex's (its triangles are then neither
            // written nor hidden there). Below it, no difference of two values overflows and no NaN can arise.
            if p.u.abs() <= PROJ_MAX && p.lo.abs() <= PROJ_MAX && p.hi.abs() <= PROJ_MAX {
                out.mask |= 1 << k;
                out.face[k] = p;
            }
        }
    }
    out.wedge = wedge_of(&out);
    out
}

/// One image edge `P → Q` with `P.u < Q.u`: its value at `u` and the rounding margin of that value.
#[derive(Clone, Copy, Debug)]
struct Edge {
    u0: f64,
    v0: f64,
    slope: f64,
    margin: f64,
}

/// An edge [`Edge::new`] cannot bound: a value not finite, or a slope or margin beyond f64. The triangle or segment
/// it belongs to is then unusable (not written as an occluder, not called hidden): standing in for it with the other
/// short edge, as for an edge without width, would bound nothing.
#[derive(Clone, Copy, Debug)]
struct Unusable;

impl Edge {
    /// The edge `P Q`, or `None` when it has no width (`P.u = Q.u`: the other short edge stands in for it).
    #[inline(always)]
    fn new(p: (f64, f64), q: (f64, f64)) -> Result<Option<Edge>, Unusable> {
        let (p, q) = if p.0 <= q.0 { (p, q) } else { (q, p) };
        if !(p.0.is_finite() && q.0.is_finite() && p.1.is_finite() && q.1.is_finite()) {
            return Err(Unusable);
        }
        if q.0 <= p.0 {
            return Ok(None);
        }
        let slope = (q.1 - p.1) / (q.0 - p.0);
        let margin = REL * (p.1.abs() + q.1.abs() + slope.abs() * (p.0.abs() + q.0.abs() + 2.0));
        if !(slope.is_finite() && margin.is_finite()) {
            return Err(Unusable);
        }
        Ok(Some(Edge {
            u0: p.0,
            v0: p.1,
            slope,
            margin,
        }))
    }

    #[inline(always)]
    fn at(&self, u: f64) -> f64 {
        self.v0 + (u - self.u0) * self.slope
    }
}

/// An edge that is never there: its value is `−∞` everywhere (for a triangle whose short edges both lack width).
const NO_EDGE: Edge = Edge {
    u0: 0.0,
    v0: f64::NEG_INFINITY,
    slope: 0.0,
    margin: 0.0,
};

/// A projected triangle's upper boundary `top(u)` over `[ua, uc]`, with its middle vertex's `u`. With the vertices
/// sorted by `u` as `A, B, C`, the vertical section at `u` lies between the long edge `AC` and the edge `AB`
/// (`u ≤ u_B`) or `BC` (`u ≥ u_B`), so `top(u)` is the larger of those two edges' values. Where one short edge has no
/// width the other one stands for both (`left` and `right` below); where neither has, only `AC` counts ([`NO_EDGE`]).
#[derive(Clone, Copy, Debug)]
struct Top {
    ac: Edge,
    /// The short edge used up to `u_B` (`AB`, or `BC` where `AB` has no width).
    left: Edge,
    /// The short edge used beyond `u_B` (`BC`, or `AB` where `BC` has no width).
    right: Edge,
    ua: f64,
    ub: f64,
    uc: f64,
    /// Points at `ua` and `uc`.
    ida: PointId,
    idc: PointId,
    /// A segment: `top` is `AC` alone.
    segment: bool,
}

impl Top {
    #[inline(always)]
    fn new(p: [(f64, f64, PointId); 3]) -> Option<Top> {
        // Sorting network on `u` (a NaN ends up anywhere; `Edge::new` refuses every edge with a value not finite).
        let [mut a, mut b, mut c] = p;
        if b.0 < a.0 {
            std::mem::swap(&mut a, &mut b);
        }
        if c.0 < b.0 {
            std::mem::swap(&mut b, &mut c);
        }
        if b.0 < a.0 {
            std::mem::swap(&mut a, &mut b);
        }
        let (a2, b2, c2) = ((a.0, a.1), (b.0, b.1), (c.0, c.1));
        let ac = Edge::new(a2, c2).ok()??;
        let ab = Edge::new(a2, b2).ok()?;
        let bc = Edge::new(b2, c2).ok()?;
        Some(Top {
            ac,
            left: ab.or(bc).unwrap_or(NO_EDGE),
            right: bc.or(ab).unwrap_or(NO_EDGE),
            ua: a.0,
            ub: b.0,
            uc: c.0,
            ida: a.2,
            idc: c.2,
            segment: false,
        })
    }

    /// A lowered segment `P Q` as a degenerate triangle: `top` is the segment itself (`AC`), with no short edges.
    #[inline(always)]
    fn segment(p: (f64, f64, PointId), q: (f64, f64, PointId)) -> Option<Top> {
        let (a, c) = if q.0 < p.0 { (q, p) } else { (p, q) };
        let ac = Edge::new((a.0, a.1), (c.0, c.1)).ok()??;
        Some(Top {
            ac,
            left: NO_EDGE,
            right: NO_EDGE,
            ua: a.0,
            ub: c.0,
            uc: c.0,
            ida: a.2,
            idc: c.2,
            segment: true,
        })
    }

    /// The short edge spanning `u` (`AB` up to `u_B`, then `BC`; the other one where one of them has no width).
    #[inline(always)]
    fn piece(&self, u: f64) -> &Edge {
        if u <= self.ub { &self.left } else { &self.right }
    }

    /// A lower bound of `top(u)` for `u` in `[ua, uc]` (occluders).
    #[inline(always)]
    fn low(&self, u: f64) -> f64 {
        let e = self.piece(u);
        (self.ac.at(u) - self.ac.margin).max(e.at(u) - e.margin)
    }

    /// An upper bound of `top(u)` for `u` in `[ua, uc]` (occludees); NaN when either edge's value is (`f64::max`
    /// would drop it, and the other edge alone bounds nothing).
    #[inline(always)]
    fn high(&self, u: f64) -> f64 {
        let e = self.piece(u);
        max_or_nan(self.ac.at(u) + self.ac.margin, e.at(u) + e.margin)
    }
}

/// The larger of `a` and `b`, or NaN when either is NaN (for upper bounds, where a NaN must answer "not hidden").
#[inline(always)]
fn max_or_nan(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() { f64::NAN } else { a.max(b) }
}

/// Partial covers of one column: left-anchored (`[a_j, reach]`) and right-anchored (`[start, a_{j+1}]`), two
/// candidates each (the highest bound and the widest cover), each with the point at its inner end.
#[derive(Clone, Copy, Debug)]
struct Partial {
    /// `(bound, reach, vertex)`: highest bound, widest reach.
    left: [(f64, f64, PointId); 2],
    /// `(bound, start, vertex)`: highest bound, widest (smallest start).
    right: [(f64, f64, PointId); 2],
}

const NO_PARTIAL: Partial = Partial {
    left: [(f64::NEG_INFINITY, f64::NEG_INFINITY, PointId::NONE); 2],
    right: [(f64::NEG_INFINITY, f64::INFINITY, PointId::NONE); 2],
};

/// The horizon buffer: `4 w` column values and the partial covers behind them.
#[derive(Clone, Debug)]
pub struct Horizon {
    w: usize,
    half_w: f64,
    step: f64,
    h: Vec<f64>,
    partial: Vec<Partial>,
    /// Per column, an upper bound of what the occluders not yet written could raise it to (`max(H, P)` is what
    /// flushing them could achieve at best; see [`crate::safe`]).
    potential: Vec<f64>,
}

impl Horizon {
    /// A buffer of `columns_per_face` columns in each of the four faces (a power of two, at least 2).
    pub fn new(columns_per_face: usize) -> Horizon {
        let w = columns_per_face.next_power_of_two().max(2);
        Horizon {
            w,
            half_w: w as f64 * 0.5,
            step: 2.0 / w as f64,
            h: vec![f64::NEG_INFINITY; FACES * w],
            partial: vec![NO_PARTIAL; FACES * w],
            potential: vec![f64::NEG_INFINITY; FACES * w],
        }
    }

    /// Columns per face.
    pub fn columns_per_face(&self) -> usize {
        self.w
    }

    /// Column values (`−∞` where nothing covers the column yet), face after face.
    pub fn values(&self) -> &[f64] {
        &self.h
    }

    /// The horizon as directions from the camera, for plots and overlays: per column, its centre's azimuth (degrees
    /// counter-clockwise from +x, in `[0, 360)`) and the elevation angle of its value (degrees; `None` where nothing
    /// covers the column), sorted by azimuth.
    pub fn profile(&self) -> Vec<(f64, Option<f64>)> {
        let mut out: Vec<(f64, Option<f64>)> = (0..FACES * self.w)
            .map(|c| {
                let (k, j) = (c / self.w, c % self.w);
                // Column j of face k spans u in [-1 + j step, -1 + (j + 1) step]; u = tan(azimuth - 90° k) and the
                // value is height over forward distance, so the elevation is atan(v / sqrt(1 + u²)).
                let u = -1.0 + (j as f64 + 0.5) * self.step;
                let azimuth = (90.0 * k as f64 + u.atan().to_degrees()).rem_euclid(360.0);
                let v = self.h[c];
                (azimuth, v.is_finite().then(|| (v / u.hypot(1.0)).atan().to_degrees()))
            })
            .collect();
        out.sort_by(|a, b| a.0.total_cmp(&b.0));
        out
    }

    /// Forgets every occluder.
    pub fn clear(&mut self) {
        self.h.fill(f64::NEG_INFINITY);
        self.partial.fill(NO_PARTIAL);
        self.potential.fill(f64::NEG_INFINITY);
    }

    /// The value an occludee must stay below in column `col`: `H`, or `max(H, P)` when asking whether writing the
    /// waiting occluders could hide it.
    #[inline(always)]
    fn bar(&self, col: usize, with_potential: bool) -> f64 {
        if with_potential {
            self.h[col].max(self.potential[col])
        } else {
            self.h[col]
        }
    }

    /// Whether `v` is strictly below the bar ([`Horizon::bar`]) of every column `j0..=j1` of face `k`.
    #[inline(always)]
    fn below_all(&self, k: usize, j0: usize, j1: usize, v: f64, with_potential: bool) -> bool {
        let base = k * self.w;
        if with_potential {
            (base + j0..=base + j1).all(|c| v < self.h[c].max(self.potential[c]))
        } else {
            self.h[base + j0..=base + j1].iter().all(|&h| v < h)
        }
    }

    /// Raises the potential of the columns that the projected vertices `verts` span in each face to their highest
    /// lowered `v` there: no triangle or edge over these vertices can write more (its writes are lower bounds of its
    /// top, whose highest point is a vertex). Returns per face the columns raised and the value raised to.
    pub(crate) fn raise_potential_reach(&mut self, verts: &[Projected]) -> Reach {
        let mut u_min = [f64::INFINITY; FACES];
        let mut u_max = [f64::NEG_INFINITY; FACES];
        let mut v_max = [f64::NEG_INFINITY; FACES];
        for p in verts {
            for k in 0..FACES {
                if p.mask & (1 << k) != 0 {
                    let q = p.face[k];
                    u_min[k] = u_min[k].min(q.u);
                    u_max[k] = u_max[k].max(q.u);
                    v_max[k] = v_max[k].max(q.lo);
                }
            }
        }
        let mut reach = Reach {
            columns: [[1, 0]; FACES],
            v: v_max,
        };
        for k in 0..FACES {
            let Some([j0, j1]) = self.columns(u_min[k], u_max[k]) else {
                continue;
            };
            reach.columns[k] = [j0 as u32, j1 as u32];
            let base = k * self.w;
            for p in &mut self.potential[base + j0..=base + j1] {
                *p = p.max(v_max[k]);
            }
        }
        reach
    }

    /// Whether writing triangles or edges over the vertices that gave `reach` could raise a column: not when their
    /// highest lowered vertex is at most `H` in every column they span, in every face (a write is a lower bound of a
    /// `top`, whose highest point is a vertex; and a partial cover pairs with another one to the lower of the two).
    pub(crate) fn can_raise(&self, reach: &Reach) -> bool {
        (0..FACES).any(|k| {
            let [j0, j1] = reach.columns[k];
            let base = k * self.w;
            j0 <= j1
                && !self.h[base + j0 as usize..=base + j1 as usize]
                    .iter()
                    .all(|&h| reach.v[k] <= h)
        })
    }

    /// The columns of one face that `[u_min, u_max]` meets (none when it misses the face or is empty).
    #[inline(always)]
    fn columns(&self, u_min: f64, u_max: f64) -> Option<[usize; 2]> {
        if !(u_min <= u_max) || u_max <= -1.0 || u_min >= 1.0 {
            return None;
        }
        let last = self.w as isize - 1;
        let j0 = floor(self.column_of(u_min)).clamp(0, last) as usize;
        let j1 = floor(self.column_of(u_max)).clamp(0, last) as usize;
        Some([j0, j1])
    }

    /// Left boundary `a_j` of column `j` (exact).
    #[inline(always)]
    fn boundary(&self, j: usize) -> f64 {
        -1.0 + j as f64 * self.step
    }

    /// The column containing `u` (clamped to the face), as a float index.
    #[inline(always)]
    fn column_of(&self, u: f64) -> f64 {
        (u + 1.0) * self.half_w
    }

    /// Writes the lowered triangle `tri` (three projected vertices) into every face where it can be projected.
    #[cfg(test)] // the cullers write segments (TIN edges); the tests write whole triangles
    pub(crate) fn write_triangle(&mut self, tri: [&Projected; 3]) {
        let faces = tri[0].mask & tri[1].mask & tri[2].mask;
        for k in 0..FACES {
            if faces & (1 << k) == 0 {
                continue;
            }
            let p = [tri[0].face[k], tri[1].face[k], tri[2].face[k]];
            let (u_min, u_max) = (p[0].u.min(p[1].u).min(p[2].u), p[0].u.max(p[1].u).max(p[2].u));
            if u_max <= -1.0 || u_min >= 1.0 {
                continue;
            }
            // Inside one column a triangle covers none fully and adds no cover anchored at a column boundary; and
            // nothing is gained when its highest point (a vertex: `top` is concave) is not above the horizon in any
            // column it touches: it could raise neither a column nor a future pair of covers.
            let last = self.w as isize - 1;
            let j0 = floor(self.column_of(u_min)).clamp(0, last) as usize;
            let j1 = floor(self.column_of(u_max)).clamp(0, last) as usize;
            let v_max = p[0].lo.max(p[1].lo).max(p[2].lo);
            let base = k * self.w;
            if j0 == j1 || self.h[base + j0..=base + j1].iter().all(|&h| v_max <= h) {
                continue;
            }
            let Some(top) = Top::new([
                (p[0].u, p[0].lo, tri[0].id),
                (p[1].u, p[1].lo, tri[1].id),
                (p[2].u, p[2].lo, tri[2].id),
            ]) else {
                continue;
            };
            self.write_top(k, &top);
        }
    }

    /// Writes the lowered segment `seg` (two projected vertices: a TIN edge, which lies on the terrain) into every
    /// face where it can be projected.
    pub(crate) fn write_segment(&mut self, seg: [&Projected; 2]) {
        let faces = seg[0].mask & seg[1].mask;
        for k in 0..FACES {
            if faces & (1 << k) == 0 {
                continue;
            }
            let (p, q) = (seg[0].face[k], seg[1].face[k]);
            let Some([j0, j1]) = self.columns(p.u.min(q.u), p.u.max(q.u)) else {
                continue;
            };
            // As for triangles: inside one column, or nowhere above the horizon, a segment adds nothing.
            let v_max = p.lo.max(q.lo);
            let base = k * self.w;
            if j0 == j1 || self.h[base + j0..=base + j1].iter().all(|&h| v_max <= h) {
                continue;
            }
            let Some(top) = Top::segment((p.u, p.lo, seg[0].id), (q.u, q.lo, seg[1].id)) else {
                continue;
            };
            self.write_top(k, &top);
        }
    }

    /// Writes a flat cover into face `k`: every `u` of `[a.0, b.0]` has, on its vertical half-plane, a point of the
    /// occluders with lowered `v` at least `bound` (a connected set of lowered TIN edges whose vertices all lie in
    /// front of the camera in face `k`, spanning the `u` of its vertices from `a` to `b`, with `bound` the least
    /// lowered `v` of its vertices; see the module documentation). `a` and `b` (in either order) carry the mesh
    /// vertices at the ends.
    pub(crate) fn write_flat(&mut self, k: usize, a: (f64, PointId), b: (f64, PointId), bound: f64) {
        let (a, b) = if b.0 < a.0 { (b, a) } else { (a, b) };
        let Some([j0, j1]) = self.columns(a.0, b.0) else {
            return;
        };
        let base = k * self.w;
        if j0 == j1 || self.h[base + j0..=base + j1].iter().all(|&h| bound <= h) {
            return;
        }
        let Some(top) = Top::segment((a.0, bound, a.1), (b.0, bound, b.1)) else {
            return;
        };
        self.write_top(k, &top);
    }

    fn write_top(&mut self, k: usize, top: &Top) {
        let lo_u = top.ua + REL * (1.0 + top.ua.abs());
        let hi_u = top.uc - REL * (1.0 + top.uc.abs());
        if !(lo_u < hi_u) || hi_u <= -1.0 || lo_u >= 1.0 {
            return;
        }
        let w = self.w as isize;
        // Full columns: j with a_j ≥ lo_u and a_{j+1} ≤ hi_u.
        let first = ceil(self.column_of(lo_u));
        let end = floor(self.column_of(hi_u)); // one past the last full column
        let (first_c, end_c) = (first.clamp(0, w), end.clamp(0, w));
        let base = k * self.w;
        if first_c < end_c {
            if top.segment {
                // One line: its value at the boundaries, lowered by its margin.
                let (e, h) = (&top.ac, &mut self.h);
                let mut prev = e.at(-1.0 + first_c as f64 * self.step) - e.margin;
                for j in first_c..end_c {
                    let next = e.at(-1.0 + (j + 1) as f64 * self.step) - e.margin;
                    let slot = &mut h[base + j as usize];
                    *slot = slot.max(prev.min(next));
                    prev = next;
                }
            } else {
                let mut prev = top.low(self.boundary(first_c as usize));
                for j in first_c..end_c {
                    let next = top.low(self.boundary(j as usize + 1));
                    let slot = &mut self.h[base + j as usize];
                    *slot = slot.max(prev.min(next));
                    prev = next;
                }
            }
        }
        // Partial columns at both ends (only when the triangle does not fit inside one column).
        // `first` may have saturated to `isize::MIN` (a vertex almost beside the camera): the left partial column is
        // then outside the face, and must not wrap around to `isize::MAX`.
        let left_col = first.saturating_sub(1); // contains lo_u (unless lo_u is on a boundary, then a weaker cover)
        let right_col = end; // contains hi_u
        if left_col < right_col {
            // The covers run exactly from and to the end vertices (`ua`, `uc`); whether two covers meet is decided
            // in `combine`, exactly when they share the point ([`PointId`]), else with the rounding margin.
            if (0..w).contains(&left_col) {
                let b = self.boundary(left_col as usize + 1);
                let bound = top.low(top.ua).min(top.low(b));
                self.add_right_anchored(base + left_col as usize, (bound, top.ua, top.ida));
            }
            if (0..w).contains(&right_col) {
                let a = self.boundary(right_col as usize);
                let bound = top.low(a).min(top.low(top.uc));
                self.add_left_anchored(base + right_col as usize, (bound, top.uc, top.idc));
            }
        }
    }

    fn add_left_anchored(&mut self, col: usize, cover: (f64, f64, PointId)) {
        // A cover no higher than the column can raise it in no pair (a pair raises it to the lower of two bounds).
        if !(cover.0 > self.h[col]) {
            return;
        }
        let p = &mut self.partial[col];
        if cover.0 > p.left[0].0 {
            p.left[0] = cover;
        }
        if cover.1 > p.left[1].1 {
            p.left[1] = cover;
        }
        self.combine(col);
    }

    fn add_right_anchored(&mut self, col: usize, cover: (f64, f64, PointId)) {
        // A cover no higher than the column can raise it in no pair (a pair raises it to the lower of two bounds).
        if !(cover.0 > self.h[col]) {
            return;
        }
        let p = &mut self.partial[col];
        if cover.0 > p.right[0].0 {
            p.right[0] = cover;
        }
        if cover.1 < p.right[1].1 {
            p.right[1] = cover;
        }
        self.combine(col);
    }

    /// Raises column `col` to the best pair of partial covers that together cover it: a left-anchored cover reaching
    /// the point where a right-anchored one starts (the same [`PointId`], hence the same computed `u`), or reaching
    /// past its start by more than the rounding margin.
    fn combine(&mut self, col: usize) {
        let p = self.partial[col];
        let mut best = self.h[col];
        for l in p.left {
            for r in p.right {
                let meet = (l.2 == r.2 && l.2 != PointId::NONE)
                    || l.1 - REL * (1.0 + l.1.abs()) >= r.1 + REL * (1.0 + r.1.abs());
                if meet {
                    best = best.max(l.0.min(r.0));
                }
            }
        }
        self.h[col] = best;
    }

    /// Whether the raised triangle `tri` is strictly below the horizon in every column it touches. A triangle that
    /// touches a face in which it cannot be projected is not hidden.
    pub(crate) fn triangle_hidden(&self, tri: [&Projected; 3], with_potential: bool) -> bool {
        let faces = tri[0].mask & tri[1].mask & tri[2].mask;
        if faces == 0 {
            return false;
        }
        // The wedges the triangle touches: those of its vertices when they are one wedge or two adjacent ones (a
        // triangle that does not contain the camera spans less than 180° of azimuth, so it stays within them);
        // anything else is left visible.
        let touched = tri[0].wedge | tri[1].wedge | tri[2].wedge;
        if !matches!(
            touched,
            0b0001 | 0b0010 | 0b0100 | 0b1000 | 0b0011 | 0b0110 | 0b1100 | 0b1001
        ) {
            return false;
        }
        if touched & !faces != 0 {
            return false;
        }
        for k in 0..FACES {
            if touched & (1 << k) == 0 {
                continue;
            }
            let p = [tri[0].face[k], tri[1].face[k], tri[2].face[k]];
            // First the bound of the whole triangle by its highest vertex over its columns (every point of its image
            // is a convex combination of the projected vertices); inside one column that is all `top` could say.
            let (u_min, u_max) = (p[0].u.min(p[1].u).min(p[2].u), p[0].u.max(p[1].u).max(p[2].u));
            let v_max = p[0].hi.max(p[1].hi).max(p[2].hi);
            if p.iter().all(|q| !q.u.is_nan() && !q.hi.is_nan()) {
                let lo_u = u_min - REL * (1.0 + u_min.abs());
                let hi_u = u_max + REL * (1.0 + u_max.abs());
                if hi_u < -1.0 || lo_u > 1.0 {
                    continue;
                }
                let last = self.w as isize - 1;
                let j0 = floor(self.column_of(lo_u)).clamp(0, last) as usize;
                let j1 = floor(self.column_of(hi_u)).clamp(0, last) as usize;
                if self.below_all(k, j0, j1, v_max, with_potential) {
                    continue;
                }
                if j0 == j1 {
                    return false;
                }
            }
            let Some(top) = Top::new([
                (p[0].u, p[0].hi, PointId::NONE),
                (p[1].u, p[1].hi, PointId::NONE),
                (p[2].u, p[2].hi, PointId::NONE),
            ]) else {
                return false;
            };
            if !self.top_hidden(k, &top, with_potential) {
                return false;
            }
        }
        true
    }

    /// Whether one of the raised projected vertices `verts` is not below the horizon in its column: then a triangle
    /// over it is not hidden either (its test reads that column and bounds it by at least this value). A shortcut to
    /// "visible", which needs no proof.
    pub(crate) fn vertex_above(&self, verts: &[Projected], with_potential: bool) -> bool {
        let last = self.w as isize - 1;
        verts.iter().any(|v| {
            (0..FACES).any(|k| {
                let q = v.face[k];
                v.wedge & v.mask & (1 << k) != 0
                    && q.u.abs() <= 1.0
                    && !(q.hi
                        < self.bar(
                            k * self.w + floor(self.column_of(q.u)).clamp(0, last) as usize,
                            with_potential,
                        ))
            })
        })
    }

    /// Whether every triangle over the raised projected vertices `verts` is strictly below the horizon in every
    /// column it touches, judged from the vertices alone (their highest `v` over the span of their `u`, face by
    /// face). The triangles must not contain the camera's x,y. It answers "not hidden" more often than
    /// [`Horizon::triangle_hidden`] on each triangle, never "hidden" when one of those would not.
    pub(crate) fn vertices_hidden(&self, verts: &[Projected], with_potential: bool) -> bool {
        let (mut touched, mut faces) = (0u8, 0b1111u8);
        for v in verts {
            touched |= v.wedge;
            faces &= v.mask;
        }
        if verts.is_empty()
            || !matches!(
                touched,
                0b0001 | 0b0010 | 0b0100 | 0b1000 | 0b0011 | 0b0110 | 0b1100 | 0b1001
            )
            || touched & !faces != 0
        {
            return false;
        }
        for k in 0..FACES {
            if touched & (1 << k) == 0 {
                continue;
            }
            let (mut u_min, mut u_max, mut v_max) = (f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
            for v in verts {
                let q = v.face[k];
                if q.u.is_nan() || q.hi.is_nan() {
                    return false;
                }
                u_min = u_min.min(q.u);
                u_max = u_max.max(q.u);
                v_max = v_max.max(q.hi);
            }
            if !(u_min <= u_max && v_max > f64::NEG_INFINITY) {
                return false;
            }
            let lo_u = u_min - REL * (1.0 + u_min.abs());
            let hi_u = u_max + REL * (1.0 + u_max.abs());
            if hi_u < -1.0 || lo_u > 1.0 {
                continue;
            }
            let last = self.w as isize - 1;
            let j0 = floor(self.column_of(lo_u)).clamp(0, last) as usize;
            let j1 = floor(self.column_of(hi_u)).clamp(0, last) as usize;
            if !self.below_all(k, j0, j1, v_max, with_potential) {
                return false;
            }
        }
        true
    }

    fn top_hidden(&self, k: usize, top: &Top, with_potential: bool) -> bool {
        let lo_u = top.ua - REL * (1.0 + top.ua.abs());
        let hi_u = top.uc + REL * (1.0 + top.uc.abs());
        if hi_u < -1.0 || lo_u > 1.0 {
            return true;
        }
        let last = self.w as isize - 1;
        let j0 = floor(self.column_of(lo_u)).clamp(0, last) as usize;
        let j1 = floor(self.column_of(hi_u)).clamp(0, last) as usize;
        let base = k * self.w;
        for j in j0..=j1 {
            let h = self.bar(base + j, with_potential);
            if h == f64::NEG_INFINITY {
                return false;
            }
            let l = self.boundary(j).max(top.ua);
            let r = self.boundary(j + 1).min(top.uc);
            let mut m = max_or_nan(top.high(l), top.high(r));
            if l < top.ub && top.ub < r {
                m = max_or_nan(m, top.high(top.ub));
            }
            // Ends that fall just outside the computed span (inside the margin) are bounded by the end vertices.
            if l > r {
                m = max_or_nan(max_or_nan(top.high(top.ua), top.high(top.uc)), top.high(top.ub));
            }
            if !(m < h) {
                return false;
            }
        }
        true
    }

    /// Whether a disk (centre offset `m = centre − c` in x,y, radius `r`, `m` farther than `r`) whose points are all at
    /// most `dz_max` above the camera (already raised by the height margin) is strictly below the horizon in every
    /// column it touches.
    pub(crate) fn disk_hidden(&self, m: [f64; 2], r: f64, dz_max: f64, with_potential: bool) -> bool {
        self.disk_span(m, r, dz_max)
            .is_some_and(|span| self.span_hidden(&span, with_potential))
    }

    /// The columns a disk touches and the bound of its `v` there, face by face, for [`Horizon::span_hidden`]
    /// (arguments as for [`Horizon::disk_hidden`]); `None` when the disk cannot be judged hidden at all (it is not
    /// farther than its radius, or it reaches behind the camera in a face it meets). It depends on the buffer's
    /// column count only, so one span serves every test of the same disk.
    pub(crate) fn disk_span(&self, m: [f64; 2], r: f64, dz_max: f64) -> Option<DiskSpan> {
        let dist = (m[0] * m[0] + m[1] * m[1]).sqrt();
        // The offset m carries a rounding error below ε |m|: grow the disk by more.
        let r = r + 1e-15 * dist;
        if !(dist > r * (1.0 + 1e-6)) {
            return None;
        }
        let mut span = DiskSpan {
            faces: [(1, 0, 0.0); FACES],
        };
        for k in 0..FACES {
            let (mf, ml) = face_coords(k, m[0], m[1]);
            // Does the disk meet the wedge f ≥ |l|?
            if !disk_meets_wedge(mf, ml, r) {
                continue;
            }
            let f_lo = (mf - r).max((dist - r - 1e-15 * dist) * std::f64::consts::FRAC_1_SQRT_2) * (1.0 - REL);
            let f_hi = (mf + r).min(dist + r) * (1.0 + REL);
            if !(f_lo > 0.0) {
                return None;
            }
            let v = if dz_max >= 0.0 { dz_max / f_lo } else { dz_max / f_hi };
            let v = v + REL * v.abs();
            let (u_lo, u_hi) = if mf > r * (1.0 + 1e-6) {
                let den = mf * mf - r * r;
                let root = r * (mf * mf + ml * ml - r * r).max(0.0).sqrt();
                let a = (mf * ml - root) / den;
                let b = (mf * ml + root) / den;
                (a - 1e-9 * (1.0 + a.abs()), b + 1e-9 * (1.0 + b.abs()))
            } else {
                (-1.0, 1.0)
            };
            if u_hi < -1.0 || u_lo > 1.0 {
                continue;
            }
            let last = self.w as isize - 1;
            let j0 = floor(self.column_of(u_lo.max(-1.0))).clamp(0, last) as u32;
            let j1 = floor(self.column_of(u_hi.min(1.0))).clamp(0, last) as u32;
            span.faces[k] = (j0, j1, v);
        }
        Some(span)
    }

    /// Whether the disk of `span` is strictly below the horizon in every column it touches.
    #[inline]
    pub(crate) fn span_hidden(&self, span: &DiskSpan, with_potential: bool) -> bool {
        (0..FACES).all(|k| {
            let (j0, j1, v) = span.faces[k];
            j0 > j1 || self.below_all(k, j0 as usize, j1 as usize, v, with_potential)
        })
    }
}

/// What a disk touches of the horizon ([`Horizon::disk_span`]): per face, the columns `j0..=j1` (none when
/// `j0 > j1`) and the bound of its `v` there.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DiskSpan {
    faces: [(u32, u32, f64); FACES],
}

/// `⌊x⌋` for column arithmetic: an `x` beyond the range of `isize` saturates to its end (a vertex almost beside the
/// camera has `|u|` up to `1e300`, a disk's tangent more), a NaN gives 0; callers clamp.
#[inline(always)]
fn floor(x: f64) -> isize {
    let t = x as isize;
    if (t as f64) > x { t.saturating_sub(1) } else { t }
}

/// `⌈x⌉`, likewise.
#[inline(always)]
fn ceil(x: f64) -> isize {
    let t = x as isize;
    if (t as f64) < x { t.saturating_add(1) } else { t }
}

/// The wedges (as face bits) that may contain the projected vertex: every face where `|u| ≤ 1` up to the rounding
/// margin (two faces next to a diagonal). A vertex at the camera's x,y is in no face and claims all four.
#[inline]
fn wedge_of(p: &Projected) -> u8 {
    let mut bits = 0;
    for k in 0..FACES {
        if p.mask & (1 << k) != 0 && p.face[k].u.abs() <= 1.0 + 4.0 * REL {
            bits |= 1 << k;
        }
    }
    if bits == 0 { 0b1111 } else { bits }
}

/// Whether the disk at `(mf, ml)` (face coordinates) with radius `r` meets the wedge `f ≥ |l|` (conservatively:
/// may answer yes when it does not).
#[inline]
fn disk_meets_wedge(mf: f64, ml: f64, r: f64) -> bool {
    if mf >= ml.abs() {
        return true;
    }
    // Distance to the two boundary rays (1, ±1)/√2, widened slightly.
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let r = r * (1.0 + 1e-9) + 1e-12;
    for sign in [1.0, -1.0] {
        let t = (mf + sign * ml) * h;
        let d2 = if t <= 0.0 {
            mf * mf + ml * ml
        } else {
            let (px, py) = (mf - t * h, ml - sign * t * h);
            px * px + py * py
        };
        if d2 <= r * r * (1.0 + 1e-9) {
            return true;
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_profile_turns_column_values_into_directions() {
        let mut h = Horizon::new(8);
        // Face 1 (azimuth 45°–135°) covered at height over forward distance 1: 45° straight ahead, lower sideways.
        for c in 8..16 {
            h.h[c] = 1.0;
        }
        let p = h.profile();
        assert_eq!(p.len(), 32);
        assert!(p.windows(2).all(|w| w[0].0 <= w[1].0), "sorted by azimuth");
        for &(azimuth, elevation) in &p {
            let offset = azimuth - 90.0;
            if offset.abs() < 45.0 {
                let u = offset.to_radians().tan();
                let want = (1.0 / u.hypot(1.0)).atan().to_degrees();
                let got = elevation.expect("a covered column");
                assert!((got - want).abs() < 1e-9, "azimuth {azimuth}: {got} vs {want}");
            } else {
                assert_eq!(elevation, None, "azimuth {azimuth}");
            }
        }
    }

    #[test]
    fn faces_cover_the_plane_counter_clockwise() {
        // Azimuths 0°, 90°, 180°, 270° are the centres of faces 0..3, at u = 0.
        let dirs = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)];
        for (k, &(dx, dy)) in dirs.iter().enumerate() {
            let (f, l) = face_coords(k, dx, dy);
            assert_eq!((f, l), (1.0, 0.0));
        }
        // u grows counter-clockwise in every face.
        for k in 0..FACES {
            let a = std::f64::consts::FRAC_PI_2 * k as f64;
            let (f0, l0) = face_coords(k, (a - 0.1).cos(), (a - 0.1).sin());
            let (f1, l1) = face_coords(k, (a + 0.1).cos(), (a + 0.1).sin());
            assert!(l0 / f0 < l1 / f1);
        }
    }

    #[test]
    fn a_wall_hides_a_lower_triangle_behind_it() {
        let mu = 1e-6;
        let mut h = Horizon::new(64);
        // A wall across face 0 at x = 10, 5 m above the camera: two triangles.
        let wall = [[10.0, -50.0, 5.0], [10.0, 50.0, 5.0], [11.0, 0.0, 5.0]];
        let p: Vec<Projected> = wall.iter().map(|&d| project(d, mu, PointId::NONE)).collect();
        h.write_triangle([&p[0], &p[1], &p[2]]);
        // Behind it at x = 20..30 and below the sight line (z < 10 at x = 20).
        let behind = [[20.0, -1.0, 9.0], [30.0, 1.0, 9.0], [25.0, 3.0, 9.0]];
        let q: Vec<Projected> = behind.iter().map(|&d| project(d, mu, PointId::NONE)).collect();
        assert!(h.triangle_hidden([&q[0], &q[1], &q[2]], false));
        // Above the sight line: visible.
        let above = [[20.0, -1.0, 10.5], [30.0, 1.0, 9.0], [25.0, 3.0, 9.0]];
        let q: Vec<Projected> = above.iter().map(|&d| project(d, mu, PointId::NONE)).collect();
        assert!(!h.triangle_hidden([&q[0], &q[1], &q[2]], false));
        // Beyond the wall's lateral extent: visible.
        let aside = [[20.0, 45.0, 0.0], [30.0, 70.0, 0.0], [25.0, 60.0, 0.0]];
        let q: Vec<Projected> = aside.iter().map(|&d| project(d, mu, PointId::NONE)).collect();
        assert!(!h.triangle_hidden([&q[0], &q[1], &q[2]], false));
        // A disk behind the wall, low enough, is hidden; one reaching above the sight line is not.
        assert!(h.disk_hidden([25.0, 0.0], 3.0, 8.0 + mu, false));
        assert!(!h.disk_hidden([25.0, 0.0], 3.0, 12.0, false));
    }

    /// Regression: a vertex almost exactly beside the camera (forward distance `f` of 1e-298 m in face 0, so its
    /// `u` is about −2e299, within [`PROJ_MAX`]) once made `⌊column⌋` overflow to the last column, so the span of
    /// columns checked in face 0 was empty and the patch was called hidden there without any test: the visible vertices
    /// in face 0 were culled. Every face's span must reach from the first column.
    #[test]
    fn a_vertex_almost_beside_the_camera_keeps_its_columns() {
        let mu = 1e-6;
        let mut h = Horizon::new(64);
        // A high wall across face 3 (−y), nothing at all in face 0 (+x).
        let wall = [[-60.0, -10.0, 50.0], [60.0, -10.0, 50.0], [0.0, -11.0, 50.0]];
        let p: Vec<Projected> = wall.iter().map(|&d| project(d, mu, PointId::NONE)).collect();
        h.write_triangle([&p[0], &p[1], &p[2]]);
        // A patch in the quadrant x > 0, y < 0: one vertex in plain view in face 0, one hidden behind the wall in
        // face 3, and one south of the camera at x = 1e-298 (in face 0 with f > 0, but at u ≈ −2e299).
        let patch = [[30.0, -5.0, 0.0], [5.0, -30.0, 0.0], [1e-298, -20.0, 0.0]];
        let q: Vec<Projected> = patch.iter().map(|&d| project(d, mu, PointId::NONE)).collect();
        assert!(q[2].mask & 1 != 0 && q[2].face[0].u < -1e299, "{:?}", q[2].face[0]);
        assert!(!h.vertices_hidden(&q, false), "the vertex in face 0 is in plain view");
        assert!(!h.triangle_hidden([&q[0], &q[1], &q[2]], false));
        assert_eq!(floor(-1e302), isize::MIN);
        assert_eq!(ceil(1e302), isize::MAX);
        assert_eq!((floor(-2.5), ceil(-2.5), floor(2.5), ceil(2.5)), (-3, -2, 2, 3));
        assert_eq!((floor(f64::NAN), ceil(f64::NAN)), (0, 0));
    }

    /// Regression (found by a library user's fuzzing of `.tch` files): a segment reaching from a vertex almost beside
    /// the camera (`u` about −2e299, so `⌈column⌉` saturates to `isize::MIN`) took one column off that minimum to
    /// find its left partial column: an overflow, which panicked in debug builds and in release wrapped to
    /// `isize::MAX`, so neither of its partial covers was written. The cover at its right end, which pairs with the
    /// next segment's at their shared vertex, must be written.
    #[test]
    fn a_segment_from_beside_the_camera_keeps_its_partial_cover() {
        let mu = 1e-6;
        let mut h = Horizon::new(64);
        // Face 0 (+x): u = y / x. The first vertex's lowered v is exactly 0 (height μ), so the segment's rounding
        // margin stays small however far its u reaches.
        let p: Vec<Projected> = [[1e-298, -20.0, mu], [10.0, 3.0, 5.0], [10.0, 9.0, 5.0]]
            .iter()
            .enumerate()
            .map(|(i, &d)| project(d, mu, PointId::vertex(i as u32)))
            .collect();
        assert!(p[0].face[0].u < -1e299 && p[0].face[0].lo == 0.0, "{:?}", p[0].face[0]);
        h.write_segment([&p[0], &p[1]]);
        h.write_segment([&p[1], &p[2]]);
        // u = 0.3 lies inside column ⌊(0.3 + 1) · 32⌋ = 41, covered by the two segments' partial covers, which meet
        // at their shared vertex 1 (v ≈ 0.5).
        let v = h.values()[41];
        assert!(v > 0.49 && v < 0.5, "column 41 is {v}");
    }

    #[test]
    fn a_ridge_of_segments_hides_what_is_below_it_and_no_more() {
        let mu = 1e-6;
        let mut h = Horizon::new(64);
        // A ridge line across face 0 at x = 10, 5 m above the camera, as two edges meeting at a vertex.
        let a = project([10.0, -50.0, 5.0], mu, PointId::vertex(0));
        let b = project([10.0, 0.5, 5.0], mu, PointId::vertex(1));
        let c = project([10.0, 50.0, 5.0], mu, PointId::vertex(2));
        h.write_segment([&a, &b]);
        h.write_segment([&b, &c]);
        assert!(
            h.values()[..64].iter().all(|&v| v > 0.49 && v < 0.5),
            "{:?}",
            &h.values()[..64]
        );
        let tri = |p: [[f64; 3]; 3]| p.map(|d| project(d, mu, PointId::NONE));
        // Behind it and below the sight line: hidden, by the vertex bound and triangle by triangle.
        let behind = tri([[20.0, -1.0, 9.0], [30.0, 1.0, 9.0], [25.0, 3.0, 9.0]]);
        assert!(h.triangle_hidden([&behind[0], &behind[1], &behind[2]], false));
        assert!(h.vertices_hidden(&behind, false));
        assert!(!h.vertex_above(&behind, false));
        // One vertex above the sight line: visible in every test.
        let above = tri([[20.0, -1.0, 10.5], [30.0, 1.0, 9.0], [25.0, 3.0, 9.0]]);
        assert!(!h.triangle_hidden([&above[0], &above[1], &above[2]], false));
        assert!(!h.vertices_hidden(&above, false));
        assert!(h.vertex_above(&above, false));
        // A set of vertices reaching past the ridge's end: not hidden.
        let aside = tri([[20.0, 0.0, 0.0], [30.0, 70.0, 0.0], [25.0, 60.0, 0.0]]);
        assert!(!h.vertices_hidden(&aside, false));
    }

    #[test]
    fn a_vertex_bound_spanning_three_faces_is_not_trusted() {
        use std::f64::consts::FRAC_PI_4;
        let mu = 1e-6;
        let mut h = Horizon::new(8);
        // A high wall all around the camera, its corners between the faces' diagonals.
        for k in 0..8 {
            let (a0, a1) = ((k as f64 + 0.5) * FRAC_PI_4, (k as f64 + 1.5) * FRAC_PI_4);
            let p = project([5.0 * a0.cos(), 5.0 * a0.sin(), 100.0], mu, PointId::vertex(k));
            let q = project(
                [5.0 * a1.cos(), 5.0 * a1.sin(), 100.0],
                mu,
                PointId::vertex((k + 1) % 8),
            );
            h.write_segment([&p, &q]);
        }
        // Low vertices behind it in the wedges of faces 0, 1 and 2: three wedges are more than a set of triangles
        // that do not contain the camera is known to stay within, so the bound is not used; two adjacent ones are.
        let verts = [[20.0, 10.0, 0.0], [10.0, 20.0, 0.0], [-20.0, 10.0, 0.0]].map(|d| project(d, mu, PointId::NONE));
        assert!(!h.vertices_hidden(&verts, false));
        assert!(h.vertices_hidden(&verts[..2], false));
    }

    #[test]
    fn partial_covers_join_at_a_shared_vertex() {
        let mu = 0.0;
        let mut h = Horizon::new(4);
        // Two triangles meeting at u = 0.1 (inside column 2 of 4: [0, 0.5]) make one wall over [−0.5, 0.6].
        let a = project([10.0, -5.0, 5.0], mu, PointId::vertex(0));
        let b = project([10.0, 1.0, 5.0], mu, PointId::vertex(1));
        let c = project([10.0, 6.0, 5.0], mu, PointId::vertex(2));
        let apex1 = project([11.0, -2.0, 5.0], mu, PointId::vertex(3));
        let apex2 = project([11.0, 3.0, 5.0], mu, PointId::vertex(4));
        h.write_triangle([&a, &b, &apex1]);
        assert_eq!(h.values()[2], f64::NEG_INFINITY);
        h.write_triangle([&b, &c, &apex2]);
        assert!(h.values()[2] > 0.4, "{:?}", &h.values()[..4]);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 3000, ..Default::default() })]

        /// What `disk_span` records of a disk (the cylinder test of every node) holds each of its points: sampled on
        /// its rim (720 directions and the two tangent points seen from the camera) and at its centre, a point in a
        /// face's wedge (`f ≥ |l|`, `f > 0`) lies in that face's recorded columns, and the disk's top seen from it,
        /// `dz_max / f`, is at most the recorded bound. Disks anywhere, also just outside the camera (where the
        /// tangents' cancellation is worst), across the diagonals between faces, and far beside small ones.
        #[test]
        fn a_disk_span_holds_every_point_of_the_disk(
            dist in 1e-3f64..1e6, angle in -4.0f64..4.0, share in 0.0f64..1.0,
            grazing in proptest::option::of(-6.0f64..-1.0), dz in -1e3f64..1e3, log_w in 1u32..12,
        ) {
            let m = [dist * angle.cos(), dist * angle.sin()];
            let r = grazing.map_or(share * dist, |g| dist / (1.0 + 10f64.powf(g) * (1.0 + share)));
            let h = Horizon::new(1 << log_w);
            let Some(span) = h.disk_span(m, r, dz) else {
                return Ok(()); // never judged hidden: nothing to hold
            };
            let alpha = (r / dist).min(1.0).asin();
            let towards = m[1].atan2(m[0]);
            let mut points: Vec<[f64; 2]> = (0..720)
                .map(|i| {
                    let t = i as f64 * std::f64::consts::TAU / 720.0;
                    [m[0] + r * t.cos(), m[1] + r * t.sin()]
                })
                .collect();
            for side in [-1.0, 1.0] {
                // The tangent point: at distance √(d² − r²) from the camera, in the direction θ ± α.
                let (a, reach) = (towards + side * alpha, (dist * dist - r * r).max(0.0).sqrt());
                points.push([reach * a.cos(), reach * a.sin()]);
            }
            points.push(m);
            for p in points {
                for k in 0..FACES {
                    let (f, l) = face_coords(k, p[0], p[1]);
                    if !(f > 0.0 && f >= l.abs()) {
                        continue;
                    }
                    let (j0, j1, v) = span.faces[k];
                    let col = floor(h.column_of((l / f).clamp(-1.0, 1.0))).clamp(0, h.w as isize - 1);
                    proptest::prop_assert!(
                        j0 <= j1 && (j0 as isize..=j1 as isize).contains(&col),
                        "point {p:?} of the disk {m:?} r {r} in face {k}, column {col}: span {:?}", span.faces[k]
                    );
                    proptest::prop_assert!(dz / f <= v, "point {p:?}, face {k}: v {} above the bound {v}", dz / f);
                }
            }
        }
    }

    /// The highest `v` of the lowered segment `a b` (offsets from the camera, heights already lowered) on the
    /// vertical half-plane `u` of face `k`, if it meets it in front of the camera: where `l − u f`, linear along the
    /// segment, is zero.
    fn segment_v_at(k: usize, a: [f64; 3], b: [f64; 3], u: f64) -> Option<f64> {
        let (fa, la) = face_coords(k, a[0], a[1]);
        let (fb, lb) = face_coords(k, b[0], b[1]);
        let (ga, gb) = (la - u * fa, lb - u * fb);
        let t = if ga == gb {
            if ga != 0.0 {
                return None;
            }
            // The whole segment lies on the half-plane: its higher end.
            return [(fa, a[2]), (fb, b[2])]
                .into_iter()
                .filter(|&(f, _)| f > 0.0)
                .map(|(f, z)| z / f)
                .reduce(f64::max);
        } else {
            ga / (ga - gb)
        };
        if !(-1e-12..=1.0 + 1e-12).contains(&t) {
            return None;
        }
        let t = t.clamp(0.0, 1.0);
        let f = fa + t * (fb - fa);
        (f > 0.0).then(|| (a[2] + t * (b[2] - a[2])) / f)
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 1000, ..Default::default() })]

        /// The buffer's invariant, checked directly: after random TIN-like edges and flat chains are written, every
        /// `u` sampled in a covered column (its ends, and points between) has a point of a written occluder on its
        /// half-plane at least as high as the column's value; and a triangle called hidden has every sampled point
        /// below the value of the column it falls in. Occluders share vertices (so partial covers pair up at them),
        /// come from near the camera (wide, crossing faces) and far (narrower than a column), and the columns
        /// are few or many.
        #[test]
        fn the_horizon_promises_only_what_its_occluders_give(
            points in proptest::collection::vec((-100.0f64..100.0, -100.0f64..100.0, -20.0f64..20.0), 4..40),
            links in proptest::collection::vec((0usize..40, 0usize..40), 1..60),
            chains in proptest::collection::vec(proptest::collection::vec(0usize..40, 2..6), 0..4),
            tris in proptest::collection::vec((0usize..40, 0usize..40, 0usize..40), 1..30),
            log_w in 1u32..9, lift in 0.0f64..30.0,
        ) {
            let mu = 1e-6;
            let pts: Vec<[f64; 3]> = points.iter().map(|&(x, y, z)| [x, y, z]).collect();
            let n = pts.len();
            let proj: Vec<Projected> =
                pts.iter().enumerate().map(|(i, &d)| project(d, mu, PointId::vertex(i as u32))).collect();
            let lowered = |i: usize| [pts[i][0], pts[i][1], pts[i][2] - mu];
            let mut h = Horizon::new(1 << log_w);
            // Every occluder written, as lowered segments, for the check.
            let mut written: Vec<(usize, usize)> = Vec::new();
            for &(a, b) in &links {
                let (a, b) = (a % n, b % n);
                if a != b {
                    h.write_segment([&proj[a], &proj[b]]);
                    written.push((a, b));
                }
            }
            for chain in &chains {
                let chain: Vec<usize> = chain.iter().map(|&i| i % n).collect();
                for k in 0..FACES {
                    if !chain.iter().all(|&i| proj[i].mask & (1 << k) != 0) {
                        continue;
                    }
                    let by_u = |&i: &usize| proj[i].face[k].u;
                    let lo = *chain.iter().min_by(|x, y| by_u(x).total_cmp(&by_u(y))).expect("a chain");
                    let hi = *chain.iter().max_by(|x, y| by_u(x).total_cmp(&by_u(y))).expect("a chain");
                    let bound = chain.iter().map(|&i| proj[i].face[k].lo).fold(f64::INFINITY, f64::min);
                    let (a, b) = (PointId::vertex(lo as u32), PointId::vertex(hi as u32));
                    h.write_flat(k, (by_u(&lo), a), (by_u(&hi), b), bound);
                }
                written.extend(chain.windows(2).map(|w| (w[0], w[1])));
            }
            let w = h.w;
            for k in 0..FACES {
                for j in 0..w {
                    let hj = h.h[k * w + j];
                    if hj == f64::NEG_INFINITY {
                        continue;
                    }
                    let (a, b) = (h.boundary(j), h.boundary(j + 1));
                    for s in 0..=16 {
                        let u = a + (b - a) * s as f64 / 16.0;
                        let best = written
                            .iter()
                            .filter_map(|&(p, q)| segment_v_at(k, lowered(p), lowered(q), u))
                            .fold(f64::NEG_INFINITY, f64::max);
                        proptest::prop_assert!(
                            best >= hj - 1e-9 * (1.0 + hj.abs()),
                            "face {k} column {j} (of {w}) at u {u}: value {hj}, but the occluders reach only {best}"
                        );
                    }
                }
            }
            // Occludees: raised triangles (lifted to vary how many are hidden).
            let up: Vec<Projected> = pts
                .iter()
                .enumerate()
                .map(|(i, &d)| project([d[0], d[1], d[2] - lift], mu, PointId::vertex((n + i) as u32)))
                .collect();
            for &(a, b, c) in &tris {
                let (a, b, c) = (a % n, b % n, c % n);
                let hidden = h.triangle_hidden([&up[a], &up[b], &up[c]], false);
                let set_hidden = h.vertices_hidden(&[up[a], up[b], up[c]], false);
                if !(hidden || set_hidden) {
                    continue;
                }
                let corner = |i: usize| [pts[i][0], pts[i][1], pts[i][2] - lift + mu];
                let (pa, pb, pc) = (corner(a), corner(b), corner(c));
                for s in 0..=12 {
                    for t in 0..=(12 - s) {
                        let (x, y) = (s as f64 / 12.0, t as f64 / 12.0);
                        let p: [f64; 3] = std::array::from_fn(|i| pa[i] + x * (pb[i] - pa[i]) + y * (pc[i] - pa[i]));
                        for k in 0..FACES {
                            let (f, l) = face_coords(k, p[0], p[1]);
                            if !(f > 0.0 && l.abs() <= f) {
                                continue;
                            }
                            let (u, v) = (l / f, p[2] / f);
                            // A point on a column boundary is in both columns.
                            let x = h.column_of(u);
                            let cols = [x.floor(), x.ceil() - 1.0, x.ceil()];
                            for col in cols {
                                let col = (col as isize).clamp(0, w as isize - 1) as usize;
                                if h.boundary(col) <= u && u <= h.boundary(col + 1) {
                                    let hj = h.h[k * w + col];
                                    proptest::prop_assert!(
                                        v < hj + 1e-9 * (1.0 + hj.abs()),
                                        "triangle {a} {b} {c} called hidden (alone {hidden}, by its vertices \
                                         {set_hidden}): its point {p:?} in face {k} column {col} has v {v} over {hj}"
                                    );
                                }
                            }
                        }
                    }
                }
            }
        }
    }
}
