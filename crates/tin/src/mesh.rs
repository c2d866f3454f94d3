//! The [`Tin`] type: an f64 height-field triangle mesh with edge adjacency.

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use crate::error::{Result, TinError};
use crate::predicates::orient2d;

/// Marks a triangle edge with no neighbour (a boundary edge) in [`Tin::neighbours`].
pub const NO_NEIGHBOUR: u32 = u32::MAX;

/// Axis-aligned bounding box in world coordinates.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Aabb {
    /// Smallest x, y, z.
    pub min: DVec3,
    /// Largest x, y, z.
    pub max: DVec3,
}

impl Aabb {
    /// The box of a set of points; `None` when empty.
    pub fn of_points(points: impl IntoIterator<Item = DVec3>) -> Option<Aabb> {
        let mut it = points.into_iter();
        let first = it.next()?;
        Some(it.fold(Aabb { min: first, max: first }, |b, p| Aabb {
            min: b.min.min(p),
            max: b.max.max(p),
        }))
    }

    /// Extent along each axis.
    pub fn size(&self) -> DVec3 {
        self.max - self.min
    }

    /// Area of the box's footprint in x,y (m²).
    pub fn footprint_area(&self) -> f64 {
        let s = self.size();
        s.x * s.y
    }
}

/// A circle in the x,y plane.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Circle {
    /// Centre in world x,y.
    pub centre: DVec2,
    /// Radius (m).
    pub radius: f64,
}

/// A triangulated irregular network: unique x,y per vertex, non-degenerate triangles that are counter-clockwise in
/// x,y and do not overlap, with per-edge neighbours.
///
/// Positions are absolute world coordinates in f64. [`Tin::origin`] is a local origin to subtract before anything is
/// converted to f32.
#[derive(Clone, Debug, PartialEq)]
pub struct Tin {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    neighbours: Vec<[u32; 3]>,
    origin: DVec3,
}

impl Tin {
    /// Builds a TIN from vertex positions and triangles, checking indices, non-degeneracy, orientation and
    /// manifold edges, and computing adjacency.
    ///
    /// Triangles must all be counter-clockwise in x,y, or all clockwise (then every triangle is flipped).
    /// Overlap in x,y is not checked here; see [`crate::validate()`].
    pub fn from_parts(positions: Vec<DVec3>, mut triangles: Vec<[u32; 3]>) -> Result<Tin> {
        for (index, p) in positions.iter().enumerate() {
            if !p.is_finite() {
                return Err(TinError::NonFinite {
                    index,
                    x: p.x,
                    y: p.y,
                    z: p.z,
                });
            }
        }
        if triangles.is_empty() {
            return Err(TinError::TooFewPoints("the mesh has no triangles".into()));
        }
        let n = positions.len();
        // Whether triangle `t` is counter-clockwise, or the first thing wrong with it.
        let orientation = |t: usize, tri: &[u32; 3]| -> Result<bool> {
            for &v in tri {
                if v as usize >= n {
                    return Err(TinError::IndexOutOfRange {
                        triangle: t,
                        vertex: u64::from(v),
                        vertices: n,
                    });
                }
            }
            let [a, b, c] = *tri;
            let o = orient2d(
                positions[a as usize].truncate(),
                positions[b as usize].truncate(),
                positions[c as usize].truncate(),
            );
            if o == 0.0 || a == b || b == c || a == c {
                return Err(TinError::DegenerateTriangle { triangle: t, a, b, c });
            }
            Ok(o > 0.0)
        };
        let first_ccw = orientation(0, &triangles[0])?;
        // Every triangle is checked on its own (in parallel) and the error of the smallest index is reported, which
        // is the one a scan in order would meet first.
        let first_error =
            triangles
                .par_iter()
                .enumerate()
                .skip(1)
                .find_map_first(|(t, tri)| match orientation(t, tri) {
                    Ok(ccw) if ccw != first_ccw => Some(TinError::InconsistentOrientation { triangle: t }),
                    Ok(_) => None,
                    Err(e) => Some(e),
                });
        if let Some(e) = first_error {
            return Err(e);
        }
        if !first_ccw {
            for tri in &mut triangles {
                tri.swap(1, 2);
            }
        }
        let neighbours = compute_neighbours(&triangles)?;
        let origin = local_origin(&positions);
        Ok(Tin {
            positions,
            triangles,
            neighbours,
            origin,
        })
    }

