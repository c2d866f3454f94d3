//! The recursive run-time culler (thesis 5.3, with the frustum restriction of 5.1.1; design.md "Run-time test").
//!
//! For each top-level node: a camera inside the node's bounding circle sees it. Otherwise the directions from the
//! node's points to the camera lie within `azimuth(c − centre) ± asin(radius / distance)`; the node is culled when, for
//! every sector that interval touches, the camera projected into that sector's plane lies strictly inside the node's
//! region (an empty region in any touched sector means visible). With a horizontal field of view below 360°, a node
//! whose directions from the camera miss the view is culled first. A visible leaf is drawn; a visible inner node
//! recurses into its children. The always-visible range is always drawn.

use std::f64::consts::{PI, TAU};

use crate::hierarchy::{Hierarchy, StoredRegion};
use crate::sector::{azimuth, for_each_sector_in};

/// A camera: position in world coordinates and an optional horizontal view restriction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position, world coordinates (m).
    pub position: [f64; 3],
    /// View direction as an azimuth in radians, counter-clockwise from +x; ignored at a 360° field of view.
    pub yaw: f64,
    /// Horizontal field of view in radians; `2π` (the default) means no frustum restriction.
    pub hfov: f64,
}

impl Camera {
    /// A camera at `position` looking all around (360°), the thesis' measurement mode.
    pub fn all_around(position: [f64; 3]) -> Camera {
        Camera {
            position,
            yaw: 0.0,
            hfov: TAU,
        }
    }
}

/// Counters of one cull.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct CullStats {
    /// Nodes whose test ran.
    pub nodes_tested: u32,
    /// Nodes never tested because an ancestor was culled.
    pub nodes_skipped: u32,
    /// Nodes culled by the occlusion test.
    pub culled_by_occlusion: u32,
    /// Nodes culled by the frustum test.
    pub culled_by_frustum: u32,
    /// Triangles in the drawn ranges.
    pub triangles_drawn: u32,
    /// Triangles not drawn.
    pub triangles_culled: u32,
}

/// The result of a cull: half-open triangle ranges to draw (ascending, adjacent ranges merged) and counters.
/// Reuse one `DrawList` across calls to avoid allocation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DrawList {
    /// `[start, end)` ranges over the hierarchy's triangle order.
    pub ranges: Vec<[u32; 2]>,
    /// Counters.
    pub stats: CullStats,
}

impl DrawList {
    fn push(&mut self, [s, e]: [u32; 2]) {
        if s == e {
            return;
        }
        self.stats.triangles_drawn += e - s;
        match self.ranges.last_mut() {
            Some(last) if last[1] == s => last[1] = e,
            _ => self.ranges.push([s, e]),
        }
    }

    /// Marks every triangle of the drawn ranges in a per-triangle mask.
    pub fn mask(&self, triangles: usize) -> Vec<bool> {
        let mut m = vec![false; triangles];
        for &[s, e] in &self.ranges {
            m[s as usize..e as usize].fill(true);
        }
        m
    }
}

const NO_REGION: u32 = u32::MAX;

#[derive(Clone, Debug)]
struct FlatNode {
    centre: [f64; 2],
    radius: f64,
    children: [u32; 2],
    triangles: [u32; 2],
}

/// The run-time culler over a [`Hierarchy`]: flattened f64 copies of the node data, `Send + Sync`, no allocation per
/// call once the [`DrawList`] has grown to size.
#[derive(Clone, Debug)]
pub struct Culler {
    sectors: u32,
    origin: [f64; 3],
    directions: Vec<[f64; 2]>,
    nodes: Vec<FlatNode>,
    child_list: Vec<u32>,
    roots: Vec<u32>,
    /// `region_of[node * sectors + sector]`: index into `regions`, or `NO_REGION`.
    region_of: Vec<u32>,
    regions: Vec<StoredRegion>,
    always_visible: [u32; 2],
    triangles: u32,
}

