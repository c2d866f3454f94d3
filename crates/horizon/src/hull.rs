//! Covering sets: dynamic upper convex hulls of projected points `(t, z)` (thesis 4.5.2–4.5.3).
//!
//! A covering set holds the projected points of the vertices that may be the horizon of later vertices. Only the
//! upper hull matters: seen from an apex `p̂` left of every point (`t_p < t`), the steepest point is a vertex of the
//! upper hull, and the *leftmost* steepest point (the tie-break) is too, because the points on the tangent line
//! form a face of the hull whose left end is an extreme point. So the hull keeps strict vertices only (points on or
//! below the hull are dropped), except that of several points with identical `(t, z)` it keeps the smallest vertex
//! index — the one the tie-break would choose.
//!
//! Points arrive in any `t` order. Two representations, behind one handle ([`HullRef`] in a [`HullSet`]):
//! - *small* hulls (the common case on terrain: a few vertices) are sorted arrays in power-of-two chunks of a
//!   shared pool: binary search, then a short `copy_within`; one or two cache lines per operation;
//! - a hull that grows beyond a limit (e.g. on a dome, where every point is a hull vertex) becomes a treap keyed
//!   by `t` with its vertices threaded as a doubly linked list ([`HullArena`]), so every operation stays
//!   O(log h): insertion locates the neighbours, drops the point if on or below the hull, else links it in and
//!   pops the neighbours that stopped being strictly convex (amortised, every point is removed at most once).
//!
//! Tangent query from an apex left of all points: the slope from the apex increases along the hull while the apex
//! is strictly above the line of the current edge, then never again (the edges' lines, evaluated at
//! `t_p < t_min`, increase along an upper hull), so a binary search (array) or a descent (treap) finds the first
//! vertex whose outgoing edge does not increase the slope: the leftmost tangent vertex, in O(log h).
//!
//! All turns are decided by the exact [`crate::predicates::orient2d`].

use std::cmp::Ordering;

use glam::DVec2;

use crate::candidate::Candidate;
use crate::predicates::orient2d;

const NIL: u32 = u32::MAX;

/// The first state of a [`HullArena`]'s priority generator (xorshift64*).
const PRIORITY_SEED: u64 = 0x9E37_79B9_7F4A_7C15;

#[derive(Clone, Copy, Debug)]
struct Node {
    t: f64,
    z: f64,
    index: u32,
    prio: u32,
    left: u32,
    right: u32,
    prev: u32,
    next: u32,
}

impl Node {
    #[inline]
    fn point(&self) -> DVec2 {
        DVec2::new(self.t, self.z)
    }
}

/// Handle of one upper hull stored in a [`HullArena`]. Copy it out, pass it back mutably to change it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Hull {
    root: u32,
    head: u32,
}

impl Hull {
    /// The empty hull.
    pub const EMPTY: Hull = Hull { root: NIL, head: NIL };

    /// Whether the hull holds no point.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.root == NIL
    }
}

impl Default for Hull {
    fn default() -> Self {
        Hull::EMPTY
    }
}

/// Storage for many upper hulls (the covering sets of one sweep).
#[derive(Clone, Debug)]
pub struct HullArena {
    nodes: Vec<Node>,
    free: Vec<u32>,
    rng: u64,
}

impl Default for HullArena {
    fn default() -> Self {
        HullArena::with_capacity(0)
    }
}

impl HullArena {
    /// An empty arena with room for `capacity` hull vertices.
    pub fn with_capacity(capacity: usize) -> HullArena {
        HullArena {
            nodes: Vec::with_capacity(capacity),
            free: Vec::new(),
            rng: PRIORITY_SEED,
        }
    }

    /// Empties the arena as [`HullArena::with_capacity`] makes it (priorities start again from the same seed),
    /// keeping its memory for reuse.
    pub fn clear(&mut self) {
        self.nodes.clear();
        self.free.clear();
        self.rng = PRIORITY_SEED;
    }

    /// Number of hull vertices alive in all hulls of this arena.
    pub fn live(&self) -> usize {
        self.nodes.len() - self.free.len()
    }

    /// The smallest `t` of all points ever inserted into `hull` (its leftmost vertex), or `None` when empty.
    #[inline]
    pub fn min_t(&self, hull: &Hull) -> Option<f64> {
        (hull.head != NIL).then(|| self.nodes[hull.head as usize].t)
    }

