//! Point location in a TIN: a uniform grid of triangle bounding boxes, plus the footprint's boundary.
//!
//! The grid has about one cell per two triangles over the TIN's x,y bounding box; each cell lists, in increasing
//! order, the triangles whose bounding box meets it. [`Locator::locate`] tests the triangles of one cell with
//! Shewchuk's exact orientation predicate (the `robust` crate), so a point on a shared edge or vertex is found
//! deterministically (in the lowest-numbered triangle that contains it, boundary included).
//!
//! The locator also records the footprint's boundary edges and whether the footprint is convex, which the segment
//! walk ([`crate::walk`]) needs once a segment leaves the TIN: a segment that leaves a convex footprint never comes
//! back, otherwise the walk looks for the next boundary edge where it re-enters.

use glam::{DVec2, DVec3};
use tin::{NO_NEIGHBOUR, Tin, VertexTriangles};

/// Largest number of grid cells (keeps memory bounded for huge TINs).
const MAX_CELLS: usize = 1 << 22;

/// Exact orientation of `c` relative to the directed line `a -> b`: positive when `c` is on the left.
///
/// The sign is exact (Shewchuk's adaptive predicate); the magnitude is twice the signed area, to within rounding.
#[inline]
pub(crate) fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    robust::orient2d(
        robust::Coord { x: a.x, y: a.y },
        robust::Coord { x: b.x, y: b.y },
        robust::Coord { x: c.x, y: c.y },
    )
}

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

/// Whether `p` lies in the closed triangle `t` (exact).
#[inline]
pub(crate) fn triangle_contains(tin: &Tin, t: usize, p: DVec2) -> bool {
    let [a, b, c] = tin.corners(t).map(|q| q.truncate());
    orient(a, b, p) >= 0.0 && orient(b, c, p) >= 0.0 && orient(c, a, p) >= 0.0
}

/// An edge of the footprint's boundary: edge `edge` (from corner `edge` to corner `edge + 1`) of triangle `tri`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct BoundaryEdge {
    pub tri: u32,
    pub edge: u8,
}

/// A point locator for one [`Tin`]: uniform grid over triangle bounding boxes, vertex-triangle incidence and the
/// footprint boundary.
///
/// A locator belongs to the TIN it was built from; using it with another TIN gives meaningless (but never
/// out-of-bounds) answers only when both have the same counts, and [`Locator::matches`] tells the two apart
/// otherwise.
#[derive(Clone, Debug)]
pub struct Locator {
    num_vertices: usize,
    num_triangles: usize,
    min: DVec2,
    inv_cell: DVec2,
    nx: usize,
    ny: usize,
    cell_start: Vec<u32>,
    cell_tris: Vec<u32>,
    vertex_triangles: VertexTriangles,
    boundary: Vec<BoundaryEdge>,
    convex: bool,
}

impl Locator {
    /// Builds the locator of `tin` (O(triangles)).
    pub fn new(tin: &Tin) -> Locator {
        let bbox = tin.bbox();
        let min = bbox.min.truncate();
        let size = bbox.size().truncate().max(DVec2::splat(f64::MIN_POSITIVE));
        let cells = (tin.num_triangles() / 2).clamp(1, MAX_CELLS) as f64;
        let aspect = size.x / size.y;
        let nx = ((cells * aspect).sqrt().ceil() as usize).clamp(1, MAX_CELLS);
        let ny = ((cells / nx as f64).ceil() as usize).clamp(1, MAX_CELLS / nx);
        let inv_cell = DVec2::new(nx as f64 / size.x, ny as f64 / size.y);
        let mut loc = Locator {
            num_vertices: tin.num_vertices(),
            num_triangles: tin.num_triangles(),
            min,
            inv_cell,
            nx,
            ny,
            cell_start: Vec::new(),
            cell_tris: Vec::new(),
            vertex_triangles: tin.vertex_triangles(),
            boundary: Vec::new(),
            convex: false,
        };
        loc.fill_grid(tin);
        loc.boundary = boundary_edges(tin);
        loc.convex = footprint_is_convex(tin, &loc.boundary);
        loc
    }

    /// Whether this locator was plausibly built from `tin` (same vertex and triangle counts).
    pub fn matches(&self, tin: &Tin) -> bool {
        self.num_vertices == tin.num_vertices() && self.num_triangles == tin.num_triangles()
    }

