//! Checks and statistics of a TIN: is it a height field, how good are its triangles, and is it safe to convert to
//! f32 for rendering.
//!
//! The thesis (Edmondson 2004, section 4.1) assumes a TIN that is a height field: unique x,y per vertex, triangles
//! that do not overlap in x,y. [`Tin::from_parts`] checks indices, degeneracy, orientation and manifold edges; this
//! module adds what it cannot check cheaply at construction, and reports everything at once instead of failing on
//! the first problem.
//!
//! Choices where nothing else fixes them:
//! - All triangle quality figures are in the x,y projection (the triangulation lives there; 3-D quality of a height
//!   field mostly reflects the slope).
//! - *Aspect ratio* is `longest edge² / (2 · area)`, i.e. the longest edge over the altitude onto it (2/√3 ≈ 1.155
//!   for an equilateral triangle). A *sliver* has its smallest angle below [`SLIVER_MIN_ANGLE_DEG`] or its aspect
//!   ratio above [`SLIVER_MAX_ASPECT`]. A triangle is *near-degenerate* when its aspect ratio exceeds
//!   [`NEAR_DEGENERATE_ASPECT`] (altitude below a millionth of the longest edge) and *degenerate* when its x,y area is
//!   exactly zero under an exact orientation predicate or it repeats a vertex.
//! - Overlap is interior overlap: triangles that only share an edge, a vertex or touch along a boundary do not
//!   overlap. The test is exact (Shewchuk's adaptive predicates through the `robust` crate): two convex polygons have
//!   disjoint interiors exactly when one of their edge lines weakly separates them. Candidate pairs come from a
//!   uniform grid over the triangles' bounding boxes, with cells about the size of an average triangle, so a
//!   well-shaped mesh of n triangles is checked in O(n) after bucketing; a few huge triangles (for example over a
//!   flat lake) cost time proportional to the cells they cover.
//! - A *crack* is a T-junction (a vertex on an edge of a triangle that does not use it, not at a corner) at another
//!   height than the edge's there: the triangles only touch, so no overlap is found, but the surface has two heights
//!   at the vertex's x,y. The same grid finds them: each used vertex is tested exactly (in x,y) against the triangles
//!   whose boxes hold it, then its height against the edge's. A T-junction at the edge's height is a whole surface.
//! - f32 precision: converting a coordinate of magnitude m to f32 rounds it to a multiple of the f32 spacing
//!   2^(⌊log2 m⌋ − 23). Absolute coordinates of 1e5 m or more get a warning (f32 spacing ≥ 2^-7 m ≈ 8 mm there, and
//!   0.5 m at UTM northings); coordinates relative to [`Tin::origin`] are flagged when their f32 spacing exceeds 1% of
//!   the shortest x,y edge.

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use serde::Serialize;

use crate::mesh::{Aabb, NO_NEIGHBOUR, Tin, local_origin};
use crate::predicates::orient2d;

/// A triangle whose smallest x,y angle is below this (degrees) is a sliver.
pub const SLIVER_MIN_ANGLE_DEG: f64 = 5.0;
/// A triangle whose aspect ratio (longest edge² / (2 · area), in x,y) is above this is a sliver.
pub const SLIVER_MAX_ASPECT: f64 = 20.0;
/// A triangle whose aspect ratio is above this is near-degenerate.
pub const NEAR_DEGENERATE_ASPECT: f64 = 1e6;
/// Absolute coordinates at or above this magnitude (m) get an f32 precision warning.
pub const F32_ABSOLUTE_WARNING: f64 = 1e5;
/// How many example elements a report lists for each kind of problem.
pub const MAX_EXAMPLES: usize = 20;

/// Everything [`validate`] found wrong or risky in a mesh. Counts are complete; example lists hold at most
/// [`MAX_EXAMPLES`] entries, smallest indices first.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ValidationReport {
    /// Number of vertices.
    pub vertices: usize,
    /// Number of triangles.
    pub triangles: usize,
    /// Vertices with a NaN or infinite coordinate.
    pub non_finite_vertices: usize,
    /// Some of them.
    pub non_finite_examples: Vec<u32>,
    /// Triangles that refer to a vertex that does not exist (never for a [`Tin`]).
    pub bad_index_triangles: usize,
    /// Vertices that share x,y with an earlier vertex (equal or different z).
    pub duplicate_xy_vertices: usize,
    /// Vertices no triangle uses.
    pub unreferenced_vertices: usize,
    /// Triangles with zero x,y area or a repeated vertex.
    pub degenerate_triangles: usize,
    /// Some of them.
    pub degenerate_examples: Vec<u32>,
    /// Triangles that are clockwise in x,y (a [`Tin`] has none).
    pub clockwise_triangles: usize,
    /// Undirected edges used by more than two triangles or twice in the same direction.
    pub non_manifold_edges: usize,
    /// Pairs of triangles whose interiors overlap in x,y.
    pub overlapping_pairs: usize,
    /// Some of them, as `[smaller, larger]` triangle indices.
    pub overlap_examples: Vec<[u32; 2]>,
    /// Vertices on an edge of a triangle that does not use them at another height than that edge, as (vertex,
    /// triangle) pairs: cracks in the surface ([`find_cracks`]).
    pub cracks: usize,
    /// Some of them, as `[vertex, triangle]`.
    pub crack_examples: Vec<[u32; 2]>,
    /// Non-degenerate triangles with aspect ratio above [`NEAR_DEGENERATE_ASPECT`].
    pub near_degenerate_triangles: usize,
    /// Triangles with smallest angle below [`SLIVER_MIN_ANGLE_DEG`] or aspect ratio above [`SLIVER_MAX_ASPECT`]
    /// (degenerate triangles included).
    pub slivers: usize,
    /// Some of them.
    pub sliver_examples: Vec<u32>,
    /// How well the coordinates survive conversion to f32.
    pub precision: PrecisionReport,
    /// Human-readable summary of every problem and risk above, one line each.
    pub warnings: Vec<String>,
}

impl ValidationReport {
    /// True when the mesh is a valid height field: finite, unique x,y, valid indices, no degenerate, clockwise or
    /// overlapping triangles, manifold edges, no cracks. Slivers, unreferenced vertices and precision risks do
    /// not count.
    pub fn is_height_field(&self) -> bool {
        self.non_finite_vertices == 0
            && self.bad_index_triangles == 0
            && self.duplicate_xy_vertices == 0
            && self.degenerate_triangles == 0
            && self.clockwise_triangles == 0
            && self.non_manifold_edges == 0
            && self.overlapping_pairs == 0
            && self.cracks == 0
    }
}

