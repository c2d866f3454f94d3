//! Wavefront OBJ import and export of TINs.
//!
//! The thesis' data sets (Edmondson 2004, section 6.1) are TINs; OBJ is the common exchange format for them. Only the
//! geometry statements matter here: `v x y z` (optionally `w`, or `r g b` colours, which are ignored) and
//! `f`/`fo` faces with `v`, `v/vt`, `v//vn` or `v/vt/vn` references (positive or negative, i.e. relative, indices).
//! Every other standard OBJ statement (`vt`, `vn`, `l`, `p`, `o`, `g`, `s`, `usemtl`, `mtllib`, free-form geometry,
//! …) is counted and ignored; an unknown statement is an error, which is how foreign files are caught. `#` starts
//! a comment anywhere on a line; a UTF-8 byte-order mark is skipped. Line continuation with a trailing `\` is not
//! supported.
//!
//! The reader is a small line parser of its own rather than `tobj`: `tobj` reports errors without line numbers,
//! reindexes vertices per object (dropping unreferenced ones, so a vertex-only point cloud yields nothing) and
//! parses f32 unless a feature is enabled. The tests use `tobj` (with f64) as an independent oracle.
//!
//! Import has two modes ([`ObjImportOptions::keep_faces`]):
//! - Default: the file's vertices are Delaunay-triangulated ([`crate::triangulate`]); its faces are checked for
//!   syntax and index range, counted, and otherwise ignored.
//! - `keep_faces`: the file's faces become the TIN. Vertices with the same x,y are first welded (equal heights are
//!   merged; different heights are an error, or resolved by [`DedupePolicy::KeepHighest`], which keeps the highest
//!   and may leave vertical faces degenerate, which is then an error). Polygons are triangulated in x,y by ear
//!   clipping. **Vertices that no face uses are dropped** and counted in [`ObjImportReport::unreferenced_dropped`]
//!   (exporters often leave stray vertices behind; they are not part of the surface). The result must be a height
//!   field: non-degenerate, consistently oriented (all clockwise is flipped), manifold, and without two triangles
//!   overlapping in x,y (checked exactly, see [`crate::validate::find_overlaps`]), and without a crack: a vertex on
//!   another face's edge at another height than the edge's ([`crate::validate::find_cracks`]; a T-junction at the
//!   edge's height is accepted).
//!
//! Every error names the file and the line (see [`ObjLineError`]); errors about two faces or vertices name both
//! lines. Vertex numbers in messages are the file's own 1-based numbers.
//!
//! Export writes `v` lines with Rust's shortest round-trip formatting of f64 (`{}`), so positions survive export and
//! import bit for bit, and `f` lines with the TIN's triangles in order ([`write_obj_to`], to any writer; tincull puts
//! it in a file with its one output writer, the `outfile` crate).

use std::io::{self, Write};
use std::path::{Path, PathBuf};

use glam::{DVec2, DVec3};
use serde::Serialize;

use crate::delaunay::{DedupePolicy, triangulate};
use crate::error::{Result, TinError};
use crate::mesh::Tin;
use crate::predicates::orient2d;
use crate::validate::{find_cracks, find_overlaps};

/// Largest polygon (number of vertices in one face) the importer triangulates.
pub const MAX_POLYGON_VERTICES: usize = 1024;

/// How to turn an OBJ file into a TIN.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ObjImportOptions {
    /// Use the file's own faces (checked to form a height field) instead of Delaunay-triangulating its vertices.
    pub keep_faces: bool,
    /// What to do with vertices that share x,y but differ in z.
    pub dedupe: DedupePolicy,
    /// Which of the file's axes points up (see [`UpAxis`]).
    pub up: UpAxis,
}

/// The axis that points up in an OBJ file. tincull's terrains are z-up (x east, y north, z height); many 3-D tools
/// write OBJ with y up instead (x east, y up, z towards the viewer, i.e. south), which import turns into z-up by the
/// rotation `(x, y, z) → (x, −z, y)` (a proper rotation, so faces keep their orientation). Everything after import,
/// error messages about positions included, is in the z-up frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum UpAxis {
    /// z is height (tincull's own frame; the default).
    #[default]
    Z,
    /// y is height: rotated to z-up on import.
    Y,
}

