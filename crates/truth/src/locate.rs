//! Point location in a TIN and the triangle layout of the segment walk.
//!
//! A uniform grid over the TIN's x,y bounding box (about one cell per two triangles) lists in each cell the
//! triangles whose bounding box meets it. [`Locator::locate`] tests the triangles of one cell with Shewchuk's exact
//! orientation predicate ([`tin::orient2d`], through the `robust` crate), so a point on a shared edge or vertex is
//! found deterministically (always the same one of the triangles that contain it, boundary included).
//!
//! For speed the walk ([`crate::walk`]) does not read the [`Tin`] directly: the locator keeps a copy of the triangles
//! in Morton order of their centroids, one record per triangle with corners, vertex ids and neighbours, so that a
//! walk from neighbour to neighbour mostly reads memory it has just read (about twice as fast on 200k triangles as
//! following the TIN's own order). Indices given to and returned by the public functions are always the TIN's.
//!
//! The locator also records the footprint's boundary edges and whether the footprint is convex, which the walk needs
//! once a segment leaves the TIN: a segment that leaves a convex footprint never comes back, otherwise the walk
//! looks for the next boundary edge where it re-enters.

use glam::{DVec2, DVec3};
use tin::{NO_NEIGHBOUR, Tin};

/// Largest number of grid cells (keeps memory bounded for huge TINs).
const MAX_CELLS: usize = 1 << 22;

/// Exact orientation of `c` relative to the directed line `a -> b`: positive when `c` is on the left (the project's
/// one predicate, [`tin::orient2d`]).
pub(crate) use tin::orient2d as orient;

/// Height at `p` of the plane through the three corners `[a, b, c]` (non-degenerate in x,y).
#[inline]
pub(crate) fn plane_height(corners: &[DVec3; 3], p: DVec2) -> f64 {
    let [a, b, c] = *corners;
    let u = (b - a).truncate();
    let v = (c - a).truncate();
    let w = p - a.truncate();
    let det = u.perp_dot(v);
    let beta = w.perp_dot(v) / det;
    let gamma = u.perp_dot(w) / det;
    a.z + beta * (b.z - a.z) + gamma * (c.z - a.z)
}

