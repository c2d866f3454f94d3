//! Greedy-insertion simplification of a [`Grid`] into a [`Tin`].
//!
//! Garland and Heckbert, "Fast Polygonal Approximation of Terrains and Height Fields" (1995), algorithm III
//! ("greedy insertion" with a Delaunay triangulation, as in their Scape program and in the `hmm` tool):
//!
//! 1. Start from a coarse triangulation that covers every valid sample.
//! 2. For each triangle, scan the grid samples inside it and remember the one of largest vertical error
//!    `|z - interpolated z|` (its candidate); keep the candidates in a max-heap.
//! 3. Pop the worst candidate, insert it into the Delaunay triangulation, and rescan only the triangles that changed.
//!    With Delaunay insertion those are exactly the triangles incident to the new vertex (the faces created by the
//!    split and by the edge flips that follow it all contain the new vertex). Every face whose vertices changed gets
//!    a new generation number, so heap entries of its previous incarnation are recognised as stale and skipped
//!    (lazy deletion); spade reuses face indices, so the generation lives in a vector indexed by face index.
//! 4. Stop when the vertex budget is reached, when the worst error is at most the error bound, or when every valid
//!    sample is reproduced exactly.
//!
//! Choices where the paper is silent:
//!
//! - **Start.** The paper starts from the four grid corners. Here the start is the convex hull of the valid
//!   (non-void) samples: its strictly convex corners, so a grid without void corners starts from exactly its four
//!   corners, and a grid with void corners starts from the extreme valid samples, so every valid sample still lies
//!   in the TIN. If that hull has more corners than the vertex budget, [`simplify`] refuses with an error.
//! - **Voids** (NaN samples) are never vertices and never contribute error; triangles simply span them.
//! - **Ties** between equal errors go to the smaller sample index (row-major), in a triangle and in the heap, so the
//!   result is deterministic.
//! - **Geometry.** The triangulation is built in exact integer coordinates `(col·p, −row·q)`, where `q/p` is the
//!   grid's `dy/dx` rounded to 1/1024 (clamped to `[1e-6, 1e6]`), so that spade's predicates and the scan of samples
//!   inside each triangle agree exactly about which sample is inside, on an edge or on the hull. The triangulation is
//!   therefore Delaunay in world metres up to that rounding of the aspect ratio. Interpolation is linear in each
//!   triangle; it is affine-invariant, so computing it in grid units gives the world-space value.
//! - **Reported error.** [`SimplifyReport::max_error`] comes from a separate final pass over every triangle of the
//!   result and every valid sample, not from the heap; vertices reproduce their sample exactly and count as zero.

use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;
use spade::handles::{FixedFaceHandle, FixedVertexHandle, InnerTag};
use spade::{DelaunayTriangulation, Point2, Triangulation};

use crate::error::{Result, TinError};
use crate::grid::Grid;
use crate::mesh::Tin;

/// When to stop inserting vertices. At least one of the two must be set; with both, whichever is reached first.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SimplifyOptions {
    /// Stop when the TIN has this many vertices.
    pub max_vertices: Option<usize>,
    /// Stop when the largest vertical error over all valid samples is at most this (metres, ≥ 0).
    pub max_error: Option<f64>,
}

impl SimplifyOptions {
    /// Stop at `n` vertices.
    pub fn vertices(n: usize) -> SimplifyOptions {
        SimplifyOptions {
            max_vertices: Some(n),
            max_error: None,
        }
    }

    /// Stop when the largest error is at most `e` metres.
    pub fn error(e: f64) -> SimplifyOptions {
        SimplifyOptions {
            max_vertices: None,
            max_error: Some(e),
        }
    }

    /// Checks that at least one stopping rule is set and that the values make sense.
    pub fn validate(&self) -> Result<()> {
        if self.max_vertices.is_none() && self.max_error.is_none() {
            return Err(TinError::InvalidParameter(
                "simplification needs max_vertices or max_error (or both)".into(),
            ));
        }
        if let Some(n) = self.max_vertices
            && n < 3
        {
            return Err(TinError::InvalidParameter(format!(
                "the vertex budget (--vertices) must be at least 3, got {n}"
            )));
        }
        if let Some(n) = self.max_vertices
            && n > u32::MAX as usize
        {
            return Err(TinError::InvalidParameter(format!(
                "the vertex budget (--vertices) must fit in 32 bits (at most 4294967295), got {n}"
            )));
        }
        if let Some(e) = self.max_error
            && !(e.is_finite() && e >= 0.0)
        {
            return Err(TinError::InvalidParameter(format!(
                "max_error must be finite and non-negative, got {}",
                crate::compact_number(e)
            )));
        }
        Ok(())
    }
}

/// Why the simplification stopped (in JSON `vertex_budget`, `error_bound`, `exact`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The vertex budget was reached.
    VertexBudget,
    /// The largest error fell to the error bound or below.
    ErrorBound,
    /// Every valid sample is reproduced exactly (nothing left to insert).
    Exact,
}

/// What [`simplify`] did.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SimplifyReport {
    /// Vertices of the result.
    pub vertices: usize,
    /// Triangles of the result.
    pub triangles: usize,
    /// Vertices of the start triangulation (the corners of the convex hull of the valid samples, and the fixed
    /// samples of [`simplify_constrained`]).
    pub initial_vertices: usize,
    /// Largest vertical error `|z - TIN(x, y)|` over all valid samples (m), from a final pass over the result.
    pub max_error: f64,
    /// The `(row, col)` of a sample with that error (the smallest row-major index among ties); `None` when exact.
    pub max_error_at: Option<(usize, usize)>,
    /// Root-mean-square vertical error over all valid samples (m).
    pub rms_error: f64,
    /// Valid samples of the grid.
    pub samples: usize,
    /// Void samples, skipped (never vertices, never an error).
    pub voids_skipped: usize,
    /// Why insertion stopped.
    pub stopped_by: StopReason,
    /// Wall time of the whole call (s).
    pub seconds: f64,
}

