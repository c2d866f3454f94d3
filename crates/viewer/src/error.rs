//! Errors of the viewer: no adapter, bad options, I/O, and the errors of the crates it reads.

use std::path::PathBuf;

/// What can go wrong rendering, writing images or running the viewer.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ViewerError {
    /// No GPU adapter (not even a software one such as Mesa's llvmpipe) could be found.
    #[error(
        "no GPU adapter found ({0}); on Debian/Ubuntu install Mesa's software Vulkan driver: `apt-get install mesa-vulkan-drivers libvulkan1`"
    )]
    NoAdapter(String),
    /// The adapter refused to create a device.
    #[error("cannot create a GPU device: {0}")]
    Device(String),
    /// The GPU reported an error (validation, out of memory, lost device, failed map).
    #[error("GPU error: {0}")]
    Gpu(String),
    /// An option is out of range or does not fit the input; the message names the option.
    #[error("{0}")]
    Invalid(String),
    /// A file could not be read or written.
    #[error("{path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A PNG could not be encoded or decoded.
    #[error("{path}: {message}")]
    Png {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// An output could not be written (the message names the file).
    #[error(transparent)]
    Output(#[from] outfile::Error),
    /// The hierarchy could not be read, written or checked.
    #[error(transparent)]
    Hierarchy(#[from] cull::HierarchyError),
    /// The terrain mesh was rejected.
    #[error(transparent)]
    Tin(#[from] tin::TinError),
    /// The window could not be opened or the event loop failed.
    #[error("viewer window: {0}")]
    Window(String),
}

/// Result with a [`ViewerError`].
pub type Result<T, E = ViewerError> = std::result::Result<T, E>;