/// [`plane_height`] at a point `p` of the closed triangle `corners` (the caller checks that exactly), with a bound on
/// its rounding error: `(height, error)`, the exact height of the triangle's plane at `p` within `error` of `height`.
/// `None` when the triangle is too near degenerate for a bound: its computed doubled area is not above twice the
/// bound on its own rounding (a triangle whose corners are collinear but for a few ulps, whose plane's height swings
/// by kilometres with the last bits of `p`).
///
/// Proof, with `E = 2⁻⁵³` (the unit roundoff: `fl(x ∘ y) = (x ∘ y)(1 + θ)`, `|θ| ≤ E`) and exact `U = b − a`,
/// `V = c − a`, `W = p − a` (x,y), `D = U × V`, `N_b = W × V`, `N_c = U × W` (`X × Y = X.x Y.y − X.y Y.x`), so that the
/// exact height is `h = a.z + β Δ_b + γ Δ_c` with `β = N_b / D`, `γ = N_c / D`, `Δ_b = b.z − a.z`, `Δ_c = c.z − a.z`:
///
/// 1. Each computed cross product rounds its two differences, its two products and their difference:
///    `|fl(X × Y) − X × Y| ≤ γ₄ (|X.x Y.y| + |X.y Y.x|)`, `γ₄ = 4E / (1 − 4E)`. The sums `S` of those two magnitudes,
///    computed from the rounded terms, are at least the exact ones times `(1 − E)⁵`, so `8 E S` (computed, itself
///    rounded by a few `E` relative) bounds that error: `e_D`, `e_b`, `e_c` below.
/// 2. With `d = |fl(D)| > 2 (e_D + max(e_b, e_c))` (else `None`) and `|β| ≤ 1` (`p` is in the closed triangle, so
///    `β, γ ∈ [0, 1]`): `|Ñ_b / D̃ − β| = |(Ñ_b − N_b) − β (D̃ − D)| / d ≤ (e_b + e_D) / d = r < 1/2`, so
///    `|Ñ_b / D̃| < 1.5` and the division adds at most `1.5 E`: `|β̃ − β| ≤ r + 2E = e_β`; the same for `γ`.
/// 3. `h̃ = fl(fl(a.z + fl(β̃ Δ̃_b)) + fl(γ̃ Δ̃_c))` with `Δ̃ = Δ (1 + θ)`: each product is off by at most
///    `e_β |Δ_b| + 1.5 · 2.01 E |Δ_b|` (and the same with `γ`, `Δ_c`), the two sums by `E` of their values, at most
///    `E (|a.z| + 1.5 |Δ_b|)` and `E (|a.z| + 1.5 |Δ_b| + 1.5 |Δ_c|)` (times `1 + E`). In all
///    `|h̃ − h| ≤ e_β |Δ_b| + e_γ |Δ_c| + 8 E (|a.z| + |Δ_b| + |Δ_c|)`; the bound returned uses the computed `|Δ̃|`
///    (`|Δ| ≤ |Δ̃| (1 + 2E)`, covered by the factor `1 + 4E`) and twice that last term, and is widened by a relative
///    `1e-6`, far more than the few roundings of its own evaluation.
pub(crate) fn plane_height_bounded(corners: &[DVec3; 3], p: DVec2) -> Option<(f64, f64)> {
    const E: f64 = f64::EPSILON / 2.0;
    let [a, b, c] = *corners;
    let u = (b - a).truncate();
    let v = (c - a).truncate();
    let w = p - a.truncate();
    let e_d = 8.0 * E * ((u.x * v.y).abs() + (u.y * v.x).abs());
    let e_b = 8.0 * E * ((w.x * v.y).abs() + (w.y * v.x).abs());
    let e_c = 8.0 * E * ((u.x * w.y).abs() + (u.y * w.x).abs());
    let d = u.perp_dot(v).abs();
    // A NaN goes on to a NaN error, refused below.
    if d <= 2.0 * (e_d + e_b.max(e_c)) {
        return None;
    }
    let e_beta = (e_b + e_d) / d + 2.0 * E;
    let e_gamma = (e_c + e_d) / d + 2.0 * E;
    let (dz_b, dz_c) = ((b.z - a.z).abs(), (c.z - a.z).abs());
    let error = ((e_beta * dz_b + e_gamma * dz_c) * (1.0 + 4.0 * E) + 8.0 * E * (a.z.abs() + 2.0 * (dz_b + dz_c)))
        * (1.0 + 1e-6);
    let height = plane_height(corners, p);
    (height.is_finite() && error.is_finite()).then_some((height, error))
}

/// Whether `p` lies in the closed triangle with corners `c` (counter-clockwise in x,y; exact).
#[inline]
pub(crate) fn corners_contain(c: &[DVec3; 3], p: DVec2) -> bool {
    let [a, b, c] = c.map(|q| q.truncate());
    orient(a, b, p) >= 0.0 && orient(b, c, p) >= 0.0 && orient(c, a, p) >= 0.0
}

/// The terrain's height under each of `points` (x,y), or `None` outside the mesh, from a mesh given as its vertex
/// positions and counter-clockwise triangles (a [`Tin`]'s, or a hierarchy's): the plane of a closed triangle that
/// holds the point (exactly, [`tin::orient2d`]; the first such triangle in mesh order). One pass over the triangles,
/// with the points sorted by x: O(triangles · log points + matches), without building a [`Locator`], for the few
/// points of a command line (an eye to check against the ground).
pub fn ground_heights(positions: &[[f64; 3]], triangles: &[[u32; 3]], points: &[DVec2]) -> Vec<Option<f64>> {
    let mut by_x: Vec<u32> = (0..points.len() as u32)
        .filter(|&i| points[i as usize].is_finite())
        .collect();
    by_x.sort_by(|&a, &b| points[a as usize].x.total_cmp(&points[b as usize].x));
    let mut out = vec![None; points.len()];
    for tri in triangles {
        let [Some(a), Some(b), Some(c)] = tri.map(|v| positions.get(v as usize).map(|p| DVec3::from_array(*p))) else {
            continue;
        };
        let c = [a, b, c];
        let (lo, hi) = (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]));
        let first = by_x.partition_point(|&i| points[i as usize].x < lo.x);
        for &i in by_x[first..].iter().take_while(|&&i| points[i as usize].x <= hi.x) {
            let p = points[i as usize];
            if out[i as usize].is_none() && p.y >= lo.y && p.y <= hi.y && corners_contain(&c, p) {
                // A triangle of zero area (none in a valid mesh) gives no height.
                out[i as usize] = Some(plane_height(&c, p)).filter(|h| h.is_finite());
            }
        }
    }
    out
}

