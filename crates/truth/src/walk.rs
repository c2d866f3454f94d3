//! Exact segment visibility on a TIN (design notes, "Measuring accuracy": the ground-truth point test).
//!
//! A point `target` is visible from `eye` when the segment between them never passes below the terrain. Over the
//! TIN's footprint the terrain is piecewise linear, and so is the clearance (segment height minus terrain height)
//! along the segment: it is linear inside each triangle. Its minimum is therefore reached at the segment's ends or
//! where the segment's x,y projection crosses a triangle edge or passes through a vertex. The walk visits exactly
//! those points, triangle by triangle, from the target toward the eye, and stops at the first one below the terrain.
//!
//! Choices (the design notes leave them open):
//!
//! - **Exact topology.** Every side-of-line decision uses Shewchuk's adaptive orientation predicate
//!   ([`tin::orient2d`]), so the walk is consistent when the segment passes exactly through vertices or runs along
//!   edges. At a vertex the walk continues in the incident triangle whose corner wedge strictly contains the segment's
//!   direction, or along the incident edge that points exactly in that direction. Only heights and crossing parameters
//!   are rounded.
//! - **Tolerance.** A point counts as below the terrain only if it is lower by more than
//!   `EPS_REL * (1 + |eye - target| + max(|eye.z|, |target.z|))` metres ([`EPS_REL`] = 1e-9, so about 1e-6 m for a
//!   1 km segment at 1 km altitude). A segment that only touches the terrain (grazing a ridge vertex, running along
//!   a ridge edge, or lying in the plane of the target's own triangle) is therefore *not* blocked: the point is
//!   visible.
//! - **Target.** The target is meant to lie on the terrain. It is itself checked like any other point of the
//!   segment (a target buried deeper than the tolerance is not visible); a target above the terrain is allowed.
//! - **Outside the footprint** there is no terrain, so nothing blocks there. When the segment leaves a convex
//!   footprint (every Delaunay TIN) it never comes back and the walk ends; otherwise the walk looks for the
//!   nearest boundary edge (or boundary vertex) ahead where the segment re-enters, by scanning the boundary.
//! - **Eye below the terrain.** The eye is a point of the segment, so an eye inside the footprint and below the
//!   terrain sees nothing (every point is not visible). This is the plain reading of the definition.
//! - **Vertical segment** (eye exactly above or below the target in x,y): visible iff the lower end is not below
//!   the terrain at that x,y, i.e. for a target on the terrain, iff the eye is not below the target.
//! - **Non-finite input** (NaN or infinite coordinates): not visible.
//! - A walk that has not finished after more steps than the TIN has triangles and vertices (impossible on a valid
//!   height field, possible on an overlapping mesh) falls back to testing the segment against every triangle.

use glam::{DVec2, DVec3};
use tin::{NO_NEIGHBOUR, Tin};

use crate::locate::{BoundaryEdge, Locator, WalkTri, corners_contain, orient, plane_height};

/// Relative tolerance of the height comparison (see the module documentation).
pub const EPS_REL: f64 = 1e-9;

/// Whether `target` (a point on the terrain) is visible from `eye`: the segment between them never passes below the
/// terrain of `tin` by more than the tolerance.
///
/// `locator` must have been built from `tin` ([`Locator::new`]). See the module documentation for the exact rules
/// (grazing counts as visible, no terrain outside the footprint, an eye below the terrain sees nothing).
pub fn point_visible(tin: &Tin, locator: &Locator, eye: DVec3, target: DVec3) -> bool {
    segment_clear(tin, locator, None, target, eye)
}

/// The absolute height tolerance for the segment `target`–`eye` (m).
pub(crate) fn tolerance(target: DVec3, eye: DVec3) -> f64 {
    EPS_REL * (1.0 + target.distance(eye) + target.z.abs().max(eye.z.abs()))
}

/// Where a height margin fixed in advance stays far above the exact checker's tolerance (`1e-9 (1 + |eye − target| +
/// max(|eye.z|, |target.z|))` m, see the module documentation): the conservative methods whose margin `μ` is
/// chosen when they are prepared, from the terrain alone (`occlusion`'s conservative regions, `pvs`'s walls), hide
/// what lies at least `μ` under every sight line, which the checker calls hidden only while its tolerance, growing
/// with the eye's distance and height, stays below `μ`. They judge an eye or a viewcell only when
/// [`MarginReach::covers`] it, and call everything visible from farther away.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarginReach {
    mu: f64,
    lo: [f64; 3],
    hi: [f64; 3],
}

