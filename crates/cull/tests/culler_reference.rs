//! The optimised culler against the straightforward reference (`reference/mod.rs`): identical draw lists and
//! counters on random hierarchies (trees of several levels, 1 to 40 sectors) for random cameras, cameras placed
//! exactly on sector boundaries and tangents, inside and on bounding circles, with and without a frustum.

mod reference;

use std::f64::consts::TAU;

use cull::{Camera, Culler, Hierarchy, Mesh, Node, StoredRegion, sector_direction};
use proptest::prelude::*;
use reference::{ReferenceCuller, compare};

/// SplitMix64: one seed names a whole scene.
struct Gen(u64);

impl Gen {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next() >> 11) as f64 / (1u64 << 53) as f64)
    }
    fn below(&mut self, n: u32) -> u32 {
        (self.next() % u64::from(n)) as u32
    }
}

fn regions(g: &mut Gen, sectors: u32, centre: [f32; 2]) -> Vec<StoredRegion> {
    let present: Vec<u32> = (0..sectors).filter(|_| g.below(6) != 0).collect();
    present
        .into_iter()
        .map(|sector| {
            let [rx, ry] = sector_direction(sectors, sector);
            let mut t = rx * f64::from(centre[0]) + ry * f64::from(centre[1]) + g.range(-200.0, 150.0);
            let mut z = g.range(-20.0, 90.0);
            let mut points = vec![[t as f32, z as f32]];
            for _ in 0..g.below(4) {
                t += g.range(0.5, 150.0);
                z += g.range(-50.0, 40.0);
                points.push([t as f32, z as f32]);
            }
            StoredRegion {
                sector: sector as u16,
                points,
                tail_slope: g.range(-0.6, 0.4) as f32,
            }
        })
        .collect()
}

/// Leaves with one triangle each (a few empty ones), merged in rounds into parents over runs of consecutive nodes,
/// an origin far from zero, and a few always-visible triangles.
fn tree(g: &mut Gen, sectors: u32) -> Hierarchy {
    let leaves = 1 + g.below(24);
    let mut nodes = Vec::new();
    let mut at = 0;
    for _ in 0..leaves {
        let centre = [g.range(-400.0, 400.0) as f32, g.range(-400.0, 400.0) as f32];
        let size = u32::from(g.below(8) != 0);
        nodes.push(Node {
            centre,
            radius: if g.below(12) == 0 {
                0.0
            } else {
                g.range(0.5, 60.0) as f32
            },
            children: vec![],
            triangles: [at, at + size],
            level: 0,
            regions: regions(g, sectors, centre),
        });
        at += size;
    }
    let mut top: Vec<u32> = (0..leaves).collect();
    for _ in 0..g.below(4) {
        let mut next = Vec::new();
        let mut k = 0;
        while k < top.len() {
            let run = (1 + g.below(3) as usize).min(top.len() - k);
            if run == 1 {
                next.push(top[k]);
            } else {
                let children: Vec<u32> = top[k..k + run].to_vec();
                let first = &nodes[children[0] as usize];
                let last = &nodes[children[run - 1] as usize];
                let triangles = [first.triangles[0], last.triangles[1]];
                let level = 1 + children.iter().map(|&c| nodes[c as usize].level).max().unwrap_or(0);
                let centre = first.centre;
                nodes.push(Node {
                    centre,
                    radius: g.range(20.0, 200.0) as f32,
                    children,
                    triangles,
                    level,
                    regions: regions(g, sectors, centre),
                });
                next.push(nodes.len() as u32 - 1);
            }
            k += run;
        }
        top = next;
    }
    // Roots listed in any order: the culler visits them by triangle range.
    let mut roots = top;
    if g.below(2) == 0 {
        roots.reverse();
    }
    let always = g.below(3);
    let h = Hierarchy {
        sectors,
        origin: [
            g.range(-1e6, 1e6).round(),
            g.range(-1e6, 1e6).round(),
            g.range(-100.0, 100.0).round(),
        ],
        nodes,
        roots,
        always_visible: [at, at + always],
        mesh: Mesh {
            positions: vec![[0.0; 3]; 3],
            triangles: vec![[0, 1, 2]; (at + always) as usize],
        },
        build: Default::default(),
    };
    h.check_invariants().expect("valid tree");
    h
}

/// A camera in world coordinates: anywhere, or placed exactly relative to node `n`'s circle and a sector boundary.
fn camera(g: &mut Gen, h: &Hierarchy) -> Camera {
    let n = &h.nodes[g.below(h.nodes.len() as u32) as usize];
    let (cx, cy, r) = (f64::from(n.centre[0]), f64::from(n.centre[1]), f64::from(n.radius));
    let theta = TAU * f64::from(g.below(h.sectors)) / f64::from(h.sectors);
    let dist = r + g.range(0.0, 1.0).powi(3) * 900.0;
    let local = match g.below(7) {
        0 | 1 => [g.range(-700.0, 700.0), g.range(-700.0, 700.0)],
        2 => [cx + dist * theta.cos(), cy + dist * theta.sin()],
        3 | 4 => {
            let a = theta + if g.below(2) == 0 { 1.0 } else { -1.0 } * (r / dist).min(1.0).asin();
            [cx + dist * a.cos(), cy + dist * a.sin()]
        }
        5 => [cx + r * theta.cos(), cy + r * theta.sin()],
        _ => [cx, cy],
    };
    let o = h.origin;
    let position = [local[0] + o[0], local[1] + o[1], g.range(-40.0, 140.0) + o[2]];
    match g.below(4) {
        0 => Camera {
            position,
            yaw: g.range(-1.0, 7.0),
            hfov: g.range(0.05, 6.5),
        },
        _ => Camera::all_around(position),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn same_draw_list_as_the_reference(seed in any::<u64>()) {
        let mut g = Gen(seed);
        let sectors = [1, 2, 3, 4, 5, 7, 8, 16, 16, 16, 17, 32, 40][g.below(13) as usize];
        let h = tree(&mut g, sectors);
        let culler = Culler::new(&h);
        let reference = ReferenceCuller::new(&h);
        let mut out = cull::DrawList::default();
        for _ in 0..40 {
            let cam = camera(&mut g, &h);
            culler.cull_into(&cam, &mut out);
            let want = reference.cull(&cam);
            if let Err(e) = compare(&out, &want) {
                prop_assert!(false, "sectors {}, camera {:?}: {}", sectors, cam, e);
            }
        }
    }
}

/// The scenes above do cull: a check that the comparison is not between two all-visible lists.
#[test]
fn scenes_exercise_culling() {
    let mut g = Gen(11);
    let (mut culled, mut drawn, mut tested) = (0u32, 0u32, 0u32);
    for _ in 0..200 {
        let h = tree(&mut g, 16);
        let culler = Culler::new(&h);
        for _ in 0..20 {
            let cam = camera(&mut g, &h);
            let d = culler.cull(&cam);
            assert!(compare(&d, &ReferenceCuller::new(&h).cull(&cam)).is_ok());
            culled += d.stats.culled_by_occlusion;
            drawn += d.stats.triangles_drawn;
            tested += d.stats.nodes_tested;
        }
    }
    assert!(culled > tested / 20, "{culled} of {tested} tested nodes culled");
    assert!(drawn > 0);
}
