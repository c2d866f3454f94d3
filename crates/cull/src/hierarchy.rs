//! The exported occlusion hierarchy: what the run-time culler needs and nothing more, plus the reordered mesh.
//!
//! Regions are stored in f32, relative to the hierarchy's local origin, rounded so that they only shrink (see
//! [`StoredRegion::from_f64`]): storage can lose occlusion, never add a false cull. Bounding circles are rounded so
//! that they only grow.

use serde::{Deserialize, Serialize};

use crate::error::HierarchyError;
use crate::sector::sector_direction;

/// Largest coordinate magnitude of a vertex (2^100), the limit of the mesh readers (`tin::COORDINATE_LIMIT`, equal
/// by a test); non-zero magnitudes below its inverse are refused too. A file beyond it is refused on load: its
/// coordinates would not survive the f32 of exports.
pub const COORDINATE_LIMIT: f64 = 1.267_650_600_228_229_4e30;

/// Most regions a hierarchy may hold (2^28, a file of some 4 GB): the thesis' culler indexes at most eight slots per
/// region and every region vertex with 32 bits.
pub const MAX_REGIONS: u64 = 1 << 28;

/// Most region vertices a hierarchy may hold, counting one more per region for its tail (2^31).
pub const MAX_REGION_POINTS: u64 = 1 << 31;

/// Whether `value` is 0 or a magnitude in `[1 / COORDINATE_LIMIT, COORDINATE_LIMIT]` (NaN and infinities are not).
fn coordinate_in_range(value: f64) -> bool {
    let m = value.abs();
    m == 0.0 || (1.0 / COORDINATE_LIMIT..=COORDINATE_LIMIT).contains(&m)
}

/// One sector's occlusion region of a node, in the sector's vertical plane relative to the local origin:
/// `t = r_i · (xy − origin.xy)`, `z − origin.z`. The region is `t > points[0].t` and `z <` the boundary through
/// `points`, continued beyond the last point with slope `tail_slope`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StoredRegion {
    /// The sector this region belongs to.
    pub sector: u16,
    /// Boundary vertices `[t, z]`, `t` strictly increasing; the first one lies on the left bound.
    pub points: Vec<[f32; 2]>,
    /// Slope of the boundary beyond the last vertex.
    pub tail_slope: f32,
}

impl StoredRegion {
    /// Rounds an f64 boundary (plane coordinates `[t, z]` in any frame, strictly increasing `t`, concave) to f32
    /// relative to `origin_t` and `origin_z` (the file origin's coordinates in that frame) such that the stored
    /// region is contained in the original one: the left bound rounds up, each vertex is re-evaluated on the original
    /// boundary at its rounded `t` and rounded down, and the tail slope rounds down.
    pub fn from_f64(
        sector: u16,
        points: &[[f64; 2]],
        tail_slope: f64,
        origin_t: f64,
        origin_z: f64,
    ) -> Option<StoredRegion> {
        let eval = |t: f64| {
            let i = points.partition_point(|p| p[0] <= t).saturating_sub(1);
            match points.get(i + 1) {
                Some(b) => {
                    let a = points[i];
                    a[1] + (b[1] - a[1]) * ((t - a[0]) / (b[0] - a[0]))
                }
                None => points[i][1] + tail_slope * (t - points[i][0]),
            }
        };
        let mut out: Vec<[f32; 2]> = Vec::with_capacity(points.len());
        for (k, p) in points.iter().enumerate() {
            let rel = p[0] - origin_t;
            let mut t = rel as f32;
            if k == 0 && f64::from(t) < rel {
                t = t.next_up();
            }
            if out.last().is_some_and(|q| q[0] >= t) {
                continue;
            }
            let z_true = eval(f64::from(t) + origin_t) - origin_z;
            let mut z = z_true as f32;
            if f64::from(z) > z_true {
                z = z.next_down();
            }
            out.push([t, z]);
        }
        let mut tail = tail_slope as f32;
        if f64::from(tail) > tail_slope {
            tail = tail.next_down();
        }
        let ok = !out.is_empty() && tail.is_finite() && out.iter().all(|p| p[0].is_finite() && p[1].is_finite());
        ok.then_some(StoredRegion {
            sector,
            points: out,
            tail_slope: tail,
        })
    }

