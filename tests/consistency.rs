//! One command line (issue 16): `--json` is the same flag everywhere (one JSON object on stdout; files go to
//! `--export-json FILE`), `-o/--out` everywhere, `--view-seed` seeds viewpoints and `--rng-seed` the grouping,
//! `subsectors` means per sector, every command that reads a mesh takes `--keep-faces` and `--dedupe`, and
//! nonsense values are refused with an error that names the option.

use std::path::{Path, PathBuf};

mod common;
use common::{fails_with, json, mesh, ok, run, s};

/// A small hierarchy in a temporary directory.
fn hierarchy(dir: &Path) -> PathBuf {
    let tch = dir.join("h.tch");
    ok(&["build", s(&mesh("jacksboro-2k.obj")), "-o", s(&tch), "-q"]);
    tch
}

#[test]
fn json_is_a_flag_everywhere_and_files_are_export_json() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = hierarchy(dir.path());
    let out = dir.path().join("e.json");
    let v = json(&[
        "eval",
        s(&tch),
        "--viewpoints",
        "1",
        "--classes",
        "sky",
        "--no-per-triangle",
        "--export-json",
        s(&out),
        "--json",
    ]);
    assert_eq!(v["options"]["viewpoints"], 1);
    // The culler's parameters are reported, the defaults included, with the unlimited occluder budget as null.
    let d = cull::SafeParams::default();
    assert_eq!(v["options"]["safe"]["columns_per_face"], d.columns_per_face, "{v}");
    assert_eq!(v["options"]["safe"]["work_budget"], d.work_budget, "{v}");
    assert!(v["options"]["safe"]["occluder_budget"].is_null(), "{v}");
    assert!(v["rows"].as_array().is_some_and(|r| !r.is_empty()));
    let file: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).expect("file")).expect("JSON file");
    assert!(file["rows"].is_array());
    // `--json` and `--export-json` name the options alike.
    assert_eq!(file["options"], v["options"]);

    let hj = dir.path().join("h.json");
    let v = json(&["export", s(&tch), "--export-json", s(&hj), "--json"]);
    assert_eq!(v["json"], s(&hj));
    // Formats not asked for are null, whatever their kind; the files written beside one are named.
    assert!(v["obj"].is_null() && v["mtl"].is_null() && v["gltf"].is_null(), "{v}");
    let (obj, gltf) = (dir.path().join("g.obj"), dir.path().join("g.gltf"));
    let v = json(&[
        "export",
        s(&tch),
        "--export-obj",
        s(&obj),
        "--export-gltf",
        s(&gltf),
        "--json",
    ]);
    assert_eq!(v["obj"], s(&obj));
    assert_eq!(v["mtl"], s(&dir.path().join("g.mtl")));
    assert_eq!(v["gltf"], serde_json::json!([s(&gltf), s(&dir.path().join("g.bin"))]));
    assert!(v["json"].is_null(), "{v}");
    // `-` puts the hierarchy's JSON on stdout; with --json both would go there.
    let text = ok(&["export", s(&tch), "--export-json", "-"]).stdout;
    let h: serde_json::Value = serde_json::from_slice(&text).expect("the hierarchy's JSON on stdout");
    assert!(h["nodes"].is_array());
    fails_with(&["export", s(&tch), "--export-json", "-", "--json"], "standard output");
    // `horizon --export-json -` too, as `export`.
    let m = mesh("jacksboro-2k.obj");
    let text = ok(&[
        "horizon",
        s(&m),
        "--sectors",
        "4",
        "--subsectors",
        "1",
        "--export-json",
        "-",
        "-q",
    ])
    .stdout;
    let v: serde_json::Value = serde_json::from_slice(&text).expect("the horizons' JSON on stdout");
    // Subsectors per sector under the one name every output gives them.
    assert_eq!((&v["sectors"], &v["subsectors"]), (&4.into(), &1.into()));
    fails_with(&["horizon", s(&m), "--export-json", "-", "--json"], "standard output");
    // `build --export-json -` too: the hierarchy's JSON on stdout, instead of the report.
    let built = dir.path().join("b.tch");
    let text = ok(&["build", s(&m), "-o", s(&built), "--export-json", "-"]).stdout;
    let v: serde_json::Value = serde_json::from_slice(&text).expect("the built hierarchy's JSON on stdout");
    assert!(v["nodes"].is_array());
    assert_eq!(
        cull::Hierarchy::load(&built).expect("the .tch").nodes.len(),
        v["nodes"].as_array().map_or(0, Vec::len)
    );
    fails_with(
        &["build", s(&m), "-o", "-", "--export-json", "-"],
        "-o - and --export-json - both write to standard output",
    );
    // `eval --export-json -` and `--csv -`: the evaluation on stdout instead of the table; one of them only.
    let args = |extra: &[&'static str]| {
        let mut a = vec![
            "eval",
            s(&tch),
            "--viewpoints",
            "1",
            "--classes",
            "ground",
            "--no-safe-regions",
        ];
        a.extend_from_slice(extra);
        a
    };
    let text = ok(&args(&["--export-json", "-"])).stdout;
    let v: serde_json::Value = serde_json::from_slice(&text).expect("the evaluation's JSON on stdout");
    assert!(v["rows"].is_array());
    // No occluder budget is `null`, not 2^64 − 1 (which a JSON reader in JavaScript cannot hold exactly).
    assert!(v["options"]["safe"]["occluder_budget"].is_null(), "{}", v["options"]);
    assert_eq!(v["options"]["safe"]["work_budget"], 200_000);
    let csv = String::from_utf8(ok(&args(&["--csv", "-"])).stdout).expect("UTF-8");
    assert!(csv.starts_with("method,class,"), "{csv}");
    assert!(
        csv.lines()
            .skip(1)
            .all(|l| l.split(',').count() == csv.lines().next().map_or(0, |h| h.split(',').count())),
        "{csv}"
    );
    fails_with(
        &args(&["--csv", "-", "--export-json", "-"]),
        "--export-json - and --csv - both write to standard output",
    );
    fails_with(
        &args(&["--csv", "-", "--json"]),
        "--csv - and --json both write to standard output",
    );
    // A flag's bad value names the flag; a run with no result says what would give one.
    fails_with(&args(&["--fov", "0"]), "--fov 0: the field of view");
    fails_with(
        &["pvs", s(&tch), "--check", "1", "-q"],
        "-q hides the report, this run's only result; give --json",
    );
}

