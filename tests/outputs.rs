//! Outputs of the `tincull` binary never destroy what is not theirs (issue 16): every output path is checked before
//! the work, FIFOs and directories are refused and left alone, symlinks are followed (the link stays), a failed
//! command leaves none of its outputs, `export --export-obj same.mtl` is refused, and `-o -` writes to standard output.
//! Everything is made in a temporary directory; no real device is touched.

mod common;

use std::fs;
use std::path::Path;
use std::process::Command;

use common::{mesh, ok, run};

fn p(path: &Path) -> &str {
    path.to_str().expect("UTF-8 temporary path")
}

/// Names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .expect("list")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn fails_with(args: &[&str], needles: &[&str]) -> String {
    let out = run(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "tincull {args:?} should fail");
    assert!(!stderr.contains("panicked"), "{stderr}");
    for n in needles {
        assert!(stderr.contains(n), "tincull {args:?}: {n:?} not in\n{stderr}");
    }
    stderr
}

const SMALL: &str = "jacksboro-2k.obj";

#[test]
fn a_missing_directory_is_refused_before_the_build() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("nodir/x.tch");
    let m = mesh(SMALL);
    let stderr = fails_with(
        &["build", p(&m), "-o", p(&out), "--quiet"],
        &["nodir", "does not exist"],
    );
    // Refused before the work: no build report was printed.
    assert!(!stderr.contains("triangles"), "{stderr}");
}

#[cfg(unix)]
#[test]
fn a_fifo_is_refused_and_left_alone() {
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().expect("tempdir");
    let fifo = dir.path().join("out.tch");
    assert!(Command::new("mkfifo").arg(&fifo).status().expect("mkfifo").success());
    let m = mesh(SMALL);
    fails_with(&["build", p(&m), "-o", p(&fifo), "--quiet"], &["out.tch", "FIFO"]);
    assert!(fs::symlink_metadata(&fifo).expect("lstat").file_type().is_fifo());
    assert_eq!(names(dir.path()), ["out.tch"]);
}

#[cfg(unix)]
#[test]
fn a_symlink_output_writes_its_target_and_stays_a_link() {
    let dir = tempfile::tempdir().expect("tempdir");
    let target = dir.path().join("real.tch");
    let link = dir.path().join("link.tch");
    fs::write(&target, "stale").expect("write");
    std::os::unix::fs::symlink("real.tch", &link).expect("symlink");
    let m = mesh(SMALL);
    ok(&["build", p(&m), "-o", p(&link), "--quiet"]);
    assert!(fs::symlink_metadata(&link).expect("lstat").file_type().is_symlink());
    let h = cull::Hierarchy::load(&target).expect("the link's target is the new hierarchy");
    assert!(!h.nodes.is_empty());
    assert_eq!(names(dir.path()), ["link.tch", "real.tch"]);
}

#[test]
fn a_failed_build_leaves_none_of_its_outputs() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = dir.path().join("h.tch");
    let obj_dir = dir.path().join("sub");
    fs::create_dir(&obj_dir).expect("mkdir");
    // The OBJ export's .mtl is a directory: refused before the build, so not even the .tch is written.
    fs::create_dir(obj_dir.join("g.mtl")).expect("mkdir");
    let m = mesh(SMALL);
    let obj = obj_dir.join("g.obj");
    fails_with(
        &["build", p(&m), "-o", p(&tch), "--export-obj", p(&obj), "--quiet"],
        &["g.mtl", "directory"],
    );
    assert_eq!(names(dir.path()), ["sub"]);
    assert_eq!(names(&obj_dir), ["g.mtl"]);
}

#[test]
fn export_refuses_an_obj_named_like_its_materials() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = dir.path().join("h.tch");
    let m = mesh(SMALL);
    ok(&["build", p(&m), "-o", p(&tch), "--quiet"]);
    let same = dir.path().join("same.mtl");
    fails_with(&["export", p(&tch), "--export-obj", p(&same)], &["same.mtl", ".mtl"]);
    assert_eq!(names(dir.path()), ["h.tch"]);
    // A glTF named like the OBJ's materials is refused for its name, before any clash with the `.mtl`.
    let beside = dir.path().join("x.obj");
    let gltf = dir.path().join("x.mtl");
    let e = fails_with(
        &["export", p(&tch), "--export-obj", p(&beside), "--export-gltf", p(&gltf)],
        &["x.mtl", "name it .glb or .gltf"],
    );
    assert!(!e.contains("the same file"), "{e}");
    assert_eq!(names(dir.path()), ["h.tch"]);
    // A good pair is written together.
    let obj = dir.path().join("g.obj");
    ok(&["export", p(&tch), "--export-obj", p(&obj), "--quiet"]);
    assert_eq!(names(dir.path()), ["g.mtl", "g.obj", "h.tch"]);
}

