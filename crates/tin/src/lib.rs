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
pub mod sniff;
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
pub use validate::{
    Cracks, MeshStats, PrecisionReport, ValidationReport, find_cracks, find_overlaps, mesh_stats, validate,
    validate_parts,
};

/// A number as messages print it: as Rust writes it (`2.5`, `1000`, `inf`) from 10^-4 to 10^9 in magnitude, and in
/// scientific notation outside (`1e308`, `1.5e-9`), so that a huge or tiny value given by a user takes a few
/// characters instead of hundreds of digits.
pub fn compact_number(x: f64) -> String {
    let a = x.abs();
    if a.is_finite() && a != 0.0 && !(1e-4..1e9).contains(&a) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

#[cfg(test)]
mod compact_number_tests {
    use super::compact_number;

    #[test]
    fn huge_and_tiny_numbers_are_short() {
        assert_eq!(compact_number(1e308), "1e308");
        assert_eq!(compact_number(-2.5e-9), "-2.5e-9");
        assert_eq!(compact_number(1234.5), "1234.5");
        assert_eq!(compact_number(0.0), "0");
        assert_eq!(compact_number(f64::INFINITY), "inf");
    }
}
