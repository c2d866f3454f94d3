//! Sector and subsector geometry (thesis 4.5.1; the definitions below).
//!
//! With `s` sectors of `k` subsectors, subsector `j` (of `N = s·k`) spans azimuths `[2πj/N, 2π(j+1)/N]`,
//! counter-clockwise from +x, and belongs to sector `j / k`. Its wedge at a vertex `p` is bounded by the edge
//! directions `a = e_j` and `b = e_(j+1 mod N)`; its projection direction is the centre `r_j`.
//!
//! Choices made where the sources are vague:
//! - Each boundary direction `e_j` is computed once as an f64 unit vector; multiples of 45° are snapped to their
//!   exact axis/diagonal values (`(1, 0)`, `(FRAC_1_SQRT_2, FRAC_1_SQRT_2)`, …) so that grid directions on those
//!   boundaries are exactly on them. The wedge is then *defined* by these f64 vectors: `q` is in the closed wedge of
//!   `p` iff `cross(a, q − p) ≥ 0` and `cross(q − p, b) ≥ 0`, decided exactly ([`crate::predicates`]). A direction
//!   on a boundary therefore belongs to both adjacent subsectors, and the sweep and the oracle agree on every case.
//! - Projected coordinates are `t = r · (x − o)` in f64 with `o` the lower-left corner of the TIN's bounding box
//!   ([`crate::projection_origin`]; a constant shift of `r · x`, which keeps rounding small on UTM-sized coordinates,
//!   and which moves exactly with the terrain under an exact translation, so a translated copy makes the same
//!   rounding decisions). Every consumer calls [`Wedge::project`].
//! - Since `N ≥ 4`, a wedge spans at most 90°, and `r` lies strictly inside it: every `q ≠ p` in the closed wedge
//!   has `r · (q − p) ≥ |q − p| cos 45° > 0`. Only rounding of `t` can make `t_q ≤ t_p` for such a `q` (points
//!   closer than about `1e-15` of the terrain's extent); such vertices are not candidates (see [`crate::oracle`]).

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::error::HorizonError;
use crate::predicates::LineKey;

/// Largest supported `sectors · subsectors`.
pub const MAX_TOTAL_SUBSECTORS: u32 = 1024;

/// A validated choice of sectors and subsectors: at least 4 sectors, at least 1 subsector per sector, and at most
/// [`MAX_TOTAL_SUBSECTORS`] subsectors in all.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(try_from = "RawSectorConfig")]
pub struct SectorConfig {
    sectors: u32,
    subsectors: u32,
}

#[derive(Deserialize)]
struct RawSectorConfig {
    sectors: u32,
    subsectors: u32,
}

impl TryFrom<RawSectorConfig> for SectorConfig {
    type Error = HorizonError;

    fn try_from(raw: RawSectorConfig) -> Result<Self, Self::Error> {
        SectorConfig::new(raw.sectors, raw.subsectors)
    }
}

impl SectorConfig {
    /// Validates `sectors` (≥ 4) and `subsectors` per sector (≥ 1, product ≤ [`MAX_TOTAL_SUBSECTORS`]).
    pub fn new(sectors: u32, subsectors: u32) -> Result<SectorConfig, HorizonError> {
        if sectors < 4 {
            return Err(HorizonError::TooFewSectors { sectors });
        }
        if subsectors == 0 {
            return Err(HorizonError::NoSubsectors);
        }
        match sectors.checked_mul(subsectors) {
            Some(total) if total <= MAX_TOTAL_SUBSECTORS => Ok(SectorConfig { sectors, subsectors }),
            _ => Err(HorizonError::TooManySubsectors {
                sectors,
                subsectors,
                limit: MAX_TOTAL_SUBSECTORS,
            }),
        }
    }

    /// Number of sectors `s`.
    pub fn sectors(&self) -> u32 {
        self.sectors
    }

    /// Number of subsectors per sector `k`.
    pub fn subsectors(&self) -> u32 {
        self.subsectors
    }

    /// Number of subsectors in all, `s · k`.
    pub fn total_subsectors(&self) -> u32 {
        self.sectors * self.subsectors
    }

