//! End-to-end: Stewart's quadtree baseline through the CLI (`build --grouping quadtree`, `eval`, `cull --method
//! stewart`), the pairing of region methods with groupings, and Lloyd & Egbert's culler (`--method lloyd-egbert`) on
//! both groupings.

mod common;
use common::{fails_with, json, mesh, ok, s};

#[test]
fn quadtree_build_eval_and_cull() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (quad, crystal) = (dir.path().join("q.tch"), dir.path().join("c.tch"));
    let m = mesh("jacksboro-2k.obj");
    let out = ok(&[
        "build",
        s(&m),
        "-o",
        s(&quad),
        "--grouping",
        "quadtree",
        "--depth",
        "3",
        "--sectors",
        "8",
        "--subsectors",
        "2",
        "--json",
        "-q",
    ]);
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON report");
    assert_eq!(report["grouping"], "quadtree");
    let levels = report["quadtree_levels"].as_array().expect("levels");
    assert_eq!(levels.len(), 4);
    let total: u64 = levels.iter().map(|l| l["bytes"].as_u64().expect("bytes")).sum();
    assert!(report["visibility_bytes"].as_u64().expect("bytes") <= total);

    // A budget below the full tree drops the finest level.
    let small = dir.path().join("small.tch");
    let budget = (total - 1).to_string();
    let out = ok(&[
        "build",
        s(&m),
        "-o",
        s(&small),
        "--grouping",
        "quadtree",
        "--depth",
        "3",
        "--sectors",
        "8",
        "--subsectors",
        "2",
        "--max-bytes",
        &budget,
        "--json",
        "-q",
    ]);
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON report");
    assert_eq!(report["levels"], 3);
    assert_eq!(report["quadtree_levels"][3]["stored"], false);
    assert!(report["visibility_bytes"].as_u64().expect("bytes") < total);
    fails_with(
        &[
            "build",
            s(&m),
            "-o",
            s(&small),
            "--grouping",
            "quadtree",
            "--max-bytes",
            "5",
        ],
        "byte budget",
    );
    fails_with(
        &["build", s(&m), "-o", s(&small), "--depth", "3"],
        "--grouping quadtree",
    );
    // The crystal grouping's parameters are refused for a quadtree rather than ignored.
    for flag in [
        "--seeds",
        "--orphan-passes",
        "--min-group",
        "--max-expanse",
        "--rng-seed",
    ] {
        let value = if flag == "--max-expanse" { "0.5" } else { "5" };
        fails_with(
            &["build", s(&m), "-o", s(&small), "--grouping", "quadtree", flag, value],
            &format!("{flag} applies to the crystal grouping"),
        );
    }
    // `info` reports what a quadtree was built with: its depths, not the crystal parameters it has not used.
    let info = ok(&["info", s(&quad)]);
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(
        text.contains("built with    quadtree depth 3, depth 3 stored"),
        "{text}"
    );
    assert!(!text.contains("seeds"), "{text}");
    let info = ok(&["info", s(&small)]);
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(
        text.contains("built with    quadtree depth 3, depth 2 stored"),
        "{text}"
    );

    let csv = dir.path().join("e.csv");
    ok(&[
        "eval",
        s(&quad),
        "--viewpoints",
        "2",
        "--classes",
        "ground,low",
        "--no-per-triangle",
        "--csv",
        s(&csv),
        "-q",
    ]);
    let csv = std::fs::read_to_string(&csv).expect("csv");
    assert!(csv.contains("\nstewart,ground,"), "{csv}");
    assert!(csv.contains("\nsafe,ground,"), "{csv}");
    assert!(!csv.contains("\nthesis,"), "{csv}");
    // Lloyd & Egbert over the quadtree: 2 viewpoints, none with a false cull.
    assert!(csv.contains("\nlloyd-egbert,ground,2,0,"), "{csv}");
    assert!(csv.contains("\nlloyd-egbert,low,2,0,"), "{csv}");

    let eye = "0,0,100000";
    let out = ok(&["cull", s(&quad), "--method", "stewart", "--eye", eye, "--json"]);
    let c: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(c["method"], "stewart");
    ok(&["cull", s(&quad), "--method", "safe", "--eye", eye]);
    let out = ok(&[
        "cull",
        s(&quad),
        "--method",
        "lloyd-egbert",
        "--columns",
        "1024",
        "--eye",
        eye,
        "--json",
    ]);
    let c: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(c["method"], "lloyd-egbert");
    fails_with(
        &["cull", s(&quad), "--method", "thesis", "--eye", eye],
        "method `stewart`",
    );
    // So do `failmap` and `render` (checked before any work or GPU).
    let map = dir.path().join("map.csv");
    fails_with(
        &[
            "failmap",
            s(&quad),
            "--method",
            "thesis",
            "--cell-size",
            "100",
            "--csv",
            s(&map),
        ],
        "method `stewart`",
    );
    fails_with(
        &[
            "render",
            s(&quad),
            "--method",
            "thesis",
            "-o",
            s(&dir.path().join("r.png")),
        ],
        "method `stewart`",
    );
    assert!(!map.exists());

    ok(&[
        "build",
        s(&m),
        "-o",
        s(&crystal),
        "--sectors",
        "8",
        "--subsectors",
        "2",
        "--seeds",
        "20",
        "-q",
    ]);
    fails_with(
        &["cull", s(&crystal), "--method", "stewart", "--eye", eye],
        "--grouping quadtree",
    );
    // Lloyd & Egbert takes a crystal hierarchy too (a grid of about as many cells as leaf groups).
    ok(&["cull", s(&crystal), "--method", "lloyd-egbert", "--eye", eye]);
    // A parameter the method does not use is an error naming it, not ignored.
    fails_with(
        &[
            "cull",
            s(&crystal),
            "--method",
            "lloyd-egbert",
            "--patch",
            "4",
            "--eye",
            eye,
        ],
        "--patch 4 is a parameter of the `safe` culler; method `lloyd-egbert` does not use it",
    );
    fails_with(
        &[
            "cull",
            s(&crystal),
            "--method",
            "thesis",
            "--columns",
            "512",
            "--eye",
            eye,
        ],
        "--columns 512 is a parameter of the `safe` and `lloyd-egbert` cullers",
    );
    fails_with(
        &[
            "cull",
            s(&crystal),
            "--method",
            "thesis",
            "--work-budget",
            "100",
            "--eye",
            eye,
        ],
        "method `thesis` does not use it",
    );
    // Even at its default value: given, it would be ignored.
    fails_with(
        &[
            "cull",
            s(&crystal),
            "--method",
            "thesis",
            "--work-budget",
            "200000",
            "--eye",
            eye,
        ],
        "--work-budget 200000 is a parameter of the `safe` culler; method `thesis` does not use it",
    );
    fails_with(
        &[
            "cull",
            s(&crystal),
            "--method",
            "stewart",
            "--columns",
            "256",
            "--eye",
            eye,
        ],
        "--columns 256 is a parameter of the `safe` and `lloyd-egbert` cullers",
    );
    ok(&[
        "cull",
        s(&crystal),
        "--method",
        "safe",
        "--patch",
        "4",
        "--coarse-columns",
        "2",
        "--eye",
        eye,
    ]);
    // Values out of their ranges are errors naming the flag and the range.
    for (flag, value, message) in [
        (
            "--columns",
            "96",
            "--columns must be a power of two from 2 to 65536, got 96",
        ),
        (
            "--columns",
            "131072",
            "--columns must be a power of two from 2 to 65536, got 131072",
        ),
        ("--patch", "0", "--patch must be from 1 to 64, got 0"),
        ("--patch", "65", "--patch must be from 1 to 64, got 65"),
    ] {
        fails_with(&["cull", s(&crystal), flag, value, "--eye", eye], message);
    }
    // `failmap` takes the same parameters, and refuses them where its method does not use them.
    let map = ["failmap", s(&crystal), "--cell-size", "4000", "--json"];
    fails_with(
        &[&map[..], &["--method", "thesis", "--columns", "64"]].concat(),
        "--columns 64 is a parameter of the `safe` and `lloyd-egbert` cullers",
    );
    let captured = |v: serde_json::Value| v["occlusion_captured_mean"].as_f64().expect("captured");
    let spent = captured(json(&[&map[..], &["--work-budget", "1"]].concat()));
    assert!(spent < captured(json(&map)), "{spent}");
}