#[test]
fn dash_writes_the_hierarchy_to_standard_output() {
    let m = mesh(SMALL);
    let out = ok(&["build", p(&m), "-o", "-", "--quiet"]);
    let h = cull::Hierarchy::from_bytes(&out.stdout).expect("stdout holds exactly the .tch file");
    assert!(!h.nodes.is_empty());
    fails_with(&["build", p(&m), "-o", "-", "--json"], &["standard output"]);
    // A synthetic terrain's OBJ (text) too.
    let out = ok(&["synth", "-o", "-", "--vertices", "50", "--quiet"]);
    let text = String::from_utf8(out.stdout).expect("OBJ text");
    assert_eq!(text.lines().filter(|l| l.starts_with("v ")).count(), 50, "{text}");
}

#[test]
fn new_outputs_are_not_private_files() {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("t.obj");
        ok(&[
            "synth",
            "-o",
            p(&out),
            "--vertices",
            "200",
            "--rng-seed",
            "1",
            "--quiet",
        ]);
        let mode = fs::metadata(&out).expect("stat").permissions().mode() & 0o777;
        assert_ne!(
            mode, 0o600,
            "a new output gets 0666 less the umask, not a temporary file's 0600"
        );
    }
}

#[test]
fn an_output_never_overwrites_an_input() {
    let dir = tempfile::tempdir().expect("tempdir");
    let obj = dir.path().join("m.obj");
    fs::copy(mesh(SMALL), &obj).expect("copy");
    let original = fs::read(&obj).expect("read");
    let tch = dir.path().join("m.tch");
    let link = dir.path().join("link.obj");
    std::os::unix::fs::symlink(&obj, &link).expect("symlink");
    // The mesh as the build's own output, as an export beside it, and through a link: refused before the build.
    fails_with(
        &["build", p(&obj), "-o", p(&obj)],
        &["m.obj", "the same file as the input"],
    );
    fails_with(
        &["build", p(&obj), "-o", p(&tch), "--export-obj", p(&link)],
        &["link.obj", "the same file as the input", "m.obj"],
    );
    assert_eq!(fs::read(&obj).expect("read"), original);
    assert_eq!(names(dir.path()), ["link.obj", "m.obj"], "nothing written");
    ok(&["build", "-q", p(&obj), "-o", p(&tch)]);
    let built = fs::read(&tch).expect("read");
    // A hierarchy as its own export, evaluation or PVS; a DEM as its own TIN.
    fails_with(
        &["export", p(&tch), "--export-json", p(&tch)],
        &["the same file as the input"],
    );
    fails_with(
        &["eval", p(&tch), "--viewpoints", "1", "--csv", p(&tch)],
        &["the same file as the input"],
    );
    fails_with(
        &["pvs", p(&tch), "--cell", "0,0,10,10", "-o", p(&tch)],
        &["the same file as the input"],
    );
    let asc = common::small_asc(dir.path(), "g.asc");
    fails_with(
        &["tin", p(&asc), "--keep-grid", "-o", p(&asc)],
        &["g.asc", "the same file as the input"],
    );
    fails_with(&["sweep", p(&obj), "-o", p(&obj)], &["the same file as the input"]);
    assert_eq!(fs::read(&tch).expect("read"), built);
    assert_eq!(fs::read(&obj).expect("read"), original);
}

