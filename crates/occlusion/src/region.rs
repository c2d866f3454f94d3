//! Occlusion regions in a sector plane (thesis 4.6; the definitions below).
//!
//! Everything about sector `i` lives in its vertical plane, with coordinates `(t, z)` where `t = r_i · (xy − o)` is the
//! position along the sector's centre direction, relative to a fixed origin `o` shared by all regions that are
//! intersected or tested together (see [`crate::RegionTable`]; [`Region`] itself only sees `t`). The region of a vertex
//! `p` in sector `i` is the set of camera positions `c` with `t_c ≥ t0` and `z_c ≤ z_p + m·(t_c − t_p)`: a wedge
//! bounded on the left by `t0 = t_p + d` and above by the line through `p` with the sector's minimum horizon slope `m`.
//! Intersections of such wedges (the regions of triangles and groups) are convex: a left bound and a concave,
//! piecewise-linear upper boundary that ends in a ray. [`Region`] stores that boundary as a short vertex chain.
//!
//! Choices where the thesis is vague:
//! - The region is unbounded to the right (`t → ∞`) and below (`z → −∞`), so the intersection of two non-empty
//!   regions is never empty; a region is empty only because some vertex has no horizon in the sector, which callers
//!   represent as `Option<Region>::None`.
//! - Containment is strict: a camera exactly on the boundary is outside, i.e. it sees the element (grazing view).
//!   This is the conservative tie rule; a closed definition would differ only on the boundary itself.

use glam::DVec2;
use smallvec::SmallVec;

/// Chain storage: a vertex region has one vertex and lives inline without allocation; longer chains (triangles,
/// groups) go to the heap. One inline vertex keeps `Option<Region>` at 40 bytes, which matters for the vertex
/// region table (one entry per vertex and sector, read at random during crystal growth).
pub type Chain = SmallVec<[DVec2; 1]>;

/// A non-empty convex occlusion region in one sector plane.
///
/// Its upper boundary passes through `points` (`x` = t, `y` = z, `t` strictly increasing, the first point on the left
/// bound) and continues beyond the last point as a ray of slope `tail_slope`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Region {
    points: Chain,
    tail_slope: f64,
}

impl Region {
    /// The region of one vertex at `(t_p, z_p)` whose sector horizon has minimum slope `slope` and lies up to
    /// `distance` ahead along the sector direction: `t ≥ t_p + distance`, `z ≤ z_p + slope·(t − t_p)`.
    pub fn of_vertex(t_p: f64, z_p: f64, slope: f64, distance: f64) -> Region {
        let t0 = t_p + distance;
        let mut points = Chain::new();
        points.push(DVec2::new(t0, z_p + slope * distance));
        Region {
            points,
            tail_slope: slope,
        }
    }

    /// Builds a region from a boundary chain, or `None` when the chain is not valid (empty, non-finite, or `t` not
    /// strictly increasing). Concavity is not required.
    pub fn from_chain(points: Vec<DVec2>, tail_slope: f64) -> Option<Region> {
        let valid = !points.is_empty()
            && tail_slope.is_finite()
            && points.iter().all(|p| p.is_finite())
            && points.windows(2).all(|w| w[0].x < w[1].x);
        valid.then(|| Region {
            points: Chain::from_vec(points),
            tail_slope,
        })
    }

    /// The boundary chain's vertices `(t, z)`; the first one lies on the left bound.
    pub fn points(&self) -> &[DVec2] {
        &self.points
    }

    /// Slope of the ray that continues the boundary beyond the last vertex.
    pub fn tail_slope(&self) -> f64 {
        self.tail_slope
    }

    /// The left bound `t0`.
    pub fn t0(&self) -> f64 {
        self.points[0].x
    }

    /// Height of the upper boundary at `t` (for `t` before the left bound, the first segment is extended).
    pub fn height_at(&self, t: f64) -> f64 {
        let pts = &self.points;
        // Index of the last vertex with x ≤ t (0 when t is before every vertex).
        let i = pts.partition_point(|p| p.x <= t).saturating_sub(1);
        if i + 1 < pts.len() {
            let (a, b) = (pts[i], pts[i + 1]);
            a.y + (b.y - a.y) * ((t - a.x) / (b.x - a.x))
        } else {
            let a = pts[i];
            a.y + self.tail_slope * (t - a.x)
        }
    }

    /// Whether the camera at plane coordinates `(t, z)` is strictly inside the region (the element is hidden).
    /// Points on the boundary are outside.
    pub fn contains(&self, t: f64, z: f64) -> bool {
        t > self.t0() && z < self.height_at(t)
    }

