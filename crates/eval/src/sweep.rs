//! Parameter sweeps: speed against accuracy over the build parameters (thesis 6.3, Table 3 and Figs. 16–17).
//!
//! A sweep builds the hierarchy for every combination of sectors `s`, subsectors `k`, first-pass seeds and crystal
//! random seeds, and scores each build against one ground truth (the viewpoints and their visible sets depend only
//! on the mesh and the viewpoint options, so they are computed once for the whole sweep, on the terrain in its
//! original triangle order; every build's draw lists are mapped back to that order through `crystal.order`).
//!
//! Choices:
//!
//! - The results are a CSV table, one line per combination × method × class (the classes, then `all`). Lines are
//!   kept sorted by the combination's key `(sectors, subsectors, seeds, rng_seed, viewpoints_per_class)` (both seeds 0
//!   for a quadtree, which uses neither), then in the
//!   evaluation's method and class order, so the file's order does not depend on the order the combinations ran in.
//!   The column `viewpoints` counts the viewpoints scored on the line (every class's on an `all` line), as in
//!   `eval`'s CSV.
//! - A sweep resumes: combinations whose key is already in the file with every line are not run again (one that
//!   lost a line is run again; a malformed field or a repeated line is refused). The key leaves out the
//!   viewpoint classes, the viewpoint seed and the field of view: resume only with the same ones.
//! - Combinations the horizon sweep rejects (fewer than 4 sectors, no subsectors, `s·k` above the limit) are skipped
//!   with a note rather than failing the sweep.
//! - The per-triangle method uses triangle regions made from the build's own vertex regions (no second horizon
//!   sweep).
//! - Combinations run one after the other, so that their wall times (each stage is parallel inside) are not
//!   disturbed by each other.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use anyhow::{Context, Result, bail};
use horizon::SectorConfig;
use tin::Tin;

use crate::evaluate::{
    EvalOptions, Evaluation, GroundTruthSet, Leaves, score, standard_method_names, standard_methods,
};
use pipeline::{BuildParams, BuildProgress, BuildReport, build, per_triangle_hierarchy, triangle_regions};

/// The header line of a sweep CSV (without the newline): `viewpoints_per_class` is the key's count of viewpoints
/// per class, `viewpoints` those scored on the line (as in `eval`'s CSV).
pub const HEADER: &str = "sectors,subsectors,seeds,rng_seed,viewpoints_per_class,vertices,triangles,horizon_seconds,\
regions_seconds,grouping_seconds,visibility_bytes,groups,orphans,orphan_passes_run,nodes,levels,top_level,method,class,\
viewpoints,false_culls_mean,false_culls_max,viewpoints_with_false_culls,false_cull_area_mean,occlusion_captured_mean,\
occlusion_captured_p50,overdraw_mean,triangles_drawn_mean,cull_ns,visible_fraction,drawn_fraction,leaf_limit,setup";

/// The digest of everything a sweep's lines depend on besides their key (the mesh, the build options every
/// combination shares, the evaluation's classes, viewpoint seed, field of view, safe-culler parameters and whether the
/// per-triangle method runs), written in the last column (`setup`) of every line: a file holds the sweep of one setup,
/// and a run with another one is refused instead of taking the file's lines for its own.
pub fn setup_digest(tin: &Tin, base: &BuildParams, eval: &EvalOptions) -> String {
    let mut hasher = crc32fast::Hasher::new();
    for p in tin.positions() {
        for c in p.to_array() {
            hasher.update(&c.to_bits().to_le_bytes());
        }
    }
    for t in tin.triangles() {
        for v in t {
            hasher.update(&v.to_le_bytes());
        }
    }
    let options = format!(
        "{base:?}|{:?}|{}|{}|{}|{:?}",
        eval.classes,
        eval.view_seed,
        eval.fov_deg.to_bits(),
        eval.per_triangle,
        eval.safe
    );
    hasher.update(options.as_bytes());
    format!("{:08x}", hasher.finalize())
}

/// What identifies a combination in a sweep file; ordered as the file's lines are.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SweepKey {
    /// Sectors `s`.
    pub sectors: u32,
    /// Subsectors per sector `k`.
    pub subsectors: u32,
    /// Seeds of the first crystal pass (resolved: never "default"); 0 for a quadtree, which has none.
    pub seeds: usize,
    /// Seed of the crystal's random generator; 0 for a quadtree, which has none.
    pub rng_seed: u64,
    /// Viewpoints per class.
    pub viewpoints: usize,
}

/// One combination to build and score.
#[derive(Clone, Debug, PartialEq)]
pub struct Combo {
    /// Its key.
    pub key: SweepKey,
    /// The build parameters.
    pub params: BuildParams,
}

