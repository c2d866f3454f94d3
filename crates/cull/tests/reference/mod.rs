//! A straightforward reference for the run-time culler: the rule of `cull::culler`'s module documentation written
//! out directly (recursion over the stored nodes, atan2 and asin for the azimuth interval, [`StoredRegion::contains`]
//! for every touched sector), as the culler computed it before it was optimised. The optimised [`cull::Culler`] must
//! give exactly the same draw list and counters for every camera.
//!
//! Shared by the crate's tests and the `cull` benchmark (which checks the optimised culler against it on built
//! hierarchies before timing).
#![allow(dead_code)]

use std::f64::consts::{PI, TAU};

use cull::{Camera, DrawList, Hierarchy, Node, StoredRegion, azimuth, for_each_sector_in};

/// The reference culler.
pub struct ReferenceCuller<'a> {
    h: &'a Hierarchy,
    roots: Vec<u32>,
    /// `region_of[node][sector]`.
    region_of: Vec<Vec<Option<&'a StoredRegion>>>,
}

enum Verdict {
    Visible,
    CulledByFrustum,
    CulledByOcclusion,
}

impl<'a> ReferenceCuller<'a> {
    /// Prepares the reference for `h`.
    pub fn new(h: &'a Hierarchy) -> Self {
        let mut roots = h.roots.clone();
        roots.sort_by_key(|&r| h.nodes[r as usize].triangles[0]);
        let region_of = h
            .nodes
            .iter()
            .map(|n| {
                (0..h.sectors)
                    .map(|s| n.regions.iter().find(|r| u32::from(r.sector) == s))
                    .collect()
            })
            .collect();
        ReferenceCuller { h, roots, region_of }
    }

    /// Culls for `camera`.
    pub fn cull(&self, camera: &Camera) -> DrawList {
        let mut out = DrawList::default();
        let o = self.h.origin;
        let eye = [
            camera.position[0] - o[0],
            camera.position[1] - o[1],
            camera.position[2] - o[2],
        ];
        let frustum = (camera.hfov < TAU).then_some((camera.yaw, camera.hfov * 0.5));
        for &r in &self.roots {
            self.visit(r, eye, frustum, &mut out);
        }
        push(&mut out, self.h.always_visible);
        out.stats.nodes_skipped = self.h.nodes.len() as u32 - out.stats.nodes_tested;
        out.stats.triangles_culled = self.h.mesh.triangles.len() as u32 - out.stats.triangles_drawn;
        out
    }

    fn visit(&self, index: u32, eye: [f64; 3], frustum: Option<(f64, f64)>, out: &mut DrawList) {
        let node = &self.h.nodes[index as usize];
        out.stats.nodes_tested += 1;
        match self.test(index, node, eye, frustum) {
            Verdict::CulledByFrustum => out.stats.culled_by_frustum += 1,
            Verdict::CulledByOcclusion => out.stats.culled_by_occlusion += 1,
            Verdict::Visible if node.children.is_empty() => push(out, node.triangles),
            Verdict::Visible => {
                for &c in &node.children {
                    self.visit(c, eye, frustum, out);
                }
            }
        }
    }

    fn test(&self, index: u32, node: &Node, eye: [f64; 3], frustum: Option<(f64, f64)>) -> Verdict {
        let (cx, cy, radius) = (
            f64::from(node.centre[0]),
            f64::from(node.centre[1]),
            f64::from(node.radius),
        );
        let (dx, dy) = (eye[0] - cx, eye[1] - cy);
        let dist2 = dx * dx + dy * dy;
        if dist2 <= radius * radius {
            return Verdict::Visible;
        }
        let half = (radius / dist2.sqrt()).min(1.0).asin() * (1.0 + 1e-12);
        let to_eye = azimuth(dx, dy);
        if let Some((yaw, half_fov)) = frustum {
            let to_node = to_eye + PI;
            let gap = (to_node - yaw + PI).rem_euclid(TAU) - PI;
            if gap.abs() > half_fov + half {
                return Verdict::CulledByFrustum;
            }
        }
        let hidden = for_each_sector_in(self.h.sectors, to_eye, half, |sector| {
            match self.region_of[index as usize][sector as usize] {
                None => false,
                Some(region) => {
                    let [rx, ry] = self.h.sector_direction(sector);
                    region.contains(rx * eye[0] + ry * eye[1], eye[2])
                }
            }
        });
        if hidden {
            Verdict::CulledByOcclusion
        } else {
            Verdict::Visible
        }
    }
}

fn push(out: &mut DrawList, [s, e]: [u32; 2]) {
    if s == e {
        return;
    }
    out.stats.triangles_drawn += e - s;
    match out.ranges.last_mut() {
        Some(last) if last[1] == s => last[1] = e,
        _ => out.ranges.push([s, e]),
    }
}

/// Compares the optimised culler's draw list with the reference's; `Err` names the first difference.
pub fn compare(got: &DrawList, want: &DrawList) -> Result<(), String> {
    if got.stats != want.stats {
        return Err(format!("counters differ: got {:?}, want {:?}", got.stats, want.stats));
    }
    if got.ranges != want.ranges {
        return Err(format!("ranges differ: got {:?}, want {:?}", got.ranges, want.ranges));
    }
    Ok(())
}
