//! Exact geometric predicates: the one place where the sweep, the oracle and the undersampling pass compare
//! orientations and slopes.
//!
//! Every decision that selects a horizon (is `q` in the wedge of `p`? is `q1` steeper than `q2` as seen from `p`?)
//! is answered here, from the f64 input values, as if evaluated in exact arithmetic. A floating-point filter answers
//! almost every call; the rare near-degenerate case falls back to exact expansion arithmetic (Shewchuk, *Adaptive
//! Precision Floating-Point Arithmetic and Fast Robust Geometric Predicates*, 1997: `two_sum`, `two_product` with
//! Dekker's split, zero-eliminating grow-expansion). Because the sweep and the oracle call the same functions on the
//! same f64 values, they cannot disagree because of rounding. Orientation itself is not implemented here: it is the
//! project's one exact predicate, [`tin::predicates`], re-exported as [`orient2d`].
//!
//! Exactness needs the products to stay inside the normal f64 range; [`crate::compute`] rejects coordinates outside
//! `0 ∪ [2^-100, 2^100]` in magnitude (see [`COORDINATE_LIMIT`]).

use std::cmp::Ordering;

use glam::DVec2;

/// Largest coordinate magnitude accepted by the exact predicates (2^100); smaller non-zero magnitudes than
/// `1 / COORDINATE_LIMIT` are rejected too, so that no product underflows. The project's one limit, checked at import.
pub use tin::COORDINATE_LIMIT;

const EPS: f64 = f64::EPSILON * 0.5; // unit roundoff 2^-53
const SPLITTER: f64 = 134_217_729.0; // 2^27 + 1
/// Bound on the error of a difference of two [`LineKey`] values, relative to the sum of their magnitudes
/// (each key is within `2u(1+u)` of exact relative to its magnitude; generous margin).
const KEY_ERR_BOUND: f64 = 8.0 * EPS;

#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let x = a + b;
    let bv = x - a;
    let av = x - bv;
    (x, (a - av) + (b - bv))
}

#[inline]
fn split(a: f64) -> (f64, f64) {
    let c = SPLITTER * a;
    let abig = c - a;
    let hi = c - abig;
    (hi, a - hi)
}

/// `a * b = x + y` exactly (Dekker), barring overflow and underflow.
#[inline]
fn two_product(a: f64, b: f64) -> (f64, f64) {
    let x = a * b;
    let (ahi, alo) = split(a);
    let (bhi, blo) = split(b);
    let err1 = x - ahi * bhi;
    let err2 = err1 - alo * bhi;
    let err3 = err2 - ahi * blo;
    (x, alo * blo - err3)
}

/// The exact sign of a sum of at most 32 doubles.
fn exact_sign_of_sum(terms: &[f64]) -> Ordering {
    debug_assert!(terms.len() <= 32);
    let mut e = [0.0f64; 32];
    let mut len = 0;
    for &b in terms {
        // Grow-expansion with zero elimination: e stays non-overlapping, increasing in magnitude.
        let mut q = b;
        let mut k = 0;
        for i in 0..len {
            let (s, h) = two_sum(q, e[i]);
            if h != 0.0 {
                e[k] = h;
                k += 1;
            }
            q = s;
        }
        if q != 0.0 {
            e[k] = q;
            k += 1;
        }
        len = k;
    }
    if len == 0 {
        Ordering::Equal
    } else if e[len - 1] > 0.0 {
        Ordering::Greater
    } else {
        Ordering::Less
    }
}

/// The exact sign of `Σ a_i · b_i` for up to 16 products.
fn exact_sign_of_products(pairs: &[(f64, f64)]) -> Ordering {
    debug_assert!(pairs.len() <= 16);
    let mut terms = [0.0f64; 32];
    for (i, &(a, b)) in pairs.iter().enumerate() {
        let (x, y) = two_product(a, b);
        terms[2 * i] = y;
        terms[2 * i + 1] = x;
    }
    exact_sign_of_sum(&terms[..2 * pairs.len()])
}

