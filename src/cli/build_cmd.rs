//! `tincull build`: horizons, regions, crystal grouping and the merge hierarchy (or Stewart's quadtree with
//! `--grouping quadtree`, and its cells alone, without horizons or regions, with `--no-regions`), written as a `.tch`
//! file.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use serde::Deserialize;
use serde_json::json;

use super::mesh_input::MeshArgs;
use super::{Output, OutputArgs};
use pipeline::export::to_json;

use super::files::Outputs;
use pipeline::{BuildError, BuildParams, BuildReport, Grouping, QuadtreeParams, build, build_without_regions};

/// Parameters that may also come from a TOML file (`--config`); the command line wins.
#[derive(Debug, Default, Clone, Args, Deserialize)]
pub struct ParamArgs {
    /// Number of sectors, at least 4 [default: 16].
    #[arg(long)]
    pub sectors: Option<u32>,
    /// Subsectors per sector, at least 1, with sectors × subsectors at most 1024 [default: 4].
    #[arg(long)]
    pub subsectors: Option<u32>,
    /// Crystal seeds of the first pass, at least 1 [default: one per 200 triangles].
    #[arg(long)]
    pub seeds: Option<usize>,
    /// Seed of the random generator [default: 1].
    #[arg(long)]
    pub rng_seed: Option<u64>,
    /// The parameters that `sweep` takes as they are (it sweeps the four above).
    #[command(flatten)]
    #[serde(flatten)]
    pub fixed: FixedParamArgs,
}

/// The build parameters that `tincull sweep` does not sweep: one definition for every command that builds.
#[derive(Debug, Default, Clone, Args, Deserialize)]
pub struct FixedParamArgs {
    /// Orphan passes after the first [default: 10].
    #[arg(long)]
    pub orphan_passes: Option<u32>,
    /// Groups smaller than this many triangles (at least 1) are merged or freed to the always-visible set [default:
    /// 30].
    #[arg(long)]
    pub min_group: Option<usize>,
    /// A merge whose bounding circle covers more than this fraction of the terrain's area (positive) is not made
    /// [default: 0.25].
    #[arg(long)]
    pub max_expanse: Option<f64>,
    /// Radius (m, positive) of the horizon undersampling fix [default: off].
    #[arg(long, value_name = "RADIUS")]
    pub undersampling: Option<f64>,
    /// How triangles are grouped into nodes: `crystal` (the thesis) or `quadtree` (Stewart's 1997 baseline: square
    /// cells over the footprint) [default: crystal].
    #[arg(long, value_name = "KIND", value_parser = ["crystal", "quadtree"])]
    pub grouping: Option<String>,
    /// Quadtree: finest depth (root = 0), at most 16 [default: cells of about 128 triangles].
    #[arg(long, value_name = "D", conflicts_with = "cell_size")]
    pub depth: Option<u32>,
    /// Quadtree: finest cell side in metres, instead of --depth (`--cell` is an older name; `cell_size` or `cell` in
    /// a `--config` file).
    #[arg(long, value_name = "M", alias = "cell")]
    #[serde(alias = "cell")]
    pub cell_size: Option<f64>,
    /// Quadtree: byte budget of the visibility data; the finest levels are dropped until it fits (Stewart's memory
    /// levels).
    #[arg(long, value_name = "N")]
    pub max_bytes: Option<u64>,
}

/// What a `--config` key takes, so that a wrong type is named in words (serde names the Rust type).
#[derive(Clone, Copy)]
enum ConfigValue {
    /// A whole number from 0 to this.
    Whole(u64),
    /// Any number (an integer is read as a float).
    Number,
    /// A string.
    Text,
}

/// The keys of a `--config` file: the long options of [`ParamArgs`] with underscores, and `cell` (the older name of
/// `cell_size`), with what each takes. Checked by hand, because serde cannot refuse unknown keys of a struct with a
/// flattened part.
const CONFIG_KEYS: [(&str, ConfigValue); 13] = {
    use ConfigValue::{Number, Text, Whole};
    const U32: ConfigValue = Whole(u32::MAX as u64);
    const U64: ConfigValue = Whole(i64::MAX as u64); // TOML's integers are i64
    [
        ("sectors", U32),
        ("subsectors", U32),
        ("seeds", U64),
        ("rng_seed", U64),
        ("orphan_passes", U32),
        ("min_group", U64),
        ("max_expanse", Number),
        ("undersampling", Number),
        ("grouping", Text),
        ("depth", U32),
        ("cell_size", Number),
        ("cell", Number),
        ("max_bytes", U64),
    ]
};