    /// The hull's vertices from left to right as `(t, z, index)`.
    pub fn vertices(&self, hull: &Hull) -> Vec<(f64, f64, u32)> {
        let mut out = Vec::new();
        let mut n = hull.head;
        while n != NIL {
            let node = &self.nodes[n as usize];
            out.push((node.t, node.z, node.index));
            n = node.next;
        }
        out
    }

    /// Inserts the projected point `(t, z)` of vertex `index` into `hull`.
    pub fn insert(&mut self, hull: &mut Hull, t: f64, z: f64, index: u32) {
        let q = DVec2::new(t, z);
        let (mut pred, succ) = self.locate(hull.root, t);
        if pred != NIL && self.nodes[pred as usize].t == t {
            let node = &mut self.nodes[pred as usize];
            match node.z.partial_cmp(&z).unwrap_or(Ordering::Equal) {
                Ordering::Greater => return,
                Ordering::Equal => {
                    node.index = node.index.min(index);
                    return;
                }
                Ordering::Less => {
                    // The new point is directly above a hull vertex: it replaces it.
                    let pp = node.prev;
                    self.remove(hull, pred);
                    pred = pp;
                }
            }
        } else if pred != NIL
            && succ != NIL
            && orient2d(self.nodes[pred as usize].point(), self.nodes[succ as usize].point(), q) != Ordering::Greater
        {
            // On or below the segment between its neighbours: never the (leftmost) steepest point.
            return;
        }
        let x = self.alloc(t, z, index, pred, succ);
        if pred == NIL {
            hull.head = x;
        } else {
            self.nodes[pred as usize].next = x;
        }
        if succ != NIL {
            self.nodes[succ as usize].prev = x;
        }
        hull.root = self.treap_insert(hull.root, x);
        // Pop neighbours that are no longer strictly convex (right turns only along an upper hull).
        loop {
            let p1 = self.nodes[x as usize].prev;
            if p1 == NIL {
                break;
            }
            let p2 = self.nodes[p1 as usize].prev;
            if p2 == NIL
                || orient2d(self.nodes[p2 as usize].point(), self.nodes[p1 as usize].point(), q) == Ordering::Less
            {
                break;
            }
            self.remove(hull, p1);
        }
        loop {
            let s1 = self.nodes[x as usize].next;
            if s1 == NIL {
                break;
            }
            let s2 = self.nodes[s1 as usize].next;
            if s2 == NIL
                || orient2d(q, self.nodes[s1 as usize].point(), self.nodes[s2 as usize].point()) == Ordering::Less
            {
                break;
            }
            self.remove(hull, s1);
        }
    }

    /// The leftmost steepest hull vertex seen from `apex`, which must lie strictly left of every point of the hull
    /// (`apex.x < min_t`). `None` when the hull is empty.
    #[inline]
    pub(crate) fn tangent(&self, hull: &Hull, apex: DVec2) -> Option<Candidate> {
        let mut n = hull.root;
        let mut best = NIL;
        while n != NIL {
            let node = &self.nodes[n as usize];
            let next = node.next;
            if next != NIL && orient2d(apex, node.point(), self.nodes[next as usize].point()) == Ordering::Greater {
                // The slope still increases along the edge leaving n: the tangent is further right.
                n = node.right;
            } else {
                best = n;
                n = node.left;
            }
        }
        (best != NIL).then(|| {
            let node = &self.nodes[best as usize];
            Candidate::vertex(node.t, node.z, node.index)
        })
    }

    /// Checks every invariant of `hull`: a strictly increasing, strictly convex upper chain; list and treap agree;
    /// treap heap order. Returns a description of the first violation.
    pub fn check_invariants(&self, hull: &Hull) -> Result<(), String> {
        let list = self.vertices(hull);
        let mut inorder = Vec::new();
        self.collect_inorder(hull.root, &mut inorder)?;
        if inorder.len() != list.len() {
            return Err(format!("treap has {} nodes, list {}", inorder.len(), list.len()));
        }
        let mut prev = NIL;
        let mut n = hull.head;
        for &id in &inorder {
            if id != n {
                return Err(format!("treap order and list order differ at node {id}"));
            }
            if self.nodes[id as usize].prev != prev {
                return Err(format!("node {id} has a wrong prev link"));
            }
            prev = n;
            n = self.nodes[n as usize].next;
        }
        check_chain(&list)
    }

