//! End-to-end tests of `tincull tiles plan|build|merge` and of `synth` writing a height grid.

mod common;

use common::{fails_with, json, mesh, ok, s};

/// A small synthetic grid and its plan of 3 x 3 tiles in `dir`.
fn planned(dir: &std::path::Path) -> std::path::PathBuf {
    let npy = dir.join("t.npy");
    let v = json(&[
        "synth",
        "--vertices",
        "3600",
        "--rng-seed",
        "2",
        "-o",
        s(&npy),
        "--json",
    ]);
    assert_eq!((v["rows"].as_u64(), v["cols"].as_u64()), (Some(60), Some(60)));
    assert!(dir.join("t.json").is_file(), "the sidecar is written beside the grid");
    let plan = dir.join("plan.json");
    let v = json(&[
        "tiles",
        "plan",
        s(&npy),
        "-o",
        s(&plan),
        "--tile",
        "20",
        "--halo",
        "4",
        "--max-error",
        "0.5",
        "--sectors",
        "8",
        "--subsectors",
        "2",
        "--json",
    ]);
    assert_eq!(v["tiles"].as_u64(), Some(9));
    plan
}

/// A synthetic grid of 30 x 30 samples, `t.npy` in `dir`.
fn small_grid(dir: &std::path::Path) -> std::path::PathBuf {
    let npy = dir.join("t.npy");
    ok(&["synth", "--vertices", "900", "--rng-seed", "2", "-o", s(&npy), "-q"]);
    npy
}

/// The tiles' output files named by a plan, resolved.
fn tile_outputs(plan: &std::path::Path) -> Vec<std::path::PathBuf> {
    let text = std::fs::read_to_string(plan).expect("plan");
    let v: serde_json::Value = serde_json::from_str(&text).expect("plan JSON");
    let dir = plan.parent().expect("folder");
    v["tiles"]
        .as_array()
        .expect("tiles")
        .iter()
        .map(|t| dir.join(t["output"].as_str().expect("output")))
        .collect()
}

#[test]
fn tiles_of_an_earlier_plan_are_never_merged() {
    let dir = tempfile::tempdir().expect("tempdir");
    let plan = planned(dir.path());
    ok(&["tiles", "build", s(&plan), "--all", "-q"]);
    let before = tile_outputs(&plan);
    // Planning again to the same file, the same grid with other options: the built tiles are not this plan's.
    let replan = || {
        ok(&[
            "tiles",
            "plan",
            s(&dir.path().join("t.npy")),
            "-o",
            s(&plan),
            "--tile",
            "20",
            "--halo",
            "2",
            "-q",
        ])
    };
    // The earlier plan's tiles stay (the user's to remove), with a warning.
    let warned = String::from_utf8_lossy(&replan().stderr).into_owned();
    assert!(
        warned.contains(&format!("{} files of an earlier plan remain", before.len())),
        "{warned}"
    );
    assert!(before.iter().all(|p| p.is_file()));
    let after = tile_outputs(&plan);
    assert_eq!(after.len(), before.len());
    assert!(before.iter().zip(&after).all(|(a, b)| a != b), "other names");
    fails_with(
        &["tiles", "merge", s(&plan), "-o", s(&dir.path().join("m.tch"))],
        "tile 0 has not been built",
    );
    // And the same plan again names the same files: what was built stays usable.
    ok(&["tiles", "build", s(&plan), "--all", "-q"]);
    replan();
    assert_eq!(tile_outputs(&plan), after);
    ok(&["tiles", "merge", s(&plan), "-o", s(&dir.path().join("m.tch")), "-q"]);
}

#[test]
fn all_tiles_or_one_by_one_merge_to_the_same_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let plan = planned(dir.path());
    let v = json(&["tiles", "build", s(&plan), "--all", "--jobs", "2", "--json"]);
    assert_eq!(v["tiles"].as_array().map(Vec::len), Some(9));
    let a = dir.path().join("a.tch");
    let m = json(&["tiles", "merge", s(&plan), "-o", s(&a), "--json"]);
    assert!(m["triangles"].as_u64().expect("triangles") > 3000);
    // One tile at a time, single-threaded: the same bytes.
    for i in 0..9 {
        ok(&[
            "tiles",
            "build",
            s(&plan),
            "--tile",
            &i.to_string(),
            "--jobs",
            "1",
            "-q",
        ]);
    }
    // More jobs than tiles: one thread per tile to build, whatever was asked (not 100,000 idle threads).
    let v = json(&[
        "tiles",
        "build",
        s(&plan),
        "--tile",
        "0",
        "--tile",
        "1",
        "--jobs",
        "100000",
        "--json",
    ]);
    assert_eq!(v["threads"].as_u64(), Some(2));
    // One tile: its build uses the threads asked for, up to the cores.
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as u64;
    let v = json(&["tiles", "build", s(&plan), "--tile", "2", "--jobs", "2", "--json"]);
    assert_eq!(v["threads"].as_u64(), Some(2.min(cores)));
    let v = json(&["tiles", "build", s(&plan), "--tile", "2", "--jobs", "100000", "--json"]);
    assert_eq!(v["threads"].as_u64(), Some(cores));
    let b = dir.path().join("b.tch");
    ok(&["tiles", "merge", s(&plan), "-o", s(&b), "-q"]);
    assert_eq!(std::fs::read(&a).expect("a"), std::fs::read(&b).expect("b"));
    // The merged file is an ordinary hierarchy: cull and eval read it.
    let e = json(&[
        "eval",
        s(&a),
        "--viewpoints",
        "2",
        "--no-per-triangle",
        "--no-safe-regions",
        "--json",
        "-q",
    ]);
    let safe = e["rows"]
        .as_array()
        .expect("rows")
        .iter()
        .find(|r| r["method"] == "safe" && r["class"] == "all")
        .expect("safe row")
        .clone();
    assert_eq!(safe["summary"]["viewpoints_with_false_culls"].as_u64(), Some(0));
}

