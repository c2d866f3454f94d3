//! End-to-end test of `tincull sweep`: a small sweep on the bundled mesh, its CSV, and resuming.

use std::path::{Path, PathBuf};
use std::process::Command;

fn mesh(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes").join(name)
}

fn sweep(out: &Path, extra: &[&str]) -> serde_json::Value {
    let mesh = mesh("jacksboro-2k.obj");
    let mut args = vec![
        "sweep",
        mesh.to_str().expect("utf-8 path"),
        "--viewpoints",
        "1",
        "--classes",
        "low,ridge",
        "--json",
        "-o",
        out.to_str().expect("utf-8 path"),
    ];
    args.extend_from_slice(extra);
    let o = Command::new(env!("CARGO_BIN_EXE_tincull"))
        .args(&args)
        .output()
        .expect("the binary runs");
    assert!(
        o.status.success(),
        "tincull {args:?} failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).expect("one JSON object on stdout")
}

#[test]
fn sweep_writes_every_combination_and_resumes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let csv = dir.path().join("sweep.csv");
    // 2 sectors and 64 x 32 subsectors are invalid: a sweep of nothing else is an error giving both reasons, before
    // any work, and writes nothing.
    let o = Command::new(env!("CARGO_BIN_EXE_tincull"))
        .args([
            "sweep",
            mesh("jacksboro-2k.obj").to_str().expect("utf-8 path"),
            "--sectors",
            "2,64",
        ])
        .args(["--subsectors", "32", "--json", "-o", csv.to_str().expect("utf-8 path")])
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    assert!(stderr.contains("no combination to sweep is valid"), "{stderr}");
    assert!(stderr.contains("sectors 2 x"), "{stderr}");
    assert!(stderr.contains("sectors 64 x subsectors 32"), "{stderr}");
    assert!(o.stdout.is_empty() && !csv.exists());

    let small = dir.path().join("small.csv");
    let v = sweep(&small, &["--sectors", "4,8", "--subsectors", "1,2"]);
    assert_eq!(v["ran"], 4);
    assert_eq!(v["skipped"], 0);
    let text = std::fs::read_to_string(&small).expect("csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("no {name}"))
    };
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    // 4 combinations x 6 methods (safe, lloyd-egbert, thesis, per_triangle, frustum_only, none) x (2 classes + all).
    assert_eq!(rows.len(), 4 * 6 * 3);
    assert!(rows.iter().all(|r| r.len() == header.len()));
    let combos: Vec<(&str, &str)> = rows.iter().map(|r| (r[col("sectors")], r[col("subsectors")])).collect();
    let mut expected = Vec::new();
    for c in [("4", "1"), ("4", "2"), ("8", "1"), ("8", "2")] {
        expected.extend(std::iter::repeat_n(c, 18));
    }
    assert_eq!(combos, expected, "rows in key order");
    for r in &rows {
        let num = |name: &str| {
            r[col(name)]
                .parse::<f64>()
                .unwrap_or_else(|_| panic!("{name}: {:?}", r[col(name)]))
        };
        assert_eq!(num("viewpoints_per_class"), 1.0);
        assert_eq!(num("seeds"), (num("triangles") / 200.0).floor().max(1.0));
        assert!(num("groups") >= 1.0 && num("nodes") >= num("groups"));
        assert!(num("horizon_seconds") > 0.0);
        // Viewpoints scored on the line, as in `eval`'s CSV: one per class here, both classes' in `all`.
        let views = if r[col("class")] == "all" { 2.0 } else { 1.0 };
        assert_eq!(num("viewpoints"), views);
        match r[col("method")] {
            "none" => {
                assert_eq!(num("triangles_drawn_mean"), num("triangles"));
                assert_eq!(num("false_culls_max"), 0.0);
                if !r[col("occlusion_captured_mean")].is_empty() {
                    assert_eq!(num("occlusion_captured_mean"), 0.0);
                }
            }
            "safe" | "lloyd-egbert" | "thesis" | "per_triangle" | "frustum_only" => {
                assert!(num("triangles_drawn_mean") <= num("triangles"));
                assert!(num("cull_ns") > 0.0);
            }
            m => panic!("unexpected method {m}"),
        }
    }
    // Everything but the timings is deterministic: a second sweep into another file agrees.
    let again = dir.path().join("again.csv");
    sweep(&again, &["--sectors", "8,4", "--subsectors", "2,1"]);
    let strip = |t: &str| -> Vec<String> {
        let timing = ["horizon_seconds", "regions_seconds", "grouping_seconds", "cull_ns"].map(col);
        t.lines()
            .map(|l| {
                l.split(',')
                    .enumerate()
                    .filter(|(i, _)| !timing.contains(i))
                    .map(|(_, f)| f)
                    .collect::<Vec<_>>()
                    .join(",")
            })
            .collect()
    };
    assert_eq!(strip(&text), strip(&std::fs::read_to_string(&again).expect("csv")));

    // Resuming: nothing to run and the file is untouched; a wider sweep runs only the new combinations.
    let v = sweep(&small, &["--sectors", "4,8", "--subsectors", "1,2"]);
    assert_eq!(v["ran"], 0);
    assert_eq!(v["skipped"], 4);
    assert_eq!(std::fs::read_to_string(&small).expect("csv"), text);
    let v = sweep(&small, &["--sectors", "4,8", "--subsectors", "1..3"]);
    assert_eq!(v["ran"], 2);
    assert_eq!(v["skipped"], 4);
    let wider = std::fs::read_to_string(&small).expect("csv");
    assert_eq!(wider.lines().count(), 1 + 6 * 18);
    let old: Vec<&str> = text.lines().collect();
    assert!(
        old.iter().all(|l| wider.lines().any(|w| w == *l)),
        "old rows kept verbatim"
    );

    // A file that is not a sweep file is refused, not overwritten.
    let foreign = dir.path().join("foreign.csv");
    std::fs::write(&foreign, "a,b\n1,2\n").expect("write");
    let o = Command::new(env!("CARGO_BIN_EXE_tincull"))
        .args(["sweep", mesh("jacksboro-2k.obj").to_str().expect("path"), "-q", "-o"])
        .arg(&foreign)
        .output()
        .expect("runs");
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("header"));
    assert_eq!(std::fs::read_to_string(&foreign).expect("read"), "a,b\n1,2\n");
}

