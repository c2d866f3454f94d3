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
//!    `|eye − centroid| − (largest centroid-to-corner distance)`. `n` is capped at [`MAX_LEVELS`] = 64
//!    (2,145 grid points), which only binds for triangles closer than about 3.6 edge lengths to the eye.
//!
//! Every sample is nudged toward the centroid by [`NUDGE`] in barycentric terms (each barycentric coordinate is at
//! least 1e-6), so that it lies inside its own triangle and the walk starts there.
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

use glam::DVec3;
use rayon::prelude::*;
use tin::Tin;

use crate::locate::{Locator, plane_height};
use crate::walk::{EPS_REL, Outcome, edge_blocks, segment_clear, tolerance, walk_outcome};

/// Largest angle (degrees) that neighbouring grid samples of a triangle may subtend from the eye.
pub const SAMPLE_ANGLE_DEG: f64 = 0.25;

/// Cap on the number of barycentric grid levels per triangle ((64 + 1)(64 + 2) / 2 = 2,145 grid points).
pub const MAX_LEVELS: usize = 64;

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

    /// Number of barycentric grid levels used for triangle `t` seen from `eye` (1 to [`MAX_LEVELS`]; 0 for an index
    /// out of range).
    pub fn levels(&self, eye: DVec3, t: usize) -> usize {
        if t >= self.tin.num_triangles() {
            return 0;
        }
        let c = self.tin.corners(t);
        let centroid = (c[0] + c[1] + c[2]) / 3.0;
        let radius = c.iter().map(|p| p.distance(centroid)).fold(0.0, f64::max);
        let longest = (0..3).map(|i| c[i].distance(c[(i + 1) % 3])).fold(0.0, f64::max);
        let dist = (eye.distance(centroid) - radius).max(f64::MIN_POSITIVE);
        let n = (longest / (dist * SAMPLE_ANGLE_DEG.to_radians())).ceil();
        if n.is_nan() {
            MAX_LEVELS
        } else {
            n.clamp(1.0, MAX_LEVELS as f64) as usize
        }
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
        let at = |b: [f64; 3]| {
            let w = b.map(|x| (1.0 - 3.0 * NUDGE) * x + NUDGE);
            c[0] * w[0] + c[1] * w[1] + c[2] * w[2]
        };
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
        if fixed.iter().any(|&b| f(at(b))) {
            return true;
        }
        let n = self.levels(eye, t);
        for i in 0..=n {
            for j in 0..=n - i {
                let k = n - i - j;
                let is_corner = i == n || j == n || k == n;
                let is_mid = 2 * i.max(j).max(k) == n && (i == 0 || j == 0 || k == 0);
                let is_centroid = 3 * i == n && 3 * j == n;
                if is_corner || is_mid || is_centroid {
                    continue;
                }
                let inv = 1.0 / n as f64;
                if f(at([i as f64 * inv, j as f64 * inv, k as f64 * inv])) {
                    return true;
                }
            }
        }
        false
    }
}

/// The triangles in a horizontal view wedge: those with a vertex or the centroid inside `yaw ± half` (radians,
/// azimuth counter-clockwise from +x) seen from `eye`; a point straight above or below the eye is inside. The ground
/// truth of a view narrower than 360° is [`visible_triangles`] restricted to them (`eval --fov`, the viewer).
pub fn in_view(tin: &Tin, eye: DVec3, yaw: f64, half: f64) -> Vec<bool> {
    use std::f64::consts::{PI, TAU};
    // A yaw beyond one turn is reduced exactly first (through its sine and cosine), as `cull::Camera::frustum` does.
    let yaw = if yaw.abs() <= TAU {
        yaw
    } else {
        yaw.sin().atan2(yaw.cos())
    };
    let inside = |p: DVec3| {
        let d = p - eye;
        if d.x == 0.0 && d.y == 0.0 {
            return true;
        }
        let gap = (d.y.atan2(d.x) - yaw + PI).rem_euclid(TAU) - PI;
        gap.abs() <= half
    };
    (0..tin.num_triangles())
        .map(|t| {
            let c = tin.corners(t);
            c.iter().any(|&p| inside(p)) || inside((c[0] + c[1] + c[2]) / 3.0)
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
        for (eye, levels) in [(DVec3::new(5.0, 5.0, 1e6), 1), (DVec3::new(5.0, 5.0, 1.0), MAX_LEVELS)] {
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
                for b in &s[..i] {
                    assert!(a.distance(*b) > 1e-9, "duplicate sample {a}");
                }
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