impl UpAxis {
    /// The z-up position of a point written as `p` in a file whose up axis is `self`.
    pub fn to_z_up(self, p: DVec3) -> DVec3 {
        match self {
            UpAxis::Z => p,
            UpAxis::Y => DVec3::new(p.x, -p.z, p.y),
        }
    }
}

/// What an OBJ import read and what it did to the data.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ObjImportReport {
    /// `v` statements in the file.
    pub vertices_read: usize,
    /// `f` statements in the file.
    pub faces_read: usize,
    /// Faces with more than three vertices.
    pub polygons_read: usize,
    /// Other statements that were recognised and ignored (`vt`, `vn`, `g`, `usemtl`, …).
    pub ignored_statements: usize,
    /// Vertices dropped because an earlier vertex had the same x, y and z.
    pub merged_duplicates: usize,
    /// Vertices dropped under [`DedupePolicy::KeepHighest`] because a vertex at the same x,y was higher.
    pub dropped_lower: usize,
    /// With `keep_faces`: vertices dropped because no face uses them.
    pub unreferenced_dropped: usize,
    /// Whether the TIN uses the file's faces.
    pub kept_faces: bool,
    /// Vertices of the resulting TIN.
    pub vertices: usize,
    /// Triangles of the resulting TIN.
    pub triangles: usize,
    /// Whether the text does not end with a line break: every OBJ writer ends its last line with one, and a file cut
    /// short (a copy or download that stopped) need not show it otherwise: a number cut after its point still
    /// reads (`10.`), as does a last face that lost none of its vertices.
    pub unterminated: bool,
}

/// What is wrong with one line of an OBJ file (see [`TinError::ObjLine`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ObjLineError {
    /// The line is not UTF-8 text.
    #[error("the line is not UTF-8 text (a binary or foreign file?)")]
    NotUtf8,
    /// A statement keyword that OBJ does not define.
    #[error("unknown statement {keyword:?} (not an OBJ file?)")]
    UnknownStatement {
        /// The first word of the line (shortened).
        keyword: String,
    },
    /// A coordinate is not a number.
    #[error("{token:?} is not a number (truncated or garbled line?)")]
    BadNumber {
        /// The offending word (shortened).
        token: String,
    },
    /// A `v` line with the wrong number of values.
    #[error("a vertex needs x y z (optionally w, or r g b), found {found} values (truncated line?)")]
    VertexArity {
        /// Values found after `v`.
        found: usize,
    },
    /// The optional fourth vertex value `w` is zero or not finite.
    #[error("vertex weight w = {w} must be finite and non-zero")]
    BadWeight {
        /// The value read.
        w: f64,
    },
    /// A vertex coordinate is finite but outside the range every stage accepts ([`crate::COORDINATE_LIMIT`]).
    #[error("vertex {vertex} has {axis} = {value:e}: coordinates must be 0 or between 2^-100 and 2^100 in magnitude")]
    OutOfRange {
        /// 1-based vertex number.
        vertex: usize,
        /// `"x"`, `"y"` or `"z"`.
        axis: &'static str,
        /// The value read.
        value: f64,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate ({x}, {y}, {z})")]
    NonFinite {
        /// 1-based vertex number.
        vertex: usize,
        /// x as read.
        x: f64,
        /// y as read.
        y: f64,
        /// z as read.
        z: f64,
    },
    /// A face with fewer than three vertices.
    #[error("a face needs at least 3 vertices, found {found} (truncated line?)")]
    FaceArity {
        /// Vertex references found after `f`.
        found: usize,
    },
    /// A face has more vertices than [`MAX_POLYGON_VERTICES`].
    #[error("the face has {vertices} vertices, more than the {MAX_POLYGON_VERTICES} supported")]
    PolygonTooLarge {
        /// Vertex references on the line.
        vertices: usize,
    },
    /// A face vertex reference that is not of the form `v`, `v/vt`, `v//vn` or `v/vt/vn` with non-zero integers.
    #[error("{token:?} is not a vertex reference (v, v/vt, v//vn or v/vt/vn with non-zero integers)")]
    BadReference {
        /// The offending word (shortened).
        token: String,
    },
    /// A face refers to a vertex that does not exist.
    #[error("vertex reference {index} is out of range: there are {vertices} vertices")]
    IndexOutOfRange {
        /// The index as written (negative: relative to the vertices before the line).
        index: i64,
        /// Vertices available to it.
        vertices: usize,
    },
    /// Two vertices share x,y but not z.
    #[error(
        "vertex {vertex} and vertex {other_vertex} (line {other_line}) share x,y = ({x}, {y}) but have heights {z} and \
         {other_z}: a vertical wall, not a height field (the dedupe policy keep-highest, `--dedupe keep-highest`, \
         keeps the higher one)"
    )]
    DuplicateXy {
        /// 1-based number of the vertex on this line.
        vertex: usize,
        /// 1-based number of the earlier vertex.
        other_vertex: usize,
        /// Line of the earlier vertex.
        other_line: usize,
        /// Shared x.
        x: f64,
        /// Shared y.
        y: f64,
        /// Height of the vertex on this line.
        z: f64,
        /// Height of the earlier vertex.
        other_z: f64,
    },
    /// A face with zero area in x,y (vertical or collapsed) or a repeated vertex.
    #[error("the face is degenerate: zero area in x,y (vertical?) or a repeated vertex")]
    DegenerateFace,
    /// A polygon that ear clipping cannot triangulate in x,y.
    #[error("the polygon cannot be triangulated in x,y (self-intersecting or collinear)")]
    BadPolygon,
    /// The face winds the other way round in x,y than the first face.
    #[error("the face winds the other way in x,y than the face on line {first_line}: inconsistent orientation")]
    InconsistentOrientation {
        /// Line of the first face.
        first_line: usize,
    },
    /// An edge used twice in the same direction or by more than two faces.
    #[error(
        "the edge from vertex {a} to vertex {b} is also used by the face on line {other_line} (in the same direction, \
         or by a third face): not manifold"
    )]
    NonManifoldEdge {
        /// 1-based number of the edge's first vertex.
        a: usize,
        /// 1-based number of the edge's second vertex.
        b: usize,
        /// Line of the other face.
        other_line: usize,
    },
    /// Two faces overlap in x,y.
    #[error("the face overlaps the face on line {other_line} in x,y: not a height field")]
    Overlap {
        /// Line of the other face.
        other_line: usize,
    },
    /// A vertex lies on an edge of the face, not at one of its corners, at another height than the edge there.
    #[error(
        "vertex {vertex} lies on an edge of the face, not at one of its corners, at another height than the edge there \
         (a crack in the surface): not a height field"
    )]
    Crack {
        /// 1-based number of the vertex.
        vertex: usize,
    },
    /// The Delaunay triangulator refused the vertex.
    #[error("the triangulator rejected this vertex: {reason}")]
    Rejected {
        /// The triangulator's reason.
        reason: String,
    },
}