#[test]
fn sweep_without_per_triangle_has_five_methods() {
    let dir = tempfile::tempdir().expect("temp dir");
    let csv = dir.path().join("s.csv");
    let v = sweep(&csv, &["--sectors", "4", "--subsectors", "1", "--no-per-triangle"]);
    assert_eq!(v["ran"], 1);
    let text = std::fs::read_to_string(&csv).expect("csv");
    assert_eq!(text.lines().count(), 1 + 5 * 3);
    assert!(!text.contains("per_triangle"));
}

/// A resume never takes a damaged file's combinations for finished ones: a lost line, or a last line cut short
/// (an interrupted write), runs that combination again (with a warning) and restores the file; a field that is not
/// a number and a repeated line are refused by line, and the file is left as it is.
#[test]
fn sweep_resume_reruns_incomplete_combinations_and_refuses_damaged_lines() {
    let dir = tempfile::tempdir().expect("temp dir");
    let csv = dir.path().join("s.csv");
    let args = ["--sectors", "4,8", "--subsectors", "1", "--no-per-triangle"];
    assert_eq!(sweep(&csv, &args)["ran"], 2);
    let text = std::fs::read_to_string(&csv).expect("csv");
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 1 + 2 * 5 * 3);
    // Timings differ from run to run: compare the lines without them.
    let header: Vec<&str> = lines[0].split(',').collect();
    let timing: Vec<usize> = ["horizon_seconds", "regions_seconds", "grouping_seconds", "cull_ns"]
        .iter()
        .map(|n| header.iter().position(|h| h == n).expect("timing column"))
        .collect();
    let strip = |t: &str| -> Vec<String> {
        t.lines()
            .map(|l| {
                let f: Vec<&str> = l
                    .split(',')
                    .enumerate()
                    .filter(|(i, _)| !timing.contains(i))
                    .map(|(_, f)| f)
                    .collect();
                f.join(",")
            })
            .collect()
    };
    let resume = |damaged: &str| {
        std::fs::write(&csv, damaged).expect("write");
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_tincull"));
        cmd.args(["sweep", mesh("jacksboro-2k.obj").to_str().expect("path")])
            .args(["--viewpoints", "1", "--classes", "low,ridge", "--json", "-o"])
            .arg(&csv)
            .args(args);
        cmd.output().expect("runs")
    };

    // A line lost (the last one, and one in the middle of the first combination): that combination runs again.
    for lost in [lines.len() - 1, 3] {
        let kept: Vec<&str> = lines
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != lost)
            .map(|(_, l)| *l)
            .collect();
        let o = resume(&(kept.join("\n") + "\n"));
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{stderr}");
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
        assert_eq!(
            (v["ran"].as_u64(), v["skipped"].as_u64()),
            (Some(1), Some(1)),
            "line {lost} lost"
        );
        assert!(stderr.contains("incomplete: run again"), "{stderr}");
        let sectors = if lost == 3 { "sectors 4" } else { "sectors 8" };
        assert!(stderr.contains(sectors), "{stderr}");
        assert_eq!(strip(&std::fs::read_to_string(&csv).expect("csv")), strip(&text));
    }
    // The last line cut short, without its newline: left out with a warning, its combination run again.
    let cut = &text[..text.len() - 8];
    let o = resume(cut);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!("line {} is cut short", lines.len())),
        "{stderr}"
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(v["ran"], 1);
    assert_eq!(strip(&std::fs::read_to_string(&csv).expect("csv")), strip(&text));

    // A field that is not a number, and a repeated line: refused by line (and column), the file untouched.
    let column = timing[0];
    let mut fields: Vec<&str> = lines[2].split(',').collect();
    fields[column] = "abc";
    let bad_field = fields.join(",");
    let not_a_number = text.replacen(lines[2], &bad_field, 1);
    let repeated = format!("{text}{}\n", lines[5]);
    for (damaged, says) in [
        (not_a_number, format!("line 3, column {} (horizon_seconds)", column + 1)),
        (repeated, format!("line {}: a second line", lines.len() + 1)),
    ] {
        let o = resume(&damaged);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{says}: resumed");
        assert!(stderr.contains(&says) && stderr.contains("s.csv"), "{says}: {stderr}");
        assert_eq!(std::fs::read_to_string(&csv).expect("csv"), damaged);
    }
}

