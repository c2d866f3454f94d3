//! Sector geometry shared by every stage (design.md "Sectors and horizons").
//!
//! Azimuth is measured counter-clockwise from +x. With `s` sectors, sector `i` covers azimuths
//! `[2πi/s, 2π(i+1)/s)`; its centre direction `r_i` is the unit vector at azimuth `2π(i + ½)/s`. A point's coordinate
//! in the sector's vertical plane is `t = r_i · xy`.

use std::f64::consts::TAU;

/// The unit centre direction `r_i` of sector `i` of `sectors`, as `[x, y]`: azimuth `2π(2i + 1) / (2s)`, with the
/// exact values at multiples of 45° (the horizon stage uses the same directions, bit for bit).
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
pub fn sector_of_azimuth(sectors: u32, angle: f64) -> u32 {
    let i = (angle * (f64::from(sectors) / TAU)).floor() as i64;
    i.rem_euclid(i64::from(sectors)) as u32
}

/// Calls `f` once for every sector of `sectors` that the closed azimuth interval `[centre − half, centre + half]`
/// touches, in increasing order from the interval's start (wrapping past 2π). `half ≥ π` touches every sector.
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
/// misses the horizontal view `yaw ± half_fov` (a camera inside the circle sees it).
pub(crate) fn circle_outside_view(centre: [f64; 2], radius: f64, yaw: f64, half_fov: f64) -> bool {
    let dist = centre[0].hypot(centre[1]);
    if dist <= radius {
        return false;
    }
    let half = (radius / dist).min(1.0).asin() * (1.0 + 1e-12) + 1e-12;
    let to_node = azimuth(centre[0], centre[1]);
    let gap = (to_node - yaw + std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI;
    gap.abs() > half_fov + half
}

#[cfg(test)]
mod tests {
    use super::*;

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
