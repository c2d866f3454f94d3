//! Options shared by the commands that cull: the horizon cullers' parameters (safe, lloyd-egbert), and files of eye
//! positions.

use std::path::Path;

use anyhow::{Context, Result};
use clap::Args;
use cull::{CullMethod, MAX_COLUMNS_PER_FACE, MAX_PATCH, SafeParams, SafeParamsError};

use super::Output;
use super::values::parse_point;

/// Warns that `method` culls nothing in `h`, read from `path`, when it is a region test (`thesis`, `stewart`) and the
/// file holds no regions (built with `--no-regions`, or nothing hid anything from its vertices).
pub fn warn_if_no_regions(path: &Path, h: &cull::Hierarchy, method: CullMethod, out: Output) {
    if matches!(method, CullMethod::Thesis | CullMethod::Stewart) && !h.has_regions() {
        out.warn(format!(
            "{} holds no regions (built with --no-regions, or the terrain hid nothing from its vertices in the \
             build): `{method}` culls nothing in it",
            path.display()
        ));
    }
}

/// The horizon cullers' run-time parameters (nothing of them is stored in the `.tch`): `--columns` for both `safe`
/// and `lloyd-egbert`, the others for `safe` alone.
#[derive(Clone, Debug, Args)]
pub struct SafeArgs {
    /// Safe and lloyd-egbert cullers: horizon columns per 90° face, a power of two from 2 to 65536 (more: finer
    /// horizon, slower) [default: 256].
    #[arg(long, value_name = "N")]
    pub columns: Option<usize>,
    /// Safe culler: largest patch (triangles) it tests and draws below the hierarchy's leaves, 1 to 64 [default: 16].
    #[arg(long, value_name = "N")]
    pub patch: Option<usize>,
    /// Safe culler: most occluder edges written per cull, nearest first (fewer occluders cull less, never
    /// wrongly). It bounds the writing, not the cost of a cull: with few occluders little is hidden, and every
    /// visible node is refined and tested, which can cost more than the default; --work-budget bounds the cost.
    /// Unlimited by default.
    #[arg(long, value_name = "N")]
    pub occluder_budget: Option<usize>,
    /// Safe culler: most work units per cull (nodes tested while refining, occluder edges and chains written; a
    /// count, so culls stay reproducible). Once spent, the nodes still queued are tested against the horizon as it
    /// stands, largest first, split at most ⌈N/8⌉ more times, and those left are tested once more, nearest first,
    /// behind the terrain's profiles along the grid-cell edges around the ones drawn before them (at most ⌈N/8⌉
    /// segments) and otherwise drawn whole: the cost of a cull is bounded whatever the view, at the price of drawing
    /// more in views that see much terrain (never of culling a visible triangle). The default caps views that see most
    /// of a 1M-vertex terrain (from the sky) and is not reached by smaller or less open views; smaller budgets make
    /// culls of a 1M-vertex terrain cheaper, drawing much more [default: 200000].
    #[arg(long, value_name = "N")]
    pub work_budget: Option<usize>,
    /// Safe culler: a visible node whose circle spans fewer than N horizon columns is drawn whole instead of being
    /// refined down to its patches, and writes only its two crests (bottleneck paths of its TIN edges, across x and
    /// across y) as occluders: cheaper culls of views that see much distant terrain, drawing more. Only inner nodes
    /// of at most 2048 triangles have crests and can be drawn so; larger ones and patches are refined as usual. 0
    /// (the default) refines every visible node.
    #[arg(long, value_name = "N")]
    pub coarse_columns: Option<usize>,
}

impl SafeArgs {
    /// An error when a parameter is given that `method` does not use (`--columns` by `thesis` and `stewart`, the
    /// others by every method but `safe`), rather than ignoring it, even at its default value.
    pub fn check_method(&self, method: CullMethod) -> Result<()> {
        let (columns, safe_only) = self.given();
        let unused = match method {
            CullMethod::Safe => None,
            CullMethod::LloydEgbert => safe_only.map(|f| (f, "the `safe` culler")),
            CullMethod::Thesis | CullMethod::Stewart => columns
                .map(|f| (f, "the `safe` and `lloyd-egbert` cullers"))
                .or_else(|| safe_only.map(|f| (f, "the `safe` culler"))),
        };
        if let Some((flag, whose)) = unused {
            anyhow::bail!(
                "{flag} is a parameter of {whose}; method `{}` does not use it",
                method.name()
            );
        }
        Ok(())
    }

