//! Why a build fails: [`BuildError`], the error of [`crate::build`], [`crate::build_from_regions`] and
//! [`crate::BuildParams::validate`]. Each stage's own error is kept as it is (match on it, or print it: the messages
//! name the parameter or the vertex at fault).

/// Everything that can go wrong in a build.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BuildError {
    /// The sector configuration or the undersampling radius is invalid, or the horizon sweep refused the terrain (a
    /// coordinate out of the range of its exact predicates).
    #[error(transparent)]
    Horizon(#[from] horizon::HorizonError),
    /// A crystal parameter is out of range, or crystal grouping failed.
    #[error(transparent)]
    Crystal(#[from] crystal::CrystalError),
    /// A quadtree parameter is out of range, or the quadtree failed.
    #[error(transparent)]
    Quadtree(#[from] quadtree::QuadtreeError),
    /// A build without regions ([`crate::build_without_regions`]) asked for crystal groups, which grow from them.
    #[error("crystal groups grow from the occlusion regions: a build without regions needs the quadtree grouping")]
    RegionsNeeded,
    /// Vertex regions computed elsewhere ([`crate::build_from_regions`]) do not fit the terrain or the parameters.
    #[error(
        "{rows} vertex region rows of {sectors} sectors do not match a terrain of {vertices} vertices built with \
         {expected_sectors} sectors"
    )]
    RegionsMismatch {
        /// Rows of the region table.
        rows: usize,
        /// Sectors of the region table.
        sectors: u32,
        /// Vertices of the terrain.
        vertices: usize,
        /// Sectors of the build parameters.
        expected_sectors: u32,
    },
}

/// Why an export to the hierarchy's other forms (grouped OBJ, JSON, glTF) or a read back from them failed: the error
/// of the functions of [`crate::export`] and [`crate::gltf`]. Messages name the path or the element at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExportError {
    /// The hierarchy has no vertex or no triangle (glTF has nothing to hold).
    #[error("the hierarchy has no triangles to export")]
    NoTriangles,
    /// A `.glb` holds at most 4 GiB (its length is a `u32`).
    #[error("the mesh is too large for a .glb (over 4 GiB)")]
    TooLargeForGlb,
    /// An output path that the export cannot use (it would overwrite its own companion file, or has no file name).
    #[error("{}: {reason}", path.display())]
    Path {
        /// The path given.
        path: std::path::PathBuf,
        /// Why it cannot be used.
        reason: &'static str,
    },
    /// JSON that could not be encoded or decoded (`context` says what and where; the decoder's message says why).
    #[error("{context}: {cause}")]
    Json {
        /// What was encoded or decoded: a sentence, or the element's path in the document (`nodes[3].extras.tincull`).
        context: String,
        /// The encoder's or decoder's error.
        cause: serde_json::Error,
    },
    /// A glTF document that is not one [`crate::gltf::to_gltf`] writes: the message names the element.
    #[error("{0}")]
    Malformed(String),
    /// What was read back is not a valid hierarchy ([`cull::Hierarchy::check_invariants`]).
    #[error(transparent)]
    Invalid(#[from] cull::HierarchyError),
}

impl ExportError {
    /// [`ExportError::Json`] with `context` (for `map_err`).
    pub(crate) fn json(context: impl Into<String>) -> impl FnOnce(serde_json::Error) -> ExportError {
        let context = context.into();
        move |cause| ExportError::Json { context, cause }
    }
}