#[test]
fn failmap_takes_out() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = hierarchy(dir.path());
    let png = dir.path().join("m.png");
    ok(&["failmap", s(&tch), "--cell-size", "4000", "--out", s(&png), "-q"]);
    assert!(png.exists());
    let out = run(&["failmap", s(&tch), "--cell-size", "4000", "--output", s(&png)]);
    assert!(!out.status.success(), "--output is gone: -o/--out everywhere");
    // `--json` as everywhere: the summary as one object (and enough on its own).
    let v = json(&["failmap", s(&tch), "--cell-size", "4000", "--json"]);
    assert_eq!(v["method"], "safe");
    assert_eq!(v["cells_with_false_culls"], 0);
    assert!(v["cells_on_terrain"].as_u64().expect("cells") > 0, "{v}");
    // Without an output the text summary is the result, as for `pvs`; quietened too, there would be nothing.
    let text = String::from_utf8_lossy(&ok(&["failmap", s(&tch), "--cell-size", "4000"]).stdout).into_owned();
    assert!(text.contains("0 with false culls"), "{text}");
    fails_with(
        &["failmap", s(&tch), "--cell-size", "4000", "-q"],
        "nothing to write: -q hides the report",
    );
    // `--csv -`: the CSV alone on standard output, as `eval --csv -`.
    let csv = String::from_utf8(ok(&["failmap", s(&tch), "--cell-size", "4000", "--csv", "-"]).stdout).expect("UTF-8");
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("x,y,eye_z,false_culls,false_cull_area,occlusion_captured,triangles_drawn,visible")
    );
    assert!(lines.all(|l| l.split(',').count() == 8), "{csv}");
    fails_with(
        &["failmap", s(&tch), "--cell-size", "4000", "--csv", "-", "--json"],
        "standard output",
    );
}