    /// The first parameter given, as written on the command line: `--columns`, then the safe culler's own.
    pub fn first_given(&self) -> Option<String> {
        let (columns, safe_only) = self.given();
        columns.or(safe_only)
    }

    /// `--columns` when given, and the first of the safe culler's own parameters given.
    fn given(&self) -> (Option<String>, Option<String>) {
        let columns = self.columns.map(|n| format!("--columns {n}"));
        let safe_only = [
            self.patch.map(|n| format!("--patch {n}")),
            self.occluder_budget.map(|n| format!("--occluder-budget {n}")),
            self.work_budget.map(|n| format!("--work-budget {n}")),
            self.coarse_columns.map(|n| format!("--coarse-columns {n}")),
        ];
        (columns, safe_only.into_iter().flatten().next())
    }

    /// The parameters, checked.
    pub fn params(&self) -> Result<SafeParams> {
        let d = SafeParams::default();
        let params = SafeParams {
            columns_per_face: self.columns.unwrap_or(d.columns_per_face),
            patch: self.patch.unwrap_or(d.patch),
            occluder_budget: self.occluder_budget.unwrap_or(d.occluder_budget),
            work_budget: self.work_budget.unwrap_or(d.work_budget),
            coarse_columns: self.coarse_columns.unwrap_or(d.coarse_columns),
        };
        match params.check() {
            Ok(()) => Ok(params),
            Err(SafeParamsError::Columns(n)) => {
                anyhow::bail!("--columns must be a power of two from 2 to {MAX_COLUMNS_PER_FACE}, got {n}")
            }
            Err(SafeParamsError::Patch(n)) => anyhow::bail!("--patch must be from 1 to {MAX_PATCH}, got {n}"),
            Err(e) => Err(e.into()),
        }
    }
}

/// How far from the terrain's box (in any coordinate) `eval` takes an eye: 10,000 km, where its exact checker's
/// tolerance is still 1 cm.
pub const EVAL_REACH: f64 = 1e7;

/// Eye positions, each with where it was given, to name it in errors.
#[derive(Clone, Debug)]
pub struct Eyes {
    /// The positions, in order.
    pub points: Vec<[f64; 3]>,
    /// Where each was given: `--eye`, or `FILE:LINE`.
    sources: Vec<String>,
}

/// An eye this far below the ground under it, or less, is taken to be on it (the rounding of the ground's height
/// from its triangle's plane, for an eye put exactly on the terrain).
fn ground_tolerance(ground: f64) -> f64 {
    1e-9 * (1.0 + ground.abs())
}

impl Eyes {
    /// The one eye of `--eye`.
    pub fn given(eye: [f64; 3]) -> Eyes {
        Eyes {
            points: vec![eye],
            sources: vec!["--eye".into()],
        }
    }

    /// Reads a file of eye positions: one `x,y,z` a line; `#` starts a comment (to the end of the line), blank lines
    /// are skipped, and a leading byte-order mark is ignored.
    pub fn read(path: &Path) -> Result<Eyes> {
        let bytes = infile::read(path).with_context(|| format!("cannot read {}", path.display()))?;
        let text = String::from_utf8(bytes).map_err(|_| {
            anyhow::anyhow!(
                "{}: a binary file, not a text file of eye positions (one x,y,z a line)",
                path.display()
            )
        })?;
        let mut eyes = Eyes {
            points: Vec::new(),
            sources: Vec::new(),
        };
        let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
        for (i, line) in text.lines().enumerate() {
            let line = line.split_once('#').map_or(line, |(before, _)| before);
            if line.trim().is_empty() {
                continue;
            }
            let source = format!("{}:{}", path.display(), i + 1);
            eyes.points
                .push(parse_point(line).map_err(|e| anyhow::anyhow!("{source}: {e}"))?);
            eyes.sources.push(source);
        }
        anyhow::ensure!(!eyes.points.is_empty(), "{}: no eye positions", path.display());
        Ok(eyes)
    }

    /// Refuses an eye farther than [`EVAL_REACH`] from the box of `h`'s vertices in any coordinate: the exact checker
    /// that scores `eval` works to `1e-9` of the distance (`truth::walk`), a kilometre at 1e12 m, where it would call
    /// visible what is not.
    pub fn check_within_reach(&self, h: &cull::Hierarchy) -> Result<()> {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in &h.mesh.positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        for (i, e) in self.points.iter().enumerate() {
            let far = (0..3).map(|k| (lo[k] - e[k]).max(e[k] - hi[k])).fold(0.0, f64::max);
            anyhow::ensure!(
                far <= EVAL_REACH,
                "{} at {} lies {} m from the terrain's box: eval scores eyes within {} m of it (its exact checker \
                 works to 1e-9 of the distance)",
                self.name(i),
                super::output::point(e.to_owned()),
                tin::compact_number(far),
                tin::compact_number(EVAL_REACH)
            );
        }
        Ok(())
    }

