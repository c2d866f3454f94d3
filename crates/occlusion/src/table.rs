//! Per-sector regions of many elements (vertices, triangles, groups), and the vertex-from-point test that crystal
//! growth uses.

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use horizon::{HorizonField, SectorHorizon};

use crate::region::{Region, intersect_all};

/// The plane coordinate `t = r_i · xy` of a point in sector `sector` of `sectors`.
pub fn plane_t(sectors: u32, sector: u32, xy: DVec2) -> f64 {
    let [x, y] = cull::sector_direction(sectors, sector);
    DVec2::new(x, y).dot(xy)
}

/// Regions of `len` elements in each of `sectors` sectors; `None` is the empty region (never hidden there).
#[derive(Clone, Debug, PartialEq)]
pub struct RegionTable {
    sectors: u32,
    /// The sectors' centre directions `r_i`.
    directions: Vec<DVec2>,
    regions: Vec<Option<Region>>,
}

/// The centre directions of all sectors.
fn directions(sectors: u32) -> Vec<DVec2> {
    (0..sectors)
        .map(|i| {
            let [x, y] = cull::sector_direction(sectors, i);
            DVec2::new(x, y)
        })
        .collect()
}

impl RegionTable {
    /// A table from row-major regions (`regions[element * sectors + sector]`).
    pub fn from_rows(sectors: u32, regions: Vec<Option<Region>>) -> RegionTable {
        assert!(
            sectors > 0 && regions.len().is_multiple_of(sectors as usize),
            "region table rows must be complete"
        );
        RegionTable {
            sectors,
            directions: directions(sectors),
            regions,
        }
    }

    /// The regions of every vertex of a mesh: in each sector, the wedge of [`Region::of_vertex`] built from the
    /// vertex's sector horizon, or empty where `horizon(v, sector)` is `None`.
    pub fn of_vertices(
        positions: &[DVec3],
        sectors: u32,
        horizon: impl Fn(u32, u32) -> Option<SectorHorizon> + Sync,
    ) -> RegionTable {
        let dirs = directions(sectors);
        let regions = (0..positions.len() as u32)
            .into_par_iter()
            .flat_map_iter(|v| {
                let p = positions[v as usize];
                let (horizon, dirs) = (&horizon, &dirs);
                (0..sectors).map(move |s| {
                    horizon(v, s)
                        .map(|h| Region::of_vertex(dirs[s as usize].dot(p.truncate()), p.z, h.slope, h.distance))
                })
            })
            .collect();
        RegionTable {
            sectors,
            directions: dirs,
            regions,
        }
    }

    /// The regions of every vertex from a horizon field (see [`RegionTable::of_vertices`]).
    pub fn from_field(positions: &[DVec3], field: &HorizonField) -> RegionTable {
        RegionTable::of_vertices(positions, field.config().sectors(), |v, s| field.sector_summary(v, s))
    }

    /// The regions of element sets: row `e` is the intersection of the rows of `members(e)` of `self`.
    /// Used for triangles (members = the three vertices) and for groups (members = triangles).
    pub fn intersect_rows<I>(&self, len: usize, members: impl Fn(usize) -> I + Sync) -> RegionTable
    where
        I: IntoIterator<Item = u32>,
        I::IntoIter: Clone,
    {
        let s = self.sectors;
        let regions = (0..len)
            .into_par_iter()
            .flat_map_iter(|e| {
                let ids = members(e).into_iter();
                (0..s).map(move |sector| intersect_all(ids.clone().map(|m| self.get(m, sector))))
            })
            .collect();
        RegionTable {
            sectors: s,
            directions: self.directions.clone(),
            regions,
        }
    }

    /// Number of sectors.
    pub fn sectors(&self) -> u32 {
        self.sectors
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.regions.len() / self.sectors as usize
    }

    /// Whether the table has no elements.
    pub fn is_empty(&self) -> bool {
        self.regions.is_empty()
    }

