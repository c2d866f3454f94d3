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

/// A directory holding only links to `bash` and `awk`, for `PATH`.
fn minimal_path() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("tempdir");
    for tool in ["bash", "awk"] {
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
    Command::new(root().join("scripts").join(name))
        .arg(arg)
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
        if !takes_arguments {
            let out = script(name, "--bogus", path.path());
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "scripts/{name} --bogus:\n{stderr}");
            assert!(
                stderr.contains(&format!("scripts/{name}: unknown argument --bogus")),
                "scripts/{name} --bogus:\n{stderr}"
            );
        }
    }
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