/// `--cell-size` is the side of square cells wherever cells have a size (`build --grouping quadtree`, `failmap`,
/// `pvs --check`); `--cell`, its older name in `build` and `failmap`, still means the same there (and `cell` beside
/// `cell_size` in a `--config` file). `pvs --cell` is a viewcell's corners, nothing else.
#[test]
fn cell_size_has_one_name() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = hierarchy(dir.path());
    let new = json(&["failmap", s(&tch), "--cell-size", "4000", "--json"]);
    let old = json(&["failmap", s(&tch), "--cell", "4000", "--json"]);
    assert_eq!(new, old);
    let m = mesh("jacksboro-2k.obj");
    let build = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec!["build", s(&m), "--grouping", "quadtree", "-q", "-o", s(&out)];
        args.extend_from_slice(extra);
        ok(&args);
        std::fs::read(&out).expect("the built file")
    };
    let reference = build("a.tch", &["--cell-size", "2500"]);
    assert_eq!(build("b.tch", &["--cell", "2500"]), reference);
    for (i, key) in ["cell_size", "cell"].iter().enumerate() {
        let config = dir.path().join(format!("p{i}.toml"));
        std::fs::write(&config, format!("{key} = 2500.0\n")).expect("write the config");
        assert_eq!(
            build(&format!("c{i}.tch"), &["--config", s(&config)]),
            reference,
            "{key}"
        );
    }
    let depth = build("d.tch", &["--depth", "1"]);
    assert_ne!(depth, reference, "the cell size is used");
    fails_with(
        &["build", s(&m), "-o", s(&dir.path().join("e.tch")), "--cell-size", "100"],
        "--grouping quadtree",
    );
}

/// A hierarchy given where a mesh is read is named for what it is, whatever its file name; `info` describes it.
#[test]
fn a_hierarchy_is_not_taken_for_a_mesh() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = hierarchy(dir.path());
    let renamed = dir.path().join("h.dat");
    std::fs::copy(&tch, &renamed).expect("copy");
    let h = cull::Hierarchy::load(&tch).expect("loads");
    for input in [&tch, &renamed] {
        fails_with(
            &["build", s(input), "-o", s(&dir.path().join("x.tch"))],
            "is a tincull hierarchy (.tch), not a mesh",
        );
        let v = json(&["info", s(input), "--json"]);
        assert_eq!(v["triangles"], h.num_triangles());
        assert_eq!(v["vertices"], h.mesh.positions.len());
        assert_eq!(v["nodes"], h.nodes.len());
        assert_eq!(v["visibility_bytes"], h.visibility_bytes());
        assert_eq!(v["file_bytes"], std::fs::metadata(input).expect("file").len());
        assert_eq!(v["build"]["rng_seed"], h.build.rng_seed);
    }
    assert!(!dir.path().join("x.tch").exists());
    // A mesh named `.tch` is read as the mesh it is (found by a user's test: it was refused by its name), and a
    // directory so named is named as a directory.
    let obj_named_tch = dir.path().join("mesh.tch");
    std::fs::copy(mesh("jacksboro-2k.obj"), &obj_named_tch).expect("copy");
    ok(&["build", s(&obj_named_tch), "-o", s(&dir.path().join("y.tch")), "-q"]);
    let folder = dir.path().join("folder.tch");
    std::fs::create_dir(&folder).expect("mkdir");
    fails_with(
        &["build", s(&folder), "-o", s(&dir.path().join("z.tch"))],
        "folder.tch: a directory, not a file",
    );
}

