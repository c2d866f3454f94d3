//! Errors of loading and saving a hierarchy.

use std::path::PathBuf;

/// What can go wrong reading or writing a `.tch` hierarchy file.
#[derive(Debug)]
#[non_exhaustive]
pub enum HierarchyError {
    /// The file could not be read or written (the I/O error is the source).
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The file does not start with the `.tch` magic number.
    BadMagic,
    /// The file was written by a format version this build cannot read.
    UnsupportedVersion {
        /// Version in the file.
        found: u32,
        /// The newest version this build reads (it reads every version from 1).
        supported: u32,
    },
    /// The file ends before the end of its header, or of the data whose length the header declares (truncated, or
    /// the length field corrupt).
    Truncated {
        /// Bytes the whole file needs: [`crate::file::HEADER_LEN`] when it is shorter than its header, else the
        /// header's and the data length it declares.
        expected: u64,
        /// Bytes of the whole file.
        found: u64,
    },
    /// The checksum does not match: the file is corrupted.
    Checksum {
        /// Checksum in the header.
        stored: u32,
        /// Checksum of the data.
        found: u32,
    },
    /// The data could not be decoded.
    Decode(String),
    /// The content is structurally invalid (indices out of range, ranges not nested, ...).
    Invalid(String),
    /// A valid hierarchy that the asked culling method does not apply to (a region method of the other grouping:
    /// [`crate::CullMethod::check`]).
    MethodMismatch(String),
    /// What is wrong with the file at `path` ([`crate::Hierarchy::load`] names the file of every error but
    /// [`HierarchyError::Io`], which names it itself).
    InFile {
        /// The file.
        path: PathBuf,
        /// What is wrong with its content.
        error: Box<HierarchyError>,
    },
}

impl HierarchyError {
    /// The error itself, without the file that [`HierarchyError::InFile`] names.
    pub fn kind(&self) -> &HierarchyError {
        match self {
            HierarchyError::InFile { error, .. } => error.kind(),
            e => e,
        }
    }
}

impl std::fmt::Display for HierarchyError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            HierarchyError::Io { path, .. } => write!(f, "{}", path.display()),
            HierarchyError::BadMagic => f.write_str(
                "not a tincull hierarchy file (wrong magic number; expected a .tch file written by `tincull build`)",
            ),
            HierarchyError::UnsupportedVersion { found, supported } => write!(
                f,
                "unsupported hierarchy format version {found} (this build reads versions 1 to {supported})"
            ),
            HierarchyError::Truncated { expected, found } => {
                f.write_str(&crate::file::truncation(" hierarchy file", *expected, *found))
            }
            HierarchyError::Checksum { stored, found } => write!(
                f,
                "corrupted hierarchy file: checksum {found:08x} does not match the stored {stored:08x}"
            ),
            HierarchyError::Decode(e) => write!(f, "cannot decode hierarchy data: {e}"),
            HierarchyError::Invalid(e) => write!(f, "invalid hierarchy: {e}"),
            HierarchyError::MethodMismatch(e) => f.write_str(e),
            HierarchyError::InFile { path, error } => write!(f, "{}: {error}", path.display()),
        }
    }
}

impl std::error::Error for HierarchyError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            HierarchyError::Io { source, .. } => Some(source),
            HierarchyError::InFile { error, .. } => error.source(),
            _ => None,
        }
    }
}