/// The sign of the orientation of the triangle `a, b, c`: `Greater` when counter-clockwise (c left of a→b),
/// `Less` when clockwise, `Equal` when collinear; exact. The project's one orientation predicate,
/// [`tin::predicates::orientation`].
pub use tin::predicates::orientation as orient2d;

/// A point's position across a line direction `e`: the value `cross(e, x) = e.x·x.y − e.y·x.x`, in f64, with the
/// magnitude needed to bound its rounding error (0 when the value is exact).
///
/// Across an axis (`e` one of `(±1, 0)`, `(0, ±1)`, as the sector boundaries at multiples of 90° are,
/// [`crate::sector`]) the value is exact: one product is `±x.y` or `±x.x`, the other `±0`, and subtracting a zero is
/// exact. Its magnitude is then 0, so comparisons of two such keys need no exact fallback, and ties (every vertex
/// of one grid row, for a TIN from a DEM) are decided at once.
///
/// `cross(e, q − p) ≥ 0` (q on or left of the line through p with direction e) exactly when
/// `key(q) ≥ key(p)` in exact arithmetic; [`LineKey::cmp_exact`] decides that comparison exactly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineKey {
    value: f64,
    magnitude: f64,
}

impl LineKey {
    /// The key of point `x` across direction `e`.
    #[inline]
    pub fn new(e: DVec2, x: DVec2) -> LineKey {
        let u = e.x * x.y;
        let v = e.y * x.x;
        let axis = (e.x == 0.0 || e.y == 0.0) && e.x.abs() + e.y.abs() == 1.0;
        LineKey {
            value: u - v,
            magnitude: if axis { 0.0 } else { u.abs() + v.abs() },
        }
    }

    /// The approximate value `cross(e, x)`.
    #[inline]
    pub fn value(&self) -> f64 {
        self.value
    }

    /// A gap between approximate values beyond which two keys are certainly ordered like their approximations,
    /// for keys whose magnitudes are at most `max_magnitude` (see [`LineKey::magnitude`]).
    pub fn certain_gap(max_magnitude: f64) -> f64 {
        2.0 * KEY_ERR_BOUND * max_magnitude
    }

    /// The magnitude `|e.x·x.y| + |e.y·x.x|` that bounds the rounding error of the value; 0 when the value is exact
    /// (across an axis).
    #[inline]
    pub fn magnitude(&self) -> f64 {
        self.magnitude
    }

    /// Compares the exact values `cross(e, q)` (self, the key of `q`) and `cross(e, p)` (other, the key of `p`):
    /// `Greater` when `q` lies strictly left of the line through `p` with direction `e`.
    #[inline]
    pub fn cmp_exact(&self, other: &LineKey, e: DVec2, q: DVec2, p: DVec2) -> Ordering {
        let d = self.value - other.value;
        let bound = KEY_ERR_BOUND * (self.magnitude + other.magnitude);
        if d > bound {
            Ordering::Greater
        } else if d < -bound {
            Ordering::Less
        } else if bound == 0.0 {
            // Both values exact (magnitudes 0), and equal.
            Ordering::Equal
        } else {
            side_exact(e, q, p)
        }
    }
}

/// The exact sign of `cross(e, q − p)`: `Greater` when `q` is strictly left of the line through `p` with direction
/// `e`, `Equal` when on it.
#[inline]
pub fn side(e: DVec2, p: DVec2, q: DVec2) -> Ordering {
    LineKey::new(e, q).cmp_exact(&LineKey::new(e, p), e, q, p)
}

#[cold]
fn side_exact(e: DVec2, q: DVec2, p: DVec2) -> Ordering {
    // Across a diagonal (`|e.x| = |e.y|`, the sector boundaries at odd multiples of 45°), `cross(e, q − p) =
    // |e.x| (sgn(e.x) (q.y − p.y) − sgn(e.y) (q.x − p.x))`. When both differences are exact in f64 (their `two_sum`
    // errors are 0: nearby points, by Sterbenz's lemma, such as the vertices of one diagonal of a square grid), its
    // sign is one comparison of f64 values, which is exact.
    if e.x.abs() == e.y.abs() && e.x != 0.0 {
        let (dx, err_x) = two_sum(q.x, -p.x);
        let (dy, err_y) = two_sum(q.y, -p.y);
        if err_x == 0.0 && err_y == 0.0 {
            let a = if e.x > 0.0 { dy } else { -dy };
            let b = if e.y > 0.0 { dx } else { -dx };
            return a.partial_cmp(&b).unwrap_or(Ordering::Equal);
        }
    }
    exact_sign_of_products(&[(e.x, q.y), (-e.y, q.x), (-e.x, p.y), (e.y, p.x)])
}

