//! [`HorizonField`]: the horizon of every vertex in every subsector, and the per-sector summaries that the
//! occlusion regions are built from (the `sector` module and crate `occlusion`; Stewart 1997 §5.1).
//!
//! Storage: one `u32` per vertex and subsector (subsector-major, [`NO_HORIZON`] for none), a sorted side table of
//! the edge points that won under the undersampling option, and per vertex and sector a [`SectorHorizon`]:
//! - `slope`: the minimum over the sector's `k` subsectors of the horizon slope `(z_h − z_p)/(t_h − t_p)`, each
//!   measured in its own subsector's projection (`t` along the subsector centre `r_j`, as the horizon was chosen);
//! - `distance`: the largest distance from `p` to its subsector horizon points measured along the *sector* centre
//!   `r_i`, `r_i · (h − p)` (Stewart's correction: the region starts behind the farthest horizon point).
//!
//! The summary is empty when any subsector of the sector has no horizon.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering as AtomicOrdering};

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use tin::Tin;

use crate::error::HorizonError;
use crate::sector::{SectorConfig, SectorGeometry};
use crate::{NO_HORIZON, oracle, sweep, undersampling};

/// A progress callback: `(subsector sweeps finished, total)`, called from worker threads.
pub type Progress = Arc<dyn Fn(usize, usize) + Send + Sync>;

/// Options of [`compute`] and [`brute_force`].
#[derive(Clone, Default)]
pub struct HorizonOptions {
    /// Enables the undersampling fix (thesis 4.5.4) with this radius in metres (see [`crate::undersampling`]).
    pub undersampling_radius: Option<f64>,
    /// Called with `(done, total)` after each subsector sweep ([`compute`]), or once at the end ([`brute_force`]).
    pub progress: Option<Progress>,
}

impl std::fmt::Debug for HorizonOptions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HorizonOptions")
            .field("undersampling_radius", &self.undersampling_radius)
            .field("progress", &self.progress.as_ref().map(|_| "callback"))
            .finish()
    }
}

/// An edge point that is a horizon (undersampling fix): where the edge crosses the subsector's centre ray.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EdgeHorizon {
    /// The edge's endpoints, smaller index first.
    pub edge: [u32; 2],
    /// The crossing point in world coordinates, height interpolated along the edge.
    pub point: DVec3,
}

/// A horizon point: a vertex, or an edge point from the undersampling fix.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum HorizonPoint {
    /// A TIN vertex.
    Vertex(u32),
    /// A point on a TIN edge.
    Edge(EdgeHorizon),
}

impl HorizonPoint {
    /// The point's world position.
    pub fn position(&self, tin: &Tin) -> DVec3 {
        match self {
            HorizonPoint::Vertex(v) => tin.position(*v),
            HorizonPoint::Edge(e) => e.point,
        }
    }
}

/// The horizon summary of one vertex in one sector.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SectorHorizon {
    /// Minimum horizon slope over the sector's subsectors (rise over run, each in its subsector's projection).
    pub slope: f64,
    /// Largest distance from the vertex to its subsector horizon points, measured along the sector centre (m).
    pub distance: f64,
}

/// Horizons of every vertex of a TIN in every subsector, with per-sector summaries.
///
/// Equality compares everything, summaries bit for bit.
#[derive(Clone, Debug)]
pub struct HorizonField {
    config: SectorConfig,
    num_vertices: usize,
    undersampling_radius: Option<f64>,
    /// Subsector-major: `horizons[j * n + v]`.
    horizons: Vec<u32>,
    /// Sorted by slot `j * n + v`.
    edge_points: Vec<(u64, EdgeHorizon)>,
    /// Vertex-major: `summaries[v * s + i]`; `slope` NaN when empty.
    summaries: Vec<SectorHorizon>,
    /// The point `o` of the projections `t = r · (x − o)` ([`projection_origin`]).
    origin: DVec2,
}

impl PartialEq for HorizonField {
    fn eq(&self, other: &Self) -> bool {
        let bits = |s: &SectorHorizon| (s.slope.to_bits(), s.distance.to_bits());
        self.config == other.config
            && self.num_vertices == other.num_vertices
            && self.undersampling_radius.map(f64::to_bits) == other.undersampling_radius.map(f64::to_bits)
            && self.horizons == other.horizons
            && self.edge_points == other.edge_points
            && self.summaries.iter().map(bits).eq(other.summaries.iter().map(bits))
            && self.origin.to_array().map(f64::to_bits) == other.origin.to_array().map(f64::to_bits)
    }
}

