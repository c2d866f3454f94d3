//! Run-time side of tincull: sector geometry, the exported hierarchy format and the culler.
//!
//! Light on dependencies so that a renderer can embed it.
#![warn(missing_docs)]

pub mod sector;

pub use sector::{azimuth, for_each_sector_in, sector_direction, sector_of_azimuth};
