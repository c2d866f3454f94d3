//! End-to-end tests of `tincull pvs`: one cell, a grid, the binary file, the check against ground truth, errors.

mod common;

use common::{fails_with, json, mesh, ok, s};
use pvs::PvsFile;

/// Builds the bundled 2k mesh's hierarchy in `dir`; returns its path and the footprint's centre.
fn hierarchy(dir: &std::path::Path) -> (std::path::PathBuf, [f64; 2]) {
    let tch = dir.join("j2k.tch");
    ok(&[
        "build",
        s(&mesh("jacksboro-2k.obj")),
        "-o",
        s(&tch),
        "--seeds",
        "20",
        "-q",
    ]);
    let bbox = json(&["info", s(&mesh("jacksboro-2k.obj")), "--json"])["bbox"].clone();
    let c = |k: usize| (bbox["min"][k].as_f64().expect("min") + bbox["max"][k].as_f64().expect("max")) / 2.0;
    (tch, [c(0), c(1)])
}

fn ranges(v: &serde_json::Value) -> Vec<[u32; 2]> {
    v.as_array()
        .expect("ranges")
        .iter()
        .map(|r| [r[0].as_u64().expect("start") as u32, r[1].as_u64().expect("end") as u32])
        .collect()
}

#[test]
fn one_cell_a_grid_and_the_binary_file_agree() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (tch, [cx, cy]) = hierarchy(dir.path());
    let cell = format!("{},{},{},{}", cx - 150.0, cy - 150.0, cx + 150.0, cy + 150.0);
    let file = dir.path().join("one.pvs");
    let v = json(&[
        "pvs",
        s(&tch),
        "--cell",
        &cell,
        "--above-ground",
        "0,20",
        "--resolution",
        "32",
        "-o",
        s(&file),
        "--json",
    ]);
    let nt = v["triangles"].as_u64().expect("triangles") as u32;
    let c = &v["cells"][0];
    let r = ranges(&c["ranges"]);
    assert!(!r.is_empty(), "the cell sees at least the ground under it");
    assert!(
        r.windows(2).all(|w| w[0][1] < w[1][0]),
        "ranges increasing and merged: {r:?}"
    );
    assert!(r.iter().all(|x| x[0] < x[1] && x[1] <= nt));
    let size: u64 = r.iter().map(|x| u64::from(x[1] - x[0])).sum();
    assert_eq!(c["pvs_triangles"].as_u64(), Some(size));
    assert!(
        size < u64::from(nt),
        "a 300 m cell near the ground does not see the whole terrain"
    );
    // The height as the flags name it, and the file's size as written.
    assert_eq!(v["height"], serde_json::json!({"above_ground": [0.0, 20.0]}));
    assert_eq!(
        v["file_bytes"].as_u64(),
        Some(std::fs::metadata(&file).expect("pvs file").len())
    );
    let decoded = PvsFile::from_bytes(&std::fs::read(&file).expect("pvs file")).expect("a valid .pvs");
    assert_eq!(decoded.cells.len(), 1);
    assert_eq!(decoded.cells[0].ranges(), r);
    assert_eq!(decoded.triangles, nt);
    // `info` describes the file as `pvs` computed it.
    let info = json(&["info", s(&file), "--json"]);
    assert_eq!(info["triangles"].as_u64(), Some(u64::from(nt)));
    assert_eq!(info["file_bytes"], v["file_bytes"]);
    assert_eq!((&info["method"], info["resolution"].as_u64()), (&v["method"], Some(32)));
    assert_eq!(ranges(&info["cells"][0]["ranges"]), r);
    assert_eq!(info["cells"][0]["pvs_triangles"].as_u64(), Some(size));
    assert_eq!(info["cells"][0]["nodes"], c["nodes"]);
    assert_eq!(info["cells"][0]["height"], v["height"]);
    let text = String::from_utf8_lossy(&ok(&["info", s(&file)]).stdout).into_owned();
    assert!(
        text.contains("(a tincull PVS file,") && text.contains(&format!("cells         1, mean PVS {size} triangles")),
        "{text}"
    );
    // By its content, whatever its name: the same file named .tch is described as a PVS file too.
    let renamed = dir.path().join("one-pvs.tch");
    std::fs::copy(&file, &renamed).expect("copy");
    assert_eq!(json(&["info", s(&renamed), "--json"])["cells"], info["cells"]);

    // The grid: deterministic, and its cell containing the one above has ranges of the same kind.
    let (g1, g2) = (dir.path().join("g1.pvs"), dir.path().join("g2.pvs"));
    let grid = json(&["pvs", s(&tch), "--grid", "4000", "-o", s(&g1), "--json", "-q"]);
    let cells = grid["cells"].as_array().expect("cells");
    assert!(cells.len() > 4, "a 4 km grid over a 30 km terrain");
    for c in cells {
        let r = ranges(&c["ranges"]);
        assert!(r.windows(2).all(|w| w[0][1] < w[1][0]) && r.iter().all(|x| x[1] <= nt));
        assert!(c["bytes"].as_u64().expect("bytes") > 0);
    }
    ok(&["pvs", s(&tch), "--grid", "4000", "-o", s(&g2), "-q"]);
    // Without -o there is no file, and no file size.
    let none = json(&["pvs", s(&tch), "--cell", &cell, "--height-band", "0,3000", "--json"]);
    assert_eq!(none["file_bytes"], serde_json::Value::Null);
    assert_eq!(none["height"], serde_json::json!({"band": [0.0, 3000.0]}));
    assert_eq!(
        std::fs::read(&g1).expect("g1"),
        std::fs::read(&g2).expect("g2"),
        "same input, same bytes"
    );
}