    /// Vertex positions in world coordinates.
    pub fn positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// Position of vertex `v`.
    pub fn position(&self, v: u32) -> DVec3 {
        self.positions[v as usize]
    }

    /// Triangles as counter-clockwise vertex index triples.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Neighbour triangles: `neighbours()[t][i]` lies across the edge from corner `i` to corner `(i + 1) % 3` of
    /// triangle `t`, or is [`NO_NEIGHBOUR`] on the boundary.
    pub fn neighbours(&self) -> &[[u32; 3]] {
        &self.neighbours
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// The local origin: a round point near the centre of the bounding box, to subtract before converting to f32.
    pub fn origin(&self) -> DVec3 {
        self.origin
    }

    /// Bounding box of all vertices.
    pub fn bbox(&self) -> Aabb {
        Aabb::of_points(self.positions.iter().copied()).unwrap_or(Aabb {
            min: DVec3::ZERO,
            max: DVec3::ZERO,
        })
    }

    /// The three corner positions of triangle `t`.
    pub fn corners(&self, t: usize) -> [DVec3; 3] {
        self.triangles[t].map(|v| self.positions[v as usize])
    }

    /// Area of triangle `t` projected to x,y (m²).
    pub fn triangle_area_xy(&self, t: usize) -> f64 {
        let [a, b, c] = self.corners(t);
        0.5 * orient2d(a.truncate(), b.truncate(), c.truncate())
    }

    /// Area of triangle `t` in 3-D (m²).
    pub fn triangle_area_3d(&self, t: usize) -> f64 {
        let [a, b, c] = self.corners(t);
        0.5 * (b - a).cross(c - a).length()
    }

    /// Triangles around each vertex, as compressed rows: the triangles of vertex `v` are
    /// `indices[offsets[v]..offsets[v + 1]]`, in increasing triangle order.
    pub fn vertex_triangles(&self) -> VertexTriangles {
        let n = self.positions.len();
        let mut offsets = vec![0u32; n + 1];
        for tri in &self.triangles {
            for &v in tri {
                offsets[v as usize + 1] += 1;
            }
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut indices = vec![0u32; self.triangles.len() * 3];
        for (t, tri) in self.triangles.iter().enumerate() {
            for &v in tri {
                indices[fill[v as usize] as usize] = t as u32;
                fill[v as usize] += 1;
            }
        }
        VertexTriangles { offsets, indices }
    }

    /// A circle in x,y enclosing every vertex of the given triangles (Ritter's approximation: at most a few percent
    /// larger than the smallest one). `None` for an empty set.
    pub fn bounding_circle(&self, triangles: impl IntoIterator<Item = u32>) -> Option<Circle> {
        let points: Vec<DVec2> = triangles
            .into_iter()
            .flat_map(|t| self.triangles[t as usize])
            .map(|v| self.positions[v as usize].truncate())
            .collect();
        bounding_circle_of_points(&points)
    }

    /// Consumes the TIN, returning positions and triangles.
    pub fn into_parts(self) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        (self.positions, self.triangles)
    }
}

/// Triangles incident to each vertex, in compressed-row form (see [`Tin::vertex_triangles`]).
#[derive(Clone, Debug)]
pub struct VertexTriangles {
    /// Row offsets, one more than there are vertices.
    pub offsets: Vec<u32>,
    /// Triangle indices.
    pub indices: Vec<u32>,
}

impl VertexTriangles {
    /// The triangles incident to vertex `v`.
    pub fn of(&self, v: u32) -> &[u32] {
        let v = v as usize;
        &self.indices[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }
}

/// A circle enclosing all `points` (Ritter's bounding circle, then grown to cover every point exactly).
pub fn bounding_circle_of_points(points: &[DVec2]) -> Option<Circle> {
    let &p0 = points.first()?;
    let far = |from: DVec2| {
        points
            .iter()
            .copied()
            .max_by(|a, b| a.distance_squared(from).total_cmp(&b.distance_squared(from)))
            .unwrap_or(from)
    };
    let p1 = far(p0);
    let p2 = far(p1);
    let mut centre = (p1 + p2) * 0.5;
    let mut radius = p1.distance(p2) * 0.5;
    for &p in points {
        let d = p.distance(centre);
        if d > radius {
            let new_radius = 0.5 * (radius + d);
            centre += (p - centre) * ((new_radius - radius) / d);
            radius = new_radius;
        }
    }
    // Guard against rounding: every point must be inside.
    let exact = points.iter().map(|p| p.distance(centre)).fold(radius, f64::max);
    Some(Circle { centre, radius: exact })
}

/// A round local origin near the centre of the points' bounding box (a multiple of 1 km in x and y, 0 in z),
/// so that coordinates relative to it stay small and are reproducible.
pub(crate) fn local_origin(positions: &[DVec3]) -> DVec3 {
    match Aabb::of_points(positions.iter().copied()) {
        Some(b) => {
            let c = (b.min + b.max) * 0.5;
            DVec3::new((c.x / 1000.0).round() * 1000.0, (c.y / 1000.0).round() * 1000.0, 0.0)
        }
        None => DVec3::ZERO,
    }
}

/// Computes per-edge neighbours, failing on non-manifold edges: every half-edge is put in the bucket of its smaller
/// vertex and each bucket is sorted, so the (at most two) uses of an edge end up side by side.
fn compute_neighbours(triangles: &[[u32; 3]]) -> Result<Vec<[u32; 3]>> {
    if triangles.len() >= (1 << 31) / 3 {
        return Err(TinError::InvalidParameter(format!(
            "{} triangles: more than a mesh can hold (at most {})",
            triangles.len(),
            (1u64 << 31) / 3 - 1
        )));
    }
    // Half-edges bucketed by their smaller vertex (a counting sort, 8 bytes a half-edge), each as one u64: the larger
    // vertex, 1 if the half-edge runs from the larger to the smaller, and triangle * 3 + corner. Sorting each bucket
    // orders them as a sort of (edge, direction, half-edge) would.
    let n = triangles.iter().flatten().max().map_or(0, |&v| v as usize + 1);
    let mut start = vec![0usize; n + 1];
    for tri in triangles {
        for i in 0..3 {
            start[tri[i].min(tri[(i + 1) % 3]) as usize + 1] += 1;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut half = vec![0u64; triangles.len() * 3];
    for (t, tri) in triangles.iter().enumerate() {
        for i in 0..3 {
            let (a, b) = (tri[i], tri[(i + 1) % 3]);
            let slot = &mut fill[a.min(b) as usize];
            half[*slot] = (u64::from(a.max(b)) << 32) | (u64::from(a > b) << 31) | (t * 3 + i) as u64;
            *slot += 1;
        }
    }
    drop(fill);
    let other = |h: u64| (h >> 32) as u32;
    let dir = |h: u64| (h >> 31) & 1;
    let id = |h: u64| (h & 0x7fff_ffff) as usize;
    let mut neighbours = vec![[NO_NEIGHBOUR; 3]; triangles.len()];
    for lo in 0..n {
        let bucket = &mut half[start[lo]..start[lo + 1]];
        bucket.sort_unstable();
        for run in bucket.chunk_by(|x, y| other(*x) == other(*y)) {
            if run.len() > 2 || (run.len() == 2 && dir(run[0]) == dir(run[1])) {
                let (a, b) = (lo as u32, other(run[0]));
                let (a, b) = if dir(run[0]) == 1 { (b, a) } else { (a, b) };
                return Err(TinError::NonManifoldEdge {
                    a,
                    b,
                    first: id(run[0]) / 3,
                    second: id(run[1]) / 3,
                });
            }
            if let [s, o] = *run {
                let (s, o) = (id(s), id(o));
                neighbours[s / 3][s % 3] = (o / 3) as u32;
                neighbours[o / 3][o % 3] = (s / 3) as u32;
            }
        }
    }
    Ok(neighbours)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The neighbours by one global sort of (edge, direction, half-edge): what the bucketed version must give,
    /// errors included.
    fn neighbours_by_sort(triangles: &[[u32; 3]]) -> Result<Vec<[u32; 3]>> {
        let mut edges: Vec<(u64, u8, u32)> = Vec::new();
        for (t, tri) in triangles.iter().enumerate() {
            for i in 0..3 {
                let (a, b) = (tri[i], tri[(i + 1) % 3]);
                edges.push((
                    (u64::from(a.min(b)) << 32) | u64::from(a.max(b)),
                    u8::from(a > b),
                    (t * 3 + i) as u32,
                ));
            }
        }
        edges.sort_unstable();
        let mut neighbours = vec![[NO_NEIGHBOUR; 3]; triangles.len()];
        for run in edges.chunk_by(|x, y| x.0 == y.0) {
            if run.len() > 2 || (run.len() == 2 && run[0].1 == run[1].1) {
                let (a, b) = ((run[0].0 >> 32) as u32, run[0].0 as u32);
                let (a, b) = if run[0].1 == 1 { (b, a) } else { (a, b) };
                return Err(TinError::NonManifoldEdge {
                    a,
                    b,
                    first: (run[0].2 / 3) as usize,
                    second: (run[1].2 / 3) as usize,
                });
            }
            if let [s, o] = run {
                let (s, o) = (s.2 as usize, o.2 as usize);
                neighbours[s / 3][s % 3] = (o / 3) as u32;
                neighbours[o / 3][o % 3] = (s / 3) as u32;
            }
        }
        Ok(neighbours)
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

        /// Bucketing the half-edges by their smaller vertex gives the global sort's neighbours and errors, on valid
        /// grids and on random triangle soups (mostly non-manifold).
        #[test]
        fn bucketed_neighbours_equal_the_global_sort(w in 2u32..7, h in 2u32..7, soup in prop::collection::vec((0u32..9, 0u32..9, 0u32..9), 0..14)) {
            let mut grid = Vec::new();
            for r in 0..h - 1 {
                for c in 0..w - 1 {
                    let v = r * w + c;
                    grid.push([v, v + 1, v + w + 1]);
                    grid.push([v, v + w + 1, v + w]);
                }
            }
            let soup: Vec<[u32; 3]> = soup.into_iter().filter(|t| t.0 != t.1 && t.1 != t.2 && t.0 != t.2).map(|t| [t.0, t.1, t.2]).collect();
            for tris in [grid, soup] {
                let (a, b) = (compute_neighbours(&tris), neighbours_by_sort(&tris));
                prop_assert_eq!(format!("{a:?}"), format!("{b:?}"));
            }
        }

        /// Triangles are checked in parallel, yet the error is the one a scan in order meets first: on a grid of
        /// some 20,000 triangles (several rayon splits) with a few planted faults (an index out of range, a
        /// degenerate triangle, a flipped one) at random places.
        #[test]
        fn the_first_bad_triangle_is_reported(faults in prop::collection::vec((0usize..20_000, 0u8..3), 1..5), flip_first in any::<bool>()) {
            let w = 101u32;
            let positions: Vec<DVec3> =
                (0..w * w).map(|i| DVec3::new(f64::from(i % w), f64::from(i / w), 0.0)).collect();
            let mut tris = Vec::new();
            for r in 0..w - 1 {
                for c in 0..w - 1 {
                    let v = r * w + c;
                    tris.push([v, v + 1, v + w + 1]);
                    tris.push([v, v + w + 1, v + w]);
                }
            }
            if flip_first {
                tris.swap(0, 1); // still counter-clockwise: only the order changes
            }
            for &(t, kind) in &faults {
                let tri = &mut tris[t];
                match kind {
                    0 => tri[1] = w * w + 5,
                    1 => tri[2] = tri[0],
                    _ => tri.swap(1, 2),
                }
            }
            // The reference: the checks of one triangle after another, as a scan in order makes them.
            let expect = tris.iter().enumerate().find_map(|(t, tri)| {
                if let Some(&v) = tri.iter().find(|&&v| v >= w * w) {
                    return Some(format!("index {t} {v}"));
                }
                let [a, b, c] = tri.map(|v| positions[v as usize].truncate());
                let o = orient2d(a, b, c);
                if o == 0.0 || tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
                    return Some(format!("degenerate {t}"));
                }
                let [a0, b0, c0] = tris[0].map(|v| positions[v as usize].truncate());
                ((o > 0.0) != (orient2d(a0, b0, c0) > 0.0)).then(|| format!("orientation {t}"))
            });
            let got = match Tin::from_parts(positions.clone(), tris.clone()) {
                Err(TinError::IndexOutOfRange { triangle, vertex, .. }) => Some(format!("index {triangle} {vertex}")),
                Err(TinError::DegenerateTriangle { triangle, .. }) => Some(format!("degenerate {triangle}")),
                Err(TinError::InconsistentOrientation { triangle }) => Some(format!("orientation {triangle}")),
                Err(e) => Some(format!("other: {e}")),
                Ok(_) => None,
            };
            prop_assert_eq!(got, expect);
        }
    }

    fn square() -> Tin {
        let p = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 1.0),
            DVec3::new(1.0, 1.0, 2.0),
            DVec3::new(0.0, 1.0, 3.0),
        ];
        Tin::from_parts(p, vec![[0, 1, 2], [0, 2, 3]]).expect("valid square")
    }