#[test]
fn errors_name_what_is_wrong() {
    let dir = tempfile::tempdir().expect("tempdir");
    let plan = planned(dir.path());
    fails_with(
        &["tiles", "merge", s(&plan), "-o", s(&dir.path().join("m.tch"))],
        "tile 0 has not been built",
    );
    // With no tile built, the hint builds them all.
    fails_with(
        &["tiles", "merge", s(&plan), "-o", s(&dir.path().join("m.tch"))],
        &format!("run `tincull tiles build {} --all`", plan.display()),
    );
    // A plan named like its own tiles' folder (`y.tiles` would hold the tiles of `y.tiles`) is refused before any
    // work, leaving nothing behind (it said "is a directory" of a path where nothing was).
    let npy = dir.path().join("t.npy");
    let clash = dir.path().join("y.tiles");
    fails_with(
        &["tiles", "plan", s(&npy), "-o", s(&clash), "--tile", "20"],
        "which would be this very path; name the plan otherwise",
    );
    assert!(!clash.exists());
    // A tile's file that is not a hierarchy: the merge names the tile and its file, and writes nothing.
    let outputs = tile_outputs(&plan);
    for path in &outputs {
        std::fs::write(path, b"not a hierarchy").expect("write");
    }
    let merged = dir.path().join("m.tch");
    let first = outputs[0].file_name().expect("name").to_string_lossy().into_owned();
    assert!(first.starts_with("tile-00000-") && first.ends_with(".tch"), "{first}");
    fails_with(&["tiles", "merge", s(&plan), "-o", s(&merged)], &first);
    assert!(!merged.exists(), "a failed merge leaves no file");
    fails_with(&["tiles", "build", s(&plan), "--tile", "9"], "tile 9 does not exist");
    // Plan options out of range name their option.
    let grid = dir.path().join("t.npy");
    let other = dir.path().join("other.json");
    for (flag, value, said) in [
        ("--tile", "1", "--tile 1: the tile side must be at least 2"),
        (
            "--far-block",
            "0",
            "--far-block 0: the far field's blocks must be at least 1",
        ),
        (
            "--max-error",
            "inf",
            "--max-error inf: the error bound must be 0 or between 1e-9 and 1e9 m",
        ),
        // Finite, but the halo and far field lowered by it would leave every height stage's range.
        (
            "--max-error",
            "1e300",
            "--max-error 1e300: the error bound must be 0 or between",
        ),
    ] {
        fails_with(&["tiles", "plan", s(&grid), "-o", s(&other), flag, value], said);
    }
    assert!(!other.exists(), "a refused plan writes nothing");
    // A tile given twice is built once, and the tiles in index order.
    let v = json(&[
        "tiles",
        "build",
        s(&plan),
        "--tile",
        "4",
        "--tile",
        "1",
        "--tile",
        "4",
        "--json",
    ]);
    let built: Vec<u64> = v["tiles"]
        .as_array()
        .expect("tiles")
        .iter()
        .map(|t| t["index"].as_u64().expect("index"))
        .collect();
    assert_eq!(built, [1, 4]);
    fails_with(&["tiles", "build", s(&plan)], "--tile");
    // Each DEM tile reads its own far-field file, written beside the plan; damaged or missing, it is named.
    let far = dir.path().join("plan.tiles").join("far-00004.bin");
    let bytes = std::fs::read(&far).expect("the plan writes every tile's far field");
    std::fs::write(&far, &bytes[..bytes.len() - 3]).expect("truncate");
    fails_with(
        &["tiles", "build", s(&plan), "--tile", "4"],
        "far-00004.bin: not a valid far field file: truncated",
    );
    let mut flipped = bytes.clone();
    *flipped.last_mut().expect("bytes") ^= 1;
    std::fs::write(&far, &flipped).expect("flip");
    fails_with(&["tiles", "build", s(&plan), "--tile", "4"], "checksum");
    std::fs::remove_file(&far).expect("remove");
    fails_with(
        &["tiles", "build", s(&plan), "--tile", "4"],
        "far-00004.bin is missing (the plan writes it beside itself): plan again",
    );
    // With the whole folder of far fields and tiles gone, a job says what is missing and makes no empty folder.
    let tiles_dir = dir.path().join("plan.tiles");
    std::fs::remove_dir_all(&tiles_dir).expect("remove the folder");
    fails_with(&["tiles", "build", s(&plan), "--tile", "0"], "far-00000.bin is missing");
    assert!(!tiles_dir.exists(), "the job does not make the folder again");
    fails_with(
        &["tiles", "plan", s(&dir.path().join("t.npy")), "-o", s(dir.path())],
        "directory",
    );
    // A file where the plan's tiles folder goes: refused before the work, and left as it was.
    std::fs::write(dir.path().join("p2.tiles"), "mine").expect("a file");
    fails_with(
        &[
            "tiles",
            "plan",
            s(&dir.path().join("t.npy")),
            "-o",
            s(&dir.path().join("p2.json")),
        ],
        "something that is not a folder is there",
    );
    assert!(!dir.path().join("p2.json").exists());
    assert_eq!(std::fs::read(dir.path().join("p2.tiles")).expect("kept"), b"mine");
    fails_with(
        &[
            "tiles",
            "plan",
            s(&dir.path().join("t.npy")),
            "-o",
            s(&plan),
            "--halo",
            "2.5",
        ],
        "\"2.5\" is not a whole number",
    );
    // The plan of t.npy named t.json would replace the grid's sidecar, which holds its spacing: refused.
    let sidecar = std::fs::read(dir.path().join("t.json")).expect("sidecar");
    fails_with(
        &[
            "tiles",
            "plan",
            s(&dir.path().join("t.npy")),
            "-o",
            s(&dir.path().join("t.json")),
        ],
        "the same file as the input",
    );
    assert_eq!(std::fs::read(dir.path().join("t.json")).expect("sidecar"), sidecar);
    std::fs::write(dir.path().join("bad.json"), "[1, 2]").expect("write");
    fails_with(
        &["tiles", "build", s(&dir.path().join("bad.json")), "--all"],
        "not a tincull tile plan",
    );
}