/// Whether `value` is of the kind `takes`, or what it takes in words.
fn check_config_value(value: &toml::Value, takes: ConfigValue) -> std::result::Result<(), String> {
    use toml::Value;
    match (takes, value) {
        (ConfigValue::Whole(max), Value::Integer(i)) if u64::try_from(*i).is_ok_and(|i| i <= max) => Ok(()),
        (ConfigValue::Whole(max), _) if max < i64::MAX as u64 => Err(format!("a whole number from 0 to {max}")),
        (ConfigValue::Whole(_), _) => Err("a whole number (0 or more)".into()),
        (ConfigValue::Number, Value::Integer(_) | Value::Float(_)) => Ok(()),
        (ConfigValue::Number, _) => Err("a number".into()),
        (ConfigValue::Text, Value::String(_)) => Ok(()),
        (ConfigValue::Text, _) => Err("a string".into()),
    }
}

impl ParamArgs {
    /// The parameters of a `--config` TOML file (keys as the long options of these parameters, with underscores;
    /// any other key is refused).
    pub fn read(path: &Path) -> Result<ParamArgs> {
        let text = infile::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
        let invalid = || format!("{}: invalid parameters", path.display());
        let table: toml::Table = toml::from_str(&text).with_context(invalid)?;
        for (key, value) in &table {
            let Some(&(_, takes)) = CONFIG_KEYS.iter().find(|(k, _)| k == key) else {
                let keys: Vec<&str> = CONFIG_KEYS.iter().map(|(k, _)| *k).collect();
                anyhow::bail!("{}: unknown key `{key}`; the keys are {}", invalid(), keys.join(", "));
            };
            if let Err(wanted) = check_config_value(value, takes) {
                let mut shown = value.to_string();
                if shown.chars().count() > 60 {
                    shown = format!("of {} characters", shown.chars().count());
                }
                anyhow::bail!(
                    "{}: `{key}` takes {wanted}, not the {} {shown}",
                    invalid(),
                    value.type_str()
                );
            }
        }
        toml::from_str(&text).with_context(invalid)
    }

