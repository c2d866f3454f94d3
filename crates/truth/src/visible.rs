//! Ground-truth triangle visibility from a point (design notes, "Measuring accuracy").
//!
//! A triangle is visible from the eye if any of its sample points is visible by the exact segment walk
//! ([`crate::walk`]). The samples are finite, so the visible set found here is a **lower bound** of the true
//! visible set `V`: a triangle seen only through a gap narrower than the sample spacing is reported hidden.
//!
//! Samples, in the order they are tried (cheapest and most likely first; the first visible one ends the test):
//!
//! 1. the centroid;
//! 2. the three vertices;
//! 3. the three edge midpoints;
//! 4. the remaining points of the barycentric grid `(i, j, k) / n`, `i + j + k = n`, where the number of levels `n`
//!    is the smallest for which neighbouring samples subtend at most [`SAMPLE_ANGLE_DEG`] (0.25°) from the eye:
//!    `n = ceil(longest edge / (distance lower bound · 0.25° in radians))`, with the distance lower bound
//!    `|eye − centroid| − (largest centroid-to-corner distance)`. Where `n` would exceed [`MAX_LEVELS`] = 64 (2,145
//!    grid points; a triangle closer than about 3.6 edge lengths to the eye), the triangle is split at its edge
//!    midpoints into four and each part is sampled the same way, its own `n` from its own corners, down to
//!    [`MAX_SPLITS`] = 8 splits, where `n` is capped at 64. A part left coarser than 0.25° has a distance lower bound
//!    below `L / (2^8 · 64 · 0.25° in radians) ≈ L / 71` (`L` the triangle's longest edge) and is at most `L / 2^8`
//!    across, so the 0.25° spacing holds at every point of the triangle farther than `L / 71 + L / 128 < L / 45`
//!    from the eye.
//!
//! Every sample's x,y is nudged toward the centroid by [`NUDGE`] in barycentric terms (each barycentric coordinate is
//! at least 1e-6), so that it lies inside its own triangle and the walk starts there, and its height is that of the
//! triangle's plane at the rounded x,y, computed as the walk computes it: a sample interpolated in 3-D lands off its
//! plane by the slope times the rounding of x,y, which on a near-vertical face at UTM-sized coordinates exceeds the
//! walk's tolerance and would bury it (regression test
//! `a_cliff_face_at_utm_coordinates_is_not_buried_by_its_own_samples`, `tests/checker_attacks.rs`). That height is
//! then lowered by a proven bound on its rounding (`locate::plane_height_bounded`), so that a sample is never above
//! the terrain point it stands for: a segment from a lower start lies below the one from the true point all along its
//! length, so a visible sample makes a visible point. A sample whose rounded x,y falls outside its triangle (exact
//! test) is skipped, and so is every sample of a triangle too near degenerate for a bound: there the plane's height
//! swings with the last bits of x,y, and a sample once floated a kilometre above a sliver whose corners are collinear
//! but for a few ulps (regression test `a_sliver_of_collinear_corners_has_no_floating_samples`).
//!
//! Choices:
//!
//! - **Back faces.** When the eye is below the plane of a triangle by more than the walk's tolerance, every interior
//!   point of the triangle is hidden by the triangle itself (the segment dips under its plane at once), so the
//!   triangle is hidden without sampling. This is the exact answer for the interior; the walk alone could call a
//!   nudged corner sample of such a triangle visible within the tolerance.
//! - **Eye below the terrain** (inside the footprint): nothing is visible (see [`crate::walk`]).
//! - **Non-finite eye:** nothing is visible.
//!
//! Speed: most triangles are hidden, and a hidden triangle needs every sample tested. The first walk that ends
//! below the terrain reports the edge where it did; the following samples of the same triangle first check whether
//! their segment crosses one of the last four such edges below the terrain (the same computation as the walk's at
//! that crossing, a few orientation tests), and walk only when none does. The cache is per triangle, so results do
//! not depend on scheduling. Triangles are tested in parallel (rayon); the result is collected in triangle order,
//! so it does not depend on the number of threads.

