//! No PVS misses a visible triangle: adversarial terrains and random TINs, random viewcells, every triangle that the
//! exact checker (`truth`) sees from any of 64 sample points of the cell (corners, edges, interior, both heights)
//! must be in the PVS, for every method, several resolutions and patch sizes.
//!
//! The checker's visible set is a lower bound of the true one (finite samples), so every triangle it calls visible
//! really is: a PVS missing one of them is a bug.

#[path = "../../cull/tests/common/mod.rs"]
mod common;

use common::{grid_tin, hierarchy_of, notch, random_tin, splitmix};
use glam::DVec3;
use proptest::prelude::*;
use pvs::{Height, Method, Pvs, PvsParams, ViewCell, sample_eyes};
use tin::Tin;
use truth::GroundTruth;

/// Every configuration a PVS is checked under.
const CONFIGS: [(Method, u32, u32); 6] = [
    (Method::Koltun, 16, 16),
    (Method::Koltun, 64, 1),
    (Method::Koltun, 256, 4),
    (Method::Regions, 64, 16),
    (Method::Both, 32, 1),
    (Method::Both, 256, 16),
];

/// Checks the PVS of every cell under every configuration and hierarchy shape; returns, over all of them, the
/// triangles in the PVS and the triangles of the mesh (for tightness assertions).
fn assert_pvs_safe(name: &str, tin: &Tin, cells: &[ViewCell]) -> (u64, u64) {
    let truth = GroundTruth::new(tin);
    let nt = tin.num_triangles();
    let seen: Vec<(Vec<bool>, usize)> = cells
        .iter()
        .enumerate()
        .map(|(i, cell)| {
            let eyes = sample_eyes(&truth, cell, 7, i as u64);
            let mut union = vec![false; nt];
            for &eye in &eyes {
                for (u, v) in union.iter_mut().zip(truth.visible_triangles(eye)) {
                    *u |= v;
                }
            }
            (union, eyes.len())
        })
        .collect();
    let mut sizes = (0u64, 0u64);
    for (leaf, orphans) in [(8usize, 0usize), (40, 7)] {
        let (h, order) = hierarchy_of(tin, leaf, orphans);
        for (method, resolution, patch) in CONFIGS {
            let params = PvsParams {
                method,
                resolution,
                patch,
            };
            let pvs = Pvs::new(&h, params).expect("valid parameters");
            for (cell, (visible, eyes)) in cells.iter().zip(&seen) {
                let result = pvs.compute(cell).expect("a valid cell");
                let mask = result.mask(nt);
                for (i, &t) in order.iter().enumerate() {
                    assert!(
                        !visible[t as usize] || mask[i],
                        "{name}: triangle {t} {:?} is visible from one of {eyes} points of cell {cell:?} but not in \
                         its PVS ({params:?}, leaf {leaf}, orphans {orphans})",
                        tin.corners(t as usize)
                    );
                }
                sizes.0 += result.triangles();
                sizes.1 += nt as u64;
            }
        }
    }
    sizes
}

fn cell(x: f64, y: f64, size: f64, height: Height) -> ViewCell {
    ViewCell {
        rect: [x, y, x + size, y + size],
        height,
    }
}

const GROUND: Height = Height::AboveGround([0.0, 2.0]);
const LOW: Height = Height::AboveGround([0.0, 20.0]);

#[test]
fn ridge_with_a_notch() {
    let tin = grid_tin(41, 200.0, DVec3::ZERO, notch);
    let cells = [
        cell(20.0, 90.0, 20.0, GROUND),
        cell(30.0, 95.0, 10.0, LOW),
        cell(60.0, 60.0, 30.0, GROUND),
        cell(5.0, 5.0, 50.0, Height::Band([0.0, 6.0])),
        cell(95.0, 95.0, 10.0, GROUND),
        cell(120.0, 20.0, 40.0, LOW),
    ];
    let (pvs, all) = assert_pvs_safe("notch", &tin, &cells);
    assert!(pvs < all, "the ridge hides something: {pvs} of {all}");
}

#[test]
fn knife_edge_ridge_hides_the_far_side() {
    let tin = grid_tin(
        41,
        200.0,
        DVec3::ZERO,
        |x, _| if (x - 100.0).abs() < 1.0 { 50.0 } else { 0.0 },
    );
    let cells = [
        cell(20.0, 80.0, 30.0, GROUND),
        cell(40.0, 20.0, 50.0, LOW),
        cell(95.0, 95.0, 10.0, GROUND),
    ];
    let (pvs, all) = assert_pvs_safe("knife edge", &tin, &cells);
    assert!(
        (pvs as f64) < 0.8 * all as f64,
        "a 50 m wall hides most of the far half from low cells: {pvs} of {all}"
    );
}

#[test]
fn plateau_edge_and_grazing_cells() {
    let tin = grid_tin(31, 300.0, DVec3::ZERO, |x, _| if x < 150.0 { 20.0 } else { 0.0 });
    let cells = [
        cell(100.0, 140.0, 20.0, GROUND),
        cell(140.0, 140.0, 10.0, Height::Band([20.0, 20.0])),
        cell(180.0, 100.0, 50.0, LOW),
        cell(149.0, 10.0, 2.0, GROUND),
    ];
    assert_pvs_safe("plateau", &tin, &cells);
}

#[test]
fn rolling_hills_and_utm_offsets() {
    for offset in [DVec3::ZERO, DVec3::new(5e5, 5e6, 1000.0)] {
        let tin = grid_tin(21, 200.0, offset, |x, y| 10.0 * ((x / 40.0).sin() + (y / 55.0).cos()));
        let cells = [
            cell(offset.x + 10.0, offset.y + 10.0, 30.0, GROUND),
            cell(offset.x + 100.0, offset.y + 50.0, 50.0, LOW),
            cell(offset.x + 150.0, offset.y + 150.0, 40.0, GROUND),
        ];
        assert_pvs_safe("hills", &tin, &cells);
    }
}