#[test]
fn sweep_rejects_bad_lists() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("x.csv");
    // Runs a sweep that must fail without a panic and write nothing; returns its error.
    let refused = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_tincull"))
            .args(["sweep", mesh("jacksboro-2k.obj").to_str().expect("path"), "-q", "-o"])
            .arg(&out)
            .args(args)
            .output()
            .expect("runs");
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(!o.status.success(), "{args:?}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(!out.exists(), "{args:?}");
        err
    };
    for (opt, val) in [("--sectors", "4,x"), ("--rng-seeds", "5..1"), ("--subsectors", "")] {
        let err = refused(&[opt, val]);
        assert!(err.contains(opt), "{opt} {val}: {err}");
    }
    // A value given twice would be swept once: refused (it once was dropped without a word).
    for (opt, val) in [("--sectors", "4,4"), ("--subsectors", "1..3,2"), ("--rng-seeds", "1,1")] {
        let err = refused(&[opt, val]);
        assert!(err.contains(opt) && err.contains("given twice"), "{opt} {val}: {err}");
    }
    // The crystal's swept parameters with a quadtree: refused by name.
    for (opt, val) in [("--seeds", "10"), ("--rng-seeds", "1,2"), ("--rng-seed", "3")] {
        let err = refused(&["--grouping", "quadtree", opt, val]);
        assert!(err.contains("applies to the crystal grouping"), "{opt} {val}: {err}");
    }
    // A table named as another format (it once wrote a CSV named .tch, or read a hierarchy as one to resume).
    let tch = dir.path().join("x.tch");
    let o = Command::new(env!("CARGO_BIN_EXE_tincull"))
        .args(["sweep", mesh("jacksboro-2k.obj").to_str().expect("path"), "-q", "-o"])
        .arg(&tch)
        .args(["--sectors", "4", "--subsectors", "1"])
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("name it .csv"), "{err}");
    assert!(!tch.exists());
}

#[test]
fn sweep_never_resumes_another_setup() {
    let dir = tempfile::tempdir().expect("temp dir");
    let csv = dir.path().join("s.csv");
    let v = sweep(&csv, &["--sectors", "4", "--subsectors", "1", "--no-per-triangle"]);
    assert_eq!(v["ran"], 1);
    let text = std::fs::read_to_string(&csv).expect("csv");
    // Another viewpoint seed, other classes, another mesh or other build options: refused, the file untouched.
    let other_mesh = mesh("synth-5k.obj");
    for extra in [
        vec!["--view-seed", "7"],
        vec!["--classes", "sky"],
        vec!["--min-group", "40"],
        vec!["--mesh-instead"],
    ] {
        let mut args = vec![
            "sweep".to_string(),
            if extra[0] == "--mesh-instead" {
                other_mesh.to_string_lossy().into_owned()
            } else {
                mesh("jacksboro-2k.obj").to_string_lossy().into_owned()
            },
        ];
        for a in [
            "--sectors",
            "4",
            "--subsectors",
            "1",
            "--no-per-triangle",
            "--viewpoints",
            "1",
            "-q",
            "-o",
        ] {
            args.push(a.into());
        }
        args.push(csv.to_string_lossy().into_owned());
        if extra[0] != "--mesh-instead" {
            args.extend(extra.iter().map(|s| s.to_string()));
        }
        if !args.contains(&"--classes".to_string()) {
            args.extend(["--classes".to_string(), "low,ridge".to_string()]);
        }
        let o = Command::new(env!("CARGO_BIN_EXE_tincull"))
            .args(&args)
            .output()
            .expect("runs");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{extra:?} resumed another setup");
        assert!(
            err.contains("s.csv") && err.contains("another sweep setup"),
            "{extra:?}: {err}"
        );
        assert_eq!(std::fs::read_to_string(&csv).expect("csv"), text);
    }
    // The same setup resumes.
    let v = sweep(&csv, &["--sectors", "4", "--subsectors", "1", "--no-per-triangle"]);
    assert_eq!((v["ran"].as_u64(), v["skipped"].as_u64()), (Some(0), Some(1)), "{v}");
}

