//! Sector geometry shared by every stage (the horizon stage uses the same directions; its `sector` module holds the
//! horizon's definition).
//!
//! Azimuth is measured counter-clockwise from +x. With `s` sectors, sector `i` covers azimuths
//! `[2πi/s, 2π(i+1)/s)`; its centre direction `r_i` is the unit vector at azimuth `2π(i + ½)/s`. A point's coordinate
//! in the sector's vertical plane is `t = r_i · xy`.

use std::f64::consts::TAU;

/// The unit centre direction `r_i` of sector `i` of `sectors`, as `[x, y]`: azimuth `2π(2i + 1) / (2s)`, with the
/// exact values at multiples of 45° (the horizon stage uses the same directions, bit for bit). `sectors` must be at
/// least 1 (NaN for 0).
pub fn sector_direction(sectors: u32, i: u32) -> [f64; 2] {
    let (num, den) = (2 * u64::from(i) + 1, 2 * u64::from(sectors));
    if (8 * num).is_multiple_of(den) {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        return match (8 * num / den) % 8 {
            0 => [1.0, 0.0],
            1 => [h, h],
            2 => [0.0, 1.0],
            3 => [-h, h],
            4 => [-1.0, 0.0],
            5 => [-h, -h],
            6 => [0.0, -1.0],
            _ => [h, -h],
        };
    }
    let (sin, cos) = (TAU * num as f64 / den as f64).sin_cos();
    [cos, sin]
}

/// Azimuth of the direction `(dx, dy)` in `[0, 2π)`.
pub fn azimuth(dx: f64, dy: f64) -> f64 {
    let a = dy.atan2(dx);
    if a < 0.0 { (a + TAU).min(TAU.next_down()) } else { a }
}

/// The sector of `sectors` that contains azimuth `angle` (any real; wrapped into `[0, 2π)`).
///
/// # Panics
///
/// When `sectors` is 0 (no sector holds it; every hierarchy has at least one, see
/// [`crate::Hierarchy::check_invariants`]).
pub fn sector_of_azimuth(sectors: u32, angle: f64) -> u32 {
    let i = (angle * (f64::from(sectors) / TAU)).floor() as i64;
    i.rem_euclid(i64::from(sectors)) as u32
}

/// Calls `f` once for every sector of `sectors` that the closed azimuth interval `[centre − half, centre + half]`
/// touches, in increasing order from the interval's start (wrapping past 2π). `half ≥ π` touches every sector. Panics
/// as [`sector_of_azimuth`] when `sectors` is 0.
pub fn for_each_sector_in(sectors: u32, centre: f64, half: f64, mut f: impl FnMut(u32) -> bool) -> bool {
    if half >= std::f64::consts::PI {
        return (0..sectors).all(f);
    }
    let first = sector_of_azimuth(sectors, centre - half);
    let last = sector_of_azimuth(sectors, centre + half);
    let count = (last + sectors - first) % sectors + 1;
    (0..count).all(|k| f((first + k) % sectors))
}