/// How coordinates fare when converted to f32 (see the module documentation).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PrecisionReport {
    /// The local origin ([`Tin::origin`]) that renderers subtract.
    pub origin: DVec3,
    /// Largest absolute value of any coordinate (m).
    pub max_abs_coordinate: f64,
    /// f32 spacing at that magnitude (m).
    pub f32_step_absolute: f64,
    /// Largest absolute value of any coordinate relative to the origin (m).
    pub max_local_coordinate: f64,
    /// f32 spacing at that magnitude (m).
    pub f32_step_local: f64,
    /// Shortest triangle edge in x,y (m); infinite without triangles.
    pub min_edge_xy: f64,
    /// `max_abs_coordinate` ≥ [`F32_ABSOLUTE_WARNING`]: absolute coordinates must not go to f32.
    pub absolute_f32_unsafe: bool,
    /// `f32_step_local` > 1% of `min_edge_xy`: even origin-relative f32 coordinates distort the smallest triangles.
    pub local_f32_unsafe: bool,
}

/// Summary figures of a mesh, for `tincull info` and reports.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeshStats {
    /// Number of vertices.
    pub vertices: usize,
    /// Number of triangles.
    pub triangles: usize,
    /// Triangle edges without a neighbour.
    pub boundary_edges: usize,
    /// Bounding box of the vertices.
    pub bbox: Aabb,
    /// Highest minus lowest vertex (m).
    pub relief: f64,
    /// The local origin for f32 conversion.
    pub origin: DVec3,
    /// Total x,y area of the triangles (m²).
    pub area_xy_total: f64,
    /// Smallest triangle x,y area (m²).
    pub area_xy_min: f64,
    /// Largest triangle x,y area (m²).
    pub area_xy_max: f64,
    /// Mean triangle x,y area (m²).
    pub area_xy_mean: f64,
    /// Shortest edge in x,y (m).
    pub edge_xy_min: f64,
    /// Longest edge in x,y (m).
    pub edge_xy_max: f64,
    /// Smallest interior angle of any triangle in x,y (degrees).
    pub min_angle_deg: f64,
    /// Largest aspect ratio (longest edge² / (2 · area)) of any triangle.
    pub max_aspect: f64,
    /// Number of slivers (see [`is_sliver`]).
    pub slivers: usize,
}

/// Shape of one triangle in x,y.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TriangleQuality {
    /// Smallest interior angle (degrees); 0 for a degenerate triangle.
    pub min_angle_deg: f64,
    /// Longest edge² / (2 · area); infinite for a degenerate triangle.
    pub aspect: f64,
}

/// Shape of triangle `abc` in x,y (orientation does not matter).
pub fn triangle_quality(a: DVec2, b: DVec2, c: DVec2) -> TriangleQuality {
    let angle = |p: DVec2, q: DVec2, r: DVec2| {
        let (u, v) = (q - p, r - p);
        u.perp_dot(v).abs().atan2(u.dot(v))
    };
    let twice_area = (b - a).perp_dot(c - a).abs();
    let longest = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    if twice_area == 0.0 || !twice_area.is_finite() {
        return TriangleQuality {
            min_angle_deg: 0.0,
            aspect: f64::INFINITY,
        };
    }
    let min_angle = angle(a, b, c).min(angle(b, c, a)).min(angle(c, a, b));
    TriangleQuality {
        min_angle_deg: min_angle.to_degrees(),
        aspect: longest / twice_area,
    }
}

/// Whether a triangle of this shape is a sliver (see the module documentation).
pub fn is_sliver(q: TriangleQuality) -> bool {
    q.min_angle_deg < SLIVER_MIN_ANGLE_DEG || q.aspect > SLIVER_MAX_ASPECT
}

/// The spacing of f32 values near magnitude `m` (the gap between `m` rounded to f32 and the next f32).
pub fn f32_step(m: f64) -> f64 {
    let m = m.abs();
    if !m.is_finite() {
        return f64::INFINITY;
    }
    if m < f64::from(f32::MIN_POSITIVE) {
        return 2f64.powi(-149);
    }
    let exponent = ((m.to_bits() >> 52) & 0x7ff) as i32 - 1023;
    2f64.powi(exponent - 23)
}

/// Whether two counter-clockwise triangles have overlapping interiors (exact).
pub(crate) fn interiors_overlap(a: &[DVec2; 3], b: &[DVec2; 3]) -> bool {
    let separates = |s: &[DVec2; 3], t: &[DVec2; 3]| {
        (0..3).any(|i| {
            let (p, q) = (s[i], s[(i + 1) % 3]);
            t.iter().all(|&v| orient2d(p, q, v) <= 0.0)
        })
    };
    !(separates(a, b) || separates(b, a))
}

/// Pairs of triangles whose interiors overlap in x,y.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Overlaps {
    /// How many pairs overlap.
    pub count: usize,
    /// The smallest pairs (by first, then second index), `[smaller, larger]`, at most the requested limit.
    pub first: Vec<[u32; 2]>,
}

