//! The sides of a tile: which samples of a side become vertices.
//!
//! Two neighbouring tiles share a side (the same row or column of samples, between the same two corners). Each tile
//! simplifies that side on its own with [`side_vertices`], a Douglas–Peucker simplification that depends only on
//! the side's samples and the error bound, so both tiles keep exactly the same samples and their TINs join without
//! a crack. Every sample of the side that is not kept lies within the error bound of the straight edge between the
//! kept samples around it, which is also the TIN's height there (a TIN is linear along its edges).

/// The positions (indices into `z`) of the samples of one side to keep as vertices: its first and last valid
/// samples, and, recursively, the valid sample farthest (vertically) from the chord between two kept ones while that
/// distance exceeds `max_error` (ties: the smallest index). Void samples (NaN) are never kept; a side with no valid
/// sample keeps none. The result is sorted.
pub fn side_vertices(z: &[f64], max_error: f64) -> Vec<usize> {
    let valid: Vec<usize> = (0..z.len()).filter(|&i| !z[i].is_nan()).collect();
    let (Some(&first), Some(&last)) = (valid.first(), valid.last()) else {
        return Vec::new();
    };
    let mut keep = vec![first];
    if last != first {
        keep.push(last);
    }
    // Spans of `valid` positions to refine: (a, b) with a < b, both kept.
    let mut stack = vec![(0usize, valid.len() - 1)];
    while let Some((a, b)) = stack.pop() {
        if b <= a + 1 {
            continue;
        }
        let (ia, ib) = (valid[a], valid[b]);
        let (za, zb) = (z[ia], z[ib]);
        let mut worst: Option<(f64, usize)> = None;
        for (k, &i) in valid.iter().enumerate().take(b).skip(a + 1) {
            let chord = za + (zb - za) * ((i - ia) as f64 / (ib - ia) as f64);
            let e = (z[i] - chord).abs();
            if worst.is_none_or(|(we, _)| e > we) {
                worst = Some((e, k));
            }
        }
        if let Some((e, k)) = worst
            && e > max_error
        {
            keep.push(valid[k]);
            stack.push((a, k));
            stack.push((k, b));
        }
    }
    keep.sort_unstable();
    keep
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The error of a sample against the chord of the kept samples around it.
    fn chord_error(z: &[f64], keep: &[usize], i: usize) -> f64 {
        let b = keep.partition_point(|&k| k <= i);
        if b == 0 || b == keep.len() {
            return if keep.contains(&i) { 0.0 } else { f64::INFINITY };
        }
        let (ia, ib) = (keep[b - 1], keep[b]);
        if ia == i {
            return 0.0;
        }
        z[i] - (z[ia] + (z[ib] - z[ia]) * ((i - ia) as f64 / (ib - ia) as f64))
    }

    #[test]
    fn a_straight_side_keeps_its_ends() {
        let z: Vec<f64> = (0..10).map(|i| 3.0 * i as f64).collect();
        assert_eq!(side_vertices(&z, 0.0), vec![0, 9]);
    }

    #[test]
    fn a_peak_is_kept() {
        let z = [0.0, 0.0, 5.0, 0.0, 0.0];
        assert_eq!(side_vertices(&z, 2.6), vec![0, 2, 4]);
        // Within 1 m, the flanks of the peak are 2.5 m off its chords: they stay too.
        assert_eq!(side_vertices(&z, 1.0), vec![0, 1, 2, 3, 4]);
        assert_eq!(side_vertices(&z, 5.0), vec![0, 4]);
    }

    #[test]
    fn voids_are_skipped() {
        let z = [f64::NAN, 1.0, f64::NAN, 7.0, 1.0, f64::NAN];
        assert_eq!(side_vertices(&z, 0.5), vec![1, 3, 4]);
        assert!(side_vertices(&[f64::NAN; 4], 0.0).is_empty());
    }

    proptest! {
        /// Every valid sample is within the bound of the kept chords, and reversing the side keeps the mirrored
        /// samples' count (the result depends on the samples only).
        #[test]
        fn every_sample_within_the_bound(z in proptest::collection::vec(prop_oneof![9 => -100.0..100.0f64, 1 => Just(f64::NAN)], 1..60), e in 0.0..20.0f64) {
            let keep = side_vertices(&z, e);
            for i in 0..z.len() {
                if !z[i].is_nan() {
                    prop_assert!(chord_error(&z, &keep, i).abs() <= e + 1e-9, "sample {i}");
                }
            }
            prop_assert!(keep.iter().all(|&k| !z[k].is_nan()));
            prop_assert!(keep.windows(2).all(|w| w[0] < w[1]));
        }
    }
}