use std::borrow::Cow;

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use tin::Tin;

use crate::locate::{Locator, corners_contain, plane_height, plane_height_bounded};
use crate::walk::{EPS_REL, Outcome, edge_blocks, segment_clear, tolerance, walk_outcome};

/// Largest angle (degrees) that neighbouring grid samples of a triangle may subtend from the eye.
pub const SAMPLE_ANGLE_DEG: f64 = 0.25;

/// Cap on the number of barycentric grid levels per triangle or part of one ((64 + 1)(64 + 2) / 2 = 2,145 grid
/// points); a triangle that needs more is split (module documentation).
pub const MAX_LEVELS: usize = 64;

/// Most times a triangle is split in four for its grid samples.
pub const MAX_SPLITS: u32 = 8;

/// How far every sample is pulled toward the centroid, in barycentric terms: each barycentric coordinate of a
/// sample is at least this.
pub const NUDGE: f64 = 1e-6;

/// Number of blocking edges remembered while the samples of one triangle are tested.
const BLOCKER_CACHE: usize = 4;

/// Triangle visibility from any number of eyes over one TIN, reusing its [`Locator`].
#[derive(Clone, Debug)]
pub struct GroundTruth<'a> {
    tin: &'a Tin,
    locator: Cow<'a, Locator>,
}

/// Visible triangles of `tin` from `eye`, one flag per triangle in the TIN's order (a lower bound of `V`).
///
/// Builds a [`Locator`] on every call: use [`GroundTruth`] for several eyes.
pub fn visible_triangles(tin: &Tin, eye: DVec3) -> Vec<bool> {
    GroundTruth::new(tin).visible_triangles(eye)
}

impl<'a> GroundTruth<'a> {
    /// Prepares ground truth for `tin` (builds the locator).
    pub fn new(tin: &'a Tin) -> GroundTruth<'a> {
        GroundTruth {
            tin,
            locator: Cow::Owned(Locator::new(tin)),
        }
    }

    /// Prepares ground truth for `tin` with a locator built before ([`Locator::new`], e.g. kept for height queries);
    /// one that does not [match](Locator::matches) `tin` is not used: a new one is built.
    pub fn with_locator(tin: &'a Tin, locator: &'a Locator) -> GroundTruth<'a> {
        if locator.matches(tin) {
            GroundTruth {
                tin,
                locator: Cow::Borrowed(locator),
            }
        } else {
            GroundTruth::new(tin)
        }
    }