impl MarginReach {
    /// The margin `mu` (m) of a terrain whose points all lie in the box `lo..=hi` (world coordinates).
    pub fn new(mu: f64, lo: [f64; 3], hi: [f64; 3]) -> MarginReach {
        MarginReach { mu, lo, hi }
    }

    /// Whether the margin is at least ten times the checker's tolerance for every segment from a point `e` of the box
    /// `eye_lo..=eye_hi` to a point `p` of the terrain's box (centre `c`, sides `w`): `|e − p|` is at most the sum of
    /// the coordinate differences, each at most `|e_k − c_k| + w_k / 2` in x and y and `|e.z| + |p.z|` in z, and
    /// `max(|e.z|, |p.z|) ≤ |e.z| + |p.z|`, so `1 + |e − p| + max(|e.z|, |p.z|)` is below
    /// `B = 1 + max|e.x − c.x| + max|e.y − c.y| + (w_x + w_y) / 2 + 2 max|e.z| + 2 max|p.z|`; the answer is
    /// `10 · 1e-9 · B (1 + 1e-9) ≤ μ` (the relative 1e-9 covers the rounding of the sum). NaN anywhere: `false`.
    pub fn covers(&self, eye_lo: [f64; 3], eye_hi: [f64; 3]) -> bool {
        // `f64::max` drops a NaN: refused here first.
        if !eye_lo.iter().chain(&eye_hi).all(|x| x.is_finite()) {
            return false;
        }
        let off = |k: usize| {
            let c = 0.5 * (self.lo[k] + self.hi[k]);
            (eye_lo[k] - c).abs().max((eye_hi[k] - c).abs())
        };
        let half = 0.5 * ((self.hi[0] - self.lo[0]) + (self.hi[1] - self.lo[1]));
        let ez = eye_lo[2].abs().max(eye_hi[2].abs());
        let pz = self.lo[2].abs().max(self.hi[2].abs());
        let bound = 1.0 + off(0) + off(1) + half + 2.0 * ez + 2.0 * pz;
        10.0 * EPS_REL * bound * (1.0 + 1e-9) <= self.mu
    }
}

/// [`point_visible`] with an optional triangle that probably contains the target (checked exactly before use).
pub(crate) fn segment_clear(tin: &Tin, loc: &Locator, hint: Option<usize>, target: DVec3, eye: DVec3) -> bool {
    if !target.is_finite() || !eye.is_finite() {
        return false;
    }
    if !loc.matches(tin) {
        // A locator of another mesh: build the right one rather than index out of bounds.
        let own = Locator::new(tin);
        return Walk::new(tin, &own, target, eye).run(None) == Outcome::Visible;
    }
    Walk::new(tin, loc, target, eye).run(hint) == Outcome::Visible
}

/// [`segment_clear`] reporting the blocking edge; `loc` must match `tin` and the inputs must be finite.
pub(crate) fn walk_outcome(tin: &Tin, loc: &Locator, hint: Option<usize>, target: DVec3, eye: DVec3) -> Outcome {
    Walk::new(tin, loc, target, eye).run(hint)
}

/// Whether the segment target -> eye crosses edge `(a, b)` (properly, decided exactly) below the terrain by more
/// than the tolerance: a certificate that the target is hidden, computed exactly as the walk computes that crossing.
pub(crate) fn edge_blocks(tin: &Tin, loc: &Locator, (a, b): (u32, u32), target: DVec3, eye: DVec3) -> bool {
    let walk = Walk::new(tin, loc, target, eye);
    let (pa, pb) = (tin.position(a), tin.position(b));
    let oa = orient(walk.q0, walk.q1, pa.truncate());
    let ob = orient(walk.q0, walk.q1, pb.truncate());
    if !((oa < 0.0 && ob > 0.0) || (oa > 0.0 && ob < 0.0)) {
        return false;
    }
    let ea = orient(pa.truncate(), pb.truncate(), walk.q0);
    let eb = orient(pa.truncate(), pb.truncate(), walk.q1);
    if !((ea < 0.0 && eb > 0.0) || (ea > 0.0 && eb < 0.0)) {
        return false;
    }
    let w = oa / (oa - ob);
    let x = pa.truncate() + w * (pb.truncate() - pa.truncate());
    walk.cross_edge(pa, pb, w, walk.param(x), 0.0).is_none()
}

