//! Shared test fixtures: a tiny hand-made hierarchy with known groups, regions and orphans, and the GPU (or a SKIP).

#![allow(dead_code)]

use std::sync::OnceLock;

use cull::{BuildInfo, Hierarchy, Mesh, Node, StoredRegion};
use viewer::{Gpu, gpu_required};

/// World origin of the fixture (UTM-sized, so the relative conversion matters).
pub const ORIGIN: [f64; 3] = [512_000.0, 4_180_000.0, 300.0];
/// Cells per side of the grid; each quadrant is `CELLS / 2` cells square.
pub const CELLS: u32 = 4;
/// Side of the square terrain (m).
pub const SIDE: f64 = 100.0;

/// A flat 100 m square of 4 × 4 cells (32 triangles) in four quadrants:
///
/// | quadrant | triangles | role |
/// | --- | --- | --- |
/// | south-west | `[0, 8)` | leaf A (group 0), never occluded |
/// | south-east | `[8, 16)` | leaf B (group 1), occluded from everywhere below 10 km outside its circle |
/// | north-west | `[16, 24)` | leaf C (group 2), never occluded |
/// | north-east | `[24, 32)` | orphans (always visible) |
///
/// Node 2 merges A and B (level 1); the roots are 2 and 3 (C). Four sectors.
pub fn tiny_hierarchy() -> Hierarchy {
    let n = CELLS + 1;
    let step = SIDE / f64::from(CELLS);
    let mut positions = Vec::new();
    for j in 0..n {
        for i in 0..n {
            positions.push([
                ORIGIN[0] + f64::from(i) * step,
                ORIGIN[1] + f64::from(j) * step,
                ORIGIN[2],
            ]);
        }
    }
    let v = |i: u32, j: u32| j * n + i;
    let quadrant = |qi: u32, qj: u32| {
        let mut tris = Vec::new();
        let h = CELLS / 2;
        for j in qj * h..(qj + 1) * h {
            for i in qi * h..(qi + 1) * h {
                tris.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
                tris.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
            }
        }
        tris
    };
    let mut triangles = quadrant(0, 0);
    triangles.extend(quadrant(1, 0));
    triangles.extend(quadrant(0, 1));
    triangles.extend(quadrant(1, 1));
    let circle = |qi: f32, qj: f32| {
        let q = (SIDE / 2.0) as f32;
        (
            [q * (qi + 0.5), q * (qj + 0.5)],
            q * std::f32::consts::FRAC_1_SQRT_2 * 1.001,
        )
    };
    let hidden: Vec<StoredRegion> = (0..4)
        .map(|s| StoredRegion {
            sector: s,
            points: vec![[-1.0e6, 1.0e4]],
            tail_slope: 0.0,
        })
        .collect();
    let leaf = |c: ([f32; 2], f32), range: [u32; 2], regions: Vec<StoredRegion>| Node {
        centre: c.0,
        radius: c.1,
        children: vec![],
        triangles: range,
        level: 0,
        regions,
    };
    let nodes = vec![
        leaf(circle(0.0, 0.0), [0, 8], vec![]),
        leaf(circle(1.0, 0.0), [8, 16], hidden),
        Node {
            centre: [50.0, 25.0],
            radius: 56.0,
            children: vec![0, 1],
            triangles: [0, 16],
            level: 1,
            regions: vec![],
        },
        leaf(circle(0.0, 1.0), [16, 24], vec![]),
    ];
    let h = Hierarchy {
        sectors: 4,
        origin: ORIGIN,
        nodes,
        roots: vec![2, 3],
        always_visible: [24, 32],
        mesh: Mesh { positions, triangles },
        build: BuildInfo::default(),
    };
    h.check_invariants().expect("the fixture is a valid hierarchy");
    h
}

/// World point from local fixture coordinates.
pub fn world(x: f64, y: f64, z: f64) -> [f64; 3] {
    [ORIGIN[0] + x, ORIGIN[1] + y, ORIGIN[2] + z]
}

/// The headless GPU, or `None` after printing a SKIP notice; panics instead when `TINCULL_REQUIRE_GPU` is set.
pub fn gpu() -> Option<&'static Gpu> {
    static GPU: OnceLock<Option<Gpu>> = OnceLock::new();
    GPU.get_or_init(|| match Gpu::headless() {
        Ok(g) => {
            eprintln!("GPU: {}", g.describe());
            Some(g)
        }
        Err(e) if gpu_required() => panic!("TINCULL_REQUIRE_GPU is set but no GPU is usable: {e}"),
        Err(e) => {
            eprintln!("SKIP: no GPU adapter, GPU test not run ({e}); set TINCULL_REQUIRE_GPU=1 to make this an error");
            None
        }
    })
    .as_ref()
}

/// Whether two colours are within `tol` per channel.
pub fn close(a: [u8; 4], b: [u8; 4], tol: u8) -> bool {
    a.iter().zip(&b).all(|(x, y)| x.abs_diff(*y) <= tol)
}

/// A display colour shaded by the flat-terrain hillshade, as the renderer writes it.
pub fn shaded(c: [f64; 3]) -> [u8; 4] {
    let s = f64::from(viewer::render::hillshade(glam::Vec3::Z));
    viewer::palette::to_rgba8([c[0] * s, c[1] * s, c[2] * s])
}