/// One triangle as the walk sees it: corner positions, vertex ids (of the [`Tin`]) and neighbours (walk indices,
/// [`NO_NEIGHBOUR`] on the boundary), in one record so that a walk step touches one place in memory.
#[derive(Clone, Copy, Debug)]
pub(crate) struct WalkTri {
    /// Corner positions, counter-clockwise in x,y.
    pub p: [DVec3; 3],
    /// Vertex ids of the corners.
    pub v: [u32; 3],
    /// Neighbour across edge `i` (corner `i` to `i + 1`), as a walk index.
    pub n: [u32; 3],
}

/// An edge of the footprint's boundary: edge `edge` (from corner `edge` to corner `edge + 1`) of walk triangle `tri`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct BoundaryEdge {
    pub tri: u32,
    pub edge: u8,
}

/// A point locator for one [`Tin`], and the TIN's triangles laid out for segment walks.
///
/// - A uniform grid over the triangles' bounding boxes (about one cell per two triangles) finds the triangle that
///   contains a point.
/// - The triangles are stored again in Morton (Z-curve) order of their centroids, each as one record with its corner
///   positions, vertex ids and neighbours, so that a walk, which moves between neighbours, mostly stays within
///   memory it has just touched. Results are always reported in the TIN's own triangle order.
/// - The footprint's boundary edges and whether it is convex.
///
/// A locator belongs to the TIN it was built from: [`Locator::matches`] checks the vertex and triangle counts, and
/// the functions of this crate rebuild the locator when they do not match rather than read out of bounds.
#[derive(Clone, Debug)]
pub struct Locator {
    num_vertices: usize,
    num_triangles: usize,
    min: DVec2,
    max: DVec2,
    inv_cell: DVec2,
    nx: usize,
    ny: usize,
    cell_start: Vec<u32>,
    cell_tris: Vec<u32>,
    tris: Vec<WalkTri>,
    walk_of: Vec<u32>,
    tin_of: Vec<u32>,
    vertex_start: Vec<u32>,
    vertex_tris: Vec<u32>,
    boundary: Vec<BoundaryEdge>,
    convex: bool,
}

impl Locator {
    /// Builds the locator of `tin` (O(triangles log triangles)).
    pub fn new(tin: &Tin) -> Locator {
        let bbox = tin.bbox();
        let min = bbox.min.truncate();
        let size = bbox.size().truncate().max(DVec2::splat(f64::MIN_POSITIVE));
        let nt = tin.num_triangles();
        let cells = (nt / 2).clamp(1, MAX_CELLS) as f64;
        let aspect = size.x / size.y;
        let nx = ((cells * aspect).sqrt().ceil() as usize).clamp(1, MAX_CELLS);
        let ny = ((cells / nx as f64).ceil() as usize).clamp(1, MAX_CELLS / nx);
        let inv_cell = DVec2::new(nx as f64 / size.x, ny as f64 / size.y);

        // Walk order: Morton code of the centroid, ties by TIN index.
        let morton = |t: usize| {
            let c = tin.corners(t).iter().map(|p| p.truncate()).sum::<DVec2>() / 3.0;
            let r = ((c - min) / size).clamp(DVec2::ZERO, DVec2::ONE) * 65535.0;
            interleave(r.x as u32) | (interleave(r.y as u32) << 1)
        };
        let mut tin_of: Vec<u32> = (0..nt as u32).collect();
        let keys: Vec<u32> = (0..nt).map(morton).collect();
        tin_of.sort_by_key(|&t| (keys[t as usize], t));
        let mut walk_of = vec![0u32; nt];
        for (w, &t) in tin_of.iter().enumerate() {
            walk_of[t as usize] = w as u32;
        }
        let tris: Vec<WalkTri> = tin_of
            .iter()
            .map(|&t| {
                let t = t as usize;
                WalkTri {
                    p: tin.corners(t),
                    v: tin.triangles()[t],
                    n: tin.neighbours()[t].map(|n| {
                        if n == NO_NEIGHBOUR {
                            NO_NEIGHBOUR
                        } else {
                            walk_of[n as usize]
                        }
                    }),
                }
            })
            .collect();

        let vt = tin.vertex_triangles();
        let vertex_start = vt.offsets.clone();
        let vertex_tris = vt.indices.iter().map(|&t| walk_of[t as usize]).collect();

        let mut loc = Locator {
            num_vertices: tin.num_vertices(),
            num_triangles: nt,
            min,
            max: bbox.max.truncate(),
            inv_cell,
            nx,
            ny,
            cell_start: Vec::new(),
            cell_tris: Vec::new(),
            tris,
            walk_of,
            tin_of,
            vertex_start,
            vertex_tris,
            boundary: Vec::new(),
            convex: false,
        };
        loc.fill_grid();
        loc.boundary = boundary_edges(&loc.tris);
        loc.convex = footprint_is_convex(tin.num_vertices(), &loc.tris, &loc.boundary);
        loc
    }

