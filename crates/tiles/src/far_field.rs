//! The far field: what a tile's horizons see of the terrain beyond its halo.
//!
//! The grid is cut into blocks of `b × b` samples; each block contributes one point, its lowest valid sample
//! (ties: the first in row-major order) at that sample's position, lowered by the tiles' error bound `E`. Every
//! tile's TIN reproduces every sample within `E` (its simplification stops at `E`; its sides are simplified to `E`,
//! [`crate::boundary`]), so the merged terrain at that position is at least `z_min − E`: each far-field point lies on
//! or below the terrain. A horizon computed over points on or below the terrain is on or below the horizon the
//! terrain itself casts (a lower point subtends a smaller elevation angle from every eye), so regions built from
//! it claim no more occlusion than the terrain gives. The halo's samples are lowered by `E` for the same reason
//! ([`crate::job`]).

use serde::{Deserialize, Serialize};
use tin::Grid;

/// One far-field point: a sample position and its lowered height.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FarPoint {
    /// Sample row.
    pub row: u32,
    /// Sample column.
    pub col: u32,
    /// The sample's height lowered by the error bound (m).
    pub z: f64,
}

/// The far field of `grid` with blocks of `block` samples (see the module docs), lowered by `max_error`. Blocks
/// with no valid sample contribute nothing.
pub fn far_field(grid: &Grid, block: usize, max_error: f64) -> Vec<FarPoint> {
    let block = block.max(1);
    let mut out = Vec::new();
    for r0 in (0..grid.rows).step_by(block) {
        for c0 in (0..grid.cols).step_by(block) {
            let mut low: Option<(f64, usize, usize)> = None;
            for r in r0..(r0 + block).min(grid.rows) {
                for c in c0..(c0 + block).min(grid.cols) {
                    let z = grid.z[r * grid.cols + c];
                    if !z.is_nan() && low.is_none_or(|(lz, _, _)| z < lz) {
                        low = Some((z, r, c));
                    }
                }
            }
            if let Some((z, r, c)) = low {
                out.push(FarPoint {
                    row: r as u32,
                    col: c as u32,
                    z: z - max_error,
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    #[test]
    fn one_lowest_sample_per_block_lowered() {
        let z: Vec<f64> = (0..16)
            .map(|i| f64::from(i) * if i % 5 == 0 { -1.0 } else { 1.0 })
            .collect();
        let g = Grid::new(4, 4, 1.0, 1.0, DVec2::ZERO, z).expect("grid");
        let f = far_field(&g, 2, 0.5);
        assert_eq!(f.len(), 4);
        // Block (0,0) holds samples 0, 1, 4, 5: the lowest is 5 (height -5).
        assert_eq!(
            f[0],
            FarPoint {
                row: 1,
                col: 1,
                z: -5.5
            }
        );
        for p in &f {
            let (r0, c0) = (p.row as usize / 2 * 2, p.col as usize / 2 * 2);
            for r in r0..r0 + 2 {
                for c in c0..c0 + 2 {
                    assert!(p.z + 0.5 <= g.z[r * 4 + c]);
                }
            }
        }
    }
}