/// The files a DEM is read with are inputs too: a `.npy` grid's JSON sidecar (which `--export-json` or a demo in the
/// grid's folder would have replaced) and an `.asc` grid's `.prj`.
#[test]
fn an_output_never_overwrites_the_files_a_dem_is_read_with() {
    let dir = tempfile::tempdir().expect("tempdir");
    let npy = dir.path().join("g.npy");
    ok(&["synth", "-o", p(&npy), "--vertices", "400", "--rng-seed", "1", "-q"]);
    let sidecar = dir.path().join("g.json");
    let original = fs::read(&sidecar).expect("the grid's sidecar");
    let tch = dir.path().join("g.tch");
    let refused = ["g.json", "the same file as the input"];
    fails_with(
        &["build", p(&npy), "-o", p(&tch), "--export-json", p(&sidecar)],
        &refused,
    );
    fails_with(&["horizon", p(&npy), "--export-json", p(&sidecar)], &refused);
    fails_with(
        &["demo", p(&npy), "--out-dir", p(dir.path()), "--viewpoints", "1"],
        &refused,
    );
    assert_eq!(fs::read(&sidecar).expect("read"), original);
    assert_eq!(names(dir.path()), ["g.json", "g.npy"], "nothing written");

    let asc = common::small_asc(dir.path(), "h.asc");
    let prj = dir.path().join("h.prj");
    fs::write(&prj, "LOCAL_CS[\"metres\"]").expect("prj");
    fails_with(
        &["tin", p(&asc), "--keep-grid", "-o", p(&prj)],
        &["h.prj", "the same file as the input"],
    );
    assert_eq!(fs::read_to_string(&prj).expect("read"), "LOCAL_CS[\"metres\"]");
}

/// `demo` makes its output folder and those above it, checks its outputs there before it reads the terrain, and
/// removes the folders it made when it fails (it left the ones above the last behind).
#[test]
fn demo_checks_its_outputs_first_and_leaves_no_folder_when_it_fails() {
    let dir = tempfile::tempdir().expect("tempdir");
    let missing = dir.path().join("missing.obj");
    let nested = dir.path().join("a").join("b").join("out");
    fails_with(&["demo", p(&missing), "--out-dir", p(&nested)], &["missing.obj"]);
    assert_eq!(names(dir.path()), Vec::<String>::new(), "no folder left");
    // An output that cannot be written is refused before the terrain is read (the terrain here is missing too).
    let out = dir.path().join("out");
    fs::create_dir_all(out.join("missing.tch")).expect("a folder in the hierarchy's place");
    fails_with(
        &["demo", p(&missing), "--out-dir", p(&out)],
        &["missing.tch", "is a directory"],
    );
    // A file where a folder should be is named.
    fs::write(dir.path().join("afile"), b"").expect("write");
    fails_with(
        &[
            "demo",
            p(&missing),
            "--out-dir",
            p(&dir.path().join("afile").join("sub")),
        ],
        &["afile is not a directory"],
    );
}

