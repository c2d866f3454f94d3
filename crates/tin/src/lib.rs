//! Triangulated irregular networks for tincull.
//!
//! [`Tin`] is the mesh every later stage works on: f64 positions, counter-clockwise triangles, edge adjacency and a
//! local origin for f32 conversion. It is built by Delaunay triangulation ([`triangulate`]) of points that come
//! from OBJ files or DEM grids, or from the simplification of a grid.

pub mod delaunay;
pub mod error;
pub mod grid;
pub mod mesh;
pub mod simplify;
pub mod synth;

pub use delaunay::{DedupePolicy, DelaunayReport, triangulate};
pub use error::{Result, TinError};
pub use grid::Grid;
pub use mesh::{Aabb, Circle, NO_NEIGHBOUR, Tin, VertexTriangles, bounding_circle_of_points, orient2d};
pub use simplify::{SimplifyOptions, SimplifyReport, StopReason, simplify};
pub use synth::{SynthOptions, synth_grid, synth_tin};
