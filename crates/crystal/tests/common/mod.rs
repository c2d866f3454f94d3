//! Test terrains and a brute-force horizon oracle for the crystal tests.
#![allow(dead_code)]

use std::f64::consts::TAU;

use glam::{DVec2, DVec3};
use occlusion::{RegionTable, SectorHorizon};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tin::{DedupePolicy, Tin};

/// A jittered `nx × ny` grid with spacing `step`, each point moved by up to `jitter` in x and y, heights from `z`.
pub fn jittered_grid(nx: usize, ny: usize, step: f64, jitter: f64, seed: u64, z: impl Fn(DVec2) -> f64) -> Tin {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut points = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let xy = DVec2::new(
                i as f64 * step + rng.random_range(-jitter..=jitter),
                j as f64 * step + rng.random_range(-jitter..=jitter),
            );
            points.push(xy.extend(z(xy)));
        }
    }
    tin::triangulate(&points, DedupePolicy::Reject).expect("valid grid").0
}

/// A fractal-ish height function: octaves of products of sines with random phases, amplitude `amp` at the largest
/// wavelength `wave`, halving per octave.
pub fn fractal(seed: u64, amp: f64, wave: f64) -> impl Fn(DVec2) -> f64 {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
    let octaves: Vec<(f64, f64, f64, f64, f64)> = (0..5)
        .map(|o| {
            let f = TAU / wave * 2f64.powi(o);
            let a = amp / 2f64.powi(o);
            let angle = rng.random_range(0.0..TAU);
            (f, a, angle, rng.random_range(0.0..TAU), rng.random_range(0.0..TAU))
        })
        .collect();
    move |p: DVec2| {
        octaves
            .iter()
            .map(|&(f, a, angle, p1, p2)| {
                let (s, c) = angle.sin_cos();
                let (u, v) = (c * p.x + s * p.y, -s * p.x + c * p.y);
                a * (f * u + p1).sin() * (f * 0.8 * v + p2).cos()
            })
            .sum()
    }
}

/// A random fractal terrain on a jittered grid.
pub fn random_terrain(nx: usize, ny: usize, seed: u64) -> Tin {
    jittered_grid(nx, ny, 10.0, 3.0, seed, fractal(seed, 25.0, 120.0))
}

/// Brute-force sector horizons after the horizon crate's `sector` module: for each vertex and subsector, the vertex of
/// greatest slope among those in the subsector's closed wedge (slope along the subsector's centre direction; ties to
/// the smaller distance, then the smaller index); per sector the minimum slope over its subsectors and the largest
/// distance, along the sector's centre direction, to a subsector horizon point; `None` when a subsector has none.
/// Row-major: `result[v * sectors + s]`.
pub fn brute_horizons(positions: &[DVec3], sectors: u32, subsectors: u32) -> Vec<Option<SectorHorizon>> {
    let total = (sectors * subsectors) as usize;
    let width = TAU / total as f64;
    let centre = |j: usize| {
        let a = (j as f64 + 0.5) * width;
        DVec2::new(a.cos(), a.sin())
    };
    let sector_dirs: Vec<DVec2> = (0..sectors)
        .map(|i| {
            let [x, y] = cull::sector_direction(sectors, i);
            DVec2::new(x, y)
        })
        .collect();
    let mut out = Vec::with_capacity(positions.len() * sectors as usize);
    for (pi, p) in positions.iter().enumerate() {
        // Per subsector: (slope, dt, index).
        let mut best: Vec<Option<(f64, f64, usize)>> = vec![None; total];
        for (qi, q) in positions.iter().enumerate() {
            if qi == pi {
                continue;
            }
            let d = (q - p).truncate();
            if d == DVec2::ZERO {
                continue;
            }
            let f = cull::azimuth(d.x, d.y) / width;
            let j = (f.floor() as usize).min(total - 1);
            let mut wedges = vec![j];
            if f == f.floor() {
                wedges.push((j + total - 1) % total);
            }
            for j in wedges {
                let dt = centre(j).dot(d);
                if dt <= 0.0 {
                    continue;
                }
                let slope = (q.z - p.z) / dt;
                let better = match best[j] {
                    None => true,
                    Some((s, t, i)) => slope > s || (slope == s && (dt < t || (dt == t && qi < i))),
                };
                if better {
                    best[j] = Some((slope, dt, qi));
                }
            }
        }
        for s in 0..sectors as usize {
            let subs = &best[s * subsectors as usize..(s + 1) * subsectors as usize];
            if subs.iter().any(Option::is_none) {
                out.push(None);
                continue;
            }
            let slope = subs.iter().flatten().map(|b| b.0).fold(f64::INFINITY, f64::min);
            let distance = subs
                .iter()
                .flatten()
                .map(|b| sector_dirs[s].dot((positions[b.2] - p).truncate()))
                .fold(f64::NEG_INFINITY, f64::max);
            out.push(Some(SectorHorizon { slope, distance }));
        }
    }
    out
}