    /// The region of `element` in `sector` (`None` = empty).
    pub fn get(&self, element: u32, sector: u32) -> Option<&Region> {
        self.regions[element as usize * self.sectors as usize + sector as usize].as_ref()
    }

    /// All sectors' regions of `element`.
    pub fn row(&self, element: u32) -> &[Option<Region>] {
        let s = self.sectors as usize;
        &self.regions[element as usize * s..(element as usize + 1) * s]
    }

    /// Whether `element` at `at` is hidden from the camera at `camera`: the camera's plane coordinates lie inside
    /// the element's region in the sector that contains the direction from `at` to the camera. A camera straight
    /// above or below `at` (no direction) never hides it.
    pub fn hidden_from(&self, element: u32, at: DVec2, camera: DVec3) -> bool {
        let d = camera.truncate() - at;
        if d == DVec2::ZERO {
            return false;
        }
        let sector = cull::sector_of_azimuth(self.sectors, cull::azimuth(d.x, d.y));
        self.get(element, sector)
            .is_some_and(|r| r.contains(self.directions[sector as usize].dot(camera.truncate()), camera.z))
    }

    /// Bytes of chain data held (vertices and tail slopes of non-empty regions), a measure of visibility storage.
    pub fn chain_bytes(&self) -> usize {
        self.regions.iter().flatten().map(|r| r.points().len() * 16 + 8).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_rows_intersect_vertex_rows() {
        let positions = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(10.0, 0.0, 1.0),
            DVec3::new(0.0, 10.0, 2.0),
        ];
        let vertices = RegionTable::of_vertices(&positions, 4, |v, s| {
            (s != 3 || v != 2).then_some(SectorHorizon {
                slope: 0.1 * f64::from(v),
                distance: 5.0,
            })
        });
        let tris = vertices.intersect_rows(1, |_| [0u32, 1, 2]);
        assert_eq!(tris.len(), 1);
        assert!(
            tris.get(0, 3).is_none(),
            "an empty vertex region empties the triangle's"
        );
        let r = tris.get(0, 0).expect("non-empty");
        assert_eq!(
            r.t0(),
            (0..3)
                .map(|v| vertices.get(v, 0).map_or(f64::NAN, Region::t0))
                .fold(f64::MIN, f64::max)
        );
        for t in [r.t0(), 7.0, 20.0, 100.0] {
            let lowest = (0..3)
                .filter_map(|v| vertices.get(v, 0))
                .map(|r| r.height_at(t))
                .fold(f64::INFINITY, f64::min);
            assert!((r.height_at(t) - lowest).abs() < 1e-9, "t = {t}");
        }
    }

    #[test]
    fn sector_directions_agree_with_the_horizon_stage() {
        for s in 4..=64 {
            let geometry = horizon::SectorGeometry::new(&horizon::SectorConfig::new(s, 1).expect("valid"));
            for i in 0..s {
                let [x, y] = cull::sector_direction(s, i);
                assert_eq!(DVec2::new(x, y), geometry.sector_centre(i as usize), "s = {s}, i = {i}");
            }
        }
    }

    #[test]
    fn hidden_from_uses_the_sector_towards_the_camera() {
        // One vertex at the origin, hidden in sector 0 (azimuth 0..90°) below slope 0 beyond t0 = 0 + 5.
        let positions = vec![DVec3::ZERO];
        let table = RegionTable::of_vertices(&positions, 4, |_, s| {
            (s == 0).then_some(SectorHorizon {
                slope: 0.0,
                distance: 5.0,
            })
        });
        assert!(table.hidden_from(0, DVec2::ZERO, DVec3::new(20.0, 20.0, -1.0)));
        assert!(!table.hidden_from(0, DVec2::ZERO, DVec3::new(20.0, 20.0, 1.0)));
        assert!(
            !table.hidden_from(0, DVec2::ZERO, DVec3::new(-20.0, 20.0, -1.0)),
            "sector 1 is empty"
        );
        assert!(!table.hidden_from(0, DVec2::ZERO, DVec3::new(0.0, 0.0, -10.0)));
    }
}
