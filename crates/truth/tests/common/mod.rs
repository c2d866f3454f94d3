//! Shared test helpers: an independent brute-force visibility oracle and terrain builders.

#![allow(dead_code)]

use glam::{DVec2, DVec3};
use tin::{DedupePolicy, Tin, triangulate};

/// What the brute-force oracle concludes about one segment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// The segment is nowhere below the terrain (within 1e-10 m).
    Visible,
    /// The segment is below the terrain by more than 1e-5 m somewhere.
    Hidden,
    /// Too close to grazing to compare with a tolerance-based test.
    Unclear,
}

/// Smallest clearance (segment height minus terrain height) over the segment target -> eye, ignoring the target
/// point itself (parameter s <= 1e-9), computed by testing the segment against the vertical prism of every
/// triangle: the segment's x,y projection is clipped to the triangle, and the clearance, linear on the clipped
/// piece, is evaluated at both ends. `f64::INFINITY` when the segment meets no triangle.
///
/// Independent of the walk: no adjacency, no exact predicates, no locator; plane heights come from the 3-D normal.
pub fn min_clearance(tin: &Tin, eye: DVec3, target: DVec3) -> f64 {
    let (q0, q1) = (target.truncate(), eye.truncate());
    let d = q1 - q0;
    let mut min_c = f64::INFINITY;
    for t in 0..tin.num_triangles() {
        let [a, b, c] = tin.corners(t);
        let n = (b - a).cross(c - a);
        let plane = |q: DVec2| a.z - (n.x * (q.x - a.x) + n.y * (q.y - a.y)) / n.z;
        let p = [a, b, c].map(|v| v.truncate());
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        let mut empty = false;
        for i in 0..3 {
            let (pi, pj) = (p[i], p[(i + 1) % 3]);
            let e = pj - pi;
            let f0 = e.perp_dot(q0 - pi);
            let f1 = e.perp_dot(q1 - pi);
            if f0 < 0.0 && f1 < 0.0 {
                empty = true;
                break;
            }
            if f0 < 0.0 {
                lo = lo.max(f0 / (f0 - f1));
            } else if f1 < 0.0 {
                hi = hi.min(f0 / (f0 - f1));
            }
        }
        if empty || lo > hi {
            continue;
        }
        for s in [lo, hi] {
            if s <= 1e-9 {
                continue;
            }
            let q = q0 + s * d;
            let clearance = target.z + s * (eye.z - target.z) - plane(q);
            min_c = min_c.min(clearance);
        }
    }
    min_c
}

/// The oracle's verdict for the segment target -> eye.
pub fn oracle(tin: &Tin, eye: DVec3, target: DVec3) -> Verdict {
    let c = min_clearance(tin, eye, target);
    if c < -1e-5 {
        Verdict::Hidden
    } else if c >= -1e-10 {
        Verdict::Visible
    } else {
        Verdict::Unclear
    }
}

/// Delaunay TIN of a w x h integer grid with heights `z(x, y)`, spacing `step`.
pub fn grid_tin(w: usize, h: usize, step: f64, z: impl Fn(f64, f64) -> f64) -> Tin {
    let pts: Vec<DVec3> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f64 * step, (i / w) as f64 * step);
            DVec3::new(x, y, z(x, y))
        })
        .collect();
    triangulate(&pts, DedupePolicy::Reject).expect("grid triangulates").0
}

/// A point of triangle `t` at barycentric weights (1 - u - v, u, v) (folded into the triangle).
pub fn point_in(tin: &Tin, t: usize, u: f64, v: f64) -> DVec3 {
    let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
    let [a, b, c] = tin.corners(t);
    a * (1.0 - u - v) + b * u + c * v
}

/// Centroid of triangle `t`.
pub fn centroid(tin: &Tin, t: usize) -> DVec3 {
    let [a, b, c] = tin.corners(t);
    (a + b + c) / 3.0
}

/// Proptest case count: `PROPTEST_CASES` from the environment when set (for long soak runs), else `default`.
pub fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}
