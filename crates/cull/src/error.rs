//! Errors of loading and saving a hierarchy.

use std::path::PathBuf;

/// What can go wrong reading or writing a `.tch` hierarchy file.
#[derive(Debug, thiserror::Error)]
pub enum HierarchyError {
    /// The file could not be read or written (the I/O error is the source).
    #[error("{path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The file does not start with the `.tch` magic number.
    #[error("not a tincull hierarchy file (wrong magic number; expected a .tch file written by `tincull build`)")]
    BadMagic,
    /// The file was written by a format version this build cannot read.
    #[error("unsupported hierarchy format version {found} (this build reads version {supported})")]
    UnsupportedVersion {
        /// Version in the file.
        found: u32,
        /// Version this build reads.
        supported: u32,
    },
    /// The file ends before its declared length.
    #[error("truncated hierarchy file: {expected} bytes of data declared, {found} present")]
    Truncated {
        /// Bytes declared in the header.
        expected: u64,
        /// Bytes present.
        found: u64,
    },
    /// The checksum does not match: the file is corrupted.
    #[error("corrupted hierarchy file: checksum {found:08x} does not match the stored {stored:08x}")]
    Checksum {
        /// Checksum in the header.
        stored: u32,
        /// Checksum of the data.
        found: u32,
    },
    /// The data could not be decoded.
    #[error("cannot decode hierarchy data: {0}")]
    Decode(String),
    /// The content is structurally invalid (indices out of range, ranges not nested, ...).
    #[error("invalid hierarchy: {0}")]
    Invalid(String),
}