/// `build --grouping quadtree --no-regions`: no horizons, no regions, the quadtree build's cells; the safe culler
/// draws from it what it draws from the build with regions, `stewart` culls nothing in it; what it cannot honour is
/// refused and no file is written.
#[test]
fn a_quadtree_without_regions_culls_as_the_one_with_them() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (with, without) = (dir.path().join("with.tch"), dir.path().join("without.tch"));
    let m = mesh("jacksboro-2k.obj");
    ok(&["build", s(&m), "-o", s(&with), "--grouping", "quadtree", "-q"]);
    let out = ok(&[
        "build",
        s(&m),
        "-o",
        s(&without),
        "--grouping",
        "quadtree",
        "--no-regions",
        "--json",
        "-q",
    ]);
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON report");
    assert_eq!(report["without_regions"], true);
    assert_eq!(
        (report["horizon_seconds"].as_f64(), report["regions_seconds"].as_f64()),
        (Some(0.0), Some(0.0))
    );
    assert!(
        report["quadtree_levels"]
            .as_array()
            .expect("levels")
            .iter()
            .all(|l| l["regions"] == 0)
    );
    let eyes = dir.path().join("eyes.txt");
    std::fs::write(&eyes, "15000,15000,2\n4000,26000,30\n29000,3000,300\n1000,1000,2\n").expect("eyes");
    let ranges = |file: &std::path::Path, method: &str| {
        let out = ok(&[
            "cull",
            s(file),
            "--eyes",
            s(&eyes),
            "--above-ground",
            "--method",
            method,
            "--json",
        ]);
        String::from_utf8(out.stdout)
            .expect("UTF-8")
            .lines()
            .map(|l| serde_json::from_str::<serde_json::Value>(l).expect("JSON line")["ranges"].clone())
            .collect::<Vec<_>>()
    };
    let safe = ranges(&without, "safe");
    assert_eq!(safe.len(), 4);
    assert_eq!(safe, ranges(&with, "safe"));
    let everything = serde_json::json!([[0, count_triangles(&m)]]);
    assert!(safe.iter().any(|r| *r != everything), "safe culls");
    assert!(
        ranges(&without, "stewart").iter().all(|r| *r == everything),
        "stewart culls nothing"
    );
    let out = ok(&[
        "cull",
        s(&without),
        "--eye",
        "15000,15000,2",
        "--above-ground",
        "--method",
        "stewart",
    ]);
    let warning = String::from_utf8_lossy(&out.stderr);
    assert!(
        warning.contains("holds no regions") && warning.contains("`stewart` culls nothing"),
        "{warning}"
    );
    // `eval` scores `stewart` too, and says why it culls nothing; over the file with regions it says nothing.
    let eval = |file: &std::path::Path| {
        let out = ok(&[
            "eval",
            s(file),
            "--viewpoints",
            "1",
            "--classes",
            "ground",
            "--no-per-triangle",
            "--no-safe-regions",
            "--json",
        ]);
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let warning = eval(&without);
    assert!(
        warning.contains("holds no regions") && warning.contains("`stewart` culls nothing"),
        "{warning}"
    );
    assert!(!eval(&with).contains("holds no regions"));
    let info = String::from_utf8(ok(&["info", s(&without)]).stdout).expect("UTF-8");
    assert!(info.contains("regions       none (built with --no-regions"), "{info}");
    let refused = dir.path().join("refused.tch");
    fails_with(
        &["build", s(&m), "-o", s(&refused), "--no-regions"],
        "--grouping quadtree",
    );
    for flag in [["--sectors", "8"], ["--subsectors", "2"], ["--undersampling", "100"]] {
        let mut args = vec![
            "build",
            s(&m),
            "-o",
            s(&refused),
            "--grouping",
            "quadtree",
            "--no-regions",
        ];
        args.extend(flag);
        fails_with(&args, "computes no horizons");
    }
    assert!(!refused.exists());
}

/// The triangles of an OBJ (its `f` lines).
fn count_triangles(obj: &std::path::Path) -> u64 {
    std::fs::read_to_string(obj)
        .expect("OBJ")
        .lines()
        .filter(|l| l.starts_with("f "))
        .count() as u64
}