/// The ranges of a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepSpec {
    /// Sector counts.
    pub sectors: Vec<u32>,
    /// Subsector counts.
    pub subsectors: Vec<u32>,
    /// First-pass seed counts; `None` is the default (one per 200 triangles).
    pub seeds: Vec<Option<usize>>,
    /// Crystal random seeds.
    pub rng_seeds: Vec<u64>,
    /// Everything else of the builds (its sectors, subsectors, seeds and rng seed are replaced).
    pub base: BuildParams,
    /// Viewpoints per class of the evaluation.
    pub viewpoints: usize,
}

/// The most combinations a sweep may list (10,000): each is a build and an evaluation, so a sweep of more would run
/// for weeks, and its notes on the combinations left out would fill the memory first.
pub const MAX_COMBINATIONS: usize = 10_000;

impl SweepSpec {
    /// The valid combinations for a mesh of `triangles` triangles, in key order without duplicates, and a note for
    /// each combination left out; an error when the lists make more than [`MAX_COMBINATIONS`] combinations.
    pub fn combos(&self, triangles: usize) -> Result<(Vec<Combo>, Vec<String>)> {
        let lists = [
            ("--sectors", self.sectors.len()),
            ("--subsectors", self.subsectors.len()),
            ("--seeds", self.seeds.len()),
            ("--rng-seeds", self.rng_seeds.len()),
        ];
        let count = lists.iter().fold(1usize, |n, (_, len)| n.saturating_mul(*len));
        if count > MAX_COMBINATIONS {
            let sizes: Vec<String> = lists.iter().map(|(flag, len)| format!("{flag} {len}")).collect();
            bail!(
                "the lists make {count} combinations ({}), more than the {MAX_COMBINATIONS} a sweep runs (each is a \
                 build and an evaluation): sweep fewer values",
                sizes.join(" x ")
            );
        }
        let mut combos = BTreeMap::new();
        let mut notes = Vec::new();
        for &s in &self.sectors {
            for &k in &self.subsectors {
                if let Err(e) = SectorConfig::new(s, k) {
                    notes.push(format!("skipped sectors {s} x subsectors {k}: {e}"));
                    continue;
                }
                for &seeds in &self.seeds {
                    for &rng_seed in &self.rng_seeds {
                        let mut params = self.base.clone();
                        params.sectors = s;
                        params.subsectors = k;
                        params.crystal.seeds = seeds;
                        params.crystal.rng_seed = rng_seed;
                        if let Err(e) = params.crystal.validate() {
                            let seeds = seeds.map_or("default".to_string(), |n| n.to_string());
                            notes.push(format!(
                                "skipped sectors {s} x subsectors {k}, seeds {seeds}, rng seed {rng_seed}: {e}"
                            ));
                            continue;
                        }
                        // A quadtree uses neither seed: its key says so rather than record values it ignored.
                        let crystal = matches!(params.grouping, pipeline::Grouping::Crystal);
                        let key = SweepKey {
                            sectors: s,
                            subsectors: k,
                            seeds: if crystal {
                                params.crystal.first_seeds(triangles)
                            } else {
                                0
                            },
                            rng_seed: if crystal { rng_seed } else { 0 },
                            viewpoints: self.viewpoints,
                        };
                        combos.entry(key).or_insert(Combo { key, params });
                    }
                }
            }
        }
        Ok((combos.into_values().collect(), notes))
    }
}

/// Parses a list of non-negative integers: comma-separated items, each a number or an inclusive range `a..b`
/// (`"1..5"`, `"4,8,16"`, `"1..3,8"`). A value given twice (`"4,4"`, `"1..5,3"`) is refused: it would be swept
/// once. `what` names the option in errors.
pub fn parse_list(text: &str, what: &str) -> Result<Vec<u64>> {
    let mut out = Vec::new();
    for item in text.split(',').map(str::trim) {
        if item.is_empty() {
            bail!("{what}: empty item in {text:?}");
        }
        let num = |s: &str| -> Result<u64> {
            s.trim()
                .parse::<u64>()
                .with_context(|| format!("{what}: {s:?} is not a non-negative integer"))
        };
        match item.split_once("..") {
            Some((a, b)) => {
                let (a, b) = (num(a)?, num(b.strip_prefix('=').unwrap_or(b))?);
                if a > b {
                    bail!("{what}: the range {item:?} is empty");
                }
                if b - a >= 100_000 {
                    bail!("{what}: the range {item:?} is too long");
                }
                out.extend(a..=b);
            }
            None => out.push(num(item)?),
        }
    }
    let mut sorted = out.clone();
    sorted.sort_unstable();
    if let Some(twice) = sorted.windows(2).find(|w| w[0] == w[1]) {
        bail!("{what}: {} is given twice in {text:?}", twice[0]);
    }
    Ok(out)
}

