//! The vertex-from-camera test that crystal growth uses ([`RegionTable::vertex_hidden_from`]) on horizon fields of
//! random TINs, at small and at UTM-sized coordinates: a camera standing on one of a vertex's own horizon vertices is
//! never hidden from it (the tie that defines the region's left bound goes to "visible", as the strict containment
//! rule says), and the test agrees with a straightforward evaluation of the region's definition in vertex-relative
//! terms.

use glam::{DVec2, DVec3};
use horizon::{HorizonField, HorizonOptions, HorizonPoint, SectorConfig, SectorGeometry, compute};
use occlusion::RegionTable;
use proptest::prelude::*;
use tin::{DedupePolicy, Tin, triangulate};

/// The configurations every test runs.
const CONFIGS: [(u32, u32); 5] = [(8, 1), (8, 4), (16, 2), (5, 3), (64, 1)];

/// A TIN of `points` moved by `offset` (rounded sums: the mesh is whatever the offset coordinates are).
fn terrain(points: &[(f64, f64, f64)], offset: DVec2) -> Option<Tin> {
    let positions: Vec<DVec3> = points
        .iter()
        .map(|&(x, y, z)| DVec3::new(x + offset.x, y + offset.y, z))
        .collect();
    triangulate(&positions, DedupePolicy::KeepHighest)
        .ok()
        .map(|(tin, _)| tin)
}

fn field(tin: &Tin, s: u32, k: u32) -> HorizonField {
    compute(
        tin,
        &SectorConfig::new(s, k).expect("valid config"),
        &HorizonOptions::default(),
    )
    .expect("valid input")
}

/// The sector of `sectors` that the direction `d` falls into.
fn sector_towards(sectors: u32, d: DVec2) -> u32 {
    cull::sector_of_azimuth(sectors, cull::azimuth(d.x, d.y))
}

/// The definition, evaluated on its own: `p` is hidden from `c` iff, in the sector towards `c` where `p` has a
/// horizon summary `(m, d)`, `t = r · (c − p) > d` and `c.z − p.z < m · t` (boundary points are outside).
fn straightforward(field: &HorizonField, geometry: &SectorGeometry, v: u32, p: DVec3, c: DVec3) -> bool {
    let d = c.truncate() - p.truncate();
    if d == DVec2::ZERO {
        return false;
    }
    let s = sector_towards(field.config().sectors(), d);
    let Some(h) = field.sector_summary(v, s) else {
        return false;
    };
    let r = geometry.sector_centre(s as usize);
    let t = r.x * d.x + r.y * d.y;
    t > h.distance && c.z - p.z < h.slope * t
}

fn points() -> impl Strategy<Value = Vec<(f64, f64, f64)>> {
    proptest::collection::vec((0.0f64..1000.0, 0.0f64..1000.0, 0.0f64..120.0), 4..70)
}

