//! Colours of the renders and the interactive viewer: the group palette (one distinct colour per leaf group, dark
//! grey for the always-visible triangles; owned by [`pipeline::palette`] and shared with the grouped OBJ export),
//! a hypsometric ramp for plain meshes, and the drawn / culled / false-cull colours.
//!
//! Colours are display values (sRGB-encoded) in `[0, 1]`; the renderer writes them to the image unchanged, apart
//! from the hillshade factor.

pub use pipeline::palette::{ORPHAN_COLOUR, group_colour};

/// Triangles the culler draws, in the `visibility` colouring: pale green.
pub const DRAWN_COLOUR: [f64; 3] = [0.62, 0.80, 0.52];

/// Triangles the culler skips, in the `visibility` colouring: slate blue.
pub const CULLED_COLOUR: [f64; 3] = [0.36, 0.44, 0.72];

/// False culls (culled but visible by the ground truth): pure red, so that they can be counted in an image.
pub const FALSE_CULL_COLOUR: [f64; 3] = [1.0, 0.0, 0.0];

/// The viewpoint marker: magenta.
pub const MARKER_COLOUR: [f64; 3] = [0.95, 0.10, 0.85];

/// Background of every render: a light blue-grey sky.
pub const BACKGROUND: [f64; 3] = [0.80, 0.85, 0.90];

/// A hypsometric ramp for `t` in `[0, 1]` (low to high): green lowland, ochre, brown, near-white summits.
/// Values outside `[0, 1]` are clamped.
pub fn height_colour(t: f64) -> [f64; 3] {
    const STOPS: [(f64, [f64; 3]); 5] = [
        (0.0, [0.20, 0.45, 0.25]),
        (0.3, [0.55, 0.65, 0.35]),
        (0.6, [0.72, 0.62, 0.40]),
        (0.85, [0.55, 0.42, 0.32]),
        (1.0, [0.95, 0.95, 0.95]),
    ];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    let i = STOPS.iter().rposition(|s| s.0 <= t).unwrap_or(0).min(STOPS.len() - 2);
    let (t0, a) = STOPS[i];
    let (t1, b) = STOPS[i + 1];
    let f = (t - t0) / (t1 - t0);
    [
        a[0] + (b[0] - a[0]) * f,
        a[1] + (b[1] - a[1]) * f,
        a[2] + (b[2] - a[2]) * f,
    ]
}

/// Converts a `[0, 1]` colour to 8-bit RGBA (opaque), rounding to nearest.
pub fn to_rgba8(c: [f64; 3]) -> [u8; 4] {
    let q = |v: f64| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    [q(c[0]), q(c[1]), q(c[2]), 255]
}
