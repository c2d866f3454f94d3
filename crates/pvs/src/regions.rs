//! The cheap from-region test over our own precomputed data: a node is hidden from the whole viewcell if the cell,
//! as a box, lies inside the node's conservative region (`occlusion::conservative`, via
//! `pipeline::conservative_hierarchy`) in every sector that the cell–node azimuth interval touches.
//!
//! **Proof.** The conservative region of node `N` in sector `i` is a set of cameras `c` hidden from every point `p`
//! of `N` whose direction `c − p` lies in sector `i` (theorem in `occlusion::conservative`; its f32 storage only
//! shrinks it). In the sector's plane `(t, z) = (r_i · xy, z)` it is `{t > t0, z < h(t)}` with `h` piecewise linear
//! (its stored points, then its tail), a set closed downwards, and the map from 3-D to `(t, z)` is linear: the box's
//! points have `t` in `[t_lo, t_hi]`, the least and greatest `t` of its corners, and `z` at most its top `z_top`. The
//! box lies in the region if `t_lo > t0` and `z_top < h(t)` for every `t` in `[t_lo, t_hi]`; `h` being linear between
//! its vertices (not concave: a union of half-planes joins a falling line to a later rising one, a V), its least value
//! on the interval is at an end or at a vertex inside it. So the four top corners and every region vertex with `t`
//! strictly between `t_lo` and `t_hi` are tested, with the strict [`cull::StoredRegion::contains`] (which evaluates
//! `h` in f64 from the stored f32 points, the same value at a vertex as on either side of it). For `p` in `N`'s
//! bounding circle `(m, r)` and `c` in the cell's circle `(m_c, r_c)` (`c − p` then lies in the disc of radius
//! `r + r_c` around `m_c − m`), the direction of `c − p` is within `asin((r + r_c) / |m_c − m|)` of the azimuth of
//! `m_c − m`; the culler's own interval test ([`cull::for_each_sector_in`], closed interval, widened by a relative
//! 1e-12) visits every sector it may fall in. A cell whose circle meets the node's is visible. Coordinates are relative
//! to the hierarchy's origin, as the stored regions and circles are; the cell's circle radius is widened by
//! `1e-9 (1 + |m_c|)` for the rounding of its corners' shift.

// Comparisons are written so that a NaN answers "visible", on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use cull::{Hierarchy, azimuth, for_each_sector_in};

use crate::koltun::Box3;

/// Whether hierarchy node `index` of `h` (whose regions must be conservative) is hidden from every point of `cell`.
pub fn hidden_by_regions(h: &Hierarchy, index: usize, cell: &Box3) -> bool {
    let node = &h.nodes[index];
    if node.regions.is_empty() {
        return false;
    }
    let [ox, oy, oz] = h.origin;
    let corners = [
        [cell.lo[0] - ox, cell.lo[1] - oy],
        [cell.hi[0] - ox, cell.lo[1] - oy],
        [cell.lo[0] - ox, cell.hi[1] - oy],
        [cell.hi[0] - ox, cell.hi[1] - oy],
    ];
    let mc = [
        0.5 * (corners[0][0] + corners[3][0]),
        0.5 * (corners[0][1] + corners[3][1]),
    ];
    let rc = corners
        .iter()
        .map(|c| (c[0] - mc[0]).hypot(c[1] - mc[1]))
        .fold(0.0f64, f64::max)
        * (1.0 + 1e-12)
        + 1e-9 * (1.0 + mc[0].abs() + mc[1].abs());
    let (dx, dy) = (mc[0] - f64::from(node.centre[0]), mc[1] - f64::from(node.centre[1]));
    let dist = dx.hypot(dy);
    let reach = f64::from(node.radius) + rc;
    if !(dist > reach) {
        return false;
    }
    let half = (reach / dist).min(1.0).asin() * (1.0 + 1e-12);
    let z = cell.ztop - oz;
    for_each_sector_in(h.sectors, azimuth(dx, dy), half, |sector| {
        let Some(region) = node.regions.iter().find(|r| u32::from(r.sector) == sector) else {
            return false;
        };
        let [rx, ry] = h.sector_direction(sector);
        let ts = corners.map(|c| rx * c[0] + ry * c[1]);
        let (t_lo, t_hi) = (
            ts.iter().copied().fold(f64::INFINITY, f64::min),
            ts.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        );
        // The corners, then every vertex of the boundary between them: `h` is piecewise linear but not concave.
        ts.iter().all(|&t| region.contains(t, z))
            && region.points.iter().all(|p| {
                let t = f64::from(p[0]);
                !(t_lo < t && t < t_hi) || region.contains(t, z)
            })
    })
}