/// `--config` gives the build parameters that are not swept, as `build --config` does: a sweep with `min_group = 40`
/// in the file is the same setup as one with `--min-group 40` (it resumes it), and a swept key in the file is refused
/// with an error naming the file and the key.
#[test]
fn sweep_reads_its_fixed_parameters_from_a_config() {
    let dir = tempfile::tempdir().expect("temp dir");
    let csv = dir.path().join("s.csv");
    let fixed = ["--sectors", "4", "--subsectors", "1", "--no-per-triangle"];
    let v = sweep(&csv, &[&fixed[..], &["--min-group", "40"]].concat());
    assert_eq!(v["ran"], 1);
    let config = dir.path().join("p.toml");
    std::fs::write(&config, "min_group = 40\n").expect("write");
    let v = sweep(
        &csv,
        &[&fixed[..], &["--config", config.to_str().expect("utf-8")]].concat(),
    );
    assert_eq!((v["ran"].as_u64(), v["skipped"].as_u64()), (Some(0), Some(1)), "{v}");
    for key in ["sectors = 8", "rng_seed = 3"] {
        std::fs::write(&config, format!("{key}\n")).expect("write");
        let o = Command::new(env!("CARGO_BIN_EXE_tincull"))
            .args(["sweep", mesh("jacksboro-2k.obj").to_str().expect("path"), "-q", "-o"])
            .arg(dir.path().join("x.csv"))
            .arg("--config")
            .arg(&config)
            .output()
            .expect("runs");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{key}");
        let name = key.split(' ').next().expect("key");
        assert!(err.contains("p.toml") && err.contains(name), "{key}: {err}");
        assert!(!dir.path().join("x.csv").exists());
    }
}

/// A sweep whose every combination is invalid, or whose `--classes` name a class twice, is an error naming why, before
/// the mesh is read; nothing is written.
#[test]
fn a_sweep_of_nothing_valid_is_an_error() {
    let dir = tempfile::tempdir().expect("temp dir");
    let csv = dir.path().join("sw.csv");
    for (extra, needle) in [
        (["--sectors", "0", "--subsectors", "1"], "sectors 0 x subsectors 1"),
        (["--sectors", "512", "--subsectors", "4"], "sectors 512 x subsectors 4"),
        (["--classes", "low,ridge,low", "--sectors", "4"], "`low` is given twice"),
        // The seed count as given, not as Rust's `Some(0)`.
        (["--seeds", "0", "--sectors", "4"], "subsectors 1, seeds 0, rng seed 1"),
        // More viewpoints than a run could score: refused, not a capacity overflow (a panic).
        (
            ["--viewpoints", "18446744073709551615", "--sectors", "4"],
            "at most 1000000 per class",
        ),
    ] {
        // A mesh that does not exist: the checks come first.
        let o = Command::new(env!("CARGO_BIN_EXE_tincull"))
            .args(["sweep", "no-such-mesh.obj", "-o", csv.to_str().expect("utf-8 path")])
            .args(extra)
            .output()
            .expect("the binary runs");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{extra:?}: {stderr}");
        assert!(
            stderr.contains("error") && stderr.contains(needle),
            "{extra:?}: {stderr}"
        );
        assert!(!stderr.contains("no-such-mesh"), "{extra:?}: {stderr}");
        assert!(!csv.exists());
    }
}

/// Invalid combinations of the lists are skipped with a warning each, the first few by name and the rest counted (a
/// range such as `--sectors 4..100000` once printed thousands of lines); `--json` lists every one.
#[test]
fn many_skipped_combinations_are_counted() {
    let dir = tempfile::tempdir().expect("temp dir");
    let csv = dir.path().join("s.csv");
    let mesh = mesh("jacksboro-2k.obj");
    let o = Command::new(env!("CARGO_BIN_EXE_tincull"))
        .args([
            "sweep",
            mesh.to_str().expect("path"),
            "--viewpoints",
            "1",
            "--classes",
            "low",
            "--json",
        ])
        .args(["--no-per-triangle", "-o", csv.to_str().expect("path")])
        .args(["--sectors", "1,2,3,4", "--subsectors", "1,5000,6000"])
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert_eq!(err.matches("warning: skipped").count(), 8, "{err}");
    assert!(
        err.contains("and 3 more skipped combinations (--json lists them all)"),
        "{err}"
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(v["notes"].as_array().map(Vec::len), Some(11), "{v}");
}
