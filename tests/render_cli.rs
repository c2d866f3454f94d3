//! End-to-end tests of `tincull render` (headless PNG renders) on a small synthetic terrain and its hierarchy.
//!
//! Without a GPU adapter the GPU parts print a SKIP notice and pass, unless `TINCULL_REQUIRE_GPU` is set.

use std::path::Path;
use std::process::{Command, Output};

fn tincull(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tincull"))
        .args(args)
        .output()
        .expect("run tincull")
}

fn ok(out: &Output) -> String {
    assert!(
        out.status.success(),
        "tincull failed:\nstdout: {}\nstderr: {}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn gpu_missing(out: &Output) -> bool {
    let err = String::from_utf8_lossy(&out.stderr);
    if out.status.success() || !err.contains("no GPU adapter") {
        return false;
    }
    if viewer::gpu_required() {
        panic!("TINCULL_REQUIRE_GPU is set but no GPU is usable: {err}");
    }
    eprintln!("SKIP: no GPU adapter, render test not run; set TINCULL_REQUIRE_GPU=1 to make this an error");
    true
}

fn p(path: &Path) -> &str {
    path.to_str().expect("utf-8 temp path")
}

#[test]
fn render_map_orbit_and_eye_compare() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("t.obj");
    let tch = dir.path().join("t.tch");
    ok(&tincull(&["synth", "-o", p(&obj), "--vertices", "1200", "-q"]));
    ok(&tincull(&["build", p(&obj), "-o", p(&tch), "-q"]));

    // The map of the hierarchy, coloured by group.
    let map = dir.path().join("map.png");
    let out = tincull(&["render", p(&tch), "--out", p(&map), "--size", "200x150", "--json"]);
    if gpu_missing(&out) {
        return;
    }
    let j: serde_json::Value = serde_json::from_str(ok(&out).trim()).unwrap();
    assert_eq!(j["draws"], 1);
    // On a headless machine (no Wayland session) a render prints nothing that reads like an error: Mesa's
    // device-select layer would make libwayland complain about XDG_RUNTIME_DIR (see `main.rs`).
    let headless = Command::new(env!("CARGO_BIN_EXE_tincull"))
        .args(["render", p(&tch), "--out", p(&map), "--size", "200x150", "-q"])
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("NODEVICE_SELECT")
        .output()
        .expect("run tincull");
    ok(&headless);
    let err = String::from_utf8_lossy(&headless.stderr);
    assert!(!err.contains("error"), "a successful headless render printed:\n{err}");
    let img = viewer::read_png(&map).unwrap();
    assert_eq!((img.width, img.height), (200, 150));
    let grey = img.count(viewer::palette::to_rgba8([0.0; 3]));
    assert!(grey < 200 * 150, "not black");
    // With --eye the map shows the viewpoint's pin (its head was once clipped by the map camera, above the terrain).
    let pinned = dir.path().join("pinned.png");
    let h = cull::Hierarchy::load(&tch).unwrap();
    let c = h.mesh.positions[h.mesh.positions.len() / 2];
    let eye = format!("{},{},{}", c[0], c[1], c[2] + 20.0);
    ok(&tincull(&[
        "render",
        p(&tch),
        "--out",
        p(&pinned),
        "--size",
        "200x150",
        "--eye",
        &eye,
    ]));
    let with_pin = viewer::read_png(&pinned).unwrap();
    let differing = with_pin
        .pixels
        .chunks_exact(4)
        .zip(img.pixels.chunks_exact(4))
        .filter(|(a, b)| a != b)
        .count();
    assert!(differing > 4, "the pin shows on the map ({differing} pixels differ)");

    // A plain mesh renders by height.
    let height = dir.path().join("height.png");
    ok(&tincull(&["render", p(&obj), "--out", p(&height), "--size", "64x64"]));
    assert!(viewer::read_png(&height).is_ok());

    // Orbit with a viewpoint: the culler runs and its counts are reported.
    let h = cull::Hierarchy::load(&tch).unwrap();
    let (lo, hi) = h
        .mesh
        .positions
        .iter()
        .fold(([f64::MAX; 3], [f64::MIN; 3]), |(mut lo, mut hi), q| {
            for k in 0..3 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
            (lo, hi)
        });
    // Above the highest vertex: an eye below the ground is refused.
    let eye = format!("{},{},{}", (lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, hi[2] + 5.0);
    let orbit = dir.path().join("orbit.png");
    let out = ok(&tincull(&[
        "render",
        p(&tch),
        "--out",
        p(&orbit),
        "--view",
        "orbit",
        "--eye",
        &eye,
        "--size",
        "160x120",
        "--json",
    ]));
    let j: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    let drawn = j["cull"]["triangles_drawn"].as_u64().unwrap();
    let culled = j["cull"]["triangles_culled"].as_u64().unwrap();
    assert_eq!(drawn + culled, h.num_triangles() as u64);

    // Eye view with comparison: JSON fields, the difference image, and the triangle counts.
    let eyeimg = dir.path().join("eye.png");
    let out = ok(&tincull(&[
        "render",
        p(&tch),
        "--out",
        p(&eyeimg),
        "--view",
        "eye",
        "--eye",
        &eye,
        "--yaw",
        "30",
        "--pitch",
        "-5",
        "--size",
        "128x96",
        "--compare",
        "--json",
    ]));
    let j: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    let differing = j["differing_pixels"].as_u64().unwrap();
    assert_eq!(j["triangles_unculled"].as_u64().unwrap(), h.num_triangles() as u64);
    assert_eq!(
        j["triangles_submitted"].as_u64().unwrap(),
        j["cull"]["triangles_drawn"].as_u64().unwrap()
    );
    let diff = viewer::read_png(&dir.path().join("eye-diff.png")).unwrap();
    assert_eq!(diff.count([255, 0, 0, 255]), differing);
    assert!(j["frame_ms_culled"].as_f64().unwrap() > 0.0);

    // A pitched picture reaches further round than its field at the corners: a --cull-fov narrower than what it
    // reaches is said (the culler hides terrain at the picture's edges), one as wide is not.
    let reach = (viewer::camera::culling_hfov_deg(90.0, -30.0, 128.0 / 96.0) * 10.0).ceil() / 10.0;
    assert!(reach > 120.0, "{reach}");
    for (field, warned) in [
        ("90", true),
        ("120", true),
        (&*format!("{reach}"), false),
        ("360", false),
    ] {
        let out = tincull(&[
            "render",
            p(&tch),
            "--out",
            p(&eyeimg),
            "--view",
            "eye",
            "--eye",
            &eye,
            "--pitch",
            "-30",
            "--size",
            "128x96",
            "--cull-fov",
            field,
            "-q",
        ]);
        ok(&out);
        let err = String::from_utf8_lossy(&out.stderr);
        let said = format!("--cull-fov {field}: this picture (--fov 90, --pitch -30, 128x96) reaches {reach} degrees");
        assert_eq!(err.contains(&said), warned, "--cull-fov {field}:\n{err}");
    }
    // A perspective picture is drawn at most 150 degrees wide: a wider --fov draws the same picture, and says so.
    let eye_at = |fov: &str, img: &Path| {
        let out = tincull(&[
            "render",
            p(&tch),
            "--out",
            p(img),
            "--view",
            "eye",
            "--eye",
            &eye,
            "--size",
            "64x48",
            "--fov",
            fov,
            "-q",
        ]);
        ok(&out);
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let wide = dir.path().join("wide.png");
    let widest = dir.path().join("widest.png");
    assert!(!eye_at("150", &widest).contains("--fov"));
    let err = eye_at("170", &wide);
    assert!(
        err.contains("--fov 170: an eye picture is drawn at most 150 degrees wide; this one is drawn at 150"),
        "{err}"
    );
    assert_eq!(std::fs::read(&wide).unwrap(), std::fs::read(&widest).unwrap());
}

#[test]
fn render_rejects_bad_options_with_clear_messages() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("t.obj");
    ok(&tincull(&["synth", "-o", p(&obj), "--vertices", "300", "-q"]));
    let png = dir.path().join("x.png");
    let cases: [(&[&str], &str); 8] = [
        (&["--view", "eye"], "--eye"),
        (&["--pvs-cell", "0,0,10,10"], "hierarchy"),
        (&["--size", "0x10"], "size"),
        (&["--view", "map", "--compare"], "--compare"),
        (&["--colour", "groups"], "hierarchy"),
        // Options of another option, given without it: refused, not ignored.
        (&["--resolution", "32"], "--pvs-cell"),
        (&["--runs", "3"], "--compare"),
        (&["--fov", "1e300"], "got 1e300"),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["render", p(&obj), "--out", p(&png)];
        args.extend_from_slice(extra);
        let out = tincull(&args);
        if gpu_missing(&out) {
            continue;
        }
        assert!(!out.status.success(), "{extra:?} should fail");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{extra:?}: {err}");
    }
    assert!(!png.exists(), "no image is written on error");
    // The output is checked before the terrain is read (and its PVS computed): a missing input is not even opened.
    let out = tincull(&[
        "render",
        p(&dir.path().join("missing.tch")),
        "--out",
        p(&dir.path().join("x.jpg")),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("x.jpg: render writes a PNG image"),
        "{err}"
    );
}

/// Culling parameters that a render does not use are refused, as `cull` refuses them, before anything is drawn; so are
/// view flags that change nothing in the image (the map view's yaw and pitch, the eye view's field of view elsewhere).
#[test]
fn render_refuses_culling_flags_it_does_not_use() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("t.obj");
    ok(&tincull(&["synth", "-o", p(&obj), "--vertices", "300", "-q"]));
    let tch = dir.path().join("t.tch");
    ok(&tincull(&["build", p(&obj), "-o", p(&tch), "-q"]));
    let png = dir.path().join("x.png");
    let eye = ["--view", "eye", "--eye", "100,100,500"];
    let cases: [(&Path, Vec<&str>, &str); 12] = [
        (
            &tch,
            [&eye[..], &["--method", "thesis", "--columns", "8"]].concat(),
            "--columns 8 is a parameter",
        ),
        (
            &tch,
            [&eye[..], &["--method", "lloyd-egbert", "--patch", "8"]].concat(),
            "--patch 8 is a parameter",
        ),
        (
            &obj,
            [&eye[..], &["--method", "thesis"]].concat(),
            "--method thesis: this render culls nothing",
        ),
        // The default method given by name, as any other (it was taken for the default and let through).
        (
            &tch,
            vec!["--view", "map", "--method", "safe"],
            "--method safe: this render culls nothing",
        ),
        (
            &tch,
            vec!["--view", "map", "--patch", "8"],
            "--patch 8: this render culls nothing",
        ),
        (
            &tch,
            vec!["--view", "orbit", "--columns", "64"],
            "--columns 64: this render culls nothing",
        ),
        // View flags that change nothing in the image, likewise.
        (
            &tch,
            vec!["--view", "map", "--pitch", "-30"],
            "--pitch: the map view looks straight down",
        ),
        (&tch, vec!["--yaw", "30"], "--yaw: the map view looks straight down"),
        (
            &tch,
            vec!["--eye", "100,100,500", "--colour", "visibility", "--yaw", "30"],
            "(this render: --view map)",
        ),
        (
            &obj,
            vec!["--view", "orbit", "--fov", "60"],
            "--fov is the eye view's field of view",
        ),
        (
            &tch,
            vec!["--level", "0"],
            "--level is the level that --colour level paints",
        ),
        (
            &tch,
            vec!["--view", "orbit", "--cull-fov", "90"],
            "--cull-fov: this render culls nothing",
        ),
    ];
    // An eye below the ground of a plain mesh, as of a hierarchy.
    let j2k = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/meshes/jacksboro-2k.obj"));
    let cases = cases.into_iter().chain([(
        j2k,
        vec!["--view", "eye", "--eye", "2458,17626,100"],
        "is 317.963 m below the ground (at z 417.963 there)",
    )]);
    for (input, extra, needle) in cases {
        let mut args = vec!["render", p(input), "--out", p(&png)];
        args.extend_from_slice(&extra);
        let out = tincull(&args);
        assert!(!out.status.success(), "{extra:?} should fail");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{extra:?}: {err}");
    }
    assert!(!png.exists(), "no image is written on error");
}

/// `--pvs-cell` paints a viewcell's PVS: what it holds in the drawn colour, what it excludes in the culled colour,
/// exactly as many of each as `tincull pvs` reports.
#[test]
fn render_paints_a_viewcell_pvs() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("t.obj");
    let tch = dir.path().join("t.tch");
    ok(&tincull(&["synth", "-o", p(&obj), "--vertices", "1200", "-q"]));
    ok(&tincull(&["build", p(&obj), "-o", p(&tch), "-q"]));
    let h = cull::Hierarchy::load(&tch).unwrap();
    let (lo, hi) = h
        .mesh
        .positions
        .iter()
        .fold(([f64::MAX; 2], [f64::MIN; 2]), |(mut lo, mut hi), q| {
            for k in 0..2 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
            (lo, hi)
        });
    let (w, d) = (hi[0] - lo[0], hi[1] - lo[1]);
    let cell = format!(
        "{},{},{},{}",
        lo[0] + 0.2 * w,
        lo[1] + 0.2 * d,
        lo[0] + 0.25 * w,
        lo[1] + 0.25 * d
    );
    let map = dir.path().join("pvs.png");
    let out = tincull(&[
        "render",
        p(&tch),
        "--out",
        p(&map),
        "--size",
        "200x200",
        "--pvs-cell",
        &cell,
    ]);
    if gpu_missing(&out) {
        return;
    }
    let text = ok(&out);
    assert!(text.contains("PVS of cell"), "{text}");
    let img = viewer::read_png(&map).unwrap();
    let drawn = img.count(viewer::palette::to_rgba8(viewer::palette::DRAWN_COLOUR));
    let culled = img.count(viewer::palette::to_rgba8(viewer::palette::CULLED_COLOUR));
    let j: serde_json::Value =
        serde_json::from_str(ok(&tincull(&["pvs", p(&tch), "--cell", &cell, "--json"])).trim()).unwrap();
    let in_pvs = j["cells"][0]["pvs_triangles"].as_u64().unwrap();
    assert!(in_pvs > 0);
    assert!(drawn > 0, "the PVS is painted");
    assert_eq!(
        culled > 0,
        in_pvs < h.num_triangles() as u64,
        "what the PVS excludes is painted as culled"
    );
    // The eye view of a cell's PVS draws its triangles and no other; nothing is culled from a point (it once drew
    // the point culler's set under the PVS's name).
    let eye_png = dir.path().join("eye.png");
    let v: serde_json::Value = serde_json::from_str(
        ok(&tincull(&[
            "render",
            p(&tch),
            "--out",
            p(&eye_png),
            "--size",
            "100x100",
            "--pvs-cell",
            &cell,
            "--view",
            "eye",
            "--json",
        ]))
        .trim(),
    )
    .unwrap();
    assert_eq!(v["triangles_submitted"].as_u64(), Some(in_pvs), "{v}");
    assert!(v["cull"].is_null(), "{v}");
    // Flags that would change nothing in a PVS's image, or are out of range, are refused before the PVS is computed
    // (which the report would name).
    for (extra, needle) in [
        (
            ["--colour", "groups"],
            "--pvs-cell paints what the cell's PVS excludes with --colour visibility",
        ),
        (
            ["--method", "thesis"],
            "with --pvs-cell the render shows the cell's PVS",
        ),
        (["--pitch", "10"], "--pitch: the map view looks straight down"),
        (
            ["--work-budget", "5"],
            "with --pvs-cell the render shows the cell's PVS",
        ),
        (["--resolution", "999"], "--resolution"),
    ] {
        let mut args = vec!["render", p(&tch), "--out", p(&map), "--pvs-cell", &cell];
        args.extend_from_slice(&extra);
        let out = tincull(&args);
        assert!(!out.status.success(), "{extra:?} should fail");
        assert!(String::from_utf8_lossy(&out.stderr).contains(needle), "{extra:?}");
        assert!(
            !String::from_utf8_lossy(&out.stdout).contains("PVS of cell"),
            "{extra:?}: the PVS was computed"
        );
    }
}