/// Finds every pair of triangles whose interiors overlap in x,y, exactly. Triangles with an invalid index, a
/// non-finite corner or zero area are skipped (they are reported elsewhere). The result does not depend on the
/// number of threads.
///
/// Pairs that share a vertex are found around it (`overlaps_around_vertices`); the others in the cells of a grid
/// that both triangles meet, where the triangles are grouped by their *hub* (the corner with the most triangles):
/// a group's pairs share its hub and are not looked at there, so the spokes of a fan, which all meet its centre's
/// cells, cost nothing there.
pub fn find_overlaps(positions: &[DVec3], triangles: &[[u32; 3]], limit: usize) -> Overlaps {
    let Some(grid) = TriangleGrid::new(positions, triangles) else {
        return Overlaps::default();
    };
    if grid.tris.len() < 2 {
        return Overlaps::default();
    }
    let mut degree = vec![0u32; positions.len()];
    for u in &grid.tris {
        u.ids.iter().for_each(|&v| degree[v as usize] += 1);
    }
    let hub = |u: &Usable| {
        u.ids
            .into_iter()
            .max_by_key(|&v| (degree[v as usize], std::cmp::Reverse(v)))
            .unwrap_or(0)
    };
    let hubs: Vec<u32> = grid.tris.iter().map(hub).collect();
    let keep_smallest = |mut v: Vec<[u32; 2]>| {
        if v.len() > limit {
            v.sort_unstable();
            v.truncate(limit);
        }
        v
    };
    let tris = &grid.tris;
    let (count, first) = (0..grid.nx * grid.ny)
        .into_par_iter()
        .fold(
            || (0usize, Vec::new(), Vec::new(), Vec::new(), Vec::new()),
            |(mut count, mut found, mut here, mut cells_a, mut cells_b), c| {
                here.clear();
                here.extend(grid.members(c).iter().map(|&k| (hubs[k as usize], k)));
                here.sort_unstable();
                // Each triangle against those of the later groups only.
                let mut group_end = 0;
                for i in 0..here.len() {
                    if i == group_end {
                        group_end = here[i..].partition_point(|h| h.0 == here[i].0) + i;
                    }
                    let a = &tris[here[i].1 as usize];
                    for &(_, kb) in &here[group_end..] {
                        let b = &tris[kb as usize];
                        // Boxes must overlap with positive area; pairs sharing a vertex are found around it.
                        if a.lo.x >= b.hi.x || b.lo.x >= a.hi.x || a.lo.y >= b.hi.y || b.lo.y >= a.hi.y {
                            continue;
                        }
                        if a.ids.iter().any(|v| b.ids.contains(v)) || !interiors_overlap(&a.c, &b.c) {
                            continue;
                        }
                        // Counted once: in the first cell both meet.
                        cells_a.clear();
                        cells_b.clear();
                        grid.raster(a, |cell| cells_a.push(cell));
                        grid.raster(b, |cell| cells_b.push(cell));
                        if first_common(&cells_a, &cells_b) != Some(c) {
                            continue;
                        }
                        count += 1;
                        if limit > 0 {
                            found.push([a.t.min(b.t), a.t.max(b.t)]);
                            if found.len() >= limit.saturating_mul(2) {
                                found = keep_smallest(found);
                            }
                        }
                    }
                }
                (count, found, here, cells_a, cells_b)
            },
        )
        .map(|(count, found, ..)| (count, found))
        .reduce(
            || (0, Vec::new()),
            |(ca, mut fa), (cb, fb)| {
                fa.extend(fb);
                (ca + cb, keep_smallest(fa))
            },
        );
    let around = overlaps_around_vertices(&grid.tris, positions.len());
    let mut first = keep_smallest(first);
    first.extend(around.iter().take(limit));
    first.sort_unstable();
    first.truncate(limit);
    Overlaps {
        count: count + around.len(),
        first,
    }
}

/// The smallest value in both ascending lists.
fn first_common(a: &[usize], b: &[usize]) -> Option<usize> {
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => return Some(a[i]),
        }
    }
    None
}

/// A triangle's wedge at one of its corners: the triangle (its entry in the usable ones), then the far ends of its
/// first and second edges there, counter-clockwise.
type Wedge = (u32, DVec2, DVec2);

/// Every pair of `tris` that share a vertex and whose interiors overlap, `[smaller, larger]` triangle index, sorted.
///
/// Two counter-clockwise triangles with a common corner `v` overlap exactly when their open wedges at `v` do: each
/// lies in its wedge, and near `v` each fills it. An open wedge spans less than π, so two of them overlap exactly
/// when the first edge of one lies in the other's half-open wedge `[first edge, second edge)`. Around each vertex the
/// wedges are sorted by their first edge's direction (exactly: the half-plane by the signs of the differences, then
/// the orientation predicate); each wedge is followed counter-clockwise while the next first edge lies in it, so a
/// vertex of `k` wedges costs `O(k log k)` and one test per overlapping pair. Each pair found is confirmed by the
/// triangle test itself.
fn overlaps_around_vertices(tris: &[Usable], vertices: usize) -> Vec<[u32; 2]> {
    // The triangles at each vertex (compressed rows), with the vertex's corner.
    let mut offsets = vec![0usize; vertices + 1];
    for u in tris {
        u.ids.iter().for_each(|&v| offsets[v as usize + 1] += 1);
    }
    for i in 0..vertices {
        offsets[i + 1] += offsets[i];
    }
    let mut fill = offsets.clone();
    let mut at = vec![(0u32, 0u8); offsets[vertices]];
    for (k, u) in tris.iter().enumerate() {
        for (m, &v) in u.ids.iter().enumerate() {
            at[fill[v as usize]] = (k as u32, m as u8);
            fill[v as usize] += 1;
        }
    }
    let mut pairs: Vec<[u32; 2]> = (0..vertices)
        .into_par_iter()
        .filter(|&v| offsets[v + 1] - offsets[v] > 1)
        .fold(
            || (Vec::new(), Vec::new()),
            |(mut found, mut wedges): (Vec<[u32; 2]>, Vec<Wedge>), v| {
                wedges.clear();
                wedges.extend(at[offsets[v]..offsets[v + 1]].iter().map(|&(k, m)| {
                    let c = &tris[k as usize].c;
                    (k, c[(m as usize + 1) % 3], c[(m as usize + 2) % 3])
                }));
                let centre = tris[wedges[0].0 as usize].c[at[offsets[v]].1 as usize];
                // Directions from the centre, counter-clockwise from +x: first the half-plane, then the orientation.
                let half = |p: DVec2| !(p.y > centre.y || (p.y == centre.y && p.x > centre.x));
                wedges.sort_by(|a, b| {
                    half(a.1).cmp(&half(b.1)).then_with(|| {
                        let o = orient2d(centre, a.1, b.1);
                        if o > 0.0 {
                            std::cmp::Ordering::Less
                        } else if o < 0.0 {
                            std::cmp::Ordering::Greater
                        } else {
                            std::cmp::Ordering::Equal
                        }
                    })
                });
                let inside =
                    |d: DVec2, s: DVec2, e: DVec2| orient2d(centre, s, d) >= 0.0 && orient2d(centre, d, e) > 0.0;
                let n = wedges.len();
                for i in 0..n {
                    let (ka, s, e) = wedges[i];
                    for step in 1..n {
                        let (kb, d, _) = wedges[(i + step) % n];
                        if !inside(d, s, e) {
                            break;
                        }
                        let (a, b) = (&tris[ka as usize], &tris[kb as usize]);
                        if interiors_overlap(&a.c, &b.c) {
                            found.push([a.t.min(b.t), a.t.max(b.t)]);
                        }
                    }
                }
                (found, wedges)
            },
        )
        .map(|(found, _)| found)
        .reduce(Vec::new, |mut a, b| {
            a.extend(b);
            a
        });
    // A pair sharing an edge is found at both its ends, a pair of equal first edges from both sides.
    pairs.par_sort_unstable();
    pairs.dedup();
    pairs
}

/// Vertices lying on an edge of a triangle that does not use them at another height than that edge (cracks).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Cracks {
    /// How many (vertex, triangle) pairs there are.
    pub count: usize,
    /// The smallest pairs (by vertex, then triangle), `[vertex, triangle]`, at most the requested limit.
    pub first: Vec<[u32; 2]>,
}

