//! Errors of TIN construction, import and validation.

use std::path::PathBuf;

/// Everything that can go wrong while building, importing or checking a TIN.
///
/// Every variant names the offending element (input index, triangle, file line) so that a user can find it.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TinError {
    /// A coordinate is NaN or infinite.
    #[error("vertex {index} has a non-finite coordinate ({x}, {y}, {z})")]
    NonFinite {
        /// Input index of the vertex.
        index: usize,
        /// x coordinate as read.
        x: f64,
        /// y coordinate as read.
        y: f64,
        /// z coordinate as read.
        z: f64,
    },
    /// Two input vertices share x and y but not z (a vertical wall or overhang).
    #[error(
        "vertices {first} and {second} share x,y = ({x}, {y}) but have different heights ({z_first} vs {z_second}): \
         not a height field (the dedupe policy keep-highest, `--dedupe keep-highest`, keeps the higher one)"
    )]
    DuplicateXy {
        /// Input index of the vertex kept first.
        first: usize,
        /// Input index of the later vertex at the same x,y.
        second: usize,
        /// Shared x.
        x: f64,
        /// Shared y.
        y: f64,
        /// Height of `first`.
        z_first: f64,
        /// Height of `second`.
        z_second: f64,
    },
    /// Fewer than three distinct, non-collinear points.
    #[error("cannot triangulate: {0}")]
    TooFewPoints(String),
    /// The Delaunay triangulator refused a point (for example an absurdly large coordinate).
    #[error("vertex {index} was rejected by the triangulator: {reason}")]
    Insertion {
        /// Input index of the vertex.
        index: usize,
        /// The triangulator's reason.
        reason: String,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {vertex}, but there are only {vertices} vertices")]
    IndexOutOfRange {
        /// Triangle index.
        triangle: usize,
        /// The bad vertex index.
        vertex: u64,
        /// Number of vertices.
        vertices: usize,
    },
    /// A triangle has zero area in xy (or repeats a vertex).
    #[error("triangle {triangle} ({a}, {b}, {c}) is degenerate: zero area in x,y")]
    DegenerateTriangle {
        /// Triangle index.
        triangle: usize,
        /// First vertex.
        a: u32,
        /// Second vertex.
        b: u32,
        /// Third vertex.
        c: u32,
    },
    /// Triangles are not consistently oriented (some CCW, some CW in xy).
    #[error(
        "triangle {triangle} is oriented clockwise in x,y while triangle 0 is counter-clockwise: inconsistent orientation"
    )]
    InconsistentOrientation {
        /// Triangle index.
        triangle: usize,
    },
    /// An edge is shared by more than two triangles, or twice in the same direction.
    #[error(
        "edge ({a}, {b}) is not manifold: it is used by triangles {first} and {second} in the same direction or by more than two triangles"
    )]
    NonManifoldEdge {
        /// Edge start.
        a: u32,
        /// Edge end.
        b: u32,
        /// One triangle using the edge.
        first: usize,
        /// Another triangle using the edge.
        second: usize,
    },
    /// Two triangles overlap in xy, so the mesh is not a height field.
    #[error("triangles {first} and {second} overlap in x,y: not a height field")]
    Overlap {
        /// One triangle.
        first: usize,
        /// The other.
        second: usize,
    },
    /// A file could not be read or written (the I/O error is the source).
    #[error("{path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A file is malformed; the message says where (line, byte offset or field).
    #[error("{path}: {message}")]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong and where.
        message: String,
    },
    /// A parameter is out of range, or missing where the input needs it (the message names it, and the file where the
    /// file decides it).
    #[error("{0}")]
    InvalidParameter(String),
    /// A line of an OBJ file is malformed, or the mesh it describes is not a height field there.
    #[error("{path}:{line}: {kind}")]
    ObjLine {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong with that line.
        kind: crate::obj::ObjLineError,
    },
}

impl TinError {
    /// Builds a [`TinError::Format`] for `path`.
    pub fn format(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        TinError::Format {
            path: path.into(),
            message: message.into(),
        }
    }

    /// Builds a [`TinError::Io`] for `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        TinError::Io {
            path: path.into(),
            source,
        }
    }
}

/// Result alias of this crate.
pub type Result<T, E = TinError> = std::result::Result<T, E>;