    /// Height of the boundary at plane coordinate `t` (relative to the origin), in f64.
    ///
    /// # Panics
    ///
    /// When the region has no points (every region of a hierarchy that passes [`Hierarchy::check_invariants`] has).
    pub fn height_at(&self, t: f64) -> f64 {
        let pts = &self.points;
        let i = pts.partition_point(|p| f64::from(p[0]) <= t).saturating_sub(1);
        let a = pts[i];
        match pts.get(i + 1) {
            Some(b) => {
                let (ax, ay, bx, by) = (f64::from(a[0]), f64::from(a[1]), f64::from(b[0]), f64::from(b[1]));
                ay + (by - ay) * ((t - ax) / (bx - ax))
            }
            None => f64::from(a[1]) + f64::from(self.tail_slope) * (t - f64::from(a[0])),
        }
    }

    /// Whether `(t, z)` (relative to the origin) is strictly inside the region; the boundary is outside. Panics, as
    /// [`StoredRegion::height_at`], for a region without points (which [`Hierarchy::check_invariants`] refuses).
    pub fn contains(&self, t: f64, z: f64) -> bool {
        t > f64::from(self.points[0][0]) && z < self.height_at(t)
    }
}

/// One node of the hierarchy: a leaf group or a merge of child nodes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Node {
    /// Centre of the node's bounding circle, x,y relative to the origin.
    pub centre: [f32; 2],
    /// Radius of the bounding circle (rounded up).
    pub radius: f32,
    /// Child node indices; empty for a leaf group.
    pub children: Vec<u32>,
    /// The node's triangles: `[start, end)` in the hierarchy's triangle order.
    pub triangles: [u32; 2],
    /// Level in the hierarchy: 0 for leaf groups, one more than the highest child otherwise.
    pub level: u32,
    /// Non-empty occlusion regions, in increasing sector order; sectors not listed are empty (never occluded).
    pub regions: Vec<StoredRegion>,
}

/// The reordered terrain mesh that the hierarchy's triangle ranges refer to.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Mesh {
    /// Vertex positions in world coordinates (f64, exact).
    pub positions: Vec<[f64; 3]>,
    /// Counter-clockwise triangles, in hierarchy order: every node is one contiguous range, the always-visible
    /// triangles last.
    pub triangles: Vec<[u32; 3]>,
}

/// Parameters the hierarchy was built with, kept for people and tools; the culler does not read them.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BuildInfo {
    /// Subsectors per sector used for the horizons.
    pub subsectors: u32,
    /// Crystal seeds of the first pass (this and the next four fields are the crystal grouping's: 0 for a quadtree;
    /// counts beyond `u32::MAX` are recorded as `u32::MAX`, and a merged tiled build holds the tiles' sum).
    pub seeds: u32,
    /// Orphan passes allowed.
    pub orphan_passes: u32,
    /// Minimum group size (`u32::MAX` for any larger one).
    pub min_group: u32,
    /// Expanse limit as a fraction of the terrain area (infinite for none: `"inf"` in JSON, see [`crate::limit`]).
    #[serde(with = "crate::limit")]
    pub max_expanse: f64,
    /// Seed of the random generator.
    pub rng_seed: u64,
    /// Undersampling-fix radius used for the horizons, if any.
    pub undersampling: Option<f64>,
    /// How the triangles were grouped into nodes (format version 2; version-1 files read as [`Grouping::Crystal`]).
    /// It must stay the last field of the file: see [`crate::file`].
    #[serde(default)]
    pub grouping: Grouping,
}

/// How a hierarchy's nodes were formed; it decides which region test the nodes are meant for
/// ([`crate::CullMethod::Thesis`] or [`crate::CullMethod::Stewart`]).
///
/// In JSON it is named as on the command line: `"crystal"`, or `{"quadtree": {"built_depth": …, "stored_depth": …}}`
/// (the binary `.tch` stores the variant's index, not its name).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Grouping {
    /// Crystal groups and their merge hierarchy (the thesis, 5.2.3 and 6.3). Must stay variant 0: see
    /// [`crate::file`].
    #[default]
    Crystal,
    /// Stewart's (1997) quadtree over the footprint (crate `quadtree`): every node a non-empty square cell.
    Quadtree {
        /// The finest depth built (the root is depth 0).
        built_depth: u32,
        /// The finest depth stored, after memory levels were dropped to fit a byte budget; its cells are the leaves.
        stored_depth: u32,
    },
}