    /// Whether this locator was plausibly built from `tin` (same vertex and triangle counts).
    pub fn matches(&self, tin: &Tin) -> bool {
        self.num_vertices == tin.num_vertices() && self.num_triangles == tin.num_triangles()
    }

    /// The triangle (TIN index) whose closed x,y footprint contains `p`, or `None` outside the TIN. When `p` is on
    /// an edge or vertex shared by several triangles, one of them is returned, always the same one.
    pub fn locate(&self, tin: &Tin, p: DVec2) -> Option<usize> {
        if !self.matches(tin) {
            return None;
        }
        self.locate_walk(p).map(|w| self.tin_of[w as usize] as usize)
    }

    /// Terrain height at `p` (the plane of the triangle that [`Locator::locate`] finds), or `None` outside the TIN.
    pub fn ground_height(&self, tin: &Tin, p: DVec2) -> Option<f64> {
        if !self.matches(tin) {
            return None;
        }
        self.locate_walk(p).map(|w| plane_height(&self.tris[w as usize].p, p))
    }

    /// Whether the TIN's footprint is convex (one boundary loop turning left or straight at every vertex), as for
    /// any Delaunay triangulation of a point set.
    pub fn footprint_is_convex(&self) -> bool {
        self.convex
    }

    /// Number of edges on the footprint's boundary.
    pub fn num_boundary_edges(&self) -> usize {
        self.boundary.len()
    }

    /// The walk triangle containing `p` (closed), or `None`.
    pub(crate) fn locate_walk(&self, p: DVec2) -> Option<u32> {
        if !p.is_finite() {
            return None;
        }
        let (ix, iy) = self.cell_of(p)?;
        let cell = iy * self.nx + ix;
        let range = self.cell_start[cell] as usize..self.cell_start[cell + 1] as usize;
        self.cell_tris[range]
            .iter()
            .copied()
            .find(|&w| corners_contain(&self.tris[w as usize].p, p))
    }

    /// Walk triangles, in walk order.
    pub(crate) fn tris(&self) -> &[WalkTri] {
        &self.tris
    }

    /// Walk index of TIN triangle `t` (`None` out of range).
    pub(crate) fn walk_index(&self, t: usize) -> Option<u32> {
        self.walk_of.get(t).copied()
    }

    /// Walk triangles around vertex `v`.
    pub(crate) fn vertex_tris(&self, v: u32) -> &[u32] {
        let v = v as usize;
        match (self.vertex_start.get(v), self.vertex_start.get(v + 1)) {
            (Some(&a), Some(&b)) => &self.vertex_tris[a as usize..b as usize],
            _ => &[],
        }
    }

    pub(crate) fn boundary(&self) -> &[BoundaryEdge] {
        &self.boundary
    }

    /// Grid cell of `p`, or `None` when `p` is outside the bounding box.
    fn cell_of(&self, p: DVec2) -> Option<(usize, usize)> {
        if p.x < self.min.x || p.y < self.min.y || p.x > self.max.x || p.y > self.max.y {
            return None;
        }
        Some(self.clamped_cell(p))
    }