/// The sweep CSV's lines for one combination: one per evaluation row (method × class).
pub fn csv_lines(key: &SweepKey, report: &BuildReport, e: &Evaluation) -> Vec<String> {
    let f = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x}"));
    e.rows
        .iter()
        .map(|r| {
            let m = &r.summary;
            let mut line = String::new();
            let _ = write!(
                line,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                key.sectors,
                key.subsectors,
                key.seeds,
                key.rng_seed,
                key.viewpoints,
                report.vertices,
                report.triangles,
                report.horizon_seconds,
                report.regions_seconds,
                report.grouping_seconds,
                report.visibility_bytes,
                report.groups,
                report.orphans,
                report.orphan_passes_run,
                report.nodes,
                report.levels,
                report.top_level,
                r.method,
                r.class,
                m.viewpoints,
                f(m.false_culls.map(|x| x.mean)),
                f(m.false_culls.map(|x| x.max)),
                m.viewpoints_with_false_culls,
                f(m.false_cull_area.map(|x| x.mean)),
                f(m.occlusion_captured.map(|x| x.mean)),
                f(m.occlusion_captured.map(|x| x.p50)),
                f(m.overdraw.map(|x| x.mean)),
                f(m.triangles_drawn.map(|x| x.mean)),
                r.cull_ns,
                r.visible_fraction,
                r.drawn_fraction,
                f(r.leaf_limit)
            );
            line
        })
        .collect()
}

/// The (method, class) of each line a combination of a sweep writes, in the file's order: the methods of
/// [`standard_method_names`] for the sweep's grouping, each with the evaluation's classes then `all`.
pub fn expected_rows(base: &BuildParams, eval: &EvalOptions) -> Vec<(String, String)> {
    let classes: Vec<String> = eval
        .classes
        .iter()
        .map(|c| c.name().to_string())
        .chain(["all".to_string()])
        .collect();
    standard_method_names(
        matches!(base.grouping, pipeline::Grouping::Quadtree(_)),
        eval.per_triangle,
    )
    .into_iter()
    .flat_map(|m| classes.iter().map(move |c| (m.to_string(), c.clone())))
    .collect()
}

/// The index of the `method` column in [`HEADER`] (`class` follows it).
const METHOD_COLUMN: usize = 17;

/// What a column of a sweep file holds, for checking a file read back.
#[derive(Clone, Copy, PartialEq)]
enum Column {
    /// A whole number.
    Count,
    /// A number, 0 or more (times, fractions, bytes: none is negative).
    Number,
    /// A number, 0 or more, or empty where the evaluation has none (e.g. no hidden triangle).
    MaybeNumber,
    /// A method or class name.
    Name,
}

/// The kind of each column of [`HEADER`], by name.
fn column_kind(name: &str) -> Column {
    match name {
        "horizon_seconds" | "regions_seconds" | "grouping_seconds" | "cull_ns" | "visible_fraction"
        | "drawn_fraction" => Column::Number,
        "false_culls_mean"
        | "false_culls_max"
        | "false_cull_area_mean"
        | "occlusion_captured_mean"
        | "occlusion_captured_p50"
        | "overdraw_mean"
        | "triangles_drawn_mean"
        | "leaf_limit" => Column::MaybeNumber,
        "method" | "class" | "setup" => Column::Name,
        _ => Column::Count,
    }
}

/// The lines of a sweep file, grouped by combination.
#[derive(Clone, Debug, Default)]
pub struct SweepTable {
    /// Each combination's lines, without their last column (`setup`).
    rows: BTreeMap<SweepKey, Vec<String>>,
    /// The line number of every (combination, method, class).
    line_of: BTreeMap<(SweepKey, String, String), usize>,
    /// The setup of every line ([`setup_digest`]); `None` for an empty table.
    setup: Option<String>,
    /// The number of a last line that was cut short (no newline: a write that was interrupted), left out of the
    /// table.
    truncated: Option<usize>,
}

impl PartialEq for SweepTable {
    /// The same lines, setup and cut line (where the lines were read from, if they were, does not count).
    fn eq(&self, other: &Self) -> bool {
        (&self.rows, &self.setup, self.truncated) == (&other.rows, &other.setup, other.truncated)
    }
}

