//! The helper scripts as a new user meets them: `--help` says what each does and does nothing else, an argument a
//! script does not take is refused before any work, and the Dask driver of tiled builds says how to install Dask
//! when it is missing (and refuses a cluster that could never run a tile) instead of a Python traceback.
//!
//! The scripts run with a `PATH` that holds only `bash` and `awk`, so that a script which ignored its arguments
//! could not install packages, build or run anything: it would fail instead.

#![cfg(unix)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A directory holding only links to `bash`, `awk` and `dirname`, for `PATH`.
fn minimal_path() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("tempdir");
    for tool in ["bash", "awk", "dirname"] {
        let found = ["/usr/bin", "/bin"]
            .iter()
            .map(|d| Path::new(d).join(tool))
            .find(|p| p.exists())
            .unwrap_or_else(|| panic!("{tool} is not in /usr/bin or /bin"));
        std::os::unix::fs::symlink(&found, dir.path().join(tool)).expect("symlink");
    }
    dir
}

fn script(name: &str, arg: &str, path: &Path) -> Output {
    script_with(name, &[arg], path)
}

fn script_with(name: &str, args: &[&str], path: &Path) -> Output {
    Command::new(root().join("scripts").join(name))
        .args(args)
        .env("PATH", path)
        .env("TINCULL_SKIP_INSTALL", "1")
        .current_dir(root())
        .output()
        .expect("the script runs")
}

#[test]
fn every_script_has_help_and_refuses_arguments_it_does_not_take() {
    let path = minimal_path();
    // (script, the first words of its description, whether it takes arguments of its own)
    let scripts = [
        ("charts", "Regenerates the charts in docs/", false),
        ("install-deps", "Installs the system packages the GPU tests need", false),
        ("test", "Runs every check of the project", false),
        ("tiles-dask", "Tests the Dask driver of tiled builds", false),
        ("notebooks", "Runs every notebook in notebooks/ headless", false),
        (
            "check-cull-latest",
            "Builds the embeddable `cull` crate on its own",
            false,
        ),
        (
            "tiles-figures",
            "The figures of the README's \"Tiled builds\" section",
            true,
        ),
        ("fuzz", "Runs the libFuzzer targets of fuzz/", true),
        ("scale", "Scale measurement", true),
        ("hunt", "False-cull hunt", true),
        ("soak", "Soak test of the safe cullers", true),
        ("tiles-safety", "Safety of tiled builds on real terrain", true),
    ];
    for (name, description, takes_arguments) in scripts {
        for help in ["--help", "-h"] {
            let out = script(name, help, path.path());
            let stdout = String::from_utf8_lossy(&out.stdout);
            assert!(
                out.status.success(),
                "scripts/{name} {help} failed:\n{}",
                String::from_utf8_lossy(&out.stderr)
            );
            assert!(stdout.starts_with(description), "scripts/{name} {help}:\n{stdout}");
            assert!(stdout.lines().count() >= 2, "scripts/{name} {help}:\n{stdout}");
            assert!(!stdout.contains("#!/"), "scripts/{name} {help}:\n{stdout}");
        }
        let out = script(name, "--bogus", path.path());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "scripts/{name} --bogus:\n{stderr}");
        let expected = if name == "fuzz" {
            // Its first argument is SECONDS.
            "scripts/fuzz: SECONDS takes a whole number, not '--bogus'".to_string()
        } else {
            format!("scripts/{name}: unknown argument --bogus")
        };
        assert!(stderr.contains(&expected), "scripts/{name} --bogus:\n{stderr}");
        if !takes_arguments {
            let out = script_with(name, &["--help", "x"], path.path());
            assert_eq!(out.status.code(), Some(2), "scripts/{name} --help x");
        }
    }
}

