//! Errors of the ground-truth crate.

/// What can go wrong when computing metrics or parsing names.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TruthError {
    /// A per-triangle array does not have one entry per triangle of the TIN.
    #[error("{what} has {got} entries, but the TIN has {expected} triangles")]
    LengthMismatch {
        /// Which input (for example "drawn" or "visible").
        what: &'static str,
        /// Number of triangles of the TIN.
        expected: usize,
        /// Length of the array given.
        got: usize,
    },
    /// A viewpoint class name that is not one of the six.
    #[error("unknown viewpoint class {0:?}: expected one of ground, low, high, valley, ridge, sky")]
    UnknownClass(String),
}

/// Result alias of this crate.
pub type Result<T, E = TruthError> = std::result::Result<T, E>;