impl SweepTable {
    /// Reads a sweep file's text; the header must be [`HEADER`], every field must hold what its column does, and a
    /// combination may not have two lines for one method and class. Errors name the offending line and column. A
    /// last line cut short (no final newline) is left out and reported by
    /// [`SweepTable::truncated_line`]: its combination is then incomplete ([`SweepTable::incomplete`]).
    pub fn parse(text: &str) -> Result<SweepTable> {
        let mut lines = text.lines().enumerate().peekable();
        let mut table = SweepTable::default();
        match lines.next() {
            None => return Ok(table),
            Some((_, h)) if h.trim_end() == HEADER => {}
            Some((_, h)) => bail!(
                "line 1: the header {:?} is not that of this version's sweep files; move the file away or name \
                 another one",
                h.chars().take(60).collect::<String>()
            ),
        }
        let names: Vec<&str> = HEADER.split(',').collect();
        let columns = names.len();
        // Where each (combination, method, class) was first seen, to name both lines of a repeat.
        let mut seen: BTreeMap<(SweepKey, String, String), usize> = BTreeMap::new();
        while let Some((i, line)) = lines.next() {
            let line = line.trim_end();
            if line.is_empty() {
                continue;
            }
            // Every line is written with its newline (and the file replaced at once): a last line without one was
            // cut short, even where what is left of it would parse (a cut inside a number).
            if lines.peek().is_none() && !text.ends_with('\n') {
                table.truncated = Some(i + 1);
                break;
            }
            let fields: Vec<&str> = line.split(',').collect();
            if fields.len() != columns {
                bail!("line {}: {} fields, expected {columns}", i + 1, fields.len());
            }
            for (j, (field, name)) in fields.iter().zip(&names).enumerate() {
                let ok = match column_kind(name) {
                    Column::Count => field.parse::<u64>().is_ok(),
                    Column::Number => field.parse::<f64>().is_ok_and(|x| x.is_finite() && x >= 0.0),
                    Column::MaybeNumber => {
                        field.is_empty() || field.parse::<f64>().is_ok_and(|x| x.is_finite() && x >= 0.0)
                    }
                    Column::Name => !field.is_empty(),
                };
                if !ok {
                    let what = match column_kind(name) {
                        Column::Count => "a whole number",
                        Column::Number => "a finite number, 0 or more",
                        Column::MaybeNumber => "a finite number, 0 or more, or empty",
                        Column::Name => "a name",
                    };
                    bail!("line {}, column {} ({name}): {field:?} is not {what}", i + 1, j + 1);
                }
            }
            let setup = fields[columns - 1];
            match &table.setup {
                Some(s) if s != setup => bail!("line {}: setup {setup:?}, where the lines before have {s:?}", i + 1),
                Some(_) => {}
                None => table.setup = Some(setup.to_string()),
            }
            let field = |j: usize| -> Result<u64> {
                fields[j]
                    .parse::<u64>()
                    .with_context(|| format!("line {}: field {} ({:?}) is not an integer", i + 1, j + 1, fields[j]))
            };
            let small = |j: usize| -> Result<u32> {
                u32::try_from(field(j)?).with_context(|| format!("line {}: field {} is too large", i + 1, j + 1))
            };
            let key = SweepKey {
                sectors: small(0)?,
                subsectors: small(1)?,
                seeds: field(2)? as usize,
                rng_seed: field(3)?,
                viewpoints: field(4)? as usize,
            };
            let row = (
                key,
                fields[METHOD_COLUMN].to_string(),
                fields[METHOD_COLUMN + 1].to_string(),
            );
            if let Some(first) = seen.insert(row.clone(), i + 1) {
                bail!(
                    "line {}: a second line for method {} and class {} of sectors {} x subsectors {} (the first is \
                     line {first}); remove one",
                    i + 1,
                    row.1,
                    row.2,
                    key.sectors,
                    key.subsectors
                );
            }
            let data = &line[..line.len() - setup.len() - 1];
            table.rows.entry(key).or_default().push(data.to_string());
        }
        table.line_of = seen;
        Ok(table)
    }

    /// The lines whose method or class is none of `expected` (hand-edited, or of another version's evaluation):
    /// `(line number, method, class)`, in line order. Their combinations are incomplete.
    pub fn unexpected(&self, expected: &[(String, String)]) -> Vec<(usize, String, String)> {
        let mut found: Vec<(usize, String, String)> = self
            .line_of
            .iter()
            .filter(|((_, m, c), _)| !expected.iter().any(|(em, ec)| em == m && ec == c))
            .map(|((_, m, c), &line)| (line, m.clone(), c.clone()))
            .collect();
        found.sort();
        found
    }

    /// The line number of a last line that was cut short and left out by [`SweepTable::parse`], if any.
    pub fn truncated_line(&self) -> Option<usize> {
        self.truncated
    }

