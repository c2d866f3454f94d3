//! CPU side of the viewer, no GPU needed: colours per triangle (groups, levels, visibility, height), the palette,
//! heights under a point, the per-vertex expansion, PNG writing and reading.

mod common;

use common::{ORIGIN, tiny_hierarchy, world};
use proptest::prelude::*;
use viewer::palette::{self, ORPHAN_COLOUR, group_colour, to_rgba8};
use viewer::scene::flat_vertices;
use viewer::{ColourMode, RgbaImage, Terrain};

#[test]
fn groups_colour_each_leaf_in_triangle_order_and_orphans_grey() {
    let t = Terrain::from_hierarchy(tiny_hierarchy()).unwrap();
    assert_eq!(t.groups, 3);
    let c = t.colours(ColourMode::Groups, None, None).unwrap();
    for (tri, colour) in c.iter().enumerate() {
        let expected = match tri {
            0..8 => to_rgba8(group_colour(0)),
            8..16 => to_rgba8(group_colour(1)),
            16..24 => to_rgba8(group_colour(2)),
            _ => to_rgba8(ORPHAN_COLOUR),
        };
        assert_eq!(*colour, expected, "triangle {tri}");
    }
}

#[test]
fn level_colouring_merges_children_at_their_parents_level() {
    let t = Terrain::from_hierarchy(tiny_hierarchy()).unwrap();
    assert_eq!(t.max_level(), 1);
    // Level 0: the leaves, as in the groups colouring.
    let l0 = t.colours(ColourMode::Level, Some(0), None).unwrap();
    assert_eq!(l0, t.colours(ColourMode::Groups, None, None).unwrap());
    // Level 1 (the default, the top): A and B share node 2's colour; C is next; orphans grey.
    let l1 = t.colours(ColourMode::Level, None, None).unwrap();
    assert!(l1[..16].iter().all(|&c| c == to_rgba8(group_colour(0))));
    assert!(l1[16..24].iter().all(|&c| c == to_rgba8(group_colour(1))));
    assert!(l1[24..].iter().all(|&c| c == to_rgba8(ORPHAN_COLOUR)));
}

#[test]
fn visibility_colouring_follows_the_mask_and_needs_one() {
    let t = Terrain::from_hierarchy(tiny_hierarchy()).unwrap();
    let mask: Vec<bool> = (0..32).map(|i| !(8..16).contains(&i)).collect();
    let c = t.colours(ColourMode::Visibility, None, Some(&mask)).unwrap();
    for (i, &m) in mask.iter().enumerate() {
        let want = if m {
            palette::DRAWN_COLOUR
        } else {
            palette::CULLED_COLOUR
        };
        assert_eq!(c[i], to_rgba8(want));
    }
    assert!(t.colours(ColourMode::Visibility, None, None).is_err());
    assert!(t.colours(ColourMode::Visibility, None, Some(&mask[..5])).is_err());
}

#[test]
fn plain_meshes_colour_by_height_only() {
    let h = tiny_hierarchy();
    let positions = h
        .mesh
        .positions
        .iter()
        .map(|p| glam::DVec3::new(p[0], p[1], p[2] + (p[0] - ORIGIN[0])))
        .collect();
    let tin = tin::Tin::from_parts(positions, h.mesh.triangles.clone()).unwrap();
    let t = Terrain::from_tin(&tin).unwrap();
    assert!(t.hierarchy.is_none());
    for mode in [ColourMode::Groups, ColourMode::Level] {
        let err = t.colours(mode, None, None).unwrap_err().to_string();
        assert!(err.contains("needs a hierarchy"), "{err}");
    }
    let c = t.colours(ColourMode::Height, None, None).unwrap();
    // The lowest column (x in 0..25) is greener than the highest (x in 75..100).
    let low = t
        .triangles
        .iter()
        .position(|tri| {
            tri.iter()
                .all(|&v| t.positions[v as usize][0] <= 25.0 - (t.origin[0] - ORIGIN[0]) as f32)
        })
        .unwrap();
    let high = t
        .triangles
        .iter()
        .position(|tri| {
            tri.iter()
                .all(|&v| t.positions[v as usize][0] >= 75.0 - (t.origin[0] - ORIGIN[0]) as f32)
        })
        .unwrap();
    assert_ne!(c[low], c[high]);
    assert!(c[low][1] > c[low][0], "lowland is green: {:?}", c[low]);
}