    fn collect_inorder(&self, n: u32, out: &mut Vec<u32>) -> Result<(), String> {
        if n == NIL {
            return Ok(());
        }
        let node = &self.nodes[n as usize];
        for child in [node.left, node.right] {
            if child != NIL && self.nodes[child as usize].prio > node.prio {
                return Err(format!("heap order violated below node {n}"));
            }
        }
        self.collect_inorder(node.left, out)?;
        out.push(n);
        self.collect_inorder(node.right, out)
    }

    /// Predecessor (largest `t' ≤ t`) and successor (smallest `t' > t`).
    #[inline]
    fn locate(&self, root: u32, t: f64) -> (u32, u32) {
        let (mut pred, mut succ) = (NIL, NIL);
        let mut n = root;
        while n != NIL {
            let node = &self.nodes[n as usize];
            if node.t <= t {
                pred = n;
                n = node.right;
            } else {
                succ = n;
                n = node.left;
            }
        }
        (pred, succ)
    }

    fn alloc(&mut self, t: f64, z: f64, index: u32, prev: u32, next: u32) -> u32 {
        // xorshift64*: deterministic priorities.
        self.rng ^= self.rng >> 12;
        self.rng ^= self.rng << 25;
        self.rng ^= self.rng >> 27;
        let prio = (self.rng.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 32) as u32;
        let node = Node {
            t,
            z,
            index,
            prio,
            left: NIL,
            right: NIL,
            prev,
            next,
        };
        match self.free.pop() {
            Some(id) => {
                self.nodes[id as usize] = node;
                id
            }
            None => {
                self.nodes.push(node);
                (self.nodes.len() - 1) as u32
            }
        }
    }

    fn remove(&mut self, hull: &mut Hull, n: u32) {
        let Node { prev, next, t, .. } = self.nodes[n as usize];
        if prev == NIL {
            hull.head = next;
        } else {
            self.nodes[prev as usize].next = next;
        }
        if next != NIL {
            self.nodes[next as usize].prev = prev;
        }
        hull.root = self.treap_erase(hull.root, t);
        self.free.push(n);
    }

    fn treap_insert(&mut self, n: u32, x: u32) -> u32 {
        if n == NIL {
            return x;
        }
        let xt = self.nodes[x as usize].t;
        if self.nodes[x as usize].prio > self.nodes[n as usize].prio {
            let (l, r) = self.split(n, xt);
            let node = &mut self.nodes[x as usize];
            node.left = l;
            node.right = r;
            return x;
        }
        if xt < self.nodes[n as usize].t {
            let child = self.treap_insert(self.nodes[n as usize].left, x);
            self.nodes[n as usize].left = child;
        } else {
            let child = self.treap_insert(self.nodes[n as usize].right, x);
            self.nodes[n as usize].right = child;
        }
        n
    }

    /// Splits subtree `n` into keys `< t` and keys `> t` (`t` is not present).
    fn split(&mut self, n: u32, t: f64) -> (u32, u32) {
        if n == NIL {
            return (NIL, NIL);
        }
        if self.nodes[n as usize].t < t {
            let (l, r) = self.split(self.nodes[n as usize].right, t);
            self.nodes[n as usize].right = l;
            (n, r)
        } else {
            let (l, r) = self.split(self.nodes[n as usize].left, t);
            self.nodes[n as usize].left = r;
            (l, n)
        }
    }

    /// Joins two subtrees whose keys are all ordered (`a` before `b`).
    fn merge(&mut self, a: u32, b: u32) -> u32 {
        if a == NIL {
            return b;
        }
        if b == NIL {
            return a;
        }
        if self.nodes[a as usize].prio > self.nodes[b as usize].prio {
            let r = self.merge(self.nodes[a as usize].right, b);
            self.nodes[a as usize].right = r;
            a
        } else {
            let l = self.merge(a, self.nodes[b as usize].left);
            self.nodes[b as usize].left = l;
            b
        }
    }

    fn treap_erase(&mut self, n: u32, t: f64) -> u32 {
        if n == NIL {
            return NIL;
        }
        let node = self.nodes[n as usize];
        if node.t == t {
            return self.merge(node.left, node.right);
        }
        if t < node.t {
            let l = self.treap_erase(node.left, t);
            self.nodes[n as usize].left = l;
        } else {
            let r = self.treap_erase(node.right, t);
            self.nodes[n as usize].right = r;
        }
        n
    }
}