    /// Command-line values over those of `file` over the defaults.
    pub fn resolve(&self, file: Option<&Path>) -> Result<BuildParams> {
        let from_file = match file {
            Some(path) => ParamArgs::read(path)?,
            None => ParamArgs::default(),
        };
        let d = BuildParams::default();
        let mut p = d.clone();
        p.sectors = self.sectors.or(from_file.sectors).unwrap_or(d.sectors);
        p.subsectors = self.subsectors.or(from_file.subsectors).unwrap_or(d.subsectors);
        p.undersampling = self.fixed.undersampling.or(from_file.fixed.undersampling);
        p.crystal.seeds = self.seeds.or(from_file.seeds);
        p.crystal.orphan_passes = self
            .fixed
            .orphan_passes
            .or(from_file.fixed.orphan_passes)
            .unwrap_or(d.crystal.orphan_passes);
        p.crystal.min_group = self
            .fixed
            .min_group
            .or(from_file.fixed.min_group)
            .unwrap_or(d.crystal.min_group);
        p.crystal.max_expanse = self
            .fixed
            .max_expanse
            .or(from_file.fixed.max_expanse)
            .unwrap_or(d.crystal.max_expanse);
        p.crystal.rng_seed = self.rng_seed.or(from_file.rng_seed).unwrap_or(d.crystal.rng_seed);
        // The depth and the cell size are one choice (the finest level): either on the command line replaces both of
        // the file's.
        let (depth, cell) = if self.fixed.depth.is_some() || self.fixed.cell_size.is_some() {
            (self.fixed.depth, self.fixed.cell_size)
        } else {
            (from_file.fixed.depth, from_file.fixed.cell_size)
        };
        anyhow::ensure!(
            depth.is_none() || cell.is_none(),
            "--depth and --cell-size (`depth` and `cell_size` in --config) both set the finest level of the quadtree: \
             give one"
        );
        let quadtree = QuadtreeParams {
            depth,
            cell,
            max_bytes: self.fixed.max_bytes.or(from_file.fixed.max_bytes),
        };
        match self.fixed.grouping.as_deref().or(from_file.fixed.grouping.as_deref()) {
            None | Some("crystal") => {
                if quadtree != QuadtreeParams::default() {
                    anyhow::bail!(
                        "--depth, --cell-size and --max-bytes (`depth`, `cell_size` and `max_bytes` in --config) need \
                         --grouping quadtree"
                    );
                }
            }
            Some("quadtree") => {
                // The crystal grouping's parameters mean nothing to a quadtree: refused rather than ignored.
                let crystal_only = [
                    ("--seeds", self.seeds.is_some(), from_file.seeds.is_some()),
                    (
                        "--orphan-passes",
                        self.fixed.orphan_passes.is_some(),
                        from_file.fixed.orphan_passes.is_some(),
                    ),
                    (
                        "--min-group",
                        self.fixed.min_group.is_some(),
                        from_file.fixed.min_group.is_some(),
                    ),
                    (
                        "--max-expanse",
                        self.fixed.max_expanse.is_some(),
                        from_file.fixed.max_expanse.is_some(),
                    ),
                    ("--rng-seed", self.rng_seed.is_some(), from_file.rng_seed.is_some()),
                ];
                if let Some(&(flag, on_command_line, _)) = crystal_only.iter().find(|(_, cli, f)| *cli || *f) {
                    // Named as the user gave it: a flag, or a key of the --config file.
                    let given = match file {
                        Some(path) if !on_command_line => {
                            format!(
                                "`{}` (in {})",
                                flag.trim_start_matches('-').replace('-', "_"),
                                path.display()
                            )
                        }
                        _ => flag.to_string(),
                    };
                    anyhow::bail!(
                        "{given} applies to the crystal grouping (its seeds, passes, groups and random generator); a \
                         quadtree's cells are fixed by its depth"
                    );
                }
                p.grouping = Grouping::Quadtree(quadtree);
            }
            Some(other) => {
                let given = match file {
                    Some(path) if self.fixed.grouping.is_none() => format!("`grouping` (in {})", path.display()),
                    _ => "--grouping".to_string(),
                };
                anyhow::bail!("{given}: unknown grouping {other:?}; expected crystal or quadtree")
            }
        }
        // A value out of range is named by its flag, and by the file it may come from (the build checks them again).
        p.validate().map_err(|e| {
            let flag = flag_of(&e);
            let named = match file {
                Some(path) => format!("{flag} (or its key in {})", path.display()),
                None => flag,
            };
            anyhow::Error::new(e).context(named)
        })?;
        Ok(p)
    }
}

/// The flag (or flags) whose value [`BuildParams::validate`] refused with `e`: the keys of a `--config` file are the
/// same names with underscores.
fn flag_of(e: &BuildError) -> String {
    match e {
        BuildError::Horizon(h) => horizon_flag(h).into(),
        BuildError::Crystal(crystal::CrystalError::InvalidParams { field, .. }) => {
            format!("--{}", field.replace('_', "-"))
        }
        BuildError::Quadtree(_) => "--depth or --cell-size".into(),
        _ => "the build parameters".into(),
    }
}

/// The flag (or flags) whose value the horizon stage refused with `e` (`build`, `horizon`).
pub fn horizon_flag(e: &horizon::HorizonError) -> &'static str {
    use horizon::HorizonError as H;
    match e {
        H::TooFewSectors { .. } => "--sectors",
        H::NoSubsectors => "--subsectors",
        H::TooManySubsectors { .. } => "--sectors and --subsectors",
        H::InvalidRadius { .. } => "--undersampling",
        _ => "the horizon parameters",
    }
}