impl Culler {
    /// Prepares a culler for `h` (which must satisfy [`Hierarchy::check_invariants`], as every loaded file does).
    pub fn new(h: &Hierarchy) -> Culler {
        let s = h.sectors as usize;
        let mut region_of = vec![NO_REGION; h.nodes.len() * s];
        let mut regions = Vec::new();
        let mut child_list = Vec::new();
        let nodes = h
            .nodes
            .iter()
            .enumerate()
            .map(|(i, n)| {
                for r in &n.regions {
                    region_of[i * s + r.sector as usize] = regions.len() as u32;
                    regions.push(r.clone());
                }
                let first = child_list.len() as u32;
                child_list.extend_from_slice(&n.children);
                FlatNode {
                    centre: [f64::from(n.centre[0]), f64::from(n.centre[1])],
                    radius: f64::from(n.radius),
                    children: [first, child_list.len() as u32],
                    triangles: n.triangles,
                }
            })
            .collect();
        let mut roots = h.roots.clone();
        roots.sort_by_key(|&r| h.nodes[r as usize].triangles[0]);
        Culler {
            sectors: h.sectors,
            origin: h.origin,
            directions: (0..h.sectors).map(|i| h.sector_direction(i)).collect(),
            nodes,
            child_list,
            roots,
            region_of,
            regions,
            always_visible: h.always_visible,
            triangles: h.mesh.triangles.len() as u32,
        }
    }

    /// Culls for `camera`, returning a new draw list.
    pub fn cull(&self, camera: &Camera) -> DrawList {
        let mut out = DrawList::default();
        self.cull_into(camera, &mut out);
        out
    }

    /// Culls for `camera` into `out` (cleared first), without allocating once `out` has grown.
    pub fn cull_into(&self, camera: &Camera, out: &mut DrawList) {
        out.ranges.clear();
        out.stats = CullStats::default();
        let eye = [
            camera.position[0] - self.origin[0],
            camera.position[1] - self.origin[1],
            camera.position[2] - self.origin[2],
        ];
        let frustum = (camera.hfov < TAU).then_some((camera.yaw, camera.hfov * 0.5));
        for &r in &self.roots {
            self.visit(r, eye, frustum, out);
        }
        out.push(self.always_visible);
        out.stats.nodes_skipped = self.nodes.len() as u32 - out.stats.nodes_tested;
        out.stats.triangles_culled = self.triangles - out.stats.triangles_drawn;
    }

    fn visit(&self, index: u32, eye: [f64; 3], frustum: Option<(f64, f64)>, out: &mut DrawList) {
        let node = &self.nodes[index as usize];
        out.stats.nodes_tested += 1;
        match self.test(index, node, eye, frustum) {
            Verdict::CulledByFrustum => out.stats.culled_by_frustum += 1,
            Verdict::CulledByOcclusion => out.stats.culled_by_occlusion += 1,
            Verdict::Visible => {
                let [c0, c1] = node.children;
                if c0 == c1 {
                    out.push(node.triangles);
                } else {
                    for &c in &self.child_list[c0 as usize..c1 as usize] {
                        self.visit(c, eye, frustum, out);
                    }
                }
            }
        }
    }

    fn test(&self, index: u32, node: &FlatNode, eye: [f64; 3], frustum: Option<(f64, f64)>) -> Verdict {
        let (dx, dy) = (eye[0] - node.centre[0], eye[1] - node.centre[1]);
        let dist2 = dx * dx + dy * dy;
        if dist2 <= node.radius * node.radius {
            return Verdict::Visible;
        }
        // asin(r / d) ≤ π/2; rounding of r / d can only be compensated by the strict tests below, so widen slightly.
        let half = (node.radius / dist2.sqrt()).min(1.0).asin() * (1.0 + 1e-12);
        let to_eye = azimuth(dx, dy);
        if let Some((yaw, half_fov)) = frustum {
            // Directions from the eye to the node's points lie within the opposite interval.
            let to_node = to_eye + PI;
            let gap = (to_node - yaw + PI).rem_euclid(TAU) - PI;
            if gap.abs() > half_fov + half {
                return Verdict::CulledByFrustum;
            }
        }
        let base = index as usize * self.sectors as usize;
        let hidden = for_each_sector_in(self.sectors, to_eye, half, |sector| {
            let r = self.region_of[base + sector as usize];
            if r == NO_REGION {
                return false;
            }
            let [rx, ry] = self.directions[sector as usize];
            self.regions[r as usize].contains(rx * eye[0] + ry * eye[1], eye[2])
        });
        if hidden {
            Verdict::CulledByOcclusion
        } else {
            Verdict::Visible
        }
    }
}

enum Verdict {
    Visible,
    CulledByFrustum,
    CulledByOcclusion,
}
