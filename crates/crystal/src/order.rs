//! Triangle reordering so that every hierarchy node draws with one call (design.md "Crystal grouping").
//!
//! A depth-first walk over the forest (roots in increasing id, children in stored order) lays out each group's
//! triangles, in the order they joined, when it reaches the group's leaf; every node then covers one contiguous range
//! of the new order, and a parent's range is its children's ranges side by side. The always-visible triangles come
//! last, in increasing index.

use std::ops::Range;

use crate::merge::Hierarchy;

/// Lays out the triangles and sets every node's range. Returns the order (`order[k]` is the original index of the
/// triangle drawn `k`-th) and the range of the always-visible set.
pub(crate) fn lay_out(hierarchy: &mut Hierarchy, groups: &[Vec<u32>], orphans: &[u32]) -> (Vec<u32>, Range<u32>) {
    let total = groups.iter().map(Vec::len).sum::<usize>() + orphans.len();
    let mut order = Vec::with_capacity(total);
    let mut stack: Vec<(u32, usize)> = Vec::new();
    for &root in &hierarchy.roots {
        hierarchy.nodes[root as usize].range.start = order.len() as u32;
        stack.push((root, 0));
        while let Some(&mut (n, ref mut next)) = stack.last_mut() {
            let node = &hierarchy.nodes[n as usize];
            if node.is_leaf() {
                order.extend_from_slice(&groups[n as usize]);
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
    let end = order.len() as u32;
    (order, start..end)
}