/// Arguments of the measuring scripts are checked before any work: a flag without its value, a value of the wrong
/// kind, a second working directory and a missing `TINCULL_BIN` are refused with exit 2 and a message, and a refused
/// `scripts/scale` leaves the table it would have replaced as it was.
#[test]
fn the_measuring_scripts_check_their_arguments_first() {
    let path = minimal_path();
    let dir = tempfile::tempdir().expect("tempdir");
    let table = dir.path().join("scale.csv");
    std::fs::write(&table, "source,vertices\nsynth,10\n").expect("write");
    let out_dir = dir.path().to_str().expect("utf-8 path");
    let cases: &[(&str, &[&str], &str)] = &[
        ("scale", &["--vertices"], "scripts/scale: --vertices needs a value"),
        ("scale", &["--out"], "scripts/scale: --out needs a value"),
        (
            "scale",
            &["--vertices", "abc", "--out", out_dir],
            "scripts/scale: --vertices takes counts separated by commas, not 'abc'",
        ),
        (
            "scale",
            &["--sources", "moon", "--out", out_dir],
            "scripts/scale: unknown source 'moon' in --sources",
        ),
        (
            "scale",
            &["--quick", "--vertices", "10"],
            "not with --vertices or --sources",
        ),
        ("hunt", &["--out"], "scripts/hunt: --out needs a value"),
        ("soak", &["--seed"], "scripts/soak: --seed needs a value"),
        (
            "soak",
            &["--runs", "x"],
            "scripts/soak: --runs takes a whole number, not 'x'",
        ),
        (
            "soak",
            &["--seconds", "0"],
            "scripts/soak: --seconds must be at least 1",
        ),
        ("soak", &["--runs", "3", "--seconds", "9"], "give one"),
        ("fuzz", &["0"], "scripts/fuzz: SECONDS must be at least 1"),
        ("fuzz", &["5", "nope"], "scripts/fuzz: unknown target nope"),
        ("tiles-safety", &["a", "b"], "scripts/tiles-safety: unknown argument b"),
        (
            "tiles-figures",
            &["a", "b"],
            "scripts/tiles-figures: unknown argument b",
        ),
    ];
    for (name, args, expected) in cases {
        let out = script_with(name, args, path.path());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "scripts/{name} {args:?}:\n{stderr}");
        assert!(stderr.contains(expected), "scripts/{name} {args:?}:\n{stderr}");
    }
    assert_eq!(
        std::fs::read_to_string(&table).expect("read"),
        "source,vertices\nsynth,10\n",
        "a refused scripts/scale left the table as it was"
    );

    // A TINCULL_BIN that is no binary is named before any run (soak made a failed run of each, in a tight loop).
    let missing = dir.path().join("no-such-tincull");
    let out = Command::new(root().join("scripts/soak"))
        .args(["--runs", "2"])
        .env("PATH", path.path())
        .env("TINCULL_BIN", &missing)
        .current_dir(root())
        .output()
        .expect("the script runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "scripts/soak: {} is not an executable tincull binary",
            missing.display()
        )),
        "{stderr}"
    );

    // A missing DEM for the cascades source is refused before any work: skipping it replaced the table with one
    // without its rows.
    let out = Command::new(root().join("scripts/scale"))
        .args(["--sources", "cascades", "--vertices", "10000", "--out", out_dir])
        .env("PATH", path.path())
        .env("TINCULL_DEM", dir.path().join("no-such.hgt"))
        .current_dir(root())
        .output()
        .expect("the script runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("no-such.hgt is missing: the cascades source needs it"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read_to_string(&table).expect("read"),
        "source,vertices\nsynth,10\n",
        "scripts/scale without its DEM left the table as it was"
    );
}

/// `scripts/tiles/dask_tiles.py` run by `python3` with the given extra arguments, `PYTHONPATH` set to `pythonpath`.
fn dask_driver(pythonpath: &Path, plan: &Path, extra: &[&str]) -> Output {
    let out_tch = plan.with_extension("tch");
    Command::new("python3")
        .arg(root().join("scripts/tiles/dask_tiles.py"))
        .arg(plan)
        .arg("-o")
        .arg(&out_tch)
        .args(["--tincull", env!("CARGO_BIN_EXE_tincull")])
        .args(extra)
        .env("PYTHONPATH", pythonpath)
        .output()
        .expect("python3 runs")
}