/// Arguments of `tincull build`.
#[derive(Debug, Args)]
pub struct BuildArgs {
    /// The mesh and how to import it.
    #[command(flatten)]
    pub mesh: MeshArgs,
    /// Output hierarchy file (.tch; `-` for standard output, instead of the report, when it is not a terminal).
    #[arg(short, long, value_name = "FILE")]
    pub out: PathBuf,
    /// Build parameters.
    #[command(flatten)]
    pub params: ParamArgs,
    /// Read the build parameters from this TOML file; its keys are those options written with underscores, and only
    /// they: sectors, subsectors, seeds, orphan_passes, min_group, max_expanse, rng_seed, undersampling, grouping,
    /// depth, cell_size (or cell), max_bytes. The command line wins; the import and output options are not read
    /// from it.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// With --grouping quadtree: compute no horizons and no regions, for the run-time cullers only (`safe`, the
    /// default, and `lloyd-egbert`, which read the mesh and the nodes): the same cells in a fraction of the time and
    /// with no visibility data; the region tests (`stewart`, `thesis`) cull nothing in the file.
    #[arg(long)]
    pub no_regions: bool,
    /// Also write the hierarchy's JSON form here (`-` for standard output, instead of the report).
    #[arg(long, value_name = "FILE")]
    pub export_json: Option<PathBuf>,
    /// Also write the mesh as OBJ with one group per leaf and the orphans, with a .mtl beside it.
    #[arg(long, value_name = "FILE")]
    pub export_obj: Option<PathBuf>,
    /// Also write the mesh as glTF 2.0, as `tincull export --export-gltf` does (`.glb`, or `.gltf` with its `.bin`).
    #[arg(long, visible_alias = "gltf", value_name = "FILE")]
    pub export_gltf: Option<PathBuf>,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// A progress bar per pipeline stage.
pub fn stage_progress(out: Output) -> pipeline::BuildProgress {
    let bar = out.progress(1, "horizons");
    // Threads report out of order: within a stage the bar only moves forward.
    let high = std::sync::Mutex::new(0u64);
    Arc::new(move |stage: &str, done: u64, total: u64| {
        let Ok(mut high) = high.lock() else { return };
        if bar.message() != stage {
            bar.set_message(stage.to_string());
            bar.reset();
            *high = 0;
        } else if done < *high {
            return;
        }
        *high = done;
        bar.set_length(total);
        bar.set_position(done);
    })
}

/// Prints the thesis-style table of a build (for a quadtree, its levels).
pub fn print_report(r: &BuildReport, out: Output) {
    if !r.quadtree_levels.is_empty() {
        if r.without_regions {
            out.say(format!("{} vertices, {} triangles; quadtree", r.vertices, r.triangles));
        } else {
            out.say(format!(
                "{} vertices, {} triangles; {} sectors x {} subsectors, quadtree",
                r.vertices, r.triangles, r.sectors, r.subsectors
            ));
        }
        if r.without_regions {
            out.say(format!(
                "  no horizons or regions (--no-regions: for the run-time cullers), quadtree {:.3} s",
                r.grouping_seconds
            ));
        } else {
            out.say(format!(
                "  horizons {:.3} s, regions {:.3} s, quadtree {:.3} s",
                r.horizon_seconds, r.regions_seconds, r.grouping_seconds
            ));
        }
        out.say("  depth  cell (m)  cells  triangles/cell  regions  points  bytes  stored");
        for l in &r.quadtree_levels {
            out.say(format!(
                "  {:>5}  {:>8.1}  {:>5}  {:>14.1}  {:>7}  {:>6}  {:>5}  {}",
                l.depth,
                l.cell_side,
                l.nodes,
                l.mean_triangles,
                l.regions,
                l.region_points,
                l.bytes,
                if l.stored { "yes" } else { "dropped" }
            ));
        }
        out.say(format!(
            "  nodes {}, leaves {}, levels {}; visibility data {} bytes ({:.1} bytes per triangle)",
            r.nodes, r.groups, r.levels, r.visibility_bytes, r.visibility_bytes_per_triangle
        ));
        return;
    }
    out.say(format!(
        "{} vertices, {} triangles; {} sectors x {} subsectors, {} seeds{}",
        r.vertices,
        r.triangles,
        r.sectors,
        r.subsectors,
        r.seeds,
        if r.first_pass_crystals < r.seeds {
            format!(" ({} crystals started)", r.first_pass_crystals)
        } else {
            String::new()
        }
    ));
    out.say(format!(
        "  horizons {:.3} s, regions {:.3} s, grouping {:.3} s",
        r.horizon_seconds, r.regions_seconds, r.grouping_seconds
    ));
    out.say(format!(
        "  orphan passes run {}, orphans {}, groups {}, nodes {}, levels {}, top-level {}",
        r.orphan_passes_run, r.orphans, r.groups, r.nodes, r.levels, r.top_level
    ));
    out.say(format!(
        "  visibility data {} bytes ({:.1} bytes per triangle)",
        r.visibility_bytes, r.visibility_bytes_per_triangle
    ));
}

/// Refuses parameters that a build without regions (`--no-regions`, of `build` and `tiles plan`) cannot take: a
/// grouping other than the quadtree, and horizon parameters other than their defaults, which it would ignore.
pub fn check_no_regions(params: &BuildParams) -> Result<()> {
    anyhow::ensure!(
        matches!(params.grouping, Grouping::Quadtree(_)),
        "--no-regions needs --grouping quadtree: crystal groups grow from the occlusion regions"
    );
    let d = BuildParams::default();
    anyhow::ensure!(
        (params.sectors, params.subsectors, params.undersampling) == (d.sectors, d.subsectors, d.undersampling),
        "--no-regions computes no horizons: --sectors, --subsectors and --undersampling (or their --config keys) \
         mean nothing to it"
    );
    Ok(())
}

/// Runs `tincull build`.
pub fn run(args: &BuildArgs, out: Output) -> Result<()> {
    let mut out = out;
    let params = args.params.resolve(args.config.as_deref())?;
    if args.no_regions {
        check_no_regions(&params)?;
    }
    let mut files = Outputs::new();
    files.input(&args.mesh.mesh)?;
    if let Some(config) = &args.config {
        files.input(config)?;
    }
    files.check_binary_or_stdout(&args.out, "-o", &mut out)?;
    super::files::refuse_other_format(&args.out, "a hierarchy", "tch")?;
    if let Some(path) = &args.export_json {
        files.check_or_stdout(path, "--export-json", &mut out)?;
        super::files::refuse_other_format(path, "a hierarchy's JSON", "json")?;
    }
    if let Some(path) = &args.export_obj {
        files.check_grouped_obj(path, "--export-obj")?;
    }
    if let Some(path) = &args.export_gltf {
        files.check_gltf(path, "--export-gltf")?;
    }
    let started = Instant::now();
    let (tin, _) = args.mesh.load(out)?;
    if let Some(w) = tin::validate::small_terrain_warning(tin.positions()) {
        out.warn(format!("{}: {w}", args.mesh.mesh.display()));
    }
    let load_seconds = started.elapsed().as_secs_f64();
    let result = if args.no_regions {
        build_without_regions(&tin, &params, Some(stage_progress(out)))?
    } else {
        build(&tin, &params, Some(stage_progress(out)))?
    };
    let started = Instant::now();
    files.add_bytes(&args.out, &result.hierarchy.to_bytes()?)?;
    if let Some(path) = &args.export_json {
        files.add_bytes(path, to_json(&result.hierarchy)?.as_bytes())?;
    }
    if let Some(path) = &args.export_obj {
        files.add_grouped_obj(&result.hierarchy, path)?;
    }
    let mut gltf_written = Vec::new();
    if let Some(path) = &args.export_gltf {
        gltf_written = files.add_gltf(&result.hierarchy, path)?;
    }
    files.commit()?;
    let write_seconds = started.elapsed().as_secs_f64();
    print_report(&result.report, out);
    out.say(format!(
        "  mesh read and triangulated in {load_seconds:.3} s, output written in {write_seconds:.3} s; {}",
        super::output::count(rayon::current_num_threads(), "thread")
    ));
    let peak = peak_memory_bytes();
    if let Some(bytes) = peak {
        out.say(format!(
            "  peak memory {:.1} MB (the whole process so far)",
            bytes as f64 / 1e6
        ));
    }
    out.say(format!("wrote {}", args.out.display()));
    if let Some(path) = &args.export_json {
        out.say(format!("wrote {}", path.display()));
    }
    if let Some(path) = &args.export_obj {
        out.say(format!("wrote {} and its .mtl", path.display()));
    }
    if !gltf_written.is_empty() {
        let names: Vec<String> = gltf_written.iter().map(|p| p.display().to_string()).collect();
        out.say(format!("wrote {}", names.join(" and ")));
    }
    let mut j = serde_json::to_value(&result.report)?;
    j["output"] = json!(args.out);
    j["params"] = params_json(&params)?;
    j["peak_memory_bytes"] = json!(peak);
    j["load_seconds"] = json!(load_seconds);
    j["write_seconds"] = json!(write_seconds);
    j["threads"] = json!(rayon::current_num_threads());
    out.json(&j)
}

/// The build parameters as `build --json` reports them: `grouping` is always its name, and only that grouping's
/// parameters follow (`crystal`, or `quadtree` with its options' names: `depth`, `cell_size`, `max_bytes`).
fn params_json(params: &BuildParams) -> Result<serde_json::Value> {
    let mut j = json!({
        "sectors": params.sectors,
        "subsectors": params.subsectors,
        "undersampling": params.undersampling,
        "grouping": params.grouping.name(),
    });
    match &params.grouping {
        Grouping::Crystal => j["crystal"] = serde_json::to_value(&params.crystal)?,
        Grouping::Quadtree(q) => {
            j["quadtree"] = json!({ "depth": q.depth, "cell_size": q.cell, "max_bytes": q.max_bytes });
        }
    }
    Ok(j)
}

/// The process's peak resident memory (`VmHWM` of `/proc/self/status`), where the system reports it (Linux).
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line
        .trim_start_matches("VmHWM:")
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every key of [`CONFIG_KEYS`] is read into its field (the hand-written list and the structs agree), a value of
    /// the wrong type is refused in words, and a key outside the list is refused with the list.
    #[test]
    fn every_config_key_is_read_and_no_other() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("p.toml");
        let text = "sectors = 8\nsubsectors = 2\nseeds = 50\nrng_seed = 3\norphan_passes = 4\nmin_group = 20\n\
                    max_expanse = 0.5\nundersampling = 100.0\ngrouping = \"quadtree\"\ndepth = 3\nmax_bytes = 1000\n";
        std::fs::write(&path, text).expect("write");
        let p = ParamArgs::read(&path).expect("every key but the cell size");
        let f = &p.fixed;
        assert_eq!(
            (p.sectors, p.subsectors, p.seeds, p.rng_seed),
            (Some(8), Some(2), Some(50), Some(3))
        );
        assert_eq!(
            (f.orphan_passes, f.min_group, f.max_expanse),
            (Some(4), Some(20), Some(0.5))
        );
        assert_eq!(
            (f.undersampling, f.grouping.as_deref()),
            (Some(100.0), Some("quadtree"))
        );
        assert_eq!((f.depth, f.cell_size, f.max_bytes), (Some(3), None, Some(1000)));
        for key in ["cell_size", "cell"] {
            std::fs::write(&path, format!("{key} = 250.0\n")).expect("write");
            assert_eq!(ParamArgs::read(&path).expect(key).fixed.cell_size, Some(250.0), "{key}");
        }
        assert_eq!(
            text.lines().count() + 2,
            CONFIG_KEYS.len(),
            "a key of the list is not tested here"
        );
        for (text, message) in [
            (
                "sectors = \"x\"",
                "`sectors` takes a whole number from 0 to 4294967295, not the string \"x\"",
            ),
            (
                "depth = -1",
                "`depth` takes a whole number from 0 to 4294967295, not the integer -1",
            ),
            ("subsectors = 4294967296", "not the integer 4294967296"),
            (
                "seeds = 2.0",
                "`seeds` takes a whole number (0 or more), not the float 2.0",
            ),
            (
                "max_expanse = true",
                "`max_expanse` takes a number, not the boolean true",
            ),
            ("grouping = 3", "`grouping` takes a string, not the integer 3"),
        ] {
            std::fs::write(&path, text).expect("write");
            let e = format!("{:#}", ParamArgs::read(&path).expect_err(text));
            assert!(e.contains(message), "{text}: {e}");
        }
        let long = format!("rng_seed = [{}]", vec!["1"; 100].join(", "));
        std::fs::write(&path, &long).expect("write");
        let e = format!("{:#}", ParamArgs::read(&path).expect_err("an array"));
        assert!(e.ends_with("not the array of 300 characters"), "{e}");
        std::fs::write(&path, "sectors = 8\ncolumns = 64\n").expect("write");
        let e = format!("{:#}", ParamArgs::read(&path).expect_err("not a build parameter"));
        assert!(e.contains("unknown key `columns`") && e.contains("max_bytes"), "{e}");
    }
}