/// Two heights closer than this, relative to `1 + |z|` of the three vertices, are one (the rounding of an exporter
/// that split an edge at a vertex it computed).
const CRACK_TOLERANCE: f64 = 1e-9;

/// Finds every vertex used by some triangle that lies, exactly in x,y, on an edge of a triangle that does not use it
/// (a T-junction: not at one of its corners) at a height other than the edge's there (by more than 1e-9 times
/// `1 + |z|` of the three vertices): the surface has a *crack* along that edge, two heights at the vertex's x,y. Such a
/// mesh passes the overlap test (the triangles only touch) but is not a height field. A T-junction at the edge's own
/// height leaves the surface whole and is not reported. A vertex at a corner's x,y is a duplicate x,y, reported as
/// such; a vertex inside a triangle makes its own triangles overlap it. Triangles with an invalid index, a non-finite
/// corner or zero area are skipped, as by [`find_overlaps`]. The result does not depend on the number of threads.
pub fn find_cracks(positions: &[DVec3], triangles: &[[u32; 3]], limit: usize) -> Cracks {
    let Some(grid) = TriangleGrid::new(positions, triangles) else {
        return Cracks::default();
    };
    let mut used = vec![false; positions.len()];
    for tri in triangles {
        if tri.iter().all(|&v| (v as usize) < positions.len()) {
            tri.iter().for_each(|&v| used[v as usize] = true);
        }
    }
    let grid = &grid;
    let found: Vec<[u32; 2]> = (0..positions.len() as u32)
        .into_par_iter()
        .filter(|&v| used[v as usize] && positions[v as usize].is_finite())
        .flat_map_iter(|v| {
            let q = positions[v as usize];
            let p = q.truncate();
            let inside = p.x >= grid.lo.x && p.y >= grid.lo.y && p.x <= grid.hi.x && p.y <= grid.hi.y;
            let here: &[u32] = if inside { grid.members(grid.cell_of(p)) } else { &[] };
            here.iter().filter_map(move |&k| {
                let Usable { t, c, lo, hi, .. } = &grid.tris[k as usize];
                let tri = triangles[*t as usize];
                if tri.contains(&v) || c.contains(&p) || p.x < lo.x || p.y < lo.y || p.x > hi.x || p.y > hi.y {
                    return None;
                }
                // Counter-clockwise corners: in the closed triangle when no edge has it strictly to its right, and on
                // the edge whose line holds it (at most one: it is no corner).
                let sides = [0, 1, 2].map(|i| orient2d(c[i], c[(i + 1) % 3], p));
                let edge = sides.iter().position(|&o| o == 0.0)?;
                if sides.iter().any(|&o| o < 0.0) {
                    return None;
                }
                // The edge's end vertices in 3-D (the corners `c` may have been swapped to counter-clockwise).
                let [a, b] = [c[edge], c[(edge + 1) % 3]].map(|e| {
                    let i = tri
                        .iter()
                        .position(|&w| positions[w as usize].truncate() == e)
                        .unwrap_or(0);
                    positions[tri[i] as usize]
                });
                let d = b - a;
                let s = if d.x.abs() >= d.y.abs() {
                    (q.x - a.x) / d.x
                } else {
                    (q.y - a.y) / d.y
                };
                let z = a.z + s * d.z;
                let tolerance = CRACK_TOLERANCE * (1.0 + a.z.abs() + b.z.abs() + q.z.abs());
                ((q.z - z).abs() > tolerance).then_some([v, *t])
            })
        })
        .collect();
    let mut first = found;
    let count = first.len();
    first.sort_unstable();
    first.truncate(limit);
    Cracks { count, first }
}

/// A usable triangle: counter-clockwise, with finite corners and a positive x,y area.
struct Usable {
    /// Its index in the mesh.
    t: u32,
    /// Its vertices, in the order of `c`.
    ids: [u32; 3],
    /// Its corners in x,y, counter-clockwise.
    c: [DVec2; 3],
    /// Its x,y box.
    lo: DVec2,
    hi: DVec2,
}

/// Most grid entries per usable triangle (beyond 16): the cells grow until the triangles meet no more.
const ENTRIES_PER_TRIANGLE: usize = 32;

/// The usable triangles of a mesh (invalid indices, non-finite corners and zero area left out) listed in the cells of
/// a uniform grid that they meet.
///
/// A triangle is listed in every cell its closed x,y region meets, and possibly a few more: the cells of its box
/// when that spans at most four, else row by row the cells between the least and the greatest x of the triangle
/// within the row's band; the box, the band and the x range widened by a millionth of a cell and a billionth of the
/// largest coordinate, far more than the rounding of the band's edges, of the edges' crossings with them, and of
/// [`TriangleGrid::cell_of`]. So a point of a triangle (and every vertex on its edges) lies in a cell that lists it,
/// and two triangles whose interiors overlap share a cell. The cells start at the side of a square per four
/// triangles over the box of all of them and grow by half until there are at most four cells and
/// [`ENTRIES_PER_TRIANGLE`] entries per triangle (long thin triangles, as in a fan, meet many small cells).
struct TriangleGrid {
    tris: Vec<Usable>,
    lo: DVec2,
    hi: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    /// The widening of the bands and x ranges.
    slack: f64,
    /// The entries of `tris` that meet cell `c` are `members[offsets[c]..offsets[c + 1]]`.
    offsets: Vec<usize>,
    members: Vec<u32>,
}