/// Vertex and triangle region tables of `tin` from brute-force horizons.
pub fn tables(tin: &Tin, sectors: u32, subsectors: u32) -> (RegionTable, RegionTable) {
    let h = brute_horizons(tin.positions(), sectors, subsectors);
    let vertices = RegionTable::of_vertices(tin.positions(), tin.bbox().min.truncate(), sectors, |v, s| {
        h[(v * sectors + s) as usize]
    });
    let tris = tin.triangles();
    let triangles = vertices.intersect_rows(tin.num_triangles(), |t| tris[t]);
    (vertices, triangles)
}

/// The lowest of three vertices (z, then index).
pub fn lowest_of(tin: &Tin, tri: [u32; 3]) -> u32 {
    let p = tin.positions();
    *tri.iter()
        .min_by(|&&a, &&b| p[a as usize].z.total_cmp(&p[b as usize].z).then(a.cmp(&b)))
        .expect("three vertices")
}

/// Re-checks the growth rule independently: replaying each crystal's joins in order, every triangle's recorded lowest
/// vertex is the crystal's lowest vertex so far (for a seed, the lowest of its own), and none of the triangle's
/// vertices is hidden from it by [`RegionTable::vertex_hidden_from`].
pub fn recheck_growth(tin: &Tin, vertices: &RegionTable, c: &crystal::Crystal) {
    let p = tin.positions();
    let mut joined: Vec<(u32, u32, u32)> = c
        .joins
        .iter()
        .enumerate()
        .filter_map(|(t, j)| j.map(|j| (j.crystal, j.seq, t as u32)))
        .collect();
    joined.sort_unstable();
    let mut current: Option<(u32, u32)> = None; // (crystal, lowest)
    for &(crystal, _, t) in &joined {
        let tri = tin.triangles()[t as usize];
        let j = c.joins[t as usize].expect("joined");
        let expected = match current {
            Some((k, low)) if k == crystal => low,
            _ => lowest_of(tin, tri),
        };
        assert_eq!(
            j.lowest, expected,
            "triangle {t} of crystal {crystal}: wrong lowest vertex"
        );
        let camera = p[j.lowest as usize];
        for v in tri {
            assert!(
                v == j.lowest || !vertices.vertex_hidden_from(v, p[v as usize], camera),
                "triangle {t} joined crystal {crystal} although vertex {v} is hidden from its lowest vertex {}",
                j.lowest
            );
        }
        let own = lowest_of(tin, tri);
        let next = if p[own as usize].z < p[expected as usize].z
            || (p[own as usize].z == p[expected as usize].z && own < expected)
        {
            own
        } else {
            expected
        };
        current = Some((crystal, next));
    }
    // Every triangle of a group joined a crystal; orphans that never joined have no record.
    for members in &c.groups {
        for &t in members {
            assert!(c.joins[t as usize].is_some(), "grouped triangle {t} has no join record");
        }
    }
}