/// Every tile's output is checked before the first tile is built (tiles 0 to 2 used to be built and written before
/// tile 3's output was found to be a folder).
#[test]
fn every_tile_output_is_checked_before_any_tile_is_built() {
    let dir = tempfile::tempdir().expect("tempdir");
    let plan = planned(dir.path());
    let outputs = tile_outputs(&plan);
    std::fs::create_dir_all(&outputs[3]).expect("a folder in tile 3's place");
    fails_with(
        &["tiles", "build", s(&plan), "--all", "--jobs", "1"],
        "tile 3: its output",
    );
    assert!(outputs.iter().all(|p| !p.is_file()), "no tile built");
}

#[test]
fn a_mesh_is_cut_into_parts_and_merges_back_whole() {
    let dir = tempfile::tempdir().expect("tempdir");
    let plan = dir.path().join("mesh.json");
    let v = json(&[
        "tiles",
        "plan",
        s(&mesh("jacksboro-2k.obj")),
        "-o",
        s(&plan),
        "--tile",
        "10000",
        "--halo",
        "1000",
        "--far-block",
        "1000",
        "--sectors",
        "8",
        "--subsectors",
        "2",
        "--json",
    ]);
    assert_eq!(v["tiles"].as_u64(), Some(12));
    assert!(dir.path().join("mesh.tiles/part-00000.bin").is_file());
    ok(&["tiles", "build", s(&plan), "--all", "-q"]);
    let m = json(&["tiles", "merge", s(&plan), "-o", s(&dir.path().join("m.tch")), "--json"]);
    let info = json(&["info", s(&mesh("jacksboro-2k.obj")), "--json"]);
    assert_eq!(m["vertices"], info["vertices"]);
    assert_eq!(m["triangles"], info["triangles"]);
    // Another tile's part in a tile's place: refused by its digest, naming the file.
    std::fs::copy(
        dir.path().join("mesh.tiles/part-00004.bin"),
        dir.path().join("mesh.tiles/part-00003.bin"),
    )
    .expect("copy");
    fails_with(
        &["tiles", "build", s(&plan), "--tile", "3"],
        "part-00003.bin: not tile 3's file as the plan wrote it",
    );
    std::fs::remove_file(dir.path().join("mesh.tiles/part-00003.bin")).expect("remove");
    fails_with(&["tiles", "build", s(&plan), "--tile", "3"], "part-00003.bin");
    // Unset sizes are a DEM's in mean vertex spacings (about 690 m here): 512 of them hold this 30 km mesh in one
    // tile, with a 16-spacing halo, as a DEM of 2,000 samples would be planned.
    let out = ok(&[
        "tiles",
        "plan",
        s(&mesh("jacksboro-2k.obj")),
        "-o",
        s(&dir.path().join("d.json")),
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("1 tile (of a 1 x 1 grid of 353792 m squares), halo 11056 m"),
        "{text}"
    );
}

/// `tiles plan MESH` resolves vertices that share x,y as every command that reads a mesh: refused by default with an
/// error naming them, the highest kept with `--dedupe keep-highest`.
#[test]
fn a_mesh_plan_takes_dedupe() {
    let dir = tempfile::tempdir().expect("tempdir");
    let text = std::fs::read_to_string(mesh("jacksboro-2k.obj")).expect("mesh");
    let first = text.lines().find(|l| l.starts_with("v ")).expect("a vertex");
    let f: Vec<f64> = first[2..]
        .split_whitespace()
        .map(|x| x.parse().expect("number"))
        .collect();
    let obj = dir.path().join("dup.obj");
    std::fs::write(&obj, format!("{text}v {} {} {}\n", f[0], f[1], f[2] - 5.0)).expect("write");
    let plan = dir.path().join("dup.json");
    let base = [
        "tiles",
        "plan",
        s(&obj),
        "-o",
        s(&plan),
        "--tile",
        "10000",
        "--halo",
        "1000",
        "-q",
    ];
    fails_with(&base, "--dedupe");
    assert!(!plan.exists(), "no plan after an error");
    // A DEM's simplification bound means nothing to a mesh's tiles: refused, not ignored.
    fails_with(
        &[&base[..], &["--dedupe", "keep-highest", "--max-error", "5"]].concat(),
        "--max-error 5 applies to a DEM",
    );
    let v = json(&[&base[..], &["--dedupe", "keep-highest", "--json"]].concat());
    assert!(v["tiles"].as_u64().expect("tiles") > 1, "{v}");
    ok(&["tiles", "build", s(&plan), "--all", "-q"]);
    let m = json(&["tiles", "merge", s(&plan), "-o", s(&dir.path().join("m.tch")), "--json"]);
    let info = json(&["info", s(&mesh("jacksboro-2k.obj")), "--json"]);
    assert_eq!(m["vertices"], info["vertices"], "the lower duplicate is dropped");
}

#[test]
#[cfg(unix)]
fn a_plan_of_many_tiles_needs_few_open_files() {
    use std::os::unix::process::CommandExt;
    let dir = tempfile::tempdir().expect("tempdir");
    let npy = dir.path().join("t.npy");
    ok(&["synth", "--vertices", "3600", "--rng-seed", "2", "-o", s(&npy), "-q"]);
    let plan = dir.path().join("plan.json");
    // 144 tiles (each with its far-field file) under a limit of 32 open files: every file is written, synced and
    // closed before the next one, and all are renamed together at the end.
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_tincull"));
    cmd.args([
        "tiles",
        "plan",
        s(&npy),
        "-o",
        s(&plan),
        "--tile",
        "5",
        "--halo",
        "2",
        "--json",
    ]);
    // SAFETY: setrlimit(2) is async-signal-safe; it only lowers this child's own limit before exec.
    unsafe {
        cmd.pre_exec(|| {
            let limit = libc::rlimit {
                rlim_cur: 32,
                rlim_max: 32,
            };
            if libc::setrlimit(libc::RLIMIT_NOFILE, &limit) == 0 {
                Ok(())
            } else {
                Err(std::io::Error::last_os_error())
            }
        });
    }
    let out = cmd.output().expect("the binary runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(v["tiles"].as_u64(), Some(144));
    let far = std::fs::read_dir(dir.path().join("plan.tiles"))
        .expect("tiles folder")
        .count();
    assert_eq!(far, 144, "one far-field file per tile");
}

/// A halo wider than the grid is the whole grid (it overflowed past the end of the grid, and the job panicked).
#[test]
fn a_halo_wider_than_the_grid_is_the_whole_grid() {
    let dir = tempfile::tempdir().expect("tempdir");
    let npy = small_grid(dir.path());
    let plan = dir.path().join("plan.json");
    let v = json(&[
        "tiles",
        "plan",
        s(&npy),
        "-o",
        s(&plan),
        "--tile",
        "10",
        "--halo",
        &usize::MAX.to_string(),
        "--sectors",
        "8",
        "--subsectors",
        "1",
        "--json",
    ]);
    assert_eq!(v["tiles"].as_u64(), Some(9));
    ok(&["tiles", "build", s(&plan), "--all", "-q"]);
    ok(&["tiles", "merge", s(&plan), "-o", s(&dir.path().join("m.tch")), "-q"]);
}

/// A plan edited by hand or another file given as a plan: refused with the file and the tile named, never a hang (a
/// tile far out in the tile grid looped the merge's quadtree forever) or a merge that cannot say what is wrong.
#[test]
fn a_malformed_plan_is_refused_naming_the_tile() {
    let dir = tempfile::tempdir().expect("tempdir");
    let plan = planned(dir.path());
    ok(&["tiles", "build", s(&plan), "--all", "-q"]);
    let original: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&plan).expect("plan")).expect("plan JSON");
    let edited = dir.path().join("edited.json");
    let merged = dir.path().join("m.tch");
    let edit = |change: &dyn Fn(&mut serde_json::Value)| {
        let mut v = original.clone();
        change(&mut v);
        std::fs::write(&edited, serde_json::to_string(&v).expect("JSON")).expect("write");
    };
    edit(&|v| v["tiles"][0]["tile_row"] = serde_json::json!(1u64 << 63));
    fails_with(
        &["tiles", "merge", s(&edited), "-o", s(&merged)],
        "tile 0 is at row 9223372036854775808",
    );
    edit(&|v| {
        v["tiles"][1]["tile_row"] = serde_json::json!(0);
        v["tiles"][1]["tile_col"] = serde_json::json!(0);
    });
    fails_with(
        &["tiles", "merge", s(&edited), "-o", s(&merged)],
        "as an earlier tile is",
    );
    fails_with(&["tiles", "build", s(&edited), "--tile", "0"], "edited.json");
    // A tile that does not fit its plan is refused with the reason.
    edit(&|v| v["tiles"][1]["rows"] = serde_json::json!([5, 2]));
    fails_with(
        &["tiles", "build", s(&edited), "--tile", "0"],
        "tile 1 is malformed: its rows [5, 2] and columns",
    );
    edit(&|v| v["tiles"][0]["index"] = serde_json::json!(3));
    fails_with(
        &["tiles", "merge", s(&edited), "-o", s(&merged)],
        "tile 0 is malformed: its index is 3",
    );
    // A key no plan has (a typo in a hand edit) is named, as a `--config` file's is.
    edit(&|v| v["bogus"] = serde_json::json!(1));
    fails_with(&["tiles", "build", s(&edited), "--tile", "0"], "unknown field `bogus`");
    edit(&|v| v["tiles"][0]["outptu"] = serde_json::json!("x.tch"));
    fails_with(&["tiles", "build", s(&edited), "--tile", "0"], "unknown field `outptu`");
    edit(&|v| v["version"] = serde_json::json!(99));
    fails_with(
        &["tiles", "build", s(&edited), "--tile", "0"],
        "edited.json: a tile plan of version 99, made by another tincull; this one reads version 3: plan again",
    );
    // Any other edit of a sealed plan (its options, a tile's output) no longer matches its tiles' names: refused,
    // so that tiles built under two sets of options are never merged (they were merged with cracks between them).
    for change in [
        &(|v: &mut serde_json::Value| v["options"]["max_error"] = serde_json::json!(5.0))
            as &dyn Fn(&mut serde_json::Value),
        &|v: &mut serde_json::Value| v["tiles"][0]["output"] = serde_json::json!("t.npy"),
    ] {
        edit(change);
        for args in [
            vec!["tiles", "build", s(&edited), "--tile", "0"],
            vec!["tiles", "merge", s(&edited), "-o", s(&merged)],
        ] {
            fails_with(
                &args,
                "edited.json: the plan's content does not match the names `tincull tiles plan` gave its tiles",
            );
        }
    }
    // A plan without its tiles' file digests (made before they were kept) is not checked for its seal: what a job
    // writes is still checked on its own. A tile's output that names what the job reads (the DEM, a far-field
    // file): refused, the file untouched (the DEM was replaced by the tile's hierarchy).
    let edit = |change: &dyn Fn(&mut serde_json::Value)| {
        edit(&|v| {
            for t in v["tiles"].as_array_mut().expect("tiles") {
                t.as_object_mut().expect("tile").remove("file_digest");
            }
            change(v);
        })
    };
    let dem = dir.path().join("t.npy");
    let dem_bytes = std::fs::read(&dem).expect("DEM");
    edit(&|v| v["tiles"][0]["output"] = serde_json::json!("t.npy"));
    fails_with(
        &["tiles", "build", s(&edited), "--tile", "0"],
        "the same file as the input",
    );
    assert_eq!(std::fs::read(&dem).expect("DEM"), dem_bytes, "the DEM is untouched");
    edit(&|v| v["tiles"][0]["output"] = serde_json::json!("t.json"));
    fails_with(
        &["tiles", "build", s(&edited), "--tile", "0"],
        "the same file as the input",
    );
    edit(&|v| v["tiles"][1]["output"] = v["tiles"][1]["far"].clone());
    fails_with(&["tiles", "build", s(&edited), "--tile", "1"], "far-00001.bin");
    edit(&|v| v["tiles"][2]["output"] = serde_json::json!("edited.json"));
    fails_with(&["tiles", "build", s(&edited), "--tile", "2"], "tile 2: its output");
    edit(&|v| v["tiles"] = serde_json::json!([]));
    fails_with(&["tiles", "build", s(&edited), "--all"], "it has no tiles");
    fails_with(&["tiles", "merge", s(&edited), "-o", s(&merged)], "it has no tiles");
    edit(&|v| v["options"]["max_error"] = serde_json::json!(-1.0));
    fails_with(
        &["tiles", "build", s(&edited), "--all"],
        "edited.json: not a tincull tile plan",
    );
    assert!(!merged.exists(), "no merge of a malformed plan");
    // Another tile's far-field file in a tile's place: refused by its digest, naming the file (it was read, and
    // failed later as "not a height field").
    let far = |i: usize| dir.path().join(original["tiles"][i]["far"].as_str().expect("far"));
    std::fs::copy(far(1), far(0)).expect("copy");
    fails_with(
        &["tiles", "build", s(&plan), "--tile", "0"],
        "far-00000.bin: not tile 0's file as the plan wrote it",
    );
    // A hierarchy given for the plan: said to be binary, not "stream did not contain valid UTF-8".
    let tch = tile_outputs(&plan)[0].clone();
    fails_with(
        &["tiles", "merge", s(&tch), "-o", s(&merged)],
        "a binary file, not the JSON",
    );
    fails_with(&["tiles", "build", s(&tch), "--all"], "not a tincull tile plan");
}