#[test]
fn the_dask_driver_explains_a_missing_dask_and_refuses_no_workers() {
    let dir = tempfile::tempdir().expect("tempdir");
    // A `dask` package without `dask.distributed`: what the import finds when Dask is not (fully) installed.
    let fake: PathBuf = dir.path().join("site");
    std::fs::create_dir_all(fake.join("dask")).expect("mkdir");
    std::fs::write(fake.join("dask/__init__.py"), "").expect("write");
    let plan = dir.path().join("plan.json");
    std::fs::write(&plan, r#"{"tiles": [{}, {}]}"#).expect("write the plan");

    let out = dask_driver(&fake, &plan, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(!stderr.contains("Traceback"), "{stderr}");
    assert!(stderr.contains("error: Dask is not installed"), "{stderr}");
    assert!(stderr.contains("scripts/tiles/requirements.txt"), "{stderr}");

    // What `tiles plan --json` prints is not the plan; a merged file in a missing folder is refused before any tile.
    let report = dir.path().join("report.json");
    std::fs::write(&report, r#"{"tiles": 2}"#).expect("write the report");
    let out = dask_driver(&fake, &report, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("not a tincull plan (its `tiles` is no list"),
        "{stderr}"
    );
    let out = Command::new("python3")
        .arg(root().join("scripts/tiles/dask_tiles.py"))
        .arg(&plan)
        .arg("-o")
        .arg(dir.path().join("no-such-folder/x.tch"))
        .args(["--tincull", env!("CARGO_BIN_EXE_tincull")])
        .env("PYTHONPATH", &fake)
        .output()
        .expect("python3 runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(stderr.contains("x.tch: its folder does not exist"), "{stderr}");

    let out = dask_driver(&fake, &plan, &["--workers", "0"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--workers must be at least 1"), "{stderr}");

    let missing = dir.path().join("no-such-tincull");
    let out = Command::new("python3")
        .arg(root().join("scripts/tiles/dask_tiles.py"))
        .arg(&plan)
        .args(["-o", "x.tch", "--tincull"])
        .arg(&missing)
        .env("PYTHONPATH", &fake)
        .output()
        .expect("python3 runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!("{}: not an executable tincull binary", missing.display())),
        "{stderr}"
    );
}

/// The chart scripts: `--help` prints the description without drawing (it redrew the chart in docs/), an argument a
/// script does not take is refused, and a missing matplotlib is named with the environment that has it instead of a
/// traceback. A `matplotlib` package that fails to import stands for a missing one (and keeps any real one away).
#[test]
fn the_chart_scripts_have_help_and_name_a_missing_matplotlib() {
    let dir = tempfile::tempdir().expect("tempdir");
    let fake = dir.path().join("site");
    std::fs::create_dir_all(fake.join("matplotlib")).expect("mkdir");
    std::fs::write(
        fake.join("matplotlib/__init__.py"),
        "raise ImportError(\"No module named 'matplotlib'\")\n",
    )
    .expect("write");
    let python = |script: &str, args: &[&str]| {
        Command::new("python3")
            .arg(root().join("scripts").join(script))
            .args(args)
            .env("PYTHONPATH", &fake)
            .env("PYTHONDONTWRITEBYTECODE", "1")
            .current_dir(dir.path())
            .output()
            .expect("python3 runs")
    };
    for (script, takes) in [
        ("lloyd_egbert_chart.py", 0),
        ("pvs_chart.py", 0),
        ("stewart_chart.py", 0),
        ("scale_chart.py", 2),
    ] {
        let out = python(script, &["--help"]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{script} --help:\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(stdout.starts_with("Chart"), "{script} --help:\n{stdout}");

        let extra: Vec<&str> = std::iter::repeat_n("x", takes + 1).collect();
        let out = python(script, &extra);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{script} {extra:?}");
        assert!(stderr.contains(&format!("{script}: unknown argument x")), "{stderr}");

        let out = python(script, &[]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{script}");
        assert!(!stderr.contains("Traceback"), "{script}:\n{stderr}");
        assert!(
            stderr.contains("error: matplotlib is not installed") && stderr.contains(".venv-notebooks"),
            "{script}:\n{stderr}"
        );
    }
    assert_eq!(std::fs::read_dir(dir.path()).expect("list").count(), 1, "nothing drawn");
}