    /// The combinations whose lines are not exactly `expected`, the (method, class) of each line in order (as
    /// [`expected_rows`] gives them): a line lost or cut short, or lines of another evaluation.
    pub fn incomplete(&self, expected: &[(String, String)]) -> Vec<SweepKey> {
        self.rows
            .iter()
            .filter(|(_, lines)| {
                lines.len() != expected.len()
                    || lines.iter().zip(expected).any(|(line, (method, class))| {
                        let mut f = line.split(',').skip(METHOD_COLUMN);
                        f.next() != Some(method.as_str()) || f.next() != Some(class.as_str())
                    })
            })
            .map(|(k, _)| *k)
            .collect()
    }

    /// Drops the lines of the combination `key` (to run it again).
    pub fn remove(&mut self, key: &SweepKey) {
        self.rows.remove(key);
        self.line_of.retain(|(k, _, _), _| k != key);
    }

    /// Takes `setup` as this table's: refused when its lines were written for another one.
    pub fn adopt(&mut self, setup: &str) -> Result<()> {
        match &self.setup {
            Some(s) if s != setup => bail!(
                "its lines are of another sweep setup ({s}; this run's is {setup}): the mesh, the build options, \
                 --classes, --view-seed, --fov or --no-per-triangle differ. Name another file, or run with the \
                 same setup to resume"
            ),
            _ => {
                self.setup = Some(setup.to_string());
                Ok(())
            }
        }
    }

    /// Whether the combination `key` is in the table.
    pub fn contains(&self, key: &SweepKey) -> bool {
        self.rows.contains_key(key)
    }

    /// Sets the lines of a combination.
    pub fn insert(&mut self, key: SweepKey, lines: Vec<String>) {
        self.rows.insert(key, lines);
    }

    /// Number of combinations.
    pub fn combos(&self) -> usize {
        self.rows.len()
    }

    /// Number of data lines.
    pub fn lines(&self) -> usize {
        self.rows.values().map(Vec::len).sum()
    }

    /// The file's text: the header, then every combination's lines in key order.
    pub fn to_csv(&self) -> String {
        let mut s = String::from(HEADER);
        s.push('\n');
        let setup = self.setup.as_deref().unwrap_or("");
        for line in self.rows.values().flatten() {
            s += line;
            s.push(',');
            s += setup;
            s.push('\n');
        }
        s
    }
}

/// The result of one combination.
pub struct ComboResult {
    /// Build figures.
    pub report: BuildReport,
    /// The evaluation against the sweep's ground truth.
    pub evaluation: Evaluation,
    /// The CSV lines.
    pub lines: Vec<String>,
}