/// A tile's output in folders that are missing: `tiles build` makes them, and removes them again when the tile
/// fails (they were left behind, empty, by `create_dir_all`).
#[test]
fn folders_made_for_a_failed_tile_are_removed() {
    let dir = tempfile::tempdir().expect("tempdir");
    let plan = planned(dir.path());
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&plan).expect("plan")).expect("JSON");
    // Without the digests (a plan made before they were kept) an edited output is taken as it is. Tile 0 in a
    // folder inside tile 1's, both missing.
    for t in v["tiles"].as_array_mut().expect("tiles") {
        t.as_object_mut().expect("tile").remove("file_digest");
    }
    v["tiles"][0]["output"] = serde_json::json!("new/sub/t0.tch");
    v["tiles"][1]["output"] = serde_json::json!("new/t1.tch");
    let edited = dir.path().join("edited.json");
    std::fs::write(&edited, serde_json::to_string(&v).expect("JSON")).expect("write");
    let far = |i: usize| dir.path().join(v["tiles"][i]["far"].as_str().expect("far"));
    let far_bytes = [0, 1].map(|i| std::fs::read(far(i)).expect("far field"));
    for (i, bytes) in far_bytes.iter().enumerate() {
        std::fs::write(far(i), &bytes[..bytes.len() / 2]).expect("truncate");
    }
    for tiles in [&["--tile", "0"][..], &["--tile", "1", "--tile", "0"]] {
        fails_with(&[&["tiles", "build", s(&edited)][..], tiles].concat(), "far field");
        assert!(
            !dir.path().join("new").exists(),
            "the folders made for {tiles:?} are removed"
        );
    }
    for (i, bytes) in far_bytes.iter().enumerate() {
        std::fs::write(far(i), bytes).expect("restore");
    }
    ok(&["tiles", "build", s(&edited), "--tile", "0", "--tile", "1", "-q"]);
    for built in ["new/sub/t0.tch", "new/t1.tch"] {
        assert!(dir.path().join(built).is_file(), "{built} built into the folders made");
    }
}