/// `build --export-gltf` writes what `export --export-gltf` writes of the same hierarchy, as `--export-json` and
/// `--export-obj` do.
#[test]
fn build_exports_the_formats_export_writes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (tch, glb, gltf) = (
        dir.path().join("b.tch"),
        dir.path().join("b.glb"),
        dir.path().join("b.gltf"),
    );
    let m = mesh("jacksboro-2k.obj");
    let text = String::from_utf8(ok(&["build", s(&m), "-o", s(&tch), "--export-gltf", s(&glb)]).stdout).expect("text");
    assert!(text.contains(&format!("wrote {}", glb.display())), "{text}");
    let exported = dir.path().join("e.glb");
    ok(&["export", s(&tch), "--export-gltf", s(&exported), "-q"]);
    assert_eq!(
        std::fs::read(&glb).expect("glb"),
        std::fs::read(&exported).expect("glb")
    );
    ok(&["build", s(&m), "-o", s(&tch), "--export-gltf", s(&gltf), "-q"]);
    assert!(dir.path().join("b.bin").is_file(), "a .gltf has its .bin beside it");
    // Checked before the work, as every output.
    fails_with(
        &["build", s(&m), "-o", s(&dir.path().join("c.tch")), "--export-gltf", "-"],
        "--export-gltf -: glTF is written as a binary .glb",
    );
    assert!(!dir.path().join("c.tch").exists());
}

#[test]
fn subsectors_mean_per_sector() {
    let v = json(&[
        "horizon",
        s(&mesh("jacksboro-2k.obj")),
        "--sectors",
        "8",
        "--subsectors",
        "2",
        "--json",
        "-q",
    ]);
    assert_eq!(v["sectors"], 8);
    assert_eq!(v["subsectors"], 2);
    assert_eq!(v["total_subsectors"], 16);
}

#[test]
fn seeds_have_one_name_each() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = hierarchy(dir.path());
    let base = [
        "eval",
        s(&tch),
        "--viewpoints",
        "1",
        "--classes",
        "sky",
        "--no-per-triangle",
        "--json",
        "-q",
    ];
    let mut with_view = base.to_vec();
    with_view.extend(["--view-seed", "3"]);
    ok(&with_view);
    let mut with_rng = base.to_vec();
    with_rng.extend(["--rng-seed", "3"]);
    let out = run(&with_rng);
    assert!(
        !out.status.success(),
        "eval's viewpoint seed is --view-seed, not --rng-seed"
    );
}