    /// The sector that subsector `j` belongs to (`j / k`).
    pub fn sector_of(&self, subsector: u32) -> u32 {
        subsector / self.subsectors
    }
}

/// The unit vector at azimuth `2π · num / den`, snapped to exact values at multiples of 45°.
pub fn unit_direction(num: u64, den: u64) -> DVec2 {
    let num = num % den;
    if (8 * num).is_multiple_of(den) {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        return match 8 * num / den {
            0 => DVec2::new(1.0, 0.0),
            1 => DVec2::new(h, h),
            2 => DVec2::new(0.0, 1.0),
            3 => DVec2::new(-h, h),
            4 => DVec2::new(-1.0, 0.0),
            5 => DVec2::new(-h, -h),
            6 => DVec2::new(0.0, -1.0),
            _ => DVec2::new(h, -h),
        };
    }
    let angle = std::f64::consts::TAU * num as f64 / den as f64;
    let (s, c) = angle.sin_cos();
    DVec2::new(c, s)
}

/// A monotone stand-in for the azimuth of `d` (the "diamond angle"): 0 at +x, increasing counter-clockwise to 4.
/// Its derivative with respect to the angle lies in [1/2, 1].
fn pseudo_angle(d: DVec2) -> f64 {
    let (x, y) = (d.x, d.y);
    if y >= 0.0 {
        if x >= 0.0 { y / (x + y) } else { 1.0 - x / (y - x) }
    } else if x < 0.0 {
        2.0 - y / (-x - y)
    } else {
        3.0 + x / (x - y)
    }
}

/// The wedge of one subsector: boundary directions `a` (start) and `b` (end, counter-clockwise from `a`) and the
/// centre direction `r` onto which points are projected.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wedge {
    /// Direction of the boundary at azimuth `2πj/N`.
    pub a: DVec2,
    /// Direction of the boundary at azimuth `2π(j+1)/N`.
    pub b: DVec2,
    /// Centre direction, azimuth `2π(j+½)/N`.
    pub r: DVec2,
}

impl Wedge {
    /// Whether `q` lies in the closed wedge with apex `p` (both boundary rays included). `q == p` counts as inside;
    /// callers exclude the apex itself.
    pub fn contains(&self, p: DVec2, q: DVec2) -> bool {
        let (ka_p, kb_p) = (LineKey::new(self.a, p), LineKey::new(self.b, p));
        self.contains_keyed(p, ka_p, kb_p, q, LineKey::new(self.a, q), LineKey::new(self.b, q))
    }

    /// Whether the direction `d` lies in the closed wedge (`d` on a boundary ray counts): [`Wedge::contains`] with
    /// the apex at the origin.
    pub fn contains_direction(&self, d: DVec2) -> bool {
        self.contains(DVec2::ZERO, d)
    }

    /// [`Wedge::contains`] with precomputed [`LineKey`]s of `p` and `q` across `a` and `b`.
    #[inline]
    pub fn contains_keyed(
        &self,
        p: DVec2,
        ka_p: LineKey,
        kb_p: LineKey,
        q: DVec2,
        ka_q: LineKey,
        kb_q: LineKey,
    ) -> bool {
        ka_q.cmp_exact(&ka_p, self.a, q, p).is_ge() && kb_q.cmp_exact(&kb_p, self.b, q, p).is_le()
    }

    /// The projected coordinate `t = r · (x − origin)`.
    #[inline]
    pub fn project(&self, origin: DVec2, x: DVec2) -> f64 {
        let d = x - origin;
        self.r.x * d.x + self.r.y * d.y
    }
}

/// The precomputed directions of a [`SectorConfig`]: subsector boundaries, subsector centres and sector centres.
#[derive(Clone, Debug, PartialEq)]
pub struct SectorGeometry {
    config: SectorConfig,
    edges: Vec<DVec2>,
    /// Pseudo-angles of the edges (increasing, the first 0).
    edge_pseudo: Vec<f64>,
    wedges: Vec<Wedge>,
    sector_centres: Vec<DVec2>,
}

