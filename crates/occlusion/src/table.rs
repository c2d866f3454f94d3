//! Per-sector regions of many elements (vertices, triangles, groups), and the vertex-from-point test that crystal
//! growth uses.
//!
//! A table's plane coordinates are relative to its origin `o`: `t = r_i · (xy − o)`, with `o` the horizon field's
//! projection origin ([`horizon::projection_origin`], the lower-left corner of the terrain's bounding box). That keeps
//! rounding small on UTM-sized coordinates and, since `o` moves exactly with the terrain, makes every decision
//! translation-invariant. All regions of one table share that plane, so they intersect directly.
//!
//! A vertex table ([`RegionTable::of_vertices`]) also keeps the sector horizon summaries its regions were built from,
//! for [`RegionTable::vertex_hidden_from`]: growth's cameras are mesh vertices, often the very horizon vertex `q` that
//! set a region's left bound `t_p + d`, `d = r_i · (q − p)`. Such a camera lies exactly on the bound, outside by the
//! strict containment rule, but `r_i · (q − o)` against the rounded sum `t_p + d` lets rounding decide. The vertex test
//! therefore evaluates the definition relative to the vertex, with the horizon stage's own operands:
//! `t = r_i · (c.xy − p.xy) > d` and `c.z − p.z < m · t`; for `c = q` that `t` is `d` to the last bit.

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use horizon::{HorizonField, SectorHorizon};

use crate::region::{Region, intersect_all};

/// The plane coordinate `t = r_i · xy` of a point (or a difference of points) in sector `sector` of `sectors`.
pub fn plane_t(sectors: u32, sector: u32, xy: DVec2) -> f64 {
    let [x, y] = cull::sector_direction(sectors, sector);
    DVec2::new(x, y).dot(xy)
}

/// Regions of `len` elements in each of `sectors` sectors; `None` is the empty region (never hidden there).
#[derive(Clone, Debug, PartialEq)]
pub struct RegionTable {
    sectors: u32,
    /// The origin `o` of the plane coordinates `t = r_i · (xy − o)`.
    origin: DVec2,
    /// The sectors' centre directions `r_i`.
    directions: Vec<DVec2>,
    regions: Vec<Option<Region>>,
    /// Vertex tables only (else empty): the summaries the regions were built from, laid out like `regions`; an empty
    /// region has distance `+∞` (nothing lies beyond it).
    horizons: Vec<SectorHorizon>,
}

/// No horizon in a sector (as [`HorizonField`] marks it: a NaN slope).
const NO_HORIZON: SectorHorizon = SectorHorizon {
    slope: f64::NAN,
    distance: f64::NAN,
};

/// The summary stored for an empty vertex region: no camera is ever beyond its left bound.
const NO_SUMMARY: SectorHorizon = SectorHorizon {
    slope: 0.0,
    distance: f64::INFINITY,
};