impl Grouping {
    /// The grouping's name in reports and on the command line (`crystal`, `quadtree`).
    pub fn name(self) -> &'static str {
        match self {
            Grouping::Crystal => "crystal",
            Grouping::Quadtree { .. } => "quadtree",
        }
    }

    /// Whether this is a quadtree.
    pub fn is_quadtree(self) -> bool {
        matches!(self, Grouping::Quadtree { .. })
    }
}

/// The exported hierarchy: sector count, local origin, nodes, top-level nodes, the always-visible range, and the
/// reordered mesh.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Hierarchy {
    /// Number of sectors `s` of the regions.
    pub sectors: u32,
    /// Local origin subtracted from positions before anything is stored in f32.
    pub origin: [f64; 3],
    /// All nodes.
    pub nodes: Vec<Node>,
    /// Top-level nodes, tested first by the culler.
    pub roots: Vec<u32>,
    /// Triangles drawn whatever the camera (orphans): `[start, end)`, the end of the triangle order.
    pub always_visible: [u32; 2],
    /// The reordered mesh.
    pub mesh: Mesh,
    /// How it was built.
    pub build: BuildInfo,
}

impl Hierarchy {
    /// The unit centre direction of sector `i`, as `[x, y]`.
    pub fn sector_direction(&self, i: u32) -> [f64; 2] {
        sector_direction(self.sectors, i)
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.mesh.triangles.len()
    }

    /// The triangle ranges of the leaf groups in triangle order; group `i` of the exports and renders is the `i`-th.
    pub fn leaf_ranges(&self) -> Vec<[u32; 2]> {
        let mut leaves: Vec<[u32; 2]> = self
            .nodes
            .iter()
            .filter(|n| n.children.is_empty())
            .map(|n| n.triangles)
            .collect();
        leaves.sort_unstable();
        leaves
    }

    /// Whether any node holds a region: none in a hierarchy built without them (`tincull build --no-regions`), where
    /// the region tests ([`crate::CullMethod::Thesis`], [`crate::CullMethod::Stewart`]) cull nothing.
    pub fn has_regions(&self) -> bool {
        self.nodes.iter().any(|n| !n.regions.is_empty())
    }

    /// Bytes of visibility data: regions, circles, ranges and child links (not the mesh).
    pub fn visibility_bytes(&self) -> usize {
        self.nodes
            .iter()
            .map(|n| {
                let regions: usize = n.regions.iter().map(|r| 2 + 4 + 8 * r.points.len()).sum();
                12 + 8 + 4 + 4 * n.children.len() + regions
            })
            .sum::<usize>()
            + 4 * self.roots.len()
    }

