//! Checking a PVS against the exact from-point checker (`truth`): sample points of the cell (corners, edges,
//! interior, both ends of the height band), the union of what the exact checker sees from them, and the union of
//! what the safe from-point culler draws from them.

use cull::{Camera, DrawList, SafeCuller};
use glam::{DVec2, DVec3};
use truth::GroundTruth;

use crate::{Height, ViewCell};

/// The sample points of `cell`: a 5 × 5 lattice over its rectangle (corners, edge points and interior) and `extra`
/// seeded random interior points, each at both ends of the height band (above ground: over the ground at that x,y;
/// points outside the footprint are skipped). With `extra = 7` that is 64 points inside the footprint.
pub fn sample_eyes(truth: &GroundTruth, cell: &ViewCell, extra: usize, seed: u64) -> Vec<DVec3> {
    let [x0, y0, x1, y1] = cell.rect;
    let mut xy = Vec::new();
    for j in 0..5 {
        for i in 0..5 {
            let (fx, fy) = (f64::from(i) / 4.0, f64::from(j) / 4.0);
            xy.push(DVec2::new(x0 + fx * (x1 - x0), y0 + fy * (y1 - y0)));
        }
    }
    let mut g = seed;
    let mut next = || {
        g = g.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = g;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..extra {
        let (fx, fy) = (next(), next());
        xy.push(DVec2::new(x0 + fx * (x1 - x0), y0 + fy * (y1 - y0)));
    }
    let mut eyes = Vec::with_capacity(2 * xy.len());
    for p in xy {
        match cell.height {
            Height::Band([z0, z1]) => {
                eyes.push(p.extend(z0));
                eyes.push(p.extend(z1));
            }
            Height::AboveGround([h0, h1]) => {
                if let Some(g) = truth.locator().ground_height(truth.tin(), p) {
                    eyes.push(p.extend(g + h0));
                    eyes.push(p.extend(g + h1));
                }
            }
        }
    }
    eyes
}

/// What the exact checker sees and the safe culler draws from a cell's sample points.
#[derive(Clone, Debug, PartialEq)]
pub struct CellCheck {
    /// Sample points used.
    pub eyes: usize,
    /// Per triangle (hierarchy order): visible from some sample point (exact checker).
    pub visible: Vec<bool>,
    /// Per triangle: drawn by the safe from-point culler from some sample point.
    pub safe_drawn: Vec<bool>,
}

impl CellCheck {
    /// Triangles visible from some sample point but missing from `pvs` (a per-triangle mask): 0 is the target.
    pub fn misses(&self, pvs: &[bool]) -> Vec<u32> {
        self.visible
            .iter()
            .zip(pvs)
            .enumerate()
            .filter(|(_, (v, p))| **v && !**p)
            .map(|(t, _)| t as u32)
            .collect()
    }

    /// Number of triangles visible from some sample point.
    pub fn visible_count(&self) -> u64 {
        self.visible.iter().filter(|&&v| v).count() as u64
    }

    /// Number of triangles drawn by the safe culler from some sample point.
    pub fn safe_count(&self) -> u64 {
        self.safe_drawn.iter().filter(|&&v| v).count() as u64
    }
}

/// The unions over `eyes` of the exact visible sets (`truth` over the hierarchy's mesh, triangles in hierarchy order)
/// and of the safe culler's drawn sets (360°).
pub fn check_cell(truth: &GroundTruth, safe: &SafeCuller, eyes: &[DVec3]) -> CellCheck {
    let n = truth.tin().num_triangles();
    let mut visible = vec![false; n];
    let mut safe_drawn = vec![false; n];
    let mut list = DrawList::default();
    for &eye in eyes {
        for (u, v) in visible.iter_mut().zip(truth.visible_triangles(eye)) {
            *u |= v;
        }
        safe.cull_into(&Camera::all_around(eye.to_array()), &mut list);
        for r in &list.ranges {
            for d in &mut safe_drawn[r[0] as usize..(r[1] as usize).min(n)] {
                *d = true;
            }
        }
    }
    CellCheck {
        eyes: eyes.len(),
        visible,
        safe_drawn,
    }
}
