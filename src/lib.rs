//! tincull: precomputed self-occlusion culling for irregular triangulated terrains.
//!
//! This crate is the command-line tool and a facade over the library crates, one per stage. Data flows one way,
//! from the top of this table to the bottom; no crate depends on one below it.
//!
//! | stage | crate |
//! | --- | --- |
//! | terrain: the [`tin::Tin`] mesh, Delaunay construction, OBJ and DEM import, simplification | [`tin`] |
//! | per-vertex sector horizons (the covering-set sweep and its oracle) | [`horizon`] |
//! | occlusion regions of vertices, triangles and groups | [`occlusion`] |
//! | crystal grouping and the merge hierarchy | [`crystal`] |
//! | the exported hierarchy (`.tch`) and the run-time culler, embeddable | [`cull`] |
//! | ground-truth visibility, viewpoint sets, metrics | [`truth`] |
//! | the whole build from a TIN to a hierarchy, grouped OBJ/MTL and JSON exports, the group palette | [`pipeline`] (also [`export`]) |
//! | evaluation against ground truth, sweeps, the stability suite, failure maps | [`eval`] ([`evaluate`], [`sweep`], [`stress`]) |
//! | from-region visibility: the PVS of viewcells (Koltun et al. 2001, adapted) and its binary form | [`pvs`] |
//! | tiled builds: the plan, one tile's job, the merge of the tiles' hierarchies | [`tiles`] |
//! | wgpu renders and the interactive viewer (feature `viewer`, on by default) | `viewer` |
//! | the command line | [`cli`] |
//!
//! The method follows P. M. Edmondson, *Hierarchical Occlusion Culling for Arbitrarily-Meshed Height Fields* (2004).

#![warn(missing_docs)]

pub use crystal;
pub use cull;
pub use eval;
pub use horizon;
pub use occlusion;
pub use pipeline;
pub use pvs;
pub use tiles;
pub use tin;
pub use truth;
#[cfg(feature = "viewer")]
pub use viewer;

pub use eval::{evaluate, failmap, stress, sweep};
pub use pipeline::export;

pub mod cli;