#[test]
fn positions_are_relative_to_the_hierarchy_origin() {
    let t = Terrain::from_hierarchy(tiny_hierarchy()).unwrap();
    assert_eq!(t.origin, ORIGIN);
    assert_eq!(t.min, [0.0, 0.0, 0.0]);
    assert_eq!(t.max, [100.0, 100.0, 0.0]);
    assert_eq!(t.to_local(world(12.5, 50.0, 2.0)), [12.5, 50.0, 2.0]);
    assert_eq!(t.to_world([12.5, 50.0, 2.0]), world(12.5, 50.0, 2.0));
}

#[test]
fn group_colours_are_distinct_and_match_the_golden_ratio_scheme() {
    // The first colours, as the grouped OBJ's .mtl has always written them.
    let c0 = group_colour(0);
    assert!((c0[0] - 0.92).abs() < 1e-12 && (c0[1] - 0.322).abs() < 1e-12 && (c0[2] - 0.322).abs() < 1e-12);
    let rgb: Vec<[u8; 4]> = (0..64).map(|i| to_rgba8(group_colour(i))).collect();
    for i in 0..63 {
        let d: u32 = (0..3).map(|k| u32::from(rgb[i][k].abs_diff(rgb[i + 1][k]))).sum();
        assert!(d > 60, "groups {i} and {} look alike", i + 1);
        assert_ne!(rgb[i], to_rgba8(ORPHAN_COLOUR));
    }
}

#[test]
fn png_round_trips_and_writes_atomically() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("img.png");
    let img = RgbaImage {
        width: 3,
        height: 2,
        pixels: (0..24).map(|i| (i * 10) as u8).collect(),
    };
    viewer::write_png(&path, &img).unwrap();
    assert_eq!(viewer::read_png(&path).unwrap(), img);
    // Only the image is left in the directory (no temporary files).
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    // A malformed image is rejected and nothing is written.
    let bad = RgbaImage {
        width: 3,
        height: 3,
        pixels: vec![0; 4],
    };
    let other = dir.path().join("bad.png");
    let err = viewer::write_png(&other, &bad).unwrap_err().to_string();
    assert!(err.contains("bad.png"), "{err}");
    assert!(!other.exists());
    // Not a PNG: a clear error naming the file.
    std::fs::write(&other, b"not a png").unwrap();
    assert!(viewer::read_png(&other).unwrap_err().to_string().contains("bad.png"));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Three vertices per triangle with its upward face normal, whatever the (counter-clockwise) triangle.
    #[test]
    fn flat_vertices_carry_face_normals(p in proptest::collection::vec((-1e4f32..1e4, -1e4f32..1e4, -1e3f32..1e3), 3)) {
        let positions: Vec<[f32; 3]> = p.iter().map(|&(x, y, z)| [x, y, z]).collect();
        let [a, b, c] = [positions[0], positions[1], positions[2]];
        let area = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        prop_assume!(area.abs() > 1.0);
        let tri = if area > 0.0 { [0, 1, 2] } else { [0, 2, 1] };
        let v = flat_vertices(&positions, &[tri]);
        prop_assert_eq!(v.len(), 3);
        for vert in &v {
            let n = glam::Vec3::new(vert[3], vert[4], vert[5]);
            prop_assert!((n.length() - 1.0).abs() < 1e-4);
            prop_assert!(n.z > 0.0, "a counter-clockwise terrain triangle faces up: {n}");
        }
        prop_assert_eq!(&v[0][3..], &v[2][3..]);
    }

    /// The height ramp stays in [0, 1] and clamps out-of-range and non-finite input.
    #[test]
    fn height_ramp_is_bounded(t in prop_oneof![-10.0f64..10.0, Just(f64::NAN), Just(f64::INFINITY)]) {
        let c = palette::height_colour(t);
        prop_assert!(c.iter().all(|v| (0.0..=1.0).contains(v)));
    }
}