/// `n` parallel slivers of width `spacing` (in y) from `x = 0` to `x = length`, rising by `rise · length` across it:
/// every strip's two long edges cross the whole terrain diagonally (the walls' grid walks them instead of registering
/// their boxes). Vertex `k` of the side `end` (false: `x = 0`) has the height `z(k, end)`.
fn slivers(n: u32, spacing: f64, length: f64, rise: f64, z: impl Fn(u32, bool) -> f64) -> Tin {
    let mut positions = Vec::new();
    for k in 0..=n {
        let d = spacing * f64::from(k);
        positions.push(DVec3::new(0.0, d, z(k, false)));
        positions.push(DVec3::new(length, rise * length + d, z(k, true)));
    }
    let triangles = (0..n)
        .flat_map(|k| [[2 * k, 2 * k + 1, 2 * k + 3], [2 * k, 2 * k + 3, 2 * k + 2]])
        .collect();
    Tin::from_parts(positions, triangles).expect("slivers make a valid TIN")
}

/// The audit's long diagonal slivers (F4), with a 12 m ridge along one of them: cells on both sides and on the ridge.
/// (Every sliver's box spans the terrain, so little can be hidden: this checks that nothing visible is. Each long edge
/// spans five grid cells or more, so the walls' grid walks it.)
#[test]
fn long_diagonal_slivers_with_a_ridge() {
    let ridge = |k: u32, end: bool| {
        let phase = if end { 1.3 } else { 0.0 };
        (0.21 * f64::from(k) + phase).sin() + if k == 30 { 12.0 } else { 0.0 }
    };
    let tin = slivers(60, 0.5, 60.0, 1.0, ridge);
    let cells = [
        cell(30.0, 10.0, 5.0, GROUND),
        cell(10.0, 50.0, 8.0, LOW),
        cell(30.0, 40.0, 3.0, Height::Band([0.0, 3.0])),
    ];
    assert_pvs_safe("slivers", &tin, &cells);
}

#[test]
fn bad_cells_are_refused() {
    let tin = grid_tin(5, 100.0, DVec3::ZERO, |_, _| 0.0);
    let (h, _) = hierarchy_of(&tin, 4, 0);
    let pvs = Pvs::new(&h, PvsParams::default()).expect("valid parameters");
    for c in [
        cell(0.0, 0.0, 0.0, GROUND),
        cell(f64::NAN, 0.0, 10.0, GROUND),
        cell(0.0, 0.0, 10.0, Height::Band([5.0, 1.0])),
        cell(0.0, 0.0, 10.0, Height::AboveGround([0.0, f64::INFINITY])),
    ] {
        assert!(pvs.compute(&c).is_err(), "{c:?}");
    }
    for resolution in [0, 257] {
        let params = PvsParams {
            resolution,
            ..PvsParams::default()
        };
        assert!(Pvs::new(&h, params).is_err());
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    /// Random TINs (random points, rough random heights) and random cells of random sizes and bands.
    #[test]
    fn random_tins_and_cells(seed in any::<u64>(), n in 20usize..160, rough in 0.0f64..3.0) {
        let mut next = splitmix(seed);
        let Some(tin) = random_tin(&mut next, n, rough) else { return Ok(()) };
        let mut cells = Vec::new();
        for k in 0..3 {
            let size = 5.0 + 100.0 * next();
            let (x, y) = (next() * 500.0 - 20.0, next() * 500.0 - 20.0);
            let height = match k {
                0 => GROUND,
                1 => Height::AboveGround([0.0, 30.0 * next()]),
                _ => Height::Band([0.0, 60.0 * next()]),
            };
            cells.push(cell(x, y, size, height));
        }
        assert_pvs_safe("random", &tin, &cells);
    }
}

proptest! {
    // The exact checker is slow on slivers (some 10 s a case): few cases, small terrains.
    #![proptest_config(ProptestConfig::with_cases(4))]

    /// Random long slivers (random count, width, length, slope, rough heights and ridges along a few of them) and
    /// random cells over them.
    #[test]
    fn random_slivers_and_cells(
        seed in any::<u64>(),
        n in 20u32..60,
        spacing in 0.25f64..1.0,
        length in 20.0f64..60.0,
        rise in -2.0f64..3.0,
    ) {
        let mut next = splitmix(seed);
        let ridges: Vec<(u32, f64)> = (0..3).map(|_| ((next() * f64::from(n)) as u32, 15.0 * next())).collect();
        let rough: Vec<f64> = (0..2 * (n + 1)).map(|_| 2.0 * next()).collect();
        let tin = slivers(n, spacing, length, rise, |k, end| {
            let ridge: f64 = ridges.iter().filter(|r| r.0 == k).map(|r| r.1).sum();
            rough[(2 * k + u32::from(end)) as usize] + ridge
        });
        let (ylo, yhi) = (rise.min(0.0) * length, rise.max(0.0) * length + spacing * f64::from(n));
        let mut cells = Vec::new();
        for k in 0..2 {
            let size = 1.0 + 0.2 * length * next();
            let (x, y) = (next() * length - 2.0, ylo + next() * (yhi - ylo) - 2.0);
            let height = if k == 0 {
                Height::AboveGround([0.0, 10.0 * next()])
            } else {
                Height::Band([0.0, 20.0 * next()])
            };
            cells.push(cell(x, y, size, height));
        }
        assert_pvs_safe("random slivers", &tin, &cells);
    }
}