/// Whether two regions are the same up to rounding: equal emptiness, equal left bound, and upper boundaries within
/// `1e-9` (relative to the heights' scale) at every chain vertex of either, between them and far beyond.
pub fn same_region(a: Option<&occlusion::Region>, b: Option<&occlusion::Region>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            let mut ts: Vec<f64> = a.points().iter().chain(b.points()).map(|p| p.x).collect();
            ts.sort_by(f64::total_cmp);
            let last = *ts.last().expect("non-empty");
            let mids: Vec<f64> = ts.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
            ts.extend(mids);
            ts.extend([last + 1.0, last + 100.0, last + 1e4]);
            let scale = a
                .points()
                .iter()
                .chain(b.points())
                .map(|p| p.y.abs())
                .fold(1.0, f64::max);
            let t0 = a.t0().max(b.t0());
            a.t0() == b.t0()
                && ts.iter().filter(|&&t| t >= t0).all(|&t| {
                    let (za, zb) = (a.height_at(t), b.height_at(t));
                    (za - zb).abs() <= 1e-9 * scale.max(za.abs()) * (1.0 + (t - t0).abs() / scale)
                })
        }
        _ => false,
    }
}

/// Checks that each group's regions are the intersection of its triangles' regions ([`occlusion::intersect_all`],
/// the running intersection), up to rounding.
pub fn recheck_group_regions(c: &crystal::Crystal, triangles: &RegionTable) {
    for (g, members) in c.groups.iter().enumerate() {
        for s in 0..triangles.sectors() {
            let want = occlusion::intersect_all(members.iter().map(|&t| triangles.get(t, s)));
            let got = c.hierarchy.nodes[g].regions[s as usize].as_ref();
            assert!(
                same_region(got, want.as_ref()),
                "group {g} sector {s}: region is not the intersection of its triangles': {got:?} vs {want:?}"
            );
        }
    }
}

/// Re-checks the pass bookkeeping from the join records: seeds per pass (the first pass's count, then
/// `max(1, ⌊first × unassigned / triangles⌋)`), crystals started and the largest one per pass, and the stop rule.
pub fn recheck_passes(tin: &Tin, c: &crystal::Crystal) {
    let n = tin.num_triangles();
    let p = &c.stats.passes;
    let first = c.params.first_seeds(n);
    assert!(!p.is_empty());
    assert_eq!(p[0].seeds, first);
    let mut sizes: std::collections::BTreeMap<(u32, u32), usize> = Default::default(); // (pass, crystal) -> size
    for j in c.joins.iter().flatten() {
        *sizes.entry((j.pass, j.crystal)).or_default() += 1;
    }
    let mut unassigned = n;
    for (k, pass) in p.iter().enumerate() {
        if k > 0 {
            assert_eq!(pass.seeds, (first * unassigned / n).max(1), "pass {k}: seeds");
        }
        let of_pass: Vec<usize> = sizes.iter().filter(|e| e.0.0 == k as u32).map(|e| *e.1).collect();
        assert_eq!(pass.new_groups, of_pass.len(), "pass {k}: crystals started");
        assert!(pass.new_groups <= pass.seeds);
        assert_eq!(
            pass.largest_new_group,
            of_pass.iter().copied().max().unwrap_or(0),
            "pass {k}: largest"
        );
        unassigned -= of_pass.iter().sum::<usize>();
        let last = k + 1 == p.len();
        let stop = pass.new_groups == 0
            || unassigned == 0
            || k as u32 == c.params.orphan_passes
            || (k > 0 && pass.largest_new_group < c.params.min_group);
        assert_eq!(stop, last, "pass {k}: the stop rule (unassigned {unassigned})");
    }
    assert_eq!(c.stats.orphan_passes as usize, p.len() - 1);
    assert_eq!(c.joins.iter().filter(|j| j.is_none()).count(), unassigned);
}