#[test]
fn nonsense_values_are_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = hierarchy(dir.path());
    fails_with(&["eval", s(&tch), "--viewpoints", "0"], "--viewpoints");
    fails_with(
        &["cull", s(&tch), "--eye", "0,0,100", "--yaw", "nan", "--fov", "90"],
        "--yaw must be finite",
    );
    // A yaw at 360 degrees would change nothing.
    fails_with(
        &["cull", s(&tch), "--eye", "0,0,100", "--yaw", "30"],
        "at --fov 360 (the default) there is none to turn",
    );
    ok(&["cull", s(&tch), "--eye", "0,0,3000", "--yaw", "30", "--fov", "90"]);
    fails_with(&["cull", s(&tch), "--eye", "0,0,100", "--fov", "nan"], "--fov");
    if cfg!(feature = "viewer") {
        // Refused before any GPU work, so this runs without an adapter.
        let png = dir.path().join("x.png");
        fails_with(
            &["render", s(&tch), "-o", s(&png), "--colour", "level", "--level", "99"],
            "--level 99",
        );
        fails_with(&["render", s(&tch), "-o", s(&png), "--yaw", "nan"], "--yaw");
        fails_with(
            &["render", s(&tch), "-o", s(&png), "--compare", "--runs", "0"],
            "--runs",
        );
        fails_with(
            &["render", s(&tch), "-o", s(&png), "--view", "orbit", "--pitch", "95"],
            "--pitch must be between -89° and 89° (exclusive: the camera never looks straight up or down), got 95",
        );
        assert!(!png.exists());
    }
    let pvs = dir.path().join("x.pvs");
    fails_with(&["pvs", s(&tch), "--check", "0"], "--check must be at least 1");
    // A reversed band is refused before the hierarchy is even read (that takes seconds on a large one).
    let missing = dir.path().join("missing.tch");
    fails_with(
        &["pvs", s(&missing), "--check", "2", "--above-ground", "5,1"],
        "the height above ground 5,1 must be two finite values, the lower first",
    );
    fails_with(&["pvs", s(&tch), "--check", "2", "-o", s(&pvs)], "--check");
    fails_with(
        &["pvs", s(&tch), "--grid", "5000", "--cell-size", "50"],
        "--cell-size is for --check",
    );
    fails_with(
        &["pvs", s(&tch), "--grid", "5000", "--view-seed", "3"],
        "--view-seed is for --check",
    );
    assert!(!pvs.exists());
    let out = dir.path().join("demo");
    fails_with(
        &[
            "demo",
            s(&mesh("jacksboro-2k.obj")),
            "--out-dir",
            s(&out),
            "--viewpoints",
            "0",
        ],
        "--viewpoints",
    );
    assert!(!out.exists());
    // A render path that cannot be written is refused before any work, as the other outputs are.
    let blocked = out.join("jacksboro-2k-map.png");
    std::fs::create_dir_all(&blocked).expect("mkdir");
    fails_with(
        &["demo", s(&mesh("jacksboro-2k.obj")), "--out-dir", s(&out)],
        "jacksboro-2k-map.png",
    );
    assert_eq!(
        std::fs::read_dir(&out).expect("out").count(),
        1,
        "nothing written beside the blocked path"
    );
    let wrong = dir.path().join("s.tch");
    fails_with(
        &["synth", "-o", s(&wrong), "--vertices", "100"],
        "or a height grid (.npy)",
    );
    assert!(!wrong.exists());
    if cfg!(feature = "viewer") {
        let jpg = dir.path().join("x.jpg");
        fails_with(&["render", s(&tch), "-o", s(&jpg)], "render writes a PNG image");
        assert!(!jpg.exists());
    }
    // Every PNG output wants its name: a failure map named .jpg would be a PNG under another name.
    let jpg = dir.path().join("map.jpg");
    fails_with(
        &["failmap", s(&tch), "--cell-size", "1000", "-o", s(&jpg)],
        "-o writes a PNG image; name it .png",
    );
    assert!(!jpg.exists());
    let obj = dir.path().join("s.obj");
    fails_with(
        &["synth", "-o", s(&obj), "--vertices", "100", "--relief", "1e308"],
        "relief",
    );
    assert!(!obj.exists());
}

#[test]
fn every_command_that_reads_a_mesh_takes_keep_faces_and_dedupe() {
    let mut commands = vec!["info", "horizon", "build", "sweep", "stress", "demo"];
    if cfg!(feature = "viewer") {
        commands.extend(["render", "view"]);
    }
    for c in commands {
        let help = String::from_utf8_lossy(&ok(&[c, "--help"]).stdout).into_owned();
        assert!(
            help.contains("--keep-faces") && help.contains("--dedupe"),
            "tincull {c} lacks --keep-faces or --dedupe:\n{help}"
        );
        // And the DEM options of `tin`, so that every DEM its help lists can be read (a .png needs --spacing).
        for flag in ["--spacing", "--z-scale", "--band"] {
            assert!(help.contains(flag), "tincull {c} lacks {flag}:\n{help}");
        }
    }
    let png = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/dem_readers/gray16_4x3.png");
    fails_with(&["info", s(&png)], "--spacing dx,dy");
    let v = json(&["info", s(&png), "--spacing", "10,10", "--z-scale", "2", "--json"]);
    assert_eq!(v["dem"]["spacing"], serde_json::json!([10.0, 10.0]), "{v}");
    assert_eq!(v["dem"]["rows"], 3);
}