    /// Checks every structural invariant, so that a loaded file can never make the culler index out of range or
    /// loop: counts and indices in range, regions well formed and in increasing sector order, node ranges nested
    /// (a parent's range is exactly the union of its children's, which are contiguous), the nodes form a forest whose
    /// roots are `roots`, the roots' ranges and the always-visible range (which closes the triangle order) hold every
    /// triangle once, and coordinates lie within the mesh readers' limits.
    pub fn check_invariants(&self) -> Result<(), HierarchyError> {
        let invalid = |m: String| Err(HierarchyError::Invalid(m));
        if self.sectors == 0 || self.sectors > 1024 {
            return invalid(format!("sector count {} is out of range 1..=1024", self.sectors));
        }
        if !self.origin.iter().all(|c| c.abs() <= COORDINATE_LIMIT) {
            return invalid(format!(
                "the origin {:?} is not finite or beyond 2^100 in magnitude",
                self.origin
            ));
        }
        let nv = self.mesh.positions.len();
        let nt = self.mesh.triangles.len() as u64;
        if let Some(i) = self
            .mesh
            .positions
            .iter()
            .position(|p| !p.iter().all(|&c| coordinate_in_range(c)))
        {
            return invalid(format!(
                "vertex {i} at {:?} has a coordinate that is not finite, or not 0 and outside 2^-100 ..= 2^100 in \
                 magnitude (the range every mesh reader accepts)",
                self.mesh.positions[i]
            ));
        }
        if let Some(t) = self
            .mesh
            .triangles
            .iter()
            .position(|t| t.iter().any(|&v| v as usize >= nv))
        {
            return invalid(format!("triangle {t} refers to a vertex beyond {nv}"));
        }
        let [av0, av1] = self.always_visible;
        if av0 > av1 || u64::from(av1) != nt {
            return invalid(format!(
                "always-visible range [{av0}, {av1}) does not end the {nt} triangles"
            ));
        }
        let regions: u64 = self.nodes.iter().map(|n| n.regions.len() as u64).sum();
        let points: u64 = self
            .nodes
            .iter()
            .flat_map(|n| &n.regions)
            .map(|r| r.points.len() as u64 + 1)
            .sum();
        if regions >= MAX_REGIONS || points >= MAX_REGION_POINTS {
            return invalid(format!(
                "{regions} regions of {points} vertices and tails: the cullers hold fewer than {MAX_REGIONS} and \
                 {MAX_REGION_POINTS}"
            ));
        }
        let n = self.nodes.len();
        let mut parent = vec![u32::MAX; n];
        for (i, node) in self.nodes.iter().enumerate() {
            let [s, e] = node.triangles;
            if s > e || e > av0 {
                return invalid(format!("node {i} has triangle range [{s}, {e}) outside [0, {av0})"));
            }
            if !(node.radius >= 0.0 && node.radius.is_finite() && node.centre.iter().all(|c| c.is_finite())) {
                return invalid(format!("node {i} has an invalid bounding circle"));
            }
            let mut last_sector = None;
            for r in &node.regions {
                if u32::from(r.sector) >= self.sectors || last_sector.is_some_and(|l| l >= r.sector) {
                    return invalid(format!("node {i} has regions out of sector order"));
                }
                last_sector = Some(r.sector);
                let ok = !r.points.is_empty()
                    && r.tail_slope.is_finite()
                    && r.points.iter().all(|p| p[0].is_finite() && p[1].is_finite())
                    && r.points.windows(2).all(|w| w[0][0] < w[1][0]);
                if !ok {
                    return invalid(format!("node {i} has a malformed region in sector {}", r.sector));
                }
            }
            if !node.children.is_empty() {
                let mut at = s;
                for &c in &node.children {
                    let Some(child) = self.nodes.get(c as usize) else {
                        return invalid(format!("node {i} has child {c} beyond {n}"));
                    };
                    if c as usize == i || parent[c as usize] != u32::MAX {
                        return invalid(format!("node {c} has more than one parent"));
                    }
                    parent[c as usize] = i as u32;
                    if child.triangles[0] != at || child.level >= node.level {
                        return invalid(format!("children of node {i} are not contiguous, ordered and lower"));
                    }
                    at = child.triangles[1];
                }
                if at != e {
                    return invalid(format!("children of node {i} do not cover its range"));
                }
            } else if node.level != 0 {
                return invalid(format!("leaf node {i} is not at level 0"));
            }
        }
        let mut is_root = vec![false; n];
        for &r in &self.roots {
            match is_root.get_mut(r as usize) {
                Some(flag) if !*flag && parent[r as usize] == u32::MAX => *flag = true,
                _ => return invalid(format!("root {r} is out of range, repeated or has a parent")),
            }
        }
        if let Some(i) = (0..n).find(|&i| parent[i] == u32::MAX && !is_root[i]) {
            return invalid(format!("node {i} has no parent and is not a root"));
        }
        // Levels strictly decrease from parent to child, so there is no cycle. The roots' ranges tile the triangles
        // before the always-visible ones, without overlap or gap: a triangle in no node would never be drawn.
        let mut ranges: Vec<[u32; 2]> = self.roots.iter().map(|&r| self.nodes[r as usize].triangles).collect();
        ranges.sort_unstable();
        if ranges.windows(2).any(|w| w[0][1] > w[1][0]) {
            return invalid("top-level nodes overlap".into());
        }
        let mut at = 0;
        for [s, e] in ranges {
            if s != at {
                return invalid(format!("triangles [{at}, {s}) are in no node and not always visible"));
            }
            at = e;
        }
        if at != av0 {
            return invalid(format!("triangles [{at}, {av0}) are in no node and not always visible"));
        }
        Ok(())
    }
}