/// How often (in inserted vertices) the progress hook is called.
const PROGRESS_EVERY: usize = 1024;

/// Simplifies `grid` into a TIN by greedy insertion (see the module docs).
///
/// `progress`, when given, is called with the current vertex count every 1024 insertions and once at the end.
/// Vertex order is insertion order: the hull corners first, then each inserted sample. Vertex positions are exactly
/// the grid sample positions ([`Grid::sample`]).
pub fn simplify(
    grid: &Grid,
    opts: &SimplifyOptions,
    progress: Option<&dyn Fn(usize)>,
) -> Result<(Tin, SimplifyReport)> {
    simplify_constrained(grid, &[], &[], opts, progress)
}

/// [`simplify`] with constraints, for tiles that must join their neighbours exactly: every sample of `fixed` is a
/// vertex from the start (after the hull corners, in the given order), and no sample of `frozen` is ever inserted
/// (unless it is also fixed or a hull corner). Frozen samples count as voids for the error: the caller bounds their
/// error itself (a tile's sides are simplified on their own, see crate `tiles`). Indices are row-major sample
/// indices; a void, out-of-range or repeated fixed sample is an error naming its row and column.
pub fn simplify_constrained(
    grid: &Grid,
    fixed: &[u32],
    frozen: &[u32],
    opts: &SimplifyOptions,
    progress: Option<&dyn Fn(usize)>,
) -> Result<(Tin, SimplifyReport)> {
    let start = Instant::now();
    opts.validate()?;
    check_grid(grid)?;
    let mut s = Simplifier::new(grid)?;
    let mut start_vertices = valid_hull(grid)?;
    let hull_corners = start_vertices.len();
    let mut is_start = vec![false; grid.z.len()];
    for &v in &start_vertices {
        is_start[v as usize] = true;
    }
    let at = |i: u32| (i as usize / grid.cols, i as usize % grid.cols);
    let mut seen = vec![false; grid.z.len()];
    for &f in fixed {
        let (r, c) = at(f);
        if f as usize >= grid.z.len() || grid.z[f as usize].is_nan() {
            return Err(TinError::InvalidParameter(format!(
                "fixed sample (row {r}, col {c}) is outside the grid or void"
            )));
        }
        if std::mem::replace(&mut seen[f as usize], true) {
            return Err(TinError::InvalidParameter(format!(
                "fixed sample (row {r}, col {c}) is given twice"
            )));
        }
        if !std::mem::replace(&mut is_start[f as usize], true) {
            start_vertices.push(f);
        }
    }
    let budget = opts.max_vertices.unwrap_or(usize::MAX);
    if start_vertices.len() > budget {
        let more = start_vertices.len() - hull_corners;
        return Err(TinError::InvalidParameter(format!(
            "a budget of {budget} vertices is too small: the convex hull of the valid samples already has {hull_corners} \
             corners{}",
            if more > 0 {
                format!(" and {more} more fixed samples")
            } else {
                String::new()
            }
        )));
    }
    for &f in frozen {
        if f as usize >= grid.z.len() {
            let (r, c) = at(f);
            return Err(TinError::InvalidParameter(format!(
                "frozen sample (row {r}, col {c}) is outside the grid"
            )));
        }
        if !is_start[f as usize] {
            s.open[f as usize] = f64::NAN;
        }
    }
    let start_len = start_vertices.len();
    s.start(&start_vertices)?;
    let bound = opts.max_error.unwrap_or(0.0);
    let stopped_by = s.run(budget, bound, progress)?;
    if let Some(p) = progress {
        p(s.vertex_sample.len());
    }
    let (tin, mut report) = s.finish(stopped_by)?;
    report.initial_vertices = start_len;
    report.seconds = start.elapsed().as_secs_f64();
    Ok((tin, report))
}

/// Rejects grids whose dimensions do not match their data (the fields are public, so [`Grid::new`] may be bypassed).
fn check_grid(grid: &Grid) -> Result<()> {
    if grid.rows < 2 || grid.cols < 2 || grid.z.len() != grid.rows * grid.cols {
        return Err(TinError::InvalidParameter(format!(
            "grid of {} x {} samples with {} heights cannot be simplified",
            grid.rows,
            grid.cols,
            grid.z.len()
        )));
    }
    if grid.rows > 1 << 24 || grid.cols > 1 << 24 || grid.rows * grid.cols > u32::MAX as usize {
        return Err(TinError::InvalidParameter(format!(
            "grid of {} x {} samples is too large to simplify (at most 2^32 samples)",
            grid.rows, grid.cols
        )));
    }
    if !(grid.dx.is_finite() && grid.dy.is_finite() && grid.dx > 0.0 && grid.dy > 0.0) {
        return Err(TinError::InvalidParameter(format!(
            "grid spacing must be positive and finite, got {}, {}",
            grid.dx, grid.dy
        )));
    }
    if let Some(i) = grid.z.iter().position(|h| h.is_infinite()) {
        return Err(TinError::InvalidParameter(format!(
            "row {}, column {} (1-based, row 1 north): the height is infinite",
            i / grid.cols + 1,
            i % grid.cols + 1
        )));
    }
    Ok(())
}