    /// The triangle whose closed x,y footprint contains `p` (the lowest-numbered one when `p` is on a shared edge or
    /// vertex), or `None` outside the TIN.
    pub fn locate(&self, tin: &Tin, p: DVec2) -> Option<usize> {
        if !p.is_finite() || !self.matches(tin) {
            return None;
        }
        let (ix, iy) = self.cell_of(p)?;
        let cell = iy * self.nx + ix;
        let range = self.cell_start[cell] as usize..self.cell_start[cell + 1] as usize;
        self.cell_tris[range]
            .iter()
            .map(|&t| t as usize)
            .find(|&t| triangle_contains(tin, t, p))
    }

    /// Terrain height at `p` (the plane of the triangle that [`Locator::locate`] finds), or `None` outside the TIN.
    pub fn ground_height(&self, tin: &Tin, p: DVec2) -> Option<f64> {
        self.locate(tin, p).map(|t| plane_height(&tin.corners(t), p))
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

    pub(crate) fn vertex_triangles(&self) -> &VertexTriangles {
        &self.vertex_triangles
    }

    pub(crate) fn boundary(&self) -> &[BoundaryEdge] {
        &self.boundary
    }

    /// Grid cell of `p`, or `None` when `p` is outside the bounding box.
    fn cell_of(&self, p: DVec2) -> Option<(usize, usize)> {
        let r = (p - self.min) * self.inv_cell;
        if r.x < 0.0 || r.y < 0.0 || r.x > self.nx as f64 || r.y > self.ny as f64 {
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

    fn fill_grid(&mut self, tin: &Tin) {
        let ncells = self.nx * self.ny;
        let ranges: Vec<((usize, usize), (usize, usize))> = (0..tin.num_triangles())
            .map(|t| {
                let [a, b, c] = tin.corners(t).map(|q| q.truncate());
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
        for (t, &((x0, y0), (x1, y1))) in ranges.iter().enumerate() {
            for iy in y0..=y1 {
                for ix in x0..=x1 {
                    let cell = iy * self.nx + ix;
                    tris[fill[cell] as usize] = t as u32;
                    fill[cell] += 1;
                }
            }
        }
        self.cell_start = counts;
        self.cell_tris = tris;
    }
}

/// All boundary edges, in triangle order.
fn boundary_edges(tin: &Tin) -> Vec<BoundaryEdge> {
    tin.neighbours()
        .iter()
        .enumerate()
        .flat_map(|(t, n)| {
            (0..3u8)
                .filter(move |&i| n[i as usize] == NO_NEIGHBOUR)
                .map(move |edge| BoundaryEdge { tri: t as u32, edge })
        })
        .collect()
}

/// One boundary loop, no pinched vertex, and no right turn along it.
fn footprint_is_convex(tin: &Tin, boundary: &[BoundaryEdge]) -> bool {
    if boundary.is_empty() {
        return false;
    }
    let ends = |e: &BoundaryEdge| {
        let tri = tin.triangles()[e.tri as usize];
        (tri[e.edge as usize], tri[(e.edge as usize + 1) % 3])
    };
    // next[v] = boundary edge starting at v; a vertex starting two boundary edges is pinched.
    let mut next = vec![u32::MAX; tin.num_vertices()];
    for (i, e) in boundary.iter().enumerate() {
        let (a, _) = ends(e);
        if next[a as usize] != u32::MAX {
            return false;
        }
        next[a as usize] = i as u32;
    }
    let mut i = 0usize;
    for _ in 0..boundary.len() {
        let (a, b) = ends(&boundary[i]);
        let j = next[b as usize];
        if j == u32::MAX {
            return false;
        }
        let (_, c) = ends(&boundary[j as usize]);
        let [pa, pb, pc] = [a, b, c].map(|v| tin.position(v).truncate());
        if orient(pa, pb, pc) < 0.0 {
            return false;
        }
        i = j as usize;
    }
    // Back at the start after exactly |boundary| steps, and no shorter loop: one loop.
    if i != 0 {
        return false;
    }
    let mut len = 0;
    let mut k = 0usize;
    loop {
        let (_, b) = ends(&boundary[k]);
        k = next[b as usize] as usize;
        len += 1;
        if k == 0 || len > boundary.len() {
            break;
        }
    }
    len == boundary.len()
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
    fn ground_height_is_the_plane() {
        let tin = grid_tin(5);
        let loc = Locator::new(&tin);
        for (v, p) in tin.positions().iter().enumerate() {
            let z = loc.ground_height(&tin, p.truncate()).expect("vertex inside");
            assert!((z - p.z).abs() < 1e-12, "vertex {v}");
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
    }
}