/// What the walk left through when it left the footprint (excluded when looking for re-entry).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Exited {
    /// The segment started outside.
    Nothing,
    /// Through the interior of this boundary edge.
    Edge(BoundaryEdge),
    /// Through this boundary vertex.
    Vertex(u32),
}

/// Where the walk stands. Every state is at a point of the segment whose clearance has already been checked.
#[derive(Clone, Copy, Debug)]
enum State {
    /// The segment continues through the interior of triangle `t` from parameter `s`. `known` caches the
    /// side-of-line values of up to two of its vertices (vertex `u32::MAX` = empty).
    InTri { t: usize, s: f64, known: [(u32, f64); 2] },
    /// At vertex `v`, exactly on the segment, at parameter `s`.
    AtVertex { v: u32, s: f64 },
    /// Off the footprint after segment parameter `after`.
    Outside { after: f64, exited: Exited },
}

enum Step {
    Go(State),
    Done(bool),
    /// Below the terrain where the segment crosses the edge between these two vertices.
    BlockedAt(u32, u32),
}

/// Result of a walk, with the edge that blocked it when there is one (a certificate that can be re-checked cheaply
/// for nearby segments, see [`edge_blocks`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Outcome {
    Visible,
    Hidden(Option<(u32, u32)>),
}

impl Outcome {
    fn of(visible: bool) -> Outcome {
        if visible {
            Outcome::Visible
        } else {
            Outcome::Hidden(None)
        }
    }
}

const NONE_KNOWN: [(u32, f64); 2] = [(u32::MAX, 0.0), (u32::MAX, 0.0)];

/// One segment walk, from `q0` (the target, parameter 0) to `q1` (the eye, parameter 1). Triangle indices are the
/// locator's walk indices.
struct Walk<'a> {
    tin: &'a Tin,
    loc: &'a Locator,
    tris: &'a [WalkTri],
    q0: DVec2,
    q1: DVec2,
    z0: f64,
    z1: f64,
    d: DVec2,
    /// `1 / |d|²`.
    inv_dd: f64,
    eps: f64,
    /// Index (0 = x, 1 = y) of the dominant axis of `d`, and the sign of `d` along it: points exactly on the
    /// segment's line are ordered exactly by `sign * coordinate`.
    axis: usize,
    sign: f64,
}

