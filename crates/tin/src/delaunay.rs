//! Delaunay construction of a [`Tin`] from scattered points, with spade's bulk loader.
//!
//! Duplicate x,y positions are resolved here, before spade sees them (spade would merge them silently):
//! equal heights are merged and counted; different heights are an error unless [`DedupePolicy::KeepHighest`].

use glam::DVec3;
use rayon::prelude::*;
use spade::{DelaunayTriangulation, Point2, Triangulation};

use crate::error::{Result, TinError};
use crate::mesh::Tin;

/// What to do with input points that share x and y but differ in z.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum DedupePolicy {
    /// Reject the input with an error naming both points (the default: such input is not a height field).
    #[default]
    Reject,
    /// Keep the highest of the points at each x,y.
    KeepHighest,
}

/// What Delaunay construction did to its input.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DelaunayReport {
    /// Points dropped because an earlier point had the same x, y and z.
    pub merged_duplicates: usize,
    /// Points dropped under [`DedupePolicy::KeepHighest`] because another point at the same x,y was higher.
    pub dropped_lower: usize,
    /// For each vertex of the TIN, the index of the input point it came from.
    pub input_index: Vec<usize>,
}

/// Delaunay-triangulates `points` (x, y positions with heights) into a [`Tin`].
///
/// Vertex order follows input order, with dropped duplicates removed (see [`DelaunayReport::input_index`]).
pub fn triangulate(points: &[DVec3], policy: DedupePolicy) -> Result<(Tin, DelaunayReport)> {
    for (index, p) in points.iter().enumerate() {
        if !p.is_finite() {
            return Err(TinError::NonFinite {
                index,
                x: p.x,
                y: p.y,
                z: p.z,
            });
        }
    }
    let (keep, report) = dedupe(points, policy)?;
    if keep.len() < 3 {
        return Err(TinError::TooFewPoints(format!(
            "{} distinct points, at least 3 are needed",
            keep.len()
        )));
    }
    // Insert in Morton (Z-curve) order of the points' positions: spatially coherent, so each point location starts
    // near the previous one, and deterministic. (spade's bulk loader re-inserts skipped points from a HashSet whose
    // order changes from process to process, which can change the triangulation of cocircular points.)
    let order = morton_order(points, &keep);
    // The points in insertion order, gathered beforehand (in parallel) so that the insertion loop reads them in order.
    let ordered: Vec<Point2<f64>> = order
        .par_iter()
        .map(|&k| {
            let p = points[keep[k]];
            Point2::new(p.x, p.y)
        })
        .collect();
    let mut dt = DelaunayTriangulation::<Point2<f64>>::with_capacity(keep.len(), keep.len() * 3, keep.len() * 2);
    // `vertex_of_slot[k]` is the position in `keep` of the k-th vertex spade created.
    let mut vertex_of_slot = Vec::with_capacity(keep.len());
    for (&k, &p) in order.iter().zip(&ordered) {
        let handle = dt.insert(p).map_err(|e| TinError::Insertion {
            index: keep[k],
            reason: e.to_string(),
        })?;
        if handle.index() != vertex_of_slot.len() {
            // Exact duplicates were removed above, so this only happens if spade considers two distinct points equal.
            return Err(TinError::TooFewPoints(format!(
                "the triangulator merged input points {} and {}, which differ only below its precision",
                keep[vertex_of_slot[handle.index()] as usize],
                keep[k]
            )));
        }
        vertex_of_slot.push(k as u32);
    }
    drop((order, ordered));
    let triangles: Vec<[u32; 3]> = dt
        .inner_faces()
        .map(|f| f.vertices().map(|v| vertex_of_slot[v.fix().index()]))
        .collect();
    // Memory is freed as soon as it is no longer needed, to keep the peak down.
    drop(dt);
    if triangles.is_empty() {
        return Err(TinError::TooFewPoints("all points are collinear".into()));
    }
    let positions: Vec<DVec3> = keep.iter().map(|&i| points[i]).collect();
    let tin = Tin::from_parts(positions, triangles)?;
    Ok((
        tin,
        DelaunayReport {
            input_index: keep,
            ..report
        },
    ))
}