    /// Grid cell of `p` clamped into the grid; monotone in each coordinate.
    fn clamped_cell(&self, p: DVec2) -> (usize, usize) {
        let r = (p - self.min) * self.inv_cell;
        let ix = (r.x.floor().max(0.0) as usize).min(self.nx - 1);
        let iy = (r.y.floor().max(0.0) as usize).min(self.ny - 1);
        (ix, iy)
    }

    fn fill_grid(&mut self) {
        let ncells = self.nx * self.ny;
        let ranges: Vec<((usize, usize), (usize, usize))> = self
            .tris
            .iter()
            .map(|tri| {
                let [a, b, c] = tri.p.map(|q| q.truncate());
                (self.clamped_cell(a.min(b).min(c)), self.clamped_cell(a.max(b).max(c)))
            })
            .collect();
        let mut counts = vec![0u32; ncells + 1];
        for &((x0, y0), (x1, y1)) in &ranges {
            for iy in y0..=y1 {
                for ix in x0..=x1 {
                    counts[iy * self.nx + ix + 1] += 1;
                }
            }
        }
        for i in 0..ncells {
            counts[i + 1] += counts[i];
        }
        let mut fill = counts.clone();
        let mut tris = vec![0u32; counts[ncells] as usize];
        for (w, &((x0, y0), (x1, y1))) in ranges.iter().enumerate() {
            for iy in y0..=y1 {
                for ix in x0..=x1 {
                    let cell = iy * self.nx + ix;
                    tris[fill[cell] as usize] = w as u32;
                    fill[cell] += 1;
                }
            }
        }
        self.cell_start = counts;
        self.cell_tris = tris;
    }
}

/// Spreads the low 16 bits of `x` to the even bit positions.
fn interleave(x: u32) -> u32 {
    let mut x = x & 0xffff;
    x = (x | (x << 8)) & 0x00ff_00ff;
    x = (x | (x << 4)) & 0x0f0f_0f0f;
    x = (x | (x << 2)) & 0x3333_3333;
    (x | (x << 1)) & 0x5555_5555
}

/// All boundary edges, in walk order.
fn boundary_edges(tris: &[WalkTri]) -> Vec<BoundaryEdge> {
    tris.iter()
        .enumerate()
        .flat_map(|(w, tri)| {
            (0..3u8)
                .filter(move |&i| tri.n[i as usize] == NO_NEIGHBOUR)
                .map(move |edge| BoundaryEdge { tri: w as u32, edge })
        })
        .collect()
}

/// One boundary loop, no pinched vertex, and no right turn along it.
fn footprint_is_convex(num_vertices: usize, tris: &[WalkTri], boundary: &[BoundaryEdge]) -> bool {
    if boundary.is_empty() {
        return false;
    }
    let ends = |e: &BoundaryEdge| {
        let tri = &tris[e.tri as usize];
        let (i, j) = (e.edge as usize, (e.edge as usize + 1) % 3);
        (tri.v[i], tri.v[j], tri.p[i].truncate(), tri.p[j].truncate())
    };
    // next[v] = boundary edge starting at v; a vertex starting two boundary edges is pinched.
    let mut next = vec![u32::MAX; num_vertices];
    for (i, e) in boundary.iter().enumerate() {
        let (a, ..) = ends(e);
        if next[a as usize] != u32::MAX {
            return false;
        }
        next[a as usize] = i as u32;
    }
    // Follow the loop from edge 0: it must come back after exactly |boundary| edges, turning left or straight.
    let mut i = 0usize;
    for step in 0..boundary.len() {
        let (_, b, pa, pb) = ends(&boundary[i]);
        let j = next[b as usize];
        if j == u32::MAX {
            return false;
        }
        let (.., pc) = ends(&boundary[j as usize]);
        if orient(pa, pb, pc) < 0.0 {
            return false;
        }
        i = j as usize;
        if i == 0 && step + 1 < boundary.len() {
            return false;
        }
    }
    i == 0
}

#[cfg(test)]
mod tests {
    use super::*;
    use tin::{DedupePolicy, triangulate};