impl<'a> Walk<'a> {
    fn new(tin: &'a Tin, loc: &'a Locator, target: DVec3, eye: DVec3) -> Walk<'a> {
        let q0 = target.truncate();
        let q1 = eye.truncate();
        let d = q1 - q0;
        let axis = usize::from(d.y.abs() > d.x.abs());
        let sign = if d[axis] < 0.0 { -1.0 } else { 1.0 };
        Walk {
            tin,
            loc,
            tris: loc.tris(),
            q0,
            q1,
            z0: target.z,
            z1: eye.z,
            d,
            inv_dd: 1.0 / d.length_squared(),
            eps: tolerance(target, eye),
            axis,
            sign,
        }
    }

    fn pos(&self, v: u32) -> DVec3 {
        self.tin.position(v)
    }

    /// Exact order key of a point on the segment's line.
    fn key(&self, p: DVec2) -> f64 {
        self.sign * p[self.axis]
    }

    /// Segment parameter of a point on (or rounded near) the line.
    fn param(&self, p: DVec2) -> f64 {
        (p - self.q0).dot(self.d) * self.inv_dd
    }

    /// Whether the segment at parameter `s` is not below terrain height `terrain`.
    fn clear_at(&self, s: f64, terrain: f64) -> bool {
        self.z0 + s * (self.z1 - self.z0) - terrain >= -self.eps
    }

    /// Rounded parameter of a vertex known (exactly) to lie on the segment at or after parameter `lo`.
    fn vertex_param(&self, p: DVec2, lo: f64) -> f64 {
        self.param(p).clamp(lo, 1.0)
    }

    /// Checks the clearance where the segment crosses edge `a`-`b`, at the rounded edge point `a + w (b - a)` whose
    /// parameter on the segment is `s_guess`, and returns the parameter used, or `None` when the segment is below the
    /// terrain there.
    ///
    /// The edge point lies within rounding distance of the segment's line (its side-of-line value interpolates
    /// those of `a` and `b` to zero), so comparing the terrain there with the segment at `s_guess` is exact up to
    /// rounding. When the segment runs nearly along the edge, though, the crossing is ill-conditioned and
    /// `s_guess` may fall outside the part of the segment still to walk. The parameter is then clamped to
    /// `[lo, 1]` and the terrain is taken at the edge point nearest to that segment point: the segment stays within
    /// rounding distance of the edge over the whole stretch, so this is still the clearance of a true point of the
    /// segment, and the extremes of the (linear) clearance along the stretch are checked where the segment meets
    /// and leaves the edge.
    fn cross_edge(&self, a: DVec3, b: DVec3, w: f64, s_guess: f64, lo: f64) -> Option<f64> {
        if (lo..=1.0).contains(&s_guess) {
            return self.clear_at(s_guess, a.z + w * (b.z - a.z)).then_some(s_guess);
        }
        let s = s_guess.clamp(lo, 1.0);
        let q = self.q0 + s * self.d;
        let e = (b - a).truncate();
        let w = ((q - a.truncate()).dot(e) / e.length_squared()).clamp(0.0, 1.0);
        self.clear_at(s, a.z + w * (b.z - a.z)).then_some(s)
    }

    /// Final check: the eye, inside closed walk triangle `t`.
    fn eye_clear(&self, t: usize) -> bool {
        self.z1 - plane_height(&self.tris[t].p, self.q1) >= -self.eps
    }

    /// Walks the segment; `hint` is a TIN triangle that probably contains the target.
    fn run(&self, hint: Option<usize>) -> Outcome {
        let start = hint
            .and_then(|t| self.loc.walk_index(t))
            .filter(|&w| corners_contain(&self.tris[w as usize].p, self.q0))
            .or_else(|| self.loc.locate_walk(self.q0))
            .map(|w| w as usize);
        if self.q0 == self.q1 {
            return Outcome::of(match start {
                None => true,
                Some(t) => {
                    let ground = plane_height(&self.tris[t].p, self.q0);
                    self.z0.min(self.z1) - ground >= -self.eps
                }
            });
        }
        let mut state = match start {
            None => State::Outside {
                after: 0.0,
                exited: Exited::Nothing,
            },
            Some(t) => match self.start_in(t) {
                Step::Go(s) => s,
                Step::Done(b) => return Outcome::of(b),
                Step::BlockedAt(a, b) => return Outcome::Hidden(Some((a, b))),
            },
        };
        let cap = 2 * (self.tris.len() + self.tin.num_vertices()) + 64;
        for _ in 0..cap {
            let step = match state {
                State::InTri { t, s, known } => self.in_triangle(t, s, known),
                State::AtVertex { v, s } => self.at_vertex(v, s),
                State::Outside { after, exited } => self.outside(after, exited),
            };
            match step {
                Step::Go(s) => state = s,
                Step::Done(b) => return Outcome::of(b),
                Step::BlockedAt(a, b) => return Outcome::Hidden(Some((a, b))),
            }
        }
        Outcome::of(self.brute_force())
    }

    /// The target lies in closed walk triangle `t`: check it and find where the segment goes.
    fn start_in(&self, t: usize) -> Step {
        let tri = &self.tris[t];
        if self.z0 - plane_height(&tri.p, self.q0) < -self.eps {
            return Step::Done(false);
        }
        let p = tri.p.map(|c| c.truncate());
        let e = [0, 1, 2].map(|i| orient(p[i], p[(i + 1) % 3], self.q0));
        let zeros = e.iter().filter(|&&x| x == 0.0).count();
        let inside = State::InTri {
            t,
            s: 0.0,
            known: NONE_KNOWN,
        };
        if zeros == 0 {
            return Step::Go(inside);
        }
        if zeros >= 2 {
            // On two edges: at the vertex they share (edge i-1 ends and edge i starts at corner i).
            let i = (0..3).find(|&i| e[(i + 2) % 3] == 0.0 && e[i] == 0.0).unwrap_or(0);
            return Step::Go(State::AtVertex { v: tri.v[i], s: 0.0 });
        }
        let i = (0..3).find(|&i| e[i] == 0.0).unwrap_or(0);
        let j = (i + 1) % 3;
        let side = orient(p[i], p[j], self.q1);
        if side > 0.0 {
            Step::Go(inside)
        } else if side < 0.0 {
            match tri.n[i] {
                NO_NEIGHBOUR => Step::Go(State::Outside {
                    after: 0.0,
                    exited: Exited::Edge(BoundaryEdge {
                        tri: t as u32,
                        edge: i as u8,
                    }),
                }),
                n => Step::Go(State::InTri {
                    t: n as usize,
                    s: 0.0,
                    known: NONE_KNOWN,
                }),
            }
        } else {
            let ahead = if self.key(p[j]) > self.key(p[i]) {
                tri.v[j]
            } else {
                tri.v[i]
            };
            self.along_edge(ahead, t, 0.0)
        }
    }

    /// The segment runs exactly along an edge of walk triangle `t`, from parameter `lo` toward the edge's vertex `v`.
    fn along_edge(&self, v: u32, t: usize, lo: f64) -> Step {
        let p = self.pos(v);
        if self.key(self.q1) <= self.key(p.truncate()) {
            return Step::Done(self.eye_clear(t));
        }
        let s = self.vertex_param(p.truncate(), lo);
        if !self.clear_at(s, p.z) {
            return Step::Done(false);
        }
        Step::Go(State::AtVertex { v, s })
    }

    /// The segment passes through the interior of walk triangle `t` from parameter `lo`: find where it leaves.
    fn in_triangle(&self, t: usize, lo: f64, known: [(u32, f64); 2]) -> Step {
        let tri = &self.tris[t];
        let o: [f64; 3] = std::array::from_fn(|i| {
            let v = tri.v[i];
            if known[0].0 == v {
                known[0].1
            } else if known[1].0 == v {
                known[1].1
            } else {
                orient(self.q0, self.q1, tri.p[i].truncate())
            }
        });
        for i in 0..3 {
            let j = (i + 1) % 3;
            if o[i] < 0.0 && o[j] > 0.0 {
                // Leaves through the interior of edge i (corner i on the right, corner j on the left).
                let (a, b) = (tri.p[i], tri.p[j]);
                if orient(a.truncate(), b.truncate(), self.q1) >= 0.0 {
                    return Step::Done(self.eye_clear(t));
                }
                let w = o[i] / (o[i] - o[j]);
                let x = a.truncate() + w * (b.truncate() - a.truncate());
                let Some(s) = self.cross_edge(a, b, w, self.param(x), lo) else {
                    return Step::BlockedAt(tri.v[i], tri.v[j]);
                };
                return match tri.n[i] {
                    NO_NEIGHBOUR => Step::Go(State::Outside {
                        after: s,
                        exited: Exited::Edge(BoundaryEdge {
                            tri: t as u32,
                            edge: i as u8,
                        }),
                    }),
                    n => Step::Go(State::InTri {
                        t: n as usize,
                        s,
                        known: [(tri.v[i], o[i]), (tri.v[j], o[j])],
                    }),
                };
            }
        }
        for i in 0..3 {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            if o[i] == 0.0 && o[j] > 0.0 && o[k] < 0.0 {
                // Leaves through corner i (enters through the opposite edge).
                let p = tri.p.map(|c| c.truncate());
                if orient(p[k], p[i], self.q1) >= 0.0 && orient(p[i], p[j], self.q1) >= 0.0 {
                    return Step::Done(self.eye_clear(t));
                }
                let s = self.vertex_param(p[i], lo);
                if !self.clear_at(s, tri.p[i].z) {
                    return Step::Done(false);
                }
                return Step::Go(State::AtVertex { v: tri.v[i], s });
            }
        }
        // The line does not cross the interior: impossible on a valid TIN.
        Step::Done(self.brute_force())
    }

    /// At vertex `v` on the segment, at parameter `s`: continue into the triangle or along the edge that contains
    /// the direction.
    fn at_vertex(&self, v: u32, s: f64) -> Step {
        let pv = self.pos(v);
        let p = pv.truncate();
        if p == self.q1 {
            return Step::Done(self.z1 - pv.z >= -self.eps);
        }
        for &t in self.loc.vertex_tris(v) {
            let tri = &self.tris[t as usize];
            let k = tri.v.iter().position(|&x| x == v).unwrap_or(0);
            let (kb, kc) = ((k + 1) % 3, (k + 2) % 3);
            let (pb, pc) = (tri.p[kb].truncate(), tri.p[kc].truncate());
            let ob = orient(p, pb, self.q1);
            let oc = orient(p, self.q1, pc);
            if ob > 0.0 && oc > 0.0 {
                return Step::Go(State::InTri {
                    t: t as usize,
                    s,
                    known: [(v, 0.0), (u32::MAX, 0.0)],
                });
            }
            if ob == 0.0 && self.key(pb) > self.key(p) {
                return self.along_edge(tri.v[kb], t as usize, s);
            }
            if oc == 0.0 && self.key(pc) > self.key(p) {
                return self.along_edge(tri.v[kc], t as usize, s);
            }
        }
        Step::Go(State::Outside {
            after: s,
            exited: Exited::Vertex(v),
        })
    }

    /// Off the footprint after parameter `after`: find where the segment re-enters, if anywhere.
    ///
    /// Candidates are boundary edges that the segment crosses (exactly decided) from outside to inside, and boundary
    /// vertices exactly on the segment; the nearest one past the exit wins. Crossings of two edges that share a
    /// vertex are ordered exactly ([`Walk::crosses_before`]), which settles the common near-tie of a segment slipping
    /// past a boundary vertex; other crossings are ordered by their rounded parameters.
    fn outside(&self, after: f64, exited: Exited) -> Step {
        if self.loc.footprint_is_convex() && exited != Exited::Nothing {
            return Step::Done(true);
        }
        #[derive(Clone, Copy)]
        struct Candidate {
            s: f64,
            /// Boundary edge (walk triangle, ends, side-of-line values of the ends, eye side), or `None` for a vertex.
            edge: Option<(usize, u32, u32, f64, f64, f64)>,
            vertex: u32,
        }
        let ends = |e: BoundaryEdge| {
            let tri = &self.tris[e.tri as usize];
            let (i, j) = (e.edge as usize, (e.edge as usize + 1) % 3);
            (tri.v[i], tri.v[j], tri.p[i].truncate(), tri.p[j].truncate())
        };
        let exit_ends = match exited {
            Exited::Edge(e) => {
                let (a, b, ..) = ends(e);
                Some((a, b))
            }
            _ => None,
        };
        let beyond = |s: f64| {
            if exited == Exited::Nothing {
                s >= after
            } else {
                s > after
            }
        };
        // Whether candidate edge (a, b) crossed at rounded parameter s lies past the exit.
        let past_exit = |a: u32, b: u32, s: f64| match exit_ends.and_then(|x| shared_vertex(x, (a, b))) {
            Some((v, from, to)) => self.crosses_before(v, from, to),
            None => beyond(s),
        };
        let before = |c: &Candidate, best: &Candidate| match (c.edge, best.edge) {
            (Some((_, a, b, ..)), Some((_, x, y, ..))) => match shared_vertex((a, b), (x, y)) {
                Some((v, from, to)) => self.crosses_before(v, from, to),
                None => c.s < best.s,
            },
            _ => c.s < best.s,
        };
        let mut best: Option<Candidate> = None;
        let (k0, k1) = (self.key(self.q0), self.key(self.q1));
        for &e in self.loc.boundary() {
            let (a, b, pa, pb) = ends(e);
            let oa = orient(self.q0, self.q1, pa);
            if oa == 0.0 && exited != Exited::Vertex(a) {
                let ka = self.key(pa);
                let s = self.param(pa);
                let c = Candidate {
                    s,
                    edge: None,
                    vertex: a,
                };
                if ka >= k0 && ka <= k1 && beyond(s) && best.is_none_or(|bc| before(&c, &bc)) {
                    best = Some(c);
                }
            }
            if exited == Exited::Edge(e) {
                continue;
            }
            let ob = orient(self.q0, self.q1, pb);
            if !(oa > 0.0 && ob < 0.0) {
                continue;
            }
            let ea = orient(pa, pb, self.q0);
            let eb = orient(pa, pb, self.q1);
            if ea > 0.0 || eb < 0.0 {
                continue;
            }
            let s = ea / (ea - eb);
            let c = Candidate {
                s,
                edge: Some((e.tri as usize, a, b, oa, ob, eb)),
                vertex: u32::MAX,
            };
            if past_exit(a, b, s) && best.is_none_or(|bc| before(&c, &bc)) {
                best = Some(c);
            }
        }
        let lo = after.max(0.0);
        match best {
            None => Step::Done(true),
            Some(Candidate {
                s, edge: None, vertex, ..
            }) => {
                let s = s.clamp(lo, 1.0);
                if !self.clear_at(s, self.pos(vertex).z) {
                    return Step::Done(false);
                }
                Step::Go(State::AtVertex { v: vertex, s })
            }
            Some(Candidate {
                edge: Some((t, a, b, oa, ob, eb)),
                ..
            }) => {
                let w = oa / (oa - ob);
                let (pa, pb) = (self.pos(a), self.pos(b));
                let x = pa.truncate() + w * (pb.truncate() - pa.truncate());
                let Some(s) = self.cross_edge(pa, pb, w, self.param(x), lo) else {
                    return Step::BlockedAt(a, b);
                };
                if eb == 0.0 {
                    return Step::Done(self.eye_clear(t));
                }
                Step::Go(State::InTri {
                    t,
                    s,
                    known: [(a, oa), (b, ob)],
                })
            }
        }
    }

    /// Whether the segment's line crosses edge `(v, x)` strictly before edge `(v, y)` (exact). Both edges must be
    /// crossed properly (their ends strictly on opposite sides of the line), so `v` is off the line.
    ///
    /// With `v` on the right of the line, and the line along +x, the crossings are at `X`, `Y` on rays from `v`, and
    /// `cross(x - v, y - v)` has the sign of `X - Y`; on the left the sign flips.
    fn crosses_before(&self, v: u32, x: u32, y: u32) -> bool {
        let pv = self.pos(v).truncate();
        let side = orient(self.q0, self.q1, pv);
        let turn = orient(pv, self.pos(x).truncate(), self.pos(y).truncate());
        (side > 0.0 && turn > 0.0) || (side < 0.0 && turn < 0.0)
    }

    /// Fallback for meshes the walk cannot traverse: the segment against every triangle (clip the segment's x,y
    /// projection to the triangle; the clearance is linear there, so check both ends of the clipped piece).
    fn brute_force(&self) -> bool {
        self.tris.iter().all(|tri| {
            let p = tri.p.map(|c| c.truncate());
            let (mut lo, mut hi) = (0.0f64, 1.0f64);
            for i in 0..3 {
                let (a, b) = (p[i], p[(i + 1) % 3]);
                // Inside edge i: f(s) = cross(b - a, q(s) - a) >= 0, linear in s.
                let f0 = (b - a).perp_dot(self.q0 - a);
                let f1 = (b - a).perp_dot(self.q1 - a);
                if f0 < 0.0 && f1 < 0.0 {
                    return true;
                }
                if f0 < 0.0 {
                    lo = lo.max(f0 / (f0 - f1));
                } else if f1 < 0.0 {
                    hi = hi.min(f0 / (f0 - f1));
                }
            }
            if lo > hi {
                return true;
            }
            [lo, hi].iter().all(|&s| {
                let q = self.q0 + s * self.d;
                self.clear_at(s, plane_height(&tri.p, q))
            })
        })
    }
}