#[test]
fn stress_does_not_read_developer_data_by_default() {
    let help = String::from_utf8_lossy(&ok(&["stress", "--help"]).stdout).into_owned();
    assert!(!help.contains("../shared"), "{help}");
    fails_with(
        &[
            "stress",
            s(&mesh("jacksboro-2k.obj")),
            "--quick",
            "--dem-dir",
            "/nonexistent-dir",
        ],
        "/nonexistent-dir: no such folder (--dem-dir names the folder of the DEMs)",
    );
}

/// `--view-seed` seeds the viewpoints of the mesh, not of one build: two builds of one mesh (their triangles in other
/// orders) are scored from the same eyes, and a class gets the same eyes whichever other classes are asked for.
#[test]
fn a_view_seed_gives_the_same_eyes_to_every_build_of_a_mesh() {
    let dir = tempfile::tempdir().expect("tempdir");
    let default = hierarchy(dir.path());
    let other = dir.path().join("8x1.tch");
    let obj = mesh("jacksboro-2k.obj");
    ok(&[
        "build",
        s(&obj),
        "-o",
        s(&other),
        "--sectors",
        "8",
        "--subsectors",
        "1",
        "--rng-seed",
        "2",
        "-q",
    ]);
    let eyes = |tch: &Path, classes: &str| -> Vec<(String, serde_json::Value)> {
        let out = dir.path().join("e.json");
        ok(&[
            "eval",
            s(tch),
            "--viewpoints",
            "3",
            "--classes",
            classes,
            "--no-per-triangle",
            "--no-safe-regions",
            "--export-json",
            s(&out),
            "-q",
        ]);
        let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).expect("file")).expect("JSON file");
        v["viewpoints"]
            .as_array()
            .expect("viewpoints")
            .iter()
            .map(|p| (p["class"].as_str().unwrap_or("").to_string(), p["eye"].clone()))
            .collect()
    };
    let a = eyes(&default, "ground,high,sky");
    assert_eq!(a.len(), 9);
    assert_eq!(a, eyes(&other, "ground,high,sky"), "two builds of one mesh");
    let high: Vec<_> = a.iter().filter(|(c, _)| c == "high").cloned().collect();
    assert_eq!(high, eyes(&default, "high"), "high alone");
}

/// `-q` without `--json` where the printed report is the only result (no file written, nothing in the exit status)
/// is refused before any work, saying what keeps a result; where a file or the exit status is the result it runs.
#[test]
fn quiet_runs_with_no_result_are_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = hierarchy(dir.path());
    let m = mesh("jacksboro-2k.obj");
    for (args, hint) in [
        (vec!["cull", s(&tch), "--eye", "10000,12000,2000", "-q"], "give --json"),
        (
            vec!["eval", s(&tch), "-q"],
            "give --csv FILE, --export-json FILE or --json",
        ),
        (
            vec!["pvs", s(&tch), "--grid", "4000", "-q"],
            "give -o FILE.pvs or --json",
        ),
        (
            vec!["horizon", s(&m), "-q"],
            "give --export-json FILE, --verify or --json",
        ),
        (vec!["stress", s(&m), "-q"], "give --json"),
        (
            vec!["failmap", s(&tch), "--cell-size", "8000", "-q"],
            "give -o MAP.png, --csv MAP.csv or --json",
        ),
    ] {
        fails_with(
            &args,
            &format!("nothing to write: -q hides the report, this run's only result; {hint}"),
        );
    }
    let csv = dir.path().join("e.csv");
    let csv_arg = s(&csv);
    ok(&[
        "eval",
        s(&tch),
        "--viewpoints",
        "1",
        "--no-safe-regions",
        "--csv",
        csv_arg,
        "-q",
    ]);
    assert!(csv.is_file());
    ok(&[
        "horizon",
        s(&m),
        "--sectors",
        "4",
        "--subsectors",
        "1",
        "--verify",
        "-q",
    ]);
    // A quiet info prints its warnings only: they are the result.
    ok(&["info", s(&tch), "-q"]);
}
