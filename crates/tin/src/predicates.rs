//! The project's one orientation predicate, exact for every finite input: Shewchuk's adaptive `orient2d` (the
//! `robust` crate: a floating-point filter answers almost every call, exact expansion arithmetic the rest).
//!
//! Every crate decides orientation here: [`crate::Tin::from_parts`] and validation (degenerate and clockwise
//! triangles, overlaps), ground truth's point location and segment walks (`truth`), and the covering-set hulls and
//! the undersampling pass of the horizon sweep (`horizon`, through [`orientation`]). So a triangle of area 0.5 m² at
//! UTM-sized coordinates is never called degenerate because of rounding, and two stages never disagree about a turn.

use std::cmp::Ordering;

use glam::DVec2;

/// Largest coordinate magnitude any stage accepts (2^100); non-zero magnitudes below `1 / COORDINATE_LIMIT` are
/// refused too, so that no product of the exact predicates overflows or underflows. Checked at import
/// ([`crate::read_obj`] names the file, the line and the 1-based vertex) and again by the horizon sweep.
pub const COORDINATE_LIMIT: f64 = 1.267_650_600_228_229_4e30;

/// Whether `value` is a coordinate every stage accepts: 0, or a magnitude in `[1 / COORDINATE_LIMIT,
/// COORDINATE_LIMIT]` (so NaN and infinities are not).
pub fn coordinate_in_range(value: f64) -> bool {
    let m = value.abs();
    m == 0.0 || (1.0 / COORDINATE_LIMIT..=COORDINATE_LIMIT).contains(&m)
}

/// Orientation of `c` relative to the directed line `a → b`, in x,y: positive when `c` is on the left (`abc`
/// counter-clockwise), negative on the right, exactly zero when collinear. The sign is exact; the magnitude is twice
/// the triangle's signed area, to within rounding.
#[inline]
pub fn orient2d(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    robust::orient2d(
        robust::Coord { x: a.x, y: a.y },
        robust::Coord { x: b.x, y: b.y },
        robust::Coord { x: c.x, y: c.y },
    )
}

/// [`orient2d`] as an ordering: `Greater` when `abc` is counter-clockwise, `Less` when clockwise, `Equal` when
/// collinear (or when an input is NaN).
#[inline]
pub fn orientation(a: DVec2, b: DVec2, c: DVec2) -> Ordering {
    orient2d(a, b, c).partial_cmp(&0.0).unwrap_or(Ordering::Equal)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_where_the_naive_formula_rounds_to_zero() {
        // (b - a) x (c - a) = k·k - (k - 1)(k + 1) = 1, but (k - 1)(k + 1) rounds to k² = 2^54 in f64.
        let k = 134_217_728.0;
        let a = DVec2::new(1e6, 5e6);
        let b = a + DVec2::new(k, k - 1.0);
        let c = a + DVec2::new(k + 1.0, k);
        assert_eq!((b - a).perp_dot(c - a), 0.0, "the naive formula loses it");
        assert_eq!(orientation(a, b, c), Ordering::Greater);
        assert_eq!(orientation(a, c, b), Ordering::Less);
        assert_eq!(orient2d(a, b, c), 1.0);
        assert_eq!(orientation(a, a, b), Ordering::Equal);
    }
}
