//! Culling accuracy metrics (design notes, "Measuring accuracy": every report uses these names).
//!
//! For one viewpoint: `A` all triangles, `V` visible (ground truth, [`crate::visible_triangles`]), `D` drawn,
//! `C = A \ D` culled, `H = A \ V` hidden.
//!
//! | metric | definition |
//! | --- | --- |
//! | `false_culls` | `|C ∩ V|` (count), and `false_cull_area`: their summed 3-D area (m²) |
//! | `occlusion_captured` | `|C ∩ H| / |H|`; `None` when `|H| = 0` (nothing to capture) |
//! | `overdraw` | `|D| / |V|`; `None` when `|V| = 0` |
//! | `triangles_drawn` | `|D|` |
//!
//! Choices: undefined ratios are `None` rather than 1.0 or NaN, and aggregation ([`summarize`]) runs over the
//! viewpoints where they are defined (`Stat::count` says how many). Percentiles use the nearest-rank rule: the
//! p-th percentile of `N` sorted values is the value of rank `ceil(p/100 · N)` (1-based), so it is always one of
//! the values. Since `V` is a lower bound of the true visible set, `false_culls` is a lower bound too, and
//! `overdraw` an upper bound.

use tin::Tin;

use crate::error::{Result, TruthError};

/// Accuracy of one drawn set from one viewpoint.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ViewMetrics {
    /// `|A|`: all triangles.
    pub triangles: usize,
    /// `|V|`: visible triangles (ground truth).
    pub visible: usize,
    /// `|H|`: hidden triangles.
    pub hidden: usize,
    /// `|D|`: drawn triangles.
    pub triangles_drawn: usize,
    /// `|C|`: culled triangles.
    pub culled: usize,
    /// `|C ∩ V|`: visible triangles that were culled.
    pub false_culls: usize,
    /// Summed 3-D area of the falsely culled triangles (m²).
    pub false_cull_area: f64,
    /// `|C ∩ H|`: hidden triangles that were culled.
    pub culled_hidden: usize,
    /// `|C ∩ H| / |H|`, or `None` when nothing is hidden.
    pub occlusion_captured: Option<f64>,
    /// `|D| / |V|`, or `None` when nothing is visible.
    pub overdraw: Option<f64>,
}

/// Metrics of the drawn set `drawn` against the ground truth `visible` (one flag per triangle of `tin`, in the
/// TIN's order). Fails when either array does not have one entry per triangle.
pub fn view_metrics(tin: &Tin, visible: &[bool], drawn: &[bool]) -> Result<ViewMetrics> {
    let n = tin.num_triangles();
    for (what, len) in [("visible", visible.len()), ("drawn", drawn.len())] {
        if len != n {
            return Err(TruthError::LengthMismatch {
                what,
                expected: n,
                got: len,
            });
        }
    }
    let mut m = ViewMetrics {
        triangles: n,
        visible: 0,
        hidden: 0,
        triangles_drawn: 0,
        culled: 0,
        false_culls: 0,
        false_cull_area: 0.0,
        culled_hidden: 0,
        occlusion_captured: None,
        overdraw: None,
    };
    for (t, (&v, &d)) in visible.iter().zip(drawn).enumerate() {
        m.visible += usize::from(v);
        m.triangles_drawn += usize::from(d);
        if !d {
            if v {
                m.false_culls += 1;
                m.false_cull_area += tin.triangle_area_3d(t);
            } else {
                m.culled_hidden += 1;
            }
        }
    }
    m.hidden = n - m.visible;
    m.culled = n - m.triangles_drawn;
    m.occlusion_captured = (m.hidden > 0).then(|| m.culled_hidden as f64 / m.hidden as f64);
    m.overdraw = (m.visible > 0).then(|| m.triangles_drawn as f64 / m.visible as f64);
    Ok(m)
}

/// Mean, median, 95th percentile and maximum of one metric over the viewpoints where it is defined.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Stat {
    /// Number of values aggregated.
    pub count: usize,
    /// Arithmetic mean.
    pub mean: f64,
    /// Median (nearest rank).
    pub p50: f64,
    /// 95th percentile (nearest rank).
    pub p95: f64,
    /// Largest value.
    pub max: f64,
}