    #[test]
    fn adjacency_of_two_triangles() {
        let tin = square();
        assert_eq!(tin.neighbours()[0], [NO_NEIGHBOUR, NO_NEIGHBOUR, 1]);
        assert_eq!(tin.neighbours()[1], [0, NO_NEIGHBOUR, NO_NEIGHBOUR]);
        assert_eq!(tin.triangle_area_xy(0), 0.5);
        let vt = tin.vertex_triangles();
        assert_eq!(vt.of(0), &[0, 1]);
        assert_eq!(vt.of(1), &[0]);
    }

    #[test]
    fn clockwise_input_is_flipped() {
        let p = vec![DVec3::ZERO, DVec3::new(0.0, 1.0, 0.0), DVec3::new(1.0, 0.0, 0.0)];
        let tin = Tin::from_parts(p, vec![[0, 1, 2]]).expect("valid");
        assert!(tin.triangle_area_xy(0) > 0.0);
    }

    #[test]
    fn rejects_bad_meshes() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0)];
        assert!(matches!(
            Tin::from_parts(p.clone(), vec![[0, 1, 7]]),
            Err(TinError::IndexOutOfRange { vertex: 7, .. })
        ));
        assert!(matches!(
            Tin::from_parts(vec![DVec3::ZERO, DVec3::X, DVec3::new(2.0, 0.0, 0.0)], vec![[0, 1, 2]]),
            Err(TinError::DegenerateTriangle { triangle: 0, .. })
        ));
        assert!(matches!(
            Tin::from_parts(p.clone(), vec![[0, 1, 3], [0, 2, 3]]),
            Err(TinError::InconsistentOrientation { triangle: 1 })
        ));
        assert!(matches!(
            Tin::from_parts(p, vec![[0, 1, 3], [0, 1, 3]]),
            Err(TinError::NonManifoldEdge { .. })
        ));
    }

    #[test]
    fn bounding_circle_contains_all_points() {
        let pts: Vec<DVec2> = (0..50)
            .map(|i| DVec2::new((i as f64 * 1.7).sin() * 10.0, (i as f64 * 0.3).cos() * 4.0))
            .collect();
        let c = bounding_circle_of_points(&pts).expect("non-empty");
        assert!(pts.iter().all(|p| p.distance(c.centre) <= c.radius));
    }

    #[test]
    fn origin_is_round_and_near_centre() {
        let p = vec![
            DVec3::new(500_123.0, 5_000_456.0, 10.0),
            DVec3::new(501_900.0, 5_001_000.0, 10.0),
            DVec3::new(500_500.0, 5_002_000.0, 10.0),
        ];
        let tin = Tin::from_parts(p, vec![[0, 1, 2]]).expect("valid");
        assert_eq!(tin.origin(), DVec3::new(501_000.0, 5_001_000.0, 0.0));
    }
}
