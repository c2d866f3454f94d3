//! Run-time side of tincull: sector geometry, the exported hierarchy and its `.tch` file format, and the cullers
//! (the thesis' region test, named `stewart` over Stewart's 1997 quadtree hierarchies; see [`method`]).
//!
//! Light on dependencies (serde, postcard, crc32fast, and `infile`, the project's opener of input files, which has
//! none) so that a renderer can embed it: load a file with [`Hierarchy::load`], make an [`AnyCuller`] (or a
//! [`SafeCuller`] directly), and call `cull_into` once per frame with a reused [`DrawList`].
//!
//! | culler | module | verdict "hidden" |
//! | --- | --- | --- |
//! | [`SafeCuller`] (the default) | [`safe`], over the conservative horizon of [`horizon`] | a theorem: every point of the culled triangles is below the terrain's horizon seen from the camera (proof in the modules' docs) |
//! | [`LloydEgbertCuller`] (`lloyd-egbert`) | [`lloyd_egbert`], cell-edge occluders over the same horizon | the same theorem, with occluders on or below the terrain's exact profile along the cell edges and the node's bounding box as occludee |
//! | [`Culler`] (`thesis`) | [`culler`] | the thesis' test of the camera against the precomputed sector regions; not conservative unless the regions are (see `occlusion::conservative`) |
//!
//! Eyes below the ground: every verdict is about sight lines from an eye on or above the terrain. From under the
//! surface a camera sees none of it, yet the cullers do not look for that case (this crate holds no point location in
//! the TIN, to stay light) and return a draw list all the same; the `tincull` commands refuse such eyes with
//! `truth::ground_heights`. A renderer keeps its camera above the ground, as it must to draw anything.
//!
//! The terrain must be a height field: one surface over the plane, triangles that do not overlap in x,y and meet
//! without cracks. The safe cullers' theorem is about sight lines passing below such a surface (an edge of a mesh that
//! folds over itself need not block what lies behind it). Every `.tch` that `tincull build` or `tiles merge` writes
//! holds one (`build` triangulates the terrain itself and checks a mesh's own triangles under `--keep-faces`; a merge
//! joins tiles that cover the grid side by side, which its tests check with `tin::validate`); [`Hierarchy::load`]
//! checks a file's structure ([`Hierarchy::check_invariants`]), not this, which takes a spatial index: for a file from
//! elsewhere, `tincull info FILE.tch` reports it (its `height field` line), as `tin::validate` does in code.
//!
//! In a renderer (the `pipeline` crate's documentation has a whole build and cull that runs):
//!
//! ```no_run
//! use cull::{AnyCuller, Camera, CullMethod, DrawList, Hierarchy};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let h = Hierarchy::load("terrain.tch")?; // written by `tincull build`
//! let culler = AnyCuller::new(&h, CullMethod::default()); // the safe culler
//! let mut list = DrawList::default(); // reused: no allocation once it has grown
//! # let frames: Vec<([f64; 3], f64)> = Vec::new();
//! for (eye, yaw_deg) in frames {
//!     // World coordinates as in the mesh; a level view with a 90° horizontal field (360 looks all around; a
//!     // pitched view covers more azimuths at its corners: see `Camera::hfov`).
//!     culler.cull_into(&Camera::from_degrees(eye, yaw_deg, 90.0)?, &mut list);
//!     for &[start, end] in &list.ranges {
//!         // draw triangles start..end of h.mesh.triangles (one index-buffer range each)
//!         # let _ = (start, end);
//!     }
//! }
//! # Ok(())
//! # }
//! ```
#![warn(missing_docs)]

pub mod culler;
pub mod error;
pub mod file;
pub mod hierarchy;
pub mod horizon;
pub mod limit;
pub mod lloyd_egbert;
pub mod method;
pub mod safe;
pub mod sector;

pub use culler::{Camera, CameraError, CullStats, Culler, DrawList};
pub use error::HierarchyError;
pub use file::{FORMAT_VERSION, MAGIC, OLDEST_READABLE_VERSION};
pub use hierarchy::{BuildInfo, Grouping, Hierarchy, Mesh, Node, StoredRegion};
pub use lloyd_egbert::LloydEgbertCuller;
pub use method::{AnyCuller, CullMethod};
pub use safe::{DEFAULT_WORK_BUDGET, MAX_COLUMNS_PER_FACE, MAX_PATCH, SafeCuller, SafeParams, SafeParamsError};
pub use sector::{azimuth, for_each_sector_in, sector_direction, sector_of_azimuth};