impl TriangleGrid {
    /// The grid of the usable triangles; `None` when there is none.
    fn new(positions: &[DVec3], triangles: &[[u32; 3]]) -> Option<TriangleGrid> {
        let mut tris: Vec<Usable> = Vec::with_capacity(triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            if tri.iter().any(|&v| v as usize >= positions.len()) {
                continue;
            }
            let mut ids = *tri;
            let mut c = tri.map(|v| positions[v as usize].truncate());
            if !c.iter().all(|p| p.is_finite()) {
                continue;
            }
            let o = orient2d(c[0], c[1], c[2]);
            if o == 0.0 {
                continue;
            }
            if o < 0.0 {
                c.swap(1, 2);
                ids.swap(1, 2);
            }
            let lo = c[0].min(c[1]).min(c[2]);
            let hi = c[0].max(c[1]).max(c[2]);
            tris.push(Usable {
                t: t as u32,
                ids,
                c,
                lo,
                hi,
            });
        }
        let (mut lo, mut hi) = (tris.first()?.lo, tris.first()?.hi);
        for u in &tris {
            lo = lo.min(u.lo);
            hi = hi.max(u.hi);
        }
        let size = hi - lo;
        let max_cells = 4.0 * tris.len() as f64 + 16.0;
        let max_entries = ENTRIES_PER_TRIANGLE * tris.len() + 16;
        let mut cell = (4.0 * size.x * size.y / tris.len() as f64)
            .sqrt()
            .max(f64::MIN_POSITIVE);
        let cells_for = |cell: f64| ((size.x / cell).floor() + 1.0) * ((size.y / cell).floor() + 1.0);
        let slack_of = |cell: f64| 1e-6 * cell + 1e-9 * lo.abs().max(hi.abs()).max_element();
        let mut grid = TriangleGrid {
            tris,
            lo,
            hi,
            cell,
            nx: 1,
            ny: 1,
            slack: 0.0,
            offsets: Vec::new(),
            members: Vec::new(),
        };
        // Cells grown until there are few enough, then until the triangles meet few enough of them (counted).
        loop {
            while cells_for(cell) > max_cells {
                cell *= 1.5;
            }
            grid.cell = cell;
            grid.nx = (size.x / cell).floor() as usize + 1;
            grid.ny = (size.y / cell).floor() as usize + 1;
            grid.slack = slack_of(cell);
            // The cells of the boxes bound those met: counted first, the triangles are rasterized only when needed.
            let boxes: f64 = grid.tris.iter().map(|u| grid.box_cells(u)).sum();
            let mut entries = 0;
            if boxes > max_entries as f64 {
                for u in &grid.tris {
                    grid.raster(u, |_| entries += 1);
                    if entries > max_entries {
                        break;
                    }
                }
            }
            if entries <= max_entries || grid.nx * grid.ny == 1 {
                break;
            }
            cell *= 1.5;
        }
        // Bucket triangles into every cell they meet (compressed rows, each cell's triangles in increasing order).
        let cells = grid.nx * grid.ny;
        let mut offsets = vec![0usize; cells + 1];
        for u in &grid.tris {
            grid.raster(u, |c| offsets[c + 1] += 1);
        }
        for i in 0..cells {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut members = vec![0u32; offsets[cells]];
        for (k, u) in grid.tris.iter().enumerate() {
            grid.raster(u, |c| {
                members[fill[c]] = k as u32;
                fill[c] += 1;
            });
        }
        grid.offsets = offsets;
        grid.members = members;
        Some(grid)
    }

    /// Calls `f` with every cell that `u` meets (see [`TriangleGrid`]), in increasing order.
    fn raster(&self, u: &Usable, mut f: impl FnMut(usize)) {
        // A box of a few cells, widened by the slack, is taken whole: it holds every cell the triangle meets.
        let s = DVec2::splat(self.slack);
        let ((bx0, by0), (bx1, by1)) = (self.cell_xy(u.lo - s), self.cell_xy(u.hi + s));
        if (bx1 - bx0 + 1) * (by1 - by0 + 1) <= 4 {
            for cy in by0..=by1 {
                for cx in bx0..=bx1 {
                    f(cy * self.nx + cx);
                }
            }
            return;
        }
        let (y0, y1) = (self.cell_xy(u.lo).1, self.cell_xy(u.hi).1);
        for cy in y0..=y1 {
            // The row's band, widened; the first and last rows reach to infinity (points beyond are clamped there).
            let band_lo = if cy == 0 {
                f64::NEG_INFINITY
            } else {
                self.lo.y + cy as f64 * self.cell - self.slack
            };
            let band_hi = if cy + 1 == self.ny {
                f64::INFINITY
            } else {
                self.lo.y + (cy + 1) as f64 * self.cell + self.slack
            };
            let (mut xmin, mut xmax) = (f64::INFINITY, f64::NEG_INFINITY);
            for i in 0..3 {
                let (a, b) = (u.c[i], u.c[(i + 1) % 3]);
                if (band_lo..=band_hi).contains(&a.y) {
                    xmin = xmin.min(a.x);
                    xmax = xmax.max(a.x);
                }
                // Where the edge crosses the band's lines.
                for y in [band_lo, band_hi] {
                    if (a.y < y) != (b.y < y) && y.is_finite() {
                        let x = a.x + (y - a.y) * ((b.x - a.x) / (b.y - a.y));
                        xmin = xmin.min(x);
                        xmax = xmax.max(x);
                    }
                }
            }
            if xmin > xmax {
                continue;
            }
            let p = |x: f64| DVec2::new(x, u.lo.y);
            let (x0, x1) = (
                self.cell_xy(p(xmin - self.slack)).0,
                self.cell_xy(p(xmax + self.slack)).0,
            );
            for cx in x0..=x1 {
                f(cy * self.nx + cx);
            }
        }
    }

    /// The number of cells of `u`'s box widened by the slack: at least those it meets.
    fn box_cells(&self, u: &Usable) -> f64 {
        let s = DVec2::splat(self.slack);
        let ((x0, y0), (x1, y1)) = (self.cell_xy(u.lo - s), self.cell_xy(u.hi + s));
        ((x1 - x0 + 1) * (y1 - y0 + 1)) as f64
    }

    /// The cell column and row holding `p` (clamped to the grid).
    fn cell_xy(&self, p: DVec2) -> (usize, usize) {
        let cx = (((p.x - self.lo.x) / self.cell).floor().max(0.0) as usize).min(self.nx - 1);
        let cy = (((p.y - self.lo.y) / self.cell).floor().max(0.0) as usize).min(self.ny - 1);
        (cx, cy)
    }

    /// The index of the cell holding `p` (clamped to the grid).
    fn cell_of(&self, p: DVec2) -> usize {
        let (cx, cy) = self.cell_xy(p);
        cy * self.nx + cx
    }

    /// The entries of `tris` that meet cell `c`.
    fn members(&self, c: usize) -> &[u32] {
        &self.members[self.offsets[c]..self.offsets[c + 1]]
    }
}

/// Checks a mesh given as raw parts, which may break any rule (see [`ValidationReport`]). Never panics.
pub fn validate_parts(positions: &[DVec3], triangles: &[[u32; 3]]) -> ValidationReport {
    let n = positions.len();
    let non_finite: Vec<u32> = (0..n as u32).filter(|&v| !positions[v as usize].is_finite()).collect();
    let mut referenced = vec![false; n];
    let mut bad_index_triangles = 0;
    let mut degenerate = Vec::new();
    let mut clockwise_triangles = 0;
    let mut near_degenerate_triangles = 0;
    let mut slivers = Vec::new();
    let mut min_edge_xy = f64::INFINITY;
    // Every directed edge as (smaller end, larger end, whether it runs from the larger to the smaller), sorted below.
    let mut edges: Vec<(u32, u32, bool)> = Vec::with_capacity(triangles.len() * 3);
    for (t, tri) in triangles.iter().enumerate() {
        if tri.iter().any(|&v| v as usize >= n) {
            bad_index_triangles += 1;
            continue;
        }
        for &v in tri {
            referenced[v as usize] = true;
        }
        for i in 0..3 {
            let (a, b) = (tri[i], tri[(i + 1) % 3]);
            edges.push((a.min(b), a.max(b), a > b));
        }
        let c = tri.map(|v| positions[v as usize].truncate());
        if !c.iter().all(|p| p.is_finite()) {
            continue;
        }
        for i in 0..3 {
            let len = c[i].distance(c[(i + 1) % 3]);
            if len > 0.0 {
                min_edge_xy = min_edge_xy.min(len);
            }
        }
        let o = orient2d(c[0], c[1], c[2]);
        if o == 0.0 || tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
            degenerate.push(t as u32);
            slivers.push(t as u32);
            continue;
        }
        if o < 0.0 {
            clockwise_triangles += 1;
        }
        let q = triangle_quality(c[0], c[1], c[2]);
        if q.aspect > NEAR_DEGENERATE_ASPECT {
            near_degenerate_triangles += 1;
        }
        if is_sliver(q) {
            slivers.push(t as u32);
        }
    }
    // An undirected edge is non-manifold when it is used twice in the same direction (or more than twice, which
    // needs that): equal neighbours in the sorted list.
    edges.par_sort_unstable();
    let non_manifold_edges = edges
        .chunk_by(|x, y| (x.0, x.1) == (y.0, y.1))
        .filter(|uses| uses.windows(2).any(|w| w[0] == w[1]))
        .count();
    let unreferenced_vertices = referenced.iter().filter(|&&r| !r).count();
    let duplicate_xy_vertices = {
        let mut keys: Vec<(u64, u64)> = positions
            .iter()
            .filter(|p| p.is_finite())
            .map(|p| ((p.x + 0.0).to_bits(), (p.y + 0.0).to_bits()))
            .collect();
        keys.sort_unstable();
        keys.windows(2).filter(|w| w[0] == w[1]).count()
    };
    let overlaps = find_overlaps(positions, triangles, MAX_EXAMPLES);
    let cracks = find_cracks(positions, triangles, MAX_EXAMPLES);
    let precision = precision_report(positions, min_edge_xy);