/// Whether every direction from the camera to a circle (centre offset `centre` from the camera in x,y, `radius`)
/// misses the horizontal view `yaw ± half_fov` (a camera inside the circle sees it); `|yaw| ≤ 2π`
/// ([`crate::Camera::frustum`] reduces it).
///
/// *Proof.* With the camera outside the circle (`d = |centre| > r`), the directions to the disc's points fill the
/// closed arc `θ ± α` of azimuths, `θ` the centre's and `α = asin(r / d)` (the tangents). The view is the closed arc
/// `yaw ± h`. Two closed arcs of the circle of directions are disjoint exactly when the angular distance of their
/// centres, `|gap|` with `gap` reduced to `[−π, π]`, exceeds `h + α` (never when `h + α ≥ π`). Rounding: `d` (hypot,
/// within an ulp) and the division leave `r / d` within a relative `4ε` of the true ratio, so the ratio raised by a
/// relative `1e-12` (and capped at 1) is at least the true one, and `asin`, increasing, of it at least the true `α`
/// up to its own error of an ulp or two; `atan2`, the subtraction of `yaw` and the reduction move `gap` by a few ulp
/// of 2π, below `1e-14`. The `1e-12` rad added to `α` covers both, so "outside" is said only when the true `|gap|`
/// exceeds `h + α`. (Raising the ratio before `asin`, not `α` after it, matters when the camera is just outside the
/// circle: there `asin` magnifies an error of `r / d` by `1 / √(1 − (r/d)²)`.)
pub(crate) fn circle_outside_view(centre: [f64; 2], radius: f64, yaw: f64, half_fov: f64) -> bool {
    let dist = centre[0].hypot(centre[1]);
    if dist <= radius {
        return false;
    }
    let half = ((radius / dist) * (1.0 + 1e-12)).min(1.0).asin() + 1e-12;
    let to_node = azimuth(centre[0], centre[1]);
    let gap = (to_node - yaw + std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI;
    gap.abs() > half_fov + half
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    /// Distance from `p` to the ray from the origin along the unit vector `e`.
    fn ray_distance(p: [f64; 2], e: [f64; 2]) -> f64 {
        let along = p[0] * e[0] + p[1] * e[1];
        if along <= 0.0 {
            p[0].hypot(p[1])
        } else {
            (e[0] * p[1] - e[1] * p[0]).abs()
        }
    }

    /// An oracle independent of angles and their wrap-around: whether the disc `(c, r)` misses the closed view wedge
    /// `yaw ± half` by more than `tol`, from the disc's distances to the wedge's two boundary rays and the side of
    /// the wedge its centre lies on. Up to a right angle the wedge is convex: the disc misses it when its centre is
    /// outside and both rays are farther than `r`; beyond, its complement is convex and must hold the disc.
    fn misses(c: [f64; 2], r: f64, yaw: f64, half: f64, tol: f64) -> bool {
        if half >= PI {
            return false; // the view is every direction
        }
        let dir = |a: f64| [a.cos(), a.sin()];
        let (e, lo, hi) = (dir(yaw), dir(yaw - half), dir(yaw + half));
        let d = c[0].hypot(c[1]);
        let rays_far = ray_distance(c, lo) > r + tol && ray_distance(c, hi) > r + tol;
        let along = c[0] * e[0] + c[1] * e[1];
        if half <= FRAC_PI_2 {
            rays_far && along < d * half.cos() - tol
        } else {
            rays_far && -along > d * (PI - half).cos() + tol
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 4000, ..ProptestConfig::default() })]

        /// A circle called outside the view misses it (the frustum test of every culler: a node so called is culled
        /// whole), against an oracle that uses no azimuths; and the test is not vacuous: a circle that misses the
        /// view by a clear margin is called outside. Circles are placed anywhere, or tangent to a boundary ray (to
        /// within a relative 1e-9 either side), with yaws around the wrap at 0 and 2π and beyond.
        #[test]
        fn a_circle_called_outside_the_view_misses_it(
            yaw in -8.0f64..8.0, half in 1e-6f64..3.2, dist in 0.5f64..1e5, angle in -4.0f64..4.0,
            radius_share in 0.0f64..1.2, tangent in prop::option::of((any::<bool>(), -1e-9f64..1e-9)),
            grazing in prop::option::of(-16.0f64..-6.0),
        ) {
            let mut c = [dist * angle.cos(), dist * angle.sin()];
            // The camera just outside the circle (`d = r (1 + 10^g)`): the circle then spans almost half the
            // directions, where `asin` magnifies every rounding of `r / d`.
            let mut r = grazing.map_or(radius_share * dist, |g| dist / (1.0 + 10f64.powf(g)));
            if let Some((upper, rel)) = tangent {
                // The circle touches a boundary ray at the point `dist` along it, from outside the view.
                let a = if upper { yaw + half } else { yaw - half };
                let (e, n) = ([a.cos(), a.sin()], if upper { [-a.sin(), a.cos()] } else { [a.sin(), -a.cos()] });
                r = radius_share.min(1.0) * dist * 0.5;
                let off = r * (1.0 + rel);
                c = [dist * e[0] + off * n[0], dist * e[1] + off * n[1]];
            }
            let d = c[0].hypot(c[1]);
            let tol = 1e-11 * (d + r);
            if circle_outside_view(c, r, yaw, half) {
                prop_assert!(d > r, "a circle around the camera is never outside the view");
                prop_assert!(misses(c, r, yaw, half, -tol), "c {c:?} r {r} yaw {yaw} half {half}: it meets the view");
            } else if d > r {
                prop_assert!(!misses(c, r, yaw, half, 1e-6 * (d + r)), "c {c:?} r {r} yaw {yaw} half {half}: it misses the view");
            }
        }
    }

    #[test]
    fn directions_are_sector_centres() {
        let [x, y] = sector_direction(4, 0);
        assert!((x - (TAU / 8.0).cos()).abs() < 1e-15 && (y - (TAU / 8.0).sin()).abs() < 1e-15);
        assert_eq!(sector_of_azimuth(4, azimuth(x, y)), 0);
        assert_eq!(sector_of_azimuth(8, -0.01), 7);
        assert_eq!(sector_of_azimuth(8, TAU), 0);
    }

    #[test]
    fn interval_visits_touched_sectors_with_wrap() {
        let mut seen = vec![];
        for_each_sector_in(8, 0.0, 0.1, |s| {
            seen.push(s);
            true
        });
        assert_eq!(seen, vec![7, 0]);
        seen.clear();
        for_each_sector_in(8, 1.0, 4.0, |s| {
            seen.push(s);
            true
        });
        assert_eq!(seen.len(), 8);
        // Early stop when the callback says so.
        let mut calls = 0;
        assert!(!for_each_sector_in(16, 2.0, 1.0, |_| {
            calls += 1;
            false
        }));
        assert_eq!(calls, 1);
    }
}