/// A mesh's plan keeps a list per square of its tiles and of its far field's blocks: cut into too many, it is
/// refused before the lists are made (a 2 m tile of a 30 km mesh asked for gigabytes and aborted).
#[test]
fn a_mesh_cut_into_too_many_squares_is_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let plan = dir.path().join("mesh.json");
    let m = mesh("jacksboro-2k.obj");
    fails_with(
        &["tiles", "plan", s(&m), "-o", s(&plan), "--tile", "2"],
        "give a larger --tile",
    );
    fails_with(
        &["tiles", "plan", s(&m), "-o", s(&plan), "--far-block", "1"],
        "give a larger --far-block",
    );
    assert!(
        !plan.exists() && !dir.path().join("mesh.tiles").exists(),
        "nothing written"
    );
}

/// Writes an `n` × `n` ESRI ASCII grid of `cell` m with `sample(row, column)` (`None`: a void, -9999), heights to the
/// centimetre.
fn write_asc(path: &std::path::Path, n: usize, cell: f64, sample: impl Fn(usize, usize) -> Option<f64>) {
    let mut text = format!("ncols {n}\nnrows {n}\nxllcorner 0\nyllcorner 0\ncellsize {cell}\nNODATA_value -9999\n");
    for r in 0..n {
        let row: Vec<String> = (0..n)
            .map(|c| sample(r, c).map_or_else(|| "-9999".to_string(), |z| format!("{z:.2}")))
            .collect();
        text.push_str(&row.join(" "));
        text.push('\n');
    }
    std::fs::write(path, text).expect("grid");
}