/// The strictly convex corners of the convex hull of the valid samples, as sample indices, counter-clockwise in
/// world x,y (Andrew's monotone chain over the first and last valid sample of each row, in exact integer arithmetic).
fn valid_hull(grid: &Grid) -> Result<Vec<u32>> {
    // Points as (col, -row) so that the orientation matches world x,y.
    let mut pts: Vec<(i64, i64)> = Vec::with_capacity(2 * grid.rows);
    for r in 0..grid.rows {
        let row = &grid.z[r * grid.cols..(r + 1) * grid.cols];
        let first = row.iter().position(|z| !z.is_nan());
        let last = row.iter().rposition(|z| !z.is_nan());
        if let (Some(a), Some(b)) = (first, last) {
            pts.push((a as i64, -(r as i64)));
            if b != a {
                pts.push((b as i64, -(r as i64)));
            }
        }
    }
    pts.sort_unstable();
    let cross = |o: (i64, i64), a: (i64, i64), b: (i64, i64)| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    let mut hull: Vec<(i64, i64)> = Vec::with_capacity(pts.len() + 1);
    for &p in &pts {
        while hull.len() >= 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0 {
            hull.pop();
        }
        hull.push(p);
    }
    let lower = hull.len() + 1;
    for &p in pts.iter().rev().skip(1) {
        while hull.len() >= lower && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0 {
            hull.pop();
        }
        hull.push(p);
    }
    hull.pop(); // the first point again
    if hull.len() < 3 {
        return Err(TinError::TooFewPoints(format!(
            "the grid has {} valid samples and they do not span an area (all void or collinear)",
            grid.z.iter().filter(|z| !z.is_nan()).count()
        )));
    }
    Ok(hull
        .into_iter()
        .map(|(c, nr)| ((-nr) as usize * grid.cols + c as usize) as u32)
        .collect())
}

/// A heap entry: the worst sample of face `face` in its generation `generation`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Candidate {
    /// `error.to_bits()`: errors are non-negative, so the bit patterns order like the values.
    error_bits: u64,
    sample: u32,
    face: u32,
    generation: u32,
}

impl Ord for Candidate {
    fn cmp(&self, other: &Self) -> Ordering {
        self.error_bits
            .cmp(&other.error_bits)
            .then(other.sample.cmp(&self.sample)) // smaller sample index first
            .then(other.face.cmp(&self.face))
            .then(self.generation.cmp(&other.generation))
    }
}

impl PartialOrd for Candidate {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// What was recorded about a face when it was last scanned.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct FaceRecord {
    generation: u32,
    /// Its vertices (spade vertex indices = insertion order), in spade's order.
    vertices: [u32; 3],
    /// Its worst sample and that sample's error, if any sample inside is neither a vertex nor a void.
    worst: Option<(f64, u32)>,
}

/// The state of one greedy-insertion run.
struct Simplifier<'g> {
    grid: &'g Grid,
    /// Heights with voids and vertices set to NaN: exactly the samples that still contribute error.
    open: Vec<f64>,
    dt: DelaunayTriangulation<Point2<f64>>,
    /// Integer scales of columns and rows in spade's coordinates.
    scale: (f64, f64),
    /// Sample index of each spade vertex, by vertex index (= insertion order).
    vertex_sample: Vec<u32>,
    faces: Vec<FaceRecord>,
    heap: BinaryHeap<Candidate>,
}

