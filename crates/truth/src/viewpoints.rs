//! Seeded viewpoint sets of the six classes of the design notes ("Measuring accuracy").
//!
//! | class | position |
//! | --- | --- |
//! | `ground` | uniform over the footprint, 2 m above the terrain |
//! | `low` | uniform over the footprint, 20 m above the terrain |
//! | `high` | uniform over the footprint, 200 m above the terrain |
//! | `valley` | 2 m above a local minimum |
//! | `ridge` | 2 m above a local maximum |
//! | `sky` | uniform over the footprint, 10% of the relief (max z − min z) above the highest vertex |
//!
//! Choices:
//!
//! - "Uniform over the footprint": a triangle is drawn with probability proportional to its x,y area, then a
//!   uniform point inside it; the terrain height there is the triangle's plane. This is exactly uniform over the
//!   footprint, whatever its shape, without rejection. The triangles are taken in a canonical order (by their
//!   corners' positions, each triangle's corners rotated to start at its least one), not in the order the TIN
//!   stores them: builds of one mesh store its triangles in different orders (the grouping decides it), and they
//!   get the same eyes.
//! - A local minimum (maximum) is a vertex strictly lower (higher) than every vertex it shares a triangle with.
//!   Vertices that belong to no triangle are ignored everywhere. Vertices on the footprint boundary are left out: their
//!   neighbourhood is cut off by the edge of the data, so they are not known to be extrema. When no interior vertex
//!   qualifies, the candidates are all vertices, lowest (highest) first. `n` viewpoints are drawn from the candidates
//!   without replacement (a seeded shuffle) while candidates last, then with replacement. With the fallback, the first
//!   `n` lowest (highest) vertices are used in order instead.
//! - On a flat terrain the relief is 0, so `sky` viewpoints lie on the surface (where everything is grazing).
//! - The random generator is `ChaCha8Rng::seed_from_u64(seed)`, so the same TIN, class, count and seed give the same
//!   points on every platform.

use std::fmt;
use std::str::FromStr;

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tin::{NO_NEIGHBOUR, Tin};

use crate::error::TruthError;

/// The six viewpoint classes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ViewpointClass {
    /// 2 m above the terrain, anywhere on the footprint.
    Ground,
    /// 20 m above the terrain.
    Low,
    /// 200 m above the terrain.
    High,
    /// 2 m above a local minimum.
    Valley,
    /// 2 m above a local maximum.
    Ridge,
    /// 10% of the relief above the highest point.
    Sky,
    /// Eyes given by the user (a camera path, `eval --eyes`); not drawn by [`viewpoints()`].
    Path,
}

impl ViewpointClass {
    /// All six classes, in the order of the design notes.
    pub const ALL: [ViewpointClass; 6] = [
        ViewpointClass::Ground,
        ViewpointClass::Low,
        ViewpointClass::High,
        ViewpointClass::Valley,
        ViewpointClass::Ridge,
        ViewpointClass::Sky,
    ];

    /// The class's name as used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            ViewpointClass::Ground => "ground",
            ViewpointClass::Low => "low",
            ViewpointClass::High => "high",
            ViewpointClass::Valley => "valley",
            ViewpointClass::Ridge => "ridge",
            ViewpointClass::Sky => "sky",
            ViewpointClass::Path => "path",
        }
    }
}

impl fmt::Display for ViewpointClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ViewpointClass {
    type Err = TruthError;

    /// A class by its name, blanks around it ignored (`--classes "ground, low"`, as other lists are read).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let s = s.trim();
        ViewpointClass::ALL
            .into_iter()
            .find(|c| c.name() == s)
            .ok_or_else(|| TruthError::UnknownClass(s.to_string()))
    }
}

/// Height above the terrain of the classes placed relative to the ground (m).
const GROUND_OFFSET: f64 = 2.0;
const LOW_OFFSET: f64 = 20.0;
const HIGH_OFFSET: f64 = 200.0;
/// Height above a local extremum (m).
const EXTREMUM_OFFSET: f64 = 2.0;
/// Fraction of the relief above the highest point for `sky`.
const SKY_FRACTION: f64 = 0.1;

