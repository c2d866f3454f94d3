//! Seeded synthetic terrain: a ridged multifractal with broad valleys, as a [`Grid`] or as a [`Tin`] of an exact
//! vertex count.
//!
//! Heights follow Musgrave's ridged multifractal (Ebert et al., "Texturing and Modeling: A Procedural Approach",
//! ch. 16): each octave contributes `(1 - |noise|)²`, weighted by the previous octave's signal, so ridges are sharp
//! and valley floors smooth. The noise is 2-D gradient noise (Perlin's improved noise) over a permutation table
//! shuffled by a seeded `ChaCha8Rng`. Octaves are rotated by the exact rotation `(0.6, 0.8)` and scaled by 2, so no
//! grid direction dominates; the input position is first displaced by a small gradient-noise domain warp (0.2 of the
//! coarsest wavelength) so ridge lines meander instead of following the noise's circular arcs. A low-frequency
//! gradient-noise swell modulates the ridges, and the result is raised to the power 1.5 to widen the valleys. Heights
//! are then scaled to span exactly `[0, relief]` over the generated points.
//!
//! Choices:
//! - Everything is computed with `+ - * /`, `floor` and `sqrt` only (all exactly rounded in IEEE 754), and random
//!   numbers come from `ChaCha8Rng::seed_from_u64` through `next_u64` alone, so the output is bit-identical on every
//!   platform.
//! - The coarsest ridges have a wavelength of a third of the extent; octaves are halved in wavelength while the finest
//!   stays at least six point spacings long (at most 12 octaves); each octave has 0.45 of the previous amplitude.
//! - [`synth_tin`] places points on a jittered lattice: `round(√n)` rows with the `n` points spread over them as
//!   evenly as possible, each point moved by up to ±35% of its spacing, except that points on the boundary stay on
//!   the square's edges (so the footprint is exactly the square `[0, extent]²`). Points are therefore distinct and
//!   the Delaunay triangulation has exactly `n` vertices.

use glam::{DVec2, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::delaunay::{DedupePolicy, triangulate};
use crate::error::{Result, TinError};
use crate::grid::Grid;
use crate::mesh::Tin;

/// Parameters of synthetic terrain.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SynthOptions {
    /// Number of vertices of [`synth_tin`] (exact), or about the number of samples of [`synth_grid`] (at least 4).
    pub vertices: usize,
    /// Seed of the random generator (noise and point jitter).
    pub rng_seed: u64,
    /// Side of the square footprint (m); [`SynthOptions::new`] uses `30 · √vertices`, a 30 m spacing.
    pub extent: f64,
    /// Height difference between the lowest and the highest point (m); [`SynthOptions::new`] uses `extent / 10`.
    pub relief: f64,
}

impl SynthOptions {
    /// Options for `vertices` vertices with the default extent (`30 · √vertices` m) and relief (`extent / 10`).
    pub fn new(vertices: usize, rng_seed: u64) -> SynthOptions {
        let extent = 30.0 * (vertices as f64).sqrt();
        SynthOptions {
            vertices,
            rng_seed,
            extent,
            relief: extent / 10.0,
        }
    }

    /// Checks the vertex count (4 to 2^31), extent (positive, finite, below 1e12 m, and at least 1 mm per point
    /// spacing, `extent / √vertices`) and relief (0, or at least 1 µm and below 1e12 m: every coordinate stays within
    /// what the mesh readers accept).
    pub fn validate(&self) -> Result<()> {
        if !(4..=1 << 31).contains(&self.vertices) {
            return Err(TinError::InvalidParameter(format!(
                "synthetic terrain needs 4 to 2^31 vertices, got {}",
                self.vertices
            )));
        }
        if !(self.extent.is_finite() && self.extent > 0.0 && self.extent < 1e12) {
            return Err(TinError::InvalidParameter(format!(
                "synthetic terrain extent (--extent) must be positive and below 1e12 m, got {}",
                crate::compact_number(self.extent)
            )));
        }
        let spacing = self.extent / (self.vertices as f64).sqrt();
        if spacing < 1e-3 {
            return Err(TinError::InvalidParameter(format!(
                "synthetic terrain extent (--extent) {:.3e} m is too small for {} vertices: points would be \
                 {spacing:.3e} m apart (at least 1 mm)",
                self.extent, self.vertices
            )));
        }
        if !(self.relief.is_finite() && (self.relief == 0.0 || (1e-6..1e12).contains(&self.relief))) {
            return Err(TinError::InvalidParameter(format!(
                "synthetic terrain relief (--relief) must be 0, or at least 1 µm and below 1e12 m, got {}",
                crate::compact_number(self.relief)
            )));
        }
        Ok(())
    }
}