/// Compares the slopes of `q1` and `q2` seen from `p` in a projection plane (coordinates `(t, z)`), where both lie
/// strictly to the right of `p` (`t > t_p`): `Greater` when `q1` is strictly steeper.
///
/// `slope(q1) > slope(q2)` ⇔ `(z1 − zp)(t2 − tp) > (z2 − zp)(t1 − tp)` ⇔ `q2` is clockwise from `q1` about `p`.
#[inline]
pub fn cmp_slope(p: DVec2, q1: DVec2, q2: DVec2) -> Ordering {
    orient2d(p, q1, q2).reverse()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Exact value of `m · 2^e` scaled by `2^SCALE` as an integer.
    const SCALE: i32 = 12;

    fn to_int(x: f64) -> i128 {
        let scaled = x * 2f64.powi(SCALE);
        assert_eq!(scaled.fract(), 0.0, "{x} not representable on the test lattice");
        scaled as i128
    }

    fn lattice() -> impl Strategy<Value = f64> {
        // 30-bit mantissas with exponents in [-12, 12]: products need more than 53 bits, yet fit an i128.
        (-(1i64 << 30)..(1i64 << 30), -12i32..=12).prop_map(|(m, e)| {
            let x = m as f64 * 2f64.powi(e);
            // Keep on the 2^-12 lattice.
            (x * 4096.0).trunc() / 4096.0
        })
    }

    fn orient_int(a: (i128, i128), b: (i128, i128), c: (i128, i128)) -> Ordering {
        ((a.0 - c.0) * (b.1 - c.1) - (a.1 - c.1) * (b.0 - c.0)).cmp(&0)
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

        #[test]
        fn orient_matches_integer_arithmetic(ax in lattice(), ay in lattice(), bx in lattice(), by in lattice(),
                                             cx in lattice(), cy in lattice()) {
            let (a, b, c) = (DVec2::new(ax, ay), DVec2::new(bx, by), DVec2::new(cx, cy));
            let expect = orient_int((to_int(ax), to_int(ay)), (to_int(bx), to_int(by)), (to_int(cx), to_int(cy)));
            prop_assert_eq!(orient2d(a, b, c), expect);
        }

        #[test]
        fn orient_matches_robust_on_near_collinear(x0 in -1e6f64..1e6, y0 in -1e6f64..1e6, dx in -10.0f64..10.0,
                                                   dy in -10.0f64..10.0, s in -3.0f64..3.0, nudge in -4i64..4) {
            // c on (or a few ulps off) the line through a and b.
            let a = DVec2::new(x0, y0);
            let b = DVec2::new(x0 + dx, y0 + dy);
            let mut c = a + (b - a) * s;
            c.x = f64::from_bits((c.x.to_bits() as i64 + nudge) as u64);
            let r = robust::orient2d(
                robust::Coord { x: a.x, y: a.y },
                robust::Coord { x: b.x, y: b.y },
                robust::Coord { x: c.x, y: c.y },
            );
            prop_assert_eq!(orient2d(a, b, c), r.partial_cmp(&0.0).expect("finite"));
        }

        #[test]
        fn line_key_matches_integer_arithmetic(ex in lattice(), ey in lattice(), qx in lattice(), qy in lattice(),
                                               px in lattice(), py in lattice()) {
            let (e, q, p) = (DVec2::new(ex, ey), DVec2::new(qx, qy), DVec2::new(px, py));
            let (exi, eyi) = (to_int(ex), to_int(ey));
            let expect = (exi * (to_int(qy) - to_int(py)) - eyi * (to_int(qx) - to_int(px))).cmp(&0);
            prop_assert_eq!(side(e, p, q), expect);
            prop_assert_eq!(side_exact(e, q, p), expect);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

        /// Across the axes the keys are exact (magnitude 0) and decide every comparison, ties included, as integer
        /// arithmetic does.
        #[test]
        fn axis_keys_are_exact(axis in 0usize..4, qx in lattice(), qy in lattice(), px in lattice(), py in lattice(),
                               tie in any::<bool>()) {
            let (ex, ey) = [(1i128, 0i128), (0, 1), (-1, 0), (0, -1)][axis];
            let e = DVec2::new(ex as f64, ey as f64);
            // Half the cases on the line through p (a grid row or column).
            let q = match (tie, ey == 0) {
                (true, true) => DVec2::new(qx, py),
                (true, false) => DVec2::new(px, qy),
                (false, _) => DVec2::new(qx, qy),
            };
            let p = DVec2::new(px, py);
            prop_assert_eq!(LineKey::new(e, q).magnitude(), 0.0);
            let expect = (ex * (to_int(q.y) - to_int(py)) - ey * (to_int(q.x) - to_int(px))).cmp(&0);
            prop_assert_eq!(side(e, p, q), expect);
            prop_assert_eq!(side_exact(e, q, p), expect);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

        /// Across the diagonals (`(±h, ±h)`, `h` = f64 `1/√2`) the exact sign is `sgn(e.x) dy − sgn(e.y) dx`, ties
        /// (q on the diagonal through p, as on a square grid) included, whether or not the differences are exact.
        #[test]
        fn diagonal_sides_are_exact(diagonal in 0usize..4, qx in lattice(), qy in lattice(), px in lattice(),
                                    py in lattice(), step in -1000i32..1000, tie in any::<bool>()) {
            let h = std::f64::consts::FRAC_1_SQRT_2;
            let (sx, sy) = [(1i128, 1i128), (-1, 1), (-1, -1), (1, -1)][diagonal];
            let e = DVec2::new(sx as f64 * h, sy as f64 * h);
            let p = DVec2::new(px, py);
            // Half the cases on the diagonal through p: q − p = step · (sx, sy) on the 2^-12 lattice.
            let d = step as f64 / 64.0;
            let q = if tie { DVec2::new(px + sx as f64 * d, py + sy as f64 * d) } else { DVec2::new(qx, qy) };
            let expect = (sx * (to_int(q.y) - to_int(py)) - sy * (to_int(q.x) - to_int(px))).cmp(&0);
            prop_assert_eq!(side(e, p, q), expect);
            prop_assert_eq!(side_exact(e, q, p), expect);
        }
    }

    #[test]
    fn keys_decide_points_on_irrational_lines() {
        // Points constructed to lie a few ulps from the 30° line through p.
        let e = DVec2::new((std::f64::consts::PI / 6.0).cos(), (std::f64::consts::PI / 6.0).sin());
        let p = DVec2::new(500_000.0, 5_000_000.0);
        let mut seen = [0usize; 3];
        for i in 1..2000 {
            let q = p + e * (i as f64 * 0.37);
            let s = side(e, p, q);
            seen[(s as i8 + 1) as usize] += 1;
            // Agree with the exact evaluation.
            assert_eq!(s, side_exact(e, q, p));
            // And with a symmetric evaluation from q.
            assert_eq!(side(e, q, p), s.reverse());
        }
        assert!(
            seen[0] > 0 && seen[2] > 0,
            "rounding should put points on both sides: {seen:?}"
        );
    }

    #[test]
    fn exact_sum_cancels() {
        assert_eq!(exact_sign_of_sum(&[1e300, 1.0, -1e300]), Ordering::Greater);
        assert_eq!(exact_sign_of_sum(&[1e-300, -1.0, 1.0]), Ordering::Greater);
        // The f64 values 0.1 and 0.2 sum to slightly more than the f64 value 0.3.
        assert_eq!(exact_sign_of_sum(&[0.1, 0.2, -0.3]), Ordering::Greater);
        assert_eq!(exact_sign_of_sum(&[]), Ordering::Equal);
        assert_eq!(exact_sign_of_products(&[(3.0, 1.0 / 3.0), (-1.0, 1.0)]), Ordering::Less);
    }
}