impl Stat {
    /// Statistics of `values`; `None` when empty.
    pub fn of(values: &[f64]) -> Option<Stat> {
        if values.is_empty() {
            return None;
        }
        let mut v = values.to_vec();
        v.sort_by(f64::total_cmp);
        let rank = |p: f64| {
            let r = (p / 100.0 * v.len() as f64).ceil() as usize;
            v[r.clamp(1, v.len()) - 1]
        };
        Some(Stat {
            count: v.len(),
            mean: v.iter().sum::<f64>() / v.len() as f64,
            p50: rank(50.0),
            p95: rank(95.0),
            max: v[v.len() - 1],
        })
    }
}

/// Aggregate of [`ViewMetrics`] over a set of viewpoints. A `None` statistic means no viewpoint defined it.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Summary {
    /// Number of viewpoints.
    pub viewpoints: usize,
    /// Viewpoints with at least one false cull.
    pub viewpoints_with_false_culls: usize,
    /// `false_culls` (counts).
    pub false_culls: Option<Stat>,
    /// `false_cull_area` (m²).
    pub false_cull_area: Option<Stat>,
    /// `occlusion_captured`, over the viewpoints with something hidden.
    pub occlusion_captured: Option<Stat>,
    /// `overdraw`, over the viewpoints with something visible.
    pub overdraw: Option<Stat>,
    /// `triangles_drawn`.
    pub triangles_drawn: Option<Stat>,
}