    fn grid_tin(n: usize) -> Tin {
        let pts: Vec<DVec3> = (0..n * n)
            .map(|i| DVec3::new((i % n) as f64, (i / n) as f64, ((i * 7) % 5) as f64))
            .collect();
        triangulate(&pts, DedupePolicy::Reject).expect("grid").0
    }

    #[test]
    fn locates_every_centroid_and_rejects_outside() {
        let tin = grid_tin(9);
        let loc = Locator::new(&tin);
        for t in 0..tin.num_triangles() {
            let c = tin.corners(t).iter().map(|p| p.truncate()).sum::<DVec2>() / 3.0;
            assert_eq!(loc.locate(&tin, c), Some(t));
        }
        assert_eq!(loc.locate(&tin, DVec2::new(-0.1, 3.0)), None);
        assert_eq!(loc.locate(&tin, DVec2::new(8.0001, 3.0)), None);
        assert_eq!(loc.locate(&tin, DVec2::new(f64::NAN, 3.0)), None);
        // Corners of the footprint are inside (closed triangles).
        assert!(loc.locate(&tin, DVec2::new(8.0, 8.0)).is_some());
        assert!(loc.footprint_is_convex());
        assert_eq!(loc.num_boundary_edges(), 32);
    }

    #[test]
    fn vertices_on_the_bounding_box_edge_are_located() {
        // (p.x - min.x) * (nx / size.x) can round above nx for the largest x: the bounding-box test must not scale.
        let pts: Vec<DVec3> = [
            (8.156624807949786, 0.0),
            (29.729122177091924, 12.60582476815652),
            (73.20491810439292, 66.0112775111784),
            (98.89484077348024, 8.211054437121584),
            (56.63987684829212, 57.67675456863607),
            (10.580489938960318, 0.0),
            (79.51829885705037, 67.55058638655619),
        ]
        .iter()
        .map(|&(x, y)| DVec3::new(x, y, 1.0))
        .collect();
        for n in 1..pts.len() - 2 {
            let (tin, _) = triangulate(&pts[..n + 3], DedupePolicy::Reject).expect("points");
            let loc = Locator::new(&tin);
            for p in tin.positions() {
                assert!(
                    loc.locate(&tin, p.truncate()).is_some(),
                    "vertex {p} of {} points",
                    n + 3
                );
            }
        }
    }

    #[test]
    fn ground_height_is_the_plane() {
        let tin = grid_tin(5);
        let loc = Locator::new(&tin);
        for (v, p) in tin.positions().iter().enumerate() {
            let z = loc.ground_height(&tin, p.truncate()).expect("vertex inside");
            assert!((z - p.z).abs() < 1e-12, "vertex {v}");
        }
    }

    proptest::proptest! {
        /// The one-pass heights agree with the locator's: the same footprint (`None` exactly outside it, the L's notch
        /// included) and the same plane up to rounding (on a shared edge both triangles' planes hold the point).
        #[test]
        fn ground_heights_agree_with_the_locator(
            n in 2usize..9,
            points in proptest::collection::vec((-1.0f64..9.0, -1.0f64..9.0), 1..40),
        ) {
            let tin = grid_tin(n);
            let loc = Locator::new(&tin);
            let mut xy: Vec<DVec2> = points.iter().map(|&(x, y)| DVec2::new(x, y)).collect();
            // Vertices and edge midpoints too, and a NaN.
            xy.extend(tin.positions().iter().take(5).map(|p| p.truncate()));
            xy.push(DVec2::new(0.5, 0.0));
            xy.push(DVec2::new(f64::NAN, 1.0));
            let positions: Vec<[f64; 3]> = tin.positions().iter().map(|p| p.to_array()).collect();
            let heights = ground_heights(&positions, tin.triangles(), &xy);
            for (p, h) in xy.iter().zip(heights) {
                match (h, loc.ground_height(&tin, *p)) {
                    (None, None) => {}
                    (Some(a), Some(b)) => {
                        proptest::prop_assert!((a - b).abs() <= 1e-12 * (1.0 + b.abs()), "{p}: {a} {b}")
                    }
                    (a, b) => proptest::prop_assert!(false, "{p}: {a:?} {b:?}"),
                }
            }
        }
    }

