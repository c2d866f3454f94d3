//! Run-time side of tincull: sector geometry, the exported hierarchy and its `.tch` file format, and the recursive
//! culler (the thesis' region test over crystal hierarchies, the same test as Stewart's 1997 baseline over quadtree
//! hierarchies, and the safe culler; see [`method`]).
//!
//! Light on dependencies (serde, postcard, crc32fast) so that a renderer can embed it: load a file with
//! [`Hierarchy::load`], make a [`Culler`], and call [`Culler::cull_into`] once per frame.
#![warn(missing_docs)]

pub mod culler;
pub mod error;
pub mod file;
pub mod hierarchy;
pub mod horizon;
pub mod method;
pub mod safe;
pub mod sector;

pub use culler::{Camera, CullStats, Culler, DrawList};
pub use error::HierarchyError;
pub use file::{FORMAT_VERSION, MAGIC, OLDEST_READABLE_VERSION, write_atomically};
pub use hierarchy::{BuildInfo, Grouping, Hierarchy, Mesh, Node, StoredRegion};
pub use method::{AnyCuller, CullMethod};
pub use safe::{SafeCuller, SafeParams};
pub use sector::{azimuth, for_each_sector_in, sector_direction, sector_of_azimuth};