/// A tile whose samples lie in one row (a line of samples amid voids) cannot be triangulated alone: the plan leaves
/// it out and says so, counting its samples, rather than calling it a tile without terrain (found by a user's test).
#[test]
fn a_tile_of_one_row_of_samples_is_left_out_with_a_warning() {
    let dir = tempfile::tempdir().expect("tempdir");
    let asc = dir.path().join("line.asc");
    write_asc(&asc, 21, 10.0, |i, j| {
        (j <= 10 || i == 15).then(|| ((i * 7 + j * 13) % 50 + 1) as f64)
    });
    let plan = dir.path().join("p.json");
    let args = [
        "tiles",
        "plan",
        s(&asc),
        "-o",
        s(&plan),
        "--tile",
        "5",
        "--max-error",
        "0",
    ];
    let v = json(&[&args[..], &["--json"]].concat());
    assert_eq!(
        (v["tiles"].as_u64(), v["void_tiles"].as_u64(), v["line_tiles"].as_u64()),
        (Some(10), Some(2), Some(4)),
        "{v}"
    );
    assert!(v["line_samples"].as_u64().is_some_and(|n| n > 0), "{v}");
    let out = ok(&args);
    let (text, warning) = (
        String::from_utf8(out.stdout).expect("text"),
        String::from_utf8(out.stderr).expect("text"),
    );
    assert!(text.contains("2 tiles of voids left out"), "{text}");
    assert!(
        warning.contains("4 tiles left out") && warning.contains("lie on one line"),
        "{warning}"
    );
}