/// A projected point in a small hull.
#[derive(Clone, Copy, Debug, Default)]
struct Pt {
    t: f64,
    z: f64,
    index: u32,
}

impl Pt {
    #[inline]
    fn point(&self) -> DVec2 {
        DVec2::new(self.t, self.z)
    }
}

/// Handle of one upper hull in a [`HullSet`]: empty, a small sorted array, or a treap.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HullRef {
    /// Start of the chunk in the pool (small), or index of the treap (big).
    start: u32,
    /// Number of vertices of a small hull.
    len: u16,
    /// Chunk capacity is `1 << class`.
    class: u8,
    big: bool,
}

impl HullRef {
    /// The empty hull.
    pub const EMPTY: HullRef = HullRef {
        start: 0,
        len: 0,
        class: 0,
        big: false,
    };

    /// Whether the hull holds no point.
    #[inline]
    pub fn is_empty(&self) -> bool {
        !self.big && self.len == 0
    }
}

/// Storage for the covering sets of one sweep: small hulls as sorted arrays, big ones as treaps.
#[derive(Clone, Debug)]
pub struct HullSet {
    small_limit: usize,
    pool: Vec<Pt>,
    free: Vec<Vec<u32>>,
    trees: Vec<Hull>,
    arena: HullArena,
}

impl Default for HullSet {
    fn default() -> Self {
        HullSet::new(HullSet::DEFAULT_SMALL_LIMIT, 0)
    }
}

impl HullSet {
    /// Default number of vertices beyond which a hull becomes a treap.
    pub const DEFAULT_SMALL_LIMIT: usize = 32;

    /// An empty set whose hulls turn into treaps beyond `small_limit` vertices (clamped to 1..=1024), with room
    /// for `capacity` small-hull vertices.
    pub fn new(small_limit: usize, capacity: usize) -> HullSet {
        let small_limit = small_limit.clamp(1, 1024);
        let classes = small_limit.next_power_of_two().trailing_zeros() as usize + 1;
        HullSet {
            small_limit,
            pool: Vec::with_capacity(capacity),
            free: vec![Vec::new(); classes],
            trees: Vec::new(),
            arena: HullArena::default(),
        }
    }

    /// Empties the set as [`HullSet::new`] makes it with `small_limit` and `capacity` (every [`HullRef`] into it is
    /// invalid afterwards), keeping its memory for the next sweep.
    pub fn clear(&mut self, small_limit: usize, capacity: usize) {
        let small_limit = small_limit.clamp(1, 1024);
        let classes = small_limit.next_power_of_two().trailing_zeros() as usize + 1;
        self.small_limit = small_limit;
        self.pool.clear();
        self.pool.reserve(capacity);
        self.free.iter_mut().for_each(Vec::clear);
        self.free.resize_with(classes, Vec::new);
        self.trees.clear();
        self.arena.clear();
    }

    /// The smallest `t` of all points ever inserted into `hull` (its leftmost vertex), or `None` when empty.
    #[inline]
    pub fn min_t(&self, hull: &HullRef) -> Option<f64> {
        if hull.big {
            self.arena.min_t(&self.trees[hull.start as usize])
        } else {
            (hull.len > 0).then(|| self.pool[hull.start as usize].t)
        }
    }

    /// Whether `hull` is stored as a treap.
    pub fn is_big(&self, hull: &HullRef) -> bool {
        hull.big
    }

    /// The hull's vertices from left to right as `(t, z, index)`.
    pub fn vertices(&self, hull: &HullRef) -> Vec<(f64, f64, u32)> {
        if hull.big {
            self.arena.vertices(&self.trees[hull.start as usize])
        } else {
            self.small(hull).iter().map(|p| (p.t, p.z, p.index)).collect()
        }
    }

    /// Hints the processor to load the first cache line of a small hull's points (a treap is left alone); no
    /// effect on any result.
    #[inline(always)]
    pub fn prefetch(&self, hull: &HullRef) {
        if !hull.big
            && let Some(p) = self.pool.get(hull.start as usize)
        {
            tin::prefetch(p);
        }
    }

    #[inline]
    fn small(&self, hull: &HullRef) -> &[Pt] {
        &self.pool[hull.start as usize..hull.start as usize + hull.len as usize]
    }

