//! Triangle reordering so that every hierarchy node draws with one call (the README's "What it does").
//!
//! A depth-first walk over the forest (roots in increasing id, children in stored order) lays out each group's
//! triangles when it reaches the group's leaf; every node then covers one contiguous range of the new order, and a
//! parent's range is its children's ranges side by side. The always-visible triangles come last.
//!
//! Inside a group and inside the always-visible set, triangles are in [`spatial_order`]: a range of `n` triangles
//! is split at `n / 2` into two halves that are compact in x,y, recursively. Any range obtained by halving is
//! therefore a compact patch of terrain, which the run-time horizon culler (`cull::safe`) uses to cull below the
//! groups without storing anything more.

use std::ops::Range;

use rayon::prelude::*;

use crate::merge::Hierarchy;

/// Lays out the triangles and sets every node's range. Returns the order (`order[k]` is the original index of the
/// triangle drawn `k`-th) and the range of the always-visible set.
pub(crate) fn lay_out(
    hierarchy: &mut Hierarchy,
    groups: &[Vec<u32>],
    orphans: &[u32],
    centroids: &[[f64; 2]],
) -> (Vec<u32>, Range<u32>) {
    let total = groups.iter().map(Vec::len).sum::<usize>() + orphans.len();
    let mut order = Vec::with_capacity(total);
    let mut stack: Vec<(u32, usize)> = Vec::new();
    // Triangles of each leaf in layout order (the leaves' ranges follow each other without gaps).
    let mut leaf_lengths: Vec<usize> = Vec::with_capacity(groups.len() + 1);
    for &root in &hierarchy.roots {
        hierarchy.nodes[root as usize].range.start = order.len() as u32;
        stack.push((root, 0));
        while let Some(&mut (n, ref mut next)) = stack.last_mut() {
            let node = &hierarchy.nodes[n as usize];
            if node.is_leaf() {
                order.extend_from_slice(&groups[n as usize]);
                leaf_lengths.push(groups[n as usize].len());
            }
            if let Some(&c) = node.children.get(*next) {
                *next += 1;
                hierarchy.nodes[c as usize].range.start = order.len() as u32;
                stack.push((c, 0));
            } else {
                hierarchy.nodes[n as usize].range.end = order.len() as u32;
                stack.pop();
            }
        }
    }
    let start = order.len() as u32;
    order.extend_from_slice(orphans);
    leaf_lengths.push(orphans.len());
    // The leaves' ranges and the always-visible tail tile the order; each is put in spatial order on its own, which
    // depends only on its own triangles, so they can be ordered in parallel with the same result.
    let mut parts: Vec<&mut [u32]> = Vec::with_capacity(leaf_lengths.len());
    let mut rest = order.as_mut_slice();
    for &len in &leaf_lengths {
        let (part, tail) = rest.split_at_mut(len);
        parts.push(part);
        rest = tail;
    }
    parts.into_par_iter().for_each(|part| spatial_order(part, centroids));
    let end = order.len() as u32;
    (order, start..end)
}

/// Orders `triangles` so that halving is a spatial split: the first `n / 2` are those whose centroids come first
/// along the longer side of the centroids' bounding box (ties by triangle index), recursively in both halves.
/// Deterministic: the result depends only on the set of triangles and their centroids.
pub(crate) fn spatial_order(triangles: &mut [u32], centroids: &[[f64; 2]]) {
    if triangles.len() <= 2 {
        triangles.sort_unstable();
        return;
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for &t in triangles.iter() {
        let c = centroids[t as usize];
        for k in 0..2 {
            lo[k] = lo[k].min(c[k]);
            hi[k] = hi[k].max(c[k]);
        }
    }
    let axis = usize::from(hi[1] - lo[1] > hi[0] - lo[0]);
    let mid = triangles.len() / 2;
    triangles.select_nth_unstable_by(mid, |&a, &b| {
        centroids[a as usize][axis]
            .total_cmp(&centroids[b as usize][axis])
            .then(a.cmp(&b))
    });
    let (left, right) = triangles.split_at_mut(mid);
    spatial_order(left, centroids);
    spatial_order(right, centroids);
}
