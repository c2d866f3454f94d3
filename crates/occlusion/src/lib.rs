//! Occlusion regions for tincull (thesis 4.6; the `region` module).
//!
//! A [`Region`] is the set of camera positions, in one sector's vertical plane, from which a vertex, a triangle or a
//! group of triangles is hidden by the terrain. Regions of triangles and groups are intersections of their vertices'
//! regions; a [`RegionTable`] holds them for many elements and all sectors.
#![warn(missing_docs)]

pub mod conservative;
pub mod region;
pub mod table;

pub use conservative::{NodeShape, Polyline, conservative_regions};
pub use horizon::SectorHorizon;
pub use region::{Region, intersect_all};
pub use table::{RegionTable, plane_t};