/// Positions in `keep` sorted along a Morton curve over the points' bounding box (ties by position in `keep`).
fn morton_order(points: &[DVec3], keep: &[usize]) -> Vec<usize> {
    let (mut lo, mut hi) = (glam::DVec2::splat(f64::INFINITY), glam::DVec2::splat(f64::NEG_INFINITY));
    for &i in keep {
        lo = lo.min(points[i].truncate());
        hi = hi.max(points[i].truncate());
    }
    let scale = (hi - lo).max(glam::DVec2::splat(f64::MIN_POSITIVE));
    let spread = |v: u32| {
        let mut x = u64::from(v);
        x = (x | (x << 16)) & 0x0000_ffff_0000_ffff;
        x = (x | (x << 8)) & 0x00ff_00ff_00ff_00ff;
        x = (x | (x << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
        x = (x | (x << 2)) & 0x3333_3333_3333_3333;
        (x | (x << 1)) & 0x5555_5555_5555_5555
    };
    let key = |i: usize| {
        let q = (points[i].truncate() - lo) / scale * f64::from(u32::MAX);
        spread(q.x as u32) | (spread(q.y as u32) << 1)
    };
    let mut order: Vec<usize> = (0..keep.len()).collect();
    // The keys are distinct (ties broken by position), so the parallel sort's order is the only sorted one.
    order.par_sort_by_cached_key(|&k| (key(keep[k]), k));
    order
}

/// Returns the input indices to keep, in input order, and the counts of what was dropped.
fn dedupe(points: &[DVec3], policy: DedupePolicy) -> Result<(Vec<usize>, DelaunayReport)> {
    let key = |p: &DVec3| ((p.x + 0.0).to_bits(), (p.y + 0.0).to_bits()); // + 0.0 folds -0.0 into 0.0
    let mut order: Vec<usize> = (0..points.len()).collect();
    // The keys are distinct (ties broken by index), so the parallel sort's order is the only sorted one.
    order.par_sort_unstable_by_key(|&i| (key(&points[i]), i));
    let mut drop = vec![false; points.len()];
    let mut report = DelaunayReport::default();
    let mut start = 0;
    while start < order.len() {
        let mut end = start + 1;
        while end < order.len() && key(&points[order[end]]) == key(&points[order[start]]) {
            end += 1;
        }
        let group = &order[start..end];
        if group.len() > 1 {
            let best = *group
                .iter()
                .max_by(|&&a, &&b| points[a].z.total_cmp(&points[b].z).then(b.cmp(&a)))
                .unwrap_or(&group[0]);
            for &i in group {
                if i == best {
                    continue;
                }
                if points[i].z == points[best].z {
                    report.merged_duplicates += 1;
                } else if policy == DedupePolicy::Reject {
                    let (first, second) = (
                        group[0],
                        *group.iter().find(|&&j| points[j].z != points[group[0]].z).unwrap_or(&i),
                    );
                    return Err(TinError::DuplicateXy {
                        first,
                        second,
                        x: points[first].x,
                        y: points[first].y,
                        z_first: points[first].z,
                        z_second: points[second].z,
                    });
                } else {
                    report.dropped_lower += 1;
                }
                drop[i] = true;
            }
        }
        start = end;
    }
    let keep = (0..points.len()).filter(|&i| !drop[i]).collect();
    Ok((keep, report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::predicates::orient2d;
    use proptest::prelude::*;

    fn in_circumcircle(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
        // > 0 when d is strictly inside the circumcircle of CCW abc.
        let (ax, ay) = (a.x - d.x, a.y - d.y);
        let (bx, by) = (b.x - d.x, b.y - d.y);
        let (cx, cy) = (c.x - d.x, c.y - d.y);
        (ax * ax + ay * ay) * (bx * cy - cx * by) - (bx * bx + by * by) * (ax * cy - cx * ay)
            + (cx * cx + cy * cy) * (ax * by - bx * ay)
    }

    fn assert_delaunay(tin: &Tin) {
        let scale = tin.bbox().size().truncate().length().max(1.0);
        for (t, tri) in tin.triangles().iter().enumerate() {
            let [a, b, c] = tin.corners(t);
            assert!(
                orient2d(a.truncate(), b.truncate(), c.truncate()) > 0.0,
                "triangle {t} not CCW"
            );
            for (v, &p) in tin.positions().iter().enumerate() {
                if tri.contains(&(v as u32)) {
                    continue;
                }
                let s = in_circumcircle(a, b, c, p);
                assert!(
                    s <= 1e-9 * scale.powi(4),
                    "vertex {v} inside circumcircle of triangle {t}: {s}"
                );
            }
        }
    }

    fn euler_ok(tin: &Tin) {
        // Planar triangulation of a point set: T = 2n - 2 - h, with h hull vertices.
        let boundary_edges = tin
            .neighbours()
            .iter()
            .flatten()
            .filter(|&&n| n == crate::NO_NEIGHBOUR)
            .count();
        assert_eq!(tin.num_triangles(), 2 * tin.num_vertices() - 2 - boundary_edges);
    }

    proptest! {
        #[test]
        fn random_points_are_delaunay(pts in prop::collection::vec((0.0f64..1000.0, 0.0f64..1000.0, 0.0f64..100.0), 3..120)) {
            let points: Vec<DVec3> = pts.iter().map(|&(x, y, z)| DVec3::new(x, y, z)).collect();
            match triangulate(&points, DedupePolicy::KeepHighest) {
                Ok((tin, _)) => { assert_delaunay(&tin); euler_ok(&tin); }
                Err(TinError::TooFewPoints(_)) => {}
                Err(e) => panic!("unexpected error {e}"),
            }
        }

        #[test]
        fn integer_grids_are_delaunay(w in 2usize..12, h in 2usize..12, z in prop::collection::vec(0.0f64..5.0, 144)) {
            // Cocircular and collinear points everywhere.
            let points: Vec<DVec3> = (0..w * h).map(|i| DVec3::new((i % w) as f64, (i / w) as f64, z[i])).collect();
            let (tin, report) = triangulate(&points, DedupePolicy::Reject).expect("grid triangulates");
            prop_assert_eq!(tin.num_vertices(), w * h);
            prop_assert_eq!(report.input_index.len(), w * h);
            prop_assert_eq!(tin.num_triangles(), 2 * (w - 1) * (h - 1));
            assert_delaunay(&tin);
        }
    }

    #[test]
    fn duplicates_with_equal_height_are_merged() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::X, DVec3::new(1.0, 1.0, 0.0)];
        let (tin, report) = triangulate(&p, DedupePolicy::Reject).expect("valid");
        assert_eq!(tin.num_vertices(), 4);
        assert_eq!(report.merged_duplicates, 1);
        assert_eq!(report.input_index, vec![0, 1, 2, 4]);
    }

    #[test]
    fn duplicates_with_different_height_are_named() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 0.0, 5.0)];
        match triangulate(&p, DedupePolicy::Reject) {
            Err(TinError::DuplicateXy {
                first: 1, second: 3, ..
            }) => {}
            other => panic!("expected DuplicateXy, got {other:?}"),
        }
        let (tin, report) = triangulate(&p, DedupePolicy::KeepHighest).expect("valid");
        assert_eq!(report.dropped_lower, 1);
        assert_eq!(report.input_index, vec![0, 2, 3]);
        assert_eq!(tin.position(2).z, 5.0);
    }

    #[test]
    fn collinear_and_tiny_inputs_are_errors() {
        let line: Vec<DVec3> = (0..10).map(|i| DVec3::new(i as f64, 2.0 * i as f64, 0.0)).collect();
        assert!(matches!(
            triangulate(&line, DedupePolicy::Reject),
            Err(TinError::TooFewPoints(_))
        ));
        assert!(matches!(
            triangulate(&line[..2], DedupePolicy::Reject),
            Err(TinError::TooFewPoints(_))
        ));
        let nan = vec![DVec3::ZERO, DVec3::X, DVec3::new(0.0, f64::NAN, 0.0)];
        assert!(matches!(
            triangulate(&nan, DedupePolicy::Reject),
            Err(TinError::NonFinite { index: 2, .. })
        ));
    }

    #[test]
    fn huge_coordinates_are_rejected_not_panicking() {
        let p = vec![DVec3::ZERO, DVec3::new(1e300, 0.0, 0.0), DVec3::Y];
        assert!(matches!(
            triangulate(&p, DedupePolicy::Reject),
            Err(TinError::Insertion { index: 1, .. })
        ));
    }
}
