//! Options shared by the commands that cull: the horizon cullers' parameters (safe, lloyd-egbert), and files of eye
//! positions.

use std::path::Path;

use anyhow::{Context, Result};
use clap::Args;
use cull::{CullMethod, SafeParams};

use super::cull_cmd::parse_point;

/// The horizon cullers' run-time parameters (nothing of them is stored in the `.tch`): `--columns` for both `safe`
/// and `lloyd-egbert`, the others for `safe` alone.
#[derive(Clone, Debug, Args)]
pub struct SafeArgs {
    /// Safe and lloyd-egbert cullers: horizon columns per 90° face, a power of two from 2 to 65536 (more: finer
    /// horizon, slower).
    #[arg(long, default_value_t = 256, value_name = "N")]
    pub columns: usize,
    /// Safe culler: largest patch (triangles) it tests and draws below the hierarchy's leaves, 1 to 64.
    #[arg(long, default_value_t = 16, value_name = "N")]
    pub patch: usize,
    /// Safe culler: most occluder edges written per cull, nearest first (bounds the cost of views that see
    /// much terrain; fewer occluders cull less, never wrongly). Unlimited by default.
    #[arg(long, value_name = "N")]
    pub occluder_budget: Option<usize>,
    /// Safe culler: most work units per cull (nodes tested while refining, occluder edges and chains written; a
    /// count, so culls stay reproducible). Once spent, the nodes still queued are tested against the horizon as it
    /// stands, largest first, split up to N/8 more times and otherwise drawn whole: the cost of a cull is bounded
    /// whatever the view, at the price of drawing more in views that see much terrain (never of culling a visible
    /// triangle). The default caps views that see most of a 1M-vertex terrain (from the sky) and is not reached by
    /// smaller or less open views; about 5000 kept a cull of a 1M-vertex terrain near 1 ms, drawing much more.
    #[arg(long, default_value_t = cull::DEFAULT_WORK_BUDGET, value_name = "N")]
    pub work_budget: usize,
    /// Safe culler: a visible node whose circle spans fewer than N horizon columns is drawn whole instead of being
    /// refined down to its patches, and writes only its two crests (bottleneck paths of its TIN edges, across x and
    /// across y) as occluders: cheaper culls of views that see much distant terrain, drawing more. 0 (the default)
    /// refines every visible node.
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub coarse_columns: usize,
}

impl SafeArgs {
    /// An error when a parameter is given that `method` does not use (`--columns` by `thesis` and `stewart`, the
    /// others by every method but `safe`), rather than ignoring it; a parameter at its default counts as not given.
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

    /// The first parameter given (not at its default), as written on the command line: `--columns`, then the safe
    /// culler's own.
    pub fn first_given(&self) -> Option<String> {
        let (columns, safe_only) = self.given();
        columns.or(safe_only)
    }

    /// `--columns` when given, and the first of the safe culler's own parameters given.
    fn given(&self) -> (Option<String>, Option<String>) {
        let d = SafeParams::default();
        let columns = (self.columns != d.columns_per_face).then(|| format!("--columns {}", self.columns));
        let safe_only = [
            (self.patch != d.patch).then(|| format!("--patch {}", self.patch)),
            self.occluder_budget.map(|n| format!("--occluder-budget {n}")),
            (self.work_budget != d.work_budget).then(|| format!("--work-budget {}", self.work_budget)),
            (self.coarse_columns != d.coarse_columns).then(|| format!("--coarse-columns {}", self.coarse_columns)),
        ];
        (columns, safe_only.into_iter().flatten().next())
    }

    /// The parameters, checked.
    pub fn params(&self) -> Result<SafeParams> {
        anyhow::ensure!(
            self.columns.is_power_of_two() && (2..=65536).contains(&self.columns),
            "--columns must be a power of two from 2 to 65536, got {}",
            self.columns
        );
        anyhow::ensure!(
            (1..=64).contains(&self.patch),
            "--patch must be from 1 to 64, got {}",
            self.patch
        );
        Ok(SafeParams {
            columns_per_face: self.columns,
            patch: self.patch,
            occluder_budget: self.occluder_budget.unwrap_or(usize::MAX),
            work_budget: self.work_budget,
            coarse_columns: self.coarse_columns,
        })
    }
}

/// Reads a file of eye positions, one `x,y,z` per line (blank lines and `#` comments skipped); errors name the file
/// and the 1-based line.
pub fn read_eyes(path: &Path) -> Result<Vec<[f64; 3]>> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let text = String::from_utf8(bytes).map_err(|_| {
        anyhow::anyhow!(
            "{}: a binary file, not a text file of eye positions (one x,y,z a line)",
            path.display()
        )
    })?;
    let eyes: Vec<[f64; 3]> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
        .map(|(i, l)| parse_point(l).map_err(|e| anyhow::anyhow!("{}:{}: {e}", path.display(), i + 1)))
        .collect::<Result<_>>()?;
    anyhow::ensure!(!eyes.is_empty(), "{}: no eye positions", path.display());
    Ok(eyes)
}