/// Statements that are valid OBJ but carry nothing a TIN needs.
const IGNORED: &[&str] = &[
    "vt",
    "vn",
    "vp",
    "l",
    "p",
    "o",
    "g",
    "s",
    "mg",
    "usemtl",
    "mtllib",
    "usemap",
    "maplib",
    "cstype",
    "deg",
    "bmat",
    "step",
    "curv",
    "curv2",
    "surf",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "bevel",
    "c_interp",
    "d_interp",
    "lod",
    "shadow_obj",
    "trace_obj",
    "ctech",
    "stech",
    "call",
    "csh",
];

/// The geometry of an OBJ file, with the line of every element.
#[derive(Debug, Default)]
struct Parsed {
    positions: Vec<DVec3>,
    vertex_lines: Vec<usize>,
    /// Face `i` is `face_refs[face_starts[i]..face_starts[i + 1]]`, 0-based, possibly out of range.
    face_starts: Vec<usize>,
    face_refs: Vec<i64>,
    face_lines: Vec<usize>,
    /// For each face reference, the index as written (for error messages).
    written: Vec<i64>,
    polygons: usize,
    ignored: usize,
}

impl Parsed {
    fn face(&self, f: usize) -> &[i64] {
        &self.face_refs[self.face_starts[f]..self.face_starts[f + 1]]
    }
}

fn shorten(s: &str) -> String {
    const MAX: usize = 40;
    match s.char_indices().nth(MAX) {
        Some((i, _)) => format!("{}…", &s[..i]),
        None => s.to_owned(),
    }
}