/// A tile whose samples are all voids holds no terrain: the plan leaves it out (its job could never build), and the
/// other tiles build and merge into the terrain that `build` makes of the whole grid (the same triangles count).
#[test]
fn a_tile_of_voids_is_left_out_of_the_plan() {
    let dir = tempfile::tempdir().expect("tempdir");
    let asc = dir.path().join("v.asc");
    write_asc(&asc, 60, 30.0, |r, c| {
        (r >= 30 || c >= 30).then(|| 100.0 + 20.0 * ((r as f64) / 7.0).sin() * ((c as f64) / 5.0).cos())
    });
    let plan = dir.path().join("p.json");
    let args = [
        "tiles",
        "plan",
        s(&asc),
        "-o",
        s(&plan),
        "--tile",
        "28",
        "--max-error",
        "0.5",
    ];
    let v = json(&[&args[..], &["--json"]].concat());
    assert_eq!(
        (v["tiles"].as_u64(), v["void_tiles"].as_u64()),
        (Some(8), Some(1)),
        "{v}"
    );
    let text = String::from_utf8(ok(&args).stdout).expect("text");
    assert!(text.contains("8 tiles (3 x 3, 1 tile of voids left out)"), "{text}");
    let built = json(&["tiles", "build", s(&plan), "--all", "--json", "-q"]);
    let far = built["tiles"].as_array().expect("tiles").iter();
    assert_eq!(
        far.map(|t| t["far_points"].as_u64().expect("far_points")).max(),
        v["far_points_max"].as_u64(),
        "the plan's far_points_max is the most far points of a tile: {built}"
    );
    let merged = dir.path().join("m.tch");
    ok(&["tiles", "merge", s(&plan), "-o", s(&merged), "-q"]);
    let info = json(&["info", s(&merged), "--json"]);
    assert!(info["triangles"].as_u64().is_some_and(|t| t > 1000), "{info}");

    // Build parameters that every tile job would refuse are refused by the plan, once.
    let bad = dir.path().join("bad.json");
    fails_with(
        &[
            "tiles",
            "plan",
            s(&asc),
            "-o",
            s(&bad),
            "--tile",
            "28",
            "--sectors",
            "2",
        ],
        "at least 4 sectors",
    );
    assert!(!bad.exists());
}

/// `synth -o NAME.npy` writes the sidecar `NAME.json` beside the grid: it replaces an earlier sidecar, but not another
/// JSON file there (a tile plan once was), which it refuses before writing anything.
#[test]
fn synth_never_replaces_a_json_that_is_not_a_sidecar() {
    let dir = tempfile::tempdir().expect("tempdir");
    let npy = dir.path().join("plan.npy");
    let plan = dir.path().join("plan.json");
    std::fs::write(&plan, "{\"version\": 3, \"tiles\": []}").expect("a plan");
    fails_with(&["synth", "--vertices", "400", "-o", s(&npy)], "is not one");
    assert!(!npy.exists());
    assert_eq!(
        std::fs::read_to_string(&plan).expect("plan"),
        "{\"version\": 3, \"tiles\": []}"
    );
    std::fs::remove_file(&plan).expect("removed");
    ok(&["synth", "--vertices", "400", "-o", s(&npy), "-q"]);
    ok(&["synth", "--vertices", "900", "-o", s(&npy), "-q"]);
    assert!(std::fs::read_to_string(&plan).expect("sidecar").contains("\"rows\":30"));
}