impl HorizonField {
    /// The sector configuration.
    pub fn config(&self) -> &SectorConfig {
        &self.config
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.num_vertices
    }

    /// The undersampling radius used, if any.
    pub fn undersampling_radius(&self) -> Option<f64> {
        self.undersampling_radius
    }

    /// The point `o` of every projection `t = r · (x − o)` the field was computed with ([`projection_origin`]).
    pub fn origin(&self) -> DVec2 {
        self.origin
    }

    /// The horizon vertex of `vertex` in `subsector` under the vertex-only definition (the sweep's answer, also
    /// when the undersampling fix replaced it by an edge point; see [`HorizonField::horizon_point`]). `None` when
    /// no vertex lies in the wedge, or the indices are out of range.
    pub fn horizon(&self, vertex: u32, subsector: u32) -> Option<u32> {
        let slot = self.slot(vertex, subsector)?;
        let h = self.horizons[slot];
        (h != NO_HORIZON).then_some(h)
    }

    /// The horizon point of `vertex` in `subsector`, with the undersampling fix applied when it was enabled.
    pub fn horizon_point(&self, vertex: u32, subsector: u32) -> Option<HorizonPoint> {
        let slot = self.slot(vertex, subsector)?;
        if let Ok(i) = self.edge_points.binary_search_by_key(&(slot as u64), |&(s, _)| s) {
            return Some(HorizonPoint::Edge(self.edge_points[i].1));
        }
        let h = self.horizons[slot];
        (h != NO_HORIZON).then_some(HorizonPoint::Vertex(h))
    }

    /// The per-sector summaries, vertex-major (`[v * sectors + i]`, `slope` NaN where [`HorizonField::sector_summary`]
    /// is `None`), taken out of the field; the rest of it is freed at once (a large terrain's next stages need that
    /// memory).
    pub fn into_summaries(self) -> Vec<SectorHorizon> {
        self.summaries
    }

    /// The summary of `vertex` in `sector`: `None` when some subsector of the sector has no horizon (the vertex
    /// is then never occluded from that sector), or the indices are out of range.
    pub fn sector_summary(&self, vertex: u32, sector: u32) -> Option<SectorHorizon> {
        if vertex as usize >= self.num_vertices || sector >= self.config.sectors() {
            return None;
        }
        let s = self.summaries[vertex as usize * self.config.sectors() as usize + sector as usize];
        (!s.slope.is_nan()).then_some(s)
    }

    /// Number of (vertex, subsector) pairs whose horizon points differ; every pair counts when the fields have
    /// different shapes.
    pub fn mismatches(&self, other: &HorizonField) -> usize {
        if self.config != other.config || self.num_vertices != other.num_vertices {
            return self.horizons.len().max(other.horizons.len());
        }
        self.mismatch_slots(other).count()
    }

    /// The first `(vertex, subsector)` whose horizon points differ, for diagnostics.
    pub fn first_mismatch(&self, other: &HorizonField) -> Option<(u32, u32)> {
        if self.config != other.config || self.num_vertices != other.num_vertices {
            return Some((0, 0));
        }
        self.mismatch_slots(other)
            .next()
            .map(|slot| ((slot % self.num_vertices) as u32, (slot / self.num_vertices) as u32))
    }

    /// Number of (vertex, subsector) pairs whose horizon is an edge point.
    pub fn edge_horizon_count(&self) -> usize {
        self.edge_points.len()
    }

    /// Number of (vertex, subsector) pairs with no horizon at all.
    pub fn empty_count(&self) -> usize {
        let empty_vertex = self.horizons.iter().filter(|&&h| h == NO_HORIZON).count();
        let filled_by_edges = self
            .edge_points
            .iter()
            .filter(|(slot, _)| self.horizons[*slot as usize] == NO_HORIZON)
            .count();
        empty_vertex - filled_by_edges
    }

