//! Triangulated irregular networks for tincull.
//!
//! [`Tin`] is the mesh every later stage works on: f64 positions, counter-clockwise triangles, edge adjacency and a
//! local origin for f32 conversion. It is built by Delaunay triangulation ([`triangulate`]) of points that come
//! from OBJ files or DEM grids, or from the simplification of a grid.
//!
//! Features: `png` (8/16-bit grayscale height maps) and `geotiff` (GeoTIFF rasters) are on by default; without them
//! [`read_dem`] reads `.npy`, `.asc` and `.hgt` only and names the feature a `.png` or `.tif` needs.

#![warn(missing_docs)]

pub mod delaunay;
pub mod dem;
pub mod error;
pub mod grid;
pub mod mesh;
pub mod obj;
pub mod predicates;
pub mod prefetch;
pub mod simplify;
pub mod synth;
pub mod validate;

pub use delaunay::{DedupePolicy, DelaunayReport, triangulate};
pub use dem::{
    DemOptions, GridShape, read_dem, read_dem_header, read_dem_strips, read_dem_window, read_dem_window_heights,
};
pub use error::{Result, TinError};
pub use grid::Grid;
pub use mesh::{Aabb, Circle, NO_NEIGHBOUR, Tin, VertexTriangles, bounding_circle_of_points};
pub use obj::{ObjImportOptions, ObjImportReport, ObjLineError, UpAxis, parse_obj, read_obj, write_obj_to};
pub use predicates::{COORDINATE_LIMIT, coordinate_in_range, orient2d, orientation};
pub use prefetch::prefetch;
pub use simplify::{SimplifyOptions, SimplifyReport, StopReason, simplify, simplify_constrained};
pub use synth::{SynthOptions, synth_grid, synth_tin};
pub use validate::{MeshStats, PrecisionReport, ValidationReport, find_overlaps, mesh_stats, validate, validate_parts};
