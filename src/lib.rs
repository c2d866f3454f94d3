//! tincull: precomputed self-occlusion culling for irregular triangulated terrains.
//!
//! This crate is the command-line tool and a facade over the pipeline's crates, one per stage:
//!
//! | stage | crate |
//! | --- | --- |
//! | terrain: the [`tin::Tin`] mesh, Delaunay construction, OBJ and DEM import, simplification | [`tin`] |
//! | per-vertex sector horizons (the covering-set sweep and its oracle) | [`horizon`] |
//!
//! The method follows P. M. Edmondson, *Hierarchical Occlusion Culling for Arbitrarily-Meshed Height Fields* (2004).

pub use crystal;
pub use cull;
pub use horizon;
pub use occlusion;
pub use tin;
pub use truth;

pub mod cli;
pub mod evaluate;
pub mod export;
pub mod pipeline;
pub mod stress;
pub mod sweep;
