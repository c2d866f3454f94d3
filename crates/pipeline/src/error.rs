//! Why a build fails: [`BuildError`], the error of [`crate::build`], [`crate::build_from_regions`] and
//! [`crate::BuildParams::validate`]. Each stage's own error is kept as it is (match on it, or print it: the messages
//! name the parameter or the vertex at fault).

/// Everything that can go wrong in a build.
#[derive(Debug, thiserror::Error)]
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