    /// How errors name eye `i`: `eye 2 (eyes.txt:3)`, or `the eye (--eye)` for the one eye of `--eye`.
    pub fn name(&self, i: usize) -> String {
        if self.points.len() == 1 && self.sources[i] == "--eye" {
            "the eye (--eye)".to_owned()
        } else {
            format!("eye {} ({})", i + 1, self.sources[i])
        }
    }

    /// The ground's height under each eye on `h`'s mesh, `None` outside its footprint ([`truth::ground_heights`]).
    fn grounds(&self, h: &cull::Hierarchy) -> Vec<Option<f64>> {
        self.grounds_on(&h.mesh.positions, &h.mesh.triangles)
    }

    /// The ground's height under each eye on a mesh, `None` outside its footprint.
    fn grounds_on(&self, positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<Option<f64>> {
        let xy: Vec<glam::DVec2> = self.points.iter().map(|e| glam::DVec2::new(e[0], e[1])).collect();
        truth::ground_heights(positions, triangles, &xy)
    }

    /// Refuses an eye below the ground of `h`'s mesh (by more than the rounding of the ground's height): it sees none
    /// of the terrain. Eyes outside the footprint, on the ground or above it are fine. `above_ground_flag`: the
    /// command takes `--above-ground` (heights above the ground), which the error then suggests.
    pub fn check_not_below_ground(&self, h: &cull::Hierarchy, above_ground_flag: bool) -> Result<()> {
        self.check_not_below(self.grounds(h), above_ground_flag)
    }

    /// [`Eyes::check_not_below_ground`] on a plain mesh (a TIN read from a file, not a hierarchy).
    pub fn check_not_below_mesh(&self, tin: &tin::Tin, above_ground_flag: bool) -> Result<()> {
        let positions: Vec<[f64; 3]> = tin.positions().iter().map(|p| p.to_array()).collect();
        self.check_not_below(self.grounds_on(&positions, tin.triangles()), above_ground_flag)
    }

    /// Refuses an eye below its ground (`grounds`, one per eye).
    fn check_not_below(&self, grounds: Vec<Option<f64>>, above_ground_flag: bool) -> Result<()> {
        for (i, ground) in grounds.into_iter().enumerate() {
            let z = self.points[i][2];
            if let Some(g) = ground
                && z < g - ground_tolerance(g)
            {
                // Millimetres, unless the eye is closer than that to the ground (or farther than any terrain).
                let depth = if (1e-3..1e9).contains(&(g - z)) {
                    format!("{:.3}", g - z)
                } else {
                    format!("{:.1e}", g - z)
                };
                let ground = if g - z >= 1e-3 {
                    format!("{g:.3}")
                } else {
                    format!("{g}")
                };
                let [x, y, z] = self.points[i].map(tin::compact_number);
                anyhow::bail!(
                    "{} at x {x}, y {y}, z {z} is {depth} m below the ground (at z {ground} there): an eye below the \
                     ground sees none of the terrain{}",
                    self.name(i),
                    if above_ground_flag {
                        " (for heights above the ground, give --above-ground)"
                    } else {
                        ""
                    }
                );
            }
        }
        Ok(())
    }

    /// Reads each eye's z as a height above the ground of `h`'s mesh (`--above-ground`) and turns it into a world z;
    /// refuses negative heights and eyes outside the footprint.
    pub fn lift_above_ground(&mut self, h: &cull::Hierarchy) -> Result<()> {
        if let Some(i) = self.points.iter().position(|e| e[2] < 0.0) {
            anyhow::bail!(
                "{}: with --above-ground, z is a height above the ground and must be 0 or more (an eye below the \
                 ground sees none of the terrain), got {}",
                self.name(i),
                tin::compact_number(self.points[i][2])
            );
        }
        for (i, ground) in self.grounds(h).into_iter().enumerate() {
            let ground = ground.with_context(|| {
                format!(
                    "{} at x {}, y {} is outside the terrain's footprint: --above-ground has no ground there",
                    self.name(i),
                    tin::compact_number(self.points[i][0]),
                    tin::compact_number(self.points[i][1])
                )
            })?;
            self.points[i][2] += ground;
        }
        Ok(())
    }
}
