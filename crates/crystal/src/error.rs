//! Errors of crystal grouping.

/// Everything that can go wrong in [`crate::build`] and [`crate::Crystal::check_invariants`].
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CrystalError {
    /// A parameter is out of range.
    #[error("crystal parameter `{field}`: {reason}")]
    InvalidParams {
        /// The parameter's name (as in TOML).
        field: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// A region table does not have one row per element of the mesh.
    #[error("the {table} region table has {found} rows, but the mesh has {expected} {table}s")]
    TableSize {
        /// `"vertex"`.
        table: &'static str,
        /// Rows the mesh needs.
        expected: usize,
        /// Rows the table has.
        found: usize,
    },
    /// A grouping broke one of its invariants (see [`crate::Crystal::check_invariants`]).
    #[error("crystal invariant violated: {0}")]
    Invariant(String),
}