#[test]
fn demo_writes_the_hierarchy_evaluation_and_renders() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = concat!(env!("CARGO_MANIFEST_DIR"), "/meshes/jacksboro-2k.obj");
    let out = tincull(&["demo", mesh, "--out-dir", p(dir.path()), "--viewpoints", "1"]);
    let stdout = ok(&out);
    for suffix in [".tch", ".json", "-groups.obj", "-groups.mtl", "-eval.csv", "-eval.json"] {
        let f = dir.path().join(format!("jacksboro-2k{suffix}"));
        assert!(f.is_file(), "{} missing", f.display());
    }
    let (map, culling) = (
        dir.path().join("jacksboro-2k-map.png"),
        dir.path().join("jacksboro-2k-culling.png"),
    );
    if !map.exists() {
        assert!(stdout.contains("no renders"), "the demo says why it wrote no images");
        assert!(
            !viewer::gpu_required(),
            "TINCULL_REQUIRE_GPU is set but the demo wrote no renders: {stdout}"
        );
        eprintln!("SKIP: no GPU adapter, demo renders not checked");
        return;
    }
    let map = viewer::read_png(&map).unwrap();
    let culling = viewer::read_png(&culling).unwrap();
    assert_eq!((map.width, map.height), (1024, 768));
    assert_eq!((culling.width, culling.height), (1024, 768));
    // Groups in distinct colours: many different pixel colours across the map.
    let colours: std::collections::HashSet<[u8; 4]> = (0..768)
        .step_by(8)
        .flat_map(|y| (0..1024).step_by(8).map(move |x| (x, y)))
        .filter_map(|(x, y)| map.pixel(x, y))
        .collect();
    assert!(colours.len() > 50, "only {} colours on the groups map", colours.len());
    assert!(
        map.difference(&culling).is_some_and(|(_, n)| n > 0),
        "the culling view is another image"
    );
}