/// Aggregates per-viewpoint metrics.
pub fn summarize(metrics: &[ViewMetrics]) -> Summary {
    let collect = |f: &dyn Fn(&ViewMetrics) -> Option<f64>| -> Option<Stat> {
        Stat::of(&metrics.iter().filter_map(f).collect::<Vec<f64>>())
    };
    Summary {
        viewpoints: metrics.len(),
        viewpoints_with_false_culls: metrics.iter().filter(|m| m.false_culls > 0).count(),
        false_culls: collect(&|m| Some(m.false_culls as f64)),
        false_cull_area: collect(&|m| Some(m.false_cull_area)),
        occlusion_captured: collect(&|m| m.occlusion_captured),
        overdraw: collect(&|m| m.overdraw),
        triangles_drawn: collect(&|m| Some(m.triangles_drawn as f64)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use proptest::prelude::*;

    /// A 1 x 1 grid cell pair plus a 2 x 2 one: triangle areas 0.5, 0.5, 2, 2 (flat).
    fn four() -> Tin {
        let p = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(3.0, 0.0, 0.0),
            DVec3::new(3.0, 2.0, 0.0),
            DVec3::new(5.0, 2.0, 0.0),
        ];
        Tin::from_parts(p, vec![[0, 1, 2], [0, 2, 3], [4, 6, 5], [1, 4, 5]]).expect("valid")
    }

    #[test]
    fn hand_computed() {
        let tin = four();
        assert_eq!(tin.triangle_area_3d(2), 2.0);
        // V = {0, 1, 2}, D = {0, 3}: C = {1, 2}, H = {3}.
        let m = view_metrics(&tin, &[true, true, true, false], &[true, false, false, true]).expect("lengths");
        assert_eq!(m.visible, 3);
        assert_eq!(m.hidden, 1);
        assert_eq!(m.culled, 2);
        assert_eq!(m.false_culls, 2);
        assert_eq!(m.false_cull_area, 2.5);
        assert_eq!(m.culled_hidden, 0);
        assert_eq!(m.occlusion_captured, Some(0.0));
        assert_eq!(m.overdraw, Some(2.0 / 3.0));
        assert_eq!(m.triangles_drawn, 2);
        // Perfect culling.
        let m = view_metrics(&tin, &[true, false, false, false], &[true, false, false, false]).expect("lengths");
        assert_eq!(
            (m.false_culls, m.occlusion_captured, m.overdraw),
            (0, Some(1.0), Some(1.0))
        );
        // Nothing hidden, nothing visible.
        let m = view_metrics(&tin, &[true; 4], &[true; 4]).expect("lengths");
        assert_eq!(m.occlusion_captured, None);
        let m = view_metrics(&tin, &[false; 4], &[true; 4]).expect("lengths");
        assert_eq!((m.overdraw, m.occlusion_captured), (None, Some(0.0)));
    }

    #[test]
    fn length_errors_name_the_input() {
        let tin = four();
        assert_eq!(
            view_metrics(&tin, &[true; 4], &[true; 3]),
            Err(TruthError::LengthMismatch {
                what: "drawn",
                expected: 4,
                got: 3
            })
        );
        let e = view_metrics(&tin, &[true; 5], &[true; 4]).expect_err("too long");
        assert_eq!(e.to_string(), "visible has 5 entries, but the TIN has 4 triangles");
    }

    #[test]
    fn summary_statistics() {
        let s = Stat::of(&[3.0, 1.0, 2.0, 10.0]).expect("non-empty");
        assert_eq!((s.count, s.mean, s.p50, s.p95, s.max), (4, 4.0, 2.0, 10.0, 10.0));
        let many: Vec<f64> = (1..=100).map(f64::from).collect();
        let s = Stat::of(&many).expect("non-empty");
        assert_eq!((s.p50, s.p95, s.max), (50.0, 95.0, 100.0));
        assert_eq!(Stat::of(&[]), None);

        let tin = four();
        let a = view_metrics(&tin, &[true, true, false, false], &[true, false, true, false]).expect("ok");
        let b = view_metrics(&tin, &[true; 4], &[true; 4]).expect("ok");
        let sum = summarize(&[a.clone(), b]);
        assert_eq!(sum.viewpoints, 2);
        assert_eq!(sum.viewpoints_with_false_culls, 1);
        // Only `a` has hidden triangles: occlusion captured 1/2.
        let oc = sum.occlusion_captured.expect("defined once");
        assert_eq!((oc.count, oc.mean), (1, 0.5));
        assert_eq!(sum.overdraw.expect("defined").count, 2);
        assert_eq!(sum.false_cull_area.expect("defined").max, a.false_cull_area);
        let empty = summarize(&[]);
        assert_eq!((empty.viewpoints, empty.false_culls), (0, None));
        let json = serde_json::to_value(&sum).expect("serialize");
        assert!(json["occlusion_captured"]["p95"].is_number());
    }

    proptest! {
        #[test]
        fn set_identities(flags in prop::collection::vec((any::<bool>(), any::<bool>()), 4)) {
            let tin = four();
            let visible: Vec<bool> = flags.iter().map(|f| f.0).collect();
            let drawn: Vec<bool> = flags.iter().map(|f| f.1).collect();
            let m = view_metrics(&tin, &visible, &drawn).expect("lengths");
            prop_assert_eq!(m.false_culls + m.culled_hidden, m.culled);
            prop_assert_eq!(m.visible + m.hidden, m.triangles);
            prop_assert_eq!(m.triangles_drawn + m.culled, m.triangles);
            prop_assert!(m.false_culls <= m.visible.min(m.culled));
            prop_assert!(m.culled_hidden <= m.hidden);
            let drawn_visible = m.visible - m.false_culls;
            // |D| = |D ∩ V| + |D ∩ H|
            prop_assert_eq!(m.triangles_drawn, drawn_visible + (m.hidden - m.culled_hidden));
            if let Some(oc) = m.occlusion_captured {
                prop_assert!((0.0..=1.0).contains(&oc));
            }
            if m.false_culls == 0 && let Some(od) = m.overdraw {
                prop_assert!(od >= 1.0);
            }
            let area: f64 = (0..4).filter(|&t| visible[t] && !drawn[t]).map(|t| tin.triangle_area_3d(t)).sum();
            prop_assert_eq!(m.false_cull_area, area);
            // Drawing everything never culls falsely; drawing exactly V gives overdraw 1 and captures all of H.
            let all = view_metrics(&tin, &visible, &[true; 4]).expect("lengths");
            prop_assert_eq!(all.false_culls, 0);
            let exact = view_metrics(&tin, &visible, &visible).expect("lengths");
            prop_assert_eq!(exact.false_culls, 0);
            prop_assert!(exact.overdraw.is_none_or(|o| o == 1.0));
            prop_assert!(exact.occlusion_captured.is_none_or(|o| o == 1.0));
        }
    }
}
