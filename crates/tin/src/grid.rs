//! [`Grid`]: a regular elevation grid (a DEM), the input of simplification.

use glam::{DVec2, DVec3};

use crate::error::{Result, TinError};

/// A regular elevation grid. Row 0 is the northern edge, column 0 the western edge.
///
/// Sample `(row, col)` lies at `x = origin.x + col * dx`, `y = origin.y - row * dy`. Void (nodata) samples are stored
/// as NaN and never become vertices; see [`Grid::sample`].
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Number of rows (north to south).
    pub rows: usize,
    /// Number of columns (west to east).
    pub cols: usize,
    /// Sample spacing east-west (m).
    pub dx: f64,
    /// Sample spacing north-south (m).
    pub dy: f64,
    /// World x,y of sample (0, 0), the north-west corner.
    pub origin: DVec2,
    /// Heights in row-major order, NaN for voids.
    pub z: Vec<f64>,
}

impl Grid {
    /// Builds a grid, checking that the sizes agree and the spacing is positive and finite.
    /// Infinite heights are rejected; NaN marks a void.
    pub fn new(rows: usize, cols: usize, dx: f64, dy: f64, origin: DVec2, z: Vec<f64>) -> Result<Grid> {
        if rows < 2 || cols < 2 {
            return Err(TinError::InvalidParameter(format!(
                "a grid needs at least 2 x 2 samples, got {rows} x {cols}"
            )));
        }
        if z.len() != rows * cols {
            return Err(TinError::InvalidParameter(format!(
                "grid of {rows} x {cols} needs {} heights, got {}",
                rows * cols,
                z.len()
            )));
        }
        if !(dx.is_finite() && dy.is_finite() && dx > 0.0 && dy > 0.0) {
            return Err(TinError::InvalidParameter(format!(
                "grid spacing must be positive and finite, got {dx}, {dy}"
            )));
        }
        if !origin.is_finite() {
            return Err(TinError::InvalidParameter(format!(
                "grid origin must be finite, got {origin}"
            )));
        }
        if let Some(i) = z.iter().position(|h| h.is_infinite()) {
            return Err(TinError::InvalidParameter(format!(
                "row {}, column {} (1-based, row 1 north): the height is infinite",
                i / cols + 1,
                i % cols + 1
            )));
        }
        Ok(Grid {
            rows,
            cols,
            dx,
            dy,
            origin,
            z,
        })
    }

    /// The world position of sample `(row, col)`, or `None` for a void.
    pub fn sample(&self, row: usize, col: usize) -> Option<DVec3> {
        let z = self.z[row * self.cols + col];
        (!z.is_nan()).then(|| {
            DVec3::new(
                self.origin.x + col as f64 * self.dx,
                self.origin.y - row as f64 * self.dy,
                z,
            )
        })
    }

    /// Number of void samples.
    pub fn voids(&self) -> usize {
        self.z.iter().filter(|z| z.is_nan()).count()
    }

    /// Every non-void sample as a point, in row-major order.
    pub fn points(&self) -> Vec<DVec3> {
        (0..self.rows)
            .flat_map(|r| (0..self.cols).map(move |c| (r, c)))
            .filter_map(|(r, c)| self.sample(r, c))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_and_voids() {
        let g = Grid::new(
            2,
            3,
            10.0,
            20.0,
            DVec2::new(100.0, 200.0),
            vec![1.0, 2.0, f64::NAN, 4.0, 5.0, 6.0],
        )
        .expect("valid grid");
        assert_eq!(g.sample(1, 2), Some(DVec3::new(120.0, 180.0, 6.0)));
        assert_eq!(g.sample(0, 2), None);
        assert_eq!(g.voids(), 1);
        assert_eq!(g.points().len(), 5);
        assert!(Grid::new(2, 2, 0.0, 1.0, DVec2::ZERO, vec![0.0; 4]).is_err());
        assert!(Grid::new(2, 2, 1.0, 1.0, DVec2::ZERO, vec![0.0; 3]).is_err());
    }
}