fn parse_lines(text: &[u8], path: &Path) -> Result<Parsed> {
    let line_err = |line: usize, kind: ObjLineError| TinError::ObjLine {
        path: path.to_path_buf(),
        line,
        kind,
    };
    let mut p = Parsed {
        face_starts: vec![0],
        ..Parsed::default()
    };
    for (i, raw) in text.split(|&b| b == b'\n').enumerate() {
        let line = i + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let raw = if i == 0 {
            raw.strip_prefix("\u{feff}".as_bytes()).unwrap_or(raw)
        } else {
            raw
        };
        let s = std::str::from_utf8(raw).map_err(|_| line_err(line, ObjLineError::NotUtf8))?;
        let s = s.find('#').map_or(s, |c| &s[..c]);
        let mut words = s.split_whitespace();
        let Some(keyword) = words.next() else { continue };
        match keyword {
            "v" => {
                let mut values = [0.0f64; 6];
                let mut found = 0;
                for w in words {
                    let v: f64 = w
                        .parse()
                        .map_err(|_| line_err(line, ObjLineError::BadNumber { token: shorten(w) }))?;
                    if found < values.len() {
                        values[found] = v;
                    }
                    found += 1;
                }
                let [mut x, mut y, mut z, w, ..] = values;
                match found {
                    3 | 6 => {}
                    4 => {
                        if !w.is_finite() || w == 0.0 {
                            return Err(line_err(line, ObjLineError::BadWeight { w }));
                        }
                        x /= w;
                        y /= w;
                        z /= w;
                    }
                    _ => return Err(line_err(line, ObjLineError::VertexArity { found })),
                }
                let vertex = p.positions.len() + 1;
                if !(x.is_finite() && y.is_finite() && z.is_finite()) {
                    return Err(line_err(line, ObjLineError::NonFinite { vertex, x, y, z }));
                }
                for (axis, value) in [("x", x), ("y", y), ("z", z)] {
                    if !crate::predicates::coordinate_in_range(value) {
                        return Err(line_err(line, ObjLineError::OutOfRange { vertex, axis, value }));
                    }
                }
                if p.positions.len() >= u32::MAX as usize {
                    return Err(TinError::format(
                        path,
                        format!("line {line}: more than {} vertices", u32::MAX),
                    ));
                }
                p.positions.push(DVec3::new(x, y, z));
                p.vertex_lines.push(line);
            }
            "f" | "fo" => {
                let start = p.face_refs.len();
                for w in words {
                    let bad = || line_err(line, ObjLineError::BadReference { token: shorten(w) });
                    let mut parts = w.split('/');
                    let index: i64 = parts.next().and_then(|v| v.parse().ok()).ok_or_else(bad)?;
                    let mut others = 0;
                    for part in parts {
                        others += 1;
                        if others > 2 || !(part.is_empty() || part.parse::<i64>().is_ok_and(|i| i != 0)) {
                            return Err(bad());
                        }
                    }
                    if index == 0 {
                        return Err(bad());
                    }
                    let resolved = if index > 0 {
                        index - 1
                    } else {
                        let r = p.positions.len() as i64 + index;
                        if r < 0 {
                            return Err(line_err(
                                line,
                                ObjLineError::IndexOutOfRange {
                                    index,
                                    vertices: p.positions.len(),
                                },
                            ));
                        }
                        r
                    };
                    p.face_refs.push(resolved);
                    p.written.push(index);
                }
                let found = p.face_refs.len() - start;
                if found < 3 {
                    return Err(line_err(line, ObjLineError::FaceArity { found }));
                }
                if found > MAX_POLYGON_VERTICES {
                    return Err(line_err(line, ObjLineError::PolygonTooLarge { vertices: found }));
                }
                if found > 3 {
                    p.polygons += 1;
                }
                p.face_starts.push(p.face_refs.len());
                p.face_lines.push(line);
            }
            k if IGNORED.contains(&k) => p.ignored += 1,
            k => {
                return Err(line_err(line, ObjLineError::UnknownStatement { keyword: shorten(k) }));
            }
        }
    }
    if p.positions.is_empty() {
        return Err(TinError::format(
            path,
            "no vertices ('v' lines): the file is empty or not an OBJ file",
        ));
    }
    // Forward references are resolved against the whole file.
    let n = p.positions.len() as i64;
    for f in 0..p.face_lines.len() {
        for k in p.face_starts[f]..p.face_starts[f + 1] {
            if p.face_refs[k] >= n {
                return Err(line_err(
                    p.face_lines[f],
                    ObjLineError::IndexOutOfRange {
                        index: p.written[k],
                        vertices: p.positions.len(),
                    },
                ));
            }
        }
    }
    Ok(p)
}

