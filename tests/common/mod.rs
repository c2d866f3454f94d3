//! Helpers shared by the end-to-end tests of the `tincull` binary: run it, expect success or a clear failure.

// Each test binary uses its own subset of these.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A bundled mesh.
pub fn mesh(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes").join(name)
}

/// Runs the binary with `args`.
pub fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tincull"))
        .args(args)
        .output()
        .expect("the binary runs")
}

/// Runs the binary and asserts success.
pub fn ok(args: &[&str]) -> Output {
    let out = run(args);
    assert!(
        out.status.success(),
        "tincull {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs the binary, asserts success and parses its standard output as one JSON object.
pub fn json(args: &[&str]) -> serde_json::Value {
    serde_json::from_slice(&ok(args).stdout).expect("one JSON object on stdout")
}

/// Runs the binary and asserts a clean failure (no panic) whose error message mentions `needle`.
pub fn fails_with(args: &[&str], needle: &str) {
    let out = run(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "tincull {args:?} should fail");
    assert!(!stderr.contains("panicked"), "tincull {args:?} panicked:\n{stderr}");
    assert!(stderr.contains("error"), "no error message for {args:?}:\n{stderr}");
    assert!(
        stderr.contains(needle),
        "error for {args:?} does not mention {needle:?}:\n{stderr}"
    );
}

/// A path as an argument.
pub fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

/// A 3 × 3 ESRI ASCII grid (10 m cells, heights 1 to 9) written as `name` in `dir`: the smallest DEM the readers take.
pub fn small_asc(dir: &Path, name: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(
        &path,
        "ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 10\n1 2 3\n4 5 6\n7 8 9\n",
    )
    .expect("write the grid");
    path
}