    /// Checks the field's invariants: horizon indices in range and never the vertex itself, edge points sorted by
    /// slot and on valid edges, a summary exactly where every subsector of the sector has a horizon point, with a
    /// finite slope and distance. Returns a description of the first violation.
    pub fn check_invariants(&self) -> Result<(), String> {
        let n = self.num_vertices;
        let total = self.config.total_subsectors() as usize;
        if self.horizons.len() != n * total || self.summaries.len() != n * self.config.sectors() as usize {
            return Err("storage sizes do not match the configuration".into());
        }
        for (slot, &h) in self.horizons.iter().enumerate() {
            if h != NO_HORIZON && (h as usize >= n || h as usize == slot % n.max(1)) {
                return Err(format!("slot {slot}: horizon {h} out of range or the vertex itself"));
            }
        }
        for w in self.edge_points.windows(2) {
            if w[0].0 >= w[1].0 {
                return Err(format!("edge points not sorted at slot {}", w[1].0));
            }
        }
        for (slot, e) in &self.edge_points {
            if *slot as usize >= self.horizons.len() || e.edge[0] >= e.edge[1] || e.edge[1] as usize >= n {
                return Err(format!("edge point at slot {slot} is invalid: {e:?}"));
            }
        }
        let k = self.config.subsectors();
        for v in 0..n as u32 {
            for i in 0..self.config.sectors() {
                let complete = (i * k..(i + 1) * k).all(|j| self.horizon_point(v, j).is_some());
                match self.sector_summary(v, i) {
                    Some(s) if !complete || !s.slope.is_finite() || !s.distance.is_finite() => {
                        return Err(format!(
                            "vertex {v} sector {i}: summary {s:?} without complete horizons"
                        ));
                    }
                    None if complete => return Err(format!("vertex {v} sector {i}: summary missing")),
                    _ => {}
                }
            }
        }
        Ok(())
    }

    fn mismatch_slots<'a>(&'a self, other: &'a HorizonField) -> impl Iterator<Item = usize> + 'a {
        let n = self.num_vertices.max(1);
        (0..self.horizons.len()).filter(move |&slot| {
            let (v, j) = ((slot % n) as u32, (slot / n) as u32);
            self.horizon_point(v, j) != other.horizon_point(v, j)
        })
    }

    fn slot(&self, vertex: u32, subsector: u32) -> Option<usize> {
        ((vertex as usize) < self.num_vertices && subsector < self.config.total_subsectors())
            .then(|| subsector as usize * self.num_vertices + vertex as usize)
    }

    /// Builds the field from vertex horizons and edge-point overrides, computing the sector summaries.
    fn assemble(
        tin: &Tin,
        geometry: &SectorGeometry,
        horizons: Vec<u32>,
        edge_points: Vec<(u64, EdgeHorizon)>,
        undersampling_radius: Option<f64>,
    ) -> HorizonField {
        let config = *geometry.config();
        let n = tin.num_vertices();
        let sectors = config.sectors() as usize;
        let k = config.subsectors() as usize;
        let origin = projection_origin(tin);
        let mut field = HorizonField {
            origin,
            config,
            num_vertices: n,
            undersampling_radius,
            horizons,
            edge_points,
            summaries: vec![
                SectorHorizon {
                    slope: f64::NAN,
                    distance: f64::NAN,
                };
                n * sectors
            ],
        };
        let mut summaries = std::mem::take(&mut field.summaries);
        summaries.par_chunks_mut(sectors).enumerate().for_each(|(v, row)| {
            let p = tin.position(v as u32);
            for (i, out) in row.iter_mut().enumerate() {
                let ri = geometry.sector_centre(i);
                let mut summary = Some(SectorHorizon {
                    slope: f64::INFINITY,
                    distance: f64::NEG_INFINITY,
                });
                for j in i * k..(i + 1) * k {
                    match (field.horizon_point(v as u32, j as u32), summary.as_mut()) {
                        (Some(h), Some(sum)) => {
                            let wedge = geometry.wedge(j);
                            let q = h.position(tin);
                            let dt = wedge.project(origin, q.truncate()) - wedge.project(origin, p.truncate());
                            sum.slope = sum.slope.min((q.z - p.z) / dt);
                            sum.distance = sum.distance.max(ri.dot(q.truncate() - p.truncate()));
                        }
                        _ => summary = None,
                    }
                }
                if let Some(s) = summary {
                    *out = s;
                }
            }
        });
        field.summaries = summaries;
        field
    }
}

/// Checks an undersampling radius as [`compute`] does: off (`None`) or a positive finite number of metres.
pub fn check_undersampling_radius(radius: Option<f64>) -> Result<(), HorizonError> {
    match radius {
        Some(radius) if !(radius.is_finite() && radius > 0.0) => Err(HorizonError::InvalidRadius { radius }),
        _ => Ok(()),
    }
}