impl Default for SynthOptions {
    /// 10,000 vertices, seed 0.
    fn default() -> Self {
        SynthOptions::new(10_000, 0)
    }
}

/// A grid of about `opts.vertices` samples (`round(√vertices)` on a side, at least 2) over `[0, extent]²`, with
/// heights in `[0, relief]`. Row 0 is the northern edge (`y = extent`).
pub fn synth_grid(opts: &SynthOptions) -> Result<Grid> {
    opts.validate()?;
    let mut rng = ChaCha8Rng::seed_from_u64(opts.rng_seed);
    let terrain = Terrain::new(&mut rng, opts);
    let n = round_sqrt(opts.vertices).max(2);
    let step = opts.extent / (n - 1) as f64;
    let mut z = Vec::new();
    z.try_reserve_exact(n * n).map_err(|_| {
        TinError::InvalidParameter(format!(
            "not enough memory for a synthetic grid of {n} x {n} samples ({:.1} GB)",
            (n * n * 8) as f64 / 1e9
        ))
    })?;
    for r in 0..n {
        let y = opts.extent - r as f64 * step;
        for c in 0..n {
            z.push(terrain.raw(c as f64 * step, y));
        }
    }
    normalise(&mut z, opts.relief);
    Grid::new(n, n, step, step, DVec2::new(0.0, opts.extent), z)
}

/// A Delaunay TIN of exactly `opts.vertices` vertices over `[0, extent]²`, with heights in `[0, relief]`.
pub fn synth_tin(opts: &SynthOptions) -> Result<Tin> {
    opts.validate()?;
    let mut rng = ChaCha8Rng::seed_from_u64(opts.rng_seed);
    let terrain = Terrain::new(&mut rng, opts);
    let n = opts.vertices;
    let rows = round_sqrt(n).max(2);
    let hy = opts.extent / (rows - 1) as f64;
    let mut points = Vec::new();
    points.try_reserve_exact(n).map_err(|_| {
        TinError::InvalidParameter(format!(
            "not enough memory for a synthetic terrain of {n} vertices (its points alone take {:.1} GB)",
            (n * std::mem::size_of::<DVec3>()) as f64 / 1e9
        ))
    })?;
    for j in 0..rows {
        let count = n / rows + usize::from(j < n % rows);
        let hx = opts.extent / (count - 1) as f64;
        for i in 0..count {
            let (jx, jy) = (jitter(&mut rng), jitter(&mut rng));
            let x = if i == 0 {
                0.0
            } else if i == count - 1 {
                opts.extent
            } else {
                i as f64 * hx + jx * hx
            };
            let y = if j == 0 {
                0.0
            } else if j == rows - 1 {
                opts.extent
            } else {
                j as f64 * hy + jy * hy
            };
            points.push(DVec3::new(x, y, 0.0));
        }
    }
    let mut z: Vec<f64> = points.iter().map(|p| terrain.raw(p.x, p.y)).collect();
    normalise(&mut z, opts.relief);
    for (p, h) in points.iter_mut().zip(z) {
        p.z = h;
    }
    let (tin, _) = triangulate(&points, DedupePolicy::Reject)?;
    if tin.num_vertices() != n {
        return Err(TinError::TooFewPoints(format!(
            "synthetic terrain: {} of {n} points survived triangulation",
            tin.num_vertices()
        )));
    }
    Ok(tin)
}

/// `round(√n)` in integers (exact for all `usize`).
fn round_sqrt(n: usize) -> usize {
    let mut r = (n as f64).sqrt() as usize;
    while r.checked_mul(r).is_none_or(|s| s > n) {
        r -= 1;
    }
    while (r + 1).checked_mul(r + 1).is_some_and(|s| s <= n) {
        r += 1;
    }
    // r = floor(√n); round up when n ≥ (r + ½)² = r² + r + ¼, i.e. n > r² + r.
    if n > r * r + r { r + 1 } else { r }
}