    /// The TIN.
    pub fn tin(&self) -> &'a Tin {
        self.tin
    }

    /// The point locator.
    pub fn locator(&self) -> &Locator {
        &self.locator
    }

    /// [`crate::point_visible`] on this TIN.
    pub fn point_visible(&self, eye: DVec3, target: DVec3) -> bool {
        segment_clear(self.tin, &self.locator, None, target, eye)
    }

    /// Visible triangles from `eye`, one flag per triangle in the TIN's order (a lower bound of `V`).
    pub fn visible_triangles(&self, eye: DVec3) -> Vec<bool> {
        let n = self.tin.num_triangles();
        if !eye.is_finite() || self.eye_buried(eye) {
            return vec![false; n];
        }
        (0..n).into_par_iter().map(|t| self.test_triangle(eye, t)).collect()
    }

    /// Whether triangle `t` is visible from `eye` (false for an index out of range).
    pub fn triangle_visible(&self, eye: DVec3, t: usize) -> bool {
        if t >= self.tin.num_triangles() || !eye.is_finite() || self.eye_buried(eye) {
            return false;
        }
        self.test_triangle(eye, t)
    }

    /// Number of barycentric grid levels of triangle `t` seen from `eye` before any split (1 to [`MAX_LEVELS`]; 0 for
    /// an index out of range): [`MAX_LEVELS`] means that the triangle is split if [`MAX_SPLITS`] allows (module
    /// documentation).
    pub fn levels(&self, eye: DVec3, t: usize) -> usize {
        if t >= self.tin.num_triangles() {
            return 0;
        }
        (levels_wanted(&self.tin.corners(t), eye).clamp(1.0, MAX_LEVELS as f64)) as usize
    }

    /// The sample points of triangle `t` seen from `eye`, in the order they are tried (none for an index out of
    /// range).
    pub fn samples(&self, eye: DVec3, t: usize) -> Vec<DVec3> {
        let mut out = Vec::new();
        if t >= self.tin.num_triangles() {
            return out;
        }
        self.any_sample(eye, t, |p| {
            out.push(p);
            false
        });
        out
    }

    /// Whether triangle `t` faces away from `eye` by more than the tolerance (false for an index out of range).
    pub fn back_facing(&self, eye: DVec3, t: usize) -> bool {
        if t >= self.tin.num_triangles() {
            return false;
        }
        let c = self.tin.corners(t);
        let centroid = (c[0] + c[1] + c[2]) / 3.0;
        eye.z - plane_height(&c, eye.truncate()) < -tolerance(centroid, eye)
    }

    /// Whether the eye is inside the footprint and below the terrain by more than the walk's tolerance for any
    /// target of the TIN (so that every walk would end below the terrain at the eye, if not before).
    fn eye_buried(&self, eye: DVec3) -> bool {
        let Some(ground) = self.locator.ground_height(self.tin, eye.truncate()) else {
            return false;
        };
        let b = self.tin.bbox();
        let farthest = (0..8)
            .map(|i| {
                let corner = DVec3::new(
                    if i & 1 == 0 { b.min.x } else { b.max.x },
                    if i & 2 == 0 { b.min.y } else { b.max.y },
                    if i & 4 == 0 { b.min.z } else { b.max.z },
                );
                corner.distance(eye)
            })
            .fold(0.0, f64::max);
        let highest = eye.z.abs().max(b.min.z.abs()).max(b.max.z.abs());
        eye.z - ground < -EPS_REL * (1.0 + farthest + highest)
    }

    fn test_triangle(&self, eye: DVec3, t: usize) -> bool {
        if self.back_facing(eye, t) {
            return false;
        }
        // Edges that blocked earlier samples of this triangle: a sample whose segment crosses one of them below the
        // terrain is hidden without a walk (the same crossing the walk would reach). Kept per triangle, so the
        // result does not depend on the order in which threads take triangles.
        let mut blockers: [(u32, u32); BLOCKER_CACHE] = [(u32::MAX, u32::MAX); BLOCKER_CACHE];
        let mut next = 0;
        self.any_sample(eye, t, |p| {
            let cached = blockers
                .iter()
                .take_while(|e| e.0 != u32::MAX)
                .any(|&e| edge_blocks(self.tin, &self.locator, e, p, eye));
            if cached {
                return false;
            }
            match walk_outcome(self.tin, &self.locator, Some(t), p, eye) {
                Outcome::Visible => true,
                Outcome::Hidden(Some(edge)) => {
                    blockers[next % BLOCKER_CACHE] = edge;
                    next += 1;
                    false
                }
                Outcome::Hidden(None) => false,
            }
        })
    }

    /// Calls `f` on the samples of `t` in order until it returns true; returns whether it did.
    fn any_sample(&self, eye: DVec3, t: usize, mut f: impl FnMut(DVec3) -> bool) -> bool {
        let c = self.tin.corners(t);
        let third = 1.0 / 3.0;
        let fixed = [
            [third, third, third],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.5, 0.5, 0.0],
            [0.0, 0.5, 0.5],
            [0.5, 0.0, 0.5],
        ];
        if fixed.iter().filter_map(|&b| sample_at(&c, b)).any(&mut f) {
            return true;
        }
        let whole = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        grid_samples(&c, whole, eye, 0, &mut f)
    }
}