/// Reads an OBJ file into a TIN (see the module documentation for the two modes and every check).
pub fn read_obj(path: impl AsRef<Path>, opts: &ObjImportOptions) -> Result<(Tin, ObjImportReport)> {
    let path = path.as_ref();
    let bytes = infile::read(path).map_err(|e| TinError::io(path, e))?;
    import(&bytes, path, opts)
}

/// Parses OBJ text already in memory; `name` stands for the file name in error messages.
pub fn parse_obj(text: &[u8], name: &str, opts: &ObjImportOptions) -> Result<(Tin, ObjImportReport)> {
    import(text, &PathBuf::from(name), opts)
}

fn import(text: &[u8], path: &Path, opts: &ObjImportOptions) -> Result<(Tin, ObjImportReport)> {
    if let Some(what) = crate::sniff::sniff(&text[..text.len().min(crate::sniff::HEAD)]).and_then(|f| f.as_mesh_hint())
    {
        return Err(TinError::format(
            path,
            format!("not an OBJ mesh: it starts like {what}"),
        ));
    }
    let mut parsed = parse_lines(text, path)?;
    if opts.up != UpAxis::Z {
        for p in &mut parsed.positions {
            *p = opts.up.to_z_up(*p);
        }
    }
    let mut report = ObjImportReport {
        vertices_read: parsed.positions.len(),
        faces_read: parsed.face_lines.len(),
        polygons_read: parsed.polygons,
        ignored_statements: parsed.ignored,
        kept_faces: opts.keep_faces,
        unterminated: text.last().is_some_and(|&b| b != b'\n'),
        ..ObjImportReport::default()
    };
    let tin = if opts.keep_faces {
        from_faces(&parsed, path, opts.dedupe, &mut report)?
    } else {
        from_vertices(&parsed, path, opts.dedupe, &mut report)?
    };
    report.vertices = tin.num_vertices();
    report.triangles = tin.num_triangles();
    Ok((tin, report))
}

fn line_error(path: &Path, line: usize, kind: ObjLineError) -> TinError {
    TinError::ObjLine {
        path: path.to_path_buf(),
        line,
        kind,
    }
}

fn from_vertices(p: &Parsed, path: &Path, dedupe: DedupePolicy, report: &mut ObjImportReport) -> Result<Tin> {
    match triangulate(&p.positions, dedupe) {
        Ok((tin, r)) => {
            report.merged_duplicates = r.merged_duplicates;
            report.dropped_lower = r.dropped_lower;
            Ok(tin)
        }
        Err(TinError::DuplicateXy {
            first,
            second,
            x,
            y,
            z_first,
            z_second,
        }) => Err(line_error(
            path,
            p.vertex_lines[second],
            ObjLineError::DuplicateXy {
                vertex: second + 1,
                other_vertex: first + 1,
                other_line: p.vertex_lines[first],
                x,
                y,
                z: z_second,
                other_z: z_first,
            },
        )),
        Err(TinError::Insertion { index, reason }) => Err(line_error(
            path,
            p.vertex_lines[index],
            ObjLineError::Rejected { reason },
        )),
        Err(TinError::TooFewPoints(m)) => Err(TinError::format(path, format!("cannot triangulate: {m}"))),
        Err(e) => Err(e),
    }
}