/// A uniform number in `[0, 1)` from the top 53 bits of one `next_u64` (portable).
fn unit(rng: &mut ChaCha8Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A jitter in `[-0.35, 0.35)` of a spacing.
fn jitter(rng: &mut ChaCha8Rng) -> f64 {
    (unit(rng) - 0.5) * 0.7
}

/// Scales `z` linearly onto `[0, relief]` (all zero if `z` is constant).
/// Heights whose magnitude is below what the readers accept (`1 / COORDINATE_LIMIT`) become 0, so every terrain
/// written reads back.
fn normalise(z: &mut [f64], relief: f64) {
    let lo = z.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = z.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let span = hi - lo;
    for h in z {
        *h = if span > 0.0 {
            ((*h - lo) / span * relief).clamp(0.0, relief)
        } else {
            0.0
        };
        if *h < 1.0 / crate::COORDINATE_LIMIT {
            *h = 0.0;
        }
    }
}

/// The height function before normalisation.
struct Terrain {
    noise: GradientNoise,
    /// Per-octave offsets, so octaves are not correlated at the origin.
    offsets: Vec<DVec2>,
    /// Offset of the low-frequency swell.
    swell_offset: DVec2,
    /// Offsets of the two components of the domain warp.
    warp_offsets: [DVec2; 2],
    /// 1 / (coarsest wavelength).
    frequency: f64,
}

impl Terrain {
    fn new(rng: &mut ChaCha8Rng, opts: &SynthOptions) -> Terrain {
        let noise = GradientNoise::new(rng);
        let coarsest = opts.extent / 3.0;
        let spacing = opts.extent / (opts.vertices as f64).sqrt();
        let mut octaves = 1;
        let mut wavelength = coarsest;
        while octaves < 12 && wavelength / 2.0 >= 6.0 * spacing {
            octaves += 1;
            wavelength /= 2.0;
        }
        let mut offset = || DVec2::new(unit(rng) * 256.0, unit(rng) * 256.0);
        let offsets = (0..octaves).map(|_| offset()).collect();
        let swell_offset = offset();
        let warp_offsets = [offset(), offset()];
        Terrain {
            noise,
            offsets,
            swell_offset,
            warp_offsets,
            frequency: 1.0 / coarsest,
        }
    }

    /// Ridged multifractal (offset 1, gain 2, amplitude ratio 0.45, lacunarity 2) of the warped position, times a
    /// swell, to the power 1.5.
    fn raw(&self, x: f64, y: f64) -> f64 {
        let p0 = DVec2::new(x, y) * self.frequency;
        // Domain warp: bends the ridge lines, which plain gradient noise draws as circular arcs.
        let warp = DVec2::new(
            self.noise.at(p0 + self.warp_offsets[0]),
            self.noise.at(p0 + self.warp_offsets[1]),
        );
        let mut p = p0 + warp * 0.2;
        let mut sum = 0.0;
        let mut weight = 1.0;
        let mut amplitude = 1.0;
        for off in &self.offsets {
            let n = self.noise.at(p + *off);
            let mut signal = 1.0 - n.abs();
            signal *= signal;
            signal *= weight;
            weight = (signal * 2.0).clamp(0.0, 1.0);
            sum += signal * amplitude;
            amplitude *= 0.45;
            // Rotate by (0.6, 0.8) and double the frequency.
            p = DVec2::new(1.2 * p.x - 1.6 * p.y, 1.6 * p.x + 1.2 * p.y);
        }
        let swell = 0.5 + 0.5 * self.noise.at(p0 * 0.5 + self.swell_offset).clamp(-1.0, 1.0);
        let h = sum * (0.35 + 0.65 * swell);
        h * h.sqrt()
    }
}

/// 2-D gradient noise (Perlin's improved noise) over a seeded permutation table; values in about `[-1, 1]`.
struct GradientNoise {
    perm: [u8; 512],
}

impl GradientNoise {
    fn new(rng: &mut ChaCha8Rng) -> GradientNoise {
        let mut table: [u8; 256] = std::array::from_fn(|i| i as u8);
        // Fisher-Yates with `next_u64 % (i + 1)`: portable (the bias is far below anything visible).
        for i in (1..256).rev() {
            let j = (rng.next_u64() % (i as u64 + 1)) as usize;
            table.swap(i, j);
        }
        GradientNoise {
            perm: std::array::from_fn(|i| table[i & 255]),
        }
    }

    fn at(&self, p: DVec2) -> f64 {
        let (fx, fy) = (p.x.floor(), p.y.floor());
        let xi = (fx as i64 & 255) as usize;
        let yi = (fy as i64 & 255) as usize;
        let (x, y) = (p.x - fx, p.y - fy);
        let (u, v) = (fade(x), fade(y));
        let perm = &self.perm;
        let a = perm[xi] as usize + yi;
        let b = perm[xi + 1] as usize + yi;
        // Eight unit gradients at 22.5° + k·45°: none is parallel to an axis, so the noise never vanishes along a
        // whole lattice edge (which the ridge function would turn into a straight crest).
        const A: f64 = 0.923_879_532_511_286_7; // cos 22.5°
        const B: f64 = 0.382_683_432_365_089_8; // sin 22.5°
        let g = |h: u8, x: f64, y: f64| match h & 7 {
            0 => A * x + B * y,
            1 => B * x + A * y,
            2 => -B * x + A * y,
            3 => -A * x + B * y,
            4 => -A * x - B * y,
            5 => -B * x - A * y,
            6 => B * x - A * y,
            _ => A * x - B * y,
        };
        let lerp = |t: f64, a: f64, b: f64| a + t * (b - a);
        lerp(
            v,
            lerp(u, g(perm[a], x, y), g(perm[b], x - 1.0, y)),
            lerp(u, g(perm[a + 1], x, y - 1.0), g(perm[b + 1], x - 1.0, y - 1.0)),
        )
    }
}

/// Perlin's quintic fade `6t⁵ - 15t⁴ + 10t³`.
fn fade(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn small(vertices: usize, rng_seed: u64) -> SynthOptions {
        SynthOptions::new(vertices, rng_seed)
    }

    /// Checks the footprint, the height range and the vertex count.
    fn check_tin(tin: &Tin, opts: &SynthOptions) {
        assert_eq!(tin.num_vertices(), opts.vertices);
        let b = tin.bbox();
        assert_eq!(
            (b.min.x, b.min.y, b.max.x, b.max.y),
            (0.0, 0.0, opts.extent, opts.extent)
        );
        assert_eq!(b.min.z, 0.0);
        assert_eq!(b.max.z, opts.relief);
        assert!(tin.positions().iter().all(|p| p.is_finite()));
        // A triangulation of n points with h on the hull has 2n - 2 - h triangles; here h >= 4.
        assert!(tin.num_triangles() <= 2 * opts.vertices - 6);
    }

    #[test]
    fn exact_vertex_counts() {
        for n in [4, 5, 6, 7, 8, 9, 10, 11, 99, 1000, 1001, 4097] {
            let opts = small(n, 7);
            let tin = synth_tin(&opts).expect("synthetic TIN");
            check_tin(&tin, &opts);
        }
    }

    #[test]
    fn same_seed_same_terrain_other_seed_other_terrain() {
        let a = synth_tin(&small(2000, 11)).expect("tin");
        let b = synth_tin(&small(2000, 11)).expect("tin");
        let c = synth_tin(&small(2000, 12)).expect("tin");
        assert_eq!(a, b);
        assert_ne!(a.positions(), c.positions());
        let ga = synth_grid(&small(2000, 11)).expect("grid");
        assert_eq!(ga, synth_grid(&small(2000, 11)).expect("grid"));
        assert_ne!(ga.z, synth_grid(&small(2000, 12)).expect("grid").z);
    }

    /// Pins the generator's output bit for bit: a change here means terrain changed for every user (or that a
    /// platform computes differently, which the design forbids).
    #[test]
    fn output_is_pinned() {
        let tin = synth_tin(&small(1000, 42)).expect("tin");
        let fingerprint = tin.positions().iter().fold(0u64, |h, p| {
            [p.x, p.y, p.z]
                .iter()
                .fold(h, |h, v| (h ^ v.to_bits()).wrapping_mul(0x0100_0000_01b3))
        });
        assert_eq!(fingerprint, PINNED_FINGERPRINT, "fingerprint {fingerprint:#x}");
    }
    const PINNED_FINGERPRINT: u64 = 0x2a91_b51f_36d1_7cbd;

    #[test]
    fn grid_has_ridges_and_valleys() {
        for seed in 0..5 {
            let opts = small(10_000, seed);
            let g = synth_grid(&opts).expect("grid");
            assert_eq!((g.rows, g.cols), (100, 100));
            assert_eq!(g.dx, opts.extent / 99.0);
            assert!(g.z.iter().all(|&z| (0.0..=opts.relief).contains(&z)));
            let (mut maxima, mut minima) = (0, 0);
            for r in 1..g.rows - 1 {
                for c in 1..g.cols - 1 {
                    let z = g.z[r * g.cols + c];
                    let around = (r - 1..=r + 1)
                        .flat_map(|rr| (c - 1..=c + 1).map(move |cc| (rr, cc)))
                        .filter(|&(rr, cc)| (rr, cc) != (r, c))
                        .map(|(rr, cc)| g.z[rr * g.cols + cc]);
                    let (lo, hi) =
                        around.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), h| (lo.min(h), hi.max(h)));
                    maxima += usize::from(z > hi);
                    minima += usize::from(z < lo);
                }
            }
            let mut sorted = g.z.clone();
            sorted.sort_by(f64::total_cmp);
            let median = sorted[sorted.len() / 2];
            let low = g.z.iter().filter(|&&z| z < 0.25 * opts.relief).count() as f64 / g.z.len() as f64;
            let high = g.z.iter().filter(|&&z| z > 0.75 * opts.relief).count() as f64 / g.z.len() as f64;
            eprintln!("seed {seed}: {maxima} peaks, {minima} pits, median {median:.1}, low {low:.3}, high {high:.3}");
            assert!(
                maxima >= 20 && minima >= 20,
                "seed {seed}: {maxima} peaks, {minima} pits"
            );
            // Broad valleys, narrow ridges: most of the area lies in the lower half of the relief.
            assert!(median < 0.5 * opts.relief, "seed {seed}: median {median}");
            assert!(low > 0.08 && high > 0.01, "seed {seed}: low {low}, high {high}");
        }
    }

    #[test]
    fn rejects_bad_options() {
        let ok = small(100, 0);
        let bad = [
            SynthOptions { vertices: 3, ..ok },
            SynthOptions { extent: 0.0, ..ok },
            SynthOptions { extent: f64::NAN, ..ok },
            SynthOptions { relief: -1.0, ..ok },
            SynthOptions {
                relief: f64::INFINITY,
                ..ok
            },
            // Heights of about 1e-31 m: below what the readers accept (2^-100), so refused rather than written.
            SynthOptions { relief: 1e-30, ..ok },
        ];
        for opts in bad {
            assert!(
                matches!(synth_tin(&opts), Err(TinError::InvalidParameter(_))),
                "{opts:?}"
            );
            assert!(
                matches!(synth_grid(&opts), Err(TinError::InvalidParameter(_))),
                "{opts:?}"
            );
        }
        let flat = synth_tin(&SynthOptions { relief: 0.0, ..ok }).expect("flat terrain");
        assert!(flat.positions().iter().all(|p| p.z == 0.0));
        // The smallest relief accepted: every height is 0 or within the readers' range.
        let low = SynthOptions { relief: 1e-6, ..ok };
        let tin = synth_tin(&low).expect("1 µm relief");
        assert!(tin.positions().iter().all(|p| crate::coordinate_in_range(p.z)));
        let grid = synth_grid(&low).expect("1 µm relief");
        assert!(grid.z.iter().all(|&h| crate::coordinate_in_range(h)));
    }

    #[test]
    fn heights_below_the_readers_range_become_zero() {
        let mut z = vec![0.0, 1e-40, 1.0, 0.5];
        normalise(&mut z, 1.0);
        assert_eq!(z, [0.0, 0.0, 1.0, 0.5]);
    }

    #[test]
    fn round_sqrt_matches_real_rounding() {
        for n in 0..100_000usize {
            assert_eq!(round_sqrt(n), (n as f64).sqrt().round() as usize, "n = {n}");
        }
        assert_eq!(round_sqrt(usize::MAX), 1 << 32);
    }

    #[test]
    fn a_million_vertices() {
        let opts = small(1_000_000, 5);
        let tin = synth_tin(&opts).expect("tin");
        check_tin(&tin, &opts);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(40))]

        #[test]
        fn any_count_extent_and_relief(
            vertices in 4usize..3000,
            seed in any::<u64>(),
            extent in 1.0f64..1e6,
            relief in 0.0f64..5000.0,
        ) {
            let opts = SynthOptions { vertices, rng_seed: seed, extent, relief };
            let tin = synth_tin(&opts).expect("tin");
            prop_assert_eq!(tin.num_vertices(), vertices);
            let b = tin.bbox();
            prop_assert_eq!((b.min.x, b.min.y, b.max.x, b.max.y), (0.0, 0.0, extent, extent));
            prop_assert!(b.min.z >= 0.0 && b.max.z <= relief);
        }
    }
}