/// The number of grid levels that the 0.25° spacing asks of the triangle with corners `c` seen from `eye`
/// (uncapped; infinite when the eye may touch it).
fn levels_wanted(c: &[DVec3; 3], eye: DVec3) -> f64 {
    let centroid = (c[0] + c[1] + c[2]) / 3.0;
    let radius = c.iter().map(|p| p.distance(centroid)).fold(0.0, f64::max);
    let longest = (0..3).map(|i| c[i].distance(c[(i + 1) % 3])).fold(0.0, f64::max);
    let dist = (eye.distance(centroid) - radius).max(f64::MIN_POSITIVE);
    let n = (longest / (dist * SAMPLE_ANGLE_DEG.to_radians())).ceil();
    if n.is_nan() { f64::INFINITY } else { n }
}

/// The sample of the triangle with corners `c` at barycentric coordinates `b`: x,y nudged toward the centroid (each
/// weight at least [`NUDGE`]), height that of the triangle's plane there as the walk computes it, lowered by the bound
/// on its rounding; `None` when the rounded x,y is not in the closed triangle or the triangle is too near degenerate
/// for a bound (module documentation).
fn sample_at(c: &[DVec3; 3], b: [f64; 3]) -> Option<DVec3> {
    let w = b.map(|x| (1.0 - 3.0 * NUDGE) * x + NUDGE);
    let xy = c[0].truncate() * w[0] + c[1].truncate() * w[1] + c[2].truncate() * w[2];
    if !corners_contain(c, xy) {
        return None;
    }
    let (height, error) = plane_height_bounded(c, xy)?;
    // `next_down` undoes the rounding of the difference: the sample is never above the plane.
    Some(xy.extend(if error > 0.0 {
        (height - error).next_down()
    } else {
        height
    }))
}

/// Calls `f` on the grid samples of the part of the triangle `c` whose corners have barycentric coordinates `part`,
/// `depth` splits down (module documentation, sample 4), until it returns true; returns whether it did. The whole
/// triangle (`depth` 0) skips the points tried before (corners, edge midpoints, centroid).
fn grid_samples(
    c: &[DVec3; 3],
    part: [[f64; 3]; 3],
    eye: DVec3,
    depth: u32,
    f: &mut impl FnMut(DVec3) -> bool,
) -> bool {
    let at = |w: [f64; 3]| -> [f64; 3] {
        std::array::from_fn(|k| part[0][k] * w[0] + part[1][k] * w[1] + part[2][k] * w[2])
    };
    let wanted = levels_wanted(&part.map(|b| c[0] * b[0] + c[1] * b[1] + c[2] * b[2]), eye);
    if wanted > MAX_LEVELS as f64 && depth < MAX_SPLITS {
        let mid = |i: usize, j: usize| std::array::from_fn(|k| 0.5 * (part[i][k] + part[j][k]));
        let (m01, m12, m20) = (mid(0, 1), mid(1, 2), mid(2, 0));
        return [
            [part[0], m01, m20],
            [m01, part[1], m12],
            [m20, m12, part[2]],
            [m01, m12, m20],
        ]
        .into_iter()
        .any(|sub| grid_samples(c, sub, eye, depth + 1, f));
    }
    let n = wanted.clamp(1.0, MAX_LEVELS as f64) as usize;
    let inv = 1.0 / n as f64;
    for i in 0..=n {
        for j in 0..=n - i {
            let k = n - i - j;
            if depth == 0 {
                let is_corner = i == n || j == n || k == n;
                let is_mid = 2 * i.max(j).max(k) == n && (i == 0 || j == 0 || k == 0);
                let is_centroid = 3 * i == n && 3 * j == n;
                if is_corner || is_mid || is_centroid {
                    continue;
                }
            }
            if sample_at(c, at([i as f64 * inv, j as f64 * inv, k as f64 * inv])).is_some_and(&mut *f) {
                return true;
            }
        }
    }
    false
}