impl SectorGeometry {
    /// Computes every direction of `config` once.
    pub fn new(config: &SectorConfig) -> SectorGeometry {
        let n = u64::from(config.total_subsectors());
        let s = u64::from(config.sectors());
        let edges: Vec<DVec2> = (0..n).map(|j| unit_direction(j, n)).collect();
        let wedges = (0..n as usize)
            .map(|j| Wedge {
                a: edges[j],
                b: edges[(j + 1) % n as usize],
                r: unit_direction(2 * j as u64 + 1, 2 * n),
            })
            .collect();
        SectorGeometry {
            config: *config,
            edge_pseudo: edges.iter().map(|e| pseudo_angle(*e)).collect(),
            edges,
            wedges,
            sector_centres: (0..s).map(|i| unit_direction(2 * i + 1, 2 * s)).collect(),
        }
    }

    /// The configuration.
    pub fn config(&self) -> &SectorConfig {
        &self.config
    }

    /// Number of subsectors in all.
    pub fn total(&self) -> usize {
        self.edges.len()
    }

    /// Boundary direction `e_j` at azimuth `2πj/N`.
    pub fn edge(&self, j: usize) -> DVec2 {
        self.edges[j % self.edges.len()]
    }

    /// The wedge of subsector `j`.
    #[inline]
    pub fn wedge(&self, j: usize) -> Wedge {
        self.wedges[j]
    }

    /// Centre direction `r_i` of sector `i`.
    pub fn sector_centre(&self, i: usize) -> DVec2 {
        self.sector_centres[i]
    }

    /// The subsectors whose closed wedges at `p` contain `q ≠ p`: one, or two when `q` lies on a boundary ray.
    /// Decided with the exact predicate of [`Wedge::contains`]; `atan2` only narrows the search to three.
    pub fn subsectors_containing(&self, p: DVec2, q: DVec2) -> SubsectorHits {
        let n = self.edges.len();
        let position = pseudo_angle(q - p);
        // The subsector whose half-open pseudo-angle range holds the estimate.
        let guess = self.edge_pseudo.partition_point(|&e| e <= position).max(1) - 1;
        let upper = if guess + 1 < n {
            self.edge_pseudo[guess + 1]
        } else {
            4.0
        };
        let mut hits = SubsectorHits::default();
        // The estimate is within about 1e-15 of the exact pseudo-angle (q − p rounds to within half an ulp per
        // component, and the pseudo-angle changes no faster than the angle): a direction this far from both
        // boundaries of its guessed subsector can be in no other wedge, and the exact test of that one suffices.
        let margin = 1e-9;
        let inside = position - self.edge_pseudo[guess] > margin && upper - position > margin;
        let candidates: &[usize] = if inside { &[0] } else { &[n - 1, 0, 1] };
        for &offset in candidates {
            let j = if guess + offset >= n {
                guess + offset - n
            } else {
                guess + offset
            };
            if self.wedge(j).contains(p, q) {
                hits.push(j as u32);
            }
        }
        hits
    }
}

/// Up to three subsector indices (see [`SectorGeometry::subsectors_containing`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SubsectorHits {
    len: u8,
    items: [u32; 3],
}

impl SubsectorHits {
    fn push(&mut self, j: u32) {
        if !self.as_slice().contains(&j) {
            self.items[self.len as usize] = j;
            self.len += 1;
        }
    }