/// `tiles plan --grouping quadtree --no-regions`: no far-field files, tiles that read no halo and sweep no horizon,
/// and a merged file whose safe culls are those of the same plan with regions; what such a plan cannot honour is
/// refused before anything is written.
#[test]
fn a_plan_without_regions_culls_as_the_one_with_them() {
    let dir = tempfile::tempdir().expect("tempdir");
    let npy = dir.path().join("t.npy");
    ok(&["synth", "--vertices", "3600", "--rng-seed", "4", "-o", s(&npy), "-q"]);
    let plan = |name: &str, extra: &[&str]| {
        let path = dir.path().join(format!("{name}.json"));
        let mut args = vec![
            "tiles",
            "plan",
            s(&npy),
            "-o",
            s(&path),
            "--tile",
            "20",
            "--max-error",
            "0.5",
            "--grouping",
            "quadtree",
            "--json",
        ];
        args.extend(extra);
        (json(&args), path)
    };
    let (v, bare) = plan("bare", &["--no-regions"]);
    assert_eq!((v["tiles"].as_u64(), v["far_blocks"].as_u64()), (Some(9), Some(0)));
    let files: Vec<String> = std::fs::read_dir(dir.path().join("bare.tiles"))
        .expect("tiles folder")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        files.is_empty(),
        "a plan without regions writes no far field: {files:?}"
    );
    let (_, with) = plan("with", &["--halo", "0", "--sectors", "8", "--subsectors", "2"]);
    let built = json(&["tiles", "build", s(&bare), "--all", "--json"]);
    for t in built["tiles"].as_array().expect("tiles") {
        assert_eq!(
            (t["halo_points"].as_u64(), t["far_points"].as_u64()),
            (Some(0), Some(0))
        );
        assert_eq!(t["build"]["without_regions"], true);
        assert_eq!(t["build"]["horizon_seconds"].as_f64(), Some(0.0));
    }
    ok(&["tiles", "build", s(&with), "--all", "-q"]);
    let (bare_tch, with_tch) = (dir.path().join("bare.tch"), dir.path().join("with.tch"));
    ok(&["tiles", "merge", s(&bare), "-o", s(&bare_tch), "-q"]);
    ok(&["tiles", "merge", s(&with), "-o", s(&with_tch), "-q"]);
    let info = String::from_utf8(ok(&["info", s(&bare_tch)]).stdout).expect("UTF-8");
    assert!(info.contains("regions       none (built with --no-regions"), "{info}");
    // Eyes 2, 20 and 200 m above the ground across the terrain.
    let bbox = &json(&["info", s(&with_tch), "--json"])["bbox"];
    let at = |k: usize, f: f64| {
        let (lo, hi) = (
            bbox["min"][k].as_f64().expect("min"),
            bbox["max"][k].as_f64().expect("max"),
        );
        lo + f * (hi - lo)
    };
    let eyes = dir.path().join("eyes.txt");
    let lines: Vec<String> = [(0.3, 0.4, 2), (0.7, 0.2, 20), (0.5, 0.8, 200), (0.1, 0.9, 2)]
        .iter()
        .map(|&(fx, fy, h)| format!("{},{},{h}", at(0, fx), at(1, fy)))
        .collect();
    std::fs::write(&eyes, lines.join("\n")).expect("eyes");
    let ranges = |file: &std::path::Path| {
        let out = ok(&["cull", s(file), "--eyes", s(&eyes), "--above-ground", "--json"]);
        String::from_utf8(out.stdout)
            .expect("UTF-8")
            .lines()
            .map(|l| serde_json::from_str::<serde_json::Value>(l).expect("JSON line")["ranges"].clone())
            .collect::<Vec<_>>()
    };
    let safe = ranges(&bare_tch);
    assert_eq!(safe.len(), 4);
    assert_eq!(safe, ranges(&with_tch));
    assert!(
        safe.iter().any(|r| r.as_array().expect("ranges").len() > 1),
        "safe culls"
    );

    let refused = dir.path().join("refused.json");
    let base = ["tiles", "plan", s(&npy), "-o", s(&refused), "--no-regions"];
    fails_with(&base, "--grouping quadtree");
    for (flag, value, message) in [
        ("--halo", "4", "--halo: a plan without regions"),
        ("--far-block", "8", "--far-block: a plan without regions"),
        ("--far-ratio", "4", "--far-ratio: a plan without regions"),
        ("--sectors", "8", "computes no horizons"),
    ] {
        let mut args = base.to_vec();
        args.extend(["--grouping", "quadtree", flag, value]);
        fails_with(&args, message);
    }
    assert!(!refused.exists() && !dir.path().join("refused.tiles").exists());
}

/// `--max-expanse inf` (no limit on merges) survives every text form it is written in: a plan holding it builds and
/// merges (JSON has no number for infinity: it was written `null`, which the tile jobs could not read), and a build's
/// `--export-json` reads back.
#[test]
fn an_unlimited_expanse_is_kept_in_plans_and_exports() {
    let dir = tempfile::tempdir().expect("tempdir");
    let npy = small_grid(dir.path());
    let plan = dir.path().join("plan.json");
    ok(&[
        "tiles",
        "plan",
        s(&npy),
        "-o",
        s(&plan),
        "--tile",
        "16",
        "--max-error",
        "0.5",
        "--max-expanse",
        "inf",
        "-q",
    ]);
    let text = std::fs::read_to_string(&plan).expect("plan");
    assert!(text.contains(r#""max_expanse": "inf""#), "{text}");
    ok(&["tiles", "build", s(&plan), "--all", "-q"]);
    let merged = dir.path().join("m.tch");
    ok(&["tiles", "merge", s(&plan), "-o", s(&merged), "-q"]);
    let info = String::from_utf8_lossy(&ok(&["info", s(&merged)]).stdout).into_owned();
    assert!(info.contains("max expanse inf"), "{info}");

    let exported = dir.path().join("h.json");
    let tch = dir.path().join("h.tch");
    ok(&[
        "build",
        s(&npy),
        "-o",
        s(&tch),
        "--max-expanse",
        "inf",
        "--export-json",
        s(&exported),
        "-q",
    ]);
    let text = std::fs::read_to_string(&exported).expect("export");
    assert!(
        text.contains(r#""max_expanse":"inf""#),
        "{}",
        &text[..text.len().min(400)]
    );
    let h = tincull::pipeline::export::from_json(&text).expect("the export reads back");
    assert_eq!(h.build.max_expanse, f64::INFINITY);
}