    let mut warnings = Vec::new();
    let mut warn = |count: usize, what: &str| {
        if count > 0 {
            warnings.push(format!("{count} {what}"));
        }
    };
    warn(non_finite.len(), "vertices with a NaN or infinite coordinate");
    warn(bad_index_triangles, "triangles referring to missing vertices");
    warn(
        duplicate_xy_vertices,
        "vertices sharing x,y with another vertex: not a height field",
    );
    warn(degenerate.len(), "degenerate triangles (zero area in x,y)");
    warn(clockwise_triangles, "clockwise triangles");
    warn(non_manifold_edges, "non-manifold edges");
    warn(
        overlaps.count,
        "pairs of triangles overlapping in x,y: not a height field",
    );
    warn(
        cracks.count,
        "vertices on an edge of a triangle that does not use them, at another height (cracks in the surface): not a \
         height field",
    );
    warn(
        near_degenerate_triangles,
        "near-degenerate triangles (altitude below 1e-6 of the longest edge)",
    );
    warn(
        slivers.len(),
        "sliver triangles (smallest angle below 5 degrees or aspect ratio above 20)",
    );
    warn(unreferenced_vertices, "vertices used by no triangle");
    if precision.absolute_f32_unsafe {
        warnings.push(format!(
            "absolute coordinates reach {} m, where f32 values are {} m apart: subtract the local origin {} before \
             converting to f32",
            precision.max_abs_coordinate, precision.f32_step_absolute, precision.origin
        ));
    }
    if precision.local_f32_unsafe {
        warnings.push(format!(
            "even relative to the local origin, f32 values are {} m apart at {} m, more than 1% of the shortest \
             edge ({} m)",
            precision.f32_step_local, precision.max_local_coordinate, precision.min_edge_xy
        ));
    }

    warnings.extend(small_terrain_warning(positions));

    let examples = |v: &[u32]| v.iter().copied().take(MAX_EXAMPLES).collect::<Vec<u32>>();
    ValidationReport {
        vertices: n,
        triangles: triangles.len(),
        non_finite_vertices: non_finite.len(),
        non_finite_examples: examples(&non_finite),
        bad_index_triangles,
        duplicate_xy_vertices,
        unreferenced_vertices,
        degenerate_triangles: degenerate.len(),
        degenerate_examples: examples(&degenerate),
        clockwise_triangles,
        non_manifold_edges,
        overlapping_pairs: overlaps.count,
        overlap_examples: overlaps.first,
        cracks: cracks.count,
        crack_examples: cracks.first,
        near_degenerate_triangles,
        slivers: slivers.len(),
        sliver_examples: examples(&slivers),
        precision,
        warnings,
    }
}

/// A terrain narrower than this (m) gets a warning: its tolerances are no longer small against it.
const SMALL_TERRAIN: f64 = 1.0;

/// A warning for a terrain under a metre across (`SMALL_TERRAIN`, its wider side in x,y over the finite
/// `positions`). Tolerances are absolute in part (the ground truth's 1e-9 m, the safe culler's 1e-7 m): on a terrain a
/// few millimetres across they call sight lines clear that are not, which culls less but scores less exactly.
pub fn small_terrain_warning(positions: &[DVec3]) -> Option<String> {
    let span = positions
        .iter()
        .filter(|p| p.is_finite())
        .fold(None, |b: Option<(DVec3, DVec3)>, &p| {
            Some(b.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))))
        })
        .map_or(f64::INFINITY, |(lo, hi)| (hi - lo).truncate().max_element());
    (span > 0.0 && span < SMALL_TERRAIN).then(|| {
        format!(
            "the terrain spans only {span:.3e} m across: tincull works in metres with tolerances of 1e-9 m and more, \
             so at this size its ground truth calls too much visible and the safe culler culls less (never a visible \
             triangle); give its coordinates in metres"
        )
    })
}