impl<'g> Simplifier<'g> {
    fn new(grid: &'g Grid) -> Result<Simplifier<'g>> {
        let ratio = (grid.dy / grid.dx).clamp(1e-6, 1e6);
        let scale = if ratio >= 1.0 {
            (1024.0, (1024.0 * ratio).round())
        } else {
            ((1024.0 / ratio).round(), 1024.0)
        };
        // Keep every coordinate an integer below 2^53, so it is exact in f64.
        if grid.cols as f64 * scale.0 > 2f64.powi(53) || grid.rows as f64 * scale.1 > 2f64.powi(53) {
            return Err(TinError::InvalidParameter(format!(
                "grid of {} x {} samples with spacing {} x {} is too elongated to simplify exactly",
                grid.rows, grid.cols, grid.dx, grid.dy
            )));
        }
        Ok(Simplifier {
            grid,
            open: grid.z.clone(),
            dt: DelaunayTriangulation::new(),
            scale,
            vertex_sample: Vec::new(),
            faces: Vec::new(),
            heap: BinaryHeap::new(),
        })
    }

    fn spade_point(&self, sample: u32) -> Point2<f64> {
        let (r, c) = self.row_col(sample);
        Point2::new(c as f64 * self.scale.0, -(r as f64) * self.scale.1)
    }

    fn row_col(&self, sample: u32) -> (usize, usize) {
        let s = sample as usize;
        (s / self.grid.cols, s % self.grid.cols)
    }

    /// Inserts the hull corners and scans the first faces.
    fn start(&mut self, hull: &[u32]) -> Result<()> {
        for &s in hull {
            self.insert_vertex(s, None)?;
        }
        let faces: Vec<FixedFaceHandle<InnerTag>> = self.dt.inner_faces().map(|f| f.fix()).collect();
        for f in faces {
            self.rescan_face(f);
        }
        Ok(())
    }

    /// Inserts sample `s` and returns its vertex handle.
    fn insert_vertex(&mut self, s: u32, hint: Option<FixedVertexHandle>) -> Result<FixedVertexHandle> {
        let p = self.spade_point(s);
        let before = self.dt.num_vertices();
        let handle = match hint {
            Some(h) => self.dt.insert_with_hint(p, h),
            None => self.dt.insert(p),
        }
        .map_err(|e| TinError::Insertion {
            index: s as usize,
            reason: e.to_string(),
        })?;
        if self.dt.num_vertices() != before + 1 || handle.index() != before {
            let (r, c) = self.row_col(s);
            return Err(TinError::InvalidParameter(format!(
                "internal error: sample (row {r}, col {c}) was already a vertex"
            )));
        }
        self.vertex_sample.push(s);
        self.open[s as usize] = f64::NAN;
        Ok(handle)
    }

    /// Scans face `handle`, records it under a new generation and pushes its candidate.
    fn rescan_face(&mut self, handle: FixedFaceHandle<InnerTag>) {
        let f = handle.index();
        let vertices = self.dt.face(handle).vertices().map(|v| v.fix().index() as u32);
        let samples = vertices.map(|v| self.vertex_sample[v as usize]);
        let worst = scan_triangle(self.grid.cols, &self.grid.z, &self.open, samples);
        if self.faces.len() <= f {
            self.faces.resize(f + 1, FaceRecord::default());
        }
        let rec = &mut self.faces[f];
        rec.generation = rec.generation.wrapping_add(1);
        rec.vertices = vertices;
        rec.worst = worst;
        if let Some((e, s)) = worst {
            self.heap.push(Candidate {
                error_bits: e.to_bits(),
                sample: s,
                face: f as u32,
                generation: rec.generation,
            });
        }
    }

    /// The current worst candidate, dropping stale heap entries.
    fn top(&mut self) -> Option<Candidate> {
        while let Some(&c) = self.heap.peek() {
            if self.faces[c.face as usize].generation == c.generation {
                return Some(c);
            }
            self.heap.pop();
        }
        None
    }

    /// Inserts the worst sample while the budget and the error bound allow.
    fn run(&mut self, budget: usize, bound: f64, progress: Option<&dyn Fn(usize)>) -> Result<StopReason> {
        loop {
            if self.vertex_sample.len() >= budget {
                return Ok(StopReason::VertexBudget);
            }
            let Some(c) = self.top() else {
                return Ok(StopReason::Exact);
            };
            if f64::from_bits(c.error_bits) <= bound {
                return Ok(StopReason::ErrorBound);
            }
            self.heap.pop();
            self.insert_step(c)?;
            if let Some(p) = progress
                && self.vertex_sample.len().is_multiple_of(PROGRESS_EVERY)
            {
                p(self.vertex_sample.len());
            }
        }
    }

    /// Inserts the candidate's sample and rescans the faces around it.
    fn insert_step(&mut self, c: Candidate) -> Result<()> {
        let rec = self.faces[c.face as usize];
        // A vertex of the face that held the sample: the point location walk starts right there.
        let hint = FixedVertexHandle::from_index(rec.vertices[0] as usize);
        debug_assert_eq!(rec.worst.map(|w| w.1), Some(c.sample));
        let v = self.insert_vertex(c.sample, Some(hint))?;
        let star: Vec<FixedFaceHandle<InnerTag>> = self
            .dt
            .vertex(v)
            .out_edges()
            .filter_map(|e| e.face().as_inner().map(|f| f.fix()))
            .collect();
        for f in star {
            self.rescan_face(f);
        }
        Ok(())
    }

    /// Builds the TIN and the report, with the error measured by a fresh pass over every face.
    fn finish(self, stopped_by: StopReason) -> Result<(Tin, SimplifyReport)> {
        let grid = self.grid;
        let positions: Vec<DVec3> = self
            .vertex_sample
            .iter()
            .map(|&s| {
                let (r, c) = self.row_col(s);
                grid.sample(r, c).ok_or_else(|| {
                    TinError::InvalidParameter(format!("internal error: vertex at void sample (row {r}, col {c})"))
                })
            })
            .collect::<Result<_>>()?;
        let faces: Vec<[u32; 3]> = self
            .dt
            .inner_faces()
            .map(|f| f.vertices().map(|v| v.fix().index() as u32))
            .collect();
        let cols = grid.cols;
        let open = &self.open;
        let vertex_sample = &self.vertex_sample;
        // Per face: worst (error, sample) and the sum of squared errors of the samples it owns. A sample on an edge
        // shared by two faces is owned by the first face in `faces` order (via `owner`), so the sum counts it once.
        let mut owner = vec![u32::MAX; open.len()];
        for (fi, f) in faces.iter().enumerate() {
            for_each_span(cols, f.map(|v| vertex_sample[v as usize]), |r, lo, hi| {
                let base = r as usize * cols;
                for o in &mut owner[base + lo as usize..=base + hi as usize] {
                    if *o == u32::MAX {
                        *o = fi as u32;
                    }
                }
            });
        }
        let per_face: Vec<(Option<(f64, u32)>, f64)> = faces
            .par_iter()
            .enumerate()
            .map(|(fi, f)| {
                let samples = f.map(|v| vertex_sample[v as usize]);
                let worst = scan_triangle(cols, &grid.z, open, samples);
                let mut sq = 0.0;
                let plane = Plane::new(cols, &grid.z, samples);
                for_each_span(cols, samples, |r, lo, hi| {
                    let base = r as usize * cols;
                    let row = plane.row(r);
                    for c in lo..=hi {
                        let s = base + c as usize;
                        let z = open[s];
                        if !z.is_nan() && owner[s] == fi as u32 {
                            let e = z - plane.at(row, c);
                            sq += e * e;
                        }
                    }
                });
                (worst, sq)
            })
            .collect();
        let mut worst: Option<(f64, u32)> = None;
        let mut sum_sq = 0.0;
        for (w, sq) in per_face {
            sum_sq += sq;
            if let Some((e, s)) = w
                && worst.is_none_or(|(we, ws)| e > we || (e == we && s < ws))
            {
                worst = Some((e, s));
            }
        }
        let voids = grid.z.iter().filter(|z| z.is_nan()).count();
        let samples = grid.z.len() - voids;
        let uncovered = owner
            .iter()
            .zip(&grid.z)
            .position(|(&o, z)| o == u32::MAX && !z.is_nan());
        if let Some(i) = uncovered {
            return Err(TinError::InvalidParameter(format!(
                "internal error: sample (row {}, col {}) is outside the simplified TIN",
                i / cols,
                i % cols
            )));
        }
        let tin = Tin::from_parts(positions, faces)?;
        let report = SimplifyReport {
            vertices: tin.num_vertices(),
            triangles: tin.num_triangles(),
            initial_vertices: 0,
            max_error: worst.map_or(0.0, |w| w.0),
            max_error_at: worst.map(|(_, s)| (s as usize / cols, s as usize % cols)),
            rms_error: (sum_sq / samples as f64).sqrt(),
            samples,
            voids_skipped: voids,
            stopped_by,
            seconds: 0.0,
        };
        Ok((tin, report))
    }
}

/// The linear interpolant of a triangle of grid samples, in grid units relative to its first vertex.
struct Plane {
    c0: i64,
    r0: i64,
    z0: f64,
    gc: f64,
    gr: f64,
}

impl Plane {
    /// The plane through the three samples; heights from `z` (the original grid, so vertices are included).
    fn new(cols: usize, z: &[f64], samples: [u32; 3]) -> Plane {
        let rc = samples.map(|s| ((s as usize % cols) as i64, (s as usize / cols) as i64));
        let zz = samples.map(|s| z[s as usize]);
        let (c1, r1) = (rc[1].0 - rc[0].0, rc[1].1 - rc[0].1);
        let (c2, r2) = (rc[2].0 - rc[0].0, rc[2].1 - rc[0].1);
        let det = (c1 * r2 - r1 * c2) as f64;
        let (dz1, dz2) = (zz[1] - zz[0], zz[2] - zz[0]);
        Plane {
            c0: rc[0].0,
            r0: rc[0].1,
            z0: zz[0],
            gc: (dz1 * r2 as f64 - dz2 * r1 as f64) / det,
            gr: (c1 as f64 * dz2 - c2 as f64 * dz1) / det,
        }
    }