/// Checks the input of [`compute`] and [`brute_force`].
fn validate(tin: &Tin, opts: &HorizonOptions) -> Result<(), HorizonError> {
    check_undersampling_radius(opts.undersampling_radius)?;
    let limit = NO_HORIZON as usize - 1;
    if tin.num_vertices() > limit {
        return Err(HorizonError::TooManyVertices {
            vertices: tin.num_vertices(),
            limit,
        });
    }
    for (vertex, p) in tin.positions().iter().enumerate() {
        for (axis, value) in [("x", p.x), ("y", p.y), ("z", p.z)] {
            if !tin::coordinate_in_range(value) {
                return Err(HorizonError::CoordinateOutOfRange {
                    vertex: vertex + 1,
                    axis,
                    value,
                });
            }
        }
    }
    Ok(())
}

/// Computes the horizon of every vertex in every subsector with the covering-set sweep (O(n log² n) per
/// subsector, subsectors in parallel), then the undersampling fix if enabled, then the sector summaries.
///
/// Deterministic: the result does not depend on the number of threads.
pub fn compute(tin: &Tin, config: &SectorConfig, opts: &HorizonOptions) -> Result<HorizonField, HorizonError> {
    validate(tin, opts)?;
    let geometry = SectorGeometry::new(config);
    let positions = tin.positions();
    let n = positions.len();
    let total = geometry.total();
    let origin = projection_origin(tin);
    let mut horizons = vec![NO_HORIZON; n * total];
    let done = AtomicUsize::new(0);
    // One task per run of consecutive subsectors, a few runs per thread: within a run each sweep hands its sorted
    // order to the next (one sort saved per sweep). Rayon runs at most one task per worker thread at a time, so
    // the working memory is that of (threads) sweeps, each O(n log n), kept from one sweep of a run to the next.
    // The result does not depend on the runs.
    let run = (total / (4 * rayon::current_num_threads().max(1))).max(1);
    horizons
        .par_chunks_mut((n * run).max(1))
        .enumerate()
        .for_each(|(c, block)| {
            let (mut previous, mut scratch) = (None, sweep::Scratch::default());
            for (k, out) in block.chunks_mut(n.max(1)).enumerate() {
                let wedge = geometry.wedge(c * run + k);
                previous = Some(sweep::sweep_subsector(
                    positions,
                    origin,
                    &wedge,
                    out,
                    previous,
                    &mut scratch,
                ));
                let finished = done.fetch_add(1, AtomicOrdering::Relaxed) + 1;
                if let Some(progress) = &opts.progress {
                    progress(finished, total);
                }
            }
        });
    let edge_points = match opts.undersampling_radius {
        Some(radius) => undersampling::fast(tin, &geometry, origin, radius, &horizons),
        None => Vec::new(),
    };
    Ok(HorizonField::assemble(
        tin,
        &geometry,
        horizons,
        edge_points,
        opts.undersampling_radius,
    ))
}

/// Computes the same field as [`compute`] by brute force: every vertex against every other vertex (O(n²), vertices
/// in parallel), and for the undersampling fix every nearby edge against every subsector. The reference that
/// `compute` must match exactly; practical up to some 10⁴–10⁵ vertices.
pub fn brute_force(tin: &Tin, config: &SectorConfig, opts: &HorizonOptions) -> Result<HorizonField, HorizonError> {
    validate(tin, opts)?;
    let geometry = SectorGeometry::new(config);
    let origin = projection_origin(tin);
    let horizons = oracle::vertex_horizons(tin.positions(), origin, &geometry);
    if let Some(progress) = &opts.progress {
        progress(1, 1);
    }
    let edge_points = match opts.undersampling_radius {
        Some(radius) => undersampling::straightforward(tin, &geometry, origin, radius, &horizons),
        None => Vec::new(),
    };
    Ok(HorizonField::assemble(
        tin,
        &geometry,
        horizons,
        edge_points,
        opts.undersampling_radius,
    ))
}

/// The point `o` of every projection `t = r · (x − o)` ([`crate::sector::Wedge::project`]) of a TIN: the lower-left
/// corner of its bounding box in x,y. Unlike [`Tin::origin`] (rounded to whole kilometres) it moves exactly with the
/// terrain under any exactly representable translation, so `x − o`, and with it every rounding decision, is the same
/// for a translated copy.
pub fn projection_origin(tin: &Tin) -> DVec2 {
    tin.bbox().min.truncate()
}