fn precision_report(positions: &[DVec3], min_edge_xy: f64) -> PrecisionReport {
    let finite: Vec<DVec3> = positions.iter().copied().filter(|p| p.is_finite()).collect();
    let origin = local_origin(&finite);
    let max_abs_coordinate = finite.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max);
    let max_local_coordinate = finite
        .iter()
        .map(|p| (*p - origin).abs().max_element())
        .fold(0.0, f64::max);
    let f32_step_absolute = f32_step(max_abs_coordinate);
    let f32_step_local = f32_step(max_local_coordinate);
    PrecisionReport {
        origin,
        max_abs_coordinate,
        f32_step_absolute,
        max_local_coordinate,
        f32_step_local,
        min_edge_xy,
        absolute_f32_unsafe: max_abs_coordinate >= F32_ABSOLUTE_WARNING,
        local_f32_unsafe: f32_step_local > 0.01 * min_edge_xy,
    }
}

/// Checks a [`Tin`] (see [`ValidationReport`]). A TIN built by [`Tin::from_parts`] can still overlap itself in x,y,
/// have duplicate x,y positions among vertices no triangle uses, slivers, or coordinates too large for f32.
pub fn validate(tin: &Tin) -> ValidationReport {
    validate_parts(tin.positions(), tin.triangles())
}

/// Summary figures of a TIN.
pub fn mesh_stats(tin: &Tin) -> MeshStats {
    let bbox = tin.bbox();
    let mut area_min = f64::INFINITY;
    let mut area_max: f64 = 0.0;
    let mut area_total = 0.0;
    let mut edge_min = f64::INFINITY;
    let mut edge_max: f64 = 0.0;
    let mut min_angle = f64::INFINITY;
    let mut max_aspect: f64 = 0.0;
    let mut slivers = 0;
    for t in 0..tin.num_triangles() {
        let [a, b, c] = tin.corners(t).map(|p| p.truncate());
        let area = tin.triangle_area_xy(t);
        area_min = area_min.min(area);
        area_max = area_max.max(area);
        area_total += area;
        for (p, q) in [(a, b), (b, c), (c, a)] {
            let len = p.distance(q);
            edge_min = edge_min.min(len);
            edge_max = edge_max.max(len);
        }
        let q = triangle_quality(a, b, c);
        min_angle = min_angle.min(q.min_angle_deg);
        max_aspect = max_aspect.max(q.aspect);
        slivers += usize::from(is_sliver(q));
    }
    let boundary_edges = tin
        .neighbours()
        .iter()
        .flatten()
        .filter(|&&n| n == NO_NEIGHBOUR)
        .count();
    MeshStats {
        vertices: tin.num_vertices(),
        triangles: tin.num_triangles(),
        boundary_edges,
        bbox,
        relief: bbox.max.z - bbox.min.z,
        origin: tin.origin(),
        area_xy_total: area_total,
        area_xy_min: area_min,
        area_xy_max: area_max,
        area_xy_mean: area_total / tin.num_triangles() as f64,
        edge_xy_min: edge_min,
        edge_xy_max: edge_max,
        min_angle_deg: min_angle,
        max_aspect,
        slivers,
    }
}

impl Tin {
    /// Checks this TIN; see [`validate`].
    pub fn validate(&self) -> ValidationReport {
        validate(self)
    }