#[test]
fn a_reader_that_goes_away_ends_the_command_quietly() {
    use std::io::Read;
    use std::process::Stdio;
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = dir.path().join("h.tch");
    ok(&["build", "-q", p(&mesh("jacksboro-10k.obj")), "-o", p(&tch)]);
    // Like `tincull export h.tch --export-json - | head -c 100`.
    let mut child = Command::new(env!("CARGO_BIN_EXE_tincull"))
        .args(["export", p(&tch), "--export-json", "-"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary runs");
    let mut stdout = child.stdout.take().expect("stdout");
    let mut head = [0u8; 100];
    stdout.read_exact(&mut head).expect("the JSON starts");
    drop(stdout);
    let out = child.wait_with_output().expect("wait");
    assert_eq!(out.status.code(), Some(141), "the status of a process ended by SIGPIPE");
    assert_eq!(String::from_utf8_lossy(&out.stderr), "", "nothing to say");
}

#[test]
fn text_to_a_reader_that_goes_away_ends_quietly_too() {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = dir.path().join("h.tch");
    ok(&["build", "-q", p(&mesh(SMALL)), "-o", p(&tch)]);
    let eyes = dir.path().join("eyes.txt");
    let lines: String = (0..20_000).map(|i| format!("{},{},5000\n", i % 900, i / 900)).collect();
    fs::write(&eyes, lines).expect("eyes");
    // Like `tincull cull h.tch --eyes eyes.txt | head -1`: one line of text per eye.
    let mut child = Command::new(env!("CARGO_BIN_EXE_tincull"))
        .args(["cull", p(&tch), "--eyes", p(&eyes)])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary runs");
    let mut first = String::new();
    BufReader::new(child.stdout.take().expect("stdout"))
        .read_line(&mut first)
        .expect("a first line");
    let out = child.wait_with_output().expect("wait");
    assert_eq!(out.status.code(), Some(141), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(String::from_utf8_lossy(&out.stderr), "", "nothing to say");
}

/// `--json` to a reader that is gone (`tincull pvs h.tch --grid 300 --json | head -c 200`): quiet, status 141, as the
/// text (the JSON once reported "error: Broken pipe").
#[test]
fn json_to_a_reader_that_is_gone_ends_quietly() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = dir.path().join("h.tch");
    ok(&["build", "-q", p(&mesh(SMALL)), "-o", p(&tch)]);
    let (reader, writer) = std::io::pipe().expect("a pipe");
    drop(reader);
    let out = Command::new(env!("CARGO_BIN_EXE_tincull"))
        .args(["info", p(&tch), "--json"])
        .stdout(writer)
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(141), "{stderr}");
    assert!(!stderr.contains("error"), "nothing to say: {stderr}");
}

#[test]
fn a_closed_stderr_is_not_a_failure() {
    use std::process::Stdio;
    // Like `tincull info m.obj 2>&1 >/dev/null | true`: the reader of stderr is gone before the first warning (the
    // mesh has slivers, so `info` warns). The warning cannot be read by anyone; the command still succeeds.
    let (reader, writer) = std::io::pipe().expect("a pipe");
    drop(reader);
    let out = Command::new(env!("CARGO_BIN_EXE_tincull"))
        .args(["info", p(&mesh(SMALL))])
        .stdout(Stdio::null())
        .stderr(Stdio::from(writer))
        .output()
        .expect("the binary runs");
    assert_eq!(
        out.status.code(),
        Some(0),
        "a warning nobody can read is no reason to fail"
    );
    // An error that nobody can read still gives the error status.
    let (reader, writer) = std::io::pipe().expect("a pipe");
    drop(reader);
    let out = Command::new(env!("CARGO_BIN_EXE_tincull"))
        .args(["info", "no-such-mesh.obj"])
        .stdout(Stdio::null())
        .stderr(Stdio::from(writer))
        .output()
        .expect("the binary runs");
    assert_eq!(out.status.code(), Some(1));
}

#[test]
fn an_output_named_like_another_format_is_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let obj = mesh(SMALL);
    // An OBJ named .npy, a hierarchy named .obj: each would later be read as the format its name says.
    fails_with(
        &[
            "tin",
            "../shared/dem/jacksboro_fault.npy",
            "--vertices",
            "100",
            "-o",
            p(&dir.path().join("t.npy")),
        ],
        &["t.npy", "writes an OBJ mesh", "name it .obj"],
    );
    fails_with(
        &["build", p(&obj), "-o", p(&dir.path().join("b.obj"))],
        &["b.obj", "writes a hierarchy", "name it .tch"],
    );
    assert!(names(dir.path()).is_empty(), "nothing written");
    // Names of no format tincull knows are the user's choice: the content tells a hierarchy.
    let other = dir.path().join("terrain.hierarchy");
    ok(&["build", "-q", p(&obj), "-o", p(&other)]);
    ok(&["info", p(&other)]);
}