    /// The indices found.
    pub fn as_slice(&self) -> &[u32] {
        &self.items[..self.len as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn config_validation_names_the_field() {
        assert_eq!(SectorConfig::new(3, 1), Err(HorizonError::TooFewSectors { sectors: 3 }));
        assert_eq!(SectorConfig::new(8, 0), Err(HorizonError::NoSubsectors));
        assert!(matches!(
            SectorConfig::new(64, 17),
            Err(HorizonError::TooManySubsectors {
                sectors: 64,
                subsectors: 17,
                ..
            })
        ));
        assert!(matches!(
            SectorConfig::new(u32::MAX, u32::MAX),
            Err(HorizonError::TooManySubsectors { .. })
        ));
        let c = SectorConfig::new(16, 4).expect("valid");
        assert_eq!(
            (c.sectors(), c.subsectors(), c.total_subsectors(), c.sector_of(37)),
            (16, 4, 64, 9)
        );
        assert!(SectorConfig::new(1024, 1).is_ok());
        assert!(SectorConfig::new(4, 1).is_ok());
    }

    #[test]
    fn directions_are_unit_and_ordered() {
        let g = SectorGeometry::new(&SectorConfig::new(5, 3).expect("valid"));
        assert_eq!(g.total(), 15);
        for j in 0..15 {
            let w = g.wedge(j);
            for v in [w.a, w.b, w.r] {
                assert!((v.length() - 1.0).abs() < 1e-15);
            }
            // r strictly inside, b counter-clockwise from a.
            assert!(w.a.perp_dot(w.r) > 0.1 && w.r.perp_dot(w.b) > 0.1 && w.a.perp_dot(w.b) > 0.0);
        }
        assert_eq!(g.edge(0), DVec2::X);
        let angle = std::f64::consts::PI / 5.0; // centre of sector 0 of 5
        assert!((g.sector_centre(0) - DVec2::new(angle.cos(), angle.sin())).length() < 1e-15);
    }

    #[test]
    fn snapped_boundaries_are_shared() {
        let g = SectorGeometry::new(&SectorConfig::new(8, 1).expect("valid"));
        assert_eq!(g.edge(2), DVec2::Y);
        let p = DVec2::new(3.0, 4.0);
        // Exactly north and exactly north-east of p: on boundaries, in both adjacent wedges.
        for (d, js) in [(DVec2::new(0.0, 5.0), [1usize, 2]), (DVec2::new(2.0, 2.0), [0, 1])] {
            for j in 0..8 {
                assert_eq!(
                    g.wedge(j).contains(p, p + d),
                    js.contains(&j),
                    "direction {d} subsector {j}"
                );
            }
            let hits = g.subsectors_containing(p, p + d);
            assert_eq!(hits.as_slice().len(), 2);
        }
        assert!(g.wedge(1).contains_direction(DVec2::Y) && g.wedge(2).contains_direction(DVec2::Y));
        assert!(!g.wedge(3).contains_direction(DVec2::Y));
        // Strictly inside one wedge.
        let hits = g.subsectors_containing(p, p + DVec2::new(1.0, 0.2));
        assert_eq!(hits.as_slice(), &[0]);
    }

    #[test]
    fn pseudo_angle_is_monotone() {
        let mut last = -1.0;
        for i in 0..10_000 {
            let a = std::f64::consts::TAU * i as f64 / 10_000.0;
            let p = pseudo_angle(DVec2::new(a.cos(), a.sin()));
            assert!(p > last && (0.0..4.0).contains(&p), "angle {a}: {p} after {last}");
            last = p;
        }
    }

    #[test]
    fn subsectors_containing_agrees_with_every_wedge() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        for (s, k) in [(4, 1), (8, 8), (5, 3), (1024, 1)] {
            let g = SectorGeometry::new(&SectorConfig::new(s, k).expect("valid"));
            for _ in 0..2000 {
                let p = DVec2::new(rng.random_range(-3..3) as f64, rng.random_range(-3..3) as f64);
                let q = if rng.random_range(0..2) == 0 {
                    DVec2::new(rng.random_range(-3..3) as f64, rng.random_range(-3..3) as f64)
                } else {
                    p + g.edge(rng.random_range(0..g.total())) * rng.random_range(0.1..10.0)
                };
                if p == q {
                    continue;
                }
                let expect: Vec<u32> = (0..g.total() as u32)
                    .filter(|&j| g.wedge(j as usize).contains(p, q))
                    .collect();
                let mut got = g.subsectors_containing(p, q).as_slice().to_vec();
                got.sort_unstable();
                assert_eq!(got, expect, "{s}x{k}: p {p} q {q}");
            }
        }
    }

    #[test]
    fn projection_is_positive_inside_the_wedge() {
        let g = SectorGeometry::new(&SectorConfig::new(4, 1).expect("valid"));
        let o = DVec2::new(1000.0, 2000.0);
        let p = DVec2::new(1003.0, 2004.0);
        for j in 0..4 {
            let w = g.wedge(j);
            for d in [w.a, w.b, w.r, w.a + w.b] {
                let q = p + d * 7.0;
                assert!(w.contains(p, q));
                assert!(w.project(o, q) > w.project(o, p));
            }
        }
    }
}