    /// Summary figures; see [`mesh_stats`].
    pub fn stats(&self) -> MeshStats {
        mesh_stats(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn tri(p: [(f64, f64); 3]) -> [DVec2; 3] {
        let mut t = p.map(|(x, y)| DVec2::new(x, y));
        if orient2d(t[0], t[1], t[2]) < 0.0 {
            t.swap(1, 2);
        }
        t
    }

    /// Area of the intersection of two counter-clockwise triangles (Sutherland-Hodgman clipping): an independent
    /// oracle for [`interiors_overlap`].
    fn intersection_area(a: &[DVec2; 3], b: &[DVec2; 3]) -> f64 {
        let mut poly: Vec<DVec2> = a.to_vec();
        for i in 0..3 {
            let (p, q) = (b[i], b[(i + 1) % 3]);
            let side = |v: DVec2| (q - p).perp_dot(v - p);
            let mut out = Vec::new();
            for k in 0..poly.len() {
                let (s, e) = (poly[k], poly[(k + 1) % poly.len()]);
                let (ds, de) = (side(s), side(e));
                if ds >= 0.0 {
                    out.push(s);
                }
                if (ds >= 0.0) != (de >= 0.0) {
                    out.push(s + (e - s) * (ds / (ds - de)));
                }
            }
            poly = out;
            if poly.is_empty() {
                return 0.0;
            }
        }
        0.5 * (0..poly.len())
            .map(|k| poly[k].perp_dot(poly[(k + 1) % poly.len()]))
            .sum::<f64>()
    }

    #[test]
    fn overlap_cases() {
        let a = tri([(0.0, 0.0), (4.0, 0.0), (0.0, 4.0)]);
        // Shared edge, other side.
        assert!(!interiors_overlap(&a, &tri([(4.0, 0.0), (0.0, 4.0), (4.0, 4.0)])));
        // Shared vertex only.
        assert!(!interiors_overlap(&a, &tri([(4.0, 0.0), (6.0, 0.0), (5.0, 1.0)])));
        // Touching along part of an edge (T-junction).
        assert!(!interiors_overlap(&a, &tri([(1.0, 0.0), (3.0, 0.0), (2.0, -1.0)])));
        // Identical.
        assert!(interiors_overlap(&a, &a));
        // One inside the other.
        assert!(interiors_overlap(&a, &tri([(1.0, 1.0), (2.0, 1.0), (1.0, 2.0)])));
        // Star of David: no vertex inside the other, edges cross.
        let up = tri([(0.0, 0.0), (6.0, 0.0), (3.0, 5.0)]);
        let down = tri([(0.0, 3.0), (6.0, 3.0), (3.0, -2.0)]);
        assert!(interiors_overlap(&up, &down));
        // Same edge, same side.
        assert!(interiors_overlap(&a, &tri([(0.0, 0.0), (4.0, 0.0), (1.0, 1.0)])));
        // Disjoint.
        assert!(!interiors_overlap(&a, &tri([(5.0, 5.0), (6.0, 5.0), (5.0, 6.0)])));
    }

    #[test]
    fn f32_step_matches_f32() {
        for v in [
            1.0f32,
            1.5,
            100_000.0,
            4_194_304.0,
            5_000_000.0,
            0.001,
            3.0e38,
            f32::MIN_POSITIVE,
        ] {
            assert_eq!(f32_step(f64::from(v)), f64::from(v.next_up() - v), "{v}");
        }
        assert_eq!(f32_step(5e6), 0.5);
        assert_eq!(f32_step(1e5), 2f64.powi(-7));
    }

    fn small_point() -> impl Strategy<Value = (f64, f64)> {
        (0i32..7, 0i32..7).prop_map(|(x, y)| (f64::from(x), f64::from(y)))
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

        /// The exact separating-edge test agrees with the area of the clipped intersection.
        #[test]
        fn overlap_test_matches_clipping(p in prop::array::uniform3(small_point()), q in prop::array::uniform3(small_point())) {
            let (a, b) = (tri(p), tri(q));
            prop_assume!(orient2d(a[0], a[1], a[2]) != 0.0 && orient2d(b[0], b[1], b[2]) != 0.0);
            let area = intersection_area(&a, &b);
            // Intersection areas of triangles on a 7 x 7 integer grid are rationals far above 1e-6 when positive.
            prop_assert_eq!(interiors_overlap(&a, &b), area > 1e-6, "area {}", area);
            prop_assert_eq!(interiors_overlap(&a, &b), interiors_overlap(&b, &a));
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

        /// The bucketed search finds exactly the pairs that the all-pairs search finds.
        #[test]
        fn grid_search_matches_all_pairs(
            pts in prop::collection::vec((0.0f64..100.0, 0.0f64..100.0), 3..40),
            tris in prop::collection::vec((0usize..40, 0usize..40, 0usize..40), 1..60),
            limit in 0usize..10,
        ) {
            let positions: Vec<DVec3> = pts.iter().map(|&(x, y)| DVec3::new(x, y, 0.0)).collect();
            let n = positions.len();
            let triangles: Vec<[u32; 3]> = tris.iter().map(|&(a, b, c)| [(a % n) as u32, (b % n) as u32, (c % n) as u32]).collect();
            check_against_all_pairs(&positions, &triangles, limit)?;
        }

        /// Same, with many small triangles scattered over a large area (many grid cells, few overlaps).
        #[test]
        fn grid_search_matches_all_pairs_small_triangles(
            tris in prop::collection::vec(((0.0f64..200.0, 0.0f64..200.0), prop::array::uniform3((-4.0f64..4.0, -4.0f64..4.0))), 1..150),
            limit in 0usize..10,
        ) {
            let mut positions = Vec::new();
            let mut triangles = Vec::new();
            for ((x, y), corners) in &tris {
                let base = positions.len() as u32;
                positions.extend(corners.iter().map(|(dx, dy)| DVec3::new(x + dx, y + dy, 0.0)));
                triangles.push([base, base + 1, base + 2]);
            }
            check_against_all_pairs(&positions, &triangles, limit)?;
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 100, ..ProptestConfig::default() })]

        /// Same, on fans: a centre and spokes to points around it (long thin triangles that all meet the centre's
        /// cells, grouped there by their hub), some spokes out of angular order so that wedges overlap at the centre,
        /// the rim or both, and a few triangles across the fan that share no vertex with it.
        #[test]
        fn grid_search_matches_all_pairs_on_fans(
            angles in prop::collection::vec(0.0f64..std::f64::consts::TAU, 3..80),
            radii in prop::collection::vec(10.0f64..1000.0, 80),
            swaps in prop::collection::vec((0usize..80, 0usize..80), 0..3),
            across in prop::collection::vec(prop::array::uniform3((-1000.0f64..1000.0, -1000.0f64..1000.0)), 0..4),
            sorted in any::<bool>(),
            limit in 0usize..10,
        ) {
            let mut angles = angles;
            if sorted {
                angles.sort_by(f64::total_cmp);
            }
            let k = angles.len();
            for &(i, j) in &swaps {
                angles.swap(i % k, j % k);
            }
            let mut positions = vec![DVec3::ZERO];
            positions.extend(angles.iter().zip(&radii).map(|(&a, &r)| DVec3::new(r * a.cos(), r * a.sin(), 0.0)));
            let mut triangles: Vec<[u32; 3]> = (0..k as u32).map(|i| [0, i + 1, (i + 1) % k as u32 + 1]).collect();
            for corners in &across {
                let base = positions.len() as u32;
                positions.extend(corners.iter().map(|&(x, y)| DVec3::new(x, y, 0.0)));
                triangles.push([base, base + 1, base + 2]);
            }
            check_against_all_pairs(&positions, &triangles, limit)?;
        }
    }

    /// Triangles at a fan's centre over several of its spokes' wedges (one sharing its first edge with a spoke, one
    /// with another vertex of its own): every overlapping pair is found around the centre, once, also those that
    /// share no other vertex and lie beyond the first wedge overlapped.
    #[test]
    fn a_wedge_over_several_spokes() {
        let mut positions = vec![DVec3::ZERO];
        positions.extend((0..8).map(|i| {
            let a = f64::from(i) * std::f64::consts::FRAC_PI_4;
            DVec3::new(100.0 * a.cos(), 100.0 * a.sin(), 0.0)
        }));
        let a = 2.5 * std::f64::consts::FRAC_PI_4;
        positions.push(DVec3::new(50.0 * a.cos(), 50.0 * a.sin(), 0.0));
        let mut triangles: Vec<[u32; 3]> = (0..8).map(|i| [0, i + 1, (i + 1) % 8 + 1]).collect();
        triangles.push([0, 1, 9]);
        triangles.push([0, 6, 8]);
        check_against_all_pairs(&positions, &triangles, usize::MAX).expect("the pairs of all pairs");
        assert_eq!(find_overlaps(&positions, &triangles, 0).count, 5);
    }

    fn check_against_all_pairs(positions: &[DVec3], triangles: &[[u32; 3]], limit: usize) -> Result<(), TestCaseError> {
        {
            let mut expected = Vec::new();
            let ccw = |t: &[u32; 3]| {
                let c = t.map(|v| positions[v as usize].truncate());
                let o = orient2d(c[0], c[1], c[2]);
                (o != 0.0).then(|| if o < 0.0 { [c[0], c[2], c[1]] } else { c })
            };
            for i in 0..triangles.len() {
                for j in i + 1..triangles.len() {
                    if let (Some(a), Some(b)) = (ccw(&triangles[i]), ccw(&triangles[j]))
                        && interiors_overlap(&a, &b)
                    {
                        expected.push([i as u32, j as u32]);
                    }
                }
            }
            let found = find_overlaps(positions, triangles, usize::MAX);
            prop_assert_eq!(found.count, expected.len());
            prop_assert_eq!(&found.first, &expected);
            let limited = find_overlaps(positions, triangles, limit);
            prop_assert_eq!(limited.count, expected.len());
            prop_assert_eq!(&limited.first[..], &expected[..limit.min(expected.len())]);
        }
        Ok(())
    }
}
