//! Evaluation of tincull's culling methods against ground truth (the README's "Accuracy: how it is measured"), as a
//! library.
//!
//! | module | what it does |
//! | --- | --- |
//! | [`evaluate`] | viewpoint sets and their ground truth, every method scored against it, reports (CSV, tables) |
//! | [`sweep`] | builds over sectors × subsectors × seeds scored against one shared ground truth (resumable CSV) |
//! | [`stress`] | the stability suite: the pipeline over degenerate terrains, parameters and viewpoints |
//! | [`failmap`] | false culls and occlusion captured over a grid of viewpoints covering the footprint |
//!
//! Data flows one way: this crate uses the stages (`tin` … `cull`), the ground truth (`truth`) and the build
//! (`pipeline`); the viewer and the command line use it, never the other way round.
#![warn(missing_docs)]

pub mod evaluate;
pub mod failmap;
pub mod stress;
pub mod sweep;