/// The region of the vertex at `p` in the sector of centre direction `direction`, from its summary `h` there, in
/// plane coordinates relative to `origin` ([`Region::of_vertex`]).
fn vertex_region(direction: DVec2, origin: DVec2, p: DVec3, h: &SectorHorizon) -> Region {
    Region::of_vertex(direction.dot(p.truncate() - origin), p.z, h.slope, h.distance)
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
    /// A table from row-major regions (`regions[element * sectors + sector]`) whose plane coordinates are relative
    /// to `origin`.
    pub fn from_rows(sectors: u32, origin: DVec2, regions: Vec<Option<Region>>) -> RegionTable {
        assert!(
            sectors > 0 && regions.len().is_multiple_of(sectors as usize),
            "region table rows must be complete"
        );
        RegionTable {
            sectors,
            origin,
            directions: directions(sectors),
            regions,
            horizons: Vec::new(),
        }
    }

    /// The regions of every vertex of a mesh, in plane coordinates relative to `origin`: in each sector, the wedge of
    /// [`Region::of_vertex`] built from the vertex's sector horizon, or empty where `horizon(v, sector)` is `None`
    /// (or has a NaN slope). The table keeps the sector horizons too, for [`RegionTable::vertex_hidden_from`].
    pub fn of_vertices(
        positions: &[DVec3],
        origin: DVec2,
        sectors: u32,
        horizon: impl Fn(u32, u32) -> Option<SectorHorizon> + Sync,
    ) -> RegionTable {
        let s = sectors as usize;
        let summaries = (0..positions.len() * s)
            .into_par_iter()
            .map(|i| horizon((i / s) as u32, (i % s) as u32).unwrap_or(NO_HORIZON))
            .collect();
        RegionTable::of_summaries(positions, origin, sectors, summaries)
    }

    /// The regions of every vertex from a horizon field (see [`RegionTable::of_vertices`]), relative to the field's
    /// projection origin.
    pub fn from_field(positions: &[DVec3], field: &HorizonField) -> RegionTable {
        RegionTable::of_vertices(positions, field.origin(), field.config().sectors(), |v, s| {
            field.sector_summary(v, s)
        })
    }

    /// [`RegionTable::from_field`], taking the field: its summaries become the table's (no copy), and the rest of
    /// the field is freed before the regions are allocated, which keeps a large terrain's peak memory lower by the
    /// size of both. `positions` may be the first vertices of the field's (a tile's own, before its halo): the table
    /// holds those.
    ///
    /// # Panics
    /// If `positions` has more vertices than the field.
    pub fn from_field_owned(positions: &[DVec3], field: HorizonField) -> RegionTable {
        assert!(
            positions.len() <= field.num_vertices(),
            "{} positions for a horizon field of {} vertices",
            positions.len(),
            field.num_vertices()
        );
        let (origin, sectors) = (field.origin(), field.config().sectors());
        let mut summaries = field.into_summaries();
        summaries.truncate(positions.len() * sectors as usize);
        RegionTable::of_summaries(positions, origin, sectors, summaries)
    }

    /// The vertex table of the summaries `horizons` (vertex-major, as [`HorizonField`] lays them out; a NaN slope is
    /// no horizon, as [`HorizonField::sector_summary`] reads it), which it keeps, those entries replaced by
    /// [`NO_SUMMARY`].
    fn of_summaries(positions: &[DVec3], origin: DVec2, sectors: u32, mut horizons: Vec<SectorHorizon>) -> RegionTable {
        let s = sectors as usize;
        let dirs = directions(sectors);
        let regions = horizons
            .par_iter_mut()
            .enumerate()
            .map(|(i, h)| {
                if h.slope.is_nan() {
                    *h = NO_SUMMARY;
                    return None;
                }
                Some(vertex_region(dirs[i % s], origin, positions[i / s], h))
            })
            .collect();
        RegionTable {
            sectors,
            origin,
            directions: dirs,
            regions,
            horizons,
        }
    }

    /// The regions of element sets: row `e` is the intersection of the rows of `members(e)` of `self`.
    /// Used for triangles (members = the three vertices) and for groups (members = triangles).
    pub fn intersect_rows<I>(&self, len: usize, members: impl Fn(usize) -> I + Sync) -> RegionTable
    where
        I: IntoIterator<Item = u32>,
    {
        let s = self.sectors;
        let regions = (0..len * s as usize)
            .into_par_iter()
            .map(|i| {
                let (e, sector) = (i / s as usize, i as u32 % s);
                intersect_all(members(e).into_iter().map(|m| self.get(m, sector)))
            })
            .collect();
        RegionTable {
            sectors: s,
            origin: self.origin,
            directions: self.directions.clone(),
            regions,
            horizons: Vec::new(),
        }
    }

    /// Number of sectors.
    pub fn sectors(&self) -> u32 {
        self.sectors
    }

    /// The origin `o` of the plane coordinates `t = r_i · (xy − o)`.
    pub fn origin(&self) -> DVec2 {
        self.origin
    }

    /// The plane coordinate `t = r_i · (xy − o)` of the point `xy` in `sector`.
    pub fn plane_t(&self, sector: u32, xy: DVec2) -> f64 {
        self.directions[sector as usize].dot(xy - self.origin)
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
    #[inline]
    pub fn hidden_from(&self, element: u32, at: DVec2, camera: DVec3) -> bool {
        let d = camera.truncate() - at;
        if d == DVec2::ZERO {
            return false;
        }
        let sector = cull::sector_of_azimuth(self.sectors, cull::azimuth(d.x, d.y));
        self.get(element, sector)
            .is_some_and(|r| r.contains(self.plane_t(sector, camera.truncate()), camera.z))
    }

    /// Whether vertex `vertex` at `position` is hidden from the camera at `camera`, decided exactly by the region's
    /// definition in the sector towards the camera, relative to the vertex: with that sector's horizon summary
    /// `(m, d)` of the vertex and `t = r_i · (camera.xy − position.xy)` (the operands and order of the horizon
    /// stage's `d`), hidden iff `t > d` and `camera.z − position.z < m · t`. A camera at the horizon vertex that set
    /// `d` is therefore on the left bound, i.e. not hidden, whatever the coordinates. A camera straight above or
    /// below the vertex never hides it. Tables without vertex summaries (not built by
    /// [`RegionTable::of_vertices`]) fall back to [`RegionTable::hidden_from`].
    #[inline]
    pub fn vertex_hidden_from(&self, vertex: u32, position: DVec3, camera: DVec3) -> bool {
        if self.horizons.is_empty() {
            return self.hidden_from(vertex, position.truncate(), camera);
        }
        let d = camera.truncate() - position.truncate();
        if d == DVec2::ZERO {
            return false;
        }
        let sector = cull::sector_of_azimuth(self.sectors, cull::azimuth(d.x, d.y));
        let h = &self.horizons[vertex as usize * self.sectors as usize + sector as usize];
        let t = self.directions[sector as usize].dot(d);
        t > h.distance && camera.z - position.z < h.slope * t
    }

    /// Hints the processor to load the sector horizon summary that [`RegionTable::vertex_hidden_from`] reads for
    /// the same arguments, so that a caller that knows its next tests ahead can overlap their memory reads. No effect
    /// on any result (and nothing is read for tables without vertex summaries).
    #[inline]
    pub fn prefetch_vertex_test(&self, vertex: u32, position: DVec3, camera: DVec3) {
        let d = camera.truncate() - position.truncate();
        if self.horizons.is_empty() || d == DVec2::ZERO {
            return;
        }
        let sector = cull::sector_of_azimuth(self.sectors, cull::azimuth(d.x, d.y));
        if let Some(h) = self
            .horizons
            .get(vertex as usize * self.sectors as usize + sector as usize)
        {
            tin::prefetch(h);
        }
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
        let vertices = RegionTable::of_vertices(&positions, DVec2::ZERO, 4, |v, s| {
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

    proptest::proptest! {
        /// With integer coordinates and an integer offset every translated coordinate is exact: a table of the
        /// translated vertices relative to the translated origin holds the same regions, and hides the same vertices
        /// from the translated cameras.
        #[test]
        fn translating_vertices_and_origin_together_changes_nothing(
            vertices in proptest::collection::vec((-500i32..500, -500i32..500, -50i32..50), 1..10),
            horizons in proptest::collection::vec(proptest::option::weighted(0.8, (-1.0f64..1.0, 0.0f64..300.0)), 10 * 8),
            cameras in proptest::collection::vec((-800i32..800, -800i32..800, -80i32..80), 1..10),
            origin in (-1000i32..1000, -1000i32..1000),
            offset in (0i32..1_000_000, 0i32..5_000_000),
        ) {
            let p3 = |(x, y, z): (i32, i32, i32)| DVec3::new(f64::from(x), f64::from(y), f64::from(z));
            let off = DVec3::new(f64::from(offset.0), f64::from(offset.1), 0.0);
            let positions: Vec<DVec3> = vertices.iter().copied().map(p3).collect();
            let moved: Vec<DVec3> = positions.iter().map(|&p| p + off).collect();
            let o = DVec2::new(f64::from(origin.0), f64::from(origin.1));
            let horizon = |v: u32, s: u32| {
                horizons[(v * 8 + s) as usize].map(|(slope, distance)| SectorHorizon { slope, distance })
            };
            let a = RegionTable::of_vertices(&positions, o, 8, horizon);
            let b = RegionTable::of_vertices(&moved, o + off.truncate(), 8, horizon);
            proptest::prop_assert_eq!(b.origin() - off.truncate(), a.origin());
            for v in 0..positions.len() as u32 {
                proptest::prop_assert_eq!(a.row(v), b.row(v));
                for &c in &cameras {
                    let c = p3(c);
                    let at = positions[v as usize].truncate();
                    proptest::prop_assert_eq!(
                        a.hidden_from(v, at, c),
                        b.hidden_from(v, at + off.truncate(), c + off)
                    );
                }
            }
        }
    }

    #[test]
    fn plane_coordinates_are_relative_to_the_origin() {
        let positions = vec![DVec3::new(1010.0, 20.0, 5.0)];
        let origin = DVec2::new(1000.0, 0.0);
        // Sector 0 of 4 has centre direction 45°.
        let table = RegionTable::of_vertices(&positions, origin, 4, |_, s| {
            (s == 0).then_some(SectorHorizon {
                slope: 0.0,
                distance: 5.0,
            })
        });
        let r = table.get(0, 0).expect("sector 0");
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert_eq!(r.t0(), h * 10.0 + h * 20.0 + 5.0);
        assert_eq!(table.plane_t(0, DVec2::new(1000.0, 0.0)), 0.0);
        assert_eq!(table.plane_t(0, DVec2::new(1010.0, 20.0)), h * 10.0 + h * 20.0);
        // A camera 30 m further along the diagonal and below the vertex is hidden; one above it is not.
        let c = DVec2::new(1010.0, 20.0) + DVec2::splat(30.0 * h);
        assert!(table.hidden_from(0, positions[0].truncate(), c.extend(4.0)));
        assert!(!table.hidden_from(0, positions[0].truncate(), c.extend(6.0)));
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
        let table = RegionTable::of_vertices(&positions, DVec2::ZERO, 4, |_, s| {
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

    #[test]
    fn vertex_test_without_summaries_falls_back_to_the_regions() {
        let positions = vec![DVec3::new(3.0, 4.0, 10.0)];
        let horizon = |_, s| {
            (s == 0).then_some(SectorHorizon {
                slope: -0.5,
                distance: 2.0,
            })
        };
        let with = RegionTable::of_vertices(&positions, DVec2::ZERO, 4, horizon);
        let without = RegionTable::from_rows(4, DVec2::ZERO, with.row(0).to_vec());
        let at = positions[0].truncate();
        for c in [
            DVec3::new(20.0, 20.0, -5.0),
            DVec3::new(20.0, 20.0, 9.0),
            DVec3::new(4.0, 5.0, 0.0),
            DVec3::new(-20.0, 20.0, -100.0),
            DVec3::new(3.0, 4.0, -100.0),
        ] {
            assert_eq!(
                without.vertex_hidden_from(0, positions[0], c),
                without.hidden_from(0, at, c)
            );
            assert_eq!(
                with.vertex_hidden_from(0, positions[0], c),
                with.hidden_from(0, at, c),
                "{c}"
            );
        }
        assert!(with.vertex_hidden_from(0, positions[0], DVec3::new(20.0, 20.0, -5.0)));
    }
}