/// Welds vertices with equal x,y: returns, for each vertex, the vertex that stands for it.
fn weld(p: &Parsed, path: &Path, dedupe: DedupePolicy, report: &mut ObjImportReport) -> Result<Vec<u32>> {
    let pos = &p.positions;
    let key = |i: usize| ((pos[i].x + 0.0).to_bits(), (pos[i].y + 0.0).to_bits()); // + 0.0 folds -0.0
    let mut order: Vec<usize> = (0..pos.len()).collect();
    order.sort_unstable_by_key(|&i| (key(i), i));
    let mut rep: Vec<u32> = (0..pos.len() as u32).collect();
    for group in order.chunk_by(|&a, &b| key(a) == key(b)) {
        if group.len() < 2 {
            continue;
        }
        let first = group[0];
        if let Some(&second) = group.iter().find(|&&j| pos[j].z != pos[first].z)
            && dedupe == DedupePolicy::Reject
        {
            return Err(line_error(
                path,
                p.vertex_lines[second],
                ObjLineError::DuplicateXy {
                    vertex: second + 1,
                    other_vertex: first + 1,
                    other_line: p.vertex_lines[first],
                    x: pos[first].x,
                    y: pos[first].y,
                    z: pos[second].z,
                    other_z: pos[first].z,
                },
            ));
        }
        // Highest wins; among equals, the first in the file.
        let best = group
            .iter()
            .copied()
            .fold(first, |b, j| if pos[j].z > pos[b].z { j } else { b });
        for &j in group {
            if j != best {
                if pos[j].z == pos[best].z {
                    report.merged_duplicates += 1;
                } else {
                    report.dropped_lower += 1;
                }
                rep[j] = best as u32;
            }
        }
    }
    Ok(rep)
}

/// Triangulates a simple polygon (vertex indices into `positions`) in x,y by ear clipping, keeping its winding: the
/// first ear in ring order is clipped, again and again. `None` when the polygon has zero area or no ear can be found
/// (self-intersecting or collinear).
///
/// Each convex ring vertex keeps the number of other ring vertices in its closed corner triangle (an ear has none).
/// Clipping a vertex changes only its two neighbours' triangles, which are counted again; every other vertex's
/// count drops by one when the clipped vertex lay in its triangle. So a face of `k` vertices takes `O(k²)`
/// orientation tests (a search for an ear from the start of the ring took `O(k³)`: 1.7 s for 1,024 vertices).
fn ear_clip(polygon: &[u32], positions: &[DVec3]) -> Option<Vec<[u32; 3]>> {
    let at = |v: u32| positions[v as usize].truncate();
    let k = polygon.len();
    let twice_area: f64 = (0..k).map(|i| at(polygon[i]).perp_dot(at(polygon[(i + 1) % k]))).sum();
    if twice_area == 0.0 || !twice_area.is_finite() {
        return None;
    }
    let sign = twice_area.signum();
    let convex = |a: DVec2, b: DVec2, c: DVec2| orient2d(a, b, c) * sign > 0.0;
    let inside_closed = |[a, b, c]: [DVec2; 3], q: DVec2| {
        orient2d(a, b, q) * sign >= 0.0 && orient2d(b, c, q) * sign >= 0.0 && orient2d(c, a, q) * sign >= 0.0
    };
    let corner = |ring: &[u32], i: usize| {
        let n = ring.len();
        [ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]]
    };
    // The other ring vertices in the closed corner triangle of vertex `i`; `None` for a reflex one (never an ear).
    let blockers = |ring: &[u32], i: usize| {
        let ids = corner(ring, i);
        let t = ids.map(at);
        convex(t[0], t[1], t[2]).then(|| {
            ring.iter()
                .filter(|&&v| !ids.contains(&v) && inside_closed(t, at(v)))
                .count()
        })
    };
    let mut ring = polygon.to_vec();
    let mut blocked: Vec<Option<usize>> = (0..k).map(|i| blockers(&ring, i)).collect();
    let mut out = Vec::with_capacity(k - 2);
    while ring.len() > 3 {
        let ear = blocked.iter().position(|&b| b == Some(0))?;
        let tri = corner(&ring, ear);
        out.push(tri);
        ring.remove(ear);
        blocked.remove(ear);
        let n = ring.len();
        let neighbours = [(ear + n - 1) % n, ear % n];
        let gone = at(tri[1]);
        for (i, count) in blocked.iter_mut().enumerate() {
            match count {
                Some(c) if !neighbours.contains(&i) && inside_closed(corner(&ring, i).map(at), gone) => *c -= 1,
                _ => {}
            }
        }
        for i in neighbours {
            blocked[i] = blockers(&ring, i);
        }
    }
    if !convex(at(ring[0]), at(ring[1]), at(ring[2])) {
        return None;
    }
    out.push([ring[0], ring[1], ring[2]]);
    Some(out)
}