    /// The leftmost steepest hull vertex seen from `apex`, which must lie strictly left of every point of the hull.
    #[inline]
    pub(crate) fn tangent(&self, hull: &HullRef, apex: DVec2) -> Option<Candidate> {
        if hull.big {
            return self.arena.tangent(&self.trees[hull.start as usize], apex);
        }
        let pts = self.small(hull);
        if pts.is_empty() {
            return None;
        }
        // First i whose outgoing edge does not increase the slope (the predicate is true on a prefix).
        let (mut lo, mut hi) = (0, pts.len() - 1);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if orient2d(apex, pts[mid].point(), pts[mid + 1].point()) == Ordering::Greater {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        let p = pts[lo];
        Some(Candidate::vertex(p.t, p.z, p.index))
    }

    /// Inserts the projected point `(t, z)` of vertex `index` into `hull`.
    pub fn insert(&mut self, hull: &mut HullRef, t: f64, z: f64, index: u32) {
        if hull.big {
            self.arena.insert(&mut self.trees[hull.start as usize], t, z, index);
            return;
        }
        let new = Pt { t, z, index };
        if hull.len == 0 {
            let start = self.alloc(0);
            self.pool[start as usize] = new;
            *hull = HullRef {
                start,
                len: 1,
                class: 0,
                big: false,
            };
            return;
        }
        let q = new.point();
        let start = hull.start as usize;
        let len = hull.len as usize;
        let pts = &mut self.pool[start..start + len];
        let pos = pts.partition_point(|p| p.t <= t);
        let (mut keep_left, mut resume_right) = (pos, pos);
        if pos > 0 && pts[pos - 1].t == t {
            let pred = &mut pts[pos - 1];
            // Numeric comparison: −0.0 equals 0.0, as in the exact predicates.
            match pred.z.partial_cmp(&z).unwrap_or(Ordering::Equal) {
                Ordering::Greater => return,
                Ordering::Equal => {
                    pred.index = pred.index.min(index);
                    return;
                }
                // Directly above a hull vertex: replaces it.
                Ordering::Less => keep_left = pos - 1,
            }
        } else if pos > 0 && pos < len && orient2d(pts[pos - 1].point(), pts[pos].point(), q) != Ordering::Greater {
            // On or below the segment between its neighbours.
            return;
        }
        while keep_left >= 2 && orient2d(pts[keep_left - 2].point(), pts[keep_left - 1].point(), q) != Ordering::Less {
            keep_left -= 1;
        }
        while resume_right + 1 < len
            && orient2d(q, pts[resume_right].point(), pts[resume_right + 1].point()) != Ordering::Less
        {
            resume_right += 1;
        }
        let new_len = keep_left + 1 + (len - resume_right);
        if new_len > self.small_limit {
            self.make_big(hull, new);
        } else if new_len > 1 << hull.class {
            let class = hull.class + 1;
            let to = self.alloc(class) as usize;
            self.pool.copy_within(start..start + keep_left, to);
            self.pool[to + keep_left] = new;
            self.pool
                .copy_within(start + resume_right..start + len, to + keep_left + 1);
            self.free[hull.class as usize].push(hull.start);
            *hull = HullRef {
                start: to as u32,
                len: new_len as u16,
                class,
                big: false,
            };
        } else {
            self.pool
                .copy_within(start + resume_right..start + len, start + keep_left + 1);
            self.pool[start + keep_left] = new;
            hull.len = new_len as u16;
        }
    }

    /// Moves a small hull into a treap and inserts `new`.
    fn make_big(&mut self, hull: &mut HullRef, new: Pt) {
        let mut tree = Hull::EMPTY;
        let (start, len) = (hull.start as usize, hull.len as usize);
        for i in start..start + len {
            let p = self.pool[i];
            self.arena.insert(&mut tree, p.t, p.z, p.index);
        }
        self.arena.insert(&mut tree, new.t, new.z, new.index);
        self.free[hull.class as usize].push(hull.start);
        self.trees.push(tree);
        *hull = HullRef {
            start: (self.trees.len() - 1) as u32,
            len: 0,
            class: 0,
            big: true,
        };
    }

    fn alloc(&mut self, class: u8) -> u32 {
        if let Some(start) = self.free[class as usize].pop() {
            return start;
        }
        let start = self.pool.len() as u32;
        self.pool.resize(self.pool.len() + (1 << class), Pt::default());
        start
    }

    /// Checks every invariant of `hull`: a strictly increasing, strictly convex upper chain (and, for a treap,
    /// the treap's own invariants). Returns a description of the first violation.
    pub fn check_invariants(&self, hull: &HullRef) -> Result<(), String> {
        if hull.big {
            return self.arena.check_invariants(&self.trees[hull.start as usize]);
        }
        if hull.len as usize > 1 << hull.class || hull.len as usize > self.small_limit {
            return Err(format!(
                "small hull of {} vertices in a chunk of {}",
                hull.len,
                1 << hull.class
            ));
        }
        check_chain(&self.vertices(hull))
    }
}

/// A strictly increasing, strictly convex upper chain.
fn check_chain(list: &[(f64, f64, u32)]) -> Result<(), String> {
    for w in list.windows(2) {
        if w[0].0 >= w[1].0 {
            return Err(format!("t not strictly increasing: {} then {}", w[0].0, w[1].0));
        }
    }
    for w in list.windows(3) {
        let [a, b, c] = [w[0], w[1], w[2]].map(|(t, z, _)| DVec2::new(t, z));
        if orient2d(a, b, c) != Ordering::Less {
            return Err(format!("vertex {b} is not strictly convex"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::candidate::CandidateId;
    use proptest::prelude::*;

    /// Brute force: the leftmost steepest point, smallest index on full ties.
    fn steepest(points: &[(f64, f64, u32)], apex: DVec2) -> Option<Candidate> {
        let mut best: Option<Candidate> = None;
        for &(t, z, i) in points {
            crate::candidate::keep_best(&mut best, Candidate::vertex(t, z, i), apex);
        }
        best
    }

    /// Brute force upper hull (strict vertices, smallest index on duplicates).
    fn upper_hull(points: &[(f64, f64, u32)]) -> Vec<(f64, f64, u32)> {
        let mut sorted = points.to_vec();
        let num = |x: f64, y: f64| x.partial_cmp(&y).expect("not NaN"); // −0.0 == 0.0
        sorted.sort_by(|a, b| num(a.0, b.0).then(num(b.1, a.1)).then(a.2.cmp(&b.2)));
        sorted.dedup_by(|b, a| a.0 == b.0); // keep the highest (then smallest index) per t
        let mut hull: Vec<(f64, f64, u32)> = Vec::new();
        for p in sorted {
            while hull.len() >= 2 {
                let [a, b] = [hull[hull.len() - 2], hull[hull.len() - 1]].map(|(t, z, _)| DVec2::new(t, z));
                if orient2d(a, b, DVec2::new(p.0, p.1)) == Ordering::Less {
                    break;
                }
                hull.pop();
            }
            hull.push(p);
        }
        hull
    }

    fn small_points() -> impl Strategy<Value = Vec<(f64, f64, u32)>> {
        // Small integer coordinates: many duplicates, equal t, collinear runs.
        prop::collection::vec((0i32..12, -4i32..6), 1..60).prop_map(|v| {
            // Zeros alternate in sign: −0.0 and 0.0 must behave as the same coordinate.
            let signed = |x: i32, i: usize| if x == 0 && i % 2 == 1 { -0.0 } else { x as f64 };
            v.into_iter()
                .enumerate()
                .map(|(i, (t, z))| (signed(t, i), signed(z, i / 2), (i * 7 % 61) as u32))
                .collect()
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

        #[test]
        fn hull_and_tangent_match_brute_force(points in small_points(), apex_z in -20i32..20, apex_dt in 1i32..5) {
            let mut arena = HullArena::default();
            let mut hull = Hull::EMPTY;
            for (k, &(t, z, i)) in points.iter().enumerate() {
                arena.insert(&mut hull, t, z, i);
                arena.check_invariants(&hull).map_err(TestCaseError::fail)?;
                let so_far = &points[..=k];
                prop_assert_eq!(arena.vertices(&hull), upper_hull(so_far));
                let apex = DVec2::new(-(apex_dt as f64) / 2.0, apex_z as f64 / 3.0);
                prop_assert_eq!(arena.tangent(&hull, apex), steepest(so_far, apex));
            }
            prop_assert_eq!(arena.min_t(&hull), points.iter().map(|p| p.0).reduce(f64::min));
        }

        #[test]
        fn hull_set_matches_brute_force(points in small_points(), limit in 1usize..8, apex_z in -20i32..20) {
            // Low limits force the conversion from arrays to treaps in the middle of the sequence.
            let mut set = HullSet::new(limit, 0);
            let mut hulls = [HullRef::EMPTY; 2];
            for (k, &(t, z, i)) in points.iter().enumerate() {
                let h = k % 2;
                set.insert(&mut hulls[h], t, z, i);
                set.check_invariants(&hulls[h]).map_err(TestCaseError::fail)?;
                let mine: Vec<_> = points[..=k].iter().enumerate().filter(|(j, _)| j % 2 == h).map(|(_, &p)| p).collect();
                prop_assert_eq!(set.vertices(&hulls[h]), upper_hull(&mine));
                let apex = DVec2::new(-0.5, apex_z as f64 / 3.0);
                prop_assert_eq!(set.tangent(&hulls[h], apex), steepest(&mine, apex));
                prop_assert_eq!(set.min_t(&hulls[h]), mine.iter().map(|p| p.0).reduce(f64::min));
            }
        }

        #[test]
        fn many_hulls_share_an_arena(points in prop::collection::vec((0.0f64..100.0, 0.0f64..10.0), 1..200)) {
            let mut arena = HullArena::default();
            let mut hulls = [Hull::EMPTY; 3];
            for (i, &(t, z)) in points.iter().enumerate() {
                arena.insert(&mut hulls[i % 3], t, z, i as u32);
            }
            let mut live = 0;
            for (h, hull) in hulls.iter().enumerate() {
                arena.check_invariants(hull).map_err(TestCaseError::fail)?;
                let mine: Vec<_> = points.iter().enumerate().filter(|(i, _)| i % 3 == h)
                    .map(|(i, &(t, z))| (t, z, i as u32)).collect();
                prop_assert_eq!(arena.vertices(hull), upper_hull(&mine));
                live += arena.vertices(hull).len();
            }
            prop_assert_eq!(arena.live(), live);
        }
    }

    #[test]
    fn a_dome_becomes_a_treap() {
        // Points on a concave parabola: every point is a hull vertex.
        let mut set = HullSet::default();
        let mut hull = HullRef::EMPTY;
        for i in 0..200u32 {
            let t = ((i * 37) % 200) as f64;
            set.insert(&mut hull, t, -(t - 100.0) * (t - 100.0), i);
        }
        assert!(set.is_big(&hull));
        set.check_invariants(&hull).expect("valid");
        assert_eq!(set.vertices(&hull).len(), 200);
        let c = set.tangent(&hull, DVec2::new(-10.0, 0.0)).expect("non-empty");
        assert_eq!(
            c,
            steepest(&set.vertices(&hull), DVec2::new(-10.0, 0.0)).expect("non-empty")
        );
    }

    #[test]
    fn duplicates_keep_the_smallest_index() {
        let mut arena = HullArena::default();
        let mut hull = Hull::EMPTY;
        arena.insert(&mut hull, 1.0, 1.0, 9);
        arena.insert(&mut hull, 1.0, 1.0, 4);
        arena.insert(&mut hull, 1.0, 1.0, 6);
        arena.insert(&mut hull, 1.0, 0.5, 1);
        assert_eq!(arena.vertices(&hull), vec![(1.0, 1.0, 4)]);
        arena.insert(&mut hull, 1.0, 2.0, 8);
        assert_eq!(arena.vertices(&hull), vec![(1.0, 2.0, 8)]);
    }

    #[test]
    fn collinear_points_keep_the_leftmost_tangent() {
        // Flat lake: every point has slope 0 from an apex at the same height; the leftmost must win.
        let mut arena = HullArena::default();
        let mut hull = Hull::EMPTY;
        for (i, t) in [5.0, 3.0, 9.0, 1.0, 7.0].into_iter().enumerate() {
            arena.insert(&mut hull, t, 2.0, i as u32);
        }
        assert_eq!(arena.vertices(&hull), vec![(1.0, 2.0, 3), (9.0, 2.0, 2)]);
        let c = arena.tangent(&hull, DVec2::new(0.0, 2.0)).expect("non-empty");
        assert_eq!(c.id, CandidateId::Vertex(3));
        // Same line through the apex: points on a rising line, tangent is the leftmost.
        let mut hull = Hull::EMPTY;
        for (i, t) in [4.0, 2.0, 6.0].into_iter().enumerate() {
            arena.insert(&mut hull, t, t, 10 + i as u32);
        }
        let c = arena.tangent(&hull, DVec2::new(0.0, 0.0)).expect("non-empty");
        assert_eq!(c.id, CandidateId::Vertex(11));
    }
}