/// `n` viewpoints of `class` over `tin`, drawn with `ChaCha8Rng::seed_from_u64(seed)`.
pub fn viewpoints(tin: &Tin, class: ViewpointClass, n: usize, seed: u64) -> Vec<DVec3> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    match class {
        ViewpointClass::Ground => uniform_points(tin, n, &mut rng, |p| p.z + GROUND_OFFSET),
        ViewpointClass::Low => uniform_points(tin, n, &mut rng, |p| p.z + LOW_OFFSET),
        ViewpointClass::High => uniform_points(tin, n, &mut rng, |p| p.z + HIGH_OFFSET),
        ViewpointClass::Sky => {
            let b = tin.bbox();
            let z = b.max.z + SKY_FRACTION * (b.max.z - b.min.z);
            uniform_points(tin, n, &mut rng, |_| z)
        }
        ViewpointClass::Valley => extremum_points(tin, n, &mut rng, Extremum::Minimum),
        ViewpointClass::Ridge => extremum_points(tin, n, &mut rng, Extremum::Maximum),
        ViewpointClass::Path => Vec::new(),
    }
}

/// `n` points uniform over the footprint, with height `z(ground point)`; the same for any order of the TIN's
/// triangles and of their corners (see the module documentation).
fn uniform_points(tin: &Tin, n: usize, rng: &mut ChaCha8Rng, z: impl Fn(DVec3) -> f64) -> Vec<DVec3> {
    let triangles = canonical_triangles(tin);
    let mut cumulative = Vec::with_capacity(triangles.len());
    let mut total = 0.0;
    for [a, b, c] in &triangles {
        total += 0.5 * tin::orient2d(a.truncate(), b.truncate(), c.truncate()).abs();
        cumulative.push(total);
    }
    (0..n)
        .map(|_| {
            let u = rng.random::<f64>() * total;
            let t = cumulative.partition_point(|&c| c <= u).min(triangles.len() - 1);
            let (mut r1, mut r2) = (rng.random::<f64>(), rng.random::<f64>());
            if r1 + r2 > 1.0 {
                (r1, r2) = (1.0 - r1, 1.0 - r2);
            }
            let [a, b, c] = triangles[t];
            let ground = a + r1 * (b - a) + r2 * (c - a);
            DVec3::new(ground.x, ground.y, z(ground))
        })
        .collect()
}