#[test]
fn the_check_finds_no_miss() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (tch, _) = hierarchy(dir.path());
    let v = json(&[
        "pvs",
        s(&tch),
        "--check",
        "2",
        "--cell-size",
        "300",
        "--above-ground",
        "0,20",
        "--resolution",
        "16,64",
        "--json",
        "-q",
    ]);
    assert_eq!(v["sample_points"].as_u64(), Some(128), "64 sample points per cell");
    let rows = v["rows"].as_array().expect("rows");
    assert_eq!(rows.len(), 4, "koltun at 16 and 64, regions, both at 64");
    let visible = v["mean_union_visible"].as_f64().expect("visible");
    assert!(visible > 0.0);
    for row in rows {
        assert_eq!(row["misses"].as_u64(), Some(0), "{row}");
        assert!(row["mean_pvs_over_visible"].as_f64().expect("ratio") >= 1.0, "{row}");
    }
}

/// A check whose sample points see nothing (a band a millimetre thick at the lowest ground, its eyes under the ground
/// almost everywhere) gives no ratio to the union of visible sets (a divisor of 0 was taken as 1).
#[test]
fn a_check_that_sees_nothing_has_no_ratio() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (obj, tch) = (dir.path().join("s.obj"), dir.path().join("s.tch"));
    ok(&["synth", "-o", s(&obj), "--vertices", "300", "--rng-seed", "3", "-q"]);
    ok(&["build", s(&obj), "-o", s(&tch), "-q"]);
    let v = json(&[
        "pvs",
        s(&tch),
        "--check",
        "2",
        "--height-band",
        "0,0.001",
        "--json",
        "-q",
    ]);
    assert_eq!(v["mean_union_visible"].as_f64(), Some(0.0), "{v}");
    for row in v["rows"].as_array().expect("rows") {
        assert_eq!(row["pvs_over_visible"], serde_json::Value::Null, "{row}");
        assert!(row["pvs_over_safe"].as_f64().expect("a ratio") > 0.0, "{row}");
    }
}