#[test]
fn every_output_named_like_another_format_is_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let obj = dir.path().join("m.obj");
    fs::copy(mesh(SMALL), &obj).expect("copy the mesh");
    let tch = dir.path().join("h.tch");
    ok(&["build", "-q", p(&obj), "-o", p(&tch)]);
    // Another hierarchy and the mesh beside it: an export named like them would replace them with JSON or glTF.
    let other = dir.path().join("other.tch");
    fs::copy(&tch, &other).expect("copy the hierarchy");
    let before = |path: &Path| fs::read(path).expect("read");
    let (mesh_bytes, other_bytes) = (before(&obj), before(&other));
    let named = |n: &str| dir.path().join(n).to_str().expect("UTF-8").to_string();
    let cases: Vec<(Vec<String>, &str, &str)> = vec![
        (
            vec![
                "export".into(),
                p(&tch).into(),
                "--export-json".into(),
                p(&other).into(),
            ],
            "writes a hierarchy's JSON",
            "name it .json",
        ),
        (
            vec!["export".into(), p(&tch).into(), "--export-obj".into(), p(&other).into()],
            "writes an OBJ mesh",
            "name it .obj",
        ),
        (
            vec!["export".into(), p(&tch).into(), "--export-gltf".into(), p(&obj).into()],
            "writes glTF",
            "name it .glb or .gltf",
        ),
        (
            vec![
                "build".into(),
                p(&obj).into(),
                "-o".into(),
                named("b.tch"),
                "--export-json".into(),
                p(&other).into(),
            ],
            "writes a hierarchy's JSON",
            "name it .json",
        ),
        (
            vec![
                "build".into(),
                p(&obj).into(),
                "-o".into(),
                named("b.tch"),
                "--export-obj".into(),
                named("g.npy"),
            ],
            "writes an OBJ mesh",
            "name it .obj",
        ),
        (
            vec![
                "horizon".into(),
                p(&obj).into(),
                "--export-json".into(),
                p(&other).into(),
            ],
            "writes horizons as JSON",
            "name it .json",
        ),
        (
            vec!["eval".into(), p(&tch).into(), "--csv".into(), p(&other).into()],
            "writes the evaluation as CSV",
            "name it .csv",
        ),
        (
            vec!["eval".into(), p(&tch).into(), "--export-json".into(), named("e.csv")],
            "writes the evaluation as JSON",
            "name it .json",
        ),
        (
            vec![
                "pvs".into(),
                p(&tch).into(),
                "--cell".into(),
                "0,0,10,10".into(),
                "-o".into(),
                p(&other).into(),
            ],
            "writes a PVS file",
            "name it .pvs",
        ),
        (
            vec![
                "failmap".into(),
                p(&tch).into(),
                "--cell-size".into(),
                "100".into(),
                "-o".into(),
                p(&other).into(),
            ],
            "writes a PNG image",
            "name it .png",
        ),
        (
            vec![
                "failmap".into(),
                p(&tch).into(),
                "--cell-size".into(),
                "100".into(),
                "--csv".into(),
                named("map.json"),
            ],
            "writes the map as CSV",
            "name it .csv",
        ),
        (
            vec![
                "tiles".into(),
                "plan".into(),
                p(&obj).into(),
                "--tile".into(),
                "500".into(),
                "-o".into(),
                p(&other).into(),
            ],
            "writes a tiling plan (JSON)",
            "name it .json",
        ),
    ];
    for (args, what, fix) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let path = args[args.len() - 1];
        fails_with(&args, &[path, what, fix]);
    }
    assert_eq!(before(&obj), mesh_bytes, "the mesh is left alone");
    assert_eq!(before(&other), other_bytes, "the other hierarchy is left alone");
    assert_eq!(names(dir.path()), ["h.tch", "m.obj", "other.tch"], "nothing written");
    // Each output's own extension, in any case, is taken.
    ok(&[
        "export",
        p(&tch),
        "-q",
        "--export-json",
        &named("h.JSON"),
        "--export-obj",
        &named("g.obj"),
        "--export-gltf",
        &named("h.GLB"),
    ]);
    ok(&["export", p(&tch), "-q", "--export-gltf", &named("t.gltf")]);
    assert_eq!(
        names(dir.path()),
        [
            "g.mtl",
            "g.obj",
            "h.GLB",
            "h.JSON",
            "h.tch",
            "m.obj",
            "other.tch",
            "t.bin",
            "t.gltf"
        ]
    );
}

#[test]
fn an_output_that_ends_in_a_slash_is_named_a_directory() {
    let dir = tempfile::tempdir().expect("tempdir");
    let obj = dir.path().join("m.obj");
    fs::copy(mesh(SMALL), &obj).expect("copy the mesh");
    let tch = dir.path().join("h.tch");
    ok(&["build", "-q", p(&obj), "-o", p(&tch)]);
    fs::create_dir(dir.path().join("sub")).expect("mkdir");
    // A missing name, an existing file and an existing directory, each with a trailing slash.
    for name in ["newdir/", "h.json/", "sub/"] {
        let out = format!("{}/{name}", p(dir.path()));
        fails_with(
            &["export", p(&tch), "--export-json", &out],
            &[&out, "which names a directory, not a file; give a file name"],
        );
    }
    let out = format!("{}/", p(&obj));
    fails_with(
        &["build", p(&obj), "-o", &out],
        &[&out, "which names a directory, not a file"],
    );
    assert_eq!(names(dir.path()), ["h.tch", "m.obj", "sub"], "nothing written");
}