/// The TIN's triangles as corner positions, each rotated (its winding kept) to start at its least corner, sorted:
/// corners compared by x, then y, then z (`total_cmp`), triangles by their first corner, then second, then third.
/// Two triangles of a valid TIN never compare equal, so the order depends on the triangles alone.
fn canonical_triangles(tin: &Tin) -> Vec<[DVec3; 3]> {
    let cmp = |p: &DVec3, q: &DVec3| p.x.total_cmp(&q.x).then(p.y.total_cmp(&q.y)).then(p.z.total_cmp(&q.z));
    let mut triangles: Vec<[DVec3; 3]> = (0..tin.num_triangles())
        .map(|t| {
            let mut c = tin.corners(t);
            let least = (0..3).min_by(|&i, &j| cmp(&c[i], &c[j])).unwrap_or(0);
            c.rotate_left(least);
            c
        })
        .collect();
    triangles.sort_by(|s, t| cmp(&s[0], &t[0]).then(cmp(&s[1], &t[1])).then(cmp(&s[2], &t[2])));
    triangles
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Extremum {
    Minimum,
    Maximum,
}

/// Interior vertices strictly lower (`Minimum`) or higher (`Maximum`) than all their neighbours, in index order.
fn local_extrema(tin: &Tin, kind: Extremum) -> Vec<u32> {
    let nv = tin.num_vertices();
    let mut on_boundary = vec![false; nv];
    let used = used_vertices(tin);
    // better[v]: some neighbour is at least as low (high) as v.
    let mut beaten = vec![false; nv];
    for (t, tri) in tin.triangles().iter().enumerate() {
        for i in 0..3 {
            let (a, b) = (tri[i], tri[(i + 1) % 3]);
            if tin.neighbours()[t][i] == NO_NEIGHBOUR {
                on_boundary[a as usize] = true;
                on_boundary[b as usize] = true;
            }
            let (za, zb) = (tin.position(a).z, tin.position(b).z);
            match kind {
                Extremum::Minimum => {
                    beaten[a as usize] |= zb <= za;
                    beaten[b as usize] |= za <= zb;
                }
                Extremum::Maximum => {
                    beaten[a as usize] |= zb >= za;
                    beaten[b as usize] |= za >= zb;
                }
            }
        }
    }
    (0..nv as u32)
        .filter(|&v| used[v as usize] && !on_boundary[v as usize] && !beaten[v as usize])
        .collect()
}

/// Which vertices belong to at least one triangle.
fn used_vertices(tin: &Tin) -> Vec<bool> {
    let mut used = vec![false; tin.num_vertices()];
    for tri in tin.triangles() {
        for &v in tri {
            used[v as usize] = true;
        }
    }
    used
}

fn extremum_points(tin: &Tin, n: usize, rng: &mut ChaCha8Rng, kind: Extremum) -> Vec<DVec3> {
    let above = |v: u32| tin.position(v) + DVec3::new(0.0, 0.0, EXTREMUM_OFFSET);
    let mut candidates = local_extrema(tin, kind);
    if candidates.is_empty() {
        // Fallback: the lowest (highest) vertices of the mesh, ties by index.
        let used = used_vertices(tin);
        let mut all: Vec<u32> = (0..tin.num_vertices() as u32).filter(|&v| used[v as usize]).collect();
        all.sort_by(|&a, &b| {
            let (za, zb) = (tin.position(a).z, tin.position(b).z);
            let o = if kind == Extremum::Minimum {
                za.total_cmp(&zb)
            } else {
                zb.total_cmp(&za)
            };
            o.then(a.cmp(&b))
        });
        return (0..n).map(|i| above(all[i % all.len()])).collect();
    }
    // Partial Fisher-Yates shuffle for the first min(n, len) picks, then picks with replacement.
    let len = candidates.len();
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        if i < len {
            let j = rng.random_range(i..len);
            candidates.swap(i, j);
            out.push(above(candidates[i]));
        } else {
            out.push(above(candidates[rng.random_range(0..len)]));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Locator;
    use tin::{DedupePolicy, triangulate};

    fn bumpy(n: usize) -> Tin {
        let pts: Vec<DVec3> = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f64 * 10.0, (i / n) as f64 * 10.0);
                DVec3::new(x, y, 30.0 * (x / 37.0).sin() * (y / 23.0).cos() + 0.01 * x)
            })
            .collect();
        triangulate(&pts, DedupePolicy::Reject).expect("grid").0
    }

    /// Builds of one mesh store its triangles in other orders (and may rotate their corners): the eyes of every
    /// class stay the same.
    #[test]
    fn eyes_do_not_depend_on_the_triangle_order() {
        let tin = bumpy(12);
        let mut triangles = tin.triangles().to_vec();
        triangles.reverse();
        for (i, t) in triangles.iter_mut().enumerate() {
            t.rotate_left(i % 3);
        }
        let shuffled = Tin::from_parts(tin.positions().to_vec(), triangles).expect("same triangles");
        for class in ViewpointClass::ALL {
            assert_eq!(
                viewpoints(&tin, class, 30, 5),
                viewpoints(&shuffled, class, 30, 5),
                "{class}"
            );
        }
    }

    #[test]
    fn names_round_trip() {
        for c in ViewpointClass::ALL {
            assert_eq!(c.to_string().parse::<ViewpointClass>(), Ok(c));
            assert_eq!(serde_json::to_string(&c).expect("json"), format!("\"{c}\""));
        }
        assert_eq!(
            "Ground".parse::<ViewpointClass>(),
            Err(TruthError::UnknownClass("Ground".into()))
        );
        // Blanks around a name, as in `--classes "ground, low"`.
        assert_eq!(" low ".parse::<ViewpointClass>(), Ok(ViewpointClass::Low));
    }

    #[test]
    fn heights_and_footprint() {
        let tin = bumpy(20);
        let loc = Locator::new(&tin);
        let b = tin.bbox();
        for class in ViewpointClass::ALL {
            let pts = viewpoints(&tin, class, 25, 7);
            assert_eq!(pts.len(), 25);
            assert_eq!(pts, viewpoints(&tin, class, 25, 7), "{class} is deterministic");
            assert_ne!(pts, viewpoints(&tin, class, 25, 8), "{class} depends on the seed");
            for p in &pts {
                let ground = loc.ground_height(&tin, p.truncate()).expect("inside the footprint");
                let above = p.z - ground;
                match class {
                    ViewpointClass::Ground | ViewpointClass::Valley | ViewpointClass::Ridge => {
                        assert!((above - 2.0).abs() < 1e-9, "{class}: {above}")
                    }
                    ViewpointClass::Low => assert!((above - 20.0).abs() < 1e-9),
                    ViewpointClass::High => assert!((above - 200.0).abs() < 1e-9),
                    ViewpointClass::Sky => {
                        assert!((p.z - (b.max.z + 0.1 * (b.max.z - b.min.z))).abs() < 1e-9)
                    }
                    ViewpointClass::Path => unreachable!("not in ALL"),
                }
            }
        }
    }

    #[test]
    fn extrema_are_strict_and_interior() {
        let tin = bumpy(20);
        let vt = tin.vertex_triangles();
        for (kind, class) in [
            (Extremum::Minimum, ViewpointClass::Valley),
            (Extremum::Maximum, ViewpointClass::Ridge),
        ] {
            let ext = local_extrema(&tin, kind);
            assert!(!ext.is_empty());
            for &v in &ext {
                let z = tin.position(v).z;
                for &t in vt.of(v) {
                    for w in tin.triangles()[t as usize] {
                        if w != v {
                            let zw = tin.position(w).z;
                            assert!(if kind == Extremum::Minimum { zw > z } else { zw < z });
                        }
                    }
                }
            }
            // Without replacement while candidates last.
            let pts = viewpoints(&tin, class, ext.len(), 3);
            let mut xy: Vec<(u64, u64)> = pts.iter().map(|p| (p.x.to_bits(), p.y.to_bits())).collect();
            xy.sort_unstable();
            xy.dedup();
            assert_eq!(xy.len(), ext.len());
        }
    }

    proptest::proptest! {
        /// On random TINs, some with triangles removed (holes, non-convex footprints), every viewpoint stands over
        /// the footprint at its class's height.
        #[test]
        fn viewpoints_stand_over_the_footprint(
            pts in proptest::collection::vec((0.0f64..100.0, 0.0f64..100.0, 0.0f64..30.0), 3..40),
            drop_every in 0usize..4,
            seed in 0u64..1000,
        ) {
            let points: Vec<DVec3> = pts.iter().map(|&(x, y, z)| DVec3::new(x, y, z)).collect();
            let Ok((tin, _)) = triangulate(&points, DedupePolicy::KeepHighest) else { return Ok(()) };
            let tin = if drop_every > 1 && tin.num_triangles() > drop_every {
                let keep: Vec<[u32; 3]> = tin.triangles().iter().enumerate()
                    .filter(|(t, _)| t % drop_every != 0).map(|(_, &tri)| tri).collect();
                Tin::from_parts(tin.positions().to_vec(), keep).expect("subset of a valid TIN")
            } else {
                tin
            };
            let loc = Locator::new(&tin);
            let b = tin.bbox();
            for class in ViewpointClass::ALL {
                let pts = viewpoints(&tin, class, 5, seed);
                proptest::prop_assert_eq!(pts.len(), 5);
                for p in pts {
                    let ground = loc.ground_height(&tin, p.truncate());
                    proptest::prop_assert!(ground.is_some(), "{} viewpoint {} off the footprint", class, p);
                    let above = p.z - ground.unwrap_or(f64::NAN);
                    let expected = match class {
                        ViewpointClass::Ground | ViewpointClass::Valley | ViewpointClass::Ridge => Some(2.0),
                        ViewpointClass::Low => Some(20.0),
                        ViewpointClass::High => Some(200.0),
                        ViewpointClass::Sky | ViewpointClass::Path => None,
                    };
                    match expected {
                        Some(h) => proptest::prop_assert!((above - h).abs() < 1e-9, "{} at {} m", class, above),
                        None => proptest::prop_assert_eq!(p.z, b.max.z + 0.1 * (b.max.z - b.min.z)),
                    }
                }
            }
        }
    }

    #[test]
    fn plane_falls_back_to_lowest_and_highest() {
        // A tilted plane has no interior extrema.
        let pts: Vec<DVec3> = (0..25)
            .map(|i| DVec3::new((i % 5) as f64, (i / 5) as f64, (i % 5) as f64 + 10.0 * (i / 5) as f64))
            .collect();
        let (tin, _) = triangulate(&pts, DedupePolicy::Reject).expect("grid");
        let v = viewpoints(&tin, ViewpointClass::Valley, 2, 1);
        assert_eq!(v, vec![DVec3::new(0.0, 0.0, 2.0), DVec3::new(1.0, 0.0, 3.0)]);
        let r = viewpoints(&tin, ViewpointClass::Ridge, 1, 1);
        assert_eq!(r, vec![DVec3::new(4.0, 4.0, 46.0)]);
    }
}
