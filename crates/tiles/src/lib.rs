//! Tiled builds: terrains larger than one machine's memory, cut into tiles that build independently (on one machine
//! or many) and merge into one hierarchy (thesis §7.1, "out-of-core").
//!
//! - [`plan`]: `tincull tiles plan DEM --tile N` reads a DEM grid in strips of rows, cuts it into tiles that share
//!   their sides and computes the far field once, writing each tile's cut of it beside the plan ([`far_field`]);
//!   `tincull tiles plan MESH --tile M` cuts a mesh's triangles into squares of `M` metres and writes each tile's
//!   part ([`part`]).
//! - [`job`]: `tincull tiles build plan.json --tile I` builds one tile: its TIN (sides simplified identically by
//!   both neighbours, [`boundary`]), its vertices' horizons over the tile, a full-resolution halo and the far field
//!   (all on or below the terrain), and its partial hierarchy, written as a `.tch`.
//! - [`merge`](mod@merge): `tincull tiles merge plan.json -o terrain.tch` joins the tiles' meshes and hierarchies;
//!   every tile is a node near the top.
//!
//! A plan made with [`PlanOptions::no_regions`] (`tiles plan --no-regions --grouping quadtree`) builds tiles as
//! `build --no-regions` does: no horizons, halo or far field, only the quadtree's cells, for the run-time cullers.
//!
//! **Safety.** The default culler (`safe`) decides at run time from the mesh alone, so the merged hierarchy culls
//! as safely as any other: its proof needs only that every node's range holds the triangles its bounds cover, which
//! [`cull::Hierarchy::check_invariants`] and the merge's circles (they only grow) give. The stored regions (the
//! thesis' test, not conservative in any case) come from horizons over points on or below the terrain, whose
//! vertices are never higher than the terrain there; they may still differ from an untiled build's either way (see
//! [`crate::far_field`]).
#![warn(missing_docs)]

pub mod boundary;
pub mod far_field;
mod framed;
pub mod job;
pub mod merge;
pub mod part;
pub mod plan;

use std::path::PathBuf;

pub use job::{TileReport, build_tile};
pub use merge::merge;
pub use plan::{LeftOut, MeshExtent, Plan, PlanOptions, TileSpec, make_mesh_plan, make_plan};

/// Errors of tiled builds.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TilesError {
    /// A parameter or a plan's content is wrong.
    #[error("{0}")]
    Parameter(String),
    /// A plan file cannot be read.
    #[error("cannot read {}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A plan file is malformed.
    #[error("{}: not a tincull tile plan: {reason}", path.display())]
    Plan {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A file a plan wrote for its jobs (a mesh tile's part, a DEM tile's far field) is damaged or foreign.
    #[error("{}: not a valid {what} file: {reason}", path.display())]
    TileFile {
        /// The file.
        path: PathBuf,
        /// What kind of file it should be ("part", "far field").
        what: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// Reading or simplifying the terrain failed.
    #[error(transparent)]
    Tin(#[from] tin::TinError),
    /// The horizon sweep failed.
    #[error(transparent)]
    Horizon(#[from] horizon::HorizonError),
}