/// The vertex shared by edges `e` and `f`, with the other end of `e` and the other end of `f`.
fn shared_vertex(e: (u32, u32), f: (u32, u32)) -> Option<(u32, u32, u32)> {
    if e.0 == f.0 {
        Some((e.0, e.1, f.1))
    } else if e.0 == f.1 {
        Some((e.0, e.1, f.0))
    } else if e.1 == f.0 {
        Some((e.1, e.0, f.1))
    } else if e.1 == f.1 {
        Some((e.1, e.0, f.0))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// A margin that covers an eye box is ten times the tolerance of every segment from a point of it to a point
        /// of the terrain's box (corners and random points of both).
        #[test]
        fn a_covered_eye_box_keeps_the_margin_above_every_tolerance(
            c in prop::array::uniform3(-1e6f64..1e6), w in prop::array::uniform3(0.0f64..1e5),
            e in prop::array::uniform3(-1e7f64..1e7), ew in prop::array::uniform3(0.0f64..1e4),
            mu in 1e-6f64..1.0, t in prop::collection::vec(prop::array::uniform3(0.0f64..=1.0), 8),
        ) {
            let (lo, hi) = ([0, 1, 2].map(|k| c[k] - w[k]), [0, 1, 2].map(|k| c[k] + w[k]));
            let (elo, ehi) = (e, [0, 1, 2].map(|k| e[k] + ew[k]));
            let reach = MarginReach::new(mu, lo, hi);
            if reach.covers(elo, ehi) {
                let at = |a: [f64; 3], b: [f64; 3], f: [f64; 3]| {
                    DVec3::new(a[0] + f[0] * (b[0] - a[0]), a[1] + f[1] * (b[1] - a[1]), a[2] + f[2] * (b[2] - a[2]))
                };
                for (i, f) in t.iter().enumerate() {
                    let g = t[(i + 3) % t.len()].map(|x| x.round());
                    let (eye, p) = (at(elo, ehi, *f), at(lo, hi, g));
                    prop_assert!(10.0 * tolerance(p, eye) <= mu, "{eye} to {p}");
                }
            }
        }
    }

    #[test]
    fn a_margin_covers_the_eyes_near_its_terrain_only() {
        // A 10 km terrain up to 2 km high: μ = 1e-7 (1 + 20,000 + 2,000) ≈ 2.2 mm.
        let (lo, hi) = ([0.0, 0.0, 0.0], [1e4, 1e4, 2e3]);
        let reach = MarginReach::new(1e-7 * (1.0 + 2e4 + 2e3), lo, hi);
        assert!(reach.covers([5e3, 5e3, 2.2e3], [5.1e3, 5.1e3, 2.4e3]));
        assert!(reach.covers([-5e4, -5e4, 0.0], [-4e4, -4e4, 3e4]));
        assert!(!reach.covers([1e6, 0.0, 0.0], [1e6, 1.0, 1.0]));
        assert!(!reach.covers([0.0, 0.0, 8e5], [1.0, 1.0, 8e5]));
        assert!(!reach.covers([f64::NAN, 0.0, 0.0], [1.0, 1.0, 1.0]));
    }

    /// Two triangles over the unit square, with a ridge along the diagonal (0,0)-(1,1) of height `h`.
    fn square(h: f64) -> Tin {
        let p = vec![
            DVec3::new(0.0, 0.0, h),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, h),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        Tin::from_parts(p, vec![[0, 1, 2], [0, 2, 3]]).expect("square")
    }

    #[test]
    fn ridge_blocks_across_and_grazing_is_visible() {
        let tin = square(1.0);
        let loc = Locator::new(&tin);
        // Triangle 0 is the plane z = 1 - x + y, triangle 1 the plane z = 1 + x - y.
        let target = DVec3::new(0.9, 0.1, 0.2);
        // Eye low on the other side of the ridge: blocked.
        assert!(!point_visible(&tin, &loc, DVec3::new(0.1, 0.9, 0.5), target));
        // Eye high above: visible.
        assert!(point_visible(&tin, &loc, DVec3::new(0.1, 0.9, 10.0), target));
        // Eye on the ridge line itself (above the ridge): the segment crosses the ridge at the eye's side.
        assert!(point_visible(&tin, &loc, DVec3::new(0.5, 0.5, 1.0), target));
        // Exactly grazing the ridge at its midpoint: crossing at (0.5, 0.5) at height 0.5 exactly.
        let t2 = DVec3::new(1.0, 0.0, 0.0);
        let eye = DVec3::new(0.0, 1.0, 1.0);
        // The segment (1,0,0)->(0,1,1) crosses the ridge (z = 1 along it... h = 1 on the diagonal ends, linear)
        // at (0.5, 0.5) where the ridge is at height 1 and the segment at 0.5: blocked.
        assert!(!point_visible(&tin, &loc, eye, t2));
        let eye = DVec3::new(0.0, 1.0, 2.0);
        // Now the segment is at height 1 at the crossing: it touches the ridge exactly: visible.
        assert!(point_visible(&tin, &loc, eye, t2));
        let eye = DVec3::new(0.0, 1.0, 2.0 - 1e-3);
        assert!(!point_visible(&tin, &loc, eye, t2));
    }

    #[test]
    fn along_the_ridge_edge() {
        let tin = square(1.0);
        let loc = Locator::new(&tin);
        // Target at vertex 0 (height 1), eye beyond vertex 2 along the diagonal, outside the footprint.
        let target = DVec3::new(0.0, 0.0, 1.0);
        assert!(point_visible(&tin, &loc, DVec3::new(2.0, 2.0, 1.0), target));
        assert!(point_visible(&tin, &loc, DVec3::new(2.0, 2.0, 5.0), target));
        assert!(!point_visible(&tin, &loc, DVec3::new(2.0, 2.0, 0.5), target));
        // Target mid-edge on the ridge.
        let target = DVec3::new(0.5, 0.5, 1.0);
        assert!(point_visible(&tin, &loc, DVec3::new(1.0, 1.0, 1.0), target));
        assert!(!point_visible(&tin, &loc, DVec3::new(1.0, 1.0, 0.9), target));
    }

    #[test]
    fn vertical_and_non_finite() {
        let tin = square(1.0);
        let loc = Locator::new(&tin);
        let target = DVec3::new(0.75, 0.25, 0.5);
        assert!(point_visible(&tin, &loc, DVec3::new(0.75, 0.25, 3.0), target));
        assert!(!point_visible(&tin, &loc, DVec3::new(0.75, 0.25, 0.4), target));
        assert!(!point_visible(&tin, &loc, DVec3::new(f64::NAN, 0.25, 3.0), target));
        assert!(!point_visible(&tin, &loc, DVec3::new(0.5, 0.25, f64::INFINITY), target));
    }
}
