//! The group palette shared by the grouped OBJ export ([`crate::export`]) and the viewer's renders: one distinct
//! colour per leaf group (golden-ratio hue steps, so neighbouring indices differ strongly) and dark grey for the
//! always-visible (orphan) triangles. Colours are display values (sRGB-encoded) in `[0, 1]`.

/// A distinct, reproducible colour for group `i` (golden-ratio hue steps, fixed saturation and value).
pub fn group_colour(i: usize) -> [f64; 3] {
    let h = (i as f64 * 0.618_033_988_749_895).fract() * 6.0;
    let (s, v) = (0.65, 0.92);
    let c = v * s;
    let x = c * (1.0 - ((h % 2.0) - 1.0).abs());
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r + m, g + m, b + m]
}

/// The colour of the always-visible (orphan) triangles: dark grey.
pub const ORPHAN_COLOUR: [f64; 3] = [0.25, 0.25, 0.25];