#[test]
fn bad_arguments_give_clear_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (tch, [cx, cy]) = hierarchy(dir.path());
    let cell = format!("{},{},{},{}", cx, cy, cx + 50.0, cy + 50.0);
    fails_with(&["pvs", s(&tch), "--cell", &cell, "--resolution", "0"], "resolution");
    fails_with(&["pvs", s(&tch), "--cell", &cell, "--resolution", "300"], "resolution");
    fails_with(
        &["pvs", s(&tch), "--cell", &cell, "--resolution", "16,32"],
        "only with --check",
    );
    fails_with(
        &["pvs", s(&tch), "--check", "1", "--resolution", "8,8"],
        "--resolution: 8 is given twice",
    );
    fails_with(&["pvs", s(&tch), "--cell", "10,0,5,5"], "x0 < x1");
    fails_with(&["pvs", s(&tch), "--cell", "1,2,3"], "4 comma-separated");
    fails_with(
        &["pvs", s(&tch), "--cell", &cell, "--height-band", "5,1"],
        "height band",
    );
    fails_with(&["pvs", s(&tch), "--cell", &cell, "--method", "exact"], "koltun");
    fails_with(&["pvs", s(&tch), "--grid", "0"], "grid");
    fails_with(&["pvs", s(&tch), "--cell", &cell, "--patch", "0"], "--patch");
    // Koltun's parameters with the regions alone, which would ignore them.
    for (flag, value) in [("--resolution", "16"), ("--patch", "4")] {
        fails_with(
            &["pvs", s(&tch), "--cell", &cell, "--method", "regions", flag, value],
            &format!("{flag} does not apply to --method regions"),
        );
    }
    fails_with(&["pvs", s(&tch), "--check", "1", "--cell-size", "1e6"], "cell-size");
    fails_with(
        &["pvs", s(&tch), "--check", "1", "--method", "koltun"],
        "--check reports every method",
    );
    fails_with(&["pvs", "/no/such.tch", "--cell", &cell], "such.tch");
    // Cells whose heights make no sense where they lie: off the terrain with heights above the ground, below the
    // ground (the bundled terrain lies above 200 m), and a grid of more cells than a run could compute.
    let off = format!("{},{},{},{}", cx + 1e6, cy, cx + 1e6 + 50.0, cy + 50.0);
    fails_with(&["pvs", s(&tch), "--cell", &off], "lies off the terrain");
    // An absolute band is fine beside the terrain (an aircraft approaching it).
    ok(&["pvs", s(&tch), "--cell", &off, "--height-band", "0,3000", "--json"]);
    fails_with(
        &["pvs", s(&tch), "--cell", &cell, "--above-ground=-5,-1"],
        "must be 0 or more",
    );
    fails_with(
        &["pvs", s(&tch), "--cell", &cell, "--height-band", "0,100"],
        "lies below the terrain",
    );
    // A grid's or a check's cells are held to the whole terrain: a band below its lowest vertex is refused (it was
    // computed, every eye under the ground).
    for flag in ["--grid", "--check"] {
        fails_with(
            &["pvs", s(&tch), flag, "3000", "--height-band", "0,100", "--json"],
            "--height-band: the band up to 100 m lies below the whole terrain",
        );
    }
    fails_with(&["pvs", s(&tch), "--grid", "1"], "more than 1000000");
    fails_with(&["pvs", s(&tch), "--grid", "1e-300"], "a grid of 1e-300 m gives 2.99");
    // As many random cells: refused before they are drawn (a capacity overflow panicked, or the allocation aborted).
    fails_with(
        &["pvs", s(&tch), "--check", "18446744073709551615"],
        "at most 1000000 cells",
    );
    fails_with(&["pvs", s(&tch), "--check", "1000000000000"], "at most 1000000 cells");
    fails_with(
        &["pvs", s(&tch), "--check", "1", "--cell-size", "1e-300"],
        "--cell-size 1e-300",
    );
    let eye = format!("{cx},{cy},-5");
    fails_with(&["cull", s(&tch), "--eye", &eye, "--above-ground"], "must be 0 or more");
    fails_with(
        &["failmap", s(&tch), "--cell-size", "5000", "--eye-height=-5", "--json"],
        "--eye-height",
    );
    // Beyond the exact checker's reach (10,000 km), as for `eval`: refused rather than scored wrongly.
    fails_with(
        &[
            "failmap",
            s(&tch),
            "--cell-size",
            "5000",
            "--eye-height",
            "1e308",
            "--json",
        ],
        "--eye-height 1e308: failmap scores eyes within 10000000 m of the terrain",
    );
    fails_with(
        &["pvs", s(&tch), "--check", "1", "--above-ground", "0,1e12"],
        "--above-ground: --check scores sample points within 10000000 m of the terrain's box",
    );
    fails_with(
        &["pvs", s(&tch), "--check", "1", "--height-band", "0,1e12"],
        "and this band reaches",
    );
}

/// The regions of a hierarchy built without them keep every triangle: `--method regions` says so, as `cull` and
/// `failmap` do for their region methods; without `-o` the size is that of the file it would write.
#[test]
fn regions_without_regions_are_named() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (obj, tch) = (dir.path().join("s.obj"), dir.path().join("q.tch"));
    ok(&["synth", "-o", s(&obj), "--vertices", "300", "--rng-seed", "3", "-q"]);
    ok(&[
        "build",
        s(&obj),
        "-o",
        s(&tch),
        "--grouping",
        "quadtree",
        "--no-regions",
        "-q",
    ]);
    let out = ok(&["pvs", s(&tch), "--cell", "100,100,150,150", "--method", "regions"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("q.tch holds no regions") && stderr.contains("--method regions keeps every triangle"),
        "{stderr}"
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("bytes as a .pvs file (give -o to write it)"),
        "{stdout}"
    );
}