fn from_faces(p: &Parsed, path: &Path, dedupe: DedupePolicy, report: &mut ObjImportReport) -> Result<Tin> {
    if p.face_lines.is_empty() {
        return Err(TinError::format(
            path,
            "the faces were to be kept, but the file has no faces ('f' lines)",
        ));
    }
    let rep = weld(p, path, dedupe, report)?;
    // Faces in terms of representative vertices, triangulated; the line of each triangle.
    let mut triangles: Vec<[u32; 3]> = Vec::with_capacity(p.face_refs.len());
    let mut tri_lines: Vec<usize> = Vec::with_capacity(p.face_refs.len());
    let mut face = Vec::new();
    for f in 0..p.face_lines.len() {
        let line = p.face_lines[f];
        face.clear();
        face.extend(p.face(f).iter().map(|&v| rep[v as usize]));
        let mut sorted = face.clone();
        sorted.sort_unstable();
        if sorted.windows(2).any(|w| w[0] == w[1]) {
            return Err(line_error(path, line, ObjLineError::DegenerateFace));
        }
        if face.len() == 3 {
            triangles.push([face[0], face[1], face[2]]);
            tri_lines.push(line);
        } else {
            let tris = ear_clip(&face, &p.positions).ok_or_else(|| line_error(path, line, ObjLineError::BadPolygon))?;
            tri_lines.extend(std::iter::repeat_n(line, tris.len()));
            triangles.extend(tris);
        }
    }
    // Keep the referenced representatives, in file order.
    let mut new_index = vec![u32::MAX; p.positions.len()];
    for t in &triangles {
        for &v in t {
            new_index[v as usize] = 0;
        }
    }
    let mut original: Vec<u32> = Vec::new();
    for (v, slot) in new_index.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = original.len() as u32;
            original.push(v as u32);
        }
    }
    report.unreferenced_dropped = (0..p.positions.len())
        .filter(|&v| rep[v] == v as u32 && new_index[v] == u32::MAX)
        .count();
    for t in &mut triangles {
        *t = t.map(|v| new_index[v as usize]);
    }
    let positions: Vec<DVec3> = original.iter().map(|&v| p.positions[v as usize]).collect();
    let number = |v: u32| original[v as usize] as usize + 1;
    let tin = Tin::from_parts(positions, triangles).map_err(|e| match e {
        TinError::DegenerateTriangle { triangle, .. } => {
            line_error(path, tri_lines[triangle], ObjLineError::DegenerateFace)
        }
        TinError::InconsistentOrientation { triangle } => line_error(
            path,
            tri_lines[triangle],
            ObjLineError::InconsistentOrientation {
                first_line: tri_lines[0],
            },
        ),
        TinError::NonManifoldEdge { a, b, first, second } => line_error(
            path,
            tri_lines[second],
            ObjLineError::NonManifoldEdge {
                a: number(a),
                b: number(b),
                other_line: tri_lines[first],
            },
        ),
        e => e,
    })?;
    let overlaps = find_overlaps(tin.positions(), tin.triangles(), 1);
    if let Some(&[first, second]) = overlaps.first.first() {
        return Err(line_error(
            path,
            tri_lines[second as usize],
            ObjLineError::Overlap {
                other_line: tri_lines[first as usize],
            },
        ));
    }
    if let Some(&[vertex, triangle]) = find_cracks(tin.positions(), tin.triangles(), 1).first.first() {
        return Err(line_error(
            path,
            tri_lines[triangle as usize],
            ObjLineError::Crack { vertex: number(vertex) },
        ));
    }
    Ok(tin)
}

