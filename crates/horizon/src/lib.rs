//! Per-vertex sector horizons of a TIN (Edmondson 2004, thesis section 4.5; Stewart 1997).
//!
//! For every vertex `p` and every subsector `j` of a [`SectorConfig`], the horizon is the vertex `q` in the
//! subsector's closed wedge at `p` whose projection onto the subsector's centre direction has the greatest slope
//! from `p` (ties: nearer, then smaller index). [`compute`] finds all of them with the a/b-ordered covering-set sweep
//! in O(n log² n) per subsector; [`brute_force`] is the O(n²) oracle it must match exactly. The result, a
//! [`HorizonField`], also holds per-sector summaries (minimum slope, farthest horizon distance) for the occlusion
//! regions, and, with [`HorizonOptions::undersampling_radius`], the thesis' undersampling fix.
//!
//! Modules: [`sector`] (geometry), [`predicates`] (exact comparisons), [`hull`] (covering sets), [`sweep`],
//! [`oracle`], [`undersampling`] (their documentation states the exact definitions and choices).

#![warn(missing_docs)]

pub mod candidate;
mod error;
mod field;
pub mod hull;
pub mod oracle;
pub mod predicates;
pub mod sector;
pub mod sweep;
pub mod undersampling;

pub use error::HorizonError;
pub use field::{
    EdgeHorizon, HorizonField, HorizonOptions, HorizonPoint, Progress, SectorHorizon, brute_force,
    check_undersampling_radius, compute, projection_origin,
};
pub use sector::{MAX_TOTAL_SUBSECTORS, SectorConfig, SectorGeometry, Wedge};

/// Sentinel for "no horizon" in compact per-subsector storage.
pub const NO_HORIZON: u32 = u32::MAX;