/// The triangles in a horizontal view wedge: those with a point inside `yaw ± half` (radians, azimuth
/// counter-clockwise from +x) seen from `eye`, in x,y: a vertex inside the wedge, an edge crossed by one of the
/// wedge's two boundary rays, or the eye's x,y inside the (closed) triangle; a point straight above or below the eye
/// is inside. The ground truth of a view narrower than 360° is [`visible_triangles`] restricted to them (`eval
/// --fov`, the viewer). A triangle that meets the wedge with no vertex in it has a stretch of a boundary ray inside
/// it, which either crosses one of its edges or starts inside it (at the eye), so no other case is left.
pub fn in_view(tin: &Tin, eye: DVec3, yaw: f64, half: f64) -> Vec<bool> {
    use std::f64::consts::{PI, TAU};
    if half >= PI {
        return vec![true; tin.num_triangles()];
    }
    // A yaw beyond one turn is reduced exactly first (through its sine and cosine), as `cull::Camera::frustum` does.
    let yaw = if yaw.abs() <= TAU {
        yaw
    } else {
        yaw.sin().atan2(yaw.cos())
    };
    let e = eye.truncate();
    let inside = |p: DVec2| {
        let d = p - e;
        if d.x == 0.0 && d.y == 0.0 {
            return true;
        }
        let gap = (d.y.atan2(d.x) - yaw + PI).rem_euclid(TAU) - PI;
        gap.abs() <= half
    };
    let rays = [yaw - half, yaw + half].map(|a| DVec2::new(a.cos(), a.sin()));
    // Whether the ray from the eye along `r` meets the closed segment `a b`.
    let ray_meets = |r: DVec2, a: DVec2, b: DVec2| {
        let (a, b) = (a - e, b - e);
        let (sa, sb) = (r.perp_dot(a), r.perp_dot(b));
        if (sa > 0.0 && sb > 0.0) || (sa < 0.0 && sb < 0.0) {
            return false;
        }
        // The segment's point on the ray's line, as a distance along the ray (both ends on it: the farther one).
        let along = if sa == sb {
            a.dot(r).max(b.dot(r))
        } else {
            (sb * a.dot(r) - sa * b.dot(r)) / (sb - sa)
        };
        along >= 0.0
    };
    (0..tin.num_triangles())
        .map(|t| {
            let c = tin.corners(t).map(|p| p.truncate());
            c.iter().any(|&p| inside(p))
                || (0..3).any(|i| rays.iter().any(|&r| ray_meets(r, c[i], c[(i + 1) % 3])))
                || (0..3).all(|i| tin::orient2d(c[i], c[(i + 1) % 3], e) >= 0.0)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat() -> Tin {
        let p = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(10.0, 0.0, 0.0),
            DVec3::new(10.0, 10.0, 0.0),
            DVec3::new(0.0, 10.0, 0.0),
        ];
        Tin::from_parts(p, vec![[0, 1, 2], [0, 2, 3]]).expect("square")
    }

    /// A locator built before serves the TIN it was built from; one built from another TIN is not used (its triangle
    /// numbers mean other triangles): ground truth then builds its own and sees what a fresh one sees.
    #[test]
    fn a_given_locator_is_used_only_for_its_own_tin() {
        let tin = flat();
        let own = Locator::new(&tin);
        let gt = GroundTruth::with_locator(&tin, &own);
        assert!(std::ptr::eq(gt.locator(), &own));
        let eye = DVec3::new(3.0, 4.0, 2.0);
        assert_eq!(gt.visible_triangles(eye), GroundTruth::new(&tin).visible_triangles(eye));
        let other = Tin::from_parts(
            vec![DVec3::ZERO, DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.0, 1.0, 0.0)],
            vec![[0, 1, 2]],
        )
        .expect("one triangle");
        let foreign = Locator::new(&other);
        let gt = GroundTruth::with_locator(&tin, &foreign);
        assert!(!std::ptr::eq(gt.locator(), &foreign) && gt.locator().matches(&tin));
        assert_eq!(gt.visible_triangles(eye), vec![true, true]);
    }

    #[test]
    fn sample_grid_has_no_duplicates_and_stays_inside() {
        let tin = flat();
        let gt = GroundTruth::new(&tin);
        // 1 level from far above; 62 levels, the most without a split, from 60 m above.
        for (eye, levels) in [(DVec3::new(5.0, 5.0, 1e6), 1), (DVec3::new(5.0, 5.0, 60.0), 62)] {
            assert_eq!(gt.levels(eye, 0), levels);
            let s = gt.samples(eye, 0);
            let n = levels;
            let expected = if n == 1 {
                7
            } else {
                (n + 1) * (n + 2) / 2 + 1 + if n % 2 == 1 { 3 } else { 0 }
            };
            let expected = if n > 1 && n % 3 == 0 { expected - 1 } else { expected };
            assert_eq!(s.len(), expected, "levels {n}");
            for (i, a) in s.iter().enumerate() {
                assert_eq!(gt.locator().locate(&tin, a.truncate()), Some(0), "sample {i} inside");
                assert_eq!(a.z, 0.0, "sample {i} on its plane");
                for b in &s[..i] {
                    assert!(a.distance(*b) > 1e-9, "duplicate sample {a}");
                }
            }
        }
    }

    /// A triangle near the eye is split: every point of it farther than `L / 45` from the eye (`L` its longest
    /// edge) has a sample within 0.25° of it as seen from the eye, and every sample lies inside it.
    #[test]
    fn a_near_triangle_is_split_until_its_samples_are_a_quarter_degree_apart() {
        let tin = flat();
        let gt = GroundTruth::new(&tin);
        let eye = DVec3::new(5.0, 5.0, 0.5);
        assert_eq!(gt.levels(eye, 0), MAX_LEVELS);
        let s = gt.samples(eye, 0);
        assert!(s.len() > 2 * 2145, "{} samples", s.len());
        for (i, a) in s.iter().enumerate() {
            assert_eq!(gt.locator().locate(&tin, a.truncate()), Some(0), "sample {i} inside");
        }
        let c = tin.corners(0);
        let near = 200f64.sqrt() / 45.0;
        let angle = |p: DVec3, q: DVec3| (p - eye).angle_between(q - eye);
        let steps = 24;
        for i in 0..=steps {
            for j in 0..=steps - i {
                let w = [i, j, steps - i - j].map(|x| x as f64 / steps as f64);
                let p = c[0] * w[0] + c[1] * w[1] + c[2] * w[2];
                if p.distance(eye) <= near {
                    continue;
                }
                let best = s.iter().map(|&q| angle(p, q)).fold(f64::INFINITY, f64::min);
                assert!(
                    best <= SAMPLE_ANGLE_DEG.to_radians(),
                    "point {p}: nearest sample {}°",
                    best.to_degrees()
                );
            }
        }
    }

    #[test]
    fn out_of_range_triangles_do_not_panic() {
        let tin = flat();
        let gt = GroundTruth::new(&tin);
        let eye = DVec3::new(5.0, 5.0, 10.0);
        assert_eq!(gt.levels(eye, 2), 0);
        assert!(gt.samples(eye, 2).is_empty());
        assert!(!gt.back_facing(eye, 2));
        assert!(!gt.triangle_visible(eye, 2));
        assert!(gt.triangle_visible(eye, 1));
    }

    #[test]
    fn levels_follow_the_angle() {
        let tin = flat();
        let gt = GroundTruth::new(&tin);
        // Longest edge of triangle 0 is the diagonal, 14.14 m; radius about 7.45 m.
        let c = tin.corners(0);
        let centroid = (c[0] + c[1] + c[2]) / 3.0;
        let eye = centroid + DVec3::new(0.0, 0.0, 2000.0);
        let n = gt.levels(eye, 0);
        let radius = c.iter().map(|p| p.distance(centroid)).fold(0.0, f64::max);
        let spacing_angle = (200.0f64.sqrt() / n as f64) / (2000.0 - radius);
        assert!(spacing_angle <= SAMPLE_ANGLE_DEG.to_radians());
        let coarser = (200.0f64.sqrt() / (n - 1) as f64) / (2000.0 - radius);
        assert!(coarser > SAMPLE_ANGLE_DEG.to_radians());
    }
}