/// Builds `combo` on `tin` and scores it (hierarchy, per-triangle when `per_triangle`, frustum only, none) against
/// `truth`, which must have been computed on `tin`.
pub fn run_combo(
    tin: &Tin,
    truth: &GroundTruthSet,
    combo: &Combo,
    per_triangle: bool,
    progress: Option<BuildProgress>,
) -> Result<ComboResult> {
    let b = build(tin, &combo.params, progress)?;
    let per_triangle = per_triangle.then(|| per_triangle_hierarchy(tin, &triangle_regions(tin, &b.vertex_regions)));
    let methods = standard_methods(&b.hierarchy, per_triangle.as_ref(), Some(&b.order), truth.options.safe);
    let ranges = b.hierarchy.leaf_ranges();
    let leaves = Leaves {
        ranges: &ranges,
        order: Some(&b.order),
    };
    let evaluation = score(tin, truth, &methods, Some(leaves))?;
    let lines = csv_lines(&combo.key, &b.report, &evaluation);
    Ok(ComboResult {
        report: b.report,
        evaluation,
        lines,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::evaluate::{EvalOptions, evaluate, hierarchy_tin};
    use truth::ViewpointClass;

    #[test]
    fn lists_and_ranges_parse() {
        assert_eq!(parse_list("4,8,16", "x").unwrap(), vec![4, 8, 16]);
        assert_eq!(parse_list("1..5", "x").unwrap(), vec![1, 2, 3, 4, 5]);
        assert_eq!(parse_list("1..=3, 8", "x").unwrap(), vec![1, 2, 3, 8]);
        for bad in ["", "1,,2", "a", "5..1", "-1", "1..x", "4,4", "1..5,3"] {
            let e = parse_list(bad, "--sectors").unwrap_err().to_string();
            assert!(e.contains("--sectors"), "{bad}: {e}");
        }
    }

    #[test]
    fn combos_skip_invalid_and_come_in_key_order() {
        let spec = SweepSpec {
            sectors: vec![64, 2, 8],
            subsectors: vec![32, 1],
            seeds: vec![None, Some(0), Some(7)],
            rng_seeds: vec![2, 1],
            base: BuildParams::default(),
            viewpoints: 3,
        };
        let (combos, notes) = spec.combos(4000).expect("combinations");
        let keys: Vec<SweepKey> = combos.iter().map(|c| c.key).collect();
        let mut sorted = keys.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(keys, sorted);
        // 64 x 32 = 2048 subsectors and 2 sectors are rejected; seeds 0 is invalid or maps to 1 (never run twice).
        assert!(keys.iter().all(|k| k.sectors * k.subsectors <= 1024 && k.sectors >= 4));
        assert!(notes.iter().any(|n| n.contains("sectors 64 x subsectors 32")));
        assert!(notes.iter().any(|n| n.contains("sectors 2 x")));
        assert!(
            keys.iter()
                .any(|k| k.seeds == 20 && k.sectors == 8 && k.subsectors == 32)
        );
        for c in &combos {
            assert_eq!(c.params.sectors, c.key.sectors);
            assert_eq!(c.params.crystal.first_seeds(4000), c.key.seeds);
            assert_eq!(c.params.crystal.rng_seed, c.key.rng_seed);
        }
    }

    /// A quadtree's combinations record no crystal seeds: it uses none.
    #[test]
    fn a_quadtree_key_has_no_seeds() {
        let spec = SweepSpec {
            sectors: vec![8],
            subsectors: vec![2],
            seeds: vec![None],
            rng_seeds: vec![1],
            base: BuildParams {
                grouping: pipeline::Grouping::Quadtree(Default::default()),
                ..BuildParams::default()
            },
            viewpoints: 3,
        };
        let (combos, notes) = spec.combos(4000).expect("combinations");
        assert!(notes.is_empty(), "{notes:?}");
        assert_eq!(combos.len(), 1);
        assert_eq!((combos[0].key.seeds, combos[0].key.rng_seed), (0, 0));
        let crystal = SweepSpec {
            base: BuildParams::default(),
            ..spec
        };
        assert_eq!(crystal.combos(4000).expect("combinations").0[0].key.seeds, 20);
    }

    /// Lists whose product is more than a sweep runs are refused, naming each list's length, before any combination
    /// or note is made (found by an audit: `--sectors 4..99999 --subsectors 1..99999` filled 3.6 GB with notes).
    #[test]
    fn too_many_combinations_are_refused_before_they_are_listed() {
        let spec = SweepSpec {
            sectors: (1..=99_999).collect(),
            subsectors: (1..=99_999).collect(),
            seeds: vec![None],
            rng_seeds: vec![1, 2],
            base: BuildParams::default(),
            viewpoints: 3,
        };
        let message = format!("{:#}", spec.combos(4000).expect_err("too many"));
        assert!(
            message.contains("19999600002 combinations") && message.contains("--sectors 99999 x --subsectors 99999"),
            "{message}"
        );
        let at_most = SweepSpec {
            sectors: (1..=100).collect(),
            subsectors: (1..=50).collect(),
            ..spec
        };
        assert_eq!(at_most.sectors.len() * at_most.subsectors.len() * 2, MAX_COMBINATIONS);
        at_most.combos(4000).expect("as many as a sweep runs");
    }

    /// The combination of [`line`].
    const KEY: SweepKey = SweepKey {
        sectors: 8,
        subsectors: 2,
        seeds: 10,
        rng_seed: 1,
        viewpoints: 2,
    };

    /// A line of the combination [`KEY`] for `method` and `class`, without its setup column.
    fn line(method: &str, class: &str) -> String {
        format!(
            "8,2,10,1,2,100,180,0.1,0.2,0.3,720,4,1,2,9,3,2,{method},{class},2,0,0,0,0,0.5,0.5,1.2,90,1500,0.1,0.5,"
        )
    }

    #[test]
    fn table_round_trips_and_rejects_foreign_files() {
        let key = KEY;
        // A combination's lines hold every column but the last, the setup, which the table writes.
        let one = line("safe", "all");
        assert_eq!(one.split(',').count(), HEADER.split(',').count() - 1);
        let mut t = SweepTable::default();
        t.insert(key, vec![one.clone()]);
        t.adopt("0badcafe").unwrap();
        let text = t.to_csv();
        assert!(
            text.ends_with(",all,2,0,0,0,0,0.5,0.5,1.2,90,1500,0.1,0.5,,0badcafe\n"),
            "{text}"
        );
        let mut back = SweepTable::parse(&text).unwrap();
        assert_eq!(back, t);
        assert!(back.contains(&key));
        assert_eq!(back.to_csv(), text);
        // Another setup is refused, and so is a file whose lines mix two.
        assert!(
            back.adopt("12345678")
                .unwrap_err()
                .to_string()
                .contains("another sweep setup")
        );
        back.adopt("0badcafe").unwrap();
        let mixed = format!("{text}{}\n", line("none", "all") + ",12345678");
        assert!(
            SweepTable::parse(&mixed)
                .unwrap_err()
                .to_string()
                .contains("line 3: setup")
        );
        assert!(SweepTable::parse("a,b\n").unwrap_err().to_string().contains("line 1"));
        let short = format!("{HEADER}\n1,2,3\n");
        assert!(SweepTable::parse(&short).unwrap_err().to_string().contains("line 2"));
        let bad = format!("{HEADER}\n{}x\n", one.replacen('8', "eight", 1));
        assert!(SweepTable::parse(&bad).unwrap_err().to_string().contains("line 2"));
    }

    /// Damage a resume must not take for a finished combination: a field that is not a number is refused by line
    /// and column, a repeated line by both its lines, a lost line makes the combination incomplete, and a last line
    /// cut short (no newline) is left out as an interrupted write.
    #[test]
    fn damaged_files_are_refused_or_their_combinations_incomplete() {
        let key = KEY;
        let expected: Vec<(String, String)> = [("safe", "low"), ("safe", "all"), ("none", "low"), ("none", "all")]
            .iter()
            .map(|(m, c)| (m.to_string(), c.to_string()))
            .collect();
        let lines: Vec<String> = expected.iter().map(|(m, c)| format!("{},s", line(m, c))).collect();
        let text = format!("{HEADER}\n{}\n", lines.join("\n"));
        let whole = SweepTable::parse(&text).unwrap();
        assert_eq!(whole.incomplete(&expected), vec![]);
        assert_eq!(whole.truncated_line(), None);

        // A value that is not a number, in a count column and in a number column.
        for (from, to, column) in [
            (",720,", ",abc,", "column 11 (visibility_bytes)"),
            (",0.1,0.2,", ",abc,0.2,", "column 8 (horizon_seconds)"),
            (",1500,", ",inf,", "column 29 (cull_ns)"),
            // A negative time or mean: no column holds one.
            (",1500,", ",-1500,", "column 29 (cull_ns)"),
            (",0,0,0,0,0.5,", ",-1,0,0,0,0.5,", "column 21 (false_culls_mean)"),
        ] {
            let bad = text.replacen(from, to, 1);
            let e = SweepTable::parse(&bad).unwrap_err().to_string();
            assert!(e.contains("line 2") && e.contains(column), "{to}: {e}");
        }
        // An empty method name.
        let e = SweepTable::parse(&text.replacen(",safe,", ",,", 1))
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 2, column 18 (method)"), "{e}");
        // A method or class this sweep does not write: named by its line, its combination incomplete.
        let edited = SweepTable::parse(&text.replacen(",none,low,", ",bogus,low,", 1)).unwrap();
        assert_eq!(
            edited.unexpected(&expected),
            vec![(4, "bogus".to_string(), "low".to_string())]
        );
        assert_eq!(edited.incomplete(&expected), vec![key]);
        assert_eq!(whole.unexpected(&expected), vec![]);
        // A repeated line.
        let repeated = format!("{text}{}\n", lines[1]);
        let e = SweepTable::parse(&repeated).unwrap_err().to_string();
        assert!(
            e.contains("line 6") && e.contains("line 3") && e.contains("method safe and class all"),
            "{e}"
        );
        // A lost line (any of them), and lines in another order.
        for lost in 0..lines.len() {
            let mut kept = lines.clone();
            kept.remove(lost);
            let t = SweepTable::parse(&format!("{HEADER}\n{}\n", kept.join("\n"))).unwrap();
            assert_eq!(t.incomplete(&expected), vec![key], "line {lost} lost");
        }
        let mut swapped = lines.clone();
        swapped.swap(0, 1);
        let t = SweepTable::parse(&format!("{HEADER}\n{}\n", swapped.join("\n"))).unwrap();
        assert_eq!(t.incomplete(&expected), vec![key]);
        // A last line cut short at any point: left out, the combination incomplete; with its newline it is refused.
        let last = &lines[3];
        for cut in [1, 10, last.len() / 2, last.len() - 3] {
            let cut_text = format!("{HEADER}\n{}\n{}", lines[..3].join("\n"), &last[..cut]);
            let t = SweepTable::parse(&cut_text).unwrap();
            assert_eq!(t.truncated_line(), Some(5), "cut at {cut}");
            assert_eq!(t.incomplete(&expected), vec![key], "cut at {cut}");
            assert!(SweepTable::parse(&format!("{cut_text}\n")).is_err(), "cut at {cut}");
        }
    }

    /// Scoring a build against ground truth computed once on the original triangle order gives the same figures
    /// as evaluating the exported hierarchy on its own mesh (viewpoints drawn over the same footprint).
    #[test]
    fn shared_ground_truth_matches_a_direct_evaluation() {
        let tin = tin::synth_tin(&tin::SynthOptions::new(600, 3)).unwrap();
        let params = BuildParams {
            sectors: 8,
            subsectors: 2,
            ..BuildParams::default()
        };
        let opts = EvalOptions {
            viewpoints: 3,
            classes: vec![ViewpointClass::Low, ViewpointClass::Ridge],
            ..EvalOptions::default()
        };
        let truth = GroundTruthSet::compute(&tin, &opts, &|_, _| {}).unwrap();
        let combo = Combo {
            key: SweepKey {
                sectors: 8,
                subsectors: 2,
                seeds: params.crystal.first_seeds(tin.num_triangles()),
                rng_seed: 1,
                viewpoints: 3,
            },
            params: params.clone(),
        };
        let swept = run_combo(&tin, &truth, &combo, true, None).unwrap();
        let b = build(&tin, &params, None).unwrap();
        let htin = hierarchy_tin(&b.hierarchy).unwrap();
        // The direct evaluation draws its viewpoints over the reordered mesh; score the same eyes both ways.
        let direct_truth = GroundTruthSet {
            views: truth
                .views
                .iter()
                .map(|v| crate::evaluate::TruthView {
                    visible: truth::GroundTruth::new(&htin).visible_triangles(v.eye),
                    ..v.clone()
                })
                .collect(),
            ..truth.clone()
        };
        let pt = crate::evaluate::per_triangle_of(&b.hierarchy, &htin).unwrap();
        let direct = score(
            &htin,
            &direct_truth,
            &standard_methods(&b.hierarchy, Some(&pt), None, Default::default()),
            None,
        )
        .unwrap();
        assert_eq!(swept.evaluation.rows.len(), direct.rows.len());
        // The lines of a combination are those expected_rows names, in its order.
        let rows: Vec<(String, String)> = swept
            .evaluation
            .rows
            .iter()
            .map(|r| (r.method.clone(), r.class.clone()))
            .collect();
        assert_eq!(rows, expected_rows(&params, &opts));
        let mut table = SweepTable::default();
        table.insert(combo.key, swept.lines.clone());
        table.adopt("0badcafe").unwrap();
        let back = SweepTable::parse(&table.to_csv()).unwrap();
        assert_eq!(back.incomplete(&expected_rows(&params, &opts)), vec![]);
        for (a, d) in swept.evaluation.rows.iter().zip(&direct.rows) {
            assert_eq!((&a.method, &a.class), (&d.method, &d.class));
            // Counts agree exactly; areas are summed in another triangle order, so only to rounding.
            let (x, y) = (&a.summary, &d.summary);
            let what = format!("{} {}", a.method, a.class);
            assert_eq!(x.viewpoints, y.viewpoints, "{what}");
            assert_eq!(x.viewpoints_with_false_culls, y.viewpoints_with_false_culls, "{what}");
            assert_eq!(x.false_culls, y.false_culls, "{what}");
            assert_eq!(x.occlusion_captured, y.occlusion_captured, "{what}");
            assert_eq!(x.overdraw, y.overdraw, "{what}");
            assert_eq!(x.triangles_drawn, y.triangles_drawn, "{what}");
            match (x.false_cull_area, y.false_cull_area) {
                (Some(p), Some(q)) => {
                    for (u, v) in [(p.mean, q.mean), (p.max, q.max), (p.p50, q.p50)] {
                        assert!((u - v).abs() <= 1e-9 * u.abs().max(1.0), "{what}: {u} vs {v}");
                    }
                }
                (p, q) => assert_eq!(p, q, "{what}"),
            }
        }
        assert_eq!(swept.lines.len(), swept.evaluation.rows.len());
        assert!(
            swept
                .lines
                .iter()
                .all(|l| l.split(',').count() == HEADER.split(',').count() - 1)
        );
        // evaluate() still runs end to end on the exported hierarchy.
        let e = evaluate(&b.hierarchy, &htin, &opts, &|_, _| {}).unwrap();
        // safe, lloyd-egbert, safe_regions, thesis, per_triangle, frustum_only, none.
        assert_eq!(e.rows.len(), 7 * 3);
    }
}
