//! The error type of the horizon crate.

use thiserror::Error;

/// Why horizons could not be computed.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum HorizonError {
    /// `sectors` is below the minimum of 4 (a sector wider than 90° has no well-defined projection).
    #[error("sectors = {sectors}: at least 4 sectors are needed")]
    TooFewSectors {
        /// The rejected number of sectors.
        sectors: u32,
    },
    /// `subsectors` is zero.
    #[error("subsectors = 0: at least 1 subsector per sector is needed")]
    NoSubsectors,
    /// `sectors · subsectors` exceeds [`crate::MAX_TOTAL_SUBSECTORS`].
    #[error("sectors × subsectors = {sectors} × {subsectors} exceeds the limit of {limit} subsectors")]
    TooManySubsectors {
        /// Requested sectors.
        sectors: u32,
        /// Requested subsectors per sector.
        subsectors: u32,
        /// The limit on their product.
        limit: u32,
    },
    /// The undersampling radius is not a positive finite number.
    #[error("undersampling radius {radius} must be a positive finite number of metres")]
    InvalidRadius {
        /// The rejected radius.
        radius: f64,
    },
    /// A vertex coordinate is outside the range the exact predicates support.
    #[error("vertex {vertex} has {axis} = {value:e}: coordinates must be 0 or between 2^-100 and 2^100 in magnitude")]
    CoordinateOutOfRange {
        /// 1-based number of the offending vertex (as in an OBJ file).
        vertex: usize,
        /// `"x"`, `"y"` or `"z"`.
        axis: &'static str,
        /// The offending value.
        value: f64,
    },
    /// The mesh has more vertices than horizon indices can address.
    #[error("{vertices} vertices: at most {limit} are supported")]
    TooManyVertices {
        /// Number of vertices of the mesh.
        vertices: usize,
        /// The limit.
        limit: usize,
    },
}