/// Writes `tin` as OBJ text: a comment, one `v x y z` line per vertex (shortest round-trip decimal form of each
/// f64) and one `f a b c` line per triangle (1-based, counter-clockwise seen from above).
pub fn write_obj_to<W: Write + ?Sized>(tin: &Tin, out: &mut W) -> io::Result<()> {
    let mut w = io::BufWriter::new(out);
    writeln!(
        w,
        "# TIN: {} vertices, {} triangles; x east, y north, z up (m)",
        tin.num_vertices(),
        tin.num_triangles()
    )?;
    for p in tin.positions() {
        writeln!(w, "v {} {} {}", p.x, p.y, p.z)?;
    }
    for t in tin.triangles() {
        writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
    }
    w.flush()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Ear clipping as written first (an independent oracle): the first ear in ring order, each sought by testing
    /// every vertex against every other from the start of the ring.
    fn ear_clip_by_search(polygon: &[u32], positions: &[DVec3]) -> Option<Vec<[u32; 3]>> {
        let at = |v: u32| positions[v as usize].truncate();
        let k = polygon.len();
        let twice_area: f64 = (0..k).map(|i| at(polygon[i]).perp_dot(at(polygon[(i + 1) % k]))).sum();
        if twice_area == 0.0 || !twice_area.is_finite() {
            return None;
        }
        let sign = twice_area.signum();
        let convex = |a: DVec2, b: DVec2, c: DVec2| orient2d(a, b, c) * sign > 0.0;
        let inside = |a: DVec2, b: DVec2, c: DVec2, q: DVec2| {
            orient2d(a, b, q) * sign >= 0.0 && orient2d(b, c, q) * sign >= 0.0 && orient2d(c, a, q) * sign >= 0.0
        };
        let mut ring = polygon.to_vec();
        let mut out = Vec::new();
        while ring.len() > 3 {
            let n = ring.len();
            let ear = (0..n).find(|&i| {
                let (a, b, c) = (ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]);
                convex(at(a), at(b), at(c))
                    && !ring
                        .iter()
                        .any(|&v| v != a && v != b && v != c && inside(at(a), at(b), at(c), at(v)))
            })?;
            out.push([ring[(ear + n - 1) % n], ring[ear], ring[(ear + 1) % n]]);
            ring.remove(ear);
        }
        convex(at(ring[0]), at(ring[1]), at(ring[2])).then(|| {
            out.push([ring[0], ring[1], ring[2]]);
            out
        })
    }

    /// A polygon of `radii.len()` vertices around the origin at increasing angles (star-shaped, so simple unless
    /// vertices coincide), on a coarse grid when `snap` (collinear and repeated points), either winding.
    fn star(radii: &[f64], turns: &[f64], snap: bool, clockwise: bool) -> Vec<DVec3> {
        let mut at = 0.0;
        let total: f64 = turns.iter().sum();
        let mut p: Vec<DVec3> = radii
            .iter()
            .zip(turns)
            .map(|(&r, &t)| {
                at += t / total * std::f64::consts::TAU;
                let (x, y) = (r * at.cos(), r * at.sin());
                if snap {
                    DVec3::new(x.round(), y.round(), 0.0)
                } else {
                    DVec3::new(x, y, 0.0)
                }
            })
            .collect();
        if clockwise {
            p.reverse();
        }
        p
    }

    proptest! {
        /// The ears clipped are those of the search from the start of the ring, one by one, for simple polygons
        /// with many reflex corners, collinear and repeated points, in either winding and from any first vertex.
        #[test]
        fn ear_clipping_clips_the_first_ear_in_ring_order(
            radii in prop::collection::vec(0.5f64..8.0, 3..60),
            turns in prop::collection::vec(0.1f64..1.0, 60),
            snap in any::<bool>(),
            clockwise in any::<bool>(),
            start in 0usize..60,
        ) {
            let positions = star(&radii, &turns[..radii.len()], snap, clockwise);
            let n = positions.len();
            let polygon: Vec<u32> = (0..n).map(|i| ((i + start) % n) as u32).collect();
            prop_assert_eq!(ear_clip(&polygon, &positions), ear_clip_by_search(&polygon, &positions));
        }
    }

    /// The thin annular band of the audit, whose ears lie far from the start of the ring (1.7 s for its 1,024
    /// vertices with the search): every vertex is clipped, with the search's result.
    #[test]
    fn a_thin_band_is_clipped_as_by_the_search() {
        let m = 128;
        let (r, d) = (1000.0f64, std::f64::consts::FRAC_PI_2 / (m as f64 - 1.0));
        let t = r * (1.0 - d.cos()) * 0.5;
        let arc = |radius: f64| {
            (0..m).map(move |j| DVec3::new(radius * (j as f64 * d).cos(), radius * (j as f64 * d).sin(), 0.0))
        };
        let positions: Vec<DVec3> = arc(r).chain(arc(r - t).collect::<Vec<_>>().into_iter().rev()).collect();
        let polygon: Vec<u32> = (0..positions.len() as u32).collect();
        let tris = ear_clip(&polygon, &positions).expect("a simple polygon");
        assert_eq!(tris.len(), polygon.len() - 2);
        assert_eq!(Some(tris), ear_clip_by_search(&polygon, &positions));
    }
}