    /// The intersection of two regions: left bound the larger one, upper boundary the lower envelope.
    /// A linear merge: both chains are walked once, in increasing `t`.
    pub fn intersect(&self, other: &Region) -> Region {
        let (a, b) = (&self.points[..], &other.points[..]);
        let t0 = self.t0().max(other.t0());
        let (mut wa, mut wb) = (Walker::new(a, self.tail_slope), Walker::new(b, other.tail_slope));
        let (mut ia, mut ib) = (a.partition_point(|p| p.x <= t0), b.partition_point(|p| p.x <= t0));
        let mut points = Chain::new();
        let (mut tp, mut hap, mut hbp) = (t0, wa.at(t0), wb.at(t0));
        points.push(DVec2::new(t0, hap.min(hbp)));
        loop {
            // The next event: the smaller of the two chains' next vertices.
            let t = match (a.get(ia), b.get(ib)) {
                (None, None) => break,
                (Some(p), None) => p.x,
                (None, Some(q)) => q.x,
                (Some(p), Some(q)) => p.x.min(q.x),
            };
            while a.get(ia).is_some_and(|p| p.x <= t) {
                ia += 1;
            }
            while b.get(ib).is_some_and(|q| q.x <= t) {
                ib += 1;
            }
            let (ha, hb) = (wa.at(t), wb.at(t));
            // Between two events both boundaries are linear, so they cross at most once.
            let (dp, dc) = (hap - hbp, ha - hb);
            if (dp < 0.0 && dc > 0.0) || (dp > 0.0 && dc < 0.0) {
                let f = dp / (dp - dc);
                let tx = tp + (t - tp) * f;
                if tx > tp && tx < t {
                    points.push(DVec2::new(tx, hap + (ha - hap) * f));
                }
            }
            points.push(DVec2::new(t, ha.min(hb)));
            (tp, hap, hbp) = (t, ha, hb);
        }
        // Beyond the last event both boundaries are rays; they may cross once more.
        let (d, dm) = (hap - hbp, self.tail_slope - other.tail_slope);
        if (d < 0.0 && dm > 0.0) || (d > 0.0 && dm < 0.0) {
            let tx = tp - d / dm;
            if tx > tp && tx.is_finite() {
                points.push(DVec2::new(tx, hap + self.tail_slope * (tx - tp)));
            }
        }
        let mut region = Region {
            points,
            tail_slope: self.tail_slope.min(other.tail_slope),
        };
        region.drop_collinear();
        region
    }

    /// Removes chain vertices whose incoming and outgoing slopes agree (within rounding).
    fn drop_collinear(&mut self) {
        if self.points.len() < 2 {
            return;
        }
        let mut kept = Chain::new();
        for (k, &p) in self.points.iter().enumerate() {
            if let Some(&prev) = kept.last() {
                let slope_in = (p.y - prev.y) / (p.x - prev.x);
                let slope_out = match self.points.get(k + 1) {
                    Some(&next) => (next.y - p.y) / (next.x - p.x),
                    None => self.tail_slope,
                };
                let scale = slope_in.abs().max(slope_out.abs()).max(f64::MIN_POSITIVE);
                if (slope_in - slope_out).abs() <= 1e-12 * scale {
                    continue;
                }
            }
            kept.push(p);
        }
        self.points = kept;
    }

    /// A region with at most `max_points` chain vertices (at least 1) that is contained in `self`: the region only
    /// shrinks. Vertices are removed greedily, the one whose removal loses the least area first; removing a vertex
    /// replaces its two edges by the chord between its neighbours, which lies below a concave boundary.
    pub fn simplified(&self, max_points: usize) -> Region {
        let max_points = max_points.max(1);
        let mut pts = self.points.clone();
        while pts.len() > max_points {
            // Interior vertices (not the first, not the last) cost the triangle area they cut off.
            let best = (1..pts.len().saturating_sub(1))
                .map(|i| {
                    let (a, b, c) = (pts[i - 1], pts[i], pts[i + 1]);
                    let twice_area = (b - a).perp_dot(c - a); // < 0 when b is above the chord (concave).
                    (i, -twice_area)
                })
                .filter(|&(_, area)| area >= 0.0)
                .min_by(|x, y| x.1.total_cmp(&y.1));
            match best {
                Some((i, _)) => {
                    pts.remove(i);
                }
                None => {
                    // Only the last vertex is left to remove: continue from the one before with the tail slope, which
                    // is the smallest slope of a concave chain, so the new boundary stays below the old one.
                    let n = pts.len();
                    let (a, b) = (pts[n - 2], pts[n - 1]);
                    let slope_ab = (b.y - a.y) / (b.x - a.x);
                    if slope_ab < self.tail_slope {
                        break; // Not concave here: removing would enlarge the region.
                    }
                    pts.pop();
                }
            }
        }
        Region {
            points: pts,
            tail_slope: self.tail_slope,
        }
    }
}

/// Evaluates a chain's boundary at increasing `t`, advancing a cursor instead of searching.
struct Walker<'a> {
    points: &'a [DVec2],
    tail_slope: f64,
    i: usize,
}

impl<'a> Walker<'a> {
    fn new(points: &'a [DVec2], tail_slope: f64) -> Self {
        Walker {
            points,
            tail_slope,
            i: 0,
        }
    }