    /// The interpolated height at row `r`, column `c0` (the first vertex's column).
    fn row(&self, r: i64) -> f64 {
        self.z0 + self.gr * (r - self.r0) as f64
    }

    /// Interpolated height at column `c` of a row whose [`Plane::row`] value is `row`.
    fn at(&self, row: f64, c: i64) -> f64 {
        row + self.gc * (c - self.c0) as f64
    }
}

/// Calls `f(row, first_col, last_col)` for every row of grid samples inside or on the boundary of the triangle of
/// samples `tri`, top row first; rows without samples are skipped. Membership is decided in exact integer arithmetic.
fn for_each_span(cols: usize, tri: [u32; 3], mut f: impl FnMut(i64, i64, i64)) {
    let mut p = tri.map(|s| ((s as usize % cols) as i64, (s as usize / cols) as i64));
    let orient = |a: (i64, i64), b: (i64, i64), c: (i64, i64)| (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
    let area = orient(p[0], p[1], p[2]);
    if area == 0 {
        return;
    }
    if area < 0 {
        p.swap(1, 2);
    }
    let rmin = p.iter().map(|q| q.1).min().unwrap_or(0);
    let rmax = p.iter().map(|q| q.1).max().unwrap_or(-1);
    let cmin = p.iter().map(|q| q.0).min().unwrap_or(0);
    let cmax = p.iter().map(|q| q.0).max().unwrap_or(-1);
    for r in rmin..=rmax {
        let (mut lo, mut hi) = (cmin, cmax);
        for i in 0..3 {
            let (a, b) = (p[i], p[(i + 1) % 3]);
            // orient(a, b, (c, r)) = A·c + k, non-negative inside.
            let coef = -(b.1 - a.1);
            let k = (b.0 - a.0) * (r - a.1) + (b.1 - a.1) * a.0;
            match coef.cmp(&0) {
                Ordering::Greater => lo = lo.max(-k.div_euclid(coef)), // c >= ceil(-k / A)
                Ordering::Less => hi = hi.min(k.div_euclid(-coef)),    // c <= floor(k / -A)
                Ordering::Equal => {
                    if k < 0 {
                        hi = lo - 1;
                    }
                }
            }
        }
        if lo <= hi {
            f(r, lo, hi);
        }
    }
}

/// The worst sample of a triangle: largest `|z - plane|` over the samples inside or on it that are still open (not
/// a vertex, not a void), ties to the smaller index; `None` if every such sample is reproduced exactly. `z` holds the
/// grid heights, `open` the same with vertices and voids as NaN.
fn scan_triangle(cols: usize, z: &[f64], open: &[f64], tri: [u32; 3]) -> Option<(f64, u32)> {
    let mut worst = 0.0;
    let mut at = usize::MAX;
    let plane = Plane::new(cols, z, tri);
    for_each_span(cols, tri, |r, lo, hi| {
        let base = r as usize * cols;
        let row = plane.row(r);
        let span = &open[base + lo as usize..=base + hi as usize];
        for (c, &h) in (lo..).zip(span) {
            // NaN (vertex or void) fails the comparison and is skipped.
            let e = (h - plane.at(row, c)).abs();
            if e > worst {
                worst = e;
                at = base + c as usize;
            }
        }
    });
    (at != usize::MAX).then_some((worst, at as u32))
}

#[cfg(test)]
impl Simplifier<'_> {
    /// Every inner face has a record made from its current vertices, whose worst sample is what a fresh scan finds,
    /// and whose candidate is live in the heap; every live heap entry belongs to such a face.
    fn check_invariants(&self) {
        use std::collections::HashMap;
        let mut live: HashMap<u32, Candidate> = HashMap::new();
        for c in &self.heap {
            if self.faces[c.face as usize].generation == c.generation {
                assert!(
                    live.insert(c.face, *c).is_none(),
                    "two live heap entries for face {}",
                    c.face
                );
            }
        }
        let mut inner = 0;
        for f in self.dt.inner_faces() {
            inner += 1;
            let i = f.fix().index();
            let rec = self.faces[i];
            let now = f.vertices().map(|v| v.fix().index() as u32);
            assert_eq!(rec.vertices, now, "face {i} changed without being rescanned");
            let samples = now.map(|v| self.vertex_sample[v as usize]);
            let fresh = scan_triangle(self.grid.cols, &self.grid.z, &self.open, samples);
            assert_eq!(rec.worst, fresh, "face {i} has a stale worst sample");
            match fresh {
                Some((e, s)) => {
                    let c = live
                        .get(&(i as u32))
                        .unwrap_or_else(|| panic!("face {i} has no live heap entry"));
                    assert_eq!((c.error_bits, c.sample), (e.to_bits(), s));
                }
                None => assert!(!live.contains_key(&(i as u32))),
            }
        }
        assert!(live.len() <= inner);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;
    use proptest::prelude::*;

    /// Independent oracle: for every valid sample, finds a triangle of `tin` containing it (world coordinates,
    /// barycentric weights with a small tolerance) and returns the largest `|z - interpolation|`, its sample, and
    /// whether every valid sample was covered.
    fn brute_force_error(grid: &Grid, tin: &Tin) -> (f64, Option<usize>, bool) {
        let o = tin.origin().truncate();
        let mut interp = vec![f64::NAN; grid.z.len()];
        for t in 0..tin.num_triangles() {
            let [a, b, c] = tin.corners(t);
            let (pa, pb, pc) = (a.truncate() - o, b.truncate() - o, c.truncate() - o);
            let area = (pb - pa).perp_dot(pc - pa);
            let lo = pa.min(pb).min(pc) + o;
            let hi = pa.max(pb).max(pc) + o;
            let c0 = ((lo.x - grid.origin.x) / grid.dx).floor().max(0.0) as usize;
            let c1 = (((hi.x - grid.origin.x) / grid.dx).ceil() as usize).min(grid.cols - 1);
            let r0 = ((grid.origin.y - hi.y) / grid.dy).floor().max(0.0) as usize;
            let r1 = (((grid.origin.y - lo.y) / grid.dy).ceil() as usize).min(grid.rows - 1);
            for r in r0..=r1 {
                for col in c0..=c1 {
                    let p = DVec2::new(grid.origin.x + col as f64 * grid.dx, grid.origin.y - r as f64 * grid.dy) - o;
                    let wa = (pc - pb).perp_dot(p - pb) / area;
                    let wb = (pa - pc).perp_dot(p - pc) / area;
                    let wc = (pb - pa).perp_dot(p - pa) / area;
                    if wa >= -1e-9 && wb >= -1e-9 && wc >= -1e-9 {
                        interp[r * grid.cols + col] = wa * a.z + wb * b.z + wc * c.z;
                    }
                }
            }
        }
        let mut worst = (0.0, None);
        let mut covered = true;
        for (i, (&z, &h)) in grid.z.iter().zip(&interp).enumerate() {
            if z.is_nan() {
                continue;
            }
            if h.is_nan() {
                covered = false;
                continue;
            }
            let e = (z - h).abs();
            if e > worst.0 {
                worst = (e, Some(i));
            }
        }
        (worst.0, worst.1, covered)
    }

    fn grid_from(rows: usize, cols: usize, z: Vec<f64>) -> Grid {
        Grid::new(rows, cols, 30.0, 40.0, DVec2::new(500_000.0, 4_000_000.0), z).expect("valid grid")
    }

    /// Smooth hills with a sharp ridge (for monotonicity on smooth terrain).
    fn hills(rows: usize, cols: usize) -> Grid {
        let z = (0..rows * cols)
            .map(|i| {
                let (r, c) = ((i / cols) as f64, (i % cols) as f64);
                100.0 * (r / 7.0).sin() * (c / 9.0).cos() + 3.0 * r - (c - cols as f64 / 2.0).abs() * 2.0
            })
            .collect();
        grid_from(rows, cols, z)
    }

    #[test]
    fn constrained_keeps_fixed_samples_and_never_inserts_frozen_ones() {
        let g = hills(9, 9);
        let top_row: Vec<u32> = (0..9).collect();
        let (tin, report) =
            simplify_constrained(&g, &[4, 40], &top_row, &SimplifyOptions::error(0.0), None).expect("constrained");
        assert_eq!(report.initial_vertices, 6);
        let top: Vec<f64> = tin
            .positions()
            .iter()
            .filter(|p| p.y == g.origin.y)
            .map(|p| p.x - g.origin.x)
            .collect();
        let mut top = top;
        top.sort_by(f64::total_cmp);
        assert_eq!(
            top,
            vec![0.0, 4.0 * g.dx, 8.0 * g.dx],
            "the top row keeps its corners and sample 4 only"
        );
        let centre = g.sample(4, 4).expect("centre");
        assert!(tin.positions().contains(&centre));
        // Every sample off the top row is exact (error bound 0).
        let (e, _, covered) = brute_force_error(&g, &tin);
        assert!(covered);
        assert!(e.is_finite());
        let err = simplify_constrained(&g, &[4, 4], &[], &SimplifyOptions::error(0.0), None).expect_err("twice");
        assert!(err.to_string().contains("given twice"), "{err}");
        let mut holed = hills(9, 9);
        holed.z[40] = f64::NAN;
        let err = simplify_constrained(&holed, &[40], &[], &SimplifyOptions::error(0.0), None).expect_err("void");
        assert!(err.to_string().contains("row 4, col 4"), "{err}");
    }

    /// Checks the report and the TIN against the oracle and the grid.
    fn check_result(grid: &Grid, opts: &SimplifyOptions, tin: &Tin, report: &SimplifyReport) {
        let (e, _, covered) = brute_force_error(grid, tin);
        assert!(covered, "some valid sample lies outside the TIN");
        let tol = 1e-9 * (1.0 + e);
        assert!(
            (report.max_error - e).abs() <= tol,
            "reported {} vs brute force {e}",
            report.max_error
        );
        assert_eq!(report.vertices, tin.num_vertices());
        assert_eq!(report.triangles, tin.num_triangles());
        assert_eq!(report.voids_skipped, grid.voids());
        for p in tin.positions() {
            let col = ((p.x - grid.origin.x) / grid.dx).round() as usize;
            let row = ((grid.origin.y - p.y) / grid.dy).round() as usize;
            assert_eq!(grid.sample(row, col), Some(*p), "vertex is not a valid grid sample");
        }
        match report.stopped_by {
            StopReason::VertexBudget => assert_eq!(Some(report.vertices), opts.max_vertices),
            StopReason::ErrorBound => assert!(report.max_error <= opts.max_error.expect("bound set")),
            StopReason::Exact => {
                assert_eq!(report.max_error, 0.0);
                assert_eq!(report.rms_error, 0.0);
            }
        }
        if let Some(n) = opts.max_vertices {
            assert!(report.vertices <= n);
        }
    }

    #[test]
    fn planar_grid_needs_only_the_corners() {
        let z = (0..15 * 20)
            .map(|i| 0.37 * (i / 20) as f64 - 1.3 * (i % 20) as f64 + 250.0)
            .collect();
        let grid = grid_from(15, 20, z);
        let opts = SimplifyOptions::error(1e-9);
        let (tin, report) = simplify(&grid, &opts, None).expect("simplify");
        assert_eq!(report.vertices, 4);
        assert_eq!(report.triangles, 2);
        assert_eq!(report.initial_vertices, 4);
        assert!(report.max_error < 1e-9);
        check_result(&grid, &opts, &tin, &report);
    }

    #[test]
    fn full_budget_reproduces_the_grid() {
        let grid = hills(17, 13);
        let opts = SimplifyOptions::vertices(17 * 13);
        let (tin, report) = simplify(&grid, &opts, None).expect("simplify");
        // Samples that the TIN already reproduces exactly are not inserted.
        assert_eq!(report.stopped_by, StopReason::Exact);
        assert!(report.vertices <= 17 * 13);
        assert_eq!(report.max_error, 0.0);
        assert_eq!(report.rms_error, 0.0);
        check_result(&grid, &opts, &tin, &report);
        // Error bound 0 does the same.
        let (tin0, report0) = simplify(&grid, &SimplifyOptions::error(0.0), None).expect("simplify");
        assert_eq!(report0.stopped_by, StopReason::Exact);
        assert_eq!(tin0, tin);
    }

    #[test]
    fn error_shrinks_as_the_budget_grows() {
        let grid = hills(60, 70);
        let errors: Vec<f64> = [4, 20, 100, 500, 2000]
            .iter()
            .map(|&n| {
                simplify(&grid, &SimplifyOptions::vertices(n), None)
                    .expect("simplify")
                    .1
                    .max_error
            })
            .collect();
        for w in errors.windows(2) {
            assert!(w[1] <= w[0], "errors {errors:?}");
        }
        assert!(errors[4] < errors[0] / 10.0, "errors {errors:?}");
    }

    #[test]
    fn error_bound_stops_at_the_first_vertex_count_that_meets_it() {
        let grid = hills(40, 45);
        for bound in [50.0, 10.0, 2.0, 0.5] {
            let opts = SimplifyOptions::error(bound);
            let (tin, report) = simplify(&grid, &opts, None).expect("simplify");
            check_result(&grid, &opts, &tin, &report);
            assert!(report.max_error <= bound);
            // One vertex fewer: the same greedy run stopped earlier, and its error was still above the bound.
            let (_, before) = simplify(&grid, &SimplifyOptions::vertices(report.vertices - 1), None).expect("simplify");
            assert!(
                before.max_error > bound,
                "bound {bound}: {} at one vertex fewer",
                before.max_error
            );
        }
    }

    #[test]
    fn smaller_budgets_give_prefixes_of_the_insertion_order() {
        let grid = hills(30, 30);
        let (big, _) = simplify(&grid, &SimplifyOptions::vertices(300), None).expect("simplify");
        let (small, _) = simplify(&grid, &SimplifyOptions::vertices(120), None).expect("simplify");
        assert_eq!(&big.positions()[..120], small.positions());
    }

    #[test]
    fn void_corners_start_from_the_hull_of_valid_samples() {
        let mut grid = hills(20, 25);
        for (r, c) in [(0, 0), (0, 1), (1, 0), (19, 24), (19, 23), (0, 24), (5, 5), (6, 5)] {
            grid.z[r * 25 + c] = f64::NAN;
        }
        let opts = SimplifyOptions::vertices(60);
        let (tin, report) = simplify(&grid, &opts, None).expect("simplify");
        assert_eq!(report.voids_skipped, 8);
        // The strictly convex hull corners; (1, 1) lies on the edge from (0, 2) to (2, 0), so it is not one.
        let hull: Vec<(usize, usize)> = tin.positions()[..report.initial_vertices]
            .iter()
            .map(|p| {
                (
                    ((grid.origin.y - p.y) / grid.dy).round() as usize,
                    ((p.x - grid.origin.x) / grid.dx).round() as usize,
                )
            })
            .collect();
        let mut sorted = hull.clone();
        sorted.sort_unstable();
        assert_eq!(
            sorted,
            vec![(0, 2), (0, 23), (1, 24), (2, 0), (18, 24), (19, 0), (19, 22)]
        );
        check_result(&grid, &opts, &tin, &report);
    }

    #[test]
    fn progress_reports_vertex_counts() {
        let grid = hills(60, 60);
        let seen = std::cell::RefCell::new(Vec::new());
        let hook = |n: usize| seen.borrow_mut().push(n);
        let (_, report) = simplify(&grid, &SimplifyOptions::vertices(2100), Some(&hook)).expect("simplify");
        assert_eq!(*seen.borrow(), vec![1024, 2048, report.vertices]);
    }

    #[test]
    fn rejects_bad_options_and_grids() {
        let grid = hills(5, 5);
        let bad = [
            SimplifyOptions::default(),
            SimplifyOptions::vertices(2),
            SimplifyOptions::error(-1.0),
            SimplifyOptions::error(f64::NAN),
        ];
        for opts in bad {
            assert!(
                matches!(simplify(&grid, &opts, None), Err(TinError::InvalidParameter(_))),
                "{opts:?}"
            );
        }
        let mut voids = hills(5, 5);
        voids.z.iter_mut().for_each(|z| *z = f64::NAN);
        assert!(matches!(
            simplify(&voids, &SimplifyOptions::vertices(10), None),
            Err(TinError::TooFewPoints(_))
        ));
        // Valid samples on one line only.
        let mut line = hills(5, 5);
        for (i, z) in line.z.iter_mut().enumerate() {
            if i / 5 != i % 5 {
                *z = f64::NAN;
            }
        }
        assert!(matches!(
            simplify(&line, &SimplifyOptions::vertices(10), None),
            Err(TinError::TooFewPoints(_))
        ));
        // A hull of 8 corners does not fit in 5 vertices.
        let mut octagon = hills(5, 5);
        for i in [0, 4, 20, 24] {
            octagon.z[i] = f64::NAN;
        }
        let err = simplify(&octagon, &SimplifyOptions::vertices(5), None).expect_err("hull too big");
        assert!(err.to_string().contains("8 corners"), "{err}");
        // Inconsistent public fields.
        let mut broken = hills(5, 5);
        broken.z.pop();
        assert!(simplify(&broken, &SimplifyOptions::vertices(10), None).is_err());
        broken = hills(5, 5);
        broken.z[3] = f64::INFINITY;
        assert!(simplify(&broken, &SimplifyOptions::vertices(10), None).is_err());
    }

    #[test]
    fn jacksboro_fault_to_10k_vertices() {
        // Developer data beside the clone (CI has it): missing data is a failure, not a skip.
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/dem/jacksboro_fault.npy");
        let grid = crate::dem::npy::read_npy(&path, &crate::dem::DemOptions::default())
            .unwrap_or_else(|e| panic!("{e} (the test needs ../shared/dem beside the repository)"));
        assert_eq!((grid.rows, grid.cols, grid.dx, grid.dy), (344, 403, 74.485, 92.767));
        let opts = SimplifyOptions::vertices(10_000);
        let (tin, report) = simplify(&grid, &opts, None).expect("simplify");
        assert_eq!(report.vertices, 10_000);
        assert_eq!(report.initial_vertices, 4);
        assert!(report.max_error > 0.0 && report.max_error < 50.0, "{report:?}");
        check_result(&grid, &opts, &tin, &report);
    }

    /// A random small grid: heights from a few levels (so ties happen) or continuous, with voids.
    fn arb_grid() -> impl Strategy<Value = Grid> {
        (2usize..16, 2usize..16, any::<bool>(), 0.0f64..0.3, any::<u64>()).prop_map(
            |(rows, cols, levels, void_rate, seed)| {
                use rand::{RngExt, SeedableRng};
                let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
                let z = (0..rows * cols)
                    .map(|_| {
                        if rng.random::<f64>() < void_rate {
                            f64::NAN
                        } else if levels {
                            f64::from(rng.random_range(0..4i32)) * 10.0
                        } else {
                            rng.random_range(-100.0..100.0)
                        }
                    })
                    .collect();
                grid_from(rows, cols, z)
            },
        )
    }

    /// Whether the valid samples span an area (at least three not on one line).
    fn spans_area(grid: &Grid) -> bool {
        let pts: Vec<(i64, i64)> = (0..grid.z.len())
            .filter(|&i| !grid.z[i].is_nan())
            .map(|i| ((i % grid.cols) as i64, (i / grid.cols) as i64))
            .collect();
        pts.iter().any(|a| {
            pts.iter().any(|b| {
                pts.iter()
                    .any(|c| (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0) != 0)
            })
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        #[test]
        fn reported_error_matches_brute_force(grid in arb_grid(), budget in 3usize..100, bound in prop::option::of(0.0f64..60.0)) {
            let opts = SimplifyOptions { max_vertices: Some(budget), max_error: bound };
            match simplify(&grid, &opts, None) {
                Ok((tin, report)) => {
                    prop_assert!(spans_area(&grid));
                    check_result(&grid, &opts, &tin, &report);
                }
                Err(TinError::TooFewPoints(_)) => prop_assert!(!spans_area(&grid)),
                Err(TinError::InvalidParameter(m)) => {
                    prop_assert!(m.contains("convex hull"), "{}", m);
                    prop_assert!(budget < 2 * grid.rows + 2 * grid.cols);
                }
                Err(e) => prop_assert!(false, "unexpected error {}", e),
            }
        }

        #[test]
        fn heap_holds_a_correct_entry_for_every_face(grid in arb_grid()) {
            prop_assume!(spans_area(&grid));
            let mut s = Simplifier::new(&grid).expect("simplifier");
            let hull = valid_hull(&grid).expect("hull");
            s.start(&hull).expect("start");
            s.check_invariants();
            while let Some(c) = s.top() {
                s.heap.pop();
                s.insert_step(c).expect("insert");
                s.check_invariants();
            }
            prop_assert!(s.faces.iter().all(|f| f.worst.is_none()));
        }
    }
}