fn offset() -> impl Strategy<Value = DVec2> {
    prop_oneof![
        Just(DVec2::ZERO),
        (200_000.0f64..800_000.0, 3_000_000.0f64..6_000_000.0).prop_map(|(x, y)| DVec2::new(x, y)),
        (-1000i32..1000, -1000i32..1000).prop_map(|(x, y)| DVec2::new(f64::from(x) * 1000.0, f64::from(y) * 4000.0)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// A camera at any horizon vertex of `p` in a sector (in particular the one that sets the left bound `t0`), seen
    /// from `p` in that same sector, is never hidden: its distance along the sector direction is at most the
    /// largest one, computed the same way.
    #[test]
    fn a_camera_on_a_horizon_vertex_is_never_hidden(points in points(), offset in offset()) {
        let Some(tin) = terrain(&points, offset) else { return Ok(()) };
        let positions = tin.positions();
        for (s, k) in CONFIGS {
            let field = field(&tin, s, k);
            let geometry = SectorGeometry::new(field.config());
            let table = RegionTable::from_field(positions, &field);
            for v in 0..tin.num_vertices() as u32 {
                let p = positions[v as usize];
                for i in 0..s {
                    let Some(h) = field.sector_summary(v, i) else { continue };
                    for j in i * k..(i + 1) * k {
                        let Some(HorizonPoint::Vertex(q)) = field.horizon_point(v, j) else { continue };
                        let c = positions[q as usize];
                        if sector_towards(s, c.truncate() - p.truncate()) != i {
                            continue; // On a sector boundary: the other sector's region decides.
                        }
                        let along = geometry.sector_centre(i as usize).dot(c.truncate() - p.truncate());
                        prop_assert!(along <= h.distance, "the horizon's distance is the largest");
                        prop_assert!(
                            !table.vertex_hidden_from(v, p, c),
                            "{s}x{k}: vertex {v} hidden from its own horizon vertex {q} in sector {i} \
                             (distance {}, along {along})", h.distance
                        );
                    }
                }
            }
        }
    }

    /// On random vertex pairs and random cameras the growth's test agrees with the definition evaluated
    /// independently, and with the region's containment test wherever the camera is not within rounding of the
    /// region's boundary. The table built by taking the field is the one built from a borrowed field, for all the
    /// field's vertices and for the first half of them.
    #[test]
    fn agrees_with_the_definition(
        points in points(),
        offset in offset(),
        cameras in proptest::collection::vec((-100.0f64..1100.0, -100.0f64..1100.0, -50.0f64..200.0), 20),
    ) {
        let Some(tin) = terrain(&points, offset) else { return Ok(()) };
        let positions = tin.positions();
        let n = tin.num_vertices() as u32;
        for (s, k) in CONFIGS {
            let field = field(&tin, s, k);
            let geometry = SectorGeometry::new(field.config());
            let table = RegionTable::from_field(positions, &field);
            // Taking the field (as the build does) gives the same table, empty regions and summaries included.
            prop_assert!(RegionTable::from_field_owned(positions, field.clone()) == table, "{}x{}", s, k);
            // And of the first vertices only (a tile's, before its halo).
            let m = positions.len() / 2;
            prop_assert!(
                RegionTable::from_field_owned(&positions[..m], field.clone())
                    == RegionTable::from_field(&positions[..m], &field),
                "{}x{}, first {}", s, k, m
            );
            let free = cameras.iter().map(|&(x, y, z)| DVec3::new(x + offset.x, y + offset.y, z));
            for v in 0..n {
                let p = positions[v as usize];
                for c in positions.iter().copied().chain(free.clone()) {
                    let hidden = table.vertex_hidden_from(v, p, c);
                    prop_assert_eq!(hidden, straightforward(&field, &geometry, v, p, c), "{}x{} vertex {} camera {}", s, k, v, c);
                    // Away from the boundary the region in the table's plane gives the same answer.
                    let d = c.truncate() - p.truncate();
                    if d == DVec2::ZERO {
                        continue;
                    }
                    let sector = sector_towards(s, d);
                    if let Some(h) = field.sector_summary(v, sector) {
                        let t = geometry.sector_centre(sector as usize).dot(d);
                        let margin = 1e-6 * (1.0 + c.abs().max_element());
                        if (t - h.distance).abs() > margin && (c.z - p.z - h.slope * t).abs() > margin {
                            prop_assert_eq!(hidden, table.hidden_from(v, p.truncate(), c));
                        }
                    }
                }
            }
        }
    }
}

/// An exact tie on the left bound: a camera at the horizon vertex that sets the distance is not hidden, even far
/// below the upper boundary, while a camera farther along the sector is.
#[test]
fn an_exact_tie_on_the_left_bound_is_visible() {
    let p = DVec3::new(512_345.678, 4_987_654.321, 100.0);
    let q = p + DVec3::new(0.3, -0.3, -50.0); // Towards the centre of sector 3 of 4 (azimuth 315°).
    let positions = vec![p, q];
    let r = DVec2::from(cull::sector_direction(4, 3));
    let distance = r.dot(q.truncate() - p.truncate());
    let table = RegionTable::of_vertices(&positions, DVec2::new(512_000.0, 4_987_000.0), 4, |v, s| {
        (v == 0 && s == 3).then_some(horizon::SectorHorizon { slope: 0.0, distance })
    });
    assert!(!table.vertex_hidden_from(0, p, q), "on the left bound");
    let far = p + DVec3::new(10.0, -10.0, -5.0);
    assert!(table.vertex_hidden_from(0, p, far));
    assert!(
        !table.vertex_hidden_from(0, p, far.with_z(p.z)),
        "on the upper boundary"
    );
    assert!(!table.vertex_hidden_from(0, p, far.with_z(p.z + 20.0)));
    assert!(
        !table.vertex_hidden_from(0, p, p.with_z(0.0)),
        "straight below: no direction"
    );
    assert!(
        !table.vertex_hidden_from(0, p, p + DVec3::new(-10.0, -10.0, -5.0)),
        "sector 2 is empty"
    );
}