    /// The boundary's height at `t`, which must not be smaller than at the previous call.
    fn at(&mut self, t: f64) -> f64 {
        let pts = self.points;
        while self.i + 1 < pts.len() && pts[self.i + 1].x <= t {
            self.i += 1;
        }
        let p = pts[self.i];
        match pts.get(self.i + 1) {
            Some(q) => p.y + (q.y - p.y) * ((t - p.x) / (q.x - p.x)),
            None => p.y + self.tail_slope * (t - p.x),
        }
    }
}

/// Intersects a sequence of regions of one sector; any `None` (empty) makes the result empty, and so does an empty
/// sequence.
pub fn intersect_all<'a>(regions: impl IntoIterator<Item = Option<&'a Region>>) -> Option<Region> {
    let mut it = regions.into_iter();
    let mut acc = it.next()??.clone();
    for r in it {
        acc = acc.intersect(r?);
    }
    Some(acc)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn vertex_region() -> impl Strategy<Value = Region> {
        (-100.0f64..100.0, -50.0f64..50.0, -2.0f64..2.0, 0.0f64..60.0)
            .prop_map(|(t, z, m, d)| Region::of_vertex(t, z, m, d))
    }

    fn region() -> impl Strategy<Value = Region> {
        prop::collection::vec(vertex_region(), 1..6)
            .prop_map(|rs| intersect_all(rs.iter().map(Some)).expect("non-empty"))
    }

    /// Membership by the definition: inside every vertex wedge.
    fn in_all(rs: &[Region], t: f64, z: f64) -> bool {
        rs.iter().all(|r| r.contains(t, z))
    }

    #[test]
    fn vertex_regions_are_small() {
        assert!(std::mem::size_of::<Option<Region>>() <= 40);
    }

    #[test]
    fn vertex_region_is_a_wedge() {
        let r = Region::of_vertex(10.0, 5.0, 0.5, 4.0);
        assert_eq!(r.t0(), 14.0);
        assert!(r.contains(20.0, 7.0)); // line at t=20: 5 + 0.5*10 = 10
        assert!(!r.contains(20.0, 10.0)); // on the boundary: outside
        assert!(!r.contains(14.0, -100.0)); // on the left bound: outside
        assert!(!r.contains(13.0, -100.0));
    }

    #[test]
    fn intersection_of_crossing_lines_has_a_kink() {
        let a = Region::of_vertex(0.0, 0.0, 1.0, 1.0); // z <= t, t >= 1
        let b = Region::of_vertex(0.0, 5.0, 0.0, 2.0); // z <= 5, t >= 2
        let r = a.intersect(&b);
        assert_eq!(r.points(), &[DVec2::new(2.0, 2.0), DVec2::new(5.0, 5.0)]);
        assert_eq!(r.tail_slope(), 0.0);
    }

    proptest! {
        #[test]
        fn intersection_matches_point_sampling(rs in prop::collection::vec(vertex_region(), 1..7),
                                               samples in prop::collection::vec((-150.0f64..250.0, -200.0f64..200.0), 200)) {
            let r = intersect_all(rs.iter().map(Some)).expect("non-empty");
            for (t, z) in samples {
                // Skip samples within rounding distance of a boundary, where either answer is right.
                let margin = rs.iter().map(|v| (v.height_at(t) - z).abs().min((t - v.t0()).abs())).fold(f64::INFINITY, f64::min);
                if margin < 1e-9 { continue; }
                prop_assert_eq!(r.contains(t, z), in_all(&rs, t, z), "t={} z={}", t, z);
            }
        }

        #[test]
        fn intersection_is_commutative_and_shrinks(a in region(), b in region(),
                                                   samples in prop::collection::vec((-150.0f64..250.0, -200.0f64..200.0), 100)) {
            let ab = a.intersect(&b);
            let ba = b.intersect(&a);
            for (t, z) in samples {
                let h = ab.height_at(t);
                prop_assert!((h - ba.height_at(t)).abs() <= 1e-9 * (1.0 + h.abs()));
                // Containment is monotone: inside the intersection implies inside both.
                if ab.contains(t, z) {
                    prop_assert!(a.contains(t, z) || (a.height_at(t) - z).abs() < 1e-9);
                    prop_assert!(b.contains(t, z) || (b.height_at(t) - z).abs() < 1e-9);
                }
            }
            prop_assert!(ab.points().windows(2).all(|w| w[0].x < w[1].x));
        }

        #[test]
        fn simplification_only_shrinks(r in region(), m in 1usize..4,
                                       samples in prop::collection::vec((-150.0f64..250.0, -200.0f64..200.0), 200)) {
            let s = r.simplified(m);
            prop_assert!(s.points().len() <= m, "{} points left, {} allowed", s.points().len(), m);
            prop_assert_eq!(s.t0(), r.t0());
            for (t, z) in samples {
                if s.contains(t, z) {
                    prop_assert!(r.height_at(t) >= z - 1e-9 * (1.0 + z.abs()), "simplified region grew at t={}", t);
                }
            }
        }
    }
}