    #[test]
    fn l_shape_is_not_convex() {
        // An L made of three unit squares.
        let p = [(0, 0), (1, 0), (2, 0), (0, 1), (1, 1), (2, 1), (0, 2), (1, 2)]
            .map(|(x, y)| DVec3::new(x as f64, y as f64, 0.0))
            .to_vec();
        let tris = vec![[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [3, 4, 7], [3, 7, 6]];
        let tin = Tin::from_parts(p, tris).expect("valid L");
        let loc = Locator::new(&tin);
        assert!(!loc.footprint_is_convex());
        assert_eq!(loc.locate(&tin, DVec2::new(1.5, 1.5)), None);
        assert_eq!(loc.locate(&tin, DVec2::new(1.5, 0.5)), Some(2));
        let positions: Vec<[f64; 3]> = tin.positions().iter().map(|p| p.to_array()).collect();
        let notch = [DVec2::new(1.5, 1.5), DVec2::new(1.5, 0.5), DVec2::new(1.0, 2.0)];
        assert_eq!(
            ground_heights(&positions, tin.triangles(), &notch),
            vec![None, Some(0.0), Some(0.0)]
        );
    }

    proptest::proptest! {
        /// [`plane_height_bounded`] against the exact height: corners at integer coordinates (some triangles nearly
        /// flat: the third corner on the line through the first two but for a unit or two, or exactly on it), the
        /// point at barycentric weights in 256ths, so its x,y is exact and its height is exactly
        /// `a.z + (w_b Δ_b + w_c Δ_c) / 256`. The bound holds whenever a height is given, a height is given for every
        /// triangle that is not nearly flat, and there its bound is tiny.
        #[test]
        fn the_plane_height_bound_holds(
            a in proptest::array::uniform3(-4096i32..4096),
            b in proptest::array::uniform3(-4096i32..4096),
            c in proptest::array::uniform3(-4096i32..4096),
            along in -8i32..8,
            off in proptest::array::uniform2(-2i32..=2),
            flat in proptest::bool::ANY,
            w in (0u32..=256, 0u32..=256),
            scale in 0u32..3,
        ) {
            let f = |p: [i32; 3]| DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]));
            let (a, b) = (f(a), f(b));
            let c = if flat {
                // On the line a-b (`along` steps of b - a) but for `off`.
                let d = b - a;
                DVec3::new(
                    a.x + f64::from(along) * d.x + f64::from(off[0]),
                    a.y + f64::from(along) * d.y + f64::from(off[1]),
                    f64::from(c[2]),
                )
            } else {
                f(c)
            };
            // Coordinates far from the origin too (UTM-like), where differences of nearby corners are still exact.
            let shift = DVec3::new(f64::from(scale) * 500_000.0, f64::from(scale) * 4_000_000.0, 0.0);
            let (a, b, c) = (a + shift, b + shift, c + shift);
            let (wb, wc) = if w.0 + w.1 > 256 { (256 - w.0, 256 - w.1) } else { w };
            let p = a.truncate() + (b - a).truncate() * (f64::from(wb) / 256.0) + (c - a).truncate() * (f64::from(wc) / 256.0);
            // The weights are exact in 256ths and every coordinate below 2^25: p is exact.
            let exact = a.z + ((b.z - a.z) * f64::from(wb) + (c.z - a.z) * f64::from(wc)) / 256.0;
            let area = (b - a).truncate().perp_dot((c - a).truncate());
            let corners = if area < 0.0 { [a, c, b] } else { [a, b, c] };
            match plane_height_bounded(&corners, p) {
                Some((height, error)) => {
                    proptest::prop_assert!(
                        (height - exact).abs() <= error,
                        "height {height}, exact {exact}, error bound {error}"
                    );
                    if !flat {
                        proptest::prop_assert!(error <= 1e-6 * (1.0 + a.z.abs() + b.z.abs() + c.z.abs()));
                    }
                }
                None => {
                    let sides = (b - a).truncate().length() * (c - a).truncate().length();
                    proptest::prop_assert!(area.abs() <= 1e-6 * sides, "no height for a triangle of area {area}");
                }
            }
        }
    }
}
